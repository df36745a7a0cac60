//! Constraint representations and the linearised torque QP, a view of a
//! [`GraspModel`] and a [`Constraints`] (paper sections 3–4, eqs. 39, 43).
//!
//! Each contact's cone is a typed block: exact, or an inscribed polyhedron. The linear
//! rows are, per contact, the inscribed faces (`S_c f_c ≥ 0`) or none, then its minimum
//! normal force `fz ≥ f_min`, and after all contacts the torque limits. With
//! `f = Z1 w + Z2 τ + N ξ` they read
//!
//! ```text
//! H τ + Hp ξ ≥ c(w) = c0 − Hw w,      H = S Z2, Hw = S Z1, Hp = S N   (eqs. 39, 43)
//! ```
//!
//! and the problem is `min Σ w_j τ_j²` subject to those rows, `C τ = e(w)` and, for
//! exact blocks, the exact cones. Every row carries a [`RowId`] (contact, block, face)
//! that survives re-linearising another contact.

use crate::cone::{inscribed_cone, InscribedCone, Linearization};
use crate::contact::ContactModel;
use crate::error::ModelError;
use crate::linalg::{decompose, RankThreshold};
use crate::matrix::{dot, Matrix};
use crate::model::GraspModel;
use serde::Serialize;
use std::fmt;
use std::sync::{Arc, OnceLock};

/// The stable identity of a linear constraint row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[non_exhaustive]
pub enum RowId {
    /// Face `face` of contact `contact`'s inscribed cone (eq. 50 order).
    Face {
        /// Contact index.
        contact: usize,
        /// Face index within the contact's cone.
        face: usize,
    },
    /// `fz ≥ f_min` of contact `contact`.
    NormalForce {
        /// Contact index.
        contact: usize,
    },
    /// `τ_j ≤ upper_j` (`upper`) or `τ_j ≥ lower_j`.
    TorqueLimit {
        /// Joint index.
        joint: usize,
        /// Upper or lower bound.
        upper: bool,
    },
}

impl RowId {
    /// Row `k` of `rows` rows of contact `contact`: faces, then the normal force last.
    fn of_contact(contact: usize, k: usize, rows: usize) -> Self {
        if k + 1 == rows {
            RowId::NormalForce { contact }
        } else {
            RowId::Face { contact, face: k }
        }
    }
}

impl fmt::Display for RowId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            RowId::Face { contact, face } => write!(f, "contact {contact} face {face}"),
            RowId::NormalForce { contact } => write!(f, "contact {contact} normal force"),
            RowId::TorqueLimit { joint, upper } => write!(
                f,
                "joint {joint} {} torque limit",
                if upper { "upper" } else { "lower" }
            ),
        }
    }
}

/// One contact's friction cone, as a backend sees it.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub enum ConeRepr {
    /// The exact cone (eqs. 1–4).
    Exact,
    /// An inscribed polyhedral cone.
    Inscribed(InscribedCone),
}

/// The cone representation of every contact.
#[derive(Clone, Debug)]
pub struct Constraints {
    /// One per contact, in contact order.
    pub cones: Vec<ConeRepr>,
    /// The linearisation the inscribed blocks were built with, if any.
    pub linearization: Option<Linearization>,
}

impl Constraints {
    /// Every contact inscribed at `lin` (assumed validated).
    pub fn inscribed(model: &GraspModel, lin: &Linearization) -> Self {
        // Hands repeat contact models (one friction coefficient for every fingertip):
        // each distinct one is built once.
        let mut cones: Vec<ConeRepr> = Vec::with_capacity(model.contacts.len());
        for (i, c) in model.contacts.iter().enumerate() {
            let cone = match model.contacts[..i].iter().position(|d| d == c) {
                Some(j) => cones[j].clone(),
                None => ConeRepr::Inscribed(inscribed_cone(c, lin)),
            };
            cones.push(cone);
        }
        Self {
            cones,
            linearization: Some(*lin),
        }
    }

    /// Every contact exact.
    pub fn exact(model: &GraspModel) -> Self {
        Self {
            cones: vec![ConeRepr::Exact; model.contacts.len()],
            linearization: None,
        }
    }

    /// Whether any contact uses its exact cone.
    pub fn has_exact(&self) -> bool {
        self.cones.iter().any(|c| matches!(c, ConeRepr::Exact))
    }
}

