//! Clarabel backend: the torque problem with any mix of exact cones (an SOCP) and
//! inscribed cones (linear rows), solved by Clarabel's interior-point method.
//!
//! The variables are τ, the free internal forces ξ (when the model leaves them free)
//! and, per exact SFCl contact, two auxiliaries. `f = Z1 w + Z2 τ + N ξ` is substituted,
//! so every row is affine in the variables. Clarabel's form is `A x + s = b`, `s ∈ K`.
//!
//! Rows, all read from the [`TorqueQp`] view and its typed cone blocks:
//! - the consistency equalities `C τ = e(w)` (zero cone);
//! - the linear rows `H τ + Hp ξ ≥ c(w)`: inscribed faces, every contact's minimum
//!   normal force `fz ≥ f_min`, and the torque limits (nonnegative cone);
//! - per exact contact: PCwF `(mu·fz, fx, fy)` ∈ SOC(3); SFCe
//!   `(fz, fx/mu, fy/mu, mz/mu_torsion)` ∈ SOC(4); SFCl `(mu·a, fx, fy)` ∈ SOC(3),
//!   `b ≥ |mz|/mu_torsion` and `a + b ≤ fz`, which is `‖f_t‖/mu + |mz|/mu_torsion ≤ fz`
//!   without shifting the cone by the minimum normal force.
//!
//! **Scaling.** An interior-point method stops on absolute and relative tolerances, so
//! the data are scaled before Clarabel sees them: every row is in force units (`mz`
//! counted as `mz/mu_torsion`), the torques are scaled to `k √w_j τ_j` (the objective
//! becomes `‖x‖²`, with k putting x in force units), the free internal forces by their
//! force response, and every solve divides the right-hand side by its own magnitude α (the
//! problem is homogeneous: `(w, f_min, τmax) → α(…)` gives `τ → α τ`). The answer is
//! unscaled afterwards, so it is the same in any units and at any load.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use grasp_core::matrix::{dot, norm2};
use grasp_core::{
    Capabilities, ConeRepr, ContactModel, Reason, RowId, Solution, Status, TorqueQp, TorqueSolver,
    WarmStart,
};

/// What the Clarabel backend supports.
pub const CAPABILITIES: Capabilities = Capabilities {
    exact_cones: true,
    free_internal_forces: true,
    warm_key_set: false,
    warm_torque: false,
};

/// Relative accuracy of Clarabel's answers at the default settings: the tolerance of
/// the core's final residual check.
pub const RESIDUAL_TOLERANCE: f64 = 1e-7;

/// Settings passed to Clarabel. The defaults reach 1e-8 relative accuracy in σ on the
/// reference cases. Tolerances apply to the scaled problem (see the crate docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClarabelSettings {
    /// Absolute duality-gap tolerance. Default 1e-10.
    pub tol_gap_abs: f64,
    /// Relative duality-gap tolerance. Default 1e-10.
    pub tol_gap_rel: f64,
    /// Feasibility tolerance. Default 1e-10.
    pub tol_feas: f64,
    /// Iteration cap. Default 200.
    pub max_iter: u32,
}

impl Default for ClarabelSettings {
    fn default() -> Self {
        Self {
            tol_gap_abs: 1e-10,
            tol_gap_rel: 1e-10,
            tol_feas: 1e-10,
            max_iter: 200,
        }
    }
}

/// Clarabel rejected the settings.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("Clarabel settings: {0}")]
pub struct ClarabelError(pub String);

impl ClarabelSettings {
    fn build(&self) -> Result<DefaultSettings<f64>, ClarabelError> {
        DefaultSettingsBuilder::default()
            .verbose(false)
            .tol_gap_abs(self.tol_gap_abs)
            .tol_gap_rel(self.tol_gap_rel)
            .tol_feas(self.tol_feas)
            .max_iter(self.max_iter)
            .build()
            .map_err(|e| ClarabelError(e.to_string()))
    }
}

/// One affine row `a·x + s = b0 + bw·w`, before assembly.
struct Row {
    a: Vec<f64>,
    b0: f64,
    bw: [f64; 6],
}

/// The Clarabel backend for one grasp.
pub struct ClarabelSolver {
    qp: TorqueQp,
    settings: DefaultSettings<f64>,
    p: CscMatrix<f64>,
    q: Vec<f64>,
    a: CscMatrix<f64>,
    b0: Vec<f64>,
    bw: Vec<[f64; 6]>,
    b: Vec<f64>,
    cones: Vec<SupportedConeT<f64>>,
    /// Variable scale: x = scale ⊙ (τ, ξ) / α.
    col_scale: Vec<f64>,
    /// Objective normalisation κ.
    kappa: f64,
    /// The linear rows of the view start here, each scaled by `row_scale`.
    linear_at: usize,
    row_scale: Vec<f64>,
    solver: Option<DefaultSolver<f64>>,
}

