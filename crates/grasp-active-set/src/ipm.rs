//! A small dense primal-dual interior-point method for the exact-cone problem in the
//! core's [`ConicForm`]: minimise `½ xᵀPx` (P diagonal) subject to `E x = b_E`,
//! `G x + s = h`, `s ∈ K` (nonnegative orthant × second-order cones).
//!
//! It follows CVXOPT's `coneqp` (Vandenberghe, "The CVXOPT linear and quadratic cone
//! program solvers", 2010): Nesterov–Todd scaling `W` (`W z = W⁻¹ s = λ`), Mehrotra's
//! predictor–corrector, and the reduced system `(P + Gᵀ W⁻² G) dx + Eᵀ dy = r`, solved
//! by a dense Cholesky factor and the Schur complement of the few equalities. Problems
//! here have tens of variables and rows, so dense kernels beat any sparse machinery.
//! Every buffer is allocated when the solver is built. Where Newton's method has
//! eliminated the equalities (`x = x_p + N y`), the method runs on `y` instead
//! ([`Ipm::reduced`]): about half the variables on a hand, no equalities. Its
//! directions are refined only while their equations miss by more than rounding. Where
//! the formed matrix loses its Cholesky factor to rounding near the end, a QR of
//! `[√P; W⁻¹G]` gives the factor without forming it ([`Ipm::factor_by_qr`]).
//!
//! It is the fallback of the exact-cone solver, used when the active-set Newton path
//! does not end with a certificate; infeasibility is decided before it runs (the
//! inscribed and circumscribed polyhedra), so it has no homogeneous embedding.

use crate::dense::{backward, forward, qr_factor, schur};
use grasp_core::matrix::{dot, norm2, norm_inf};
use grasp_core::{ConeKind, ConicForm, Matrix};

/// Largest second-order cone handled (the exact friction cones have 3 or 4 rows).
pub(crate) const SOC_MAX: usize = 8;

/// Steps of iterative refinement per search direction, at most.
const REFINEMENT_STEPS: usize = 3;

/// A direction whose block equations hold to this, relative to their right-hand
/// side, is not refined: a correction would change it by rounding (64 ε). Early
/// iterations' directions start there; the last ones, with W⁻² spread over many
/// orders of magnitude, do not.
const REFINEMENT_TOLERANCE: f64 = 64.0 * f64::EPSILON;

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum IpmEnd {
    /// Converged to the tolerances.
    Converged,
    /// The iteration cap was reached.
    IterationLimit,
    /// The step length vanished or the factorisation broke down.
    Stalled,
    /// The caller's test stopped it (its multipliers proved the problem infeasible).
    Stopped,
}

/// One cone of the inequality rows.
#[derive(Clone, Copy, Debug)]
enum Block {
    /// Rows `start..start+dim` of G, each `s_i ≥ 0`.
    Orthant { start: usize, dim: usize },
    /// Rows `start..start+dim` of G, `s0 ≥ ‖s1..‖`.
    Soc { start: usize, dim: usize },
}

/// Tolerances and limits of the interior-point method, on the scaled problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct IpmSettings {
    /// Primal and dual residuals, relative. 1e-11.
    pub feasibility: f64,
    /// Duality gap, relative to the objective. 1e-11.
    pub gap_rel: f64,
    /// Duality gap, absolute (the scaled problem has right-hand side of size 1). 1e-13.
    pub gap_abs: f64,
    /// Iteration cap. 80.
    pub max_iterations: usize,
    /// A run that stalls or reaches the cap ends converged with its best iterate when
    /// that iterate's largest relative residual or gap is at most this. 1e-9.
    pub acceptable: f64,
}

impl Default for IpmSettings {
    fn default() -> Self {
        Self {
            feasibility: 1e-11,
            gap_rel: 1e-11,
            gap_abs: 1e-13,
            max_iterations: 80,
            acceptable: 1e-9,
        }
    }
}

/// The interior-point solver of one conic form, with its workspace.
#[derive(Clone, Debug)]
pub(crate) struct Ipm {
    settings: IpmSettings,
    n: usize,
    pdiag: Vec<f64>,
    /// Equality rows E (p × n).
    e: Matrix,
    /// Inequality rows G (r × n).
    g: Matrix,
    blocks: Vec<Block>,
    /// Degree of the cone (orthant rows + number of second-order cones).
    degree: f64,
    // Iterates.
    pub(crate) x: Vec<f64>,
    pub(crate) y: Vec<f64>,
    pub(crate) z: Vec<f64>,
    pub(crate) s: Vec<f64>,
    pub(crate) iterations: usize,
    /// The lowest merit of the last run (largest relative residual or gap), infinite
    /// before its first iterate.
    pub(crate) best_merit: f64,
    /// Whether the variables are `y` of `x = x_p + N y` (the equalities eliminated, no
    /// rows of the zero cone), not the form's x.
    reduced: bool,
    ws: Work,
}

