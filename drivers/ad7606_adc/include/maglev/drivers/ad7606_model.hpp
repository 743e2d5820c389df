// AD7606 serial-interface model for host tests: on each CS frame it clocks
// V1..V8 (two's complement, MSB first) out of DOUTA. Heap-free.
#pragma once

#include <cstdint>

#include "maglev/drivers/ad7606.hpp"
#include "maglev/drivers/fake_bus.hpp"

namespace maglev::drivers::ad7606 {

class DeviceModel final : public SpiPeripheralModel {
 public:
  void set_input_V(std::size_t channel, double volts) {
    double code = volts / 10.0 * 32768.0;
    code = code > 32767.0 ? 32767.0 : (code < -32768.0 ? -32768.0 : code);
    codes_[channel] = static_cast<std::int16_t>(code < 0 ? code - 0.5 : code + 0.5);
  }
  void set_code(std::size_t channel, std::int16_t code) { codes_[channel] = code; }
  std::uint32_t clock_word(std::uint32_t /*mosi*/, std::uint8_t word_bits) override {
    std::uint32_t miso = 0;
    for (unsigned b = 0; b < word_bits; ++b) {
      const std::size_t ch = bit_ / 16;
      const std::size_t pos = 15 - bit_ % 16;
      const std::uint32_t v =
          ch < kChannelsPerDevice ? (static_cast<std::uint32_t>(static_cast<std::uint16_t>(codes_[ch])) >> pos) & 1u : 0u;
      miso = (miso << 1) | v;
      ++bit_;
    }
    return miso;
  }
  void chip_select_released() override {
    last_frame_bits_ = bit_;
    bit_ = 0;
  }
  std::size_t last_frame_bits() const { return last_frame_bits_; }

 private:
  std::int16_t codes_[kChannelsPerDevice]{};
  std::size_t bit_ = 0;
  std::size_t last_frame_bits_ = 0;
};

}  // namespace maglev::drivers::ad7606
