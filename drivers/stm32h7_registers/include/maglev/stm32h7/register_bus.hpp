// Register-access policies. Every register-level driver is a template on a
// `Bus` with read32(addr) / write32(addr, value): on the target that is
// MmioBus (one volatile load/store, inlined away), in host tests it is
// FakeRegisterBus (fixed-capacity register file + write log, no heap), so
// tests check the exact register traffic the target would produce.
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>

#include "maglev/stm32h7/registers.hpp"

namespace maglev::stm32h7 {

template <typename B>
concept RegisterBus = requires(B& bus, Addr addr, std::uint32_t value) {
  { bus.read32(addr) } -> std::same_as<std::uint32_t>;
  bus.write32(addr, value);
};

// Read-modify-write: clear `clear_mask`, then set `set_mask`.
template <RegisterBus Bus>
inline void modify32(Bus& bus, Addr addr, std::uint32_t clear_mask, std::uint32_t set_mask) {
  bus.write32(addr, (bus.read32(addr) & ~clear_mask) | set_mask);
}

// Poll until (reg & mask) == expected, at most `max_reads` reads. Returns
// false on timeout, so no driver can hang the servo loop on a dead peripheral.
template <RegisterBus Bus>
inline bool wait_for(Bus& bus, Addr addr, std::uint32_t mask, std::uint32_t expected,
                     std::uint32_t max_reads) {
  for (std::uint32_t i = 0; i < max_reads; ++i) {
    if ((bus.read32(addr) & mask) == expected) return true;
  }
  return false;
}

// The target policy: memory-mapped I/O.
struct MmioBus {
  std::uint32_t read32(Addr addr) const { return *reinterpret_cast<volatile const std::uint32_t*>(addr); }
  void write32(Addr addr, std::uint32_t value) const {
    *reinterpret_cast<volatile std::uint32_t*>(addr) = value;
  }
  // Completes outstanding writes before the next access (flash programming,
  // MPU/cache changes). A no-op off-target.
  void barrier() const {
#if defined(__arm__)
    __asm__ volatile("dsb 0xF\n isb 0xF" ::: "memory");
#endif
  }
};

// Bus policies may offer barrier(); drivers call it through this helper.
template <RegisterBus Bus>
inline void barrier(Bus& bus) {
  if constexpr (requires { bus.barrier(); }) bus.barrier();
}

// Host fake: a sparse register file of fixed capacity plus a log of every
// write in order. Registers that were never written read as their preset
// value (preset()) or 0. A test can install a write hook to model hardware
// side effects (a ready flag following an enable bit, write-1-to-clear, ...).
template <std::size_t kRegisters = 96, std::size_t kLogEntries = 512>
class FakeRegisterBus {
 public:
  struct Write {
    Addr addr;
    std::uint32_t value;
  };
  using WriteHook = void (*)(void* context, FakeRegisterBus& bus, Addr addr, std::uint32_t value);
  // Models a register whose value hardware changes (status flags): gets the
  // stored value, returns what the read sees.
  using ReadHook = std::uint32_t (*)(void* context, FakeRegisterBus& bus, Addr addr, std::uint32_t stored);

  std::uint32_t read32(Addr addr) {
    ++reads_;
    const Slot* slot = find(addr);
    const std::uint32_t stored = slot != nullptr ? slot->value : 0u;
    return read_hook_ != nullptr ? read_hook_(read_context_, *this, addr, stored) : stored;
  }
  void write32(Addr addr, std::uint32_t value) {
    if (log_size_ < kLogEntries) {
      log_[log_size_++] = Write{addr, value};
    } else {
      log_overflow_ = true;
    }
    store(addr, value);
    if (hook_ != nullptr) hook_(hook_context_, *this, addr, value);
  }

  // Test-side access: set a register without logging it (hardware state).
  void preset(Addr addr, std::uint32_t value) { store(addr, value); }
  std::uint32_t peek(Addr addr) const {
    const Slot* slot = find(addr);
    return slot != nullptr ? slot->value : 0u;
  }
  void set_write_hook(WriteHook hook, void* context) {
    hook_ = hook;
    hook_context_ = context;
  }
  void set_read_hook(ReadHook hook, void* context) {
    read_hook_ = hook;
    read_context_ = context;
  }

  std::size_t log_size() const { return log_size_; }
  const Write& log(std::size_t i) const { return log_[i]; }
  bool log_overflow() const { return log_overflow_; }
  bool capacity_exceeded() const { return capacity_exceeded_; }
  std::uint32_t reads() const { return reads_; }
  void clear_log() { log_size_ = 0; }
  // Number of logged writes to `addr`, and the index of the n-th one (or -1).
  std::size_t writes_to(Addr addr) const {
    std::size_t n = 0;
    for (std::size_t i = 0; i < log_size_; ++i) n += (log_[i].addr == addr) ? 1u : 0u;
    return n;
  }
  long index_of_write(Addr addr, std::size_t nth = 0) const {
    for (std::size_t i = 0; i < log_size_; ++i) {
      if (log_[i].addr == addr) {
        if (nth == 0) return static_cast<long>(i);
        --nth;
      }
    }
    return -1;
  }

 private:
  struct Slot {
    Addr addr;
    std::uint32_t value;
  };
  const Slot* find(Addr addr) const {
    for (std::size_t i = 0; i < used_; ++i) {
      if (slots_[i].addr == addr) return &slots_[i];
    }
    return nullptr;
  }
  void store(Addr addr, std::uint32_t value) {
    for (std::size_t i = 0; i < used_; ++i) {
      if (slots_[i].addr == addr) {
        slots_[i].value = value;
        return;
      }
    }
    if (used_ < kRegisters) {
      slots_[used_++] = Slot{addr, value};
    } else {
      capacity_exceeded_ = true;
    }
  }

  Slot slots_[kRegisters]{};
  std::size_t used_ = 0;
  Write log_[kLogEntries]{};
  std::size_t log_size_ = 0;
  bool log_overflow_ = false;
  bool capacity_exceeded_ = false;
  std::uint32_t reads_ = 0;
  WriteHook hook_ = nullptr;
  void* hook_context_ = nullptr;
  ReadHook read_hook_ = nullptr;
  void* read_context_ = nullptr;
};

}  // namespace maglev::stm32h7
