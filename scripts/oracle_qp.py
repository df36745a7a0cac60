#!/usr/bin/env python3
"""The linearised QP of one problem file, exactly as the native solver sees it
(`grasp-torque export-qp FILE --format json`: minimise Σ w_j τ_j² subject to H τ ≥ c
and C τ = e), solved by Clarabel and by SCS through cvxpy: an oracle for a linearised
answer. Prints the native answer's σ and its largest row miss (max(c − H τ) and
|C τ − e|, with the passive torques' offset taken off), then each solver's status, σ
and row miss. A solver's σ below the native one with a miss of its own is not a
better optimum: on ill-conditioned grasps compare the misses too.

Usage: /tmp/cvx/bin/python scripts/oracle_qp.py FILE [--sides N]   (after `cargo build
--release`; cvxpy, numpy from PyPI)
"""
import json
import os
import subprocess
import sys

import cvxpy as cp
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("GRASP_TORQUE_BIN", os.path.join(ROOT, "target", "release", "grasp-torque"))


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = subprocess.run([BIN, "export-qp", sys.argv[1], *sys.argv[2:], "--format", "json"],
                         capture_output=True, text=True, check=True).stdout
    d = json.loads(out)
    H, c, W = np.array(d["H"], float), np.array(d["c"], float), np.array(d["weights"], float)
    C, e = np.array(d["C"], float), np.array(d["e"], float)
    sol = d["solution"]
    if sol.get("torque"):
        v = np.array(sol["torque"]) - np.array(d.get("torque_offset") or 0.0)
        eq = float(np.max(np.abs(C @ v - e))) if C.size else 0.0
        print(f"native: {sol['status']} σ {sol['objective']!r}, row miss {float(np.max(c - H @ v)):.1e}, equalities {eq:.1e}")
    else:
        print(f"native: {sol['status']}")
    t = cp.Variable(H.shape[1])
    cons = [H @ t >= c] + ([C @ t == e] if C.size else [])
    problem = cp.Problem(cp.Minimize(cp.sum(cp.multiply(W, cp.square(t)))), cons)
    for solver in ("CLARABEL", "SCS"):
        try:
            problem.solve(solver=solver)
        except cp.error.SolverError as err:
            print(f"{solver}: failed ({str(err)[:60]})")
            continue
        if t.value is None:
            print(f"{solver}: {problem.status}")
        else:
            print(f"{solver}: {problem.status} σ {float(problem.value)!r}, row miss {float(np.max(c - H @ t.value)):.1e}")


if __name__ == "__main__":
    main()
