//! The backend trait and what every backend returns.
//!
//! The core completes every answer the same way, whichever backend produced it: the
//! contact forces, σ, the residuals and the cone margins, and a final check. An answer
//! a backend calls optimal whose residuals exceed the backend's stated accuracy,
//! relative to the problem's own scale, is reported as a numerical failure instead.

use crate::matrix::{add_column_block, all_finite, norm_inf};
use crate::model::Equilibrium;
use crate::qp::{ConeRepr, RowId, TorqueQp};
use serde::{Serialize, Serializer};
use std::fmt;
use std::time::{Duration, Instant};

/// How a solve finished ("ran and finished"; bad input is an `Err` instead).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Status {
    /// An optimal torque was found, and it passed the residual checks.
    Optimal,
    /// The backend reached only reduced accuracy (Clarabel's "almost solved", or an
    /// exact-cone answer whose certificate bounds σ only to within 1e-6 of the
    /// optimum, with the bound in a warning); the answer still passed the residual
    /// checks.
    AlmostOptimal,
    /// No torque satisfies the constraints; [`Solution::reason`] says why.
    Infeasible,
    /// The iteration cap was reached before optimality.
    IterationLimit,
    /// The backend could not make progress reliably, or its answer failed the checks.
    #[default]
    NumericalFailure,
}

impl Status {
    /// `optimal`, `almost_optimal`, `infeasible`, `iteration_limit` or `numerical_failure`.
    pub fn as_str(&self) -> &'static str {
        match self {
            Status::Optimal => "optimal",
            Status::AlmostOptimal => "almost_optimal",
            Status::Infeasible => "infeasible",
            Status::IterationLimit => "iteration_limit",
            Status::NumericalFailure => "numerical_failure",
        }
    }

    /// Optimal, at full or reduced accuracy: the torque is an answer.
    pub fn has_answer(&self) -> bool {
        matches!(self, Status::Optimal | Status::AlmostOptimal)
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Why a solve did not end optimal.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[non_exhaustive]
pub enum Reason {
    /// No torque can make `[w; τ]` consistent: part of the wrench is outside what any
    /// contact force produced by the joints can balance.
    UnreachableWrench {
        /// `‖unreachable · w‖∞`, in equilibrated wrench units.
        residual: f64,
    },
    /// A constraint row that no torque affects is violated by the wrench alone.
    FixedRowViolated {
        /// The row.
        row: RowId,
        /// By how much (force units for cone rows).
        violation: f64,
    },
    /// The cones, the consistency equalities and the options admit no torque.
    NoAdmissibleTorque {
        /// With an elastic start: the smallest uniform relaxation of the normalised rows
        /// that the solver found would make the problem feasible.
        relaxation: Option<f64>,
        /// The rows that block.
        blocking: Vec<RowId>,
    },
    /// The backend's answer failed the core's residual check.
    ResidualCheck {
        /// `‖G f − w‖∞`.
        wrench_residual: f64,
        /// `‖Jᵀ f − τ‖∞`.
        torque_residual: f64,
        /// Largest violation of a linear row or an exact cone (force or torque units).
        violation: f64,
        /// The relative tolerance that applied.
        tolerance: f64,
        /// Each check's worst row as a fraction of that row's bound, which the size of
        /// its own terms sets (above 1 fails): [`Diagnostics::wrench_check`],
        /// [`Diagnostics::torque_check`], and the larger of
        /// [`Diagnostics::violation_check`] and [`Diagnostics::cone_check`]. A residual
        /// far below the tolerance can fail on a row whose terms are smaller still.
        checks: [f64; 3],
    },
    /// Infeasible for `cause`, on a hand whose joint torques must stay in the range of
    /// its transmission: the directions no actuator produces are named.
    Underactuated {
        /// The unactuated joint-torque directions, as joint combinations.
        unactuated: Vec<String>,
        /// What the solver found.
        cause: Box<Reason>,
    },
    /// Even the circumscribed polyhedral cones, which contain the exact cones, admit
    /// no torque: a certificate that the exact problem is infeasible.
    OuterApproximation {
        /// Sides N of the circumscribed polygons.
        sides: usize,
        /// Why the circumscribed problem is infeasible.
        cause: Box<Reason>,
    },
    /// A ray of the problem's dual, on the exact cones or the polyhedra (a Farkas
    /// certificate): multipliers `z` in the dual cones whose combination of the
    /// constraint rows has no torque terms (to `stationarity`) and a negative
    /// right-hand side, `zᵀ(b − A x) = value < 0` for every torque meeting the
    /// equalities, although a feasible torque would make it `zᵀ s ≥ 0`. Checked from
    /// scratch ([`crate::ConicForm::dual_ray`]).
    DualRay {
        /// `value` against the size of its terms (negative).
        value: f64,
        /// The largest torque term left, against the size of its terms.
        stationarity: f64,
    },
    /// Backend-specific explanation.
    Backend {
        /// The backend's name.
        backend: &'static str,
        /// What it said.
        message: String,
    },
}

impl fmt::Display for Reason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Reason::UnreachableWrench { residual } => write!(
                f,
                "the wrench has a component ({residual:.3e}) that no joint torque can balance: [w; τ] cannot lie in the range of [G; Jᵀ]"
            ),
            Reason::FixedRowViolated { row, violation } => write!(
                f,
                "row {row} is not affected by any joint torque and the wrench violates it by {violation:.3e}"
            ),
            Reason::NoAdmissibleTorque { relaxation, blocking } => {
                write!(f, "no joint torque keeps every contact force inside its cone while balancing the wrench (")?;
                if let Some(r) = relaxation {
                    write!(f, "the rows would need relaxing by {r:.3e}; ")?;
                }
                let names: Vec<String> = blocking.iter().map(RowId::to_string).collect();
                write!(f, "conflicting rows: {})", names.join(", "))
            }
            Reason::ResidualCheck { wrench_residual, torque_residual, violation, tolerance, checks } => {
                let of = |c: f64| match c {
                    c if !c.is_finite() => "not finite against its bound".to_string(),
                    0.0 => "within its row's bound".to_string(),
                    c if (1e-3..1e4).contains(&c) => format!("{c:.3} times its row's bound"),
                    c => format!("{c:.1e} times its row's bound"),
                };
                write!(
                    f,
                    "the backend's answer failed the residual check at relative tolerance {tolerance:.1e}, each row against the size of its terms: ‖G f − w‖∞ = {wrench_residual:.3e} ({}), ‖Jᵀ f − τ‖∞ = {torque_residual:.3e} ({}), largest constraint violation {violation:.3e} ({})",
                    of(checks[0]),
                    of(checks[1]),
                    of(checks[2])
                )
            }
            Reason::Underactuated { unactuated, cause } => write!(
                f,
                "{cause}; the hand is underactuated: Jᵀ f must lie in the range of the transmission, and no actuator produces joint torque along {}",
                unactuated.join("; ")
            ),
            Reason::OuterApproximation { sides, cause } => write!(
                f,
                "even the circumscribed polyhedral cones (N = {sides}), which contain the exact cones, admit no torque: {cause}"
            ),
            Reason::DualRay { value, stationarity } => write!(
                f,
                "no torque keeps every contact force inside its cone while balancing the wrench: multipliers in the dual cones combine the constraints into 0 ≤ {value:.3e} (relative; a Farkas certificate, torque terms cancelled to {stationarity:.1e})"
            ),
            Reason::Backend { backend, message } => write!(f, "{backend}: {message}"),
        }
    }
}

