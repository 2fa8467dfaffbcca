//! Cropping a surface to a ball around a point: the face of a head scan (a ball around
//! the nose tip), so that two surfaces of different extent — a scan with hair and
//! shoulders, a template head — can be matched on the region they share.

use super::edge_graph::EdgeGraph;
use super::{Topology, TriMesh};
use crate::vec3::{norm3, sub3};

/// How distance from the centre is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CropDistance {
    /// Straight-line distance in space.
    Euclidean,
    /// Length of the shortest path along the mesh's edges (Dijkstra) from the vertex
    /// nearest the centre, plus that vertex's distance to it: follows the surface, so a
    /// ball on the face does not take in the ears behind the cheeks.
    Geodesic,
}

/// A cropped surface and where its vertices came from.
#[derive(Clone, Debug)]
pub struct Crop {
    pub mesh: TriMesh,
    /// For each vertex of the crop, its index in the input mesh.
    pub vertex_ids: Vec<u32>,
    /// The input's vertex nearest the centre (an input index).
    pub seed: u32,
}

/// Why a crop cannot be made.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CropError {
    #[error("the crop radius must be finite and positive, got {0}")]
    Radius(f64),
    #[error("the crop centre must be three finite numbers, got {0:?}")]
    Centre([f64; 3]),
    #[error("the mesh has no vertex used by a face")]
    Empty,
    #[error(
        "no face lies within {radius} of the centre (the nearest vertex, {seed}, is {distance} away); give a larger radius"
    )]
    NothingInside {
        radius: f64,
        seed: u32,
        distance: f64,
    },
}

/// Keeps the faces whose three vertices lie within `radius` of `centre` (by `distance`),
/// and of those the connected piece around the vertex nearest the centre; vertices are
/// renumbered in their input order ([`Crop::vertex_ids`] maps back). Per-vertex UVs follow
/// their vertices; per-corner UVs are dropped. Cost `O(V + F)` (Euclidean) or
/// `O((V + E) log V)` (geodesic: Dijkstra over the whole mesh).
pub fn crop_ball(
    mesh: &TriMesh,
    centre: [f64; 3],
    radius: f64,
    distance: CropDistance,
) -> Result<Crop, CropError> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(CropError::Radius(radius));
    }
    if centre.iter().any(|c| !c.is_finite()) {
        return Err(CropError::Centre(centre));
    }
    let nv = mesh.positions.len();
    let mut used = vec![false; nv];
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let to_centre = |v: usize| norm3(sub3(mesh.positions[v], centre));
    let seed = (0..nv)
        .filter(|&v| used[v] && to_centre(v).is_finite())
        .min_by(|&x, &y| to_centre(x).total_cmp(&to_centre(y)))
        .ok_or(CropError::Empty)?;
    let dist: Vec<f64> = match distance {
        CropDistance::Euclidean => (0..nv).map(to_centre).collect(),
        CropDistance::Geodesic => edge_distances(mesh, seed, to_centre(seed)),
    };
    let inside = |v: u32| dist[v as usize] <= radius;
    let kept: Vec<usize> = (0..mesh.triangles.len())
        .filter(|&t| mesh.triangles[t].iter().all(|&v| inside(v)))
        .collect();
    // The connected piece (faces sharing a vertex) around the seed.
    let ball = TriMesh::new(
        mesh.positions.clone(),
        kept.iter().map(|&t| mesh.triangles[t]).collect(),
    );
    let topo = Topology::new(&ball);
    let piece = ball
        .triangles
        .iter()
        .position(|t| t.contains(&(seed as u32)))
        .map(|t| topo.face_component[t])
        .ok_or(CropError::NothingInside {
            radius,
            seed: seed as u32,
            distance: dist[seed],
        })?;
    let faces: Vec<usize> = (0..ball.triangles.len())
        .filter(|&t| topo.face_component[t] == piece)
        .collect();
    let mut keep_vertex = vec![false; nv];
    for &t in &faces {
        for &v in &ball.triangles[t] {
            keep_vertex[v as usize] = true;
        }
    }
    let vertex_ids: Vec<u32> = (0..nv as u32)
        .filter(|&v| keep_vertex[v as usize])
        .collect();
    let mut new_id = vec![u32::MAX; nv];
    for (i, &v) in vertex_ids.iter().enumerate() {
        new_id[v as usize] = i as u32;
    }
    let mut out = TriMesh::new(
        vertex_ids
            .iter()
            .map(|&v| mesh.positions[v as usize])
            .collect(),
        faces
            .iter()
            .map(|&t| ball.triangles[t].map(|v| new_id[v as usize]))
            .collect(),
    );
    if let Some(uv) = mesh.vertex_uvs() {
        out.uvs = Some(super::Uvs::PerVertex(
            vertex_ids.iter().map(|&v| uv[v as usize]).collect(),
        ));
    }
    Ok(Crop {
        mesh: out,
        vertex_ids,
        seed: seed as u32,
    })
}

