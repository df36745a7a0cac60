//! Native backend: the paper's primal "key constraint set" method (Jia et al.,
//! section 4.2, Steps 1–4), specialised to this problem's identity Hessian.
//!
//! # Reduction
//! With `u = D τ` (`D = diag(√w_j)`), the objective is `‖u‖²`. The consistency
//! equalities are eliminated with an orthonormal null-space basis: `u = u0 + N y`, `u0`
//! the minimum-norm particular solution, so `‖u‖² = ‖u0‖² + ‖y‖²` and the paper's
//! algorithm runs unchanged on `y` (a least-distance problem). Every inequality row is
//! normalised to unit length in `y`, so one tolerance fits rows of any scale
//! (soft-finger rows with `mu_torsion = 0.01` are 100× larger than force rows).
//!
//! # Feasible start (Step 1)
//! The start is `y0` (zero, or the warm torque, or the point of a warm key constraint
//! set). Rows it violates get an elastic variable `s ≥ 0` (`Ĥ_i y + s ≥ ĉ_i`) and the
//! objective a penalty `M s`. `(y0, max violation)` is then feasible, and the same
//! primal iteration drives `s` to zero: an exact penalty, raised ×1000 while `s` stays
//! positive. If `s` stays positive at the largest penalty the grasp is infeasible.
//! Every iterate satisfies every row; the answer is re-checked before it is returned.
//!
//! # Iteration (Steps 2–4)
//! The equality-constrained subproblem (eq. 44) is solved from a QR factorisation of
//! the key-set rows, updated with Givens rotations when a row joins (eq. 47) or leaves
//! (most negative multiplier, Step 4): O(k²) per iteration, no allocation.
//! Zero-length steps switch to Bland's rule, which rules out cycling.

use grasp_core::linalg::{decompose, orthonormal_columns, RankThreshold, ROW_SPREAD};
use grasp_core::matrix::{add_columns, dot, min_value, norm_inf, write_columns};
use grasp_core::solver::TORQUE_SPREAD_NOTE;
use grasp_core::{
    Capabilities, ConicForm, EqFactors, ForceSpaceQp, InequalityRows, LeastDistance, Matrix,
    Reason, RowId, Solution, Status, TorqueQp, TorqueSolver, WarmStart,
};
use std::sync::Arc;

mod dense;
mod exact;
mod factor;
mod hot;
mod ipm;
mod newton;
pub use exact::{ExactSolver, CERTIFICATE_TOLERANCE};
use factor::Factor;

/// The factor on [`ActiveSetSettings::feasibility_tolerance`] of a solve's first run.
pub const TIGHT: f64 = 1e-2;

/// A solve's runs ([`Engine::runs`]), in the order they are tried.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
enum Run {
    /// Rows hold to [`TIGHT`] times the feasibility tolerance.
    Tight,
    /// Rows hold to the feasibility tolerance.
    Loose,
    /// As `Loose`, with each row relaxed by `share` (at most 1) of the rounding it
    /// carries at `‖y‖ = size` ([`Engine::noise`]).
    Rounding { size: f64, share: f64 },
}

/// How a cold solve finds its first feasible point (Step 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Phase1 {
    /// The dual active-set method of Goldfarb and Idnani on the same factorisation: on
    /// this identity-Hessian problem its first feasible point is already optimal, so the
    /// paper's Steps 2–4 confirm it in one iteration. Fastest; the default.
    #[default]
    Dual,
    /// The paper's primal iteration from τ = the minimum-norm consistent torque, made
    /// feasible by one elastic variable with an exact penalty: the paper's algorithm
    /// from scratch, for studying it. Typically several times more iterations.
    Elastic,
}

/// Settings of the active-set method. Tolerances are relative to the problem's scale
/// (`max(‖ĉ‖∞, ‖y‖∞)`, in units of the weighted torque).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActiveSetSettings {
    /// Cold-start phase 1. Default [`Phase1::Dual`], which also hot-starts from a warm
    /// key set whose point the new wrench made infeasible; with [`Phase1::Elastic`] that
    /// case takes the elastic start. A feasible warm start goes straight to Steps 2–4.
    pub phase1: Phase1,
    /// Iteration cap (each iteration is one subproblem solve or one phase-1 step).
    /// Default 10 000.
    pub max_iterations: usize,
    /// A row holds when `Ĥ_i y − ĉ_i ≥ −feasibility_tolerance · scale`. Default 1e-9.
    /// A solve first iterates to [`TIGHT`] times it: a row is normalised by its norm,
    /// which a joint with short moment arms inflates through its huge column of H while
    /// its torque stays small, so that 1e-9 let a force miss its face by 19 N. Where
    /// that finds no optimum (on a grasp so ill-conditioned that rounding exceeds it, or
    /// an infeasibility proven only by a row within this tolerance), the solve runs
    /// again at this one; where a run proves infeasibility by less than the rounding
    /// its rows carry, again with each row relaxed by its rounding.
    pub feasibility_tolerance: f64,
    /// A multiplier counts as non-negative above `−multiplier_tolerance · scale`.
    /// Default 1e-10.
    pub multiplier_tolerance: f64,
    /// A row is linearly dependent on the key set when the part of it outside their span
    /// is below this, relative to its norm. Default 1e-10.
    pub dependence_tolerance: f64,
    /// First elastic penalty M, relative to the scale. Default 1e3.
    pub elastic_penalty: f64,
    /// Factor by which M grows while the elastic variable stays positive. Default 1000.
    pub penalty_growth: f64,
    /// Times M may grow before the grasp is declared infeasible. Default 4.
    pub penalty_increases: u32,
}

impl Default for ActiveSetSettings {
    fn default() -> Self {
        Self {
            phase1: Phase1::Dual,
            max_iterations: 10_000,
            feasibility_tolerance: 1e-9,
            multiplier_tolerance: 1e-10,
            dependence_tolerance: 1e-10,
            elastic_penalty: 1e3,
            penalty_growth: 1e3,
            penalty_increases: 4,
        }
    }
}

/// A setting out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("active-set setting {field}: expected {expected}")]
pub struct SettingsError {
    /// The setting.
    pub field: &'static str,
    /// Its valid range.
    pub expected: &'static str,
}

impl ActiveSetSettings {
    /// Checks every setting's range.
    pub fn validate(&self) -> Result<(), SettingsError> {
        let tol = |field, v: f64| {
            if v.is_finite() && v > 0.0 && v < 1.0 {
                Ok(())
            } else {
                Err(SettingsError {
                    field,
                    expected: "a number in (0, 1)",
                })
            }
        };
        if self.max_iterations == 0 {
            return Err(SettingsError {
                field: "max_iterations",
                expected: "at least 1",
            });
        }
        tol("feasibility_tolerance", self.feasibility_tolerance)?;
        tol("multiplier_tolerance", self.multiplier_tolerance)?;
        tol("dependence_tolerance", self.dependence_tolerance)?;
        if !(self.elastic_penalty.is_finite() && self.elastic_penalty > 0.0) {
            return Err(SettingsError {
                field: "elastic_penalty",
                expected: "a finite number > 0",
            });
        }
        if !(self.penalty_growth.is_finite() && self.penalty_growth > 1.0) {
            return Err(SettingsError {
                field: "penalty_growth",
                expected: "a finite number > 1",
            });
        }
        Ok(())
    }
}

/// Errors building the solver.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BuildError {
    /// Bad settings.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The null-space decomposition of the consistency equalities failed.
    #[error(transparent)]
    Svd(#[from] grasp_core::linalg::SvdError),
    /// The consistency equalities the core handed over are dependent in the weighted
    /// torque coordinates (torque weights too far apart).
    #[error("the consistency equalities are numerically dependent after weighting (rank {rank} of {rows}); bring the torque weights closer together")]
    DependentEqualities {
        /// The numerical rank of `C D⁻¹` (relative tolerance 1e-13).
        rank: usize,
        /// Its rows.
        rows: usize,
    },
}

/// What the native backend supports.
pub const CAPABILITIES: Capabilities = Capabilities {
    exact_cones: true,
    free_internal_forces: false,
    warm_key_set: true,
    warm_torque: true,
    certifies_rows: true,
};

/// Relative accuracy of the native backend's answers: the tolerance of the core's
/// final residual check. Its iterates satisfy rows to 1e-9 of the problem's scale in
/// normalised coordinates; the residuals of `G f = w` are at rounding level.
pub const RESIDUAL_TOLERANCE: f64 = 1e-8;

/// The largest bound on σ's excess over the optimum, relative, at which an
/// interior-point answer that fails its certificate only on the gap, or stopped short
/// with a gap that bounds σ no closer, is `almost_optimal`
/// ([`grasp_core::conic::Certificate::almost`]).
pub(crate) const ALMOST_EXCESS: f64 = 1e-6;

/// The warning of an `almost_optimal` answer: `what`'s bound on σ's excess.
pub(crate) fn almost_warning(what: &str, excess: f64) -> String {
    format!(
        "{what}'s certificate bounds σ only to {excess:.1e} above the optimum, relative (its gap; optimal answers are within 2e-9)"
    )
}

/// The share of the problem's scale beyond which a key set's point is rounding
/// ([`Engine::beyond_rounding`]).
const BEYOND_ROUNDING: f64 = 1e-2;

/// A key set whose multipliers cancel to one part in more than this
/// ([`Engine::amplification`]) amplifies the rows' rounding into σ beyond what
/// `optimal` claims: the solve looks again with the rows relaxed ([`Engine::relaxed`]).
const AMPLIFIED: f64 = 1e6;
/// Steps of [`Engine::refine`]: each shrinks the error by about the amplification
/// times ε, so two leave it at rounding below 1e10.
const REFINEMENTS: usize = 2;
/// [`Engine::refine`] steps only where the key rows' residuals are this many times
/// the rounding of their terms (`ROUNDING` times them), so that a step reduces the
/// error at least as many times.
const REFINABLE: f64 = 1e3;
/// The rounding of a row's value `c_i − H_i τ`, relative to its terms.
const ROUNDING: f64 = 16.0 * f64::EPSILON;
/// The relaxation of [`Engine::relaxed`], relative to the feasibility tolerance.
const RELAX: f64 = 0.1;
/// How much finer [`ActiveSetSolver::solve_fine_dependence`] takes the dependence
/// tolerance: 1e-13 by default, still 450 times ε.
const FINE_DEPENDENCE: f64 = 1e-3;

/// Whether the key set `rows` (reduced rows, with [`S_ROW`]) is `set` (rows of H,
/// sorted), `h_row` mapping one to the other.
fn is_set(rows: &[usize], h_row: &[usize], set: &[usize]) -> bool {
    let mut ours = rows.iter().filter(|&&r| r != S_ROW);
    ours.clone().count() == set.len() && ours.all(|&r| set.binary_search(&h_row[r]).is_ok())
}

/// The size of the terms of row `h`'s constant `c0_h − hw_h · w`.
fn constant_terms(ld: &LeastDistance<'_>, h: usize, w: &[f64; 6]) -> f64 {
    ld.c0_terms[h]
        + (ld.hw.row(h).iter().zip(w))
            .map(|(a, b)| (a * b).abs())
            .sum::<f64>()
}

/// Marker for the elastic bound `s ≥ 0` in the key set.
const S_ROW: usize = usize::MAX;

/// The native solver for one grasp. Build once, then solve for many wrenches.
#[derive(Clone, Debug)]
pub struct ActiveSetSolver {
    qp: TorqueQp,
    engine: Engine,
    /// The interior-point method on the same polyhedra, built at the first answer the
    /// core's check refuses ([`TorqueSolver::solve_fallback`]).
    fallback: Option<Box<Fallback>>,
    /// The same polyhedra with each joint's torque in a unit of its own, and the
    /// answer it writes, built at the first need
    /// ([`ActiveSetSolver::check_in_joint_units`]).
    units: Option<Box<(Option<ActiveSetSolver>, Solution)>>,
    /// Whether an `infeasible` answer is checked so: where the torques' scales are
    /// more than [`TORQUE_SPREAD_NOTE`] apart, and not in that view itself.
    unit_check: bool,
}

/// A proof of infeasibility the solver could not settle: `numerical_failure`, with
/// `message` as its reason, and the iterations of the run that made the proof.
#[cold]
fn unsettled(out: &mut Solution, message: String, iterations: usize) {
    out.status = Status::NumericalFailure;
    out.reason = Some(Reason::Backend {
        backend: "active-set",
        message,
    });
    out.recycle_active_set();
    out.torque.clear();
    out.iterations = iterations;
}

