#!/usr/bin/env python3
"""Mutated problems through `grasp-torque solve`, every optimal answer checked from
the problem file alone, and again in other units.

Each seed takes one bundled problem in matrix form (`fixtures/*.json`,
`fixtures/sweep/*.json`, and the geometry, hand and Table 1 problems through
`grasp-torque build`, transmissions and passive torques included) and makes one
to three edits within the input domain: a row of Jᵀ scaled by 10^±9, made a multiple
of another (×1, ×−1, ×(1 + 1e-12), ×1e-8) or reduced to one tiny entry; noise of
1e-15 to 1e-8 on G or Jᵀ; the wrench scaled, zeroed or pushed along one component; a
friction coefficient or torsional length scaled; torque limits (symmetric, one-sided,
tendons that only pull), a minimum normal force, torque weights 1e±4 apart; the
Euclidean internal forces. It solves the problem with linear and exact cones and
checks each `optimal` or `almost_optimal` answer against the file, not the solver's
diagnostics:
- `G f = w` and `Jᵀ f = T u + τ_p` (τ = u without a transmission T or passive
  torques τ_p), each row to 1e-7 of the normwise terms `‖row‖₁ ‖f‖∞ +
  |target|` of the largest row of its block (G's force rows, G's moment rows, Jᵀ): a
  row within the rank tolerance of its block's largest is rounding to the model, which
  sets it to 0;
- each contact's force in its exact cone (the inscribed polyhedra lie inside it),
  to 1e-7 of the largest force in the force metric (mz as mz/mu_torsion);
- every torque within its limits, exactly;
- σ = Σ w_j τ_j² (to 1e-9), and σ* ≤ σ(N) when both are optimal;
- the same status (where both are `optimal` or `infeasible`), and σ × (F L)², with
  forces in units F times smaller and lengths L times smaller (mz and moments F L,
  mu_torsion L, torques F L), unless the problem uses the Euclidean internal forces or
  the paper's SFCe latitudes, which are not unit-free by design (README, "Problem
  files"), or the other units leave the input domain (σ at rounding of zero, below
  `zero_sigma`, compares as zero).
It also checks that the report agrees with the status: every check's ratio
(`diagnostics.*_check`) at most 1 on an `optimal` answer, one above 1 on an answer the
residual check refused. It reports each failure of these, each run that exits other
than 0, 2, 3 or 4, and each `numerical_failure` or `iteration_limit` (not a wrong
answer, but no answer: all seen so far come from a row of Jᵀ far from the others'
size, a joint whose moment arms are 1e-6 to 1e-9 of the others' or as many times
larger, or a singular value of [G; Jᵀ] within a factor of 10 of the rank tolerance;
docs/solver.md, "Limits").

`fuzz_answers.py pinned-limits FROM COUNT` makes one joint of each of the sweep's
grasps one whose torque the wrench fixes (its row of Jᵀ a multiple of a combination
of G's rows), with one side of its limit exactly at that torque, and checks that the
answer is the one without the limit, in any units. `fuzz_answers.py statuses FROM
COUNT OTHER_BIN [N...] [clarabel]` lists the seeds of the main search whose status, or
optimal σ beyond 1e-12, differs between this binary and OTHER_BIN (exact cones, and
linear ones at each N given, else at the file's; with `clarabel`, Clarabel's
answers). `fuzz_answers.py spreads FROM COUNT` counts the main search's answers (linear at N = 8
and 16, and exact) that state how far their rows' rounding moves σ, and lists them.
`fuzz_answers.py infeasible FROM COUNT` solves each of the main search's
problems that the native exact solver calls infeasible again with Clarabel's exact
cones, and lists those Clarabel holds with every contact inside its cone (friction
margins above −1e-3: an answer within the check's tolerance of the largest force can
leave a small contact well outside).

`fuzz_answers.py joint-rows FROM COUNT` solves each of the main search's problems
that the native solver calls infeasible (linear cones at the file's N, and exact; not
an unreachable wrench) again with each joint's torque in a unit of its own (each row of
Jᵀ divided by its largest entry, a row the model made zero left zero), with both
backends, and lists those either holds with every contact inside its cone: the
admissible forces are the same, so each is a false `infeasible`.

`fuzz_answers.py nested FROM COUNT` solves each of the main search's problems with
linear cones at N = 4, 8, 16, 32 and 64 and with exact cones, and lists every pair of
runs where more sides (or the exact cones) give a higher optimal σ or call a grasp
infeasible that fewer sides hold: each polygon's vertices are among the next one's, so
either is a wrong answer.

`fuzz_answers.py backends FROM COUNT` solves each of the main search's problems with
the native solver and with Clarabel, linear cones (the file's N) and exact, and lists
each run where one backend calls the grasp infeasible and the other answers it, with
whether that answer passes the checks above: a feasible answer that does makes the
`infeasible` wrong. `fuzz_answers.py write SEED` prints the main search's problem for
SEED, for the command line (`grasp-torque compare`, say).

`fuzz_answers.py joint-units FROM COUNT` solves the sweep's grasps with each joint's
torque in its own unit (Jᵀ's row times s_j, 10^U(−2, 2), the weight 1/s_j²) and
compares status and σ with the SI answer. `fuzz_answers.py moment-arms SCALE FROM
COUNT` solves the sweep's grasps (seeds FROM.., at normal and at a quarter of the
friction; `fallbacks write`) with one joint's moment arms scaled by SCALE, the same
checks on each optimal answer, and counts the statuses.

Usage: python3 scripts/fuzz_answers.py FROM COUNT   (numpy; after `cargo build --release`
and `cargo build --release -p grasp-torque --example fallbacks`); another build of the
binary (an older commit's, say) with GRASP_TORQUE_BIN=path/to/grasp-torque.
"""
import glob
import json
import math
import os
import random
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("GRASP_TORQUE_BIN") or os.path.join(ROOT, "target", "release", "grasp-torque")


