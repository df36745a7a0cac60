//! Backend selection: the one place that knows every backend.

use grasp_core::cone::LinearizationError;
use grasp_core::{
    Capabilities, Check, Equilibrium, GraspModel, GraspProblem, InternalForces, Linearization,
    ModelOptions, SfceSpacing, TorqueQp, TorqueSolver,
};
use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

/// The QP backends. Each is compiled in through the cargo feature of the same name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Backend {
    /// The paper's key-constraint-set method (crate `grasp-active-set`) for linearised
    /// cones, and its exact-cone solver for exact ones.
    ActiveSet,
    /// Clarabel's interior-point method (crate `grasp-clarabel`), linearised or exact cones.
    Clarabel,
    /// OSQP's ADMM with polishing (crate `grasp-osqp`), linearised cones. Opt-in: its
    /// build needs cmake.
    Osqp,
}

/// Which friction cones the backend sees.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Cones {
    /// The inscribed polyhedral cones (`H τ ≥ c`).
    #[default]
    Linear,
    /// The exact (second-order) cones.
    Exact,
}

impl Cones {
    /// `linear` or `exact`.
    pub fn name(&self) -> &'static str {
        match self {
            Cones::Linear => "linear",
            Cones::Exact => "exact",
        }
    }
}

impl FromStr for Cones {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "linear" => Ok(Cones::Linear),
            "exact" => Ok(Cones::Exact),
            _ => Err(format!("unknown cones `{s}`: expected `linear` or `exact`")),
        }
    }
}

impl fmt::Display for Cones {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A backend that cannot be built.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BackendError {
    /// Not compiled into this build.
    #[error("backend `{backend}` is not compiled in: rebuild with `--features {feature}`")]
    NotCompiled {
        /// Its name.
        backend: &'static str,
        /// The cargo feature that enables it.
        feature: &'static str,
    },
    /// This backend cannot solve this formulation.
    #[error(
        "backend `{backend}` does not support {what}; backends compiled in that do: {supported}"
    )]
    Unsupported {
        /// Its name.
        backend: &'static str,
        /// What it lacks, such as `--cones exact`.
        what: &'static str,
        /// The compiled backends that support it (may be empty).
        supported: String,
    },
    /// The native backend rejected its settings or the problem.
    #[cfg(feature = "active-set")]
    #[error("backend `active-set`: {0}")]
    ActiveSet(#[from] grasp_active_set::BuildError),
    /// Clarabel rejected its settings.
    #[cfg(feature = "clarabel")]
    #[error("backend `clarabel`: {0}")]
    Clarabel(#[from] grasp_clarabel::ClarabelError),
    /// OSQP rejected its settings or the problem.
    #[cfg(feature = "osqp")]
    #[error("backend `osqp`: {0}")]
    Osqp(#[from] grasp_osqp::OsqpError),
}

impl Backend {
    /// Every backend, compiled in or not.
    pub const ALL: [Backend; 3] = [Backend::ActiveSet, Backend::Clarabel, Backend::Osqp];

    /// The command-line name.
    pub fn name(&self) -> &'static str {
        match self {
            Backend::ActiveSet => "active-set",
            Backend::Clarabel => "clarabel",
            Backend::Osqp => "osqp",
        }
    }

    /// The cargo feature that compiles it in.
    pub fn feature(&self) -> &'static str {
        self.name()
    }

    /// What it supports, as its crate declares; `None` when it is not compiled in.
    pub fn capabilities(&self) -> Option<Capabilities> {
        match self {
            #[cfg(feature = "active-set")]
            Backend::ActiveSet => Some(grasp_active_set::CAPABILITIES),
            #[cfg(feature = "clarabel")]
            Backend::Clarabel => Some(grasp_clarabel::CAPABILITIES),
            #[cfg(feature = "osqp")]
            Backend::Osqp => Some(grasp_osqp::CAPABILITIES),
            #[allow(unreachable_patterns)]
            _ => None,
        }
    }

    /// Whether this build has it.
    pub fn is_compiled(&self) -> bool {
        self.capabilities().is_some()
    }

    /// What a backend lacks for `need`, if anything.
    fn lacks(&self, need: &Needs) -> Option<&'static str> {
        let caps = self.capabilities()?;
        if need.exact && !caps.exact_cones {
            Some("--cones exact")
        } else if need.free && !caps.free_internal_forces {
            Some("free internal forces (internal_forces: free)")
        } else {
            None
        }
    }

    /// The backends compiled into this build.
    pub fn compiled() -> impl Iterator<Item = Backend> {
        Self::ALL.into_iter().filter(Backend::is_compiled)
    }

    /// Whether it handles `cones` (with fixed internal forces).
    pub fn supports(&self, cones: Cones) -> bool {
        let need = Needs {
            exact: cones == Cones::Exact,
            free: false,
        };
        self.is_compiled() && self.lacks(&need).is_none()
    }
}

