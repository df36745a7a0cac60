"""solve_batch: the same answers as one-by-one solves, status codes, preallocated
outputs, the GIL released, and distribution (fork, process pools, Ray)."""

import concurrent.futures
import multiprocessing
import os
import pickle
import subprocess
import sys
import threading
import time
import warnings

import numpy as np
import pytest

import grasp_torque as gt

PCWF = [{"model": "pcwf", "mu": 0.7}] * 3


def one_by_one(G, JT, W, contacts, **kw):
    """Fresh solver per item, cold."""
    out = []
    for b in range(G.shape[0]):
        p = gt.Problem.from_arrays(G[b], JT[b], contacts, W[b] if W.ndim == 2 else W[b, 0])
        s = gt.Solver(p, **kw)
        ws = [W[b]] if W.ndim == 2 else list(W[b])
        out.append([s.solve(w, warm=False) for w in ws])
    return out


@pytest.mark.parametrize("wrenches", [0, 4])
def test_batch_matches_one_by_one(wrenches):
    G, JT, W = gt.synthetic_grasps(120, wrenches=wrenches, seed=3)
    out = gt.solve_batch(G, JT, W, PCWF, threads=2)
    alone = one_by_one(G, JT, W, PCWF)
    K = 1 if W.ndim == 2 else W.shape[1]
    status = out.status.reshape(-1, K)
    objective = out.objective.reshape(-1, K)
    torque = out.torque.reshape(-1, K, JT.shape[1])
    optimal = 0
    for b, rs in enumerate(alone):
        for k, r in enumerate(rs):
            assert gt.STATUS_CODES[int(status[b, k])] == r.status
            if r.objective is not None:
                optimal += 1
                assert abs(objective[b, k] - r.objective) <= 1e-9 * max(r.objective, 1e-300)
                np.testing.assert_allclose(torque[b, k], r.torque, rtol=0, atol=1e-9 * np.abs(r.torque).max())
            else:
                assert np.isnan(objective[b, k]) and np.isnan(torque[b, k]).all()
    assert optimal > len(alone) * K // 2


@pytest.mark.parametrize("wrenches", [0, 3])
def test_contact_forces_on_request(wrenches):
    G, JT, W = gt.synthetic_grasps(60, wrenches=wrenches, seed=8)
    W[5] = np.nan  # an invalid item: its forces are NaN
    out = gt.solve_batch(G, JT, W, PCWF, threads=2, contact_forces=True)
    assert gt.solve_batch(G, JT, W, PCWF, threads=2).contact_forces is None
    B, n = G.shape[0], G.shape[2]
    K = 1 if W.ndim == 2 else W.shape[1]
    F = out.contact_forces.reshape(B, K, n)
    Ws, T = W.reshape(B, K, 6), out.torque.reshape(B, K, -1)
    status = out.status.reshape(B, K)
    held = 0
    for b in range(B):
        for k in range(K):
            if status[b, k] != 0:
                assert np.isnan(F[b, k]).all()
                continue
            held += 1
            f = F[b, k]
            # The statics of the answer: G f = w, Jᵀ f = τ.
            scale = np.abs(f).max()
            np.testing.assert_allclose(G[b] @ f, Ws[b, k], rtol=0, atol=1e-9 * scale)
            np.testing.assert_allclose(JT[b] @ f, T[b, k], rtol=0, atol=1e-9 * scale * np.abs(JT[b]).max())
    assert held > B // 2
    # One wrench per grasp: the forces of a one-by-one solve, bit for bit.
    if K == 1:
        for b in (0, 1, 2):
            r = gt.Solver(gt.Problem.from_arrays(G[b], JT[b], PCWF, W[b])).solve()
            if r.status == "optimal":
                np.testing.assert_array_equal(F[b, 0], r.contact_forces)
    # Preallocated, filled in place; a wrong shape is named.
    F2 = np.empty(out.contact_forces.shape)
    again = gt.solve_batch(G, JT, W, PCWF, threads=1, contact_forces=F2)
    assert again.contact_forces is F2
    with pytest.raises(ValueError, match="contact_forces: expected .*shape"):
        gt.solve_batch(G, JT, W, PCWF, contact_forces=np.empty((B, n + 1)))


