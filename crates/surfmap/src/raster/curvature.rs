//! Signed mean curvature per vertex (thesis §3.2.3; Meyer, Desbrun, Schröder, Barr 2003).
//!
//! Convention: `H = (κ1 + κ2) / 2`, positive where the surface bends away from its normal
//! (a sphere of radius `R` with outward normals has `H = +1/R`; a plane has `H = 0`).
//! Units: 1 / (the length unit of the positions passed in).
//!
//! With the cotangent Laplacian `(L x)_i = ½ Σ_j (cot α_ij + cot β_ij)(x_j − x_i)`
//! (≈ `A_i Δ_S x = −2 A_i H n`) and the mixed Voronoi area `A_i`, the mean-curvature
//! normal is `H n = −(L x)_i / (2 A_i)`; `|H| = |(L x)_i| / (2 A_i)`, and the sign is that of
//! `(H n) · N_i`, with `N_i` the area-weighted sum of the counter-clockwise triangle normals
//! around vertex `i`.
//!
//! The one-ring formula is not valid on the boundary (half the ring is missing); boundary
//! vertices take the mean of `H` over their interior neighbours (repeated outward for
//! boundary vertices with no interior neighbour).

use super::boundary::boundary_vertices;
use crate::vec3::{cross3, dot3, sub3};

