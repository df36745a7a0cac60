#!/usr/bin/env python3
"""Large random grasps: 3 to 24 contacts on a 4 cm sphere (mixed FPC, PCwF, SFCl and
SFCe; one finger of 3 or 4 joints per contact, so up to about 90 joints), friction
0.1 to 1, and on some of them torque limits, minimum normal forces, weights 1e±2 and
other N. Whole-hand grasps are this size; the bundled fixtures and the sweep have 3 to
5 contacts.

`python3 scripts/large_grasps.py compare FROM COUNT` runs `grasp-torque compare` on
each (native and Clarabel, linear and exact cones) and lists every grasp whose verdict
is not agreement. `python3 scripts/large_grasps.py bench FROM COUNT [OTHER_BIN]` times
the exact cones' cold solve (`grasp-torque bench`, `cold_raw_us`) of the native
solver, of Clarabel and, given, of another build's native solver, one grasp after
another, and prints per grasp the sizes, the times and the native method, then the
median ratios over all grasps and over those the interior-point method answers.
`python3 scripts/large_grasps.py write SEED` prints one grasp as a problem file.

Needs numpy and `cargo build --release`; GRASP_TORQUE_BIN selects the binary.
"""
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("GRASP_TORQUE_BIN", os.path.join(ROOT, "target", "release", "grasp-torque"))


def skew(p):
    return np.array([[0, -p[2], p[1]], [p[2], 0, -p[0]], [-p[1], p[0], 0]])


def frame(n):
    z = n / np.linalg.norm(n)
    a = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(a, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z], axis=1)


def grasp(seed):
    rnd, rng = random.Random(seed), np.random.default_rng(seed)
    count = rnd.randint(3, 24)
    mu = rnd.choice([0.1, 0.2, 0.3, 0.5, 0.8, 1.0])
    blocks, contacts, dims = [], [], []
    for _ in range(count):
        p = rng.normal(size=3)
        p *= 0.04 / np.linalg.norm(p)
        r = frame(-p)
        model = rnd.choice(["pcwf", "sfcl", "sfce", "fpc"])
        d = {"fpc": 1, "pcwf": 3}.get(model, 4)
        axes = r[:, 2:3] if d == 1 else r
        g = np.zeros((6, d))
        g[:3, : axes.shape[1]] = axes
        g[3:, : axes.shape[1]] = skew(p) @ axes
        if d == 4:
            g[3:, 3] = r[:, 2]
        blocks.append(g)
        dims.append(d)
        c = {"model": model}
        if model != "fpc":
            c["mu"] = mu
        if model in ("sfcl", "sfce"):
            c["mu_torsion"] = 0.01
        contacts.append(c)
    g = np.concatenate(blocks, axis=1)
    rows, off = [], 0
    for d in dims:
        for _ in range(rnd.randint(3, 4)):
            row = np.zeros(g.shape[1])
            row[off : off + d] = rng.normal(scale=0.04, size=d)
            if d == 4:
                row[off + 3] = rng.choice([0.0, 1.0])
            rows.append(row)
        off += d
    m = len(rows)
    w = [0, 0, rnd.uniform(0.5, 20), rnd.uniform(-0.1, 0.1), rnd.uniform(-0.1, 0.1), rnd.uniform(-0.05, 0.05)]
    p = {"name": f"large-{seed}", "grasp_matrix": g.tolist(), "jacobian_transpose": np.array(rows).tolist(),
         "wrench": w, "contacts": contacts}
    if rnd.random() < 0.4:
        p["torque_limits"] = [rnd.uniform(0.01, 0.5) for _ in range(m)]
    if rnd.random() < 0.3:
        p["min_normal_force"] = [rnd.uniform(0, 0.5) for _ in range(count)]
    if rnd.random() < 0.3:
        p["torque_weights"] = [10 ** rnd.uniform(-2, 2) for _ in range(m)]
    if rnd.random() < 0.3:
        p["linearization"] = {"sides": rnd.choice([4, 6, 8, 12, 16])}
    return p


def written(seed):
    f = tempfile.NamedTemporaryFile("w", suffix=".json", delete=False)
    json.dump(grasp(seed), f)
    f.close()
    return f.name


def bench(binary, path, backend, repeats):
    out = subprocess.run([binary, "bench", path, "--cones", "exact", "--backend", backend, "--repeats",
                          str(repeats), "--format", "json"], capture_output=True, text=True)
    d = json.loads(out.stdout)
    return d["status"], d["cold_raw_us"]


def main():
    mode = sys.argv[1]
    if mode == "write":
        json.dump(grasp(int(sys.argv[2])), sys.stdout, indent=1)
        return
    start, count = int(sys.argv[2]), int(sys.argv[3])
    if mode == "compare":
        bad = 0
        for seed in range(start, start + count):
            path = written(seed)
            out = subprocess.run([BIN, "compare", path], capture_output=True, text=True)
            os.unlink(path)
            verdict = [l for l in out.stdout.splitlines() if l.startswith("verdict")]
            if out.returncode not in (0, 3, 4) or not verdict or not verdict[0].startswith("verdict: agree"):
                bad += 1
                print(f"seed {seed}: exit {out.returncode}", *out.stdout.splitlines()[-6:], sep="\n  ")
        print(f"{count} grasps: {bad} without agreement")
        sys.exit(1 if bad else 0)
    other = sys.argv[4] if len(sys.argv) > 4 else None
    ratios, others, by_ipm, solved = [], [], [], 0
    for seed in range(start, start + count):
        path = written(seed)
        p = grasp(seed)
        status, native = bench(BIN, path, "active-set", 20)
        cla_status, cla = bench(BIN, path, "clarabel", 5)
        out = subprocess.run([BIN, "solve", path, "--cones", "exact", "--format", "json"],
                             capture_output=True, text=True)
        method = json.loads(out.stdout).get("method")
        line = f"{seed} contacts {len(p['contacts'])} joints {len(p['jacobian_transpose'])} {status} {method}: native {native:.0f} µs, Clarabel {cla:.0f} µs ({cla_status})"
        old = None
        if other:
            _, old = bench(other, path, "active-set", 20)
            line += f", other build {old:.0f} µs"
        os.unlink(path)
        print(line, flush=True)
        solved += status == "optimal"
        ratios.append(cla / native)
        if method == "interior_point":
            by_ipm.append((cla / native, old / native if old else None))
    summary = lambda v: f"median {statistics.median(v):.2f} ({min(v):.2f}-{max(v):.2f})" if v else "none"
    print(f"{count} grasps, {solved} optimal, {len(by_ipm)} answered by the interior-point method")
    print(f"Clarabel / native exact: all {summary(ratios)}; interior-point ones {summary([r for r, _ in by_ipm])}")
    if other:
        print(f"other build / this one, interior-point ones: {summary([o for _, o in by_ipm])}")


if __name__ == "__main__":
    main()
