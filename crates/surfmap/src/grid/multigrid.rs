//! Transfer between nested grid levels: level `k` (`N = 2^k + 1`) and level `k ± 1`. The
//! matcher prolongates its deformation from each level to the next finer one (thesis
//! §3.2.4); a multigrid or H¹-preconditioned solver also restricts residuals.
//!
//! * [`Grid::prolongate`] (`P`, level `k → k + 1`): bilinear interpolation. Coarse nodes are
//!   copied, edge midpoints average their two coarse neighbours, cell centres their four;
//!   bilinear functions are reproduced exactly.
//! * [`Grid::restrict`] (`R`, level `k → k − 1`): full weighting, the tensor product of the
//!   1D weights `(¼, ½, ¼)` centred on every coarse node, a neighbour beyond the border
//!   replaced by its mirror image (natural boundary conditions, as in the pyramid filter).
//!   Constants are kept; smooth functions are reproduced to `O(h²)` inside, and to `O(h²)`
//!   on the border when their normal derivative vanishes there (otherwise the border
//!   average is off by `O(h)`, as any non-negative averaging of a sloped function).
//!
//! `R` is the adjoint of `P` in the trapezoid-rule `L²` inner product
//! `⟨u, v⟩_h = h² Σ_{ij} w_i w_j u_ij · v_ij` (`w = ½` on border nodes, 1 inside):
//! `⟨R u, v⟩_{2h} = ⟨u, P v⟩_h`, i.e. `Σ w w (R u) v = ¼ Σ w w u (P v)` in plain weighted
//! sums, since `(2h)² = 4h²`.
//!
//! Cost `O(N²)` each, rows in parallel.

use rayon::prelude::*;

use super::GridError;
use super::domain::MAX_SIZE;
use super::grid::Grid;
use super::value::Vector;

impl<T: Vector> Grid<T> {
    /// Full-weighting restriction to the next coarser level (`(N + 1)/2` nodes per side).
    /// The `2 × 2` grid has no coarser level.
    pub fn restrict(&self) -> Result<Grid<T>, GridError> {
        let n = self.size();
        if n <= 2 {
            return Err(GridError::NoCoarserLevel { size: n });
        }
        let c = (n - 1) / 2 + 1;
        let fine = self.as_slice();
        // Fine index of the taps around 2I, mirrored about the border nodes.
        let taps = |m: usize| {
            let m = 2 * m;
            [
                if m == 0 { 1 } else { m - 1 },
                m,
                if m + 1 == n { n - 2 } else { m + 1 },
            ]
        };
        const W: [f64; 3] = [0.25, 0.5, 0.25];
        let mut out = vec![T::ZERO; c * c];
        out.par_chunks_mut(c).enumerate().for_each(|(ci, row)| {
            let rows = taps(ci);
            for (cj, o) in row.iter_mut().enumerate() {
                let cols = taps(cj);
                let mut acc = T::ZERO;
                for (wi, &r) in W.iter().zip(&rows) {
                    let mut line = T::ZERO;
                    for (wj, &col) in W.iter().zip(&cols) {
                        line = line.add_scaled(*wj, fine[r * n + col]);
                    }
                    acc = acc.add_scaled(*wi, line);
                }
                *o = acc;
            }
        });
        Ok(Grid::from_parts(c, out))
    }

