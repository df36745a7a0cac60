//! Invariances of the answer under the problem's bookkeeping: the same grasp written with
//! its joints in another order, its contacts in another order, or its wrench in another
//! object frame (rotated, with the moments about another point) is the same grasp, and
//! must get the same torques (permuted with the joints) and the same σ. Every backend
//! and cone kind, with torque weights, torque limits and minimum normal forces that
//! travel with their joints and contacts, with and without passive internal forces.
#![cfg(all(feature = "active-set", feature = "clarabel"))]

use grasp_testkit::{synthetic_grasp, ModelMix, Rng, SynthSpec};
use grasp_torque::file::ModelName;
use grasp_torque::{Backend, Cones, GraspProblem, Matrix, Solution, TorqueLimit};
use proptest::prelude::*;

mod common;
use common::run;

/// The backends and cone kinds, each with the accuracy its answers are certified to:
/// the native solver's certificate (1e-9, both kinds), Clarabel's linearised answers
/// polished and certified alike, its exact ones to its stated accuracy.
const RUNS: [(Backend, Cones, f64); 4] = [
    (Backend::ActiveSet, Cones::Linear, 1e-9),
    (Backend::ActiveSet, Cones::Exact, 1e-9),
    (Backend::Clarabel, Cones::Linear, 1e-9),
    (Backend::Clarabel, Cones::Exact, 1e-7),
];

/// A synthetic grasp with weights, limits on every other joint and minimum normal
/// forces on some contacts; with `null_space`, four soft fingers of two joints each
/// (`[G; Jᵀ]` then has passive internal forces).
fn grasp(seed: u64, null_space: bool) -> GraspProblem {
    let mut spec = SynthSpec::default();
    if null_space {
        spec.fingers = Some(4);
        spec.joints_per_finger = Some(2);
        spec.models = ModelMix::Only(ModelName::Sfcl);
    }
    let mut p = synthetic_grasp(seed, &spec).into_problem().unwrap();
    let mut rng = Rng(seed ^ 0x5eed);
    let m = p.joints();
    p.torque_weights = Some((0..m).map(|_| rng.uniform(0.5, 4.0)).collect());
    // Symmetric limits on every fourth joint, ranges of both signs or one side open
    // on the others but one in four.
    p.torque_limits = Some(
        (0..m)
            .map(|j| match j % 4 {
                0 => Some(rng.uniform(0.5, 3.0).into()),
                1 => Some(TorqueLimit::Range(
                    Some(-rng.uniform(0.2, 1.0)),
                    Some(rng.uniform(1.0, 3.0)),
                )),
                2 => Some(TorqueLimit::Range(None, Some(rng.uniform(0.5, 3.0)))),
                _ => None,
            })
            .collect(),
    );
    p.min_normal_force = Some(
        (0..p.contacts.len())
            .map(|i| 0.05 * (i % 2) as f64)
            .collect(),
    );
    p
}

/// A permutation of `0..n`, Fisher–Yates.
fn permutation(n: usize, rng: &mut Rng) -> Vec<usize> {
    let mut v: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        v.swap(i, rng.int(0, i));
    }
    v
}

/// Joint `j` of the new problem is joint `perm[j]` of the old.
fn relabel_joints(p: &GraspProblem, perm: &[usize]) -> GraspProblem {
    let mut q = p.clone();
    let jt = &p.jacobian_transpose;
    q.jacobian_transpose = Matrix::from_fn(jt.nrows(), jt.ncols(), |j, c| jt[(perm[j], c)]);
    let take = |v: &Vec<f64>| perm.iter().map(|&k| v[k]).collect();
    q.torque_weights = p.torque_weights.as_ref().map(take);
    q.torque_limits = p
        .torque_limits
        .as_ref()
        .map(|v| perm.iter().map(|&k| v[k]).collect());
    q.initial_torque = p.initial_torque.as_ref().map(take);
    if !p.joint_names.is_empty() {
        q.joint_names = perm.iter().map(|&k| p.joint_names[k].clone()).collect();
    }
    q
}

/// Contact `i` of the new problem is contact `perm[i]` of the old: its columns of G
/// and Jᵀ, its model and its minimum normal force move together.
fn reorder_contacts(p: &GraspProblem, perm: &[usize]) -> GraspProblem {
    let offsets: Vec<usize> = p
        .contacts
        .iter()
        .scan(0, |o, c| {
            let at = *o;
            *o += c.dim();
            Some(at)
        })
        .collect();
    let cols: Vec<usize> = perm
        .iter()
        .flat_map(|&k| offsets[k]..offsets[k] + p.contacts[k].dim())
        .collect();
    let mut q = p.clone();
    let moved = |a: &Matrix| Matrix::from_fn(a.nrows(), a.ncols(), |r, c| a[(r, cols[c])]);
    q.grasp_matrix = moved(&p.grasp_matrix);
    q.jacobian_transpose = moved(&p.jacobian_transpose);
    q.contacts = perm.iter().map(|&k| p.contacts[k]).collect();
    q.min_normal_force = p
        .min_normal_force
        .as_ref()
        .map(|v| perm.iter().map(|&k| v[k]).collect());
    q
}

