"""The held object's weight from Python: ``Hand.solve_batch(..., object_mass=)`` and
``Hand.arrays(...).object_wrench`` against the weight written out in numpy
(``F = −m Rᵀ g`` at the centre of mass), and against each grasp's hand-form dict."""

import json

import numpy as np
import pytest

import grasp_torque as gt
from conftest import ROOT

URDF = ROOT / "fixtures/urdf/allegro/allegro_hand_right.urdf"


def rotation(q):
    """The rotation matrix of the unit quaternion [w, x, y, z]."""
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def weight(mass, com, g, quaternion):
    f = -mass * rotation(quaternion).T @ g
    return np.concatenate([f, np.cross(com, f)])


def candidates(B, seed):
    hand = gt.Hand(URDF)
    pinch = json.loads((ROOT / "fixtures/hands/allegro-pinch.json").read_text())
    q = np.array([pinch["hand"]["joint_positions"].get(n, 0.0) for n in hand.joint_names])
    rng = np.random.default_rng(seed)
    Q = q + rng.normal(0, 0.02, (B, q.size))
    # Each grasp's hand turned its own way (gravity in the root frame), the object
    # turned a little about its centre.
    g = rng.normal(size=(B, 3))
    g *= 9.81 / np.linalg.norm(g, axis=1, keepdims=True)
    quats = np.array([1.0, 0, 0, 0]) + rng.normal(0, 0.05, (B, 4))
    quats /= np.linalg.norm(quats, axis=1, keepdims=True)
    pose = np.hstack([np.tile(pinch["object_pose"]["position"], (B, 1)), quats])
    return hand, pinch, Q, g, pose


def test_the_object_weighs_on_every_grasp():
    B, mass, com = 16, 0.25, np.array([0.0, 0.004, -0.003])
    hand, pinch, Q, g, pose = candidates(B, 5)
    contacts = pinch["contacts"]
    a = hand.arrays(Q, contacts, object_pose=pose, gravity=g, object_mass=mass, center_of_mass=com)
    want = np.array([weight(mass, com, g[b], pose[b, 3:]) for b in range(B)])
    scale = mass * 9.81
    np.testing.assert_allclose(a.object_wrench, want, rtol=0, atol=8 * np.finfo(float).eps * scale)
    weighed = hand.solve_batch(
        Q, None, contacts, object_pose=pose, gravity=g, object_mass=mass, center_of_mass=com
    )
    # The same as the weight given as W, and as `W` plus the weight.
    given = hand.solve_batch(Q, a.object_wrench, contacts, object_pose=pose, gravity=g)
    np.testing.assert_array_equal(weighed.status, given.status)
    np.testing.assert_array_equal(weighed.torque, given.torque)
    extra = np.random.default_rng(1).normal(0, 0.1, (B, 6))
    more = hand.solve_batch(
        Q, extra, contacts, object_pose=pose, gravity=g, object_mass=mass, center_of_mass=com
    )
    more_given = hand.solve_batch(Q, extra + a.object_wrench, contacts, object_pose=pose, gravity=g)
    np.testing.assert_array_equal(more.status, more_given.status)
    np.testing.assert_allclose(more.torque, more_given.torque, rtol=1e-12, atol=1e-14)
    assert (weighed.status == 0).sum() >= B // 2
    # And each grasp's hand-form dict with `object`, solved on its own.
    for b in range(B):
        d = json.loads(json.dumps(pinch))
        del d["wrench"]
        d["hand"]["model"] = str(URDF)
        d["hand"]["joint_positions"] = dict(zip(hand.joint_names, Q[b].tolist()))
        d["hand"]["gravity"] = g[b].tolist()
        d["object_pose"] = {"position": pose[b, :3].tolist(), "quaternion": pose[b, 3:].tolist()}
        d["object"] = {"mass": mass, "center_of_mass": com.tolist()}
        r = gt.Solver(gt.Problem.from_dict(d)).solve()
        assert gt.STATUS_CODES[weighed.status[b]] == r.status
        np.testing.assert_array_equal(weighed.torque[b], r.torque)
    # The contact forces carry the weight: G f = W + the weight's wrench.
    forces = hand.solve_batch(
        Q, extra, contacts, object_pose=pose, gravity=g, object_mass=mass,
        center_of_mass=com, contact_forces=True,
    )
    np.testing.assert_array_equal(forces.torque, more.torque)
    for b in np.flatnonzero(forces.status == 0):
        f = forces.contact_forces[b]
        np.testing.assert_allclose(
            a.G[b] @ f, extra[b] + a.object_wrench[b], rtol=0, atol=1e-9 * np.abs(f).max()
        )
    # Without object_mass, no object_wrench.
    assert hand.arrays(Q, contacts, object_pose=pose, gravity=g).object_wrench is None


def test_bad_object_arguments_are_named():
    hand, pinch, Q, g, pose = candidates(4, 2)
    contacts = pinch["contacts"]
    with pytest.raises(ValueError, match="object.mass.*hand.gravity"):
        hand.solve_batch(Q, None, contacts, object_mass=0.1)
    with pytest.raises(ValueError, match="W: expected .*None only with object_mass"):
        hand.solve_batch(Q, None, contacts, gravity=g)
    with pytest.raises(ValueError, match="center_of_mass: given without object_mass"):
        hand.arrays(Q, contacts, center_of_mass=[0, 0, 0])
    with pytest.raises(ValueError, match="object_mass: expected one number"):
        hand.arrays(Q, contacts, gravity=g, object_mass=[0.1, 0.2])
    with pytest.raises(ValueError, match="center_of_mass: expected"):
        hand.arrays(Q, contacts, gravity=g, object_mass=0.1, center_of_mass=[0, 0])
    with pytest.raises(ValueError, match="object.mass"):
        hand.arrays(Q, contacts, gravity=g, object_mass=-1.0)
    # An object pose that is not a unit quaternion is that grasp's error, and its
    # object_wrench is NaN.
    pose[2, 3:] = [2.0, 0, 0, 0]
    a = hand.arrays(Q, contacts, object_pose=pose, gravity=g, object_mass=0.1)
    assert set(a.errors) == {2} and "quaternion" in a.errors[2]
    assert np.isnan(a.object_wrench[2]).all() and np.isfinite(a.object_wrench[[0, 1, 3]]).all()


def test_object_forces_carry_the_weight():
    path = ROOT / "fixtures/hands/allegro-weighed.json"
    weight = np.array(gt.Problem.load(path).hand["object_weight"])
    for cones in ("linear", "exact"):
        r = gt.Solver(path, cones=cones).solve()
        F = r.object_forces
        assert F.shape == (3, 3)
        # Each contact's force in the object frame: together, the weight's reaction.
        np.testing.assert_allclose(F.sum(axis=0), weight[:3], rtol=0, atol=1e-12)
        # And the components in each contact's frame have the same length.
        for f, c in zip(F, r.forces_per_contact):
            assert abs(np.linalg.norm(f) - np.linalg.norm(c)) <= 1e-12
        # Pickled and back.
        import pickle

        np.testing.assert_array_equal(pickle.loads(pickle.dumps(r)).object_forces, F)
    # The lazy check defers them with the other forces.
    s = gt.Solver(path, check="lazy")
    assert s.solve().object_forces is None
    np.testing.assert_allclose(s.diagnose().object_forces.sum(axis=0), weight[:3], atol=1e-12)
