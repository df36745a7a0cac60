//! Active-set Newton on the exact cones, started from the linearised optimum.
//!
//! At the optimum each second-order cone of the [`ConicForm`] is inactive (its contact
//! force strictly inside) or on its smooth boundary `g(x) = ‖s1‖ − s0 = 0`, with
//! `s = b − A x`; each nonnegative row is inactive or active (`s_i = 0`). With that
//! guess — read off the inscribed optimum's key constraint set — the optimum solves the
//! equality-constrained problem `min ½ xᵀPx` s.t. `E x = b_E`, the active rows and the
//! active boundaries. Newton's method on its KKT system converges quadratically:
//!
//! ```text
//! (P + Σ ν_k ∇²g_k) dx + Cᵀ ν⁺ = −P x,   C dx = −c(x),
//! ∇g_k = A_kᵀ (1, −u),   ∇²g_k = A_k1ᵀ (I − u uᵀ) A_k1 / ‖s1‖,   u = s1/‖s1‖
//! ```
//!
//! `∇²g_k` is positive semidefinite (g is convex) and P = 2I on the torques, so the
//! Hessian is positive definite: one Cholesky factor and the Schur complement of the
//! few constraint rows. Then the guess is corrected like a primal active-set method: a
//! violated inactive piece joins, a negative multiplier leaves. The conic dual is
//! `z_i = ν_i` on rows and `z_k = ν_k (1, −u)` on a boundary (in K exactly when
//! `ν_k ≥ 0`), so the caller's certificate checks the answer.
//!
//! A cone at its apex (an unloaded contact, or SFCl's edge `f_t = 0`), where g is not
//! differentiable, is the piece `s_k = 0`: linear rows whose multipliers are the conic
//! dual, which must lie in the dual cone. The apex is read off the iterate (the
//! inscribed optimum's key set holds only independent faces, so it cannot say), or
//! reached when a boundary's tail vanishes. A guess that does not converge, or that
//! sends the same cone to its apex twice (it cycles), is left to the caller's other
//! start or the interior-point method.
//!
//! Once Newton's steps shrink quadratically, the last ones are chord steps on the
//! current factors (Shamanskii's variant): the factors would barely change.
//!
//! A warm re-solve with the same pieces keeps the last factorisation and runs chord
//! iterations on it, through the KKT matrix's explicit inverse, built once per
//! factorisation: a control loop pays O((k + nc)²) per iteration.

use crate::dense::{backward, cholesky, dot4, forward, schur};
use grasp_core::conic::{soc_excess, CERTIFICATE_TOLERANCE};
use grasp_core::matrix::{add_column_block, add_columns, column_major, norm_inf};
use grasp_core::{ConeKind, ConicForm, Matrix};

/// Largest tail of a second-order cone (the friction cones' are 2 or 3 long).
const MAX_TAIL: usize = crate::ipm::SOC_MAX - 1;
/// A reduced row at most this times the largest of its cone's is one the equalities
/// make constant (rounding of zero), as `grasp_core::model::PINNED` decides a pinned
/// joint ([`Newton::rebalance_apex`]).
const PINNED_ROW: f64 = 1e3 * f64::EPSILON;
/// Newton iterations per guess, and corrections of the guess.
const MAX_NEWTON: usize = 12;
const MAX_CHANGES: usize = 8;
/// The error a chord re-solve stops at, relative to the iterate (the scaled problem's
/// answer has size about 1): a hundredth of the certificate's tolerance.
const CHORD_ERROR: f64 = 1e-11;
/// A cone whose slack is this small against the iterate (the scaled problem's answer
/// has size about 1) is at its apex.
const APEX: f64 = 1e-9;
/// A multiplier of a certified answer this small against the largest is an inactive
/// piece's (see [`Newton::adopt`]).
const ADOPT: f64 = 1e-6;
/// A boundary piece this close to its apex during Newton's method, relative to the size
/// of its own terms ([`Newton::cone_terms`]), is put at the apex (and, at the end of
/// the guess's iterations, one this close relative to the largest variable that is
/// closing on it: [`CRAWL`]).
const NEAR_APEX: f64 = 1e-6;
/// A boundary piece whose `‖s1‖` shrank to this fraction of the last iterate's or less,
/// [`CLOSING`] iterates in a row, is closing on its apex: Newton's steps there only
/// halve it (its curvature `ν/‖s1‖` grows as fast). When Newton's iterations run out
/// with such a piece within [`NEAR_APEX`] of the largest variable, the apex is the
/// next guess (by its own terms it may not be near yet). Taken as soon as the third
/// shrink is seen, it sent pieces whose optimum rests just off the apex there too
/// (`newton_leaves_the_tangent_planes_it_converged_on`, seed 600583).
const CRAWL: f64 = 0.75;
/// See [`CRAWL`].
const CLOSING: usize = 3;
/// A line along y within this of a cone's boundary direction (`|d0² − ‖d1‖²|` against
/// `‖d‖²`) is left to the general path: where it meets the cone, rounding decides.
const LINE_PARALLEL: f64 = 1e-10;
/// The largest answer the closed form gives (see [`Newton::solve_line`]).
const LINE_LIMIT: f64 = 6.7e7;
/// A row of a cone at its apex whose part independent of the constraints before it is
/// below this, relative to the row (or to the largest row, for a row the iterate
/// barely moves), is left out.
const INDEPENDENT: f64 = 1e-8;

/// Where a second-order cone is at the optimum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Piece {
    /// Its contact force is strictly inside.
    Inside,
    /// On its smooth boundary.
    Boundary,
    /// At its apex: `s_k = 0`.
    Apex,
}

/// The span of a few rows of the reduced constraint matrix (a cone's at its apex, for
/// [`Newton::rebalance_apex`]): the Cholesky factor of their Gram matrix, rows not
/// `free` standing in as unit rows with coefficient 0.
struct RowSpan<'a> {
    rows: &'a [usize],
    free: &'a [bool],
    gram: [f64; crate::ipm::SOC_MAX * crate::ipm::SOC_MAX],
}

impl<'a> RowSpan<'a> {
    fn new(a: &Matrix, rows: &'a [usize], free: &'a [bool]) -> Option<Self> {
        let k = rows.len();
        let mut gram = [0.0; crate::ipm::SOC_MAX * crate::ipm::SOC_MAX];
        for i in 0..k {
            for j in 0..k {
                gram[i * k + j] = match (free[i], free[j]) {
                    (true, true) => dot4(a.row(rows[i]), a.row(rows[j])),
                    _ => f64::from(u8::from(i == j)),
                };
            }
        }
        cholesky(&mut gram[..k * k], k).then_some(Self { rows, free, gram })
    }

    /// Row r's coefficients in the span, into `gamma`; whether r lies in it (the
    /// least-squares residual is rounding of the row).
    fn coefficients(&self, a: &Matrix, r: usize, gamma: &mut [f64]) -> bool {
        self.coefficients_within(a, r, gamma, PINNED_ROW)
    }

    /// [`Self::coefficients`], r in the span where the least-squares residual is at
    /// most `tol` of the row.
    fn coefficients_within(&self, a: &Matrix, r: usize, gamma: &mut [f64], tol: f64) -> bool {
        let (k, ar) = (self.rows.len(), a.row(r));
        for (j, g) in gamma.iter_mut().enumerate() {
            *g = if self.free[j] {
                dot4(a.row(self.rows[j]), ar)
            } else {
                0.0
            };
        }
        forward(&self.gram[..k * k], k, gamma);
        backward(&self.gram[..k * k], k, gamma);
        let off = (0..a.ncols()).fold(0.0f64, |m, c| {
            let v: f64 = (0..k).map(|j| gamma[j] * a[(self.rows[j], c)]).sum();
            m.max((v - ar[c]).abs())
        });
        !(off.is_nan() || off > tol * norm_inf(ar))
    }
}

/// How Newton's method on one guess ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Converged,
    /// A multiplier of the wrong sign: drop it before converging.
    Negative,
    /// An inactive piece violated far beyond the step: add it before converging.
    Violated,
    /// A boundary's tail vanished: the cone is at its apex.
    AtApex(usize),
    Failed,
}

/// One row of the Newton constraint matrix: what its multiplier belongs to.
#[derive(Clone, Copy, Debug)]
enum Owner {
    Row(usize),
    Cone(usize),
    /// A row of a cone at its apex (its multiplier in `nu_row`, like a row's).
    Apex(usize),
}

/// The Newton solver of one conic form, with its workspace.
#[derive(Clone, Debug)]
pub(crate) struct Newton {
    n: usize,
    /// Zero-cone rows `0..eq`, nonnegative rows `orth.0..orth.1`.
    eq: usize,
    orth: (usize, usize),
    /// Second-order cones: `(first row, dim)`.
    socs: Vec<(usize, usize)>,
    /// The other cone of an SFCl contact, which shares this one's tail rows `(fx, fy)`.
    pair: Vec<Option<usize>>,
    /// Per cone, the nonnegative row of its contact's minimum normal force: implied by
    /// the apex (`f = 0`), so it leaves the constraints there.
    normal_row: Vec<Option<usize>>,
    /// Per row of the form: whether a nonnegative row is active.
    pub(crate) active: Vec<bool>,
    /// Per second-order cone.
    pub(crate) piece: Vec<Piece>,
    /// Per cone, whether it left its apex in this solve (its dual outside the dual
    /// cone): it goes back there only exactly at the apex, not near it, so that the
    /// guess cannot cycle.
    left_apex: Vec<bool>,
    /// Per cone on its boundary, in this guess's Newton method: `‖s1‖ + |s0|` and `‖s1‖`
    /// at the last iterate, and how many iterates in a row have shrunk `‖s1‖` to
    /// [`CRAWL`] of the one before or less.
    closing: Vec<(f64, f64, usize)>,
    /// Per cone that left its apex, the direction u of its tail (`MAX_TAIL` each).
    hint: Vec<f64>,
    /// Per cone, whether the current Newton step holds it to that tangent plane (its
    /// step is then no Newton step of the cone: no chord steps follow).
    tangent: Vec<bool>,
    /// The guesses of this solve whose Newton run took a cone to its apex, by
    /// [`Self::guess_key`]: the same guess taking it there again cycles.
    to_apex: Vec<u64>,
    /// Multipliers per row and per cone.
    pub(crate) nu_row: Vec<f64>,
    pub(crate) nu_cone: Vec<f64>,
    /// The consistency equalities eliminated once per grasp: `x = x_p + N y` with
    /// `x_p = E⁺ b_E` (orthogonal to N), so the objective is `‖y‖²` plus a constant.
    null_basis: Matrix,
    /// Nᵀ (k × nx): its rows are N's columns, for `x = x_p + N y` down columns.
    null_basis_t: Matrix,
    /// Rows of A times N (rows × k); the equality rows unused.
    a_red: Matrix,
    /// The largest entry of `a_red`.
    a_scale: f64,
    /// Each row's ℓ1 norm in `a_red`: `|a·dx| ≤ ‖a‖₁ ‖dx‖∞` bounds a slack's change
    /// without the product.
    a_red_l1: Vec<f64>,
    /// Nonnegative rows constant on the equalities' solutions (a zero row of `a_red`:
    /// a limit on a joint the wrench fixes). None is ever active: their slack is the
    /// wrench's alone, checked once per solve ([`Self::still_rows_hold`]).
    still: Vec<bool>,
    /// With at most one free direction, the rounding level of each row's `a_red`:
    /// a slope below it is no slope ([`Self::solve_line`]).
    line_floor: Vec<f64>,
    /// Rows `eq..` of `a_red` column-major, for the pass over every slack.
    a_red_cols: Vec<f64>,
    /// `b − A x_p` and `x_p` are affine in the wrench, like b: their constant and
    /// wrench parts side by side, column-major (rows `eq..` × 7 and nx × 7), so that a
    /// solve costs seven passes down columns, not a pass through E⁺
    /// (`b = (b0 + bw w)/α`).
    b_red_cols: Vec<f64>,
    xp_cols: Vec<f64>,
    /// `b − A x_p` and `x_p`, per solve.
    b_red: Vec<f64>,
    xp: Vec<f64>,
    y: Vec<f64>,
    /// Whether `s` holds the slacks at the current `y` (one pass over every row saved).
    slacks_at_y: bool,
    /// The iterate in the form's variables.
    pub(crate) x: Vec<f64>,
    pub(crate) z: Vec<f64>,
    pub(crate) iterations: usize,
    /// The constraint count of the last converged Newton step, whose factors (`h`,
    /// `ycols`, `schur`) and constraint owners are kept for a chord re-solve.
    frozen: Option<usize>,
    /// The frozen KKT matrix's inverse, (k + nc) × (k + nc) row-major from
    /// `[t; c]` to `[dy; ν]`, built at the first chord re-solve on new factors: a
    /// control loop then pays one dense product per iteration, not two triangular
    /// solves and the Schur complement's.
    kkt_inverse: Vec<f64>,
    kkt_inverse_valid: bool,
    rhs: Vec<f64>,
    s: Vec<f64>,
    h: Vec<f64>,
    c: Vec<f64>,
    cval: Vec<f64>,
    owner: Vec<Owner>,
    ycols: Vec<f64>,
    schur: Vec<f64>,
    t: Vec<f64>,
    nu: Vec<f64>,
    dx: Vec<f64>,
}

