#!/bin/sh
# A scenario-file error must give a clear message (file:line: what) and a
# non-zero exit; an unknown scenario name too.
set -u
HIL="$1"; DIR="$2"; OUT="$3"
out=$("$HIL" run "$DIR/bad.scenario" --out "$OUT/bad" 2>&1); rc=$?
echo "$out"
[ $rc -ne 0 ] || { echo "FAIL: exit 0 on a bad scenario"; exit 1; }
echo "$out" | grep -q "bad.scenario:7: 'step' takes 2 argument" || { echo "FAIL: no file:line message"; exit 1; }
out=$("$HIL" run no_such_scenario --out "$OUT/none" 2>&1); rc=$?
echo "$out"
[ $rc -ne 0 ] || { echo "FAIL: exit 0 on an unknown scenario"; exit 1; }
echo "$out" | grep -q "no scenario 'no_such_scenario'" || { echo "FAIL: unclear message"; exit 1; }
out=$("$HIL" check "$DIR/short.scenario" 2>&1) || { echo "FAIL: check refused a good scenario: $out"; exit 1; }
echo "2 passed, 0 failed"
