//! Problem files: JSON, read with serde; unknown fields are rejected.
//!
//! Errors name the field (`contacts[1].mu`) and what was expected, or the JSON line and
//! column when the text is not well-formed.

use crate::urdf::Robot;
use grasp_core::by_name::ByName;
use grasp_core::cone::Linearization;
use grasp_core::contact::ContactModel;
use grasp_core::error::ProblemError;
use grasp_core::matrix::Matrix;
use grasp_core::model::InternalForces;
use grasp_core::problem::{GraspProblem, TorqueLimit};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The contact model names of problem files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ModelName {
    /// Frictionless point contact.
    Fpc,
    /// Point contact with friction.
    Pcwf,
    /// Soft finger, linear coupling.
    Sfcl,
    /// Soft finger, elliptic coupling.
    Sfce,
}

impl ByName for ModelName {
    const VARIANTS: &'static [Self] = &[Self::Fpc, Self::Pcwf, Self::Sfcl, Self::Sfce];
    const NAMES: &'static [&'static str] = &["fpc", "pcwf", "sfcl", "sfce"];
}
grasp_core::deserialize_by_name!(ModelName);

/// One entry of `contacts` in a matrix-form file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// `fpc`, `pcwf`, `sfcl` or `sfce`.
    pub model: ModelName,
    /// Tangential friction coefficient (all but `fpc`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu: Option<f64>,
    /// Torsional friction coefficient, a length (`sfcl`, `sfce`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu_torsion: Option<f64>,
}

impl ContactSpec {
    /// Converts to a model, naming `field` (such as `contacts[2]`) in errors.
    pub fn to_model(&self, field: &str) -> Result<ContactModel, ProblemError> {
        self.to_model_named(|| field.to_string())
    }

    /// [`Self::to_model`] with the field named only on failure (no allocation on the
    /// way to a valid model).
    pub fn to_model_named(&self, field: impl Fn() -> String) -> Result<ContactModel, ProblemError> {
        let name = match self.model {
            ModelName::Fpc => "fpc",
            ModelName::Pcwf => "pcwf",
            ModelName::Sfcl => "sfcl",
            ModelName::Sfce => "sfce",
        };
        let need = |v: Option<f64>, what: &str| {
            v.ok_or_else(|| {
                ProblemError::invalid(
                    format!("{}.{what}", field()),
                    format!("a number > 0 (model {name} needs it)"),
                    "nothing",
                )
            })
        };
        let unused = |v: Option<f64>, what: &str| match v {
            Some(x) => Err(ProblemError::invalid(
                format!("{}.{what}", field()),
                format!("no {what} for model {name}, which does not use it"),
                x,
            )),
            None => Ok(()),
        };
        let model = match self.model {
            ModelName::Fpc => {
                unused(self.mu, "mu")?;
                unused(self.mu_torsion, "mu_torsion")?;
                ContactModel::Fpc
            }
            ModelName::Pcwf => {
                unused(self.mu_torsion, "mu_torsion")?;
                ContactModel::Pcwf {
                    mu: need(self.mu, "mu")?,
                }
            }
            ModelName::Sfcl => ContactModel::SfcLinear {
                mu: need(self.mu, "mu")?,
                mu_torsion: need(self.mu_torsion, "mu_torsion")?,
            },
            ModelName::Sfce => ContactModel::SfcElliptic {
                mu: need(self.mu, "mu")?,
                mu_torsion: need(self.mu_torsion, "mu_torsion")?,
            },
        };
        model.validate().map_err(|e| {
            ProblemError::invalid(
                format!("{}.{}", field(), e.field),
                format!("a number from {:e} to {:e}", e.range.0, e.range.1),
                e.value,
            )
        })?;
        Ok(model)
    }
}

