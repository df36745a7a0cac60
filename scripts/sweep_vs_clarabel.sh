#!/usr/bin/env bash
# The exact-cone solver against Clarabel on random grasps of the robustness sweep
# (`grasp_testkit::sweep_grasp`), seeds FROM..TO at one friction scale: how each
# native answer was decided, every status on which the two differ (Clarabel's
# `almost_optimal` counts as `optimal`), each with the native solve of the inscribed
# polyhedra at N = 256 (inside the cones: optimal there means the grasp is feasible,
# and σ* is at most that σ), and the largest relative difference of σ where both are
# optimal (against Clarabel's `optimal` and its `almost_optimal` apart). Each grasp is
# one line of `fallbacks sweep`; run it on seeds the tests do not use to look for
# failures on grasps no one has seen.
# Usage: bash scripts/sweep_vs_clarabel.sh FROM TO FRICTION   (after `cargo build --release`)
set -euo pipefail
cd "$(dirname "$0")/.."
from=$1 to=$2 friction=$3
cargo build -q --release -p grasp-torque --example fallbacks
bin=target/release/examples/fallbacks
native=$(mktemp) clarabel=$(mktemp)
trap 'rm -f "$native" "$clarabel"' EXIT
"$bin" sweep "$from" "$to" "$friction" >"$native"
"$bin" sweep "$from" "$to" "$friction" clarabel >"$clarabel"
python3 - "$native" "$clarabel" "$bin" <<'PY'
import subprocess, sys
from collections import Counter
native = [l.split() for l in open(sys.argv[1])]
clarabel = [l.split() for l in open(sys.argv[2])]
paths, differ = Counter(), []
worst = {"optimal": (0.0, None), "almost_optimal": (0.0, None)}
for a, b in zip(native, clarabel):
    paths[(a[1], a[2])] += 1
    if a[1] != b[1].replace("almost_", ""):
        differ.append((a, b))
    elif a[1] == "optimal":
        r = abs(float(a[4]) - float(b[4])) / max(abs(float(a[4])), abs(float(b[4])), 1e-300)
        if r > worst[b[1]][0]:
            worst[b[1]] = (r, a[0])
print(f"{len(native)} grasps; native status and path: " + ", ".join(f"{s}/{m} {n}" for (s, m), n in sorted(paths.items())))
for k, (r, where) in worst.items():
    print(f"largest relative difference of sigma, native optimal and Clarabel {k}: {r:.2e} ({where})")
print(f"{len(differ)} status differences:")
for a, b in differ:
    seed, friction = a[0].split(":")
    fine = subprocess.run([sys.argv[3], "sweep", seed, str(int(seed) + 1), friction, "sides=256"],
                          capture_output=True, text=True, check=True).stdout.split()
    print(f"  {a[0]}: native {a[1]} ({a[2]}, sigma {a[4]}), Clarabel {b[1]} (sigma {b[4]}, least margin {b[6]}), inscribed N = 256 {fine[1]} (sigma {fine[4]})")
PY
