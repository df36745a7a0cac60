#![doc = include_str!("../../../README.md")]

pub use grasp_core::*;
pub use grasp_io::{
    file, geometry, hand, load, load_problem, mass, parse_problem, parse_problem_at, urdf,
    HandFile, Loaded, ProblemParser, Robot,
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
    for_each_index, for_each_solution, solve_batch, BatchError, BatchGrasp, BatchOptions,
    BatchResult, BatchSource,
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

/// A solver for one grasp, reused across wrenches: it keeps the backend's workspace
/// and the last two solutions' buffers, so a solve with a new wrench allocates nothing
/// once warmed up.
pub struct GraspSolver {
    backend: Box<dyn TorqueSolver>,
    check: Check,
    /// The wrench of the last solve, for [`Self::diagnose`].
    wrench: [f64; 6],
    /// The last solution and the one before: a solve writes over the older while it
    /// warm-starts from the last, so the warm start is never copied.
    solutions: [Solution; 2],
    /// Which of `solutions` is the last.
    last: usize,
    /// Whether the last solution is optimal, and so a warm start.
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
            solutions: Default::default(),
            last: 0,
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
        let next = &mut self.solutions[1 - self.last];
        solve_into_with(self.backend.as_mut(), wrench, warm, self.check, next)?;
        Ok(self.advance(wrench))
    }

    /// Solves for `wrench`, warm-started from the previous optimal answer if there is one
    /// (its torque and key constraint set): the control-loop call.
    pub fn resolve(&mut self, wrench: &[f64; 6]) -> Result<&Solution, Error> {
        let [a, b] = &mut self.solutions;
        let (last, next) = if self.last == 0 { (&*a, b) } else { (&*b, a) };
        let warm = if self.has_last {
            WarmStart {
                torque: Some(&last.torque),
                active_set: Some(last.active_set.as_deref().unwrap_or(&[])),
            }
        } else {
            WarmStart::default()
        };
        solve_into_with(self.backend.as_mut(), wrench, &warm, self.check, next)?;
        Ok(self.advance(wrench))
    }

    /// The solve just written becomes the last.
    fn advance(&mut self, wrench: &[f64; 6]) -> &Solution {
        self.last = 1 - self.last;
        self.wrench = *wrench;
        let s = &self.solutions[self.last];
        self.has_last = s.is_optimal();
        s
    }

    /// Completes what [`Check::Lazy`] deferred for the last solution, as [`Check::Full`]
    /// would have ([`complete_deferred`]): the contact forces, the residuals and margins,
    /// and the core's independent residual check, whose refusal sends the wrench to the
    /// backend's fallback; the answer may still become a numerical failure (the next
    /// `resolve` then starts cold). Nothing changes after a full check.
    pub fn diagnose(&mut self) -> &Solution {
        let s = &mut self.solutions[self.last];
        complete_deferred(self.backend.as_mut(), &self.wrench, s);
        self.has_last &= s.is_optimal();
        &self.solutions[self.last]
    }

    /// The last solution.
    pub fn solution(&self) -> &Solution {
        &self.solutions[self.last]
    }
}
