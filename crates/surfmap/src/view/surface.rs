//! A mesh as a page holds it: positions and triangles as typed arrays, the camera it is
//! first seen from, and the edges drawn over it — texture seams and the boundary — as
//! half-edges `3·t + k` (the edge from corner `k` of triangle `t` to corner `k + 1`),
//! so that the page can draw each in 3D and, with the corner's texture coordinates, in
//! the UV layout.

use std::collections::HashMap;

use serde_json::{Value, json};

use super::page::PageData;
use crate::mesh::Uvs;
use crate::render::surface::automatic_view;

/// Adds `positions` and `triangles` to the page as arrays `NAME.positions` and
/// `NAME.triangles` and returns the mesh's description: the array names, counts and
/// the camera ([`camera`]).
pub fn add_mesh(
    page: &mut PageData,
    name: &str,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Value {
    let p = format!("{name}.positions");
    let t = format!("{name}.triangles");
    page.add_points(&p, positions);
    page.add_triangles(&t, triangles);
    json!({
        "positions": p,
        "triangles": t,
        "vertices": positions.len(),
        "triangle_count": triangles.len(),
        "camera": camera(positions, triangles),
    })
}

/// The camera a mesh is first seen from: `axes` = (right, up, towards the viewer) of
/// [`automatic_view`] (the surface's mean normal, or its principal axes), `center` and
/// `radius` of its bounding box (half the diagonal).
pub fn camera(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Value {
    let finite: Vec<[f64; 3]> = positions
        .iter()
        .copied()
        .filter(|p| p.iter().all(|x| x.is_finite()))
        .collect();
    let (center, radius) = match crate::mesh::bounding_box(&finite) {
        Some((lo, hi)) => {
            let c = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
            let r = 0.5 * (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
            (c, if r > 0.0 { r } else { 1.0 })
        }
        None => ([0.0; 3], 1.0),
    };
    json!({
        "axes": automatic_view(positions, triangles),
        "center": center,
        "radius": radius,
    })
}

/// The half-edge `3·t + k` of every directed edge, by its vertex pair.
fn half_edges(triangles: &[[u32; 3]]) -> HashMap<(u32, u32), u32> {
    let mut map = HashMap::with_capacity(3 * triangles.len());
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            map.insert((tri[k], tri[(k + 1) % 3]), (3 * t + k) as u32);
        }
    }
    map
}

/// Half-edges without a twin: the boundary of the surface.
pub fn boundary_half_edges(triangles: &[[u32; 3]]) -> Vec<u32> {
    let map = half_edges(triangles);
    let mut out: Vec<u32> = map
        .iter()
        .filter(|((a, b), _)| !map.contains_key(&(*b, *a)))
        .map(|(_, &h)| h)
        .collect();
    out.sort_unstable();
    out
}

/// Half-edges of interior edges whose texture coordinates differ on the two sides
/// (both half-edges of each seam, so that the UV layout shows both of its sides).
/// Per-vertex texture coordinates have no seam.
pub fn seam_half_edges(triangles: &[[u32; 3]], uvs: &Uvs) -> Vec<u32> {
    let Uvs::PerCorner { coords, indices } = uvs else {
        return vec![];
    };
    let uv = |h: u32| {
        let (t, k) = ((h / 3) as usize, (h % 3) as usize);
        let at = |k: usize| coords.get(indices[t][k] as usize).copied();
        (at(k), at((k + 1) % 3))
    };
    let map = half_edges(triangles);
    let mut out: Vec<u32> = map
        .iter()
        .filter_map(|((a, b), &h)| {
            let twin = *map.get(&(*b, *a))?;
            let (start, end) = uv(h);
            let (twin_start, twin_end) = uv(twin);
            (start != twin_end || end != twin_start).then_some(h)
        })
        .collect();
    out.sort_unstable();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seams_are_the_edges_whose_uvs_differ_and_boundaries_have_no_twin() {
        // Two triangles sharing the edge 0–2 (half-edges 2 in triangle 0, 3 in
        // triangle 1); the boundary is the square's four sides.
        let triangles = vec![[0, 1, 2], [0, 2, 3]];
        let mut boundary = boundary_half_edges(&triangles);
        boundary.sort_unstable();
        assert_eq!(boundary, vec![0, 1, 4, 5]);
        let same = Uvs::PerCorner {
            coords: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            indices: vec![[0, 1, 2], [0, 2, 3]],
        };
        assert!(seam_half_edges(&triangles, &same).is_empty());
        // Equal coordinates under different indices are no seam either.
        let duplicated = Uvs::PerCorner {
            coords: vec![
                [0.0, 0.0],
                [1.0, 0.0],
                [1.0, 1.0],
                [0.0, 0.0],
                [1.0, 1.0],
                [0.0, 1.0],
            ],
            indices: vec![[0, 1, 2], [3, 4, 5]],
        };
        assert!(seam_half_edges(&triangles, &duplicated).is_empty());
        let cut = Uvs::PerCorner {
            coords: vec![
                [0.0, 0.0],
                [1.0, 0.0],
                [1.0, 1.0],
                [2.0, 0.0],
                [3.0, 1.0],
                [2.0, 1.0],
            ],
            indices: vec![[0, 1, 2], [3, 4, 5]],
        };
        assert_eq!(seam_half_edges(&triangles, &cut), vec![2, 3]);
        assert!(seam_half_edges(&triangles, &Uvs::PerVertex(vec![[0.0; 2]; 4])).is_empty());
    }

    #[test]
    fn the_camera_frames_the_bounding_box() {
        let mesh = crate::mesh::generate::bumpy_disc(4, 0.2);
        let c = camera(&mesh.positions, &mesh.triangles);
        let (lo, hi) = mesh.bounding_box().unwrap();
        for k in 0..3 {
            let centre = c["center"][k].as_f64().unwrap();
            assert!((centre - 0.5 * (lo[k] + hi[k])).abs() < 1e-12);
        }
        let r = c["radius"].as_f64().unwrap();
        for p in &mesh.positions {
            let d: f64 = (0..3)
                .map(|k| (p[k] - c["center"][k].as_f64().unwrap()).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(d <= r * (1.0 + 1e-12));
        }
    }
}
