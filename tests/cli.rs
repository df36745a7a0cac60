//! The command line: exit codes, JSON output, and a named error for every class of
//! malformed input (never a panic).

use std::path::PathBuf;
use std::process::{Command, Output};

/// An edit that spoils a problem file.
type Edit = Box<dyn Fn(&mut serde_json::Value)>;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_grasp-torque"))
}

fn fixture(name: &str) -> String {
    format!("{}/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

fn temp_file(name: &str, text: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("grasp-torque-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn paper() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(fixture("paper-example.json")).unwrap()).unwrap()
}

/// Asserts exit code 2, an error naming `needle`, nothing on stdout, no panic.
fn assert_rejected(out: &Output, needle: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    assert!(err.contains(needle), "expected `{needle}` in: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(out.stdout.is_empty());
}

#[test]
fn solves_the_paper_example_as_text_and_json() {
    let out = run(&["solve", &fixture("paper-example.json")]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("status    optimal") && text.contains("72.5"),
        "{text}"
    );
    assert!(!text.contains("NaN"));
    // Each contact's force on the object: the rows of G times its components (the
    // first finger pushes along +z, the second along −z; together −1, −1 along x, y).
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip_while(|l| !l.starts_with("forces on the object (object frame)"))
        .skip(1)
        .take(2)
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(
        rows,
        [
            ["0", "-0.5", "-0.5", "3.25"],
            ["1", "-0.5", "-0.5", "-3.25"]
        ],
        "{text}"
    );

    let out = run(&["solve", &fixture("paper-example.json"), "--format", "json"]);
    assert_eq!(out.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in [
        "status",
        "objective",
        "torque",
        "contact_forces",
        "object_forces",
        "iterations",
        "residuals",
        "diagnostics",
        "passive_internal_forces",
        "backend",
        "sides",
        "solve_time_us",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["status"], "optimal");
    assert!((v["objective"].as_f64().unwrap() - 72.5).abs() < 1e-9);
    assert!(v["residuals"]["wrench"].as_f64().unwrap() < 1e-12);
}

#[test]
fn paper_model_warns_on_stderr_with_the_residual() {
    let out = run(&[
        "solve",
        &fixture("paper-example.json"),
        "--paper-model",
        "--format",
        "json",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning") && err.contains("‖G f − w‖∞"),
        "{err}"
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((v["objective"].as_f64().unwrap() - 42.5).abs() < 1e-9);
}

#[test]
fn initial_torque_flag_is_used() {
    let out = run(&[
        "solve",
        &fixture("paper-example.json"),
        "--paper-model",
        "--initial-torque",
        "7.5,-2,-7.5,2",
        "--format",
        "json",
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn infeasible_exits_3_with_a_reason() {
    let mut p = paper();
    p["torque_limits"] = serde_json::json!([0.1, 0.1, 0.1, 0.1]);
    let f = temp_file("infeasible.json", &p.to_string());
    let out = run(&["solve", f.to_str().unwrap(), "--format", "json"]);
    assert_eq!(out.status.code(), Some(3));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["status"], "infeasible");
    assert!(v["reason"]["message"]
        .as_str()
        .unwrap()
        .contains("torque limit"));
    assert!(v["reason"]["kind"].is_string());
    assert!(v["torque"].is_null());
    let out = run(&["solve", f.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&out.stdout).contains("reason"));
}

#[test]
fn malformed_files_name_the_field() {
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "unknown field",
            Box::new(|p| p["gripper"] = 1.into()),
            "unknown field `gripper`",
        ),
        (
            "missing wrench",
            Box::new(|p| {
                p.as_object_mut().unwrap().remove("wrench");
            }),
            "missing field `wrench`",
        ),
        (
            "wrong type",
            Box::new(|p| p["contacts"][1]["mu"] = "high".into()),
            "contacts[1].mu",
        ),
        (
            "five rows of G",
            Box::new(|p| {
                p["grasp_matrix"].as_array_mut().unwrap().pop();
            }),
            "grasp_matrix: expected 6 rows",
        ),
        (
            "ragged G",
            Box::new(|p| {
                p["grasp_matrix"][2].as_array_mut().unwrap().pop();
            }),
            "grasp_matrix[2]",
        ),
        (
            "ragged Jᵀ",
            Box::new(|p| {
                p["jacobian_transpose"][1]
                    .as_array_mut()
                    .unwrap()
                    .push(0.into());
            }),
            "jacobian_transpose[1]",
        ),
        (
            "Jᵀ columns",
            Box::new(|p| {
                for r in p["jacobian_transpose"].as_array_mut().unwrap() {
                    r.as_array_mut().unwrap().pop();
                }
            }),
            "jacobian_transpose",
        ),
        (
            "contact dims",
            Box::new(|p| p["contacts"][1]["model"] = "pcwf".into()),
            "contacts",
        ),
        (
            "mu zero",
            Box::new(|p| p["contacts"][0]["mu"] = 0.0.into()),
            "contacts[0].mu",
        ),
        (
            "mu_torsion negative",
            Box::new(|p| p["contacts"][1]["mu_torsion"] = (-0.2).into()),
            "contacts[1].mu_torsion",
        ),
        (
            "missing mu",
            Box::new(|p| {
                p["contacts"][0].as_object_mut().unwrap().remove("mu");
            }),
            "contacts[0].mu",
        ),
        (
            "unknown model",
            Box::new(|p| p["contacts"][0]["model"] = "sticky".into()),
            "unknown variant `sticky`",
        ),
        (
            "model of the wrong type",
            Box::new(|p| p["contacts"][0]["model"] = 1.into()),
            "contacts[0].model: invalid type: integer `1`, expected one of `fpc`, `pcwf`, `sfcl`, `sfce`",
        ),
        (
            "internal forces of the wrong type",
            Box::new(|p| p["internal_forces"] = serde_json::json!([])),
            "internal_forces: invalid type: sequence, expected one of `compliance`, `euclidean`, `free`",
        ),
        (
            "wrench length",
            Box::new(|p| {
                p["wrench"].as_array_mut().unwrap().pop();
            }),
            "wrench: expected 6 numbers",
        ),
        (
            "weights length",
            Box::new(|p| p["torque_weights"] = serde_json::json!([1, 1])),
            "torque_weights",
        ),
        (
            "weights sign",
            Box::new(|p| p["torque_weights"] = serde_json::json!([1, -1, 1, 1])),
            "torque_weights[1]",
        ),
        (
            "limits sign",
            Box::new(|p| p["torque_limits"] = serde_json::json!([1, null, 0, 1])),
            "torque_limits[2]",
        ),
        (
            "min force sign",
            Box::new(|p| p["min_normal_force"] = serde_json::json!(-1)),
            "min_normal_force[0]",
        ),
        (
            "min force length",
            Box::new(|p| p["min_normal_force"] = serde_json::json!([1, 2, 3])),
            "min_normal_force",
        ),
        (
            "min force type",
            Box::new(|p| p["min_normal_force"] = serde_json::json!("lots")),
            "min_normal_force",
        ),
        (
            "initial torque",
            Box::new(|p| p["initial_torque"] = serde_json::json!([1, 2])),
            "initial_torque",
        ),
        (
            "sides",
            Box::new(|p| p["linearization"]["sides"] = 2.into()),
            "linearization",
        ),
        (
            "latitudes",
            Box::new(|p| p["linearization"]["latitudes"] = 0.into()),
            "latitudes",
        ),
        (
            "linearization field",
            Box::new(|p| p["linearization"]["faces"] = 4.into()),
            "linearization",
        ),
        (
            "both forms",
            Box::new(|p| p["fingers"] = serde_json::json!([])),
            "more than one form",
        ),
        (
            "neither form",
            Box::new(|p| {
                p.as_object_mut().unwrap().remove("grasp_matrix");
                p.as_object_mut().unwrap().remove("jacobian_transpose");
            }),
            "three forms",
        ),
        (
            "huge number",
            Box::new(|p| p["wrench"][0] = serde_json::Value::String("1e999".into())),
            "wrench[0]",
        ),
    ];
    for (what, edit, needle) in cases {
        let mut p = paper();
        edit(&mut p);
        let f = temp_file("bad.json", &p.to_string());
        let out = run(&["solve", f.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert_eq!(out.status.code(), Some(2), "{what}: {err}");
        assert!(
            err.contains(needle),
            "{what}: expected `{needle}` in: {err}"
        );
        assert!(!err.contains("panicked"), "{what}: {err}");
    }
}

#[test]
fn syntax_errors_give_line_and_column() {
    let f = temp_file("syntax.json", "{\n  \"wrench\": [1, 2,\n}");
    let out = run(&["solve", f.to_str().unwrap()]);
    assert_rejected(&out, "line 3");
    let f = temp_file("overflow.json", "{\"wrench\": [1e999]}");
    assert_rejected(&run(&["solve", f.to_str().unwrap()]), "line 1");
}

#[test]
fn malformed_geometry_names_the_contact_or_joint() {
    let base = serde_json::json!({
        "contacts": [
            {"name": "thumb_tip", "position": [-0.05, 0, 0], "normal": [1, 0, 0], "model": "pcwf", "mu": 0.5, "finger": 0},
            {"position": [0.05, 0, 0], "normal": [-1, 0, 0], "model": "pcwf", "mu": 0.5, "finger": 1}
        ],
        "fingers": [
            {"name": "thumb", "joints": [{"name": "thumb_base", "origin": [-0.05, 0, 0.1], "axis": [0, 1, 0]}]},
            {"joints": [{"origin": [0.05, 0, 0.1], "axis": [0, 1, 0]}]}
        ],
        "wrench": [0, 0, 1, 0, 0, 0]
    });
    let cases: Vec<(Edit, &str)> = vec![
        (
            Box::new(|g| g["contacts"][0]["normal"] = serde_json::json!([2, 0, 0])),
            "contacts[0] (thumb_tip).normal",
        ),
        (
            Box::new(|g| g["fingers"][0]["joints"][0]["axis"] = serde_json::json!([0, 0.9, 0])),
            "fingers[0] (thumb).joints[0] (thumb_base).axis",
        ),
        (
            Box::new(|g| g["contacts"][1]["finger"] = 7.into()),
            "contacts[1].finger",
        ),
        (
            Box::new(|g| g["contacts"][1]["link"] = 3.into()),
            "contacts[1].link",
        ),
        (
            Box::new(|g| g["fingers"][0]["joints"][0]["type"] = "spherical".into()),
            "unknown variant `spherical`",
        ),
        (
            Box::new(|g| g["contacts"][0]["depth"] = 1.into()),
            "unknown field `depth`",
        ),
    ];
    let f = temp_file("geo-ok.json", &base.to_string());
    let out = run(&["solve", f.to_str().unwrap()]);
    assert!(
        matches!(out.status.code(), Some(0 | 3)),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (edit, needle) in cases {
        let mut g = base.clone();
        edit(&mut g);
        let f = temp_file("geo.json", &g.to_string());
        assert_rejected(&run(&["solve", f.to_str().unwrap()]), needle);
    }
}

#[test]
fn bad_flags_are_usage_errors() {
    let p = fixture("paper-example.json");
    assert_rejected(&run(&["solve", &p, "--sides", "2"]), "--sides");
    assert_rejected(&run(&["solve", &p, "--backend", "cplex"]), "--backend");
    // The native backend does not optimise free internal forces; the error names one
    // that does.
    let out = run(&[
        "solve",
        &p,
        "--backend",
        "active-set",
        "--internal-forces",
        "free",
    ]);
    assert_rejected(&out, "free internal forces");
    if cfg!(feature = "clarabel") {
        assert!(String::from_utf8_lossy(&out.stderr).contains("clarabel"));
    }
    assert_rejected(
        &run(&["solve", &p, "--initial-torque", "1,x,3,4"]),
        "--initial-torque",
    );
    assert_rejected(
        &run(&["solve", &p, "--initial-torque", "1,2"]),
        "--initial-torque: expected 4 values",
    );
    assert_rejected(
        &run(&["solve", "/nonexistent/problem.json"]),
        "could not read",
    );
    let out = run(&["solve"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn oversized_linearisations_and_zero_wrenches() {
    let p = fixture("hand4-sfce.json");
    assert_rejected(
        &run(&["solve", &p, "--sides", "4096", "--latitudes", "256"]),
        "at most 1048576 cone rows",
    );
    let mut v = paper();
    v["wrench"] = serde_json::json!([0, 0, 0, 0, 0, 0]);
    let f = temp_file("zero.json", &v.to_string());
    let out = run(&["solve", f.to_str().unwrap(), "--format", "json"]);
    assert_eq!(out.status.code(), Some(0));
    let s: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(s["objective"].as_f64().unwrap(), 0.0);
}

/// The exact solver's hard grasps (`fixtures/sweep`, README there) end with an answer
/// from the command line: optimal (exit 0) or infeasible with its reason (exit 3). One
/// of them, whose consistency equalities fix the torque, panicked before: its point
/// lies just outside a cone, which the ray of that cone now proves.
#[test]
fn the_sweeps_hard_grasps_are_answered_on_the_exact_cones() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/sweep");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    assert!(files.len() >= 9, "{files:?}");
    for f in &files {
        let out = run(&[
            "solve",
            f.to_str().unwrap(),
            "--cones",
            "exact",
            "--format",
            "json",
        ]);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout)
            .unwrap_or_else(|e| panic!("{f:?}: {e}: {}", String::from_utf8_lossy(&out.stderr)));
        match v["status"].as_str() {
            Some("optimal") => assert_eq!(out.status.code(), Some(0), "{f:?}"),
            Some("infeasible") => {
                assert_eq!(out.status.code(), Some(3), "{f:?}");
                assert!(v["reason"]["kind"].is_string(), "{f:?}");
            }
            other => panic!("{f:?}: {other:?} {}", v["reason"]),
        }
        if f.ends_with("sweep-992275-friction-1.json") {
            assert_eq!(v["status"], "infeasible");
            assert_eq!(v["method"], "closed_form");
            assert_eq!(v["reason"]["kind"], "dual_ray");
        }
    }
}

/// Rows of Jᵀ within the rank tolerance of another joint's on the same contact
/// (`fixtures/fuzz/joint-rows-below-the-rank-tolerance.json`, `fuzz_answers.py` seed
/// 228942: one joint's torque in a unit 5.9e8 times smaller): the model makes them
/// zero, and the report says so for each, with the ratio computed here from the file
/// (each row's largest entry on the third contact over the largest of any joint's
/// there; PCwF, so no mz). Their torques are 0; the paper example has no such row.
#[test]
fn joint_rows_the_model_makes_zero_are_named() {
    let path = fixture("fuzz/joint-rows-below-the-rank-tolerance.json");
    let p: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let jt: Vec<Vec<f64>> = serde_json::from_value(p["jacobian_transpose"].clone()).unwrap();
    let names: Vec<String> = serde_json::from_value(p["joint_names"].clone()).unwrap();
    let contact = 6..9;
    let top = |i: usize| contact.clone().map(|c| jt[i][c].abs()).fold(0.0, f64::max);
    let scale = (0..jt.len()).map(top).fold(0.0, f64::max);
    let largest = (0..jt.len()).find(|&i| top(i) == scale).unwrap();
    let out = run(&["solve", &path, "--format", "json"]);
    assert_eq!(out.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let warnings: Vec<String> = serde_json::from_value(v["warnings"].clone()).unwrap();
    let zeroed: Vec<&String> = warnings
        .iter()
        .filter(|w| w.contains("the model makes it zero"))
        .collect();
    let mut named = 0;
    for (j, row) in jt.iter().enumerate() {
        let ratio = top(j) / scale;
        let touches_only_it = row
            .iter()
            .enumerate()
            .all(|(c, v)| *v == 0.0 || contact.contains(&c));
        if j == largest || ratio == 0.0 || ratio > 1e-9 || !touches_only_it {
            continue;
        }
        let w = zeroed
            .iter()
            .find(|w| w.starts_with(&format!("{}:", names[j])))
            .unwrap_or_else(|| panic!("{} in {zeroed:?}", names[j]));
        assert!(
            w.contains(&format!("at most {ratio:.1e} of {}'s", names[largest])),
            "{w}"
        );
        assert_eq!(v["torque"][j].as_f64(), Some(0.0));
        named += 1;
    }
    assert_eq!((named, zeroed.len()), (2, 2), "{zeroed:?}");
    let paper = run(&["solve", &fixture("paper-example.json"), "--format", "json"]);
    assert!(!String::from_utf8_lossy(&paper.stderr).contains("makes it zero"));
}
