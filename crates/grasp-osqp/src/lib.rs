//! OSQP backend: the linearised torque QP (`min Σ w τ²`, `C τ = e`, `H τ ≥ c`) solved by
//! OSQP's ADMM, with solution polishing so that active rows hold exactly where OSQP
//! manages it, and OSQP's warm start when a starting torque is given.
//!
//! Built against osqp 0.6, which bundles its linear solver (qdldl) and builds offline,
//! but needs a `cmake` binary: `apt-get install cmake` on Debian. Hence the facade's
//! `osqp` feature is opt-in.

use grasp_core::matrix::dot;
use grasp_core::{Capabilities, Reason, Solution, Status, TorqueQp, TorqueSolver, WarmStart};

/// What the OSQP backend supports.
pub const CAPABILITIES: Capabilities = Capabilities {
    exact_cones: false,
    free_internal_forces: false,
    warm_key_set: false,
    warm_torque: true,
    certifies_rows: false,
};

fn backend(message: &str) -> Option<Reason> {
    Some(Reason::Backend {
        backend: "osqp",
        message: message.into(),
    })
}
use osqp::{CscMatrix, PolishStatus, Problem, Settings};

/// OSQP's infinity: a larger bound makes OSQP treat the row as two-sided.
const OSQP_INFTY: f64 = 1e30;

/// Settings passed to OSQP.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OsqpSettings {
    /// Absolute tolerance. Default 1e-7: tighter makes ADMM run to its cap on badly
    /// scaled grasps; polishing recovers the accuracy where it succeeds.
    pub eps_abs: f64,
    /// Relative tolerance. Default 1e-7.
    pub eps_rel: f64,
    /// ADMM iteration cap. Default 200 000 (badly scaled grasps need tens of thousands).
    pub max_iter: u32,
    /// Polish the ADMM answer by solving the equality QP on its guessed active set.
    /// Default true.
    pub polish: bool,
}

impl Default for OsqpSettings {
    fn default() -> Self {
        Self {
            eps_abs: 1e-7,
            eps_rel: 1e-7,
            max_iter: 200_000,
            polish: true,
        }
    }
}

impl OsqpSettings {
    /// Relative σ tolerance the answers are tested to: 1e-5 when polishing succeeded
    /// (polishing solves a KKT system regularised by OSQP's delta = 1e-6, so on badly
    /// scaled grasps σ lands ~1e-6 off), ADMM's first-order accuracy (1e-3) otherwise.
    pub fn stated_tolerance(polished: bool) -> f64 {
        if polished {
            1e-5
        } else {
            1e-3
        }
    }
}

/// OSQP rejected the problem data or settings.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("OSQP setup: {0}")]
pub struct OsqpError(pub String);

/// The OSQP backend for one grasp.
pub struct OsqpSolver {
    qp: TorqueQp,
    problem: Problem,
    lower: Vec<f64>,
    upper: Vec<f64>,
    zeros_x: Vec<f64>,
    zeros_y: Vec<f64>,
    /// Whether the last solve's polish succeeded.
    polished: bool,
}

impl OsqpSolver {
    /// Sets OSQP up for `qp` (the wrench enters only through the bounds).
    pub fn new(qp: TorqueQp, settings: OsqpSettings) -> Result<Self, OsqpError> {
        let m = qp.joints();
        let (p_eq, p_in) = (qp.equality_rows(), qp.inequality_rows());
        let rows = p_eq + p_in;
        let p = CscMatrix::from_column_iter_dense(
            m,
            m,
            (0..m)
                .flat_map(|j| (0..m).map(move |i| (i, j)))
                .map(|(i, j)| {
                    if i == j {
                        2.0 * qp.model.weights[i]
                    } else {
                        0.0
                    }
                }),
        )
        .into_upper_tri();
        let a = CscMatrix::from_row_iter_dense(
            rows,
            m,
            (0..rows).flat_map(|i| {
                let row = if i < p_eq {
                    qp.model.eq.row(i)
                } else {
                    qp.h().row(i - p_eq)
                };
                row.to_vec()
            }),
        );
        let s = Settings::default()
            .verbose(false)
            .eps_abs(settings.eps_abs)
            .eps_rel(settings.eps_rel)
            .max_iter(settings.max_iter)
            .polish(settings.polish)
            .warm_start(true);
        let lower = vec![0.0; rows];
        let mut upper = vec![OSQP_INFTY; rows];
        upper[..p_eq].iter_mut().for_each(|u| *u = 0.0);
        let problem = Problem::new(&p, &vec![0.0; m], &a, &lower, &upper, &s)
            .map_err(|e| OsqpError(format!("{e:?}")))?;
        Ok(Self {
            problem,
            lower,
            upper,
            zeros_x: vec![0.0; m],
            zeros_y: vec![0.0; rows],
            polished: false,
            qp,
        })
    }