/// One contact's place in f and in the linear rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactBlock {
    /// The contact model.
    pub model: ContactModel,
    /// Index of its first force component in f.
    pub offset: usize,
    /// Index of its first linear row.
    pub first_row: usize,
    /// Its number of linear rows (faces, then `fz ≥ f_min`).
    pub rows: usize,
}

/// A least-distance QP as the native solver reads it: minimise `Σ weights_j x_j²`
/// subject to `h x ≥ c0 − hw w` and `eq x = −eq_w w` (`eq` with independent rows).
#[derive(Clone, Copy, Debug)]
pub struct LeastDistance<'a> {
    /// Inequality rows, R × k.
    pub h: InequalityRows<'a>,
    /// Constant part of the right-hand side.
    pub c0: &'a [f64],
    /// The size of the terms behind each entry of `c0`, which bounds its rounding.
    pub c0_terms: &'a [f64],
    /// Wrench part of the right-hand side, R × 6.
    pub hw: &'a Matrix,
    /// Equality rows, p × k, independent.
    pub eq: &'a Matrix,
    /// Wrench part of the equalities, p × 6.
    pub eq_w: &'a Matrix,
    /// Objective weights, k.
    pub weights: &'a [f64],
    /// Identity of each inequality row.
    pub rows: &'a [RowId],
    /// How `eq` was formed, when the model's consistency rows are it (see
    /// [`EqFactors`]).
    pub eq_factors: Option<EqFactors<'a>>,
    /// What the answer adds to `x` (the passive torques' `u_p`, [`crate::model::Passive`];
    /// empty without): the σ reported is `Σ weights_j (x_j + offset_j)²`.
    pub offset: &'a [f64],
}

/// The inequality rows H of a [`LeastDistance`] problem.
#[derive(Clone, Copy, Debug)]
pub enum InequalityRows<'a> {
    /// H itself, R × k.
    Formed(&'a Matrix),
    /// `H = S Z2`, never formed: the native solver reads H only through products and
    /// row norms, which the factors give for a fraction of H's own cost.
    Factored(RowFactors<'a>),
}

/// `C = Bᵀ diag(scale)` with B orthonormal (m × p), and `null` an orthonormal basis of
/// the null space of Bᵀ (m × (m − p)): [`GraspModel::eq_basis`],
/// [`GraspModel::eq_null`] and [`GraspModel::torque_scale`]. With them, the null space
/// of C under any diagonal weighting is a rescaled `null`, and `B` gives a particular
/// solution of `C τ = e`: no decomposition of C is needed.
#[derive(Clone, Copy, Debug)]
pub struct EqFactors<'a> {
    /// B, m × p.
    pub basis: &'a Matrix,
    /// An orthonormal basis of the null space of Bᵀ, m × (m − p).
    pub null: &'a Matrix,
    /// The column scale, m.
    pub scale: &'a [f64],
}

/// `H = S Z2` with S block-diagonal (at most four nonzeros per row), and ±1 in the
/// torque-limit rows: a product `H X` costs one product through Z2 (n rows) and a few
/// multiply-adds per row of H, instead of one full row of H per row.
#[derive(Clone, Copy, Debug)]
pub struct RowFactors<'a> {
    /// Z2, n × m.
    pub z2: &'a Matrix,
    /// Each contact's rows.
    pub contacts: &'a [ContactBlock],
    /// Each contact's cone (its face rows are the blocks of S).
    pub cones: &'a [ConeRepr],
}

