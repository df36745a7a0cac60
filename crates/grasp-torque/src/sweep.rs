//! The linearisation sweep (the paper's Figure 9, made quantitative): σ(N) against the
//! exact-cone optimum σ*, with rows, iterations and solve time per N (and per K for
//! SFCe contacts).

use crate::{
    solve_into, Backend, Cones, Error, GraspModel, GraspProblem, Solution, SolverConfig, Status,
    TorqueQp, WarmStart,
};
use grasp_core::{ContactModel, SfceSpacing};
use std::sync::Arc;

/// What to sweep.
#[derive(Clone, Debug)]
pub struct SweepConfig {
    /// Values of N.
    pub sides: Vec<usize>,
    /// Values of K; used only when the problem has SFCe contacts.
    pub latitudes: Vec<usize>,
    /// SFCe latitude placement; `None` keeps the problem's.
    pub spacing: Option<SfceSpacing>,
    /// The backend for the linearised problems. Default: active-set.
    pub backend: Backend,
    /// Timed solves per row, 1 to [`MAX_REPEATS`]; the median is reported. Default 21.
    pub repeats: usize,
}

/// Most timed solves per row: their times are kept for the median.
pub const MAX_REPEATS: usize = 10_000_000;

impl Default for SweepConfig {
    fn default() -> Self {
        Self {
            sides: vec![4, 8, 16, 32, 64],
            latitudes: vec![2],
            spacing: None,
            backend: Backend::ActiveSet,
            repeats: 21,
        }
    }
}

/// One linearisation's result.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepRow {
    /// N.
    pub sides: usize,
    /// K.
    pub latitudes: usize,
    /// Solve status.
    pub status: Status,
    /// σ(N), when optimal.
    pub objective: Option<f64>,
    /// `(σ(N) − σ*)/σ*`, when both are known.
    pub gap: Option<f64>,
    /// Inequality rows of H.
    pub constraint_rows: usize,
    /// Backend iterations.
    pub iterations: usize,
    /// Median solve time, µs.
    pub solve_time_us: f64,
}

/// A whole sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// σ* on the exact cones (None when no exact backend is compiled in or the exact
    /// problem is not optimal).
    pub exact_objective: Option<f64>,
    /// Median time of the exact solve, µs.
    pub exact_time_us: Option<f64>,
    /// The backend that gave σ*: the first compiled one with exact cones (native first).
    pub exact_backend: Option<Backend>,
    /// Clarabel's σ*, when σ* came from another backend and Clarabel is compiled in.
    pub exact_cross_check: Option<f64>,
    /// One row per (N, K).
    pub rows: Vec<SweepRow>,
    /// Timed solves per row.
    pub repeats: usize,
    /// Rows whose gap was within [`GAP_FLOOR`] below 0 and is reported as 0.
    pub gaps_clamped: usize,
}

/// The exact solver's relative accuracy: a σ(N) below σ* by less than this is σ*
/// (the inscribed polyhedron touches the cone at the optimum), and its gap is 0.
pub const GAP_FLOOR: f64 = 1e-6;

/// Builds the backend, solves once and reports that first answer (a backend whose
/// first solve fails must not hide it behind later ones), then times `repeats` more.
fn timed(
    config: &SolverConfig,
    qp: TorqueQp,
    w: &[f64; 6],
    repeats: usize,
) -> Result<(Solution, f64), Error> {
    let mut solver = config.build(qp)?;
    let mut first = Solution::default();
    solve_into(solver.as_mut(), w, &WarmStart::default(), &mut first)?;
    let mut s = Solution::default();
    let mut times = Vec::with_capacity(repeats);
    times.push(first.solve_time.as_secs_f64() * 1e6);
    for _ in 1..repeats.max(1) {
        solve_into(solver.as_mut(), w, &WarmStart::default(), &mut s)?;
        times.push(s.solve_time.as_secs_f64() * 1e6);
    }
    times.sort_by(f64::total_cmp);
    Ok((first, times[times.len() / 2]))
}

