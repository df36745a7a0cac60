//! A small dense row-major matrix, sized for grasp problems (tens of rows and columns).
//!
//! The solver hot loops work on raw row slices, so the storage is row-major and the
//! type stays minimal; the decompositions are in [`crate::linalg`].

use std::ops::{Index, IndexMut};

/// Dense row-major `f64` matrix.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Matrix {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

impl Matrix {
    /// A `rows × cols` matrix of zeros.
    pub fn zeros(rows: usize, cols: usize) -> Self {
        Self {
            rows,
            cols,
            data: vec![0.0; rows * cols],
        }
    }

    /// The `n × n` identity.
    pub fn identity(n: usize) -> Self {
        Self::from_fn(n, n, |i, j| if i == j { 1.0 } else { 0.0 })
    }

    /// A `rows × cols` matrix from its entries, row by row.
    ///
    /// # Panics
    /// If there are not `rows × cols` entries.
    pub fn from_rows_data(rows: usize, cols: usize, data: Vec<f64>) -> Self {
        assert_eq!(data.len(), rows * cols, "entries of a {rows}×{cols} matrix");
        Self { rows, cols, data }
    }

    /// Builds a matrix entry by entry.
    pub fn from_fn(rows: usize, cols: usize, mut f: impl FnMut(usize, usize) -> f64) -> Self {
        let mut data = Vec::with_capacity(rows * cols);
        for i in 0..rows {
            for j in 0..cols {
                data.push(f(i, j));
            }
        }
        Self { rows, cols, data }
    }

    /// Builds a matrix from equally long rows; `cols` is used when there are no rows.
    ///
    /// # Panics
    /// If the rows differ in length (callers validate user input first).
    pub fn from_rows(rows: &[Vec<f64>], cols: usize) -> Self {
        let cols = rows.first().map_or(cols, Vec::len);
        assert!(rows.iter().all(|r| r.len() == cols), "ragged rows");
        Self {
            rows: rows.len(),
            cols,
            data: rows.concat(),
        }
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.cols
    }

    /// Row `i` as a slice.
    #[inline]
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.cols..(i + 1) * self.cols]
    }

    /// Row `i` as a mutable slice.
    #[inline]
    pub fn row_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.data[i * self.cols..(i + 1) * self.cols]
    }

    /// The rows as owned vectors (for serialisation).
    pub fn to_rows(&self) -> Vec<Vec<f64>> {
        (0..self.rows).map(|i| self.row(i).to_vec()).collect()
    }

    /// `out = self · x`.
    pub fn mul_vec_into(&self, x: &[f64], out: &mut [f64]) {
        debug_assert_eq!(x.len(), self.cols);
        debug_assert_eq!(out.len(), self.rows);
        for (o, r) in out.iter_mut().zip(self.data.chunks_exact(self.cols.max(1))) {
            *o = dot(r, x);
        }
        if self.cols == 0 {
            out.iter_mut().for_each(|o| *o = 0.0);
        }
    }

    /// `self · x` as a new vector.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.rows];
        self.mul_vec_into(x, &mut out);
        out
    }

    /// The product `self · other`.
    pub fn matmul(&self, other: &Matrix) -> Matrix {
        assert_eq!(self.cols, other.rows, "matmul dimension mismatch");
        let (inner, c) = (self.cols, other.cols);
        let mut out = Matrix::zeros(self.rows, c);
        if inner == 0 || c == 0 {
            return out;
        }
        // Blocks of eight output columns accumulate in a local array across the whole
        // inner dimension (each entry summed in k order, zeros of `self` skipped):
        // the small matrices here are otherwise bound by reloading the output row.
        for (arow, orow) in self
            .data
            .chunks_exact(inner)
            .zip(out.data.chunks_exact_mut(c))
        {
            for (j0, block) in (0..c).step_by(8).zip(orow.chunks_mut(8)) {
                let mut acc = [0.0f64; 8];
                for (k, &a) in arow.iter().enumerate() {
                    if a == 0.0 {
                        continue;
                    }
                    let b = &other.data[k * c + j0..];
                    if let Ok(b8) = <&[f64; 8]>::try_from(&b[..block.len().min(8)]) {
                        for l in 0..8 {
                            acc[l] += a * b8[l];
                        }
                    } else {
                        for (x, y) in acc.iter_mut().zip(&b[..block.len()]) {
                            *x += a * y;
                        }
                    }
                }
                block.copy_from_slice(&acc[..block.len()]);
            }
        }
        out
    }

    /// The transpose.
    pub fn transpose(&self) -> Matrix {
        Matrix::from_fn(self.cols, self.rows, |i, j| self[(j, i)])
    }

    /// Columns `start..end` as a new matrix.
    pub fn columns(&self, start: usize, end: usize) -> Matrix {
        Matrix::from_fn(self.rows, end - start, |i, j| self[(i, start + j)])
    }

    /// Stacks `self` on top of `below` (same column count).
    pub fn vstack(&self, below: &Matrix) -> Matrix {
        assert_eq!(self.cols, below.cols, "vstack column mismatch");
        let mut data = self.data.clone();
        data.extend_from_slice(&below.data);
        Matrix {
            rows: self.rows + below.rows,
            cols: self.cols,
            data,
        }
    }

    /// Largest absolute entry (0 for an empty matrix).
    pub fn max_abs(&self) -> f64 {
        self.data.iter().fold(0.0, |m, v| m.max(v.abs()))
    }

    /// The entries, row by row, mutably.
    pub fn as_mut_slice(&mut self) -> &mut [f64] {
        &mut self.data
    }

    /// The entries, row by row.
    pub fn as_slice(&self) -> &[f64] {
        &self.data
    }
}

