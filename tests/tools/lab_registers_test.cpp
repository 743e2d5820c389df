// The rec.* / wave.* registers through the RegisterServer (the map's one
// PDU path, as RTU and TCP use it) over LabRegisters, the recorder, the wave
// generator and the real kernel (landed): configuration refusals with 03/06
// and nothing changed, arming, the 0x17 download of a finished capture, and
// 02 for the lab registers of a server without lab tools.
#include <cstring>
#include <memory>

#include "maglev/lab_tools/lab_registers.hpp"
#include "maglev/modbus/controller_binding.hpp"

#include <CppUTest/TestHarness.h>

using namespace maglev;
using namespace maglev::modbus;

namespace {

float g_pool[lab::kBoardPoolWords];
float g_table[lab::kWaveTableLen];

struct Bench {
  std::unique_ptr<kernel::Controller<float>> controller = std::make_unique<kernel::Controller<float>>();
  ControllerDevice<float> device{*controller, nullptr};
  RegisterServer server{device, device.boot()};
  lab::Recorder recorder{g_pool, lab::kBoardPoolWords};
  lab::WaveGenerator wave{g_table, lab::kWaveTableLen};
  lab::LabRegisters lab{recorder, wave, controller->config()};
  Bench() {
    (void)recorder.configure(lab::fault_watch_config(2500.0f));
    (void)recorder.arm();
    server.set_lab_tools(&lab);
  }
  double get(RegId id) {
    std::uint16_t w[2] = {};
    CHECK(server.read_registers(def(id).address, width(def(id).type), w) == ExceptionCode::kNone);
    return decode(def(id).type, width(def(id).type) == 1 ? w[0] : join_words(w));
  }
  ExceptionCode set(RegId id, double v) {
    std::uint16_t w[2];
    const std::uint32_t raw = encode(def(id).type, v);
    if (width(def(id).type) == 1) {
      w[0] = static_cast<std::uint16_t>(raw);
    } else {
      split_words(raw, w);
    }
    return server.write_registers(def(id).address, width(def(id).type), w);
  }
};

}  // namespace

TEST_GROUP(LabRegisters) {
  std::unique_ptr<Bench> b;
  void setup() override { b = std::make_unique<Bench>(); }
};

TEST(LabRegisters, BootsArmedInFaultWatch) {
  DOUBLES_EQUAL(1, b->get(RegId::rec_state), 0);
  DOUBLES_EQUAL(3, b->get(RegId::rec_trigger_mode), 0);
  DOUBLES_EQUAL(16384, b->get(RegId::rec_capacity), 0);
  DOUBLES_EQUAL(2500, b->get(RegId::rec_sample_rate), 1e-3);
  DOUBLES_EQUAL(0.5, b->get(RegId::wave_limit), 1e-7);
}

TEST(LabRegisters, ConfigurationWhileArmedIsBusyAndBadOnesAreRefusedWhole) {
  CHECK(b->set(RegId::rec_length, 100) == ExceptionCode::kServerDeviceBusy);
  CHECK(b->set(RegId::rec_control, lab::kRecStop) == ExceptionCode::kNone);
  DOUBLES_EQUAL(0, b->get(RegId::rec_state), 0);
  // One request: 2 channels, channel 1 unknown (0) -> 03, nothing changed.
  std::uint16_t w[3] = {2, 1, 0};
  CHECK(b->server.write_registers(def(RegId::rec_channel_count).address, 3, w) == ExceptionCode::kIllegalDataValue);
  DOUBLES_EQUAL(8, b->get(RegId::rec_channel_count), 0);
  DOUBLES_EQUAL(7, b->get(RegId::rec_channel_1), 0);
  DOUBLES_EQUAL(static_cast<int>(lab::RecorderError::kUnknownSignal), b->get(RegId::rec_error), 0);
  // Too many channels: the map's range (1..8) -> 03.
  CHECK(b->set(RegId::rec_channel_count, 9) == ExceptionCode::kIllegalDataValue);
  // Longer than the memory holds for 8 channels -> 03.
  CHECK(b->set(RegId::rec_length, 16385) == ExceptionCode::kIllegalDataValue);
  DOUBLES_EQUAL(5000, b->get(RegId::rec_length), 0);
  // With one channel it fits.
  std::uint16_t one[1] = {1};
  CHECK(b->server.write_registers(def(RegId::rec_channel_count).address, 1, one) == ExceptionCode::kNone);
  DOUBLES_EQUAL(131072, b->get(RegId::rec_capacity), 0);
  CHECK(b->set(RegId::rec_length, 16385) == ExceptionCode::kNone);
  // A command trigger while not armed: 06.
  CHECK(b->set(RegId::rec_control, lab::kRecTrigger) == ExceptionCode::kServerDeviceBusy);
}

