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
//! [`prolongate`] is bilinear interpolation from level `k` to level `k + 1`.

use rayon::prelude::*;

/// One level of the pyramid.
#[derive(Clone, Debug, PartialEq)]
pub struct PyramidLevel {
    /// `k`: the grid has `2^k + 1` nodes per side.
    pub level: u32,
    pub size: usize,
    /// Gaussian width (domain units) the images were filtered with.
    pub sigma: f64,
    /// Filtered images, in the order of [`Pyramid::names`].
    pub images: Vec<Vec<f64>>,
}

/// Images filtered and restricted to every level, coarsest first.
#[derive(Clone, Debug, PartialEq)]
pub struct Pyramid {
    pub names: Vec<String>,
    pub levels: Vec<PyramidLevel>,
}

impl Pyramid {
    /// Builds the pyramid of `images` (each `size²`, `size = 2^K + 1`, all values finite).
    pub fn build(size: usize, names: Vec<String>, images: Vec<Vec<f64>>) -> Self {
        let top = (size - 1).trailing_zeros();
        let mut levels = vec![PyramidLevel {
            level: top,
            size,
            sigma: 0.0,
            images,
        }];
        for k in (0..top).rev() {
            let finer = levels.last().unwrap();
            let sigma = 0.5f64.powi(k as i32);
            let spacing = 1.0 / (finer.size - 1) as f64;
            let extra = (sigma * sigma - finer.sigma * finer.sigma).sqrt() / spacing;
            let images = finer
                .images
                .par_iter()
                .map(|img| filter_and_restrict(img, finer.size, extra))
                .collect();
            levels.push(PyramidLevel {
                level: k,
                size: (finer.size - 1) / 2 + 1,
                sigma,
                images,
            });
        }
        levels.reverse();
        Self { names, levels }
    }

    /// The image called `name` at level `k`.
    pub fn image(&self, k: usize, name: &str) -> Option<&[f64]> {
        let i = self.names.iter().position(|n| n == name)?;
        Some(&self.levels.get(k)?.images[i])
    }
}