impl Index<(usize, usize)> for Matrix {
    type Output = f64;
    #[inline]
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        debug_assert!(i < self.rows && j < self.cols);
        &self.data[i * self.cols + j]
    }
}

impl IndexMut<(usize, usize)> for Matrix {
    #[inline]
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut f64 {
        debug_assert!(i < self.rows && j < self.cols);
        &mut self.data[i * self.cols + j]
    }
}

/// Dot product of two equally long slices, in four lanes ([`dot4`]).
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    dot4(a, b)
}

/// `Σ a_i b_i` over the shorter length, in four independent lanes (Rust does not
/// reassociate floating-point sums, so the lanes that let it vectorise are written out).
#[inline]
pub fn dot4(a: &[f64], b: &[f64]) -> f64 {
    sum4(a, b, |x, y| x * y)
}

/// `Σ |a_i b_i|` over the shorter length, in four lanes like [`dot4`]: the size of the
/// terms behind a dot product, for rounding bounds.
#[inline]
pub fn abs_dot4(a: &[f64], b: &[f64]) -> f64 {
    sum4(a, b, |x, y| (x * y).abs())
}

/// `Σ term(a_i, b_i)` in four lanes, then the tail.
#[inline(always)]
fn sum4(a: &[f64], b: &[f64], term: impl Fn(f64, f64) -> f64) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut s = [0.0f64; 4];
    let mut ca = a.chunks_exact(4);
    let mut cb = b.chunks_exact(4);
    for (x, y) in (&mut ca).zip(&mut cb) {
        for l in 0..4 {
            s[l] += term(x[l], y[l]);
        }
    }
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| term(*x, *y))
        .sum();
    (s[0] + s[1]) + (s[2] + s[3]) + tail
}

/// `out += sign · M x` for a column-major M (`out.len()` rows, one column per entry
/// of x), four columns per pass over `out`: at these sizes a pass down columns
/// vectorises where a short dot product per row does not.
#[inline]
pub fn add_columns(out: &mut [f64], cols: &[f64], x: &[f64], sign: f64) {
    let n = out.len();
    if n == 0 {
        return;
    }
    let mut cs = cols.chunks_exact(n);
    let mut xs = x.chunks_exact(4);
    for xb in &mut xs {
        let (x0, x1, x2, x3) = (sign * xb[0], sign * xb[1], sign * xb[2], sign * xb[3]);
        let (Some(c0), Some(c1), Some(c2), Some(c3)) = (cs.next(), cs.next(), cs.next(), cs.next())
        else {
            return;
        };
        for ((((o, a), b), c), d) in out.iter_mut().zip(c0).zip(c1).zip(c2).zip(c3) {
            *o += (x0 * a + x1 * b) + (x2 * c + x3 * d);
        }
    }
    // The last one to three columns in one pass, not one pass each.
    match (xs.remainder(), cs.next(), cs.next(), cs.next()) {
        ([x0, x1, x2], Some(c0), Some(c1), Some(c2)) => {
            let (x0, x1, x2) = (sign * x0, sign * x1, sign * x2);
            for (((o, a), b), c) in out.iter_mut().zip(c0).zip(c1).zip(c2) {
                *o += (x0 * a + x1 * b) + x2 * c;
            }
        }
        ([x0, x1], Some(c0), Some(c1), _) => {
            let (x0, x1) = (sign * x0, sign * x1);
            for ((o, a), b) in out.iter_mut().zip(c0).zip(c1) {
                *o += x0 * a + x1 * b;
            }
        }
        ([x0], Some(c0), _, _) => {
            let x0 = sign * x0;
            for (o, a) in out.iter_mut().zip(c0) {
                *o += x0 * a;
            }
        }
        _ => {}
    }
}

