"""A planner's batch from a robot file, measured in one run (docs/benchmarks.md, "A
planner's batch from a URDF or MJCF hand"): candidate grasps of one hand, each a joint
configuration with its contact points and normals perturbed around a bundled fixture,
solved for the fixture's wrench, alternating, best of ``--rounds``:

1. ``Hand.solve_batch`` (kinematics, model and solve in Rust, GIL released), all cores;
2. ``Hand.solve_batch`` on one thread;
3. ``solve_batch`` on one thread on the same grasps' G and Jᵀ as arrays (built
   beforehand, untimed): what the kinematics add to a batch;
4. the loop a user would write without ``Hand``: each grasp as a hand-form dict through
   ``Problem.from_dict`` and ``Solver(...).solve()``.

Before timing, the answers must agree: statuses equal, objectives bit for bit.

With ``--gravity``, it measures instead what the fingers' weight costs: ``Hand.solve_batch``
on one thread with ``gravity`` and without, interleaved, after checking that the batch
with gravity equals ``solve_batch`` on ``Hand.arrays``' G, Jᵀ and passive torques.

Run (after ``pip install ./python``, from the repository root):
    python scripts/bench_hand_batch.py [--grasps 20000] [--loop-grasps 1000] [--rounds 3] [--gravity]
"""

import argparse
import copy
import json
import os
import pathlib
import time

import numpy as np

import grasp_torque as gt

ROOT = pathlib.Path(__file__).resolve().parents[1]
HANDS = ROOT / "fixtures" / "hands"


def candidates(name, B, seed):
    d = json.loads((HANDS / f"{name}.json").read_text())
    hand = gt.Hand(HANDS / d["hand"]["model"])
    q0 = np.array([d["hand"]["joint_positions"].get(n, 0.0) for n in hand.joint_names])
    rng = np.random.default_rng(seed)
    q = q0 + rng.normal(0, 0.02, (B, len(q0)))
    k = len(d["contacts"])
    P = N = None
    if all("position" in c for c in d["contacts"]):
        P = np.array([c["position"] for c in d["contacts"]]) + rng.normal(0, 0.001, (B, k, 3))
        N = np.array([c["normal"] for c in d["contacts"]]) + rng.normal(0, 0.03, (B, k, 3))
        N /= np.linalg.norm(N, axis=2, keepdims=True)
    p = d.get("object_pose", {})
    pose = np.array(p.get("position", [0.0] * 3) + p.get("quaternion", [1.0, 0, 0, 0]))
    return d, hand, q, P, N, pose, np.tile(d["wrench"], (B, 1))


def as_dict(d, hand, q, P, N, b):
    """Candidate b as a hand-form dict."""
    e = copy.deepcopy(d)
    e["hand"]["model"] = str(HANDS / d["hand"]["model"])
    e["hand"]["joint_positions"] = dict(zip(hand.joint_names, q[b].tolist()))
    if P is not None:
        for i, c in enumerate(e["contacts"]):
            c["position"], c["normal"] = P[b, i].tolist(), N[b, i].tolist()
    return e


def rate(n, f):
    t = time.perf_counter()
    f()
    return n / (time.perf_counter() - t)


# Gravity in each fixture's root frame: the Allegro pinch's palm faces down (+x, its
# description); the MJCF hand's file gives its own; the Ability hand's is a choice.
GRAVITY = {"allegro-pinch": [9.81, 0.0, 0.0], "shadow-tripod": "model",
           "ability-tripod": [0.0, 0.0, -9.81]}


