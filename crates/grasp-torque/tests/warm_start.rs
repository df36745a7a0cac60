//! A warm start that does not fit the problem is an `Err` naming what is wrong, wherever
//! the bad entry sits (the checks run four lanes at a time).
#![cfg(feature = "active-set")]

use grasp_torque::{Error, GraspSolver, SolverConfig, WarmStart, WarmStartError};

#[test]
fn warm_starts_that_do_not_fit_are_errors() {
    // 20 and 9 joints: whole blocks of four, and a remainder.
    for name in ["hand5-pcwf.json", "hand3-pcwf.json"] {
        let path = grasp_testkit::fixture_paths(&[""])
            .into_iter()
            .find(|p| p.ends_with(name))
            .unwrap();
        misfits_are_errors(&grasp_torque::load_problem(path).unwrap());
    }
}

fn misfits_are_errors(p: &grasp_torque::GraspProblem) {
    let mut s = GraspSolver::new(p, &SolverConfig::default()).unwrap();
    let good = s.solve(&p.wrench, &WarmStart::default()).unwrap().clone();
    let m = good.torque.len();
    let rows = s.problem().inequality_rows();
    for index in 0..m {
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut t = good.torque.clone();
            t[index] = bad;
            let warm = WarmStart {
                torque: Some(&t),
                active_set: None,
            };
            match s.solve(&p.wrench, &warm) {
                Err(Error::WarmStart(WarmStartError::TorqueNotFinite { index: i })) => {
                    assert_eq!(i, index)
                }
                other => panic!("torque[{index}] = {bad}: {:?}", other.map(|s| s.status)),
            }
        }
    }
    let short = vec![0.0; m - 1];
    let warm = WarmStart {
        torque: Some(&short),
        active_set: None,
    };
    assert!(matches!(
        s.solve(&p.wrench, &warm),
        Err(Error::WarmStart(WarmStartError::TorqueLength { expected, found }))
            if expected == m && found == m - 1
    ));
    let set = good.active_set.clone().unwrap();
    assert!(!set.is_empty());
    for pos in 0..set.len() {
        let mut a = set.clone();
        a[pos] = rows + pos;
        let warm = WarmStart {
            torque: None,
            active_set: Some(&a),
        };
        match s.solve(&p.wrench, &warm) {
            Err(Error::WarmStart(WarmStartError::ActiveSetRow { row, rows: r })) => {
                assert_eq!((row, r), (rows + pos, rows))
            }
            other => panic!("active set [{pos}]: {:?}", other.map(|s| s.status)),
        }
    }
    // The good ones still solve, to the same answer.
    let warm = WarmStart::from_solution(&good);
    let again = s.solve(&p.wrench, &warm).unwrap();
    assert!((again.objective - good.objective).abs() <= 1e-12 * good.objective);
}