/// The interior-point method on the conic form of the linearised problem (its faces
/// as nonnegative rows), with its buffers.
#[derive(Clone, Debug)]
struct Fallback {
    conic: ConicForm,
    ipm: ipm::Ipm,
    b: Vec<f64>,
    /// A point meeting the equalities, `E⁺ b_E`, for a ray of the dual.
    xp: Vec<f64>,
    dual: Vec<f64>,
    scratch: Vec<f64>,
}

/// The native solver on the contact-force-space baseline ([`ForceSpaceQp`]): its
/// "torque" is the contact force f.
#[derive(Clone, Debug)]
pub struct ForceSpaceSolver {
    engine: Engine,
    fs: ForceSpaceQp,
}

/// The least-distance solver proper, on any [`LeastDistance`] data.
#[derive(Clone, Debug)]
struct Engine {
    /// Identity of each inequality row.
    rows: Vec<RowId>,
    /// Variables.
    m: usize,
    settings: ActiveSetSettings,
    /// `1/√w_j`.
    dinv: Vec<f64>,
    /// N, m × k: orthonormal null-space basis of `C D⁻¹`.
    null_basis: Matrix,
    /// N column-major (column l at `l·m..`), for `τ = D⁻¹(u0 + N y)` per solve.
    null_cols: Vec<f64>,
    /// `u0 = pu · w`, with pu (m × 6) column-major.
    pu_cols: Vec<f64>,
    /// Normalised rows `Ĥ`, R × k (R: rows of H that depend on τ).
    a: Matrix,
    /// `a` column-major (column j at `j·R..`): the passes over every row (residuals,
    /// right-hand side) run down columns, which vectorises where a row of k numbers
    /// does not.
    a_cols: Vec<f64>,
    /// Row r of `a` is row `h_row[r]` of H.
    h_row: Vec<usize>,
    /// Row of `a` for each row of H (`usize::MAX` for rows no torque affects).
    red_row: Vec<usize>,
    /// `‖(H D⁻¹ N)_i‖` of each reduced row.
    nu: Vec<f64>,
    /// The rounding each reduced row's value `a_r · y − b_r` carries, in units of ε:
    /// `‖(H D⁻¹)_i‖ / ν_r` per unit of y and of u0 (the row's entries before the
    /// null space cancelled them to `ν_r`: a joint with moment arms 1e-6 of the others'
    /// makes them 1e6 times larger), and the normalised size of the terms behind its
    /// constant. See [`Engine::noise`].
    noise: Vec<[f64; 2]>,
    /// `ĉ = c0n − mn · w`, with mn (R × 6) column-major like `a_cols`.
    c0n: Vec<f64>,
    /// The reduced rows before the torque limits' (the view's last rows): those whose
    /// right-hand sides set the tolerances' scale. A loose limit's constant side (1e6
    /// times the torques) made the tolerances loose enough to accept a cone row
    /// violated by 1e-2 before.
    scale_rows: usize,
    mn_cols: Vec<f64>,
    /// Rows of H that no torque affects: `c0 − m · w ≤ 0` must hold as it is.
    fixed: Vec<usize>,
    fixed_c0: Vec<f64>,
    /// The size of the terms behind each fixed row's constant, for its tolerance.
    fixed_c0_terms: Vec<f64>,
    fixed_m: Matrix,
    /// Per fixed row, whether its part in y is above the rounding of its own norm: set
    /// aside beside a far larger row (below the model's resolution of its own norm and
    /// the rounding of the largest row), it is still moved by the free torques, so
    /// its violation at y = 0 proves nothing; the core's check of the answer judges it.
    fixed_moved: Vec<bool>,
    /// The largest `|m_ij|` of any row (fixed or not) per wrench component `j`: a fixed
    /// row's value is judged against `Σ_j |m_ij w_j|` of these, in force units.
    wrench_terms: [f64; 6],
    ws: Workspace,
    /// The hot start's answer as affine maps of the wrench, for one key set.
    hot: hot::HotMap,
    /// The last amplified key set whose relaxation gave no better answer, as rows of H
    /// (sorted), and its wrench ([`Engine::relaxed`]).
    amplified: (Vec<usize>, [f64; 6]),
    /// Set when the last solve ended `infeasible` on a proof whose rows are
    /// independent beyond their rounding ([`Iter::local_proof`]): it rules out only
    /// the torques near its point, and the interior-point method may still find one
    /// ([`ActiveSetSolver::solve_raw`]).
    local_proof: bool,
}

#[derive(Clone, Debug)]
struct Workspace {
    b: Vec<f64>,
    e: Vec<f64>,
    resid: Vec<f64>,
    ad: Vec<f64>,
    in_set: Vec<bool>,
    z: Vec<f64>,
    zstar: Vec<f64>,
    d: Vec<f64>,
    u: Vec<f64>,
    /// Multipliers of the key set during the dual phase, in factor order.
    mult: Vec<f64>,
    factor: Factor,
    /// Whether every row in `factor` entered with no elastic term (its column does
    /// not depend on the wrench), and the last solve ended optimal there: a warm start
    /// with the same key set then keeps the factor (a hot start).
    reusable: bool,
}

impl ActiveSetSolver {
    /// Precomputes everything that depends only on the grasp. The problem must have
    /// only inscribed cones and fixed internal forces ([`CAPABILITIES`]).
    pub fn new(qp: TorqueQp, settings: ActiveSetSettings) -> Result<Self, BuildError> {
        let engine = Engine::new(&qp.least_distance(), settings)?;
        Ok(Self {
            qp,
            engine,
            fallback: None,
            units: None,
            unit_check: false,
        }
        .with_unit_check())
    }

    /// As [`Self::new`], with the equalities eliminated by `other` when `qp` has the
    /// same ones (the same C, `e(w)` and weights): another polyhedral view of its grasp.
    pub(crate) fn sharing(
        qp: TorqueQp,
        settings: ActiveSetSettings,
        other: &Self,
    ) -> Result<Self, BuildError> {
        settings.validate()?;
        let (ld, of) = (qp.least_distance(), other.qp.least_distance());
        let engine = if ld.eq == of.eq && ld.eq_w == of.eq_w && ld.weights == of.weights {
            let e = &other.engine;
            let eqs = Equalities {
                dinv: e.dinv.clone(),
                null_basis: e.null_basis.clone(),
                // (pu_cols holds −pu column-major: negation is exact.)
                pu: Matrix::from_fn(e.m, 6, |i, j| -e.pu_cols[j * e.m + i]),
            };
            Engine::with_equalities(&ld, settings, eqs)?
        } else {
            Engine::new(&ld, settings)?
        };
        Ok(Self {
            qp,
            engine,
            fallback: None,
            units: None,
            unit_check: false,
        }
        .with_unit_check())
    }

    /// As [`Self::new`] for a polyhedral view of the grasp of `form` (the exact view's
    /// conic form), with the equalities eliminated through the form's decomposition of
    /// them, which differs from C D⁻¹ᐟ² only by row and column scales (the same null
    /// space, and a pseudo-inverse rescaled). A form with free internal forces or
    /// dependent equalities leaves it to [`Self::new`].
    pub(crate) fn from_form(
        qp: TorqueQp,
        settings: ActiveSetSettings,
        form: &ConicForm,
    ) -> Result<Self, BuildError> {
        settings.validate()?;
        let ld = qp.least_distance();
        let p = ld.eq.nrows();
        let eqs = match (&form.eq_null_t, &form.eq_pinv) {
            (Some(nt), Some(pinv))
                if form.free == 0 && pinv.ncols() == p && form.torque_scale.is_normal() =>
            {
                // (1/√κ where κ is normal: the same k to the last bit as always.)
                // x = (k/α) D^½ τ on the torques (col_scale = k √w), so the form's
                // particular solution x_p = E⁺ bw_E w / α is u0 = E⁺ bw_E w / k, and
                // u0 = −pu w.
                let k = if form.kappa.is_normal() {
                    1.0 / form.kappa.sqrt()
                } else {
                    form.torque_scale
                };
                let mut pu = Matrix::zeros(form.joints, 6);
                for i in 0..form.joints {
                    let row = pu.row_mut(i);
                    for (e, b) in pinv.row(i).iter().zip(form.bw.as_slice().chunks_exact(6)) {
                        for (v, b) in row.iter_mut().zip(b) {
                            *v += e * b;
                        }
                    }
                    row.iter_mut().for_each(|v| *v = -*v / k);
                }
                Equalities {
                    dinv: ld.weights.iter().map(|w| 1.0 / w.sqrt()).collect(),
                    null_basis: nt.transpose(),
                    pu,
                }
            }
            _ => Equalities::new(&ld)?,
        };
        let engine = Engine::with_equalities(&ld, settings, eqs)?;
        Ok(Self {
            qp,
            engine,
            fallback: None,
            units: None,
            unit_check: false,
        }
        .with_unit_check())
    }

    /// With [`Self::check_in_joint_units`] where the torques' scales are more than
    /// [`TORQUE_SPREAD_NOTE`] apart.
    fn with_unit_check(mut self) -> Self {
        if let Some([(_, big), (_, small)]) = self.qp.model.torque_spread() {
            if big > TORQUE_SPREAD_NOTE * small {
                self.unit_check = true;
            }
        }
        self
    }

    /// The settings in use.
    pub fn settings(&self) -> &ActiveSetSettings {
        &self.engine.settings
    }

    /// Dimension k of the reduced space (joints minus independent consistency rows).
    pub fn reduced_dim(&self) -> usize {
        self.engine.null_basis.ncols()
    }

    /// The iteration again, cold, with [`ActiveSetSettings::dependence_tolerance`]
    /// [`FINE_DEPENDENCE`] times finer; true where it ends optimal and its answer
    /// passes the core's residual check, with a warning. A local proof's rows meet, if
    /// at all, far from its point (at `v / ‖ζ‖`), where the interior-point method may
    /// stall: on Table 1's carbon pen squeezed by forces of 3.5e9 N
    /// (`fixtures/fuzz/squeezed-by-torques-of-1e8.json`), feasible at N = 8, two faces
    /// and a limit 3.7e-11 from dependent (2 500 times their rounding, `v / ‖ζ‖` 2.5e8
    /// against an iterate of norm 0.02) proved N = 16 infeasible, and the method
    /// stalled after 10 iterations. Counted independent, the row joins and the
    /// iteration reaches the optimum. Rows counted independent that far can also give
    /// a point that misses a row (`fuzz_answers.py` seed 3238, which Clarabel and the
    /// exact cones' dual ray prove infeasible: σ 6e22, a row missed by 1.8e7 times its
    /// bound); the proof then stands.
    #[cold]
    fn solve_fine_dependence(&mut self, w: &[f64; 6], out: &mut Solution) -> bool {
        let (tol, warnings) = (
            self.engine.settings.dependence_tolerance,
            out.warnings.len(),
        );
        self.engine.settings.dependence_tolerance = tol * FINE_DEPENDENCE;
        let qp = &self.qp;
        self.engine
            .solve(|| qp.least_distance(), w, &WarmStart::default(), out);
        self.engine.settings.dependence_tolerance = tol;
        // (A hot start would keep a factor of rows that the usual tolerance calls
        // dependent.)
        self.engine.ws.reusable = false;
        if out.status == Status::Optimal {
            qp.complete(w, RESIDUAL_TOLERANCE, "active-set", out);
        }
        if out.status != Status::Optimal {
            out.warnings.truncate(warnings);
            out.torque.clear();
            return false;
        }
        out.warnings.push(format!(
            "active-set's proof of infeasibility held only near its own point (rows independent beyond their rounding); this answer is the iteration's with rows counted independent down to {:.0e} of their norm",
            tol * FINE_DEPENDENCE
        ));
        true
    }
}

impl ForceSpaceSolver {
    /// Precomputes everything that depends only on the grasp.
    pub fn new(fs: ForceSpaceQp, settings: ActiveSetSettings) -> Result<Self, BuildError> {
        let engine = Engine::new(&fs.least_distance(), settings)?;
        Ok(Self { engine, fs })
    }

    /// The optimal contact forces for `w` into `out.torque` (status, reason and
    /// iterations as for a torque solve; the other fields are left empty).
    pub fn solve(&mut self, w: &[f64; 6], out: &mut Solution) {
        out.reason = None;
        let residual = self.fs.unreachable_residual(w);
        if residual > 10.0 * self.fs.model.rank_tolerance * norm_inf(w).max(f64::MIN_POSITIVE) {
            out.status = Status::Infeasible;
            out.reason = Some(Reason::UnreachableWrench { residual });
            out.torque.clear();
            return;
        }
        let fs = &self.fs;
        self.engine
            .solve(|| fs.least_distance(), w, &WarmStart::default(), out);
    }

