"""Python-side benchmarks of issue 10, measured in one run (docs/benchmarks.md):

1. ``grasp_torque.solve_batch`` against the Rust batch on the same arrays (the
   ``batch_arrays`` example, in-process timing): the Python overhead;
2. the same torque QPs through ``qpsolvers`` with Clarabel and with DAQP, one call per
   grasp as planners write it, against ``solve_batch`` on one thread: the ratio.

The qpsolvers QP is the usual contact-force formulation: minimise ``‖Jᵀ f‖²`` subject
to ``G f = w`` and the same inscribed N-sided pyramids (``shared/reference/README.md``,
item 4). The synthetic 3-finger grasps have ``[G; Jᵀ]`` of full column rank, so it has
the same optimum as grasp-torque's torque-space problem; the script checks that.

Run (after ``pip install ./python qpsolvers[clarabel] daqp``, from the repository root):
    python scripts/bench_python.py [--grasps 20000] [--qp-grasps 500]
"""

import argparse
import json
import warnings
import os
import subprocess
import tempfile
import time

import numpy as np

import grasp_torque as gt

MU, SIDES = 0.7, 8
CONTACTS = [{"model": "pcwf", "mu": MU}] * 3


def best_of(f, repeats):
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t)
    return best


def rust_batch(G, JT, W, threads, repeats):
    """Seconds of the Rust batch on the same arrays (best of `repeats`)."""
    W3 = W if W.ndim == 3 else W[:, None, :]
    B, K, m, n = G.shape[0], W3.shape[1], JT.shape[1], G.shape[2]
    with tempfile.NamedTemporaryFile(suffix=".bin", delete=False) as f:
        np.array([B, K, m, n], dtype="<u8").tofile(f)
        for a in (G, JT, W3):
            np.ascontiguousarray(a, dtype="<f8").tofile(f)
        path = f.name
    try:
        # Built as the extension is (python/Cargo.toml: thin LTO, one codegen unit), in
        # a target folder of its own: like for like.
        env = dict(os.environ, CARGO_PROFILE_RELEASE_LTO="thin", CARGO_PROFILE_RELEASE_CODEGEN_UNITS="1",
                   CARGO_TARGET_DIR=os.path.join("target", "bench-python"))
        out = subprocess.run(
            ["cargo", "run", "--release", "-q", "-p", "grasp-torque", "--example", "batch_arrays",
             "--", path, str(MU), str(threads), str(repeats)],
            check=True, capture_output=True, text=True, env=env,
        )
    finally:
        os.unlink(path)
    return json.loads(out.stdout)["seconds"]


def pyramid(mu, n_sides):
    """Rows s with s·[fx, fy, fz] ≤ 0: the inscribed pyramid's faces, and fz ≥ 0."""
    rows = []
    for j in range(n_sides):
        phi = (2 * j + 1) * np.pi / n_sides
        rows.append([np.cos(phi), np.sin(phi), -mu * np.cos(np.pi / n_sides)])
    rows.append([0.0, 0.0, -1.0])
    return np.array(rows)


def qp_of(G, JT, w):
    n = G.shape[1]
    P = JT.T @ JT
    face = pyramid(MU, SIDES)
    Gin = np.zeros((face.shape[0] * (n // 3), n))
    for c in range(n // 3):
        Gin[c * face.shape[0]:(c + 1) * face.shape[0], 3 * c:3 * c + 3] = face
    return P, np.zeros(n), Gin, np.zeros(Gin.shape[0]), G, w


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--grasps", type=int, default=20000)
    ap.add_argument("--qp-grasps", type=int, default=500)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()

    print("## Python solve_batch against the Rust batch (same arrays, best of", args.repeats, "runs)")
    print("| wrenches/grasp | threads | Rust batch (grasps/s) | Python solve_batch (grasps/s) | overhead |")
    print("|---|---|---|---|---|")
    for K in (0, 6):
        G, JT, W = gt.synthetic_grasps(args.grasps, wrenches=K, seed=0)
        for threads in (1, 2):
            rust = rust_batch(G, JT, W, threads, args.repeats)
            py = best_of(lambda: gt.solve_batch(G, JT, W, CONTACTS, sides=SIDES, threads=threads), args.repeats)
            print(f"| {max(K, 1)} | {threads} | {args.grasps / rust:,.0f} | {args.grasps / py:,.0f} | {100 * (py / rust - 1):+.1f} % |")

    import qpsolvers

    # qpsolvers converts dense matrices for Clarabel and says so on every call.
    warnings.filterwarnings("ignore", module="qpsolvers")

    B = args.qp_grasps
    G, JT, W = gt.synthetic_grasps(B, seed=1)
    ours = gt.solve_batch(G, JT, W, CONTACTS, sides=SIDES, threads=1)
    t_ours = best_of(lambda: gt.solve_batch(G, JT, W, CONTACTS, sides=SIDES, threads=1), args.repeats) / B
    problems = [qp_of(G[b], JT[b], W[b]) for b in range(B)]
    print()
    print(f"## qpsolvers against solve_batch ({B} synthetic 3-finger PCwF grasps, N = {SIDES}, one thread)")
    print("| solver | per grasp (µs) | ratio to grasp_torque | optimal | max rel. objective difference |")
    print("|---|---|---|---|---|")
    print(f"| grasp_torque.solve_batch | {1e6 * t_ours:.1f} | 1 | {int((ours.status == 0).sum())} | — |")
    for solver in ("clarabel", "daqp"):
        if solver not in qpsolvers.available_solvers:
            print(f"| qpsolvers + {solver} | not installed | | | |")
            continue
        xs = []
        t = time.perf_counter()
        for P, q, Gin, h, A, b in problems:
            xs.append(qpsolvers.solve_qp(P, q, Gin, h, A, b, solver=solver))
        per = (time.perf_counter() - t) / B
        diff, ok = 0.0, 0
        for b, x in enumerate(xs):
            if x is None:
                continue
            ok += 1
            sigma = float(np.sum((JT[b] @ x) ** 2))
            if ours.status[b] == 0:
                diff = max(diff, abs(sigma - ours.objective[b]) / ours.objective[b])
        print(f"| qpsolvers + {solver} | {1e6 * per:.1f} | {per / t_ours:.0f}× | {ok} | {diff:.1e} |")


if __name__ == "__main__":
    main()
