// The production amplifier board's part drivers on one register bus, composed
// once: the board image (src/main.cpp, non-HIL) and the QEMU image that counts
// the whole servo interrupt (firmware/board/mps2_an500/servo_tick, on a fake
// register bus) build the same objects, wired the same way.
//
//   SPI1 -> AD5764 chain (SYNC PD14, LDAC PD15), SPI3 -> two AD7606 (CS PE15 /
//   PE10, BUSY PE11, raw words into `adc_rx` by the SPI3 RX DMA: DMA1 stream 0,
//   DMAMUX1 request spi3_rx_dma), TIM2 / TIM5 / TIM3 encoder counters (loss
//   lines PF12..14, active low), AmplifierBoardSensors over them.
// The ADC pair is read by DMA before the tick (ad7606::Stm32DmaReader `adc`, at
// the register level; schedule in
// drivers/ad7606_adc/README.md): the image calls on_busy_fell() from the BUSY
// interrupt and on_adc_dma() from the DMA stream's, and runs the servo tick
// when either says so.
// The DAC chain is written from SPI1's end-of-transfer interrupt
// (ad5764::Stm32IrqWriter `dac_writer`, at the register level; the image
// calls AmplifierBoardIrqActuators::on_dac_irq() from SPI1_IRQHandler);
// `dac`, the polled chain on the same SPI, zeroes the outputs at boot,
// before `dac_writer` takes SPI1 over.
// The amplifier-enable line and the actuator sink stay with the board
// (the HIL image shares the enable pin).
#pragma once

#include <cstdint>

#include "maglev/board/stm32h743/amplifier_board_io.hpp"
#include "maglev/board/stm32h743/pinmap.hpp"
#include "maglev/drivers/ad5764.hpp"
#include "maglev/drivers/ad5764_stm32_irq.hpp"
#include "maglev/drivers/ad7606.hpp"
#include "maglev/drivers/ad7606_stm32_dma.hpp"
#include "maglev/drivers/quadrature_encoder.hpp"
#include "maglev/drivers/stm32h7_gpio.hpp"
#include "maglev/drivers/stm32h7_spi.hpp"
#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::board::stm32h743 {

template <stm32h7::RegisterBus Bus>
struct AmplifierBoardDrivers {
  using Encoder = drivers::QuadratureEncoder<Bus, drivers::Stm32InputPin<Bus>>;
  // SPI1 -> the AD5764 chain. SCLK: pll1_q 80 MHz kernel clock / 4 = 20 MHz
  // (AD5764 max 30 MHz), mode 1 (data latched on SCLK falling edges).
  static constexpr drivers::ad5764::Stm32ChainWiring kDacWiring{
      stm32h7::spi::kSpi1, pins::kDacSync.port, pins::kDacSync.pin, pins::kDacLdac.port, pins::kDacLdac.pin, 1,
      false, true};
  using DacWriter = drivers::ad5764::Stm32IrqWriter<Bus, kDacWiring>;
  // SPI3 -> the AD7606 pair: /8 = 10 MHz, mode 2; RX by DMA1 stream 0
  // (DMAMUX1 request spi3_rx_dma).
  static constexpr drivers::ad7606::Stm32AdcWiring kAdcWiring{
      stm32h7::spi::kSpi3, {pins::kAdc0Cs.port, pins::kAdc1Cs.port}, {pins::kAdc0Cs.pin, pins::kAdc1Cs.pin},
      pins::kAdcBusy.port, pins::kAdcBusy.pin, stm32h7::dma::kDma1, 0, stm32h7::dma::kReqSpi3Rx, 2, true, false};
  using AdcReader = drivers::ad7606::Stm32DmaReader<Bus, kAdcWiring>;

  // `adc_rx`: the AD7606 raw words (the board: D2 SRAM, non-cacheable, where
  // the SPI3 RX DMA stream writes them).
  AmplifierBoardDrivers(Bus& b, std::uint32_t (&adc_rx)[drivers::ad7606::kDevices][drivers::ad7606::kChannelsPerDevice / 2])
      : bus(b), adc{b, adc_rx} {}
  AmplifierBoardDrivers(const AmplifierBoardDrivers&) = delete;
  AmplifierBoardDrivers& operator=(const AmplifierBoardDrivers&) = delete;

