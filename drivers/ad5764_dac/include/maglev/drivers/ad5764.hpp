// AD5764 quad 16-bit +-10 V DAC, two devices daisy-chained on one SPI bus:
// the eight coil-current commands (io::ActuatorCommand::dac_code).
//
// Datasheet facts this driver encodes (AD5764 Rev. D, "Serial interface",
// "Input shift register", "Daisy-chaining", register tables):
//   * The input shift register is 24 bits: DB23 = R/W (1 = read), DB22 = 0,
//     DB21..DB19 = REG2..REG0, DB18..DB16 = A2..A0, DB15..DB0 = data, MSB first,
//     latched on the SYNC rising edge (after the last SCLK falling edge).
//   * REG2..0: 000 function register, 010 data, 011 coarse gain,
//     100 fine gain, 101 offset. A2..0: 000..011 = DAC A..D, 100 = all DACs.
//     Function register addresses: 000 NOP, 001 config (SDO disable bit),
//     100 clear, 101 load.
//   * With BIN/2sCOMP hard-wired low the data register takes two's complement:
//     0x8000 = -10 V, 0x0000 = 0 V, 0x7FFF = +10 V * 32767/32768.
//   * Daisy chain: SDO of the first device drives SDIN of the next. Bits
//     enter the first device and ripple onward, so in each 48-bit SYNC frame
//     the word for the LAST device in the chain is shifted FIRST. The SDO of
//     the last device returns, during frame k+1, the 48 bits of frame k --
//     the driver uses that echo as a free link check.
//   * LDAC held high: writes only load the input registers; a low pulse on
//     LDAC updates all DAC registers of both devices at once, so the eight
//     coil currents change in the same instant every servo tick.
//
// Coil j (0-based) is device j / 4, channel j % 4 (DAC A..D). Device 0 is the
// first in the chain (nearest the MCU's MOSI).
//
// Chain writes it polled, through any SpiMaster (the board zeroes the
// outputs with it at boot). The production board's servo tick writes the same
// words, frame order, LDAC rule and link check from SPI1's end-of-transfer
// interrupt with ad5764::Stm32IrqWriter (ad5764_stm32_irq.hpp), at the
// register level.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/drivers/bus.hpp"

namespace maglev::drivers::ad5764 {

enum class Register : std::uint8_t {
  kFunction = 0b000,
  kData = 0b010,
  kCoarseGain = 0b011,
  kFineGain = 0b100,
  kOffset = 0b101,
};
inline constexpr std::uint8_t kAddressDacA = 0b000;
inline constexpr std::uint8_t kAddressAllDacs = 0b100;
inline constexpr std::uint8_t kFunctionNop = 0b000;
inline constexpr std::uint8_t kFunctionConfig = 0b001;
inline constexpr std::uint8_t kFunctionClear = 0b100;
inline constexpr std::uint8_t kFunctionLoad = 0b101;
inline constexpr std::size_t kChannelsPerDevice = 4;
inline constexpr std::uint8_t kWordBits = 24;

constexpr std::uint32_t command_word(bool read, Register reg, std::uint8_t address, std::uint16_t data) {
  return (read ? (1u << 23) : 0u) | (static_cast<std::uint32_t>(reg) << 19) |
         (static_cast<std::uint32_t>(address & 0x7u) << 16) | data;
}
constexpr std::uint32_t data_word(std::uint8_t channel, std::int16_t code) {
  return command_word(false, Register::kData, channel, static_cast<std::uint16_t>(code));
}

enum class Status : std::uint8_t { kOk = 0, kBusError, kLinkMismatch };

struct State {
  std::uint32_t writes = 0;
  std::uint32_t bus_errors = 0;
  std::uint32_t link_mismatches = 0;  // SDO echo differed from what we sent
};

template <std::size_t kDevices = 2>
class Chain {
 public:
  static constexpr std::size_t kChannels = kDevices * kChannelsPerDevice;

  // `device` is the SPI master's chip-select index for SYNC; `ldac` is the
  // (active-low) LDAC line, idled high.
  Chain(SpiMaster& spi, std::uint8_t device, OutputPin& ldac) : spi_(spi), device_(device), ldac_(ldac) {}

  void init() {
    ldac_.write(true);
    have_previous_ = false;
  }

  // One 48-bit (kDevices x 24) SYNC frame: words[d] is for device d; the
  // last device's word goes out first.
  Status write_frame(const std::uint32_t (&words)[kDevices]) {
    std::uint32_t tx[kDevices];
    std::uint32_t rx[kDevices];
    for (std::size_t d = 0; d < kDevices; ++d) tx[d] = words[kDevices - 1 - d];
    const BusStatus bs = spi_.transfer(SpiTransfer{device_, kWordBits, tx, rx, kDevices});
    if (bs != BusStatus::kOk) {
      ++state_.bus_errors;
      have_previous_ = false;
      return Status::kBusError;
    }
    Status status = Status::kOk;
    if (have_previous_) {
      for (std::size_t d = 0; d < kDevices; ++d) {
        if (rx[d] != previous_[d]) status = Status::kLinkMismatch;
      }
      if (status != Status::kOk) ++state_.link_mismatches;
    }
    for (std::size_t d = 0; d < kDevices; ++d) previous_[d] = tx[d];
    have_previous_ = true;
    return status;
  }

  // Load all eight codes into the input registers (four frames, channel A..D),
  // then pulse LDAC so every output changes together.
  Status write_codes(const std::int16_t (&codes)[kChannels]) {
    Status result = Status::kOk;
    for (std::size_t ch = 0; ch < kChannelsPerDevice; ++ch) {
      std::uint32_t words[kDevices];
      for (std::size_t d = 0; d < kDevices; ++d) {
        words[d] = data_word(static_cast<std::uint8_t>(ch), codes[d * kChannelsPerDevice + ch]);
      }
      const Status s = write_frame(words);
      if (s == Status::kBusError) return s;  // never pulse LDAC on a partial update
      if (s != Status::kOk) result = s;
    }
    ldac_.write(false);
    ldac_.write(true);
    ++state_.writes;
    return result;
  }

  Status write_zero() {
    const std::int16_t zero[kChannels]{};
    return write_codes(zero);
  }

  const State& state() const { return state_; }

 private:
  SpiMaster& spi_;
  std::uint8_t device_;
  OutputPin& ldac_;
  State state_{};
  std::uint32_t previous_[kDevices]{};
  bool have_previous_ = false;
};

}  // namespace maglev::drivers::ad5764
