//! URDF hands: Jᵀ and G against Pinocchio (fixtures written by scripts/oracle_urdf.py),
//! the Jacobian against finite differences of the forward kinematics, mimic couplings,
//! and named errors for malformed descriptions and hand files.

use grasp_core::TorqueLimit;
use grasp_io::frame::{UnitQuaternion, Vector3};
use grasp_io::hand::HandFile;
use grasp_io::urdf::Robot;
use grasp_io::ProblemError;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

mod common;

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

const ROBOTS: [&str; 3] = [
    "fixtures/urdf/allegro/allegro_hand_right.urdf",
    "fixtures/urdf/ability_hand/ability_hand_right.urdf",
    "fixtures/urdf/test/linkage_gripper.urdf",
];

#[test]
fn jacobians_match_pinocchio() {
    let dir = repo("fixtures/urdf/oracle");
    // The random hands of scripts/random_urdf.py, all of them.
    let mut randoms: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|f| f.starts_with("random-") && f.ends_with(".json"))
        .map(|f| f.trim_end_matches(".json").to_string())
        .collect();
    randoms.sort();
    assert!(randoms.len() >= 6, "{randoms:?}");
    let named = [
        "allegro",
        "ability",
        "linkage-gripper",
        "leap",
        "shadow-urdf",
        "barrett",
    ];
    for name in named
        .iter()
        .copied()
        .chain(randoms.iter().map(String::as_str))
    {
        let text = std::fs::read_to_string(dir.join(format!("{name}.json"))).unwrap();
        let oracle: serde_json::Value = serde_json::from_str(&text).unwrap();
        let cases = oracle["cases"].as_array().unwrap();
        let least = if name.starts_with("random-") { 20 } else { 50 };
        assert!(
            cases.len() >= least,
            "{name}: {} configurations",
            cases.len()
        );
        let mut worst: f64 = 0.0;
        let mut worst_f: f64 = 0.0;
        let mut worst_g: f64 = 0.0;
        let model = cases[0]["problem"]["hand"]["model"].as_str().unwrap();
        let robot = Robot::load(&dir.join(model)).unwrap();
        for case in cases {
            // Every frame where Pinocchio puts it (the first cases).
            worst_f = worst_f.max(common::frame_error(&robot, case, model));
            let mut file: HandFile = serde_json::from_value(case["problem"].clone()).unwrap();
            // The links' weight under the case's gravity, as passive torques.
            file.hand.gravity = Some(case["gravity"].clone());
            let built = file.into_problem(&dir).unwrap();
            let p = &built.problem;
            let label = case["problem"]["name"].as_str().unwrap();
            let weight: BTreeMap<String, f64> =
                serde_json::from_value(case["gravity_torque"].clone()).unwrap();
            let wscale = weight.values().fold(0.0f64, |a, v| a.max(v.abs()));
            let got = p.passive_torque.as_ref().expect("gravity was asked for");
            for (j, jname) in p.joint_names.iter().enumerate() {
                let err = (got[j] - weight[jname]).abs();
                assert!(
                    err <= 1e-10 * wscale,
                    "{label}: weight on {jname} {} vs Pinocchio {}",
                    got[j],
                    weight[jname]
                );
                worst_g = worst_g.max(err / wscale.max(f64::MIN_POSITIVE));
            }
            let expect: BTreeMap<String, Vec<f64>> =
                serde_json::from_value(case["jacobian_transpose"].clone()).unwrap();
            let scale = expect
                .values()
                .flatten()
                .fold(0.0f64, |a, v| a.max(v.abs()));
            let n = p.force_dim();
            // Every joint of the problem is Pinocchio's; every other joint of
            // Pinocchio's moves no contact.
            for (j, jname) in p.joint_names.iter().enumerate() {
                let row = &expect[jname];
                for c in 0..n {
                    let err = (p.jacobian_transpose[(j, c)] - row[c]).abs() / scale;
                    worst = worst.max(err);
                    assert!(
                        err <= 1e-10,
                        "{label}: Jᵀ[{jname}][{c}] off by {err:e} relative"
                    );
                }
            }
            for (jname, row) in &expect {
                if !p.joint_names.contains(jname) {
                    assert!(
                        row.iter().all(|&v| v == 0.0),
                        "{label}: {jname} moves a contact but is not in the problem"
                    );
                }
            }
            let g: Vec<Vec<f64>> = serde_json::from_value(case["grasp_matrix"].clone()).unwrap();
            let gscale = g.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
            for r in 0..6 {
                for c in 0..n {
                    let err = (p.grasp_matrix[(r, c)] - g[r][c]).abs() / gscale;
                    assert!(err <= 1e-12, "{label}: G[{r}][{c}] off by {err:e}");
                }
            }
            let omitted: Vec<String> =
                serde_json::from_value(case["defaulted_joints"].clone()).unwrap();
            let expected_defaulted: Vec<&String> = p
                .joint_names
                .iter()
                .filter(|j| omitted.contains(j))
                .collect();
            let got: Vec<&String> = built.report.defaulted_joints.iter().collect();
            assert_eq!(got, expected_defaulted, "{label}: defaulted joints");
            assert_eq!(built.report.torque_limits, "model");
            // Each joint's bound is Pinocchio's effort limit (none without one).
            let limits = p
                .torque_limits
                .as_ref()
                .expect("model limits were asked for");
            for (j, jname) in p.joint_names.iter().enumerate() {
                let want = oracle["effort_limits"][jname]
                    .as_f64()
                    .map(TorqueLimit::Symmetric);
                assert_eq!(limits[j], want, "{label}: the effort limit of {jname}");
            }
        }
        eprintln!(
            "{name}: {} configurations, worst Jᵀ error {worst:.1e} relative, frames {worst_f:.1e} (metres, rotation entries), gravity torques {worst_g:.1e}",
            cases.len()
        );
    }
}

