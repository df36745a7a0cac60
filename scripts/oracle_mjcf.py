#!/usr/bin/env python3
"""MuJoCo's Jacobians and actuator moments for MJCF hands: the oracle of the MJCF reader.

For each hand it samples configurations of the independent joints within their ranges
(coupled joints follow their <equality>), picks two to four fingertip sites, and
writes per configuration:

- `problem`: a hand-form problem (contacts on sites, some with an explicit normal,
  the object frame at the sites' centre with a random orientation);
- `jacobian_transpose`: the expected Jᵀ by independent joint name, from `mj_jacSite`
  and the contact frame convention of docs/geometry.md, reduced by the couplings
  (`Jᵀ = Pᵀ Jᵀ_full`);
- `transmission`: T by joint and actuator name, from `data.actuator_moment` after
  `mj_forward`, reduced the same way (`T = Pᵀ T_full`);
- `passive_torque` (hands with springs): the springs' joint torques `data.qfrc_spring`,
  reduced the same way;
- `grasp_matrix`: the expected G;
- `frames` (the first five configurations): every site's and body's frame in the world
  (`site_xpos`/`site_xmat`, `xpos`/`xmat`), for `Robot::named_frame` and the poses;

and per hand `actuator_limits`, the limit on each actuator's force that
`"torque_limits": "model"` must give (a number t for |u| ≤ t, or [lower, upper]), from
MuJoCo's compiled ranges.

MuJoCo needs every mesh a file names; the fixtures carry none. The script expands the
includes itself, drops <asset>, <contact>, <sensor> and every <geom> but those a spatial
tendon wraps (without their mesh and material), and bounds body masses (none of which
changes kinematics or moment arms) before `from_xml_string`.

Run from the repository root (mujoco 3.3 and numpy from PyPI):

    python3 -m venv /tmp/mj && /tmp/mj/bin/pip install "mujoco==3.3.*" numpy
    /tmp/mj/bin/python scripts/oracle_mjcf.py

It rewrites fixtures/mjcf/oracle/*.json, which `cargo test -p grasp-io --test mjcf`
compares against to 1e-10 relative. The tests do not run this script.
"""

import json
import os
import xml.etree.ElementTree as ET

import mujoco
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "fixtures", "mjcf", "oracle")
CASES = 60
# Configurations whose site and body frames are written too.
FRAME_CASES = 5
RANDOM = "fixtures/mjcf/random"
RANDOM_CASES = 20

HANDS = [
    ("shadow", "fixtures/mjcf/shadow_hand/shadow_hand.xml",
     ["robot0:S_thtip", "robot0:S_fftip", "robot0:S_mftip", "robot0:S_rftip", "robot0:S_lftip"], 1),
    ("adroit", "fixtures/mjcf/adroit_hand/adroit_hand.xml",
     ["S_thtip", "S_fftip", "S_mftip", "S_rftip", "S_lftip"], 2),
    # No fingertip sites: contacts on bodies, at a point and normal in the body frame.
    ("robotiq-s", "fixtures/mjcf/robosuite/robotiq_gripper_s.xml",
     ["body:finger_1_link_3", "body:finger_2_link_3", "body:finger_middle_link_3",
      "body:finger_1_link_2"], 3),
    ("jaco", "fixtures/mjcf/robosuite/jaco_three_finger_gripper.xml",
     ["body:thumb_distal", "body:index_distal", "body:pinky_distal", "body:index_proximal"], 4),
    ("tendon-test", "fixtures/mjcf/test/tendon_finger.xml",
     ["f1_tip_site", "f2_tip_site", "th_tip_site", "body:f1_mid"], 5),
    # MuJoCo Menagerie's hands (kinematics only: fixtures/mjcf/menagerie/README.md).
    ("menagerie-shadow", "fixtures/mjcf/menagerie/shadow_right.xml",
     ["body:rh_ffdistal", "body:rh_mfdistal", "body:rh_rfdistal", "body:rh_lfdistal",
      "body:rh_thdistal", "grasp_site"], 11),
    ("menagerie-allegro", "fixtures/mjcf/menagerie/allegro_right.xml",
     ["body:ff_tip", "body:mf_tip", "body:rf_tip", "body:th_tip", "body:ff_medial"], 12),
    ("menagerie-leap", "fixtures/mjcf/menagerie/leap_right.xml",
     ["body:if_ds", "body:mf_ds", "body:rf_ds", "body:th_ds", "body:th_px"], 13),
    # Slide fingers coupled by a joint equality, driven through a tendon by a biased
    # general actuator.
    ("menagerie-panda", "fixtures/mjcf/menagerie/panda_hand.xml",
     ["body:left_finger", "body:right_finger", "body:hand"], 15),
    # PID plugin actuators, bodies named with slashes, a site on the world body.
    ("menagerie-dexee", "fixtures/mjcf/menagerie/shadow_dexee.xml",
     ["F0/fingertip_site", "F1/fingertip_site", "F2/fingertip_site", "F0/distal_site",
      "body:F1/finger_middle"], 14),
    # Tendon-driven: actuators on spatial tendons wrapped around cylinders with side
    # sites, springs, joint equalities.
    ("menagerie-aero", "fixtures/mjcf/menagerie/aero_right.xml",
     ["if_tip", "mf_tip", "rf_tip", "pf_tip", "th_tip", "body:right_index_middle_link"], 16),
]