/// Physical consistency checks, computed by the core so every backend reports alike.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Diagnostics {
    /// The core's residual check and everything below were deferred ([`Check::Lazy`]):
    /// the fields are zero until [`TorqueQp::complete`] runs.
    pub deferred: bool,
    /// `‖G f − w‖∞`: does the answer hold the object?
    pub wrench_residual: f64,
    /// `‖Jᵀ f − τ‖∞`: do the joints produce these forces?
    pub torque_residual: f64,
    /// `‖C τ − e‖∞` (0 in the paper model).
    pub consistency_residual: f64,
    /// Largest violation `max(c_i − H_i τ, 0)` of the linear rows: inscribed faces,
    /// minimum normal forces (force units) and torque limits (torque units).
    pub max_violation: f64,
    /// Largest violation `max(g(f) − fz, 0)` of an exact cone (force units; 0 when no
    /// contact uses its exact cone).
    pub cone_violation: f64,
    /// Per contact, the scale-free margin to its exact cone (see
    /// [`crate::ContactModel::exact_margin`]): 1 pure normal push, 0 on the cone, < 0
    /// outside. `None` for an unloaded contact, whose force is at rounding level.
    pub friction_margins: Vec<Option<f64>>,
    /// The relative tolerance of the final residual check.
    pub check_tolerance: f64,
    /// The largest `|G_i f − w_i|` as a fraction of the check's bound for its row:
    /// at most 1 means the object is held to the backend's accuracy.
    pub wrench_check: f64,
    /// The same for `Jᵀ f = τ`.
    pub torque_check: f64,
    /// The same for the linear rows (`c − H τ`: inscribed faces and minimum normal
    /// forces) and the torque limits: the largest violation as a fraction of its row's
    /// bound. At most 1 passes; 0 when nothing is violated.
    pub violation_check: f64,
    /// The same for the exact cones (`g(f) − fz`).
    pub cone_check: f64,
}

/// Rows of the residual check formed at a time, on the stack.
const CHECK_BLOCK: usize = 16;

/// The largest `r / bound` of a check's rows (r > 0), kept as a fraction: one division
/// at the end instead of one per row.
#[derive(Clone, Copy)]
struct WorstRatio {
    r: f64,
    bound: f64,
}

impl WorstRatio {
    const NONE: Self = Self { r: 0.0, bound: 1.0 };

    #[inline]
    fn add(&mut self, r: f64, bound: f64) {
        if r * self.bound > self.r * bound {
            *self = Self { r, bound };
        }
    }

    fn value(self) -> f64 {
        self.r / self.bound
    }
}

/// The linear rows' violations so far: the largest, the worst against the bound it
/// was judged by, and the largest of those within the bound `tol F` that the rows with
/// `c0 = 0` (all but each contact's normal) share, kept apart: one maximum per row.
struct RowViolations {
    worst: f64,
    ratio: WorstRatio,
    passed: f64,
}

/// One contact's rows `c0_k − s_k · f_c ≤ 0` (faces of `D` components, row-major):
/// adds them to `viol` and returns whether a row fails at `tol`. At these lengths a
/// general dot product costs several times the arithmetic, hence `D` fixed. A row over
/// the cheap bound `tol (|c0| + F)` pays for its own terms `Σ |s f|`, and one over that
/// for the rounding of f itself, `floor(s)`.
#[inline(always)]
fn cone_rows<const D: usize>(
    faces: &[f64],
    fc: &[f64],
    fmin: f64,
    tol: f64,
    fscale: f64,
    floor: &mut impl FnMut(&[f64]) -> f64,
    viol: &mut RowViolations,
) -> bool {
    let fc: &[f64; D] = fc
        .try_into()
        .expect("contact force of its model's dimension");
    let dot = |s: &[f64]| -> f64 {
        if D == 4 {
            (s[0] * fc[0] + s[1] * fc[1]) + (s[2] * fc[2] + s[3] * fc[3])
        } else {
            (0..D).map(|k| s[k] * fc[k]).sum()
        }
    };
    let terms = |s: &[f64]| -> f64 { (0..D).map(|k| (s[k] * fc[k]).abs()).sum() };
    let mut bad = false;
    // Every row's constant is 0 but the last's (the normal's): fz ≥ f_min.
    let (body, last) = faces.split_at(faces.len().saturating_sub(D));
    let cheap = tol * fscale;
    for s in body.chunks_exact(D) {
        let v = -dot(s);
        viol.worst = viol.worst.max(v);
        if exceeds(v, cheap) {
            let mut bound = cheap + tol * terms(s);
            if exceeds(v, bound) {
                bound += floor(s);
            }
            bad |= exceeds(v, bound);
            viol.ratio.add(v, bound);
        } else {
            viol.passed = viol.passed.max(v);
        }
    }
    if last.len() == D {
        let v = fmin - dot(last);
        viol.worst = viol.worst.max(v);
        let cheap = tol * (fmin.abs() + fscale);
        if exceeds(v, cheap) {
            let mut bound = cheap + tol * terms(last);
            if exceeds(v, bound) {
                bound += floor(last);
            }
            bad |= exceeds(v, bound);
            viol.ratio.add(v, bound);
        } else if v > 0.0 {
            viol.ratio.add(v, cheap);
        }
    }
    bad
}

