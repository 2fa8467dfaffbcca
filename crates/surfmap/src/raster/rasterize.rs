//! Scan conversion of a flattened triangulation onto the grid (thesis §3.2.3): for every
//! grid node, the triangle that contains it and its barycentric coordinates, so that any
//! per-vertex or per-triangle surface quantity can be sampled at the node.
//!
//! A node belongs to triangle `t` when its barycentric coordinates in the domain triangle
//! are all `≥ −1e-12`; a node on an edge shared by two triangles takes the one with the
//! lower index, which makes the result independent of the thread count. Rows are
//! processed in parallel bands; each band visits only the triangles whose bounding box
//! meets it, so the cost is `O(N² + #triangles)`.

use rayon::prelude::*;

use super::RasterError;

/// Triangle id stored for nodes outside the flattened surface.
pub const OUTSIDE: u32 = u32::MAX;

/// Per-node triangle id and barycentric coordinates on an `size × size` grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Rasterization {
    pub size: usize,
    /// Triangle containing node `i · size + j`, or [`OUTSIDE`].
    pub triangle: Vec<u32>,
    /// Barycentric coordinates of the node w.r.t. the triangle's corners (zero outside).
    pub bary: Vec<[f32; 3]>,
}

const BAND_ROWS: usize = 8;

impl Rasterization {
    /// Rasterizes triangles given by their domain coordinates `xi` (one per vertex, in
    /// ω = \[0,1\]²). Degenerate or flipped domain triangles are an error: the input must be
    /// a flip-free flattening.
    pub fn new(xi: &[[f64; 2]], triangles: &[[u32; 3]], size: usize) -> Result<Self, RasterError> {
        super::domain::grid_level(size)?;
        let n = size;
        let nodes_per_unit = (n - 1) as f64;
        for (t, tri) in triangles.iter().enumerate() {
            for &v in tri {
                if v as usize >= xi.len() {
                    return Err(RasterError::BadVertexIndex {
                        triangle: t,
                        vertex: v as usize,
                        num_vertices: xi.len(),
                    });
                }
            }
            let [a, b, c] = tri.map(|v| xi[v as usize]);
            let area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            if area2.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return Err(RasterError::FlippedTriangle {
                    triangle: t,
                    signed_area: 0.5 * area2,
                });
            }
        }
        // Row range [r0, r1] of every triangle, and the bands it meets (CSR).
        let num_bands = n.div_ceil(BAND_ROWS);
        let row_range = |tri: &[u32; 3]| -> Option<(usize, usize)> {
            let ys = tri.map(|v| xi[v as usize][1] * nodes_per_unit);
            let lo = ys[0].min(ys[1]).min(ys[2]).ceil().max(0.0);
            let hi = ys[0].max(ys[1]).max(ys[2]).floor().min((n - 1) as f64);
            (lo <= hi).then_some((lo as usize, hi as usize))
        };
        let mut band_start = vec![0u32; num_bands + 1];
        for tri in triangles {
            if let Some((r0, r1)) = row_range(tri) {
                for b in r0 / BAND_ROWS..=r1 / BAND_ROWS {
                    band_start[b + 1] += 1;
                }
            }
        }
        for b in 0..num_bands {
            band_start[b + 1] += band_start[b];
        }
        let mut fill = band_start.clone();
        let mut band_tris = vec![0u32; band_start[num_bands] as usize];
        for (t, tri) in triangles.iter().enumerate() {
            if let Some((r0, r1)) = row_range(tri) {
                for b in r0 / BAND_ROWS..=r1 / BAND_ROWS {
                    band_tris[fill[b] as usize] = t as u32;
                    fill[b] += 1;
                }
            }
        }

