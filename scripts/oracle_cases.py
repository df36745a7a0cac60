#!/usr/bin/env python3
"""Grasps no one here has solved, in the format of `shared/reference/cases.json`, with
optima from cvxpy: the oracle of `cargo test --test oracle_cases`.

Each case is drawn at random as the reference cases were (`shared/reference/README.md`,
"Geometry convention"): 2 to 5 fingers of 2 to 4 revolute joints, one contact per
finger (two on a quarter of them) on a sphere of radius 4 cm (normals into the object,
tilted by about 0.15 rad), one contact-model family per case (FPC mixes, PCwF, SFCl,
SFCe or mixed), friction drawn per contact, and a wrench that holds 0.1 to 1 kg
against gravity with a random push and twist. Some draws are infeasible; they are
kept: a status is part of the answer.

Everything the project computes is computed again here, in numpy, from the reference
README's model and from this project's documented defaults: G and Jᵀ from the
geometry; the contact forces `f = Z1 w + Z2 τ` and the consistency rows, with
`Z = [G; Jᵀ]⁺` (rank tolerance 1e-9 σ_max) under the reference set's conventions
(`reference`), and with the force of least compliance `‖D f‖` (D = 1 on forces,
1/mu_torsion on mz; the rows of `A D⁻¹` equilibrated before the rank decision)
under the project's defaults (`defaults`); the inscribed polyhedra (PCwF pyramids,
SFCl bipyramids, the SFCe polyhedron with K = 2 latitudes at the paper's eq. 13
angles, or uniform in the normalised ellipse angle for `defaults`) and the exact
cones. Each case is also solved under the defaults with problem fields drawn for it
(`extras`: torque weights, torque limits and minimum normal forces; `extras_reference`
holds those answers). cvxpy then solves each variant (`exact`, `N4`, `N8`, `N16`) in
each setting with Clarabel: the exact cones at the reference cases' tolerances, 1e-10,
twice, the second time with σ divided by the first answer's (Clarabel's absolute
tolerances then count relative to σ*), the polyhedra at 1e-12. Each polyhedral
variant is solved again by DAQP (a dual active-set QP solver, exact to rounding),
whose answer is kept; a case is written only if the two agree on the status and,
when optimal, on σ to 1e-10 relative (the largest difference is printed and written
to the file), and if σ* ≤ σ(16) (the polyhedra are inside the cones) with the
statuses to match. A draw that fails is drawn again.

Run from the repository root (cvxpy 1.9 with Clarabel, daqp and numpy from PyPI):

    python3 -m venv /tmp/cvx && /tmp/cvx/bin/pip install cvxpy daqp numpy
    /tmp/cvx/bin/python scripts/oracle_cases.py 150 > tests/data/oracle-cases.json

(`oracle_cases.py COUNT [SEED]`, seed 20261205 by default.) With `ORACLE_REJECTED=DIR`,
each draw the oracles could not settle is written to DIR as problem files, one per
setting, for `grasp-torque compare`.

The tests do not run this script.
"""
import json
import math
import os
import sys

import cvxpy as cp
import numpy as np

RANK_TOL = 1e-9
AGREE = 1e-10
K = 2
# Each case is solved twice: `reference` under the reference set's conventions (the
# Euclidean A⁺, the paper's SFCe latitudes), `defaults` under this project's defaults
# (least-compliance internal forces, uniform latitudes).
CONVENTIONS = {"reference": ("euclidean", "paper"), "defaults": ("compliance", "uniform")}
FAMILIES = ["fpcmix", "pcwf", "sfcl", "sfce", "mixed"]
# Clarabel's tolerances: on the QPs of the polyhedra it reaches 1e-12; on the exact cones
# 1e-10, the reference cases' own (tighter, it often ends `optimal_inaccurate`).
CLARABEL_QP = dict(tol_gap_abs=1e-12, tol_gap_rel=1e-12, tol_feas=1e-12, tol_ktratio=1e-10, max_iter=500)
CLARABEL_SOCP = dict(tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10, tol_ktratio=1e-8, max_iter=500)


def unit(v):
    return v / np.linalg.norm(v)


