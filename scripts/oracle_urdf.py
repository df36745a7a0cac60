#!/usr/bin/env python3
"""Pinocchio's contact Jacobians for URDF hands: the oracle of grasp-torque's hand form.

For each hand it samples joint configurations within the joint limits and two to four
fingertip contacts pushing toward their common centre, and writes, per configuration:

- `problem`: a hand-form problem file (the object frame sits at the contacts' centre
  with a random orientation; some contacts are given in their link's frame);
- `jacobian_transpose`: the expected Jᵀ, one row per independent joint, by name, from
  Pinocchio's frame Jacobian (LOCAL_WORLD_ALIGNED, at the contact point) and the
  contact frame convention of docs/geometry.md;
- `grasp_matrix`: the expected G;
- `gravity`, `gravity_torque`: an acceleration of gravity (9.81 m/s² in a random
  direction of the root frame) and the links' weight on each independent joint,
  `−computeGeneralizedGravity` (reduced by the couplings as Jᵀ is; for the hands loaded
  with mimic, checked against the unreduced model reduced here);
- `frames` (the first five configurations): every link's frame, from Pinocchio's body
  frames;

and per hand `effort_limits`, Pinocchio's effort limit of each independent joint, which
`"torque_limits": "model"` must give.

The Allegro and Ability hands are loaded with `buildModelFromUrdf(path, mimic=True)`, so
Pinocchio itself couples the Ability hand's mimic joints. Pinocchio couples one level of
mimic only, so the test gripper (mimic chains) is loaded without mimic and this script
applies `Jᵀ = Pᵀ Jᵀ_full` with P from its own reading of the URDF.

Run from the repository root (pin 4.1.0 and numpy from PyPI):

    python3 -m venv /tmp/oracle && /tmp/oracle/bin/pip install pin==4.1.0 numpy
    /tmp/oracle/bin/python scripts/oracle_urdf.py

It rewrites fixtures/urdf/oracle/*.json, which `cargo test -p grasp-io --test urdf`
compares against to 1e-10 relative. The tests do not run this script.
"""

import json
import os
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "fixtures", "urdf", "oracle")
CASES = 60
# Configurations whose link frames are written too.
FRAME_CASES = 5
RANDOM = "fixtures/urdf/random"
RANDOM_CASES = 20

HANDS = [
    ("allegro", "fixtures/urdf/allegro/allegro_hand_right.urdf", True,
     ["link_3.0_tip", "link_7.0_tip", "link_11.0_tip", "link_15.0_tip"], 1),
    ("ability", "fixtures/urdf/ability_hand/ability_hand_right.urdf", True,
     ["thumb_tip", "index_tip", "middle_tip", "ring_tip", "pinky_tip"], 2),
    ("linkage-gripper", "fixtures/urdf/test/linkage_gripper.urdf", False,
     ["left_tip", "right_tip", "thumb_tip", "left_mid", "right_roll_link"], 3),
    # DexSuite's dex-urdf (fixtures/urdf/dex-urdf/README.md).
    ("leap", "fixtures/urdf/dex-urdf/leap_hand_right.urdf", True,
     ["thumb_tip_head", "index_tip_head", "middle_tip_head", "ring_tip_head"], 4),
    ("shadow-urdf", "fixtures/urdf/dex-urdf/shadow_hand_right.urdf", True,
     ["fftip", "mftip", "rftip", "lftip", "thtip"], 5),
    ("barrett", "fixtures/urdf/dex-urdf/bhand_model.urdf", True,
     ["finger_1_dist_link", "finger_2_dist_link", "finger_3_dist_link"], 6),
]


def contact_frame(n):
    """(t1, t2, n) of docs/geometry.md: t1 = normalize(n × a0)."""
    a0 = np.array([0.0, 1.0, 0.0]) if abs(n[0]) >= 0.9 else np.array([1.0, 0.0, 0.0])
    t1 = np.cross(n, a0)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n, t1), n


def couplings(path):
    """Per non-fixed joint: (independent leader, multiplier, offset), chains resolved."""
    joints = {}
    for j in ET.parse(path).getroot().iter("joint"):
        m = j.find("mimic")
        joints[j.get("name")] = (
            j.get("type"),
            None if m is None else (m.get("joint"), float(m.get("multiplier", 1)),
                                    float(m.get("offset", 0))),
        )
    out = {}
    for name, (kind, mimic) in joints.items():
        if kind == "fixed":
            continue
        mult, off, at = 1.0, 0.0, name
        while joints[at][1] is not None:
            leader, m, o = joints[at][1]
            off += mult * o
            mult *= m
            at = leader
        out[name] = (at, mult, off)
    return out


def sample(rng, lo, hi, kind):
    if kind == "continuous" or not np.isfinite(lo) or not np.isfinite(hi):
        return rng.uniform(-np.pi, np.pi)
    return rng.uniform(lo, hi)


def random_quaternion(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)  # [w, x, y, z]