/// What a formulation asks of a backend.
struct Needs {
    exact: bool,
    free: bool,
}

impl Needs {
    fn of(qp: &TorqueQp) -> Self {
        Self {
            exact: qp.constraints.has_exact(),
            // (With no passive internal forces, `free` leaves nothing to optimise.)
            free: qp.model.free_dim() > 0,
        }
    }

    fn supporting(&self) -> Vec<Backend> {
        Backend::compiled()
            .filter(|b| b.lacks(self).is_none())
            .collect()
    }
}

impl FromStr for Backend {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|b| b.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(Backend::name).collect();
                format!(
                    "unknown backend `{s}`: expected one of {}",
                    names.join(", ")
                )
            })
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The options a caller sets over a problem's own: the command line's flags and the
/// Python keywords, applied the same way by both.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Overrides {
    /// The backend (default: the first compiled one that supports the problem).
    pub backend: Option<Backend>,
    /// The cones. Default: linear.
    pub cones: Cones,
    /// What is checked on every solve ([`SolverConfig::check`]).
    pub check: Check,
    /// N, sides of the inscribed polygons (the problem's own when `None`).
    pub sides: Option<usize>,
    /// K, latitudes per hemisphere of SFCe polyhedra.
    pub latitudes: Option<usize>,
    /// Placement of SFCe latitudes.
    pub sfce_spacing: Option<SfceSpacing>,
    /// How the passive internal forces are fixed.
    pub internal_forces: Option<InternalForces>,
    /// The paper's model, without the consistency equalities.
    pub paper_model: bool,
}

impl Overrides {
    /// Applies the overrides to `p` and returns the solver configuration; an invalid
    /// linearisation is refused before anything is built.
    pub fn apply(&self, p: &mut GraspProblem) -> Result<SolverConfig, LinearizationError> {
        if let Some(n) = self.sides {
            p.linearization.sides = n;
        }
        if let Some(k) = self.latitudes {
            p.linearization.latitudes = k;
        }
        if let Some(s) = self.sfce_spacing {
            p.linearization.sfce_spacing = s;
        }
        p.linearization.validate()?;
        if let Some(i) = self.internal_forces {
            p.internal_forces = i;
        }
        let mut config = SolverConfig {
            backend: self.backend,
            cones: self.cones,
            check: self.check,
            ..Default::default()
        };
        if self.paper_model {
            config.model.equilibrium = Equilibrium::PaperModel;
        }
        Ok(config)
    }
}

/// Everything that configures a solve: model options, backend, cones and each
/// backend's settings (all with documented defaults).
#[derive(Clone, Debug, Default)]
pub struct SolverConfig {
    /// Consistency equalities or the paper model, and the rank tolerance.
    pub model: ModelOptions,
    /// The backend. Default (`None`): the first compiled backend, in the order
    /// active-set, clarabel, osqp, that supports the formulation.
    pub backend: Option<Backend>,
    /// The cones. Default: linear.
    pub cones: Cones,
    /// What [`crate::GraspSolver`] and the batches check on every solve. Default:
    /// [`Check::Full`]; [`Check::Lazy`] defers the forces and residuals to
    /// [`crate::GraspSolver::diagnose`] (the control-loop setting; a batch's answers
    /// then carry σ and τ only).
    pub check: Check,
    /// Settings of the native backend.
    #[cfg(feature = "active-set")]
    pub active_set: grasp_active_set::ActiveSetSettings,
    /// Settings of the Clarabel backend.
    #[cfg(feature = "clarabel")]
    pub clarabel: grasp_clarabel::ClarabelSettings,
    /// Settings of the OSQP backend.
    #[cfg(feature = "osqp")]
    pub osqp: grasp_osqp::OsqpSettings,
}

