//! A proptest-based fuzzer (cargo-fuzz needs a nightly toolchain, which this project
//! does not assume). Two targets, each from fixed seeds so CI and every developer see
//! the same cases; `GRASP_FUZZ_CASES` raises the case count for a longer run
//! (`.ci/run` runs a time-bounded one), and `GRASP_FUZZ_SEED` draws other cases.
//!
//! - **The parser**: mutations of the bundled fixtures and of the corpus of hostile
//!   inputs in `fixtures/fuzz/` (bytes flipped, cut or inserted; numbers replaced by
//!   extreme values). `parse_problem` and the whole solve never panic.
//! - **The solve**: random finite problems anywhere in the input domain (entries over
//!   twelve orders of magnitude, every contact model, friction at the domain's ends).
//!   No panic, every reported number finite, and `optimal` implies residuals that an
//!   independent recomputation confirms.
//!
//! Both solve with every backend and cone kind (the native exact solver among them),
//! cold and then as a control loop does: `resolve` on the wrench 1 % away and back,
//! through the hot starts.
#![cfg(all(feature = "active-set", feature = "clarabel"))]

use grasp_torque::{
    matrix::Matrix, solve, Backend, Cones, ContactModel, GraspProblem, GraspSolver, Solution,
    SolverConfig, TorqueLimit, WarmStart,
};
use proptest::prelude::*;

