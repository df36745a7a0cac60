//! Contact models (paper section 2.1, eqs. 1–4) and their exact friction cones.

/// How a fingertip touches the object, with its friction coefficients.
///
/// The force layout in the contact frame (z along the inward normal) is
/// `[fz]` for [`ContactModel::Fpc`], `[fx fy fz]` for [`ContactModel::Pcwf`] and
/// `[fx fy fz mz]` for the soft-finger models.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ContactModel {
    /// Frictionless point contact, eq. 1: `fz ≥ 0`.
    Fpc,
    /// Point contact with friction, eq. 2: `‖(fx, fy)‖ ≤ mu·fz`.
    Pcwf {
        /// Tangential (Coulomb) friction coefficient, dimensionless.
        mu: f64,
    },
    /// Soft finger, linear coupling, eq. 3: `‖(fx, fy)‖/mu + |mz|/mu_torsion ≤ fz`.
    SfcLinear {
        /// Tangential friction coefficient, dimensionless.
        mu: f64,
        /// Torsional friction coefficient, a length (metres when forces are in newtons
        /// and moments in newton-metres).
        mu_torsion: f64,
    },
    /// Soft finger, elliptic coupling, eq. 4: `√(‖(fx, fy)‖²/mu² + mz²/mu_torsion²) ≤ fz`.
    SfcElliptic {
        /// Tangential friction coefficient, dimensionless.
        mu: f64,
        /// Torsional friction coefficient, a length.
        mu_torsion: f64,
    },
}

/// Smallest and largest tangential friction coefficient accepted. Beyond them the
/// cones are so narrow or so wide that the answer is set by rounding, not by friction.
pub const MU_RANGE: (f64, f64) = (1e-3, 1e3);
/// Smallest and largest torsional friction coefficient accepted (a length, in the
/// problem's unit).
pub const MU_TORSION_RANGE: (f64, f64) = (1e-9, 1e9);

/// A contact model with an unusable coefficient.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field} must be a number from {:e} to {:e}, got {value}", range.0, range.1)]
pub struct ContactError {
    /// `"mu"` or `"mu_torsion"`.
    pub field: &'static str,
    /// The rejected value.
    pub value: f64,
    /// The accepted range.
    pub range: (f64, f64),
}

impl ContactModel {
    /// Number of force components: 1, 3 or 4.
    pub fn dim(&self) -> usize {
        match self {
            Self::Fpc => 1,
            Self::Pcwf { .. } => 3,
            Self::SfcLinear { .. } | Self::SfcElliptic { .. } => 4,
        }
    }

    /// Index of `fz` within the contact's force components.
    pub fn normal_index(&self) -> usize {
        match self {
            Self::Fpc => 0,
            _ => 2,
        }
    }

    /// The name used in problem files: `fpc`, `pcwf`, `sfcl` or `sfce`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Fpc => "fpc",
            Self::Pcwf { .. } => "pcwf",
            Self::SfcLinear { .. } => "sfcl",
            Self::SfcElliptic { .. } => "sfce",
        }
    }

    /// Checks every coefficient against [`MU_RANGE`] and [`MU_TORSION_RANGE`].
    pub fn validate(&self) -> Result<(), ContactError> {
        let check = |field, value: f64, range: (f64, f64)| {
            if (range.0..=range.1).contains(&value) {
                Ok(())
            } else {
                Err(ContactError {
                    field,
                    value,
                    range,
                })
            }
        };
        match *self {
            Self::Fpc => Ok(()),
            Self::Pcwf { mu } => check("mu", mu, MU_RANGE),
            Self::SfcLinear { mu, mu_torsion } | Self::SfcElliptic { mu, mu_torsion } => {
                check("mu", mu, MU_RANGE)?;
                check("mu_torsion", mu_torsion, MU_TORSION_RANGE)
            }
        }
    }

    /// The cone's gauge `g(f)`: the exact cone is `g(f) ≤ fz` (eqs. 1–4).
    pub fn gauge(&self, f: &[f64]) -> f64 {
        match *self {
            Self::Fpc => 0.0,
            Self::Pcwf { mu } => (f[0] * f[0] + f[1] * f[1]).sqrt() / mu,
            Self::SfcLinear { mu, mu_torsion } => {
                (f[0] * f[0] + f[1] * f[1]).sqrt() / mu + f[3].abs() / mu_torsion
            }
            Self::SfcElliptic { mu, mu_torsion } => {
                let (r, t) = ((f[0] * f[0] + f[1] * f[1]) / (mu * mu), f[3] / mu_torsion);
                (r + t * t).sqrt()
            }
        }
    }

    /// Scale-free margin to the exact cone: `(fz − g)/max(|fz|, g)`.
    ///
    /// 1 is a pure normal push, 0 is on the cone surface, and a negative value is
    /// outside the cone (down to −1). Multiplying the force by a positive factor leaves
    /// it unchanged. A force with `max(|fz|, g) ≤ zero` counts as no force at all,
    /// which sits on the apex: margin 0 (pass `0.0` to disable; the core passes
    /// `1e-12 × the largest contact force component`, below which components are rounding).
    pub fn exact_margin(&self, f: &[f64], zero: f64) -> f64 {
        let fz = f[self.normal_index()];
        let g = self.gauge(f);
        let den = fz.abs().max(g);
        if den <= zero {
            0.0
        } else {
            (fz - g) / den
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn margins_are_scale_free_and_signed() {
        let c = ContactModel::Pcwf { mu: 0.5 };
        assert_eq!(c.exact_margin(&[0.0, 0.0, 2.0], 0.0), 1.0);
        assert!(c.exact_margin(&[0.5, 0.0, 1.0], 0.0).abs() < 1e-15);
        assert!(c.exact_margin(&[1.0, 0.0, 1.0], 0.0) < 0.0);
        let a = c.exact_margin(&[0.1, 0.2, 1.0], 0.0);
        let b = c.exact_margin(&[10.0, 20.0, 100.0], 0.0);
        assert!((a - b).abs() < 1e-15);
        assert_eq!(ContactModel::Fpc.exact_margin(&[-3.0], 0.0), -1.0);
        assert_eq!(c.exact_margin(&[1e-17, 0.0, -1e-18], 1e-12), 0.0);
    }

    #[test]
    fn validation_rejects_bad_coefficients() {
        assert!(ContactModel::Pcwf { mu: 0.0 }.validate().is_err());
        assert!(ContactModel::Pcwf { mu: 5e-324 }.validate().is_err());
        assert!(ContactModel::SfcLinear {
            mu: 0.5,
            mu_torsion: f64::NAN
        }
        .validate()
        .is_err());
        assert!(ContactModel::SfcElliptic {
            mu: 0.5,
            mu_torsion: 0.01
        }
        .validate()
        .is_ok());
    }
}
