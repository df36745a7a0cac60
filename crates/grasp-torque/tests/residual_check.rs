//! The core's residual check against a plain recomputation: on every bundled grasp
//! (the Shadow tripod with its transmission among them, the Aero pinch with its
//! springs), the reported residuals equal `‖G f − w‖∞`, `‖[E; Jᵀ] f − [0; τ]‖∞` with the
//! joint-space `‖Jᵀ f − T u‖∞`, and `‖C τ − e‖∞` (each target moved by the passive
//! torques), formed here row by row from the model's matrices; and an answer
//! moved off its optimum along one joint is no longer called optimal.
#![cfg(feature = "active-set")]

use grasp_torque::{
    GraspProblem, GraspSolver, Matrix, Reason, Solution, SolverConfig, Status, WarmStart,
};

mod common;
use common::{stated_excess, stated_spread};

/// A cold solve of `q` at its own wrench.
fn solved(q: &GraspProblem, config: &SolverConfig) -> Solution {
    GraspSolver::new(q, config)
        .unwrap()
        .solve(&q.wrench, &WarmStart::default())
        .unwrap()
        .clone()
}

/// A cold solve of `q` on the exact cones.
fn solved_exact(q: &GraspProblem) -> Solution {
    let config = SolverConfig {
        cones: grasp_torque::Cones::Exact,
        ..Default::default()
    };
    solved(q, &config)
}

/// Cold solves of `p` with each number of polygon sides in `sides`.
fn by_sides(p: &GraspProblem, sides: &[usize]) -> Vec<(usize, Solution)> {
    (sides.iter())
        .map(|&n| {
            let mut q = p.clone();
            q.linearization.sides = n;
            (n, solved(&q, &SolverConfig::default()))
        })
        .collect()
}

/// Systems of units (lengths × l, forces × f) for the fuzz fixtures' invariance.
const UNITS: [(f64, f64); 6] = [
    (1.0, 1.0),
    (1e-3, 1e3),
    (1e3, 1e-3),
    (0.244, 17.7),
    (1.0, 1e6),
    (1.0, 1e-6),
];

/// A problem of `fixtures/fuzz`.
fn fuzz_fixture(name: &str) -> GraspProblem {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/fuzz");
    grasp_torque::load_problem(format!("{dir}/{name}.json")).unwrap()
}

/// `max_i |M_i x − t_i|` and the largest `Σ_j |M_ij x_j| + |t_i|` (the sums' size).
fn residual(m: &Matrix, x: &[f64], t: &[f64]) -> (f64, f64) {
    (0..m.nrows()).fold((0.0f64, 0.0f64), |(r, s), i| {
        let row = m.row(i);
        let v: f64 = row.iter().zip(x).map(|(a, b)| a * b).sum();
        let size: f64 = row.iter().zip(x).map(|(a, b)| (a * b).abs()).sum();
        let ti = t.get(i).copied().unwrap_or(0.0);
        (r.max((v - ti).abs()), s.max(size + ti.abs()))
    })
}

/// The residuals of `s` recomputed from the model, each with the size of its terms.
fn check_against_plain(s: &Solution, solver: &GraspSolver, w: &[f64; 6], label: &str) {
    let model = &solver.problem().model;
    let (f, tau) = (&s.contact_forces, &s.torque);
    let d = &s.diagnostics;
    let eps = 64.0 * f64::EPSILON * (f.len() + tau.len() + 6) as f64;
    // Passive torques τ_p move the targets: E f = Q₂ᵀ τ_p, T⁺Jᵀ f = u + T⁺ τ_p,
    // Jᵀ f = T u + τ_p and C u − e(w) = e_p (all zero without them).
    let pas = &model.passive;
    let k = model.unactuated.nrows();
    let target = |i: usize| pas.row_targets.get(i).copied().unwrap_or(0.0);
    let (wr, ws) = residual(&model.grasp_matrix, f, w);
    let rows: Vec<f64> = (0..tau.len()).map(|j| tau[j] + target(k + j)).collect();
    let (tr, ts) = residual(&model.jacobian_transpose, f, &rows);
    let (er, es) = residual(
        &model.unactuated,
        f,
        &(0..k).map(target).collect::<Vec<_>>(),
    );
    let (mut tr, mut ts) = (tr.max(er), ts.max(es));
    if let Some(a) = &model.actuators {
        let mut joint = a.transmission.mul_vec(tau);
        joint
            .iter_mut()
            .zip(&pas.joint_torque)
            .for_each(|(j, p)| *j += p);
        let (jr, js) = residual(&a.joint_jacobian_transpose, f, &joint);
        let (_, us) = residual(&a.transmission, tau, &[]);
        tr = tr.max(jr);
        ts = ts.max(js + us);
    }
    let e: Vec<f64> = (0..model.equality_rows())
        .map(|i| {
            -model
                .eq_w
                .row(i)
                .iter()
                .zip(w)
                .map(|(a, b)| a * b)
                .sum::<f64>()
                + pas.eq_offset.get(i).copied().unwrap_or(0.0)
        })
        .collect();
    let (cr, cs) = residual(&model.eq, tau, &e);
    for (name, got, want, size) in [
        ("wrench", d.wrench_residual, wr, ws),
        ("torque", d.torque_residual, tr, ts),
        ("consistency", d.consistency_residual, cr, cs),
    ] {
        assert!(
            (got - want).abs() <= eps * size.max(f64::MIN_POSITIVE),
            "{label}: {name} residual {got:e}, recomputed {want:e} (terms {size:e})"
        );
    }
}

