"""Static types. The package ships `py.typed` and a stub of its extension
(`grasp_torque/_native.pyi`): mypy checks the stub against the built module
(stubtest) and `uses` below under `--strict`, and `uses` also runs, so that the types
the annotations promise are the types the calls return."""

import pathlib
import subprocess
import sys

import numpy as np
import pytest
from numpy.typing import NDArray

import grasp_torque as gt

if sys.version_info >= (3, 11):
    from typing import assert_type
else:  # mypy checks them; at run time they pass through.

    def assert_type(value: object, typ: object) -> object:
        return value


FloatArray = NDArray[np.float64]


def uses(root: pathlib.Path) -> None:
    """The public API as a controller and a planner call it, with the types a type
    checker infers."""
    problem = gt.Problem.load(root / "fixtures" / "paper-example.json")
    assert_type(problem.joints, int)
    assert_type(problem.grasp_matrix, FloatArray)
    solver = gt.Solver(problem, sides=8)
    r = solver.solve([-1.0, -1.0, 0.0, 0.0, 0.0, 0.5])
    assert_type(r, gt.Result)
    assert_type(r.status, str)
    assert_type(r.objective, "float | None")
    assert r.torque is not None and r.objective is not None and r.residuals is not None
    assert_type(r.torque, FloatArray)
    assert r.torque.dtype == np.float64 and r.torque.shape == (problem.joints,)
    assert isinstance(r.objective, float) and isinstance(r.residuals["wrench"], float)

    G, JT, W = gt.synthetic_grasps(16, wrenches=2, seed=3)
    out = gt.solve_batch(G, JT, W, [{"model": "pcwf", "mu": 0.5}] * 3, torque_limits=[5.0] * 9)
    assert_type(out, gt.BatchResult)
    assert_type(out.status, NDArray[np.int8])
    assert_type(out.contact_forces, "FloatArray | None")
    assert out.status.dtype == np.int8 and out.torque.shape == (16, 2, 9)
    for key, message in out.errors.items():
        assert_type(message, str)

    hand = gt.Hand(root / "fixtures" / "mjcf" / "menagerie" / "aero_right.xml")
    assert_type(hand.joint_names, "list[str]")
    q = np.zeros((2, len(hand.joint_names)))
    P, R = hand.frames(q, ["th_tip"])
    assert_type(P, FloatArray)
    assert P.shape == (2, 1, 3) and R.shape == (2, 1, 3, 3)
    a = hand.arrays(q, [{"site": "th_tip", "model": "pcwf", "mu": 1.0}])
    assert_type(a, gt.HandArrays)
    assert_type(a.transmission, "FloatArray | None")
    assert_type(a.errors, "dict[int, str]")
    assert a.G.shape[:2] == (2, 6) and a.torque_limits.shape[1] == 2


def test_the_annotated_calls_return_what_they_say(root: pathlib.Path) -> None:
    uses(root)


def _mypy(cwd: pathlib.Path, *args: str) -> None:
    """`python -m ARGS` in `cwd` (a scratch folder: mypy writes its cache there, and
    the package is the installed one, not a source tree on the path)."""
    pytest.importorskip("mypy", reason="pip install mypy (the README's test command does)")
    run = subprocess.run([sys.executable, "-m", *args], capture_output=True, text=True, cwd=cwd)
    assert run.returncode == 0, run.stdout + run.stderr


def test_the_calls_type_check_under_strict(tmp_path: pathlib.Path) -> None:
    _mypy(tmp_path, "mypy", "--strict", str(pathlib.Path(__file__)))


def test_the_extension_stub_matches_the_built_module(tmp_path: pathlib.Path) -> None:
    _mypy(tmp_path, "mypy.stubtest", "grasp_torque._native")
