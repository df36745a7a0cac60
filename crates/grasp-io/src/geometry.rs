//! Grasps from geometry: contact points and normals, finger joint axes, in the object
//! frame at the current configuration. Builds G and Jᵀ with the convention of
//! `shared/reference/README.md` ("Geometry convention"), written out in
//! `docs/geometry.md`.
//!
//! ```text
//!            n (into the object) = contact z
//!            ^
//!            |   t2 = n × t1
//!            |  /
//!   contact  o ---> t1 = normalize(n × a0),  a0 = e_x, or e_y when |n_x| ≥ 0.9
//!           /
//!   finger joint j: origin o_j, unit axis a_j; joints 0..=link move the contact
//!
//!   G column of direction d:   [d; p × d]           torsion column: [0; n]
//!   Jᵀ entry, revolute joint:  d · (a × (p − o))    torsion: n · a
//!   Jᵀ entry, prismatic joint: d · a                torsion: 0
//! ```

use crate::file::{ModelName, Options};
use grasp_core::by_name::ByName;
use grasp_core::contact::ContactModel;
use grasp_core::error::ProblemError;
use grasp_core::matrix::Matrix;
use grasp_core::problem::{
    contact_count, flush_subnormal, in_domain, GraspProblem, DOMAIN, MAX_JOINTS,
};
use serde::{Deserialize, Serialize};

/// How far from unit length an axis or normal may be.
pub const UNIT_TOLERANCE: f64 = 1e-6;

/// A joint type.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum JointType {
    /// Rotation about `axis` through `origin`.
    #[default]
    Revolute,
    /// Translation along `axis`.
    Prismatic,
}

impl ByName for JointType {
    const VARIANTS: &'static [Self] = &[Self::Revolute, Self::Prismatic];
    const NAMES: &'static [&'static str] = &["revolute", "prismatic"];
}
grasp_core::deserialize_by_name!(JointType);

/// One finger joint, in the object frame at the current configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSpec {
    /// Optional name, used in messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A point on the joint axis.
    pub origin: [f64; 3],
    /// The unit joint axis.
    pub axis: [f64; 3],
    /// `revolute` (default) or `prismatic`.
    #[serde(default, rename = "type")]
    pub kind: JointType,
}

/// One finger: a serial chain of joints, base first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FingerSpec {
    /// Optional name, used in messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The joints, from the palm outwards.
    pub joints: Vec<JointSpec>,
}

/// One contact, in the object frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeometricContact {
    /// Optional name, used in messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Contact point p.
    pub position: [f64; 3],
    /// Unit normal n, pointing into the object.
    pub normal: [f64; 3],
    /// `fpc`, `pcwf`, `sfcl` or `sfce`.
    pub model: ModelName,
    /// Tangential friction coefficient.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu: Option<f64>,
    /// Torsional friction coefficient, a length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu_torsion: Option<f64>,
    /// The finger that touches here; `null` for the palm (no joint moves it).
    #[serde(default)]
    pub finger: Option<usize>,
    /// Index of the finger's joint after which the contact sits: joints `0..=link` move
    /// it. Default: all of the finger's joints.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub link: Option<usize>,
}

/// A problem file in geometry form.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeometryFile {
    /// Free-text name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Free-text description: where the numbers come from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// The contacts; their order is the column order of G.
    pub contacts: Vec<GeometricContact>,
    /// The fingers; joints are numbered finger by finger, base first.
    pub fingers: Vec<FingerSpec>,
    /// `[Fx Fy Fz Mx My Mz]`, about the object frame's origin.
    pub wrench: Vec<f64>,
    /// See the matrix form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linearization: Option<grasp_core::cone::Linearization>,
    /// See the matrix form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_weights: Option<Vec<f64>>,
    /// See the matrix form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_limits: Option<Vec<Option<grasp_core::TorqueLimit>>>,
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

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm3(a: [f64; 3]) -> f64 {
    dot3(a, a).sqrt()
}