#[test]
fn residuals_match_a_plain_recomputation_and_a_moved_answer_fails() {
    let files = grasp_testkit::fixture_paths(&["", "hands", "table1", "geometry"]);
    assert!(files.len() >= 15, "{files:?}");
    let mut failed = 0;
    for path in &files {
        let p = grasp_torque::load_problem(path).unwrap();
        let label = path.display().to_string();
        let mut solver = GraspSolver::new(&p, &SolverConfig::default()).unwrap();
        let s = solver
            .solve(&p.wrench, &WarmStart::default())
            .unwrap()
            .clone();
        // Every bundled grasp is feasible: a check that refused an optimum is wrong too.
        assert_eq!(s.status, Status::Optimal, "{label}: {:?}", s.reason);
        check_against_plain(&s, &solver, &p.wrench, &label);
        // Moved along the joint with the largest torque, by a tenth of it: the forces
        // follow from τ, so a row the optimum holds (a cone face, an equality, the
        // wrench through C τ = e) must now fail.
        let j = (0..s.torque.len())
            .max_by(|&a, &b| s.torque[a].abs().total_cmp(&s.torque[b].abs()))
            .unwrap();
        let mut moved = s.clone();
        moved.status = Status::Optimal;
        moved.torque[j] += 0.1 * s.torque[j].abs().max(1e-3);
        let qp = solver.problem();
        qp.complete(&p.wrench, 1e-9, "test", &mut moved);
        check_against_plain(&moved, &solver, &p.wrench, &label);
        // Where the move breaks C τ = e far beyond any tolerance (relative to the terms
        // of the equalities), the wrench is no longer balanced: the answer must fail.
        let d = &moved.diagnostics;
        let model = &qp.model;
        let size = (0..model.equality_rows())
            .map(|i| {
                let r = model.eq.row(i).iter().zip(&moved.torque);
                r.map(|(a, b)| (a * b).abs()).sum::<f64>()
            })
            .fold(0.0, f64::max);
        if d.consistency_residual > 1e-6 * size {
            assert_eq!(moved.status, Status::NumericalFailure, "{label}: {d:?}");
            // The reason says which check failed, as the diagnostics measured it.
            let Some(Reason::ResidualCheck { checks, .. }) = moved.reason else {
                panic!("{label}: {:?}", moved.reason)
            };
            let measured = [
                d.wrench_check,
                d.torque_check,
                d.violation_check.max(d.cone_check),
            ];
            assert_eq!(checks, measured, "{label}");
            assert!(checks.iter().any(|&c| c > 1.0), "{label}: {checks:?}");
            failed += 1;
        }
    }
    assert!(failed >= 5, "only {failed} moved answers checked");
}

/// A moment no contact can make is not admitted by a tiny lever in the same block of
/// rows: sweep seed 1720 at normal friction, five point contacts whose moment rows of G
/// are 0, 6.8e-21 and 0 (their forces pass through the object's origin), and a wrench
/// with moments of 2 N·m. Equilibrated up by 1.5e20, the tiny row raised the unreachable
/// check's tolerance, read in raw units on the zero rows, above those moments, and the
/// answer was `optimal` with σ = 2.3e40 and `‖G f − w‖∞` = 3.9e7. A zero row's target is
/// now scaled as its block's rows are: the wrench is unreachable, on every backend and
/// cone, and in millimetres too.
#[test]
fn a_moment_no_contact_makes_is_unreachable() {
    use grasp_torque::{Backend, Cones, Reason};
    let p = grasp_testkit::sweep_grasp(1720, 1.0);
    let mut backends = vec![Backend::ActiveSet];
    if cfg!(feature = "clarabel") {
        backends.push(Backend::Clarabel);
    }
    for q in [p.clone(), grasp_testkit::rescale(&p, 1e3, 1.0)] {
        for &backend in &backends {
            for cones in [Cones::Linear, Cones::Exact] {
                let config = SolverConfig {
                    backend: Some(backend),
                    cones,
                    ..Default::default()
                };
                let s = solved(&q, &config);
                assert_eq!(
                    s.status,
                    Status::Infeasible,
                    "{backend:?} {cones:?}: σ {}",
                    s.objective
                );
                assert!(
                    matches!(s.reason, Some(Reason::UnreachableWrench { .. })),
                    "{backend:?} {cones:?}: {:?}",
                    s.reason
                );
            }
        }
    }
}

