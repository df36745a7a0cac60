//! The singular value decomposition, by one-sided Jacobi rotations.
//!
//! Grasp matrices are small (at most 262 × 1024 within the input domain) and the model
//! needs the *full* decomposition: V's trailing columns span the passive internal
//! forces, U's the complement of the range that the consistency equalities come from.
//! One-sided Jacobi (Hestenes) orthogonalises the columns of the shorter side by plane
//! rotations until every pair is orthogonal to rounding. It is simple, it allocates
//! only its result, and it is accurate: singular values to high relative accuracy and
//! factors that reconstruct A to rounding (the reason faer's SVD was preferred over
//! nalgebra's earlier; `cargo bench -p grasp-torque --bench decomposition` compares).
//! Dropping faer also removed the largest part of the build.
//!
//! The model calls [`decompose`], which takes the SVD only when a rank decision is close
//! to its threshold: a Householder QR answers when A is clearly of full rank, and a
//! complete orthogonal decomposition (QR with column pivoting) when its rank is clearly
//! lower, as for grasps whose `[G; Jᵀ]` has passive internal forces. Both decide the rank
//! exactly as the SVD would, from bounds on the singular values.

use crate::matrix::{finite_max_abs, Matrix};

/// A full singular value decomposition `A = U Σ Vᵀ`.
#[derive(Clone, Debug)]
pub struct Svd {
    /// Left singular vectors, `rows × rows`.
    pub u: Matrix,
    /// Singular values, non-increasing, `min(rows, cols)` of them.
    pub s: Vec<f64>,
    /// Right singular vectors, `cols × cols`.
    pub v: Matrix,
}

impl Svd {
    /// The numerical rank: singular values above `rel_tol · σ_max`.
    pub fn rank(&self, rel_tol: f64) -> usize {
        let smax = self.s.first().copied().unwrap_or(0.0);
        if smax == 0.0 {
            return 0;
        }
        self.s.iter().take_while(|&&s| s > rel_tol * smax).count()
    }

    /// The pseudo-inverse `V Σ⁺ Uᵀ` with singular values at or below `rel_tol · σ_max` dropped.
    pub fn pseudo_inverse(&self, rel_tol: f64) -> Matrix {
        let r = self.rank(rel_tol);
        let (rows, cols) = (self.u.nrows(), self.v.nrows());
        let mut out = Matrix::zeros(cols, rows);
        for k in 0..r {
            let inv = 1.0 / self.s[k];
            for i in 0..cols {
                let vik = self.v[(i, k)] * inv;
                if vik != 0.0 {
                    for j in 0..rows {
                        out[(i, j)] += vik * self.u[(j, k)];
                    }
                }
            }
        }
        out
    }
}

/// Why a decomposition could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the singular value decomposition of a {rows}×{cols} matrix did not converge")]
pub struct SvdError {
    /// Rows of the matrix.
    pub rows: usize,
    /// Columns of the matrix.
    pub cols: usize,
}

/// Sweeps before giving up; convergence is quadratic and takes 6–12 at grasp sizes.
const MAX_SWEEPS: usize = 80;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// One-sided Jacobi on the columns of `cols` (each of length `len`): rotates pairs
/// until they are orthogonal, applying the same rotations to the columns of `w`.
/// Columns whose squared norm is at most `negligible` are numerically zero: rotating
/// them only stirs rounding, so they are left alone (and later completed).
fn orthogonalise(cols: &mut [Vec<f64>], w: &mut [Vec<f64>], negligible: f64) -> bool {
    let n = cols.len();
    let len = cols.first().map_or(0, Vec::len);
    let tol = f64::EPSILON * len.max(1) as f64;
    // Squared column norms, updated by each rotation and recomputed every sweep.
    let mut sq: Vec<f64> = cols.iter().map(|c| dot(c, c)).collect();
    for _ in 0..MAX_SWEEPS {
        let mut rotated = false;
        for i in 0..n {
            for j in i + 1..n {
                let (alpha, beta) = (sq[i], sq[j]);
                if alpha <= negligible || beta <= negligible {
                    continue;
                }
                let gamma = {
                    let (l, r) = cols.split_at(j);
                    dot(&l[i], &r[0])
                };
                if gamma.abs() <= tol * (alpha * beta).sqrt() {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = c * t;
                for m in [&mut *cols, &mut *w] {
                    let (l, r) = m.split_at_mut(j);
                    for (x, y) in l[i].iter_mut().zip(r[0].iter_mut()) {
                        let (p, q) = (*x, *y);
                        *x = c * p - s * q;
                        *y = s * p + c * q;
                    }
                }
                sq[i] = alpha - t * gamma;
                sq[j] = beta + t * gamma;
            }
        }
        if !rotated {
            return true;
        }
        for (q, c) in sq.iter_mut().zip(cols.iter()) {
            *q = dot(c, c);
        }
    }
    false
}

/// Completes orthonormal columns `q` (each of length `len`) to an orthonormal basis:
/// the trailing columns of the Householder Q of `[q]` span their complement.
fn complete(q: &[Vec<f64>], len: usize) -> Vec<Vec<f64>> {
    let k = q.len();
    let mut w: Vec<f64> = q.iter().flatten().copied().collect();
    let (mut vhead, mut tau) = (vec![0.0; k], vec![0.0; k]);
    householder(&mut w, len, k, &mut vhead, &mut tau);
    let full = explicit_q(&w, len, k, &vhead, &tau);
    full[k * len..]
        .chunks_exact(len)
        .map(<[f64]>::to_vec)
        .collect()
}

/// Full SVD of `a`. Empty matrices give empty factors.
pub fn svd(a: &Matrix) -> Result<Svd, SvdError> {
    let (rows, cols) = (a.nrows(), a.ncols());
    if rows == 0 || cols == 0 {
        return Ok(Svd {
            u: Matrix::identity(rows),
            s: Vec::new(),
            v: Matrix::identity(cols),
        });
    }
    if a.as_slice().iter().any(|x| !x.is_finite()) {
        return Err(SvdError { rows, cols });
    }
    // Rotate the columns of the shorter side: M = A (tall) or Aᵀ (wide), so that
    // M W = [σ_k x_k] with W orthogonal (k = min(rows, cols) columns).
    let wide = rows < cols;
    let (len, k) = if wide { (cols, rows) } else { (rows, cols) };
    let mut m: Vec<Vec<f64>> = (0..k)
        .map(|c| {
            (0..len)
                .map(|i| if wide { a[(c, i)] } else { a[(i, c)] })
                .collect()
        })
        .collect();
    let mut w: Vec<Vec<f64>> = (0..k)
        .map(|c| (0..k).map(|i| if i == c { 1.0 } else { 0.0 }).collect())
        .collect();
    // Below ε·‖A‖_F (times √len) a column is rounding noise.
    let fro = a.as_slice().iter().map(|x| x * x).sum::<f64>().sqrt();
    let tiny = f64::EPSILON * fro * (len as f64).sqrt();
    if !orthogonalise(&mut m, &mut w, tiny * tiny) {
        return Err(SvdError { rows, cols });
    }
    let norms: Vec<f64> = m.iter().map(|c| dot(c, c).sqrt()).collect();
    let mut order: Vec<usize> = (0..k).collect();
    order.sort_by(|&x, &y| norms[y].total_cmp(&norms[x]));
    let s: Vec<f64> = order.iter().map(|&c| norms[c]).collect();
    // The long side's singular vectors: normalised columns where σ is above the
    // noise, completed to an orthonormal basis.
    let defined: Vec<Vec<f64>> = order
        .iter()
        .filter(|&&c| norms[c] > tiny && norms[c] > 1e-280)
        .map(|&c| m[c].iter().map(|x| x / norms[c]).collect())
        .collect();
    let mut long = defined.clone();
    long.extend(complete(&defined, len));
    let short = |i: usize, j: usize| w[order[j]][i];
    let longm = |i: usize, j: usize| long[j][i];
    let (u, v) = if wide {
        (
            Matrix::from_fn(rows, rows, short),
            Matrix::from_fn(cols, cols, longm),
        )
    } else {
        (
            Matrix::from_fn(rows, rows, longm),
            Matrix::from_fn(cols, cols, short),
        )
    };
    Ok(Svd { u, s, v })
}

/// What the model needs of a matrix A (rows × cols) of rank r, from a QR factorisation
/// (the fast path, when A is clearly of full rank), a complete orthogonal
/// decomposition (when its rank is clearly lower) or the SVD:
///
/// - `A x = b` for a b in the range of A ⇔ `row_basisᵀ x = row_transform · b`;
/// - `A⁺ = row_basis · row_transform`;
/// - `null_basis` spans the null space, `left_null` the complement of the range.
///
/// All three bases are orthonormal.
#[derive(Clone, Debug)]
pub struct Decomposition {
    /// Orthonormal basis of the row space, cols × r.
    pub row_basis: Matrix,
    /// r × rows.
    pub row_transform: Matrix,
    /// Orthonormal basis of the null space, cols × (cols − r).
    pub null_basis: Matrix,
    /// Orthonormal basis of the range's complement, rows × (rows − r).
    pub left_null: Matrix,
}

impl Decomposition {
    /// The rank r.
    pub fn rank(&self) -> usize {
        self.row_basis.ncols()
    }

    /// The pseudo-inverse `A⁺ = row_basis · row_transform`.
    pub fn pseudo_inverse(&self) -> Matrix {
        // The QR path of a full-column-rank A has row_basis = I: A⁺ is row_transform.
        let b = &self.row_basis;
        let identity = b.nrows() == b.ncols()
            && (0..b.nrows()).all(|i| {
                b.row(i)
                    .iter()
                    .enumerate()
                    .all(|(j, &x)| x == (i == j) as u8 as f64)
            });
        if identity {
            return self.row_transform.clone();
        }
        b.matmul(&self.row_transform)
    }
}

/// How small a singular value counts as zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RankThreshold {
    /// At or below `tol · σ_max`.
    Relative(f64),
    /// At or below `tol`.
    Absolute(f64),
}

