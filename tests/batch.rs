//! `grasp-torque batch`: the same answers as `solve`, line by line, for every bundled
//! fixture (all three forms) and every reference case; per-line errors; exit codes.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grasp-torque"))
        .args(args)
        .output()
        .unwrap()
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("grasp-torque-batch-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Every bundled fixture and every reference case, as one-line JSON problems (hand
/// files with their robot's absolute path, so that the lines stand alone).
fn problems() -> Vec<Value> {
    let mut out = Vec::new();
    let mut files: Vec<PathBuf> = ["fixtures", "fixtures/geometry", "fixtures/hands"]
        .iter()
        .flat_map(|d| std::fs::read_dir(root().join(d)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    for f in files {
        let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&f).unwrap()).unwrap();
        if let Some(model) = v.pointer_mut("/hand/model") {
            let abs = f.parent().unwrap().join(model.as_str().unwrap());
            *model = Value::String(abs.canonicalize().unwrap().display().to_string());
        }
        out.push(v);
    }
    let cases: Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("tests/data/reference-cases.json")).unwrap(),
    )
    .unwrap();
    for c in cases["cases"].as_array().unwrap() {
        out.push(c.get("problem").unwrap_or(&c["geometry"]).clone());
    }
    out
}

fn lines(out: &Output) -> Vec<Value> {
    String::from_utf8(out.stdout.clone())
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn close(a: &Value, b: &Value, scale: f64) -> bool {
    (a.as_f64().unwrap() - b.as_f64().unwrap()).abs() <= 1e-9 * scale
}

#[test]
fn every_line_matches_solve() {
    let problems = problems();
    let dir = temp_dir("match");
    let input = dir.join("in.jsonl");
    let text: String = problems.iter().map(|p| format!("{p}\n")).collect();
    std::fs::write(&input, text).unwrap();
    for threads in ["1", "2"] {
        let out = run(&["batch", input.to_str().unwrap(), "--threads", threads]);
        let records = lines(&out);
        assert_eq!(records.len(), problems.len());
        for (i, (r, p)) in records.iter().zip(&problems).enumerate() {
            assert_eq!(r["line"], i + 1);
            assert_eq!(r["wrench"], 0);
            let file = dir.join(format!("{i}.json"));
            std::fs::write(&file, p.to_string()).unwrap();
            let solo = run(&["solve", file.to_str().unwrap(), "--format", "json"]);
            let s: Value = serde_json::from_slice(&solo.stdout).unwrap();
            assert_eq!(r["status"], s["status"], "line {}", i + 1);
            if s["status"] == "optimal" {
                let sigma = s["objective"].as_f64().unwrap();
                assert!(
                    close(&r["objective"], &s["objective"], sigma),
                    "line {}",
                    i + 1
                );
                // Torques to rounding of the largest one (σ = Σ w τ², weights ≤ 1e12).
                let t = s["torque"].as_array().unwrap();
                let tmax = t
                    .iter()
                    .map(|x| x.as_f64().unwrap().abs())
                    .fold(0.0, f64::max);
                for (a, b) in r["torque"].as_array().unwrap().iter().zip(t) {
                    assert!(close(a, b, tmax), "line {}: {a} vs {b}", i + 1);
                }
                // One name per torque: actuators with a transmission, else joints.
                let names = if r["actuator_names"].is_array() {
                    &r["actuator_names"]
                } else {
                    &r["joint_names"]
                };
                assert_eq!(names.as_array().map(Vec::len).unwrap_or(t.len()), t.len());
            } else {
                assert!(r["reason"]["message"].is_string());
            }
        }
    }
}

#[test]
fn several_wrenches_per_line_share_the_grasp() {
    let p: Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("fixtures/hand5-mixed.json")).unwrap(),
    )
    .unwrap();
    let w: Vec<f64> = serde_json::from_value(p["wrench"].clone()).unwrap();
    let wrenches: Vec<Vec<f64>> = (0..6)
        .map(|k| {
            let mut v = w.clone();
            v[k % 3] += 0.2 * if k < 3 { 1.0 } else { -1.0 };
            v
        })
        .collect();
    let mut line = p.clone();
    line["wrenches"] = serde_json::json!(wrenches);
    let dir = temp_dir("wrenches");
    let input = dir.join("in.jsonl");
    std::fs::write(&input, format!("{line}\n")).unwrap();
    let records = lines(&run(&["batch", input.to_str().unwrap()]));
    assert_eq!(records.len(), 6);
    for (k, r) in records.iter().enumerate() {
        assert_eq!(
            (r["line"].as_u64(), r["wrench"].as_u64()),
            (Some(1), Some(k as u64))
        );
        let mut single = p.clone();
        single["wrench"] = serde_json::json!(wrenches[k]);
        let file = dir.join(format!("{k}.json"));
        std::fs::write(&file, single.to_string()).unwrap();
        let s: Value = serde_json::from_slice(
            &run(&["solve", file.to_str().unwrap(), "--format", "json"]).stdout,
        )
        .unwrap();
        assert_eq!(r["status"], s["status"]);
        if s["status"] == "optimal" {
            assert!(close(
                &r["objective"],
                &s["objective"],
                s["objective"].as_f64().unwrap()
            ));
        }
    }
}

