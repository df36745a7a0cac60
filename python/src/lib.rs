//! `grasp_torque._native`: the Rust side of the Python package. A thin shell over the
//! `grasp-torque` facade; the conveniences (dicts, keyword defaults, named tuples) live
//! in `grasp_torque/__init__.py`.

use grasp_torque::hand::{GraspPose, HandContact, HandGrasps, HeldObject, ObjectPose};
use grasp_torque::{
    file::ContactSpec, file::MatrixFile, for_each_index, for_each_solution, Backend, BatchOptions,
    BatchSource, Error, GraspProblem, GraspSolver, Matrix, Overrides, ProblemError, ProblemParser,
    SfceSpacing, Solution, SolverConfig, Status, WarmStart,
};
use numpy::ndarray::{ArrayView2, ArrayView3, Axis};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2, PyReadonlyArray3, PyReadwriteArrayDyn,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::path::Path;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

fn invalid(message: impl ToString) -> PyErr {
    PyValueError::new_err(message.to_string())
}

/// Reads JSON that the Python side wrote from the caller's keywords, naming the field
/// at fault (`contacts[0].mu`, `sides`); the line and column of that text would mean
/// nothing to the caller.
fn from_keywords<'de, T: Deserialize<'de>>(text: &'de str) -> PyResult<T> {
    grasp_torque::file::from_json_str(text).map_err(|e| match e {
        ProblemError::Parse { path, message, .. } if !path.is_empty() && path != "." => {
            invalid(format!("{path}: {message}"))
        }
        ProblemError::Parse { message, .. } => invalid(message),
        e => invalid(e),
    })
}

/// Robot files read once per process, shared by every hand-form problem that names them.
fn parser() -> &'static ProblemParser {
    static P: OnceLock<ProblemParser> = OnceLock::new();
    P.get_or_init(ProblemParser::new)
}

/// A validated grasp problem (any of the three JSON forms, or arrays).
#[pyclass(module = "grasp_torque._native", frozen)]
struct Problem {
    inner: GraspProblem,
    /// The hand form's report (robot, joints defaulted, warnings), as JSON.
    hand: Option<String>,
}

#[pymethods]
impl Problem {
    /// Parses a problem in any form from JSON text; relative robot paths are taken
    /// relative to `base`.
    /// `hand` restores a hand report (unpickling a matrix-form copy of a hand problem).
    #[staticmethod]
    #[pyo3(signature = (text, base, hand=None))]
    fn from_json(text: &str, base: &str, hand: Option<String>) -> PyResult<Self> {
        let loaded = parser().parse_at(text, Path::new(base)).map_err(invalid)?;
        let hand = match loaded.hand {
            Some(h) => Some(serde_json::to_string(&h).map_err(invalid)?),
            None => hand,
        };
        Ok(Self {
            inner: loaded.problem,
            hand,
        })
    }

    /// The problem in matrix form, as JSON text (what `grasp-torque build` prints).
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&MatrixFile::from_problem(&self.inner, None)).map_err(invalid)
    }

    /// The hand form's report as JSON text, or None.
    fn hand_json(&self) -> Option<String> {
        self.hand.clone()
    }

    #[getter]
    fn joints(&self) -> usize {
        self.inner.joints()
    }

    #[getter]
    fn force_dim(&self) -> usize {
        self.inner.force_dim()
    }

    #[getter]
    fn contacts(&self) -> usize {
        self.inner.contacts.len()
    }

    #[getter]
    fn joint_names(&self) -> Option<Vec<String>> {
        names(&self.inner)
    }

    #[getter]
    fn wrench<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner.wrench.to_vec().into_pyarray(py)
    }

    #[getter]
    fn grasp_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix(py, &self.inner.grasp_matrix)
    }

    #[getter]
    fn jacobian_transpose<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix(py, &self.inner.jacobian_transpose)
    }

    /// τ_p per joint (springs, the links' weight), or None.
    #[getter]
    fn passive_torque<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner
            .passive_torque
            .as_ref()
            .map(|t| t.clone().into_pyarray(py))
    }
}

fn matrix<'py>(py: Python<'py>, m: &Matrix) -> Bound<'py, PyArray2<f64>> {
    let (r, c) = (m.nrows(), m.ncols());
    numpy::ndarray::Array2::from_shape_fn((r, c), |(i, j)| m[(i, j)]).into_pyarray(py)
}

fn names(p: &GraspProblem) -> Option<Vec<String>> {
    (!p.joint_names.is_empty()).then(|| p.joint_names.clone())
}

/// The solver settings that are not part of the problem.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Settings {
    backend: Option<String>,
    cones: Option<String>,
    sides: Option<usize>,
    latitudes: Option<usize>,
    sfce_spacing: Option<String>,
    internal_forces: Option<String>,
    paper_model: Option<bool>,
    check: Option<String>,
}

impl Settings {
    /// Applies the overrides to `p` and returns the configuration, as the CLI's flags
    /// do (errors name the keyword instead of the flag).
    fn configure(&self, p: &mut GraspProblem) -> PyResult<SolverConfig> {
        fn parsed<T: std::str::FromStr<Err = String>>(
            name: &str,
            v: Option<&str>,
        ) -> PyResult<Option<T>> {
            v.map(str::parse)
                .transpose()
                .map_err(|e| invalid(format!("{name}: {e}")))
        }
        Overrides {
            backend: parsed("backend", self.backend.as_deref())?,
            cones: parsed("cones", self.cones.as_deref())?.unwrap_or_default(),
            check: parsed("check", self.check.as_deref())?.unwrap_or_default(),
            sides: self.sides,
            latitudes: self.latitudes,
            sfce_spacing: match self.sfce_spacing.as_deref() {
                None => None,
                Some("uniform") => Some(SfceSpacing::Uniform),
                Some("paper") => Some(SfceSpacing::Paper),
                Some(other) => {
                    return Err(invalid(format!(
                        "sfce_spacing: unknown `{other}`: expected `uniform` or `paper`"
                    )))
                }
            },
            internal_forces: parsed("internal_forces", self.internal_forces.as_deref())?,
            paper_model: self.paper_model == Some(true),
        }
        .apply(p)
        .map_err(|e| invalid(e.to_string().replace("linearization.", "")))
    }
}

/// A solver for one grasp, reused across wrenches (the control-loop object).
#[pyclass(module = "grasp_torque._native")]
struct Solver {
    solver: Mutex<GraspSolver>,
    problem: GraspProblem,
    settings_json: String,
    cones: &'static str,
}

#[pymethods]
impl Solver {
    #[new]
    fn new(problem: &Problem, settings_json: &str) -> PyResult<Self> {
        let settings: Settings = from_keywords(settings_json)?;
        let mut p = problem.inner.clone();
        let config = settings.configure(&mut p)?;
        let solver = GraspSolver::new(&p, &config).map_err(invalid)?;
        Ok(Self {
            solver: Mutex::new(solver),
            problem: p,
            settings_json: settings_json.to_string(),
            cones: config.cones.name(),
        })
    }

