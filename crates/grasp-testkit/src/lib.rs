//! Synthetic but physically sensible grasps, for property tests and benchmarks.
//!
//! A sphere of radius 3–6 cm at the origin is held by 2–5 fingers, one fingertip
//! contact each, spread around it; each finger is a chain of 2–4 joints whose axes are
//! roughly perpendicular to the approach direction (flexion) with one abduction joint
//! at the base. The wrench holds 50–500 g against gravity, plus a small disturbance.
//! Everything follows from a seed through a small fixed PRNG, so a failing case is
//! reproducible from its seed alone.

use grasp_core::cone::Linearization;
use grasp_io::file::ModelName;
use grasp_io::geometry::{FingerSpec, GeometricContact, GeometryFile, JointSpec, JointType};

/// Which contact models the generator may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelMix {
    /// All four models, chosen per contact.
    Mixed,
    /// One model for every contact.
    Only(ModelName),
}

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SynthSpec {
    /// Fingers (= contacts), 2–5 when random.
    pub fingers: Option<usize>,
    /// Joints per finger, 2–4 when random.
    pub joints_per_finger: Option<usize>,
    /// Contact models.
    pub models: ModelMix,
    /// Linearisation written into the problem.
    pub linearization: Linearization,
}

impl Default for SynthSpec {
    fn default() -> Self {
        Self {
            fingers: None,
            joints_per_finger: None,
            models: ModelMix::Mixed,
            linearization: Linearization::default(),
        }
    }
}

/// splitmix64: tiny, fixed, good enough for test data.
pub struct Rng(pub u64);

