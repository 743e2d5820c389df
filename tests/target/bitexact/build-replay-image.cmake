# cmake -DSOURCE_DIR=<repo> -DBUILD_DIR=<repo>/build/qemu-m7 -P build-replay-image.cmake
#
# Part of the host build (target maglev-qemu-kernel-replay-image, in ALL): the
# host-side bit-exact tests replay on the qemu-m7 build's replay images (the
# paper-000 kernel's, paper 002's and paper 001's, and the whole servo tick's), so the host preset builds
# those targets of the qemu-m7 build, in one build of that tree, -- configuring it with its preset if it was never
# configured. `ctest --preset host` then passes without a separate qemu-m7
# workflow; in CI (.ci/run: the qemu-m7 workflow first) it is an up-to-date
# no-op. Any failure stops the host build and says what to run.
if(NOT EXISTS "${BUILD_DIR}/CMakeCache.txt")
  message(STATUS "kernel replay image: configuring ${BUILD_DIR} (cmake --preset qemu-m7)")
  execute_process(COMMAND ${CMAKE_COMMAND} --preset qemu-m7 WORKING_DIRECTORY ${SOURCE_DIR}
                  RESULT_VARIABLE _rc)
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "kernel replay image: 'cmake --preset qemu-m7' failed (${_rc}). The host build needs the "
                        "cross toolchain for the bit-exact tests' M7 image: run ./cmake/setup-debian.sh, or point "
                        "the host build at an existing image with -DMAGLEV_KERNEL_REPLAY_ELF=<path>.")
  endif()
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BUILD_DIR} --target maglev-qemu-kernel-replay maglev-qemu-pmlsm-replay
                        maglev-qemu-selfstab-replay maglev-qemu-servo-tick
                RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "kernel replay images: 'cmake --build ${BUILD_DIR} --target maglev-qemu-kernel-replay "
                      "maglev-qemu-pmlsm-replay maglev-qemu-selfstab-replay maglev-qemu-servo-tick' failed (${_rc}); fix the qemu-m7 build (cmake --workflow --preset qemu-m7 shows it).")
endif()
