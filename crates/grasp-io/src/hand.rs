//! The hand form: a robot description (URDF), joint positions, an object pose and
//! contacts on named links. Forward kinematics gives every joint's frame; G and Jᵀ then
//! follow the geometry form's convention (`docs/geometry.md`), in the object frame, and
//! mimic couplings reduce Jᵀ to the independent joints (`Jᵀ = Pᵀ Jᵀ_full`).
//!
//! The problem's joints are the independent joints that move at least one contact, in
//! the order of their `<joint>` elements in the URDF. A mimic joint's motion is credited
//! to the independent joint at the end of its mimic chain, scaled by the product of the
//! multipliers.

use crate::file::{ModelName, Options};
use crate::frame::{Isometry3, UnitQuaternion, Vector3};
use crate::geometry::{check_vec, contact_frame, UNIT_TOLERANCE};
use crate::urdf::{nearest, Drive, JointKind, LimitSource, Pose, Robot};
use grasp_core::by_name::ByName;
use grasp_core::contact::ContactModel;
use grasp_core::error::ProblemError;
use grasp_core::matrix::Matrix;
use grasp_core::problem::{
    contact_count, flush_subnormal, in_domain, GraspProblem, TorqueLimit, MAX_JOINTS, MAX_MAGNITUDE,
};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A JSON object read as a map whose keys must differ: JSON readers keep the last of
/// a repeated key, which here would be a copy-paste slip passed over in silence.
fn unique_keys<'de, D: serde::Deserializer<'de>>(d: D) -> Result<BTreeMap<String, f64>, D::Error> {
    struct Unique;
    impl<'de> serde::de::Visitor<'de> for Unique {
        type Value = BTreeMap<String, f64>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("an object of joint names and positions")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(
            self,
            mut a: A,
        ) -> Result<Self::Value, A::Error> {
            let mut map = BTreeMap::new();
            while let Some((k, v)) = a.next_entry::<String, f64>()? {
                if map.contains_key(&k) {
                    return Err(serde::de::Error::custom(format!("`{k}` is given twice")));
                }
                map.insert(k, v);
            }
            Ok(map)
        }
    }
    d.deserialize_map(Unique)
}

/// `hand`: which robot, in which configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandSpec {
    /// A URDF path; a relative path is relative to the problem file.
    pub model: String,
    /// Positions of independent joints by name, in radians (revolute, continuous) or
    /// metres (prismatic). A joint not listed sits at 0; one listed twice is an error.
    #[serde(default, deserialize_with = "unique_keys")]
    pub joint_positions: BTreeMap<String, f64>,
    /// The acceleration of gravity on the fingers, `[gx, gy, gz]` in the root frame
    /// (m/s² in SI; a URDF's root link, an MJCF's world), or `"model"` for an MJCF
    /// file's `<option gravity>`: the links' weight then enters as passive joint
    /// torques. Absent: the fingers are weightless. It also weighs the held `object`
    /// when the file gives its mass.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<serde_json::Value>,
}

/// The object frame in the robot's root-link frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectPose {
    /// Origin of the object frame (default 0).
    #[serde(default)]
    pub position: [f64; 3],
    /// Orientation as a unit quaternion `[w, x, y, z]` (default identity).
    #[serde(default = "identity")]
    pub quaternion: [f64; 4],
}

fn identity() -> [f64; 4] {
    [1.0, 0.0, 0.0, 0.0]
}

impl Default for ObjectPose {
    fn default() -> Self {
        Self {
            position: [0.0; 3],
            quaternion: identity(),
        }
    }
}

/// `object`: the held object's mass, whose weight the contacts then carry.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeldObject {
    /// Its mass, in kg when gravity is in m/s² and forces in N (0 to 1e12).
    pub mass: f64,
    /// Its centre of mass in the object frame (default the object frame's origin).
    #[serde(default)]
    pub center_of_mass: [f64; 3],
}

impl HeldObject {
    /// What the contacts must apply to carry the weight `m g` (`gravity` in the root
    /// frame, the object frame turned by `rotation` in it): `F = −m Rᵀ g` at the centre
    /// of mass c, so `[F; c × F]` about the object frame's origin.
    pub fn weight_wrench(&self, gravity: &Vector3, rotation: &UnitQuaternion) -> [f64; 6] {
        let f = rotation.inverse_transform_vector(gravity) * -self.mass;
        let m = Vector3::from(self.center_of_mass).cross(&f);
        // (+ 0 reports a zero component as 0, not −0.)
        [f.x, f.y, f.z, m.x, m.y, m.z].map(|v| flush_subnormal(v) + 0.0)
    }
}

/// The frame a contact's position and normal are given in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ContactFrame {
    /// The object frame (default).
    #[default]
    Object,
    /// The frame of the contact's `link`, as tactile sensors report.
    Link,
}

impl ByName for ContactFrame {
    const VARIANTS: &'static [Self] = &[Self::Object, Self::Link];
    const NAMES: &'static [&'static str] = &["object", "link"];
}
grasp_core::deserialize_by_name!(ContactFrame);

/// One contact on a link of the hand.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandContact {
    /// Optional name, used in messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The link (an MJCF body) that touches: every moving joint from the root to it
    /// moves the contact. Give either `link` with `position`, or `site`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub link: Option<String>,
    /// An MJCF site: the contact point is its origin, on its body, and its z axis is
    /// the normal unless `normal` is given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub site: Option<String>,
    /// Contact point (with `link`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<[f64; 3]>,
    /// Unit normal, pointing into the object (optional with `site`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f64; 3]>,
    /// `object` (default) or `link`: the frame of `position` and `normal`.
    #[serde(default)]
    pub frame: ContactFrame,
    /// `fpc`, `pcwf`, `sfcl` or `sfce`.
    pub model: ModelName,
    /// Tangential friction coefficient.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu: Option<f64>,
    /// Torsional friction coefficient, a length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu_torsion: Option<f64>,
}

