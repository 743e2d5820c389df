// app::Application<Scalar>: everything below the servo interrupt, the same on
// the amplifier board, the HIL board and the host controller node.
//
//   boot (constructor)  load the configuration from the two flash banks
//                       (persistence::ConfigStore), apply it to the kernel
//                       (modbus::ControllerDevice::boot); persist_status()
//                       and Modbus persist.flags/reason show what happened
//                       (bank corrupt, defaults, refused, migrated).
//   on_uart_byte()      one received RS-485 byte + its microsecond timestamp
//                       into the Modbus RTU server (t3.5 framing).
//   service(now_us, servo_ticks)   the communications loop body:
//     1. Modbus: a complete request (t3.5 of silence) is processed and the
//        reply handed to the ByteSink; config.save writes flash (the
//        long_operation hook brackets it: the board lengthens the IWDG);
//     2. CAN RX (when Config::drain_can_rx): frames checked by a LinkReceiver
//        and counted (the HIL board's CanSensorSource owns RX instead);
//     2b. host commands (host_command frames from that receiver, or from
//        Hooks::host_commands -- the HIL board's CanSensorSource queue):
//        motion_commands::to_motion_command -> kernel command() inside the critical
//        section, answered with host_command_ack (result, sequencer state,
//        servo tick) -- the same mapping as the bench's controller node;
//     3. CAN telemetry by servo ticks: controller_status every
//        status_period_ticks (catalog: 10 = 250 Hz) from kernel status(),
//        heartbeat_controller every heartbeat_period_ticks (250 = 10 Hz);
//        a loop that fell behind sends one frame, not a burst; sync every
//        sync_period_ticks when this node is the time master (HIL board);
//     4. recorder drain (oldest first; a reader more than N behind skips
//        ahead and counts the loss);
//     5. watchdog: comms_ran() on the FeedGate, then FeedGate::service(dog):
//        the IWDG is fed only when the servo loop ALSO checked in since the
//        last feed (ServoHooks::servo_ran -> FeedGate::servo_ran).
//
// Concurrency: the kernel and (on the HIL board) the CAN port are shared with
// the servo interrupt. Every kernel access (status snapshot, Modbus
// read_status/command/apply_config) and every CAN send runs between
// hooks.critical_enter/critical_exit (the board masks the tick interrupt;
// the host passes a mutex pair or nothing). Flash writes run outside it.
//
// Heap-free, exception-free; host + Cortex-M7. Header-only template
// (Scalar = float on the board; numeric::Q7_24 also works).
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/motion_commands/to_motion_command.hpp"
#include "maglev/app/host_command_queue.hpp"
#include "maglev/app/interrupt_meter.hpp"
#include "maglev/app/recorder.hpp"
#include "maglev/app/servo_loop.hpp"
#include "maglev/app/telemetry.hpp"
#include "maglev/can_link/catalog.hpp"
#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/can_port/can_port.hpp"
#include "maglev/controller/controller.hpp"
#include "maglev/drivers/iwdg.hpp"
#include "maglev/modbus/controller_binding.hpp"
#include "maglev/modbus/register_server.hpp"
#include "maglev/modbus/rtu_server.hpp"
#include "maglev/persistence/config_store.hpp"

namespace maglev::app {

// Where Modbus replies go (USART2/RS-485 on the board, a pty/socket on the host).
class ByteSink {
 public:
  virtual bool transmit(const std::uint8_t* data, std::size_t len) = 0;

 protected:
  ByteSink() = default;
  ByteSink(const ByteSink&) = default;
  ByteSink& operator=(const ByteSink&) = default;
  ~ByteSink() = default;
};

// The hardware watchdog (IWDG on the board).
class WatchdogFeeder {
 public:
  virtual void feed() = 0;