def draw_contact(rng, family, i):
    mu = float(np.round(rng.uniform(0.2, 1.0), 3))
    mt = float(np.round(rng.uniform(0.003, 0.04), 4))
    kind = {"fpcmix": ["pcwf", "fpc", "sfcl"][i % 3], "mixed": rng.choice(["pcwf", "sfcl", "sfce"])}.get(
        family, family)
    c = {"model": str(kind)}
    if kind != "fpc":
        c["mu"] = mu
    if kind in ("sfcl", "sfce"):
        c["mu_torsion"] = mt
    return c


def draw_case(rng, index):
    family = FAMILIES[index % len(FAMILIES)]
    fingers = int(rng.integers(2, 6))
    contacts, joints_of = [], []
    # Contacts spread around the sphere: evenly spaced azimuths, jittered.
    phase = rng.uniform(0, 2 * math.pi)
    for k in range(fingers):
        az = phase + 2 * math.pi * k / fingers + rng.normal(0, 0.25)
        el = rng.normal(0, 0.35)
        p = 0.04 * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
        # The normal into the object, tilted.
        n = unit(-p / np.linalg.norm(p) + rng.normal(0, 0.15, 3))
        c = draw_contact(rng, family, k)
        c.update(finger=k, position=p.tolist(), normal=n.tolist())
        contacts.append(c)
        # A quarter of the fingers touch twice (a second link, nearer the palm).
        if rng.random() < 0.25:
            q = unit(p + rng.normal(0, 0.015, 3)) * 0.04
            c = draw_contact(rng, family, k + 1)
            c.update(finger=k, position=q.tolist(), normal=unit(-q + rng.normal(0, 0.006, 3)).tolist())
            contacts.append(c)
        # Joints from the palm side out to the contact.
        count = int(rng.integers(2, 5))
        out = unit(p)
        joints = []
        for j in range(count):
            reach = 0.13 - 0.025 * j + rng.normal(0, 0.005)
            o = out * reach + rng.normal(0, 0.012, 3)
            joints.append({"origin": o.tolist(), "axis": unit(rng.normal(size=3)).tolist()})
        joints_of.append({"joints": joints})
    mass = rng.uniform(0.1, 1.0)
    push = rng.normal(0, 0.25, 3) * 9.81 * mass
    twist = rng.normal(0, 0.02, 3) * 9.81 * mass
    wrench = np.concatenate([push + [0, 0, 9.81 * mass], twist])
    return family, {"contacts": contacts, "fingers": joints_of, "wrench": wrench.tolist()}


def directions(c):
    """The contact frame's force directions of the model, and whether it has torsion."""
    n = np.array(c["normal"])
    a0 = np.array([0.0, 1.0, 0.0]) if abs(n[0]) >= 0.9 else np.array([1.0, 0.0, 0.0])
    t1 = unit(np.cross(n, a0))
    t2 = np.cross(n, t1)
    if c["model"] == "fpc":
        return [n], False
    return [t1, t2, n], c["model"] in ("sfcl", "sfce")


def matrices(geo):
    """G and Jᵀ by the README's geometry convention."""
    g_cols, jt_cols = [], []
    joints = [(f, j) for f, finger in enumerate(geo["fingers"]) for j in finger["joints"]]
    for c in geo["contacts"]:
        p = np.array(c["position"])
        dirs, torsion = directions(c)
        for d in dirs:
            g_cols.append(np.concatenate([d, np.cross(p, d)]))
            jt_cols.append([d @ np.cross(np.array(j["axis"]), p - np.array(j["origin"])) if f == c["finger"] else 0.0
                            for f, j in joints])
        if torsion:
            n = np.array(c["normal"])
            g_cols.append(np.concatenate([np.zeros(3), n]))
            jt_cols.append([n @ np.array(j["axis"]) if f == c["finger"] else 0.0 for f, j in joints])
    return np.array(g_cols).T, np.array(jt_cols).T


