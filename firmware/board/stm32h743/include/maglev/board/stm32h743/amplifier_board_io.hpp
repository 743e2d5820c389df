// The board's implementation of the app::SensorSource / app::ActuatorSink
// seam: AD7606 pair + three quadrature counters in, AD5764 chain + the
// amplifier-enable line out. The HIL build swaps exactly these two objects
// for CAN-frame versions; nothing else in the image changes.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/app/board_io.hpp"
#include "maglev/drivers/ad5764.hpp"
#include "maglev/drivers/ad7606.hpp"
#include "maglev/drivers/amplifier_enable.hpp"

namespace maglev::board::stm32h743 {

// The amplifier board's ADC wiring (drivers/ad7606_adc README): ADC0 V1-V3
// the laser displacement sensors, V4-V7 the Hall channels; ADC1 V1-V8 the
// coil current monitors. The driver knows codes; the board knows what they mean.
// code(d, k): ADC d's channel k (0-based), from decoded codes or raw words.
template <typename CodeOf>
inline void map_codes_to_sample(const CodeOf& code, io::SensorSample& sample) {
  // Unrolled: every channel index a constant, so a raw word's half is one
  // shift or one extension.
#pragma GCC unroll 8
  for (std::size_t i = 0; i < static_cast<std::size_t>(io::kDisplacementSensors); ++i) sample.displacement_adc[i] = code(0, i);
#pragma GCC unroll 8
  for (std::size_t i = 0; i < static_cast<std::size_t>(io::kHallChannels); ++i) sample.hall_adc[i] = code(0, 3 + i);
#pragma GCC unroll 8
  for (std::size_t i = 0; i < static_cast<std::size_t>(io::kCoils); ++i) sample.coil_current_adc[i] = code(1, i);
}
inline void map_to_sample(const drivers::ad7606::Codes& codes, io::SensorSample& sample) {
  map_codes_to_sample([&codes](std::size_t d, std::size_t k) { return codes.channel[d][k]; }, sample);
}

// Adc: ad7606::Adc (polled read in the tick) or ad7606::Stm32DmaReader (the pair
// read by DMA before the tick; read() takes the completed buffer).
template <typename Encoder, typename Adc = drivers::ad7606::Adc>
class AmplifierBoardSensors final : public app::SensorSource {
 public:
  AmplifierBoardSensors(Adc& adc, Encoder& enc0, Encoder& enc1, Encoder& enc2)
      : adc_(adc), encoders_{&enc0, &enc1, &enc2} {}

  bool read(io::SensorSample& s) override {
    std::uint16_t flags = 0;
    for (std::size_t i = 0; i < static_cast<std::size_t>(io::kInterferometerAxes); ++i) {
      s.interferometer_counts[i] = encoders_[i]->update();
      if (encoders_[i]->signal_lost()) flags = static_cast<std::uint16_t>(flags | (io::kBeamLoss0 << i));
    }
    const bool adc_ok = read_adc(s);
    if (adc_ok) {
      // A laser sensor with no target rails its output: treat full scale as out of range.
      for (std::size_t i = 0; i < static_cast<std::size_t>(io::kDisplacementSensors); ++i) {
        if (s.displacement_adc[i] == INT16_MAX || s.displacement_adc[i] == INT16_MIN) {
          flags = static_cast<std::uint16_t>(flags | (io::kDisplacementOutOfRange0 << i));
        }
      }
    } else {
      flags = static_cast<std::uint16_t>(flags | io::kAdcFault);
    }
    s.status_flags = flags;
    return adc_ok;
  }

