//! The matching deformation φ on the grid of one level (thesis §3.2.4, NOTES §2b).
//!
//! φ = id + u with one displacement `u_p ∈ ℝ²` per node of the `n × n` grid over
//! ω = [0, 1]², interpolated by P1 finite elements on the grid triangulated with one
//! diagonal per cell: cell `(i, j)` (corners `p00 = (i, j)`, `p01 = (i, j+1)`,
//! `p10 = (i+1, j)`, `p11 = (i+1, j+1)`, row `i` along ξ₁) is split into the lower
//! triangle `(p00, p01, p10)` and the upper triangle `(p11, p10, p01)`, both
//! counter-clockwise. On each triangle `Dφ` is constant:
//!
//! ```text
//! lower:  Dφ = [ (φ01 − φ00)/h | (φ10 − φ00)/h ]
//! upper:  Dφ = [ (φ11 − φ10)/h | (φ11 − φ01)/h ]      (columns ∂φ/∂ξ₀, ∂φ/∂ξ₁)
//! ```
//!
//! so `det Dφ` is one number per triangle, and `det Dφ(u + t·v)` is a quadratic in `t`:
//! the flattening's closed-form flip-free step ([`crate::param::flip_free`]) bounds
//! every line search, which is how the matcher stays fold-free by construction.
//! Prolongation to the next finer grid interpolates the P1 function (edge midpoints,
//! and the cell centre on the shared diagonal `p01–p10`), so the finer map is the
//! *same* map and stays fold-free.

use rayon::prelude::*;

use crate::param::flip_free::flip_free_step_below;

/// Node position `ξ = (j, i)/(n − 1)` of grid index `k`.
#[inline]
pub fn node(n: usize, k: usize) -> [f64; 2] {
    let h = 1.0 / (n - 1) as f64;
    [(k % n) as f64 * h, (k / n) as f64 * h]
}

/// The grid indices of the two triangles of cell `(i, j)`: lower then upper, each
/// counter-clockwise as `[origin, along ξ₀-side, along ξ₁-side]` in the sense of the
/// module docs.
#[inline]
pub fn cell_triangles(n: usize, i: usize, j: usize) -> [[usize; 3]; 2] {
    let p00 = i * n + j;
    let (p01, p10, p11) = (p00 + 1, p00 + n, p00 + n + 1);
    [[p00, p01, p10], [p11, p10, p01]]
}

/// `Dφ` of a triangle from its three node values, `[[∂φ⁰/∂ξ₀, ∂φ⁰/∂ξ₁], [∂φ¹/∂ξ₀, ∂φ¹/∂ξ₁]]`
/// (row = component of φ). `upper` selects the stencil of the module docs.
#[inline]
pub fn jacobian(phi: [[f64; 2]; 3], upper: bool, inv_h: f64) -> [[f64; 2]; 2] {
    let (cx, cy) = if upper {
        // [p11, p10, p01]: ∂/∂ξ₀ = φ11 − φ10, ∂/∂ξ₁ = φ11 − φ01
        (
            [phi[0][0] - phi[1][0], phi[0][1] - phi[1][1]],
            [phi[0][0] - phi[2][0], phi[0][1] - phi[2][1]],
        )
    } else {
        (
            [phi[1][0] - phi[0][0], phi[1][1] - phi[0][1]],
            [phi[2][0] - phi[0][0], phi[2][1] - phi[0][1]],
        )
    };
    [
        [cx[0] * inv_h, cy[0] * inv_h],
        [cx[1] * inv_h, cy[1] * inv_h],
    ]
}

/// Distributes `P = ∂E/∂Dφ` (same layout as [`jacobian`]) to the three nodes:
/// `∂E/∂φ_node` for `[node0, node1, node2]` of the triangle.
#[inline]
pub fn jacobian_adjoint(p: [[f64; 2]; 2], upper: bool, inv_h: f64) -> [[f64; 2]; 3] {
    let col0 = [p[0][0] * inv_h, p[1][0] * inv_h];
    let col1 = [p[0][1] * inv_h, p[1][1] * inv_h];
    if upper {
        [
            [col0[0] + col1[0], col0[1] + col1[1]],
            [-col0[0], -col0[1]],
            [-col1[0], -col1[1]],
        ]
    } else {
        [[-col0[0] - col1[0], -col0[1] - col1[1]], col0, col1]
    }
}

/// A deformation φ = id + u on an `n × n` grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Deformation {
    pub size: usize,
    /// Displacement `u` per node.
    pub displacement: Vec<[f64; 2]>,
}

impl Deformation {
    /// The identity on an `n × n` grid.
    pub fn identity(size: usize) -> Self {
        Self {
            size,
            displacement: vec![[0.0; 2]; size * size],
        }
    }

