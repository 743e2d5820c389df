// The register map bound to the REAL kernel (kernel::Controller<float>) and
// persistence, driven by a libmodbus TCP client through the bench adapter.
#include <CppUTest/TestHarness.h>
#include <modbus/modbus.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <thread>

#include "maglev/can_link/host_commands.hpp"
#include "maglev/modbus/controller_binding.hpp"
#include "maglev/modbus_tcp/tcp_server.hpp"
#include "maglev/stage_profile/apply_profile.hpp"
#include "maglev/stage_profile/stage_database.hpp"
#include "maglev_test/resting_sample.hpp"

using namespace maglev;
using namespace maglev::modbus;

namespace {

std::uint16_t addr(RegId id) { return def(id).address; }
void set_f32(float v, std::uint16_t* w) { split_words(encode(RegType::kF32, static_cast<double>(v)), w); }
double get_f32(const std::uint16_t* w) { return decode(RegType::kF32, join_words(w)); }

using kernel::same_config;  // the values, padding excluded

constexpr std::size_t kSector = 4096;

struct Stage {
  std::uint8_t* flash_bytes;
  persistence::RamFlash flash;
  persistence::ConfigStore store{flash, 0, 1};
  std::unique_ptr<kernel::Controller<float>> controller = std::make_unique<kernel::Controller<float>>();
  ControllerDevice<float> device{*controller, &store};
  RegisterServer server{device, device.boot()};
  modbus_tcp::TcpServer tcp{server, "127.0.0.1", 0, 1};
  std::mutex m;
  std::atomic<bool> stop{false};
  std::thread thread;
  modbus_t* ctx = nullptr;

  explicit Stage(std::uint8_t* bytes) : flash_bytes(bytes), flash(bytes, kSector, 2) {
    thread = std::thread([this] {
      while (!stop) {
        std::lock_guard<std::mutex> lock(m);
        tcp.poll(2);
      }
    });
    ctx = modbus_new_tcp("127.0.0.1", tcp.port());
    modbus_set_slave(ctx, 1);
    modbus_connect(ctx);
  }
  ~Stage() {
    modbus_close(ctx);
    modbus_free(ctx);
    stop = true;
    thread.join();
  }
  kernel::KernelConfig config() {
    std::lock_guard<std::mutex> lock(m);
    return controller->config();
  }
};

#define EXPECT_EXCEPTION(rc, code)          \
  do {                                      \
    const int rc_ = (rc);                   \
    const int errno_ = errno;               \
    LONGS_EQUAL(-1, rc_);                   \
    LONGS_EQUAL(MODBUS_ENOBASE + (code), errno_); \
  } while (0)

}  // namespace

TEST_GROUP(KernelBinding) {
  std::uint8_t flash[kSector * 2];
  void setup() override { std::memset(flash, 0xFF, sizeof flash); }
};

TEST(KernelBinding, TableDefaultsAreTheKernelDefaults) {
  const ConfigImage from_kernel = image_from_kernel(kernel::default_kernel_config());
  const ConfigImage table = ConfigImage::defaults();
  for (std::size_t s = 0; s < kPersistedCount; ++s) {
    const RegisterDef& d = persisted_def(s);
    // Every persisted entry is a kernel field, except the stage selection.
    CHECK_TEXT(has_config_field(d.id) == (d.kind == Kind::kConfig), d.name);
    if (from_kernel.raw[s] != table.raw[s]) {
      FAIL(d.name);
    }
    CHECK_TEXT(value_in_range(d, from_kernel.get(d.id)), d.name);
  }
}

TEST(KernelBinding, GainWritesReachTheKernelWhole) {
  Stage st(flash);
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
  std::uint16_t w[14];
  const float v[7] = {30000.0f, 2.0e6f, 90.0f, 800.0f, 0.6f, 0.2f, 3.5f};
  for (int i = 0; i < 7; ++i) set_f32(v[i], w + 2 * i);
  LONGS_EQUAL(14, modbus_write_registers(st.ctx, addr(RegId::gain_y_kp), 14, w));
  const kernel::KernelConfig c = st.config();
  DOUBLES_EQUAL(30000.0, static_cast<double>(c.axis[1].pid.kp), 0.0);
  DOUBLES_EQUAL(2.0e6, static_cast<double>(c.axis[1].pid.ki), 0.0);
  DOUBLES_EQUAL(90.0, static_cast<double>(c.axis[1].pid.kd), 0.0);
  DOUBLES_EQUAL(800.0, static_cast<double>(c.axis[1].pid.derivative_filter_hz), 0.0);
  DOUBLES_EQUAL(0.6, static_cast<double>(c.axis[1].pid.setpoint_weight_p), 1e-7);
  DOUBLES_EQUAL(0.2, static_cast<double>(c.axis[1].pid.setpoint_weight_d), 1e-7);
  DOUBLES_EQUAL(3.5, static_cast<double>(c.axis[1].pid.effort_limit_A), 0.0);
  DOUBLES_EQUAL(36000.0, static_cast<double>(c.axis[0].pid.kp), 0.0);  // x untouched
  // Read back through the map.
  std::uint16_t r[2];
  LONGS_EQUAL(2, modbus_read_registers(st.ctx, addr(RegId::gain_y_kp), 2, r));
  DOUBLES_EQUAL(30000.0, get_f32(r), 0.0);
}