    /// Bilinear prolongation to the next finer level (`2N − 1` nodes per side); fails
    /// beyond the largest supported grid.
    pub fn prolongate(&self) -> Result<Grid<T>, GridError> {
        let c = self.size();
        let f = 2 * (c - 1) + 1;
        if f > MAX_SIZE {
            return Err(GridError::NoFinerLevel { size: c });
        }
        let coarse = self.as_slice();
        let at = |i: usize, j: usize| coarse[i * c + j];
        let mut out = vec![T::ZERO; f * f];
        out.par_chunks_mut(f).enumerate().for_each(|(i, row)| {
            let i0 = i / 2;
            for (j, o) in row.iter_mut().enumerate() {
                let j0 = j / 2;
                *o = match (i % 2, j % 2) {
                    (0, 0) => at(i0, j0),
                    (0, _) => at(i0, j0).add(at(i0, j0 + 1)).scale(0.5),
                    (_, 0) => at(i0, j0).add(at(i0 + 1, j0)).scale(0.5),
                    _ => at(i0, j0)
                        .add(at(i0, j0 + 1))
                        .add(at(i0 + 1, j0))
                        .add(at(i0 + 1, j0 + 1))
                        .scale(0.25),
                };
            }
        });
        Ok(Grid::from_parts(f, out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Rng;
    use std::f64::consts::PI;

    fn sampled<T>(n: usize, f: impl Fn(f64, f64) -> T) -> Grid<T> {
        let s = (n - 1) as f64;
        Grid::from_fn(n, |i, j| f(j as f64 / s, i as f64 / s)).unwrap()
    }

    /// `Σ_ij w_i w_j u_ij v_ij`, trapezoid weights `½` on border nodes.
    fn weighted_dot(u: &Grid<f64>, v: &Grid<f64>) -> f64 {
        let n = u.size();
        let w = |m: usize| if m == 0 || m == n - 1 { 0.5 } else { 1.0 };
        (0..n * n)
            .map(|k| w(k / n) * w(k % n) * u.as_slice()[k] * v.as_slice()[k])
            .sum()
    }

    #[test]
    fn prolongation_reproduces_bilinear_functions() {
        let f = |x: f64, y: f64| [1.0 + 2.0 * x - 3.0 * y + 0.5 * x * y, x * y - 4.0];
        for m in [3, 9] {
            let fine = sampled(m, f).prolongate().unwrap();
            assert_eq!(fine.size(), 2 * m - 1);
            let exact = sampled(2 * m - 1, f);
            for (a, b) in fine.iter().zip(exact.iter()) {
                assert!((a[0] - b[0]).abs() < 1e-13 && (a[1] - b[1]).abs() < 1e-13);
            }
        }
        // Coarse nodes are copied exactly.
        let coarse = sampled(5, |x, y| (x * 7.0).sin() + y.sqrt());
        let fine = coarse.prolongate().unwrap();
        for i in 0..5 {
            for j in 0..5 {
                assert_eq!(fine[(2 * i, 2 * j)], coarse[(i, j)]);
            }
        }
    }

    #[test]
    fn restriction_keeps_constants() {
        let g = Grid::new(17, [0.1, -3.7, 1e6]).unwrap();
        let r = g.restrict().unwrap();
        assert_eq!(r.size(), 9);
        for v in r.iter() {
            for c in 0..3 {
                assert!((v[c] - g[(0, 0)][c]).abs() <= 1e-15 * g[(0, 0)][c].abs());
            }
        }
        let coarsest = Grid::new(3, 2.5).unwrap().restrict().unwrap();
        assert_eq!((coarsest.size(), coarsest.level()), (2, 0));
        assert_eq!(coarsest.as_slice(), &[2.5; 4]);
        assert_eq!(
            coarsest.restrict().unwrap_err(),
            GridError::NoCoarserLevel { size: 2 }
        );
    }

    #[test]
    fn prolongation_after_restriction_converges_on_smooth_functions() {
        // Error of P R u against u: O(h²) everywhere for a Neumann function (zero normal
        // derivative on ∂ω), O(h²) away from the border for a general one.
        let neumann = |x: f64, y: f64| (PI * x).cos() * (2.0 * PI * y).cos();
        let general = |x: f64, y: f64| (2.0 * x + y).sin() + x * x * y;
        let mut errs = vec![];
        for n in [33, 65, 129] {
            let u = sampled(n, |x, y| [neumann(x, y), general(x, y)]);
            let back = u.restrict().unwrap().prolongate().unwrap();
            let (mut e_all, mut e_inside) = (0.0f64, 0.0f64);
            for i in 0..n {
                for j in 0..n {
                    let (a, b) = (u[(i, j)], back[(i, j)]);
                    e_all = e_all.max((a[0] - b[0]).abs());
                    if i.min(j).min(n - 1 - i).min(n - 1 - j) >= 4 {
                        e_inside = e_inside.max((a[1] - b[1]).abs());
                    }
                }
            }
            errs.push((e_all, e_inside));
        }
        for k in 1..3 {
            assert!(errs[k].0 < 0.3 * errs[k - 1].0, "{errs:?}");
            assert!(errs[k].1 < 0.3 * errs[k - 1].1, "{errs:?}");
        }
        assert!(errs[2].0 < 3e-3 && errs[2].1 < 3e-4, "{errs:?}");
    }

    #[test]
    fn restriction_is_the_adjoint_of_prolongation() {
        let mut rng = Rng(3);
        for c in [2, 3, 5, 17] {
            let f = 2 * c - 1;
            let u = Grid::from_parts(f, (0..f * f).map(|_| rng.range(-1.0, 1.0)).collect());
            let v = Grid::from_parts(c, (0..c * c).map(|_| rng.range(-1.0, 1.0)).collect());
            let lhs = weighted_dot(&u.restrict().unwrap(), &v);
            let rhs = 0.25 * weighted_dot(&u, &v.prolongate().unwrap());
            assert!(
                (lhs - rhs).abs() < 1e-12 * (1.0 + lhs.abs()),
                "{c}: {lhs} vs {rhs}"
            );
        }
    }

    #[test]
    fn no_level_beyond_the_largest_grid() {
        // Zero-sized values: the 4097² grid costs no memory.
        let g = Grid::new(MAX_SIZE, [0.0f64; 0]).unwrap();
        assert_eq!(
            g.prolongate().unwrap_err(),
            GridError::NoFinerLevel { size: MAX_SIZE }
        );
        assert_eq!(
            Grid::new(2049, [0.0f64; 0])
                .unwrap()
                .prolongate()
                .unwrap()
                .size(),
            MAX_SIZE
        );
    }
}