#[derive(Clone, Debug, Default)]
struct Work {
    be: Vec<f64>,
    h: Vec<f64>,
    rx: Vec<f64>,
    ry: Vec<f64>,
    rz: Vec<f64>,
    dx: Vec<f64>,
    dy: Vec<f64>,
    dz: Vec<f64>,
    ds: Vec<f64>,
    dsa: Vec<f64>,
    dza: Vec<f64>,
    lam: Vec<f64>,
    /// Per orthant row: `√(s/z)`; per SOC: `w̄` (its rows) and η in `eta`.
    w: Vec<f64>,
    eta: Vec<f64>,
    u: Vec<f64>,
    t1: Vec<f64>,
    t2: Vec<f64>,
    rhs_x: Vec<f64>,
    /// The right-hand side and the first solution during refinement.
    rx0: Vec<f64>,
    ry0: Vec<f64>,
    rz0: Vec<f64>,
    t10: Vec<f64>,
    sdx: Vec<f64>,
    sdy: Vec<f64>,
    sdz: Vec<f64>,
    sds: Vec<f64>,
    /// The best iterate so far.
    best_x: Vec<f64>,
    best_y: Vec<f64>,
    best_z: Vec<f64>,
    best_s: Vec<f64>,
    /// Reduced matrix `P + Gᵀ W⁻² G` and its Cholesky factor (n × n, row-major).
    m: Vec<f64>,
    /// `L⁻¹ Eᵀ` (n × p, column j in `y_cols[j*n..]`) and the Schur factor (p × p).
    y_cols: Vec<f64>,
    schur: Vec<f64>,
    /// `[√P; W⁻¹ G]` ((n + r) × n), for [`Ipm::factor_by_qr`].
    stack: Vec<f64>,
}

impl Ipm {
    /// The solver of `form` (rows of the zero cone become equalities).
    pub(crate) fn new(form: &ConicForm, settings: IpmSettings) -> Self {
        Self::with_rows(form, None, settings)
    }

    /// The solver of `form` with its equalities eliminated, `x = x_p + N y` (N
    /// orthonormal, `x_p` orthogonal to it): on `y`, minimise `‖y‖²` subject to
    /// `(b − A x_p) − (A N) y ∈ K` on the inequality rows, whose `A N` is `g`. Without
    /// free internal forces `½ xᵀPx = ‖x‖²`, which is `‖y‖²` plus a constant. Fewer
    /// variables (the null space's dimension, about half the form's on a hand) and no
    /// Schur complement: each iteration's `Gᵀ W⁻² G` and factor cost a fraction.
    /// [`Self::solve`] then takes `b − A x_p` in the form's row order.
    pub(crate) fn reduced(form: &ConicForm, g: Matrix, settings: IpmSettings) -> Self {
        Self::with_rows(form, Some(g), settings)
    }

    fn with_rows(form: &ConicForm, reduced: Option<Matrix>, settings: IpmSettings) -> Self {
        let n = reduced.as_ref().map_or(form.nx, Matrix::ncols);
        let mut pdiag = vec![0.0; n];
        match reduced {
            Some(_) => pdiag.iter_mut().for_each(|p| *p = 2.0),
            None => pdiag[..form.joints].iter_mut().for_each(|p| *p = 2.0),
        }
        let mut eq_rows = Vec::new();
        let mut in_rows = Vec::new();
        let mut blocks = Vec::new();
        let mut row = 0;
        let mut degree = 0.0;
        for cone in &form.cones {
            let dim = cone.dim();
            let start = in_rows.len();
            match cone {
                ConeKind::Zero(_) => eq_rows.extend(row..row + dim),
                ConeKind::Nonnegative(_) => {
                    in_rows.extend(row..row + dim);
                    blocks.push(Block::Orthant { start, dim });
                    degree += dim as f64;
                }
                ConeKind::SecondOrder(_) => {
                    in_rows.extend(row..row + dim);
                    blocks.push(Block::Soc { start, dim });
                    degree += 1.0;
                }
            }
            row += dim;
        }
        let is_reduced = reduced.is_some();
        let (e, g) = match reduced {
            Some(g) => (Matrix::zeros(0, n), g),
            None => (
                Matrix::from_fn(eq_rows.len(), n, |i, j| form.a[(eq_rows[i], j)]),
                Matrix::from_fn(in_rows.len(), n, |i, j| form.a[(in_rows[i], j)]),
            ),
        };
        let (p, r) = (e.nrows(), g.nrows());
        let ws = Work {
            be: vec![0.0; p],
            h: vec![0.0; r],
            rx: vec![0.0; n],
            ry: vec![0.0; p],
            rz: vec![0.0; r],
            dx: vec![0.0; n],
            dy: vec![0.0; p],
            dz: vec![0.0; r],
            ds: vec![0.0; r],
            dsa: vec![0.0; r],
            dza: vec![0.0; r],
            lam: vec![0.0; r],
            w: vec![0.0; r],
            eta: vec![0.0; blocks.len()],
            u: vec![0.0; r],
            t1: vec![0.0; r.max(n)],
            t2: vec![0.0; r.max(n)],
            rhs_x: vec![0.0; n],
            rx0: vec![0.0; n],
            ry0: vec![0.0; p],
            rz0: vec![0.0; r],
            t10: vec![0.0; r],
            sdx: vec![0.0; n],
            sdy: vec![0.0; p],
            sdz: vec![0.0; r],
            sds: vec![0.0; r],
            best_x: vec![0.0; n],
            best_y: vec![0.0; p],
            best_z: vec![0.0; r],
            best_s: vec![0.0; r],
            m: vec![0.0; n * n],
            y_cols: vec![0.0; n * p],
            schur: vec![0.0; p * p],
            stack: vec![0.0; (n + r) * n],
        };
        Self {
            settings,
            n,
            pdiag,
            e,
            g,
            blocks,
            degree,
            x: vec![0.0; n],
            y: vec![0.0; p],
            z: vec![0.0; r],
            s: vec![0.0; r],
            iterations: 0,
            best_merit: f64::INFINITY,
            reduced: is_reduced,
            ws,
        }
    }

