// Bit-level model of a chain of AD5764s for host tests: each device is a
// 24-bit shift register whose MSB spills into the next device's SDIN; on the
// SYNC rising edge every device decodes its own word (R/W, REG2..0, A2..0,
// data) into its input registers; an LDAC falling edge copies input ->
// DAC registers. Heap-free.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/drivers/ad5764.hpp"
#include "maglev/drivers/fake_bus.hpp"

namespace maglev::drivers::ad5764 {

template <std::size_t kDevices = 2>
class ChainModel final : public SpiPeripheralModel {
 public:
  std::uint32_t clock_word(std::uint32_t mosi, std::uint8_t word_bits) override {
    std::uint32_t miso = 0;
    for (int b = word_bits - 1; b >= 0; --b) {
      std::uint32_t in = (mosi >> b) & 1u;
      // The last device's SDO is the MCU's MISO.
      const std::uint32_t out = (shift_[kDevices - 1] >> 23) & 1u;
      for (std::size_t d = 0; d < kDevices; ++d) {
        const std::uint32_t spill = (shift_[d] >> 23) & 1u;
        shift_[d] = ((shift_[d] << 1) | in) & 0xFFFFFFu;
        in = spill;
      }
      miso = (miso << 1) | out;
      ++bits_;
    }
    return miso;
  }
  void chip_select_released() override {
    ++frames_;
    if (bits_ % 24 != 0) ++malformed_frames_;  // SYNC raised early: the part ignores the frame
    else {
      for (std::size_t d = 0; d < kDevices; ++d) decode(d, shift_[d]);
    }
    bits_ = 0;
  }
  void ldac_edge(bool high) {
    if (!high) {
      for (std::size_t d = 0; d < kDevices; ++d)
        for (std::size_t c = 0; c < kChannelsPerDevice; ++c) dac_[d][c] = input_[d][c];
      ++ldac_pulses_;
    }
  }
  static void ldac_hook(void* self, bool high) { static_cast<ChainModel*>(self)->ldac_edge(high); }

  std::int16_t input_register(std::size_t device, std::size_t channel) const { return input_[device][channel]; }
  std::int16_t dac_register(std::size_t device, std::size_t channel) const { return dac_[device][channel]; }
  std::uint32_t shift_register(std::size_t device) const { return shift_[device]; }
  int frames() const { return frames_; }
  int malformed_frames() const { return malformed_frames_; }
  int ldac_pulses() const { return ldac_pulses_; }
  int non_data_writes() const { return non_data_writes_; }
  // Output voltage of a DAC register in two's complement coding, +-10 V span.
  double output_V(std::size_t device, std::size_t channel) const { return 10.0 * dac_[device][channel] / 32768.0; }

 private:
  void decode(std::size_t d, std::uint32_t word) {
    const bool read = (word >> 23) & 1u;
    const auto reg = static_cast<Register>((word >> 19) & 0x7u);
    const std::uint32_t address = (word >> 16) & 0x7u;
    const auto data = static_cast<std::int16_t>(static_cast<std::uint16_t>(word & 0xFFFFu));
    if (read || (word >> 22) & 1u) {
      ++non_data_writes_;
      return;
    }
    if (reg == Register::kData) {
      if (address == kAddressAllDacs) {
        for (std::size_t c = 0; c < kChannelsPerDevice; ++c) input_[d][c] = data;
      } else if (address < 4) {
        input_[d][address] = data;
      }
    } else {
      ++non_data_writes_;
    }
  }

  std::uint32_t shift_[kDevices]{};
  std::int16_t input_[kDevices][kChannelsPerDevice]{};
  std::int16_t dac_[kDevices][kChannelsPerDevice]{};
  int bits_ = 0;
  int frames_ = 0;
  int malformed_frames_ = 0;
  int ldac_pulses_ = 0;
  int non_data_writes_ = 0;
};

}  // namespace maglev::drivers::ad5764
