# cmake -DRECORDER=<selfstab-vector-recorder> -DQEMU=<qemu-system-arm>
#       -DELF=<maglev-qemu-selfstab-replay.elf> -DPROFILE=<file.profile>
#       -DWORKDIR=<dir> -DTIMEOUT=<s> -P run-selfstab-bitexact.cmake
# 1. record the paper-001 session on the host (plant + selfstab kernel);
# 2. replay its vectors on QEMU's Cortex-M7; 3. compare bit for bit.
if(NOT EXISTS "${ELF}")
  message(FATAL_ERROR "selfstab-bitexact: the M7 replay image ${ELF} does not exist "
                      "(the host build makes it: target maglev-qemu-selfstab-replay-image).")
endif()
if(NOT QEMU)
  message(FATAL_ERROR "selfstab-bitexact: qemu-system-arm not found; run ./cmake/setup-debian.sh")
endif()
file(MAKE_DIRECTORY ${WORKDIR})
set(_vectors ${WORKDIR}/vectors.bin)
set(_host ${WORKDIR}/host_outputs.bin)
set(_target ${WORKDIR}/target_outputs.bin)
file(REMOVE ${_target})
execute_process(COMMAND ${RECORDER} ${_vectors} ${_host} --profile ${PROFILE}
                RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
message("${_out}")
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "selfstab-bitexact: the recorder failed (${_rc})")
endif()
execute_process(COMMAND ${QEMU} -M mps2-an500 -nographic -monitor none -serial null
                        -semihosting-config enable=on,target=native
                        -kernel ${ELF} -append "${_vectors} ${_target}"
                INPUT_FILE /dev/null RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out TIMEOUT ${TIMEOUT})
message("${_out}")
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "selfstab-bitexact: the replay image failed under QEMU (status ${_rc})")
endif()
execute_process(COMMAND ${RECORDER} --compare ${_host} ${_target}
                RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
message("${_out}")
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "selfstab-bitexact: host and Cortex-M7 outputs differ")
endif()