/// A problem file in hand form.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandFile {
    /// Free-text name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Free-text description.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// The robot and its configuration.
    pub hand: HandSpec,
    /// The object frame in the root-link frame (default identity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub object_pose: Option<ObjectPose>,
    /// The held object's mass and centre of mass: with a gravity (`hand.gravity`), its
    /// weight is added to `wrench`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub object: Option<HeldObject>,
    /// The contacts; their order is the column order of G.
    pub contacts: Vec<HandContact>,
    /// `[Fx Fy Fz Mx My Mz]` the contacts must apply to the object, in the object frame
    /// about its origin: required, unless `object` gives its weight (then it is what
    /// they apply besides, default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wrench: Option<Vec<f64>>,
    /// See the matrix form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linearization: Option<grasp_core::cone::Linearization>,
    /// See the matrix form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_weights: Option<Vec<f64>>,
    /// `"model"` for each joint's `<limit effort>`, or a list as in the matrix form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_limits: Option<serde_json::Value>,
    /// See the matrix form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_normal_force: Option<serde_json::Value>,
    /// See the matrix form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_torque: Option<Vec<f64>>,
    /// See the matrix form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub internal_forces: Option<grasp_core::model::InternalForces>,
}

/// What a hand-form problem was built from, for reports.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct HandReport {
    /// The URDF path, as written in the file.
    pub model: String,
    /// `<robot name>`.
    pub robot: String,
    /// The problem's joints that were not in `joint_positions` and sit at 0.
    pub defaulted_joints: Vec<String>,
    /// Where the torque limits came from: `"model"` (`<limit effort>`), `"file"` or
    /// `"none"`.
    pub torque_limits: &'static str,
    /// The problem's joints without a usable `<limit effort>`, when limits come from
    /// the model: they are unlimited.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unlimited_joints: Vec<String>,
    /// Per actuator of an MJCF hand: its force limit and where it comes from
    /// (`forcerange`, `ctrlrange` × gain, or `none`), whether or not limits are used.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub actuator_limits: Vec<ActuatorLimit>,
    /// The acceleration of gravity on the links, in the root frame, when the links'
    /// weight is part of the passive torques.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gravity: Option<[f64; 3]>,
    /// With `object`: what its weight asks of the contacts, in the object frame (part
    /// of the problem's wrench).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub object_weight: Option<[f64; 6]>,
    /// What was loaded but ignored, or looks wrong (one line each).
    pub warnings: Vec<String>,
}

/// An actuator's force limit in a report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ActuatorLimit {
    /// The actuator.
    pub actuator: String,
    /// `|u| ≤ t` (a number) or `lower ≤ u ≤ upper` (`[lower, upper]`), in the
    /// actuator's force unit (N or N·m times its gear's unit).
    pub limit: Option<TorqueLimit>,
    /// Where it comes from.
    pub source: crate::urdf::LimitSource,
}

/// The actuators' force limits as `"torque_limits": "model"` takes them
/// ([`Robot::actuator_limits`]).
#[derive(Clone, Debug)]
pub struct ModelLimits {
    /// Per actuator asked for: its limit (`None`: unlimited) and where it comes from.
    pub limits: Vec<(Option<TorqueLimit>, LimitSource)>,
    /// The joints whose `actuatorfrcrange` bounds no single actuator: not applied.
    pub shared: Vec<String>,
}

impl Robot {
    /// Each of the actuators `columns`' force limit for `"torque_limits": "model"`, and
    /// where it comes from: its own range, narrowed by the `actuatorfrcrange` of every
    /// joint it alone drives through a constant arm m (MuJoCo clamps the total actuator
    /// force on a joint, here `m u`, to that range). Also the joints whose range bounds
    /// several actuators' forces together, or a spatial tendon's arm that changes with
    /// the configuration: no bound on one actuator, so not applied (callers warn). An
    /// actuator whose ranges leave no force is an error.
    pub fn actuator_limits(&self, columns: &[usize]) -> Result<ModelLimits, ProblemError> {
        // Per actuator, the joints it moves: (joint, constant arm, or None for a spatial
        // tendon's).
        let moves: Vec<Vec<(usize, Option<f64>)>> = self
            .actuators
            .iter()
            .map(|a| match &a.drive {
                Drive::Fixed(moment) => {
                    let mut v: Vec<(usize, Option<f64>)> = Vec::new();
                    for &(j, m) in moment {
                        match v.iter_mut().find(|e| e.0 == j) {
                            Some((_, Some(s))) => *s += m,
                            _ => v.push((j, Some(m))),
                        }
                    }
                    v.retain(|e| e.1 != Some(0.0));
                    v
                }
                Drive::Tendon { tendon, .. } => self
                    .tendon_joints(*tendon)
                    .into_iter()
                    .map(|j| (j, None))
                    .collect(),
            })
            .collect();
        let mut drivers = vec![0usize; self.joints.len()];
        for v in &moves {
            for &(j, _) in v {
                drivers[j] += 1;
            }
        }
        let mut shared = Vec::new();
        let mut out = Vec::with_capacity(columns.len());
        for &a in columns {
            let act = &self.actuators[a];
            let (mut lo, mut hi) = (
                act.limit.and_then(|l| l.lower()),
                act.limit.and_then(|l| l.upper()),
            );
            let mut source = act.limit_source;
            for &(j, arm) in &moves[a] {
                let Some(range) = self.joints[j].effort else {
                    continue;
                };
                let name = &self.joints[j].name;
                let m = match arm {
                    Some(m) if drivers[j] == 1 => m,
                    _ => {
                        if !shared.contains(name) {
                            shared.push(name.clone());
                        }
                        continue;
                    }
                };
                // lower ≤ m u ≤ upper.
                let (a_lo, a_hi) = (range.lower().map(|v| v / m), range.upper().map(|v| v / m));
                let (u_lo, u_hi) = if m > 0.0 { (a_lo, a_hi) } else { (a_hi, a_lo) };
                if let Some(v) = u_lo.filter(|&v| lo.is_none_or(|l| v > l)) {
                    lo = Some(v);
                    source = LimitSource::Actuatorfrcrange;
                }
                if let Some(v) = u_hi.filter(|&v| hi.is_none_or(|h| v < h)) {
                    hi = Some(v);
                    source = LimitSource::Actuatorfrcrange;
                }
                if let (Some(l), Some(h)) = (lo, hi) {
                    if l >= h {
                        return Err(ProblemError::invalid(
                            "torque_limits",
                            format!(
                                "actuator ranges that leave a force: `{}`'s own range and joint `{name}`'s actuatorfrcrange (through its arm {m}) leave none",
                                act.name
                            ),
                            format!("[{l}, {h}]"),
                        ));
                    }
                }
            }
            let limit = match (lo, hi) {
                (None, None) => None,
                (Some(l), Some(h)) => Some(TorqueLimit::from_range(l, h)),
                (l, h) => Some(TorqueLimit::Range(l, h)),
            };
            out.push((
                limit,
                if limit.is_some() {
                    source
                } else {
                    LimitSource::None
                },
            ));
        }
        Ok(ModelLimits {
            limits: out,
            shared,
        })
    }
}