    /// The problem.
    pub fn problem(&self) -> &ForceSpaceQp {
        &self.fs
    }
}

/// The consistency equalities eliminated: everything of the engine that depends on C,
/// `e(w)` and the weights alone, not on the rows of H. Views of one grasp with other
/// polyhedra share it (the exact solver's inscribed and circumscribed ones).
#[derive(Clone, Debug)]
struct Equalities {
    dinv: Vec<f64>,
    null_basis: Matrix,
    /// `pu` (m × 6): `u0 = Cd⁺ e(w) = pu · w`.
    pu: Matrix,
}

/// Whether [`Equalities::from_factors`] costs fewer floating-point operations than the
/// decomposition of C, to leading order, for m torques and p equalities: its thin QR
/// of m × k (k = m − p; twice 2mk² − ⅔k³ with its Q) and three products with the
/// wrench's six columns, against the QR of C's p rows with its full m × m Q
/// (4m²p − 2mp² + 4p³/3) and the pseudo-inverse's products. With few equalities
/// (p < k, roughly) the decomposition is the cheaper.
fn factors_cheaper(m: usize, p: usize) -> bool {
    let (mf, pf, kf) = (m as f64, p as f64, m.saturating_sub(p) as f64);
    let factored = 4.0 * mf * kf * kf - 4.0 / 3.0 * kf.powi(3) + 6.0 * mf * (pf + 2.0 * kf);
    let decomposed =
        4.0 * mf * mf * pf - 2.0 * mf * pf * pf + 4.0 / 3.0 * pf.powi(3) + 6.0 * pf * (pf + mf);
    factored < decomposed
}

impl Equalities {
    fn new(qp: &LeastDistance<'_>) -> Result<Self, BuildError> {
        let cheaper = factors_cheaper(qp.weights.len(), qp.eq.nrows());
        // C D⁻¹ᐟ²'s columns spread as g does (below): a joint whose moment arms are 1e-8
        // of the others' has one 1e8 times theirs, and the decomposition's null basis
        // then carries an error of ε against rows of that joint 1e-8 of the rest. The
        // factors keep each row's digits (`orthonormal_columns`).
        let spread = |f: &EqFactors<'_>| {
            let (lo, hi) = qp
                .weights
                .iter()
                .zip(f.scale)
                .map(|(w, r)| w.sqrt() / r)
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), g| {
                    (lo.min(g), hi.max(g))
                });
            hi > ROW_SPREAD * lo
        };
        if let Some(eqs) = qp
            .eq_factors
            .filter(|f| cheaper || spread(f))
            .and_then(|f| Self::from_factors(qp, f))
        {
            return Ok(eqs);
        }
        let m = qp.weights.len();
        let dinv: Vec<f64> = qp.weights.iter().map(|w| 1.0 / w.sqrt()).collect();
        let cd = Matrix::from_fn(qp.eq.nrows(), m, |i, j| qp.eq[(i, j)] * dinv[j]);
        // The core decided the rank: every row of C is independent. Weighting must not
        // make them dependent.
        let rc = qp.eq.nrows();
        let dec = decompose(&cd, RankThreshold::Relative(1e-13))?;
        if dec.rank() < rc {
            return Err(BuildError::DependentEqualities {
                rank: dec.rank(),
                rows: rc,
            });
        }
        // u0 = Cd⁺ e = −row_basis (row_transform eq_w) w: the small product first.
        let pu = dec.row_basis.matmul(&dec.row_transform.matmul(qp.eq_w));
        let mut null_basis = dec.null_basis;
        // A joint the model found pinned (a zero row of its null basis) has a row of
        // rounding here: zero too, so that its torque limit is a fixed row.
        if let Some(f) = qp.eq_factors.filter(|f| f.null.nrows() == m) {
            for j in 0..m {
                if f.null.row(j).iter().all(|v| *v == 0.0) {
                    null_basis.row_mut(j).iter_mut().for_each(|v| *v = 0.0);
                }
            }
        }
        Ok(Self {
            dinv,
            null_basis,
            pu,
        })
    }

    /// The same from the model's factors `C = Bᵀ diag(r)` (no decomposition of C): in
    /// `u = D^½ τ`, `C D⁻¹ᐟ² u = 0 ⇔ u ∈ diag(g) range(N_B)` with `g = √w / r`, so N is
    /// an orthonormal basis of `diag(g) N_B` (a thin QR); and `u = diag(g) B v` solves
    /// `C D⁻¹ᐟ² u = v` (`BᵀB = I`), so the least-norm solution is that minus its part
    /// in N. `None` (the decomposition decides) without equalities, or when the
    /// weighting leaves `diag(g) N_B` near rank-deficient.
    fn from_factors(qp: &LeastDistance<'_>, f: EqFactors<'_>) -> Option<Self> {
        let (p, m) = (qp.eq.nrows(), qp.weights.len());
        if p == 0
            || f.basis.nrows() != m
            || f.basis.ncols() != p
            || f.null.nrows() != m
            || m.checked_sub(p) != Some(f.null.ncols())
            || f.scale.len() != m
            || qp.weights.len() != m
        {
            return None;
        }
        let g: Vec<f64> = qp
            .weights
            .iter()
            .zip(f.scale)
            .map(|(w, r)| w.sqrt() / r)
            .collect();
        let y = Matrix::from_fn(m, m - p, |i, j| g[i] * f.null[(i, j)]);
        let null_basis = orthonormal_columns(&y)?;
        // diag(g) B eq_w, then less N (Nᵀ ·): rows of six, as fixed arrays.
        let mut rows = vec![[0.0f64; 6]; m];
        for ((row, b), gi) in rows
            .iter_mut()
            .zip(f.basis.as_slice().chunks_exact(p))
            .zip(&g)
        {
            for (bl, e) in b.iter().zip(qp.eq_w.as_slice().chunks_exact(6)) {
                for (v, e) in row.iter_mut().zip(e) {
                    *v += bl * e;
                }
            }
            row.iter_mut().for_each(|v| *v *= gi);
        }
        let kk = m - p;
        let mut ntp = vec![[0.0f64; 6]; kk];
        for (n, row) in null_basis.as_slice().chunks_exact(kk.max(1)).zip(&rows) {
            for (t, nij) in ntp.iter_mut().zip(n) {
                for (t, v) in t.iter_mut().zip(row) {
                    *t += nij * v;
                }
            }
        }
        for (n, row) in null_basis
            .as_slice()
            .chunks_exact(kk.max(1))
            .zip(rows.iter_mut())
        {
            for (t, nij) in ntp.iter().zip(n) {
                for (v, t) in row.iter_mut().zip(t) {
                    *v -= nij * t;
                }
            }
        }
        let pu = Matrix::from_rows_data(m, 6, rows.concat());
        Some(Self {
            dinv: qp.weights.iter().map(|w| 1.0 / w.sqrt()).collect(),
            null_basis,
            pu,
        })
    }
}

impl Engine {
    fn new(qp: &LeastDistance<'_>, settings: ActiveSetSettings) -> Result<Self, BuildError> {
        settings.validate()?;
        Self::with_equalities(qp, settings, Equalities::new(qp)?)
    }

    fn with_equalities(
        qp: &LeastDistance<'_>,
        settings: ActiveSetSettings,
        eqs: Equalities,
    ) -> Result<Self, BuildError> {
        let m = qp.weights.len();
        let Equalities {
            dinv,
            null_basis,
            pu,
        } = eqs;
        let k = null_basis.ncols();
        let mut null_cols = vec![0.0; m * k];
        write_columns(&null_basis, &mut null_cols, m);
        let mut pu_cols = vec![0.0; m * 6];
        write_columns(&pu, &mut pu_cols, m);
        pu_cols.iter_mut().for_each(|v| *v = -*v);
        // One product for both: H D⁻¹ [N | −pu], with D⁻¹ folded into the short side.
        let mut np = Matrix::zeros(m, k + 6);
        for (i, row) in np.as_mut_slice().chunks_exact_mut(k + 6).enumerate() {
            let di = dinv[i];
            for (x, v) in row[..k].iter_mut().zip(null_basis.row(i)) {
                *x = di * v;
            }
            for (x, v) in row[k..].iter_mut().zip(pu.row(i)) {
                *x = di * -v;
            }
        }
        let hnp = qp.h_mul(&np);
        let rows = qp.rows.len();
        // ĉ(w) = c0 − (hw + Hd pu) w, before normalisation: row i's wrench terms.
        let mfull = |i: usize| -> [f64; 6] {
            let mut out = [0.0; 6];
            for ((o, h), v) in out.iter_mut().zip(qp.hw.row(i)).zip(&hnp.row(i)[k..]) {
                *o = h + v;
            }
            out
        };
        // A row no torque affects: its norm in y is at rounding level of H D⁻¹'s. A
        // torque limit's row is judged at its own rounding level, whatever the cone
        // rows' scale (forces in units 1e150 times smaller make those 1e150 times
        // longer; the limit is as binding): on torques (H factored) the row is τ_j
        // itself, whose norm in y is dinv_j; on contact forces (the force-space QP,
        // H formed) it is `Jᵀ_j f`, of norm ‖H_i D⁻¹‖.
        let mut own = Vec::new();
        let hscale = qp.row_norms(&dinv, &mut own);
        let rounding = 1e3 * f64::EPSILON * (m as f64);
        let zero = rounding * hscale.max(f64::MIN_POSITIVE);
        // A cone row is also judged against its own norm, at the model's resolution
        // (its default rank tolerance, 1e-9): where one joint's force response is 1e8
        // times the others' (a tiny row of Jᵀ), the largest row is that joint's, whose
        // torque the equalities pin, and a row whose part in y is 8e-8 of its own norm
        // fell below the first bound (fuzz seed 34182: infeasible, where cvxpy finds
        // σ* = 1.55). Only a row below both is one no torque affects. (Against its own
        // norm at rounding level instead, a tendon hand's row of part 6e-12, the
        // model's conditioning, was kept and broke the solve.)
        let resolution = grasp_core::ModelOptions::default()
            .rank_tolerance
            .max(rounding);
        let zero_of = |i: usize| match (qp.rows[i], qp.h) {
            (RowId::TorqueLimit { joint, .. }, InequalityRows::Factored(_)) => {
                rounding * dinv[joint]
            }
            (RowId::TorqueLimit { .. }, _) => rounding * own[i],
            _ => zero.min(resolution * own[i]),
        };
        let (mut h_row, mut fixed, mut fixed_moved) =
            (Vec::with_capacity(rows), Vec::new(), Vec::new());
        let mut nu = Vec::with_capacity(rows);
        let mut red_row = vec![usize::MAX; rows];
        // A fixed row whose wrench terms are themselves rounding (a contact that neither
        // torque nor wrench loads, as an unactuated joint can leave one) is judged
        // against the wrench's largest terms in any row.
        let mut wrench_terms = [0.0f64; 6];
        for i in 0..rows {
            let nrm = grasp_core::matrix::norm2(&hnp.row(i)[..k]);
            if nrm > zero_of(i) {
                red_row[i] = h_row.len();
                h_row.push(i);
                nu.push(nrm);
            } else {
                fixed.push(i);
                fixed_moved.push(nrm > rounding * own[i]);
            }
            for (t, v) in wrench_terms.iter_mut().zip(mfull(i)) {
                *t = t.max(v.abs());
            }
        }
        // The reduced rows, normalised: row-major in `a`, column-major in `a_cols` and
        // `mn_cols`.
        let nr = h_row.len();
        let mut a = Matrix::zeros(nr, k);
        let mut a_cols = vec![0.0; nr * k];
        let mut mn_cols = vec![0.0; nr * 6];
        let mut c0n = Vec::with_capacity(nr);
        let mut noise = Vec::with_capacity(nr);
        // (By the reciprocal: a division per row, not per entry, which was a tenth of
        // the build. Each entry moves by an ulp at most. A kept row's norm is above
        // 1e-13 of the largest, which is at least about 1e-12 wherever Jᵀ's entries
        // are within the input domain's 1e12 (H ~ 1/Jᵀ): its reciprocal is finite.)
        for (r, (&i, &nrm)) in h_row.iter().zip(&nu).enumerate() {
            let inv = 1.0 / nrm;
            for (x, v) in a.row_mut(r).iter_mut().zip(&hnp.row(i)[..k]) {
                *x = v * inv;
            }
            for (j, v) in mfull(i).iter().enumerate() {
                mn_cols[j * nr + r] = v * inv;
            }
            c0n.push(qp.c0[i] * inv);
            noise.push([own[i] * inv, qp.c0_terms[i] * inv]);
        }
        write_columns(&a, &mut a_cols, nr);
        let fixed_c0 = fixed.iter().map(|&i| qp.c0[i]).collect();
        let fixed_c0_terms = fixed.iter().map(|&i| qp.c0_terms[i]).collect();
        let mut fixed_m = Matrix::zeros(fixed.len(), 6);
        for (r, &i) in fixed.iter().enumerate() {
            fixed_m.row_mut(r).copy_from_slice(&mfull(i));
        }
        let kp = k + 1;
        let ws = Workspace {
            b: vec![0.0; nr],
            e: vec![0.0; nr],
            resid: vec![0.0; nr],
            ad: vec![0.0; nr],
            in_set: vec![false; nr],
            z: vec![0.0; kp],
            zstar: vec![0.0; kp],
            d: vec![0.0; kp],
            u: vec![0.0; m],
            mult: Vec::with_capacity(kp),
            factor: Factor::new(kp),
            reusable: false,
        };
        let scale_rows = h_row
            .iter()
            .take_while(|&&i| !matches!(qp.rows[i], RowId::TorqueLimit { .. }))
            .count();
        Ok(Self {
            scale_rows,
            rows: qp.rows.to_vec(),
            m,
            settings,
            dinv,
            null_basis,
            null_cols,
            pu_cols,
            a,
            a_cols,
            h_row,
            red_row,
            nu,
            noise,
            c0n,
            mn_cols,
            fixed,
            fixed_c0,
            fixed_c0_terms,
            fixed_m,
            fixed_moved,
            wrench_terms,
            ws,
            hot: hot::HotMap::new(k, nr, m),
            amplified: (Vec::new(), [f64::NAN; 6]),
            local_proof: false,
        })
    }
}