  Bus& bus;
  drivers::Stm32OutputPin<Bus> dac_sync{bus, pins::kDacSync};
  drivers::Stm32OutputPin<Bus> dac_ldac{bus, pins::kDacLdac};
  drivers::Stm32OutputPin<Bus> adc0_cs{bus, pins::kAdc0Cs};
  drivers::Stm32OutputPin<Bus> adc1_cs{bus, pins::kAdc1Cs};
  drivers::Stm32InputPin<Bus> adc_busy{bus, pins::kAdcBusy};
  drivers::Stm32InputPin<Bus> loss0{bus, pins::kLoss0};
  drivers::Stm32InputPin<Bus> loss1{bus, pins::kLoss1};
  drivers::Stm32InputPin<Bus> loss2{bus, pins::kLoss2};
  // The boot write's polled chain on SPI1 (pll1_q 80 MHz kernel clock): kDacWiring's settings.
  const drivers::SpiDeviceSettings dac_spi[1] = {
      {&dac_sync, kDacWiring.clock_divider_log2, kDacWiring.cpol, kDacWiring.cpha}};
  drivers::Stm32SpiMaster<Bus, 1> spi_dac{bus, stm32h7::spi::kSpi1, dac_spi};
  drivers::ad5764::Chain<2> dac{spi_dac, 0, dac_ldac};
  DacWriter dac_writer{bus};
  AdcReader adc;
  Encoder enc0{bus, {stm32h7::tim::kTim2, true, 1, false}, loss0};
  Encoder enc1{bus, {stm32h7::tim::kTim5, true, 1, false}, loss1};
  Encoder enc2{bus, {stm32h7::tim::kTim3, false, 1, false}, loss2};  // 16-bit: TIM3_IRQHandler extends it
  AmplifierBoardSensors<Encoder, AdcReader> sensors{adc, enc0, enc1, enc2};

  // BUSY fell (EXTI11): start the DMA read of the pair. True: run the tick
  // now -- the read could not start, and the tick reports the sensor loss.
  bool on_busy_fell() { return adc.begin() != drivers::ad7606::Status::kOk; }
  // DMA1 stream 0 interrupt: ADC0 done -> ADC1 started (false); ADC1 done
  // or a transfer error -> true: run the tick, it takes the buffer (or the loss).
  bool on_adc_dma() {
    const auto step = adc.advance();
    return step == AdcReader::Step::kComplete || step == AdcReader::Step::kError;
  }

  // Alternate functions and GPIO of the parts (clocks already on).
  void configure_pins() {
    drivers::configure_alternate_pin(bus, pins::kDacSck, pins::kAfSpi1);
    drivers::configure_alternate_pin(bus, pins::kDacMiso, pins::kAfSpi1);
    drivers::configure_alternate_pin(bus, pins::kDacMosi, pins::kAfSpi1);
    drivers::configure_alternate_pin(bus, pins::kAdcSck, pins::kAfSpi3);
    drivers::configure_alternate_pin(bus, pins::kAdcMiso, pins::kAfSpi3);
    drivers::configure_alternate_pin(bus, pins::kAdcMosi, pins::kAfSpi3);
    drivers::configure_alternate_pin(bus, pins::kAdcConvst, pins::kAfTim1);
    drivers::configure_alternate_pin(bus, pins::kEnc0A, pins::kAfTim2, 2);
    drivers::configure_alternate_pin(bus, pins::kEnc0B, pins::kAfTim2, 2);
    drivers::configure_alternate_pin(bus, pins::kEnc1A, pins::kAfTim5, 2);
    drivers::configure_alternate_pin(bus, pins::kEnc1B, pins::kAfTim5, 2);
    drivers::configure_alternate_pin(bus, pins::kEnc2A, pins::kAfTim3, 2);
    drivers::configure_alternate_pin(bus, pins::kEnc2B, pins::kAfTim3, 2);
    dac_sync.configure(true);
    dac_ldac.configure(true);
    adc0_cs.configure(true);
    adc1_cs.configure(true);
    adc_busy.configure();
    loss0.configure(1);
    loss1.configure(1);
    loss2.configure(1);
  }

  // SPI masters (the ADC's with its RX DMA stream; DMA1's clock already on),
  // the DAC at 0 A (before the amplifiers can ever be enabled), the encoder
  // counters from 0.
  void init() {
    spi_dac.init();
    adc.init();
    dac.init();
    (void)dac.write_zero();
    dac_writer.init();
    enc0.init();
    enc1.init();
    enc2.init();
  }
};

}  // namespace maglev::board::stm32h743
