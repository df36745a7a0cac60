//! `grasp-torque table`: the paper's Table 1 layout, torques before and after, where
//! "before" is the usual two-step method (optimal contact forces mapped through Jᵀ)
//! and "after" the torque-space optimum.

use super::format::g;
use super::load;
use anyhow::{bail, Result};
use clap::ValueEnum;
use grasp_torque::matrix::norm_inf;
use grasp_torque::{
    solve, ActiveSetSettings, ActiveSetSolver, ForceSpaceQp, ForceSpaceSolver, GraspModel,
    GraspProblem, ModelOptions, Solution, Status, TorqueQp, WarmStart,
};
use serde_json::json;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum TableFormat {
    Markdown,
    Csv,
    Json,
}

#[derive(clap::Args, Debug)]
pub(crate) struct TableArgs {
    /// Problem files, one per object.
    #[arg(required = true)]
    problems: Vec<PathBuf>,
    /// N, sides of the inscribed polygons (overrides the files).
    #[arg(long)]
    sides: Option<usize>,
    /// Output format.
    #[arg(long, value_enum, default_value = "markdown")]
    format: TableFormat,
}

/// One object's comparison.
pub(crate) struct Row {
    pub(crate) name: String,
    pub(crate) joints: Vec<String>,
    pub(crate) before: Vec<f64>,
    pub(crate) after: Vec<f64>,
    /// Why the baseline torque is not admissible under the torque model, if it is not.
    pub(crate) baseline_note: Option<String>,
}

impl Row {
    fn sum_abs(t: &[f64]) -> f64 {
        t.iter().map(|v| v.abs()).sum()
    }
    fn sigma(t: &[f64]) -> f64 {
        t.iter().map(|v| v * v).sum()
    }
}

fn native(qp: TorqueQp, w: &[f64; 6]) -> Result<Solution> {
    let mut s = ActiveSetSolver::new(qp, ActiveSetSettings::default())?;
    Ok(solve(&mut s, w, &WarmStart::default())?)
}

/// Solves both problems for one object.
pub(crate) fn compare(name: String, p: &GraspProblem) -> Result<Row> {
    p.validate()?;
    let model = Arc::new(GraspModel::new(p, &ModelOptions::default())?);
    let torque_qp = TorqueQp::linearized(model.clone(), &p.linearization);
    let after = native(torque_qp.clone(), &p.wrench)?;
    let fs = ForceSpaceQp::new(model.clone(), &p.linearization)?;
    let mut base = Solution::default();
    ForceSpaceSolver::new(fs, ActiveSetSettings::default())?.solve(&p.wrench, &mut base);
    if after.status != Status::Optimal || base.status != Status::Optimal {
        bail!(
            "{name}: torque space {} ({}), force space {} ({})",
            after.status,
            after
                .reason
                .as_ref()
                .map_or(String::new(), |r| r.to_string()),
            base.status,
            base.reason
                .as_ref()
                .map_or(String::new(), |r| r.to_string())
        );
    }
    // The model's Jᵀ maps forces to its torque variables: with a transmission, the
    // actuator forces `T⁺ Jᵀ f` (the baseline keeps Jᵀ f in the range of T).
    let before = model.jacobian_transpose.mul_vec(&base.torque);
    // Is the baseline torque admissible under the torque model (consistency, cones)?
    let mut check = Solution {
        torque: before.clone(),
        ..Default::default()
    };
    torque_qp.complete(&p.wrench, 1e-9, "baseline", &mut check);
    let d = &check.diagnostics;
    let scale = norm_inf(&p.wrench)
        .max(norm_inf(&check.contact_forces))
        .max(f64::MIN_POSITIVE);
    let tol = 1e-9 * scale;
    let baseline_note = (d.consistency_residual > tol || d.max_violation > tol).then(|| {
        format!(
            "the baseline torque is not admissible under the torque model: ‖C τ − e‖∞ = {:.3e}, largest cone-row violation {:.3e} (the force-space optimum uses passive internal forces in null([G; Jᵀ]), which the torque model fixes by its `internal_forces` assumption)",
            d.consistency_residual, d.max_violation
        )
    });
    Ok(Row {
        name,
        joints: (0..p.actuated()).map(|j| p.actuator_name(j)).collect(),
        before,
        after: after.torque,
        baseline_note,
    })
}

/// Percentage reduction; values within rounding of zero print as 0.
fn reduction(before: f64, after: f64) -> f64 {
    let r = if before == 0.0 {
        0.0
    } else {
        100.0 * (before - after) / before
    };
    if r.abs() < 1e-9 {
        0.0
    } else {
        r
    }
}