/// Signed mean curvature `H` of every vertex (`0` for unused vertices).
pub fn vertex_mean_curvature(x: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<f64> {
    let nv = x.len();
    let mut lap = vec![[0.0f64; 3]; nv];
    let mut area = vec![0.0f64; nv];
    let mut normal = vec![[0.0f64; 3]; nv];
    for tri in triangles {
        let v = tri.map(|i| i as usize);
        let p = v.map(|i| x[i]);
        let n = cross3(sub3(p[1], p[0]), sub3(p[2], p[0]));
        let twice_area = dot3(n, n).sqrt();
        if twice_area <= 0.0 || !twice_area.is_finite() {
            continue;
        }
        // Corner k is opposite the edge (k+1, k+2).
        let mut cot = [0.0; 3];
        let mut len2 = [0.0; 3]; // squared length of the edge opposite corner k
        for k in 0..3 {
            let (a, b) = (sub3(p[(k + 1) % 3], p[k]), sub3(p[(k + 2) % 3], p[k]));
            cot[k] = dot3(a, b) / twice_area;
            let e = sub3(p[(k + 2) % 3], p[(k + 1) % 3]);
            len2[k] = dot3(e, e);
        }
        for k in 0..3 {
            let (i, j) = (v[(k + 1) % 3], v[(k + 2) % 3]);
            let w = 0.5 * cot[k];
            for d in 0..3 {
                let e = x[j][d] - x[i][d];
                lap[i][d] += w * e;
                lap[j][d] -= w * e;
            }
        }
        // Mixed area (Meyer et al. 2003, Fig. 4).
        let tri_area = 0.5 * twice_area;
        let obtuse = (0..3).find(|&k| cot[k] < 0.0);
        for k in 0..3 {
            let a = match obtuse {
                None => {
                    // Voronoi: (|e_k,k+1|² cot(k+2) + |e_k,k+2|² cot(k+1)) / 8.
                    (len2[(k + 2) % 3] * cot[(k + 2) % 3] + len2[(k + 1) % 3] * cot[(k + 1) % 3])
                        / 8.0
                }
                Some(o) if o == k => tri_area / 2.0,
                Some(_) => tri_area / 4.0,
            };
            area[v[k]] += a;
            for d in 0..3 {
                normal[v[k]][d] += n[d];
            }
        }
    }
    let mut h: Vec<f64> = (0..nv)
        .map(|i| {
            if area[i] <= 0.0 {
                return 0.0;
            }
            let hn = lap[i].map(|c| -c / (2.0 * area[i]));
            let mag = dot3(hn, hn).sqrt();
            if dot3(hn, normal[i]) < 0.0 { -mag } else { mag }
        })
        .collect();

    // Boundary vertices: mean over already-known neighbours, sweeping inward-out.
    let on_boundary = boundary_vertices(nv, triangles);
    let mut known: Vec<bool> = (0..nv).map(|i| !on_boundary[i] && area[i] > 0.0).collect();
    let mut pending: Vec<usize> = (0..nv).filter(|&i| on_boundary[i]).collect();
    let mut sum = vec![0.0f64; nv];
    let mut cnt = vec![0u32; nv];
    while !pending.is_empty() {
        for tri in triangles {
            for k in 0..3 {
                let (i, j) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
                if !known[i] && known[j] {
                    sum[i] += h[j];
                    cnt[i] += 1;
                }
                if !known[j] && known[i] {
                    sum[j] += h[i];
                    cnt[j] += 1;
                }
            }
        }
        let before = pending.len();
        pending.retain(|&i| {
            if cnt[i] > 0 {
                h[i] = sum[i] / cnt[i] as f64;
                false
            } else {
                true
            }
        });
        for i in 0..nv {
            if cnt[i] > 0 {
                known[i] = true;
                cnt[i] = 0;
                sum[i] = 0.0;
            }
        }
        if pending.len() == before {
            for &i in &pending {
                h[i] = 0.0;
            }
            break;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::testmesh;

    #[test]
    fn plane_has_zero_curvature() {
        let (x, _, tris) = testmesh::disc(8, 1.0, |u, v| [u + 0.3 * v, v, 0.5 * u - 0.2 * v]);
        let h = vertex_mean_curvature(&x, &tris);
        assert!(h.iter().all(|v| v.abs() < 1e-10), "{h:?}");
        let (x, _, tris) = testmesh::grid(8, 1.0, |u, v| [u, 2.0 * v, u - v]);
        let h = vertex_mean_curvature(&x, &tris);
        assert!(h.iter().all(|v| v.abs() < 1e-10), "{h:?}");
    }

    #[test]
    fn sphere_cap_converges_to_one_over_r() {
        // Regular grid meshes: centrally symmetric one-rings, pointwise O(h²) convergence.
        let r = 2.0;
        let mut errs = vec![];
        for n in [8, 16, 32] {
            let (x, _, tris) = testmesh::sphere_cap(n, r, 0.9);
            let h = vertex_mean_curvature(&x, &tris);
            let err = h.iter().map(|v| (v - 1.0 / r).abs()).fold(0.0, f64::max);
            errs.push(err);
        }
        assert!(
            errs[1] < errs[0] && errs[2] < errs[1] && errs[2] < 0.01 / r,
            "{errs:?}"
        );
    }

    #[test]
    fn irregular_disc_mesh_converges_on_average() {
        // On irregular one-rings the cotangent formula is only accurate on average
        // (Hildebrandt et al. 2006): the area-weighted mean error still decreases.
        let r = 2.0;
        let mut errs = vec![];
        for n in [6, 12, 24] {
            let (x, _, tris) =
                testmesh::disc(n, 1.2, |u, v| [u, v, (r * r - u * u - v * v).sqrt()]);
            let h = vertex_mean_curvature(&x, &tris);
            errs.push(h.iter().map(|v| (v - 1.0 / r).abs()).sum::<f64>() / h.len() as f64);
        }
        assert!(errs[1] < errs[0] && errs[2] < errs[1], "{errs:?}");
    }

    #[test]
    fn sign_flips_with_orientation() {
        let (x, _, tris) = testmesh::sphere_cap(8, 1.0, 0.6);
        let flipped: Vec<[u32; 3]> = tris.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let h = vertex_mean_curvature(&x, &tris);
        let hf = vertex_mean_curvature(&x, &flipped);
        for (a, b) in h.iter().zip(&hf) {
            assert!(*a > 0.0 && (a + b).abs() < 1e-12);
        }
    }

    #[test]
    fn cylinder_has_half_the_curvature_of_its_circle() {
        // Cylinder of radius R: κ1 = 1/R around, κ2 = 0 along, H = 1/(2R).
        let r = 1.5;
        let mut errs = vec![];
        // A grid aligned with the principal directions is exact by symmetry.
        let (x, _, tris) = testmesh::cylinder_patch(8, r);
        let h = vertex_mean_curvature(&x, &tris);
        assert!(h.iter().all(|v| (v - 0.5 / r).abs() < 1e-12), "{h:?}");
        // A grid rotated by 30° against them converges.
        let (s, c) = 30f64.to_radians().sin_cos();
        for n in [8, 16, 32] {
            let (x, _, tris) = testmesh::grid(n, 0.7, |u, v| {
                let (u, v) = (c * u - s * v, s * u + c * v);
                [r * (u / r).sin(), v, r * (u / r).cos()]
            });
            let h = vertex_mean_curvature(&x, &tris);
            errs.push(h.iter().map(|v| (v - 0.5 / r).abs()).fold(0.0, f64::max));
        }
        assert!(
            errs[1] < errs[0] && errs[2] < errs[1] && errs[2] < 0.01 / r,
            "{errs:?}"
        );
    }
}