/// The contact frame `(t1, t2, n)` of a unit normal.
pub fn contact_frame(n: [f64; 3]) -> [[f64; 3]; 3] {
    let a0 = if n[0].abs() >= 0.9 {
        [0.0, 1.0, 0.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let t = cross(n, a0);
    let l = norm3(t);
    let t1 = [t[0] / l, t[1] / l, t[2] / l];
    [t1, cross(n, t1), n]
}

fn label(kind: &str, i: usize, name: &Option<String>) -> String {
    match name {
        Some(n) => format!("{kind}[{i}] ({n})"),
        None => format!("{kind}[{i}]"),
    }
}

/// Checks a 3-vector (and its length when `unit`); `field` is called only on failure.
pub(crate) fn check_vec(
    field: impl FnOnce() -> String,
    v: [f64; 3],
    unit: bool,
) -> Result<(), ProblemError> {
    if !v.iter().all(|&x| in_domain(x)) {
        return Err(ProblemError::invalid(
            field(),
            format!("three numbers, each {DOMAIN}"),
            format!("{v:?}"),
        ));
    }
    if unit && (norm3(v) - 1.0).abs() > UNIT_TOLERANCE {
        return Err(ProblemError::invalid(
            field(),
            format!("a unit vector (length 1 ± {UNIT_TOLERANCE:e}; normalise it yourself, it is not done silently)"),
            format!("length {}", norm3(v)),
        ));
    }
    Ok(())
}

impl GeometryFile {
    /// Validates the geometry and builds the matrix-form problem.
    pub fn into_problem(self) -> Result<GraspProblem, ProblemError> {
        let joints_of: Vec<usize> = self.fingers.iter().map(|f| f.joints.len()).collect();
        let first_joint: Vec<usize> = joints_of
            .iter()
            .scan(0, |acc, &n| {
                let s = *acc;
                *acc += n;
                Some(s)
            })
            .collect();
        let m: usize = joints_of.iter().sum();
        if m == 0 {
            return Err(ProblemError::invalid(
                "fingers",
                "at least one joint",
                "none",
            ));
        }
        // Sizes first: G and Jᵀ are allocated from them.
        if m > MAX_JOINTS {
            return Err(ProblemError::invalid(
                "fingers",
                format!("at most {MAX_JOINTS} joints in all"),
                format!("{m} joints"),
            ));
        }
        contact_count(self.contacts.len())?;
        for (k, f) in self.fingers.iter().enumerate() {
            for (j, joint) in f.joints.iter().enumerate() {
                let at = format!("{}.joints[{j}]", label("fingers", k, &f.name));
                let at = match &joint.name {
                    Some(n) => format!("{at} ({n})"),
                    None => at,
                };
                check_vec(|| format!("{at}.origin"), joint.origin, false)?;
                check_vec(|| format!("{at}.axis"), joint.axis, true)?;
            }
        }
        let mut models = Vec::with_capacity(self.contacts.len());
        let mut g_cols: Vec<[f64; 6]> = Vec::new();
        let mut jt_cols: Vec<Vec<f64>> = Vec::new();
        for (i, c) in self.contacts.iter().enumerate() {
            let at = label("contacts", i, &c.name);
            check_vec(|| format!("{at}.position"), c.position, false)?;
            check_vec(|| format!("{at}.normal"), c.normal, true)?;
            let spec = crate::file::ContactSpec {
                model: c.model,
                mu: c.mu,
                mu_torsion: c.mu_torsion,
            };
            let model = spec.to_model(&at)?;
            let moving: &[JointSpec] = match c.finger {
                None => {
                    if c.link.is_some() {
                        return Err(ProblemError::invalid(
                            format!("{at}.link"),
                            "no link for a palm contact (finger null)",
                            c.link.unwrap_or_default(),
                        ));
                    }
                    &[]
                }
                Some(k) => {
                    let f = self.fingers.get(k).ok_or_else(|| {
                        ProblemError::invalid(
                            format!("{at}.finger"),
                            format!(
                                "a finger index below {} or null for the palm",
                                self.fingers.len()
                            ),
                            k,
                        )
                    })?;
                    let upto = match c.link {
                        None => f.joints.len(),
                        Some(l) if l < f.joints.len() => l + 1,
                        Some(l) => {
                            return Err(ProblemError::invalid(
                                format!("{at}.link"),
                                format!(
                                    "a joint index of {} below {}",
                                    label("fingers", k, &f.name),
                                    f.joints.len()
                                ),
                                l,
                            ))
                        }
                    };
                    &f.joints[..upto]
                }
            };
            let base = c.finger.map_or(0, |k| first_joint[k]);
            let [t1, t2, n] = contact_frame(c.normal);
            let dirs: &[[f64; 3]] = match model {
                ContactModel::Fpc => &[n],
                _ => &[t1, t2, n],
            };
            let p = c.position;
            for &d in dirs {
                let pd = cross(p, d);
                g_cols.push([d[0], d[1], d[2], pd[0], pd[1], pd[2]]);
                let mut col = vec![0.0; m];
                for (j, joint) in moving.iter().enumerate() {
                    col[base + j] = match joint.kind {
                        JointType::Revolute => dot3(d, cross(joint.axis, sub(p, joint.origin))),
                        JointType::Prismatic => dot3(d, joint.axis),
                    };
                }
                jt_cols.push(col);
            }
            if model.dim() == 4 {
                g_cols.push([0.0, 0.0, 0.0, n[0], n[1], n[2]]);
                let mut col = vec![0.0; m];
                for (j, joint) in moving.iter().enumerate() {
                    col[base + j] = match joint.kind {
                        JointType::Revolute => dot3(n, joint.axis),
                        JointType::Prismatic => 0.0,
                    };
                }
                jt_cols.push(col);
            }
            models.push(model);
        }
        let nf = g_cols.len();
        let g = Matrix::from_fn(6, nf, |r, c| flush_subnormal(g_cols[c][r]));
        let jt = Matrix::from_fn(m, nf, |r, c| flush_subnormal(jt_cols[c][r]));
        let wrench = crate::file::wrench6(&self.wrench)?;
        let mut p = GraspProblem::new(g, jt, wrench, models);
        p.joint_names =
            self.fingers
                .iter()
                .enumerate()
                .flat_map(|(k, f)| {
                    f.joints.iter().enumerate().map(move |(j, joint)| {
                        match (&joint.name, &f.name) {
                            (Some(n), _) => n.clone(),
                            (None, Some(fname)) => format!("{fname}[{j}]"),
                            (None, None) => format!("finger {k} joint {j}"),
                        }
                    })
                })
                .collect();
        Options {
            linearization: self.linearization,
            torque_weights: self.torque_weights,
            torque_limits: self.torque_limits,
            min_normal_force: self.min_normal_force,
            initial_torque: self.initial_torque,
            internal_forces: self.internal_forces,
        }
        .apply(&mut p)?;
        p.validate()?;
        Ok(p)
    }
}