TEST(LabRegisters, DownloadOfAFinishedCaptureBy0x17) {
  CHECK(b->set(RegId::rec_control, lab::kRecStop) == ExceptionCode::kNone);
  // rec.data before a capture: 06.
  std::uint16_t words[kBlockWords];
  CHECK(b->server.read_registers(def(RegId::rec_data).address, kBlockWords, words) == ExceptionCode::kServerDeviceBusy);
  // ... so a 0x17 that reads it is refused before its write: cmd.code = 1
  // (home) is not executed (it used to be, and the reply said 06).
  {
    const std::uint16_t ra = def(RegId::rec_data).address, wa = def(RegId::cmd_code).address;
    const std::uint8_t req[12] = {0x17, static_cast<std::uint8_t>(ra >> 8), static_cast<std::uint8_t>(ra & 0xFF), 0, 2,
                                  static_cast<std::uint8_t>(wa >> 8), static_cast<std::uint8_t>(wa & 0xFF), 0, 1, 2, 0, 1};
    std::uint8_t resp[kMaxPdu];
    const std::size_t n = b->server.handle_pdu(req, sizeof req, resp, false);
    CHECK_EQUAL(2u, n);
    CHECK_EQUAL(0x97, resp[0]);
    CHECK_EQUAL(static_cast<int>(ExceptionCode::kServerDeviceBusy), resp[1]);
    CHECK(b->controller->status().state == kernel::SequencerState::kIdle);
  }
  // 2 channels (x.pose, x.error), 100 samples, immediate, armed in the same request.
  std::uint16_t cfg15[16] = {};
  CHECK(b->server.read_registers(def(RegId::rec_control).address, 16, cfg15) == ExceptionCode::kNone);
  cfg15[0] = lab::kRecArm;
  cfg15[1] = 2;
  split_words(100, cfg15 + 11);
  split_words(0, cfg15 + 13);
  cfg15[15] = static_cast<std::uint16_t>(lab::TriggerMode::kImmediate);
  // A range that cuts rec.pretrigger (I32) in half: 02, nothing armed.
  CHECK(b->server.write_registers(def(RegId::rec_control).address, 14, cfg15) == ExceptionCode::kIllegalDataAddress);
  DOUBLES_EQUAL(0, b->get(RegId::rec_state), 0);
  CHECK(b->server.write_registers(def(RegId::rec_control).address, 16, cfg15) == ExceptionCode::kNone);
  DOUBLES_EQUAL(1, b->get(RegId::rec_state), 0);
  for (int n = 0; n < 150; ++n) {
    kernel::ControllerStatus st{};
    st.pose.pico[0] = static_cast<std::int64_t>(n) * 1000000;
    b->recorder.sample(st, io::SensorSample{});
  }
  DOUBLES_EQUAL(3, b->get(RegId::rec_state), 0);
  DOUBLES_EQUAL(100, b->get(RegId::rec_captured), 0);
  // 0x17: rec.read_offset = 62 (sample 31), read the window.
  std::uint8_t req[14] = {0x17, 0, 0, 0, 0, 0, 0, 0, 2, 4, 0, 0, 0, 62};
  const std::uint16_t ra = def(RegId::rec_data).address, wa = def(RegId::rec_read_offset).address;
  req[1] = static_cast<std::uint8_t>(ra >> 8);
  req[2] = static_cast<std::uint8_t>(ra & 0xFF);
  req[4] = kBlockWords;
  req[5] = static_cast<std::uint8_t>(wa >> 8);
  req[6] = static_cast<std::uint8_t>(wa & 0xFF);
  std::uint8_t resp[kMaxPdu];
  const std::size_t n = b->server.handle_pdu(req, sizeof req, resp, false);
  CHECK_EQUAL(2u + 2u * kBlockWords, n);
  for (int i = 0; i < kBlockWords / 2; ++i) {
    const std::uint16_t hw[2] = {static_cast<std::uint16_t>((resp[2 + 4 * i] << 8) | resp[3 + 4 * i]),
                                 static_cast<std::uint16_t>((resp[4 + 4 * i] << 8) | resp[5 + 4 * i])};
    const float v = static_cast<float>(decode(RegType::kF32, join_words(hw)));
    const std::uint32_t k = 62u + static_cast<std::uint32_t>(i);
    DOUBLES_EQUAL(b->recorder.at(k), v, 0.0);
    if (k % 2 == 0) DOUBLES_EQUAL(static_cast<double>(k / 2) * 1e-6, v, 1e-7 * static_cast<double>(k / 2) * 1e-6);
  }
  // Past the end: zeros.
  CHECK(b->set(RegId::rec_read_offset, 190) == ExceptionCode::kNone);
  CHECK(b->server.read_registers(def(RegId::rec_data).address, kBlockWords, words) == ExceptionCode::kNone);
  CHECK_EQUAL(0, words[20]);
}

