//! The native exact-cone solver: the torque problem with the friction cones of eqs. 1–4
//! themselves, not their linearisations, for every contact model.
//!
//! A solve:
//! 0. where the equalities leave at most one free direction, solves the problem in
//!    closed form ([`Newton::solve_line`]), certified as in step 3
//!    (`method: "closed_form"`). With none, the one point they admit decides: if its
//!    certificate refuses it, the piece it misses is a ray of the dual
//!    ([`separating_piece`]). Where the closed form cannot decide, goes on:
//! 1. solves the problem with the inscribed polyhedra (`N = 8`) by the active-set
//!    method. Their key constraint set says, per contact, whether the force is inside
//!    its cone or on its boundary: that guess starts the active-set Newton method of
//!    [`crate::newton`] from the inscribed optimum, which converges in a few steps;
//! 2. if the inscribed problem is infeasible, or Newton fails from its optimum, solves
//!    the problem with circumscribed polyhedra (which contain the cones). Infeasible
//!    there (after an infeasible inscribed problem) is a certificate that the exact
//!    problem is infeasible; otherwise their optimum, just outside the cones, starts
//!    Newton the same way, from the other side of each cone's boundary (where a cone
//!    near its apex sent Newton from the inscribed optimum between apex and boundary).
//!    If Newton fails there too, after an infeasible inscribed problem, circumscribed
//!    polyhedra at `N = 32` (within 0.5 % of the cones) are tried: infeasible, they
//!    prove the exact problem so;
//! 3. checks the Newton answer from scratch ([`ConicForm::certificate`]: primal and
//!    dual cone feasibility, stationarity, complementarity and the duality gap). Only an
//!    answer that passes is `optimal` (`method: "newton"`);
//! 4. otherwise (a guess Newton cannot correct or does not converge from) falls back
//!    to the dense interior-point method of [`crate::ipm`] on the same form,
//!    certificate-checked the same way (`method: "interior_point"`). A run that fails
//!    ends `infeasible` when its multipliers have grown along a ray of the dual that
//!    proves it
//!    ([`ConicForm::dual_ray`], `Reason::DualRay`); else its best iterate finishes
//!    it: Newton from there (`method: "interior_point_newton"`), or the iterate
//!    itself, each if certified; else the run is tried against finer circumscribed
//!    polyhedra (`N = 256`, within 8e-5 of the cones).
//!
//! A warm solve (`GraspSolver::resolve`) starts Newton from the previous answer and its
//! pieces, without the inscribed solve; if that fails, Newton follows the wrenches
//! between the two in steps ([`ExactSolver::follow`]) before the cold path.

use crate::ipm::{Ipm, IpmEnd, IpmSettings};
use crate::newton::{Newton, Piece};
use crate::{ActiveSetSettings, ActiveSetSolver, BuildError, ALMOST_EXCESS};
use grasp_core::{
    circumscribed_cone, inscribed_cone, Capabilities, Certificate, ConeRepr, ConicForm,
    Constraints, ContactModel, Linearization, Reason, RowId, Solution, Status, TorqueQp,
    TorqueSolver, WarmStart,
};

pub use grasp_core::conic::CERTIFICATE_TOLERANCE;
use grasp_core::conic::{soc_excess, RAY_MARGIN};

/// Sides of the polygons of the feasibility proofs.
const PROOF_SIDES: usize = 8;
/// Sides of the circumscribed polygons tried before the interior-point method on a
/// grasp the inscribed polyhedra cannot hold and the coarse proof left undecided: within
/// 0.5 % of the cones, they prove most such grasps infeasible in a fifth of the
/// method's time (docs/benchmarks.md, "Finer proofs before the interior-point method").
const MID_SIDES: usize = 32;
/// Sides of the finer circumscribed polygons tried when the interior-point method does
/// not converge on a grasp the coarser proofs left undecided.
const FINE_SIDES: usize = 256;

/// Newton solves, at most, on the way from the last answer's wrench to a new one
/// ([`ExactSolver::follow`]).
const MAX_FOLLOW: usize = 8;

/// The native solver of a view with exact cones.
#[derive(Clone, Debug)]
pub struct ExactSolver {
    qp: TorqueQp,
    conic: ConicForm,
    /// Built at the grasp's first fallback, then kept (as [`Self::outer`]).
    ipm: Option<Ipm>,
    /// Its last answer in the form's variables.
    ipm_x: Vec<f64>,
    /// The view with every exact cone inscribed, and its rows' meaning here: the conic
    /// row of a row both views share, and the (contact, SFCl group) of an inscribed face.
    inner: ActiveSetSolver,
    inner_row: Vec<Option<usize>>,
    inner_face: Vec<Option<(usize, usize)>>,
    /// Active faces per (contact, group) in the last solve.
    active_faces: Vec<[usize; 2]>,
    /// Each second-order cone's (contact, group).
    soc_group: Vec<(usize, usize)>,
    newton: Newton,
    /// Whether `newton` holds the last answer (for a warm solve), at magnitude α, and
    /// the wrench it answers.
    hot: Option<f64>,
    hot_wrench: [f64; 6],
    /// That answer's primal-dual pair in the form (at magnitude α), for
    /// [`Self::follow`]: a warm solve from it that converges and fails its certificate
    /// leaves Newton's own elsewhere.
    answer_x: Vec<f64>,
    answer_z: Vec<f64>,
    /// The first step of the next [`Self::follow`], as a fraction of the way: that of
    /// the last one's first solve that converged (doubled if it was its first
    /// try), so that a control loop that needs short steps does not relearn them
    /// every tick.
    follow_step: f64,
    /// Whether the last follow failed: the next warm solve that fails goes on cold
    /// without one (a grasp where following fails every tick pays for every other).
    follow_failed: bool,
    /// Whether that answer is the interior-point method's ([`Newton::adopt`]), and
    /// whether the method's answers are taken up: not after a warm solve from one has
    /// failed, until Newton solves a grasp again.
    adopted: bool,
    adopt: bool,
    /// The view with every exact cone circumscribed, built the first time a grasp
    /// needs it (the inscribed polyhedra infeasible, or Newton failing from their
    /// optimum), then kept for the grasp's next solves: most grasps never need it, and a
    /// grasp planner builds a solver per grasp.
    outer: Option<ActiveSetSolver>,
    /// The same at [`MID_SIDES`] and [`FINE_SIDES`], likewise (at the edge of
    /// feasibility).
    mid: Option<ActiveSetSolver>,
    fine: Option<ActiveSetSolver>,
    settings: ActiveSetSettings,
    lin: Solution,
    /// The core's check of `lin` in the exact cones ([`Self::inscribed_holds`]).
    probe: Solution,
    b: Vec<f64>,
    dual: Vec<f64>,
    scratch: Vec<f64>,
    /// The last certificate checked.
    certificate: Certificate,
}

