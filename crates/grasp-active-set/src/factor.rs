//! QR factorisation of the key-set rows, `A_Wᵀ = Q [R; 0]`, updated in place.
//!
//! Adding a row costs one `Qᵀa` and Givens rotations; removing one shifts R's columns
//! and restores the triangle with Givens rotations. Both are O(n²) and allocate nothing.

use grasp_core::matrix::dot;

/// Factorisation of up to `n` rows in `n` dimensions (n = k + 1, the elastic variable last).
#[derive(Clone, Debug)]
pub(crate) struct Factor {
    n: usize,
    /// Q, column-major, n × n.
    q: Vec<f64>,
    /// R, column-major, n × n; column c holds the key-set row `rows[c]`.
    r: Vec<f64>,
    rows: Vec<usize>,
    u1: Vec<f64>,
    lambda: Vec<f64>,
    buf: Vec<f64>,
    /// `Qᵀa` of the last row added or passed to [`Self::directions`].
    v: Vec<f64>,
    /// `v` is `Qᵀa` for the current Q and the last [`Self::directions`] row.
    v_current: bool,
}

/// Rotation zeroing `b` against `a`. Entries are O(1) here (unit rows), so the plain
/// square root cannot overflow and is much cheaper than `hypot`.
#[inline]
fn givens(a: f64, b: f64) -> (f64, f64, f64) {
    let r = (a * a + b * b).sqrt();
    if r == 0.0 {
        (1.0, 0.0, 0.0)
    } else {
        (a / r, b / r, r)
    }
}

impl Factor {
    pub(crate) fn new(n: usize) -> Self {
        let mut f = Self {
            n,
            q: vec![0.0; n * n],
            r: vec![0.0; n * n],
            rows: Vec::with_capacity(n),
            u1: vec![0.0; n],
            lambda: vec![0.0; n],
            buf: vec![0.0; n],
            v: vec![0.0; n],
            v_current: false,
        };
        f.clear();
        f
    }

    /// Empties the key set (Q = I).
    pub(crate) fn clear(&mut self) {
        self.rows.clear();
        self.v_current = false;
        self.q.iter_mut().for_each(|x| *x = 0.0);
        for i in 0..self.n {
            self.q[i * self.n + i] = 1.0;
        }
    }

    /// The key-set rows, in factor order.
    pub(crate) fn rows(&self) -> &[usize] {
        &self.rows
    }

    pub(crate) fn contains(&self, id: usize) -> bool {
        self.rows.contains(&id)
    }

    pub(crate) fn position(&self, id: usize) -> Option<usize> {
        self.rows.iter().position(|&r| r == id)
    }

    /// Multiplier of the key-set row at `pos` from the last [`Self::solve`].
    pub(crate) fn lambda(&self, pos: usize) -> f64 {
        self.lambda[pos]
    }

    fn rotate_q(&mut self, j: usize, c: f64, s: f64) {
        let n = self.n;
        let (left, right) = self.q.split_at_mut((j + 1) * n);
        let (qj, qj1) = (&mut left[j * n..], &mut right[..n]);
        for (x, y) in qj.iter_mut().zip(qj1.iter_mut()) {
            let (a, b) = (*x, *y);
            *x = c * a + s * b;
            *y = -s * a + c * b;
        }
    }

    /// Adds the row written by `fill`; false (and no change) when it is within `tol`
    /// (relative) of the span of the key set, or the set is full.
    pub(crate) fn add(&mut self, id: usize, tol: f64, fill: impl FnOnce(&mut [f64])) -> bool {
        if self.rows.len() == self.n {
            return false;
        }
        fill(&mut self.buf);
        self.project_buf();
        self.insert(id, tol)
    }

    /// [`Self::add`] for the row `a` last passed to [`Self::directions`]: its `Qᵀa` is
    /// reused when Q has not changed since (the dual phase's full step).
    pub(crate) fn add_direction_row(&mut self, id: usize, tol: f64, a: &[f64]) -> bool {
        if self.rows.len() == self.n {
            return false;
        }
        self.buf.copy_from_slice(&a[..self.n]);
        if !self.v_current {
            self.project_buf();
        }
        self.insert(id, tol)
    }

    /// `v = Qᵀ buf`.
    fn project_buf(&mut self) {
        let n = self.n;
        for (vj, qj) in self.v.iter_mut().zip(self.q.chunks_exact(n)) {
            *vj = dot(qj, &self.buf);
        }
    }