/// Each check's ratio (`wrench_check`, `torque_check`, `violation_check`,
/// `cone_check`: the worst row against the bound it was judged by) is the check's own
/// decision: an answer is refused exactly when one exceeds 1. On every bundled grasp,
/// linear and exact, the optimum and answers moved off it along each joint by 1e-14
/// to 1e-1 of the largest torque, so that some pass and some fail by a little. (The
/// report printed "within 7.3e-12" beside a violation of 5.1e-12 that the check had
/// refused against its row's own bound of 2.2e-12: fuzz_answers.py seed 5532.)
#[test]
fn each_check_ratio_is_the_check_decision() {
    use grasp_torque::Cones;
    let files = grasp_testkit::fixture_paths(&["", "hands", "table1", "geometry"]);
    let (mut passed, mut refused) = (0, 0);
    for path in &files {
        let p = grasp_torque::load_problem(path).unwrap();
        for cones in [Cones::Linear, Cones::Exact] {
            let label = format!("{} {cones:?}", path.display());
            let config = SolverConfig {
                cones,
                ..Default::default()
            };
            let mut solver = GraspSolver::new(&p, &config).unwrap();
            let s = solver
                .solve(&p.wrench, &WarmStart::default())
                .unwrap()
                .clone();
            assert_eq!(s.status, Status::Optimal, "{label}: {:?}", s.reason);
            let scale = s.torque.iter().fold(0.0f64, |a, t| a.max(t.abs()));
            let qp = solver.problem();
            for j in 0..s.torque.len() {
                for step in [1e-14, 1e-12, 1e-10, 1e-9, 1e-8, 1e-6, 1e-1] {
                    let mut moved = s.clone();
                    moved.torque[j] += step * scale;
                    qp.complete(&p.wrench, 1e-9, "test", &mut moved);
                    let d = &moved.diagnostics;
                    let worst = [
                        d.wrench_check,
                        d.torque_check,
                        d.violation_check,
                        d.cone_check,
                    ]
                    .into_iter()
                    .fold(0.0f64, f64::max);
                    let failed = moved.status == Status::NumericalFailure;
                    assert_eq!(failed, worst > 1.0, "{label}, joint {j} by {step:e}: {d:?}");
                    if failed {
                        refused += 1;
                    } else {
                        passed += 1;
                    }
                }
            }
        }
    }
    assert!(
        passed >= 100 && refused >= 100,
        "{passed} passed, {refused} refused"
    );
}

/// A row of Jᵀ scaled by 438 on a sweep grasp
/// (`fixtures/fuzz/scaled-row-refused-then-held.json`, `fuzz_answers.py` seed 200593):
/// the native active-set answer at N = 8 ended 7.4e-2 outside a face, within its
/// tolerance on rows normalised in y and 3.1e4 times the core's bound, and was
/// refused (`numerical_failure`). The core now asks for the backend's fallback, the
/// interior-point method on the same polyhedra, and checks it: it holds the grasp at
/// the exported QP's optimum (7.41535882931192 by cvxpy with Clarabel,
/// `scripts/oracle_qp.py FILE --sides 8`, whose point misses the rows by 3e-13), and
/// more sides give a σ no higher, down to the exact cones'.
#[test]
fn a_refused_linear_answer_is_held_by_the_interior_point_method() {
    let p = fuzz_fixture("scaled-row-refused-then-held");
    let mut last = f64::INFINITY;
    for (sides, cones) in [
        (4, grasp_torque::Cones::Linear),
        (8, grasp_torque::Cones::Linear),
        (16, grasp_torque::Cones::Linear),
        (32, grasp_torque::Cones::Linear),
        (8, grasp_torque::Cones::Exact),
    ] {
        let mut q = p.clone();
        q.linearization.sides = sides;
        let config = SolverConfig {
            cones,
            ..Default::default()
        };
        let s = solved(&q, &config);
        let at = format!("{cones:?} at N = {sides}");
        assert_eq!(s.status, Status::Optimal, "{at}: {:?}", s.reason);
        if sides == 8 && cones == grasp_torque::Cones::Linear {
            assert!(
                (s.objective - 7.41535882931192).abs() <= 1e-9 * s.objective,
                "{at}: σ {}",
                s.objective
            );
            assert!(
                s.warnings.iter().any(|w| w.contains("fallback")),
                "{at}: {:?}",
                s.warnings
            );
        }
        assert!(
            s.objective <= last * (1.0 + 1e-9),
            "{at}: σ {} above {last}",
            s.objective
        );
        last = s.objective;
    }
}

