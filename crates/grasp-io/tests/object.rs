//! The hand form's `object`: its weight, under the hand's gravity and in the object's
//! pose, joins the wrench. Checked against the weight written out by hand (a rotation
//! matrix from the quaternion's formula, `F = −m Rᵀ g`, `M = c × F`) in a file without
//! `object`, for random masses, centres, gravities and object poses; per grasp through
//! `HandGrasps::pose`; and the errors.

use grasp_core::error::ProblemError;
use grasp_io::hand::{GraspPose, HandFile, HeldObject, ObjectPose};
use grasp_io::urdf::Robot;
use std::path::{Path, PathBuf};

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(p)
}

mod rng;
use rng::Rng;

fn vec3(rng: &mut Rng, scale: f64) -> [f64; 3] {
    [rng.next(), rng.next(), rng.next()].map(|x| scale * x)
}

/// A random unit quaternion `[w, x, y, z]`.
fn random_quaternion(rng: &mut Rng) -> [f64; 4] {
    let q = [rng.next(), rng.next(), rng.next(), rng.next()];
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    q.map(|x| x / n)
}

fn allegro() -> (HandFile, Robot) {
    let path = repo("fixtures/hands/allegro-pinch.json");
    let file: HandFile = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let robot = Robot::load(&file.model_path(path.parent().unwrap())).unwrap();
    (file, robot)
}

