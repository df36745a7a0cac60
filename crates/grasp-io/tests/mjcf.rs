//! MJCF hands against MuJoCo (fixtures/mjcf/oracle, written by scripts/oracle_mjcf.py):
//! Jᵀ, T and G per configuration; the bodies' masses and gravity's joint torques
//! (fixtures/mjcf/gravity, written by scripts/mass_mjcf.py); and malformed files as
//! named errors.

use grasp_core::error::ProblemError;
use grasp_core::TorqueLimit;
use grasp_io::hand::HandFile;
use grasp_io::mass::LinkMass;
use grasp_io::urdf::Robot;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

mod common;

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(p)
}

#[test]
fn jacobians_and_transmissions_match_mujoco() {
    let dir = repo("fixtures/mjcf/oracle");
    // The random hands of scripts/random_mjcf.py, all of them (`spatial-*`: with
    // spatial tendons).
    let mut randoms: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|f| f.starts_with("random-") || f.starts_with("spatial-"))
        .filter_map(|f| Some(f.strip_suffix(".json")?.to_string()))
        .collect();
    randoms.sort();
    let spatial = randoms.iter().filter(|r| r.starts_with("spatial-")).count();
    assert!(randoms.len() - spatial >= 8 && spatial >= 6, "{randoms:?}");
    let named = [
        "shadow",
        "adroit",
        "robotiq-s",
        "jaco",
        "tendon-test",
        "menagerie-shadow",
        "menagerie-allegro",
        "menagerie-leap",
        "menagerie-dexee",
        "menagerie-panda",
        "menagerie-aero",
    ];
    for name in named
        .iter()
        .copied()
        .chain(randoms.iter().map(String::as_str))
    {
        let text = std::fs::read_to_string(dir.join(format!("{name}.json"))).unwrap();
        let oracle: serde_json::Value = serde_json::from_str(&text).unwrap();
        let cases = oracle["cases"].as_array().unwrap();
        let least = if randoms.iter().any(|r| r == name) {
            20
        } else {
            50
        };
        assert!(
            cases.len() >= least,
            "{name}: {} configurations",
            cases.len()
        );
        let (mut worst_j, mut worst_t, mut worst_f): (f64, f64, f64) = (0.0, 0.0, 0.0);
        let (mut worst_p, mut with_springs) = (0.0f64, 0);
        let model = cases[0]["problem"]["hand"]["model"].as_str().unwrap();
        let robot = Robot::load(&dir.join(model)).unwrap();
        for case in cases {
            // Every frame where MuJoCo puts it (the first cases).
            worst_f = worst_f.max(common::frame_error(&robot, case, model));
            let file: HandFile = serde_json::from_value(case["problem"].clone()).unwrap();
            let label = case["problem"]["name"].as_str().unwrap().to_string();
            let built = file
                .into_problem(&dir)
                .unwrap_or_else(|e| panic!("{label}: {e}"));
            let p = &built.problem;
            let expect: BTreeMap<String, Vec<f64>> =
                serde_json::from_value(case["jacobian_transpose"].clone()).unwrap();
            let scale = expect
                .values()
                .flatten()
                .fold(0.0f64, |a, v| a.max(v.abs()));
            let n = p.force_dim();
            for (j, jname) in p.joint_names.iter().enumerate() {
                for c in 0..n {
                    let err = (p.jacobian_transpose[(j, c)] - expect[jname][c]).abs() / scale;
                    worst_j = worst_j.max(err);
                    assert!(err <= 1e-10, "{label}: Jᵀ[{jname}][{c}] off by {err:e}");
                }
            }
            for (jname, row) in &expect {
                if !p.joint_names.contains(jname) {
                    assert!(
                        row.iter().all(|&v| v.abs() <= 1e-14 * scale),
                        "{label}: {jname} moves a contact but is not in the problem"
                    );
                }
            }
            let tr: BTreeMap<String, BTreeMap<String, f64>> =
                serde_json::from_value(case["transmission"].clone()).unwrap();
            let t = p
                .transmission
                .as_ref()
                .expect("an actuated MJCF hand has a transmission");
            let tscale = tr
                .values()
                .flat_map(|r| r.values())
                .fold(0.0f64, |a, v| a.max(v.abs()));
            for (j, jname) in p.joint_names.iter().enumerate() {
                for (a, aname) in t.actuator_names.iter().enumerate() {
                    let want = tr[jname].get(aname).copied().unwrap_or(0.0);
                    let err = (t.matrix[(j, a)] - want).abs() / tscale;
                    worst_t = worst_t.max(err);
                    assert!(
                        err <= 1e-10,
                        "{label}: T[{jname}][{aname}] = {} vs MuJoCo {want}",
                        t.matrix[(j, a)]
                    );
                }
                // Every actuator MuJoCo has on this joint is in the problem.
                for aname in tr[jname].keys() {
                    assert!(
                        t.actuator_names.contains(aname),
                        "{label}: {aname} drives {jname} but is missing"
                    );
                }
            }
            // `"torque_limits": "model"`: each actuator's bound as MuJoCo's compiled
            // ranges give it (classes, autolimits, gains resolved by MuJoCo).
            let limits = p
                .torque_limits
                .as_ref()
                .expect("model limits were asked for");
            for (a, aname) in t.actuator_names.iter().enumerate() {
                let want: Option<TorqueLimit> =
                    serde_json::from_value(oracle["actuator_limits"][aname].clone()).unwrap();
                assert_eq!(limits[a], want, "{label}: the limit of {aname}");
            }
            // The springs' torques (MuJoCo's qfrc_spring reduced by the couplings; none
            // written when all are 0), each against the torques' scale.
            let springs: BTreeMap<String, f64> =
                serde_json::from_value(case["passive_torque"].clone()).unwrap_or_default();
            let pscale = springs.values().fold(0.0f64, |a, v| a.max(v.abs()));
            for (j, jname) in p.joint_names.iter().enumerate() {
                let want = springs.get(jname).copied().unwrap_or(0.0);
                let got = p.passive_torque.as_ref().map_or(0.0, |t| t[j]);
                let err = (got - want).abs() / pscale.max(tscale);
                worst_p = worst_p.max(err);
                assert!(
                    err <= 1e-10,
                    "{label}: passive torque on {jname} {got} vs MuJoCo {want}"
                );
            }
            if !springs.is_empty() {
                with_springs += 1;
            }
            let g: Vec<Vec<f64>> = serde_json::from_value(case["grasp_matrix"].clone()).unwrap();
            let gscale = g.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
            for r in 0..6 {
                for c in 0..n {
                    let err = (p.grasp_matrix[(r, c)] - g[r][c]).abs() / gscale;
                    assert!(err <= 1e-10, "{label}: G[{r}][{c}] off by {err:e}");
                }
            }
        }
        eprintln!(
            "{name}: {} configurations, worst relative error Jᵀ {worst_j:.1e}, T {worst_t:.1e}, frames {worst_f:.1e} (metres, rotation entries), spring torques {worst_p:.1e} ({with_springs} configurations with springs)",
            cases.len()
        );
    }
}

