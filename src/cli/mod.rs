//! Command-line parsing and the subcommands.

/// Writes a line to standard output; a write error (a full disk, a closed file)
/// returns from the calling function as [`OutputError`], never a panic.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*).map_err($crate::cli::OutputError)?
    }};
}

/// [`outln!`] without the newline.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*).map_err($crate::cli::OutputError)?
    }};
}

mod batch;
mod bench;
mod build;
mod compare;
mod export_qp;
mod format;
mod hand;
mod solve;
mod sweep;
// The force-space baseline is solved by the native backend.
#[cfg(feature = "active-set")]
mod table;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use grasp_torque::{
    Backend, Check, Cones, GraspProblem, InternalForces, Overrides, SfceSpacing, SolverConfig,
};
use std::path::PathBuf;

/// Minimum-torque grasp forces for dexterous hands (Jia et al.'s key-constraint-set
/// method, with the consistency constraints that make the torques hold the object).
#[derive(Parser, Debug)]
#[command(name = "grasp-torque", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Solve one problem file and report torques, contact forces and checks.
    Solve(solve::SolveArgs),
    /// Solve many problems, one per line of a JSON-lines file, in parallel: one result
    /// per output line (JSON lines or CSV), in input order, with its line number.
    Batch(batch::BatchArgs),
    /// Time one problem in-process: median build, cold and warm solve (µs).
    Bench(bench::BenchArgs),
    /// Print the linearised QP exactly as the native solver receives it (H, c(w), C,
    /// e(w), weights), with the native answer, for peers to solve like for like.
    ExportQp(export_qp::ExportQpArgs),
    /// Print a problem file (any form) in matrix form, ready for `solve`.
    Build(build::BuildArgs),
    /// List a URDF hand's links, independent joints (limits, efforts), mimic couplings
    /// and chains: what a hand-form problem file refers to.
    Hand(hand::HandArgs),
    /// The paper's Table 1: torques before (contact-force optimum mapped through Jᵀ)
    /// and after (torque-space optimum), per object.
    #[cfg(feature = "active-set")]
    Table(table::TableArgs),
    /// Every compiled backend on the linearised problem, plus Clarabel on the exact
    /// cones, with a verdict (exit 5 when they disagree).
    Compare(compare::CompareArgs),
    /// σ(N) against the exact optimum σ*, with rows, iterations and time per N (and per
    /// K for SFCe): the paper's Figure 9, quantitative.
    Sweep(sweep::SweepArgs),
}

/// Output format of a report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum Format {
    /// A readable report.
    Text,
    /// One JSON object on stdout.
    Json,
}

/// Options shared by the commands that build a model.
#[derive(clap::Args, Debug, Clone)]
pub(crate) struct ModelArgs {
    /// Backend: active-set, clarabel or osqp (those compiled in). Default: the first
    /// that supports the cones and internal forces asked for (active-set when it can).
    #[arg(long)]
    backend: Option<String>,
    /// Cones: linear (inscribed polyhedra) or exact (second-order cones).
    #[arg(long, default_value = "linear")]
    cones: String,
    /// How the passive internal forces are fixed (overrides the file): compliance
    /// (unit-invariant least norm, the default), euclidean (the paper's A⁺) or free
    /// (optimised).
    #[arg(long, value_enum)]
    internal_forces: Option<Internal>,
    /// N, sides of the inscribed polygons (overrides the file).
    #[arg(long)]
    sides: Option<usize>,
    /// K, latitudes per hemisphere of SFCe polyhedra (overrides the file).
    #[arg(long)]
    latitudes: Option<usize>,
    /// Placement of SFCe latitudes: paper (eq. 13) or uniform (ellipse angle).
    #[arg(long, value_enum)]
    sfce_spacing: Option<Spacing>,
    /// The paper's model without the consistency constraints: reproduces its numbers,
    /// but the torques generally do not hold the object (a warning says by how much).
    #[arg(long)]
    paper_model: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum Spacing {
    Paper,
    Uniform,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum Internal {
    Compliance,
    Euclidean,
    Free,
}

impl ModelArgs {
    /// Applies the overrides to `p` and returns the solver configuration.
    pub(crate) fn configure(&self, p: &mut GraspProblem) -> Result<SolverConfig> {
        let backend: Option<Backend> = self
            .backend
            .as_deref()
            .map(str::parse)
            .transpose()
            .map_err(|e: String| anyhow::anyhow!("--backend: {e}"))?;
        let cones: Cones = self
            .cones
            .parse()
            .map_err(|e: String| anyhow::anyhow!("--cones: {e}"))?;
        Overrides {
            backend,
            cones,
            check: Check::Full,
            sides: self.sides,
            latitudes: self.latitudes,
            sfce_spacing: self.sfce_spacing.map(|s| match s {
                Spacing::Paper => SfceSpacing::Paper,
                Spacing::Uniform => SfceSpacing::Uniform,
            }),
            internal_forces: self.internal_forces.map(|i| match i {
                Internal::Compliance => InternalForces::Compliance,
                Internal::Euclidean => InternalForces::Euclidean,
                Internal::Free => InternalForces::Free,
            }),
            paper_model: self.paper_model,
        }
        .apply(p)
        .map_err(|e| anyhow::anyhow!("{}", e.to_string().replace("linearization.", "--")))
    }
}

/// Parses `a,b,c` into numbers, naming the flag in errors.
pub(crate) fn parse_list(flag: &str, text: &str) -> Result<Vec<f64>> {
    text.split(',')
        .enumerate()
        .map(|(i, s)| {
            let v: f64 = s
                .trim()
                .parse()
                .with_context(|| format!("{flag}: value {i} (`{}`) is not a number", s.trim()))?;
            if !v.is_finite() {
                bail!(
                    "{flag}: value {i}: expected a finite number, got `{}`",
                    s.trim()
                );
            }
            Ok(v)
        })
        .collect()
}

/// Reads a problem file, attributing errors to its path.
pub(crate) fn load(path: &PathBuf) -> Result<GraspProblem> {
    load_report(path).map(|l| l.problem)
}

/// Reads a problem file with what its form adds to reports; a hand file's warnings go
/// to standard error.
pub(crate) fn load_report(path: &PathBuf) -> Result<grasp_torque::Loaded> {
    let loaded = grasp_torque::load(path).with_context(|| format!("{}", path.display()))?;
    for w in loaded.hand.iter().flat_map(|h| &h.warnings) {
        eprintln!("warning: {w}");
    }
    Ok(loaded)
}

/// Standard output could not be written.
#[derive(Debug)]
pub(crate) struct OutputError(pub(crate) std::io::Error);

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "could not write to standard output: {}", self.0)
    }
}

impl std::error::Error for OutputError {}

pub(crate) fn run() -> Result<u8> {
    let cli = Cli::parse();
    let code = match cli.command {
        Command::Solve(args) => solve::run(&args),
        Command::Batch(args) => batch::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::ExportQp(args) => export_qp::run(&args),
        Command::Build(args) => build::run(&args),
        Command::Hand(args) => hand::run(&args),
        #[cfg(feature = "active-set")]
        Command::Table(args) => table::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Sweep(args) => sweep::run(&args),
    }?;
    use std::io::Write as _;
    std::io::stdout().flush().map_err(OutputError)?;
    Ok(code)
}
