"""A grasp planner's inner loop from a robot file: rank candidate pinch grasps of the
Allegro hand by the torque they need.

Each candidate is the bundled pinch (fixtures/hands/allegro-pinch.json) with its joint
positions, contact points and normals perturbed; ``Hand.solve_batch`` builds each one's
G and Jᵀ from the URDF and solves it, in parallel with the GIL released.

    python examples/python/hand_batch.py [--grasps 20000] [--check]

``--check`` solves the best candidate again as a hand-form dict, one by one.
"""

import argparse
import copy
import json
import pathlib
import time

import numpy as np

import grasp_torque as gt

ROOT = pathlib.Path(__file__).resolve().parents[2]

ap = argparse.ArgumentParser()
ap.add_argument("--grasps", type=int, default=20000)
ap.add_argument("--check", action="store_true")
args = ap.parse_args()

pinch = json.loads((ROOT / "fixtures/hands/allegro-pinch.json").read_text())
hand = gt.Hand(ROOT / "fixtures/urdf/allegro/allegro_hand_right.urdf")

rng = np.random.default_rng(0)
B, k = args.grasps, len(pinch["contacts"])
q0 = np.array([pinch["hand"]["joint_positions"].get(n, 0.0) for n in hand.joint_names])
q = q0 + rng.normal(0, 0.02, (B, q0.size))  # radians, columns in hand.joint_names order
P = np.array([c["position"] for c in pinch["contacts"]]) + rng.normal(0, 1e-3, (B, k, 3))
N = np.array([c["normal"] for c in pinch["contacts"]]) + rng.normal(0, 0.05, (B, k, 3))
N /= np.linalg.norm(N, axis=2, keepdims=True)
pose = pinch["object_pose"]["position"] + pinch["object_pose"]["quaternion"]
W = np.tile(pinch["wrench"], (B, 1))

t = time.perf_counter()
out = hand.solve_batch(q, W, pinch["contacts"], positions=P, normals=N, object_pose=pose)
t = time.perf_counter() - t
holds = out.status == 0
best = int(np.nanargmin(out.objective))
print(f"{holds.sum()} of {B} candidates hold the object ({B / t:.0f} grasps/s)")
print(f"least effort: candidate {best}, σ = {out.objective[best]:.6g} N²m²")
for name, tau in zip(out.names, out.torque[best]):
    print(f"  {name:12s} {tau:+.4f} N m")

if args.check:
    d = copy.deepcopy(pinch)
    d["hand"]["joint_positions"] = dict(zip(hand.joint_names, q[best].tolist()))
    for i, c in enumerate(d["contacts"]):
        c["position"], c["normal"] = P[best, i].tolist(), N[best, i].tolist()
    r = gt.Solver(gt.Problem.from_dict(d, base=ROOT / "fixtures/hands")).solve()
    assert r.status == "optimal" and r.objective == out.objective[best]
    assert np.array_equal(r.torque, out.torque[best])
    print("the best candidate, solved alone, matches the batch")