/// `v > limit`, or not a number.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn exceeds(v: f64, limit: f64) -> bool {
    !(v <= limit)
}

fn reason_with_message<S: Serializer>(r: &Option<Reason>, s: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct WithMessage<'a> {
        message: String,
        #[serde(flatten)]
        detail: &'a Reason,
    }
    match r {
        None => s.serialize_none(),
        Some(detail) => WithMessage {
            message: detail.to_string(),
            detail,
        }
        .serialize(s),
    }
}

fn micros<S: Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(d.as_secs_f64() * 1e6)
}

/// The answer of one solve.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Solution {
    /// How the solve finished.
    pub status: Status,
    /// Why it is not optimal, when it is not (in JSON: `message` and the details).
    #[serde(serialize_with = "reason_with_message")]
    pub reason: Option<Reason>,
    /// τ, one per joint (empty unless the status has an answer, or an iteration limit
    /// with a feasible iterate). With a transmission: u, one per actuator.
    pub torque: Vec<f64>,
    /// With a transmission, the joint torques `τ = T u` (empty otherwise).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub joint_torque: Vec<f64>,
    /// The passive internal forces ξ chosen (empty unless they are free).
    pub internal_forces: Vec<f64>,
    /// `f = Z1 w + Z2 τ + N ξ`, in contact order (empty when `torque` is).
    pub contact_forces: Vec<f64>,
    /// `σ = Σ w_j τ_j²` (eq. 40; 0 when there is no torque).
    pub objective: f64,
    /// Iterations of the backend.
    pub iterations: usize,
    /// Which of the backend's methods produced the answer, when it has several: the
    /// native exact-cone solver's `newton` (active-set Newton from the linearised
    /// optimum) or `interior_point` (its fallback); `polished` for a Clarabel answer
    /// whose rows held with equality were solved exactly and certified.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method: Option<&'static str>,
    /// The final key constraint set: linear rows active at τ, when the backend has one
    /// (indices into the rows of [`TorqueQp`]).
    pub active_set: Option<Vec<usize>>,
    /// Lagrange multipliers of the linear rows for `Σ w_j τ_j²` (empty if not reported).
    pub multipliers: Vec<f64>,
    /// Wall-clock time of the solve, model already built (µs in JSON); zero under
    /// [`Check::Lazy`].
    #[serde(rename = "solve_time_us", serialize_with = "micros")]
    pub solve_time: Duration,
    /// Residuals and margins.
    pub diagnostics: Diagnostics,
    /// Warnings to show the user (for example the paper model's unbalanced wrench).
    pub warnings: Vec<String>,
    /// Earlier answers' buffers (a reason's, a key set's), which the next answer is
    /// built in: a control loop whose ticks stay infeasible, or cross the limits and
    /// back, allocates nothing ([`Solution::recycle_reason`]). Not part of the answer.
    #[serde(skip)]
    pub recycled: Recycled,
}

/// The buffers a [`Solution`] no longer holds, for its next answer: a key set, and a
/// reason's rows, boxes and names.
#[derive(Clone, Default)]
pub struct Recycled {
    set: Vec<usize>,
    rows: Vec<RowId>,
    names: Vec<String>,
    // (The boxes themselves are the buffers kept.)
    #[allow(clippy::vec_box)]
    boxes: Vec<Box<Reason>>,
}

impl fmt::Debug for Recycled {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Recycled")
    }
}

/// Boxes kept at most (a reason nests two: underactuated, around the circumscribed
/// polyhedra's proof).
const KEPT_BOXES: usize = 4;

impl Recycled {
    /// Takes `reason` apart into the buffers (the larger of two alike is kept).
    fn keep(&mut self, reason: Reason) {
        match reason {
            Reason::NoAdmissibleTorque { blocking, .. } => self.keep_rows(blocking),
            Reason::OuterApproximation { cause, .. } => self.keep_box(cause),
            Reason::Underactuated { unactuated, cause } => {
                if unactuated.capacity() > self.names.capacity() {
                    self.names = unactuated;
                }
                self.keep_box(cause);
            }
            _ => {}
        }
    }

    fn keep_rows(&mut self, rows: Vec<RowId>) {
        if rows.capacity() > self.rows.capacity() {
            self.rows = rows;
        }
    }

    fn keep_box(&mut self, mut b: Box<Reason>) {
        // (A placeholder that owns nothing takes the content's place.)
        let inner = std::mem::replace(&mut *b, Reason::UnreachableWrench { residual: 0.0 });
        if self.boxes.len() < KEPT_BOXES {
            self.boxes.push(b);
        }
        self.keep(inner);
    }
}

impl Solution {
    /// Clears the reason, keeping its buffers for the next ([`Recycled`]).
    pub fn recycle_reason(&mut self) {
        if let Some(r) = self.reason.take() {
            self.recycled.keep(r);
        }
    }

    /// Clears the key set, keeping its buffer for the next ([`Recycled`]).
    pub fn recycle_active_set(&mut self) {
        if let Some(set) = self.active_set.take() {
            if set.capacity() > self.recycled.set.capacity() {
                self.recycled.set = set;
            }
        }
    }

    /// The key set, emptied, in a kept buffer where there is one.
    pub fn cleared_active_set(&mut self) -> &mut Vec<usize> {
        let Self {
            active_set,
            recycled,
            ..
        } = self;
        let set = active_set.get_or_insert_with(|| std::mem::take(&mut recycled.set));
        set.clear();
        set
    }

    /// Keeps `rows`' buffer for a later reason (another solution's, say).
    pub fn recycle_rows(&mut self, rows: Vec<RowId>) {
        self.recycled.keep_rows(rows);
    }

    /// An empty list of rows for a new reason, in a kept buffer where there is one.
    pub fn recycled_rows(&mut self) -> Vec<RowId> {
        let mut rows = std::mem::take(&mut self.recycled.rows);
        rows.clear();
        rows
    }

    /// An empty list of names for a new reason, in a kept buffer where there is one.
    pub fn recycled_names(&mut self) -> Vec<String> {
        std::mem::take(&mut self.recycled.names)
    }

    /// `reason` boxed, in a kept box where there is one.
    pub fn recycled_box(&mut self, reason: Reason) -> Box<Reason> {
        match self.recycled.boxes.pop() {
            Some(mut b) => {
                *b = reason;
                b
            }
            None => Box::new(reason),
        }
    }

