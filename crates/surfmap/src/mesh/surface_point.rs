//! A point on a triangle mesh, given intrinsically: a triangle and barycentric
//! coordinates in it. The same value names a point of the 3D surface, of its flattening
//! and of any per-vertex field, which is what maps between surfaces, texture transfer and
//! morphs pass around.

use serde::{Deserialize, Serialize};

/// A point of triangle `triangle` with barycentric coordinates `barycentric`.
///
/// The coordinates follow the triangle's vertex order: with `triangles[t] = [i, j, k]`,
/// `barycentric = [λ0, λ1, λ2]` weights vertices `i`, `j`, `k`, and any per-vertex
/// quantity `f` takes the value `λ0·f[i] + λ1·f[j] + λ2·f[k]` at the point. For a point
/// of the triangle `λ0, λ1, λ2 ≥ 0` and `λ0 + λ1 + λ2 = 1`; `λm` is the ratio of the
/// signed area of the sub-triangle opposite corner `m` (the point replacing that corner)
/// to the signed area of the whole triangle, so a corner is `[1, 0, 0]` (and its
/// rotations) and the point on an edge has a zero for the opposite corner.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SurfacePoint {
    pub triangle: u32,
    pub barycentric: [f64; 3],
}

impl SurfacePoint {
    /// The point at vertex `v`: a corner of the first of `triangles` that uses it
    /// (`None` when no triangle does).
    pub fn at_vertex(triangles: &[[u32; 3]], v: u32) -> Option<Self> {
        triangles.iter().enumerate().find_map(|(t, tri)| {
            let k = tri.iter().position(|&u| u == v)?;
            let mut barycentric = [0.0; 3];
            barycentric[k] = 1.0;
            Some(SurfacePoint {
                triangle: t as u32,
                barycentric,
            })
        })
    }

    /// The 3D position of the point: [`Self::interpolate`] of the vertex positions.
    ///
    /// Panics if `triangle` or one of its vertex indices is out of range (as slice
    /// indexing does): the point must belong to this mesh.
    #[inline]
    pub fn position(&self, positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> [f64; 3] {
        self.interpolate(positions, triangles)
    }

    /// Linear interpolation of a per-vertex attribute (positions, UVs, colours, …):
    /// `Σm λm · values[triangles[t][m]]`.
    ///
    /// Panics if `triangle` or one of its vertex indices is out of range (as slice
    /// indexing does): the point must belong to this mesh.
    #[inline]
    pub fn interpolate<const D: usize>(
        &self,
        values: &[[f64; D]],
        triangles: &[[u32; 3]],
    ) -> [f64; D] {
        let tri = triangles[self.triangle as usize];
        let mut out = [0.0; D];
        for (m, &v) in tri.iter().enumerate() {
            let value = &values[v as usize];
            for d in 0..D {
                out[d] += self.barycentric[m] * value[d];
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRIANGLES: [[u32; 3]; 2] = [[0, 1, 2], [2, 3, 0]];
    const POSITIONS: [[f64; 3]; 4] = [
        [0.0, 0.0, 1.0],
        [2.0, 0.0, 1.0],
        [2.0, 3.0, 1.0],
        [0.0, 3.0, 5.0],
    ];

    #[test]
    fn corners_give_the_vertices_in_triangle_order() {
        for t in 0..2 {
            for m in 0..3 {
                let mut barycentric = [0.0; 3];
                barycentric[m] = 1.0;
                let p = SurfacePoint {
                    triangle: t,
                    barycentric,
                };
                let v = TRIANGLES[t as usize][m] as usize;
                assert_eq!(p.position(&POSITIONS, &TRIANGLES), POSITIONS[v]);
            }
        }
    }

    #[test]
    fn interpolation_is_affine_in_any_dimension() {
        // Triangle 1 = (2, 3, 0): the weights go to vertices 2, 3 and 0 in that order.
        let p = SurfacePoint {
            triangle: 1,
            barycentric: [0.5, 0.25, 0.25],
        };
        // An affine attribute f(x, y, z) = (3x − y + 2, z) interpolates exactly.
        let f = POSITIONS.map(|[x, y, z]| [3.0 * x - y + 2.0, z]);
        let x = p.position(&POSITIONS, &TRIANGLES);
        assert_eq!(x, [1.0, 2.25, 2.0]);
        assert_eq!(
            p.interpolate(&f, &TRIANGLES),
            [3.0 * x[0] - x[1] + 2.0, x[2]]
        );
        let scalar = [[1.0], [10.0], [100.0], [1000.0]];
        assert_eq!(p.interpolate(&scalar, &TRIANGLES), [50.0 + 250.0 + 0.25]);
    }

    #[test]
    fn serializes_as_its_two_fields() {
        let p = SurfacePoint {
            triangle: 7,
            barycentric: [0.5, 0.25, 0.25],
        };
        let json = serde_json::to_string(&p).unwrap();
        assert_eq!(json, r#"{"triangle":7,"barycentric":[0.5,0.25,0.25]}"#);
        assert_eq!(serde_json::from_str::<SurfacePoint>(&json).unwrap(), p);
    }
}
