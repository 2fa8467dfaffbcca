//! Closest points: the nearest vertices of a point set (a k-d tree, `kiddo`) and the
//! closest point of a triangle mesh's surface, with the vertex → triangle incidence both
//! need. Used by the matcher (rigid alignment in space, rim completion, pinning) and by
//! anything else that projects points onto a surface.

use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};

use super::{SurfacePoint, TriMesh};

/// Closest points of a point set, by k-d tree.
pub struct ClosestPoints {
    tree: ImmutableKdTree<f64, 3>,
}

impl ClosestPoints {
    pub fn new(points: &[[f64; 3]]) -> Self {
        Self {
            tree: ImmutableKdTree::new_from_slice(points),
        }
    }

    /// Index of and squared distance to the closest point.
    #[inline]
    pub fn closest(&self, p: &[f64; 3]) -> (usize, f64) {
        let nn = self.tree.nearest_one::<SquaredEuclidean>(p);
        (nn.item as usize, nn.distance)
    }

    /// Indices of the `k` closest points, closest first.
    pub fn closest_n(&self, p: &[f64; 3], k: usize) -> impl Iterator<Item = usize> {
        let k = std::num::NonZeroUsize::new(k.max(1)).expect("k ≥ 1");
        self.tree
            .nearest_n::<SquaredEuclidean>(p, k)
            .into_iter()
            .map(|n| n.item as usize)
    }
}

/// The closest point of a triangle `(a, b, c)` to `p`, as barycentric coordinates
/// (Ericson, *Real-Time Collision Detection*, §5.1.5: Voronoi regions of the vertices,
/// then of the edges, else the face).
pub fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> [f64; 3] {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    [1.0 - v - w, v, w]
}

/// Compressed rows: the items `(row, value)` grouped by row, as `(start, list)` with row
/// `r`'s values in `list[start[r]..start[r + 1]]` (in the order given).
pub(crate) fn compressed_rows(
    rows: usize,
    items: impl Iterator<Item = (u32, u32)> + Clone,
) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; rows + 1];
    for (r, _) in items.clone() {
        start[r as usize + 1] += 1;
    }
    for r in 0..rows {
        start[r + 1] += start[r];
    }
    let mut fill = start.clone();
    let mut list = vec![0u32; start[rows] as usize];
    for (r, value) in items {
        list[fill[r as usize] as usize] = value;
        fill[r as usize] += 1;
    }
    (start, list)
}

/// Triangles around each vertex as CSR arrays `(start, list)`: the triangles of vertex
/// `v` are `list[start[v]..start[v + 1]]`.
pub fn vertex_triangles(triangles: &[[u32; 3]], num_vertices: usize) -> (Vec<u32>, Vec<u32>) {
    compressed_rows(
        num_vertices,
        triangles
            .iter()
            .enumerate()
            .flat_map(|(t, tri)| tri.map(|v| (v, t as u32))),
    )
}

/// Closest points on a triangle mesh: the triangles around the `K` nearest vertices
/// (k-d tree) are searched — exact for the meshes we match, whose triangles are not much
/// longer than their neighbours' spacing.
pub struct SurfaceProjector<'a> {
    mesh: &'a TriMesh,
    vertices: ClosestPoints,
    /// CSR vertex → triangles.
    start: Vec<u32>,
    triangles: Vec<u32>,
}

impl<'a> SurfaceProjector<'a> {
    const K: usize = 6;

    pub fn new(mesh: &'a TriMesh) -> Self {
        let (start, triangles) = vertex_triangles(&mesh.triangles, mesh.positions.len());
        Self {
            mesh,
            vertices: ClosestPoints::new(&mesh.positions),
            start,
            triangles,
        }
    }

    /// The closest point of the surface to `p` and its distance.
    pub fn project(&self, p: [f64; 3]) -> Option<(SurfacePoint, f64)> {
        let near = self.vertices.closest_n(&p, Self::K);
        self.closest_among(
            DVec3::from_array(p),
            near.into_iter()
                .flat_map(|v| &self.triangles[self.start[v] as usize..self.start[v + 1] as usize])
                .copied(),
        )
    }

    /// The closest point to `p` among the triangles within `rings` rings (triangles
    /// sharing a vertex) of the `seeds` triangles, and its distance: a projection that
    /// cannot jump across a narrow gap of the surface (the two lips of a closed mouth,
    /// the sheets of an ear) to a part not connected to the seeds nearby.
    pub fn project_near(
        &self,
        p: [f64; 3],
        seeds: &[u32],
        rings: usize,
    ) -> Option<(SurfacePoint, f64)> {
        let mut set: Vec<u32> = seeds.to_vec();
        set.sort_unstable();
        set.dedup();
        let mut frontier = set.clone();
        for _ in 0..rings {
            let mut next: Vec<u32> = frontier
                .iter()
                .flat_map(|&t| self.mesh.triangles[t as usize])
                .flat_map(|v| {
                    &self.triangles
                        [self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
                })
                .copied()
                .filter(|t| set.binary_search(t).is_err())
                .collect();
            next.sort_unstable();
            next.dedup();
            if next.is_empty() {
                break;
            }
            set.extend_from_slice(&next);
            set.sort_unstable();
            frontier = next;
        }
        self.closest_among(DVec3::from_array(p), set.into_iter())
    }

    fn closest_among(
        &self,
        p: DVec3,
        triangles: impl Iterator<Item = u32>,
    ) -> Option<(SurfacePoint, f64)> {
        let mut best: Option<(SurfacePoint, f64)> = None;
        for t in triangles {
            let [a, b, c] = self.mesh.triangles[t as usize]
                .map(|i| DVec3::from_array(self.mesh.positions[i as usize]));
            let l = closest_point_on_triangle(p, a, b, c);
            let q = a * l[0] + b * l[1] + c * l[2];
            let d = q.distance(p);
            if best.is_none_or(|(_, bd)| d < bd) {
                best = Some((
                    SurfacePoint {
                        triangle: t,
                        barycentric: l,
                    },
                    d,
                ));
            }
        }
        best
    }
}