    /// Whether the last solve's polish succeeded (its answer is then accurate to
    /// [`OsqpSettings::stated_tolerance`]`(true)`).
    pub fn polished(&self) -> bool {
        self.polished
    }
}

impl TorqueSolver for OsqpSolver {
    fn name(&self) -> &'static str {
        "osqp"
    }

    fn capabilities(&self) -> Capabilities {
        CAPABILITIES
    }

    fn residual_tolerance(&self) -> f64 {
        // ADMM's feasibility is ε-relative to its own data; polishing makes it exact on
        // the active set.
        if self.polished {
            1e-6
        } else {
            1e-4
        }
    }

    fn problem(&self) -> &TorqueQp {
        &self.qp
    }

    fn solve_raw(&mut self, w: &[f64; 6], warm: &WarmStart<'_>, out: &mut Solution) {
        let qp = &self.qp;
        let p_eq = qp.equality_rows();
        for i in 0..p_eq {
            let e = -dot(qp.model.eq_w.row(i), w);
            self.lower[i] = e;
            self.upper[i] = e;
        }
        for i in 0..qp.inequality_rows() {
            self.lower[p_eq + i] = qp.c0[i] - dot(qp.hw.row(i), w);
        }
        self.problem.update_bounds(&self.lower, &self.upper);
        match warm.torque {
            Some(t) => self.problem.warm_start_x(t),
            None => self.problem.warm_start(&self.zeros_x, &self.zeros_y),
        }
        out.torque.clear();
        out.active_set = None;
        let status = self.problem.solve();
        out.iterations = status.iter() as usize;
        let (st, reason, x) = match &status {
            osqp::Status::Solved(s) => (Status::Optimal, None, Some((s.x(), s.y(), s.polish_status()))),
            osqp::Status::SolvedInaccurate(s) => {
                out.warnings.push("OSQP: solved inaccurately".into());
                (Status::Optimal, None, Some((s.x(), s.y(), s.polish_status())))
            }
            osqp::Status::PrimalInfeasible(_) | osqp::Status::PrimalInfeasibleInaccurate(_) => (
                Status::Infeasible,
                backend("a certificate of primal infeasibility: no torque keeps every contact force inside its linearised cone while balancing the wrench"),
                None,
            ),
            osqp::Status::MaxIterationsReached(_) | osqp::Status::TimeLimitReached(_) => (
                Status::IterationLimit,
                backend("reached its iteration limit"),
                None,
            ),
            _ => (Status::NumericalFailure, backend("failed"), None),
        };
        out.status = st;
        out.reason = reason;
        self.polished = false;
        if let Some((x, y, polish)) = x {
            out.torque.extend_from_slice(x);
            // OSQP's y is the multiplier of l ≤ A x ≤ u with y < 0 on active lower bounds.
            out.multipliers
                .extend(y[p_eq..].iter().map(|v| (-v).max(0.0)));
            self.polished = polish == PolishStatus::Successful;
            if !self.polished {
                out.warnings.push(format!(
                    "OSQP: polishing did not succeed; expect relative accuracy near {:.0e}",
                    OsqpSettings::stated_tolerance(false)
                ));
            }
        }
    }
}
