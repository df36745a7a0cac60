//! The grasp model: everything that depends on neither the wrench nor the cone
//! representation, built once per grasp and shared (`Send + Sync`, behind an `Arc`).
//!
//! With `A = [G; Jᵀ]`, the contact forces that produce `[w; τ]` are
//! `f = Z1 w + Z2 τ + N ξ` (eq. 31), where `N` spans the null space of A: the passive
//! internal forces, which neither the wrench nor any torque determines. How `ξ` is fixed
//! is a modelling choice ([`InternalForces`]):
//!
//! - [`InternalForces::Compliance`] (default): `Z = D⁻¹ (A D⁻¹)⁺`, the least-norm force in
//!   the metric `‖D f‖` with `D = 1` on force components and `1/mu_torsion` on `mz`.
//!   Every component of `D f` is a force, so the choice does not depend on the unit of
//!   length; it is the force of least elastic energy of contacts with equal
//!   translational and torsional compliance per unit of friction. `ξ = 0`.
//! - [`InternalForces::Euclidean`]: `Z = A⁺`, the paper's (eq. 31) and the reference
//!   set's; it mixes N and N·m, so with a null space it depends on the unit of length.
//! - [`InternalForces::Free`]: `ξ` is a decision variable, so only `G f = w`, `Jᵀ f = τ`
//!   and the cones bind: the least torque any internal force allows.
//!
//! `[w; τ]` must lie in the range of A for `G f = w` to hold. With `U⊥` spanning the
//! complement of the range of the row-equilibrated `R A D⁻¹`, that is `C τ = e(w)`; the
//! core decides the rank of C once and keeps independent rows only, so no backend
//! makes a rank decision of its own.

use crate::by_name::ByName;
use crate::contact::ContactModel;
use crate::error::ModelError;
use crate::linalg::{decompose, RankThreshold};
use crate::matrix::{add_columns, column_major, dot, norm2, norm_inf, write_columns, Matrix};
use crate::problem::{GraspProblem, TorqueLimit};
use serde::Serialize;

/// How the passive internal forces (the null space of `[G; Jᵀ]`) are fixed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum InternalForces {
    /// Least norm in the contact-compliance metric (`mz` measured as `mz/mu_torsion`):
    /// unit-invariant. The default.
    #[default]
    Compliance,
    /// Least Euclidean norm of f, the paper's `A⁺` (eq. 31). Depends on the unit of
    /// length when `[G; Jᵀ]` has a null space and a soft-finger contact.
    Euclidean,
    /// Optimised with the torques: the best case. Needs a backend that supports it.
    Free,
}

impl ByName for InternalForces {
    const VARIANTS: &'static [Self] = &[Self::Compliance, Self::Euclidean, Self::Free];
    const NAMES: &'static [&'static str] = &["compliance", "euclidean", "free"];
}
crate::deserialize_by_name!(InternalForces);

impl InternalForces {
    /// `compliance`, `euclidean` or `free`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Compliance => "compliance",
            Self::Euclidean => "euclidean",
            Self::Free => "free",
        }
    }
}

impl std::str::FromStr for InternalForces {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "compliance" => Ok(Self::Compliance),
            "euclidean" => Ok(Self::Euclidean),
            "free" => Ok(Self::Free),
            _ => Err(format!(
                "unknown `{s}`: expected `compliance`, `euclidean` or `free`"
            )),
        }
    }
}

/// Whether `C τ = e` is enforced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Equilibrium {
    /// Enforce `C τ = e`: every answer balances the wrench (`G f = w`). The default.
    #[default]
    Consistent,
    /// The paper's model as printed: `H τ ≥ c` alone. Its answers generally do not
    /// balance the wrench; each carries a warning with `‖G f − w‖∞`. For reproducing the
    /// paper's numbers only.
    PaperModel,
}

/// How the model is assembled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelOptions {
    /// Consistency equalities on (default) or the paper's model.
    pub equilibrium: Equilibrium,
    /// Relative rank tolerance for the pseudo-inverse and the consistency rows: singular
    /// values at or below `rank_tolerance · σ_max` of the row-equilibrated matrix count
    /// as zero, and so does a row of G or Jᵀ whose entries on every contact are at most
    /// `rank_tolerance` times the largest of its block's there (equilibration would
    /// make a unit row of it). Default `1e-9`, as in the reference implementation
    /// (`shared/reference/README.md`, item 1).
    pub rank_tolerance: f64,
}

impl Default for ModelOptions {
    fn default() -> Self {
        Self {
            equilibrium: Equilibrium::Consistent,
            rank_tolerance: 1e-9,
        }
    }
}

/// One grasp, ready for any cone representation and any wrench. Immutable once built.
#[derive(Clone, Debug)]
pub struct GraspModel {
    /// G, 6 × n.
    pub grasp_matrix: Matrix,
    /// Jᵀ, m × n, in the torques the solver chooses: `T⁺ Jᵀ` (a × n) with a
    /// transmission, so that `u = T⁺ Jᵀ f`.
    pub jacobian_transpose: Matrix,
    /// `E = Q₂ᵀ Jᵀ`, k × n: `E f = 0` keeps `Jᵀ f` in the range of T (Q₂ spans the joint
    /// torques no actuator produces). Empty without an underactuated transmission.
    pub unactuated: Matrix,
    /// The joint space behind an actuated model (`None` when T is absent or I).
    pub actuators: Option<ActuatorSpace>,
    /// The contacts, in the column order of G.
    pub contacts: Vec<ContactModel>,
    /// Index of each contact's first force component in f.
    pub offsets: Vec<usize>,
    /// Objective weights `w_j` (all 1 by default).
    pub weights: Vec<f64>,
    /// `|τ_j| ≤ t` or `lower ≤ τ_j ≤ upper`; `None` is unlimited.
    pub torque_limits: Vec<Option<TorqueLimit>>,
    /// `fz ≥ value` per contact (0 by default).
    pub min_normal_force: Vec<f64>,
    /// Names of the torques the solver chooses: actuators with a transmission, else
    /// joints (empty when unknown).
    pub joint_names: Vec<String>,
    /// How the passive internal forces are fixed.
    pub internal_forces: InternalForces,
    /// Consistent or paper model.
    pub equilibrium: Equilibrium,
    /// The rank tolerance used.
    pub rank_tolerance: f64,
    /// Z1, n × 6 (eq. 31).
    pub z1: Matrix,
    /// Z2, n × m (eq. 31).
    pub z2: Matrix,
    /// Numerical rank of `[G; Jᵀ]`.
    pub rank: usize,
    /// N, n × d: a basis of the passive internal forces (the null space of `[G; Jᵀ]`).
    pub passive_basis: Matrix,
    /// C, p × m with independent rows (empty in the paper model).
    pub eq: Matrix,
    /// C's factors: `C = Bᵀ diag(torque_scale)` with B (m × p, this) orthonormal.
    pub eq_basis: Matrix,
    /// An orthonormal basis of the null space of Bᵀ, m × (m − p), so that
    /// `C τ = 0 ⇔ torque_scale ⊙ τ ∈ range(eq_null)`. A backend that weights the
    /// torques finds the null space of its weighted C from it without a decomposition.
    pub eq_null: Matrix,
    /// `e(w) = −eq_w · w`, p × 6.
    pub eq_w: Matrix,
    /// `unreachable · w ≠ 0` means no torque satisfies `C τ = e(w)`, q × 6 (in
    /// equilibrated wrench units, see [`Self::wrench_scale`]).
    pub unreachable: Matrix,
    /// The row equilibration of the wrench rows of A: `w_i · wrench_scale_i` is
    /// unit-free up to one common force unit.
    pub wrench_scale: [f64; 6],
    /// The row equilibration of the torque rows of A, likewise.
    pub torque_scale: Vec<f64>,
    /// The row equilibration of the rows of E, likewise.
    pub unactuated_scale: Vec<f64>,
    /// Per force component, the length that turns it into a force: `mu_torsion` for
    /// `mz`, 1 otherwise. `|f_j| / force_unit_j` is in force units whatever the
    /// assumption, which makes the residual check unit-invariant.
    pub force_unit: Vec<f64>,
    /// `1 / force_unit`, for the hot path.
    pub force_unit_inv: Vec<f64>,
    /// Per row of `[G; E; Jᵀ]`, `Σ_j |a_ij| · force_unit_j`: how strongly a unit force
    /// (mz counted as mz/mu_torsion) reaches the row, for the residual check's scale.
    pub row_reach: Vec<f64>,
    /// The row equilibration of `[G; E; Jᵀ]`: [`Self::wrench_scale`], then
    /// [`Self::unactuated_scale`] and [`Self::torque_scale`].
    pub row_scale: Vec<f64>,
    /// `[G; E; Jᵀ]` column-major (force component j at `j · (6 + k + m)..`): the
    /// residual check forms `A f` in passes down columns.
    pub stacked_cols: Vec<f64>,
    /// `[C | eq_w]` column-major (p rows, m + 6 columns), for `C τ − e(w)` likewise.
    pub eq_cols: Vec<f64>,
    /// `[Z1 | Z2 | N]` column-major (n rows), for `f = Z1 w + Z2 τ + N ξ` in passes
    /// down columns.
    pub force_cols: Vec<f64>,
    /// The passive joint torques (joint space), empty without any.
    pub passive: Passive,
    /// Joints whose row of Jᵀ is nonzero but at most the rank tolerance of what the
    /// joints do with each contact it touches, which the model makes zero (a joint
    /// whose axis passes through its contact, whose kinematics left rounding in its
    /// row). Every answer holds the zero row instead (joint j's torque is 0, less any
    /// passive torque), so the given row's `Jᵀ_j f` is matched only to the rank
    /// tolerance of the largest joint's torque there, not to joint j's own scale. A
    /// joint whose torque is in a unit 1e9 times another's on the same contact lands
    /// here too.
    pub zeroed_joints: Vec<ZeroedJoint>,
}