/// The interior-point method's multipliers as a ray of the dual, when they prove the
/// grasp infeasible: on a grasp the exact cones cannot hold, although the
/// circumscribed polyhedra can, the method's dual iterates grow along such a ray until
/// it stalls. `xp` meets the equalities ([`ConicForm::dual_ray`]). The ray must also
/// reach [`RAY_MARGIN`] times `reach` from `xp` (see [`ExactSolver::polyhedral_reach`]).
fn ray_of(
    ipm: &Ipm,
    conic: &ConicForm,
    b: &[f64],
    xp: &[f64],
    reach: f64,
    dual: &mut [f64],
    scratch: &mut Vec<f64>,
) -> Option<Reason> {
    ipm.dual_into(conic, dual);
    let ray = conic.dual_ray(b, xp, dual, CERTIFICATE_TOLERANCE, scratch);
    (ray.passed && ray.horizon >= RAY_MARGIN * reach).then_some(Reason::DualRay {
        value: ray.value,
        stationarity: ray.stationarity,
    })
}

/// Where the equalities leave no free direction, the slacks `s_p = b − A x_p` of the one
/// point they admit decide the grasp: a piece of the cones they miss separates `s_p`
/// from every feasible slack. Writes into `z` (rows `eq..`; zero elsewhere) the dual
/// vector of the piece missed by most against its terms (as [`ConicForm::dual_ray`]
/// measures them): `e_i` on a nonnegative row (`s_i < 0`), `(1, −s1/‖s1‖)` on a
/// second-order cone (`zᵀ s_p = s0 − ‖s1‖ < 0`; `(1, 0)` at `s1 = 0`). False if every
/// piece holds.
fn separating_piece(conic: &ConicForm, b: &[f64], sp: &[f64], z: &mut [f64]) -> bool {
    z.iter_mut().for_each(|v| *v = 0.0);
    // The worst piece: (relative miss, first row, rows, ‖s1‖ on a cone).
    let mut worst: Option<(f64, usize, usize, f64)> = None;
    let mut consider = |miss: f64, size: f64, start: usize, dim: usize, norm: f64| {
        let rel = miss / size.max(f64::MIN_POSITIVE);
        if miss > 0.0 && worst.is_none_or(|w| rel > w.0) {
            worst = Some((rel, start, dim, norm));
        }
    };
    let terms = |i: usize| b[i].abs() + (b[i] - sp[i]).abs();
    let mut start = 0;
    for cone in &conic.cones {
        let dim = cone.dim();
        match cone {
            grasp_core::ConeKind::Zero(_) => {}
            grasp_core::ConeKind::Nonnegative(_) => {
                for i in start..start + dim {
                    consider(-sp[i], terms(i), i, 1, 0.0);
                }
            }
            grasp_core::ConeKind::SecondOrder(_) => {
                let miss = soc_excess(sp[start], &sp[start + 1..start + dim]);
                // ‖s1‖ where the cone is missed; |z|ᵀ terms with |z_j| = |s_j| / ‖s1‖.
                let norm = miss + sp[start];
                let size = terms(start)
                    + (start + 1..start + dim)
                        .map(|i| terms(i) * sp[i].abs() / norm.max(f64::MIN_POSITIVE))
                        .sum::<f64>();
                consider(miss, size, start, dim, norm);
            }
        }
        start += dim;
    }
    let Some((_, start, dim, norm)) = worst else {
        return false;
    };
    z[start] = 1.0;
    if norm > 0.0 {
        for i in start + 1..start + dim {
            z[i] = -sp[i] / norm;
        }
    }
    true
}

/// `qp` with every exact cone replaced by a polyhedron from `cone`.
fn polyhedral(
    qp: &TorqueQp,
    lin: &Linearization,
    cone: fn(&grasp_core::ContactModel, &Linearization) -> grasp_core::InscribedCone,
) -> TorqueQp {
    let cones = qp
        .constraints
        .cones
        .iter()
        .zip(&qp.model.contacts)
        .map(|(r, c)| match r {
            ConeRepr::Exact => ConeRepr::Inscribed(cone(c, lin)),
            other => other.clone(),
        })
        .collect();
    TorqueQp::new(
        qp.model.clone(),
        Constraints {
            cones,
            linearization: Some(*lin),
        },
    )
}

impl ExactSolver {
    /// Precomputes everything that depends only on the grasp.
    pub fn new(qp: TorqueQp, settings: ActiveSetSettings) -> Result<Self, BuildError> {
        let lin = Linearization {
            sides: PROOF_SIDES,
            ..qp.constraints.linearization.unwrap_or_default()
        };
        let inner_qp = polyhedral(&qp, &lin, inscribed_cone);
        let conic = ConicForm::new(&qp);
        // Rows both views share (minimum normal forces, torque limits, inscribed
        // contacts) are the conic form's nonnegative rows in the exact view's order.
        let inner_row = inner_qp
            .rows
            .iter()
            .map(|id| {
                qp.rows
                    .iter()
                    .position(|r| r == id)
                    .map(|i| conic.linear_at + i)
            })
            .collect();
        let nc = qp.contacts.len();
        let inner_face = inner_qp
            .rows
            .iter()
            .map(|id| match *id {
                RowId::Face { contact, face }
                    if matches!(qp.constraints.cones[contact], ConeRepr::Exact) =>
                {
                    // SFCl: the first N faces meet the +mz pole (they bind when mz > 0,
                    // the form's first cone of the contact), the next N the −mz pole.
                    let group = match qp.contacts[contact].model {
                        ContactModel::SfcLinear { .. } => usize::from(face >= lin.sides),
                        _ => 0,
                    };
                    Some((contact, group))
                }
                _ => None,
            })
            .collect();
        let mut soc_group: Vec<(usize, usize)> = Vec::with_capacity(conic.soc_contacts.len());
        for &c in &conic.soc_contacts {
            let group = soc_group.iter().filter(|(d, _)| *d == c).count();
            soc_group.push((c, group));
        }
        let inner = ActiveSetSolver::from_form(inner_qp, settings, &conic)?;
        // Each cone's contact's minimum normal force row, in the conic form's rows.
        let normal_row = conic
            .soc_contacts
            .iter()
            .map(|&c| {
                qp.rows
                    .iter()
                    .position(|r| *r == RowId::NormalForce { contact: c })
                    .map(|i| conic.linear_at + i)
            })
            .collect();
        let newton = Newton::new(&conic, normal_row);
        let rows = conic.rows();
        Ok(Self {
            ipm: None,
            ipm_x: Vec::new(),
            inner,
            inner_row,
            inner_face,
            active_faces: vec![[0; 2]; nc],
            soc_group,
            newton,
            hot: None,
            hot_wrench: [0.0; 6],
            answer_x: vec![0.0; conic.nx],
            answer_z: vec![0.0; rows],
            follow_step: 0.5,
            follow_failed: false,
            adopted: false,
            adopt: true,
            outer: None,
            mid: None,
            fine: None,
            settings,
            lin: Solution::default(),
            probe: Solution::default(),
            b: vec![0.0; rows],
            dual: vec![0.0; rows],
            scratch: Vec::new(),
            certificate: Certificate::default(),
            conic,
            qp,
        })
    }

    /// The certificate of the last answer.
    pub fn certificate(&self) -> &Certificate {
        &self.certificate
    }