/// A hand-form problem, built.
#[derive(Clone, Debug)]
pub struct HandProblem {
    /// The problem in matrix form, with `joint_names`.
    pub problem: GraspProblem,
    /// How it was built.
    pub report: HandReport,
}

/// Reads and parses a hand's URDF; an unreadable file is an error of `hand.model`.
pub(crate) fn load_robot(path: &Path) -> Result<Robot, ProblemError> {
    Robot::load(path).map_err(model_error)
}

/// A robot file's error as a problem file's: an unreadable file is an error of its
/// field `hand.model`.
pub(crate) fn model_error(e: ProblemError) -> ProblemError {
    match e {
        ProblemError::Io { path, error } => ProblemError::invalid(
            "hand.model",
            "a readable URDF file (a relative path is relative to the problem file)",
            format!("{path}: {error}"),
        ),
        other => other,
    }
}

fn label(i: usize, name: &Option<String>) -> String {
    match name {
        Some(n) => format!("contacts[{i}] ({n})"),
        None => format!("contacts[{i}]"),
    }
}

impl HandFile {
    /// Loads the robot (a relative `hand.model` is taken relative to `base`, the
    /// problem file's folder) and builds the problem.
    pub fn into_problem(self, base: &Path) -> Result<HandProblem, ProblemError> {
        self.build(&load_robot(&self.model_path(base))?)
    }

    /// The robot file: `hand.model`, relative to `base` unless absolute.
    pub fn model_path(&self, base: &Path) -> PathBuf {
        base.join(&self.hand.model)
    }

    /// Builds the problem on an already parsed robot.
    pub fn build(&self, robot: &Robot) -> Result<HandProblem, ProblemError> {
        let mut warnings = robot.warnings.clone();
        contact_count(self.contacts.len())?;
        // Independent coordinates.
        let mut q_ind = vec![0.0; robot.independent.len()];
        let mut given = vec![false; robot.independent.len()];
        for (name, &value) in &self.hand.joint_positions {
            let field = || format!("hand.joint_positions.{name}");
            let Some(j) = robot.joint(name) else {
                return Err(ProblemError::invalid(
                    field(),
                    format!(
                        "a joint of {} ({})",
                        robot.source,
                        nearest(
                            name,
                            robot
                                .independent
                                .iter()
                                .map(|&j| robot.joints[j].name.as_str())
                        )
                    ),
                    "a name the model does not have",
                ));
            };
            let joint = &robot.joints[j];
            if joint.kind == JointKind::Fixed {
                return Err(ProblemError::invalid(
                    field(),
                    "an independent joint (this one is fixed and has no position)",
                    value,
                ));
            }
            if let Some(m) = joint.mimic {
                return Err(ProblemError::invalid(
                    field(),
                    format!(
                        "an independent joint: this one mimics `{}`, so set that joint's position",
                        robot.joints[m.leader].name
                    ),
                    value,
                ));
            }
            let k = robot.coupling[j]
                .expect("a moving joint has a coupling")
                .independent;
            check_position(robot, k, value, field, &mut warnings)?;
            q_ind[k] = value;
            given[k] = true;
        }
        let grasps = self.grasps(robot)?;
        let problem = grasps.pose(&GraspPose {
            joint_positions: &q_ind,
            ..GraspPose::default()
        })?;
        warnings.extend(grasps.warnings.iter().cloned());
        let defaulted_joints = grasps
            .rows
            .iter()
            .filter(|&&k| !given[k])
            .map(|&k| robot.joints[robot.independent[k]].name.clone())
            .collect();
        Ok(HandProblem {
            problem,
            report: HandReport {
                model: self.hand.model.clone(),
                robot: robot.name.clone(),
                defaulted_joints,
                torque_limits: grasps.limits_from,
                unlimited_joints: grasps.unlimited_joints.clone(),
                actuator_limits: grasps.actuator_limits.clone(),
                gravity: grasps.gravity.map(Into::into),
                object_weight: grasps.object_weight(&GraspPose::default()),
                warnings,
            },
        })
    }

