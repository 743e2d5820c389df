// The M7 counterpart of tests/kernel/controller/counting_malloc.cpp: counts
// every allocation (malloc/calloc/realloc, hence operator new too) via the
// linker's --wrap (newlib has no __libc_* entry points to forward to).
#include <cstddef>

extern "C" {
void* __real_malloc(std::size_t);
void* __real_calloc(std::size_t, std::size_t);
void* __real_realloc(void*, std::size_t);

// Read by the test: allocations since the last reset.
volatile unsigned long g_alloc_count = 0;

void* __wrap_malloc(std::size_t n) {
  g_alloc_count = g_alloc_count + 1;
  return __real_malloc(n);
}
void* __wrap_calloc(std::size_t n, std::size_t s) {
  g_alloc_count = g_alloc_count + 1;
  return __real_calloc(n, s);
}
void* __wrap_realloc(void* p, std::size_t n) {
  g_alloc_count = g_alloc_count + 1;
  return __real_realloc(p, n);
}
}
