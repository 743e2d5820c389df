# cmake -DRECORDER=<kernel-vector-recorder> -DCOMPARE=<kernel-bitexact-compare>
#       -DQEMU=<qemu-system-arm> -DELF=<maglev-qemu-kernel-replay.elf>
#       -DWORKDIR=<dir> -DTIMEOUT=<s> [-DICOUNT_SHIFT=<n>] [-DPROFILE=<file.profile>] [-DNEAR_HOME=ON]
#       [-DQ7_24=ON]  (the fixed-point kernel, Controller<Q7_24>, on both sides)
#       -P run-bitexact.cmake
#
# 1. record: plant + host Controller<float> -> vectors.bin, host_outputs.bin
# 2. replay: the same vectors through Controller<float> on QEMU's Cortex-M7
#    -> target_outputs.bin (and, with ICOUNT_SHIFT, instructions per step())
# 3. compare the two output files bit for bit.
# A missing replay image FAILS (the host build builds it with the default
# MAGLEV_KERNEL_REPLAY_ELF; a path given by hand must exist).
if(NOT EXISTS "${ELF}")
  message(FATAL_ERROR
    "kernel-bitexact: the M7 replay image ${ELF} does not exist.\n"
    "With the default MAGLEV_KERNEL_REPLAY_ELF the host build makes it: cmake --build --preset host\n"
    "  (target maglev-qemu-kernel-replay-image); a path set by hand is not built. Directly:\n"
    "  cmake --workflow --preset qemu-m7\n"
    "  (or: cmake --preset qemu-m7 && cmake --build --preset qemu-m7 --target maglev-qemu-kernel-replay)\n"
    "or point the host build at another image: -DMAGLEV_KERNEL_REPLAY_ELF=<path>.")
endif()
if(NOT QEMU)
  message(FATAL_ERROR "kernel-bitexact: qemu-system-arm not found; run ./cmake/setup-debian.sh")
endif()
file(MAKE_DIRECTORY ${WORKDIR})
set(_vectors ${WORKDIR}/vectors.bin)
set(_host ${WORKDIR}/host_outputs.bin)
set(_target ${WORKDIR}/target_outputs.bin)
file(REMOVE ${_target})

set(_profile_args)
if(DEFINED PROFILE)
  set(_profile_args --profile ${PROFILE})
endif()
if(NEAR_HOME)
  list(APPEND _profile_args --near-home)
endif()
set(_image_scalar "")
if(Q7_24)
  list(APPEND _profile_args --q7.24)
  set(_image_scalar " --q7.24")
endif()
execute_process(COMMAND ${RECORDER} ${_vectors} ${_host} ${_profile_args} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
message("${_out}")
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "kernel-bitexact: the recorder failed (${_rc})")
endif()

set(_cmd ${QEMU} -M mps2-an500 -nographic -monitor none -serial null
         -semihosting-config enable=on,target=native)
if(DEFINED ICOUNT_SHIFT)
  list(APPEND _cmd -icount shift=${ICOUNT_SHIFT})
endif()
if(DEFINED ICOUNT_SHIFT)
  list(APPEND _cmd -kernel ${ELF} -append "${_vectors} ${_target} --icount${_image_scalar}")
else()
  list(APPEND _cmd -kernel ${ELF} -append "${_vectors} ${_target}${_image_scalar}")
endif()
string(REPLACE ";" " " _shown "${_cmd}")
message("kernel-bitexact: ${_shown}")
execute_process(COMMAND ${_cmd} INPUT_FILE /dev/null RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out
                TIMEOUT ${TIMEOUT})
message("${_out}")
set(_qemu_out "${_out}")
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "kernel-bitexact: the replay image failed under QEMU (status ${_rc})")
endif()

execute_process(COMMAND ${COMPARE} ${_host} ${_target} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
message("${_out}")
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "kernel-bitexact: host and Cortex-M7 outputs differ")
endif()

# Instruction budget (only meaningful under -icount): the image prints
#   step_instructions Ready: ticks=N min=A mean=B max=C (tick T)
if(DEFINED MAX_READY_INSTRUCTIONS)
  if(NOT _qemu_out MATCHES "step_instructions Ready: ticks=([0-9]+) min=([0-9]+) mean=([0-9.]+) max=([0-9]+)")
    message(FATAL_ERROR "kernel-bitexact: the image printed no Ready step_instructions line")
  endif()
  set(_ready_ticks ${CMAKE_MATCH_1})
  set(_ready_max ${CMAKE_MATCH_4})
  if(_ready_ticks LESS 1000)
    message(FATAL_ERROR "kernel-bitexact: only ${_ready_ticks} Ready ticks measured")
  endif()
  if(_ready_max GREATER MAX_READY_INSTRUCTIONS)
    message(FATAL_ERROR "kernel-bitexact: a Ready step() took ${_ready_max} instructions > budget ${MAX_READY_INSTRUCTIONS}")
  endif()
  message("kernel-bitexact: Ready step() max ${_ready_max} instructions <= budget ${MAX_READY_INSTRUCTIONS}")
endif()
