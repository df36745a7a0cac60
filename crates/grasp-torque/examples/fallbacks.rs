//! The exact-cone solver's hard grasps, from the robustness sweep of
//! `tests/exact.rs` (`grasp_testkit::sweep_grasp`): which grasps reach the
//! interior-point fallback, and what they cost cold and in a control loop.
//!
//! Run: `cargo run --release -p grasp-torque --example fallbacks -- list` lists the
//! grasps of the 12 000-grasp sweep (seeds 0..6000 at normal friction, 10000..16000 at
//! a quarter of it) whose cold exact solve ends by the interior-point method, with
//! their status. `… -- time SEED:FRICTION...` times each grasp: a cold solve of the
//! backend alone (200 solves, best of five) and a control loop of `resolve` on a
//! wrench alternating by 1 % as `grasp-torque bench` does it (100 ticks, best of
//! three), with the methods the loop's answers came by. `… -- sweep FROM TO FRICTION`
//! prints every grasp of seeds `FROM..TO` at that friction: status, method, how an
//! infeasible one was decided, σ, iterations, the least friction margin (scale-free,
//! negative outside a cone) and the largest violation of a linear row (force or torque
//! units), one line each, so that two builds' answers can be compared line by line
//! (`diff`); with `clarabel` after them, Clarabel's; with `sides=N`, the native
//! linearised solve at N. `… -- ticks FROM TO FRICTION [CHANGE]` runs six ticks of a
//! control loop per grasp (`resolve`, the wrench alternating with the one CHANGE
//! away, 0.01 by default, as `grasp-torque bench` nudges it) and prints each tick's
//! status, method and σ; `… -- loop SEED:FRICTION N` runs N such ticks silently, for
//! instruction counts (valgrind). `… -- units SEED:FRICTION...` solves each grasp in
//! SI units, in millimetres, in millinewtons, both ways and with the wrench scaled by
//! 1e6 and 1e-6, and prints each status, method and σ's relative difference from the
//! SI answer scaled. `… -- write SEED:FRICTION` prints the grasp as a matrix-form
//! problem file (as in `fixtures/sweep`), for the command line.