    /// Whether the status is optimal (at full or reduced accuracy).
    pub fn is_optimal(&self) -> bool {
        self.status.has_answer()
    }
}

/// A starting point for a solve.
#[derive(Clone, Copy, Debug, Default)]
pub struct WarmStart<'a> {
    /// An initial torque (used when feasible, otherwise as a starting guess).
    pub torque: Option<&'a [f64]>,
    /// An initial key constraint set (linear rows), such as a previous answer's.
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

    /// Whether this starts from anything.
    pub fn is_cold(&self) -> bool {
        self.torque.is_none() && self.active_set.is_none()
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
        /// Linear rows.
        rows: usize,
    },
    /// A wrench component outside the input domain (the same bound as a problem
    /// file's wrench: [`crate::problem::in_domain`]).
    #[error("wrench[{index}]: expected {}, got {value:e}", crate::problem::DOMAIN)]
    Wrench {
        /// Component.
        index: usize,
        /// Its value.
        value: f64,
    },
}

/// What a backend can do, so that the facade chooses without knowing backends.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Capabilities {
    /// Solves exact (second-order) cones.
    pub exact_cones: bool,
    /// Optimises free passive internal forces.
    pub free_internal_forces: bool,
    /// Warm-starts from a key constraint set.
    pub warm_key_set: bool,
    /// Warm-starts from a torque.
    pub warm_torque: bool,
    /// Checks every row of an answer from scratch before calling it optimal (primal
    /// feasibility in its own coordinates, or a conic certificate), so that
    /// [`Check::Lazy`] may defer the core's independent check.
    pub certifies_rows: bool,
}

/// A QP backend. Built once per grasp (it may factor and cache what depends only on
/// the grasp), then solved for any number of wrenches without allocating.
pub trait TorqueSolver: Send {
    /// The backend's name, as used on the command line.
    fn name(&self) -> &'static str;

    /// What this backend supports.
    fn capabilities(&self) -> Capabilities;

    /// The backend's accuracy: the relative tolerance of the core's final residual check.
    fn residual_tolerance(&self) -> f64;

    /// The problem this solver was built for.
    fn problem(&self) -> &TorqueQp;

    /// Solves for `wrench`: sets `status`, `reason`, `torque`, `internal_forces`,
    /// `iterations`, `active_set` and `multipliers` of `out`, reusing its buffers.
    /// Inputs have been checked by [`solve_into`], which also fills the rest.
    fn solve_raw(&mut self, wrench: &[f64; 6], warm: &WarmStart<'_>, out: &mut Solution);

    /// A second answer for `wrench`, by a method of the backend's own that does not
    /// share the first's path, after [`Self::solve_raw`]'s answer failed the core's
    /// residual check; sets `out` as `solve_raw` does. `false` (and `out` untouched)
    /// where the backend has none, the default. The core checks it as it checked the
    /// first. The native solvers' interior-point method is one: Newton's method stops
    /// on a point its certificate admits, measured against the size of every row's
    /// terms, and the active-set method on one its rows normalised in y admit, both of
    /// which the core can refuse against the contact forces' scale.
    fn solve_fallback(&mut self, wrench: &[f64; 6], out: &mut Solution) -> bool {
        let _ = (wrench, out);
        false
    }
}

/// How much of an answer the core completes and checks after the backend's solve.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Check {
    /// On every solve: the contact forces, σ, every residual and margin, and the core's
    /// independent check of the physics (`G f = w`, `Jᵀ f = τ`, `C τ = e`, and the rows
    /// and cones at f).
    #[default]
    Full,
    /// The control-loop form, for a backend that certifies its rows
    /// ([`Capabilities::certifies_rows`]). `optimal` rests on the backend's from-scratch
    /// check of every row (torque limits included), with the core's check that σ, and
    /// so τ, is finite. The forces, the residuals and the core's independent check wait for
    /// [`TorqueQp::complete`] (`GraspSolver::diagnose`), which may still turn the answer
    /// into a numerical failure. Other backends, the paper model, and answers that are
    /// not optimal or not finite get the full check. The solve is not timed
    /// ([`Solution::solve_time`] is zero): a control loop times its own tick.
    Lazy,
}

impl Check {
    /// `full` or `lazy`.
    pub fn as_str(&self) -> &'static str {
        match self {
            Check::Full => "full",
            Check::Lazy => "lazy",
        }
    }
}

impl std::str::FromStr for Check {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "full" => Ok(Check::Full),
            "lazy" => Ok(Check::Lazy),
            _ => Err(format!("unknown check {s:?}: expected full or lazy")),
        }
    }
}

