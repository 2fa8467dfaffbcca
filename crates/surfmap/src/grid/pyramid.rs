//! The scale pyramid of the multiscale matcher (thesis §3.2.4, Fig. 3.7, 3.8).
//!
//! Level `k = 0..=K` lives on the `(2^k + 1)²` grid (`N = 2^K + 1` is the finest) and holds
//! the images filtered with a Gaussian of width `σ_k = 2^−k` (domain units) for `k < K`;
//! the finest level is unfiltered (`σ_K = 0`, as the thesis's `σ_m = 0`).
//!
//! Gaussian filtering is the heat semigroup: `G_σ` solves the heat equation for time
//! `σ²/2`, with natural (zero-flux) boundary conditions on ∂ω, i.e. the image mirrored
//! about its border nodes. Semigroup property `G_a ∘ G_b = G_√(a²+b²)` lets each level be
//! made from the next finer one with a narrow kernel: level `K−1` filters level `K` with
//! `σ = 2^−(K−1)` (2 fine nodes), level `k < K−1` filters level `k+1` with
//! `√(σ_k² − σ_{k+1}²) = (√3/2) σ_k` (√3 nodes of level `k+1`), then restricts by injection
//! (every other node). Cost `O(N²)` for the whole pyramid.
//!
//! Filtering is linear and acts component-wise, so one [`Pyramid<T>`] serves scalar
//! images (`T = f64`: mean curvature, distances) and vector images (`T = [f64; D]`): the
//! [`MetricPyramid`] filters `[g11, g12, g22]` together. A Gaussian is a convex combination
//! (non-negative weights summing to 1), so filtered symmetric positive definite tensors
//! stay symmetric positive definite. Bilinear transfer between levels is in
//! [`multigrid`](super::multigrid).

use rayon::prelude::*;

use super::grid::Grid;
use super::value::Vector;

/// A grid filtered and restricted to every level, coarsest first: level `k` is a
/// `(2^k + 1)²` grid filtered with `σ_k = 2^−k`, the finest level unfiltered (`σ = 0`).
#[derive(Clone, Debug, PartialEq)]
pub struct Pyramid<T> {
    levels: Vec<Grid<T>>,
    sigmas: Vec<f64>,
}

/// The pyramid of a metric image `[g11, g12, g22]` (2×2 symmetric tensors per node).
pub type MetricPyramid = Pyramid<[f64; 3]>;

impl<T: Vector> Pyramid<T> {
    /// Builds the pyramid of `finest` (`N = 2^K + 1`, all values finite): `K + 1` levels,
    /// down to the `2 × 2` grid of `σ_0 = 1`.
    pub fn new(finest: Grid<T>) -> Self {
        let top = finest.level();
        let mut levels = vec![finest];
        let mut sigmas = vec![0.0];
        for k in (0..top).rev() {
            let finer = levels.last().unwrap();
            let finer_sigma = *sigmas.last().unwrap();
            let sigma = 0.5f64.powi(k as i32);
            let extra = (sigma * sigma - finer_sigma * finer_sigma).sqrt() / finer.spacing();
            let coarser = filter_strided(finer, extra, 2);
            levels.push(coarser);
            sigmas.push(sigma);
        }
        levels.reverse();
        sigmas.reverse();
        Self { levels, sigmas }
    }

    /// The pyramids of several grids (any sizes), built in parallel; grids of other value
    /// types go through another call, e.g. both inside one `rayon::join`.
    pub fn build_all(finest: Vec<Grid<T>>) -> Vec<Self> {
        finest.into_par_iter().map(Self::new).collect()
    }
}

impl<T> Pyramid<T> {
    /// `K + 1`: the levels `k = 0..=K`.
    pub fn num_levels(&self) -> usize {
        self.levels.len()
    }

    /// Level `k` (`(2^k + 1)²` nodes). Panics if `k > K`.
    pub fn level(&self, k: usize) -> &Grid<T> {
        &self.levels[k]
    }

    /// `σ_k` (domain units) level `k` was filtered with; `0` for the finest.
    pub fn sigma(&self, k: usize) -> f64 {
        self.sigmas[k]
    }

    /// All levels, coarsest first.
    pub fn levels(&self) -> &[Grid<T>] {
        &self.levels
    }

    /// `σ_k` of every level, coarsest first.
    pub fn sigmas(&self) -> &[f64] {
        &self.sigmas
    }

    /// The unfiltered finest level.
    pub fn finest(&self) -> &Grid<T> {
        self.levels.last().unwrap()
    }

    /// `(grid, σ_k)` of every level, coarsest first.
    pub fn iter(&self) -> impl Iterator<Item = (&Grid<T>, f64)> {
        self.levels.iter().zip(self.sigmas.iter().copied())
    }

    /// The levels, coarsest first.
    pub fn into_levels(self) -> Vec<Grid<T>> {
        self.levels
    }
}

