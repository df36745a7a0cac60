"""One grasp at a time: agreement with the Rust CLI and with the independent reference
optima, every input form, results, errors and pickling."""

import json
import pickle
import subprocess

import numpy as np
import pytest

import grasp_torque as gt
from conftest import ROOT, fixture_files, reference_cases


def cli_solve(cli, path, *flags):
    out = subprocess.run(
        [cli, "solve", str(path), "--format", "json", *flags], capture_output=True, text=True
    )
    return json.loads(out.stdout) if out.stdout else None, out


def rel_close(a, b, rtol):
    return abs(a - b) <= rtol * max(abs(a), abs(b), 1e-300)


def test_import_and_backends():
    assert gt.__version__
    assert "active-set" in gt.backends()
    assert gt.STATUS_CODES[gt.INVALID] == "invalid"


@pytest.mark.parametrize("path", fixture_files(), ids=lambda p: p.name)
def test_bundled_fixtures_match_the_cli(cli, path):
    expected, _ = cli_solve(cli, path)
    r = gt.Solver(path).solve()
    assert r.status == expected["status"]
    assert rel_close(r.objective, expected["objective"], 1e-8)
    np.testing.assert_allclose(
        r.torque, expected["torque"], rtol=0, atol=1e-8 * max(np.abs(expected["torque"]))
    )
    if path.parent.name == "hands":
        assert r.joint_names is not None
    if r.joint_names is not None:
        assert r.joint_names == expected["joint_names"]
    assert r.residuals["wrench"] <= 1e-9 * max(1.0, np.abs(gt.Problem.load(path).wrench).max())
    for check in ("wrench_check", "torque_check", "violation_check", "cone_check"):
        assert 0.0 <= r.diagnostics[check] <= 1.0
    assert sum(r.contact_dims) == len(r.contact_forces)
    assert len(r.forces_per_contact) == len(r.contact_dims)


@pytest.mark.parametrize("case", reference_cases(), ids=lambda c: c["name"])
def test_reference_cases_match_the_cli_and_the_reference(cli, case, tmp_path):
    problem = case["problem"]
    path = tmp_path / "p.json"
    path.write_text(json.dumps(problem))
    expected, _ = cli_solve(cli, path)
    r = gt.Solver(problem).solve()
    assert r.status == expected["status"]
    if r.objective is not None:
        assert rel_close(r.objective, expected["objective"], 1e-8)
    # The independent optimum, in the reference's conventions (Euclidean A⁺, the
    # paper's SFCe latitudes): `shared/reference/README.md`.
    ref = case["reference"]["N8"]
    as_ref = dict(problem, internal_forces="euclidean", linearization={"sfce_spacing": "paper"})
    r = gt.Solver(as_ref).solve()
    if ref["status"] == "optimal":
        assert r.status == "optimal"
        assert rel_close(r.objective, ref["objective"], 1e-8), (r.objective, ref["objective"])
    else:
        assert r.status == "infeasible"


def test_every_form_and_arrays_give_one_problem(root):
    path = root / "fixtures" / "hand3-pcwf.json"
    d = json.loads(path.read_text())
    from_file = gt.Problem.load(path)
    from_dict = gt.Problem.from_dict(d)
    from_arrays = gt.Problem.from_arrays(
        np.array(d["grasp_matrix"]),
        np.array(d["jacobian_transpose"]),
        d["contacts"],
        d["wrench"],
        internal_forces=d["internal_forces"],
    )
    objectives = {gt.Solver(p).solve().objective for p in (from_file, from_dict, from_arrays, str(path), d)}
    assert len(objectives) == 1
    assert from_arrays.joints == 9 and from_arrays.force_dim == 9 and from_arrays.contacts == 3
    np.testing.assert_array_equal(from_arrays.grasp_matrix, np.array(d["grasp_matrix"]))
    # The hand form, from a dict with a base folder for the robot's path.
    hand = json.loads((root / "fixtures" / "hands" / "allegro-pinch.json").read_text())
    p = gt.Problem.from_dict(hand, base=root / "fixtures" / "hands")
    assert p.hand["torque_limits"] == "model"
    assert p.joint_names and len(p.joint_names) == p.joints


