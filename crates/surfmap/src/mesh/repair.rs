//! Opt-in repairs. Each returns a new mesh and says what it changed; nothing here
//! runs unless the caller asks for it (the CLI prints every repair it applies).

use super::{Topology, TriMesh, Uvs};
use std::collections::HashMap;

/// Keeps the vertices where `keep` is true, renumbering faces; faces that use a
/// dropped vertex are dropped. Per-vertex UVs follow their vertex.
fn retain_vertices(mesh: &TriMesh, keep: &[bool]) -> TriMesh {
    let mut new_id = vec![u32::MAX; mesh.positions.len()];
    let mut positions = Vec::new();
    for (v, p) in mesh.positions.iter().enumerate() {
        if keep[v] {
            new_id[v] = positions.len() as u32;
            positions.push(*p);
        }
    }
    let kept_faces: Vec<usize> = (0..mesh.triangles.len())
        .filter(|&t| mesh.triangles[t].iter().all(|&v| keep[v as usize]))
        .collect();
    let triangles = kept_faces
        .iter()
        .map(|&t| mesh.triangles[t].map(|v| new_id[v as usize]))
        .collect();
    let uvs = mesh.uvs.as_ref().map(|uv| match uv {
        Uvs::PerVertex(uv) => {
            Uvs::PerVertex((0..uv.len()).filter(|&v| keep[v]).map(|v| uv[v]).collect())
        }
        Uvs::PerCorner { coords, indices } => Uvs::PerCorner {
            coords: coords.clone(),
            indices: kept_faces.iter().map(|&t| indices[t]).collect(),
        },
    });
    TriMesh {
        positions,
        triangles,
        uvs,
    }
}

/// Keeps the faces where `keep` is true (UV corner indices follow their face).
fn retain_faces(mesh: &TriMesh, keep: impl Fn(usize) -> bool) -> TriMesh {
    let kept: Vec<usize> = (0..mesh.triangles.len()).filter(|&t| keep(t)).collect();
    TriMesh {
        positions: mesh.positions.clone(),
        triangles: kept.iter().map(|&t| mesh.triangles[t]).collect(),
        uvs: mesh.uvs.as_ref().map(|uv| match uv {
            Uvs::PerVertex(_) => uv.clone(),
            Uvs::PerCorner { coords, indices } => Uvs::PerCorner {
                coords: coords.clone(),
                indices: kept.iter().map(|&t| indices[t]).collect(),
            },
        }),
    }
}

/// Removes vertices used by no face. Returns the mesh and how many were removed.
pub fn drop_unreferenced(mesh: &TriMesh) -> (TriMesh, usize) {
    let mut used = vec![false; mesh.positions.len()];
    for tri in &mesh.triangles {
        for &v in tri {
            used[v as usize] = true;
        }
    }
    let removed = used.iter().filter(|&&u| !u).count();
    (retain_vertices(mesh, &used), removed)
}

/// Removes faces with a repeated vertex or zero area (see
/// [`super::validate::zero_area_faces`]). Returns the mesh and how many were removed.
pub fn drop_degenerate(mesh: &TriMesh) -> (TriMesh, usize) {
    let mut bad = vec![false; mesh.triangles.len()];
    for t in super::validate::repeated_index_faces(mesh)
        .into_iter()
        .chain(super::validate::zero_area_faces(mesh))
    {
        bad[t as usize] = true;
    }
    let removed = bad.iter().filter(|&&b| b).count();
    (retain_faces(mesh, |t| !bad[t]), removed)
}

