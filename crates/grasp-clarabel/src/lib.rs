//! Clarabel backend: the torque problem on the exact friction cones (an SOCP), or on the
//! same linearised cones as the native solver (a QP with a nonnegative cone), solved by
//! Clarabel's interior-point method.
//!
//! One variable vector holds τ (and, for SFCl contacts, two auxiliaries each);
//! `f = Z1 w + Z2 τ` is substituted, so every cone row is affine in τ. The consistency
//! equalities form a zero cone. Clarabel's form is `A x + s = b`, `s ∈ K`.
//!
//! Exact cones per contact:
//! - FPC: `fz ≥ f_min` (nonnegative cone).
//! - PCwF: `(mu·fz, fx, fy)` in a 3-dimensional second-order cone.
//! - SFCl: `s ≥ ‖(fx, fy)‖` (SOC), `r ≥ |mz|` (two rows), `s/mu + r/mu_torsion ≤ fz`;
//!   `s`, `r` are kept out of the objective and out of the reported τ.
//! - SFCe: `(fz, fx/mu, fy/mu, mz/mu_torsion)` in a 4-dimensional second-order cone.
//!
//! Minimum normal forces and torque limits are linear rows in both modes.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use grasp_core::matrix::dot;
use grasp_core::{
    ContactModel, Reason, RowKind, Solution, Status, TorqueQp, TorqueSolver, WarmStart,
};

/// Settings passed to Clarabel. The defaults reach 1e-8 relative accuracy in σ on the
/// reference cases.
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

/// Clarabel rejected the settings or the problem's data.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ClarabelError(pub String);