    /// Solves the circumscribed polyhedra at `sides` (cold) into `self.lin`, building
    /// them at the first need; false if they could not be built (their rows are the
    /// inscribed view's, widened, and share its equalities: not expected).
    fn solve_outer(&mut self, w: &[f64; 6], sides: usize) -> bool {
        let slot = match sides {
            PROOF_SIDES => &mut self.outer,
            MID_SIDES => &mut self.mid,
            _ => &mut self.fine,
        };
        if slot.is_none() {
            let lin = Linearization {
                sides,
                ..self.qp.constraints.linearization.unwrap_or_default()
            };
            let qp = polyhedral(&self.qp, &lin, circumscribed_cone);
            *slot = ActiveSetSolver::sharing(qp, self.settings, &self.inner).ok();
        }
        let Some(view) = slot.as_mut() else {
            return false;
        };
        view.solve_raw(w, &WarmStart::default(), &mut self.lin);
        true
    }

    /// Whether the circumscribed polyhedra at `sides` admit no torque for `w`; the
    /// reason when they do not, built in `out`'s kept buffers (whose rows the
    /// polyhedra's next solve takes: an infeasible control loop allocates nothing).
    fn outer_infeasible(
        &mut self,
        w: &[f64; 6],
        sides: usize,
        out: &mut Solution,
    ) -> Option<Reason> {
        if !self.solve_outer(w, sides) || self.lin.status != Status::Infeasible {
            return None;
        }
        let cause = self
            .lin
            .reason
            .take()
            .unwrap_or_else(|| Reason::NoAdmissibleTorque {
                relaxation: None,
                blocking: Vec::new(),
            });
        self.lin.recycle_rows(out.recycled_rows());
        Some(Reason::OuterApproximation {
            sides,
            cause: out.recycled_box(cause),
        })
    }

    /// Newton from the polyhedral optimum in `self.lin` (inscribed or circumscribed:
    /// their rows are the same, widened), its guess read off the key set (Newton reads
    /// a cone at its apex off the iterate); on a certified answer fills `out`.
    fn newton_from_polyhedra(&mut self, w: &[f64; 6], alpha: f64, out: &mut Solution) -> bool {
        self.guess(alpha);
        self.try_newton(w, alpha, false, out)
    }

    /// Whether the polyhedral optimum in `self.lin` holds the grasp in the exact cones:
    /// the core's own check of it, on the exact view. The linear solver's `optimal` is
    /// not proof: it holds its rows normalised in the free torques, and where `[G; Jᵀ]`
    /// is ill-conditioned (a row of Jᵀ scaled by 1e7, another's entry at 1e-9) such an
    /// answer has left a contact outside its cone by 2.6e3 N, which the core refuses.
    fn inscribed_holds(&mut self, w: &[f64; 6]) -> bool {
        let probe = &mut self.probe;
        probe.status = Status::Optimal;
        probe.torque.clone_from(&self.lin.torque);
        probe.internal_forces.clone_from(&self.lin.internal_forces);
        self.qp
            .complete(w, crate::RESIDUAL_TOLERANCE, "active-set", probe);
        probe.status == Status::Optimal
    }

    /// The Newton guess from the polyhedral optimum in `self.lin`.
    fn guess(&mut self, alpha: f64) {
        let nw = &mut self.newton;
        nw.active.iter_mut().for_each(|a| *a = false);
        self.active_faces.iter_mut().for_each(|c| *c = [0; 2]);
        for &i in self.lin.active_set.as_deref().unwrap_or(&[]) {
            if let Some(r) = self.inner_row[i] {
                nw.active[r] = true;
            }
            if let Some((c, g)) = self.inner_face[i] {
                self.active_faces[c][g] += 1;
            }
        }
        for (k, &(c, g)) in self.soc_group.iter().enumerate() {
            let [a, b] = self.active_faces[c];
            let on = if g == 0 { a } else { b };
            nw.piece[k] = if on > 0 {
                Piece::Boundary
            } else {
                Piece::Inside
            };
        }
        for (j, x) in nw.x.iter_mut().enumerate() {
            *x = self.lin.torque[j] * self.conic.col_scale[j] / alpha;
        }
        nw.reset_multipliers();
        // Multipliers from the inscribed ones (for Σ w τ²; in the scaled form a row's is
        // μ/(α κ ρ)): a shared row's directly; a cone's from its faces, whose fz
        // coefficient is 1, through the cone's head row (mu·fz, or fz for SFCe), so
        // that the first Newton step already has the cone's curvature.
        // Where κ = 1/k² underflows (the small end of the input domain), μ k/α · k/ρ.
        let (kappa, ts) = (self.conic.kappa, self.conic.torque_scale);
        let scaled = |mu: f64, rho: f64| {
            if kappa.is_normal() {
                mu / (alpha * kappa * rho)
            } else {
                mu * (ts / alpha) * (ts / rho)
            }
        };
        let mu = &self.lin.multipliers;
        if mu.len() == self.inner_row.len() {
            for &i in self.lin.active_set.as_deref().unwrap_or(&[]) {
                if let Some(r) = self.inner_row[i] {
                    nw.nu_row[r] = scaled(mu[i], self.conic.row_scale[r - self.conic.linear_at]);
                }
                if let Some((c, g)) = self.inner_face[i] {
                    let head = match self.qp.contacts[c].model {
                        ContactModel::Pcwf { mu } | ContactModel::SfcLinear { mu, .. } => mu,
                        _ => 1.0,
                    };
                    if let Some(k) = self.soc_group.iter().position(|&p| p == (c, g)) {
                        nw.nu_cone[k] += scaled(mu[i], head);
                    }
                }
            }
        }
    }

    /// Newton from its current state (`hot`: a warm re-solve of the last answer's
    /// pieces); on a certified answer fills `out`.
    fn try_newton(&mut self, w: &[f64; 6], alpha: f64, hot: bool, out: &mut Solution) -> bool {
        let ok = self.newton.solve(&self.conic, w, alpha, hot);
        out.iterations += self.newton.iterations;
        if ok {
            return self.certify(w, alpha, out);
        }
        self.hot = None;
        false
    }

    /// Checks Newton's converged answer from scratch; if it passes, fills `out` and
    /// keeps the answer for a warm solve.
    fn certify(&mut self, w: &[f64; 6], alpha: f64, out: &mut Solution) -> bool {
        if !self.accept_newton(alpha, "newton", out) {
            self.hot = None;
            return false;
        }
        (self.hot, self.hot_wrench) = (Some(alpha), *w);
        self.keep_answer();
        true
    }

    /// The closed form of a grasp with at most one free direction
    /// ([`Newton::solve_line`]), checked from scratch like Newton's answer
    /// (`method: "closed_form"`). It is no start for a warm Newton solve: the next
    /// solve takes the closed form again, or the cold path.
    fn solve_line(&mut self, w: &[f64; 6], alpha: f64, out: &mut Solution) -> bool {
        if !(self.newton.solve_line(&self.conic, w, alpha)
            && self.accept_newton(alpha, "closed_form", out))
        {
            return false;
        }
        self.hot = None;
        true
    }