    /// Takes the best iterate of the last run (the lowest merit seen) as the current
    /// one: where the method lost its last digits to rounding, it is the closest to
    /// the optimum.
    pub(crate) fn restore_best(&mut self) {
        self.x.copy_from_slice(&self.ws.best_x);
        self.y.copy_from_slice(&self.ws.best_y);
        self.z.copy_from_slice(&self.ws.best_z);
        self.s.copy_from_slice(&self.ws.best_s);
    }

    /// Whether the solver works on `y` of `x = x_p + N y` ([`Self::reduced`]).
    pub(crate) fn is_reduced(&self) -> bool {
        self.reduced
    }

    /// Splits `b` (in the form's row order) into `b_E` and `h`.
    fn load(&mut self, form: &ConicForm, b: &[f64]) {
        let (mut ie, mut ih) = (0, 0);
        let mut row = 0;
        for cone in &form.cones {
            for i in row..row + cone.dim() {
                if matches!(cone, ConeKind::Zero(_)) {
                    if !self.reduced {
                        self.ws.be[ie] = b[i];
                        ie += 1;
                    }
                } else {
                    self.ws.h[ih] = b[i];
                    ih += 1;
                }
            }
            row += cone.dim();
        }
    }

    /// The dual variables in the form's row order (equalities' y with the sign of z;
    /// zero when they were eliminated, which the certificate and the dual ray do not
    /// read).
    pub(crate) fn dual_into(&self, form: &ConicForm, out: &mut [f64]) {
        let (mut ie, mut ih) = (0, 0);
        let mut row = 0;
        for cone in &form.cones {
            for o in &mut out[row..row + cone.dim()] {
                if matches!(cone, ConeKind::Zero(_)) {
                    *o = if self.reduced { 0.0 } else { self.y[ie] };
                    ie += usize::from(!self.reduced);
                } else {
                    *o = self.z[ih];
                    ih += 1;
                }
            }
            row += cone.dim();
        }
    }

    /// Solves the scaled problem with right-hand side `b` (the form's row order).
    /// `stop` sees each iterate that has not converged; true ends the run there
    /// (`IpmEnd::Stopped`).
    pub(crate) fn solve(
        &mut self,
        form: &ConicForm,
        b: &[f64],
        stop: &mut dyn FnMut(&Self) -> bool,
    ) -> IpmEnd {
        self.load(form, b);
        self.iterations = 0;
        self.best_merit = f64::INFINITY;
        if !self.initial_point() {
            return IpmEnd::Stalled;
        }
        let st = self.settings;
        let bscale = norm_inf(&self.ws.be).max(norm_inf(&self.ws.h)).max(1.0);
        let mut best = f64::INFINITY;
        let end = self.iterate(bscale, &mut best, stop);
        self.best_merit = best;
        if matches!(end, IpmEnd::IterationLimit | IpmEnd::Stalled) && best <= st.acceptable {
            // Rounding stopped the last digits: the best iterate is the answer.
            self.restore_best();
            return IpmEnd::Converged;
        }
        end
    }

