//! `grasp-torque solve`.

use super::format::{g, micros};
use super::{load, parse_list, Format, ModelArgs};
use anyhow::Result;
use grasp_torque::{Equilibrium, GraspSolver, Solution, Status, TorqueQp, WarmStart};
use serde_json::json;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub(crate) struct SolveArgs {
    /// The problem file (JSON).
    problem: PathBuf,
    #[command(flatten)]
    model: ModelArgs,
    /// Starting torque, one value per joint, comma-separated (overrides the file's
    /// `initial_torque`).
    #[arg(long, allow_hyphen_values = true)]
    initial_torque: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

/// Exit code of a finished solve.
pub(crate) fn exit_code(s: Status) -> u8 {
    match s {
        Status::Optimal => 0,
        Status::Infeasible => 3,
        Status::IterationLimit | Status::NumericalFailure => 4,
    }
}

pub(crate) fn run(args: &SolveArgs) -> Result<u8> {
    let mut problem = load(&args.problem)?;
    let config = args.model.configure(&mut problem)?;
    if let Some(t) = &args.initial_torque {
        let t = parse_list("--initial-torque", t)?;
        if t.len() != problem.joints() {
            anyhow::bail!(
                "--initial-torque: expected {} values (one per joint), got {}",
                problem.joints(),
                t.len()
            );
        }
        problem.initial_torque = Some(t);
    }
    let mut solver = GraspSolver::new(&problem, &config)?;
    let warm = WarmStart {
        torque: problem.initial_torque.as_deref(),
        active_set: None,
    };
    solver.solve(&problem.wrench, &warm)?;
    let sol = solver.solution();
    for w in &sol.warnings {
        eprintln!("warning: {w}");
    }
    let qp = solver.problem();
    let cones = config.cones.name();
    match args.format {
        Format::Json => println!(
            "{}",
            serde_json::to_string_pretty(&to_json(qp, sol, solver.backend_name(), cones))?
        ),
        Format::Text => print!(
            "{}",
            text_report(
                &args.problem.display().to_string(),
                qp,
                sol,
                solver.backend_name(),
                cones
            )
        ),
    }
    Ok(exit_code(sol.status))
}

/// Per-contact force vectors.
fn per_contact(qp: &TorqueQp, f: &[f64]) -> Vec<Vec<f64>> {
    qp.contacts
        .iter()
        .map(|c| f[c.offset..c.offset + c.model.dim()].to_vec())
        .collect()
}

pub(crate) fn to_json(
    qp: &TorqueQp,
    s: &Solution,
    backend: &str,
    cones: &str,
) -> serde_json::Value {
    let ok = !s.torque.is_empty();
    let opt = |v: f64| if ok { json!(v) } else { json!(null) };
    json!({
        "status": s.status.as_str(),
        "reason": s.reason.as_ref().map(|r| r.to_string()),
        "objective": opt(s.objective),
        "torque": if ok { json!(s.torque) } else { json!(null) },
        "contact_forces": if ok { json!(per_contact(qp, &s.contact_forces)) } else { json!(null) },
        "contact_models": qp.contacts.iter().map(|c| c.model.name()).collect::<Vec<_>>(),
        "iterations": s.iterations,
        "active_set": s.active_set,
        "residuals": {
            "wrench": opt(s.diagnostics.wrench_residual),
            "torque": opt(s.diagnostics.torque_residual),
            "consistency": opt(s.diagnostics.consistency_residual),
        },
        "max_violation": opt(s.diagnostics.max_violation),
        "friction_margin": if ok { json!(s.diagnostics.friction_margins) } else { json!(null) },
        "backend": backend,
        "cones": cones,
        "sides": qp.linearization.sides,
        "latitudes": qp.linearization.latitudes,
        "constraint_rows": qp.inequality_rows(),
        "consistency": qp.equilibrium == Equilibrium::Consistent,
        "solve_time_us": s.solve_time.as_secs_f64() * 1e6,
        "warnings": s.warnings,
    })
}

fn text_report(name: &str, qp: &TorqueQp, s: &Solution, backend: &str, cones: &str) -> String {
    use std::fmt::Write;
    let mut o = String::new();
    let lin = qp.linearization;
    let _ = writeln!(o, "problem   {name}");
    let _ = writeln!(
        o,
        "model     {} joints, {} contacts, {} inequality rows (N = {}, K = {}), {}",
        qp.joints(),
        qp.contacts.len(),
        qp.inequality_rows(),
        lin.sides,
        lin.latitudes,
        match qp.equilibrium {
            Equilibrium::Consistent => format!("{} consistency equalities", qp.equality_rows()),
            Equilibrium::PaperModel => "paper model (no consistency equalities)".to_string(),
        }
    );
    let _ = writeln!(o, "backend   {backend}, {cones} cones");
    let _ = writeln!(o, "status    {}", s.status);
    if let Some(r) = &s.reason {
        let _ = writeln!(o, "reason    {r}");
    }
    if s.torque.is_empty() {
        return o;
    }
    let _ = writeln!(o, "objective σ = Σ w τ² = {}", g(s.objective, 10));
    let _ = writeln!(o, "\njoint torques");
    for (j, t) in s.torque.iter().enumerate() {
        let _ = writeln!(o, "  τ{j:<3} {:>14}", g(*t, 7));
    }
    let _ = writeln!(
        o,
        "\ncontact forces (contact frame)                 exact-cone margin"
    );
    for (i, c) in qp.contacts.iter().enumerate() {
        let f = &s.contact_forces[c.offset..c.offset + c.model.dim()];
        let names: &[&str] = match c.model.dim() {
            1 => &["fz"],
            3 => &["fx", "fy", "fz"],
            _ => &["fx", "fy", "fz", "mz"],
        };
        let comps: Vec<String> = names
            .iter()
            .zip(f)
            .map(|(n, v)| format!("{n} {}", g(*v, 5)))
            .collect();
        let _ = writeln!(
            o,
            "  {i:<3} {:<5} {:<38} {:>8}",
            c.model.name(),
            comps.join("  "),
            g(s.diagnostics.friction_margins[i], 4)
        );
    }
    let d = &s.diagnostics;
    let _ = writeln!(o, "\nchecks");
    let _ = writeln!(
        o,
        "  ‖G f − w‖∞  {:>10}   (the object is held)",
        g(d.wrench_residual, 3)
    );
    let _ = writeln!(
        o,
        "  ‖Jᵀf − τ‖∞  {:>10}   (the joints produce f)",
        g(d.torque_residual, 3)
    );
    let _ = writeln!(
        o,
        "  ‖C τ − e‖∞  {:>10}   (consistency)",
        g(d.consistency_residual, 3)
    );
    let _ = writeln!(
        o,
        "  max(c − Hτ) {:>10}   (linearised cones)",
        g(d.max_violation, 3)
    );
    let _ = writeln!(o, "\niterations  {}", s.iterations);
    if let Some(a) = &s.active_set {
        let rows: Vec<String> = a
            .iter()
            .map(|&r| format!("{r} ({})", qp.describe_row(r)))
            .collect();
        let _ = writeln!(
            o,
            "key set     {}",
            if rows.is_empty() {
                "(empty)".into()
            } else {
                rows.join(", ")
            }
        );
    }
    let _ = writeln!(o, "solve time  {}", micros(s.solve_time));
    o
}
