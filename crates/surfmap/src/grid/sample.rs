//! Bilinear sampling of a grid at any point of the plane, with the gradient: the inner
//! loop of the matcher, which evaluates surface B's images at the deformed positions
//! `φ(ξ)` (thesis §3.2, App. B: every term's variation carries `∇(·)_B ∘ φ`).
//!
//! On the cell `[j, j + 1] × [i, i + 1]` (in node units) with local coordinates
//! `(s, t) ∈ [0, 1]²` and corner values `f₀₀ = f(i, j)`, `f₀₁ = f(i, j + 1)`,
//! `f₁₀ = f(i + 1, j)`, `f₁₁ = f(i + 1, j + 1)`:
//!
//! `f(s, t) = (1 − t)·[f₀₀ + s (f₀₁ − f₀₀)] + t·[f₁₀ + s (f₁₁ − f₁₀)]`,
//! `∂f/∂ξ₀ = (N − 1)·[(1 − t)(f₀₁ − f₀₀) + t (f₁₁ − f₁₀)]`,
//! `∂f/∂ξ₁ = (N − 1)·[f₁₀ + s (f₁₁ − f₁₀) − f₀₀ − s (f₀₁ − f₀₀)]`,
//!
//! the exact derivatives of the interpolant. On a cell edge (where the interpolant is
//! only continuous) the cell above / to the right is used, except on the last row and
//! column of nodes. Outside ω a point is first clamped onto ω (constant extension along
//! the normal); the gradient is that of the clamped function, so its component across a
//! clamped direction is zero. Vector grids (`[f64; D]`) are sampled component-wise.
//!
//! Cost: two bounds checks, a few flops per component, no allocation; both functions are
//! `#[inline]` so that a caller's loop specializes them. A NaN coordinate gives NaN values
//! (no panic); non-finite grid values make the result non-finite.

use super::grid::Grid;
use super::value::Vector;

/// Where a point falls on an `n × n` grid, after clamping onto ω: the index of its
/// cell's lower-left node, the local coordinates `(s, t)`, and `∂(local)/∂ξ` per axis
/// (`N − 1`, or `0` where the point was clamped). Located once, it samples every grid of
/// that size at the point ([`Grid::sample_with_gradient_at`]): the matcher reads B's
/// images and all of B's feature distances at the same `φ(ξ)`.
#[derive(Clone, Copy, Debug)]
pub struct GridPoint {
    n: usize,
    k: usize,
    s: f64,
    t: f64,
    ds: f64,
    dt: f64,
}

impl GridPoint {
    /// Locates `p ∈ ℝ²` (domain coordinates) on an `n × n` grid (`n ≥ 2`).
    #[inline(always)]
    pub fn locate(n: usize, p: [f64; 2]) -> Self {
        let last = (n - 1) as f64;
        let (x, y) = (p[0] * last, p[1] * last);
        let (xc, yc) = (x.clamp(0.0, last), y.clamp(0.0, last));
        // `as usize` saturates (NaN → 0), so the index stays in range for any input.
        let j = (xc as usize).min(n - 2);
        let i = (yc as usize).min(n - 2);
        Self {
            n,
            k: i * n + j,
            s: xc - j as f64,
            t: yc - i as f64,
            ds: if x == xc { last } else { 0.0 },
            dt: if y == yc { last } else { 0.0 },
        }
    }

    /// Indices of the cell's corners `[(i, j), (i, j + 1), (i + 1, j), (i + 1, j + 1)]`.
    #[inline(always)]
    pub fn corners(&self) -> [usize; 4] {
        [self.k, self.k + 1, self.k + self.n, self.k + self.n + 1]
    }