        let mut triangle = vec![OUTSIDE; n * n];
        let mut bary = vec![[0.0f32; 3]; n * n];
        triangle
            .par_chunks_mut(BAND_ROWS * n)
            .zip(bary.par_chunks_mut(BAND_ROWS * n))
            .enumerate()
            .for_each(|(band, (tri_out, bary_out))| {
                let row0 = band * BAND_ROWS;
                let rows = tri_out.len() / n;
                let list = &band_tris[band_start[band] as usize..band_start[band + 1] as usize];
                for &t in list {
                    let [a, b, c] = triangles[t as usize].map(|v| {
                        let p = xi[v as usize];
                        [p[0] * nodes_per_unit, p[1] * nodes_per_unit]
                    });
                    let area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
                    let inv = 1.0 / area2;
                    let ymin = a[1].min(b[1]).min(c[1]).ceil().max(row0 as f64) as usize;
                    let ymax = a[1].max(b[1]).max(c[1]).floor();
                    if ymax < row0 as f64 {
                        continue;
                    }
                    let ymax = (ymax as usize).min(row0 + rows - 1);
                    let xmin = a[0].min(b[0]).min(c[0]).ceil().max(0.0) as usize;
                    let xmax = a[0].max(b[0]).max(c[0]).floor().min((n - 1) as f64);
                    if xmax < 0.0 {
                        continue;
                    }
                    let xmax = xmax as usize;
                    for y in ymin..=ymax {
                        let py = y as f64;
                        for x in xmin..=xmax {
                            let k = (y - row0) * n + x;
                            if tri_out[k] != OUTSIDE {
                                continue;
                            }
                            let px = x as f64;
                            // Barycentric coordinates from the sub-triangle areas.
                            let l0 = ((b[0] - px) * (c[1] - py) - (b[1] - py) * (c[0] - px)) * inv;
                            let l1 = ((c[0] - px) * (a[1] - py) - (c[1] - py) * (a[0] - px)) * inv;
                            let l2 = 1.0 - l0 - l1;
                            const TOL: f64 = -1e-12;
                            if l0 >= TOL && l1 >= TOL && l2 >= TOL {
                                tri_out[k] = t;
                                bary_out[k] = [l0 as f32, l1 as f32, l2 as f32];
                            }
                        }
                    }
                }
            });
        Ok(Self {
            size,
            triangle,
            bary,
        })
    }

    /// Whether node `k` lies on the flattened surface.
    #[inline]
    pub fn is_inside(&self, k: usize) -> bool {
        self.triangle[k] != OUTSIDE
    }

    /// The inside mask as booleans.
    pub fn inside_mask(&self) -> Vec<bool> {
        self.triangle.iter().map(|&t| t != OUTSIDE).collect()
    }

    /// Interpolates a per-vertex field linearly across triangles; `NaN` outside.
    pub fn sample_vertex_field<const D: usize>(
        &self,
        triangles: &[[u32; 3]],
        values: &[[f64; D]],
    ) -> Vec<[f64; D]> {
        self.triangle
            .par_iter()
            .zip(self.bary.par_iter())
            .map(|(&t, b)| {
                if t == OUTSIDE {
                    return [f64::NAN; D];
                }
                let [i0, i1, i2] = triangles[t as usize].map(|v| v as usize);
                let (b0, b1, b2) = (b[0] as f64, b[1] as f64, b[2] as f64);
                std::array::from_fn(|d| {
                    b0 * values[i0][d] + b1 * values[i1][d] + b2 * values[i2][d]
                })
            })
            .collect()
    }

    /// Samples a per-triangle (piecewise constant) field; `NaN` outside.
    pub fn sample_triangle_field<const D: usize>(&self, values: &[[f64; D]]) -> Vec<[f64; D]> {
        self.triangle
            .par_iter()
            .map(|&t| {
                if t == OUTSIDE {
                    [f64::NAN; D]
                } else {
                    values[t as usize]
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::domain::node_position;

    /// Two triangles forming the square [0.2, 0.7]²; a third far triangle with a hole between.
    fn square() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        (
            vec![[0.2, 0.2], [0.7, 0.2], [0.7, 0.7], [0.2, 0.7]],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn square_mask_and_linear_fields_are_exact() {
        let (xi, tris) = square();
        let n = 65;
        let r = Rasterization::new(&xi, &tris, n).unwrap();
        // A linear function of ξ interpolates exactly.
        let f: Vec<[f64; 1]> = xi.iter().map(|p| [3.0 * p[0] - 2.0 * p[1] + 1.0]).collect();
        let s = r.sample_vertex_field(&tris, &f);
        for i in 0..n {
            for j in 0..n {
                let p = node_position(n, i, j);
                let inside_exact = (0.2 - 1e-12..=0.7 + 1e-12).contains(&p[0])
                    && (0.2 - 1e-12..=0.7 + 1e-12).contains(&p[1]);
                let k = i * n + j;
                assert_eq!(r.is_inside(k), inside_exact, "node {i},{j}");
                if inside_exact {
                    let exact = 3.0 * p[0] - 2.0 * p[1] + 1.0;
                    assert!((s[k][0] - exact).abs() < 1e-6);
                    let b = r.bary[k];
                    assert!(
                        b.iter().all(|&x| x >= -1e-6) && (b.iter().sum::<f32>() - 1.0).abs() < 1e-6
                    );
                } else {
                    assert!(s[k][0].is_nan());
                }
            }
        }
        // Diagonal nodes are shared; the lower triangle id wins.
        let k = 32 * n + 32; // ξ = (0.5, 0.5) is on the diagonal
        assert_eq!(r.triangle[k], 0);
    }

    #[test]
    fn covered_area_converges_to_polygon_area() {
        // A fan of 12 triangles approximating a disc of radius 0.4.
        let mut xi = vec![[0.5, 0.5]];
        let m = 12;
        for i in 0..m {
            let a = std::f64::consts::TAU * i as f64 / m as f64;
            xi.push([0.5 + 0.4 * a.cos(), 0.5 + 0.4 * a.sin()]);
        }
        let tris: Vec<[u32; 3]> = (0..m as u32)
            .map(|i| [0, 1 + i, 1 + (i + 1) % m as u32])
            .collect();
        let exact = 0.5 * m as f64 * 0.16 * (std::f64::consts::TAU / m as f64).sin();
        let mut errs = vec![];
        for n in [65, 257] {
            let r = Rasterization::new(&xi, &tris, n).unwrap();
            let count = r.triangle.iter().filter(|&&t| t != OUTSIDE).count();
            errs.push((count as f64 / ((n - 1) * (n - 1)) as f64 - exact).abs());
        }
        assert!(errs[1] < errs[0] && errs[1] < 0.01, "{errs:?}");
    }

    #[test]
    fn flipped_triangles_and_bad_indices_are_errors() {
        let (xi, _) = square();
        assert!(matches!(
            Rasterization::new(&xi, &[[0, 2, 1]], 17),
            Err(RasterError::FlippedTriangle { triangle: 0, .. })
        ));
        assert!(matches!(
            Rasterization::new(&xi, &[[0, 1, 9]], 17),
            Err(RasterError::BadVertexIndex { vertex: 9, .. })
        ));
        assert!(Rasterization::new(&xi, &[[0, 1, 2]], 16).is_err());
    }
}
