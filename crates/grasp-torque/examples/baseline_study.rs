//! How much the torque-space optimum saves over the contact-force optimum mapped
//! through Jᵀ, on 2000 synthetic grasps per hand type (docs/experiments.md).
//!
//! Run: `cargo run --release -p grasp-torque --example baseline_study`

use grasp_testkit::{synthetic_grasp, ModelMix, SynthSpec};
use grasp_torque::file::ModelName;
use grasp_torque::{
    solve, ActiveSetSettings, ActiveSetSolver, ForceSpaceQp, ForceSpaceSolver, ModelOptions,
    Solution, Status, TorqueQp, WarmStart,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let pcwf = ModelMix::Only(ModelName::Pcwf);
    let hands = [
        (
            "3 fingers × 3 joints, PCwF (Table 1's hand)",
            Some(3),
            Some(3),
            pcwf,
        ),
        ("4 fingers × 4 joints, PCwF", Some(4), Some(4), pcwf),
        (
            "2–5 fingers × 2–4 joints, mixed models",
            None,
            None,
            ModelMix::Mixed,
        ),
    ];
    println!("| hand | grasps solved | baseline inadmissible | σ reduction: min | 25 % | median | 75 % | max | share > 1 % |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for (label, fingers, joints, models) in hands {
        let spec = SynthSpec {
            fingers,
            joints_per_finger: joints,
            models,
            ..Default::default()
        };
        let (mut reductions, mut inadmissible, mut solved) = (Vec::new(), 0, 0);
        for seed in 0..2000u64 {
            let p = synthetic_grasp(seed, &spec).into_problem()?;
            let opts = ModelOptions::default();
            let qp = TorqueQp::from_problem(&p, &opts)?;
            let settings = ActiveSetSettings::default();
            let after = solve(
                &mut ActiveSetSolver::new(qp.clone(), settings)?,
                &p.wrench,
                &WarmStart::default(),
            )?;
            let base_qp = ForceSpaceQp::new(qp.model.clone(), &p.linearization)?;
            let mut base = Solution::default();
            ForceSpaceSolver::new(base_qp, settings)?.solve(&p.wrench, &mut base);
            if after.status != Status::Optimal || base.status != Status::Optimal {
                continue;
            }
            solved += 1;
            let tau_b = p.jacobian_transpose.mul_vec(&base.torque);
            let mut check = Solution {
                torque: tau_b.clone(),
                ..Default::default()
            };
            qp.complete(&p.wrench, 1e-9, "baseline", &mut check);
            if check.diagnostics.consistency_residual > 1e-9
                || check.diagnostics.max_violation > 1e-9
            {
                inadmissible += 1;
                continue;
            }
            let sigma_b: f64 = tau_b.iter().map(|t| t * t).sum();
            reductions.push((100.0 * (sigma_b - after.objective) / sigma_b).max(0.0));
        }
        reductions.sort_by(f64::total_cmp);
        let q = |f: f64| reductions[((reductions.len() - 1) as f64 * f).round() as usize];
        let share =
            reductions.iter().filter(|&&r| r > 1.0).count() as f64 / reductions.len() as f64;
        println!(
            "| {label} | {solved} | {inadmissible} | {:.1} % | {:.1} % | {:.1} % | {:.1} % | {:.1} % | {:.0} % |",
            q(0.0),
            q(0.25),
            q(0.5),
            q(0.75),
            q(1.0),
            100.0 * share
        );
    }
    Ok(())
}