    /// The iteration proper; `best` tracks the best merit seen, whose iterate is kept.
    fn iterate(
        &mut self,
        bscale: f64,
        best: &mut f64,
        stop: &mut dyn FnMut(&Self) -> bool,
    ) -> IpmEnd {
        let st = self.settings;
        for it in 0..st.max_iterations {
            self.iterations = it + 1;
            self.residuals();
            let gap = dot(&self.s, &self.z);
            let pobj: f64 = 0.5
                * self
                    .x
                    .iter()
                    .zip(&self.pdiag)
                    .map(|(x, p)| p * x * x)
                    .sum::<f64>();
            let px = self
                .x
                .iter()
                .zip(&self.pdiag)
                .fold(0.0f64, |a, (x, p)| a.max((p * x).abs()));
            let pres = norm_inf(&self.ws.ry).max(norm_inf(&self.ws.rz)) / bscale;
            let dres = norm_inf(&self.ws.rx) / px.max(1.0);
            // An iterate that rounding made non-finite is neither an answer nor the best
            // one (the norms above skip NaN, and its merit would read 0).
            let finite = [&self.ws.rx, &self.ws.ry, &self.ws.rz]
                .iter()
                .all(|r| r.iter().map(|v| v * 0.0).sum::<f64>() == 0.0);
            if !(finite && gap.is_finite() && pobj.is_finite()) {
                return IpmEnd::Stalled;
            }
            if pres <= st.feasibility
                && dres <= st.feasibility
                && (gap <= st.gap_abs || gap <= st.gap_rel * pobj)
            {
                return IpmEnd::Converged;
            }
            let merit = pres.max(dres).max(if gap <= st.gap_abs {
                0.0
            } else {
                gap / pobj.max(f64::MIN_POSITIVE)
            });
            if merit < *best {
                *best = merit;
                self.ws.best_x.copy_from_slice(&self.x);
                self.ws.best_y.copy_from_slice(&self.y);
                self.ws.best_z.copy_from_slice(&self.z);
                self.ws.best_s.copy_from_slice(&self.s);
            }
            if stop(self) {
                return IpmEnd::Stopped;
            }
            let mu = gap / self.degree.max(1.0);
            if !self.scaling() || !self.factor() {
                return IpmEnd::Stalled;
            }
            // Predictor: d_s = −λ∘λ.
            let r = self.s.len();
            for bi in 0..self.blocks.len() {
                let blk = self.blocks[bi];
                let (start, dim) = blk.range();
                let lam = &self.ws.lam[start..start + dim];
                let out = &mut self.ws.t1[start..start + dim];
                circ(blk, lam, lam, out);
                out.iter_mut().for_each(|v| *v = -*v);
            }
            self.direction();
            let alpha_aff = self.max_step(1.0);
            self.ws.dsa[..r].copy_from_slice(&self.ws.ds);
            self.ws.dza[..r].copy_from_slice(&self.ws.dz);
            let sigma = (1.0 - alpha_aff).clamp(0.0, 1.0).powi(3);
            // Corrector: d_s = −λ∘λ − (W⁻¹ ds_a)∘(W dz_a) + σ μ e.
            for bi in 0..self.blocks.len() {
                let blk = self.blocks[bi];
                let (start, dim) = blk.range();
                let ws = &mut self.ws;
                match blk {
                    Block::Orthant { .. } => {
                        for k in start..start + dim {
                            let corr = (ws.dsa[k] / ws.w[k]) * (ws.dza[k] * ws.w[k]);
                            ws.t1[k] = -ws.lam[k] * ws.lam[k] - corr + sigma * mu;
                        }
                    }
                    Block::Soc { .. } => {
                        let (mut a, mut c) = ([0.0; SOC_MAX], [0.0; SOC_MAX]);
                        let (mut corr, mut lam2) = ([0.0; SOC_MAX], [0.0; SOC_MAX]);
                        let (w, eta) = (&ws.w[start..start + dim], ws.eta[bi]);
                        apply_winv(w, eta, &ws.dsa[start..start + dim], &mut a[..dim]);
                        apply_w(w, eta, &ws.dza[start..start + dim], &mut c[..dim]);
                        circ(blk, &a[..dim], &c[..dim], &mut corr[..dim]);
                        let lam = &ws.lam[start..start + dim];
                        circ(blk, lam, lam, &mut lam2[..dim]);
                        for k in 0..dim {
                            let e = if k == 0 { sigma * mu } else { 0.0 };
                            ws.t1[start + k] = -lam2[k] - corr[k] + e;
                        }
                    }
                }
            }
            self.direction();
            let alpha = self.max_step(0.99);
            if alpha < 1e-12 {
                return IpmEnd::Stalled;
            }
            for (x, d) in self.x.iter_mut().zip(&self.ws.dx) {
                *x += alpha * d;
            }
            for (y, d) in self.y.iter_mut().zip(&self.ws.dy) {
                *y += alpha * d;
            }
            for (z, d) in self.z.iter_mut().zip(&self.ws.dz) {
                *z += alpha * d;
            }
            for (s, d) in self.s.iter_mut().zip(&self.ws.ds) {
                *s += alpha * d;
            }
        }
        IpmEnd::IterationLimit
    }

    /// CVXOPT's starting point: the least-squares solution with `W = I`, then `s` and
    /// `z` shifted into the interior.
    fn initial_point(&mut self) -> bool {
        let r = self.s.len();
        self.ws.w.iter_mut().for_each(|w| *w = 1.0);
        for (bi, blk) in self.blocks.iter().enumerate() {
            self.ws.eta[bi] = 1.0;
            if let Block::Soc { start, dim } = *blk {
                // w̄ = e (W = I).
                self.ws.w[start..start + dim]
                    .iter_mut()
                    .for_each(|w| *w = 0.0);
                self.ws.w[start] = 1.0;
            }
        }
        if !self.factor() {
            return false;
        }
        // (P + GᵀG) x + Eᵀ y = Gᵀ h, E x = b_E: the direction solve with rx = −Gᵀh... as
        // a solve with zero iterate: rx = 0, ry = −b_E, rz = −h, d_s = 0.
        self.ws.rx.iter_mut().for_each(|v| *v = 0.0);
        for (r, b) in self.ws.ry.iter_mut().zip(&self.ws.be) {
            *r = -b;
        }
        for (r, h) in self.ws.rz.iter_mut().zip(&self.ws.h) {
            *r = -h;
        }
        self.ws.t1[..r].iter_mut().for_each(|v| *v = 0.0);
        self.x.iter_mut().for_each(|v| *v = 0.0);
        self.s.iter_mut().for_each(|v| *v = 0.0);
        self.z.iter_mut().for_each(|v| *v = 0.0);
        // λ = 0 makes λ⧵0 undefined: with d_s = 0 the solve uses u = 0 directly.
        self.ws.lam.iter_mut().for_each(|v| *v = 1.0);
        for blk in &self.blocks {
            if let Block::Soc { start, dim } = *blk {
                self.ws.lam[start..start + dim]
                    .iter_mut()
                    .for_each(|v| *v = 0.0);
                self.ws.lam[start] = 1.0;
            }
        }
        self.direction();
        self.x.copy_from_slice(&self.ws.dx);
        self.y.copy_from_slice(&self.ws.dy);
        // z = G x − h, s = −z.
        for i in 0..r {
            let gx = dot(self.g.row(i), &self.x);
            self.z[i] = gx - self.ws.h[i];
            self.s[i] = -self.z[i];
        }
        for v in [&mut self.s, &mut self.z] {
            let mut shift = f64::NEG_INFINITY;
            for blk in &self.blocks {
                let (start, dim) = blk.range();
                let m = match blk {
                    Block::Orthant { .. } => v[start..start + dim]
                        .iter()
                        .fold(f64::NEG_INFINITY, |a, x| a.max(-x)),
                    Block::Soc { .. } => norm2(&v[start + 1..start + dim]) - v[start],
                };
                shift = shift.max(m);
            }
            if shift >= -1e-8 {
                let add = 1.0 + shift.max(0.0);
                for blk in &self.blocks {
                    match *blk {
                        Block::Orthant { start, dim } => {
                            v[start..start + dim].iter_mut().for_each(|x| *x += add)
                        }
                        Block::Soc { start, .. } => v[start] += add,
                    }
                }
            }
        }
        self.x.iter().all(|v| v.is_finite())
    }