impl ClarabelSolver {
    /// Assembles the conic problem of `qp` (exact blocks become second-order cones).
    pub fn new(qp: TorqueQp, settings: ClarabelSettings) -> Result<Self, ClarabelError> {
        let settings = settings.build()?;
        let model = qp.model.clone();
        let (m, d) = (model.joints(), model.free_dim());
        let n_aux = 2 * qp
            .contacts
            .iter()
            .zip(&qp.constraints.cones)
            .filter(|(c, r)| {
                matches!(r, ConeRepr::Exact) && matches!(c.model, ContactModel::SfcLinear { .. })
            })
            .count();
        let nx = m + d + n_aux;
        // Force-unit metric: mz counts as mz/mu_torsion.
        let mut fscale = vec![1.0; model.force_dim()];
        for c in &qp.contacts {
            if let ContactModel::SfcLinear { mu_torsion, .. }
            | ContactModel::SfcElliptic { mu_torsion, .. } = c.model
            {
                fscale[c.offset + 3] = 1.0 / mu_torsion;
            }
        }
        // Column scales: the force response of a unit of each variable. A variable
        // with no response at rounding level (a joint that moves no contact) takes the
        // largest scale, so that its rounding-level column does not blow up.
        let mut col_scale: Vec<f64> = (0..nx)
            .map(|j| {
                if j >= m + d {
                    return 1.0;
                }
                let v: Vec<f64> = (0..model.force_dim())
                    .map(|i| {
                        fscale[i]
                            * if j < m {
                                model.z2[(i, j)]
                            } else {
                                model.passive_basis[(i, j - m)]
                            }
                    })
                    .collect();
                norm2(&v)
            })
            .collect();
        let largest = col_scale[m..m + d].iter().copied().fold(0.0, f64::max);
        for s in &mut col_scale[m..m + d] {
            if s.is_nan() || *s <= 1e3 * f64::EPSILON * largest {
                *s = if largest > 0.0 { largest } else { 1.0 };
            }
        }
        // Torques: x_j = k √w_j τ_j, so that the objective is ‖x‖² (a least-distance
        // problem, P = 2I) and k = max_j (response_j / √w_j) puts x in force units.
        let k = (0..m)
            .map(|j| col_scale[j] / model.weights[j].sqrt())
            .fold(0.0, f64::max);
        let k = if k > 0.0 && k.is_finite() { k } else { 1.0 };
        for j in 0..m {
            col_scale[j] = k * model.weights[j].sqrt();
        }
        // A row "v·f + k ≥ 0" (v on force components, already in force units).
        let force_row = |v: &[(usize, f64)], k: f64| -> Row {
            let mut a = vec![0.0; nx];
            let mut bw = [0.0; 6];
            for &(i, c) in v {
                for j in 0..m {
                    a[j] -= c * model.z2[(i, j)] / col_scale[j];
                }
                for j in 0..d {
                    a[m + j] -= c * model.passive_basis[(i, j)] / col_scale[m + j];
                }
                for (bj, z) in bw.iter_mut().zip(model.z1.row(i)) {
                    *bj += c * z;
                }
            }
            Row { a, b0: k, bw }
        };
        let mut zero = Vec::new();
        for i in 0..model.equality_rows() {
            // C τ = −eq_w w, each row normalised in the scaled variables.
            let mut a: Vec<f64> = (0..nx)
                .map(|j| {
                    if j < m {
                        model.eq[(i, j)] / col_scale[j]
                    } else {
                        0.0
                    }
                })
                .collect();
            let nrm = norm2(&a).max(f64::MIN_POSITIVE);
            a.iter_mut().for_each(|v| *v /= nrm);
            let mut bw = [0.0; 6];
            for (j, v) in bw.iter_mut().enumerate() {
                *v = -model.eq_w[(i, j)] / nrm;
            }
            zero.push(Row { a, b0: 0.0, bw });
        }
        // The linear rows of the view: −(H τ + Hp ξ) + s = −c0 + hw·w, in force units.
        let linear_at = zero.len();
        let mut nonneg = Vec::new();
        let mut row_scale = Vec::with_capacity(qp.inequality_rows());
        for i in 0..qp.inequality_rows() {
            let rho = match qp.rows[i] {
                RowId::TorqueLimit { joint, .. } => col_scale[joint],
                _ => 1.0,
            };
            let mut a = vec![0.0; nx];
            for j in 0..m {
                a[j] = -rho * qp.h[(i, j)] / col_scale[j];
            }
            for j in 0..d {
                a[m + j] = -rho * qp.hp[(i, j)] / col_scale[m + j];
            }
            let mut bw = [0.0; 6];
            for (j, v) in bw.iter_mut().enumerate() {
                *v = rho * qp.hw[(i, j)];
            }
            nonneg.push(Row {
                a,
                b0: -rho * qp.c0[i],
                bw,
            });
            row_scale.push(rho);
        }
        let mut socs: Vec<Vec<Row>> = Vec::new();
        let mut aux = m + d;
        for (c, repr) in qp.contacts.iter().zip(&qp.constraints.cones) {
            if !matches!(repr, ConeRepr::Exact) {
                continue;
            }
            let o = c.offset;
            let (x, y, z, t) = (o, o + 1, o + 2, o + 3);
            match c.model {
                // fz ≥ f_min ≥ 0 is already a linear row.
                ContactModel::Fpc => {}
                ContactModel::Pcwf { mu } => socs.push(vec![
                    force_row(&[(z, mu)], 0.0),
                    force_row(&[(x, 1.0)], 0.0),
                    force_row(&[(y, 1.0)], 0.0),
                ]),
                ContactModel::SfcElliptic { mu, mu_torsion } => socs.push(vec![
                    force_row(&[(z, 1.0)], 0.0),
                    force_row(&[(x, 1.0 / mu)], 0.0),
                    force_row(&[(y, 1.0 / mu)], 0.0),
                    force_row(&[(t, 1.0 / mu_torsion)], 0.0),
                ]),
                ContactModel::SfcLinear { mu, mu_torsion } => {
                    // a ≥ ‖f_t‖/mu, b ≥ |mz|/mu_torsion, a + b ≤ fz (a, b in force units).
                    let (sa, sb) = (aux, aux + 1);
                    aux += 2;
                    let mut top = Row {
                        a: vec![0.0; nx],
                        b0: 0.0,
                        bw: [0.0; 6],
                    };
                    top.a[sa] = -mu;
                    socs.push(vec![
                        top,
                        force_row(&[(x, 1.0)], 0.0),
                        force_row(&[(y, 1.0)], 0.0),
                    ]);
                    for sign in [-1.0, 1.0] {
                        let mut row = force_row(&[(t, sign / mu_torsion)], 0.0);
                        row.a[sb] -= 1.0;
                        nonneg.push(row);
                    }
                    let mut row = force_row(&[(z, 1.0)], 0.0);
                    row.a[sa] += 1.0;
                    row.a[sb] += 1.0;
                    nonneg.push(row);
                }
            }
        }
        let mut cones = Vec::new();
        let mut rows = Vec::new();
        if !zero.is_empty() {
            cones.push(SupportedConeT::ZeroConeT(zero.len()));
            rows.extend(zero);
        }
        if !nonneg.is_empty() {
            cones.push(SupportedConeT::NonnegativeConeT(nonneg.len()));
            rows.extend(nonneg);
        }
        for soc in socs {
            cones.push(SupportedConeT::SecondOrderConeT(soc.len()));
            rows.extend(soc);
        }
        let (mut ii, mut jj, mut vv) = (Vec::new(), Vec::new(), Vec::new());
        for (i, r) in rows.iter().enumerate() {
            for (j, &v) in r.a.iter().enumerate() {
                if v != 0.0 {
                    ii.push(i);
                    jj.push(j);
                    vv.push(v);
                }
            }
        }
        let a = CscMatrix::new_from_triplets(rows.len(), nx, ii, jj, vv);
        // ½ xᵀ P x = ‖x_τ‖² = Σ w_j τ_j² / (α² κ) with κ = 1/k².
        let kappa = 1.0 / (k * k);
        let p =
            CscMatrix::new_from_triplets(nx, nx, (0..m).collect(), (0..m).collect(), vec![2.0; m]);
        Ok(Self {
            settings,
            p,
            q: vec![0.0; nx],
            b: vec![0.0; rows.len()],
            b0: rows.iter().map(|r| r.b0).collect(),
            bw: rows.iter().map(|r| r.bw).collect(),
            a,
            cones,
            col_scale,
            kappa,
            linear_at,
            row_scale,
            solver: None,
            qp,
        })
    }

