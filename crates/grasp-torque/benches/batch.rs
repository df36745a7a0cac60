//! Batch throughput: synthetic grasps (grasp-testkit), each with its model built, solved
//! for one wrench or six, on one worker thread and on two; and with exact cones, one
//! wrench on one thread (a planner's screening pass, the build of the exact solver
//! included). Throughput is in grasps per second; with six wrenches each grasp is six
//! solves.
//!
//! Run: `cargo bench -p grasp-torque --bench batch`. Figures are in docs/benchmarks.md.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use grasp_testkit::{synthetic_grasp, ModelMix, SynthSpec};
use grasp_torque::{file::ModelName, solve_batch, BatchGrasp, BatchOptions, Cones, SolverConfig};
use std::hint::black_box;

const GRASPS: usize = 2000;

/// Six load directions: ± 10 % of the weight along each axis.
fn six(w: &[f64; 6]) -> Vec<[f64; 6]> {
    (0..6)
        .map(|d| {
            let mut v = *w;
            v[d / 2] += if d % 2 == 0 { 0.1 } else { -0.1 } * w[2].abs();
            v
        })
        .collect()
}

fn grasps(fingers: usize, joints: usize, model: ModelName, wrenches: usize) -> Vec<BatchGrasp> {
    let spec = SynthSpec {
        fingers: Some(fingers),
        joints_per_finger: Some(joints),
        models: ModelMix::Only(model),
        ..Default::default()
    };
    (0..GRASPS as u64)
        .map(|seed| {
            let problem = synthetic_grasp(seed, &spec).into_problem().unwrap();
            let wrenches = if wrenches == 1 {
                Vec::new()
            } else {
                six(&problem.wrench)
            };
            BatchGrasp { problem, wrenches }
        })
        .collect()
}

fn batch(c: &mut Criterion) {
    let config = SolverConfig::default();
    for (name, fingers, joints, model) in [
        ("3-finger-pcwf", 3, 3, ModelName::Pcwf),
        ("5-finger-pcwf", 5, 4, ModelName::Pcwf),
        ("4-finger-sfcl", 4, 4, ModelName::Sfcl),
    ] {
        let mut g = c.benchmark_group(format!("batch/{name}"));
        g.sample_size(10);
        g.throughput(Throughput::Elements(GRASPS as u64));
        let exact = SolverConfig {
            cones: Cones::Exact,
            ..Default::default()
        };
        let one = BatchOptions {
            threads: Some(1),
            ..Default::default()
        };
        let input = grasps(fingers, joints, model, 1);
        g.bench_function("exact/1-wrench/1-thread", |b| {
            b.iter(|| black_box(solve_batch(&input, &exact, &one).unwrap()))
        });
        for wrenches in [1, 6] {
            let input = grasps(fingers, joints, model, wrenches);
            for threads in [1, 2] {
                let opts = BatchOptions {
                    threads: Some(threads),
                    ..Default::default()
                };
                g.bench_function(
                    BenchmarkId::new(format!("{wrenches}-wrench"), format!("{threads}-thread")),
                    |b| b.iter(|| black_box(solve_batch(&input, &config, &opts).unwrap())),
                );
            }
        }
        g.finish();
    }
}

criterion_group!(benches, batch);
criterion_main!(benches);