/// The wrench and G's rows in an object frame rotated by `r` (rows: the new axes in the
/// old frame) whose moments are taken about the point `o` (old frame): forces `R F`,
/// moments `R (M − o × F)`.
fn move_frame(p: &GraspProblem, r: &[[f64; 3]; 3], o: [f64; 3]) -> GraspProblem {
    let map = |v: [f64; 6]| -> [f64; 6] {
        let (f, m) = ([v[0], v[1], v[2]], [v[3], v[4], v[5]]);
        let of = [
            o[1] * f[2] - o[2] * f[1],
            o[2] * f[0] - o[0] * f[2],
            o[0] * f[1] - o[1] * f[0],
        ];
        let mut out = [0.0; 6];
        for i in 0..3 {
            out[i] = (0..3).map(|k| r[i][k] * f[k]).sum();
            out[3 + i] = (0..3).map(|k| r[i][k] * (m[k] - of[k])).sum();
        }
        out
    };
    let mut q = p.clone();
    let g = &p.grasp_matrix;
    let cols: Vec<[f64; 6]> = (0..g.ncols())
        .map(|c| map(std::array::from_fn(|i| g[(i, c)])))
        .collect();
    q.grasp_matrix = Matrix::from_fn(6, g.ncols(), |i, c| cols[c][i]);
    q.wrench = map(p.wrench);
    q
}

/// A rotation from three angles (z, then y, then x).
fn rotation(a: f64, b: f64, c: f64) -> [[f64; 3]; 3] {
    let (sa, ca, sb, cb, sc, cc) = (a.sin(), a.cos(), b.sin(), b.cos(), c.sin(), c.cos());
    [
        [ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc],
        [sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc],
        [-sb, cb * sc, cb * cc],
    ]
}

/// The same answer: the same status class, σ within `tol`, and τ (with joint `j` of `b`
/// read as joint `perm[j]` of `a`) within √tol of the largest torque, which is what an
/// error of `tol` in σ allows in τ.
fn same_answer(
    a: &Solution,
    b: &Solution,
    perm: &[usize],
    tol: f64,
    what: &str,
) -> Result<(), TestCaseError> {
    prop_assert_eq!(
        a.status.has_answer(),
        b.status.has_answer(),
        "{}: {:?} / {:?}",
        what,
        a.reason,
        b.reason
    );
    if !a.status.has_answer() {
        return Ok(());
    }
    let scale = a
        .objective
        .abs()
        .max(b.objective.abs())
        .max(f64::MIN_POSITIVE);
    prop_assert!(
        (a.objective - b.objective).abs() <= tol * scale,
        "{}: σ {} vs {}",
        what,
        a.objective,
        b.objective
    );
    let tmax = a.torque.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    for (j, &k) in perm.iter().enumerate() {
        prop_assert!(
            (b.torque[j] - a.torque[k]).abs() <= tol.sqrt() * tmax,
            "{}: τ[{}] {} vs τ[{}] {}",
            what,
            j,
            b.torque[j],
            k,
            a.torque[k]
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 200,
        // Fixed seed: CI and every developer see the same cases (STYLE.md).
        rng_seed: proptest::test_runner::RngSeed::Fixed(97),
        ..ProptestConfig::default()
    })]

    #[test]
    fn relabelling_joints_permutes_the_torques(seed in any::<u64>(), null_space in any::<bool>()) {
        let p = grasp(seed, null_space);
        let perm = permutation(p.joints(), &mut Rng(seed));
        let q = relabel_joints(&p, &perm);
        for (backend, cones, tol) in RUNS {
            let what = format!("{backend} {cones:?}");
            same_answer(&run(&p, backend, cones), &run(&q, backend, cones), &perm, tol, &what)?;
        }
    }

    #[test]
    fn reordering_contacts_leaves_the_torques(seed in any::<u64>(), null_space in any::<bool>()) {
        let p = grasp(seed, null_space);
        let perm = permutation(p.contacts.len(), &mut Rng(seed));
        let q = reorder_contacts(&p, &perm);
        let joints: Vec<usize> = (0..p.joints()).collect();
        for (backend, cones, tol) in RUNS {
            let what = format!("{backend} {cones:?}");
            same_answer(&run(&p, backend, cones), &run(&q, backend, cones), &joints, tol, &what)?;
        }
    }

    #[test]
    fn the_object_frame_does_not_change_the_torques(
        seed in any::<u64>(),
        null_space in any::<bool>(),
        angles in prop::array::uniform3(-3.0f64..3.0),
        origin in prop::array::uniform3(-0.2f64..0.2),
    ) {
        let p = grasp(seed, null_space);
        let q = move_frame(&p, &rotation(angles[0], angles[1], angles[2]), origin);
        let joints: Vec<usize> = (0..p.joints()).collect();
        for (backend, cones, tol) in RUNS {
            let what = format!("{backend} {cones:?}");
            same_answer(&run(&p, backend, cones), &run(&q, backend, cones), &joints, tol, &what)?;
        }
    }
}
