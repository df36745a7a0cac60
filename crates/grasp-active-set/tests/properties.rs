//! Property tests on synthetic grasps: native solutions satisfy the KKT conditions of
//! the original (unreduced) problem, warm and cold solves agree, and every optimal
//! answer holds the object.

use grasp_active_set::{ActiveSetSettings, ActiveSetSolver, Phase1};
use grasp_core::linalg::svd;
use grasp_core::matrix::{dot, norm_inf};
use grasp_core::{solve, GraspProblem, ModelOptions, Solution, Status, TorqueQp, WarmStart};
use grasp_testkit::{synthetic_grasp, SynthSpec};
use proptest::prelude::*;

fn build(p: &GraspProblem) -> ActiveSetSolver {
    let qp = TorqueQp::from_problem(p, &ModelOptions::default()).unwrap();
    ActiveSetSolver::new(qp, ActiveSetSettings::default()).unwrap()
}

fn problem(seed: u64, sides: usize) -> GraspProblem {
    let mut spec = SynthSpec::default();
    spec.linearization.sides = sides;
    synthetic_grasp(seed, &spec).into_problem().unwrap()
}

/// Checks KKT for `min Σ w τ²  s.t.  H τ ≥ c, C τ = e` from τ and the row multipliers,
/// with tolerances relative to the size of the terms involved.
fn assert_kkt(qp: &TorqueQp, w: &[f64; 6], s: &Solution) -> Result<(), TestCaseError> {
    let (m, rows) = (qp.joints(), qp.inequality_rows());
    let tau = &s.torque;
    let lam = &s.multipliers;
    prop_assert_eq!(lam.len(), rows);
    let mut c = vec![0.0; rows];
    qp.c_into(w, &mut c);
    let scale = norm_inf(&c).max(norm_inf(tau)).max(f64::MIN_POSITIVE);
    let eps = 1e-8;
    for i in 0..rows {
        let hn = grasp_core::matrix::norm2(qp.h().row(i)).max(f64::MIN_POSITIVE);
        let slack = (dot(qp.h().row(i), tau) - c[i]) / hn;
        prop_assert!(slack >= -eps * scale, "primal: row {} slack {}", i, slack);
        prop_assert!(lam[i] >= 0.0, "dual: row {} multiplier {}", i, lam[i]);
        prop_assert!(
            (lam[i] * hn * slack).abs() <= eps * scale * scale.max(lam[i] * hn),
            "complementarity: row {}",
            i
        );
    }
    // Stationarity: r = 2 W τ − Hᵀ λ lies in the range of Cᵀ, i.e. its projection on
    // null(C) vanishes.
    let mut r: Vec<f64> = (0..m).map(|j| 2.0 * qp.model.weights[j] * tau[j]).collect();
    let mut mag = norm_inf(&r);
    for i in 0..rows {
        for j in 0..m {
            r[j] -= lam[i] * qp.h()[(i, j)];
            mag = mag.max((lam[i] * qp.h()[(i, j)]).abs());
        }
    }
    let dec = svd(&qp.model.eq).unwrap();
    // The core hands over independent rows.
    let rank = qp.model.eq.nrows();
    for k in rank..m {
        let proj: f64 = (0..m).map(|j| dec.v[(j, k)] * r[j]).sum();
        prop_assert!(
            proj.abs() <= eps * mag.max(f64::MIN_POSITIVE),
            "stationarity {} vs {}",
            proj,
            mag
        );
    }
    let e_res = s.diagnostics.consistency_residual;
    prop_assert!(e_res <= eps * norm_inf(w).max(1.0), "consistency {}", e_res);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 300,
        // Fixed seed: CI and every developer see the same cases (STYLE.md).
        rng_seed: proptest::test_runner::RngSeed::Fixed(11),
        ..ProptestConfig::default()
    })]

    #[test]
    fn native_solutions_satisfy_kkt(seed in any::<u64>(), sides in prop::sample::select(vec![3usize, 4, 8, 16])) {
        let p = problem(seed, sides);
        let mut solver = build(&p);
        let s = solve(&mut solver, &p.wrench, &WarmStart::default()).unwrap();
        prop_assert!(matches!(s.status, Status::Optimal | Status::Infeasible), "{:?} {:?}", s.status, s.reason);
        if s.status == Status::Optimal {
            let qp = TorqueQp::from_problem(&p, &ModelOptions::default()).unwrap();
            assert_kkt(&qp, &p.wrench, &s)?;
            // The object is held: G f = w to rounding.
            let gscale = qp.model.grasp_matrix.max_abs() * norm_inf(&s.contact_forces) + norm_inf(&p.wrench);
            prop_assert!(s.diagnostics.wrench_residual <= 1e-9 * gscale);
            prop_assert!(s.diagnostics.friction_margins.iter().flatten().all(|&m| m >= -1e-9));
        } else {
            prop_assert!(s.torque.is_empty());
        }
    }

    #[test]
    fn warm_and_cold_solves_agree(seed in any::<u64>(), change in -0.02f64..0.02) {
        let p = problem(seed, 8);
        let mut solver = build(&p);
        let first = solve(&mut solver, &p.wrench, &WarmStart::default()).unwrap();
        prop_assume!(first.status == Status::Optimal);
        let mut w = p.wrench;
        for (i, v) in w.iter_mut().enumerate() {
            *v *= 1.0 + change * if i % 2 == 0 { 1.0 } else { -0.5 };
        }
        let cold = solve(&mut solver, &w, &WarmStart::default()).unwrap();
        let warm = solve(&mut solver, &w, &WarmStart::from_solution(&first)).unwrap();
        let warm_t = solve(&mut solver, &w, &WarmStart { torque: Some(&first.torque), active_set: None }).unwrap();
        prop_assert_eq!(cold.status, warm.status);
        prop_assert_eq!(cold.status, warm_t.status);
        if cold.status == Status::Optimal {
            for s in [&warm, &warm_t] {
                let rel = (s.objective - cold.objective).abs() / cold.objective.max(f64::MIN_POSITIVE);
                prop_assert!(rel <= 1e-9, "objective {} vs {}", s.objective, cold.objective);
                let dt = s.torque.iter().zip(&cold.torque).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                prop_assert!(dt <= 1e-6 * norm_inf(&cold.torque).max(1e-12), "torque differs by {}", dt);
            }
        }
    }
}