TEST(LabRegisters, WaveStartRefusedAboveTheLimitAndPastNyquist) {
  CHECK(b->set(RegId::wave_amplitude, 0.6) == ExceptionCode::kNone);  // held, checked at start
  CHECK(b->set(RegId::wave_control, lab::kWaveStart) == ExceptionCode::kIllegalDataValue);
  DOUBLES_EQUAL(static_cast<int>(lab::WaveError::kAmplitude), b->get(RegId::wave_error), 0);
  DOUBLES_EQUAL(0, b->get(RegId::wave_state), 0);
  CHECK(b->set(RegId::wave_amplitude, 0.4) == ExceptionCode::kNone);
  CHECK(b->set(RegId::wave_shape, 1) == ExceptionCode::kNone);
  CHECK(b->set(RegId::wave_duration, 2) == ExceptionCode::kNone);
  CHECK(b->set(RegId::wave_f_end, 1250) == ExceptionCode::kNone);
  CHECK(b->set(RegId::wave_control, lab::kWaveStart) == ExceptionCode::kIllegalDataValue);
  DOUBLES_EQUAL(static_cast<int>(lab::WaveError::kNyquist), b->get(RegId::wave_error), 0);
  CHECK(b->set(RegId::wave_f_end, 200) == ExceptionCode::kNone);
  CHECK(b->set(RegId::wave_control, lab::kWaveStart) == ExceptionCode::kNone);
  DOUBLES_EQUAL(1, b->get(RegId::wave_state), 0);
  // Running: configuration busy; stop.
  CHECK(b->set(RegId::wave_amplitude, 0.1) == ExceptionCode::kServerDeviceBusy);
  CHECK(b->set(RegId::wave_control, lab::kWaveStop) == ExceptionCode::kNone);
  DOUBLES_EQUAL(0, b->get(RegId::wave_state), 0);
  // The reference limit of z (max step 10 um).
  std::uint16_t ap[2] = {3, 1};
  CHECK(b->server.write_registers(def(RegId::wave_axis).address, 2, ap) == ExceptionCode::kNone);
  DOUBLES_EQUAL(10e-6, b->get(RegId::wave_limit), 1e-12);
}

TEST(LabRegisters, WithoutLabToolsTheRegistersAnswer02) {
  auto ctl = std::make_unique<kernel::Controller<float>>();
  ControllerDevice<float> device{*ctl, nullptr};
  RegisterServer server{device, device.boot()};
  std::uint16_t w[2] = {};
  CHECK(server.read_registers(def(RegId::rec_state).address, 1, w) == ExceptionCode::kIllegalDataAddress);
  w[0] = 1;
  CHECK(server.write_registers(def(RegId::wave_control).address, 1, w) == ExceptionCode::kIllegalDataAddress);
  CHECK(server.read_registers(def(RegId::id_magic).address, 1, w) == ExceptionCode::kNone);
}