    /// What the file fixes for every grasp of this hand on `robot`: the contacts'
    /// links or sites and models, the problem's joints, actuators and limits, and the
    /// options. [`HandGrasps::pose`] then builds the problem of one configuration,
    /// contact placement and object pose (a planner's candidate grasp), without the
    /// file's `joint_positions`.
    pub fn grasps<'r>(&self, robot: &'r Robot) -> Result<HandGrasps<'r>, ProblemError> {
        contact_count(self.contacts.len())?;
        let mut warnings = Vec::new();
        let mut contacts = Vec::with_capacity(self.contacts.len());
        let mut used = vec![false; robot.independent.len()];
        // The links whose frames the contacts need, and the moving joints they pass.
        let mut needed = vec![false; robot.links.len()];
        let mut moving = Vec::new();
        for (i, c) in self.contacts.iter().enumerate() {
            let at = || label(i, &c.name);
            let model = crate::file::ContactSpec {
                model: c.model,
                mu: c.mu,
                mu_torsion: c.mu_torsion,
            }
            .to_model_named(at)?;
            let (link, site) = match (&c.link, &c.site) {
                (Some(name), None) => {
                    let link = robot.link(name).ok_or_else(|| {
                        ProblemError::invalid(
                            format!("{}.link", at()),
                            format!(
                                "a link of {} ({})",
                                robot.source,
                                nearest(name, robot.links.iter().map(String::as_str))
                            ),
                            format!("`{name}`"),
                        )
                    })?;
                    (link, None)
                }
                (None, Some(name)) => {
                    let site = robot
                        .sites
                        .iter()
                        .position(|s| &s.name == name)
                        .ok_or_else(|| {
                            ProblemError::invalid(
                                format!("{}.site", at()),
                                format!(
                                    "a site of {} ({})",
                                    robot.source,
                                    nearest(name, robot.sites.iter().map(|s| s.name.as_str()))
                                ),
                                format!("`{name}`"),
                            )
                        })?;
                    if c.position.is_some() {
                        return Err(ProblemError::invalid(
                            format!("{}.position", at()),
                            "no position with site (the contact point is the site's origin)",
                            "a position",
                        ));
                    }
                    (robot.sites[site].link, Some(site))
                }
                _ => {
                    return Err(ProblemError::invalid(
                        at(),
                        "either link (with position and normal) or site",
                        if c.link.is_some() {
                            "both link and site"
                        } else {
                            "neither link nor site"
                        },
                    ))
                }
            };
            robot.mark_ancestors(link, &mut needed);
            let chain: Vec<usize> = robot
                .chain(link)
                .into_iter()
                .filter(|&j| robot.joints[j].kind != JointKind::Fixed)
                .collect();
            moving.extend(&chain);
            for &j in &chain {
                used[robot.coupling[j].expect("moving").independent] = true;
            }
            contacts.push(Placing {
                label: at(),
                model,
                link,
                site,
                chain,
            });
        }
        // Actuator moment arms on the independent joints (τ_ind = Pᵀ τ_full). An arm
        // whose terms cancel to within their rounding is 0: an actuator on a tendon
        // that an equality holds at fixed length, say, moves no independent joint
        // (the coupling's multiplier is the ratio of the tendon's coefficients). A
        // spatial tendon's arms depend on the configuration: here, the joints it can
        // move (each pose computes the values).
        let arms: Vec<Vec<(usize, f64)>> = robot
            .actuators
            .iter()
            .map(|a| {
                let moment = match &a.drive {
                    Drive::Fixed(moment) => moment,
                    Drive::Tendon { tendon, .. } => {
                        let mut v: Vec<(usize, f64)> = robot
                            .tendon_joints(*tendon)
                            .into_iter()
                            .map(|j| (robot.coupling[j].expect("moving").independent, 1.0))
                            .collect();
                        v.sort_unstable_by_key(|e| e.0);
                        v.dedup_by_key(|e| e.0);
                        return v;
                    }
                };
                // (independent joint, arm, Σ|terms|, terms)
                let mut v: Vec<(usize, f64, f64, usize)> = Vec::new();
                for &(j, m) in moment {
                    let cp = robot.coupling[j].expect("actuators drive moving joints");
                    let term = cp.multiplier * m;
                    match v.iter_mut().find(|e| e.0 == cp.independent) {
                        Some(e) => {
                            e.1 += term;
                            e.2 += term.abs();
                            e.3 += 1;
                        }
                        None => v.push((cp.independent, term, term.abs(), 1)),
                    }
                }
                v.into_iter()
                    .filter(|&(_, arm, size, terms)| {
                        arm.abs() > 2.0 * terms as f64 * f64::EPSILON * size
                    })
                    .map(|(k, arm, ..)| (k, arm))
                    .collect()
            })
            .collect();
        // An actuator that drives a contact's joint also loads its other joints, which
        // must then be balanced too: they join the problem (with zero Jᵀ rows).
        let mut driving = vec![false; arms.len()];
        loop {
            let mut grew = false;
            for (a, arm) in arms.iter().enumerate() {
                if !driving[a] && arm.iter().any(|&(k, _)| used[k]) {
                    driving[a] = true;
                    for &(k, _) in arm {
                        grew |= !used[k];
                        used[k] = true;
                    }
                }
            }
            if !grew {
                break;
            }
        }
        let rows: Vec<usize> = (0..robot.independent.len()).filter(|&k| used[k]).collect();
        if rows.is_empty() {
            return Err(ProblemError::invalid(
                "contacts",
                "at least one contact on a link that a moving joint moves",
                "contacts only on links fixed to the root",
            ));
        }
        if rows.len() > MAX_JOINTS {
            return Err(ProblemError::invalid(
                "contacts",
                format!("contacts moved by at most {MAX_JOINTS} independent joints in all"),
                format!("{} joints", rows.len()),
            ));
        }
        let mut row_of = vec![usize::MAX; robot.independent.len()];
        for (r, &k) in rows.iter().enumerate() {
            row_of[k] = r;
        }
        let wrench = match (&self.wrench, &self.object) {
            (Some(w), _) => crate::file::wrench6(w)?,
            (None, Some(_)) => [0.0; 6],
            (None, None) => {
                return Err(ProblemError::invalid(
                    "wrench",
                    "[Fx, Fy, Fz, Mx, My, Mz] in the object frame (or `object` with the mass, and hand.gravity, to carry its weight)",
                    "missing",
                ))
            }
        };
        let models = contacts.iter().map(|c| c.model).collect();
        let mut p = GraspProblem::new(
            Matrix::zeros(6, 0),
            Matrix::zeros(rows.len(), 0),
            wrench,
            models,
        );
        let name_of = |k: usize| robot.joints[robot.independent[k]].name.clone();
        p.joint_names = rows.iter().map(|&k| name_of(k)).collect();

        let columns: Vec<usize> = (0..arms.len()).filter(|&a| driving[a]).collect();
        if !robot.actuators.is_empty() {
            if columns.is_empty() {
                return Err(ProblemError::invalid(
                    "contacts",
                    format!(
                        "contacts on links that an actuator of {} moves",
                        robot.source
                    ),
                    "no actuator drives a joint that moves a contact",
                ));
            }
            if columns.len() > rows.len() {
                let names: Vec<&str> = columns
                    .iter()
                    .map(|&a| robot.actuators[a].name.as_str())
                    .collect();
                return Err(ProblemError::invalid(
                    "hand.model",
                    format!(
                        "at most as many actuators as joints on the contacts' chains ({})",
                        rows.len()
                    ),
                    format!("{} actuators: {}", columns.len(), names.join(", ")),
                ));
            }
            p.transmission = Some(grasp_core::problem::Transmission {
                matrix: Matrix::from_fn(rows.len(), columns.len(), |r, c| {
                    arms[columns[c]]
                        .iter()
                        .find(|&&(k, _)| k == rows[r])
                        .map_or(0.0, |&(_, m)| m)
                }),
                actuator_names: columns
                    .iter()
                    .map(|&a| robot.actuators[a].name.clone())
                    .collect(),
            });
        }
        let mut unlimited_joints = Vec::new();
        let ModelLimits {
            limits: limits_of,
            shared,
        } = robot.actuator_limits(&columns)?;
        let (torque_limits, limits_from) = match &self.torque_limits {
            None | Some(serde_json::Value::Null) => (None, "none"),
            Some(serde_json::Value::String(s)) if s == "model" && !columns.is_empty() => {
                let limits: Vec<Option<TorqueLimit>> = limits_of.iter().map(|l| l.0).collect();
                for (&a, l) in columns.iter().zip(&limits_of) {
                    if l.0.is_none() {
                        unlimited_joints.push(robot.actuators[a].name.clone());
                    }
                }
                if !shared.is_empty() {
                    warnings.push(format!(
                        "torque_limits \"model\": the actuatorfrcrange of {} is not applied: it bounds the sum of several actuators' forces, or a spatial tendon's, not one actuator's",
                        shared.join(", ")
                    ));
                }
                if !unlimited_joints.is_empty() {
                    warnings.push(format!(
                        "torque_limits \"model\": no forcerange, no ctrlrange of a force actuator and no actuatorfrcrange of a joint it alone drives, for {}; unlimited",
                        unlimited_joints.join(", ")
                    ));
                }
                (Some(limits), "model")
            }
            Some(serde_json::Value::String(s)) if s == "model" => {
                let limits: Vec<Option<TorqueLimit>> = rows
                    .iter()
                    .map(|&k| robot.joints[robot.independent[k]].effort)
                    .collect();
                for (r, l) in limits.iter().enumerate() {
                    if l.is_none() {
                        unlimited_joints.push(p.joint_names[r].clone());
                    }
                }
                if !unlimited_joints.is_empty() {
                    warnings.push(format!(
                        "torque_limits \"model\": no positive <limit effort> (URDF) or actuatorfrcrange (MJCF) for {}; unlimited",
                        unlimited_joints.join(", ")
                    ));
                }
                (Some(limits), "model")
            }
            Some(v @ serde_json::Value::Array(_)) => {
                let limits: Vec<Option<TorqueLimit>> =
                    serde_json::from_value(v.clone()).map_err(|_| {
                        ProblemError::invalid(
                            "torque_limits",
                            "\"model\", or a list with one limit per joint: a number t > 0 (|τ| ≤ t), [lower, upper] (either null) or null",
                            v,
                        )
                    })?;
                (Some(limits), "file")
            }
            Some(other) => {
                return Err(ProblemError::invalid(
                    "torque_limits",
                    "\"model\" (each joint's <limit effort>), or a list with one number > 0 or null per joint",
                    other,
                ))
            }
        };
        Options {
            linearization: self.linearization,
            torque_weights: self.torque_weights.clone(),
            torque_limits,
            min_normal_force: self.min_normal_force.clone(),
            initial_torque: self.initial_torque.clone(),
            internal_forces: self.internal_forces,
        }
        .apply(&mut p)?;
        let actuator_limits = columns
            .iter()
            .zip(limits_of)
            .map(|(&a, (limit, source))| ActuatorLimit {
                actuator: robot.actuators[a].name.clone(),
                limit,
                source,
            })
            .collect();
        moving.sort_unstable();
        moving.dedup();
        // Spatial tendons: their columns of T, and the links their paths pass.
        let mut tendon_columns = Vec::new();
        for (c, &a) in columns.iter().enumerate() {
            if let Drive::Tendon { tendon, gear } = robot.actuators[a].drive {
                tendon_columns.push((c, tendon, gear));
                for branch in robot.tendons[tendon].branches(robot) {
                    for link in branch {
                        robot.mark_ancestors(link, &mut needed);
                    }
                }
            }
        }
        // The links spatial springs pass, posed for their lengths.
        for sp in &robot.springs {
            if let crate::tendon::SpringOn::Spatial(tendon) = sp.on {
                for branch in robot.tendons[tendon].branches(robot) {
                    for link in branch {
                        robot.mark_ancestors(link, &mut needed);
                    }
                }
            }
        }
        let gravity = self.hand.gravity(robot)?;
        let object = self
            .object
            .map(|o| held_object(o, gravity.is_some()))
            .transpose()?;
        // The links a problem's joint carries are posed for their weight; the others
        // load only joints outside the problem.
        let mut weighed = needed.clone();
        for l in 0..robot.links.len() {
            let loads = robot
                .chain(l)
                .iter()
                .any(|&j| robot.coupling[j].is_some_and(|c| row_of[c.independent] != usize::MAX));
            if loads {
                robot.mark_ancestors(l, &mut weighed);
            }
        }
        let mut grasps = HandGrasps {
            gravity,
            object,
            weighed,
            robot,
            contacts,
            needed,
            moving,
            positions: self.contacts.iter().map(|c| c.position).collect(),
            normals: self.contacts.iter().map(|c| c.normal).collect(),
            frames: self.contacts.iter().map(|c| c.frame).collect(),
            object_pose: self.object_pose.unwrap_or_default(),
            rows,
            row_of,
            template: p,
            limits_from,
            unlimited_joints,
            actuator_limits,
            warnings,
            tendon_columns,
        };
        // The template's spatial tendon arms: at every joint's 0 (every pose computes
        // its own; where 0 puts a side site inside its geom, the columns stay 0).
        if !grasps.tendon_columns.is_empty() {
            let frames = robot.pose_of(&vec![0.0; robot.independent.len()], &grasps.needed);
            let mut template = grasps.template.clone();
            if grasps.tendon_arms(&frames, &mut template).is_err() {
                for &(c, ..) in &grasps.tendon_columns {
                    let t = template.transmission.as_mut().expect("actuated");
                    for r in 0..t.matrix.nrows() {
                        t.matrix[(r, c)] = 0.0;
                    }
                }
            }
            grasps.template = template;
        }
        Ok(grasps)
    }
}

