//! The Rust batch on arrays written by `scripts/bench_python.py`, timed in-process: the
//! figure the Python `solve_batch` overhead is measured against (docs/benchmarks.md).
//!
//! Input: little-endian u64 `B, K, m, n`, then f64 `G[B,6,n]`, `JT[B,m,n]`, `W[B,K,6]`;
//! PCwF contacts with the friction coefficient given. Prints the best of R runs.
//!
//! Run: `cargo run --release -p grasp-torque --example batch_arrays -- FILE MU THREADS [R]`

use grasp_torque::{
    for_each_solution, BatchGrasp, BatchOptions, ContactModel, GraspProblem, Matrix, SolverConfig,
};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let bytes = std::fs::read(&args[1]).expect("input file");
    let mu: f64 = args[2].parse().expect("mu");
    let threads: usize = args[3].parse().expect("threads");
    let repeats: usize = args.get(4).map_or(5, |r| r.parse().expect("repeats"));
    let u = |i: usize| u64::from_le_bytes(bytes[8 * i..8 * i + 8].try_into().unwrap()) as usize;
    let (b, k, m, n) = (u(0), u(1), u(2), u(3));
    let f: Vec<f64> = bytes[32..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let (g, rest) = f.split_at(b * 6 * n);
    let (jt, w) = rest.split_at(b * m * n);
    let contacts = vec![ContactModel::Pcwf { mu }; n / 3];
    let grasps: Vec<BatchGrasp> = (0..b)
        .map(|i| {
            let gm = Matrix::from_fn(6, n, |r, c| g[i * 6 * n + r * n + c]);
            let jm = Matrix::from_fn(m, n, |r, c| jt[i * m * n + r * n + c]);
            let ws: Vec<[f64; 6]> = (0..k)
                .map(|q| std::array::from_fn(|j| w[(i * k + q) * 6 + j]))
                .collect();
            BatchGrasp {
                problem: GraspProblem::new(gm, jm, ws[0], contacts.clone()),
                wrenches: ws,
            }
        })
        .collect();
    let opts = BatchOptions {
        threads: Some(threads),
        ..Default::default()
    };
    let config = SolverConfig::default();
    let mut best = f64::INFINITY;
    let optimal = AtomicUsize::new(0);
    for _ in 0..repeats {
        optimal.store(0, Ordering::Relaxed);
        let t = Instant::now();
        // As the Python batch does: answers handed over where they are solved.
        for_each_solution(&grasps[..], &config, &opts, |_, _, r| {
            if r.is_ok_and(|s| s.is_optimal()) {
                optimal.fetch_add(1, Ordering::Relaxed);
            }
        })
        .expect("threads");
        best = best.min(t.elapsed().as_secs_f64());
    }
    let optimal = optimal.into_inner();
    println!(
        "{{\"grasps\": {b}, \"wrenches\": {k}, \"threads\": {threads}, \"seconds\": {best}, \"optimal\": {optimal}}}"
    );
}
