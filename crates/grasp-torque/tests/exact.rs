//! The native exact-cone solver against independent answers: the reference optima of
//! `shared/reference/cases.json`, Clarabel's exact cones, every linearisation (the
//! inscribed polyhedra lie inside the cones, so σ* ≤ σ(N), and they converge to σ*),
//! and a robustness sweep at normal and at a quarter of the friction. The tests that
//! need no Clarabel also run in the native-only build.
#![cfg(feature = "active-set")]

use grasp_testkit::sweep_grasp as grasp;
use grasp_torque::{
    Backend, Cones, GraspProblem, GraspSolver, Reason, Solution, SolverConfig, Status, WarmStart,
};

mod common;
use common::{run, stated_excess};

/// A bundled fixture.
fn fixture(name: &str) -> GraspProblem {
    let path = format!("{}/../../fixtures/{name}.json", env!("CARGO_MANIFEST_DIR"));
    grasp_torque::load_problem(&path).unwrap()
}

/// Exact cones on the default (native) backend.
fn exact_config() -> SolverConfig {
    SolverConfig {
        cones: Cones::Exact,
        ..Default::default()
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

/// The references sit up to 2e-9 above the true optimum (their README): 3e-9.
#[test]
fn reference_exact_objectives_are_reproduced_natively() {
    let (mut worst, mut newton) = (0.0f64, 0);
    for case in grasp_testkit::reference_cases() {
        let p = grasp_testkit::reference_problem(&case["problem"]);
        let name = case["name"].as_str().unwrap();
        let want = case["reference"]["exact"]["objective"].as_f64().unwrap();
        let s = run(&p, Backend::ActiveSet, Cones::Exact);
        assert_eq!(s.status, Status::Optimal, "{name}: {:?}", s.reason);
        assert!(s.method.is_some(), "{name}");
        newton += usize::from(s.method == Some("newton"));
        let r = rel(s.objective, want);
        assert!(r <= 3e-9, "{name}: {} vs {want} ({r:.1e})", s.objective);
        worst = worst.max(r);
    }
    eprintln!("worst relative difference to the exact references: {worst:.2e}; {newton} of 41 by Newton, the rest by the interior-point fallback");
}

/// A grasp whose wrench the passive forces hold with no torque at all
/// (`tests/data/held-at-zero-torque.json`, an unseen grasp `scripts/oracle_cases.py`
/// drew: five SFCl contacts, `Z1 w` inside every cone but outside the polyhedra):
/// σ* = 0 at τ = 0. It ended `numerical_failure`: Newton, dropping the polyhedra's
/// pieces, reached y = 0 only to rounding (a step through the factor of 2I leaves
/// ε‖y‖), which the certificate's stationarity, relative to its own terms, refused;
/// and the interior-point iterate, which only nears 0, failed the gap. Clarabel ends
/// `almost_optimal` at σ ≈ 4e-16. A cold solve now takes y = 0 first where it holds.
#[test]
fn a_grasp_held_without_torque_is_optimal_at_zero() {
    let path = format!(
        "{}/../../tests/data/held-at-zero-torque.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let p = grasp_torque::load_problem(&path).unwrap();
    let s = run(&p, Backend::ActiveSet, Cones::Exact);
    assert_eq!(s.status, Status::Optimal, "{:?}", s.reason);
    assert_eq!(s.method, Some("newton"));
    assert!(s.torque.iter().all(|t| *t == 0.0), "{:?}", s.torque);
    assert_eq!(s.objective, 0.0);
    // Checked here from G, w and the friction coefficients: G f = w to rounding, and
    // each force strictly inside its SFCl cone, ‖f_t‖/μ + |mz|/μ_t < fz, or (two of
    // the five contacts) unloaded: within a thousand roundings of the largest force.
    let (g, f) = (&p.grasp_matrix, &s.contact_forces);
    for (i, w) in p.wrench.iter().enumerate() {
        let row = g.row(i);
        let gf: f64 = row.iter().zip(f).map(|(a, b)| a * b).sum();
        let size: f64 = row.iter().zip(f).map(|(a, b)| (a * b).abs()).sum();
        assert!(
            (gf - w).abs() <= 64.0 * f64::EPSILON * size.max(w.abs()),
            "row {i}"
        );
    }
    let largest = f.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut unloaded = 0;
    for (c, fc) in p.contacts.iter().zip(f.chunks_exact(4)) {
        let grasp_torque::ContactModel::SfcLinear { mu, mu_torsion } = *c else {
            panic!("{c:?}")
        };
        if fc.iter().all(|v| v.abs() <= 1e3 * f64::EPSILON * largest) {
            unloaded += 1;
            continue;
        }
        let load = fc[0].hypot(fc[1]) / mu + fc[3].abs() / mu_torsion;
        assert!(load < fc[2], "{fc:?}");
    }
    assert_eq!(unloaded, 2);
    // The polyhedra, inside the cones, need torque.
    assert!(run(&p, Backend::ActiveSet, Cones::Linear).objective > 0.0);
    // In a control loop, from an answer that needs torque back to this wrench: the
    // warm solve takes y = 0 at once. It used to drop the last answer's pieces one at a
    // time through the unloaded contacts' apexes, fail, follow the wrench, fail, and
    // solve cold: 94 iterations, a tick a hundred times the others.
    let mut solver = GraspSolver::new(&p, &exact_config()).unwrap();
    let mut pushed = p.wrench;
    pushed[0] += 1.0;
    let s = solver.resolve(&pushed).unwrap();
    assert_eq!(s.status, Status::Optimal, "{:?}", s.reason);
    assert!(s.objective > 0.0);
    let s = solver.resolve(&p.wrench).unwrap();
    assert_eq!(s.status, Status::Optimal, "{:?}", s.reason);
    assert_eq!((s.method, s.objective), (Some("newton"), 0.0));
    assert_eq!(s.iterations, 0);
}

/// `solve FILE --cones exact` picks the native solver by default.
#[test]
fn exact_cones_use_the_native_solver_by_default() {
    let p = fixture("hand4-sfce");
    let mut s = GraspSolver::new(&p, &exact_config()).unwrap();
    assert_eq!(s.backend_name(), "active-set");
    let sol = s.solve(&p.wrench, &WarmStart::default()).unwrap();
    assert_eq!(sol.status, Status::Optimal);
}

/// Hundreds of random grasps and wrenches, at normal friction and at a quarter of it:
/// no `optimal` answer that Clarabel calls infeasible or that disagrees with Clarabel's
/// (1e-7 relative), none above a linearisation's σ(N), and the same status as Clarabel
/// wherever Clarabel is decisive. Reports how often each path decided.
#[cfg(feature = "clarabel")]
#[test]
fn robustness_sweep_against_clarabel_and_the_linearisations() {
    // Optimal, infeasible by the N = 8 circumscribed cones, by N = 256, other, an
    // unreachable wrench (the core's check), a dual ray, and by N = 32.
    let mut count = [0usize; 7];
    let mut worst = 0.0f64;
    let (mut linear_checks, mut fallback) = (0, 0);
    for (friction, seeds) in [(1.0, 0..300u64), (0.25, 1000..1300u64)] {
        for seed in seeds {
            let p = grasp(seed, friction);
            let native = run(&p, Backend::ActiveSet, Cones::Exact);
            let clarabel = run(&p, Backend::Clarabel, Cones::Exact);
            let decisive = matches!(clarabel.status, Status::Optimal | Status::Infeasible);
            if decisive {
                assert_eq!(
                    native.status, clarabel.status,
                    "seed {seed} friction {friction}: native {:?} ({:?}), clarabel {:?}",
                    native.status, native.reason, clarabel.reason
                );
            }
            match native.status {
                Status::Optimal => {
                    count[0] += 1;
                    fallback += usize::from(matches!(
                        native.method,
                        Some("interior_point" | "interior_point_newton")
                    ));
                    if clarabel.status == Status::Optimal {
                        let r = rel(native.objective, clarabel.objective);
                        // σ ≈ 0 (a load the contacts take without torque): absolute.
                        let floor = 1e-12 * p.wrench.iter().map(|v| v * v).sum::<f64>();
                        assert!(
                            r <= 1e-7 || (native.objective - clarabel.objective).abs() <= floor,
                            "seed {seed}: {} vs {}",
                            native.objective,
                            clarabel.objective
                        );
                        worst = worst.max(r);
                    }
                    for sides in [4, 8, 16] {
                        let mut q = p.clone();
                        q.linearization.sides = sides;
                        let lin = run(&q, Backend::ActiveSet, Cones::Linear);
                        if lin.status == Status::Optimal {
                            assert!(
                                native.objective <= lin.objective * (1.0 + 1e-9) + 1e-300,
                                "seed {seed} N={sides}: σ* {} > σ(N) {}",
                                native.objective,
                                lin.objective
                            );
                            linear_checks += 1;
                        }
                    }
                }
                Status::Infeasible => match native.reason {
                    // Decided by the core before any backend runs.
                    Some(Reason::UnreachableWrench { .. }) => count[4] += 1,
                    Some(Reason::OuterApproximation { sides: 8, .. }) => count[1] += 1,
                    Some(Reason::OuterApproximation { sides: 32, .. }) => count[6] += 1,
                    Some(Reason::OuterApproximation { .. }) => count[2] += 1,
                    Some(Reason::DualRay { .. }) => count[5] += 1,
                    ref other => panic!("seed {seed}: infeasible for {other:?}"),
                },
                _ => count[3] += 1,
            }
        }
    }
    eprintln!(
        "600 grasps: {} optimal ({fallback} by the interior-point fallback), {} infeasible by the N = 8 circumscribed cones, {} by N = 32, {} by a dual ray, {} by N = 256, {} with an unreachable wrench, {} other; worst σ difference to Clarabel {worst:.1e}; {linear_checks} σ* ≤ σ(N) checks",
        count[0], count[1], count[6], count[5], count[2], count[4], count[3]
    );
    assert!(count[0] > 100 && count[1] > 10, "{count:?}");
}

/// A torque limit far beyond the torques changes nothing: the same status and σ on
/// the exact cones as without it, whether it is 1e3, 1e6 or 1e9 times the torques
/// (a limit of 1e9 is how a user says "none"), on both sides or one. Its constant once
/// set the scale of the certificate's primal check for every row, so a point outside
/// a cone passed it (sweep seed 13316 at a quarter of the friction: σ 5.08 against
/// 5.20, caught by the core's check as a numerical failure; seed 992275 at normal
/// friction: infeasible, then a failed optimum at σ 52).
#[test]
fn a_loose_torque_limit_changes_no_answer() {
    use grasp_torque::TorqueLimit;
    let (mut optimal, mut infeasible) = (0, 0);
    let seeds = (0..150u64)
        .map(|s| (s, 1.0))
        .chain((1000..1150).map(|s| (s, 0.25)))
        .chain([(13316, 0.25), (992275, 1.0)]);
    for (seed, friction) in seeds {
        let p = grasp(seed, friction);
        let free = run(&p, Backend::ActiveSet, Cones::Exact);
        assert!(
            matches!(free.status, Status::Optimal | Status::Infeasible),
            "seed {seed}"
        );
        // The torques' size: the answer's, and at least 1 N·m (an infeasible grasp has
        // none; the sweep's torques are of that order).
        let size = match free.status {
            Status::Optimal => free.torque.iter().fold(0.0f64, |a, t| a.max(t.abs())),
            _ => 0.0,
        }
        .max(1.0);
        for factor in [1e3, 1e6, 1e9] {
            let t = factor * size;
            for limit in [TorqueLimit::Symmetric(t), TorqueLimit::Range(None, Some(t))] {
                let mut q = p.clone();
                q.torque_limits = Some(vec![Some(limit); p.joints()]);
                let s = run(&q, Backend::ActiveSet, Cones::Exact);
                assert_eq!(
                    s.status, free.status,
                    "seed {seed} friction {friction}, limit {limit:?}: {:?} {:?}",
                    s.reason, s.warnings
                );
                if s.status == Status::Optimal {
                    assert!(
                        rel(s.objective, free.objective) <= 1e-9,
                        "seed {seed} friction {friction}, limit {limit:?}: σ {} against {}",
                        s.objective,
                        free.objective
                    );
                }
            }
        }
        optimal += usize::from(free.status == Status::Optimal);
        infeasible += usize::from(free.status == Status::Infeasible);
    }
    assert!(
        optimal > 100 && infeasible > 20,
        "{optimal} optimal, {infeasible} infeasible"
    );
}

/// A joint with short moment arms (a contact near its axis): 100 of the sweep's
/// grasps, each with each joint's row of Jᵀ in turn scaled by 1e-4 and 1e-6. Scaling a
/// joint's torque changes which torques are feasible only by that scale, so the
/// status is the unscaled grasp's; it makes that joint's torque cheaper, so σ is not
/// above the unscaled σ; and σ* ≤ σ(8). At 1e-4 every grasp is decided, linear and
/// exact; at 1e-6 every one linear, and all but one exact (a numerical failure:
/// docs/solver.md, "Limits"), as the unscaled grasp. The row's huge column in H made
/// its normalised row look feasible within 1e-9 while a force missed its face by 19 N
/// (seed 5085 at a quarter of the friction, by `scripts/fuzz_answers.py moment-arms`;
/// the core's check caught it), and three linear solves here ended in numerical
/// failures: the active-set method now iterates to 1e-11 first (`TIGHT`). The conic
/// form scaled the torques by the largest force response, which left the others'
/// columns too small for the exact methods: two exact failures here, 17 of 200 at
/// 1e-8 in docs/solver.md's table; by the typical response, one and two.
#[test]
fn a_joint_with_short_moment_arms_is_decided() {
    // Numerical failures at 1e-6, linear and exact.
    let mut undecided = [0usize; 2];
    for (friction, seeds) in [(1.0, 5000..5050u64), (0.25, 5000..5050u64)] {
        for seed in seeds {
            let p = grasp(seed, friction);
            let free = [Cones::Linear, Cones::Exact].map(|c| run(&p, Backend::ActiveSet, c));
            for (j, scale) in (0..p.joints()).flat_map(|j| [(j, 1e-4), (j, 1e-6)]) {
                let mut q = p.clone();
                for v in q.jacobian_transpose.row_mut(j) {
                    *v *= scale;
                }
                let [lin, exact] =
                    [Cones::Linear, Cones::Exact].map(|c| run(&q, Backend::ActiveSet, c));
                for (i, (s, f)) in [(&lin, &free[0]), (&exact, &free[1])]
                    .into_iter()
                    .enumerate()
                {
                    let at = format!(
                        "seed {seed} friction {friction}, joint {j} × {scale:e}, cones {i}"
                    );
                    if scale == 1e-6 && s.status == Status::NumericalFailure {
                        undecided[i] += 1;
                        continue;
                    }
                    assert_eq!(s.status, f.status, "{at}: {:?}", s.reason);
                    // σ to the core check's tolerance (1e-8): the scaled grasp's rows,
                    // and so its σ, are as accurate as that check makes them.
                    if s.status == Status::Optimal {
                        assert!(
                            s.objective <= f.objective * (1.0 + 1e-8),
                            "{at}: σ {} above the unscaled {}",
                            s.objective,
                            f.objective
                        );
                    }
                }
                if lin.status == Status::Optimal && exact.status == Status::Optimal {
                    assert!(
                        exact.objective <= lin.objective * (1.0 + 1e-8),
                        "seed {seed}"
                    );
                }
            }
        }
    }
    eprintln!(
        "moment arms × 1e-6: {} linear and {} exact numerical failures",
        undecided[0], undecided[1]
    );
    assert!(undecided[0] == 0 && undecided[1] <= 1, "{undecided:?}");
}

/// A contact pinned to its cone's apex beside joints whose moment arms are 1e-8 of
/// others' (`fixtures/fuzz/pinned-contact.json`): joint 8's upper limit of 0 admits no
/// force at the middle finger but zero, so the grasp is feasible with nothing to spare.
/// The null space of the consistency equalities carried an error of ε in every entry,
/// which its rows for the short-armed joints (1e-8 of the others) could not bear against
/// their columns of H (1e9): in SI units the inscribed and the circumscribed polyhedra
/// alike were called infeasible (two opposite rows 2e-10 apart), in other units
/// optimal. Its rows now keep their own digits (`linalg::orthonormal_columns`), and the
/// grasp is optimal in every unit, at σ* = 0.1645292523000 from the forces alone
/// (`python3 scripts/oracle_file.py fixtures/fuzz/pinned-contact.json`: cvxpy and
/// Clarabel at 1e-10).
#[test]
fn a_contact_pinned_beside_short_moment_arms_is_held() {
    const ORACLE: f64 = 1.645292523000e-1;
    let p = fixture("fuzz/pinned-contact");
    for (l, f) in [
        (1.0, 1.0),
        (2.97e-3, 6.9e-2),
        (1e-3, 1e3),
        (1e3, 1e-3),
        (1e2, 1e2),
    ] {
        let q = grasp_testkit::rescale(&p, l, f);
        let back = (l * f) * (l * f);
        let [lin, exact] = [Cones::Linear, Cones::Exact].map(|c| run(&q, Backend::ActiveSet, c));
        let at = format!("lengths × {l:e}, forces × {f:e}");
        assert_eq!(lin.status, Status::Optimal, "{at}: {:?}", lin.reason);
        assert_eq!(exact.status, Status::Optimal, "{at}: {:?}", exact.reason);
        // The oracle's tolerance, 1e-10, and the certificate's, 1e-9.
        let sigma = exact.objective / back;
        assert!(
            rel(sigma, ORACLE) <= 1e-9,
            "{at}: σ* {sigma} against {ORACLE}"
        );
        assert!(exact.objective <= lin.objective * (1.0 + 1e-9), "{at}");
    }
}

/// A joint the consistency equalities pin at exactly its torque limit, with moment
/// arms up to 1e6 times the others': the pinch's index roll (`fixtures/geometry/
/// pinch.json`), whose torque is the index contact's fy times the arm, which the
/// wrench fixes at 0, under an upper limit of 0 (fuzz seed 2866). The model's null
/// basis of the equalities had a row of 2e-17 for it, which the backends' weighting
/// grows with the arms: at 1e6 the limit was judged along a direction of 1e-11 as a
/// row of the problem, not a fixed one, and the grasp was called infeasible, linear
/// and exact (at 9.7e5, optimal at σ = 7.67, 8000 times σ*). The model now zeroes
/// the row of a pinned joint (`model::PINNED`), and Newton's closed form takes a row
/// that does not move along its line within the certificate's tolerance of a limit's
/// terms (the pinned torque comes out of the equalities 1e-10 of the largest past the
/// limit it meets exactly). Every arm and unit gives σ* = 9.604e-4, the pinch's
/// without the limit, which its optimum meets at τ = 0. (At 1e7 the exact solve is
/// `numerical_failure`, and at 1e8 the linear one: docs/solver.md, "Limits".)
#[test]
fn a_pinned_joint_at_its_limit_is_held_whatever_its_arms() {
    let plain = run(
        &fixture("geometry/pinch"),
        Backend::ActiveSet,
        Cones::Linear,
    )
    .objective;
    for arm in [1e-3, 1.0, 1e3, 1e5, 9.678e5, 1e6] {
        let mut p = fixture("geometry/pinch");
        for v in p.jacobian_transpose.row_mut(5) {
            *v *= arm;
        }
        let mut limits = vec![None; p.joints()];
        limits[5] = Some(grasp_torque::TorqueLimit::Range(Some(-1.0), Some(0.0)));
        p.torque_limits = Some(limits);
        for (l, f) in [(1.0, 1.0), (1e-3, 1e3), (1e3, 1e-3), (0.288, 4.45e-3)] {
            let q = grasp_testkit::rescale(&p, l, f);
            let back = (l * f) * (l * f);
            for cones in [Cones::Linear, Cones::Exact] {
                let s = run(&q, Backend::ActiveSet, cones);
                let at = format!("arm × {arm:e}, lengths × {l:e}, forces × {f:e}, {cones:?}");
                assert_eq!(s.status, Status::Optimal, "{at}: {:?}", s.reason);
                let sigma = s.objective / back;
                assert!(rel(sigma, plain) <= 1e-9, "{at}: σ {sigma} against {plain}");
            }
        }
    }
}

/// A limit exactly at a torque that the wrench pins only up to the rounding its row of
/// Jᵀ was formed with (`fixtures/fuzz/limit-at-a-torque-pinned-to-rounding.json` and
/// `limit-above-a-torque-pinned-to-rounding.json`, `fuzz_answers.py pinned-limits`
/// seeds 3463 and 3141: a row `s cᵀ G` in floating point, in G's span to 3e-16 of
/// itself, whose row of the equalities' null basis came out above `PINNED`). Every
/// admissible torque meets the limit, so the answer is the grasp's without it, linear
/// and exact, in any units: before, one was infeasible and the other's σ 2e-5 high.
#[test]
fn a_limit_at_a_torque_pinned_to_rounding_is_the_grasp_without_it() {
    for name in [
        "limit-at-a-torque-pinned-to-rounding",
        "limit-above-a-torque-pinned-to-rounding",
    ] {
        let limited = fixture(&format!("fuzz/{name}"));
        let mut free = limited.clone();
        free.torque_limits = None;
        for (l, f) in [(1.0, 1.0), (1e-3, 1e3), (1e3, 1e-3), (0.244, 17.7)] {
            let (q, p) = (
                grasp_testkit::rescale(&limited, l, f),
                grasp_testkit::rescale(&free, l, f),
            );
            for cones in [Cones::Linear, Cones::Exact] {
                let (s, t) = (
                    run(&q, Backend::ActiveSet, cones),
                    run(&p, Backend::ActiveSet, cones),
                );
                let at = format!("{name}, lengths × {l:e}, forces × {f:e}, {cones:?}");
                assert_eq!(s.status, Status::Optimal, "{at}: {:?}", s.reason);
                assert_eq!(t.status, Status::Optimal, "{at} without the limit");
                // Both within the optimality tolerance of one optimum (the exact
                // certificate's 2e-9 each).
                assert!(
                    rel(s.objective, t.objective) <= 4e-9,
                    "{at}: σ {} against {} without the limit",
                    s.objective,
                    t.objective
                );
            }
        }
    }
}

/// The pinch's roll joints, which the equalities pin, at torques other than 0 (a
/// wrench with a sideways force or a twist): one constant row of a second-order cone
/// (a contact's fy, which the wrench fixes) still carries the cone's multiplier. A
/// certificate that dropped it as it drops a constant limit row failed every such
/// answer on its duality gap (0.84), found by `fuzz_answers.py` (seed 3105).
#[test]
fn pinned_torques_off_zero_are_certified() {
    for (fy, mz) in [(0.0, 0.5), (1.0, 0.0), (-0.7, -0.3), (0.2, 2.0)] {
        let mut p = fixture("geometry/pinch");
        p.wrench[1] += fy;
        p.wrench[5] += mz;
        let exact = run(&p, Backend::ActiveSet, Cones::Exact);
        let at = format!("fy {fy}, mz {mz}");
        assert_eq!(exact.status, Status::Optimal, "{at}: {:?}", exact.reason);
        let lin = run(&p, Backend::ActiveSet, Cones::Linear);
        assert!(
            lin.status != Status::Optimal || exact.objective <= lin.objective * (1.0 + 1e-9),
            "{at}"
        );
        #[cfg(feature = "clarabel")]
        {
            let c = run(&p, Backend::Clarabel, Cones::Exact);
            assert_eq!(c.status, Status::Optimal, "{at}: {:?}", c.reason);
            assert!(
                rel(exact.objective, c.objective) <= 1e-7,
                "{at}: {} against Clarabel's {}",
                exact.objective,
                c.objective
            );
        }
    }
}

/// `fixtures/fuzz/long-and-short-arms.json` (fuzz seed 3197): the paper example with
/// joint 0's arms 10834 times its own and joint 3's one entry of 1e-8. It is held only
/// with joint 0's torque about 5e4 times the others', each contact's force on its
/// exact cone's boundary, at σ* = 2.7366e9: cvxpy (Clarabel) on τ with the paper's
/// `A⁺` and the exact cones, from the file alone, gives 2736638060.93, as accurate as
/// a problem this scaled allows (4e-9). At 06e2229 the exact cones were called
/// infeasible (the circumscribed polyhedra, by a face taken for one no torque
/// moves); Newton's closed form now takes a row whose slope along its line is
/// rounding as holding within the certificate's tolerance of its terms, and the
/// certificate passes its answer. (The
/// inscribed polyhedra do not hold it, nor Clarabel's exact cones, by a ray that
/// excludes only torques within some multiple of the load.)
#[test]
fn a_grasp_held_only_by_a_long_arm_is_held() {
    let p = fixture("fuzz/long-and-short-arms");
    let s = run(&p, Backend::ActiveSet, Cones::Exact);
    assert_eq!(s.status, Status::Optimal, "{:?}", s.reason);
    assert!(
        rel(s.objective, 2736638060.93) <= 1e-8,
        "σ* {}",
        s.objective
    );
}

/// The certificate's gap bounds σ's error, `σ(x) − σ* ≤ sᵀz + ‖ρ‖²/4` for z in K*,
/// and is judged against σ, with only the rounding of sᵀz admitted beyond: against
/// `Σ |b_i z_i|` as before, multipliers grown along a ray of the dual passed points
/// far from the optimum. Four grasps at a hundredth of the friction were `optimal` at
/// 2.4e-9 to 5.5e-8 from σ* (cvxpy on the forces, `scripts/oracle_file.py` on
/// `fallbacks write SEED:0.01`), and `fixtures/fuzz/apex-held-by-a-limit.json`, whose
/// torque limit holds a contact at its apex (no strictly feasible point), at 1e-4
/// above σ* in any units, by the interior-point method with multipliers of 1e12. (That
/// grasp is now Newton's: `a_tendon_that_holds_a_contact_unloaded_is_the_grasp_without_it`.)
#[test]
fn the_gap_bounds_sigma_whatever_the_multipliers() {
    for (seed, oracle) in [
        (500409, 2.410757797021e2),
        (507928, 1.493778392058e5),
        (526991, 1.152370310595e5),
        (533495, 1.886582418482e5),
    ] {
        let s = run(&grasp(seed, 0.01), Backend::ActiveSet, Cones::Exact);
        assert_eq!(s.status, Status::Optimal, "seed {seed}: {:?}", s.reason);
        // The oracle's accuracy, about 1e-10, and the certificate's 2e-9 on σ.
        assert!(
            rel(s.objective, oracle) <= 1e-9,
            "seed {seed}: σ* {} against {oracle}",
            s.objective
        );
    }
    const ORACLE: f64 = 2.266529191106e-7;
    let p = fixture("fuzz/apex-held-by-a-limit");
    for (l, f) in [(1.0, 1.0), (1.1, 20.5), (1e-3, 1e3), (1e2, 1e-2)] {
        let q = grasp_testkit::rescale(&p, l, f);
        let back = (l * f) * (l * f);
        let at = format!("lengths × {l:e}, forces × {f:e}");
        let lin = run(&q, Backend::ActiveSet, Cones::Linear);
        assert_eq!(lin.status, Status::Optimal, "{at}: {:?}", lin.reason);
        // The inscribed polyhedra hold the contact at the apex too, at the same σ.
        assert!(
            rel(lin.objective / back, ORACLE) <= 1e-9,
            "{at}: σ(8) {}",
            lin.objective
        );
        // Newton, with the limit's multiplier moved into the apex's dual.
        let s = run(&q, Backend::ActiveSet, Cones::Exact);
        assert_eq!(s.status, Status::Optimal, "{at}: {:?}", s.reason);
        assert_eq!(s.method, Some("newton"), "{at}");
        assert!(
            rel(s.objective / back, ORACLE) <= 1e-9,
            "{at}: σ* {} against {ORACLE}",
            s.objective / back
        );
    }
}

/// An SFCl finger that torque limits at zero hold unloaded (`fixtures/fuzz/
/// sfcl-finger-held-unloaded-by-limits.json`, fuzz seed 4830): both cones of its pair
/// are at the apex, and their shared dual lies in its cone only with a limit's
/// multiplier moved into it (`Newton::rebalance_pair`). Without that, Newton's guesses
/// cycled and the interior-point method stopped short, 6.0e-8 above σ*. Newton now
/// certifies it, σ* to 1e-9 (the direct SOCP's, which Clarabel's exact answer matches
/// to 1e-11), in four systems of units.
#[test]
fn an_sfcl_pair_held_at_its_apex_by_limits_is_newtons() {
    const ORACLE: f64 = 1.6348449612028e-4;
    newtons_in_four_units("fuzz/sfcl-finger-held-unloaded-by-limits", ORACLE);
}

/// A contact that the plane of the contacts' forces meets only at its apex
/// (`fixtures/fuzz/contact-confined-to-a-plane-through-its-apex.json`, fuzz seed
/// 340274: the weighed Allegro pinch with no wrench and the thumb at mu = 0.0083).
/// The thumb's three cone rows are dependent on the equalities' solutions, and its
/// apex dual is known only up to their combination `u` (`Newton::rebalance_own_rows`),
/// which lies inside the dual cone. Before, Newton left the dependent row's multiplier
/// at 0, the apex's dual fell outside its cone, and the interior-point method, with no
/// strictly feasible point, grew that dual until it stalled: `numerical_failure` with
/// lengths × 0.399 and forces × 2.83, `optimal` in SI. Newton now certifies it at the
/// direct SOCP's σ* (`scripts/oracle_file.py`: cvxpy and Clarabel, 4.409748764085e-3).
#[test]
fn a_contact_confined_to_a_plane_through_its_apex_is_newtons() {
    const ORACLE: f64 = 4.409748764085e-3;
    newtons_in_four_units("fuzz/contact-confined-to-a-plane-through-its-apex", ORACLE);
    let p = fixture("fuzz/contact-confined-to-a-plane-through-its-apex");
    let s = run(
        &grasp_testkit::rescale(&p, 0.399, 2.83),
        Backend::ActiveSet,
        Cones::Exact,
    );
    assert_eq!(s.method, Some("newton"), "{:?}", s.reason);
    let thumb = &s.contact_forces[6..9];
    assert!(
        thumb.iter().all(|f| f.abs() <= 1e-12),
        "the thumb's force {thumb:?} is not at its apex"
    );
}

/// The fixture `name`, in four systems of units: Newton's `optimal`, σ* to 1e-9 of
/// `oracle` (the oracle's accuracy, 1e-10, and the certificate's 2e-9 on σ).
fn newtons_in_four_units(name: &str, oracle: f64) {
    let p = fixture(name);
    for (l, f) in [(1.0, 1.0), (1.1, 20.5), (1e-3, 1e3), (1e2, 1e-2)] {
        let q = grasp_testkit::rescale(&p, l, f);
        let back = (l * f) * (l * f);
        let at = format!("{name}, lengths × {l:e}, forces × {f:e}");
        let s = run(&q, Backend::ActiveSet, Cones::Exact);
        assert_eq!(s.status, Status::Optimal, "{at}: {:?}", s.reason);
        assert_eq!(s.method, Some("newton"), "{at}");
        assert!(
            rel(s.objective / back, oracle) <= 1e-9,
            "{at}: σ* {} against {oracle}",
            s.objective / back
        );
    }
}

/// A tendon that only pulls (upper limit 0) on a joint whose only load is one contact,
/// through a direction inside that contact's dual cone: every force in the cone but
/// zero would push the joint, so every admissible torque leaves the contact unloaded,
/// an equality no row states (no strictly feasible point). The answer must be the
/// grasp's without that contact, σ to 1e-8, linear and exact. The multipliers are then
/// unbounded: the interior-point method grew the limit's to 1e12 and was `optimal` at
/// 1e-4 above σ* (fuzz seed 230, `fixtures/fuzz/apex-held-by-a-limit.json`), and Newton
/// left the apex, whose dual was outside the dual cone with the limit's multiplier
/// where the pieces had put it; it now moves that multiplier into the cone's
/// (`Newton::rebalance_apex`).
#[test]
fn a_tendon_that_holds_a_contact_unloaded_is_the_grasp_without_it() {
    use grasp_torque::{ContactModel, Matrix, TorqueLimit};
    let mut compared = 0;
    for friction in [1.0, 0.25] {
        for seed in 0..200u64 {
            let p = grasp(seed, friction);
            let (c, j) = (seed as usize % p.contacts.len(), seed as usize % p.joints());
            let off: usize = p.contacts[..c].iter().map(|m| m.dim()).sum();
            let model = p.contacts[c];
            // g inside the dual cone: the normal, half the cone's tangential reach.
            let mut g = vec![0.0; model.dim()];
            g[model.normal_index()] = 1.0;
            match model {
                ContactModel::Fpc => {}
                ContactModel::Pcwf { mu } => g[0] = 0.5 / mu,
                ContactModel::SfcLinear { mu, mu_torsion }
                | ContactModel::SfcElliptic { mu, mu_torsion } => {
                    (g[0], g[1], g[3]) = (0.3 / mu, -0.2 / mu, 0.3 / mu_torsion);
                }
            }
            let arm = p
                .jacobian_transpose
                .row(j)
                .iter()
                .fold(0.0f64, |a, v| a.max(v.abs()));
            let mut held = p.clone();
            let row = held.jacobian_transpose.row_mut(j);
            row.iter_mut().for_each(|v| *v = 0.0);
            for (k, gk) in g.iter().enumerate() {
                row[off + k] = arm * gk;
            }
            let mut limits = held.torque_limits.clone().unwrap_or(vec![None; p.joints()]);
            limits[j] = Some(TorqueLimit::Range(None, Some(0.0)));
            held.torque_limits = Some(limits);
            if let Some(f) = &mut held.min_normal_force {
                f[c] = 0.0;
            }
            // Without the contact: its columns gone, joint j's row empty (τ_j = 0).
            let keep: Vec<usize> = (0..p.grasp_matrix.ncols())
                .filter(|&k| k < off || k >= off + model.dim())
                .collect();
            let cols = |m: &Matrix| Matrix::from_fn(m.nrows(), keep.len(), |r, k| m[(r, keep[k])]);
            let mut free = held.clone();
            free.grasp_matrix = cols(&held.grasp_matrix);
            free.jacobian_transpose = cols(&held.jacobian_transpose);
            free.contacts.remove(c);
            free.torque_limits.as_mut().unwrap()[j] = None;
            if let Some(f) = &mut free.min_normal_force {
                f.remove(c);
            }
            // (Where [G; Jᵀ] has a null space, its passive internal forces depend on
            // every contact's columns: the two grasps are then different problems.)
            let passive = |q: &GraspProblem| {
                GraspSolver::new(q, &SolverConfig::default())
                    .map_or(1, |s| s.problem().model.passive_dim())
            };
            if free.contacts.is_empty() || passive(&held) + passive(&free) > 0 {
                continue;
            }
            for cones in [Cones::Linear, Cones::Exact] {
                let [a, b] = [&held, &free].map(|q| run(q, Backend::ActiveSet, cones));
                let at =
                    format!("seed {seed} friction {friction}, contact {c}, joint {j}, {cones:?}");
                assert_eq!(a.status, b.status, "{at}: {:?} / {:?}", a.reason, b.reason);
                if a.status == Status::Optimal {
                    assert!(
                        rel(a.objective, b.objective) <= 1e-8,
                        "{at}: σ {} against {}",
                        a.objective,
                        b.objective
                    );
                    compared += 1;
                    // The contact is unloaded: its force rounding of the largest.
                    let fmax = a.contact_forces.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    let f = &a.contact_forces[off..off + model.dim()];
                    assert!(
                        f.iter().all(|v| v.abs() <= 1e-7 * fmax),
                        "{at}: the held contact's force {f:?} (largest {fmax:e})"
                    );
                }
            }
        }
    }
    eprintln!("{compared} optimal answers compared, each with the contact unloaded");
    assert!(compared >= 100, "{compared}");
}

/// `fixtures/fuzz/interior-point-gap.json` (fuzz seed 1030): the exact solve ended with
/// the interior-point method, whose best iterate's gap, a primal residual of rounding
/// times multipliers of 1e6, is 5e-8 of σ. It was `optimal` at 5e-9 above σ*, with σ
/// spread by 1.5e-8 over five unit systems, then `almost_optimal` with that bound
/// (`ExactSolver::almost`). Newton stopped there on a multiplier that only the apex's
/// rebalancing put right, and gave up; it now runs the same guess again from the
/// rebalanced multipliers, and certifies σ* to 1e-9 in four systems of units.
#[test]
fn a_guess_whose_multipliers_the_apex_put_right_is_solved_again() {
    const ORACLE: f64 = 1.450032515658e-1;
    newtons_in_four_units("fuzz/interior-point-gap", ORACLE);
}

/// A joint whose row of Jᵀ is a combination of G's, `s cᵀ G` (so that the equalities
/// pin its torque to `s c·w`), with one side of its range exactly there: every
/// admissible torque meets that limit, so the answer is the one without it. On 100
/// sweep grasps per friction, the arm's scale s over 1e-3 to 1e6: the same status and
/// σ to 1e-8, linear and exact. `python3 scripts/fuzz_answers.py pinned-limits 0 150`
/// finds 43 of 300 grasps answered otherwise at 06e2229 and 12 at 4b45439, `optimal`
/// at up to 134 000 times σ: the exact method's certificate fooled by a multiplier of
/// 1e18 on the limit's row, which the equalities absorb. Now the certificate reads no
/// multiplier on a row the equalities make constant, Newton never takes one in, and
/// the interior-point method sees it slack (`ConicForm::fixed`, `Newton::still`).
#[test]
fn a_limit_at_a_pinned_torque_changes_no_answer() {
    let mut rng = grasp_testkit::Rng(2866);
    for (friction, seeds) in [(1.0, 200..300u64), (0.25, 200..300u64)] {
        for seed in seeds {
            let mut p = grasp(seed, friction);
            let m = p.joints();
            let j = rng.int(0, m - 1);
            let c: Vec<f64> = (0..6)
                .map(|_| {
                    if rng.uniform(0.0, 1.0) < 0.5 {
                        rng.uniform(-1.0, 1.0)
                    } else {
                        0.0
                    }
                })
                .collect();
            let scale = 10f64.powf(rng.uniform(-3.0, 6.0));
            for k in 0..p.force_dim() {
                p.jacobian_transpose[(j, k)] =
                    scale * (0..6).map(|i| c[i] * p.grasp_matrix[(i, k)]).sum::<f64>();
            }
            let pinned = scale * (0..6).map(|i| c[i] * p.wrench[i]).sum::<f64>();
            let span = 10.0 * pinned.abs() + 1.0;
            let mut q = p.clone();
            let mut limits = vec![None; m];
            limits[j] = Some(if rng.uniform(0.0, 1.0) < 0.5 {
                grasp_torque::TorqueLimit::Range(Some(pinned - span), Some(pinned))
            } else {
                grasp_torque::TorqueLimit::Range(Some(pinned), Some(pinned + span))
            });
            q.torque_limits = Some(limits);
            for cones in [Cones::Linear, Cones::Exact] {
                let (free, held) = (
                    run(&p, Backend::ActiveSet, cones),
                    run(&q, Backend::ActiveSet, cones),
                );
                let at =
                    format!("seed {seed} friction {friction}, joint {j} × {scale:e}, {cones:?}");
                assert_eq!(held.status, free.status, "{at}: {:?}", held.reason);
                if free.status == Status::Optimal {
                    assert!(
                        rel(held.objective, free.objective) <= 1e-8,
                        "{at}: σ {} against {}",
                        held.objective,
                        free.objective
                    );
                }
            }
        }
    }
}

/// Clarabel's infeasibility is reported only with a proof checked from scratch. On two
/// grasps of a sweep beyond the ones here (seeds 30179 and 37476 at a quarter of the
/// friction), Clarabel at its default tolerances stops after a few iterations with a
/// claim of infeasibility whose multipliers leave torque terms of a good part of their
/// size (`ConicForm::dual_ray`'s measure, in the answer's warning; `-- --nocapture`
/// prints it), on grasps that the inscribed polyhedra (N = 8) hold: feasible. It then
/// runs again with strict infeasibility tolerances, and ends optimal on one and at
/// its iteration limit on the other, never `infeasible`. (Seed 30017 at normal friction
/// did this too while the conic form scaled the torques by their largest response; by
/// their typical one, as now for a joint whose response is a thousand times the
/// others', Clarabel solves it at once.) Where it
/// does prove infeasibility, at seeds the native solver proves so too, the reason is
/// the checked ray.
#[cfg(feature = "clarabel")]
#[test]
fn clarabel_claims_infeasibility_only_with_a_checked_ray() {
    for (seed, friction) in [(30179, 0.25), (37476, 0.25)] {
        let p = grasp(seed, friction);
        let mut inscribed = p.clone();
        inscribed.linearization.sides = 8;
        let held = run(&inscribed, Backend::ActiveSet, Cones::Linear);
        assert_eq!(held.status, Status::Optimal, "seed {seed}");
        let clarabel = run(&p, Backend::Clarabel, Cones::Exact);
        assert_ne!(
            clarabel.status,
            Status::Infeasible,
            "seed {seed}: {:?}",
            clarabel.reason
        );
        // The strict run leaves no trace: the same solver gives the same answer again.
        let config = SolverConfig {
            backend: Some(Backend::Clarabel),
            cones: Cones::Exact,
            ..Default::default()
        };
        let mut solver = GraspSolver::new(&p, &config).unwrap();
        let first = solver
            .solve(&p.wrench, &WarmStart::default())
            .unwrap()
            .clone();
        let again = solver.solve(&p.wrench, &WarmStart::default()).unwrap();
        assert_eq!(first.status, clarabel.status, "seed {seed}");
        // The first run's claim, and why it did not hold, are on the answer.
        eprintln!("seed {seed}: {}, {:?}", first.status, first.warnings);
        assert!(
            first
                .warnings
                .iter()
                .any(|w| w.contains("torque terms left")),
            "seed {seed}: {:?}",
            first.warnings
        );
        assert_eq!(
            (again.status, again.objective.to_bits()),
            (first.status, first.objective.to_bits()),
            "seed {seed}"
        );
        assert_eq!(
            run(&p, Backend::ActiveSet, Cones::Exact).status,
            Status::Optimal
        );
    }
    for (seed, friction) in [(30226, 0.25), (30411, 0.25), (30992, 0.25), (31206, 0.25)] {
        let p = grasp(seed, friction);
        let clarabel = run(&p, Backend::Clarabel, Cones::Exact);
        assert_eq!(clarabel.status, Status::Infeasible, "seed {seed}");
        assert!(
            matches!(clarabel.reason, Some(Reason::DualRay { value, stationarity }) if value < 0.0 && stationarity <= 1e-7),
            "seed {seed}: {:?}",
            clarabel.reason
        );
        assert_eq!(
            run(&p, Backend::ActiveSet, Cones::Exact).status,
            Status::Infeasible
        );
    }
}

/// Inscribed polyhedra that hold a grasp prove it feasible, however large its torques:
/// a dual ray proves only that none lies within |value| / stationarity times the
/// problem's scale. The paper's example with an entry of G made 1e-6 to 1e-8 of the
/// rest (found by a mutation fuzz of the fixtures) is held only by torques 1e6 to 1e8
/// times its scale; the native exact solver called the last infeasible by a ray whose
/// torque terms cancelled to 1.4e-10. It now says `numerical_failure`, and why.
#[test]
fn a_grasp_the_inscribed_polyhedra_hold_is_never_infeasible() {
    for eps in [1e-6, 1e-7, 1e-8] {
        let mut p = fixture("paper-example");
        p.grasp_matrix[(2, 6)] = -eps;
        p.grasp_matrix[(3, 7)] = 0.12593805902239033;
        let linear = run(&p, Backend::ActiveSet, Cones::Linear);
        assert_eq!(linear.status, Status::Optimal, "{eps}");
        let exact = run(&p, Backend::ActiveSet, Cones::Exact);
        match exact.status {
            // (At 1e-7 the interior-point answer's gap bounds σ to 3e-9 of the optimum.)
            Status::Optimal | Status::AlmostOptimal => {
                assert!(exact.objective <= linear.objective, "{eps}")
            }
            Status::NumericalFailure => assert!(
                format!("{}", exact.reason.as_ref().unwrap()).contains("inscribed polyhedra hold"),
                "{eps}: {:?}",
                exact.reason
            ),
            s => panic!("{eps}: {s}, {:?}", exact.reason),
        }
    }
}

/// Clarabel's `infeasible` from the equalities alone needs their least-squares point to
/// miss them by more than its own rounding: a finger joint 60 km from the object
/// (geometry form, found by the same fuzz) makes the consistency rows ill-conditioned,
/// and one row, whose coefficients on that point's large entries are rounding, was
/// judged against its own size. Both cone kinds said infeasible; the native solver
/// holds the grasp.
#[cfg(feature = "clarabel")]
#[test]
fn clarabel_judges_the_equalities_miss_against_their_conditioning() {
    let path = format!(
        "{}/../../fixtures/geometry/pinch.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    for (finger, joint) in [(0, 1), (1, 0)] {
        let mut g = v.clone();
        let x = &mut g["fingers"][finger]["joints"][joint]["origin"][0];
        *x = (x.as_f64().unwrap() * 1e6).into();
        let p = grasp_torque::file::parse_problem(&g.to_string()).unwrap();
        for cones in [Cones::Linear, Cones::Exact] {
            assert_eq!(run(&p, Backend::ActiveSet, cones).status, Status::Optimal);
            let c = run(&p, Backend::Clarabel, cones);
            assert_ne!(c.status, Status::Infeasible, "{cones:?}: {:?}", c.reason);
        }
    }
}

/// Clarabel's "solved" is its own measure in its own scaling: with a friction
/// coefficient of 600 (in the domain, up to 1e3) it stopped 3e-5 above the optimum and
/// said optimal. Its answer must now pass the conic certificate at 1e-8 to be
/// optimal; this one is almost optimal, and the warning gives the gap.
#[cfg(feature = "clarabel")]
#[test]
fn clarabel_is_optimal_only_with_its_certificate() {
    let path = format!(
        "{}/../../fixtures/geometry/pinch.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    for (mu, expected) in [(0.6, Status::Optimal), (600.0, Status::AlmostOptimal)] {
        v["contacts"][0]["mu"] = mu.into();
        let p = grasp_torque::file::parse_problem(&v.to_string()).unwrap();
        let native = run(&p, Backend::ActiveSet, Cones::Exact);
        let c = run(&p, Backend::Clarabel, Cones::Exact);
        assert_eq!(native.status, Status::Optimal);
        assert_eq!(c.status, expected, "μ = {mu}: {:?}", c.warnings);
        if expected == Status::Optimal {
            assert!(rel(c.objective, native.objective) <= 1e-7, "μ = {mu}");
        } else {
            assert!(c.objective >= native.objective * (1.0 - 1e-9), "μ = {mu}");
            assert!(
                c.warnings
                    .iter()
                    .any(|w| w.contains("optimality certificate")),
                "{:?}",
                c.warnings
            );
        }
    }
}

/// Grasps at the edge of feasibility, found by a sweep five times wider than the one
/// above (seeds 0..1500 at normal friction, 10000..11500 at a quarter of it): the exact
/// cones cannot hold them, but the circumscribed polyhedra can, even at N = 256. There
/// the interior-point method's multipliers grow along a ray of the dual, which proves
/// the grasp infeasible (they ended `numerical_failure` before). Clarabel agrees.
#[test]
fn grasps_at_the_edge_of_feasibility_are_proved_infeasible_by_a_dual_ray() {
    let edge = [
        (1084, 1.0),
        (10372, 0.25),
        (10595, 0.25),
        (10876, 0.25),
        (10965, 0.25),
        (11001, 0.25),
        (11048, 0.25),
        (11065, 0.25),
        (11103, 0.25),
        (11179, 0.25),
        // Found by the 12 000-grasp sweep (seeds 0..6000, 10000..16000): its ray shows
        // once the method runs on the null space of the equalities (before, it stalled).
        (14620, 0.25),
    ];
    for (seed, friction) in edge {
        let native = infeasible_as_clarabel_finds(seed, friction);
        match native.reason {
            Some(Reason::DualRay {
                value,
                stationarity,
            }) => {
                assert!(
                    value < -1e-6 && stationarity <= 1e-9,
                    "seed {seed}: {value:e} {stationarity:e}"
                );
            }
            ref other => panic!("seed {seed}: infeasible for {other:?}"),
        }
    }
}

/// The native exact solve of a sweep grasp, asserted `infeasible`, as Clarabel finds it
/// too (with the `clarabel` feature).
fn infeasible_as_clarabel_finds(seed: u64, friction: f64) -> Solution {
    let p = grasp(seed, friction);
    let native = run(&p, Backend::ActiveSet, Cones::Exact);
    assert_eq!(
        native.status,
        Status::Infeasible,
        "seed {seed}: {:?}",
        native.reason
    );
    #[cfg(feature = "clarabel")]
    {
        let clarabel = run(&p, Backend::Clarabel, Cones::Exact);
        assert_eq!(clarabel.status, Status::Infeasible, "seed {seed}");
    }
    native
}

/// Grasps the inscribed polyhedra cannot hold and the circumscribed ones at N = 8 can,
/// where Newton fails from their optimum: outside the exact cones, but close. The
/// circumscribed polyhedra at N = 32, within 0.5 % of the cones, prove most of them
/// infeasible before the interior-point method runs (a fifth of its time: before, each
/// was proved by the method's dual ray). Found by the 12 000-grasp sweep (`fallbacks
/// sweep`, 72 of its 110 dual-ray grasps). Clarabel agrees.
#[test]
fn finer_circumscribed_polyhedra_prove_grasps_infeasible_before_the_interior_point_method() {
    for (seed, friction) in [
        (370, 1.0),
        (1317, 1.0),
        (10031, 0.25),
        (11600, 0.25),
        (14328, 0.25),
    ] {
        let native = infeasible_as_clarabel_finds(seed, friction);
        assert!(
            matches!(
                native.reason,
                Some(Reason::OuterApproximation { sides: 32, .. })
            ),
            "seed {seed}: {:?}",
            native.reason
        );
        assert_eq!(native.method, None, "seed {seed}");
    }
}

/// The interior-point method's multipliers are checked for a ray of the dual at every
/// iterate, so a ray ends the run as soon as it shows. On seed 3992 at normal
/// friction it shows at the method's 16th iteration; the method itself runs on to its
/// cap of 80 iterations without the check. (Seed 1317, which this test used before, is
/// now proved infeasible by the circumscribed polyhedra at N = 32, before the method.)
#[test]
fn a_dual_ray_ends_the_interior_point_method_as_soon_as_it_shows() {
    let native = run(&grasp(3992, 1.0), Backend::ActiveSet, Cones::Exact);
    assert!(
        matches!(native.reason, Some(Reason::DualRay { .. })),
        "{:?}",
        native.reason
    );
    // (The count includes the polyhedral solves' and Newton's iterations.)
    assert!(native.iterations < 80, "{} iterations", native.iterations);
}

/// Grasps at a quarter of the friction whose optimum holds a cone at its apex: an
/// unloaded contact, or an SFCl contact on the edge `f_t = 0` of its cone. Found by a
/// sweep twenty times wider than the one above (seeds 0..6000 at normal friction,
/// 10000..16000 at a quarter of it). The inscribed optimum's key set cannot say so
/// (it holds independent faces only), so Newton failed there and the interior-point
/// method stalled: `numerical_failure`, where Clarabel finds the optimum. Newton now
/// reads the apex off the iterate, or puts a boundary there when its tail vanishes.
#[test]
fn cones_at_their_apex_are_solved_by_newton() {
    for seed in [10543, 10870, 11147, 14815] {
        let p = grasp(seed, 0.25);
        let native = newton_like_clarabel(&p, seed);
        // Some contact's tangential force vanishes against the largest force.
        let f = &native.contact_forces;
        let fmax = f.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut off = 0;
        let mut at_apex = 0;
        for c in &p.contacts {
            let d = c.dim();
            if d >= 3 && f[off].hypot(f[off + 1]) <= 1e-8 * fmax {
                at_apex += 1;
            }
            off += d;
        }
        assert!(at_apex >= 1, "seed {seed}: {f:?}");
    }
}

/// Ill-conditioned grasps where Newton fails from both polyhedra and the
/// interior-point method lost its last digits to rounding while its factor came from
/// the formed `P + Gᵀ W⁻² G`: its residuals fell to 1e-9–1e-7, then grew again until
/// the factor broke down (on the first two the scaled optimum ‖x‖² is 5e3 and 3e8,
/// against a right-hand side of size 1). All six ended `numerical_failure` once; then
/// Newton from the method's best iterate, or that iterate itself, finished them (on
/// the last, a hundredth of the friction, the iterate turned NaN after a best merit
/// of 4e-11, and the NaN iterate, whose norms read 0, was taken for the best). With
/// the factor from a QR of `[√P; W⁻¹ G]` the method converges on every one itself
/// (checked alone, as the backend's fallback); by default Newton now answers 201282,
/// 404279 and 500475 (a cone resting near its apex judged against its own terms).
/// Found by sweeps of unseen seeds (200000..202000 at a quarter and at half the
/// friction, 400000..405000 at a twentieth, 500000..502000 at a hundredth) and, seeds
/// 17551 and 12161, earlier ones. Checked against Clarabel when it is built, and
/// against σ(N) of inscribed polyhedra, which lie inside the cones, where they hold
/// the grasp.
#[test]
fn the_interior_point_method_finishes_ill_conditioned_grasps() {
    for (seed, friction) in [
        (201282, 0.25),
        (201233, 0.5),
        (17551, 0.25),
        (404279, 0.05),
        (12161, 0.25),
        (500475, 0.01),
    ] {
        let p = grasp(seed, friction);
        let answers = interior_point_like_clarabel(&p, seed);
        let mut fine = p.clone();
        fine.linearization.sides = 256;
        // (No inscribed polyhedron holds seed 12161.)
        let inscribed = run(&fine, Backend::ActiveSet, Cones::Linear);
        assert_eq!(inscribed.is_optimal(), seed != 12161, "seed {seed}");
        for native in answers {
            assert!(
                !inscribed.is_optimal() || native.objective <= inscribed.objective * (1.0 + 1e-9),
                "seed {seed}: {} above σ(256) = {}",
                native.objective,
                inscribed.objective
            );
        }
    }
}

/// Grasps whose interior-point run lost its dual residual to the formed matrix's
/// Cholesky factor (5e-13 growing to 1e-4 until the method stalled, its best iterate
/// a gap of 1.05e-9 short of the certificate) and ended `numerical_failure`, although
/// the inscribed polyhedra hold them: 30 of 80 000 at a hundredth and a fiftieth of
/// normal friction (seeds 500000..540000), one of 6 000 at a quarter. With the
/// factor from the QR of `[√P; W⁻¹ G]` the method converges on each (checked alone);
/// by default Newton now answers all four.
#[test]
fn the_interior_point_method_keeps_its_digits_at_low_friction() {
    for (seed, friction) in [(500889, 0.01), (502980, 0.01), (525864, 0.02), (4001, 0.25)] {
        interior_point_like_clarabel(&grasp(seed, friction), seed);
    }
}

/// The exact answer for `p`, asserted optimal by Newton and, when Clarabel is built,
/// within 1e-7 of Clarabel's σ.
fn newton_like_clarabel(p: &GraspProblem, seed: u64) -> Solution {
    optimal_like_clarabel(p, seed, "newton")
}

/// The exact answer for `p`, asserted optimal by `method` and, when Clarabel is built,
/// within 1e-7 of Clarabel's σ.
fn optimal_like_clarabel(p: &GraspProblem, seed: u64, method: &str) -> Solution {
    let native = run(p, Backend::ActiveSet, Cones::Exact);
    assert_eq!(native.method, Some(method), "seed {seed}");
    like_clarabel(p, seed, native)
}

/// `native` asserted optimal and, when Clarabel is built, within 1e-7 of Clarabel's σ.
fn like_clarabel(p: &GraspProblem, seed: u64, native: Solution) -> Solution {
    assert_eq!(
        native.status,
        Status::Optimal,
        "seed {seed} ({:?}): {:?}",
        native.method,
        native.reason
    );
    #[cfg(feature = "clarabel")]
    {
        let clarabel = run(p, Backend::Clarabel, Cones::Exact);
        assert_eq!(clarabel.status, Status::Optimal, "seed {seed}");
        let r = rel(native.objective, clarabel.objective);
        assert!(
            r <= 1e-7,
            "seed {seed}: {} vs {}",
            native.objective,
            clarabel.objective
        );
    }
    native
}

/// Grasps that once reached the interior-point method: its answer alone (the exact
/// backend's own fallback, as the core calls it after a refusal, with the core's check)
/// and the default path's, whichever method gives it, both optimal and like Clarabel's.
/// (Newton now answers many of them: see
/// `whole_hand_grasps_are_newtons_cold_and_in_a_control_loop`.)
fn interior_point_like_clarabel(p: &GraspProblem, seed: u64) -> [Solution; 2] {
    let config = SolverConfig {
        backend: Some(Backend::ActiveSet),
        ..exact_config()
    };
    let mut s = config.build(config.qp(p).unwrap()).unwrap();
    let mut alone = Solution::default();
    assert!(s.solve_fallback(&p.wrench, &mut alone), "seed {seed}");
    assert_eq!(alone.method, Some("interior_point"), "seed {seed}");
    s.problem()
        .complete(&p.wrench, s.residual_tolerance(), s.name(), &mut alone);
    let default = run(p, Backend::ActiveSet, Cones::Exact);
    [
        like_clarabel(p, seed, alone),
        like_clarabel(p, seed, default),
    ]
}

/// Cones the inscribed optimum puts at their apex while the exact optimum is not
/// quite there (normal friction, from the wider sweep). Seed 337: the cone is at its
/// apex, and Newton's first step, which only moves the multipliers, is taken whole.
/// Seed 900: the apex's dual leaves the dual cone, so the cone goes to its boundary,
/// first along the tangent plane that dual points to. Both went to the interior-point
/// method before.
///
/// Seeds 1693 and 1718: the cone leaves its apex for its boundary, then its iterate
/// passes near the apex again. Holding it to the tangent plane there once more made
/// Newton alternate between plane and boundary without converging; it is held to the
/// plane only from the apex, and a return is the apex piece again.
#[test]
fn cones_that_leave_their_apex_are_solved_by_newton() {
    for seed in [337, 900, 1693, 1718] {
        newton_like_clarabel(&grasp(seed, 1.0), seed);
    }
}

/// Grasps whose optimum has more pieces on their boundary than the reduced problem has
/// free directions (seed 1252: three cones and two directions), so that the last
/// piece's constraint depends on the others. It replaces the one whose multiplier it
/// drives to zero first, as in the dual active-set method; stacked, the dependent
/// constraints failed Newton's factorisation and the grasps went to the
/// interior-point method. (Seeds 1545 and 2139, two cones and one direction, are the
/// closed form's now; the unit test of the closed form runs Newton on 1545.)
#[test]
fn a_dependent_piece_replaces_one_of_the_others() {
    newton_like_clarabel(&grasp(1252, 1.0), 1252);
    for seed in [1545, 2139] {
        optimal_like_clarabel(&grasp(seed, 1.0), seed, "closed_form");
    }
}

/// Grasps whose multipliers are large against their answer (seed 10045 at a quarter of
/// the friction: 1e4 on an answer of size 8), where the merit refuses Newton's full
/// steps for the curvature of the boundaries (the Maratos effect) and the line search
/// damped every step to 1/16 until the iterations ran out. A second-order correction
/// of the rejected full step is taken whole instead.
#[test]
fn a_corrected_full_step_is_taken_where_the_merit_refuses_newtons() {
    for seed in [10045, 11280, 12255] {
        newton_like_clarabel(&grasp(seed, 0.25), seed);
    }
}

/// Grasps Newton cannot solve from the inscribed optimum (the guess cycles: a cone
/// near its apex, taken to the apex and back) but solves from the circumscribed
/// optimum, which lies just outside the cones. All six went to the interior-point
/// method before, at 120–360 µs a solve.
#[test]
fn newton_starts_again_from_the_circumscribed_optimum() {
    for (seed, friction) in [
        (1243, 1.0),
        (2282, 1.0),
        (5616, 1.0),
        (10590, 0.25),
        (13316, 0.25),
        (14047, 0.25),
    ] {
        newton_like_clarabel(&grasp(seed, friction), seed);
    }
}

/// Grasps whose Newton steps carried a cone near its apex past it (a small force on its
/// boundary, approached from a start farther out): declared at the apex, found not to
/// be, and sent back, the guess cycled from both polyhedral starts. With the step cut
/// short of the apex, Newton solves them. All six went to the interior-point method
/// before, at 270–1090 µs a solve.
#[test]
fn newton_steps_stop_short_of_a_cone_apex() {
    for (seed, friction) in [
        (1203, 1.0),
        (1782, 1.0),
        (4048, 1.0),
        (5600, 1.0),
        (12108, 0.25),
        (13404, 0.25),
    ] {
        newton_like_clarabel(&grasp(seed, friction), seed);
    }
}

/// Grasps whose optimum holds a contact barely loaded, on its cone's boundary within
/// 1e-6 of the apex (common at low friction): the cone leaves its apex for its tangent
/// plane, where Newton converges and, with the plane held to the end, never stopped
/// (a point of the plane is outside the cone by `‖s1‖ − uᵀs1`, 1e-7 here): all went to
/// the interior-point method. Converged on the plane, Newton now goes on with the
/// cone's own boundary from there. Seeds from the unseen sweeps at a twentieth,
/// a thirtieth and a hundredth of the friction, and 15900 from the tests' sweep.
/// Seed 501284 (a hundredth) went on to the interior-point method: Newton's guess
/// spent eleven damped steps reaching it, and its chord steps then contracted at 0.45
/// with 4e-9 to go, until the guess's steps ran out. On the last chord ratio alone they
/// stopped there, at a force 3e-10 outside its cone and σ 1.9e-10 below Clarabel's; the
/// method's answer is 1.1e-11 from it. With a cone resting near its apex judged
/// against its own terms Newton answers it; the method alone is still checked on it.
#[test]
fn newton_leaves_the_tangent_planes_it_converged_on() {
    for (seed, friction) in [
        (15900, 0.25),
        (402841, 0.05),
        (600391, 0.03),
        (600583, 0.03),
    ] {
        newton_like_clarabel(&grasp(seed, friction), seed);
    }
    interior_point_like_clarabel(&grasp(501284, 0.01), 501284);
}

/// The inscribed linearisations bracket σ* from above and close in on it as N grows;
/// the native optimum is in its exact cones.
#[test]
fn refining_the_linearisation_converges_to_the_native_optimum() {
    for name in [
        "paper-example",
        "hand3-pcwf",
        "hand4-sfcl",
        "hand4-sfce",
        "hand5-mixed",
    ] {
        let mut p = fixture(name);
        let exact = run(&p, Backend::ActiveSet, Cones::Exact);
        assert_eq!(exact.status, Status::Optimal, "{name}");
        assert!(
            exact.diagnostics.cone_violation
                <= 1e-9
                    * exact
                        .contact_forces
                        .iter()
                        .fold(0.0f64, |a, v| a.max(v.abs()))
        );
        let mut last = f64::INFINITY;
        for sides in [8, 32, 128] {
            p.linearization.sides = sides;
            p.linearization.latitudes = sides / 4;
            // The paper's SFCe latitudes converge too slowly to show it (docs/benchmarks.md).
            p.linearization.sfce_spacing = grasp_torque::SfceSpacing::Uniform;
            let s = run(&p, Backend::ActiveSet, Cones::Linear);
            assert!(
                s.objective >= exact.objective * (1.0 - 1e-9),
                "{name} N={sides}"
            );
            assert!(s.objective <= last * (1.0 + 1e-9));
            last = s.objective;
        }
        assert!(
            rel(last, exact.objective) < 2e-3,
            "{name}: σ(128) {last} vs σ* {}",
            exact.objective
        );
    }
}

/// Warm and cold solves agree, and a controller's `resolve` after a 1 % wrench change
/// gives Clarabel's answer.
#[cfg(feature = "clarabel")]
#[test]
fn resolve_in_a_control_loop_matches_cold_solves() {
    let p = fixture("hand5-mixed");
    let mut ctl = GraspSolver::new(&p, &exact_config()).unwrap();
    let mut w = p.wrench;
    for k in 0..20 {
        w[k % 6] *= 1.01;
        let warm = ctl.resolve(&w).unwrap().clone();
        let mut q = p.clone();
        q.wrench = w;
        let cold = run(&q, Backend::Clarabel, Cones::Exact);
        assert_eq!(warm.status, cold.status);
        assert!(rel(warm.objective, cold.objective) < 1e-7);
    }
}

/// Grasps that only the interior-point method solves cold (Newton cycles from both
/// polyhedral starts: a force on its boundary near the apex). A control loop starts
/// Newton from the last answer, the interior-point method's the first time, and Newton
/// converges from there: every warm re-solve is by Newton and gives the cold answer.
/// Before, every re-solve went the cold way, at the method's cost (docs/benchmarks.md,
/// "Warm starts from the interior-point answer").
#[test]
fn a_control_loop_starts_newton_from_the_interior_point_answer() {
    for (seed, friction) in [(10028, 0.25), (10369, 0.25), (15668, 0.25)] {
        let p = grasp(seed, friction);
        let mut w = p.wrench;
        let path = (0..30).map(|k| {
            w[k % 6] *= 1.0 + 0.01 * ((k as f64) * 0.7).sin();
            w
        });
        newton_ticks_give_the_cold_answers(seed, &p, path, 1e-9, None);
    }
}

/// A control loop on `p` along `path`, after a first solve at `p.wrench` by the
/// interior-point method: every tick is by Newton and within `tol` (relative) of a
/// cold solve's σ, made by `cold_method` if given.
fn newton_ticks_give_the_cold_answers(
    seed: u64,
    p: &GraspProblem,
    path: impl Iterator<Item = [f64; 6]>,
    tol: f64,
    cold_method: Option<&str>,
) {
    let mut ctl = GraspSolver::new(p, &exact_config()).unwrap();
    let mut cold = GraspSolver::new(p, &exact_config()).unwrap();
    let first = ctl.resolve(&p.wrench).unwrap();
    assert_eq!(first.method, Some("interior_point"), "seed {seed}");
    for (k, w) in path.enumerate() {
        let warm = ctl.resolve(&w).unwrap().clone();
        let fresh = cold.solve(&w, &WarmStart::default()).unwrap();
        assert!(
            warm.is_optimal() && fresh.is_optimal(),
            "seed {seed} tick {k}"
        );
        assert_eq!(warm.method, Some("newton"), "seed {seed} tick {k}");
        if cold_method.is_some() {
            assert_eq!(fresh.method, cold_method, "seed {seed} tick {k}");
        }
        assert!(
            rel(warm.objective, fresh.objective) < tol,
            "seed {seed} tick {k}: {} vs {}",
            warm.objective,
            fresh.objective
        );
    }
}

/// Grasps with a force on its boundary near the apex, where a 1 % change of the wrench
/// moves the force by more than Newton's model of the cone holds: the warm solve
/// straight from the last answer fails, and before the follow every tick of a control
/// loop went to the interior-point method (120–500 µs a tick, docs/benchmarks.md,
/// "Following the wrench"). Newton now follows the wrench from the last answer in
/// steps: every tick after the first is by Newton and gives the cold answer, which the
/// interior-point method finds. Both are certified to 1e-9 of the gap, so the
/// objectives agree to twice that.
#[test]
fn a_control_loop_follows_the_wrench_where_newton_loses_a_force_near_the_apex() {
    for (seed, friction) in [
        (1541, 1.0),
        (10376, 0.25),
        (11901, 0.25),
        (12509, 0.25),
        (12678, 0.25),
    ] {
        let p = grasp(seed, friction);
        // As `grasp-torque bench` nudges the wrench: forces up, moments down.
        let near: [f64; 6] = std::array::from_fn(|i| p.wrench[i] * if i < 3 { 1.01 } else { 0.99 });
        let path = (0..6).map(|k| if k % 2 == 0 { near } else { p.wrench });
        newton_ticks_give_the_cold_answers(seed, &p, path, 2e-9, Some("interior_point"));
    }
}

/// A control loop's chord steps, on factors from another wrench, stop on a rate they
/// have measured twice. On the first ratio (1.4e-5: the first step takes up the
/// wrench's change, which those factors map almost exactly) every tick of this grasp
/// stopped with 4.8e-3 of its last step still to go, 9.4e-10 above the cold σ, and
/// was certified (the gap's tolerance is relative to terms several times σ). The
/// chord's own target is 1e-11 of the iterate, about 2e-11 of σ; cold Newton's as
/// much: 1e-10.
#[test]
fn a_control_loops_chord_steps_stop_on_a_measured_rate() {
    for (seed, friction) in [(11095, 0.25), (10000, 0.25), (0, 1.0)] {
        let p = grasp(seed, friction);
        let near: [f64; 6] = std::array::from_fn(|i| p.wrench[i] * if i < 3 { 1.01 } else { 0.99 });
        let mut ctl = GraspSolver::new(&p, &exact_config()).unwrap();
        let mut cold = GraspSolver::new(&p, &exact_config()).unwrap();
        for k in 0..8 {
            let w = if k % 2 == 0 { p.wrench } else { near };
            let warm = ctl.resolve(&w).unwrap().clone();
            let fresh = cold.solve(&w, &WarmStart::default()).unwrap();
            assert!(
                warm.is_optimal() && fresh.is_optimal(),
                "seed {seed} tick {k}"
            );
            let r = rel(warm.objective, fresh.objective);
            assert!(
                r <= 1e-10,
                "seed {seed} tick {k}: {} vs {} ({r:.1e})",
                warm.objective,
                fresh.objective
            );
        }
    }
}

/// A control loop of warm re-solves (the hot path: chord iterations on the kept Newton
/// factors) gives the cold answers, on every bundled fixture, without Clarabel.
#[test]
fn warm_and_cold_solves_agree() {
    let fixtures = [
        "paper-example",
        "hand3-pcwf",
        "hand4-sfcl",
        "hand4-sfce",
        "hand5-mixed",
    ]
    .map(|name| (name.to_string(), fixture(name)));
    // Grasps whose optimum holds a cone at or near its apex: a warm re-solve keeps the
    // apex piece.
    let apex = [(10543, 0.25), (14815, 0.25), (337, 1.0), (900, 1.0)]
        .map(|(seed, friction)| (format!("seed {seed}"), grasp(seed, friction)));
    for (name, p) in fixtures.into_iter().chain(apex) {
        let mut ctl = GraspSolver::new(&p, &exact_config()).unwrap();
        let mut cold = GraspSolver::new(&p, &exact_config()).unwrap();
        let mut w = p.wrench;
        for k in 0..30 {
            w[k % 6] *= 1.0 + 0.01 * ((k as f64) * 0.7).sin();
            let warm = ctl.resolve(&w).unwrap().clone();
            let fresh = cold.solve(&w, &WarmStart::default()).unwrap();
            assert_eq!(warm.status, fresh.status, "{name} step {k}");
            if fresh.is_optimal() {
                assert!(
                    rel(warm.objective, fresh.objective) < 1e-9,
                    "{name} step {k}: {} vs {}",
                    warm.objective,
                    fresh.objective
                );
            }
        }
    }
}

/// Where the consistency equalities fix the torque (as many independent rows as joints:
/// seed 992275 of the sweep, 10 joints, forces `[fz | fx fy fz mz | fz]` by a square G),
/// that one point decides the grasp. Its slacks outside a cone or row are a ray of the
/// dual: before, a point between the cones and the circumscribed polyhedra at N = 32
/// went on to the interior-point method on the equalities' null space, which had no
/// variable, and panicked (found by `scripts/sweep_vs_clarabel.sh 990000 993000 1`).
/// Along the wrenches from one the contacts' normal forces hold to the seed's, the
/// answer is optimal up to the boundary and infeasible by that ray beyond it, with
/// nothing undecided between (a ray proves beyond the certificate's tolerance, where
/// no free direction gives it a horizon); Clarabel agrees wherever it decides.
#[test]
fn a_torque_the_equalities_fix_is_decided_by_its_own_slacks() {
    let p = grasp(992275, 1.0);
    let decide = |t: f64| {
        let mut q = p.clone();
        // The contacts' unit normal forces, balanced by their wrench.
        let mut f = vec![0.0; q.grasp_matrix.ncols()];
        let mut at = 0;
        for c in &q.contacts {
            f[at + c.normal_index()] = 1.0;
            at += c.dim();
        }
        let w_in = q.grasp_matrix.mul_vec(&f);
        for (v, a) in q.wrench.iter_mut().zip(&w_in) {
            *v = (1.0 - t) * a + t * *v;
        }
        (run(&q, Backend::ActiveSet, Cones::Exact), q)
    };
    let is_ray = |s: &Solution| {
        s.status == Status::Infeasible
            && s.method == Some("closed_form")
            && matches!(s.reason, Some(Reason::DualRay { value, stationarity })
                if value < -1e-9 && stationarity <= 1e-9)
    };
    let (start, _) = decide(0.0);
    assert_eq!(start.status, Status::Optimal, "{:?}", start.reason);
    let (end, _) = decide(1.0);
    assert!(
        is_ray(&end),
        "{:?} {:?} {:?}",
        end.status,
        end.method,
        end.reason
    );
    // The boundary, by bisection on the status.
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if decide(mid).0.status == Status::Optimal {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    // Just past it the miss is beyond the certificate's tolerance, and the ray proves
    // it: no wrench is left undecided.
    for k in (2..=12).rev() {
        let t = hi * (1.0 + 10f64.powi(-k));
        let (s, _) = decide(t);
        assert!(
            is_ray(&s),
            "t = t*(1 + 1e-{k}): {:?} {:?}",
            s.status,
            s.reason
        );
    }
    for i in 0..=20 {
        let t = f64::from(i) / 20.0;
        let (s, q) = decide(t);
        if t < lo {
            assert_eq!(s.status, Status::Optimal, "t = {t}: {:?}", s.reason);
        } else {
            assert!(is_ray(&s), "t = {t}: {:?} {:?}", s.status, s.reason);
        }
        #[cfg(feature = "clarabel")]
        {
            let c = run(&q, Backend::Clarabel, Cones::Exact);
            if matches!(c.status, Status::Optimal | Status::Infeasible) {
                assert_eq!(s.status, c.status, "t = {t}");
            }
            if c.status == Status::Optimal {
                assert!(rel(s.objective, c.objective) <= 1e-7, "t = {t}");
            }
        }
        let _ = q;
    }
}

/// The native linear solver's `optimal` at N = 8 is not proof that a grasp is feasible:
/// it holds its rows normalised in the free torques, and on
/// `fixtures/fuzz/inscribed-optimum-outside.json` (`fuzz_answers.py` seed 18013: one
/// joint's row of Jᵀ at 1.1e7, another's one entry of 1.3e-9) its answer leaves a
/// contact outside its cone by 2.6e3 N, which the core refuses. The exact solver took
/// it as proof, looked for no infeasibility, and ended at the interior-point method's
/// iteration cap saying the grasp was feasible. cvxpy (`scripts/oracle_file.py`) and
/// Clarabel call it infeasible; so does the native solver now, by the circumscribed
/// polyhedra at N = 256, which it tries where the inscribed optimum fails the core's
/// check. Clarabel's multipliers cancel the torque terms against the largest column
/// (1.7e-16) but leave 0.41 of a free direction's own: no proof
/// (`RayCheck::directions`), so its answer is a numerical failure, never `optimal`.
#[test]
fn an_inscribed_optimum_outside_the_cones_proves_nothing() {
    let p = fixture("fuzz/inscribed-optimum-outside");
    let linear = run(&p, Backend::ActiveSet, Cones::Linear);
    assert_eq!(
        linear.status,
        Status::NumericalFailure,
        "{:?}",
        linear.reason
    );
    let s = run(&p, Backend::ActiveSet, Cones::Exact);
    assert_eq!(s.status, Status::Infeasible, "{:?}", s.reason);
    assert!(
        matches!(s.reason, Some(Reason::OuterApproximation { .. })),
        "{:?}",
        s.reason
    );
    #[cfg(feature = "clarabel")]
    {
        let s = run(&p, Backend::Clarabel, Cones::Exact);
        assert_eq!(
            s.status,
            Status::NumericalFailure,
            "Clarabel: {:?}",
            s.reason
        );
    }
}

/// An exact-cone answer from an interior-point iterate stopped short states the bound
/// its gap gives, and the bound holds (`fixtures/fuzz/sfce-interior-point-stopped-short.json`,
/// `fuzz_answers.py` seed 229135: three SFCe contacts, a joint's row of Jᵀ scaled,
/// torque limits). In six systems of units each answer is `optimal` (within 2e-9) or
/// `almost_optimal` with a bound of at most 1e-6, and any two agree within their
/// bounds; with Clarabel, each is its certified σ* to that bound and Clarabel's own
/// tolerance (1e-8).
#[test]
fn an_exact_answer_stopped_short_states_a_bound_that_holds() {
    let p = fixture("fuzz/sfce-interior-point-stopped-short");
    let mut answers = Vec::new();
    for (l, f) in [
        (1.0, 1.0),
        (1.1, 20.5),
        (1e-3, 1e3),
        (1e2, 1e-2),
        (0.29, 75.9),
        (1e3, 1e3),
    ] {
        let q = grasp_testkit::rescale(&p, l, f);
        let s = run(&q, Backend::ActiveSet, Cones::Exact);
        let b = stated_excess(&s);
        assert!(b <= 1e-6, "lengths × {l:e}, forces × {f:e}: bound {b:e}");
        let sigma = s.objective / ((l * f) * (l * f));
        #[cfg(feature = "clarabel")]
        {
            let c = run(&q, Backend::Clarabel, Cones::Exact);
            assert_eq!(c.status, Status::Optimal, "{:?}", c.reason);
            let star = c.objective / ((l * f) * (l * f));
            assert!(
                rel(sigma, star) <= b + 1e-8,
                "lengths × {l:e}, forces × {f:e}: σ {sigma} against Clarabel's {star}"
            );
        }
        answers.push((sigma, b));
    }
    for (i, &(a, ba)) in answers.iter().enumerate() {
        for &(c, bc) in &answers[i + 1..] {
            assert!(
                rel(a, c) <= ba + bc,
                "σ {a} (bound {ba:e}) and {c} ({bc:e})"
            );
        }
    }
}

/// Whole-hand grasps (`fixtures/large/`, from `scripts/large_grasps.py`: 20 to 22
/// contacts of all four models, 68 to 74 joints, limits and weights): the native exact
/// answer, and the interior-point method's alone (whose factor, a QR of a few hundred
/// rows applied by rows, no bundled small grasp reaches at this size), agree with
/// Clarabel's exact σ* to 1e-7 and lie below every native linearisation's σ(N).
#[cfg(feature = "clarabel")]
#[test]
fn whole_hand_grasps_agree_with_clarabel() {
    for seed in [163, 240, 392] {
        let p = fixture(&format!("large/large-{seed}"));
        for native in interior_point_like_clarabel(&p, seed) {
            for sides in [4, 8, 16] {
                let mut q = p.clone();
                q.linearization.sides = sides;
                let lin = run(&q, Backend::ActiveSet, Cones::Linear);
                assert_eq!(lin.status, Status::Optimal, "{seed} N = {sides}");
                assert!(
                    native.objective <= lin.objective * (1.0 + 1e-9),
                    "{seed} N = {sides}: σ* {} > σ(N) {}",
                    native.objective,
                    lin.objective
                );
            }
        }
    }
}

/// Whole-hand grasps whose contacts' loads span seven decades: a contact on its cone's
/// boundary with a slack of 1.6e-4 beside torques of 690 was within 1e-6 of the largest
/// and so "near its apex" to Newton, which sent it there, took it back to the boundary
/// and again until its guesses ran out, from the polyhedra and from the interior-point
/// method's own answer alike: every solve and every tick of a control loop took the
/// interior-point method (10–15 ms a tick). Nearness is now judged against the cone's
/// own terms, or against the largest variable only while the iterates close on the
/// apex. Cold and in a control loop (the wrench 1 % away and back, as `grasp-torque
/// bench` moves it) each answer is Newton's and gives the cold σ, like Clarabel's.
#[test]
fn whole_hand_grasps_are_newtons_cold_and_in_a_control_loop() {
    for seed in [163, 240] {
        let p = fixture(&format!("large/large-{seed}"));
        optimal_like_clarabel(&p, seed, "newton");
        let near: [f64; 6] = std::array::from_fn(|i| p.wrench[i] * if i < 3 { 1.01 } else { 0.99 });
        let mut ctl = GraspSolver::new(&p, &exact_config()).unwrap();
        let mut cold = GraspSolver::new(&p, &exact_config()).unwrap();
        for k in 0..6 {
            let w = if k % 2 == 0 { near } else { p.wrench };
            let warm = ctl.resolve(&w).unwrap().clone();
            let fresh = cold.solve(&w, &WarmStart::default()).unwrap();
            assert!(warm.is_optimal() && fresh.is_optimal(), "{seed} tick {k}");
            assert_eq!(warm.method, Some("newton"), "{seed} tick {k}");
            assert_eq!(fresh.method, Some("newton"), "{seed} tick {k}");
            // Both certified to 1e-9 of the gap.
            assert!(
                rel(warm.objective, fresh.objective) < 2e-9,
                "{seed} tick {k}: {} vs {}",
                warm.objective,
                fresh.objective
            );
        }
    }
}
