//! Hand-form problems from the command line: solve, build then solve, the `hand`
//! listing, and named errors (exit 2) for malformed URDFs and hand files.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grasp-torque"))
        .args(args)
        .output()
        .unwrap()
}

fn fixture(name: &str) -> String {
    format!("{}/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))
}

const HANDS: [&str; 3] = [
    "hands/allegro-pinch.json",
    "hands/ability-tripod.json",
    "hands/shadow-tripod.json",
];

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn temp_dir() -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("grasp-torque-hands-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn hand_files_solve_and_build_then_solve_agrees() {
    // Exact cones need an exact-cone backend (Clarabel) compiled in.
    let cones_kinds: &[&str] = if cfg!(feature = "clarabel") {
        &["linear", "exact"]
    } else {
        &["linear"]
    };
    for hand in HANDS {
        for &cones in cones_kinds {
            let direct = json(&run(&[
                "solve",
                &fixture(hand),
                "--cones",
                cones,
                "--format",
                "json",
            ]));
            assert_eq!(direct["status"], "optimal", "{hand} {cones}");
            assert_eq!(direct["hand"]["torque_limits"], "model");
            let names = direct["joint_names"].as_array().unwrap();
            assert!(names
                .iter()
                .all(|n| !n.as_str().unwrap().starts_with("joint ")));

            let built = run(&["build", &fixture(hand)]);
            assert!(built.status.success());
            let matrix: serde_json::Value = serde_json::from_slice(&built.stdout).unwrap();
            assert_eq!(&matrix["joint_names"], &direct["joint_names"]);
            let path = temp_dir().join(Path::new(hand).file_name().unwrap());
            std::fs::write(&path, &built.stdout).unwrap();
            let via = json(&run(&[
                "solve",
                path.to_str().unwrap(),
                "--cones",
                cones,
                "--format",
                "json",
            ]));
            // The matrix form round-trips every number, so the answer is the same.
            assert_eq!(via["objective"], direct["objective"], "{hand} {cones}");
            assert_eq!(via["torque"], direct["torque"], "{hand} {cones}");
            assert_eq!(via["joint_names"], direct["joint_names"]);
        }
    }
}

#[test]
fn text_report_names_joints_and_the_hand() {
    let out = run(&["solve", &fixture("hands/allegro-pinch.json")]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("joint_14.0") && text.contains("|τ| ≤ 10"),
        "{text}"
    );
    assert!(text.contains("robot `allegro_right`"), "{text}");
    assert!(
        !text.contains("joint_8.0"),
        "ring finger joints move no contact: {text}"
    );
    // A weighed object: the gravity and what its weight asks of the contacts.
    let out = run(&["solve", &fixture("hands/allegro-weighed.json")]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(
            "gravity [9.81, 0, 0] in the root frame, on the links (passive torques) and the object"
        ) && text
            .contains("the object's weight asks [-0.981, 0, 0, 0, 0, 0.004905] of the contacts"),
        "{text}"
    );
    let v = json(&run(&[
        "solve",
        &fixture("hands/allegro-weighed.json"),
        "--format",
        "json",
    ]));
    let w: Vec<f64> = serde_json::from_value(v["hand"]["object_weight"].clone()).unwrap();
    // −m g along x at 5 mm along y: the moment is about z.
    let expected = [-0.981, 0.0, 0.0, 0.0, 0.0, 0.005 * 0.981];
    assert!(w
        .iter()
        .zip(expected)
        .all(|(a, b)| (a - b).abs() <= 4.0 * f64::EPSILON));
}

#[test]
fn hand_command_lists_joints_mimics_and_chains() {
    let out = run(&[
        "hand",
        &fixture("urdf/ability_hand/ability_hand_right.urdf"),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("index_q2 = 1.0585133 · index_q1 + 0.72349796"),
        "{text}"
    );
    assert!(text.contains("thumb_tip: thumb_q1, thumb_q2"), "{text}");
    assert!(
        text.contains("masses (for hand.gravity):") && text.contains("gravity in the file: none"),
        "{text}"
    );
    // The masses a gravity oracle hand carries, and its file's gravity.
    let m = json(&run(&[
        "hand",
        &fixture("mjcf/gravity/spatial-3.xml"),
        "--format",
        "json",
    ]));
    assert_eq!(m["gravity"].as_array().unwrap().len(), 3);
    assert!(!m["masses"].as_array().unwrap().is_empty());
    assert!(m["unknown_masses"].as_array().unwrap().is_empty());
    let v = json(&run(&[
        "hand",
        &fixture("urdf/test/linkage_gripper.urdf"),
        "--format",
        "json",
    ]));
    let mimic = v["mimic_joints"].as_array().unwrap();
    let roll = mimic.iter().find(|m| m["name"] == "right_roll").unwrap();
    assert_eq!(roll["follows"], "right_prox");
    assert!((roll["multiplier"].as_f64().unwrap() + 0.45).abs() < 1e-15);
    assert_eq!(v["independent_joints"].as_array().unwrap().len(), 5);
    let compare = run(&["compare", &fixture("hands/ability-tripod.json")]);
    assert_eq!(
        compare.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&compare.stdout)
    );
}

#[test]
fn the_fingers_weight_enters_as_passive_torques() {
    let dir = temp_dir();
    let mut pinch: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(fixture("hands/allegro-pinch.json")).unwrap(),
    )
    .unwrap();
    pinch["hand"]["model"] = fixture("urdf/allegro/allegro_hand_right.urdf").into();
    // The palm faces down: gravity is +x in the root frame (the fixture's description).
    pinch["hand"]["gravity"] = serde_json::json!([9.81, 0, 0]);
    let path = dir.join("pinch-weight.json");
    std::fs::write(&path, pinch.to_string()).unwrap();
    let p = path.to_str().unwrap();
    let solved = json(&run(&["solve", p, "--format", "json"]));
    assert_eq!(solved["status"], "optimal");
    assert_eq!(
        solved["hand"]["gravity"],
        serde_json::json!([9.81, 0.0, 0.0])
    );
    // Jᵀ f = τ + τ_p, with τ_p the matrix form's passive_torque.
    let built: serde_json::Value = serde_json::from_slice(&run(&["build", p]).stdout).unwrap();
    let tp: Vec<f64> = serde_json::from_value(built["passive_torque"].clone()).unwrap();
    assert_eq!(solved["passive_torque"], built["passive_torque"]);
    let jt: Vec<Vec<f64>> = serde_json::from_value(built["jacobian_transpose"].clone()).unwrap();
    let f: Vec<Vec<f64>> = serde_json::from_value(solved["contact_forces"].clone()).unwrap();
    let f: Vec<f64> = f.concat();
    let tau: Vec<f64> = serde_json::from_value(solved["torque"].clone()).unwrap();
    let scale = tp.iter().chain(&tau).fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(tp.iter().any(|&t| t.abs() > 1e-3 * scale), "{tp:?}");
    for (j, row) in jt.iter().enumerate() {
        let jf: f64 = row.iter().zip(&f).map(|(a, b)| a * b).sum();
        assert!((jf - tau[j] - tp[j]).abs() <= 1e-12 * scale, "row {j}");
    }
    let text = String::from_utf8_lossy(&run(&["solve", p]).stdout).into_owned();
    assert!(
        text.contains("passive joint torques τ_p") && text.contains("produce f with τ_p"),
        "{text}"
    );
    // A URDF gives no gravity of its own.
    pinch["hand"]["gravity"] = "model".into();
    std::fs::write(&path, pinch.to_string()).unwrap();
    assert_rejected(&run(&["solve", p]), &["hand.gravity", "a URDF has none"]);
}