/// The inverse of the upper triangular `k × k` matrix with entries `r(i, j)`, row-major,
/// by back substitution a row at a time: entry (i, j) is
/// `(δᵢⱼ − Σ_{l=i+1..j} r(i, l) R⁻¹(l, j)) / r(i, i)`, summed in l order, with the row's
/// entries updated together so that the sums run side by side.
fn upper_inverse(r: impl Fn(usize, usize) -> f64, k: usize) -> Vec<f64> {
    let mut inv = vec![0.0; k * k];
    for i in (0..k).rev() {
        let (head, below) = inv.split_at_mut((i + 1) * k);
        let row = &mut head[i * k..];
        row[i] = 1.0;
        for l in i + 1..k {
            let f = r(i, l);
            for (x, y) in row[l..]
                .iter_mut()
                .zip(&below[(l - i - 1) * k + l..(l - i) * k])
            {
                *x -= f * y;
            }
        }
        let d = r(i, i);
        row[i..].iter_mut().for_each(|x| *x /= d);
    }
    inv
}

/// Applies the reflector `I − t u uᵀ`, `u = (head, v)`, to rows `c..` of every column
/// of `cols` (column-major, columns of length `len`). Four columns at a time: each
/// column's sum runs in the same order as one at a time, so the result is the same to
/// the bit, but four independent sums hide the latency of the additions, which is what
/// a single short dot product waits on.
fn reflect(head: f64, v: &[f64], t: f64, cols: &mut [f64], len: usize, c: usize) {
    let mut blocks = cols.chunks_exact_mut(4 * len);
    for block in &mut blocks {
        let (a, rest) = block.split_at_mut(len);
        let (b, rest) = rest.split_at_mut(len);
        let (d, e) = rest.split_at_mut(len);
        let (a, b, d, e) = (&mut a[c..], &mut b[c..], &mut d[c..], &mut e[c..]);
        let n = v.len();
        let (a1, b1, d1, e1) = (&a[1..=n], &b[1..=n], &d[1..=n], &e[1..=n]);
        let mut s = [-0.0f64; 4];
        for i in 0..n {
            s[0] += v[i] * a1[i];
            s[1] += v[i] * b1[i];
            s[2] += v[i] * d1[i];
            s[3] += v[i] * e1[i];
        }
        for (y, si) in [a, b, d, e].into_iter().zip(s) {
            let f = t * (head * y[0] + si);
            y[0] -= f * head;
            for (yi, vi) in y[1..].iter_mut().zip(v) {
                *yi -= f * vi;
            }
        }
    }
    for col in blocks.into_remainder().chunks_exact_mut(len) {
        let y = &mut col[c..];
        let f = t * (head * y[0] + dot(v, &y[1..]));
        y[0] -= f * head;
        for (yi, vi) in y[1..].iter_mut().zip(v) {
            *yi -= f * vi;
        }
    }
}

/// Householder QR of `k` columns of length `len ≥ k`, stored column-major in `w`
/// (column c at `w[c·len..]`). On return the upper triangle of the first k rows holds
/// R, and reflector c is `v = w[c·len + c..(c+1)·len]` below the diagonal with
/// `v[0] = vhead[c]`, applied as `I − tau[c] v vᵀ` (tau 0: no reflection).
fn householder(w: &mut [f64], len: usize, k: usize, vhead: &mut [f64], tau: &mut [f64]) {
    for c in 0..k {
        householder_step(w, len, k, c, vhead, tau);
    }
}

/// Step c of [`householder`]: the reflector of column c, applied to columns c+1..k.
fn householder_step(
    w: &mut [f64],
    len: usize,
    k: usize,
    c: usize,
    vhead: &mut [f64],
    tau: &mut [f64],
) {
    let (col, later) = w[c * len..k * len].split_at_mut(len);
    let x = &mut col[c..];
    let norm = dot(x, x).sqrt();
    let alpha = if x[0] >= 0.0 { -norm } else { norm };
    let head = x[0] - alpha;
    // ‖v‖² with v = x − alpha e₁.
    let vn = head * head + dot(&x[1..], &x[1..]);
    if vn > 0.0 {
        let t = 2.0 / vn;
        reflect(head, &x[1..], t, later, len, c);
        tau[c] = t;
        x[0] = alpha;
    } else {
        tau[c] = 0.0;
    }
    vhead[c] = head;
}

