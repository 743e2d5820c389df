#!/bin/sh
# Runs INSIDE the test VM: can-utils <-> our codec, both directions.
#   interop.sh TOOL DBC
set -eu
TOOL="$1"
DBC="$2"
OUT="${TMPDIR:-/tmp}/candump.log"
echo "== cansend (our frame) -> candump -> DBC decode"
candump -L -n 1 vcan0 > "$OUT" &
DUMP=$!
sleep 0.3
FRAME="$("$TOOL" print-sensor 7 42)"
echo "cansend vcan0 $FRAME"
cansend vcan0 "$FRAME"
wait $DUMP
cat "$OUT"
"$TOOL" check-candump "$DBC" 7 42 < "$OUT"
echo "== cansend -> our SocketCAN receiver"
READY="${TMPDIR:-/tmp}/ready"
"$TOOL" receive-sensor vcan0 8 43 > "$READY" &
RX=$!
i=0
while ! grep -q ready "$READY" 2>/dev/null; do
  i=$((i + 1)); [ $i -gt 100 ] && { echo "receiver did not start"; exit 1; }
  sleep 0.05
done
cansend vcan0 "$("$TOOL" print-sensor 8 43)"
wait $RX
cat "$READY"
echo "interop OK"
