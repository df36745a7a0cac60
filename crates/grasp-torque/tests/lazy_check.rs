//! `Check::Lazy`, the control-loop setting: on every bundled grasp and reference case,
//! linear and exact cones, a control loop with the lazy check gives the same statuses,
//! torques and σ as one with the full check, and `diagnose` then gives the same forces
//! and diagnostics; batches follow the configured check. A backend whose answer is not
//! finite is never `optimal`, and one whose certificate lied is caught by `diagnose`.
#![cfg(feature = "active-set")]

use grasp_torque::{
    Capabilities, Check, Cones, GraspProblem, GraspSolver, Reason, Solution, SolverConfig, Status,
    TorqueQp, TorqueSolver, WarmStart,
};

fn problems() -> Vec<(String, GraspProblem)> {
    let mut v: Vec<(String, GraspProblem)> =
        grasp_testkit::fixture_paths(&["", "hands", "table1", "geometry"])
            .iter()
            .map(|p| {
                let problem = grasp_torque::load_problem(p).unwrap();
                (p.display().to_string(), problem)
            })
            .collect();
    for case in grasp_testkit::reference_cases() {
        let name = case["name"].as_str().unwrap_or("reference").to_string();
        let problem = match case.get("problem") {
            Some(p) => grasp_testkit::reference_problem(p),
            None => grasp_testkit::reference_geometry(&case["geometry"]),
        };
        v.push((name, problem));
    }
    v
}

/// The wrench of tick `k`: alternately the problem's own and one 1 % away.
fn tick(w: &[f64; 6], k: usize) -> [f64; 6] {
    std::array::from_fn(|i| {
        if k % 2 == 1 {
            w[i] * if i < 3 { 1.01 } else { 0.99 }
        } else {
            w[i]
        }
    })
}

#[test]
fn lazy_answers_equal_full_ones_and_diagnose_completes_them() {
    let problems = problems();
    assert!(problems.len() >= 50, "{}", problems.len());
    let (mut deferred, mut answers) = (0, 0);
    for cones in [Cones::Linear, Cones::Exact] {
        for (label, p) in &problems {
            let config = |check| SolverConfig {
                cones,
                check,
                ..Default::default()
            };
            let mut full = GraspSolver::new(p, &config(Check::Full)).unwrap();
            let mut lazy = GraspSolver::new(p, &config(Check::Lazy)).unwrap();
            for k in 0..6 {
                let w = tick(&p.wrench, k);
                let a = full.resolve(&w).unwrap().clone();
                let b = lazy.resolve(&w).unwrap().clone();
                let at = format!("{label} ({cones}), tick {k}");
                assert_eq!(a.status, b.status, "{at}");
                assert_eq!(a.torque, b.torque, "{at}");
                assert_eq!(a.objective.to_bits(), b.objective.to_bits(), "{at}");
                assert!(!a.diagnostics.deferred, "{at}");
                if b.diagnostics.deferred {
                    deferred += 1;
                    assert!(b.is_optimal() && b.contact_forces.is_empty(), "{at}");
                } else {
                    // Only answers that are not optimal get the full check at once.
                    assert!(!b.is_optimal(), "{at}");
                }
                answers += usize::from(a.is_optimal());
                let c = lazy.diagnose().clone();
                assert_eq!(a.status, c.status, "{at}");
                assert_eq!(a.contact_forces, c.contact_forces, "{at}");
                assert_eq!(a.diagnostics, c.diagnostics, "{at}");
                assert_eq!(a.warnings, c.warnings, "{at}");
            }
        }
    }
    // Every optimal answer of the native backend was deferred.
    assert_eq!(deferred, answers);
    assert!(answers > 500, "{answers}");
}

/// The native backend with its answer changed afterwards, still claiming to certify.
struct Tampered {
    inner: Box<dyn TorqueSolver>,
    change: fn(&mut Solution),
    /// A fallback: the inner solver's cold answer, changed so.
    fallback: Option<fn(&mut Solution)>,
}