    /// Solves for `wrench` (the problem's own when None): warm-started from the
    /// previous optimal answer when `warm`, else from the problem's initial torque.
    #[pyo3(signature = (wrench=None, warm=true))]
    fn solve(&self, wrench: Option<[f64; 6]>, warm: bool) -> PyResult<SolveResult> {
        let w = wrench.unwrap_or(self.problem.wrench);
        let mut s = self.solver.lock().unwrap_or_else(|e| e.into_inner());
        let backend = s.backend_name();
        let sol = if warm {
            s.resolve(&w)
        } else {
            let start = WarmStart {
                torque: self.problem.initial_torque.as_deref(),
                active_set: None,
            };
            s.solve(&w, &start)
        }
        .map_err(invalid)?;
        let mut result = SolveResult::new(sol, &self.problem, backend, self.cones);
        let model = &s.problem().model;
        result.data.warnings.extend(model.zeroed_joint_warnings());
        Ok(result)
    }

    /// Completes what the lazy check deferred for the last answer: forces, residuals
    /// and the core's independent check (`GraspSolver::diagnose`).
    fn diagnose(&self) -> SolveResult {
        let mut s = self.solver.lock().unwrap_or_else(|e| e.into_inner());
        let backend = s.backend_name();
        SolveResult::new(s.diagnose(), &self.problem, backend, self.cones)
    }

    /// The problem as solved (overrides applied).
    fn problem(&self) -> Problem {
        Problem {
            inner: self.problem.clone(),
            hand: None,
        }
    }

    #[getter]
    fn backend(&self) -> &'static str {
        self.solver
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .backend_name()
    }

    /// The settings given, as JSON (for pickling).
    fn settings_json(&self) -> String {
        self.settings_json.clone()
    }
}

/// Residuals and margins of a solve (the Rust `Diagnostics`).
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Checks {
    /// The lazy check deferred the rest (`diagnose` computes it).
    #[serde(default)]
    deferred: bool,
    wrench_residual: f64,
    torque_residual: f64,
    consistency_residual: f64,
    max_violation: f64,
    cone_violation: f64,
    friction_margins: Vec<Option<f64>>,
    check_tolerance: f64,
    wrench_check: f64,
    torque_check: f64,
    #[serde(default)]
    violation_check: f64,
    #[serde(default)]
    cone_check: f64,
}

/// Everything a Python result holds; serialisable, so results pickle.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct ResultData {
    status: String,
    reason: Option<serde_json::Value>,
    torque: Option<Vec<f64>>,
    contact_forces: Option<Vec<f64>>,
    /// Each contact's force on the object in the wrench's frame.
    object_forces: Option<Vec<[f64; 3]>>,
    contact_dims: Vec<usize>,
    internal_forces: Vec<f64>,
    objective: Option<f64>,
    iterations: usize,
    active_set: Option<Vec<usize>>,
    solve_time_us: f64,
    checks: Checks,
    joint_names: Option<Vec<String>>,
    /// With a transmission: τ = T u per joint (`torque` holds u per actuator).
    joint_torque: Option<Vec<f64>>,
    actuator_names: Option<Vec<String>>,
    warnings: Vec<String>,
    backend: String,
    cones: String,
}

/// The answer of one solve.
#[pyclass(module = "grasp_torque._native", frozen, name = "Result")]
struct SolveResult {
    data: ResultData,
}

impl SolveResult {
    fn new(s: &Solution, p: &GraspProblem, backend: &str, cones: &str) -> Self {
        let ok = !s.torque.is_empty();
        let d = &s.diagnostics;
        let reason = s.reason.as_ref().map(|r| {
            let mut v = serde_json::to_value(r).unwrap_or(serde_json::Value::Null);
            if let Some(o) = v.as_object_mut() {
                o.insert("message".into(), r.to_string().into());
            }
            v
        });
        Self {
            data: ResultData {
                status: s.status.as_str().into(),
                reason,
                torque: ok.then(|| s.torque.clone()),
                contact_forces: (ok && !d.deferred).then(|| s.contact_forces.clone()),
                object_forces: (ok && !d.deferred).then(|| {
                    grasp_torque::model::object_forces(
                        &p.grasp_matrix,
                        &p.contacts,
                        &s.contact_forces,
                    )
                }),
                contact_dims: p.contacts.iter().map(|c| c.dim()).collect(),
                internal_forces: s.internal_forces.clone(),
                objective: ok.then_some(s.objective),
                iterations: s.iterations,
                active_set: s.active_set.clone(),
                solve_time_us: s.solve_time.as_secs_f64() * 1e6,
                checks: Checks {
                    deferred: d.deferred,
                    wrench_residual: d.wrench_residual,
                    torque_residual: d.torque_residual,
                    consistency_residual: d.consistency_residual,
                    max_violation: d.max_violation,
                    cone_violation: d.cone_violation,
                    friction_margins: d.friction_margins.clone(),
                    check_tolerance: d.check_tolerance,
                    wrench_check: d.wrench_check,
                    torque_check: d.torque_check,
                    violation_check: d.violation_check,
                    cone_check: d.cone_check,
                },
                joint_names: names(p),
                joint_torque: (ok && !s.joint_torque.is_empty()).then(|| s.joint_torque.clone()),
                actuator_names: p
                    .transmission
                    .as_ref()
                    .map(|_| (0..p.actuated()).map(|j| p.actuator_name(j)).collect()),
                warnings: s.warnings.clone(),
                backend: backend.into(),
                cones: cones.into(),
            },
        }
    }
}

