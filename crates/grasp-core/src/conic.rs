//! The torque problem with exact cones as a scaled second-order cone program, the form
//! every conic backend reads (Clarabel's, and the native interior-point fallback), and
//! the certificate that proves one of its answers optimal.
//!
//! The variables are τ and the free internal forces ξ (when the model leaves them free).
//! `f = Z1 w + Z2 τ + N ξ` is substituted,
//! so every row is affine in the variables: `A x + s = b(w)`, `s ∈ K`, minimising
//! `‖x_τ‖²` (`P = 2I` on the torques, 0 elsewhere).
//!
//! Rows, all read from the [`TorqueQp`] view and its typed cone blocks:
//! - the consistency equalities `C τ = e(w)` (zero cone);
//! - the linear rows `H τ + Hp ξ ≥ c(w)`: inscribed faces, every contact's minimum
//!   normal force `fz ≥ f_min`, and the torque limits (nonnegative cone);
//! - per exact contact: PCwF `(mu·fz, fx, fy)` ∈ SOC(3); SFCe
//!   `(fz, fx/mu, fy/mu, mz/mu_torsion)` ∈ SOC(4) (eq. 4); SFCl
//!   `(mu·(fz − mz/mu_torsion), fx, fy)` and `(mu·(fz + mz/mu_torsion), fx, fy)` ∈ SOC(3),
//!   which together are eq. 3's `‖f_t‖/mu + |mz|/mu_torsion ≤ fz` with no auxiliary
//!   variable (auxiliaries would be free, and curvature-free, wherever a contact is
//!   inside its cone).
//!
//! **Scaling.** An interior-point method stops on absolute and relative tolerances, so
//! the data are scaled: every row is in force units (`mz` counted as `mz/mu_torsion`),
//! the torques are scaled to `k √w_j τ_j` (the objective becomes `‖x‖²`, with k putting
//! x in force units), the free internal forces by their force response, and a solve
//! divides the right-hand side by its own magnitude α (the problem is homogeneous:
//! `(w, f_min, τmax) → α(…)` gives `τ → α τ`). [`ConicForm::unscale_into`] unscales, so the
//! answer is the same in any units and at any load.

use crate::contact::ContactModel;
use crate::linalg::{decompose, orthonormal_columns, RankThreshold, ROW_SPREAD};
use crate::matrix::{add_columns, dot4, norm2, write_columns, Matrix};
use crate::qp::{ConeRepr, RowId, TorqueQp};

/// Spread of the torques' force responses beyond which they are scaled by the typical
/// one, not the largest ([`ConicForm::new`]).
const SPREAD: f64 = 1e3;

/// One block of rows of a [`ConicForm`], in row order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConeKind {
    /// `s = 0`: equalities.
    Zero(usize),
    /// `s ≥ 0`.
    Nonnegative(usize),
    /// `s0 ≥ ‖s1..‖`, of the given dimension.
    SecondOrder(usize),
}

impl ConeKind {
    /// Number of rows.
    pub fn dim(&self) -> usize {
        match *self {
            ConeKind::Zero(d) | ConeKind::Nonnegative(d) | ConeKind::SecondOrder(d) => d,
        }
    }
}

/// The scaled conic problem of one [`TorqueQp`]: minimise `‖x_τ‖²` subject to
/// `A x + s = b0 + bw·w`, `s ∈ K`.
#[derive(Clone, Debug)]
pub struct ConicForm {
    /// Number of variables: joints, then free internal forces.
    pub nx: usize,
    /// Joints m (the first m variables carry the objective).
    pub joints: usize,
    /// Free internal forces d.
    pub free: usize,
    /// `A`, rows × nx.
    pub a: Matrix,
    /// Constant part of `b`.
    pub b0: Vec<f64>,
    /// Wrench part of `b`, rows × 6.
    pub bw: Matrix,
    /// The cones, in row order: the zero cone first, then the nonnegative cone, then
    /// one second-order cone per exact contact with friction.
    pub cones: Vec<ConeKind>,
    /// Variable scale: `x = col_scale ⊙ (τ, ξ) / α`.
    pub col_scale: Vec<f64>,
    /// Objective normalisation κ = 1/k²: `Σ w_j τ_j² = α² κ ‖x_τ‖²`. It underflows
    /// where the answer's σ would (k near 1e200, at the small end of the input domain):
    /// what must survive there reads [`Self::torque_scale`].
    pub kappa: f64,
    /// Torque scale k: `x_j = k √w_j τ_j / α` on the torques.
    pub torque_scale: f64,
    /// The linear rows of the view start at this row, each scaled by `row_scale`.
    pub linear_at: usize,
    /// The torque limits' rows (the view's last linear rows): constant right-hand
    /// sides that x = 0 meets, so they do not set α.
    pub limit_rows: std::ops::Range<usize>,
    /// Scale of each linear row of the view.
    pub row_scale: Vec<f64>,
    /// The contact of each second-order cone, in cone order. An SFCl contact has two:
    /// first `fz − mz/mu_torsion` (binding when `mz > 0`), then `fz + mz/mu_torsion`.
    pub soc_contacts: Vec<usize>,
    /// An orthonormal basis of the null space of the equality rows, transposed
    /// ((nx − p) × nx); `None` without equalities. The certificate's stationarity is
    /// `P x + A_inᵀ z_in` projected on it: a z on the equalities that cancels the rest
    /// exists exactly when the projection vanishes, so none is needed.
    pub eq_null_t: Option<Matrix>,
    /// The equality rows' pseudo-inverse `E⁺` (nx × p) from the same decomposition,
    /// when the rank it decides is p; `None` otherwise, and without equalities. Newton
    /// eliminates the equalities with it ([`Self::eq_null_t`] and `E⁺`), so the rows
    /// are decomposed once per grasp.
    pub eq_pinv: Option<Matrix>,
    /// `A` with its rows zero-padded to a multiple of four columns, and per row the
    /// span of four-column blocks holding its nonzeros: a torque limit or a minimum
    /// normal force touches few, and the certificate's passes over A run whole blocks.
    a_padded: Matrix,
    row_span: Vec<(usize, usize)>,
    /// Per row: whether it is constant on the equalities' solutions (every nonzero
    /// entry on a variable they pin, whose column of [`Self::eq_null_t`] is zero: a
    /// limit on a joint the wrench fixes), a row of the nonnegative cone or a whole
    /// second-order cone. Its slack is a function of the wrench alone and any
    /// multiplier on it is absorbed by the equalities', so the certificate reads none
    /// ([`Self::certificate`]).
    fixed: Vec<bool>,
    /// `A`, `|A|` and `bw` column-major: the certificate's `b − A x` and the sizes of
    /// its terms `|A| |x|`, and `b(w)`, are passes down columns, which vectorise where
    /// a short row does not.
    a_cols: Vec<f64>,
    abs_cols: Vec<f64>,
    bw_cols: Vec<f64>,
    /// The size of the terms behind each entry of `b0` (the passive torques' force, the
    /// minimum normal forces, the limits), the largest of them on the rows that set α,
    /// and the largest `Σ_j |bw_ij|`: `b(w)` is rounding where it is within
    /// [`B_ROUNDING`] of them.
    b0_terms: Vec<f64>,
    b0_terms_max: f64,
    bw_abs_max: f64,
}