/// Q = H_0 … H_{k−1} of [`householder`]'s output, column-major len × len: the
/// reflectors applied to I from the last one. Reflector c leaves rows < c alone, and
/// columns e < c are still e_e there, so it touches columns c.. only.
fn explicit_q(w: &[f64], len: usize, k: usize, vhead: &[f64], tau: &[f64]) -> Vec<f64> {
    let mut q = vec![0.0; len * len];
    for e in 0..len {
        q[e * len + e] = 1.0;
    }
    for c in (0..k).rev() {
        if tau[c] == 0.0 {
            continue;
        }
        let v = &w[c * len + c + 1..(c + 1) * len];
        reflect(vhead[c], v, tau[c], &mut q[c * len..], len, c);
    }
    q
}

/// An orthonormal basis of the range of the tall `y` (rows ≥ cols), rows × cols, by
/// Householder QR (backward stable: the basis is that of a matrix within rounding of
/// `y`), when R shows full column rank clearly, `min |r_ii| > 1e-6 max |r_ii|`; `None`
/// otherwise (and for a wide or non-finite `y`).
///
/// The explicit Q carries an error of ε in every entry. Where y's rows span more than
/// [`ROW_SPREAD`] in norm, that buries the small rows (a joint whose moment arms are
/// 1e-8 of the others', which the consistency equalities' null space pins to 1e-8 of
/// their torques: products with the large columns of H that such a joint has left a
/// feasible grasp 1e-9 short of its cones). There the basis is `y R⁻¹`, twice
/// (`range_pass`), of y or, where R is too ill conditioned for that, of the graded
/// basis of y's range (`graded_range`): each of its rows is y's row times a k × k
/// matrix, so it keeps its digits relative to its own size; the first pass is
/// orthonormal to ε times R's condition, the second to ε.
pub fn orthonormal_columns(y: &Matrix) -> Option<Matrix> {
    let (len, k) = (y.nrows(), y.ncols());
    let big = finite_max_abs(y.as_slice())?;
    if k > len {
        return None;
    }
    // The basis is that of any multiple of y.
    if let Some((scaled, ..)) = power_of_two_scaled(y, big, RankThreshold::Relative(0.0)) {
        return orthonormal_columns(&scaled);
    }
    let (lo, hi) = (0..len).fold((f64::INFINITY, 0.0f64), |(lo, hi), i| {
        let r = crate::matrix::norm2(y.row(i));
        (if r > 0.0 { lo.min(r) } else { lo }, hi.max(r))
    });
    if hi > ROW_SPREAD * lo {
        // Rows far apart in size. Where fewer rows are large than y has columns, y's
        // columns are near parallel and R too ill conditioned for a basis: then that
        // of the graded basis of the same range (`graded_range`).
        return range_pass(y)
            .and_then(|q| range_pass(&q))
            .or_else(|| range_pass(&range_pass(&graded_range(y)?)?));
    }
    let mut w = longer_side(y);
    let (mut vhead, mut tau) = (vec![0.0; k], vec![0.0; k]);
    householder(&mut w, len, k, &mut vhead, &mut tau);
    let (lo, hi) = (0..k).fold((f64::INFINITY, 0.0f64), |(lo, hi), i| {
        let d = w[i * len + i].abs();
        (lo.min(d), hi.max(d))
    });
    if k > 0 && (lo.is_nan() || lo <= 1e-6 * hi) {
        return None;
    }
    // Q e_j for j < k only: reflector c touches columns c..k of them.
    let mut q = vec![0.0; len * k];
    for e in 0..k {
        q[e * len + e] = 1.0;
    }
    for c in (0..k).rev() {
        if tau[c] != 0.0 {
            let v = &w[c * len + c + 1..(c + 1) * len];
            reflect(vhead[c], v, tau[c], &mut q[c * len..], len, c);
        }
    }
    // A zero row of y is one of the range: exactly (Q's would be rounding).
    Some(Matrix::from_fn(len, k, |i, j| {
        if y.row(i).iter().all(|v| *v == 0.0) {
            0.0
        } else {
            q[j * len + i]
        }
    }))
}

/// The spread of row norms past which [`orthonormal_columns`] forms its basis row by
/// row: Q's error of ε is then up to 1e-12 of a small row.
pub const ROW_SPREAD: f64 = 1e4;

/// A basis of the range of `y` (tall, finite) whose columns are near orthogonal even
/// where y's rows differ in size by many orders, with each row a combination of y's row
/// alone: `y V` for an orthogonal k × k V made of reflections from the right, one per
/// row taken in order of size (the largest first, of what earlier reflections left),
/// each zeroing that row past one column. The largest row then sits in one column and
/// the next columns see only the smaller rows, so that no column is a small remainder
/// of a large one; each column is scaled to unit length. (Householder QR of y itself
/// mixes the rows: its R is as ill conditioned as y's columns are, and beside a joint
/// with moment arms 8e8 times the others' and one pinned at 1e-8 of them its diagonal
/// spread past the 1e6 that [`range_pass`] admits, so that there was no basis.) `None`
/// if a column is left without a nonzero row.
fn graded_range(y: &Matrix) -> Option<Matrix> {
    let (len, k) = (y.nrows(), y.ncols());
    let mut l = y.clone();
    let mut done = vec![false; len];
    let mut v = vec![0.0; k];
    for t in 0..k.min(len) {
        // The remaining row with the largest part in columns t..k.
        let (mut best, mut size) = (usize::MAX, 0.0f64);
        for i in (0..len).filter(|&i| !done[i]) {
            let r = crate::matrix::norm2(&l.row(i)[t..]);
            if r > size {
                (best, size) = (i, r);
            }
        }
        if best == usize::MAX {
            return None;
        }
        done[best] = true;
        // The reflection I − 2 v vᵀ/(vᵀv) mapping that part onto ±size e_t.
        let row = &l.row(best)[t..];
        let head = row[0];
        let alpha = if head >= 0.0 { -size } else { size };
        v[t..].copy_from_slice(row);
        v[t] -= alpha;
        let vv = crate::matrix::norm2(&v[t..]).powi(2);
        if vv > 0.0 {
            for i in 0..len {
                let r = &mut l.row_mut(i)[t..];
                let d: f64 = r.iter().zip(&v[t..]).map(|(a, b)| a * b).sum();
                let f = 2.0 * d / vv;
                r.iter_mut().zip(&v[t..]).for_each(|(a, b)| *a -= f * b);
            }
        }
        // (Exactly what the reflection makes of that row.)
        let r = &mut l.row_mut(best)[t..];
        r.fill(0.0);
        r[0] = alpha;
    }
    for j in 0..k {
        let norm = (0..len).map(|i| l[(i, j)] * l[(i, j)]).sum::<f64>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return None;
        }
        (0..len).for_each(|i| l[(i, j)] /= norm);
    }
    Some(l)
}

