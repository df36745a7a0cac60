//! A grasp-torque problem in matrix form, as the paper states it (section 5).

use crate::cone::Linearization;
use crate::contact::ContactModel;
use crate::error::ProblemError;
use crate::matrix::Matrix;
use crate::model::InternalForces;
use std::fmt;

/// Most inequality rows a problem may have.
pub const MAX_ROWS: usize = 1 << 20;

/// Most numbers in the dense row matrices (H, S Z1 and S): rows × (joints + 6 + force
/// components), 256 MiB of `f64`.
pub const MAX_MATRIX_ENTRIES: usize = 1 << 25;

/// Most joints (rows of Jᵀ). The model's decomposition is dense and cubic in size: at
/// the limits it takes about a second.
pub const MAX_JOINTS: usize = 256;

/// Most contacts.
pub const MAX_CONTACTS: usize = 256;

/// Most contact force components (columns of G).
pub const MAX_FORCE_COMPONENTS: usize = 1024;

/// Largest magnitude of any number in G, Jᵀ, the wrench, torque limits, minimum
/// normal forces and geometry. Results are unit-invariant within it. Nonzero numbers
/// must also be normal (at least `f64::MIN_POSITIVE`, about 2.2e-308, in magnitude):
/// subnormal numbers carry fewer significant digits, so no answer built on them could
/// pass the residual checks.
pub const MAX_MAGNITUDE: f64 = 1e12;

/// Whether `v` is in the input domain: zero, or normal with magnitude at most
/// [`MAX_MAGNITUDE`] (false for NaN and infinities).
#[inline]
pub fn in_domain(v: f64) -> bool {
    // (Non-short-circuit: the validation of a matrix then vectorises.)
    let a = v.abs();
    (a <= MAX_MAGNITUDE) & ((a >= f64::MIN_POSITIVE) | (a == 0.0))
}

/// `x`, or 0 where it is subnormal: for G and Jᵀ computed from geometry, whose
/// rounding error is far above the subnormal range, so that a product of small but
/// valid inputs is not rejected by [`in_domain`].
pub fn flush_subnormal(x: f64) -> f64 {
    if x.is_subnormal() {
        0.0
    } else {
        x
    }
}

/// A limit as the file gives it, for error messages: `2.5` or `[0.0, null]`.
fn limit_json(l: TorqueLimit) -> String {
    let side = |v: Option<f64>| v.map_or("null".to_string(), |v| format!("{v:?}"));
    match l {
        TorqueLimit::Symmetric(t) => format!("{t:?}"),
        TorqueLimit::Range(lo, hi) => format!("[{}, {}]", side(lo), side(hi)),
    }
}

/// What [`in_domain`] expects, for error messages.
pub const DOMAIN: &str =
    "a finite number of magnitude at most 1e12, and 0 or at least 2.2e-308 (not subnormal)";

/// Smallest and largest torque weight.
pub const WEIGHT_RANGE: (f64, f64) = (1e-12, 1e12);

/// Largest ratio between two torque weights. The native solver works in `√w_j τ_j`;
/// beyond this the consistency equalities lose accuracy in those coordinates
/// (a ratio of 1e18 left `‖C τ − e‖∞` at 1e-6).
pub const MAX_WEIGHT_RATIO: f64 = 1e8;

/// One joint's (or actuator's) torque limit. In files: a number `t` for `|τ| ≤ t`, or
/// `[lower, upper]` for `lower ≤ τ ≤ upper`, either side `null` for none (an actuator
/// whose range is not symmetric: a tendon that only pulls is `[0, f_max]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TorqueLimit {
    /// `|τ| ≤ t`, with `t > 0`.
    Symmetric(f64),
    /// `lower ≤ τ ≤ upper`; `None` is no bound on that side (both `None`: no limit),
    /// and `lower < upper`. Neither side needs to be of either sign.
    Range(Option<f64>, Option<f64>),
}

impl TorqueLimit {
    /// The lower bound, if any.
    pub fn lower(self) -> Option<f64> {
        match self {
            TorqueLimit::Symmetric(t) => Some(-t),
            TorqueLimit::Range(lo, _) => lo,
        }
    }

    /// The upper bound, if any.
    pub fn upper(self) -> Option<f64> {
        match self {
            TorqueLimit::Symmetric(t) => Some(t),
            TorqueLimit::Range(_, hi) => hi,
        }
    }