def sources():
    """(name, problem) for every matrix-form fixture, and for the geometry- and hand-form
    ones in matrix form (`grasp-torque build`), transmissions and passive torques
    included."""
    out = []
    for f in sorted(glob.glob(os.path.join(ROOT, "fixtures", "*.json")) + glob.glob(os.path.join(ROOT, "fixtures", "sweep", "*.json"))):
        p = json.load(open(f))
        if "grasp_matrix" in p:
            out.append((os.path.basename(f), p))
    for d in ("geometry", "hands", "table1"):
        for f in sorted(glob.glob(os.path.join(ROOT, "fixtures", d, "*.json"))):
            built = subprocess.run([BIN, "build", f], capture_output=True, text=True)
            if built.returncode == 0:
                out.append((f"{d}/{os.path.basename(f)}", json.loads(built.stdout)))
    return out


DIM = {"fpc": 1, "pcwf": 3, "sfcl": 4, "sfce": 4}
TOL = 1e-7


def mutate(rnd, p):
    """One to three edits of `p`, in place; returns their names."""
    G = np.array(p["grasp_matrix"], float)
    JT = np.array(p["jacobian_transpose"], float)
    w = np.array(p["wrench"], float)
    m, n = JT.shape
    # Limits and weights are per actuator where a transmission maps actuators to joints.
    a = len(p["transmission"][0]) if p.get("transmission") else m
    contacts = [dict(c) for c in p["contacts"]]
    rng = np.random.default_rng(rnd.randrange(1 << 30))
    edits = []
    for _ in range(rnd.randint(1, 3)):
        r = rnd.random()
        i, j = rnd.randrange(m), rnd.randrange(m)
        c = rnd.randrange(len(contacts))
        if r < 0.12:
            JT[i] *= 10 ** rnd.uniform(-9, 9)
            edits.append(f"Jᵀ row {i} scaled")
        elif r < 0.2:
            JT[i] = JT[j] * rnd.choice([1, -1, 1 + 1e-12, 1e-8])
            edits.append(f"Jᵀ row {i} a multiple of row {j}")
        elif r < 0.28:
            JT[i] = 0
            JT[i, rnd.randrange(n)] = 10 ** rnd.uniform(-14, -6)
            edits.append(f"Jᵀ row {i} one tiny entry")
        elif r < 0.36:
            w *= 10 ** rnd.uniform(-8, 8)
            edits.append("wrench scaled")
        elif r < 0.42:
            w[:] = 0
            edits.append("wrench zero")
        elif r < 0.5:
            k = rnd.randrange(6)
            w[k] += rnd.choice([-1, 1]) * 10 ** rnd.uniform(-3, 2) * (np.abs(w).max() + 1)
            edits.append(f"wrench[{k}] pushed")
        elif r < 0.58:
            G += rng.normal(size=G.shape) * 10 ** rnd.uniform(-15, -8) * np.abs(G).max()
            edits.append("noise on G")
        elif r < 0.64:
            JT += rng.normal(size=JT.shape) * 10 ** rnd.uniform(-15, -8) * np.abs(JT).max()
            edits.append("noise on Jᵀ")
        elif r < 0.7 and "mu" in contacts[c]:
            contacts[c]["mu"] = min(1e3, max(1e-3, contacts[c]["mu"] * 10 ** rnd.uniform(-3, 3)))
            edits.append(f"contacts[{c}].mu")
        elif 0.7 <= r < 0.76 and "mu_torsion" in contacts[c]:
            contacts[c]["mu_torsion"] = min(1e9, max(1e-9, contacts[c]["mu_torsion"] * 10 ** rnd.uniform(-6, 6)))
            edits.append(f"contacts[{c}].mu_torsion")
        elif 0.76 <= r < 0.84:
            limits = []
            for _ in range(a):
                x, s = rnd.random(), 10 ** rnd.uniform(-2, 3)
                limits.append(None if x < 0.3 else s if x < 0.7 else [rnd.choice([None, -s]), rnd.choice([None, s, 0.0])])
            p["torque_limits"] = limits
            edits.append("torque limits")
        elif 0.84 <= r < 0.9:
            p["min_normal_force"] = 10 ** rnd.uniform(-4, 1)
            edits.append("minimum normal force")
        elif 0.9 <= r < 0.95:
            base = 10 ** rnd.uniform(-4, 4)
            p["torque_weights"] = [base * 10 ** rnd.uniform(-2, 2) for _ in range(a)]
            edits.append("torque weights")
        elif r >= 0.95:
            p["internal_forces"] = rnd.choice(["euclidean", "compliance"])
            edits.append(f"internal forces {p['internal_forces']}")
    # Within the input domain: |v| ≤ 1e12, no subnormals.
    domain = lambda a: np.where(np.abs(a) < 2.3e-308, 0.0, np.clip(a, -1e12, 1e12)).tolist()
    p["grasp_matrix"], p["jacobian_transpose"], p["wrench"] = domain(G), domain(JT), domain(w)
    p["contacts"] = contacts
    return edits


