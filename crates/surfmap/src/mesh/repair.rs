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

/// Keeps the faces where `keep[t]` and drops the vertices no face uses then: the kept
/// faces stay in their order and keep their UV corners (so [`FaceOrigins`] tags
/// survive).
pub fn keep_faces(mesh: &TriMesh, keep: &[bool]) -> TriMesh {
    drop_unreferenced(&retain_faces(mesh, |t| keep[t])).0
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
/// [`super::validate::zero_area_faces`]) and faces that repeat an earlier face (the same
/// three vertices, [`super::validate::duplicate_faces`]; the first is kept). Returns the
/// mesh and how many were removed.
pub fn drop_degenerate(mesh: &TriMesh) -> (TriMesh, usize) {
    let mut bad = vec![false; mesh.triangles.len()];
    let repeats = super::validate::duplicate_faces(mesh);
    for t in super::validate::repeated_index_faces(mesh)
        .into_iter()
        .chain(super::validate::zero_area_faces(mesh))
        .chain(repeats.into_iter().map(|(repeat, _)| repeat))
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

/// What [`fix_non_manifold`] changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NonManifoldFix {
    /// Edges shared by more than two faces, cut apart into sheets.
    pub cut_edges: usize,
    /// Faces on such an edge left without a partner there (a fin's face: it is cut loose
    /// along that edge).
    pub unpaired_faces: usize,
    /// Faces removed where cutting could not separate the sheets (they stay joined around
    /// both ends of the edge, e.g. a face repeated on the same three vertices).
    pub dropped_faces: usize,
    /// Vertex copies added, one per fan of faces after the first around a vertex.
    pub split_vertices: usize,
}

/// Makes a triangle soup manifold, for the two defects scans and boolean exports carry:
///
/// 1. **Edges shared by more than two faces** (fins, internal walls, two sheets touching
///    along an edge) are cut apart into sheets: the faces on such an edge are paired
///    greedily, best pair first (`ranked_pairs`), and only paired faces stay joined
///    across it; an odd face out (a fin) is joined to nothing there.
/// 2. **Vertices whose faces form separate fans** — bow-ties, two sheets touching at a
///    point, and the ends of the cuts of step 1 — get one copy per fan after the first
///    (same position and per-vertex UV), appended after the existing vertices; fans are
///    the classes of a vertex's faces joined through edges with two faces or a pair of
///    step 1.
/// 3. Where that leaves an edge with more than two faces (the sheets are joined around
///    both of its ends, so no vertex split separates them), the best pair on it is kept
///    and the other faces are removed, and step 2 runs again.
///
/// Otherwise no face is removed, moved or re-triangulated: a fin or a sheet glued onto
/// the surface becomes a piece of its own ([`keep_component`] removes such pieces), two
/// sheets touching along an edge become two sheets with a seam. Every original vertex
/// keeps its index. Cost `O(F log F)` (a few topology passes).
pub fn fix_non_manifold(mesh: &TriMesh) -> (TriMesh, NonManifoldFix) {
    let (cut, mut fix) = cut_non_manifold(mesh);
    if Topology::new(&cut).non_manifold_edges.is_empty() {
        return (cut, fix);
    }
    let (dropped, n) = drop_non_manifold_faces(&cut);
    let (out, again) = cut_non_manifold(&dropped);
    fix.dropped_faces = n;
    fix.split_vertices += again.split_vertices;
    (out, fix)
}

/// The pairs of faces on non-manifold edge `e`, best first: a consistent orientation
/// (one face runs the edge a→b, the other b→a), then the largest cosine between their
/// oriented unit normals `n_s · n_t` (a flat continuation is 1, a fin folded back onto its
/// neighbour −1), then the larger total area.
fn ranked_pairs(mesh: &TriMesh, topo: &Topology, e: u32) -> Vec<[u32; 2]> {
    use crate::vec3::{cross3, dot3, norm3, sub3};
    let [a, b] = topo.edges[e as usize];
    let faces = topo.faces_of_edge(e as usize);
    let p = &mesh.positions;
    let unit_normal = |t: u32| -> ([f64; 3], f64) {
        let [a, b, c] = mesh.triangles[t as usize].map(|v| p[v as usize]);
        let n = cross3(sub3(b, a), sub3(c, a));
        let len = norm3(n);
        if len > 0.0 && len.is_finite() {
            (n.map(|x| x / len), len / 2.0)
        } else {
            ([0.0; 3], 0.0)
        }
    };
    // Whether face t runs the edge from a to b.
    let forward = |t: u32| {
        let tri = mesh.triangles[t as usize];
        (0..3).any(|k| tri[k] == a && tri[(k + 1) % 3] == b)
    };
    let mut ranked = Vec::new();
    for i in 0..faces.len() {
        for j in i + 1..faces.len() {
            let (s, t) = (faces[i], faces[j]);
            let consistent = forward(s) != forward(t);
            let ((ns, area_s), (nt, area_t)) = (unit_normal(s), unit_normal(t));
            // With a consistent orientation the normals of a flat continuation agree; with
            // an inconsistent one they are opposite.
            let cosine = if consistent {
                dot3(ns, nt)
            } else {
                -dot3(ns, nt)
            };
            ranked.push(((consistent, cosine, area_s + area_t), [s, t]));
        }
    }
    ranked.sort_by(|x, y| y.0.partial_cmp(&x.0).unwrap_or(std::cmp::Ordering::Equal));
    ranked.into_iter().map(|(_, pair)| pair).collect()
}

/// Steps 1 and 2 of [`fix_non_manifold`].
fn cut_non_manifold(mesh: &TriMesh) -> (TriMesh, NonManifoldFix) {
    let topo = Topology::new(mesh);
    if topo.is_manifold() {
        return (mesh.clone(), NonManifoldFix::default());
    }
    // Step 1: the pairs of faces that stay joined across each non-manifold edge.
    let mut pairs: HashMap<u32, Vec<[u32; 2]>> = HashMap::new();
    let mut unpaired_faces = 0;
    for &e in &topo.non_manifold_edges {
        let mut taken: Vec<u32> = Vec::new();
        let chosen = pairs.entry(e).or_default();
        for [s, t] in ranked_pairs(mesh, &topo, e) {
            if !taken.contains(&s) && !taken.contains(&t) {
                taken.extend([s, t]);
                chosen.push([s, t]);
            }
        }
        unpaired_faces += topo.faces_of_edge(e as usize).len() - taken.len();
    }
    // Whether faces s and t are joined across edge e.
    let joined = |e: u32, s: u32, t: u32| match pairs.get(&e) {
        None => topo.faces_of_edge(e as usize).len() == 2,
        Some(list) => list
            .iter()
            .any(|&[x, y]| (x, y) == (s, t) || (x, y) == (t, s)),
    };
    // Step 2: split every vertex whose faces form several fans. Only vertices on a cut
    // edge or pinched already can have several.
    let mut candidate = vec![false; mesh.positions.len()];
    for &v in &topo.non_manifold_vertices {
        candidate[v as usize] = true;
    }
    for &e in &topo.non_manifold_edges {
        for v in topo.edges[e as usize] {
            candidate[v as usize] = true;
        }
    }
    let mut around: HashMap<u32, Vec<u32>> = HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &v in tri {
            if candidate[v as usize] {
                around.entry(v).or_default().push(t as u32);
            }
        }
    }
    let mut order: Vec<u32> = around.keys().copied().collect();
    order.sort_unstable();
    let mut out = mesh.clone();
    let mut split_vertices = 0;
    for v in order {
        let faces = &around[&v];
        // Fan label per incident face: flood through the joined edges at v.
        let mut fan = vec![usize::MAX; faces.len()];
        let mut fans = 0;
        for seed in 0..faces.len() {
            if fan[seed] != usize::MAX {
                continue;
            }
            fan[seed] = fans;
            let mut stack = vec![seed];
            while let Some(i) = stack.pop() {
                let t = faces[i];
                let tri = mesh.triangles[t as usize];
                for k in 0..3 {
                    if tri[k] != v && tri[(k + 1) % 3] != v {
                        continue; // the edge opposite v
                    }
                    let e = topo.face_edges[t as usize][k];
                    for &u in topo.faces_of_edge(e as usize) {
                        if u == t || !joined(e, t, u) {
                            continue;
                        }
                        if let Some(j) = faces.iter().position(|&x| x == u)
                            && fan[j] == usize::MAX
                        {
                            fan[j] = fans;
                            stack.push(j);
                        }
                    }
                }
            }
            fans += 1;
        }
        // Fan 0 keeps v; fan f > 0 gets a new vertex.
        let first_new = out.positions.len() as u32;
        for _ in 1..fans {
            out.positions.push(mesh.positions[v as usize]);
            if let Some(Uvs::PerVertex(uv)) = &mut out.uvs {
                let copy = uv[v as usize];
                uv.push(copy);
            }
        }
        for (i, &t) in faces.iter().enumerate() {
            if fan[i] > 0 {
                let new_v = first_new + fan[i] as u32 - 1;
                for corner in out.triangles[t as usize].iter_mut() {
                    if *corner == v {
                        *corner = new_v;
                    }
                }
            }
        }
        split_vertices += fans - 1;
    }
    (
        out,
        NonManifoldFix {
            cut_edges: topo.non_manifold_edges.len(),
            unpaired_faces,
            dropped_faces: 0,
            split_vertices,
        },
    )
}

