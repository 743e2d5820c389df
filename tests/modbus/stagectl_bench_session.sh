#!/usr/bin/env bash
# stagectl session against the running HIL bench (kernel + plant, real time):
#   maglev-hil serve --modbus-tcp 127.0.0.1:PORT --flash WORK/flash.bin
# Through stagectl only: slow the x profile down (landed-only write), levitate
# (wait for Ready), move x to current + 1 mm, try `save` DURING the move (the
# "not moving" rule: exception 06 -> stagectl exit 5), wait for the move to
# end, check x moved 1 mm (+-1 um) and status says ready, `save` again (now
# allowed: 0), land (wait for Idle), select the square stage and levitate it
# (the bench rebuilds its plant), land, set servo.rate 10 kHz (the bench
# re-times), levitate and land at it, stop the server (SIGTERM, exit 0).
# Any deviation fails the test and prints the server's log.
# usage: stagectl_bench_session.sh STAGECTL MAGLEV_HIL WORKDIR
set -u
STAGECTL=$1; HIL=$2; WORK=$3
rm -rf "$WORK"; mkdir -p "$WORK"
T0=$(date +%s.%N)
PORT=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"$HIL" serve --modbus-tcp "127.0.0.1:$PORT" --flash "$WORK/flash.bin" >"$WORK/hil.log" 2>&1 &
HIL_PID=$!
cleanup() { kill "$HIL_PID" 2>/dev/null; wait "$HIL_PID" 2>/dev/null; }
trap cleanup EXIT
S() { "$STAGECTL" --tcp "127.0.0.1:$PORT" "$@"; }
fails=0; passes=0
fail() { fails=$((fails + 1)); echo "FAIL: $*"; }
pass() { passes=$((passes + 1)); echo "ok:   $*"; }
finish() {
  echo "session wall time: $(python3 -c "print(f'{$(date +%s.%N) - $T0:.2f}')") s"
  if [ "$fails" -ne 0 ]; then echo "---- maglev-hil serve log ----"; cat "$WORK/hil.log"; fi
  echo "$passes passed, $fails failed"
  [ "$fails" -eq 0 ]; exit $?
}
# expect RC TEXT CMD...: run a stagectl command, its exit code must be RC.
expect() {
  local want=$1 what=$2; shift 2
  S "$@" >"$WORK/last.out" 2>&1; local rc=$?
  if [ "$rc" -eq "$want" ]; then pass "$what (exit $rc)"; else fail "$what: exit $rc, expected $want: $(cat "$WORK/last.out")"; fi
}
val() { S get "$1" | sed -e 's/.* = //' -e 's/ *#.*//'; }
# within A B TOL: |A - B| <= TOL
within() { python3 -c "import sys; sys.exit(0 if abs(($1) - ($2)) <= $3 else 1)"; }

for _ in $(seq 100); do S get id.magic >/dev/null 2>&1 && break; sleep 0.1; done
if ! kill -0 "$HIL_PID" 2>/dev/null || ! S get id.magic >/dev/null 2>&1; then
  fail "maglev-hil serve did not come up on 127.0.0.1:$PORT"; finish
fi
grep -q "listening on 127.0.0.1:$PORT" "$WORK/hil.log" && pass "server prints its address" || fail "no address line"

# Landed: profile limits are writable; 1 mm/s makes the 1 mm move last ~1 s
# (time for the two requests below even on a loaded machine).
expect 0 "max_velocity.x = 1 mm/s while landed" set max_velocity.x 1mm/s
expect 0 "levitate, wait for ready" --wait 20 levitate
[ "$(val status.state)" = 6 ] && pass "state ready" || fail "state $(val status.state), expected 6"
# Levitated: a landed-only write is busy (06 -> 5).
expect 5 "max_velocity.x while levitated is busy" set max_velocity.x 3mm/s