/// What passive joint torques `τ_p` (`Jᵀ f = T u + τ_p`) add to the model: constants
/// in its equations, all empty without passive torques.
///
/// In the torques u, `[G; E; T⁺Jᵀ] f = [w; Q₂ᵀ τ_p; u + T⁺ τ_p]`, so that
/// `f = Z1 w + Z2 u + f_p` and `C u = e(w) + e_p`. The solvers see
/// `v = u − u_p` instead, with `u_p` the least `Σ w_j u_j²` solution of `C u_p = e_p`:
/// then `C v = e(w)` as without passive torques, the cone rows and limits only shift,
/// and the objective is unchanged up to a constant on the feasible set
/// (`u_pᵀ W v = λᵀ C v = λᵀ e(w)` because `W u_p = Cᵀ λ`). The core adds `u_p` back to
/// every answer, and takes it off a warm start.
#[derive(Clone, Debug, Default)]
pub struct Passive {
    /// `τ_p` per joint.
    pub joint_torque: Vec<f64>,
    /// The targets of the rows of E and Jᵀ: `[Q₂ᵀ τ_p; T⁺ τ_p]` (k + m).
    pub row_targets: Vec<f64>,
    /// `f_p`: the contact forces at `w = 0`, `u = 0`.
    pub force: Vec<f64>,
    /// The size of the terms behind each component of `f_p`, which bounds its rounding.
    pub force_terms: Vec<f64>,
    /// `u_p`, per torque variable.
    pub torque_offset: Vec<f64>,
    /// `f_p + Z2 u_p`: the contact forces at `w = 0`, `v = 0`.
    pub solver_force: Vec<f64>,
    /// The size of the terms behind each component of `solver_force`: its value is
    /// known to within their rounding, amplified by the conditioning of Z and of the
    /// consistency rows (up to 40 ε seen on a contact that no torque loads, whose
    /// components cancel to zero).
    pub solver_force_terms: Vec<f64>,
    /// `e_p`: `C u − e(w) = e_p`, per equality row.
    pub eq_offset: Vec<f64>,
    /// Added to `unreachable · w` (equilibrated units): a passive torque that no
    /// contact force can balance makes every wrench unreachable.
    pub unreachable_offset: Vec<f64>,
}

impl Passive {
    /// Whether there are passive torques.
    pub fn is_empty(&self) -> bool {
        self.joint_torque.is_empty()
    }
}

/// The joint space of a model whose torques are actuator forces: `τ = T u`.
#[derive(Clone, Debug)]
pub struct ActuatorSpace {
    /// T, m × a.
    pub transmission: Matrix,
    /// Jᵀ in joint space, m × n, with its negligible rows zero (rows that the rank
    /// decision would drop, contact by contact, in Jᵀ's own scale).
    pub joint_jacobian_transpose: Matrix,
    /// Joint names (empty when unknown).
    pub joint_names: Vec<String>,
    /// Q₂ᵀ, k × m: orthonormal joint-torque directions outside the range of T.
    pub unactuated_directions: Matrix,
    /// Jᵀ in joint space, column-major (m rows), for the residual check.
    pub joint_jacobian_cols: Vec<f64>,
    /// T column-major (m rows): `τ = T u`, for the residual check.
    pub transmission_cols: Vec<f64>,
    /// Per joint, `‖T_i‖₁`: the residual check judges row i against `‖T_i‖₁ ‖u‖∞`.
    pub transmission_reach: Vec<f64>,
    /// Per joint, `Σ_j |Jᵀ_ij| · force_unit_j` (as [`GraspModel::row_reach`]).
    pub joint_reach: Vec<f64>,
    /// [`Self::describe_unactuated`], once: an infeasible answer names the directions
    /// on every solve.
    pub unactuated_description: Vec<String>,
}

impl ActuatorSpace {
    /// Joints m.
    pub fn joints(&self) -> usize {
        self.transmission.nrows()
    }

    /// `τ = T u` into `out` (length m).
    pub fn joint_torques_into(&self, u: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        add_columns(out, &self.transmission_cols, u, 1.0);
    }

    /// The unactuated directions as joint combinations, for messages:
    /// `0.71·FFJ0 − 0.71·FFJ1` (terms below 1e-3 of the largest left out).
    pub fn describe_unactuated(&self) -> Vec<String> {
        let q = &self.unactuated_directions;
        (0..q.nrows())
            .map(|i| {
                let row = q.row(i);
                let big = row.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                let mut s = String::new();
                for (j, &v) in row.iter().enumerate() {
                    if v.abs() <= 1e-3 * big {
                        continue;
                    }
                    let name = self
                        .joint_names
                        .get(j)
                        .cloned()
                        .unwrap_or_else(|| format!("joint {j}"));
                    let sign = if v < 0.0 { "−" } else { "+" };
                    if s.is_empty() {
                        if v < 0.0 {
                            s.push('−');
                        }
                    } else {
                        s.push_str(&format!(" {sign} "));
                    }
                    s.push_str(&format!("{:.3}·{name}", v.abs()));
                }
                s
            })
            .collect()
    }
}

/// The rows of `[E; Jᵀ]`, their passive targets, and the joints whose rows were made
/// zero.
type ActuatorRows = (
    Matrix,
    Matrix,
    Option<ActuatorSpace>,
    Vec<f64>,
    Vec<ZeroedJoint>,
);

/// A joint whose row of Jᵀ the rank decision made zero ([`GraspModel::zeroed_joints`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZeroedJoint {
    /// The joint (a row of Jᵀ).
    pub joint: usize,
    /// Its row's largest entry over the largest of any joint's on the same contact, per
    /// contact, the most of these (mz counted as mz/mu_torsion): at most the rank
    /// tolerance.
    pub ratio: f64,
    /// The joint with that largest entry, on the contact where the ratio is taken.
    pub against: usize,
}