impl Newton {
    /// `normal_row`: per second-order cone, the nonnegative row of its contact's
    /// minimum normal force, if any.
    pub(crate) fn new(form: &ConicForm, normal_row: Vec<Option<usize>>) -> Self {
        let (n, rows) = (form.nx, form.rows());
        let (mut eq, mut orth, mut socs) = (0, (0, 0), Vec::new());
        let mut row = 0;
        for cone in &form.cones {
            match *cone {
                ConeKind::Zero(d) => eq = d,
                ConeKind::Nonnegative(d) => orth = (row, row + d),
                ConeKind::SecondOrder(d) => socs.push((row, d)),
            }
            row += cone.dim();
        }
        // The form's decomposition of its (independent, normalised) equality rows; rows
        // it could not eliminate leave an empty basis, which marks Newton unusable
        // (see `solve`).
        let (null_basis_t, e_pinv) = if eq == 0 {
            (Matrix::identity(n), Matrix::zeros(n, 0))
        } else {
            match (&form.eq_null_t, &form.eq_pinv) {
                (Some(nt), Some(pinv)) => (nt.clone(), pinv.clone()),
                _ => (Matrix::zeros(0, 0), Matrix::zeros(n, eq)),
            }
        };
        let null_basis = null_basis_t.transpose();
        let k = null_basis.ncols();
        let inq = rows - eq;
        // A N on the rows past the equalities (eliminated), column-major: a pass down
        // A's columns per column of N (Nᵀ's rows).
        let mut a_red_cols = vec![0.0; inq * k];
        for (col, x) in a_red_cols
            .chunks_exact_mut(inq.max(1))
            .zip(null_basis_t.as_slice().chunks_exact(n.max(1)))
        {
            add_column_block(col, form.a_cols(), rows, eq, x, 1.0);
        }
        let a_red = Matrix::from_fn(rows, k, |i, j| {
            if i < eq {
                0.0
            } else {
                a_red_cols[j * inq + i - eq]
            }
        });
        // [b0 | bw] on the equalities through E⁺ (x_p's map), then b − A x_p on the
        // rest, likewise.
        let be_t = Matrix::from_fn(7, eq, |c, i| {
            if c == 0 {
                form.b0[i]
            } else {
                form.bw[(i, c - 1)]
            }
        });
        let xp_cols = column_major(form.nx, 7, |j, c| dot4(e_pinv.row(j), be_t.row(c)));
        let mut b_red_cols = column_major(inq, 7, |i, c| {
            if c == 0 {
                form.b0[eq + i]
            } else {
                form.bw[(eq + i, c - 1)]
            }
        });
        for (col, x) in b_red_cols
            .chunks_exact_mut(inq.max(1))
            .zip(xp_cols.chunks_exact(n.max(1)))
        {
            add_column_block(col, form.a_cols(), rows, eq, x, -1.0);
        }
        // With one free direction at most, each row's slope along it to rounding:
        // A N's entries carry errors up to about nx ε ‖A_i‖₁ (N's entries are at most 1).
        let line_floor = if k <= 1 {
            (0..rows)
                .map(|i| {
                    n as f64 * f64::EPSILON * form.a.row(i).iter().map(|v| v.abs()).sum::<f64>()
                })
                .collect()
        } else {
            Vec::new()
        };
        let n = k;
        let ncmax = (orth.1 - orth.0) + socs.iter().map(|&(_, d)| d).sum::<usize>();
        // SFCl's two cones are consecutive, and the only ones of their contact.
        let pair = (0..socs.len())
            .map(|k| {
                let c = form.soc_contacts[k];
                [k.wrapping_sub(1), k + 1]
                    .into_iter()
                    .find(|&j| form.soc_contacts.get(j) == Some(&c))
            })
            .collect();
        Self {
            b_red_cols,
            xp_cols,
            null_basis_t,
            null_basis,
            a_red_cols,
            a_scale: a_red.max_abs(),
            a_red_l1: (0..rows)
                .map(|i| a_red.row(i).iter().map(|v| v.abs()).sum())
                .collect(),
            still: (0..rows)
                .map(|i| {
                    (orth.0..orth.1).contains(&i) && k > 0 && a_red.row(i).iter().all(|v| *v == 0.0)
                })
                .collect(),
            a_red,
            line_floor,
            b_red: vec![0.0; rows],
            xp: vec![0.0; form.nx],
            y: vec![0.0; k],
            n,
            eq,
            orth,
            active: vec![false; rows],
            piece: vec![Piece::Inside; socs.len()],
            left_apex: vec![false; socs.len()],
            closing: vec![(f64::NAN, f64::NAN, 0); socs.len()],
            hint: vec![0.0; socs.len() * MAX_TAIL],
            tangent: vec![false; socs.len()],
            to_apex: Vec::with_capacity(MAX_CHANGES),
            nu_row: vec![0.0; rows],
            nu_cone: vec![0.0; socs.len()],
            socs,
            pair,
            normal_row,
            slacks_at_y: false,
            x: vec![0.0; form.nx],
            z: vec![0.0; rows],
            iterations: 0,
            frozen: None,
            kkt_inverse: vec![0.0; (n + ncmax) * (n + ncmax)],
            kkt_inverse_valid: false,
            rhs: vec![0.0; n + ncmax],
            s: vec![0.0; rows],
            h: vec![0.0; n * n],
            c: vec![0.0; ncmax * n],
            cval: vec![0.0; ncmax],
            owner: vec![Owner::Row(0); ncmax],
            ycols: vec![0.0; ncmax * n],
            schur: vec![0.0; ncmax * ncmax],
            t: vec![0.0; n.max(form.nx)],
            nu: vec![0.0; ncmax],
            dx: vec![0.0; n],
        }
    }

    /// `x_p = E⁺ b_E` for the wrench at magnitude α, a point meeting the equalities
    /// (for a dual ray's value); None when they could not be eliminated.
    pub(crate) fn particular(&mut self, w: &[f64; 6], alpha: f64) -> Option<&[f64]> {
        (self.null_basis.nrows() == self.xp.len()).then(|| {
            self.set_particular(w, alpha);
            &self.xp[..]
        })
    }

    /// The inequality rows of `A N` (rows `eq..`): the interior-point method's rows on
    /// `y`, with `x = x_p + N y` ([`Self::lift`]). None where Newton cannot run (the
    /// equalities not eliminated, or free internal forces, whose zero curvature leaves
    /// `Nᵀ P N` no multiple of I).
    pub(crate) fn reduced_rows(&self, form: &ConicForm) -> Option<Matrix> {
        (self.null_basis.nrows() == form.nx && form.free == 0).then(|| {
            Matrix::from_fn(self.a_red.nrows() - self.eq, self.n, |i, j| {
                self.a_red[(self.eq + i, j)]
            })
        })
    }

    /// `x_p` and `b − A x_p` (its rows `eq..`; the rest unused) for the wrench at
    /// magnitude α: the reduced problem's right-hand side.
    pub(crate) fn reduced_rhs(&mut self, w: &[f64; 6], alpha: f64) -> (&[f64], &[f64]) {
        self.set_wrench(w, alpha);
        // A row that does not move with y is no constraint on y: at a slack of 0 (a
        // pinned torque at its limit) it would hold the method's interior at its
        // boundary, its multiplier growing without end. The method sees it slack by
        // the problem's size (1, scaled), and the certificate reads the true one.
        for i in self.orth.0..self.orth.1 {
            if self.still[i] {
                self.b_red[i] = self.b_red[i].max(1.0);
            }
        }
        (&self.xp, &self.b_red)
    }

    /// `x = x_p + N y` into `x`, with `x_p` of the last [`Self::reduced_rhs`].
    pub(crate) fn lift(&self, y: &[f64], x: &mut [f64]) {
        x.copy_from_slice(&self.xp);
        add_columns(x, self.null_basis_t.as_slice(), y, 1.0);
    }

    /// Fills `xp`; returns the weights `[1, w]/α` of the maps' seven columns.
    fn set_particular(&mut self, w: &[f64; 6], alpha: f64) -> [f64; 7] {
        let r = 1.0 / alpha;
        let wt = [
            r,
            r * w[0],
            r * w[1],
            r * w[2],
            r * w[3],
            r * w[4],
            r * w[5],
        ];
        self.xp.iter_mut().for_each(|v| *v = 0.0);
        add_columns(&mut self.xp, &self.xp_cols, &wt, 1.0);
        wt
    }

    /// `x_p = E⁺ b_E` and `b_red = b − (A E⁺) b_E` from the wrench, at magnitude α.
    fn set_wrench(&mut self, w: &[f64; 6], alpha: f64) {
        let wt = self.set_particular(w, alpha);
        let b_red = &mut self.b_red[self.eq..];
        b_red.iter_mut().for_each(|v| *v = 0.0);
        add_columns(b_red, &self.b_red_cols, &wt, 1.0);
    }

    /// Scales the iterate and multipliers by `f` (the scaled problem's answer moves
    /// with 1/α when the right-hand side's magnitude α changes).
    pub(crate) fn rescale(&mut self, f: f64) {
        // (Past the nonnegative rows, `nu_row` holds the apex rows' multipliers.)
        let nu_row = &mut self.nu_row[self.orth.0..];
        for part in [&mut self.x[..], &mut self.y, nu_row, &mut self.nu_cone] {
            part.iter_mut().for_each(|v| *v *= f);
        }
    }

    /// Takes a certified primal-dual pair `(x, z)` of the form at wrench `w` (magnitude
    /// α) as the last answer, so that a warm solve starts Newton from it, with the
    /// guess complementarity gives: a row or cone with a multiplier is active, and a
    /// cone on its boundary has the multiplier of its dual's head (`z = ν (1, −u)`),
    /// unless its slack vanishes: then it is at its apex, its rows' multipliers the
    /// dual. False, and nothing to start from, when the equalities were not eliminated.
    pub(crate) fn adopt(
        &mut self,
        form: &ConicForm,
        x: &[f64],
        z: &[f64],
        w: &[f64; 6],
        alpha: f64,
    ) -> bool {
        if self.null_basis.nrows() != form.nx || form.free > 0 {
            return false;
        }
        self.x.copy_from_slice(&x[..form.nx]);
        self.y.iter_mut().for_each(|v| *v = 0.0);
        add_columns(&mut self.y, self.null_basis.as_slice(), &self.x, 1.0);
        self.set_wrench(w, alpha);
        self.slacks();
        self.reset_multipliers();
        // The interior-point method leaves an inactive piece's multiplier at μ over its
        // slack: far below an active one's.
        let tol = ADOPT * norm_inf(&z[self.eq..]);
        let apex = APEX * norm_inf(&self.y).max(1.0);
        for i in self.orth.0..self.orth.1 {
            self.active[i] = z[i] > tol && !self.still[i];
            self.nu_row[i] = if self.active[i] { z[i] } else { 0.0 };
        }
        for k in 0..self.socs.len() {
            let (start, dim) = self.socs[k];
            if z[start] <= tol {
                self.piece[k] = Piece::Inside;
            } else if self.s[start..start + dim].iter().all(|v| v.abs() <= apex) {
                self.set_apex(k);
            } else {
                self.piece[k] = Piece::Boundary;
                self.nu_cone[k] = z[start];
            }
        }
        // (After every piece is known: an SFCl pair at the apex together keeps its
        // shared tail's multiplier, both tails', in the first cone's rows.)
        for k in 0..self.socs.len() {
            if self.piece[k] != Piece::Apex {
                continue;
            }
            let (start, dim) = self.socs[k];
            self.nu_row[start] = z[start];
            match self.pair[k] {
                Some(j) if self.piece[j] == Piece::Apex => {
                    let first = start.min(self.socs[j].0);
                    for t in 1..dim {
                        self.nu_row[first + t] += z[start + t];
                    }
                }
                _ => {
                    self.nu_row[start + 1..start + dim].copy_from_slice(&z[start + 1..start + dim])
                }
            }
        }
        true
    }

