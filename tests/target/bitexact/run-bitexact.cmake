# cmake -DRECORDER=<kernel-vector-recorder> -DCOMPARE=<kernel-bitexact-compare>
#       -DQEMU=<qemu-system-arm> -DELF=<maglev-qemu-kernel-replay.elf>
#       -DWORKDIR=<dir> -DTIMEOUT=<s> [-DICOUNT_SHIFT=<n>] [-DPROFILE=<file.profile>] [-DNEAR_HOME=ON]
#       [-DQ7_24=ON]  (the fixed-point kernel, Controller<Q7_24>, on both sides)
#       [-DINTERNAL_MODEL_AXES=x,y]  (PROFILE with these axes' controllers
#       made internal_model: their PID gains dropped, the rest as it is)
#       -P run-bitexact.cmake
#
# 1. record: plant + host Controller<float> -> vectors.bin, host_outputs.bin
# 2. replay: the same vectors through Controller<float> on QEMU's Cortex-M7
#    -> target_outputs.bin (and, with ICOUNT_SHIFT, instructions per step())
# 3. compare the two output files bit for bit.
# A missing replay image FAILS (the host build builds it with the default
# MAGLEV_KERNEL_REPLAY_ELF; a path given by hand must exist).
include(${CMAKE_CURRENT_LIST_DIR}/bitexact-steps.cmake)
maglev_bitexact_preflight(kernel-bitexact "${QEMU}" "${ELF}"
  "With the default MAGLEV_KERNEL_REPLAY_ELF the host build makes it: cmake --build --preset host\n"
  "  (target maglev-qemu-kernel-replay-image); a path set by hand is not built. Directly:\n"
  "  cmake --workflow --preset qemu-m7\n"
  "  (or: cmake --preset qemu-m7 && cmake --build --preset qemu-m7 --target maglev-qemu-kernel-replay)\n"
  "or point the host build at another image: -DMAGLEV_KERNEL_REPLAY_ELF=<path>.")
file(MAKE_DIRECTORY ${WORKDIR})
set(_vectors ${WORKDIR}/vectors.bin)
set(_host ${WORKDIR}/host_outputs.bin)
set(_target ${WORKDIR}/target_outputs.bin)
file(REMOVE ${_target})

set(_profile_args)
if(DEFINED PROFILE AND DEFINED INTERNAL_MODEL_AXES)
  string(REPLACE "," ";" INTERNAL_MODEL_AXES "${INTERNAL_MODEL_AXES}")
  # The shipped profile, rewritten in the work folder: in each named axis'
  # section, controller = internal_model and no PID gains (the profile check
  # refuses a PID gain on an internal-model axis).
  file(STRINGS ${PROFILE} _lines)
  set(_out "")
  set(_in_axis OFF)
  foreach(_line IN LISTS _lines)
    if(_line MATCHES "^\\[axis ([a-z_]+)\\]")
      list(FIND INTERNAL_MODEL_AXES "${CMAKE_MATCH_1}" _at)
      if(_at GREATER -1)
        set(_in_axis ON)
      else()
        set(_in_axis OFF)
      endif()
    elseif(_line MATCHES "^\\[")
      set(_in_axis OFF)
    endif()
    if(_in_axis AND _line MATCHES "^controller *=")
      set(_line "controller = internal_model")
    elseif(_in_axis AND _line MATCHES "^(kp|ki|kd|setpoint_weight_p|setpoint_weight_d) *=")
      continue()
    endif()
    string(APPEND _out "${_line}\n")
  endforeach()
  set(PROFILE ${WORKDIR}/internal_model.profile)
  file(WRITE ${PROFILE} "${_out}")
endif()
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
maglev_bitexact_record(kernel-bitexact ${RECORDER} ${_vectors} ${_host} ${_profile_args})

set(_append "${_vectors} ${_target}")
if(DEFINED ICOUNT_SHIFT)
  string(APPEND _append " --icount")
endif()
maglev_qemu_run(kernel-bitexact "${QEMU}" "${ELF}" "${_append}${_image_scalar}" "${ICOUNT_SHIFT}" ${TIMEOUT} _qemu_out)

execute_process(COMMAND ${COMPARE} ${_host} ${_target} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
message("${_out}")
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "kernel-bitexact: host and Cortex-M7 outputs differ")
endif()

# Instruction budget (only meaningful under -icount): the image prints
#   step_instructions Ready: ticks=N min=A mean=B max=C (tick T)
if(DEFINED MAX_READY_INSTRUCTIONS)
  maglev_check_ready_instructions(kernel-bitexact "${_qemu_out}" step_instructions "step()" ${MAX_READY_INSTRUCTIONS})
endif()
