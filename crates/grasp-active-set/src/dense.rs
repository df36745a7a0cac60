//! Dense Cholesky kernels for the small systems of the exact-cone solvers, on row
//! slices (no bounds checks in the inner loops) with a four-lane dot product: Rust does
//! not reassociate floating-point sums, so the lanes are written out.

/// `Σ a_i b_i` over the shorter length, in four independent lanes.
#[inline]
pub(crate) fn dot4(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut s = [0.0f64; 4];
    let mut ca = a.chunks_exact(4);
    let mut cb = b.chunks_exact(4);
    for (x, y) in (&mut ca).zip(&mut cb) {
        s[0] += x[0] * y[0];
        s[1] += x[1] * y[1];
        s[2] += x[2] * y[2];
        s[3] += x[3] * y[3];
    }
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    (s[0] + s[1]) + (s[2] + s[3]) + tail
}

/// In-place Cholesky `A = L Lᵀ` (lower triangle of the row-major n × n `a`); false if
/// not positive definite.
pub(crate) fn cholesky(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let (lo, hi) = a.split_at_mut(j * n);
        let row_j = &mut hi[..n];
        let d = row_j[j] - dot4(&row_j[..j], &row_j[..j]);
        if d.is_nan() || d <= 0.0 || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        row_j[j] = d;
        let _ = lo;
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
