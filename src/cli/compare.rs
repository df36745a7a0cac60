//! `grasp-torque compare`: every compiled backend on the linearised problem, and
//! every compiled exact-cone backend (native and Clarabel) on the exact cones, with a
//! verdict.

use super::format::{g, micros};
use super::{load, Format};
use anyhow::Result;
use grasp_torque::matrix::norm_inf;
use grasp_torque::{
    solve_into, Backend, Cones, GraspModel, Solution, SolverConfig, Status, TorqueQp, WarmStart,
};
use serde_json::json;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

#[derive(clap::Args, Debug)]
pub(crate) struct CompareArgs {
    /// The problem file (JSON).
    problem: PathBuf,
    /// N, sides of the inscribed polygons (overrides the file).
    #[arg(long)]
    sides: Option<usize>,
    /// K, latitudes per hemisphere of SFCe polyhedra (overrides the file).
    #[arg(long)]
    latitudes: Option<usize>,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

/// Each backend's stated relative accuracy in σ on the linearised problem.
pub(crate) fn sigma_tolerance(backend: Backend, solution: &Solution) -> f64 {
    match backend {
        Backend::ActiveSet => 1e-9,
        Backend::Clarabel => 1e-6,
        // Polishing makes OSQP exact on its active set; without it, ADMM accuracy.
        Backend::Osqp => {
            if solution
                .warnings
                .iter()
                .any(|w| w.contains("polishing did not succeed"))
            {
                1e-3
            } else {
                1e-6
            }
        }
    }
}

/// Where one of two answers is optimal and the other almost (short of its optimality
/// certificate: Clarabel's with friction in the hundreds), the almost optimal one is
/// feasible, so its σ cannot be below the optimum; only that can be checked.
fn almost_below(what: &str, first: &Run, r: &Run) -> Option<String> {
    let (a, b) = (&first.solution, &r.solution);
    let (opt, almost, who) = if a.status == Status::Optimal {
        (a, b, r.backend)
    } else {
        (b, a, first.backend)
    };
    let tol = sigma_tolerance(first.backend, a).max(sigma_tolerance(r.backend, b));
    (almost.objective < opt.objective * (1.0 - tol)).then(|| {
        format!(
            "{what}{who}'s almost optimal σ = {} is below the optimum {}",
            almost.objective, opt.objective
        )
    })
}

struct Run {
    backend: Backend,
    cones: Cones,
    solution: Solution,
    time: Duration,
}

/// Reports the first solve (a first failure must not hide behind later successes),
/// and the median time of it and six more.
fn run_backend(qp: &TorqueQp, w: &[f64; 6], backend: Backend, cones: Cones) -> Result<Run> {
    let config = SolverConfig {
        backend: Some(backend),
        cones,
        ..Default::default()
    };
    let mut solver = config.build(qp.clone())?;
    let mut solution = Solution::default();
    solve_into(solver.as_mut(), w, &WarmStart::default(), &mut solution)?;
    let mut times = vec![solution.solve_time];
    let mut again = Solution::default();
    for _ in 0..6 {
        solve_into(solver.as_mut(), w, &WarmStart::default(), &mut again)?;
        times.push(again.solve_time);
    }
    times.sort();
    Ok(Run {
        backend,
        cones,
        solution,
        time: times[times.len() / 2],
    })
}

pub(crate) fn run(args: &CompareArgs) -> Result<u8> {
    let mut p = load(&args.problem)?;
    if let Some(n) = args.sides {
        p.linearization.sides = n;
    }
    if let Some(k) = args.latitudes {
        p.linearization.latitudes = k;
    }
    p.linearization
        .validate()
        .map_err(|e| anyhow::anyhow!("{}", e.to_string().replace("linearization.", "--")))?;
    p.validate()?;
    let model = Arc::new(GraspModel::new(&p, &Default::default())?);
    let qp = TorqueQp::linearized(model.clone(), &p.linearization);
    let exact_qp = TorqueQp::exact(model);
    let w = p.wrench;
    let mut runs = Vec::new();
    for b in Backend::compiled().filter(|b| b.supports(Cones::Linear)) {
        runs.push(run_backend(&qp, &w, b, Cones::Linear)?);
    }
    for b in Backend::compiled().filter(|b| b.supports(Cones::Exact)) {
        runs.push(run_backend(&exact_qp, &w, b, Cones::Exact)?);
    }
    let reference = runs
        .iter()
        .find(|r| r.backend == Backend::ActiveSet && r.cones == Cones::Linear);
    let tau_ref: Option<Vec<f64>> = reference
        .filter(|r| r.solution.is_optimal())
        .map(|r| r.solution.torque.clone());
    let mut problems = Vec::new();
    let linear: Vec<&Run> = runs.iter().filter(|r| r.cones == Cones::Linear).collect();
    if let Some(first) = linear.first() {
        for r in &linear {
            let (a, b) = (&first.solution, &r.solution);
            if a.status != b.status && a.is_optimal() && b.is_optimal() {
                problems.extend(almost_below("", first, r));
                continue;
            }
            if r.solution.status != first.solution.status {
                problems.push(format!(
                    "{}: status {} but {} says {}",
                    r.backend, r.solution.status, first.backend, first.solution.status
                ));
                continue;
            }
            if !r.solution.is_optimal() || !first.solution.is_optimal() {
                continue;
            }
            let tol = sigma_tolerance(r.backend, &r.solution)
                .max(sigma_tolerance(first.backend, &first.solution));
            let (a, b) = (r.solution.objective, first.solution.objective);
            let rel = (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE);
            if rel > tol {
                problems.push(format!(
                    "{}: σ differs from {} by {rel:.2e} relative (tolerance {tol:.0e})",
                    r.backend, first.backend
                ));
            }
            // A strongly convex objective: τ within √tol of the optimum, relative.
            let dt = max_diff(&r.solution.torque, &first.solution.torque);
            let ttol = tol.sqrt() * norm_inf(&first.solution.torque).max(f64::MIN_POSITIVE);
            if dt > ttol {
                problems.push(format!(
                    "{}: τ differs from {} by {dt:.2e} (tolerance {ttol:.1e})",
                    r.backend, first.backend
                ));
            }
        }
    }
    if let Some(exact) = runs.iter().find(|r| r.cones == Cones::Exact) {
        for r in &linear {
            match (exact.solution.status, r.solution.status) {
                (a, b) if a.has_answer() && b.has_answer() => {
                    let tol = 1e-6 * r.solution.objective.abs().max(f64::MIN_POSITIVE);
                    if exact.solution.objective > r.solution.objective + tol {
                        problems.push(format!(
                            "exact σ* = {} exceeds {}'s linearised σ = {} (the cones are inscribed)",
                            exact.solution.objective, r.backend, r.solution.objective
                        ));
                    }
                }
                (Status::Infeasible, b) if b.has_answer() => problems.push(format!(
                    "exact cones infeasible but {} found a linearised optimum (inscribed cones cannot be larger)",
                    r.backend
                )),
                _ => {}
            }
        }
    }
    // The exact backends (native and Clarabel) must agree with each other.
    let exact: Vec<&Run> = runs.iter().filter(|r| r.cones == Cones::Exact).collect();
    if let Some(first) = exact.first() {
        for r in &exact[1..] {
            let (a, b) = (&first.solution, &r.solution);
            if a.status != b.status && a.is_optimal() && b.is_optimal() {
                problems.extend(almost_below("exact cones: ", first, r));
            } else if a.status != b.status {
                problems.push(format!(
                    "exact cones: {} says {} but {} says {}",
                    r.backend, b.status, first.backend, a.status
                ));
            } else if a.is_optimal() {
                let tol = sigma_tolerance(first.backend, a).max(sigma_tolerance(r.backend, b));
                let rel = (a.objective - b.objective).abs()
                    / a.objective
                        .abs()
                        .max(b.objective.abs())
                        .max(f64::MIN_POSITIVE);
                if rel > tol {
                    problems.push(format!(
                        "exact cones: {}'s σ* differs from {}'s by {rel:.2e} relative (tolerance {tol:.0e})",
                        r.backend, first.backend
                    ));
                }
            }
        }
    }
    let agree = problems.is_empty();
    match args.format {
        Format::Json => {
            let rows: Vec<_> = runs
                .iter()
                .map(|r| {
                    let s = &r.solution;
                    let ok = !s.torque.is_empty();
                    json!({
                        "backend": r.backend.name(),
                        "cones": r.cones.name(),
                        "status": s.status.as_str(),
                        "objective": if ok { json!(s.objective) } else { json!(null) },
                        "max_torque_difference": match (&tau_ref, ok) { (Some(t), true) => json!(max_diff(&s.torque, t)), _ => json!(null) },
                        "iterations": s.iterations,
                        "solve_time_us": r.time.as_secs_f64() * 1e6,
                        "wrench_residual": if ok { json!(s.diagnostics.wrench_residual) } else { json!(null) },
                        "min_friction_margin": if ok { json!(min_margin(s)) } else { json!(null) },
                        "sigma_tolerance": if r.cones == Cones::Linear { json!(sigma_tolerance(r.backend, s)) } else { json!(null) },
                    })
                })
                .collect();
            let out = json!({"sides": p.linearization.sides, "latitudes": p.linearization.latitudes, "runs": rows, "agree": agree, "disagreements": problems});
            outln!("{}", serde_json::to_string_pretty(&out)?);
        }
        Format::Text => {
            // K (SFCe latitudes) matters only with SFCe contacts.
            let sfce = p
                .contacts
                .iter()
                .any(|c| matches!(c, grasp_torque::ContactModel::SfcElliptic { .. }));
            let k = if sfce {
                format!(", K = {}", p.linearization.latitudes)
            } else {
                String::new()
            };
            outln!(
                "problem {}  (inscribed cones: N = {}{k})\n",
                args.problem.display(),
                p.linearization.sides
            );
            outln!(
                "{:<11} {:<7} {:<18} {:>14} {:>12} {:>6} {:>11} {:>10} {:>10}",
                "backend",
                "cones",
                "status",
                "σ",
                "max|Δτ|",
                "iter",
                "time",
                "‖Gf−w‖∞",
                "min margin"
            );
            for r in &runs {
                let s = &r.solution;
                let ok = !s.torque.is_empty();
                let dash = || "—".to_string();
                outln!(
                    "{:<11} {:<7} {:<18} {:>14} {:>12} {:>6} {:>11} {:>10} {:>10}",
                    r.backend.name(),
                    r.cones.name(),
                    s.status.as_str(),
                    if ok { g(s.objective, 10) } else { dash() },
                    match (&tau_ref, ok) {
                        (Some(t), true) => g(max_diff(&s.torque, t), 3),
                        _ => dash(),
                    },
                    s.iterations,
                    micros(r.time),
                    if ok {
                        g(s.diagnostics.wrench_residual, 2)
                    } else {
                        dash()
                    },
                    match (ok, min_margin(s)) {
                        (true, Some(m)) => g(m, 3),
                        (true, None) => "unloaded".into(),
                        _ => dash(),
                    },
                );
            }
            outln!();
            if agree {
                outln!("verdict: agree (linearised backends within their tolerances; exact backends agree; exact σ* ≤ every linearised σ)");
            } else {
                outln!("verdict: DISAGREE");
                for d in &problems {
                    outln!("  - {d}");
                }
            }
        }
    }
    Ok(if agree { 0 } else { 5 })
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The smallest margin of a loaded contact (`None` when no contact is loaded).
fn min_margin(s: &Solution) -> Option<f64> {
    s.diagnostics
        .friction_margins
        .iter()
        .flatten()
        .copied()
        .reduce(f64::min)
}