/// On a grasp where the interior-point fallback stops short of its own tolerances at
/// every N, each answer states a bound on σ that holds: nested polyhedra (N's vertices
/// are among 2N's) give σ*(M) ≤ σ*(N) ≤ σ(N) for M > N, so σ(M) ≤ σ(N) (1 + b_M). At
/// N = 16 a best iterate whose gap bounds σ only to 3.3e-7, admitted by the
/// allowance for sᵀz's rounding, was `optimal` 1.8e-7 above the answer at N = 8.
#[test]
fn an_iterate_stopped_short_states_the_bound_its_gap_gives() {
    let p = fuzz_fixture("noisy-paper-grasp-stopped-short");
    let answers = by_sides(&p, &[4, 8, 16, 32, 64]);
    for (i, (n, a)) in answers.iter().enumerate() {
        let bound = stated_excess(a);
        assert!(bound <= 1e-6, "N = {n}: {:?}", a.warnings);
        for (m, b) in &answers[i + 1..] {
            assert!(
                b.objective <= a.objective * (1.0 + stated_excess(b)),
                "σ {} at N = {m} above σ {} at N = {n} by more than its bound ({:?})",
                b.objective,
                a.objective,
                b.warnings
            );
        }
    }
}

/// A key set of two nearly opposite faces is solved to the rounding of its terms
/// (`fixtures/fuzz/opposite-faces-beside-a-scaled-joint.json`, `fuzz_answers.py` seed
/// 245048: the paper example with joint 1's row of Jᵀ scaled to 2e-8, whose faces'
/// entries on joint 1 are 5e9 and their sum's 1). The native method holds its rows in
/// the free torques only to ε times their norm, and its answers sat 4e-7 inside both
/// faces, σ up to 4.5e-7 above the key set's optimum and out of the nested polygons'
/// order; it now refines them in τ. `scripts/key_set_optimum.py` (50 digits, on the
/// exported QP and the answer's key set) gives 23.81370850096063 at N = 8, and within
/// 6e-14 of it at N = 16, 32 and 64 (their rows' own rounding): each answer must be
/// within 1e-12 of it, a hundred times that spread, cold and warm, and with the
/// wrench scaled by 1e6 and 1e-6 (σ by their squares).
#[test]
fn a_key_set_of_nearly_opposite_faces_is_solved_to_its_terms() {
    let p = fuzz_fixture("opposite-faces-beside-a-scaled-joint");
    // The rows' constants are linear in w, so σ scales as its square.
    for sides in [8, 16, 32, 64] {
        for k in [1.0, 1e6, 1e-6] {
            let mut q = p.clone();
            q.linearization.sides = sides;
            q.wrench.iter_mut().for_each(|v| *v *= k);
            let mut solver = GraspSolver::new(&q, &SolverConfig::default()).unwrap();
            // Cold, then warm from that answer (a hot start: the same key set).
            for run in ["cold", "warm"] {
                let s = solver.resolve(&q.wrench).unwrap();
                let at = format!("N = {sides}, wrench × {k:e}, {run}");
                assert_eq!(s.status, Status::Optimal, "{at}: {:?}", s.reason);
                let sigma = s.objective / (k * k);
                assert!(
                    (sigma - 23.81370850096063).abs() <= 1e-12 * sigma,
                    "{at}: σ {sigma}"
                );
            }
        }
    }
}

/// A proof of infeasibility from rows that are parallel only to the factor's
/// dependence tolerance (1e-10), not to their own rounding, rules out only the torques
/// near its point (`fixtures/fuzz/rows-parallel-beside-a-tiny-joint*.json`,
/// `fuzz_answers.py nested` seeds 253291 and 256090: the Ability tripod with one
/// joint's row of Jᵀ a single entry of 4e-14 or 5e-13, whose force response, 1e13 times
/// the others', makes every row nearly parallel). Both grasps were `infeasible` at
/// N = 8 (the first at 32 and exact too) and held at N = 4. Now each answer at
/// N = 4, 8, 16, 32 and exact is
/// optimal in any units and under any load (forces alone × 1e6 or 1e-6: the wrench
/// and the torque limits together), σ falls as N grows (each within its stated bound),
/// and at N = 8 σ is Clarabel's through cvxpy on the exported QP (row misses 1.3e-10
/// and 1.5e-9): within the certificate's 2e-9 of the optimum, and the oracle's own
/// 2e-9 for its misses.
#[test]
fn a_proof_from_rows_parallel_beyond_their_rounding_is_not_final() {
    for (name, oracle) in [
        ("rows-parallel-beside-a-tiny-joint", 0.024154065455693007),
        ("rows-parallel-beside-a-tiny-joint-2", 0.0002174589526613313),
    ] {
        let p = fuzz_fixture(name);
        for (l, f) in UNITS {
            let q = grasp_testkit::rescale(&p, l, f);
            let answers = by_sides(&q, &[4, 8, 16, 32]);
            let at = format!("{name}, lengths × {l:e}, forces × {f:e}");
            for (i, (n, a)) in answers.iter().enumerate() {
                assert_eq!(a.status, Status::Optimal, "{at}, N = {n}: {:?}", a.reason);
                for (m, b) in &answers[i + 1..] {
                    assert!(
                        b.objective <= a.objective * (1.0 + stated_excess(b)),
                        "{at}: σ {} at N = {m} above σ {} at N = {n}",
                        b.objective,
                        a.objective
                    );
                }
            }
            // The exact cones contain every polygon (the exact path's circumscribed
            // polyhedra took the same false proof).
            let exact = solved_exact(&q);
            assert_eq!(
                exact.status,
                Status::Optimal,
                "{at}, exact: {:?}",
                exact.reason
            );
            let last = &answers[answers.len() - 1].1;
            assert!(
                exact.objective <= last.objective * (1.0 + stated_excess(&exact)),
                "{at}: exact σ {} above σ {} at N = 32",
                exact.objective,
                last.objective
            );
            let sigma = answers[1].1.objective / (l * f).powi(2);
            assert!(
                (sigma - oracle).abs() <= 4e-9 * oracle,
                "{at}: σ {sigma} at N = 8 against the oracle's {oracle}"
            );
        }
    }
}

