//! Clarabel backend: the torque problem with any mix of exact cones (an SOCP) and
//! inscribed cones (linear rows), solved by Clarabel's interior-point method.
//!
//! The problem is the core's [`ConicForm`]: τ (and free internal forces and SFCl
//! auxiliaries) as variables, the exact cones as second-order cones, every row in
//! force units and the right-hand side normalised per solve, so that Clarabel's
//! absolute and relative tolerances mean the same in any units and at any load.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use grasp_core::{
    Capabilities, ConeKind, ConicForm, Reason, Solution, Status, TorqueQp, TorqueSolver, WarmStart,
};

/// What the Clarabel backend supports.
pub const CAPABILITIES: Capabilities = Capabilities {
    exact_cones: true,
    free_internal_forces: true,
    warm_key_set: false,
    warm_torque: false,
    certifies_rows: false,
};

/// Relative accuracy of Clarabel's answers at the default settings: the tolerance of
/// the core's final residual check.
pub const RESIDUAL_TOLERANCE: f64 = 1e-7;

/// Settings passed to Clarabel. The defaults reach 1e-8 relative accuracy in σ on the
/// reference cases. Tolerances apply to the scaled problem (see the crate docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClarabelSettings {
    /// Absolute duality-gap tolerance. Default 1e-10.
    pub tol_gap_abs: f64,
    /// Relative duality-gap tolerance. Default 1e-10.
    pub tol_gap_rel: f64,
    /// Feasibility tolerance. Default 1e-10.
    pub tol_feas: f64,
    /// Iteration cap. Default 200.
    pub max_iter: u32,
}

impl Default for ClarabelSettings {
    fn default() -> Self {
        Self {
            tol_gap_abs: 1e-10,
            tol_gap_rel: 1e-10,
            tol_feas: 1e-10,
            max_iter: 200,
        }
    }
}

/// Clarabel rejected the settings.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("Clarabel settings: {0}")]
pub struct ClarabelError(pub String);

impl ClarabelSettings {
    fn build(&self) -> Result<DefaultSettings<f64>, ClarabelError> {
        DefaultSettingsBuilder::default()
            .verbose(false)
            .tol_gap_abs(self.tol_gap_abs)
            .tol_gap_rel(self.tol_gap_rel)
            .tol_feas(self.tol_feas)
            .max_iter(self.max_iter)
            .build()
            .map_err(|e| ClarabelError(e.to_string()))
    }
}

/// The Clarabel backend for one grasp.
pub struct ClarabelSolver {
    qp: TorqueQp,
    conic: ConicForm,
    settings: DefaultSettings<f64>,
    p: CscMatrix<f64>,
    q: Vec<f64>,
    a: CscMatrix<f64>,
    b: Vec<f64>,
    cones: Vec<SupportedConeT<f64>>,
    solver: Option<DefaultSolver<f64>>,
}

impl ClarabelSolver {
    /// Assembles the conic problem of `qp` (exact blocks become second-order cones).
    pub fn new(qp: TorqueQp, settings: ClarabelSettings) -> Result<Self, ClarabelError> {
        let settings = settings.build()?;
        let conic = ConicForm::new(&qp);
        let (nx, m) = (conic.nx, conic.joints);
        let (mut ii, mut jj, mut vv) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..conic.rows() {
            for (j, &v) in conic.a.row(i).iter().enumerate() {
                if v != 0.0 {
                    ii.push(i);
                    jj.push(j);
                    vv.push(v);
                }
            }
        }
        let a = CscMatrix::new_from_triplets(conic.rows(), nx, ii, jj, vv);
        let cones = conic
            .cones
            .iter()
            .map(|c| match *c {
                ConeKind::Zero(d) => SupportedConeT::ZeroConeT(d),
                ConeKind::Nonnegative(d) => SupportedConeT::NonnegativeConeT(d),
                ConeKind::SecondOrder(d) => SupportedConeT::SecondOrderConeT(d),
            })
            .collect();
        // ½ xᵀ P x = ‖x_τ‖² = Σ w_j τ_j² / (α² κ).
        let p =
            CscMatrix::new_from_triplets(nx, nx, (0..m).collect(), (0..m).collect(), vec![2.0; m]);
        Ok(Self {
            settings,
            p,
            q: vec![0.0; nx],
            b: vec![0.0; conic.rows()],
            a,
            cones,
            solver: None,
            conic,
            qp,
        })
    }

    /// Whether any contact uses its exact cone.
    pub fn is_exact(&self) -> bool {
        self.qp.constraints.has_exact()
    }

    /// Solves the data in `self.b`, with the last solver where Clarabel allows it; a
    /// reused factorisation must not change the answer, so a failure is retried fresh.
    fn solve_b(&mut self) -> Result<(), String> {
        self.run(false)?;
        if !matches!(
            self.status(),
            SolverStatus::Solved
                | SolverStatus::PrimalInfeasible
                | SolverStatus::AlmostPrimalInfeasible
        ) {
            self.run(true)?;
        }
        Ok(())
    }

