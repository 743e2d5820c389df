# Shared by the fidelity bench scripts, sourced with their arguments
# MAGLEV_HIL SOURCE_DIR OUT_DIR PYTHON3: HIL, DIR, OUT (emptied), PY.
set -u
HIL="$1"; DIR="$2"; OUT="$3"; PY="$4"
rm -rf "$OUT"; mkdir -p "$OUT"
fail() { echo "FAIL: $*"; exit 1; }
# expect FILE PATTERN: `check` refuses FILE with PATTERN (file:line: key: reason).
expect() {
  out=$("$HIL" check "$DIR/$1" 2>&1) && fail "$1 accepted"
  echo "$out" | grep -q -- "$2" || { echo "$out"; fail "$1: no '$2'"; }
}
# refused_option SCENARIO OUT PATTERN ARGS...: `run` refuses the option with PATTERN.
refused_option() {
  sc=$1; o=$2; pat=$3; shift 3
  out=$("$HIL" run "$DIR/$sc" --out "$o" "$@" 2>&1) && fail "$* accepted"
  echo "$out" | grep -q -- "$pat" || fail "$*: $out"
}
