#![doc = include_str!("../../../README.md")]

pub use grasp_core::*;
pub use grasp_io::{
    file, geometry, hand, load, load_problem, parse_problem, parse_problem_at, urdf, HandFile,
    Loaded, ProblemParser, Robot,
};

#[cfg(feature = "active-set")]
pub use grasp_active_set::{
    ActiveSetSettings, ActiveSetSolver, ExactSolver, ForceSpaceSolver, Phase1,
};
#[cfg(feature = "clarabel")]
pub use grasp_clarabel::{ClarabelSettings, ClarabelSolver};
#[cfg(feature = "osqp")]
pub use grasp_osqp::{OsqpSettings, OsqpSolver};

mod backend;
pub use backend::{Backend, BackendError, Cones, Overrides, SolverConfig};
pub mod batch;
pub mod sweep;
pub use batch::{
    for_each_solution, solve_batch, BatchError, BatchGrasp, BatchOptions, BatchResult, BatchSource,
};

use std::sync::Arc;

/// Anything that stops a problem from being set up.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The problem description is invalid.
    #[error(transparent)]
    Problem(#[from] ProblemError),
    /// The QP could not be assembled.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The backend is unavailable or rejected its settings.
    #[error(transparent)]
    Backend(#[from] BackendError),
    /// A wrench or warm start does not fit the problem.
    #[error(transparent)]
    WarmStart(#[from] WarmStartError),
}

/// A solver for one grasp, reused across wrenches: it keeps the backend's workspace,
/// the last solution's buffers and a copy of the last answer for warm starts, so a
/// solve with a new wrench allocates nothing once warmed up.
pub struct GraspSolver {
    backend: Box<dyn TorqueSolver>,
    check: Check,
    /// The wrench of the last solve, for [`Self::diagnose`].
    wrench: [f64; 6],
    solution: Solution,
    last_torque: Vec<f64>,
    last_active: Vec<usize>,
    has_last: bool,
}

impl GraspSolver {
    /// Validates the problem, builds its model and the configured view, and the backend.
    pub fn new(problem: &GraspProblem, config: &SolverConfig) -> Result<Self, Error> {
        problem.validate()?;
        let model = Arc::new(GraspModel::new(problem, &config.model)?);
        Self::from_model(model, &problem.linearization, config)
    }

    /// A solver on an already built model (shared, for example, by the threads of a
    /// batch or by the rows of a sweep): only the view and the backend are built.
    pub fn from_model(
        model: Arc<GraspModel>,
        linearization: &Linearization,
        config: &SolverConfig,
    ) -> Result<Self, Error> {
        linearization
            .validate()
            .map_err(|e| ProblemError::invalid("linearization", "valid N and K", e))?;
        let qp = config.view(model, linearization);
        Ok(Self::from_backend(config.build(qp)?).with_check(config.check))
    }

    /// Wraps an already built backend, with the full check on every solve.
    pub fn from_backend(backend: Box<dyn TorqueSolver>) -> Self {
        Self {
            backend,
            check: Check::Full,
            wrench: [0.0; 6],
            solution: Solution::default(),
            last_torque: Vec::new(),
            last_active: Vec::new(),
            has_last: false,
        }
    }

    /// The same solver with `check` on every solve.
    pub fn with_check(mut self, check: Check) -> Self {
        self.check = check;
        self
    }

    /// The view the backend solves (its model is [`TorqueQp::model`]).
    pub fn problem(&self) -> &TorqueQp {
        self.backend.problem()
    }

    /// The backend's name.
    pub fn backend_name(&self) -> &'static str {
        self.backend.name()
    }

    /// Solves for `wrench` from `warm`.
    pub fn solve(&mut self, wrench: &[f64; 6], warm: &WarmStart<'_>) -> Result<&Solution, Error> {
        solve_into_with(
            self.backend.as_mut(),
            wrench,
            warm,
            self.check,
            &mut self.solution,
        )?;
        self.wrench = *wrench;
        self.remember();
        Ok(&self.solution)
    }

    /// Solves for `wrench`, warm-started from the previous optimal answer if there is one
    /// (its torque and key constraint set): the control-loop call.
    pub fn resolve(&mut self, wrench: &[f64; 6]) -> Result<&Solution, Error> {
        let warm = if self.has_last {
            WarmStart {
                torque: Some(&self.last_torque),
                active_set: Some(&self.last_active),
            }
        } else {
            WarmStart::default()
        };
        solve_into_with(
            self.backend.as_mut(),
            wrench,
            &warm,
            self.check,
            &mut self.solution,
        )?;
        self.wrench = *wrench;
        self.remember();
        Ok(&self.solution)
    }

    /// Completes what [`Check::Lazy`] deferred for the last solution: the contact forces,
    /// the residuals and margins, and the core's independent residual check, which may
    /// still turn the answer into a numerical failure (the next `resolve` then starts
    /// cold). Nothing changes after a full check.
    pub fn diagnose(&mut self) -> &Solution {
        if self.solution.diagnostics.deferred {
            let b = &self.backend;
            let (tol, name) = (b.residual_tolerance(), b.name());
            b.problem()
                .complete(&self.wrench, tol, name, &mut self.solution);
            self.has_last &= self.solution.is_optimal();
        }
        &self.solution
    }

    /// The last solution.
    pub fn solution(&self) -> &Solution {
        &self.solution
    }

    fn remember(&mut self) {
        self.has_last = self.solution.is_optimal();
        if self.has_last {
            self.last_torque.clear();
            self.last_torque.extend_from_slice(&self.solution.torque);
            self.last_active.clear();
            if let Some(a) = &self.solution.active_set {
                self.last_active.extend_from_slice(a);
            }
        }
    }
}