    /// Whether the last answer of a relaxed solve meets the torque limits' rows (their
    /// `b` is constant: `b0 / α`), or proved infeasibility.
    fn relaxation_holds(&self, alpha: f64) -> bool {
        let Some(solver) = self.solver.as_ref() else {
            return false;
        };
        let sol = &solver.solution;
        match sol.status {
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => true,
            SolverStatus::Solved | SolverStatus::AlmostSolved => {
                let (a, inv) = (&self.conic.a, 1.0 / alpha);
                self.conic.limit_rows.clone().all(|i| {
                    let ax: f64 = a.row(i).iter().zip(&sol.x).map(|(a, x)| a * x).sum();
                    ax <= self.conic.b0[i] * inv
                })
            }
            _ => false,
        }
    }

    /// Solves the data in `self.b` with a reused or fresh solver.
    fn run(&mut self, fresh: bool) -> Result<(), String> {
        let reused = !fresh
            && match self.solver.as_mut() {
                Some(s) if s.is_data_update_allowed() => s.update_b(&self.b).is_ok(),
                _ => false,
            };
        if !reused {
            let s = DefaultSolver::new(
                &self.p,
                &self.q,
                &self.a,
                &self.b,
                &self.cones,
                self.settings.clone(),
            )
            .map_err(|e| format!("Clarabel setup: {e}"))?;
            self.solver = Some(s);
        }
        if let Some(s) = self.solver.as_mut() {
            s.solve();
        }
        Ok(())
    }

    fn status(&self) -> SolverStatus {
        self.solver
            .as_ref()
            .map_or(SolverStatus::Unsolved, |s| s.solution.status)
    }
}

/// A torque limit's row whose scaled right-hand side exceeds this (the other rows'
/// are at most 1) is relaxed first ([`ClarabelSolver`]'s `solve_raw`).
const FAR_LIMIT: f64 = 1e6;

fn backend(message: String) -> Option<Reason> {
    Some(Reason::Backend {
        backend: "clarabel",
        message,
    })
}

impl TorqueSolver for ClarabelSolver {
    fn name(&self) -> &'static str {
        "clarabel"
    }

    fn capabilities(&self) -> Capabilities {
        CAPABILITIES
    }

    fn residual_tolerance(&self) -> f64 {
        RESIDUAL_TOLERANCE
    }

    fn problem(&self) -> &TorqueQp {
        &self.qp
    }

    fn solve_raw(&mut self, w: &[f64; 6], _warm: &WarmStart<'_>, out: &mut Solution) {
        let (m, d) = (self.conic.joints, self.conic.free);
        out.active_set = None;
        out.torque.clear();
        out.iterations = 0;
        let alpha = self.conic.b_into(w, &mut self.b);
        if alpha == 0.0 {
            // Every row is homogeneous: τ = 0 is feasible and optimal.
            out.status = Status::Optimal;
            out.torque.resize(m, 0.0);
            out.internal_forces.resize(d, 0.0);
            return;
        }
        // Torque limits far beyond the rest of the scaled problem (1e9 written for "no
        // limit") stall Clarabel's interior point. They are relaxed first (b = ∞, rows
        // its presolve drops), and that answer kept only if it meets them: the optimum
        // of a relaxation that is feasible is optimal, and a relaxation that is
        // infeasible proves the problem so. Otherwise the full problem is solved.
        let limits = self.conic.limit_rows.clone();
        let relaxed = self.b[limits.clone()].iter().any(|&v| v > FAR_LIMIT);
        if relaxed {
            self.b[limits.clone()]
                .iter_mut()
                .filter(|v| **v > FAR_LIMIT)
                .for_each(|v| *v = f64::INFINITY);
        }
        if let Err(e) = self.solve_b() {
            out.status = Status::NumericalFailure;
            out.reason = backend(e);
            return;
        }
        if relaxed && !self.relaxation_holds(alpha) {
            self.conic.b_into(w, &mut self.b);
            if let Err(e) = self.solve_b() {
                out.status = Status::NumericalFailure;
                out.reason = backend(e);
                return;
            }
        }
        let Some(solver) = self.solver.as_ref() else {
            return;
        };
        let sol = &solver.solution;
        out.iterations = sol.iterations as usize;
        let exact = self.qp.constraints.has_exact();
        let (status, reason) = match sol.status {
            SolverStatus::Solved => (Status::Optimal, None),
            SolverStatus::AlmostSolved => (Status::AlmostOptimal, None),
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => (
                Status::Infeasible,
                backend(format!(
                    "a certificate of primal infeasibility ({:?}): no torque keeps every contact force inside its {} cone while balancing the wrench",
                    sol.status,
                    if exact { "exact" } else { "linearised" }
                )),
            ),
            SolverStatus::MaxIterations | SolverStatus::MaxTime => (
                Status::IterationLimit,
                backend(format!("stopped: {:?}", sol.status)),
            ),
            other => (Status::NumericalFailure, backend(format!("stopped: {other:?}"))),
        };
        out.status = status;
        out.reason = reason;
        if status.has_answer() {
            self.conic
                .unscale_into(&sol.x, alpha, &mut out.torque, &mut out.internal_forces);
            if !exact {
                // μ_i = z_i ρ_i α κ for Σ w τ² on the rows H τ ≥ c.
                let (c, rows) = (&self.conic, self.qp.inequality_rows());
                out.multipliers.extend(
                    (0..rows).map(|i| sol.z[c.linear_at + i] * c.row_scale[i] * alpha * c.kappa),
                );
            }
        }
    }
}