impl From<&ContactModel> for ContactSpec {
    fn from(m: &ContactModel) -> Self {
        match *m {
            ContactModel::Fpc => Self {
                model: ModelName::Fpc,
                mu: None,
                mu_torsion: None,
            },
            ContactModel::Pcwf { mu } => Self {
                model: ModelName::Pcwf,
                mu: Some(mu),
                mu_torsion: None,
            },
            ContactModel::SfcLinear { mu, mu_torsion } => Self {
                model: ModelName::Sfcl,
                mu: Some(mu),
                mu_torsion: Some(mu_torsion),
            },
            ContactModel::SfcElliptic { mu, mu_torsion } => Self {
                model: ModelName::Sfce,
                mu: Some(mu),
                mu_torsion: Some(mu_torsion),
            },
        }
    }
}

/// Optional fields shared by both file forms (listed inline in each form's struct,
/// because serde cannot reject unknown fields through `flatten`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Options {
    /// N (`sides`, default 8), K (`latitudes`, default 2) and `sfce_spacing`.
    pub linearization: Option<Linearization>,
    /// Objective weights, one per joint (> 0).
    pub torque_weights: Option<Vec<f64>>,
    /// One per joint: `t` for `|τ_j| ≤ t`, `[lower, upper]` (either `null`), or `null`
    /// for no limit.
    pub torque_limits: Option<Vec<Option<TorqueLimit>>>,
    /// `fz ≥ value`: one number for every contact, or a list with one per contact.
    pub min_normal_force: Option<serde_json::Value>,
    /// A starting torque, one per joint.
    pub initial_torque: Option<Vec<f64>>,
    /// How the passive internal forces are fixed: `compliance` (default),
    /// `euclidean` (the paper's `A⁺`) or `free`.
    pub internal_forces: Option<InternalForces>,
}

/// A problem file in matrix form.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MatrixFile {
    /// Free-text name, for reports.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Free-text description: where the numbers come from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// G, 6 rows × n.
    pub grasp_matrix: Vec<Vec<f64>>,
    /// Jᵀ, m rows × n.
    pub jacobian_transpose: Vec<Vec<f64>>,
    /// `[Fx Fy Fz Mx My Mz]`.
    pub wrench: Vec<f64>,
    /// One entry per contact, in column order.
    pub contacts: Vec<ContactSpec>,
    /// N (`sides`, default 8), K (`latitudes`, default 2) and `sfce_spacing`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linearization: Option<Linearization>,
    /// Objective weights, one per joint (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_weights: Option<Vec<f64>>,
    /// One per joint: `t` for `|τ_j| ≤ t`, `[lower, upper]` (either `null`), or `null`
    /// for no limit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_limits: Option<Vec<Option<TorqueLimit>>>,
    /// `fz ≥ value`: one number for every contact, or a list with one per contact.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_normal_force: Option<serde_json::Value>,
    /// A starting torque, one per joint.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_torque: Option<Vec<f64>>,
    /// `compliance` (default), `euclidean` or `free`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub internal_forces: Option<InternalForces>,
    /// One name per row of `jacobian_transpose`, echoed in reports.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_names: Option<Vec<String>>,
    /// T, joints × actuators: `τ = T u`. With it the solver chooses the actuator
    /// forces u, and the weights, limits and initial torque are per actuator.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transmission: Option<Vec<Vec<f64>>>,
    /// One name per column of `transmission`, echoed in reports.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub actuator_names: Option<Vec<String>>,
    /// Joint torques no actuator controls (springs, gravity on the fingers), one per
    /// row of `jacobian_transpose`: `Jᵀ f = T u + passive_torque`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub passive_torque: Option<Vec<f64>>,
}

