//! Dense Cholesky kernels for the small systems of the exact-cone solvers, on row
//! slices (no bounds checks in the inner loops) with the core's four-lane dot product.

pub(crate) use grasp_core::matrix::dot4;

/// In-place Cholesky `A = L Lᵀ` (lower triangle of the row-major n × n `a`), with
/// each diagonal entry stored as its reciprocal `1/L_jj`: the triangular solves then
/// multiply where they would divide (a division's latency, on every row of a solve
/// whose rows wait on each other). False if not positive definite.
pub(crate) fn cholesky(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let row_j = &mut a[j * n..j * n + n];
        let d = row_j[j] - dot4(&row_j[..j], &row_j[..j]);
        if d.is_nan() || d <= 0.0 || !d.is_finite() {
            return false;
        }
        let inv = 1.0 / d.sqrt();
        row_j[j] = inv;
        for i in j + 1..n {
            let (lo, hi) = a.split_at_mut(i * n);
            let row_j = &lo[j * n..j * n + j];
            let row_i = &mut hi[..n];
            row_i[j] = (row_i[j] - dot4(&row_i[..j], row_j)) * inv;
        }
    }
    true
}

/// Solves `L x = b` in place (L from [`cholesky`]).
pub(crate) fn forward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let row = &l[i * n..i * n + i + 1];
        b[i] = (b[i] - dot4(&row[..i], &b[..i])) * row[i];
    }
}

/// Solves `Lᵀ x = b` in place (row-oriented: each solved x_i is taken out of the rest).
pub(crate) fn backward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in (0..n).rev() {
        let row = &l[i * n..i * n + i + 1];
        let x = b[i] * row[i];
        b[i] = x;
        for (bk, lk) in b[..i].iter_mut().zip(&row[..i]) {
            *bk -= lk * x;
        }
    }
}

/// The Schur complement of `rows` constraint rows `c` (row-major, each of length n)
/// against the Cholesky factor `l` of an n × n matrix M: `Y = L⁻¹ Cᵀ` into `y_cols`
/// (column r at `r·n..`), then `S = YᵀY = C M⁻¹ Cᵀ` factored in place in
/// `s[..rows²]`. False if S is not positive definite (dependent rows).
pub(crate) fn schur(
    l: &[f64],
    n: usize,
    c: &[f64],
    rows: usize,
    y_cols: &mut [f64],
    s: &mut [f64],
) -> bool {
    for r in 0..rows {
        let col = &mut y_cols[r * n..r * n + n];
        col.copy_from_slice(&c[r * n..r * n + n]);
        forward(l, n, col);
    }
    for r in 0..rows {
        for q in 0..=r {
            let v = dot4(&y_cols[r * n..r * n + n], &y_cols[q * n..q * n + n]);
            s[r * rows + q] = v;
            s[q * rows + r] = v;
        }
    }
    rows == 0 || cholesky(&mut s[..rows * rows], rows)
}

