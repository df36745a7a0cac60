//! `grasp-torque`: minimum-torque grasp solving from the shell.
//!
//! Exit codes: 0 optimal (or agreement), 2 invalid input or usage, 3 infeasible,
//! 4 iteration limit or numerical failure, 5 backends disagree (`compare`).

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    match cli::run() {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
