//! Litke's density, thesis (2.5), and its weights α (conditions (2.6)).
//!
//! ```text
//! W(a, d) = αl·a + αa·(d + (αl/αa + 1)/d) + αc·(a²/d − 4)
//! ```
//!
//! The same density with `αc = 0` is the regularization density (2.8) of matching: its
//! weights are an [`Alpha`] with a zero angle weight.

use super::{Density, DensityDerivs};
use thiserror::Error;

/// Invalid `α = (αl, αa, αc)` for the Litke density (2.5); the conditions are (2.6).
#[derive(Clone, Debug, Error, PartialEq)]
pub enum AlphaError {
    #[error(
        "energy weight {name} = {value} is not a finite number; give three finite weights (length, area, angle)"
    )]
    NonFinite { name: &'static str, value: f64 },
    #[error(
        "length weight αl = {0} must be > 0: without it a minimizer need not exist (shears cost nothing) and the isometry is not a minimum (thesis 2.6)"
    )]
    LengthNotPositive(f64),
    #[error(
        "area weight αa = {0} must be > 0: the term αa·(αl/αa + 1)/d is the barrier that keeps triangles from flipping, and it keeps the isometry stationary (thesis 2.6)"
    )]
    AreaNotPositive(f64),
    #[error("angle weight αc = {0} must be ≥ 0 (thesis 2.6); use 0 to switch the angle term off")]
    AngleNegative(f64),
}

/// The weights `α = (αl, αa, αc)` of Litke's density, thesis (2.5); as a [`Density`]
/// it is that density:
///
/// ```text
/// W(a, d) = αl·a + αa·(d + (αl/αa + 1)/d) + αc·(a²/d − 4)
/// ```
///
/// `αl·a` controls length, `αa·(d + k/d)` area expansion and compression (the `1/d`
/// term is a barrier against flips), `αc·(a²/d − 4) = αc·(σ1/σ2 − σ2/σ1)²` angle
/// (conformality). The factor `k = αl/αa + 1` makes the isometry stationary:
/// `∂W/∂σi = 0` at `σ1 = σ2 = 1`. Valid weights (2.6): `αl > 0, αa > 0, αc ≥ 0`
/// (`αc = 0` is matching's regularization (2.8)); they are normalized to sum 1 (thesis
/// §3.1, "for better numerics").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alpha {
    length: f64,
    area: f64,
    angle: f64,
}

impl Alpha {
    /// Checks (2.6) and normalizes `αl + αa + αc = 1`.
    pub fn new(length: f64, area: f64, angle: f64) -> Result<Self, AlphaError> {
        for (name, value) in [
            ("αl (length)", length),
            ("αa (area)", area),
            ("αc (angle)", angle),
        ] {
            if !value.is_finite() {
                return Err(AlphaError::NonFinite { name, value });
            }
        }
        if length <= 0.0 {
            return Err(AlphaError::LengthNotPositive(length));
        }
        if area <= 0.0 {
            return Err(AlphaError::AreaNotPositive(area));
        }
        if angle < 0.0 {
            return Err(AlphaError::AngleNegative(angle));
        }
        let sum = length + area + angle;
        if !sum.is_finite() {
            return Err(AlphaError::NonFinite {
                name: "αl + αa + αc",
                value: sum,
            });
        }
        Ok(Self {
            length: length / sum,
            area: area / sum,
            angle: angle / sum,
        })
    }

    /// Nearly conformal, α = (0.5 %, 0.5 %, 99 %): the thesis's Table 4.1 setting.
    pub fn conformal() -> Self {
        Self::new(0.005, 0.005, 0.99).expect("valid preset")
    }

    /// Equal weights α = (1/3, 1/3, 1/3) (thesis §3.2.1 and Table 4.2); the default
    /// everywhere in surfmap.
    pub fn balanced() -> Self {
        Self::new(1.0, 1.0, 1.0).expect("valid preset")
    }

    /// Area-biased, α = (0.1, 0.8, 0.1): our choice (not from the thesis), area
    /// distortion traded against moderate length and angle distortion.
    pub fn area() -> Self {
        Self::new(0.1, 0.8, 0.1).expect("valid preset")
    }

    /// Length-biased, α = (0.8, 0.1, 0.1): our choice (not from the thesis), close to
    /// the (90, 5, 5) start of the thesis's mannequin continuation (Table 4.2).
    pub fn length() -> Self {
        Self::new(0.8, 0.1, 0.1).expect("valid preset")
    }

    /// Normalized `[αl, αa, αc]`.
    pub fn alphas(&self) -> [f64; 3] {
        [self.length, self.area, self.angle]
    }

    /// The continuation blend `α = (1 − θ)·α0 + θ·α1` of thesis §3.1.3 (`θ` clamped to
    /// `[0, 1]`); a convex combination of valid weights is valid.
    pub fn blend(&self, target: &Alpha, theta: f64) -> Alpha {
        let t = if theta.is_nan() {
            0.0
        } else {
            theta.clamp(0.0, 1.0)
        };
        let mix = |x: f64, y: f64| (1.0 - t) * x + t * y;
        Alpha {
            length: mix(self.length, target.length),
            area: mix(self.area, target.area),
            angle: mix(self.angle, target.angle),
        }
    }
}

impl Default for Alpha {
    /// [`Alpha::balanced`].
    fn default() -> Self {
        Self::balanced()
    }
}