def cone_rows(c, sides, spacing):
    """Rows S of the inscribed polyhedron, `S f ≥ 0` on the contact's components, with
    the SFCe latitudes at `spacing` ("paper" or "uniform")."""
    model = c["model"]
    if model == "fpc":
        return [[1.0]]
    mu = c["mu"]
    cos = math.cos(math.pi / sides)
    phis = [(2 * j + 1) * math.pi / sides for j in range(sides)]
    if model == "pcwf":
        rows = [[-math.cos(f), -math.sin(f), mu * cos] for f in phis]
        return rows + [[0.0, 0.0, 1.0]]
    mt = c["mu_torsion"]
    if model == "sfcl":
        rows = []
        for sign in (1.0, -1.0):
            rows += [[-math.cos(f) / (mu * cos), -math.sin(f) / (mu * cos), -sign / mt, 1.0] for f in phis]
        return rows + [[0.0, 0.0, 0.0, 1.0]]
    # SFCe: latitudes at angles ψ_i = π i / (2K), each a vertex radius l_i and height
    # h_i: "paper" (eq. 13) puts them on the ellipse at polar angle ψ_i, h_i = l_i tan ψ_i;
    # "uniform" at the normalised ellipse angle, (l, h) = (mu cos ψ_i, mt sin ψ_i). The
    # pole is (0, mt). A face between latitudes i and i + 1 around the bisector φ is
    # α (x cos φ + y sin φ) + β m ≤ fz with α l cos(π/N) + β h = 1 at both.
    lat = []
    for i in range(K + 1):
        psi = math.pi * i / (2 * K)
        if i == K:
            lat.append((0.0, mt))
        elif spacing == "uniform":
            lat.append((mu * math.cos(psi), mt * math.sin(psi)))
        else:
            l = mu * mt / math.sqrt(mu ** 2 * math.tan(psi) ** 2 + mt ** 2)
            lat.append((l, l * math.tan(psi)))
    rows = []
    for sign in (1.0, -1.0):
        for i in range(K):
            (l0, h0), (l1, h1) = lat[i], lat[i + 1]
            a, b = np.linalg.solve([[l0 * cos, h0], [l1 * cos, h1]], [1.0, 1.0])
            rows += [[-a * math.cos(f), -a * math.sin(f), -sign * b, 1.0] for f in phis]
    return rows + [[0.0, 0.0, 0.0, 1.0]]


def model(G, JT, w, contacts, internal):
    """f = Z1 w + Z2 τ and the consistency rows `Cτ = e`. "euclidean": Z = A⁺ (eq. 31).
    "compliance": the f of least ‖D f‖, D = 1 on forces and 1/mu_torsion on mz, with
    the rows of A D⁻¹ equilibrated before the rank decision: Z = D⁻¹ (R A D⁻¹)⁺ R."""
    A = np.vstack([G, JT])
    d = np.ones(A.shape[1])
    R = np.ones(A.shape[0])
    if internal == "compliance":
        col = 0
        for c in contacts:
            dim = {"fpc": 1, "pcwf": 3}.get(c["model"], 4)
            if dim == 4:
                d[col + 3] = 1.0 / c["mu_torsion"]
            col += dim
        norms = np.linalg.norm(A / d, axis=1)
        R = np.where(norms > 0, 1.0 / np.where(norms > 0, norms, 1.0), 1.0)
    B = R[:, None] * A / d
    U, s, _ = np.linalg.svd(B)
    rank = int(np.sum(s > RANK_TOL * s[0]))
    Z = (np.linalg.pinv(B, rcond=RANK_TOL) * R) / d[:, None]
    Uperp = U[:, rank:].T * R
    return Z[:, :6], Z[:, 6:], Uperp[:, 6:], -Uperp[:, :6] @ w


