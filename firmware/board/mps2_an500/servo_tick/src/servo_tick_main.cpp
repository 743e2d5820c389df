// maglev-qemu-servo-tick: the board's whole servo interrupt body --
// app::ServoLoop<Controller<float>>::on_tick() composed as
// firmware/board/stm32h743/src/main.cpp composes it for the production
// (non-HIL) board: AmplifierBoardSensors (AD7606 pair + three quadrature
// counters) in, AmplifierBoardIrqActuators (AD5764 chain written from
// SPI1's end-of-transfer interrupt + amplifier enable) out, the real drivers over Stm32SpiMaster / Stm32OutputPin /
// Stm32InputPin, the tick recorder + LabTick record hook, the LabTick
// before_step hook, the watchdog FeedGate, the cycle-counter and
// next-tick-pending hooks -- with the register bus replaced by
// BoardRegisterFake (board_register_fake.hpp), which answers the drivers'
// register reads with a recorded closed-loop session's sensor values
// (kernel-vector-recorder --rate 20000: tests/target/bitexact), so the
// kernel, configured at 20 kHz, runs start-up into Ready exactly as the
// host kernel did.
//
//   qemu-system-arm -M mps2-an500 -nographic -semihosting-config enable=on,target=native
//       -icount shift=6 -kernel maglev-qemu-servo-tick.elf
//       -append "<vectors.bin> <outputs_tick.bin> <outputs_step.bin> --icount"
//
// Two passes over the vectors, each from a fresh kernel and fresh drivers:
//   A: ServoLoop<Controller<float>> exactly as on the board; SysTick around
//      the whole on_tick() -> servo_tick_instructions <state>, and around
//      the AD7606 DMA read's interrupt work before it (BUSY fell: start ADC0;
//      DMA done: ADC0 -> ADC1; DMA done: pair complete) ->
//      adc_dma_isr_instructions <state>. The fake completes each device's
//      DMA transfer at CSTART (the wire time is not in either count);
//      main.cpp's handlers call the same on_busy_fell() / on_adc_dma();
//      and around the DAC chain's interrupt work after it (SPI1 EOT of each
//      of the four SYNC frames: echo checked, next frame started; the
//      fourth pulses LDAC and requests the enable) -> dac_irq_instructions
//      <state>, main.cpp's SPI1_IRQHandler (the fake sets EOT at once: no
//      wire time in it either);
//   B: the same composition with timing wrappers around the sensor source,
//      kernel step() and actuator sink -> servo_step_instructions,
//      servo_sensors_instructions, servo_actuators_instructions,
//      servo_outside_step_instructions (on_tick minus step: drivers, hooks,
//      bookkeeping, the wrappers' own reads) and the register accesses per tick.
// Each pass writes per tick the outputs the DRIVERS produced (DAC codes and
// amplifier enable decoded from the register writes, kernel status) in the
// kernel replay's output format, so the host compares them bit for bit with
// its own kernel (kernel-bitexact-compare). The image itself checks every
// tick that the sample the drivers built equals the recorded one. A third
// pass (C: pass A's composition, no outputs file) only counts the register
// accesses per tick: counting costs instructions, so no timed pass counts.
// Instruction counts need -icount (instruction_counter.hpp).
//
// Exit status: 0 ok, 2 usage, 3 cannot read, 4 bad header, 5 cannot write,
// 6 config refused, 7 the drivers' sample or DAC traffic differs from the record.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "maglev/app/interrupt_meter.hpp"
#include "maglev/app/recorder.hpp"
#include "maglev/app/servo_loop.hpp"
#include "maglev/board/mps2_an500/instruction_counter.hpp"
#include "maglev/board/mps2_an500/instruction_stats.hpp"
#include "maglev/board/mps2_an500/semihosting.hpp"
#include "maglev/board/stm32h743/amplifier_board_drivers.hpp"
#include "maglev/board/stm32h743/amplifier_board_io.hpp"
#include "maglev/board/stm32h743/pinmap.hpp"
#include "maglev/board/stm32h743/servo_kernel.hpp"
#include "maglev/drivers/ad5764.hpp"
#include "maglev/drivers/ad7606.hpp"
#include "maglev/drivers/amplifier_enable.hpp"
#include "maglev/drivers/iwdg.hpp"
#include "maglev/drivers/quadrature_encoder.hpp"
#include "maglev/drivers/stm32h7_gpio.hpp"
#include "maglev/drivers/stm32h7_spi.hpp"
#include "maglev/kernel_replay/replay_format.hpp"
#include "maglev/kernel_replay/semihost_file.hpp"
#include "maglev/kernel_replay/vectors_file.hpp"
#include "maglev/lab_tools/lab_tick.hpp"
#include "maglev/lab_tools/recorder.hpp"
#include "maglev/lab_tools/wave_generator.hpp"
#include "maglev/servo_tick/board_register_fake.hpp"

