"""Hand.solve_batch: a planner's batch straight from a URDF or MJCF hand, against the
same grasps written as hand-form dicts and solved one by one."""

import copy
import json
import os
import pickle
import signal
import threading

import numpy as np
import pytest

import grasp_torque as gt
from conftest import ROOT

HANDS = ROOT / "fixtures" / "hands"


def fixture(name):
    d = json.loads((HANDS / f"{name}.json").read_text())
    hand = gt.Hand(HANDS / d["hand"]["model"])
    q = np.zeros(len(hand.joint_names))
    for k, v in d["hand"]["joint_positions"].items():
        q[hand.joint_names.index(k)] = v
    return d, hand, q


def pose_of(d):
    p = d.get("object_pose", {})
    return np.array(p.get("position", [0.0] * 3) + p.get("quaternion", [1.0, 0, 0, 0]))


def as_dict(d, hand, q, positions=None, normals=None, pose=None):
    """Grasp b written as a hand-form problem, as a user without the batch would."""
    e = copy.deepcopy(d)
    e["hand"]["model"] = str(HANDS / d["hand"]["model"])
    e["hand"]["joint_positions"] = dict(zip(hand.joint_names, map(float, q)))
    for i, c in enumerate(e["contacts"]):
        if positions is not None and not np.isnan(positions[i]).all():
            c["position"] = positions[i].tolist()
        if normals is not None and not np.isnan(normals[i]).all():
            c["normal"] = normals[i].tolist()
    if pose is not None:
        e["object_pose"] = {"position": pose[:3].tolist(), "quaternion": pose[3:].tolist()}
    return e


def test_a_urdf_hands_batch_matches_its_grasps_one_by_one():
    d, hand, q0 = fixture("allegro-pinch")
    rng = np.random.default_rng(7)
    B, K = 60, 3
    k = len(d["contacts"])
    q = q0 + rng.normal(0, 0.03, (B, len(q0)))
    P = np.array([c["position"] for c in d["contacts"]]) + rng.normal(0, 0.002, (B, k, 3))
    N = np.array([c["normal"] for c in d["contacts"]]) + rng.normal(0, 0.05, (B, k, 3))
    N /= np.linalg.norm(N, axis=2, keepdims=True)
    N[::4, 1] = np.nan  # a row of NaN: the contact dict's own normal
    W = np.array(d["wrench"]) * (1 + 0.01 * np.arange(K))[None, :, None] * np.ones((B, 1, 1))
    pose = pose_of(d)
    contacts = d["contacts"]
    out = hand.solve_batch(q, W, contacts, positions=P, normals=N, object_pose=pose, threads=2)
    assert out.torque.shape == (B, K, 12) and out.errors == {}
    assert out.names == [n for n in hand.joint_names if n not in ("joint_8.0", "joint_9.0", "joint_10.0", "joint_11.0")]
    solved = 0
    for b in range(B):
        p = gt.Problem.from_dict(as_dict(d, hand, q[b], P[b], N[b], pose))
        assert p.joint_names == out.names
        s = gt.Solver(p)
        for kk in range(K):
            r = s.solve(W[b, kk])
            assert gt.STATUS_CODES[int(out.status[b, kk])] == r.status
            if r.objective is not None:
                solved += 1
                assert out.objective[b, kk] == r.objective
                np.testing.assert_array_equal(out.torque[b, kk], r.torque)
    assert solved >= B * K // 2


class Stop(Exception):
    """What the test's signal handler raises."""


def _stop(signum, frame):
    raise Stop


def test_a_signal_stops_a_long_batch_with_the_answers_before_it_written():
    """Python's signal handlers run while a batch runs, between spans of about 50 ms:
    Ctrl-C (here SIGUSR1, whose handler raises) stops a planner's long batch early
    instead of after its last grasp. The spans before it are written, and are what an
    uninterrupted batch of those grasps gives, bit for bit."""
    d, hand, q0 = fixture("allegro-pinch")
    B = 300_000  # several seconds on one thread; the signal comes after half a second
    q = q0 + np.random.default_rng(3).normal(0, 0.02, (B, len(q0)))
    W = np.broadcast_to(np.array(d["wrench"]), (B, 6))
    status = np.full(B, 9, dtype=np.int8)
    torque = np.full((B, 12), np.nan)
    old = signal.signal(signal.SIGUSR1, _stop)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGUSR1))
    try:
        timer.start()
        with pytest.raises(Stop):
            hand.solve_batch(q, W, d["contacts"], object_pose=pose_of(d), threads=1, status=status, torque=torque)
    finally:
        timer.cancel()
        signal.signal(signal.SIGUSR1, old)
    done = int((status != 9).sum())
    assert 0 < done < B
    assert (status[:done] != 9).all(), "the spans are written in order"
    full = hand.solve_batch(q[:done], W[:done], d["contacts"], object_pose=pose_of(d), threads=2)
    np.testing.assert_array_equal(status[:done], full.status)
    np.testing.assert_array_equal(torque[:done], full.torque)