/// Where `b(w)` is within this of its terms ([`ConicForm::b_into`]), it is their
/// rounding, as the core's check judges forces (`1e3 ε` per term, and up to 40 ε seen).
const B_ROUNDING: f64 = 1e3 * f64::EPSILON;

impl ConicForm {
    /// Assembles the conic problem of `qp` (exact blocks become second-order cones).
    pub fn new(qp: &TorqueQp) -> Self {
        let model = &qp.model;
        let (m, d) = (model.joints(), model.free_dim());
        let nx = m + d;
        // Force-unit metric: mz counts as mz/mu_torsion.
        let mut fscale = vec![1.0; model.force_dim()];
        for c in &qp.contacts {
            if let ContactModel::SfcLinear { mu_torsion, .. }
            | ContactModel::SfcElliptic { mu_torsion, .. } = c.model
            {
                fscale[c.offset + 3] = 1.0 / mu_torsion;
            }
        }
        // Column scales: the force response of a unit of each variable. A variable
        // with no response at rounding level (a joint that moves no contact) takes the
        // largest scale, so that its rounding-level column does not blow up.
        let mut v = vec![0.0; model.force_dim()];
        let mut col_scale: Vec<f64> = (0..nx)
            .map(|j| {
                for (i, (vi, f)) in v.iter_mut().zip(&fscale).enumerate() {
                    *vi = f * if j < m {
                        model.z2[(i, j)]
                    } else {
                        model.passive_basis[(i, j - m)]
                    };
                }
                norm2(&v)
            })
            .collect();
        let largest = col_scale[m..m + d].iter().copied().fold(0.0, f64::max);
        for s in &mut col_scale[m..m + d] {
            if s.is_nan() || *s <= 1e3 * f64::EPSILON * largest {
                *s = if largest > 0.0 { largest } else { 1.0 };
            }
        }
        // Torques: x_j = k √w_j τ_j, so that the objective is ‖x‖² (a least-distance
        // problem) and k = max_j (response_j / √w_j) puts x in force units. Where that
        // largest is more than SPREAD times the typical (geometric mean) response, k
        // is the typical one: the largest would shrink every other column below the
        // methods' resolution against P = 2I (a joint with moment arms 1e-8 of the
        // others' left 17 of 200 sweep grasps failing, Newton and the interior-point
        // method alike; 2 with the typical scale). Below that spread k stays the
        // largest, which the hard cases of tests/exact.rs were solved with. A joint
        // that moves no contact (its row of Jᵀ zero, its torque pinned) has no scale:
        // its response, rounding at 1e-17, took the mean down by 1e10, x with it, and
        // the interior-point method stopped on its absolute gap at 1e-4 of σ.
        let (mut logs, mut count, mut largest) = (0.0f64, 0usize, 0.0f64);
        for j in 0..m {
            let r = col_scale[j] / model.weights[j].sqrt();
            let moves = model.jacobian_transpose.row(j).iter().any(|v| *v != 0.0);
            if moves && r > 0.0 && r.is_finite() {
                logs += r.ln();
                count += 1;
                largest = largest.max(r);
            }
        }
        let typical = if count > 0 {
            (logs / count as f64).exp()
        } else {
            0.0
        };
        let k = if largest <= SPREAD * typical {
            largest
        } else {
            typical
        };
        let k = if k > 0.0 && k.is_finite() { k } else { 1.0 };
        for j in 0..m {
            col_scale[j] = k * model.weights[j].sqrt();
        }
        // The rows, assembled in place in their final order (equalities, the view's
        // linear rows, then each second-order cone's): `a·x + s = b0 + bw·w`.
        let socs: usize = qp
            .contacts
            .iter()
            .zip(&qp.constraints.cones)
            .filter(|(_, repr)| matches!(repr, ConeRepr::Exact))
            .map(|(c, _)| match c.model {
                ContactModel::Fpc => 0,
                ContactModel::Pcwf { .. } => 3,
                ContactModel::SfcElliptic { .. } => 4,
                ContactModel::SfcLinear { .. } => 6,
            })
            .sum();
        let n = model.equality_rows() + qp.inequality_rows() + socs;
        let mut data: Vec<f64> = Vec::with_capacity(n * nx);
        let mut b0: Vec<f64> = Vec::with_capacity(n);
        let mut b0_terms: Vec<f64> = Vec::with_capacity(n);
        let mut bws: Vec<[f64; 6]> = Vec::with_capacity(n);
        // A new zero row of A, to be filled.
        let new_row = |data: &mut Vec<f64>| -> usize {
            let start = data.len();
            data.resize(start + nx, 0.0);
            start
        };
        // A row "v·f + k ≥ 0" (v on force components, already in force units).
        let force_row = |data: &mut Vec<f64>,
                         b0: &mut Vec<f64>,
                         b0_terms: &mut Vec<f64>,
                         bws: &mut Vec<[f64; 6]>,
                         v: &[(usize, f64)]| {
            let start = new_row(data);
            let a = &mut data[start..];
            let (mut bw, mut b, mut size) = ([0.0; 6], 0.0, 0.0);
            for &(i, c) in v {
                // The passive torques' force at v = 0 (Passive::solver_force).
                b += c * model.passive.solver_force.get(i).copied().unwrap_or(0.0);
                size += c.abs()
                    * model
                        .passive
                        .solver_force_terms
                        .get(i)
                        .copied()
                        .unwrap_or(0.0);
                for ((aj, z), s) in a.iter_mut().zip(model.z2.row(i)).zip(&col_scale) {
                    *aj -= c * z / s;
                }
                for ((aj, p), s) in a[m..]
                    .iter_mut()
                    .zip(model.passive_basis.row(i))
                    .zip(&col_scale[m..])
                {
                    *aj -= c * p / s;
                }
                for (bj, z) in bw.iter_mut().zip(model.z1.row(i)) {
                    *bj += c * z;
                }
            }
            b0.push(b);
            b0_terms.push(size);
            bws.push(bw);
        };
        let mut cones = Vec::new();
        let mut eq_norms = Vec::with_capacity(model.equality_rows());
        for i in 0..model.equality_rows() {
            // C τ = −eq_w w, each row normalised in the scaled variables.
            let start = new_row(&mut data);
            let a = &mut data[start..];
            for ((aj, e), s) in a.iter_mut().zip(model.eq.row(i)).zip(&col_scale) {
                *aj = e / s;
            }
            let nrm = norm2(a).max(f64::MIN_POSITIVE);
            a.iter_mut().for_each(|v| *v /= nrm);
            eq_norms.push(nrm);
            let mut bw = [0.0; 6];
            for (j, v) in bw.iter_mut().enumerate() {
                *v = -model.eq_w[(i, j)] / nrm;
            }
            b0.push(0.0);
            b0_terms.push(0.0);
            bws.push(bw);
        }
        if model.equality_rows() > 0 {
            cones.push(ConeKind::Zero(model.equality_rows()));
        }
        // The linear rows of the view: −(H τ + Hp ξ) + s = −c0 + hw·w, in force units.
        let linear_at = b0.len();
        let mut row_scale = Vec::with_capacity(qp.inequality_rows());
        let h = qp.h();
        for i in 0..qp.inequality_rows() {
            let rho = match qp.rows[i] {
                RowId::TorqueLimit { joint, .. } => col_scale[joint],
                _ => 1.0,
            };
            let start = new_row(&mut data);
            let a = &mut data[start..];
            for ((aj, h), s) in a.iter_mut().zip(h.row(i)).zip(&col_scale) {
                *aj = -rho * h / s;
            }
            for ((aj, h), s) in a[m..].iter_mut().zip(qp.hp.row(i)).zip(&col_scale[m..]) {
                *aj = -rho * h / s;
            }
            let mut bw = [0.0; 6];
            for (j, v) in bw.iter_mut().enumerate() {
                *v = rho * qp.hw[(i, j)];
            }
            b0.push(-rho * qp.c0[i]);
            b0_terms.push(rho * qp.c0_terms[i]);
            bws.push(bw);
            row_scale.push(rho);
        }
        if qp.inequality_rows() > 0 {
            cones.push(ConeKind::Nonnegative(qp.inequality_rows()));
        }
        let limits = qp
            .rows
            .iter()
            .filter(|r| matches!(r, RowId::TorqueLimit { .. }))
            .count();
        let limit_rows =
            linear_at + qp.inequality_rows() - limits..linear_at + qp.inequality_rows();
        debug_assert!(qp.rows[qp.inequality_rows() - limits..]
            .iter()
            .all(|r| matches!(r, RowId::TorqueLimit { .. })));
        let mut soc_contacts = Vec::new();
        for (ci, (c, repr)) in qp.contacts.iter().zip(&qp.constraints.cones).enumerate() {
            if !matches!(repr, ConeRepr::Exact) {
                continue;
            }
            let o = c.offset;
            let (x, y, z, t) = (o, o + 1, o + 2, o + 3);
            let mut cone = |rows: &[&[(usize, f64)]]| {
                for v in rows {
                    force_row(&mut data, &mut b0, &mut b0_terms, &mut bws, v);
                }
                soc_contacts.push(ci);
                cones.push(ConeKind::SecondOrder(rows.len()));
            };
            match c.model {
                // fz ≥ f_min ≥ 0 is already a linear row.
                ContactModel::Fpc => {}
                ContactModel::Pcwf { mu } => cone(&[&[(z, mu)], &[(x, 1.0)], &[(y, 1.0)]]),
                ContactModel::SfcElliptic { mu, mu_torsion } => cone(&[
                    &[(z, 1.0)],
                    &[(x, 1.0 / mu)],
                    &[(y, 1.0 / mu)],
                    &[(t, 1.0 / mu_torsion)],
                ]),
                // ‖f_t‖/mu + |mz|/mu_torsion ≤ fz is ‖f_t‖ ≤ mu (fz ∓ mz/mu_torsion), both.
                ContactModel::SfcLinear { mu, mu_torsion } => {
                    for sign in [-1.0, 1.0] {
                        cone(&[
                            &[(z, mu), (t, sign * mu / mu_torsion)],
                            &[(x, 1.0)],
                            &[(y, 1.0)],
                        ]);
                    }
                }
            }
        }
        let n = b0.len();
        let a = Matrix::from_rows_data(n, nx, data);
        let row_span = (0..n)
            .map(|i| {
                let r = a.row(i);
                let first = r.iter().position(|&v| v != 0.0).unwrap_or(0);
                let last = r.iter().rposition(|&v| v != 0.0).map_or(0, |j| j + 1);
                // Whole blocks of four within the padded width.
                (first / 4 * 4, last.max(first).div_ceil(4) * 4)
            })
            .collect();
        let padded = nx.div_ceil(4) * 4;
        let eq = match cones.first() {
            Some(&ConeKind::Zero(p)) => p,
            _ => 0,
        };
        // (Independent rows from the core; a failed decomposition leaves the basis
        // out, and the certificate then fails rather than guess.)
        let (eq_null_t, eq_pinv) = if eq > 0 {
            let norms: Vec<f64> = (0..eq).map(|i| eq_norms[i]).collect();
            match factored_equalities(model, &col_scale, &norms) {
                Some((nt, pinv)) => (Some(nt), Some(pinv)),
                None => {
                    let e = Matrix::from_fn(eq, nx, |i, j| a[(i, j)]);
                    match decompose(&e, RankThreshold::Relative(1e-13)) {
                        Ok(d) => {
                            let pinv = (d.rank() == eq).then(|| d.pseudo_inverse());
                            let mut nt = d.null_basis.transpose();
                            // A joint the model found pinned: its entries are rounding.
                            if model.eq_null.nrows() == m && nt.ncols() == nx {
                                for j in 0..m {
                                    if model.eq_null.row(j).iter().all(|v| *v == 0.0) {
                                        for c in 0..nt.nrows() {
                                            nt[(c, j)] = 0.0;
                                        }
                                    }
                                }
                            }
                            (Some(nt), pinv)
                        }
                        Err(_) => (Some(Matrix::zeros(0, 0)), None),
                    }
                }
            }
        } else {
            (None, None)
        };
        let fixed = match &eq_null_t {
            Some(nt) if nt.ncols() == nx && eq > 0 => {
                let pinned: Vec<bool> = (0..nx)
                    .map(|j| (0..nt.nrows()).all(|r| nt[(r, j)] == 0.0))
                    .collect();
                let constant = |i: usize| {
                    a.row(i).iter().zip(&pinned).all(|(v, &p)| *v == 0.0 || p)
                        && a.row(i).iter().any(|v| *v != 0.0)
                };
                // A row of the nonnegative cone on its own; a second-order cone only
                // whole (one constant row of a cone, a force component the wrench
                // fixes, still carries the cone's multiplier).
                let mut fixed = vec![false; n];
                let mut start = 0;
                for cone in &cones {
                    let r = start..start + cone.dim();
                    match cone {
                        ConeKind::Zero(_) => {}
                        ConeKind::Nonnegative(_) => r.for_each(|i| fixed[i] = constant(i)),
                        ConeKind::SecondOrder(_) => {
                            if r.clone().all(constant) {
                                r.for_each(|i| fixed[i] = true);
                            }
                        }
                    }
                    start += cone.dim();
                }
                fixed
            }
            _ => vec![false; n],
        };
        // A and |A| down columns, and A in rows padded to whole blocks of four.
        let mut a_cols: Vec<f64> = vec![0.0; n * nx];
        write_columns(&a, &mut a_cols, n);
        let abs_cols = a_cols.iter().map(|v| v.abs()).collect();
        let mut bw_cols = vec![0.0; n * 6];
        for (i, bw) in bws.iter().enumerate() {
            for (j, v) in bw.iter().enumerate() {
                bw_cols[j * n + i] = *v;
            }
        }
        let mut a_padded = Matrix::zeros(n, padded);
        for i in 0..n {
            a_padded.row_mut(i)[..nx].copy_from_slice(a.row(i));
        }
        // (Over the rows that set α: a loose limit's terms would open the gate below on
        // every solve.)
        let b0_terms_max = b0_terms
            .iter()
            .enumerate()
            .filter(|(i, _)| !limit_rows.contains(i))
            .fold(0.0f64, |a, (_, &v)| a.max(v));
        let bw_abs_max = bws
            .iter()
            .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0f64, f64::max);
        Self {
            a_cols,
            abs_cols,
            bw_cols,
            b0_terms,
            b0_terms_max,
            bw_abs_max,
            nx,
            joints: m,
            free: d,
            a_padded,
            a,
            eq_null_t,
            eq_pinv,
            row_span,
            fixed,
            b0,
            bw: Matrix::from_rows_data(n, 6, bws.concat()),
            cones,
            col_scale,
            kappa: 1.0 / (k * k),
            torque_scale: k,
            linear_at,
            limit_rows,
            row_scale,
            soc_contacts,
        }
    }

    /// `A` column-major (column j at `j · rows..`).
    pub fn a_cols(&self) -> &[f64] {
        &self.a_cols
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.a.nrows()
    }

    /// Number of equality rows: the zero cone's, first.
    pub fn equalities(&self) -> usize {
        match self.cones.first() {
            Some(&ConeKind::Zero(p)) => p,
            _ => 0,
        }
    }

    /// `b(w)` into `out`; returns its magnitude α = ‖b(w)‖∞ over every row but the
    /// torque limits' that x = 0 meets, by which `out` is then divided (unless it is 0:
    /// every row homogeneous, τ = 0 optimal). A loose limit (1e6 times the torques) set the scale
    /// before, and every other row then sat at 1e-6 of it, below the solvers'
    /// tolerances.
    pub fn b_into(&self, w: &[f64; 6], out: &mut [f64]) -> f64 {
        out.copy_from_slice(&self.b0);
        add_columns(out, &self.bw_cols, w, 1.0);
        let mut alpha = self.b_scale(out);
        // A b within the rounding of its terms is zero, entry by entry: where the
        // passive torques alone leave every contact unloaded (no wrench, G of full
        // column rank), b is their force cancelled to 40 ε of terms of 1 N, and α
        // scaled that rounding up to a grasp that every method called infeasible.
        let wmax = w.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if alpha > 0.0 && alpha <= B_ROUNDING * (self.b0_terms_max + self.bw_abs_max * wmax) {
            let rows = out.len();
            for (i, (v, t)) in out.iter_mut().zip(&self.b0_terms).enumerate() {
                let terms = t
                    + (0..6)
                        .map(|j| (self.bw_cols[j * rows + i] * w[j]).abs())
                        .sum::<f64>();
                if v.abs() <= B_ROUNDING * terms {
                    *v = 0.0;
                }
            }
            alpha = self.b_scale(out);
        }
        if alpha > 0.0 {
            let inv = 1.0 / alpha;
            out.iter_mut().for_each(|v| *v *= inv);
        }
        alpha
    }

    /// α of [`Self::b_into`]: the largest |b_i|, a limit's only where x = 0 breaks it
    /// (b < 0: a range that excludes 0, or passive torques beyond a limit), for that
    /// says how large the answer is, and one that x = 0 meets does not.
    fn b_scale(&self, b: &[f64]) -> f64 {
        let (head, tail) = (&b[..self.limit_rows.start], &b[self.limit_rows.end..]);
        b[self.limit_rows.clone()]
            .iter()
            .filter(|&&v| v < 0.0)
            .fold(
                head.iter().chain(tail).fold(0.0f64, |a, v| a.max(v.abs())),
                |a, &v| a.max(-v),
            )
    }

    /// Adds `A_inᵀ z_in` to `grad` and its terms' sizes to `gsize` (rows `eq..` with a
    /// multiplier: most are inactive, z = 0). Returns the largest component of `grad`
    /// in the null space of the equalities (all of it without any), the largest column
    /// of terms, and whether that basis fits.
    fn torque_terms(
        &self,
        z: &[f64],
        eq: usize,
        grad: &mut [f64],
        gsize: &mut [f64],
    ) -> (f64, f64, bool) {
        let nx = self.nx;
        for i in (eq..self.rows()).filter(|&i| z[i] != 0.0 && !self.fixed[i]) {
            let (lo, hi) = self.row_span[i];
            for ((g, gs), a) in grad[lo..hi]
                .iter_mut()
                .zip(&mut gsize[lo..hi])
                .zip(&self.a_padded.row(i)[lo..hi])
            {
                let t = a * z[i];
                *g += t;
                *gs += t.abs();
            }
        }
        // (A fixed row's terms are left out above: a multiplier of 1e18 there, which
        // the equalities absorb, made every other column's residual look small.)
        let colsize = gsize.iter().fold(f64::MIN_POSITIVE, |a, v| fmax(a, *v));
        let (residual, basis_ok) = match &self.eq_null_t {
            None => (grad.iter().fold(0.0f64, |a, g| fmax(a, g.abs())), true),
            Some(nt) => (
                (0..nt.nrows()).fold(0.0f64, |a, r| fmax(a, dot4(nt.row(r), &grad[..nx]).abs())),
                nt.ncols() == nx,
            ),
        };
        (residual, colsize, basis_ok)
    }

    /// Checks from scratch that `z` is a ray of the dual of the scaled problem with
    /// right-hand side `b`, a certificate that no x has `s = b − A x ∈ K`: `z` in the
    /// dual cone on the inequality rows, `A_inᵀ z` in the range of the equality rows
    /// (its projection on their null space vanishes: the equalities' multipliers
    /// cancel the rest), and `zᵀ (b − A x_p) < 0` for a point `x_p` meeting the
    /// equalities. For any x meeting them, `x = x_p + N y` and
    /// `zᵀ s = zᵀ(b − A x_p) − (Nᵀ A_inᵀ z)ᵀ y`, negative unless y is huge, while
    /// `s ∈ K` would make it non-negative. Each measure is relative to its terms, as
    /// in [`Self::certificate`]; `scratch` is grown once and reused.
    pub fn dual_ray(
        &self,
        b: &[f64],
        xp: &[f64],
        z: &[f64],
        tol: f64,
        scratch: &mut Vec<f64>,
    ) -> RayCheck {
        let (rows, nx) = (self.rows(), self.nx);
        let w4 = self.a_padded.ncols();
        if scratch.len() < rows + 2 * w4 {
            scratch.resize(rows + 2 * w4, 0.0);
        }
        let (sp, rest) = scratch.split_at_mut(rows);
        let (grad, gsize) = rest[..2 * w4].split_at_mut(w4);
        let eq = self.equalities();
        // s_p = b − A x_p: zero on the equalities, the value's terms on the rest.
        sp.copy_from_slice(&b[..rows]);
        add_columns(sp, &self.a_cols, &xp[..nx], -1.0);
        // Each miss against |b_i| + ‖a_i‖₁ ‖x_p‖∞, the normwise backward error of a
        // least-squares point: its entries carry the equalities' conditioning times
        // rounding, and a row whose coefficients on x_p's large entries are small (b_i
        // itself rounding) must not count that as a miss of its own size.
        let xmax = xp[..nx].iter().fold(0.0f64, |a, v| fmax(a, v.abs()));
        let mut particular = 0.0f64;
        for (i, (&bi, &si)) in b[..eq].iter().zip(&sp[..eq]).enumerate() {
            let row: f64 = self.a.row(i).iter().map(|v| v.abs()).sum();
            let size = (bi.abs() + row * xmax).max(f64::MIN_POSITIVE);
            particular = fmax(particular, si.abs() / size);
        }
        let (mut value, mut vsize, mut zmax) = (0.0, f64::MIN_POSITIVE, f64::MIN_POSITIVE);
        for i in eq..rows {
            value += z[i] * sp[i];
            vsize += z[i].abs() * (b[i].abs() + (b[i] - sp[i]).abs());
            zmax = fmax(zmax, z[i].abs());
        }
        let mut dual = 0.0f64;
        let mut start = 0;
        for cone in &self.cones {
            let r = start..start + cone.dim();
            match *cone {
                ConeKind::Zero(_) => {}
                ConeKind::Nonnegative(_) => {
                    for i in r {
                        dual = fmax(dual, -z[i]);
                    }
                }
                ConeKind::SecondOrder(_) => {
                    dual = fmax(dual, soc_excess(z[r.start], &z[r.start + 1..r.end]));
                }
            }
            start += cone.dim();
        }
        // A_inᵀ z_in: no torque terms may be left.
        grad.iter_mut()
            .chain(gsize.iter_mut())
            .for_each(|v| *v = 0.0);
        let (residual, colsize, basis_ok) = self.torque_terms(z, eq, grad, gsize);
        let stationarity = residual / colsize;
        // Each free direction against its own terms: the normwise measure reads them
        // against the largest column, and a joint whose row of Jᵀ is 1e9 times the
        // others' sets that column, so that the terms of the others' directions need
        // not cancel at all (a ray that then passed "proved" infeasible grasps the
        // native solver holds: `fuzz_answers.py backends`).
        let own = |g: f64, t: f64| g.abs() / t.max(f64::MIN_POSITIVE);
        let directions = match &self.eq_null_t {
            None => (0..nx).fold(0.0f64, |a, j| fmax(a, own(grad[j], gsize[j]))),
            Some(nt) => (0..nt.nrows()).fold(0.0f64, |a, r| {
                let row = nt.row(r);
                let t: f64 = row
                    .iter()
                    .zip(&gsize[..nx])
                    .map(|(n, s)| (n * s).abs())
                    .sum();
                fmax(a, own(dot4(row, &grad[..nx]), t))
            }),
        };
        let finite =
            basis_ok && all_finite(&b[..rows]) && all_finite(&xp[..nx]) && all_finite(&z[eq..rows]);
        let horizon = if value >= 0.0 {
            0.0
        } else if residual > 0.0 {
            -value / residual
        } else {
            f64::INFINITY
        };
        let (dual, value) = (dual / zmax, value / vsize);
        // With no free direction, x_p is the only point meeting the equalities: the ray
        // has no horizon, and a value beyond the tolerance proves.
        let margin = match &self.eq_null_t {
            Some(nt) if nt.nrows() == 0 => 1.0,
            _ => RAY_MARGIN,
        };
        RayCheck {
            dual,
            stationarity,
            directions,
            value,
            particular,
            horizon,
            passed: finite
                && dual <= tol
                && stationarity <= tol
                && particular <= tol
                && value < -margin * tol
                && -value >= RAY_MARGIN * directions,
        }
    }

    /// `‖Nᵀ (x − x_p)‖₁` for x and x_p meeting the equalities (`‖x − x_p‖₁` without
    /// them): the free directions' coordinates of x from x_p, the distance a dual ray's
    /// [`RayCheck::horizon`] is measured in.
    pub fn ray_distance(&self, xp: &[f64], x: &[f64]) -> f64 {
        let nx = self.nx;
        match &self.eq_null_t {
            None => x[..nx].iter().zip(xp).map(|(a, b)| (a - b).abs()).sum(),
            Some(nt) => (0..nt.nrows())
                .map(|r| {
                    let terms = nt.row(r).iter().zip(&x[..nx]).zip(xp);
                    terms.map(|((n, a), b)| n * (a - b)).sum::<f64>().abs()
                })
                .sum(),
        }
    }

    /// The torques and free internal forces of a scaled solution `x` at magnitude α.
    pub fn unscale_into(&self, x: &[f64], alpha: f64, torque: &mut Vec<f64>, xi: &mut Vec<f64>) {
        let (m, d) = (self.joints, self.free);
        torque.clear();
        torque.extend((0..m).map(|j| x[j] * alpha / self.col_scale[j]));
        xi.clear();
        xi.extend((0..d).map(|j| x[m + j] * alpha / self.col_scale[m + j]));
    }

    /// The largest violation of `s = b − A x` in K but on the torque limits' rows,
    /// each against the size of the terms `t(i)` of row i: the equalities' against the
    /// largest over every row but the limits', whose constants are in torque units and
    /// may be loose by any factor (1e9 for "no limit": a point 83 N outside a cone
    /// passed, sweep seed 27); the contacts' rows against the largest of theirs, S, as
    /// the core's check judges forces against the largest force. (Against every row,
    /// a contact whose force the wrench alone fixes, 5e-3 outside its cone, passed
    /// beside equalities 1e7 times its terms, moved there by a torque of 1.7e7 through
    /// rounding: `fuzz_answers.py` seed 314274.) A second-order cone is judged against
    /// the larger of S and its terms as its ray of the dual reads them ([`Self::dual_ray`]
    /// with `z = (1, −s_t/‖s_t‖)`), so that where the equalities admit one point, the
    /// ray proves every miss this refuses.
    fn primal_excess(&self, s: &[f64], t: impl Fn(usize) -> f64) -> f64 {
        let eq = self.equalities();
        let (mut scale, mut force) = (f64::MIN_POSITIVE, f64::MIN_POSITIVE);
        for i in (0..self.rows()).filter(|i| !self.limit_rows.contains(i)) {
            let ti = t(i);
            if i >= eq {
                force = fmax(force, ti);
            }
            scale = fmax(scale, ti);
        }
        let mut primal = 0.0f64;
        let mut start = 0;
        for cone in &self.cones {
            let r = start..start + cone.dim();
            start = r.end;
            match *cone {
                ConeKind::Zero(_) => {
                    for i in r {
                        primal = fmax(primal, s[i].abs() / scale);
                    }
                }
                ConeKind::Nonnegative(_) => {
                    for i in r.filter(|i| !self.limit_rows.contains(i)) {
                        primal = fmax(primal, -s[i] / force);
                    }
                }
                ConeKind::SecondOrder(_) => {
                    let (h, tail) = (r.start, r.start + 1..r.end);
                    let excess = soc_excess(s[h], &s[tail.clone()]);
                    if excess > 0.0 {
                        // ‖s_t‖, past the head by the excess.
                        let norm = (excess + s[h]).max(f64::MIN_POSITIVE);
                        let own = t(h) + tail.map(|i| t(i) * s[i].abs() / norm).sum::<f64>();
                        primal = fmax(primal, excess / fmax(force, own));
                    }
                }
            }
        }
        primal
    }

    /// Checks from scratch that `(x, z)` is an optimal primal-dual pair of the scaled
    /// problem with right-hand side `b`, to relative tolerance `tol`:
    /// - primal feasibility: `s = b − A x` in K (the equalities `s_E = 0` included);
    /// - dual feasibility: z in the dual cone K* on the inequality rows;
    /// - stationarity: `P x + Aᵀ z = 0` for some multipliers of the equalities, that
    ///   is, `P x + A_inᵀ z_in` orthogonal to the null space of the equality rows
    ///   (`z`'s entries on the equalities are not read);
    /// - complementarity, the duality gap: `s_inᵀ z_in ≈ 0`.
    ///
    /// Every measure is relative to the size of the terms it sums, so the check is the
    /// same at any scale. `scratch` is grown once and reused (no allocation after).
    pub fn certificate(
        &self,
        b: &[f64],
        x: &[f64],
        z: &[f64],
        tol: f64,
        scratch: &mut Vec<f64>,
    ) -> Certificate {
        let (rows, m, nx) = (self.rows(), self.joints, self.nx);
        let w4 = self.a_padded.ncols();
        // Every entry used is written below: no clearing.
        let need = 3 * rows + nx + 2 * w4;
        if scratch.len() < need {
            scratch.resize(need, 0.0);
        }
        let (s, rest) = scratch.split_at_mut(rows);
        let (size, rest) = rest.split_at_mut(rows);
        let (zk, rest) = rest.split_at_mut(rows);
        let (xabs, rest) = rest.split_at_mut(nx);
        let (grad, gsize) = rest[..2 * w4].split_at_mut(w4);
        // s = b − A x.
        s.copy_from_slice(&b[..rows]);
        add_columns(s, &self.a_cols, &x[..nx], -1.0);
        let eq = self.equalities();
        let mut dual = 0.0f64;
        let mut start = 0;
        for cone in &self.cones {
            let r = start..start + cone.dim();
            start = r.end;
            match *cone {
                ConeKind::Zero(_) => {}
                ConeKind::Nonnegative(_) => {
                    for i in r.filter(|&i| !self.fixed[i]) {
                        dual = fmax(dual, -z[i]);
                    }
                }
                ConeKind::SecondOrder(_) if !self.fixed[r.start] => {
                    dual = fmax(dual, soc_excess(z[r.start], &z[r.start + 1..r.end]));
                }
                ConeKind::SecondOrder(_) => {}
            }
        }
        // The measures below read z in K*: a z outside it, projected there. The
        // projection is itself a multiplier, so that the gap's bound on σ holds for it
        // exactly, where a violation judged against the largest multiplier (1e8 on a
        // ray of the dual) would be a large one.
        // (The maxima above skip NaN: a non-finite input fails below instead.)
        let finite = all_finite(b) && all_finite(x) && all_finite(&z[eq..]);
        let z: &[f64] = if dual > 0.0 {
            project_dual(&self.cones, z, zk);
            zk
        } else {
            z
        };
        // zscale and sᵀz over the inequality rows in one pass.
        let (mut zscale, mut sz) = (f64::MIN_POSITIVE, 0.0);
        // (A fixed row's multiplier is not read: a point 1000 times the optimal σ
        // passed on a multiplier of 1e18 there, its b·z swamping the gap's terms.)
        for ((si, zi), _) in s
            .iter()
            .zip(z)
            .zip(&self.fixed)
            .skip(eq)
            .filter(|(_, &f)| !f)
        {
            zscale = fmax(zscale, zi.abs());
            sz += si * zi;
        }
        // g = P x + A_inᵀ z_in, against Σ |terms| per column.
        for j in 0..w4 {
            let g = if j < m { 2.0 * x[j] } else { 0.0 };
            grad[j] = g;
            gsize[j] = g.abs();
        }
        let (residual, colsize, basis_ok) = self.torque_terms(z, eq, grad, gsize);
        let stationarity = residual / colsize;
        let finite = finite && basis_ok;
        // |b_i| + Σ_j |a_ij x_j| per row, formed once and only when a measure needs it.
        let mut sized = false;
        let mut row_sizes = |size: &mut [f64]| {
            if !std::mem::replace(&mut sized, true) {
                for (v, xj) in xabs.iter_mut().zip(x) {
                    *v = xj.abs();
                }
                for (z, bi) in size.iter_mut().zip(b) {
                    *z = bi.abs();
                }
                add_columns(size, &self.abs_cols, xabs, 1.0);
            }
        };
        // The primal violation ([`Self::primal_excess`]) against its terms' lower bound
        // |b_i| + |(A x)_i| first: a violation within tolerance of that is within
        // tolerance of the terms, and only a point that fails it pays for the second
        // pass, |A| |x|.
        let mut primal = self.primal_excess(s, |i| b[i].abs() + (b[i] - s[i]).abs());
        if primal > tol {
            row_sizes(size);
            let size = &*size;
            primal = self.primal_excess(s, |i| size[i]);
        }
        // A limit row against its own terms, |b_i| + ‖a_i‖₁ ‖x_τ‖∞: its torque comes out
        // of the linear algebra with an error relative to the largest (the core's
        // check reads τ so too), and a bound at 0 has no other term.
        let xmax = x[..m].iter().fold(0.0f64, |a, v| fmax(a, v.abs()));
        for i in self.limit_rows.clone().filter(|&i| s[i] < 0.0) {
            let (lo, hi) = self.row_span[i];
            let row: f64 = self.a_padded.row(i)[lo..hi].iter().map(|v| v.abs()).sum();
            let size = (b[i].abs() + row * xmax).max(f64::MIN_POSITIVE);
            primal = fmax(primal, -s[i] / size);
        }
        let dual = dual / zscale;
        // The gap bounds σ's error: for z in K*, σ(x) − σ* ≤ sᵀz + ‖ρ‖²/4 (the
        // Lagrangian, of curvature 2 on the equalities' null space, is at least
        // σ(x) − sᵀz − ‖ρ‖²/4 there, and at most σ on every feasible point), ρ the
        // stationarity residual above. Its first term is judged against σ's own terms
        // xᵀPx = 2σ, with no floor: the scaled optimum is not always of size 1 (rows
        // that x = 0 meets can set α), and a floor of 1 once let a point with 4e5 times
        // the optimal σ pass when the optimum's terms were 1e-18. Beyond that, only the
        // rounding of sᵀz, ε (nx + rows) Σ |z_i| (|b_i| + |a_i| |x|), is admitted:
        // multipliers that grow along a ray of the dual (an unloaded contact held at
        // its apex by a torque limit, the rows of a face every feasible point lies on)
        // make those terms large without making σ more accurate, and against `tol`
        // times them a point 1e-4 above σ* passed (fuzz_answers.py seed 230). The
        // second term, second order, is left to the stationarity check: the rounding
        // of ρ alone, on a column of 3e13 (a joint with short moment arms), is 4e-4 σ
        // where σ agrees to 1e-11 in five unit systems (fuzz_answers.py seed 2233).
        let xpx: f64 = 2.0 * x[..m].iter().map(|v| v * v).sum::<f64>();
        let excess = sz.abs();
        let gap = if excess <= tol * xpx {
            excess / xpx.max(f64::MIN_POSITIVE)
        } else {
            row_sizes(size);
            let terms: f64 = (eq..rows)
                .filter(|&i| !self.fixed[i])
                .map(|i| z[i].abs() * size[i])
                .sum();
            let rounding = f64::EPSILON * (nx + rows) as f64 * terms;
            excess / (xpx + rounding / tol).max(f64::MIN_POSITIVE)
        };
        Certificate {
            primal,
            dual,
            stationarity,
            gap,
            excess: excess / (0.5 * xpx).max(f64::MIN_POSITIVE),
            passed: finite && primal <= tol && dual <= tol && stationarity <= tol && gap <= tol,
        }
    }
}

