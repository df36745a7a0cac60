#!/usr/bin/env python3
"""The optimum of one linearised problem's key set, in 50-digit arithmetic: an oracle
for the native solver's answer where its rows nearly depend on each other.

It takes the QP exactly as the native solver sees it (`grasp-torque export-qp FILE
--format json`: minimise Σ w_j τ_j² subject to H τ ≥ c and C τ = e) and the native
answer's key set K, and solves min Σ w_j τ_j² subject to C τ = e and H_K τ = c_K (the
KKT system, mpmath at 50 digits). Prints that σ, the key rows' multipliers (all ≥ 0
where K is optimal) and the largest violation of any other row (≤ 0 where the key
set's point is feasible), then the native σ beside it.

Usage: /tmp/cvx/bin/python scripts/key_set_optimum.py FILE [--sides N]   (after `cargo
build --release`; mpmath and numpy from PyPI)
"""
import json
import os
import subprocess
import sys

import mpmath as mp

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("GRASP_TORQUE_BIN", os.path.join(ROOT, "target", "release", "grasp-torque"))


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    mp.mp.dps = 50
    out = subprocess.run([BIN, "export-qp", sys.argv[1], *sys.argv[2:], "--format", "json"],
                         capture_output=True, text=True, check=True).stdout
    d = json.loads(out)
    sol = d["solution"]
    if sol.get("status") != "optimal":
        sys.exit(f"the native answer is {sol.get('status')}: no key set")
    key = sol["active_set"]
    H = [[mp.mpf(v) for v in row] for row in d["H"]]
    c = [mp.mpf(v) for v in d["c"]]
    C = [[mp.mpf(v) for v in row] for row in d["C"]]
    e = [mp.mpf(v) for v in d["e"]]
    W = [mp.mpf(v) for v in d["weights"]]
    m = len(W)
    rows, rhs = C + [H[i] for i in key], e + [c[i] for i in key]
    P = [[2 * W[i] if i == j else mp.mpf(0) for j in range(m)] for i in range(m)]
    tau, nu = equality_qp(P, [mp.mpf(0)] * m, rows, rhs)
    sigma = sum(W[j] * tau[j] ** 2 for j in range(m))
    others = [c[i] - sum(H[i][j] * tau[j] for j in range(m)) for i in range(len(c)) if i not in key]
    report(key, sigma, [-v for v in nu[len(C):]], others, sol["objective"])


def equality_qp(P, g, rows, rhs):
    """`x` minimising `½ xᵀ P x − gᵀ x` subject to `rows x = rhs`, and the rows'
    multipliers ν of the KKT system `P x + rowsᵀ ν = g` (a row held as `a·x ≥ b` has
    the multiplier −ν)."""
    n, k = len(g), len(rows)
    K, b = mp.zeros(n + k, n + k), mp.zeros(n + k, 1)
    for i in range(n):
        for j in range(n):
            K[i, j] = P[i][j]
        b[i] = g[i]
    for i in range(k):
        for j in range(n):
            K[j, n + i] = rows[i][j]
            K[n + i, j] = rows[i][j]
        b[n + i] = rhs[i]
    s = mp.lu_solve(K, b)
    return [s[j] for j in range(n)], [s[n + i] for i in range(k)]


def report(key, sigma, multipliers, others, native):
    """The oracle's lines: σ, the key rows' multipliers, the worst other row (c − a·x,
    > 0 violated) and the native σ."""
    print(f"key set {key}: σ {mp.nstr(sigma, 17)}")
    print(f"multipliers {[mp.nstr(v, 6) for v in multipliers]}")
    print(f"largest violation of another row {mp.nstr(max(others, default=mp.mpf(0)), 3)}")
    print(f"native σ {native!r}")


if __name__ == "__main__":
    main()