/// A small deterministic generator (SplitMix64), for configurations.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

fn random_configuration(robot: &Robot, rng: &mut Rng) -> Vec<f64> {
    robot
        .independent
        .iter()
        .map(|&j| {
            let joint = &robot.joints[j];
            match (joint.lower, joint.upper) {
                (Some(lo), Some(hi)) => rng.range(lo, hi),
                _ => rng.range(-3.0, 3.0),
            }
        })
        .collect()
}

/// Jᵀ from the hand form against central differences of the forward kinematics: for a
/// point fixed on a link, `∂p/∂q_k · d` for each contact direction, and the rotation's
/// rate about the normal for the torsion column.
#[test]
fn jacobian_matches_finite_differences() {
    let mut rng = Rng(7);
    for rel in ROBOTS {
        let path = repo(rel);
        let robot = Robot::load(&path).unwrap();
        let leaves = robot.leaves();
        for trial in 0..20 {
            let q = random_configuration(&robot, &mut rng);
            let link = leaves[trial % leaves.len()];
            if robot
                .chain(link)
                .iter()
                .all(|&j| robot.coupling[j].is_none())
            {
                continue;
            }
            let offset = [
                rng.range(-0.01, 0.01),
                rng.range(-0.01, 0.01),
                rng.range(-0.01, 0.01),
            ];
            let nl = Vector3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            )
            .normalize();
            let positions: BTreeMap<String, f64> = robot
                .independent
                .iter()
                .zip(&q)
                .map(|(&j, &v)| (robot.joints[j].name.clone(), v))
                .collect();
            let file: HandFile = serde_json::from_value(serde_json::json!({
                "hand": {"model": path.display().to_string(), "joint_positions": positions},
                "contacts": [{"link": robot.links[link], "frame": "link", "position": offset,
                              "normal": [nl.x, nl.y, nl.z], "model": "sfce", "mu": 0.5, "mu_torsion": 0.01}],
                "wrench": [0, 0, 1, 0, 0, 0]
            }))
            .unwrap();
            let p = file.build(&robot).unwrap().problem;
            // The contact frame, from G's columns (object frame = root frame here).
            let dirs: Vec<Vector3> = (0..3)
                .map(|c| {
                    Vector3::new(
                        p.grasp_matrix[(0, c)],
                        p.grasp_matrix[(1, c)],
                        p.grasp_matrix[(2, c)],
                    )
                })
                .collect();
            let point =
                |q: &[f64]| robot.pose(q).links[link].transform_point(&Vector3::from(offset));
            let rotation = |q: &[f64]| robot.pose(q).links[link].rotation;
            let h = 1e-6;
            for (row, jname) in p.joint_names.iter().enumerate() {
                let k = robot
                    .independent
                    .iter()
                    .position(|&j| &robot.joints[j].name == jname)
                    .unwrap();
                let (mut qp, mut qm) = (q.clone(), q.clone());
                qp[k] += h;
                qm[k] -= h;
                let v = (point(&qp) - point(&qm)) / (2.0 * h);
                let dr = rotation(&qp) * rotation(&qm).inverse();
                // Its rotation vector: the axis times the angle.
                let [c, x, y, z] = dr.coords();
                let (u, n) = (Vector3::new(x, y, z), Vector3::new(x, y, z).norm());
                let w = u * (c.signum() * 2.0 * n.atan2(c.abs()) / n.max(f64::MIN_POSITIVE))
                    / (2.0 * h);
                let scale = 0.2 + v.norm() + w.norm();
                for (c, d) in dirs.iter().enumerate() {
                    let err = (p.jacobian_transpose[(row, c)] - d.dot(&v)).abs() / scale;
                    assert!(
                        err < 1e-8,
                        "{rel} trial {trial}: {jname} column {c} off by {err:e}"
                    );
                }
                let err = (p.jacobian_transpose[(row, 3)] - dirs[2].dot(&w)).abs() / scale;
                assert!(
                    err < 1e-8,
                    "{rel} trial {trial}: {jname} torsion off by {err:e}"
                );
            }
        }
    }
}