def expand(path):
    """The model as one XML tree: includes inlined, assets and geoms dropped but for
    those a spatial tendon wraps."""
    wrapped = set()

    def load(p):
        root = ET.parse(p).getroot()
        base = os.path.dirname(p)

        def walk(el):
            out = []
            for c in list(el):
                if c.tag == "include":
                    inc = load(os.path.join(base, c.get("file")))
                    out.extend(list(inc))
                elif c.tag in ("asset", "contact", "sensor", "keyframe"):
                    continue
                elif c.tag == "geom" and el.tag not in ("spatial", "default") and c.get("name") not in wrapped:
                    continue
                else:
                    walk(c)
                    out.append(c)
            for c in list(el):
                el.remove(c)
            el.extend(out)
        for g in root.iter("geom"):
            for k in ("mesh", "material"):
                g.attrib.pop(k, None)
            if g.get("type") == "mesh":
                del g.attrib["type"]
        walk(root)
        return root
    # The geoms spatial tendons name, from a first pass over the files.
    first = load(os.path.join(ROOT, path))
    wrapped.update(g.get("geom") for sp in first.iter("spatial") for g in sp.iter("geom"))
    root = load(os.path.join(ROOT, path))
    root.tag = "mujoco"
    comp = root.find("compiler")
    if comp is None:
        comp = ET.SubElement(root, "compiler")
        root.remove(comp)
        root.insert(0, comp)
    comp.set("boundmass", "1e-3")
    comp.set("boundinertia", "1e-6")
    comp.set("inertiafromgeom", "false")
    for k in ("meshdir", "texturedir"):
        comp.attrib.pop(k, None)
    return ET.tostring(root, encoding="unicode")


def contact_frame(n):
    """(t1, t2, n) of docs/geometry.md: t1 = normalize(n × a0)."""
    a0 = np.array([0.0, 1.0, 0.0]) if abs(n[0]) >= 0.9 else np.array([1.0, 0.0, 0.0])
    t1 = np.cross(n, a0)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n, t1), n


def couplings(m):
    """Per hinge/slide joint id: (leader id, multiplier, offset) in motion coordinates
    q − qpos0, from joint equalities and two-joint fixed tendon equalities; chains
    resolved to independent joints."""
    follow = {}
    for e in range(m.neq):
        if not m.eq_active0[e]:
            continue
        t, a, b, data = m.eq_type[e], m.eq_obj1id[e], m.eq_obj2id[e], m.eq_data[e]
        if t == mujoco.mjtEq.mjEQ_JOINT:
            follow[a] = (b, data[1], data[0])
        elif t == mujoco.mjtEq.mjEQ_TENDON:
            adr, num = m.tendon_adr[a], m.tendon_num[a]
            (j1, c1), (j2, c2) = [(m.wrap_objid[adr + i], m.wrap_prm[adr + i]) for i in range(num)]
            (ja, ca), (jb, cb) = sorted([(j1, c1), (j2, c2)])
            follow[jb] = (ja, -ca / cb, data[0] / cb)
    resolved = {}
    for j in range(m.njnt):
        if m.jnt_type[j] not in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
            continue
        mult, off, at = 1.0, 0.0, j
        while at in follow:
            lead, k, o = follow[at]
            off += mult * o
            mult *= k
            at = lead
        resolved[j] = (at, mult, off)
    return resolved


