//! `grasp-torque hand`: what a URDF offers a hand-form problem file.

use super::format::g;
use super::Format;
use anyhow::Result;
use grasp_torque::mass::LinkMass;
use grasp_torque::urdf::{Drive, JointKind, Robot};
use serde_json::json;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub(crate) struct HandArgs {
    /// The robot description: a URDF, or an MJCF file (root element `<mujoco>`).
    urdf: PathBuf,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

fn limit(v: Option<impl serde::Serialize>) -> serde_json::Value {
    v.map_or(serde_json::Value::Null, |x| json!(x))
}

pub(crate) fn run(args: &HandArgs) -> Result<u8> {
    // The error names the file already.
    let robot = Robot::load(&args.urdf)?;
    for w in &robot.warnings {
        eprintln!("warning: {w}");
    }
    let joint = |j: usize| &robot.joints[j];
    // Each actuator's limit as `"torque_limits": "model"` takes it (joints'
    // actuatorfrcrange included).
    let all: Vec<usize> = (0..robot.actuators.len()).collect();
    let grasp_torque::hand::ModelLimits { limits, shared } = robot.actuator_limits(&all)?;
    if !shared.is_empty() {
        eprintln!(
            "warning: the actuatorfrcrange of {} bounds several actuators' forces together (or a spatial tendon's): not applied",
            shared.join(", ")
        );
    }
    let moving: Vec<usize> = (0..robot.joints.len())
        .filter(|&j| joint(j).kind != JointKind::Fixed)
        .collect();
    let chains: Vec<(usize, Vec<usize>)> = robot
        .leaves()
        .into_iter()
        .map(|l| {
            let c = robot
                .chain(l)
                .into_iter()
                .filter(|&j| joint(j).kind != JointKind::Fixed)
                .collect();
            (l, c)
        })
        .collect();
    // The links' masses, for `hand.gravity`.
    let (mut known, mut unknown) = (Vec::new(), Vec::new());
    for (l, m) in robot.masses.iter().enumerate() {
        match m {
            LinkMass::Known { mass, com } if *mass > 0.0 => known.push((l, *mass, *com)),
            LinkMass::Unknown(why) => unknown.push((l, why)),
            _ => {}
        }
    }
    let total: f64 = known.iter().map(|k| k.1).sum();
    let leader = |j: usize| {
        let c = robot.coupling[j].expect("a moving joint has a coupling");
        (joint(robot.independent[c.independent]).name.clone(), c)
    };
    match args.format {
        Format::Json => {
            let v = json!({
                "robot": robot.name,
                "file": args.urdf.display().to_string(),
                "root": robot.links[robot.root],
                "links": robot.links,
                "independent_joints": robot.independent.iter().map(|&j| json!({
                    "name": joint(j).name,
                    "type": joint(j).kind.name(),
                    "lower": limit(joint(j).lower),
                    "upper": limit(joint(j).upper),
                    "effort": limit(joint(j).effort),
                    "child": robot.links[joint(j).child],
                })).collect::<Vec<_>>(),
                "mimic_joints": moving.iter().filter(|&&j| joint(j).mimic.is_some()).map(|&j| {
                    let (name, c) = leader(j);
                    json!({"name": joint(j).name, "type": joint(j).kind.name(), "follows": name,
                           "multiplier": c.multiplier, "offset": c.offset})
                }).collect::<Vec<_>>(),
                "chains": chains.iter().map(|(l, c)| json!({
                    "link": robot.links[*l],
                    "independent_joints": dedup(c.iter().map(|&j| leader(j).0)),
                })).collect::<Vec<_>>(),
                "sites": robot.sites.iter().map(|s| json!({"name": s.name, "link": robot.links[s.link]})).collect::<Vec<_>>(),
                "actuators": robot.actuators.iter().zip(&limits).map(|(a, (lim, source))| {
                    let mut v = json!({
                        "name": a.name,
                        "type": a.kind,
                        "limit": limit(*lim),
                        "limit_source": source,
                    });
                    match &a.drive {
                        Drive::Fixed(moment) => v["moment"] = json!(moment.iter().map(|&(j, m)| (joint(j).name.clone(), m)).collect::<std::collections::BTreeMap<_, _>>()),
                        Drive::Tendon { tendon, gear } => v["spatial_tendon"] = json!({
                            "name": robot.tendons[*tendon].name,
                            "gear": gear,
                            "joints": robot.tendon_joints(*tendon).iter().map(|&j| &joint(j).name).collect::<Vec<_>>(),
                        }),
                    }
                    v
                }).collect::<Vec<_>>(),
                "masses": known.iter().map(|(l, m, c)| json!({
                    "link": robot.links[*l], "mass": m, "com": [c.x, c.y, c.z],
                })).collect::<Vec<_>>(),
                "unknown_masses": unknown.iter().map(|(l, why)| json!({
                    "link": robot.links[*l], "why": why,
                })).collect::<Vec<_>>(),
                "gravity": robot.gravity.map(|g| [g.x, g.y, g.z]),
                "warnings": robot.warnings,
            });
            outln!("{}", serde_json::to_string_pretty(&v)?);
        }
        Format::Text => {
            outln!(
                "robot `{}` ({}): {} links, root `{}`",
                robot.name,
                args.urdf.display(),
                robot.links.len(),
                robot.links[robot.root]
            );
            outln!(
                "\nindependent joints ({}; positions in radians, or metres for prismatic; effort in N·m or N)",
                robot.independent.len()
            );
            let width = robot
                .independent
                .iter()
                .map(|&j| joint(j).name.chars().count())
                .max()
                .unwrap_or(0);
            let show = |v: Option<f64>| v.map_or("—".to_string(), |x| g(x, 5));
            for &j in &robot.independent {
                let jt = joint(j);
                outln!(
                    "  {:<width$}  {:<10}  [{}, {}]  effort {}",
                    jt.name,
                    jt.kind.name(),
                    show(jt.lower),
                    show(jt.upper),
                    jt.effort
                        .map_or("—".into(), |l| l.describe("τ", |x| g(x, 5)))
                );
            }
            let mimics: Vec<usize> = moving
                .iter()
                .copied()
                .filter(|&j| joint(j).mimic.is_some())
                .collect();
            if !mimics.is_empty() {
                outln!("\nmimic joints (q = multiplier · q_leader + offset, chains resolved)");
                for j in mimics {
                    let (name, c) = leader(j);
                    let sign = if c.offset < 0.0 { '−' } else { '+' };
                    outln!(
                        "  {} = {} · {name} {sign} {}",
                        joint(j).name,
                        g(c.multiplier, 8),
                        g(c.offset.abs(), 8)
                    );
                }
            }
            if !robot.actuators.is_empty() {
                outln!("\nactuators (τ = T u: moment arms on the joints; the force u within its limit)");
                let width = robot
                    .actuators
                    .iter()
                    .map(|a| a.name.chars().count())
                    .max()
                    .unwrap_or(0);
                for (a, (lim, source)) in robot.actuators.iter().zip(&limits) {
                    let arms: Vec<String> = match &a.drive {
                        Drive::Fixed(moment) => moment
                            .iter()
                            .map(|&(j, m)| format!("{}·{}", g(m, 6), joint(j).name))
                            .collect(),
                        Drive::Tendon { tendon, gear } => {
                            let joints: Vec<&str> = robot
                                .tendon_joints(*tendon)
                                .iter()
                                .map(|&j| joint(j).name.as_str())
                                .collect();
                            vec![format!(
                                "{}·spatial tendon `{}` (arms vary with the configuration; on {})",
                                g(*gear, 6),
                                robot.tendons[*tendon].name,
                                joints.join(", ")
                            )]
                        }
                    };
                    let lim = match lim {
                        Some(l) => format!(
                            "{} ({})",
                            l.describe("u", |v| g(v, 5)),
                            format!("{source:?}").to_lowercase()
                        ),
                        None => "unlimited".into(),
                    };
                    outln!(
                        "  {:<width$}  {:<11}  {}   {lim}",
                        a.name,
                        a.kind,
                        arms.join(" + ")
                    );
                }
            }
            if !robot.sites.is_empty() {
                let names: Vec<&str> = robot.sites.iter().map(|s| s.name.as_str()).collect();
                outln!("\nsites ({}): {}", names.len(), names.join(", "));
            }
            outln!(
                "\nmasses (for hand.gravity): {} over {} links; gravity in the file: {}",
                g(total, 6),
                known.len(),
                robot.gravity.map_or("none".into(), |v| format!(
                    "[{}, {}, {}]",
                    g(v.x, 6),
                    g(v.y, 6),
                    g(v.z, 6)
                ))
            );
            for (l, why) in &unknown {
                outln!("  unknown: {}: {why}", robot.links[*l]);
            }
            outln!("\nchains (end link: the independent joints that move it, root first)");
            for (l, c) in &chains {
                let names = dedup(c.iter().map(|&j| leader(j).0));
                outln!(
                    "  {}: {}",
                    robot.links[*l],
                    if names.is_empty() {
                        "(fixed to the root)".into()
                    } else {
                        names.join(", ")
                    }
                );
            }
        }
    }
    Ok(0)
}

/// Names in order, each once (a mimic joint credits its leader, which may already be
/// on the chain).
fn dedup(names: impl Iterator<Item = String>) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for n in names {
        if !out.contains(&n) {
            out.push(n);
        }
    }
    out
}
