//! Batch solving: many grasps, each with one or more wrenches, in parallel on `rayon`.
//!
//! Each grasp's model is built once and solved for each of its wrenches in order, each
//! wrench warm-started from the previous one's answer (the first from the problem's
//! `initial_torque`, as `solve` does). Each worker keeps one [`Solution`] and the warm
//! start buffers for all the grasps it takes, so a solve allocates nothing once they
//! have grown; a new grasp allocates its model and backend. Results keep input order,
//! and each carries its own status or error: one bad or infeasible grasp never fails
//! the batch.

use crate::{Error, SolverConfig};
use grasp_core::{solve_into_with, GraspModel, GraspProblem, Solution, TorqueSolver, WarmStart};
use rayon::prelude::*;
use rayon::{ThreadPool, ThreadPoolBuilder};
use std::borrow::Cow;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Most worker threads a batch starts: far more than cores only costs memory and
/// start-up time.
pub const MAX_THREADS: usize = 1024;

/// How a batch runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BatchOptions {
    /// Worker threads. `None` (default): the current rayon pool, which is the global
    /// pool (one thread per core) unless the caller runs the batch inside its own
    /// pool's `install`. `Some(n)`: a pool of `n` threads that the process keeps for
    /// later batches of the same size (rebuilt in a child after `fork`).
    pub threads: Option<usize>,
    /// Warm-start each wrench of a grasp from the previous wrench's answer. Default
    /// `true`; `false` solves every wrench cold (still sharing the model build).
    pub warm_start: bool,
}

impl Default for BatchOptions {
    fn default() -> Self {
        Self {
            threads: None,
            warm_start: true,
        }
    }
}

/// A batch that cannot start (a bad grasp is a per-item error instead).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BatchError {
    /// `threads` is 0.
    #[error("threads: expected at least 1 worker thread, got 0")]
    NoThreads,
    /// `threads` is above [`MAX_THREADS`].
    #[error("threads: expected at most {MAX_THREADS} worker threads, got {0}")]
    TooManyThreads(usize),
    /// The operating system refused the worker threads.
    #[error("could not start {threads} worker threads: {source}")]
    ThreadPool {
        /// Threads asked for.
        threads: usize,
        /// Why.
        source: rayon::ThreadPoolBuildError,
    },
}

/// Where a batch's grasps come from: any indexable collection that builds each grasp's
/// problem on demand (in the worker that solves it).
pub trait BatchSource: Sync {
    /// Number of grasps.
    fn grasps(&self) -> usize;
    /// Number of wrenches of grasp `g`.
    fn wrenches(&self, g: usize) -> usize;
    /// The problem of grasp `g`; the batch validates it.
    fn problem(&self, g: usize) -> Result<Cow<'_, GraspProblem>, Error>;
    /// Wrench `k` of grasp `g`.
    fn wrench(&self, g: usize, k: usize) -> [f64; 6];
}

/// One grasp of a batch and the wrenches it must hold.
#[derive(Clone, Debug)]
pub struct BatchGrasp {
    /// The grasp.
    pub problem: GraspProblem,
    /// The wrenches, solved in this order; empty means the problem's own wrench.
    pub wrenches: Vec<[f64; 6]>,
}

impl BatchGrasp {
    /// A grasp solved for its own wrench only.
    pub fn new(problem: GraspProblem) -> Self {
        Self {
            problem,
            wrenches: Vec::new(),
        }
    }
}

impl BatchSource for [BatchGrasp] {
    fn grasps(&self) -> usize {
        self.len()
    }
    fn wrenches(&self, g: usize) -> usize {
        self[g].wrenches.len().max(1)
    }
    fn problem(&self, g: usize) -> Result<Cow<'_, GraspProblem>, Error> {
        Ok(Cow::Borrowed(&self[g].problem))
    }
    fn wrench(&self, g: usize, k: usize) -> [f64; 6] {
        let b = &self[g];
        b.wrenches.get(k).copied().unwrap_or(b.problem.wrench)
    }
}

/// The answer for one (grasp, wrench) pair.
#[derive(Clone, Debug)]
pub struct BatchResult {
    /// Index of the grasp in the input.
    pub grasp: usize,
    /// Index of the wrench within the grasp.
    pub wrench: usize,
    /// The solution (with its own status), or why the grasp or wrench could not be
    /// solved (shared by the wrenches of a grasp that could not be set up).
    pub outcome: Result<Solution, Arc<Error>>,
}

/// Solves every (grasp, wrench) pair; results in input order, grasp-major.
pub fn solve_batch(
    grasps: &[BatchGrasp],
    config: &SolverConfig,
    options: &BatchOptions,
) -> Result<Vec<BatchResult>, BatchError> {
    run_in(options, || {
        grasps
            .par_iter()
            .enumerate()
            .map_init(Worker::default, |worker, (g, _)| {
                let mut out = Vec::with_capacity(grasps.wrenches(g));
                worker.grasp(grasps, g, config, options, |k, r| {
                    out.push(BatchResult {
                        grasp: g,
                        wrench: k,
                        outcome: r.cloned().map_err(Arc::clone),
                    });
                });
                out
            })
            .flatten_iter()
            .collect()
    })
}

/// Solves every (grasp, wrench) pair of `source` and hands each answer to `emit(grasp,
/// wrench, result)` on the worker thread that solved it, as soon as it is solved (so
/// in no particular order across grasps; in wrench order within a grasp). Nothing is
/// allocated per solve beyond what the solver needs: `emit` can write results straight
/// into preallocated output.
pub fn for_each_solution<S, F>(
    source: &S,
    config: &SolverConfig,
    options: &BatchOptions,
    emit: F,
) -> Result<(), BatchError>
where
    S: BatchSource + ?Sized,
    F: Fn(usize, usize, Result<&Solution, &Error>) + Sync,
{
    run_in(options, || {
        (0..source.grasps())
            .into_par_iter()
            .for_each_init(Worker::default, |worker, g| {
                worker.grasp(source, g, config, options, |k, r| {
                    emit(g, k, r.map_err(|e| &**e))
                })
            })
    })
}

