//! Points, directions and rigid frames in 3-D: what forward kinematics, tendons and
//! masses need, and nothing more. Each operation computes the same terms in the same
//! order as nalgebra's `Vector3`, `UnitQuaternion` and `Isometry3` (which the readers
//! used before), so every frame is the same to the bit; that crate and its numeric
//! tower were a seventh of the first build.

use std::ops::{Add, AddAssign, Div, DivAssign, Index, IndexMut, Mul, Neg, Sub, SubAssign};

/// A point or a direction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vector3 {
    /// First component.
    pub x: f64,
    /// Second component.
    pub y: f64,
    /// Third component.
    pub z: f64,
}

impl Vector3 {
    /// `[x, y, z]`.
    #[inline]
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }

    /// The origin.
    #[inline]
    pub const fn zeros() -> Self {
        Self::new(0.0, 0.0, 0.0)
    }

    /// The unit x axis.
    #[inline]
    pub const fn x() -> Self {
        Self::new(1.0, 0.0, 0.0)
    }

    /// The unit y axis.
    #[inline]
    pub const fn y() -> Self {
        Self::new(0.0, 1.0, 0.0)
    }

    /// The unit z axis.
    #[inline]
    pub const fn z() -> Self {
        Self::new(0.0, 0.0, 1.0)
    }

    /// The components as an array.
    #[inline]
    pub const fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }

    /// `f` of each component.
    #[inline]
    pub fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Self::new(f(self.x), f(self.y), f(self.z))
    }

    /// The scalar product.
    #[inline]
    pub fn dot(&self, o: &Self) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// The vector product.
    #[inline]
    pub fn cross(&self, o: &Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    /// The squared length.
    #[inline]
    pub fn norm_squared(&self) -> f64 {
        self.dot(self)
    }

    /// The length.
    #[inline]
    pub fn norm(&self) -> f64 {
        self.norm_squared().sqrt()
    }

    /// The vector divided by its length (NaN for the zero vector).
    #[inline]
    pub fn normalize(&self) -> Self {
        *self / self.norm()
    }
}

impl From<[f64; 3]> for Vector3 {
    #[inline]
    fn from([x, y, z]: [f64; 3]) -> Self {
        Self::new(x, y, z)
    }
}

impl From<Vector3> for [f64; 3] {
    #[inline]
    fn from(v: Vector3) -> Self {
        v.to_array()
    }
}

impl Index<usize> for Vector3 {
    type Output = f64;
    #[inline]
    fn index(&self, i: usize) -> &f64 {
        match i {
            0 => &self.x,
            1 => &self.y,
            2 => &self.z,
            _ => panic!("index {i} of a 3-vector"),
        }
    }
}

impl IndexMut<usize> for Vector3 {
    #[inline]
    fn index_mut(&mut self, i: usize) -> &mut f64 {
        match i {
            0 => &mut self.x,
            1 => &mut self.y,
            2 => &mut self.z,
            _ => panic!("index {i} of a 3-vector"),
        }
    }
}

impl Add for Vector3 {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl Sub for Vector3 {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl AddAssign for Vector3 {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl SubAssign for Vector3 {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}

impl DivAssign<f64> for Vector3 {
    #[inline]
    fn div_assign(&mut self, s: f64) {
        *self = *self / s;
    }
}

impl Neg for Vector3 {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

impl Mul<f64> for Vector3 {
    type Output = Self;
    #[inline]
    fn mul(self, s: f64) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}

impl Mul<Vector3> for f64 {
    type Output = Vector3;
    #[inline]
    fn mul(self, v: Vector3) -> Vector3 {
        Vector3::new(self * v.x, self * v.y, self * v.z)
    }
}

impl Div<f64> for Vector3 {
    type Output = Self;
    #[inline]
    fn div(self, s: f64) -> Self {
        Self::new(self.x / s, self.y / s, self.z / s)
    }
}

/// A rotation, as a unit quaternion `w + x i + y j + z k`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnitQuaternion {
    w: f64,
    v: Vector3,
}

impl UnitQuaternion {
    /// No rotation.
    #[inline]
    pub const fn identity() -> Self {
        Self {
            w: 1.0,
            v: Vector3::zeros(),
        }
    }

    /// `[w, x, y, z]` divided by its length (its rotation; NaN for zero).
    #[inline]
    pub fn new_normalize(w: f64, x: f64, y: f64, z: f64) -> Self {
        // (x² + z²) + (y² + w²): nalgebra's four-term sum.
        let n = ((x * x + z * z) + (y * y + w * w)).sqrt();
        Self {
            w: w / n,
            v: Vector3::new(x / n, y / n, z / n),
        }
    }

    /// `[w, x, y, z]`.
    #[inline]
    pub fn coords(&self) -> [f64; 4] {
        [self.w, self.v.x, self.v.y, self.v.z]
    }

