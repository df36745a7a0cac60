//! Torque limits that are not symmetric: `lower ≤ τ_j ≤ upper`, either side open (a
//! tendon that only pulls is `[0, f_max]`; MuJoCo's `forcerange` is any interval).
//! Checked against Clarabel on both cone kinds, against the symmetric limit they
//! generalise, and by mirroring a joint, which must mirror its range and its torque.
#![cfg(all(feature = "active-set", feature = "clarabel"))]

mod common;

use common::run;
use grasp_testkit::{synthetic_grasp, ModelMix, Rng, SynthSpec};
use grasp_torque::file::ModelName;
use grasp_torque::{Backend, Cones, GraspProblem, Solution, Status, TorqueLimit};

/// Native and Clarabel both answer, or neither does.
fn same_status(at: &str, native: &Solution, clarabel: &Solution) {
    assert_eq!(
        native.status.has_answer(),
        clarabel.status.has_answer(),
        "{at}: native {:?} {:?}, Clarabel {:?} {:?}",
        native.status,
        native.reason,
        clarabel.status,
        clarabel.reason
    );
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

/// A synthetic grasp; odd seeds have four soft fingers of two joints each (passive
/// internal forces).
fn grasp(seed: u64) -> GraspProblem {
    let mut spec = SynthSpec::default();
    if seed % 2 == 1 {
        spec.fingers = Some(4);
        spec.joints_per_finger = Some(2);
        spec.models = ModelMix::Only(if seed % 4 == 1 {
            ModelName::Sfcl
        } else {
            ModelName::Sfce
        });
    }
    synthetic_grasp(seed, &spec).into_problem().unwrap()
}

/// Random limits around the unlimited optimum `tau` (largest `s`), so that they bite:
/// none (half of them), symmetric, one sign only (`[0, u]` or `[−u, 0]`), one side open, or an
/// interval near τ_j that may exclude 0 or τ_j.
fn ranges(tau: &[f64], rng: &mut Rng) -> Vec<Option<TorqueLimit>> {
    let s = tau.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    tau.iter()
        .map(|&t| match rng.int(0, 8) {
            0..=3 => None,
            4 => Some(TorqueLimit::Symmetric(rng.uniform(0.3, 1.5) * s)),
            5 if rng.uniform(0.0, 1.0) < 0.5 => Some(TorqueLimit::Range(
                Some(0.0),
                Some(rng.uniform(0.3, 1.5) * s),
            )),
            5 => Some(TorqueLimit::Range(
                Some(-rng.uniform(0.3, 1.5) * s),
                Some(0.0),
            )),
            6 if rng.uniform(0.0, 1.0) < 0.5 => Some(TorqueLimit::Range(
                Some(t + rng.uniform(-0.3, 0.3) * s),
                None,
            )),
            6 => Some(TorqueLimit::Range(
                None,
                Some(t + rng.uniform(-0.3, 0.3) * s),
            )),
            _ => {
                let lo = t + rng.uniform(-0.5, 0.3) * s;
                Some(TorqueLimit::Range(
                    Some(lo),
                    Some(lo + rng.uniform(0.05, 1.0) * s),
                ))
            }
        })
        .collect()
}

/// Grasp `seed` with random ranges around its unlimited optimum (none if it has none),
/// and the generator that drew them.
fn limited(seed: u64, salt: u64) -> Option<(GraspProblem, Rng)> {
    let mut p = grasp(seed);
    let free = run(&p, Backend::ActiveSet, Cones::Linear);
    if !free.is_optimal() {
        return None;
    }
    let mut rng = Rng(seed ^ salt);
    p.torque_limits = Some(ranges(&free.torque, &mut rng));
    Some((p, rng))
}

/// How far `tau` is outside its limits, relative to the largest torque.
fn outside(p: &GraspProblem, tau: &[f64]) -> f64 {
    let s = tau.iter().fold(f64::MIN_POSITIVE, |a, v| a.max(v.abs()));
    let limits = p.torque_limits.as_deref().unwrap_or(&[]);
    tau.iter()
        .zip(limits)
        .filter_map(|(&t, l)| l.map(|l| (t, l)))
        .map(|(t, l)| {
            let below = l.lower().map_or(0.0, |lo| lo - t);
            let above = l.upper().map_or(0.0, |hi| t - hi);
            below.max(above) / s
        })
        .fold(0.0, f64::max)
}

/// Joints whose optimal torque sits on a bound (within 1e-7 of the largest torque).
fn on_a_bound(p: &GraspProblem, tau: &[f64]) -> usize {
    let s = tau.iter().fold(f64::MIN_POSITIVE, |a, v| a.max(v.abs()));
    let limits = p.torque_limits.as_deref().unwrap_or(&[]);
    tau.iter()
        .zip(limits)
        .filter(|(&t, l)| {
            l.is_some_and(|l| {
                [l.lower(), l.upper()]
                    .into_iter()
                    .flatten()
                    .any(|b| (t - b).abs() <= 1e-7 * s)
            })
        })
        .count()
}

/// 240 grasps with random ranges (`GRASP_RANGE_CASES` for more: 30 000 agreed, 13 061
/// optimal at N = 8, 14 004 infeasible): the native solver and Clarabel agree on the
/// status and σ, on the inscribed cones (N = 8) and on the exact cones; every answer
/// holds its limits exactly; the exact σ* is not above σ(8). Most answers hold a joint on a
/// bound.
#[test]
fn ranges_agree_with_clarabel_on_both_cone_kinds() {
    let (mut optimal, mut infeasible, mut bound, mut exact_optimal) = (0, 0, 0, 0);
    let n: u64 = std::env::var("GRASP_RANGE_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(240);
    for seed in 0..n {
        let Some((p, _)) = limited(seed, 0x7a6e) else {
            continue;
        };
        let a = run(&p, Backend::ActiveSet, Cones::Linear);
        let b = run(&p, Backend::Clarabel, Cones::Linear);
        same_status(&format!("seed {seed}"), &a, &b);
        let e = run(&p, Backend::ActiveSet, Cones::Exact);
        let c = run(&p, Backend::Clarabel, Cones::Exact);
        same_status(&format!("seed {seed} exact"), &e, &c);
        // Every answer holds its limits exactly, not to rounding: a backend ends on an
        // active limit only to rounding or its tolerance (a tendon that only pulled was
        // reported pushing by 5e-18), and the core puts it on the limit.
        for (s, what) in [
            (&a, "native"),
            (&b, "Clarabel"),
            (&e, "native exact"),
            (&c, "Clarabel exact"),
        ] {
            if s.status.has_answer() {
                assert_eq!(
                    outside(&p, &s.torque),
                    0.0,
                    "seed {seed} {what}: {:?}",
                    s.torque
                );
            }
        }
        if a.status.has_answer() {
            assert_eq!(a.status, Status::Optimal, "seed {seed}");
            optimal += 1;
            assert!(
                rel(a.objective, b.objective) <= 1e-6,
                "seed {seed}: σ {} vs Clarabel {}",
                a.objective,
                b.objective
            );
            bound += (on_a_bound(&p, &a.torque) > 0) as usize;
            assert!(e.status.has_answer(), "seed {seed}: exact {:?}", e.reason);
        } else {
            assert_eq!(a.status, Status::Infeasible, "seed {seed}: {:?}", a.reason);
            infeasible += 1;
        }
        if e.status.has_answer() {
            assert_eq!(e.status, Status::Optimal, "seed {seed}: {:?}", e.reason);
            exact_optimal += 1;
            assert!(
                rel(e.objective, c.objective) <= 1e-7,
                "seed {seed}: σ* {} vs Clarabel {}",
                e.objective,
                c.objective
            );
            if a.status.has_answer() {
                assert!(e.objective <= a.objective * (1.0 + 1e-9), "seed {seed}");
            }
        }
    }
    eprintln!(
        "{optimal} optimal at N = 8 ({bound} with a joint on a bound), {infeasible} infeasible; {exact_optimal} optimal on the exact cones"
    );
    assert!(optimal >= 80 && infeasible >= 50 && bound >= optimal / 2);
}

/// `[−t, t]` is `|τ| ≤ t`: the same rows, so the same answer bit for bit.
#[test]
fn a_symmetric_range_is_the_symmetric_limit() {
    for seed in 0..40u64 {
        let mut p = grasp(seed);
        let free = run(&p, Backend::ActiveSet, Cones::Linear);
        if !free.is_optimal() {
            continue;
        }
        let s = free.torque.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let m = p.joints();
        p.torque_limits = Some(
            (0..m)
                .map(|j| Some(TorqueLimit::Symmetric(s * (0.4 + 0.1 * j as f64))))
                .collect(),
        );
        let mut q = p.clone();
        q.torque_limits = Some(
            (0..m)
                .map(|j| {
                    let t = s * (0.4 + 0.1 * j as f64);
                    Some(TorqueLimit::Range(Some(-t), Some(t)))
                })
                .collect(),
        );
        for cones in [Cones::Linear, Cones::Exact] {
            let (a, b) = (
                run(&p, Backend::ActiveSet, cones),
                run(&q, Backend::ActiveSet, cones),
            );
            assert_eq!(a.status, b.status, "seed {seed}");
            assert_eq!(a.torque, b.torque, "seed {seed} {cones:?}");
        }
    }
}

/// Turning joint j's axis around negates its row of Jᵀ and its torque: the range
/// `[lo, hi]` becomes `[−hi, −lo]`, and the answer is the same with τ_j negated.
#[test]
fn mirroring_a_joint_mirrors_its_range() {
    let mut checked = 0;
    for seed in 0..60u64 {
        let Some((p, mut rng)) = limited(seed, 0x6d69) else {
            continue;
        };
        let j = rng.int(0, p.joints() - 1);
        let mut q = p.clone();
        for c in 0..q.jacobian_transpose.ncols() {
            q.jacobian_transpose[(j, c)] = -q.jacobian_transpose[(j, c)];
        }
        let limits = q.torque_limits.as_mut().unwrap();
        limits[j] = limits[j].map(|l| match l {
            TorqueLimit::Symmetric(t) => TorqueLimit::Symmetric(t),
            TorqueLimit::Range(lo, hi) => TorqueLimit::Range(hi.map(|v| -v), lo.map(|v| -v)),
        });
        for cones in [Cones::Linear, Cones::Exact] {
            let (a, b) = (
                run(&p, Backend::ActiveSet, cones),
                run(&q, Backend::ActiveSet, cones),
            );
            assert_eq!(a.status, b.status, "seed {seed} {cones:?}");
            if a.status.has_answer() {
                let s = a
                    .torque
                    .iter()
                    .fold(f64::MIN_POSITIVE, |x, v| x.max(v.abs()));
                for (k, (x, y)) in a.torque.iter().zip(&b.torque).enumerate() {
                    let y = if k == j { -y } else { *y };
                    assert!(
                        (x - y).abs() <= 1e-9 * s,
                        "seed {seed} {cones:?}: τ_{k} {x} vs {y}"
                    );
                }
                assert!(
                    rel(a.objective, b.objective) <= 1e-9,
                    "seed {seed} {cones:?}"
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 30, "{checked}");
}

/// With no load, τ = 0 is the answer unless a range excludes 0: then the contacts
/// must squeeze the object for the joint to reach its range, or cannot. Native and
/// Clarabel agree either way, and an answer holds the range; so with a load 1e-12 and
/// 1e-6 of the grasp's own, where the range, not the wrench, sets the answer's size
/// (Clarabel called such grasps infeasible while the scale came from the wrench alone).
#[test]
fn an_unloaded_grasp_with_a_range_that_excludes_zero() {
    let (mut squeezed, mut infeasible) = (0, 0);
    for seed in 0..40u64 {
        let base = grasp(seed);
        let free = run(&base, Backend::ActiveSet, Cones::Linear);
        if !free.is_optimal() {
            continue;
        }
        let s = free.torque.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let m = base.joints();
        let j = seed as usize % m;
        let mut limits = vec![None; m];
        let sign = if seed % 3 == 0 { -1.0 } else { 1.0 };
        let (lo, hi) = (0.05 * s, 0.5 * s);
        limits[j] = Some(if sign > 0.0 {
            TorqueLimit::Range(Some(lo), Some(hi))
        } else {
            TorqueLimit::Range(Some(-hi), Some(-lo))
        });
        for load in [0.0, 1e-12, 1e-6] {
            let mut p = base.clone();
            p.wrench = p.wrench.map(|v| v * load);
            p.torque_limits = Some(limits.clone());
            for cones in [Cones::Linear, Cones::Exact] {
                let at = format!("seed {seed}, load {load:e}, {cones:?}");
                let a = run(&p, Backend::ActiveSet, cones);
                let b = run(&p, Backend::Clarabel, cones);
                same_status(&at, &a, &b);
                if a.status.has_answer() {
                    assert_eq!(a.status, Status::Optimal, "{at}");
                    assert!(sign * a.torque[j] >= lo * (1.0 - 1e-9), "{at}");
                    assert!(rel(a.objective, b.objective) <= 1e-6, "{at}");
                    squeezed += 1;
                } else {
                    assert_eq!(a.status, Status::Infeasible, "{at}: {:?}", a.reason);
                    infeasible += 1;
                }
            }
        }
    }
    eprintln!("{squeezed} squeezing answers, {infeasible} infeasible");
    assert!(squeezed > 0 && infeasible > 0);
}

/// Ranges in files: a pair `[lower, upper]` with either side null, checked with the
/// field and the value named.
#[test]
fn ranges_in_files_are_read_and_checked() {
    let paper = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/paper-example.json"
    ))
    .unwrap();
    let with = |limits: &str| {
        let mut v: serde_json::Value = serde_json::from_str(&paper).unwrap();
        v["torque_limits"] = serde_json::from_str(limits).unwrap();
        grasp_torque::parse_problem(&v.to_string())
    };
    let p = with("[[0, 10], [null, 2], 7, [null, null]]").unwrap();
    assert_eq!(
        p.torque_limits.clone().unwrap(),
        vec![
            Some(TorqueLimit::Range(Some(0.0), Some(10.0))),
            Some(TorqueLimit::Range(None, Some(2.0))),
            Some(TorqueLimit::Symmetric(7.0)),
            Some(TorqueLimit::Range(None, None))
        ]
    );
    // Both sides open is no limit: no rows.
    let model =
        std::sync::Arc::new(grasp_torque::GraspModel::new(&p, &Default::default()).unwrap());
    let qp = grasp_torque::TorqueQp::linearized(model, &p.linearization);
    let limit_rows: Vec<_> = qp
        .rows
        .iter()
        .filter_map(|r| match *r {
            grasp_torque::RowId::TorqueLimit { joint, upper } => Some((joint, upper)),
            _ => None,
        })
        .collect();
    assert_eq!(
        limit_rows,
        [(0, false), (0, true), (1, true), (2, false), (2, true)]
    );
    for (limits, field, says) in [
        (
            "[[1, 0], null, null, null]",
            "torque_limits[0]",
            "lower < upper",
        ),
        (
            "[null, null, [1, 2, 3], null]",
            "torque_limits[2]",
            "got a list of 3",
        ),
        (
            "[null, null, [\"a\", 2], null]",
            "torque_limits[2]",
            "expected f64",
        ),
        ("[null, null, null, [-1e13, 0]]", "torque_limits[3]", "1e12"),
        (
            "[null, null, null, [0, 1e-310]]",
            "torque_limits[3]",
            "subnormal",
        ),
        ("[null, null, null, -2]", "torque_limits[3]", "t > 0"),
    ] {
        let e = with(limits).unwrap_err().to_string();
        assert!(e.contains(field) && e.contains(says), "{limits}: {e}");
    }
}