/// What the iteration ended with.
enum End {
    Optimal,
    /// Out of iterations; whether the last iterate satisfies every row.
    IterationLimit(bool),
    /// With the row the dual phase could not satisfy, or `None` after the elastic phase.
    Infeasible(Option<usize>),
    Numerical(&'static str),
}

impl TorqueSolver for ActiveSetSolver {
    fn name(&self) -> &'static str {
        "active-set"
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

    fn solve_raw(&mut self, w: &[f64; 6], warm: &WarmStart<'_>, out: &mut Solution) {
        let qp = &self.qp;
        self.engine.solve(|| qp.least_distance(), w, warm, out);
        // A warm start may make a solve slower, never wrong: retry a failure cold.
        if !warm.is_cold() && !matches!(out.status, Status::Optimal | Status::Infeasible) {
            let iterations = out.iterations;
            self.engine
                .solve(|| qp.least_distance(), w, &WarmStart::default(), out);
            out.iterations += iterations;
        }
        // A proof that rules out only the torques near its point: the interior-point
        // method, which follows no key set, answers where it certifies an optimum;
        // else the iteration again with rows counted independent down to a finer
        // tolerance, where its optimum holds; else the method's multipliers, where
        // they grew along a ray of the dual, prove the grasp infeasible. (A ray proves
        // it only for the torques within its horizon: one of value −1 called
        // `squeezed-by-torques-of-1e8.json` infeasible at N = 16, where the finer
        // iteration holds it.) Failing all three, the proof is no answer:
        // `fuzz_answers.py` seed 319014, held only by torques of 3e10 where two nearly
        // opposite faces meet, was `infeasible` by such a proof in the systems of
        // units where the method stalled.
        if out.status == Status::Infeasible && self.engine.local_proof {
            let (reason, iterations) = (out.reason.take(), out.iterations);
            let warnings = out.warnings.len();
            let ray = match self.interior_point(w, true, out) {
                Ok(()) if out.status == Status::Optimal => {
                    out.iterations += iterations;
                    out.warnings.push(
                        "active-set's proof of infeasibility held only near its own point \
                         (rows independent beyond their rounding); this answer is its \
                         interior-point method's"
                            .into(),
                    );
                    return;
                }
                Ok(()) => {
                    out.warnings.truncate(warnings);
                    None
                }
                Err(ray) => ray,
            };
            let ipm_iterations = self.fallback.as_ref().map_or(0, |f| f.ipm.iterations);
            if self.solve_fine_dependence(w, out) {
                out.iterations += iterations;
            } else if let Some(ray) = ray {
                out.status = Status::Infeasible;
                out.reason = Some(ray);
                out.recycle_active_set();
                out.torque.clear();
                out.iterations = iterations + ipm_iterations;
                out.method = Some("interior_point");
            } else {
                let message = format!(
                    "a proof of infeasibility that holds only near its own point (rows independent beyond their rounding: {}), which neither the interior-point method (no optimum, no ray of the dual) nor the iteration with rows counted independent down to {:.0e} of their norm settled",
                    reason.map_or_else(String::new, |r| r.to_string()),
                    self.engine.settings.dependence_tolerance * FINE_DEPENDENCE,
                );
                unsettled(out, message, iterations);
            }
        }
        if out.status == Status::Infeasible && self.unit_check {
            self.check_in_joint_units(w, out);
        }
    }

    /// The interior-point method on the same polyhedra, its iterate certified from
    /// scratch ([`ConicForm::certificate`]). `false` where it does not converge to a
    /// certified answer (it proves no infeasibility).
    fn solve_fallback(&mut self, w: &[f64; 6], out: &mut Solution) -> bool {
        self.interior_point(w, false, out).is_ok()
    }
}

impl ActiveSetSolver {
    /// An `infeasible` answer checked with each joint's torque in a unit of its own
    /// ([`grasp_core::GraspModel::equilibrated`]: the same polyhedra, only the
    /// objective's weights changed). Where the torques' scales are far apart, the
    /// smaller torques' entries in a row are below its rounding, and a proof their
    /// rounding made can be false: `fuzz_answers.py` seed 297974 (scales 1.3e15 apart)
    /// was `infeasible` at N = 4 and 8, and with exact cones by the circumscribed
    /// polyhedra, where the same grasp with each row of Jᵀ of norm 1 is optimal for
    /// both backends. Where this view holds the grasp, the answer is the
    /// interior-point method's if it certifies one (the method is invariant to the
    /// torques' units), else `numerical_failure`.
    #[cold]
    fn check_in_joint_units(&mut self, w: &[f64; 6], out: &mut Solution) {
        let mut units = self.units.take().unwrap_or_default();
        let (view, answer) = &mut *units;
        if view.is_none() {
            let model = Arc::new(self.qp.model.equilibrated());
            let qp = TorqueQp::new(model, self.qp.constraints.clone());
            *view = Self::new(qp, self.engine.settings).ok().map(|mut v| {
                v.unit_check = false;
                v
            });
        }
        let held = view.as_mut().is_some_and(|v| {
            v.solve_raw(w, &WarmStart::default(), answer);
            answer.status == Status::Optimal
        });
        self.units = Some(units);
        if !held {
            return;
        }
        let (reason, iterations) = (out.reason.take(), out.iterations);
        let spread = self
            .qp
            .model
            .torque_spread()
            .map_or(0.0, |[(_, big), (_, small)]| big / small);
        let warnings = out.warnings.len();
        if self.interior_point(w, false, out).is_ok() {
            out.iterations += iterations;
            out.warnings.push(format!(
                "active-set proved this grasp infeasible with the torques' scales {spread:.1e} apart, and with each joint's torque in a unit of its own found it feasible; this answer is its interior-point method's"
            ));
            return;
        }
        out.warnings.truncate(warnings);
        let message = format!(
            "a proof of infeasibility ({}) that rounding made: with each joint's torque in a unit of its own (the torques' scales are {spread:.1e} apart) the grasp is feasible, and the interior-point method certified no optimum",
            reason.map_or_else(String::new, |r| r.to_string()),
        );
        unsettled(out, message, iterations);
        out.method = None;
    }

    /// [`TorqueSolver::solve_fallback`]: `Ok` where it fills `out` with a certified
    /// answer; else `Err`, with `rays` the first ray of the dual its multipliers grew
    /// along, if any ([`ConicForm::dual_ray`], checked at each iterate from the
    /// equalities' point `E⁺ b_E`, as the exact cones' method proves infeasibility).
    fn interior_point(
        &mut self,
        w: &[f64; 6],
        rays: bool,
        out: &mut Solution,
    ) -> Result<(), Option<Reason>> {
        let qp = &self.qp;
        let f = self.fallback.get_or_insert_with(|| {
            let conic = ConicForm::new(qp);
            let ipm = ipm::Ipm::new(&conic, ipm::IpmSettings::default());
            let rows = conic.rows();
            Box::new(Fallback {
                xp: vec![0.0; conic.nx],
                conic,
                ipm,
                b: vec![0.0; rows],
                dual: vec![0.0; rows],
                scratch: Vec::new(),
            })
        });
        let alpha = f.conic.b_into(w, &mut f.b);
        if alpha == 0.0 {
            return Err(None);
        }
        let eq = f.conic.equalities();
        let rays = rays
            && match &f.conic.eq_pinv {
                Some(pinv) => {
                    for (j, x) in f.xp.iter_mut().enumerate() {
                        *x = dot(&pinv.row(j)[..eq], &f.b[..eq]);
                    }
                    true
                }
                None => eq == 0,
            };
        let mut ray = None;
        let (conic, b, xp) = (&f.conic, &f.b, &f.xp);
        let (dual, scratch) = (&mut f.dual, &mut f.scratch);
        // (The run goes on past a ray: an optimum further on is the answer.)
        let end = f.ipm.solve(conic, b, &mut |ipm| {
            if rays && ray.is_none() {
                ipm.dual_into(conic, dual);
                let r = conic.dual_ray(b, xp, dual, CERTIFICATE_TOLERANCE, scratch);
                ray = r.passed.then_some(Reason::DualRay {
                    value: r.value,
                    stationarity: r.stationarity,
                });
            }
            false
        });
        if !matches!(end, ipm::IpmEnd::Converged) {
            if !f.ipm.best_merit.is_finite() {
                return Err(ray);
            }
            f.ipm.restore_best();
        }
        let nx = f.conic.nx;
        f.ipm.dual_into(&f.conic, &mut f.dual);
        let c = f.conic.certificate(
            &f.b,
            &f.ipm.x[..nx],
            &f.dual,
            CERTIFICATE_TOLERANCE,
            &mut f.scratch,
        );
        // An iterate the method stopped short at is `optimal` only where the gap alone
        // bounds σ (as the exact cones' best iterate, `ExactSolver::finish_from_best`).
        let stopped = !matches!(end, ipm::IpmEnd::Converged);
        out.status = if c.passed && (!stopped || c.bounds_sigma(CERTIFICATE_TOLERANCE)) {
            Status::Optimal
        } else if c.almost(CERTIFICATE_TOLERANCE, ALMOST_EXCESS)
            && f.ipm.x[..nx].iter().all(|v| v.is_finite())
        {
            out.warnings
                .push(almost_warning("the interior-point answer", c.excess));
            Status::AlmostOptimal
        } else {
            return Err(ray);
        };
        out.reason = None;
        out.recycle_active_set();
        out.iterations = f.ipm.iterations;
        out.method = Some("interior_point");
        f.conic.unscale_into(
            &f.ipm.x[..nx],
            alpha,
            &mut out.torque,
            &mut out.internal_forces,
        );
        Ok(())
    }
}

impl Engine {
    /// `ld` gives the problem's rows, for the refinement of an amplified key set.
    fn solve<'q>(
        &mut self,
        ld: impl FnOnce() -> LeastDistance<'q>,
        w: &[f64; 6],
        warm: &WarmStart<'_>,
        out: &mut Solution,
    ) {
        out.torque.clear();
        out.iterations = 0;
        // (A reason's buffers are kept for the next: an infeasible control loop's.)
        out.recycle_reason();
        self.local_proof = false;
        out.cleared_active_set();
        // Rows that no torque affects must hold for the wrench alone (a row the free
        // torques still move, set aside beside a far larger one, is left to the core's
        // check of the answer: `fuzz_answers.py nested` seed 48783, a face whose part in
        // y was 26 beside rows of 1e13, called the grasp infeasible by 2.1 at N = 16
        // where the answer at N = 8 holds it).
        for (r, &row) in self.fixed.iter().enumerate() {
            let c = self.fixed_c0[r] - dot(self.fixed_m.row(r), w);
            // Relative to the row's own terms and to the wrench's largest terms in any
            // row, both forces: the same in any units. The row's value is the difference
            // of terms that cancel, whose rounding the conditioning of the consistency
            // rows amplifies: a contact the wrench leaves unloaded came out at 1e-12 of
            // the wrench below its cone, judged infeasible in one system of units only,
            // where the floor was ‖w‖∞ times the largest row's terms.
            let size = |m: &[f64]| m.iter().zip(w).map(|(a, b)| (a * b).abs()).sum::<f64>();
            // The constant's own terms, not its value: the passive torques' force on a
            // contact they leave unloaded cancels to rounding of terms of 1 N.
            let scale =
                self.fixed_c0_terms[r] + size(self.fixed_m.row(r)) + size(&self.wrench_terms);
            if c > self.settings.feasibility_tolerance * scale && !self.fixed_moved[r] {
                out.status = Status::Infeasible;
                out.reason = Some(Reason::FixedRowViolated {
                    row: self.rows[row],
                    violation: c,
                });
                out.recycle_active_set();
                return;
            }
        }
        let ws = &mut self.ws;
        let k = self.null_basis.ncols();
        // A hot start keeps the factor of the last key set when the warm one is that
        // set: the rows do not depend on the wrench, only b does.
        let hot = ws.reusable
            && warm.active_set.is_some_and(|set| {
                set.len() + 1 == ws.factor.rows().len()
                    && set.iter().all(|&h| {
                        let r = self.red_row[h];
                        r != usize::MAX && ws.in_set[r]
                    })
            });
        if hot && self.solve_mapped(w, out) {
            return;
        }
        let (end, iterations) = self.runs(w, warm, hot, 0.0);
        self.ws.reusable &= matches!(end, End::Optimal) && self.ws.factor.contains(S_ROW);
        self.note_hot_start(hot && matches!(end, End::Optimal) && iterations == 0);
        out.iterations = iterations;
        let end = match end {
            End::Optimal if self.beyond_rounding() => {
                self.ws.reusable = false;
                End::Numerical(
                    "the key set's rows meet only at torques whose rounding exceeds 1 % of the largest row constant: the answer there is rounding, not a grasp",
                )
            }
            end => end,
        };
        match end {
            End::Optimal => {
                self.write_solution(out);
                out.status = Status::Optimal;
                let a = self.amplification();
                if a > AMPLIFIED {
                    let ld = ld();
                    self.refine(&ld, w, out);
                    if self.is_amplified_set(w) || !self.relaxed(w, a, out) {
                        self.warn_rounding_spread(&ld, w, a, out);
                    }
                }
            }
            End::IterationLimit(feasible) => {
                // Hand the last iterate back only when it satisfies every row.
                if feasible {
                    self.write_solution(out);
                } else {
                    out.recycle_active_set();
                }
                out.status = Status::IterationLimit;
                out.reason = Some(Reason::Backend {
                    backend: "active-set",
                    message: format!(
                        "stopped after {iterations} iterations (max_iterations = {})",
                        self.settings.max_iterations
                    ),
                });
            }
            End::Infeasible(row) => {
                out.status = Status::Infeasible;
                let mut blocking = out.recycled_rows();
                self.blocking_into(&mut blocking);
                let relaxation = match row {
                    Some(r) => {
                        blocking.push(self.rows[self.h_row[r]]);
                        None
                    }
                    None => Some(self.ws.z[k]),
                };
                out.reason = Some(Reason::NoAdmissibleTorque {
                    relaxation,
                    blocking,
                });
                out.recycle_active_set();
            }
            End::Numerical(why) => {
                out.status = Status::NumericalFailure;
                out.reason = Some(Reason::Backend {
                    backend: "active-set",
                    message: why.to_string(),
                });
                out.recycle_active_set();
            }
        }
    }
}

