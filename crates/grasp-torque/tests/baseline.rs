//! The inequality behind the paper's claim: over the same admissible torques, the
//! torque-space optimum's σ is never above that of the contact-force optimum mapped
//! through Jᵀ, whenever that mapped torque is itself admissible.

use grasp_testkit::{synthetic_grasp, SynthSpec};
use grasp_torque::matrix::norm_inf;
use grasp_torque::{
    load_problem, solve, ActiveSetSettings, ActiveSetSolver, ForceSpaceQp, ForceSpaceSolver,
    GraspProblem, ModelOptions, Solution, Status, TorqueQp, WarmStart,
};
use proptest::prelude::*;

fn native(qp: TorqueQp, w: &[f64; 6]) -> Solution {
    let mut s = ActiveSetSolver::new(qp, ActiveSetSettings::default()).unwrap();
    solve(&mut s, w, &WarmStart::default()).unwrap()
}

/// (σ after, σ before, baseline admissible), or None when either side is infeasible.
fn both(p: &GraspProblem) -> Option<(f64, f64, bool)> {
    let opts = ModelOptions::default();
    let qp = TorqueQp::from_problem(p, &opts).unwrap();
    let after = native(qp.clone(), &p.wrench);
    let fs = ForceSpaceQp::new(qp.model.clone(), &p.linearization).unwrap();
    let mut base = Solution::default();
    ForceSpaceSolver::new(fs, ActiveSetSettings::default())
        .unwrap()
        .solve(&p.wrench, &mut base);
    if after.status != Status::Optimal || base.status != Status::Optimal {
        return None;
    }
    // The force-space answer satisfies its own constraints.
    let gf = p.grasp_matrix.mul_vec(&base.torque);
    let wres = gf
        .iter()
        .zip(&p.wrench)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(wres <= 1e-9 * norm_inf(&p.wrench).max(1.0));
    let tau_b = p.jacobian_transpose.mul_vec(&base.torque);
    let mut check = Solution {
        torque: tau_b.clone(),
        ..Default::default()
    };
    qp.complete(&p.wrench, 1e-9, "baseline", &mut check);
    let tol = 1e-9
        * norm_inf(&p.wrench)
            .max(norm_inf(&check.contact_forces))
            .max(1e-12);
    let admissible =
        check.diagnostics.consistency_residual <= tol && check.diagnostics.max_violation <= tol;
    let sigma_b: f64 = tau_b.iter().map(|t| t * t).sum();
    Some((after.objective, sigma_b, admissible))
}

#[test]
fn table1_fixtures_never_get_worse() {
    let mut n = 0;
    for path in grasp_testkit::fixture_paths(&["table1"]) {
        let p = load_problem(&path).unwrap();
        let (after, before, admissible) = both(&p).unwrap_or_else(|| panic!("{path:?} infeasible"));
        assert!(admissible, "{path:?}: baseline torque not admissible");
        assert!(
            after <= before * (1.0 + 1e-9),
            "{path:?}: {after} > {before}"
        );
        n += 1;
    }
    assert_eq!(n, 6);
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 200,
        // Fixed seed: CI and every developer see the same cases (STYLE.md).
        rng_seed: proptest::test_runner::RngSeed::Fixed(31),
        ..ProptestConfig::default()
    })]

    #[test]
    fn torque_space_optimum_is_never_above_the_admissible_baseline(seed in any::<u64>()) {
        let p = synthetic_grasp(seed, &SynthSpec::default()).into_problem().unwrap();
        if let Some((after, before, admissible)) = both(&p) {
            if admissible {
                prop_assert!(after <= before * (1.0 + 1e-9) + 1e-15, "{} > {}", after, before);
            }
        }
    }
}
