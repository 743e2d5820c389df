# The steps the record / replay / compare scripts share (run-bitexact.cmake,
# run-stage-bitexact.cmake, run-servo-tick.cmake): include() this file, then
# call the functions. Every failure is FATAL_ERROR prefixed with the test's name.

# The M7 image and QEMU must exist: a missing image FAILS (never a skip);
# the remaining arguments, joined, say how to build it.
function(maglev_bitexact_preflight name qemu elf)
  if(NOT EXISTS "${elf}")
    string(CONCAT _hint ${ARGN})
    message(FATAL_ERROR "${name}: the M7 image ${elf} does not exist.\n${_hint}")
  endif()
  if(NOT qemu)
    message(FATAL_ERROR "${name}: qemu-system-arm not found; run ./cmake/setup-debian.sh")
  endif()
endfunction()

# Runs the host recorder (the command in ARGN); fails if it exits non-zero.
function(maglev_bitexact_record name)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
  message("${_out}")
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "${name}: the recorder failed (${_rc})")
  endif()
endfunction()

# Runs `elf` on QEMU's mps2-an500 (Cortex-M7) with semihosting and the command
# line `append`, under -icount shift=<icount_shift> unless that is empty; fails
# if the image exits non-zero. Its console output goes to ${out_var}.
function(maglev_qemu_run name qemu elf append icount_shift timeout out_var)
  set(_cmd ${qemu} -M mps2-an500 -nographic -monitor none -serial null -semihosting-config enable=on,target=native)
  if(NOT "${icount_shift}" STREQUAL "")
    list(APPEND _cmd -icount shift=${icount_shift})
  endif()
  list(APPEND _cmd -kernel ${elf} -append "${append}")
  string(REPLACE ";" " " _shown "${_cmd}")
  message("${name}: ${_shown}")
  execute_process(COMMAND ${_cmd} INPUT_FILE /dev/null RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out
                  TIMEOUT ${timeout})
  message("${_out}")
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "${name}: the image failed under QEMU (status ${_rc})")
  endif()
  set(${out_var} "${_out}" PARENT_SCOPE)
endfunction()

# The regression guard on the image's line
#   <line> Ready: ticks=N min=A mean=B max=C (tick T)
# (meaningful only under -icount): at least 1 000 Ready ticks, and C <= max.
# `what` names the measured call in the messages.
function(maglev_check_ready_instructions name output line what max)
  if(NOT output MATCHES "${line} Ready: ticks=([0-9]+) min=([0-9]+) mean=([0-9.]+) max=([0-9]+)")
    message(FATAL_ERROR "${name}: the image printed no Ready ${line} line")
  endif()
  set(_ready_ticks ${CMAKE_MATCH_1})
  set(_ready_max ${CMAKE_MATCH_4})
  if(_ready_ticks LESS 1000)
    message(FATAL_ERROR "${name}: only ${_ready_ticks} Ready ticks measured")
  endif()
  if(_ready_max GREATER max)
    message(FATAL_ERROR "${name}: a Ready ${what} took ${_ready_max} instructions > ${max} "
                        "(the measured maximum + 10 %, docs/PERFORMANCE.md)")
  endif()
  message("${name}: Ready ${what} max ${_ready_max} instructions <= ${max}")
endfunction()