impl MatrixFile {
    /// The matrix-form file of a problem (what `grasp-torque build` prints).
    pub fn from_problem(p: &GraspProblem, name: Option<String>) -> Self {
        Self {
            name,
            description: None,
            grasp_matrix: p.grasp_matrix.to_rows(),
            jacobian_transpose: p.jacobian_transpose.to_rows(),
            wrench: p.wrench.to_vec(),
            contacts: p.contacts.iter().map(ContactSpec::from).collect(),
            linearization: Some(p.linearization),
            torque_weights: p.torque_weights.clone(),
            torque_limits: p.torque_limits.clone(),
            min_normal_force: p.min_normal_force.as_ref().map(|v| serde_json::json!(v)),
            initial_torque: p.initial_torque.clone(),
            internal_forces: Some(p.internal_forces),
            joint_names: (!p.joint_names.is_empty()).then(|| p.joint_names.clone()),
            transmission: p.transmission.as_ref().map(|t| t.matrix.to_rows()),
            actuator_names: p
                .transmission
                .as_ref()
                .filter(|t| !t.actuator_names.is_empty())
                .map(|t| t.actuator_names.clone()),
            passive_torque: p.passive_torque.clone(),
        }
    }

    /// Converts to a validated problem.
    pub fn into_problem(self) -> Result<GraspProblem, ProblemError> {
        let g = rectangular("grasp_matrix", &self.grasp_matrix)?;
        let jt = rectangular("jacobian_transpose", &self.jacobian_transpose)?;
        let wrench = wrench6(&self.wrench)?;
        let contacts = self
            .contacts
            .iter()
            .enumerate()
            .map(|(i, c)| c.to_model(&format!("contacts[{i}]")))
            .collect::<Result<Vec<_>, _>>()?;
        let mut p = GraspProblem::new(g, jt, wrench, contacts);
        p.joint_names = self.joint_names.unwrap_or_default();
        p.transmission = match (self.transmission, self.actuator_names) {
            (Some(t), names) => Some(grasp_core::problem::Transmission {
                matrix: rectangular("transmission", &t)?,
                actuator_names: names.unwrap_or_default(),
            }),
            (None, Some(_)) => {
                return Err(ProblemError::invalid(
                    "actuator_names",
                    "a transmission to name the columns of",
                    "actuator_names without transmission",
                ))
            }
            (None, None) => None,
        };
        p.passive_torque = self.passive_torque;
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

impl Options {
    /// Copies the options into `p`, expanding a scalar `min_normal_force`.
    pub fn apply(self, p: &mut GraspProblem) -> Result<(), ProblemError> {
        if let Some(l) = self.linearization {
            p.linearization = l;
        }
        p.torque_weights = self.torque_weights;
        p.torque_limits = self.torque_limits;
        p.initial_torque = self.initial_torque;
        if let Some(i) = self.internal_forces {
            p.internal_forces = i;
        }
        p.min_normal_force = match self.min_normal_force {
            None | Some(serde_json::Value::Null) => None,
            Some(serde_json::Value::Number(x)) => {
                Some(vec![x.as_f64().unwrap_or(f64::NAN); p.contacts.len()])
            }
            Some(serde_json::Value::Array(a)) => Some(
                a.iter()
                    .enumerate()
                    .map(|(i, v)| {
                        v.as_f64().ok_or_else(|| {
                            ProblemError::invalid(
                                format!("min_normal_force[{i}]"),
                                "a number ≥ 0",
                                v,
                            )
                        })
                    })
                    .collect::<Result<_, _>>()?,
            ),
            Some(other) => {
                return Err(ProblemError::invalid(
                    "min_normal_force",
                    "a number ≥ 0, or a list with one number ≥ 0 per contact",
                    other,
                ))
            }
        };
        Ok(())
    }
}

/// The wrench field as 6 numbers, or an error naming it.
pub fn wrench6(w: &[f64]) -> Result<[f64; 6], ProblemError> {
    w.try_into().map_err(|_| {
        ProblemError::invalid(
            "wrench",
            "6 numbers [Fx, Fy, Fz, Mx, My, Mz]",
            format!("{} numbers", w.len()),
        )
    })
}

fn rectangular(name: &str, rows: &[Vec<f64>]) -> Result<Matrix, ProblemError> {
    let cols = rows.first().map_or(0, Vec::len);
    if let Some((i, r)) = rows.iter().enumerate().find(|(_, r)| r.len() != cols) {
        return Err(ProblemError::invalid(
            format!("{name}[{i}]"),
            format!("{cols} entries, like row 0"),
            format!("{} entries", r.len()),
        ));
    }
    Ok(Matrix::from_rows(rows, cols))
}

/// Deserialises `T` from JSON text, reporting the path of the field at fault. A
/// leading byte order mark (which Windows editors write) is skipped, as editors show
/// the text: line and column count from after it.
pub fn from_json_str<'de, T: Deserialize<'de>>(text: &'de str) -> Result<T, ProblemError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut de = serde_json::Deserializer::from_str(text);
    let value = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let mut path = e.path().to_string();
        let inner = e.into_inner();
        let (line, column) = (inner.line(), inner.column());
        let message = inner.to_string();
        // serde_json appends " at line L column C"; the variant carries them already.
        let mut message = match message.rfind(" at line ") {
            Some(i) => message[..i].to_string(),
            None => message,
        };
        // Past serde_json's nesting limit the path is a hundred-odd segments: its first
        // three say where the nesting starts.
        if message == "recursion limit exceeded" {
            let cut = path
                .char_indices()
                .filter(|&(i, c)| i > 0 && (c == '.' || c == '['))
                .nth(2);
            if let Some((i, _)) = cut {
                path.truncate(i);
                path.push('…');
            }
            message = "expected arrays and objects nested at most 128 deep, got deeper (recursion limit exceeded)".into();
        }
        ProblemError::Parse {
            path,
            message,
            line,
            column,
        }
    })?;
    // Nothing but white space may follow the object.
    de.end().map_err(|e| ProblemError::Parse {
        path: ".".into(),
        message: "unexpected text after the JSON value".into(),
        line: e.line(),
        column: e.column(),
    })?;
    Ok(value)
}

