// lab::LabRegisters: the rec.* / wave.* registers (Kind::kLab in registers.def)
// over one Recorder and one WaveGenerator -- the modbus::LabTools the
// RegisterServer serves them through.
//
//   static float pool[N];     // .axi_bss on the board
//   static float table[4096];
//   lab::Recorder recorder(pool, N);
//   lab::WaveGenerator wave(table, 4096);
//   lab::LabRegisters lab(recorder, wave, controller.config(), hooks);
//   registers.set_lab_tools(&lab);
//   per tick: before step: controller.set_injection(wave.step(ready));
//             after step:  recorder.sample(controller.status(), sample);
//
// Writes are checked whole (the request's rec.* over the present recorder
// configuration; wave.* on start) and refused with 03 (bad configuration:
// rec.error / wave.error say why) or 06 (recorder armed / generator running,
// or nothing to download); nothing changes then. Heap-free; host + target.
#pragma once

#include <cstdint>

#include "maglev/controller/controller.hpp"
#include "maglev/lab_tools/recorder.hpp"
#include "maglev/lab_tools/wave_generator.hpp"
#include "maglev/modbus/register_server.hpp"

namespace maglev::lab {

struct LabRegistersHooks {
  // Around recorder configure/arm/stop (the board masks the servo tick).
  void (*critical_enter)() = nullptr;
  void (*critical_exit)() = nullptr;
};

// rec.control / wave.control values.
enum RecorderControl : std::uint16_t { kRecArm = 1, kRecTrigger = 2, kRecStop = 3 };
enum WaveControl : std::uint16_t { kWaveStart = 1, kWaveStop = 2 };

class LabRegisters final : public modbus::LabTools {
 public:
  LabRegisters(Recorder& recorder, WaveGenerator& wave, const kernel::KernelConfig& kernel_config,
               const LabRegistersHooks& hooks = {});

  std::uint32_t read(modbus::RegId id) const override;
  modbus::ExceptionCode read_block(modbus::RegId id, std::uint16_t first, std::uint16_t count,
                                   std::uint16_t* out) const override;
  modbus::ExceptionCode write(const modbus::PendingWrite* writes, std::size_t n, bool commit) override;

 private:
  void enter() const {
    if (hooks_.critical_enter != nullptr) hooks_.critical_enter();
  }
  void exit() const {
    if (hooks_.critical_exit != nullptr) hooks_.critical_exit();
  }

  Recorder& recorder_;
  WaveGenerator& wave_;
  const kernel::KernelConfig& kernel_config_;
  LabRegistersHooks hooks_;
  WaveConfig wave_cfg_{};  // what the wave.* registers hold
  std::uint32_t read_offset_ = 0;
  std::uint16_t rec_error_ = 0;
  std::uint16_t wave_error_ = 0;
};

}  // namespace maglev::lab