    /// The bilinear interpolant of the corner values `[f(i, j), f(i, j + 1), f(i + 1, j),
    /// f(i + 1, j + 1)]` at this point and its partial derivatives (see the module docs).
    #[inline(always)]
    pub fn interpolate_with_gradient<T: Vector>(&self, corners: [T; 4]) -> (T, T, T) {
        let [f00, f01, f10, f11] = corners;
        let (e0, e1) = (f01.sub(f00), f11.sub(f10));
        let lo = f00.add_scaled(self.s, e0);
        let hi = f10.add_scaled(self.s, e1);
        let across = hi.sub(lo);
        let value = lo.add_scaled(self.t, across);
        let along = e0.add_scaled(self.t, e1.sub(e0));
        (value, along.scale(self.ds), across.scale(self.dt))
    }
}

impl<T: Vector> Grid<T> {
    /// The bilinear interpolant at `p ∈ ℝ²` (domain coordinates), `p` clamped onto ω.
    #[inline(always)]
    pub fn sample(&self, p: [f64; 2]) -> T {
        let c = GridPoint::locate(self.size(), p);
        let [f00, f01, f10, f11] = self.cell_corners(c.k);
        let lo = f00.add_scaled(c.s, f01.sub(f00));
        let hi = f10.add_scaled(c.s, f11.sub(f10));
        lo.add_scaled(c.t, hi.sub(lo))
    }

    /// The bilinear interpolant at `p ∈ ℝ²` and its partial derivatives
    /// `(f, ∂f/∂ξ₀, ∂f/∂ξ₁)`; outside ω, those of the clamped function (see the module docs).
    #[inline(always)]
    pub fn sample_with_gradient(&self, p: [f64; 2]) -> (T, T, T) {
        self.sample_with_gradient_at(&GridPoint::locate(self.size(), p))
    }

    /// [`Grid::sample_with_gradient`] at a point already located on a grid of this size.
    #[inline(always)]
    pub fn sample_with_gradient_at(&self, c: &GridPoint) -> (T, T, T) {
        debug_assert_eq!(c.n, self.size(), "located on a grid of another size");
        c.interpolate_with_gradient(self.cell_corners(c.k))
    }