/// Merges vertices closer than `tolerance` (Euclidean) into the first of them, then
/// removes the merged-away vertices and faces that became degenerate. Uses a hash
/// grid of cell size `tolerance`, so the cost is linear. Returns the mesh and how
/// many vertices were merged away.
pub fn weld(mesh: &TriMesh, tolerance: f64) -> (TriMesh, usize) {
    let tol = tolerance.max(0.0);
    let n = mesh.positions.len();
    let mut target: Vec<u32> = (0..n as u32).collect();
    let cell = |p: &[f64; 3]| -> [i64; 3] {
        if tol > 0.0 {
            p.map(|x| (x / tol).floor() as i64)
        } else {
            p.map(|x| x.to_bits() as i64)
        }
    };
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::with_capacity(n);
    let mut merged = 0;
    for (v, &p) in mesh.positions.iter().enumerate() {
        if p.iter().any(|x| !x.is_finite()) {
            continue;
        }
        let c = cell(&p);
        let mut found = None;
        let range: &[i64] = if tol > 0.0 { &[-1, 0, 1] } else { &[0] };
        'search: for &dx in range {
            for &dy in range {
                for &dz in range {
                    if let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                        for &w in list {
                            let q = mesh.positions[w as usize];
                            let d2: f64 = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum();
                            if d2 <= tol * tol {
                                found = Some(w);
                                break 'search;
                            }
                        }
                    }
                }
            }
        }
        match found {
            Some(w) => {
                target[v] = w;
                merged += 1;
            }
            None => grid.entry(c).or_default().push(v as u32),
        }
    }
    let welded = TriMesh {
        positions: mesh.positions.clone(),
        triangles: mesh
            .triangles
            .iter()
            .map(|t| t.map(|v| target[v as usize]))
            .collect(),
        uvs: match &mesh.uvs {
            // Merged vertices share one UV; keep per-corner UVs as they were.
            Some(Uvs::PerVertex(uv)) => Some(Uvs::PerCorner {
                coords: uv.clone(),
                indices: mesh.triangles.clone(),
            }),
            other => other.clone(),
        },
    };
    let (welded, _) = drop_degenerate_indices(&welded);
    let (welded, _) = drop_unreferenced(&welded);
    (welded, merged)
}

fn drop_degenerate_indices(mesh: &TriMesh) -> (TriMesh, usize) {
    let bad: Vec<bool> = mesh
        .triangles
        .iter()
        .map(|&[a, b, c]| a == b || b == c || a == c)
        .collect();
    let removed = bad.iter().filter(|&&b| b).count();
    (retain_faces(mesh, |t| !bad[t]), removed)
}

/// Flips faces so that every orientable component is consistently oriented, flipping
/// the smaller side of each component. Returns the mesh and how many faces were
/// flipped, or `None` when some component is not orientable.
pub fn reorient(mesh: &TriMesh) -> Option<(TriMesh, usize)> {
    let topo = Topology::new(mesh);
    if !topo.orientable {
        return None;
    }
    let mut out = mesh.clone();
    for &t in &topo.faces_to_flip_list {
        out.triangles[t as usize].swap(1, 2);
        if let Some(Uvs::PerCorner { indices, .. }) = &mut out.uvs {
            indices[t as usize].swap(1, 2);
        }
    }
    Some((out, topo.faces_to_flip_list.len()))
}

/// Which component to keep.
#[derive(Clone, Copy, Debug)]
pub enum ComponentChoice {
    /// The component with the most faces.
    Largest,
    /// Component number `n` as numbered by [`Topology::face_component`].
    Index(usize),
}

/// Keeps one connected component (and only the vertices it uses). Returns the mesh
/// and how many faces were removed, or `None` when the index does not exist.
pub fn keep_component(mesh: &TriMesh, choice: ComponentChoice) -> Option<(TriMesh, usize)> {
    let topo = Topology::new(mesh);
    let mut sizes = vec![0usize; topo.num_components];
    for &c in &topo.face_component {
        sizes[c as usize] += 1;
    }
    let chosen = match choice {
        ComponentChoice::Largest => {
            (0..sizes.len()).max_by_key(|&c| (sizes[c], std::cmp::Reverse(c)))?
        }
        ComponentChoice::Index(i) if i < sizes.len() => i,
        ComponentChoice::Index(_) => return None,
    };
    let kept = retain_faces(mesh, |t| topo.face_component[t] as usize == chosen);
    let removed = mesh.triangles.len() - kept.triangles.len();
    let (kept, _) = drop_unreferenced(&kept);
    Some((kept, removed))
}

