#!/usr/bin/env bash
# stagectl against maglev-modbus-serve (the real kernel, not stepped) over
# Modbus TCP on 127.0.0.1: get/set with units, dump, status, config
# export/import, save + restart (FileFlash), and every error path's exit code.
# usage: stagectl_session.sh STAGECTL SERVE WORKDIR
set -u
STAGECTL=$1; SERVE=$2; WORK=$3
rm -rf "$WORK"; mkdir -p "$WORK"
fails=0; passes=0
SERVER_PID=""

start_server() {
  rm -f "$WORK/port"
  "$SERVE" --tcp 127.0.0.1:0 --flash "$WORK/flash.bin" --port-file "$WORK/port" --seconds 120 >"$WORK/serve.log" 2>&1 &
  SERVER_PID=$!
  for _ in $(seq 100); do [ -s "$WORK/port" ] && break; sleep 0.05; done
  PORT=$(cat "$WORK/port")
}
stop_server() { kill "$SERVER_PID" 2>/dev/null; wait "$SERVER_PID" 2>/dev/null; }
trap stop_server EXIT

# expect EXIT_CODE "description" -- args...
expect() {
  local want=$1 what=$2; shift 3
  "$STAGECTL" --tcp "127.0.0.1:$PORT" "$@" >"$WORK/out" 2>"$WORK/err"
  local got=$?
  if [ "$got" -eq "$want" ]; then passes=$((passes + 1)); else
    fails=$((fails + 1)); echo "FAIL: $what: exit $got, expected $want"; cat "$WORK/out" "$WORK/err"; fi
}
# contains FILE TEXT "description"
contains() {
  if grep -qF -- "$2" "$1"; then passes=$((passes + 1)); else
    fails=$((fails + 1)); echo "FAIL: $3: '$2' not in $1:"; cat "$1"; fi
}

start_server
expect 0 "get identity" -- get id.magic
contains "$WORK/out" "id.magic = 19788" "magic 0x4D4C"
expect 0 "set with units" -- --engineer set gain.x.kp 30000
contains "$WORK/out" "gain.x.kp = 30000  # A/m" "kp read back"
expect 0 "set mm" -- set max_velocity.x 120mm/s
contains "$WORK/out" "max_velocity.x = 0.119999997  # m/s" "mm/s converted"
expect 0 "set um" -- --engineer set following_error.z 12 um
contains "$WORK/out" "following_error.z = 1.20000004e-05  # m" "um converted"
expect 0 "status" -- status
contains "$WORK/out" "state      = Idle (0)" "status state"
contains "$WORK/out" "[unsaved changes]" "unsaved flag"
expect 0 "dump" -- dump
contains "$WORK/out" "gain.theta_y.effort_limit = 4  # A" "dump has the last axis"
[ "$(wc -l <"$WORK/out")" -gt 100 ] && passes=$((passes + 1)) || { fails=$((fails + 1)); echo "FAIL: dump too short"; }

# --- errors: each names the register, the value and the range ---------------
expect 3 "unknown register" -- get gain.w.kp
contains "$WORK/err" "unknown register 'gain.w.kp'" "unknown name"
expect 3 "out of range (local check)" -- --engineer set limit.peak_current 6A
contains "$WORK/err" "limit.peak_current: value 6A is out of range [0, 5] A" "range message"
# Inside the board's 5 A, beyond the seed stage's own 4 A: the kernel refuses it, and says why.
expect 4 "beyond the stage's own limit" -- --engineer set limit.peak_current 4.5A
contains "$WORK/err" "status.config_error 15 BeyondStageLimits" "stage limit message"
expect 3 "wrong unit" -- --engineer set limit.peak_current 2mm
contains "$WORK/err" "unit 'mm' does not fit 'A'" "unit message"
expect 6 "engineer register without --engineer" -- set gain.x.kd 50
contains "$WORK/err" "engineer access required" "access message"
expect 4 "read-only register" -- set status.state 3
expect 7 "move while landed" -- move x 1mm
contains "$WORK/err" "not ready" "kernel result"
expect 1 "usage" -- frobnicate
expect 3 "bad axis value" -- move x 0.5
expect 0 "home" -- home
expect 5 "gain while homing (busy)" -- --engineer set gain.x.kp 31000
contains "$WORK/err" "gain.x.kp (address 1000) value 31000 now: controller busy" "busy message"
stop_server