/// Step 3 of [`fix_non_manifold`]: on every edge with more than two faces keep the best
/// pair of [`ranked_pairs`] and remove the other faces. Returns the mesh and the faces
/// removed.
fn drop_non_manifold_faces(mesh: &TriMesh) -> (TriMesh, usize) {
    let topo = Topology::new(mesh);
    let mut dropped = vec![false; mesh.triangles.len()];
    for &e in &topo.non_manifold_edges {
        let best = ranked_pairs(mesh, &topo, e)
            .into_iter()
            .find(|&[s, t]| !dropped[s as usize] && !dropped[t as usize]);
        for &t in topo.faces_of_edge(e as usize) {
            if best.is_some_and(|pair| !pair.contains(&t)) {
                dropped[t as usize] = true;
            }
        }
    }
    let removed = dropped.iter().filter(|&&d| d).count();
    (retain_faces(mesh, |t| !dropped[t]), removed)
}

/// Fills every boundary loop but the longest with a fan around a new vertex at the
/// loop's centroid, so a face scan with open eyes and mouth becomes a disc. Returns the
/// mesh (original vertices and faces first, in their order; the fill after them) and
/// the number of holes filled. Loops through non-manifold vertices are filled as
/// walked. UVs are dropped.
pub fn fill_holes(mesh: &TriMesh) -> (TriMesh, usize) {
    let topo = Topology::new(mesh);
    let holes = hole_loops(&topo);
    let mut out = TriMesh::new(mesh.positions.clone(), mesh.triangles.clone());
    for hole in &holes {
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
    (out, holes.len())
}

/// Every boundary loop of `topo` but the longest (the outer rim), longest first (loops
/// of equal length in their order in `topo`): the holes [`fill_holes`] fills.
pub fn hole_loops(topo: &Topology) -> Vec<&[u32]> {
    let mut loops: Vec<&[u32]> = topo
        .boundary_loops
        .iter()
        .map(|l| l.vertices.as_slice())
        .collect();
    loops.sort_by_key(|l| std::cmp::Reverse(l.len()));
    loops.into_iter().skip(1).collect()
}

/// Where the faces of a repaired mesh came from in the mesh as read, so that results on
/// the repaired mesh can be given back in the input's numbering (the CLI's `match
/// --repair` writes its correspondence against the files as given).
///
/// **How it is tracked.** [`FaceOrigins::tag`] replaces the mesh's UVs by per-corner
/// tags: corner `k` of face `t` gets the UV `(t, k)`. Every repair here carries
/// per-corner UVs along with the faces it keeps — `retain_faces` filters them,
/// [`reorient`] swaps them with the corners, [`weld`], [`fix_non_manifold`] and
/// [`drop_unreferenced`] renumber vertices and leave each face's corners as they were —
/// so after any sequence of them [`FaceOrigins::read`] finds, for each face, the input
/// face and which of its corners each corner is (both exact: integers below 2⁵³ as
/// f64). A unit test runs every repair on a tagged mesh and checks the positions.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceOrigins {
    /// For each face of the repaired mesh, the face of the input.
    pub face: Vec<u32>,
    /// For each face of the repaired mesh, which corner of its input face each of its
    /// three corners is (`[0, 2, 1]` after [`reorient`] flipped it).
    pub corner: Vec<[u8; 3]>,
}