impl Engine {
    /// The solve's runs from `warm` ([`Self::solve`]), every row relaxed by `relax`:
    /// first to TIGHT times the feasibility tolerance; again at the tolerance itself
    /// where that run finds no optimum and a looser one might (ActiveSetSettings); and
    /// again with every row relaxed by the rounding it carries ([`Self::noise`]) where
    /// a run proved infeasibility only by a violation within its rows' rounding.
    /// Returns how they ended and the iterations of all.
    fn runs(&mut self, w: &[f64; 6], warm: &WarmStart<'_>, hot: bool, relax: f64) -> (End, usize) {
        let (mut next, mut first, mut iterations) = (Some(Run::Tight), true, 0);
        let mut end = End::Numerical("no run");
        while let Some(run) = next.take() {
            self.set_rows(w, relax, run);
            // Starting point y0.
            let ws = &mut self.ws;
            ws.z.iter_mut().for_each(|v| *v = 0.0);
            ws.e.iter_mut().for_each(|v| *v = 0.0);
            if !hot || !first {
                ws.in_set.iter_mut().for_each(|v| *v = false);
                ws.factor.clear();
            }
            ws.reusable = true;
            let tight = run == Run::Tight;
            let mut state = Iter::new(self, tight, w);
            // The iteration cap is on all runs together.
            state.iterations = iterations;
            end = state.run(warm);
            iterations = state.iterations;
            let local = state.local_proof;
            next = match end {
                End::Optimal | End::IterationLimit(_) => None,
                End::Infeasible(_) if !matches!(run, Run::Rounding { .. }) => {
                    state.undecided.filter(|n| *n > run)
                }
                End::Infeasible(_) => None,
                End::Numerical(_) => tight.then_some(Run::Loose),
            };
            self.local_proof = local && matches!(end, End::Infeasible(_));
            first = false;
            if let (End::Optimal, Run::Rounding { .. }) = (&end, run) {
                // The key set on the rows as given, where its point holds them (σ
                // within the tolerance, not the relaxation, of the optimum).
                self.set_rows(w, relax, Run::Loose);
                if !matches!(Iter::new(self, false, w).finish(), End::Optimal) {
                    self.set_rows(w, relax, run);
                    Iter::new(self, false, w).finish();
                }
            }
        }
        (end, iterations)
    }

    /// `b` and `u0` for a run of [`Self::runs`] at `w`, every row relaxed by `relax`
    /// and, in a [`Run::Rounding`], by its rounding.
    fn set_rows(&mut self, w: &[f64; 6], relax: f64, run: Run) {
        self.set_b(w);
        let ws = &mut self.ws;
        if relax > 0.0 {
            ws.b.iter_mut().for_each(|v| *v -= relax);
        }
        ws.u.iter_mut().for_each(|v| *v = 0.0);
        add_columns(&mut ws.u, &self.pu_cols, w, 1.0);
        if let Run::Rounding { size, share } = run {
            let u0 = grasp_core::matrix::norm2(&self.ws.u);
            for r in 0..self.ws.b.len() {
                self.ws.b[r] -= share * self.noise(r, w, size + u0);
            }
        }
    }

    /// The rounding that row `r`'s value `a_r · y − b_r` carries at `‖y‖ + ‖u0‖ =
    /// size`: the bound `m ε` on a product of `m` terms (Higham, "Accuracy and Stability
    /// of Numerical Algorithms", §3.1) times those behind its entries and constant,
    /// `H D⁻¹`'s, `c0`'s and the wrench maps', which the null space and the passive
    /// torques cancel. (Ten times it undid a proof that the exact cones and cvxpy
    /// confirm, `fuzz_answers.py` seed 34939, docs/solver.md §4.)
    fn noise(&self, r: usize, w: &[f64; 6], size: f64) -> f64 {
        let nr = self.nu.len();
        let wrench: f64 = (0..6)
            .map(|j| (self.mn_cols[j * nr + r] * w[j]).abs())
            .sum();
        let [per_y, c0] = self.noise[r];
        let terms = per_y * size + c0 + wrench;
        self.m as f64 * f64::EPSILON * terms
    }

    /// `b = ĉ(w)`, the rows' right-hand side.
    fn set_b(&mut self, w: &[f64; 6]) {
        let ws = &mut self.ws;
        ws.b.copy_from_slice(&self.c0n);
        add_columns(&mut ws.b, &self.mn_cols, w, -1.0);
    }

    /// The scale of the right-hand side `b`, which the tolerances are relative to: its
    /// largest entry but a torque limit's that y = 0 meets (a limit that y = 0 breaks,
    /// a range that excludes 0 or passive torques beyond it, says how large the answer
    /// is; one that it meets does not).
    fn rhs_scale(&self) -> f64 {
        let b = &self.ws.b;
        b[self.scale_rows..]
            .iter()
            .filter(|&&v| v > 0.0)
            .fold(norm_inf(&b[..self.scale_rows]), |a, &v| a.max(v))
            .max(f64::MIN_POSITIVE)
    }

    /// How far the key set's multipliers cancel: `Σ λ_r / ‖Σ λ_r a_r‖` over its rows
    /// (unit rows `a_r`, and `Σ λ_r a_r = y` at its minimiser), at least 1. A large one
    /// is rows that nearly depend on each other, held by multipliers of opposite pull:
    /// σ moves with their rounding times this.
    fn amplification(&self) -> f64 {
        let ws = &self.ws;
        let sum: f64 = (ws.factor.rows().iter().enumerate())
            .filter(|&(_, &r)| r != S_ROW)
            .map(|(pos, _)| ws.factor.lambda(pos).max(0.0))
            .sum();
        let k = self.null_basis.ncols();
        match sum {
            0.0 => 0.0,
            _ => sum / ws.z[..k].iter().map(|v| v * v).sum::<f64>().sqrt(),
        }
    }

    /// Whether the key set at `w` is the one whose relaxation last gave no better
    /// answer ([`Self::relaxed`]), which is then not tried again.
    fn is_amplified_set(&self, w: &[f64; 6]) -> bool {
        let (set, at) = &self.amplified;
        at == w && is_set(self.ws.factor.rows(), &self.h_row, set)
    }

    /// Whether the key set's point y is so far out that its rows' rounding, `m ε ‖y‖∞`
    /// on unit rows (each formed from sums over the m joints), exceeds
    /// [`BEYOND_ROUNDING`] of the largest row constant (the problem's own scale,
    /// [`Self::rhs_scale`]): nearly parallel rows then meet there only through their
    /// rounding, and hold within a tolerance that is a fair share of the problem.
    /// (`fuzz_answers.py` seed 296620 in other units: torques of 1e13 for a load of
    /// 10 N, y at 13 and 1.9 times the problem's scale at N = 8 and 16, the object's
    /// equilibrium missed by 24 N, which the core's check passed against forces of
    /// 5e16. In the file's units the native solver proves the grasp infeasible, and
    /// Clarabel does in both. The answers on the bundled and fuzz fixtures stay below
    /// 1e-4 of that scale, the squeeze of `squeezed-by-torques-of-1e8.json` at 4e-5.)
    fn beyond_rounding(&self) -> bool {
        let k = self.null_basis.ncols();
        self.m as f64 * f64::EPSILON * norm_inf(&self.ws.z[..k])
            > BEYOND_ROUNDING * self.rhs_scale()
    }

    /// `‖u‖² = σ` at the current iterate, `u = u0 + N y`.
    fn sigma(&self) -> f64 {
        let (m, k) = (self.m, self.null_basis.ncols());
        let ws = &self.ws;
        (0..m)
            .map(|i| {
                let u = ws.u[i]
                    + (0..k)
                        .map(|l| self.null_cols[l * m + i] * ws.z[l])
                        .sum::<f64>();
                u * u
            })
            .sum()
    }

    /// After an optimum `out` whose key set is amplified by `a`
    /// ([`Self::amplification`]): the solve again with every row relaxed by
    /// [`RELAX`] times the feasibility tolerance, its key set then solved on the rows as
    /// given. Nearly dependent rows can leave a sliver where, in exact arithmetic, they
    /// meet at a point: a contact at its apex whose faces' rounding excludes the
    /// apex, beside a force on a polygon's vertex, both held there by a torque limit
    /// (`fixtures/fuzz/apex-sliver-beside-a-vertex.json`: σ 14 % above every other
    /// solver's, and above the exact cones' σ*, which the rows within tolerance
    /// reach). That answer replaces `out` where it is optimal on the rows as given (to
    /// the feasibility tolerance), its own key set is not amplified, and its σ is lower
    /// by more than an `almost_optimal` bound (true); else `out` stands, and its key set
    /// is not relaxed again.
    #[cold]
    fn relaxed(&mut self, w: &[f64; 6], a: f64, out: &mut Solution) -> bool {
        let sigma = self.sigma();
        let relax = RELAX * self.settings.feasibility_tolerance * self.rhs_scale();
        let (end, iterations) = self.runs(w, &WarmStart::default(), false, relax);
        out.iterations += iterations;
        if matches!(end, End::Optimal) {
            self.set_b(w);
            let polished = Iter::new(self, false, w).finish();
            let drop = (sigma - self.sigma()) / sigma;
            if matches!(polished, End::Optimal)
                && self.amplification() <= AMPLIFIED
                && drop > ALMOST_EXCESS
            {
                self.ws.reusable &= self.ws.factor.contains(S_ROW);
                self.write_solution(out);
                out.warnings.push(format!(
                    "the key set's multipliers cancelled to one part in {a:.1e} (nearly dependent rows, whose rounding they amplify): this answer is the key set found with every row relaxed by {RELAX} of the feasibility tolerance, solved on the rows as given, σ {drop:.1e} lower (relative)"
                ));
                return true;
            }
        }
        // (The factor is the relaxed solve's: the next solve builds its own.)
        self.ws.reusable = false;
        let (set, at) = &mut self.amplified;
        set.clear();
        set.extend_from_slice(out.active_set.as_deref().unwrap_or_default());
        *at = *w;
        false
    }