#[test]
fn mimic_chains_are_resolved() {
    let robot = Robot::load(&repo("fixtures/urdf/test/linkage_gripper.urdf")).unwrap();
    let names: Vec<&str> = robot
        .independent
        .iter()
        .map(|&j| robot.joints[j].name.as_str())
        .collect();
    assert_eq!(
        names,
        [
            "thumb_yaw",
            "thumb_pitch",
            "slide_left",
            "left_prox",
            "right_prox"
        ]
    );
    let q = [0.3, -0.2, 0.01, 0.7, 0.4];
    let full = robot.full_positions(&q);
    let at = |n: &str| full[robot.joint(n).unwrap()];
    assert_eq!(at("left_dist"), 0.8 * 0.7 + 0.1);
    assert_eq!(at("slide_right"), -0.01);
    let right_dist = 0.9 * 0.4 - 0.05;
    assert!((at("right_dist") - right_dist).abs() < 1e-15);
    assert!((at("right_roll") - (-0.5 * right_dist + 0.2)).abs() < 1e-15);
    assert_eq!(at("mount_joint"), 0.0);
    // Ability: four mimic joints, six independent.
    let ability = Robot::load(&repo("fixtures/urdf/ability_hand/ability_hand_right.urdf")).unwrap();
    assert_eq!(ability.independent.len(), 6);
    assert_eq!(
        ability.joints.iter().filter(|j| j.mimic.is_some()).count(),
        4
    );
}

fn urdf(joints: &str, links: &[&str]) -> String {
    let links: String = links
        .iter()
        .map(|l| format!("<link name=\"{l}\"/>\n"))
        .collect();
    format!("<robot name=\"r\">\n{links}{joints}\n</robot>\n")
}

fn revolute(name: &str, parent: &str, child: &str, extra: &str) -> String {
    format!(
        "<joint name=\"{name}\" type=\"revolute\"><parent link=\"{parent}\"/><child link=\"{child}\"/>\
         <axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>{extra}</joint>\n"
    )
}

fn robot_error(text: &str) -> String {
    match Robot::parse(text, "bad.urdf") {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => {
            let s = e.to_string();
            assert!(matches!(e, ProblemError::RobotModel { .. }), "{s}");
            assert!(s.starts_with("bad.urdf: "), "{s}");
            s
        }
    }
}