/// The decision rows `T⁺ Jᵀ`, the unactuated rows `Q₂ᵀ Jᵀ` and the joint space, or
/// `Jᵀ` itself without a transmission (or with `T = I`); and the passive torques' targets
/// of those rows, `[Q₂ᵀ τ_p; T⁺ τ_p]` (empty without passive torques).
///
/// A row that the rank decision would drop in its block's own scale is made exactly
/// zero ([`flush_rows`]): a joint that moves no contact (its axis through the contact,
/// say) whose kinematics left `1e-16` in its row. Row i of `M Jᵀ` is judged against
/// `Σ_k |M_ik|` times what the joints do with each contact.
fn actuator_space(
    p: &GraspProblem,
    unit: &[f64],
    cols: &[std::ops::Range<usize>],
    rank_tolerance: f64,
) -> Result<ActuatorRows, ModelError> {
    let n = p.force_dim();
    let jt = &p.jacobian_transpose;
    let mut scale = vec![0.0; n];
    contact_scales(jt, 0..jt.nrows(), unit, cols, &mut scale);
    let flush = |mut rows: Matrix, mix: &dyn Fn(usize) -> f64| {
        let all = 0..rows.nrows();
        flush_rows(&mut rows, all, unit, &scale, |i| rank_tolerance * mix(i));
        rows
    };
    // Joint space first: the core's check of `Jᵀ f = T u + τ_p` reads these rows, and
    // a row of rounding judged against its own size would fail on any force.
    let size = |i: usize, j: usize| (jt[(i, j)] * unit[j]).abs();
    let zeroed = (0..jt.nrows())
        .filter(|&i| negligible(jt, i, unit, &scale, rank_tolerance))
        .map(|joint| {
            // (A zero column's scale is 0, and so is the row's entry: that 0/0 is NaN,
            // which `max` passes over.)
            let (ratio, col) = (0..n).fold((0.0f64, 0), |(r, c), j| {
                let v = size(joint, j) / scale[j];
                if v > r {
                    (v, j)
                } else {
                    (r, c)
                }
            });
            let contact = cols
                .iter()
                .find(|c| c.contains(&col))
                .cloned()
                .unwrap_or(col..col + 1);
            let mut against = joint;
            for i in 0..jt.nrows() {
                if contact
                    .clone()
                    .any(|j| size(i, j) == scale[j] && scale[j] > 0.0)
                {
                    against = i;
                    break;
                }
            }
            ZeroedJoint {
                joint,
                ratio,
                against,
            }
        })
        .collect();
    let joint_rows = flush(jt.clone(), &|_| 1.0);
    let Some(t) = p.transmission.as_ref().filter(|t| !t.is_identity()) else {
        return Ok((
            joint_rows,
            Matrix::zeros(0, n),
            None,
            p.passive_torque.clone().unwrap_or_default(),
            zeroed,
        ));
    };
    let tm = &t.matrix;
    let (m, a) = (tm.nrows(), tm.ncols());
    let setting = rank_tolerance.to_bits();
    let (tplus, q2t) = match T_FACTORS.with(|c| c.borrow().get(tm, setting)) {
        Some(factors) => factors,
        None => {
            let dec = decompose(tm, RankThreshold::Relative(rank_tolerance)).map_err(|_| {
                ModelError::Decomposition {
                    what: "the transmission T",
                    rows: m,
                    cols: a,
                }
            })?;
            // T has independent columns (validated), so T⁺ T = I and u = T⁺ τ.
            let factors = (dec.pseudo_inverse(), dec.left_null.transpose());
            T_FACTORS.with(|c| c.borrow_mut().put(tm, setting, factors.clone()));
            factors
        }
    };
    let l1 = |m: &Matrix, i: usize| m.row(i).iter().map(|v| v.abs()).sum::<f64>();
    let jt = flush(tplus.matmul(&joint_rows), &|i| l1(&tplus, i));
    let unactuated = flush(q2t.matmul(&joint_rows), &|i| l1(&q2t, i));
    let targets = match &p.passive_torque {
        Some(tp) => (0..q2t.nrows())
            .map(|i| dot(q2t.row(i), tp))
            .chain((0..tplus.nrows()).map(|i| dot(tplus.row(i), tp)))
            .collect(),
        None => Vec::new(),
    };
    let mut space = ActuatorSpace {
        transmission: tm.clone(),
        joint_jacobian_cols: column_major(m, n, |i, j| joint_rows[(i, j)]),
        transmission_cols: column_major(m, a, |i, j| tm[(i, j)]),
        transmission_reach: (0..m)
            .map(|i| tm.row(i).iter().map(|v| v.abs()).sum())
            .collect(),
        joint_jacobian_transpose: joint_rows,
        joint_names: p.joint_names.clone(),
        unactuated_directions: q2t,
        // Filled by the model, which knows the force units.
        joint_reach: Vec::new(),
        unactuated_description: Vec::new(),
    };
    space.unactuated_description = space.describe_unactuated();
    Ok((jt, unactuated, Some(space), targets, zeroed))
}

thread_local! {
    /// `T⁺` and `Q₂ᵀ` of the last transmission this thread factored: a batch of grasps
    /// of one hand shares its T.
    static T_FACTORS: std::cell::RefCell<crate::matrix::LastMatrix<(Matrix, Matrix)>> =
        std::cell::RefCell::new(crate::matrix::LastMatrix::default());
}

/// Per column, the largest entry of `m`'s `rows` on its contact's columns (`cols`), in
/// the force metric (mz as mz/mu_torsion, so that a moment row's entries are all
/// lengths): the scale of what that block of rows does with that contact's force.
fn contact_scales(
    m: &Matrix,
    rows: std::ops::Range<usize>,
    unit: &[f64],
    cols: &[std::ops::Range<usize>],
    out: &mut [f64],
) {
    out.fill(0.0);
    for i in rows {
        for ((s, v), u) in out.iter_mut().zip(m.row(i)).zip(unit) {
            let a = (v * u).abs();
            if a > *s {
                *s = a;
            }
        }
    }
    for c in cols {
        let block = &mut out[c.clone()];
        let top = block.iter().fold(0.0f64, |a, &v| if v > a { v } else { a });
        block.fill(top);
    }
}

/// Whether row i of `m` does nothing with any contact's force beyond `t` times what its
/// block does with it (`scale`, per column, [`contact_scales`]), and is not zero
/// already: a row that the rank decision would drop, contact by contact, in the
/// block's own scale. Equilibrated, such a row (rounding, or a lever 1e-12 of the
/// others) became a unit row, a constraint as strong as any: a joint that moves no
/// contact made forces at a gain of 1/ε, with consistency rows 1e17 apart (an MJCF
/// hand, spatial-7 in fixtures/mjcf/oracle), and a pinch whose contact sat an
/// attometre off the line through the other and the object's origin could not hold
/// its object. Judged per contact, a row stays that matters for one contact though
/// another, far away, has levers 1e11 times larger. A block's rows scale alike in any
/// unit of force, torque or length, so the decision is unit-free.
fn negligible(m: &Matrix, i: usize, unit: &[f64], scale: &[f64], t: f64) -> bool {
    let mut nonzero = false;
    for ((v, u), s) in m.row(i).iter().zip(unit).zip(scale) {
        let a = (v * u).abs();
        if a > t * s {
            return false;
        }
        nonzero |= a != 0.0;
    }
    nonzero
}

/// Zeroes the [`negligible`] rows among `rows`, with `t = tol(i)`.
fn flush_rows(
    m: &mut Matrix,
    rows: std::ops::Range<usize>,
    unit: &[f64],
    scale: &[f64],
    tol: impl Fn(usize) -> f64,
) {
    for i in rows {
        if negligible(m, i, unit, scale, tol(i)) {
            m.row_mut(i).iter_mut().for_each(|v| *v = 0.0);
        }
    }
}