/// The rotation matrix of the unit quaternion `[w, x, y, z]`.
fn matrix([w, x, y, z]: [f64; 4]) -> [[f64; 3]; 3] {
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// What the contacts apply to carry `m g` at `c`, about the object origin, written out.
fn weight(mass: f64, c: [f64; 3], g: [f64; 3], q: [f64; 4]) -> [f64; 6] {
    let r = matrix(q);
    // Rᵀ g: gravity in the object frame.
    let f: [f64; 3] = std::array::from_fn(|i| -mass * (0..3).map(|k| r[k][i] * g[k]).sum::<f64>());
    [
        f[0],
        f[1],
        f[2],
        c[1] * f[2] - c[2] * f[1],
        c[2] * f[0] - c[0] * f[2],
        c[0] * f[1] - c[1] * f[0],
    ]
}

#[test]
fn the_weight_joins_the_wrench() {
    let (template, robot) = allegro();
    let mut rng = Rng(41);
    let mut worst = 0.0f64;
    for case in 0..200 {
        let mass = 0.01 + 2.0 * (1.0 + rng.next());
        let center_of_mass = vec3(&mut rng, 0.05);
        // Any direction; from a hundredth of Earth's to ten times.
        let g = vec3(&mut rng, 1.0).map(|x| x * 9.81 * 10f64.powf(1.5 * rng.next() - 0.5));
        let quaternion = random_quaternion(&mut rng);
        let besides = vec3(&mut rng, 0.5)
            .into_iter()
            .chain(vec3(&mut rng, 0.02))
            .collect::<Vec<_>>();
        let mut file = template.clone();
        file.hand.gravity = Some(serde_json::json!(g));
        file.object_pose = Some(ObjectPose {
            position: vec3(&mut rng, 0.1),
            quaternion,
        });
        file.object = Some(HeldObject {
            mass,
            center_of_mass,
        });
        // Half the cases give only the object; `wrench` is then 0.
        file.wrench = (case % 2 == 0).then(|| besides.clone());
        let built = file.build(&robot).unwrap();
        let expected = weight(mass, center_of_mass, g, quaternion);
        let report = built.report.object_weight.unwrap();
        let mut by_hand = file.clone();
        by_hand.object = None;
        by_hand.wrench = Some(
            (0..6)
                .map(|i| expected[i] + if case % 2 == 0 { besides[i] } else { 0.0 })
                .collect(),
        );
        let without = by_hand.build(&robot).unwrap().problem;
        let p = &built.problem;
        // Everything but the wrench is the file's without `object`, bit for bit.
        assert_eq!(
            format!(
                "{:?}",
                (&p.grasp_matrix, &p.jacobian_transpose, &p.passive_torque)
            ),
            format!(
                "{:?}",
                (
                    &without.grasp_matrix,
                    &without.jacobian_transpose,
                    &without.passive_torque
                )
            ),
            "case {case}"
        );
        // The wrench to rounding: of |F| ≤ m|g|, of |M| ≤ |c| m|g|, and of `besides`.
        let scale = mass * g.iter().map(|x| x * x).sum::<f64>().sqrt();
        let arm = center_of_mass.iter().map(|x| x * x).sum::<f64>().sqrt();
        for i in 0..6 {
            let size = if i < 3 { scale } else { scale * arm } + besides[i].abs();
            let err = (p.wrench[i] - without.wrench[i]).abs() / size;
            let report_err = (report[i] - expected[i]).abs() / size;
            worst = worst.max(err).max(report_err);
            assert!(
                err <= 16.0 * f64::EPSILON,
                "case {case}, component {i}: {err:e}"
            );
            assert!(
                report_err <= 16.0 * f64::EPSILON,
                "case {case}: {report_err:e}"
            );
        }
        // Back in the root frame, the contacts' force is −m g.
        let r = matrix(quaternion);
        for k in 0..3 {
            let f: f64 = (0..3).map(|i| r[k][i] * report[i]).sum();
            assert!(
                (f + mass * g[k]).abs() <= 8.0 * f64::EPSILON * scale,
                "case {case}"
            );
        }
    }
    println!("the object's weight against its written-out formula: worst {worst:.1e} relative");
}

/// A planner's grasps: each pose's gravity and object pose weigh the object, as a file
/// of that grasp does.
#[test]
fn each_pose_weighs_the_object_its_own_way() {
    let (mut template, robot) = allegro();
    template.hand.gravity = Some(serde_json::json!([9.81, 0.0, 0.0]));
    template.object = Some(HeldObject {
        mass: 0.3,
        center_of_mass: [0.0, 0.01, -0.02],
    });
    template.wrench = None;
    let grasps = template.grasps(&robot).unwrap();
    let mut rng = Rng(7);
    for case in 0..50 {
        let gravity = vec3(&mut rng, 9.81);
        let object_pose = ObjectPose {
            position: vec3(&mut rng, 0.1),
            quaternion: random_quaternion(&mut rng),
        };
        let pose = GraspPose {
            object_pose: Some(object_pose),
            gravity: Some(gravity),
            ..GraspPose::default()
        };
        let posed = grasps.pose(&pose).unwrap();
        assert_eq!(
            Some(posed.wrench),
            grasps.object_weight(&pose),
            "case {case}"
        );
        let mut file = template.clone();
        file.hand.joint_positions.clear();
        file.hand.gravity = Some(serde_json::json!(gravity));
        file.object_pose = Some(object_pose);
        let built = file.build(&robot).unwrap().problem;
        assert_eq!(format!("{built:?}"), format!("{posed:?}"), "case {case}");
    }
}

#[test]
fn a_bad_object_is_an_error_naming_the_field() {
    let (template, robot) = allegro();
    let err = |edit: &dyn Fn(&mut HandFile)| -> String {
        let mut f = template.clone();
        edit(&mut f);
        match f.build(&robot) {
            Ok(_) => panic!("accepted"),
            Err(e) => {
                assert!(matches!(e, ProblemError::Invalid { .. }), "{e}");
                e.to_string()
            }
        }
    };
    let object = |mass, center_of_mass| {
        Some(HeldObject {
            mass,
            center_of_mass,
        })
    };
    let e = err(&|f| f.object = object(0.1, [0.0; 3]));
    assert!(
        e.contains("object.mass") && e.contains("hand.gravity"),
        "{e}"
    );
    let with_gravity = |f: &mut HandFile| f.hand.gravity = Some(serde_json::json!([0, 0, -9.81]));
    for mass in [-0.1, 2e12, f64::NAN, f64::INFINITY, 1e-310] {
        let e = err(&|f| {
            with_gravity(f);
            f.object = object(mass, [0.0; 3]);
        });
        assert!(e.contains("object.mass") && e.contains("0 to 1e12"), "{e}");
    }
    let e = err(&|f| {
        with_gravity(f);
        f.object = object(0.1, [0.0, f64::NAN, 0.0]);
    });
    assert!(e.contains("object.center_of_mass"), "{e}");
    // In range, but its weight is not.
    let e = err(&|f| {
        f.hand.gravity = Some(serde_json::json!([0, 0, -1e12]));
        f.object = object(1e6, [0.0; 3]);
    });
    assert!(
        e.contains("object.mass") && e.contains("component 2"),
        "{e}"
    );
    let e = err(&|f| f.wrench = None);
    assert!(e.contains("wrench") && e.contains("missing"), "{e}");
    // The file form says the same.
    let mut v = serde_json::to_value(&template).unwrap();
    v["object"] = serde_json::json!({"mass": 0.1, "centre": [0, 0, 0]});
    let e = serde_json::from_value::<HandFile>(v)
        .unwrap_err()
        .to_string();
    assert!(e.contains("centre"), "{e}");
}
