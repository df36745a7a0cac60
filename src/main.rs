//! `grasp-torque`: minimum-torque grasp solving from the shell.
//!
//! Exit codes: 0 optimal (or agreement), 1 output could not be written, 2 invalid input
//! or usage, 3 infeasible, 4 iteration limit or numerical failure, 5 backends disagree
//! (`compare`).

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    // Rust ignores SIGPIPE, which turns a closed stdout (`| head`) into a panic in
    // `println!`; the default action ends the process quietly, as shell tools do.
    #[cfg(unix)]
    // SAFETY: called once at start-up, before any thread exists; SIG_DFL is a valid action.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    match cli::run() {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            eprintln!("error: {e:#}");
            // 1: the output could not be written; 2: invalid input or usage.
            if e.downcast_ref::<cli::OutputError>().is_some() {
                ExitCode::from(1)
            } else {
                ExitCode::from(2)
            }
        }
    }
}