#[test]
fn masses_and_gravity_torques_match_mujoco() {
    let dir = repo("fixtures/mjcf/gravity");
    let oracle: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("oracle.json")).unwrap()).unwrap();
    let hands = oracle["hands"].as_array().unwrap();
    assert!(hands.len() >= 16, "{} hands", hands.len());
    let (mut worst_m, mut worst_g, mut worst_p, mut loaded) = (0.0f64, 0.0f64, 0.0f64, 0);
    for hand in hands {
        let file = hand["model"].as_str().unwrap();
        let robot = Robot::load(&dir.join(file)).unwrap();
        let gravity: [f64; 3] = serde_json::from_value(hand["gravity"].clone()).unwrap();
        let g = robot.gravity.expect("a fixed hand's file fixes gravity");
        assert_eq!(g.to_array(), gravity, "{file}: <option gravity>");
        // Each body's mass (the part gravity loads) and centre, as MuJoCo compiles them.
        let bodies = hand["bodies"].as_object().unwrap();
        let heaviest = bodies
            .values()
            .fold(0.0f64, |a, b| a.max(b["mass"].as_f64().unwrap()));
        for (name, b) in bodies {
            let link = robot
                .link(name)
                .unwrap_or_else(|| panic!("{file}: body {name}"));
            let loads = b["mass"].as_f64().unwrap() * (1.0 - b["gravcomp"].as_f64().unwrap());
            let com: [f64; 3] = serde_json::from_value(b["com"].clone()).unwrap();
            let (mass, at) = match &robot.masses[link] {
                LinkMass::None => (0.0, grasp_io::frame::Vector3::zeros()),
                LinkMass::Known { mass, com } => (*mass, *com),
                LinkMass::Unknown(why) => panic!("{file}: {name}: {why}"),
            };
            let err = (mass - loads).abs() / heaviest;
            worst_m = worst_m.max(err);
            assert!(err <= 1e-12, "{file}: {name} weighs {mass}, MuJoCo {loads}");
            if loads > 0.0 {
                let off = (at - grasp_io::frame::Vector3::from(com)).norm();
                worst_m = worst_m.max(off / 0.1);
                assert!(
                    off <= 1e-12,
                    "{file}: {name}'s centre {at:?}, MuJoCo {com:?}"
                );
            }
        }
        // Gravity's torques per configuration, reduced by the couplings; and the hand
        // form's passive torques (springs and weight) on its joints.
        let sites: Vec<serde_json::Value> = robot
            .sites
            .iter()
            .filter(|s| {
                robot
                    .chain(s.link)
                    .iter()
                    .any(|&j| robot.joints[j].kind != grasp_io::urdf::JointKind::Fixed)
            })
            .take(3)
            .map(|s| serde_json::json!({"site": s.name, "model": "fpc"}))
            .collect();
        for case in hand["cases"].as_array().unwrap() {
            let q: BTreeMap<String, f64> =
                serde_json::from_value(case["joint_positions"].clone()).unwrap();
            let want: BTreeMap<String, f64> =
                serde_json::from_value(case["gravity_torque"].clone()).unwrap();
            let springs: BTreeMap<String, f64> =
                serde_json::from_value(case["spring_torque"].clone()).unwrap();
            let q_ind: Vec<f64> = robot
                .independent
                .iter()
                .map(|&j| q[&robot.joints[j].name])
                .collect();
            let full = robot.gravity_torques(&robot.pose(&q_ind), &g).unwrap();
            let mut got = vec![0.0; q_ind.len()];
            for (j, c) in robot.coupling.iter().enumerate() {
                if let Some(c) = c {
                    got[c.independent] += c.multiplier * full[j];
                }
            }
            let scale = want.values().fold(0.0f64, |a, v| a.max(v.abs()));
            for (k, &j) in robot.independent.iter().enumerate() {
                let name = &robot.joints[j].name;
                let err = (got[k] - want[name]).abs() / scale;
                worst_g = worst_g.max(err);
                assert!(
                    err <= 1e-10,
                    "{file}: weight on {name} {} vs MuJoCo {}",
                    got[k],
                    want[name]
                );
            }
            let problem: HandFile = serde_json::from_value(serde_json::json!({
                "hand": {"model": file, "joint_positions": q, "gravity": "model"},
                "contacts": sites,
                "wrench": [0, 0, 0, 0, 0, 0]
            }))
            .unwrap();
            let p = match problem.into_problem(&dir) {
                Ok(p) => p.problem,
                // A configuration that puts a side site inside its geom.
                Err(e) if e.to_string().contains("side site") => continue,
                Err(e) => panic!("{file}: {e}"),
            };
            let passive = p.passive_torque.expect("gravity was asked for");
            let pscale = scale.max(springs.values().fold(0.0f64, |a, v| a.max(v.abs())));
            for (r, name) in p.joint_names.iter().enumerate() {
                let err = (passive[r] - want[name] - springs[name]).abs() / pscale;
                worst_p = worst_p.max(err);
                assert!(err <= 1e-10, "{file}: passive torque on {name}");
            }
            loaded += 1;
        }
    }
    eprintln!(
        "{} hands: masses and centres within {worst_m:.1e} (of the heaviest body, of 0.1 m), gravity torques {worst_g:.1e}, hand-form passive torques {worst_p:.1e} on {loaded} configurations",
        hands.len()
    );
}

