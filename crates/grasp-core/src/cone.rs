//! Inscribed polyhedral friction cones (paper section 2, eqs. 5–17).
//!
//! Every cone is built from its vertex rays, which lie on the exact cone, and each face
//! is computed from its vertices with cross products. The printed coefficient formulas
//! are not used: eq. 5 has `cos` where `sin` belongs, and eqs. 10/14 are garbled.
//!
//! Each face row is scaled so that its `fz` coefficient is 1: a row reads
//! `fz − (a·fx + b·fy + c·mz) ≥ 0`, so its value is a slack in units of normal force.

use crate::by_name::ByName;
use crate::contact::ContactModel;
use crate::matrix::Matrix;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Largest number of sides accepted.
pub const MAX_SIDES: usize = 4096;
/// Largest number of SFCe latitudes per hemisphere accepted.
pub const MAX_LATITUDES: usize = 256;

/// Where the SFCe latitudes sit on each meridian ellipse.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SfceSpacing {
    /// The paper's eq. 13: polar angles `ψi = πi/(2K)` uniform in the `(r, mz)` plane.
    /// That plane mixes a pure number with a length, so the vertices, and σ(N), change
    /// with the unit of length; when `mu_torsion ≪ mu` the latitudes crowd at the pole.
    Paper,
    /// Uniform in the normalised ellipse angle `αi = πi/(2K)`:
    /// `r = mu·cos αi`, `mz = mu_torsion·sin αi` (eq. 13 applied to `mz/mu_torsion`).
    /// Unit-free. The default.
    #[default]
    Uniform,
}

impl ByName for SfceSpacing {
    const VARIANTS: &'static [Self] = &[Self::Paper, Self::Uniform];
    const NAMES: &'static [&'static str] = &["paper", "uniform"];
}
crate::deserialize_by_name!(SfceSpacing);

/// How finely the friction cones are linearised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Linearization {
    /// N, the number of sides of the inscribed polygon (3..=4096). Default 8.
    pub sides: usize,
    /// K, the number of latitudes per hemisphere for SFCe contacts (1..=256). Default 2.
    pub latitudes: usize,
    /// Placement of the SFCe latitudes. Default: uniform (unit-free).
    pub sfce_spacing: SfceSpacing,
}

impl Default for Linearization {
    fn default() -> Self {
        Self {
            sides: 8,
            latitudes: 2,
            sfce_spacing: SfceSpacing::Uniform,
        }
    }
}

/// A linearisation setting out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinearizationError {
    /// `sides` outside `3..=MAX_SIDES`.
    #[error("linearization.sides must be an integer from 3 to {MAX_SIDES}, got {0}")]
    Sides(usize),
    /// `latitudes` outside `1..=MAX_LATITUDES`.
    #[error("linearization.latitudes must be an integer from 1 to {MAX_LATITUDES}, got {0}")]
    Latitudes(usize),
}

impl Linearization {
    /// Checks the ranges of N and K.
    pub fn validate(&self) -> Result<(), LinearizationError> {
        if !(3..=MAX_SIDES).contains(&self.sides) {
            return Err(LinearizationError::Sides(self.sides));
        }
        if !(1..=MAX_LATITUDES).contains(&self.latitudes) {
            return Err(LinearizationError::Latitudes(self.latitudes));
        }
        Ok(())
    }

    /// Number of inequality rows for one contact of this model:
    /// 1 (FPC), N+1 (PCwF), 2N+1 (SFCl) or 2NK+1 (SFCe), as in eqs. 7, 11 and 17.
    pub fn rows_for(&self, model: &ContactModel) -> usize {
        let (n, k) = (self.sides, self.latitudes);
        match model {
            ContactModel::Fpc => 1,
            ContactModel::Pcwf { .. } => n + 1,
            ContactModel::SfcLinear { .. } => 2 * n + 1,
            ContactModel::SfcElliptic { .. } => 2 * n * k + 1,
        }
    }
}

/// An inscribed polyhedral cone `S f ≥ 0` for one contact, with the vertex rays it was
/// built from.
#[derive(Clone, Debug)]
pub struct InscribedCone {
    /// Face rows, one per inequality, `rows × dim`; the last row is `fz ≥ 0`.
    pub faces: Matrix,
    /// Vertex rays with `fz = 1`, one per row in the contact's force layout, each on the
    /// exact cone.
    pub vertices: Matrix,
}

