//! `grasp-torque bench`: one problem timed in-process, so that scripts outside the
//! project compare like for like (medians of single calls; the machine's noise is the
//! caller's to control).

use super::format::g;
use super::{load, Format, ModelArgs};
use anyhow::{bail, Result};
use grasp_torque::sweep::MAX_REPEATS;
use grasp_torque::{solve_into, Check, GraspSolver, Solution, WarmStart};
use serde_json::json;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub(crate) struct BenchArgs {
    /// The problem file (any form).
    problem: PathBuf,
    #[command(flatten)]
    model: ModelArgs,
    /// Timed calls of each kind (builds: a tenth of them, at least 10).
    #[arg(long, default_value_t = 1000)]
    repeats: usize,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

/// The median of `n` timed calls of `f`, in µs.
fn median_us(n: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..n)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[n / 2]
}

/// The wrench changed by 1 %: force components up, moments down.
fn nudged(w: &[f64; 6]) -> [f64; 6] {
    std::array::from_fn(|i| w[i] * if i < 3 { 1.01 } else { 0.99 })
}

pub(crate) fn run(args: &BenchArgs) -> Result<u8> {
    if !(1..=MAX_REPEATS).contains(&args.repeats) {
        bail!(
            "--repeats: expected 1 to {MAX_REPEATS}, got {}",
            args.repeats
        );
    }
    let mut p = load(&args.problem)?;
    let config = args.model.configure(&mut p)?;
    let n = args.repeats;
    let build_us = median_us((n / 10).max(10), || {
        black_box(GraspSolver::new(black_box(&p), &config).map(|_| ()).ok());
    });
    let mut solver = GraspSolver::new(&p, &config)?;
    let cold = WarmStart::default();
    let first = solver.solve(&p.wrench, &cold)?.clone();
    let cold_us = median_us(n, || {
        black_box(
            solver
                .solve(black_box(&p.wrench), &cold)
                .map(|s| s.status)
                .ok(),
        );
    });
    // The backend alone, without the core's completion and checks.
    let mut backend = config.build(solver.problem().clone())?;
    let mut raw = Solution::default();
    solve_into(backend.as_mut(), &p.wrench, &cold, &mut raw)?;
    let cold_raw_us = median_us(n, || {
        backend.solve_raw(black_box(&p.wrench), &cold, &mut raw)
    });
    // A control loop whose wrench alternates by 1 %, each tick from the previous answer.
    let (w0, w1) = (p.wrench, nudged(&p.wrench));
    let mut flip = false;
    solver.resolve(&w0)?;
    let warm_us = median_us(n, || {
        flip = !flip;
        black_box(
            solver
                .resolve(if flip { &w1 } else { &w0 })
                .map(|s| s.status)
                .ok(),
        );
    });
    // The same two with the lazy check (`Check::Lazy`): the backend's certificate only,
    // forces and residuals on demand.
    let mut lazy = GraspSolver::new(&p, &config)?.with_check(Check::Lazy);
    let cold_lazy_us = median_us(n, || {
        black_box(
            lazy.solve(black_box(&p.wrench), &cold)
                .map(|s| s.status)
                .ok(),
        );
    });
    lazy.resolve(&w0)?;
    let warm_lazy_us = median_us(n, || {
        flip = !flip;
        black_box(
            lazy.resolve(if flip { &w1 } else { &w0 })
                .map(|s| s.status)
                .ok(),
        );
    });
    let v = json!({
        "problem": args.problem.display().to_string(),
        "backend": solver.backend_name(),
        "cones": config.cones.name(),
        "sides": p.linearization.sides,
        "repeats": n,
        "status": first.status,
        "objective": (!first.torque.is_empty()).then_some(first.objective),
        "iterations": first.iterations,
        "build_us": build_us,
        "cold_us": cold_us,
        "cold_raw_us": cold_raw_us,
        "warm_1pct_us": warm_us,
        "cold_lazy_us": cold_lazy_us,
        "warm_1pct_lazy_us": warm_lazy_us,
    });
    match args.format {
        Format::Json => outln!("{}", serde_json::to_string_pretty(&v)?),
        Format::Text => {
            outln!(
                "{}: {} ({} cones), status {}, σ = {}",
                args.problem.display(),
                solver.backend_name(),
                config.cones.name(),
                first.status,
                g(first.objective, 10)
            );
            outln!("median of {n} calls: build {build_us:.2} µs, cold solve {cold_us:.2} µs (backend alone {cold_raw_us:.2} µs), warm after a 1 % wrench change {warm_us:.2} µs");
            outln!(
                "with the lazy check: cold solve {cold_lazy_us:.2} µs, warm {warm_lazy_us:.2} µs"
            );
        }
    }
    Ok(0)
}
