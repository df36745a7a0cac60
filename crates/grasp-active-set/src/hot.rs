//! The hot start as affine maps of the wrench (docs/solver.md, Step 1).
//!
//! With the key set K held, everything a hot solve returns is affine in w: the
//! minimiser `y(w)` and its multipliers `λ(w)` (the factor's solve is linear in `b_K`,
//! and `b = ĉ0 − M w`), the residuals `Ĥ y(w) − b(w)` of every row, and
//! `τ(w) = D⁻¹(u0(w) + N y(w))`. A control loop whose key set stays put then pays one
//! pass over the rows for the residuals (six columns) and O(k + m) for the rest: no
//! factor solve, and no `b(w)`. The maps are built on the second consecutive reuse of
//! a key set (seven factor solves and seven passes), so a key set reused once costs
//! nothing extra. They belong to an ordered key set, not to a factorisation, and are
//! checked against the factor's rows before each use. The answer they give passes
//! the tests of the hot start through the factor, with tolerances no looser, or the
//! solve goes that way.

use crate::{Engine, AMPLIFIED, S_ROW};
use grasp_core::matrix::{add_columns, min_value, norm_inf};
use grasp_core::{Solution, Status};

/// Each map as its constant part and six wrench columns (column-major).
#[derive(Clone, Debug)]
pub(crate) struct HotMap {
    /// The key set, in factor order, that the maps belong to (empty: none yet).
    rows: Vec<usize>,
    /// Consecutive solves that reused their warm key set unchanged.
    streak: usize,
    y0: Vec<f64>,
    yw: Vec<f64>,
    /// Over the key set's positions (`rows.len()` of them).
    l0: Vec<f64>,
    lw: Vec<f64>,
    r0: Vec<f64>,
    rw: Vec<f64>,
    t0: Vec<f64>,
    tw: Vec<f64>,
    /// The key set as sorted rows of H: the answer's active set.
    active: Vec<usize>,
    /// Answers the maps gave (for the tests).
    #[cfg(test)]
    pub(crate) hits: usize,
}

impl HotMap {
    /// Room for `k` reduced variables, key sets of up to `k + 1` rows, `nr` rows and
    /// `m` torques: building a map never allocates.
    pub(crate) fn new(k: usize, nr: usize, m: usize) -> Self {
        let kp = k + 1;
        Self {
            rows: Vec::with_capacity(kp),
            streak: 0,
            y0: vec![0.0; k],
            yw: vec![0.0; 6 * k],
            l0: vec![0.0; kp],
            lw: vec![0.0; 6 * kp],
            r0: vec![0.0; nr],
            rw: vec![0.0; 6 * nr],
            t0: vec![0.0; m],
            tw: vec![0.0; 6 * m],
            active: Vec::with_capacity(kp),
            #[cfg(test)]
            hits: 0,
        }
    }
}

impl Engine {
    /// The hot start through the maps, when they belong to the factor's key set and
    /// their answer for `w` holds every row with non-negative multipliers; false:
    /// solve through the factor.
    pub(crate) fn solve_mapped(&mut self, w: &[f64; 6], out: &mut Solution) -> bool {
        let hm = &self.hot;
        if hm.rows.is_empty() || hm.rows != self.ws.factor.rows() {
            return false;
        }
        let k = self.null_basis.ncols();
        let ws = &mut self.ws;
        let y = &mut ws.z[..k];
        y.copy_from_slice(&hm.y0);
        add_columns(y, &hm.yw, w, 1.0);
        ws.z[k] = 0.0;
        ws.resid.copy_from_slice(&hm.r0);
        add_columns(&mut ws.resid, &hm.rw, w, 1.0);
        // The tolerances of `Iter::feas_tol` and `Iter::multipliers_nonnegative` with
        // ‖y‖∞ for their max(‖b‖∞, ‖y‖∞): no test is passed here that the hot start
        // through the factor would fail, and b(w), one more pass over the rows, is not
        // needed.
        let ynorm = norm_inf(&ws.z[..k]);
        // (Overflow at an extreme wrench: the factor's path decides.)
        if !ws.z[..k].iter().all(|v| v.is_finite())
            || min_value(&ws.resid) < -self.settings.feasibility_tolerance * ynorm
        {
            return false;
        }
        let t = hm.rows.len();
        let lambda = &mut ws.d[..t];
        lambda.copy_from_slice(&hm.l0[..t]);
        add_columns(lambda, &hm.lw[..6 * t], w, 1.0);
        let ltol = self.settings.multiplier_tolerance * ynorm * 10.0;
        // (With the multipliers' sum, for the test below.)
        let mut sum = 0.0;
        if !hm.rows.iter().zip(lambda.iter()).all(|(&r, &l)| {
            if r == S_ROW {
                return true;
            }
            sum += l;
            l >= -ltol
        }) {
            return false;
        }
        // An amplified key set goes through the factor, which refines its answer in τ
        // (`Engine::refine`) and looks again with the rows relaxed (`Engine::relaxed`).
        // (‖y‖₂ ≥ ‖y‖∞: only a sum past the bound on ‖y‖∞ can be amplified.)
        if sum > AMPLIFIED * ynorm {
            let y2: f64 = ws.z[..k].iter().map(|v| v * v).sum();
            if sum * sum > AMPLIFIED * AMPLIFIED * y2 {
                return false;
            }
        }
        out.torque.clear();
        out.torque.extend_from_slice(&hm.t0);
        add_columns(&mut out.torque, &hm.tw, w, 1.0);
        let active = out.cleared_active_set();
        active.extend_from_slice(&hm.active);
        out.multipliers.clear();
        out.multipliers.resize(self.rows.len(), 0.0);
        for (&r, &l) in hm.rows.iter().zip(lambda.iter()) {
            if r != S_ROW {
                // As in `write_solution`: μ = 2 λ / ν on the rows of H.
                out.multipliers[self.h_row[r]] = 2.0 * l.max(0.0) / self.nu[r];
            }
        }
        out.iterations = 0;
        out.status = Status::Optimal;
        #[cfg(test)]
        {
            self.hot.hits += 1;
        }
        true
    }