def gravity_cost(a):
    print(f"cores: {os.cpu_count()}, grasp_torque {gt.__version__}; grasps per second, 1 thread")
    print("| hand | without gravity | with gravity | cost | optimal without / with |")
    print("|---|---|---|---|---|")
    for name, g in GRAVITY.items():
        d, hand, q, P, N, pose, W = candidates(name, a.grasps, 1)
        kw = dict(positions=P, normals=N, object_pose=pose, torque_limits=d.get("torque_limits"),
                  threads=1)
        heavy = hand.solve_batch(q, W, d["contacts"], gravity=g, **kw)
        light = hand.solve_batch(q, W, d["contacts"], **kw)
        arr = hand.arrays(q, d["contacts"], positions=P, normals=N, object_pose=pose, gravity=g)
        m = gt.Problem.from_dict(as_dict(d, hand, q, P, N, 0)).to_dict()
        models = [{k: c[k] for k in ("model", "mu", "mu_torsion") if k in c} for c in d["contacts"]]
        via = gt.solve_batch(arr.G, arr.JT, W, models, transmission=arr.transmission,
                             passive_torque=arr.passive_torque,
                             torque_limits=m.get("torque_limits"))
        assert np.array_equal(via.objective, heavy.objective, equal_nan=True), name
        best = {"light": 0.0, "heavy": 0.0}
        for _ in range(a.rounds):
            best["light"] = max(best["light"], rate(a.grasps, lambda: hand.solve_batch(q, W, d["contacts"], **kw)))
            best["heavy"] = max(best["heavy"], rate(a.grasps, lambda: hand.solve_batch(
                q, W, d["contacts"], gravity=g, **kw)))
        print(f"| {name} | {best['light']:.0f} | {best['heavy']:.0f} | "
              f"{best['light'] / best['heavy']:.2f}× | {(light.status == 0).sum()} / {(heavy.status == 0).sum()} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--grasps", type=int, default=20000)
    ap.add_argument("--loop-grasps", type=int, default=1000)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--gravity", action="store_true")
    a = ap.parse_args()
    if a.gravity:
        return gravity_cost(a)
    print(f"cores: {os.cpu_count()}, grasp_torque {gt.__version__}; grasps per second")
    print("| hand | outputs | `Hand.solve_batch`, all cores | `Hand.solve_batch`, 1 thread | arrays `solve_batch`, 1 thread | `from_dict` loop | hand batch / loop (1 thread) | hand / arrays (1 thread) |")
    print("|---|---|---|---|---|---|---|---|")
    for name in ("allegro-pinch", "shadow-tripod", "ability-tripod"):
        d, hand, q, P, N, pose, W = candidates(name, a.grasps, 1)
        L = min(a.loop_grasps, a.grasps)
        hkw = dict(positions=P, normals=N, object_pose=pose, torque_limits=d.get("torque_limits"))
        out = hand.solve_batch(q, W, d["contacts"], **hkw)
        dicts = [as_dict(d, hand, q, P, N, b) for b in range(L)]
        probs = [gt.Problem.from_dict(e) for e in dicts]
        m = probs[0].to_dict()
        G = np.stack([p.grasp_matrix for p in probs])
        JT = np.stack([p.jacobian_transpose for p in probs])
        akw = dict(torque_limits=m.get("torque_limits"), threads=1)
        if m.get("transmission") is not None:
            akw["transmission"] = np.array(m["transmission"])
        arrays = lambda: gt.solve_batch(G, JT, W[:L], m["contacts"], **akw)
        loop = lambda: [gt.Solver(gt.Problem.from_dict(e)).solve() for e in dicts]
        small = dict(hkw, threads=1)
        if P is not None:
            small.update(positions=P[:L], normals=N[:L])
        hand_l = lambda: hand.solve_batch(q[:L], W[:L], d["contacts"], **small)
        for b, r in enumerate(loop()):
            assert gt.STATUS_CODES[int(out.status[b])] == r.status, (name, b)
            assert r.objective is None or out.objective[b] == r.objective, (name, b)
        assert np.array_equal(arrays().objective, out.objective[:L], equal_nan=True), name
        best = dict.fromkeys(["all", "one", "arrays", "loop"], 0.0)
        for _ in range(a.rounds):
            best["all"] = max(best["all"], rate(a.grasps, lambda: hand.solve_batch(q, W, d["contacts"], **hkw)))
            best["one"] = max(best["one"], rate(L, hand_l))
            best["arrays"] = max(best["arrays"], rate(L, arrays))
            best["loop"] = max(best["loop"], rate(L, loop))
        print(
            f"| {name} | {len(out.names)} | {best['all']:.0f} | {best['one']:.0f} | {best['arrays']:.0f} | "
            f"{best['loop']:.0f} | {best['one'] / best['loop']:.1f}× | {best['arrays'] / best['one']:.2f} |"
        )


if __name__ == "__main__":
    main()
