//! Triangle meshes: positions and triangles (connectivity kept apart from derived
//! topology), file input/output, validation and opt-in repairs; points on a mesh
//! ([`SurfacePoint`]) and their location in a flattening ([`PointLocator`]).

pub mod decimate;
pub mod generate;
pub mod io;
pub mod locate;
pub mod repair;
pub mod subdivide;
pub mod surface_point;
pub mod topology;
pub mod validate;

pub use locate::PointLocator;
pub use surface_point::SurfacePoint;
pub use topology::{BoundaryLoop, Topology};

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
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
    }

    /// Total 3D surface area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| self.triangle_area(t))
            .sum()
    }

    /// Axis-aligned bounding box `(min, max)` of the finite positions; `None` when there are none.
    pub fn bounding_box(&self) -> Option<([f64; 3], [f64; 3])> {
        let mut it = self
            .positions
            .iter()
            .filter(|p| p.iter().all(|x| x.is_finite()));
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

    /// The first triangle `(t, corner)` whose vertex index is out of range, if any.
    pub fn first_invalid_index(&self) -> Option<(usize, usize)> {
        let n = self.positions.len();
        self.triangles
            .iter()
            .enumerate()
            .find_map(|(t, tri)| tri.iter().position(|&v| v as usize >= n).map(|k| (t, k)))
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