/// The factor `L = Rᵀ` of `AᵀA` from a Householder QR of the row-major `rows × n`
/// matrix `a` (rows ≥ n; overwritten), in [`cholesky`]'s layout in `l` (row-major
/// n × n, lower triangle, each diagonal entry stored as its reciprocal): the factor
/// of a product that is never formed. Each row of R is signed so that its diagonal
/// is positive. False if a column is (numerically) dependent on those before it.
///
/// Each reflector is applied a row at a time (its products with every later column
/// summed along the rows, then each row updated), so that both passes run along
/// contiguous rows and vectorise; each entry sees the same operations in the same
/// order as column by column, which strode down the matrix and was 62 % of the
/// instructions of a large grasp's exact solve (`scripts/large_grasps.py` seed 392: 22
/// contacts, 73 joints), 3.6 times what it takes now.
///
/// The first `top` rows (at most n) are diagonal, as `[√P; W⁻¹G]`'s are: row i < top
/// has no entry but column i, and reflectors before the i-th leave it so (their
/// vectors are zero there), so reflector j skips rows j + 1 to top − 1.
pub(crate) fn qr_factor(a: &mut [f64], rows: usize, n: usize, top: usize, l: &mut [f64]) -> bool {
    for j in 0..n {
        // The rows reflector j moves: j, then `rest..`.
        let rest = (j + 1).max(top);
        let below = |i: usize| a[i * n + j] * a[i * n + j];
        let norm2: f64 = std::iter::once(j).chain(rest..rows).map(below).sum();
        let norm = norm2.sqrt();
        if norm.is_nan() || norm == 0.0 || !norm.is_finite() {
            return false;
        }
        // The reflector I − 2vvᵀ/vᵀv with v = x − αe_j, α of the sign opposite to x_j
        // (no cancellation), stored in column j while the others are reflected.
        let x0 = a[j * n + j];
        let alpha = if x0 >= 0.0 { -norm } else { norm };
        let v0 = x0 - alpha;
        let vtv = norm2 - x0 * x0 + v0 * v0;
        a[j * n + j] = v0;
        // f_k = 2 vᵀa_k / vᵀv for the later columns, in `l`'s first row (written last).
        let f = &mut l[j + 1..n];
        let (pivot, others) = a[j * n..rows * n].split_at_mut(n);
        let others = &mut others[(rest - j - 1) * n..];
        // (-0.0 + v x: the first term as a sum's.)
        for (f, x) in f.iter_mut().zip(&pivot[j + 1..]) {
            *f = -0.0 + v0 * x;
        }
        for row in others.chunks_exact(n) {
            let v = row[j];
            for (f, x) in f.iter_mut().zip(&row[j + 1..]) {
                *f += v * x;
            }
        }
        f.iter_mut().for_each(|f| *f = 2.0 * *f / vtv);
        for (x, f) in pivot[j + 1..].iter_mut().zip(&*f) {
            *x -= f * v0;
        }
        for row in others.chunks_exact_mut(n) {
            let (head, tail) = row.split_at_mut(j + 1);
            let v = head[j];
            for (x, f) in tail.iter_mut().zip(&*f) {
                *x -= f * v;
            }
        }
        a[j * n + j] = alpha;
    }
    for j in 0..n {
        let sign = if a[j * n + j] < 0.0 { -1.0 } else { 1.0 };
        l[j * n + j] = 1.0 / (sign * a[j * n + j]);
        for k in j + 1..n {
            l[k * n + j] = sign * a[j * n + k];
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn solve(l: &[f64], n: usize, b: &[f64]) -> Vec<f64> {
        let mut x = b.to_vec();
        forward(l, n, &mut x);
        backward(l, n, &mut x);
        x
    }

    /// The QR factor of A is the Cholesky factor of the formed AᵀA where that exists,
    /// and solves with `AᵀA = 2I + t² g gᵀ` where rounding has broken the formed one
    /// (t = 1e10: the 2I is lost in entries of 1e20), against Sherman–Morrison, to the
    /// accuracy its condition number allows.
    #[test]
    fn the_qr_factor_is_the_cholesky_factor_of_the_product() {
        let (rows, n) = (7, 4);
        let a: Vec<f64> = (0..rows * n)
            .map(|k| ((k * 37 % 11) as f64 - 5.0) / 3.0 + if k % (n + 1) == 0 { 2.0 } else { 0.0 })
            .collect();
        let mut m = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                m[i * n + j] = (0..rows).map(|r| a[r * n + i] * a[r * n + j]).sum();
            }
        }
        let mut chol = m.clone();
        assert!(cholesky(&mut chol, n));
        let (mut q, mut l) = (a.clone(), vec![0.0; n * n]);
        assert!(qr_factor(&mut q, rows, n, 0, &mut l));
        for i in 0..n {
            for j in 0..=i {
                let (c, r) = (chol[i * n + j], l[i * n + j]);
                assert!(
                    (c - r).abs() <= 1e-13 * (1.0 + c.abs()),
                    "({i}, {j}): {c} {r}"
                );
            }
        }
        let g = [0.6, -0.8, 0.3, 0.1];
        let t = 1e10;
        let mut formed = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                formed[i * n + j] = t * t * g[i] * g[j] + if i == j { 2.0 } else { 0.0 };
            }
        }
        assert!(
            !cholesky(&mut formed, n),
            "the formed matrix kept its factor"
        );
        let mut stack = vec![0.0; (n + 1) * n];
        for j in 0..n {
            stack[j * n + j] = 2f64.sqrt();
            stack[n * n + j] = t * g[j];
        }
        assert!(qr_factor(&mut stack, n + 1, n, n, &mut l));
        let b = [1.0, 2.0, -1.0, 0.5];
        let x = solve(&l, n, &b);
        let (gb, gg): (f64, f64) = (
            g.iter().zip(&b).map(|(g, b)| g * b).sum(),
            g.iter().map(|g| g * g).sum(),
        );
        // Two triangular solves with R, whose condition number is about t‖g‖/√2 (the
        // formed product's is its square): errors up to a few ε κ(R) of the answer.
        let tol = 10.0 * f64::EPSILON * t * gg.sqrt() / 2f64.sqrt();
        for i in 0..n {
            let want = (b[i] - t * t * g[i] * gb / (2.0 + t * t * gg)) / 2.0;
            assert!((x[i] - want).abs() <= tol, "{i}: {} against {want}", x[i]);
        }
    }
}
