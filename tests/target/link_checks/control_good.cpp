// Heap-free control image: static storage, a class with virtual functions and
// a protected non-virtual destructor (the firmware interface pattern; a public
// virtual destructor would emit a deleting destructor -> operator delete).
#include <array>
#include <cstdint>

namespace {

class Filter {
 public:
  virtual std::int32_t step(std::int32_t input) = 0;

 protected:
  ~Filter() = default;
};

class RunningSum final : public Filter {
 public:
  std::int32_t step(std::int32_t input) override {
    sum_ += input;
    return sum_;
  }

 private:
  std::int32_t sum_ = 0;
};

RunningSum g_sum;
std::array<std::int32_t, 16> g_buffer{};

}  // namespace

int main() {
  Filter& filter = g_sum;
  std::int32_t last = 0;
  for (std::size_t i = 0; i < g_buffer.size(); ++i) {
    g_buffer[i] = static_cast<std::int32_t>(i);
    last = filter.step(g_buffer[i]);
  }
  return last == 120 ? 0 : 1;
}
