// The "write during motion" rule on the REAL kernel, levitated over the HIL
// plant (hil::Plant stepped in the test, no threads): status.moving follows
// kernel::Controller::motion_active() (move profiles, pending steps), and a
// "not moving" register (config.save) is refused with 06 while the stage is
// moved, accepted again once the move has ended. Gains follow "idle, or live
// tuning" (06 while levitated unless tuning.live = 1).
#include <cmath>
#include <cstring>
#include <memory>

#include "maglev/plant/plant.hpp"
#include "maglev/can_link/host_commands.hpp"
#include "maglev/modbus/controller_binding.hpp"
#include "maglev/persistence/flash.hpp"

// Last: CppUTest's new/delete macros would break Eigen (hil::Plant).
#include <CppUTest/TestHarness.h>

using namespace maglev;
using namespace maglev::modbus;

namespace {

constexpr std::size_t kSector = 4096;

// Erased flash before anything boots from it (base: initialised first).
struct ErasedFlash {
  std::uint8_t flash_bytes[2 * kSector];
  ErasedFlash() { std::memset(flash_bytes, 0xFF, sizeof flash_bytes); }
};

struct LevitatedStage : ErasedFlash {
  persistence::RamFlash flash{flash_bytes, kSector, 2};
  persistence::ConfigStore store{flash, 0, 1};
  std::unique_ptr<kernel::Controller<float>> controller = std::make_unique<kernel::Controller<float>>();
  std::unique_ptr<hil::Plant> plant = std::make_unique<hil::Plant>(hil::PlantConfig{}, 7);
  ControllerDevice<float> device{*controller, &store};
  RegisterServer server{device, device.boot()};

  void tick() {
    const io::ActuatorCommand cmd = controller->step(plant->sample(), false);
    plant->apply(cmd);
    plant->advance_tick();
  }
  ExceptionCode write_u16(RegId id, std::uint16_t v) { return server.write_registers(def(id).address, 1, &v); }
  ExceptionCode write_f32(RegId id, float v) {
    std::uint16_t w[2];
    split_words(encode(RegType::kF32, static_cast<double>(v)), w);
    return server.write_registers(def(id).address, 2, w);
  }
  double read(RegId id) const {
    std::uint16_t w[2] = {};
    const RegisterDef& d = def(id);
    const std::uint16_t n = d.type == RegType::kU16 ? 1 : 2;
    if (server.read_registers(d.address, n, w) != ExceptionCode::kNone) return NAN;
    return d.type == RegType::kU16 ? static_cast<double>(w[0]) : decode(d.type, join_words(w));
  }
  // cmd.axis, cmd.value, cmd.code in one write (as stagectl does).
  std::uint16_t command(maglev::can::HostCommandCode code, std::uint16_t axis, float value) {
    std::uint16_t w[4] = {axis, 0, 0, static_cast<std::uint16_t>(code)};
    split_words(encode(RegType::kF32, static_cast<double>(value)), w + 1);
    if (server.write_registers(def(RegId::cmd_axis).address, 4, w) != ExceptionCode::kNone) return 0xFFFF;
    return static_cast<std::uint16_t>(read(RegId::cmd_result));
  }
  bool run_until(bool (*done)(const LevitatedStage&), int max_ticks) {
    for (int i = 0; i < max_ticks; ++i) {
      if (done(*this)) return true;
      tick();
    }
    return done(*this);
  }
};

bool is_ready(const LevitatedStage& s) { return s.controller->status().state == kernel::SequencerState::kReady; }
bool not_moving(const LevitatedStage& s) { return s.read(RegId::status_moving) == 0.0; }

}  // namespace

TEST_GROUP(MotionRule){};

