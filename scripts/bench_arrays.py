"""A planner's arrays from a robot file, measured in one run (docs/benchmarks.md,
"Posing a planner's candidates in parallel"): ``Hand.arrays`` (G, Jᵀ and the passive
torques of each candidate) and ``Hand.frames`` (every link, or every site of an MJCF
hand), on one thread and on all cores, alternating, best of ``--rounds``, in candidates
per second. The candidates are the bundled fixture's configuration perturbed by 0.02 rad
per joint. Before timing, one thread and all cores must give the same arrays, bit for
bit.

Run (after ``pip install ./python``, from the repository root):
    python scripts/bench_arrays.py [--grasps 50000] [--rounds 3]
"""

import argparse
import json
import os
import pathlib
import time

import numpy as np

import grasp_torque as gt

ROOT = pathlib.Path(__file__).resolve().parents[1]
HANDS = ROOT / "fixtures" / "hands"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--grasps", type=int, default=50000)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    print(f"{os.cpu_count()} cores, {gt._native.default_threads()} threads by default, {args.grasps} candidates")
    print("| hand | frames | arrays, 1 thread | arrays, all cores | ratio | frames, 1 thread | frames, all cores | ratio |")
    print("|---|---|---|---|---|---|---|---|")
    for name in ["allegro-pinch", "shadow-tripod", "ability-tripod", "aero-pinch"]:
        d = json.loads((HANDS / f"{name}.json").read_text())
        hand = gt.Hand(HANDS / d["hand"]["model"])
        q0 = np.zeros(len(hand.joint_names))
        for k, v in d["hand"]["joint_positions"].items():
            q0[hand.joint_names.index(k)] = v
        q = q0 + np.random.default_rng(1).normal(0, 0.02, (args.grasps, len(q0)))
        p = d.get("object_pose", {})
        pose = np.array(p.get("position", [0.0] * 3) + p.get("quaternion", [1.0, 0, 0, 0]))
        names = hand.sites or hand.links
        runs = {
            ("arrays", 1): lambda t: hand.arrays(q, d["contacts"], object_pose=pose, threads=t),
            ("arrays", None): lambda t: hand.arrays(q, d["contacts"], object_pose=pose, threads=t),
            ("frames", 1): lambda t: hand.frames(q, names, threads=t),
            ("frames", None): lambda t: hand.frames(q, names, threads=t),
        }
        one, all_ = runs[("arrays", 1)](1), runs[("arrays", None)](None)
        for field in ("G", "JT", "passive_torque"):
            np.testing.assert_array_equal(getattr(one, field), getattr(all_, field))
        for a, b in zip(runs[("frames", 1)](1), runs[("frames", None)](None)):
            np.testing.assert_array_equal(a, b)
        best = {k: float("inf") for k in runs}
        for _ in range(args.rounds):
            for (kind, threads), run in runs.items():
                t = time.perf_counter()
                run(threads)
                best[(kind, threads)] = min(best[(kind, threads)], time.perf_counter() - t)
        rate = {k: args.grasps / v for k, v in best.items()}
        a1, an, f1, fn = (rate[("arrays", 1)], rate[("arrays", None)], rate[("frames", 1)], rate[("frames", None)])
        print(f"| {name} | {len(names)} {'sites' if hand.sites else 'links'} | {a1:,.0f} | {an:,.0f} | {an / a1:.2f}× "
              f"| {f1:,.0f} | {fn:,.0f} | {fn / f1:.2f}× |")


if __name__ == "__main__":
    main()