/// Where the torques' scales g (below) spread by more than [`ROW_SPREAD`], the null
/// space of the equality rows and their pseudo-inverse from the model's factors,
/// `C = Bᵀ diag(r)` (no decomposition of the rows): the form's rows are
/// `E = diag(1/ν) Bᵀ diag(1/g)` on the torques, with ν their norms and `g = s / r`
/// (s the torques' column scales), and zero on the free internal forces. So
/// `null(E) = diag(g) range(N_B)` on the torques (with every free direction), and
/// `x₀ = diag(g) B diag(ν) v` solves `E x = v`, whose least-norm solution is `x₀`
/// less its part in the null space. Each row keeps its digits relative to its own
/// g ([`orthonormal_columns`]): decomposed, E's columns span the spread of r (1e8
/// where a joint's moment arms are 1e-8 of the others'), and the basis's rounding
/// left a feasible grasp 1e-9 outside its circumscribed cones. `None` (the
/// decomposition decides, accurate at a smaller spread) otherwise, where the factors
/// do not fit, or where g is not finite and positive.
fn factored_equalities(
    model: &crate::GraspModel,
    col_scale: &[f64],
    norms: &[f64],
) -> Option<(Matrix, Matrix)> {
    let (b, nb, r) = (&model.eq_basis, &model.eq_null, &model.torque_scale);
    let (m, p, d) = (model.joints(), norms.len(), model.free_dim());
    if b.nrows() != m || b.ncols() != p || nb.nrows() != m || nb.ncols() + p != m || r.len() != m {
        return None;
    }
    let g: Vec<f64> = (0..m).map(|j| col_scale[j] / r[j]).collect();
    let (lo, hi) = g.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
        (lo.min(v), hi.max(v))
    });
    if !(lo > 0.0 && hi.is_finite() && hi > ROW_SPREAD * lo) {
        return None;
    }
    let k = m - p;
    let null = if k > 0 {
        orthonormal_columns(&Matrix::from_fn(m, k, |i, j| g[i] * nb[(i, j)]))?
    } else {
        Matrix::zeros(m, 0)
    };
    // x₀ = diag(g) B diag(ν), then less N Nᵀ x₀, twice: x₀'s rows spread as g does, so
    // that one pass leaves a part in N of ε times x₀'s largest row (1e-8 of the answer
    // where one joint's arms are 1e9 times the others', which the certificate's
    // stationarity then read), and the second takes that to ε of what remains.
    let mut pinv = Matrix::from_fn(m + d, p, |i, j| {
        if i < m {
            g[i] * b[(i, j)] * norms[j]
        } else {
            0.0
        }
    });
    for _ in 0..2 {
        for j in 0..p {
            let ntx: Vec<f64> = (0..k)
                .map(|c| (0..m).map(|i| null[(i, c)] * pinv[(i, j)]).sum())
                .collect();
            for i in 0..m {
                pinv[(i, j)] -= (0..k).map(|c| null[(i, c)] * ntx[c]).sum::<f64>();
            }
        }
    }
    // Nᵀ: the torques' basis, then each free direction.
    let nt = Matrix::from_fn(k + d, m + d, |c, i| match (c < k, i < m) {
        (true, true) => null[(i, c)],
        (false, false) => f64::from(c - k == i - m),
        _ => 0.0,
    });
    Some((nt, pinv))
}