def solve(geo, G, JT, variant, solver, conventions, scale=1.0, extras=None):
    """One variant by `solver` under `conventions` (internal forces, SFCe spacing) and
    the problem fields in `extras` (torque weights, limits, minimum normal forces),
    minimising σ / `scale` (Clarabel's absolute tolerances then mean something relative
    to σ)."""
    internal, spacing = conventions
    extras = extras or {}
    w = np.array(geo["wrench"])
    m = JT.shape[0]
    Z1, Z2, C, e = model(G, JT, w, geo["contacts"], internal)
    tau = cp.Variable(m)
    f = Z1 @ w + Z2 @ tau
    cons = []
    if C.shape[0]:
        cons.append(C @ tau == e)
    for j, limit in enumerate(extras.get("torque_limits", [None] * m)):
        lower, upper = (-limit, limit) if isinstance(limit, float) else (limit or [None, None])
        if lower is not None:
            cons.append(tau[j] >= lower)
        if upper is not None:
            cons.append(tau[j] <= upper)
    fmin = extras.get("min_normal_force", 0.0)
    col = 0
    for i, c in enumerate(geo["contacts"]):
        dim = {"fpc": 1, "pcwf": 3}.get(c["model"], 4)
        fc = f[col:col + dim]
        col += dim
        least = fmin[i] if isinstance(fmin, list) else fmin
        if least > 0:
            cons.append(fc[0 if dim == 1 else 2] >= least)
        if variant == "exact":
            if c["model"] == "fpc":
                cons.append(fc[0] >= 0)
            elif c["model"] == "pcwf":
                cons.append(cp.SOC(c["mu"] * fc[2], fc[:2]))
            elif c["model"] == "sfcl":
                cons.append(cp.norm(fc[:2], 2) / c["mu"] + cp.abs(fc[3]) / c["mu_torsion"] <= fc[2])
            else:
                cons.append(cp.SOC(fc[2], cp.hstack([fc[0] / c["mu"], fc[1] / c["mu"], fc[3] / c["mu_torsion"]])))
        else:
            S = np.array(cone_rows(c, int(variant[1:]), spacing))
            if c["model"] in ("sfcl", "sfce"):
                # Rows are written on (fx, fy, mz, fz); the columns are (fx, fy, fz, mz).
                S = S[:, [0, 1, 3, 2]]
            cons.append(S @ fc >= 0)
    weights = np.array(extras.get("torque_weights", np.ones(m)))
    prob = cp.Problem(cp.Minimize(cp.sum_squares(cp.multiply(np.sqrt(weights), tau)) / scale), cons)
    try:
        if solver == "CLARABEL":
            prob.solve(solver="CLARABEL", **(CLARABEL_SOCP if variant == "exact" else CLARABEL_QP))
        else:
            prob.solve(solver=solver)
    except cp.error.SolverError:
        return {"status": "solver_error"}
    if prob.status == "optimal":
        t = np.array(tau.value)
        return {"status": "optimal", "objective": float(weights @ (t * t)), "torque": t.tolist()}
    if prob.status == "infeasible":
        return {"status": "infeasible", "objective": None, "torque": None}
    return {"status": prob.status}


def draw_extras(rng, geo, m, tau):
    """Problem fields for the project's defaults to be solved with: torque weights (on
    seven draws in ten), minimum normal forces (one number, or one per contact; on
    half), and torque limits from a third to one and a half times the largest torque
    without them, symmetric, one-sided or two-sided, some joints unlimited (on six in
    ten grasps that have that torque)."""
    extras = {}
    if rng.random() < 0.7:
        extras["torque_weights"] = np.round(rng.uniform(0.2, 5.0, m), 3).tolist()
    if rng.random() < 0.5:
        if rng.random() < 0.5:
            extras["min_normal_force"] = float(np.round(rng.uniform(0.05, 0.5), 3))
        else:
            extras["min_normal_force"] = np.round(rng.uniform(0.0, 0.5, len(geo["contacts"])), 3).tolist()
    if tau is not None and rng.random() < 0.6:
        top = max(abs(t) for t in tau)
        limits = []
        for _ in range(m):
            r, a, b = rng.random(), float(top * rng.uniform(0.33, 1.5)), float(top * rng.uniform(0.33, 1.5))
            if r < 0.3:
                limits.append(None)
            elif r < 0.65:
                limits.append(a)
            elif r < 0.85:
                limits.append([-a, b])
            elif r < 0.925:
                limits.append([-a, None])
            else:
                limits.append([None, b])
        extras["torque_limits"] = limits
    return extras


