//! Symmetric Dirichlet density (as libigl's SLIM minimizes it).

use super::{Density, DensityDerivs};

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