#[pymethods]
impl SolveResult {
    /// Rebuilds a result from [`Self::to_json`] (unpickling).
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        Ok(Self {
            data: serde_json::from_str(text).map_err(invalid)?,
        })
    }

    /// Everything, as JSON text.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.data).map_err(invalid)
    }

    #[getter]
    fn status(&self) -> &str {
        &self.data.status
    }

    /// Why the solve is not optimal (the CLI's message), or None.
    #[getter]
    fn reason(&self) -> Option<String> {
        self.data
            .reason
            .as_ref()
            .and_then(|r| r["message"].as_str().map(String::from))
    }

    /// The reason's details as JSON text (`kind` and its fields), or None.
    fn reason_json(&self) -> Option<String> {
        self.data.reason.as_ref().map(|r| r.to_string())
    }

    #[getter]
    fn torque<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.data.torque.clone().map(|t| t.into_pyarray(py))
    }

    #[getter]
    fn contact_forces<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.data.contact_forces.clone().map(|t| t.into_pyarray(py))
    }

    /// Each contact's force on the object, `[k, 3]` in the wrench's (object) frame:
    /// G's force rows times its components (None without forces).
    #[getter]
    fn object_forces<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        let f = self.data.object_forces.as_ref()?;
        let rows: Vec<Vec<f64>> = f.iter().map(|r| r.to_vec()).collect();
        PyArray2::from_vec2(py, &rows).ok()
    }

    #[getter]
    fn contact_dims(&self) -> Vec<usize> {
        self.data.contact_dims.clone()
    }

    #[getter]
    fn objective(&self) -> Option<f64> {
        self.data.objective
    }

    #[getter]
    fn iterations(&self) -> usize {
        self.data.iterations
    }

    #[getter]
    fn active_set(&self) -> Option<Vec<usize>> {
        self.data.active_set.clone()
    }

    #[getter]
    fn solve_time_us(&self) -> f64 {
        self.data.solve_time_us
    }

    #[getter]
    fn joint_names(&self) -> Option<Vec<String>> {
        self.data.joint_names.clone()
    }

    /// With a transmission (an MJCF hand, or `transmission` in the matrix form): the
    /// joint torques τ = T u; `torque` then holds the actuator forces u.
    #[getter]
    fn joint_torque<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.data.joint_torque.clone().map(|t| t.into_pyarray(py))
    }

    /// With a transmission: one name per entry of `torque`.
    #[getter]
    fn actuator_names(&self) -> Option<Vec<String>> {
        self.data.actuator_names.clone()
    }

    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.data.warnings.clone()
    }

    #[getter]
    fn backend(&self) -> &str {
        &self.data.backend
    }

    #[getter]
    fn cones(&self) -> &str {
        &self.data.cones
    }

    /// `‖G f − w‖∞`, `‖Jᵀ f − τ‖∞` and `‖C τ − e‖∞` (None without an answer, or
    /// when the lazy check deferred them).
    #[getter]
    fn residuals<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        if self.data.torque.is_none() || self.data.checks.deferred {
            return Ok(None);
        }
        let c = &self.data.checks;
        let d = PyDict::new(py);
        d.set_item("wrench", c.wrench_residual)?;
        d.set_item("torque", c.torque_residual)?;
        d.set_item("consistency", c.consistency_residual)?;
        Ok(Some(d))
    }

    /// Every check of the Rust diagnostics: residuals, violations, friction margins
    /// per contact, the check's tolerance and how close each check came to it.
    #[getter]
    fn diagnostics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        loads(
            py,
            &serde_json::to_string(&self.data.checks).map_err(invalid)?,
        )
    }

    /// The reason's kind and fields (and `message`), or None.
    #[getter]
    fn reason_detail<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.data
            .reason
            .as_ref()
            .map(|r| loads(py, &r.to_string()))
            .transpose()
    }

    /// `contact_forces` split per contact (None without an answer).
    #[getter]
    fn forces_per_contact<'py>(&self, py: Python<'py>) -> Option<Vec<Bound<'py, PyArray1<f64>>>> {
        let f = self.data.contact_forces.as_ref()?;
        let mut off = 0;
        Some(
            self.data
                .contact_dims
                .iter()
                .map(|&d| {
                    let v = f[off..off + d].to_vec();
                    off += d;
                    v.into_pyarray(py)
                })
                .collect(),
        )
    }

    /// Everything as plain Python (lists, numbers, dicts).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        loads(py, &self.to_json()?)
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let cls = py.get_type::<SolveResult>();
        Ok((cls.getattr("from_json")?, (self.to_json()?,)))
    }

    fn __repr__(&self) -> String {
        match (self.data.objective, &self.data.torque) {
            (Some(o), Some(t)) => format!(
                "Result(status='{}', objective={o:.6e}, torque={t:?})",
                self.data.status
            ),
            _ => format!(
                "Result(status='{}', reason={:?})",
                self.data.status,
                self.reason().unwrap_or_default()
            ),
        }
    }
}

fn loads<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

/// The integer status codes of `solve_batch`.
fn status_code(s: Status) -> i8 {
    match s {
        Status::Optimal => 0,
        Status::AlmostOptimal => 1,
        Status::Infeasible => 2,
        Status::IterationLimit => 3,
        _ => 4,
    }
}

/// Code of an item whose input was rejected.
const INVALID: i8 = 5;

/// The options every grasp of a batch shares (the solver settings come apart, as for
/// [`Solver`], so that an error names the keyword).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BatchSpec {
    contacts: Vec<ContactSpec>,
    torque_weights: Option<Vec<f64>>,
    torque_limits: Option<Vec<Option<grasp_torque::TorqueLimit>>>,
    min_normal_force: Option<serde_json::Value>,
    joint_names: Option<Vec<String>>,
    /// T (joints × actuators), shared by every grasp: τ = T u.
    transmission: Option<Vec<Vec<f64>>>,
    actuator_names: Option<Vec<String>>,
}

/// A batch's grasps, read straight from the caller's arrays.
struct Arrays<'a> {
    g: ArrayView3<'a, f64>,
    jt: ArrayView3<'a, f64>,
    /// `[B, K, 6]` (K = 1 for `[B, 6]`).
    w: ArrayView3<'a, f64>,
    /// `[B, m]`: each grasp's passive joint torques, if given.
    passive: Option<ArrayView2<'a, f64>>,
    /// `[B, m, a]`: each grasp's transmission, if it varies.
    transmissions: Option<ArrayView3<'a, f64>>,
    /// Everything but G, Jᵀ and the wrench, with the settings' overrides applied.
    template: GraspProblem,
}

impl BatchSource for Arrays<'_> {
    fn grasps(&self) -> usize {
        self.g.shape()[0]
    }
    fn wrenches(&self, _: usize) -> usize {
        self.w.shape()[1]
    }
    fn problem(&self, b: usize) -> Result<Cow<'_, GraspProblem>, Error> {
        let (g, jt) = (
            self.g.index_axis(Axis(0), b),
            self.jt.index_axis(Axis(0), b),
        );
        let mut p = self.template.clone();
        p.grasp_matrix = to_matrix(g);
        p.jacobian_transpose = to_matrix(jt);
        p.passive_torque = self.passive.map(|t| t.row(b).to_vec());
        if let (Some(t), Some(tr)) = (&self.transmissions, p.transmission.as_mut()) {
            tr.matrix = to_matrix(t.index_axis(Axis(0), b));
        }
        // Each wrench is checked when it is solved: a bad first wrench fails only itself.
        p.wrench = [0.0; 6];
        Ok(Cow::Owned(p))
    }
    fn wrench(&self, b: usize, k: usize) -> [f64; 6] {
        std::array::from_fn(|i| self.w[(b, k, i)])
    }
}

fn to_matrix(a: ArrayView2<'_, f64>) -> Matrix {
    Matrix::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)])
}

/// A batch's output arrays, each item `b · K + k` written once, by the worker that
/// solved (grasp b, wrench k).
struct Outputs {
    torque: Rows<f64>,
    objective: Rows<f64>,
    residual: Rows<f64>,
    status: Rows<i8>,
    /// `[B, K, n]`, when the caller asked for the contact forces.
    forces: Option<Rows<f64>>,
    wrenches: usize,
}