    /// Warns where the rounding of an amplified key set's rows moves σ by more than
    /// `optimal` otherwise claims. Each key row's constant moves σ by its multiplier
    /// (`μ_r = ∂σ/∂c_r`), so rounding of `m ε` (a sum of m products) on the terms of
    /// `c_r − H_r τ` moves it by up to `Σ_r μ_r m ε terms_r`, against σ as reported
    /// (with the passive torques' offset). On rows nearly opposite to one part in 1e9
    /// the terms are 1e9 times the row's value: σ at N = 8, 16, 32 and 64 differed by
    /// 1.5e-7 (`fuzz_answers.py nested` seed 260254, the paper example with noise on
    /// G), and between systems of units by up to 9.6e-3 on seed 281676 (the weighed
    /// Allegro hand with rows of Jᵀ 1e14 apart), where `ε` alone gave 8.9e-4: the rows,
    /// rounded anew at each N or unit, fix σ no closer.
    fn warn_rounding_spread(
        &self,
        ld: &LeastDistance<'_>,
        w: &[f64; 6],
        a: f64,
        out: &mut Solution,
    ) {
        let Some(set) = out.active_set.as_deref() else {
            return;
        };
        let sigma: f64 = (out.torque.iter().enumerate())
            .map(|(j, t)| {
                let u = t + ld.offset.get(j).copied().unwrap_or(0.0);
                ld.weights[j] * u * u
            })
            .sum();
        let rounding = self.m as f64 * f64::EPSILON;
        let spread: f64 = set
            .iter()
            .map(|&h| {
                let (_, terms) = ld.row_value(h, &out.torque);
                out.multipliers[h] * rounding * (terms + constant_terms(ld, h, w))
            })
            .sum::<f64>()
            / sigma;
        if spread > 2.0 * CERTIFICATE_TOLERANCE {
            out.warnings.push(format!(
                "σ is fixed by the key set's rows only to about {spread:.1e}, relative: the rows nearly depend on each other (multipliers cancelling to one part in {a:.1e}), and the rounding of their terms moves σ by their multipliers times it (optimal answers are otherwise within 2e-9)"
            ));
        }
    }

    /// Iterative refinement of an amplified key set's answer `out` in τ (at most
    /// [`REFINEMENTS`] steps): each step takes the key rows' residuals `c_i − H_i τ`,
    /// formed in τ so that each keeps the rounding of its own terms, and adds the
    /// least-norm `δτ = D⁻¹ N δy` with `Ĥ_K δy` equal to them (normalised). In y the
    /// rows are held only to `ε ‖(H D⁻¹)_i‖ ‖u‖`, and `τ = D⁻¹(u0 + N y)` cancels to a
    /// small torque on a joint whose column of H is large: two nearly opposite faces
    /// of one contact (fuzz seed 245048, the paper example with a row of Jᵀ scaled)
    /// were held 4e-7 inside, σ that much above the key set's own optimum at every N.
    /// A step is taken only where the residuals stand well above their own rounding
    /// ([`REFINABLE`]), and undone where another row no longer holds in τ to the
    /// feasibility tolerance of its terms (the key set's exact point outside a row
    /// that the iteration's rounding kept): the answer then stays the iteration's.
    fn refine(&mut self, ld: &LeastDistance<'_>, w: &[f64; 6], out: &mut Solution) {
        let (m, k) = (self.m, self.null_basis.ncols());
        // With s ≥ 0 out of the key set, a correction could move s.
        if out.torque.len() != m || !self.ws.factor.contains(S_ROW) {
            return;
        }
        let c = |h: usize| ld.c0[h] - dot(ld.hw.row(h), w);
        for _ in 0..REFINEMENTS {
            let ws = &mut self.ws;
            let (resid, tau) = (&mut ws.ad, &out.torque);
            let (mut largest, mut noise) = (0.0f64, 0.0f64);
            for &r in ws.factor.rows() {
                if r != S_ROW {
                    let h = self.h_row[r];
                    let (v, terms) = ld.row_value(h, tau);
                    let c_terms = constant_terms(ld, h, w);
                    resid[r] = (c(h) - v) / self.nu[r];
                    largest = largest.max(resid[r].abs());
                    noise = noise.max(ROUNDING * (terms + c_terms) / self.nu[r]);
                }
            }
            // A residual within its rounding, or too near it for the step to be
            // accurate, is left: on rows whose constants cancel from 1e8 (seed
            // 246300) the steps were of that noise, and the core's check refused them.
            if largest <= REFINABLE * noise {
                return;
            }
            ws.factor
                .least_norm(|r| if r == S_ROW { 0.0 } else { resid[r] }, &mut ws.zstar);
            let step = |torque: &mut [f64], sign: f64| {
                for (j, t) in torque.iter_mut().enumerate() {
                    let d: f64 = (0..k)
                        .map(|l| self.null_cols[l * m + j] * ws.zstar[l])
                        .sum();
                    *t += sign * self.dinv[j] * d;
                }
            };
            step(&mut out.torque, 1.0);
            let tol = self.settings.feasibility_tolerance;
            let holds = self.h_row.iter().enumerate().all(|(r, &h)| {
                ws.in_set[r] || {
                    let (v, terms) = ld.row_value(h, &out.torque);
                    let c = c(h);
                    v - c >= -tol * (terms + c.abs())
                }
            });
            if !holds {
                step(&mut out.torque, -1.0);
                return;
            }
        }
    }

    /// The key-set rows at the end, for infeasibility reports, appended to `out`.
    fn blocking_into(&self, out: &mut Vec<RowId>) {
        out.extend(
            self.ws
                .factor
                .rows()
                .iter()
                .filter(|&&r| r != S_ROW)
                .map(|&r| self.rows[self.h_row[r]]),
        );
    }

    /// τ = D⁻¹(u0 + N y), the key set as rows of H, and multipliers for `Σ w τ²`.
    fn write_solution(&self, out: &mut Solution) {
        let ws = &self.ws;
        let k = self.null_basis.ncols();
        let m = self.m;
        out.torque.clear();
        out.torque.extend_from_slice(&ws.u[..m]);
        add_columns(&mut out.torque, &self.null_cols, &ws.z[..k], 1.0);
        for (t, d) in out.torque.iter_mut().zip(&self.dinv) {
            *t *= d;
        }
        out.multipliers.clear();
        out.multipliers.resize(self.rows.len(), 0.0);
        for (pos, &r) in ws.factor.rows().iter().enumerate() {
            if r != S_ROW {
                // ½‖y‖² on unit rows → ‖u‖² on rows of H: μ = 2 λ / ν.
                out.multipliers[self.h_row[r]] = 2.0 * ws.factor.lambda(pos).max(0.0) / self.nu[r];
            }
        }
        let active = out.cleared_active_set();
        active.extend(
            ws.factor
                .rows()
                .iter()
                .filter(|&&r| r != S_ROW)
                .map(|&r| self.h_row[r]),
        );
        active.sort_unstable();
    }
}

/// One run of the iteration, borrowing the solver.
struct Iter<'s> {
    s: &'s mut Engine,
    iterations: usize,
    /// Set by a dual phase 1 that proved no torque exists: the row it could not satisfy.
    infeasible: Option<usize>,
    /// Set when Step 1 ended at a feasible point whose exact multipliers are all
    /// non-negative: it is optimal, and Steps 2–4 are skipped.
    certified: bool,
    penalty: f64,
    scale: f64,
    bland: bool,
    /// Set when the dual phase stopped making progress; the elastic start takes over.
    stalled: bool,
    /// Rows hold to [`TIGHT`] times the feasibility tolerance (the first run).
    tight: bool,
    /// The feasibility tolerance of this run, relative to the scale.
    feasibility: f64,
    /// Set with `infeasible` (or an elastic proof) when the proof's violation does not
    /// decide: the run that may ([`Iter::undecided_run`]).
    undecided: Option<Run>,
    /// Set with `infeasible` when the dual phase's proof holds only near its point
    /// ([`Iter::local_proof`]).
    local_proof: bool,
    /// The wrench, for the rounding of the rows' constants.
    w: [f64; 6],
}

impl<'s> Iter<'s> {
    fn new(s: &'s mut Engine, tight: bool, w: &[f64; 6]) -> Self {
        // A torque limit that y = 0 breaks (a range that excludes 0, or passive torques
        // beyond a limit) says how large the answer is; one that it meets does not.
        let scale = s.rhs_scale();
        let penalty = s.settings.elastic_penalty * scale.max(1e-12);
        let feasibility = s.settings.feasibility_tolerance * if tight { TIGHT } else { 1.0 };
        Self {
            s,
            iterations: 0,
            infeasible: None,
            certified: false,
            penalty,
            scale,
            bland: false,
            stalled: false,
            tight,
            feasibility,
            undecided: None,
            local_proof: false,
            w: *w,
        }
    }

    fn k(&self) -> usize {
        self.s.null_basis.ncols()
    }

    #[inline]
    fn feas_tol(&self) -> f64 {
        let y = norm_inf(&self.s.ws.z[..self.k()]);
        self.feasibility * self.scale.max(y)
    }

    /// The run that may still find a point where this one proved infeasibility by the
    /// violation `v` of a non-negative combination of rows (each row's multiplier in
    /// `combination`, the others 0): one at the untightened tolerance where `v` is
    /// within it, one with every row relaxed by its rounding where `v` is within the
    /// combination's rounding ([`Engine::noise`]); `None` where `v` decides. (A joint
    /// whose moment arms are 1e-6 of the others' leaves rows whose entries cancelled
    /// from 1e6 times their norm: fuzz seed 246677, a grasp whose only admissible force
    /// is zero, was infeasible in one system of units.)
    fn undecided_run(
        &self,
        v: f64,
        combination: impl Iterator<Item = (usize, f64)>,
    ) -> Option<Run> {
        // The combination is 0 in y (to its rounding): its rows' rounding enters at the
        // size of a point that would hold them, the problem's scale, not at the
        // iterate's, which a tightened run can take far past it: there it undid the
        // proof on fuzz seed 18013 (`fixtures/fuzz/inscribed-optimum-outside.json`).
        let size = self.scale;
        let u0 = grasp_core::matrix::norm2(&self.s.ws.u);
        let noise: f64 = combination
            .map(|(r, c)| c.abs() * self.s.noise(r, &self.w, size + u0))
            .sum();
        if self.tight && v <= self.feas_tol() / TIGHT {
            Some(Run::Loose)
        } else {
            // Relaxed by twice what undoes this proof: the answer moves with the
            // relaxation, which need not be the whole bound.
            (v <= noise).then_some(Run::Rounding {
                size,
                share: (2.0 * v / noise).min(1.0),
            })
        }
    }

    /// Whether the dual phase's proof by the combination `ζ = Σ c_r a_r` (0 in y to
    /// the factor's [`ActiveSetSettings::dependence_tolerance`]; `zn`, the new row's
    /// distance from the key set's span, is its size as the factor sees it) holds only
    /// near its point: both `zn` and `‖ζ‖` formed from the rows themselves exceed the
    /// rows' own rounding, `m ε Σ |c_r| per_y_r` ([`Engine::noise`]). Then every
    /// feasible y has `ζ · (y − z) ≥ v` at the iterate z, which rules out only the y
    /// within `v / ‖ζ‖` of it: a joint whose force response is 1e13 times the others'
    /// makes every row nearly parallel, and `fuzz_answers.py nested` seed 253291,
    /// feasible, was proven infeasible by two rows 2e-11 apart with `v / ‖ζ‖` of the
    /// torques' own size.
    fn local_proof(
        &self,
        zn: f64,
        combination: impl Iterator<Item = (usize, f64)> + Clone,
    ) -> bool {
        // ‖δa_r‖ ≤ m ε per_y_r for unit rows.
        let rounding = self.s.m as f64
            * f64::EPSILON
            * (combination.clone())
                .map(|(r, c)| c.abs() * self.s.noise[r][0])
                .sum::<f64>();
        zn > rounding && {
            let zeta = (0..self.k())
                .map(|j| {
                    let zj: f64 = (combination.clone())
                        .map(|(r, c)| c * self.s.a.row(r)[j])
                        .sum();
                    zj * zj
                })
                .sum::<f64>()
                .sqrt();
            zeta > rounding
        }
    }

