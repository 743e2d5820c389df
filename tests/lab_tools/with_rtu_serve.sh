#!/usr/bin/env bash
# with_rtu_serve.sh MAGLEV_MODBUS_SERVE WORKDIR COMMAND...
# Starts `maglev-modbus-serve --rtu-pty 115200` (the firmware's RtuServer and
# the real kernel behind a new pseudo-terminal), waits for the pty's path, runs
# COMMAND with MAGLEV_RTU=PATH, stops the server and exits with COMMAND's status.
set -u
SERVE=$1; WORK=$2; shift 2
rm -rf "$WORK"; mkdir -p "$WORK"
"$SERVE" --rtu-pty 115200 --flash "$WORK/flash.bin" --port-file "$WORK/port" --seconds 120 >"$WORK/serve.log" 2>&1 &
PID=$!
cleanup() { kill "$PID" 2>/dev/null; wait "$PID" 2>/dev/null; }
trap cleanup EXIT
for _ in $(seq 100); do [ -s "$WORK/port" ] && break; kill -0 "$PID" 2>/dev/null || break; sleep 0.1; done
if [ ! -s "$WORK/port" ]; then echo "with_rtu_serve.sh: no pty from maglev-modbus-serve"; cat "$WORK/serve.log"; exit 1; fi
MAGLEV_RTU=$(cat "$WORK/port") "$@"; rc=$?
[ "$rc" -eq 0 ] || { echo "---- maglev-modbus-serve log ----"; cat "$WORK/serve.log"; }
exit "$rc"