def test_an_mjcf_hands_batch_gives_actuator_forces_within_the_models_limits():
    d, hand, q0 = fixture("shadow-tripod")
    rng = np.random.default_rng(11)
    B = 40
    q = q0 + rng.normal(0, 0.02, (B, len(q0)))
    W = np.tile(d["wrench"], (B, 1))
    pose = pose_of(d)
    out = hand.solve_batch(q, W, d["contacts"], object_pose=pose, torque_limits="model")
    assert out.errors == {}
    optimal = 0
    for b in range(B):
        r = gt.Solver(gt.Problem.from_dict(as_dict(d, hand, q[b], pose=pose))).solve()
        assert r.actuator_names == out.names
        assert gt.STATUS_CODES[int(out.status[b])] == r.status
        if r.objective is not None:
            optimal += 1
            assert out.objective[b] == r.objective
            np.testing.assert_array_equal(out.torque[b], r.torque)
    assert optimal >= B // 2


def test_rejected_grasps_are_invalid_items_naming_the_field():
    d, hand, q0 = fixture("allegro-pinch")
    B = 6
    q = np.tile(q0, (B, 1))
    q[1, 3] = np.nan
    N = np.tile([c["normal"] for c in d["contacts"]], (B, 1, 1))
    N[2, 0] *= 2.0
    P = np.tile([c["position"] for c in d["contacts"]], (B, 1, 1))
    P[3, 2, 1] = np.nan  # part of a row: not "the contact's own"
    W = np.tile(d["wrench"], (B, 1))
    W[4, 0] = np.inf
    out = hand.solve_batch(q, W, d["contacts"], positions=P, normals=N, object_pose=pose_of(d))
    assert list(out.status) == [0, 5, 5, 5, 5, 0]
    assert out.errors[1].startswith("joint_positions[3] (joint_3.0): ") and "NaN" in out.errors[1]
    assert out.errors[2].startswith("contacts[0] (index).normal: ")
    assert out.errors[3].startswith("contacts[2] (thumb).position: ")
    assert "wrench" in out.errors[4]
    assert np.isnan(out.torque[1:5]).all() and np.isnan(out.objective[1:5]).all()


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(joint_positions=np.zeros((2, 3))), "joint_positions: expected shape (B, 16)"),
        (dict(joint_positions=np.zeros(16)), "joint_positions: expected shape (B, 16)"),
        (dict(positions=np.zeros((2, 2, 3))), "positions: expected shape (2, 3, 3)"),
        (dict(normals=np.zeros((2, 3))), "normals: expected shape (B, k, 3)"),
        (dict(object_pose=np.zeros(6)), "object_pose: expected shape (7,) or (2, 7)"),
        (dict(W=np.zeros((3, 6))), "W: expected shape (2, 6) or (2, K, 6)"),
        (dict(contacts=[{"link": "link_3.0_tipp", "model": "pcwf", "mu": 0.5}]), "link_3.0_tip"),
        (dict(contacts={"link": "link_3.0_tip"}), "contacts: expected a list"),
        (dict(torque_weights=[1.0] * 3), "torque_weights"),
        (dict(sides=2), "sides"),
        (dict(threads=0), "threads: expected at least 1"),
    ],
)
def test_arguments_that_make_the_batch_impossible_raise(kwargs, message):
    d, hand, q0 = fixture("allegro-pinch")
    args = dict(joint_positions=np.tile(q0, (2, 1)), W=np.tile(d["wrench"], (2, 1)), contacts=d["contacts"])
    for k in ("joint_positions", "W", "contacts"):
        if k in kwargs:
            args[k] = kwargs.pop(k)
    with pytest.raises(ValueError, match=None) as e:
        hand.solve_batch(args["joint_positions"], args["W"], args["contacts"], **kwargs)
    assert message in str(e.value)