/// A key set whose rows meet only where their rounding exceeds the problem's scale is
/// no answer: seed 296620 in other units
/// (`fixtures/fuzz/rows-meeting-beyond-their-rounding.json`), which Clarabel proves
/// infeasible, was `optimal` at torques of 1e13 with the object's equilibrium missed by
/// 24 against a load of 10 (the core's check, against forces of 5e16, passed it). At
/// every N and in every system of units of [`UNITS`] the linear answer is now
/// `infeasible` or `numerical_failure`, never an optimum, and the exact cones' is
/// `infeasible`.
#[test]
fn a_key_set_meeting_beyond_its_rounding_is_no_answer() {
    let p = fuzz_fixture("rows-meeting-beyond-their-rounding");
    for (l, f) in UNITS {
        let q = grasp_testkit::rescale(&p, l, f);
        let at = format!("lengths × {l:e}, forces × {f:e}");
        for (n, a) in by_sides(&q, &[4, 8, 16, 32, 64]) {
            assert!(
                matches!(a.status, Status::Infeasible | Status::NumericalFailure),
                "{at}, N = {n}: {:?} at σ {}",
                a.status,
                a.objective
            );
        }
        let exact = solved_exact(&q);
        assert_eq!(
            exact.status,
            Status::Infeasible,
            "{at}, exact: {:?}",
            exact.reason
        );
    }
}

/// A joint whose row of Jᵀ the model zeroes is pinned to 0 by the consistency rows,
/// through the column of C that its zero row's scale makes: seed 296009
/// (`fixtures/fuzz/zeroed-joint-beside-a-row-of-5e7.json`), whose joint 10 has an upper
/// limit of 0 beside a row of 5e7, had τ₁₀ = 4.5e-8 at the block's largest norm (the
/// linear answer refused, the exact one failing its certificate, and one system of
/// units `infeasible`). In every system of units of [`UNITS`] both are optimal, τ₁₀ is 0
/// to the torques' rounding times the square root of the rows' spread, and σ is
/// Clarabel's (the exported QP through cvxpy at N = 8, the Clarabel backend on the exact
/// cones) to its 1e-8.
#[test]
fn a_zeroed_joint_beside_a_long_row_is_pinned_to_its_torque() {
    let p = fuzz_fixture("zeroed-joint-beside-a-row-of-5e7");
    let (linear_oracle, exact_oracle) = (1.4363460513660298, 1.3441349491110557);
    // The spread of the rows of Jᵀ: the zero row's scale, their geometric mean's, leaves
    // τ₁₀ the rounding of the torques times its square root at most.
    let norms = (0..p.jacobian_transpose.nrows())
        .map(|i| grasp_torque::matrix::norm2(p.jacobian_transpose.row(i)));
    let (lo, hi) = norms.fold((f64::INFINITY, 0.0f64), |(l, h), v| (l.min(v), h.max(v)));
    let spread = hi / lo;
    for (l, f) in UNITS {
        let q = grasp_testkit::rescale(&p, l, f);
        let at = format!("lengths × {l:e}, forces × {f:e}");
        let k2 = (l * f).powi(2);
        let exact = solved_exact(&q);
        let answers = by_sides(&q, &[4, 8, 16]);
        for (n, a) in answers
            .iter()
            .map(|(n, a)| (n.to_string(), a))
            .chain([("exact".into(), &exact)])
        {
            assert_eq!(a.status, Status::Optimal, "{at}, N = {n}: {:?}", a.reason);
            let tmax = a.torque.iter().fold(0.0f64, |m, t| m.max(t.abs()));
            let rounding = a.torque.len() as f64 * f64::EPSILON * spread.sqrt() * tmax;
            assert!(
                a.torque[10].abs() <= rounding,
                "{at}, N = {n}: τ₁₀ {}",
                a.torque[10]
            );
        }
        for (sigma, oracle, what) in [
            (answers[1].1.objective / k2, linear_oracle, "N = 8"),
            (exact.objective / k2, exact_oracle, "exact"),
        ] {
            assert!(
                (sigma - oracle).abs() <= 1e-8 * oracle,
                "{at}, {what}: σ {sigma} against Clarabel's {oracle}"
            );
        }
    }
}