/// `‖tail‖ − head` where positive, else 0: how far `(head, tail)` is outside its
/// second-order cone (no square root for a point inside).
#[inline]
pub fn soc_excess(head: f64, tail: &[f64]) -> f64 {
    let q: f64 = tail.iter().map(|v| v * v).sum();
    if head >= 0.0 && q <= head * head {
        0.0
    } else {
        q.sqrt() - head
    }
}

/// `z` projected on the dual cone, each block on its own, into `out` (the
/// equalities' entries copied: their multipliers are free). The cones are self-dual.
fn project_dual(cones: &[ConeKind], z: &[f64], out: &mut [f64]) {
    let mut start = 0;
    for cone in cones {
        let r = start..start + cone.dim();
        match *cone {
            ConeKind::Zero(_) => out[r.clone()].copy_from_slice(&z[r.clone()]),
            ConeKind::Nonnegative(_) => {
                for i in r.clone() {
                    out[i] = z[i].max(0.0);
                }
            }
            ConeKind::SecondOrder(_) => {
                let (h, t) = (z[r.start], &z[r.start + 1..r.end]);
                let q = t.iter().map(|v| v * v).sum::<f64>().sqrt();
                if q <= h {
                    out[r.clone()].copy_from_slice(&z[r.clone()]);
                } else if q <= -h {
                    out[r.clone()].fill(0.0);
                } else {
                    // The nearest point of the cone: on its boundary, (h + q)/2 (1, t/q).
                    let c = 0.5 * (h + q);
                    out[r.start] = c;
                    for (o, v) in out[r.start + 1..r.end].iter_mut().zip(t) {
                        *o = c * v / q;
                    }
                }
            }
        }
        start = r.end;
    }
}

