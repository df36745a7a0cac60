//! The backend trait and what every backend returns.

use crate::matrix::{dot, norm_inf};
use crate::qp::{Equilibrium, TorqueQp};
use std::fmt;
use std::time::{Duration, Instant};

/// How a solve finished ("ran and finished"; bad input is an `Err` instead).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Status {
    /// An optimal torque was found.
    Optimal,
    /// No torque satisfies the constraints; [`Solution::reason`] says why.
    Infeasible,
    /// The iteration cap was reached before optimality.
    IterationLimit,
    /// The backend could not make progress reliably.
    #[default]
    NumericalFailure,
}

impl Status {
    /// `optimal`, `infeasible`, `iteration_limit` or `numerical_failure`.
    pub fn as_str(&self) -> &'static str {
        match self {
            Status::Optimal => "optimal",
            Status::Infeasible => "infeasible",
            Status::IterationLimit => "iteration_limit",
            Status::NumericalFailure => "numerical_failure",
        }
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Why a solve did not end optimal.
#[derive(Clone, Debug, PartialEq)]
pub enum Reason {
    /// No torque can make `[w; τ]` consistent: part of the wrench is outside what any
    /// contact force produced by the joints can balance.
    UnreachableWrench {
        /// `‖unreachable · w‖∞`, in wrench units.
        residual: f64,
    },
    /// A constraint row that no torque affects is violated by the wrench alone.
    FixedRowViolated {
        /// Row of H.
        row: usize,
        /// What the row stands for.
        description: String,
        /// By how much (force units for cone rows).
        violation: f64,
    },
    /// The linearised cones, the consistency equalities and the options admit no torque.
    NoAdmissibleTorque {
        /// With an elastic start: the smallest uniform relaxation of the normalised rows
        /// that the solver found would make the problem feasible.
        relaxation: Option<f64>,
        /// The rows that block, with their descriptions.
        blocking: Vec<String>,
    },
    /// Backend-specific explanation.
    Backend(String),
}

impl fmt::Display for Reason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Reason::UnreachableWrench { residual } => write!(
                f,
                "the wrench has a component ({residual:.3e}) that no joint torque can balance: [w; τ] cannot lie in the range of [G; Jᵀ]"
            ),
            Reason::FixedRowViolated { row, description, violation } => write!(
                f,
                "row {row} ({description}) is not affected by any joint torque and the wrench violates it by {violation:.3e}"
            ),
            Reason::NoAdmissibleTorque { relaxation, blocking } => {
                write!(f, "no joint torque keeps every contact force inside its linearised cone while balancing the wrench (")?;
                if let Some(r) = relaxation {
                    write!(f, "the rows would need relaxing by {r:.3e}; ")?;
                }
                write!(f, "conflicting rows: {})", blocking.join(", "))
            }
            Reason::Backend(s) => f.write_str(s),
        }
    }
}

/// Physical consistency checks, computed by the core so every backend reports alike.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Diagnostics {
    /// `‖G f − w‖∞`: does the answer hold the object?
    pub wrench_residual: f64,
    /// `‖Jᵀ f − τ‖∞`: do the joints produce these forces?
    pub torque_residual: f64,
    /// `‖C τ − e‖∞` (0 in the paper model).
    pub consistency_residual: f64,
    /// Largest violation `max(c_i − H_i τ, 0)` of the linearised rows (force units for
    /// cone rows, torque units for limit rows).
    pub max_violation: f64,
    /// Per contact, the scale-free margin to its exact cone (see
    /// [`crate::ContactModel::exact_margin`]): 1 pure normal push, 0 on the cone, < 0 outside.
    pub friction_margins: Vec<f64>,
}

