# cmake -DSOURCE_DIR=<repo> -DBUILD_DIR=<repo>/build/qemu-m7 -DTARGET=<image target> -P build-selfstab-replay-image.cmake
#
# Part of the host build (target maglev-qemu-selfstab-replay-image, in ALL):
# builds paper 001's replay image in the qemu-m7 build, configuring it with
# its preset if it was never configured (as build-replay-image.cmake does for
# the paper-000 kernel's image).
if(NOT EXISTS "${BUILD_DIR}/CMakeCache.txt")
  execute_process(COMMAND ${CMAKE_COMMAND} --preset qemu-m7 WORKING_DIRECTORY ${SOURCE_DIR} RESULT_VARIABLE _rc)
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "selfstab replay image: 'cmake --preset qemu-m7' failed (${_rc}); run ./cmake/setup-debian.sh "
                        "or set -DMAGLEV_SELFSTAB_REPLAY_ELF=<path>.")
  endif()
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BUILD_DIR} --target ${TARGET} RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "selfstab replay image: 'cmake --build ${BUILD_DIR} --target ${TARGET}' failed (${_rc}).")
endif()