/// Shortest edge-path lengths from `seed`, plus `start` (the seed's own distance to the
/// centre).
fn edge_distances(mesh: &TriMesh, seed: usize, start: f64) -> Vec<f64> {
    let graph = EdgeGraph::new(mesh, &Topology::new(mesh));
    let (distance, _, _) =
        graph.shortest_paths(&[seed as u32], |_, _, length| length, |_| true, |_| false);
    distance.into_iter().map(|d| d + start).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::grid_disc;

    /// On a flat grid, straight-line and edge-path balls: the Euclidean crop keeps exactly
    /// the faces inside the circle; the geodesic one (edge paths are at least as long)
    /// keeps a subset of them that still contains every face within radius/√2 of the
    /// centre (an edge path on this grid is at most √2 times the straight line).
    #[test]
    fn a_ball_on_a_flat_grid() {
        let grid = grid_disc(20);
        let centre = [0.5, 0.5, 0.0];
        let radius = 0.3;
        let euclid = crop_ball(&grid, centre, radius, CropDistance::Euclidean).unwrap();
        let within = |p: [f64; 3], r: f64| norm3(sub3(p, centre)) <= r;
        let expected = grid
            .triangles
            .iter()
            .filter(|t| {
                t.iter()
                    .all(|&v| within(grid.positions[v as usize], radius))
            })
            .count();
        assert_eq!(euclid.mesh.triangles.len(), expected);
        assert!(Topology::new(&euclid.mesh).is_disc());
        // Every kept vertex maps back to the same position.
        for (i, &v) in euclid.vertex_ids.iter().enumerate() {
            assert_eq!(euclid.mesh.positions[i], grid.positions[v as usize]);
        }
        let geo = crop_ball(&grid, centre, radius, CropDistance::Geodesic).unwrap();
        assert!(geo.mesh.triangles.len() <= expected);
        let inner = grid
            .triangles
            .iter()
            .filter(|t| {
                t.iter()
                    .all(|&v| within(grid.positions[v as usize], radius / 2f64.sqrt()))
            })
            .count();
        assert!(
            geo.mesh.triangles.len() >= inner,
            "{} < {inner}",
            geo.mesh.triangles.len()
        );
        assert_eq!(euclid.seed, 10 * 21 + 10);
    }

    /// Geodesic distance follows the surface: on a grid folded into a U, a ball around a
    /// point on one arm reaches the other arm in space but not along the surface.
    #[test]
    fn a_geodesic_ball_does_not_jump_across_a_fold() {
        let mut grid = grid_disc(30);
        // Fold x ∈ [0, 1] into two parallel arms 0.1 apart joined at x = 0.5.
        for p in &mut grid.positions {
            let x = p[0];
            if x > 0.5 {
                *p = [1.0 - x, p[1], 0.1];
            }
        }
        let centre = [0.25, 0.5, 0.0];
        let euclid = crop_ball(&grid, centre, 0.15, CropDistance::Euclidean).unwrap();
        let geo = crop_ball(&grid, centre, 0.15, CropDistance::Geodesic).unwrap();
        let on_upper = |c: &Crop| c.mesh.positions.iter().any(|p| p[2] > 0.05);
        // The straight-line ball takes in faces of the other arm, but only the piece around
        // the centre is kept — the same arm; along the surface the other arm is never
        // reached.
        assert!(!on_upper(&euclid) && !on_upper(&geo));
        let far = crop_ball(&grid, [0.25, 0.5, 0.0], 0.45, CropDistance::Geodesic).unwrap();
        // 0.25 to the fold and 0.2 back along the upper arm: the upper arm is reached.
        assert!(on_upper(&far));
        assert!(Topology::new(&far.mesh).is_disc());
    }

    #[test]
    fn bad_requests_are_refused_by_name() {
        let grid = grid_disc(4);
        assert_eq!(
            crop_ball(&grid, [0.5; 3], -1.0, CropDistance::Euclidean).unwrap_err(),
            CropError::Radius(-1.0)
        );
        let err = crop_ball(&grid, [0.5, 0.5, 0.0], 0.01, CropDistance::Euclidean).unwrap_err();
        assert!(matches!(err, CropError::NothingInside { .. }), "{err:?}");
        assert!(err.to_string().contains("give a larger radius"));
        assert!(matches!(
            crop_ball(&grid, [f64::NAN, 0.0, 0.0], 1.0, CropDistance::Geodesic),
            Err(CropError::Centre(_))
        ));
    }
}
