//! Hostile and extreme input (issue 14): every class that broke the contract before
//! gets a named error with exit 2, an honest status, or a correct answer; never a
//! panic, a hang, a NaN or a false `optimal`.

use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

fn fixture(name: &str) -> String {
    format!("{}/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn paper() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(fixture("paper-example.json")).unwrap()).unwrap()
}

fn temp_file(name: &str, text: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("grasp-torque-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grasp-torque"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn solve_json(v: &serde_json::Value, name: &str, extra: &[&str]) -> Output {
    let f = temp_file(name, &v.to_string());
    let mut args = vec!["solve", f.to_str().unwrap()];
    args.extend_from_slice(extra);
    run(&args)
}

/// Exit 2, the field and the expectation named, nothing on stdout, no panic.
fn assert_refused(out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    for n in needles {
        assert!(err.contains(n), "expected `{n}` in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    assert!(out.stdout.is_empty());
}

/// No panic, no NaN or inf on stdout, and `optimal` only with small residuals.
fn assert_honest(out: &Output) {
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        !text.contains("NaN") && !text.contains(" inf") && !text.contains("-inf"),
        "{text}"
    );
    if let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) {
        if v["status"] == "optimal" {
            // Each residual within its check's bound, and the bound itself small.
            let d = &v["diagnostics"];
            assert!(d["check_tolerance"].as_f64().unwrap() <= 1e-6, "{text}");
            assert!(d["wrench_check"].as_f64().unwrap() <= 1.0, "{text}");
            assert!(d["torque_check"].as_f64().unwrap() <= 1.0, "{text}");
        }
    }
}

#[test]
fn trailing_bytes_after_the_object_are_refused() {
    let text = format!("{} garbage", paper());
    let f = temp_file("trailing.json", &text);
    assert_refused(
        &run(&["solve", f.to_str().unwrap()]),
        &["after the JSON value"],
    );
}

/// Nesting past serde_json's limit names where it starts (the first three segments of
/// its path), not a hundred-odd `[0]`s.
#[test]
fn deep_nesting_names_where_it_starts() {
    for (name, text, field) in [
        ("deep-top.json", "[".repeat(300), "[0][0][0]…:"),
        (
            "deep-matrix.json",
            format!("{{\"grasp_matrix\": {}", "[".repeat(300)),
            "grasp_matrix[0][0]…:",
        ),
        (
            "deep-contact.json",
            format!("{{\"contacts\": [{{\"a\": {}", "{\"b\": ".repeat(300)),
            "contacts[0].a…:",
        ),
    ] {
        let f = temp_file(name, &text);
        let out = run(&["solve", f.to_str().unwrap()]);
        assert_refused(&out, &[field, "nested at most 128 deep"]);
        assert!(String::from_utf8_lossy(&out.stderr).len() < 300);
    }
}

/// A byte order mark, as Windows editors write, is not part of the JSON: the file
/// solves, and an error's column is the one the editor shows.
#[test]
fn a_byte_order_mark_is_skipped() {
    let f = temp_file("bom.json", &format!("\u{feff}{}", paper()));
    let out = run(&["solve", f.to_str().unwrap(), "--format", "json"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let f = temp_file("bom-bad.json", "\u{feff}{\"wrench\": x}");
    assert_refused(
        &run(&["solve", f.to_str().unwrap()]),
        &["line 1, column 12"],
    );
    let mut batch = Command::new(env!("CARGO_BIN_EXE_grasp-torque"))
        .args(["batch", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    use std::io::Write;
    let line = format!("\u{feff}{}\n", paper());
    batch
        .stdin
        .take()
        .unwrap()
        .write_all(line.as_bytes())
        .unwrap();
    let out = batch.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
}

/// JSON readers keep the last of a repeated key; a joint position given twice is
/// refused rather than half-read.
#[test]
fn a_joint_position_given_twice_is_refused() {
    let text = std::fs::read_to_string(fixture("hands/allegro-pinch.json")).unwrap();
    let text = text
        .replace(
            "\"../urdf/allegro/allegro_hand_right.urdf",
            &format!("\"{}", fixture("urdf/allegro/allegro_hand_right.urdf")),
        )
        .replace(
            "\"joint_0.0\": -0.0718,",
            "\"joint_0.0\": -0.0718, \"joint_0.0\": 0.3,",
        );
    let f = temp_file("twice.json", &text);
    assert_refused(
        &run(&["solve", f.to_str().unwrap()]),
        &["hand.joint_positions: `joint_0.0` is given twice"],
    );
}

#[test]
fn out_of_domain_numbers_name_field_value_and_range() {
    type Edit = Box<dyn Fn(&mut serde_json::Value)>;
    let cases: Vec<(Edit, &[&str])> = vec![
        (
            Box::new(|p| p["contacts"][0]["mu"] = 5e-324.into()),
            &["contacts[0].mu", "1e-3"],
        ),
        (
            Box::new(|p| p["contacts"][1]["mu_torsion"] = 1e-300.into()),
            &["contacts[1].mu_torsion", "1e-9"],
        ),
        (
            Box::new(|p| p["wrench"][2] = 1e308.into()),
            &["wrench[2]", "1e12"],
        ),
        (
            Box::new(|p| p["min_normal_force"] = 1e308.into()),
            &["min_normal_force[0]", "1e12"],
        ),
        (
            Box::new(|p| p["min_normal_force"] = 1e200.into()),
            &["min_normal_force[0]"],
        ),
        (
            Box::new(|p| p["grasp_matrix"][3][1] = 1e308.into()),
            &["grasp_matrix[3][1]", "1e12"],
        ),
        (
            Box::new(|p| p["torque_weights"] = serde_json::json!([1, 1e18, 1, 1])),
            &["torque_weights[1]", "1e12"],
        ),
        (
            Box::new(|p| p["torque_weights"] = serde_json::json!([1, 1e-19, 1, 1])),
            &["torque_weights[1]"],
        ),
        (
            Box::new(|p| p["torque_weights"] = serde_json::json!([5e-324, 1, 1, 1])),
            &["torque_weights[0]"],
        ),
        (
            Box::new(|p| p["torque_weights"] = serde_json::json!([1, 1e9, 1, 1])),
            &["torque_weights[1]", "ratio"],
        ),
        (
            Box::new(|p| p["torque_limits"] = serde_json::json!([1e300, null, 1, 1])),
            &["torque_limits[0]"],
        ),
        // Subnormal numbers: too few digits for any answer to pass its checks.
        (
            Box::new(|p| p["grasp_matrix"][0][0] = 1e-310.into()),
            &["grasp_matrix[0][0]", "subnormal", "1e-310"],
        ),
        (
            Box::new(|p| p["jacobian_transpose"][1][1] = (-4e-320).into()),
            &["jacobian_transpose[1][1]", "subnormal"],
        ),
        (
            Box::new(|p| p["wrench"][5] = 5e-324.into()),
            &["wrench[5]", "subnormal"],
        ),
        (
            Box::new(|p| p["torque_limits"] = serde_json::json!([1e-310, null, 1, 1])),
            &["torque_limits[0]", "subnormal"],
        ),
        (
            Box::new(|p| p["min_normal_force"] = 1e-315.into()),
            &["min_normal_force[0]", "subnormal"],
        ),
    ];
    for (i, (edit, needles)) in cases.iter().enumerate() {
        let mut p = paper();
        edit(&mut p);
        assert_refused(&solve_json(&p, &format!("domain{i}.json"), &[]), needles);
    }
}

#[test]
fn geometry_out_of_domain_is_refused() {
    let mut g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("geometry/pinch.json")).unwrap())
            .unwrap();
    g["fingers"][0]["joints"][0]["origin"] = serde_json::json!([1e308, 0, 0]);
    assert_refused(&solve_json(&g, "origin.json", &[]), &["origin", "1e12"]);
    g["fingers"][0]["joints"][0]["origin"] = serde_json::json!([0.09, 1e-320, -0.04]);
    assert_refused(
        &solve_json(&g, "origin.json", &[]),
        &["origin", "subnormal"],
    );
}

#[test]
fn sizes_are_limited_before_allocating() {
    // 257 joints.
    let mut p = paper();
    let row = p["jacobian_transpose"][0].clone();
    p["jacobian_transpose"] = serde_json::Value::Array(vec![row; 257]);
    assert_refused(
        &solve_json(&p, "joints.json", &[]),
        &["jacobian_transpose", "256"],
    );
    // 10 000 contacts in geometry form: refused before G and Jᵀ are built.
    let mut g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("geometry/pinch.json")).unwrap())
            .unwrap();
    let c = g["contacts"][0].clone();
    g["contacts"] = serde_json::Value::Array(vec![c; 10_000]);
    assert_refused(&solve_json(&g, "contacts.json", &[]), &["contacts", "256"]);
}

#[test]
fn an_endless_input_is_refused_quickly() {
    let start = std::time::Instant::now();
    let out = run(&["solve", "/dev/zero"]);
    assert_refused(&out, &["/dev/zero", "expected at most 67108864 bytes"]);
    // A robot description is read with the same limit, and the message names it.
    let out = run(&["hand", "/dev/zero"]);
    assert_refused(&out, &["/dev/zero", "expected at most 67108864 bytes"]);
    let mut p: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(fixture("hands/allegro-pinch.json")).unwrap(),
    )
    .unwrap();
    p["hand"]["model"] = "/dev/zero".into();
    assert_refused(
        &solve_json(&p, "endless-model.json", &[]),
        &["hand.model", "/dev/zero", "expected at most 67108864 bytes"],
    );
    assert!(start.elapsed().as_secs() < 30);
}

#[test]
fn a_robot_description_that_is_not_text_names_its_file() {
    let f = temp_file("latin1.urdf", "");
    std::fs::write(&f, b"<robot name=\"h\xe9\"/>").unwrap();
    let path = f.to_str().unwrap();
    assert_refused(
        &run(&["hand", path]),
        &[path, "expected UTF-8 text, got invalid UTF-8 at byte 14"],
    );
}

/// A timing count is kept per solve for the median: one that no memory holds is
/// refused (`sweep --repeats 99999999999` aborted allocating 800 GB).
#[test]
fn a_timing_count_beyond_memory_is_refused() {
    let paper = fixture("paper-example.json");
    for cmd in ["sweep", "bench"] {
        let out = run(&[cmd, &paper, "--repeats", "99999999999"]);
        assert_refused(
            &out,
            &["--repeats: expected 1 to 10000000, got 99999999999"],
        );
    }
}

#[test]
fn a_full_disk_is_an_error_not_a_panic() {
    if !std::path::Path::new("/dev/full").exists() {
        return;
    }
    for args in [
        vec!["solve", "PAPER"],
        vec!["build", "PAPER"],
        vec!["compare", "PAPER"],
        vec!["sweep", "PAPER", "--sides", "4,8", "--repeats", "1"],
    ] {
        let paper = fixture("paper-example.json");
        let args: Vec<&str> = args
            .iter()
            .map(|a| if *a == "PAPER" { paper.as_str() } else { a })
            .collect();
        let out = Command::new(env!("CARGO_BIN_EXE_grasp-torque"))
            .args(&args)
            .stdout(std::fs::File::create("/dev/full").unwrap())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains("could not write to standard output"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn extreme_but_legal_inputs_are_answered_honestly() {
    // Every backend and cone kind compiled in.
    let mut exacts: Vec<&[&str]> = vec![&[]];
    if cfg!(feature = "clarabel") {
        exacts.push(&["--backend", "clarabel"]);
        exacts.push(&["--cones", "exact"]);
    }
    for scale in [1e-9, 1e-5, 1e4, 1e6, 1e9] {
        for &extra in &exacts {
            let mut p = paper();
            for w in p["wrench"].as_array_mut().unwrap() {
                *w = (w.as_f64().unwrap() * scale).into();
            }
            let mut args = vec!["--format", "json"];
            args.extend_from_slice(extra);
            let out = solve_json(&p, "scaled.json", &args);
            assert_honest(&out);
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            assert_eq!(v["status"], "optimal", "scale {scale} {extra:?}");
        }
    }
    // A zero wrench: σ = 0 exactly, everywhere.
    for &extra in &exacts {
        let mut p = paper();
        p["wrench"] = serde_json::json!([0, 0, 0, 0, 0, 0]);
        let mut args = vec!["--format", "json"];
        args.extend_from_slice(extra);
        let out = solve_json(&p, "zero.json", &args);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["objective"].as_f64(), Some(0.0), "{extra:?}");
    }
    // Friction at the ends of the domain.
    for mu in [1e-3, 1e3] {
        for &extra in &exacts {
            let mut p = paper();
            p["contacts"][0]["mu"] = mu.into();
            p["contacts"][1]["mu"] = mu.into();
            let mut args = vec!["--format", "json"];
            args.extend_from_slice(extra);
            assert_honest(&solve_json(&p, "mu.json", &args));
        }
    }
    // A warm start far from the optimum makes a solve slower, never wrong.
    let p = paper();
    let out = solve_json(
        &p,
        "warm.json",
        &[
            "--initial-torque",
            "1e100,1e100,-1e100,1e100",
            "--format",
            "json",
        ],
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((v["objective"].as_f64().unwrap() - 72.5).abs() < 1e-9);
}