def zero_sigma(p):
    """σ at or below this is rounding of zero: torques of 1e-10 of the problem's own
    scale (the largest row of Jᵀ times the wrench's force, |Jᵀ| |w| / |G|, each the
    largest entry), weighted. Where no torque is needed (the geometry pinch with rows of
    Jᵀ made dependent, seeds 197726 and 209650), σ came out at 3e-34 in one system of
    units and 4e-25 in another, which a relative comparison calls different."""
    G, JT = np.abs(np.array(p["grasp_matrix"], float)), np.abs(np.array(p["jacobian_transpose"], float))
    w = np.abs(np.array(p["wrench"], float))
    if G.max() == 0.0:
        return 0.0
    torque = 1e-10 * JT.max() * w.max() / G.max()
    weights = p.get("torque_weights") or [1.0]
    return torque * torque * max(weights) * len(JT)


def in_units(p, F, L):
    """`p` with forces in units F times smaller and lengths L times smaller."""
    q = json.loads(json.dumps(p))
    G, JT = np.array(q["grasp_matrix"]), np.array(q["jacobian_transpose"])
    moment = []
    for c in q["contacts"]:
        d = DIM[c["model"]]
        moment += [False] * min(d, 3) + [True] * (d - 3)
        if "mu_torsion" in c:
            c["mu_torsion"] *= L
    force = ~np.array(moment)
    G[3:, force] *= L
    # (A force row's entry on a moment component, zero unless perturbed, is per length.)
    G[:3, ~force] /= L
    JT[:, force] *= L
    q["grasp_matrix"], q["jacobian_transpose"] = G.tolist(), JT.tolist()
    q["wrench"] = [v * F for v in q["wrench"][:3]] + [v * F * L for v in q["wrench"][3:]]
    scale = lambda t: None if t is None else t * F * L
    if "torque_limits" in q:
        q["torque_limits"] = [[scale(x) for x in t] if isinstance(t, list) else scale(t) for t in q["torque_limits"]]
    if "passive_torque" in q:
        q["passive_torque"] = [v * F * L for v in q["passive_torque"]]
    if "min_normal_force" in q:
        fmin = q["min_normal_force"]
        q["min_normal_force"] = [v * F for v in fmin] if isinstance(fmin, list) else fmin * F
    return q


