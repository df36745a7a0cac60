#!/usr/bin/env python3
"""The optimum of one linearised answer's key set, solved in the contact forces in
50-digit arithmetic from the problem file alone: an oracle where the model's own
constants (Z, the passive torques' force) carry the rounding in question.

It runs `grasp-torque solve FILE --cones linear` for the key set (`export-qp` names its
rows), then solves min Σ w_j τ_j² over f with `τ = Jᵀ f − τ_p` (the file's
`passive_torque`), subject to `G f = w` and each key row held with equality, written
from geometry: PCwF face j `fx cos φ_j + fy sin φ_j = mu cos(π/N) fz`, φ_j = (2j+1)π/N
(the shared reference's closed form), a normal-force row `fz = f_min`, a torque limit
`τ_j = ±t` (mpmath's LU on the KKT system). Prints σ, the key rows' multipliers (≥ 0
where the key set is optimal), the largest violation of any other face or limit, and
the native σ. Only FPC and PCwF contacts, no transmission, and `[G; Jᵀ]` of full column
rank (f is then fixed by w and τ).

Usage: /tmp/cvx/bin/python scripts/key_set_in_forces.py FILE [--sides N]   (after `cargo
build --release`; mpmath from PyPI)
"""
import json
import os
import re
import subprocess
import sys

import mpmath as mp

from key_set_optimum import equality_qp, report

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("GRASP_TORQUE_BIN", os.path.join(ROOT, "target", "release", "grasp-torque"))


def run(*args):
    return json.loads(subprocess.run([BIN, *args, "--format", "json"], capture_output=True,
                                     text=True, check=True).stdout)


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    mp.mp.dps = 50
    path, extra = sys.argv[1], sys.argv[2:]
    p = json.load(open(path))
    if p.get("transmission") or any(c["model"] not in ("fpc", "pcwf") for c in p["contacts"]):
        sys.exit("only FPC and PCwF contacts without a transmission")
    qp = run("export-qp", path, *extra)
    sol = qp["solution"]
    if sol.get("status") != "optimal":
        sys.exit(f"the native answer is {sol.get('status')}: no key set")
    sides = qp["sides"]
    G = mp.matrix(p["grasp_matrix"])
    J = mp.matrix(p["jacobian_transpose"])
    w = mp.matrix(p["wrench"])
    m, n = J.rows, G.cols
    tp = mp.matrix(p.get("passive_torque") or [0.0] * m)
    weights = [mp.mpf(v) for v in (p.get("torque_weights") or [1.0] * m)]
    stacked = mp.matrix([[G[i, j] for j in range(n)] for i in range(6)]
                        + [[J[i, j] for j in range(n)] for i in range(m)])
    if mp.svd_r(stacked, compute_uv=False)[n - 1] < mp.mpf("1e-30"):
        sys.exit("[G; Jᵀ] is rank-deficient")
    offsets, off = [], 0
    for c in p["contacts"]:
        offsets.append(off)
        off += 1 if c["model"] == "fpc" else 3
    fmin = p.get("min_normal_force") or 0.0
    limits = p.get("torque_limits") or []

    def row(name):
        """(a, b) with the row a·f ≥ b, in the forces (a torque limit through Jᵀ)."""
        a, b = [mp.mpf(0)] * n, mp.mpf(0)
        if mt := re.fullmatch(r"contact (\d+) face (\d+)", name):
            c, j = int(mt[1]), int(mt[2])
            mu, o = mp.mpf(p["contacts"][c]["mu"]), offsets[c]
            phi = (2 * j + 1) * mp.pi / sides
            a[o], a[o + 1], a[o + 2] = -mp.cos(phi), -mp.sin(phi), mu * mp.cos(mp.pi / sides)
        elif mt := re.fullmatch(r"contact (\d+) normal force", name):
            c = int(mt[1])
            o = offsets[c] + (0 if p["contacts"][c]["model"] == "fpc" else 2)
            a[o] = mp.mpf(1)
            b = mp.mpf(fmin[c] if isinstance(fmin, list) else fmin)
        elif mt := re.fullmatch(r"joint (\d+) (lower|upper) torque limit", name):
            j, upper = int(mt[1]), mt[2] == "upper"
            lim = limits[j]
            lo, hi = lim if isinstance(lim, list) else (-lim, lim)
            sign = -1 if upper else 1
            a = [sign * J[j, k] for k in range(n)]
            b = sign * (mp.mpf(hi if upper else lo) + tp[j])
        else:
            sys.exit(f"row {name!r}: not read")
        return a, b

    rows = [row(name) for name in qp["row_names"]]
    key = sol["active_set"]
    cons = [([G[i, k] for k in range(n)], w[i]) for i in range(6)] + [rows[i] for i in key]
    P = [[2 * sum(weights[j] * J[j, r] * J[j, c] for j in range(m)) for c in range(n)]
         for r in range(n)]
    g = [2 * sum(weights[j] * J[j, r] * tp[j] for j in range(m)) for r in range(n)]
    f, nu = equality_qp(P, g, [a for a, _ in cons], [b for _, b in cons])
    tau = [sum(J[j, c] * f[c] for c in range(n)) - tp[j] for j in range(m)]
    sigma = sum(weights[j] * tau[j] ** 2 for j in range(m))
    others = [b - sum(a[c] * f[c] for c in range(n))
              for i, (a, b) in enumerate(rows) if i not in key]
    report(key, sigma, [-v for v in nu[6:]], others, sol["objective"])


if __name__ == "__main__":
    main()
