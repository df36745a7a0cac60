//! The torque QP (paper sections 3–4, eqs. 31, 39, 43), with the consistency equalities
//! the paper omits.
//!
//! With `A = [G; Jᵀ]` and `Z = A⁺ = [Z1 Z2]`, the contact forces are `f = Z1 w + Z2 τ`
//! (eq. 31, passive internal forces taken as zero). This balances `w` only when
//! `[w; τ]` lies in the range of A; with `U⊥` an orthonormal basis of the range's
//! complement that is `C τ = e` with `C = U⊥ᵀ[:, 6:]`, `e = −U⊥ᵀ[:, :6] w`.
//! The problem solved is
//!
//! ```text
//! minimise Σ w_j τ_j²   subject to   H τ ≥ c(w),   C τ = e(w)
//! ```
//!
//! with `H = S Z2`, `c = s0 − S Z1 w` (eqs. 39, 43; `s0` holds the minimum normal
//! forces) followed by the torque-limit rows.

use crate::cone::{inscribed_cone, Linearization};
use crate::contact::ContactModel;
use crate::error::ModelError;
use crate::linalg::svd;
use crate::matrix::{dot, Matrix};
use crate::problem::GraspProblem;

/// Whether `C τ = e` is enforced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Equilibrium {
    /// Enforce `C τ = e`: every answer balances the wrench (`G f = w`). The default.
    #[default]
    Consistent,
    /// The paper's model as printed: `H τ ≥ c` alone. Its answers generally do not
    /// balance the wrench; each carries a warning with `‖G f − w‖∞`. For reproducing the
    /// paper's numbers only.
    PaperModel,
}

/// How the QP is assembled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelOptions {
    /// Consistency equalities on (default) or the paper's model.
    pub equilibrium: Equilibrium,
    /// Relative rank tolerance for `A⁺` and the consistency rows: singular values at or
    /// below `rank_tolerance · σ_max` count as zero. Default `1e-9`, as in the
    /// reference implementation (`shared/reference/README.md`, item 1).
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

/// What an inequality row of H stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowKind {
    /// Face `face` of contact `contact`'s inscribed cone.
    Face {
        /// Contact index.
        contact: usize,
        /// Face index within the contact (eq. 50 order).
        face: usize,
    },
    /// `fz ≥ f_min` of contact `contact` (the last row of each cone).
    NormalForce {
        /// Contact index.
        contact: usize,
    },
    /// `τ_j ≤ τmax_j` (`upper`) or `−τ_j ≤ τmax_j`.
    TorqueLimit {
        /// Joint index.
        joint: usize,
        /// Upper or lower bound.
        upper: bool,
    },
}

/// One contact's place in f and in the rows of H.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactBlock {
    /// The contact model.
    pub model: ContactModel,
    /// Index of its first force component in f.
    pub offset: usize,
    /// Index of its first row in H.
    pub first_row: usize,
    /// Its number of rows (N+1, 2N+1, 2NK+1 or 1).
    pub rows: usize,
}

/// The assembled torque QP for one grasp; the wrench enters only through `c(w)` and
/// `e(w)`, so one `TorqueQp` serves any number of wrenches.
#[derive(Clone, Debug)]
pub struct TorqueQp {
    /// G, 6 × n.
    pub grasp_matrix: Matrix,
    /// Jᵀ, m × n.
    pub jacobian_transpose: Matrix,
    /// Z1 = A⁺[:, :6], n × 6 (eq. 31).
    pub z1: Matrix,
    /// Z2 = A⁺[:, 6:], n × m (eq. 31).
    pub z2: Matrix,
    /// Numerical rank of A.
    pub rank: usize,
    /// The contacts and their rows.
    pub contacts: Vec<ContactBlock>,
    /// The block-diagonal linearised cones S, rows × n.
    pub s: Matrix,
    /// H = S Z2 followed by the torque-limit rows, rows × m (eq. 43).
    pub h: Matrix,
    /// `c(w) = c0 − hw · w`: the constant part (minimum normal forces, limits).
    pub c0: Vec<f64>,
    /// `c(w) = c0 − hw · w`: S Z1, zero on limit rows, rows × 6.
    pub hw: Matrix,
    /// C, p × m (empty in the paper model).
    pub eq: Matrix,
    /// `e(w) = −eq_w · w`, p × 6.
    pub eq_w: Matrix,
    /// Left null space of C applied to e: `unreachable · w ≠ 0` means no torque can
    /// satisfy `C τ = e` for this wrench, q × 6.
    pub unreachable: Matrix,
    /// Objective weights `w_j` (all 1 by default).
    pub weights: Vec<f64>,
    /// What each row of H stands for.
    pub row_kinds: Vec<RowKind>,
    /// The linearisation used.
    pub linearization: Linearization,
    /// Consistent or paper model.
    pub equilibrium: Equilibrium,
    /// The rank tolerance used.
    pub rank_tolerance: f64,
}