fn assert_rejected(out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    for n in needles {
        assert!(err.contains(n), "expected `{n}` in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    assert!(out.stdout.is_empty());
}

#[test]
fn malformed_robots_and_hand_files_exit_2_with_a_named_error() {
    let dir = temp_dir();
    let urdf = dir.join("broken.urdf");
    std::fs::write(
        &urdf,
        "<robot name=\"r\">\n<link name=\"palm\"/>\n<link name=\"tip\"/>\n\
         <joint name=\"j\" type=\"revolute\"><parent link=\"plam\"/><child link=\"tip\"/>\
         <axis xyz=\"0 0 1\"/></joint>\n</robot>\n",
    )
    .unwrap();
    assert_rejected(
        &run(&["hand", urdf.to_str().unwrap()]),
        &[
            "broken.urdf",
            "<joint name=\"j\"> (line 4)",
            "`plam`",
            "nearest: `palm`",
        ],
    );
    let hand = |body: serde_json::Value| {
        let p = dir.join("hand.json");
        std::fs::write(&p, body.to_string()).unwrap();
        run(&["solve", p.to_str().unwrap()])
    };
    assert_rejected(
        &hand(serde_json::json!({
            "hand": {"model": "broken.urdf"},
            "contacts": [{"link": "tip", "position": [0, 0, 0], "normal": [0, 0, 1], "model": "fpc"}],
            "wrench": [0, 0, 1, 0, 0, 0]
        })),
        &["broken.urdf", "parent link `plam`"],
    );
    let allegro = fixture("urdf/allegro/allegro_hand_right.urdf");
    assert_rejected(
        &hand(serde_json::json!({
            "hand": {"model": allegro, "joint_positions": {"joint_2": 0.1}},
            "contacts": [{"link": "link_3.0_tip", "position": [0, 0, 0], "normal": [0, 0, 1], "model": "fpc"}],
            "wrench": [0, 0, 1, 0, 0, 0]
        })),
        &["hand.joint_positions.joint_2", "nearest: `joint_2.0`"],
    );
    assert_rejected(
        &hand(serde_json::json!({
            "hand": {"model": allegro},
            "contacts": [{"link": "link_3.0_tip", "position": [0, 0, 0], "normal": [0, 0, 1], "model": "fpc"}],
            "wrench": [0, 0, 1, 0, 0, 0],
            "torque_limits": [1, 2]
        })),
        &["torque_limits"],
    );
    assert_rejected(
        &hand(serde_json::json!({
            "hand": {"model": allegro, "joint_positions": {"joint_1.0": 0.1}},
            "contacts": [{"link": "link_3.0_tip", "position": [0, 0, 0], "normal": [0, 0, 1], "model": "fpc"}],
            "fingers": [],
            "wrench": [0, 0, 1, 0, 0, 0]
        })),
        &["fields of more than one form"],
    );
}

/// `object_forces`, each contact's force on the object in the object frame, against the
/// files' own geometry: they sum to the wrench's force, their component along the
/// contact's normal is its `fz`, and their length is that of its `[fx, fy, fz]` (the
/// contact frame is orthonormal). Both cone forms, the geometry and hand forms.
#[test]
fn object_forces_follow_the_normals_and_sum_to_the_wrench() {
    for name in [
        "geometry/pinch.json",
        "hands/allegro-pinch.json",
        "hands/allegro-weighed.json",
    ] {
        let file: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(fixture(name)).unwrap()).unwrap();
        for cones in ["linear", "exact"] {
            let v = json(&run(&[
                "solve",
                &fixture(name),
                "--cones",
                cones,
                "--format",
                "json",
            ]));
            let wrench: Vec<f64> = serde_json::from_value(
                v["hand"]
                    .get("object_weight")
                    .unwrap_or(&file["wrench"])
                    .clone(),
            )
            .unwrap();
            let forces: Vec<[f64; 3]> = serde_json::from_value(v["object_forces"].clone()).unwrap();
            let components: Vec<Vec<f64>> =
                serde_json::from_value(v["contact_forces"].clone()).unwrap();
            let scale = components
                .iter()
                .flatten()
                .fold(0.0f64, |a, b| a.max(b.abs()));
            let tol = 1e-12 * scale;
            for k in 0..3 {
                let sum: f64 = forces.iter().map(|f| f[k]).sum();
                assert!(
                    (sum - wrench[k]).abs() <= tol,
                    "{name} {cones}: {sum} vs {wrench:?}"
                );
            }
            for (i, (f, c)) in forces.iter().zip(&components).enumerate() {
                // (The files' normals are unit to 1e-6; the contact frame's exactly.)
                let n: Vec<f64> =
                    serde_json::from_value(file["contacts"][i]["normal"].clone()).unwrap();
                let along = (0..3).map(|k| f[k] * n[k]).sum::<f64>()
                    / n.iter().map(|x| x * x).sum::<f64>().sqrt();
                let fz = c[if c.len() == 1 { 0 } else { 2 }];
                assert!((along - fz).abs() <= tol, "{name} {cones} contact {i}");
                let len = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
                let tangential_and_normal = len(&c[..c.len().min(3)]);
                assert!(
                    (len(f) - tangential_and_normal).abs() <= tol,
                    "{name} {cones} {i}"
                );
            }
        }
    }
}
