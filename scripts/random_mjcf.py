#!/usr/bin/env python3
"""Random MJCF hands for the MJCF reader's oracle (scripts/oracle_mjcf.py).

Each model is a seeded random hand of two to four fingers that uses, at random, what
the reader claims to read: `<compiler angle eulerseq>`, nested `<default>` classes
(joint axis, range, ref and pos; site and actuator attributes) with `class` and
`childclass`, body and site frames by `pos` and each of `quat`, `euler`, `axisangle`,
`xyaxes` and `zaxis`, `<frame>` wrappers, one or two hinge or slide joints per body
with anchors and references, fixed tendons, joint and tendon equalities with a linear
`polycoef`, and `motor`, `position` and `general` actuators on joints or fixed tendons
with gears, force and control ranges. A model MuJoCo refuses is drawn again.

With `--spatial`, each hand also routes spatial tendons (`spatial-*.xml`): a string per
finger from a palm site through a site on each finger body, wrapping spheres and
cylinders (placed by `pos` and an orientation or by `fromto`) with and without side
sites, sometimes through a site on another finger, sometimes two fingers' strings
joined by a `<pulley>` with a divisor; actuators pull on them. Springs (`stiffness`, with
`springref`, or `springlength` as a length, a range or MuJoCo's default) sit on some
joints, fixed tendons and spatial tendons.

Run from the repository root (mujoco 3.3 and numpy from PyPI; see oracle_mjcf.py):

    /tmp/mj/bin/python scripts/random_mjcf.py
    /tmp/mj/bin/python scripts/random_mjcf.py --spatial

It writes fixtures/mjcf/random/random-*.xml (spatial-*.xml); oracle_mjcf.py then writes
their oracles.
"""

import os
import sys

import mujoco
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "fixtures", "mjcf", "random")
MODELS = int(os.environ.get("RANDOM_MODELS", 8))


def fmt(v):
    return " ".join(f"{x:.6g}" for x in np.atleast_1d(v))