fn parse_err(text: &str) -> String {
    match Robot::parse_mjcf(text, "bad.xml", None) {
        Ok(_) => panic!("accepted: {text}"),
        Err(e @ ProblemError::RobotModel { .. }) => e.to_string(),
        Err(e) => panic!("not a model error: {e}"),
    }
}

#[test]
fn malformed_mjcf_is_a_named_error() {
    let body = |inner: &str| {
        format!("<mujoco><worldbody><body name=\"b\">{inner}</body></worldbody></mujoco>")
    };
    // An actuator on a spatial tendon with this path.
    let spatial = |path: &str| {
        format!(
            "<mujoco><worldbody><site name=\"s0\" pos=\"-1 0 0\"/><body><joint name=\"a\"/>\
             <geom name=\"c\" type=\"cylinder\" size=\"0.1 1\"/><geom name=\"box\" type=\"box\" size=\"1 1 1\"/>\
             <geom name=\"flat\" type=\"cylinder\" size=\"0 1\"/><geom type=\"sphere\" size=\"1\"/>\
             <site name=\"s1\" pos=\"1 0 0\"/></body></worldbody>\
             <tendon><spatial name=\"t\">{path}</spatial></tendon><actuator><motor tendon=\"t\"/></actuator></mujoco>"
        )
    };
    for (text, needle) in [
        ("<robot/>".to_string(), "root element"),
        ("<mujoco><worldbody>".to_string(), "well-formed"),
        (body("<joint type=\"ball\"/><body><joint type=\"ball\"/></body>"), "ball joint"),
        (body("<body><freejoint/></body>"), "free joint"),
        ("<mujoco><worldbody><body name=\"l\"><freejoint/><body><joint/></body></body><body name=\"r\"><freejoint/><body><joint/></body></body></worldbody></mujoco>".to_string(), "a second floating hand (`r`, after `l`)"),
        (body("<joint axis=\"0 0 0\"/>"), "zero axis"),
        (body("<joint pos=\"1 nan 0\"/>"), "finite numbers"),
        (body("<joint type=\"spring\"/>"), "unknown joint type"),
        (body("<replicate count=\"2\"/>"), "changes the kinematic tree"),
        (body("<site quat=\"0 0 0 0\"/>"), "zero quaternion"),
        (body("<site quat=\"1 0 0 0\" euler=\"0 0 0\"/>"), "more than one orientation"),
        ("<mujoco><compiler angle=\"grad\"/></mujoco>".to_string(), "degree or radian"),
        ("<mujoco><compiler eulerseq=\"xxq\"/></mujoco>".to_string(), "eulerseq"),
        ("<mujoco><compiler autolimits=\"yes\"/></mujoco>".to_string(), "expected true or false"),
        // Without autolimits MuJoCo refuses a range whose `limited` is unspecified.
        ("<mujoco><compiler autolimits=\"false\"/><worldbody><body><joint range=\"0 1\"/></body></worldbody></mujoco>".to_string(), "range is given but not limited"),
        ("<mujoco><compiler autolimits=\"false\"/><worldbody><body><joint name=\"a\"/></body></worldbody><actuator><motor joint=\"a\" forcerange=\"-1 1\" forcelimited=\"auto\"/></actuator></mujoco>".to_string(), "forcerange is given but not forcelimited"),
        ("<mujoco><include file=\"missing.xml\"/></mujoco>".to_string(), "cannot read"),
        ("<mujoco><actuator><motor joint=\"nope\"/></actuator></mujoco>".to_string(), "not a hinge or slide joint"),
        ("<mujoco><worldbody><body><joint name=\"a\"/><joint name=\"b\"/></body></worldbody><equality><joint joint1=\"a\" joint2=\"b\" polycoef=\"0 1 2 0 0\"/></equality></mujoco>".to_string(), "only a linear coupling"),
        ("<mujoco><worldbody><body><joint name=\"a\"/></body></worldbody><equality><connect body1=\"a\" body2=\"b\" anchor=\"0 0 0\"/></equality></mujoco>".to_string(), "loop-closing"),
        ("<mujoco><worldbody><body><joint name=\"a\"/></body></worldbody><tendon><spatial name=\"s\"/></tendon><actuator><motor tendon=\"s\"/></actuator></mujoco>".to_string(), "pulls on tendon `s`, which cannot be used"),
        (spatial("<site site=\"s0\"/><geom geom=\"box\"/><site site=\"s1\"/>"), "a tendon wraps spheres and cylinders only"),
        (spatial("<site site=\"s0\"/><geom geom=\"nameless\"/><site site=\"s1\"/>"), "is not a named geom"),
        (spatial("<site site=\"s0\"/><site site=\"s9\"/>"), "site `s9` is not a site of this model"),
        (spatial("<site site=\"s0\"/><geom geom=\"c\" sidesite=\"x\"/><site site=\"s1\"/>"), "sidesite `x` is not a site"),
        (spatial("<geom geom=\"c\"/><site site=\"s1\"/>"), "must start and end at a site"),
        (spatial("<site site=\"s0\"/><geom geom=\"c\"/><geom geom=\"c\"/><site site=\"s1\"/>"), "a geom between two sites"),
        (spatial("<site site=\"s0\"/><site site=\"s1\"/><pulley divisor=\"0\"/><site site=\"s0\"/><site site=\"s1\"/>"), "divisor > 0"),
        (spatial("<site site=\"s0\"/><site site=\"s1\"/><pulley divisor=\"2\"/><site site=\"s0\"/>"), "at least two sites"),
        (spatial("<site site=\"s0\"/><geom geom=\"flat\"/><site site=\"s1\"/>"), "radius size > 0"),
        ("<mujoco><worldbody><body><joint name=\"a\"/><joint name=\"b\"/></body></worldbody><actuator><motor joint=\"a\" forcerange=\"2 1\" forcelimited=\"true\"/></actuator></mujoco>".to_string(), "expected lower < upper"),
        (body("<joint limited=\"true\"/>"), "limited=\"true\" without a range"),
        // A misspelt class would silently take `main`'s values (an actuator's gear, say).
        ("<mujoco><default><default class=\"finger\"/></default><worldbody><body childclass=\"fingr\"><joint/></body></worldbody></mujoco>".to_string(), "childclass=\"fingr\": expected a <default> class of this model (nearest: `finger`, `main`)"),
        ("<mujoco><worldbody><body><joint name=\"a\"/></body></worldbody><actuator><motor class=\"big\" joint=\"a\"/></actuator></mujoco>".to_string(), "<motor> (line 1): class=\"big\""),
        ("<mujoco><default><default class=\"a\"/><default class=\"b\"><default class=\"a\"/></default></default></mujoco>".to_string(), "a second <default class=\"a\">"),
        (format!("<mujoco><worldbody>{}{}</worldbody></mujoco>", "<body>".repeat(100_000), "</body>".repeat(100_000)), "nested"),
    ] {
        let msg = parse_err(&text);
        assert!(msg.contains(needle), "{needle:?} not in {msg:?}");
    }
    // A self-including file stops at the include depth.
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("gt-mjcf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("self.xml"),
        "<mujoco><include file=\"self.xml\"/></mujoco>",
    )
    .unwrap();
    let e = Robot::load(&dir.join("self.xml")).unwrap_err().to_string();
    assert!(e.contains("nested more than"), "{e}");
}