    /// `rx = P x + Eᵀ y + Gᵀ z`, `ry = E x − b_E`, `rz = G x + s − h`.
    fn residuals(&mut self) {
        let ws = &mut self.ws;
        for j in 0..self.n {
            ws.rx[j] = self.pdiag[j] * self.x[j];
        }
        for i in 0..self.e.nrows() {
            let row = self.e.row(i);
            ws.ry[i] = dot(row, &self.x) - ws.be[i];
            for (r, a) in ws.rx.iter_mut().zip(row) {
                *r += a * self.y[i];
            }
        }
        for i in 0..self.g.nrows() {
            let row = self.g.row(i);
            ws.rz[i] = dot(row, &self.x) + self.s[i] - ws.h[i];
            for (r, a) in ws.rx.iter_mut().zip(row) {
                *r += a * self.z[i];
            }
        }
    }

    /// Nesterov–Todd scaling of `(s, z)` and `λ = W z`; false if they left the cone.
    fn scaling(&mut self) -> bool {
        for (bi, blk) in self.blocks.iter().enumerate() {
            let (start, dim) = blk.range();
            let s = &self.s[start..start + dim];
            let z = &self.z[start..start + dim];
            match blk {
                Block::Orthant { .. } => {
                    for k in 0..dim {
                        if s[k] <= 0.0 || z[k] <= 0.0 {
                            return false;
                        }
                        self.ws.w[start + k] = (s[k] / z[k]).sqrt();
                        self.ws.lam[start + k] = (s[k] * z[k]).sqrt();
                    }
                }
                Block::Soc { .. } => {
                    let ds = soc_det(s);
                    let dz = soc_det(z);
                    if ds <= 0.0 || dz <= 0.0 || s[0] <= 0.0 || z[0] <= 0.0 {
                        return false;
                    }
                    let (rs, rz) = (ds.sqrt(), dz.sqrt());
                    let sz: f64 = s.iter().zip(z).map(|(a, b)| a * b).sum::<f64>() / (rs * rz);
                    let gamma = ((1.0 + sz) / 2.0).sqrt();
                    let w = &mut self.ws.w[start..start + dim];
                    w[0] = (s[0] / rs + z[0] / rz) / (2.0 * gamma);
                    for k in 1..dim {
                        w[k] = (s[k] / rs - z[k] / rz) / (2.0 * gamma);
                    }
                    let eta = (ds / dz).sqrt().sqrt();
                    self.ws.eta[bi] = eta;
                    let w = &self.ws.w[start..start + dim];
                    apply_w(w, eta, z, &mut self.ws.lam[start..start + dim]);
                }
            }
        }
        true
    }

    /// Factors `P + Gᵀ W⁻² G` ([`Self::factor_by_qr`]) and the Schur complement of the
    /// equalities.
    fn factor(&mut self) -> bool {
        if !self.factor_by_qr() {
            return false;
        }
        let ws = &mut self.ws;
        // Schur complement S = E M⁻¹ Eᵀ = YᵀY with Y = L⁻¹ Eᵀ.
        let p = self.e.nrows();
        schur(
            &ws.m,
            self.n,
            self.e.as_slice(),
            p,
            &mut ws.y_cols,
            &mut ws.schur,
        )
    }

    /// The factor of `P + Gᵀ W⁻² G` from a QR of `[√P; W⁻¹ G]`, never forming the
    /// product: near the end W⁻² spans many orders of magnitude, and the product's
    /// Cholesky factor, with the square of R's condition number, loses the directions'
    /// last digits first (the dual residual grows again, 5e-13 to 1e-4 over a few
    /// iterations on grasps at a hundredth of normal friction, until the method
    /// stalls) and then its positive definiteness. Into `ws.m` in the layout of
    /// [`crate::dense::cholesky`]; false if the QR breaks down.
    fn factor_by_qr(&mut self) -> bool {
        let n = self.n;
        let ws = &mut self.ws;
        let rows = n + self.g.nrows();
        let a = &mut ws.stack[..rows * n];
        a.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..n {
            // (Variables without curvature: the same small one as the formed matrix.)
            let p = if self.pdiag[j] == 0.0 {
                1e-12
            } else {
                self.pdiag[j]
            };
            a[j * n + j] = p.sqrt();
        }
        for (bi, blk) in self.blocks.iter().enumerate() {
            let (start, dim) = blk.range();
            let rows = &mut a[(n + start) * n..(n + start + dim) * n];
            match blk {
                Block::Orthant { .. } => {
                    for (i, row) in rows.chunks_exact_mut(n).enumerate() {
                        let w = ws.w[start + i];
                        for (r, g) in row.iter_mut().zip(self.g.row(start + i)) {
                            *r = g / w;
                        }
                    }
                }
                Block::Soc { .. } => {
                    let w = &ws.w[start..start + dim];
                    let (mut col, mut out) = ([0.0; SOC_MAX], [0.0; SOC_MAX]);
                    for j in 0..n {
                        for a in 0..dim {
                            col[a] = self.g[(start + a, j)];
                        }
                        apply_winv(w, ws.eta[bi], &col[..dim], &mut out[..dim]);
                        for a in 0..dim {
                            rows[a * n + j] = out[a];
                        }
                    }
                }
            }
        }
        qr_factor(a, rows, n, n, &mut ws.m)
    }