impl Density for Alpha {
    /// With `k = αl/αa + 1`:
    /// `W_a = αl + 2αc·a/d`, `W_d = αa(1 − k/d²) − αc·a²/d²`,
    /// `W_aa = 2αc/d`, `W_ad = −2αc·a/d²`, `W_dd = 2αa·k/d³ + 2αc·a²/d³`.
    #[inline]
    fn eval(&self, a: f64, d: f64) -> DensityDerivs {
        let (l, ar, c) = (self.length, self.area, self.angle);
        let k = l / ar + 1.0;
        let inv_d = 1.0 / d;
        let inv_d2 = inv_d * inv_d;
        let inv_d3 = inv_d2 * inv_d;
        DensityDerivs {
            w: l * a + ar * (d + k * inv_d) + c * (a * a * inv_d - 4.0),
            w_a: l + 2.0 * c * a * inv_d,
            w_d: ar * (1.0 - k * inv_d2) - c * a * a * inv_d2,
            w_aa: 2.0 * c * inv_d,
            w_ad: -2.0 * c * a * inv_d2,
            w_dd: 2.0 * ar * k * inv_d3 + 2.0 * c * a * a * inv_d3,
        }
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // weight indices read best as indices
mod tests {
    use super::*;
    use crate::testing::Rng;

    /// `∂W/∂σi = 2σi·(W_a + σj²·W_d)` vanishes at σ1 = σ2 = 1 for any valid α
    /// (the role of the factor αl/αa + 1), and W is then a local minimum along σ.
    #[test]
    fn isometry_is_stationary_for_random_alphas() {
        let mut rng = Rng(7);
        for _ in 0..200 {
            let l = rng.range(1e-3, 1.0);
            let ar = rng.range(1e-3, 1.0);
            let c = if rng.uniform() < 0.2 {
                0.0
            } else {
                rng.range(0.0, 1.0)
            };
            let w = Alpha::new(l, ar, c).unwrap();
            let [nl, na, nc] = w.alphas();
            assert!((nl + na + nc - 1.0).abs() < 1e-15);
            let f = w.eval(2.0, 1.0);
            let dw_dsigma = 2.0 * (f.w_a + f.w_d);
            assert!(
                dw_dsigma.abs() < 1e-14,
                "∂W/∂σ = {dw_dsigma} for α = {:?}",
                w.alphas()
            );
            // Independent check by moving σ1 alone: W(σ1 = 1 ± h, σ2 = 1).
            let h = 1e-4;
            let at = |s1: f64| w.eval(s1 * s1 + 1.0, s1 * s1).w;
            let slope = (at(1.0 + h) - at(1.0 - h)) / (2.0 * h);
            assert!(slope.abs() < 1e-7, "slope {slope}");
            assert!(at(1.0 + h) > at(1.0) && at(1.0 - h) > at(1.0));
        }
    }

    /// Matching's regularization (2.8) is (2.5) without the angle term: with αc = 0 the
    /// value is `αl·a + αa·(d + (αl/αa + 1)/d)` at any `(a, d)`, also at invariants of
    /// a general symmetric tensor rather than of a triangle's Jacobian.
    #[test]
    fn zero_angle_weight_is_the_matching_regularization() {
        let alpha = Alpha::new(2.0, 1.0, 0.0).unwrap();
        let [l, ar, c] = alpha.alphas();
        assert_eq!(c, 0.0);
        assert!((l - 2.0 / 3.0).abs() < 1e-15 && (ar - 1.0 / 3.0).abs() < 1e-15);
        let mut rng = Rng(11);
        for _ in 0..100 {
            // G = [[p, q], [q, r]] positive definite.
            let (p, r) = (rng.range(0.1, 3.0), rng.range(0.1, 3.0));
            let q = rng.range(-0.9, 0.9) * (p * r).sqrt();
            let (a, d) = super::super::invariants([[p, q], [q, r]]);
            let want = l * a + ar * (d + (l / ar + 1.0) / d);
            let (w, [w_a, w_d]) = alpha.value_and_gradient(a, d);
            assert!((w - want).abs() <= 1e-13 * want, "{w} vs {want}");
            assert!((w_a - l).abs() < 1e-15);
            assert!(
                (w_d - ar * (1.0 - (l / ar + 1.0) / (d * d))).abs() <= 1e-12 * (1.0 + w_d.abs())
            );
        }
    }

    #[test]
    fn invalid_alphas_are_rejected_with_the_reason() {
        assert!(matches!(
            Alpha::new(0.0, 1.0, 1.0),
            Err(AlphaError::LengthNotPositive(_))
        ));
        assert!(matches!(
            Alpha::new(1.0, -1.0, 1.0),
            Err(AlphaError::AreaNotPositive(_))
        ));
        assert!(matches!(
            Alpha::new(1.0, 1.0, -0.1),
            Err(AlphaError::AngleNegative(_))
        ));
        assert!(matches!(
            Alpha::new(f64::NAN, 1.0, 1.0),
            Err(AlphaError::NonFinite { .. })
        ));
        assert!(matches!(
            Alpha::new(f64::MAX, f64::MAX, 1.0),
            Err(AlphaError::NonFinite { .. })
        ));
        let msg = Alpha::new(1.0, 0.0, 1.0).unwrap_err().to_string();
        assert!(msg.contains("area") && msg.contains("> 0"), "{msg}");
        assert!(Alpha::new(1.0, 1.0, 0.0).is_ok());
    }

    #[test]
    fn blend_interpolates_normalized_weights() {
        let (a, b) = (Alpha::conformal(), Alpha::balanced());
        assert_eq!(a.blend(&b, 0.0), a);
        assert_eq!(a.blend(&b, 1.0).alphas(), b.alphas());
        let m = a.blend(&b, 0.5).alphas();
        for k in 0..3 {
            assert!((m[k] - 0.5 * (a.alphas()[k] + b.alphas()[k])).abs() < 1e-15);
        }
        assert_eq!(a.blend(&b, 7.0).alphas(), b.alphas());
    }
}