use grasp_testkit::sweep_grasp;
use grasp_torque::{
    solve_into, Backend, Cones, GraspProblem, GraspSolver, Reason, Solution, SolverConfig,
    WarmStart,
};
use std::collections::BTreeMap;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let config = SolverConfig {
        cones: Cones::Exact,
        ..Default::default()
    };
    match args.first().map(String::as_str) {
        Some("list") => {
            for (friction, seeds) in [(1.0, 0..6000u64), (0.25, 10000..16000u64)] {
                for seed in seeds {
                    let p = sweep_grasp(seed, friction);
                    let mut s = config.build(config.qp(&p)?)?;
                    let mut out = Solution::default();
                    solve_into(s.as_mut(), &p.wrench, &WarmStart::default(), &mut out)?;
                    if matches!(out.method, Some("interior_point" | "interior_point_newton")) {
                        println!("{seed}:{friction} {}", out.status);
                    }
                }
            }
        }
        Some("time") => {
            for arg in &args[1..] {
                let p = named_grasp(arg)?;
                let mut s = config.build(config.qp(&p)?)?;
                let mut out = Solution::default();
                let cold = best_of(5, 200, || {
                    solve_into(s.as_mut(), &p.wrench, &WarmStart::default(), &mut out).map(|_| ())
                })?;
                let (w0, w1) = (p.wrench, nudged(&p.wrench, 0.01));
                let mut ctl = GraspSolver::new(&p, &config)?;
                ctl.resolve(&w0)?;
                let mut methods = BTreeMap::new();
                let mut tick = 0usize;
                let warm = best_of(3, 100, || {
                    tick += 1;
                    let r = ctl.resolve(if tick % 2 == 1 { &w1 } else { &w0 })?;
                    *methods.entry(r.method.unwrap_or("none")).or_insert(0) += 1;
                    Ok::<(), grasp_torque::Error>(())
                })?;
                println!(
                    "{arg} {} by {}: cold {cold:.2} µs, control loop {warm:.2} µs a tick {methods:?}",
                    out.status,
                    out.method.unwrap_or("none"),
                );
            }
        }
        Some("sweep") => {
            let usage = "usage: fallbacks sweep FROM TO FRICTION [clarabel | sides=N]";
            let (config, sides, [from, to, friction]) = match &args[1..] {
                [a, b, c] => (config, None, [a, b, c]),
                [a, b, c, d] if d == "clarabel" => (
                    SolverConfig {
                        backend: Some(Backend::Clarabel),
                        ..config
                    },
                    None,
                    [a, b, c],
                ),
                [a, b, c, d] => {
                    let n: usize = d.strip_prefix("sides=").ok_or(usage)?.parse()?;
                    let linear = SolverConfig {
                        cones: Cones::Linear,
                        ..config
                    };
                    (linear, Some(n), [a, b, c])
                }
                _ => return Err(usage.into()),
            };
            let friction: f64 = friction.parse()?;
            for seed in from.parse::<u64>()?..to.parse()? {
                let mut p = sweep_grasp(seed, friction);
                if let Some(n) = sides {
                    p.linearization.sides = n;
                }
                let mut s = config.build(config.qp(&p)?)?;
                let mut out = Solution::default();
                solve_into(s.as_mut(), &p.wrench, &WarmStart::default(), &mut out)?;
                let decided = match &out.reason {
                    Some(Reason::OuterApproximation { sides, .. }) => format!("polyhedra-{sides}"),
                    Some(Reason::DualRay { .. }) => "dual-ray".into(),
                    Some(_) => "other".into(),
                    None => "-".into(),
                };
                let d = &out.diagnostics;
                let margin = d.friction_margins.iter().flatten().fold(1.0f64, |a, m| a.min(*m));
                println!(
                    "{seed}:{friction} {} {} {decided} {:.15e} {} {margin:.2e} {:.2e}",
                    out.status,
                    out.method.unwrap_or("none"),
                    out.objective,
                    out.iterations,
                    d.max_violation,
                );
            }
        }
        Some("ticks") => {
            let [from, to, friction, rest @ ..] = &args[1..] else {
                return Err("usage: fallbacks ticks FROM TO FRICTION [CHANGE]".into());
            };
            let friction: f64 = friction.parse()?;
            let change: f64 = rest.first().map_or(Ok(0.01), |c| c.parse())?;
            for seed in from.parse::<u64>()?..to.parse()? {
                let p = sweep_grasp(seed, friction);
                let w = [p.wrench, nudged(&p.wrench, change)];
                let mut ctl = GraspSolver::new(&p, &config)?;
                let mut line = format!("{seed}:{friction}");
                for tick in 0..6 {
                    let r = ctl.resolve(&w[tick % 2])?;
                    let method = r.method.unwrap_or("none");
                    line += &format!(" {}/{method}/{:.10e}", r.status, r.objective);
                }
                println!("{line}");
            }
        }
        Some("loop") => {
            let [grasp, n] = &args[1..] else {
                return Err("usage: fallbacks loop SEED:FRICTION N".into());
            };
            let p = named_grasp(grasp)?;
            let w = [p.wrench, nudged(&p.wrench, 0.01)];
            let mut ctl = GraspSolver::new(&p, &config)?;
            for tick in 0..n.parse::<usize>()? {
                std::hint::black_box(ctl.resolve(&w[tick % 2])?.status);
            }
        }
        Some("units") => {
            let solve = |p: &GraspProblem| -> Result<Solution, Box<dyn std::error::Error>> {
                let mut s = config.build(config.qp(p)?)?;
                let mut out = Solution::default();
                solve_into(s.as_mut(), &p.wrench, &WarmStart::default(), &mut out)?;
                Ok(out)
            };
            for arg in &args[1..] {
                let p = named_grasp(arg)?;
                let si = solve(&p)?;
                let mut line = format!("{arg} {}/{}", si.status, si.method.unwrap_or("none"));
                // Millimetres, millinewtons, both ways, and the wrench scaled: σ scales
                // by (l f w)².
                for (l, f, w) in [
                    (1e3, 1.0, 1.0),
                    (1.0, 1e3, 1.0),
                    (1e-3, 1e3, 1.0),
                    (1.0, 1.0, 1e6),
                    (1.0, 1.0, 1e-6),
                ] {
                    let mut q = grasp_testkit::rescale(&p, l, f);
                    q.wrench.iter_mut().for_each(|v| *v *= w);
                    let r = solve(&q)?;
                    let want = si.objective * (l * f * w).powi(2);
                    let diff = if si.is_optimal() && r.is_optimal() {
                        let d = (r.objective - want).abs() / want.abs().max(r.objective.abs());
                        format!("{d:.1e}")
                    } else {
                        "-".into()
                    };
                    line += &format!(
                        " | l={l:e} f={f:e} w={w:e} {}/{} {diff}",
                        r.status,
                        r.method.unwrap_or("none")
                    );
                }
                println!("{line}");
            }
        }
        Some("write") => {
            let [grasp] = &args[1..] else {
                return Err("usage: fallbacks write SEED:FRICTION".into());
            };
            let (seed, friction) = grasp.split_once(':').unwrap_or_default();
            let mut file = grasp_io::MatrixFile::from_problem(
                &named_grasp(grasp)?,
                Some(format!("sweep-{seed}-friction-{friction}")),
            );
            file.description = Some(format!(
                "grasp_testkit::sweep_grasp({seed}, {friction}): a random grasp of the exact-cone robustness sweep (crates/grasp-torque/tests/exact.rs)"
            ));
            println!("{}", serde_json::to_string_pretty(&file)?);
        }
        _ => {
            return Err(
                "usage: fallbacks list | time SEED:FRICTION... | sweep FROM TO FRICTION [clarabel | sides=N] | ticks FROM TO FRICTION [CHANGE] | loop SEED:FRICTION N | units SEED:FRICTION... | write SEED:FRICTION"
                    .into(),
            )
        }
    }
    Ok(())
}

/// The sweep grasp named `SEED:FRICTION`.
fn named_grasp(arg: &str) -> Result<GraspProblem, Box<dyn std::error::Error>> {
    let (seed, friction) = arg
        .split_once(':')
        .ok_or_else(|| format!("{arg}: expected SEED:FRICTION"))?;
    Ok(sweep_grasp(seed.parse()?, friction.parse()?))
}

/// The wrench `change` away, as `grasp-torque bench` nudges it: forces up, moments
/// down (a uniform scale would leave the scaled exact problem unchanged).
fn nudged(w: &[f64; 6], change: f64) -> [f64; 6] {
    std::array::from_fn(|i| w[i] * if i < 3 { 1.0 + change } else { 1.0 - change })
}

/// The lowest over `rounds` of the mean time of `n` calls, in µs.
fn best_of<E>(rounds: usize, n: usize, mut f: impl FnMut() -> Result<(), E>) -> Result<f64, E> {
    let mut best = f64::INFINITY;
    for _ in 0..rounds {
        let t = Instant::now();
        for _ in 0..n {
            f()?;
        }
        best = best.min(t.elapsed().as_secs_f64() / n as f64 * 1e6);
    }
    Ok(best)
}
