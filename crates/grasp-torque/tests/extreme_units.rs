//! Units at the edges of the input domain: the force unit, the torque unit, or both with
//! the wrench, changed by factors from 1e-300 to 1e10 (the domain's normal numbers up to
//! its 1e12 bound), on every bundled fixture in its own convention (`euclidean` ones
//! included). The native solver, linear and exact cones, must give the same answer in
//! the new units: σ computed from the rescaled torques matches the unscaled σ to the
//! certificate's accuracy.
//!
//! Before: a torque unit 1e8 times the wrench's made `[G; Jᵀ]` look rank-deficient to
//! the plain A⁺ (`infeasible`); a whole problem at 1e-170 lost its rank to underflowing
//! squares (`infeasible`); torques at 1e-155 of the forces' scale gave NaN torques.
#![cfg(feature = "active-set")]

use grasp_torque::{
    solve, Backend, Cones, GraspProblem, GraspSolver, Solution, SolverConfig, Status, WarmStart,
};

fn run(p: &GraspProblem, cones: Cones) -> Solution {
    let config = SolverConfig {
        backend: Some(Backend::ActiveSet),
        cones,
        ..Default::default()
    };
    let mut s = config.build(config.qp(p).unwrap()).unwrap();
    solve(s.as_mut(), &p.wrench, &WarmStart::default()).unwrap()
}

/// Which unit changes.
#[derive(Clone, Copy, Debug)]
enum Unit {
    /// Contact forces measured in units of 1/c: G and Jᵀ times c.
    Force,
    /// Torques in units of 1/c: Jᵀ, torque limits, passive torques (and τ) times c.
    Torque,
    /// Forces, moments and torques all in units of 1/c, lengths unchanged: G, Jᵀ, the
    /// wrench and torque limits times c, contact forces unchanged.
    Everything,
}

/// The problem in the new units, and the factor on its torques.
fn rescaled(p: &GraspProblem, unit: Unit, c: f64) -> (GraspProblem, f64) {
    let mut q = p.clone();
    let scale = |m: &mut grasp_torque::Matrix| m.as_mut_slice().iter_mut().for_each(|v| *v *= c);
    match unit {
        Unit::Force => {
            scale(&mut q.grasp_matrix);
            scale(&mut q.jacobian_transpose);
            if let Some(fmin) = &mut q.min_normal_force {
                fmin.iter_mut().for_each(|v| *v /= c);
            }
        }
        Unit::Torque | Unit::Everything => {
            scale(&mut q.jacobian_transpose);
            if let Some(lim) = &mut q.torque_limits {
                lim.iter_mut().flatten().for_each(|v| *v = v.scaled(c));
            }
            if let Some(t) = &mut q.initial_torque {
                t.iter_mut().for_each(|v| *v *= c);
            }
            if let Some(t) = &mut q.passive_torque {
                t.iter_mut().for_each(|v| *v *= c);
            }
            if matches!(unit, Unit::Everything) {
                scale(&mut q.grasp_matrix);
                q.wrench.iter_mut().for_each(|v| *v *= c);
            }
        }
    }
    let tau_factor = if matches!(unit, Unit::Force) { 1.0 } else { c };
    (q, tau_factor)
}

/// Whether every number of `q` is in the domain: within its bound of 1e12 (a factor of
/// 1e10 takes some beyond it, as 1e-300 does minimum normal forces), and normal where
/// not zero (1e-300 makes the geometry fixtures' entries at rounding level, such as
/// the Shadow tripod's 4e-19, subnormal).
fn within_bound(q: &GraspProblem) -> bool {
    let limits: Vec<f64> = q
        .torque_limits
        .iter()
        .flatten()
        .flatten()
        .flat_map(|l| [l.lower(), l.upper()])
        .flatten()
        .collect();
    q.grasp_matrix
        .as_slice()
        .iter()
        .chain(q.jacobian_transpose.as_slice())
        .chain(&q.wrench)
        .chain(q.min_normal_force.iter().flatten())
        .chain(q.passive_torque.iter().flatten())
        .chain(&limits)
        .all(|&v| grasp_torque::problem::in_domain(v))
}