    /// Adds the row in `buf`, whose `Qᵀ buf` is in `v`.
    fn insert(&mut self, id: usize, tol: f64) -> bool {
        let (n, t) = (self.n, self.rows.len());
        self.v_current = false;
        let anorm = dot(&self.buf, &self.buf).sqrt();
        let tail = dot(&self.v[t..], &self.v[t..]).sqrt();
        // Also rejects NaN.
        if tail.partial_cmp(&(tol * anorm)) != Some(std::cmp::Ordering::Greater) {
            return false;
        }
        for j in (t + 1..n).rev() {
            let (c, s, r) = givens(self.v[j - 1], self.v[j]);
            self.v[j - 1] = r;
            self.v[j] = 0.0;
            self.rotate_q(j - 1, c, s);
        }
        self.r[t * n..t * n + t + 1].copy_from_slice(&self.v[..=t]);
        self.rows.push(id);
        true
    }

    /// For the dual phase: the primal direction `Q2 Q2ᵀ a` into `z` and the dual
    /// direction `R⁻¹ Q1ᵀ a` into [`Self::lambda`].
    pub(crate) fn directions(&mut self, a: &[f64], z: &mut [f64]) {
        let (n, t) = (self.n, self.rows.len());
        for (vj, qj) in self.v.iter_mut().zip(self.q.chunks_exact(n)) {
            *vj = dot(qj, &a[..n]);
        }
        self.v_current = true;
        z[..n].iter_mut().for_each(|x| *x = 0.0);
        for j in t..n {
            let c = self.v[j];
            for (zi, qv) in z.iter_mut().zip(&self.q[j * n..(j + 1) * n]) {
                *zi += c * qv;
            }
        }
        for i in (0..t).rev() {
            let mut s = self.v[i];
            for j in i + 1..t {
                s -= self.r[j * n + i] * self.lambda[j];
            }
            self.lambda[i] = s / self.r[i * n + i];
        }
    }

    /// Removes the key-set row at `pos`.
    pub(crate) fn remove(&mut self, pos: usize) {
        let (n, t) = (self.n, self.rows.len());
        self.v_current = false;
        self.rows.remove(pos);
        self.r.copy_within((pos + 1) * n..t * n, pos * n);
        for j in pos..t - 1 {
            let (c, s, r) = givens(self.r[j * n + j], self.r[j * n + j + 1]);
            self.r[j * n + j] = r;
            self.r[j * n + j + 1] = 0.0;
            for col in j + 1..t - 1 {
                let (a, b) = (self.r[col * n + j], self.r[col * n + j + 1]);
                self.r[col * n + j] = c * a + s * b;
                self.r[col * n + j + 1] = -s * a + c * b;
            }
            self.rotate_q(j, c, s);
        }
    }

    /// `Rᵀ u1 = rhs` over the key set (forward substitution).
    fn forward(&mut self, rhs: impl Fn(usize) -> f64) {
        let n = self.n;
        for i in 0..self.rows.len() {
            let col = &self.r[i * n..i * n + i + 1];
            let s = rhs(self.rows[i]) - dot(&col[..i], &self.u1[..i]);
            self.u1[i] = s / col[i];
        }
    }

    /// The least-norm `z` with `a_i·z = rhs(i)` over the key set, `Q1 R⁻ᵀ rhs`; the
    /// multipliers of the last [`Self::solve`] are kept.
    pub(crate) fn least_norm(&mut self, rhs: impl Fn(usize) -> f64, z: &mut [f64]) {
        let n = self.n;
        self.forward(rhs);
        z.iter_mut().for_each(|x| *x = 0.0);
        for (j, &u) in self.u1[..self.rows.len()].iter().enumerate() {
            for (x, qv) in z.iter_mut().zip(&self.q[j * n..(j + 1) * n]) {
                *x += u * qv;
            }
        }
    }

