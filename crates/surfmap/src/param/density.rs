//! Isotropic energy densities `W(a, d)` and their derivatives (thesis §2.1.5, eq. 2.5).
//!
//! Per triangle the map from the 3D triangle (in an orthonormal frame of its plane) to
//! its UV triangle is linear with Jacobian `J`; with singular values `σ1 ≥ σ2` of `J`
//!
//! ```text
//! a = tr(JᵀJ)  = σ1² + σ2²        (length)
//! d = det(JᵀJ) = σ1² σ2²          (area; NOT √ — see NOTES §1)
//! ```
//!
//! and the element energy is `area3D · W(a, d)`. Every density here is isotropic
//! (depends on `J` only through `a` and `d`), is defined for `det J > 0`, and returns
//! its value with first and second partial derivatives in `(a, d)`, which is all that
//! [`super::element`] needs to build gradients and PSD-projected Hessians.

use thiserror::Error;

/// Value and partial derivatives of a density `W(a, d)` at one point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DensityDerivs {
    /// `W`
    pub w: f64,
    /// `∂W/∂a`
    pub w_a: f64,
    /// `∂W/∂d`
    pub w_d: f64,
    /// `∂²W/∂a²`
    pub w_aa: f64,
    /// `∂²W/∂a∂d`
    pub w_ad: f64,
    /// `∂²W/∂d²`
    pub w_dd: f64,
}

/// An isotropic distortion density `W(a, d)` with `a = σ1² + σ2²`, `d = σ1²σ2²`.
///
/// Callers guarantee `a > 0`, `d > 0` (a non-degenerate, positively oriented
/// triangle); outside that set the values are meaningless.
pub trait Density: Sync {
    /// `W` and its first and second partial derivatives at `(a, d)`.
    fn eval(&self, a: f64, d: f64) -> DensityDerivs;

    /// Whether `W → ∞` as `d → 0` (the density itself keeps triangles from
    /// collapsing). For non-barrier densities (ARAP) the flip-free step cap of the
    /// line search is the only protection against flips.
    fn is_barrier(&self) -> bool {
        true
    }
}

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

/// Litke's density, thesis (2.5):
///
/// ```text
/// W(a, d) = αl·a + αa·(d + (αl/αa + 1)/d) + αc·(a²/d − 4)
/// ```
///
/// `αl·a` controls length, `αa·(d + k/d)` area expansion and compression (the `1/d`
/// term is a barrier against flips), `αc·(a²/d − 4) = αc·(σ1/σ2 − σ2/σ1)²` angle
/// (conformality). The factor `k = αl/αa + 1` makes the isometry stationary:
/// `∂W/∂σi = 0` at `σ1 = σ2 = 1`. Valid weights (2.6): `αl > 0, αa > 0, αc ≥ 0`;
/// they are normalized to sum 1 (thesis §3.1, "for better numerics").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Litke {
    alpha_length: f64,
    alpha_area: f64,
    alpha_angle: f64,
}

impl Litke {
    /// Checks (2.6) and normalizes `αl + αa + αc = 1`.
    pub fn new(alpha_length: f64, alpha_area: f64, alpha_angle: f64) -> Result<Self, AlphaError> {
        for (name, value) in [
            ("αl (length)", alpha_length),
            ("αa (area)", alpha_area),
            ("αc (angle)", alpha_angle),
        ] {
            if !value.is_finite() {
                return Err(AlphaError::NonFinite { name, value });
            }
        }
        if alpha_length <= 0.0 {
            return Err(AlphaError::LengthNotPositive(alpha_length));
        }
        if alpha_area <= 0.0 {
            return Err(AlphaError::AreaNotPositive(alpha_area));
        }
        if alpha_angle < 0.0 {
            return Err(AlphaError::AngleNegative(alpha_angle));
        }
        let sum = alpha_length + alpha_area + alpha_angle;
        if !sum.is_finite() {
            return Err(AlphaError::NonFinite {
                name: "αl + αa + αc",
                value: sum,
            });
        }
        Ok(Self {
            alpha_length: alpha_length / sum,
            alpha_area: alpha_area / sum,
            alpha_angle: alpha_angle / sum,
        })
    }

    /// Nearly conformal, α = (0.5 %, 0.5 %, 99 %): the thesis's Table 4.1 setting.
    pub fn conformal() -> Self {
        Self::new(0.005, 0.005, 0.99).expect("valid preset")
    }

