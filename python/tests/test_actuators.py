"""Actuator space (τ = T u) from Python: an MJCF hand, a transmission in the matrix
form, and batches with a shared transmission."""

import numpy as np
import pytest

import grasp_torque as gt

from conftest import ROOT
from test_solver import cli_solve


def test_shadow_tripod_solves_in_actuator_space_like_the_cli(cli):
    path = ROOT / "fixtures" / "hands" / "shadow-tripod.json"
    expected, _ = cli_solve(cli, path)
    r = gt.Solver(path).solve()
    assert r.status == "optimal"
    assert r.actuator_names == expected["actuator_names"]
    assert r.joint_names == expected["joint_names"]
    assert len(r.torque) == 13 and len(r.joint_torque) == 15
    np.testing.assert_allclose(r.joint_torque, expected["joint_torque"], rtol=0, atol=1e-12)
    k = r.joint_names.index("robot0:FFJ0")
    assert abs(r.joint_torque[k]) <= 1e-7 * np.abs(r.joint_torque).max()
    assert gt.Problem.load(path).hand["actuator_limits"][0]["source"] == "forcerange"


CONTACTS = [{"model": "pcwf", "mu": 0.8}] * 3


def _grasps(B, seed=3):
    G, JT, W = gt.synthetic_grasps(B, seed=seed)
    return G, JT, W, CONTACTS


def test_batch_with_a_transmission_matches_one_by_one():
    G, JT, W, contacts = _grasps(40)
    m = JT.shape[1]
    rng = np.random.default_rng(0)
    # An underactuated tendon hand: the last two joints share one actuator.
    T = np.eye(m)[:, : m - 1].copy()
    T[m - 1, m - 2] = 0.7
    T *= rng.uniform(0.5, 2.0, size=m - 1)
    names = [f"a{j}" for j in range(m - 1)]
    b = gt.solve_batch(G, JT, W, contacts, transmission=T, actuator_names=names, threads=2)
    assert b.torque.shape == (40, m - 1)
    for i in range(40):
        p = gt.Problem.from_arrays(G[i], JT[i], contacts, W[i], transmission=T, actuator_names=names)
        r = gt.Solver(p).solve()
        assert gt.STATUS_CODES[b.status[i]] == r.status
        if r.status == "optimal":
            np.testing.assert_allclose(b.torque[i], r.torque, rtol=0, atol=1e-9 * np.abs(r.torque).max())
            assert r.actuator_names == names
            np.testing.assert_allclose(T @ r.torque, r.joint_torque, rtol=0, atol=1e-12)


def test_identity_transmission_changes_nothing():
    G, JT, W, contacts = _grasps(10, seed=5)
    m = JT.shape[1]
    a = gt.solve_batch(G, JT, W, contacts, threads=1)
    b = gt.solve_batch(G, JT, W, contacts, transmission=np.eye(m), threads=1)
    np.testing.assert_array_equal(a.torque, b.torque)
    np.testing.assert_array_equal(a.status, b.status)


def test_per_grasp_transmissions_match_one_by_one():
    G, JT, W, contacts = _grasps(20, seed=9)
    B, m = JT.shape[:2]
    rng = np.random.default_rng(1)
    # A spatial tendon's moment arms change with the configuration: one T per grasp.
    T = np.repeat(np.eye(m)[None, :, : m - 1], B, axis=0)
    T[:, m - 1, m - 2] = rng.uniform(0.3, 1.0, B)
    b = gt.solve_batch(G, JT, W, contacts, transmission=T, threads=2)
    assert b.torque.shape == (B, m - 1)
    for i in range(B):
        r = gt.Solver(gt.Problem.from_arrays(G[i], JT[i], contacts, W[i], transmission=T[i])).solve()
        assert gt.STATUS_CODES[b.status[i]] == r.status
        if r.status == "optimal":
            np.testing.assert_array_equal(b.torque[i], r.torque)
    T[3, 0, 0] = np.nan
    bad = gt.solve_batch(G, JT, W, contacts, transmission=T)
    assert set(bad.errors) == {3} and "transmission" in bad.errors[3]
    for shape in ((B + 1, m, m - 1), (m + 1, m - 1), (B, m)):
        with pytest.raises(ValueError, match="transmission: expected shape"):
            gt.solve_batch(G, JT, W, contacts, transmission=np.ones(shape))