/// The block-diagonal cones of a problem, in contact order.
struct Cones {
    s: Matrix,
    s0: Vec<f64>,
    row_kinds: Vec<RowKind>,
    contacts: Vec<ContactBlock>,
}

fn stack_cones(p: &GraspProblem) -> Cones {
    let lin = p.linearization;
    let total: usize = p.contacts.iter().map(|c| lin.rows_for(c)).sum();
    let mut s = Matrix::zeros(total, p.force_dim());
    let mut s0 = vec![0.0; total];
    let mut row_kinds = Vec::with_capacity(total);
    let mut contacts = Vec::with_capacity(p.contacts.len());
    let (mut offset, mut row) = (0, 0);
    for (ci, model) in p.contacts.iter().enumerate() {
        let cone = inscribed_cone(model, &lin);
        let r = cone.faces.nrows();
        for k in 0..r {
            s.row_mut(row + k)[offset..offset + model.dim()].copy_from_slice(cone.faces.row(k));
            row_kinds.push(if k + 1 == r {
                RowKind::NormalForce { contact: ci }
            } else {
                RowKind::Face {
                    contact: ci,
                    face: k,
                }
            });
        }
        if let Some(fmin) = &p.min_normal_force {
            s0[row + r - 1] = fmin[ci];
        }
        contacts.push(ContactBlock {
            model: *model,
            offset,
            first_row: row,
            rows: r,
        });
        offset += model.dim();
        row += r;
    }
    Cones {
        s,
        s0,
        row_kinds,
        contacts,
    }
}

/// Rows `±(τ-map)_j · x ≥ −τmax_j` for the limited joints, where `tau_map` gives τ from
/// the variables (the identity for the torque QP, Jᵀ for the force-space QP).
fn limit_rows(
    p: &GraspProblem,
    tau_map: &Matrix,
    c0: &mut Vec<f64>,
    kinds: &mut Vec<RowKind>,
) -> Matrix {
    let mut rows = Vec::new();
    if let Some(limits) = &p.torque_limits {
        for (j, lim) in limits.iter().enumerate() {
            if let Some(t) = *lim {
                for upper in [false, true] {
                    let sign = if upper { -1.0 } else { 1.0 };
                    rows.push(tau_map.row(j).iter().map(|v| sign * v).collect::<Vec<_>>());
                    c0.push(-t);
                    kinds.push(RowKind::TorqueLimit { joint: j, upper });
                }
            }
        }
    }
    Matrix::from_rows(&rows, tau_map.ncols())
}

/// Orthonormal rows spanning the left null space of `a`, applied to `a_w`: a wrench
/// with `result · w ≠ 0` makes `a x = −a_w w` unsolvable.
fn unreachable_map(a: &Matrix, a_w: &Matrix, rank_tolerance: f64) -> Result<Matrix, ModelError> {
    let p = a.nrows();
    let d = svd(a)?;
    let r = d.rank(rank_tolerance);
    let left_null = Matrix::from_fn(p - r, p, |i, j| d.u[(j, r + i)]);
    Ok(left_null.matmul(a_w))
}

impl TorqueQp {
    /// The contact-force-space QP of the usual two-step method, for comparison: minimise
    /// `‖f‖²` subject to `G f = w`, the same linearised cones and minimum normal forces,
    /// and the torque limits applied to `Jᵀ f`. Its "torque" is f itself (`z2 = I`,
    /// `jacobian_transpose = I`); map the answer through Jᵀ to get joint torques.
    pub fn force_space(p: &GraspProblem, opts: &ModelOptions) -> Result<Self, ModelError> {
        if !(opts.rank_tolerance > 0.0 && opts.rank_tolerance < 1.0) {
            return Err(ModelError::RankTolerance(opts.rank_tolerance));
        }
        let n = p.force_dim();
        let cones = stack_cones(p);
        let mut row_kinds = cones.row_kinds;
        let mut c0 = cones.s0;
        let limits = limit_rows(p, &p.jacobian_transpose, &mut c0, &mut row_kinds);
        let h = cones.s.vstack(&limits);
        let hw = Matrix::zeros(h.nrows(), 6);
        let eq = p.grasp_matrix.clone();
        let eq_w = Matrix::from_fn(6, 6, |i, j| if i == j { -1.0 } else { 0.0 });
        let unreachable = unreachable_map(&eq, &eq_w, opts.rank_tolerance)?;
        Ok(Self {
            grasp_matrix: p.grasp_matrix.clone(),
            jacobian_transpose: Matrix::identity(n),
            z1: Matrix::zeros(n, 6),
            z2: Matrix::identity(n),
            rank: n,
            contacts: cones.contacts,
            s: cones.s,
            h,
            c0,
            hw,
            eq,
            eq_w,
            unreachable,
            weights: vec![1.0; n],
            row_kinds,
            linearization: p.linearization,
            equilibrium: Equilibrium::Consistent,
            rank_tolerance: opts.rank_tolerance,
        })
    }