    /// Adds row `i` to the key set; false when it depends on the rows already there.
    fn add(&mut self, i: usize) -> bool {
        let k = self.k();
        let ws = &mut self.s.ws;
        if i != S_ROW && ws.e[i] != 0.0 {
            ws.reusable = false;
        }
        let (a, e) = (&self.s.a, &ws.e);
        let tol = self.s.settings.dependence_tolerance;
        let ok = ws.factor.add(i, tol, |buf| {
            buf.iter_mut().for_each(|v| *v = 0.0);
            if i == S_ROW {
                buf[k] = 1.0;
            } else {
                buf[..k].copy_from_slice(a.row(i));
                buf[k] = e[i];
            }
        });
        self.joined(i, ok)
    }

    /// [`Self::add`] for the dual phase's row `i`, which is in `d` and whose
    /// directions were just computed.
    fn add_direction_row(&mut self, i: usize) -> bool {
        let ws = &mut self.s.ws;
        if ws.e[i] != 0.0 {
            ws.reusable = false;
        }
        let tol = self.s.settings.dependence_tolerance;
        let ok = ws.factor.add_direction_row(i, tol, &ws.d);
        self.joined(i, ok)
    }

    /// Records that row `i` joined the key set (when `ok`).
    fn joined(&mut self, i: usize, ok: bool) -> bool {
        if ok && i != S_ROW {
            self.s.ws.in_set[i] = true;
            self.s.ws.resid[i] = 0.0;
        }
        ok
    }

    fn remove(&mut self, pos: usize) {
        let r = self.s.ws.factor.rows()[pos];
        if r != S_ROW {
            self.s.ws.in_set[r] = false;
        }
        self.s.ws.factor.remove(pos);
    }

    /// Exact residuals `a_i z − b_i` of every row.
    fn refresh_residuals(&mut self) {
        let k = self.k();
        let ws = &mut self.s.ws;
        let (y, s) = (&ws.z[..k], ws.z[k]);
        for ((r, e), b) in ws.resid.iter_mut().zip(&ws.e).zip(&ws.b) {
            *r = e * s - b;
        }
        add_columns(&mut ws.resid, &self.s.a_cols, y, 1.0);
    }

    /// Step 1: a feasible start and its key set.
    fn start(&mut self, warm: &WarmStart<'_>) {
        let k = self.k();
        let nr = self.s.ws.b.len();
        if let Some(set) = warm.active_set {
            // Start at the minimiser over the given key set with s fixed at 0 (a hot
            // start has its factor already).
            if !self.s.ws.factor.contains(S_ROW) {
                self.add(S_ROW);
            }
            for &h in set {
                let r = self.s.red_row[h];
                if r != usize::MAX && !self.s.ws.in_set[r] {
                    self.add(r);
                }
            }
            self.subproblem(0.0);
            let (z, zs) = (&mut self.s.ws.z, &self.s.ws.zstar);
            z.copy_from_slice(zs);
            z[k] = 0.0;
            if self.s.settings.phase1 == Phase1::Dual {
                // Feasible: the primal Steps 2–4 confirm or improve it. Infeasible (the
                // wrench moved): hot-start the dual phase from this key set instead of
                // an elastic detour.
                self.refresh_residuals();
                let tol = self.feas_tol();
                if min_value(&self.s.ws.resid) < -tol {
                    match self.dual_from_key_set() {
                        Err(row) => self.infeasible = Some(row),
                        Ok(true) => self.certify(),
                        Ok(false) => {}
                    }
                    if !self.stalled {
                        return;
                    }
                    self.restart_elastic();
                } else {
                    // Feasible, and the multipliers from that solve are at hand.
                    self.certified = self.multipliers_nonnegative();
                    return;
                }
            }
        } else if let Some(t) = warm.torque {
            // y0 = Nᵀ(D τ − u0).
            let s = &mut *self.s;
            for j in 0..k {
                s.ws.z[j] = (0..t.len())
                    .map(|i| s.null_basis[(i, j)] * (t[i] / s.dinv[i] - s.ws.u[i]))
                    .sum();
            }
        } else if self.s.settings.phase1 == Phase1::Dual {
            // Ends with the key set, s pinned at 0 and fresh residuals: feasible unless
            // it proved infeasibility or ran out of iterations (the main loop then stops
            // at once and checks the point).
            match self.dual_phase() {
                Err(row) => self.infeasible = Some(row),
                Ok(true) => self.certify(),
                Ok(false) => {}
            }
            if !self.stalled {
                return;
            }
            self.restart_elastic();
        }
        // Elastic variable for the rows y0 violates.
        self.refresh_residuals();
        let mut worst = (0.0, usize::MAX);
        for i in 0..nr {
            let v = -self.s.ws.resid[i];
            if v > 0.0 && !self.s.ws.in_set[i] {
                self.s.ws.e[i] = 1.0;
                if v > worst.0 {
                    worst = (v, i);
                }
            }
        }
        let tol = self.feas_tol();
        if worst.0 > tol {
            if let Some(pos) = self.s.ws.factor.position(S_ROW) {
                self.remove(pos);
            }
            self.s.ws.z[k] = worst.0;
            self.refresh_residuals();
            self.add(worst.1);
        } else {
            self.s.ws.e.iter_mut().for_each(|v| *v = 0.0);
            self.s.ws.z[k] = 0.0;
            self.refresh_residuals();
            if !self.s.ws.factor.contains(S_ROW) {
                self.add(S_ROW);
            }
            if warm.active_set.is_none() && warm.torque.is_some() {
                // The key set at a given feasible torque: the rows active there.
                for i in 0..nr {
                    if self.s.ws.resid[i].abs() <= tol && !self.s.ws.in_set[i] {
                        self.add(i);
                    }
                }
            }
        }
    }

    /// Forgets the key set and the point: the elastic start from y = 0 follows.
    fn restart_elastic(&mut self) {
        let ws = &mut self.s.ws;
        ws.z.iter_mut().for_each(|v| *v = 0.0);
        ws.e.iter_mut().for_each(|v| *v = 0.0);
        ws.in_set.iter_mut().for_each(|v| *v = false);
        ws.factor.clear();
        ws.mult.clear();
        self.stalled = false;
        self.bland = false;
    }

    /// Cold-start phase 1 (with [`Phase1::Dual`]): the dual active-set method of
    /// Goldfarb and Idnani on the same QR factorisation. From the unconstrained minimum
    /// (y = 0, s pinned at 0) it adds the most violated row, stepping along the primal
    /// direction `Q2 Q2ᵀ a` and the dual direction `R⁻¹ Q1ᵀ a`, and drops a key-set row
    /// whose multiplier would turn negative. Every iterate is optimal for the rows in
    /// its key set, so the first primal-feasible one is optimal overall; Steps 2–4 then
    /// confirm it. Fails with the violated row when it is a non-negative combination of
    /// the key set's rows (no torque exists); each add or drop counts as an iteration.
    fn dual_phase(&mut self) -> Result<bool, usize> {
        self.add(S_ROW);
        self.s.ws.mult.clear();
        self.s.ws.mult.push(0.0);
        self.dual_iterate()
    }

    /// The dual phase hot-started from the current key set (s pinned at 0), for a warm
    /// key set whose point the new wrench made infeasible: rows with negative
    /// multipliers leave until the set is dual feasible, then the dual iteration goes on.
    fn dual_from_key_set(&mut self) -> Result<bool, usize> {
        let k = self.k();
        loop {
            self.subproblem(0.0);
            let ws = &self.s.ws;
            let tol = self.s.settings.multiplier_tolerance * norm_inf(&ws.zstar).max(self.scale);
            let worst = ws
                .factor
                .rows()
                .iter()
                .enumerate()
                .filter(|&(pos, &r)| r != S_ROW && ws.factor.lambda(pos) < -tol)
                .min_by(|a, b| ws.factor.lambda(a.0).total_cmp(&ws.factor.lambda(b.0)));
            match worst {
                Some((pos, _)) => {
                    self.iterations += 1;
                    self.remove(pos);
                }
                None => break,
            }
        }
        let ws = &mut self.s.ws;
        ws.z.copy_from_slice(&ws.zstar);
        ws.z[k] = 0.0;
        ws.mult.clear();
        for pos in 0..ws.factor.rows().len() {
            ws.mult.push(ws.factor.lambda(pos));
        }
        self.dual_iterate()
    }

    /// The dual iteration proper (see [`Self::dual_phase`]), from a key set whose
    /// multipliers `mult` are non-negative and whose minimiser is `z`. `Ok(true)` when
    /// it reached a feasible (hence optimal) point, `Ok(false)` at the iteration cap.
    fn dual_iterate(&mut self) -> Result<bool, usize> {
        let mut stalls = 0usize;
        let k = self.k();
        let n = k + 1;
        let max_it = self.s.settings.max_iterations;
        loop {
            self.refresh_residuals();
            let tol = self.feas_tol();
            let mut worst = (tol, usize::MAX);
            for (i, &r) in self.s.ws.resid.iter().enumerate() {
                if -r > worst.0 && !self.s.ws.in_set[i] {
                    worst = (-r, i);
                }
            }
            let p = worst.1;
            if p == usize::MAX {
                return Ok(true);
            }
            let mut lam_p = 0.0;
            loop {
                if self.iterations >= max_it {
                    return Ok(false);
                }
                self.iterations += 1;
                let ws = &mut self.s.ws;
                ws.d.iter_mut().for_each(|v| *v = 0.0);
                ws.d[..k].copy_from_slice(self.s.a.row(p));
                ws.d[k] = ws.e[p];
                let t = ws.factor.rows().len();
                // Primal direction into `ad` (length ≥ n is not guaranteed; use zstar),
                // dual direction into the factor's λ buffer.
                ws.factor.directions(&ws.d, &mut ws.zstar);
                let anorm = grasp_core::matrix::norm2(&ws.d);
                let zn = grasp_core::matrix::norm2(&ws.zstar[..n]);
                let slack = dot(&ws.d, &ws.z) - ws.b[p];
                // Dual step limit: a key-set row's multiplier reaching zero (never s ≥ 0,
                // which pins s and may take either sign).
                let mut t1 = (f64::INFINITY, usize::MAX);
                for pos in 0..t {
                    let r = ws.factor.lambda(pos);
                    if ws.factor.rows()[pos] != S_ROW && r > 0.0 {
                        let ratio = ws.mult[pos] / r;
                        if ratio < t1.0 {
                            t1 = (ratio, pos);
                        }
                    }
                }
                let az = dot(&ws.d, &ws.zstar[..n]);
                let t2 = if zn > self.s.settings.dependence_tolerance * anorm && az > 0.0 {
                    -slack / az
                } else {
                    f64::INFINITY
                };
                // A full step (row p joins) or a partial one (a key-set row leaves).
                let full = t2 <= t1.0;
                let step = if full { t2 } else { t1.0 };
                if step.is_infinite() {
                    // Row p plus the key set's rows times −(its direction's
                    // multipliers), all non-negative, is 0 in y and `v` in b.
                    let rows = self.s.ws.factor.rows();
                    let key = (0..t)
                        .filter(|&pos| rows[pos] != S_ROW)
                        .map(|pos| (rows[pos], -self.s.ws.factor.lambda(pos)));
                    let combination = key.chain([(p, 1.0)]);
                    self.undecided = self.undecided_run(worst.0, combination.clone());
                    self.local_proof = self.local_proof(zn, combination);
                    return Err(p);
                }
                for pos in 0..t {
                    let r = ws.factor.lambda(pos);
                    ws.mult[pos] -= step * r;
                }
                lam_p += step;
                if t2.is_finite() {
                    for j in 0..n {
                        ws.z[j] += step * ws.zstar[j];
                    }
                }
                if full {
                    if self.add_direction_row(p) {
                        self.s.ws.mult.push(lam_p);
                        stalls = 0;
                    } else {
                        // p depends on the key set numerically though the step said
                        // otherwise: the same row would be picked again.
                        stalls += 1;
                        if stalls > n {
                            self.stalled = true;
                            return Ok(false);
                        }
                    }
                    break;
                }
                let pos = t1.1;
                self.s.ws.mult.remove(pos);
                self.remove(pos);
            }
        }
    }