/// A polyhedral cone that contains the exact cone of `model`: the inscribed cone at
/// `lin` widened by its inradius ratio r (the largest cone of the same shape inside it
/// has friction coefficients `r·mu`, `r·mu_torsion`), so that its faces touch the exact
/// cone. A problem infeasible with these cones is infeasible with the exact ones.
pub fn circumscribed_cone(model: &ContactModel, lin: &Linearization) -> InscribedCone {
    let inner = inscribed_cone(model, lin);
    // Face rows read fz − (a·fx + b·fy + c·mz) ≥ 0; in coordinates normalised by the
    // friction coefficients a round (PCwF, SFCe) cone of ratio r is inside iff
    // r·‖(a·mu, b·mu, c·mu_torsion)‖ ≤ 1. For SFCl the tangential part decides (the
    // torsional part is linear already): widening both coefficients by 1/r contains it.
    let (mu, mt, torsion) = match *model {
        ContactModel::Fpc => return inner,
        ContactModel::Pcwf { mu } => (mu, 0.0, false),
        ContactModel::SfcLinear { mu, mu_torsion } => (mu, mu_torsion, false),
        ContactModel::SfcElliptic { mu, mu_torsion } => (mu, mu_torsion, true),
    };
    let rows = inner.faces.nrows();
    let mut r = f64::INFINITY;
    for k in 0..rows - 1 {
        let row = inner.faces.row(k);
        let t = if torsion { row[3] * mt } else { 0.0 };
        let size = ((row[0] * mu).powi(2) + (row[1] * mu).powi(2) + t * t).sqrt();
        r = r.min(1.0 / size);
    }
    let wide = match *model {
        ContactModel::Pcwf { .. } => ContactModel::Pcwf { mu: mu / r },
        ContactModel::SfcLinear { .. } => ContactModel::SfcLinear {
            mu: mu / r,
            mu_torsion: mt / r,
        },
        _ => ContactModel::SfcElliptic {
            mu: mu / r,
            mu_torsion: mt / r,
        },
    };
    inscribed_cone(&wide, lin)
}

/// Builds the inscribed cone of `model` (assumed validated) at linearisation `lin`.
///
/// Row order follows the paper's eq. 50 (see `shared/reference/README.md`, item 4):
/// PCwF faces j = 0…N−1; SFCl the `+mz` group then the `−mz` group; SFCe the upper
/// hemisphere (latitude outer, longitude inner) then the lower; `fz ≥ 0` last.
pub fn inscribed_cone(model: &ContactModel, lin: &Linearization) -> InscribedCone {
    let n = lin.sides;
    let theta = |j: usize| 2.0 * PI * (j % n) as f64 / n as f64;
    // The unit circle at the N angles: row j of a ring is mu times this.
    let circle = |j: usize| {
        let (s, c) = theta(j).sin_cos();
        [c, s]
    };
    match *model {
        ContactModel::Fpc => InscribedCone {
            faces: Matrix::from_rows_data(1, 1, vec![1.0]),
            vertices: Matrix::from_rows_data(1, 1, vec![1.0]),
        },
        ContactModel::Pcwf { mu } => {
            let (mut faces, mut vertices) =
                (Vec::with_capacity(3 * (n + 1)), Vec::with_capacity(3 * n));
            let ring: Vec<[f64; 2]> = (0..n).map(|j| circle(j).map(|x| mu * x)).collect();
            for (j, p) in ring.iter().enumerate() {
                faces.extend_from_slice(&edge_row(*p, ring[(j + 1) % n]));
                vertices.extend_from_slice(&[p[0], p[1], 1.0]);
            }
            faces.extend_from_slice(&[0.0, 0.0, 1.0]);
            InscribedCone {
                faces: Matrix::from_rows_data(n + 1, 3, faces),
                vertices: Matrix::from_rows_data(n, 3, vertices),
            }
        }
        ContactModel::SfcLinear { mu, mu_torsion } => {
            let ring: Vec<[f64; 3]> = (0..n)
                .map(|j| {
                    let [c, s] = circle(j);
                    [mu * c, mu * s, 0.0]
                })
                .collect();
            let mut faces = Vec::with_capacity(4 * (2 * n + 1));
            for pole in [mu_torsion, -mu_torsion] {
                for j in 0..n {
                    faces.extend_from_slice(&face_row(
                        ring[j],
                        ring[(j + 1) % n],
                        [0.0, 0.0, pole],
                    ));
                }
            }
            faces.extend_from_slice(&[0.0, 0.0, 1.0, 0.0]);
            let mut vertices = Vec::with_capacity(4 * (n + 2));
            for p in &ring {
                vertices.extend_from_slice(&[p[0], p[1], 1.0, 0.0]);
            }
            vertices.extend_from_slice(&[0.0, 0.0, 1.0, mu_torsion, 0.0, 0.0, 1.0, -mu_torsion]);
            InscribedCone {
                faces: Matrix::from_rows_data(2 * n + 1, 4, faces),
                vertices: Matrix::from_rows_data(n + 2, 4, vertices),
            }
        }
        ContactModel::SfcElliptic { mu, mu_torsion } => {
            sfce_cone(mu, mu_torsion, lin.sides, lin.latitudes, lin.sfce_spacing)
        }
    }
}