    /// `φ = f` at the nodes.
    pub fn from_map(size: usize, f: impl Fn([f64; 2]) -> [f64; 2] + Sync) -> Self {
        let displacement = (0..size * size)
            .into_par_iter()
            .map(|k| {
                let x = node(size, k);
                let y = f(x);
                [y[0] - x[0], y[1] - x[1]]
            })
            .collect();
        Self { size, displacement }
    }

    /// φ at node `k`.
    #[inline]
    pub fn at(&self, k: usize) -> [f64; 2] {
        let x = node(self.size, k);
        [
            x[0] + self.displacement[k][0],
            x[1] + self.displacement[k][1],
        ]
    }

    /// φ at every node.
    pub fn positions(&self) -> Vec<[f64; 2]> {
        (0..self.size * self.size).map(|k| self.at(k)).collect()
    }

    /// φ at any point of ω (P1 interpolation; points outside ω are clamped onto it).
    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let n = self.size;
        let last = (n - 1) as f64;
        let gx = (p[0] * last).clamp(0.0, last);
        let gy = (p[1] * last).clamp(0.0, last);
        let j = (gx as usize).min(n - 2);
        let i = (gy as usize).min(n - 2);
        let (fx, fy) = (gx - j as f64, gy - i as f64);
        let [lower, upper] = cell_triangles(n, i, j);
        let q = [p[0].clamp(0.0, 1.0), p[1].clamp(0.0, 1.0)];
        // Barycentric weights in the containing triangle, then φ = ξ + Σ wₖ uₖ.
        let (tri, w) = if fx + fy <= 1.0 {
            (lower, [1.0 - fx - fy, fx, fy])
        } else {
            (upper, [fx + fy - 1.0, 1.0 - fx, 1.0 - fy])
        };
        let mut out = q;
        for (&k, wk) in tri.iter().zip(w) {
            out[0] += wk * self.displacement[k][0];
            out[1] += wk * self.displacement[k][1];
        }
        out
    }

    /// Smallest `det Dφ` over all triangles (in units of ω: 1 for the identity).
    pub fn min_jacobian_determinant(&self) -> f64 {
        let n = self.size;
        let inv_h = (n - 1) as f64;
        (0..n - 1)
            .into_par_iter()
            .map(|i| {
                let mut m = f64::INFINITY;
                for j in 0..n - 1 {
                    for (t, tri) in cell_triangles(n, i, j).iter().enumerate() {
                        let d = jacobian(tri.map(|k| self.at(k)), t == 1, inv_h);
                        m = m.min(d[0][0] * d[1][1] - d[0][1] * d[1][0]);
                    }
                }
                m
            })
            .reduce(|| f64::INFINITY, f64::min)
    }

    /// Number of triangles with `det Dφ ≤ 0` (or not finite).
    pub fn folded_triangles(&self) -> usize {
        let n = self.size;
        let inv_h = (n - 1) as f64;
        (0..n - 1)
            .into_par_iter()
            .map(|i| {
                let mut count = 0;
                for j in 0..n - 1 {
                    for (t, tri) in cell_triangles(n, i, j).iter().enumerate() {
                        let d = jacobian(tri.map(|k| self.at(k)), t == 1, inv_h);
                        let det = d[0][0] * d[1][1] - d[0][1] * d[1][0];
                        if det.is_nan() || det <= 0.0 {
                            count += 1;
                        }
                    }
                }
                count
            })
            .sum()
    }

    /// Largest `t` such that `φ + s·v` keeps every triangle positively oriented for
    /// `s ∈ [0, t)` (closed form per triangle, [`crate::param::flip_free::flip_free_step`]); `0` if φ itself
    /// has a folded triangle, `∞` if no triangle ever degenerates along `v`.
    pub fn max_fold_free_step(&self, direction: &[[f64; 2]]) -> f64 {
        let n = self.size;
        let h = 1.0 / (n - 1) as f64;
        let u = &self.displacement;
        (0..n - 1)
            .into_par_iter()
            .map(|i| {
                let (y0, y1) = (i as f64 * h, (i + 1) as f64 * h);
                let mut m = f64::INFINITY;
                for j in 0..n - 1 {
                    let (x0, x1) = (j as f64 * h, (j + 1) as f64 * h);
                    let k = i * n + j;
                    let p00 = [x0 + u[k][0], y0 + u[k][1]];
                    let p01 = [x1 + u[k + 1][0], y0 + u[k + 1][1]];
                    let p10 = [x0 + u[k + n][0], y1 + u[k + n][1]];
                    let p11 = [x1 + u[k + n + 1][0], y1 + u[k + n + 1][1]];
                    let (d00, d01, d10, d11) = (
                        direction[k],
                        direction[k + 1],
                        direction[k + n],
                        direction[k + n + 1],
                    );
                    // Node order [origin, ξ₀-side, ξ₁-side] is counter-clockwise for
                    // both triangles, as flip_free_step expects.
                    m = m.min(flip_free_step_below([p00, p01, p10], [d00, d01, d10], m));
                    m = m.min(flip_free_step_below([p11, p10, p01], [d11, d10, d01], m));
                }
                m
            })
            .reduce(|| f64::INFINITY, f64::min)
    }

    /// The same P1 map on the next finer grid (`2n − 1` nodes per side).
    pub fn prolongate(&self) -> Self {
        let n = self.size;
        let f = 2 * (n - 1) + 1;
        let u = &self.displacement;
        let mut out = vec![[0.0; 2]; f * f];
        out.par_chunks_mut(f).enumerate().for_each(|(i, row)| {
            for (j, o) in row.iter_mut().enumerate() {
                let (i0, j0) = (i / 2, j / 2);
                let k = i0 * n + j0;
                let avg =
                    |a: usize, b: usize| [0.5 * (u[a][0] + u[b][0]), 0.5 * (u[a][1] + u[b][1])];
                *o = match (i % 2, j % 2) {
                    (0, 0) => u[k],
                    (0, _) => avg(k, k + 1),
                    (_, 0) => avg(k, k + n),
                    // Cell centre: on the diagonal p01–p10 shared by both triangles.
                    _ => avg(k + 1, k + n),
                };
            }
        });
        Self {
            size: f,
            displacement: out,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn swirl(n: usize, amount: f64) -> Deformation {
        Deformation::from_map(n, |p| {
            let (x, y) = (p[0] - 0.5, p[1] - 0.5);
            let a = amount * (1.0 - 4.0 * (x * x + y * y)).max(0.0);
            let (s, c) = a.sin_cos();
            [0.5 + c * x - s * y, 0.5 + s * x + c * y]
        })
    }

    #[test]
    fn jacobian_of_an_affine_map_is_its_matrix() {
        let m = [[1.2, 0.3], [-0.4, 0.9]];
        let phi = Deformation::from_map(5, |p| {
            [
                m[0][0] * p[0] + m[0][1] * p[1] + 0.1,
                m[1][0] * p[0] + m[1][1] * p[1] - 0.2,
            ]
        });
        for (t, tri) in cell_triangles(5, 1, 2).iter().enumerate() {
            let d = jacobian(tri.map(|k| phi.at(k)), t == 1, 4.0);
            for a in 0..2 {
                for b in 0..2 {
                    assert!((d[a][b] - m[a][b]).abs() < 1e-12, "{d:?}");
                }
            }
        }
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        assert!((phi.min_jacobian_determinant() - det).abs() < 1e-12);
    }

    #[test]
    fn adjoint_is_the_transpose_of_the_jacobian() {
        // ⟨P, J(φ)⟩ = Σ_nodes ⟨adjoint(P)_node, φ_node⟩ for a linear J.
        let phi = [[0.3, -0.1], [0.7, 0.2], [-0.2, 0.5]];
        let p = [[0.4, -1.3], [2.0, 0.7]];
        for upper in [false, true] {
            let d = jacobian(phi, upper, 3.0);
            let lhs: f64 = (0..2)
                .map(|a| (0..2).map(|b| p[a][b] * d[a][b]).sum::<f64>())
                .sum();
            let adj = jacobian_adjoint(p, upper, 3.0);
            let rhs: f64 = (0..3)
                .map(|k| adj[k][0] * phi[k][0] + adj[k][1] * phi[k][1])
                .sum();
            assert!((lhs - rhs).abs() < 1e-12, "{upper}: {lhs} vs {rhs}");
        }
    }

    #[test]
    fn prolongation_keeps_the_p1_map_exactly() {
        let coarse = swirl(9, 0.8);
        assert!(coarse.min_jacobian_determinant() > 0.0);
        let fine = coarse.prolongate();
        assert_eq!(fine.size, 17);
        let mut rng = crate::testing::Rng(3);
        for _ in 0..200 {
            let p = [rng.uniform(), rng.uniform()];
            let (a, b) = (coarse.apply(p), fine.apply(p));
            assert!((a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12);
        }
        assert!(fine.min_jacobian_determinant() > 0.0);
        assert!((fine.min_jacobian_determinant() - coarse.min_jacobian_determinant()).abs() < 1e-9);
    }

    #[test]
    fn fold_free_step_is_the_first_degeneracy() {
        let phi = swirl(9, 0.8);
        let mut rng = crate::testing::Rng(11);
        let v: Vec<[f64; 2]> = (0..81)
            .map(|_| [rng.uniform() - 0.5, rng.uniform() - 0.5])
            .collect();
        let t = phi.max_fold_free_step(&v);
        assert!(t.is_finite() && t > 0.0);
        let moved = |s: f64| Deformation {
            size: 9,
            displacement: phi
                .displacement
                .iter()
                .zip(&v)
                .map(|(u, d)| [u[0] + s * d[0], u[1] + s * d[1]])
                .collect(),
        };
        assert_eq!(moved(0.999 * t).folded_triangles(), 0);
        assert!(moved(1.001 * t).folded_triangles() > 0);
    }
}