TEST(MotionRule, SaveIsBusyDuringAMoveAndAllowedAfterIt) {
  auto st = std::make_unique<LevitatedStage>();
  LONGS_EQUAL(0, static_cast<int>(st->write_u16(RegId::access_key, kEngineerKey)));
  // Landed: nothing moves, save is allowed.
  DOUBLES_EQUAL(0.0, st->read(RegId::status_moving), 0.0);
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kNone), static_cast<int>(st->write_u16(RegId::config_save, 1)));

  LONGS_EQUAL(0, st->command(maglev::can::HostCommandCode::kLevitate, 0, 0.0f));
  // The sequencer lifting the stage is "moving" too (and the save is busy).
  st->tick();
  DOUBLES_EQUAL(1.0, st->read(RegId::status_moving), 0.0);
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kServerDeviceBusy),
              static_cast<int>(st->write_u16(RegId::config_save, 1)));
  CHECK_TEXT(st->run_until(is_ready, 25000), "no Ready within 10 s");
  for (int i = 0; i < 500; ++i) st->tick();  // settle 0.2 s
  // Levitated and holding: not moving, save allowed; gains are not (06).
  DOUBLES_EQUAL(0.0, st->read(RegId::status_moving), 0.0);
  CHECK_FALSE(st->controller->status().motion_active);
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kNone), static_cast<int>(st->write_u16(RegId::config_save, 1)));
  const float kp = static_cast<float>(st->read(RegId::gain_x_kp));
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kServerDeviceBusy),
              static_cast<int>(st->write_f32(RegId::gain_x_kp, kp)));

  const double x0 = st->read(RegId::status_x);
  LONGS_EQUAL(0, st->command(maglev::can::HostCommandCode::kMoveTo, 0, static_cast<float>(x0 + 1e-3)));
  // Right after the command, before any tick: the kernel's live flag already
  // says moving, so the very next request is refused.
  DOUBLES_EQUAL(1.0, st->read(RegId::status_moving), 0.0);
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kServerDeviceBusy),
              static_cast<int>(st->write_u16(RegId::config_save, 1)));
  for (int i = 0; i < 25; ++i) st->tick();  // 10 ms into the ~52 ms move
  CHECK(st->controller->status().motion_active);
  DOUBLES_EQUAL(1.0, st->read(RegId::status_moving), 0.0);
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kServerDeviceBusy),
              static_cast<int>(st->write_u16(RegId::config_save, 1)));
  // Gains during the move: busy unless live tuning is on.
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kServerDeviceBusy),
              static_cast<int>(st->write_f32(RegId::gain_x_kp, kp)));
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kNone), static_cast<int>(st->write_u16(RegId::tuning_live, 1)));
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kNone), static_cast<int>(st->write_f32(RegId::gain_x_kp, kp)));
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kNone), static_cast<int>(st->write_u16(RegId::tuning_live, 0)));
  // Wait for the end of the profile.
  CHECK_TEXT(st->run_until(not_moving, 2500), "move did not end within 1 s");
  CHECK_FALSE(st->controller->status().motion_active);
  for (int i = 0; i < 250; ++i) st->tick();  // settle 0.1 s
  const double x1 = st->read(RegId::status_x);
  DOUBLES_EQUAL(1e-3, x1 - x0, 1e-6);
  DOUBLES_EQUAL(6.0, st->read(RegId::status_state), 0.0);  // still Ready
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kNone), static_cast<int>(st->write_u16(RegId::config_save, 1)));

  // A step is motion until the tick that applies it.
  LONGS_EQUAL(0, st->command(maglev::can::HostCommandCode::kStep, 0, 1e-6f));
  DOUBLES_EQUAL(1.0, st->read(RegId::status_moving), 0.0);
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kServerDeviceBusy),
              static_cast<int>(st->write_u16(RegId::config_save, 1)));
  st->tick();
  DOUBLES_EQUAL(0.0, st->read(RegId::status_moving), 0.0);
}

// Issue 16: servo.rate while levitated (Ready, holding: not moving, so the
// save is allowed) is SERVER_DEVICE_BUSY and changes nothing: not the kernel,
// not the register, not what a save then stores.
TEST(MotionRule, TheServoRateIsRefusedWhileLevitatedAndChangesNothing) {
  auto st = std::make_unique<LevitatedStage>();
  LONGS_EQUAL(0, static_cast<int>(st->write_u16(RegId::access_key, kEngineerKey)));
  LONGS_EQUAL(0, st->command(maglev::can::HostCommandCode::kLevitate, 0, 0.0f));
  CHECK_TEXT(st->run_until(is_ready, 25000), "no Ready within 10 s");
  for (int i = 0; i < 250; ++i) st->tick();
  DOUBLES_EQUAL(0.0, st->read(RegId::status_moving), 0.0);
  kernel::KernelConfig before;
  std::memcpy(&before, &st->controller->config(), sizeof before);
  for (std::uint16_t rate : {std::uint16_t{5000}, std::uint16_t{10000}, std::uint16_t{20000}, std::uint16_t{3000}}) {
    LONGS_EQUAL(static_cast<int>(ExceptionCode::kServerDeviceBusy),
                static_cast<int>(st->write_u16(RegId::servo_rate, rate)));
  }
  // Live tuning unlocks gains, never the rate.
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kNone), static_cast<int>(st->write_u16(RegId::tuning_live, 1)));
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kServerDeviceBusy),
              static_cast<int>(st->write_u16(RegId::servo_rate, 10000)));
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kNone), static_cast<int>(st->write_u16(RegId::tuning_live, 0)));
  MEMCMP_EQUAL(&before, &st->controller->config(), sizeof(kernel::KernelConfig));
  DOUBLES_EQUAL(2500.0, st->read(RegId::servo_rate), 0.0);
  for (int i = 0; i < 250; ++i) st->tick();
  DOUBLES_EQUAL(6.0, st->read(RegId::status_state), 0.0);  // still Ready, still at 2.5 kHz
  // What a save stores: the running 2.5 kHz.
  LONGS_EQUAL(static_cast<int>(ExceptionCode::kNone), static_cast<int>(st->write_u16(RegId::config_save, 1)));
  const persistence::LoadResult stored = st->store.load();
  LONGS_EQUAL(2500, static_cast<int>(stored.config.get(RegId::servo_rate)));
}