def solve(p, cones, *extra):
    """The answer as JSON, or None and why."""
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(p, f)
    try:
        out = subprocess.run([BIN, "solve", f.name, "--format", "json", "--cones", cones, *extra],
                             capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        return None, "hung (60 s)"
    finally:
        os.unlink(f.name)
    if out.returncode == 2:
        return None, "refused: " + out.stderr.strip()[:200]
    if out.returncode not in (0, 3, 4):
        return None, f"exit {out.returncode}: {out.stderr.strip()[:300]}"
    return json.loads(out.stdout), None


def wrong(p, d):
    """What is wrong with the optimal answer `d` of `p`, from the file alone."""
    G, JT, w = np.array(p["grasp_matrix"]), np.array(p["jacobian_transpose"]), np.array(p["wrench"])
    f = np.concatenate([np.atleast_1d(np.array(c, float)) for c in d["contact_forces"]])
    tau = np.array(d["torque"], float)
    # Jᵀ f = T u + τ_p with a transmission T and passive torques τ_p (u: the answer's
    # torques, per actuator).
    T = np.array(p["transmission"], float) if p.get("transmission") else np.eye(len(tau))
    passive = np.array(p.get("passive_torque") or np.zeros(T.shape[0]), float)
    joint = T @ tau + passive
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(tau)) and math.isfinite(d["objective"])):
        return ["non-finite"]
    out = []
    # f is Z [w; T u + τ_p] (Z = [G; Jᵀ]⁺) plus internal forces, so its rounding is
    # relative to |Z| times the terms it is formed from, which a force cancelled to
    # nearly zero does not show (a joint's actuator against its passive torque
    # through a short arm: forces of 1e-12 N formed from terms of 1 N).
    joint_terms = np.abs(T) @ np.abs(tau) + np.abs(passive)
    formed = np.abs(np.linalg.pinv(np.vstack([G, JT]))) @ np.concatenate([np.abs(w), joint_terms])
    fmax = max(np.abs(f).max(), formed.max())
    for name, A, target, target_terms in (("G f − w", G, w, np.abs(w)), ("Jᵀ f − τ", JT, joint, joint_terms)):
        r = np.abs(A @ f - target)
        terms = np.abs(A).sum(axis=1) * fmax + target_terms
        # Normwise over a block (the joints; G's force rows, its moment rows): a row
        # within the rank tolerance of its block's largest is rounding to the model,
        # which sets it to 0.
        blocks = [slice(0, 3), slice(3, 6)] if name.startswith("G") else [slice(None)]
        for b in blocks:
            terms[b] = terms[b].max()
        i = int(np.argmax(r - TOL * terms))
        if r[i] > TOL * terms[i]:
            out.append(f"{name}: row {i} misses by {r[i]:.3e} (terms {terms[i]:.3e})")
    k, metric = 0, []
    for c in p["contacts"]:
        d_ = DIM[c["model"]]
        metric += [1.0] * min(d_, 3) + ([1 / c["mu_torsion"]] if d_ == 4 else [])
    fscale = max(np.abs(f * np.array(metric)).max(), (formed * np.array(metric)).max())
    for i, c in enumerate(p["contacts"]):
        x = f[k:k + DIM[c["model"]]]
        k += len(x)
        fz = x[0] if len(x) == 1 else x[2]
        ft = 0.0 if len(x) == 1 else math.hypot(x[0], x[1])
        mz = abs(x[3]) / c["mu_torsion"] if len(x) == 4 else 0.0
        g = {"fpc": 0.0, "pcwf": ft / c.get("mu", 1), "sfcl": ft / c.get("mu", 1) + mz,
             "sfce": math.hypot(ft / c.get("mu", 1), mz)}[c["model"]]
        miss = max(g - fz, -fz)
        if miss > TOL * fscale:
            out.append(f"contact {i} ({c['model']}) outside its cone by {miss:.3e} (largest force {fscale:.3e})")
    weights = p.get("torque_weights") or [1.0] * len(tau)
    sigma = float(np.dot(weights, tau * tau))
    if abs(sigma - d["objective"]) > 1e-9 * abs(sigma):
        out.append(f"σ {d['objective']} but Σ w τ² = {sigma}")
    for j, t in enumerate(p.get("torque_limits") or []):
        lo, hi = (-t, t) if isinstance(t, (int, float)) else (-math.inf if t is None or t[0] is None else t[0], math.inf if t is None or t[1] is None else t[1])
        if not lo <= tau[j] <= hi:
            out.append(f"τ[{j}] = {tau[j]} outside [{lo}, {hi}]")
    return out


CHECKS = ("wrench_check", "torque_check", "violation_check", "cone_check")


def misreported(d):
    """Where the report contradicts the status: each check's ratio is its worst row
    against that row's bound, so an optimal answer has all of them at most 1 and one
    refused by the residual check has one above 1."""
    ratios = {k: (d.get("diagnostics") or {}).get(k) for k in CHECKS}
    if any(v is None for v in ratios.values()):
        return []
    worst = max(ratios.values())
    if d["status"] == "optimal" and worst > 1:
        return [f"a check's ratio is {worst:.3g} ({ratios})"]
    if (d.get("reason") or {}).get("kind") == "residual_check" and not worst > 1:
        return [f"refused by the residual check with every ratio at most 1 ({ratios})"]
    return []


def sweep_grasps(start, count):
    """The sweep's grasps (`fallbacks write SEED:FRICTION`), seeds FROM.. at normal and
    at a quarter of the friction."""
    fallbacks = os.path.join(ROOT, "target", "release", "examples", "fallbacks")
    for seed in range(start, start + count):
        for friction in ("1", "0.25"):
            text = subprocess.run([fallbacks, "write", f"{seed}:{friction}"], capture_output=True,
                                  text=True, check=True).stdout
            yield seed, friction, json.loads(text)