/// Runs the sweep; `progress(done, total)` is called after each row.
pub fn sweep(
    p: &GraspProblem,
    config: &SweepConfig,
    mut progress: impl FnMut(usize, usize),
) -> Result<Sweep, Error> {
    let mut p = p.clone();
    if let Some(s) = config.spacing {
        p.linearization.sfce_spacing = s;
    }
    let has_sfce = p
        .contacts
        .iter()
        .any(|c| matches!(c, ContactModel::SfcElliptic { .. }));
    let latitudes = if has_sfce {
        config.latitudes.clone()
    } else {
        vec![p.linearization.latitudes]
    };
    p.validate()?;
    if !(1..=MAX_REPEATS).contains(&config.repeats) {
        return Err(grasp_core::ProblemError::invalid(
            "repeats",
            format!("1 to {MAX_REPEATS}"),
            config.repeats,
        )
        .into());
    }
    // One model serves every linearisation: only the cone blocks change.
    let model = Arc::new(GraspModel::new(&p, &SolverConfig::default().model)?);
    // σ* from the first compiled exact backend (the native one when compiled in), and
    // Clarabel's as the cross-check when it is another backend.
    let exact = |backend: Backend| -> Result<(Option<f64>, f64), Error> {
        let c = SolverConfig {
            backend: Some(backend),
            cones: Cones::Exact,
            ..Default::default()
        };
        let (s, t) = timed(
            &c,
            TorqueQp::exact(model.clone()),
            &p.wrench,
            config.repeats.min(5),
        )?;
        Ok((s.is_optimal().then_some(s.objective), t))
    };
    let exact_backend = Backend::compiled().find(|b| b.supports(Cones::Exact));
    let (exact_objective, exact_time_us) = match exact_backend {
        Some(b) => {
            let (s, t) = exact(b)?;
            (s, Some(t))
        }
        None => (None, None),
    };
    let exact_cross_check = match exact_backend {
        Some(b) if b != Backend::Clarabel && Backend::Clarabel.is_compiled() => {
            exact(Backend::Clarabel)?.0
        }
        _ => None,
    };
    let lin = SolverConfig {
        backend: Some(config.backend),
        ..Default::default()
    };
    let total = config.sides.len() * latitudes.len();
    let mut gaps_clamped = 0;
    let mut rows = Vec::with_capacity(total);
    for &k in &latitudes {
        for &n in &config.sides {
            p.linearization.sides = n;
            p.linearization.latitudes = k;
            p.validate()?;
            let qp = TorqueQp::linearized(model.clone(), &p.linearization);
            let constraint_rows = qp.inequality_rows();
            let (s, t) = timed(&lin, qp, &p.wrench, config.repeats)?;
            let objective = s.is_optimal().then_some(s.objective);
            let gap = match (objective, exact_objective) {
                (Some(o), Some(e)) if e > 0.0 => {
                    let g = (o - e) / e;
                    if (-GAP_FLOOR..0.0).contains(&g) {
                        gaps_clamped += 1;
                        Some(0.0)
                    } else {
                        Some(g)
                    }
                }
                _ => None,
            };
            rows.push(SweepRow {
                sides: n,
                latitudes: k,
                status: s.status,
                objective,
                gap,
                constraint_rows,
                iterations: s.iterations,
                solve_time_us: t,
            });
            progress(rows.len(), total);
        }
    }
    Ok(Sweep {
        exact_objective,
        exact_time_us,
        exact_backend,
        exact_cross_check,
        rows,
        repeats: config.repeats,
        gaps_clamped,
    })
}

/// The smallest N (over the rows of one K) whose gap is at most `tolerance`.
pub fn smallest_sides_within(rows: &[SweepRow], tolerance: f64) -> Option<&SweepRow> {
    rows.iter()
        .filter(|r| r.gap.is_some_and(|g| g <= tolerance))
        .min_by_key(|r| r.sides)
}
