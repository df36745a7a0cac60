//! The scale sweep of issue 14: on every bundled fixture, the wrench scaled by 10^k for
//! k in −9…9 and lengths in m, mm and km, every backend and both cone kinds (the
//! native exact solver's closed form and its Newton method among them) agree with
//! the unscaled answer (σ scales by (α l)², exactly up to each backend's accuracy),
//! and exact cones are never infeasible where an inscribed linearisation is feasible.
#![cfg(all(feature = "active-set", feature = "clarabel"))]

use grasp_testkit::rescale;
use grasp_torque::{Backend, Cones, GraspProblem, Solution};

mod common;
use common::run;

fn fixtures() -> Vec<(String, GraspProblem)> {
    let mut out: Vec<_> = grasp_testkit::fixture_paths(&["", "table1", "geometry"])
        .into_iter()
        .map(|path| {
            let mut p = grasp_torque::load_problem(&path).unwrap();
            // The unit-invariant defaults: the reference set's conventions
            // (`euclidean`, the paper's SFCe spacing) depend on the unit of length.
            p.internal_forces = Default::default();
            p.linearization.sfce_spacing = Default::default();
            (path.display().to_string(), p)
        })
        .collect();
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

#[test]
fn every_backend_agrees_at_every_scale() {
    // (The native exact answers are certified to a gap of 1e-9 each: two of them
    // agree within twice that.)
    let runs = [
        (Backend::ActiveSet, Cones::Linear, 1e-9),
        (Backend::Clarabel, Cones::Linear, 1e-6),
        (Backend::Clarabel, Cones::Exact, 1e-6),
        (Backend::ActiveSet, Cones::Exact, 2e-9),
    ];
    let mut checked = 0;
    let all = fixtures();
    assert!(all.len() >= 13);
    let expected = all.len() * 3 * 19 * runs.len();
    for (name, p) in all {
        let base: Vec<Solution> = runs.iter().map(|&(b, c, _)| run(&p, b, c)).collect();
        assert!(base[0].is_optimal(), "{name}: {:?}", base[0].reason);
        for l in [1.0, 1e3, 1e-3] {
            for k in -9..=9 {
                let alpha = 10f64.powi(k);
                let q = rescale(&p, l, alpha);
                let factor = (l * alpha) * (l * alpha);
                let sols: Vec<Solution> = runs.iter().map(|&(b, c, _)| run(&q, b, c)).collect();
                for ((s, b0), &(backend, cones, tol)) in sols.iter().zip(&base).zip(&runs) {
                    let at = format!("{name} l = {l:e} α = {alpha:e} {backend}/{cones}");
                    assert!(s.is_optimal(), "{at}: {:?} {:?}", s.status, s.reason);
                    let want = b0.objective * factor;
                    assert!(
                        (s.objective - want).abs() <= tol * want.abs(),
                        "{at}: σ = {} against {want}",
                        s.objective
                    );
                    checked += 1;
                }
                // Inscribed cones: σ* ≤ σ(N).
                assert!(sols[2].objective <= sols[0].objective * (1.0 + 1e-6));
            }
        }
    }
    assert_eq!(checked, expected);
}