namespace {

namespace hw = maglev::board::mps2_an500;
namespace kr = maglev::kernel_replay;
namespace kernel = maglev::kernel;
namespace io = maglev::io;
namespace app = maglev::app;
namespace d = maglev::drivers;
namespace b = maglev::board::stm32h743;
namespace pins = maglev::board::stm32h743::pins;
namespace r = maglev::stm32h7;
namespace lab = maglev::lab;
using namespace hw::icount;

enum ExitCode : int {
  kOk = 0,
  kBadCommandLine = 2,
  kCannotRead = 3,
  kBadHeader = 4,
  kCannotWrite = 5,
  kConfigRefused = 6,
  kDriverMismatch = 7,
};
constexpr float kServoRate_Hz = 20000.0f;  // servo.rate: what this measurement is about

using Stats = TickStats;
constexpr int kStates = static_cast<int>(kernel::SequencerState::kFault) + 1;
struct StateStats {
  Stats s[kStates];
};
void print_all(const char* what, const StateStats& st, const Calibration& cal) {
  for (int i = 0; i < kStates; ++i) {
    if (st.s[i].count > 0U) print_tick_stats(what, kernel::to_string(static_cast<kernel::SequencerState>(i)), st.s[i], cal);
  }
}

// --- what the board image shares between ticks (main.cpp's statics) ----------------
constexpr std::size_t kRecorderEntries = 2048;  // main.cpp: the per-tick record ring
app::Recorder<kRecorderEntries> g_recorder;
float g_lab_pool[lab::kBoardPoolWords];
float g_wave_table[lab::kWaveTableLen];
lab::Recorder g_lab_recorder{g_lab_pool, lab::kBoardPoolWords};
lab::WaveGenerator g_wave{g_wave_table, lab::kWaveTableLen};
d::iwdg::FeedGate g_feed_gate;

// The board's cycle counter is DWT CYCCNT (one load); QEMU models no DWT, so
// the hook reads SysTick (counting down, 24 bits) as an up-counter modulo
// 2^32 in units of 1/256 count: ServoState::max_cycles >> 8 = SysTick counts.
std::uint32_t cycle_counter() { return (0u - systick().cvr) << 8; }
void servo_ran() { g_feed_gate.servo_ran(); }
void record(const io::SensorSample& s, const io::ActuatorCommand& c) {
  g_recorder.record(s, c);
  lab::LabTick<float>::record(s, c);
}

// SysTick-timed forwarding wrappers (pass B only).
std::uint32_t g_step_counts = 0, g_read_counts = 0, g_write_counts = 0;
struct TimedKernel {
  b::ServoKernel& k;
  io::ActuatorCommand step(const io::SensorSample& s, bool overrun) {
    const std::uint32_t t0 = systick_now();
    const io::ActuatorCommand c = k.step(s, overrun);
    const std::uint32_t t1 = systick_now();
    g_step_counts = systick_elapsed(t0, t1);
    return c;
  }
};
struct TimedSensors final : app::SensorSource {
  explicit TimedSensors(app::SensorSource& inner) : in(inner) {}
  bool read(io::SensorSample& s) override {
    const std::uint32_t t0 = systick_now();
    const bool ok = in.read(s);
    const std::uint32_t t1 = systick_now();
    g_read_counts = systick_elapsed(t0, t1);
    return ok;
  }
  app::SensorSource& in;
};
struct TimedActuators final : app::ActuatorSink {
  explicit TimedActuators(app::ActuatorSink& inner) : out(inner) {}
  void write(const io::ActuatorCommand& c) override {
    const std::uint32_t t0 = systick_now();
    out.write(c);
    const std::uint32_t t1 = systick_now();
    g_write_counts = systick_elapsed(t0, t1);
  }
  void force_safe() override { out.force_safe(); }  // forwarded, untimed (no deadline path runs here)
  app::ActuatorSink& out;
};

// The production board's tick composition (main.cpp, !MAGLEV_BOARD_HIL) on
// the fake register bus. kTimed: pass B's wrappers; kCount: pass C's counting bus.
template <bool kTimed, bool kCount = false, typename BusT = maglev::servo_tick::BoardRegisterFake<kCount>>
struct Board {
  using Bus = BusT;
  using Kernel = std::conditional_t<kTimed, TimedKernel, b::ServoKernel>;
  static inline Board* self = nullptr;
  static bool tick_irq_pending_again() {
    return (self->bus.read32(r::exti::kBase + r::exti::kCpupr1) & r::bit(11)) != 0;
  }