    /// Clears multipliers before a new guess.
    pub(crate) fn reset_multipliers(&mut self) {
        self.frozen = None;
        self.nu_row.iter_mut().for_each(|v| *v = 0.0);
        self.nu_cone.iter_mut().for_each(|v| *v = 0.0);
    }

    /// Whether y = 0 meets every row and cone (within Newton's feasibility tolerance):
    /// its slacks are the reduced right-hand side.
    fn origin_holds(&self) -> bool {
        let s = &self.b_red;
        // (At y = 0: no iterate to scale it by.)
        let feas = feasibility_tolerance_at(&[]);
        (self.orth.0..self.orth.1).all(|i| s[i] >= -feas)
            && self
                .socs
                .iter()
                .all(|&(start, dim)| soc_excess(s[start], &s[start + 1..start + dim]) <= feas)
    }

    /// Solves from `self.x` and the guess in `active`/`piece`; on success `x` and `z`
    /// hold a primal-dual pair for the caller's certificate.
    ///
    /// With `hot`, the first guess is solved by chord iterations on the factors of the
    /// last converged Newton step (a warm re-solve with the same pieces), falling back
    /// to Newton's method.
    pub(crate) fn solve(&mut self, form: &ConicForm, w: &[f64; 6], alpha: f64, hot: bool) -> bool {
        self.iterations = 0;
        if self.null_basis.nrows() != form.nx || form.free > 0 {
            // The equalities could not be eliminated (or free internal forces, which
            // carry no curvature): the interior-point method's case.
            return false;
        }
        self.set_wrench(w, alpha);
        if !self.still_rows_hold(form) {
            return false;
        }
        // y = Nᵀ x, unless hot: then y is the last answer's, rescaled with x.
        self.slacks_at_y = false;
        self.left_apex.iter_mut().for_each(|v| *v = false);
        if self.origin_holds() {
            // The unconstrained minimum y = 0 (τ = x_p) holds the grasp: it is the
            // optimum, taken exactly. Dropping a guess's pieces one change at a time
            // (the polyhedra's, or a warm solve's from a wrench that needed torque)
            // nears it only through the degenerate pieces of contacts it leaves
            // unloaded, if at all within MAX_CHANGES.
            let eq = self.eq;
            self.y.iter_mut().for_each(|v| *v = 0.0);
            self.s[eq..].copy_from_slice(&self.b_red[eq..]);
            self.slacks_at_y = true;
            self.active.iter_mut().for_each(|a| *a = false);
            self.piece.iter_mut().for_each(|p| *p = Piece::Inside);
            self.reset_multipliers();
            self.finish(form);
            return true;
        }
        if !hot {
            // (N's rows are Nᵀ's columns.)
            self.y.iter_mut().for_each(|v| *v = 0.0);
            add_columns(&mut self.y, self.null_basis.as_slice(), &self.x, 1.0);
            // A cone whose slack vanishes is at its apex.
            self.slacks();
            let tol = APEX * norm_inf(&self.y).max(1.0);
            for k in 0..self.socs.len() {
                let (start, dim) = self.socs[k];
                if self.s[start..start + dim].iter().all(|v| v.abs() <= tol) {
                    self.set_apex(k);
                }
            }
        }
        self.to_apex.clear();
        for change in 0..MAX_CHANGES {
            let end = match (hot && change == 0, self.frozen) {
                (true, Some(nc)) => match self.chord(nc, true, f64::INFINITY) {
                    Step::Converged => Step::Converged,
                    _ => self.newton(),
                },
                _ => self.newton(),
            };
            match end {
                Step::Failed => return false,
                Step::AtApex(k) => {
                    // The same guess sending the same cone to its apex again: the guess
                    // alternates between apex and boundary (a force on its boundary
                    // near the apex), and would until its changes run out. The
                    // caller's other start, or the interior-point method, takes over.
                    // (Newton's method leaves the guess as it was.)
                    let key = self.guess_key() ^ (k as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15);
                    if self.to_apex.contains(&key) {
                        return false;
                    }
                    self.to_apex.push(key);
                    self.set_apex(k);
                    self.frozen = None;
                    continue;
                }
                _ => {}
            }
            self.slacks();
            let feas = self.feasibility_tolerance();
            // The most violated inactive piece joins.
            let mut worst: Option<(f64, Owner)> = None;
            for i in self.orth.0..self.orth.1 {
                if !self.active[i] && !self.still[i] && -self.s[i] > feas {
                    let v = -self.s[i];
                    if worst.is_none_or(|(w, _)| v > w) {
                        worst = Some((v, Owner::Row(i)));
                    }
                }
            }
            for (k, &(start, dim)) in self.socs.iter().enumerate() {
                if self.piece[k] == Piece::Inside {
                    let v = soc_excess(self.s[start], &self.s[start + 1..start + dim]);
                    if v > feas && worst.is_none_or(|(w, _)| v > w) {
                        worst = Some((v, Owner::Cone(k)));
                    }
                }
            }
            if let (Step::Converged | Step::Violated, Some((_, o))) = (end, worst) {
                // A piece whose constraint depends on the current ones at this point
                // (more active pieces than free directions, say) replaces the one whose
                // multiplier its own would drive to zero first.
                if let (Step::Converged, Some(nc)) = (end, self.frozen) {
                    match self.replaced_by(o, nc) {
                        Some(Owner::Row(i)) => self.active[i] = false,
                        Some(Owner::Cone(k)) => self.piece[k] = Piece::Inside,
                        _ => {}
                    }
                }
                match o {
                    Owner::Row(i) | Owner::Apex(i) => self.active[i] = true,
                    Owner::Cone(k) => self.piece[k] = Piece::Boundary,
                }
                self.frozen = None;
                continue;
            }
            // The most negative multiplier leaves.
            // (Past the nonnegative rows, `nu_row` holds the apex rows' multipliers.)
            let last = if self.piece.contains(&Piece::Apex) {
                self.nu_row.len()
            } else {
                self.orth.1
            };
            let numax = norm_inf(&self.nu_row[self.orth.0..last])
                .max(norm_inf(&self.nu_cone))
                .max(f64::MIN_POSITIVE);
            let mut most: Option<(f64, Owner)> = None;
            for i in self.orth.0..self.orth.1 {
                if self.active[i] && self.nu_row[i] < -1e-12 * numax {
                    let v = self.nu_row[i];
                    if most.is_none_or(|(m, _)| v < m) {
                        most = Some((v, Owner::Row(i)));
                    }
                }
            }
            for k in 0..self.socs.len() {
                let v = match self.piece[k] {
                    Piece::Boundary => self.nu_cone[k],
                    Piece::Apex => {
                        let v = -self.apex_deficit(k);
                        if v < -1e-12 * numax && self.rebalance_apex(k) {
                            -self.apex_deficit(k)
                        } else {
                            v
                        }
                    }
                    Piece::Inside => continue,
                };
                if v < -1e-12 * numax && most.is_none_or(|(m, _)| v < m) {
                    most = Some((v, Owner::Cone(self.apex_leaving(k))));
                }
            }
            if let Some((_, o)) = most {
                match o {
                    Owner::Row(i) | Owner::Apex(i) => self.active[i] = false,
                    Owner::Cone(k) => match (self.piece[k], self.pair[k]) {
                        // An SFCl cone at its apex whose tail multiplier outweighs its
                        // head, with the other cone near its apex too: with both there
                        // (the contact unloaded) the heads share the tail.
                        (Piece::Apex, Some(j))
                            if self.piece[j] != Piece::Apex
                                && !self.left_apex[j]
                                && self.nu_row[self.socs[k].0] >= 0.0
                                && self.near_apex(j) =>
                        {
                            self.set_apex(j);
                        }
                        (Piece::Apex, _) => self.leave_apex(k),
                        _ => self.piece[k] = Piece::Inside,
                    },
                }
                self.frozen = None;
                continue;
            }
            // Stopped on a multiplier that only its apex's rebalancing put right (an
            // SFCl pair held at its apex by a limit's row): the same guess again, from
            // the multipliers as they now are.
            if end == Step::Negative {
                self.frozen = None;
                continue;
            }
            if end != Step::Converged {
                return false;
            }
            self.finish(form);
            return true;
        }
        false
    }

