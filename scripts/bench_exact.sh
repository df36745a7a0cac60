#!/usr/bin/env bash
# Exact cones side by side in one run: the native exact solver, Clarabel's exact cones
# and the native linearised solve at N = 8, each the in-process median of `grasp-torque
# bench` (model built once), interleaved: each round runs every fixture and solver
# once, so a fixture's rounds spread over the whole run; each figure is the lowest of
# its rounds' medians (the shared machine's load only ever adds time, and it changes
# over seconds to minutes; and some fixtures' timings are bimodal from one process to
# the next, so that five rounds can miss the fast mode: docs/benchmarks.md, run J).
# Cold: `cold_raw_us`, the backend alone. Warm: `warm_1pct_us`, a full `resolve` (with
# the core's checks) after a 1 % wrench change.
# Usage: bash scripts/bench_exact.sh [REPEATS] [ROUNDS]   (after `cargo build --release`)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/grasp-torque
repeats=${1:-1000}
rounds=${2:-12}
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for _ in $(seq "$rounds"); do
  for f in fixtures/paper-example.json fixtures/hand3-pcwf.json fixtures/hand5-pcwf.json fixtures/hand4-sfcl.json fixtures/hand4-sfce.json fixtures/hand5-mixed.json fixtures/hands/allegro-pinch.json fixtures/hands/ability-tripod.json fixtures/hands/shadow-tripod.json; do
    for kind in "lin --sides 8 --backend active-set" "nat --cones exact --backend active-set" "cla --cones exact --backend clarabel"; do
      set -- $kind
      tag=$1; shift
      "$bin" bench "$f" "$@" --repeats "$repeats" --format json |
        python3 -c 'import json,sys; d=json.load(sys.stdin); ok=d["status"]=="optimal"; print(sys.argv[1], sys.argv[2], d["cold_raw_us"] if ok else "nan", d["warm_1pct_us"] if ok else "nan")' "$(basename "$f" .json)" "$tag" >>"$out"
    done
  done
done
python3 - "$out" <<'PY'
import sys, statistics as st
best = {}
order = []
for line in open(sys.argv[1]):
    f, tag, cold, warm = line.split()
    if f not in order:
        order.append(f)
    c, w = best.get((f, tag), (float("inf"), float("inf")))
    best[(f, tag)] = (min(c, float(cold)), min(w, float(warm)))
print("| fixture | native N = 8 µs | native exact µs | Clarabel exact µs | native exact / N = 8 | Clarabel / native exact |")
print("|---|---|---|---|---|---|")
r1, r2, r3 = [], [], []
for f in order:
    lin, nat, cla = (best[(f, t)][0] for t in ("lin", "nat", "cla"))
    r1.append(nat / lin); r2.append(cla / nat)
    print(f"| {f} | {lin:.2f} | {nat:.2f} | {cla:.1f} | {nat/lin:.2f}× | {cla/nat:.1f}× |")
print()
print("| fixture | native warm N = 8 µs | native warm exact µs | exact / N = 8 |")
print("|---|---|---|---|")
for f in order:
    lin, nat = best[(f, "lin")][1], best[(f, "nat")][1]
    r3.append(nat / lin)
    print(f"| {f} | {lin:.2f} | {nat:.2f} | {nat/lin:.2f}× |")
print()
for name, r in (("cold exact / N = 8", r1), ("Clarabel / native exact", r2), ("warm exact / warm N = 8", r3)):
    print(f"{name}: median {st.median(r):.2f}×, range {min(r):.2f}–{max(r):.2f}×")
PY