/// A problem as read from a file, with what its form adds to reports.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The validated problem.
    pub problem: GraspProblem,
    /// For the hand form: the robot, the joints that defaulted to 0, the source of the
    /// torque limits and the warnings.
    pub hand: Option<crate::hand::HandReport>,
}

/// Parses a problem file's text, in matrix form (`grasp_matrix`, `jacobian_transpose`)
/// or geometry form (`contacts` with positions, and `fingers`). A hand-form file's
/// relative robot path is taken from the working directory; see [`parse_problem_at`].
pub fn parse_problem(text: &str) -> Result<GraspProblem, ProblemError> {
    parse_problem_at(text, Path::new(".")).map(|l| l.problem)
}

/// Parses a problem file's text in any of the three forms; a hand-form file's relative
/// `hand.model` is taken relative to `base` (the problem file's folder).
pub fn parse_problem_at(text: &str, base: &Path) -> Result<Loaded, ProblemError> {
    parse_with(text, base, &|path| Robot::load(path).map(Arc::new))
}

/// Parses many problems that may share robot files (a batch, a planner's loop): each
/// URDF that a hand-form problem names is read and parsed once, keyed by its path,
/// then shared by every problem that names it. `Sync`: threads may share one parser.
#[derive(Debug, Default)]
pub struct ProblemParser {
    robots: Mutex<HashMap<PathBuf, Arc<Robot>>>,
}

impl ProblemParser {
    /// A parser with no robot read yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// As [`parse_problem_at`], with the robot files cached.
    pub fn parse_at(&self, text: &str, base: &Path) -> Result<Loaded, ProblemError> {
        parse_with(text, base, &|path| self.robot(path))
    }

    /// The robot file at `path` (URDF or MJCF), parsed on first use. An unreadable
    /// file is a [`ProblemError::Io`] naming it.
    pub fn robot(&self, path: &Path) -> Result<Arc<Robot>, ProblemError> {
        // Held while a new robot parses, so that threads asking for it parse it once.
        let mut robots = self.robots.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(r) = robots.get(path) {
            return Ok(r.clone());
        }
        let r = Arc::new(Robot::load(path)?);
        robots.insert(path.to_path_buf(), r.clone());
        Ok(r)
    }
}