/// A proof from rows independent beyond their rounding, whose iteration with rows
/// counted independent to 1e-13 ends at a point that misses a row, is decided by the
/// interior-point method's ray of the dual: seed 3238
/// (`fixtures/fuzz/infeasible-beside-rows-near-dependence.json`) is infeasible by
/// Clarabel and SCS on the exported QP, and by the exact cones' dual ray; the point
/// was σ 6e22 with a row missed by 1.8e7 times its bound.
#[test]
fn a_ray_of_the_dual_decides_where_the_finer_iteration_misses_a_row() {
    let p = fuzz_fixture("infeasible-beside-rows-near-dependence");
    let s = solved(&p, &SolverConfig::default());
    assert!(
        s.status == Status::Infeasible
            && matches!(s.reason, Some(Reason::DualRay { value, .. }) if value < -1e-6),
        "{:?} {:?} {:?}",
        s.status,
        s.reason,
        s.warnings
    );
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let exact = solved_exact(&p);
    assert_eq!(
        exact.status,
        Status::Infeasible,
        "exact: {:?}",
        exact.reason
    );
}

/// Where the key set's rows nearly depend on each other, their rounding fixes σ no
/// closer than their multipliers times it, and the answer says how close. σ differed:
/// - on `fixtures/fuzz/rows-opposite-to-1e-9-on-a-noisy-paper-grasp.json` (nested
///   seed 260254: two faces opposite to one part in 1e9, terms of 1.9e9) at N = 8, 32
///   and 64 by up to 1.5e-7, not nested;
/// - on `…/squeezed-by-torques-of-1e8.json` (seed 265929: forces of 3.5e9 N holding
///   0.2 N) by up to 3e-5 between units;
/// - on `…/rows-of-jt-1e14-apart-on-the-weighed-allegro.json` (seed 281676, with
///   passive torques) by up to 9.6e-3 between units.
///
/// Each answer is optimal and states a spread that covers every difference, and at
/// N = 8 the first grasp's key-set point in 50 digits on the exported QP
/// (`scripts/key_set_optimum.py`: σ 47.127416487665906). A bundled grasp states none.
#[test]
fn an_answer_states_how_far_its_rows_rounding_moves_sigma() {
    // Each answer optimal, with a spread, and every two within their spreads.
    let covered = |answers: &[(String, Solution)]| {
        for (at, a) in answers {
            assert_eq!(a.status, Status::Optimal, "{at}: {:?}", a.reason);
            assert!(stated_spread(a) > 2e-9, "{at}: {:?}", a.warnings);
        }
        for (i, (at, a)) in answers.iter().enumerate() {
            for (other, b) in &answers[i + 1..] {
                let (sa, sb) = (stated_spread(a), stated_spread(b));
                assert!(
                    (a.objective - b.objective).abs() <= (sa + sb) * a.objective.max(b.objective),
                    "{at} and {other}: σ {} and {} beyond their stated spreads {sa:e} and {sb:e}",
                    a.objective,
                    b.objective,
                );
            }
        }
    };
    let p = fuzz_fixture("rows-opposite-to-1e-9-on-a-noisy-paper-grasp");
    let answers: Vec<(String, Solution)> = by_sides(&p, &[8, 32, 64])
        .into_iter()
        .map(|(n, s)| (format!("N = {n}"), s))
        .collect();
    covered(&answers);
    let (oracle, eight) = (47.127416487665906, &answers[0].1);
    assert!(
        (eight.objective - oracle).abs() <= stated_spread(eight) * oracle,
        "N = 8: σ {} against the key set's {oracle}",
        eight.objective
    );

    // In four systems of units, and at N = 16 to 64 (where a proof from rows 3.7e-11
    // from dependent, 2 500 times their rounding, called it infeasible; the iteration
    // with rows counted independent to 1e-13 holds it).
    let in_units = |p: &GraspProblem, units: &[(f64, f64)]| -> Vec<(String, Solution)> {
        (units.iter())
            .map(|&(l, f)| {
                let mut s = solved(&grasp_testkit::rescale(p, l, f), &SolverConfig::default());
                s.objective /= (l * f).powi(2);
                (format!("lengths × {l:e}, forces × {f:e}"), s)
            })
            .collect()
    };
    let p = fuzz_fixture("squeezed-by-torques-of-1e8");
    let mut answers = in_units(&p, &[(1.0, 1.0), (1e-3, 1e3), (1e3, 1e-3), (0.244, 17.7)]);
    answers.extend(
        by_sides(&p, &[16, 32, 64])
            .into_iter()
            .map(|(n, s)| (format!("N = {n}"), s)),
    );
    covered(&answers);
    // With passive torques, whose offset the spread is taken against too; the second
    // system of units is near the search's, where σ moved by 3.2e-3.
    let p = fuzz_fixture("rows-of-jt-1e14-apart-on-the-weighed-allegro");
    covered(&in_units(
        &p,
        &[(1.0, 1.0), (0.031, 48.8), (1e-3, 1e3), (0.244, 17.7)],
    ));

    for path in grasp_testkit::fixture_paths(&["", "hands", "table1"]) {
        let p = grasp_torque::load_problem(&path).unwrap();
        let s = solved(&p, &SolverConfig::default());
        assert_eq!(
            stated_spread(&s),
            0.0,
            "{}: {:?}",
            path.display(),
            s.warnings
        );
    }
}