impl FaceOrigins {
    /// The origins of a mesh's faces as they are (face `t` is input face `t`).
    pub fn identity(faces: usize) -> Self {
        Self {
            face: (0..faces as u32).collect(),
            corner: vec![[0, 1, 2]; faces],
        }
    }

    /// These origins followed by `later`, the origins of a mesh made from the one these
    /// describe: each face of that mesh traced back through both to the input.
    pub fn then(&self, later: &FaceOrigins) -> Self {
        Self {
            face: later.face.iter().map(|&f| self.face[f as usize]).collect(),
            corner: later
                .face
                .iter()
                .zip(&later.corner)
                .map(|(&f, c)| c.map(|k| self.corner[f as usize][k as usize]))
                .collect(),
        }
    }

    /// `mesh` with its UVs replaced by the per-corner tags `(face, corner)`.
    pub fn tag(mesh: &TriMesh) -> TriMesh {
        let n = mesh.triangles.len();
        TriMesh {
            positions: mesh.positions.clone(),
            triangles: mesh.triangles.clone(),
            uvs: Some(Uvs::PerCorner {
                coords: (0..n)
                    .flat_map(|t| (0..3).map(move |k| [t as f64, k as f64]))
                    .collect(),
                indices: (0..n as u32)
                    .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                    .collect(),
            }),
        }
    }

