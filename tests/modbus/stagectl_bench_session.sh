#!/usr/bin/env bash
# stagectl session against the running HIL bench (kernel + plant):
#   maglev-hil serve --modbus-tcp 127.0.0.1:PORT
# levitate, move x by 1 mm, status, land -- each through stagectl, checked.
# usage: stagectl_bench_session.sh STAGECTL MAGLEV_HIL WORKDIR
set -u
STAGECTL=$1; HIL=$2; WORK=$3
rm -rf "$WORK"; mkdir -p "$WORK"
PORT=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"$HIL" serve --modbus-tcp "127.0.0.1:$PORT" >"$WORK/hil.log" 2>&1 &
HIL_PID=$!
trap 'kill $HIL_PID 2>/dev/null; wait $HIL_PID 2>/dev/null' EXIT
S() { "$STAGECTL" --tcp "127.0.0.1:$PORT" "$@"; }
for _ in $(seq 100); do S get id.magic >/dev/null 2>&1 && break; sleep 0.1; done
if ! kill -0 "$HIL_PID" 2>/dev/null || ! S get id.magic >/dev/null 2>&1; then
  echo "maglev-hil serve did not come up on 127.0.0.1:$PORT:"; cat "$WORK/hil.log"
  echo "0 passed, 1 failed"; exit 1
fi
fails=0; passes=0
check() { if eval "$2"; then passes=$((passes + 1)); else fails=$((fails + 1)); echo "FAIL: $1"; fi; }
val() { S get "$1" | sed -e 's/.* = //' -e 's/ *#.*//'; }

S levitate --wait 20; check "levitate reaches ready" '[ $? -eq 0 ]'
check "state ready" '[ "$(val status.state)" = 6 ]'
x0=$(val status.x)
S move-by x 1mm --wait 10; check "move x by 1 mm" '[ $? -eq 0 ]'
x1=$(val status.x)
check "x moved 1 mm (+-1 um): $x0 -> $x1" "python3 -c 'import sys; sys.exit(0 if abs(($x1)-($x0)-1e-3) < 1e-6 else 1)'"
S status >"$WORK/status.txt"; check "status" '[ $? -eq 0 ]'
grep -q "state      = ready" "$WORK/status.txt"; check "status says ready" '[ $? -eq 0 ]'
S land --wait 20; check "land" '[ $? -eq 0 ]'
check "state idle" '[ "$(val status.state)" = 0 ]'
echo "$passes passed, $fails failed"
[ "$fails" -eq 0 ]
