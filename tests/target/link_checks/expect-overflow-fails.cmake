# Links the heap-free control objects with the mps2-an500 script shrunk to a
# 32 KiB RAM region (the image reserves a 64 KiB stack): GNU ld must print the
# memory table and FAIL with "region `RAM' overflowed". Proves the link-time
# memory check maglev_firmware_image() relies on.
separate_arguments(_cpu_flags UNIX_COMMAND "${CPU_FLAGS}")
file(READ ${SCRIPT} _text)
string(REGEX REPLACE "(RAM[^\n]*LENGTH = )4M" "\\132K" _small "${_text}")
if(_small STREQUAL _text)
  message(FATAL_ERROR "could not shrink the RAM region in ${SCRIPT}")
endif()
file(WRITE ${WORK_DIR}/overflow-ram-32k.ld "${_small}")
execute_process(
  COMMAND ${CXX} ${_cpu_flags} --specs=nano.specs -nostartfiles -Wl,--gc-sections
          -T${WORK_DIR}/overflow-ram-32k.ld -Wl,--print-memory-usage
          ${OBJECTS} -o ${WORK_DIR}/overflow-ram-32k.elf
  RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
message("${_out}")
if(_rc EQUAL 0)
  message(FATAL_ERROR "link succeeded although RAM overflows: the region check is not working")
endif()
if(NOT _out MATCHES "region `RAM' overflowed")
  message(FATAL_ERROR "link failed (${_rc}) but not with a RAM region overflow")
endif()
message("expect-overflow-fails: OK, ld rejected the overflowing image")
