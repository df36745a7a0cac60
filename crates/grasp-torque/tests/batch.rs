//! Batch solving against one-by-one solves: the same answers item by item, input order,
//! per-item statuses and errors, thread counts and pools that change nothing.

use grasp_testkit::{reference_cases, reference_geometry, reference_problem};
use grasp_torque::{
    for_each_index, for_each_solution, load_problem, solve_batch, BatchError, BatchGrasp,
    BatchOptions, GraspProblem, GraspSolver, SolverConfig, Status, WarmStart,
};
use std::sync::Mutex;

fn fixture(name: &str) -> GraspProblem {
    load_problem(format!(
        "{}/fixtures/{name}.json",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../..")
    ))
    .unwrap()
}

const FIXTURES: [&str; 8] = [
    "paper-example",
    "hand3-pcwf",
    "hand5-pcwf",
    "hand4-sfcl",
    "hand4-sfce",
    "hand5-mixed",
    "hands/allegro-pinch",
    "hands/ability-tripod",
];

/// Six load directions around the problem's own wrench, as DexGraspBench checks them:
/// ± a tenth of its force magnitude along each axis.
fn load_directions(w: &[f64; 6]) -> Vec<[f64; 6]> {
    let f = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt().max(1.0);
    (0..6)
        .map(|d| {
            let mut v = *w;
            v[d / 2] += if d % 2 == 0 { 0.1 } else { -0.1 } * f;
            v
        })
        .collect()
}

/// Every bundled fixture, and every reference case, each with six wrenches.
fn grasps() -> Vec<BatchGrasp> {
    let mut out: Vec<BatchGrasp> = FIXTURES
        .iter()
        .map(|n| {
            let problem = fixture(n);
            BatchGrasp {
                wrenches: load_directions(&problem.wrench),
                problem,
            }
        })
        .collect();
    for case in reference_cases() {
        let problem = if case.get("problem").is_some() {
            reference_problem(&case["problem"])
        } else {
            reference_geometry(&case["geometry"])
        };
        out.push(BatchGrasp {
            wrenches: load_directions(&problem.wrench),
            problem,
        });
    }
    out
}

/// The one-by-one answer: a fresh solver, cold (the problem's initial torque aside).
fn alone(p: &GraspProblem, w: &[f64; 6], config: &SolverConfig) -> (Status, f64) {
    let mut s = GraspSolver::new(p, config).unwrap();
    let warm = WarmStart {
        torque: p.initial_torque.as_deref(),
        active_set: None,
    };
    let sol = s.solve(w, &warm).unwrap();
    (sol.status, sol.objective)
}

#[test]
fn batch_answers_match_one_by_one_solves_in_input_order() {
    let grasps = grasps();
    let config = SolverConfig::default();
    let results = solve_batch(&grasps, &config, &BatchOptions::default()).unwrap();
    assert_eq!(results.len(), grasps.len() * 6);
    let mut optimal = 0;
    for (i, r) in results.iter().enumerate() {
        assert_eq!((r.grasp, r.wrench), (i / 6, i % 6), "input order");
        let g = &grasps[r.grasp];
        let sol = r.outcome.as_ref().expect("every grasp here is valid");
        let (status, objective) = alone(&g.problem, &g.wrenches[r.wrench], &config);
        assert_eq!(sol.status, status, "grasp {} wrench {}", r.grasp, r.wrench);
        if status.has_answer() {
            optimal += 1;
            // Warm and cold paths agree to rounding of σ.
            let tol = 1e-9 * sol.objective.abs().max(objective.abs()) + 1e-300;
            assert!(
                (sol.objective - objective).abs() <= tol,
                "grasp {} wrench {}: batch σ {} vs alone {}",
                r.grasp,
                r.wrench,
                sol.objective,
                objective
            );
            assert!(sol.diagnostics.wrench_check <= 1.0);
        }
    }
    // The load directions are mostly holdable: the comparison is not vacuous.
    assert!(
        optimal > results.len() / 2,
        "{optimal} of {}",
        results.len()
    );
}