    /// The certificate of Newton's `x` and `z` ([`ConicForm::certificate`]); if they
    /// pass, fills `out` as optimal by `method`.
    fn accept_newton(&mut self, alpha: f64, method: &'static str, out: &mut Solution) -> bool {
        self.certificate = self.conic.certificate(
            &self.b,
            &self.newton.x,
            &self.newton.z,
            CERTIFICATE_TOLERANCE,
            &mut self.scratch,
        );
        if !self.certificate.passed {
            return false;
        }
        out.status = Status::Optimal;
        out.method = Some(method);
        self.conic.unscale_into(
            &self.newton.x,
            alpha,
            &mut out.torque,
            &mut out.internal_forces,
        );
        (self.adopted, self.adopt) = (false, true);
        true
    }

    /// Keeps Newton's answer in `answer_x` and `answer_z` by swapping buffers, not
    /// copying (a control loop pays this every tick): Newton writes its x and z afresh
    /// before it reads them again.
    fn keep_answer(&mut self) {
        std::mem::swap(&mut self.answer_x, &mut self.newton.x);
        std::mem::swap(&mut self.answer_z, &mut self.newton.z);
    }

    /// Newton along the wrenches from the last answer's (at magnitude `prev`) to `w`,
    /// when a warm solve straight to `w` failed: each solve
    /// starts from the answer one step back, and a failed step is halved. Newton's
    /// model of a cone's boundary holds over a distance about that of the force from
    /// the apex, so a force on its boundary near the apex, which a 1 % change of the
    /// wrench moves by more than that, is otherwise lost to the interior-point method
    /// at every tick of a control loop. Only the answer at `w` is certified; on
    /// failure `b` is `w`'s again.
    fn follow(&mut self, w: &[f64; 6], prev: f64, out: &mut Solution) -> bool {
        let from = self.hot_wrench;
        let (mut reached, mut step) = (0.0f64, self.follow_step);
        // The answer reached (its wrench and magnitude; its pair in `answer_x`,
        // `answer_z`), and whether Newton's state has left it.
        let (mut wr, mut ar, mut left) = (from, prev, true);
        for attempt in 0..MAX_FOLLOW {
            if left {
                self.newton
                    .adopt(&self.conic, &self.answer_x, &self.answer_z, &wr, ar);
            }
            let t = (reached + step).min(1.0);
            let wt: [f64; 6] = if t == 1.0 {
                *w
            } else {
                std::array::from_fn(|i| from[i] + t * (w[i] - from[i]))
            };
            let at = self.conic.b_into(&wt, &mut self.b);
            if at == 0.0 {
                break;
            }
            self.newton.rescale(ar / at);
            let ok = self.newton.solve(&self.conic, &wt, at, true);
            out.iterations += self.newton.iterations;
            if ok && t == 1.0 {
                return self.certify(w, at, out);
            }
            if ok {
                if reached == 0.0 {
                    self.follow_step = if attempt == 0 {
                        (2.0 * step).min(0.5)
                    } else {
                        step
                    };
                }
                (reached, wr, ar, left, step) = (t, wt, at, false, 2.0 * step);
                self.keep_answer();
            } else {
                // Two failures in a row past the start: the pieces change between
                // here and there in a way Newton cannot follow (a contact leaving its
                // apex, say), and shorter steps only close in on it.
                if left && reached > 0.0 {
                    break;
                }
                left = true;
                step *= 0.5;
            }
        }
        self.conic.b_into(w, &mut self.b);
        false
    }

    /// Certifies the interior-point answer in `ipm_x` and `dual`; if it passes, fills
    /// `out` and keeps the answer for a warm solve. `stopped`: the method stopped short
    /// of its own tolerances there, so only the gap's own bound on σ counts
    /// ([`Certificate::bounds_sigma`]).
    fn accept_ipm(&mut self, w: &[f64; 6], alpha: f64, stopped: bool, out: &mut Solution) -> bool {
        self.certificate = self.conic.certificate(
            &self.b,
            &self.ipm_x,
            &self.dual,
            CERTIFICATE_TOLERANCE,
            &mut self.scratch,
        );
        let c = self.certificate;
        if !c.passed || (stopped && !c.bounds_sigma(CERTIFICATE_TOLERANCE)) {
            return false;
        }
        out.status = Status::Optimal;
        self.conic.unscale_into(
            &self.ipm_x,
            alpha,
            &mut out.torque,
            &mut out.internal_forces,
        );
        // A warm solve starts Newton from this answer: near it, Newton often converges
        // where it did not from the polyhedra.
        if self.adopt
            && self
                .newton
                .adopt(&self.conic, &self.ipm_x, &self.dual, w, alpha)
        {
            (self.hot, self.hot_wrench) = (Some(alpha), *w);
            self.answer_x.copy_from_slice(&self.ipm_x);
            self.answer_z.copy_from_slice(&self.dual);
            self.adopted = true;
        }
        true
    }

    /// The interior-point method's best iterate, when the method ended short of its
    /// tolerances or of the certificate: on an ill-conditioned grasp its directions
    /// lose their accuracy to rounding as W⁻² spreads, a few digits before the end,
    /// and its residuals grow again. Which pieces are active is plain by then
    /// (complementarity): Newton starts from it and converges as from any good guess,
    /// certified as always (`method: "interior_point_newton"`). Failing that, the
    /// iterate itself is certified (`method: "interior_point"`), `optimal` only where
    /// the gap alone bounds σ within 2e-9: the method stopped short of its own merit
    /// (residuals against the right-hand side, the gap against the objective), which
    /// is what lets the certificate admit the rounding of sᵀz's terms, and on an
    /// ill-conditioned grasp that admitted a gap of 3.3e-7 of σ, with σ 1.8e-7 above
    /// the optimum (`fuzz_answers.py nested` seed 232401, the linear fallback at N = 16).
    /// Else it is `almost_optimal` with that bound ([`Self::almost`]). Newton comes
    /// first because its answer is the more accurate: on the grasps that found this, σ
    /// within 4e-12 of Clarabel's where the iterate's is within 2e-9 to 2e-8.
    fn finish_from_best(
        &mut self,
        w: &[f64; 6],
        alpha: f64,
        newton_after: bool,
        out: &mut Solution,
    ) -> bool {
        let Some(ipm) = self.ipm.as_mut() else {
            return false;
        };
        if !ipm.best_merit.is_finite() {
            return false;
        }
        ipm.restore_best();
        if ipm.is_reduced() {
            self.newton.lift(&ipm.x, &mut self.ipm_x);
        } else {
            self.ipm_x.copy_from_slice(&ipm.x[..self.conic.nx]);
        }
        ipm.dual_into(&self.conic, &mut self.dual);
        // (Newton reads the pair, it does not change it.)
        if newton_after
            && self
                .newton
                .adopt(&self.conic, &self.ipm_x, &self.dual, w, alpha)
            && self.try_newton(w, alpha, true, out)
        {
            out.method = Some("interior_point_newton");
            return true;
        }
        self.accept_ipm(w, alpha, true, out) || self.almost(alpha, out)
    }