def joint_units(start, count):
    """The sweep's grasps with each joint's torque in its own unit (its row of Jᵀ times
    s_j, 10^U(−2, 2), the weight 1/s_j², within the documented ratio of 1e8): the same
    status and σ as in SI units."""
    problems, same = 0, 0
    for seed, friction, p in sweep_grasps(start, count):
        rnd = random.Random(seed)
        s = [10 ** rnd.uniform(-2, 2) for _ in p["jacobian_transpose"]]
        q = json.loads(json.dumps(p))
        q["jacobian_transpose"] = [[v * sj for v in row] for sj, row in zip(s, p["jacobian_transpose"])]
        q["torque_weights"] = [1 / (sj * sj) for sj in s]
        for cones in ("linear", "exact"):
            (a, _), (b, _) = solve(p, cones), solve(q, cones)
            differ = a["status"] != b["status"] or (
                a["status"] == "optimal" and abs(a["objective"] - b["objective"]) > 1e-7 * abs(a["objective"]))
            if differ:
                print(f"seed {seed}:{friction} {cones}: {a['status']} σ {a.get('objective')} became {b['status']} σ {b.get('objective')}")
            problems += differ
            same += not differ
    print(f"joints in their own units, {2 * count} grasps: {same} answers the same, {problems} not")
    sys.exit(1 if problems else 0)


def moment_arms(scale, start, count):
    """The sweep's grasps, each with one joint's row of Jᵀ scaled by `scale`: the
    statuses, and every optimal answer checked as above."""
    counts, problems = {}, 0
    for seed, friction, p in sweep_grasps(start, count):
        j = random.Random(seed).randrange(len(p["jacobian_transpose"]))
        p["jacobian_transpose"][j] = [v * scale for v in p["jacobian_transpose"][j]]
        for cones in ("linear", "exact"):
            d, why = solve(p, cones)
            status = d["status"] if d else why
            counts[(cones, status)] = counts.get((cones, status), 0) + 1
            if status not in ("optimal", "infeasible"):
                print(f"seed {seed}:{friction} {cones}: {status} (joint {j})")
            for what in wrong(p, d) if d and status == "optimal" else []:
                print(f"seed {seed}:{friction} {cones}: optimal, but {what}")
                problems += 1
    print(f"one joint's moment arms × {scale:g}, {2 * count} grasps: {problems} wrong answers; statuses {dict(sorted(counts.items()))}")
    sys.exit(1 if problems else 0)


def pinned_limits(start, count):
    """The sweep's grasps, each with one joint's row of Jᵀ made `s cᵀ G` (so that the
    equalities pin its torque to `s c·w`; c random, s 10^U(−3, 6)) and one side of its
    limit exactly there: every admissible torque meets the limit, so the status and σ
    must be the problem's without it, and the same in other units."""
    counts, problems = {}, 0
    for seed, friction, p in sweep_grasps(start, count):
        rnd = random.Random(f"{seed}:{friction}")
        G, JT, w = np.array(p["grasp_matrix"]), np.array(p["jacobian_transpose"]), np.array(p["wrench"])
        j = rnd.randrange(len(JT))
        c = np.array([rnd.gauss(0, 1) if rnd.random() < 0.5 else 0.0 for _ in range(6)])
        if not c.any():
            c[rnd.randrange(6)] = 1.0
        scale = 10 ** rnd.uniform(-3, 6)
        JT[j] = scale * (c @ G)
        pinned = float(scale * (c @ w))
        p["jacobian_transpose"] = JT.tolist()
        q = json.loads(json.dumps(p))
        span = 10 * abs(pinned) + 1.0
        q["torque_limits"] = [None] * len(JT)
        q["torque_limits"][j] = [pinned - span, pinned] if rnd.random() < 0.5 else [pinned, pinned + span]
        F, L = 10 ** rnd.uniform(-3, 3), 10 ** rnd.uniform(-3, 3)
        for cones in ("linear", "exact"):
            (a, _), (b, _), (u, _) = solve(p, cones), solve(q, cones), solve(in_units(q, F, L), cones)
            # (None: the other units left the input domain.)
            u = u or {"status": None}
            counts[(cones, b["status"])] = counts.get((cones, b["status"]), 0) + 1
            at = f"seed {seed}:{friction} {cones} (joint {j} × {scale:.2g})"
            decisive = ("optimal", "infeasible")
            if a["status"] in decisive and b["status"] != a["status"]:
                print(f"{at}: {a['status']} without the limit, {b['status']} with it")
                problems += 1
            elif a["status"] == b["status"] == "optimal" and abs(a["objective"] - b["objective"]) > 1e-8 * a["objective"]:
                print(f"{at}: σ {a['objective']} without the limit, {b['objective']} with it")
                problems += 1
            if b["status"] in decisive and u["status"] in decisive and b["status"] != u["status"]:
                print(f"{at}: {b['status']} in SI units, {u['status']} in others")
                problems += 1
    print(f"a limit at a pinned torque, {2 * count} grasps: {problems} wrong answers; statuses {dict(sorted(counts.items()))}")
    sys.exit(1 if problems else 0)


