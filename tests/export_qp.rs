//! `export-qp` and `bench`: the exported QP is the one the native solver solved (its
//! answer satisfies the exported rows and a KKT certificate built from them alone), and
//! the timings are medians that exist.

use serde_json::Value;
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

fn mat(v: &Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

fn vec(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solves the small symmetric system `a x = b` by Gaussian elimination with pivoting.
fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
            .unwrap();
        a.swap(k, p);
        b.swap(k, p);
        for i in k + 1..n {
            let f = a[i][k] / a[k][k];
            for j in k..n {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        x[k] = (b[k] - (k + 1..n).map(|j| a[k][j] * x[j]).sum::<f64>()) / a[k][k];
    }
    x
}

#[test]
fn the_exported_qp_is_the_one_solved() {
    for name in [
        "paper-example.json",
        "hand3-pcwf.json",
        "hand5-pcwf.json",
        "hand4-sfcl.json",
        "hand4-sfce.json",
        "hand5-mixed.json",
        "hands/allegro-pinch.json",
        "hands/ability-tripod.json",
    ] {
        for sides in ["4", "8", "16"] {
            let out = run(&["export-qp", &fixture(name), "--sides", sides]);
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let v: Value = serde_json::from_slice(&out.stdout).unwrap();
            let (h, hw, c_eq, cw) = (mat(&v["H"]), mat(&v["Hw"]), mat(&v["C"]), mat(&v["Cw"]));
            let (c0, c, e, w) = (vec(&v["c0"]), vec(&v["c"]), vec(&v["e"]), vec(&v["wrench"]));
            let weights = vec(&v["weights"]);
            let m = v["joints"].as_u64().unwrap() as usize;
            assert_eq!(h.len(), c0.len());
            assert_eq!(h.len(), v["row_names"].as_array().unwrap().len());
            assert!(h.iter().chain(&c_eq).all(|r| r.len() == m));
            // The right-hand sides are the stated maps of the wrench.
            for i in 0..h.len() {
                let ci = c0[i] - dot(&hw[i], &w);
                assert!(
                    (ci - c[i]).abs() <= 1e-12 * (1.0 + ci.abs()),
                    "{name}: c[{i}]"
                );
            }
            for i in 0..c_eq.len() {
                assert!((e[i] + dot(&cw[i], &w)).abs() <= 1e-12 * (1.0 + e[i].abs()));
            }
            let s = &v["solution"];
            assert_eq!(s["status"], "optimal", "{name} N = {sides}");
            let tau = vec(&s["torque"]);
            let lambda = vec(&s["multipliers"]);
            let sigma: f64 = weights.iter().zip(&tau).map(|(w, t)| w * t * t).sum();
            assert!((sigma - s["objective"].as_f64().unwrap()).abs() <= 1e-12 * sigma.max(1e-300));
            let tmax = tau
                .iter()
                .fold(0.0_f64, |a, t| a.max(t.abs()))
                .max(f64::MIN_POSITIVE);
            // Primal feasibility and complementarity, to the rows' own scale.
            for i in 0..h.len() {
                let scale = h[i].iter().fold(0.0_f64, |a, x| a.max(x.abs())) * tmax + c[i].abs();
                let slack = dot(&h[i], &tau) - c[i];
                assert!(
                    slack >= -1e-9 * scale,
                    "{name}: row {i} violated by {slack}"
                );
                assert!(lambda[i] >= 0.0);
                assert!(
                    lambda[i] * slack.abs() <= 1e-8 * scale * (1.0 + lambda[i]),
                    "{name}: row {i}"
                );
            }
            for i in 0..c_eq.len() {
                let scale = c_eq[i].iter().fold(0.0_f64, |a, x| a.max(x.abs())) * tmax + e[i].abs();
                assert!(
                    (dot(&c_eq[i], &tau) - e[i]).abs() <= 1e-9 * scale,
                    "{name}: C row {i}"
                );
            }
            // Stationarity: 2 W τ − Hᵀ λ lies in the row space of C (ν by least squares).
            let r: Vec<f64> = (0..m)
                .map(|j| {
                    2.0 * weights[j] * tau[j]
                        - (0..h.len()).map(|i| h[i][j] * lambda[i]).sum::<f64>()
                })
                .collect();
            let p = c_eq.len();
            let nu = if p == 0 {
                Vec::new()
            } else {
                let cct: Vec<Vec<f64>> = (0..p)
                    .map(|a| (0..p).map(|b| dot(&c_eq[a], &c_eq[b])).collect())
                    .collect();
                solve(cct, (0..p).map(|a| dot(&c_eq[a], &r)).collect())
            };
            let grad = 2.0 * weights.iter().fold(0.0_f64, |a, w| a.max(*w)) * tmax;
            for j in 0..m {
                let rest = r[j] - (0..p).map(|a| c_eq[a][j] * nu[a]).sum::<f64>();
                assert!(
                    rest.abs() <= 1e-7 * grad.max(f64::MIN_POSITIVE),
                    "{name} N = {sides}: stationarity {j}: {rest}"
                );
            }
        }
    }
}

#[test]
fn export_refuses_what_is_not_a_linear_qp_in_tau() {
    let p = fixture("hand3-pcwf.json");
    let exact = run(&["export-qp", &p, "--cones", "exact"]);
    assert_eq!(exact.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&exact.stderr).contains("--cones"));
    let free = run(&["export-qp", &p, "--internal-forces", "free"]);
    assert_eq!(free.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&free.stderr).contains("--internal-forces"));
}

#[test]
fn bench_reports_medians() {
    let out = run(&[
        "bench",
        &fixture("hand3-pcwf.json"),
        "--repeats",
        "50",
        "--format",
        "json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["status"], "optimal");
    for key in [
        "build_us",
        "cold_us",
        "cold_raw_us",
        "warm_1pct_us",
        "cold_lazy_us",
        "warm_1pct_lazy_us",
    ] {
        let t = v[key].as_f64().unwrap();
        assert!(t.is_finite() && t > 0.0, "{key} = {t}");
    }
    let zero = run(&["bench", &fixture("hand3-pcwf.json"), "--repeats", "0"]);
    assert_eq!(zero.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&zero.stderr).contains("--repeats"));
}