impl<const D: usize> Pyramid<[f64; D]> {
    /// Component `c` at every level (e.g. the `g11` pyramid of a metric pyramid).
    pub fn component(&self, c: usize) -> Pyramid<f64> {
        Pyramid {
            levels: self.levels.iter().map(|g| g.component(c)).collect(),
            sigmas: self.sigmas.clone(),
        }
    }
}

/// Mirror index for natural boundary conditions: reflect about nodes `0` and `n − 1` (`n ≥ 2`).
#[inline]
fn mirror(i: i64, n: usize) -> usize {
    let period = 2 * (n as i64 - 1);
    let m = i.rem_euclid(period);
    (if m >= n as i64 { period - m } else { m }) as usize
}

/// Normalized sampled Gaussian of width `sigma_nodes` (grid spacings), radius `⌈4σ⌉`.
fn gaussian_kernel(sigma_nodes: f64) -> (Vec<f64>, usize) {
    let radius = (4.0 * sigma_nodes).ceil() as usize;
    let r = radius as i64;
    let mut kernel: Vec<f64> = (-r..=r)
        .map(|t| (-(t * t) as f64 / (2.0 * sigma_nodes * sigma_nodes)).exp())
        .collect();
    let total: f64 = kernel.iter().sum();
    kernel.iter_mut().for_each(|w| *w /= total);
    (kernel, radius)
}

/// `mirror(i − radius, n)` for `i = 0 .. n + 2·radius`: the source index of every tap position.
fn mirrored_indices(n: usize, radius: usize) -> Vec<usize> {
    (0..n + 2 * radius)
        .map(|i| mirror(i as i64 - radius as i64, n))
        .collect()
}

/// Separable Gaussian filter of width `sigma_nodes` (in grid spacings) with mirrored
/// borders; the sampled kernel is normalized to sum 1, radius `⌈4σ⌉`. Output on the
/// rows and columns `0, step, 2·step, …` (`step` = 1: the whole grid; 2: filtered then
/// restricted by injection, computing only the kept nodes).
fn filter_strided<T: Vector>(img: &Grid<T>, sigma_nodes: f64, step: usize) -> Grid<T> {
    let n = img.size();
    let img = img.as_slice();
    let c = (n - 1) / step + 1;
    if sigma_nodes <= 0.0 {
        let kept = (0..c * c)
            .map(|k| img[(k / c) * step * n + (k % c) * step])
            .collect();
        return Grid::from_parts(c, kept);
    }
    let (kernel, radius) = gaussian_kernel(sigma_nodes);
    let index = mirrored_indices(n, radius);
    // Along rows (every row, kept columns only): tmp is n × c.
    let mut tmp = vec![T::ZERO; n * c];
    tmp.par_chunks_mut(c).enumerate().for_each(|(i, row)| {
        let src = &img[i * n..(i + 1) * n];
        for (jc, out) in row.iter_mut().enumerate() {
            let taps = &index[jc * step..jc * step + kernel.len()];
            *out = kernel
                .iter()
                .zip(taps)
                .fold(T::ZERO, |acc, (&w, &t)| acc.add_scaled(w, src[t]));
        }
    });
    // Along columns (kept rows only).
    let mut out = vec![T::ZERO; c * c];
    out.par_chunks_mut(c).enumerate().for_each(|(ic, row)| {
        let taps = &index[ic * step..ic * step + kernel.len()];
        for (&w, &t) in kernel.iter().zip(taps) {
            let src = &tmp[t * c..(t + 1) * c];
            for (o, &s) in row.iter_mut().zip(src) {
                *o = o.add_scaled(w, s);
            }
        }
    });
    Grid::from_parts(c, out)
}

/// Separable Gaussian filter of width `sigma_nodes` (in grid spacings) with mirrored
/// borders (natural boundary conditions); the sampled kernel is normalized to sum 1,
/// radius `⌈4σ⌉`. Acts component-wise on vector grids.
pub fn gaussian_filter<T: Vector>(img: &Grid<T>, sigma_nodes: f64) -> Grid<T> {
    filter_strided(img, sigma_nodes, 1)
}