 private:
  // The pair's channels into the sample. A reader that hands out its raw
  // words (Stm32DmaReader::read_raw) is mapped straight from them: the
  // channels the board uses, each decoded once, with no Codes copy between.
  bool read_adc(io::SensorSample& s) {
    using drivers::ad7606::Status;
    if constexpr (requires { adc_.read_raw(); }) {
      if (adc_.read_raw() != Status::kOk) return false;
      const auto& rx = adc_.words();
      map_codes_to_sample([&rx](std::size_t d, std::size_t k) { return drivers::ad7606::channel_code(rx[d], k); }, s);
      return true;
    } else {
      drivers::ad7606::Codes codes;  // read() fills it whenever it says kOk; unused otherwise
      if (adc_.read(codes) != Status::kOk) return false;
      map_to_sample(codes, s);
      return true;
    }
  }

  Adc& adc_;
  Encoder* encoders_[3];
};

class AmplifierBoardActuators final : public app::ActuatorSink {
 public:
  AmplifierBoardActuators(drivers::ad5764::Chain<2>& dac, drivers::AmplifierEnable& enable)
      : dac_(dac), enable_(enable) {}

  // Disable before changing currents when switching off; load currents
  // before enabling when switching on. A DAC link we cannot trust trips the
  // (latched) amplifier enable.
  void write(const io::ActuatorCommand& c) override {
    if (!c.amplifier_enable) enable_.request(false);
    const auto status = dac_.write_codes(c.dac_code);
    if (status != drivers::ad5764::Status::kOk) {
      enable_.trip();
      return;
    }
    if (c.amplifier_enable) enable_.request(true);
  }
  // Missed deadline (SysTick, below the tick): the enable line low, one BSRR
  // store; no DAC frame a resuming tick could interleave with. Not latched:
  // a resumed tick's command enables again, as after write(kSafe...).
  void force_safe() override { enable_.request(false); }

 private:
  drivers::ad5764::Chain<2>& dac_;
  drivers::AmplifierEnable& enable_;
};

// The production board's sink: the same rules as AmplifierBoardActuators,
// with the DAC chain written from SPI1's end-of-transfer interrupt
// (DacWriter: ad5764::Stm32IrqWriter), so the rules split where the write
// now ends.
// Switching off: disable before the first frame (write(), in the tick).
// Switching on: request the enable only when the fourth frame's LDAC pulse
// has put the currents out with every echo matching (on_dac_irq()). A write
// that cannot start (the previous one never finished), fails, or whose link
// cannot be trusted trips the (latched) amplifier enable.
template <typename DacWriter>
class AmplifierBoardIrqActuators final : public app::ActuatorSink {
 public:
  AmplifierBoardIrqActuators(DacWriter& dac, drivers::AmplifierEnable& enable)
      : dac_(dac), enable_(enable) {}

  void write(const io::ActuatorCommand& c) override {
    if (!c.amplifier_enable) enable_.request(false);
    enable_when_written_ = c.amplifier_enable;
    if (dac_.begin(c.dac_code) != drivers::ad5764::Status::kOk) {
      enable_when_written_ = false;
      enable_.trip();
    }
  }

  // Missed deadline (SysTick, below the tick and SPI1): the enable line low,
  // one BSRR store, and no enable when a write still running completes.
  // No DAC frame: a resuming tick's begin() would find it half-started and
  // abandon it with a (latched) trip. Not latched itself: a resumed tick's
  // command enables again after its LDAC, as after write(kSafe...).
  void force_safe() override {
    enable_when_written_ = false;
    enable_.request(false);
  }

  // SPI1's interrupt. True when the write has finished (either way).
  bool on_dac_irq() {
    using Step = typename DacWriter::Step;
    const Step step = dac_.advance();
    if (step == Step::kComplete) {
      if (dac_.result() != drivers::ad5764::Status::kOk) {
        enable_.trip();
      } else if (enable_when_written_) {
        enable_.request(true);
      }
      return true;
    }
    if (step == Step::kError) {
      enable_.trip();
      return true;
    }
    return false;
  }

 private:
  DacWriter& dac_;
  drivers::AmplifierEnable& enable_;
  bool enable_when_written_ = false;
};

}  // namespace maglev::board::stm32h743