impl Rng {
    /// 64 random bits.
    pub fn bits(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.bits() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in `lo..=hi`.
    pub fn int(&mut self, lo: usize, hi: usize) -> usize {
        lo + (self.bits() % (hi - lo + 1) as u64) as usize
    }
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / l, v[1] / l, v[2] / l]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A grasp in geometry form from `seed`.
pub fn synthetic_grasp(seed: u64, spec: &SynthSpec) -> GeometryFile {
    let mut rng = Rng(seed ^ 0x6a09_e667_f3bc_c908);
    let nf = spec.fingers.unwrap_or_else(|| rng.int(2, 5));
    let radius = rng.uniform(0.03, 0.06);
    let mass = rng.uniform(0.05, 0.5);
    let phase = rng.uniform(0.0, std::f64::consts::TAU);
    let mut contacts = Vec::with_capacity(nf);
    let mut fingers = Vec::with_capacity(nf);
    for k in 0..nf {
        let nj = spec.joints_per_finger.unwrap_or_else(|| rng.int(2, 4));
        // Spread around the equator, tilted up or down a little.
        let az = phase + std::f64::consts::TAU * k as f64 / nf as f64 + rng.uniform(-0.3, 0.3);
        let el = rng.uniform(-0.5, 0.5);
        let u = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
        let p = [radius * u[0], radius * u[1], radius * u[2]];
        let model = match spec.models {
            ModelMix::Only(m) => m,
            ModelMix::Mixed => [
                ModelName::Fpc,
                ModelName::Pcwf,
                ModelName::Sfcl,
                ModelName::Sfce,
            ][rng.int(0, 3)],
        };
        let mu = rng.uniform(0.3, 1.0);
        let mu_t = rng.uniform(0.005, 0.03);
        contacts.push(GeometricContact {
            name: None,
            position: p,
            normal: [-u[0], -u[1], -u[2]],
            model,
            mu: (model != ModelName::Fpc).then_some(mu),
            mu_torsion: matches!(model, ModelName::Sfcl | ModelName::Sfce).then_some(mu_t),
            finger: Some(k),
            link: None,
        });
        // Joints from the palm side toward the fingertip, 2–5 cm apart.
        let side = normalize(cross(u, [0.0, 0.0, 1.0]));
        let mut joints = Vec::with_capacity(nj);
        for j in 0..nj {
            let back = rng.uniform(0.02, 0.05) * (nj - j) as f64;
            let o = [
                p[0] + u[0] * back + rng.uniform(-0.01, 0.01),
                p[1] + u[1] * back + rng.uniform(-0.01, 0.01),
                p[2] + u[2] * back + rng.uniform(-0.01, 0.01) + 0.02,
            ];
            let axis = if j == 0 {
                normalize([
                    u[0] * 0.1 + rng.uniform(-0.2, 0.2),
                    u[1] * 0.1 + rng.uniform(-0.2, 0.2),
                    1.0,
                ])
            } else {
                normalize([
                    side[0] + rng.uniform(-0.2, 0.2),
                    side[1] + rng.uniform(-0.2, 0.2),
                    side[2] + rng.uniform(-0.2, 0.2),
                ])
            };
            joints.push(JointSpec {
                name: None,
                origin: o,
                axis,
                kind: JointType::Revolute,
            });
        }
        fingers.push(FingerSpec { name: None, joints });
    }
    let g = 9.81;
    let wrench = vec![
        rng.uniform(-0.1, 0.1) * mass * g,
        rng.uniform(-0.1, 0.1) * mass * g,
        mass * g,
        rng.uniform(-0.01, 0.01) * mass * g * radius * 10.0,
        rng.uniform(-0.01, 0.01) * mass * g * radius * 10.0,
        rng.uniform(-0.01, 0.01) * mass * g * radius * 10.0,
    ];
    GeometryFile {
        name: Some(format!("synthetic-{seed}")),
        description: Some("grasp_testkit::synthetic_grasp".into()),
        contacts,
        fingers,
        wrench,
        linearization: Some(spec.linearization),
        torque_weights: None,
        torque_limits: None,
        min_normal_force: None,
        initial_torque: None,
        internal_forces: None,
    }
}

/// The exact-cone robustness sweep's grasp: [`synthetic_grasp`] at the default spec,
/// every friction coefficient scaled by `friction`, and the wrench moved by up to half
/// its largest component per entry (seeded by `seed`).
pub fn sweep_grasp(seed: u64, friction: f64) -> grasp_core::GraspProblem {
    use grasp_core::ContactModel;
    let mut p = synthetic_grasp(seed, &SynthSpec::default())
        .into_problem()
        .expect("a synthetic grasp is valid");
    for c in &mut p.contacts {
        *c = match *c {
            ContactModel::Fpc => ContactModel::Fpc,
            ContactModel::Pcwf { mu } => ContactModel::Pcwf { mu: mu * friction },
            ContactModel::SfcLinear { mu, mu_torsion } => ContactModel::SfcLinear {
                mu: mu * friction,
                mu_torsion: mu_torsion * friction,
            },
            ContactModel::SfcElliptic { mu, mu_torsion } => ContactModel::SfcElliptic {
                mu: mu * friction,
                mu_torsion: mu_torsion * friction,
            },
        };
    }
    let mut rng = Rng(seed ^ 0x5eed);
    let size = p.wrench.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for w in &mut p.wrench {
        *w += rng.uniform(-0.5, 0.5) * size;
    }
    p
}

/// The JSON files of the bundled fixtures in each of `dirs` (relative to `fixtures/`,
/// `""` for the top level), sorted by name within each folder, folders in the order
/// given.
pub fn fixture_paths(dirs: &[&str]) -> Vec<std::path::PathBuf> {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures");
    let mut out = Vec::new();
    for dir in dirs {
        let mut files: Vec<_> = std::fs::read_dir(format!("{root}/{dir}"))
            .expect("a fixtures folder")
            .map(|e| e.expect("a fixtures entry").path())
            .filter(|p| p.extension().is_some_and(|x| x == "json"))
            .collect();
        files.sort();
        out.extend(files);
    }
    out
}

/// The reference cases of `shared/reference/cases.json` (copied to `tests/data/`).
pub fn reference_cases() -> Vec<serde_json::Value> {
    cases_in("reference-cases.json")
}

/// Grasps in the reference cases' format with optima from cvxpy and DAQP, written by
/// `scripts/oracle_cases.py`: `tests/data/oracle-cases.json`, or the file
/// `GRASP_ORACLE_CASES` names (another draw of the script, or grasps of your own).
pub fn oracle_cases() -> Vec<serde_json::Value> {
    match std::env::var("GRASP_ORACLE_CASES") {
        Ok(path) => cases_at(&path),
        Err(_) => cases_in("oracle-cases.json"),
    }
}

/// The case list of `tests/data/NAME`.
fn cases_in(name: &str) -> Vec<serde_json::Value> {
    cases_at(&format!(
        "{}/../../tests/data/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
}

/// The case list of the file at `path`.
fn cases_at(path: &str) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(path).expect("a case file");
    let v: serde_json::Value = serde_json::from_str(&text).expect("a case file's JSON");
    v["cases"].as_array().expect("a case list").clone()
}

/// The reference model's conventions (`shared/reference/README.md`): passive internal
/// forces by the Euclidean `A⁺` (item 1) and SFCe latitudes at the paper's eq. 13
/// angles (item 4). They differ from this project's unit-invariant defaults only where
/// `[G; Jᵀ]` has a null space, or for SFCe contacts.
pub fn as_reference(mut p: grasp_core::GraspProblem) -> grasp_core::GraspProblem {
    p.internal_forces = grasp_core::InternalForces::Euclidean;
    p.linearization.sfce_spacing = grasp_core::SfceSpacing::Paper;
    p
}

/// A reference case's matrix-form problem, with the reference conventions.
pub fn reference_problem(problem: &serde_json::Value) -> grasp_core::GraspProblem {
    as_reference(matrix_problem(problem))
}

/// A reference case's geometry-form problem, with the reference conventions.
pub fn reference_geometry(geometry: &serde_json::Value) -> grasp_core::GraspProblem {
    as_reference(geometry_problem(geometry))
}

/// A case's matrix-form problem, with this project's defaults.
pub fn matrix_problem(problem: &serde_json::Value) -> grasp_core::GraspProblem {
    let file: grasp_io::MatrixFile =
        serde_json::from_value(problem.clone()).expect("a matrix-form problem");
    file.into_problem().expect("a valid problem")
}

/// A case's geometry-form problem, with this project's defaults.
pub fn geometry_problem(geometry: &serde_json::Value) -> grasp_core::GraspProblem {
    let geo: grasp_io::GeometryFile =
        serde_json::from_value(geometry.clone()).expect("a geometry-form problem");
    geo.into_problem().expect("a valid problem")
}

/// The same problem with lengths multiplied by `l` (m → mm: 1000) and forces by `f`
/// (N → mN: 1000): the moment rows of G and the wrench, every row of Jᵀ (each torque
/// scales by `l·f`, as for revolute joints), the `mz` columns, `mu_torsion`, the
/// minimum normal forces, the torque limits and the passive torques. σ scales by
/// `(l f)²` exactly.
pub fn rescale(p: &grasp_core::GraspProblem, l: f64, f: f64) -> grasp_core::GraspProblem {
    let mut q = p.clone();
    let mut mz_cols = Vec::new();
    let mut off = 0;
    for c in &mut q.contacts {
        if let grasp_core::ContactModel::SfcLinear { mu_torsion, .. }
        | grasp_core::ContactModel::SfcElliptic { mu_torsion, .. } = c
        {
            *mu_torsion *= l;
            mz_cols.push(off + 3);
        }
        off += c.dim();
    }
    let n = q.force_dim();
    for j in 0..n {
        let col = if mz_cols.contains(&j) { 1.0 / l } else { 1.0 };
        for i in 0..6 {
            let row = if i >= 3 { l } else { 1.0 };
            q.grasp_matrix[(i, j)] *= row * col;
        }
        for i in 0..q.joints() {
            q.jacobian_transpose[(i, j)] *= l * col;
        }
    }
    for (i, w) in q.wrench.iter_mut().enumerate() {
        *w *= f * if i >= 3 { l } else { 1.0 };
    }
    if let Some(fmin) = &mut q.min_normal_force {
        fmin.iter_mut().for_each(|v| *v *= f);
    }
    if let Some(lim) = &mut q.torque_limits {
        lim.iter_mut().flatten().for_each(|v| *v = v.scaled(l * f));
    }
    if let Some(tp) = &mut q.passive_torque {
        tp.iter_mut().for_each(|v| *v *= l * f);
    }
    q
}
