// lab::Recorder: the on-board data recorder. Up to kMaxChannels kernel signals
// (maglev/lab_tools/signals.hpp) sampled at the servo rate or decimated into a
// static pool (the board: 512 KiB of AXI SRAM, section ".axi_bss"; the host:
// plain static storage), with a trigger and pre-trigger samples.
//
// Data path (one tick, top-priority interrupt):
//   ServoLoop::on_tick -> kernel step() -> ServoHooks::record -> Recorder::sample(status, sample)
//   sample():  idle/done: return (one compare);
//              every `decimation`-th tick: nch signal reads -> pool[slot * nch + c]
//              (channel-interleaved ring of capacity = pool / nch samples);
//              armed: trigger test (immediate, command, level crossing of any
//              signal, fault); triggered: count down the post-trigger samples.
// Readout (Modbus, lower priority): only a finished capture (state kDone) is
// read, so the tick and the reader never share a slot being written.
//
// Cost (measured on QEMU's Cortex-M7, docs/LAB-TOOLS.md): 8 channels + a
// level trigger 314 instructions per tick; idle or done 8.
//
// Heap-free, exception-free; host + Cortex-M7.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/controller/controller.hpp"
#include "maglev/io/sensor_sample.hpp"
#include "maglev/lab_tools/signals.hpp"

namespace maglev::lab {

inline constexpr std::uint16_t kMaxChannels = 8;
// The board's recorder memory: all of AXI SRAM (512 KiB, linker/stm32h743.ld
// section .axi_bss) as float32 values: 8 channels x 16384 samples.
inline constexpr std::size_t kBoardPoolWords = 512u * 1024u / sizeof(float);

// Pinned values: they are register values (rec.trigger_mode, rec.state, ...).
enum class TriggerMode : std::uint16_t {
  kImmediate = 0,  // at the first sample after arming (after the pre-trigger samples)
  kCommand = 1,    // when rec.control = 2 (trigger) is written
  kLevel = 2,      // trigger_signal crosses trigger_level (edge: rising, falling, either)
  kFault = 3,      // the kernel latches a fault (status.fault 0 -> nonzero, or state -> fault)
};
enum class TriggerEdge : std::uint16_t { kRising = 0, kFalling = 1, kEither = 2 };
enum class RecorderState : std::uint16_t {
  kIdle = 0,       // not armed (nothing is written)
  kArmed = 1,      // filling the ring, waiting for the trigger
  kTriggered = 2,  // recording the post-trigger samples
  kDone = 3,       // capture complete: readable
};
// Why a configuration or an action was refused (nothing changed). Pinned.
enum class RecorderError : std::uint8_t {
  kOk = 0,
  kUnknownSignal = 1,     // a channel or the trigger signal names no signal
  kChannelCount = 2,      // 0 or more than kMaxChannels channels
  kLength = 3,            // 0 or more samples per channel than the pool holds for this channel count
  kPretrigger = 4,        // pre-trigger samples >= length
  kDecimation = 5,        // 0
  kBusy = 6,              // configuration while armed/triggered
  kNotArmed = 7,          // command trigger while not armed in command mode
  kBadMode = 8,           // unknown trigger mode / edge
};

struct RecorderConfig {
  std::uint16_t channel_count = 0;
  std::uint16_t channel[kMaxChannels] = {};  // signal ids
  std::uint16_t decimation = 1;              // record every N-th tick
  std::uint32_t length = 0;                  // samples per channel in a capture
  std::uint32_t pretrigger = 0;              // of them, before the trigger sample
  TriggerMode mode = TriggerMode::kImmediate;
  std::uint16_t trigger_signal = 0;          // kLevel
  TriggerEdge edge = TriggerEdge::kRising;   // kLevel
  float level = 0.0f;                        // kLevel, in the signal's unit
};

// The configuration the board arms at boot: the last second before a fault is
// kept (pre-trigger 1 s, 1 s after), x and z pose/reference/effort, coil 1
// current, sequencer state and fault.
RecorderConfig fault_watch_config(float servo_rate_Hz);

// The value of signal `id` in this tick (SI units; codes as numbers).
float signal_value(SignalRef s, const kernel::ControllerStatus& st, const io::SensorSample& sample);

class Recorder {
 public:
  // `pool`: static storage of `pool_words` floats (the caller places it).
  Recorder(float* pool, std::size_t pool_words) : pool_(pool), pool_words_(static_cast<std::uint32_t>(pool_words)) {}

  // Samples per channel the pool holds with `channels` channels.
  std::uint32_t capacity(std::uint16_t channels) const { return channels == 0 ? 0u : pool_words_ / channels; }
  RecorderError check(const RecorderConfig& c) const;
  // Replace the configuration (not while armed/triggered); a finished capture
  // is discarded. Arm() starts recording with it.
  RecorderError configure(const RecorderConfig& c);
  RecorderError arm();      // idle/done -> armed (a capture is discarded)
  RecorderError trigger();  // command trigger
  void stop();              // -> idle (a capture in progress is discarded)

  // The servo tick (after kernel step()).
  void sample(const kernel::ControllerStatus& st, const io::SensorSample& s) {
    if (state_ != RecorderState::kArmed && state_ != RecorderState::kTriggered) return;
    if (++decimation_count_ < config_.decimation) return;
    decimation_count_ = 0;
    record(st, s);
  }

  RecorderState state() const { return state_; }
  const RecorderConfig& config() const { return config_; }
  // Of a finished capture: samples per channel, index of the trigger sample.
  std::uint32_t captured() const { return state_ == RecorderState::kDone ? config_.length : 0u; }
  std::uint32_t trigger_index() const { return trigger_index_; }
  // Increments at every finished capture (a resumed download checks it).
  std::uint16_t capture_id() const { return capture_id_; }
  // Value k of a finished capture, channel-interleaved (k = sample * nch + channel);
  // 0 outside it or while not done.
  float at(std::uint32_t k) const;
  std::uint32_t values() const { return captured() * config_.channel_count; }

 private:
  void record(const kernel::ControllerStatus& st, const io::SensorSample& s);
  bool triggered_now(const kernel::ControllerStatus& st, const io::SensorSample& s);

  float* pool_;
  std::uint32_t pool_words_;
  RecorderConfig config_{};
  SignalRef ref_[kMaxChannels]{};
  SignalRef trigger_ref_{};
  std::uint32_t cap_ = 0;          // ring capacity (samples per channel)
  std::uint32_t write_slot_ = 0;   // next slot written
  std::uint32_t filled_ = 0;       // samples written since arm (saturates at cap_)
  std::uint32_t remaining_ = 0;    // post-trigger samples still to write
  std::uint32_t start_slot_ = 0;   // slot of capture sample 0
  std::uint32_t trigger_index_ = 0;
  std::uint16_t decimation_count_ = 0;
  std::uint16_t capture_id_ = 0;
  float previous_ = 0.0f;          // trigger signal, last sample
  bool have_previous_ = false;
  volatile bool trigger_request_ = false;
  volatile RecorderState state_ = RecorderState::kIdle;
};

}  // namespace maglev::lab