/// `object`, checked: a mass in the input domain, a finite centre, and a gravity to
/// weigh it.
fn held_object(o: HeldObject, weighed: bool) -> Result<HeldObject, ProblemError> {
    if !(o.mass >= 0.0 && in_domain(o.mass)) {
        return Err(ProblemError::invalid(
            "object.mass",
            format!("a mass from 0 to {MAX_MAGNITUDE:e} (0, or not subnormal)"),
            o.mass,
        ));
    }
    check_vec(|| "object.center_of_mass".into(), o.center_of_mass, false)?;
    if !weighed {
        return Err(ProblemError::invalid(
            "object.mass",
            "a gravity to weigh the object: hand.gravity, [gx, gy, gz] in the root frame or \"model\" (an MJCF file's); or no object, and its weight in `wrench`",
            o.mass,
        ));
    }
    Ok(o)
}

/// A link whose weight gravity needs but the file does not give.
fn unknown_mass(why: &str) -> ProblemError {
    ProblemError::invalid(
        "hand.gravity",
        "a hand whose moving links' masses are known (or no gravity)",
        why,
    )
}

impl HandSpec {
    /// `gravity` as a vector in the root frame, checked.
    fn gravity(&self, robot: &Robot) -> Result<Option<Vector3>, ProblemError> {
        let expected = "\"model\" (the MJCF file's <option gravity>) or [gx, gy, gz] in the root frame, finite, of magnitude at most 1e12";
        let g = match &self.gravity {
            None | Some(serde_json::Value::Null) => return Ok(None),
            Some(serde_json::Value::String(s)) if s == "model" => robot.gravity.ok_or_else(|| {
                ProblemError::invalid(
                    "hand.gravity",
                    "[gx, gy, gz] in the root frame: this file fixes no gravity on the hand (a URDF has none, and a floating MJCF hand's orientation in the world is not fixed)",
                    "\"model\"",
                )
            })?,
            Some(v) => {
                let g: [f64; 3] = serde_json::from_value(v.clone())
                    .map_err(|_| ProblemError::invalid("hand.gravity", expected, v))?;
                if let Some(x) = g.iter().find(|x| !x.is_finite() || x.abs() > MAX_MAGNITUDE) {
                    return Err(ProblemError::invalid("hand.gravity", expected, x));
                }
                Vector3::from(g)
            }
        };
        // Every moving link's mass must be known: checked once, not per pose.
        robot
            .gravity_torques(&robot.pose(&vec![0.0; robot.independent.len()]), &g)
            .map_err(|why| unknown_mass(&why))?;
        Ok(Some(g))
    }
}