/// With `autolimits="false"`, only what `limited`, `forcelimited` and `ctrllimited`
/// say limits: as in MuJoCo, which loads this model with j unlimited, `f` force-limited
/// and `c`'s control range not a limit. With autolimits (the default), a range limits
/// only when its lower bound is below its upper, as in MuJoCo.
#[test]
fn without_autolimits_the_flags_decide() {
    let text = r#"<mujoco><compiler autolimits="false"/><default><motor ctrllimited="false"/></default>
      <worldbody><body name="b"><joint name="j" axis="0 0 1" range="0 90" limited="false"/>
      <body name="c"><joint name="k" axis="0 1 0" range="-10 10" limited="true"/></body></body></worldbody>
      <actuator><motor name="f" joint="j" forcerange="-2 3" forcelimited="true"/>
      <motor name="c" joint="k" ctrlrange="-1 1"/></actuator></mujoco>"#;
    let r = Robot::parse_mjcf(text, "a.xml", None).unwrap();
    let (j, k) = (
        &r.joints[r.joint("j").unwrap()],
        &r.joints[r.joint("k").unwrap()],
    );
    assert_eq!((j.lower, j.upper), (None, None));
    assert!((k.upper.unwrap() - 10f64.to_radians()).abs() < 1e-15);
    let limit = |name: &str| r.actuators.iter().find(|a| a.name == name).unwrap().limit;
    assert_eq!(limit("f"), Some(TorqueLimit::Range(Some(-2.0), Some(3.0))));
    assert_eq!(limit("c"), None);
    let text = r#"<mujoco><worldbody><body name="b"><joint name="j" axis="0 0 1" range="2 1"/>
      </body></worldbody><actuator><motor name="f" joint="j" forcerange="0 0" ctrlrange="1 -1"/>
      </actuator></mujoco>"#;
    let r = Robot::parse_mjcf(text, "b.xml", None).unwrap();
    assert_eq!(r.joints[r.joint("j").unwrap()].upper, None);
    assert_eq!(r.actuators[0].limit, None);
}

