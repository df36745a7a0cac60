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
use grasp_core::conic::{CERTIFICATE_TOLERANCE, RAY_MARGIN};
use grasp_core::linalg::{decompose, RankThreshold};
use grasp_core::matrix::norm2;
use grasp_core::{
    Capabilities, ConeKind, ConicForm, Matrix, Reason, Solution, Status, TorqueQp, TorqueSolver,
    WarmStart,
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

/// The optimality certificate an answer Clarabel calls solved must pass (each measure
/// relative to its terms, [`ConicForm::certificate`]) to be `optimal`, else it is
/// `almost_optimal`: σ is then above the optimum by about the gap. At the default
/// settings every solved answer of 6 000 random grasps at 1 to 10 times normal friction
/// passes it; at 100 and 1 000 times, 2 % and 17 % do not.
pub const OPTIMALITY_TOLERANCE: f64 = 1e-8;

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

/// Clarabel's infeasibility tolerances (absolute and relative) for a second run, when
/// the first one's certificate of infeasibility does not verify: at its defaults (1e-8,
/// on its equilibrated problem) Clarabel can stop after a few iterations on a grasp the
/// inscribed polyhedra prove feasible, with multipliers whose torque terms are 1e-4 to
/// 1e-2 of their size ([`ConicForm::dual_ray`]'s measure).
const STRICT_INFEASIBILITY: f64 = 1e-13;

/// The Clarabel backend for one grasp.
pub struct ClarabelSolver {
    qp: TorqueQp,
    conic: ConicForm,
    settings: DefaultSettings<f64>,
    /// `settings` with [`STRICT_INFEASIBILITY`], swapped in for the second run.
    strict: DefaultSettings<f64>,
    /// Whether the last solve ran with `strict`: the next one starts a fresh solver
    /// with `settings`, as after any other solve that was not reused.
    strict_used: bool,
    p: CscMatrix<f64>,
    q: Vec<f64>,
    a: CscMatrix<f64>,
    b: Vec<f64>,
    cones: Vec<SupportedConeT<f64>>,
    solver: Option<DefaultSolver<f64>>,
    /// The polished answer ([`ClarabelSolver::polish`]) and the certificate's scratch.
    polished_x: Vec<f64>,
    polished_z: Vec<f64>,
    scratch: Vec<f64>,
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
        let mut strict = settings.clone();
        strict.tol_infeas_abs = STRICT_INFEASIBILITY;
        strict.tol_infeas_rel = STRICT_INFEASIBILITY;
        Ok(Self {
            settings,
            strict,
            strict_used: false,
            p,
            q: vec![0.0; nx],
            b: vec![0.0; conic.rows()],
            a,
            cones,
            solver: None,
            polished_x: Vec::new(),
            polished_z: Vec::new(),
            scratch: Vec::new(),
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

    /// The relaxed problem solved, then the full one where the relaxation's answer
    /// breaks a limit (see [`TorqueSolver::solve_raw`]); whether `b` is left relaxed.
    fn attempt(&mut self, w: &[f64; 6], alpha: f64) -> Result<bool, String> {
        let limits = self.conic.limit_rows.clone();
        let relaxed = self.b[limits.clone()].iter().any(|&v| v > FAR_LIMIT);
        if relaxed {
            self.b[limits]
                .iter_mut()
                .filter(|v| **v > FAR_LIMIT)
                .for_each(|v| *v = f64::INFINITY);
        }
        self.solve_b()?;
        if relaxed && !self.relaxation_holds(alpha) {
            self.conic.b_into(w, &mut self.b);
            self.solve_b()?;
        }
        Ok(relaxed)
    }

    fn claims_infeasibility(&self) -> bool {
        self.solver.as_ref().is_some_and(|s| {
            matches!(
                s.solution.status,
                SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible
            )
        })
    }

    /// The last run's multipliers checked from scratch as a ray of the dual of the
    /// problem in `self.b` ([`ConicForm::dual_ray`]), against `x_p = E⁺ b_E`, a point
    /// meeting the equalities (0 without them): the proof of infeasibility, or what
    /// falls short. A ray proves that no torque within `|value| / stationarity` times
    /// the problem's own scale holds the grasp; as the native check
    /// ([`CERTIFICATE_TOLERANCE`], value below −[`RAY_MARGIN`] times it) this one asks
    /// for a margin of [`RAY_MARGIN`] on that ratio, with the dual cones, `x_p` and the
    /// torque terms within this backend's accuracy, [`RESIDUAL_TOLERANCE`]. Where even
    /// `x_p`, the least-squares point, misses the equalities by that margin, they admit
    /// no torque at all: that is the proof.
    fn verified_ray(&mut self) -> Result<Reason, String> {
        let c = &self.conic;
        let z = match self.solver.as_ref() {
            Some(s) => s.solution.z.clone(),
            None => return Err("no multipliers".into()),
        };
        let eq = c.equalities();
        // The equalities' null space must be known to judge the torque terms.
        if c.eq_null_t.as_ref().is_some_and(|nt| nt.ncols() != c.nx) {
            return Err("the equalities could not be decomposed".into());
        }
        let mut xp = vec![0.0; c.nx];
        if eq > 0 {
            // E⁺ b_E, also where the equalities are dependent (consistent, as the
            // core's check before any backend ensures): the ray check measures how far
            // it misses them.
            let pinv = match &c.eq_pinv {
                Some(p) => p.clone(),
                None => {
                    let e = Matrix::from_fn(eq, c.nx, |i, j| c.a[(i, j)]);
                    decompose(&e, RankThreshold::Relative(1e-13))
                        .map_err(|e| format!("the equalities could not be decomposed: {e}"))?
                        .pseudo_inverse()
                }
            };
            for (i, x) in xp.iter_mut().enumerate() {
                *x = (0..eq).map(|k| pinv[(i, k)] * self.b[k]).sum();
            }
        }
        let tol = RESIDUAL_TOLERANCE;
        let ray = c.dual_ray(&self.b, &xp, &z, tol, &mut self.scratch);
        if ray.particular > RAY_MARGIN * tol {
            return Ok(Reason::Backend {
                backend: "clarabel",
                message: format!(
                    "no torque meets the equality rows (consistency, transmission): their least-squares point misses them by {:.1e} (relative)",
                    ray.particular
                ),
            });
        }
        // (Each free direction's terms against their own: `RayCheck::directions`.)
        let floor = RAY_MARGIN
            * ray
                .stationarity
                .max(ray.directions)
                .max(CERTIFICATE_TOLERANCE);
        if ray.dual <= tol && ray.particular <= tol && ray.stationarity <= tol && ray.value < -floor
        {
            Ok(Reason::DualRay {
                value: ray.value,
                stationarity: ray.stationarity,
            })
        } else {
            Err(format!(
                "torque terms left {:.1e} ({:.1e} in a free direction against its own), value {:.1e}, dual cones missed by {:.1e}, the equalities by {:.1e} (relative; a ray needs at most {tol:.0e} each and a value below −{floor:.1e})",
                ray.stationarity, ray.directions, ray.value, ray.dual, ray.particular
            ))
        }
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

    /// Polishes the last answer, as OSQP does: the equalities and the inequality rows
    /// it holds with equality (multiplier above slack) are solved as equalities, by
    /// least norm (the objective is ‖x‖²), with multipliers from stationarity,
    /// `2x = −A_Eᵀ z_E`. The point is kept, in `polished_x` and `polished_z`, only if the
    /// conic form's certificate passes from scratch: then it is the optimum to
    /// rounding, where the interior point stops at its tolerance. A row far steeper
    /// than the rest (a thin torsional cone, `mu_torsion` 1e-5 of the lever arms, or
    /// torque weights 1e8 apart) amplifies that tolerance past the core's check. (A
    /// stalled run is polished too: if its rows are right, the certificate says so.) A
    /// row whose multiplier comes out negative (weakly active: Clarabel's is near zero)
    /// leaves, and the rest are solved again, a few times at most. Linear rows without
    /// free internal forces only: a second-order cone's boundary is not a row, and free
    /// internal forces carry no curvature.
    fn polish(&mut self) -> bool {
        let c = &self.conic;
        let Some(sol) = self.solver.as_ref().map(|s| &s.solution) else {
            return false;
        };
        let eq = c.equalities();
        let finite = |v: &[f64]| v.iter().all(|v| v.is_finite());
        if c.free > 0
            || c.cones
                .iter()
                .any(|k| matches!(k, ConeKind::SecondOrder(_)))
            || sol.x.len() != c.nx
            || !(finite(&sol.x) && finite(&sol.z) && finite(&sol.s))
        {
            return false;
        }
        let (nx, rows) = (c.nx, c.rows());
        let mut held: Vec<bool> = (0..rows)
            .map(|i| i < eq || (sol.z[i] > sol.s[i] && self.b[i].is_finite()))
            .collect();
        let (x, z) = (&mut self.polished_x, &mut self.polished_z);
        for _ in 0..POLISH_ROUNDS {
            // The rows held, each normalised (which leaves the least-norm point and
            // the multipliers alone, and makes the rank decision unit-free); Clarabel's
            // multipliers scale with the norms.
            let (mut data, mut be, mut which) = (Vec::new(), Vec::new(), Vec::new());
            for i in (0..rows).filter(|&i| held[i]) {
                let row = c.a.row(i);
                let nrm = norm2(row);
                if nrm > 0.0 {
                    data.extend(row.iter().map(|v| v / nrm));
                    be.push(self.b[i] / nrm);
                    which.push((i, nrm, sol.z[i] * nrm));
                }
            }
            x.clear();
            x.resize(nx, 0.0);
            z.clear();
            z.resize(rows, 0.0);
            if !which.is_empty() {
                let ae = Matrix::from_rows_data(which.len(), nx, data);
                let Ok(dec) = decompose(&ae, RankThreshold::Relative(1e3 * f64::EPSILON)) else {
                    return false;
                };
                // x = A_E⁺ b_E, and Clarabel's multipliers moved least onto stationarity,
                // z_E − (A_E⁺)ᵀ (A_Eᵀ z_E + 2x): at a degenerate vertex (dependent rows)
                // the least-norm multipliers can be negative where Clarabel's are not.
                let pinv = dec.pseudo_inverse();
                for (j, xj) in x.iter_mut().enumerate() {
                    *xj = pinv.row(j).iter().zip(&be).map(|(p, b)| p * b).sum();
                }
                let mut res: Vec<f64> = x.iter().map(|v| 2.0 * v).collect();
                for (row, &(_, _, zr)) in ae.as_slice().chunks_exact(nx).zip(&which) {
                    for (r, a) in res.iter_mut().zip(row) {
                        *r += a * zr;
                    }
                }
                for (r, &(i, nrm, zr)) in which.iter().enumerate() {
                    let step: f64 = (0..nx).map(|j| pinv[(j, r)] * res[j]).sum();
                    z[i] = (zr - step) / nrm;
                }
            }
            if c.certificate(&self.b, x, z, CERTIFICATE_TOLERANCE, &mut self.scratch)
                .passed
            {
                return true;
            }
            let mut dropped = false;
            for i in eq..rows {
                if held[i] && z[i] < 0.0 {
                    held[i] = false;
                    dropped = true;
                }
            }
            if !dropped {
                return false;
            }
        }
        false
    }

    fn status(&self) -> SolverStatus {
        self.solver
            .as_ref()
            .map_or(SolverStatus::Unsolved, |s| s.solution.status)
    }
}

/// Most times [`ClarabelSolver::polish`] drops the rows whose multipliers come out
/// negative and solves again.
const POLISH_ROUNDS: usize = 3;

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
        if std::mem::take(&mut self.strict_used) {
            self.solver = None;
        }
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
        let mut relaxed = match self.attempt(w, alpha) {
            Ok(relaxed) => relaxed,
            Err(e) => {
                out.status = Status::NumericalFailure;
                out.reason = backend(e);
                return;
            }
        };
        // Clarabel's infeasibility is reported only with its multipliers checked from
        // scratch as a ray of the dual; otherwise it runs once more with strict
        // infeasibility tolerances, and an unproved claim is a numerical failure.
        let mut ray = None;
        if self.claims_infeasibility() {
            self.conic.b_into(w, &mut self.b);
            match self.verified_ray() {
                Ok(proof) => ray = Some(Ok(proof)),
                Err(why) => {
                    out.warnings.push(format!(
                        "Clarabel claimed infeasibility, but its multipliers do not prove it ({why}); it ran again with strict infeasibility tolerances"
                    ));
                    std::mem::swap(&mut self.settings, &mut self.strict);
                    self.solver = None;
                    self.strict_used = true;
                    let again = self.attempt(w, alpha);
                    std::mem::swap(&mut self.settings, &mut self.strict);
                    match again {
                        Ok(r) => relaxed = r,
                        Err(e) => {
                            out.status = Status::NumericalFailure;
                            out.reason = backend(e);
                            return;
                        }
                    }
                    if self.claims_infeasibility() {
                        self.conic.b_into(w, &mut self.b);
                        ray = Some(self.verified_ray());
                    }
                }
            }
        }
        let Some(solver) = self.solver.as_ref() else {
            return;
        };
        let sol = &solver.solution;
        out.iterations = sol.iterations as usize;
        let (mut status, mut reason) = match sol.status {
            SolverStatus::Solved => (Status::Optimal, None),
            SolverStatus::AlmostSolved => (Status::AlmostOptimal, None),
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => match ray {
                Some(Ok(proof)) => (Status::Infeasible, Some(proof)),
                why => (
                    Status::NumericalFailure,
                    backend(format!(
                        "Clarabel reported {:?}, but its multipliers do not prove it: {}",
                        sol.status,
                        why.and_then(Result::err).unwrap_or_default()
                    )),
                ),
            },
            SolverStatus::MaxIterations | SolverStatus::MaxTime => (
                Status::IterationLimit,
                backend(format!("stopped: {:?}", sol.status)),
            ),
            other => (
                Status::NumericalFailure,
                backend(format!("stopped: {other:?}")),
            ),
        };
        // Polished where Clarabel ran to an end with an answer, or stalled near one
        // (not where it proved infeasibility): against the limits as they are.
        let polished =
            status != Status::Infeasible && !matches!(sol.status, SolverStatus::Unsolved) && {
                if relaxed {
                    self.conic.b_into(w, &mut self.b);
                }
                self.polish()
            };
        if polished {
            (status, reason) = (Status::Optimal, None);
            out.method = Some("polished");
        } else if status == Status::Optimal {
            // "Solved" is Clarabel's own measure, in its equilibrated scaling: with
            // friction coefficients in the hundreds it stops with σ up to 1.6e-5 above
            // the optimum while its gap is within 1e-10. Its answer is checked against
            // the conic form's certificate at this backend's accuracy; short of it, the
            // answer is almost optimal, and says by how much.
            if let Some(sol) = self.solver.as_ref().map(|s| &s.solution) {
                let c = self.conic.certificate(
                    &self.b,
                    &sol.x,
                    &sol.z,
                    OPTIMALITY_TOLERANCE,
                    &mut self.scratch,
                );
                if !c.passed {
                    status = Status::AlmostOptimal;
                    out.warnings.push(format!(
                        "Clarabel's answer misses its optimality certificate (primal {:.1e}, dual {:.1e}, stationarity {:.1e}, gap {:.1e}; tolerance {OPTIMALITY_TOLERANCE:.0e}): σ may be above the optimum by about the gap, relative",
                        c.primal, c.dual, c.stationarity, c.gap
                    ));
                }
            }
        }
        out.status = status;
        out.reason = reason;
        if status.has_answer() {
            let Some(sol) = self.solver.as_ref().map(|s| &s.solution) else {
                return;
            };
            let (x, z) = if polished {
                (&self.polished_x, &self.polished_z)
            } else {
                (&sol.x, &sol.z)
            };
            self.conic
                .unscale_into(x, alpha, &mut out.torque, &mut out.internal_forces);
            if !self.qp.constraints.has_exact() {
                // μ_i = z_i ρ_i α κ for Σ w τ² on the rows H τ ≥ c.
                let (c, rows) = (&self.conic, self.qp.inequality_rows());
                out.multipliers.extend(
                    (0..rows).map(|i| z[c.linear_at + i] * c.row_scale[i] * alpha * c.kappa),
                );
            }
        }
    }
}