impl fmt::Display for Check {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Solves with any backend and completes the answer with forces, objective and
/// diagnostics, then checks it ([`Check::Full`]). Reuses `out`'s buffers: no
/// allocation once they have grown to size, an infeasible answer's reason included
/// ([`Solution::recycled`]; warnings and the messages of answers that are not ones
/// aside).
pub fn solve_into(
    solver: &mut dyn TorqueSolver,
    wrench: &[f64; 6],
    warm: &WarmStart<'_>,
    out: &mut Solution,
) -> Result<(), WarmStartError> {
    solve_into_with(solver, wrench, warm, Check::Full, out)
}

/// [`solve_into`] with the core's part chosen by `check`.
pub fn solve_into_with(
    solver: &mut dyn TorqueSolver,
    wrench: &[f64; 6],
    warm: &WarmStart<'_>,
    check: Check,
    out: &mut Solution,
) -> Result<(), WarmStartError> {
    let qp = solver.problem();
    check_inputs(qp, wrench, warm)?;
    // Two clock reads cost more than the lazy check itself on the smallest grasps.
    let start = (check == Check::Full).then(Instant::now);
    out.warnings.clear();
    out.recycle_reason();
    out.multipliers.clear();
    out.internal_forces.clear();
    out.method = None;
    // Only a model with wrench directions no torque reaches has rows to test.
    let residual = match qp.model.unreachable.nrows() {
        0 => 0.0,
        _ => qp.model.unreachable_residual(wrench),
    };
    if residual > 0.0 && residual > qp.model.unreachable_tolerance(wrench) {
        out.status = Status::Infeasible;
        out.reason = Some(Reason::UnreachableWrench { residual });
        out.torque.clear();
        out.iterations = 0;
        out.recycle_active_set();
    } else {
        backend_solve(solver, wrench, warm, false, out);
    }
    out.solve_time = start.map_or(Duration::ZERO, |t| t.elapsed());
    let tol = solver.residual_tolerance();
    let lazy = check == Check::Lazy && solver.capabilities().certifies_rows;
    let qp = solver.problem();
    if !(lazy && qp.complete_lazy(tol, out)) {
        qp.complete(wrench, tol, solver.name(), out);
    }
    if refused(out) {
        fall_back_after_refusal(solver, wrench, warm, start, out);
    }
    let qp = solver.problem();
    note_torque_spread(qp, out);
    if let Some(a) = &qp.model.actuators {
        if out.status == Status::Infeasible && a.unactuated_directions.nrows() > 0 {
            if let Some(cause) = out.reason.take() {
                let mut unactuated = out.recycled_names();
                unactuated.clone_from(&a.unactuated_description);
                out.reason = Some(Reason::Underactuated {
                    unactuated,
                    cause: out.recycled_box(cause),
                });
            }
        }
    }
    Ok(())
}

/// Completes an answer whose check [`Check::Lazy`] deferred, as [`solve_into_with`]
/// with [`Check::Full`] would have: the core's residual check, then, where it refuses
/// the answer, the backend's fallback checked likewise. `wrench` is the one solved for.
pub fn complete_deferred(solver: &mut dyn TorqueSolver, wrench: &[f64; 6], out: &mut Solution) {
    if !out.diagnostics.deferred {
        return;
    }
    let tol = solver.residual_tolerance();
    solver.problem().complete(wrench, tol, solver.name(), out);
    if refused(out) {
        fall_back_after_refusal(solver, wrench, &WarmStart::default(), None, out);
    }
    note_torque_spread(solver.problem(), out);
}

/// The spread of the torques' scales ([`crate::GraspModel::torque_spread`]) beyond
/// which a grasp without an answer says so: 8 of the 9 no-answers of `fuzz_answers.py
/// 234500 3000` had spreads of 2.1e7 to 2.2e9 (the ninth, a near-passive internal
/// force, of 3), and all 15 of `237500 4000` spreads of 5.3e5 or more, while real
/// hands' are below 1e3 (revolute joints beside prismatic ones, in metres).
pub const TORQUE_SPREAD_NOTE: f64 = 1e4;

/// A warning on an answer that is not one (`numerical_failure`, `iteration_limit`)
/// where the torques' scales are more than [`TORQUE_SPREAD_NOTE`] apart: a likely
/// cause, and what avoids it. (Only on those statuses: no cost to a solve that
/// answers.)
#[cold]
fn note_torque_spread(qp: &TorqueQp, out: &mut Solution) {
    if !matches!(
        out.status,
        Status::NumericalFailure | Status::IterationLimit
    ) {
        return;
    }
    let model = &*qp.model;
    let Some([(hi, big), (lo, small)]) = model.torque_spread() else {
        return;
    };
    if big > TORQUE_SPREAD_NOTE * small {
        out.warnings.push(format!(
            "the torques' scales in the objective (√w_j Σ_i |Jᵀ_ji|, mz as mz/mu_torsion) are {:.1e} apart: {} at {big:.3e}, {} at {small:.3e}; the smaller torques are then near the rounding of the larger, a common cause of this status (docs/solver.md, \"Limits\"): torques in comparable units, or weights that balance the scales, avoid it",
            big / small,
            model.joint_name(hi),
            model.joint_name(lo),
        ));
    }
}

/// Whether the core's check refused an answer the backend called optimal.
fn refused(out: &Solution) -> bool {
    out.status == Status::NumericalFailure
        && matches!(out.reason, Some(Reason::ResidualCheck { .. }))
}

/// An answer the backend called optimal and the check refused ([`refused`]): the
/// backend's fallback, if it has one, checked in full likewise. Where that gives no
/// answer either, the first refusal is the report (its figures say what failed). (The
/// copy is made only here, after a refusal.) `start`: the solve's clock, if timed.
#[cold]
fn fall_back_after_refusal(
    solver: &mut dyn TorqueSolver,
    wrench: &[f64; 6],
    warm: &WarmStart<'_>,
    start: Option<Instant>,
    out: &mut Solution,
) {
    let first = out.clone();
    out.warnings.clear();
    out.reason = None;
    out.multipliers.clear();
    if !backend_solve(solver, wrench, warm, true, out) {
        *out = first;
        return;
    }
    if let Some(t) = start {
        out.solve_time = t.elapsed();
    }
    let tol = solver.residual_tolerance();
    solver.problem().complete(wrench, tol, solver.name(), out);
    let method = out.method.unwrap_or("another method");
    let note = if out.status.has_answer() {
        out.iterations += first.iterations;
        format!(
            "{}'s first answer failed the residual check; this one is its fallback's ({method})",
            solver.name()
        )
    } else {
        let status = out.status;
        *out = first;
        format!(
            "{}'s fallback ({method}) gave no answer either ({status})",
            solver.name()
        )
    };
    out.warnings.push(note);
}

/// The backend's solve ([`TorqueSolver::solve_raw`], or with `fallback` its
/// [`TorqueSolver::solve_fallback`], whose return this is) in the backend's variable
/// `v = u − u_p` where the model has passive torques (model::Passive): a warm start's
/// torque goes in shifted (in the joint torques' buffer, which the check refills), the
/// answer comes out shifted back.
fn backend_solve(
    solver: &mut dyn TorqueSolver,
    wrench: &[f64; 6],
    warm: &WarmStart<'_>,
    fallback: bool,
    out: &mut Solution,
) -> bool {
    let run = |solver: &mut dyn TorqueSolver, warm: &WarmStart<'_>, out: &mut Solution| {
        if fallback {
            solver.solve_fallback(wrench, out)
        } else {
            solver.solve_raw(wrench, warm, out);
            true
        }
    };
    if solver.problem().model.passive.is_empty() {
        return run(solver, warm, out);
    }
    let mut shifted = std::mem::take(&mut out.joint_torque);
    let solved = {
        let offset = &solver.problem().model.passive.torque_offset;
        let warm = match warm.torque {
            Some(t) => {
                shifted.clear();
                shifted.extend(t.iter().zip(offset).map(|(t, o)| t - o));
                WarmStart {
                    torque: Some(&shifted),
                    active_set: warm.active_set,
                }
            }
            None => *warm,
        };
        run(solver, &warm, out)
    };
    out.joint_torque = shifted;
    let offset = &solver.problem().model.passive.torque_offset;
    if solved && out.torque.len() == offset.len() {
        out.torque.iter_mut().zip(offset).for_each(|(t, o)| *t += o);
    }
    solved
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
    if let Some(index) = w.iter().position(|v| !crate::problem::in_domain(*v)) {
        return Err(WarmStartError::Wrench {
            index,
            value: w[index],
        });
    }
    if let Some(t) = warm.torque {
        if t.len() != qp.joints() {
            return Err(WarmStartError::TorqueLength {
                expected: qp.joints(),
                found: t.len(),
            });
        }
        if !all_finite(t) {
            let index = t.iter().position(|v| !v.is_finite()).unwrap_or(0);
            return Err(WarmStartError::TorqueNotFinite { index });
        }
    }
    if let Some(a) = warm.active_set {
        let rows = qp.inequality_rows();
        // The largest index first, without a branch per entry (the control loop's path).
        if a.iter().fold(0, |m, &r| m.max(r)) >= rows {
            let row = a.iter().copied().find(|&r| r >= rows).unwrap_or(rows);
            return Err(WarmStartError::ActiveSetRow { row, rows });
        }
    }
    Ok(())
}