#[test]
fn malformed_descriptions_are_named_errors() {
    let j1 = revolute("j1", "a", "b", "");
    let cases: Vec<(String, &str)> = vec![
        ("<robot".into(), "not well-formed XML"),
        ("<model name=\"x\"/>".into(), "expected a <robot>"),
        (
            urdf(&revolute("j1", "a", "missing", ""), &["a"]),
            "child link `missing` is not a <link>",
        ),
        (
            urdf(&revolute("j1", "nope", "a", ""), &["a", "b"]),
            "parent link `nope`",
        ),
        (urdf(&j1, &["a", "b", "c"]), "2 root links"),
        (
            urdf(
                &format!(
                    "{}{}",
                    revolute("j1", "a", "b", ""),
                    revolute("j2", "b", "a", "")
                ),
                &["a", "b"],
            ),
            "cycle",
        ),
        (
            urdf(
                &format!(
                    "{j1}{}{}",
                    revolute("j2", "b", "c", ""),
                    revolute("j3", "c", "b", "")
                ),
                &["a", "b", "c"],
            ),
            "already the child",
        ),
        (
            urdf(&j1.replace("revolute", "hinge"), &["a", "b"]),
            "unknown joint type `hinge`",
        ),
        (
            urdf(&j1.replace("revolute", "spherical"), &["a", "b"]),
            "`spherical` is not supported",
        ),
        (
            urdf(&j1.replace("0 0 1", "0 0 0"), &["a", "b"]),
            "<axis xyz> is zero",
        ),
        (
            urdf(&j1.replace("0 0 1", "0 nan 1"), &["a", "b"]),
            "<axis xyz=\"0 nan 1\">: expected 3 finite numbers",
        ),
        (
            urdf(
                &j1.replace("</joint>", "<origin xyz=\"0 0 inf\"/></joint>"),
                &["a", "b"],
            ),
            "<origin xyz=\"0 0 inf\">: expected 3 finite numbers",
        ),
        (
            urdf(&j1.replace("effort=\"1\"", "effort=\"-2\""), &["a", "b"]),
            "negative",
        ),
        (
            urdf(
                &revolute("j1", "a", "b", "<mimic joint=\"jx\"/>"),
                &["a", "b"],
            ),
            "<mimic joint=\"jx\">: no joint of that name",
        ),
        (
            urdf(
                &format!(
                    "{}{}",
                    revolute("j1", "a", "b", "<mimic joint=\"j2\"/>"),
                    revolute("j2", "b", "c", "<mimic joint=\"j1\"/>")
                ),
                &["a", "b", "c"],
            ),
            "cycle of mimic joints",
        ),
        (urdf(&j1, &["a", "b", "a"]), "a second link of this name"),
        (urdf("<joint type=\"fixed\"/>", &["a"]), "has no name"),
        (
            urdf(
                "<joint name=\"j\" type=\"fixed\"><parent link=\"a\"/></joint>",
                &["a"],
            ),
            "no <child",
        ),
        ("<robot name=\"r\"></robot>".into(), "has no <link>"),
    ];
    let more: Vec<(String, &str)> = vec![
        (
            urdf(&j1.replace("0 0 1", "0 0 x"), &["a", "b"]),
            "<axis xyz=\"0 0 x\">",
        ),
        (
            urdf(&j1.replace("upper=\"1\"", "upper=\"one\""), &["a", "b"]),
            "<limit upper=\"one\">",
        ),
        (
            urdf(
                &revolute("j1", "a", "b", "<mimic joint=\"j1\" multiplier=\"2 3\"/>"),
                &["a", "b"],
            ),
            "expected 1 finite number",
        ),
        (
            urdf(
                &revolute("j1", "a", "b", "<mimic multiplier=\"2\"/>"),
                &["a", "b"],
            ),
            "<mimic> has no joint attribute",
        ),
        (
            urdf(
                &revolute("j1", "a", "b", "<axis xyz=\"1 0 0\"/>"),
                &["a", "b"],
            ),
            "a second <axis> (line 4; the first is on line 4)",
        ),
        (
            urdf(
                &revolute("j1", "a", "b", "<origin/>\n<origin xyz=\"0 0 1\"/>"),
                &["a", "b"],
            ),
            "a second <origin> (line 5; the first is on line 4)",
        ),
        (
            urdf(
                &revolute("j1", "a", "b", "<child link=\"b\"/>"),
                &["a", "b"],
            ),
            "a second <child>",
        ),
        (
            urdf(
                &revolute(
                    "j1",
                    "a",
                    "b",
                    "<origin rpy=\"0 0 1\" quat_xyzw=\"0 0 0 1\"/>",
                ),
                &["a", "b"],
            )
            .replace("<robot name=\"r\">", "<robot name=\"r\" version=\"1.1\">"),
            "both rpy and quat_xyzw",
        ),
        (
            urdf(
                &revolute("j1", "a", "b", "<origin quat_xyzw=\"0 0 0 0\"/>"),
                &["a", "b"],
            )
            .replace("<robot name=\"r\">", "<robot name=\"r\" version=\"1.2\">"),
            "expected a nonzero quaternion",
        ),
        (
            urdf(
                &revolute("j1", "a", "b", "<origin quat_xyzw=\"0 0 1\"/>"),
                &["a", "b"],
            )
            .replace("<robot name=\"r\">", "<robot name=\"r\" version=\"1.1\">"),
            "<origin quat_xyzw=\"0 0 1\">: expected 4 finite numbers",
        ),
    ];
    for (text, expect) in cases.into_iter().chain(more) {
        let msg = robot_error(&text);
        assert!(msg.contains(expect), "expected `{expect}` in: {msg}");
    }
    // The element and its line are named.
    let msg = robot_error(&urdf(&j1.replace("0 0 1", "0 0 0"), &["a", "b"]));
    assert!(msg.contains("<joint name=\"j1\"> (line 4)"), "{msg}");
}