/// The answer of one solve.
#[derive(Clone, Debug, Default)]
pub struct Solution {
    /// How the solve finished.
    pub status: Status,
    /// Why it is not optimal, when it is not.
    pub reason: Option<Reason>,
    /// τ, one per joint (empty unless the status is optimal, or an iteration limit with
    /// a feasible iterate).
    pub torque: Vec<f64>,
    /// `f = Z1 w + Z2 τ`, in contact order (empty when `torque` is).
    pub contact_forces: Vec<f64>,
    /// `σ = Σ w_j τ_j²` (eq. 40; NaN-free: 0 when there is no torque).
    pub objective: f64,
    /// Iterations of the backend.
    pub iterations: usize,
    /// The final key constraint set: rows of H active at τ, when the backend has one.
    pub active_set: Option<Vec<usize>>,
    /// Lagrange multipliers of the rows of H for `Σ w_j τ_j²` (empty if not reported).
    pub multipliers: Vec<f64>,
    /// Wall-clock time of the solve, model already built.
    pub solve_time: Duration,
    /// Residuals and margins.
    pub diagnostics: Diagnostics,
    /// Warnings to show the user (for example the paper model's unbalanced wrench).
    pub warnings: Vec<String>,
}

impl Solution {
    /// Whether the status is optimal.
    pub fn is_optimal(&self) -> bool {
        self.status == Status::Optimal
    }
}

/// A starting point for a solve.
#[derive(Clone, Copy, Debug, Default)]
pub struct WarmStart<'a> {
    /// An initial torque (used when feasible, otherwise as a starting guess).
    pub torque: Option<&'a [f64]>,
    /// An initial key constraint set (rows of H), such as a previous answer's.
    pub active_set: Option<&'a [usize]>,
}

impl<'a> WarmStart<'a> {
    /// Warm start from a previous answer: its torque and its key constraint set.
    pub fn from_solution(s: &'a Solution) -> Self {
        Self {
            torque: (!s.torque.is_empty()).then_some(s.torque.as_slice()),
            active_set: s.active_set.as_deref(),
        }
    }
}

/// A warm start that does not fit the problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum WarmStartError {
    /// Wrong number of torques.
    #[error("initial torque: expected {expected} values (one per joint), got {found}")]
    TorqueLength {
        /// Joints.
        expected: usize,
        /// Given.
        found: usize,
    },
    /// A torque that is not finite.
    #[error("initial torque[{index}]: expected a finite number")]
    TorqueNotFinite {
        /// Joint.
        index: usize,
    },
    /// An active-set index out of range.
    #[error("initial active set: row {row} does not exist (the problem has {rows} rows)")]
    ActiveSetRow {
        /// The index given.
        row: usize,
        /// Rows of H.
        rows: usize,
    },
    /// A wrench that is not finite.
    #[error("wrench[{index}]: expected a finite number")]
    WrenchNotFinite {
        /// Component.
        index: usize,
    },
}

/// A QP backend. Built once per grasp (it may factor and cache what depends only on
/// the grasp), then solved for any number of wrenches without allocating.
pub trait TorqueSolver {
    /// The backend's name, as used on the command line.
    fn name(&self) -> &'static str;

    /// The problem this solver was built for.
    fn problem(&self) -> &TorqueQp;