TEST(KernelBinding, RefusedWritesLeaveTheKernelConfigUnchanged) {
  Stage st(flash);
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
  const kernel::KernelConfig before = st.config();
  std::uint16_t w[4];
  // Out of the map's range: 03.
  set_f32(20000.0f, w);
  EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::gain_x_derivative_filter), 2, w), 3);
  // In the map's range (which reaches the 20 kHz rate's Nyquist) but at or
  // above this rate's (2.5 kHz: 1250 Hz): refused by the kernel, 03.
  set_f32(1250.0f, w);
  EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::gain_x_derivative_filter), 2, w), 3);
  // In the map's range but refused by the kernel: the travel window would no
  // longer contain the reference limits (ConfigError::kReferenceLimits) -> 03.
  set_f32(0.001f, w);
  EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::limit_x_max), 2, w), 3);
  std::uint16_t err = 0;
  LONGS_EQUAL(1, modbus_read_registers(st.ctx, addr(RegId::status_config_error), 1, &err));
  CHECK(err != 0);
  CHECK(same_config(before, st.config()));
  // A multi-register write with a good kp and a bad ki: neither lands.
  set_f32(20000.0f, w);
  set_f32(-1.0f, w + 2);
  EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::gain_x_kp), 4, w), 3);
  CHECK(same_config(before, st.config()));
}

TEST(KernelBinding, GainWriteWhileTheKernelIsBusyIsServerBusy) {
  Stage st(flash);
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
  // Home: the sequencer leaves Idle at once.
  std::uint16_t cmd[4] = {0, 0, 0, static_cast<std::uint16_t>(maglev::can::HostCommandCode::kHome)};
  LONGS_EQUAL(4, modbus_write_registers(st.ctx, addr(RegId::cmd_axis), 4, cmd));
  std::uint16_t result = 0xFFFF;
  LONGS_EQUAL(1, modbus_read_registers(st.ctx, addr(RegId::cmd_result), 1, &result));
  LONGS_EQUAL(static_cast<int>(kernel::CommandResult::kAccepted), result);
  const kernel::KernelConfig before = st.config();
  std::uint16_t w[2];
  set_f32(20000.0f, w);
  EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::gain_x_kp), 2, w), 6);
  set_f32(3.0f, w);
  EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::limit_peak_current), 2, w), 6);
  CHECK(same_config(before, st.config()));
  // A move is refused by the kernel (not levitated): cmd.result says why.
  cmd[0] = 0;
  set_f32(1.0e-3f, cmd + 1);
  cmd[3] = static_cast<std::uint16_t>(maglev::can::HostCommandCode::kMoveTo);
  LONGS_EQUAL(4, modbus_write_registers(st.ctx, addr(RegId::cmd_axis), 4, cmd));
  LONGS_EQUAL(1, modbus_read_registers(st.ctx, addr(RegId::cmd_result), 1, &result));
  LONGS_EQUAL(static_cast<int>(kernel::CommandResult::kRefusedNotReady), result);
}

TEST(KernelBinding, ALiveGainStepBeyondTwiceIsIllegalDataValueAndChangesNothing) {
  Stage st(flash);
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::tuning_live), 1));
  // Home: off rest, so the gains may move only by live tuning's step.
  std::uint16_t cmd[4] = {0, 0, 0, static_cast<std::uint16_t>(maglev::can::HostCommandCode::kHome)};
  LONGS_EQUAL(4, modbus_write_registers(st.ctx, addr(RegId::cmd_axis), 4, cmd));
  const kernel::KernelConfig before = st.config();
  // theta_x kp and kd x3 in one 0x10 (run 3013 of the campaign wrote x20): 03.
  std::uint16_t w[6];
  set_f32(70.0f * 3.0f, w);
  set_f32(17600.0f, w + 2);
  set_f32(0.09f * 3.0f, w + 4);
  EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::gain_theta_x_kp), 6, w), 3);
  CHECK(same_config(before, st.config()));
  {
    std::lock_guard<std::mutex> lock(st.m);
    LONGS_EQUAL(static_cast<int>(kernel::ConfigError::kGainStepTooLarge),
                static_cast<int>(st.controller->status().last_config_error));
    LONGS_EQUAL(4, st.controller->status().config_axis);
  }
  // x2: applied.
  set_f32(70.0f * 2.0f, w);
  set_f32(0.09f * 2.0f, w + 4);
  LONGS_EQUAL(6, modbus_write_registers(st.ctx, addr(RegId::gain_theta_x_kp), 6, w));
  DOUBLES_EQUAL(140.0, static_cast<double>(st.config().axis[4].pid.kp), 0.0);
}

TEST(KernelBinding, SavedConfigurationIsAppliedAtBoot) {
  {
    Stage st(flash);
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
    std::uint16_t w[2];
    set_f32(2.75f, w);
    LONGS_EQUAL(2, modbus_write_registers(st.ctx, addr(RegId::limit_rms_current), 2, w));
    set_f32(250.0f, w);
    LONGS_EQUAL(2, modbus_write_registers(st.ctx, addr(RegId::gain_theta_z_kp), 2, w));
    EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::limit_rms_current), 2, w), 3);  // 250 A
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::config_save), 1));
  }
  Stage rebooted(flash);
  const kernel::KernelConfig c = rebooted.config();
  DOUBLES_EQUAL(250.0, static_cast<double>(c.axis[2].pid.kp), 0.0);
  DOUBLES_EQUAL(2.75, static_cast<double>(c.supervisor.rms_current_A), 0.0);
  std::uint16_t flags = 0;
  LONGS_EQUAL(1, modbus_read_registers(rebooted.ctx, addr(RegId::persist_flags), 1, &flags));
  LONGS_EQUAL(kLoadedBankA, flags);
}

