"""Passive joint torques (springs, the fingers' weight) from Python: the batch's
``passive_torque`` against one-by-one solves and the statics, and a spring hand's
``Hand.arrays`` solved as ``Hand.solve_batch`` solves it."""

import json

import numpy as np
import pytest

import grasp_torque as gt
from conftest import ROOT

CONTACTS = [{"model": "pcwf", "mu": 0.8}] * 3


@pytest.mark.parametrize("shared", [True, False])
def test_batch_passive_torques_match_one_by_one_and_the_statics(shared):
    G, JT, W = gt.synthetic_grasps(40, seed=11)
    B, m = JT.shape[0], JT.shape[1]
    rng = np.random.default_rng(2)
    # Springs of about the torques the wrench asks for (a tenth of the weight on a
    # 5 cm lever), per grasp or one set for all.
    scale = 0.1 * np.abs(W[:, 2:3]) * 0.05
    TP = rng.normal(0, 1, (m,)) * scale.mean() if shared else rng.normal(0, 1, (B, m)) * scale
    b = gt.solve_batch(G, JT, W, CONTACTS, passive_torque=TP, threads=2)
    none = gt.solve_batch(G, JT, W, CONTACTS, threads=2)
    held = 0
    for i in range(B):
        tp = TP if shared else TP[i]
        p = gt.Problem.from_arrays(G[i], JT[i], CONTACTS, W[i], passive_torque=tp)
        assert p.to_dict()["passive_torque"] == list(tp)
        r = gt.Solver(p).solve()
        assert gt.STATUS_CODES[b.status[i]] == r.status
        if r.status != "optimal":
            continue
        held += 1
        f = r.contact_forces
        u = r.torque
        # The user's equations, not the solver's shifted ones: G f = w and Jᵀ f = u + τ_p.
        size = np.abs(JT[i]).sum(axis=1).max() * np.abs(f).max() + np.abs(tp).max()
        np.testing.assert_allclose(JT[i] @ f, u + tp, rtol=0, atol=1e-9 * size)
        np.testing.assert_allclose(G[i] @ f, W[i], rtol=0, atol=1e-9 * np.abs(f).max() * 2)
        np.testing.assert_allclose(b.torque[i], u, rtol=0, atol=1e-9 * np.abs(u).max())
        # Springs change the answer: a batch without them solves another problem.
        assert none.status[i] != b.status[i] or not np.allclose(none.torque[i], u)
    assert held >= B // 2


def test_zero_passive_torques_change_nothing():
    G, JT, W = gt.synthetic_grasps(12, seed=4)
    a = gt.solve_batch(G, JT, W, CONTACTS, threads=1)
    z = gt.solve_batch(G, JT, W, CONTACTS, passive_torque=np.zeros(JT.shape[1]), threads=1)
    np.testing.assert_array_equal(a.torque, z.torque)
    np.testing.assert_array_equal(a.status, z.status)


def test_bad_passive_torques_are_named():
    G, JT, W = gt.synthetic_grasps(5, seed=1)
    m = JT.shape[1]
    for bad in (np.zeros(m + 1), np.zeros((4, m)), np.zeros((5, m, 1)), 1.0):
        with pytest.raises(ValueError, match="passive_torque: expected shape"):
            gt.solve_batch(G, JT, W, CONTACTS, passive_torque=bad)
    with pytest.raises(ValueError, match="passive_torque: expected real numbers"):
        gt.solve_batch(G, JT, W, CONTACTS, passive_torque=["a"] * m)
    TP = np.zeros((5, m))
    TP[3, 2] = np.nan
    out = gt.solve_batch(G, JT, W, CONTACTS, passive_torque=TP)
    assert set(out.errors) == {3} and "passive_torque[2]" in out.errors[3]
    assert out.status[3] == gt.INVALID and np.isnan(out.torque[3]).all()