    /// The best iterate, where its certificate (just formed) fails only on the gap and
    /// that bounds σ within [`crate::ALMOST_EXCESS`] of the optimum: `almost_optimal`, with the
    /// bound in a warning. Rounding stops the interior-point method with a primal
    /// residual that, times multipliers of 1e6, leaves the gap's bound at 1e-8 of σ on
    /// some grasps where σ is within 2e-9 (fuzz_answers.py seed 651); no answer
    /// would be a worse report of it, and `optimal` a wrong one. No warm solve starts
    /// from it.
    fn almost(&mut self, alpha: f64, out: &mut Solution) -> bool {
        let c = self.certificate;
        if !(c.almost(CERTIFICATE_TOLERANCE, ALMOST_EXCESS)
            && self.ipm_x.iter().all(|v| v.is_finite()))
        {
            return false;
        }
        out.status = Status::AlmostOptimal;
        out.method = Some("interior_point");
        self.conic.unscale_into(
            &self.ipm_x,
            alpha,
            &mut out.torque,
            &mut out.internal_forces,
        );
        out.warnings
            .push(crate::almost_warning("the exact-cone answer", c.excess));
        true
    }

    /// The interior-point method's last multipliers as a ray of the dual, when they
    /// prove the grasp infeasible ([`ray_of`]).
    fn dual_ray(&mut self, w: &[f64; 6], alpha: f64, reach: f64) -> Option<Reason> {
        let xp = self.newton.particular(w, alpha)?;
        ray_of(
            self.ipm.as_ref()?,
            &self.conic,
            &self.b,
            xp,
            reach,
            &mut self.dual,
            &mut self.scratch,
        )
    }

    /// How far the last polyhedral optimum in `lin` (the circumscribed polyhedra's,
    /// where a ray is looked for) lies from the equalities' particular point, in the
    /// free directions ([`ConicForm::ray_distance`]); 0 without one. The polyhedra
    /// contain the cones, so the exact optimum's σ is no smaller than theirs, and a
    /// dual ray that reaches no further than their optimum proves nothing: on a grasp
    /// whose joint with a tiny row of Jᵀ puts the answer at 1.5e4 in the scaled
    /// variables, a ray reaching 1.5e4 "proved" infeasible a grasp that Clarabel and
    /// the polyhedra at N = 64 hold (`fuzz_answers.py nested`, seed 7105).
    fn polyhedral_reach(&mut self, w: &[f64; 6], alpha: f64) -> f64 {
        let (m, nx) = (self.conic.joints, self.conic.nx);
        let lin = &self.lin;
        if lin.status != Status::Optimal
            || lin.torque.len() != m
            || lin.internal_forces.len() != nx - m
        {
            return 0.0;
        }
        self.ipm_x.resize(nx, 0.0);
        let values = lin.torque.iter().chain(&lin.internal_forces);
        for ((x, v), s) in self.ipm_x.iter_mut().zip(values).zip(&self.conic.col_scale) {
            *x = v * s / alpha;
        }
        match self.newton.particular(w, alpha) {
            Some(xp) => self.conic.ray_distance(xp, &self.ipm_x),
            None => 0.0,
        }
    }

    /// The one point the equalities admit, which its certificate refused: the piece it
    /// misses by most ([`separating_piece`]) is a ray of the dual, checked from scratch
    /// (`infeasible`, `method: "closed_form"`). Nothing else can hold the grasp, so a
    /// ray that fails its check (a miss beyond the certificate's tolerance by one
    /// measure and within it by the other, or equalities that `x_p` misses) leaves a
    /// numerical failure.
    fn refuse_point(&mut self, w: &[f64; 6], alpha: f64, out: &mut Solution) {
        self.hot = None;
        out.method = Some("closed_form");
        let (xp, sp) = self.newton.reduced_rhs(w, alpha);
        let ray = separating_piece(&self.conic, &self.b, sp, &mut self.dual).then(|| {
            self.conic.dual_ray(
                &self.b,
                xp,
                &self.dual,
                CERTIFICATE_TOLERANCE,
                &mut self.scratch,
            )
        });
        if let Some(r) = ray.filter(|r| r.passed) {
            let reason = Reason::DualRay {
                value: r.value,
                stationarity: r.stationarity,
            };
            return Self::infeasible(out, reason);
        }
        let c = self.certificate;
        out.status = Status::NumericalFailure;
        out.reason = Some(Reason::Backend {
            backend: "active-set",
            message: format!(
                "the consistency equalities fix the torque, and it failed its certificate (primal {:.1e}, stationarity {:.1e}; tolerance {CERTIFICATE_TOLERANCE:.0e}) without a ray of the dual to prove the grasp infeasible{}",
                c.primal,
                c.stationarity,
                ray.map_or(String::new(), |r| format!(
                    " (value {:.1e}, equalities {:.1e})",
                    r.value, r.particular
                )),
            ),
        });
    }

    fn infeasible(out: &mut Solution, reason: Reason) {
        out.status = Status::Infeasible;
        out.reason = Some(reason);
        out.torque.clear();
    }
}