impl Diagnostics {
    /// Zero, with the margins' buffer kept.
    fn clear(&mut self) {
        self.deferred = false;
        self.wrench_residual = 0.0;
        self.torque_residual = 0.0;
        self.consistency_residual = 0.0;
        self.max_violation = 0.0;
        self.cone_violation = 0.0;
        self.friction_margins.clear();
        self.check_tolerance = 0.0;
        self.wrench_check = 0.0;
        self.torque_check = 0.0;
        self.violation_check = 0.0;
        self.cone_check = 0.0;
    }
}

impl TorqueQp {
    /// The relative tolerance of the core's checks for a backend of accuracy `tol`: an
    /// accepted wrench may be off the reachable set by the rank decision.
    fn check_tolerance(&self, tol: f64) -> f64 {
        tol.max(10.0 * self.model.rank_tolerance)
    }

    /// `σ = Σ w_j τ_j²` (eq. 40).
    fn objective(&self, tau: &[f64]) -> f64 {
        tau.iter()
            .zip(&self.model.weights)
            .map(|(t, wj)| wj * t * t)
            .sum()
    }

    /// The largest violation `c_i − H_i τ` of the torque-limit rows, and whether one
    /// exceeds `tol` relative to its terms: the rows `τ_j ≥ lower` and `−τ_j ≥ −upper`
    /// (TorqueQp::new) are violated by `lower − τ_j` and `τ_j − upper`. Each τ_j comes
    /// out of the solver's linear algebra with an error relative to the largest torque,
    /// which joins the terms: a bound at 0 (a tendon that only pulls) has no other.
    fn limit_violation(&self, tau: &[f64], tol: f64, ratio: &mut WorstRatio) -> (f64, bool) {
        // (An open side is infinite: never violated, its bound infinite. A NaN torque
        // is the caller's finiteness check's.)
        let mut viol = f64::NEG_INFINITY;
        for &(j, lo, hi) in self.limits() {
            viol = viol.max(lo - tau[j]).max(tau[j] - hi);
        }
        if viol <= 0.0 {
            return (viol, false);
        }
        let scale = norm_inf(tau);
        let mut bad = false;
        for &(j, lo, hi) in self.limits() {
            let t = tau[j];
            let terms = t.abs() + scale;
            for (v, bound) in [
                (lo - t, tol * (lo.abs() + terms)),
                (t - hi, tol * (hi.abs() + terms)),
            ] {
                bad |= exceeds(v, bound);
                if v > 0.0 {
                    ratio.add(v, bound);
                }
            }
        }
        (viol, bad)
    }

    /// Puts each torque that misses a limit by no more than the check's tolerance on
    /// that limit ([`Self::limit_violation`]'s measure, but with the other torques for
    /// the error's scale, below). A backend ends on
    /// an active limit only to rounding, or to its tolerance (an interior-point
    /// method), and a tendon that only pulls (upper limit 0) must not be reported
    /// pushing by 5e-18. A torque further out is left for the check to refuse. The
    /// error's scale is the limit and the other torques, not the torque itself: a
    /// torque of 1e300 is not a rounding of a limit of 5.
    fn snap_to_limits(&self, tau: &mut [f64], tol: f64) {
        if self.limits().is_empty() {
            return;
        }
        // The two largest magnitudes: the largest but τ_j's own, for every j.
        let (mut first, mut second, mut at) = (0.0f64, 0.0f64, usize::MAX);
        for (j, t) in tau.iter().enumerate() {
            let a = t.abs();
            if a > first {
                (second, first, at) = (first, a, j);
            } else if a > second {
                second = a;
            }
        }
        for &(j, lo, hi) in self.limits() {
            let t = tau[j];
            let terms = if j == at { second } else { first };
            if t < lo && !exceeds(lo - t, tol * (lo.abs() + terms)) {
                tau[j] = lo;
            } else if t > hi && !exceeds(t - hi, tol * (hi.abs() + terms)) {
                tau[j] = hi;
            }
        }
    }

    /// What [`Check::Lazy`] keeps of [`Self::complete`] for an optimal answer of a
    /// backend that certified its rows (the torque limits among them): σ, which must
    /// be finite, so τ is. Returns false, with `out` untouched but for σ, when the full
    /// check must run instead: an answer that is not optimal or not finite, or the
    /// paper model (whose warning needs the residual).
    pub fn complete_lazy(&self, tol: f64, out: &mut Solution) -> bool {
        if !out.status.has_answer() || self.model.equilibrium == Equilibrium::PaperModel {
            return false;
        }
        let tol = self.check_tolerance(tol);
        self.snap_to_limits(&mut out.torque, tol);
        out.objective = self.objective(&out.torque);
        if !out.objective.is_finite() {
            return false;
        }
        out.contact_forces.clear();
        out.joint_torque.clear();
        let d = &mut out.diagnostics;
        d.clear();
        d.deferred = true;
        d.check_tolerance = tol;
        true
    }