/// [`add_columns`] for rows `first..first + out.len()` of a column-major M whose
/// columns are `rows` long: a block of a tall M without a buffer as long as it. (Kept
/// apart from [`add_columns`], the solver's hot loop: sharing one generic body cost
/// that loop 2–4 % more instructions.)
pub fn add_column_block(
    out: &mut [f64],
    cols: &[f64],
    rows: usize,
    first: usize,
    x: &[f64],
    sign: f64,
) {
    let n = out.len();
    if n == 0 || rows == 0 {
        return;
    }
    let mut cs = cols[first..].chunks(rows).map(|c| &c[..n]);
    let mut xs = x.chunks_exact(4);
    for xb in &mut xs {
        let (x0, x1, x2, x3) = (sign * xb[0], sign * xb[1], sign * xb[2], sign * xb[3]);
        let (Some(c0), Some(c1), Some(c2), Some(c3)) = (cs.next(), cs.next(), cs.next(), cs.next())
        else {
            return;
        };
        for ((((o, a), b), c), d) in out.iter_mut().zip(c0).zip(c1).zip(c2).zip(c3) {
            *o += (x0 * a + x1 * b) + (x2 * c + x3 * d);
        }
    }
    for (col, xj) in cs.zip(xs.remainder()) {
        let xj = sign * xj;
        for (o, c) in out.iter_mut().zip(col) {
            *o += xj * c;
        }
    }
}

/// Writes `m`'s columns into `dst`, column j at `j · ld..` (rows `0..m.nrows()` of
/// it): a block of a column-major matrix whose columns are `ld` long. Row by row from
/// the row-major data, with no per-entry indexing of `m`.
pub fn write_columns(m: &Matrix, dst: &mut [f64], ld: usize) {
    let (rows, cols) = (m.nrows(), m.ncols());
    if rows == 0 || cols == 0 {
        return;
    }
    for (i, row) in m.as_slice().chunks_exact(cols).enumerate() {
        for (j, &v) in row.iter().enumerate() {
            dst[j * ld + i] = v;
        }
    }
}

/// The entries `f(i, j)` of a rows × cols matrix, column after column (the layout of
/// [`add_columns`]).
pub fn column_major(rows: usize, cols: usize, f: impl Fn(usize, usize) -> f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(rows * cols);
    for j in 0..cols {
        out.extend((0..rows).map(|i| f(i, j)));
    }
    out
}

/// Infinity norm of a slice (0 when empty; NaN entries are skipped, as by `f64::max`).
#[inline]
pub fn norm_inf(a: &[f64]) -> f64 {
    fold4(a, 0.0, f64::abs, |v, m| v > m)
}

/// The smallest entry (+∞ when empty; NaN entries are skipped): "does any row fall
/// below −tol" as one vectorised pass.
#[inline]
pub fn min_value(a: &[f64]) -> f64 {
    fold4(a, f64::INFINITY, |v| v, |v, m| v < m)
}

