/*
 * Minimal C/C++ runtime hooks for heap-free, exception-free firmware images.
 * Linked into every image by maglev_firmware_image() as an OBJECT library, so
 * these definitions win over newlib/libstdc++ members that would otherwise
 * drag in stdio, malloc or the unwinder. Every function is weak: a board may
 * replace any of them (the QEMU board reports through semihosting instead).
 *
 * Why each exists:
 *   __dso_handle       normally from crtbegin.o, which -nostartfiles drops.
 *   __cxa_atexit       static objects with destructors register them here;
 *                      firmware never returns from main, so nothing to run.
 *                      newlib's version may allocate exit-proc blocks.
 *   __cxa_pure_virtual libsupc++'s calls std::terminate -> verbose terminate
 *                      handler -> demangler + fputs + malloc.
 *   __assert_func      newlib's prints with fiprintf (stdio, malloc).
 *   abort, _exit       newlib's abort -> raise -> _kill/_getpid syscalls.
 */
#include <stdint.h>

void maglev_runtime_fatal(void) __attribute__((weak, noreturn));
int __cxa_atexit(void (*destructor)(void*), void* object, void* dso_handle) __attribute__((weak));
void __cxa_pure_virtual(void) __attribute__((weak, noreturn));
void __assert_func(const char* file, int line, const char* function, const char* expression)
    __attribute__((weak, noreturn));
void abort(void) __attribute__((weak, noreturn));
void _exit(int status) __attribute__((weak, noreturn));

void* __dso_handle __attribute__((weak)) = 0;

/* Default fatal path: stop here so a debugger shows where; boards override. */
void maglev_runtime_fatal(void) {
  for (;;) {
    __asm__ volatile("bkpt #0");
  }
}

int __cxa_atexit(void (*destructor)(void*), void* object, void* dso_handle) {
  (void)destructor;
  (void)object;
  (void)dso_handle;
  return 0;
}

void __cxa_pure_virtual(void) { maglev_runtime_fatal(); }

void __assert_func(const char* file, int line, const char* function, const char* expression) {
  (void)file;
  (void)line;
  (void)function;
  (void)expression;
  maglev_runtime_fatal();
}

void abort(void) { maglev_runtime_fatal(); }

void _exit(int status) {
  (void)status;
  maglev_runtime_fatal();
}