TEST(KernelBinding, RecordTheKernelRefusesFallsBackToKernelDefaults) {
  {
    // A record whose values are each in the map's range but that the kernel
    // refuses as a whole (travel window no longer contains the reference limits).
    persistence::RamFlash f(flash, kSector, 2);
    persistence::ConfigStore store(f, 0, 1);
    store.load();
    ConfigImage image = ConfigImage::defaults();
    image.set(RegId::limit_x_max, 0.001);
    image.set(RegId::gain_x_kp, 20000.0);
    CHECK(store.save(image));
  }
  Stage st(flash);
  const kernel::KernelConfig c = st.config();
  DOUBLES_EQUAL(36000.0, static_cast<double>(c.axis[0].pid.kp), 0.0);  // kernel default, not 20000
  DOUBLES_EQUAL(static_cast<double>(kernel::default_kernel_config().supervisor.x_max_m),
                static_cast<double>(c.supervisor.x_max_m), 0.0);  // kernel default, not 0.001
  std::uint16_t flags = 0;
  LONGS_EQUAL(1, modbus_read_registers(st.ctx, addr(RegId::persist_flags), 1, &flags));
  CHECK(flags & kRefused);
  CHECK(flags & kLoadedDefaults);
  // And the map serves the configuration the kernel actually runs.
  std::uint16_t r[2];
  LONGS_EQUAL(2, modbus_read_registers(st.ctx, addr(RegId::gain_x_kp), 2, r));
  DOUBLES_EQUAL(36000.0, get_f32(r), 0.0);
}

// --- stage.profile: the stage database selected by a persisted register ------

namespace {
// A resting stage's raw sensor sample (z at rest, Hall pairs plausible).
io::SensorSample resting_sample() {
  static const std::uint32_t base[3] = {1000u, 2000u, 3000u};
  return test::stage_sample_at(0.0, 0.0, base);
}
std::uint16_t read_u16(modbus_t* ctx, RegId id) {
  std::uint16_t v = 0xFFFF;
  LONGS_EQUAL(1, modbus_read_registers(ctx, addr(id), 1, &v));
  return v;
}
std::uint16_t run_command(modbus_t* ctx, maglev::can::HostCommandCode code) {
  std::uint16_t cmd[4] = {0, 0, 0, static_cast<std::uint16_t>(code)};
  LONGS_EQUAL(4, modbus_write_registers(ctx, addr(RegId::cmd_axis), 4, cmd));
  return read_u16(ctx, RegId::cmd_result);
}
}  // namespace

TEST(KernelBinding, SelectingAStageProfileLoadsItsWholeConfigurationAndPersists) {
  kernel::KernelConfig square{};
  CHECK(KernelConfigOfProfile(1, &square) == stage_profile::ProfileError::kOk);  // nk2020-square
  CHECK_FALSE(same_config(square, kernel::default_kernel_config()));            // a different stage
  {
    Stage st(flash);
    LONGS_EQUAL(0, read_u16(st.ctx, RegId::stage_profile));
    // Operators cannot switch stages.
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::stage_profile), 1), 1);
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
    // Beyond the register's range, and inside it but not in the database: refused, nothing changed.
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::stage_profile), 16), 3);
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::stage_profile), 9), 3);
    // In the database but of a family this kernel does not drive (paper 001,
    // which has its own kernel): refused the same way.
    const int selfstab = stage_profile::FindStageProfile("jb2002-selfstab");
    CHECK(selfstab > 0);
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::stage_profile), static_cast<std::uint16_t>(selfstab)), 3);
    CHECK(same_config(kernel::default_kernel_config(), st.config()));
    LONGS_EQUAL(0, read_u16(st.ctx, RegId::stage_profile));
    // Landed, engineer: the square stage's configuration, whole.
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::stage_profile), 1));
    kernel::KernelConfig running = st.config();
    running.live_tuning = square.live_tuning;
    CHECK(same_config(square, running));
    LONGS_EQUAL(1, read_u16(st.ctx, RegId::stage_profile));
    LONGS_EQUAL(0, read_u16(st.ctx, RegId::status_profile_error));
    // The map serves what runs (a register the profile sets).
    std::uint16_t r[2];
    LONGS_EQUAL(2, modbus_read_registers(st.ctx, addr(RegId::gain_z_kp), 2, r));
    DOUBLES_EQUAL(static_cast<double>(square.axis[3].pid.kp), get_f32(r), 0.0);
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::config_save), 1));
  }
  Stage rebooted(flash);
  kernel::KernelConfig running = rebooted.config();
  running.live_tuning = square.live_tuning;
  CHECK(same_config(square, running));
  LONGS_EQUAL(1, read_u16(rebooted.ctx, RegId::stage_profile));
}

