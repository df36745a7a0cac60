#!/usr/bin/env python3
"""Masses for the random MJCF hands, and MuJoCo's gravity torques: the oracle of the
MJCF reader's masses and of `Robot::gravity_torques`.

Each random hand of scripts/random_mjcf.py (`random-*.xml`, `spatial-*.xml`) is given
masses at random, in every form MuJoCo's compiler reads: `<inertial pos mass>` on some
bodies; sphere, capsule, cylinder, box and ellipsoid geoms (placed by `pos` and an
orientation or by `fromto`, inside `<frame>`s too) with a `mass`, a `density`, a
default class's density or size, or MuJoCo's default density, in groups inside and
outside `inertiagrouprange`; `<compiler inertiafromgeom>` (auto, true, false),
`boundmass`, `settotalmass`; body `gravcomp`; and `<option gravity>` in a random
direction or MuJoCo's default. A model MuJoCo refuses is drawn again.

It writes the hands to fixtures/mjcf/gravity/*.xml and, in fixtures/mjcf/gravity/
oracle.json, per hand MuJoCo's compiled `body_mass`, `body_ipos` and `body_gravcomp`, the
model's gravity, and per configuration (20, drawn as oracle_mjcf.py draws them) the
links' weight on each independent joint, `qfrc_gravcomp − qfrc_bias` at rest, and the
springs' `qfrc_spring`, each reduced by the couplings (`Pᵀ`).

Run from the repository root (mujoco 3.3 and numpy from PyPI; see oracle_mjcf.py):

    /tmp/mj/bin/python scripts/mass_mjcf.py

`cargo test -p grasp-io --test mjcf` compares against it to 1e-10 relative. The tests
do not run this script.
"""

import json
import os
import xml.etree.ElementTree as ET

import mujoco
import numpy as np

from oracle_mjcf import couplings

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOURCE = os.path.join(ROOT, "fixtures", "mjcf", "random")
OUT = os.path.join(ROOT, "fixtures", "mjcf", "gravity")
CASES = 20


def fmt(v):
    return " ".join(f"{x:.6g}" for x in np.atleast_1d(v))


def unit(rng):
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def geom(rng, kinds=("sphere", "capsule", "cylinder", "box", "ellipsoid")):
    """A random primitive geom that collides with nothing."""
    kind = str(rng.choice(kinds))
    g = ET.Element("geom", {"type": kind, "contype": "0", "conaffinity": "0"})
    r = rng.uniform(0.003, 0.01)
    half = rng.uniform(0.005, 0.02)
    if kind != "sphere" and rng.random() < 0.4:
        a = rng.uniform(-0.02, 0.02, 3)
        b = a + unit(rng) * 2 * half
        g.set("fromto", fmt(np.concatenate([a, b])))
        size = {"capsule": [r], "cylinder": [r], "box": [r, rng.uniform(0.003, 0.015)],
                "ellipsoid": [r, rng.uniform(0.003, 0.015)]}[kind]
    else:
        g.set("pos", fmt(rng.uniform(-0.02, 0.02, 3)))
        if rng.random() < 0.5:
            g.set("quat", fmt(rng.normal(size=4)))
        size = {"sphere": [r], "capsule": [r, half], "cylinder": [r, half],
                "box": rng.uniform(0.003, 0.015, 3), "ellipsoid": rng.uniform(0.003, 0.015, 3)}[kind]
    g.set("size", fmt(size))
    u = rng.random()
    if u < 0.3:
        g.set("mass", fmt(rng.uniform(0.005, 0.05)))
    elif u < 0.7:
        g.set("density", fmt(rng.uniform(500, 3000)))
    g.set("group", str(int(rng.integers(0, 6))))
    return g