    /// `(lower, upper)`, an open side infinite.
    #[inline]
    pub fn bounds(self) -> (f64, f64) {
        match self {
            TorqueLimit::Symmetric(t) => (-t, t),
            TorqueLimit::Range(lo, hi) => {
                (lo.unwrap_or(f64::NEG_INFINITY), hi.unwrap_or(f64::INFINITY))
            }
        }
    }

    /// The limit with both bounds scaled by `f > 0` (a change of torque unit).
    pub fn scaled(self, f: f64) -> Self {
        match self {
            TorqueLimit::Symmetric(t) => TorqueLimit::Symmetric(t * f),
            TorqueLimit::Range(lo, hi) => TorqueLimit::Range(lo.map(|v| v * f), hi.map(|v| v * f)),
        }
    }

    /// The limit as a constraint on the variable `x`, its numbers written by `num`:
    /// `|x| ≤ t`, `lo ≤ x ≤ hi`, `x ≥ lo` or `x ≤ hi`.
    pub fn describe(self, x: &str, num: impl Fn(f64) -> String) -> String {
        match self {
            TorqueLimit::Symmetric(t) => format!("|{x}| ≤ {}", num(t)),
            TorqueLimit::Range(Some(lo), Some(hi)) => format!("{} ≤ {x} ≤ {}", num(lo), num(hi)),
            TorqueLimit::Range(Some(lo), None) => format!("{x} ≥ {}", num(lo)),
            TorqueLimit::Range(None, Some(hi)) => format!("{x} ≤ {}", num(hi)),
            TorqueLimit::Range(None, None) => "unlimited".into(),
        }
    }

    /// The limit from a range `[lower, upper]`: symmetric when `lower = −upper`.
    pub fn from_range(lower: f64, upper: f64) -> Self {
        if lower == -upper {
            TorqueLimit::Symmetric(upper)
        } else {
            TorqueLimit::Range(Some(lower), Some(upper))
        }
    }

    /// Why the limit is invalid (what is expected), or `None`.
    fn invalid(self) -> Option<&'static str> {
        let side = |v: Option<f64>| v.is_none_or(in_domain);
        match self {
            TorqueLimit::Symmetric(t) if !(t > 0.0 && in_domain(t)) => Some(LIMIT_EXPECTED),
            TorqueLimit::Range(lo, hi) if !(side(lo) && side(hi)) => Some(LIMIT_EXPECTED),
            TorqueLimit::Range(Some(lo), Some(hi)) if lo >= hi => {
                Some("[lower, upper] with lower < upper")
            }
            _ => None,
        }
    }
}

impl From<f64> for TorqueLimit {
    fn from(t: f64) -> Self {
        TorqueLimit::Symmetric(t)
    }
}

/// What a torque limit must be, for error messages.
pub const LIMIT_EXPECTED: &str = "a number t > 0 (|τ| ≤ t), [lower, upper] (either null for none; numbers of magnitude at most 1e12, not subnormal), or null for no limit";

impl serde::Serialize for TorqueLimit {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match *self {
            TorqueLimit::Symmetric(t) => s.serialize_f64(t),
            TorqueLimit::Range(lo, hi) => [lo, hi].serialize(s),
        }
    }
}