def statuses(start, count, other, sides=(), backend=()):
    """Seeds FROM.. of the main search solved by this binary and by `other` (an older
    commit's, say): each status that differs, and each σ that differs by more than
    1e-12 relative where both are optimal; exact cones, and linear ones at the file's
    N or at each of `sides`; with `backend`, its arguments (`--backend clarabel`)."""
    bundled, changed, moved = sources(), 0, 0
    global BIN
    runs = [("exact", backend)] + ([("linear", ("--sides", str(n), *backend)) for n in sides]
                                   or [("linear", backend)])
    for seed in range(start, start + count):
        name, p, edits, rnd = seed_problem(bundled, seed)
        for cones, extra in runs:
            here = solve(p, cones, *extra)[0] or {}
            BIN, mine = other, BIN
            there = solve(p, cones, *extra)[0] or {}
            BIN = mine
            a, b = there.get("status"), here.get("status")
            what = f"seed {seed} ({name}: {', '.join(edits)}) {cones} {' '.join(extra)}".rstrip()
            if a != b:
                print(f"{what}: {a} there, {b} here")
                changed += 1
            elif a == "optimal" and abs(there["objective"] - here["objective"]) > 1e-12 * abs(there["objective"]):
                print(f"{what}: σ {there['objective']!r} there, {here['objective']!r} here")
                moved += 1
    print(f"{count} problems: {changed} statuses differ, {moved} optimal σ differ by more than 1e-12")


def infeasible(start, count):
    """Seeds FROM.. of the main search that the native exact solver calls infeasible
    and Clarabel's exact cones hold with every contact inside its cone."""
    bundled, kinds, held = sources(), {}, 0
    for seed in range(start, start + count):
        name, p, edits, rnd = seed_problem(bundled, seed)
        d = solve(p, "exact")[0]
        if not d or d["status"] != "infeasible":
            continue
        kind = d["reason"]["kind"]
        kinds[kind] = kinds.get(kind, 0) + 1
        with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
            json.dump(p, f)
        try:
            out = subprocess.run([BIN, "solve", f.name, "--format", "json", "--cones", "exact",
                                  "--backend", "clarabel"], capture_output=True, text=True,
                                 timeout=60)
        finally:
            os.unlink(f.name)
        try:
            c = json.loads(out.stdout)
        except ValueError:
            continue
        margins = [m for m in c["diagnostics"].get("friction_margins", []) if m is not None]
        if c["status"] == "optimal" and min(margins, default=0.0) > -1e-3:
            held += 1
            print(f"seed {seed} ({name}: {', '.join(edits)}): infeasible ({kind}), "
                  f"Clarabel optimal at σ = {c['objective']}")
    print(f"{count} problems, {sum(kinds.values())} infeasible {kinds}: {held} that "
          f"Clarabel holds")


def in_joint_rows(p, d):
    """`p` with each joint's torque in a unit of its own: its row of Jᵀ divided by its
    largest entry (its limits, passive torque and row of the transmission likewise), so that the rows are of
    one size; the rows the model made zero in `d`'s answer (its warnings) zero. The
    admissible forces are the same, so the grasp is feasible exactly where `p` is."""
    q = json.loads(json.dumps(p))
    names = d.get("joint_names") or []
    zeroed = {w.split(":")[0] for w in d.get("warnings", []) if "the model makes it zero" in w}
    JT = np.array(q["jacobian_transpose"], float)
    s = np.ones(len(JT))
    for j, row in enumerate(JT):
        big = np.abs(row).max()
        if j < len(names) and names[j] in zeroed:
            JT[j] = 0.0
        elif big > 0:
            s[j] = 1 / big
    q["jacobian_transpose"] = (JT * s[:, None]).tolist()
    scale = lambda t, sj: None if t is None else t * sj
    if "transmission" in q:
        # Joint torques T u: its rows take the joints' units; the limits are the
        # actuators'.
        q["transmission"] = [[v * sj for v in row] for row, sj in zip(q["transmission"], s)]
    elif "torque_limits" in q:
        q["torque_limits"] = [[scale(x, sj) for x in t] if isinstance(t, list) else scale(t, sj)
                              for t, sj in zip(q["torque_limits"], s)]
    if "passive_torque" in q:
        q["passive_torque"] = [v * sj for v, sj in zip(q["passive_torque"], s)]
    q.pop("torque_weights", None)
    return q