pub(crate) fn run(args: &TableArgs) -> Result<u8> {
    let mut rows = Vec::new();
    for path in &args.problems {
        let mut p = load(path)?;
        if let Some(n) = args.sides {
            p.linearization.sides = n;
            p.linearization
                .validate()
                .map_err(|e| anyhow::anyhow!("--sides: {e}"))?;
        }
        let name = path
            .file_stem()
            .map_or("?".into(), |s| s.to_string_lossy().into_owned());
        rows.push(compare(name, &p)?);
    }
    let totals = |f: fn(&[f64]) -> f64, before: bool| -> f64 {
        rows.iter()
            .map(|r| f(if before { &r.before } else { &r.after }))
            .sum()
    };
    let (sb, sa) = (totals(Row::sum_abs, true), totals(Row::sum_abs, false));
    let (qb, qa) = (totals(Row::sigma, true), totals(Row::sigma, false));
    match args.format {
        TableFormat::Json => {
            let objects: Vec<_> = rows
                .iter()
                .map(|r| {
                    json!({
                        "name": r.name,
                        "joints": r.joints,
                        "before": r.before.iter().map(|v| v.abs()).collect::<Vec<_>>(),
                        "after": r.after.iter().map(|v| v.abs()).collect::<Vec<_>>(),
                        "sum_abs_before": Row::sum_abs(&r.before),
                        "sum_abs_after": Row::sum_abs(&r.after),
                        "sum_abs_reduction_percent": reduction(Row::sum_abs(&r.before), Row::sum_abs(&r.after)),
                        "sigma_before": Row::sigma(&r.before),
                        "sigma_after": Row::sigma(&r.after),
                        "sigma_reduction_percent": reduction(Row::sigma(&r.before), Row::sigma(&r.after)),
                        "baseline_note": r.baseline_note,
                    })
                })
                .collect();
            let out = json!({
                "objects": objects,
                "overall": {
                    "sum_abs_before": sb, "sum_abs_after": sa, "sum_abs_reduction_percent": reduction(sb, sa),
                    "sigma_before": qb, "sigma_after": qa, "sigma_reduction_percent": reduction(qb, qa),
                }
            });
            outln!("{}", serde_json::to_string_pretty(&out)?);
        }
        TableFormat::Csv => {
            let joints = &rows[0].joints;
            if let Some(r) = rows.iter().find(|r| r.joints != *joints) {
                bail!(
                    "--format csv: {} and {} have different joints, and a CSV file has one header; use --format markdown (one table per set of joints) or json",
                    rows[0].name,
                    r.name
                );
            }
            outln!("object,row,{},sum_abs,sigma", joints.join(","));
            for r in &rows {
                for (label, t) in [("before", &r.before), ("after", &r.after)] {
                    let cells: Vec<String> = t.iter().map(|v| format!("{}", v.abs())).collect();
                    outln!(
                        "{},{label},{},{},{}",
                        r.name,
                        cells.join(","),
                        Row::sum_abs(t),
                        Row::sigma(t)
                    );
                }
            }
            outln!(
                "overall,before,{},{sb},{qb}",
                vec![""; joints.len()].join(",")
            );
            outln!(
                "overall,after,{},{sa},{qa}",
                vec![""; joints.len()].join(",")
            );
        }
        TableFormat::Markdown => {
            outln!("Absolute joint torques (N·m; actuator forces for a hand with a transmission): before = contact-force optimum mapped through Jᵀ (and T⁺), after = torque-space optimum.");
            // One table per set of joints: a column is one joint.
            let mut groups: Vec<(&Vec<String>, Vec<&Row>)> = Vec::new();
            for r in &rows {
                match groups.iter_mut().find(|(j, _)| **j == r.joints) {
                    Some((_, g)) => g.push(r),
                    None => groups.push((&r.joints, vec![r])),
                }
            }
            for (joints, group) in &groups {
                let line = |cells: Vec<String>| format!("| {} |", cells.join(" | "));
                let mut head = vec!["object".to_string(), String::new()];
                head.extend(joints.iter().cloned());
                head.extend(["Σ\\|τ\\|".to_string(), "σ = Στ²".to_string()]);
                outln!("\n{}", line(head.clone()));
                outln!("{}", line(vec!["---".to_string(); head.len()]));
                let blank = || vec![String::new(); joints.len()];
                for r in group {
                    for (label, t) in [("before", &r.before), ("after", &r.after)] {
                        let mut cells = vec![
                            if label == "before" {
                                r.name.clone()
                            } else {
                                String::new()
                            },
                            label.to_string(),
                        ];
                        cells.extend(t.iter().map(|v| format!("{:.4}", v.abs())));
                        cells.push(format!("{:.4}", Row::sum_abs(t)));
                        cells.push(g(Row::sigma(t), 4));
                        outln!("{}", line(cells));
                    }
                    let mut cells = vec![String::new(), "reduction".to_string()];
                    cells.extend(blank());
                    cells.push(format!(
                        "{:.1} %",
                        reduction(Row::sum_abs(&r.before), Row::sum_abs(&r.after))
                    ));
                    cells.push(format!(
                        "{:.1} %",
                        reduction(Row::sigma(&r.before), Row::sigma(&r.after))
                    ));
                    outln!("{}", line(cells));
                }
                let mut cells = vec!["**overall**".to_string(), "reduction".to_string()];
                cells.extend(blank());
                let sum = |f: fn(&[f64]) -> f64, before: bool| -> f64 {
                    group
                        .iter()
                        .map(|r| f(if before { &r.before } else { &r.after }))
                        .sum()
                };
                cells.push(format!(
                    "{:.1} %",
                    reduction(sum(Row::sum_abs, true), sum(Row::sum_abs, false))
                ));
                cells.push(format!(
                    "{:.1} %",
                    reduction(sum(Row::sigma, true), sum(Row::sigma, false))
                ));
                outln!("{}", line(cells));
            }
            if groups.len() > 1 {
                outln!(
                    "\nAll objects: Σ|τ| {:.1} % less, σ {:.1} % less.",
                    reduction(sb, sa),
                    reduction(qb, qa)
                );
            }
            for r in &rows {
                if let Some(n) = &r.baseline_note {
                    outln!("\n{}: {n}", r.name);
                }
            }
        }
    }
    for r in &rows {
        if let Some(n) = &r.baseline_note {
            eprintln!("warning: {}: {n}", r.name);
        }
    }
    Ok(0)
}