/// [`gaussian_filter`] restricted to the rows and columns `0, step, 2·step, …` (only
/// those are computed): a grid `(n − 1)/step + 1` nodes wide. `step` must divide `n − 1`.
pub fn gaussian_filter_restricted<T: Vector>(
    img: &Grid<T>,
    sigma_nodes: f64,
    step: usize,
) -> Grid<T> {
    filter_strided(img, sigma_nodes, step)
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn sampled<T>(n: usize, f: impl Fn(f64, f64) -> T) -> Grid<T> {
        let s = (n - 1) as f64;
        Grid::from_fn(n, |i, j| f(j as f64 / s, i as f64 / s)).unwrap()
    }

    #[test]
    fn neumann_eigenfunctions_decay_like_the_heat_equation() {
        // cos(aπx)cos(bπy) has zero flux on ∂ω; G_σ multiplies it by exp(−(a²+b²)π²σ²/2).
        let n = 129;
        let (a, b) = (2.0, 1.0);
        let f = |x: f64, y: f64| (a * PI * x).cos() * (b * PI * y).cos();
        let p = Pyramid::new(sampled(n, f));
        assert_eq!(p.num_levels(), 8);
        assert_eq!(
            p.sigmas(),
            &[1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125, 0.015625, 0.0]
        );
        for k in 2..7 {
            let (lvl, sigma) = (p.level(k), p.sigma(k));
            assert_eq!((lvl.level(), lvl.size()), (k as u32, (1 << k) + 1));
            let damp = (-(a * a + b * b) * PI * PI * sigma * sigma / 2.0).exp();
            let mut err = 0.0f64;
            for i in 0..lvl.size() {
                for j in 0..lvl.size() {
                    let [x, y] = lvl.node(i, j);
                    err = err.max((lvl[(i, j)] - damp * f(x, y)).abs());
                }
            }
            assert!(
                err < 0.02 * damp.max(1e-3),
                "level {k} σ {sigma} err {err} damp {damp}"
            );
        }
        assert_eq!(p.finest(), &sampled(n, f));
    }

    #[test]
    fn filtered_delta_has_variance_sigma_squared() {
        let n = 257;
        let h = 1.0 / (n - 1) as f64;
        let mut img = Grid::new(n, 0.0).unwrap();
        img[(128, 128)] = 1.0 / (h * h); // unit mass at (0.5, 0.5)
        let p = Pyramid::new(img);
        for (lvl, sigma) in p.iter().skip(4).take(4) {
            let hm = lvl.spacing();
            let (mut mass, mut var) = (0.0, 0.0);
            for i in 0..lvl.size() {
                for j in 0..lvl.size() {
                    let x = lvl.node(i, j)[0] - 0.5;
                    mass += lvl[(i, j)] * hm * hm;
                    var += lvl[(i, j)] * x * x * hm * hm;
                }
            }
            assert!(
                (mass - 1.0).abs() < 1e-4,
                "level {} mass {mass}",
                lvl.level()
            );
            let s2 = sigma * sigma;
            assert!(
                (var / mass - s2).abs() < 0.02 * s2,
                "level {}: var {} vs {s2}",
                lvl.level(),
                var / mass
            );
        }
    }

    #[test]
    fn fused_filter_and_restriction_equals_filter_then_injection() {
        let n = 17;
        let fine = sampled(n, |x, y| [(5.0 * x).sin() * y, x - y * y]);
        let fused = filter_strided(&fine, 1.7, 2);
        let filtered = gaussian_filter(&fine, 1.7);
        let injected = Grid::from_fn(9, |i, j| filtered[(2 * i, 2 * j)]).unwrap();
        for (a, b) in fused.iter().zip(injected.iter()) {
            assert!((a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12);
        }
        // σ = 0 is the identity (step 1) or plain injection (step 2).
        assert_eq!(gaussian_filter(&fine, 0.0), fine);
        assert_eq!(filter_strided(&fine, 0.0, 2)[(3, 4)], fine[(6, 8)]);
    }

    #[test]
    fn vector_pyramids_are_scalar_pyramids_component_by_component() {
        // The metric pyramid filters [g11, g12, g22] together; each component equals the
        // scalar pyramid of that component bit for bit, and SPD tensors stay SPD.
        let n = 65;
        let g = sampled(n, |x, y| {
            let (s, c) = (7.0 * x + 3.0 * y).sin_cos();
            let (l1, l2) = (1.0 + 50.0 * x * x, 0.01 + y);
            [
                l1 * c * c + l2 * s * s,
                (l1 - l2) * c * s,
                l1 * s * s + l2 * c * c,
            ]
        });
        let metric: MetricPyramid = Pyramid::new(g.clone());
        for c in 0..3 {
            assert_eq!(metric.component(c), Pyramid::new(g.component(c)));
        }
        for (lvl, _) in metric.iter() {
            assert!(
                lvl.iter()
                    .all(|m| m[0] > 0.0 && m[0] * m[2] - m[1] * m[1] > 0.0)
            );
        }
        let all = Pyramid::build_all(vec![g.component(0), g.component(1).restrict().unwrap()]);
        assert_eq!(all[0], Pyramid::new(g.component(0)));
        assert_eq!(all[1].num_levels(), 6);
        assert_eq!(metric.into_levels().len(), 7);
    }

    #[test]
    fn mirror_reflects_about_border_nodes() {
        assert_eq!(
            (-3..8).map(|i| mirror(i, 4)).collect::<Vec<_>>(),
            vec![3, 2, 1, 0, 1, 2, 3, 2, 1, 0, 1]
        );
        assert_eq!(
            (-2..3).map(|i| mirror(i, 2)).collect::<Vec<_>>(),
            vec![0, 1, 0, 1, 0]
        );
    }
}
