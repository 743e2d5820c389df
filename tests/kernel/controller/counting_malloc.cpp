// Interposes malloc/calloc/realloc/free for the whole test process (the
// executable's definitions win over libc's for every shared library too, so
// libstdc++'s operator new is counted). Forwards to glibc's __libc_* entry points.
#include <cstddef>

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void __libc_free(void*);

// Read by the test: allocations since the last reset.
volatile unsigned long g_alloc_count = 0;

void* malloc(std::size_t n) {
  g_alloc_count = g_alloc_count + 1;
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t s) {
  g_alloc_count = g_alloc_count + 1;
  return __libc_calloc(n, s);
}
void* realloc(void* p, std::size_t n) {
  g_alloc_count = g_alloc_count + 1;
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
}