impl LeastDistance<'_> {
    /// `H X` for X with one row per variable, through [`RowFactors`] when H has them.
    pub fn h_mul(&self, x: &Matrix) -> Matrix {
        let f = match self.h {
            InequalityRows::Formed(h) => return h.matmul(x),
            InequalityRows::Factored(f) => f,
        };
        let zx = f.z2.matmul(x);
        let cols = x.ncols();
        let mut out = Matrix::zeros(self.rows.len(), cols);
        for (c, repr) in f.contacts.iter().zip(f.cones) {
            let dim = c.model.dim();
            let zc = &zx.as_slice()[c.offset * cols..(c.offset + dim) * cols];
            for k in 0..c.rows {
                let (face, dim) = face_row(repr, &c.model, k);
                combine(out.row_mut(c.first_row + k), &face[..dim], zc);
            }
        }
        for (i, id) in self.rows.iter().enumerate() {
            if let RowId::TorqueLimit { joint, upper } = *id {
                let sign = if upper { -1.0 } else { 1.0 };
                for (y, v) in out.row_mut(i).iter_mut().zip(x.row(joint)) {
                    *y = sign * v;
                }
            }
        }
        out
    }

    /// `H_i · x` and the size of its terms (`Σ |h_ij x_j|`, through the factors `Σ_t
    /// |face_t| Σ_j |z2_tj x_j|`), through [`RowFactors`] when H has them: `face ·
    /// (Z2 x)` on the contact's rows of Z2, so that the product keeps the rounding of
    /// its own terms.
    pub fn row_value(&self, i: usize, x: &[f64]) -> (f64, f64) {
        let terms = |row: &[f64]| -> (f64, f64) {
            row.iter()
                .zip(x)
                .fold((0.0, 0.0), |(v, t), (a, b)| (v + a * b, t + (a * b).abs()))
        };
        let f = match self.h {
            InequalityRows::Formed(h) => return terms(h.row(i)),
            InequalityRows::Factored(f) => f,
        };
        if let RowId::TorqueLimit { joint, upper } = self.rows[i] {
            let v = if upper { -x[joint] } else { x[joint] };
            return (v, v.abs());
        }
        let Some((c, repr)) = (f.contacts.iter().zip(f.cones))
            .find(|(c, _)| (c.first_row..c.first_row + c.rows).contains(&i))
        else {
            return (0.0, 0.0);
        };
        let (face, dim) = face_row(repr, &c.model, i - c.first_row);
        (0..dim).fold((0.0, 0.0), |(v, t), k| {
            let (zv, zt) = terms(f.z2.row(c.offset + k));
            (v + face[k] * zv, t + face[k].abs() * zt)
        })
    }

    /// The largest Euclidean norm of a row of `H diag(col_scale)`: through [`RowFactors`]
    /// from each contact's Gram matrix of its scaled rows of Z2 (at most 4 × 4), so
    /// without H.
    pub fn max_row_norm(&self, col_scale: &[f64]) -> f64 {
        let plain = self.max_row_norm_unscaled(col_scale);
        if plain == 0.0 || (plain.is_finite() && (1e-140..=1e140).contains(&plain)) {
            return plain;
        }
        // Squares beyond the range of f64 (a torque unit some 1e150 times the force
        // unit's): the columns scaled by a power of two first, which is exact.
        // The largest |m_ij d_j| of H's (or Z2's) columns scaled by d.
        let largest = |m: &Matrix| {
            m.as_slice()
                .chunks_exact(m.ncols().max(1))
                .flat_map(|row| row.iter().zip(col_scale).map(|(v, d)| (v * d).abs()))
                .fold(0.0f64, f64::max)
        };
        let big = match self.h {
            InequalityRows::Formed(h) => largest(h),
            InequalityRows::Factored(f) => largest(f.z2),
        };
        let big = col_scale.iter().fold(big, |a, d| a.max(d.abs()));
        if !big.is_normal() {
            return plain;
        }
        let s = 2f64.powi(-(big.log2().round() as i32));
        let scaled: Vec<f64> = col_scale.iter().map(|d| d * s).collect();
        self.max_row_norm_unscaled(&scaled) / s
    }

    /// [`Self::max_row_norm`] without the scaling; NaN where a square overflowed.
    fn max_row_norm_unscaled(&self, col_scale: &[f64]) -> f64 {
        let mut largest = 0.0f64;
        self.row_squares(col_scale, |_, sq| largest = max_or_nan(largest, sq));
        largest.sqrt()
    }

    /// The Euclidean norm of each row of `H diag(col_scale)` into `out`, and their
    /// largest, as [`Self::max_row_norm`] finds it (in one pass where the squares stay
    /// within the range of f64, scaled by a power of two where they would not).
    pub fn row_norms(&self, col_scale: &[f64], out: &mut Vec<f64>) -> f64 {
        out.clear();
        out.resize(self.rows.len(), 0.0);
        self.row_squares(col_scale, |i, sq| out[i] = sq);
        let plain = out.iter().fold(0.0, |a, &v| max_or_nan(a, v)).sqrt();
        if plain == 0.0 || (plain.is_finite() && (1e-140..=1e140).contains(&plain)) {
            out.iter_mut().for_each(|v| *v = v.sqrt());
            return plain;
        }
        let big = self.max_row_norm(col_scale);
        let s = if big.is_normal() {
            2f64.powi(-(big.log2().round() as i32))
        } else {
            1.0
        };
        let scaled: Vec<f64> = col_scale.iter().map(|d| d * s).collect();
        self.row_squares(&scaled, |i, sq| out[i] = sq.sqrt() / s);
        big
    }

    /// `visit(i, ‖H_i diag(col_scale)‖²)` for every row i.
    fn row_squares(&self, col_scale: &[f64], mut visit: impl FnMut(usize, f64)) {
        let f = match self.h {
            InequalityRows::Formed(h) => {
                for i in 0..h.nrows() {
                    let sq = h
                        .row(i)
                        .iter()
                        .zip(col_scale)
                        .map(|(h, d)| (h * d) * (h * d))
                        .sum::<f64>();
                    visit(i, sq);
                }
                return;
            }
            InequalityRows::Factored(f) => f,
        };
        for (c, repr) in f.contacts.iter().zip(f.cones) {
            // (A contact has at most four force components: `ContactModel::dim`.)
            let dim = c.model.dim();
            let mut gram = [[0.0f64; 4]; 4];
            for t in 0..dim {
                for u in 0..=t {
                    let v = scaled_dot(f.z2.row(c.offset + t), f.z2.row(c.offset + u), col_scale);
                    gram[t][u] = v;
                    gram[u][t] = v;
                }
            }
            match repr {
                ConeRepr::Inscribed(cone) => {
                    // (Zero-padded to four: a fixed number of terms, no loop bounds.)
                    let mut f = [0.0f64; 4];
                    for (k, s) in cone
                        .faces
                        .as_slice()
                        .chunks_exact(dim)
                        .take(c.rows)
                        .enumerate()
                    {
                        f[..dim].copy_from_slice(s);
                        let mut sq = 0.0;
                        for (ft, g) in f.iter().zip(&gram) {
                            sq += ft * (g[0] * f[0] + g[1] * f[1] + g[2] * f[2] + g[3] * f[3]);
                        }
                        visit(c.first_row + k, sq);
                    }
                }
                // The normal force's row.
                ConeRepr::Exact => {
                    let n = c.model.normal_index();
                    visit(c.first_row, gram[n][n]);
                }
            }
        }
        for (i, id) in self.rows.iter().enumerate() {
            if let RowId::TorqueLimit { joint, .. } = *id {
                visit(i, col_scale[joint] * col_scale[joint]);
            }
        }
    }
}

