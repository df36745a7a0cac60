#!/usr/bin/env python3
"""Random URDF hands for the URDF reader's oracle (scripts/oracle_urdf.py).

Each model is a seeded random hand of two to four fingers that uses, at random, what
the reader claims to read: joint origins with `xyz` and `rpy`, axes that are not unit
length, revolute, continuous, prismatic and fixed joints (chains of fixed joints
included), mimic joints (chains of them, negative multipliers, offsets), limits with
a positive effort and with 0 (no limit), `<inertial>` masses off the link frames (on
most links), and `<joint>` elements listed in any order (before their links, shuffled).
From the seventh model on, the files are URDF 1.1 and about half of the joint origins
are turned by `quat_xyzw`, not normalised. Pinocchio must load it; `oracle_urdf.py`
then writes its Jᵀ, G and effort limits.

Run from the repository root (pin 4.1.0 and numpy from PyPI; see oracle_urdf.py):

    /tmp/oracle/bin/python scripts/random_urdf.py

It writes fixtures/urdf/random/random-*.urdf.
"""

import os

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "fixtures", "urdf", "random")
MODELS = int(os.environ.get("RANDOM_MODELS", 8))
# Models from this index on are URDF 1.1 with `quat_xyzw` origins.
QUATERNIONS_FROM = 6


def fmt(v):
    return " ".join(f"{x:.6g}" for x in v)


def link(name, rng):
    """A link, most with an <inertial> (its origin off the link frame, turned)."""
    if rng.random() < 0.2:
        return f'  <link name="{name}"/>'
    i = rng.uniform(1e-6, 1e-5, 3)
    return (f'  <link name="{name}"><inertial><origin xyz="{fmt(rng.uniform(-0.02, 0.02, 3))}" '
            f'rpy="{fmt(rng.uniform(-3, 3, 3))}"/><mass value="{rng.uniform(0.005, 0.1):.6g}"/>'
            f'<inertia ixx="{i[0]:.6g}" ixy="0" ixz="0" iyy="{i[1]:.6g}" iyz="0" izz="{i[2]:.6g}"/>'
            '</inertial></link>')


def hand(rng, mrng, qrng=None):
    links = ["palm"]
    joints = []  # (xml, name, kind)
    movable = []  # (name, finger)
    tips = []
    for f in range(int(rng.integers(2, 5))):
        parent = "palm"
        for d in range(int(rng.integers(2, 5))):
            kind = str(rng.choice(["revolute", "revolute", "continuous", "prismatic", "fixed"],
                                  p=[0.45, 0.15, 0.1, 0.1, 0.2]))
            child = f"f{f}_l{d}"
            name = f"f{f}_j{d}"
            origin = (f'<origin xyz="{fmt(rng.uniform(-0.04, 0.04, 3))}" '
                      f'rpy="{fmt(rng.uniform(-np.pi, np.pi, 3))}"/>')
            if qrng is not None and qrng.random() < 0.5:
                # A quaternion of any length: URDF 1.1 readers normalise it.
                quat = qrng.normal(size=4) * qrng.uniform(0.5, 2.0)
                origin = origin.split(" rpy=")[0] + f' quat_xyzw="{fmt(quat)}"/>'
            xml = [f'<joint name="{name}" type="{kind}">', f'<parent link="{parent}"/>',
                   f'<child link="{child}"/>', origin]
            if kind != "fixed":
                xml.append(f'<axis xyz="{fmt(rng.normal(size=3))}"/>')
            if kind in ("revolute", "prismatic"):
                lo, hi = sorted(rng.uniform(-1.5, 1.5, 2))
                if kind == "prismatic":
                    lo, hi = 0.02 * lo, 0.02 * hi
                # urdfdom (Pinocchio's reader) needs an effort; 0 is no limit.
                effort = f' effort="{rng.uniform(0.5, 20):.6g}"' if rng.random() < 0.7 else ' effort="0"'
                xml.append(f'<limit lower="{lo:.6g}" upper="{hi:.6g}"{effort} velocity="1"/>')
            elif kind == "continuous" and rng.random() < 0.5:
                xml.append(f'<limit effort="{rng.uniform(0.5, 20):.6g}" velocity="1"/>')
            joints.append((xml, name, kind, f))
            if kind != "fixed":
                movable.append((name, f))
            links.append(child)
            parent = child
        tips.append(parent)
    # Mimics: a later joint of a finger follows an earlier one, sometimes in a chain.
    mimic = {}
    for f in set(fi for _, fi in movable):
        names = [n for n, fi in movable if fi == f]
        for k in range(1, len(names)):
            if rng.random() < 0.35:
                mimic[names[k]] = (names[k - 1], rng.uniform(-1.5, 1.5), rng.uniform(-0.2, 0.2))
    out = ['<robot name="random">' if qrng is None else '<robot name="random" version="1.1">']
    order = list(range(len(joints)))
    if rng.random() < 0.5:
        rng.shuffle(order)
    body = []
    for i in order:
        xml, name, kind, _ = joints[i]
        if name in mimic:
            lead, mult, off = mimic[name]
            xml = xml + [f'<mimic joint="{lead}" multiplier="{mult:.6g}" offset="{off:.6g}"/>']
        body.append("  " + "".join(xml) + "</joint>")
    link_xml = [link(name, mrng) for name in links]
    # Joints before their links, or after.
    out += (body + link_xml) if rng.random() < 0.5 else (link_xml + body)
    out.append("</robot>")
    return "\n".join(out) + "\n", tips


def main():
    import pinocchio as pin

    os.makedirs(OUT, exist_ok=True)
    written, seed = 0, 0
    while written < MODELS:
        seed += 1
        rng = np.random.default_rng(2000 + seed)
        # Masses from their own stream: the kinematics stay as drawn.
        qrng = np.random.default_rng(7000 + seed) if written >= QUATERNIONS_FROM else None
        text, tips = hand(rng, np.random.default_rng(9000 + seed), qrng)
        path = os.path.join(OUT, f"random-{written}.urdf")
        with open(path, "w") as f:
            f.write('<?xml version="1.0"?>\n'
                    f"<!-- Drawn by scripts/random_urdf.py (seed {2000 + seed}) for the URDF "
                    "reader's oracle. -->\n" + text)
        try:
            pin.buildModelFromUrdf(path)
        except Exception as e:  # noqa: BLE001 - any refusal draws again
            print(f"seed {seed}: Pinocchio refuses it ({e}); drawn again")
            continue
        print(f"random-{written}: seed {2000 + seed}, tips {tips}")
        written += 1


if __name__ == "__main__":
    main()