    /// Solves for `wrench`: sets `status`, `reason`, `torque`, `iterations`,
    /// `active_set` and `multipliers` of `out`, reusing its buffers. Inputs have been
    /// checked by [`solve_into`], which also fills the rest.
    fn solve_raw(&mut self, wrench: &[f64; 6], warm: &WarmStart<'_>, out: &mut Solution);
}

/// Solves with any backend and completes the answer with forces, objective and
/// diagnostics. Reuses `out`'s buffers: no allocation once they have grown to size
/// (warnings aside).
pub fn solve_into(
    solver: &mut dyn TorqueSolver,
    wrench: &[f64; 6],
    warm: &WarmStart<'_>,
    out: &mut Solution,
) -> Result<(), WarmStartError> {
    let qp = solver.problem();
    check_inputs(qp, wrench, warm)?;
    let start = Instant::now();
    out.warnings.clear();
    out.reason = None;
    out.multipliers.clear();
    let residual = qp.unreachable_residual(wrench);
    if residual > qp.unreachable_tolerance(wrench) {
        out.status = Status::Infeasible;
        out.reason = Some(Reason::UnreachableWrench { residual });
        out.torque.clear();
        out.iterations = 0;
        out.active_set = None;
    } else {
        solver.solve_raw(wrench, warm, out);
    }
    out.solve_time = start.elapsed();
    solver.problem().complete(wrench, out);
    Ok(())
}

/// [`solve_into`] into a fresh [`Solution`].
pub fn solve(
    solver: &mut dyn TorqueSolver,
    wrench: &[f64; 6],
    warm: &WarmStart<'_>,
) -> Result<Solution, WarmStartError> {
    let mut s = Solution::default();
    solve_into(solver, wrench, warm, &mut s)?;
    Ok(s)
}

fn check_inputs(qp: &TorqueQp, w: &[f64; 6], warm: &WarmStart<'_>) -> Result<(), WarmStartError> {
    if let Some(index) = w.iter().position(|v| !v.is_finite()) {
        return Err(WarmStartError::WrenchNotFinite { index });
    }
    if let Some(t) = warm.torque {
        if t.len() != qp.joints() {
            return Err(WarmStartError::TorqueLength {
                expected: qp.joints(),
                found: t.len(),
            });
        }
        if let Some(index) = t.iter().position(|v| !v.is_finite()) {
            return Err(WarmStartError::TorqueNotFinite { index });
        }
    }
    if let Some(a) = warm.active_set {
        let rows = qp.inequality_rows();
        if let Some(&row) = a.iter().find(|&&r| r >= rows) {
            return Err(WarmStartError::ActiveSetRow { row, rows });
        }
    }
    Ok(())
}

impl TorqueQp {
    /// Fills forces, objective and diagnostics of `out` from its torque.
    pub fn complete(&self, w: &[f64; 6], out: &mut Solution) {
        let n = self.force_dim();
        let d = &mut out.diagnostics;
        d.friction_margins.clear();
        if out.torque.is_empty() {
            out.contact_forces.clear();
            out.objective = 0.0;
            d.wrench_residual = 0.0;
            d.torque_residual = 0.0;
            d.consistency_residual = 0.0;
            d.max_violation = 0.0;
            return;
        }
        let tau = &out.torque;
        out.contact_forces.resize(n, 0.0);
        self.forces_into(w, tau, &mut out.contact_forces);
        let f = &out.contact_forces;
        out.objective = tau
            .iter()
            .zip(&self.weights)
            .map(|(t, wj)| wj * t * t)
            .sum();
        d.wrench_residual = (0..6)
            .map(|i| (dot(self.grasp_matrix.row(i), f) - w[i]).abs())
            .fold(0.0, f64::max);
        d.torque_residual = (0..self.joints())
            .map(|j| (dot(self.jacobian_transpose.row(j), f) - tau[j]).abs())
            .fold(0.0, f64::max);
        d.consistency_residual = (0..self.equality_rows())
            .map(|i| (dot(self.eq.row(i), tau) + dot(self.eq_w.row(i), w)).abs())
            .fold(0.0, f64::max);
        // c − H τ = s0 − S f on cone rows (S is block-diagonal: a few flops per row),
        // and the limit rows read τ directly.
        d.max_violation = 0.0;
        for c in &self.contacts {
            let fc = &f[c.offset..c.offset + c.model.dim()];
            for i in c.first_row..c.first_row + c.rows {
                let v = self.c0[i] - dot(&self.s.row(i)[c.offset..c.offset + c.model.dim()], fc);
                d.max_violation = d.max_violation.max(v);
            }
        }
        for (i, kind) in self.row_kinds.iter().enumerate() {
            if let crate::qp::RowKind::TorqueLimit { .. } = *kind {
                let v = self.c0[i] - dot(self.h.row(i), tau);
                d.max_violation = d.max_violation.max(v);
            }
        }
        let zero = 1e-12 * norm_inf(f);
        for c in &self.contacts {
            d.friction_margins.push(
                c.model
                    .exact_margin(&f[c.offset..c.offset + c.model.dim()], zero),
            );
        }
        if self.equilibrium == Equilibrium::PaperModel {
            let scale = norm_inf(w).max(norm_inf(f)).max(1.0);
            if d.wrench_residual > 1e-9 * scale {
                out.warnings.push(format!(
                    "paper model: these torques do not balance the wrench, ‖G f − w‖∞ = {:.6e}; drop --paper-model for physically consistent torques",
                    d.wrench_residual
                ));
            }
        }
    }
}