    /// `[f(i, j), f(i, j + 1), f(i + 1, j), f(i + 1, j + 1)]` for the node at index `k`.
    #[inline(always)]
    fn cell_corners(&self, k: usize) -> [T; 4] {
        let n = self.size();
        let data = self.as_slice();
        let lo = &data[k..k + 2];
        let hi = &data[k + n..k + n + 2];
        [lo[0], lo[1], hi[0], hi[1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Rng;

    /// A bilinear function of ξ: reproduced exactly by the interpolant on any grid.
    fn bilinear(p: [f64; 2]) -> [f64; 3] {
        let (x, y) = (p[0], p[1]);
        [
            1.0 + 2.0 * x - 3.0 * y + 0.5 * x * y,
            -0.25 * x + 4.0 * x * y,
            7.0 - y,
        ]
    }

    fn bilinear_gradient(p: [f64; 2]) -> ([f64; 3], [f64; 3]) {
        let (x, y) = (p[0], p[1]);
        (
            [2.0 + 0.5 * y, -0.25 + 4.0 * y, 0.0],
            [-3.0 + 0.5 * x, 4.0 * x, -1.0],
        )
    }

    fn close<const D: usize>(a: [f64; D], b: [f64; D], tol: f64) -> bool {
        a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= tol)
    }

    #[test]
    fn bilinear_functions_and_their_gradients_are_exact() {
        let g = Grid::from_fn(17, |i, j| bilinear([j as f64 / 16.0, i as f64 / 16.0])).unwrap();
        let scalar = g.component(0);
        let mut rng = Rng(7);
        for _ in 0..1000 {
            let p = [rng.uniform(), rng.uniform()];
            let (v, d0, d1) = g.sample_with_gradient(p);
            let (e0, e1) = bilinear_gradient(p);
            assert!(close(v, bilinear(p), 1e-13), "{p:?}");
            assert!(close(d0, e0, 1e-11) && close(d1, e1, 1e-11), "{p:?}");
            assert_eq!(g.sample(p), v);
            // The scalar grid gives component 0, bit for bit.
            let (s, s0, s1) = scalar.sample_with_gradient(p);
            assert_eq!((s, s0, s1), (v[0], d0[0], d1[0]));
            assert_eq!(scalar.sample(p), s);
        }
        // Nodes (including the corners of ω) return the node values.
        for (i, j) in [(0, 0), (16, 16), (0, 16), (16, 0), (5, 9)] {
            assert!(close(g.sample(g.node(i, j)), g[(i, j)], 1e-14));
        }
    }

    #[test]
    fn gradient_matches_finite_differences_of_sample() {
        // A smooth non-bilinear function: the interpolant's derivative inside a cell is
        // tested against central differences of `sample` itself, away from cell edges.
        let n = 33;
        let f = |x: f64, y: f64| [(3.0 * x).sin() * (2.0 * y).cos(), x * x * y, (x - y).exp()];
        let g = Grid::from_fn(n, |i, j| f(j as f64 / 32.0, i as f64 / 32.0)).unwrap();
        let mut rng = Rng(11);
        let eps = 1e-7;
        let mut checked = 0;
        for _ in 0..2000 {
            let p = [rng.uniform(), rng.uniform()];
            let local = p.map(|c| (c * 32.0).fract());
            if local.iter().any(|&s| !(0.01..0.99).contains(&s)) {
                continue;
            }
            let (_, d0, d1) = g.sample_with_gradient(p);
            let fd = |e: [f64; 2]| {
                let (a, b) = (
                    g.sample([p[0] + e[0], p[1] + e[1]]),
                    g.sample([p[0] - e[0], p[1] - e[1]]),
                );
                std::array::from_fn::<f64, 3, _>(|c| (a[c] - b[c]) / (2.0 * eps))
            };
            assert!(close(d0, fd([eps, 0.0]), 1e-6), "{p:?}: {d0:?}");
            assert!(close(d1, fd([0.0, eps]), 1e-6), "{p:?}: {d1:?}");
            checked += 1;
        }
        assert!(checked > 1000);
    }

    #[test]
    fn outside_points_are_clamped_and_lose_the_normal_derivative() {
        let g = Grid::from_fn(9, |i, j| bilinear([j as f64 / 8.0, i as f64 / 8.0])).unwrap();
        // Left of ω: value of the border point, ∂/∂ξ₀ = 0, ∂/∂ξ₁ that of the border.
        let (v, d0, d1) = g.sample_with_gradient([-0.3, 0.4]);
        let (_, e1) = bilinear_gradient([0.0, 0.4]);
        assert!(close(v, bilinear([0.0, 0.4]), 1e-13));
        assert_eq!(d0, [0.0; 3]);
        assert!(close(d1, e1, 1e-12));
        // Beyond a corner: the corner value, zero gradient.
        let (v, d0, d1) = g.sample_with_gradient([1.5, -2.0]);
        assert!(close(v, bilinear([1.0, 0.0]), 1e-13));
        assert_eq!((d0, d1), ([0.0; 3], [0.0; 3]));
        // On the border itself the inside derivative is kept.
        let (_, d0, _) = g.sample_with_gradient([1.0, 0.5]);
        assert!(close(d0, bilinear_gradient([1.0, 0.5]).0, 1e-12));
        // Infinite and NaN coordinates: no panic.
        assert!(close(
            g.sample([f64::INFINITY, 0.0]),
            bilinear([1.0, 0.0]),
            1e-13
        ));
        assert!(g.sample([f64::NAN, 0.5])[0].is_nan());
    }

    #[test]
    fn the_coarsest_grid_is_one_cell() {
        let g = Grid::from_parts(2, vec![1.0, 2.0, 3.0, 5.0]);
        let (v, d0, d1) = g.sample_with_gradient([0.5, 0.5]);
        assert_eq!((v, d0, d1), (2.75, 1.5, 2.5));
    }
}