    /// The search direction for the current residuals and `d_s` in `t1`:
    /// `u = λ⧵d_s`, `(P + GᵀW⁻²G) dx + Eᵀ dy = −rx − GᵀW⁻²(rz + W u)`, `E dx = −ry`,
    /// `dz = W⁻²(G dx + rz + W u)`, `ds = W u − W² dz`.
    fn direction_once(&mut self) {
        let (n, p) = (self.n, self.e.nrows());
        for (bi, blk) in self.blocks.iter().enumerate() {
            let (start, dim) = blk.range();
            let lam = &self.ws.lam[start..start + dim];
            let ds = &self.ws.t1[start..start + dim];
            let u = &mut self.ws.u[start..start + dim];
            circ_inv(*blk, lam, ds, u);
            // t2 = rz + W u.
            let w = &self.ws.w[start..start + dim];
            let wu = &mut self.ws.t2[start..start + dim];
            match blk {
                Block::Orthant { .. } => {
                    for k in 0..dim {
                        wu[k] = w[k] * u[k];
                    }
                }
                Block::Soc { .. } => apply_w(w, self.ws.eta[bi], u, wu),
            }
            for k in 0..dim {
                wu[k] += self.ws.rz[start + k];
            }
        }
        // dz (temporarily) = W⁻² t2, then rhs_x = −rx − Gᵀ dz.
        self.apply_winv2();
        for j in 0..n {
            self.ws.rhs_x[j] = -self.ws.rx[j];
        }
        for i in 0..self.g.nrows() {
            let c = self.ws.dz[i];
            if c != 0.0 {
                for (r, a) in self.ws.rhs_x.iter_mut().zip(self.g.row(i)) {
                    *r -= a * c;
                }
            }
        }
        // dx = M⁻¹(rhs − Eᵀ dy), dy = S⁻¹(E M⁻¹ rhs + ry) (E dx = −ry).
        let ws = &mut self.ws;
        forward(&ws.m, n, &mut ws.rhs_x);
        for i in 0..p {
            ws.dy[i] = dot(&ws.y_cols[i * n..i * n + n], &ws.rhs_x) + ws.ry[i];
        }
        if p > 0 {
            forward(&ws.schur, p, &mut ws.dy);
            backward(&ws.schur, p, &mut ws.dy);
        }
        for i in 0..p {
            let c = ws.dy[i];
            for (r, y) in ws.rhs_x.iter_mut().zip(&ws.y_cols[i * n..i * n + n]) {
                *r -= c * y;
            }
        }
        backward(&ws.m, n, &mut ws.rhs_x);
        ws.dx.copy_from_slice(&ws.rhs_x);
        // dz = W⁻²(G dx + rz + W u), ds = W u − W² dz.
        for i in 0..self.g.nrows() {
            self.ws.t2[i] += dot(self.g.row(i), &self.ws.dx);
        }
        self.apply_winv2();
        for (bi, blk) in self.blocks.iter().enumerate() {
            let (start, dim) = blk.range();
            let w = &self.ws.w[start..start + dim];
            let eta = self.ws.eta[bi];
            // ds = W (u − W dz).
            let mut wdz = [0.0; SOC_MAX];
            let mut diff = [0.0; SOC_MAX];
            let dz = &self.ws.dz[start..start + dim];
            match blk {
                Block::Orthant { .. } => {
                    for k in 0..dim {
                        self.ws.ds[start + k] = w[k] * (self.ws.u[start + k] - w[k] * dz[k]);
                    }
                }
                Block::Soc { .. } => {
                    apply_w(w, eta, dz, &mut wdz[..dim]);
                    for k in 0..dim {
                        diff[k] = self.ws.u[start + k] - wdz[k];
                    }
                    apply_w(w, eta, &diff[..dim], &mut self.ws.ds[start..start + dim]);
                }
            }
        }
    }

