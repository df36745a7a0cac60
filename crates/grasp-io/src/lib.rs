//! Problem files for grasp-torque: JSON in the matrix form (G and Jᵀ, as in the paper),
//! the geometry form (contact points, normals and finger joint axes) and the hand form
//! (a URDF, joint positions and contacts on its links), read with serde; unknown fields
//! and trailing text are rejected, and every error names the field at fault. The
//! numerical core reads no file format; this crate turns files into a validated
//! [`GraspProblem`].

pub mod file;
pub mod frame;
pub mod geometry;
pub mod hand;
pub mod mass;
pub mod mjcf;
pub mod tendon;
pub mod urdf;

pub use file::{
    load, load_problem, parse_problem, parse_problem_at, ContactSpec, Loaded, MatrixFile,
    ModelName, ProblemParser,
};
pub use geometry::GeometryFile;
pub use grasp_core::error::ProblemError;
pub use grasp_core::GraspProblem;
pub use hand::{GraspPose, HandFile, HandGrasps, HandProblem, HandReport};
pub use urdf::Robot;