  Bus bus;
  std::uint32_t adc_dma_rx[2][4]{};
  d::Stm32OutputPin<Bus> amp_enable_pin{bus, pins::kAmpEnable};
  b::AmplifierBoardDrivers<Bus> parts{bus, adc_dma_rx};  // main.cpp's g_board
  decltype(b::AmplifierBoardDrivers<Bus>::sensors)& board_sensors = parts.sensors;
  d::AmplifierEnable amp{amp_enable_pin};
  b::AmplifierBoardIrqActuators<typename b::AmplifierBoardDrivers<Bus>::DacWriter> board_actuators{parts.dac_writer, amp};
  b::ServoKernel controller;
  TimedSensors timed_sensors{board_sensors};
  TimedActuators timed_actuators{board_actuators};
  Kernel kernel = make_kernel();
  app::ServoHooks hooks{&cycle_counter, &tick_irq_pending_again, &servo_ran, &record,
                        &lab::LabTick<float>::before_step};
  // The board: servo_timing(rate) = {period / 2, period, 3} in CPU cycles.
  // Here the counter counts SysTick, not CPU cycles, so no budget can be
  // compared: the largest one keeps the comparison on the path and never
  // flags an overrun (the recorded session had none).
  app::ServoConfig timing{0xFFFFFFFFu, 480000000u / 20000u, 3};
  app::ServoLoop<Kernel> servo{sensors(), actuators(), kernel, timing, hooks};

  Kernel make_kernel() {
    if constexpr (kTimed) {
      return TimedKernel{controller};
    } else {
      return {};
    }
  }
  app::SensorSource& sensors() {
    if constexpr (kTimed) {
      return timed_sensors;
    } else {
      return board_sensors;
    }
  }
  app::ActuatorSink& actuators() {
    if constexpr (kTimed) {
      return timed_actuators;
    } else {
      return board_actuators;
    }
  }
  b::ServoKernel& the_controller() {
    if constexpr (kTimed) {
      return controller;
    } else {
      return kernel;
    }
  }

  // main.cpp's EXTI15_10 (BUSY fell) and DMA1_Stream0 handlers up to the
  // point where they run the tick: true when they would (a DMA transfer
  // the fake does not complete would leave the tick unrun: the recorded
  // session then stops matching, exit 7).
  bool adc_dma_chain() {
    if (parts.on_busy_fell()) return true;
    for (std::size_t device = 0; device < 2; ++device) {
      if (parts.on_adc_dma()) return true;
    }
    return false;
  }

  // main.cpp's SPI1_IRQHandler, once per SYNC frame, until the write
  // finished: true when it did (four frames, or an error).
  bool dac_irq_chain() {
    for (int frame = 0; frame < 4; ++frame) {
      if (board_actuators.on_dac_irq()) return true;
    }
    return false;
  }

  // board_main()'s driver bring-up, in its order.
  void boot() {
    self = this;
    if constexpr (requires { bus.map_dma_memory(&adc_dma_rx[0][0], 8); }) bus.map_dma_memory(&adc_dma_rx[0][0], 8);
    amp_enable_pin.configure(false);
    parts.configure_pins();
    parts.init();
  }