def test_soft_fingers_and_options_match_one_by_one():
    G, JT, W = gt.synthetic_grasps(40, fingers=4, seed=5)
    # Soft fingers: four columns per contact, the fourth the torsional moment.
    n = 4 * 4
    G4 = np.zeros((40, 6, n))
    JT4 = np.zeros((40, JT.shape[1], n))
    for c in range(4):
        G4[:, :, 4 * c : 4 * c + 3] = G[:, :, 3 * c : 3 * c + 3]
        G4[:, 3:, 4 * c + 3] = G[:, :3, 3 * c + 2]  # mz about the normal
        JT4[:, :, 4 * c : 4 * c + 3] = JT[:, :, 3 * c : 3 * c + 3]
    contacts = [{"model": "sfcl", "mu": 0.6, "mu_torsion": 0.01}, {"model": "sfce", "mu": 0.6, "mu_torsion": 0.01}] * 2
    kw = dict(sides=12, torque_limits=[5.0] * JT.shape[1], min_normal_force=0.05)
    out = gt.solve_batch(G4, JT4, W, contacts, **kw)
    for b in range(40):
        p = gt.Problem.from_arrays(
            G4[b], JT4[b], contacts, W[b], torque_limits=kw["torque_limits"], min_normal_force=0.05
        )
        r = gt.Solver(p, sides=12).solve()
        assert gt.STATUS_CODES[int(out.status[b])] == r.status
        if r.objective is not None:
            assert abs(out.objective[b] - r.objective) <= 1e-9 * r.objective


