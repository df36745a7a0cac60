//! Iterations of the two cold starts (docs/solver.md): the dual phase 1 (default) and
//! the paper's primal iteration with an elastic start, on the 123 linearised reference
//! problems (41 grasps × N = 4, 8, 16).
//!
//! Run: `cargo run --release -p grasp-torque --example phase1`

use grasp_torque::file::MatrixFile;
use grasp_torque::{
    solve, ActiveSetSettings, ActiveSetSolver, ModelOptions, Phase1, TorqueQp, WarmStart,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = concat!(
        concat!(env!("CARGO_MANIFEST_DIR"), "/../.."),
        "/tests/data/reference-cases.json"
    );
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path)?)?;
    for phase1 in [Phase1::Dual, Phase1::Elastic] {
        let (mut iterations, mut solves, mut worst) = (0, 0, 0);
        for case in v["cases"].as_array().ok_or("no cases")? {
            let file: MatrixFile = serde_json::from_value(case["problem"].clone())?;
            let mut p = file.into_problem()?;
            for n in [4, 8, 16] {
                p.linearization.sides = n;
                let qp = TorqueQp::from_problem(&p, &ModelOptions::default())?;
                let mut s = ActiveSetSolver::new(
                    qp,
                    ActiveSetSettings {
                        phase1,
                        ..Default::default()
                    },
                )?;
                let sol = solve(&mut s, &p.wrench, &WarmStart::default())?;
                iterations += sol.iterations;
                worst = worst.max(sol.iterations);
                solves += 1;
            }
        }
        println!(
            "{phase1:?}: {solves} solves, {:.1} iterations per solve on average, {worst} at most",
            iterations as f64 / solves as f64
        );
    }
    Ok(())
}
