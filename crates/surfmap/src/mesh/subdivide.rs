//! Midpoint (1 → 4) subdivision: every triangle is split at its edge midpoints. The
//! surface keeps its exact shape (each old triangle is tiled by four), so a
//! subdivided mesh is a finer discretization of the same piecewise-flat surface —
//! used for scaling benchmarks and refinement tests.

use super::TriMesh;
use std::collections::HashMap;

/// Splits every triangle into four at its edge midpoints. Vertex `i < V` keeps its
/// index; the new vertices follow. UVs are dropped.
pub fn subdivide_midpoint(mesh: &TriMesh) -> TriMesh {
    let mut positions = mesh.positions.clone();
    let mut midpoint: HashMap<(u32, u32), u32> = HashMap::with_capacity(mesh.triangles.len() * 3 / 2);
    let mut mid = |a: u32, b: u32, positions: &mut Vec<[f64; 3]>| -> u32 {
        let key = (a.min(b), a.max(b));
        *midpoint.entry(key).or_insert_with(|| {
            let (p, q) = (positions[a as usize], positions[b as usize]);
            positions.push([(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0, (p[2] + q[2]) / 2.0]);
            (positions.len() - 1) as u32
        })
    };
    let mut triangles = Vec::with_capacity(mesh.triangles.len() * 4);
    for &[a, b, c] in &mesh.triangles {
        let ab = mid(a, b, &mut positions);
        let bc = mid(b, c, &mut positions);
        let ca = mid(c, a, &mut positions);
        triangles.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    TriMesh::new(positions, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Topology;

    #[test]
    fn subdivision_keeps_area_topology_and_orientation() {
        let m = crate::mesh::generate::bumpy_disc(4, 0.3);
        let s = subdivide_midpoint(&m);
        assert_eq!(s.triangles.len(), 4 * m.triangles.len());
        assert!((s.area() - m.area()).abs() < 1e-12 * m.area());
        let (t0, t1) = (Topology::new(&m), Topology::new(&s));
        assert_eq!(t1.euler_characteristic(), t0.euler_characteristic());
        assert!(t1.is_disc() && t1.inconsistent_edges.is_empty());
        assert_eq!(t1.boundary_loops[0].vertices.len(), 2 * t0.boundary_loops[0].vertices.len());
    }
}
