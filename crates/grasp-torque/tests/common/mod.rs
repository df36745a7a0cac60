//! What the integration tests share.

use grasp_torque::{
    solve, Backend, Cones, GraspProblem, Solution, SolverConfig, Status, WarmStart,
};

// (Each test crate that includes this module uses some of it.)

/// A cold solve of `p`'s own wrench by `backend` on `cones`, with the core's checks.
#[allow(dead_code)]
pub(crate) fn run(p: &GraspProblem, backend: Backend, cones: Cones) -> Solution {
    let config = SolverConfig {
        backend: Some(backend),
        cones,
        ..Default::default()
    };
    let mut s = config.build(config.qp(p).unwrap()).unwrap();
    solve(s.as_mut(), &p.wrench, &WarmStart::default()).unwrap()
}

/// The bound on σ's excess an answer states: 2e-9 when `optimal`, its warning's when
/// `almost_optimal`.
#[allow(dead_code)]
pub(crate) fn stated_excess(s: &Solution) -> f64 {
    match s.status {
        Status::Optimal => 2e-9,
        Status::AlmostOptimal => s
            .warnings
            .iter()
            .find_map(|w| w.split("certificate bounds σ only to ").nth(1))
            .and_then(|w| w.split(' ').next()?.parse().ok())
            .expect("the bound in a warning"),
        _ => panic!("no answer: {:?} {:?}", s.status, s.reason),
    }
}

/// How far, relative, an answer states that the rounding of its key rows moves σ (its
/// warning "σ is fixed by the key set's rows only to about …"), 0 where it states none.
#[allow(dead_code)]
pub(crate) fn stated_spread(s: &Solution) -> f64 {
    s.warnings
        .iter()
        .find_map(|w| w.split("key set's rows only to about ").nth(1))
        .map(|w| {
            let v = w.split(',').next().unwrap_or_default();
            v.parse().expect("the spread in the warning")
        })
        .unwrap_or(0.0)
}
