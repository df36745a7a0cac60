//! The native linearised solver against DAQP on the same QPs, per wrench, in one
//! interleaved run (`bash scripts/fetch_daqp.sh && cargo bench -p grasp-daqp`).
//!
//! The grasps: the bundled fixtures and the 41 reference cases of
//! `shared/reference/cases.json` (`tests/data/reference-cases.json`, with the reference
//! conventions), 50 grasps. Each at N = 4, 8 and 16 gives the QP the native solver sees
//! (`min Σ w_j τ_j²` s.t. `H τ ≥ c(w)`, `C τ = e(w)`; `grasp-torque export-qp`), posed to
//! DAQP as `min ½ τᵀ(2W)τ` s.t. `c(w) ≤ H τ`, `C τ = e(w)`. For each of a set of
//! wrenches near the fixture's, interleaved call by call:
//! - native cold: the backend alone from a cold start (it forms c(w) itself);
//! - native warm: a control loop on a solver of its own, alternating between the wrench
//!   and the one 1 % away, each solve warm-started from the other's answer: the hot
//!   start once the key set has settled (its affine maps; docs/solver.md, Step 1);
//! - DAQP per wrench: c(w) and e(w) (the same Rust code), the bounds update, a cleared
//!   working set and the solve, DAQP set up once per grasp;
//! - DAQP `solve_time`: DAQP's own clock around its solve alone.
//!
//! Conventions of qpbenchmark: the shifted geometric mean (shift 10 µs) over the
//! problems, the success rate, and agreement of the objective to 1e-9 relative.
//! Environment: `GT_BENCH_REPEATS` (default 200) timed calls per wrench and solver,
//! `GT_BENCH_WRENCHES` (default 10) wrenches per QP.

use grasp_daqp::{Daqp, INFINITY};
use grasp_torque::{
    Backend, GraspProblem, GraspSolver, Solution, SolverConfig, Status, TorqueSolver, WarmStart,
};
use std::hint::black_box;
use std::time::Instant;

const FIXTURES: [(&str, &str); 9] = [
    ("paper", "fixtures/paper-example.json"),
    ("PCwF", "fixtures/hand3-pcwf.json"),
    ("PCwF", "fixtures/hand5-pcwf.json"),
    ("SFCl", "fixtures/hand4-sfcl.json"),
    ("SFCe", "fixtures/hand4-sfce.json"),
    ("mixed", "fixtures/hand5-mixed.json"),
    ("hand", "fixtures/hands/allegro-pinch.json"),
    ("hand", "fixtures/hands/ability-tripod.json"),
    ("hand", "fixtures/hands/shadow-tripod.json"),
];

fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// One control tick, timed in µs: `w` from the answer `from`, into `to`.
fn tick(solver: &mut dyn TorqueSolver, w: &[f64; 6], from: &Solution, to: &mut Solution) -> f64 {
    let warm = WarmStart {
        torque: Some(&from.torque),
        active_set: from.active_set.as_deref(),
    };
    let s = Instant::now();
    solver.solve_raw(black_box(w), &warm, to);
    s.elapsed().as_secs_f64() * 1e6
}

/// Shifted geometric mean, shift 10 µs.
fn sgm(t: &[f64]) -> f64 {
    (t.iter().map(|v| (v + 10.0).ln()).sum::<f64>() / t.len() as f64).exp() - 10.0
}

