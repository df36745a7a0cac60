//! The native exact-cone solver: the torque problem with the friction cones of eqs. 1–4
//! themselves, not their linearisations, for every contact model.
//!
//! A solve:
//! 1. solves the problem with circumscribed polyhedra (`N = 8`, which contain the
//!    cones) by the active-set method: infeasible there is a certificate that the exact
//!    problem is infeasible, found in a few microseconds;
//! 2. solves the exact problem by the dense interior-point method of [`crate::ipm`] on
//!    the core's scaled [`ConicForm`];
//! 3. checks the answer from scratch ([`ConicForm::certificate`]: primal and dual cone
//!    feasibility, stationarity, complementarity and the duality gap). Only an answer
//!    that passes is `optimal`. One that does not, or a run that does not converge, is
//!    tried once more against finer circumscribed polyhedra (`N = 256`, within 8e-5 of
//!    the cones), which certify the grasps infeasible that the coarse ones could not.

use crate::ipm::{Ipm, IpmEnd, IpmSettings};
use crate::{ActiveSetSettings, ActiveSetSolver, BuildError};
use grasp_core::{
    circumscribed_cone, Capabilities, Certificate, ConeRepr, ConicForm, Constraints, Linearization,
    Reason, Solution, Status, TorqueQp, TorqueSolver, WarmStart,
};

/// Relative tolerance of the optimality certificate (each measure against the size of
/// its own terms, on the scaled problem).
pub const CERTIFICATE_TOLERANCE: f64 = 1e-9;

/// Sides of the polygons of the feasibility proofs.
const PROOF_SIDES: usize = 8;
/// Sides of the finer circumscribed polygons tried when the interior-point method does
/// not converge on a grasp the coarse proofs left undecided.
const FINE_SIDES: usize = 256;

/// The native solver of a view with exact cones.
#[derive(Clone, Debug)]
pub struct ExactSolver {
    qp: TorqueQp,
    conic: ConicForm,
    ipm: Ipm,
    /// The view with every exact cone circumscribed.
    outer: ActiveSetSolver,
    settings: ActiveSetSettings,
    lin: Solution,
    b: Vec<f64>,
    dual: Vec<f64>,
    scratch: Vec<f64>,
    /// The last certificate checked.
    certificate: Certificate,
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
        let outer = ActiveSetSolver::new(polyhedral(&qp, &lin, circumscribed_cone), settings)?;
        let conic = ConicForm::new(&qp);
        let ipm = Ipm::new(&conic, IpmSettings::default());
        let rows = conic.rows();
        Ok(Self {
            ipm,
            outer,
            settings,
            lin: Solution::default(),
            b: vec![0.0; rows],
            dual: vec![0.0; rows],
            scratch: Vec::new(),
            certificate: Certificate::default(),
            conic,
            qp,
        })
    }

    /// The certificate of the last interior-point answer.
    pub fn certificate(&self) -> &Certificate {
        &self.certificate
    }

    /// Whether the circumscribed polyhedra at `sides` admit no torque for `w`; the
    /// reason when they do not.
    fn outer_infeasible(&mut self, w: &[f64; 6], sides: usize) -> Option<Reason> {
        let cold = WarmStart::default();
        if sides == PROOF_SIDES {
            self.outer.solve_raw(w, &cold, &mut self.lin);
        } else {
            // Only for grasps at the edge of feasibility: built when needed.
            let lin = Linearization {
                sides,
                ..self.qp.constraints.linearization.unwrap_or_default()
            };
            let fine = polyhedral(&self.qp, &lin, circumscribed_cone);
            let mut s = ActiveSetSolver::new(fine, self.settings).ok()?;
            s.solve_raw(w, &cold, &mut self.lin);
        }
        (self.lin.status == Status::Infeasible).then(|| Reason::OuterApproximation {
            sides,
            cause: Box::new(
                self.lin
                    .reason
                    .take()
                    .unwrap_or(Reason::NoAdmissibleTorque {
                        relaxation: None,
                        blocking: Vec::new(),
                    }),
            ),
        })
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

    fn solve_raw(&mut self, w: &[f64; 6], _warm: &WarmStart<'_>, out: &mut Solution) {
        out.active_set = None;
        out.iterations = 0;
        out.torque.clear();
        out.internal_forces.clear();
        // 1. Infeasibility: the circumscribed polyhedra.
        if let Some(reason) = self.outer_infeasible(w, PROOF_SIDES) {
            out.iterations = self.lin.iterations;
            return Self::infeasible(out, reason);
        }
        out.iterations = self.lin.iterations;
        // 2. The exact problem.
        let alpha = self.conic.b_into(w, &mut self.b);
        if alpha == 0.0 {
            // Every row is homogeneous: τ = 0 is feasible and optimal.
            out.status = Status::Optimal;
            out.torque.resize(self.conic.joints, 0.0);
            out.method = Some("interior_point");
            return;
        }
        let end = self.ipm.solve(&self.conic, &self.b);
        out.iterations += self.ipm.iterations;
        out.method = Some("interior_point");
        if end == IpmEnd::Converged {
            // 3. The certificate, from scratch.
            self.ipm.dual_into(&self.conic, &mut self.dual);
            self.certificate = self.conic.certificate(
                &self.b,
                &self.ipm.x,
                &self.dual,
                CERTIFICATE_TOLERANCE,
                &mut self.scratch,
            );
            if self.certificate.passed {
                out.status = Status::Optimal;
                self.conic.unscale_into(
                    &self.ipm.x,
                    alpha,
                    &mut out.torque,
                    &mut out.internal_forces,
                );
                return;
            }
        }
        if let Some(reason) = self.outer_infeasible(w, FINE_SIDES) {
            return Self::infeasible(out, reason);
        }
        let c = self.certificate;
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
                IpmEnd::Stalled => "the exact-cone interior-point method stalled".into(),
            } + &format!(" (the circumscribed polyhedra at N = {FINE_SIDES} admit a torque)"),
        });
    }
}