    /// Minimises `½‖z‖² + penalty·z[n−1]` subject to `a_i·z = rhs(i)` for the key set:
    /// the minimiser goes to `zstar`, the multipliers to [`Self::lambda`]. With
    /// `last_fixed` (z[n−1] is pinned by the key set) the penalty term of z* is exactly
    /// zero and is skipped.
    pub(crate) fn solve(
        &mut self,
        penalty: f64,
        last_fixed: bool,
        rhs: impl Fn(usize) -> f64,
        zstar: &mut [f64],
    ) {
        let (n, t) = (self.n, self.rows.len());
        let last = n - 1;
        self.forward(rhs);
        // z* = Q1 u1 − penalty · Q2 Q2ᵀ e_last.
        zstar.iter_mut().for_each(|x| *x = 0.0);
        for j in 0..n {
            let coef = if j < t {
                self.u1[j]
            } else if last_fixed {
                0.0
            } else {
                -penalty * self.q[j * n + last]
            };
            if coef != 0.0 {
                for (z, qv) in zstar.iter_mut().zip(&self.q[j * n..(j + 1) * n]) {
                    *z += coef * qv;
                }
            }
        }
        // R λ = u1 + penalty · Q1ᵀ e_last (back substitution).
        for i in (0..t).rev() {
            let mut s = self.u1[i] + penalty * self.q[i * n + last];
            for j in i + 1..t {
                s -= self.r[j * n + i] * self.lambda[j];
            }
            self.lambda[i] = s / self.r[i * n + i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small fixed PRNG (xorshift), so failures reproduce.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// Adding the row last passed to `directions` reuses its `Qᵀa` and gives the same
    /// factor, bit for bit, as adding it afresh; after Q changes it projects again.
    #[test]
    fn adding_the_direction_row_matches_a_fresh_add() {
        for seed in 1..=20u64 {
            let mut rng = Rng(seed.wrapping_mul(0x2545_f491_4f6c_dd1d));
            let n = 3 + (seed as usize % 6);
            let rows: Vec<Vec<f64>> = (0..n)
                .map(|_| (0..n).map(|_| rng.next()).collect())
                .collect();
            let (mut a, mut b) = (Factor::new(n), Factor::new(n));
            let mut z = vec![0.0; n];
            for (id, row) in rows.iter().enumerate() {
                if id == 2 {
                    // Q changes between the direction and the add: the flag must notice.
                    a.directions(row, &mut z);
                    a.remove(0);
                    b.remove(0);
                } else {
                    a.directions(row, &mut z);
                }
                let ok_a = a.add_direction_row(id, 1e-10, row);
                let ok_b = b.add(id, 1e-10, |buf| buf.copy_from_slice(row));
                assert_eq!(ok_a, ok_b, "seed {seed} row {id}");
                assert_eq!(a.q, b.q, "seed {seed} row {id}: Q");
                assert_eq!(a.r, b.r, "seed {seed} row {id}: R");
                assert_eq!(a.rows, b.rows, "seed {seed} row {id}: rows");
            }
        }
    }

    /// After random add and remove sequences, Q stays orthogonal and Q R reproduces the
    /// key-set rows, both to c·n·ε.
    #[test]
    fn updates_keep_q_orthogonal_and_reconstruct_the_rows() {
        for seed in 1..=40u64 {
            let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15));
            let n = 2 + (seed as usize % 9);
            let pool: Vec<Vec<f64>> = (0..3 * n)
                .map(|_| {
                    let v: Vec<f64> = (0..n).map(|_| rng.next()).collect();
                    let nrm = dot(&v, &v).sqrt();
                    v.iter().map(|x| x / nrm).collect()
                })
                .collect();
            let mut f = Factor::new(n);
            for step in 0..200 {
                if f.rows().len() < n && (f.rows().is_empty() || rng.next() > -0.2) {
                    let id = (rng.next().abs() * pool.len() as f64) as usize % pool.len();
                    if !f.contains(id) {
                        f.add(id, 1e-10, |b| b.copy_from_slice(&pool[id]));
                    }
                } else {
                    let pos = (rng.next().abs() * f.rows().len() as f64) as usize;
                    f.remove(pos.min(f.rows().len() - 1));
                }
                let tol = 50.0 * n as f64 * f64::EPSILON;
                for i in 0..n {
                    for j in 0..n {
                        let qtq = dot(&f.q[i * n..(i + 1) * n], &f.q[j * n..(j + 1) * n]);
                        let want = if i == j { 1.0 } else { 0.0 };
                        assert!((qtq - want).abs() < tol, "seed {seed} step {step}: QᵀQ");
                    }
                }
                for (c, &id) in f.rows().iter().enumerate() {
                    for i in 0..n {
                        // (Q R)_{i,c} = Σ_j Q_{i,j} R_{j,c}; Q column j is q[j n..].
                        let qr: f64 = (0..=c).map(|j| f.q[j * n + i] * f.r[c * n + j]).sum();
                        assert!(
                            (qr - pool[id][i]).abs() < tol,
                            "seed {seed} step {step}: Q R column {c}"
                        );
                    }
                }
            }
        }
    }
}
