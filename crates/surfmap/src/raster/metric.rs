//! The metric tensor `g = Dxᵀ Dx` of the parameterization `x: ω → ℝ³` (thesis §2.1.2,
//! §3.2.3). `x` is linear on each domain triangle, so `g` is constant per triangle:
//! with domain edge matrix `P = [ξ1 − ξ0, ξ2 − ξ0]` (2×2) and surface edge matrix
//! `E = [x1 − x0, x2 − x0]` (3×2), `Dx = E P⁻¹` and `g = P⁻ᵀ (Eᵀ E) P⁻¹`.
//! Stored as its three unique components `[g11, g12, g22]`; `√det g` is the ratio of
//! surface area to domain area.

use crate::vec3::{dot3, sub3};
use rayon::prelude::*;

/// `[g11, g12, g22]` of every triangle, for surface positions `x` and domain coordinates `xi`.
/// Triangles must be non-degenerate in the domain (checked by the rasterizer).
pub fn triangle_metrics(x: &[[f64; 3]], xi: &[[f64; 2]], triangles: &[[u32; 3]]) -> Vec<[f64; 3]> {
    triangles
        .par_iter()
        .map(|tri| {
            let [i0, i1, i2] = tri.map(|v| v as usize);
            let e1 = sub3(x[i1], x[i0]);
            let e2 = sub3(x[i2], x[i0]);
            let (a, b, c) = (dot3(e1, e1), dot3(e1, e2), dot3(e2, e2));
            // P⁻¹ = [[p22, −p12], [−p21, p11]] / det P, with P columns ξ1 − ξ0, ξ2 − ξ0.
            let (p11, p21) = (xi[i1][0] - xi[i0][0], xi[i1][1] - xi[i0][1]);
            let (p12, p22) = (xi[i2][0] - xi[i0][0], xi[i2][1] - xi[i0][1]);
            let det = p11 * p22 - p12 * p21;
            let q = [[p22 / det, -p12 / det], [-p21 / det, p11 / det]];
            // g = Qᵀ M Q with M = [[a, b], [b, c]].
            let mq = [
                [a * q[0][0] + b * q[1][0], a * q[0][1] + b * q[1][1]],
                [b * q[0][0] + c * q[1][0], b * q[0][1] + c * q[1][1]],
            ];
            let g11 = q[0][0] * mq[0][0] + q[1][0] * mq[1][0];
            let g12 = q[0][0] * mq[0][1] + q[1][0] * mq[1][1];
            let g22 = q[0][1] * mq[0][1] + q[1][1] * mq[1][1];
            [g11, g12, g22]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vec3::cross3;

    #[test]
    fn metric_of_a_linear_map_is_its_gram_matrix() {
        // x(ξ) = A ξ + c with a fixed 3×2 matrix A: g = AᵀA on every triangle.
        let a = [[1.0, 0.5], [-0.3, 2.0], [0.7, 0.1]];
        let xi = vec![[0.1, 0.2], [0.9, 0.3], [0.4, 0.8], [0.0, 0.0]];
        let x: Vec<[f64; 3]> = xi
            .iter()
            .map(|p| std::array::from_fn(|r| a[r][0] * p[0] + a[r][1] * p[1] + 1.0))
            .collect();
        let g = triangle_metrics(&x, &xi, &[[0, 1, 2], [3, 1, 2]]);
        let col = |c: usize| [a[0][c], a[1][c], a[2][c]];
        let exact = [
            dot3(col(0), col(0)),
            dot3(col(0), col(1)),
            dot3(col(1), col(1)),
        ];
        for gt in g {
            for k in 0..3 {
                assert!((gt[k] - exact[k]).abs() < 1e-12, "{gt:?} vs {exact:?}");
            }
        }
    }

    #[test]
    fn sqrt_det_g_is_the_area_ratio() {
        let xi = vec![[0.1, 0.1], [0.5, 0.2], [0.2, 0.6]];
        let x = vec![[0.0, 0.0, 1.0], [2.0, 0.3, 0.0], [-0.5, 1.0, 2.0]];
        let g = triangle_metrics(&x, &xi, &[[0, 1, 2]])[0];
        let area3 = 0.5
            * dot3(
                cross3(sub3(x[1], x[0]), sub3(x[2], x[0])),
                cross3(sub3(x[1], x[0]), sub3(x[2], x[0])),
            )
            .sqrt();
        let area2 = 0.5 * ((0.4 * 0.5) - (0.1 * 0.1));
        assert!(((g[0] * g[2] - g[1] * g[1]).sqrt() - area3 / area2).abs() < 1e-10);
    }
}