    /// After a solve through the factor: `kept` when it was a hot start that ended
    /// optimal on its warm key set. The second such solve in a row builds the maps for
    /// that key set (unless they are already there).
    pub(crate) fn note_hot_start(&mut self, kept: bool) {
        if !kept || !self.ws.reusable || !self.ws.factor.contains(S_ROW) {
            self.hot.streak = 0;
            return;
        }
        self.hot.streak += 1;
        if self.hot.streak >= 2 && self.hot.rows != self.ws.factor.rows() {
            self.build_hot_map();
        }
    }

    /// The maps of the factor's key set: the constant part and each wrench column of
    /// `b` through the factor's solve (s pinned at 0), then through Ĥ, N and D⁻¹.
    fn build_hot_map(&mut self) {
        let k = self.null_basis.ncols();
        let (nr, m) = (self.ws.b.len(), self.m);
        let t = self.ws.factor.rows().len();
        let hm = &mut self.hot;
        let ws = &mut self.ws;
        for c in 0..7 {
            // b's constant part (c = 0) or its coefficient of w_{c−1}.
            let (c0n, mn) = (&self.c0n, &self.mn_cols);
            let rhs = |i: usize| match (i, c) {
                (S_ROW, _) => 0.0,
                (_, 0) => c0n[i],
                _ => -mn[(c - 1) * nr + i],
            };
            ws.factor.solve(0.0, true, rhs, &mut ws.zstar);
            let (y, l, r, tau) = if c == 0 {
                (
                    &mut hm.y0[..],
                    &mut hm.l0[..t],
                    &mut hm.r0[..],
                    &mut hm.t0[..],
                )
            } else {
                let j = c - 1;
                (
                    &mut hm.yw[j * k..(j + 1) * k],
                    &mut hm.lw[j * t..(j + 1) * t],
                    &mut hm.rw[j * nr..(j + 1) * nr],
                    &mut hm.tw[j * m..(j + 1) * m],
                )
            };
            y.copy_from_slice(&ws.zstar[..k]);
            for (pos, v) in l.iter_mut().enumerate() {
                *v = ws.factor.lambda(pos);
            }
            // Residuals Ĥ y − b: b's part is −ĉ0 or +M's column.
            for (ri, i) in r.iter_mut().zip(0..nr) {
                *ri = if c == 0 {
                    -self.c0n[i]
                } else {
                    self.mn_cols[(c - 1) * nr + i]
                };
            }
            add_columns(r, &self.a_cols, y, 1.0);
            // τ = D⁻¹(u0 + N y), u0 = P w.
            for (ti, i) in tau.iter_mut().zip(0..m) {
                *ti = if c == 0 {
                    0.0
                } else {
                    self.pu_cols[(c - 1) * m + i]
                };
            }
            add_columns(tau, &self.null_cols, y, 1.0);
            for (ti, d) in tau.iter_mut().zip(&self.dinv) {
                *ti *= d;
            }
        }
        hm.rows.clear();
        hm.rows.extend_from_slice(ws.factor.rows());
        hm.active.clear();
        hm.active.extend(
            hm.rows
                .iter()
                .filter(|&&r| r != S_ROW)
                .map(|&r| self.h_row[r]),
        );
        hm.active.sort_unstable();
        // The factor's multipliers for b(w) again, as the solve left them.
        let b = &ws.b;
        ws.factor.solve(
            0.0,
            true,
            |i| if i == S_ROW { 0.0 } else { b[i] },
            &mut ws.zstar,
        );
    }
}

