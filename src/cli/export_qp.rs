//! `grasp-torque export-qp`: the linearised torque QP exactly as the native solver
//! receives it, for peers (DAQP, qpbenchmark) to solve like for like.

use super::{load, ModelArgs};
use anyhow::{bail, Result};
use grasp_torque::{GraspSolver, InternalForces, Matrix, WarmStart};
use serde_json::json;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub(crate) struct ExportQpArgs {
    /// The problem file (any form).
    problem: PathBuf,
    #[command(flatten)]
    model: ModelArgs,
    /// Output format (JSON only).
    #[arg(long, value_enum, default_value = "json")]
    format: ExportFormat,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ExportFormat {
    Json,
}

pub(crate) fn run(args: &ExportQpArgs) -> Result<u8> {
    let mut p = load(&args.problem)?;
    let config = args.model.configure(&mut p)?;
    if config.cones != grasp_torque::Cones::Linear {
        bail!("--cones: export-qp writes the linearised QP; exact cones are second-order cones, not rows");
    }
    if p.internal_forces == InternalForces::Free {
        bail!("--internal-forces: export-qp writes the QP in τ alone; free internal forces add variables (use compliance or euclidean)");
    }
    let mut solver = GraspSolver::new(&p, &config)?;
    let sol = solver
        .solve(
            &p.wrench,
            &WarmStart {
                torque: p.initial_torque.as_deref(),
                active_set: None,
            },
        )?
        .clone();
    let qp = solver.problem();
    let ld = qp.least_distance();
    let w = p.wrench;
    let mut c = vec![0.0; qp.inequality_rows()];
    qp.c_into(&w, &mut c);
    let mut e = vec![0.0; qp.equality_rows()];
    qp.model.e_into(&w, &mut e);
    let rows = |m: &Matrix| m.to_rows();
    let v = json!({
        "problem": args.problem.display().to_string(),
        "form": "minimise Σ_j weights_j τ_j² subject to H τ ≥ c(w) = c0 − Hw w and C τ = e(w) = −Cw w; the answer is τ + torque_offset (passive torques)",
        "torque_offset": (!qp.model.passive.is_empty()).then_some(&qp.model.passive.torque_offset),
        "joints": qp.joints(),
        "joint_names": (0..qp.joints()).map(|j| qp.model.joint_name(j)).collect::<Vec<_>>(),
        "sides": p.linearization.sides,
        "latitudes": p.linearization.latitudes,
        "internal_forces": p.internal_forces.name(),
        "weights": ld.weights,
        "H": rows(qp.h()),
        "c0": ld.c0,
        "Hw": rows(ld.hw),
        "C": rows(ld.eq),
        "Cw": rows(ld.eq_w),
        "row_names": ld.rows.iter().map(ToString::to_string).collect::<Vec<_>>(),
        "wrench": w,
        "c": c,
        "e": e,
        "solution": {
            "status": sol.status,
            "objective": (!sol.torque.is_empty()).then_some(sol.objective),
            "torque": sol.torque,
            "active_set": sol.active_set,
            "multipliers": sol.multipliers,
        },
    });
    outln!("{}", serde_json::to_string_pretty(&v)?);
    Ok(0)
}
