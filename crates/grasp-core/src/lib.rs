//! Core model of grasp-torque: contact models, inscribed friction cones, the
//! [`GraspModel`] (`f = Z1 w + Z2 τ + N ξ` and the consistency equalities, built once
//! per grasp), typed constraint blocks ([`Constraints`]), the linear view
//! [`TorqueQp`] (`min Σ w_j τ_j²  s.t.  H τ ≥ c, C τ = e`), and the [`TorqueSolver`]
//! trait every backend implements.
//!
//! This crate depends on no solver and reads no file format. Equation numbers refer to Jia et al., "Grasping
//! Torque Optimization for a Dexterous Robotic Hand Using the Linearization of
//! Constraints".

pub mod by_name;
pub mod cone;
pub mod conic;
pub mod contact;
pub mod error;
pub mod linalg;
pub mod matrix;
pub mod model;
pub mod problem;
pub mod qp;
pub mod solver;

pub use cone::{circumscribed_cone, inscribed_cone, InscribedCone, Linearization, SfceSpacing};
pub use conic::{Certificate, ConeKind, ConicForm, RayCheck};
pub use contact::ContactModel;
pub use error::{ModelError, ProblemError};
pub use matrix::Matrix;
pub use model::{Equilibrium, GraspModel, InternalForces, ModelOptions, ZeroedJoint};
pub use problem::{GraspProblem, TorqueLimit};
pub use qp::{
    ConeRepr, Constraints, ContactBlock, EqFactors, ForceSpaceQp, InequalityRows, LeastDistance,
    RowFactors, RowId, TorqueQp,
};
pub use solver::{
    complete_deferred, solve, solve_into, solve_into_with, Capabilities, Check, Diagnostics,
    Reason, Recycled, Solution, Status, TorqueSolver, WarmStart, WarmStartError,
};