/// Calls `f(i)` for every `i` in `0..count`, in parallel on the batch's threads (as
/// [`for_each_solution`] runs its grasps), in no particular order: the per-grasp work of
/// a planner's batch besides solving, such as posing a hand's candidates into arrays
/// (`HandGrasps::pose`) or placing their frames.
pub fn for_each_index<F>(count: usize, options: &BatchOptions, f: F) -> Result<(), BatchError>
where
    F: Fn(usize) + Sync + Send,
{
    run_in(options, || (0..count).into_par_iter().for_each(f))
}

/// A worker's buffers, reused for every grasp it takes.
#[derive(Default)]
struct Worker {
    solution: Solution,
    last_torque: Vec<f64>,
    last_active: Vec<usize>,
}

impl Worker {
    fn grasp<S: BatchSource + ?Sized>(
        &mut self,
        source: &S,
        g: usize,
        config: &SolverConfig,
        options: &BatchOptions,
        mut emit: impl FnMut(usize, Result<&Solution, &Arc<Error>>),
    ) {
        let wrenches = source.wrenches(g);
        let (mut backend, initial) = match setup(source, g, config) {
            Ok(b) => b,
            Err(e) => {
                let e = Arc::new(e);
                for k in 0..wrenches {
                    emit(k, Err(&e));
                }
                return;
            }
        };
        self.last_torque.clear();
        self.last_torque
            .extend_from_slice(initial.as_deref().unwrap_or(&[]));
        self.last_active.clear();
        let mut has_active = false;
        for k in 0..wrenches {
            let w = source.wrench(g, k);
            let warm = if k == 0 || options.warm_start {
                WarmStart {
                    torque: (!self.last_torque.is_empty()).then_some(&self.last_torque[..]),
                    active_set: has_active.then_some(&self.last_active[..]),
                }
            } else {
                WarmStart::default()
            };
            match solve_into_with(
                backend.as_mut(),
                &w,
                &warm,
                config.check,
                &mut self.solution,
            ) {
                Ok(()) => {
                    let s = &self.solution;
                    emit(k, Ok(s));
                    // The next wrench starts from this answer, or from the last good one.
                    if s.is_optimal() {
                        self.last_torque.clear();
                        self.last_torque.extend_from_slice(&s.torque);
                        self.last_active.clear();
                        if let Some(a) = &s.active_set {
                            self.last_active.extend_from_slice(a);
                        }
                        has_active = s.active_set.is_some();
                    }
                }
                Err(e) => emit(k, Err(&Arc::new(Error::WarmStart(e)))),
            }
        }
    }
}

/// A grasp's backend, and the problem's initial torque.
type Setup = (Box<dyn TorqueSolver>, Option<Vec<f64>>);

/// Validates grasp `g` and builds its model and backend.
fn setup<S: BatchSource + ?Sized>(
    source: &S,
    g: usize,
    config: &SolverConfig,
) -> Result<Setup, Error> {
    let p = source.problem(g)?;
    p.validate()?;
    let model = Arc::new(GraspModel::new(&p, &config.model)?);
    let qp = config.view(model, &p.linearization);
    let backend = config.build(qp)?;
    let initial = match p {
        Cow::Borrowed(p) => p.initial_torque.clone(),
        Cow::Owned(p) => p.initial_torque,
    };
    Ok((backend, initial))
}

/// Runs `f` on the pool `options` asks for.
fn run_in<R: Send>(options: &BatchOptions, f: impl FnOnce() -> R + Send) -> Result<R, BatchError> {
    match options.threads {
        None => Ok(f()),
        Some(n) => Ok(pool(n)?.install(f)),
    }
}

/// The process's pool of `n` threads. A pool's threads do not survive `fork`, so pools
/// are keyed by process id: a forked child builds its own instead of waiting on the
/// parent's threads forever.
fn pool(n: usize) -> Result<Arc<ThreadPool>, BatchError> {
    /// By (process id, threads).
    type Pools = HashMap<(u32, usize), Arc<ThreadPool>>;
    static POOLS: Mutex<Option<Pools>> = Mutex::new(None);
    if n == 0 {
        return Err(BatchError::NoThreads);
    }
    if n > MAX_THREADS {
        return Err(BatchError::TooManyThreads(n));
    }
    let key = (std::process::id(), n);
    // A child forked while another thread held the lock would wait forever: build a
    // private pool instead of waiting.
    let mut guard = match POOLS.try_lock() {
        Ok(g) => g,
        Err(std::sync::TryLockError::Poisoned(p)) => p.into_inner(),
        Err(std::sync::TryLockError::WouldBlock) => return build_pool(n).map(Arc::new),
    };
    let pools = guard.get_or_insert_with(HashMap::new);
    // Pools of a parent process are dead threads here; forget them (never join them).
    let stale: Vec<_> = pools.keys().filter(|k| k.0 != key.0).copied().collect();
    for k in stale {
        std::mem::forget(pools.remove(&k));
    }
    if let Some(p) = pools.get(&key) {
        return Ok(p.clone());
    }
    let p = Arc::new(build_pool(n)?);
    pools.insert(key, p.clone());
    Ok(p)
}

fn build_pool(n: usize) -> Result<ThreadPool, BatchError> {
    ThreadPoolBuilder::new()
        .num_threads(n)
        .thread_name(|i| format!("grasp-torque-{i}"))
        .build()
        .map_err(|source| BatchError::ThreadPool { threads: n, source })
}