/// Σ w_j (τ_j / factor)²: σ in the original units, where σ itself may underflow.
fn sigma_back(p: &GraspProblem, s: &Solution, factor: f64) -> f64 {
    s.torque
        .iter()
        .enumerate()
        .map(|(j, t)| {
            let w = p.torque_weights.as_ref().map_or(1.0, |w| w[j]);
            w * (t / factor) * (t / factor)
        })
        .sum()
}

#[test]
fn units_at_the_edges_of_the_domain_do_not_change_the_answer() {
    let mut checked = 0;
    for path in grasp_testkit::fixture_paths(&["", "table1", "geometry", "hands"]) {
        let p = grasp_torque::load_problem(&path).unwrap();
        let name = path.display();
        for (cones, tol) in [(Cones::Linear, 1e-9), (Cones::Exact, 2e-9)] {
            let base = run(&p, cones);
            assert!(base.is_optimal(), "{name} {cones}: {:?}", base.reason);
            for unit in [Unit::Force, Unit::Torque, Unit::Everything] {
                for c in [
                    1e-300, 1e-250, 1e-200, 1e-150, 1e-100, 1e-30, 1e-8, 1e8, 1e10,
                ] {
                    let (q, factor) = rescaled(&p, unit, c);
                    if !within_bound(&q) {
                        continue;
                    }
                    let s = run(&q, cones);
                    let at = format!("{name} {cones} {unit:?} × {c:e}");
                    assert!(s.is_optimal(), "{at}: {:?} {:?}", s.status, s.reason);
                    assert!(s.torque.iter().all(|t| t.is_finite()), "{at}");
                    let sigma = sigma_back(&p, &s, factor);
                    assert!(
                        (sigma - base.objective).abs() <= tol * base.objective,
                        "{at}: σ = {sigma} against {}",
                        base.objective
                    );
                    checked += 1;
                }
            }
        }
    }
    eprintln!("{checked} rescaled problems");
    assert!(checked > 500, "{checked}");
}