/// `y R⁻¹` with R from the Householder QR of `y` (tall, finite), when R shows full
/// column rank clearly ([`orthonormal_columns`]).
fn range_pass(y: &Matrix) -> Option<Matrix> {
    let (len, k) = (y.nrows(), y.ncols());
    let mut w = longer_side(y);
    let (mut vhead, mut tau) = (vec![0.0; k], vec![0.0; k]);
    householder(&mut w, len, k, &mut vhead, &mut tau);
    let r = |i: usize, j: usize| w[j * len + i];
    let (lo, hi) = (0..k).fold((f64::INFINITY, 0.0f64), |(lo, hi), i| {
        let d = r(i, i).abs();
        (lo.min(d), hi.max(d))
    });
    if k > 0 && (lo.is_nan() || lo <= 1e-6 * hi) {
        return None;
    }
    let rinv = upper_inverse(r, k);
    let mut n = Matrix::zeros(len, k);
    for i in 0..len {
        let (yi, ni) = (y.row(i), n.row_mut(i));
        // Row i of y R⁻¹: R⁻¹ is upper triangular, so column j sums l ≤ j.
        for (l, &v) in yi.iter().enumerate() {
            for (x, q) in ni[l..].iter_mut().zip(&rinv[l * k + l..(l + 1) * k]) {
                *x += v * q;
            }
        }
    }
    Some(n)
}

/// The columns of the longer side of `a`, column-major: its columns, or its rows when
/// it is wide.
fn longer_side(a: &Matrix) -> Vec<f64> {
    let (rows, cols) = (a.nrows(), a.ncols());
    let wide = rows < cols;
    let (len, k) = if wide { (cols, rows) } else { (rows, cols) };
    let mut w = vec![0.0; len * k];
    for (c, col) in w.chunks_exact_mut(len).enumerate() {
        for (i, x) in col.iter_mut().enumerate() {
            *x = if wide { a[(c, i)] } else { a[(i, c)] };
        }
    }
    w
}

/// Householder QR of `w` ([`householder`]), and `R⁻¹` (row-major) when R shows full
/// rank by a margin: `σ_min/σ_max ≥ 1/(‖R‖_F ‖R⁻¹‖_F)` above both 1e-6 and the
/// threshold's [`COD_MARGIN`] multiple, so that no rank decision is near. `None`
/// otherwise.
fn clear_full_rank_qr(
    w: &mut [f64],
    len: usize,
    k: usize,
    vhead: &mut [f64],
    tau: &mut [f64],
    threshold: RankThreshold,
) -> Option<Vec<f64>> {
    householder(w, len, k, vhead, tau);
    let r = |i: usize, j: usize| w[j * len + i];
    // cond(R) ≥ max |r_ii| / min |r_ii|: a rank-deficient A stops here.
    let (lo, hi) = (0..k).fold((f64::INFINITY, 0.0f64), |(lo, hi), i| {
        (lo.min(r(i, i).abs()), hi.max(r(i, i).abs()))
    });
    if lo * 1e6 <= hi {
        return None;
    }
    let rinv = upper_inverse(r, k);
    let nr = (0..k)
        .map(|j| (0..=j).map(|i| r(i, j) * r(i, j)).sum::<f64>())
        .sum::<f64>()
        .sqrt();
    let ni = dot(&rinv, &rinv).sqrt();
    let clear = match threshold {
        RankThreshold::Relative(t) => nr * ni < 1e6 && nr * ni * COD_MARGIN * t < 1.0,
        // σ_min ≥ 1/‖R⁻¹‖_F must clear the threshold by the same margin.
        RankThreshold::Absolute(t) => nr * ni < 1e6 && 1.0 / ni > 1e6 * t,
    };
    clear.then_some(rinv)
}

/// The numerical rank of `a` as [`decompose`] decides it, without forming any basis
/// when `a` is clearly of full rank (the QR's R alone).
pub fn rank(a: &Matrix, threshold: RankThreshold) -> Result<usize, SvdError> {
    let (rows, cols) = (a.nrows(), a.ncols());
    let big = finite_max_abs(a.as_slice()).ok_or(SvdError { rows, cols })?;
    if let Some((scaled, _, threshold)) = power_of_two_scaled(a, big, threshold) {
        return rank(&scaled, threshold);
    }
    let k = rows.min(cols);
    if k > 0 {
        let len = rows.max(cols);
        let mut w = longer_side(a);
        let (mut vhead, mut tau) = (vec![0.0; k], vec![0.0; k]);
        if clear_full_rank_qr(&mut w, len, k, &mut vhead, &mut tau, threshold).is_some() {
            return Ok(k);
        }
    }
    decompose(a, threshold).map(|d| d.rank())
}

/// The fast path: Householder QR of the longer side when A has full rank by a
/// margin ([`clear_full_rank_qr`]); `None` otherwise. Flat buffers, one allocation
/// each: the model of every grasp passes here, so a batch of grasps is mostly this.
fn decompose_qr(a: &Matrix, threshold: RankThreshold) -> Option<Decomposition> {
    let (rows, cols) = (a.nrows(), a.ncols());
    let wide = rows < cols;
    let (len, k) = if wide { (cols, rows) } else { (rows, cols) };
    let mut w = longer_side(a);
    let (mut vhead, mut tau) = (vec![0.0; k], vec![0.0; k]);
    let rinv = clear_full_rank_qr(&mut w, len, k, &mut vhead, &mut tau, threshold)?;
    let q = explicit_q(&w, len, k, &vhead, &tau);
    // Columns a..b of Q (column-major) as a row-major matrix.
    let q_cols = |a: usize, b: usize| {
        let mut data = vec![0.0; len * (b - a)];
        for (j, col) in q[a * len..b * len].chunks_exact(len).enumerate() {
            for (i, &x) in col.iter().enumerate() {
                data[i * (b - a) + j] = x;
            }
        }
        Matrix::from_rows_data(len, b - a, data)
    };
    Some(if wide {
        // Aᵀ = Q₁ R: A = Rᵀ Q₁ᵀ, so A x = b ⇔ Q₁ᵀ x = R⁻ᵀ b.
        Decomposition {
            row_basis: q_cols(0, rows),
            row_transform: Matrix::from_fn(rows, rows, |i, j| rinv[j * k + i]),
            null_basis: q_cols(rows, cols),
            left_null: Matrix::zeros(rows, 0),
        }
    } else {
        // A = Q₁ R: A x = b ⇔ x = R⁻¹ Q₁ᵀ b (b in the range). Row i of R⁻¹ Q₁ᵀ sums
        // the columns l ≥ i of Q₁, each contiguous.
        let mut t = vec![0.0; cols * rows];
        for (i, trow) in t.chunks_exact_mut(rows).enumerate() {
            for l in i..k {
                let f = rinv[i * k + l];
                for (x, y) in trow.iter_mut().zip(&q[l * len..(l + 1) * len]) {
                    *x += f * y;
                }
            }
        }
        Decomposition {
            row_basis: Matrix::identity(cols),
            row_transform: Matrix::from_rows_data(cols, rows, t),
            null_basis: Matrix::zeros(cols, 0),
            left_null: q_cols(cols, rows),
        }
    })
}