 protected:
  WatchdogFeeder() = default;
  WatchdogFeeder(const WatchdogFeeder&) = default;
  WatchdogFeeder& operator=(const WatchdogFeeder&) = default;
  ~WatchdogFeeder() = default;
};

struct ApplicationConfig {
  std::uint8_t modbus_unit = 1;
  std::uint32_t modbus_baud = 115'200;
  bool drain_can_rx = true;  // false when a CanSensorSource reads the same port (HIL)
  std::uint16_t status_period_ticks = can::kControllerStatusPeriodTicks;
  std::uint16_t heartbeat_period_ticks = can::kHeartbeatPeriodTicks;
  // sync (time master's tick broadcast, catalog 25 ticks = 100 Hz): only the
  // node that is the time master sends it (the HIL board); 0 = off.
  std::uint16_t sync_period_ticks = 0;
  std::uint8_t max_can_rx_per_service = 16;
};

struct ApplicationHooks {
  void (*critical_enter)() = nullptr;       // mask the servo tick
  void (*critical_exit)() = nullptr;
  void (*long_operation)(bool begin) = nullptr;  // around flash saves
  // Rejections reported in the heartbeat; null: the Application's own receiver.
  const can::LinkReceiver* rx_stats = nullptr;
  // Host commands received elsewhere (HIL: CanSensorSource::host_commands()); may be null.
  HostCommandQueue* host_commands = nullptr;
};

struct ApplicationStats {
  std::uint32_t services = 0;
  std::uint32_t modbus_replies = 0;
  std::uint32_t uart_tx_errors = 0;
  std::uint32_t status_frames = 0;
  std::uint32_t heartbeat_frames = 0;
  std::uint32_t sync_frames = 0;
  std::uint32_t can_tx_errors = 0;
  std::uint32_t can_rx_frames = 0;
  std::uint32_t host_commands = 0;  // executed (or refused) and acknowledged
  std::uint32_t recorder_drained = 0;
  std::uint32_t recorder_lost = 0;
  std::uint32_t saves = 0;
};

namespace application_detail {

// The Modbus Device the RegisterServer sees: the kernel binding with every
// kernel access inside the critical section and flash writes bracketed by
// long_operation (and outside the critical section).
class GuardedDevice final : public modbus::Device {
 public:
  GuardedDevice(modbus::Device& inner, const ApplicationHooks& hooks)
      : inner_(inner), hooks_(hooks),
        masks_own_commit_(inner.set_critical_section(hooks.critical_enter, hooks.critical_exit)) {}
  modbus::Activity activity() const override {
    enter();
    const modbus::Activity a = inner_.activity();
    exit();
    return a;
  }
  double read_status(modbus::RegId id) const override {
    enter();
    double v = 0.0;
    if (servo_status(id, &v)) {
      exit();
      return v;
    }
    v = inner_.read_status(id);
    exit();
    return v;
  }
  // The servo loop's own timing (servo.* registers); null: they read 0.
  void set_servo_state(const ServoState* servo) { servo_ = servo; }
  // The board's whole interrupt chain per tick (servo.*_interrupt_cycles); null: 0.
  void set_interrupt_meter(const InterruptMeterState* meter) { meter_ = meter; }
  ApplyResult apply_config(modbus::ConfigImage& config, bool live_tuning) override {
    // The kernel binding masks only its commit (a few thousand instructions);
    // masking the whole call held the servo tick off for ~9 ms a write.
    if (masks_own_commit_) return inner_.apply_config(config, live_tuning);
    enter();
    const ApplyResult r = inner_.apply_config(config, live_tuning);
    exit();
    return r;
  }
  std::uint16_t command(std::uint16_t code, std::uint16_t axis, float value) override {
    enter();
    const std::uint16_t r = inner_.command(code, axis, value);
    exit();
    return r;
  }
  bool save_config(const modbus::ConfigImage& config) override {
    if (hooks_.long_operation != nullptr) hooks_.long_operation(true);
    const bool ok = inner_.save_config(config);
    if (hooks_.long_operation != nullptr) hooks_.long_operation(false);
    ++saves;
    return ok;
  }
  modbus::PersistStatus persist_status() const override { return inner_.persist_status(); }
  void sync_config(modbus::ConfigImage& config) override {
    enter();
    inner_.sync_config(config);
    exit();
  }

