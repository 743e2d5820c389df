// maglev-stm32h743 / maglev-stm32h743-hil: the board images. Own every static
// object (drivers, kernel, servo loop, recorder, application services), the
// interrupt priorities and the communications loop. One source, two images:
//
//   production (MAGLEV_BOARD_HIL undefined): sensors = AD7606 pair + three
//     quadrature counters, actuators = AD5764 chain + amplifier enable
//     (amplifier_board_io.hpp); tick = the AD7606 pair's words in D2 SRAM:
//     BUSY falling edge (EXTI11) starts the SPI3 RX DMA read, the DMA1
//     stream 0 interrupt chains ADC0 -> ADC1 and then runs the tick
//     (drivers/ad7606_adc/README.md "DMA schedule").
//   HIL (MAGLEV_BOARD_HIL=1): sensors/actuators = app::CanSensorSource /
//     app::CanActuatorSink over FDCAN1 (sensor frame in, actuator frame out);
//     tick = TIM2 update at 2.5 kHz (the time master). Everything else -- the
//     kernel, ServoLoop, Application (Modbus, telemetry, persistence,
//     watchdog policy) -- is the same code.
//
// Priorities (4 implemented bits, lower = more urgent):
//   0  servo tick: DMA1_Stream0 (production; EXTI15_10 starts its read) /
//      TIM2 (HIL), and TIM3 (16-bit encoder extension, production): the
//      same level, never nested.
//   1  SysTick 1 kHz: missed-tick deadline check (safe outputs).
//   thread mode: app::Application::service -- Modbus RTU (USART2/RS-485),
//      CAN FD telemetry (controller_status 250 Hz, heartbeat 10 Hz), board
//      diagnostics frame, recorder drain, watchdog (fed only when the tick
//      AND this loop ran). Kernel accesses and (HIL) CAN sends from thread
//      mode run with interrupts masked (PRIMASK, nesting-safe).
#include <cstdint>

#include "maglev/app/application.hpp"
#include "maglev/app/interrupt_meter.hpp"
#include "maglev/app/recorder.hpp"
#include "maglev/app/servo_loop.hpp"
#include "maglev/board/stm32h743/board_flash.hpp"
#include "maglev/board/stm32h743/clock.hpp"
#include "maglev/board/stm32h743/mpu_cache.hpp"
#include "maglev/board/stm32h743/pinmap.hpp"
#include "maglev/board/stm32h743/servo_kernel.hpp"
#include "maglev/drivers/amplifier_enable.hpp"
#include "maglev/drivers/fdcan.hpp"
#include "maglev/drivers/flash.hpp"
#include "maglev/drivers/iwdg.hpp"
#include "maglev/drivers/stm32h7_gpio.hpp"
#include "maglev/drivers/usart_rs485.hpp"
#include "maglev/lab_tools/lab_registers.hpp"
#include "maglev/lab_tools/lab_tick.hpp"
#include "maglev/persistence/config_store.hpp"
#include "maglev/stm32h7/register_bus.hpp"
#if MAGLEV_BOARD_HIL
#include "maglev/app/can_io.hpp"
#else
#include "maglev/board/stm32h743/amplifier_board_drivers.hpp"
#include "maglev/drivers/convst_timer.hpp"
#endif

namespace r = maglev::stm32h7;
namespace d = maglev::drivers;
namespace b = maglev::board::stm32h743;
namespace pins = maglev::board::stm32h743::pins;
using Bus = r::MmioBus;

extern "C" {
void board_early_init();
void board_main();
void HardFault_Handler();
void SysTick_Handler();
void EXTI15_10_IRQHandler();
void DMA1_Stream0_IRQHandler();
void TIM3_IRQHandler();
void TIM2_IRQHandler();
void SPI1_IRQHandler();
// Linker script (linker/stm32h743.ld): the two configuration sectors.
extern std::uint32_t __config_bank_a_start;
extern std::uint32_t __config_bank_b_start;
}

