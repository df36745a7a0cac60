//! The project's one-sided Jacobi SVD against nalgebra's for the pseudo-inverse at
//! grasp sizes (A = [G; Jᵀ] is 10 × 8 for the paper example, 26 × 18 for the 5-finger
//! mixed hand), and their accuracy, which decides. (faer, used before, reached the
//! same accuracy as Jacobi; it was dropped for its build time.) `decompose` is what the
//! model runs: a QR when A is clearly of full rank, a complete orthogonal decomposition
//! when its rank is clearly lower (the paper example), the SVD otherwise.
//!
//! Run: `cargo bench -p grasp-torque --bench decomposition`. Figures are in docs/benchmarks.md.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use grasp_torque::linalg::{decompose, svd, RankThreshold};
use grasp_torque::{load_problem, Matrix};
use std::hint::black_box;

fn a_of(name: &str) -> Matrix {
    let p = load_problem(format!(
        "{}/fixtures/{name}.json",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../..")
    ))
    .unwrap();
    p.grasp_matrix.vstack(&p.jacobian_transpose)
}

/// Largest entry of `A Z A − A` (Z the pseudo-inverse): the accuracy that decides.
fn aza_error(a: &Matrix, z: &Matrix) -> f64 {
    let aza = a.matmul(z).matmul(a);
    aza.as_slice()
        .iter()
        .zip(a.as_slice())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn nalgebra_pinv(a: &Matrix) -> Matrix {
    let na = nalgebra::DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)]);
    let d = na.svd(true, true);
    let tol = 1e-9 * d.singular_values.max();
    let p = d.pseudo_inverse(tol).unwrap();
    Matrix::from_fn(a.ncols(), a.nrows(), |i, j| p[(i, j)])
}

/// The pseudo-inverse through [`decompose`], with the model's rank tolerance.
fn model_pinv(a: &Matrix) -> Matrix {
    decompose(a, RankThreshold::Relative(1e-9))
        .unwrap()
        .pseudo_inverse()
}

fn pinv(c: &mut Criterion) {
    let mut g = c.benchmark_group("pseudo-inverse");
    for name in ["paper-example", "hand5-mixed"] {
        let a = a_of(name);
        let (r, k) = (a.nrows(), a.ncols());
        // What the model runs: the full Jacobi SVD (it also gives the complement of
        // range A and the null space).
        g.bench_function(BenchmarkId::new(format!("jacobi-{r}x{k}"), name), |b| {
            b.iter(|| black_box(svd(black_box(&a)).unwrap().pseudo_inverse(1e-9)))
        });
        g.bench_function(BenchmarkId::new(format!("decompose-{r}x{k}"), name), |b| {
            b.iter(|| black_box(model_pinv(black_box(&a))))
        });
        // nalgebra's (thin) SVD: faster, but see the accuracy report below.
        g.bench_function(BenchmarkId::new(format!("nalgebra-{r}x{k}"), name), |b| {
            b.iter(|| black_box(nalgebra_pinv(black_box(&a))))
        });
    }
    g.finish();
    // Accuracy on the fixtures and on a synthetic grasp where nalgebra's SVD
    // converges loosely: ‖A Z A − A‖max for each.
    let mut cases: Vec<(String, Matrix)> = ["paper-example", "hand5-mixed", "hand4-sfce"]
        .iter()
        .map(|n| (n.to_string(), a_of(n)))
        .collect();
    let mut spec = grasp_testkit::SynthSpec::default();
    spec.linearization.sides = 3;
    let p = grasp_testkit::synthetic_grasp(3304615860721577304, &spec)
        .into_problem()
        .unwrap();
    cases.push((
        "synthetic-3304615860721577304".into(),
        p.grasp_matrix.vstack(&p.jacobian_transpose),
    ));
    eprintln!("accuracy, max |A Z A − A|:");
    for (n, a) in &cases {
        let ours = svd(a).unwrap().pseudo_inverse(1e-9);
        eprintln!(
            "  {n:<32} jacobi {:.1e}   decompose {:.1e}   nalgebra {:.1e}",
            aza_error(a, &ours),
            aza_error(a, &model_pinv(a)),
            aza_error(a, &nalgebra_pinv(a))
        );
    }
}

criterion_group!(benches, pinv);
criterion_main!(benches);
