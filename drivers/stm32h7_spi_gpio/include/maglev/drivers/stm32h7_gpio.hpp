// STM32H7 GPIO (RM0433 §11.4) behind the OutputPin/InputPin interfaces.
// Output pins are configured glitch-free: the initial level is written to
// BSRR BEFORE the pin is switched to output mode, so a safety line such as the
// amplifier enable can never pulse high while being configured.
#pragma once

#include <cstdint>

#include "maglev/drivers/bus.hpp"
#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::drivers {

struct PinId {
  stm32h7::Addr port;  // stm32h7::gpio::port('B')
  std::uint8_t pin;    // 0..15
};

// Alternate-function pin setup (SPI, USART, FDCAN, TIM inputs).
template <stm32h7::RegisterBus Bus>
void configure_alternate_pin(Bus& bus, PinId id, std::uint32_t af, std::uint32_t speed = 3,
                             std::uint32_t pull = 0) {
  namespace g = stm32h7::gpio;
  const unsigned two = 2u * id.pin;
  const stm32h7::Addr afr = id.pin < 8 ? g::kAfrl : g::kAfrh;
  const unsigned four = 4u * (id.pin % 8u);
  stm32h7::modify32(bus, id.port + afr, 0xFu << four, (af & 0xFu) << four);
  stm32h7::modify32(bus, id.port + g::kOspeedr, 3u << two, (speed & 3u) << two);
  stm32h7::modify32(bus, id.port + g::kPupdr, 3u << two, (pull & 3u) << two);
  stm32h7::modify32(bus, id.port + g::kModer, 3u << two, g::kModeAlternate << two);
}

template <stm32h7::RegisterBus Bus>
class Stm32OutputPin final : public OutputPin {
 public:
  Stm32OutputPin(Bus& bus, PinId id) : bus_(bus), id_(id) {}

  void configure(bool initial_high, std::uint32_t speed = 2) {
    namespace g = stm32h7::gpio;
    const unsigned two = 2u * id_.pin;
    write(initial_high);  // level first: no glitch when MODER switches
    stm32h7::modify32(bus_, id_.port + g::kOtyper, 1u << id_.pin, 0u);  // push-pull
    stm32h7::modify32(bus_, id_.port + g::kOspeedr, 3u << two, (speed & 3u) << two);
    stm32h7::modify32(bus_, id_.port + g::kModer, 3u << two, g::kModeOutput << two);
  }
  void write(bool high) override {
    // BSRR: atomic set (bits 0..15) / reset (bits 16..31), no read-modify-write race with ISRs.
    bus_.write32(id_.port + stm32h7::gpio::kBsrr, stm32h7::gpio::bsrr(id_.pin, high));
  }

 private:
  Bus& bus_;
  PinId id_;
};

template <stm32h7::RegisterBus Bus>
class Stm32InputPin final : public InputPin {
 public:
  Stm32InputPin(Bus& bus, PinId id) : bus_(bus), id_(id) {}
  void configure(std::uint32_t pull = 0) {
    namespace g = stm32h7::gpio;
    const unsigned two = 2u * id_.pin;
    stm32h7::modify32(bus_, id_.port + g::kPupdr, 3u << two, (pull & 3u) << two);
    stm32h7::modify32(bus_, id_.port + g::kModer, 3u << two, g::kModeInput << two);
  }
  bool read() override { return (bus_.read32(id_.port + stm32h7::gpio::kIdr) & (1u << id_.pin)) != 0u; }

 private:
  Bus& bus_;
  PinId id_;
};

}  // namespace maglev::drivers