    /// [`Self::rebalance_apex`] for an SFCl pair at the apex together: its rows are the
    /// first cone's (`a`, head and shared tail) and the second's head, their dual
    /// `ν_a, ν_b ≥ 0`, `‖ν_t‖ ≤ ν_a + ν_b` ([`Self::apex_dual`]). An active row in the
    /// span of those rows passes its multiplier to them as for one cone; the δ nearest
    /// 0 that puts the pair's dual in its cone is taken. (A torque limit that holds an
    /// unloaded SFCl finger at zero: without it, both cones left the apex and came back
    /// until the guesses ran out, and the interior-point method stopped short with σ
    /// 6.0e-8 above Clarabel's, `fuzz_answers.py` seed 4830.)
    fn rebalance_pair(&mut self, a: usize, b: usize) -> bool {
        let ((start, dim), head_b) = (self.socs[a], self.socs[b].0);
        let rows = dim + 1;
        let row = |i: usize| if i < dim { start + i } else { head_b };
        let amat = &self.a_red;
        let largest = (0..rows).fold(0.0f64, |m, i| m.max(norm_inf(amat.row(row(i)))));
        if (0..rows).any(|i| norm_inf(amat.row(row(i))) <= PINNED_ROW * largest) {
            return false;
        }
        let index: [usize; crate::ipm::SOC_MAX] = std::array::from_fn(row);
        let Some(span) = RowSpan::new(amat, &index[..rows], &[true; crate::ipm::SOC_MAX][..rows])
        else {
            return false;
        };
        for r in self.orth.0..self.orth.1 {
            if !self.active[r] || self.nu_row[r] < 0.0 {
                continue;
            }
            let mut gamma = [0.0; crate::ipm::SOC_MAX];
            let gamma = &mut gamma[..rows];
            if !span.coefficients(&self.a_red, r, gamma) {
                continue;
            }
            let (ha, hb, t) = (
                self.nu_row[start],
                self.nu_row[head_b],
                &self.nu_row[start + 1..start + dim],
            );
            let (qa, qb, g) = (gamma[0], gamma[dim], &gamma[1..dim]);
            let (h, q) = (ha + hb, qa + qb);
            let dotp = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(x, y)| x * y).sum::<f64>();
            let tail = |d: f64| {
                t.iter()
                    .zip(g)
                    .map(|(x, y)| (x - d * y).powi(2))
                    .sum::<f64>()
                    .sqrt()
            };
            let size = |d: f64| h.abs() + soc_norm(t) + d.abs() * (q.abs() + soc_norm(g));
            let holds = |d: f64| {
                let tol = 1e-12 * size(d);
                ha - d * qa >= -tol && hb - d * qb >= -tol && tail(d) - (h - d * q) <= tol
            };
            // The dual cone's boundary (‖t − δg‖ = h − δq) and each head's zero.
            let (c2, c1, c0) = (
                dotp(g, g) - q * q,
                -2.0 * (dotp(t, g) - h * q),
                dotp(t, t) - h * h,
            );
            let disc = c1 * c1 - 4.0 * c2 * c0;
            let mut candidates = [f64::NAN; 4];
            if c2.abs() > 1e-12 * (dotp(g, g) + q * q) && disc >= 0.0 {
                let sq = disc.sqrt();
                candidates[0] = (-c1 - sq) / (2.0 * c2);
                candidates[1] = (-c1 + sq) / (2.0 * c2);
            } else if c1 != 0.0 {
                candidates[0] = -c0 / c1;
            }
            candidates[2] = ha / qa;
            candidates[3] = hb / qb;
            let lowest = -self.nu_row[r];
            let Some(d) = candidates
                .into_iter()
                .filter(|&d| d.is_finite() && d >= lowest && holds(d))
                .min_by(|x, y| x.abs().total_cmp(&y.abs()))
            else {
                continue;
            };
            self.nu_row[r] += d;
            for (i, gi) in gamma.iter().enumerate() {
                self.nu_row[row(i)] -= d * gi;
            }
            return true;
        }
        false
    }

    /// The guess as a number: the active rows, each cone's piece and whether it left
    /// its apex (which changes how Newton treats it), hashed (FNV-1a). Two guesses
    /// that collide only end a solve early.
    fn guess_key(&self) -> u64 {
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        let mut mix = |v: u64| h = (h ^ v).wrapping_mul(0x0100_0000_01b3);
        for i in self.orth.0..self.orth.1 {
            mix(self.active[i] as u64);
        }
        for (p, l) in self.piece.iter().zip(&self.left_apex) {
            mix(*p as u64 + 3 * *l as u64);
        }
        h
    }

    /// When the constraint of piece `new` (violated at the converged point) depends on
    /// the `nc` constraints of the last Newton step, the one it replaces, as in the
    /// dual active-set method (Goldfarb and Idnani): with `∇c_new = Σ r_j ∇c_j`,
    /// raising its multiplier by t moves each `ν_j` by `−t r_j`, and the first to reach
    /// zero, `min ν_j / r_j` over `r_j > 0`, leaves. None if independent, or if no
    /// multiplier would reach zero. Reads the frozen factors (L, Y = L⁻¹Cᵀ, and S's).
    fn replaced_by(&mut self, new: Owner, nc: usize) -> Option<Owner> {
        let n = self.n;
        if nc == 0 {
            return None;
        }
        // ∇c_new into `dx` (as `newton` forms its constraint rows), at the current slacks.
        match new {
            Owner::Row(i) | Owner::Apex(i) => self.dx.copy_from_slice(self.a_red.row(i)),
            Owner::Cone(k) => {
                let (start, dim) = self.socs[k];
                let r = soc_norm(&self.s[start + 1..start + dim]);
                if r.is_nan() || r <= 0.0 {
                    return None;
                }
                self.dx.copy_from_slice(self.a_red.row(start));
                for j in 1..dim {
                    let u = self.s[start + j] / r;
                    for (c, a) in self.dx.iter_mut().zip(self.a_red.row(start + j)) {
                        *c -= u * a;
                    }
                }
            }
        }
        // v = L⁻¹ ∇c_new; r = S⁻¹ Yᵀ v, the H⁻¹-weighted least-squares coefficients.
        forward(&self.h, n, &mut self.dx);
        let size = soc_norm(&self.dx);
        for q in 0..nc {
            self.nu[q] = dot4(&self.ycols[q * n..q * n + n], &self.dx);
        }
        forward(&self.schur[..nc * nc], nc, &mut self.nu[..nc]);
        backward(&self.schur[..nc * nc], nc, &mut self.nu[..nc]);
        for q in 0..nc {
            let f = self.nu[q];
            for (d, y) in self.dx.iter_mut().zip(&self.ycols[q * n..q * n + n]) {
                *d -= f * y;
            }
        }
        let left = soc_norm(&self.dx);
        if left.is_nan() || left > INDEPENDENT * size {
            return None;
        }
        let mut best: Option<(f64, Owner)> = None;
        for q in 0..nc {
            let (r, nu) = match self.owner[q] {
                Owner::Row(i) => (self.nu[q], self.nu_row[i]),
                Owner::Cone(k) if !self.tangent[k] => (self.nu[q], self.nu_cone[k]),
                _ => continue,
            };
            if r > 0.0 {
                let t = nu.max(0.0) / r;
                if best.is_none_or(|(b, _)| t < b) {
                    best = Some((t, self.owner[q]));
                }
            }
        }
        best.map(|(_, o)| o)
    }

    /// `x = x_p + N y`, and the conic dual on the inequality rows (the certificate
    /// needs none on the equalities).
    fn finish(&mut self, form: &ConicForm) {
        let x = &mut self.x[..form.nx];
        x.copy_from_slice(&self.xp);
        add_columns(x, self.null_basis_t.as_slice(), &self.y, 1.0);
        self.dual();
    }

    /// The free directions the equalities leave (k).
    #[cfg(test)]
    pub(crate) fn free_directions(&self) -> usize {
        self.n
    }

    /// Whether the equalities leave at most one free direction (`k ≤ 1`), where
    /// [`Self::solve_line`] applies.
    pub(crate) fn is_line(&self) -> bool {
        self.n <= 1 && self.null_basis.nrows() == self.xp.len()
    }

    /// Whether the equalities leave no free direction (`k = 0`): `x_p` is then the only
    /// point they admit, and decides the grasp alone.
    pub(crate) fn is_point(&self) -> bool {
        self.n == 0 && self.null_basis.nrows() == self.xp.len()
    }

    /// The problem when the equalities leave at most one free direction (a hand whose
    /// consistency rows fix all but one combination of its torques), in closed form.
    /// Along y each slack is affine, `s(y) = c + d y`: a row admits a half-line, a cone
    /// the interval where the line crosses it (between or beyond the roots of
    /// `s0² − ‖s1‖²`, a quadratic in y). The least y² is 0 clamped to their
    /// intersection, and the piece that clamps it carries the only multiplier, from
    /// stationarity `2y = dᵀz`. Into `x` and `z` for the caller's certificate; false
    /// where this cannot decide, for the general path: an empty intersection (an
    /// infeasible grasp, which the general path proves), a line along a cone's
    /// boundary direction, the clamping cone at its apex, coefficients out of range,
    /// an answer beyond [`LINE_LIMIT`], a multiplier of the wrong sign. Without a free
    /// direction, the one point the equalities admit, with no multiplier: the
    /// certificate judges it (a miss within its tolerance is rounding; one beyond it,
    /// a ray of the dual).
    pub(crate) fn solve_line(&mut self, form: &ConicForm, w: &[f64; 6], alpha: f64) -> bool {
        if !self.is_line() {
            return false;
        }
        self.set_wrench(w, alpha);
        self.frozen = None;
        self.iterations = 0;
        if self.n == 0 {
            self.z.iter_mut().for_each(|v| *v = 0.0);
            self.x[..form.nx].copy_from_slice(&self.xp);
            return true;
        }
        // (Free internal forces have no curvature: along the line, σ is no multiple
        // of y².)
        if form.free > 0 {
            return false;
        }
        // d = −(A N), the slacks' change along y.
        let a = self.a_red.as_slice();
        let floor = &self.line_floor;
        let slope = |i: usize| match a.get(i) {
            Some(v) if v.abs() > floor[i] => -v,
            _ => 0.0,
        };
        // Cone k's slopes.
        let socs = &self.socs;
        let cone_slope = |k: usize| {
            let (start, dim) = socs[k];
            let mut d = [0.0; MAX_TAIL + 1];
            for (dj, i) in d.iter_mut().zip(start..start + dim) {
                *dj = slope(i);
            }
            d
        };
        let c = &self.b_red;
        // A row that does not move with y holds within its tolerance
        // ([`Self::still_tolerance`]).
        let still = |i: usize| self.still_tolerance(form, i);
        // Each end of the intersection, and the piece that sets it.
        let (mut lo, mut hi) = ((f64::NEG_INFINITY, None), (f64::INFINITY, None));
        for i in self.orth.0..self.orth.1 {
            let d = slope(i);
            if d == 0.0 {
                if c[i] < 0.0 && c[i] < -still(i) {
                    return false;
                }
                continue;
            }
            let v = -c[i] / d;
            if d > 0.0 && v > lo.0 {
                lo = (v, Some(Owner::Row(i)));
            } else if d < 0.0 && v < hi.0 {
                hi = (v, Some(Owner::Row(i)));
            }
        }
        for (k, &(start, dim)) in socs.iter().enumerate() {
            let (c, d) = (&c[start..start + dim], cone_slope(k));
            let d = &d[..dim];
            // s0² − ‖s1‖² = qa y² + 2 qb y + qc.
            let tail = |u: &[f64], v: &[f64]| -> f64 {
                u[1..].iter().zip(&v[1..]).map(|(a, b)| a * b).sum()
            };
            let (dd, cd, cc) = (tail(d, d), tail(c, d), tail(c, c));
            let (qa, qb, qc) = (d[0] * d[0] - dd, c[0] * d[0] - cd, c[0] * c[0] - cc);
            let size = d[0] * d[0] + dd;
            if size == 0.0 {
                // The cone does not move with y (a contact the equalities pin).
                let excess = soc_excess(c[0], &c[1..]);
                if excess > 0.0 && excess > (start..start + dim).map(still).fold(0.0, f64::max) {
                    return false;
                }
                continue;
            }
            // (A line near the boundary's direction meets it where rounding decides; and
            // coefficients out of range, where `disc` is not finite, decide nothing.)
            let disc = qb * qb - qa * qc;
            if qa.abs() <= LINE_PARALLEL * size || !disc.is_finite() || (qa < 0.0 && disc < 0.0) {
                return false;
            }
            // The roots without cancellation.
            let q = -(qb + disc.max(0.0).sqrt().copysign(qb));
            let (r1, r2) = if q == 0.0 {
                (0.0, 0.0)
            } else {
                let (u, v) = (q / qa, qc / q);
                (u.min(v), u.max(v))
            };
            let owner = Some(Owner::Cone(k));
            if qa > 0.0 {
                // d inside K or −K: the line stays in the cone past one root.
                if d[0] > 0.0 && r2 > lo.0 {
                    lo = (r2, owner);
                } else if d[0] < 0.0 && r1 < hi.0 {
                    hi = (r1, owner);
                }
            } else {
                // Between the roots, on K or on −K.
                if c[0] + d[0] * 0.5 * (r1 + r2) < 0.0 {
                    return false;
                }
                if r1 > lo.0 {
                    lo = (r1, owner);
                }
                if r2 < hi.0 {
                    hi = (r2, owner);
                }
            }
        }
        if lo.0 > hi.0 {
            return false;
        }
        let (mut y, by) = if lo.0 > 0.0 {
            lo
        } else if hi.0 < 0.0 {
            hi
        } else {
            (0.0, None)
        };
        // Torques beyond 1/√ε times the load (the scaled right-hand side has size 1):
        // the slacks' rounding, ε |A| |x|, would pass for feasibility.
        if y.abs() > LINE_LIMIT {
            return false;
        }
        self.z.iter_mut().for_each(|v| *v = 0.0);
        let nu = match by {
            Some(Owner::Row(i)) => {
                let nu = 2.0 * y / slope(i);
                self.z[i] = nu;
                nu
            }
            Some(Owner::Cone(k)) => {
                let (start, dim) = socs[k];
                let (c, d) = (&c[start..start + dim], cone_slope(k));
                let d = &d[..dim];
                let mut s = [0.0; MAX_TAIL + 1];
                let at = |y: f64, s: &mut [f64; MAX_TAIL + 1]| {
                    for ((s, c), d) in s.iter_mut().zip(c).zip(d) {
                        *s = c + d * y;
                    }
                    soc_norm(&s[1..dim])
                };
                // Newton on s0 − ‖s1‖ = 0 from the root: the formula is only as
                // accurate as its coefficients' cancellation allows.
                for _ in 0..2 {
                    let r = at(y, &mut s);
                    let slope_g = d[0]
                        - s[1..dim]
                            .iter()
                            .zip(&d[1..])
                            .map(|(s, d)| s * d)
                            .sum::<f64>()
                            / r;
                    let step = (s[0] - r) / slope_g;
                    if !(r > 0.0 && step.is_finite()) {
                        break;
                    }
                    y -= step;
                }
                let r = at(y, &mut s);
                // At the apex (a force that must vanish) the multiplier's direction is
                // not s1's: the general path's apex piece decides.
                if r <= APEX * (norm_inf(c) + norm_inf(d) * y.abs()) {
                    return false;
                }
                // z = ν (1, −u), u = s1/‖s1‖.
                let z = &mut self.z[start..start + dim];
                z[0] = 1.0;
                for (zj, v) in z[1..].iter_mut().zip(&s[1..dim]) {
                    *zj = -v / r;
                }
                let nu = 2.0 * y / d.iter().zip(z.iter()).map(|(d, z)| d * z).sum::<f64>();
                z.iter_mut().for_each(|v| *v *= nu);
                nu
            }
            _ => 0.0,
        };
        if !(nu >= 0.0 && nu.is_finite()) {
            return false;
        }
        self.y.iter_mut().for_each(|v| *v = y);
        let x = &mut self.x[..form.nx];
        x.copy_from_slice(&self.xp);
        add_columns(x, self.null_basis_t.as_slice(), &self.y, 1.0);
        true
    }

    /// Cone k leaves its apex, its dual outside the dual cone: to the boundary, along
    /// the direction the dual's tail gives (`z = ν (1, −u)` there), when the tail
    /// outweighs the head; inside otherwise.
    fn leave_apex(&mut self, k: usize) {
        let mut tail = [0.0; MAX_TAIL];
        let head = self.apex_dual(k, &mut tail);
        let (_, dim) = self.socs[k];
        let t = soc_norm(&tail[..dim - 1]);
        self.left_apex[k] = true;
        if t > head.max(0.0) {
            for (h, z) in self.hint[k * MAX_TAIL..].iter_mut().zip(&tail[..dim - 1]) {
                *h = -z / t;
            }
            self.piece[k] = Piece::Boundary;
            self.nu_cone[k] = t;
        } else {
            self.piece[k] = Piece::Inside;
        }
    }

    /// Whether cone k's slack is within [`NEAR_APEX`] of its apex.
    fn near_apex(&self, k: usize) -> bool {
        let (start, dim) = self.socs[k];
        // (A NaN slack is near nothing.)
        let size = self.s[start..start + dim].iter().fold(0.0f64, |m, v| {
            if v.abs() > m || v.is_nan() {
                v.abs()
            } else {
                m
            }
        });
        self.within_near_apex(k, size, norm_inf(&self.y))
    }

    /// The size of the terms behind cone k's slack at y: the largest over its rows of
    /// `|b_i| + Σ_j |a_ij y_j|`, at least 1 (the scaled problem's size). Nearness to the
    /// apex is judged against it, not against the largest variable: where contacts'
    /// loads span seven decades (a whole hand), a boundary force of 1.6e-4 beside
    /// variables of 690 was taken to its apex and back until the guesses ran out.
    fn cone_terms(&self, k: usize) -> f64 {
        let (start, dim) = self.socs[k];
        let rows =
            self.a_red.as_slice()[start * self.n..(start + dim) * self.n].chunks_exact(self.n);
        let mut size = 1.0f64;
        for (row, b) in rows.zip(&self.b_red[start..start + dim]) {
            let t = b.abs()
                + row
                    .iter()
                    .zip(&self.y)
                    .map(|(a, y)| (a * y).abs())
                    .sum::<f64>();
            if t > size {
                size = t;
            }
        }
        size
    }

    /// Whether `size` (a distance of cone k's slack from its apex) is within
    /// [`NEAR_APEX`] of the cone's terms; first against their bound `|b_i| + ‖a_i‖₁ ‖y‖∞`
    /// (O(dim), `ymax` = ‖y‖∞), which settles almost every call.
    fn within_near_apex(&self, k: usize, size: f64, ymax: f64) -> bool {
        let (start, dim) = self.socs[k];
        let mut bound = 1.0f64;
        for (b, l1) in self.b_red[start..start + dim]
            .iter()
            .zip(&self.a_red_l1[start..start + dim])
        {
            let t = b.abs() + l1 * ymax;
            if t > bound {
                bound = t;
            }
        }
        // (The bound widened past its own rounding: it only rejects.)
        size <= NEAR_APEX * bound * (1.0 + 1e-9) && size <= NEAR_APEX * self.cone_terms(k)
    }

    /// Puts cone k at its apex; its contact's minimum normal force row is then implied.
    fn set_apex(&mut self, k: usize) {
        self.piece[k] = Piece::Apex;
        if let Some(r) = self.normal_row[k] {
            self.active[r] = false;
            self.nu_row[r] = 0.0;
        }
    }

    /// The rows of cone k at its apex that are constraints: all, but only the head of
    /// the second of an SFCl pair at the apex together (the tails are the same rows).
    fn apex_rows(&self, k: usize) -> std::ops::Range<usize> {
        let (start, dim) = self.socs[k];
        match self.pair[k] {
            Some(j) if j < k && self.piece[j] == Piece::Apex => start..start + 1,
            _ => start..start + dim,
        }
    }

    /// The conic dual of cone k at its apex, `(head, tail)` with the tail in `tail`:
    /// its rows' multipliers. An SFCl pair at the apex together shares one tail
    /// multiplier `ν_t`, split in proportion to the heads `ν_a`, `ν_b` (both duals are
    /// then in their cones exactly when `ν_a, ν_b ≥ 0` and `ν_a + ν_b ≥ ‖ν_t‖`).
    fn apex_dual(&self, k: usize, tail: &mut [f64]) -> f64 {
        let (start, dim) = self.socs[k];
        let head = self.nu_row[start];
        let (first, share) = match self.pair[k] {
            Some(j) if self.piece[j] == Piece::Apex => {
                let other = self.nu_row[self.socs[j].0];
                let sum = head + other;
                let theta = if sum > 0.0 { head / sum } else { 0.5 };
                (start.min(self.socs[j].0), theta)
            }
            _ => (start, 1.0),
        };
        for (t, v) in tail[..dim - 1]
            .iter_mut()
            .zip(&self.nu_row[first + 1..first + dim])
        {
            *t = share * v;
        }
        head
    }

    /// How far cone k's apex dual is outside the dual cone (≤ 0 inside).
    fn apex_deficit(&self, k: usize) -> f64 {
        let mut tail = [0.0; MAX_TAIL];
        let head = self.apex_dual(k, &mut tail);
        let (_, dim) = self.socs[k];
        match self.pair[k] {
            Some(j) if self.piece[j] == Piece::Apex => {
                let other = self.nu_row[self.socs[j].0];
                let (first, _) = self.socs[k.min(j)];
                let t = soc_norm(&self.nu_row[first + 1..first + dim]);
                (-head).max(-other).max(t - head - other)
            }
            _ => soc_norm(&tail[..dim - 1]) - head,
        }
    }

    /// Where cone k's apex dual is outside the dual cone, the multipliers the pieces
    /// leave undetermined, chosen to put it there, if they can; whether they did.
    /// - A row of the cone that the equalities make constant (zero on their null
    ///   space) has a multiplier stationarity does not read: a tail row's is taken 0,
    ///   a head's as large as the tail.
    /// - An active row whose gradient lies in the span of the cone's other rows (a
    ///   torque limit on a joint only that contact moves, say) can pass its multiplier
    ///   to the cone's: `a_r = Σ γ_j a_j` leaves `ν_r a_r + Σ λ_j a_j` unchanged by
    ///   `ν_r + δ`, `λ − δγ`; the δ nearest 0 (with `ν_r + δ ≥ 0`) that puts the apex
    ///   dual on the dual cone is taken.
    ///
    /// Where such a row holds the contact at its apex (a limit at the torque of the
    /// unloaded contact, which every other force in the cone would pass), there are no
    /// multipliers in the dual cone without it: the cone left its apex and came back
    /// until its guesses ran out, and the interior-point method, with no strictly
    /// feasible point, grew the limit's multiplier to 1e12 (fuzz_answers.py seed 230).
    fn rebalance_apex(&mut self, k: usize) -> bool {
        if let Some(j) = self.pair[k].filter(|&j| self.piece[j] == Piece::Apex) {
            return self.rebalance_pair(k.min(j), k.max(j));
        }
        let (start, dim) = self.socs[k];
        // The cone's rows that the equalities leave free.
        let largest = (0..dim).fold(0.0f64, |m, j| m.max(norm_inf(self.a_red.row(start + j))));
        let fixed = |j: usize, a: &Matrix| norm_inf(a.row(start + j)) <= PINNED_ROW * largest;
        if fixed(0, &self.a_red) {
            let tail = soc_norm(&self.nu_row[start + 1..start + dim]);
            self.nu_row[start] = self.nu_row[start].max(tail);
            return true;
        }
        // (Kept, to be put back unless the dual ends in the dual cone: leaving the apex
        // reads its direction.)
        let mut was = [0.0; crate::ipm::SOC_MAX];
        was[..dim].copy_from_slice(&self.nu_row[start..start + dim]);
        for j in 1..dim {
            if fixed(j, &self.a_red) {
                self.nu_row[start + j] = 0.0;
            }
        }
        if self.apex_deficit(k) <= 0.0 {
            return true;
        }
        let free: [bool; crate::ipm::SOC_MAX] =
            std::array::from_fn(|j| j < dim && !fixed(j, &self.a_red));
        if self.rebalance_own_rows(k, &free[..dim]) {
            return true;
        }
        // The Gram matrix of the free rows, and each active row's coefficients in them.
        let rows: [usize; crate::ipm::SOC_MAX] = std::array::from_fn(|j| start + j);
        let span = RowSpan::new(&self.a_red, &rows[..dim], &free[..dim]);
        let Some(span) = span else {
            self.nu_row[start..start + dim].copy_from_slice(&was[..dim]);
            return false;
        };
        for r in self.orth.0..self.orth.1 {
            if !self.active[r] || self.nu_row[r] < 0.0 {
                continue;
            }
            let mut gamma = [0.0; crate::ipm::SOC_MAX];
            let gamma = &mut gamma[..dim];
            if !span.coefficients(&self.a_red, r, gamma) {
                continue;
            }
            // ‖t − δg‖ = h − δq on the boundary: A δ² + B δ + C = 0.
            let (h, t) = (self.nu_row[start], &self.nu_row[start + 1..start + dim]);
            let (q, g) = (gamma[0], &gamma[1..]);
            let dotp = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(x, y)| x * y).sum::<f64>();
            let (qa, qb, qc) = (
                dotp(g, g) - q * q,
                -2.0 * (dotp(t, g) - h * q),
                dotp(t, t) - h * h,
            );
            let deficit = |d: f64| {
                let tail = t
                    .iter()
                    .zip(g)
                    .map(|(x, y)| (x - d * y).powi(2))
                    .sum::<f64>();
                tail.sqrt() - (h - d * q)
            };
            let size = |d: f64| (h.abs() + soc_norm(t)) + d.abs() * (q.abs() + soc_norm(g));
            let disc = qb * qb - 4.0 * qa * qc;
            let roots = if qa.abs() > 1e-12 * (dotp(g, g) + q * q) && disc >= 0.0 {
                let sq = disc.sqrt();
                [(-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa)]
            } else if qb != 0.0 {
                [-qc / qb; 2]
            } else {
                continue;
            };
            let lowest = -self.nu_row[r];
            let best = roots
                .into_iter()
                .filter(|&d| d.is_finite() && d >= lowest && h - d * q >= 0.0)
                .filter(|&d| deficit(d) <= 1e-12 * size(d))
                .min_by(|x, y| x.abs().total_cmp(&y.abs()));
            let Some(d) = best else { continue };
            self.nu_row[r] += d;
            for (j, gj) in gamma.iter().enumerate() {
                self.nu_row[start + j] -= d * gj;
            }
            return true;
        }
        self.nu_row[start..start + dim].copy_from_slice(&was[..dim]);
        false
    }

    /// [`Self::rebalance_apex`] where cone k's own free rows are dependent: the
    /// equalities confine its contact's force to a plane or a line (with no wrench,
    /// three point contacts' forces lie in the plane through them), and its rows'
    /// multipliers are known only up to the combinations `u` with `Σ u_j a_j = 0`.
    /// Where one points into the dual cone's interior, that plane meets the cone only
    /// at its apex, and `ν + δ u` with the least δ puts the apex dual on the dual cone.
    /// Without it the dual optimum is out of reach of multipliers left at 0 on the
    /// dependent rows: the cone left its apex and came back until the guesses ran out,
    /// and the interior-point method, with no strictly feasible point, grew the cone's
    /// multiplier until it stalled (`fuzz_answers.py` seed 340274: the weighed Allegro
    /// pinch with no wrench, the thumb at mu = 0.0083). Whether it did.
    fn rebalance_own_rows(&mut self, k: usize, free: &[bool]) -> bool {
        const SOC_MAX: usize = crate::ipm::SOC_MAX;
        let (start, dim) = self.socs[k];
        let rows: [usize; SOC_MAX] = std::array::from_fn(|j| start + j);
        // Null vectors: each free row in the span of the independent rows before it, as
        // Newton's constraints judge dependence ([`Self::apex_constraints`]: a plane
        // through three contacts, formed through the pseudo-inverse and the equalities'
        // null basis, can leave the third row 2500 ε off it). The certificate judges
        // the multipliers this gives.
        let mut basis = [false; SOC_MAX];
        let mut null = [[0.0; SOC_MAX]; SOC_MAX];
        let mut count = 0;
        for j in 0..dim {
            if !free[j] {
                continue;
            }
            let mut gamma = [0.0; SOC_MAX];
            let in_span = basis[..j].contains(&true)
                && RowSpan::new(&self.a_red, &rows[..j], &basis[..j]).is_some_and(|span| {
                    span.coefficients_within(&self.a_red, start + j, &mut gamma[..j], INDEPENDENT)
                });
            if in_span {
                null[count][j] = 1.0;
                for i in 0..j {
                    null[count][i] = -gamma[i];
                }
                count += 1;
            } else {
                basis[j] = true;
            }
        }
        if count == 0 {
            return false;
        }
        // The combination nearest the dual cone's axis: e0 projected on their span,
        // u = U (UᵀU)⁻¹ Uᵀ e0.
        let mut gram = [0.0; SOC_MAX * SOC_MAX];
        let mut c = [0.0; SOC_MAX];
        for i in 0..count {
            c[i] = null[i][0];
            for j in 0..count {
                gram[i * count + j] = null[i][..dim]
                    .iter()
                    .zip(&null[j][..dim])
                    .map(|(a, b)| a * b)
                    .sum();
            }
        }
        if !cholesky(&mut gram[..count * count], count) {
            return false;
        }
        forward(&gram[..count * count], count, &mut c[..count]);
        backward(&gram[..count * count], count, &mut c[..count]);
        let mut u = [0.0; SOC_MAX];
        for i in 0..count {
            for j in 0..dim {
                u[j] += c[i] * null[i][j];
            }
        }
        let (q, g) = (u[0], &u[1..dim]);
        // (NaN fails too.)
        if q.is_nan() || q <= soc_norm(g) {
            return false;
        }
        // ‖t + δg‖ = h + δq: A δ² + B δ + C = 0, A < 0. The root with h + δq ≥ 0 is
        // where the line enters the dual cone (the other is on its negative); past it,
        // the line stays inside.
        let (h, t) = (self.nu_row[start], &self.nu_row[start + 1..start + dim]);
        let dotp = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let (qa, qb, qc) = (
            dotp(g, g) - q * q,
            2.0 * (dotp(t, g) - h * q),
            dotp(t, t) - h * h,
        );
        let disc = qb * qb - 4.0 * qa * qc;
        if disc.is_nan() || disc < 0.0 {
            return false;
        }
        let sq = disc.sqrt();
        let Some(d) = [(-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa)]
            .into_iter()
            .filter(|&d| d.is_finite() && h + d * q >= 0.0)
            .reduce(f64::max)
        else {
            return false;
        };
        for j in 0..dim {
            self.nu_row[start + j] += d * u[j];
        }
        true
    }

    /// The cone that leaves the apex when cone k's apex dual is outside the dual cone:
    /// k, or of an SFCl pair at the apex together, the one with the smaller head.
    fn apex_leaving(&self, k: usize) -> usize {
        match (self.piece[k], self.pair[k]) {
            (Piece::Apex, Some(j)) if self.piece[j] == Piece::Apex => {
                if self.nu_row[self.socs[j].0] < self.nu_row[self.socs[k].0] {
                    j
                } else {
                    k
                }
            }
            _ => k,
        }
    }

    /// Appends the rows of the cones at their apex to the first `nc` constraints, each
    /// only if independent of those before it (at the apex every row of the cone is
    /// active, and some may be fixed by the wrench alone or by other rows: their
    /// multipliers are then not determined, and are left at 0). Returns the new count.
    fn apex_constraints(&mut self, mut nc: usize) -> usize {
        let n = self.n;
        // An orthonormal basis of the rows so far, in `ycols` (until `schur` fills it).
        let mut basis = 0;
        for r in 0..nc {
            self.dx.copy_from_slice(&self.c[r * n..r * n + n]);
            if self.orthogonalise(basis) {
                basis += 1;
            }
        }
        for k in 0..self.socs.len() {
            if self.piece[k] != Piece::Apex {
                continue;
            }
            for i in self.apex_rows(k) {
                self.dx.copy_from_slice(self.a_red.row(i));
                if !self.orthogonalise(basis) {
                    self.nu_row[i] = 0.0;
                    continue;
                }
                basis += 1;
                self.c[nc * n..nc * n + n].copy_from_slice(self.a_red.row(i));
                self.cval[nc] = -self.s[i];
                self.owner[nc] = Owner::Apex(i);
                nc += 1;
            }
        }
        nc
    }

    /// Orthogonalises `dx` against the first `basis` rows of `ycols` (twice, Gram–Schmidt
    /// being unstable once); if what is left is not negligible, normalised, it becomes
    /// row `basis`. Whether it did.
    fn orthogonalise(&mut self, basis: usize) -> bool {
        let n = self.n;
        let size = norm_inf(&self.dx);
        for _ in 0..2 {
            for q in self.ycols[..basis * n].chunks_exact(n) {
                let d = dot4(q, &self.dx);
                for (v, qj) in self.dx.iter_mut().zip(q) {
                    *v -= d * qj;
                }
            }
        }
        let left = soc_norm(&self.dx);
        // (A row the iterate barely moves is fixed by the wrench: not independent.)
        if left.is_nan() || left <= INDEPENDENT * size.max(self.a_scale) {
            return false;
        }
        for (q, v) in self.ycols[basis * n..(basis + 1) * n]
            .iter_mut()
            .zip(&self.dx)
        {
            *q = v / left;
        }
        true
    }

    /// A second-order correction of a rejected full step (Nocedal and Wright §15.6): the
    /// curvature of the boundaries can make the merit refuse Newton's own step near the
    /// optimum (the Maratos effect). The correction `d2 = −H⁻¹Cᵀ(CH⁻¹Cᵀ)⁻¹ c(y + dx)`
    /// takes the step back onto the linearised constraints at its end, on the same
    /// factors; `dx + d2` is taken whole when the merit accepts it. The trial point is in
    /// `t`; on success `dx` holds the corrected step, and `nu` Newton's multipliers.
    fn second_order_correction(&mut self, nc: usize, merit0: f64, rho: f64, slope: f64) -> bool {
        let n = self.n;
        if nc == 0 {
            return false;
        }
        for r in 0..nc {
            self.cval[r] = self.constraint(r);
        }
        // Newton's step and multipliers aside, in `rhs` (free outside chord re-solves).
        self.rhs[..n].copy_from_slice(&self.dx);
        self.rhs[n..n + nc].copy_from_slice(&self.nu[..nc]);
        self.t[..n].iter_mut().for_each(|v| *v = 0.0);
        self.solve_kkt(nc);
        for ((t, y), (d, d2)) in self.t[..n]
            .iter_mut()
            .zip(&self.y)
            .zip(self.rhs[..n].iter().zip(self.dx.iter_mut()))
        {
            *d2 += d;
            *t = y + *d2;
        }
        let viol = self.violation(nc);
        let f: f64 = self.t[..n].iter().map(|v| v * v).sum();
        let accepted = f + rho * viol <= merit0 + 1e-4 * slope.min(0.0);
        self.nu[..nc].copy_from_slice(&self.rhs[n..n + nc]);
        if !accepted {
            self.dx.copy_from_slice(&self.rhs[..n]);
        }
        accepted
    }

    /// `Σ |c_j|` of the first `nc` Newton constraints at the trial point in `t`.
    fn violation(&self, nc: usize) -> f64 {
        (0..nc).map(|r| self.constraint(r).abs()).sum()
    }

    /// Newton constraint r at the trial point in `t`: a row's `−s_i`, a boundary's
    /// `‖s1‖ − s0` (on its tangent plane, `uᵀs1 − s0`).
    fn constraint(&self, r: usize) -> f64 {
        let y = &self.t[..self.n];
        let slack = |i: usize| self.b_red[i] - dot4(self.a_red.row(i), y);
        match self.owner[r] {
            Owner::Row(i) | Owner::Apex(i) => -slack(i),
            Owner::Cone(k) => {
                let (start, dim) = self.socs[k];
                let g = if self.tangent[k] {
                    let u = &self.hint[k * MAX_TAIL..];
                    (1..dim).map(|j| u[j - 1] * slack(start + j)).sum::<f64>()
                } else {
                    (1..dim)
                        .map(|j| slack(start + j).powi(2))
                        .sum::<f64>()
                        .sqrt()
                };
                g - slack(start)
            }
        }
    }

    /// Scaled data: b has size 1, so absolute tolerances are relative ones.
    fn feasibility_tolerance(&self) -> f64 {
        feasibility_tolerance_at(&self.y)
    }

    /// How far past 0 the slack of row i may be when it does not move with y (a
    /// torque the equalities pin, its limit at the torque they pin it to): the
    /// certificate's tolerance of its terms as the certificate measures a torque
    /// limit's, `|b_i| + ‖a_i‖₁ ‖x_p‖∞`. The pinned torque comes out of the
    /// equalities with an error relative to the largest (a joint with moment arms 1e6
    /// times the others' was 1e-10 past a limit of 0 that it meets exactly).
    fn still_tolerance(&self, form: &ConicForm, i: usize) -> f64 {
        let (xp, nx) = (&self.xp[..form.nx], form.nx);
        let a = &form.a.row(i)[..nx];
        let b = self.b_red[i] + a.iter().zip(xp).map(|(a, x)| a * x).sum::<f64>();
        let a1: f64 = a.iter().map(|v| v.abs()).sum();
        CERTIFICATE_TOLERANCE * (b.abs() + a1 * norm_inf(xp))
    }

    /// Whether every row that does not move with y holds at the current wrench
    /// ([`Self::still_tolerance`]): where one does not, no y helps, and the methods
    /// that prove infeasibility decide.
    fn still_rows_hold(&self, form: &ConicForm) -> bool {
        (self.orth.0..self.orth.1)
            .filter(|&i| self.still[i])
            .all(|i| self.b_red[i] >= 0.0 || self.b_red[i] >= -self.still_tolerance(form, i))
    }

    /// A step along `dx` short enough that no boundary cone's slack crosses its apex
    /// (into −K): halved until `s0 + ‖s1‖`, the slack's distance from −K along the
    /// axis, keeps a tenth of its value at y. A force on its boundary near the apex,
    /// approached from a start farther out, is otherwise overshot, declared at the
    /// apex, found not to be, and the guess cycles. A cone whose optimum is its apex
    /// still reaches it (the distance shrinks tenfold a step at most). 1 when no
    /// full step crosses.
    fn apex_limit(&self) -> f64 {
        let n = self.n;
        let dx = norm_inf(&self.dx);
        let mut limit = 1.0f64;
        for (k, &(start, dim)) in self.socs.iter().enumerate() {
            if self.piece[k] != Piece::Boundary || self.tangent[k] {
                continue;
            }
            let now = &self.s[start..start + dim];
            let dist = now[0] + soc_norm(&now[1..]);
            // (A head that keeps a tenth of the distance whatever the step clears it:
            // the tail's norm only adds.)
            if dist.is_nan() || dist <= 0.0 || now[0] - self.a_red_l1[start] * dx >= 0.1 * dist {
                continue;
            }
            let ds_row = |j: usize| {
                -dot4(
                    &self.a_red.as_slice()[(start + j) * n..(start + j + 1) * n],
                    &self.dx,
                )
            };
            // The head alone keeping a tenth clears it (the tail's norm only adds).
            let ds0 = ds_row(0);
            if now[0] + limit * ds0 >= 0.1 * dist {
                continue;
            }
            let mut ds = [0.0; MAX_TAIL + 1];
            ds[0] = ds0;
            for (j, d) in ds[..dim].iter_mut().enumerate().skip(1) {
                *d = ds_row(j);
            }
            let at = |a: f64| {
                let mut e = [0.0; MAX_TAIL + 1];
                for ((e, s), d) in e[..dim].iter_mut().zip(now).zip(&ds) {
                    *e = s + a * d;
                }
                e[0] + soc_norm(&e[1..dim])
            };
            let mut a = limit;
            while a > 1e-3 && at(a) < 0.1 * dist {
                a *= 0.5;
            }
            limit = a;
        }
        limit
    }

    /// The largest violation of an inactive piece at the current slacks.
    fn worst_inactive(&self) -> f64 {
        let mut worst = 0.0f64;
        for i in self.orth.0..self.orth.1 {
            if !self.active[i] && !self.still[i] {
                worst = worst.max(-self.s[i]);
            }
        }
        for (k, &(start, dim)) in self.socs.iter().enumerate() {
            if self.piece[k] == Piece::Inside {
                worst = worst.max(soc_excess(self.s[start], &self.s[start + 1..start + dim]));
            }
        }
        worst
    }

    /// `s = b − A x` on the inequality rows, in the reduced variables.
    fn slacks(&mut self) {
        self.slacks_at_y = true;
        let eq = self.eq;
        self.s[eq..].copy_from_slice(&self.b_red[eq..]);
        add_columns(&mut self.s[eq..], &self.a_red_cols, &self.y, -1.0);
    }

    /// The conic dual of the current multipliers.
    fn dual(&mut self) {
        self.z.iter_mut().for_each(|v| *v = 0.0);
        for i in self.orth.0..self.orth.1 {
            if self.active[i] {
                self.z[i] = self.nu_row[i];
            }
        }
        for (k, &(start, dim)) in self.socs.iter().enumerate() {
            match self.piece[k] {
                Piece::Boundary => {
                    let r = soc_norm(&self.s[start + 1..start + dim]);
                    let nu = self.nu_cone[k];
                    self.z[start] = nu;
                    for j in 1..dim {
                        self.z[start + j] = -nu * self.s[start + j] / r;
                    }
                }
                Piece::Apex => {
                    let mut tail = [0.0; MAX_TAIL];
                    self.z[start] = self.apex_dual(k, &mut tail);
                    self.z[start + 1..start + dim].copy_from_slice(&tail[..dim - 1]);
                }
                Piece::Inside => {}
            }
        }
    }

    /// The KKT system `[H Cᵀ; C 0] [dy; ν] = [t; −c]` with the factors in `h`
    /// (L), `ycols` (Y = L⁻¹Cᵀ) and `schur` (of YᵀY): `ν = S⁻¹(Yᵀ L⁻¹ t + c)`,
    /// `dy = L⁻ᵀ(L⁻¹ t − Y ν)`, into `nu` and `dx` (`t` is overwritten).
    fn solve_kkt(&mut self, nc: usize) {
        let n = self.n;
        forward(&self.h, n, &mut self.t[..n]);
        for r in 0..nc {
            self.nu[r] = dot4(&self.ycols[r * n..r * n + n], &self.t[..n]) + self.cval[r];
        }
        if nc > 0 {
            forward(&self.schur[..nc * nc], nc, &mut self.nu[..nc]);
            backward(&self.schur[..nc * nc], nc, &mut self.nu[..nc]);
        }
        self.dx.copy_from_slice(&self.t[..n]);
        for r in 0..nc {
            let v = self.nu[r];
            for (d, y) in self.dx.iter_mut().zip(&self.ycols[r * n..r * n + n]) {
                *d -= v * y;
            }
        }
        backward(&self.h, n, &mut self.dx);
    }

    /// `[dx; nu] = K⁻¹ [t; cval]` with the frozen factors' explicit inverse, built
    /// here from k + nc solves when the factors are new (`t` and `cval` are used up).
    fn apply_kkt_inverse(&mut self, nc: usize) {
        let (n, m) = (self.n, self.n + nc);
        self.rhs[..n].copy_from_slice(&self.t[..n]);
        self.rhs[n..m].copy_from_slice(&self.cval[..nc]);
        if !self.kkt_inverse_valid {
            for col in 0..m {
                self.t[..n].iter_mut().for_each(|v| *v = 0.0);
                self.cval[..nc].iter_mut().for_each(|v| *v = 0.0);
                if col < n {
                    self.t[col] = 1.0;
                } else {
                    self.cval[col - n] = 1.0;
                }
                self.solve_kkt(nc);
                for i in 0..n {
                    self.kkt_inverse[i * m + col] = self.dx[i];
                }
                for r in 0..nc {
                    self.kkt_inverse[(n + r) * m + col] = self.nu[r];
                }
            }
            self.kkt_inverse_valid = true;
        }
        let rhs = &self.rhs[..m];
        for (i, d) in self.dx.iter_mut().enumerate() {
            *d = dot4(&self.kkt_inverse[i * m..i * m + m], rhs);
        }
        for r in 0..nc {
            self.nu[r] = dot4(&self.kkt_inverse[(n + r) * m..(n + r) * m + m], rhs);
        }
    }

    /// Chord iterations: the KKT residual at the current point, solved with the frozen
    /// factors of the last Newton step (`nc` constraints, same owners). Its fixed point
    /// is the KKT point of the current guess; it converges linearly, at the rate of the
    /// change in H and C since the factorisation (small after a small wrench change,
    /// or once Newton's steps shrink quadratically), each iteration O(k² + nc·k).
    ///
    /// `explicit`: through the KKT matrix's inverse (for a control loop, which re-solves
    /// on the same factors many times); otherwise through the factors. `previous`: the
    /// step before the first (the Newton step that produced the factors; infinite if
    /// none), against which the first step's contraction is measured.
    fn chord(&mut self, nc: usize, explicit: bool, mut previous: f64) -> Step {
        let (mut rate, mut ratios) = (f64::NAN, 0);
        for _ in 0..MAX_NEWTON {
            self.iterations += 1;
            if !self.residual(nc) {
                return Step::Failed;
            }
            if explicit {
                self.apply_kkt_inverse(nc);
            } else {
                self.solve_kkt(nc);
            }
            for r in 0..nc {
                match self.owner[r] {
                    Owner::Row(i) | Owner::Apex(i) => self.nu_row[i] += self.nu[r],
                    Owner::Cone(k) => self.nu_cone[k] += self.nu[r],
                }
            }
            for (y, d) in self.y.iter_mut().zip(&self.dx) {
                *y += d;
            }
            self.slacks_at_y = false;
            if !self.y.iter().all(|v| v.is_finite()) {
                return Step::Failed;
            }
            // Linear convergence at rate ρ leaves an error of about ρ/(1−ρ) × the step:
            // stop when that is below CHORD_ERROR (or the step itself is). Steps are
            // relative to their variables (floored at 1, the scaled problem's size).
            // Within Newton's method they count the multipliers' too: those start from
            // the polyhedra's and can still be moving when the primal has settled, and
            // the certificate's stationarity reads them. (A hot start begins at a
            // converged pair.)
            let mut step = norm_inf(&self.dx) / norm_inf(&self.y).max(1.0);
            if !explicit {
                step = step.max(self.multiplier_step(nc, &self.nu));
            }
            // (No rate before a second step, unless Newton's step came before it.) The
            // slowest contraction seen counts: the error's components contract at
            // different rates, and once the fast ones are gone the last ratio
            // understates what is left (within Newton's method, ratios of 7.9e-3, then
            // 4.5e-4, then 2.5e-2: stopped on the second, a force 8e-11 outside its cone
            // and σ 2.1e-10 low). On a control loop's factors, from another wrench, the
            // first ratio needs a second: the first step takes up the wrench's change,
            // which those factors map almost exactly, and the boundaries' curvature
            // leaves an error that contracts at the factors' own, slower rate (1.4e-5,
            // then 4.8e-3: stopped on the first, σ 9.4e-10 high). Within Newton's
            // method the first ratio is the theory's (`c / s_j`, on fresh factors).
            if previous.is_finite() {
                ratios += 1;
                rate = rate.max(step / previous);
            }
            let previous_step = previous;
            previous = step;
            let settled = (!explicit || ratios >= 2)
                && rate.is_finite()
                && rate < 0.5
                && step * rate / (1.0 - rate) <= CHORD_ERROR;
            if step <= CHORD_ERROR || settled {
                return Step::Converged;
            }
            // Within Newton's method, a measured contraction this slow means fresh
            // factors are cheaper than more chord steps.
            if !explicit && step > 0.25 * previous_step {
                return Step::Failed;
            }
        }
        Step::Failed
    }

    /// The KKT residual of the first `nc` constraints at `y`: `t = −(P y + Σ ν_r
    /// ∇c_r(y))` and `cval = c(y)`, with those constraints' slacks (the caller computes
    /// the rest once it has converged); false at a cone's apex.
    fn residual(&mut self, nc: usize) -> bool {
        let n = self.n;
        let a = self.a_red.as_slice();
        let (y, t, s) = (&self.y[..n], &mut self.t[..n], &mut self.s);
        for (t, y) in t.iter_mut().zip(y) {
            *t = -2.0 * y;
        }
        for r in 0..nc {
            match self.owner[r] {
                Owner::Row(i) | Owner::Apex(i) => {
                    let ai = &a[i * n..i * n + n];
                    let si = self.b_red[i] - dot4(ai, y);
                    s[i] = si;
                    self.cval[r] = -si;
                    let nu = self.nu_row[i];
                    for (t, a) in t.iter_mut().zip(ai) {
                        *t -= nu * a;
                    }
                }
                Owner::Cone(k) => {
                    let (start, dim) = self.socs[k];
                    let block = &a[start * n..(start + dim) * n];
                    let sk = &mut s[start..start + dim];
                    for ((sj, aj), bj) in sk
                        .iter_mut()
                        .zip(block.chunks_exact(n))
                        .zip(&self.b_red[start..])
                    {
                        *sj = bj - dot4(aj, y);
                    }
                    let rr = soc_norm(&sk[1..]);
                    if rr.is_nan() || rr <= 1e-12 * (sk[0].abs() + rr) {
                        return false;
                    }
                    self.cval[r] = rr - sk[0];
                    let nu = self.nu_cone[k];
                    for (t, a) in t.iter_mut().zip(&block[..n]) {
                        *t -= nu * a;
                    }
                    for (sj, aj) in sk[1..].iter().zip(block[n..].chunks_exact(n)) {
                        let c = nu * sj / rr;
                        for (t, a) in t.iter_mut().zip(aj) {
                            *t += c * a;
                        }
                    }
                }
            }
        }
        true
    }

    /// The largest change `d` of the first `nc` constraints' multipliers, relative to
    /// the largest multiplier (at least 1, like the scaled problem's variables).
    fn multiplier_step(&self, nc: usize, d: &[f64]) -> f64 {
        let (mut step, mut size) = (0.0f64, 1.0f64);
        for (r, d) in d[..nc].iter().enumerate() {
            let nu = match self.owner[r] {
                Owner::Row(i) | Owner::Apex(i) => self.nu_row[i],
                Owner::Cone(k) => self.nu_cone[k],
            };
            step = step.max(d.abs());
            size = size.max(nu.abs());
        }
        step / size
    }

    /// Newton's method on the current guess.
    fn newton(&mut self) -> Step {
        let n = self.n;
        let (mut last_step, mut before_last) = (f64::INFINITY, f64::INFINITY);
        // The last step of the primal and dual variables together.
        let mut last_pair = f64::INFINITY;
        // The factors below replace the frozen ones.
        self.kkt_inverse_valid = false;
        let apex = self.piece.contains(&Piece::Apex);
        // Only a cone that left its apex can be held to a tangent plane.
        let left_apex = self.left_apex.contains(&true);
        self.tangent.iter_mut().for_each(|t| *t = false);
        self.closing
            .iter_mut()
            .for_each(|c| *c = (f64::NAN, f64::NAN, 0));
        // Whether Newton converged on the tangent planes, and the cones' own boundaries
        // took over from there, near their apex or not: an optimum that near the apex
        // (a contact barely loaded) would otherwise keep the planes to the end.
        let mut released = false;
        for it in 0..MAX_NEWTON {
            self.iterations += 1;
            if !self.slacks_at_y {
                self.slacks();
            }
            // Converging this guess cannot remove a violation far beyond the step, nor,
            // once the steps shrink quadratically (what is left to move is far below
            // the last step), one a few times the last step.
            if it >= 2 {
                let v = self.worst_inactive();
                let settling = last_step <= 0.1 * before_last;
                let bound = if settling { 2.0 } else { 100.0 } * last_step;
                if v > self.feasibility_tolerance() && v > bound {
                    return Step::Violated;
                }
            }
            // Constraint rows C and values c(x).
            let mut nc = 0;
            for i in self.orth.0..self.orth.1 {
                if self.active[i] {
                    self.c[nc * n..nc * n + n].copy_from_slice(self.a_red.row(i));
                    self.cval[nc] = -self.s[i];
                    self.owner[nc] = Owner::Row(i);
                    nc += 1;
                }
            }
            // H = P (2I: the objective is ‖y‖²), then the curvature.
            self.h.iter_mut().for_each(|v| *v = 0.0);
            for j in 0..n {
                self.h[j * n + j] = 2.0;
            }
            let ymax = norm_inf(&self.y);
            for k in 0..self.socs.len() {
                let (start, dim) = self.socs[k];
                if self.piece[k] != Piece::Boundary {
                    continue;
                }
                let s1 = &self.s[start + 1..start + dim];
                let r = soc_norm(s1);
                if r.is_nan() {
                    return Step::Failed;
                }
                let size = r + self.s[start].abs();
                let (_, last, runs) = self.closing[k];
                self.closing[k] = (size, r, if r <= CRAWL * last { runs + 1 } else { 0 });
                let near = self.within_near_apex(k, size, ymax) || self.s[start] <= -r;
                // (Only from the apex, on the first step, and while it stays there: a
                // cone released to its boundary that nears the apex again is the apex
                // piece again. Back on the plane, Newton alternated between plane and
                // boundary without converging.)
                let tangent = left_apex
                    && self.left_apex[k]
                    && (it == 0 || self.tangent[k])
                    && (near || self.s[start] <= 0.0 || r <= 1e-12 * self.s[start]);
                if left_apex {
                    self.tangent[k] = tangent;
                }
                if !tangent && (r <= 1e-12 * (self.s[start].abs() + r) || (near && !released)) {
                    // At the apex g is not differentiable; near it, its curvature ν/r
                    // grows without bound and Newton crawls; and from s in −K (past the
                    // apex) the nearest point of the cone is the apex.
                    return Step::AtApex(k);
                }
                // A cone that left its apex, while still near it, is held to the
                // tangent plane along the direction its apex dual gave (linear, no
                // curvature): from the apex, s1's own direction means nothing.
                let row = &mut self.c[nc * n..nc * n + n];
                row.copy_from_slice(self.a_red.row(start));
                self.owner[nc] = Owner::Cone(k);
                if tangent {
                    let u = &self.hint[k * MAX_TAIL..];
                    let mut along = 0.0;
                    for j in 1..dim {
                        along += u[j - 1] * s1[j - 1];
                        for (c, a) in row.iter_mut().zip(self.a_red.row(start + j)) {
                            *c -= u[j - 1] * a;
                        }
                    }
                    self.cval[nc] = along - self.s[start];
                    nc += 1;
                    continue;
                }
                let inv_r = 1.0 / r;
                for j in 1..dim {
                    let u = s1[j - 1] * inv_r;
                    for (c, a) in row.iter_mut().zip(self.a_red.row(start + j)) {
                        *c -= u * a;
                    }
                }
                self.cval[nc] = r - self.s[start];
                nc += 1;
                let nu = self.nu_cone[k];
                if nu <= 0.0 {
                    continue;
                }
                // (ν/r) A1ᵀ (I − uuᵀ) A1 as a sum of squares, positive semidefinite by
                // construction (G − v vᵀ with G = A1ᵀA1 cancels: with ν/r large it lost
                // the positive definiteness of H to rounding). In the plane (a tail of two),
                // I − uuᵀ = v vᵀ with v = (−u2, u1). Longer tails: the reflector
                // Q = I − 2 q qᵀ, q ∝ u ± e1, maps u to ∓e1, so its columns Q e_j,
                // j ≥ 1, are an orthonormal basis of u⊥ and I − uuᵀ = Σ_j Q e_j (Q e_j)ᵀ;
                // A1ᵀ Q e_j = a_j − 2 q_j m with m = Σ_i q_i a_i.
                let c = nu * inv_r;
                let tail = dim - 1;
                let a1 = &self.a_red.as_slice()[(start + 1) * n..(start + dim) * n];
                let g = &mut self.dx[..n];
                if tail == 2 {
                    let (v1, v2) = (-s1[1] * inv_r, s1[0] * inv_r);
                    for ((g, a), b) in g.iter_mut().zip(&a1[..n]).zip(&a1[n..]) {
                        *g = v1 * a + v2 * b;
                    }
                    add_square(&mut self.h, n, c, g);
                    continue;
                }
                let mut q = [0.0; MAX_TAIL];
                let q = &mut q[..tail];
                for (qi, si) in q.iter_mut().zip(s1) {
                    *qi = si * inv_r;
                }
                let sign = if q[0] >= 0.0 { 1.0 } else { -1.0 };
                q[0] += sign;
                let inv_qn = 1.0 / soc_norm(q);
                q.iter_mut().for_each(|v| *v *= inv_qn);
                let m = &mut self.t[..n];
                m.iter_mut().for_each(|x| *x = 0.0);
                for (qi, row) in q.iter().zip(a1.chunks_exact(n)) {
                    for (x, a) in m.iter_mut().zip(row) {
                        *x += qi * a;
                    }
                }
                for (j, row) in a1[n..].chunks_exact(n).enumerate() {
                    let f = 2.0 * q[j + 1];
                    for ((g, a), m) in g.iter_mut().zip(row).zip(&*m) {
                        *g = a - f * m;
                    }
                    add_square(&mut self.h, n, c, g);
                }
            }
            if apex {
                nc = self.apex_constraints(nc);
            }
            if !cholesky(&mut self.h, n) {
                return Step::Failed;
            }
            // Y = L⁻¹ Cᵀ, S = YᵀY, t = L⁻¹(−P x).
            if !schur(&self.h, n, &self.c, nc, &mut self.ycols, &mut self.schur) {
                // Dependent constraints: the guess is degenerate.
                return Step::Failed;
            }
            for j in 0..n {
                self.t[j] = -2.0 * self.y[j];
            }
            self.solve_kkt(nc);
            // Globalised by backtracking on the ℓ1 merit ‖y‖² + ρ Σ|c_j(y)|, ρ above
            // every multiplier; a full step is also taken when it at least halves the
            // constraint violation (it is Newton's, and the merit alone would refuse
            // full steps near the boundary's curvature).
            let rho = 2.0 * self.nu[..nc].iter().fold(0.0f64, |a, v| a.max(v.abs())) + 1e-12;
            let viol0: f64 = self.cval[..nc].iter().map(|v| v.abs()).sum();
            let f0: f64 = self.y.iter().map(|v| v * v).sum();
            let slope = 2.0 * dot4(&self.y, &self.dx) - rho * viol0;
            let mut alpha = 1.0;
            // A full step that leaves the point where it is (the guess changed its
            // constraints, not the point: a cone put at the apex it is at) is taken
            // as it is: the merit only sees rounding there, and the multipliers need
            // the whole step.
            let full_step = norm_inf(&self.dx);
            let still = apex && full_step <= 1e-10 * norm_inf(&self.y).max(1.0);
            for _ in 0..if still { 0 } else { 30 } {
                for (t, (y, d)) in self.t[..n].iter_mut().zip(self.y.iter().zip(&self.dx)) {
                    *t = y + alpha * d;
                }
                let viol = self.violation(nc);
                let f: f64 = self.t[..n].iter().map(|v| v * v).sum();
                let armijo = f + rho * viol <= f0 + rho * viol0 + 1e-4 * alpha * slope.min(0.0);
                if (alpha == 1.0 && viol <= 0.5 * viol0) || armijo {
                    break;
                }
                if alpha == 1.0 && self.second_order_correction(nc, f0 + rho * viol0, rho, slope) {
                    break;
                }
                alpha *= 0.5;
            }
            if !still {
                alpha = alpha.min(self.apex_limit());
            }
            for r in 0..nc {
                let old = match self.owner[r] {
                    Owner::Row(i) | Owner::Apex(i) => &mut self.nu_row[i],
                    Owner::Cone(k) => &mut self.nu_cone[k],
                };
                let d = alpha * (self.nu[r] - *old);
                // (`nu` keeps the change, for the multipliers' step below.)
                self.nu[r] = d;
                *old += d;
            }
            for d in self.dx.iter_mut() {
                *d *= alpha;
            }
            for (y, d) in self.y.iter_mut().zip(&self.dx) {
                *y += d;
            }
            self.slacks_at_y = false;
            let step = norm_inf(&self.dx);
            let previous = last_step;
            before_last = last_step;
            last_step = step;
            if !self.y.iter().all(|v| v.is_finite()) {
                return Step::Failed;
            }
            // Converged: with every multiplier of the right sign the Hessian is exact
            // and the error after this step is of the order of its square — so a full
            // step of 1e-7 that shrank ×100 from the last leaves an error near 1e-14.
            let scale = norm_inf(&self.y).max(1.0);
            let quadratic = alpha == 1.0 && step <= 1e-7 * scale && step <= 1e-2 * previous;
            // (The full step: a line search that collapsed is no convergence.)
            let tangent = left_apex && self.tangent.contains(&true);
            if (full_step <= 1e-10 * scale || quadratic) && !tangent {
                self.frozen = Some(nc);
                return Step::Converged;
            }
            let pair = (step / scale).max(self.multiplier_step(nc, &self.nu));
            let contraction = if previous.is_finite() && last_pair.is_finite() {
                (step / previous).max(pair / last_pair)
            } else {
                f64::INFINITY
            };
            last_pair = pair;
            // A clearly negative multiplier: this guess is wrong, change it now. After
            // the first step only one far below zero counts (a tenth of the largest:
            // the start's multipliers came from the polyhedra), after that any below
            // rounding. With a cone at its apex, only after a full step: an apex's
            // multipliers start from zero, not from the polyhedra, and a damped step
            // leaves every multiplier part way to its new value.
            {
                // On the multipliers as stored (damped by the step), which the caller's
                // correction reads.
                let stored = |r: usize| match self.owner[r] {
                    Owner::Row(i) | Owner::Apex(i) => self.nu_row[i],
                    Owner::Cone(k) => self.nu_cone[k],
                };
                let numax = (0..nc).fold(f64::MIN_POSITIVE, |a, r| a.max(stored(r).abs()));
                let bar = if it == 0 { 0.1 } else { 1e-6 };
                // (An apex's rows may have either sign: its dual cone decides.)
                let negative = (0..nc)
                    .any(|r| !matches!(self.owner[r], Owner::Apex(_)) && stored(r) < -bar * numax);
                let outside = apex
                    && (0..self.socs.len()).any(|k| {
                        self.piece[k] == Piece::Apex && self.apex_deficit(k) > bar * numax
                    });
                if (negative || outside) && (alpha == 1.0 || !apex) {
                    return Step::Negative;
                }
            }
            // Converged on a plane, with the guess's multipliers right: on to the cones'
            // own boundaries (a point of a plane is outside its cone by ‖s1‖ − uᵀs1).
            if full_step <= 1e-10 * scale && tangent && !released {
                released = true;
                self.tangent.iter_mut().for_each(|t| *t = false);
                continue;
            }
            // Settling quadratically (a full step a twentieth of the last or less): the
            // factors would barely change, so the rest is chord steps on these
            // (Shamanskii's variant), each O(k² + nc·k) instead of a factorisation.
            // After Newton's step s_j the error is about the first chord step c, and a
            // chord step contracts it by about K s_j with K ≈ c / s_j² (quadratic
            // convergence): c / s_j, the rate the chord measures against s_j.
            if alpha == 1.0 && contraction <= 0.05 && !tangent {
                self.frozen = Some(nc);
                match self.chord(nc, false, pair) {
                    Step::Converged => return Step::Converged,
                    Step::Failed if !self.y.iter().all(|v| v.is_finite()) => return Step::Failed,
                    // Slower than expected (or at the apex, which Newton reports
                    // itself): refactor.
                    _ => self.frozen = None,
                }
            }
        }
        // Out of iterations: a piece closing on its apex goes there (see CRAWL).
        let near = NEAR_APEX * norm_inf(&self.y).max(1.0);
        let closing = (0..self.socs.len())
            .filter(|&k| {
                let (size, _, runs) = self.closing[k];
                self.piece[k] == Piece::Boundary && runs >= CLOSING && size <= near
            })
            .min_by(|&a, &b| self.closing[a].0.total_cmp(&self.closing[b].0));
        match closing {
            Some(k) => Step::AtApex(k),
            None => Step::Failed,
        }
    }
}

/// How far a slack may be below zero at `y` and still count as held.
fn feasibility_tolerance_at(y: &[f64]) -> f64 {
    1e-10 * norm_inf(y).max(1.0)
}

/// `h += c g gᵀ` on the row-major n × n `h` (whole rows: at these sizes the lower
/// triangle's uneven rows cost more than they save).
fn add_square(h: &mut [f64], n: usize, c: f64, g: &[f64]) {
    for (hrow, gi) in h.chunks_exact_mut(n).zip(g) {
        let cg = c * gi;
        for (h, gj) in hrow.iter_mut().zip(g) {
            *h += cg * gj;
        }
    }
}

fn soc_norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}