/// The SFCe ellipsoidal polyhedron (eqs. 13–17), built from its vertices.
fn sfce_cone(mu: f64, mu_t: f64, n: usize, k: usize, spacing: SfceSpacing) -> InscribedCone {
    // (radius, |mz|) of latitude i = 0..=k in the fz = 1 slice; i = k is the pole.
    let lat: Vec<(f64, f64)> = (0..=k)
        .map(|i| {
            if i == k {
                return (0.0, mu_t);
            }
            let angle = PI * i as f64 / (2 * k) as f64;
            match spacing {
                SfceSpacing::Paper => {
                    // eq. 13: l_i = mu·mu_t/√(mu²·tan²ψ + mu_t²), vertex (l cos θ, l sin θ, l tan ψ).
                    let t = angle.tan();
                    let l = mu * mu_t / (mu * mu * t * t + mu_t * mu_t).sqrt();
                    (l, l * t)
                }
                SfceSpacing::Uniform => (mu * angle.cos(), mu_t * angle.sin()),
            }
        })
        .collect();
    let circle: Vec<(f64, f64)> = (0..n)
        .map(|j| (2.0 * PI * j as f64 / n as f64).sin_cos())
        .collect();
    let point = |i: usize, j: usize, sign: f64| {
        let (r, z) = lat[i];
        let (s, c) = circle[j % n];
        [r * c, r * s, sign * z]
    };
    let mut faces = Vec::with_capacity(4 * (2 * n * k + 1));
    for sign in [1.0, -1.0] {
        for i in 0..k {
            for j in 0..n {
                // Quad (i,j),(i,j+1),(i+1,j+1),(i+1,j) is an isosceles trapezoid, hence
                // planar; at i+1 = k it degenerates to the pole triangle. Three of its
                // corners define the plane; pick ones that are distinct.
                let a = point(i, j, sign);
                let b = point(i, j + 1, sign);
                let c = if i + 1 == k {
                    point(k, 0, sign)
                } else {
                    point(i + 1, j, sign)
                };
                faces.extend_from_slice(&face_row(a, b, c));
            }
        }
    }
    faces.extend_from_slice(&[0.0, 0.0, 1.0, 0.0]);
    let nv = 2 * n * (k - 1) + n + 2;
    let mut vertices = Vec::with_capacity(4 * nv);
    for sign in [1.0, -1.0] {
        for i in 0..k {
            if i == 0 && sign < 0.0 {
                continue; // the equator is shared by both hemispheres
            }
            for j in 0..n {
                let p = point(i, j, sign);
                vertices.extend_from_slice(&[p[0], p[1], 1.0, p[2]]);
            }
        }
        vertices.extend_from_slice(&[0.0, 0.0, 1.0, sign * mu_t]);
    }
    InscribedCone {
        faces: Matrix::from_rows_data(2 * n * k + 1, 4, faces),
        vertices: Matrix::from_rows_data(nv, 4, vertices),
    }
}