/// Whether every entry is finite: `v · 0` is 0 for a finite v and NaN otherwise, so
/// one sum tells, without a branch per entry.
fn all_finite(v: &[f64]) -> bool {
    v.iter().map(|v| v * 0.0).sum::<f64>() == 0.0
}

/// The larger of two numbers, one comparison (NaN is the caller's to rule out).
#[inline]
fn fmax(a: f64, b: f64) -> f64 {
    if b > a {
        b
    } else {
        a
    }
}

/// The outcome of [`ConicForm::dual_ray`]: each measure relative to its terms.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayCheck {
    /// Largest violation of `z ∈ K*` on the inequality rows, against `‖z‖∞`.
    pub dual: f64,
    /// The torque terms left, `‖N_Eᵀ A_inᵀ z‖∞` (on the null space of the equalities),
    /// against the largest column sum of `|a_ij z_i|`.
    pub stationarity: f64,
    /// The largest of the same terms in each free direction (each column without
    /// equalities) against that direction's own terms. A direction whose terms do not
    /// cancel is one a torque can move along at the problem's own scale, so a ray
    /// proves nothing unless `value` is [`RAY_MARGIN`] times beyond this.
    pub directions: f64,
    /// `zᵀ (b − A x_p)` on the inequality rows, against the size of its terms: negative
    /// for a certificate.
    pub value: f64,
    /// How far `x_p` misses the equalities, each row against `|b_i| + ‖a_i‖₁ ‖x_p‖∞`.
    pub particular: f64,
    /// How far from `x_p` the ray reaches: no x meeting the equalities closer than
    /// this, by [`ConicForm::ray_distance`], has `s ∈ K` (`zᵀ s` is the value's
    /// `zᵀ s_p` less the torque terms' `(Nᵀ A_inᵀ z)ᵀ y`, at most
    /// `‖Nᵀ A_inᵀ z‖∞ ‖y‖₁`). Infinite where no direction is free.
    pub horizon: f64,
    /// Whether `z` proves the problem infeasible: every measure within the tolerance,
    /// `value` below −[`RAY_MARGIN`] times it (below −tolerance where the equalities
    /// leave no free direction: no torque but `x_p` meets them) and below
    /// −[`RAY_MARGIN`] times `directions`.
    pub passed: bool,
}