// The register map's current and travel ranges were the seed stage's (4 A,
// 3 A, +-30 / +-19.5 mm). A stage whose profile allows more (here 4.5 A
// peak, 3.5 A rms, +-40 mm of x travel: inside the board's 5 A) loaded, but
// its registers could not be written back with their own values, and a
// saved record was refused at the next boot (kValueOutOfRange): the stage
// fell back to the default one. The ranges are now the board's envelope and
// each stage's own limits bound the supervisor in the kernel
// (KernelConfig::stage, ConfigError kBeyondStageLimits).
TEST(KernelBinding, AStagesOwnLimitsBoundTheWritesAndItsValuesSaveAndRestore) {
  // 1. The seed stage: its own 4 A / +-28 mm still bound what a host writes.
  {
    Stage st(flash);
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
    const kernel::KernelConfig before = st.config();
    std::uint16_t w[2];
    set_f32(4.5f, w);  // inside the register's 5 A, beyond the seed's coils
    EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::limit_peak_current), 2, w), 3);
    LONGS_EQUAL(static_cast<int>(kernel::ConfigError::kBeyondStageLimits), read_u16(st.ctx, RegId::status_config_error));
    set_f32(0.0305f, w);  // the window more than 2 mm beyond the 28 mm travel
    EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::limit_x_max), 2, w), 3);
    set_f32(3.5f, w);
    EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::limit_rms_current), 2, w), 3);
    CHECK(same_config(before, st.config()));
    set_f32(0.030f, w);  // 2 mm beyond: admitted
    LONGS_EQUAL(2, modbus_write_registers(st.ctx, addr(RegId::limit_x_max), 2, w));
    set_f32(3.5f, w);  // a lower peak current: admitted
    LONGS_EQUAL(2, modbus_write_registers(st.ctx, addr(RegId::limit_peak_current), 2, w));
    DOUBLES_EQUAL(3.5, static_cast<double>(st.config().supervisor.peak_current_A), 0.0);
  }
  // 2. A lab's stage with wider limits: every value fits the map, the kernel
  // takes its own values back through the map, and a saved record loads.
  stage_profile::StageProfile lab{};
  CHECK(stage_profile::LoadStageProfile(0, &lab) == stage_profile::ProfileError::kOk);
  lab.limits.peak_current_A = 4.5;
  lab.limits.rms_current_A = 3.5;
  lab.axis[0].travel_min = -0.040;
  lab.axis[0].travel_max = 0.040;
  kernel::KernelConfig cfg{};
  CHECK(stage_profile::MakeKernelConfig(lab, &cfg).error == stage_profile::ProfileError::kOk);
  CHECK(FirstRegisterOutOfRange(cfg) == nullptr);
  const ConfigImage image = image_from_kernel(cfg);
  kernel::KernelConfig back = cfg;
  image_to_kernel(image, back);
  CHECK(same_config(cfg, back));
  static kernel::Controller<float> controller;
  LONGS_EQUAL(static_cast<int>(kernel::ConfigError::kOk), static_cast<int>(controller.apply_config(back)));
  {
    persistence::RamFlash f(flash, kSector, 2);
    persistence::ConfigStore store(f, 0, 1);
    store.load();
    CHECK(store.save(image));
    const persistence::LoadResult loaded = persistence::ConfigStore(f, 0, 1).load();
    CHECK_FALSE(loaded.status.flags & kLoadedDefaults);
    CHECK_FALSE(loaded.status.flags & kRefused);
    DOUBLES_EQUAL(4.5, loaded.config.get(RegId::limit_peak_current), 0.0);
    DOUBLES_EQUAL(0.041, loaded.config.get(RegId::limit_x_max), 1e-8);
  }
  // On that stage the seed's 4 A is no ceiling, its own 4.5 A is.
  kernel::KernelConfig over = cfg;
  over.supervisor.peak_current_A = 4.6f;
  LONGS_EQUAL(static_cast<int>(kernel::ConfigError::kBeyondStageLimits), static_cast<int>(controller.apply_config(over)));
  // 3. A profile value the map cannot hold at all is refused when the stage
  // is selected (kRegisterRange), never loaded and lost at the next boot.
  lab.axis[0].max_acceleration = 3.0;  // max_acceleration.x holds up to 2 m/s^2
  CHECK(stage_profile::MakeKernelConfig(lab, &cfg).error == stage_profile::ProfileError::kOk);
  const RegisterDef* d = FirstRegisterOutOfRange(cfg);
  CHECK(d != nullptr);
  STRCMP_EQUAL("max_acceleration.x", d->name);
}

TEST(KernelBinding, SwitchingTheStageWhileOffRestIsRefusedAndChangesNothing) {
  Stage st(flash);
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
  LONGS_EQUAL(static_cast<int>(kernel::CommandResult::kAccepted),
              run_command(st.ctx, maglev::can::HostCommandCode::kHome));
  const kernel::KernelConfig before = st.config();
  EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::stage_profile), 1), 6);  // server busy
  CHECK(same_config(before, st.config()));
  LONGS_EQUAL(0, read_u16(st.ctx, RegId::stage_profile));
}

