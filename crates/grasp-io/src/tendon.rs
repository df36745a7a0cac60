//! Spatial tendons (MJCF `<tendon><spatial>`): a string through sites, wrapped around
//! spheres and cylinders, whose length's derivative in each joint is the moment arm of
//! an actuator that pulls on it. The arms depend on the configuration.
//!
//! The wrapping follows MuJoCo's model of it (`mju_wrap`), so that a hand's arms are
//! MuJoCo's: between two sites the string either runs straight or wraps the geom's
//! circle (a cylinder's cross-section, or a sphere's great circle through both ends)
//! along the tangents from each end; a side site picks the side. The derivative is the
//! envelope theorem's: each straight piece contributes its unit direction times the
//! difference of its ends' velocities, with the tangent points fixed to the geom's body
//! (the arc on the geom moves rigidly with it).

use crate::frame::{Isometry3, Vector3};
use crate::urdf::{JointKind, Pose, Robot};

/// Below this, relative to the lengths it is compared with, a length, a squared length
/// or a determinant is zero: MuJoCo's `mjMINVAL`, which MuJoCo compares with absolute
/// values, taken relative to the wrap's own scale (its radius, its ends' distances), so
/// that a hand written in other units wraps the same way. At every configuration that
/// is not degenerate at the level of rounding, the sides and the "no wrap"s are
/// MuJoCo's.
const TINY: f64 = 1e-15;

/// The solid a tendon wraps around.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WrapShape {
    /// Around a great circle through both ends.
    Sphere,
    /// Around the circular cross-section, as a helix.
    Cylinder,
}

/// A sphere or cylinder geom that a tendon wraps around.
#[derive(Clone, Debug, PartialEq)]
pub struct WrapGeom {
    /// The geom's name.
    pub name: String,
    /// The link it is on.
    pub link: usize,
    /// Its frame in the link's frame (a cylinder's axis is its z axis).
    pub frame: Isometry3,
    /// Its radius (`size[0]`), in the model's length unit.
    pub radius: f64,
    /// Sphere or cylinder.
    pub shape: WrapShape,
}

/// One element of a tendon's path.
#[derive(Clone, Debug, PartialEq)]
pub enum PathPoint {
    /// A site (an index of [`Robot::sites`]) the string passes through.
    Site(usize),
    /// A geom the string may wrap between the sites before and after it; `side` (a
    /// site) picks the side it wraps on.
    Wrap {
        /// The geom.
        geom: WrapGeom,
        /// The side site.
        side: Option<usize>,
    },
    /// A pulley: the branch that follows counts `1 / divisor` toward the length.
    Pulley {
        /// The divisor (> 0).
        divisor: f64,
    },
}

/// A spatial tendon: its path of sites, wrapping geoms and pulleys, checked at load
/// (every branch starts and ends at a site, and a geom sits between two sites).
#[derive(Clone, Debug, PartialEq)]
pub struct SpatialTendon {
    /// Its name.
    pub name: String,
    /// The path, in file order.
    pub path: Vec<PathPoint>,
    /// Line of the element.
    pub line: u32,
}

/// A side site inside the geom it picks the side of: MuJoCo then wraps the string
/// inside the circle, which this reader does not model.
#[derive(Clone, Debug, PartialEq)]
pub struct InsideWrap {
    /// The wrapping geom.
    pub geom: String,
    /// The tendon.
    pub tendon: String,
}

/// What a spring stretches.
#[derive(Clone, Debug, PartialEq)]
pub enum SpringOn {
    /// A joint's motion (an index of [`Robot::joints`]).
    Joint(usize),
    /// A fixed tendon, `Σ coef · motion` over (joint, coef).
    Fixed(Vec<(usize, f64)>),
    /// A spatial tendon's length (an index of [`Robot::tendons`]).
    Spatial(usize),
}

/// A linear spring (MJCF `stiffness`), as MuJoCo's `qfrc_spring`: its force is
/// `−k (L − rest)` outside the rest range and 0 inside it.
#[derive(Clone, Debug, PartialEq)]
pub struct Spring {
    /// The joint's or tendon's name.
    pub name: String,
    /// What it stretches.
    pub on: SpringOn,
    /// k, force per unit length (or torque per radian).
    pub stiffness: f64,
    /// The rest range of L, low ≤ high, in the units of L: a joint's and a fixed
    /// tendon's measured as their motion from the joints' references (MuJoCo's
    /// `springref` or `springlength` less the references' part).
    pub rest: (f64, f64),
}