    /// The origins of a mesh made by repairs from a [`FaceOrigins::tag`]ged one, or
    /// `None` when it carries no such tags (its UVs were not the tags, or were lost).
    pub fn read(repaired: &TriMesh) -> Option<Self> {
        let Some(Uvs::PerCorner { coords, indices }) = &repaired.uvs else {
            return None;
        };
        if indices.len() != repaired.triangles.len() {
            return None;
        }
        let mut face = Vec::with_capacity(indices.len());
        let mut corner = Vec::with_capacity(indices.len());
        for ids in indices {
            let tags = ids.map(|i| coords.get(i as usize).copied());
            let [Some(t0), Some(t1), Some(t2)] = tags else {
                return None;
            };
            let f = t0[0];
            let corners = [t0[1], t1[1], t2[1]];
            let valid = [t1[0], t2[0]].iter().all(|&g| g == f)
                && f >= 0.0
                && f.fract() == 0.0
                && f < u32::MAX as f64
                && corners.iter().all(|&c| c == 0.0 || c == 1.0 || c == 2.0)
                && corners[0] != corners[1]
                && corners[1] != corners[2]
                && corners[0] != corners[2];
            if !valid {
                return None;
            }
            face.push(f as u32);
            corner.push(corners.map(|c| c as u8));
        }
        Some(Self { face, corner })
    }

    /// A point of the repaired mesh as the same point of the input mesh: its input face,
    /// each barycentric coordinate on the input corner it belongs to.
    pub fn point(&self, p: super::SurfacePoint) -> super::SurfacePoint {
        let t = p.triangle as usize;
        let mut barycentric = [0.0; 3];
        for k in 0..3 {
            barycentric[self.corner[t][k] as usize] = p.barycentric[k];
        }
        super::SurfacePoint {
            triangle: self.face[t],
            barycentric,
        }
    }

    /// For each vertex of `repaired`, the vertex of `input` it stands for (`None` for a
    /// vertex no face uses).
    pub fn vertex_sources(&self, input: &TriMesh, repaired: &TriMesh) -> Vec<Option<u32>> {
        let mut sources = vec![None; repaired.positions.len()];
        for (t, tri) in repaired.triangles.iter().enumerate() {
            let source = input.triangles[self.face[t] as usize];
            for k in 0..3 {
                sources[tri[k] as usize] = Some(source[self.corner[t][k] as usize]);
            }
        }
        sources
    }

