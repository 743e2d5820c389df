# maglev_hot_path(<target>...): build a library on the servo tick's or the
# bench's per-tick path at -O3. Measured: 13 % fewer M7 instructions per
# step() (the kernel's tick libraries) and ~9 % fewer per bench tick on the
# host than -O2 (docs/PERFORMANCE.md, "On-target" and "Bench speed"). The
# results are the same bits at any level: no FP contraction
# (-ffp-contract=off everywhere) and no reassociation without -ffast-math.
# -fno-math-errno: sqrt becomes the bare instruction (VSQRT / sqrtsd),
# without the compare and the library call that would set errno for a
# negative argument; IEEE sqrt is correctly rounded, so the same bits, and
# no kernel code reads errno.
function(maglev_hot_path)
  foreach(_target ${ARGN})
    target_compile_options(${_target} PRIVATE -O3 -fno-math-errno)
  endforeach()
endfunction()
