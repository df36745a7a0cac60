//! Native solver benchmarks: the paper example and the bundled hand fixtures, cold and
//! warm-started after a 1% wrench change, plus model build times.
//!
//! Run: `cargo bench -p grasp-torque --bench solve`. Figures are in docs/benchmarks.md.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use grasp_torque::{
    load_problem, solve_into, GraspProblem, GraspSolver, ModelOptions, Solution, SolverConfig,
    TorqueQp, WarmStart,
};
use std::hint::black_box;

const FIXTURES: [&str; 6] = [
    "paper-example",
    "hand3-pcwf",
    "hand5-pcwf",
    "hand4-sfcl",
    "hand4-sfce",
    "hand5-mixed",
];

fn problem(name: &str) -> GraspProblem {
    load_problem(format!(
        "{}/fixtures/{name}.json",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../..")
    ))
    .unwrap()
}

/// The wrench changed by 1%: force components up, moments down.
fn nudged(w: &[f64; 6]) -> [f64; 6] {
    let mut v = *w;
    for (i, x) in v.iter_mut().enumerate() {
        *x *= if i < 3 { 1.01 } else { 0.99 };
    }
    v
}

fn native(c: &mut Criterion) {
    let mut g = c.benchmark_group("native");
    for name in FIXTURES {
        let p = problem(name);
        let config = SolverConfig::default();
        let qp = TorqueQp::from_problem(&p, &config.model).unwrap();
        let mut solver = config.build(qp).unwrap();
        let mut sol = Solution::default();
        let cold = WarmStart::default();
        // Cold: no starting point, every tick.
        g.bench_function(BenchmarkId::new("cold", name), |b| {
            b.iter(|| {
                solve_into(solver.as_mut(), black_box(&p.wrench), &cold, &mut sol).unwrap();
                assert!(sol.is_optimal());
            })
        });
        // Warm: a control loop whose wrench alternates by 1%, each tick warm-started
        // from the previous answer.
        let mut gs = GraspSolver::new(&p, &config).unwrap();
        let (w0, w1) = (p.wrench, nudged(&p.wrench));
        gs.resolve(&w0).unwrap();
        let mut flip = false;
        g.bench_function(BenchmarkId::new("warm-1pct", name), |b| {
            b.iter(|| {
                flip = !flip;
                let s = gs.resolve(black_box(if flip { &w1 } else { &w0 })).unwrap();
                assert!(s.is_optimal());
            })
        });
        // The backend alone, without the core's diagnostics.
        g.bench_function(BenchmarkId::new("cold-raw", name), |b| {
            b.iter(|| solver.solve_raw(black_box(&p.wrench), &cold, &mut sol))
        });
    }
    g.finish();
}

fn build(c: &mut Criterion) {
    let mut g = c.benchmark_group("build");
    for name in FIXTURES {
        let p = problem(name);
        let config = SolverConfig::default();
        g.bench_function(BenchmarkId::new("new-grasp", name), |b| {
            b.iter(|| {
                let qp = TorqueQp::from_problem(black_box(&p), &ModelOptions::default()).unwrap();
                black_box(config.build(qp).unwrap());
            })
        });
    }
    g.finish();
}

criterion_group!(benches, native, build);
criterion_main!(benches);