/// A control loop: each tick warm-started from the last answer (mostly a hot start,
/// the factor of the last key set kept), against a separate solver's cold solve.
#[test]
fn hot_started_control_loops_match_cold_solves() {
    let mut ticks = 0;
    for seed in 0..40u64 {
        let p = problem(seed, 8);
        let (mut hot, mut fresh) = (build(&p), build(&p));
        let mut last = solve(&mut hot, &p.wrench, &WarmStart::default()).unwrap();
        let mut w = p.wrench;
        for k in 0..25 {
            for (i, v) in w.iter_mut().enumerate() {
                *v *= 1.0 + 0.005 * (((seed as usize + 7 * k + 3 * i) % 5) as f64 - 2.0);
            }
            let cold = solve(&mut fresh, &w, &WarmStart::default()).unwrap();
            let warm = solve(&mut hot, &w, &WarmStart::from_solution(&last)).unwrap();
            assert_eq!(cold.status, warm.status, "seed {seed} tick {k}");
            if cold.status == Status::Optimal {
                let rel =
                    (warm.objective - cold.objective).abs() / cold.objective.max(f64::MIN_POSITIVE);
                assert!(
                    rel <= 1e-9,
                    "seed {seed} tick {k}: {} vs {}",
                    warm.objective,
                    cold.objective
                );
                ticks += 1;
            }
            last = warm;
        }
    }
    assert!(ticks > 500, "only {ticks} optimal ticks");
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 200,
        // Fixed seed: CI and every developer see the same cases (STYLE.md).
        rng_seed: proptest::test_runner::RngSeed::Fixed(12),
        ..ProptestConfig::default()
    })]

    /// The two cold starts (dual phase 1, and the paper's primal iteration with an
    /// elastic start) reach the same answer.
    #[test]
    fn both_phase1_methods_agree(seed in any::<u64>()) {
        let p = problem(seed, 8);
        let qp = TorqueQp::from_problem(&p, &ModelOptions::default()).unwrap();
        let mut dual = ActiveSetSolver::new(qp.clone(), ActiveSetSettings::default()).unwrap();
        let settings = ActiveSetSettings { phase1: Phase1::Elastic, ..Default::default() };
        let mut elastic = ActiveSetSolver::new(qp, settings).unwrap();
        let a = solve(&mut dual, &p.wrench, &WarmStart::default()).unwrap();
        let b = solve(&mut elastic, &p.wrench, &WarmStart::default()).unwrap();
        prop_assert_eq!(a.status, b.status, "{:?} / {:?}", a.reason, b.reason);
        if a.status == Status::Optimal {
            let rel = (a.objective - b.objective).abs() / a.objective.max(f64::MIN_POSITIVE);
            prop_assert!(rel <= 1e-9, "{} vs {}", a.objective, b.objective);
        }
    }
}