/// The `better` of `map(a_i)` and `init`, in four lanes of plain comparisons, which
/// vectorise where `f64::max`'s NaN handling does not (a NaN is never better).
#[inline(always)]
fn fold4(a: &[f64], init: f64, map: impl Fn(f64) -> f64, better: impl Fn(f64, f64) -> bool) -> f64 {
    let pick = |v: f64, m: f64| if better(v, m) { v } else { m };
    let mut m = [init; 4];
    let mut blocks = a.chunks_exact(4);
    for b in &mut blocks {
        for l in 0..4 {
            m[l] = pick(map(b[l]), m[l]);
        }
    }
    for &v in blocks.remainder() {
        m[0] = pick(map(v), m[0]);
    }
    pick(pick(m[1], m[0]), pick(m[3], m[2]))
}

/// Whether every entry is finite: `0 · v` is 0 for a finite v and NaN otherwise,
/// summed in four lanes (no branch per entry).
pub fn all_finite(a: &[f64]) -> bool {
    let mut s = [0.0f64; 4];
    let mut blocks = a.chunks_exact(4);
    for b in &mut blocks {
        for l in 0..4 {
            s[l] += b[l] * 0.0;
        }
    }
    for &v in blocks.remainder() {
        s[0] += v * 0.0;
    }
    (s[0] + s[1]) + (s[2] + s[3]) == 0.0
}

/// The largest magnitude of an entry, `None` if any is not finite: [`all_finite`] and
/// [`Matrix::max_abs`] in one pass, four lanes.
pub fn finite_max_abs(a: &[f64]) -> Option<f64> {
    let (mut s, mut m) = ([0.0f64; 4], [0.0f64; 4]);
    let mut blocks = a.chunks_exact(4);
    for b in &mut blocks {
        for l in 0..4 {
            s[l] += b[l] * 0.0;
            let v = b[l].abs();
            m[l] = if v > m[l] { v } else { m[l] };
        }
    }
    for &v in blocks.remainder() {
        s[0] += v * 0.0;
        m[0] = if v.abs() > m[0] { v.abs() } else { m[0] };
    }
    ((s[0] + s[1]) + (s[2] + s[3]) == 0.0).then(|| m[0].max(m[1]).max(m[2].max(m[3])))
}

/// Euclidean norm of a slice. Where the squares would underflow or overflow (entries
/// beyond about 1e±150), the slice is scaled by its largest entry first, so that a
/// change of units by any factor scales the norm by the same factor.
#[inline]
pub fn norm2(a: &[f64]) -> f64 {
    let plain = dot(a, a);
    if plain.is_nan() || (plain.is_finite() && plain > 1e-280) {
        plain.sqrt()
    } else {
        norm2_scaled(a)
    }
}

/// [`norm2`] by the largest entry: squares of `a / max |a_i|` cannot overflow.
#[cold]
#[inline(never)]
fn norm2_scaled(a: &[f64]) -> f64 {
    let big = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if big == 0.0 || !big.is_finite() {
        return big;
    }
    big * a.iter().map(|v| (v / big) * (v / big)).sum::<f64>().sqrt()
}

/// What was computed from the last matrix seen, keyed by its shape, its entries' bits
/// and a setting (a tolerance's bits, say). Held per thread by its users: a batch of
/// grasps of one hand passes the same transmission T for every grasp, and its
/// decompositions need not be repeated.
#[derive(Default)]
pub(crate) struct LastMatrix<V> {
    key: Vec<u64>,
    value: Option<V>,
}

impl<V: Clone> LastMatrix<V> {
    fn matches(&self, m: &Matrix, setting: u64) -> bool {
        self.value.is_some()
            && self.key.len() == 3 + m.data.len()
            && self.key[..3] == [m.rows as u64, m.cols as u64, setting]
            && self.key[3..]
                .iter()
                .zip(&m.data)
                .all(|(k, x)| *k == x.to_bits())
    }

    /// The value stored for `m` and `setting`, if the last one stored was for them.
    pub(crate) fn get(&self, m: &Matrix, setting: u64) -> Option<V> {
        self.matches(m, setting)
            .then(|| self.value.clone())
            .flatten()
    }

    /// Stores `value` as the one for `m` and `setting`.
    pub(crate) fn put(&mut self, m: &Matrix, setting: u64, value: V) {
        self.key.clear();
        self.key.extend([m.rows as u64, m.cols as u64, setting]);
        self.key.extend(m.data.iter().map(|x| x.to_bits()));
        self.value = Some(value);
    }
}