def test_a_hand_reports_its_file_and_pickles():
    _, hand, _ = fixture("shadow-tripod")
    assert "robot0:S_thtip" in hand.sites and "robot0:FFJ3" in hand.joint_names
    again = pickle.loads(pickle.dumps(hand))
    assert again.joint_names == hand.joint_names and again.name == hand.name
    with pytest.raises(ValueError, match="no_such_hand.urdf: cannot read the robot file"):
        gt.Hand(HANDS / "no_such_hand.urdf")
    with pytest.raises(ValueError, match="got a directory"):
        gt.Hand(HANDS)
    with pytest.raises(ValueError, match="allegro-pinch.json: .*not well-formed XML"):
        gt.Hand(HANDS / "allegro-pinch.json")
    # The size and encoding limits name the file itself, not a problem file's field.
    if os.path.exists("/dev/zero"):
        with pytest.raises(ValueError, match="^could not read /dev/zero: expected at most 67108864 bytes"):
            gt.Hand("/dev/zero")


def test_the_planner_example_runs(root):
    import subprocess
    import sys

    script = root / "examples" / "python" / "hand_batch.py"
    out = subprocess.run(
        [sys.executable, str(script), "--grasps", "500", "--check"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert "500 of 500 candidates hold the object" in out.stdout
    assert "matches the batch" in out.stdout


@pytest.mark.parametrize("name", ["allegro-pinch", "shadow-tripod", "ability-tripod"])
def test_arrays_are_the_hand_forms_matrices_and_solve_as_the_hand_batch(name):
    d, hand, q0 = fixture(name)
    rng = np.random.default_rng(3)
    B = 25
    q = q0 + rng.normal(0, 0.02, (B, len(q0)))
    q[4, 0] = np.inf
    pose = pose_of(d)
    a = hand.arrays(q, d["contacts"], object_pose=pose)
    assert set(a.errors) == {4} and "joint_positions[0]" in a.errors[4]
    assert np.isnan(a.G[4]).all() and np.isnan(a.JT[4]).all()
    for b in range(B):
        if b == 4:
            continue
        p = gt.Problem.from_dict(as_dict(d, hand, q[b], pose=pose))
        np.testing.assert_array_equal(a.G[b], p.grasp_matrix)
        np.testing.assert_array_equal(a.JT[b], p.jacobian_transpose)
        assert a.joint_names == p.joint_names
    W = np.tile(d["wrench"], (B, 1))
    limits = d.get("torque_limits")
    ok = [b for b in range(B) if b != 4]
    direct = hand.solve_batch(q[ok], W[ok], d["contacts"], object_pose=pose, torque_limits=limits)
    models = [{k: c[k] for k in ("model", "mu", "mu_torsion") if k in c} for c in d["contacts"]]
    kw = {}
    if a.transmission is not None:
        kw = dict(transmission=a.transmission, actuator_names=a.actuator_names)
        assert direct.names == a.actuator_names
    if limits == "model":
        # The model's limits as the hand form takes them, as rows [lower, upper].
        one = gt.Problem.from_dict(as_dict(d, hand, q[0], pose=pose)).to_dict()["torque_limits"]
        want = [[-l, l] if isinstance(l, float) else l or [None, None] for l in one]
        want = np.array([[-np.inf if lo is None else lo, np.inf if hi is None else hi] for lo, hi in want])
        np.testing.assert_array_equal(a.torque_limits, want)
        kw["torque_limits"] = a.torque_limits
    via = gt.solve_batch(a.G[ok], a.JT[ok], W[ok], models, **kw)
    np.testing.assert_array_equal(via.status, direct.status)
    np.testing.assert_array_equal(via.objective, direct.objective)
    np.testing.assert_array_equal(via.torque, direct.torque)


@pytest.mark.parametrize("name", [p.stem for p in sorted(HANDS.glob("*.json"))])
def test_arrays_and_frames_are_the_same_on_any_number_of_threads(name):
    """Hand.arrays and Hand.frames pose their grasps in parallel, in spans (more than
    one here): one thread and two give the same arrays bit for bit, a rejected grasp's
    NaN rows and message included."""
    d, hand, q0 = fixture(name)
    B = 3000
    q = q0 + np.random.default_rng(5).normal(0, 0.02, (B, len(q0)))
    q[1234, -1] = np.nan
    kw = {"object_pose": pose_of(d)}
    if "gravity" in d["hand"]:
        kw["gravity"] = d["hand"]["gravity"]
    if "object" in d:
        kw["object_mass"] = d["object"]["mass"]
        kw["center_of_mass"] = d["object"].get("center_of_mass")
    one = hand.arrays(q, d["contacts"], threads=1, **kw)
    two = hand.arrays(q, d["contacts"], threads=2, **kw)
    assert set(one.errors) == {1234} and one.errors == two.errors
    for field in ("G", "JT", "transmission", "passive_torque", "object_wrench"):
        a, b = getattr(one, field), getattr(two, field)
        assert (a is None) == (b is None), field
        if a is not None:
            np.testing.assert_array_equal(a, b, err_msg=field)
    assert np.isnan(one.G[1234]).all() and not np.isnan(one.G[:1234]).any()
    q[1234, -1] = 0.0
    names = hand.sites or hand.links
    for a, b in zip(hand.frames(q, names, threads=1), hand.frames(q, names, threads=2)):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="threads"):
        hand.arrays(q, d["contacts"], threads=0, **kw)
    with pytest.raises(ValueError, match="threads"):
        hand.frames(q, names, threads=0)


def contact_frame(n):
    """(t1, t2, n) of docs/geometry.md."""
    a0 = np.array([0.0, 1.0, 0.0]) if abs(n[0]) >= 0.9 else np.array([1.0, 0.0, 0.0])
    t1 = np.cross(n, a0)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n, t1), n


