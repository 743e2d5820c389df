# The bit-exact replay of a stage family with its own kernel (paper 002's
# pmlsm_stage, paper 001's selfstab_stage; label target):
# cmake -DNAME=<test name> -DRECORDER=<program> [-DRECORDER_COMMAND=<subcommand>]
#       -DQEMU=<qemu-system-arm> -DELF=<replay image> -DPROFILE=<file.profile>
#       -DWORKDIR=<dir> -DTIMEOUT=<s> [-DICOUNT_SHIFT=6]
#       [-DCOMPARER=<program>]   its `--compare HOST M7` decides; otherwise the files
#       [-DRECORD_BYTES=<n>]     must be identical byte for byte (n-byte records:
#                                the first differing tick is named)
#       -P run-stage-bitexact.cmake
# 1. record: `RECORDER [RECORDER_COMMAND] vectors host_outputs --profile PROFILE`
#    (the host bench's session with the family's kernel);
# 2. replay the vectors through the same kernel on QEMU's Cortex-M7;
# 3. compare the two output files.
include(${CMAKE_CURRENT_LIST_DIR}/bitexact-steps.cmake)
maglev_bitexact_preflight(${NAME} "${QEMU}" "${ELF}" "(the host build makes it: target maglev-qemu-kernel-replay-image)")
file(MAKE_DIRECTORY ${WORKDIR})
set(_vectors ${WORKDIR}/vectors.bin)
set(_host ${WORKDIR}/host_outputs.bin)
set(_target ${WORKDIR}/target_outputs.bin)
file(REMOVE ${_target})
maglev_bitexact_record(${NAME} ${RECORDER} ${RECORDER_COMMAND} ${_vectors} ${_host} --profile ${PROFILE})
set(_append "${_vectors} ${_target}")
if(DEFINED ICOUNT_SHIFT)
  string(APPEND _append " --icount")
endif()
maglev_qemu_run(${NAME} "${QEMU}" "${ELF}" "${_append}" "${ICOUNT_SHIFT}" ${TIMEOUT} _qemu_out)

if(DEFINED COMPARER)
  execute_process(COMMAND ${COMPARER} --compare ${_host} ${_target}
                  RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
  message("${_out}")
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "${NAME}: host and Cortex-M7 outputs differ")
  endif()
  return()
endif()
file(SIZE ${_host} _host_size)
file(SIZE ${_target} _target_size)
math(EXPR _min_bytes "${RECORD_BYTES} * 1000")
if(NOT _host_size EQUAL _target_size OR _host_size LESS _min_bytes)
  message(FATAL_ERROR "${NAME}: output sizes differ or too short (host ${_host_size}, M7 ${_target_size} bytes)")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${_host} ${_target} RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  # Name the first differing tick.
  file(READ ${_host} _h HEX)
  file(READ ${_target} _t HEX)
  string(LENGTH "${_h}" _n)
  math(EXPR _hex_per_record "${RECORD_BYTES} * 2")
  set(_i 0)
  while(_i LESS _n)
    string(SUBSTRING "${_h}" ${_i} ${_hex_per_record} _a)
    string(SUBSTRING "${_t}" ${_i} ${_hex_per_record} _b)
    if(NOT _a STREQUAL _b)
      math(EXPR _tick "${_i} / ${_hex_per_record}")
      message(FATAL_ERROR "${NAME}: host and Cortex-M7 outputs differ first at tick ${_tick}\n host ${_a}\n M7   ${_b}")
    endif()
    math(EXPR _i "${_i} + ${_hex_per_record}")
  endwhile()
  message(FATAL_ERROR "${NAME}: host and Cortex-M7 outputs differ")
endif()
math(EXPR _ticks "${_host_size} / ${RECORD_BYTES}")
message("${NAME}: ${_ticks} ticks, host and Cortex-M7 outputs identical")