impl Outputs {
    /// The output arrays for `[B, K, m]` (and `[B, K, n]` contact forces), checked
    /// (shape, C order).
    fn new(
        [b, k, m, n]: [usize; 4],
        torque: &mut PyReadwriteArrayDyn<'_, f64>,
        objective: &mut PyReadwriteArrayDyn<'_, f64>,
        wrench_residual: &mut PyReadwriteArrayDyn<'_, f64>,
        status: &mut PyReadwriteArrayDyn<'_, i8>,
        forces: Option<&mut PyReadwriteArrayDyn<'_, f64>>,
    ) -> PyResult<Self> {
        Ok(Self {
            torque: Rows::new(contiguous_out("torque", torque, &[b, k, m])?, m),
            objective: Rows::new(contiguous_out("objective", objective, &[b, k])?, 1),
            residual: Rows::new(
                contiguous_out("wrench_residual", wrench_residual, &[b, k])?,
                1,
            ),
            status: Rows::new(contiguous_out("status", status, &[b, k])?, 1),
            forces: match forces {
                Some(f) => Some(Rows::new(
                    contiguous_out("contact_forces", f, &[b, k, n])?,
                    n,
                )),
                None => None,
            },
            wrenches: k,
        })
    }

    fn write(&self, b: usize, k: usize, r: Result<&Solution, &Error>) {
        let i = b * self.wrenches + k;
        let (code, objective, residual, answer) = match r {
            Ok(s) if !s.torque.is_empty() => (
                status_code(s.status),
                s.objective,
                s.diagnostics.wrench_residual,
                Some(s),
            ),
            Ok(s) => (status_code(s.status), f64::NAN, f64::NAN, None),
            Err(_) => (INVALID, f64::NAN, f64::NAN, None),
        };
        // SAFETY: each (grasp, wrench) pair is emitted once, so item i is this call's.
        unsafe {
            self.status.item(i)[0] = code;
            self.objective.item(i)[0] = objective;
            self.residual.item(i)[0] = residual;
            let row = self.torque.item(i);
            match answer {
                Some(s) => row.copy_from_slice(&s.torque),
                None => row.fill(f64::NAN),
            }
            if let Some(f) = &self.forces {
                let row = f.item(i);
                match answer.filter(|s| s.contact_forces.len() == row.len()) {
                    Some(s) => row.copy_from_slice(&s.contact_forces),
                    None => row.fill(f64::NAN),
                }
            }
        }
    }
}

/// Checks `W[B, K, 6]` against the batch's B grasps; returns K (at least 1).
fn wrench_count(w: &ArrayView3<'_, f64>, b: usize) -> PyResult<usize> {
    let (bw, k, six) = w.dim();
    if bw != b || six != 6 {
        return Err(invalid(format!(
            "W: expected shape ({b}, 6) or ({b}, K, 6), got {:?}",
            w.shape()
        )));
    }
    if k == 0 {
        return Err(invalid("W: expected at least one wrench per grasp (K ≥ 1)"));
    }
    Ok(k)
}

fn contiguous_out<'py, T: numpy::Element>(
    name: &str,
    a: &'py mut PyReadwriteArrayDyn<'_, T>,
    shape: &[usize],
) -> PyResult<&'py mut [T]> {
    if a.shape() != shape {
        return Err(invalid(format!(
            "{name}: expected an output array of shape {shape:?}, got {:?}",
            a.shape()
        )));
    }
    a.as_slice_mut()
        .map_err(|_| invalid(format!("{name}: expected a C-contiguous output array")))
}

/// The batch: fills the four output arrays; returns `{grasp: message}` for the grasps
/// (or wrenches) whose input was rejected.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn solve_batch(
    py: Python<'_>,
    g: PyReadonlyArray3<'_, f64>,
    jt: PyReadonlyArray3<'_, f64>,
    w: PyReadonlyArray3<'_, f64>,
    passive: Option<PyReadonlyArray2<'_, f64>>,
    transmissions: Option<PyReadonlyArray3<'_, f64>>,
    spec_json: &str,
    settings_json: &str,
    threads: usize,
    warm_start: bool,
    mut torque: PyReadwriteArrayDyn<'_, f64>,
    mut objective: PyReadwriteArrayDyn<'_, f64>,
    mut wrench_residual: PyReadwriteArrayDyn<'_, f64>,
    mut status: PyReadwriteArrayDyn<'_, i8>,
    mut forces: Option<PyReadwriteArrayDyn<'_, f64>>,
) -> PyResult<Vec<(usize, usize, String)>> {
    let spec: BatchSpec = from_keywords(spec_json)?;
    let settings: Settings = from_keywords(settings_json)?;
    let (gv, jv, wv) = (g.as_array(), jt.as_array(), w.as_array());
    let (b, six, n) = gv.dim();
    let (bj, m, nj) = jv.dim();
    if six != 6 {
        return Err(invalid(format!(
            "G: expected shape (B, 6, n), got {:?}",
            gv.shape()
        )));
    }
    if bj != b || nj != n {
        return Err(invalid(format!(
            "JT: expected shape ({b}, m, {n}) to match G {:?}, got {:?}",
            gv.shape(),
            jv.shape()
        )));
    }
    let k = wrench_count(&wv, b)?;
    let passive = passive.as_ref().map(|t| t.as_array());
    if let Some(t) = &passive {
        if t.dim() != (b, m) {
            return Err(invalid(format!(
                "passive_torque: expected shape ({m},) or ({b}, {m}), one per row of JT, got {:?}",
                t.shape()
            )));
        }
    }
    let transmissions = transmissions.as_ref().map(|t| t.as_array());
    let mut shared_transmission = spec.transmission;
    if let Some(t) = &transmissions {
        let (bt, mt, a) = t.dim();
        if bt != b || mt != m || shared_transmission.is_some() {
            return Err(invalid(format!(
                "transmission: expected shape ({m}, a) or ({b}, {m}, a), one row per joint of JT, got {:?}",
                t.shape()
            )));
        }
        // The shared checks (shape, names) see a placeholder of T's shape; each
        // grasp's own T is checked with its grasp.
        shared_transmission = Some(
            (0..m)
                .map(|i| (0..a).map(|j| f64::from(u8::from(i == j))).collect())
                .collect(),
        );
    }
    let contacts = spec
        .contacts
        .iter()
        .enumerate()
        .map(|(i, c)| c.to_model(&format!("contacts[{i}]")))
        .collect::<Result<Vec<_>, _>>()
        .map_err(invalid)?;
    let mut template =
        GraspProblem::new(Matrix::zeros(6, 0), Matrix::zeros(m, 0), [0.0; 6], contacts);
    template.joint_names = spec.joint_names.unwrap_or_default();
    if let Some(t) = shared_transmission {
        let cols = t.first().map_or(0, Vec::len);
        if t.len() != m || t.iter().any(|r| r.len() != cols) {
            return Err(invalid(format!(
                "transmission: expected shape ({m}, a), one row per joint of JT"
            )));
        }
        template.transmission = Some(grasp_torque::problem::Transmission {
            matrix: Matrix::from_fn(m, cols, |i, j| t[i][j]),
            actuator_names: spec.actuator_names.unwrap_or_default(),
        });
    }
    grasp_torque::file::Options {
        min_normal_force: spec.min_normal_force,
        torque_weights: spec.torque_weights,
        torque_limits: spec.torque_limits,
        ..Default::default()
    }
    .apply(&mut template)
    .map_err(invalid)?;
    let config = settings.configure(&mut template)?;
    // What every grasp shares is checked once, against the arrays' shapes: contacts
    // that do not add up to G's columns, or weights of the wrong length, make the
    // whole batch impossible (an error, not B invalid items).
    let mut shared = template.clone();
    shared.grasp_matrix = Matrix::zeros(6, n);
    shared.jacobian_transpose = Matrix::zeros(m, n);
    shared.validate().map_err(invalid)?;
    if threads == 0 {
        return Err(invalid("threads: expected at least 1 worker thread, got 0"));
    }
    // One torque per actuator with a transmission, else per joint.
    let m = template.actuated();
    let out = Outputs::new(
        [b, k, m, n],
        &mut torque,
        &mut objective,
        &mut wrench_residual,
        &mut status,
        forces.as_mut(),
    )?;
    let source = Arrays {
        g: gv,
        jt: jv,
        w: wv,
        passive,
        transmissions,
        template,
    };
    let options = BatchOptions {
        threads: Some(threads),
        warm_start,
    };
    run_batch(py, &source, &config, &options, &out)
}