fn cases(default: u32) -> u32 {
    std::env::var("GRASP_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The cases' seed: 1414, or `GRASP_FUZZ_SEED` for others.
fn seed() -> u64 {
    std::env::var("GRASP_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1414)
}

fn corpus() -> Vec<String> {
    grasp_testkit::fixture_paths(&["", "fuzz", "geometry", "table1"])
        .iter()
        .map(|f| std::fs::read_to_string(f).unwrap())
        .collect()
}

const EXTREMES: [&str; 12] = [
    "1e308",
    "-1e308",
    "5e-324",
    "0",
    "-0.0",
    "1e12",
    "1.0000001e12",
    "1e-300",
    "1e999",
    "18446744073709551616",
    "-1",
    "3",
];

/// Solves with every backend and cone kind, cold and then in a control loop; checks
/// the contract.
fn check_solves(p: &GraspProblem) {
    for (backend, cones) in [
        (Backend::ActiveSet, Cones::Linear),
        (Backend::ActiveSet, Cones::Exact),
        (Backend::Clarabel, Cones::Linear),
        (Backend::Clarabel, Cones::Exact),
    ] {
        let config = SolverConfig {
            backend: Some(backend),
            cones,
            ..Default::default()
        };
        let Ok(mut solver) = GraspSolver::new(p, &config) else {
            continue;
        };
        // The cold solve, then a control loop's hot path: `resolve` on the wrench
        // 1 % away (forces up, moments down) and back.
        let near: [f64; 6] = std::array::from_fn(|i| p.wrench[i] * if i < 3 { 1.01 } else { 0.99 });
        for (tick, w) in [p.wrench, near, p.wrench].iter().enumerate() {
            let answer = if tick == 0 {
                solver.solve(w, &WarmStart::default())
            } else {
                solver.resolve(w)
            };
            let Ok(s) = answer else {
                break;
            };
            check_answer(p, backend, cones, w, s);
        }
    }
}

/// No number that is not finite; `optimal` holds the object, by a recomputation.
fn check_answer(p: &GraspProblem, backend: Backend, cones: Cones, wrench: &[f64; 6], s: &Solution) {
    assert!(
        s.objective.is_finite(),
        "{backend}/{cones}: σ {}",
        s.objective
    );
    assert!(s
        .torque
        .iter()
        .chain(&s.contact_forces)
        .all(|v| v.is_finite()));
    if s.is_optimal() {
        // Every torque within its limits, against the limit and the largest torque.
        let tmax = s.torque.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (j, l) in p.torque_limits.iter().flatten().enumerate() {
            let (Some(l), Some(&t)) = (l, s.torque.get(j)) else {
                continue;
            };
            let (lo, hi) = l.bounds();
            let out = (lo - t).max(t - hi);
            assert!(
                out <= 1e-6 * (lo.abs().min(hi.abs()) + tmax),
                "{backend}/{cones}: τ_{j} = {t} outside {l:?}"
            );
        }
        // Recompute ‖G f − w‖ from scratch, relative to the problem's scale: the
        // largest contact force (mz as mz/mu_torsion) seen through the row.
        let g = &p.grasp_matrix;
        let mut unit = Vec::new();
        for c in &p.contacts {
            unit.extend((0..c.dim()).map(|k| match (c, k) {
                (
                    ContactModel::SfcLinear { mu_torsion, .. }
                    | ContactModel::SfcElliptic { mu_torsion, .. },
                    3,
                ) => *mu_torsion,
                _ => 1.0,
            }));
        }
        let fmax = s
            .contact_forces
            .iter()
            .zip(&unit)
            .fold(0.0f64, |a, (v, u)| a.max((v / u).abs()))
            .max(formed(p, s, wrench, &unit));
        for i in 0..6 {
            let through: f64 = (0..g.ncols())
                .map(|j| (g[(i, j)] * unit[j]).abs())
                .sum::<f64>()
                * fmax;
            let r: f64 = (0..g.ncols())
                .map(|j| g[(i, j)] * s.contact_forces[j])
                .sum::<f64>()
                - wrench[i];
            let scale = through + wrench[i].abs();
            assert!(
                r.abs() <= 1e-5 * scale,
                "{backend}/{cones}: row {i} residual {r} of {scale}"
            );
        }
    }
}

/// With passive torques, the largest size of the terms a force component is formed
/// from, `|Z| [|w|; |T| |u| + |τ_p|]` with `Z = [G; Jᵀ]⁺` by nalgebra's SVD, in force
/// units: forces cancelled to nearly zero keep the rounding of those terms (contacts
/// the passive torques alone leave unloaded, 1e-16 N formed from terms of 1 N). Zero
/// without passive torques, or where the SVD gives nothing finite.
fn formed(p: &GraspProblem, s: &Solution, wrench: &[f64; 6], unit: &[f64]) -> f64 {
    let Some(tp) = p.passive_torque.as_deref() else {
        return 0.0;
    };
    let (g, jt) = (&p.grasp_matrix, &p.jacobian_transpose);
    let (n, m) = (g.ncols(), jt.nrows());
    let a = nalgebra::DMatrix::from_fn(
        6 + m,
        n,
        |i, j| {
            if i < 6 {
                g[(i, j)]
            } else {
                jt[(i - 6, j)]
            }
        },
    );
    let eps = 1e-15 * a.amax();
    let Ok(z) = a.pseudo_inverse(eps) else {
        return 0.0;
    };
    let joint: Vec<f64> = (0..m)
        .map(|i| {
            let tu: f64 = match &p.transmission {
                Some(t) => (0..t.matrix.ncols())
                    .map(|k| (t.matrix[(i, k)] * s.torque.get(k).copied().unwrap_or(0.0)).abs())
                    .sum(),
                None => s.torque.get(i).copied().unwrap_or(0.0).abs(),
            };
            tu + tp.get(i).copied().unwrap_or(0.0).abs()
        })
        .collect();
    let terms = |j: usize| -> f64 {
        (0..6 + m)
            .map(|i| z[(j, i)].abs() * if i < 6 { wrench[i].abs() } else { joint[i - 6] })
            .sum::<f64>()
            / unit[j]
    };
    let top = (0..n).map(terms).fold(0.0f64, f64::max);
    if top.is_finite() {
        top
    } else {
        0.0
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: cases(300),
        rng_seed: proptest::test_runner::RngSeed::Fixed(seed()),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn the_parser_and_solve_never_panic_on_mutated_files(
        which in any::<prop::sample::Index>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), 0u8..4, any::<u8>(), any::<prop::sample::Index>()), 1..6),
    ) {
        let corpus = corpus();
        let mut text = corpus[which.index(corpus.len())].clone().into_bytes();
        for (at, kind, byte, extreme) in edits {
            if text.is_empty() {
                break;
            }
            let i = at.index(text.len());
            match kind {
                0 => text[i] = byte,
                1 => { text.truncate(i); }
                2 => text.insert(i, byte),
                _ => {
                    // Replace the number that starts at or after i by an extreme value.
                    if let Some(start) = text[i..].iter().position(|c| c.is_ascii_digit()).map(|k| i + k) {
                        let end = text[start..].iter().position(|c| !(c.is_ascii_digit() || *c == b'.' || *c == b'e' || *c == b'-')).map_or(text.len(), |k| start + k);
                        let e = EXTREMES[extreme.index(EXTREMES.len())];
                        text.splice(start..end, e.bytes());
                    }
                }
            }
        }
        let text = String::from_utf8_lossy(&text);
        if let Ok(p) = grasp_torque::parse_problem(&text) {
            check_solves(&p);
        }
    }

    #[test]
    fn solve_never_panics_and_optimal_means_held(
        seed in any::<u64>(),
        models in prop::collection::vec(0u8..4, 1..5),
        joints in 1usize..10,
        exponent in -6i32..6,
        mu_end in any::<bool>(),
    ) {
        // A small fixed PRNG, so the case is reproducible from its inputs.
        let mut state = seed | 1;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let contacts: Vec<ContactModel> = models.iter().map(|m| {
            let mu = if mu_end { 1e-3 } else { 0.2 + next().abs() };
            let mu_torsion = 10f64.powi(exponent).clamp(1e-9, 1e9);
            match m {
                0 => ContactModel::Fpc,
                1 => ContactModel::Pcwf { mu },
                2 => ContactModel::SfcLinear { mu, mu_torsion },
                _ => ContactModel::SfcElliptic { mu, mu_torsion },
            }
        }).collect();
        let n: usize = contacts.iter().map(ContactModel::dim).sum();
        let scale = 10f64.powi(exponent);
        let g = Matrix::from_fn(6, n, |_, _| next() * scale);
        let jt = Matrix::from_fn(joints, n, |_, _| next());
        let w = [next() * scale, next() * scale, next() * scale, next(), next(), next()];
        let mut p = GraspProblem::new(g, jt, w, contacts);
        p.linearization.sides = 4 + (seed % 8) as usize;
        if seed % 3 == 0 {
            // Torque limits of every form over six decades: |τ| ≤ t, [lo, hi] of
            // either sign or excluding 0, one side open.
            p.torque_limits = Some((0..joints).map(|_| {
                let s = 10f64.powi((next() * 3.0) as i32);
                let (a, b) = (next() * s, next() * s);
                let (lo, hi) = (a.min(b), a.max(b));
                match (next() * 5.0) as i32 {
                    0 => None,
                    1 => Some(TorqueLimit::Symmetric(hi.abs().max(1e-3))),
                    2 => Some(TorqueLimit::Range(Some(lo), None)),
                    3 => Some(TorqueLimit::Range(None, Some(hi))),
                    _ => Some(TorqueLimit::Range(Some(lo), Some(hi))),
                }
            }).collect());
        }
        if p.validate().is_ok() {
            check_solves(&p);
            // A cold solve through the trait object as well.
            let config = SolverConfig::default();
            if let Ok(qp) = config.qp(&p) {
                let mut s = config.build(qp).unwrap();
                let sol = solve(s.as_mut(), &p.wrench, &WarmStart::default()).unwrap();
                prop_assert!(sol.objective.is_finite());
            }
        }
    }
}