/// `quat_xyzw` turns a joint's origin from URDF 1.1 on, normalised (as urdfdom reads
/// it); an older file's is ignored, as urdfdom ignores it. random-6 and random-7 check
/// it against Pinocchio; this checks the versions and the length.
#[test]
fn quaternion_origins_from_urdf_1_1() {
    let (x, y, z, w) = (0.1, -0.4, 0.3, 0.8);
    let with = |version: &str, quat: [f64; 4]| {
        let text = urdf(
            &revolute(
                "j1",
                "a",
                "b",
                &format!(
                    "<origin quat_xyzw=\"{} {} {} {}\"/>",
                    quat[0], quat[1], quat[2], quat[3]
                ),
            ),
            &["a", "b"],
        )
        .replace(
            "<robot name=\"r\">",
            &format!("<robot name=\"r\"{version}>"),
        );
        Robot::parse(&text, "q.urdf").unwrap().joints[0]
            .origin
            .rotation
    };
    let expected = UnitQuaternion::new_normalize(w, x, y, z);
    for version in [" version=\"1.1\"", " version=\" 1.2 \"", " version=\"2.0\""] {
        for scale in [1.0, 3.5, 1e-200, 1e300] {
            let r = with(version, [x * scale, y * scale, z * scale, w * scale]);
            assert!(
                r.angle_to(&expected) < 4.0 * f64::EPSILON,
                "{version} {scale}: {r:?}"
            );
        }
    }
    for version in ["", " version=\"1.0\"", " version=\"one\""] {
        let r = with(version, [x, y, z, w]);
        assert_eq!(r, UnitQuaternion::identity(), "{version}");
    }
}

#[test]
fn limits_without_effort_or_velocity_load_unlimited() {
    let j = "<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\
             <axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\"/></joint>";
    let robot = Robot::parse(&urdf(j, &["a", "b"]), "x.urdf").unwrap();
    assert_eq!(robot.joints[0].effort, None);
    assert_eq!(
        (robot.joints[0].lower, robot.joints[0].upper),
        (Some(-1.0), Some(1.0))
    );
    let robot = Robot::parse(
        &urdf(
            &j.replace(
                "<limit lower=\"-1\" upper=\"1\"/>",
                "<limit effort=\"0\" velocity=\"1\"/>",
            ),
            &["a", "b"],
        ),
        "x.urdf",
    )
    .unwrap();
    assert_eq!(robot.joints[0].effort, None, "an effort of 0 is no limit");
}