/// Runs a batch with the GIL released, writing each answer into `out`; returns the
/// rejected items' messages in item order.
///
/// The grasps go in spans of about [`SPAN_SECONDS`], and between spans the GIL is
/// taken back to run Python's signal handlers: Ctrl-C stops a batch of millions of
/// grasps within a span, with the answers of the spans before it written, instead of
/// after the whole batch. Each grasp is solved as in one span (its wrenches together,
/// on a worker's buffers), so the answers are the same bit for bit.
fn run_batch<S: BatchSource>(
    py: Python<'_>,
    source: &S,
    config: &SolverConfig,
    options: &BatchOptions,
    out: &Outputs,
) -> PyResult<Vec<(usize, usize, String)>> {
    let errors = Mutex::new(Vec::new());
    in_spans(py, source.grasps(), |start, len| {
        let span = Span { source, start, len };
        for_each_solution(&span, config, options, |gi, ki, r| {
            let gi = start + gi;
            if let Err(e) = r {
                errors
                    .lock()
                    .unwrap_or_else(|p| p.into_inner())
                    .push((gi, ki, e.to_string()));
            }
            out.write(gi, ki, r);
        })
        .map_err(invalid)
    })?;
    let mut errors = errors.into_inner().unwrap_or_else(|p| p.into_inner());
    errors.sort_by_key(|e| (e.0, e.1));
    Ok(errors)
}

/// Runs `work(start, len)` over the items `0..total` in spans of about
/// [`SPAN_SECONDS`], each with the GIL released, taking it back between spans to run
/// Python's signal handlers: Ctrl-C stops a batch of millions of grasps within a span,
/// with the spans before it done, instead of after the whole batch.
fn in_spans<F>(py: Python<'_>, total: usize, work: F) -> PyResult<()>
where
    F: Fn(usize, usize) -> PyResult<()> + Sync,
{
    let (mut start, mut len) = (0, FIRST_SPAN);
    while start < total {
        len = len.min(total - start);
        let clock = Instant::now();
        py.detach(|| work(start, len))?;
        start += len;
        py.check_signals()?;
        // The next span takes about SPAN_SECONDS at this span's pace (within a factor
        // of 8 of this one, so that one odd span does not swing it far).
        let pace = clock.elapsed().as_secs_f64() / len as f64;
        let next = if pace > 0.0 {
            SPAN_SECONDS / pace
        } else {
            f64::INFINITY
        };
        len = (next.min((8 * len) as f64) as usize).max(len / 8).max(1);
    }
    Ok(())
}

/// An output array filled by parallel workers, `width` entries per item; each item's
/// entries are written by one worker only.
struct Rows<T> {
    ptr: *mut T,
    width: usize,
    items: usize,
}

// SAFETY: workers write disjoint items (`Rows::item`'s contract), and the array outlives
// the work (its borrow is held across it).
unsafe impl<T: Send> Sync for Rows<T> {}

impl<T> Rows<T> {
    fn new(a: &mut [T], width: usize) -> Self {
        Self {
            ptr: a.as_mut_ptr(),
            width,
            items: a.len() / width.max(1),
        }
    }

    /// Item `i`'s entries.
    ///
    /// # Safety
    /// No other reference to item `i` may be live: each item goes to one worker.
    #[allow(clippy::mut_from_ref)]
    unsafe fn item(&self, i: usize) -> &mut [T] {
        assert!(self.width == 0 || i < self.items);
        // SAFETY: i < items, so the item lies within the array; exclusive by contract.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(i * self.width), self.width) }
    }
}

/// How long a batch runs between two looks at Python's signals: Ctrl-C is answered
/// within about this, and a span boundary (the workers waiting for the span's last
/// grasp) costs well under 1 % of it.
const SPAN_SECONDS: f64 = 0.05;

/// The first span's grasps, before the batch's pace is known: a few milliseconds of
/// the cheapest grasps, a fraction of a second of the dearest.
const FIRST_SPAN: usize = 256;

/// Grasps `start .. start + len` of a batch, as a batch of their own.
struct Span<'a, S: ?Sized> {
    source: &'a S,
    start: usize,
    len: usize,
}

impl<S: BatchSource + ?Sized> BatchSource for Span<'_, S> {
    fn grasps(&self) -> usize {
        self.len
    }
    fn wrenches(&self, g: usize) -> usize {
        self.source.wrenches(self.start + g)
    }
    fn problem(&self, g: usize) -> Result<Cow<'_, GraspProblem>, Error> {
        self.source.problem(self.start + g)
    }
    fn wrench(&self, g: usize, k: usize) -> [f64; 6] {
        self.source.wrench(self.start + g, k)
    }
}

/// The options every grasp of a hand's batch shares.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HandSpec {
    contacts: Vec<HandContact>,
    /// The hand form's `hand.gravity`: `[gx, gy, gz]` or `"model"`.
    gravity: Option<serde_json::Value>,
    /// The hand form's `object`: its weight joins every wrench.
    object: Option<HeldObject>,
    torque_weights: Option<Vec<f64>>,
    torque_limits: Option<serde_json::Value>,
    min_normal_force: Option<serde_json::Value>,
}

/// A robot hand (URDF or MJCF), parsed once per process.
#[pyclass(module = "grasp_torque._native", frozen)]
struct Hand {
    robot: Arc<grasp_torque::Robot>,
    path: String,
}