/// How far a rank decision must clear the threshold on both sides, as a factor, for
/// the complete orthogonal decomposition to take it instead of the SVD: its bounds on
/// the singular values are then far from any value rounding could move across.
const COD_MARGIN: f64 = 1e3;

/// Solves `T X = B` in place (`b` holds B on entry, X on return), T triangular with
/// entries `t(i, j)`: upper by back substitution, lower by forward substitution.
fn solve_triangular(b: &mut Matrix, t: impl Fn(usize, usize) -> f64, upper: bool) {
    let (r, c) = (b.nrows(), b.ncols());
    for step in 0..r {
        let i = if upper { r - 1 - step } else { step };
        let solved = if upper { i + 1..r } else { 0..i };
        for l in solved {
            let f = t(i, l);
            for j in 0..c {
                b[(i, j)] -= f * b[(l, j)];
            }
        }
        let d = t(i, i);
        b.row_mut(i).iter_mut().for_each(|v| *v /= d);
    }
}

/// The rank-deficient path: a complete orthogonal decomposition `M P = Q [R₁₁ R₁₂; 0 R₂₂]`
/// by Householder QR with column pivoting, `R₂₂` dropped, then `[R₁₁ R₁₂]ᵀ = Z₁ L` by
/// a second QR (Golub and Van Loan, §5.4.2), so that `M = Q₁ Lᵀ W₁ᵀ` with `W = P Z`.
/// M is A, or Aᵀ when A is wide.
///
/// It decides the rank only when the decision is certain by [`COD_MARGIN`] on both
/// sides, from bounds that hold for any pivoting: `σ_{r+1} ≤ ‖R₂₂‖_F`,
/// `σ_r ≥ σ_min(R₁₁) ≥ 1/‖R₁₁⁻¹‖_F` and `|R₀₀| ≤ σ_max ≤ ‖A‖_F`. It is then the
/// SVD's decision, and `None` (the SVD) otherwise. The bases it returns span the SVD's
/// subspaces; on the paper example's `[G; Jᵀ]` it takes 3.6 µs to the SVD's 4.9 µs
/// (docs/benchmarks.md, "Which SVD").
fn decompose_cod(a: &Matrix, threshold: RankThreshold) -> Option<Decomposition> {
    let (rows, cols) = (a.nrows(), a.ncols());
    let wide = rows < cols;
    let (len, k) = if wide { (cols, rows) } else { (rows, cols) };
    let mut w = longer_side(a);
    let fro = dot(&w, &w).sqrt();
    let mut perm: Vec<usize> = (0..k).collect();
    let mut norms: Vec<f64> = w.chunks_exact(len).map(|c| dot(c, c)).collect();
    let (mut vhead, mut tau) = (vec![0.0; k], vec![0.0; k]);
    // The threshold below which the remainder is dropped, once |R₀₀| is known.
    let mut drop_below = 0.0;
    let mut r = 0;
    while r < k {
        // Pivot: the remaining column of largest norm, recomputed exactly (k is small,
        // and downdated norms lose accuracy exactly where the rank is decided).
        for (c, n) in norms.iter_mut().enumerate().skip(r) {
            let col = &w[c * len + r..(c + 1) * len];
            *n = dot(col, col);
        }
        let rest: f64 = norms[r..].iter().sum();
        if r > 0 && rest.sqrt() <= drop_below {
            break;
        }
        let p = (r..k).fold(r, |b, c| if norms[c] > norms[b] { c } else { b });
        if p != r {
            let (lo, hi) = w.split_at_mut(p * len);
            lo[r * len..(r + 1) * len].swap_with_slice(&mut hi[..len]);
            perm.swap(r, p);
            norms.swap(r, p);
        }
        householder_step(&mut w, len, k, r, &mut vhead, &mut tau);
        if r == 0 {
            let r00 = w[0].abs();
            drop_below = match threshold {
                RankThreshold::Relative(t) => t * r00,
                RankThreshold::Absolute(t) => t,
            } / COD_MARGIN;
        }
        r += 1;
    }
    if r == 0 || r == k {
        // Zero, or of full rank but too ill-conditioned for the QR path: the SVD.
        return None;
    }
    // σ_r ≥ 1/‖R₁₁⁻¹‖_F must clear the threshold's upper bound.
    let rr = |i: usize, j: usize| w[j * len + i];
    let rinv = upper_inverse(rr, r);
    let sigma_r = 1.0 / dot(&rinv, &rinv).sqrt();
    let above = match threshold {
        RankThreshold::Relative(t) => t * fro,
        RankThreshold::Absolute(t) => t,
    } * COD_MARGIN;
    if sigma_r.is_nan() || sigma_r <= above {
        return None;
    }
    let q = explicit_q(&w, len, r, &vhead, &tau);
    // [R₁₁ R₁₂]ᵀ, k × r column-major (column i is row i of R), and its QR.
    let mut t = vec![0.0; k * r];
    for (i, col) in t.chunks_exact_mut(k).enumerate() {
        for (j, x) in col.iter_mut().enumerate().skip(i) {
            *x = rr(i, j);
        }
    }
    let (mut zhead, mut ztau) = (vec![0.0; r], vec![0.0; r]);
    householder(&mut t, k, r, &mut zhead, &mut ztau);
    let z = explicit_q(&t, k, r, &zhead, &ztau);
    // L (r × r, upper) is the R of that QR; W = P Z, row perm[i] of W is row i of Z.
    let l = |i: usize, j: usize| t[j * k + i];
    let wm = |row: usize, col: usize| z[col * k + row];
    let mut pinv = vec![0; k];
    for (i, &p) in perm.iter().enumerate() {
        pinv[p] = i;
    }
    let w_of = |orig: usize, col: usize| wm(pinv[orig], col);
    let q_of = |i: usize, col: usize| q[col * len + i];
    Some(if wide {
        // Aᵀ = Q₁ Lᵀ W₁ᵀ: A = W₁ L Q₁ᵀ, so A x = b ⇔ Q₁ᵀ x = L⁻¹ W₁ᵀ b.
        let mut tr = Matrix::from_fn(r, rows, |i, j| w_of(j, i));
        solve_triangular(&mut tr, l, true);
        Decomposition {
            row_basis: Matrix::from_fn(cols, r, q_of),
            row_transform: tr,
            null_basis: Matrix::from_fn(cols, cols - r, |i, j| q_of(i, r + j)),
            left_null: Matrix::from_fn(rows, rows - r, |i, j| w_of(i, r + j)),
        }
    } else {
        // A = Q₁ Lᵀ W₁ᵀ: A x = b ⇔ W₁ᵀ x = L⁻ᵀ Q₁ᵀ b (b in the range).
        let mut tr = Matrix::from_fn(r, rows, |i, j| q_of(j, i));
        solve_triangular(&mut tr, |i, j| l(j, i), false);
        Decomposition {
            row_basis: Matrix::from_fn(cols, r, w_of),
            row_transform: tr,
            null_basis: Matrix::from_fn(cols, cols - r, |i, j| w_of(i, r + j)),
            left_null: Matrix::from_fn(rows, rows - r, |i, j| q_of(i, r + j)),
        }
    })
}