    /// Whether any contact uses its exact cone.
    pub fn is_exact(&self) -> bool {
        self.qp.constraints.has_exact()
    }

    /// Solves the data in `self.b` with a reused or fresh solver.
    fn run(&mut self, fresh: bool) -> Result<(), String> {
        let reused = !fresh
            && match self.solver.as_mut() {
                Some(s) if s.is_data_update_allowed() => s.update_b(&self.b).is_ok(),
                _ => false,
            };
        if !reused {
            let s = DefaultSolver::new(
                &self.p,
                &self.q,
                &self.a,
                &self.b,
                &self.cones,
                self.settings.clone(),
            )
            .map_err(|e| format!("Clarabel setup: {e}"))?;
            self.solver = Some(s);
        }
        if let Some(s) = self.solver.as_mut() {
            s.solve();
        }
        Ok(())
    }

    fn status(&self) -> SolverStatus {
        self.solver
            .as_ref()
            .map_or(SolverStatus::Unsolved, |s| s.solution.status)
    }
}

fn backend(message: String) -> Option<Reason> {
    Some(Reason::Backend {
        backend: "clarabel",
        message,
    })
}

impl TorqueSolver for ClarabelSolver {
    fn name(&self) -> &'static str {
        "clarabel"
    }

    fn capabilities(&self) -> Capabilities {
        CAPABILITIES
    }

    fn residual_tolerance(&self) -> f64 {
        RESIDUAL_TOLERANCE
    }

    fn problem(&self) -> &TorqueQp {
        &self.qp
    }

    fn solve_raw(&mut self, w: &[f64; 6], _warm: &WarmStart<'_>, out: &mut Solution) {
        let model = self.qp.model.clone();
        let (m, d) = (model.joints(), model.free_dim());
        out.active_set = None;
        out.torque.clear();
        out.iterations = 0;
        for (i, b) in self.b.iter_mut().enumerate() {
            *b = self.b0[i] + dot(&self.bw[i], w);
        }
        let alpha = self.b.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if alpha == 0.0 {
            // Every row is homogeneous: τ = 0 is feasible and optimal.
            out.status = Status::Optimal;
            out.torque.resize(m, 0.0);
            out.internal_forces.resize(d, 0.0);
            return;
        }
        self.b.iter_mut().for_each(|v| *v /= alpha);
        if let Err(e) = self.run(false) {
            out.status = Status::NumericalFailure;
            out.reason = backend(e);
            return;
        }
        // A reused factorisation must not change the answer: retry a failure fresh.
        if !matches!(
            self.status(),
            SolverStatus::Solved
                | SolverStatus::PrimalInfeasible
                | SolverStatus::AlmostPrimalInfeasible
        ) {
            if let Err(e) = self.run(true) {
                out.status = Status::NumericalFailure;
                out.reason = backend(e);
                return;
            }
        }
        let Some(solver) = self.solver.as_ref() else {
            return;
        };
        let sol = &solver.solution;
        out.iterations = sol.iterations as usize;
        let exact = self.qp.constraints.has_exact();
        let (status, reason) = match sol.status {
            SolverStatus::Solved => (Status::Optimal, None),
            SolverStatus::AlmostSolved => (Status::AlmostOptimal, None),
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => (
                Status::Infeasible,
                backend(format!(
                    "a certificate of primal infeasibility ({:?}): no torque keeps every contact force inside its {} cone while balancing the wrench",
                    sol.status,
                    if exact { "exact" } else { "linearised" }
                )),
            ),
            SolverStatus::MaxIterations | SolverStatus::MaxTime => (
                Status::IterationLimit,
                backend(format!("stopped: {:?}", sol.status)),
            ),
            other => (Status::NumericalFailure, backend(format!("stopped: {other:?}"))),
        };
        out.status = status;
        out.reason = reason;
        if status.has_answer() {
            out.torque
                .extend((0..m).map(|j| sol.x[j] * alpha / self.col_scale[j]));
            out.internal_forces
                .extend((0..d).map(|j| sol.x[m + j] * alpha / self.col_scale[m + j]));
            if !exact {
                // μ_i = z_i ρ_i α κ for Σ w τ² on the rows H τ ≥ c.
                let rows = self.qp.inequality_rows();
                out.multipliers.extend(
                    (0..rows).map(|i| {
                        sol.z[self.linear_at + i] * self.row_scale[i] * alpha * self.kappa
                    }),
                );
            }
        }
    }
}