class Hand:
    def __init__(self, rng, spatial=False):
        self.rng = rng
        self.spatial = spatial
        # Per finger, its spatial path: [(site, geom or None, side site or None)].
        self.routes = {}
        self.degrees = bool(rng.integers(2))
        self.seq = str(rng.choice(["xyz", "zyx", "XYZ", "xzy", "ZYX", "yxz"]))
        # Without autolimits, every range says whether it limits.
        self.autolimits = bool(rng.random() < 0.7)
        self.joints = []  # (name, finger, kind)
        self.sites = []
        self.tips = []

    def angle(self, rad):
        return np.degrees(rad) if self.degrees else rad

    def orientation(self):
        """One of MuJoCo's orientation forms, or none."""
        rng = self.rng
        form = rng.choice(["none", "quat", "euler", "axisangle", "xyaxes", "zaxis"])
        if form == "quat":
            return f' quat="{fmt(rng.normal(size=4))}"'
        if form == "euler":
            return f' euler="{fmt(self.angle(rng.uniform(-1.5, 1.5, 3)))}"'
        if form == "axisangle":
            return f' axisangle="{fmt(rng.normal(size=3))} {fmt(self.angle(rng.uniform(-2, 2)))}"'
        if form == "xyaxes":
            x = rng.normal(size=3)
            y = rng.normal(size=3)
            return f' xyaxes="{fmt(x)} {fmt(y)}"'
        if form == "zaxis":
            return f' zaxis="{fmt(rng.normal(size=3))}"'
        return ""

    def frame(self, scale=0.04):
        return f' pos="{fmt(self.rng.uniform(-scale, scale, 3))}"' + self.orientation()

    def flag(self, prefix):
        """An explicit `{prefix}limited`: always without autolimits, sometimes with."""
        rng = self.rng
        if not self.autolimits or rng.random() < 0.2:
            return f' {prefix}limited="{"true" if rng.random() < 0.7 else "false"}"'
        return ""

    def joint(self, finger, k, cls):
        rng = self.rng
        name = f"f{finger}_j{k}"
        kind = "slide" if rng.random() < 0.15 else "hinge"
        attrs = f'name="{name}"'
        if kind == "slide":
            attrs += ' type="slide"'
        if cls and rng.random() < 0.5:
            attrs += f' class="{cls}"'
        if rng.random() < 0.6:
            attrs += f' axis="{fmt(rng.normal(size=3))}"'
        if rng.random() < 0.5:
            attrs += f' pos="{fmt(rng.uniform(-0.01, 0.01, 3))}"'
        if rng.random() < 0.3:
            ref = rng.uniform(-0.01, 0.01) if kind == "slide" else self.angle(rng.uniform(-0.5, 0.5))
            attrs += f' ref="{ref:.6g}"'
        if rng.random() < 0.5:
            lo, hi = sorted(rng.uniform(-1, 1, 2))
            if kind == "slide":
                lo, hi = 0.02 * lo, 0.02 * hi
            else:
                lo, hi = self.angle(lo), self.angle(hi)
            attrs += f' range="{lo:.6g} {hi:.6g}"' + self.flag("")
        if self.spatial and rng.random() < 0.3:
            # A spring, at rest at springref (MuJoCo's qfrc_spring = −k (q − springref)).
            ref = rng.uniform(-0.01, 0.01) if kind == "slide" else self.angle(rng.uniform(-0.5, 0.5))
            attrs += f' stiffness="{rng.uniform(0.1, 5):.6g}"'
            if rng.random() < 0.7:
                attrs += f' springref="{ref:.6g}"'
        self.joints.append((name, finger, kind))
        return f"<joint {attrs}/>"

    def finger(self, f, depth, cls):
        rng = self.rng
        out = []
        k = 0
        for d in range(depth):
            body = f'<body name="f{f}_b{d}"{self.frame()}'
            if d == 0 and cls:
                body += f' childclass="{cls}"'
            out.append(body + ">")
            for _ in range(1 + (rng.random() < 0.2)):
                out.append(self.joint(f, k, "distal" if d > 0 and cls else None))
                k += 1
            if self.spatial:
                out.extend(self.route(f, d))
        site = f"f{f}_tip"
        if rng.random() < 0.2:
            ends = fmt(rng.uniform(-0.02, 0.02, 6))
            out.append(f'<site name="{site}" type="capsule" size="0.004" fromto="{ends}"/>')
        else:
            out.append(f'<site name="{site}"{self.frame(0.02)}/>')
        self.sites.append(site)
        out.extend(["</body>"] * depth)
        if rng.random() < 0.3:
            out = [f"<frame{self.frame()}>"] + out + ["</frame>"]
        return out

    def route(self, f, d):
        """A wrap geom (sometimes, with a side site outside it) and a routing site on
        body d of finger f, on the finger's spatial path."""
        rng = self.rng
        out = []
        geom = side = None
        if rng.random() < 0.7:
            geom = f"f{f}_g{d}"
            r = rng.uniform(0.003, 0.012)
            centre = rng.uniform(-0.01, 0.01, 3)
            if rng.random() < 0.5:
                axis = rng.normal(size=3)
                axis /= np.linalg.norm(axis)
                if rng.random() < 0.3:
                    h = rng.uniform(0.005, 0.02)
                    ends = np.concatenate([centre - h * axis, centre + h * axis])
                    out.append(f'<geom name="{geom}" type="cylinder" size="{r:.6g}" fromto="{fmt(ends)}"/>')
                else:
                    out.append(f'<geom name="{geom}" type="cylinder" size="{r:.6g} 0.01" '
                               f'pos="{fmt(centre)}" zaxis="{fmt(axis)}"/>')
                # Off the axis, outside the radius (MuJoCo's inside wrap is not read).
                away = np.cross(axis, rng.normal(size=3))
                away = away / np.linalg.norm(away) * r * rng.uniform(1.5, 3)
                at = centre + away + axis * rng.uniform(-0.005, 0.005)
            else:
                out.append(f'<geom name="{geom}" type="sphere" size="{r:.6g}" pos="{fmt(centre)}"/>')
                away = rng.normal(size=3)
                at = centre + away / np.linalg.norm(away) * r * rng.uniform(1.5, 3)
            if rng.random() < 0.6:
                side = f"f{f}_side{d}"
                out.append(f'<site name="{side}" pos="{fmt(at)}"/>')
        site = f"f{f}_r{d}"
        out.append(f'<site name="{site}" pos="{fmt(rng.uniform(-0.02, 0.02, 3))}"/>')
        self.routes.setdefault(f, []).append((site, geom, side))
        return out

    def spatial_tendons(self, fingers):
        """Per finger (sometimes), a string from a palm site along its route; sometimes
        through a site of another finger, sometimes two fingers joined by a pulley."""
        rng = self.rng

        def path(f):
            out = [f'      <site site="palm_r{f}"/>']
            for site, geom, side in self.routes[f]:
                if geom is not None and rng.random() < 0.8:
                    attrs = f' sidesite="{side}"' if side is not None else ""
                    out.append(f'      <geom geom="{geom}"{attrs}/>')
                out.append(f'      <site site="{site}"/>')
            return out

        names, body = [], []
        order = [f for f in range(fingers) if rng.random() < 0.8]
        while order:
            f = order.pop(0)
            lines = path(f)
            if rng.random() < 0.2 and fingers > 1:
                # On to a site of another finger's first body.
                g = int(rng.choice([x for x in range(fingers) if x != f]))
                lines.append(f'      <site site="{self.routes[g][0][0]}"/>')
            name = f"s{f}"
            if order and rng.random() < 0.3:
                g = order.pop(0)
                lines.append(f'      <pulley divisor="{rng.uniform(0.5, 3):.6g}"/>')
                lines += path(g)
                name = f"s{f}_{g}"
            spring = ""
            if rng.random() < 0.3:
                spring = f' stiffness="{rng.uniform(1, 50):.6g}"'
                r = rng.random()
                if r < 0.3:
                    spring += f' springlength="{rng.uniform(0.02, 0.1):.6g}"'
                elif r < 0.5:
                    lo = rng.uniform(0.02, 0.08)
                    spring += f' springlength="{lo:.6g} {lo + rng.uniform(0, 0.03):.6g}"'
                # else: at rest at the length with every joint at its springref.
            body += [f'    <spatial name="{name}"{spring}>'] + lines + ["    </spatial>"]
            names.append(name)
        return names, body

    def model(self, fingers):
        rng = self.rng
        lines = [f'<mujoco model="random">',
                 f'  <compiler angle="{"degree" if self.degrees else "radian"}" eulerseq="{self.seq}" '
                 f'autolimits="{"true" if self.autolimits else "false"}"/>']
        # Defaults: a root class, a finger class, a nested distal class.
        lines += ["  <default>",
                  f'    <joint axis="{fmt(rng.normal(size=3))}"/>',
                  '    <default class="finger">',
                  f'      <joint axis="{fmt(rng.normal(size=3))}" ref="{self.angle(rng.uniform(-0.3, 0.3)):.6g}"/>',
                  f'      <motor gear="{rng.uniform(0.5, 3):.6g}" forcerange="-{rng.uniform(1, 5):.6g} {rng.uniform(1, 5):.6g}"'
                  + (' forcelimited="true"' if not self.autolimits else "") + "/>",
                  '      <default class="distal">',
                  f'        <joint axis="{fmt(rng.normal(size=3))}" pos="{fmt(rng.uniform(-0.005, 0.005, 3))}"/>',
                  "      </default>",
                  "    </default>",
                  "  </default>"]
        lines += ["  <worldbody>", f'    <body name="palm"{self.frame(0.1)}>']
        if self.spatial:
            lines += [f'      <site name="palm_r{f}" pos="{fmt(rng.uniform(-0.04, 0.04, 3))}"/>'
                      for f in range(fingers)]
        for f in range(fingers):
            cls = "finger" if rng.random() < 0.6 else None
            for line in self.finger(f, int(rng.integers(2, 5)), cls):
                lines.append("      " + line)
        lines += ["    </body>", "  </worldbody>"]
        # Tendons: fixed, over two or three joints of one finger.
        tendons = []
        body = []
        for f in range(fingers):
            js = [j for j, fi, _ in self.joints if fi == f]
            if len(js) >= 2 and rng.random() < 0.7:
                n = int(rng.integers(2, min(3, len(js)) + 1))
                chosen = list(rng.choice(js, size=n, replace=False))
                name = f"t{f}"
                tendons.append((name, chosen))
                spring = ""
                if self.spatial and rng.random() < 0.3:
                    spring = f' stiffness="{rng.uniform(0.5, 5):.6g}"'
                    if rng.random() < 0.5:
                        lo = rng.uniform(-0.3, 0.3)
                        spring += f' springlength="{lo:.6g} {lo + rng.uniform(0, 0.2):.6g}"'
                body.append(f'    <fixed name="{name}"{spring}>')
                for j in chosen:
                    c = rng.uniform(0.2, 1.5) * (1 if rng.random() < 0.8 else -1)
                    body.append(f'      <joint joint="{j}" coef="{c:.6g}"/>')
                body.append("    </fixed>")
        spatial = []
        if self.spatial:
            spatial, more = self.spatial_tendons(fingers)
            body += more
        if body:
            lines += ["  <tendon>"] + body + ["  </tendon>"]
        # Equalities: a follower joint per finger at most, following an earlier one of
        # the same finger, none of them in a tendon equality too.
        eq = []
        coupled = set()
        for f in range(fingers):
            js = [(j, kind) for j, fi, kind in self.joints if fi == f]
            if len(js) >= 3 and rng.random() < 0.4:
                (lead, _), (follow, _) = js[-2], js[-1]
                c1 = rng.uniform(-1.2, 1.2)
                c0 = rng.uniform(-0.1, 0.1)
                eq.append(f'    <joint joint1="{follow}" joint2="{lead}" polycoef="{c0:.6g} {c1:.6g} 0 0 0"/>')
                coupled.add(follow)
        for name, chosen in tendons:
            if len(chosen) == 2 and not (set(chosen) & coupled) and rng.random() < 0.3:
                eq.append(f'    <tendon tendon1="{name}" polycoef="{rng.uniform(-0.05, 0.05):.6g} 0 0 0 0"/>')
                coupled.update(chosen)
        if eq:
            lines += ["  <equality>"] + eq + ["  </equality>"]
        # Actuators: on free joints or tendons, fewer than the joints.
        acts = []
        targets = [("joint", j) for j, _, _ in self.joints if j not in coupled]
        targets += [("tendon", t) for t, _ in tendons]
        rng.shuffle(targets)
        n = max(1, len(targets) - int(rng.integers(0, 3)))
        if spatial:
            # The spatial tendons first, and fewer actuators than independent joints.
            targets = [("tendon", t) for t in spatial] + targets
            n = min(len(targets), max(1, len(self.joints) - len(coupled) - int(rng.integers(0, 3))))
        for i, (kind, name) in enumerate(targets[:n]):
            a = str(rng.choice(["motor", "position", "general", "velocity", "intvelocity", "cylinder"]))
            attrs = f'name="a{i}" {kind}="{name}"'
            if rng.random() < 0.5:
                attrs += ' class="finger"' if a == "motor" else ""
            if rng.random() < 0.5:
                attrs += f' gear="{rng.uniform(0.2, 4) * (1 if rng.random() < 0.8 else -1):.6g}"'
            r = rng.random()
            if r < 0.3:
                attrs += f' forcerange="-{rng.uniform(0.5, 5):.6g} {rng.uniform(0.5, 5):.6g}"' + self.flag("force")
            elif r < 0.6:
                attrs += f' ctrlrange="-{rng.uniform(0.5, 2):.6g} {rng.uniform(0.5, 2):.6g}"' + self.flag("ctrl")
            if a == "general" and rng.random() < 0.5:
                attrs += f' gainprm="{rng.uniform(0.5, 3):.6g}"'
                if rng.random() < 0.3:
                    attrs += f' biastype="affine" biasprm="0 -{rng.uniform(1, 5):.6g} 0"'
            if a == "position":
                attrs += f' kp="{rng.uniform(1, 10):.6g}"'
            if a == "intvelocity":
                attrs += f' actrange="-1 1"'
            acts.append(f"    <{a} {attrs}/>")
        lines += ["  <actuator>"] + acts + ["  </actuator>", "</mujoco>"]
        return "\n".join(lines) + "\n"


