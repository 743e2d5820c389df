// Vector table and reset handler for QEMU's mps2-an500 (Cortex-M7 + FPv5-D16).
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "maglev/board/mps2_an500/semihosting.hpp"
#include "maglev/board/mps2_an500/startup.hpp"

extern "C" {
// From linker/mps2-an500.ld.
extern std::uint32_t __data_start__[];
extern std::uint32_t __data_end__[];
extern const std::uint32_t __data_load__[];
extern std::uint32_t __bss_start__[];
extern std::uint32_t __bss_end__[];
extern std::uint32_t __stack_top__[];
using InitFunction = void (*)();
extern InitFunction __preinit_array_start[];
extern InitFunction __preinit_array_end[];
extern InitFunction __init_array_start[];
extern InitFunction __init_array_end[];

// The application's main(), under another C++ name: ISO C++ forbids calling
// ::main, but the reset handler must.
int maglev_application_main() __asm__("main");
[[noreturn]] void Reset_Handler();
void maglev_runtime_fatal();
[[noreturn]] void _exit(int status);
}

namespace maglev::board::mps2_an500 {
namespace {

// System Control Block registers used here (ARMv7-M ARM, B3.2).
constexpr std::uintptr_t kCpacrAddress = 0xE000ED88U;
constexpr std::uintptr_t kCfsrAddress = 0xE000ED28U;

volatile std::uint32_t& reg32(std::uintptr_t address) {
  return *reinterpret_cast<volatile std::uint32_t*>(address);
}

[[noreturn]] void report_fault(const char* name, const std::uint32_t* stacked_frame) {
  semihost_write("\n*** FAULT: ");
  semihost_write(name);
  semihost_write(" CFSR=");
  semihost_write_hex(reg32(kCfsrAddress), 8);
  if (stacked_frame != nullptr) {
    // Exception frame: r0 r1 r2 r3 r12 lr pc xpsr.
    semihost_write(" PC=");
    semihost_write_hex(stacked_frame[6], 8);
    semihost_write(" LR=");
    semihost_write_hex(stacked_frame[5], 8);
  }
  semihost_write("\n");
  semihost_exit(kFaultExitCode);
}

}  // namespace

DataImage data_image() {
  return DataImage{reinterpret_cast<const std::uint8_t*>(__data_start__),
                   reinterpret_cast<const std::uint8_t*>(__data_end__),
                   reinterpret_cast<const std::uint8_t*>(__data_load__)};
}

}  // namespace maglev::board::mps2_an500

namespace mps2 = maglev::board::mps2_an500;

extern "C" {

// Fault entry: find the stacked frame (MSP or PSP per EXC_RETURN bit 2).
[[gnu::naked]] static void fault_entry() {
  __asm__ volatile(
      "tst lr, #4\n"
      "ite eq\n"
      "mrseq r1, msp\n"
      "mrsne r1, psp\n"
      "mrs r0, ipsr\n"
      "b maglev_report_exception\n");
}

[[noreturn, gnu::used]] void maglev_report_exception(std::uint32_t ipsr, const std::uint32_t* frame);
void maglev_report_exception(std::uint32_t ipsr, const std::uint32_t* frame) {
  const std::uint32_t exception = ipsr & 0x1FFU;
  const char* name = "unexpected interrupt";
  switch (exception) {
    case 2: name = "NMI"; break;
    case 3: name = "HardFault"; break;
    case 4: name = "MemManage"; break;
    case 5: name = "BusFault"; break;
    case 6: name = "UsageFault"; break;
    default: break;
  }
  mps2::report_fault(name, frame);
}

// Runtime hooks (cmake/runtime/no_heap_runtime.c has weak defaults).
void maglev_runtime_fatal() {
  mps2::semihost_write("\n*** FATAL: abort/assert/pure virtual call\n");
  mps2::semihost_exit(mps2::kFaultExitCode);
}

void _exit(int status) { mps2::semihost_exit(status); }

void Reset_Handler() {
  // FPU first: the compiler may use VFP registers anywhere after this point.
  mps2::reg32(mps2::kCpacrAddress) |= (0xFU << 20);  // CP10, CP11 full access
  __asm__ volatile("dsb\n isb" ::: "memory");

  // Word loops, not memcpy/memset: nothing from the C library before .data is set.
  const std::uint32_t* source = __data_load__;
  for (std::uint32_t* destination = __data_start__; destination < __data_end__; ++destination, ++source) {
    *destination = *source;
  }
  for (std::uint32_t* destination = __bss_start__; destination < __bss_end__; ++destination) {
    *destination = 0U;
  }

  for (InitFunction* function = __preinit_array_start; function < __preinit_array_end; ++function) {
    (*function)();
  }
  for (InitFunction* function = __init_array_start; function < __init_array_end; ++function) {
    (*function)();
  }

  mps2::semihost_exit(maglev_application_main());
}

using VectorEntry = void (*)();

// 16 ARMv7-M system vectors + the 32 external interrupts QEMU wires for AN500.
[[gnu::used, gnu::section(".isr_vector")]] const VectorEntry g_vector_table[16 + 32] = {
    reinterpret_cast<VectorEntry>(__stack_top__),  // initial MSP
    Reset_Handler,
    fault_entry,  // NMI
    fault_entry,  // HardFault
    fault_entry,  // MemManage
    fault_entry,  // BusFault
    fault_entry,  // UsageFault
    nullptr, nullptr, nullptr, nullptr,
    fault_entry,  // SVCall
    fault_entry,  // DebugMonitor
    nullptr,
    fault_entry,  // PendSV
    fault_entry,  // SysTick
    fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry,
    fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry,
    fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry,
    fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry, fault_entry,
};

}  // extern "C"