/// The linear rows of a model under some constraints: the view every backend reads.
#[derive(Clone, Debug)]
pub struct TorqueQp {
    /// The grasp.
    pub model: Arc<GraspModel>,
    /// The cone of each contact.
    pub constraints: Constraints,
    /// Each contact's rows.
    pub contacts: Vec<ContactBlock>,
    /// H = S Z2, R × m, formed the first time [`TorqueQp::h`] is called: the native
    /// solver reads it through [`RowFactors`] and never forms it.
    h: OnceLock<Matrix>,
    /// Hp = S N, R × d (d = 0 unless the internal forces are free).
    pub hp: Matrix,
    /// `c(w) = c0 − hw · w`: the constant part (minimum normal forces, limits).
    pub c0: Vec<f64>,
    /// The size of the terms behind each entry of `c0` (the minimum normal force or the
    /// limit, and the passive torques' force or torque offset), which bounds its
    /// rounding: on a contact the passive torques alone leave unloaded, `c0` is their
    /// force cancelled to nearly zero.
    pub c0_terms: Vec<f64>,
    /// `c(w) = c0 − hw · w`: S Z1, zero on limit rows, R × 6.
    pub hw: Matrix,
    /// What each row stands for.
    pub rows: Vec<RowId>,
    /// Each limited torque's `(index, lower, upper)`, an open side infinite: what the
    /// residual check reads.
    limits: Vec<(usize, f64, f64)>,
}

/// The rows of one contact: `(S_c, fmin row last)`.
fn contact_faces(model: &GraspModel, ci: usize, repr: &ConeRepr) -> Matrix {
    let c = &model.contacts[ci];
    match repr {
        ConeRepr::Inscribed(cone) => cone.faces.clone(),
        ConeRepr::Exact => {
            let mut row = vec![0.0; c.dim()];
            row[c.normal_index()] = 1.0;
            Matrix::from_rows(&[row], c.dim())
        }
    }
}

/// The larger of two values, NaN if either is (`f64::max` drops a NaN).
fn max_or_nan(a: f64, b: f64) -> f64 {
    if b.is_nan() || b > a {
        b
    } else {
        a
    }
}