impl<'de> serde::Deserialize<'de> for TorqueLimit {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = TorqueLimit;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(LIMIT_EXPECTED)
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<TorqueLimit, E> {
                Ok(TorqueLimit::Symmetric(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<TorqueLimit, E> {
                Ok(TorqueLimit::Symmetric(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<TorqueLimit, E> {
                Ok(TorqueLimit::Symmetric(v as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<TorqueLimit, A::Error> {
                let wrong = |n: usize| {
                    serde::de::Error::custom(format!(
                        "expected {LIMIT_EXPECTED}, got a list of {n}"
                    ))
                };
                let lo: Option<f64> = a.next_element()?.ok_or_else(|| wrong(0))?;
                let hi: Option<f64> = a.next_element()?.ok_or_else(|| wrong(1))?;
                let mut n = 2;
                while a.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    n += 1;
                }
                if n > 2 {
                    return Err(wrong(n));
                }
                Ok(TorqueLimit::Range(lo, hi))
            }
        }
        d.deserialize_any(V)
    }
}

/// Everything that defines one grasp-torque problem.
///
/// `G f = w` must hold for the contact forces `f` (n components, contacts in column
/// order), `Jᵀ f = τ` maps them to the m joint torques, and each contact's force must lie
/// in its (linearised) friction cone.
#[derive(Clone, Debug)]
pub struct GraspProblem {
    /// G, the 6 × n grasp matrix (eq. 18).
    pub grasp_matrix: Matrix,
    /// Jᵀ, the m × n transposed hand Jacobian (eq. 19).
    pub jacobian_transpose: Matrix,
    /// w = `[Fx Fy Fz Mx My Mz]`, the wrench the contact forces must apply to the object.
    pub wrench: [f64; 6],
    /// The contacts, in the column order of G.
    pub contacts: Vec<ContactModel>,
    /// N and K of the inscribed cones.
    pub linearization: Linearization,
    /// Objective weights `w_j` in `Σ w_j τ_j²`; `None` means all 1.
    pub torque_weights: Option<Vec<f64>>,
    /// Limits `|τ_j| ≤ t_j` or `lower_j ≤ τ_j ≤ upper_j`; `None` entries are unlimited.
    pub torque_limits: Option<Vec<Option<TorqueLimit>>>,
    /// Minimum normal force per contact, `fz ≥ f_min` (same unit as f); `None` means 0.
    pub min_normal_force: Option<Vec<f64>>,
    /// A starting torque for the solver (used when feasible).
    pub initial_torque: Option<Vec<f64>>,
    /// Joint names for reports (from a file's `joint_names`, a geometry file's joints or
    /// a robot description; empty when unknown).
    pub joint_names: Vec<String>,
    /// How the passive internal forces (the null space of `[G; Jᵀ]`) are fixed.
    pub internal_forces: InternalForces,
    /// Actuators that drive the joints (`τ = T u`); `None` means one per joint
    /// (`T = I`). With it, the weights, limits and initial torque are per actuator.
    pub transmission: Option<Transmission>,
    /// Joint torques no actuator controls, per joint (rows of `jacobian_transpose`):
    /// springs on joints and tendons, or gravity on the fingers (MuJoCo's
    /// `qfrc_spring`, `−qfrc_bias`). The joints then balance the contact forces with
    /// `Jᵀ f = T u + τ_passive`, and the objective and limits stay on u. `None` is 0.
    pub passive_torque: Option<Vec<f64>>,
}

/// How actuator forces u become joint torques: `τ = T u`.
///
/// T is MuJoCo's actuator moment arm, transposed: the gear for an actuator on a joint,
/// the gear times the tendon coefficients for one on a fixed tendon. Its columns must be
/// linearly independent. With fewer actuators than joints the hand is underactuated,
/// and `Jᵀ f` must lie in the range of T.
#[derive(Clone, Debug, PartialEq)]
pub struct Transmission {
    /// T, joints × actuators.
    pub matrix: Matrix,
    /// One name per actuator (column of T), or empty.
    pub actuator_names: Vec<String>,
}

impl Transmission {
    /// Whether T is exactly the identity: the problem is then the same as without it.
    pub fn is_identity(&self) -> bool {
        let t = &self.matrix;
        t.nrows() == t.ncols()
            && (0..t.nrows()).all(|i| {
                t.row(i)
                    .iter()
                    .enumerate()
                    .all(|(j, &v)| v == if i == j { 1.0 } else { 0.0 })
            })
    }

    /// Number of actuators a.
    pub fn actuators(&self) -> usize {
        self.matrix.ncols()
    }
}

impl GraspProblem {
    /// A problem with default options: uniform weights, no limits, no minimum force.
    pub fn new(
        grasp_matrix: Matrix,
        jacobian_transpose: Matrix,
        wrench: [f64; 6],
        contacts: Vec<ContactModel>,
    ) -> Self {
        Self {
            grasp_matrix,
            jacobian_transpose,
            wrench,
            contacts,
            linearization: Linearization::default(),
            torque_weights: None,
            torque_limits: None,
            min_normal_force: None,
            initial_torque: None,
            joint_names: Vec::new(),
            internal_forces: InternalForces::default(),
            transmission: None,
            passive_torque: None,
        }
    }

    /// The name of joint `j`: its given name, else `joint j`.
    pub fn joint_name(&self, j: usize) -> String {
        self.joint_names
            .get(j)
            .cloned()
            .unwrap_or_else(|| format!("joint {j}"))
    }

    /// Number of joints m.
    pub fn joints(&self) -> usize {
        self.jacobian_transpose.nrows()
    }

    /// Number of torques the solver chooses: the actuators a with a transmission, else
    /// the joints m.
    pub fn actuated(&self) -> usize {
        self.transmission
            .as_ref()
            .map_or(self.joints(), Transmission::actuators)
    }

    /// The name of torque variable `j`: an actuator's name with a transmission, else a
    /// joint's.
    pub fn actuator_name(&self, j: usize) -> String {
        match &self.transmission {
            Some(t) => t
                .actuator_names
                .get(j)
                .cloned()
                .unwrap_or_else(|| format!("actuator {j}")),
            None => self.joint_name(j),
        }
    }

    /// Number of contact force components n.
    pub fn force_dim(&self) -> usize {
        self.grasp_matrix.ncols()
    }

    /// Checks every dimension and value against the input domain (the constants of
    /// this module), naming the first field at fault, its value and the allowed range.
    /// Sizes are checked before anything proportional to them is allocated.
    pub fn validate(&self) -> Result<(), ProblemError> {
        let g = &self.grasp_matrix;
        if g.nrows() != 6 {
            return Err(ProblemError::invalid(
                "grasp_matrix",
                "6 rows (Fx Fy Fz Mx My Mz)",
                format!("{} rows", g.nrows()),
            ));
        }
        let n = g.ncols();
        if n == 0 {
            return Err(ProblemError::invalid(
                "grasp_matrix",
                "at least one column",
                "none",
            ));
        }
        if n > MAX_FORCE_COMPONENTS {
            return Err(ProblemError::invalid(
                "grasp_matrix",
                format!("at most {MAX_FORCE_COMPONENTS} columns (force components)"),
                format!("{n} columns"),
            ));
        }
        contact_count(self.contacts.len())?;
        let jt = &self.jacobian_transpose;
        let m = jt.nrows();
        if m == 0 {
            return Err(ProblemError::invalid(
                "jacobian_transpose",
                "at least one joint row",
                "none",
            ));
        }
        if m > MAX_JOINTS {
            return Err(ProblemError::invalid(
                "jacobian_transpose",
                format!("at most {MAX_JOINTS} joint rows"),
                format!("{m} rows"),
            ));
        }
        if !self.joint_names.is_empty() && self.joint_names.len() != m {
            return Err(ProblemError::invalid(
                "joint_names",
                format!("{m} names, one per row of jacobian_transpose"),
                format!("{} names", self.joint_names.len()),
            ));
        }
        if let Some(t) = &self.transmission {
            validate_transmission(t, m)?;
        }
        if let Some(t) = &self.passive_torque {
            per_joint(
                "passive_torque",
                t.len(),
                m,
                "joint (rows of jacobian_transpose)",
            )?;
            for (j, &v) in t.iter().enumerate() {
                if !in_domain(v) {
                    bounded(&format!("passive_torque[{j}]"), v)?;
                }
            }
        }
        bounded_matrix("grasp_matrix", g)?;
        for (i, c) in self.contacts.iter().enumerate() {
            c.validate().map_err(|e| {
                ProblemError::invalid(
                    format!("contacts[{i}].{}", e.field),
                    format!("a number from {:e} to {:e}", e.range.0, e.range.1),
                    e.value,
                )
            })?;
        }
        let dims: usize = self.contacts.iter().map(ContactModel::dim).sum();
        if dims != n {
            return Err(ProblemError::invalid(
                "contacts",
                format!("models whose force components add up to the {n} columns of grasp_matrix (fpc 1, pcwf 3, sfcl/sfce 4)"),
                format!("{dims} components"),
            ));
        }
        if jt.ncols() != n {
            return Err(ProblemError::invalid(
                "jacobian_transpose",
                format!("rows of {n} entries (the columns of grasp_matrix)"),
                format!("rows of {}", jt.ncols()),
            ));
        }
        bounded_matrix("jacobian_transpose", jt)?;
        for (j, &v) in self.wrench.iter().enumerate() {
            if !in_domain(v) {
                bounded(&format!("wrench[{j}]"), v)?;
            }
        }
        self.linearization
            .validate()
            .map_err(|e| ProblemError::invalid("linearization", "valid N and K", e))?;
        let rows: usize = self
            .contacts
            .iter()
            .map(|c| self.linearization.rows_for(c))
            .sum();
        // H is dense: rows × (joints + 6 + force components) numbers.
        if rows > MAX_ROWS || rows * (m + 6 + n) > MAX_MATRIX_ENTRIES {
            return Err(ProblemError::invalid(
                "linearization",
                format!(
                    "at most {MAX_ROWS} cone rows, and rows × (joints + 6 + force components) at most {MAX_MATRIX_ENTRIES} (fewer sides or latitudes)"
                ),
                format!(
                    "{rows} rows for N = {}, K = {}",
                    self.linearization.sides, self.linearization.latitudes
                ),
            ));
        }
        // Weights, limits and the initial torque are per actuator with a transmission.
        let (m, per) = match &self.transmission {
            Some(t) => (t.actuators(), "actuator (columns of transmission)"),
            None => (m, "joint (rows of jacobian_transpose)"),
        };
        if let Some(w) = &self.torque_weights {
            per_joint("torque_weights", w.len(), m, per)?;
            for (j, &v) in w.iter().enumerate() {
                if !(WEIGHT_RANGE.0..=WEIGHT_RANGE.1).contains(&v) {
                    return Err(ProblemError::invalid(
                        format!("torque_weights[{j}]"),
                        format!("a number from {:e} to {:e}", WEIGHT_RANGE.0, WEIGHT_RANGE.1),
                        v,
                    ));
                }
            }
            let lo = w.iter().copied().fold(f64::INFINITY, f64::min);
            let (j, hi) =
                w.iter()
                    .copied()
                    .enumerate()
                    .fold((0, 0.0), |a, (j, v)| if v > a.1 { (j, v) } else { a });
            if hi / lo > MAX_WEIGHT_RATIO {
                return Err(ProblemError::invalid(
                    format!("torque_weights[{j}]"),
                    format!(
                        "weights within a ratio of {MAX_WEIGHT_RATIO:e} of each other (the smallest is {lo:e})"
                    ),
                    hi,
                ));
            }
        }
        if let Some(l) = &self.torque_limits {
            per_joint("torque_limits", l.len(), m, per)?;
            for (j, v) in l.iter().enumerate() {
                if let Some(why) = v.and_then(TorqueLimit::invalid) {
                    return Err(ProblemError::invalid(
                        format!("torque_limits[{j}]"),
                        why,
                        v.map_or(String::new(), limit_json),
                    ));
                }
            }
        }
        if let Some(f) = &self.min_normal_force {
            if f.len() != self.contacts.len() {
                return Err(ProblemError::invalid(
                    "min_normal_force",
                    format!("one value per contact ({})", self.contacts.len()),
                    format!("{} values", f.len()),
                ));
            }
            for (i, &v) in f.iter().enumerate() {
                if !(v >= 0.0 && in_domain(v)) {
                    return Err(ProblemError::invalid(
                        format!("min_normal_force[{i}]"),
                        format!("a number from 0 to {MAX_MAGNITUDE:e}, not subnormal"),
                        v,
                    ));
                }
            }
        }
        if let Some(t) = &self.initial_torque {
            per_joint("initial_torque", t.len(), m, per)?;
            for (j, v) in t.iter().enumerate() {
                if !v.is_finite() {
                    return Err(ProblemError::invalid(
                        format!("initial_torque[{j}]"),
                        "a finite number",
                        v,
                    ));
                }
            }
        }
        Ok(())
    }
}

/// At least one contact and at most [`MAX_CONTACTS`]: checked by every problem form
/// before anything proportional to the count is allocated.
pub fn contact_count(count: usize) -> Result<(), ProblemError> {
    if count == 0 {
        return Err(ProblemError::invalid(
            "contacts",
            "at least one contact",
            "an empty list",
        ));
    }
    if count > MAX_CONTACTS {
        return Err(ProblemError::invalid(
            "contacts",
            format!("at most {MAX_CONTACTS} contacts"),
            format!("{count} contacts"),
        ));
    }
    Ok(())
}

/// A number within the input domain ([`in_domain`]), or an error naming `field`.
pub fn bounded(field: &str, v: f64) -> Result<(), ProblemError> {
    if in_domain(v) {
        Ok(())
    } else {
        Err(ProblemError::invalid(field, DOMAIN, v))
    }
}

fn bounded_matrix(name: &str, a: &Matrix) -> Result<(), ProblemError> {
    if a.as_slice().iter().fold(true, |ok, &v| ok & in_domain(v)) {
        return Ok(());
    }
    for i in 0..a.nrows() {
        for (j, &v) in a.row(i).iter().enumerate() {
            // The field is named only on failure: validation runs per grasp.
            if !in_domain(v) {
                bounded(&format!("{name}[{i}][{j}]"), v)?;
            }
        }
    }
    Ok(())
}

fn per_joint(name: &str, len: usize, m: usize, per: &str) -> Result<(), ProblemError> {
    if len == m {
        Ok(())
    } else {
        Err(ProblemError::invalid(
            name,
            format!("one value per {per}: {m}"),
            format!("{len} values"),
        ))
    }
}

/// Shape, magnitudes, names and independent columns of T.
fn validate_transmission(t: &Transmission, m: usize) -> Result<(), ProblemError> {
    let a = t.matrix.ncols();
    if t.matrix.nrows() != m {
        return Err(ProblemError::invalid(
            "transmission",
            format!("{m} rows, one per joint (the rows of jacobian_transpose)"),
            format!("{} rows", t.matrix.nrows()),
        ));
    }
    if a == 0 || a > m {
        return Err(ProblemError::invalid(
            "transmission",
            format!("1 to {m} columns (actuators; more actuators than joints cannot have independent columns)"),
            format!("{a} columns"),
        ));
    }
    if !t.actuator_names.is_empty() && t.actuator_names.len() != a {
        return Err(ProblemError::invalid(
            "actuator_names",
            format!("{a} names, one per column of transmission"),
            format!("{} names", t.actuator_names.len()),
        ));
    }
    // A batch of grasps of one hand shares its T: the last T that passed every check
    // below on this thread passes again without them (each depends on T alone).
    if FULL_RANK_TRANSMISSION.with(|c| c.borrow().get(&t.matrix, 0).is_some()) {
        return Ok(());
    }
    bounded_matrix("transmission", &t.matrix)?;
    // A moment arm below 1e-12 of the unit would put u beyond any force within the domain.
    for i in 0..m {
        for (j, &v) in t.matrix.row(i).iter().enumerate() {
            if v != 0.0 && v.abs() < 1.0 / MAX_MAGNITUDE {
                return Err(ProblemError::invalid(
                    format!("transmission[{i}][{j}]"),
                    format!(
                        "0, or a magnitude from {:e} to {MAX_MAGNITUDE:e}",
                        1.0 / MAX_MAGNITUDE
                    ),
                    v,
                ));
            }
        }
    }
    for j in 0..a {
        if (0..m).all(|i| t.matrix[(i, j)] == 0.0) {
            return Err(ProblemError::invalid(
                format!("transmission[..][{j}]"),
                "a column that drives at least one joint",
                "all zeros",
            ));
        }
    }
    // Columns at unit length: an actuator's gear or tendon radius is not a reason to
    // call it dependent.
    let norms: Vec<f64> = (0..a)
        .map(|j| (0..m).map(|i| t.matrix[(i, j)].powi(2)).sum::<f64>().sqrt())
        .collect();
    let unit = Matrix::from_fn(m, a, |i, j| t.matrix[(i, j)] / norms[j]);
    // The SVD's rank decision, from the QR's R alone when T is clearly of full rank.
    let rank = crate::linalg::rank(
        &unit,
        crate::linalg::RankThreshold::Relative(TRANSMISSION_RANK_TOLERANCE),
    )
    .map_err(|_| {
        ProblemError::invalid(
            "transmission",
            "finite entries",
            "an SVD that did not converge",
        )
    })?;
    if rank < a {
        return Err(ProblemError::invalid(
            "transmission",
            format!("linearly independent columns (rank {a}): two actuator combinations drive the same joint torques, so u is not unique"),
            format!("rank {rank}"),
        ));
    }
    FULL_RANK_TRANSMISSION.with(|c| c.borrow_mut().put(&t.matrix, 0, ()));
    Ok(())
}

thread_local! {
    /// The last transmission this thread found of full rank.
    static FULL_RANK_TRANSMISSION: std::cell::RefCell<crate::matrix::LastMatrix<()>> =
        std::cell::RefCell::new(crate::matrix::LastMatrix::default());
}

/// Relative singular value below which T's columns count as dependent.
pub const TRANSMISSION_RANK_TOLERANCE: f64 = 1e-9;
