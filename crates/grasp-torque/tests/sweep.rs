//! The linearisation sweep: σ(N) ≥ σ* always, σ(2N) ≤ σ(N) (the 2N-gon contains the
//! N-gon), and the gap shrinks toward zero; plus the command's CSV, SVG and JSON.
#![cfg(feature = "clarabel")]

use grasp_torque::sweep::{sweep, SweepConfig};
use grasp_torque::{load_problem, SfceSpacing, Status};

fn fixture(name: &str) -> String {
    format!(
        "{}/fixtures/{name}",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../..")
    )
}

fn run(
    name: &str,
    sides: Vec<usize>,
    latitudes: Vec<usize>,
    spacing: SfceSpacing,
) -> grasp_torque::sweep::Sweep {
    let p = load_problem(fixture(name)).unwrap();
    let config = SweepConfig {
        sides,
        latitudes,
        spacing: Some(spacing),
        repeats: 1,
        ..Default::default()
    };
    sweep(&p, &config, |_, _| {}).unwrap()
}

#[test]
fn sigma_is_above_the_exact_optimum_and_halving_never_hurts() {
    for name in [
        "paper-example.json",
        "hand3-pcwf.json",
        "hand5-pcwf.json",
        "hand4-sfcl.json",
        "hand4-sfce.json",
        "hand5-mixed.json",
        "table1/6-cup.json",
    ] {
        for spacing in [SfceSpacing::Paper, SfceSpacing::Uniform] {
            let s = run(
                name,
                vec![3, 4, 6, 8, 12, 16, 24, 32, 64],
                vec![1, 2, 4],
                spacing,
            );
            let exact = s.exact_objective.expect("exact optimum");
            for r in &s.rows {
                assert_eq!(r.status, Status::Optimal, "{name} N={}", r.sides);
                let o = r.objective.unwrap();
                assert!(
                    o >= exact * (1.0 - 1e-6),
                    "{name} N={} K={}: σ {o} < σ* {exact}",
                    r.sides,
                    r.latitudes
                );
            }
            for a in &s.rows {
                if let Some(b) = s
                    .rows
                    .iter()
                    .find(|b| b.sides == 2 * a.sides && b.latitudes == a.latitudes)
                {
                    let (sa, sb) = (a.objective.unwrap(), b.objective.unwrap());
                    assert!(
                        sb <= sa * (1.0 + 1e-9),
                        "{name}: σ({}) = {sb} > σ({}) = {sa}",
                        b.sides,
                        a.sides
                    );
                }
            }
        }
    }
}

#[test]
fn the_gap_shrinks_toward_zero() {
    // Point contacts and linear soft fingers: the gap is O(1/N²).
    for name in [
        "hand3-pcwf.json",
        "hand5-pcwf.json",
        "hand4-sfcl.json",
        "table1/3-plastic-bottle.json",
    ] {
        let s = run(name, vec![4, 16, 64, 256], vec![2], SfceSpacing::Paper);
        let gaps: Vec<f64> = s.rows.iter().map(|r| r.gap.unwrap()).collect();
        assert!(
            gaps.windows(2).all(|w| w[1] <= w[0] + 1e-9),
            "{name}: {gaps:?}"
        );
        assert!(gaps[3] < 1e-3, "{name}: gap at N = 256 is {}", gaps[3]);
    }
    // Elliptic soft fingers need latitudes too: refining N and K together (uniform
    // placement) drives the gap down.
    let s = run(
        "hand4-sfce.json",
        vec![4, 8, 16, 32],
        vec![1, 2, 4, 8],
        SfceSpacing::Uniform,
    );
    let diag: Vec<f64> = [(4, 1), (8, 2), (16, 4), (32, 8)]
        .iter()
        .map(|&(n, k)| {
            s.rows
                .iter()
                .find(|r| r.sides == n && r.latitudes == k)
                .unwrap()
                .gap
                .unwrap()
        })
        .collect();
    assert!(diag.windows(2).all(|w| w[1] < w[0]), "{diag:?}");
    assert!(diag[3] < 2e-3, "{diag:?}");
}
