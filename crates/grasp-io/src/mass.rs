//! The fingers' weight: each link's mass and centre of mass, and the joint torques
//! gravity puts on the joints, `Σ_b m_b J_bᵀ g` (MuJoCo's `−qfrc_bias` at rest,
//! Pinocchio's `−computeGeneralizedGravity`), which enter the grasp as passive torques
//! (`Jᵀ f = T u + τ_p`).

use crate::frame::Vector3;
use crate::urdf::{JointKind, Pose, Robot};

/// What a link weighs.
#[derive(Clone, Debug, PartialEq)]
pub enum LinkMass {
    /// Nothing: no `<inertial>` (and, in MJCF, no geoms that give a mass), or a link
    /// between one MJCF body's joints.
    None,
    /// `mass` (kg, or the file's mass unit) at `com` (in the link's frame). For an MJCF
    /// body with `gravcomp`, the part gravity still loads: its mass times
    /// `1 − gravcomp`.
    Known {
        /// The mass.
        mass: f64,
        /// The centre of mass, in the link's frame.
        com: Vector3,
    },
    /// Not known, and why (a malformed `<inertial>`, a mass from a mesh): an error
    /// only when gravity is asked for and a moving joint carries the link.
    Unknown(String),
}

impl Robot {
    /// Gravity's torques on every joint (one per [`Robot::joints`], 0 on fixed ones) at
    /// `pose` (every link placed: [`Robot::pose`]), for the acceleration of gravity `g`
    /// in the root frame (m/s² in SI): on a hinge, `g · (a × (S − M o))`, with `M` the
    /// mass the joint carries, `S` its first moment and `o`, `a` the joint's anchor
    /// and axis; on a slide, `M (a · g)`. `Err` names a link whose mass is not known
    /// and that a moving joint carries.
    pub fn gravity_torques(&self, pose: &Pose, g: &Vector3) -> Result<Vec<f64>, String> {
        let n = self.links.len();
        let (mut carried, mut moment) = (vec![0.0; n], vec![Vector3::zeros(); n]);
        for &l in self.order.iter().rev() {
            match &self.masses[l] {
                LinkMass::None => {}
                LinkMass::Known { mass, com } => {
                    carried[l] += mass;
                    moment[l] += *mass * pose.links[l].transform_point(com);
                }
                LinkMass::Unknown(why) => {
                    let moves = self
                        .chain(l)
                        .iter()
                        .any(|&j| self.joints[j].kind != JointKind::Fixed);
                    if moves {
                        return Err(format!("link `{}`: {why}", self.links[l]));
                    }
                }
            }
            if let Some(j) = self.parent_joint[l] {
                let p = self.joints[j].parent;
                carried[p] += carried[l];
                let m = moment[l];
                moment[p] += m;
            }
        }
        Ok(self
            .joints
            .iter()
            .enumerate()
            .map(|(j, joint)| {
                let c = joint.child;
                let frame = pose.joints[j];
                let axis = frame.rotation * joint.axis;
                match joint.kind {
                    JointKind::Fixed => 0.0,
                    k if k.rotates() => {
                        g.dot(&axis.cross(&(moment[c] - carried[c] * frame.translation)))
                    }
                    _ => carried[c] * axis.dot(g),
                }
            })
            .collect())
    }
}