def actuator_limits(m):
    """Per actuator, the limit of `"torque_limits": "model"` from MuJoCo's compiled model
    (defaults, classes and autolimits resolved by MuJoCo), as the files write it: its
    forcerange when force-limited; else, for a force that is a fixed gain times the
    control (no bias), gain × ctrlrange when ctrl-limited; then narrowed by the
    actuatorfrcrange of each joint it alone drives (MuJoCo clamps the total actuator
    force on a joint: moment × u within the range; the moment from `actuator_moment` at
    qpos0, constant for actuators on joints and fixed tendons; a joint that a spatial
    tendon's actuator also moves is shared). A range [lo, hi] is the number hi when
    lo = −hi (|u| ≤ hi), and none when empty."""
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    moment = np.zeros((m.nu, m.nv))
    mujoco.mju_sparse2dense(moment, d.actuator_moment, d.moment_rownnz,
                            d.moment_rowadr, d.moment_colind)
    spatial = [m.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_TENDON
               and m.tendon_num[m.actuator_trnid[a][0]] > 0
               and m.wrap_type[m.tendon_adr[m.actuator_trnid[a][0]]] != mujoco.mjtWrap.mjWRAP_JOINT
               for a in range(m.nu)]
    drivers = [(moment[:, v] != 0).sum() for v in range(m.nv)]
    out = {}
    for a in range(m.nu):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a)
        lo, hi = -np.inf, np.inf
        if m.actuator_forcelimited[a]:
            lo, hi = (float(v) for v in m.actuator_forcerange[a])
        elif (m.actuator_ctrllimited[a] and m.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_NONE
              and m.actuator_gaintype[a] == mujoco.mjtGain.mjGAIN_FIXED):
            g = m.actuator_gainprm[a][0]
            lo, hi = sorted(float(v) for v in g * m.actuator_ctrlrange[a])
        if not spatial[a]:
            for v in range(m.nv):
                j, arm = m.dof_jntid[v], moment[a, v]
                if arm == 0 or not m.jnt_actfrclimited[j] or drivers[v] != 1:
                    continue
                jlo, jhi = (float(x) / arm for x in m.jnt_actfrcrange[j])
                jlo, jhi = min(jlo, jhi), max(jlo, jhi)
                lo, hi = max(lo, jlo), min(hi, jhi)
        if not lo < hi or (lo == -np.inf and hi == np.inf):
            out[name] = None
        elif lo == -hi:
            out[name] = hi
        else:
            out[name] = [None if lo == -np.inf else lo, None if hi == np.inf else hi]
    return out


def sites_of(m, names):
    if names is not None:
        return names
    # Tip sites: those on bodies without child bodies.
    leaves = set(range(m.nbody)) - {m.body_parentid[b] for b in range(1, m.nbody)}
    out = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_SITE, s) for s in range(m.nsite)
           if m.site_bodyid[s] in leaves and m.site_bodyid[s] != 0]
    if not out:
        # Else one site per leaf body, at the body origin: added by the caller.
        raise SystemExit("no tip sites")
    return out


