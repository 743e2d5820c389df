# maglev_add_cpputest(NAME <name> LABEL <area> SOURCES ... [LIBS ...] [ARGS ...])
#
# Builds one CppUTest executable and registers it with ctest under the given
# area label (kernel, drivers, hil, can, socketcan-vm, modbus, target).
# CppUTest's main is tests/support/cpputest_main.cpp so every runner prints
# the same summary and returns non-zero on any failure.
# An issue's labels (bench, profiles, paper-001, ...) may follow the area:
# LABEL hil bench.
set(MAGLEV_TEST_LABELS kernel drivers hil can socketcan-vm modbus target
    bench profiles paper-001 paper-002 fidelity faults tools)

function(_maglev_check_labels fn name labels)
  if(labels STREQUAL "")
    message(FATAL_ERROR "${fn}(${name}): no LABEL")
  endif()
  foreach(_l IN LISTS labels)
    if(NOT _l IN_LIST MAGLEV_TEST_LABELS)
      message(FATAL_ERROR "${fn}(${name}): label '${_l}' is not one of ${MAGLEV_TEST_LABELS}")
    endif()
  endforeach()
endfunction()

function(maglev_add_cpputest)
  cmake_parse_arguments(T "" "NAME;TIMEOUT" "LABEL;SOURCES;LIBS;ARGS" ${ARGN})
  _maglev_check_labels(maglev_add_cpputest ${T_NAME} "${T_LABEL}")
  add_executable(${T_NAME} ${T_SOURCES} ${PROJECT_SOURCE_DIR}/tests/support/cpputest_main.cpp)
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} PkgConfig::CPPUTEST)
  # tests/support/*.hpp: fixtures shared across test folders.
  target_include_directories(${T_NAME} PRIVATE ${PROJECT_SOURCE_DIR}/tests/support/include)
  maglev_set_warnings(${T_NAME})
  # CppUTest's macros trip a few of our strict warnings; keep the rest.
  target_compile_options(${T_NAME} PRIVATE -Wno-old-style-cast -Wno-missing-declarations)
  add_test(NAME ${T_NAME} COMMAND ${T_NAME} ${T_ARGS})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  set_tests_properties(${T_NAME} PROPERTIES LABELS "${T_LABEL}" TIMEOUT ${T_TIMEOUT})
endfunction()

# maglev_add_script_test(NAME <name> LABEL <area> COMMAND ... [TIMEOUT s])
# For tests that are programs or scripts (VM tests, drift checks, QEMU runs).
function(maglev_add_script_test)
  cmake_parse_arguments(T "" "NAME;TIMEOUT;WORKING_DIRECTORY" "LABEL;COMMAND" ${ARGN})
  _maglev_check_labels(maglev_add_script_test ${T_NAME} "${T_LABEL}")
  if(NOT T_WORKING_DIRECTORY)
    set(T_WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
  endif()
  add_test(NAME ${T_NAME} COMMAND ${T_COMMAND} WORKING_DIRECTORY ${T_WORKING_DIRECTORY})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  set_tests_properties(${T_NAME} PROPERTIES LABELS "${T_LABEL}" TIMEOUT ${T_TIMEOUT})
endfunction()

# maglev_add_all_subdirectories(): add every immediate child folder that has a
# CMakeLists.txt, in name order. Lets each module own its own CMakeLists.txt
# without editing its parent. A module that is host-only or target-only
# returns early from its own CMakeLists.txt.
macro(maglev_add_all_subdirectories)
  file(GLOB _maglev_children LIST_DIRECTORIES true RELATIVE ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/*)
  list(SORT _maglev_children)
  foreach(_maglev_child IN LISTS _maglev_children)
    if(IS_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/${_maglev_child} AND EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${_maglev_child}/CMakeLists.txt)
      add_subdirectory(${_maglev_child})
    endif()
  endforeach()
endmacro()