/// Row and column scales that equilibrate `m` (every row's and column's largest entry
/// near 1), by Ruiz's iteration from the scales `r`, `c`: each pass divides by the
/// square roots of the current largest entries, which halves the spread left in log
/// scale. Its passes stop at the first matrix whose rows and columns each have an
/// entry near 1, and which one that is depends on the start: the caller starts from
/// scales that leave the scaled matrix the same in any units. Zero rows and columns
/// keep their scales.
fn ruiz(m: &Matrix, mut r: Vec<f64>, mut c: Vec<f64>) -> (Vec<f64>, Vec<f64>) {
    let (rows, cols) = (m.nrows(), m.ncols());
    let (mut rmax, mut cmax) = (vec![0.0f64; rows], vec![0.0f64; cols]);
    for _ in 0..RUIZ_PASSES {
        rmax.fill(0.0);
        cmax.fill(0.0);
        for i in 0..rows {
            for (j, v) in m.row(i).iter().enumerate() {
                let a = (r[i] * v * c[j]).abs();
                rmax[i] = rmax[i].max(a);
                cmax[j] = cmax[j].max(a);
            }
        }
        let settled = |v: &f64| *v == 0.0 || (v - 1.0).abs() <= 0.1;
        if rmax.iter().all(settled) && cmax.iter().all(settled) {
            break;
        }
        for (s, v) in r.iter_mut().zip(&rmax).chain(c.iter_mut().zip(&cmax)) {
            if *v > 0.0 {
                *s /= v.sqrt();
            }
        }
    }
    (r, c)
}

/// Ruiz's passes at most: 53 binary orders of spread are within 10 % after 9.
const RUIZ_PASSES: usize = 12;

/// The largest spread of D's units measured in the contacts' levers (a torsion length
/// over the contact's levers in G, 1 for the forces) at which its rank decision is
/// taken as it stands, and the largest such unit at which a full-rank grasp's force
/// is still formed in D ([`metric_free_rank`]): at 1e6 m beside levers of
/// centimetres, the forces missed `G f = w` by 1e-8 of their terms. (Below the levers,
/// a short torsion length, D keeps mz to the precision its cone reads, and the
/// equilibrated matrix moved σ by 1e-9.) Measured in the levers, the decision is the
/// same in any unit of length.
const METRIC_SPREAD: f64 = 1e4;

/// The decomposition of `M = R_D A D⁻¹` (A = `[G; E; Jᵀ]`, rows scaled by `rd`,
/// columns by `dinv`: what `dec` decomposed) with the rank decided on `R A C`, R and C
/// from [`ruiz`], where D's units spread past [`METRIC_SPREAD`] and `dec` dropped a
/// direction that is not null there, or D has a unit past it; `None` otherwise.
///
/// A rank decided in the metric D depends on D's spread: with one contact's
/// `mu_torsion` at 1e8 m beside levers of centimetres, mz's column of M is 1e9 times
/// the forces', the forces' moments fell below the threshold, and a grasp of full rank
/// lost one direction and then two: σ rose by 14 % at 1e7, and at 1e8 `G f = w` missed
/// by 0.16 % of its terms, admitted as an unreachable wrench (fuzz_answers.py seed
/// 181261). The equilibrated decision reads no units and no metric. At full column
/// rank the force is unique and formed from `R A C`, R then the model's row scales (M
/// at that rank lost σ by 1.3e-6 at 1e9 m, and the exact cones' certificate failed);
/// with a null space, where the metric chooses the force, M is decomposed at that
/// rank.
fn metric_free_rank<'a>(
    a_row: &impl Fn(usize) -> &'a [f64],
    rd: &[f64],
    dinv: &[f64],
    levers: &[f64],
    dec: &crate::linalg::Decomposition,
    tol: f64,
) -> Result<Option<(Vec<f64>, crate::linalg::Decomposition)>, crate::linalg::SvdError> {
    let (rows, n, q) = (rd.len(), dinv.len(), dec.null_basis.ncols());
    // D's units against the contacts' levers, unit-free. Within METRIC_SPREAD, D moves
    // the decision by less than the threshold's margin.
    let (lo, hi) = dinv
        .iter()
        .zip(levers)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), (&u, &l)| {
            (lo.min(u / l), hi.max(u / l))
        });
    let (wide, long) = (hi > METRIC_SPREAD * lo, hi > METRIC_SPREAD);
    if !wide || q == 0 && !long {
        return Ok(None);
    }
    let mut data = Vec::with_capacity(rows * n);
    for i in 0..rows {
        data.extend_from_slice(a_row(i));
    }
    let a = Matrix::from_rows_data(rows, n, data);
    // Ruiz's passes start from mz counted in the contact's levers and each row then
    // scaled to a largest entry of 1: a change of the unit of length (or of any
    // joint's or wrench component's unit) leaves that matrix as it was, so the passes
    // and the decisions below read no unit. From unit scales they stopped at once with
    // lengths in megametres, where a soft finger's moment rows held their levers at
    // 5e-8 beside mz's entry of 1: G's smallest singular value fell with the unit
    // (5.8e-4 in metres, 5.8e-10 in megametres) and a consistency row fell below the
    // rank threshold (σ 1.34 against 7.80).
    let c0 = levers.to_vec();
    let r0 = (0..rows)
        .map(|i| {
            let top = a
                .row(i)
                .iter()
                .zip(&c0)
                .fold(0.0f64, |t, (v, cj)| t.max((v * cj).abs()));
            if top > 0.0 {
                1.0 / top
            } else {
                1.0
            }
        })
        .collect();
    let (r, c) = ruiz(&a, r0, c0);
    let eq = Matrix::from_fn(rows, n, |i, j| r[i] * a[(i, j)] * c[j]);
    let fro = norm2(eq.as_slice());
    // A dropped direction f is null when ‖R A f‖ is at most `tol σ_max(R A C)` ‖C⁻¹ f‖,
    // σ_max at most the Frobenius norm.
    let null = q > 0
        && (0..q).all(|k| {
            let f: Vec<f64> = (0..n).map(|j| dinv[j] * dec.null_basis[(j, k)]).collect();
            let h2: f64 = f.iter().zip(&c).map(|(v, cj)| (v / cj) * (v / cj)).sum();
            let res2: f64 = (0..rows).map(|i| (r[i] * dot(a.row(i), &f)).powi(2)).sum();
            res2 <= (tol * fro) * (tol * fro) * h2
        });
    if null {
        return Ok(None);
    }
    let eqd = decompose(&eq, RankThreshold::Relative(tol))?;
    let rank = eqd.rank();
    if rank < n - q || rank == n - q && q > 0 {
        return Ok(None);
    }
    if rank == n {
        // Full column rank: the force is unique, `Z = C A_s⁺ R`, with R the model's row
        // scales from here on and the forces in dec's coordinates, g = f / dinv.
        let mut zm = eqd.pseudo_inverse();
        for j in 0..n {
            let s = c[j] / dinv[j];
            zm.row_mut(j).iter_mut().for_each(|v| *v *= s);
        }
        return Ok(Some((
            r,
            crate::linalg::Decomposition {
                row_basis: Matrix::identity(n),
                row_transform: zm,
                null_basis: Matrix::zeros(n, 0),
                left_null: eqd.left_null,
            },
        )));
    }
    // A null space: the metric chooses the force, so M is decomposed, at that rank,
    // with a threshold between its rank-th and next singular values (none where they
    // are equal).
    let m = Matrix::from_fn(rows, n, |i, j| rd[i] * a[(i, j)] * dinv[j]);
    let s = crate::linalg::svd(&m)?.s;
    let threshold = match (s.get(rank - 1), s.get(rank)) {
        (Some(&last), Some(&next)) if next < last => (next * last).sqrt(),
        _ => return Ok(None),
    };
    let d = decompose(&m, RankThreshold::Absolute(threshold))?;
    Ok((d.rank() == rank).then(|| (rd.to_vec(), d)))
}

/// Per joint: a row of the consistency equalities' null basis (orthonormal, in the
/// equilibrated torques) at or below this times the joint count is rounding of a zero
/// row, a joint whose torque the equalities pin ([`GraspModel::eq_null`]). Pinned
/// joints' rows come out at 1e-17 to 1e-16; a thumb 1e11 m from the palm (its rows
/// of Jᵀ 1e12 times the others') has rows of 2e-13 to 7e-13 that the weighting makes
/// as large as the rest, so the bound stays below those. A row above it but within the
/// rank tolerance is rounding too where the joint's own row of A lies in the span of
/// [G; E]'s to within this times the force components (`pinned_by_its_row`).
pub const PINNED: f64 = 10.0 * f64::EPSILON;

