//! A Sobolev (H¹) preconditioner for the gradient of the matching energy
//! (NOTES §2b "Conditioning").
//!
//! The regularization's Hessian behaves like a Laplacian, so plain L² gradients on an
//! `n × n` grid make conjugate gradients slow down like `n`. Descent directions are
//! instead taken in the metric `⟨u, v⟩ = ∫ u·v + λ ∇u : ∇v`, i.e. the gradient `g` is
//! replaced by the solution `v` of
//!
//! ```text
//! (I − λ Δ_h) v = g      on the grid, natural (mirror) boundary conditions,
//! ```
//!
//! `Δ_h` the 5-point Laplacian. Its eigenvectors are the products of DCT-I basis
//! functions `cos(π m i/(n − 1))` (the mirror condition at the border nodes is
//! exactly what DCT-I diagonalizes), with eigenvalues
//! `−(μ_l + μ_m)`, `μ_m = 4 sin²(π m / (2(n − 1))) / h²`, so one solve is a 2D DCT-I,
//! a division by `1 + λ(μ_l + μ_m)` and the inverse transform: `O(n² log n)`.

use std::sync::Arc;

use rayon::prelude::*;
use rustdct::{Dct1, DctPlanner};

/// `(I − λΔ_h)⁻¹` on an `n × n` grid.
pub struct SobolevPreconditioner {
    size: usize,
    dct: Arc<dyn Dct1<f64>>,
    /// `1 / (1 + λ(μ_l + μ_m))`, scaled by the inverse transform's `(2/(n − 1))²`.
    factor: Vec<f64>,
}

impl std::fmt::Debug for SobolevPreconditioner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SobolevPreconditioner")
            .field("size", &self.size)
            .finish()
    }
}

impl SobolevPreconditioner {
    /// For an `n × n` grid over ω = [0, 1]² (`h = 1/(n − 1)`) and `λ ≥ 0` (domain units²).
    pub fn new(size: usize, lambda: f64) -> Self {
        let n = size;
        let h = 1.0 / (n - 1) as f64;
        let mu: Vec<f64> = (0..n)
            .map(|m| {
                let s = (std::f64::consts::PI * m as f64 / (2.0 * (n - 1) as f64)).sin();
                4.0 * s * s / (h * h)
            })
            .collect();
        let norm = (2.0 / (n - 1) as f64).powi(2);
        let factor = (0..n * n)
            .map(|k| norm / (1.0 + lambda * (mu[k / n] + mu[k % n])))
            .collect();
        Self {
            size: n,
            dct: DctPlanner::new().plan_dct1(n),
            factor,
        }
    }

    /// `v = (I − λΔ_h)⁻¹ g`, both components.
    pub fn apply(&self, g: &[[f64; 2]], v: &mut [[f64; 2]]) {
        let n = self.size;
        let mut comps: [Vec<f64>; 2] = std::array::from_fn(|c| g.iter().map(|x| x[c]).collect());
        comps.par_iter_mut().for_each(|buf| {
            self.transform(buf);
            for (b, f) in buf.iter_mut().zip(&self.factor) {
                *b *= f;
            }
            self.transform(buf);
        });
        for (k, out) in v.iter_mut().enumerate().take(n * n) {
            *out = [comps[0][k], comps[1][k]];
        }
    }

    /// Unnormalized 2D DCT-I in place (rows, then columns).
    fn transform(&self, buf: &mut [f64]) {
        let n = self.size;
        for row in buf.chunks_mut(n) {
            self.dct.process_dct1(row);
        }
        let mut column = vec![0.0; n];
        for j in 0..n {
            for i in 0..n {
                column[i] = buf[i * n + j];
            }
            self.dct.process_dct1(&mut column);
            for i in 0..n {
                buf[i * n + j] = column[i];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(I − λΔ_h) v` with mirror boundaries, for checking the inverse.
    fn operator(n: usize, lambda: f64, v: &[f64]) -> Vec<f64> {
        let h2 = (1.0 / (n - 1) as f64).powi(2);
        let at = |i: i64, j: i64| {
            let m = |t: i64| {
                if t < 0 {
                    -t
                } else if t >= n as i64 {
                    2 * (n as i64 - 1) - t
                } else {
                    t
                }
            };
            v[m(i) as usize * n + m(j) as usize]
        };
        (0..n * n)
            .map(|k| {
                let (i, j) = ((k / n) as i64, (k % n) as i64);
                let lap = (at(i - 1, j) + at(i + 1, j) + at(i, j - 1) + at(i, j + 1)
                    - 4.0 * at(i, j))
                    / h2;
                v[k] - lambda * lap
            })
            .collect()
    }

    #[test]
    fn inverts_the_screened_laplacian_with_mirror_boundaries() {
        let n = 17;
        let lambda = 0.003;
        let p = SobolevPreconditioner::new(n, lambda);
        let mut rng = crate::testing::Rng(21);
        let g: Vec<[f64; 2]> = (0..n * n)
            .map(|_| [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)])
            .collect();
        let mut v = vec![[0.0; 2]; n * n];
        p.apply(&g, &mut v);
        for c in 0..2 {
            let vc: Vec<f64> = v.iter().map(|x| x[c]).collect();
            let back = operator(n, lambda, &vc);
            for k in 0..n * n {
                assert!(
                    (back[k] - g[k][c]).abs() < 1e-10,
                    "{k}: {} vs {}",
                    back[k],
                    g[k][c]
                );
            }
        }
        // λ = 0 is the identity.
        let id = SobolevPreconditioner::new(n, 0.0);
        id.apply(&g, &mut v);
        assert!(
            v.iter()
                .zip(&g)
                .all(|(a, b)| (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12)
        );
    }
}