def oracle(geo, G, JT, conventions, extras=None):
    """Every variant under `conventions` and `extras`, and the largest Clarabel–DAQP
    difference of σ; None where the oracles disagree or did not finish."""
    ref, worst = {}, 0.0
    for variant in ["N4", "N8", "N16", "exact"]:
        r = solve(geo, G, JT, variant, "CLARABEL", conventions, extras=extras)
        # The exact cones again on the scale of σ* (Clarabel's absolute tolerances are
        # then relative to it).
        if variant == "exact" and r["status"] == "optimal" and r["objective"] > 0:
            r = solve(geo, G, JT, variant, "CLARABEL", conventions, r["objective"], extras)
        if r["status"] not in ("optimal", "infeasible"):
            return None, worst
        if variant != "exact":
            d = solve(geo, G, JT, variant, "DAQP", conventions, extras=extras)
            if d["status"] != r["status"]:
                return None, worst
            if r["status"] == "optimal":
                diff = abs(d["objective"] - r["objective"]) / max(abs(d["objective"]), 1e-300)
                if diff > AGREE:
                    return None, worst
                worst = max(worst, diff)
            r = d
        ref[variant] = r
    # The polyhedra are inside the cones: σ* ≤ σ(16), and infeasible only with them.
    e, p = ref["exact"], ref["N16"]
    if p["status"] == "optimal" and not (e["status"] == "optimal" and e["objective"] <= p["objective"] * (1 + 1e-9)):
        return None, worst
    if e["status"] == "infeasible" and any(ref[v]["status"] != "infeasible" for v in ("N4", "N8", "N16")):
        return None, worst
    return {v: ref[v] for v in ("exact", "N4", "N8", "N16")}, worst


def problem_of(geo, G, JT):
    """The matrix form of a drawn grasp."""
    return {"grasp_matrix": G.tolist(), "jacobian_transpose": JT.tolist(), "wrench": geo["wrench"],
            "contacts": [{k: v for k, v in c.items() if k in ("model", "mu", "mu_torsion")}
                         for c in geo["contacts"]]}


def main():
    count = int(sys.argv[1])
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 20261205
    rejected = os.environ.get("ORACLE_REJECTED")
    rng = np.random.default_rng(seed)
    cases, worst, drawn = [], 0.0, 0
    while len(cases) < count:
        drawn += 1
        family, geo = draw_case(rng, len(cases))
        G, JT = matrices(geo)
        settled = [oracle(geo, G, JT, conventions) for conventions in CONVENTIONS.values()]
        ok = all(r is not None for r, _ in settled)
        extras = None
        if ok:
            extras = draw_extras(rng, geo, JT.shape[0], settled[-1][0]["exact"].get("torque"))
            settled.append(oracle(geo, G, JT, CONVENTIONS["defaults"], extras))
            ok = settled[-1][0] is not None
        if ok:
            worst = max([worst] + [w for _, w in settled])
        if not ok:
            print(f"draw {drawn}: the oracles disagree or did not finish; drawn again", file=sys.stderr)
            if rejected:
                settings = [(key, conventions, {}) for key, conventions in CONVENTIONS.items()]
                if extras is not None:
                    settings.append(("extras", CONVENTIONS["defaults"], extras))
                for key, (internal, spacing), fields in settings:
                    with open(os.path.join(rejected, f"draw-{drawn}-{key}.json"), "w") as out:
                        json.dump(dict(problem_of(geo, G, JT), internal_forces=internal,
                                       linearization={"sfce_spacing": spacing}, **fields), out)
            continue
        name = f"h{len(geo['contacts'])}x{sum(len(f['joints']) for f in geo['fingers'])}-{family}-{len(cases)}"
        problem = problem_of(geo, G, JT)
        case = {"name": name, "problem": problem, "geometry": geo}
        case.update({key: r for key, (r, _) in zip(list(CONVENTIONS) + ["extras_reference"], settled)})
        case["extras"] = extras
        cases.append(case)
    statuses = {}
    for c in cases:
        s = c["reference"]["exact"]["status"]
        statuses[s] = statuses.get(s, 0) + 1
    print(f"{len(cases)} cases ({drawn} drawn), exact statuses {statuses}; "
          f"largest Clarabel–DAQP difference of σ {worst:.1e}", file=sys.stderr)
    json.dump({"oracle": {"generator": "scripts/oracle_cases.py", "seed": seed, "cvxpy": cp.__version__,
                          "clarabel_qp": CLARABEL_QP, "clarabel_socp": CLARABEL_SOCP, "daqp_agreement": worst},
               "cases": cases}, sys.stdout)


if __name__ == "__main__":
    main()
