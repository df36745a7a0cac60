//! Problem files for grasp-torque: JSON in the matrix form (G and Jᵀ, as in the paper)
//! and the geometry form (contact points, normals and finger joint axes), read with
//! serde; unknown fields and trailing text are rejected, and every error names the
//! field at fault. The numerical core reads no file format; this crate turns files into
//! a validated [`GraspProblem`].

pub mod file;
pub mod geometry;

pub use file::{load_problem, parse_problem, ContactSpec, MatrixFile, ModelName};
pub use geometry::GeometryFile;
pub use grasp_core::GraspProblem;