/// The decomposition the model needs, with the rank decided by `threshold`: by QR
/// when A is clearly of full rank, by a complete orthogonal decomposition when its
/// rank is clearly below full, else by the SVD.
pub fn decompose(a: &Matrix, threshold: RankThreshold) -> Result<Decomposition, SvdError> {
    let (rows, cols) = (a.nrows(), a.ncols());
    let big = finite_max_abs(a.as_slice()).ok_or(SvdError { rows, cols })?;
    if let Some((scaled, (h1, h2), threshold)) = power_of_two_scaled(a, big, threshold) {
        // (s A)⁺ = A⁺ / s, and the bases are A's: only the transform scales back.
        let mut d = decompose_in_range(&scaled, threshold)?;
        d.row_transform
            .as_mut_slice()
            .iter_mut()
            .for_each(|x| *x = *x * h1 * h2);
        return Ok(d);
    }
    decompose_in_range(a, threshold)
}

/// Entries are safe to square and sum within this range of magnitudes.
const SAFE_SCALE: (f64, f64) = (1e-100, 1e100);

/// `s A` with s = h1 h2 a power of two that brings A's largest entry (`big`) to about
/// 1, with the threshold scaled alike, when that entry is outside [`SAFE_SCALE`] (where the
/// decompositions' squared norms would underflow or overflow); `None` otherwise, so
/// that the usual case runs unchanged. Scaling by a power of two is exact, and so is
/// every rank decision: the factors are those of A.
fn power_of_two_scaled(
    a: &Matrix,
    big: f64,
    threshold: RankThreshold,
) -> Option<(Matrix, (f64, f64), RankThreshold)> {
    if big == 0.0 || (SAFE_SCALE.0..=SAFE_SCALE.1).contains(&big) {
        return None;
    }
    // |e| ≤ 1074: 2^−e may not be a normal number, its two halves are.
    let e = big.log2().round() as i32;
    let (h1, h2) = (2f64.powi(-(e / 2)), 2f64.powi(-(e - e / 2)));
    let mut scaled = a.clone();
    scaled
        .as_mut_slice()
        .iter_mut()
        .for_each(|x| *x = *x * h1 * h2);
    let threshold = match threshold {
        RankThreshold::Relative(t) => RankThreshold::Relative(t),
        RankThreshold::Absolute(t) => RankThreshold::Absolute(t * h1 * h2),
    };
    Some((scaled, (h1, h2), threshold))
}

