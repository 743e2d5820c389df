// Where code goes on the board: the servo tick in ITCM, configuration in flash.
//
// The STM32H743 image runs the whole servo path from the 64 KB ITCM (0 wait
// states, no flash-cache misses: a deterministic tick), and linker/stm32h743.ld
// puts the kernel libraries there whole. Configuration-time code -- loop
// designs and their margin checks, reference planning, table computations,
// validation, constructors -- runs once per configuration or command, never in
// the tick, yet took half of that ITCM; the tick itself could not be built at
// -O3 (issue 16: -13 % instructions per step) for lack of room.
//
// MAGLEV_CONFIG_CODE marks such a function [[gnu::cold]]: GCC optimizes it for
// size and emits it in .text.unlikely.*, which linker/stm32h743.ld keeps in
// flash ahead of the ITCM patterns. Calls to it are also laid out as unlikely
// paths, which is what they are. On the host it changes nothing observable
// (no floating-point contraction anywhere: -ffp-contract=off), so outputs stay
// bit-identical across builds. Anything NOT marked stays in ITCM: forgetting
// the mark costs ITCM bytes, never tick time.
#pragma once

#define MAGLEV_CONFIG_CODE [[gnu::cold]]

// MAGLEV_FAULT_PATH_CODE marks code the tick runs only on a tick where a
// fault check trips (the supervisor's attribution of the first fault):
// flash, like configuration code. Such a tick runs a few hundred
// instructions from flash instead of ITCM (a few microseconds at most,
// once: the latch holds the reaction after it), and the ITCM keeps its
// room for the tick's every-tick path (4.3 KB, issue 16).
#define MAGLEV_FAULT_PATH_CODE [[gnu::cold]]