#[test]
fn a_bad_or_infeasible_grasp_does_not_fail_the_batch() {
    let good = fixture("hand3-pcwf");
    let mut bad = good.clone();
    bad.grasp_matrix[(2, 4)] = f64::NAN;
    let mut wrong_size = good.clone();
    wrong_size.contacts.pop();
    let mut infeasible = good.clone();
    // A wrench no fingertip contact can resist with torques this small.
    infeasible.torque_limits = Some(vec![Some(1e-6.into()); infeasible.joints()]);
    let mut nan_wrench = BatchGrasp::new(good.clone());
    nan_wrench.wrenches = vec![
        good.wrench,
        [f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0],
        good.wrench,
    ];
    let grasps = vec![
        BatchGrasp::new(good.clone()),
        BatchGrasp {
            problem: bad,
            wrenches: vec![good.wrench; 2],
        },
        BatchGrasp::new(wrong_size),
        BatchGrasp::new(infeasible),
        nan_wrench,
        BatchGrasp::new(good),
    ];
    let r = solve_batch(&grasps, &SolverConfig::default(), &BatchOptions::default()).unwrap();
    let summary: Vec<String> = r
        .iter()
        .map(|r| match &r.outcome {
            Ok(s) => s.status.to_string(),
            Err(e) => format!("error: {e}"),
        })
        .collect();
    assert_eq!(r.len(), 9, "{summary:?}");
    assert_eq!(summary[0], "optimal");
    assert!(
        summary[1].contains("grasp_matrix") && summary[1] == summary[2],
        "{summary:?}"
    );
    assert!(summary[3].starts_with("error: "), "{summary:?}");
    assert_eq!(summary[4], "infeasible");
    assert_eq!(summary[5], "optimal");
    assert!(summary[6].contains("wrench[0]"), "{summary:?}");
    // The wrench after a bad one starts from the last good answer.
    assert_eq!(summary[7], "optimal");
    assert_eq!(summary[8], "optimal");
    let reason = r[4].outcome.as_ref().unwrap().reason.as_ref().unwrap();
    assert!(!reason.to_string().is_empty());
}

#[test]
fn thread_counts_and_pools_change_nothing() {
    let grasps = grasps();
    let config = SolverConfig::default();
    let objectives = |opts: BatchOptions| -> Vec<(Status, u64)> {
        solve_batch(&grasps, &config, &opts)
            .unwrap()
            .into_iter()
            .map(|r| {
                let s = r.outcome.unwrap();
                (s.status, s.objective.to_bits())
            })
            .collect()
    };
    let base = objectives(BatchOptions {
        threads: Some(1),
        ..Default::default()
    });
    assert_eq!(
        base,
        objectives(BatchOptions {
            threads: Some(3),
            ..Default::default()
        }),
        "bitwise: each grasp is solved in order by one worker"
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    assert_eq!(base, pool.install(|| objectives(BatchOptions::default())));
    // Cold wrenches: the same optima to rounding.
    let cold = objectives(BatchOptions {
        warm_start: false,
        ..Default::default()
    });
    for (a, b) in base.iter().zip(&cold) {
        assert_eq!(a.0, b.0);
        let (x, y) = (f64::from_bits(a.1), f64::from_bits(b.1));
        assert!((x - y).abs() <= 1e-9 * x.abs().max(y.abs()), "{x} vs {y}");
    }
    let err = solve_batch(
        &grasps,
        &config,
        &BatchOptions {
            threads: Some(0),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(err, BatchError::NoThreads), "{err}");
    let err = solve_batch(
        &grasps,
        &config,
        &BatchOptions {
            threads: Some(1_000_000),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(err.to_string().contains("at most 1024"), "{err}");
    assert!(err.to_string().contains("threads"), "{err}");
}

#[test]
fn for_each_solution_sees_every_pair_once() {
    let grasps = grasps();
    let seen = Mutex::new(vec![0u32; grasps.len() * 6]);
    for_each_solution(
        &grasps[..],
        &SolverConfig::default(),
        &BatchOptions::default(),
        |g, k, r| {
            assert!(r.is_ok());
            seen.lock().unwrap()[g * 6 + k] += 1;
        },
    )
    .unwrap();
    assert!(seen.into_inner().unwrap().iter().all(|&c| c == 1));
}

#[test]
fn for_each_index_visits_every_index_once_on_any_pool() {
    for threads in [None, Some(1), Some(2), Some(3)] {
        let options = BatchOptions {
            threads,
            ..BatchOptions::default()
        };
        let seen = Mutex::new(vec![0u32; 1000]);
        for_each_index(1000, &options, |i| seen.lock().unwrap()[i] += 1).unwrap();
        assert!(
            seen.into_inner().unwrap().iter().all(|&c| c == 1),
            "{threads:?}"
        );
    }
    let none = BatchOptions {
        threads: Some(0),
        ..BatchOptions::default()
    };
    assert!(matches!(
        for_each_index(3, &none, |_| {}),
        Err(BatchError::NoThreads)
    ));
}