/// `Σ (a_i d_i)(b_i d_i)` in four independent lanes (a single chain of additions waits
/// on each one's latency).
fn scaled_dot(a: &[f64], b: &[f64], d: &[f64]) -> f64 {
    let mut s = [0.0f64; 4];
    let (mut ca, mut cb, mut cd) = (a.chunks_exact(4), b.chunks_exact(4), d.chunks_exact(4));
    for ((x, y), z) in (&mut ca).zip(&mut cb).zip(&mut cd) {
        for l in 0..4 {
            s[l] += (x[l] * z[l]) * (y[l] * z[l]);
        }
    }
    let mut tail = 0.0;
    for ((x, y), z) in ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .zip(cd.remainder())
    {
        tail += (x * z) * (y * z);
    }
    (s[0] + s[1]) + (s[2] + s[3]) + tail
}

/// Contact `c`'s face row k, its block of S (at most four entries: `ContactModel::dim`):
/// the inscribed face, or the exact cone's one row, its normal force.
fn face_row(repr: &ConeRepr, c: &ContactModel, k: usize) -> ([f64; 4], usize) {
    let mut face = [0.0f64; 4];
    let dim = c.dim();
    match repr {
        ConeRepr::Inscribed(cone) => {
            face[..dim].copy_from_slice(&cone.faces.as_slice()[k * dim..(k + 1) * dim])
        }
        ConeRepr::Exact => face[c.normal_index()] = 1.0,
    }
    (face, dim)
}

/// `out = Σ_t face[t] z_t`, z_t the rows of `z` (each `out.len()` long), summed in
/// order of t in one pass. (The same sums as adding each nonzero term to a zero row in
/// turn, up to the sign of an exact zero.)
fn combine(out: &mut [f64], face: &[f64], z: &[f64]) {
    let cols = out.len();
    match *face {
        [s0] => {
            for (o, a) in out.iter_mut().zip(&z[..cols]) {
                *o = s0 * a;
            }
        }
        [s0, s1, s2] => {
            let (z0, rest) = z.split_at(cols);
            let (z1, z2) = rest.split_at(cols);
            for (((o, a), b), c) in out.iter_mut().zip(z0).zip(z1).zip(&z2[..cols]) {
                *o = s0 * a + s1 * b + s2 * c;
            }
        }
        [s0, s1, s2, s3] => {
            let (z0, rest) = z.split_at(cols);
            let (z1, rest) = rest.split_at(cols);
            let (z2, z3) = rest.split_at(cols);
            for ((((o, a), b), c), d) in out.iter_mut().zip(z0).zip(z1).zip(z2).zip(&z3[..cols]) {
                *o = s0 * a + s1 * b + s2 * c + s3 * d;
            }
        }
        _ => {
            out.iter_mut().for_each(|o| *o = 0.0);
            for (s, zt) in face.iter().zip(z.chunks_exact(cols.max(1))) {
                for (o, a) in out.iter_mut().zip(zt) {
                    *o += s * a;
                }
            }
        }
    }
}

/// The constant side of row k of contact ci's r rows with face `face`: the minimum
/// normal force on the last (the normal's), less the face's share of the passive
/// torques' force at `v = 0` ([`crate::model::Passive::solver_force`]).
/// With the size of its terms.
fn contact_c0(model: &GraspModel, ci: usize, k: usize, r: usize, face: &[f64]) -> (f64, f64) {
    let fmin = if k + 1 == r {
        model.min_normal_force[ci]
    } else {
        0.0
    };
    let off = model.offsets[ci];
    match model.passive.solver_force.as_slice() {
        [] => (fmin, fmin.abs()),
        fp => {
            let terms = &model.passive.solver_force_terms[off..];
            let size: f64 = face.iter().zip(terms).map(|(s, t)| s.abs() * t).sum();
            (fmin - dot(face, &fp[off..]), fmin.abs() + size)
        }
    }
}

/// `(S_c Z2_c, S_c N_c, S_c Z1_c)` of one contact's rows.
fn block_rows(model: &GraspModel, ci: usize, faces: &Matrix) -> (Matrix, Matrix, Matrix) {
    let off = model.offsets[ci];
    let dim = model.contacts[ci].dim();
    let (m, d) = (model.joints(), model.free_dim());
    let mul = |src: &Matrix, cols: usize| {
        let mut out = Matrix::zeros(faces.nrows(), cols);
        if cols > 0 {
            let rows = &src.as_slice()[off * cols..(off + dim) * cols];
            for i in 0..faces.nrows() {
                combine(out.row_mut(i), faces.row(i), rows);
            }
        }
        out
    };
    (
        mul(&model.z2, m),
        mul(&model.passive_basis, d),
        mul(&model.z1, 6),
    )
}

