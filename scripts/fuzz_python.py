#!/usr/bin/env python3
"""Hostile calls into the Python package: `solve_batch`, `Hand.solve_batch`,
`Hand.frames`, `Hand.arrays`, `Solver` and `Problem.from_arrays` with arrays mutated
per seed (an entry set to NaN, inf, a subnormal, 1e308 or 0; the array scaled by
1e±300; other dtypes: float32, int, complex, object, bool; Fortran order or reversed; a
row or axis dropped or added; empty; nested lists; a string) and keywords set to wrong
values, and `Problem.from_dict` on the bundled problems edited as
`scripts/fuzz_commands.py` edits them. Every call must return or raise
`ValueError`/`TypeError` with a message; an `optimal` answer must be finite.

Usage: python3 scripts/fuzz_python.py FROM COUNT   (with the package installed, from the
repository root)
"""
import json
import os
import random
import sys

import numpy as np

import grasp_torque as gt
from fuzz_commands import FILES, mutate as edit_problem

HOSTILE = [np.nan, np.inf, -np.inf, 1e308, -1e308, 1e-320, 0.0, -0.0, 1e13, 1e12, 1e-12, 5e-324]


def mutate(rnd, a):
    a = np.array(a, dtype=float, copy=True)
    r = rnd.random()
    if r < 0.4 and a.size:
        a[tuple(rnd.randrange(s) for s in a.shape)] = rnd.choice(HOSTILE)
        return a
    if r < 0.5:
        return a * rnd.choice([1e-300, 1e300, 1e10, -1, 0])
    if r < 0.6:
        return a.astype(rnd.choice([np.float32, np.int64, np.complex128, object, np.bool_]))
    if r < 0.7:
        return np.asfortranarray(a) if a.ndim > 1 else a[::-1]
    if r < 0.8 and a.ndim:
        ax = rnd.randrange(a.ndim)
        return np.delete(a, 0, axis=ax) if a.shape[ax] else a
    if r < 0.85:
        return a[..., None]
    if r < 0.9:
        return np.zeros((0,) + a.shape[1:])
    if r < 0.95:
        return a.tolist()
    return "abc"


