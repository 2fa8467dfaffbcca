//! Triangle meshes: positions and triangles (connectivity kept apart from derived
//! topology), file input/output, validation, the validated [`Disc`], opt-in repairs and
//! decimation; points on a mesh ([`SurfacePoint`]) and their location in a flattening
//! ([`PointLocator`]).

pub mod closest;
pub mod crop;
pub mod cut;
pub mod decimate;
pub mod disc;
pub(crate) mod edge_graph;
pub mod generate;
pub mod io;
pub mod locate;
pub mod repair;
pub mod subdivide;
pub mod surface_point;
pub mod topology;
pub mod validate;

pub use disc::{Disc, NotADisc, PositionError};
pub use locate::PointLocator;
pub use surface_point::SurfacePoint;
pub use topology::{BoundaryLoop, Topology};

use crate::vec3::{cross3, norm3, sub3};

/// A triangle corner that names a vertex the mesh does not have: the one error every
/// function taking `(positions, triangles)` returns for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "triangle {triangle} uses vertex {vertex} (corner {corner}), but the mesh has only {num_vertices} vertices (numbers count from 0); the triangles do not belong to these positions"
)]
pub struct IndexError {
    pub triangle: usize,
    /// Which corner of the triangle (0, 1 or 2).
    pub corner: usize,
    pub vertex: u32,
    pub num_vertices: usize,
}

/// Axis-aligned bounding box `(min, max)` of the finite points; `None` when there are none.
pub fn bounding_box(points: &[[f64; 3]]) -> Option<([f64; 3], [f64; 3])> {
    let mut it = points.iter().filter(|p| p.iter().all(|x| x.is_finite()));
    let first = *it.next()?;
    let (mut lo, mut hi) = (first, first);
    for p in it {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    Some((lo, hi))
}

/// The first triangle corner whose vertex index is not below `num_vertices`, as an error.
pub fn check_indices(triangles: &[[u32; 3]], num_vertices: usize) -> Result<(), IndexError> {
    for (triangle, tri) in triangles.iter().enumerate() {
        if let Some(corner) = tri.iter().position(|&v| v as usize >= num_vertices) {
            return Err(IndexError {
                triangle,
                corner,
                vertex: tri[corner],
                num_vertices,
            });
        }
    }
    Ok(())
}

/// Texture coordinates attached to a mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum Uvs {
    /// One UV per vertex (`uv[i]` belongs to `positions[i]`).
    PerVertex(Vec<[f64; 2]>),
    /// UVs indexed per triangle corner, as OBJ `vt` with its own indices:
    /// corner `k` of triangle `t` uses `coords[indices[t][k]]`.
    PerCorner {
        coords: Vec<[f64; 2]>,
        indices: Vec<[u32; 3]>,
    },
}

/// A triangle mesh: f64 positions and counter-clockwise triangles (vertex indices),
/// optionally with texture coordinates.
///
/// The mesh is plain data; its topology (edges, boundary loops, components, genus)
/// is derived once with [`Topology::new`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub uvs: Option<Uvs>,
}

impl TriMesh {
    pub fn new(positions: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            positions,
            triangles,
            uvs: None,
        }
    }

    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `t`.
    #[inline]
    pub fn triangle_positions(&self, t: usize) -> [[f64; 3]; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Area of triangle `t` in 3D: `|(b − a) × (c − a)| / 2`.
    pub fn triangle_area(&self, t: usize) -> f64 {
        let [a, b, c] = self.triangle_positions(t);
        0.5 * norm3(cross3(sub3(b, a), sub3(c, a)))
    }

    /// SHA-256 (hex) of the mesh's content: every vertex position (three `f64`,
    /// little-endian) then every triangle (three `u32`), in order. The same mesh read
    /// from an OBJ, an OFF or a PLY — or passed as arrays — has the same digest; any
    /// change of a coordinate, of the numbering or of a face changes it. A match folder
    /// records its meshes' digests so that a folder is not used with other meshes.
    pub fn content_sha256(&self) -> String {
        use sha2::Digest;
        let mut h = sha2::Sha256::new();
        for p in &self.positions {
            p.iter().for_each(|c| h.update(c.to_le_bytes()));
        }
        for t in &self.triangles {
            t.iter().for_each(|v| h.update(v.to_le_bytes()));
        }
        h.finalize().iter().map(|b| format!("{b:02x}")).collect()
    }

    /// Total 3D surface area.
    pub fn area(&self) -> f64 {
        // `+ 0.0`: an empty sum of f64 is −0.0, which prints as "-0.000000".
        (0..self.triangles.len())
            .map(|t| self.triangle_area(t))
            .sum::<f64>()
            + 0.0
    }

    /// The positions divided by `s = √area`, so the surface has unit area, and `s`
    /// (the flattening works on these: energies and tolerances are then scale-free).
    pub fn unit_area_positions(&self) -> (Vec<[f64; 3]>, f64) {
        let scale = self.area().sqrt();
        let positions = self
            .positions
            .iter()
            .map(|p| p.map(|x| x / scale))
            .collect();
        (positions, scale)
    }

    /// Axis-aligned bounding box `(min, max)` of the finite positions; `None` when there are none.
    pub fn bounding_box(&self) -> Option<([f64; 3], [f64; 3])> {
        bounding_box(&self.positions)
    }

    /// Every triangle's vertex indices are below the vertex count ([`check_indices`]).
    pub fn check_indices(&self) -> Result<(), IndexError> {
        check_indices(&self.triangles, self.positions.len())
    }

    /// Every position a triangle uses is finite and no triangle repeats a vertex (a
    /// vertex no triangle uses may be anything: it gets no UV).
    pub fn finite_and_proper(&self) -> bool {
        let finite = |v: u32| self.positions[v as usize].iter().all(|x| x.is_finite());
        self.triangles
            .iter()
            .all(|&[a, b, c]| a != b && b != c && a != c && finite(a) && finite(b) && finite(c))
    }

    /// Per-vertex UVs, when the mesh carries them per vertex (or per corner with
    /// indices equal to the vertex indices).
    pub fn vertex_uvs(&self) -> Option<&[[f64; 2]]> {
        match &self.uvs {
            Some(Uvs::PerVertex(uv)) => Some(uv),
            Some(Uvs::PerCorner { coords, indices }) if indices == &self.triangles => Some(coords),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::TriMesh;

    /// Reports print the area: an empty mesh's is +0, not the −0.0 of an empty f64 sum.
    #[test]
    fn an_empty_mesh_has_area_plus_zero() {
        let area = TriMesh::new(vec![], vec![]).area();
        assert!(area == 0.0 && area.is_sign_positive(), "{area}");
        let one = TriMesh::new(
            vec![[0.0; 3], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        );
        assert_eq!(one.area(), 1.0);
    }
}
