//! Geometry-form grasps build the same G and Jᵀ as the reference implementation.

use grasp_core::by_name::ByName;
use grasp_io::file::MatrixFile;
use grasp_io::geometry::GeometryFile;
use grasp_io::parse_problem;

fn cases() -> Vec<serde_json::Value> {
    cases_in("reference-cases.json")
}

fn cases_in(name: &str) -> Vec<serde_json::Value> {
    let path = format!("{}/../../tests/data/{name}", env!("CARGO_MANIFEST_DIR"));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["cases"].as_array().unwrap().clone()
}

/// Each case's geometry builds its G and Jᵀ to within `tol`; the number of cases.
fn geometry_builds_the_matrices(cases: &[serde_json::Value], tol: f64) -> usize {
    let mut n = 0;
    for case in cases.iter().filter(|c| c.get("geometry").is_some()) {
        let geo: GeometryFile = serde_json::from_value(case["geometry"].clone()).unwrap();
        let built = geo.into_problem().unwrap();
        let file: MatrixFile = serde_json::from_value(case["problem"].clone()).unwrap();
        let want = file.into_problem().unwrap();
        for (a, b) in [
            (&built.grasp_matrix, &want.grasp_matrix),
            (&built.jacobian_transpose, &want.jacobian_transpose),
        ] {
            assert_eq!(
                (a.nrows(), a.ncols()),
                (b.nrows(), b.ncols()),
                "{}",
                case["name"]
            );
            for (x, y) in a.as_slice().iter().zip(b.as_slice()) {
                assert!((x - y).abs() <= tol, "{}: {x} vs {y}", case["name"]);
            }
        }
        assert_eq!(built.contacts, want.contacts);
        n += 1;
    }
    n
}

#[test]
fn every_reference_geometry_builds_the_reference_matrices() {
    // The reference prints 12 decimals.
    assert_eq!(geometry_builds_the_matrices(&cases(), 1e-11), 40);
}

/// `scripts/oracle_cases.py` builds G and Jᵀ in numpy from the README's convention, at
/// full precision: every term is at most 1 (unit directions, and lever arms under
/// 0.2 m), so the two agree to a few roundings of 1, 4ε.
#[test]
fn every_oracle_geometry_builds_the_oracle_matrices() {
    let cases = cases_in("oracle-cases.json");
    assert_eq!(
        geometry_builds_the_matrices(&cases, 4.0 * f64::EPSILON),
        cases.len()
    );
}

#[test]
fn build_output_round_trips_through_the_parser() {
    let case = &cases()[5];
    let geo: GeometryFile = serde_json::from_value(case["geometry"].clone()).unwrap();
    let p = geo.into_problem().unwrap();
    let text = serde_json::to_string(&MatrixFile::from_problem(&p, None)).unwrap();
    let q = parse_problem(&text).unwrap();
    assert_eq!(p.grasp_matrix, q.grasp_matrix);
    assert_eq!(p.jacobian_transpose, q.jacobian_transpose);
    assert_eq!(p.wrench, q.wrench);
    assert_eq!(p.contacts, q.contacts);
}

#[test]
fn palm_contacts_proximal_links_and_prismatic_joints() {
    let text = r#"{
      "contacts": [
        {"position": [0.0, 0.0, 0.05], "normal": [0.0, 0.0, -1.0], "model": "pcwf", "mu": 0.5, "finger": 0, "link": 0},
        {"position": [0.0, 0.0, -0.05], "normal": [0.0, 0.0, 1.0], "model": "sfcl", "mu": 0.5, "mu_torsion": 0.01, "finger": null}
      ],
      "fingers": [{"name": "slider", "joints": [
        {"name": "rail", "origin": [0, 0, 0.2], "axis": [0, 0, 1], "type": "prismatic"},
        {"origin": [0, 0, 0.1], "axis": [1, 0, 0]}
      ]}],
      "wrench": [0, 0, 0, 0, 0, 0]
    }"#;
    let p = parse_problem(text).unwrap();
    assert_eq!(p.joints(), 2);
    let jt = &p.jacobian_transpose;
    // Contact 0 sits after joint 0 only: joint 1's row is zero for it.
    assert!(jt.row(1)[..3].iter().all(|&v| v == 0.0));
    // Prismatic joint along z: d · a; the normal is −z, so the fz column gets −1.
    assert!((jt[(0, 2)] + 1.0).abs() < 1e-15);
    // The palm contact is passive: no joint moves it.
    assert!(jt.row(0)[3..]
        .iter()
        .chain(&jt.row(1)[3..])
        .all(|&v| v == 0.0));
}

/// The names the problem files' enums are read by ([`ByName`]) are the ones they are
/// written as.
#[test]
fn enum_names_round_trip() {
    fn check<T>()
    where
        T: ByName + serde::Serialize + serde::de::DeserializeOwned + PartialEq + std::fmt::Debug,
    {
        assert_eq!(T::VARIANTS.len(), T::NAMES.len());
        for (v, n) in T::VARIANTS.iter().zip(T::NAMES) {
            let json = format!("\"{n}\"");
            assert_eq!(serde_json::to_string(v).unwrap(), json);
            assert_eq!(&serde_json::from_str::<T>(&json).unwrap(), v);
        }
    }
    check::<grasp_core::InternalForces>();
    check::<grasp_core::SfceSpacing>();
    check::<grasp_io::file::ModelName>();
    check::<grasp_io::geometry::JointType>();
    check::<grasp_io::hand::ContactFrame>();
}