impl Hand {
    /// The hand file's grasps for `spec`, with the solver settings applied.
    fn grasps(
        &self,
        spec: HandSpec,
        settings: &Settings,
    ) -> PyResult<(HandGrasps<'_>, SolverConfig)> {
        let file = grasp_torque::HandFile {
            name: None,
            description: None,
            hand: grasp_torque::hand::HandSpec {
                model: self.path.clone(),
                joint_positions: Default::default(),
                gravity: spec.gravity,
            },
            object_pose: None,
            object: spec.object,
            contacts: spec.contacts,
            wrench: Some(vec![0.0; 6]),
            linearization: None,
            torque_weights: spec.torque_weights,
            torque_limits: spec.torque_limits,
            min_normal_force: spec.min_normal_force,
            initial_torque: None,
            internal_forces: None,
        };
        let mut grasps = file.grasps(&self.robot).map_err(invalid)?;
        let config = settings.configure(grasps.template_mut())?;
        // What every grasp shares is checked once (weights or limits of the wrong
        // length make the batch impossible, not B invalid items).
        let mut shared = grasps.template().clone();
        let n = shared.contacts.iter().map(|c| c.dim()).sum();
        shared.grasp_matrix = Matrix::zeros(6, n);
        shared.jacobian_transpose = Matrix::zeros(shared.joints(), n);
        shared.validate().map_err(invalid)?;
        Ok((grasps, config))
    }
}

#[pymethods]
impl Hand {
    #[new]
    fn new(path: &str) -> PyResult<Self> {
        // (The parser's own messages name the file and line.)
        match std::fs::metadata(path) {
            Err(e) => return Err(invalid(format!("{path}: cannot read the robot file: {e}"))),
            Ok(m) if m.is_dir() => {
                return Err(invalid(format!(
                    "{path}: expected a URDF or MJCF file, got a directory"
                )))
            }
            Ok(_) => {}
        }
        let robot = parser().robot(Path::new(path)).map_err(invalid)?;
        Ok(Self {
            robot,
            path: path.to_string(),
        })
    }

    /// `<robot name>` (or the MJCF model's name).
    #[getter]
    fn name(&self) -> &str {
        &self.robot.name
    }