/// Fills every boundary loop but the longest with a fan around a new vertex at the
/// loop's centroid, so a face scan with open eyes and mouth becomes a disc. Returns the
/// mesh (original vertices and faces first, in their order; the fill after them) and
/// the number of holes filled. Loops through non-manifold vertices are filled as
/// walked. UVs are dropped.
pub fn fill_holes(mesh: &TriMesh) -> (TriMesh, usize) {
    let topo = Topology::new(mesh);
    let mut loops: Vec<&[u32]> = topo
        .boundary_loops
        .iter()
        .map(|l| l.vertices.as_slice())
        .collect();
    if loops.len() <= 1 {
        return (
            TriMesh::new(mesh.positions.clone(), mesh.triangles.clone()),
            0,
        );
    }
    loops.sort_by_key(|l| std::cmp::Reverse(l.len()));
    let mut out = TriMesh::new(mesh.positions.clone(), mesh.triangles.clone());
    for hole in &loops[1..] {
        let n = hole.len() as f64;
        let mut c = [0.0; 3];
        for &v in *hole {
            for (ck, pk) in c.iter_mut().zip(mesh.positions[v as usize]) {
                *ck += pk / n;
            }
        }
        let centre = out.positions.len() as u32;
        out.positions.push(c);
        // The loop runs with the surface on its left; the fill lies on its right, so
        // its triangles traverse each boundary edge backwards.
        for k in 0..hole.len() {
            let (a, b) = (hole[k], hole[(k + 1) % hole.len()]);
            out.triangles.push([b, a, centre]);
        }
    }
    (out, loops.len() - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::mesh::generate::unit_square as square;

    #[test]
    fn weld_closes_a_crack() {
        // Two triangles that share an edge geometrically but not by index.
        let m = TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 0.0, 1e-9],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            vec![[0, 1, 2], [3, 4, 5]],
        );
        assert_eq!(Topology::new(&m).num_components, 2);
        let (w, merged) = weld(&m, 1e-6);
        assert_eq!(merged, 2);
        assert_eq!(w.positions.len(), 4);
        let t = Topology::new(&w);
        assert!(t.is_disc());
        // Exact welding leaves the 1e-9 offset vertex alone.
        let (w0, merged0) = weld(&m, 0.0);
        assert_eq!(merged0, 1);
        assert_eq!(w0.positions.len(), 5);
    }

    #[test]
    fn reorient_flips_the_minority() {
        let mut m = square();
        m.triangles[1] = [0, 3, 2];
        let (r, flipped) = reorient(&m).unwrap();
        assert_eq!(flipped, 1);
        let t = Topology::new(&r);
        assert!(t.inconsistent_edges.is_empty());
        assert_eq!(r.triangles[0], [0, 1, 2]);
    }

    #[test]
    fn keep_largest_and_drop_unreferenced() {
        let mut m = square();
        m.positions.extend([
            [5.0, 0.0, 0.0],
            [6.0, 0.0, 0.0],
            [5.0, 1.0, 0.0],
            [9.0, 9.0, 9.0],
        ]);
        m.triangles.push([4, 5, 6]);
        let (k, removed) = keep_component(&m, ComponentChoice::Largest).unwrap();
        assert_eq!(removed, 1);
        assert_eq!(k.positions.len(), 4);
        assert!(Topology::new(&k).is_disc());
        assert!(keep_component(&m, ComponentChoice::Index(7)).is_none());
        let (d, n) = drop_unreferenced(&m);
        assert_eq!(n, 1);
        assert_eq!(d.positions.len(), 7);
    }

    #[test]
    fn fill_holes_turns_an_annulus_into_a_disc() {
        // A square with a square hole: 8 vertices, 8 triangles, 2 boundary loops.
        let p = |x: f64, y: f64| [x, y, 0.0];
        let m = TriMesh::new(
            vec![
                p(0., 0.),
                p(3., 0.),
                p(3., 3.),
                p(0., 3.),
                p(1., 1.),
                p(2., 1.),
                p(2., 2.),
                p(1., 2.),
            ],
            vec![
                [0, 1, 5],
                [0, 5, 4],
                [1, 2, 6],
                [1, 6, 5],
                [2, 3, 7],
                [2, 7, 6],
                [3, 0, 4],
                [3, 4, 7],
            ],
        );
        let t = Topology::new(&m);
        assert_eq!(t.boundary_loops.len(), 2);
        let (f, n) = fill_holes(&m);
        assert_eq!(n, 1);
        let t = Topology::new(&f);
        assert!(t.is_disc(), "filled mesh is a disc");
        assert!(
            t.inconsistent_edges.is_empty(),
            "fill is oriented like the surface"
        );
        assert_eq!(f.positions[8], [1.5, 1.5, 0.0]);
        assert!((f.area() - 9.0).abs() < 1e-12);
        assert_eq!(&f.triangles[..8], &m.triangles[..]);
    }

    #[test]
    fn drop_degenerate_removes_repeated_and_flat() {
        let mut m = square();
        m.triangles.push([1, 1, 2]);
        let (d, n) = drop_degenerate(&m);
        assert_eq!(n, 1);
        assert_eq!(d.triangles.len(), 2);
    }
}
