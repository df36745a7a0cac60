#!/usr/bin/env bash
# The model build for a new grasp (`build_us` of `grasp-torque bench`: GraspSolver::new,
# the model, the inscribed view at N = 8 and the native backend), two builds of the CLI
# side by side: each round runs every fixture with both in turn, and each figure is the
# lowest of its rounds' medians (the shared machine's load only ever adds time).
# Usage: bash scripts/bench_build.sh BEFORE_BIN AFTER_BIN [REPEATS] [ROUNDS]
# (a BIN is a `grasp-torque` binary, for example an older commit's built in a worktree).
set -euo pipefail
cd "$(dirname "$0")/.."
before=$1 after=$2 repeats=${3:-2000} rounds=${4:-5}
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for _ in $(seq "$rounds"); do
  for f in fixtures/*.json fixtures/hands/*.json; do
    for tag in before after; do
      bin=$before
      [ "$tag" = after ] && bin=$after
      "$bin" bench "$f" --sides 8 --repeats "$repeats" --format json |
        python3 -c 'import json,sys; print(sys.argv[1], sys.argv[2], json.load(sys.stdin)["build_us"])' "$(basename "$f" .json)" "$tag" >>"$out"
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
print("| fixture | before µs | after µs | before / after |")
print("|---|---|---|---|")
for f in order:
    b, a = best[(f, "before")], best[(f, "after")]
    print(f"| {f} | {b:.2f} | {a:.2f} | {b/a:.2f}× |")
PY
