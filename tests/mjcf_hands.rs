//! MJCF hands in actuator space from the command line: the Shadow tripod, its
//! unactuated distal joints, and named errors for malformed MJCF.

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

fn json(out: &Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|_| panic!("{}", String::from_utf8_lossy(&out.stderr)))
}

fn numbers(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn shadow_tripod_is_held_in_actuator_space() {
    let cones: &[&str] = if cfg!(feature = "clarabel") {
        &["linear", "exact"]
    } else {
        &["linear"]
    };
    let mut sigma = Vec::new();
    for &c in cones {
        let out = run(&[
            "solve",
            &fixture("hands/shadow-tripod.json"),
            "--cones",
            c,
            "--format",
            "json",
        ]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v = json(&out);
        assert_eq!(v["status"], "optimal", "{c}: {}", v["message"]);
        let u = numbers(&v["torque"]);
        let tau = numbers(&v["joint_torque"]);
        let actuators = v["actuator_names"].as_array().unwrap();
        let joints: Vec<&str> = v["joint_names"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_str().unwrap())
            .collect();
        assert_eq!(u.len(), 13);
        assert_eq!(actuators.len(), 13);
        assert_eq!(tau.len(), 15);
        assert_eq!(joints.len(), 15);
        // The distal joints have no actuator: no torque there.
        let tmax = tau.iter().fold(0.0f64, |a, t| a.max(t.abs()));
        for j in ["robot0:FFJ0", "robot0:MFJ0"] {
            let k = joints.iter().position(|n| *n == j).unwrap();
            assert!(tau[k].abs() <= 1e-7 * tmax, "{j}: {}", tau[k]);
        }
        // Forcerange limits, from the model, hold.
        let limits = v["hand"]["actuator_limits"].as_array().unwrap();
        for (ui, l) in u.iter().zip(limits) {
            assert_eq!(l["source"], "forcerange");
            assert!(
                ui.abs() <= l["limit"].as_f64().unwrap() * (1.0 + 1e-9),
                "{l}"
            );
        }
        let r = &v["residuals"];
        assert!(
            r["wrench"].as_f64().unwrap() <= 1e-7 && r["torque"].as_f64().unwrap() <= 1e-7,
            "{r}"
        );
        sigma.push(v["objective"].as_f64().unwrap());
    }
    if sigma.len() == 2 {
        // Inscribed cones are conservative: σ* ≤ σ(N).
        assert!(sigma[1] <= sigma[0] * (1.0 + 1e-7), "{sigma:?}");
    }
    let text =
        String::from_utf8_lossy(&run(&["solve", &fixture("hands/shadow-tripod.json")]).stdout)
            .into_owned();
    assert!(
        text.contains("13 actuators driving 15 joints")
            && text.contains("joint torques τ = T u")
            && text.contains("|u| ≤ 0.7245"),
        "{text}"
    );
}

#[test]
fn an_unactuated_direction_that_must_carry_torque_is_named() {
    // The first finger presses with its pad (normal across the distal phalanx): its
    // force has a moment about FFJ0, which no actuator can hold.
    let mut p: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(fixture("hands/shadow-tripod.json")).unwrap(),
    )
    .unwrap();
    p["hand"]["model"] = serde_json::json!(fixture("mjcf/shadow_hand/shadow_hand.xml"));
    p["contacts"][1]["normal"] = serde_json::json!([0.0, -1.0, 0.0]);
    p["contacts"][1]["frame"] = serde_json::json!("link");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("gt-mjcf-hands-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("pad.json");
    std::fs::write(&path, p.to_string()).unwrap();
    let out = run(&["solve", path.to_str().unwrap(), "--format", "json"]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json(&out);
    assert_eq!(v["status"], "infeasible");
    let msg = v["message"].as_str().unwrap_or_default().to_string() + &v["reason"].to_string();
    assert!(
        msg.contains("robot0:FFJ0") && msg.contains("underactuated"),
        "{msg}"
    );
}

/// A force range that is not symmetric is the actuator's limit as it stands. The Aero
/// hand's tendons can only pull: given `forcerange="-100 0"` (MuJoCo's sign: a pull
/// shortens the tendon), the pinch's thumb tendon, which pushed (+0.58) without
/// limits, is held at 0 and the others pull harder, on both cone kinds and with
/// Clarabel alike. (Before, the reader took the largest symmetric range inside, |u| ≤
/// 0, and dropped it as no limit.)
#[test]
fn a_pull_only_tendon_is_held() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("gt-mjcf-range-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(fixture("mjcf/menagerie/aero_right.xml")).unwrap();
    let mut pulls = 0;
    let text: String = text
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("<position name=\"right_") && l.contains("_A_tendon\"") {
                pulls += 1;
                l.replace("/>", r#" forcerange="-100 0"/>"#)
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    assert_eq!(pulls, 6);
    std::fs::write(dir.join("aero.xml"), text).unwrap();
    let mut p: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("hands/aero-pinch.json")).unwrap())
            .unwrap();
    p["hand"]["model"] = serde_json::json!("aero.xml");
    p["torque_limits"] = serde_json::json!("model");
    let path = dir.join("pinch.json");
    std::fs::write(&path, p.to_string()).unwrap();
    let path = path.to_str().unwrap();
    let free = json(&run(&[
        "solve",
        &fixture("hands/aero-pinch.json"),
        "--format",
        "json",
    ]));
    let sigma_free = free["objective"].as_f64().unwrap();
    let mut sigmas = Vec::new();
    let backends: &[&str] = if cfg!(feature = "clarabel") {
        &["active-set", "clarabel"]
    } else {
        &["active-set"]
    };
    for cones in ["linear", "exact"] {
        for backend in backends {
            let out = run(&[
                "solve",
                path,
                "--cones",
                cones,
                "--backend",
                backend,
                "--format",
                "json",
            ]);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(0), "{cones} {backend}: {stderr}");
            let v = json(&out);
            let names: Vec<&str> = v["actuator_names"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_str().unwrap())
                .collect();
            let u = numbers(&v["torque"]);
            let umax = u.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            for (k, name) in names.iter().enumerate() {
                if name.ends_with("_A_tendon") {
                    assert_eq!(
                        v["hand"]["actuator_limits"][k]["limit"],
                        serde_json::json!([-100.0, 0.0])
                    );
                    assert!(
                        u[k] <= 1e-7 * umax,
                        "{cones} {backend}: {name} pushes, u = {}",
                        u[k]
                    );
                }
            }
            let th1 = names
                .iter()
                .position(|n| *n == "right_th1_A_tendon")
                .unwrap();
            assert!(u[th1].abs() <= 1e-7 * umax, "{cones} {backend}: {}", u[th1]);
            sigmas.push(v["objective"].as_f64().unwrap());
        }
    }
    for s in &sigmas {
        assert!(*s > 1.1 * sigma_free, "{sigmas:?} against {sigma_free}");
        assert!((s - sigmas[0]).abs() <= 1e-6 * sigmas[0], "{sigmas:?}");
    }
    let text = String::from_utf8_lossy(&run(&["solve", path]).stdout).into_owned();
    assert!(text.contains("-100 ≤ u ≤ 0  at its limit"), "{text}");
    let listing =
        String::from_utf8_lossy(&run(&["hand", dir.join("aero.xml").to_str().unwrap()]).stdout)
            .into_owned();
    assert!(listing.contains("-100 ≤ u ≤ 0 (forcerange)"), "{listing}");
}

/// Joints' `actuatorfrcrange` (MuJoCo's clamp on the total actuator force at a joint)
/// narrows the force range of the one actuator that drives the joint, through its arm:
/// the test hand's f1_abd joint (gear 1, `forcerange` ±0.5) to [−0.3, 0.4], th_slide
/// (gear 50, `ctrlrange` ±2) to [−60, 80] / 50, f2_flex (arm 0.02 through the f2_curl
/// tendon) to [−20, 15]; f2_mid, which two actuators drive, is not applied, with a
/// warning. `cargo test -p grasp-io --test mjcf` checks the same against MuJoCo's
/// compiled ranges and moment arms.
#[test]
fn a_joints_actuator_force_range_limits_its_one_actuator() {
    let out = run(&[
        "hand",
        &fixture("mjcf/test/tendon_finger.xml"),
        "--format",
        "json",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("actuatorfrcrange of f2_mid"), "{stderr}");
    let v = json(&out);
    let by_name = |n: &str| {
        v["actuators"]
            .as_array()
            .unwrap()
            .iter()
            .find(|a| a["name"] == n)
            .unwrap()
            .clone()
    };
    for (name, limit, source) in [
        ("f1_abd", serde_json::json!([-0.3, 0.4]), "actuatorfrcrange"),
        ("thumb", serde_json::json!([-1.2, 1.6]), "actuatorfrcrange"),
        (
            "f2_tendon",
            serde_json::json!([-20.0, 15.0]),
            "actuatorfrcrange",
        ),
        ("f1_tendon", serde_json::json!(40.0), "ctrlrange"),
        ("f2_mid", serde_json::Value::Null, "none"),
    ] {
        let a = by_name(name);
        assert_eq!(
            (&a["limit"], a["limit_source"].as_str().unwrap()),
            (&limit, source),
            "{name}"
        );
    }
    let joints = v["independent_joints"].as_array().unwrap();
    assert_eq!(joints[0]["effort"], serde_json::json!([-0.3, 0.4]));
}

#[test]
fn mjcf_listing_and_errors() {
    let out = run(&["hand", &fixture("mjcf/shadow_hand/shadow_hand.xml")]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("robot0:A_FFJ1") && text.contains("|u| ≤ 0.7245 (forcerange)"),
        "{text}"
    );
    let v = json(&run(&[
        "hand",
        &fixture("mjcf/test/tendon_finger.xml"),
        "--format",
        "json",
    ]));
    let a = v["actuators"].as_array().unwrap();
    let t = a.iter().find(|x| x["name"] == "f1_tendon").unwrap();
    assert!(
        (t["moment"]["f1_mid"].as_f64().unwrap() - 0.018).abs() < 1e-15,
        "{t}"
    );
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("gt-mjcf-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.xml");
    std::fs::write(&bad, "<mujoco>\n<worldbody>\n<body name=\"a\"><joint/>\n<body name=\"b\"><joint type=\"ball\"/></body></body>\n</worldbody></mujoco>").unwrap();
    let out = run(&["hand", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.xml") && err.contains("line 4") && err.contains("ball joint"),
        "{err}"
    );
}

#[test]
fn batch_lines_with_an_mjcf_hand_report_actuators_and_joints() {
    let mut p: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(fixture("hands/shadow-tripod.json")).unwrap(),
    )
    .unwrap();
    p["hand"]["model"] = serde_json::json!(fixture("mjcf/shadow_hand/shadow_hand.xml"));
    p["wrenches"] = serde_json::json!([[0, 0, -0.4905, 0, 0, 0], [0.05, 0, -0.4905, 0, 0, 0]]);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("gt-mjcf-batch-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("in.jsonl");
    std::fs::write(&path, format!("{p}\n{p}\n")).unwrap();
    let out = run(&["batch", path.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    let records: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(records.len(), 4);
    let single = json(&run(&[
        "solve",
        &fixture("hands/shadow-tripod.json"),
        "--format",
        "json",
    ]));
    assert_eq!(records[0]["objective"], single["objective"]);
    for r in &records {
        assert_eq!(
            r["actuator_names"].as_array().unwrap().len(),
            r["torque"].as_array().map_or(13, Vec::len)
        );
        if r["status"] == "optimal" {
            assert_eq!(r["joint_torque"].as_array().unwrap().len(), 15);
        }
    }
}