    /// Equal weights α = (1/3, 1/3, 1/3) (thesis §3.2.1 and Table 4.2).
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
        [self.alpha_length, self.alpha_area, self.alpha_angle]
    }

    /// The continuation blend `α = (1 − θ)·α0 + θ·α1` of thesis §3.1.3 (`θ` clamped to
    /// `[0, 1]`); a convex combination of valid weights is valid.
    pub fn blend(&self, target: &Litke, theta: f64) -> Litke {
        let t = if theta.is_nan() {
            0.0
        } else {
            theta.clamp(0.0, 1.0)
        };
        let mix = |x: f64, y: f64| (1.0 - t) * x + t * y;
        Litke {
            alpha_length: mix(self.alpha_length, target.alpha_length),
            alpha_area: mix(self.alpha_area, target.alpha_area),
            alpha_angle: mix(self.alpha_angle, target.alpha_angle),
        }
    }
}

impl Density for Litke {
    /// With `k = αl/αa + 1`:
    /// `W_a = αl + 2αc·a/d`, `W_d = αa(1 − k/d²) − αc·a²/d²`,
    /// `W_aa = 2αc/d`, `W_ad = −2αc·a/d²`, `W_dd = 2αa·k/d³ + 2αc·a²/d³`.
    #[inline]
    fn eval(&self, a: f64, d: f64) -> DensityDerivs {
        let (l, ar, c) = (self.alpha_length, self.alpha_area, self.alpha_angle);
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

/// Symmetric Dirichlet: `W = a + a/d = σ1² + σ2² + σ1⁻² + σ2⁻²` (4 at an isometry,
/// its minimum).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SymmetricDirichlet;

impl Density for SymmetricDirichlet {
    /// `W_a = 1 + 1/d`, `W_d = −a/d²`, `W_aa = 0`, `W_ad = −1/d²`, `W_dd = 2a/d³`.
    #[inline]
    fn eval(&self, a: f64, d: f64) -> DensityDerivs {
        let inv_d = 1.0 / d;
        let inv_d2 = inv_d * inv_d;
        DensityDerivs {
            w: a + a * inv_d,
            w_a: 1.0 + inv_d,
            w_d: -a * inv_d2,
            w_aa: 0.0,
            w_ad: -inv_d2,
            w_dd: 2.0 * a * inv_d2 * inv_d,
        }
    }
}

/// MIPS (most isometric parameterization): `W = a/√d = σ1/σ2 + σ2/σ1` (2 for any
/// similarity).
///
/// Scale-invariant: `W(s²a, s⁴d) = W(a, d)`, so a minimizer is only defined up to a
/// global scale (and the Hessian has a null direction along it); fix the scale
/// afterwards (e.g. match the 3D area).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Mips;

impl Density for Mips {
    /// `W_a = d^{-1/2}`, `W_d = −a/2·d^{-3/2}`, `W_aa = 0`, `W_ad = −1/2·d^{-3/2}`,
    /// `W_dd = 3a/4·d^{-5/2}`.
    #[inline]
    fn eval(&self, a: f64, d: f64) -> DensityDerivs {
        let r = 1.0 / d.sqrt(); // d^{-1/2}
        let r3 = r / d; // d^{-3/2}
        DensityDerivs {
            w: a * r,
            w_a: r,
            w_d: -0.5 * a * r3,
            w_aa: 0.0,
            w_ad: -0.5 * r3,
            w_dd: 0.75 * a * r3 / d,
        }
    }
}

/// As-rigid-as-possible: `W = (σ1 − 1)² + (σ2 − 1)² = a − 2√(a + 2√d) + 2`
/// (using `σ1 + σ2 = √(a + 2√d)`, valid for `det J > 0` only).
///
/// Not a barrier: it stays finite as a triangle collapses, so flips are kept out by
/// the flip-free step cap alone.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Arap;

impl Density for Arap {
    /// With `s = √d = σ1σ2` and `r = √(a + 2s) = σ1 + σ2`:
    /// `W_a = 1 − 1/r`, `W_d = −1/(r s)`, `W_aa = 1/(2r³)`, `W_ad = 1/(2r³s)`,
    /// `W_dd = 1/(2r³s²) + 1/(2rs³)`.
    #[inline]
    fn eval(&self, a: f64, d: f64) -> DensityDerivs {
        let s = d.sqrt();
        let r = (a + 2.0 * s).sqrt();
        let inv_r = 1.0 / r;
        let inv_r3 = inv_r * inv_r * inv_r;
        let inv_s = 1.0 / s;
        DensityDerivs {
            w: a - 2.0 * r + 2.0,
            w_a: 1.0 - inv_r,
            w_d: -inv_r * inv_s,
            w_aa: 0.5 * inv_r3,
            w_ad: 0.5 * inv_r3 * inv_s,
            w_dd: 0.5 * inv_r3 * inv_s * inv_s + 0.5 * inv_r * inv_s * inv_s * inv_s,
        }
    }

    fn is_barrier(&self) -> bool {
        false
    }
}

/// A density chosen at run time (CLI `--energy`), dispatching to the concrete ones.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EnergyKind {
    Litke(Litke),
    SymmetricDirichlet,
    Mips,
    Arap,
}

impl Density for EnergyKind {
    #[inline]
    fn eval(&self, a: f64, d: f64) -> DensityDerivs {
        match self {
            EnergyKind::Litke(l) => l.eval(a, d),
            EnergyKind::SymmetricDirichlet => SymmetricDirichlet.eval(a, d),
            EnergyKind::Mips => Mips.eval(a, d),
            EnergyKind::Arap => Arap.eval(a, d),
        }
    }