#[test]
fn unknown_elements_warn_once_and_degrees_are_the_default() {
    let text = r#"<mujoco><worldbody><body name="b"><joint name="j" axis="0 0 1" range="0 90" ref="45"/><plugin/><plugin/></body></worldbody><flag/></mujoco>"#;
    let r = Robot::parse_mjcf(text, "w.xml", None).unwrap();
    let j = &r.joints[r.joint("j").unwrap()];
    assert!((j.upper.unwrap() - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert_eq!(
        r.warnings.iter().filter(|w| w.contains("<plugin>")).count(),
        1,
        "{:?}",
        r.warnings
    );
    assert_eq!(
        r.warnings.iter().filter(|w| w.contains("<flag>")).count(),
        1
    );
    // Motion is q − ref: at q = ref the body is where the file puts it.
    let pose = r.pose(&[std::f64::consts::FRAC_PI_4]);
    let b = r.link("b").unwrap();
    assert!((pose.links[b].rotation.angle()).abs() < 1e-15);
}

/// Mutated and truncated MJCF loads or fails with a named error, never a panic; what
/// loads also builds a hand problem with the links' weight or fails with a named
/// error. Three bases: the test hand (tendons, couplings, every frame form),
/// Menagerie's Shadow hand (nested default classes, position actuators on tendons,
/// autolimits) and a random hand with masses in every form.
#[test]
fn mutated_mjcf_never_panics() {
    mutate(
        "fixtures/mjcf/test/tendon_finger.xml",
        serde_json::json!([
            {"site": "f1_tip_site", "model": "pcwf", "mu": 0.5},
            {"site": "th_tip_site", "model": "pcwf", "mu": 0.5}
        ]),
        &[
            "<equality><joint joint1=\"f2_mid\" joint2=\"f2_flex\"/></equality>",
            "tendon=\"f1_curl\"",
        ],
        12345,
    );
    mutate(
        "fixtures/mjcf/menagerie/shadow_right.xml",
        serde_json::json!([
            {"link": "rh_ffdistal", "position": [0, -0.01, 0.02], "normal": [0, -1, 0],
             "frame": "link", "model": "sfcl", "mu": 0.5, "mu_torsion": 0.005},
            {"link": "rh_thdistal", "position": [0, -0.01, 0.02], "normal": [0, -1, 0],
             "frame": "link", "model": "pcwf", "mu": 0.5}
        ]),
        &[
            "<compiler autolimits=\"false\"/>",
            "forcelimited=\"true\"",
            "limited=\"true\"",
            "childclass=\"nope\"",
            "<plugin joint=\"rh_FFJ3\" forcerange=\"-1 2\"/>",
            "<freejoint/>",
        ],
        67890,
    );
    // Masses in every form, asked for by gravity.
    mutate(
        "fixtures/mjcf/gravity/spatial-4.xml",
        serde_json::json!([
            {"site": "f0_tip", "model": "pcwf", "mu": 0.5},
            {"site": "f1_tip", "model": "pcwf", "mu": 0.5}
        ]),
        &[
            "mass=\"-1\"",
            "type=\"mesh\"",
            "fromto=\"0 0 0 0 0 0\"",
            "size=\"1e12 1e12 1e12\"",
            "density=\"1e12\"",
            "<compiler inertiafromgeom=\"true\" settotalmass=\"1e-300\" boundmass=\"1e12\"/>",
            "gravcomp=\"1e12\"",
            "<inertial pos=\"0 0 0\" mass=\"nan\"/>",
            "<option gravity=\"1e12 0 0\"/>",
            "shellinertia=\"true\"",
            "group=\"-3\"",
        ],
        24680,
    );
}

fn mutate(base: &str, contacts: serde_json::Value, extra: &[&str], seed: u64) {
    let base = std::fs::read_to_string(repo(base)).unwrap();
    let bytes = base.as_bytes();
    let mut state = seed;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut pieces = vec![
        "<",
        ">",
        "\"",
        "nan",
        "-1e999",
        "0 0 0",
        "<joint type=\"ball\"/>",
        "</body>",
        "class=\"nope\"",
        "gear=\"0\"",
        "&amp;",
        "\u{0}",
    ];
    pieces.extend_from_slice(extra);
    let file: HandFile = serde_json::from_value(serde_json::json!({
        "hand": {"model": "mutated.xml", "gravity": [0, 0, -9.81]},
        "contacts": contacts,
        "wrench": [0, 0, -1, 0, 0, 0],
        "torque_limits": "model"
    }))
    .unwrap();
    let (mut ok, mut rejected) = (0, 0);
    for _ in 0..600 {
        let mut text = bytes.to_vec();
        for _ in 0..1 + (next() * 3.0) as usize {
            let at = (next() * text.len() as f64) as usize;
            match (next() * 3.0) as usize {
                0 => text.truncate(at),
                1 => {
                    let p = pieces[(next() * pieces.len() as f64) as usize];
                    text.splice(at..at, p.bytes());
                }
                _ => {
                    let end = (at + (next() * 40.0) as usize).min(text.len());
                    text.drain(at..end);
                }
            }
        }
        let text = String::from_utf8_lossy(&text);
        match Robot::parse_mjcf(&text, "mutated.xml", None) {
            Ok(robot) => {
                ok += 1;
                if let Ok(h) = file.build(&robot) {
                    let _ = grasp_core::GraspModel::new(&h.problem, &Default::default());
                }
            }
            Err(e) => {
                assert!(e.to_string().starts_with("mutated.xml: "), "{e}");
                rejected += 1;
            }
        }
    }
    assert!(ok > 0 && rejected > 0, "{ok} loaded, {rejected} rejected");
}

/// Thousands of bodies load, and an error at the end names its line (line numbers are
/// found by binary search, not by rescanning the text per element).
#[test]
fn large_models_load_and_name_late_lines() {
    let mut text = String::from("<mujoco>\n<worldbody>\n");
    for i in 0..3000 {
        text.push_str(&format!(
            "<body name=\"b{i}\">\n<joint name=\"j{i}\"/>\n</body>\n"
        ));
    }
    let ok = format!("{text}</worldbody>\n</mujoco>\n");
    let r = Robot::parse_mjcf(&ok, "big.xml", None).unwrap();
    assert_eq!(r.independent.len(), 3000);
    let bad = format!("{text}<body><joint axis=\"0 0 0\"/></body>\n</worldbody>\n</mujoco>\n");
    let e = Robot::parse_mjcf(&bad, "big.xml", None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 9003") && e.contains("zero axis"), "{e}");
}

/// Menagerie's scene file holds the hand and a free object: the object is not the
/// hand's mount, so the hand is where the hand's own file puts it, and the warning
/// says so.
#[test]
fn a_free_object_in_the_scene_is_not_the_hand() {
    let dir = repo("fixtures/mjcf/menagerie");
    let hand = Robot::load(&dir.join("shadow_right.xml")).unwrap();
    let scene = Robot::load(&dir.join("scene_right.xml")).unwrap();
    assert_eq!(hand.independent, scene.independent);
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("`object` is a free body") && w.contains("not part of the hand")),
        "{:?}",
        scene.warnings
    );
    let q: Vec<f64> = (0..hand.independent.len())
        .map(|i| 0.1 * (i as f64 + 1.0).sin())
        .collect();
    let (a, b) = (hand.pose(&q), scene.pose(&q));
    for (i, name) in hand.links.iter().enumerate() {
        let j = scene.link(name).unwrap();
        let d = a.links[i].inverse() * b.links[j];
        assert!(
            d.translation.norm() < 1e-15 && d.rotation.angle() < 1e-15,
            "{name} moved"
        );
    }
}

/// An actuator on a tendon that an equality holds at fixed length moves no independent
/// joint: its moment arm, `c₀ + m c₁` with the coupling's `m = −c₀/c₁`, cancels to
/// rounding. It is left out of T, which keeps exact zeros (a residue of 1e-16 used to
/// be refused as a moment arm below 1e-12).
#[test]
fn an_actuator_on_a_tendon_held_fixed_moves_nothing() {
    let text = r#"<mujoco><compiler angle="radian"/><worldbody><body name="b0">
      <joint name="j0" axis="1 0 0"/><body name="b1" pos="0 0 0.05"><joint name="j1" axis="1 0.3 0"/>
      <body name="tip" pos="0 0 0.04"/></body></body></worldbody>
      <tendon><fixed name="t"><joint joint="j1" coef="0.331759"/><joint joint="j0" coef="0.337175"/></fixed></tendon>
      <equality><tendon tendon1="t" polycoef="0.0344847 0 0 0 0"/></equality>
      <actuator><position name="held" tendon="t" gear="2.50962" kp="4"/><motor name="m" joint="j0" gear="0.7"/></actuator></mujoco>"#;
    let robot = Robot::parse_mjcf(text, "held.xml", None).unwrap();
    let file: HandFile = serde_json::from_value(serde_json::json!({
        "hand": {"model": "held.xml", "joint_positions": {"j0": 0.3}},
        "contacts": [{"link": "tip", "position": [0, 0.01, 0.1], "normal": [0, -1, 0],
                      "model": "pcwf", "mu": 0.8}],
        "wrench": [0, 0.1, 0, 0, 0, 0]
    }))
    .unwrap();
    let built = file.build(&robot).unwrap();
    let t = built.problem.transmission.as_ref().unwrap();
    assert_eq!(t.actuator_names, ["m"]);
    assert_eq!(t.matrix.as_slice(), [0.7]);
}

#[test]
fn masses_that_cannot_be_computed_fail_only_gravity() {
    let model = |body: &str, extra: &str| {
        format!(
            r#"<mujoco><compiler angle="radian" {extra}/><worldbody><body name="palm">
            <body name="f" pos="0.02 0 0">{body}<joint name="j" axis="0 1 0"/><site name="tip" pos="0.03 0 0"/>
            </body></body></worldbody></mujoco>"#
        )
    };
    let gravity = |text: &str, g: serde_json::Value| -> Result<Vec<f64>, String> {
        let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("gt-mass-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("h.xml"), text).unwrap();
        let file: HandFile = serde_json::from_value(serde_json::json!({
            "hand": {"model": "h.xml", "gravity": g},
            "contacts": [{"site": "tip", "model": "fpc"}],
            "wrench": [0, 0, 0, 0, 0, 0]
        }))
        .unwrap();
        let out = file.into_problem(&dir);
        std::fs::remove_dir_all(&dir).ok();
        out.map(|p| p.problem.passive_torque.unwrap())
            .map_err(|e| e.to_string())
    };
    let down = serde_json::json!("model");
    // A 0.1 kg sphere 0.03 m out along x, under MuJoCo's default gravity, on a hinge
    // about y: τ = (y × 0.03 x) · (0, 0, −9.81) · 0.1.
    let sphere = r#"<geom type="sphere" size="0.01" pos="0.03 0 0" mass="0.1"/>"#;
    let t = gravity(&model(sphere, ""), down.clone()).unwrap();
    assert!((t[0] - 0.03 * 9.81 * 0.1).abs() <= 1e-15, "{t:?}");
    // A mesh's mass and centre come from the mesh: loading works, gravity names it.
    let mesh = r#"<geom type="mesh" mesh="m"/>"#;
    let text = model(mesh, "");
    assert!(Robot::parse_mjcf(&text, "h.xml", None).is_ok());
    let e = gravity(&text, down.clone()).unwrap_err();
    assert!(
        e.contains("hand.gravity") && e.contains("link `f`") && e.contains("mesh"),
        "{e}"
    );
    // … unless the body has an <inertial>, which `auto` prefers.
    let both =
        format!(r#"{mesh}<inertial pos="0.03 0 0" mass="0.1" diaginertia="1e-6 1e-6 1e-6"/>"#);
    assert_eq!(gravity(&model(&both, ""), down.clone()).unwrap(), t);
    // settotalmass scales every mass: one unknown makes all unknown.
    let e = gravity(&model(mesh, r#"settotalmass="1""#), down.clone()).unwrap_err();
    assert!(e.contains("settotalmass"), "{e}");
    // A geom of the palm, which no joint moves, never matters.
    let palm = model(sphere, "").replace(
        "<body name=\"palm\">",
        "<body name=\"palm\"><geom type=\"mesh\" mesh=\"m\"/>",
    );
    assert_eq!(gravity(&palm, down.clone()).unwrap(), t);
    // Gravity from the file: <option gravity>; a floating hand's is not fixed.
    let sideways =
        model(sphere, "").replace("<worldbody>", r#"<option gravity="0 0 9.81"/><worldbody>"#);
    assert_eq!(gravity(&sideways, down.clone()).unwrap(), vec![-t[0]]);
    let off = model(sphere, "").replace(
        "<worldbody>",
        r#"<option gravity="0 0 9.81"><flag gravity="disable"/></option><worldbody>"#,
    );
    assert_eq!(gravity(&off, down.clone()).unwrap(), vec![0.0]);
    let floating =
        model(sphere, "").replace("<body name=\"palm\">", "<body name=\"palm\"><freejoint/>");
    let e = gravity(&floating, down).unwrap_err();
    assert!(e.contains("hand.gravity") && e.contains("floating"), "{e}");
    assert_eq!(
        gravity(&floating, serde_json::json!([0, 0, -9.81])).unwrap(),
        t
    );
    // Masses within the input domain whose torques are not: named as gravity's.
    let huge = r#"<geom type="box" size="1e12 1e12 1e12" pos="0.03 0 0" density="1e12"/>"#;
    let e = gravity(&model(huge, ""), serde_json::json!("model")).unwrap_err();
    assert!(
        e.contains("hand.gravity") && e.contains("on joint `j`"),
        "{e}"
    );
}