/// Mirror index for natural boundary conditions: reflect about nodes `0` and `n − 1`.
#[inline]
fn mirror(i: i64, n: usize) -> usize {
    if n == 1 {
        return 0;
    }
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
fn filter_strided(img: &[f64], size: usize, sigma_nodes: f64, step: usize) -> Vec<f64> {
    let n = size;
    let c = (n - 1) / step + 1;
    if sigma_nodes <= 0.0 {
        return (0..c * c)
            .map(|k| img[(k / c) * step * n + (k % c) * step])
            .collect();
    }
    let (kernel, radius) = gaussian_kernel(sigma_nodes);
    let index = mirrored_indices(n, radius);
    // Along rows (every row, kept columns only): tmp is n × c.
    let mut tmp = vec![0.0; n * c];
    tmp.par_chunks_mut(c).enumerate().for_each(|(i, row)| {
        let src = &img[i * n..(i + 1) * n];
        for (jc, out) in row.iter_mut().enumerate() {
            let taps = &index[jc * step..jc * step + kernel.len()];
            *out = kernel.iter().zip(taps).map(|(w, &t)| w * src[t]).sum();
        }
    });
    // Along columns (kept rows only).
    let mut out = vec![0.0; c * c];
    out.par_chunks_mut(c).enumerate().for_each(|(ic, row)| {
        let taps = &index[ic * step..ic * step + kernel.len()];
        for (w, &t) in kernel.iter().zip(taps) {
            let src = &tmp[t * c..(t + 1) * c];
            for (o, s) in row.iter_mut().zip(src) {
                *o += w * s;
            }
        }
    });
    out
}

/// Separable Gaussian filter of width `sigma_nodes` (in grid spacings) with mirrored
/// borders; the sampled kernel is normalized to sum 1, radius `⌈4σ⌉`.
pub fn gaussian_filter(img: &[f64], size: usize, sigma_nodes: f64) -> Vec<f64> {
    filter_strided(img, size, sigma_nodes, 1)
}

/// `restrict(&gaussian_filter(img, size, sigma_nodes), size)`, computing only the kept nodes.
pub fn filter_and_restrict(img: &[f64], size: usize, sigma_nodes: f64) -> Vec<f64> {
    filter_strided(img, size, sigma_nodes, 2)
}

/// Injection from a `(2m + 1)²` grid to the `(m + 1)²` grid of every other node.
pub fn restrict(img: &[f64], size: usize) -> Vec<f64> {
    let c = (size - 1) / 2 + 1;
    let mut out = Vec::with_capacity(c * c);
    for i in 0..c {
        for j in 0..c {
            out.push(img[2 * i * size + 2 * j]);
        }
    }
    out
}

/// Bilinear prolongation from a `(m + 1)²` grid to the `(2m + 1)²` grid.
pub fn prolongate(img: &[f64], size: usize) -> Vec<f64> {
    let f = 2 * (size - 1) + 1;
    let mut out = vec![0.0; f * f];
    out.par_chunks_mut(f).enumerate().for_each(|(i, row)| {
        let (i0, i1) = (i / 2, i.div_ceil(2));
        for (j, o) in row.iter_mut().enumerate() {
            let (j0, j1) = (j / 2, j.div_ceil(2));
            *o = 0.25
                * (img[i0 * size + j0]
                    + img[i0 * size + j1]
                    + img[i1 * size + j0]
                    + img[i1 * size + j1]);
        }
    });
    out
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn neumann_eigenfunctions_decay_like_the_heat_equation() {
        // cos(aπx)cos(bπy) has zero flux on ∂ω; G_σ multiplies it by exp(−(a²+b²)π²σ²/2).
        let n = 129;
        let (a, b) = (2.0, 1.0);
        let f = |x: f64, y: f64| (a * PI * x).cos() * (b * PI * y).cos();
        let img: Vec<f64> = (0..n * n)
            .map(|k| {
                f(
                    (k % n) as f64 / (n - 1) as f64,
                    (k / n) as f64 / (n - 1) as f64,
                )
            })
            .collect();
        let p = Pyramid::build(n, vec!["f".into()], vec![img]);
        assert_eq!(p.levels.len(), 8);
        for lvl in &p.levels[2..7] {
            let damp = (-(a * a + b * b) * PI * PI * lvl.sigma * lvl.sigma / 2.0).exp();
            let m = lvl.size;
            let mut err = 0.0f64;
            for k in 0..m * m {
                let exact = damp
                    * f(
                        (k % m) as f64 / (m - 1) as f64,
                        (k / m) as f64 / (m - 1) as f64,
                    );
                err = err.max((lvl.images[0][k] - exact).abs());
            }
            assert!(
                err < 0.02 * damp.max(1e-3),
                "level {} σ {} err {err} damp {damp}",
                lvl.level,
                lvl.sigma
            );
        }
    }

    #[test]
    fn filtered_delta_has_variance_sigma_squared() {
        let n = 257;
        let h = 1.0 / (n - 1) as f64;
        let mut img = vec![0.0; n * n];
        let c = 128 * n + 128;
        img[c] = 1.0 / (h * h); // unit mass at (0.5, 0.5)
        let p = Pyramid::build(n, vec!["delta".into()], vec![img]);
        for lvl in &p.levels[4..8] {
            let m = lvl.size;
            let hm = 1.0 / (m - 1) as f64;
            let (mut mass, mut var) = (0.0, 0.0);
            for k in 0..m * m {
                let x = (k % m) as f64 * hm - 0.5;
                mass += lvl.images[0][k] * hm * hm;
                var += lvl.images[0][k] * x * x * hm * hm;
            }
            assert!((mass - 1.0).abs() < 1e-4, "level {} mass {mass}", lvl.level);
            let s2 = lvl.sigma * lvl.sigma;
            assert!(
                (var / mass - s2).abs() < 0.02 * s2,
                "level {}: var {} vs {s2}",
                lvl.level,
                var / mass
            );
        }
    }

    #[test]
    fn prolongation_reproduces_bilinear_functions_and_inverts_restriction() {
        let m = 9;
        let f = |x: f64, y: f64| 1.0 + 2.0 * x - 3.0 * y + 0.5 * x * y;
        let coarse: Vec<f64> = (0..m * m)
            .map(|k| {
                f(
                    (k % m) as f64 / (m - 1) as f64,
                    (k / m) as f64 / (m - 1) as f64,
                )
            })
            .collect();
        let fine = prolongate(&coarse, m);
        let n = 2 * m - 1;
        for k in 0..n * n {
            let exact = f(
                (k % n) as f64 / (n - 1) as f64,
                (k / n) as f64 / (n - 1) as f64,
            );
            assert!((fine[k] - exact).abs() < 1e-12);
        }
        assert_eq!(restrict(&fine, n), coarse);
        // The fused filter + restriction equals filtering then restricting.
        let fused = filter_and_restrict(&fine, n, 1.7);
        let separate = restrict(&gaussian_filter(&fine, n, 1.7), n);
        assert!(
            fused
                .iter()
                .zip(&separate)
                .all(|(a, b)| (a - b).abs() < 1e-12)
        );
    }

    #[test]
    fn mirror_reflects_about_border_nodes() {
        assert_eq!(
            (-3..8).map(|i| mirror(i, 4)).collect::<Vec<_>>(),
            vec![3, 2, 1, 0, 1, 2, 3, 2, 1, 0, 1]
        );
    }
}