  // The recorded counts start anywhere in 32 bits (the plant's wrapping
  // counters); the 16-bit TIM3 count is extended from 0 at init(). On the
  // board the counter gets there by moving, and the timer's own interrupt
  // (TIM3_IRQHandler -> on_timer_irq, at the wrap and the quarter points)
  // keeps the extension exact: walk it there the same way, 0x4000 at a time.
  void walk_encoder2(std::uint32_t target) {
    std::uint32_t at = 0;
    for (;;) {
      const auto left = static_cast<std::int32_t>(target - at);
      if (left < 0x4000 && left > -0x4000) break;
      at += left > 0 ? 0x4000u : static_cast<std::uint32_t>(-0x4000);
      bus.set_count(2, at);
      parts.enc2.on_timer_irq();
    }
  }
};

Board<false> g_board_a;  // pass A: exactly the board's ServoLoop<Controller<float>>
Board<true> g_board_b;   // pass B: the breakdown
Board<false, true> g_board_c;  // pass C: register accesses

// What the fake costs: the drivers alone on a bus that costs what MMIO costs
// (one volatile load/store into a RAM image of the registers, plus the
// address masking), with the ready flags preset. The data they move is
// meaningless (zeros: the DAC link check then reports a mismatch and trips
// the enable instead of requesting it, a few instructions either way), the
// path is the same: their instruction count without the fake's decoding.
struct MemoryBus {
  static inline volatile std::uint32_t image[0x10000 / 4];
  std::uint32_t read32(r::Addr a) const { return image[(a & 0xFFFFu) >> 2]; }
  void write32(r::Addr a, std::uint32_t v) const { image[(a & 0xFFFFu) >> 2] = v; }
};
Board<false, false, MemoryBus> g_board_d;

// The board's three servo-chain interrupt handlers (firmware/board/stm32h743
// src/main.cpp: EXTI15_10, DMA1_Stream0, SPI1) around their driver bodies:
// the DWT CYCCNT reads and the InterruptMeter bookkeeping (the cycle counts
// the board reports as servo.max_interrupt_cycles), the EXTI pending clear,
// the null checks. The same statements on the memory-cost bus; the body
// (inlined on the board, and counted above) is a volatile flag here.
maglev::app::InterruptMeter g_replica_meter;
void* volatile g_replica_servo = nullptr;
volatile bool g_replica_body_result = false;
std::uint32_t replica_cycle_counter() { return g_board_d.bus.read32(r::dwt::kCyccnt); }
[[gnu::noinline]] void replica_exti_handler() {
  const std::uint32_t start = replica_cycle_counter();
  g_replica_meter.begin_tick();
  g_board_d.bus.write32(r::exti::kBase + r::exti::kCpupr1, r::bit(11));
  if (g_replica_body_result && g_replica_servo != nullptr) __asm__ volatile("" ::: "memory");
  g_replica_meter.add(start, replica_cycle_counter());
}
[[gnu::noinline]] void replica_dma_handler() {
  const std::uint32_t start = replica_cycle_counter();
  if (g_replica_body_result && g_replica_servo != nullptr) __asm__ volatile("" ::: "memory");
  g_replica_meter.add(start, replica_cycle_counter());
}
[[gnu::noinline]] void replica_spi1_handler() {
  const std::uint32_t start = replica_cycle_counter();
  if (g_replica_servo != nullptr) (void)g_replica_body_result;
  g_replica_meter.add(start, replica_cycle_counter());
}

std::uint32_t& memory_bus_word(r::Addr a) {
  return const_cast<std::uint32_t&>(MemoryBus::image[(a & 0xFFFFu) >> 2]);
}

void measure_drivers_on_memory_bus(const Calibration& cal) {
  memory_bus_word(r::spi::kSpi1 + r::spi::kSr) = r::spi::kSrTxp | r::spi::kSrRxp | r::spi::kSrEot;
  memory_bus_word(r::spi::kSpi3 + r::spi::kSr) = r::spi::kSrTxp | r::spi::kSrRxp | r::spi::kSrEot;
  memory_bus_word(r::gpio::port('F') + r::gpio::kIdr) = (1u << 12) | (1u << 13) | (1u << 14);
  g_board_d.boot();
  // After boot (TIM2 CR1 shares the word in this 64 KiB image): every poll
  // of DMA1 stream 0 sees TCIF, as it does when the wire is done.
  const r::Addr lisr = r::dma::kDma1 + r::dma::kLisr;
  const r::Addr s0cr = r::dma::stream(r::dma::kDma1, 0) + r::dma::kSxCr;
  Stats chain, sensors, actuators, dac_irq;
  io::ActuatorCommand c{{100, -200, 300, -400, 500, -600, 700, -800}, true};
  for (std::uint32_t i = 0; i < 1000; ++i) {
    // The DMA read's three interrupt bodies, each timed alone: between them
    // the hardware would have cleared the stream's EN (end of transfer).
    std::uint32_t pieces = 0;
    memory_bus_word(lisr) = r::dma::kFlagTc << r::dma::flag_shift(0);
    memory_bus_word(s0cr) = 0;
    std::uint32_t t0 = systick_now();
    (void)g_board_d.parts.on_busy_fell();
    std::uint32_t t1 = systick_now();
    pieces += systick_elapsed(t0, t1);
    for (int device = 0; device < 2; ++device) {
      memory_bus_word(lisr) = r::dma::kFlagTc << r::dma::flag_shift(0);
      memory_bus_word(s0cr) = 0;
      t0 = systick_now();
      (void)g_board_d.parts.on_adc_dma();
      t1 = systick_now();
      pieces += systick_elapsed(t0, t1);
    }
    chain.add(pieces - 2u * static_cast<std::uint32_t>(cal.empty_counts), i);
    io::SensorSample s{};
    t0 = systick_now();
    (void)g_board_d.board_sensors.read(s);
    t1 = systick_now();
    // The sample escapes: without this the compiler may drop the stores of
    // an inlined read() into the unused local, and count less than the board runs.
    __asm__ volatile("" : : "r"(&s) : "memory");
    sensors.add(systick_elapsed(t0, t1), i);
    // Every coil the same code, so both devices' words of a frame are equal
    // and one RXDR word can echo them: each frame's SDO echo is the frame
    // before it, so the writer takes its real path (every echo matches, the
    // enable requested), not the link-mismatch trip.
    const auto code = static_cast<std::int16_t>(i);
    for (auto& d : c.dac_code) d = code;
    t0 = systick_now();
    g_board_d.board_actuators.write(c);
    t1 = systick_now();
    actuators.add(systick_elapsed(t0, t1), i);
    // The four SPI1 interrupt bodies, each timed alone (EOT preset above).
    pieces = 0;
    for (int frame = 0; frame < 4; ++frame) {
      const std::uint8_t echoed_channel = static_cast<std::uint8_t>((frame + 3) % 4);
      const auto echoed_code = static_cast<std::int16_t>(frame == 0 ? code - 1 : code);
      memory_bus_word(r::spi::kSpi1 + r::spi::kRxdr) = maglev::drivers::ad5764::data_word(echoed_channel, echoed_code);
      t0 = systick_now();
      (void)g_board_d.board_actuators.on_dac_irq();
      t1 = systick_now();
      pieces += systick_elapsed(t0, t1);
    }
    dac_irq.add(pieces - 3u * static_cast<std::uint32_t>(cal.empty_counts), i);
  }
  // Which paths were measured: every read and write must have completed
  // (a figure taken on an error path would be too small).
  const auto& adc = g_board_d.parts.adc.state();
  const auto& dac = g_board_d.parts.dac_writer.state();
  const struct { const char* name; std::uint32_t value; } paths[] = {
      {" adc reads=", adc.reads},           {" adc bus_errors=", adc.bus_errors}, {" adc not_ready=", adc.not_ready},
      {" busy_faults=", adc.busy_faults},   {" dac writes=", dac.writes},         {" dac bus_errors=", dac.bus_errors},
      {" dac link_mismatches=", dac.link_mismatches}, {" amplifier trips=", g_board_d.amp.trips()}};
  hw::semihost_write("drivers_on_memory_bus paths:");
  for (const auto& p : paths) {
    hw::semihost_write(p.name);
    hw::semihost_write_unsigned(p.value);
  }
  hw::semihost_write("\n");
  print_tick_stats("drivers_on_memory_bus", "adc_dma_isr", chain, cal);
  print_tick_stats("drivers_on_memory_bus", "sensors", sensors, cal);
  print_tick_stats("drivers_on_memory_bus", "actuators", actuators, cal);
  print_tick_stats("drivers_on_memory_bus", "dac_irq", dac_irq, cal);
  // The servo loop's next-tick check (ServoHooks::next_tick_pending, one EXTI
  // pending-register read) is the only other register access in on_tick():
  // its cost on the fake (pass A's bus) and on the memory-cost bus.
  Stats next_fake, next_bus;
  for (std::uint32_t i = 0; i < 1000; ++i) {
    std::uint32_t t0 = systick_now();
    bool pending = Board<false>::tick_irq_pending_again();
    std::uint32_t t1 = systick_now();
    __asm__ volatile("" : : "r"(pending) : "memory");
    next_fake.add(systick_elapsed(t0, t1), i);
    t0 = systick_now();
    pending = Board<false, false, MemoryBus>::tick_irq_pending_again();
    t1 = systick_now();
    __asm__ volatile("" : : "r"(pending) : "memory");
    next_bus.add(systick_elapsed(t0, t1), i);
  }
  // The handlers' own work per tick: EXTI once, the DMA stream's twice,
  // SPI1's four times.
  Stats wrappers;
  for (std::uint32_t i = 0; i < 1000; ++i) {
    std::uint32_t total = 0;
    const auto timed = [&total](void (*handler)()) {
      const std::uint32_t t0 = systick_now();
      handler();
      const std::uint32_t t1 = systick_now();
      total += systick_elapsed(t0, t1);
    };
    timed(&replica_exti_handler);
    for (int k = 0; k < 2; ++k) timed(&replica_dma_handler);
    for (int k = 0; k < 4; ++k) timed(&replica_spi1_handler);
    wrappers.add(total - 6u * static_cast<std::uint32_t>(cal.empty_counts), i);
  }
  print_tick_stats("drivers_on_memory_bus", "handler_wrappers", wrappers, cal);
  print_tick_stats("drivers_on_fake_bus", "next_tick_check", next_fake, cal);
  print_tick_stats("drivers_on_memory_bus", "next_tick_check", next_bus, cal);
}

char g_command_line[1024];
constexpr int kMaxWords = 5;
const char* g_words[kMaxWords] = {};
constexpr std::size_t kChunkTicks = 64;
std::uint8_t g_input[kChunkTicks * kr::kInputRecordBytes];
std::uint8_t g_output[kChunkTicks * kr::kOutputRecordBytes];

int fail(const char* message, int code) {
  hw::semihost_write("servo-tick: ");
  hw::semihost_write(message);
  hw::semihost_write("\n");
  return code;
}

bool same_sample(const io::SensorSample& a, const io::SensorSample& b) {
  for (int i = 0; i < io::kInterferometerAxes; ++i) {
    if (a.interferometer_counts[i] != b.interferometer_counts[i]) return false;
  }
  for (int i = 0; i < io::kDisplacementSensors; ++i) {
    if (a.displacement_adc[i] != b.displacement_adc[i]) return false;
  }
  for (int i = 0; i < io::kHallChannels; ++i) {
    if (a.hall_adc[i] != b.hall_adc[i]) return false;
  }
  for (int i = 0; i < io::kCoils; ++i) {
    if (a.coil_current_adc[i] != b.coil_current_adc[i]) return false;
  }
  return a.status_flags == b.status_flags;
}

struct PassResult {
  StateStats tick, step, sensors, actuators, outside, adc_dma, dac_irq;
  std::uint64_t ready_reads = 0, ready_writes = 0, ready_ticks = 0;
  std::uint32_t max_cycles = 0;
  std::uint32_t ticks = 0;
};
PassResult g_result[3];

template <bool kTimed, bool kCount>
int run_pass(Board<kTimed, kCount>& board, const char* vectors_path, const char* outputs_path, PassResult& res) {
  int in = -1;
  kr::InputHeader header{};
  if (const kr::VectorsOpen e = kr::open_vectors(vectors_path, &in, &header); e != kr::VectorsOpen::kOk) {
    const bool unreadable = e == kr::VectorsOpen::kCannotOpen || e == kr::VectorsOpen::kCannotReadHeader;
    return fail(kr::to_string(e), unreadable ? kCannotRead : kBadHeader);
  }
  if (header.profile_bytes != 0U) return fail("vectors with a stage profile: this image runs the default stage", kBadHeader);
  const int out = outputs_path != nullptr ? kr::semihost_open(outputs_path, kr::OpenMode::kWriteBinary) : -1;
  if (outputs_path != nullptr && out < 0) return fail("cannot open an outputs file", kCannotWrite);

  // The persisted configuration at servo.rate = 20000 (Application applies it on the board).
  kernel::KernelConfig config = kernel::default_kernel_config();
  config.servo_rate_Hz = kServoRate_Hz;
  config.measurement.servo_rate_Hz = kServoRate_Hz;  // as the binding applies servo.rate (image_to_kernel)
  b::ServoKernel& controller = board.the_controller();
  if (controller.apply_config(config) != kernel::ConfigError::kOk) return fail("apply_config refused", kConfigRefused);
  board.boot();
  // main.cpp: the lab recorder armed in fault watch, the wave generator off.
  g_lab_recorder.stop();
  (void)g_lab_recorder.configure(lab::fault_watch_config(controller.config().servo_rate_Hz));
  (void)g_lab_recorder.arm();
  lab::LabTick<float>::bind(&controller, &g_lab_recorder, &g_wave);

  std::uint32_t tick = 0;
  while (tick < header.tick_count) {
    const std::uint32_t left = header.tick_count - tick;
    const std::size_t n = left < kChunkTicks ? left : kChunkTicks;
    if (!kr::semihost_read(in, g_input, n * kr::kInputRecordBytes)) return fail("short read", kCannotRead);
    for (std::size_t i = 0; i < n; ++i, ++tick) {
      kr::InputRecord rec;
      kr::decode_input(&g_input[i * kr::kInputRecordBytes], &rec);
      kr::OutputRecord o;
      o.tick = tick;
      // Thread mode on the board (Modbus/CAN command, interrupts masked).
      if (tick == 0) board.walk_encoder2(rec.sample.interferometer_counts[2]);
      if (rec.has_command) o.command_result = static_cast<std::uint8_t>(controller.command(rec.command));
      board.bus.present(rec.sample);
      const std::uint32_t reads0 = board.bus.reads(), writes0 = board.bus.writes();
      const auto state_before = static_cast<int>(controller.status().state);

      const std::uint32_t c0 = systick_now();
      const bool run_tick = board.adc_dma_chain();
      const std::uint32_t c1 = systick_now();
      if (!run_tick) {
        hw::semihost_write("servo-tick: tick ");
        hw::semihost_write_unsigned(tick);
        return fail("the AD7606 DMA read did not complete", kDriverMismatch);
      }

      const std::uint32_t t0 = systick_now();
      board.servo.on_tick();
      const std::uint32_t t1 = systick_now();
      const std::uint32_t counts = systick_elapsed(t0, t1);

      const std::uint32_t d0 = systick_now();
      const bool dac_written = board.dac_irq_chain();
      const std::uint32_t d1 = systick_now();
      (void)controller.background();  // main.cpp's main loop (thread mode), not timed
      if (!dac_written) {
        hw::semihost_write("servo-tick: tick ");
        hw::semihost_write_unsigned(tick);
        return fail("the AD5764 chain's interrupt-driven write did not finish in four frames", kDriverMismatch);
      }

      if (state_before >= 0 && state_before < kStates) {
        res.tick.s[state_before].add(counts, tick);
        res.adc_dma.s[state_before].add(systick_elapsed(c0, c1), tick);
        res.dac_irq.s[state_before].add(systick_elapsed(d0, d1), tick);
        if constexpr (kTimed) {
          res.step.s[state_before].add(g_step_counts, tick);
          res.sensors.s[state_before].add(g_read_counts, tick);
          res.actuators.s[state_before].add(g_write_counts, tick);
          // on_tick minus step(): plus one empty measurement, so instructions() nets out the outer one only.
          res.outside.s[state_before].add(counts - g_step_counts + measure_empty(), tick);
        }
        if (kCount && state_before == static_cast<int>(kernel::SequencerState::kReady)) {
          res.ready_reads += board.bus.reads() - reads0;
          res.ready_writes += board.bus.writes() - writes0;
          ++res.ready_ticks;
        }
      }
      // The drivers' view of this tick: the sample they built (the tick
      // recorder's newest entry) and the DAC words / enable line they drove.
      app::RecordEntry entry{};
      if (!g_recorder.read(g_recorder.head() - 1u, entry) || !same_sample(entry.sample, rec.sample)) {
        hw::semihost_write("servo-tick: tick ");
        hw::semihost_write_unsigned(tick);
        return fail("the sample the drivers read differs from the recorded one", kDriverMismatch);
      }
      io::ActuatorCommand driven{};
      if (!board.bus.dac_command(&driven)) {
        hw::semihost_write("servo-tick: tick ");
        hw::semihost_write_unsigned(tick);
        return fail("the AD5764 chain did not receive four data frames", kDriverMismatch);
      }
      o.actuator = driven;
      o.status = &controller.status();
      kr::encode_output(o, &g_output[i * kr::kOutputRecordBytes]);
    }
    if (out >= 0 && !kr::semihost_write_file(out, g_output, n * kr::kOutputRecordBytes)) {
      return fail("cannot write the outputs", kCannotWrite);
    }
  }
  if (out >= 0) kr::semihost_close(out);
  kr::semihost_close(in);
  res.ticks = tick;
  res.max_cycles = board.servo.state().max_cycles;
  if (board.servo.state().overruns != 0U || board.servo.state().sensor_faults != 0U) {
    return fail("the servo loop counted overruns or sensor faults", kDriverMismatch);
  }
  return kOk;
}

}  // namespace