def test_a_spring_hands_arrays_solve_as_its_batch():
    oracle = json.loads((ROOT / "fixtures/mjcf/oracle/menagerie-aero.json").read_text())
    hand = gt.Hand(ROOT / "fixtures/mjcf/menagerie/aero_right.xml")
    cases = oracle["cases"]
    # Case 7 is one of the oracle's grasps the Aero hand holds.
    d = cases[7]["problem"]
    pose = np.array(d["object_pose"]["position"] + d["object_pose"]["quaternion"])
    joints = lambda c: [c["problem"]["hand"]["joint_positions"].get(n, 0.0) for n in hand.joint_names]
    # The springs at the oracle's configurations, against MuJoCo's qfrc_spring.
    q = np.array([joints(c) for c in cases])
    a = hand.arrays(q, d["contacts"], object_pose=pose)
    assert a.errors == {}
    for i, c in enumerate(cases):
        want = np.array([c["passive_torque"][n] for n in a.joint_names])
        np.testing.assert_allclose(a.passive_torque[i], want, rtol=0, atol=1e-12 * np.abs(want).max())
    assert np.abs(a.passive_torque).max() > 0.01
    # Near case 7: the arrays with their springs solve as the hand's batch does.
    B = 30
    q = np.array(joints(cases[7])) + np.random.default_rng(5).normal(0, 0.01, (B, len(hand.joint_names)))
    a = hand.arrays(q, d["contacts"], object_pose=pose)
    W = np.tile(d["wrench"], (B, 1))
    models = [{k: c[k] for k in ("model", "mu", "mu_torsion") if k in c} for c in d["contacts"]]
    direct = hand.solve_batch(q, W, d["contacts"], object_pose=pose)
    via = gt.solve_batch(
        a.G, a.JT, W, models, transmission=a.transmission, passive_torque=a.passive_torque
    )
    np.testing.assert_array_equal(via.status, direct.status)
    np.testing.assert_array_equal(via.objective, direct.objective)
    np.testing.assert_array_equal(via.torque, direct.torque)
    held = direct.status == 0
    assert held.sum() >= B // 3
    # Without the springs the same arrays are another problem.
    without = gt.solve_batch(a.G, a.JT, W, models, transmission=a.transmission)
    assert not np.allclose(without.objective[held], direct.objective[held])


def test_a_hands_weight_is_pinocchios_and_solves_as_passive_torques():
    oracle = json.loads((ROOT / "fixtures/urdf/oracle/allegro.json").read_text())
    hand = gt.Hand(ROOT / "fixtures/urdf/allegro/allegro_hand_right.urdf")
    pinch = json.loads((ROOT / "fixtures/hands/allegro-pinch.json").read_text())
    contacts = pinch["contacts"]
    for case in oracle["cases"][:10]:
        q = np.array([case["problem"]["hand"]["joint_positions"].get(n, 0.0) for n in hand.joint_names])
        a = hand.arrays(q[None], contacts, gravity=case["gravity"])
        want = np.array([case["gravity_torque"][n] for n in a.joint_names])
        scale = max(abs(v) for v in case["gravity_torque"].values())
        np.testing.assert_allclose(a.passive_torque[0], want, rtol=0, atol=1e-12 * scale)
    # The pinch with the fingers' weight (gravity is +x in its root frame), against the
    # arrays solved with it, and against weightless fingers.
    q = np.array([pinch["hand"]["joint_positions"].get(n, 0.0) for n in hand.joint_names])
    Q = q + np.random.default_rng(2).normal(0, 0.02, (40, q.size))
    pose = pinch["object_pose"]["position"] + pinch["object_pose"]["quaternion"]
    W = np.tile(pinch["wrench"], (len(Q), 1))
    g = [9.81, 0.0, 0.0]
    heavy = hand.solve_batch(Q, W, contacts, object_pose=pose, gravity=g, torque_limits="model")
    light = hand.solve_batch(Q, W, contacts, object_pose=pose, torque_limits="model")
    a = hand.arrays(Q, contacts, object_pose=pose, gravity=g)
    models = [{"model": c["model"], "mu": c["mu"]} for c in contacts]
    limits = gt.Problem.load(ROOT / "fixtures/hands/allegro-pinch.json").to_dict()["torque_limits"]
    via = gt.solve_batch(a.G, a.JT, W, models, passive_torque=a.passive_torque, torque_limits=limits)
    np.testing.assert_array_equal(via.torque, heavy.torque)
    held = (heavy.status == 0) & (light.status == 0)
    assert held.sum() >= 30
    assert np.abs(heavy.torque[held] - light.torque[held]).max() > 1e-3 * np.abs(light.torque).max()
    with pytest.raises(ValueError, match="hand.gravity.*a URDF has none"):
        hand.arrays(Q, contacts, gravity="model")
    with pytest.raises(ValueError, match="gravity: expected"):
        hand.arrays(Q, contacts, gravity=[0, 0])