#[cfg(test)]
mod tests {
    use crate::ActiveSetSolver;
    use grasp_core::matrix::norm_inf;
    use grasp_core::{
        GraspProblem, ModelOptions, Solution, Status, TorqueQp, TorqueSolver, WarmStart,
    };

    fn problems() -> Vec<(String, GraspProblem)> {
        let mut out: Vec<(String, GraspProblem)> = grasp_testkit::fixture_paths(&["", "hands"])
            .into_iter()
            .map(|p| {
                let name = p.display().to_string();
                (name, grasp_io::load(&p).unwrap().problem)
            })
            .collect();
        for case in grasp_testkit::reference_cases() {
            out.push((
                case["name"].as_str().unwrap().to_string(),
                grasp_testkit::reference_problem(&case["problem"]),
            ));
        }
        out
    }

    /// A control loop of wrenches within 1 % of the grasp's, each solved warm from the
    /// last answer: every answer equals a cold solve's to rounding, and most of them
    /// come from the maps once a key set has been reused twice.
    #[test]
    fn mapped_hot_starts_equal_cold_solves() {
        let (mut compared, mut mapped) = (0, 0);
        for (name, problem) in problems() {
            for sides in [4, 8, 16] {
                let mut p = problem.clone();
                p.linearization.sides = sides;
                let qp = TorqueQp::from_problem(&p, &ModelOptions::default()).unwrap();
                let mut hot = ActiveSetSolver::new(qp.clone(), Default::default()).unwrap();
                let mut cold = ActiveSetSolver::new(qp, Default::default()).unwrap();
                let mut rng = grasp_testkit::Rng(0x9e37_79b9 ^ sides as u64);
                let mut last = Solution::default();
                hot.solve_raw(&p.wrench, &WarmStart::default(), &mut last);
                if last.status != Status::Optimal {
                    continue;
                }
                let hits_before = hot.engine.hot.hits;
                for step in 0..12 {
                    // Small steps for a while (the key set settles), then 1 % ones.
                    let size = if step < 4 { 1e-4 } else { 1e-2 };
                    let w: [f64; 6] = std::array::from_fn(|i| {
                        p.wrench[i] * (1.0 + size * rng.uniform(-1.0, 1.0))
                    });
                    let warm = WarmStart {
                        torque: Some(&last.torque),
                        active_set: last.active_set.as_deref(),
                    };
                    let mut now = Solution::default();
                    hot.solve_raw(&w, &warm, &mut now);
                    let mut reference = Solution::default();
                    cold.solve_raw(&w, &WarmStart::default(), &mut reference);
                    assert_eq!(
                        now.status, reference.status,
                        "{name} N = {sides} step {step}"
                    );
                    if now.status == Status::Optimal {
                        let scale = norm_inf(&reference.torque).max(1e-12 * norm_inf(&w));
                        let diff = now
                            .torque
                            .iter()
                            .zip(&reference.torque)
                            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
                        assert!(
                            diff <= 1e-9 * scale,
                            "{name} N = {sides} step {step}: torques differ by {diff:.2e} (scale {scale:.2e})"
                        );
                        // The multipliers too, where the key sets agree (degenerate
                        // grasps may end on another set with the same torques).
                        if now.active_set == reference.active_set {
                            let mscale = norm_inf(&reference.multipliers);
                            for (a, b) in now.multipliers.iter().zip(&reference.multipliers) {
                                assert!(
                                    (a - b).abs() <= 1e-8 * mscale,
                                    "{name} N = {sides} step {step}: multipliers {a} vs {b}"
                                );
                            }
                        }
                        compared += 1;
                        last = now;
                    } else {
                        last = reference;
                    }
                }
                mapped += hot.engine.hot.hits - hits_before;
            }
        }
        assert!(compared > 1000, "only {compared} answers compared");
        assert!(
            mapped * 4 > compared,
            "the maps answered {mapped} of {compared} hot starts"
        );
    }
}
