#!/usr/bin/env bash
# Instructions per call of one kind (the `call_loop` example), by valgrind: the
# difference between runs of N and 2N calls over N, so that loading and setup cancel.
# Deterministic, unlike timings on a shared machine; not a time (vector and scalar
# instructions count the same), so compare like with like.
# Usage: bash scripts/instructions.sh KIND N FILE... [-- exact]   (needs valgrind)
# Another build (an older commit's, say) with BIN=path/to/call_loop.
set -euo pipefail
cd "$(dirname "$0")/.."
kind=$1 n=$2
shift 2
files=() extra=()
while [ $# -gt 0 ]; do
  if [ "$1" = "--" ]; then
    shift
    extra=("$@")
    break
  fi
  files+=("$1")
  shift
done
bin=${BIN:-target/release/examples/call_loop}
if [ -z "${BIN:-}" ]; then
  cargo build -q --release -p grasp-torque --example call_loop
fi
count() {
  valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file=/dev/null \
    "$bin" "$1" "$kind" "$2" "${extra[@]}" 2>&1 |
    awk '/I[ ]+refs/ { gsub(",", "", $NF); print $NF }'
}
for f in "${files[@]}"; do
  a=$(count "$f" "$n")
  b=$(count "$f" $((2 * n)))
  echo "$(basename "$f" .json) $kind $(((b - a) / n))"
done
