//! Dense Cholesky kernels for the small systems of the exact-cone solvers, on row
//! slices (no bounds checks in the inner loops) with the core's four-lane dot product.

pub(crate) use grasp_core::matrix::dot4;

/// In-place Cholesky `A = L Lᵀ` (lower triangle of the row-major n × n `a`); false if
/// not positive definite.
pub(crate) fn cholesky(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let row_j = &mut a[j * n..j * n + n];
        let d = row_j[j] - dot4(&row_j[..j], &row_j[..j]);
        if d.is_nan() || d <= 0.0 || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        row_j[j] = d;
        for i in j + 1..n {
            let (lo, hi) = a.split_at_mut(i * n);
            let row_j = &lo[j * n..j * n + j];
            let row_i = &mut hi[..n];
            row_i[j] = (row_i[j] - dot4(&row_i[..j], row_j)) / d;
        }
    }
    true
}

/// Solves `L x = b` in place.
pub(crate) fn forward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let row = &l[i * n..i * n + i + 1];
        b[i] = (b[i] - dot4(&row[..i], &b[..i])) / row[i];
    }
}

/// Solves `Lᵀ x = b` in place (row-oriented: each solved x_i is taken out of the rest).
pub(crate) fn backward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in (0..n).rev() {
        let row = &l[i * n..i * n + i + 1];
        let x = b[i] / row[i];
        b[i] = x;
        for (bk, lk) in b[..i].iter_mut().zip(&row[..i]) {
            *bk -= lk * x;
        }
    }
}