#[test]
fn a_floating_mount_at_the_root_is_held_fixed() {
    let fixed = |kind: &str, parent: &str| {
        format!(
            "<joint name=\"mount\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"palm\"/>\
             <origin xyz=\"0 0 0.1\"/></joint>"
        )
    };
    let finger = revolute("j1", "palm", "tip", "");
    let robot = Robot::parse(
        &urdf(
            &format!("{}{finger}", fixed("floating", "world")),
            &["world", "palm", "tip"],
        ),
        "m.urdf",
    )
    .unwrap();
    assert_eq!(robot.independent.len(), 1);
    assert!(
        robot.warnings.iter().any(|w| w.contains("mounts the hand")),
        "{:?}",
        robot.warnings
    );
    let reference = Robot::parse(
        &urdf(
            &format!("{}{finger}", fixed("fixed", "world")),
            &["world", "palm", "tip"],
        ),
        "m.urdf",
    )
    .unwrap();
    assert_eq!(robot.pose(&[0.3]).links[2], reference.pose(&[0.3]).links[2]);
    // Inside the hand it is refused.
    let inner = format!(
        "{}<joint name=\"slider\" type=\"planar\"><parent link=\"palm\"/><child link=\"tip\"/></joint>",
        revolute("j0", "world", "palm", "")
    );
    let msg = robot_error(&urdf(&inner, &["world", "palm", "tip"]));
    assert!(msg.contains("inside the hand"), "{msg}");
}

#[test]
fn inertia_never_blocks_loading() {
    let text = urdf(&revolute("j1", "a", "b", ""), &["b"]).replace(
        "<link name=\"b\"/>",
        "<link name=\"a\"><inertial><mass value=\"heavy\"/></inertial><inertial/>\
         <visual><geometry><mesh filename=\"missing.stl\"/></geometry></visual></link><link name=\"b\"/>",
    );
    let text = text.replace(
        "<robot name=\"r\">",
        "<robot name=\"r\"><material name=\"m\"><color rgba=\"1 0\"/></material>\
         <transmission name=\"t\"><type>x</type></transmission><gazebo><plugin/></gazebo>",
    );
    let robot = Robot::parse(&text, "soft.urdf").unwrap();
    assert_eq!(robot.links.len(), 2);
    assert!(
        robot.warnings.iter().any(|w| w.contains("malformed")),
        "{:?}",
        robot.warnings
    );
    assert!(
        robot
            .warnings
            .iter()
            .any(|w| w.contains("2 <inertial> elements")),
        "{:?}",
        robot.warnings
    );
}