impl ClarabelSettings {
    fn build(&self) -> Result<DefaultSettings<f64>, ClarabelError> {
        let s = DefaultSettingsBuilder::default()
            .verbose(false)
            .tol_gap_abs(self.tol_gap_abs)
            .tol_gap_rel(self.tol_gap_rel)
            .tol_feas(self.tol_feas)
            .max_iter(self.max_iter)
            .build()
            .map_err(|e| ClarabelError(e.to_string()))?;
        Ok(s)
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
    exact: bool,
    settings: DefaultSettings<f64>,
    p: CscMatrix<f64>,
    q: Vec<f64>,
    a: CscMatrix<f64>,
    b0: Vec<f64>,
    bw: Vec<[f64; 6]>,
    b: Vec<f64>,
    cones: Vec<SupportedConeT<f64>>,
    /// In linear mode, the rows of H in the nonnegative cone start here.
    h_rows_at: usize,
    solver: Option<DefaultSolver<f64>>,
}

impl ClarabelSolver {
    /// Assembles the conic problem; `exact` selects the exact cones.
    pub fn new(
        qp: TorqueQp,
        exact: bool,
        settings: ClarabelSettings,
    ) -> Result<Self, ClarabelError> {
        let settings = settings.build()?;
        let m = qp.joints();
        let n_aux = if exact {
            2 * qp
                .contacts
                .iter()
                .filter(|c| matches!(c.model, ContactModel::SfcLinear { .. }))
                .count()
        } else {
            0
        };
        let nx = m + n_aux;
        let mut zero = Vec::new();
        for i in 0..qp.equality_rows() {
            // C τ = e(w) = −eq_w w.
            let mut bw = [0.0; 6];
            for (j, v) in bw.iter_mut().enumerate() {
                *v = -qp.eq_w[(i, j)];
            }
            zero.push(Row {
                a: pad(qp.eq.row(i), nx),
                b0: 0.0,
                bw,
            });
        }
        let mut nonneg = Vec::new();
        let mut socs: Vec<Vec<Row>> = Vec::new();
        // A row "v·f + k ≥ 0" with f = Z1 w + Z2 τ: −(v Z2)·τ + s = k + (v Z1)·w.
        let force_row = |v: &[(usize, f64)], k: f64| -> Row {
            let mut a = vec![0.0; nx];
            let mut bw = [0.0; 6];
            for &(i, c) in v {
                for (aj, z) in a.iter_mut().zip(qp.z2.row(i)) {
                    *aj -= c * z;
                }
                for (bj, z) in bw.iter_mut().zip(qp.z1.row(i)) {
                    *bj += c * z;
                }
            }
            Row { a, b0: k, bw }
        };
        let h_rows_at;
        if exact {
            let mut aux = m;
            for c in &qp.contacts {
                let o = c.offset;
                let fmin = qp.c0[c.first_row + c.rows - 1];
                let (x, y, z, t) = (o, o + 1, o + 2, o + 3);
                match c.model {
                    ContactModel::Fpc => nonneg.push(force_row(&[(o, 1.0)], -fmin)),
                    ContactModel::Pcwf { mu } => {
                        socs.push(vec![
                            force_row(&[(z, mu)], 0.0),
                            force_row(&[(x, 1.0)], 0.0),
                            force_row(&[(y, 1.0)], 0.0),
                        ]);
                        if fmin > 0.0 {
                            nonneg.push(force_row(&[(z, 1.0)], -fmin));
                        }
                    }
                    ContactModel::SfcElliptic { mu, mu_torsion } => {
                        socs.push(vec![
                            force_row(&[(z, 1.0)], 0.0),
                            force_row(&[(x, 1.0 / mu)], 0.0),
                            force_row(&[(y, 1.0 / mu)], 0.0),
                            force_row(&[(t, 1.0 / mu_torsion)], 0.0),
                        ]);
                        if fmin > 0.0 {
                            nonneg.push(force_row(&[(z, 1.0)], -fmin));
                        }
                    }
                    ContactModel::SfcLinear { mu, mu_torsion } => {
                        let (s, r) = (aux, aux + 1);
                        aux += 2;
                        let unit = |j: usize, c: f64| {
                            let mut a = vec![0.0; nx];
                            a[j] = -c;
                            a
                        };
                        // (s, fx, fy) ∈ SOC: s = s_var.
                        socs.push(vec![
                            Row {
                                a: unit(s, 1.0),
                                b0: 0.0,
                                bw: [0.0; 6],
                            },
                            force_row(&[(x, 1.0)], 0.0),
                            force_row(&[(y, 1.0)], 0.0),
                        ]);
                        // r − mz ≥ 0, r + mz ≥ 0.
                        for sign in [-1.0, 1.0] {
                            let mut row = force_row(&[(t, sign)], 0.0);
                            row.a[r] -= 1.0;
                            nonneg.push(row);
                        }
                        // fz − s/mu − r/mu_torsion ≥ f_min.
                        let mut row = force_row(&[(z, 1.0)], -fmin);
                        row.a[s] += 1.0 / mu;
                        row.a[r] += 1.0 / mu_torsion;
                        nonneg.push(row);
                    }
                }
            }
            h_rows_at = usize::MAX;
            for (i, kind) in qp.row_kinds.iter().enumerate() {
                if matches!(kind, RowKind::TorqueLimit { .. }) {
                    nonneg.push(h_row(&qp, i, nx));
                }
            }
        } else {
            h_rows_at = zero.len();
            for i in 0..qp.inequality_rows() {
                nonneg.push(h_row(&qp, i, nx));
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
        // ½ xᵀ P x = Σ w_j τ_j².
        let p = CscMatrix::new_from_triplets(
            nx,
            nx,
            (0..m).collect(),
            (0..m).collect(),
            qp.weights.iter().map(|w| 2.0 * w).collect(),
        );
        Ok(Self {
            exact,
            settings,
            p,
            q: vec![0.0; nx],
            b: vec![0.0; rows.len()],
            b0: rows.iter().map(|r| r.b0).collect(),
            bw: rows.iter().map(|r| r.bw).collect(),
            a,
            cones,
            h_rows_at,
            solver: None,
            qp,
        })
    }

    /// Whether this solver uses the exact cones.
    pub fn is_exact(&self) -> bool {
        self.exact
    }
}

fn pad(v: &[f64], n: usize) -> Vec<f64> {
    let mut a = v.to_vec();
    a.resize(n, 0.0);
    a
}

/// Row i of `H τ ≥ c(w)`: `−H_i τ + s = −c0_i + hw_i·w`.
fn h_row(qp: &TorqueQp, i: usize, nx: usize) -> Row {
    let a: Vec<f64> = pad(qp.h.row(i), nx).iter().map(|v| -v).collect();
    let mut bw = [0.0; 6];
    bw.copy_from_slice(qp.hw.row(i));
    Row {
        a,
        b0: -qp.c0[i],
        bw,
    }
}

impl TorqueSolver for ClarabelSolver {
    fn name(&self) -> &'static str {
        "clarabel"
    }

    fn problem(&self) -> &TorqueQp {
        &self.qp
    }

    fn solve_raw(&mut self, w: &[f64; 6], _warm: &WarmStart<'_>, out: &mut Solution) {
        for (i, b) in self.b.iter_mut().enumerate() {
            *b = self.b0[i] + dot(&self.bw[i], w);
        }
        // Reuse the factored solver when only b changes; otherwise build anew.
        let reused = match self.solver.as_mut() {
            Some(s) if s.is_data_update_allowed() => s.update_b(&self.b).is_ok(),
            _ => false,
        };
        if !reused {
            match DefaultSolver::new(
                &self.p,
                &self.q,
                &self.a,
                &self.b,
                &self.cones,
                self.settings.clone(),
            ) {
                Ok(s) => self.solver = Some(s),
                Err(e) => {
                    out.status = Status::NumericalFailure;
                    out.reason = Some(Reason::Backend(format!("Clarabel setup: {e}")));
                    out.torque.clear();
                    out.active_set = None;
                    return;
                }
            }
        }
        let Some(solver) = self.solver.as_mut() else {
            return;
        };
        solver.solve();
        let sol = &solver.solution;
        let m = self.qp.joints();
        out.iterations = sol.iterations as usize;
        out.active_set = None;
        out.torque.clear();
        let (status, reason) = match sol.status {
            SolverStatus::Solved => (Status::Optimal, None),
            SolverStatus::AlmostSolved => {
                out.warnings.push("Clarabel: almost solved (reduced accuracy)".into());
                (Status::Optimal, None)
            }
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => (
                Status::Infeasible,
                Some(Reason::Backend(format!(
                    "Clarabel found a certificate of primal infeasibility ({:?}): no torque keeps every contact force inside its {} cone while balancing the wrench",
                    sol.status,
                    if self.exact { "exact" } else { "linearised" }
                ))),
            ),
            SolverStatus::MaxIterations | SolverStatus::MaxTime => (
                Status::IterationLimit,
                Some(Reason::Backend(format!("Clarabel stopped: {:?}", sol.status))),
            ),
            other => (
                Status::NumericalFailure,
                Some(Reason::Backend(format!("Clarabel stopped: {other:?}"))),
            ),
        };
        out.status = status;
        out.reason = reason;
        if status == Status::Optimal {
            out.torque.extend_from_slice(&sol.x[..m]);
            if !self.exact {
                let rows = self.qp.inequality_rows();
                out.multipliers
                    .extend_from_slice(&sol.z[self.h_rows_at..self.h_rows_at + rows]);
            }
        }
    }
}