    /// For each vertex of `input`, a vertex of `repaired` that stands for it (a corner
    /// of a face kept from one of its faces; the first such, when a repair split it into
    /// copies), or `None` when the repairs dropped every face around it.
    pub fn vertex_copies(&self, input: &TriMesh, repaired: &TriMesh) -> Vec<Option<u32>> {
        let mut copies = vec![None; input.positions.len()];
        for (t, tri) in repaired.triangles.iter().enumerate() {
            let source = input.triangles[self.face[t] as usize];
            for k in 0..3 {
                let v = source[self.corner[t][k] as usize] as usize;
                if copies[v].is_none() {
                    copies[v] = Some(tri[k]);
                }
            }
        }
        copies
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Faces cut with [`keep_faces`] keep their order and UV corners, so the tags of
    /// [`FaceOrigins::tag`] survive; origins of a cut after a repair (a reorientation)
    /// compose with [`FaceOrigins::then`] into the input's faces and corners.
    #[test]
    fn kept_faces_keep_their_origins() {
        let mesh = crate::mesh::generate::grid_disc(6);
        let keep: Vec<bool> = (0..mesh.triangles.len()).map(|t| t % 3 != 1).collect();
        let kept_ids: Vec<u32> = (0..mesh.triangles.len() as u32)
            .filter(|&t| keep[t as usize])
            .collect();
        let cut = keep_faces(&FaceOrigins::tag(&mesh), &keep);
        assert_eq!(FaceOrigins::read(&cut).unwrap().face, kept_ids);
        // A repair turns face 0 over; the cut then keeps every face but 1, 4, 7, ….
        let mut flipped = mesh.clone();
        flipped.triangles[0].swap(1, 2);
        let repair = FaceOrigins {
            face: (0..mesh.triangles.len() as u32).collect(),
            corner: (0..mesh.triangles.len())
                .map(|t| if t == 0 { [0, 2, 1] } else { [0, 1, 2] })
                .collect(),
        };
        let later = FaceOrigins::read(&keep_faces(&FaceOrigins::tag(&flipped), &keep)).unwrap();
        let composed = repair.then(&later);
        assert_eq!(composed.face, kept_ids);
        assert_eq!(composed.corner[0], [0, 2, 1]);
        for (t, &f) in composed.face.iter().enumerate() {
            let input = mesh.triangles[f as usize];
            let corners = composed.corner[t].map(|k| input[k as usize]);
            assert_eq!(corners, flipped.triangles[f as usize], "face {f}");
        }
        // Vertices no kept face uses are gone; the rest keep their order.
        let used: std::collections::BTreeSet<u32> = mesh
            .triangles
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .flat_map(|(t, _)| t.iter().copied())
            .collect();
        assert_eq!(cut.positions.len(), used.len());
    }

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

    /// A fin (a triangle standing on an interior edge) and a sheet glued back onto the
    /// surface along another edge: each of the two edges has three faces; the fix cuts
    /// each fin loose (no face removed), so keeping the largest piece gives exactly the
    /// original disc back.
    #[test]
    fn fix_non_manifold_cuts_fins_loose_and_keeps_the_surface() {
        use crate::mesh::generate::grid_disc;
        let disc = grid_disc(6);
        let mut m = disc.clone();
        let n = m.positions.len() as u32;
        // Interior edges of the 7×7 grid: (8, 9) and the diagonal (16, 24).
        m.positions.push([1.5 / 6.0, 1.0 / 6.0, 0.2]); // fin standing up
        m.triangles.push([8, 9, n]);
        // Folded back almost onto the surface, the wrong way round.
        m.positions.push([2.0 / 6.0, 3.5 / 6.0, 0.01]);
        m.triangles.push([24, 16, n + 1]);
        let topo = Topology::new(&m);
        assert_eq!(topo.non_manifold_edges.len(), 2);
        let (fixed, done) = fix_non_manifold(&m);
        // Each fin keeps its face and gets its own copies of its edge's two vertices.
        assert_eq!(
            done,
            NonManifoldFix {
                cut_edges: 2,
                unpaired_faces: 2,
                dropped_faces: 0,
                split_vertices: 4
            }
        );
        assert_eq!(fixed.triangles.len(), m.triangles.len());
        let topo = Topology::new(&fixed);
        assert!(topo.is_manifold());
        assert_eq!(topo.num_components, 3);
        let (kept, dropped) = keep_component(&fixed, ComponentChoice::Largest).unwrap();
        assert_eq!(dropped, 2);
        assert_eq!(kept.triangles, disc.triangles);
        assert_eq!(kept.positions, disc.positions);
        assert!(Topology::new(&kept).is_disc());
    }

    /// Two sheets crossing along an edge (four faces on it): the natural pairs (each
    /// sheet's own two faces, flat across the edge) are kept, so the fix separates the two
    /// sheets, each whole.
    #[test]
    fn fix_non_manifold_separates_two_sheets_sharing_an_edge() {
        use crate::mesh::generate::grid_disc;
        let mut m = grid_disc(2); // 3×3 vertices in the plane z = 0; edge (4, 7) inside
        let n = m.positions.len() as u32;
        m.positions.push([0.5, 0.75, 0.3]);
        m.positions.push([0.5, 0.75, -0.3]);
        m.triangles.push([4, 7, n]);
        m.triangles.push([7, 4, n + 1]);
        let (fixed, done) = fix_non_manifold(&m);
        assert_eq!(
            done,
            NonManifoldFix {
                cut_edges: 1,
                unpaired_faces: 0,
                dropped_faces: 0,
                split_vertices: 2
            }
        );
        let topo = Topology::new(&fixed);
        assert!(topo.is_manifold() && topo.orientable);
        assert_eq!(topo.num_components, 2);
        // The vertical sheet's two faces are still joined to each other.
        let [s, t] = [8, 9].map(|f| fixed.triangles[f]);
        let shared = s.iter().filter(|v| t.contains(v)).count();
        assert_eq!(shared, 2, "{s:?} {t:?}");
        assert!(s.iter().all(|&v| v != 4 && v != 7));
    }

    /// Two discs touching at one vertex (a bow-tie): the vertex is split, each disc gets
    /// its own copy at the same place, and nothing else changes.
    #[test]
    fn fix_non_manifold_splits_a_bow_tie() {
        use crate::mesh::generate::grid_disc;
        let a = grid_disc(3);
        let na = a.positions.len() as u32;
        let mut m = a.clone();
        // The second disc, shifted so its corner 0 lands on the first's corner 15 = (1, 1).
        let b = grid_disc(3);
        m.positions
            .extend(b.positions.iter().map(|p| [p[0] + 1.0, p[1] + 1.0, p[2]]));
        let join = 15u32;
        m.triangles.extend(
            b.triangles
                .iter()
                .map(|t| t.map(|v| if v == 0 { join } else { v + na })),
        );
        let (m, _) = drop_unreferenced(&m); // b's own corner 0
        let topo = Topology::new(&m);
        assert_eq!(topo.non_manifold_vertices, vec![join]);
        let (fixed, done) = fix_non_manifold(&m);
        assert_eq!(done.split_vertices, 1);
        assert_eq!((done.cut_edges, done.unpaired_faces), (0, 0));
        assert_eq!(fixed.positions.len(), m.positions.len() + 1);
        assert_eq!(fixed.positions.last(), Some(&m.positions[join as usize]));
        let topo = Topology::new(&fixed);
        assert!(topo.is_manifold());
        assert_eq!(topo.num_components, 2);
        // Every face keeps its corners' positions.
        for (t, u) in fixed.triangles.iter().zip(&m.triangles) {
            for k in 0..3 {
                assert_eq!(fixed.positions[t[k] as usize], m.positions[u[k] as usize]);
            }
        }
        let (one, _) = keep_component(&fixed, ComponentChoice::Largest).unwrap();
        assert!(Topology::new(&one).is_disc());
    }

    /// A grid disc given every defect the repairs handle — a crack (a duplicated row of
    /// vertices), a fin on an interior edge, a face the wrong way round, a degenerate
    /// face, a loose triangle, an unused vertex — tagged, then repaired in the CLI's order
    /// (weld, degenerate, unreferenced, non-manifold, reorient, largest component,
    /// unreferenced): the origins read back put every corner of every repaired face on
    /// its input corner's position (exactly, or within the weld's tolerance), map points
    /// to the same 3D place, and give every input vertex a copy at its place except the
    /// ones whose faces all went.
    #[test]
    fn face_origins_follow_every_repair() {
        use crate::mesh::SurfacePoint;
        use crate::mesh::generate::grid_disc;
        let disc = grid_disc(6); // 7×7 vertices, row-major, spacing 1/6
        let mut m = disc.clone();
        // The crack: faces touching row 3 above the diagonal use copies of its vertices.
        let copy0 = m.positions.len() as u32;
        for i in 0..7 {
            let p = m.positions[21 + i];
            m.positions.push([p[0], p[1], p[2] + 1e-9]);
        }
        for (t, tri) in m.triangles.iter_mut().enumerate() {
            if t % 2 == 0 {
                for v in tri.iter_mut() {
                    if (21..28).contains(v) {
                        *v = copy0 + (*v - 21);
                    }
                }
            }
        }
        let fin = m.positions.len() as u32;
        m.positions.push([1.5 / 6.0, 1.0 / 6.0, 0.2]);
        m.triangles.push([8, 9, fin]);
        m.triangles[40].swap(0, 1); // the wrong way round
        m.triangles.push([3, 3, 4]); // degenerate
        let loose = m.positions.len() as u32;
        m.positions
            .extend([[5.0, 5.0, 0.0], [6.0, 5.0, 0.0], [5.0, 6.0, 0.0]]);
        m.triangles.push([loose, loose + 1, loose + 2]);
        m.positions.push([9.0, 9.0, 9.0]); // unused
        let unused = m.positions.len() - 1;

        let tagged = FaceOrigins::tag(&m);
        let (r, _) = weld(&tagged, 1e-6);
        let (r, _) = drop_degenerate(&r);
        let (r, _) = drop_unreferenced(&r);
        let (r, fix) = fix_non_manifold(&r);
        assert_eq!(fix.cut_edges, 1);
        let (r, flipped) = reorient(&r).unwrap();
        assert_eq!(flipped, 1);
        let (r, _) = keep_component(&r, ComponentChoice::Largest).unwrap();
        let (r, _) = drop_unreferenced(&r);
        assert!(Topology::new(&r).is_disc());
        assert_eq!(r.triangles.len(), disc.triangles.len());

        let origins = FaceOrigins::read(&r).expect("tags carried through");
        assert_eq!(origins.face.len(), r.triangles.len());
        let close = |x: [f64; 3], y: [f64; 3]| (0..3).all(|i| (x[i] - y[i]).abs() <= 1e-6);
        for (t, tri) in r.triangles.iter().enumerate() {
            let source = m.triangles[origins.face[t] as usize];
            for k in 0..3 {
                let input_corner = source[origins.corner[t][k] as usize];
                assert!(close(
                    r.positions[tri[k] as usize],
                    m.positions[input_corner as usize]
                ));
            }
        }
        // The flipped face came back with two corners swapped.
        let t40 = origins.face.iter().position(|&f| f == 40).unwrap();
        assert_eq!(origins.corner[t40], [0, 2, 1]);
        // A point keeps its place.
        for t in [0, t40, r.triangles.len() - 1] {
            let p = SurfacePoint {
                triangle: t as u32,
                barycentric: [0.2, 0.3, 0.5],
            };
            let q = origins.point(p);
            assert!(close(
                p.position(&r.positions, &r.triangles),
                q.position(&m.positions, &m.triangles)
            ));
        }
        let copies = origins.vertex_copies(&m, &r);
        for (v, c) in copies.iter().enumerate() {
            let dropped = v == fin as usize || v >= loose as usize;
            match c {
                Some(c) => {
                    assert!(!dropped, "vertex {v}");
                    assert!(close(r.positions[*c as usize], m.positions[v]));
                }
                None => assert!(dropped, "vertex {v} lost"),
            }
        }
        assert_eq!(copies[unused], None);
        // Each repaired vertex goes back to an input vertex at its place, and a copy goes
        // back to the vertex it is a copy of.
        let sources = origins.vertex_sources(&m, &r);
        for (v, s) in sources.iter().enumerate() {
            let s = s.expect("every repaired vertex is on a face") as usize;
            assert!(close(r.positions[v], m.positions[s]));
        }
        for (v, c) in copies.iter().enumerate() {
            if let Some(c) = c {
                let back = sources[*c as usize].unwrap() as usize;
                assert!(close(m.positions[back], m.positions[v]));
            }
        }
        // An untagged mesh has no origins.
        assert_eq!(FaceOrigins::read(&m), None);
    }

    /// A manifold mesh is returned unchanged.
    #[test]
    fn fix_non_manifold_leaves_a_manifold_mesh_alone() {
        let m = crate::mesh::generate::holed_plate(2, 4);
        let (fixed, done) = fix_non_manifold(&m);
        assert_eq!(done, NonManifoldFix::default());
        assert_eq!(fixed.triangles, m.triangles);
        assert_eq!(fixed.positions, m.positions);
    }
}