TEST(KernelBinding, AnInvalidStoredProfileKeepsTheStageLandedWithTheReasonNamed) {
  {
    persistence::RamFlash f(flash, kSector, 2);
    persistence::ConfigStore store(f, 0, 1);
    store.load();
    ConfigImage image = ConfigImage::defaults();
    set_stage_profile(image, 9);  // in the register's range, not in this firmware's database
    CHECK(store.save(image));
  }
  Stage st(flash);
  LONGS_EQUAL(static_cast<int>(stage_profile::ProfileError::kUnknownProfile),
              read_u16(st.ctx, RegId::status_profile_error));
  LONGS_EQUAL(9, read_u16(st.ctx, RegId::stage_profile));  // the stored selection, shown
  {
    std::lock_guard<std::mutex> lock(st.m);
    const io::ActuatorCommand out = st.controller->step(resting_sample(), false);
    CHECK_FALSE(out.amplifier_enable);
  }
  LONGS_EQUAL(static_cast<int>(kernel::FaultCode::kStageProfileInvalid), read_u16(st.ctx, RegId::status_fault));
  // It cannot leave rest, and the fault cannot be cleared while the cause remains.
  CHECK(run_command(st.ctx, maglev::can::HostCommandCode::kHome) != 0);
  CHECK(run_command(st.ctx, maglev::can::HostCommandCode::kClearFault) != 0);
  // Nothing else may be changed until a valid stage is selected.
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
  std::uint16_t w[2];
  set_f32(20000.0f, w);
  EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::gain_x_kp), 2, w), 3);
  // Selecting a valid stage removes the cause; then the fault clears.
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::stage_profile), 0));
  LONGS_EQUAL(0, read_u16(st.ctx, RegId::status_profile_error));
  {
    std::lock_guard<std::mutex> lock(st.m);
    (void)st.controller->step(resting_sample(), false);
  }
  LONGS_EQUAL(static_cast<int>(kernel::CommandResult::kAccepted),
              run_command(st.ctx, maglev::can::HostCommandCode::kClearFault));
  CHECK(same_config(kernel::default_kernel_config(), st.config()));
}

TEST(KernelBinding, ACorruptDatabaseRecordIsRefusedByItsChecksum) {
  // The record as stored, one byte flipped (a flash bit error in the image).
  static std::uint8_t copy[sizeof(stage_profile::StageProfile)];
  std::memcpy(copy, stage_profile::kStageDatabase[0].bytes, sizeof copy);
  stage_profile::StageRecord record = stage_profile::kStageDatabase[0];
  record.bytes = copy;
  static stage_profile::StageProfile out;
  CHECK(stage_profile::LoadStageRecord(record, &out) == stage_profile::ProfileError::kOk);
  copy[100] ^= 0x10;
  CHECK(stage_profile::LoadStageRecord(record, &out) == stage_profile::ProfileError::kChecksum);
}

// --- filter.AXIS.N.*: the kernel's output filters as registers ----------------

namespace {
// type, frequency, q, depth in one 0x10 (7 registers from filter.AX.N.type).
int write_filter(modbus_t* ctx, RegId type_reg, std::uint16_t type, float f_Hz, float q, float depth_dB) {
  std::uint16_t w[7] = {type};
  set_f32(f_Hz, w + 1);
  set_f32(q, w + 3);
  set_f32(depth_dB, w + 5);
  return modbus_write_registers(ctx, addr(type_reg), 7, w);
}
}  // namespace

TEST(KernelBinding, AFilterWrittenOverModbusRunsInTheKernelAndPersists) {
  {
    Stage st(flash);
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
    // A 320 Hz notch, Q 5, 20 dB deep, on x (a structural mode above the 50 Hz crossover).
    LONGS_EQUAL(7, write_filter(st.ctx, RegId::filter_x_1_type, 1, 320.0f, 5.0f, 20.0f));
    const kernel::KernelConfig c = st.config();
    CHECK(c.axis[0].filters[0].type == kernel::BiquadType::kNotch);
    DOUBLES_EQUAL(320.0, static_cast<double>(c.axis[0].filters[0].frequency_Hz), 0.0);
    DOUBLES_EQUAL(5.0, static_cast<double>(c.axis[0].filters[0].q), 0.0);
    DOUBLES_EQUAL(20.0, static_cast<double>(c.axis[0].filters[0].depth_dB), 0.0);
    CHECK(c.axis[0].filters[1].type == kernel::BiquadType::kNone);
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::config_save), 1));
  }
  Stage rebooted(flash);
  const kernel::KernelConfig c = rebooted.config();
  CHECK(c.axis[0].filters[0].type == kernel::BiquadType::kNotch);
  DOUBLES_EQUAL(320.0, static_cast<double>(c.axis[0].filters[0].frequency_Hz), 0.0);
  LONGS_EQUAL(1, read_u16(rebooted.ctx, RegId::filter_x_1_type));
}

TEST(KernelBinding, AFilterThatWouldDestabiliseTheAxisIsRefused) {
  Stage st(flash);
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
  const kernel::KernelConfig before = st.config();
  // A 40 Hz low-pass under x's 50 Hz crossover: the loop check finds it unstable.
  EXPECT_EXCEPTION(write_filter(st.ctx, RegId::filter_x_2_type, 2, 40.0f, 0.7071f, 0.0f), 3);
  CHECK(same_config(before, st.config()));
  {
    std::lock_guard<std::mutex> lock(st.m);
    LONGS_EQUAL(static_cast<int>(kernel::ConfigError::kUnstableLoop),
                static_cast<int>(st.controller->status().last_config_error));
  }
  // A notch above Nyquist (1250 Hz at 2.5 kHz): the filter cannot be designed.
  EXPECT_EXCEPTION(write_filter(st.ctx, RegId::filter_z_1_type, 1, 2000.0f, 2.0f, 20.0f), 3);
  // A type that does not exist: outside the register's range.
  EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::filter_z_1_type), 4), 3);
  CHECK(same_config(before, st.config()));
  // The same low-pass far above the crossover is fine (a 600 Hz noise filter).
  LONGS_EQUAL(7, write_filter(st.ctx, RegId::filter_x_2_type, 2, 600.0f, 0.7071f, 0.0f));
  CHECK(st.config().axis[0].filters[1].type == kernel::BiquadType::kLowPass);
}

