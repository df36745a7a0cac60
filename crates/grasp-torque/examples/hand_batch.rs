//! A grasp planner's batch in Rust, from a robot file: candidate pinches of the Allegro
//! hand (the bundled fixture with its joint positions and contact points perturbed),
//! each posed by `HandGrasps::pose` on the worker that solves it, ranked by effort.
//! The Python `Hand.solve_batch` is this, over numpy arrays.
//!
//! Run: `cargo run --release -p grasp-torque --example hand_batch -- [GRASPS]`

use grasp_torque::hand::{GraspPose, HandGrasps};
use grasp_torque::{
    for_each_solution, BatchOptions, BatchSource, Error, GraspProblem, HandFile, Robot,
    SolverConfig,
};
use std::borrow::Cow;
use std::path::Path;
use std::sync::Mutex;
use std::time::Instant;

/// The candidates: one configuration and one set of contact points each.
struct Candidates<'r> {
    grasps: HandGrasps<'r>,
    joint_positions: Vec<Vec<f64>>,
    positions: Vec<Vec<Option<[f64; 3]>>>,
    wrench: [f64; 6],
}

impl BatchSource for Candidates<'_> {
    fn grasps(&self) -> usize {
        self.joint_positions.len()
    }
    fn wrenches(&self, _: usize) -> usize {
        1
    }
    fn problem(&self, g: usize) -> Result<Cow<'_, GraspProblem>, Error> {
        let pose = GraspPose {
            joint_positions: &self.joint_positions[g],
            positions: Some(&self.positions[g]),
            ..GraspPose::default()
        };
        Ok(Cow::Owned(self.grasps.pose(&pose)?))
    }
    fn wrench(&self, _: usize, _: usize) -> [f64; 6] {
        self.wrench
    }
}

fn main() {
    let count: usize = std::env::args()
        .nth(1)
        .map_or(20_000, |a| a.parse().expect("GRASPS"));
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/hands");
    let text = std::fs::read_to_string(dir.join("allegro-pinch.json")).expect("the fixture");
    let file: HandFile = serde_json::from_str(&text).expect("a hand-form file");
    let robot = Robot::load(&file.model_path(&dir)).expect("the URDF");
    let grasps = file.grasps(&robot).expect("its contacts");
    // The fixture's configuration, every independent joint in file order.
    let mut q0 = vec![0.0; robot.independent.len()];
    for (name, &v) in &file.hand.joint_positions {
        let j = robot.joint(name).expect("a joint of the URDF");
        q0[robot.coupling[j].expect("independent").independent] = v;
    }
    // Deterministic perturbations: ±0.02 rad per joint, ±1 mm per contact coordinate.
    let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
    let mut uniform = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut source = Candidates {
        grasps,
        joint_positions: Vec::with_capacity(count),
        positions: Vec::with_capacity(count),
        wrench: file
            .wrench
            .as_deref()
            .and_then(|w| w.try_into().ok())
            .expect("six numbers"),
    };
    for _ in 0..count {
        source
            .joint_positions
            .push(q0.iter().map(|q| q + 0.02 * uniform()).collect());
        source.positions.push(
            file.contacts
                .iter()
                .map(|c| c.position.map(|p| p.map(|x| x + 1e-3 * uniform())))
                .collect(),
        );
    }
    let best = Mutex::new((f64::INFINITY, 0, Vec::new()));
    let held = std::sync::atomic::AtomicUsize::new(0);
    let start = Instant::now();
    for_each_solution(
        &source,
        &SolverConfig::default(),
        &BatchOptions::default(),
        |g, _, r| {
            if let Some(s) = r.ok().filter(|s| s.is_optimal()) {
                held.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let mut b = best.lock().unwrap();
                if s.objective < b.0 {
                    *b = (s.objective, g, s.torque.clone());
                }
            }
        },
    )
    .expect("worker threads");
    let secs = start.elapsed().as_secs_f64();
    let (sigma, g, torque) = best.into_inner().unwrap();
    let names = &source.grasps.template().joint_names;
    println!(
        "{} of {count} candidates hold the object ({:.0} grasps/s)",
        held.into_inner(),
        count as f64 / secs
    );
    println!("least effort: candidate {g}, σ = {sigma:.6} N²m²");
    for (name, t) in names.iter().zip(torque) {
        println!("  {name:12} {t:+.4} N m");
    }
}