fn env(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// A deterministic sequence in [−1, 1].
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

struct Row {
    family: String,
    name: String,
    sides: usize,
    rows: usize,
    cold: f64,
    warm: f64,
    daqp: f64,
    daqp_solve: f64,
    solved: usize,
    tried: usize,
    worst_rel: f64,
}

fn main() {
    if !Daqp::available() {
        println!("DAQP is not compiled in: run `bash scripts/fetch_daqp.sh`, then `cargo bench -p grasp-daqp`.");
        return;
    }
    let repeats = env("GT_BENCH_REPEATS", 200).max(1);
    let wrenches = env("GT_BENCH_WRENCHES", 10).max(1);
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../");
    let mut grasps: Vec<(String, String, GraspProblem)> = FIXTURES
        .iter()
        .map(|(family, file)| {
            let name = file.rsplit('/').next().unwrap().trim_end_matches(".json");
            let p = grasp_torque::load(format!("{root}{file}")).unwrap().problem;
            (family.to_string(), name.to_string(), p)
        })
        .collect();
    for case in grasp_testkit::reference_cases() {
        let name = case["name"].as_str().unwrap().to_string();
        // h3x4-sfcl-9: the contact model names the family.
        let family = name.split('-').nth(1).unwrap_or("reference").to_string();
        grasps.push((
            format!("ref {family}"),
            name,
            grasp_testkit::reference_problem(&case["problem"]),
        ));
    }
    let mut out = Vec::new();
    for (index, (family, name, problem)) in grasps.into_iter().enumerate() {
        for sides in [4, 8, 16] {
            let mut p = problem.clone();
            p.linearization.sides = sides;
            let config = SolverConfig {
                backend: Some(Backend::ActiveSet),
                ..Default::default()
            };
            let solver = GraspSolver::new(&p, &config).unwrap();
            let qp = solver.problem().clone();
            let mut native = config.build(qp.clone()).unwrap();
            let mut looped = config.build(qp.clone()).unwrap();
            let ld = qp.least_distance();
            // σ = Σ w_j τ_j² of a torque.
            let sigma =
                |t: &[f64]| -> f64 { t.iter().zip(ld.weights).map(|(t, wj)| wj * t * t).sum() };
            let (n, r, e) = (qp.joints(), qp.inequality_rows(), ld.eq.nrows());
            let mut h = vec![0.0; n * n];
            for j in 0..n {
                h[j * n + j] = 2.0 * ld.weights[j];
            }
            let mut a = Vec::with_capacity((e + r) * n);
            for i in 0..e {
                a.extend_from_slice(ld.eq.row(i));
            }
            for i in 0..r {
                a.extend_from_slice(qp.h().row(i));
            }
            let equality: Vec<bool> = (0..e + r).map(|i| i < e).collect();
            let mut upper = vec![INFINITY; e + r];
            let lower = vec![0.0; e + r];
            upper[..e].iter_mut().for_each(|v| *v = 0.0);
            let mut daqp = Daqp::new(n, h, a, lower, upper, &equality, 1e-9).unwrap();
            let (mut c, mut ev) = (vec![0.0; r], vec![0.0; e]);
            let mut rng = Lcg(0x9e3779b97f4a7c15 ^ (sides as u64) ^ ((index as u64) << 8));
            let (mut cold_t, mut warm_t, mut daqp_t, mut daqp_s) = (vec![], vec![], vec![], vec![]);
            let (mut tried, mut solved, mut worst_rel) = (0, 0, 0.0f64);
            let cold = WarmStart::default();
            for k in 0..wrenches {
                let w: [f64; 6] = std::array::from_fn(|i| {
                    p.wrench[i] * if k == 0 { 1.0 } else { 1.0 + 0.05 * rng.next() }
                });
                let near: [f64; 6] = std::array::from_fn(|i| w[i] * 1.01);
                let mut sol = Solution::default();
                native.solve_raw(&w, &cold, &mut sol);
                let mut prev = Solution::default();
                native.solve_raw(&near, &cold, &mut prev);
                if sol.status != Status::Optimal || prev.status != Status::Optimal {
                    continue;
                }
                tried += 1;
                let objective = sigma(&sol.torque);
                // The control loop's two answers, at w and at the wrench 1 % away.
                let (mut at_w, mut at_near) = (Solution::default(), Solution::default());
                looped.solve_raw(&near, &cold, &mut at_near);
                let mut bounds = |d: &mut Daqp| {
                    qp.c_into(&w, &mut c);
                    qp.model.e_into(&w, &mut ev);
                    d.lower()[..e].copy_from_slice(&ev);
                    d.upper()[..e].copy_from_slice(&ev);
                    d.lower()[e..].copy_from_slice(&c);
                };
                bounds(&mut daqp);
                let first = daqp.solve();
                if first.exitflag != 1 {
                    continue;
                }
                // (DAQP's fval is of its internal problem: the objective from its x.)
                let theirs = sigma(daqp.x());
                worst_rel = worst_rel.max((theirs - objective).abs() / objective.abs().max(1e-300));
                solved += 1;
                let (mut tc, mut tw, mut td, mut ts) = (vec![], vec![], vec![], vec![]);
                for _ in 0..repeats {
                    let s = Instant::now();
                    native.solve_raw(black_box(&w), &cold, &mut sol);
                    tc.push(s.elapsed().as_secs_f64() * 1e6);
                    tw.push(tick(looped.as_mut(), &w, &at_near, &mut at_w));
                    tw.push(tick(looped.as_mut(), &near, &at_w, &mut at_near));
                    let s = Instant::now();
                    bounds(&mut daqp);
                    let res = daqp.solve();
                    td.push(s.elapsed().as_secs_f64() * 1e6);
                    ts.push(res.solve_time * 1e6);
                }
                // The loop's answer is the cold one.
                let looped_objective = sigma(&at_w.torque);
                assert!(
                    at_w.status == Status::Optimal
                        && (looped_objective - objective).abs() <= 1e-9 * objective.abs(),
                    "{name} N = {sides}: the control loop's answer {looped_objective} vs {objective}"
                );
                cold_t.push(median(tc));
                warm_t.push(median(tw));
                daqp_t.push(median(td));
                daqp_s.push(median(ts));
            }
            if cold_t.is_empty() {
                continue;
            }
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            out.push(Row {
                family: family.clone(),
                name: name.clone(),
                sides,
                rows: r,
                cold: mean(&cold_t),
                warm: mean(&warm_t),
                daqp: mean(&daqp_t),
                daqp_solve: mean(&daqp_s),
                solved,
                tried,
                worst_rel,
            });
        }
    }
    println!("| family | grasp | N | rows | native cold µs | native warm µs | DAQP per wrench µs | DAQP solve_time µs | cold / DAQP | cold / DAQP solve_time | solved | objective agreement |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in &out {
        println!(
            "| {} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2}× | {:.2}× | {}/{} | {:.1e} |",
            r.family,
            r.name,
            r.sides,
            r.rows,
            r.cold,
            r.warm,
            r.daqp,
            r.daqp_solve,
            r.cold / r.daqp,
            r.cold / r.daqp_solve,
            r.solved,
            r.tried,
            r.worst_rel
        );
    }
    // Per family: the shifted geometric means over its QPs and how often native wins.
    println!();
    println!("| family | QPs | native cold µs | DAQP per wrench µs | DAQP solve_time µs | cold / DAQP | cold / solve_time | cold ≤ DAQP | cold ≤ solve_time |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut families: Vec<&str> = Vec::new();
    for r in &out {
        if !families.contains(&r.family.as_str()) {
            families.push(&r.family);
        }
    }
    for f in families {
        let rows: Vec<&Row> = out.iter().filter(|r| r.family == f).collect();
        let g = |v: fn(&Row) -> f64| sgm(&rows.iter().map(|r| v(r)).collect::<Vec<_>>());
        let (c, d, t) = (g(|r| r.cold), g(|r| r.daqp), g(|r| r.daqp_solve));
        println!(
            "| {f} | {} | {c:.2} | {d:.2} | {t:.2} | {:.2}× | {:.2}× | {} | {} |",
            rows.len(),
            c / d,
            c / t,
            rows.iter().filter(|r| r.cold <= r.daqp).count(),
            rows.iter().filter(|r| r.cold <= r.daqp_solve).count()
        );
    }
    let col = |f: fn(&Row) -> f64| out.iter().map(f).collect::<Vec<_>>();
    let (cold, warm, daqp, solve) = (
        col(|r| r.cold),
        col(|r| r.warm),
        col(|r| r.daqp),
        col(|r| r.daqp_solve),
    );
    let wins = out.iter().filter(|r| r.cold <= r.daqp).count();
    let wins_s = out.iter().filter(|r| r.cold <= r.daqp_solve).count();
    println!();
    println!(
        "shifted geometric means (10 µs): native cold {:.2} µs, native warm {:.2} µs, DAQP per wrench {:.2} µs, DAQP solve_time {:.2} µs",
        sgm(&cold),
        sgm(&warm),
        sgm(&daqp),
        sgm(&solve)
    );
    println!(
        "native cold ≤ DAQP per wrench on {wins} of {} QPs, ≤ DAQP solve_time on {wins_s}; cold / DAQP {:.2}×, cold / solve_time {:.2}× (ratio of the means)",
        out.len(),
        sgm(&cold) / sgm(&daqp),
        sgm(&cold) / sgm(&solve)
    );
    let (s, t): (usize, usize) = out
        .iter()
        .fold((0, 0), |a, r| (a.0 + r.solved, a.1 + r.tried));
    let worst = out.iter().fold(0.0f64, |a, r| a.max(r.worst_rel));
    println!("DAQP solved {s} of the {t} wrenches the native solver did; worst objective disagreement {worst:.1e} (relative)");
    // Like for like or not at all.
    if worst > 1e-9 || s < t {
        eprintln!("the solvers disagree: see the table");
        std::process::exit(1);
    }
}
