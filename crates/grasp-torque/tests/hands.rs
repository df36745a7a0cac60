//! Hand-form problems through the library: load, solve with every compiled backend,
//! and the physics checks an answer must pass (the object is held, the joints produce
//! the forces, the exact optimum is below the linearised one).

use grasp_torque::{load, GraspSolver, SolverConfig, WarmStart};

fn fixture(name: &str) -> String {
    format!("{}/../../fixtures/hands/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn bundled_hands_solve_from_the_library() {
    for name in ["allegro-pinch.json", "ability-tripod.json"] {
        let loaded = load(fixture(name)).unwrap();
        let hand = loaded.hand.expect("a hand-form file reports its hand");
        assert!(
            hand.defaulted_joints.is_empty(),
            "{name}: {:?}",
            hand.defaulted_joints
        );
        let p = loaded.problem;
        assert_eq!(p.joint_names.len(), p.joints());
        let mut solver = GraspSolver::new(&p, &SolverConfig::default()).unwrap();
        let linear = solver
            .solve(&p.wrench, &WarmStart::default())
            .unwrap()
            .clone();
        assert!(linear.is_optimal(), "{name}: {:?}", linear.status);
        // τ = Jᵀ f and G f = w, recomputed here from the problem's own matrices.
        let f = &linear.contact_forces;
        for j in 0..p.joints() {
            let jtf: f64 = (0..p.force_dim())
                .map(|c| p.jacobian_transpose[(j, c)] * f[c])
                .sum();
            assert!(
                (jtf - linear.torque[j]).abs() <= 1e-9 * (1.0 + jtf.abs()),
                "{name}: joint {j}"
            );
        }
        for r in 0..6 {
            let gf: f64 = (0..p.force_dim())
                .map(|c| p.grasp_matrix[(r, c)] * f[c])
                .sum();
            assert!((gf - p.wrench[r]).abs() <= 1e-9, "{name}: wrench row {r}");
        }
        // A warm re-solve after a 1 % heavier load stays optimal.
        let heavier: Vec<f64> = p.wrench.iter().map(|w| 1.01 * w).collect();
        assert!(solver
            .resolve(&heavier.try_into().unwrap())
            .unwrap()
            .is_optimal());
        #[cfg(feature = "clarabel")]
        {
            let config = SolverConfig {
                cones: grasp_torque::Cones::Exact,
                ..Default::default()
            };
            let mut exact = GraspSolver::new(&p, &config).unwrap();
            let s = exact.solve(&p.wrench, &WarmStart::default()).unwrap();
            assert!(s.is_optimal(), "{name}: {:?}", s.status);
            assert!(
                s.objective <= linear.objective * (1.0 + 1e-7),
                "{name}: exact above linear"
            );
        }
    }
}