impl TorqueQp {
    /// The linear rows of `model` under `constraints` (one entry per contact).
    pub fn new(model: Arc<GraspModel>, constraints: Constraints) -> Self {
        let d = model.free_dim();
        let face_rows = |ci: usize| match &constraints.cones[ci] {
            ConeRepr::Inscribed(cone) => cone.faces.nrows(),
            ConeRepr::Exact => 1,
        };
        let limits: usize = model
            .torque_limits
            .iter()
            .flatten()
            .map(|l| l.lower().is_some() as usize + l.upper().is_some() as usize)
            .sum();
        let total: usize = (0..constraints.cones.len()).map(face_rows).sum::<usize>() + limits;
        // Rows are written in place: Hp = S N, Hw = S Z1 (S block-diagonal); H = S Z2
        // waits for its first reader.
        let (mut hp, mut hw) = (Matrix::zeros(total, d), Matrix::zeros(total, 6));
        let (mut c0, mut c0_terms) = (Vec::with_capacity(total), Vec::with_capacity(total));
        let mut rows = Vec::with_capacity(total);
        let mut contacts = Vec::with_capacity(model.contacts.len());
        for (ci, repr) in constraints.cones.iter().enumerate() {
            let c = &model.contacts[ci];
            let (off, dim) = (model.offsets[ci], c.dim());
            let r = face_rows(ci);
            let first = rows.len();
            contacts.push(ContactBlock {
                model: *c,
                offset: off,
                first_row: first,
                rows: r,
            });
            // The contact's rows of Z1, which its face rows combine.
            let z1 = &model.z1.as_slice()[off * 6..(off + dim) * 6];
            for k in 0..r {
                let i = first + k;
                let (face, _) = face_row(repr, c, k);
                combine(hw.row_mut(i), &face[..dim], z1);
                if d > 0 {
                    let np = &model.passive_basis.as_slice()[off * d..(off + dim) * d];
                    combine(hp.row_mut(i), &face[..dim], np);
                }
                let (v, size) = contact_c0(&model, ci, k, r, &face[..dim]);
                c0.push(v);
                c0_terms.push(size);
                rows.push(RowId::of_contact(ci, k, r));
            }
        }
        // Torque limits: τ_j ≥ lower and −τ_j ≥ −upper, in the solver's v = u − u_p.
        for (j, lim) in model.torque_limits.iter().enumerate() {
            let Some(lim) = *lim else { continue };
            let up = model.passive.torque_offset.get(j).copied().unwrap_or(0.0);
            if let Some(lo) = lim.lower() {
                c0.push(lo - up);
                c0_terms.push(lo.abs() + up.abs());
                rows.push(RowId::TorqueLimit {
                    joint: j,
                    upper: false,
                });
            }
            if let Some(hi) = lim.upper() {
                c0.push(-hi + up);
                c0_terms.push(hi.abs() + up.abs());
                rows.push(RowId::TorqueLimit {
                    joint: j,
                    upper: true,
                });
            }
        }
        Self {
            h: OnceLock::new(),
            limits: model
                .torque_limits
                .iter()
                .enumerate()
                .filter_map(|(j, l)| l.map(|l| (j, l.bounds().0, l.bounds().1)))
                .collect(),
            hp,
            hw,
            c0,
            c0_terms,
            rows,
            contacts,
            constraints,
            model,
        }
    }

    /// Each limited torque's `(index, lower, upper)`, an open side infinite.
    pub fn limits(&self) -> &[(usize, f64, f64)] {
        &self.limits
    }

    /// H = S Z2, R × m (eqs. 39, 43), formed on the first call.
    pub fn h(&self) -> &Matrix {
        self.h.get_or_init(|| {
            let m = self.model.joints();
            let mut h = Matrix::zeros(self.rows.len(), m);
            for (block, repr) in self.contacts.iter().zip(&self.constraints.cones) {
                let (off, dim) = (block.offset, block.model.dim());
                let z2 = &self.model.z2.as_slice()[off * m..(off + dim) * m];
                for k in 0..block.rows {
                    let (face, dim) = face_row(repr, &block.model, k);
                    combine(h.row_mut(block.first_row + k), &face[..dim], z2);
                }
            }
            for (i, id) in self.rows.iter().enumerate() {
                if let RowId::TorqueLimit { joint, upper } = *id {
                    h[(i, joint)] = if upper { -1.0 } else { 1.0 };
                }
            }
            h
        })
    }