// Issue 15 item 5: the coupling calibration over Modbus. cmd.code 17 is refused
// on rest (kernel CommandResult 7, status.calibration 3); the correction the
// kernel holds (written here on rest as the kernel's calibration would write
// it) shows in the coupling.* registers, is persisted by config.save and
// loaded at the next boot; a matrix write the kernel's bound refuses changes
// nothing; coupling.enabled 0 drops it.
TEST(KernelBinding, CouplingCalibrationCommandStatusAndPersistedCorrection) {
  {
    Stage st(flash);
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::cmd_code),
                                         static_cast<std::uint16_t>(can::HostCommandCode::kCalibrateCoupling)));
    std::uint16_t r[2] = {};
    LONGS_EQUAL(1, modbus_read_registers(st.ctx, addr(RegId::cmd_result), 1, r));
    LONGS_EQUAL(static_cast<int>(kernel::CommandResult::kRefusedNotReady), r[0]);
    LONGS_EQUAL(1, modbus_read_registers(st.ctx, addr(RegId::status_calibration), 1, r));
    LONGS_EQUAL(static_cast<int>(kernel::CouplingCalibrationResult::kRefusedNotReady), r[0]);
    LONGS_EQUAL(2, modbus_read_registers(st.ctx, addr(RegId::coupling_y_theta_z), 2, r));
    DOUBLES_EQUAL(0.0, get_f32(r), 0.0);
    {
      std::lock_guard<std::mutex> lock(st.m);
      kernel::KernelConfig c = st.controller->config();
      c.coupling.enabled = 1;
      c.coupling.matrix[1 * 6 + 2] = -0.0125f;  // y effort per theta_z effort
      CHECK(st.controller->apply_config(c) == kernel::ConfigError::kOk);
      c.coupling.matrix[0] = NAN;
      CHECK(st.controller->apply_config(c) == kernel::ConfigError::kCouplingCorrection);
    }
    LONGS_EQUAL(2, modbus_read_registers(st.ctx, addr(RegId::coupling_y_theta_z), 2, r));
    DOUBLES_EQUAL(-0.0125, get_f32(r), 1e-9);
    LONGS_EQUAL(1, modbus_read_registers(st.ctx, addr(RegId::coupling_enabled), 1, r));
    LONGS_EQUAL(1, r[0]);
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
    std::uint16_t w[2];
    // 5 A of theta_z effort per A of y: 72x a force over theta_z's 69 mm
    // radius of gyration, beyond the kernel's bound -- refused, nothing changed.
    set_f32(5.0f, w);
    EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::coupling_theta_z_y), 2, w), 3);
    DOUBLES_EQUAL(0.0, static_cast<double>(st.config().coupling.matrix[2 * 6 + 1]), 0.0);
    // A gain write carries the kernel's correction along (the image was synced).
    set_f32(250.0f, w);
    LONGS_EQUAL(2, modbus_write_registers(st.ctx, addr(RegId::gain_theta_z_kp), 2, w));
    DOUBLES_EQUAL(static_cast<double>(-0.0125f), static_cast<double>(st.config().coupling.matrix[1 * 6 + 2]), 0.0);
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::config_save), 1));
  }
  {
    Stage rebooted(flash);
    const kernel::KernelConfig c = rebooted.config();
    LONGS_EQUAL(1, c.coupling.enabled);
    DOUBLES_EQUAL(static_cast<double>(-0.0125f), static_cast<double>(c.coupling.matrix[1 * 6 + 2]), 0.0);
    DOUBLES_EQUAL(250.0, static_cast<double>(c.axis[2].pid.kp), 0.0);
    LONGS_EQUAL(1, modbus_write_register(rebooted.ctx, addr(RegId::access_key), kEngineerKey));
    LONGS_EQUAL(1, modbus_write_register(rebooted.ctx, addr(RegId::coupling_enabled), 0));
    LONGS_EQUAL(0, rebooted.config().coupling.enabled);
  }
}

// --- servo.rate (issue 16): the servo rate as persisted configuration --------