impl TorqueSolver for Tampered {
    fn name(&self) -> &'static str {
        "tampered"
    }
    fn capabilities(&self) -> Capabilities {
        self.inner.capabilities()
    }
    fn residual_tolerance(&self) -> f64 {
        self.inner.residual_tolerance()
    }
    fn problem(&self) -> &TorqueQp {
        self.inner.problem()
    }
    fn solve_raw(&mut self, w: &[f64; 6], warm: &WarmStart<'_>, out: &mut Solution) {
        self.inner.solve_raw(w, warm, out);
        (self.change)(out);
    }
    fn solve_fallback(&mut self, w: &[f64; 6], out: &mut Solution) -> bool {
        let Some(change) = self.fallback else {
            return false;
        };
        self.inner.solve_raw(w, &WarmStart::default(), out);
        change(out);
        true
    }
}

/// Whether the untampered solver finds an optimum (only those are tampered with).
fn solvable(p: &GraspProblem) -> bool {
    let mut s = GraspSolver::new(p, &SolverConfig::default()).unwrap();
    s.solve(&p.wrench, &WarmStart::default())
        .unwrap()
        .is_optimal()
}

/// The answer moved along the joint with the largest torque by a tenth of it: a row
/// the optimum holds must now fail (as in tests/residual_check.rs), while the backend
/// still calls it optimal.
fn lie(s: &mut Solution) {
    if let Some(j) =
        (0..s.torque.len()).max_by(|&a, &b| s.torque[a].abs().total_cmp(&s.torque[b].abs()))
    {
        s.torque[j] *= 1.1;
    }
}

fn tampered(p: &GraspProblem, change: fn(&mut Solution)) -> GraspSolver {
    with_fallback(p, change, None).with_check(Check::Lazy)
}

/// The default solver's backend, its answers changed by `change`, with `fallback`.
fn with_fallback(
    p: &GraspProblem,
    change: fn(&mut Solution),
    fallback: Option<fn(&mut Solution)>,
) -> GraspSolver {
    let config = SolverConfig::default();
    let inner = config.build(config.qp(p).unwrap()).unwrap();
    assert!(inner.capabilities().certifies_rows);
    GraspSolver::from_backend(Box::new(Tampered {
        inner,
        change,
        fallback,
    }))
}

/// A refused answer's report: the fallback's answer where it `passes`, with a warning
/// that says so, else the first refusal's, with one that says the fallback failed.
fn assert_fell_back(label: &str, s: &Solution, passes: bool) {
    let said = |what: &str| s.warnings.iter().any(|w| w.contains(what));
    if passes {
        assert_eq!(s.status, Status::Optimal, "{label}: {:?}", s.reason);
        assert!(
            said("this one is its fallback's"),
            "{label}: {:?}",
            s.warnings
        );
    } else {
        assert_eq!(s.status, Status::NumericalFailure, "{label}");
        assert!(
            matches!(s.reason, Some(Reason::ResidualCheck { .. })),
            "{label}: {:?}",
            s.reason
        );
        assert!(said("gave no answer either"), "{label}: {:?}", s.warnings);
    }
}

/// An answer the check refuses goes to the backend's fallback, checked in full: its
/// answer where it passes (with a warning that says so), else the first refusal's
/// report.
#[test]
fn a_refused_answer_goes_to_the_fallback_and_only_a_passing_one_replaces_it() {
    for (label, p) in problems().into_iter().filter(|(_, p)| solvable(p)) {
        let nan: fn(&mut Solution) = |s| s.torque[0] = f64::NAN;
        let keep: fn(&mut Solution) = |_| {};
        for (fallback, passes) in [(keep, true), (nan, false)] {
            let mut s = with_fallback(&p, nan, Some(fallback));
            let a = s.solve(&p.wrench, &WarmStart::default()).unwrap();
            assert_fell_back(&label, a, passes);
        }
    }
}

#[test]
fn a_lazy_check_never_calls_a_non_finite_answer_optimal() {
    for (label, p) in problems().into_iter().filter(|(_, p)| solvable(p)) {
        for change in [
            (|s: &mut Solution| s.torque[0] = f64::NAN) as fn(&mut Solution),
            |s| s.torque[0] = f64::INFINITY,
            |s| s.torque[0] = 1e300,
        ] {
            let mut s = tampered(&p, change);
            let a = s.solve(&p.wrench, &WarmStart::default()).unwrap();
            assert_eq!(a.status, Status::NumericalFailure, "{label}");
            assert!(!a.diagnostics.deferred, "{label}");
            assert!(
                matches!(a.reason, Some(Reason::ResidualCheck { .. })),
                "{label}: {:?}",
                a.reason
            );
        }
    }
}