def joint_rows(start, count):
    """Seeds FROM.. of the main search that the native solver calls infeasible (linear
    cones at the file's N, and exact), solved again with each joint's torque in a unit
    of its own (`in_joint_rows`) by both backends: each held there with every contact
    inside its cone is a false `infeasible`."""
    bundled, infeasible_runs, held = sources(), 0, 0
    for seed in range(start, start + count):
        name, p, edits, rnd = seed_problem(bundled, seed)
        for cones in ("linear", "exact"):
            d = solve(p, cones)[0]
            if not d or d["status"] != "infeasible" or d["reason"]["kind"] == "unreachable_wrench":
                continue
            infeasible_runs += 1
            q = in_joint_rows(p, d)
            for backend in ("active-set", "clarabel"):
                e = solve(q, cones, "--backend", backend)[0]
                if not e or e["status"] != "optimal":
                    continue
                margins = [m for m in e["diagnostics"].get("friction_margins", []) if m is not None]
                if min(margins, default=0.0) > -1e-3:
                    held += 1
                    print(f"seed {seed} ({name}: {', '.join(edits)}) {cones}: infeasible "
                          f"({d['reason']['kind']}), {backend} optimal in joint units at σ = {e['objective']}")
                    break
    print(f"{count} problems, {infeasible_runs} infeasible runs: {held} held in joint units")


def spreads(start, count):
    """Seeds FROM.. of the main search: the answers that state a spread
    (`stated_spread`), linear at N = 8 and 16 and exact."""
    bundled, found, runs = sources(), 0, 0
    for seed in range(start, start + count):
        name, p, edits, _ = seed_problem(bundled, seed)
        for cones, extra in (("linear", ("--sides", "8")), ("linear", ("--sides", "16")), ("exact", ())):
            d = solve(p, cones, *extra)[0]
            runs += 1
            if d and stated_spread(d) > 0:
                found += 1
                print(f"seed {seed} ({name}: {', '.join(edits)}) {cones} {' '.join(extra)}: "
                      f"{d['status']}, spread {stated_spread(d):.1e}")
    print(f"{runs} solves: {found} state a spread")


def stated_bound(d):
    """The bound on σ's excess an `almost_optimal` answer states in its warning, or how
    far an answer states its rows' rounding moves σ ("σ is fixed by the key set's rows
    only to about …"); 0 for an `optimal` one that states neither (its 2e-9 the
    search's 1e-7 covers)."""
    bound = stated_spread(d)
    for w in d.get("warnings") or []:
        if "certificate bounds σ only to " in w:
            bound += float(w.split("certificate bounds σ only to ")[1].split(" ")[0])
    return bound


def stated_spread(d):
    """How far an answer states its rows' rounding moves σ, either way (0 if it does not)."""
    for w in d.get("warnings") or []:
        if "key set's rows only to about " in w:
            return float(w.split("key set's rows only to about ")[1].split(",")[0])
    return 0.0


def nested(start, count):
    """Seeds FROM.. of the main search with linear cones at N = 4, 8, 16, 32 and 64 sides
    and exact cones. Each polygon's vertices are among the next one's (every N-th angle,
    the same latitudes), so each polyhedron contains the last and the exact cone all of
    them: σ falls as N grows, and a grasp held at N is held at 2N. An optimal answer
    above one for fewer sides is not optimal, nor an `almost_optimal` one above it by
    more than its stated bound; every pair of runs is compared."""
    bundled, problems, solved = sources(), 0, 0
    answered = ("optimal", "almost_optimal")
    for seed in range(start, start + count):
        name, p, edits, rnd = seed_problem(bundled, seed)
        runs = [(f"N = {n}", solve(p, "linear", "--sides", str(n))[0]) for n in (4, 8, 16, 32, 64)]
        runs.append(("exact", solve(p, "exact")[0]))
        for (a, da), (b, db) in ((x, y) for i, x in enumerate(runs) for y in runs[i + 1:]):
            sa, sb = (da or {}).get("status"), (db or {}).get("status")
            if sa == "optimal" and sb == "infeasible":
                print(f"seed {seed} ({name}: {', '.join(edits)}): optimal at {a}, infeasible at {b}")
                problems += 1
            elif sa in answered and sb in answered:
                solved += 1
                if db["objective"] > da["objective"] * (1 + 1e-7 + stated_bound(db) + stated_spread(da)):
                    print(f"seed {seed} ({name}: {', '.join(edits)}): σ {db['objective']} at {b} "
                          f"above σ {da['objective']} at {a}")
                    problems += 1
    print(f"{count} problems, {solved} pairs both answered: {problems} contradictions")


def seed_problem(bundled, seed):
    """The main search's problem for `seed`: its source's name, the problem, the edits
    and the rest of the seed's random stream."""
    rnd = random.Random(seed)
    name, p = rnd.choice(bundled)
    p = json.loads(json.dumps(p))
    edits = mutate(rnd, p)
    return name, p, edits, rnd


