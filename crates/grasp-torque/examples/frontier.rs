//! The accuracy-per-microsecond frontier of docs/benchmarks.md: for each contact model
//! and hand, the smallest linearisation whose σ is within 1 %, 0.1 % and 0.01 % of the
//! exact optimum σ*, with its native solve time, next to the exact solve's time.
//!
//! Run: `cargo run --release -p grasp-torque --example frontier`

use grasp_torque::file::ModelName;
use grasp_torque::{
    solve_into, Backend, Cones, GraspProblem, SfceSpacing, Solution, SolverConfig, WarmStart,
};

// Shared with the benches; this example uses only `hand`.
#[allow(dead_code)]
#[path = "../benches/common/fixtures.rs"]
mod fixtures;

const REPEATS: usize = 31;

/// Median solve time (µs) and the answer.
fn timed(
    p: &GraspProblem,
    backend: Backend,
    cones: Cones,
) -> Result<(Solution, f64), Box<dyn std::error::Error>> {
    let config = SolverConfig {
        backend: Some(backend),
        cones,
        ..Default::default()
    };
    let mut solver = config.build(config.qp(p)?)?;
    let mut s = Solution::default();
    let mut t = Vec::with_capacity(REPEATS);
    for _ in 0..REPEATS {
        solve_into(solver.as_mut(), &p.wrench, &WarmStart::default(), &mut s)?;
        t.push(s.solve_time.as_secs_f64() * 1e6);
    }
    t.sort_by(f64::total_cmp);
    Ok((s, t[REPEATS / 2]))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let tolerances = [1e-2, 1e-3, 1e-4];
    println!("| model | hand | placement | σ* (exact) | native exact µs | Clarabel exact µs | within 1 %: N/K, rows, µs | within 0.1 % | within 0.01 % |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for (model, label) in [
        (ModelName::Pcwf, "PCwF"),
        (ModelName::Sfcl, "SFCl"),
        (ModelName::Sfce, "SFCe"),
    ] {
        for (f, j) in [(3, 3), (4, 4), (5, 4)] {
            let base = fixtures::hand(f, j, model);
            let (exact, exact_us) = timed(&base, Backend::ActiveSet, Cones::Exact)?;
            let (check, clarabel_us) = timed(&base, Backend::Clarabel, Cones::Exact)?;
            let sigma_star = exact.objective;
            let rel =
                (check.objective - sigma_star).abs() / sigma_star.abs().max(f64::MIN_POSITIVE);
            assert!(
                rel < 1e-6,
                "native σ* {sigma_star} vs Clarabel {}",
                check.objective
            );
            let placements: &[(SfceSpacing, &[usize])] = if model == ModelName::Sfce {
                &[
                    (SfceSpacing::Paper, &[1, 2, 4, 8]),
                    (SfceSpacing::Uniform, &[1, 2, 4, 8]),
                ]
            } else {
                &[(SfceSpacing::Paper, &[2])]
            };
            for &(spacing, ks) in placements {
                // Every (N, K), cheapest first by row count: the first within each tolerance.
                let mut candidates = Vec::new();
                for &k in ks {
                    for n in 3..=128 {
                        let mut p = base.clone();
                        p.linearization.sides = n;
                        p.linearization.latitudes = k;
                        p.linearization.sfce_spacing = spacing;
                        candidates.push((
                            p.linearization.rows_for(&p.contacts[0]) * p.contacts.len(),
                            p,
                        ));
                    }
                }
                candidates.sort_by_key(|c| c.0);
                let mut cells = Vec::new();
                for &tol in &tolerances {
                    let mut found = "not reached (N ≤ 128, K ≤ 8)".to_string();
                    for (rows, p) in &candidates {
                        let (s, _) = timed_once(p)?;
                        if s.is_optimal() && (s.objective - sigma_star) / sigma_star <= tol {
                            let (_, t) = timed(p, Backend::ActiveSet, Cones::Linear)?;
                            found = if model == ModelName::Sfce {
                                format!(
                                    "N = {}, K = {}: {rows} rows, {t:.1} µs",
                                    p.linearization.sides, p.linearization.latitudes
                                )
                            } else {
                                format!("N = {}: {rows} rows, {t:.1} µs", p.linearization.sides)
                            };
                            break;
                        }
                    }
                    cells.push(found);
                }
                let place = if model == ModelName::Sfce {
                    format!("{spacing:?}").to_lowercase()
                } else {
                    "—".into()
                };
                println!(
                    "| {label} | {f} × {j} ({} joints) | {place} | {sigma_star:.6e} | {exact_us:.1} | {clarabel_us:.1} | {} |",
                    f * j,
                    cells.join(" | ")
                );
            }
        }
    }
    Ok(())
}

/// One untimed native solve.
fn timed_once(p: &GraspProblem) -> Result<(Solution, f64), Box<dyn std::error::Error>> {
    let config = SolverConfig::default();
    let mut solver = config.build(config.qp(p)?)?;
    let mut s = Solution::default();
    solve_into(solver.as_mut(), &p.wrench, &WarmStart::default(), &mut s)?;
    Ok((s, 0.0))
}
