//! `grasp-torque build`: a problem file (any form) printed in matrix form, with
//! `joint_names` when the form knows them.

use super::load;
use anyhow::Result;
use grasp_torque::file::MatrixFile;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub(crate) struct BuildArgs {
    /// The problem file (hand, geometry or matrix form).
    problem: PathBuf,
}

pub(crate) fn run(args: &BuildArgs) -> Result<u8> {
    let p = load(&args.problem)?;
    let name = args
        .problem
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned());
    let mut file = MatrixFile::from_problem(&p, name);
    file.description = Some(format!(
        "built by grasp-torque from {}",
        args.problem.display()
    ));
    outln!("{}", serde_json::to_string_pretty(&file)?);
    Ok(0)
}