impl SolverConfig {
    /// The backend that [`Self::build`] would use for `qp`.
    pub fn backend_for(&self, qp: &TorqueQp) -> Result<Backend, BackendError> {
        let need = Needs::of(qp);
        let supported = || {
            let v: Vec<_> = need.supporting().iter().map(Backend::name).collect();
            if v.is_empty() {
                "none".to_string()
            } else {
                v.join(", ")
            }
        };
        match self.backend {
            Some(b) => {
                if !b.is_compiled() {
                    return Err(BackendError::NotCompiled {
                        backend: b.name(),
                        feature: b.feature(),
                    });
                }
                match b.lacks(&need) {
                    Some(what) => Err(BackendError::Unsupported {
                        backend: b.name(),
                        what,
                        supported: supported(),
                    }),
                    None => Ok(b),
                }
            }
            None => match need.supporting().first() {
                Some(&b) => Ok(b),
                None => {
                    let b = Backend::compiled().next().unwrap_or(Backend::ActiveSet);
                    if b.is_compiled() {
                        Err(BackendError::Unsupported {
                            backend: b.name(),
                            what: b.lacks(&need).unwrap_or("this formulation"),
                            supported: supported(),
                        })
                    } else {
                        Err(BackendError::NotCompiled {
                            backend: b.name(),
                            feature: b.feature(),
                        })
                    }
                }
            },
        }
    }

    /// Validates `p`, builds its model and the view the configured cones ask for.
    pub fn qp(&self, p: &GraspProblem) -> Result<TorqueQp, crate::Error> {
        p.validate()?;
        let model = Arc::new(GraspModel::new(p, &self.model)?);
        Ok(self.view(model, &p.linearization))
    }

    /// The view of `model` the configured cones ask for: inscribed at `lin`, or exact.
    pub fn view(&self, model: Arc<GraspModel>, lin: &Linearization) -> TorqueQp {
        match self.cones {
            Cones::Linear => TorqueQp::linearized(model, lin),
            Cones::Exact => TorqueQp::exact(model),
        }
    }

    /// Builds the configured backend for `qp`.
    pub fn build(&self, qp: TorqueQp) -> Result<Box<dyn TorqueSolver>, BackendError> {
        match self.backend_for(&qp)? {
            #[cfg(feature = "active-set")]
            Backend::ActiveSet if qp.constraints.has_exact() => Ok(Box::new(
                grasp_active_set::ExactSolver::new(qp, self.active_set)?,
            )),
            #[cfg(feature = "active-set")]
            Backend::ActiveSet => Ok(Box::new(grasp_active_set::ActiveSetSolver::new(
                qp,
                self.active_set,
            )?)),
            #[cfg(feature = "clarabel")]
            Backend::Clarabel => Ok(Box::new(grasp_clarabel::ClarabelSolver::new(
                qp,
                self.clarabel,
            )?)),
            #[cfg(feature = "osqp")]
            Backend::Osqp => Ok(Box::new(grasp_osqp::OsqpSolver::new(qp, self.osqp)?)),
            // Not compiled in: backend_for already refused it; an error, never a panic.
            #[allow(unreachable_patterns)]
            b => Err(BackendError::NotCompiled {
                backend: b.name(),
                feature: b.feature(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> Arc<GraspModel> {
        let p = grasp_io::load_problem(concat!(
            concat!(env!("CARGO_MANIFEST_DIR"), "/../.."),
            "/fixtures/paper-example.json"
        ))
        .unwrap();
        Arc::new(GraspModel::new(&p, &ModelOptions::default()).unwrap())
    }

    fn qp() -> TorqueQp {
        TorqueQp::linearized(model(), &Linearization::default())
    }

    #[test]
    fn a_backend_not_compiled_in_names_its_feature() {
        for b in Backend::ALL.into_iter().filter(|b| !b.is_compiled()) {
            let config = SolverConfig {
                backend: Some(b),
                ..Default::default()
            };
            let err = config.build(qp()).err().expect("not compiled").to_string();
            assert!(
                err.contains(&format!("--features {}", b.feature())),
                "{err}"
            );
        }
    }

    #[test]
    fn unsupported_cones_list_the_supported_pairs() {
        // OSQP has no exact cones; the native backend and Clarabel have.
        if Backend::Osqp.is_compiled() {
            let config = SolverConfig {
                backend: Some(Backend::Osqp),
                cones: Cones::Exact,
                ..Default::default()
            };
            let err = config
                .build(TorqueQp::exact(model()))
                .err()
                .expect("unsupported");
            let err = err.to_string();
            assert!(err.contains("--cones exact"), "{err}");
            assert!(err.contains("active-set"), "{err}");
        }
    }

    #[test]
    fn exact_cones_default_to_the_native_solver() {
        let config = SolverConfig {
            cones: Cones::Exact,
            ..Default::default()
        };
        let exact = TorqueQp::exact(model());
        if Backend::ActiveSet.is_compiled() {
            assert_eq!(config.backend_for(&exact).unwrap(), Backend::ActiveSet);
        }
    }

    #[test]
    fn names_round_trip() {
        for b in Backend::ALL {
            assert_eq!(b.name().parse::<Backend>().unwrap(), b);
        }
        assert!("cplex".parse::<Backend>().is_err());
    }
}
