#!/bin/sh
# maglev-hil's paper 002 commands: list, run, check-profile, record-pmlsm,
# and their refusals (exit 2 with a reason). usage: pmlsm_cli.sh MAGLEV_HIL WORKDIR
set -eu
hil=$1
work=$2
rm -rf "$work"
mkdir -p "$work"
fail() { echo "pmlsm_cli: FAIL: $*"; exit 1; }

"$hil" list --profile fmp2009-pmlsm > "$work/list.txt"
grep -q "gap_step_7mm" "$work/list.txt" || fail "list does not name gap_step_7mm"
grep -q "tracking_4dof" "$work/list.txt" || fail "list does not name tracking_4dof"

"$hil" check-profile fmp2009-pmlsm > "$work/check.txt" || fail "check-profile fmp2009-pmlsm exited $?"
grep -q "the kernel accepts it" "$work/check.txt" || fail "check-profile verdict"

set +e
"$hil" run no_such_experiment --profile fmp2009-pmlsm --out "$work/bad" > "$work/bad.txt" 2>&1
rc=$?
set -e
[ "$rc" -eq 2 ] || fail "an unknown experiment exited $rc, expected 2"
grep -q "no experiment 'no_such_experiment'" "$work/bad.txt" || fail "no reason for the unknown experiment"

set +e
"$hil" suite --profile fmp2009-pmlsm > "$work/noout.txt" 2>&1
rc=$?
set -e
[ "$rc" -eq 2 ] || fail "suite without --out exited $rc, expected 2"

"$hil" run lift_off_and_land --profile fmp2009-pmlsm --out "$work/land" > "$work/land.txt" || fail "lift_off_and_land exited $?"
grep -q '"touchdown_speed_m_per_s"' "$work/land/lift_off_and_land/metrics.json" || fail "no metrics.json"
grep -q '"pass": true' "$work/land/verdicts.json" || fail "no verdicts.json"

"$hil" record-pmlsm "$work/v.bin" "$work/o.bin" > "$work/rec.txt" || fail "record-pmlsm exited $?"
grep -q "final state landed" "$work/rec.txt" || fail "the recorded session does not end landed"
echo "pmlsm_cli: OK"