  std::uint32_t saves = 0;

 private:
  void enter() const {
    if (hooks_.critical_enter != nullptr) hooks_.critical_enter();
  }
  void exit() const {
    if (hooks_.critical_exit != nullptr) hooks_.critical_exit();
  }
  bool servo_status(modbus::RegId id, double* v) const {
    if (servo_ != nullptr) {
      switch (id) {
        case modbus::RegId::servo_max_cycles: *v = servo_->max_cycles; return true;
        case modbus::RegId::servo_last_cycles: *v = servo_->last_cycles; return true;
        case modbus::RegId::servo_overruns: *v = servo_->overruns; return true;
        default: break;
      }
    }
    if (meter_ != nullptr) {
      switch (id) {
        case modbus::RegId::servo_max_interrupt_cycles: *v = meter_->max_cycles; return true;
        case modbus::RegId::servo_last_interrupt_cycles: *v = meter_->last_cycles; return true;
        default: break;
      }
    }
    return false;
  }
  modbus::Device& inner_;
  const ApplicationHooks& hooks_;
  bool masks_own_commit_;  // inner_ masks only its commit (set_critical_section)
  const ServoState* servo_ = nullptr;
  const InterruptMeterState* meter_ = nullptr;
};

template <typename T>
T saturate16(std::uint32_t v) {
  return v > 0xFFFFu ? T{0xFFFF} : static_cast<T>(v);
}

}  // namespace application_detail

template <typename Scalar, std::size_t kRecorderCapacity = 2048>
class Application {
 public:
  using Config = ApplicationConfig;
  using Hooks = ApplicationHooks;
  using RecorderType = Recorder<kRecorderCapacity>;

  // Boots: loads and applies the stored configuration (store may be null:
  // kernel defaults). can, uart, recorder may be null (not serviced).
  Application(kernel::Controller<Scalar>& kernel, persistence::ConfigStore* store, can::CanPort* can,
              ByteSink* uart, const RecorderType* recorder, drivers::iwdg::FeedGate& gate, WatchdogFeeder& dog,
              const Config& config, const Hooks& hooks)
      : kernel_(kernel),
        config_(config),
        hooks_(hooks),
        device_(kernel, store),
        guarded_(device_, hooks_),
        registers_(guarded_, device_.boot()),
        rtu_(registers_, config.modbus_unit, config.modbus_baud),
        can_(can),
        uart_(uart),
        recorder_(recorder),
        gate_(gate),
        dog_(dog) {
    const modbus::PersistStatus p = device_.persist_status();
    if ((p.flags & (modbus::kLoadedBankA | modbus::kLoadedBankB)) != 0) registers_.mark_saved();
  }

  // RS-485 receive path (thread mode or the USART RX interrupt).
  void on_uart_byte(std::uint8_t byte, std::uint32_t timestamp_us) { rtu_.receive(byte, timestamp_us); }

  // The communications loop body; servo_ticks = ServoLoop::state().ticks.
  void service(std::uint32_t now_us, std::uint32_t servo_ticks) {
    service_modbus(now_us);
    service_can_rx(servo_ticks);
    if (hooks_.host_commands != nullptr) {
      can::HostCommandFrame h{};
      while (pop_host_command(h)) execute_host_command(h, servo_ticks);
    }
    service_telemetry(now_us, servo_ticks);
    service_recorder();
    ++stats_.services;
    gate_.comms_ran();
    (void)gate_.service(dog_);
  }