/// A configuration that puts a side site inside its geom, as an error of the joint
/// positions.
fn inside_wrap(w: &crate::tendon::InsideWrap) -> ProblemError {
    ProblemError::invalid(
        "joint_positions",
        format!(
            "a configuration where the side site of geom `{}` is outside it (tendon `{}`: a string inside its wrapping geom is not modelled)",
            w.geom, w.tendon
        ),
        "the side site inside the geom",
    )
}

/// Checks one independent joint's position `value` (index `k` of
/// [`Robot::independent`]); a position outside the joint's limits is a warning.
fn check_position(
    robot: &Robot,
    k: usize,
    value: f64,
    field: impl Fn() -> String,
    warnings: &mut Vec<String>,
) -> Result<(), ProblemError> {
    if !value.is_finite() || value.abs() > MAX_MAGNITUDE {
        return Err(ProblemError::invalid(
            field(),
            format!("a finite position of magnitude at most {MAX_MAGNITUDE:e}"),
            value,
        ));
    }
    let joint = &robot.joints[robot.independent[k]];
    let (lo, hi) = (joint.lower, joint.upper);
    if lo.is_some_and(|l| value < l) || hi.is_some_and(|h| value > h) {
        warnings.push(format!(
            "{} = {value} is outside the joint's limits [{}, {}] (radians or metres)",
            field(),
            lo.map_or("-inf".into(), |l| l.to_string()),
            hi.map_or("inf".into(), |h| h.to_string())
        ));
    }
    Ok(())
}

/// A contact as the file fixes it for every grasp.
#[derive(Clone, Debug)]
struct Placing {
    /// `contacts[i]` or `contacts[i] (name)`, for messages.
    label: String,
    model: ContactModel,
    /// The link it is on (a site's link for a site).
    link: usize,
    site: Option<usize>,
    /// The moving joints from the root to `link`.
    chain: Vec<usize>,
}

/// One grasp of a hand: what [`HandGrasps::pose`] takes in place of the file's
/// `joint_positions`, contact points and normals, and object pose. `None` (or an empty
/// slice of joint positions) keeps what the file gives.
#[derive(Clone, Copy, Debug, Default)]
pub struct GraspPose<'a> {
    /// Every independent joint's position, in [`Robot::independent`] order (radians or
    /// metres); empty: all at 0.
    pub joint_positions: &'a [f64],
    /// Per contact, its point in its `frame`; `None` per contact (or for all): the
    /// file's.
    pub positions: Option<&'a [Option<[f64; 3]>]>,
    /// Per contact, its unit normal in its `frame`; `None`: the file's (a site's z axis
    /// when the file has none).
    pub normals: Option<&'a [Option<[f64; 3]>]>,
    /// The object frame in the root link's frame; `None`: the file's.
    pub object_pose: Option<ObjectPose>,
    /// The acceleration of gravity in the root frame for this grasp (a planner's hand
    /// turned another way); `None`: the file's `hand.gravity`.
    pub gravity: Option<[f64; 3]>,
}

/// The grasps of one hand file's contacts on a robot, ready to pose: what a planner
/// that tries many configurations and contact points of one hand calls
/// ([`HandFile::grasps`]). Every posed problem has the same joints (the independent
/// joints the contacts' links and the actuators bring in), columns and options.
#[derive(Clone, Debug)]
pub struct HandGrasps<'r> {
    robot: &'r Robot,
    contacts: Vec<Placing>,
    /// The contacts' links and their ancestors: the frames a pose computes.
    needed: Vec<bool>,
    /// The moving joints on the contacts' chains.
    moving: Vec<usize>,
    positions: Vec<Option<[f64; 3]>>,
    normals: Vec<Option<[f64; 3]>>,
    frames: Vec<ContactFrame>,
    object_pose: ObjectPose,
    /// The problem's joints, as indices of [`Robot::independent`].
    rows: Vec<usize>,
    /// Per independent joint, its row in the problem (`usize::MAX` if none).
    row_of: Vec<usize>,
    /// The problem without G and Jᵀ: models, joint names, transmission, options.
    template: GraspProblem,
    limits_from: &'static str,
    unlimited_joints: Vec<String>,
    actuator_limits: Vec<ActuatorLimit>,
    /// What the limits' source left unlimited.
    warnings: Vec<String>,
    /// The columns of T that spatial tendons give: (column, tendon, gear).
    tendon_columns: Vec<(usize, usize, f64)>,
    /// Gravity on the fingers, in the root frame.
    gravity: Option<Vector3>,
    /// `needed` and the links the problem's joints carry: what a pose with gravity
    /// places.
    weighed: Vec<bool>,
    /// The held object, weighed by each pose's gravity (checked: there is one).
    object: Option<HeldObject>,
}