def main():
    start, count = int(sys.argv[1]), int(sys.argv[2])
    base = gt.Problem.load("fixtures/hand3-pcwf.json")
    g0, jt0, w0 = np.array(base.grasp_matrix), np.array(base.jacobian_transpose), np.array(base.wrench)
    contacts = [{"model": "pcwf", "mu": 0.5}] * 3
    hand = gt.Hand("fixtures/urdf/allegro/allegro_hand_right.urdf")
    bad = 0

    def finite_where_optimal(out):
        status, torque = np.asarray(out.status), np.asarray(out.torque)
        return not (status == 0).any() or bool(np.all(np.isfinite(torque[status == 0])))

    for seed in range(start, start + count):
        rnd = random.Random(seed)
        b = rnd.choice([0, 1, 3])
        arrays = {"G": np.repeat(g0[None], b, 0), "JT": np.repeat(jt0[None], b, 0), "W": np.repeat(w0[None], b, 0)}
        cones = rnd.choice(["linear", "exact"])
        which = rnd.choice(["G", "JT", "W", "keyword", "keyword", "hand", "solver", "problem", "frames", "arrays",
                            "dict"])
        try:
            ok = True
            if which in arrays:
                arrays[which] = mutate(rnd, arrays[which])
                ok = finite_where_optimal(gt.solve_batch(arrays["G"], arrays["JT"], arrays["W"], contacts, cones=cones))
            elif which == "keyword":
                good = {"torque_weights": np.ones(9), "torque_limits": np.ones(9), "passive_torque": np.zeros(9),
                        "transmission": np.eye(9), "min_normal_force": 0.1, "sides": 8, "threads": 2,
                        "latitudes": 2, "sfce_spacing": "uniform"}
                k = rnd.choice(sorted(good))
                v = good[k]
                v = mutate(rnd, v) if isinstance(v, np.ndarray) else rnd.choice([-1, 0, 1e9, 2**64, np.nan, "x", None, 3.5, [1], 10**30])
                out = gt.solve_batch(arrays["G"], arrays["JT"], arrays["W"], contacts, cones=cones, **{k: v})
                ok = finite_where_optimal(out)
            elif which == "hand":
                q = mutate(rnd, np.zeros((max(b, 1), len(hand.joint_names))))
                tips = [{"link": "link_3.0_tip", "model": "pcwf", "mu": 0.6, "position": [0, 0, 0.01], "normal": [0, 0, -1]},
                        {"link": "link_15.0_tip", "model": "pcwf", "mu": 0.6, "position": [0, 0, 0.01], "normal": [0, 0, -1]}]
                if rnd.random() < 0.5:
                    rnd.choice(tips)[rnd.choice(["position", "normal", "mu", "link", "model"])] = rnd.choice(
                        [[np.nan, 0, 0], [0, 0, 0], [1e300, 0, 0], "bogus", -1, None, [1, 2]])
                w = np.tile([0, 0, -1, 0, 0, 0.0], (max(b, 1), 1))
                if rnd.random() < 0.3:
                    w = mutate(rnd, w)
                ok = finite_where_optimal(hand.solve_batch(q, w, tips, cones=cones))
            elif which == "frames":
                q = mutate(rnd, np.zeros((max(b, 1), len(hand.joint_names))))
                names = rnd.choice([[], ["link_3.0_tip"], ["link_3.0_tip", "base_link"], ["nope"], [1], "link_3.0_tip"])
                P, R = hand.frames(q, names, threads=rnd.choice([None, 1, 2, 3, 0, -1, 1025, 2.5, "2"]))
                ok = bool(np.all(np.isfinite(P)) and np.all(np.isfinite(R)))
            elif which == "arrays":
                q = mutate(rnd, np.zeros((max(b, 1), len(hand.joint_names))))
                tips = [{"link": "link_3.0_tip", "model": "pcwf", "mu": 0.6, "position": [0, 0, 0.01], "normal": [0, 0, -1]},
                        {"link": "link_15.0_tip", "model": "pcwf", "mu": 0.6, "position": [0, 0, 0.01], "normal": [0, 0, -1]}]
                extra = {}
                k = rnd.choice(["positions", "normals", "object_pose", "gravity", "object_mass", None])
                if k == "object_mass":
                    extra[k] = rnd.choice([-1, 0, np.nan, 1e300, "x", 0.2])
                elif k is not None:
                    shape = {"positions": (len(q), 2, 3), "normals": (len(q), 2, 3),
                             "object_pose": (len(q), 7), "gravity": (len(q), 3)}[k]
                    extra[k] = mutate(rnd, np.ones(shape))
                extra["threads"] = rnd.choice([None, 1, 2, 3, 0, -1, 1025, 2.5, "2"])
                a = hand.arrays(q, tips, **extra)
                good = [i for i in range(len(q)) if i not in a.errors]
                ok = bool(np.all(np.isfinite(a.G[good])) and np.all(np.isfinite(a.JT[good])))
            elif which == "dict":
                # A bundled problem of any form, edited as scripts/fuzz_commands.py does.
                source = rnd.choice(FILES)
                d = json.load(open(source))
                edit_problem(d, rnd)
                r = gt.Solver(gt.Problem.from_dict(d, base=os.path.dirname(source)), cones=cones).solve()
                ok = r.status != "optimal" or bool(np.all(np.isfinite(r.torque)))
            elif which == "solver":
                s = gt.Solver("fixtures/hand3-pcwf.json", cones=cones)
                for _ in range(4):
                    try:
                        r = s.solve(mutate(rnd, w0))
                        ok &= r.status != "optimal" or bool(np.all(np.isfinite(r.torque)))
                    except (ValueError, TypeError) as e:
                        ok &= bool(str(e))
            else:
                p = gt.Problem.from_arrays(mutate(rnd, g0), jt0, contacts, wrench=w0)
                r = gt.Solver(p, cones=cones).solve()
                ok = r.status != "optimal" or bool(np.all(np.isfinite(r.torque)))
            if not ok:
                bad += 1
                print(f"seed {seed} ({which}): a non-finite optimal answer")
        except (ValueError, TypeError) as e:
            if not str(e) or "panick" in str(e).lower():
                bad += 1
                print(f"seed {seed} ({which}): {type(e).__name__} {str(e)!r}")
        except BaseException as e:  # a panic surfaces as pyo3's PanicException
            bad += 1
            print(f"seed {seed} ({which}): {type(e).__name__}: {str(e)[:300]}")
    print(f"seeds {start}..{start + count}: {bad} bad")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