@pytest.mark.parametrize("name", ["shadow-tripod", "allegro-pinch"])
def test_frames_place_the_contacts_as_the_hand_batch_does(name):
    # G of a grasp with the object frame at the root frame, from Hand.arrays, against G
    # built from Hand.frames: a site contact at the site's origin along its z axis, a
    # link contact at its link-frame position and normal moved by the link's frame.
    d, hand, q0 = fixture(name)
    rng = np.random.default_rng(3)
    q = q0 + rng.normal(0, 0.1, (8, len(q0)))
    contacts = [{k: v for k, v in c.items() if k not in ("position", "normal", "frame")}
                for c in d["contacts"]]
    offsets = rng.normal(0, 0.005, (len(contacts), 3))
    normals = rng.normal(size=(len(contacts), 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    for c, o, n in zip(contacts, offsets, normals):
        if "link" in c:
            c.update(frame="link", position=o.tolist(), normal=n.tolist())
    names = [c.get("site", c.get("link")) for c in contacts]
    P, R = hand.frames(q, names)
    assert P.shape == (8, len(names), 3) and R.shape == (8, len(names), 3, 3)
    # No names, no frames (it panicked): empty arrays of the same leading shape.
    P0, R0 = hand.frames(q, [])
    assert P0.shape == (8, 0, 3) and R0.shape == (8, 0, 3, 3)
    assert np.allclose(np.einsum("bkij,bkil->bkjl", R, R), np.eye(3), atol=1e-14)
    G = hand.arrays(q, contacts).G
    for b in range(8):
        cols = []
        for i, c in enumerate(contacts):
            if "site" in c:
                p, n = P[b, i], R[b, i][:, 2]
            else:
                p, n = P[b, i] + R[b, i] @ offsets[i], R[b, i] @ normals[i]
            dirs = [n] if c["model"] == "fpc" else list(contact_frame(n))
            cols += [np.concatenate([v, np.cross(p, v)]) for v in dirs]
            if c["model"] in ("sfcl", "sfce"):
                cols.append(np.concatenate([np.zeros(3), n]))
        assert np.abs(np.array(cols).T - G[b]).max() <= 1e-14 * max(1.0, np.abs(G[b]).max())
    # One configuration gives one set of frames.
    P1, R1 = hand.frames(q[0], names)
    assert np.array_equal(P1, P[0]) and np.array_equal(R1, R[0])


def test_frames_name_what_is_wrong():
    _, hand, q = fixture("shadow-tripod")
    site = hand.sites[0]
    with pytest.raises(ValueError, match=r"names\[1\]: expected a link or site of .*\(nearest: `"):
        hand.frames(q, [site, site + "x"])
    bad = q.copy()
    bad[2] = np.nan
    with pytest.raises(ValueError, match=r"joint_positions\[0\]\[2\] \(.*\): expected a finite position"):
        hand.frames(bad, [site])
    with pytest.raises(ValueError, match=r"joint_positions: expected shape"):
        hand.frames(np.zeros((2, len(q) + 1)), [site])
    with pytest.raises(ValueError, match="names: expected a sequence"):
        hand.frames(q, site)