def augment(root, rng):
    """Masses, compiler settings and gravity, drawn into the parsed hand `root`."""
    comp = root.find("compiler")
    mode = str(rng.choice(["auto", "true", "false"], p=[0.5, 0.3, 0.2]))
    if mode != "auto" or rng.random() < 0.3:
        comp.set("inertiafromgeom", mode)
    if rng.random() < 0.6:
        comp.set("boundmass", fmt(rng.uniform(0.001, 0.01)))
        comp.set("boundinertia", "1e-8")
    if rng.random() < 0.3:
        comp.set("settotalmass", fmt(rng.uniform(0.2, 2.0)))
    if rng.random() < 0.3:
        comp.set("inertiagrouprange", "0 2")
    if rng.random() < 0.5:
        opt = ET.Element("option", {"gravity": fmt(unit(rng) * 9.81)})
        root.insert(list(root).index(comp) + 1, opt)
    default = root.find("default")
    if default is not None and rng.random() < 0.5:
        default.insert(0, ET.Element("geom", {"density": fmt(rng.uniform(200, 800))}))
        for cls in default.iter("default"):
            if cls.get("class") and rng.random() < 0.5:
                cls.insert(0, ET.Element("geom", {"type": "capsule", "size": fmt([0.006, 0.012])}))
    for body in root.iter("body"):
        if rng.random() < 0.4:
            body.append(ET.Element("inertial", {
                "pos": fmt(rng.uniform(-0.02, 0.02, 3)),
                "mass": fmt(rng.uniform(0.005, 0.1)),
                "diaginertia": "1e-6 1e-6 1e-6"}))
        for _ in range(int(rng.integers(0, 3))):
            body.append(geom(rng))
        if rng.random() < 0.3:
            # A geom that takes its type and size from the class (or a sphere of
            # MuJoCo's default size… given one here).
            body.append(ET.Element("geom", {"pos": fmt(rng.uniform(-0.01, 0.01, 3)),
                                            "size": fmt([0.005, 0.01]), "contype": "0",
                                            "conaffinity": "0"}))
        for frame in body.findall("frame"):
            if rng.random() < 0.5:
                frame.append(geom(rng))
        if rng.random() < 0.2:
            body.set("gravcomp", fmt(rng.choice([1.0, rng.uniform(0, 1)])))


def main():
    os.makedirs(OUT, exist_ok=True)
    sources = sorted(f for f in os.listdir(SOURCE) if f.endswith(".xml"))
    hands = []
    for i, f in enumerate(sources):
        for attempt in range(50):
            rng = np.random.default_rng(5000 + 100 * i + attempt)
            root = ET.parse(os.path.join(SOURCE, f)).getroot()
            augment(root, rng)
            text = ET.tostring(root, encoding="unicode")
            try:
                m = mujoco.MjModel.from_xml_string(text)
            except ValueError as e:
                print(f"{f} attempt {attempt}: MuJoCo refuses it ({str(e).splitlines()[0]})")
                continue
            break
        else:
            raise SystemExit(f"{f}: no model MuJoCo accepts")
        header = (f"<!-- {f} of fixtures/mjcf/random with masses drawn by scripts/mass_mjcf.py "
                  f"(seed {5000 + 100 * i + attempt}) for the oracle of the MJCF reader's masses. -->\n")
        with open(os.path.join(OUT, f), "w") as out:
            out.write(header + text + "\n")
        d = mujoco.MjData(m)
        rng = np.random.default_rng(7000 + i)
        coup = couplings(m)
        independent = [j for j in coup if coup[j][0] == j]
        jname = lambda j: mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
        cases = []
        for _ in range(CASES):
            q = {}
            for j in independent:
                lo, hi = (m.jnt_range[j] if m.jnt_limited[j] else (-1.0, 1.0))
                q[j] = rng.uniform(lo, hi)
            d.qpos[:] = m.qpos0
            d.qvel[:] = 0
            for j, (lead, mult, off) in coup.items():
                motion = mult * (q[lead] - m.qpos0[m.jnt_qposadr[lead]]) + off
                d.qpos[m.jnt_qposadr[j]] = m.qpos0[m.jnt_qposadr[j]] + motion
            mujoco.mj_forward(m, d)
            weight = d.qfrc_gravcomp - d.qfrc_bias
            gravity = {jname(j): 0.0 for j in independent}
            springs = dict(gravity)
            for j, (lead, mult, _) in coup.items():
                dof = m.jnt_dofadr[j]
                gravity[jname(lead)] += mult * weight[dof]
                springs[jname(lead)] += mult * d.qfrc_spring[dof]
            cases.append({
                "joint_positions": {jname(j): float(q[j]) for j in independent},
                "gravity_torque": gravity,
                "spring_torque": springs,
            })
        bodies = {}
        for b in range(1, m.nbody):
            bodies[mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b)] = {
                "mass": float(m.body_mass[b]),
                "com": m.body_ipos[b].tolist(),
                "gravcomp": float(m.body_gravcomp[b]),
            }
        hands.append({"model": f, "gravity": m.opt.gravity.tolist(), "bodies": bodies,
                      "cases": cases})
        print(f"{f}: seed {5000 + 100 * i + attempt}, total mass {m.body_mass.sum():.4g}, "
              f"gravity {fmt(m.opt.gravity)}, "
              f"{sum(1 for b in bodies.values() if b['gravcomp'])} bodies with gravcomp")
    with open(os.path.join(OUT, "oracle.json"), "w") as out:
        json.dump({"generator": "scripts/mass_mjcf.py", "mujoco": mujoco.__version__,
                   "hands": hands}, out, indent=1)
        out.write("\n")


if __name__ == "__main__":
    main()