def backends(start, count):
    """Seeds FROM.. of the main search where the native solver and Clarabel disagree on
    whether the grasp is feasible, linear (the file's N) and exact cones."""
    bundled, found = sources(), 0
    for seed in range(start, start + count):
        name, p, edits, _ = seed_problem(bundled, seed)
        for cones in ("linear", "exact"):
            native = solve(p, cones)[0] or {}
            clarabel = solve(p, cones, "--backend", "clarabel")[0] or {}
            pair = {native.get("status"), clarabel.get("status")}
            answered = pair & {"optimal", "almost_optimal"}
            if "infeasible" in pair and answered:
                d = native if native.get("status") in answered else clarabel
                who = "native" if d is native else "clarabel"
                problems = wrong(p, d)
                print(f"seed {seed} ({name}: {', '.join(edits)}) {cones}: native {native.get('status')}, "
                      f"clarabel {clarabel.get('status')}; the {who} answer "
                      + (f"fails the file's checks: {problems[0]}" if problems else "passes the file's checks"))
                found += 1
    print(f"{count} problems: {found} runs where one backend calls infeasible what the other answers")


def main():
    if sys.argv[1] == "write":
        print(json.dumps(seed_problem(sources(), int(sys.argv[2]))[1], indent=1))
        sys.exit(0)
    if sys.argv[1] == "backends":
        backends(int(sys.argv[2]), int(sys.argv[3]))
        sys.exit(0)
    if sys.argv[1] == "moment-arms":
        moment_arms(float(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]))
    if sys.argv[1] == "joint-units":
        joint_units(int(sys.argv[2]), int(sys.argv[3]))
    if sys.argv[1] == "pinned-limits":
        pinned_limits(int(sys.argv[2]), int(sys.argv[3]))
    if sys.argv[1] == "infeasible":
        infeasible(int(sys.argv[2]), int(sys.argv[3]))
        sys.exit(0)
    if sys.argv[1] == "joint-rows":
        joint_rows(int(sys.argv[2]), int(sys.argv[3]))
        sys.exit(0)
    if sys.argv[1] == "spreads":
        spreads(int(sys.argv[2]), int(sys.argv[3]))
        sys.exit(0)
    if sys.argv[1] == "nested":
        nested(int(sys.argv[2]), int(sys.argv[3]))
        sys.exit(0)
    if sys.argv[1] == "statuses":
        rest = sys.argv[5:]
        backend = ("--backend", "clarabel") if "clarabel" in rest else ()
        statuses(int(sys.argv[2]), int(sys.argv[3]), sys.argv[4], [int(n) for n in rest if n != "clarabel"], backend)
        sys.exit(0)
    start, count = int(sys.argv[1]), int(sys.argv[2])
    problems, counts = 0, {}
    bundled = sources()
    for seed in range(start, start + count):
        name, p, edits, rnd = seed_problem(bundled, seed)
        at = f"seed {seed} ({name}: {', '.join(edits)})"
        unit_free = p.get("internal_forces") != "euclidean" and (p.get("linearization") or {}).get("sfce_spacing") != "paper"
        F, L = 10 ** rnd.uniform(-3, 3), 10 ** rnd.uniform(-3, 3)
        answers = {}
        for cones in ("linear", "exact"):
            d, why = solve(p, cones)
            if d is None:
                if not why.startswith("refused"):
                    print(f"{at} {cones}: {why}")
                    problems += 1
                break
            answers[cones] = d
            counts[(cones, d["status"])] = counts.get((cones, d["status"]), 0) + 1
            if d["status"] in ("optimal", "almost_optimal"):
                for what in wrong(p, d):
                    print(f"{at} {cones}: {d['status']}, but {what}")
                    problems += 1
            if d["status"] not in ("optimal", "infeasible"):
                print(f"{at} {cones}: {d['status']} ({(d.get('reason') or {}).get('message', '')[:160]})")
            for what in misreported(d):
                print(f"{at} {cones}: {d['status']}, but {what}")
                problems += 1
            if unit_free:
                e, why = solve(in_units(p, F, L), cones)
                decisive = ("optimal", "infeasible")
                if e is None and why.startswith("refused"):
                    pass  # the other units left the input domain
                elif e is None or e["status"] != d["status"]:
                    # A numerical failure on either side is no answer, not a wrong one.
                    wrong_status = e is None or (d["status"] in decisive and e["status"] in decisive)
                    print(f"{at} {cones}, in units F = {F:.3g}, L = {L:.3g}: {d['status']} became {why or e['status']}")
                    problems += wrong_status
                elif d["status"] == "optimal":
                    a, b = d["objective"] * (F * L) ** 2, e["objective"]
                    spread = stated_bound(d) + stated_bound(e)
                    if abs(a - b) > (1e-6 + spread) * max(abs(a), abs(b)) + zero_sigma(p) * (F * L) ** 2:
                        print(f"{at} {cones}, in units F = {F:.3g}, L = {L:.3g}: σ {a} (scaled) became {b}")
                        problems += 1
        lin, ex = answers.get("linear"), answers.get("exact")
        if lin and ex and lin["status"] == ex["status"] == "optimal" and ex["objective"] > lin["objective"] * (1 + 1e-7):
            print(f"{at}: σ* {ex['objective']} above σ(N) {lin['objective']}")
            problems += 1
    print(f"{count} problems; {problems} wrong answers; statuses {dict(sorted(counts.items()))}")
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
