# cmake -DQEMU=<qemu-system-arm> -DELF=<image> [-DARGS="<words>"] -DEXPECT_EXIT=<n>
#       [-DEXPECT_REGEX=<re>] -DTIMEOUT=<s> -P run-qemu-test.cmake
# Runs one mps2-an500 image under QEMU with semihosting; see
# maglev_add_qemu_test() in MaglevFirmware.cmake.
set(_cmd ${QEMU} -M mps2-an500 -nographic -monitor none -serial null
         -semihosting-config enable=on,target=native -kernel ${ELF})
if(ARGS)
  list(APPEND _cmd -append "${ARGS}")
endif()
string(REPLACE ";" " " _shown "${_cmd}")
message("run-qemu-test: ${_shown}")
execute_process(COMMAND ${_cmd}
  INPUT_FILE /dev/null
  OUTPUT_VARIABLE _out ERROR_VARIABLE _out
  RESULT_VARIABLE _rc
  TIMEOUT ${TIMEOUT})
message("${_out}")
if(NOT _rc MATCHES "^[0-9]+$")
  message(FATAL_ERROR "run-qemu-test: QEMU did not exit normally: ${_rc} (timeout ${TIMEOUT} s?)")
endif()
if(NOT _rc EQUAL EXPECT_EXIT)
  message(FATAL_ERROR "run-qemu-test: QEMU exit status ${_rc}, expected ${EXPECT_EXIT}")
endif()
if(EXPECT_REGEX AND NOT _out MATCHES "${EXPECT_REGEX}")
  message(FATAL_ERROR "run-qemu-test: output does not match '${EXPECT_REGEX}'")
endif()
message("run-qemu-test: OK (exit status ${_rc})")