/// PCwF face through two neighbouring polygon vertices `p`, `q` of the `fz = 1` slice:
/// the line `n·x = d` with the origin inside (`d > 0`) gives `fz − (n/d)·(fx, fy) ≥ 0`.
fn edge_row(p: [f64; 2], q: [f64; 2]) -> [f64; 3] {
    let nrm = [q[1] - p[1], p[0] - q[0]];
    let d = nrm[0] * p[0] + nrm[1] * p[1];
    [-nrm[0] / d, -nrm[1] / d, 1.0]
}

/// Soft-finger face through three vertices of the `fz = 1` slice, in `(fx, fy, mz)`:
/// the plane `n·x = d` (cross product) with the origin inside gives
/// `fz − (n/d)·(fx, fy, mz) ≥ 0`, laid out as `[fx fy fz mz]`.
fn face_row(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 4] {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let nrm = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let d = nrm[0] * a[0] + nrm[1] * a[1] + nrm[2] * a[2];
    [-nrm[0] / d, -nrm[1] / d, 1.0, -nrm[2] / d]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lin(sides: usize, latitudes: usize, sfce_spacing: SfceSpacing) -> Linearization {
        Linearization {
            sides,
            latitudes,
            sfce_spacing,
        }
    }

    const MODELS: [ContactModel; 4] = [
        ContactModel::Fpc,
        ContactModel::Pcwf { mu: 0.6 },
        ContactModel::SfcLinear {
            mu: 0.5,
            mu_torsion: 0.01,
        },
        ContactModel::SfcElliptic {
            mu: 0.7,
            mu_torsion: 0.02,
        },
    ];

    #[test]
    fn row_counts_match_the_paper() {
        for (n, k) in [(3, 1), (4, 2), (8, 3), (17, 5)] {
            for s in [SfceSpacing::Paper, SfceSpacing::Uniform] {
                let l = lin(n, k, s);
                for m in MODELS {
                    let cone = inscribed_cone(&m, &l);
                    assert_eq!(cone.faces.nrows(), l.rows_for(&m));
                    assert_eq!(cone.faces.ncols(), m.dim());
                }
            }
        }
    }

    #[test]
    fn circumscribed_cones_contain_the_exact_cone_and_touch_it() {
        let models = [
            ContactModel::Pcwf { mu: 0.7 },
            ContactModel::SfcLinear {
                mu: 0.5,
                mu_torsion: 0.004,
            },
            ContactModel::SfcElliptic {
                mu: 0.9,
                mu_torsion: 0.02,
            },
        ];
        for m in models {
            for (sides, latitudes) in [(3, 1), (8, 2), (13, 3)] {
                let lin = Linearization {
                    sides,
                    latitudes,
                    ..Default::default()
                };
                let cone = circumscribed_cone(&m, &lin);
                // Points on the exact cone's surface at fz = 1, over a fine grid.
                let mut tightest = f64::INFINITY;
                for i in 0..400 {
                    let th = 2.0 * PI * i as f64 / 400.0;
                    for j in 0..=20 {
                        let t = -1.0 + 2.0 * j as f64 / 20.0;
                        let f = match m {
                            ContactModel::Pcwf { mu } => vec![mu * th.cos(), mu * th.sin(), 1.0],
                            ContactModel::SfcLinear { mu, mu_torsion } => {
                                let r = mu * (1.0 - t.abs());
                                vec![r * th.cos(), r * th.sin(), 1.0, mu_torsion * t]
                            }
                            ContactModel::SfcElliptic { mu, mu_torsion } => {
                                let r = mu * (1.0 - t * t).sqrt();
                                vec![r * th.cos(), r * th.sin(), 1.0, mu_torsion * t]
                            }
                            ContactModel::Fpc => unreachable!(),
                        };
                        let least = (0..cone.faces.nrows())
                            .map(|k| crate::matrix::dot(cone.faces.row(k), &f))
                            .fold(f64::INFINITY, f64::min);
                        assert!(least >= -1e-12, "{m:?} N={sides}: {f:?} outside ({least})");
                        tightest = tightest.min(least);
                    }
                }
                assert!(
                    tightest < 2e-2,
                    "{m:?} N={sides}: far from the cone ({tightest})"
                );
                // Touching: the largest face normal, in coordinates normalised by the
                // friction coefficients, has length 1 (the inradius ratio is 1).
                let (mu, mt) = match m {
                    ContactModel::Pcwf { mu } => (mu, 0.0),
                    ContactModel::SfcLinear { mu, .. } => (mu, 0.0),
                    ContactModel::SfcElliptic { mu, mu_torsion } => (mu, mu_torsion),
                    ContactModel::Fpc => unreachable!(),
                };
                let widest = (0..cone.faces.nrows() - 1)
                    .map(|k| {
                        let r = cone.faces.row(k);
                        let t = if r.len() > 3 { r[3] * mt } else { 0.0 };
                        ((r[0] * mu).powi(2) + (r[1] * mu).powi(2) + t * t).sqrt()
                    })
                    .fold(0.0, f64::max);
                assert!((widest - 1.0).abs() < 1e-12, "{m:?} N={sides}: {widest}");
            }
        }
    }

    #[test]
    fn vertices_lie_on_the_exact_cone_and_on_the_polytope() {
        for (n, k) in [(3, 1), (4, 2), (8, 3), (16, 4)] {
            for s in [SfceSpacing::Paper, SfceSpacing::Uniform] {
                for m in MODELS.iter().skip(1) {
                    let cone = inscribed_cone(m, &lin(n, k, s));
                    for v in cone.vertices.as_slice().chunks_exact(m.dim()) {
                        assert!(m.exact_margin(v, 0.0).abs() < 1e-12, "{m:?} {v:?}");
                        let vals = cone.faces.mul_vec(v);
                        assert!(vals.iter().all(|&x| x > -1e-12), "{m:?} {vals:?}");
                        // A vertex of the polytope touches at least three faces (two for PCwF).
                        let touching = vals.iter().filter(|x| x.abs() < 1e-12).count();
                        assert!(touching >= m.dim() - 1, "{m:?} {v:?} {touching}");
                    }
                }
            }
        }
    }

    #[test]
    fn paper_s1_is_reproduced_up_to_row_scale() {
        // eq. 50, N = 4, mu = 0.5, mu_torsion = 0.2; our rows have fz coefficient 1,
        // the paper's 0.1.
        let s1 = [
            [-0.2, -0.2, 0.1, -0.5],
            [0.2, -0.2, 0.1, -0.5],
            [0.2, 0.2, 0.1, -0.5],
            [-0.2, 0.2, 0.1, -0.5],
            [-0.2, -0.2, 0.1, 0.5],
            [0.2, -0.2, 0.1, 0.5],
            [0.2, 0.2, 0.1, 0.5],
            [-0.2, 0.2, 0.1, 0.5],
            [0.0, 0.0, 1.0, 0.0],
        ];
        let m = ContactModel::SfcLinear {
            mu: 0.5,
            mu_torsion: 0.2,
        };
        let cone = inscribed_cone(&m, &lin(4, 2, SfceSpacing::Paper));
        for (i, printed) in s1.iter().enumerate() {
            let scale = printed[2];
            for (j, &p) in printed.iter().enumerate() {
                assert!(
                    (cone.faces[(i, j)] * scale - p).abs() < 1e-12,
                    "row {i}: {:?} vs {printed:?}",
                    cone.faces.row(i)
                );
            }
        }
    }

    #[test]
    fn pcwf_faces_match_the_closed_form() {
        // shared/reference README: fx cos φj + fy sin φj ≤ mu cos(π/N) fz, φj = (2j+1)π/N.
        let (mu, n) = (0.6, 7);
        let cone = inscribed_cone(&ContactModel::Pcwf { mu }, &lin(n, 1, SfceSpacing::Paper));
        for j in 0..n {
            let phi = (2 * j + 1) as f64 * PI / n as f64;
            let k = mu * (PI / n as f64).cos();
            let row = cone.faces.row(j);
            assert!((row[0] + phi.cos() / k).abs() < 1e-12);
            assert!((row[1] + phi.sin() / k).abs() < 1e-12);
        }
    }

    #[test]
    fn settings_are_validated() {
        assert!(lin(2, 1, SfceSpacing::Paper).validate().is_err());
        assert!(lin(MAX_SIDES + 1, 1, SfceSpacing::Paper)
            .validate()
            .is_err());
        assert!(lin(4, 0, SfceSpacing::Paper).validate().is_err());
        assert!(Linearization::default().validate().is_ok());
    }
}
