#!/usr/bin/env python3
"""A planner's candidate grasps on the bundled hands, with optima from an SOCP that
shares nothing with the project's model: the oracle of
python/tests/test_hand_oracle.py (tests/data/hand-batch-oracle.json).

For each hand-form fixture in fixtures/hands, CANDIDATES candidates are drawn around
it (joint angles ±0.08 rad, contact points ±4 mm, normals ±0.15 rad, the wrench 0.3 to
2 times the fixture's plus a random push and twist; the fixture's gravity, no torque
limits). The installed package poses each one (`Hand.arrays`: G, Jᵀ, the transmission
T and the passive torques τ_p, whose kinematics the Rust tests check against Pinocchio
and MuJoCo), and cvxpy solves, with Clarabel,

    min Σ u²   subject to   G f = w,   Jᵀ f = T u + τ_p,   f in the exact cones,

in the forces and actuator forces themselves: no pseudo-inverse, consistency rows,
equilibration or elimination of the project's. A candidate whose `[G; Jᵀ]` has a null
space is drawn again (there the SOCP optimises the internal forces, which the
project's default fixes by least compliance: the Ability tripod, whose every candidate
has one, is left out); so is one the SOCP does not settle within 1e-10 (an
`_inaccurate` status). Each optimum is solved twice, the second time
with the objective divided by the first answer's, so that Clarabel's absolute
tolerances count relative to σ*.

Run from the repository root with the package installed (cvxpy 1.9 with Clarabel and
numpy from PyPI):

    python3 -m venv /tmp/cvx && /tmp/cvx/bin/pip install cvxpy numpy ./python
    /tmp/cvx/bin/python scripts/oracle_hand_batches.py > tests/data/hand-batch-oracle.json

(`oracle_hand_batches.py [CANDIDATES [SEED]]`, 40 and 20261205 by default.)
"""

import json
import sys
from pathlib import Path

import cvxpy as cp
import numpy as np

import grasp_torque as gt

ROOT = Path(__file__).resolve().parents[1]
HANDS = ROOT / "fixtures" / "hands"
TOL = 1e-10


def socp(G, JT, T, tp, w, contacts, scale=1.0):
    n, m = G.shape[1], JT.shape[0]
    f = cp.Variable(n)
    u = cp.Variable(m if T is None else T.shape[1])
    cons = [G @ f == w, JT @ f == (u if T is None else T @ u) + tp]
    off = 0
    for c in contacts:
        model, mu = c["model"], c.get("mu", 0.0)
        if model == "fpc":
            cons.append(f[off] >= 0)
            off += 1
        elif model == "pcwf":
            cons.append(cp.SOC(mu * f[off + 2], f[off:off + 2]))
            off += 3
        elif model == "sfce":
            mt = c["mu_torsion"]
            cons.append(cp.SOC(f[off + 2], cp.hstack([f[off] / mu, f[off + 1] / mu, f[off + 3] / mt])))
            off += 4
        else:  # sfcl: ‖f_t‖ ≤ mu (fz ∓ mz/mu_torsion)
            mt = c["mu_torsion"]
            for sign in (-1.0, 1.0):
                cons.append(cp.SOC(mu * (f[off + 2] + sign * f[off + 3] / mt), f[off:off + 2]))
            off += 4
    problem = cp.Problem(cp.Minimize(cp.sum_squares(u) / scale), cons)
    problem.solve(solver=cp.CLARABEL, tol_gap_abs=TOL, tol_gap_rel=TOL, tol_feas=TOL,
                  tol_infeas_abs=TOL, tol_infeas_rel=TOL, max_iter=500)
    return problem.status, (None if problem.value is None else problem.value * scale)


def main():
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 40
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 20261205
    rng = np.random.default_rng(seed)
    hands = []
    for path in sorted(HANDS.glob("*.json")):
        d = json.loads(path.read_text())
        hand = gt.Hand(HANDS / d["hand"]["model"])
        q0 = np.zeros(len(hand.joint_names))
        for name, v in d["hand"]["joint_positions"].items():
            q0[hand.joint_names.index(name)] = v
        pose = d.get("object_pose", {})
        pose = pose.get("position", [0.0] * 3) + pose.get("quaternion", [1.0, 0.0, 0.0, 0.0])
        gravity = d["hand"].get("gravity")
        contacts = d["contacts"]
        k = len(contacts)
        # (A site's contact without a point or normal keeps the site's: a row of NaN.)
        p0 = np.array([c.get("position", [np.nan] * 3) for c in contacts], dtype=float)
        n0 = np.array([c.get("normal", [np.nan] * 3) for c in contacts], dtype=float)
        w0 = np.array(d.get("wrench", [0.0, 0.0, 0.5 * 9.81, 0.0, 0.0, 0.0]), dtype=float)
        cases, drawn = [], 0
        while len(cases) < count and drawn < 20 * count:
            drawn += 1
            q = q0 + rng.normal(0, 0.08, len(q0))
            P = p0 + rng.normal(0, 0.004, (k, 3))
            N = n0 + rng.normal(0, 0.15, (k, 3))
            N /= np.linalg.norm(N, axis=1, keepdims=True)
            push = rng.normal(0, 0.2, 6) * np.r_[np.ones(3), 0.02 * np.ones(3)]
            w = w0 * rng.uniform(0.3, 2.0) + push
            kw = dict(positions=P[None], normals=N[None], object_pose=pose)
            if gravity is not None:
                kw["gravity"] = gravity
            a = hand.arrays(q[None], contacts, **kw)
            if a.errors:
                continue
            G, JT = a.G[0], a.JT[0]
            T = a.transmission if a.transmission is None or a.transmission.ndim == 2 else a.transmission[0]
            tp = np.zeros(JT.shape[0]) if a.passive_torque is None else a.passive_torque[0]
            A = np.vstack([G, JT])
            if np.linalg.matrix_rank(A, tol=1e-9 * np.linalg.norm(A, 2)) < A.shape[1]:
                continue
            status, value = socp(G, JT, T, tp, w, contacts)
            if status == "optimal":
                status, value = socp(G, JT, T, tp, w, contacts, scale=max(value, 1e-300))
            if status not in ("optimal", "infeasible"):
                continue
            cases.append({
                "joint_positions": q.tolist(), "positions": P.tolist(), "normals": N.tolist(),
                "wrench": w.tolist(), "status": status, "objective": value,
            })
        print(f"{path.stem}: {len(cases)} candidates ({drawn} drawn), "
              f"{sum(c['status'] == 'infeasible' for c in cases)} infeasible", file=sys.stderr)
        if cases:
            hands.append({"fixture": path.name, "object_pose": pose, "gravity": gravity,
                          "cases": cases})
    json.dump({"seed": seed, "tolerance": TOL, "hands": hands}, sys.stdout)
    print()


if __name__ == "__main__":
    main()
