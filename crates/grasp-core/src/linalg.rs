//! Decompositions on [`Matrix`], through `faer`.
//!
//! faer was chosen over nalgebra for the SVD. nalgebra's is about 2× faster at grasp
//! sizes, but on some grasp matrices its factors reconstruct A only to ~1e-9, which
//! shows up as `‖G f − w‖∞ ≈ 1e-8` instead of rounding level. faer's full SVD is
//! accurate to rounding and directly gives the complement of range(A) that the
//! consistency equalities need (`cargo bench --bench decomposition`, docs/benchmarks.md).

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
    let fa = faer::Mat::<f64>::from_fn(rows, cols, |i, j| a[(i, j)]);
    let dec = fa.svd().map_err(|_| SvdError { rows, cols })?;
    let (u, v, s) = (dec.U(), dec.V(), dec.S().column_vector());
    Ok(Svd {
        u: Matrix::from_fn(rows, rows, |i, j| u[(i, j)]),
        s: (0..rows.min(cols)).map(|i| s[i]).collect(),
        v: Matrix::from_fn(cols, cols, |i, j| v[(i, j)]),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let d = svd(&a).unwrap();
        assert_eq!(d.rank(1e-9), 3);
        let p = d.pseudo_inverse(1e-9);
        let apa = a.matmul(&p).matmul(&a);
        for (x, y) in apa.as_slice().iter().zip(a.as_slice()) {
            assert!((x - y).abs() < 1e-13, "{x} vs {y}");
        }
    }
}
