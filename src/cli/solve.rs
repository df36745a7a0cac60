//! `grasp-torque solve`.

use super::format::{g, micros};
use super::{load_report, parse_list, Format, ModelArgs};
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
    if s.has_answer() {
        0
    } else if s == Status::Infeasible {
        3
    } else {
        4
    }
}

pub(crate) fn run(args: &SolveArgs) -> Result<u8> {
    let loaded = load_report(&args.problem)?;
    let hand = loaded.hand;
    let mut problem = loaded.problem;
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
    let mut sol = solver.solution().clone();
    sol.warnings
        .extend(solver.problem().model.zeroed_joint_warnings());
    let sol = &sol;
    for w in &sol.warnings {
        eprintln!("warning: {w}");
    }
    let qp = solver.problem();
    let cones = config.cones.name();
    match args.format {
        Format::Json => {
            let mut v = to_json(qp, sol, solver.backend_name(), cones);
            if let (Some(h), Some(o)) = (&hand, v.as_object_mut()) {
                o.insert("hand".into(), serde_json::to_value(h)?);
            }
            outln!("{}", serde_json::to_string_pretty(&v)?)
        }
        Format::Text => {
            out!(
                "{}",
                text_report(
                    &args.problem.display().to_string(),
                    qp,
                    sol,
                    solver.backend_name(),
                    cones
                )
            );
            if let Some(h) = &hand {
                out!("{}", hand_text(h));
            }
        }
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

/// The JSON report: the serialised [`Solution`], with the problem's context.
pub(crate) fn to_json(
    qp: &TorqueQp,
    s: &Solution,
    backend: &str,
    cones: &str,
) -> serde_json::Value {
    let model = &qp.model;
    let mut v = serde_json::to_value(s).unwrap_or_else(|_| json!({}));
    let ok = !s.torque.is_empty();
    let o = v.as_object_mut().expect("a struct serialises to an object");
    if !ok {
        for key in [
            "torque",
            "contact_forces",
            "object_forces",
            "objective",
            "internal_forces",
        ] {
            o.insert(key.into(), json!(null));
        }
    } else {
        o.insert(
            "contact_forces".into(),
            json!(per_contact(qp, &s.contact_forces)),
        );
        // (Deferred by the lazy check, f is empty.)
        if !s.contact_forces.is_empty() {
            o.insert(
                "object_forces".into(),
                json!(grasp_torque::model::object_forces(
                    &model.grasp_matrix,
                    &model.contacts,
                    &s.contact_forces
                )),
            );
        }
    }
    let d = &s.diagnostics;
    o.insert(
        "residuals".into(),
        if ok {
            json!({"wrench": d.wrench_residual, "torque": d.torque_residual, "consistency": d.consistency_residual})
        } else {
            json!(null)
        },
    );
    let names: Vec<String> = (0..model.joints()).map(|j| model.joint_name(j)).collect();
    match &model.actuators {
        // `torque` holds u, one per actuator; `joint_torque` τ = T u, one per joint.
        Some(a) => {
            o.insert("actuator_names".into(), json!(names));
            o.insert(
                "joint_names".into(),
                json!((0..a.joints())
                    .map(|j| a
                        .joint_names
                        .get(j)
                        .cloned()
                        .unwrap_or_else(|| format!("joint {j}")))
                    .collect::<Vec<_>>()),
            );
            if !ok {
                o.insert("joint_torque".into(), json!(null));
            }
        }
        None => {
            o.insert("joint_names".into(), json!(names));
        }
    }
    // τ_p per joint (`joint_names`): Jᵀ f = τ + τ_p.
    if !model.passive.joint_torque.is_empty() {
        o.insert("passive_torque".into(), json!(model.passive.joint_torque));
    }
    o.insert(
        "contact_models".into(),
        json!(qp
            .contacts
            .iter()
            .map(|c| c.model.name())
            .collect::<Vec<_>>()),
    );
    o.insert(
        "passive_internal_forces".into(),
        json!({"dimension": model.passive_dim(), "assumption": model.internal_forces.name()}),
    );
    o.insert("backend".into(), json!(backend));
    o.insert("cones".into(), json!(cones));
    if let Some(lin) = qp.constraints.linearization {
        o.insert("sides".into(), json!(lin.sides));
        o.insert("latitudes".into(), json!(lin.latitudes));
    }
    o.insert("constraint_rows".into(), json!(qp.inequality_rows()));
    o.insert(
        "consistency".into(),
        json!(model.equilibrium == Equilibrium::Consistent),
    );
    v
}

/// What a hand-form problem adds to the text report.
fn hand_text(h: &grasp_torque::hand::HandReport) -> String {
    use grasp_torque::urdf::LimitSource;
    use std::fmt::Write;
    let mut o = String::new();
    let _ = writeln!(o, "\nhand        {} (robot `{}`)", h.model, h.robot);
    if !h.defaulted_joints.is_empty() {
        let _ = writeln!(
            o,
            "            at 0 (not in joint_positions): {}",
            h.defaulted_joints.join(", ")
        );
    }
    let limits = match h.torque_limits {
        "model" if !h.actuator_limits.is_empty() => {
            let from = |s: LimitSource| h.actuator_limits.iter().filter(|a| a.source == s).count();
            format!(
                "actuator force limits from the model: {} from forcerange, {} from ctrlrange × gain, {} none",
                from(LimitSource::Forcerange),
                from(LimitSource::Ctrlrange),
                from(LimitSource::None)
            )
        }
        "model" => "torque limits from each joint's <limit effort>".into(),
        "file" => "limits from the file".into(),
        _ => "no limits".into(),
    };
    let _ = writeln!(o, "            {limits}");
    if let Some(a) = h.gravity {
        let _ =
            writeln!(
            o,
            "            gravity [{}, {}, {}] in the root frame, on the links (passive torques){}",
            g(a[0], 5),
            g(a[1], 5),
            g(a[2], 5),
            if h.object_weight.is_some() { " and the object" } else { "" }
        );
    }
    if let Some(w) = h.object_weight {
        let _ = writeln!(
            o,
            "            the object's weight asks [{}] of the contacts (in the wrench)",
            w.map(|v| g(v, 5)).join(", ")
        );
    }
    if !h.unlimited_joints.is_empty() {
        let _ = writeln!(
            o,
            "            unlimited: {}",
            h.unlimited_joints.join(", ")
        );
    }
    o
}

/// A force component for the report: below the problem's rounding level it is 0.
fn component(v: f64, zero: f64) -> String {
    if v.abs() <= zero {
        "0".into()
    } else {
        g(v, 5)
    }
}

fn text_report(name: &str, qp: &TorqueQp, s: &Solution, backend: &str, cones: &str) -> String {
    use std::fmt::Write;
    let model = &qp.model;
    let mut o = String::new();
    let _ = writeln!(o, "problem   {name}");
    let cone_text = match qp.constraints.linearization {
        Some(lin) if !qp.constraints.has_exact() => format!(
            "inscribed cones with {} linear rows (N = {}, K = {})",
            qp.inequality_rows(),
            lin.sides,
            lin.latitudes
        ),
        _ => "exact cones".to_string(),
    };
    let _ = writeln!(
        o,
        "model     {}, {} contacts, {cone_text}, {}",
        match &model.actuators {
            Some(a) => format!("{} actuators driving {} joints", qp.joints(), a.joints()),
            None => format!("{} joints", qp.joints()),
        },
        qp.contacts.len(),
        match model.equilibrium {
            Equilibrium::Consistent => format!("{} consistency equalities", qp.equality_rows()),
            Equilibrium::PaperModel => "paper model (no consistency equalities)".to_string(),
        }
    );
    if model.passive_dim() > 0 {
        let _ = writeln!(
            o,
            "          [G; Jᵀ] has a {}-dimensional null space (passive internal forces), fixed by `{}`",
            model.passive_dim(),
            model.internal_forces.name()
        );
    }
    let method = s.method.map(|m| format!(" ({m})")).unwrap_or_default();
    let _ = writeln!(o, "backend   {backend}, {cones} cones{method}");
    let _ = writeln!(o, "status    {}", s.status);
    if let Some(r) = &s.reason {
        let _ = writeln!(o, "reason    {r}");
    }
    if s.torque.is_empty() {
        return o;
    }
    let _ = writeln!(o, "objective σ = Σ w τ² = {}", g(s.objective, 10));
    let _ = writeln!(
        o,
        "\n{}",
        if model.actuators.is_some() {
            "actuator forces u"
        } else {
            "joint torques"
        }
    );
    let names: Vec<String> = (0..model.joints()).map(|j| model.joint_name(j)).collect();
    let width = names.iter().map(|n| n.chars().count()).max().unwrap_or(0);
    // Torques below the check's tolerance of the largest are rounding: shown as 0.
    let tmax = s.torque.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let tzero = s.diagnostics.check_tolerance * tmax;
    let limits = &model.torque_limits;
    for (j, (n, t)) in names.iter().zip(&s.torque).enumerate() {
        let shown = if t.abs() <= tzero {
            "0".into()
        } else {
            g(*t, 7)
        };
        let limit = match limits.get(j).copied().flatten() {
            Some(l) => {
                // Within √tol of a bound, relative to it or to the largest torque.
                let near = |b: f64| {
                    (t - b).abs() <= s.diagnostics.check_tolerance.sqrt() * b.abs().max(tmax)
                };
                let at = if l.lower().is_some_and(near) || l.upper().is_some_and(near) {
                    "  at its limit"
                } else {
                    ""
                };
                let var = if model.actuators.is_some() { "u" } else { "τ" };
                format!("   {}{at}", l.describe(var, |v| g(v, 4)))
            }
            _ => String::new(),
        };
        let _ = writeln!(o, "  {n:<width$}  {shown:>13}{limit}");
    }
    if let Some(a) = &model.actuators {
        let _ = writeln!(o, "\njoint torques τ = T u");
        let names: Vec<String> = (0..a.joints())
            .map(|j| {
                a.joint_names
                    .get(j)
                    .cloned()
                    .unwrap_or_else(|| format!("joint {j}"))
            })
            .collect();
        let width = names.iter().map(|n| n.chars().count()).max().unwrap_or(0);
        let tmax = s.joint_torque.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let tzero = s.diagnostics.check_tolerance * tmax;
        for (n, t) in names.iter().zip(&s.joint_torque) {
            let shown = if t.abs() <= tzero {
                "0".into()
            } else {
                g(*t, 7)
            };
            let _ = writeln!(o, "  {n:<width$}  {shown:>13}");
        }
    }
    let passive = &model.passive.joint_torque;
    if !passive.is_empty() {
        let _ = writeln!(o, "\npassive joint torques τ_p: Jᵀ f = τ + τ_p");
        let names: Vec<String> = match &model.actuators {
            Some(a) => (0..a.joints())
                .map(|j| {
                    a.joint_names
                        .get(j)
                        .cloned()
                        .unwrap_or_else(|| format!("joint {j}"))
                })
                .collect(),
            None => names.clone(),
        };
        let width = names.iter().map(|n| n.chars().count()).max().unwrap_or(0);
        for (n, t) in names.iter().zip(passive) {
            let _ = writeln!(o, "  {n:<width$}  {:>13}", g(*t, 7));
        }
    }
    // Components below the check's tolerance of the largest force are rounding.
    let fmax = s
        .contact_forces
        .iter()
        .zip(&model.force_unit)
        .fold(0.0f64, |a, (v, u)| a.max((v / u).abs()));
    let zero = s.diagnostics.check_tolerance * fmax;
    let _ = writeln!(
        o,
        "\ncontact forces (contact frame)   {:>11} {:>11} {:>11} {:>11}   exact-cone margin",
        "fx", "fy", "fz", "mz"
    );
    for (i, c) in qp.contacts.iter().enumerate() {
        let f = &s.contact_forces[c.offset..c.offset + c.model.dim()];
        let slots: [Option<f64>; 4] = match c.model.dim() {
            1 => [None, None, Some(f[0]), None],
            3 => [Some(f[0]), Some(f[1]), Some(f[2]), None],
            _ => [Some(f[0]), Some(f[1]), Some(f[2]), Some(f[3])],
        };
        // mz is compared in force units (mz/mu_torsion), like the other components.
        let mz_unit = model.force_unit[c.offset + c.model.dim() - 1];
        let cells: Vec<String> = slots
            .iter()
            .enumerate()
            .map(|(k, v)| {
                let unit = if k == 3 { mz_unit } else { 1.0 };
                v.map_or("—".into(), |x| component(x, zero * unit))
            })
            .map(|t| format!("{t:>11}"))
            .collect();
        let margin = match s.diagnostics.friction_margins.get(i).copied().flatten() {
            Some(m) if m.abs() <= s.diagnostics.check_tolerance => "0".into(),
            Some(m) => g(m, 4),
            None => "unloaded".into(),
        };
        let _ = writeln!(
            o,
            "  {i:<3} {:<5}                    {}   {margin:>8}",
            c.model.name(),
            cells.join(" ")
        );
    }
    let forces =
        grasp_torque::model::object_forces(&model.grasp_matrix, &model.contacts, &s.contact_forces);
    let fmax = forces.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    let _ = writeln!(
        o,
        "
forces on the object (object frame) {:>11} {:>11} {:>11}",
        "Fx", "Fy", "Fz"
    );
    for (i, f) in forces.iter().enumerate() {
        let cells: Vec<String> = f
            .iter()
            .map(|&x| format!("{:>11}", component(x, s.diagnostics.check_tolerance * fmax)))
            .collect();
        let _ = writeln!(
            o,
            "  {i:<3}                               {}",
            cells.join(" ")
        );
    }
    let d = &s.diagnostics;
    let share = |x: f64| {
        if x < 1e-3 {
            "< 0.001".to_string()
        } else {
            g(x, 2)
        }
    };
    let _ = writeln!(
        o,
        "\nchecks (relative tolerance {:.0e}; a residual is judged against its row's share of the largest force)",
        d.check_tolerance
    );
    let _ = writeln!(
        o,
        "  ‖G f − w‖∞  {:>10}   {}",
        g(d.wrench_residual, 3),
        if d.wrench_check <= 1.0 {
            format!(
                "(the object is held: {} of the tolerance)",
                share(d.wrench_check)
            )
        } else {
            format!(
                "(the object is NOT held: {}× the tolerance)",
                g(d.wrench_check, 2)
            )
        }
    );
    let with = if passive.is_empty() { "" } else { " with τ_p" };
    let _ = writeln!(
        o,
        "  ‖Jᵀf − τ‖∞  {:>10}   {}",
        g(d.torque_residual, 3),
        if d.torque_check <= 1.0 {
            format!(
                "(the joints produce f{with}: {} of the tolerance)",
                share(d.torque_check)
            )
        } else {
            format!(
                "(the joints do NOT produce f{with}: {}× the tolerance)",
                g(d.torque_check, 2)
            )
        }
    );
    if model.equilibrium == Equilibrium::Consistent {
        let _ = writeln!(
            o,
            "  ‖C τ − e‖∞  {:>10}   (consistency)",
            g(d.consistency_residual, 3)
        );
    }
    // Each verdict is the check's own: the worst row against the bound it was judged by.
    let verdict = |ratio: f64| {
        if ratio <= 1.0 {
            format!("{} of the tolerance", share(ratio))
        } else {
            format!("VIOLATED: {}× the tolerance", g(ratio, 2))
        }
    };
    if qp.constraints.has_exact() {
        let _ = writeln!(
            o,
            "  max(g − fz) {:>10}   (exact cones, g the cone's gauge, ≤ 0 inside: {})",
            g(d.cone_violation, 3),
            verdict(d.cone_check)
        );
        let _ = writeln!(
            o,
            "  max(c − Hτ) {:>10}   (minimum normal forces and torque limits: {})",
            g(d.max_violation, 3),
            verdict(d.violation_check)
        );
    } else {
        let _ = writeln!(
            o,
            "  max(c − Hτ) {:>10}   (inscribed cones, minimum normal forces, torque limits: {})",
            g(d.max_violation, 3),
            verdict(d.violation_check)
        );
    }
    let _ = writeln!(o, "\niterations  {}", s.iterations);
    if let Some(a) = &s.active_set {
        let rows: Vec<String> = a.iter().map(|&r| format!("{r} ({})", qp.rows[r])).collect();
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
