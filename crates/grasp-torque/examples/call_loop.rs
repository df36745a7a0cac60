//! One kind of call in a loop, for instruction counts (valgrind) and profiles (perf),
//! which are steadier on a shared machine than timings: `scripts/instructions.sh`.
//!
//! Run: `cargo run --release -p grasp-torque --example call_loop -- FILE KIND N [exact]`
//! with KIND one of `cold` (the backend alone from a cold start), `check` (the core's
//! completion and residual check of that answer), `full` (`GraspSolver::solve`),
//! `lazy` (a cold solve with `Check::Lazy`), `warm` (the backend from the answer for a
//! wrench 1 % away, alternating: forces up, moments down), `tick` and `tick-full`
//! (`GraspSolver::resolve` on the same alternating wrenches, with `Check::Lazy` and
//! `Check::Full`) and `build` (`GraspSolver::new`); the linear view at N = 8 unless
//! `exact`. `pose` (a hand-form FILE) poses its grasp at every joint's 0.1
//! (`HandGrasps::pose`, a planner's batch's work per candidate before the build).

use grasp_torque::{
    solve_into, solve_into_with, Check, Cones, GraspSolver, Solution, SolverConfig, WarmStart,
};
use std::hint::black_box;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, file, kind, n, rest @ ..] = args.as_slice() else {
        return Err(
            "usage: call_loop FILE cold|check|full|lazy|warm|tick|tick-full|build|pose N [exact]"
                .into(),
        );
    };
    let n: usize = n.parse()?;
    if kind == "pose" {
        let hand: grasp_torque::HandFile = serde_json::from_str(&std::fs::read_to_string(file)?)?;
        let dir = std::path::Path::new(file)
            .parent()
            .unwrap_or(std::path::Path::new("."));
        let robot = grasp_torque::Robot::load(&hand.model_path(dir))?;
        let grasps = hand.grasps(&robot)?;
        let q = vec![0.1; robot.independent.len()];
        for _ in 0..n {
            black_box(grasps.pose(&grasp_torque::hand::GraspPose {
                joint_positions: black_box(&q),
                ..Default::default()
            })?);
        }
        return Ok(());
    }
    let mut p = grasp_torque::load(file)?.problem;
    p.linearization.sides = 8;
    let config = SolverConfig {
        cones: if rest.first().is_some_and(|a| a == "exact") {
            Cones::Exact
        } else {
            Cones::Linear
        },
        ..Default::default()
    };
    let mut solver = GraspSolver::new(&p, &config)?;
    let mut backend = config.build(solver.problem().clone())?;
    let cold = WarmStart::default();
    let mut answer = Solution::default();
    solve_into(backend.as_mut(), &p.wrench, &cold, &mut answer)?;
    let tol = backend.residual_tolerance();
    // The wrench 1 % away as `grasp-torque bench` nudges it (forces up, moments down):
    // a uniform scale would leave the scaled exact problem unchanged.
    let near: [f64; 6] = std::array::from_fn(|i| p.wrench[i] * if i < 3 { 1.01 } else { 0.99 });
    let (mut last, mut other) = (answer.clone(), Solution::default());
    let check = if kind == "tick" {
        Check::Lazy
    } else {
        Check::Full
    };
    let mut ticker = GraspSolver::new(&p, &config)?.with_check(check);
    ticker.resolve(&p.wrench)?;
    for i in 0..n {
        match kind.as_str() {
            "cold" => backend.solve_raw(black_box(&p.wrench), &cold, &mut answer),
            "check" => {
                backend
                    .problem()
                    .complete(black_box(&p.wrench), tol, "active-set", &mut answer)
            }
            "full" => {
                black_box(solver.solve(black_box(&p.wrench), &cold)?.status);
            }
            "lazy" => {
                solve_into_with(
                    backend.as_mut(),
                    black_box(&p.wrench),
                    &cold,
                    Check::Lazy,
                    &mut answer,
                )?;
            }
            "tick" | "tick-full" => {
                let w = if i % 2 == 0 { &near } else { &p.wrench };
                black_box(ticker.resolve(black_box(w))?.status);
            }
            "warm" => {
                let w = if i % 2 == 0 { &near } else { &p.wrench };
                let warm = WarmStart {
                    torque: Some(&last.torque),
                    active_set: last.active_set.as_deref(),
                };
                backend.solve_raw(black_box(w), &warm, &mut other);
                std::mem::swap(&mut last, &mut other);
            }
            "build" => {
                black_box(GraspSolver::new(black_box(&p), &config)?);
            }
            _ => return Err(format!("unknown kind {kind}").into()),
        }
    }
    black_box(&answer);
    Ok(())
}
