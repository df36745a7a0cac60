//! Core model of grasp-torque: contact models, inscribed friction cones, the
//! decomposition `f = Z1 w + Z2 τ`, the consistency equalities, and the torque QP
//! `min Σ w_j τ_j²  s.t.  H τ ≥ c, C τ = e`, with the [`TorqueSolver`] trait every
//! backend implements.
//!
//! This crate depends on no solver. Equation numbers refer to Jia et al., "Grasping
//! Torque Optimization for a Dexterous Robotic Hand Using the Linearization of
//! Constraints".

pub mod cone;
pub mod contact;
pub mod error;
pub mod file;
pub mod geometry;
pub mod linalg;
pub mod matrix;
pub mod problem;
pub mod qp;
pub mod solver;
pub mod synth;

pub use cone::{inscribed_cone, InscribedCone, Linearization, SfceSpacing};
pub use contact::ContactModel;
pub use error::{ModelError, ProblemError};
pub use file::{load_problem, parse_problem};
pub use matrix::Matrix;
pub use problem::GraspProblem;
pub use qp::{ContactBlock, Equilibrium, ModelOptions, RowKind, TorqueQp};
pub use solver::{
    solve, solve_into, Diagnostics, Reason, Solution, Status, TorqueSolver, WarmStart,
    WarmStartError,
};