#[test]
fn gravity_needs_the_moving_links_masses() {
    // `a` is the root: its malformed mass weighs on no joint. `b` moves.
    let text = urdf(&revolute("j1", "a", "b", ""), &["b"])
        .replace(
            "<link name=\"b\"/>",
            "<link name=\"a\"><inertial><mass value=\"heavy\"/></inertial></link>\
             <link name=\"b\"><inertial><origin xyz=\"0.1 0 0\"/><mass value=\"2\"/></inertial></link>",
        );
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("gt-gravity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("r.urdf"), &text).unwrap();
    let file = |gravity: serde_json::Value| -> Result<grasp_io::HandProblem, ProblemError> {
        serde_json::from_value::<HandFile>(serde_json::json!({
            "hand": {"model": "r.urdf", "gravity": gravity},
            "contacts": [{"link": "b", "position": [0.1, 0, 0], "normal": [0, 0, 1], "model": "fpc"}],
            "wrench": [0, 0, 1, 0, 0, 0]
        }))
        .unwrap()
        .into_problem(&dir)
    };
    let p = file(serde_json::json!([0.0, -9.81, 0.0])).unwrap().problem;
    let t = p.passive_torque.unwrap();
    let r = Robot::parse(&text, "r.urdf").unwrap();
    let axis = r.joints[0].axis;
    // 2 kg, 0.1 m out along x from the joint, under g along −y: (a × x) · g · m · 0.1.
    let want = axis
        .cross(&Vector3::x())
        .dot(&Vector3::new(0.0, -9.81, 0.0))
        * 0.2;
    assert!((t[0] - want).abs() <= 1e-15 * 9.81, "{t:?} vs {want}");
    let msg = |v: serde_json::Value| file(v).unwrap_err().to_string();
    assert!(msg(serde_json::json!("model")).contains("a URDF has none"));
    for bad in [
        serde_json::json!([0, 0]),
        serde_json::json!("down"),
        serde_json::json!([0, 0, 1e300]),
    ] {
        let m = msg(bad.clone());
        assert!(
            m.contains("hand.gravity") && m.contains("[gx, gy, gz]"),
            "{bad}: {m}"
        );
    }
    // A malformed mass on a moving link: an error naming the link when gravity is asked.
    let heavy = text.replace("<mass value=\"2\"/>", "<mass value=\"-2\"/>");
    std::fs::write(dir.join("r.urdf"), &heavy).unwrap();
    let m = msg(serde_json::json!([0.0, 0.0, -9.81]));
    assert!(
        m.contains("hand.gravity") && m.contains("link `b`") && m.contains("mass"),
        "{m}"
    );
    assert!(file(serde_json::Value::Null).is_ok());
    std::fs::remove_dir_all(&dir).ok();
}

fn allegro_file(
    edit: impl FnOnce(&mut serde_json::Value),
) -> Result<grasp_io::HandProblem, ProblemError> {
    let mut v = serde_json::json!({
        "hand": {"model": "allegro/allegro_hand_right.urdf", "joint_positions": {"joint_1.0": 0.6}},
        "contacts": [{"link": "link_3.0_tip", "position": [0.0, 0.0, 0.01], "normal": [0.0, 0.0, -1.0],
                      "frame": "link", "model": "pcwf", "mu": 0.8}],
        "wrench": [0, 0, 1, 0, 0, 0],
        "torque_limits": "model"
    });
    edit(&mut v);
    let file: HandFile =
        serde_json::from_value(v).map_err(|e| ProblemError::invalid("(json)", "a hand file", e))?;
    file.into_problem(&repo("fixtures/urdf"))
}

#[test]
fn hand_file_errors_name_the_field() {
    let err = |edit: fn(&mut serde_json::Value)| allegro_file(edit).unwrap_err().to_string();
    let e = err(|v| v["hand"]["joint_positions"] = serde_json::json!({"joint_1.O": 0.1}));
    assert!(
        e.contains("hand.joint_positions.joint_1.O") && e.contains("nearest: `joint_1.0`"),
        "{e}"
    );
    let e = err(|v| v["contacts"][0]["link"] = serde_json::json!("link_3_tip"));
    assert!(
        e.contains("contacts[0].link") && e.contains("`link_3.0_tip`"),
        "{e}"
    );
    let e = err(|v| v["hand"]["joint_positions"] = serde_json::json!({"joint_3.0_tip": 0.1}));
    assert!(e.contains("fixed"), "{e}");
    let e = err(|v| v["object_pose"] = serde_json::json!({"quaternion": [1, 1, 0, 0]}));
    assert!(
        e.contains("object_pose.quaternion") && e.contains("unit quaternion"),
        "{e}"
    );
    let e = err(|v| v["hand"]["model"] = serde_json::json!("nowhere.urdf"));
    assert!(
        e.contains("hand.model") && e.contains("nowhere.urdf"),
        "{e}"
    );
    let e = err(|v| v["torque_limits"] = serde_json::json!("effort"));
    assert!(
        e.contains("torque_limits") && e.contains("\"model\""),
        "{e}"
    );
    let e = err(|v| v["contacts"][0]["link"] = serde_json::json!("base_link"));
    assert!(e.contains("a moving joint moves"), "{e}");
    let e = err(|v| v["contacts"][0]["normal"] = serde_json::json!([0, 0, -2]));
    assert!(e.contains("contacts[0].normal"), "{e}");
    // A mimic joint's position is set through its leader.
    let dir = repo("fixtures/urdf");
    let file: HandFile = serde_json::from_value(serde_json::json!({
        "hand": {"model": "ability_hand/ability_hand_right.urdf", "joint_positions": {"index_q2": 0.5}},
        "contacts": [{"link": "index_tip", "position": [0, 0, 0], "normal": [0, 0, 1], "model": "fpc"}],
        "wrench": [0, 0, 1, 0, 0, 0]
    }))
    .unwrap();
    let e = file.into_problem(&dir).unwrap_err().to_string();
    assert!(e.contains("mimics `index_q1`"), "{e}");
}

#[test]
fn model_limits_and_joint_order() {
    let built = allegro_file(|_| {}).unwrap();
    let p = &built.problem;
    assert_eq!(
        p.joint_names,
        ["joint_0.0", "joint_1.0", "joint_2.0", "joint_3.0"]
    );
    assert_eq!(
        p.torque_limits.as_deref(),
        Some(&[Some(10.0.into()); 4][..])
    );
    assert_eq!(
        built.report.defaulted_joints,
        ["joint_0.0", "joint_2.0", "joint_3.0"]
    );
    // A position outside the joint's limits (degrees for radians) is flagged.
    let built =
        allegro_file(|v| v["hand"]["joint_positions"]["joint_1.0"] = serde_json::json!(35.0))
            .unwrap();
    assert!(built
        .report
        .warnings
        .iter()
        .any(|w| w.contains("outside the joint's limits")));
}

/// Mutated and truncated descriptions load or fail with a named error: never a panic.
/// 600 mutations of each of four hands (a URDF 1.1 one with quaternions among them);
/// `GRASP_URDF_MUTATIONS=N` runs N each.
#[test]
fn mutated_descriptions_never_panic() {
    let mutations: usize = std::env::var("GRASP_URDF_MUTATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(600);
    for rel in [
        ROBOTS[0],
        ROBOTS[1],
        ROBOTS[2],
        "fixtures/urdf/random/random-6.urdf",
    ] {
        mutate(rel, mutations);
    }
    // Deep nesting is refused by the XML reader, not by the stack.
    let deep = format!(
        "<robot name=\"r\"><link name=\"a\">{}{}</link></robot>",
        "<x>".repeat(100_000),
        "</x>".repeat(100_000)
    );
    assert!(Robot::parse(&deep, "deep.urdf").is_err());
}

fn mutate(rel: &str, mutations: usize) {
    let base = std::fs::read_to_string(repo(rel)).unwrap();
    let bytes = base.as_bytes();
    let mut rng = Rng(99);
    let pieces: [&str; 12] = [
        "<",
        ">",
        "\"",
        "nan",
        "-1e999",
        "<joint name=\"x\" type=\"fixed\">",
        "</link>",
        "<mimic joint=\"left_dist\"/>",
        "0 0 0",
        "type=\"planar\"",
        "&amp;",
        "\u{0}",
    ];
    let (mut ok, mut rejected) = (0, 0);
    for _ in 0..mutations {
        let mut text = bytes.to_vec();
        for _ in 0..1 + (rng.next() * 3.0) as usize {
            let at = (rng.next() * text.len() as f64) as usize;
            match (rng.next() * 3.0) as usize {
                0 => text.truncate(at),
                1 => {
                    let p = pieces[(rng.next() * pieces.len() as f64) as usize];
                    text.splice(at..at, p.bytes());
                }
                _ => {
                    let end = (at + (rng.next() * 40.0) as usize).min(text.len());
                    text.drain(at..end);
                }
            }
        }
        let text = String::from_utf8_lossy(&text);
        match Robot::parse(&text, "mutated.urdf") {
            Ok(_) => ok += 1,
            Err(e) => {
                assert!(e.to_string().starts_with("mutated.urdf: "), "{e}");
                rejected += 1;
            }
        }
    }
    assert!(
        ok > 0 && rejected > 0,
        "{rel}: {ok} loaded, {rejected} rejected"
    );
}
