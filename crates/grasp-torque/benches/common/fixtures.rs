//! The benchmark fixtures, shared by `benches/backends.rs` and
//! `examples/bench_report.rs` so both name and build them alike.

use grasp_testkit::{synthetic_grasp, ModelMix, SynthSpec};
use grasp_torque::file::ModelName;
use grasp_torque::{
    load_problem, solve, ActiveSetSettings, ActiveSetSolver, GraspProblem, ModelOptions, TorqueQp,
    WarmStart,
};

/// A named benchmark problem.
pub(crate) struct Fixture {
    /// Benchmark id, such as `h5x4-pcwf-N8`.
    pub(crate) name: String,
    /// The problem.
    pub(crate) problem: GraspProblem,
}

fn file(name: &str) -> GraspProblem {
    load_problem(format!(
        "{}/fixtures/{name}.json",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../..")
    ))
    .unwrap()
}

/// A synthetic hand with `fingers` × `joints` joints, one `model` contact per finger,
/// the first seed whose grasp is feasible at N = 4 (hence at every larger N: the cones
/// are nested).
pub(crate) fn hand(fingers: usize, joints: usize, model: ModelName) -> GraspProblem {
    let mut spec = SynthSpec {
        fingers: Some(fingers),
        joints_per_finger: Some(joints),
        models: ModelMix::Only(model),
        ..Default::default()
    };
    spec.linearization.sides = 4;
    for seed in 0.. {
        let p = synthetic_grasp(seed, &spec).into_problem().unwrap();
        let qp = TorqueQp::from_problem(&p, &ModelOptions::default()).unwrap();
        let mut s = ActiveSetSolver::new(qp, ActiveSetSettings::default()).unwrap();
        if solve(&mut s, &p.wrench, &WarmStart::default())
            .unwrap()
            .is_optimal()
        {
            return p;
        }
    }
    unreachable!()
}

/// The paper example, the Table 1 grasps, and 3-, 4- and 5-finger hands (9, 16 and 20
/// joints) under PCwF, SFCl and SFCe contacts at N = 4, 8, 16, 32.
pub(crate) fn all() -> Vec<Fixture> {
    let mut v = vec![Fixture {
        name: "paper-example".into(),
        problem: file("paper-example"),
    }];
    for t in [
        "1-aluminium-block",
        "2-screwdriver",
        "3-plastic-bottle",
        "4-carbon-pen",
        "5-iron-piece",
        "6-cup",
    ] {
        v.push(Fixture {
            name: format!("table1-{t}"),
            problem: file(&format!("table1/{t}")),
        });
    }
    for (f, j) in [(3, 3), (4, 4), (5, 4)] {
        for (m, label) in [
            (ModelName::Pcwf, "pcwf"),
            (ModelName::Sfcl, "sfcl"),
            (ModelName::Sfce, "sfce"),
        ] {
            let base = hand(f, j, m);
            for n in [4, 8, 16, 32] {
                let mut p = base.clone();
                p.linearization.sides = n;
                v.push(Fixture {
                    name: format!("h{f}x{j}-{label}-N{n}"),
                    problem: p,
                });
            }
        }
    }
    v
}