/// A hand line's `object` weighs on each of its `wrenches`, as it does on `wrench`.
#[test]
fn a_hand_lines_object_weighs_on_each_wrench() {
    let path = root().join("fixtures/hands/allegro-weighed.json");
    let mut p: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let model = path
        .parent()
        .unwrap()
        .join(p["hand"]["model"].as_str().unwrap());
    p["hand"]["model"] = Value::String(model.canonicalize().unwrap().display().to_string());
    let wrenches = serde_json::json!([
        [0, 0, 0, 0, 0, 0],
        [0.1, 0, 0, 0, 0, 0],
        [0, -0.2, 0.1, 0, 0, 0.001]
    ]);
    let mut line = p.clone();
    line["wrenches"] = wrenches.clone();
    let dir = temp_dir("object");
    let input = dir.join("in.jsonl");
    std::fs::write(&input, format!("{line}\n")).unwrap();
    let records = lines(&run(&["batch", input.to_str().unwrap()]));
    assert_eq!(records.len(), 3);
    let mut objectives = Vec::new();
    for (k, r) in records.iter().enumerate() {
        let mut single = p.clone();
        single["wrench"] = wrenches[k].clone();
        let file = dir.join(format!("{k}.json"));
        std::fs::write(&file, single.to_string()).unwrap();
        let s: Value = serde_json::from_slice(
            &run(&["solve", file.to_str().unwrap(), "--format", "json"]).stdout,
        )
        .unwrap();
        assert_eq!(
            (&r["status"], &s["status"]),
            (&"optimal".into(), &"optimal".into())
        );
        let sigma = s["objective"].as_f64().unwrap();
        assert!(close(&r["objective"], &s["objective"], sigma), "wrench {k}");
        objectives.push(sigma);
    }
    // The file's own answer (no `wrench`: the weight alone) is the first; the others
    // carry more.
    let s: Value =
        serde_json::from_slice(&run(&["solve", path.to_str().unwrap(), "--format", "json"]).stdout)
            .unwrap();
    assert!(close(
        &s["objective"],
        &records[0]["objective"],
        objectives[0]
    ));
    assert!(objectives[1] != objectives[0] && objectives[2] != objectives[0]);
}

