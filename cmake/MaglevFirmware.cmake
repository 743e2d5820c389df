# Firmware image helpers (cross builds only).
#
# maglev_firmware_image(TARGET <exe> LINKER_SCRIPT <path> [CHECK_LABEL <label>])
#
#   <exe> is an add_executable() target built with the arm-none-eabi toolchain.
#   This function:
#     * links it with -nostartfiles -T <path> (the board's startup code owns the
#       reset handler: copy .data, zero .bss, FPU on, static constructors),
#       -Wl,--print-memory-usage (GNU ld prints RAM/FLASH use per MEMORY region;
#       a region overflow FAILS the link) and -Wl,-Map=<exe>.map;
#     * names the ELF <exe>.elf;
#     * links the no-heap runtime hooks (cmake/runtime/no_heap_runtime.c);
#     * POST_BUILD: writes <exe>.bin and <exe>.hex next to the ELF and prints
#       the per-region memory table again (regions from the map file, sections
#       from objdump -h: what ld's --print-memory-usage shows, but also in
#       builds where the link step's output scrolled away);
#     * registers ctest <exe>-no-heap (label CHECK_LABEL, default "target")
#       running cmake/check-no-heap.sh on the ELF.
#
# Boards call it from firmware/board/<board>/CMakeLists.txt, e.g.
#   add_executable(maglev-stm32h743 ...)
#   maglev_set_warnings(maglev-stm32h743)
#   maglev_firmware_image(TARGET maglev-stm32h743
#                         LINKER_SCRIPT ${PROJECT_SOURCE_DIR}/linker/stm32h743.ld)

set(MAGLEV_CMAKE_DIR ${CMAKE_CURRENT_LIST_DIR})

if(CMAKE_CROSSCOMPILING AND NOT TARGET maglev_firmware_runtime)
  add_library(maglev_firmware_runtime OBJECT ${MAGLEV_CMAKE_DIR}/runtime/no_heap_runtime.c)
  maglev_set_warnings(maglev_firmware_runtime)
endif()

function(maglev_firmware_image)
  cmake_parse_arguments(F "" "TARGET;LINKER_SCRIPT;CHECK_LABEL" "" ${ARGN})
  if(NOT F_TARGET OR NOT F_LINKER_SCRIPT)
    message(FATAL_ERROR "maglev_firmware_image: TARGET and LINKER_SCRIPT are required")
  endif()
  if(NOT CMAKE_CROSSCOMPILING)
    message(FATAL_ERROR "maglev_firmware_image(${F_TARGET}): only valid in a cross build")
  endif()
  if(NOT F_CHECK_LABEL)
    set(F_CHECK_LABEL target)
  endif()
  get_filename_component(_script ${F_LINKER_SCRIPT} ABSOLUTE)

  target_link_libraries(${F_TARGET} PRIVATE maglev_firmware_runtime)
  target_link_options(${F_TARGET} PRIVATE
    -nostartfiles
    -T${_script}
    -Wl,--print-memory-usage
    -Wl,-Map=$<TARGET_FILE_DIR:${F_TARGET}>/$<TARGET_FILE_BASE_NAME:${F_TARGET}>.map
    -Wl,--cref)
  set_property(TARGET ${F_TARGET} APPEND PROPERTY LINK_DEPENDS ${_script})
  set_target_properties(${F_TARGET} PROPERTIES SUFFIX ".elf")

  set(_base $<TARGET_FILE_DIR:${F_TARGET}>/$<TARGET_FILE_BASE_NAME:${F_TARGET}>)
  add_custom_command(TARGET ${F_TARGET} POST_BUILD
    COMMAND ${CMAKE_OBJCOPY} -O binary $<TARGET_FILE:${F_TARGET}> ${_base}.bin
    COMMAND ${CMAKE_OBJCOPY} -O ihex   $<TARGET_FILE:${F_TARGET}> ${_base}.hex
    COMMAND ${CMAKE_COMMAND} -DMAP=${_base}.map -DELF=$<TARGET_FILE:${F_TARGET}>
            -DOBJDUMP=${CMAKE_OBJDUMP} -P ${MAGLEV_CMAKE_DIR}/print-memory-usage.cmake
    VERBATIM)

  maglev_add_script_test(NAME ${F_TARGET}-no-heap LABEL ${F_CHECK_LABEL} TIMEOUT 60
    COMMAND sh ${MAGLEV_CMAKE_DIR}/check-no-heap.sh ${CMAKE_NM} $<TARGET_FILE:${F_TARGET}>)
  # Bit-exact by construction: no libm transcendental function in any image.
  maglev_add_script_test(NAME ${F_TARGET}-no-libm LABEL ${F_CHECK_LABEL} TIMEOUT 60
    COMMAND sh ${MAGLEV_CMAKE_DIR}/check-no-libm.sh ${CMAKE_NM} $<TARGET_FILE:${F_TARGET}>)
endfunction()

# maglev_add_qemu_test(NAME <test> IMAGE <exe> [LABEL target] [ARGS <word>...]
#                      [EXPECT_EXIT <code>] [EXPECT_REGEX <regex>] [TIMEOUT <s>])
#
#   Boots <exe> (an mps2-an500 image) under
#     qemu-system-arm -M mps2-an500 -nographic
#                     -semihosting-config enable=on,target=native -kernel <elf>
#   (ARGS go to the image's semihosting command line via -append) and passes
#   only if QEMU's exit status equals EXPECT_EXIT (default 0: the image's
#   main() returned 0) and, if given, the output matches EXPECT_REGEX.
#   A hung image is killed after TIMEOUT seconds (default 60) and fails.
find_program(MAGLEV_QEMU_SYSTEM_ARM qemu-system-arm)
function(maglev_add_qemu_test)
  cmake_parse_arguments(Q "" "NAME;IMAGE;LABEL;EXPECT_EXIT;EXPECT_REGEX;TIMEOUT" "ARGS" ${ARGN})
  if(NOT Q_LABEL)
    set(Q_LABEL target)
  endif()
  if(NOT Q_EXPECT_EXIT)
    set(Q_EXPECT_EXIT 0)
  endif()
  if(NOT Q_TIMEOUT)
    set(Q_TIMEOUT 60)
  endif()
  if(NOT MAGLEV_QEMU_SYSTEM_ARM)
    message(FATAL_ERROR "maglev_add_qemu_test(${Q_NAME}): qemu-system-arm not found; run ./cmake/setup-debian.sh")
  endif()
  string(REPLACE ";" " " _args "${Q_ARGS}")
  # The ctest timeout is a backstop; run-qemu-test.cmake kills QEMU first.
  math(EXPR _ctest_timeout "${Q_TIMEOUT} + 30")
  maglev_add_script_test(NAME ${Q_NAME} LABEL ${Q_LABEL} TIMEOUT ${_ctest_timeout}
    COMMAND ${CMAKE_COMMAND}
            -DQEMU=${MAGLEV_QEMU_SYSTEM_ARM}
            -DELF=$<TARGET_FILE:${Q_IMAGE}>
            "-DARGS=${_args}"
            -DEXPECT_EXIT=${Q_EXPECT_EXIT}
            "-DEXPECT_REGEX=${Q_EXPECT_REGEX}"
            -DTIMEOUT=${Q_TIMEOUT}
            -P ${MAGLEV_CMAKE_DIR}/run-qemu-test.cmake)
endfunction()
