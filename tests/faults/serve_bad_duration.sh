#!/bin/sh
# `maglev-hil serve --duration nan` once ran forever: every bad duration is
# refused at once with exit 2.
HIL=$1
pass=0; fail=0
for d in nan inf -1 5x ""; do
  timeout 10 "$HIL" serve --modbus-tcp 127.0.0.1:0 --duration "$d" 2>/dev/null
  rc=$?
  if [ $rc -eq 2 ]; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "--duration '$d': exit $rc, expected 2"; fi
done
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