#[test]
fn diagnose_catches_an_answer_whose_certificate_lied() {
    for (label, p) in problems().into_iter().filter(|(_, p)| solvable(p)) {
        let mut s = tampered(&p, lie);
        let a = s.solve(&p.wrench, &WarmStart::default()).unwrap();
        if a.torque.iter().all(|&t| t == 0.0) {
            continue;
        }
        // Lazy trusts the backend's certificate, by design ...
        assert_eq!(a.status, Status::Optimal, "{label}");
        assert!(a.diagnostics.deferred, "{label}");
        // ... and the deferred check does not.
        let d = s.diagnose();
        assert_eq!(d.status, Status::NumericalFailure, "{label}");
        assert!(!d.diagnostics.deferred, "{label}");
        assert!(!d.contact_forces.is_empty(), "{label}");
    }
}

/// `diagnose` completes a deferred answer as the full check would have: a refusal goes
/// to the backend's fallback, whose answer replaces the first only where it passes.
#[test]
fn diagnose_sends_a_refused_answer_to_the_fallback() {
    let nan: fn(&mut Solution) = |s| s.torque[0] = f64::NAN;
    let keep: fn(&mut Solution) = |_| {};
    for (label, p) in problems().into_iter().filter(|(_, p)| solvable(p)) {
        let mut full = GraspSolver::new(&p, &SolverConfig::default()).unwrap();
        let want = full
            .solve(&p.wrench, &WarmStart::default())
            .unwrap()
            .clone();
        if want.torque.iter().all(|&t| t == 0.0) {
            continue;
        }
        for (fallback, passes) in [(keep, true), (nan, false)] {
            let mut s = with_fallback(&p, lie, Some(fallback)).with_check(Check::Lazy);
            assert!(
                s.resolve(&p.wrench).unwrap().diagnostics.deferred,
                "{label}"
            );
            let d = s.diagnose().clone();
            assert!(!d.diagnostics.deferred, "{label}");
            assert_fell_back(&label, &d, passes);
            if passes {
                assert_eq!(d.torque, want.torque, "{label}");
                assert_eq!(d.contact_forces, want.contact_forces, "{label}");
            }
            // A full answer is left as it is.
            let again = s.diagnose();
            assert_eq!(
                (again.status, &again.torque),
                (d.status, &d.torque),
                "{label}"
            );
            assert_eq!(again.warnings, d.warnings, "{label}");
        }
    }
}

#[cfg(feature = "clarabel")]
#[test]
fn backends_that_do_not_certify_their_rows_get_the_full_check() {
    use grasp_torque::Backend;
    let p = grasp_torque::load_problem(
        grasp_testkit::fixture_paths(&[""])
            .into_iter()
            .find(|p| p.ends_with("hand3-pcwf.json"))
            .unwrap(),
    )
    .unwrap();
    let config = SolverConfig {
        backend: Some(Backend::Clarabel),
        check: Check::Lazy,
        ..Default::default()
    };
    let mut s = GraspSolver::new(&p, &config).unwrap();
    let a = s.resolve(&p.wrench).unwrap();
    assert_eq!(a.status, Status::Optimal);
    assert!(!a.diagnostics.deferred);
    assert!(!a.contact_forces.is_empty());
}

#[test]
fn batches_follow_the_configured_check() {
    use grasp_torque::{solve_batch, BatchGrasp, BatchOptions};
    let grasps: Vec<BatchGrasp> = problems()
        .into_iter()
        .map(|(_, problem)| {
            let wrenches = (0..4).map(|k| tick(&problem.wrench, k)).collect();
            BatchGrasp { problem, wrenches }
        })
        .collect();
    let run = |check| {
        let config = SolverConfig {
            check,
            ..Default::default()
        };
        solve_batch(&grasps, &config, &BatchOptions::default()).unwrap()
    };
    let (full, lazy) = (run(Check::Full), run(Check::Lazy));
    assert_eq!(full.len(), lazy.len());
    for (a, b) in full.iter().zip(&lazy) {
        let (a, b) = (a.outcome.as_ref().unwrap(), b.outcome.as_ref().unwrap());
        assert_eq!((a.status, &a.torque), (b.status, &b.torque));
        assert_eq!(b.diagnostics.deferred, b.is_optimal());
        assert!(!a.diagnostics.deferred);
    }
}