#[test]
fn an_invalid_wrench_is_a_record_and_the_lines_other_wrenches_are_solved() {
    let p: Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("fixtures/hand5-mixed.json")).unwrap(),
    )
    .unwrap();
    let w: Vec<f64> = serde_json::from_value(p["wrench"].clone()).unwrap();
    let nudged: Vec<f64> = w.iter().map(|v| v * 1.1).collect();
    let bad = [
        serde_json::json!([0, 0, 1e300, 0, 0, 0]),
        serde_json::json!([1, 2, 3]),
        serde_json::json!("x"),
    ];
    let mut mixed = p.clone();
    mixed["wrenches"] = serde_json::json!([w, bad[0], nudged, bad[1], bad[2], w]);
    let mut good = p.clone();
    good["wrenches"] = serde_json::json!([w, nudged, w]);
    let mut none_valid = p.clone();
    none_valid["wrenches"] = serde_json::json!(bad);
    // A line whose wrenches are all invalid still has its problem checked.
    let mut bad_problem = none_valid.clone();
    bad_problem["contacts"][0]["mu"] = serde_json::json!(-1);
    let dir = temp_dir("bad-wrench");
    let input = dir.join("in.jsonl");
    std::fs::write(
        &input,
        format!("{mixed}\n{good}\n{none_valid}\n{bad_problem}\n"),
    )
    .unwrap();
    let out = run(&["batch", input.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "an invalid wrench: exit 2");
    let r = lines(&out);
    let got: Vec<(u64, Option<u64>, &str)> = r
        .iter()
        .map(|r| {
            (
                r["line"].as_u64().unwrap(),
                r["wrench"].as_u64(),
                r["status"].as_str().unwrap(),
            )
        })
        .collect();
    let expected: Vec<(u64, Option<u64>, &str)> = vec![
        (1, Some(0), "optimal"),
        (1, Some(1), "invalid"),
        (1, Some(2), "optimal"),
        (1, Some(3), "invalid"),
        (1, Some(4), "invalid"),
        (1, Some(5), "optimal"),
        (2, Some(0), "optimal"),
        (2, Some(1), "optimal"),
        (2, Some(2), "optimal"),
        (3, Some(0), "invalid"),
        (3, Some(1), "invalid"),
        (3, Some(2), "invalid"),
        (4, None, "invalid"),
    ];
    assert_eq!(got, expected);
    // Each message names its wrench; the valid ones get the answers of the line
    // without the invalid ones, in the same order.
    for (i, k) in [(1, 1), (3, 3), (4, 4), (9, 0), (10, 1), (11, 2)] {
        let e = r[i]["error"].as_str().unwrap();
        assert!(e.starts_with(&format!("wrenches[{k}]: expected")), "{e}");
    }
    for (i, j) in [(0, 6), (2, 7), (5, 8)] {
        assert_eq!(r[i]["objective"], r[j]["objective"], "{} vs {}", r[i], r[j]);
        assert_eq!(r[i]["torque"], r[j]["torque"]);
    }
    assert!(r[12]["error"].as_str().unwrap().contains("mu"), "{}", r[12]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("13 results: 7 invalid"), "{stderr}");
}

#[test]
fn a_malformed_line_is_a_record_and_the_batch_goes_on() {
    let good = std::fs::read_to_string(root().join("fixtures/hand3-pcwf.json"))
        .unwrap()
        .replace('\n', " ");
    let mut bad_wrenches: Value = serde_json::from_str(&good).unwrap();
    bad_wrenches["wrenches"] = serde_json::json!([[1, 2, 3]]);
    let input =
        format!("{good}\nnot json\n\n{{\"grasp_matrix\": [[1]]}}\n{bad_wrenches}\n{good}\n");
    let mut child = Command::new(env!("CARGO_BIN_EXE_grasp-torque"))
        .args(["batch", "-", "--format", "jsonl"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    use std::io::Write;
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(2), "an invalid line: exit 2");
    let r = lines(&out);
    let got: Vec<(u64, &str)> = r
        .iter()
        .map(|r| (r["line"].as_u64().unwrap(), r["status"].as_str().unwrap()))
        .collect();
    assert_eq!(
        got,
        [
            (1, "optimal"),
            (2, "invalid"),
            (4, "invalid"),
            (5, "invalid"),
            (6, "optimal")
        ]
    );
    assert!(
        r[1]["error"].as_str().unwrap().contains("line 1, column"),
        "{}",
        r[1]
    );
    assert!(
        r[2]["error"]
            .as_str()
            .unwrap()
            .contains("jacobian_transpose"),
        "{}",
        r[2]
    );
    assert!(
        r[3]["error"].as_str().unwrap().contains("wrenches[0]"),
        "{}",
        r[3]
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("3 invalid"), "{stderr}");
}

#[test]
fn exit_codes_csv_and_flags() {
    let dir = temp_dir("codes");
    let mut p: Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("fixtures/hand3-pcwf.json")).unwrap(),
    )
    .unwrap();
    let ok = p.to_string();
    p["torque_limits"] = serde_json::json!(vec![1e-6; 9]);
    let infeasible = p.to_string();
    let input = dir.join("in.jsonl");
    std::fs::write(&input, format!("{ok}\n{infeasible}\n")).unwrap();
    let out = run(&["batch", input.to_str().unwrap(), "--format", "csv"]);
    assert_eq!(out.status.code(), Some(3), "an infeasible grasp: exit 3");
    let text = String::from_utf8(out.stdout).unwrap();
    let rows: Vec<&str> = text.lines().collect();
    assert_eq!(rows.len(), 3);
    assert!(rows[0].starts_with("line,wrench,status,objective"));
    assert!(rows[1].starts_with("1,0,optimal,"));
    assert!(rows[2].starts_with("2,0,infeasible,"));
    let torque = rows[1].split(',').nth(9).unwrap();
    assert_eq!(torque.split(' ').count(), 9);

    std::fs::write(&input, format!("{ok}\n")).unwrap();
    assert_eq!(
        run(&["batch", input.to_str().unwrap()]).status.code(),
        Some(0)
    );
    let zero = run(&["batch", input.to_str().unwrap(), "--threads", "0"]);
    assert_eq!(zero.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&zero.stderr).contains("--threads"));
    let missing = run(&["batch", dir.join("nope.jsonl").to_str().unwrap()]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("nope.jsonl"));
}