    /// The independent joints (neither fixed nor mimic), in file order: the columns of
    /// `joint_positions`.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        let r = &self.robot;
        r.independent
            .iter()
            .map(|&j| r.joints[j].name.clone())
            .collect()
    }

    /// The links (MJCF bodies), in file order.
    #[getter]
    fn links(&self) -> Vec<String> {
        self.robot.links.clone()
    }

    /// The MJCF sites.
    #[getter]
    fn sites(&self) -> Vec<String> {
        self.robot.sites.iter().map(|s| s.name.clone()).collect()
    }

    /// The warnings of reading the file.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.robot.warnings.clone()
    }

    /// What a batch with these contacts solves for: `(names, actuated, n)`, the names
    /// of the problem's joints (or actuators, `actuated` true) in output order, and the
    /// number of contact force components.
    fn layout(&self, spec_json: &str, settings_json: &str) -> PyResult<(Vec<String>, bool, usize)> {
        let settings: Settings = from_keywords(settings_json)?;
        let (grasps, _) = self.grasps(from_keywords(spec_json)?, &settings)?;
        let t = grasps.template();
        let n = t.contacts.iter().map(|c| c.dim()).sum();
        Ok(match &t.transmission {
            Some(tr) => (tr.actuator_names.clone(), true, n),
            None => (t.joint_names.clone(), false, n),
        })
    }

    /// The batch (as `solve_batch`): grasp b is the hand at `q[b]`
    /// (`joint_positions`), its contacts at `positions[b]` with `normals[b]` (a row of
    /// NaN: the contact's own), the object at `poses[b]` (`[x, y, z, qw, qx, qy, qz]`),
    /// under `gravity[b]` when given per grasp.
    #[allow(clippy::too_many_arguments)]
    fn solve_batch(
        &self,
        py: Python<'_>,
        q: PyReadonlyArray2<'_, f64>,
        w: PyReadonlyArray3<'_, f64>,
        positions: Option<PyReadonlyArray3<'_, f64>>,
        normals: Option<PyReadonlyArray3<'_, f64>>,
        poses: Option<PyReadonlyArray2<'_, f64>>,
        gravity: Option<PyReadonlyArray2<'_, f64>>,
        spec_json: &str,
        settings_json: &str,
        threads: usize,
        warm_start: bool,
        mut torque: PyReadwriteArrayDyn<'_, f64>,
        mut objective: PyReadwriteArrayDyn<'_, f64>,
        mut wrench_residual: PyReadwriteArrayDyn<'_, f64>,
        mut status: PyReadwriteArrayDyn<'_, i8>,
        mut forces: Option<PyReadwriteArrayDyn<'_, f64>>,
    ) -> PyResult<Vec<(usize, usize, String)>> {
        let settings: Settings = from_keywords(settings_json)?;
        let (grasps, config) = self.grasps(from_keywords(spec_json)?, &settings)?;
        let wv = w.as_array();
        let source = Posed::new(grasps, &q, Some(wv), &positions, &normals, &poses, &gravity)?;
        let b = source.q.nrows();
        let k = wrench_count(&wv, b)?;
        if threads == 0 {
            return Err(invalid("threads: expected at least 1 worker thread, got 0"));
        }
        let t = source.grasps.template();
        let (m, n) = (t.actuated(), t.contacts.iter().map(|c| c.dim()).sum());
        let out = Outputs::new(
            [b, k, m, n],
            &mut torque,
            &mut objective,
            &mut wrench_residual,
            &mut status,
            forces.as_mut(),
        )?;
        let options = BatchOptions {
            threads: Some(threads),
            warm_start,
        };
        run_batch(py, &source, &config, &options, &out)
    }

    /// What every grasp of a batch with these contacts shares, as JSON: the joint and
    /// actuator names, the transmission T (joints × actuators) or null, whether T
    /// varies with the configuration (then each grasp has its own), and n.
    fn describe(&self, spec_json: &str) -> PyResult<String> {
        let (grasps, _) = self.grasps(from_keywords(spec_json)?, &Settings::default())?;
        let t = grasps.template();
        let tr = t.transmission.as_ref();
        let value = serde_json::json!({
            "joint_names": t.joint_names,
            "actuator_names": tr.map(|tr| tr.actuator_names.clone()),
            "transmission": tr.map(|tr| {
                (0..tr.matrix.nrows()).map(|i| tr.matrix.row(i).to_vec()).collect::<Vec<_>>()
            }),
            "force_dim": t.contacts.iter().map(|c| c.dim()).sum::<usize>(),
            "transmission_varies": grasps.transmission_varies(),
            "torque_limits": t.torque_limits,
        });
        Ok(value.to_string())
    }

    /// Each grasp's G, Jᵀ and passive joint torques (the springs' and, with gravity, the
    /// links' weight; zero without either), written into `g[b]`, `jt[b]` and `tp[b]`,
    /// and with `object` the wrench its weight asks of the contacts into `ow[b]` (NaN
    /// for a rejected grasp, whose message is returned with its index).
    #[allow(clippy::too_many_arguments)]
    fn arrays(
        &self,
        py: Python<'_>,
        q: PyReadonlyArray2<'_, f64>,
        positions: Option<PyReadonlyArray3<'_, f64>>,
        normals: Option<PyReadonlyArray3<'_, f64>>,
        poses: Option<PyReadonlyArray2<'_, f64>>,
        gravity: Option<PyReadonlyArray2<'_, f64>>,
        spec_json: &str,
        threads: usize,
        mut g: PyReadwriteArrayDyn<'_, f64>,
        mut jt: PyReadwriteArrayDyn<'_, f64>,
        mut tp: PyReadwriteArrayDyn<'_, f64>,
        mut tr: Option<PyReadwriteArrayDyn<'_, f64>>,
        mut ow: Option<PyReadwriteArrayDyn<'_, f64>>,
    ) -> PyResult<Vec<(usize, String)>> {
        if threads == 0 {
            return Err(invalid("threads: expected at least 1 worker thread, got 0"));
        }
        let (grasps, _) = self.grasps(from_keywords(spec_json)?, &Settings::default())?;
        let source = Posed::new(grasps, &q, None, &positions, &normals, &poses, &gravity)?;
        let b = source.q.nrows();
        let n = source
            .grasps
            .template()
            .contacts
            .iter()
            .map(|c| c.dim())
            .sum();
        let m = source.grasps.template().joints();
        let g = contiguous_out("G", &mut g, &[b, 6, n])?;
        let jt = contiguous_out("JT", &mut jt, &[b, m, n])?;
        let tp = contiguous_out("passive_torque", &mut tp, &[b, m])?;
        // Each grasp's T, when it varies with the configuration.
        let a = source.grasps.template().actuated();
        let tr = match tr.as_mut() {
            Some(t) => Some(Rows::new(
                contiguous_out("transmission", t, &[b, m, a])?,
                m * a,
            )),
            None => None,
        };
        let ow = match ow.as_mut() {
            Some(w) => Some(Rows::new(contiguous_out("object_wrench", w, &[b, 6])?, 6)),
            None => None,
        };
        let (g, jt, tp) = (Rows::new(g, 6 * n), Rows::new(jt, m * n), Rows::new(tp, m));
        let options = BatchOptions {
            threads: Some(threads),
            ..BatchOptions::default()
        };
        let errors = Mutex::new(Vec::new());
        in_spans(py, b, |start, len| {
            for_each_index(len, &options, |i| {
                let i = start + i;
                // SAFETY: each index is posed once, by one worker.
                let (gb, jb, tb) = unsafe { (g.item(i), jt.item(i), tp.item(i)) };
                let (trb, owb) = unsafe {
                    (
                        tr.as_ref().map(|t| t.item(i)),
                        ow.as_ref().map(|w| w.item(i)),
                    )
                };
                match source.problem(i) {
                    Ok(p) => {
                        gb.copy_from_slice(p.grasp_matrix.as_slice());
                        jb.copy_from_slice(p.jacobian_transpose.as_slice());
                        match &p.passive_torque {
                            Some(t) => tb.copy_from_slice(t),
                            None => tb.fill(0.0),
                        }
                        if let (Some(out), Some(t)) = (trb, &p.transmission) {
                            out.copy_from_slice(t.matrix.as_slice());
                        }
                        if let Some(out) = owb {
                            out.copy_from_slice(&source.wrench(i, 0));
                        }
                    }
                    Err(e) => {
                        for out in [Some(gb), Some(jb), Some(tb), trb, owb]
                            .into_iter()
                            .flatten()
                        {
                            out.fill(f64::NAN);
                        }
                        errors
                            .lock()
                            .unwrap_or_else(|p| p.into_inner())
                            .push((i, e.to_string()));
                    }
                }
            })
            .map_err(invalid)
        })?;
        let mut errors = errors.into_inner().unwrap_or_else(|p| p.into_inner());
        errors.sort_by_key(|e| e.0);
        Ok(errors)
    }

    /// Where the frames `names` (MJCF sites, or links) are at each row of `q`, in the
    /// model's root frame: origins into `pos[b, i]`, rotation matrices (columns: the
    /// frame's x, y, z axes) into `rot[b, i]`.
    fn frames(
        &self,
        py: Python<'_>,
        q: PyReadonlyArray2<'_, f64>,
        names: Vec<String>,
        mut pos: PyReadwriteArrayDyn<'_, f64>,
        mut rot: PyReadwriteArrayDyn<'_, f64>,
        threads: usize,
    ) -> PyResult<()> {
        if threads == 0 {
            return Err(invalid("threads: expected at least 1 worker thread, got 0"));
        }
        let r = &self.robot;
        let q = q.as_array();
        let (b, k) = (q.nrows(), names.len());
        joint_columns(&q, r.independent.len())?;
        let mut needed = vec![false; r.links.len()];
        let frames = names
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let f = r.named_frame(name, &format!("names[{i}]"));
                if let Ok((link, _)) = f {
                    r.mark_ancestors(link, &mut needed);
                }
                f
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(invalid)?;
        let most = grasp_torque::problem::MAX_MAGNITUDE;
        if let Some(((row, col), v)) = q
            .indexed_iter()
            .find(|(_, v)| !v.is_finite() || v.abs() > most)
        {
            return Err(invalid(format!(
                "joint_positions[{row}][{col}] ({}): expected a finite position of magnitude at most {most:e}, got {v}",
                r.joints[r.independent[col]].name
            )));
        }
        let pos = contiguous_out("positions", &mut pos, &[b, k, 3])?;
        let rot = contiguous_out("rotations", &mut rot, &[b, k, 3, 3])?;
        if k == 0 {
            // No frames asked for: the (B, 0, 3) and (B, 0, 3, 3) outputs are complete.
            return Ok(());
        }
        let (pos, rot) = (Rows::new(pos, 3 * k), Rows::new(rot, 9 * k));
        let options = BatchOptions {
            threads: Some(threads),
            ..BatchOptions::default()
        };
        in_spans(py, b, |start, len| {
            for_each_index(len, &options, |row| {
                let row = start + row;
                let qb: Vec<f64> = q.row(row).to_vec();
                let pose = r.pose_of(&qb, &needed);
                // SAFETY: each row is placed once, by one worker.
                let (pb, rb) = unsafe { (pos.item(row), rot.item(row)) };
                for (i, &(link, offset)) in frames.iter().enumerate() {
                    let x = pose.links[link] * offset;
                    pb[3 * i..3 * i + 3].copy_from_slice(&x.translation.to_array());
                    let m = x.rotation.to_rotation_matrix();
                    rb[9 * i..9 * i + 9].copy_from_slice(m.as_flattened());
                }
            })
            .map_err(invalid)
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "Hand({:?}: {}, {} joints)",
            self.path,
            self.robot.name,
            self.robot.independent.len()
        )
    }
}

