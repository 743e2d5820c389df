# Cross toolchain: Debian's gcc-arm-none-eabi 12.2 for a Cortex-M7 with the
# double-precision FPv5 unit (STM32H743; QEMU's mps2-an500 is also an M7).
#
#   cmake --preset stm32h743   (or qemu-m7) selects this file.
#
# What it sets, and why:
#   * -mcpu=cortex-m7 -mthumb -mfloat-abi=hard -mfpu=fpv5-d16 : selects the
#     thumb/v7e-m+dp/hard newlib multilib (hardware float calling convention).
#   * -ffunction-sections -fdata-sections + --gc-sections : unused code goes.
#   * C++: -fno-exceptions -fno-rtti -fno-threadsafe-statics : no unwinder, no
#     typeinfo, no __cxa_guard_* (single-threaded init before the scheduler).
#   * --specs=nano.specs : newlib-nano. nosys.specs is deliberately NOT used:
#     an accidental malloc/printf must fail to link (undefined _sbrk/_write)
#     instead of silently pulling a heap in. cmake/runtime/no_heap_runtime.c
#     provides the few runtime hooks a C++ image legitimately needs, and the
#     <image>-no-heap ctest (cmake/check-no-heap.sh) double-checks every ELF.
#   * -Wno-psabi: silences GCC's "parameter passing changed in GCC 7.1" notes;
#     every object is built by this one compiler, so the old ABI never meets it.
#   * -ffp-contract=off comes from the top-level CMakeLists.txt (host too).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(_maglev_prefix arm-none-eabi-)
find_program(CMAKE_C_COMPILER   ${_maglev_prefix}gcc REQUIRED)
find_program(CMAKE_CXX_COMPILER ${_maglev_prefix}g++ REQUIRED)
set(CMAKE_ASM_COMPILER ${CMAKE_C_COMPILER})
find_program(CMAKE_OBJCOPY ${_maglev_prefix}objcopy REQUIRED)
find_program(CMAKE_NM      ${_maglev_prefix}nm      REQUIRED)
find_program(CMAKE_SIZE    ${_maglev_prefix}size    REQUIRED)
find_program(CMAKE_OBJDUMP ${_maglev_prefix}objdump REQUIRED)

# Static-library try_compile: a bare-metal executable cannot link without a
# linker script, so CMake's compiler checks must not try.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(MAGLEV_TARGET_CPU_FLAGS "-mcpu=cortex-m7 -mthumb -mfloat-abi=hard -mfpu=fpv5-d16")
set(CMAKE_C_FLAGS_INIT   "${MAGLEV_TARGET_CPU_FLAGS} -ffunction-sections -fdata-sections")
set(CMAKE_CXX_FLAGS_INIT "${MAGLEV_TARGET_CPU_FLAGS} -ffunction-sections -fdata-sections -fno-exceptions -fno-rtti -fno-threadsafe-statics -Wno-psabi")
set(CMAKE_ASM_FLAGS_INIT "${MAGLEV_TARGET_CPU_FLAGS} -x assembler-with-cpp")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${MAGLEV_TARGET_CPU_FLAGS} --specs=nano.specs -Wl,--gc-sections")

# Search headers/libraries only in the target sysroot, programs on the host.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
