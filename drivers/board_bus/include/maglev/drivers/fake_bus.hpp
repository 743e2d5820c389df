// Heap-free, fixed-capacity fakes of the abstract buses (Pigweed style) for
// host tests. FakeSpiMaster logs every transaction word by word and routes it
// to an optional per-device SpiPeripheralModel (e.g. the AD5764 chain model),
// so tests can check both the raw traffic and what the chip would do with it.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/drivers/bus.hpp"

namespace maglev::drivers {

// A simulated SPI peripheral: sees each word as it is clocked (MOSI in,
// returns MISO) and the chip-select release at the end of the frame.
class SpiPeripheralModel {
 public:
  virtual std::uint32_t clock_word(std::uint32_t mosi, std::uint8_t word_bits) = 0;
  virtual void chip_select_released() = 0;

 protected:
  SpiPeripheralModel() = default;
  ~SpiPeripheralModel() = default;
  SpiPeripheralModel(const SpiPeripheralModel&) = default;
  SpiPeripheralModel& operator=(const SpiPeripheralModel&) = default;
};

template <std::size_t kMaxWords = 512, std::size_t kMaxTransfers = 64, std::size_t kDevices = 4>
class FakeSpiMaster final : public SpiMaster {
 public:
  struct Record {
    std::uint8_t device;
    std::uint8_t word_bits;
    std::size_t first_word;  // index into words()
    std::size_t words;
  };

  void attach(std::uint8_t device, SpiPeripheralModel* model) {
    if (device < kDevices) models_[device] = model;
  }

  BusStatus transfer(const SpiTransfer& t) override {
    if (t.word_bits < 4 || t.word_bits > 32 || t.device >= kDevices) return BusStatus::kBadArgument;
    if (fail_next_) {
      fail_next_ = false;
      return BusStatus::kTimeout;
    }
    if (transfers_ >= kMaxTransfers || words_ + t.words > kMaxWords) {
      overflow_ = true;
      return BusStatus::kBadArgument;
    }
    records_[transfers_++] = Record{t.device, t.word_bits, words_, t.words};
    const std::uint32_t mask = t.word_bits == 32 ? 0xFFFFFFFFu : ((1u << t.word_bits) - 1u);
    SpiPeripheralModel* model = models_[t.device];
    for (std::size_t i = 0; i < t.words; ++i) {
      const std::uint32_t mosi = (t.tx != nullptr ? t.tx[i] : 0u) & mask;
      mosi_[words_++] = mosi;
      const std::uint32_t miso = model != nullptr ? (model->clock_word(mosi, t.word_bits) & mask) : 0u;
      if (t.rx != nullptr) t.rx[i] = miso;
    }
    if (model != nullptr) model->chip_select_released();
    return BusStatus::kOk;
  }

  void fail_next_transfer() { fail_next_ = true; }
  std::size_t transfer_count() const { return transfers_; }
  const Record& record(std::size_t i) const { return records_[i]; }
  std::uint32_t word(std::size_t transfer, std::size_t i) const { return mosi_[records_[transfer].first_word + i]; }
  bool overflow() const { return overflow_; }
  void clear() {
    transfers_ = 0;
    words_ = 0;
  }

 private:
  SpiPeripheralModel* models_[kDevices]{};
  Record records_[kMaxTransfers]{};
  std::uint32_t mosi_[kMaxWords]{};
  std::size_t transfers_ = 0;
  std::size_t words_ = 0;
  bool overflow_ = false;
  bool fail_next_ = false;
};

// Records every level written, in order; an optional edge hook lets a chip
// model react (e.g. the AD5764's LDAC falling edge).
template <std::size_t kMaxEdges = 64>
class FakeOutputPin final : public OutputPin {
 public:
  using EdgeHook = void (*)(void* context, bool high);
  void write(bool high) override {
    if (count_ < kMaxEdges) history_[count_++] = high;
    level_ = high;
    if (hook_ != nullptr) hook_(context_, high);
  }
  void set_hook(EdgeHook hook, void* context) {
    hook_ = hook;
    context_ = context;
  }
  bool level() const { return level_; }
  bool written() const { return count_ > 0; }
  std::size_t writes() const { return count_; }
  bool history(std::size_t i) const { return history_[i]; }

 private:
  bool history_[kMaxEdges]{};
  std::size_t count_ = 0;
  bool level_ = false;
  EdgeHook hook_ = nullptr;
  void* context_ = nullptr;
};

class FakeInputPin final : public InputPin {
 public:
  explicit FakeInputPin(bool level = false) : level_(level) {}
  bool read() override {
    ++reads_;
    return level_;
  }
  void set(bool level) { level_ = level; }
  std::uint32_t reads() const { return reads_; }

 private:
  bool level_;
  std::uint32_t reads_ = 0;
};

}  // namespace maglev::drivers