def independent_actuators(m):
    """Whether T = Pᵀ T_full (the moment arms reduced by the couplings, as the reader
    builds it) has independent columns, and every finger an actuated joint: the reader
    refuses a T whose actuator forces are not unique, and a grasp no actuator holds,
    which this oracle is not about."""
    import importlib.util
    spec = importlib.util.spec_from_file_location(
        "oracle", os.path.join(ROOT, "scripts", "oracle_mjcf.py"))
    oracle = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(oracle)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    moment = np.zeros((m.nu, m.nv))
    mujoco.mju_sparse2dense(moment, d.actuator_moment, d.moment_rownnz,
                            d.moment_rowadr, d.moment_colind)
    coupled = oracle.couplings(m)
    leaders = sorted({lead for lead, _, _ in coupled.values()})
    t = np.zeros((len(leaders), m.nu))
    for j, (lead, mult, _) in coupled.items():
        t[leaders.index(lead)] += mult * moment[:, m.jnt_dofadr[j]]
    tol = 1e-9 * np.abs(moment).max()
    # Every finger has an actuated joint (else a grasp on it has no actuator at all).
    name = lambda j: mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
    fingers = {name(j).split("_")[0] for j in leaders}
    driven = {name(j).split("_")[0] for i, j in enumerate(leaders) if np.abs(t[i]).max() > tol}
    return (m.nu <= len(leaders) and driven == fingers
            and np.linalg.matrix_rank(t, tol=tol) == m.nu)