x0=$(val status.x)
target=$(python3 -c "print(repr($x0 + 1e-3))")
expect 0 "move x to $target (x0 $x0 + 1 mm)" move x "$target"
# During the move: status.moving = 1 and config.save (not moving) -> 06 -> 5.
moving=$(val status.moving)
[ "$moving" = 1 ] && pass "status.moving = 1 during the move" || fail "status.moving = $moving during the move"
expect 5 "save during the move is refused busy (06)" --engineer save
# Wait for the end of the move (status.moving back to 0), 10 s at most.
ok=0
for _ in $(seq 200); do
  if [ "$(val status.moving)" = 0 ]; then ok=1; break; fi
  sleep 0.05
done
[ "$ok" = 1 ] && pass "move finished (status.moving = 0)" || fail "still moving after 10 s"
sleep 0.2  # settle (the loop's tracking error after the profile end)
x1=$(val status.x)
within "$x1 - $x0" 1e-3 1e-6 && pass "x moved 1 mm +-1 um: $x0 -> $x1" || fail "x moved $x0 -> $x1, not 1 mm +-1 um"
S status >"$WORK/status.txt"; rc=$?
[ "$rc" = 0 ] && grep -q "state      = Ready" "$WORK/status.txt" && pass "status says ready" ||
  fail "status (exit $rc): $(cat "$WORK/status.txt")"
# Not moving any more: the same save is allowed.
expect 0 "save after the move" --engineer save
expect 0 "land, wait for idle" --wait 20 land
[ "$(val status.state)" = 0 ] && pass "state idle" || fail "state $(val status.state), expected 0"
within "$(val status.z)" 0 5e-6 && pass "z back at rest" || fail "z = $(val status.z) after landing"

# Another stage selected over Modbus (landed): the bench's plant is rebuilt
# from its profile, so that stage levitates (it faulted on the boot stage's
# plant: FollowingError 0.17 s into the square stage's levitation).
expect 0 "select the square stage (stage.profile 1)" --engineer set stage.profile 1
expect 0 "the square stage levitates, wait for ready" --wait 20 levitate
[ "$(val status.state)" = 6 ] && pass "square stage ready" || fail "square stage state $(val status.state), fault $(val status.fault)"
grep -q "stage.profile 1 (nk2020-square) selected: the bench's plant rebuilt" "$WORK/hil.log" &&
  pass "the bench says it rebuilt the plant" || fail "no plant rebuild line"
expect 5 "switching the stage while levitated is busy (06)" --engineer set stage.profile 0
expect 0 "land the square stage" --wait 20 land

# The servo rate written landed: the kernel re-designs its loops and the bench
# re-times with it (the plant steps at 10 kHz, the loop is paced at it), as the
# board re-times its tick timer; until 2026-11-29 serve stopped here.
expect 0 "servo.rate 10 kHz (landed)" --engineer set servo.rate 10000
sleep 0.3
grep -q "servo.rate 10000 Hz: the bench's plant steps and its loop is paced at it" "$WORK/hil.log" &&
  pass "the bench says it re-timed" || fail "no re-time line"
kill -0 "$HIL_PID" 2>/dev/null && pass "serve still running after the rate change" || fail "serve stopped at the rate change"
expect 0 "levitate at 10 kHz, wait for ready" --wait 30 levitate
[ "$(val status.state)" = 6 ] && pass "ready at 10 kHz" || fail "state $(val status.state), fault $(val status.fault) at 10 kHz"
expect 0 "land at 10 kHz" --wait 30 land

kill -TERM "$HIL_PID"; wait "$HIL_PID"; rc=$?; trap - EXIT
[ "$rc" = 0 ] && pass "server stops on SIGTERM (exit 0)" || fail "server exit $rc on SIGTERM"
grep -q "maglev-hil serve: stopped after" "$WORK/hil.log" && pass "server summary printed" || fail "no summary line"
grep "stopped after" "$WORK/hil.log"
finish
