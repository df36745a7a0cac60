//! Backends agree: property tests on synthetic grasps (all four contact models mixed)
//! and the reference cases' exact and linearised objectives.
#![cfg(feature = "clarabel")]

use grasp_testkit::{synthetic_grasp, SynthSpec};
use grasp_torque::matrix::norm_inf;
use grasp_torque::{Backend, Cones, GraspProblem, Solution, Status};
use proptest::prelude::*;

mod common;
use common::run;

fn problem(seed: u64, sides: usize) -> GraspProblem {
    let mut spec = SynthSpec::default();
    spec.linearization.sides = sides;
    synthetic_grasp(seed, &spec).into_problem().unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

/// Every optimal answer holds the object, satisfies the consistency equalities and
/// stays in its cones: the exact ones for exact backends, the linearised rows otherwise.
fn physically_consistent(
    p: &GraspProblem,
    s: &Solution,
    cones: Cones,
) -> Result<(), TestCaseError> {
    let d = &s.diagnostics;
    let scale = norm_inf(&p.wrench)
        .max(norm_inf(&s.contact_forces))
        .max(1e-12);
    // Interior-point answers are accurate to their tolerance (1e-10), not to rounding.
    let tol = 1e-7 * scale;
    prop_assert!(
        d.wrench_residual <= tol,
        "‖Gf − w‖∞ = {}",
        d.wrench_residual
    );
    prop_assert!(
        d.consistency_residual <= tol,
        "‖Cτ − e‖∞ = {}",
        d.consistency_residual
    );
    match cones {
        Cones::Linear => prop_assert!(
            d.max_violation <= tol,
            "linearised violation {}",
            d.max_violation
        ),
        Cones::Exact => {
            // Absolute cone violation `g(f) − fz` in force units: the scale-free margin
            // turns a near-zero force that is off by the solver's tolerance into −1.
            let mut offset = 0;
            for c in &p.contacts {
                let f = &s.contact_forces[offset..offset + c.dim()];
                let violation = c.gauge(f) - f[c.normal_index()];
                prop_assert!(violation <= tol, "contact {:?}: g − fz = {}", c, violation);
                offset += c.dim();
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 300,
        // Fixed seed: CI and every developer see the same cases (STYLE.md).
        rng_seed: proptest::test_runner::RngSeed::Fixed(41),
        ..ProptestConfig::default()
    })]

    #[test]
    fn native_and_clarabel_agree_on_the_linearised_problem(seed in any::<u64>(), sides in prop::sample::select(vec![4usize, 8, 16])) {
        let p = problem(seed, sides);
        let a = run(&p, Backend::ActiveSet, Cones::Linear);
        let b = run(&p, Backend::Clarabel, Cones::Linear);
        prop_assert_eq!(a.status, b.status, "native {:?} / clarabel {:?}", a.reason, b.reason);
        if a.status == Status::Optimal {
            // A polished answer passed the certificate the native one did.
            let tol = if b.method == Some("polished") { grasp_torque::conic::CERTIFICATE_TOLERANCE } else { 1e-6 };
            prop_assert!(rel(a.objective, b.objective) <= tol, "{} vs {} ({:?})", a.objective, b.objective, b.method);
            physically_consistent(&p, &a, Cones::Linear)?;
            physically_consistent(&p, &b, Cones::Linear)?;
        }
    }

    #[test]
    fn exact_optimum_is_below_every_linearisation_and_refinement_helps(seed in any::<u64>()) {
        let exact = run(&problem(seed, 8), Backend::Clarabel, Cones::Exact);
        let sigmas: Vec<Solution> = [4usize, 8, 16, 32].iter().map(|&n| run(&problem(seed, n), Backend::ActiveSet, Cones::Linear)).collect();
        for s in &sigmas {
            if s.status == Status::Optimal {
                // Inscribed cones: feasible linearised ⇒ feasible exact, with σ* ≤ σ(N).
                // Clarabel may end "almost solved" on grasps with every contact on its
                // cone; such answers passed the core's residual check.
                prop_assert!(exact.status.has_answer(), "{:?} {:?}", exact.status, exact.reason);
                prop_assert!(exact.objective <= s.objective * (1.0 + 1e-6) + 1e-12, "σ* {} > σ(N) {}", exact.objective, s.objective);
            }
        }
        if exact.status.has_answer() {
            physically_consistent(&problem(seed, 8), &exact, Cones::Exact)?;
        }
        // The 2N-gon contains the N-gon: σ(2N) ≤ σ(N), and feasibility is kept.
        for w in sigmas.windows(2) {
            if w[0].status == Status::Optimal {
                prop_assert_eq!(w[1].status, Status::Optimal);
                prop_assert!(w[1].objective <= w[0].objective * (1.0 + 1e-9) + 1e-15, "{} > {}", w[1].objective, w[0].objective);
            }
        }
    }
}

#[cfg(feature = "osqp")]
proptest! {
    #![proptest_config(ProptestConfig {
        cases: 200,
        // Fixed seed: CI and every developer see the same cases (STYLE.md).
        rng_seed: proptest::test_runner::RngSeed::Fixed(42),
        ..ProptestConfig::default()
    })]

    #[test]
    fn osqp_agrees_to_its_stated_tolerance(seed in any::<u64>()) {
        let p = problem(seed, 8);
        let a = run(&p, Backend::ActiveSet, Cones::Linear);
        let b = run(&p, Backend::Osqp, Cones::Linear);
        prop_assert_eq!(a.status, b.status, "native {:?} / osqp {:?}", a.reason, b.reason);
        if a.status == Status::Optimal {
            let polished = !b.warnings.iter().any(|w| w.contains("polishing did not succeed"));
            let tol = grasp_torque::OsqpSettings::stated_tolerance(polished);
            prop_assert!(rel(a.objective, b.objective) <= tol, "{} vs {} (polished {})", a.objective, b.objective, polished);
            // ADMM meets the equalities to its eps (1e-7), not to rounding.
            let d = &b.diagnostics;
            let scale = norm_inf(&p.wrench).max(norm_inf(&b.contact_forces)).max(1e-12);
            prop_assert!(d.wrench_residual <= 1e-5 * scale, "‖Gf − w‖∞ = {}", d.wrench_residual);
            prop_assert!(d.consistency_residual <= 1e-5 * scale, "‖Cτ − e‖∞ = {}", d.consistency_residual);
            prop_assert!(d.max_violation <= 1e-5 * scale, "linearised violation {}", d.max_violation);
        }
    }
}