    /// [`Self::direction_once`] with iterative refinement on the full (unreduced)
    /// system: near the end W⁻² spans many orders of magnitude and the reduced system
    /// alone loses digits that the residuals then show.
    fn direction(&mut self) {
        let (r, p) = (self.s.len(), self.e.nrows());
        let ws = &mut self.ws;
        ws.rx0.copy_from_slice(&ws.rx);
        ws.ry0.copy_from_slice(&ws.ry);
        ws.rz0.copy_from_slice(&ws.rz);
        ws.t10[..r].copy_from_slice(&ws.t1[..r]);
        self.direction_once();
        let size = norm_inf(&self.ws.rx0)
            .max(norm_inf(&self.ws.ry0))
            .max(norm_inf(&self.ws.rz0))
            .max(norm_inf(&self.ws.t10[..r]));
        for _ in 0..REFINEMENT_STEPS {
            let ws = &mut self.ws;
            ws.sdx.copy_from_slice(&ws.dx);
            ws.sdy.copy_from_slice(&ws.dy);
            ws.sdz.copy_from_slice(&ws.dz);
            ws.sds.copy_from_slice(&ws.ds);
            // Errors of the four block equations, as the right-hand side of a correction.
            for j in 0..self.n {
                ws.rx[j] = ws.rx0[j] + self.pdiag[j] * ws.sdx[j];
            }
            for i in 0..p {
                let row = self.e.row(i);
                ws.ry[i] = ws.ry0[i] + dot(row, &ws.sdx);
                for (v, a) in ws.rx.iter_mut().zip(row) {
                    *v += a * ws.sdy[i];
                }
            }
            for i in 0..r {
                let row = self.g.row(i);
                ws.rz[i] = ws.rz0[i] + dot(row, &ws.sdx) + ws.sds[i];
                for (v, a) in ws.rx.iter_mut().zip(row) {
                    *v += a * ws.sdz[i];
                }
            }
            for (bi, blk) in self.blocks.iter().enumerate() {
                let (start, dim) = blk.range();
                let w = &ws.w[start..start + dim];
                let (mut a, mut b, mut c) = ([0.0; SOC_MAX], [0.0; SOC_MAX], [0.0; SOC_MAX]);
                match blk {
                    Block::Orthant { .. } => {
                        for k in start..start + dim {
                            let v = ws.sds[k] / ws.w[k] + ws.w[k] * ws.sdz[k];
                            ws.t1[k] = ws.t10[k] - ws.lam[k] * v;
                        }
                    }
                    Block::Soc { .. } => {
                        let eta = ws.eta[bi];
                        apply_winv(w, eta, &ws.sds[start..start + dim], &mut a[..dim]);
                        apply_w(w, eta, &ws.sdz[start..start + dim], &mut b[..dim]);
                        for k in 0..dim {
                            a[k] += b[k];
                        }
                        circ(*blk, &ws.lam[start..start + dim], &a[..dim], &mut c[..dim]);
                        for k in 0..dim {
                            ws.t1[start + k] = ws.t10[start + k] - c[k];
                        }
                    }
                }
            }
            let error = norm_inf(&ws.rx)
                .max(norm_inf(&ws.ry))
                .max(norm_inf(&ws.rz))
                .max(norm_inf(&ws.t1[..r]));
            if error <= REFINEMENT_TOLERANCE * size {
                break;
            }
            self.direction_once();
            let ws = &mut self.ws;
            for (d, s) in ws.dx.iter_mut().zip(&ws.sdx) {
                *d += s;
            }
            for (d, s) in ws.dy.iter_mut().zip(&ws.sdy) {
                *d += s;
            }
            for (d, s) in ws.dz.iter_mut().zip(&ws.sdz) {
                *d += s;
            }
            for (d, s) in ws.ds.iter_mut().zip(&ws.sds) {
                *d += s;
            }
        }
        let ws = &mut self.ws;
        ws.rx.copy_from_slice(&ws.rx0);
        ws.ry.copy_from_slice(&ws.ry0);
        ws.rz.copy_from_slice(&ws.rz0);
        ws.t1[..r].copy_from_slice(&ws.t10[..r]);
    }

    /// `dz = W⁻² t2`.
    fn apply_winv2(&mut self) {
        for (bi, blk) in self.blocks.iter().enumerate() {
            let (start, dim) = blk.range();
            let w = &self.ws.w[start..start + dim];
            let t = &self.ws.t2[start..start + dim];
            let out = &mut self.ws.dz[start..start + dim];
            match blk {
                Block::Orthant { .. } => {
                    for k in 0..dim {
                        out[k] = t[k] / (w[k] * w[k]);
                    }
                }
                Block::Soc { .. } => {
                    let mut tmp = [0.0; SOC_MAX];
                    let eta = self.ws.eta[bi];
                    apply_winv(w, eta, t, &mut tmp[..dim]);
                    apply_winv(w, eta, &tmp[..dim], out);
                }
            }
        }
    }

    /// The largest step in `(0, 1]` keeping s and z in the cone, times `frac`.
    fn max_step(&self, frac: f64) -> f64 {
        let mut alpha = f64::INFINITY;
        for blk in &self.blocks {
            let (start, dim) = blk.range();
            for (v, d) in [(&self.s, &self.ws.ds), (&self.z, &self.ws.dz)] {
                let (v, d) = (&v[start..start + dim], &d[start..start + dim]);
                match blk {
                    Block::Orthant { .. } => {
                        for k in 0..dim {
                            if d[k] < 0.0 {
                                alpha = alpha.min(-v[k] / d[k]);
                            }
                        }
                    }
                    Block::Soc { .. } => alpha = alpha.min(soc_step(v, d)),
                }
            }
        }
        (frac * alpha).min(1.0)
    }
}

impl Block {
    fn range(&self) -> (usize, usize) {
        match *self {
            Block::Orthant { start, dim } | Block::Soc { start, dim } => (start, dim),
        }
    }
}