/// Torque limits far above the torques (1e3 to 1e12 times the largest, as a user who
/// writes 1e9 for "no limit" sets them) leave the answer alone. Before, the limits'
/// constant right-hand sides set the solvers' scale: at 1e6 times the torques the
/// native linear solve accepted a cone row violated by 1e-2 (caught by the residual
/// check: `numerical_failure`), and Clarabel's answers and the native exact one, all
/// called optimal, were up to 4e5 times the true σ (hand3-pcwf at 1e9); once the
/// scale was right, Clarabel stopped (InsufficientProgress) from about 1e9.
#[test]
fn loose_torque_limits_do_not_change_the_answer() {
    let mut checked = 0;
    for path in grasp_testkit::fixture_paths(&["", "table1", "geometry", "hands"]) {
        let p = grasp_torque::load_problem(&path).unwrap();
        let name = path.display();
        for (cones, tol) in [(Cones::Linear, 1e-9), (Cones::Exact, 2e-9)] {
            let mut free = p.clone();
            free.torque_limits = None;
            let base = run(&free, cones);
            assert!(base.is_optimal(), "{name} {cones}: {:?}", base.reason);
            let largest = base.torque.iter().fold(0.0f64, |a, t| a.max(t.abs()));
            for factor in [1e3, 1e6, 1e9, 1e12] {
                let limit = (largest * factor).min(grasp_torque::problem::MAX_MAGNITUDE);
                let mut q = p.clone();
                q.torque_limits = Some(vec![Some(limit.into()); p.actuated()]);
                let s = run(&q, cones);
                let at = format!("{name} {cones} limits {limit:e}");
                assert!(s.is_optimal(), "{at}: {:?} {:?}", s.status, s.reason);
                assert!(
                    (s.objective - base.objective).abs() <= tol * base.objective,
                    "{at}: σ = {} against {}",
                    s.objective,
                    base.objective
                );
                // Clarabel solves with the far limits relaxed, then checks them.
                #[cfg(feature = "clarabel")]
                {
                    let config = SolverConfig {
                        backend: Some(Backend::Clarabel),
                        cones,
                        ..Default::default()
                    };
                    let mut c = config.build(config.qp(&q).unwrap()).unwrap();
                    let c = solve(c.as_mut(), &q.wrench, &WarmStart::default()).unwrap();
                    assert!(
                        c.is_optimal(),
                        "{at}: Clarabel {:?} {:?}",
                        c.status,
                        c.reason
                    );
                    assert!(
                        (c.objective - base.objective).abs() <= 1e-6 * base.objective,
                        "{at}: Clarabel σ = {} against {}",
                        c.objective,
                        base.objective
                    );
                }
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "{checked}");
}

/// A contact the wrench leaves unloaded, through a row no torque affects beyond
/// rounding (`fixtures/fuzz/unloaded-by-the-wrench.json`, `fuzz_answers.py` seed 17234):
/// the row's value is a difference of terms that cancel, which rounds to 1e-12 of the
/// wrench below the cone. That rounding was judged against `‖w‖∞` times the largest
/// row's terms, which lengths in other units change, so with lengths 81 times smaller
/// the grasp was `infeasible`. It is held, with the same σ, in every unit system.
#[test]
fn a_contact_the_wrench_leaves_unloaded_is_held_in_any_units() {
    let p = fuzz_fixture("unloaded-by-the-wrench");
    for (cones, tol) in [(Cones::Linear, 1e-9), (Cones::Exact, 2e-9)] {
        let base = run(&p, cones);
        assert!(base.is_optimal(), "{cones}: {:?}", base.reason);
        for l in [1e-3, 1.0 / 81.0, 0.1, 10.0, 81.0, 1e3] {
            for f in [1e-3, 1.0, 1e3] {
                let q = grasp_testkit::rescale(&p, l, f);
                let s = run(&q, cones);
                let at = format!("{cones}, lengths × {l:e}, forces × {f:e}");
                assert!(s.is_optimal(), "{at}: {:?} {:?}", s.status, s.reason);
                let sigma = sigma_back(&p, &s, l * f);
                assert!(
                    (sigma - base.objective).abs() <= tol * base.objective,
                    "{at}: σ = {sigma} against {}",
                    base.objective
                );
            }
        }
    }
}

/// A fuzz fixture.
fn fuzz_fixture(name: &str) -> GraspProblem {
    let path = format!(
        "{}/../../fixtures/fuzz/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    grasp_torque::load_problem(&path).unwrap()
}

/// Both cones `optimal`, the exact σ* at `sigma_star` (cvxpy's, to 1e-9) and the
/// linearised σ not below it.
fn assert_held_at(p: &GraspProblem, sigma_star: f64) {
    let exact = run(p, Cones::Exact);
    assert!(exact.is_optimal(), "{:?} {:?}", exact.status, exact.reason);
    assert!(
        (exact.objective - sigma_star).abs() <= 1e-9 * sigma_star,
        "σ* = {} against {sigma_star}",
        exact.objective
    );
    let linear = run(p, Cones::Linear);
    assert!(
        linear.is_optimal(),
        "{:?} {:?}",
        linear.status,
        linear.reason
    );
    assert!(linear.objective >= exact.objective * (1.0 - 1e-9));
}

/// A row set aside as one no torque affects, on a grasp where a joint's tiny row of Jᵀ
/// sets that rounding level high (`fixtures/fuzz/set-aside-row-held.json`,
/// `fuzz_answers.py` seed 220): the wrench alone leaves it 5e-10 N below its bound,
/// within the feasibility tolerance of the wrench's terms. It was `infeasible`; the
/// answer is cvxpy's optimum (`python3 scripts/oracle_file.py FILE`, exact cones, 2e-11
/// from the native σ*), and the core's check holds every row on it.
#[test]
fn a_row_set_aside_within_the_tolerance_of_the_wrench_is_held() {
    assert_held_at(&fuzz_fixture("set-aside-row-held"), 3.423746127636e4);
}

/// A row that the free torques move, beside a joint whose force response is 1e8 times
/// the others' (`fixtures/fuzz/row-beside-a-pinned-joint.json`, `fuzz_answers.py` seed
/// 34182: joint 7's row of Jᵀ made 1e-8 times joint 9's, so the equalities pin its
/// torque). The largest row of H is that joint's, and a face whose part in the free
/// torques is 8e-8 of its own norm fell below the rounding level of that largest row:
/// set aside as one no torque affects, it made the grasp `infeasible` by 42.7 N. Rows
/// are now also judged against their own norm; the answer is cvxpy's optimum (5e-12
/// from the native σ*).
#[test]
fn a_row_beside_a_pinned_joint_is_not_set_aside() {
    assert_held_at(&fuzz_fixture("row-beside-a-pinned-joint"), 1.545814591206);
}

/// A joint whose moment arms are 8e8 times the others' beside one the equalities pin
/// (`fixtures/fuzz/long-arm-beside-a-pinned-joint.json`, `fuzz_answers.py` seed 89215:
/// joint 2's row of Jᵀ made 1e-8 of joint 1's). The equalities' null basis came from a
/// decomposition of C D⁻¹, whose columns span 1e18, and missed the rows by 3e-9 of
/// their terms (ε times the largest column): with lengths × 0.087 and forces × 28, the
/// linear answer spent that slack on a squeeze of 1700 N and a σ 1.3e-4 below the
/// optimum, and the exact σ* was `optimal` at 3.3e-7 above it. The basis now keeps each
/// row's digits (`orthonormal_columns` in grasp-core): in every unit system tried the
/// linear σ is DAQP's optimum of the exported QP (9.156345108e8, 2e-12 apart in SI and
/// in those units, which the exact cones do not better here), and the exact one too:
/// `optimal` within the certificate's 2e-9, or `almost_optimal` (the interior-point
/// method's gap on this conditioning, up to 7e-8) within the bound it states.
#[test]
fn a_long_arm_beside_a_pinned_joint_keeps_the_equalities() {
    let p = fuzz_fixture("long-arm-beside-a-pinned-joint");
    let sigma_star = 9.156345108e8;
    for l in [1e-3, 0.0866, 1.0, 11.5, 1e3] {
        for f in [1e-3, 1.0, 28.25, 1e3] {
            let q = grasp_testkit::rescale(&p, l, f);
            for cones in [Cones::Linear, Cones::Exact] {
                let s = run(&q, cones);
                let at = format!("{cones}, lengths × {l:e}, forces × {f:e}");
                let bound = match s.status {
                    Status::Optimal if cones == Cones::Linear => 1e-9,
                    Status::Optimal => 2e-9,
                    Status::AlmostOptimal if cones == Cones::Exact => stated_bound(&s),
                    _ => panic!("{at}: {:?} {:?}", s.status, s.reason),
                };
                let r = (sigma_back(&p, &s, l * f) - sigma_star) / sigma_star;
                assert!(r >= -1e-9 && r <= bound + 1e-9, "{at}: σ off by {r:e}");
            }
        }
    }
}

/// A face the free torques move only at 3e-11 of its own norm, beside rows of 1.4e13
/// (`fixtures/fuzz/face-moved-beside-a-pinned-joint.json`, `fuzz_answers.py nested`
/// seed 48783: joint 3's row of Jᵀ reduced to one tiny entry). Its part in y, 26, is
/// below both bounds for a row no torque affects, so it is set aside; the wrench alone
/// misses it by 2.1, which made the grasp `infeasible` at N = 16, 32 and 64 although
/// the answer at N = 8 holds it (each polygon's vertices are the next one's). Such a
/// row's violation at y = 0 now proves nothing, and the core's check judges the
/// answer: σ falls as N doubles, down to cvxpy's σ* (`scripts/oracle_file.py`).
#[test]
fn a_face_the_free_torques_barely_move_is_no_proof_of_infeasibility() {
    let p = fuzz_fixture("face-moved-beside-a-pinned-joint");
    let sigma_star = 7.692612522668e-2;
    let exact = run(&p, Cones::Exact);
    assert!(exact.is_optimal(), "{:?} {:?}", exact.status, exact.reason);
    assert!((exact.objective - sigma_star).abs() <= 1e-9 * sigma_star);
    let mut last = f64::INFINITY;
    for sides in [8, 16, 32, 64] {
        let mut q = p.clone();
        q.linearization.sides = sides;
        let s = run(&q, Cones::Linear);
        assert!(s.is_optimal(), "N = {sides}: {:?} {:?}", s.status, s.reason);
        assert!(
            s.objective <= last * (1.0 + 1e-9),
            "N = {sides}: σ {} after {last}",
            s.objective
        );
        assert!(
            s.objective >= sigma_star * (1.0 - 1e-9),
            "N = {sides}: σ {} below σ*",
            s.objective
        );
        last = s.objective;
    }
}

/// A dual ray that reaches no further than the circumscribed polyhedra's optimum
/// (`fixtures/fuzz/dual-ray-short-of-the-polyhedra.json`, `fuzz_answers.py nested`
/// seed 7105: the Ability tripod with a joint limited to τ ≤ 0 and a torsional length
/// of 4.7e-6). The interior-point method's multipliers passed the ray's check, but no
/// feasible torque was excluded beyond 1.458e4 from the equalities' point in the scaled
/// variables, and the polyhedra's optimum lies at 1.462e4: the grasp was `infeasible`,
/// where the inscribed polyhedra at N = 32 and 64 and Clarabel hold it. A ray must now
/// reach a thousand times that far; the answer is Clarabel's σ* (0.5592541096066).
#[test]
fn a_dual_ray_short_of_the_polyhedra_proves_nothing() {
    let p = fuzz_fixture("dual-ray-short-of-the-polyhedra");
    let sigma_star = 0.5592541096066;
    let exact = run(&p, Cones::Exact);
    assert!(exact.is_optimal(), "{:?} {:?}", exact.status, exact.reason);
    assert!(
        (exact.objective - sigma_star).abs() <= 1e-9 * sigma_star,
        "σ* = {}",
        exact.objective
    );
    for sides in [32, 64] {
        let mut q = p.clone();
        q.linearization.sides = sides;
        let s = run(&q, Cones::Linear);
        assert!(s.is_optimal(), "N = {sides}: {:?} {:?}", s.status, s.reason);
        assert!(s.objective >= exact.objective * (1.0 - 1e-9));
    }
}

/// The dual phase's iterate is its key set's minimiser only in exact arithmetic
/// (`fixtures/fuzz/iterate-beside-its-minimiser.json`, `fuzz_answers.py nested` seed
/// 154509: the Ability tripod with joint 2's row of Jᵀ reduced to one entry of 6.4e-11,
/// its column of H 1e10 times the others'). At N = 16 the final key set is three faces
/// whose normals agree to 1e-9, and the iterate, 5 % from their minimiser, was returned
/// as optimal: σ 2.2e-3 above the optimum, and above σ at N = 8. Steps 2–4 now walk it
/// to the minimiser. σ(16) is cvxpy's on the exported QP with joint 2's column scaled to
/// 1 (0.11635157761732), and the minimum-norm point of those three faces in 50-digit
/// arithmetic (0.11635157761726), in any units.
#[test]
fn the_dual_iterate_is_no_answer_until_it_is_the_minimiser() {
    let mut p = fuzz_fixture("iterate-beside-its-minimiser");
    let sigma16 = 0.1163515776173;
    p.linearization.sides = 16;
    let s = run(&p, Cones::Linear);
    assert!(s.is_optimal(), "{:?} {:?}", s.status, s.reason);
    assert!(
        (s.objective - sigma16).abs() <= 1e-9 * sigma16,
        "σ(16) = {}",
        s.objective
    );
    p.linearization.sides = 8;
    let s8 = run(&p, Cones::Linear);
    assert!(s8.is_optimal(), "{:?} {:?}", s8.status, s8.reason);
    assert!(
        s.objective <= s8.objective * (1.0 + 1e-9),
        "σ(8) = {}",
        s8.objective
    );
    let exact = run(&p, Cones::Exact);
    assert!(exact.is_optimal(), "{:?} {:?}", exact.status, exact.reason);
    assert!(exact.objective <= s.objective * (1.0 + 1e-9));
    // The same answer in other units.
    p.linearization.sides = 16;
    for unit in [Unit::Force, Unit::Torque, Unit::Everything] {
        for c in [1e-3, 37.0, 1e3] {
            let (q, factor) = rescaled(&p, unit, c);
            let s = run(&q, Cones::Linear);
            assert!(
                s.is_optimal(),
                "{unit:?} × {c}: {:?} {:?}",
                s.status,
                s.reason
            );
            let back = sigma_back(&q, &s, factor);
            assert!(
                (back - sigma16).abs() <= 1e-9 * sigma16,
                "{unit:?} × {c}: σ(16) = {back}"
            );
        }
    }
}

/// The bound an `almost_optimal` exact answer states in its warning.
fn stated_bound(s: &Solution) -> f64 {
    s.warnings
        .iter()
        .find_map(|w| w.strip_prefix("the exact-cone answer's certificate bounds σ only to "))
        .and_then(|w| w.split(' ').next()?.parse().ok())
        .expect("the bound in a warning")
}

/// A contact at its apex, a sliver from a force on a polygon's vertex
/// (`fixtures/fuzz/apex-sliver-beside-a-vertex.json`, `fuzz_answers.py` seed 221997):
/// a torque limit at 0 on a joint only the second contact loads keeps that contact
/// unloaded, and the third contact's force then sits on its cone along a vertex of
/// every polygon. The rows' rounding leaves the two 1e-11 apart, and the native key
/// set there (multipliers of 2.3e8 to 2.3e10 on two faces and the limit) was σ 14 %
/// above the exact cones' σ*, and 4.4e-6 apart between systems of units. The rows
/// relaxed within tolerance find the key set that reaches it: in 20 systems of units
/// σ(N) falls as N doubles from 4 to 32, from 1.4e-9 above σ* to 1.6e-10 above it,
/// each N's σ the same in every system to 1e-12.
#[test]
fn an_apex_a_sliver_from_a_vertex_is_reached_within_tolerance() {
    let p = fuzz_fixture("apex-sliver-beside-a-vertex");
    let sigma_star = 0.190_072_315_040_257_6;
    let mut first: Option<Vec<f64>> = None;
    for l in [1e-3, 1.58e-3, 1.0, 11.5, 1e3] {
        for f in [1e-3, 1.0, 101.5, 1e3] {
            let mut q = grasp_testkit::rescale(&p, l, f);
            let at = format!("lengths × {l:e}, forces × {f:e}");
            let exact = run(&q, Cones::Exact);
            assert_eq!(exact.status, Status::Optimal, "{at}: {:?}", exact.reason);
            let r = (sigma_back(&p, &exact, l * f) - sigma_star) / sigma_star;
            assert!(r.abs() <= 1e-9, "{at}: exact σ* off by {r:e}");
            let mut sigmas = Vec::new();
            for sides in [4, 8, 16, 32] {
                q.linearization.sides = sides;
                let s = run(&q, Cones::Linear);
                assert_eq!(
                    s.status,
                    Status::Optimal,
                    "{at}, N = {sides}: {:?}",
                    s.reason
                );
                let sigma = sigma_back(&p, &s, l * f);
                let r = (sigma - sigma_star) / sigma_star;
                assert!(
                    (-1e-12..=2e-9).contains(&r),
                    "{at}, N = {sides}: σ off by {r:e}"
                );
                if let Some(&last) = sigmas.last() {
                    assert!(sigma <= last, "{at}, N = {sides}: σ {sigma} after {last}");
                }
                sigmas.push(sigma);
            }
            let first = first.get_or_insert_with(|| sigmas.clone());
            for (a, b) in first.iter().zip(&sigmas) {
                assert!(
                    (a - b).abs() <= 1e-12 * a,
                    "{at}: σ {b} where the first system gives {a}"
                );
            }
        }
    }
}

/// The same grasp in a control loop (`GraspSolver::resolve`, the wrench walking by 1 %
/// a tick, both ways): every tick, hot or not, is the cold solve's answer to 1e-12,
/// with the relaxed key set's σ.
#[test]
fn a_control_loop_keeps_the_key_set_found_within_tolerance() {
    let p = fuzz_fixture("apex-sliver-beside-a-vertex");
    let config = SolverConfig {
        backend: Some(Backend::ActiveSet),
        ..Default::default()
    };
    let mut ctl = GraspSolver::new(&p, &config).unwrap();
    let mut w = p.wrench;
    for k in 0..40 {
        w[k % 6] *= if k % 12 < 6 { 1.01 } else { 1.0 / 1.01 };
        let warm = ctl.resolve(&w).unwrap().clone();
        let mut q = p.clone();
        q.wrench = w;
        let cold = run(&q, Cones::Linear);
        assert_eq!(warm.status, Status::Optimal, "tick {k}: {:?}", warm.reason);
        assert_eq!(cold.status, Status::Optimal, "tick {k}: {:?}", cold.reason);
        assert!(
            (warm.objective - cold.objective).abs() <= 1e-12 * cold.objective,
            "tick {k}: σ {} warm, {} cold",
            warm.objective,
            cold.objective
        );
    }
}

/// A grasp whose torques' scales in the objective are 1e8 apart
/// (`fixtures/fuzz/one-joint-in-another-unit.json`, `fuzz_answers.py` seed 236143:
/// Table 1's carbon pen with joint 5's row of Jᵀ × 2.5e7, its weight left at 1). Every
/// solve that gives no answer says so in a warning naming both ends and the spread,
/// here computed from the file (`√w_j Σ_i |Jᵀ_ji|`, the contacts being PCwF); a solve
/// that answers, or one whose joint is in a unit nearer the others', carries none. The iteration cap
/// of 1 forces the no-answer on the linear solve.
#[test]
fn a_grasp_without_an_answer_names_its_torque_spread() {
    let p = fuzz_fixture("one-joint-in-another-unit");
    let scales = |p: &GraspProblem| -> Vec<f64> {
        let jt = &p.jacobian_transpose;
        (0..jt.nrows())
            .map(|j| {
                let w = p.torque_weights.as_ref().map_or(1.0, |w| w[j]);
                w.sqrt() * jt.row(j).iter().map(|v| v.abs()).sum::<f64>()
            })
            .collect()
    };
    let s = scales(&p);
    let by = |a: &usize, b: &usize| s[*a].total_cmp(&s[*b]);
    let (hi, lo) = (
        (0..s.len()).max_by(by).unwrap(),
        (0..s.len()).min_by(by).unwrap(),
    );
    let ratio = s[hi] / s[lo];
    assert!(ratio > 1e7, "the fixture's spread {ratio:e}");
    let note = |s: &Solution| {
        s.warnings
            .iter()
            .filter(|w| w.starts_with("the torques' scales in the objective"))
            .cloned()
            .collect::<Vec<_>>()
    };
    let capped = |p: &GraspProblem| {
        let mut config = SolverConfig {
            backend: Some(Backend::ActiveSet),
            ..Default::default()
        };
        config.active_set.max_iterations = 1;
        let mut solver = config.build(config.qp(p).unwrap()).unwrap();
        solve(solver.as_mut(), &p.wrench, &WarmStart::default()).unwrap()
    };
    let a = capped(&p);
    assert_eq!(a.status, Status::IterationLimit);
    let [w] = note(&a).try_into().expect("one warning on the spread");
    let name = |j: usize| p.joint_names[j].clone();
    for part in [format!("{ratio:.1e} apart"), name(hi), name(lo)] {
        assert!(w.contains(&part), "{part:?} in {w:?}");
    }
    // Joint hi's torque in a unit 1e6 times larger: its row of Jᵀ 1e6 times smaller.
    // (Its weight cannot undo as much: weights are within 1e8 of each other.)
    let mut balanced = p.clone();
    for v in balanced.jacobian_transpose.row_mut(hi) {
        *v *= 1e-6;
    }
    let t = scales(&balanced);
    let (big, small) = t
        .iter()
        .fold((0.0f64, f64::INFINITY), |(a, b), v| (a.max(*v), b.min(*v)));
    assert!(big / small < 1e4, "the balanced spread {:e}", big / small);
    let b = capped(&balanced);
    assert_eq!(b.status, Status::IterationLimit);
    assert!(note(&b).is_empty(), "{:?}", b.warnings);
    for cones in [Cones::Linear, Cones::Exact] {
        let s = run(&p, cones);
        assert_eq!(
            note(&s).len(),
            usize::from(!s.status.has_answer()),
            "{cones:?}: {:?} {:?}",
            s.status,
            s.warnings
        );
    }
}

/// A grasp whose only admissible contact force is zero
/// (`fixtures/fuzz/only-zero-force-admissible.json`, `fuzz_answers.py` seed 246677: the
/// Allegro grasp unloaded, one contact's friction 0.026, joint 9's row of Jᵀ 7e-7 of
/// the others'). No squeeze is admissible (cvxpy: the largest normal force of one is
/// 3e-10 N), so the motors cancel the passive torques and σ* = Σ τ_p² (cvxpy's σ* in SI
/// units and with lengths × 0.1, to 1e-13). The tiny row leaves rows of H whose
/// entries cancelled from 1e6 times their norm in the free torques; with lengths 10
/// times smaller the native solver proved the grasp infeasible by a combination of
/// such rows, within their rounding. Such a proof now runs again with the rows relaxed by their rounding. The
/// linear answer is σ* in every unit system; the exact one is never `infeasible`.
#[test]
fn a_grasp_held_only_by_zero_force_is_held_in_any_units() {
    let p = fuzz_fixture("only-zero-force-admissible");
    let tp = p.passive_torque.as_ref().unwrap();
    let sigma_star: f64 = tp.iter().map(|t| t * t).sum();
    for l in [1e-3, 0.0385, 0.1, 1.0, 10.0, 1e3] {
        for f in [1e-3, 1.0, 67.6, 1e3] {
            let q = grasp_testkit::rescale(&p, l, f);
            let at = format!("lengths × {l:e}, forces × {f:e}");
            let s = run(&q, Cones::Linear);
            assert!(s.is_optimal(), "{at}: {:?} {:?}", s.status, s.reason);
            // Rows hold to the feasibility tolerance, 1e-9 of the scale, after a
            // relaxation of at most their rounding (m ε times 1e6 here, about 3e-9 of
            // it): σ moves by up to twice their sum, 8e-9, relative.
            let sigma = sigma_back(&p, &s, l * f);
            assert!(
                (sigma - sigma_star).abs() <= 1.2e-8 * sigma_star,
                "{at}: σ = {sigma} against {sigma_star}"
            );
            // The exact cones' optimum is the same (a zero force is in every cone):
            // within the certificate's 2e-9 where it is `optimal`.
            let e = run(&q, Cones::Exact);
            assert_ne!(e.status, Status::Infeasible, "{at}: {:?}", e.reason);
            if e.is_optimal() {
                let sigma = sigma_back(&p, &e, l * f);
                assert!(
                    (sigma - sigma_star).abs() <= 2e-9 * sigma_star,
                    "{at}: exact σ* = {sigma} against {sigma_star}"
                );
            }
        }
    }
}