/// Whether `row` (a joint's row of A, columns scaled by `dinv`) lies in the span of the
/// orthonormal columns of `basis` (the rows of [G; E], likewise scaled) to within
/// `tol` of its own norm: a joint whose torque the wrench alone fixes, up to the
/// rounding its row was formed with. (A thumb 1e11 m from the palm has rows 3.5e-13 to
/// 8.3e-13 of theirs out of that span, its torques' own response to the forces, 17
/// times the bound at least: not pinned.)
fn pinned_by_its_row(basis: &Matrix, row: &[f64], dinv: &[f64], tol: f64) -> bool {
    let a: Vec<f64> = row.iter().zip(dinv).map(|(a, d)| a * d).collect();
    let norm = norm2(&a);
    let mut rest = a.clone();
    for c in 0..basis.ncols() {
        let along: f64 = (0..a.len()).map(|i| basis[(i, c)] * a[i]).sum();
        for (i, r) in rest.iter_mut().enumerate() {
            *r -= along * basis[(i, c)];
        }
    }
    norm > 0.0 && norm2(&rest) <= tol * norm
}

/// Largest ratio between the norms of two rows of `[G; Jᵀ]` for which `euclidean`
/// keeps the plain A⁺: beyond it, its rounding grows with the ratio. Real hands in SI
/// units stay within about 100 (lever arms of centimetres against unit force rows).
const PLAIN_ROW_RATIO: f64 = 1e4;