TEST(KernelBinding, TheServoRateIsPersistedRedesignsTheLoopsAndIsRefusedOffRest) {
  {
    Stage st(flash);
    LONGS_EQUAL(2500, read_u16(st.ctx, RegId::servo_rate));
    // Engineer only.
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::servo_rate), 10000), 1);
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
    // Outside the register's range, and inside it but not an offered rate:
    // ILLEGAL_DATA_VALUE, nothing changed.
    const kernel::KernelConfig before = st.config();
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::servo_rate), 40000), 3);
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::servo_rate), 1000), 3);
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::servo_rate), 3000), 3);
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::servo_rate), 7500), 3);
    CHECK(same_config(before, st.config()));
    LONGS_EQUAL(2500, read_u16(st.ctx, RegId::servo_rate));
    // Landed: 10 kHz, the measurement with it, every loop re-designed from its
    // continuous gains at the new rate; nothing else changed.
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::servo_rate), 10000));
    const kernel::KernelConfig c = st.config();
    DOUBLES_EQUAL(10000.0, static_cast<double>(c.servo_rate_Hz), 0.0);
    DOUBLES_EQUAL(10000.0, static_cast<double>(c.measurement.servo_rate_Hz), 0.0);
    kernel::KernelConfig others = c;
    others.servo_rate_Hz = before.servo_rate_Hz;
    others.measurement.servo_rate_Hz = before.measurement.servo_rate_Hz;
    CHECK(same_config(before, others));
    {
      std::lock_guard<std::mutex> lock(st.m);
      for (int a = 0; a < kernel::kAxisCount; ++a) {
        kernel::Pid2DofCoefficients<float> want{};
        CHECK(kernel::design_pid2dof(c.axis[a].pid, 10000.0, &want) == kernel::LoopDesignError::kOk);
        const kernel::Pid2DofCoefficients<float>& got = st.controller->pid_coefficients(a);
        CHECK(want.kp == got.kp && want.ki_half_T == got.ki_half_T && want.a_d == got.a_d && want.b_d == got.b_d &&
              want.antiwindup == got.antiwindup && want.one_minus_b_kp == got.one_minus_b_kp && want.c == got.c);
      }
    }
    LONGS_EQUAL(10000, read_u16(st.ctx, RegId::servo_rate));
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::config_save), 1));
    // Off rest (homing: the kernel refuses to re-time a stage it is moving):
    // SERVER_DEVICE_BUSY, nothing changed.
    LONGS_EQUAL(static_cast<int>(kernel::CommandResult::kAccepted),
                run_command(st.ctx, maglev::can::HostCommandCode::kHome));
    const kernel::KernelConfig homing = st.config();
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::servo_rate), 20000), 6);
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::servo_rate), 2500), 6);
    CHECK(same_config(homing, st.config()));
    LONGS_EQUAL(10000, read_u16(st.ctx, RegId::servo_rate));
    // A save now stores what runs: the refused rates never reach the flash.
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::config_save), 1));
  }
  // Reboot: the saved 10 kHz, applied before the first tick.
  Stage rebooted(flash);
  const kernel::KernelConfig c = rebooted.config();
  DOUBLES_EQUAL(10000.0, static_cast<double>(c.servo_rate_Hz), 0.0);
  DOUBLES_EQUAL(10000.0, static_cast<double>(c.measurement.servo_rate_Hz), 0.0);
  LONGS_EQUAL(10000, read_u16(rebooted.ctx, RegId::servo_rate));
  std::uint16_t flags = 0;
  LONGS_EQUAL(1, modbus_read_registers(rebooted.ctx, addr(RegId::persist_flags), 1, &flags));
  CHECK((flags & kLoadedDefaults) == 0);  // the record, not the defaults
}

// The derivative corner's register reaches the highest rate's Nyquist; the
// kernel bounds it by the configured rate's, so a rate change that would put
// a corner at or above the new Nyquist is refused too (issue 16).
TEST(KernelBinding, TheDerivativeCornerMayRiseWithTheServoRateAndBoundsItsFall) {
  Stage st(flash);
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
  std::uint16_t w[2];
  set_f32(4000.0f, w);
  const kernel::KernelConfig at_2500 = st.config();
  EXPECT_EXCEPTION(modbus_write_registers(st.ctx, addr(RegId::gain_x_derivative_filter), 2, w), 3);
  CHECK(same_config(at_2500, st.config()));
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::servo_rate), 10000));
  LONGS_EQUAL(2, modbus_write_registers(st.ctx, addr(RegId::gain_x_derivative_filter), 2, w));
  const kernel::KernelConfig c = st.config();
  DOUBLES_EQUAL(4000.0, static_cast<double>(c.axis[0].pid.derivative_filter_hz), 0.0);
  {
    std::lock_guard<std::mutex> lock(st.m);
    kernel::Pid2DofCoefficients<float> want{};
    CHECK(kernel::design_pid2dof(c.axis[0].pid, 10000.0, &want) == kernel::LoopDesignError::kOk);
    const kernel::Pid2DofCoefficients<float>& got = st.controller->pid_coefficients(0);
    CHECK(want.a_d == got.a_d && want.b_d == got.b_d && want.kp == got.kp);
  }
  // Back to 2.5 kHz would leave x's corner above 1250 Hz: 03, nothing changed.
  EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::servo_rate), 2500), 3);
  CHECK(same_config(c, st.config()));
  LONGS_EQUAL(10000, read_u16(st.ctx, RegId::servo_rate));
  std::uint16_t err = 0;
  LONGS_EQUAL(1, modbus_read_registers(st.ctx, addr(RegId::status_config_error), 1, &err));
  CHECK(err != 0);
  // With the corner back below 1250 Hz the rate may fall again.
  set_f32(1000.0f, w);
  LONGS_EQUAL(2, modbus_write_registers(st.ctx, addr(RegId::gain_x_derivative_filter), 2, w));
  LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::servo_rate), 2500));
  CHECK(same_config(at_2500, st.config()));
}