/// [`decompose`] of a finite A whose squares stay in range.
fn decompose_in_range(a: &Matrix, threshold: RankThreshold) -> Result<Decomposition, SvdError> {
    let (rows, cols) = (a.nrows(), a.ncols());
    if rows > 0 && cols > 0 {
        if let Some(d) = decompose_qr(a, threshold).or_else(|| decompose_cod(a, threshold)) {
            return Ok(d);
        }
    }
    let d = svd(a)?;
    let r = match threshold {
        RankThreshold::Relative(t) => d.rank(t),
        RankThreshold::Absolute(t) => d.s.iter().take_while(|&&s| s > t).count(),
    };
    Ok(Decomposition {
        row_basis: Matrix::from_fn(cols, r, |i, j| d.v[(i, j)]),
        row_transform: Matrix::from_fn(r, rows, |i, j| d.u[(j, i)] / d.s[i]),
        null_basis: Matrix::from_fn(cols, cols - r, |i, j| d.v[(i, r + j)]),
        left_null: Matrix::from_fn(rows, rows - r, |i, j| d.u[(i, r + j)]),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(a: &Matrix) {
        let d = svd(a).unwrap();
        let (r, c) = (a.nrows(), a.ncols());
        let eps = 1e-13 * a.max_abs().max(1.0);
        // Orthogonal factors.
        for (q, n) in [(&d.u, r), (&d.v, c)] {
            let qtq = q.transpose().matmul(q);
            for i in 0..n {
                for j in 0..n {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((qtq[(i, j)] - want).abs() < 1e-13, "QᵀQ {i} {j}");
                }
            }
        }
        // A = U Σ Vᵀ.
        let mut sig = Matrix::zeros(r, c);
        for (i, &s) in d.s.iter().enumerate() {
            sig[(i, i)] = s;
        }
        let back = d.u.matmul(&sig).matmul(&d.v.transpose());
        for i in 0..r {
            for j in 0..c {
                assert!((back[(i, j)] - a[(i, j)]).abs() < eps, "{i} {j}");
            }
        }
        assert!(d.s.windows(2).all(|p| p[0] >= p[1]));
    }

    #[test]
    fn svd_reconstructs_and_pinv_is_a_generalised_inverse() {
        let a = Matrix::from_rows(
            &[
                vec![1.0, 2.0, 0.0],
                vec![0.0, 1.0, 1.0],
                vec![1.0, 3.0, 1.0], // row 0 + row 1: rank 2
                vec![2.0, 0.0, -1.0],
            ],
            3,
        );
        check(&a);
        check(&a.transpose());
        let d = svd(&a).unwrap();
        assert_eq!(d.rank(1e-9), 3);
        let p = d.pseudo_inverse(1e-9);
        let apa = a.matmul(&p).matmul(&a);
        for (x, y) in apa.as_slice().iter().zip(a.as_slice()) {
            assert!((x - y).abs() < 1e-13, "{x} vs {y}");
        }
    }

    #[test]
    fn rank_deficient_wide_and_tall_matrices() {
        // Rank 2 in 5 × 9 and its transpose, with an exact zero column.
        let a = Matrix::from_fn(5, 9, |i, j| {
            if j == 4 {
                0.0
            } else {
                (i as f64 + 1.0) * (j as f64 - 3.0) + ((i * j) % 3) as f64 * (i as f64 - 2.0)
            }
        });
        check(&a);
        check(&a.transpose());
        let d = svd(&a).unwrap();
        assert_eq!(d.rank(1e-9), 2);
        // The trailing columns of V span the null space.
        for k in d.rank(1e-9)..9 {
            let v: Vec<f64> = (0..9).map(|i| d.v[(i, k)]).collect();
            let av = a.mul_vec(&v);
            assert!(av.iter().all(|x| x.abs() < 1e-12), "{av:?}");
        }
    }

    /// The QR fast path and the SVD agree: same pseudo-inverse, orthonormal bases of
    /// the right dimensions, `A · null = 0`, `left_nullᵀ · A = 0`.
    #[test]
    fn qr_and_svd_decompositions_agree() {
        for (r, c) in [(10, 8), (5, 9), (7, 7), (26, 18), (6, 20)] {
            let a = Matrix::from_fn(r, c, |i, j| {
                ((i * 7 + j * 3) % 11) as f64 - 5.0 + 0.1 * (i as f64) * (j as f64).sin()
            });
            let fast = decompose(&a, RankThreshold::Relative(1e-9)).unwrap();
            let slow = {
                let d = svd(&a).unwrap();
                d.pseudo_inverse(1e-9)
            };
            let p = fast.pseudo_inverse();
            for (x, y) in p.as_slice().iter().zip(slow.as_slice()) {
                assert!(
                    (x - y).abs() < 1e-10 * (1.0 + y.abs()),
                    "{r}x{c}: {x} vs {y}"
                );
            }
            let rank = fast.rank();
            assert_eq!(fast.null_basis.ncols(), c - rank);
            assert_eq!(fast.left_null.ncols(), r - rank);
            let an = a.matmul(&fast.null_basis);
            assert!(an.as_slice().iter().all(|x| x.abs() < 1e-12));
            let la = fast.left_null.transpose().matmul(&a);
            assert!(la.as_slice().iter().all(|x| x.abs() < 1e-12));
        }
    }

    /// At scales whose squares under- or overflow (2^±900, about 1e±271), the
    /// decomposition, the rank and an orthonormal basis are those of the matrix at
    /// scale 1, bit for bit, with the transform scaled back: full rank (QR), rank
    /// deficient (the complete orthogonal decomposition), and near the threshold (the
    /// SVD), under both kinds of threshold.
    #[test]
    fn decompositions_are_exact_at_scales_whose_squares_overflow() {
        let mut next = uniform(11);
        for (rows, cols, r, gap) in [(15, 9, 9, 1.0), (10, 8, 6, 1.0), (6, 9, 5, 1e-9)] {
            // Rank r, the last singular direction at `gap`, largest entry exactly 1.
            let b = Matrix::from_fn(rows, r, |_, _| next());
            let c = Matrix::from_fn(r, cols, |i, _| next() * if i + 1 == r { gap } else { 1.0 });
            let mut a = b.matmul(&c);
            let big = a.max_abs();
            a.as_mut_slice().iter_mut().for_each(|v| *v /= big);
            for thr in [RankThreshold::Relative(1e-9), RankThreshold::Absolute(1e-9)] {
                let base = decompose(&a, thr).unwrap();
                for e in [-900, 900] {
                    let s = 2f64.powi(e);
                    let scaled = Matrix::from_fn(rows, cols, |i, j| a[(i, j)] * s);
                    let thr_s = match thr {
                        RankThreshold::Relative(t) => RankThreshold::Relative(t),
                        RankThreshold::Absolute(t) => RankThreshold::Absolute(t * s),
                    };
                    let d = decompose(&scaled, thr_s).unwrap();
                    let at = format!("{rows}×{cols} {thr:?} 2^{e}");
                    assert_eq!(rank(&scaled, thr_s).unwrap(), base.rank(), "{at}");
                    assert_eq!(d.row_basis.as_slice(), base.row_basis.as_slice(), "{at}");
                    assert_eq!(d.null_basis.as_slice(), base.null_basis.as_slice(), "{at}");
                    assert_eq!(d.left_null.as_slice(), base.left_null.as_slice(), "{at}");
                    for (x, y) in d
                        .row_transform
                        .as_slice()
                        .iter()
                        .zip(base.row_transform.as_slice())
                    {
                        assert_eq!(*x, y / s, "{at}");
                    }
                    let q = orthonormal_columns(&Matrix::from_fn(rows.max(cols), 3, |i, j| {
                        scaled[(i % rows, (i + j) % cols)]
                    }));
                    let q0 = orthonormal_columns(&Matrix::from_fn(rows.max(cols), 3, |i, j| {
                        a[(i % rows, (i + j) % cols)]
                    }));
                    assert_eq!(
                        q.map(|q| q.as_slice().to_vec()),
                        q0.map(|q| q.as_slice().to_vec())
                    );
                }
            }
        }
    }

    /// A basis of `diag(g) N` with g spread over twelve decades: orthonormal to
    /// rounding, and each row y_i = N_i R (R = Nᵀ y) to rounding relative to its own
    /// size, the small ones too. An explicit Householder Q holds only
    /// `‖y_i − Q_i R‖ ≤ ε ‖y‖`, which at a row 1e-12 of the largest is all of it.
    #[test]
    fn orthonormal_columns_keep_the_digits_of_small_rows() {
        let mut next = uniform(5);
        for (len, k) in [(9, 3), (16, 5), (20, 1), (12, 6)] {
            // k rows of size 1 (R clearly of full rank), the rest down to 1e-12, the
            // smallest first (Householder's Q keeps the digits of rows that come after
            // the large ones, Cox and Higham 1998, not of those before).
            let g: Vec<f64> = (0..len)
                .map(|i: usize| {
                    10f64.powi(-(((len - 1 - i).saturating_sub(k) * 12 / (len - k)) as i32))
                })
                .collect();
            let y = Matrix::from_fn(len, k, |i, _| g[i] * next());
            let q = orthonormal_columns(&y).unwrap();
            assert_orthonormal(&q);
            let r = q.transpose().matmul(&y);
            for i in 0..len {
                let back: Vec<f64> = (0..k)
                    .map(|j| (0..k).map(|l| q[(i, l)] * r[(l, j)]).sum())
                    .collect();
                let err = crate::matrix::norm2(
                    &back
                        .iter()
                        .zip(y.row(i))
                        .map(|(a, b)| a - b)
                        .collect::<Vec<_>>(),
                );
                let size = crate::matrix::norm2(y.row(i));
                assert!(
                    err <= 1e3 * f64::EPSILON * size,
                    "{len}×{k} row {i}: {err:e} of {size:e}"
                );
            }
        }
    }

    /// Fewer large rows than columns: one row 1e8, one 1e-8, the rest of size 1, so
    /// that every column of y is mostly its first row and y's columns are 1e-8 from
    /// parallel (the torques' scales of a joint with moment arms 1e9 times the
    /// others' beside one the equalities pin, `fuzz_answers.py` seed 89215). R of y's
    /// own QR is then too ill conditioned for a basis (there was none); the graded
    /// range is not: orthonormal, and each row's digits kept, as above.
    #[test]
    fn orthonormal_columns_of_nearly_parallel_graded_columns() {
        let mut next = uniform(11);
        for (len, k) in [(9, 3), (12, 5), (6, 2)] {
            let g = |i: usize| match i {
                0 => 1e8,
                1 => 1e-8,
                _ => 1.0,
            };
            let y = Matrix::from_fn(len, k, |i, _| g(i) * next());
            let q = orthonormal_columns(&y).expect("a basis");
            assert_orthonormal(&q);
            let r = q.transpose().matmul(&y);
            for i in 0..len {
                let err = (0..k)
                    .map(|j| (0..k).map(|l| q[(i, l)] * r[(l, j)]).sum::<f64>() - y[(i, j)])
                    .fold(0.0f64, |a, v| a.max(v.abs()));
                let size = crate::matrix::norm2(y.row(i));
                assert!(
                    err <= 1e3 * f64::EPSILON * size,
                    "{len}×{k} row {i}: {err:e} of {size:e}"
                );
            }
        }
    }

    /// Euclidean norms whose squares under- or overflow, and NaN.
    #[test]
    fn norms_at_the_ends_of_the_range() {
        use crate::matrix::norm2;
        for s in [1e-300, 1e-200, 1e-160, 1.0, 1e160, 1e300] {
            let n = norm2(&[3.0 * s, 4.0 * s, 0.0]);
            assert!(
                (n - 5.0 * s).abs() <= 4.0 * f64::EPSILON * 5.0 * s,
                "{s}: {n}"
            );
        }
        assert_eq!(norm2(&[0.0, 0.0]), 0.0);
        assert!(norm2(&[1e300, f64::NAN]).is_nan());
        assert!(norm2(&[1e-300, f64::NAN]).is_nan());
    }

    /// Uniform numbers in [−1, 1) from a linear congruential generator.
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    /// Orthonormal columns, to rounding.
    fn assert_orthonormal(q: &Matrix) {
        let qtq = q.transpose().matmul(q);
        for i in 0..q.ncols() {
            for j in 0..q.ncols() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((qtq[(i, j)] - want).abs() < 1e-14, "QᵀQ {i} {j}");
            }
        }
    }

    /// The complete orthogonal decomposition of rank-deficient matrices, tall, wide and
    /// square, with zero and repeated columns: the SVD's rank and pseudo-inverse,
    /// orthonormal bases of the four subspaces, and `A x = b ⇔ row_basisᵀ x =
    /// row_transform b` on the range.
    #[test]
    fn cod_matches_the_svd_on_rank_deficient_matrices() {
        let mut next = uniform(7);
        for (rows, cols, rank) in [
            (10, 12, 9),
            (12, 10, 7),
            (26, 18, 15),
            (8, 20, 5),
            (9, 9, 4),
            (6, 6, 1),
        ] {
            // A = B C with B rows × rank and C rank × cols, scaled over four decades.
            let b = Matrix::from_fn(rows, rank, |_, _| next());
            let c = Matrix::from_fn(rank, cols, |i, _| next() * 10f64.powi(i as i32 % 4));
            let mut a = b.matmul(&c);
            for i in 0..rows {
                a[(i, cols / 2)] = 0.0;
            }
            let thr = RankThreshold::Relative(1e-9);
            let d = decompose_cod(&a, thr).expect("a clear rank decision");
            let s = svd(&a).unwrap();
            assert_eq!(d.rank(), s.rank(1e-9), "{rows}×{cols}");
            assert_eq!(d.rank(), rank);
            let (p, q) = (d.pseudo_inverse(), s.pseudo_inverse(1e-9));
            let scale = q.max_abs();
            for (x, y) in p.as_slice().iter().zip(q.as_slice()) {
                assert!((x - y).abs() < 1e-11 * scale, "{rows}×{cols}: {x} vs {y}");
            }
            for basis in [&d.row_basis, &d.null_basis, &d.left_null] {
                assert_orthonormal(basis);
            }
            assert_eq!(d.null_basis.ncols(), cols - rank);
            assert_eq!(d.left_null.ncols(), rows - rank);
            let tol = 1e-13 * a.max_abs() * (rows.max(cols) as f64);
            let an = a.matmul(&d.null_basis);
            assert!(an.as_slice().iter().all(|x| x.abs() < tol), "A N");
            let la = d.left_null.transpose().matmul(&a);
            assert!(la.as_slice().iter().all(|x| x.abs() < tol), "U⊥ᵀ A");
            // x = A⁺ b for b = A x0: row_basisᵀ x = row_transform b.
            let x0: Vec<f64> = (0..cols).map(|_| next()).collect();
            let bv = a.mul_vec(&x0);
            let x = p.mul_vec(&bv);
            let lhs = d.row_basis.transpose().mul_vec(&x);
            let rhs = d.row_transform.mul_vec(&bv);
            for (l, r) in lhs.iter().zip(&rhs) {
                assert!((l - r).abs() < 1e-11 * (1.0 + r.abs()), "{l} vs {r}");
            }
            let back = a.mul_vec(&x);
            for (u, v) in back.iter().zip(&bv) {
                assert!((u - v).abs() < 1e-11 * (1.0 + v.abs()), "A A⁺ b");
            }
        }
    }

    /// A loose relative tolerance is the SVD's decision too: σ_min/σ_max = 1e-5 is full
    /// rank at 1e-9 (by QR) but not at 1e-4, where the QR path used to answer full rank.
    #[test]
    fn full_rank_by_qr_only_when_clear_of_the_tolerance() {
        let a = Matrix::from_fn(7, 4, |i, j| {
            let base = (i as f64 - 3.0).powi(j as i32);
            if j == 3 {
                // Column 3 = column 1 plus a 1e-5 part off the others' span.
                (i as f64 - 3.0) + 1e-5 * (i as f64 - 3.0).powi(3)
            } else {
                base
            }
        });
        let s = svd(&a).unwrap();
        for tol in [1e-9, 1e-4, 1e-3] {
            let thr = RankThreshold::Relative(tol);
            let want = s.rank(tol);
            assert_eq!(decompose(&a, thr).unwrap().rank(), want, "{tol}");
            assert_eq!(rank(&a, thr).unwrap(), want, "{tol}");
        }
        assert_eq!(s.rank(1e-9), 4);
        assert_eq!(s.rank(1e-4), 3);
    }

    /// A rank decision near the threshold goes to the SVD; a clear one does not.
    #[test]
    fn cod_declines_a_rank_decision_near_the_threshold() {
        // Rank 3 in 6 × 4: two components of size 1 and one of size 1e-9.
        let u = |i: usize, l: usize| (i as f64 - 2.5).powi(l as i32);
        let v = |j: usize, l: usize| (j as f64 + 1.0).powi(l as i32);
        let size = [1.0, 1.0, 1e-9];
        let a = Matrix::from_fn(6, 4, |i, j| {
            (0..3).map(|l| size[l] * u(i, l) * v(j, l)).sum()
        });
        assert_eq!(svd(&a).unwrap().rank(2e-13), 3);
        for (tol, taken, rank) in [(1e-9, false, 0), (1e-5, true, 2), (2e-13, true, 3)] {
            let d = decompose_cod(&a, RankThreshold::Relative(tol));
            assert_eq!(d.is_some(), taken, "tolerance {tol}");
            if let Some(d) = d {
                assert_eq!(d.rank(), rank);
                assert_eq!(svd(&a).unwrap().rank(tol), rank);
            }
        }
    }

    #[test]
    fn non_finite_entries_are_an_error() {
        let a = Matrix::from_rows(&[vec![1.0, f64::NAN]], 2);
        assert!(svd(&a).is_err());
    }
}