/// `t² − ‖x‖²` of `(t, x)`.
fn soc_det(v: &[f64]) -> f64 {
    let t = v[0];
    let x2: f64 = v[1..].iter().map(|a| a * a).sum();
    (t - x2.sqrt()) * (t + x2.sqrt())
}

/// The largest α with `v + α d` in the second-order cone (∞ if it never leaves).
fn soc_step(v: &[f64], d: &[f64]) -> f64 {
    // det(v + α d) = a α² + b α + c, c > 0; the first positive root is where it leaves.
    let a = d[0] * d[0] - d[1..].iter().map(|x| x * x).sum::<f64>();
    let b = 2.0 * (v[0] * d[0] - dot(&v[1..], &d[1..]));
    let c = soc_det(v);
    let mut alpha = f64::INFINITY;
    if a == 0.0 {
        if b < 0.0 {
            alpha = -c / b;
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            for r in [q / a, if q != 0.0 { c / q } else { f64::INFINITY }] {
                if r > 0.0 {
                    alpha = alpha.min(r);
                }
            }
        }
    }
    // The head must stay nonnegative too (det ≥ 0 also holds on the negative cone).
    if d[0] < 0.0 {
        alpha = alpha.min(-v[0] / d[0]);
    }
    alpha
}

/// `u ∘ v` in the block's Jordan algebra.
fn circ(blk: Block, u: &[f64], v: &[f64], out: &mut [f64]) {
    match blk {
        Block::Orthant { .. } => {
            for k in 0..out.len() {
                out[k] = u[k] * v[k];
            }
        }
        Block::Soc { .. } => {
            out[0] = dot(u, v);
            for k in 1..out.len() {
                out[k] = u[0] * v[k] + v[0] * u[k];
            }
        }
    }
}

/// `u` with `λ ∘ u = r`.
fn circ_inv(blk: Block, lam: &[f64], r: &[f64], u: &mut [f64]) {
    match blk {
        Block::Orthant { .. } => {
            for k in 0..u.len() {
                u[k] = r[k] / lam[k];
            }
        }
        Block::Soc { .. } => {
            let det = soc_det(lam);
            u[0] = (lam[0] * r[0] - dot(&lam[1..], &r[1..])) / det;
            for k in 1..u.len() {
                u[k] = (r[k] - u[0] * lam[k]) / lam[0];
            }
        }
    }
}

/// `W v = η W̄ v`, `W̄ = [w0 w1ᵀ; w1 I + w1 w1ᵀ/(1 + w0)]`.
fn apply_w(w: &[f64], eta: f64, v: &[f64], out: &mut [f64]) {
    let w1v1 = dot(&w[1..], &v[1..]);
    out[0] = eta * (w[0] * v[0] + w1v1);
    let c = v[0] + w1v1 / (1.0 + w[0]);
    for k in 1..out.len() {
        out[k] = eta * (v[k] + c * w[k]);
    }
}

/// `W⁻¹ v = η⁻¹ J W̄ J v`.
fn apply_winv(w: &[f64], eta: f64, v: &[f64], out: &mut [f64]) {
    let w1v1 = dot(&w[1..], &v[1..]);
    out[0] = (w[0] * v[0] - w1v1) / eta;
    let c = -v[0] + w1v1 / (1.0 + w[0]);
    for k in 1..out.len() {
        out[k] = (v[k] + c * w[k]) / eta;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nesterov_todd_scaling_maps_z_and_s_to_the_same_point() {
        let s = [2.0, 0.5, -0.7, 0.3];
        let z = [1.5, -0.2, 0.4, 0.9];
        let (ds, dz) = (soc_det(&s), soc_det(&z));
        let (rs, rz) = (ds.sqrt(), dz.sqrt());
        let sz: f64 = s.iter().zip(&z).map(|(a, b)| a * b).sum::<f64>() / (rs * rz);
        let gamma = ((1.0 + sz) / 2.0).sqrt();
        let mut w = [0.0; 4];
        w[0] = (s[0] / rs + z[0] / rz) / (2.0 * gamma);
        for k in 1..4 {
            w[k] = (s[k] / rs - z[k] / rz) / (2.0 * gamma);
        }
        let eta = (ds / dz).sqrt().sqrt();
        let (mut a, mut b, mut back) = ([0.0; 4], [0.0; 4], [0.0; 4]);
        apply_w(&w, eta, &z, &mut a);
        apply_winv(&w, eta, &s, &mut b);
        for k in 0..4 {
            assert!((a[k] - b[k]).abs() < 1e-14, "{a:?} {b:?}");
        }
        apply_winv(&w, eta, &a, &mut back);
        for k in 0..4 {
            assert!((back[k] - z[k]).abs() < 1e-14);
        }
        let blk = Block::Soc { start: 0, dim: 4 };
        let (mut p, mut u) = ([0.0; 4], [0.0; 4]);
        circ(blk, &a, &s, &mut p);
        circ_inv(blk, &a, &p, &mut u);
        for k in 0..4 {
            assert!((u[k] - s[k]).abs() < 1e-13);
        }
    }

    #[test]
    fn the_step_to_the_cone_boundary_lands_on_it() {
        let v = [2.0, 0.5, -0.7];
        let d = [-1.0, 0.8, 0.3];
        let a = soc_step(&v, &d);
        let p: Vec<f64> = v.iter().zip(&d).map(|(x, y)| x + a * y).collect();
        assert!(soc_det(&p).abs() < 1e-12 && p[0] > 0.0, "{p:?}");
    }
}
