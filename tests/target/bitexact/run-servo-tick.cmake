# cmake -DRECORDER=<kernel-vector-recorder> -DCOMPARE=<kernel-bitexact-compare>
#       -DQEMU=<qemu-system-arm> -DELF=<maglev-qemu-servo-tick.elf> -DWORKDIR=<dir> -DTIMEOUT=<s>
#       -DMAX_READY_INSTRUCTIONS=<n> -P run-servo-tick.cmake
#
# The board's whole servo interrupt at 20 kHz (firmware/board/mps2_an500/servo_tick):
# 1. record a closed-loop session at 20 kHz (kernel-vector-recorder --rate 20000);
# 2. run it through ServoLoop<Controller<float>>::on_tick() with the production
#    drivers on the fake register bus, under -icount shift=6 (the image exits
#    non-zero if the drivers' sample or DAC traffic differs from the record);
# 3. the outputs the drivers drove, both passes, bit for bit against the host kernel;
# 4. a Ready on_tick() may not exceed MAX_READY_INSTRUCTIONS (the measured
#    maximum + 10 %: a regression guard, docs/PERFORMANCE.md).
# A missing image FAILS (the host build builds it: build-replay-image.cmake).
if(NOT EXISTS "${ELF}")
  message(FATAL_ERROR "servo-tick: the M7 image ${ELF} does not exist. The host build makes it "
                      "(target maglev-qemu-kernel-replay-image); directly: cmake --preset qemu-m7 && "
                      "cmake --build build/qemu-m7 --target maglev-qemu-servo-tick")
endif()
if(NOT QEMU)
  message(FATAL_ERROR "servo-tick: qemu-system-arm not found; run ./cmake/setup-debian.sh")
endif()
file(MAKE_DIRECTORY ${WORKDIR})
set(_vectors ${WORKDIR}/vectors.bin)
set(_host ${WORKDIR}/host_outputs.bin)
set(_tick ${WORKDIR}/target_outputs_tick.bin)
set(_step ${WORKDIR}/target_outputs_step.bin)
file(REMOVE ${_tick} ${_step})

execute_process(COMMAND ${RECORDER} ${_vectors} ${_host} --rate 20000 RESULT_VARIABLE _rc OUTPUT_VARIABLE _out
                ERROR_VARIABLE _out)
message("${_out}")
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "servo-tick: the recorder failed (${_rc})")
endif()

set(_cmd ${QEMU} -M mps2-an500 -nographic -monitor none -serial null -semihosting-config enable=on,target=native
         -icount shift=6 -kernel ${ELF} -append "${_vectors} ${_tick} ${_step} --icount")
string(REPLACE ";" " " _shown "${_cmd}")
message("servo-tick: ${_shown}")
execute_process(COMMAND ${_cmd} INPUT_FILE /dev/null RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out
                TIMEOUT ${TIMEOUT})
message("${_out}")
set(_qemu_out "${_out}")
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "servo-tick: the image failed under QEMU (status ${_rc})")
endif()

foreach(_target ${_tick} ${_step})
  execute_process(COMMAND ${COMPARE} ${_host} ${_target} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
  message("${_out}")
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "servo-tick: the outputs the drivers drove (${_target}) differ from the host kernel's")
  endif()
endforeach()

if(NOT _qemu_out MATCHES "servo_tick_instructions Ready: ticks=([0-9]+) min=([0-9]+) mean=([0-9.]+) max=([0-9]+)")
  message(FATAL_ERROR "servo-tick: the image printed no Ready servo_tick_instructions line")
endif()
set(_ready_ticks ${CMAKE_MATCH_1})
set(_ready_max ${CMAKE_MATCH_4})
if(_ready_ticks LESS 1000)
  message(FATAL_ERROR "servo-tick: only ${_ready_ticks} Ready ticks measured")
endif()
if(NOT _qemu_out MATCHES "servo_step_instructions Ready: ticks=[0-9]+ min=[0-9]+ mean=[0-9.]+ max=[0-9]+")
  message(FATAL_ERROR "servo-tick: the image printed no Ready servo_step_instructions line")
endif()
if(_ready_max GREATER MAX_READY_INSTRUCTIONS)
  message(FATAL_ERROR "servo-tick: a Ready on_tick() took ${_ready_max} instructions > ${MAX_READY_INSTRUCTIONS} "
                      "(measured maximum + 10 %, docs/PERFORMANCE.md)")
endif()
message("servo-tick: Ready on_tick() max ${_ready_max} instructions <= ${MAX_READY_INSTRUCTIONS}")