/// A contact whose force the wrench alone fixes, outside its exact cone, makes the
/// grasp infeasible whatever the torques: seed 314274
/// (`fixtures/fuzz/contact-fixed-by-the-wrench-beside-a-long-row.json`), with a row of
/// Jᵀ 6e6 times the others', was answered by the exact cones' closed form at a torque
/// of 1.7e7 whose rounding moved the contact toward its cone, and the certificate
/// passed the miss against the equalities' terms, 1e7 times the contact's (the core's
/// check refused it: `numerical_failure`). In every system of units of [`UNITS`] the
/// polyhedra and the exact cones now prove it infeasible, the exact cones by a ray of
/// the dual, as Clarabel does.
#[test]
fn a_contact_the_wrench_fixes_outside_its_cone_is_infeasible() {
    let p = fuzz_fixture("contact-fixed-by-the-wrench-beside-a-long-row");
    for (l, f) in UNITS {
        let q = grasp_testkit::rescale(&p, l, f);
        let at = format!("lengths × {l:e}, forces × {f:e}");
        for (n, a) in by_sides(&q, &[4, 8, 16, 32, 64]) {
            assert_eq!(
                a.status,
                Status::Infeasible,
                "{at}, N = {n}: {:?}",
                a.reason
            );
        }
        let exact = solved_exact(&q);
        assert!(
            exact.status == Status::Infeasible
                && matches!(exact.reason, Some(Reason::DualRay { value, .. }) if value < -1e-6),
            "{at}, exact: {:?} {:?}",
            exact.status,
            exact.reason
        );
    }
}

/// A grasp held only by torques of 3e10 (`fixtures/fuzz/held-only-by-torques-of-3e10.json`,
/// `fuzz_answers.py` seed 319014: a row of Jᵀ 1e8 times the others'), where two nearly
/// opposite faces meet. The iteration's proof of infeasibility from them holds only near
/// its point, and the interior-point method, which answers in some systems of units,
/// stalls in others (lengths × 122, forces × 43.4 among them), where the proof stood:
/// both views were `infeasible`. Clarabel, SCS and DAQP on the exported QP call it
/// infeasible too, but the native answer holds every row to 1.6e-16 of its terms. In
/// every system of units of [`UNITS`] and that one, no answer is now `infeasible` (a
/// proof that holds only near its point is `numerical_failure` unless the method's
/// multipliers grow along a ray of the dual); every answer σ at N = 8, 16 and 32 is the
/// same in every system to 1e-9 and falls as N grows; the exact cones answer in each,
/// to their stated bound; and σ* lies below the polyhedra with the SFCe contact's
/// latitudes refined, within 2e-3 of them (N = 128, 64 latitudes: they converge on the
/// cone).
#[test]
fn a_proof_that_holds_only_near_its_point_is_no_answer() {
    let p = fuzz_fixture("held-only-by-torques-of-3e10");
    let units = UNITS
        .iter()
        .copied()
        .chain([(122.05561425491729, 43.41573857120869)]);
    let sides = [8, 16, 32];
    // Per N, then exact: σ / k² of the first answer.
    let mut first = [None::<f64>; 4];
    for (l, f) in units {
        let q = grasp_testkit::rescale(&p, l, f);
        let at = format!("lengths × {l:e}, forces × {f:e}");
        let k2 = (l * f).powi(2);
        let mut answers: Vec<(String, Solution)> = by_sides(&q, &sides)
            .into_iter()
            .map(|(n, a)| (format!("N = {n}"), a))
            .collect();
        answers.push(("exact".into(), solved_exact(&q)));
        for (i, (n, a)) in answers.iter().enumerate() {
            assert!(
                matches!(a.status, Status::Optimal | Status::NumericalFailure)
                    || (i == 3 && a.status == Status::AlmostOptimal),
                "{at}, {n}: {:?} {:?}",
                a.status,
                a.reason
            );
            if !a.status.has_answer() {
                continue;
            }
            let sigma = a.objective / k2;
            let want = *first[i].get_or_insert(sigma);
            assert!(
                (sigma - want).abs() <= (1e-9 + stated_excess(a)) * want,
                "{at}, {n}: σ {sigma} against {want}"
            );
        }
        assert!(
            answers[3].1.status.has_answer(),
            "{at}: exact {:?}",
            answers[3].1.reason
        );
    }
    let [Some(s8), Some(s16), Some(s32), Some(star)] = first else {
        panic!("a view answered in no system of units: {first:?}");
    };
    assert!(star <= s32 && s32 <= s16 && s16 <= s8, "{first:?}");
    let mut fine = p.clone();
    fine.linearization.sides = 128;
    fine.linearization.latitudes = 64;
    let upper = solved(&fine, &SolverConfig::default());
    assert_eq!(upper.status, Status::Optimal, "{:?}", upper.reason);
    assert!(
        star <= upper.objective && upper.objective <= star * (1.0 + 2e-3),
        "σ* {star} against the fine polyhedra's {}",
        upper.objective
    );
}

