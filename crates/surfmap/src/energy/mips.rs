//! MIPS density (most isometric parameterization, Hormann & Greiner 2000).

use super::{Density, DensityDerivs};

/// MIPS: `W = a/√d = σ1/σ2 + σ2/σ1` (2 for any similarity).
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mips_is_scale_invariant() {
        for s in [0.1, 0.5, 3.0] {
            let (a, d) = (1.3f64, 0.4f64);
            assert!((Mips.eval(s * s * a, s.powi(4) * d).w - Mips.eval(a, d).w).abs() < 1e-12);
        }
    }
}
