// Nucleo-H743ZI2 reference pin map for the amplifier board (README.md has the
// table with connector notes). Alternate-function numbers: DS12110 table 9-10.
#pragma once

#include <cstdint>

#include "maglev/drivers/stm32h7_gpio.hpp"
#include "maglev/stm32h7/registers.hpp"

namespace maglev::board::stm32h743::pins {

using drivers::PinId;
using stm32h7::gpio::port;

// SPI1 -> AD5764 chain (DAC): SCK PA5, MISO PA6 (last DAC's SDO), MOSI PB5; AF5.
inline constexpr PinId kDacSck{port('A'), 5}, kDacMiso{port('A'), 6}, kDacMosi{port('B'), 5};
inline constexpr std::uint32_t kAfSpi1 = 5;
inline constexpr PinId kDacSync{port('D'), 14};  // SYNC (chip select), active low
inline constexpr PinId kDacLdac{port('D'), 15};  // LDAC, idles high, pulse low = update all
// SPI3 -> both AD7606 (ADC), DOUTA on MISO: SCK PC10, MISO PC11, MOSI PC12; AF6.
inline constexpr PinId kAdcSck{port('C'), 10}, kAdcMiso{port('C'), 11}, kAdcMosi{port('C'), 12};
inline constexpr std::uint32_t kAfSpi3 = 6;
inline constexpr PinId kAdc0Cs{port('E'), 15}, kAdc1Cs{port('E'), 10};
inline constexpr PinId kAdcBusy{port('E'), 11};   // ADC0 BUSY -> EXTI11 (falling edge)
inline constexpr PinId kAdcConvst{port('E'), 9};  // TIM1_CH1, AF1 -> CONVST A/B of both ADCs
inline constexpr std::uint32_t kAfTim1 = 1;
// Quadrature inputs (interferometer electronics).
inline constexpr PinId kEnc0A{port('A'), 15}, kEnc0B{port('B'), 3};  // TIM2_CH1/CH2, AF1 (32-bit)
inline constexpr std::uint32_t kAfTim2 = 1;
inline constexpr PinId kEnc1A{port('A'), 0}, kEnc1B{port('A'), 1};   // TIM5_CH1/CH2, AF2 (32-bit)
inline constexpr std::uint32_t kAfTim5 = 2;
inline constexpr PinId kEnc2A{port('C'), 6}, kEnc2B{port('C'), 7};   // TIM3_CH1/CH2, AF2 (16-bit, extended)
inline constexpr std::uint32_t kAfTim3 = 2;
inline constexpr PinId kLoss0{port('F'), 12}, kLoss1{port('F'), 13}, kLoss2{port('F'), 14};  // active low
// FDCAN1 -> CAN FD transceiver: RX PD0, TX PD1, AF9.
inline constexpr PinId kCanRx{port('D'), 0}, kCanTx{port('D'), 1};
inline constexpr std::uint32_t kAfFdcan1 = 9;
// USART2 -> RS-485 transceiver: TX PD5, RX PD6, RTS/DE PD4, AF7.
inline constexpr PinId kRs485Tx{port('D'), 5}, kRs485Rx{port('D'), 6}, kRs485De{port('D'), 4};
inline constexpr std::uint32_t kAfUsart2 = 7;
// Amplifier-enable interlock (active high, 10k pull-down on the amplifier board).
inline constexpr PinId kAmpEnable{port('G'), 3};
// Nucleo LD1 (green): heartbeat.
inline constexpr PinId kLed{port('B'), 0};

}  // namespace maglev::board::stm32h743::pins
