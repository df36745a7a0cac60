//! What the integration tests share.

use grasp_torque::{solve, Backend, Cones, GraspProblem, Solution, SolverConfig, WarmStart};

/// A cold solve of `p`'s own wrench by `backend` on `cones`, with the core's checks.
pub(crate) fn run(p: &GraspProblem, backend: Backend, cones: Cones) -> Solution {
    let config = SolverConfig {
        backend: Some(backend),
        cones,
        ..Default::default()
    };
    let mut s = config.build(config.qp(p).unwrap()).unwrap();
    solve(s.as_mut(), &p.wrench, &WarmStart::default()).unwrap()
}