fn parse_with(
    text: &str,
    base: &Path,
    robot: &dyn Fn(&Path) -> Result<Arc<Robot>, ProblemError>,
) -> Result<Loaded, ProblemError> {
    let value: serde_json::Value = from_json_str(text)?;
    let Some(obj) = value.as_object() else {
        return Err(ProblemError::invalid(
            "(top level)",
            "a JSON object",
            kind_of(&value),
        ));
    };
    let matrix = obj.contains_key("grasp_matrix") || obj.contains_key("jacobian_transpose");
    let geometry = obj.contains_key("fingers");
    let hand = obj.contains_key("hand");
    let plain = |problem| Loaded {
        problem,
        hand: None,
    };
    match (matrix, geometry, hand) {
        (true, false, false) => from_json_str::<MatrixFile>(text)?
            .into_problem()
            .map(plain),
        (false, true, false) => from_json_str::<crate::geometry::GeometryFile>(text)?
            .into_problem()
            .map(plain),
        (false, false, true) => {
            let file = from_json_str::<crate::hand::HandFile>(text)?;
            let built = file.build(&*robot(&file.model_path(base)).map_err(crate::hand::model_error)?)?;
            Ok(Loaded {
                problem: built.problem,
                hand: Some(built.report),
            })
        }
        _ => Err(ProblemError::invalid(
            "(top level)",
            "one of the three forms: matrix form with grasp_matrix and jacobian_transpose, geometry form with fingers, or hand form with hand (a URDF and joint positions)",
            if matrix || geometry || hand { "fields of more than one form" } else { "none of grasp_matrix, fingers or hand" },
        )),
    }
}

fn kind_of(v: &serde_json::Value) -> &'static str {
    match v {
        serde_json::Value::Null => "null",
        serde_json::Value::Bool(_) => "a boolean",
        serde_json::Value::Number(_) => "a number",
        serde_json::Value::String(_) => "a string",
        serde_json::Value::Array(_) => "an array",
        serde_json::Value::Object(_) => "an object",
    }
}

/// Largest problem file read, in bytes (64 MiB): far above any grasp within the size
/// limits, and it stops an endless input (`/dev/zero`) at once.
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// Reads at most [`MAX_FILE_BYTES`] of UTF-8 text from `path`. A longer file or one
/// that is not UTF-8 is an [`ProblemError::Io`] naming the path, as an unreadable one
/// is: the caller (a problem file, a hand's model, an MJCF include) says what it is.
pub fn read_limited(path: &Path) -> Result<String, ProblemError> {
    use std::io::{Error, ErrorKind, Read};
    let io = |error| ProblemError::Io {
        path: path.display().to_string(),
        error,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    file.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(io(Error::new(
            ErrorKind::FileTooLarge,
            format!("expected at most {MAX_FILE_BYTES} bytes (64 MiB), got more"),
        )));
    }
    String::from_utf8(bytes).map_err(|e| {
        io(Error::new(
            ErrorKind::InvalidData,
            format!(
                "expected UTF-8 text, got invalid UTF-8 at byte {}",
                e.utf8_error().valid_up_to()
            ),
        ))
    })
}

/// Reads and parses a problem file.
pub fn load_problem(path: impl AsRef<Path>) -> Result<GraspProblem, ProblemError> {
    load(path).map(|l| l.problem)
}

/// Reads and parses a problem file in any form, with what the form adds to reports.
pub fn load(path: impl AsRef<Path>) -> Result<Loaded, ProblemError> {
    let path = path.as_ref();
    let base = path.parent().unwrap_or(Path::new("."));
    parse_problem_at(&read_limited(path)?, base)
}
