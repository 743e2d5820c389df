#!/bin/sh
# check-compare-detects-flip.sh <kernel-bitexact-compare> <host_outputs.bin> <workdir>
#
# Negative control for the bit-exact test: flips the lowest bit of ONE float
# (effort_A[0] of tick 7000, a levitated tick) in a copy of the host outputs and
# requires kernel-bitexact-compare to fail and to name that tick and field.
set -eu
compare=$1
host=$2
work=$3
record_bytes=232        # kr::kOutputRecordBytes (a change makes this test fail loudly: wrong tick/field)
effort0_offset=32       # tick, result/enable/state/mask, 8 dac codes, fault..pad, scale_k
tick=7000
offset=$((tick * record_bytes + effort0_offset))
copy=$work/flipped_outputs.bin
cp "$host" "$copy"
byte=$(od -An -tu1 -j "$offset" -N1 "$copy" | tr -d ' ')
flipped=$((byte ^ 1))
printf "$(printf '\\%03o' "$flipped")" | dd of="$copy" bs=1 seek="$offset" conv=notrunc status=none
if out=$("$compare" "$host" "$copy"); then
  echo "$out"
  echo "check-compare-detects-flip: FAIL: one flipped bit was not detected"
  exit 1
fi
echo "$out"
case "$out" in
  *"tick $tick, field effort_A[0]"*) echo "check-compare-detects-flip: OK" ;;
  *) echo "check-compare-detects-flip: FAIL: wrong tick/field reported"; exit 1 ;;
esac
