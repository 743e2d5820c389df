#!/bin/sh
# run_fuzzer.sh FUZZER SEED_DIR SCRATCH_DIR [libFuzzer options...]
# Copies the seed corpus kept in the repository into a scratch directory in
# the build tree and fuzzes there: libFuzzer adds every new input to its
# corpus directory and writes crash files next to it, and a test must never
# write into the source tree. The scratch corpus is rebuilt from the seeds on
# every run so that a run is reproducible from the repository alone.
set -eu
fuzzer=$1
seeds=$2
scratch=$3
shift 3
if [ ! -x "$fuzzer" ]; then
  echo "run_fuzzer.sh: $fuzzer not built" >&2
  exit 1
fi
if [ -z "$(ls -A "$seeds" 2>/dev/null)" ]; then
  echo "run_fuzzer.sh: no seed corpus in $seeds" >&2
  exit 1
fi
rm -rf "$scratch"
mkdir -p "$scratch/corpus" "$scratch/artifacts"
cp "$seeds"/* "$scratch/corpus/"
exec "$fuzzer" -artifact_prefix="$scratch/artifacts/" "$@" "$scratch/corpus"