  modbus::PersistStatus persist_status() const { return device_.persist_status(); }
  // The lab tools behind the rec.* / wave.* registers (firmware/lab_tools/registers).
  void attach_lab_tools(modbus::LabTools* lab) { registers_.set_lab_tools(lab); }
  // The board's ServoLoop state behind servo.max_cycles / last_cycles /
  // overruns (read with the tick masked, like every kernel status read).
  void attach_servo_state(const ServoState* servo) { guarded_.set_servo_state(servo); }
  void attach_interrupt_meter(const InterruptMeterState* meter) { guarded_.set_interrupt_meter(meter); }
  const modbus::RegisterServer& registers() const { return registers_; }
  const modbus::RtuServer& rtu() const { return rtu_; }
  const can::LinkReceiver& receiver() const { return receiver_; }
  const ApplicationStats& stats() const { return stats_; }
  // The newest drained recorder entry (valid once stats().recorder_drained > 0).
  const RecordEntry& last_record() const { return last_record_; }

 private:
  void enter() const {
    if (hooks_.critical_enter != nullptr) hooks_.critical_enter();
  }
  void exit() const {
    if (hooks_.critical_exit != nullptr) hooks_.critical_exit();
  }

  void service_modbus(std::uint32_t now_us) {
    // The engineering-access relock clock (wrapping microseconds).
    if (have_last_service_us_) registers_.advance_time_us(now_us - last_service_us_);
    last_service_us_ = now_us;
    have_last_service_us_ = true;
    const std::size_t n = rtu_.poll(now_us, tx_);
    stats_.saves = guarded_.saves;
    if (n == 0) return;
    ++stats_.modbus_replies;
    if (uart_ == nullptr || !uart_->transmit(tx_, n)) ++stats_.uart_tx_errors;
  }

  void service_can_rx(std::uint32_t servo_ticks) {
    if (can_ == nullptr || !config_.drain_can_rx) return;
    can::CanFrame f{};
    for (std::uint8_t i = 0; i < config_.max_can_rx_per_service; ++i) {
      if (can_->receive(f, 0) != can::PortStatus::kOk) break;
      ++stats_.can_rx_frames;
      if (receiver_.accept(f) != can::RxStatus::kOk) continue;
      if (receiver_.last_message() != &can::message(can::MessageKind::kHostCommand)) continue;
      can::HostCommandFrame h{};
      can::decode_host_command(f, h);
      execute_host_command(h, servo_ticks);
    }
  }

  bool pop_host_command(can::HostCommandFrame& h) {
    enter();  // the producer is the servo interrupt
    const bool got = hooks_.host_commands->pop(h);
    exit();
    return got;
  }

  // The bench controller node's rule: mapped command -> kernel result; no
  // kernel meaning (shutdown) -> kHostResultNotExecuted. Always acknowledged.
  void execute_host_command(const can::HostCommandFrame& h, std::uint32_t servo_ticks) {
    can::HostCommandAckFrame ack{};
    ack.seq = h.seq;
    ack.code = h.code;
    ack.tick = servo_ticks;
    enter();
    kernel::MotionCommand c{};
    ack.result = motion_commands::to_motion_command(h, kernel_.status().reference, &c) ? static_cast<std::uint8_t>(kernel_.command(c))
                                                                       : can::kHostResultNotExecuted;
    ack.sequencer_state = static_cast<std::uint8_t>(kernel_.status().state);
    exit();
    ++stats_.host_commands;
    if (can_ == nullptr) return;
    can::CanFrame f{};
    can::encode_host_command_ack(ack, ack_counter_++, f);
    send(f);
  }

  void send(const can::CanFrame& f) {
    enter();
    const can::PortStatus s = can_->send(f);
    exit();
    if (s != can::PortStatus::kOk) ++stats_.can_tx_errors;
  }

  // True once per `period` ticks; a loop that fell behind re-aligns instead of bursting.
  static bool due(std::uint32_t ticks, std::uint32_t& last, std::uint16_t period, bool& started) {
    if (period == 0) return false;
    if (!started) {
      started = true;
      last = ticks;
      return true;
    }
    const std::uint32_t since = ticks - last;
    if (since < period) return false;
    last = since >= 2u * period ? ticks : last + period;
    return true;
  }

