//! The hand form: parsing a URDF or MJCF, and building G, Jᵀ (and T) from the parsed
//! robot for a new grasp (forward kinematics, contact frames, couplings, validation), which a
//! planner that poses millions of grasps of one hand pays per grasp. The grasp model
//! and the solve that follow are timed beside it for scale.
//!
//! Run: `cargo bench -p grasp-torque --bench hand`. Figures are in docs/benchmarks.md.

use criterion::{criterion_group, criterion_main, Criterion};
use grasp_torque::hand::GraspPose;
use grasp_torque::{GraspSolver, HandFile, Robot, SolverConfig, WarmStart};
use std::hint::black_box;
use std::path::Path;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures");

fn hand(c: &mut Criterion) {
    for (name, file) in [
        ("allegro-pinch", "hands/allegro-pinch.json"),
        ("ability-tripod", "hands/ability-tripod.json"),
        ("shadow-tripod", "hands/shadow-tripod.json"),
    ] {
        let path = Path::new(ROOT).join(file);
        let spec: HandFile =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let urdf = path.parent().unwrap().join(&spec.hand.model);
        let mut g = c.benchmark_group(name);
        // Robot::load reads the file (and an MJCF's includes) each time, as a user does.
        g.bench_function("parse the robot", |b| {
            b.iter(|| Robot::load(black_box(&urdf)).unwrap())
        });
        let robot = Robot::load(&urdf).unwrap();
        g.bench_function("build G and Jᵀ", |b| {
            b.iter(|| spec.build(black_box(&robot)).unwrap())
        });
        // A planner's candidate: the contacts resolved once, each grasp posed from its
        // joint positions (the file's, here).
        let grasps = spec.grasps(&robot).unwrap();
        let mut q = vec![0.0; robot.independent.len()];
        for (name, &v) in &spec.hand.joint_positions {
            let j = robot.joint(name).unwrap();
            q[robot.coupling[j].unwrap().independent] = v;
        }
        g.bench_function("pose a resolved grasp", |b| {
            b.iter(|| {
                grasps
                    .pose(&GraspPose {
                        joint_positions: black_box(&q),
                        ..GraspPose::default()
                    })
                    .unwrap()
            })
        });
        let problem = spec.build(&robot).unwrap().problem;
        let config = SolverConfig::default();
        g.bench_function("grasp model and solver", |b| {
            b.iter(|| GraspSolver::new(black_box(&problem), &config).unwrap())
        });
        let mut solver = GraspSolver::new(&problem, &config).unwrap();
        g.bench_function("solve", |b| {
            b.iter(|| {
                solver
                    .solve(black_box(&problem.wrench), &WarmStart::default())
                    .unwrap();
            })
        });
        g.finish();
    }
}

criterion_group!(benches, hand);
criterion_main!(benches);