#[test]
fn paper_method_from_tau1_ends_at_the_published_optimum() {
    let p = grasp_io::load_problem(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/paper-example.json"
    ))
    .unwrap();
    let opts = ModelOptions {
        equilibrium: grasp_core::Equilibrium::PaperModel,
        ..Default::default()
    };
    let qp = TorqueQp::from_problem(&p, &opts).unwrap();
    let mut solver = ActiveSetSolver::new(qp, ActiveSetSettings::default()).unwrap();
    let tau1 = [7.5, -2.0, -7.5, 2.0];
    let s = solve(
        &mut solver,
        &p.wrench,
        &WarmStart {
            torque: Some(&tau1),
            active_set: None,
        },
    )
    .unwrap();
    assert_eq!(s.status, Status::Optimal);
    for (t, w) in s.torque.iter().zip([4.5, 1.0, -4.5, -1.0]) {
        assert!((t - w).abs() < 1e-12, "{:?}", s.torque);
    }
    assert!((s.objective - 42.5).abs() < 1e-11);
}

#[test]
fn consistent_paper_example_at_n4() {
    let p = grasp_io::load_problem(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/paper-example.json"
    ))
    .unwrap();
    let mut solver = build(&p);
    let s = solve(&mut solver, &p.wrench, &WarmStart::default()).unwrap();
    assert_eq!(s.status, Status::Optimal);
    for (t, w) in s.torque.iter().zip([6.0, -0.5, -6.0, 0.5]) {
        assert!((t - w).abs() < 1e-12, "{:?}", s.torque);
    }
    assert!((s.objective - 72.5).abs() < 1e-11);
    assert!(s.diagnostics.wrench_residual < 1e-13);
}

