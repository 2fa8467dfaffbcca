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
//! a division by `1 + λ(μ_l + μ_m)` and the inverse transform: `O(n² log n)`. The two
//! components are solved in parallel; the column transforms run as row transforms of
//! the transpose (contiguous memory), and every buffer is allocated once.

use std::sync::{Arc, Mutex};

use rustdct::{Dct1, DctPlanner};

/// `(I − λΔ_h)⁻¹` on an `n × n` grid.
pub struct SobolevPreconditioner {
    size: usize,
    dct: Arc<dyn Dct1<f64>>,
    /// `1 / (1 + λ(μ_l + μ_m))`, scaled by the inverse transform's `(2/(n − 1))²`.
    factor: Vec<f64>,
    /// Work space of each component.
    scratch: [Mutex<Scratch>; 2],
}

/// One component's values, their transpose and the 1D transform's scratch.
struct Scratch {
    values: Vec<f64>,
    transposed: Vec<f64>,
    dct: Vec<f64>,
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
        let dct = DctPlanner::new().plan_dct1(n);
        let scratch = std::array::from_fn(|_| {
            Mutex::new(Scratch {
                values: vec![0.0; n * n],
                transposed: vec![0.0; n * n],
                dct: vec![0.0; dct.get_scratch_len()],
            })
        });
        Self {
            size: n,
            dct,
            factor,
            scratch,
        }
    }

    /// `v = (I − λΔ_h)⁻¹ g`, both components.
    pub fn apply(&self, g: &[[f64; 2]], v: &mut [[f64; 2]]) {
        let n = self.size;
        let lock = |c: usize| self.scratch[c].lock().unwrap_or_else(|e| e.into_inner());
        let (mut guard0, mut guard1) = (lock(0), lock(1));
        let (s0, s1): (&mut Scratch, &mut Scratch) = (&mut guard0, &mut guard1);
        rayon::join(
            || self.solve_component(g, 0, s0),
            || self.solve_component(g, 1, s1),
        );
        for ((out, a), b) in v.iter_mut().take(n * n).zip(&s0.values).zip(&s1.values) {
            *out = [*a, *b];
        }
    }

    /// Component `c` of `(I − λΔ_h)⁻¹ g` into `s.values`.
    fn solve_component(&self, g: &[[f64; 2]], c: usize, s: &mut Scratch) {
        for (x, y) in s.values.iter_mut().zip(g) {
            *x = y[c];
        }
        self.transform(s);
        for (b, f) in s.values.iter_mut().zip(&self.factor) {
            *b *= f;
        }
        self.transform(s);
    }

    /// Unnormalized 2D DCT-I of `s.values` in place (rows, then columns as the rows of
    /// the transpose).
    fn transform(&self, s: &mut Scratch) {
        let n = self.size;
        for row in s.values.chunks_mut(n) {
            self.dct.process_dct1_with_scratch(row, &mut s.dct);
        }
        transpose(n, &s.values, &mut s.transposed);
        for row in s.transposed.chunks_mut(n) {
            self.dct.process_dct1_with_scratch(row, &mut s.dct);
        }
        transpose(n, &s.transposed, &mut s.values);
    }
}

/// `to = fromᵀ` for `n × n` row-major matrices, in cache-sized blocks.
fn transpose(n: usize, from: &[f64], to: &mut [f64]) {
    const BLOCK: usize = 16;
    for i0 in (0..n).step_by(BLOCK) {
        for j0 in (0..n).step_by(BLOCK) {
            for i in i0..(i0 + BLOCK).min(n) {
                for j in j0..(j0 + BLOCK).min(n) {
                    to[j * n + i] = from[i * n + j];
                }
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