def test_solver_options_and_warm_solves(root):
    path = root / "fixtures" / "hand5-mixed.json"
    s = gt.Solver(path, sides=16)
    cold = s.solve(warm=False)
    w = gt.Problem.load(path).wrench * 1.01
    warm = s.solve(w)
    again = gt.Solver(path, sides=16).solve(w, warm=False)
    assert rel_close(warm.objective, again.objective, 1e-9)
    assert cold.objective <= gt.Solver(path, sides=8).solve().objective * (1 + 1e-9)
    # Exact cones: the native solver by default, Clarabel on request; they agree.
    exact = gt.Solver(path, cones="exact").solve()
    assert exact.backend == "active-set" and exact.cones == "exact"
    assert exact.objective <= cold.objective * (1 + 1e-9)
    if "clarabel" in gt.backends():
        other = gt.Solver(path, cones="exact", backend="clarabel").solve()
        assert other.backend == "clarabel"
        assert rel_close(other.objective, exact.objective, 1e-7)


@pytest.mark.parametrize("path", fixture_files(), ids=lambda p: p.name)
def test_lazy_check_defers_forces_until_diagnose(path):
    full, lazy = gt.Solver(path), gt.Solver(path, check="lazy")
    w = gt.Problem.load(path).wrench
    for k in range(4):
        wk = w * (1.01 if k % 2 else 1.0)
        a, b = full.solve(wk), lazy.solve(wk)
        assert a.status == b.status == "optimal"
        assert np.array_equal(a.torque, b.torque) and a.objective == b.objective
        assert b.contact_forces is None and b.residuals is None
        assert b.diagnostics["deferred"] and not a.diagnostics["deferred"]
        c = lazy.diagnose()
        assert c.status == "optimal" and np.array_equal(c.contact_forces, a.contact_forces)
        assert c.diagnostics == a.diagnostics and c.residuals == a.residuals
    # The setting survives pickling; a wrong one names the keyword.
    assert pickle.loads(pickle.dumps(lazy)).solve().diagnostics["deferred"]
    with pytest.raises(ValueError, match="check"):
        gt.Solver(path, check="sometimes")