#[test]
fn infeasible_grasps_are_answers_with_reasons() {
    let p0 = grasp_io::load_problem(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/paper-example.json"
    ))
    .unwrap();
    // Torque limits far below what holding the disc needs.
    let mut p = p0.clone();
    p.torque_limits = Some(vec![Some(0.1.into()); 4]);
    let s = solve(&mut build(&p), &p.wrench, &WarmStart::default()).unwrap();
    assert_eq!(s.status, Status::Infeasible);
    assert!(s.torque.is_empty());
    let why = s.reason.unwrap().to_string();
    assert!(why.contains("torque limit"), "{why}");
    // Two frictionless fingertips pushing along ±x: no contact force has a y
    // component, so a sideways load cannot be balanced by any torque.
    let pinch = |w: &str| {
        grasp_io::parse_problem(&format!(r#"{{
          "contacts": [
            {{"position": [-0.05, 0, 0], "normal": [1, 0, 0], "model": "fpc", "finger": 0}},
            {{"position": [0.05, 0, 0], "normal": [-1, 0, 0], "model": "fpc", "finger": 1}}
          ],
          "fingers": [
            {{"joints": [{{"origin": [-0.05, 0, 0.1], "axis": [0, 1, 0]}}, {{"origin": [-0.1, 0, 0], "axis": [0, 0, 1]}}]}},
            {{"joints": [{{"origin": [0.05, 0, 0.1], "axis": [0, 1, 0]}}, {{"origin": [0.1, 0, 0], "axis": [0, 0, 1]}}]}}
          ],
          "wrench": {w}
        }}"#))
        .unwrap()
    };
    let p = pinch("[0, 1, 0, 0, 0, 0]");
    let s = solve(&mut build(&p), &p.wrench, &WarmStart::default()).unwrap();
    assert_eq!(s.status, Status::Infeasible, "{:?}", s.reason);
    assert!(
        matches!(s.reason, Some(grasp_core::Reason::UnreachableWrench { .. })),
        "{:?}",
        s.reason
    );
    // Pulling the object apart along x: fingertips can only push.
    let p = pinch("[0, 0, 0, 0, 0, 0.0]");
    let ok = solve(&mut build(&p), &p.wrench, &WarmStart::default()).unwrap();
    assert_eq!(ok.status, Status::Optimal, "{:?}", ok.reason);
    let mut p = pinch("[0, 0, 0, 0, 0, 0]");
    p.min_normal_force = Some(vec![1.0, 1.0]);
    p.torque_limits = Some(vec![Some(1e-3.into()); 4]);
    let s = solve(&mut build(&p), &p.wrench, &WarmStart::default()).unwrap();
    assert_eq!(s.status, Status::Infeasible, "{:?}", s.reason);
}

#[test]
fn minimum_normal_force_and_weights_are_honoured() {
    let mut p = grasp_io::load_problem(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/paper-example.json"
    ))
    .unwrap();
    p.min_normal_force = Some(vec![5.0, 5.0]);
    p.torque_weights = Some(vec![1.0, 4.0, 1.0, 4.0]);
    let s = solve(&mut build(&p), &p.wrench, &WarmStart::default()).unwrap();
    assert_eq!(s.status, Status::Optimal);
    assert!(s.contact_forces[2] >= 5.0 - 1e-9 && s.contact_forces[6] >= 5.0 - 1e-9);
    let expect: f64 = s
        .torque
        .iter()
        .zip([1.0, 4.0, 1.0, 4.0])
        .map(|(t, w)| w * t * t)
        .sum();
    assert!((s.objective - expect).abs() < 1e-12);
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 100,
        // Fixed seed: CI and every developer see the same cases (STYLE.md).
        rng_seed: proptest::test_runner::RngSeed::Fixed(13),
        ..ProptestConfig::default()
    })]

    /// An iteration cap is a status, never a panic, and any torque handed back with it
    /// satisfies every row.
    #[test]
    fn iteration_limit_returns_only_feasible_points(seed in any::<u64>(), cap in 1usize..6, elastic in any::<bool>()) {
        let p = problem(seed, 8);
        let qp = TorqueQp::from_problem(&p, &ModelOptions::default()).unwrap();
        let settings = ActiveSetSettings {
            max_iterations: cap,
            phase1: if elastic { Phase1::Elastic } else { Phase1::Dual },
            ..Default::default()
        };
        let mut solver = ActiveSetSolver::new(qp, settings).unwrap();
        let s = solve(&mut solver, &p.wrench, &WarmStart::default()).unwrap();
        prop_assert!(s.iterations <= cap);
        if !s.torque.is_empty() {
            let scale = norm_inf(&p.wrench).max(norm_inf(&s.contact_forces)).max(1e-12);
            prop_assert!(s.diagnostics.max_violation <= 1e-8 * scale, "{:?}: violation {}", s.status, s.diagnostics.max_violation);
        }
    }
}
