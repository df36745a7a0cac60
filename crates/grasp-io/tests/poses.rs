//! `HandGrasps::pose` (a planner's batch: the contacts fixed, the configuration, contact
//! points, normals and object pose per grasp) against `HandFile::build` of the same
//! grasp written as a hand file, on a URDF hand with link contacts, an MJCF hand with
//! site contacts and actuators, and a tendon hand with springs; a third of the grasps
//! under their own gravity.

use grasp_core::error::ProblemError;
use grasp_io::hand::{ContactFrame, GraspPose, HandFile, ObjectPose};
use grasp_io::urdf::Robot;
use std::path::{Path, PathBuf};

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(p)
}

mod rng;
use rng::Rng;

/// A random unit vector.
fn unit(rng: &mut Rng) -> [f64; 3] {
    loop {
        let v = [rng.next(), rng.next(), rng.next()];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if n > 0.1 && n <= 1.0 {
            return v.map(|x| x / n);
        }
    }
}

fn load(fixture: &str) -> (HandFile, Robot) {
    let path = repo(fixture);
    let file: HandFile = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let robot = Robot::load(&file.model_path(path.parent().unwrap())).unwrap();
    (file, robot)
}

/// Poses `cases` random grasps both ways and demands the same problem, bit for bit
/// (`{:?}` prints every f64 so that it reads back exactly, and tells −0 from 0).
fn same_both_ways(fixture: &str, points: bool, seed: u64, cases: usize) {
    let (template, robot) = load(fixture);
    let grasps = template.grasps(&robot).unwrap();
    let mut rng = Rng(seed);
    let names: Vec<String> = robot
        .independent
        .iter()
        .map(|&j| robot.joints[j].name.clone())
        .collect();
    for case in 0..cases {
        let q: Vec<f64> = (0..names.len()).map(|_| 1.5 * rng.next()).collect();
        let n = template.contacts.len();
        let mut file = template.clone();
        file.hand.joint_positions = names.iter().cloned().zip(q.iter().copied()).collect();
        let mut positions = vec![None; n];
        let mut normals = vec![None; n];
        for (i, c) in file.contacts.iter_mut().enumerate() {
            // Every other grasp leaves a contact as the file has it.
            if (case + i) % 2 == 0 {
                continue;
            }
            if points {
                let p = [0.05 * rng.next(), 0.05 * rng.next(), 0.05 * rng.next()];
                c.position = Some(p);
                positions[i] = Some(p);
                c.frame = if rng.next() > 0.0 {
                    ContactFrame::Link
                } else {
                    ContactFrame::Object
                };
            }
            let u = unit(&mut rng);
            c.normal = Some(u);
            normals[i] = Some(u);
        }
        let frames: Vec<ContactFrame> = file.contacts.iter().map(|c| c.frame).collect();
        let mut quaternion = [rng.next(), rng.next(), rng.next(), rng.next()];
        let norm = quaternion.iter().map(|x| x * x).sum::<f64>().sqrt();
        quaternion = quaternion.map(|x| x / norm);
        let object_pose = ObjectPose {
            position: [0.1 * rng.next(), 0.1 * rng.next(), 0.1 * rng.next()],
            quaternion,
        };
        file.object_pose = Some(object_pose);
        // Every third grasp under its own gravity (the hand turned another way).
        let gravity = (case % 3 == 0).then(|| unit(&mut rng).map(|x| 9.81 * x));
        if let Some(g) = gravity {
            file.hand.gravity = Some(serde_json::json!(g));
        }
        let built = file.build(&robot).unwrap().problem;
        // The frames travel with the template's contacts: pose with a template whose
        // frames are this grasp's.
        let mut framed = template.clone();
        for (c, f) in framed.contacts.iter_mut().zip(&frames) {
            c.frame = *f;
        }
        let framed = framed.grasps(&robot).unwrap();
        let posed = framed
            .pose(&GraspPose {
                joint_positions: &q,
                positions: points.then_some(&positions[..]),
                normals: Some(&normals),
                object_pose: Some(object_pose),
                gravity,
            })
            .unwrap();
        assert_eq!(
            format!("{built:?}"),
            format!("{posed:?}"),
            "{fixture}, case {case}"
        );
    }
    // With nothing posed, the file's own grasp at q = 0.
    let mut file = template.clone();
    file.hand.joint_positions.clear();
    let built = file.build(&robot).unwrap().problem;
    let posed = grasps.pose(&GraspPose::default()).unwrap();
    assert_eq!(
        format!("{built:?}"),
        format!("{posed:?}"),
        "{fixture} at q = 0"
    );
}

#[test]
fn posing_a_urdf_hand_is_building_its_file() {
    same_both_ways("fixtures/hands/allegro-pinch.json", true, 17, 200);
}

#[test]
fn posing_an_mjcf_hand_with_sites_and_actuators_is_building_its_file() {
    same_both_ways("fixtures/hands/shadow-tripod.json", false, 29, 200);
}

#[test]
fn posing_a_tendon_hand_with_springs_is_building_its_file() {
    same_both_ways("fixtures/hands/aero-pinch.json", false, 31, 100);
}

fn field_of(e: ProblemError) -> (String, String) {
    match e {
        ProblemError::Invalid { field, found, .. } => (field, found),
        other => panic!("expected an invalid field, got {other}"),
    }
}

#[test]
fn a_bad_pose_is_an_error_naming_the_field() {
    let (template, robot) = load("fixtures/hands/allegro-pinch.json");
    let grasps = template.grasps(&robot).unwrap();
    let nq = robot.independent.len();
    let mut q = vec![0.1; nq];
    q[3] = f64::NAN;
    let e = grasps
        .pose(&GraspPose {
            joint_positions: &q,
            ..GraspPose::default()
        })
        .unwrap_err();
    assert_eq!(
        field_of(e),
        ("joint_positions[3] (joint_3.0)".into(), "NaN".into())
    );
    let e = grasps
        .pose(&GraspPose {
            joint_positions: &q[..5],
            ..GraspPose::default()
        })
        .unwrap_err();
    assert_eq!(
        field_of(e),
        ("joint_positions".into(), "5 positions".into())
    );
    let normals = vec![Some([0.0, 0.0, 2.0]); template.contacts.len()];
    let e = grasps
        .pose(&GraspPose {
            normals: Some(&normals),
            ..GraspPose::default()
        })
        .unwrap_err();
    assert_eq!(field_of(e).0, "contacts[0] (index).normal");
    let positions = vec![Some([f64::INFINITY, 0.0, 0.0])];
    let e = grasps
        .pose(&GraspPose {
            positions: Some(&positions),
            ..GraspPose::default()
        })
        .unwrap_err();
    assert_eq!(field_of(e), ("positions".into(), "1 entries".into()));
    let e = grasps
        .pose(&GraspPose {
            object_pose: Some(ObjectPose {
                position: [0.0; 3],
                quaternion: [1.0, 1.0, 0.0, 0.0],
            }),
            ..GraspPose::default()
        })
        .unwrap_err();
    assert_eq!(field_of(e).0, "object_pose.quaternion");
    // A site's point is its origin: a position for it is refused.
    let (template, robot) = load("fixtures/hands/shadow-tripod.json");
    let grasps = template.grasps(&robot).unwrap();
    let positions = vec![Some([0.0; 3]); template.contacts.len()];
    let e = grasps
        .pose(&GraspPose {
            positions: Some(&positions),
            ..GraspPose::default()
        })
        .unwrap_err();
    assert_eq!(field_of(e).0, "contacts[0] (thumb).position");
}
