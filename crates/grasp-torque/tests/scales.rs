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

/// A row of G or Jᵀ that the rank decision would drop in its block's own scale is zero
/// (`GraspModel`'s `flush_rows`): the geometry fixture's pinch with its first contact
/// moved off the line through the other and the object's origin, by an attometre to
/// 3e-11 of the grasp's size, is the pinch itself, in metres, millimetres and
/// kilometres, on every backend. Before, the moment row about that line (`y f_z`) was
/// equilibrated into a unit row, the constraint `f_z = 0` on the first contact, and the
/// pinch could hold nothing at any offset. Beyond the rank tolerance (3e-8 of its size)
/// the offset is a lever, and the grasp what that lever makes of it: infeasible.
#[test]
fn a_lever_the_rank_tolerance_drops_is_no_lever() {
    let path = format!(
        "{}/../../fixtures/geometry/pinch.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(path).unwrap();
    let pinch = |y: f64| {
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["contacts"][0]["position"][1] = y.into();
        grasp_torque::parse_problem(&v.to_string()).unwrap()
    };
    let runs = [
        (Backend::ActiveSet, Cones::Linear, 1e-9),
        (Backend::ActiveSet, Cones::Exact, 2e-9),
        (Backend::Clarabel, Cones::Exact, 1e-6),
    ];
    for l in [1.0, 1e3, 1e-3] {
        let on_line = rescale(&pinch(0.0), l, 1.0);
        for y in [1e-18, 1e-15, 1e-12] {
            let off = rescale(&pinch(y), l, 1.0);
            for (backend, cones, tol) in runs {
                let (a, b) = (run(&on_line, backend, cones), run(&off, backend, cones));
                assert!(
                    a.is_optimal() && b.is_optimal(),
                    "y {y} l {l} {backend:?} {cones:?}: {:?}",
                    b.reason
                );
                let r = (a.objective - b.objective).abs() / a.objective;
                assert!(
                    r <= tol,
                    "y {y} l {l} {backend:?} {cones:?}: σ {} vs {}",
                    b.objective,
                    a.objective
                );
            }
        }
        let lever = rescale(&pinch(1e-9), l, 1.0);
        for (backend, cones, _) in runs {
            let s = run(&lever, backend, cones);
            assert_eq!(
                s.status,
                grasp_torque::Status::Infeasible,
                "l {l} {backend:?} {cones:?}"
            );
        }
    }
    // Judged contact by contact: with the Allegro pinch's thumb contact a million
    // kilometres up (levers 1e11 times the others'), the moment about the vertical,
    // which that contact's force hardly makes, is still the other contacts'.
    let dir = format!("{}/../../fixtures/hands", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(format!("{dir}/allegro-pinch.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["contacts"][2]["position"][2] = 1e9.into();
    let p = grasp_torque::parse_problem_at(&v.to_string(), std::path::Path::new(&dir))
        .unwrap()
        .problem;
    let model = grasp_torque::GraspModel::new(&p, &Default::default()).unwrap();
    for i in 0..6 {
        assert_eq!(model.stacked_row(i), p.grasp_matrix.row(i), "row {i} of G");
    }
}