impl HandGrasps<'_> {
    /// Writes the spatial tendons' columns of `problem`'s T at `frames`: each gear
    /// times the tendon's moment arms, reduced to the independent joints (`Pᵀ`).
    fn tendon_arms(&self, frames: &Pose, problem: &mut GraspProblem) -> Result<(), ProblemError> {
        let Some(t) = problem.transmission.as_mut() else {
            return Ok(());
        };
        for &(c, tendon, gear) in &self.tendon_columns {
            let (_, arms) = self
                .robot
                .tendon_moments(tendon, frames)
                .map_err(|w| inside_wrap(&w))?;
            for r in 0..t.matrix.nrows() {
                t.matrix[(r, c)] = 0.0;
            }
            for (j, m) in arms {
                let cp = self.robot.coupling[j].expect("moving");
                t.matrix[(self.row_of[cp.independent], c)] += cp.multiplier * gear * m;
            }
        }
        Ok(())
    }

    /// The springs' and gravity's torques on the problem's joints at `q_ind` (`None`
    /// without either), reduced to the independent joints (`Pᵀ`) as Jᵀ is.
    fn passive_torque(
        &self,
        q_ind: &[f64],
        frames: &Pose,
        gravity: Option<Vector3>,
    ) -> Result<Option<Vec<f64>>, ProblemError> {
        if self.robot.springs.is_empty() && gravity.is_none() {
            return Ok(None);
        }
        let full = self.robot.full_positions(q_ind);
        let mut torques = self
            .robot
            .passive_torques(&full, frames)
            .map_err(|w| inside_wrap(&w))?;
        if let Some(g) = &gravity {
            let weight = self
                .robot
                .gravity_torques(frames, g)
                .map_err(|why| unknown_mass(&why))?;
            torques.iter_mut().zip(weight).for_each(|(t, w)| *t += w);
        }
        let mut out = vec![0.0; self.rows.len()];
        for (j, tj) in torques.into_iter().enumerate() {
            if let Some(cp) = self.robot.coupling[j] {
                if let Some(o) = out.get_mut(self.row_of[cp.independent]) {
                    *o += cp.multiplier * tj;
                }
            }
        }
        // The model's numbers (masses, stiffnesses) may be in range while their
        // torques are not: named here rather than as the derived `passive_torque`.
        for (r, v) in out.iter_mut().enumerate() {
            *v = flush_subnormal(*v);
            if !v.is_finite() || v.abs() > MAX_MAGNITUDE {
                let (field, what) = match gravity {
                    Some(_) => ("hand.gravity", "springs' and links' weight"),
                    None => ("hand.model", "springs'"),
                };
                return Err(ProblemError::invalid(
                    field,
                    format!(
                        "a model whose {what} torques are at most {MAX_MAGNITUDE:e} in magnitude"
                    ),
                    format!(
                        "{v:e} on joint `{}`",
                        self.template.joint_names.get(r).map_or("?", String::as_str)
                    ),
                ));
            }
        }
        Ok(Some(out))
    }

    /// The problem without its G and Jᵀ (zero columns): its joints, actuators,
    /// contact models and options, the same for every pose.
    pub fn template(&self) -> &GraspProblem {
        &self.template
    }

    /// The template, for options that every pose shares (a linearisation, weights);
    /// its G and Jᵀ are replaced by each pose's, and a pose whose problem no longer
    /// fits its contacts fails validation.
    pub fn template_mut(&mut self) -> &mut GraspProblem {
        &mut self.template
    }

    /// The robot.
    pub fn robot(&self) -> &Robot {
        self.robot
    }

    /// What the held object's weight asks of the contacts in the grasp `pose` (its
    /// gravity and object pose, else the file's), in the object frame: `None` without
    /// `object`. [`HandGrasps::pose`] adds it to the wrench; a batch whose wrenches are
    /// given per grasp adds it to each. The pose's numbers are those `pose` checks.
    pub fn object_weight(&self, pose: &GraspPose<'_>) -> Option<[f64; 6]> {
        let object = self.object.as_ref()?;
        let gravity = pose.gravity.map(Vector3::from).or(self.gravity)?;
        let [w, x, y, z] = pose.object_pose.unwrap_or(self.object_pose).quaternion;
        let rotation = UnitQuaternion::new_normalize(w, x, y, z);
        Some(object.weight_wrench(&gravity, &rotation))
    }

    /// Whether each pose has its own transmission: spatial tendons' moment arms
    /// depend on the configuration (joint and fixed-tendon actuators' do not).
    pub fn transmission_varies(&self) -> bool {
        !self.tendon_columns.is_empty()
    }

    /// Builds the problem of one grasp. Its joint positions are checked (finite, of
    /// magnitude at most `MAX_MAGNITUDE`; a position outside the joint's limits is not
    /// an error), its points and normals as the file's.
    pub fn pose(&self, pose: &GraspPose<'_>) -> Result<GraspProblem, ProblemError> {
        let robot = self.robot;
        let nq = robot.independent.len();
        let zeros;
        let q_ind = if pose.joint_positions.is_empty() {
            zeros = vec![0.0; nq];
            &zeros[..]
        } else {
            pose.joint_positions
        };
        if q_ind.len() != nq {
            return Err(ProblemError::invalid(
                "joint_positions",
                format!(
                    "{nq} positions, one per independent joint of {}",
                    robot.source
                ),
                format!("{} positions", q_ind.len()),
            ));
        }
        let mut ignored = Vec::new();
        for (k, &v) in q_ind.iter().enumerate() {
            let field = || {
                format!(
                    "joint_positions[{k}] ({})",
                    robot.joints[robot.independent[k]].name
                )
            };
            check_position(robot, k, v, field, &mut ignored)?;
        }
        let n = self.contacts.len();
        for (field, given) in [("positions", pose.positions), ("normals", pose.normals)] {
            if let Some(g) = given.filter(|g| g.len() != n) {
                return Err(ProblemError::invalid(
                    field,
                    format!("{n} entries, one per contact"),
                    format!("{} entries", g.len()),
                ));
            }
        }
        let object_pose = pose.object_pose.unwrap_or(self.object_pose);
        check_vec(
            || "object_pose.position".into(),
            object_pose.position,
            false,
        )?;
        let [w, x, y, z] = object_pose.quaternion;
        let qn = (w * w + x * x + y * y + z * z).sqrt();
        if !qn.is_finite() || (qn - 1.0).abs() > UNIT_TOLERANCE {
            return Err(ProblemError::invalid(
                "object_pose.quaternion",
                format!("a unit quaternion [w, x, y, z] (length 1 ± {UNIT_TOLERANCE:e})"),
                format!("{:?} (length {qn})", object_pose.quaternion),
            ));
        }
        let object = Isometry3::from_parts(
            Vector3::from(object_pose.position),
            UnitQuaternion::new_normalize(w, x, y, z),
        );
        let to_object = object.inverse();
        let gravity = match pose.gravity {
            Some(g) => {
                if let Some(x) = g.iter().find(|x| !x.is_finite() || x.abs() > MAX_MAGNITUDE) {
                    return Err(ProblemError::invalid(
                        "gravity",
                        "[gx, gy, gz] in the root frame, finite, of magnitude at most 1e12",
                        x,
                    ));
                }
                Some(Vector3::from(g))
            }
            None => self.gravity,
        };
        let frames = robot.pose_of(
            q_ind,
            if gravity.is_some() {
                &self.weighed
            } else {
                &self.needed
            },
        );

        // Contacts in the object frame.
        let mut placed = Vec::with_capacity(n);
        for (i, c) in self.contacts.iter().enumerate() {
            let at = || c.label.clone();
            let position = pose.positions.and_then(|p| p[i]).or(self.positions[i]);
            let normal = pose.normals.and_then(|p| p[i]).or(self.normals[i]);
            if let Some(n) = normal {
                check_vec(|| format!("{}.normal", at()), n, true)?;
            }
            let to = to_object * frames.links[c.link];
            let (p, n) = match c.site {
                None => {
                    let position = position.ok_or_else(|| {
                        ProblemError::invalid(
                            format!("{}.position", at()),
                            "the contact point [x, y, z] (required with link)",
                            "missing",
                        )
                    })?;
                    check_vec(|| format!("{}.position", at()), position, false)?;
                    let normal = normal.ok_or_else(|| {
                        ProblemError::invalid(
                            format!("{}.normal", at()),
                            "the unit normal [x, y, z] (required with link)",
                            "missing",
                        )
                    })?;
                    match self.frames[i] {
                        ContactFrame::Object => (Vector3::from(position), Vector3::from(normal)),
                        ContactFrame::Link => (
                            to.transform_point(&Vector3::from(position)),
                            to.rotation * Vector3::from(normal),
                        ),
                    }
                }
                Some(s) => {
                    if position.is_some() {
                        return Err(ProblemError::invalid(
                            format!("{}.position", at()),
                            "no position with site (the contact point is the site's origin)",
                            "a position",
                        ));
                    }
                    let frame = to * robot.sites[s].frame;
                    let n = match (normal, self.frames[i]) {
                        (None, _) => frame.rotation * Vector3::z(),
                        (Some(n), ContactFrame::Object) => Vector3::from(n),
                        (Some(n), ContactFrame::Link) => to.rotation * Vector3::from(n),
                    };
                    (frame.translation, n)
                }
            };
            if p.to_array().iter().any(|v| v.abs() > MAX_MAGNITUDE) {
                return Err(ProblemError::invalid(
                    format!("{}.position", at()),
                    format!("a point within {MAX_MAGNITUDE:e} of the object origin"),
                    format!("{:?} in the object frame", p.to_array()),
                ));
            }
            // The frame convention normalises n exactly, as the geometry form does.
            placed.push((p, n.normalize()));
        }
        // The chains' joint axes and origins in the object frame.
        let mut axes = vec![(Vector3::zeros(), Vector3::zeros()); robot.joints.len()];
        for &j in &self.moving {
            let t = to_object * frames.joints[j];
            axes[j] = (t.rotation * robot.joints[j].axis, t.translation);
        }
        let m = self.rows.len();
        let nf = self.contacts.iter().map(|c| c.model.dim()).sum();
        let mut g = Matrix::zeros(6, nf);
        let mut jt = Matrix::zeros(m, nf);
        let mut col = 0;
        for (c, &(p, n)) in self.contacts.iter().zip(&placed) {
            let [t1, t2, n] = contact_frame([n.x, n.y, n.z]);
            let n = Vector3::from(n);
            let dirs: &[Vector3] = match c.model {
                ContactModel::Fpc => &[n],
                _ => &[Vector3::from(t1), Vector3::from(t2), n],
            };
            let mut column = |d: Vector3, torsion: bool| {
                let moment = if torsion { d } else { p.cross(&d) };
                let force = if torsion { Vector3::zeros() } else { d };
                for (r, v) in [force.x, force.y, force.z, moment.x, moment.y, moment.z]
                    .into_iter()
                    .enumerate()
                {
                    g[(r, col)] = flush_subnormal(v);
                }
                for &j in &c.chain {
                    let (a, o) = &axes[j];
                    let entry = match (robot.joints[j].kind.rotates(), torsion) {
                        (true, false) => d.dot(&a.cross(&(p - *o))),
                        (true, true) => d.dot(a),
                        (false, false) => d.dot(a),
                        (false, true) => 0.0,
                    };
                    let cp = robot.coupling[j].expect("moving");
                    jt[(self.row_of[cp.independent], col)] += cp.multiplier * entry;
                }
                col += 1;
            };
            for &d in dirs {
                column(d, false);
            }
            if c.model.dim() == 4 {
                column(n, true);
            }
        }
        for v in jt.as_mut_slice() {
            *v = flush_subnormal(*v);
        }
        let mut problem = self.template.clone();
        if let Some(weight) = self.object_weight(pose) {
            for (i, (w, v)) in problem.wrench.iter_mut().zip(weight).enumerate() {
                *w = flush_subnormal(*w + v);
                if !w.is_finite() || w.abs() > MAX_MAGNITUDE {
                    return Err(ProblemError::invalid(
                        "object.mass",
                        format!("a weight whose wrench, with `wrench`, is at most {MAX_MAGNITUDE:e} in magnitude"),
                        format!("{w:e} in component {i} of the wrench"),
                    ));
                }
            }
        }
        self.tendon_arms(&frames, &mut problem)?;
        problem.passive_torque = self.passive_torque(q_ind, &frames, gravity)?;
        problem.grasp_matrix = g;
        problem.jacobian_transpose = jt;
        problem.validate()?;
        Ok(problem)
    }
}
