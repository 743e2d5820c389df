# cmake -DRECORDER=<kernel-vector-recorder> -DCOMPARE=<kernel-bitexact-compare>
#       -DQEMU=<qemu-system-arm> -DELF=<maglev-qemu-servo-tick.elf> -DWORKDIR=<dir> -DTIMEOUT=<s>
#       -DMAX_READY_INSTRUCTIONS=<n> -DMAX_READY_DAC_IRQ_INSTRUCTIONS=<n> -DMAX_READY_ADC_IRQ_INSTRUCTIONS=<n>
#       -DMAX_BOARD_INSTRUCTIONS=<n> -P run-servo-tick.cmake
#
# The board's whole servo interrupt at 20 kHz (firmware/board/mps2_an500/servo_tick):
# 1. record a closed-loop session at 20 kHz (kernel-vector-recorder --rate 20000);
# 2. run it through ServoLoop<Controller<float>>::on_tick() with the production
#    drivers on the fake register bus, under -icount shift=6 (the image exits
#    non-zero if the drivers' sample or DAC traffic differs from the record);
# 3. the outputs the drivers drove, both passes, bit for bit against the host kernel;
# 4. a Ready on_tick() may not exceed MAX_READY_INSTRUCTIONS, nor the DAC
#    chain's four SPI1 interrupt bodies after it MAX_READY_DAC_IRQ_INSTRUCTIONS,
#    nor the ADC chain's three bodies before it MAX_READY_ADC_IRQ_INSTRUCTIONS,
#    nor the board estimate (5.) MAX_BOARD_INSTRUCTIONS (each the measured
#    figure + 10 %: regression guards, docs/PERFORMANCE.md).
# A missing image FAILS (the host build builds it: build-replay-image.cmake).
include(${CMAKE_CURRENT_LIST_DIR}/bitexact-steps.cmake)
maglev_bitexact_preflight(servo-tick "${QEMU}" "${ELF}"
  "The host build makes it (target maglev-qemu-kernel-replay-image). Directly: cmake --preset qemu-m7 && "
  "cmake --build build/qemu-m7 --target maglev-qemu-servo-tick")
file(MAKE_DIRECTORY ${WORKDIR})
set(_vectors ${WORKDIR}/vectors.bin)
set(_host ${WORKDIR}/host_outputs.bin)
set(_tick ${WORKDIR}/target_outputs_tick.bin)
set(_step ${WORKDIR}/target_outputs_step.bin)
file(REMOVE ${_tick} ${_step})

maglev_bitexact_record(servo-tick ${RECORDER} ${_vectors} ${_host} --rate 20000)
maglev_qemu_run(servo-tick "${QEMU}" "${ELF}" "${_vectors} ${_tick} ${_step} --icount" 6 ${TIMEOUT} _qemu_out)

foreach(_target ${_tick} ${_step})
  execute_process(COMMAND ${COMPARE} ${_host} ${_target} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
  message("${_out}")
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "servo-tick: the outputs the drivers drove (${_target}) differ from the host kernel's")
  endif()
endforeach()

if(NOT _qemu_out MATCHES "servo_step_instructions Ready: ticks=[0-9]+ min=[0-9]+ mean=[0-9.]+ max=[0-9]+")
  message(FATAL_ERROR "servo-tick: the image printed no Ready servo_step_instructions line")
endif()
maglev_check_ready_instructions(servo-tick "${_qemu_out}" servo_tick_instructions "on_tick()" ${MAX_READY_INSTRUCTIONS})
maglev_check_ready_instructions(servo-tick "${_qemu_out}" dac_irq_instructions "DAC chain's SPI1 interrupt work"
                                ${MAX_READY_DAC_IRQ_INSTRUCTIONS})
maglev_check_ready_instructions(servo-tick "${_qemu_out}" adc_dma_isr_instructions "ADC chain's interrupt work"
                                ${MAX_READY_ADC_IRQ_INSTRUCTIONS})

# 5. The board's whole interrupt work per tick, estimated from what the image
#    measured: the Ready on_tick() maximum with the fake's own share of the
#    sensor source, the actuator sink and the next-tick check (the only
#    register accesses in on_tick()) replaced by the same code on the
#    memory-cost bus (one load / store per register), plus the ADC chain's
#    three and the DAC chain's four interrupt bodies on that bus, plus the
#    seven handlers' own statements around them (DWT CYCCNT reads and the
#    InterruptMeter, EXTI clear, null checks: main.cpp's, replayed). Budget
#    (issue 16, item 3): 25 % of the 50 us period at 20 kHz, CPI 1, 480 MHz.
function(_servo_tick_max output line out)
  if(NOT output MATCHES "${line}: ticks=[0-9]+ min=[0-9]+ mean=[0-9.]+ max=([0-9]+)")
    message(FATAL_ERROR "servo-tick: the image printed no '${line}' line")
  endif()
  set(${out} ${CMAKE_MATCH_1} PARENT_SCOPE)
endfunction()
_servo_tick_max("${_qemu_out}" "servo_tick_instructions Ready" _on_tick)
_servo_tick_max("${_qemu_out}" "servo_sensors_instructions Ready" _sensors_fake)
_servo_tick_max("${_qemu_out}" "servo_actuators_instructions Ready" _actuators_fake)
_servo_tick_max("${_qemu_out}" "drivers_on_memory_bus sensors" _sensors_bus)
_servo_tick_max("${_qemu_out}" "drivers_on_memory_bus actuators" _actuators_bus)
_servo_tick_max("${_qemu_out}" "drivers_on_memory_bus adc_dma_isr" _adc_bus)
_servo_tick_max("${_qemu_out}" "drivers_on_memory_bus dac_irq" _dac_bus)
_servo_tick_max("${_qemu_out}" "drivers_on_fake_bus next_tick_check" _next_fake)
_servo_tick_max("${_qemu_out}" "drivers_on_memory_bus next_tick_check" _next_bus)
_servo_tick_max("${_qemu_out}" "drivers_on_memory_bus handler_wrappers" _wrappers)
math(EXPR _board "${_on_tick} - (${_sensors_fake} - ${_sensors_bus}) - (${_actuators_fake} - ${_actuators_bus}) - (${_next_fake} - ${_next_bus}) + ${_adc_bus} + ${_dac_bus} + ${_wrappers}")
math(EXPR _permille "${_board} * 1000 / 24000")
message("servo-tick: board interrupt work per Ready tick ~${_board} instructions = on_tick ${_on_tick} "
        "- fake share (sensors ${_sensors_fake} - ${_sensors_bus}, actuators ${_actuators_fake} - ${_actuators_bus}, "
        "next-tick check ${_next_fake} - ${_next_bus}) "
        "+ ADC bodies ${_adc_bus} + DAC bodies ${_dac_bus} + the seven handlers' own work ${_wrappers}: "
        "${_permille} permille of 50 us at CPI 1 (budget 250, 6000 instructions; the seven exception "
        "entries and exits, ~12 + ~10 cycles each on the M7, are cycles, not instructions, and not in this figure)")
if(_board GREATER MAX_BOARD_INSTRUCTIONS)
  message(FATAL_ERROR "servo-tick: board interrupt work ${_board} instructions > ${MAX_BOARD_INSTRUCTIONS} "
                      "(the measured figure + 10 %, docs/PERFORMANCE.md)")
endif()