    /// The minimiser of `½‖z‖² + penalty·s` over the key set into `zstar`, and the
    /// multipliers into the factor.
    fn subproblem(&mut self, penalty: f64) {
        let ws = &mut self.s.ws;
        let b = &ws.b;
        // With s fixed at 0 the penalty moves only the multiplier of `s ≥ 0`; leaving it
        // out of z* keeps M's rounding out of y.
        let exact = ws.factor.contains(S_ROW);
        ws.factor.solve(
            penalty,
            exact,
            |i| if i == S_ROW { 0.0 } else { b[i] },
            &mut ws.zstar,
        );
    }

    fn run(&mut self, warm: &WarmStart<'_>) -> End {
        self.start(warm);
        if let Some(row) = self.infeasible {
            return End::Infeasible(Some(row));
        }
        if self.certified {
            return End::Optimal;
        }
        let k = self.k();
        let kp = k + 1;
        let max_it = self.s.settings.max_iterations;
        let mut increases = 0;
        let mut at_minimum = false;
        let mut degenerate = 0usize;
        loop {
            if self.iterations >= max_it {
                return self.out_of_iterations();
            }
            self.iterations += 1;
            // Step 2: the equality-constrained minimiser (eq. 44) and d = τ' − τ.
            self.subproblem(self.penalty);
            let ws = &mut self.s.ws;
            let mut dmax: f64 = 0.0;
            for j in 0..kp {
                ws.d[j] = ws.zstar[j] - ws.z[j];
                dmax = dmax.max(ws.d[j].abs());
            }
            let zmax = norm_inf(&ws.z).max(self.scale);
            if at_minimum || dmax <= 1e3 * f64::EPSILON * kp as f64 * zmax {
                at_minimum = false;
                // Step 4: multipliers of the key set.
                // While s is free, multipliers carry the penalty's scale.
                let mscale = if self.s.ws.factor.contains(S_ROW) {
                    zmax
                } else {
                    zmax.max(self.penalty)
                };
                let tol = self.s.settings.multiplier_tolerance * mscale;
                let rows = self.s.ws.factor.rows();
                let mut drop: Option<(usize, f64)> = None;
                for (pos, &r) in rows.iter().enumerate() {
                    let l = self.s.ws.factor.lambda(pos);
                    if l < -tol {
                        let better = match drop {
                            None => true,
                            Some((p, best)) => {
                                if self.bland {
                                    r < rows[p]
                                } else {
                                    l < best
                                }
                            }
                        };
                        if better {
                            drop = Some((pos, l));
                        }
                    }
                }
                if let Some((pos, _)) = drop {
                    self.remove(pos);
                    continue;
                }
                if self.s.ws.factor.contains(S_ROW) {
                    return self.finish();
                }
                // Stationary with s free: the penalty is too small, or no torque exists.
                if increases == self.s.settings.penalty_increases {
                    return if self.s.ws.z[k] > self.feas_tol() {
                        // The key set's multipliers per unit of s's: the combination
                        // of rows whose value proves s > 0.
                        let ws = &self.s.ws;
                        let rows = ws.factor.rows();
                        let key = || {
                            (0..rows.len())
                                .filter(|&pos| rows[pos] != S_ROW)
                                .map(|pos| (rows[pos], ws.factor.lambda(pos).max(0.0)))
                        };
                        let total: f64 = key().map(|(r, l)| l * ws.e[r]).sum();
                        let per_s =
                            key().map(|(r, l)| (r, if total > 0.0 { l / total } else { 0.0 }));
                        self.undecided = self.undecided_run(ws.z[k], per_s);
                        End::Infeasible(None)
                    } else {
                        End::Numerical("the elastic variable would not leave the key set's span")
                    };
                }
                increases += 1;
                self.penalty *= self.s.settings.penalty_growth;
                continue;
            }
            // Step 2, ratio test (eqs. 45–47).
            let dnorm = grasp_core::matrix::norm2(&self.s.ws.d);
            let dep = self.s.settings.dependence_tolerance * dnorm;
            let mut alpha = 1.0;
            let mut block = None;
            let nr = self.s.ws.b.len();
            // a_i · d for every row at once, down the columns (key-set rows unused).
            let ws = &mut self.s.ws;
            for (ad, e) in ws.ad.iter_mut().zip(&ws.e) {
                *ad = e * ws.d[k];
            }
            add_columns(&mut ws.ad, &self.s.a_cols, &ws.d[..k], 1.0);
            for i in 0..nr {
                if self.s.ws.in_set[i] {
                    continue;
                }
                let ad = self.s.ws.ad[i];
                if ad < -dep {
                    let ratio = self.s.ws.resid[i].max(0.0) / -ad;
                    // Rows are scanned in index order, so under Bland's rule the first
                    // of tied rows (the smallest index) is kept.
                    if ratio < alpha {
                        alpha = ratio;
                        block = Some(i);
                    }
                }
            }
            if !self.s.ws.factor.contains(S_ROW) {
                let ds = self.s.ws.d[k];
                if ds < -dep {
                    let ratio = self.s.ws.z[k].max(0.0) / -ds;
                    if ratio < alpha {
                        alpha = ratio;
                        block = Some(S_ROW);
                    }
                }
            }
            let ws = &mut self.s.ws;
            for j in 0..kp {
                ws.z[j] += alpha * ws.d[j];
            }
            for i in 0..nr {
                if !ws.in_set[i] {
                    ws.resid[i] += alpha * ws.ad[i];
                }
            }
            match block {
                None => at_minimum = true,
                Some(p) => {
                    if p == S_ROW {
                        self.s.ws.z[k] = 0.0;
                    }
                    if alpha * dnorm <= 1e3 * f64::EPSILON * zmax {
                        degenerate += 1;
                        if degenerate > kp {
                            self.bland = true;
                        }
                    } else {
                        degenerate = 0;
                    }
                    // A row within rounding of the key set's span blocks only through
                    // rounding in d: the step has in effect reached the subproblem minimum.
                    if !self.add(p) {
                        at_minimum = true;
                    }
                }
            }
        }
    }

    /// After a successful dual phase: the exact multipliers of the final key set, and
    /// whether they certify optimality, so that Steps 2–4 have nothing left to do. The
    /// answer stays the iterate, whose residuals the dual phase has just computed from
    /// scratch, when it is the key set's minimiser to within the run's feasibility
    /// tolerance (the two are the same point in exact arithmetic); s is pinned at 0, and
    /// moves no row (e = 0 in the dual phase). An iterate further away is left to
    /// Steps 2–4, which walk it to the minimiser and end there (`finish`): the dual
    /// steps add up along directions that nearly parallel rows make ill-conditioned,
    /// and an iterate 5 % from the minimiser of three rows whose normals agreed to
    /// 1e-9 (one joint's column of H 1e10 times the others') was returned as optimal,
    /// σ 2.2e-3 above it (`fuzz_answers.py nested` seed 154509, at N = 16).
    fn certify(&mut self) {
        // The scan that ended the dual phase checked every row but the key set's own.
        let (tol, ws) = (self.feas_tol(), &self.s.ws);
        if ws
            .factor
            .rows()
            .iter()
            .any(|&r| r != S_ROW && ws.resid[r] < -tol)
        {
            return;
        }
        self.subproblem(0.0);
        let k = self.k();
        let ws = &mut self.s.ws;
        ws.z[k] = 0.0;
        let far = ws.z[..k]
            .iter()
            .zip(&ws.zstar)
            .fold(0.0f64, |a, (z, m)| a.max((z - m).abs()));
        self.certified = far <= tol && self.multipliers_nonnegative();
    }

    /// Whether the last subproblem's multipliers (s ≥ 0 aside) are non-negative, with
    /// the tolerance of the final check.
    fn multipliers_nonnegative(&self) -> bool {
        let ws = &self.s.ws;
        let ltol = self.s.settings.multiplier_tolerance * norm_inf(&ws.z).max(self.scale) * 10.0;
        ws.factor
            .rows()
            .iter()
            .enumerate()
            .all(|(pos, &r)| r == S_ROW || ws.factor.lambda(pos) >= -ltol)
    }

    /// The iteration cap: report whether the current iterate is admissible (s pinned at
    /// 0 and every row holding), so that only a feasible point is ever handed back.
    fn out_of_iterations(&mut self) -> End {
        self.refresh_residuals();
        let tol = self.feas_tol();
        let ws = &self.s.ws;
        End::IterationLimit(ws.factor.contains(S_ROW) && ws.resid.iter().all(|&r| r >= -tol))
    }

    /// Re-solves the final key set without the penalty (exact multipliers) and checks
    /// primal and dual feasibility before accepting.
    fn finish(&mut self) -> End {
        let k = self.k();
        self.subproblem(0.0);
        let ws = &mut self.s.ws;
        ws.z.copy_from_slice(&ws.zstar);
        ws.z[k] = 0.0;
        ws.e.iter_mut().for_each(|v| *v = 0.0);
        self.refresh_residuals();
        let tol = self.feas_tol();
        let ws = &self.s.ws;
        if min_value(&ws.resid) < -tol {
            return End::Numerical("the final point violates a row beyond tolerance");
        }
        let ltol = self.s.settings.multiplier_tolerance * norm_inf(&ws.z).max(self.scale) * 10.0;
        for (pos, &r) in ws.factor.rows().iter().enumerate() {
            if r != S_ROW && ws.factor.lambda(pos) < -ltol {
                return End::Numerical("a multiplier of the final key set is negative");
            }
        }
        End::Optimal
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use grasp_core::{GraspModel, ModelOptions};
    use std::sync::Arc;

    /// The model's factors of C give the decomposition's subspace and least-norm
    /// solution, whatever the weights: the same projector `N Nᵀ` and the same `pu`, to
    /// rounding amplified by the weighting's spread.
    #[test]
    fn the_factored_equalities_are_the_decomposed_ones() {
        let mut rng = grasp_testkit::Rng(7);
        let mut checked = 0;
        for seed in 0..200u64 {
            let mut p = grasp_testkit::sweep_grasp(seed, 1.0);
            // Weights over up to six decades.
            let spread = [0.0, 2.0, 6.0][seed as usize % 3];
            p.torque_weights = Some(
                (0..p.joints())
                    .map(|_| 10f64.powf(rng.uniform(-spread / 2.0, spread / 2.0)))
                    .collect(),
            );
            let Ok(model) = GraspModel::new(&p, &ModelOptions::default()) else {
                continue;
            };
            let m = model.joints();
            let qp = TorqueQp::linearized(Arc::new(model), &Default::default());
            let ld = qp.least_distance();
            if ld.eq.nrows() == 0 {
                continue;
            }
            let Some(f) = Equalities::from_factors(&ld, ld.eq_factors.unwrap()) else {
                panic!("seed {seed}: no factored equalities");
            };
            let d = Equalities::new(&LeastDistance {
                eq_factors: None,
                ..ld
            })
            .unwrap();
            let proj = |n: &Matrix| n.matmul(&n.transpose());
            let (pf, pd) = (proj(&f.null_basis), proj(&d.null_basis));
            let gap = pf
                .as_slice()
                .iter()
                .zip(pd.as_slice())
                .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            // κ of the column scaling √w / r that separates the two ways.
            let g: Vec<f64> = (0..m)
                .map(|j| ld.weights[j].sqrt() / qp.model.torque_scale[j])
                .collect();
            let kappa = g.iter().fold(0.0f64, |a, v| a.max(*v))
                / g.iter().fold(f64::INFINITY, |a, v| a.min(*v));
            let tol = 10.0 * m as f64 * f64::EPSILON * kappa;
            assert!(
                gap <= tol,
                "seed {seed}: projectors differ by {gap:.1e} > {tol:.1e}"
            );
            let scale = d.pu.max_abs().max(f64::MIN_POSITIVE);
            let du =
                f.pu.as_slice()
                    .iter()
                    .zip(d.pu.as_slice())
                    .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            assert!(
                du <= tol * scale,
                "seed {seed}: pu differs by {:.1e} > {:.1e}",
                du / scale,
                tol
            );
            checked += 1;
        }
        assert!(checked >= 150, "only {checked} grasps checked");
    }
}