# --- export / import / save / restart ------------------------------------------
start_server
expect 0 "export defaults" -- config export "$WORK/defaults.txt"
contains "$WORK/defaults.txt" "gain.x.kp = 36000  # A/m" "export format"
sed -e 's/^gain.z.kp = .*/gain.z.kp = 41000  # A\/m/' -e 's/^seq.nominal_height = .*/seq.nominal_height = 25  # um/' \
  "$WORK/defaults.txt" >"$WORK/new.txt"
expect 0 "import" -- --engineer config import "$WORK/new.txt"
contains "$WORK/out" "imported $(grep -c ' = ' "$WORK/defaults.txt") entries" "import count"
expect 0 "save" -- --engineer save
contains "$WORK/out" "saved (sequence 1)" "save sequence"
printf 'gain.z.kp = 41000\nlimit.rms_current = 9  # A\nnot.a.register = 1\n' >"$WORK/bad.txt"
expect 9 "import with errors writes nothing" -- --engineer config import "$WORK/bad.txt"
contains "$WORK/err" "bad.txt:2: limit.rms_current: value 9 is out of range [0, 5] A" "import range error"
contains "$WORK/err" "bad.txt:3: 'not.a.register' is not a configuration register" "import name error"
stop_server
start_server
expect 0 "after restart" -- get gain.z.kp
contains "$WORK/out" "gain.z.kp = 41000  # A/m" "saved gain survives a restart"
expect 0 "after restart" -- get seq.nominal_height
contains "$WORK/out" "seq.nominal_height = 2.49999994e-05  # m" "um from the unit comment"
expect 0 "status after restart" -- status
contains "$WORK/out" "flags 0x1 reason 0 sequence 1" "loaded from bank A"
stop_server

# --- the same client over Modbus RTU: the firmware RtuServer on a pty -----------
rm -f "$WORK/port"
"$SERVE" --rtu-pty 115200 --flash "$WORK/flash.bin" --port-file "$WORK/port" --seconds 60 >"$WORK/serve-rtu.log" 2>&1 &
SERVER_PID=$!
for _ in $(seq 100); do [ -s "$WORK/port" ] && break; sleep 0.05; done
PTY=$(cat "$WORK/port")
rtu() {
  local want=$1 what=$2; shift 3
  "$STAGECTL" --rtu "$PTY,115200" "$@" >"$WORK/out" 2>"$WORK/err"
  local got=$?
  if [ "$got" -eq "$want" ]; then passes=$((passes + 1)); else
    fails=$((fails + 1)); echo "FAIL: rtu $what: exit $got, expected $want"; cat "$WORK/out" "$WORK/err"; fi
}
rtu 0 "get over RTU" -- get gain.z.kp
contains "$WORK/out" "gain.z.kp = 41000  # A/m" "RTU reads the saved gain"
rtu 0 "set over RTU" -- --engineer set gain.x.ki 2.5e6
contains "$WORK/out" "gain.x.ki = 2500000  # A/(m*s)" "RTU write"
rtu 3 "range over RTU" -- --engineer set gain.x.derivative_filter 20kHz
contains "$WORK/err" "gain.x.derivative_filter: value 20kHz is out of range [1, 10000] Hz" "RTU range message"
# In the map's range, at or above this servo rate's Nyquist (2.5 kHz: 1250 Hz): the kernel refuses it.
rtu 4 "above the rate's Nyquist over RTU" -- --engineer set gain.x.derivative_filter 2kHz
contains "$WORK/err" "status.config_error 3 AxisLoop" "RTU Nyquist refusal"
rtu 7 "move over RTU" -- move y 1mm
rtu 0 "status over RTU" -- status
contains "$WORK/out" "state      = Idle (0)" "RTU status"
stop_server

# --- cannot connect --------------------------------------------------------------
PORT=1
expect 2 "connection refused" -- status
echo "$passes passed, $fails failed"
[ "$fails" -eq 0 ]