def full_q(model, q_full):
    """Pinocchio's configuration of `model` (no mimic joints) from every joint's
    position by name."""
    q = pin.neutral(model)
    for i in range(1, model.njoints):
        jm = model.joints[i]
        v = q_full[model.names[i]]
        if jm.nq == 2:  # continuous: (cos, sin)
            q[jm.idx_q:jm.idx_q + 2] = [np.cos(v), np.sin(v)]
        else:
            q[jm.idx_q] = v
    return q


def main():
    os.makedirs(OUT, exist_ok=True)
    # The random hands of scripts/random_urdf.py, their leaf links as contacts, fewer
    # configurations each, coupled here (Pinocchio couples one level of mimic only).
    hands = [h + (CASES,) for h in HANDS]
    rdir = os.path.join(ROOT, RANDOM)
    for i, f in enumerate(sorted(x for x in os.listdir(rdir) if x.endswith(".urdf"))):
        root = ET.parse(os.path.join(rdir, f)).getroot()
        parents = {j.find("parent").get("link") for j in root.iter("joint")}
        leaves = [j.find("child").get("link") for j in root.iter("joint")
                  if j.find("child").get("link") not in parents]
        hands.append((f[:-5], f"{RANDOM}/{f}", False, leaves, 100 + i, RANDOM_CASES))
    for name, rel, use_mimic, tips, seed, count in hands:
        rng = np.random.default_rng(seed)
        # Gravity's directions from their own stream: the configurations stay as drawn.
        grng = np.random.default_rng(seed + 1000)
        path = os.path.join(ROOT, rel)
        model = pin.buildModelFromUrdf(path, mimic=use_mimic)
        unreduced = pin.buildModelFromUrdf(path)
        coupled = couplings(path)
        kinds = {j.get("name"): j.get("type") for j in ET.parse(path).getroot().iter("joint")}
        limits = {}
        for j in ET.parse(path).getroot().iter("joint"):
            lim = j.find("limit")
            lo = float(lim.get("lower", "-inf")) if lim is not None else -np.inf
            hi = float(lim.get("upper", "inf")) if lim is not None else np.inf
            limits[j.get("name")] = (lo, hi)
        independent = [j for j, (lead, _, _) in coupled.items() if lead == j]
        # Pinocchio's velocity columns by joint name.
        col = {}
        for i in range(1, model.njoints):
            jm = model.joints[i]
            if jm.shortname() != "JointModelMimic":
                col[model.names[i]] = jm.idx_v
        cases = []
        attempts = 0
        while len(cases) < count:
            attempts += 1
            q_ind = {j: sample(rng, *limits[j], kinds[j]) for j in independent}
            # Some joints are left out of the file: they sit at 0.
            omitted = set(rng.choice(independent, size=rng.integers(0, 3), replace=False))
            for j in omitted:
                q_ind[j] = 0.0
            q_full = {j: m * q_ind[lead] + o for j, (lead, m, o) in coupled.items()}
            q = pin.neutral(model)
            for i in range(1, model.njoints):
                jm = model.joints[i]
                if jm.shortname() == "JointModelMimic":
                    continue
                v = q_full[model.names[i]]
                if jm.nq == 2:  # continuous: (cos, sin)
                    q[jm.idx_q:jm.idx_q + 2] = [np.cos(v), np.sin(v)]
                else:
                    q[jm.idx_q] = v
            k = int(rng.integers(2, min(4, len(tips)) + 1))
            chosen = list(rng.choice(tips, size=k, replace=False))
            m = model.copy()
            data0 = m.createData()
            pin.framesForwardKinematics(m, data0, q)
            points = []
            for link in chosen:
                fid = m.getFrameId(link)
                offset = rng.uniform(-0.004, 0.004, size=3)
                points.append((link, fid, offset, data0.oMf[fid].act(offset)))
            centre = np.mean([p for *_, p in points], axis=0)
            if min(np.linalg.norm(centre - p) for *_, p in points) < 5e-3:
                continue
            quat = random_quaternion(rng)
            R = pin.Quaternion(quat[0], quat[1], quat[2], quat[3]).toRotationMatrix()
            contacts, g_cols, jt_cols = [], [], []
            added = []
            for idx, (link, fid, offset, p_w) in enumerate(points):
                n_w = (centre - p_w) / np.linalg.norm(centre - p_w)
                frame = m.frames[fid]
                placement = frame.placement * pin.SE3(np.eye(3), offset)
                added.append(m.addFrame(pin.Frame(f"contact{idx}", frame.parentJoint, fid,
                                                  placement, pin.FrameType.OP_FRAME)))
                p_o = R.T @ (p_w - centre)
                n_o = R.T @ n_w
                kind = ["fpc", "pcwf", "sfcl", "sfce"][int(rng.integers(0, 4))]
                c = {"link": link, "model": kind}
                if rng.random() < 0.3:
                    R_l = data0.oMf[fid].rotation
                    c.update(frame="link", position=offset.tolist(), normal=(R_l.T @ n_w).tolist())
                else:
                    c.update(position=p_o.tolist(), normal=n_o.tolist())
                if kind != "fpc":
                    c["mu"] = round(float(rng.uniform(0.4, 1.0)), 3)
                if kind in ("sfcl", "sfce"):
                    c["mu_torsion"] = round(float(rng.uniform(0.002, 0.02)), 4)
                contacts.append((c, p_o, n_o, n_w))
            data = m.createData()
            pin.computeJointJacobians(m, data, q)
            pin.updateFramePlacements(m, data)
            jt_full = {j: [] for j in col}
            for (c, p_o, n_o, n_w), fid in zip(contacts, added):
                J = pin.getFrameJacobian(m, data, fid, pin.LOCAL_WORLD_ALIGNED)
                t1, t2, n = contact_frame(n_o)
                dirs = [n] if c["model"] == "fpc" else [t1, t2, n]
                for d in dirs:
                    g_cols.append(np.concatenate([d, np.cross(p_o, d)]))
                    for j, v in col.items():
                        jt_full[j].append(float(J[:3, v] @ (R @ d)))
                if c["model"] in ("sfcl", "sfce"):
                    g_cols.append(np.concatenate([np.zeros(3), n]))
                    for j, v in col.items():
                        jt_full[j].append(float(J[3:, v] @ (R @ n)))
            if use_mimic:
                jt = jt_full
            else:
                # Jᵀ = Pᵀ Jᵀ_full: each joint's row is credited to its leader.
                width = len(g_cols)
                jt = {j: [0.0] * width for j in independent}
                for j, row in jt_full.items():
                    lead, mult, _ = coupled[j]
                    jt[lead] = [a + mult * b for a, b in zip(jt[lead], row)]
            gravity = grng.normal(size=3)
            gravity *= 9.81 / np.linalg.norm(gravity)
            weights = []
            for gm, mimic in ((model, use_mimic), (unreduced, False)):
                gm = gm.copy()
                gm.gravity.linear = gravity
                gd = gm.createData()
                qg = q if gm.nq == model.nq else full_q(gm, q_full)
                tau = -pin.computeGeneralizedGravity(gm, gd, qg)
                cols = {gm.names[i]: gm.joints[i].idx_v for i in range(1, gm.njoints)
                        if gm.joints[i].shortname() != "JointModelMimic"}
                if mimic:
                    weights.append({j: float(tau[v]) for j, v in cols.items()})
                else:
                    red = {j: 0.0 for j in independent}
                    for j, v in cols.items():
                        lead, mult, _ = coupled[j]
                        red[lead] += mult * float(tau[v])
                    weights.append(red)
            scale = max(abs(v) for v in weights[1].values())
            assert all(abs(weights[0][j] - weights[1][j]) <= 1e-12 * scale for j in independent), name
            weight = 0.3 * 9.81
            problem = {
                "name": f"{name}-{len(cases)}",
                "hand": {
                    "model": os.path.relpath(path, OUT),
                    "joint_positions": {j: float(v) for j, v in q_ind.items() if j not in omitted},
                },
                "object_pose": {"position": centre.tolist(), "quaternion": quat.tolist()},
                "contacts": [c for c, *_ in contacts],
                "wrench": (np.concatenate([R.T @ [0, 0, weight], np.zeros(3)])).tolist(),
                "torque_limits": "model",
            }
            case_out = {
                "problem": problem,
                "defaulted_joints": sorted(omitted),
                "grasp_matrix": np.array(g_cols).T.tolist(),
                "jacobian_transpose": jt,
                "gravity": gravity.tolist(),
                "gravity_torque": weights[0],
            }
            if len(cases) < FRAME_CASES:
                # Every link's frame in the root link's: position, then the rotation
                # matrix row by row (Pinocchio's body frames).
                case_out["frames"] = {
                    f.name: list(data0.oMf[i].translation) + list(data0.oMf[i].rotation.flatten())
                    for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY
                }
            cases.append(case_out)
        # `"torque_limits": "model"`: Pinocchio's effort limit of each independent
        # joint (none when the URDF gives no positive effort).
        efforts = {}
        for i in range(1, model.njoints):
            jm = model.joints[i]
            if jm.shortname() == "JointModelMimic" or model.names[i] not in independent:
                continue
            e = float(model.effortLimit[jm.idx_v])
            efforts[model.names[i]] = e if np.isfinite(e) and e > 0 else None
        out = {
            "generator": "scripts/oracle_urdf.py",
            "effort_limits": efforts,
            "oracle": f"pinocchio {pin.__version__} (buildModelFromUrdf, mimic={use_mimic}), "
                      "getFrameJacobian LOCAL_WORLD_ALIGNED at the contact point",
            "urdf": os.path.relpath(path, OUT),
            "cases": cases,
        }
        with open(os.path.join(OUT, f"{name}.json"), "w") as f:
            json.dump(out, f, indent=1)
            f.write("\n")
        print(f"{name}: {len(cases)} configurations ({attempts} drawn)")


if __name__ == "__main__":
    main()
