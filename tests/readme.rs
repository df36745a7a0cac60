//! Every JSON example in the README is a problem that loads and does what the README
//! says: it solves optimal from the command line, with the σ the README promises.

use std::process::Command;

fn readme() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap()
}

/// The fenced ```json blocks, in order.
fn json_blocks(text: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        match (&mut current, line.trim_start()) {
            (None, l) if l.starts_with("```json") => current = Some(String::new()),
            (Some(b), l) if l.starts_with("```") => {
                blocks.push(std::mem::take(b));
                current = None;
            }
            (Some(b), _) => {
                b.push_str(line);
                b.push('\n');
            }
            _ => {}
        }
    }
    blocks
}

fn solve(text: &str, name: &str) -> serde_json::Value {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("grasp-torque-readme-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The hand form names its URDF relative to the problem file, as a user's would be.
    std::fs::copy(
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/fixtures/urdf/allegro/allegro_hand_right.urdf"
        ),
        dir.join("allegro_hand_right.urdf"),
    )
    .unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_grasp-torque"))
        .args(["solve", path.to_str().unwrap(), "--format", "json"])
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "README block {name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn every_json_example_in_the_readme_solves_as_described() {
    let blocks = json_blocks(&readme());
    assert_eq!(
        blocks.len(),
        3,
        "the matrix-form, geometry-form and hand-form examples"
    );
    // The matrix form is the paper's example: σ = 72.5 at N = 4, as the README says.
    let v = solve(&blocks[0], "matrix.json");
    assert_eq!(v["status"], "optimal");
    assert!((v["objective"].as_f64().unwrap() - 72.5).abs() < 1e-9);
    // The geometry form is the bundled pinch, and it holds the object.
    let pinch = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fixtures/geometry/pinch.json"
    ))
    .unwrap();
    assert_eq!(blocks[1], pinch);
    let v = solve(&blocks[1], "geometry.json");
    assert_eq!(v["status"], "optimal");
    assert!(v["residuals"]["wrench"].as_f64().unwrap() < 1e-12);
    assert_eq!(v["joint_names"][0], "thumb_base");
    // The hand form is the bundled Allegro pinch: the same grasp, the same answer.
    let v = solve(&blocks[2], "hand.json");
    assert_eq!(v["status"], "optimal");
    let bundled = std::process::Command::new(env!("CARGO_BIN_EXE_grasp-torque"))
        .args([
            "solve",
            concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/fixtures/hands/allegro-pinch.json"
            ),
            "--format",
            "json",
        ])
        .output()
        .unwrap();
    let bundled: serde_json::Value = serde_json::from_slice(&bundled.stdout).unwrap();
    assert_eq!(v["objective"], bundled["objective"]);
    assert_eq!(v["joint_names"], bundled["joint_names"]);
    assert_eq!(v["hand"]["defaulted_joints"], serde_json::json!([]));
}
