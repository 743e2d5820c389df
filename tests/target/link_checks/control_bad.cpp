// Deliberately BAD image for the checker's negative test: it uses the heap
// (malloc/free, new/delete) exactly the way firmware must never do.
#include <cstdint>
#include <cstdlib>

namespace {
volatile std::uint32_t g_sink = 0;
}

int main() {
  auto* block = static_cast<std::uint32_t*>(std::malloc(64));
  auto* object = new std::uint32_t(7);
  if (block != nullptr) {
    block[0] = *object;
    g_sink = block[0];
  }
  delete object;
  std::free(block);
  return static_cast<int>(g_sink);
}