#[test]
fn hostile_lines_are_records_never_crashes() {
    let good = std::fs::read_to_string(root().join("fixtures/hand3-pcwf.json"))
        .unwrap()
        .replace('\n', " ");
    let mut huge_wrench: Value = serde_json::from_str(&good).unwrap();
    huge_wrench["wrenches"] = serde_json::json!([[0, 0, 1e300, 0, 0, 0]]);
    let mut missing_robot: Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("fixtures/hands/allegro-pinch.json")).unwrap(),
    )
    .unwrap();
    missing_robot["hand"]["model"] = Value::String("/nonexistent/hand.urdf".into());
    let mut input: Vec<u8> = Vec::new();
    for line in [
        good.as_bytes().to_vec(),
        b"\xff\xfe{not utf-8}".to_vec(),
        "[".repeat(100_000).into_bytes(),
        b"[1, 2, 3]".to_vec(),
        huge_wrench.to_string().into_bytes(),
        missing_robot.to_string().into_bytes(),
        b"{\"grasp_matrix\": [[1e400]]}".to_vec(),
        good.as_bytes().to_vec(),
    ] {
        input.extend(line);
        input.push(b'\n');
    }
    let dir = temp_dir("hostile");
    let path = dir.join("in.jsonl");
    std::fs::write(&path, input).unwrap();
    let out = run(&["batch", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let r = lines(&out);
    let status: Vec<&str> = r.iter().map(|r| r["status"].as_str().unwrap()).collect();
    assert_eq!(
        status,
        ["optimal", "invalid", "invalid", "invalid", "invalid", "invalid", "invalid", "optimal"]
    );
    let errors: Vec<&str> = r[1..7]
        .iter()
        .map(|r| r["error"].as_str().unwrap())
        .collect();
    assert!(errors[0].contains("UTF-8"), "{}", errors[0]);
    assert!(errors[2].contains("JSON object"), "{}", errors[2]);
    assert!(errors[3].contains("wrenches[0]"), "{}", errors[3]);
    assert!(errors[4].contains("hand.model"), "{}", errors[4]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
}

/// A line past the 64 MiB limit is a record and the batch goes on after it; an input
/// with no line end within 1 GiB (`/dev/zero`) ends the batch at once, not after
/// reading forever.
#[test]
fn an_over_long_line_is_a_record_and_an_endless_one_ends_the_batch() {
    let good = std::fs::read_to_string(root().join("fixtures/paper-example.json"))
        .unwrap()
        .replace('\n', " ");
    let path = temp_dir("long").join("in.jsonl");
    let mut input = format!("{good}\n").into_bytes();
    input.resize(input.len() + (65 << 20), b' ');
    input.extend(format!("\n{good}\n").into_bytes());
    std::fs::write(&path, input).unwrap();
    let out = run(&["batch", path.to_str().unwrap()]);
    std::fs::remove_file(&path).unwrap();
    assert_eq!(out.status.code(), Some(2));
    let r = lines(&out);
    let status: Vec<&str> = r.iter().map(|r| r["status"].as_str().unwrap()).collect();
    assert_eq!(status, ["optimal", "invalid", "optimal"]);
    assert_eq!(r[2]["line"], 3);
    let error = r[1]["error"].as_str().unwrap();
    assert!(
        error.contains("at most 67108864 bytes, got a longer one"),
        "{error}"
    );

    if Path::new("/dev/zero").exists() {
        let start = std::time::Instant::now();
        let out = run(&["batch", "/dev/zero"]);
        assert_eq!(out.status.code(), Some(2));
        let r = lines(&out);
        assert_eq!(r.len(), 1);
        let error = r[0]["error"].as_str().unwrap();
        assert!(error.contains("read no further"), "{error}");
        assert!(start.elapsed().as_secs() < 60);
    }
}
