//! What a [`Grid`](super::Grid) holds when it is sampled, filtered or transferred: `f64`
//! or `[f64; D]`, each a real vector space ([`Vector`]).
//!
//! Bilinear sampling, Gaussian filtering, restriction, prolongation, finite differences
//! and the harmonic extension are all linear in the values, so one generic implementation
//! serves scalar images (mean curvature `h`, distances) and vector images (the metric
//! `[g11, g12, g22]`, 3D positions) alike, acting component-wise. Every operation is a
//! fixed number of flops per component, inlined: no allocation, no loop over a runtime length.

/// A real vector space of fixed dimension with the plain component layout, as the grid
/// kernels need it. Implemented for `f64` and `[f64; D]`.
pub trait Vector: Copy + Send + Sync + std::fmt::Debug + 'static {
    /// Number of components.
    const DIM: usize;
    /// The zero vector (`+0.0` in every component).
    const ZERO: Self;
    /// `self + other`.
    fn add(self, other: Self) -> Self;
    /// `self − other`.
    fn sub(self, other: Self) -> Self;
    /// `s · self`.
    fn scale(self, s: f64) -> Self;
    /// `self + s · other` (rounded as a product, then a sum; no fused multiply-add).
    fn add_scaled(self, s: f64, other: Self) -> Self;
    /// The components, `DIM` of them.
    fn components(&self) -> &[f64];
    /// The components, mutable.
    fn components_mut(&mut self) -> &mut [f64];
}

impl Vector for f64 {
    const DIM: usize = 1;
    const ZERO: Self = 0.0;
    #[inline(always)]
    fn add(self, other: Self) -> Self {
        self + other
    }
    #[inline(always)]
    fn sub(self, other: Self) -> Self {
        self - other
    }
    #[inline(always)]
    fn scale(self, s: f64) -> Self {
        s * self
    }
    #[inline(always)]
    fn add_scaled(self, s: f64, other: Self) -> Self {
        self + s * other
    }
    #[inline(always)]
    fn components(&self) -> &[f64] {
        std::slice::from_ref(self)
    }
    #[inline(always)]
    fn components_mut(&mut self) -> &mut [f64] {
        std::slice::from_mut(self)
    }
}

impl<const D: usize> Vector for [f64; D] {
    const DIM: usize = D;
    const ZERO: Self = [0.0; D];
    #[inline(always)]
    fn add(self, other: Self) -> Self {
        std::array::from_fn(|c| self[c] + other[c])
    }
    #[inline(always)]
    fn sub(self, other: Self) -> Self {
        std::array::from_fn(|c| self[c] - other[c])
    }
    #[inline(always)]
    fn scale(self, s: f64) -> Self {
        self.map(|x| s * x)
    }
    #[inline(always)]
    fn add_scaled(self, s: f64, other: Self) -> Self {
        std::array::from_fn(|c| self[c] + s * other[c])
    }
    #[inline(always)]
    fn components(&self) -> &[f64] {
        self
    }
    #[inline(always)]
    fn components_mut(&mut self) -> &mut [f64] {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The array operations are the scalar ones, component by component, bit for bit.
    #[test]
    fn arrays_act_component_wise_like_scalars() {
        let a = [1.5, -0.25, 3.0];
        let b = [0.1, 7.0, -2.5];
        let s = 0.3;
        for c in 0..3 {
            assert_eq!(a.add(b)[c], a[c].add(b[c]));
            assert_eq!(a.sub(b)[c], a[c].sub(b[c]));
            assert_eq!(a.scale(s)[c], a[c].scale(s));
            assert_eq!(a.add_scaled(s, b)[c], a[c].add_scaled(s, b[c]));
        }
        let expected = [1.53, 1.85, 2.25];
        assert!((0..3).all(|c| (a.add_scaled(s, b)[c] - expected[c]).abs() < 1e-15));
        assert_eq!(<[f64; 3]>::ZERO.components(), &[0.0; 3]);
        assert_eq!(<f64 as Vector>::DIM + <[f64; 2] as Vector>::DIM, 3);
        let mut x = 2.0;
        x.components_mut()[0] = 5.0;
        assert_eq!(x, 5.0);
    }
}