def main():
    os.makedirs(OUT, exist_ok=True)
    spatial = "--spatial" in sys.argv[1:]
    stem, base = ("spatial", 3000) if spatial else ("random", 1000)
    seed = 0
    written = 0
    while written < MODELS:
        seed += 1
        rng = np.random.default_rng(base + seed)
        hand = Hand(rng, spatial)
        text = hand.model(int(rng.integers(2, 5)))
        try:
            m = mujoco.MjModel.from_xml_string(text.replace(
                "<worldbody>", '<option gravity="0 0 0"/>\n  <worldbody>', 1).replace(
                "<compiler ", '<compiler boundmass="1e-3" boundinertia="1e-6" ', 1))
        except ValueError as e:
            print(f"seed {seed}: MuJoCo refuses it ({str(e).splitlines()[0]}); drawn again")
            continue
        if not independent_actuators(m):
            print(f"seed {seed}: its actuators are dependent; drawn again")
            continue
        # ("--" may not appear in an XML comment.)
        header = (f"<!-- Drawn by scripts/random_mjcf.py{' (spatial)' if spatial else ''} "
                  f"(seed {base + seed}) for the MJCF "
                  "reader's oracle: a random hand using every form the reader claims to read. -->\n")
        with open(os.path.join(OUT, f"{stem}-{written}.xml"), "w") as f:
            f.write(header + text)
        print(f"{stem}-{written}: seed {base + seed}, {m.njnt} joints, {m.nu} actuators, "
              f"{m.ntendon} tendons, {m.neq} equalities")
        written += 1


if __name__ == "__main__":
    main()
