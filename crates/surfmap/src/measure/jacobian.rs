//! Per-triangle Jacobian of the piecewise-affine map surface → UV and its signed
//! singular values (thesis §2.1.1–2.1.2, §4.1.4).
//!
//! For a triangle with corners `p0, p1, p2` in 3D and `u0, u1, u2` in UV, the map is
//! written in the orthonormal frame `x̂ = e1/|e1|`, `ŷ = n̂ × x̂` of the triangle's
//! plane (`e1 = p1 − p0`, `n = e1 × e2`): the 3D corners become `q0 = (0, 0)`,
//! `q1 = (|e1|, 0)`, `q2 = (e2·x̂, |n|/|e1|)`, and `J [q1 q2] = [u1 − u0, u2 − u0]`.
//! The thesis's inverse metric is `g⁻¹ = J Jᵀ` (`C = Dφ g⁻¹ Dφᵀ` of §2.1.3 written per
//! triangle), so its eigenvalues are `Γ = σ1²  ≥  γ = σ2²`.

/// Jacobian `J` (row-major `[[∂u/∂x, ∂u/∂y], [∂v/∂x, ∂v/∂y]]`) and 3D area of one
/// triangle. Returns `None` when the 3D triangle has zero area (no frame exists).
#[inline]
pub fn triangle_jacobian(p: [[f64; 3]; 3], uv: [[f64; 2]; 3]) -> Option<([[f64; 2]; 2], f64)> {
    let e1 = sub3(p[1], p[0]);
    let e2 = sub3(p[2], p[0]);
    let n = cross3(e1, e2);
    let twice_area = norm3(n);
    let l1 = norm3(e1);
    if twice_area <= 0.0 || l1 <= 0.0 || !twice_area.is_finite() {
        return None;
    }
    let q2x = dot3(e2, e1) / l1;
    let q2y = twice_area / l1;
    let du1 = [uv[1][0] - uv[0][0], uv[1][1] - uv[0][1]];
    let du2 = [uv[2][0] - uv[0][0], uv[2][1] - uv[0][1]];
    let c0 = [du1[0] / l1, du1[1] / l1];
    let c1 = [(du2[0] - q2x * c0[0]) / q2y, (du2[1] - q2x * c0[1]) / q2y];
    Some(([[c0[0], c1[0]], [c0[1], c1[1]]], 0.5 * twice_area))
}

/// Signed singular values `(σ1, σ2)` of a 2×2 matrix with `σ1 ≥ |σ2|` and
/// `σ1 σ2 = det J`, so `σ2 < 0` exactly when the triangle is flipped.
///
/// Closed form: with `E = (a+d)/2, F = (a−d)/2, G = (c+b)/2, H = (c−b)/2`,
/// `σ1 = √(E²+H²) + √(F²+G²)` and `σ2 = det J / σ1` (no cancellation).
#[inline]
pub fn signed_singular_values(j: [[f64; 2]; 2]) -> (f64, f64) {
    let (a, b, c, d) = (j[0][0], j[0][1], j[1][0], j[1][1]);
    let e = 0.5 * (a + d);
    let f = 0.5 * (a - d);
    let g = 0.5 * (c + b);
    let h = 0.5 * (c - b);
    let s1 = e.hypot(h) + f.hypot(g);
    let det = a * d - b * c;
    let s2 = if s1 > 0.0 { det / s1 } else { 0.0 };
    (s1, s2)
}

// One copy each: the signed UV area lives with the flip count in `param`, the 3-vector
// helpers in `crate::vec3`; re-exported here for the measure and render code.
pub use crate::param::signed_uv_area;
pub(crate) use crate::vec3::{cross3, dot3, norm3, sub3};

#[cfg(test)]
mod tests {
    use super::*;

    fn matmul(a: [[f64; 2]; 2], b: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
        let mut r = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                r[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j];
            }
        }
        r
    }

    #[test]
    fn singular_values_match_eigenvalues_of_j_jt() {
        // Independent check: σ1², σ2² are the eigenvalues of J Jᵀ (trace/determinant form).
        let cases = [
            [[1.0, 0.0], [0.0, 1.0]],
            [[2.0, 0.3], [-0.7, 0.5]],
            [[0.0, -3.0], [1.0, 0.0]],
            [[1.0, 2.0], [2.0, 4.0]],
            [[-1.5, 0.2], [0.1, 0.9]],
        ];
        for j in cases {
            let (s1, s2) = signed_singular_values(j);
            let jt = [[j[0][0], j[1][0]], [j[0][1], j[1][1]]];
            let c = matmul(j, jt);
            let tr = c[0][0] + c[1][1];
            let det = c[0][0] * c[1][1] - c[0][1] * c[1][0];
            let disc = (0.25 * tr * tr - det).max(0.0).sqrt();
            let (big, small) = (0.5 * tr + disc, 0.5 * tr - disc);
            assert!((s1 * s1 - big).abs() < 1e-12 * big.max(1.0), "{j:?}");
            assert!((s2 * s2 - small).abs() < 1e-12 * big.max(1.0), "{j:?}");
            let dj = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            assert!((s1 * s2 - dj).abs() < 1e-12 * big.max(1.0));
            assert!(s1 >= s2.abs());
        }
    }

    #[test]
    fn jacobian_reproduces_uv_edges_of_a_tilted_triangle() {
        let p = [[0.3, -1.0, 2.0], [1.3, 0.5, 2.2], [0.1, 0.4, 3.0]];
        let uv = [[0.0, 0.0], [0.7, 0.2], [-0.1, 0.9]];
        let (j, area) = triangle_jacobian(p, uv).unwrap();
        // Build the same frame independently and map the 3D edges through J.
        let e1 = sub3(p[1], p[0]);
        let e2 = sub3(p[2], p[0]);
        let n = cross3(e1, e2);
        let x = e1.map(|c| c / norm3(e1));
        let nn = n.map(|c| c / norm3(n));
        let y = cross3(nn, x);
        for (e, k) in [(e1, 1), (e2, 2)] {
            let loc = [dot3(e, x), dot3(e, y)];
            let mapped = [
                j[0][0] * loc[0] + j[0][1] * loc[1],
                j[1][0] * loc[0] + j[1][1] * loc[1],
            ];
            let want = [uv[k][0] - uv[0][0], uv[k][1] - uv[0][1]];
            assert!((mapped[0] - want[0]).abs() < 1e-12 && (mapped[1] - want[1]).abs() < 1e-12);
        }
        assert!((area - 0.5 * norm3(n)).abs() < 1e-14);
        // det J is the ratio of signed UV area to 3D area.
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        assert!((det - signed_uv_area(uv) / area).abs() < 1e-12);
    }

    #[test]
    fn degenerate_3d_triangle_has_no_jacobian() {
        let p = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]];
        assert!(triangle_jacobian(p, [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).is_none());
    }
}
