// A pointer the optimizer must keep as a value (issue 16).
//
// The controller is one large object (~15 KB): its configuration, states and
// status sit at offsets that a VFP load cannot encode (VLDR reaches +-1020
// bytes, ADDW 4095). Given `this + constant`, GCC rematerializes the address
// (MOVW/MLA/ADDW, two or three instructions) before nearly every float load
// in the unrolled per-axis code rather than keep one base in a register.
// Passed through an empty asm, the pointer is a value GCC cannot see into:
// it keeps it in a register (or spills and reloads it, one LDR) and reaches
// fields by immediate offsets. No instruction is emitted and no arithmetic
// changes: the same bits, fewer instructions (run_axis_loops: -92 M7
// instructions a tick for the active configuration alone; docs/PERFORMANCE.md,
// "Session of 2026-11-28").
#pragma once

namespace maglev::numeric {

template <typename T>
inline T* OpaquePointer(T* p) {
  __asm__("" : "+r"(p));
  return p;
}

}  // namespace maglev::numeric