def main():
    os.makedirs(OUT, exist_ok=True)
    # The random hands of scripts/random_mjcf.py: fewer configurations each.
    randoms = sorted(f for f in os.listdir(os.path.join(ROOT, RANDOM)) if f.endswith(".xml"))
    hands = [(name, path, tips, seed, CASES) for name, path, tips, seed in HANDS]
    hands += [(f[:-4], f"{RANDOM}/{f}", None, 100 + i, RANDOM_CASES) for i, f in enumerate(randoms)]
    for name, path, tips, seed, count in hands:
        m = mujoco.MjModel.from_xml_string(expand(path))
        d = mujoco.MjData(m)
        rng = np.random.default_rng(seed)
        coup = couplings(m)
        independent = [j for j in coup if coup[j][0] == j]
        jname = lambda j: mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
        tips = sites_of(m, tips)
        cases = []
        for case in range(count):
            q = {}
            for j in independent:
                lo, hi = (m.jnt_range[j] if m.jnt_limited[j] else (-1.0, 1.0))
                q[j] = rng.uniform(lo, hi)
            d.qpos[:] = m.qpos0
            for j, (lead, mult, off) in coup.items():
                motion = mult * (q[lead] - m.qpos0[m.jnt_qposadr[lead]]) + off
                d.qpos[m.jnt_qposadr[j]] = m.qpos0[m.jnt_qposadr[j]] + motion
            mujoco.mj_forward(m, d)
            k = int(rng.integers(2, min(4, len(tips)) + 1))
            chosen = list(rng.choice(tips, size=k, replace=False))
            pts = [d.xpos[m.body(s[5:]).id].copy() if s.startswith("body:")
                   else d.site_xpos[m.site(s).id].copy() for s in chosen]
            centre = np.mean(pts, axis=0)
            rq = rng.normal(size=4)
            rq /= np.linalg.norm(rq)
            R = np.zeros(9)
            mujoco.mju_quat2Mat(R, rq)
            R = R.reshape(3, 3)
            contacts, gcols, jcols = [], [], []
            models = ["pcwf", "sfcl", "fpc", "sfce"]
            for i, s in enumerate(chosen):
                c = {"model": models[(case + i) % 4]}
                if c["model"] != "fpc":
                    c["mu"] = 0.8
                if c["model"] in ("sfcl", "sfce"):
                    c["mu_torsion"] = 0.005
                jacp = np.zeros((3, m.nv))
                jacr = np.zeros((3, m.nv))
                if s.startswith("body:"):
                    b = m.body(s[5:]).id
                    Rb = d.xmat[b].reshape(3, 3)
                    off = rng.uniform(-0.02, 0.02, size=3)
                    nb = rng.normal(size=3)
                    nb /= np.linalg.norm(nb)
                    p_w = d.xpos[b] + Rb @ off
                    n_w = Rb @ nb
                    c.update({"link": s[5:], "position": list(off), "normal": list(nb), "frame": "link"})
                    mujoco.mj_jac(m, d, jacp, jacr, p_w, b)
                else:
                    sid = m.site(s).id
                    p_w = d.site_xpos[sid].copy()
                    z_w = d.site_xmat[sid].reshape(3, 3)[:, 2]
                    c["site"] = s
                    if rng.random() < 0.3 and np.linalg.norm(centre - p_w) > 1e-6:
                        # An explicit normal toward the centre, in the object frame.
                        n_w = centre - p_w
                        n_w /= np.linalg.norm(n_w)
                        c["normal"] = list(R.T @ n_w)
                    else:
                        n_w = z_w
                    mujoco.mj_jacSite(m, d, jacp, jacr, sid)
                contacts.append(c)
                n_o = R.T @ n_w
                p_o = R.T @ (p_w - centre)
                t1, t2, n = contact_frame(n_o)
                dirs = [n] if c["model"] == "fpc" else [t1, t2, n]
                for dv in dirs:
                    gcols.append(list(dv) + list(np.cross(p_o, dv)))
                    jcols.append(jacp.T @ (R @ dv))
                if c["model"] in ("sfcl", "sfce"):
                    gcols.append([0, 0, 0] + list(n))
                    jcols.append(jacr.T @ (R @ n))
            jt_full = np.array(jcols).T  # nv × ncols
            moment = np.zeros((m.nu, m.nv))
            mujoco.mju_sparse2dense(moment, d.actuator_moment, d.moment_rownnz,
                                    d.moment_rowadr, d.moment_colind)
            jt, tr, springs = {}, {}, {}
            for j in independent:
                jt[jname(j)] = [0.0] * jt_full.shape[1]
                tr[jname(j)] = {}
                springs[jname(j)] = 0.0
            for j, (lead, mult, _) in coup.items():
                dof = m.jnt_dofadr[j]
                springs[jname(lead)] += mult * d.qfrc_spring[dof]
                row = jt[jname(lead)]
                for c_ in range(jt_full.shape[1]):
                    row[c_] += mult * jt_full[dof, c_]
                for a in range(m.nu):
                    an = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a)
                    v = mult * moment[a, dof]
                    if v != 0.0:
                        tr[jname(lead)][an] = tr[jname(lead)].get(an, 0.0) + v
            # A moment arm that cancels (an actuator on a tendon an equality holds at
            # fixed length) is none: such an actuator moves no independent joint.
            big = np.abs(moment).max() if moment.size else 0.0
            for row in tr.values():
                for an in [an for an, v in row.items() if abs(v) <= 1e-12 * big]:
                    del row[an]
            problem = {
                "name": f"{name} case {case}",
                "hand": {
                    "model": os.path.relpath(os.path.join(ROOT, path), OUT),
                    "joint_positions": {jname(j): float(q[j]) for j in independent},
                },
                "object_pose": {"position": list(centre),
                                "quaternion": [float(x) for x in rq]},
                "contacts": contacts,
                "wrench": [0, 0, -0.5, 0, 0, 0],
                "torque_limits": "model",
            }
            case_out = {
                "problem": problem,
                "jacobian_transpose": jt,
                "transmission": tr,
                "grasp_matrix": np.array(gcols).T.tolist(),
            }
            if any(v != 0.0 for v in springs.values()):
                case_out["passive_torque"] = springs
            if case < FRAME_CASES:
                # Every site's and body's frame in the world: position, then the
                # rotation matrix row by row (MuJoCo's site_xmat, xmat).
                frames = {}
                for sid in range(m.nsite):
                    frames[mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_SITE, sid)] = (
                        list(d.site_xpos[sid]) + list(d.site_xmat[sid]))
                for bid in range(1, m.nbody):
                    frames.setdefault(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, bid),
                                      list(d.xpos[bid]) + list(d.xmat[bid]))
                case_out["frames"] = frames
            cases.append(case_out)
        out = {"model": path, "mujoco": mujoco.__version__,
               "actuator_limits": actuator_limits(m), "cases": cases}
        with open(os.path.join(OUT, f"{name}.json"), "w") as f:
            json.dump(out, f, indent=0)
        print(f"{name}: {len(cases)} configurations, nv {m.nv}, nu {m.nu}")


if __name__ == "__main__":
    main()