  void service_telemetry(std::uint32_t now_us, std::uint32_t servo_ticks) {
    // Uptime from the wrapping microsecond clock.
    if (clock_started_) {
      uptime_us_ += static_cast<std::uint64_t>(now_us - last_now_us_);
    }
    clock_started_ = true;
    last_now_us_ = now_us;
    if (can_ == nullptr) return;
    if (due(servo_ticks, last_sync_tick_, config_.sync_period_ticks, sync_started_)) {
      can::CanFrame f{};
      can::encode_sync(can::SyncFrame{servo_ticks, now_us}, sync_counter_++, f);
      send(f);
      ++stats_.sync_frames;
    }
    if (due(servo_ticks, last_status_tick_, config_.status_period_ticks, status_started_)) {
      enter();
      const can::ControllerStatusFrame frame = to_status_frame(kernel_.status());
      exit();
      can::CanFrame f{};
      can::encode_controller_status(frame, status_counter_++, f);
      send(f);
      ++stats_.status_frames;
    }
    if (due(servo_ticks, last_heartbeat_tick_, config_.heartbeat_period_ticks, heartbeat_started_)) {
      enter();
      const bool fault = kernel_.status().fault != kernel::FaultCode::kNone ||
                         kernel_.status().state == kernel::SequencerState::kFault;
      exit();
      const can::LinkReceiver& rx = hooks_.rx_stats != nullptr ? *hooks_.rx_stats : receiver_;
      can::HeartbeatFrame hb{};
      hb.node_state = fault ? can::NodeState::kFault : can::NodeState::kOperational;
      hb.uptime_ms = static_cast<std::uint32_t>(uptime_us_ / 1000u);
      hb.rx_rejected = application_detail::saturate16<std::uint16_t>(rx.stats().rejected_total());
      hb.bus_errors = application_detail::saturate16<std::uint16_t>(can_->counters().error_frames);
      can::CanFrame f{};
      can::encode_heartbeat(can::MessageKind::kHeartbeatController, hb, heartbeat_counter_++, f);
      send(f);
      ++stats_.heartbeat_frames;
    }
  }

  void service_recorder() {
    if (recorder_ == nullptr) return;
    const std::uint32_t head = recorder_->head();
    if (head - recorder_cursor_ > kRecorderCapacity) {
      stats_.recorder_lost += head - recorder_cursor_ - static_cast<std::uint32_t>(kRecorderCapacity);
      recorder_cursor_ = head - static_cast<std::uint32_t>(kRecorderCapacity);
    }
    while (recorder_->read(recorder_cursor_, last_record_)) {
      ++recorder_cursor_;
      ++stats_.recorder_drained;
    }
  }

  kernel::Controller<Scalar>& kernel_;
  Config config_;
  Hooks hooks_;
  modbus::ControllerDevice<Scalar> device_;
  application_detail::GuardedDevice guarded_;
  modbus::RegisterServer registers_;
  std::uint32_t last_service_us_ = 0;
  bool have_last_service_us_ = false;
  modbus::RtuServer rtu_;
  can::CanPort* can_;
  ByteSink* uart_;
  const RecorderType* recorder_;
  drivers::iwdg::FeedGate& gate_;
  WatchdogFeeder& dog_;
  can::LinkReceiver receiver_{};
  ApplicationStats stats_{};
  RecordEntry last_record_{};
  std::uint8_t tx_[modbus::kMaxRtuFrame] = {};
  std::uint32_t recorder_cursor_ = 0;
  std::uint32_t last_status_tick_ = 0;
  std::uint32_t last_heartbeat_tick_ = 0;
  std::uint32_t last_sync_tick_ = 0;
  bool sync_started_ = false;
  std::uint8_t sync_counter_ = 0;
  bool status_started_ = false;
  bool heartbeat_started_ = false;
  std::uint8_t status_counter_ = 0;
  std::uint8_t heartbeat_counter_ = 0;
  std::uint8_t ack_counter_ = 0;
  bool clock_started_ = false;
  std::uint32_t last_now_us_ = 0;
  std::uint64_t uptime_us_ = 0;
};

}  // namespace maglev::app
