#!/usr/bin/env bash
# Two builds of the CLI side by side on one figure of `grasp-torque bench` (FIELD:
# build_us, cold_us, cold_raw_us, warm_us, ...): each round runs every file with both
# builds in turn, and each figure is the lowest of its rounds' medians (the shared
# machine's load only ever adds time).
# Usage: bash scripts/bench_pair.sh BEFORE_BIN AFTER_BIN FIELD REPEATS ROUNDS FILE... [-- BENCH_ARGS...]
# (a BIN is a `grasp-torque` binary, for example an older commit's built in a worktree).
set -euo pipefail
cd "$(dirname "$0")/.."
before=$1 after=$2 field=$3 repeats=$4 rounds=$5
shift 5
files=() args=()
while [ $# -gt 0 ]; do
  if [ "$1" = "--" ]; then
    shift
    args=("$@")
    break
  fi
  files+=("$1")
  shift
done
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for _ in $(seq "$rounds"); do
  for f in "${files[@]}"; do
    for tag in before after; do
      bin=$before
      [ "$tag" = after ] && bin=$after
      "$bin" bench "$f" "${args[@]}" --repeats "$repeats" --format json |
        python3 -c 'import json,sys; print(sys.argv[1], sys.argv[2], json.load(sys.stdin)[sys.argv[3]])' "$(basename "$f" .json)" "$tag" "$field" >>"$out"
    done
  done
done
python3 - "$out" <<'PY'
import sys
best, order = {}, []
for line in open(sys.argv[1]):
    f, tag, us = line.split()
    if f not in order:
        order.append(f)
    best[(f, tag)] = min(best.get((f, tag), float("inf")), float(us))
print("| file | before µs | after µs | before / after |")
print("|---|---|---|---|")
for f in order:
    b, a = best[(f, "before")], best[(f, "after")]
    print(f"| {f} | {b:.2f} | {a:.2f} | {b/a:.2f}× |")
PY