/// `q` has one column per independent joint of the hand.
fn joint_columns(q: &ArrayView2<'_, f64>, joints: usize) -> PyResult<()> {
    if q.ncols() != joints {
        return Err(invalid(format!(
            "joint_positions: expected shape (B, {joints}), one column per joint of Hand.joint_names, got {:?}",
            q.shape()
        )));
    }
    Ok(())
}

/// A hand's batch: grasp b posed from row b of the caller's arrays.
struct Posed<'a> {
    grasps: HandGrasps<'a>,
    q: ArrayView2<'a, f64>,
    /// `[B, K, 6]`; none when only G and Jᵀ are wanted.
    w: Option<ArrayView3<'a, f64>>,
    positions: Option<ArrayView3<'a, f64>>,
    normals: Option<ArrayView3<'a, f64>>,
    poses: Option<ArrayView2<'a, f64>>,
    /// `[B, 3]`: each grasp's gravity in the root frame, if given per grasp.
    gravity: Option<ArrayView2<'a, f64>>,
}

impl<'a> Posed<'a> {
    /// Checks the arrays' shapes against the hand and the contacts.
    fn new(
        grasps: HandGrasps<'a>,
        q: &'a PyReadonlyArray2<'_, f64>,
        w: Option<ArrayView3<'a, f64>>,
        positions: &'a Option<PyReadonlyArray3<'_, f64>>,
        normals: &'a Option<PyReadonlyArray3<'_, f64>>,
        poses: &'a Option<PyReadonlyArray2<'_, f64>>,
        gravity: &'a Option<PyReadonlyArray2<'_, f64>>,
    ) -> PyResult<Self> {
        let q = q.as_array();
        let b = q.nrows();
        joint_columns(&q, grasps.robot().independent.len())?;
        let n = grasps.template().contacts.len();
        let (positions, normals) = (
            positions.as_ref().map(|a| a.as_array()),
            normals.as_ref().map(|a| a.as_array()),
        );
        for (name, a) in [("positions", &positions), ("normals", &normals)] {
            if let Some(a) = a {
                if a.dim() != (b, n, 3) {
                    return Err(invalid(format!(
                        "{name}: expected shape ({b}, {n}, 3), one row per contact, got {:?}",
                        a.shape()
                    )));
                }
            }
        }
        let poses = poses.as_ref().map(|a| a.as_array());
        if let Some(o) = &poses {
            if o.dim() != (b, 7) {
                return Err(invalid(format!(
                    "object_pose: expected shape (7,) or ({b}, 7), [x, y, z, qw, qx, qy, qz], got {:?}",
                    o.shape()
                )));
            }
        }
        let gravity = gravity.as_ref().map(|a| a.as_array());
        if let Some(g) = &gravity {
            if g.dim() != (b, 3) {
                return Err(invalid(format!(
                    "gravity: expected shape (3,) or ({b}, 3), [gx, gy, gz] in the root frame, got {:?}",
                    g.shape()
                )));
            }
        }
        Ok(Self {
            grasps,
            q,
            w,
            positions,
            normals,
            poses,
            gravity,
        })
    }
}

/// Row `b` of a `[B, n, 3]` array as one optional point per contact: a row of NaN is
/// `None` (the contact's own); any other row is given, and checked as the file's.
fn rows3(a: &Option<ArrayView3<'_, f64>>, b: usize) -> Option<Vec<Option<[f64; 3]>>> {
    a.as_ref().map(|a| {
        a.index_axis(Axis(0), b)
            .outer_iter()
            .map(|r| {
                let v = [r[0], r[1], r[2]];
                (!v.iter().all(|x| x.is_nan())).then_some(v)
            })
            .collect()
    })
}

impl BatchSource for Posed<'_> {
    fn grasps(&self) -> usize {
        self.q.nrows()
    }
    fn wrenches(&self, _: usize) -> usize {
        self.w.as_ref().map_or(1, |w| w.shape()[1])
    }
    fn problem(&self, b: usize) -> Result<Cow<'_, GraspProblem>, Error> {
        let q = self.q.row(b).to_vec();
        let (positions, normals) = (rows3(&self.positions, b), rows3(&self.normals, b));
        let mut p = self
            .grasps
            .pose(&GraspPose {
                joint_positions: &q,
                positions: positions.as_deref(),
                normals: normals.as_deref(),
                ..self.placement(b)
            })
            .map_err(Error::from)?;
        // Each wrench is checked when it is solved: a bad first wrench fails only itself.
        p.wrench = [0.0; 6];
        Ok(Cow::Owned(p))
    }
    fn wrench(&self, b: usize, k: usize) -> [f64; 6] {
        let mut w = self
            .w
            .as_ref()
            .map_or([0.0; 6], |w| std::array::from_fn(|i| w[(b, k, i)]));
        // (Only called once grasp b was posed, so its pose and gravity were checked.)
        if let Some(weight) = self.grasps.object_weight(&self.placement(b)) {
            for (w, v) in w.iter_mut().zip(weight) {
                *w = grasp_torque::problem::flush_subnormal(*w + v);
            }
        }
        w
    }
}

impl Posed<'_> {
    /// Grasp b's object pose and gravity, when given per grasp.
    fn placement(&self, b: usize) -> GraspPose<'static> {
        GraspPose {
            object_pose: self.poses.as_ref().map(|o| ObjectPose {
                position: [o[(b, 0)], o[(b, 1)], o[(b, 2)]],
                quaternion: [o[(b, 3)], o[(b, 4)], o[(b, 5)], o[(b, 6)]],
            }),
            gravity: self
                .gravity
                .as_ref()
                .map(|g| [g[(b, 0)], g[(b, 1)], g[(b, 2)]]),
            ..GraspPose::default()
        }
    }
}

/// The number of cores rayon would use.
#[pyfunction]
fn default_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The backends compiled into this build.
#[pyfunction]
fn backends() -> Vec<&'static str> {
    Backend::compiled().map(|b| b.name()).collect()
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Problem>()?;
    m.add_class::<Solver>()?;
    m.add_class::<SolveResult>()?;
    m.add_class::<Hand>()?;
    m.add_function(wrap_pyfunction!(solve_batch, m)?)?;
    m.add_function(wrap_pyfunction!(default_threads, m)?)?;
    m.add_function(wrap_pyfunction!(backends, m)?)?;
    m.add("INVALID", INVALID)?;
    m.add("MAX_THREADS", grasp_torque::batch::MAX_THREADS)?;
    m.add("MAX_JOINTS", grasp_torque::problem::MAX_JOINTS)?;
    m.add("MAX_CONTACTS", grasp_torque::problem::MAX_CONTACTS)?;
    m.add("VERSION", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