/// A proof of infeasibility that the rounding of the larger torques made is no
/// answer: `fixtures/fuzz/false-proof-from-joints-1e15-apart.json` (seed 297974,
/// the torques' scales 1.3e15 apart) was `infeasible` at N = 4 and 8, and with exact
/// cones by the circumscribed polyhedra, although the same grasp with each row of Jᵀ
/// divided by its largest entry (each joint's torque in a unit of its own, which
/// leaves the admissible forces as they are) is optimal at every N for both
/// backends. The native solver now checks an `infeasible` answer with each joint's
/// torque in a unit of its own where the scales are more than 1e4 apart: in seven
/// systems of units, no answer is `infeasible`.
#[test]
fn a_proof_from_the_larger_torques_rounding_is_no_answer() {
    use grasp_torque::{Backend, Cones};
    let p = fuzz_fixture("false-proof-from-joints-1e15-apart");
    let sides = [4, 8, 16, 32];
    let units = UNITS
        .iter()
        .copied()
        .chain([(122.05561425491729, 43.41573857120869)]);
    for (l, f) in units {
        let q = grasp_testkit::rescale(&p, l, f);
        let mut answers: Vec<(String, Solution)> = by_sides(&q, &sides)
            .into_iter()
            .map(|(n, a)| (format!("N = {n}"), a))
            .collect();
        answers.push(("exact".into(), solved_exact(&q)));
        for (n, a) in &answers {
            assert_ne!(
                a.status,
                Status::Infeasible,
                "lengths × {l:e}, forces × {f:e}, {n}: {:?}",
                a.reason
            );
        }
    }
    // Each joint's torque in a unit of its own: both backends hold the grasp.
    let mut q = p.clone();
    for j in 0..q.jacobian_transpose.nrows() {
        let row = q.jacobian_transpose.row_mut(j);
        let big = row.iter().fold(0.0f64, |b, v| b.max(v.abs()));
        row.iter_mut().for_each(|v| *v /= big);
    }
    let mut backends = vec![Backend::ActiveSet];
    if cfg!(feature = "clarabel") {
        backends.push(Backend::Clarabel);
    }
    for n in sides {
        q.linearization.sides = n;
        let sigma: Vec<f64> = (backends.iter())
            .map(|&backend| {
                let config = SolverConfig {
                    backend: Some(backend),
                    cones: Cones::Linear,
                    ..Default::default()
                };
                let s = solved(&q, &config);
                assert_eq!(
                    s.status,
                    Status::Optimal,
                    "{backend:?}, N = {n}: {:?}",
                    s.reason
                );
                s.objective
            })
            .collect();
        assert!(
            sigma
                .iter()
                .all(|s| (s - sigma[0]).abs() <= 1e-9 * sigma[0]),
            "N = {n}: {sigma:?}"
        );
    }
}

/// The same check on a proof whose rows meet at the edge of their rounding:
/// `fixtures/fuzz/proof-at-roundings-edge-beside-a-row-of-1e12.json` (seed 288967,
/// a row of Jᵀ of 1.5e12 beside rows of 0.07–0.6) was `infeasible` at N = 16, from a
/// combination 0 in y to 0.95 times its rounding, and `optimal` at N = 8, whose
/// polygons N = 16's contain. Now, in each system of units that keeps the row within
/// the input's bound of 1e12, no N is `infeasible`, σ falls as N grows, and in the
/// file's units every N answers.
#[test]
fn a_proof_at_the_edge_of_its_rounding_is_checked_in_joint_units() {
    let p = fuzz_fixture("proof-at-roundings-edge-beside-a-row-of-1e12");
    let sides = [4, 8, 16, 32, 64];
    for (l, f) in UNITS.iter().copied().filter(|&(l, _)| l <= 1.0) {
        let q = grasp_testkit::rescale(&p, l, f);
        let k2 = (l * f).powi(2);
        let mut last = f64::INFINITY;
        for (n, a) in by_sides(&q, &sides) {
            let at = format!("lengths × {l:e}, forces × {f:e}, N = {n}");
            assert_ne!(a.status, Status::Infeasible, "{at}: {:?}", a.reason);
            assert!(
                a.status == Status::Optimal || (l, f) != (1.0, 1.0),
                "{at}: {:?}",
                a.reason
            );
            if a.status != Status::Optimal {
                continue;
            }
            let sigma = a.objective / k2;
            assert!(
                sigma <= last * (1.0 + 1e-9 + stated_excess(&a)),
                "{at}: σ {sigma} above fewer sides' {last}"
            );
            last = sigma;
        }
    }
}
