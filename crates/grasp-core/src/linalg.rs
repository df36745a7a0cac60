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

use crate::matrix::Matrix;

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

/// What the model needs of a matrix A (rows × cols) of rank r, from either a QR
/// factorisation (the fast path, when A is clearly of full rank) or the SVD:
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

/// Householder QR of `k` columns of length `len ≥ k`, stored column-major in `w`
/// (column c at `w[c·len..]`). On return the upper triangle of the first k rows holds
/// R, and reflector c is `v = w[c·len + c..(c+1)·len]` below the diagonal with
/// `v[0] = vhead[c]`, applied as `I − tau[c] v vᵀ` (tau 0: no reflection).
fn householder(w: &mut [f64], len: usize, k: usize, vhead: &mut [f64], tau: &mut [f64]) {
    for c in 0..k {
        let (col, later) = w[c * len..].split_at_mut(len);
        let x = &mut col[c..];
        let norm = dot(x, x).sqrt();
        let alpha = if x[0] >= 0.0 { -norm } else { norm };
        let head = x[0] - alpha;
        // ‖v‖² with v = x − alpha e₁.
        let vn = head * head + dot(&x[1..], &x[1..]);
        if vn > 0.0 {
            let t = 2.0 / vn;
            for other in later.chunks_exact_mut(len) {
                let y = &mut other[c..];
                let f = t * (head * y[0] + dot(&x[1..], &y[1..]));
                y[0] -= f * head;
                for (yi, vi) in y[1..].iter_mut().zip(&x[1..]) {
                    *yi -= f * vi;
                }
            }
            tau[c] = t;
            x[0] = alpha;
        } else {
            tau[c] = 0.0;
        }
        vhead[c] = head;
    }
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
        let (h, t) = (vhead[c], tau[c]);
        for e in c..len {
            let y = &mut q[e * len + c..(e + 1) * len];
            let f = t * (h * y[0] + dot(v, &y[1..]));
            y[0] -= f * h;
            for (yi, vi) in y[1..].iter_mut().zip(v) {
                *yi -= f * vi;
            }
        }
    }
    q
}

/// The fast path: Householder QR of the longer side when A has full rank by a
/// margin (`‖R‖_F ‖R⁻¹‖_F < 1e6`, so `σ_min/σ_max > 1e-6` and no rank decision near
/// any threshold in use is at stake); `None` otherwise. Flat buffers, one allocation
/// each: the model of every grasp passes here, so a batch of grasps is mostly this.
fn decompose_qr(a: &Matrix, threshold: RankThreshold) -> Option<Decomposition> {
    let (rows, cols) = (a.nrows(), a.ncols());
    let wide = rows < cols;
    let (len, k) = if wide { (cols, rows) } else { (rows, cols) };
    // Column c of the longer side: a column of A, or a row of A when wide.
    let mut w = vec![0.0; len * k];
    for c in 0..k {
        for i in 0..len {
            w[c * len + i] = if wide { a[(c, i)] } else { a[(i, c)] };
        }
    }
    let (mut vhead, mut tau) = (vec![0.0; k], vec![0.0; k]);
    householder(&mut w, len, k, &mut vhead, &mut tau);
    let r = |i: usize, j: usize| w[j * len + i];
    // R⁻¹ (row-major, k × k) by back substitution, column by column.
    let mut rinv = vec![0.0; k * k];
    for j in 0..k {
        for i in (0..=j).rev() {
            let mut s = if i == j { 1.0 } else { 0.0 };
            for l in i + 1..=j {
                s -= r(i, l) * rinv[l * k + j];
            }
            if r(i, i) == 0.0 {
                return None;
            }
            rinv[i * k + j] = s / r(i, i);
        }
    }
    let nr = (0..k)
        .map(|j| (0..=j).map(|i| r(i, j) * r(i, j)).sum::<f64>())
        .sum::<f64>()
        .sqrt();
    let ni = dot(&rinv, &rinv).sqrt();
    if (nr * ni).is_nan() || nr * ni >= 1e6 {
        return None;
    }
    if let RankThreshold::Absolute(t) = threshold {
        // σ_min ≥ 1/‖R⁻¹‖_F must clear the threshold by the same margin.
        if 1.0 / ni <= 1e6 * t {
            return None;
        }
    }
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

/// The decomposition the model needs, with the rank decided by `threshold`: by QR
/// when A is clearly of full rank, else by the SVD.
pub fn decompose(a: &Matrix, threshold: RankThreshold) -> Result<Decomposition, SvdError> {
    let (rows, cols) = (a.nrows(), a.ncols());
    if a.as_slice().iter().any(|x| !x.is_finite()) {
        return Err(SvdError { rows, cols });
    }
    if rows > 0 && cols > 0 {
        if let Some(d) = decompose_qr(a, threshold) {
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

    #[test]
    fn non_finite_entries_are_an_error() {
        let a = Matrix::from_rows(&[vec![1.0, f64::NAN]], 2);
        assert!(svd(&a).is_err());
    }
}
