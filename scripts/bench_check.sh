#!/usr/bin/env bash
# What the core's check adds to a solve, in time: `grasp-torque bench`'s in-process
# medians of the backend alone (`cold_raw_us`), a full solve with the lazy check
# (`cold_lazy_us`) and with the full one (`cold_us`), and the control loop with each
# (`warm_1pct_lazy_us`, `warm_1pct_us`). Rounds are interleaved and each figure is the
# lowest of its rounds' medians (the shared machine's load only ever adds time).
# Usage: bash scripts/bench_check.sh REPEATS ROUNDS FILE... [-- BENCH-FLAGS]
#        (after `cargo build --release`)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/grasp-torque
repeats=$1 rounds=$2
shift 2
files=() flags=()
while [ $# -gt 0 ]; do
  if [ "$1" = "--" ]; then
    shift
    flags=("$@")
    break
  fi
  files+=("$1")
  shift
done
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for _ in $(seq "$rounds"); do
  for f in "${files[@]}"; do
    "$bin" bench "$f" "${flags[@]}" --repeats "$repeats" --format json |
      python3 -c 'import json,sys; d=json.load(sys.stdin); print(sys.argv[1], d["status"], *(d[k] for k in ("cold_raw_us", "cold_lazy_us", "cold_us", "warm_1pct_lazy_us", "warm_1pct_us")))' "$(basename "$f" .json)" >>"$out"
  done
done
python3 - "$out" <<'PY'
import sys, statistics as st
best, order = {}, []
for line in open(sys.argv[1]):
    f, status, *t = line.split()
    if f not in order:
        order.append(f)
    old = best.get(f, [float("inf")] * 5)
    best[f] = [min(a, float(b)) for a, b in zip(old, t)]
print("| problem | backend cold µs | lazy cold µs | full cold µs | lazy / backend | full / backend | lazy warm µs | full warm µs |")
print("|---|---|---|---|---|---|---|---|")
lazy, full = [], []
for f in order:
    raw, lz, fu, wl, wf = best[f]
    lazy.append(lz / raw)
    full.append(fu / raw)
    print(f"| {f} | {raw:.2f} | {lz:.2f} | {fu:.2f} | {lz / raw:.3f} | {fu / raw:.3f} | {wl:.2f} | {wf:.2f} |")
print(f"\nlazy / backend: median {st.median(lazy):.3f}, max {max(lazy):.3f}; "
      f"full / backend: median {st.median(full):.3f}, max {max(full):.3f} ({len(order)} problems)")
PY