impl SpatialTendon {
    /// The links the path's points are on, in path order, branch by branch (a pulley
    /// starts a new branch); a wrap's geom is a point between its sites.
    pub(crate) fn branches(&self, robot: &Robot) -> Vec<Vec<usize>> {
        let mut out = vec![Vec::new()];
        for p in &self.path {
            match p {
                PathPoint::Site(s) => out.last_mut().expect("a branch").push(robot.sites[*s].link),
                PathPoint::Wrap { geom, .. } => out.last_mut().expect("a branch").push(geom.link),
                PathPoint::Pulley { .. } => out.push(Vec::new()),
            }
        }
        out
    }
}

impl Robot {
    /// The joints a spatial tendon's length can depend on: those that move one end of
    /// a piece of its path and not the other (a joint moving both moves the piece
    /// rigidly). Sorted, moving joints only.
    pub fn tendon_joints(&self, tendon: usize) -> Vec<usize> {
        let mut out = Vec::new();
        for branch in self.tendons[tendon].branches(self) {
            for w in branch.windows(2) {
                let (a, b) = (self.moving_chain(w[0]), self.moving_chain(w[1]));
                out.extend(a.iter().filter(|j| !b.contains(j)));
                out.extend(b.iter().filter(|j| !a.contains(j)));
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The moving joints from the root to `link`.
    fn moving_chain(&self, link: usize) -> Vec<usize> {
        let mut c = self.chain(link);
        c.retain(|&j| self.joints[j].kind != JointKind::Fixed);
        c
    }

    /// A spatial tendon's length and its moment arms `∂L/∂q_j` on the joints it
    /// depends on ([`Robot::tendon_joints`] order), at `pose` (which must place the
    /// links of its path and the joints above them). MuJoCo's `ten_J`, per joint.
    pub fn tendon_moments(
        &self,
        tendon: usize,
        pose: &Pose,
    ) -> Result<(f64, Vec<(usize, f64)>), InsideWrap> {
        let t = &self.tendons[tendon];
        let joints = self.tendon_joints(tendon);
        let mut arms = vec![0.0; joints.len()];
        let mut length = 0.0;
        let site = |s: usize| {
            let at = pose.links[self.sites[s].link] * self.sites[s].frame;
            (at.translation, self.sites[s].link)
        };
        // One straight piece from `a` (on link la) to `b` (on lb), weighted by 1/divisor.
        let piece =
            |(a, la): (Vector3, usize), (b, lb): (Vector3, usize), scale: f64, arms: &mut [f64]| {
                let d = b - a;
                let n = d.norm();
                if la == lb || n <= TINY * (a.norm() + b.norm()) {
                    return n;
                }
                let u = d / n;
                let (ca, cb) = (self.moving_chain(la), self.moving_chain(lb));
                for (k, &j) in joints.iter().enumerate() {
                    let (on_a, on_b) = (ca.contains(&j), cb.contains(&j));
                    if on_a != on_b {
                        let p = if on_b { b } else { a };
                        let v = self.point_velocity(j, pose, &p);
                        arms[k] += scale * if on_b { u.dot(&v) } else { -u.dot(&v) };
                    }
                }
                n
            };
        let mut divisor = 1.0;
        let mut k = 0;
        while k < t.path.len() {
            let PathPoint::Site(s0) = t.path[k] else {
                if let PathPoint::Pulley { divisor: dv } = t.path[k] {
                    divisor = dv;
                }
                k += 1;
                continue;
            };
            let scale = 1.0 / divisor;
            match t.path.get(k + 1) {
                Some(PathPoint::Site(s1)) => {
                    length += scale * piece(site(s0), site(*s1), scale, &mut arms);
                    k += 1;
                }
                Some(PathPoint::Wrap { geom, side }) => {
                    let PathPoint::Site(s1) = t.path[k + 2] else {
                        unreachable!("checked at load: a wrap sits between two sites")
                    };
                    let (a, b) = (site(s0), site(s1));
                    let frame = pose.links[geom.link] * geom.frame;
                    let side = side.map(|s| site(s).0);
                    match wrap(&a.0, &b.0, &frame, geom.radius, geom.shape, side.as_ref()).map_err(
                        |()| InsideWrap {
                            geom: geom.name.clone(),
                            tendon: t.name.clone(),
                        },
                    )? {
                        None => length += scale * piece(a, b, scale, &mut arms),
                        Some((t0, t1, arc)) => {
                            let l0 = piece(a, (t0, geom.link), scale, &mut arms);
                            let l1 = piece((t1, geom.link), b, scale, &mut arms);
                            length += scale * (l0 + arc + l1);
                        }
                    }
                    k += 2;
                }
                _ => k += 1,
            }
        }
        Ok((length, joints.into_iter().zip(arms).collect()))
    }

    /// The springs' torques on every joint (one per [`Robot::joints`]) at the joints'
    /// motion `q` ([`Robot::full_positions`]) and `pose` (which must place the links
    /// of the spatial tendons with springs): `Σ −k (L − clamp(L, rest)) ∂L/∂q`,
    /// MuJoCo's `qfrc_spring`.
    pub fn passive_torques(&self, q: &[f64], pose: &Pose) -> Result<Vec<f64>, InsideWrap> {
        let mut out = vec![0.0; self.joints.len()];
        for s in &self.springs {
            let stretch = |l: f64| l - l.clamp(s.rest.0, s.rest.1);
            match &s.on {
                SpringOn::Joint(j) => out[*j] -= s.stiffness * stretch(q[*j]),
                SpringOn::Fixed(terms) => {
                    let l: f64 = terms.iter().map(|&(j, c)| c * q[j]).sum();
                    let f = -s.stiffness * stretch(l);
                    for &(j, c) in terms {
                        out[j] += f * c;
                    }
                }
                SpringOn::Spatial(t) => {
                    let (l, arms) = self.tendon_moments(*t, pose)?;
                    let f = -s.stiffness * stretch(l);
                    for (j, a) in arms {
                        out[j] += f * a;
                    }
                }
            }
        }
        Ok(out)
    }

    /// The velocity of point `p` (fixed to a link below joint `j`) per unit of `q_j`.
    fn point_velocity(&self, j: usize, pose: &Pose, p: &Vector3) -> Vector3 {
        let frame = pose.joints[j];
        let axis = frame.rotation * self.joints[j].axis;
        if self.joints[j].kind.rotates() {
            axis.cross(&(*p - frame.translation))
        } else {
            axis
        }
    }
}

/// The wrap of the string from `x0` to `x1` around a geom at `frame`: its two tangent
/// points and the length on the geom, or `None` when the string runs straight. `Err`
/// when the side site is inside the geom.
#[allow(clippy::type_complexity)]
pub(crate) fn wrap(
    x0: &Vector3,
    x1: &Vector3,
    frame: &Isometry3,
    radius: f64,
    shape: WrapShape,
    side: Option<&Vector3>,
) -> Result<Option<(Vector3, Vector3, f64)>, ()> {
    let (p0, p1) = (
        frame.inverse_transform_point(x0),
        frame.inverse_transform_point(x1),
    );
    if p0.norm() <= TINY * radius || p1.norm() <= TINY * radius {
        return Ok(None);
    }
    // The plane of the circle: a cylinder's cross-section, or the sphere's great
    // circle through both ends.
    let (ax0, ax1) = match shape {
        WrapShape::Cylinder => (Vector3::x(), Vector3::y()),
        WrapShape::Sphere => {
            let ax0 = p0.normalize();
            let mut normal = p0.cross(&p1);
            let nrm = normal.norm();
            if nrm <= TINY * p0.norm() * p1.norm() {
                // Ends in line with the centre: any plane through them.
                let a = ax0.map(f64::abs);
                let i = if a.y > a.x && a.y > a.z {
                    1
                } else if a.z > a.x && a.z > a.y {
                    2
                } else {
                    0
                };
                let mut other = Vector3::new(1.0, 1.0, 1.0);
                other[i] = 0.0;
                normal = ax0.cross(&other).normalize();
            } else {
                normal /= nrm;
            }
            (ax0, normal.cross(&ax0).normalize())
        }
    };
    let flat = |v: &Vector3| [v.dot(&ax0), v.dot(&ax1)];
    let (d0, d1) = (flat(&p0), flat(&p1));
    let side = match side {
        None => None,
        Some(s) => {
            let s = frame.inverse_transform_point(s);
            if s.norm() < radius {
                return Err(());
            }
            let sd = normalize2(flat(&s), radius);
            Some([sd[0] * radius, sd[1] * radius])
        }
    };
    let Some((t0, t1, mut arc)) = circle_wrap(d0, d1, side, radius) else {
        return Ok(None);
    };
    let lift = |t: [f64; 2]| ax0 * t[0] + ax1 * t[1];
    let (mut r0, mut r1) = (lift(t0), lift(t1));
    if shape == WrapShape::Cylinder {
        // A helix: the height grows in proportion to the length travelled in the plane.
        let l0 = ((p0.x - r0.x).powi(2) + (p0.y - r0.y).powi(2)).sqrt();
        let l1 = ((p1.x - r1.x).powi(2) + (p1.y - r1.y).powi(2)).sqrt();
        let total = l0 + arc + l1;
        r0.z = p0.z + (p1.z - p0.z) * l0 / total;
        r1.z = p0.z + (p1.z - p0.z) * (l0 + arc) / total;
        let height = (r1.z - r0.z).abs();
        arc = (arc * arc + height * height).sqrt();
    }
    Ok(Some((
        frame.transform_point(&r0),
        frame.transform_point(&r1),
        arc,
    )))
}

/// `v / |v|`, or `(1, 0)` when `|v|` is at most [`TINY`] times `scale` (0 included).
fn normalize2(v: [f64; 2], scale: f64) -> [f64; 2] {
    let n = v[0].hypot(v[1]);
    if n <= TINY * scale {
        [1.0, 0.0]
    } else {
        [v[0] / n, v[1] / n]
    }
}

/// Whether the segments `p1 p2` and `p3 p4` cross.
fn crosses(p1: [f64; 2], p2: [f64; 2], p3: [f64; 2], p4: [f64; 2]) -> bool {
    let det = (p4[1] - p3[1]) * (p2[0] - p1[0]) - (p4[0] - p3[0]) * (p2[1] - p1[1]);
    let lengths = (p2[0] - p1[0]).hypot(p2[1] - p1[1]) * (p4[0] - p3[0]).hypot(p4[1] - p3[1]);
    if det.abs() <= TINY * lengths {
        return false;
    }
    let a = ((p4[0] - p3[0]) * (p1[1] - p3[1]) - (p4[1] - p3[1]) * (p1[0] - p3[0])) / det;
    let b = ((p2[0] - p1[0]) * (p1[1] - p3[1]) - (p2[1] - p1[1]) * (p1[0] - p3[0])) / det;
    (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)
}

/// The string from `e0` to `e1` around the circle of `radius` at the origin: the
/// tangent points from each end and the arc between them, or `None` when the straight
/// string misses the circle (or passes on the side away from `side`).
fn circle_wrap(
    e0: [f64; 2],
    e1: [f64; 2],
    side: Option<[f64; 2]>,
    radius: f64,
) -> Option<([f64; 2], [f64; 2], f64)> {
    let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
    let (sq0, sq1, rr) = (dot(e0, e0), dot(e1, e1), radius * radius);
    if sq0 < rr || sq1 < rr || radius <= TINY * sq0.max(sq1).sqrt() {
        return None;
    }
    let dif = [e1[0] - e0[0], e1[1] - e0[1]];
    let dd = dot(dif, dif);
    if dd <= TINY * rr {
        return None;
    }
    // The point of the straight string nearest the centre.
    let a = (-dot(dif, e0) / dd).clamp(0.0, 1.0);
    let near = [e0[0] + a * dif[0], e0[1] + a * dif[1]];
    if dot(near, near) > rr && side.is_none_or(|s| dot(s, near) >= 0.0) {
        return None;
    }
    let (s0, s1) = ((sq0 - rr).sqrt(), (sq1 - rr).sqrt());
    // The tangent point from `e` on one side (sign) of the line to the centre.
    let tangent = |e: [f64; 2], sq: f64, s: f64, sign: f64| {
        [
            (e[0] * rr + sign * radius * e[1] * s) / sq,
            (e[1] * rr - sign * radius * e[0] * s) / sq,
        ]
    };
    let candidates = [1.0, -1.0].map(|sign| {
        let (t0, t1) = (tangent(e0, sq0, s0, sign), tangent(e1, sq1, s1, -sign));
        // A candidate whose pieces cross is never preferred (MuJoCo scores it −10000,
        // below any other at the scale of metres; here below any other in any unit).
        let good = if crosses(e0, t0, e1, t1) {
            f64::NEG_INFINITY
        } else if let Some(s) = side {
            dot(normalize2([t0[0] + t1[0], t0[1] + t1[1]], radius), s)
        } else {
            let d = [t0[0] - t1[0], t0[1] - t1[1]];
            -dot(d, d)
        };
        (t0, t1, good)
    });
    let i = if candidates[0].2 > candidates[1].2 {
        0
    } else {
        1
    };
    let (t0, t1, _) = candidates[i];
    if crosses(e0, t0, e1, t1) {
        return None;
    }
    let (n0, n1) = (normalize2(t0, radius), normalize2(t1, radius));
    let mut angle = dot(n0, n1).clamp(-1.0, 1.0).acos();
    // The long way round when the tangent points' order says so; a sine of the angle
    // below 1e-12 is rounding, not an order: the string touches the circle at one
    // point (a string laid tangent to it), and its arc is 0, not 2π.
    let cross = t0[1] * t1[0] - t0[0] * t1[1];
    let order = if cross.abs() <= 1e-12 * rr {
        0.0
    } else {
        cross
    };
    if (order > 0.0 && i == 1) || (order < 0.0 && i == 0) {
        angle = 2.0 * std::f64::consts::PI - angle;
    }
    Some((t0, t1, radius * angle))
}