    /// The model of a validated problem, inscribed at the problem's linearisation.
    pub fn from_problem(
        p: &crate::problem::GraspProblem,
        opts: &crate::model::ModelOptions,
    ) -> Result<Self, ModelError> {
        let model = Arc::new(GraspModel::new(p, opts)?);
        Ok(Self::linearized(model, &p.linearization))
    }

    /// Every contact inscribed at `lin`.
    pub fn linearized(model: Arc<GraspModel>, lin: &Linearization) -> Self {
        let c = Constraints::inscribed(&model, lin);
        Self::new(model, c)
    }

    /// Every contact exact (the linear rows are then the minimum normal forces and the
    /// torque limits).
    pub fn exact(model: Arc<GraspModel>) -> Self {
        let c = Constraints::exact(&model);
        Self::new(model, c)
    }

    /// Replaces contact `ci`'s cone: only its block of rows is rebuilt, from the model's
    /// Z (no new decomposition); the rows of other contacts keep their identities.
    pub fn set_cone(&mut self, ci: usize, repr: ConeRepr) {
        let faces = contact_faces(&self.model, ci, &repr);
        let (h, hp, hw) = block_rows(&self.model, ci, &faces);
        let old = self.contacts[ci];
        let (start, end) = (old.first_row, old.first_row + old.rows);
        let new_rows = faces.nrows();
        let splice = |a: &Matrix, b: &Matrix| {
            let mut v: Vec<Vec<f64>> = (0..start).map(|i| a.row(i).to_vec()).collect();
            v.extend((0..b.nrows()).map(|i| b.row(i).to_vec()));
            v.extend((end..a.nrows()).map(|i| a.row(i).to_vec()));
            Matrix::from_rows(&v, a.ncols())
        };
        // (An H not yet formed is formed from the new rows when first read.)
        if let Some(formed) = self.h.get_mut() {
            *formed = splice(formed, &h);
        }
        self.hp = splice(&self.hp, &hp);
        self.hw = splice(&self.hw, &hw);
        let (c0, terms): (Vec<f64>, Vec<f64>) = (0..new_rows)
            .map(|k| contact_c0(&self.model, ci, k, new_rows, faces.row(k)))
            .unzip();
        self.c0.splice(start..end, c0);
        self.c0_terms.splice(start..end, terms);
        let ids = (0..new_rows).map(|k| RowId::of_contact(ci, k, new_rows));
        self.rows.splice(start..end, ids);
        let shift = new_rows as isize - old.rows as isize;
        self.contacts[ci].rows = new_rows;
        for b in &mut self.contacts[ci + 1..] {
            b.first_row = (b.first_row as isize + shift) as usize;
        }
        self.constraints.cones[ci] = repr;
    }

    /// Number of joints m.
    pub fn joints(&self) -> usize {
        self.model.joints()
    }

    /// Number of contact force components n.
    pub fn force_dim(&self) -> usize {
        self.model.force_dim()
    }

    /// Number of linear inequality rows.
    pub fn inequality_rows(&self) -> usize {
        self.rows.len()
    }

    /// Number of consistency equalities p.
    pub fn equality_rows(&self) -> usize {
        self.model.equality_rows()
    }

    /// `c(w)` into `out` (length: inequality rows).
    pub fn c_into(&self, w: &[f64; 6], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.c0[i] - dot(self.hw.row(i), w);
        }
    }

    /// The least-distance form in τ, for the native solver.
    pub fn least_distance(&self) -> LeastDistance<'_> {
        LeastDistance {
            h: InequalityRows::Factored(RowFactors {
                z2: &self.model.z2,
                contacts: &self.contacts,
                cones: &self.constraints.cones,
            }),
            c0: &self.c0,
            c0_terms: &self.c0_terms,
            hw: &self.hw,
            eq: &self.model.eq,
            eq_w: &self.model.eq_w,
            weights: &self.model.weights,
            rows: &self.rows,
            eq_factors: Some(EqFactors {
                basis: &self.model.eq_basis,
                null: &self.model.eq_null,
                scale: &self.model.torque_scale,
            }),
            offset: &self.model.passive.torque_offset,
        }
    }
}

