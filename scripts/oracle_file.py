#!/usr/bin/env python3
"""σ* of one matrix-form problem file with exact cones, by cvxpy and Clarabel, from
the file alone: an oracle for a grasp the project found hard (tests cite its figure).

It solves the problem in the contact forces f: `G f = w`, each contact's force in its
exact cone (FPC `fz ≥ 0`; PCwF `‖(fx, fy)‖ ≤ mu fz`; SFCl `‖(fx, fy)‖/mu + |mz|/mu_torsion
≤ fz`; SFCe `‖(fx/mu, fy/mu, mz/mu_torsion)‖ ≤ fz`), minimum normal forces, torque
limits on `τ = Jᵀ f − τ_p` (τ_p the file's `passive_torque`, zero without it), and
minimises `Σ w_j τ_j²`. That is the project's problem only
where `[G; Jᵀ]` has full column rank (f is then fixed by w and τ, so no model of the
passive internal forces enters), which it checks. Clarabel runs at 1e-10, then again
with σ divided by the first answer (its absolute tolerances then count relative to
σ*), as `scripts/oracle_cases.py` does.

Usage: /tmp/cvx/bin/python scripts/oracle_file.py FILE   (cvxpy, numpy from PyPI)
"""
import json
import sys

import cvxpy as cp
import numpy as np


def main():
    p = json.load(open(sys.argv[1]))
    G, J = np.array(p["grasp_matrix"], float), np.array(p["jacobian_transpose"], float)
    w = np.array(p["wrench"], float)
    n, m = G.shape[1], J.shape[0]
    s = np.linalg.svd(np.vstack([G, J]), compute_uv=False)
    if s[-1] <= 1e-9 * s[0] or G.shape[0] + m < n:
        sys.exit("[G; Jᵀ] is rank-deficient: the passive internal forces are a modelling choice")
    if p.get("transmission"):
        sys.exit("a transmission: the oracle solves in joint torques only")
    # Passive joint torques: Jᵀ f = τ + τ_p, the motors' τ what σ weighs and limits bound.
    passive = np.array(p.get("passive_torque") or [0.0] * m, float)
    f = cp.Variable(n)
    tau = J @ f - passive
    cons = [G @ f == w]
    fmin = p.get("min_normal_force") or 0.0
    off = 0
    for i, c in enumerate(p["contacts"]):
        model = c["model"]
        lo = fmin[i] if isinstance(fmin, list) else fmin
        if model == "fpc":
            fz, dim = f[off], 1
        else:
            fz = f[off + 2]
            mu = c["mu"]
            if model == "pcwf":
                cons.append(cp.SOC(mu * fz, f[off:off + 2]))
                dim = 3
            elif model == "sfcl":
                cons.append(cp.norm(f[off:off + 2], 2) / mu + cp.abs(f[off + 3]) / c["mu_torsion"] <= fz)
                dim = 4
            elif model == "sfce":
                cons.append(cp.SOC(fz, cp.hstack([f[off] / mu, f[off + 1] / mu, f[off + 3] / c["mu_torsion"]])))
                dim = 4
            else:
                sys.exit(f"contact {i}: model {model!r}")
        cons.append(fz >= lo)
        off += dim
    for j, lim in enumerate(p.get("torque_limits") or []):
        lo, hi = lim if isinstance(lim, list) else (None, None) if lim is None else (-lim, lim)
        cons += [tau[j] >= lo] if lo is not None else []
        cons += [tau[j] <= hi] if hi is not None else []
    weights = np.array(p.get("torque_weights") or [1.0] * m, float)
    sigma = None
    for scale in (1.0, None):
        k = 1.0 if scale else 1.0 / max(sigma, 1e-300)
        prob = cp.Problem(cp.Minimize(k * cp.sum(cp.multiply(weights, cp.square(tau)))), cons)
        prob.solve(solver="CLARABEL", tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10)
        if prob.status != "optimal":
            print(prob.status)
            return
        sigma = float(np.sum(weights * (J @ f.value - passive) ** 2))
    print(f"{sigma:.12e}")


if __name__ == "__main__":
    main()