    /// The rotation by `angle` (radians) about the unit `axis`.
    #[inline]
    pub fn from_axis_angle(axis: &Vector3, angle: f64) -> Self {
        let (s, c) = (angle / 2.0).sin_cos();
        Self { w: c, v: *axis * s }
    }

    /// Roll, pitch and yaw about the fixed x, y and z axes: `Rz(yaw) Ry(pitch) Rx(roll)`.
    #[inline]
    pub fn from_euler_angles(roll: f64, pitch: f64, yaw: f64) -> Self {
        let (sr, cr) = (roll * 0.5).sin_cos();
        let (sp, cp) = (pitch * 0.5).sin_cos();
        let (sy, cy) = (yaw * 0.5).sin_cos();
        Self {
            w: cr * cp * cy + sr * sp * sy,
            v: Vector3::new(
                sr * cp * cy - cr * sp * sy,
                cr * sp * cy + sr * cp * sy,
                cr * cp * sy - sr * sp * cy,
            ),
        }
    }

    /// The shortest-arc rotation taking the direction of `a` to that of `b`: `None`
    /// when they are opposite (the axis is then undefined) or either is zero.
    #[inline]
    pub fn rotation_between(a: &Vector3, b: &Vector3) -> Option<Self> {
        let (na, nb) = (a.norm(), b.norm());
        if na == 0.0 || nb == 0.0 {
            return None;
        }
        let (a, b) = (*a / na, *b / nb);
        let c = a.cross(&b);
        let n = c.norm();
        if n > f64::EPSILON {
            let cos = a.dot(&b);
            // The cosine may leave [−1, 1] by rounding.
            if cos <= -1.0 {
                None
            } else if cos >= 1.0 {
                Some(Self::identity())
            } else {
                Some(Self::from_axis_angle(&(c / n), cos.acos()))
            }
        } else if a.dot(&b) < 0.0 {
            None
        } else {
            Some(Self::identity())
        }
    }