int main() {
  if (!hw::semihost_command_line(g_command_line, sizeof(g_command_line))) {
    return fail("no semihosting command line", kBadCommandLine);
  }
  // "<image> <vectors> <outputs_tick> <outputs_step> [--icount]"
  if (kr::split_words(g_command_line, g_words, kMaxWords) < 4) {
    return fail("usage: -append \"<vectors.bin> <outputs_tick.bin> <outputs_step.bin> [--icount]\"", kBadCommandLine);
  }
  const bool icount = g_words[4] != nullptr && std::strcmp(g_words[4], "--icount") == 0;

  const Calibration cal = start_and_calibrate();
  if (const int rc = run_pass(g_board_a, g_words[1], g_words[2], g_result[0]); rc != kOk) return rc;
  if (const int rc = run_pass(g_board_b, g_words[1], g_words[3], g_result[1]); rc != kOk) return rc;
  if (const int rc = run_pass(g_board_c, g_words[1], nullptr, g_result[2]); rc != kOk) return rc;

  hw::semihost_write("servo-tick: ");
  hw::semihost_write_unsigned(g_result[0].ticks);
  hw::semihost_write(" ticks at 20000 Hz, three times; the drivers' samples and DAC traffic matched the record\n");
  if (!icount) {
    hw::semihost_write("servo_tick_instructions: not measured (run QEMU with -icount shift=6 and pass --icount)\n");
    return kOk;
  }
  hw::semihost_write("systick calibration: empty=");
  hw::semihost_write_unsigned(cal.empty_counts);
  hw::semihost_write(" counts, 4096 nops=");
  hw::semihost_write_unsigned(cal.nop_counts);
  hw::semihost_write(" counts\n");
  print_all("servo_tick_instructions", g_result[0].tick, cal);
  print_all("adc_dma_isr_instructions", g_result[0].adc_dma, cal);
  print_all("dac_irq_instructions", g_result[0].dac_irq, cal);
  hw::semihost_write("servo_loop max_cycles (ServoState, its own cycle_counter hook; SysTick here): ");
  hw::semihost_write_unsigned(cal.instructions(g_result[0].max_cycles >> 8));
  hw::semihost_write(" instructions\n");
  print_all("servo_step_instructions", g_result[1].step, cal);
  print_all("servo_sensors_instructions", g_result[1].sensors, cal);
  print_all("servo_actuators_instructions", g_result[1].actuators, cal);
  print_all("servo_outside_step_instructions", g_result[1].outside, cal);
  print_all("servo_tick_timed_instructions", g_result[1].tick, cal);
  if (g_result[2].ready_ticks > 0U) {
    hw::semihost_write("register accesses per Ready tick: reads=");
    hw::semihost_write_unsigned(g_result[2].ready_reads / g_result[2].ready_ticks);
    hw::semihost_write(" writes=");
    hw::semihost_write_unsigned(g_result[2].ready_writes / g_result[2].ready_ticks);
    hw::semihost_write("\n");
  }
  measure_drivers_on_memory_bus(cal);
  return kOk;
}