namespace {

// The servo rate is the kernel's configured one (register servo.rate,
// persisted; 2500, 5000, 10000 or 20000 Hz): the timers are programmed from it
// at boot and again when it changes (landed: the kernel refuses it otherwise).
// Every offered rate divides the 480 MHz CPU and 240 MHz timer clocks exactly.
std::uint32_t g_servo_rate_Hz = 0;  // what the timers run at now
static_assert(b::kCpu_Hz % 20000u == 0u && b::kApbTimer_Hz % 20000u == 0u);
// Period and budget (50 % of the period) in CPU cycles: 192000 / 96000 at 2.5 kHz.
maglev::app::ServoConfig servo_timing(std::uint32_t rate_Hz) {
  const std::uint32_t period = b::kCpu_Hz / rate_Hz;
  return maglev::app::ServoConfig{period / 2u, period, 3};
}
std::uint32_t configured_servo_rate_Hz();

// --- fault log in backup SRAM (survives reset; read over Modbus after boot) ---
struct FaultLog {
  std::uint32_t magic;
  std::uint32_t count;
  std::uint32_t cfsr, hfsr, mmfar, bfar, stacked_pc;
};
constexpr std::uint32_t kFaultMagic = 0x4D41474Cu;  // "MAGL"
[[gnu::section(".backup_sram")]] FaultLog g_fault_log;

// --- the lab recorder owns all of AXI SRAM (512 KiB: 8 channels x 16384
// samples, docs/LAB-TOOLS.md); the per-tick record ring moved to D2 SRAM
// (non-cacheable: ~70 bytes written per tick, read by the comms loop) ---
constexpr std::size_t kRecorderEntries = 2048;
[[gnu::section(".dma_bss")]] maglev::app::Recorder<kRecorderEntries> g_recorder;
[[gnu::section(".axi_bss")]] float g_lab_pool[maglev::lab::kBoardPoolWords];
// One multisine period (16 KiB), read by the tick: DTCM (.bss).
float g_wave_table[maglev::lab::kWaveTableLen];
maglev::lab::Recorder g_lab_recorder{g_lab_pool, maglev::lab::kBoardPoolWords};
maglev::lab::WaveGenerator g_wave{g_wave_table, maglev::lab::kWaveTableLen};

Bus g_bus;

// GPIO
d::Stm32OutputPin<Bus> g_amp_enable_pin{g_bus, pins::kAmpEnable};
d::Stm32OutputPin<Bus> g_led{g_bus, pins::kLed};

#if !MAGLEV_BOARD_HIL
// --- DMA buffers in D2 SRAM (MPU: non-cacheable): the AD7606 raw words, written
// by the SPI3 RX DMA stream (DMA1 cannot reach DTCM). ---
[[gnu::section(".dma_bss")]] alignas(32) std::uint32_t g_adc_dma_rx[2][4];

// The parts (SPI1 DAC chain, SPI3 ADC pair, encoder counters): one composition
// shared with the QEMU whole-servo-tick image (amplifier_board_drivers.hpp).
b::AmplifierBoardDrivers<Bus> g_board{g_bus, g_adc_dma_rx};
auto& g_sensors = g_board.sensors;
using DacActuators = b::AmplifierBoardIrqActuators<b::AmplifierBoardDrivers<Bus>::DacWriter>;
DacActuators* g_dac_actuators = nullptr;  // SPI1_IRQHandler's; set in main()
// The tick's whole interrupt chain in cycles (EXTI + 2 DMA bodies with
// on_tick() + 4 SPI1 bodies): servo.max_interrupt_cycles / last_interrupt_cycles.
maglev::app::InterruptMeter g_interrupt_meter;
#endif

d::AmplifierEnable* g_amp = nullptr;  // constructed in main() after the GPIO is configured
d::fdcan::Fdcan<Bus> g_can{g_bus, d::fdcan::Config{}};
d::rs485::UsartRs485<Bus> g_rs485{g_bus, d::rs485::Config{r::usart::kUsart2, b::kApb_Hz, 115'200, 1'000, 1'000}};
d::iwdg::Watchdog<Bus> g_watchdog{g_bus};
d::iwdg::FeedGate g_feed_gate;
d::flash::Flash<Bus> g_flash{g_bus};

#if MAGLEV_BOARD_HIL
// HIL: the sensor frame replaces the ADC/encoders, the actuator frame the DAC.
// The tick clock (read count x 400 us) times the sensor-frame watchdog.
maglev::app::CanSensorSource g_sensors{g_can, maglev::app::CanSensorConfig{}};
maglev::app::CanActuatorSink g_can_actuators{g_can, g_sensors};
#endif

// Kernel + servo loop
b::ServoKernel g_kernel;
maglev::app::ServoLoop<b::ServoKernel>* g_servo = nullptr;

constexpr std::uint32_t kIwdgTimeout_ms = 50;
// A 128 KB sector erase takes up to ~4 s (DS12110 t_ERASE128KB): the IWDG is
// stretched for the duration of a configuration save only.
constexpr std::uint32_t kIwdgSaveTimeout_ms = 8000;

std::uint32_t cycle_counter() { return g_bus.read32(r::dwt::kCyccnt); }
#if MAGLEV_BOARD_HIL
bool tick_irq_pending_again() { return (g_bus.read32(r::tim::kTim2 + r::tim::kSr) & 1u) != 0; }  // UIF
#else
bool tick_irq_pending_again() { return (g_bus.read32(r::exti::kBase + r::exti::kCpupr1) & r::bit(11)) != 0; }
#endif
void servo_ran() { g_feed_gate.servo_ran(); }
void record(const maglev::io::SensorSample& s, const maglev::io::ActuatorCommand& c) {
  g_recorder.record(s, c);
  maglev::lab::LabTick<float>::record(s, c);  // the lab recorder: this tick's kernel status
}

// Microsecond clock for thread mode: DWT CYCCNT deltas accumulated (the loop
// runs far more often than CYCCNT's 8.9 s wrap), so it wraps at 2^32 us as
// the Modbus RTU timestamps and the heartbeat uptime expect.
std::uint32_t g_last_cycles = 0;
std::uint32_t g_cycle_remainder = 0;
std::uint32_t g_now_us = 0;
std::uint32_t configured_servo_rate_Hz() {
  // The kernel accepts only the offered rates (is_supported_servo_rate).
  return static_cast<std::uint32_t>(g_kernel.config().servo_rate_Hz);
}

std::uint32_t now_us() {
  const std::uint32_t c = cycle_counter();
  const std::uint32_t elapsed = c - g_last_cycles + g_cycle_remainder;
  g_last_cycles = c;
  constexpr std::uint32_t kCyclesPerUs = b::kCpu_Hz / 1'000'000u;
  g_now_us += elapsed / kCyclesPerUs;
  g_cycle_remainder = elapsed % kCyclesPerUs;
  return g_now_us;
}

// Thread-mode critical section: PRIMASK, nesting-safe. Held only for kernel
// accesses (status snapshot, Modbus status/command/config) and CAN sends.
std::uint32_t g_critical_nesting = 0;
void critical_enter() {
  __asm volatile("cpsid i" ::: "memory");
  ++g_critical_nesting;
}
void critical_exit() {
  if (--g_critical_nesting == 0) __asm volatile("cpsie i" ::: "memory");
}
void long_operation(bool begin) {
  (void)g_watchdog.start(begin ? kIwdgSaveTimeout_ms : kIwdgTimeout_ms);
}

// D-cache maintenance by address (DCIMVAC), 32-byte lines: after flash erase/program.
void invalidate_dcache(r::Addr start, std::size_t bytes) {
  constexpr r::Addr kDcimvac = 0xE000EF5C;
  r::barrier(g_bus);
  for (r::Addr a = start & ~r::Addr{31}; a < start + bytes; a += 32) g_bus.write32(kDcimvac, static_cast<std::uint32_t>(a));
  r::barrier(g_bus);
}

struct Rs485Replies final : maglev::app::ByteSink {
  bool transmit(const std::uint8_t* data, std::size_t len) override { return g_rs485.transmit(data, len); }
};
struct IwdgFeeder final : maglev::app::WatchdogFeeder {
  void feed() override { g_watchdog.feed(); }
};
Rs485Replies g_replies;
IwdgFeeder g_iwdg_feeder;

void nvic_enable(int irq, std::uint32_t priority) {
  const auto n = static_cast<std::uint32_t>(irq);
  const r::Addr ipr = r::nvic::kIpr + (n & ~3u);
  const unsigned shift = 8u * (n & 3u);
  r::modify32(g_bus, ipr, 0xFFu << shift, ((priority << 4) & 0xFFu) << shift);
  g_bus.write32(r::nvic::kIser + 4u * (n / 32u), 1u << (n % 32u));
}

void enable_peripheral_clocks() {
  r::modify32(g_bus, r::rcc::kBase + r::rcc::kAhb4enr, 0u, 0x7Fu | r::bit(28));  // GPIOA..G, BKPRAM
  r::modify32(g_bus, r::rcc::kBase + r::rcc::kAhb1enr, 0u, r::bit(0));            // DMA1 (+ DMAMUX1)
  r::modify32(g_bus, r::rcc::kBase + r::rcc::kApb1lenr, 0u,
              r::bit(0) | r::bit(1) | r::bit(3) | r::bit(15) | r::bit(17));  // TIM2/3/5, SPI3, USART2
  r::modify32(g_bus, r::rcc::kBase + r::rcc::kApb1henr, 0u, r::bit(8));      // FDCAN
  r::modify32(g_bus, r::rcc::kBase + r::rcc::kApb2enr, 0u, r::bit(0) | r::bit(12));  // TIM1, SPI1
  (void)g_bus.read32(r::rcc::kBase + r::rcc::kApb2enr);
}

void configure_pins() {
  g_amp_enable_pin.configure(false);  // OFF before anything else can run
  d::configure_alternate_pin(g_bus, pins::kCanRx, pins::kAfFdcan1);
  d::configure_alternate_pin(g_bus, pins::kCanTx, pins::kAfFdcan1);
  d::configure_alternate_pin(g_bus, pins::kRs485Tx, pins::kAfUsart2);
  d::configure_alternate_pin(g_bus, pins::kRs485Rx, pins::kAfUsart2, 3, 1);  // pull-up: idle mark
  d::configure_alternate_pin(g_bus, pins::kRs485De, pins::kAfUsart2);
  g_led.configure(false);
#if !MAGLEV_BOARD_HIL
  g_board.configure_pins();
#endif
}

#if MAGLEV_BOARD_HIL
// TIM2 (APB1 timer clock 240 MHz, 32-bit): update event every servo period.
void start_tick_timer() {
  const r::Addr t = r::tim::kTim2;
  g_bus.write32(t + r::tim::kCr1, 0u);
  g_bus.write32(t + r::tim::kPsc, 0u);
  g_bus.write32(t + r::tim::kArr, b::kApbTimer_Hz / g_servo_rate_Hz - 1u);  // 95999 at 2.5 kHz
  g_bus.write32(t + r::tim::kEgr, 1u);  // UG: load PSC/ARR
  g_bus.write32(t + r::tim::kSr, 0u);   // drop the UIF the UG just set
  g_bus.write32(t + r::tim::kDier, 1u); // UIE
  g_bus.write32(t + r::tim::kCr1, r::tim::kCr1Arpe | r::tim::kCr1Urs | r::tim::kCr1Cen);
}
#else
void configure_busy_exti() {
  // PE11 -> EXTI11 (SYSCFG_EXTICR3 bits 15:12 = 4: port E), falling edge, unmasked for CPU1.
  r::modify32(g_bus, r::syscfg::kBase + r::syscfg::kExticr1 + 8u, 0xFu << 12, 4u << 12);
  r::modify32(g_bus, r::exti::kBase + r::exti::kFtsr1, 0u, r::bit(11));
  g_bus.write32(r::exti::kBase + r::exti::kCpupr1, r::bit(11));
  r::modify32(g_bus, r::exti::kBase + r::exti::kCpuimr1, 0u, r::bit(11));
}
#endif

void enable_cycle_counter() {
  r::modify32(g_bus, r::dwt::kDemcr, 0u, r::bit(24));  // TRCENA
  g_bus.write32(r::dwt::kLar, 0xC5ACCE55u);
  g_bus.write32(r::dwt::kCyccnt, 0u);
  r::modify32(g_bus, r::dwt::kCtrl, 0u, 1u);
}

// Board diagnostic frame (ours, outside the can_link catalog): servo counters at 100 Hz.
void send_diagnostics(const maglev::app::ServoState& s) {
  maglev::can::CanFrame f{};
  f.id = 0x7F0;
  f.len = 16;
  f.flags = maglev::can::kFlagFd | maglev::can::kFlagBrs;
  const std::uint32_t words[4] = {s.ticks, s.overruns, s.max_cycles, s.sensor_faults};
  for (unsigned i = 0; i < 16; ++i) f.data[i] = static_cast<std::uint8_t>(words[i / 4] >> (8 * (i % 4)));
  critical_enter();  // HIL: the tick ISR sends on the same FDCAN TX FIFO
  (void)g_can.send(f);
  critical_exit();
}

}  // namespace

extern "C" void board_early_init() {
  if (b::configure_clock_480MHz(g_bus) != b::ClockStatus::kOk) {
    for (;;) {  // no valid clock: stay here with the amplifiers off (reset state)
    }
  }
  b::configure_mpu(g_bus);
  b::enable_caches(g_bus);
}

// Entered from Reset_Handler after static construction; never returns.
extern "C" void board_main() {
  enable_peripheral_clocks();
  configure_pins();
  static d::AmplifierEnable amp(g_amp_enable_pin);
  g_amp = &amp;
  enable_cycle_counter();

#if MAGLEV_BOARD_HIL
  maglev::app::ActuatorSink& actuators = g_can_actuators;
#else
  static DacActuators board_actuators(g_board.dac_writer, amp);
  maglev::app::ActuatorSink& actuators = board_actuators;
  g_board.init();  // DAC outputs at 0 A before the amplifiers can ever be enabled
  g_dac_actuators = &board_actuators;
#endif
  (void)g_can.init();
  g_rs485.init();

  // Persistence boot: the configuration sectors through the flash driver;
  // Application's constructor loads the newest valid bank and applies it to
  // the kernel before the first tick (persist.flags shows what happened).
  static b::BoardFlash<Bus> config_flash(g_bus, g_flash, reinterpret_cast<r::Addr>(&__config_bank_a_start),
                                         reinterpret_cast<r::Addr>(&__config_bank_b_start), &invalidate_dcache);
  static maglev::persistence::ConfigStore store(config_flash, 0, 1);
  maglev::app::ApplicationConfig app_config{};
  maglev::app::ApplicationHooks app_hooks{&critical_enter, &critical_exit, &long_operation, nullptr};
#if MAGLEV_BOARD_HIL
  app_config.drain_can_rx = false;  // CanSensorSource owns FDCAN RX
  app_config.sync_period_ticks = maglev::can::kSyncPeriodTicks;  // the HIL board is the time master
  app_hooks.rx_stats = &g_sensors.receiver();
  // host_command frames arrive in the tick ISR's drain; the comms loop
  // executes them (motion_commands::to_motion_command) and sends host_command_ack.
  app_hooks.host_commands = &g_sensors.host_commands();
#endif
  static maglev::app::Application<float, kRecorderEntries> application(
      g_kernel, &store, &g_can, &g_replies, &g_recorder, g_feed_gate, g_iwdg_feeder, app_config, app_hooks);

  // Lab tools: the recorder armed in fault watch (the last second before a
  // fault is kept), the wave generator off; rec.* / wave.* over Modbus.
  (void)g_lab_recorder.configure(maglev::lab::fault_watch_config(g_kernel.config().servo_rate_Hz));
  (void)g_lab_recorder.arm();
  maglev::lab::LabTick<float>::bind(&g_kernel, &g_lab_recorder, &g_wave);
  static maglev::lab::LabRegisters lab_registers(g_lab_recorder, g_wave, g_kernel.config(),
                                                 maglev::lab::LabRegistersHooks{&critical_enter, &critical_exit});
  application.attach_lab_tools(&lab_registers);

  static const maglev::app::ServoHooks hooks{&cycle_counter, &tick_irq_pending_again, &servo_ran, &record,
                                             &maglev::lab::LabTick<float>::before_step};
  // The rate the persisted configuration (applied by Application above) asks for.
  g_servo_rate_Hz = configured_servo_rate_Hz();
#if MAGLEV_BOARD_HIL
  g_sensors.set_period_us(1000000u / g_servo_rate_Hz);  // the CAN sensor source's tick clock
#endif
  static maglev::app::ServoLoop<b::ServoKernel> servo(g_sensors, actuators, g_kernel, servo_timing(g_servo_rate_Hz),
                                                      hooks);
  g_servo = &servo;
  application.attach_servo_state(&servo.state());  // servo.max_cycles / last_cycles / overruns over Modbus
#if !MAGLEV_BOARD_HIL
  application.attach_interrupt_meter(&g_interrupt_meter.state());  // servo.*_interrupt_cycles
#endif

  g_bus.write32(r::scb::kBase + r::scb::kShpr3, 1u << 28);  // SysTick priority 1
  g_bus.write32(r::systick::kRvr, b::kCpu_Hz / 1000u - 1u);
  g_bus.write32(r::systick::kCvr, 0u);
  g_bus.write32(r::systick::kCsr, 0x7u);  // CPU clock, interrupt, enable
#if MAGLEV_BOARD_HIL
  nvic_enable(r::irq::kTim2, 0);
  start_tick_timer();
#else
  configure_busy_exti();
  nvic_enable(r::irq::kExti15_10, 0);
  nvic_enable(r::irq::kDma1Stream0, 0);
  nvic_enable(r::irq::kTim3, 0);
  // The DAC frames' end-of-transfer: the tick's priority, so it never
  // preempts a tick; the first frame's comes ~2.4 us after the tick started
  // it, when the tick has returned.
  nvic_enable(r::irq::kSpi1, 0);
  // The servo clock: TIM1 CH1 PWM on CONVST (APB2 timer clock 240 MHz).
  d::start_convst_timer(g_bus, r::tim::kTim1, d::convst_timing(b::kApbTimer_Hz, g_servo_rate_Hz, 1000));
#endif
  (void)g_watchdog.start(kIwdgTimeout_ms);

  std::uint32_t last_diag_tick = 0;
  for (;;) {
    // Modbus RTU bytes with their arrival time (t3.5 framing in RtuServer).
    std::uint8_t byte = 0;
    while (g_rs485.receive_byte(byte)) application.on_uart_byte(byte, now_us());
    (void)g_rs485.frame_gap_elapsed();  // RtuServer times t3.5 itself; just clear RTOF
    const maglev::app::ServoState& s = servo.state();
    const std::uint32_t ticks = s.ticks;
    // Modbus reply, CAN telemetry, recorder drain, watchdog feed policy.
    application.service(now_us(), ticks);
    // Kernel work that need not run in the servo tick (homing's Hall solve;
    // the tick does it itself if this has not, same bits).
    (void)g_kernel.background();
    if (const std::uint32_t rate = configured_servo_rate_Hz(); rate != g_servo_rate_Hz) {
      // servo.rate written (landed): the kernel already re-designed its loops
      // for `rate`; stop the tick source, re-time the loop, restart it.
#if MAGLEV_BOARD_HIL
      g_bus.write32(r::tim::kTim2 + r::tim::kCr1, 0u);
      g_servo_rate_Hz = rate;
      servo.set_timing(servo_timing(rate));
      g_sensors.set_period_us(1000000u / rate);
      start_tick_timer();
#else
      g_bus.write32(r::tim::kTim1 + r::tim::kCr1, 0u);
      g_servo_rate_Hz = rate;
      servo.set_timing(servo_timing(rate));
      d::start_convst_timer(g_bus, r::tim::kTim1, d::convst_timing(b::kApbTimer_Hz, rate, 1000));
#endif
    }
    if (ticks - last_diag_tick >= g_servo_rate_Hz / 100u) {
      last_diag_tick = ticks;
      send_diagnostics(s);
      g_led.write(((ticks / g_servo_rate_Hz) & 1u) != 0u);
    }
  }
}

extern "C" {

#if MAGLEV_BOARD_HIL
// Servo tick: TIM2 update (the HIL board is the time master). ITCM-resident.
[[gnu::section(".itcm_text")]] void TIM2_IRQHandler() {
  g_bus.write32(r::tim::kTim2 + r::tim::kSr, 0u);  // clear UIF (rc_w0)
  if (g_servo != nullptr) g_servo->on_tick();
}
#else
// AD7606 BUSY fell -> both ADCs hold fresh results: start reading them by
// DMA (a few register writes; the wire runs without the CPU). A read that
// cannot start (still busy, previous read never completed) runs the tick at
// once, which reports the sensor loss. ITCM-resident.
[[gnu::section(".itcm_text")]] void EXTI15_10_IRQHandler() {
  const std::uint32_t start = cycle_counter();
  g_interrupt_meter.begin_tick();
  g_bus.write32(r::exti::kBase + r::exti::kCpupr1, r::bit(11));
  if (g_board.on_busy_fell() && g_servo != nullptr) g_servo->on_tick();
  g_interrupt_meter.add(start, cycle_counter());
}

// Servo tick: the SPI3 RX DMA finished a device. ADC0 -> ADC1 started; ADC1
// (or an error) -> the tick, which takes the completed buffer.
[[gnu::section(".itcm_text")]] void DMA1_Stream0_IRQHandler() {
  const std::uint32_t start = cycle_counter();
  if (g_board.on_adc_dma() && g_servo != nullptr) g_servo->on_tick();
  g_interrupt_meter.add(start, cycle_counter());
}

// 16-bit encoder extension points (wrap, 0x4000, 0xC000). Same priority as the tick.
[[gnu::section(".itcm_text")]] void TIM3_IRQHandler() { g_board.enc2.on_timer_irq(); }

// The AD5764 chain's SYNC frame k is on the wire: check its echo, start
// frame k + 1; after the fourth, LDAC and the amplifier enable.
[[gnu::section(".itcm_text")]] void SPI1_IRQHandler() {
  const std::uint32_t start = cycle_counter();
  if (g_dac_actuators != nullptr) (void)g_dac_actuators->on_dac_irq();
  g_interrupt_meter.add(start, cycle_counter());
}
#endif

void SysTick_Handler() {
  if (g_servo != nullptr) (void)g_servo->check_deadline(cycle_counter());
}

// Any fault: coils off first, log to backup SRAM, reset.
void HardFault_Handler() {
  g_bus.write32(pins::kAmpEnable.port + r::gpio::kBsrr, r::gpio::bsrr(pins::kAmpEnable.pin, false));
  r::modify32(g_bus, r::rcc::kBase + r::rcc::kAhb4enr, 0u, r::bit(28));
  r::modify32(g_bus, r::pwr::kBase + r::pwr::kCr1, 0u, r::pwr::kCr1Dbp);
  if (g_fault_log.magic != kFaultMagic) {
    g_fault_log.magic = kFaultMagic;
    g_fault_log.count = 0;
  }
  ++g_fault_log.count;
  g_fault_log.cfsr = g_bus.read32(0xE000ED28u);
  g_fault_log.hfsr = g_bus.read32(0xE000ED2Cu);
  g_fault_log.mmfar = g_bus.read32(0xE000ED34u);
  g_fault_log.bfar = g_bus.read32(0xE000ED38u);
  g_fault_log.stacked_pc = 0;
  r::barrier(g_bus);
  g_bus.write32(r::scb::kBase + r::scb::kAircr, (0x05FAu << 16) | (1u << 2));  // SYSRESETREQ
  for (;;) {
  }
}

}  // extern "C"
