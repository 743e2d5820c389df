#!/bin/sh
# The regression oracle of issues 11 and 12: the default scenario's trace.csv,
# commands.txt and metrics.json (less its two wall-clock fields) must equal the
# recorded digests, for the float32 and the Q7.24 kernel. A change that moves
# them on purpose (a bug fix, a faster kernel) re-records the digests in its
# own commit with the reason:  sh golden_default.sh HIL OUT --record
# A third run, classic-float32, is the default scenario with `[plant]
# integrator = classic`: the integrator before issue 16's `fast` one, which
# must stay bit for bit what it was: when it landed, its digests were those
# the default run had before the change. A kernel change that moves the
# default run on purpose moves this one too, and --record re-records all three
# (the homing Hall solve of issue 16 did).
#   usage: golden_default.sh MAGLEV_HIL OUT_DIR [--record]
set -eu
hil=$1; out=$2; record=${3:-}
here=$(dirname "$0")
status=0
mkdir -p "$out"
classic="$out/classic/default.scenario"
mkdir -p "$out/classic"
cp "$here/../../../hil/scenarios/default.scenario" "$classic"
printf '\n[plant]\nintegrator = classic\n' >> "$classic"
for k in float32 q7.24 classic-float32; do
  d="$out/golden-$k"
  rm -rf "$d"
  if [ "$k" = classic-float32 ]; then
    "$hil" run "$classic" --kernel float32 --out "$d" --no-plots --quiet > /dev/null
  else
    "$hil" run default --kernel "$k" --out "$d" --no-plots --quiet > /dev/null
  fi
  grep -v -e '"real_time_factor"' -e '"wall_time_per_tick_us"' "$d/metrics.json" > "$d/metrics.deterministic.json"
  got=$(cd "$d" && sha256sum trace.csv commands.txt metrics.deterministic.json)
  want_file="$here/golden/default-$k.sha256"
  if [ "$record" = "--record" ]; then
    printf '%s\n' "$got" > "$want_file"
    echo "recorded $want_file"
    continue
  fi
  if printf '%s\n' "$got" | cmp -s - "$want_file"; then
    echo "default/$k: trace.csv, commands.txt and metrics.json identical to the recorded run"
  else
    echo "default/$k: DIFFERS from the recorded run"
    printf '%s\n' "$got" | diff "$want_file" - || true
    status=1
  fi
done
exit $status
