//! Errors for problems that cannot be set up ("could not start").
//!
//! A grasp that is set up but has no admissible torque is not an error: it is a
//! [`crate::Status::Infeasible`] answer.

/// A problem description that cannot be used, naming the field at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ProblemError {
    /// The file could not be read.
    #[error("could not read {path}: {error}")]
    Io {
        /// The path given.
        path: String,
        /// The operating system's error.
        error: std::io::Error,
    },
    /// The text is not JSON of the expected shape.
    #[error("{}{message} (line {line}, column {column})", if path.is_empty() || path == "." { String::new() } else { format!("{path}: ") })]
    Parse {
        /// Where in the document, such as `contacts[1].mu` (`.` for the top level).
        path: String,
        /// What serde expected and found.
        message: String,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        column: usize,
    },
    /// A robot description (a URDF) that cannot be used, naming the file, the element
    /// and what is wrong with it.
    #[error("{file}: {element}: {message}")]
    RobotModel {
        /// The robot description's path, as given.
        file: String,
        /// The element at fault, such as `<joint name="j1"> (line 12)`.
        element: String,
        /// What is wrong.
        message: String,
    },
    /// A field has a value the model cannot use.
    #[error("{field}: expected {expected}, got {found}")]
    Invalid {
        /// Where in the document, such as `torque_limits[2]`.
        field: String,
        /// What a valid value looks like.
        expected: String,
        /// What was given.
        found: String,
    },
}

impl ProblemError {
    /// A field with an unusable value.
    pub fn invalid(
        field: impl Into<String>,
        expected: impl Into<String>,
        found: impl std::fmt::Display,
    ) -> Self {
        let mut found = found.to_string();
        // f64's Display writes 1e300 with 300 digits: a long number reads better as 1e300.
        if found.len() > 24 {
            if let Ok(v) = found.parse::<f64>() {
                found = format!("{v:e}");
            }
        }
        Self::Invalid {
            field: field.into(),
            expected: expected.into(),
            found,
        }
    }
}

/// A grasp model that could not be assembled from a valid problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// A decomposition failed to converge.
    #[error("the singular value decomposition of {what} ({rows}×{cols}) did not converge; check its entries for extreme magnitudes")]
    Decomposition {
        /// Which matrix.
        what: &'static str,
        /// Its rows.
        rows: usize,
        /// Its columns.
        cols: usize,
    },
    /// The rank tolerance is not in `(0, 1)`.
    #[error("rank_tolerance must be in (0, 1), got {0}")]
    RankTolerance(f64),
    /// A formulation that does not model part of the problem.
    #[error("{formulation} does not model {what}")]
    Unsupported {
        /// The formulation, such as "the contact-force baseline".
        formulation: &'static str,
        /// What it leaves out.
        what: &'static str,
    },
}