TEST(KernelBinding, TheLdsTargetRepairSwitchIsPersistedAndItsCountIsServed) {
  {
    Stage st(flash);
    // Default on, with the stage's cell (a quarter pitch); nothing repaired yet.
    LONGS_EQUAL(1, read_u16(st.ctx, RegId::lds_target_repair));
    LONGS_EQUAL(1, st.config().measurement.lds_target_repair);
    std::uint16_t n[2] = {0xFFFF, 0xFFFF};
    LONGS_EQUAL(2, modbus_read_registers(st.ctx, addr(RegId::status_lds_target_steps), 2, n));
    LONGS_EQUAL(0, n[0]);
    LONGS_EQUAL(0, n[1]);
    // Engineer only; 0 or 1, anything else ILLEGAL_DATA_VALUE and nothing changed.
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::lds_target_repair), 0), 1);
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
    const kernel::KernelConfig before = st.config();
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::lds_target_repair), 2), 3);
    CHECK(same_config(before, st.config()));
    // Off: the switch reaches the kernel, the stage's cell stays, nothing else changes.
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::lds_target_repair), 0));
    const kernel::KernelConfig c = st.config();
    LONGS_EQUAL(0, c.measurement.lds_target_repair);
    DOUBLES_EQUAL(before.measurement.lds_target_cell_m, c.measurement.lds_target_cell_m, 0.0);
    kernel::KernelConfig others = c;
    others.measurement.lds_target_repair = before.measurement.lds_target_repair;
    CHECK(same_config(before, others));
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::config_save), 1));
    // Off rest: SERVER_DEVICE_BUSY, nothing changed.
    LONGS_EQUAL(static_cast<int>(kernel::CommandResult::kAccepted),
                run_command(st.ctx, maglev::can::HostCommandCode::kHome));
    EXPECT_EXCEPTION(modbus_write_register(st.ctx, addr(RegId::lds_target_repair), 1), 6);
    LONGS_EQUAL(0, read_u16(st.ctx, RegId::lds_target_repair));
  }
  // Reboot: the saved switch, applied before the first tick.
  Stage rebooted(flash);
  LONGS_EQUAL(0, rebooted.config().measurement.lds_target_repair);
  LONGS_EQUAL(0, read_u16(rebooted.ctx, RegId::lds_target_repair));
}

// The repair's threshold and window (F32, um): the kernel's float fields
// exactly, range-checked by the map (03) and by the kernel against the
// stage's block width (03), persisted, landed only (06).
TEST(KernelBinding, TheLdsTargetThresholdAndWindowAreRegistersInMicrometres) {
  const auto read_f32 = [](modbus_t* ctx, RegId id) {
    std::uint16_t w[2] = {0, 0};
    LONGS_EQUAL(2, modbus_read_registers(ctx, addr(id), 2, w));
    return get_f32(w);
  };
  const auto write_f32 = [](modbus_t* ctx, RegId id, float v) {
    std::uint16_t w[2];
    set_f32(v, w);
    return modbus_write_registers(ctx, addr(id), 2, w);
  };
  {
    Stage st(flash);
    // Defaults: 1 um and 1000 um, which the kernel holds as 1e-6 m / 1e-3 m.
    DOUBLES_EQUAL(1.0, read_f32(st.ctx, RegId::lds_target_step_min), 0.0);
    DOUBLES_EQUAL(1000.0, read_f32(st.ctx, RegId::lds_target_window), 0.0);
    DOUBLES_EQUAL(1.0, st.config().measurement.lds_target_step_min_um, 0.0);
    DOUBLES_EQUAL(1000.0, st.config().measurement.lds_target_window_um, 0.0);
    EXPECT_EXCEPTION(write_f32(st.ctx, RegId::lds_target_step_min, 2.0f), 1);  // engineer only
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::access_key), kEngineerKey));
    const kernel::KernelConfig before = st.config();
    // Out of the register range, NaN, and a window past half the stage's
    // block width (the kernel's check): refused, nothing changed.
    EXPECT_EXCEPTION(write_f32(st.ctx, RegId::lds_target_step_min, 0.05f), 3);
    EXPECT_EXCEPTION(write_f32(st.ctx, RegId::lds_target_step_min, std::nanf("")), 3);
    EXPECT_EXCEPTION(write_f32(st.ctx, RegId::lds_target_window, 30000.0f), 3);
    const float half_block_um = static_cast<float>(before.measurement.lds_target_cell_m / 2 * 1e6);
    CHECK(half_block_um < 25000.0f);
    EXPECT_EXCEPTION(write_f32(st.ctx, RegId::lds_target_window, half_block_um), 3);
    CHECK(same_config(before, st.config()));
    // Accepted values reach the kernel exactly; nothing else changes.
    LONGS_EQUAL(2, write_f32(st.ctx, RegId::lds_target_step_min, 2.5f));
    LONGS_EQUAL(2, write_f32(st.ctx, RegId::lds_target_window, 750.0f));
    const kernel::KernelConfig c = st.config();
    DOUBLES_EQUAL(2.5, c.measurement.lds_target_step_min_um, 0.0);
    DOUBLES_EQUAL(750.0, c.measurement.lds_target_window_um, 0.0);
    kernel::KernelConfig others = c;
    others.measurement.lds_target_step_min_um = before.measurement.lds_target_step_min_um;
    others.measurement.lds_target_window_um = before.measurement.lds_target_window_um;
    CHECK(same_config(before, others));
    LONGS_EQUAL(1, modbus_write_register(st.ctx, addr(RegId::config_save), 1));
    // Off rest: SERVER_DEVICE_BUSY, nothing changed.
    LONGS_EQUAL(static_cast<int>(kernel::CommandResult::kAccepted),
                run_command(st.ctx, maglev::can::HostCommandCode::kHome));
    EXPECT_EXCEPTION(write_f32(st.ctx, RegId::lds_target_window, 900.0f), 6);
    DOUBLES_EQUAL(750.0, read_f32(st.ctx, RegId::lds_target_window), 0.0);
  }
  // Reboot: the saved values, exactly.
  Stage rebooted(flash);
  DOUBLES_EQUAL(2.5, rebooted.config().measurement.lds_target_step_min_um, 0.0);
  DOUBLES_EQUAL(750.0, rebooted.config().measurement.lds_target_window_um, 0.0);
}