impl TorqueSolver for ExactSolver {
    fn name(&self) -> &'static str {
        "active-set"
    }

    fn capabilities(&self) -> Capabilities {
        crate::CAPABILITIES
    }

    fn residual_tolerance(&self) -> f64 {
        crate::RESIDUAL_TOLERANCE
    }

    fn problem(&self) -> &TorqueQp {
        &self.qp
    }

    fn solve_raw(&mut self, w: &[f64; 6], warm: &WarmStart<'_>, out: &mut Solution) {
        out.recycle_active_set();
        out.iterations = 0;
        out.torque.clear();
        out.internal_forces.clear();
        let alpha = self.conic.b_into(w, &mut self.b);
        if alpha == 0.0 {
            // Every row is homogeneous: τ = 0 is feasible and optimal.
            out.status = Status::Optimal;
            out.torque.resize(self.conic.joints, 0.0);
            self.hot = None;
            return;
        }
        // At most one free direction: the closed form, warm or cold.
        if self.newton.is_line() && self.solve_line(w, alpha, out) {
            return;
        }
        // None: the one point the equalities admit is the whole problem, refused.
        if self.newton.is_point() {
            return self.refuse_point(w, alpha, out);
        }
        // Hot: Newton from the previous answer and its pieces (the scaled problem's
        // solution scales with 1/α).
        if let (false, Some(prev)) = (warm.is_cold(), self.hot) {
            self.newton.rescale(prev / alpha);
            if self.try_newton(w, alpha, true, out) {
                return;
            }
            if !std::mem::take(&mut self.follow_failed) {
                if self.follow(w, prev, out) {
                    return;
                }
                self.follow_failed = true;
            }
            self.adopt &= !self.adopted;
        }
        // 1. The inscribed polyhedra: a guess for Newton, or a reason to look further.
        self.inner
            .solve_raw(w, &WarmStart::default(), &mut self.lin);
        out.iterations += self.lin.iterations;
        let inscribed_infeasible = self.lin.status == Status::Infeasible;
        // Inscribed polyhedra that hold the grasp prove it feasible, so no ray of the
        // dual is looked for past them: a ray proves only that no torque within
        // |value| / stationarity times the problem's scale holds the grasp, and a grasp
        // can need more (a contact that pushes in some direction only through an entry
        // of G 1e-8 of the rest needs torques 1e8 times the rest).
        let lin_optimal = self.lin.status == Status::Optimal;
        // Whether their optimum passes the core's check in the exact cones: where it
        // does not, the grasp may still be infeasible, which the circumscribed
        // polyhedra can prove.
        let mut inscribed_feasible = false;
        let retry = match self.lin.status {
            Status::Optimal => {
                if self.newton_from_polyhedra(w, alpha, out) {
                    return;
                }
                inscribed_feasible = self.inscribed_holds(w);
                // (Inscribed polyhedra that hold the grasp prove nothing about the
                // circumscribed ones' status: only their optimum is wanted.)
                self.solve_outer(w, PROOF_SIDES)
            }
            // 2. The circumscribed polyhedra.
            Status::Infeasible => {
                if let Some(reason) = self.outer_infeasible(w, PROOF_SIDES, out) {
                    return Self::infeasible(out, reason);
                }
                true
            }
            _ => false,
        };
        // Their optimum, just outside the cones, is a second guess: from the other side
        // of each boundary, Newton takes another path to it (a cone near its apex, say).
        if retry {
            out.iterations += self.lin.iterations;
            if self.lin.status == Status::Optimal && self.newton_from_polyhedra(w, alpha, out) {
                return;
            }
        }
        // Where the inscribed polyhedra cannot hold the grasp, finer circumscribed ones:
        // a grasp at the edge of feasibility is usually outside them too.
        if inscribed_infeasible {
            if let Some(reason) = self.outer_infeasible(w, MID_SIDES, out) {
                return Self::infeasible(out, reason);
            }
        }
        // 4. The interior-point fallback.
        self.interior_point(w, alpha, lin_optimal, inscribed_feasible, true, out);
    }

    /// The interior-point method alone, its own iterate certified (no Newton's step
    /// from it): where Newton's answer passed the certificate (each row against the
    /// size of its terms, which the passive torques' cancelling forces can make 1000
    /// times the contact forces) and the core's check refused it (a contact 1.7e-6
    /// outside its cone on forces of 3.3; `fuzz_answers.py` seed 203989, where
    /// Clarabel's exact σ is the interior-point method's to 2e-12).
    fn solve_fallback(&mut self, w: &[f64; 6], out: &mut Solution) -> bool {
        if self.newton.is_point() {
            return false;
        }
        let alpha = self.conic.b_into(w, &mut self.b);
        if alpha == 0.0 {
            return false;
        }
        out.recycle_active_set();
        out.iterations = 0;
        out.torque.clear();
        out.internal_forces.clear();
        out.method = None;
        // Newton's answer held the grasp to the certificate's tolerance: feasible.
        self.interior_point(w, alpha, true, true, false, out);
        true
    }
}

