"""A planner's candidates on the bundled hands against an SOCP in the forces and
actuator forces themselves (tests/data/hand-batch-oracle.json, written by
scripts/oracle_hand_batches.py with cvxpy and Clarabel): the status of every
candidate, and σ on the exact cones, from `Hand.solve_batch` as a planner calls it."""

import json

import numpy as np

import grasp_torque as gt
from conftest import ROOT

ORACLE = json.loads((ROOT / "tests" / "data" / "hand-batch-oracle.json").read_text())
# The oracle's optima are within its gap (1e-10 of its terms, with σ* scaled to 1),
# the native answers within their certificate's (1e-9 of its terms, which are a few
# times σ): 1e-8 holds both with room for the terms' sizes.
SIGMA_TOL = 1e-8


def test_hand_batches_match_a_direct_socp():
    compared = infeasible = 0
    for h in ORACLE["hands"]:
        d = json.loads((ROOT / "fixtures" / "hands" / h["fixture"]).read_text())
        hand = gt.Hand(ROOT / "fixtures" / "hands" / d["hand"]["model"])
        cases = h["cases"]
        kw = {} if h["gravity"] is None else {"gravity": h["gravity"]}
        out = hand.solve_batch(
            np.array([c["joint_positions"] for c in cases]),
            np.array([c["wrench"] for c in cases]),
            d["contacts"],
            positions=np.array([c["positions"] for c in cases]),
            normals=np.array([c["normals"] for c in cases]),
            object_pose=np.array(h["object_pose"]),
            cones="exact",
            **kw,
        )
        assert out.errors == {}, h["fixture"]
        for b, c in enumerate(cases):
            status = gt.STATUS_CODES[int(out.status[b])]
            assert status == c["status"], (h["fixture"], b, status, c["status"])
            if status == "optimal":
                rel = abs(out.objective[b] - c["objective"]) / c["objective"]
                assert rel <= SIGMA_TOL, (h["fixture"], b, out.objective[b], c["objective"])
                compared += 1
            else:
                infeasible += 1
    assert compared >= 150 and infeasible >= 10, (compared, infeasible)