def test_status_codes_for_infeasible_and_invalid_items():
    G, JT, W = gt.synthetic_grasps(6, seed=1)
    G[2, 1, 4] = np.nan  # invalid: its grasp matrix
    W[4] *= 1e6  # infeasible: beyond the torque limits
    out = gt.solve_batch(G, JT, W, PCWF, torque_limits=[10.0] * JT.shape[1])
    assert out.status.dtype == np.int8
    assert out.status[2] == gt.INVALID and out.status[4] == 2
    assert [int(s) for i, s in enumerate(out.status) if i not in (2, 4)] == [0] * 4
    assert set(out.errors) == {2} and "grasp_matrix" in out.errors[2]
    assert np.isnan(out.torque[2]).all() and np.isnan(out.objective[4])
    # A bad wrench among several fails only itself; beyond 1e12 is as bad as NaN.
    G2, JT2, W2 = gt.synthetic_grasps(2, wrenches=3, seed=1)
    W2[0, 1, 0] = 1e300
    W2[1, 0, 5] = np.nan
    out2 = gt.solve_batch(G2, JT2, W2, PCWF)
    assert out2.status.tolist() == [[0, 5, 0], [5, 0, 0]]
    assert "at most 1e12" in out2.errors[(0, 1)] and "wrench[5]" in out2.errors[(1, 0)]
    assert np.isfinite(out2.objective[out2.status == 0]).all()
    # Whole-batch errors raise, naming the argument.
    with pytest.raises(ValueError, match="JT"):
        gt.solve_batch(G, JT[:, :, :5], W, PCWF)
    with pytest.raises(ValueError, match="W"):
        gt.solve_batch(G, JT, W[:, :5], PCWF)
    with pytest.raises(ValueError, match="contacts\\[0\\]"):
        gt.solve_batch(G, JT, W, [{"model": "pcwf", "mu": -1}] * 3)
    with pytest.raises(ValueError, match="threads"):
        gt.solve_batch(G, JT, W, PCWF, threads=0)
    with pytest.raises(ValueError, match="at most 1024"):
        gt.solve_batch(G, JT, W, PCWF, threads=10**6)


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda a: {**a, "G": a["G"].astype(complex)}, "G: expected real numbers, got complex"),
        (lambda a: {**a, "W": a["W"].astype(str)}, "W: expected real numbers"),
        (lambda a: {**a, "JT": [[1.0, 2.0], [3.0]]}, "JT: expected a rectangular array"),
        (lambda a: {**a, "contacts": PCWF[0]}, "contacts: expected a list of contact dicts"),
        (lambda a: {**a, "contacts": None}, "contacts: expected a list"),
        (lambda a: {**a, "contacts": PCWF[:2]}, "contacts: expected models whose force components"),
        (lambda a: {**a, "contacts": [{"model": "pcwf", "mu": np.nan}] * 3}, "contacts\\[0\\].mu: expected a finite number, got nan"),
        (lambda a: {**a, "contacts": [{"model": "pcwf", "mu": "a"}] * 3}, "contacts\\[0\\].mu: invalid type"),
        (lambda a: {**a, "torque_weights": [1.0] * 8}, "torque_weights: expected one value per joint"),
        (lambda a: {**a, "torque_weights": [1.0] * 8 + [np.inf]}, "torque_weights\\[8\\]: expected a finite number, got inf"),
        (lambda a: {**a, "transmission": np.full((9, 2), np.nan)}, "transmission\\[0\\]\\[0\\]: expected a finite number"),
        (lambda a: {**a, "threads": -1}, "threads: expected at least 1, got -1"),
        (lambda a: {**a, "threads": 2.5}, "threads: expected a whole number, got 2.5"),
        (lambda a: {**a, "sides": 8.5}, "sides: invalid type: floating point `8.5`"),
    ],
)
def test_bad_arguments_raise_naming_the_argument(change, message):
    """An argument every grasp shares, when wrong, is one error naming it (not B
    invalid items, a numpy warning or a JSON parse error), before anything is solved."""
    G, JT, W = gt.synthetic_grasps(3, seed=2)
    args = change({"G": G, "JT": JT, "W": W, "contacts": PCWF})
    G, JT, W, contacts = (args.pop(k) for k in ("G", "JT", "W", "contacts"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning on the way to the error
        with pytest.raises(ValueError, match=message):
            gt.solve_batch(G, JT, W, contacts, **args)


def test_inf_is_no_torque_limit():
    """numpy's ``inf`` means what the files' ``null`` does: that joint is unlimited."""
    G, JT, W = gt.synthetic_grasps(4, seed=3)
    m = JT.shape[1]
    free = gt.solve_batch(G, JT, W, PCWF)
    limits = np.full(m, np.inf)
    same = gt.solve_batch(G, JT, W, PCWF, torque_limits=limits)
    assert (same.status == free.status).all() and np.array_equal(same.torque, free.torque)
    limits[0] = 1e-3 * np.abs(free.torque[:, 0]).max()  # one joint limited, binding
    tight = gt.solve_batch(G, JT, W, PCWF, torque_limits=limits)
    held = tight.status == 0
    assert (np.abs(tight.torque[held, 0]) <= limits[0] * (1 + 1e-9)).all()
    p = gt.Problem.from_arrays(G[0], JT[0], PCWF, W[0], torque_limits=limits)
    assert p.to_dict()["torque_limits"][1:] == [None] * (m - 1)
    with pytest.raises(ValueError, match="torque_limits\\[0\\]: expected a finite number, got -inf"):
        gt.solve_batch(G, JT, W, PCWF, torque_limits=[-np.inf] + [None] * (m - 1))


def test_synthetic_grasps_checks_its_counts():
    with pytest.raises(ValueError, match="batch: expected at least 0, got -1"):
        gt.synthetic_grasps(-1)
    with pytest.raises(ValueError, match="fingers: expected a whole number"):
        gt.synthetic_grasps(2, fingers=2.5)
    assert gt.synthetic_grasps(0)[0].shape == (0, 6, 9)
    # Past the solver's limits or the memory's, a ValueError, not numpy's MemoryError.
    with pytest.raises(ValueError, match=f"fingers: expected at most {gt._native.MAX_CONTACTS}, got 300"):
        gt.synthetic_grasps(1, fingers=300)
    with pytest.raises(ValueError, match="joints_per_finger: expected at most 2, got 3"):
        gt.synthetic_grasps(1, fingers=100)
    with pytest.raises(ValueError, match="batch: expected at most [0-9]+, got 1000000000000"):
        gt.synthetic_grasps(10**12)


def test_preallocated_outputs_are_filled_in_place():
    G, JT, W = gt.synthetic_grasps(50, wrenches=3, seed=2)
    m = JT.shape[1]
    torque = np.full((50, 3, m), -1.0)
    objective = np.empty((50, 3))
    residual = np.empty((50, 3))
    status = np.full((50, 3), 9, dtype=np.int8)
    out = gt.solve_batch(G, JT, W, PCWF, torque=torque, objective=objective, wrench_residual=residual, status=status)
    assert out.torque is torque and out.status is status
    fresh = gt.solve_batch(G, JT, W, PCWF)
    np.testing.assert_array_equal(torque, fresh.torque)
    np.testing.assert_array_equal(status, fresh.status)
    with pytest.raises(ValueError, match="torque"):
        gt.solve_batch(G, JT, W, PCWF, torque=np.empty((50, m)))
    with pytest.raises(ValueError, match="status"):
        gt.solve_batch(G, JT, W, PCWF, status=np.empty((50, 3)))


def test_an_unusable_output_is_refused_for_what_it_is():
    """Each fault of a preallocated output is named (dtype, byte order, shape, layout,
    read-only), and an output that overlaps another or an input is refused before
    anything is written: the batch reads its inputs while it writes, from many
    threads."""
    G, JT, W = gt.synthetic_grasps(20, seed=5)
    m, n = JT.shape[1], JT.shape[2]
    read_only = np.empty((20, m))
    read_only.flags.writeable = False
    faults = [
        ({"torque": [[0.0] * m] * 20}, "torque: expected a numpy array of dtype float64 and shape \\(20, 9\\), got list"),
        ({"torque": np.empty((20, m), np.float32)}, "torque: expected a numpy array of dtype float64, got float32$"),
        ({"objective": np.empty(20, ">f8")}, "objective: .* got float64 in the other byte order \\(>f8\\)"),
        ({"status": np.empty(20)}, "status: expected a numpy array of dtype int8, got float64"),
        ({"torque": np.empty((20, m + 1))}, "torque: expected an array of shape \\(20, 9\\), got \\(20, 10\\)"),
        ({"torque": np.empty((20, 2 * m))[:, ::2]}, "torque: expected a C-contiguous array, got one with strides \\(144, 16\\)"),
        ({"torque": read_only}, "torque: expected a writeable array, got a read-only one"),
    ]
    shared = np.empty(40)
    faults += [
        ({"objective": shared[:20], "wrench_residual": shared[10:30]}, "objective: shares memory with wrench_residual"),
        ({"torque": JT.reshape(-1)[: 20 * m].reshape(20, m)}, "torque: shares memory with the input JT"),
        ({"contact_forces": G.reshape(-1)[: 20 * n].reshape(20, n)}, "contact_forces: shares memory with the input G"),
    ]
    for given, message in faults:
        before = [a.copy() for a in (G, JT, W)]
        with pytest.raises(ValueError, match=message):
            gt.solve_batch(G, JT, W, PCWF, **given)
        for a, b in zip((G, JT, W), before):
            np.testing.assert_array_equal(a, b)
    # Disjoint parts of one buffer are fine.
    out = gt.solve_batch(G, JT, W, PCWF, objective=shared[:20], wrench_residual=shared[20:])
    np.testing.assert_array_equal(shared[:20], out.objective)
    # Hand.solve_batch checks its outputs alike.
    hand = gt.Hand(os.path.join(os.path.dirname(__file__), "..", "..", "fixtures", "urdf", "allegro", "allegro_hand_right.urdf"))
    tip = [{"link": "link_3.0_tip", "model": "pcwf", "mu": 0.5}]
    q = np.zeros(3 * len(hand.joint_names))
    with pytest.raises(ValueError, match="torque: shares memory with the input joint_positions"):
        hand.solve_batch(q.reshape(3, -1), np.zeros((3, 6)), tip, torque=q[-12:].reshape(3, 4))


def test_the_gil_is_released():
    G, JT, W = gt.synthetic_grasps(4000, seed=4)
    t0 = time.perf_counter()
    gt.solve_batch(G, JT, W, PCWF, threads=1)
    alone = time.perf_counter() - t0
    spans = []

    def work():
        a = time.perf_counter()
        gt.solve_batch(G, JT, W, PCWF, threads=1)
        spans.append((a, time.perf_counter()))

    ticks = []
    t = threading.Thread(target=work)
    t.start()
    while t.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    t.join()
    (a, b), = spans
    # Python kept running while the batch ran: many ticks strictly inside its span.
    inside = [x for x in ticks if a + 0.1 * (b - a) < x < b - 0.1 * (b - a)]
    assert len(inside) >= 10, (len(inside), b - a, alone)
    # Two Python threads calling solve_batch overlap.
    spans.clear()
    threads = [threading.Thread(target=work) for _ in range(2)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    (a1, b1), (a2, b2) = spans
    assert min(b1, b2) > max(a1, a2), "the two batches did not overlap"


def _child_batch(conn):
    G, JT, W = gt.synthetic_grasps(200, seed=6)
    conn.send(gt.solve_batch(G, JT, W, PCWF, threads=2).objective)
    conn.close()


@pytest.mark.skipif(sys.platform != "linux", reason="fork is a Linux start method here")
def test_fork_after_use_is_safe():
    G, JT, W = gt.synthetic_grasps(200, seed=6)
    expected = gt.solve_batch(G, JT, W, PCWF, threads=2).objective  # the pool exists now
    ctx = multiprocessing.get_context("fork")
    parent, child = ctx.Pipe()
    p = ctx.Process(target=_child_batch, args=(child,))
    p.start()
    assert parent.poll(60), "the forked child hung"
    got = parent.recv()
    p.join(10)
    assert p.exitcode == 0
    np.testing.assert_array_equal(got, expected)


def _solve_pickled(blob):
    solver, wrench = pickle.loads(blob)
    return solver.solve(wrench).objective


def test_process_pools_take_pickled_solvers(root):
    s = gt.Solver(root / "fixtures" / "hand5-pcwf.json")
    w = s.problem.wrench
    wrenches = [w * (1 + 0.01 * k) for k in range(4)]
    expected = [s.solve(x, warm=False).objective for x in wrenches]
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as ex:
        got = list(ex.map(_solve_pickled, [pickle.dumps((s, x)) for x in wrenches]))
    assert all(abs(a - b) <= 1e-9 * b for a, b in zip(got, expected))


def test_ray_example_runs(root):
    pytest.importorskip("ray", reason="Ray is installed by .ci/run (pip install ray)")
    script = root / "examples" / "python" / "ray_batch.py"
    env = dict(os.environ, RAY_DISABLE_USAGE_STATS="1", RAY_USAGE_STATS_ENABLED="0")
    out = subprocess.run(
        [sys.executable, str(script), "--grasps", "2000", "--chunks", "4", "--check"],
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    assert "grasps/s" in out.stdout
    assert "matches the local batch" in out.stdout