impl GraspModel {
    /// Builds the model of a validated problem.
    pub fn new(p: &GraspProblem, opts: &ModelOptions) -> Result<Self, ModelError> {
        if !(opts.rank_tolerance > 0.0 && opts.rank_tolerance < 1.0) {
            return Err(ModelError::RankTolerance(opts.rank_tolerance));
        }
        let n = p.force_dim();
        // Column metric D: mz counts as mz/mu_torsion in the compliance metric.
        let mut force_unit = vec![1.0; n];
        let mut offsets = Vec::with_capacity(p.contacts.len());
        let mut off = 0;
        for c in &p.contacts {
            offsets.push(off);
            if let ContactModel::SfcLinear { mu_torsion, .. }
            | ContactModel::SfcElliptic { mu_torsion, .. } = *c
            {
                force_unit[off + 3] = mu_torsion;
            }
            off += c.dim();
        }
        let cols: Vec<_> = offsets
            .iter()
            .zip(&p.contacts)
            .map(|(&o, c)| o..o + c.dim())
            .collect();
        // Which rows are rounding is judged with mz counted in a unit no longer than the
        // contact's levers: mz/mu_torsion would make mz as strong as a force times
        // mu_torsion, and at 3e7 m beside levers of 3 cm every moment row no normal
        // has a component along (the pinch's moments about y and z) fell below its
        // block's scale and was dropped, the wrench's moment with it (`G f − w` 0.02
        // N·m on a moment of 0.02, answered `optimal`).
        // (`levers`: per column, the length its unit is measured against, 1 on forces.)
        let (mut flush_unit, mut levers) = (force_unit.clone(), vec![1.0; n]);
        for (&o, c) in offsets.iter().zip(&p.contacts) {
            if c.dim() == 4 {
                let top = |js: std::ops::Range<usize>| {
                    (3..6).fold(0.0f64, |a, i| {
                        js.clone()
                            .fold(a, |a, j| a.max(p.grasp_matrix[(i, j)].abs()))
                    })
                };
                let lever = top(o..o + 3) / top(o + 3..o + 4);
                if lever > 0.0 && lever.is_finite() {
                    levers[o + 3] = lever;
                    flush_unit[o + 3] = flush_unit[o + 3].min(lever);
                }
            }
        }
        let (jt, unactuated, mut actuators, row_targets, zeroed_joints) =
            actuator_space(p, &flush_unit, &cols, opts.rank_tolerance)?;
        let (k, m) = (unactuated.nrows(), jt.nrows());
        // G's force rows and its moment rows, each block likewise.
        let g = &p.grasp_matrix;
        let mut scales = vec![0.0; 2 * n];
        let (fs, ms) = scales.split_at_mut(n);
        contact_scales(g, 0..3, &flush_unit, &cols, fs);
        contact_scales(g, 3..6, &flush_unit, &cols, ms);
        let scale = |i: usize| &scales[i / 3 * n..(i / 3 + 1) * n];
        let tol = opts.rank_tolerance;
        let grasp = if (0..6).any(|i| negligible(g, i, &flush_unit, scale(i), tol)) {
            let mut g = g.clone();
            for b in [0..3, 3..6] {
                flush_rows(&mut g, b.clone(), &flush_unit, scale(b.start), |_| tol);
            }
            std::borrow::Cow::Owned(g)
        } else {
            std::borrow::Cow::Borrowed(g)
        };
        // Row i of A = [G; E; Jᵀ] (E: the unactuated directions, target 0), without
        // stacking a copy.
        let a_row = |i: usize| {
            if i < 6 {
                grasp.row(i)
            } else if i < 6 + k {
                unactuated.row(i - 6)
            } else {
                jt.row(i - 6 - k)
            }
        };
        let rows = 6 + k + m;
        let dinv = if p.internal_forces == InternalForces::Compliance {
            force_unit.clone()
        } else {
            vec![1.0; n]
        };
        // Row equilibration R: it leaves the range condition and the least-norm force of
        // a consistent [w; τ] unchanged (the solutions of R A f = R b are those of
        // A f = b), and makes the rank decision unit-free. The paper's plain A⁺
        // (`euclidean`, and the paper model's least squares, which depend on row
        // weights) keeps R = I, so that Z is eq. 49's, unless its rank decision is not
        // the equilibrated one (below).
        let mut scaled = vec![0.0; n];
        let mut row_norms = Vec::with_capacity(rows);
        for i in 0..rows {
            for ((s, x), d) in scaled.iter_mut().zip(a_row(i)).zip(&dinv) {
                *s = x * d;
            }
            row_norms.push(crate::matrix::norm2(&scaled));
        }
        // A zero row's target (a wrench component no contact can apply, a torque no
        // contact resists) is scaled as its block's rows are: the unreachable check then
        // reads it in their units. A zero torque row pins its joint, `τ_j = −τ_p,j`,
        // through the column of C that its scale makes, and C's rounding reaches τ_j
        // divided by that scale. At the block's largest norm (5e7, beside rows of 0.04:
        // `fuzz_answers.py` seed 296009) τ_j came out 4.5e-8 where it is 0, past its
        // limit at 0, and in other units a fixed row's check called the grasp
        // infeasible by 1.8e-8; at the smallest, the column outweighed the rest of C,
        // and two grasps whose rows spread by 2e7 and 3e9 lost their answers (seeds
        // 4803 and 3175). The geometric mean of the two keeps τ_j's rounding within
        // the square root of the spread of any other torque's, either way.
        let block_of = |i: usize| match i {
            0..3 => 0,
            3..6 => 1,
            _ if i < 6 + k => 2,
            _ => 3,
        };
        let (mut block_max, mut block_min) = ([0.0f64; 4], [f64::INFINITY; 4]);
        for (i, &nrm) in row_norms.iter().enumerate() {
            let b = block_of(i);
            block_max[b] = block_max[b].max(nrm);
            if nrm > 0.0 {
                block_min[b] = block_min[b].min(nrm);
            }
        }
        let zero_row_norm = |b: usize| match b {
            3 => (block_min[b] * block_max[b]).sqrt(),
            _ => block_max[b],
        };
        let decomposed = |equilibrate: bool| {
            let r: Vec<f64> = row_norms
                .iter()
                .enumerate()
                .map(
                    |(i, &nrm)| match (equilibrate, nrm > 0.0, zero_row_norm(block_of(i))) {
                        (false, ..) => 1.0,
                        (true, true, _) => 1.0 / nrm,
                        (true, false, b) if b > 0.0 && b.is_finite() => 1.0 / b,
                        _ => 1.0,
                    },
                )
                .collect();
            // R A D⁻¹.
            let mut data = Vec::with_capacity(rows * n);
            for (i, ri) in r.iter().enumerate() {
                data.extend(a_row(i).iter().zip(&dinv).map(|(a, d)| a * d * ri));
            }
            let mat = Matrix::from_rows_data(rows, n, data);
            decompose(&mat, RankThreshold::Relative(opts.rank_tolerance))
                .map(|dec| (r, dec))
                .map_err(|_| ModelError::Decomposition {
                    what: "[G; Jᵀ]",
                    rows,
                    cols: n,
                })
        };
        let consistent = opts.equilibrium == Equilibrium::Consistent;
        let (r, dec) = if consistent && p.internal_forces == InternalForces::Euclidean {
            // The plain A⁺ is kept only for rows of comparable size, and only where the
            // equilibrated matrix agrees that the directions it dropped are null:
            // torques in a unit 1e8 times the wrench's made hand3-pcwf's `[G; Jᵀ]` look
            // rank-deficient, and in one 1e8 times smaller left σ off by 4e-9.
            // Otherwise R A D⁻¹'s decomposition, whose Z agrees with A⁺ on every
            // consistent [w; τ].
            let (lo, hi) = row_norms
                .iter()
                .filter(|&&v| v > 0.0)
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                });
            let plain = (hi <= PLAIN_ROW_RATIO * lo)
                .then(|| decomposed(false))
                .transpose()?;
            let rows_fro = row_norms.iter().filter(|&&v| v > 0.0).count() as f64;
            let bound = opts.rank_tolerance * rows_fro.sqrt();
            let dropped_is_null = |dec: &crate::linalg::Decomposition| {
                let q = dec.null_basis.ncols();
                q == 0
                    || (0..rows).all(|i| {
                        (0..q).all(|k| {
                            let v: f64 = a_row(i)
                                .iter()
                                .zip(&dinv)
                                .zip(dec.null_basis.as_slice().chunks_exact(q))
                                .map(|((a, d), nrow)| a * d * nrow[k])
                                .sum();
                            v.abs() <= bound * row_norms[i]
                        })
                    })
            };
            match plain {
                Some((r, dec)) if dropped_is_null(&dec) => (r, dec),
                _ => decomposed(true)?,
            }
        } else {
            decomposed(consistent)?
        };
        let (r, dec) = match consistent {
            true => metric_free_rank(&a_row, &r, &dinv, &levers, &dec, opts.rank_tolerance)
                .map_err(|_| ModelError::Decomposition {
                    what: "[G; Jᵀ]",
                    rows,
                    cols: n,
                })?
                .unwrap_or((r, dec)),
            false => (r, dec),
        };
        let rank = dec.rank();
        let zm = dec.pseudo_inverse();
        // Z = D⁻¹ (R A D⁻¹)⁺ R, split into Z1 (wrench) and Z2 (torque); E's columns
        // multiply its zero target.
        let (mut z1, mut z2) = (Vec::with_capacity(n * 6), Vec::with_capacity(n * m));
        for (i, d) in dinv.iter().enumerate() {
            let (zw, zt) = (&zm.row(i)[..6], &zm.row(i)[6 + k..]);
            z1.extend(zw.iter().zip(&r[..6]).map(|(z, ri)| d * z * ri));
            z2.extend(zt.iter().zip(&r[6 + k..]).map(|(z, ri)| d * z * ri));
        }
        let (z1, z2) = (
            Matrix::from_rows_data(n, 6, z1),
            Matrix::from_rows_data(n, m, z2),
        );
        let passive_basis = Matrix::from_fn(n, n - rank, |i, k| dinv[i] * dec.null_basis[(i, k)]);
        // Passive torques: the targets [Q₂ᵀ τ_p; T⁺ τ_p] of E's and Jᵀ's rows, and the
        // force f_p = Z [0; those] they call for.
        // (With the size of each one's terms, which bounds its rounding.)
        let (passive_force, passive_terms): (Vec<f64>, Vec<f64>) = if row_targets.is_empty() {
            (Vec::new(), Vec::new())
        } else {
            (0..n)
                .map(|i| {
                    let terms = zm.row(i)[6..]
                        .iter()
                        .zip(&r[6..])
                        .zip(&row_targets)
                        .map(|((z, ri), t)| z * ri * t);
                    let (sum, size) = terms.fold((0.0, 0.0), |(s, a), t| (s + t, a + t.abs()));
                    (dinv[i] * sum, dinv[i] * size)
                })
                .unzip()
        };
        let mut wrench_scale = [1.0; 6];
        wrench_scale.copy_from_slice(&r[..6]);

        // The passive targets' part of each consistency row, and of each unreachable
        // row (equilibrated), by the same transforms as the wrench's.
        let (mut eq_passive, mut unreachable_offset) = (Vec::new(), Vec::new());
        let (eq, eq_w, unreachable, eq_basis, eq_null) = match opts.equilibrium {
            Equilibrium::PaperModel => (
                Matrix::zeros(0, m),
                Matrix::zeros(0, 6),
                Matrix::zeros(0, 6),
                Matrix::zeros(m, 0),
                Matrix::identity(m),
            ),
            Equilibrium::Consistent => {
                // U⊥ᵀ R [w; 0; τ] = 0 with x = R_τ τ: P_τ x = −P_w R_w w.
                let u = &dec.left_null;
                let p0 = u.ncols();
                let pw0 = Matrix::from_fn(p0, 6, |i, j| u[(j, i)]);
                let pt = Matrix::from_fn(p0, m, |i, j| u[(6 + k + j, i)]);
                // One rank decision for C: independent rows only. P_τ has orthonormal
                // origin (‖P_τ‖ ≤ 1), so the threshold is absolute.
                let dc =
                    decompose(&pt, RankThreshold::Absolute(opts.rank_tolerance)).map_err(|_| {
                        ModelError::Decomposition {
                            what: "the consistency equalities",
                            rows: p0,
                            cols: m,
                        }
                    })?;
                let rc = dc.rank();
                let eq = Matrix::from_fn(rc, m, |i, j| dc.row_basis[(j, i)] * r[6 + k + j]);
                let eq_w = Matrix::from_fn(rc, 6, |i, j| {
                    r[j] * (0..p0)
                        .map(|k| dc.row_transform[(i, k)] * pw0[(k, j)])
                        .sum::<f64>()
                });
                // Applied to the equilibrated wrench.
                let q = dc.left_null.ncols();
                let unreachable = Matrix::from_fn(q, 6, |i, j| {
                    (0..p0)
                        .map(|k| dc.left_null[(k, i)] * pw0[(k, j)])
                        .sum::<f64>()
                });
                if !row_targets.is_empty() {
                    // U⊥ᵀ R [0; targets], then through the same transforms: C τ' =
                    // −eq_w w − (this), and `unreachable` gains it.
                    let pp: Vec<f64> = (0..p0)
                        .map(|c| {
                            (0..k + m)
                                .map(|j| u[(6 + j, c)] * r[6 + j] * row_targets[j])
                                .sum::<f64>()
                        })
                        .collect();
                    eq_passive = (0..rc).map(|i| dot(dc.row_transform.row(i), &pp)).collect();
                    unreachable_offset = (0..q)
                        .map(|i| (0..p0).map(|c| dc.left_null[(c, i)] * pp[c]).sum::<f64>())
                        .collect();
                }
                // A joint the equalities pin (its torque a function of the wrench) has a
                // row of rounding in the null basis; it is zeroed, so that no method
                // moves that torque along it. The rows are of an orthonormal basis, so
                // the bound is absolute. Through `diag(g)` (the backends' weighted
                // torques) such a row grows as g does, and a joint whose moment arms
                // are 1e6 times the others' had a torque limit judged on a direction
                // of 1e-11 (fuzz seed 2866: a feasible pinch called infeasible).
                // A row above that bound is still one of rounding where the joint's
                // row of A lies in the span of [G; E]'s to within rounding of its own
                // (`pinned_by_its_row`): the decomposition's rounding, amplified by
                // A's conditioning, left rows of 3.2e-14 and 1.4e-13 on joints the data
                // pin to 1.7e-16 and 2.4e-16 of their rows (`fuzz_answers.py
                // pinned-limits` seeds 3141 and 3463: a limit at the pinned torque
                // raised σ by 2e-5 or made the grasp infeasible).
                let mut null = dc.null_basis;
                let pinned = PINNED * m as f64;
                let mut span = None;
                for j in 0..m {
                    let norm = crate::matrix::norm2(null.row(j));
                    let mut by_its_row = || {
                        let span = span.get_or_insert_with(|| {
                            let rows = Matrix::from_fn(6 + k, n, |i, c| a_row(i)[c] * dinv[c]);
                            decompose(&rows, RankThreshold::Relative(opts.rank_tolerance))
                                .map(|d| d.row_basis)
                        });
                        span.as_ref().is_ok_and(|basis| {
                            pinned_by_its_row(basis, a_row(6 + k + j), &dinv, PINNED * n as f64)
                        })
                    };
                    if norm <= pinned || (norm <= opts.rank_tolerance && by_its_row()) {
                        null.row_mut(j).iter_mut().for_each(|v| *v = 0.0);
                    }
                }
                (eq, eq_w, unreachable, dc.row_basis, null)
            }
        };
        let weights = p.torque_weights.clone().unwrap_or_else(|| vec![1.0; m]);
        let passive = match &p.passive_torque {
            None => Passive::default(),
            Some(tp) => {
                let eq_offset: Vec<f64> = eq_passive.iter().map(|v| -v).collect();
                // u_p = D⁻¹ (C D⁻¹)⁺ e_p with D = diag(√w): the least Σ w_j u_j². Each
                // row (with its e_p) is normalised first: the rows are independent, but
                // their scales span as many orders as the equilibration's (a joint with
                // a lever far below the others', scaled up: 1e6 apart on spatial-4's
                // case 4 in fixtures/mjcf/oracle), and a relative rank decision on the
                // raw rows dropped the small ones, so that u_p missed them.
                let mut torque_offset = vec![0.0; m];
                if eq.nrows() > 0 {
                    let dinv_w: Vec<f64> = weights.iter().map(|w| 1.0 / w.sqrt()).collect();
                    let mut cd = Matrix::from_fn(eq.nrows(), m, |i, j| eq[(i, j)] * dinv_w[j]);
                    let mut ep = eq_offset.clone();
                    for (i, e) in ep.iter_mut().enumerate() {
                        let row = cd.row_mut(i);
                        let nrm = norm2(row);
                        if nrm > 0.0 {
                            row.iter_mut().for_each(|v| *v /= nrm);
                            *e /= nrm;
                        }
                    }
                    let pinv = decompose(&cd, RankThreshold::Relative(1e-13))
                        .map_err(|_| ModelError::Decomposition {
                            what: "the consistency equalities",
                            rows: eq.nrows(),
                            cols: m,
                        })?
                        .pseudo_inverse();
                    for (j, t) in torque_offset.iter_mut().enumerate() {
                        *t = dinv_w[j] * dot(pinv.row(j), &ep);
                    }
                }
                // (With the size of each one's terms: see `solver_force_terms`.)
                let (solver_force, solver_force_terms) = (0..n)
                    .map(|i| {
                        let z = z2.row(i);
                        let size: f64 = z
                            .iter()
                            .zip(&torque_offset)
                            .map(|(z, u)| (z * u).abs())
                            .sum();
                        (
                            passive_force[i] + dot(z, &torque_offset),
                            passive_terms[i] + size,
                        )
                    })
                    .unzip();
                Passive {
                    joint_torque: tp.clone(),
                    row_targets,
                    force: passive_force,
                    force_terms: passive_terms,
                    torque_offset,
                    solver_force,
                    solver_force_terms,
                    eq_offset,
                    unreachable_offset,
                }
            }
        };
        let min_normal_force = p
            .min_normal_force
            .clone()
            .unwrap_or_else(|| vec![0.0; p.contacts.len()]);
        let joint_names = match (&actuators, &p.transmission) {
            (_, Some(t)) if !t.actuator_names.is_empty() => t.actuator_names.clone(),
            (Some(_), _) => (0..m).map(|j| format!("actuator {j}")).collect(),
            _ => p.joint_names.clone(),
        };
        let reach = |row: &[f64]| -> f64 {
            row.iter()
                .zip(&force_unit)
                .map(|(x, u)| (x * u).abs())
                .sum()
        };
        let row_reach = (0..rows).map(|i| reach(a_row(i))).collect();
        if let Some(a) = &mut actuators {
            let jt = &a.joint_jacobian_transpose;
            a.joint_reach = (0..jt.nrows()).map(|i| reach(jt.row(i))).collect();
        }
        let mut stacked_cols = vec![0.0; rows * n];
        write_columns(&p.grasp_matrix, &mut stacked_cols, rows);
        write_columns(&unactuated, &mut stacked_cols[6..], rows);
        write_columns(&jt, &mut stacked_cols[6 + k..], rows);
        let p_eq = eq.nrows();
        let mut eq_cols = vec![0.0; p_eq * (m + 6)];
        write_columns(&eq, &mut eq_cols, p_eq);
        write_columns(&eq_w, &mut eq_cols[p_eq * m..], p_eq);
        let mut force_cols = vec![0.0; n * (6 + m + passive_basis.ncols())];
        write_columns(&z1, &mut force_cols, n);
        write_columns(&z2, &mut force_cols[6 * n..], n);
        write_columns(&passive_basis, &mut force_cols[(6 + m) * n..], n);
        Ok(Self {
            force_cols,
            grasp_matrix: p.grasp_matrix.clone(),
            contacts: p.contacts.clone(),
            offsets,
            weights,
            passive,
            torque_limits: p.torque_limits.clone().unwrap_or_else(|| vec![None; m]),
            min_normal_force,
            joint_names,
            internal_forces: p.internal_forces,
            equilibrium: opts.equilibrium,
            rank_tolerance: opts.rank_tolerance,
            z1,
            z2,
            rank,
            passive_basis,
            eq,
            eq_w,
            eq_basis,
            eq_null,
            unreachable,
            wrench_scale,
            unactuated_scale: r[6..6 + k].to_vec(),
            torque_scale: r[6 + k..].to_vec(),
            row_scale: r,
            row_reach,
            stacked_cols,
            eq_cols,
            jacobian_transpose: jt,
            zeroed_joints,
            unactuated,
            actuators,
            force_unit_inv: force_unit.iter().map(|u| 1.0 / u).collect(),
            force_unit,
        })
    }

    /// Number of joints m.
    pub fn joints(&self) -> usize {
        self.jacobian_transpose.nrows()
    }

    /// Number of contact force components n.
    pub fn force_dim(&self) -> usize {
        self.grasp_matrix.ncols()
    }

    /// Index of torque row j in the rows of `[G; E; Jᵀ]` (for [`Self::row_reach`]).
    pub fn torque_row(&self, j: usize) -> usize {
        6 + self.unactuated.nrows() + j
    }

    /// A warning per joint of [`Self::zeroed_joints`], for a report: its ratio, the
    /// joint it is measured against, and what follows. (Not on every solve's answer:
    /// they are the model's, and a control loop's answers do not allocate.)
    pub fn zeroed_joint_warnings(&self) -> Vec<String> {
        self.zeroed_joints
            .iter()
            .map(|z| {
                let against = self.joint_name(z.against);
                format!(
                    "{}: its row of Jᵀ is at most {:.1e} of {against}'s on the contacts it touches, within the rank tolerance ({:.0e}), and the model makes it zero: its torque is 0 (less any passive torque), and Jᵀ f matches it only to that tolerance of {against}'s. Where the two torques are in units far apart, give them in nearer ones",
                    self.joint_name(z.joint),
                    z.ratio,
                    self.rank_tolerance,
                )
            })
            .collect()
    }

    /// The torques' scales in the objective, `√w_j` times their row's reach
    /// ([`Self::row_reach`]: what a unit force does to torque j): the largest and the
    /// smallest nonzero one, each `(joint, scale)`; None where fewer than two joints
    /// carry force. Far apart (a joint in a unit 1e8 times another's without the weight
    /// that undoes it, or moment arms 1e-8 of the others'), the smaller torques are at
    /// the rounding of the larger: docs/solver.md, "Limits".
    pub fn torque_spread(&self) -> Option<[(usize, f64); 2]> {
        let scales = (0..self.joints())
            .map(|j| {
                (
                    j,
                    self.weights[j].sqrt() * self.row_reach[self.torque_row(j)],
                )
            })
            .filter(|&(_, s)| s > 0.0);
        let (mut hi, mut lo) = (None::<(usize, f64)>, None::<(usize, f64)>);
        for (j, s) in scales {
            if hi.is_none_or(|h| s > h.1) {
                hi = Some((j, s));
            }
            if lo.is_none_or(|l| s < l.1) {
                lo = Some((j, s));
            }
        }
        let (hi, lo) = (hi?, lo?);
        (hi.0 != lo.0).then_some([hi, lo])
    }

    /// The same grasp with each joint's weight `1 / reach_j²` ([`Self::row_reach`]), so
    /// that every torque that carries force has scale 1 in the objective
    /// ([`Self::torque_spread`]): each joint's torque in a unit of its own. Only the
    /// objective changes (the passive torques' offset is one point of the same
    /// consistent torques), so the grasp is feasible exactly where it is.
    pub fn equilibrated(&self) -> Self {
        let mut model = self.clone();
        for (j, w) in model.weights.iter_mut().enumerate() {
            let reach = self.row_reach[self.torque_row(j)];
            if reach > 0.0 && (reach * reach).is_normal() {
                *w = 1.0 / (reach * reach);
            }
        }
        model
    }

    /// Row i of `[G; E; Jᵀ]` (the order of [`Self::row_reach`] and [`Self::row_scale`]).
    pub fn stacked_row(&self, i: usize) -> &[f64] {
        let k = self.unactuated.nrows();
        match i {
            0..6 => self.grasp_matrix.row(i),
            _ if i < 6 + k => self.unactuated.row(i - 6),
            _ => self.jacobian_transpose.row(i - 6 - k),
        }
    }

    /// Number of consistency equalities p.
    pub fn equality_rows(&self) -> usize {
        self.eq.nrows()
    }

    /// Dimension d of the passive internal forces (the null space of `[G; Jᵀ]`).
    pub fn passive_dim(&self) -> usize {
        self.passive_basis.ncols()
    }

    /// Number of internal-force variables a backend optimises: d with
    /// [`InternalForces::Free`], else 0.
    pub fn free_dim(&self) -> usize {
        if self.internal_forces == InternalForces::Free {
            self.passive_dim()
        } else {
            0
        }
    }

    /// The name of joint `j`: its given name, else `joint j`.
    pub fn joint_name(&self, j: usize) -> String {
        self.joint_names
            .get(j)
            .cloned()
            .unwrap_or_else(|| format!("joint {j}"))
    }

    /// `e(w)` into `out` (length: equality rows).
    pub fn e_into(&self, w: &[f64; 6], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = -dot(self.eq_w.row(i), w);
        }
    }

    /// `f = Z1 w + Z2 τ + N ξ + f_p` into `out` (eq. 31, with the passive torques'
    /// force [`Passive::force`]); `xi` is empty unless the internal forces are free.
    pub fn forces_into(&self, w: &[f64; 6], tau: &[f64], xi: &[f64], out: &mut [f64]) {
        let n = out.len();
        let (zw, rest) = self.force_cols.split_at(6 * n);
        let (zt, passive) = rest.split_at(tau.len() * n);
        match self.passive.force.as_slice() {
            [] => out.fill(0.0),
            fp => out.copy_from_slice(fp),
        }
        add_columns(out, zw, w, 1.0);
        add_columns(out, zt, tau, 1.0);
        if !xi.is_empty() {
            add_columns(out, passive, xi, 1.0);
        }
    }

    /// `Σ_j |a_j| · (|Z1| |w| + |Z2| |τ| + |N| |ξ|)_j`: the size of the terms behind
    /// `a · f`, which bounds the rounding of `f = Z1 w + Z2 τ + N ξ` seen through `a`.
    pub fn force_terms_dot(&self, a: &[f64], w: &[f64; 6], tau: &[f64], xi: &[f64]) -> f64 {
        (0..self.force_dim())
            .filter(|&j| a[j] != 0.0)
            .map(|j| a[j].abs() * self.force_terms(j, w, tau, xi))
            .sum()
    }

    /// `(|Z1| |w| + |Z2| |τ| + |N| |ξ|)_j` with the terms of the passive force's `f_p,j`:
    /// the size of the terms behind the force component `f_j`, which bounds its rounding
    /// (a force that cancels to nearly zero keeps the rounding of its terms).
    pub fn force_terms(&self, j: usize, w: &[f64; 6], tau: &[f64], xi: &[f64]) -> f64 {
        let abs_dot =
            |x: &[f64], y: &[f64]| -> f64 { x.iter().zip(y).map(|(p, q)| (p * q).abs()).sum() };
        let mut t = abs_dot(self.z1.row(j), w)
            + abs_dot(self.z2.row(j), tau)
            + self.passive.force_terms.get(j).copied().unwrap_or(0.0);
        if !xi.is_empty() {
            t += abs_dot(self.passive_basis.row(j), xi);
        }
        t
    }

    /// The wrench in equilibrated units: `w_i · wrench_scale_i`.
    pub fn scaled_wrench(&self, w: &[f64; 6]) -> [f64; 6] {
        let mut s = *w;
        for (v, r) in s.iter_mut().zip(&self.wrench_scale) {
            *v *= r;
        }
        s
    }

    /// How far `w` is from any wrench some torque can balance under `C τ = e`, in
    /// equilibrated wrench units (0 in the paper model).
    pub fn unreachable_residual(&self, w: &[f64; 6]) -> f64 {
        let ws = self.scaled_wrench(w);
        let offset = |i: usize| self.passive.unreachable_offset.get(i).copied();
        (0..self.unreachable.nrows())
            .map(|i| (dot(self.unreachable.row(i), &ws) + offset(i).unwrap_or(0.0)).abs())
            .fold(0.0, f64::max)
    }

    /// Tolerance on [`Self::unreachable_residual`]: the rank decision treated singular
    /// values below `rank_tolerance` as zero, so `e` may be off by as much, relative to
    /// the equilibrated wrench.
    pub fn unreachable_tolerance(&self, w: &[f64; 6]) -> f64 {
        // The passive targets enter as equilibrated as the wrench.
        let passive = self
            .passive
            .row_targets
            .iter()
            .zip(&self.row_scale[6..])
            .fold(0.0f64, |a, (t, r)| a.max((t * r).abs()));
        10.0 * self.rank_tolerance
            * norm_inf(&self.scaled_wrench(w))
                .max(passive)
                .max(f64::MIN_POSITIVE)
    }
}

/// Each contact's force on the object, `[Fx, Fy, Fz]` in the wrench's frame: the force
/// rows of G's columns times the contact's components of `f`, in contact order (a soft
/// finger's torsion adds no force). They sum to the wrench's force when `G f = w`.
pub fn object_forces(grasp_matrix: &Matrix, contacts: &[ContactModel], f: &[f64]) -> Vec<[f64; 3]> {
    let mut start = 0;
    contacts
        .iter()
        .map(|c| {
            let cols = start..start + c.dim();
            start = cols.end;
            std::array::from_fn(|r| cols.clone().map(|k| grasp_matrix[(r, k)] * f[k]).sum())
        })
        .collect()
}
