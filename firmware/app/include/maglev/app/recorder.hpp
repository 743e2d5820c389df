// Fixed-capacity ring of per-tick records (sensor sample + actuator command),
// written by the servo tick, drained at low priority (Modbus/CAN). The board
// places the storage in AXI SRAM (section ".axi_bss", linker/stm32h743.ld):
// large, cacheable, off the DTCM the kernel state lives in.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"

namespace maglev::app {

struct RecordEntry {
  std::uint32_t tick;
  io::SensorSample sample;
  io::ActuatorCommand command;
};

template <std::size_t kCapacity>
class Recorder {
 public:
  void record(const io::SensorSample& s, const io::ActuatorCommand& c) {
    entries_[head_ % kCapacity] = RecordEntry{head_, s, c};
    head_ = head_ + 1u;
  }
  // Oldest-first read of everything newer than `cursor`; returns false if
  // the ring already overwrote that entry (reader too slow) or nothing new.
  bool read(std::uint32_t cursor, RecordEntry& out) const {
    if (cursor >= head_ || head_ - cursor > kCapacity) return false;
    out = entries_[cursor % kCapacity];
    return true;
  }
  std::uint32_t head() const { return head_; }

 private:
  RecordEntry entries_[kCapacity]{};
  volatile std::uint32_t head_ = 0;
};

}  // namespace maglev::app
