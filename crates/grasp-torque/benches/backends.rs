//! Every fixture (the paper example, Table 1, synthetic 3/4/5-finger hands under PCwF,
//! SFCl and SFCe at N = 4…32): model build, the native solve cold and warm, Clarabel on
//! the same linearised QP and on the exact cones, and OSQP (with `--features osqp`).
//!
//! Run: `cargo bench -p grasp-torque --bench backends --features osqp`, then
//! `cargo run --release -p grasp-torque --example bench_report` for the tables in docs/benchmarks.md.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use grasp_torque::{
    solve_into, Backend, Cones, GraspSolver, Solution, SolverConfig, TorqueQp, WarmStart,
};
use std::hint::black_box;
use std::time::Duration;

#[path = "common/fixtures.rs"]
mod fixtures;

fn nudged(w: &[f64; 6]) -> [f64; 6] {
    let mut v = *w;
    for (i, x) in v.iter_mut().enumerate() {
        *x *= if i < 3 { 1.01 } else { 0.99 };
    }
    v
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("grasp");
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_millis(900));
    for f in fixtures::all() {
        let p = &f.problem;
        let name = f.name.as_str();
        let native = SolverConfig::default();
        g.bench_function(BenchmarkId::new("build-new-grasp", name), |b| {
            b.iter(|| {
                black_box(
                    native
                        .build(TorqueQp::from_problem(black_box(p), &native.model).unwrap())
                        .unwrap(),
                )
            })
        });
        let qp = TorqueQp::from_problem(p, &native.model).unwrap();
        let (mut cbuf, mut ebuf) = (
            vec![0.0; qp.inequality_rows()],
            vec![0.0; qp.equality_rows()],
        );
        g.bench_function(BenchmarkId::new("build-new-wrench", name), |b| {
            b.iter(|| {
                qp.c_into(black_box(&p.wrench), &mut cbuf);
                qp.model.e_into(black_box(&p.wrench), &mut ebuf);
            })
        });
        let mut runs = vec![
            (Backend::ActiveSet, Cones::Linear, "native-cold"),
            (Backend::Clarabel, Cones::Linear, "clarabel-linear"),
        ];
        // The exact cones do not depend on N: time them once per grasp.
        if !name.contains("-N") || name.ends_with("-N4") {
            runs.push((Backend::Clarabel, Cones::Exact, "clarabel-exact"));
        }
        if Backend::Osqp.is_compiled() {
            runs.push((Backend::Osqp, Cones::Linear, "osqp-linear"));
        }
        for (backend, cones, id) in runs {
            let config = SolverConfig {
                backend: Some(backend),
                cones,
                ..Default::default()
            };
            let view = config.view(qp.model.clone(), &p.linearization);
            let mut solver = config.build(view).unwrap();
            let mut sol = Solution::default();
            g.bench_function(BenchmarkId::new(id, name), |b| {
                b.iter(|| {
                    solve_into(
                        solver.as_mut(),
                        black_box(&p.wrench),
                        &WarmStart::default(),
                        &mut sol,
                    )
                    .unwrap();
                    assert!(sol.is_optimal(), "{id} {name}: {:?}", sol.reason);
                })
            });
        }
        let mut gs = GraspSolver::new(p, &native).unwrap();
        let (w0, w1) = (p.wrench, nudged(&p.wrench));
        gs.resolve(&w0).unwrap();
        let mut flip = false;
        g.bench_function(BenchmarkId::new("native-warm-1pct", name), |b| {
            b.iter(|| {
                flip = !flip;
                assert!(gs
                    .resolve(black_box(if flip { &w1 } else { &w0 }))
                    .unwrap()
                    .is_optimal());
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
