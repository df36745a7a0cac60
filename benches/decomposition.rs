//! faer against nalgebra for the SVD pseudo-inverse at grasp sizes: A = [G; Jᵀ] is
//! 10 × 8 for the paper example and 26 × 20 for a 5-finger, 20-joint soft-finger hand.
//!
//! Run: `cargo bench --bench decomposition`. Figures are in docs/benchmarks.md.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use grasp_torque::linalg::svd;
use grasp_torque::{load_problem, Matrix};
use std::hint::black_box;

fn a_of(name: &str) -> Matrix {
    let p = load_problem(format!(
        "{}/fixtures/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    p.grasp_matrix.vstack(&p.jacobian_transpose)
}

fn pinv(c: &mut Criterion) {
    let mut g = c.benchmark_group("pseudo-inverse");
    for name in ["paper-example", "hand5-mixed"] {
        let a = a_of(name);
        let (r, k) = (a.nrows(), a.ncols());
        g.bench_function(BenchmarkId::new(format!("faer-{r}x{k}"), name), |b| {
            b.iter(|| black_box(svd(black_box(&a)).unwrap().pseudo_inverse(1e-9)))
        });
        let na = nalgebra::DMatrix::from_fn(r, k, |i, j| a[(i, j)]);
        g.bench_function(BenchmarkId::new(format!("nalgebra-{r}x{k}"), name), |b| {
            b.iter(|| {
                let d = black_box(&na).clone().svd(true, true);
                let tol = 1e-9 * d.singular_values.max();
                black_box(d.pseudo_inverse(tol).unwrap())
            })
        });
        // Agreement check, so the comparison is of equal answers.
        let ours = svd(&a).unwrap().pseudo_inverse(1e-9);
        let d = na.clone().svd(true, true);
        let tol = 1e-9 * d.singular_values.max();
        let theirs = d.pseudo_inverse(tol).unwrap();
        let diff = (0..k)
            .flat_map(|i| (0..r).map(move |j| (i, j)))
            .map(|(i, j)| (ours[(i, j)] - theirs[(i, j)]).abs())
            .fold(0.0, f64::max);
        assert!(diff < 1e-12, "faer and nalgebra differ by {diff}");
    }
    g.finish();
}

criterion_group!(benches, pinv);
criterion_main!(benches);
