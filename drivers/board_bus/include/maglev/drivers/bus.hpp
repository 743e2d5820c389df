// The small abstract buses the amplifier-board part drivers (AD5764, AD7606,
// amplifier enable, signal-loss lines) talk through. The STM32 implementations
// live in drivers/stm32h7_spi_gpio; heap-free fakes for host tests live in
// fake_bus.hpp. Destructors are protected and non-virtual (no deleting
// destructor, so no operator delete in a target image).
#pragma once

#include <cstddef>
#include <cstdint>

namespace maglev::drivers {

// One chip-select-framed SPI transaction. Words are `word_bits` wide (4..32),
// right-aligned in a uint32_t, shifted MSB first. Chip select (the AD5764's
// SYNC, the AD7606's CS) is asserted for the whole transaction and released
// after the last word: one transaction = one SYNC/CS frame.
struct SpiTransfer {
  std::uint8_t device;     // index into the SPI master's chip-select table
  std::uint8_t word_bits;  // 4..32
  const std::uint32_t* tx; // nullptr: send zeros
  std::uint32_t* rx;       // nullptr: discard
  std::size_t words;
};

// Pinned values (diagnostics).
enum class BusStatus : std::uint8_t {
  kOk = 0,
  kTimeout = 1,
  kBadArgument = 2,
};

class SpiMaster {
 public:
  virtual BusStatus transfer(const SpiTransfer& t) = 0;

 protected:
  SpiMaster() = default;
  ~SpiMaster() = default;
  SpiMaster(const SpiMaster&) = default;
  SpiMaster& operator=(const SpiMaster&) = default;
};

class OutputPin {
 public:
  virtual void write(bool high) = 0;

 protected:
  OutputPin() = default;
  ~OutputPin() = default;
  OutputPin(const OutputPin&) = default;
  OutputPin& operator=(const OutputPin&) = default;
};

class InputPin {
 public:
  virtual bool read() = 0;

 protected:
  InputPin() = default;
  ~InputPin() = default;
  InputPin(const InputPin&) = default;
  InputPin& operator=(const InputPin&) = default;
};

}  // namespace maglev::drivers
