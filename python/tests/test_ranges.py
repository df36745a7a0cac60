"""Torque limits that are not symmetric, ``[lower, upper]`` per joint (either side
``None``, or ``-inf``/``inf`` from numpy): batches equal one-by-one solves, and every
answer holds its range."""

import numpy as np
import pytest

import grasp_torque as gt

PCWF = [{"model": "pcwf", "mu": 0.7}] * 3


def test_ranges_in_a_batch_are_held_and_match_one_by_one():
    G, JT, W = gt.synthetic_grasps(40, seed=5)
    m = JT.shape[1]
    free = gt.solve_batch(G, JT, W, PCWF)
    s = np.abs(free.torque).max()
    # Joint 0 pushes one way only, joint 1 has a floor above 0 (no answer at τ = 0),
    # joint 2 a ceiling only; the rest are free.
    ranges = np.full((m, 2), [-np.inf, np.inf])
    ranges[0] = [0.0, 2 * s]
    ranges[1] = [0.05 * s, np.inf]
    ranges[2] = [-np.inf, 0.1 * s]
    out = gt.solve_batch(G, JT, W, PCWF, torque_limits=ranges)
    held = out.status == 0
    assert held.sum() >= 5 and (~held).sum() >= 1, out.status
    t = out.torque[held]
    scale = np.abs(t).max(axis=1)
    assert (t[:, 0] >= -1e-9 * scale).all()
    assert (t[:, 1] >= 0.05 * s - 1e-9 * scale).all()
    assert (t[:, 2] <= 0.1 * s + 1e-9 * scale).all()
    limits = [[0.0, 2 * s], [0.05 * s, None], [None, 0.1 * s]] + [[None, None]] * (m - 3)
    for b in range(len(G)):
        p = gt.Problem.from_arrays(G[b], JT[b], PCWF, W[b], torque_limits=ranges)
        assert p.to_dict()["torque_limits"] == limits
        r = gt.Solver(p).solve()
        assert gt.STATUS_CODES[out.status[b]] == r.status
        if r.status == "optimal":
            assert np.array_equal(out.torque[b], r.torque)


def test_a_range_that_is_not_one_is_named():
    G, JT, W = gt.synthetic_grasps(2, seed=5)
    m = JT.shape[1]
    with pytest.raises(ValueError, match=r"torque_limits\[0\]: expected \[lower, upper\] with lower < upper"):
        gt.solve_batch(G, JT, W, PCWF, torque_limits=[[1.0, 0.0]] + [None] * (m - 1))
    with pytest.raises(ValueError, match=r"torque_limits\[1\]\[0\]: expected a finite number, got inf"):
        gt.solve_batch(G, JT, W, PCWF, torque_limits=[None, [np.inf, 1.0]] + [None] * (m - 2))
