//! As-rigid-as-possible density (Liu et al. 2008).

use super::{Density, DensityDerivs};

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