def test_a_hand_form_problem_shows_its_passive_torques():
    d = json.loads((ROOT / "fixtures/hands/aero-pinch.json").read_text())
    p = gt.Problem.load(ROOT / "fixtures/hands/aero-pinch.json")
    assert p.passive_torque is not None and np.abs(p.passive_torque).max() > 0.1
    np.testing.assert_array_equal(p.passive_torque, p.to_dict()["passive_torque"])
    r = gt.Solver(p).solve()
    f = r.contact_forces
    T = np.array(p.to_dict()["transmission"])
    np.testing.assert_allclose(p.jacobian_transpose @ f, T @ r.torque + p.passive_torque, rtol=0, atol=1e-12)
    assert gt.Problem.load(ROOT / "fixtures/hand3-pcwf.json").passive_torque is None
    assert d["hand"]["model"].endswith("aero_right.xml")


def test_gravity_per_grasp_is_each_grasps_hand_form():
    hand = gt.Hand(ROOT / "fixtures/urdf/allegro/allegro_hand_right.urdf")
    pinch = json.loads((ROOT / "fixtures/hands/allegro-pinch.json").read_text())
    q = np.array([pinch["hand"]["joint_positions"].get(n, 0.0) for n in hand.joint_names])
    rng = np.random.default_rng(4)
    B = 12
    Q = q + rng.normal(0, 0.02, (B, q.size))
    # The hand turned a different way for each grasp: gravity in its root frame.
    g = rng.normal(size=(B, 3))
    g *= 9.81 / np.linalg.norm(g, axis=1, keepdims=True)
    pose = pinch["object_pose"]["position"] + pinch["object_pose"]["quaternion"]
    W = np.tile(pinch["wrench"], (B, 1))
    out = hand.solve_batch(Q, W, pinch["contacts"], object_pose=pose, gravity=g, torque_limits="model")
    a = hand.arrays(Q, pinch["contacts"], object_pose=pose, gravity=g)
    for b in range(B):
        d = json.loads(json.dumps(pinch))
        d["hand"]["model"] = str(ROOT / "fixtures/urdf/allegro/allegro_hand_right.urdf")
        d["hand"]["joint_positions"] = dict(zip(hand.joint_names, Q[b].tolist()))
        d["hand"]["gravity"] = g[b].tolist()
        p = gt.Problem.from_dict(d)
        np.testing.assert_array_equal(a.passive_torque[b], p.passive_torque)
        r = gt.Solver(p).solve()
        assert gt.STATUS_CODES[out.status[b]] == r.status
        np.testing.assert_array_equal(out.torque[b], r.torque)
    # One bad row is that grasp's error; a wrong shape is the batch's.
    g[3, 1] = np.inf
    bad = hand.solve_batch(Q, W, pinch["contacts"], object_pose=pose, gravity=g)
    assert set(bad.errors) == {3} and "gravity" in bad.errors[3]
    with pytest.raises(ValueError, match=r"gravity: expected .*\(12, 3\)"):
        hand.solve_batch(Q, W, pinch["contacts"], gravity=g[:5])
