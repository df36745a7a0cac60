//! Backend selection: the one place that knows every backend.

use grasp_core::{ModelOptions, TorqueQp, TorqueSolver};
use std::fmt;
use std::str::FromStr;

/// The QP backends. Each is compiled in through the cargo feature of the same name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Backend {
    /// The paper's key-constraint-set method (crate `grasp-active-set`), linearised cones.
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
    /// This backend cannot handle these cones.
    #[error("backend `{backend}` does not support `--cones {cones}`; supported: {supported}")]
    Unsupported {
        /// Its name.
        backend: &'static str,
        /// The cones asked for.
        cones: &'static str,
        /// Every supported backend/cones pair.
        supported: String,
    },
    /// The backend rejected its settings or the problem.
    #[error("backend `{backend}`: {message}")]
    Build {
        /// Its name.
        backend: &'static str,
        /// What went wrong.
        message: String,
    },
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

    /// Whether this build has it.
    pub fn is_compiled(&self) -> bool {
        match self {
            Backend::ActiveSet => cfg!(feature = "active-set"),
            Backend::Clarabel => cfg!(feature = "clarabel"),
            Backend::Osqp => cfg!(feature = "osqp"),
        }
    }

    /// Whether it handles `cones`.
    pub fn supports(&self, cones: Cones) -> bool {
        match self {
            Backend::Clarabel => true,
            Backend::ActiveSet | Backend::Osqp => cones == Cones::Linear,
        }
    }

    /// The backends compiled into this build.
    pub fn compiled() -> impl Iterator<Item = Backend> {
        Self::ALL.into_iter().filter(Backend::is_compiled)
    }

    /// `active-set/linear, clarabel/linear, clarabel/exact`.
    pub fn supported_pairs() -> String {
        let mut v = Vec::new();
        for b in Self::ALL {
            for c in [Cones::Linear, Cones::Exact] {
                if b.supports(c) {
                    v.push(format!("{}/{}", b.name(), c.name()));
                }
            }
        }
        v.join(", ")
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

/// Everything that configures a solve: model options, backend, cones and each
/// backend's settings (all with documented defaults).
#[derive(Clone, Debug, Default)]
pub struct SolverConfig {
    /// Consistency equalities or the paper model, and the rank tolerance.
    pub model: ModelOptions,
    /// The backend. Default: the native active-set method.
    pub backend: Option<Backend>,
    /// The cones. Default: linear.
    pub cones: Cones,
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
    /// The backend in use: the configured one, else the first compiled in.
    pub fn backend(&self) -> Result<Backend, BackendError> {
        match self.backend {
            Some(b) => Ok(b),
            None => Backend::compiled().next().ok_or(BackendError::NotCompiled {
                backend: "active-set",
                feature: "active-set",
            }),
        }
    }

    /// Builds the configured backend for `qp`.
    pub fn build(&self, qp: TorqueQp) -> Result<Box<dyn TorqueSolver>, BackendError> {
        let backend = self.backend()?;
        if !backend.is_compiled() {
            return Err(BackendError::NotCompiled {
                backend: backend.name(),
                feature: backend.feature(),
            });
        }
        if !backend.supports(self.cones) {
            return Err(BackendError::Unsupported {
                backend: backend.name(),
                cones: self.cones.name(),
                supported: Backend::supported_pairs(),
            });
        }
        let build_err = |e: &dyn fmt::Display| BackendError::Build {
            backend: backend.name(),
            message: e.to_string(),
        };
        match backend {
            #[cfg(feature = "active-set")]
            Backend::ActiveSet => grasp_active_set::ActiveSetSolver::new(qp, self.active_set)
                .map(|s| Box::new(s) as Box<dyn TorqueSolver>)
                .map_err(|e| build_err(&e)),
            #[cfg(feature = "clarabel")]
            Backend::Clarabel => {
                let exact = self.cones == Cones::Exact;
                grasp_clarabel::ClarabelSolver::new(qp, exact, self.clarabel)
                    .map(|s| Box::new(s) as Box<dyn TorqueSolver>)
                    .map_err(|e| build_err(&e))
            }
            #[cfg(feature = "osqp")]
            Backend::Osqp => grasp_osqp::OsqpSolver::new(qp, self.osqp)
                .map(|s| Box::new(s) as Box<dyn TorqueSolver>)
                .map_err(|e| build_err(&e)),
            // Not compiled in: already reported above; kept as an error, never a panic.
            #[allow(unreachable_patterns)]
            _ => Err(BackendError::NotCompiled {
                backend: backend.name(),
                feature: backend.feature(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn qp() -> TorqueQp {
        let p = grasp_core::load_problem(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/fixtures/paper-example.json"
        ))
        .unwrap();
        TorqueQp::new(&p, &ModelOptions::default()).unwrap()
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
        let config = SolverConfig {
            backend: Some(Backend::ActiveSet),
            cones: Cones::Exact,
            ..Default::default()
        };
        if Backend::ActiveSet.is_compiled() {
            let err = config.build(qp()).err().expect("unsupported").to_string();
            assert!(err.contains("clarabel/exact"), "{err}");
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