def test_invalid_input_raises_the_cli_message(cli, root, tmp_path):
    bad = json.loads((root / "fixtures" / "hand3-pcwf.json").read_text())
    bad["contacts"][1]["mu"] = -0.5
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(bad))
    _, out = cli_solve(cli, path)
    assert out.returncode == 2
    with pytest.raises(ValueError) as e:
        gt.Problem.load(path)
    # The CLI prints `error: <path>: <message>`.
    assert out.stderr.strip() == f"error: {e.value}"
    with pytest.raises(ValueError, match="contacts\\[1\\]"):
        gt.Problem.from_dict(bad)
    with pytest.raises(ValueError, match="sides"):
        gt.Solver(root / "fixtures" / "hand3-pcwf.json", sides=2)
    with pytest.raises(ValueError, match="backend"):
        gt.Solver(root / "fixtures" / "hand3-pcwf.json", backend="cplex")
    with pytest.raises(ValueError, match="wrench"):
        gt.Solver(root / "fixtures" / "hand3-pcwf.json").solve([1, 2, 3])
    with pytest.raises(ValueError, match="wrench\\[0\\]"):
        gt.Solver(root / "fixtures" / "hand3-pcwf.json").solve([np.nan, 0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="grasp_matrix\\[0\\]\\[0\\]: expected a finite number, got nan"):
        gt.Problem.from_arrays(np.full((6, 3), np.nan), np.ones((1, 3)), [{"model": "pcwf", "mu": 1}])
    # Each argument named, whatever went wrong with it.
    solver = gt.Solver(root / "fixtures" / "hand3-pcwf.json")
    with pytest.raises(ValueError, match="wrench: expected real numbers, got complex"):
        solver.solve(np.ones(6) * 1j)
    with pytest.raises(ValueError, match="wrench: expected real numbers"):
        solver.solve(["a"] * 6)
    with pytest.raises(ValueError, match="sides: invalid type: floating point `8.5`"):
        gt.Solver(root / "fixtures" / "hand3-pcwf.json", sides=8.5)
    with pytest.raises(ValueError, match="latitudes: invalid type: string"):
        gt.Solver(root / "fixtures" / "hand3-pcwf.json", latitudes="2")
    with pytest.raises(ValueError, match="contacts\\[1\\].mu: invalid type: string \"a\", expected f64$"):
        gt.Problem.from_dict({**bad, "contacts": [{"model": "pcwf", "mu": 1}, {"model": "pcwf", "mu": "a"}, {"model": "pcwf", "mu": 1}]})
    with pytest.raises(ValueError, match="wrench\\[2\\]: expected a finite number, got inf"):
        gt.Problem.from_dict({**bad, "wrench": [0, 0, np.inf, 0, 0, 0]})
    with pytest.raises(ValueError, match="jacobian_transpose: expected real numbers"):
        gt.Problem.from_arrays(np.ones((6, 3)), np.ones((1, 3), dtype=complex), [{"model": "pcwf", "mu": 1}])
    with pytest.raises(ValueError, match="contacts: expected a list of contact dicts"):
        gt.Problem.from_arrays(np.ones((6, 3)), np.ones((1, 3)), {"model": "pcwf", "mu": 1})


def test_infeasible_is_a_result_not_an_exception(root):
    d = json.loads((root / "fixtures" / "hand3-pcwf.json").read_text())
    d["torque_limits"] = [1e-6] * 9
    r = gt.Solver(d).solve()
    assert r.status == "infeasible"
    assert r.torque is None and r.objective is None and r.residuals is None
    assert r.reason and "torque" in r.reason
    assert r.reason_detail["kind"]


def test_problems_solvers_and_results_pickle(root):
    hand = root / "fixtures" / "hands" / "ability-tripod.json"
    for path in (root / "fixtures" / "hand4-sfce.json", hand):
        p = gt.Problem.load(path)
        q = pickle.loads(pickle.dumps(p))
        assert q.to_dict() == p.to_dict()
        assert q.hand == p.hand
        s = gt.Solver(p, sides=12)
        r = s.solve()
        s2 = pickle.loads(pickle.dumps(s))
        r2 = s2.solve()
        assert r2.objective == r.objective
        r3 = pickle.loads(pickle.dumps(r))
        assert r3.to_dict() == r.to_dict()
        np.testing.assert_array_equal(r3.torque, r.torque)
        assert r3.diagnostics == r.diagnostics
        assert "optimal" in repr(r3)


def test_the_readmes_python_block_runs(root, monkeypatch):
    text = (root / "README.md").read_text()
    start = text.index("## Python\n")
    block = text[text.index("```python\n", start) + len("```python\n") :]
    block = block[: block.index("```")]
    monkeypatch.chdir(root)
    scope = {}
    exec(compile(block, "README.md (Python)", "exec"), scope)
    assert scope["r"].status == "optimal" and (scope["out"].status == 0).all()
    assert scope["a"].G.shape == (10_000, 6, 9) and not scope["a"].errors


def test_diagnose_falls_back_where_the_full_check_does():
    # Newton's answer on this grasp passes its certificate and the core's check refuses
    # it; the full check then takes the interior-point fallback's. Under the lazy
    # check, `diagnose` must end at the same answer.
    path = ROOT / "fixtures" / "fuzz" / "cancelled-forces-off-the-cone.json"
    full = gt.Solver(path, cones="exact").solve()
    lazy = gt.Solver(path, cones="exact", check="lazy")
    first = lazy.solve()
    assert full.status == first.status == "optimal"
    c = lazy.diagnose()
    assert c.status == "optimal" and not c.diagnostics["deferred"]
    assert rel_close(c.objective, full.objective, 1e-9)
    if first.diagnostics["deferred"]:
        assert any("fallback" in w for w in c.warnings)


def test_joint_rows_the_model_makes_zero_are_named_like_the_cli(cli):
    # One joint's torque in a unit 5.9e8 times smaller puts two others' rows of Jᵀ
    # within the rank tolerance of its own: the model makes them zero, and the answer
    # says so, as the command line's does. A grasp without an answer names its
    # torques' spread likewise.
    path = ROOT / "fixtures" / "fuzz" / "joint-rows-below-the-rank-tolerance.json"
    expected, _ = cli_solve(cli, path)
    r = gt.Solver(path).solve()
    zeroed = [w for w in r.warnings if "the model makes it zero" in w]
    assert len(zeroed) == 2
    assert zeroed == [w for w in expected["warnings"] if "the model makes it zero" in w]
    assert {w.split(":")[0] for w in zeroed} == {"middle_bottom", "middle_top"}
    path = ROOT / "fixtures" / "fuzz" / "one-joint-in-another-unit.json"
    expected, _ = cli_solve(cli, path, "--cones", "exact")
    r = gt.Solver(path, cones="exact").solve()
    assert r.status == expected["status"]
    spread = [w for w in r.warnings if w.startswith("the torques' scales")]
    assert spread == [w for w in expected["warnings"] if w.startswith("the torques' scales")]
    assert len(spread) == (0 if r.status in ("optimal", "almost_optimal") else 1)