/// The contact-force-space QP of the usual two-step method, the baseline of Table 1:
/// minimise `‖f‖²` subject to `G f = w`, the same inscribed cones and minimum normal
/// forces, and the torque limits applied to `Jᵀ f`. Its variable is f.
#[derive(Clone, Debug)]
pub struct ForceSpaceQp {
    /// The grasp.
    pub model: Arc<GraspModel>,
    /// Rows on f: cones, minimum normal forces, then limits on `Jᵀ f`.
    pub h: Matrix,
    /// Their right-hand sides (no wrench part).
    pub c0: Vec<f64>,
    /// `|c0|`: constants of no cancelled terms.
    c0_terms: Vec<f64>,
    hw: Matrix,
    /// `G f = w` with independent rows: `eq f = −eq_w w`.
    pub eq: Matrix,
    eq_w: Matrix,
    /// `unreachable · w ≠ 0`: no contact force balances w.
    pub unreachable: Matrix,
    weights: Vec<f64>,
    /// Row identities.
    pub rows: Vec<RowId>,
}

impl ForceSpaceQp {
    /// The baseline problem of `model` with every contact inscribed at `lin`.
    pub fn new(model: Arc<GraspModel>, lin: &Linearization) -> Result<Self, ModelError> {
        if !model.passive.is_empty() {
            return Err(ModelError::Unsupported {
                formulation: "the contact-force baseline",
                what: "passive joint torques",
            });
        }
        let n = model.force_dim();
        let mut h_rows = Vec::new();
        let mut c0 = Vec::new();
        let mut rows = Vec::new();
        for (ci, c) in model.contacts.iter().enumerate() {
            let faces = inscribed_cone(c, lin).faces;
            let off = model.offsets[ci];
            for k in 0..faces.nrows() {
                let mut row = vec![0.0; n];
                row[off..off + c.dim()].copy_from_slice(faces.row(k));
                h_rows.push(row);
                let r = faces.nrows();
                c0.push(if k + 1 == r {
                    model.min_normal_force[ci]
                } else {
                    0.0
                });
                rows.push(RowId::of_contact(ci, k, r));
            }
        }
        for (j, lim) in model.torque_limits.iter().enumerate() {
            let Some(lim) = *lim else { continue };
            for (upper, bound) in [(false, lim.lower()), (true, lim.upper())] {
                let Some(b) = bound else { continue };
                let sign = if upper { -1.0 } else { 1.0 };
                h_rows.push(
                    model
                        .jacobian_transpose
                        .row(j)
                        .iter()
                        .map(|v| sign * v)
                        .collect(),
                );
                c0.push(sign * b);
                rows.push(RowId::TorqueLimit { joint: j, upper });
            }
        }
        // [G; E] f = [w; 0] with independent rows: row_basisᵀ f = row_transform · [w; 0].
        let g = model.grasp_matrix.vstack(&model.unactuated);
        let d = decompose(&g, RankThreshold::Relative(model.rank_tolerance)).map_err(|_| {
            ModelError::Decomposition {
                what: "[G; E]",
                rows: g.nrows(),
                cols: n,
            }
        })?;
        let eq = d.row_basis.transpose();
        let eq_w = Matrix::from_fn(d.rank(), 6, |i, j| -d.row_transform[(i, j)]);
        let unreachable = Matrix::from_fn(d.left_null.ncols(), 6, |i, j| d.left_null[(j, i)]);
        let h = Matrix::from_rows(&h_rows, n);
        Ok(Self {
            hw: Matrix::zeros(h.nrows(), 6),
            h,
            c0_terms: c0.iter().map(|v| v.abs()).collect(),
            c0,
            eq,
            eq_w,
            unreachable,
            weights: vec![1.0; n],
            rows,
            model,
        })
    }

    /// The least-distance form in f, for the native solver.
    pub fn least_distance(&self) -> LeastDistance<'_> {
        LeastDistance {
            h: InequalityRows::Formed(&self.h),
            c0: &self.c0,
            c0_terms: &self.c0_terms,
            hw: &self.hw,
            eq: &self.eq,
            eq_w: &self.eq_w,
            weights: &self.weights,
            rows: &self.rows,
            eq_factors: None,
            offset: &[],
        }
    }

    /// `‖unreachable · w‖∞`: the part of w no contact force can balance.
    pub fn unreachable_residual(&self, w: &[f64; 6]) -> f64 {
        (0..self.unreachable.nrows())
            .map(|i| dot(self.unreachable.row(i), w).abs())
            .fold(0.0, f64::max)
    }
}