impl ExactSolver {
    /// Step 4, the interior-point method (see the module's documentation); with
    /// `newton_after`, Newton's method from its best iterate first where it ends short.
    fn interior_point(
        &mut self,
        w: &[f64; 6],
        alpha: f64,
        lin_optimal: bool,
        inscribed_feasible: bool,
        newton_after: bool,
        out: &mut Solution,
    ) {
        self.hot = None;
        let reach = if lin_optimal {
            0.0
        } else {
            self.polyhedral_reach(w, alpha)
        };
        // Each iterate's multipliers are checked for a ray of the dual: it proves the
        // grasp infeasible as soon as they show one, several iterations before the
        // method, growing them along it, stalls.
        let mut ray = None;
        let (conic, newton) = (&self.conic, &mut self.newton);
        let ipm = self.ipm.get_or_insert_with(|| {
            // On the null space of the equalities where Newton eliminated them: about
            // half the variables on a hand, and no Schur complement.
            let settings = IpmSettings::default();
            match newton.reduced_rows(conic) {
                Some(g) => Ipm::reduced(conic, g, settings),
                None => Ipm::new(conic, settings),
            }
        });
        let end = {
            let (b, dual, scratch) = (&self.b, &mut self.dual, &mut self.scratch);
            let (xp, rhs) = if ipm.is_reduced() {
                let (xp, rhs) = newton.reduced_rhs(w, alpha);
                (Some(xp), rhs)
            } else {
                (newton.particular(w, alpha), b.as_slice())
            };
            ipm.solve(conic, rhs, &mut |ipm| {
                if let (Some(xp), false) = (xp, lin_optimal) {
                    ray = ray_of(ipm, conic, b, xp, reach, dual, scratch);
                }
                ray.is_some()
            })
        };
        // The answer in the form's variables.
        self.ipm_x.resize(conic.nx, 0.0);
        if ipm.is_reduced() {
            newton.lift(&ipm.x, &mut self.ipm_x);
        } else {
            self.ipm_x.copy_from_slice(&ipm.x[..conic.nx]);
        }
        out.iterations += ipm.iterations;
        out.method = Some("interior_point");
        if let Some(reason) = ray {
            return Self::infeasible(out, reason);
        }
        if end == IpmEnd::Converged {
            ipm.dual_into(&self.conic, &mut self.dual);
            if self.accept_ipm(w, alpha, false, out) {
                return;
            }
        }
        if let Some(reason) = self.dual_ray(w, alpha, reach).filter(|_| !lin_optimal) {
            return Self::infeasible(out, reason);
        }
        // (The method's own certificate, for the report: the best iterate's and
        // Newton's replace it.)
        let c = self.certificate;
        if self.finish_from_best(w, alpha, newton_after, out) {
            return;
        }
        if !inscribed_feasible {
            if let Some(reason) = self.outer_infeasible(w, FINE_SIDES, out) {
                return Self::infeasible(out, reason);
            }
        }
        out.status = match end {
            IpmEnd::IterationLimit => Status::IterationLimit,
            _ => Status::NumericalFailure,
        };
        out.reason = Some(Reason::Backend {
            backend: "active-set",
            message: match end {
                IpmEnd::Converged => format!(
                    "the exact-cone answer failed its certificate (primal {:.1e}, dual {:.1e}, stationarity {:.1e}, gap {:.1e}; tolerance {CERTIFICATE_TOLERANCE:.0e})",
                    c.primal, c.dual, c.stationarity, c.gap
                ),
                IpmEnd::IterationLimit => "the exact-cone interior-point method reached its iteration cap".into(),
                IpmEnd::Stalled | IpmEnd::Stopped => {
                    "the exact-cone interior-point method stalled".into()
                }
            } + &if inscribed_feasible {
                " (the inscribed polyhedra hold the grasp: it is feasible)".to_string()
            } else {
                // (Their solve's status is not checked by the core: on a grasp whose
                // rows are 1e9 apart its "optimal" can miss a face, so this says only
                // what was not proven.)
                format!(" (the circumscribed polyhedra at N = {FINE_SIDES} did not prove it infeasible)")
            },
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use grasp_core::{GraspModel, ModelOptions};
    use std::sync::Arc;

    /// A dual ray proves infeasibility only as it is: scaled it still does (a ray),
    /// spoiled it does not. And the interior-point method's multipliers on a feasible
    /// grasp never pass for one.
    #[test]
    fn the_dual_ray_check_accepts_a_ray_and_nothing_near_it() {
        let p = grasp_testkit::sweep_grasp(1084, 1.0);
        let model = Arc::new(GraspModel::new(&p, &ModelOptions::default()).unwrap());
        let mut s = ExactSolver::new(TorqueQp::exact(model), Default::default()).unwrap();
        let mut out = Solution::default();
        s.solve_raw(&p.wrench, &WarmStart::default(), &mut out);
        assert!(
            matches!(out.reason, Some(Reason::DualRay { .. })),
            "{:?}",
            out.reason
        );
        let alpha = s.conic.b_into(&p.wrench, &mut s.b);
        let xp = s.newton.particular(&p.wrench, alpha).unwrap().to_vec();
        let mut scratch = Vec::new();
        let check = |z: &[f64], scratch: &mut Vec<f64>| {
            s.conic
                .dual_ray(&s.b, &xp, z, CERTIFICATE_TOLERANCE, scratch)
        };
        let ray = s.dual.clone();
        assert!(check(&ray, &mut scratch).passed);
        let scaled: Vec<f64> = ray.iter().map(|v| 1e-30 * v).collect();
        assert!(check(&scaled, &mut scratch).passed, "a scaled ray failed");
        let negated: Vec<f64> = ray.iter().map(|v| -v).collect();
        let c = check(&negated, &mut scratch);
        assert!(!c.passed && c.dual > 1e-9, "a negated ray passed: {c:?}");
        // One multiplier moved by a millionth of the largest: torque terms are left.
        let eq = s.conic.linear_at.min(s.conic.rows());
        let zmax = ray[eq..].iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let i = (eq..ray.len())
            .max_by(|&a, &b| ray[a].abs().total_cmp(&ray[b].abs()))
            .unwrap();
        let mut moved = ray.clone();
        moved[i] += 1e-6 * zmax;
        let c = check(&moved, &mut scratch);
        assert!(
            !c.passed && c.stationarity > 1e-9,
            "a moved ray passed: {c:?}"
        );
        // A point that misses the equalities is no x_p.
        if s.conic
            .cones
            .first()
            .is_some_and(|c| matches!(c, grasp_core::ConeKind::Zero(_)))
        {
            let off: Vec<f64> = xp.iter().map(|v| v + 1e-3).collect();
            let c = s
                .conic
                .dual_ray(&s.b, &off, &ray, CERTIFICATE_TOLERANCE, &mut scratch);
            assert!(
                !c.passed && c.particular > 1e-9,
                "a wrong x_p passed: {c:?}"
            );
        }
        // Feasible grasps: the converged multipliers are no ray.
        let mut checked = 0;
        for case in grasp_testkit::reference_cases() {
            let p = grasp_testkit::reference_problem(&case["problem"]);
            let model = Arc::new(GraspModel::new(&p, &ModelOptions::default()).unwrap());
            let mut s = ExactSolver::new(TorqueQp::exact(model), Default::default()).unwrap();
            let alpha = s.conic.b_into(&p.wrench, &mut s.b);
            let ipm = s.ipm.insert(Ipm::new(&s.conic, IpmSettings::default()));
            if alpha == 0.0 || ipm.solve(&s.conic, &s.b, &mut |_| false) != IpmEnd::Converged {
                continue;
            }
            ipm.dual_into(&s.conic, &mut s.dual);
            let Some(xp) = s.newton.particular(&p.wrench, alpha) else {
                continue;
            };
            let c = s
                .conic
                .dual_ray(&s.b, xp, &s.dual, CERTIFICATE_TOLERANCE, &mut scratch);
            // P x + Aᵀ z = 0 leaves torque terms unless x = 0, and then zᵀ s ≥ 0.
            assert!(
                !c.passed && (c.stationarity > 1e-9 || c.value >= -1e-6),
                "a feasible grasp's multipliers passed: {c:?}"
            );
            checked += 1;
        }
        assert!(checked >= 30, "only {checked} reference grasps checked");
    }

    /// The interior-point method on the null space of the equalities reaches the
    /// optimum it reaches on the form itself, both answers certified from scratch: on
    /// the reference grasps and on three grasps of the robustness sweep that fall back
    /// to it.
    #[test]
    fn the_reduced_interior_point_method_finds_the_full_ones_optimum() {
        let sweep = [(1541, 1.0), (1439, 1.0), (10376, 0.25)]
            .map(|(seed, friction)| grasp_testkit::sweep_grasp(seed, friction));
        let cases = grasp_testkit::reference_cases();
        let problems = cases
            .iter()
            .map(|case| grasp_testkit::reference_problem(&case["problem"]))
            .chain(sweep);
        let (mut checked, mut worst) = (0, 0.0f64);
        for p in problems {
            let model = Arc::new(GraspModel::new(&p, &ModelOptions::default()).unwrap());
            let mut s = ExactSolver::new(TorqueQp::exact(model), Default::default()).unwrap();
            let alpha = s.conic.b_into(&p.wrench, &mut s.b);
            let Some(g) = s.newton.reduced_rows(&s.conic) else {
                continue;
            };
            let mut full = Ipm::new(&s.conic, IpmSettings::default());
            if alpha == 0.0 || full.solve(&s.conic, &s.b, &mut |_| false) != IpmEnd::Converged {
                continue;
            }
            let mut reduced = Ipm::reduced(&s.conic, g, IpmSettings::default());
            let rhs = s.newton.reduced_rhs(&p.wrench, alpha).1.to_vec();
            let end = reduced.solve(&s.conic, &rhs, &mut |_| false);
            assert_eq!(end, IpmEnd::Converged);
            let mut x = vec![0.0; s.conic.nx];
            s.newton.lift(&reduced.x, &mut x);
            let (mut z, mut scratch) = (vec![0.0; s.conic.rows()], Vec::new());
            for (x, ipm) in [(&full.x[..], &full), (&x[..], &reduced)] {
                ipm.dual_into(&s.conic, &mut z);
                let c = s
                    .conic
                    .certificate(&s.b, x, &z, CERTIFICATE_TOLERANCE, &mut scratch);
                assert!(c.passed, "reduced {}: {c:?}", ipm.is_reduced());
            }
            // Two answers each within the certificate's gap of the optimum.
            let sigma = |x: &[f64]| x[..s.conic.joints].iter().map(|v| v * v).sum::<f64>();
            let (a, b) = (sigma(&full.x), sigma(&x));
            let r = (a - b).abs() / a.max(b).max(1.0);
            assert!(r <= 2.0 * CERTIFICATE_TOLERANCE, "σ {a} against {b}");
            worst = worst.max(r);
            checked += 1;
        }
        eprintln!("{checked} grasps, worst σ difference {worst:.1e}");
        assert!(checked >= 30, "only {checked} grasps checked");
    }

    /// Grasps whose equalities leave at most one free direction: the closed form
    /// agrees with the general path on every status and, where both are optimal, σ
    /// within twice the certificate's tolerance (each answer within its gap). The
    /// general path (Newton from the inscribed optimum, else the interior-point
    /// method) is run by hand, so that the closed form cannot take it; on seed 1545 at
    /// normal friction (two cones on their boundary, one direction) Newton must solve
    /// it, replacing a dependent piece (`tests/exact.rs`).
    #[test]
    fn the_closed_form_agrees_with_the_general_path_on_one_free_direction() {
        let (mut lines, mut closed, mut worst) = (0, [0; 2], 0.0f64);
        let sweep = (0..3000u64).map(|s| (s, if s % 2 == 0 { 1.0 } else { 0.25 }));
        for (seed, friction) in sweep.chain([(1545, 1.0)]) {
            let p = grasp_testkit::sweep_grasp(seed, friction);
            let Ok(model) = GraspModel::new(&p, &ModelOptions::default()) else {
                continue;
            };
            let mut s =
                ExactSolver::new(TorqueQp::exact(Arc::new(model)), Default::default()).unwrap();
            if !s.newton.is_line() {
                continue;
            }
            lines += 1;
            let (w, cold) = (&p.wrench, &WarmStart::default());
            let mut out = Solution::default();
            s.solve_raw(w, cold, &mut out);
            if out.status != Status::Optimal {
                // (Only a grasp the general path, or the ray of the one point the
                // equalities admit, proves infeasible.)
                assert_eq!(
                    out.status,
                    Status::Infeasible,
                    "seed {seed}: {:?}",
                    out.reason
                );
                continue;
            }
            assert_eq!(out.method, Some("closed_form"), "seed {seed}");
            closed[s.newton.free_directions()] += 1;
            let sigma = sigma_of(&s.newton.x, s.conic.joints);
            let alpha = s.conic.b_into(w, &mut s.b);
            s.inner.solve_raw(w, cold, &mut s.lin);
            let mut general = Solution::default();
            let newton =
                s.lin.status == Status::Optimal && s.newton_from_polyhedra(w, alpha, &mut general);
            assert!(newton || (seed, friction) != (1545, 1.0));
            let other = if newton {
                // (A certified answer is kept in `answer_x`.)
                sigma_of(&s.answer_x, s.conic.joints)
            } else {
                let mut ipm = Ipm::new(&s.conic, IpmSettings::default());
                assert_eq!(
                    ipm.solve(&s.conic, &s.b, &mut |_| false),
                    IpmEnd::Converged,
                    "seed {seed}"
                );
                sigma_of(&ipm.x, s.conic.joints)
            };
            let r = (sigma - other).abs() / sigma.max(other).max(1.0);
            assert!(
                r <= 2.0 * CERTIFICATE_TOLERANCE,
                "seed {seed}: σ {sigma} against {other}"
            );
            worst = worst.max(r);
        }
        eprintln!(
            "{lines} grasps with at most one free direction, {closed:?} (none, one) by the \
             closed form, worst σ difference {worst:.1e}"
        );
        assert!(closed[0] >= 30 && closed[1] >= 100, "{closed:?}");
    }

    /// ‖x_τ‖², the scaled objective.
    fn sigma_of(x: &[f64], joints: usize) -> f64 {
        x[..joints].iter().map(|v| v * v).sum()
    }

    /// The Newton answers of the reference grasps pass the certificate, and the same
    /// answers spoiled each way fail it.
    #[test]
    fn the_certificate_accepts_the_optimum_and_nothing_near_it() {
        let mut checked = 0;
        for case in grasp_testkit::reference_cases() {
            let p = grasp_testkit::reference_problem(&case["problem"]);
            let model = Arc::new(GraspModel::new(&p, &ModelOptions::default()).unwrap());
            let mut s = ExactSolver::new(TorqueQp::exact(model), Default::default()).unwrap();
            let mut out = Solution::default();
            s.solve_raw(&p.wrench, &WarmStart::default(), &mut out);
            if out.method != Some("newton") {
                continue;
            }
            let (x, z) = (s.answer_x.clone(), s.answer_z.clone());
            let mut scratch = Vec::new();
            let check = |x: &[f64], z: &[f64], scratch: &mut Vec<f64>| {
                s.conic
                    .certificate(&s.b, x, z, CERTIFICATE_TOLERANCE, scratch)
            };
            assert!(check(&x, &z, &mut scratch).passed);
            // Stationarity needs no multipliers of the equalities: with the
            // least-squares ones the full residual P x + Aᵀ z vanishes too.
            let (rows, nx) = (s.conic.rows(), s.conic.nx);
            let eq = s.conic.equalities();
            let mut g: Vec<f64> = (0..nx)
                .map(|j| if j < s.conic.joints { 2.0 * x[j] } else { 0.0 })
                .collect();
            for i in eq..rows {
                for j in 0..nx {
                    g[j] += s.conic.a[(i, j)] * z[i];
                }
            }
            if eq > 0 {
                let e = grasp_core::Matrix::from_fn(eq, nx, |i, j| s.conic.a[(i, j)]);
                let d = grasp_core::linalg::decompose(
                    &e,
                    grasp_core::linalg::RankThreshold::Relative(1e-13),
                )
                .unwrap();
                let pinv = d.pseudo_inverse(); // nx × eq
                let ze: Vec<f64> = (0..eq)
                    .map(|r| -(0..nx).map(|j| pinv[(j, r)] * g[j]).sum::<f64>())
                    .collect();
                for j in 0..nx {
                    let full = g[j] + (0..eq).map(|r| e[(r, j)] * ze[r]).sum::<f64>();
                    assert!(full.abs() < 1e-8 * (1.0 + grasp_core::matrix::norm_inf(&g)));
                }
            }
            // Spoiled: x moved off the optimum along a torque, z scaled, z's sign flipped
            // on a loaded cone, a NaN.
            let mut bad = x.clone();
            bad[0] += 1e-6 * (1.0 + grasp_core::matrix::norm_inf(&x));
            assert!(!check(&bad, &z, &mut scratch).passed, "moved x passed");
            // Along the equalities' null space (the equalities still hold).
            if let Some(nt) = s.conic.eq_null_t.as_ref().filter(|nt| nt.nrows() > 0) {
                let moved: Vec<f64> = (0..nx).map(|j| x[j] + 1e-6 * nt[(0, j)]).collect();
                let c = check(&moved, &z, &mut scratch);
                assert!(
                    !c.passed && c.stationarity > 1e-9,
                    "a feasible move passed: {c:?}"
                );
            }
            let scaled: Vec<f64> = z.iter().map(|v| 1.01 * v).collect();
            if z[eq..].iter().any(|v| *v != 0.0) {
                assert!(!check(&x, &scaled, &mut scratch).passed, "scaled z passed");
                let flipped: Vec<f64> = z.iter().map(|v| -v).collect();
                assert!(
                    !check(&x, &flipped, &mut scratch).passed,
                    "negated z passed"
                );
            }
            let mut nan = x.clone();
            nan[nx - 1] = f64::NAN;
            assert!(!check(&nan, &z, &mut scratch).passed, "NaN passed");
            checked += 1;
        }
        assert!(checked >= 30, "only {checked} reference grasps checked");
    }
}