/// How far below zero, in multiples of the tolerance, a dual ray's relative value must
/// be where the equalities leave free directions: clearly negative, not rounding, for
/// a ray proves only that no torque within |value| / stationarity of the problem's
/// scale holds the grasp.
pub const RAY_MARGIN: f64 = 1e3;

/// Relative tolerance of the optimality certificate, [`ConicForm::certificate`] (each
/// measure against the size of its own terms, on the scaled problem), with which the
/// solvers check an answer before they call it optimal.
pub const CERTIFICATE_TOLERANCE: f64 = 1e-9;

/// The outcome of [`ConicForm::certificate`]: each measure relative to its terms.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Certificate {
    /// Largest cone or equality violation of `s = b − A x`, relative to the largest
    /// `|b_i| + Σ_j |a_ij x_j|` of the rows but the torque limits' (to
    /// `max(|b_i|, |(A x)_i|)`, a lower bound of it, when that already passes); a torque
    /// limit's, relative to its own `|b_i| + ‖a_i‖₁ ‖x_τ‖∞`.
    pub primal: f64,
    /// Largest violation of `z ∈ K*`.
    pub dual: f64,
    /// `‖P x + Aᵀ z‖∞`.
    pub stationarity: f64,
    /// `|sᵀz|`, the duality gap, against `xᵀPx` and the rounding of its terms.
    pub gap: f64,
    /// `|sᵀz| / σ`: for z in K* (projected there), a bound on how far σ is above the
    /// optimum, relative.
    pub excess: f64,
    /// Whether every measure is within the tolerance.
    pub passed: bool,
}

impl Certificate {
    /// Whether the gap alone bounds σ within `2 tol` of the optimum (`|sᵀz| ≤ tol
    /// xᵀPx`), without the rounding of sᵀz's terms that [`Self::passed`] also admits.
    /// That allowance is for an iterate whose method converged on its own, stricter,
    /// measures; an iterate it stopped short at has only this bound.
    pub fn bounds_sigma(&self, tol: f64) -> bool {
        self.excess <= 2.0 * tol
    }

    /// Whether the point is feasible and stationary within `tol` and the gap bounds σ
    /// within `excess` of the optimum, relative: an answer of reduced accuracy.
    pub fn almost(&self, tol: f64, excess: f64) -> bool {
        self.primal <= tol && self.dual <= tol && self.stationarity <= tol && self.excess <= excess
    }
}