    /// The rotation of a rotation matrix (rows of `m`), by the larger of the trace and
    /// the diagonal entries (Shepperd's choice, for accuracy).
    #[inline]
    pub fn from_rotation_matrix(m: &[[f64; 3]; 3]) -> Self {
        let tr = m[0][0] + m[1][1] + m[2][2];
        let [w, x, y, z] = if tr > 0.0 {
            let d = (tr + 1.0).sqrt() * 2.0;
            [
                0.25 * d,
                (m[2][1] - m[1][2]) / d,
                (m[0][2] - m[2][0]) / d,
                (m[1][0] - m[0][1]) / d,
            ]
        } else if m[0][0] > m[1][1] && m[0][0] > m[2][2] {
            let d = (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt() * 2.0;
            [
                (m[2][1] - m[1][2]) / d,
                0.25 * d,
                (m[0][1] + m[1][0]) / d,
                (m[0][2] + m[2][0]) / d,
            ]
        } else if m[1][1] > m[2][2] {
            let d = (1.0 + m[1][1] - m[0][0] - m[2][2]).sqrt() * 2.0;
            [
                (m[0][2] - m[2][0]) / d,
                (m[0][1] + m[1][0]) / d,
                0.25 * d,
                (m[1][2] + m[2][1]) / d,
            ]
        } else {
            let d = (1.0 + m[2][2] - m[0][0] - m[1][1]).sqrt() * 2.0;
            [
                (m[1][0] - m[0][1]) / d,
                (m[0][2] + m[2][0]) / d,
                (m[1][2] + m[2][1]) / d,
                0.25 * d,
            ]
        };
        Self {
            w,
            v: Vector3::new(x, y, z),
        }
    }

    /// The opposite rotation.
    #[inline]
    pub fn inverse(&self) -> Self {
        Self {
            w: self.w,
            v: -self.v,
        }
    }

    /// The rotation matrix, by rows (its columns are the rotated x, y and z axes).
    #[inline]
    pub fn to_rotation_matrix(&self) -> [[f64; 3]; 3] {
        let (i, j, k, w) = (self.v.x, self.v.y, self.v.z, self.w);
        let (ww, ii, jj, kk) = (w * w, i * i, j * j, k * k);
        let (ij, wk, wj) = (i * j * 2.0, w * k * 2.0, w * j * 2.0);
        let (ik, jk, wi) = (i * k * 2.0, j * k * 2.0, w * i * 2.0);
        [
            [ww + ii - jj - kk, ij - wk, wj + ik],
            [wk + ij, ww - ii + jj - kk, jk - wi],
            [ik - wj, wi + jk, ww - ii - jj + kk],
        ]
    }

    /// `v` turned by the inverse rotation.
    #[inline]
    pub fn inverse_transform_vector(&self, v: &Vector3) -> Vector3 {
        self.inverse() * *v
    }

    /// The rotation's angle, in [0, π] (by `atan2`, accurate for small angles too).
    #[inline]
    pub fn angle(&self) -> f64 {
        2.0 * self.v.norm().atan2(self.w.abs())
    }

    /// The angle of the rotation taking `self` to `other`, in [0, π].
    #[inline]
    pub fn angle_to(&self, other: &Self) -> f64 {
        (self.inverse() * *other).angle()
    }
}

impl Mul for UnitQuaternion {
    type Output = Self;
    /// The rotation `rhs`, then `self`.
    #[inline]
    fn mul(self, r: Self) -> Self {
        let (a, b) = (self, r);
        Self {
            w: a.w * b.w - a.v.x * b.v.x - a.v.y * b.v.y - a.v.z * b.v.z,
            v: Vector3::new(
                a.w * b.v.x + a.v.x * b.w + a.v.y * b.v.z - a.v.z * b.v.y,
                a.w * b.v.y - a.v.x * b.v.z + a.v.y * b.w + a.v.z * b.v.x,
                a.w * b.v.z + a.v.x * b.v.y - a.v.y * b.v.x + a.v.z * b.w,
            ),
        }
    }
}

impl Mul<Vector3> for UnitQuaternion {
    type Output = Vector3;
    /// `p` turned: `p + w t + v × t` with `t = 2 v × p`.
    #[inline]
    fn mul(self, p: Vector3) -> Vector3 {
        let t = self.v.cross(&p) * 2.0;
        t * self.w + self.v.cross(&t) + p
    }
}

/// A rigid frame: a rotation, then a translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Isometry3 {
    /// Its orientation.
    pub rotation: UnitQuaternion,
    /// Its origin.
    pub translation: Vector3,
}

impl Isometry3 {
    /// The frame itself.
    #[inline]
    pub const fn identity() -> Self {
        Self {
            rotation: UnitQuaternion::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// The frame with origin `translation` and orientation `rotation`.
    #[inline]
    pub const fn from_parts(translation: Vector3, rotation: UnitQuaternion) -> Self {
        Self {
            rotation,
            translation,
        }
    }

    /// The point `p`, given in this frame, in the outer one.
    #[inline]
    pub fn transform_point(&self, p: &Vector3) -> Vector3 {
        self.rotation * *p + self.translation
    }

    /// The point `p`, given in the outer frame, in this one.
    #[inline]
    pub fn inverse_transform_point(&self, p: &Vector3) -> Vector3 {
        self.rotation.inverse() * (*p - self.translation)
    }

    /// The outer frame seen from this one.
    #[inline]
    pub fn inverse(&self) -> Self {
        let rotation = self.rotation.inverse();
        Self {
            rotation,
            translation: rotation * -self.translation,
        }
    }
}

impl Mul for Isometry3 {
    type Output = Self;
    /// The frame `r`, given in `self`, in the outer frame.
    #[inline]
    fn mul(self, r: Self) -> Self {
        Self {
            rotation: self.rotation * r.rotation,
            translation: self.translation + self.rotation * r.translation,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Vector3, b: &Vector3) -> bool {
        (*a - *b).norm() < 1e-14
    }

    #[test]
    fn rotations_compose_and_invert() {
        let q = UnitQuaternion::from_axis_angle(&Vector3::z(), std::f64::consts::FRAC_PI_2);
        assert!(close(&(q * Vector3::x()), &Vector3::y()));
        assert!(close(
            &(q.inverse() * (q * Vector3::new(1.0, 2.0, 3.0))),
            &Vector3::new(1.0, 2.0, 3.0)
        ));
        let r = UnitQuaternion::from_euler_angles(0.3, -0.7, 1.1);
        let m = r.to_rotation_matrix();
        let back = UnitQuaternion::from_rotation_matrix(&m);
        assert!(r.angle_to(&back) < 1e-14);
        let p = Vector3::new(0.2, -0.5, 0.9);
        let mp = Vector3::new(
            m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z,
            m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z,
            m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z,
        );
        assert!(close(&(r * p), &mp));
        let f = Isometry3::from_parts(Vector3::new(1.0, -2.0, 0.5), r);
        let g = Isometry3::from_parts(Vector3::new(0.1, 0.0, 0.3), q);
        let fg = f * g;
        assert!(close(
            &fg.transform_point(&p),
            &f.transform_point(&g.transform_point(&p))
        ));
        assert!(close(
            &f.inverse().transform_point(&f.transform_point(&p)),
            &p
        ));
        assert!(close(
            &f.inverse_transform_point(&f.transform_point(&p)),
            &p
        ));
        let z = Vector3::new(0.3, -0.4, 0.5).normalize();
        let t = UnitQuaternion::rotation_between(&Vector3::z(), &z).unwrap();
        assert!(close(&(t * Vector3::z()), &z));
        assert!(UnitQuaternion::rotation_between(&Vector3::z(), &-Vector3::z()).is_none());
    }
}