/// The reference is precise to about 2e-9 relative (its README); the native solver and
/// Clarabel's defaults land within that (measured: at most 2.0e-9), so 1e-8 is asserted,
/// tighter than the 1e-6 the issue asks for. OSQP: its stated ADMM tolerance.
#[test]
fn reference_objectives_are_reproduced_by_every_backend() {
    let mut backends = vec![(Backend::ActiveSet, 1e-8), (Backend::Clarabel, 1e-8)];
    if Backend::Osqp.is_compiled() {
        backends.push((Backend::Osqp, 1e-3));
    }
    let mut checked = 0;
    for case in grasp_testkit::reference_cases() {
        let mut p = grasp_testkit::reference_problem(&case["problem"]);
        let name = case["name"].as_str().unwrap();
        let exact = run(&p, Backend::Clarabel, Cones::Exact);
        let want = case["reference"]["exact"]["objective"].as_f64().unwrap();
        assert_eq!(exact.status, Status::Optimal, "{name}");
        assert!(
            rel(exact.objective, want) <= 1e-6,
            "{name} exact: {} vs {want}",
            exact.objective
        );
        for (variant, sides) in [("N4", 4), ("N8", 8), ("N16", 16)] {
            p.linearization.sides = sides;
            let want = case["reference"][variant]["objective"].as_f64().unwrap();
            for &(b, tol) in &backends {
                let s = run(&p, b, Cones::Linear);
                assert_eq!(s.status, Status::Optimal, "{name} {variant} {b}");
                assert!(
                    rel(s.objective, want) <= tol,
                    "{name} {variant} {b}: {} vs {want}",
                    s.objective
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 41 * 3 * backends.len());
}

/// A soft-finger grasp with every torsional coefficient set to `mu_torsion` (and the
/// tangential friction to `mu`).
fn torsion(file: &str, mu: f64, mu_torsion: f64) -> GraspProblem {
    use grasp_torque::ContactModel;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(file);
    let mut p = grasp_torque::load_problem(&path).unwrap();
    for c in &mut p.contacts {
        if let ContactModel::SfcLinear {
            mu: m,
            mu_torsion: t,
        }
        | ContactModel::SfcElliptic {
            mu: m,
            mu_torsion: t,
        } = c
        {
            (*m, *t) = (mu, mu_torsion);
        }
    }
    p
}

/// Where Clarabel's interior point stops at its tolerance and a row far steeper than
/// the rest amplifies that past the core's check, its answer is polished (the rows it
/// holds with equality solved as equalities, then certified): the optimum to rounding,
/// the native solver's. Before, each of these was `numerical_failure` (violations of
/// 6.6e-5 and 2e-2 against tolerances of 1e-7 of the forces).
#[test]
fn polishing_recovers_answers_the_interior_point_leaves_short() {
    // A torsional coefficient 2.5e-5 of the lever arms (4 cm); torque weights 1e8 apart.
    let thin = torsion("hand5-mixed.json", 0.5, 1e-6);
    let mut spread = torsion("hand4-sfcl.json", 0.5, 0.01);
    let m = spread.joints();
    spread.torque_weights = Some(
        (0..m)
            .map(|j| if j % 2 == 0 { 1e4 } else { 1e-4 })
            .collect(),
    );
    for (name, p) in [("thin torsional cone", thin), ("weights 1e8 apart", spread)] {
        let native = run(&p, Backend::ActiveSet, Cones::Linear);
        let clarabel = run(&p, Backend::Clarabel, Cones::Linear);
        assert_eq!(
            native.status,
            Status::Optimal,
            "{name}: {:?}",
            native.reason
        );
        assert_eq!(
            clarabel.status,
            Status::Optimal,
            "{name}: {:?}",
            clarabel.reason
        );
        assert_eq!(clarabel.method, Some("polished"), "{name}");
        // Both pass certificates at 1e-9: their σ agree to that.
        let r = rel(native.objective, clarabel.objective);
        assert!(
            r <= grasp_torque::conic::CERTIFICATE_TOLERANCE,
            "{name}: {r:e}"
        );
    }
}

/// A dual ray whose torque terms cancel against the largest column but not in the other
/// free directions proves nothing (`fixtures/fuzz/ray-short-of-a-scaled-joint.json`,
/// `fuzz_answers.py backends` seed 228756: a joint whose row of Jᵀ is scaled far past
/// the others'). Clarabel called the grasp infeasible, linear and exact, where the
/// native solver holds it; now it gives no such proof, and the native answers stand.
#[test]
fn a_ray_that_cancels_only_the_largest_column_proves_nothing() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/fuzz/ray-short-of-a-scaled-joint.json"
    );
    let p = grasp_torque::load_problem(path).unwrap();
    for cones in [Cones::Linear, Cones::Exact] {
        let native = run(&p, Backend::ActiveSet, cones);
        assert_eq!(
            native.status,
            Status::Optimal,
            "{cones}: {:?}",
            native.reason
        );
        let clarabel = run(&p, Backend::Clarabel, cones);
        assert_ne!(
            clarabel.status,
            Status::Infeasible,
            "{cones}: {:?}",
            clarabel.reason
        );
    }
}