    /// Fills forces, objective and diagnostics of `out` from its torque, and turns an
    /// answer that fails the residual check at relative tolerance `tol` into a
    /// numerical failure.
    pub fn complete(&self, w: &[f64; 6], tol: f64, backend: &'static str, out: &mut Solution) {
        let model = &*self.model;
        let n = model.force_dim();
        let d = &mut out.diagnostics;
        d.clear();
        // An accepted wrench may be off the reachable set by the rank decision.
        let tol = self.check_tolerance(tol);
        d.check_tolerance = tol;
        if out.torque.is_empty() {
            out.contact_forces.clear();
            out.joint_torque.clear();
            out.objective = 0.0;
            return;
        }
        if out.status.has_answer() {
            self.snap_to_limits(&mut out.torque, tol);
        }
        let tau = &out.torque;
        out.contact_forces.resize(n, 0.0);
        model.forces_into(w, tau, &out.internal_forces, &mut out.contact_forces);
        let f = &out.contact_forces;
        out.objective = self.objective(tau);
        // Residuals are judged against the problem's own scale, so the check is the
        // same in any units: the largest contact force F (with mz counted as
        // mz/mu_torsion), seen through the row (Σ_j |a_j| · force_unit_j · F), plus the
        // row's own right-hand side. Two floors: the wrench component the rank decision
        // let through, and the rounding of f = Z1 w + Z2 τ + N ξ itself (computed only
        // for a row that fails without it).
        let fmax = f
            .iter()
            .zip(&model.force_unit_inv)
            .fold(0.0f64, |a, (v, u)| a.max((v * u).abs()));
        let admitted = model.unreachable_tolerance(w);
        let rounding = 1e3 * f64::EPSILON * (6 + model.joints() + model.passive_dim()) as f64;
        // The rows of A = [G; E; Jᵀ] against their targets [w; Q₂ᵀ τ_p; τ + T⁺ τ_p]
        // (model::Passive), a block of rows at a time down the columns of A (no buffer
        // as long as A).
        let (mut wres, mut wbad, mut wratio) = (0.0f64, false, WorstRatio::NONE);
        let (mut tres, mut tbad, mut tratio) = (0.0f64, false, WorstRatio::NONE);
        let (k, rows) = (model.unactuated.nrows(), model.row_scale.len());
        let mut buf = [0.0f64; CHECK_BLOCK];
        for first in (0..rows).step_by(CHECK_BLOCK) {
            let af = &mut buf[..CHECK_BLOCK.min(rows - first)];
            af.fill(0.0);
            add_column_block(af, &model.stacked_cols, rows, first, f, 1.0);
            for (i, &ai) in (first..).zip(af.iter()) {
                let passive = model.passive.row_targets.get(i.wrapping_sub(6));
                let target = match i {
                    0..6 => w[i],
                    _ if i < 6 + k => passive.copied().unwrap_or(0.0),
                    _ => tau[i - 6 - k] + passive.copied().unwrap_or(0.0),
                };
                let r = (ai - target).abs();
                let ri = model.row_scale[i];
                // In equilibrated units (× row_scale_i), which saves a division.
                let mut bound = tol * (target.abs() + model.row_reach[i] * fmax) * ri + admitted;
                let bad = exceeds(r * ri, bound) && {
                    let row = model.stacked_row(i);
                    bound +=
                        rounding * model.force_terms_dot(row, w, tau, &out.internal_forces) * ri;
                    exceeds(r * ri, bound)
                };
                let (res, worst, ratio) = if i < 6 {
                    (&mut wres, &mut wbad, &mut wratio)
                } else {
                    (&mut tres, &mut tbad, &mut tratio)
                };
                *res = res.max(r);
                *worst |= bad;
                if r > 0.0 {
                    ratio.add(r * ri, bound);
                }
            }
        }
        match &model.actuators {
            Some(a) => {
                out.joint_torque.resize(a.joints(), 0.0);
                a.joint_torques_into(tau, &mut out.joint_torque);
                // The user's equation, in joint space: Jᵀ f = T u + τ_p (the rows above
                // are its image under T⁺ and Q₂ᵀ), each row against the forces' and the
                // actuator forces' scales seen through it, `reach · F + ‖T_i‖₁ ‖u‖∞`
                // (the row's own terms |T_i| |u| were rounding on a joint no contact
                // loads whose actuators also drive loaded fingers, and the answer's
                // rounding, at ε ‖u‖∞, failed it).
                let tp = &model.passive.joint_torque;
                let umax = norm_inf(tau);
                for first in (0..a.joints()).step_by(CHECK_BLOCK) {
                    let len = CHECK_BLOCK.min(a.joints() - first);
                    let jf = &mut buf[..len];
                    jf.fill(0.0);
                    add_column_block(jf, &a.joint_jacobian_cols, a.joints(), first, f, 1.0);
                    let terms = a.transmission_reach[first..first + len]
                        .iter()
                        .map(|t| t * umax);
                    for ((i, &ji), tu) in (first..).zip(jf.iter()).zip(terms) {
                        let p = tp.get(i).copied().unwrap_or(0.0);
                        let t = out.joint_torque[i] + p;
                        let size = a.joint_reach[i] * fmax + tu + p.abs();
                        let r = (ji - t).abs();
                        tres = tres.max(r);
                        let bound = (tol + rounding) * size;
                        tbad |= exceeds(r, bound);
                        if r > 0.0 {
                            tratio.add(r, bound.max(f64::MIN_POSITIVE));
                        }
                    }
                }
            }
            None => out.joint_torque.clear(),
        }
        d.wrench_residual = wres;
        d.torque_residual = tres;
        d.wrench_check = wratio.value();
        d.torque_check = tratio.value();
        // C τ − e(w) = [C | eq_w] [τ; w], likewise by blocks.
        let (p, m) = (model.equality_rows(), model.joints());
        let mut consistency = 0.0f64;
        for first in (0..p).step_by(CHECK_BLOCK) {
            let ce = &mut buf[..CHECK_BLOCK.min(p - first)];
            ce.fill(0.0);
            add_column_block(ce, &model.eq_cols, p, first, tau, 1.0);
            add_column_block(ce, &model.eq_cols[m * p..], p, first, w, 1.0);
            // C u − e(w) = e_p with passive torques.
            if let Some(ep) = model.passive.eq_offset.get(first..first + ce.len()) {
                ce.iter_mut().zip(ep).for_each(|(v, e)| *v -= e);
            }
            consistency = ce.iter().fold(consistency, |a, v| a.max(v.abs()));
        }
        d.consistency_residual = consistency;
        // Force scale: the largest contact force, with mz measured as mz/mu_torsion.
        // Each contact's gauge g(f), once (kept in the margins' buffer until the margins
        // replace it below).
        let mut fscale = 0.0f64;
        for c in &self.contacts {
            let fc = &f[c.offset..c.offset + c.model.dim()];
            let g = c.model.gauge(fc);
            fscale = fscale.max(g.max(fc[c.model.normal_index()].abs()));
            d.friction_margins.push(Some(g));
        }
        // c − H τ = fmin − S f on contact rows (S is block-diagonal: a few flops per
        // row), and the limit rows read τ directly.
        // The size of the terms behind each of a contact's force components, which
        // bounds their rounding: a force that cancels to nearly zero (the passive
        // torques' against the actuators') keeps that of its terms. Only with passive
        // torques can every force be nearly zero beside terms of the torques' size:
        // without them, no wrench means no torque and no terms, and a loaded contact
        // sets the forces' scale. There, forces far below their terms are a Z that
        // spans many orders, whose answers such a floor admitted 1e-7 from nested
        // polygons' order (`fuzz_answers.py nested` seed 203045) and 2e-6 from other
        // units (seed 7401), where the check refused them before.
        let cancelled = !model.passive.is_empty();
        let contact_terms = |offset: usize, dim: usize| -> [f64; 4] {
            let mut t = [0.0; 4];
            for (k, v) in t[..dim].iter_mut().enumerate() {
                *v = model.force_terms(offset + k, w, tau, &out.internal_forces);
            }
            t
        };
        let mut viol = RowViolations {
            worst: 0.0,
            ratio: WorstRatio::NONE,
            passed: 0.0,
        };
        let mut vbad = false;
        for ((ci, c), repr) in self
            .contacts
            .iter()
            .enumerate()
            .zip(&self.constraints.cones)
        {
            let dim = c.model.dim();
            let fc = &f[c.offset..c.offset + dim];
            let fmin = model.min_normal_force[ci];
            // The exact cone's only linear row is its unit normal (fz ≥ f_min).
            let mut unit = [0.0; 4];
            let faces = match repr {
                ConeRepr::Inscribed(cone) => cone.faces.as_slice(),
                ConeRepr::Exact => {
                    unit[c.model.normal_index()] = 1.0;
                    &unit[..dim]
                }
            };
            // The rounding of `s · f`, through each component's terms (formed once).
            let mut terms = None;
            let mut floor = |s: &[f64]| -> f64 {
                if !cancelled {
                    return 0.0;
                }
                let t = terms.get_or_insert_with(|| contact_terms(c.offset, dim));
                rounding * s.iter().zip(&*t).map(|(s, t)| s.abs() * t).sum::<f64>()
            };
            let bad = match dim {
                1 => cone_rows::<1>(faces, fc, fmin, tol, fscale, &mut floor, &mut viol),
                3 => cone_rows::<3>(faces, fc, fmin, tol, fscale, &mut floor, &mut viol),
                _ => cone_rows::<4>(faces, fc, fmin, tol, fscale, &mut floor, &mut viol),
            };
            vbad |= bad;
        }
        if viol.passed > 0.0 {
            viol.ratio.add(viol.passed, tol * fscale);
        }
        let (limit, limit_bad) = self.limit_violation(tau, tol, &mut viol.ratio);
        vbad |= limit_bad;
        d.max_violation = viol.worst.max(limit).max(0.0);
        d.violation_check = viol.ratio.value();
        let (mut cone, mut cratio) = (0.0f64, WorstRatio::NONE);
        // A contact whose force is rounding noise next to the largest has no margin.
        let zero = 1e3 * f64::EPSILON * (n as f64) * fscale;
        for ((c, repr), m) in self
            .contacts
            .iter()
            .zip(&self.constraints.cones)
            .zip(d.friction_margins.iter_mut())
        {
            let fz = f[c.offset + c.model.normal_index()];
            let g = m.unwrap_or(0.0);
            if let ConeRepr::Exact = repr {
                cone = cone.max(g - fz);
                let mut bound = tol * fscale.max(f64::MIN_POSITIVE) * 10.0;
                if cancelled && exceeds(g - fz, bound) {
                    // The rounding of f: the gauge is a seminorm on the components
                    // (|g(f + e) − g(f)| ≤ g(e)), so g − fz moves by at most g of the
                    // components' terms plus fz's.
                    let t = contact_terms(c.offset, c.model.dim());
                    bound += rounding * (c.model.gauge(&t) + t[c.model.normal_index()]);
                }
                vbad |= exceeds(g - fz, bound);
                if g > fz {
                    cratio.add(g - fz, bound);
                }
            }
            // (fz − g)/max(|fz|, g): ContactModel::exact_margin.
            let size = fz.abs().max(g);
            *m = (size > zero).then(|| (fz - g) / size);
        }
        d.cone_violation = cone.max(0.0);
        d.cone_check = cratio.value();
        let paper = model.equilibrium == Equilibrium::PaperModel;
        if paper {
            let scale = norm_inf(w).max(norm_inf(f)).max(1.0);
            if d.wrench_residual > 1e-9 * scale {
                out.warnings.push(format!(
                    "paper model: these torques do not balance the wrench, ‖G f − w‖∞ = {:.6e}; drop --paper-model for physically consistent torques",
                    d.wrench_residual
                ));
            }
        }
        let finite = out.objective.is_finite()
            && f.iter().all(|v| v.is_finite())
            && tau.iter().all(|v| v.is_finite());
        // The paper model balances neither the wrench nor the torques (it warns instead).
        let failed = !finite || (!paper && (wbad || tbad)) || vbad;
        if out.status.has_answer() && failed {
            out.status = Status::NumericalFailure;
            out.reason = Some(Reason::ResidualCheck {
                wrench_residual: d.wrench_residual,
                torque_residual: d.torque_residual,
                violation: d.max_violation.max(d.cone_violation),
                tolerance: tol,
                checks: [
                    d.wrench_check,
                    d.torque_check,
                    d.violation_check.max(d.cone_check),
                ],
            });
            out.warnings.push(format!(
                "{backend} called this answer optimal, but it failed the residual check"
            ));
        }
    }
}
