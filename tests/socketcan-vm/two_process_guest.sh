#!/bin/sh
# Runs INSIDE the test VM: the controller and the plant as two processes over
# vcan0, lockstep; results into OUT (a 9p share, so they come back to the host).
#   two_process_guest.sh MAGLEV_HIL SCENARIO OUT
set -u
HIL="$1"; SC="$2"; OUT="$3"
rm -rf "$OUT"; mkdir -p "$OUT"
"$HIL" controller --can vcan0 --config "$SC" --out "$OUT" --duration 170 > "$OUT/controller.log" 2>&1 &
CPID=$!
T0=$(date +%s)
# 5 s for each actuator frame, not 200 ms: the VM is emulated (TCG), and on a
# loaded CI machine, in the sanitizer build, the controller can be starved past
# 200 ms; the test is about the frames and the bits, not the guest's speed.
"$HIL" plant "$SC" --can vcan0 --out "$OUT" --lockstep-timeout-ms 5000 --no-plots --quiet > "$OUT/plant.log" 2>&1
PRC=$?
# A plant that failed to start never sends a frame: stop the controller now
# rather than letting it wait out its 170 s duration.
if [ $PRC -ne 0 ]; then kill $CPID 2>/dev/null; fi
wait $CPID
CRC=$?
T1=$(date +%s)
cat "$OUT/controller.log" "$OUT/plant.log"
echo "two-process: plant rc $PRC, controller rc $CRC, $((T1 - T0)) s in the guest"
[ $PRC -eq 0 ] && [ $CRC -eq 0 ]
