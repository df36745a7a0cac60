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
