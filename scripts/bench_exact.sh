#!/usr/bin/env bash
# Exact cones side by side in one run: the native exact solver, Clarabel's exact cones
# and the native linearised solve at N = 8, each the in-process median of `grasp-torque
# bench` (cold solves, model built once), interleaved fixture by fixture.
# Usage: bash scripts/bench_exact.sh [REPEATS]   (after `cargo build --release`)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/grasp-torque
repeats=${1:-300}
med() { "$bin" bench "$@" --repeats "$repeats" --format json | python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["cold_raw_us"] if d["status"]=="optimal" else "nan")'; }
echo "| fixture | native N = 8 µs | native exact µs | Clarabel exact µs | native exact / N = 8 | Clarabel / native exact |"
echo "|---|---|---|---|---|---|"
for f in fixtures/paper-example.json fixtures/hand3-pcwf.json fixtures/hand5-pcwf.json fixtures/hand4-sfcl.json fixtures/hand4-sfce.json fixtures/hand5-mixed.json fixtures/hands/allegro-pinch.json fixtures/hands/ability-tripod.json fixtures/hands/shadow-tripod.json; do
  lin=$(med "$f" --sides 8 --backend active-set)
  nat=$(med "$f" --cones exact --backend active-set)
  cla=$(med "$f" --cones exact --backend clarabel)
  python3 -c "print(f'| $(basename "$f" .json) | {$lin:.1f} | {$nat:.1f} | {$cla:.1f} | {$nat/$lin:.1f}× | {$cla/$nat:.2f}× |')"
done