    fn is_barrier(&self) -> bool {
        !matches!(self, EnergyKind::Arap)
    }
}

impl Default for EnergyKind {
    fn default() -> Self {
        EnergyKind::Litke(Litke::conformal())
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // matrix indices read best as indices
mod tests {
    use super::*;

    use crate::testing::Rng;

    use crate::testing::all_energies as all_densities;

    fn assert_close(got: f64, want: f64, rel: f64, what: &str) {
        let tol = rel * (1.0 + want.abs().max(got.abs()));
        assert!(
            (got - want).abs() <= tol,
            "{what}: got {got}, want {want} (tol {tol})"
        );
    }

    /// First and second derivatives in (a, d) against central differences of `w`
    /// and of the first derivatives, at random singular values.
    #[test]
    fn derivatives_match_finite_differences() {
        let mut rng = Rng(0x9e3779b97f4a7c15);
        for (name, density) in all_densities() {
            for _ in 0..200 {
                let s1 = rng.range(0.2, 3.0);
                let s2 = s1 * rng.range(0.05, 1.0);
                let (a, d) = (s1 * s1 + s2 * s2, s1 * s1 * s2 * s2);
                let f = density.eval(a, d);
                let ha = 1e-6 * a;
                let hd = 1e-6 * d;
                let (pa, ma) = (density.eval(a + ha, d), density.eval(a - ha, d));
                let (pd, md) = (density.eval(a, d + hd), density.eval(a, d - hd));
                let tag = format!("{name} at σ = ({s1}, {s2})");
                assert_close(
                    f.w_a,
                    (pa.w - ma.w) / (2.0 * ha),
                    1e-6,
                    &format!("W_a {tag}"),
                );
                assert_close(
                    f.w_d,
                    (pd.w - md.w) / (2.0 * hd),
                    1e-6,
                    &format!("W_d {tag}"),
                );
                let scale_a = f.w_aa.abs() + (f.w_a.abs() / a);
                let scale_d = f.w_dd.abs() + (f.w_d.abs() / d);
                let fd_aa = (pa.w_a - ma.w_a) / (2.0 * ha);
                let fd_dd = (pd.w_d - md.w_d) / (2.0 * hd);
                let fd_ad = (pd.w_a - md.w_a) / (2.0 * hd);
                let fd_da = (pa.w_d - ma.w_d) / (2.0 * ha);
                assert!(
                    (f.w_aa - fd_aa).abs() <= 1e-6 * (1.0 + scale_a),
                    "W_aa {tag}"
                );
                assert!(
                    (f.w_dd - fd_dd).abs() <= 1e-6 * (1.0 + scale_d),
                    "W_dd {tag}"
                );
                let scale_ad = f.w_ad.abs() + f.w_a.abs() / d + f.w_d.abs() / a;
                assert!(
                    (f.w_ad - fd_ad).abs() <= 1e-6 * (1.0 + scale_ad),
                    "W_ad {tag}"
                );
                assert!(
                    (f.w_ad - fd_da).abs() <= 1e-6 * (1.0 + scale_ad),
                    "W_da {tag}"
                );
            }
        }
    }

    /// Each density against its definition in singular values.
    #[test]
    fn values_match_singular_value_definitions() {
        let mut rng = Rng(42);
        for _ in 0..100 {
            let (s1, s2) = (rng.range(0.1, 4.0), rng.range(0.1, 4.0));
            let (a, d) = (s1 * s1 + s2 * s2, s1 * s1 * s2 * s2);
            let sd = s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2);
            assert_close(SymmetricDirichlet.eval(a, d).w, sd, 1e-12, "SD");
            assert_close(Mips.eval(a, d).w, s1 / s2 + s2 / s1, 1e-12, "MIPS");
            let arap = (s1 - 1.0).powi(2) + (s2 - 1.0).powi(2);
            assert!((Arap.eval(a, d).w - arap).abs() < 1e-12 * (1.0 + a), "ARAP");
            let [l, ar, c] = Litke::balanced().alphas();
            let litke = l * a
                + ar * (s1 * s1 * s2 * s2 + (l / ar + 1.0) / (s1 * s1 * s2 * s2))
                + c * (s1 / s2 - s2 / s1).powi(2);
            assert_close(Litke::balanced().eval(a, d).w, litke, 1e-12, "Litke");
        }
    }

    /// `∂W/∂σi = 2σi·(W_a + σj²·W_d)` vanishes at σ1 = σ2 = 1 for any valid α
    /// (the role of the factor αl/αa + 1), and W is then a local minimum along σ.
    #[test]
    fn litke_isometry_is_stationary_for_random_alphas() {
        let mut rng = Rng(7);
        for _ in 0..200 {
            let l = rng.range(1e-3, 1.0);
            let ar = rng.range(1e-3, 1.0);
            let c = if rng.uniform() < 0.2 {
                0.0
            } else {
                rng.range(0.0, 1.0)
            };
            let w = Litke::new(l, ar, c).unwrap();
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

    #[test]
    fn isometry_values() {
        assert_eq!(SymmetricDirichlet.eval(2.0, 1.0).w, 4.0);
        assert_eq!(Mips.eval(2.0, 1.0).w, 2.0);
        assert_eq!(Arap.eval(2.0, 1.0).w, 0.0);
        // Litke at the isometry: αl·2 + αa·(1 + αl/αa + 1) + 0 = 3αl + 2αa.
        let w = Litke::balanced();
        let [l, a, _] = w.alphas();
        assert!((w.eval(2.0, 1.0).w - (3.0 * l + 2.0 * a)).abs() < 1e-15);
    }

    #[test]
    fn mips_is_scale_invariant() {
        for s in [0.1, 0.5, 3.0] {
            let (a, d) = (1.3f64, 0.4f64);
            assert!((Mips.eval(s * s * a, s.powi(4) * d).w - Mips.eval(a, d).w).abs() < 1e-12);
        }
    }

    #[test]
    fn invalid_alphas_are_rejected_with_the_reason() {
        assert!(matches!(
            Litke::new(0.0, 1.0, 1.0),
            Err(AlphaError::LengthNotPositive(_))
        ));
        assert!(matches!(
            Litke::new(1.0, -1.0, 1.0),
            Err(AlphaError::AreaNotPositive(_))
        ));
        assert!(matches!(
            Litke::new(1.0, 1.0, -0.1),
            Err(AlphaError::AngleNegative(_))
        ));
        assert!(matches!(
            Litke::new(f64::NAN, 1.0, 1.0),
            Err(AlphaError::NonFinite { .. })
        ));
        assert!(matches!(
            Litke::new(f64::MAX, f64::MAX, 1.0),
            Err(AlphaError::NonFinite { .. })
        ));
        let msg = Litke::new(1.0, 0.0, 1.0).unwrap_err().to_string();
        assert!(msg.contains("area") && msg.contains("> 0"), "{msg}");
        assert!(Litke::new(1.0, 1.0, 0.0).is_ok());
    }

    #[test]
    fn blend_interpolates_normalized_weights() {
        let (a, b) = (Litke::conformal(), Litke::balanced());
        assert_eq!(a.blend(&b, 0.0), a);
        assert_eq!(a.blend(&b, 1.0).alphas(), b.alphas());
        let m = a.blend(&b, 0.5).alphas();
        for k in 0..3 {
            assert!((m[k] - 0.5 * (a.alphas()[k] + b.alphas()[k])).abs() < 1e-15);
        }
        assert_eq!(a.blend(&b, 7.0).alphas(), b.alphas());
    }
}