    /// Assembles the QP of a validated problem.
    pub fn new(p: &GraspProblem, opts: &ModelOptions) -> Result<Self, ModelError> {
        if !(opts.rank_tolerance > 0.0 && opts.rank_tolerance < 1.0) {
            return Err(ModelError::RankTolerance(opts.rank_tolerance));
        }
        let m = p.joints();
        let a = p.grasp_matrix.vstack(&p.jacobian_transpose);
        let dec = svd(&a)?;
        let rank = dec.rank(opts.rank_tolerance);
        let z = dec.pseudo_inverse(opts.rank_tolerance);
        let z1 = z.columns(0, 6);
        let z2 = z.columns(6, 6 + m);

        let cones = stack_cones(p);
        let s = cones.s;
        let mut row_kinds = cones.row_kinds;
        let mut c0 = cones.s0;
        // Torque limits: τ_j ≥ −τmax and −τ_j ≥ −τmax.
        let limits = limit_rows(p, &Matrix::identity(m), &mut c0, &mut row_kinds);
        let h = s.matmul(&z2).vstack(&limits);
        let hw = s.matmul(&z1).vstack(&Matrix::zeros(limits.nrows(), 6));

        // Consistency: U⊥ = columns of U beyond the rank.
        let (eq, eq_w, unreachable) = match opts.equilibrium {
            Equilibrium::PaperModel => (
                Matrix::zeros(0, m),
                Matrix::zeros(0, 6),
                Matrix::zeros(0, 6),
            ),
            Equilibrium::Consistent => {
                let p_rows = 6 + m - rank;
                let u_perp_t = Matrix::from_fn(p_rows, 6 + m, |i, j| dec.u[(j, rank + i)]);
                let eq = u_perp_t.columns(6, 6 + m);
                let eq_w = u_perp_t.columns(0, 6);
                // Row combinations of C that vanish: their e-part must vanish too.
                let unreachable = unreachable_map(&eq, &eq_w, opts.rank_tolerance)?;
                (eq, eq_w, unreachable)
            }
        };

        Ok(Self {
            grasp_matrix: p.grasp_matrix.clone(),
            jacobian_transpose: p.jacobian_transpose.clone(),
            z1,
            z2,
            rank,
            contacts: cones.contacts,
            s,
            h,
            c0,
            hw,
            eq,
            eq_w,
            unreachable,
            weights: p.torque_weights.clone().unwrap_or_else(|| vec![1.0; m]),
            row_kinds,
            linearization: p.linearization,
            equilibrium: opts.equilibrium,
            rank_tolerance: opts.rank_tolerance,
        })
    }

    /// Number of joints m.
    pub fn joints(&self) -> usize {
        self.h.ncols()
    }

    /// Number of contact force components n.
    pub fn force_dim(&self) -> usize {
        self.z2.nrows()
    }

    /// Number of inequality rows of H.
    pub fn inequality_rows(&self) -> usize {
        self.h.nrows()
    }

    /// Number of consistency equalities p.
    pub fn equality_rows(&self) -> usize {
        self.eq.nrows()
    }

    /// `c(w)` into `out` (length: inequality rows).
    pub fn c_into(&self, w: &[f64; 6], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.c0[i] - dot(self.hw.row(i), w);
        }
    }

    /// `e(w)` into `out` (length: equality rows).
    pub fn e_into(&self, w: &[f64; 6], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = -dot(self.eq_w.row(i), w);
        }
    }

    /// `f = Z1 w + Z2 τ` into `out` (eq. 31).
    pub fn forces_into(&self, w: &[f64; 6], tau: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = dot(self.z1.row(i), w) + dot(self.z2.row(i), tau);
        }
    }

    /// `‖U⊥ᵀ-left-null · w‖∞`: how far `w` is from any wrench some torque can balance
    /// under `C τ = e` (0 in the paper model).
    pub fn unreachable_residual(&self, w: &[f64; 6]) -> f64 {
        (0..self.unreachable.nrows())
            .map(|i| dot(self.unreachable.row(i), w).abs())
            .fold(0.0, f64::max)
    }

    /// Tolerance on [`Self::unreachable_residual`]: a wrench within it is treated as
    /// reachable. It follows from the rank decision: rows of C below
    /// `rank_tolerance · σ_max` were treated as zero, so `e` may be off by as much,
    /// relative to `‖w‖∞`.
    pub fn unreachable_tolerance(&self, w: &[f64; 6]) -> f64 {
        10.0 * self.rank_tolerance * crate::matrix::norm_inf(w).max(f64::EPSILON)
    }

    /// Human-readable description of row `i` of H.
    pub fn describe_row(&self, i: usize) -> String {
        match self.row_kinds[i] {
            RowKind::Face { contact, face } => format!("contact {contact} face {face}"),
            RowKind::NormalForce { contact } => format!("contact {contact} normal force"),
            RowKind::TorqueLimit { joint, upper } => {
                format!(
                    "joint {joint} {} torque limit",
                    if upper { "upper" } else { "lower" }
                )
            }
        }
    }
}
