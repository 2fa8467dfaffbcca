//! The region two surfaces share: which parts of each lie far from the other once they
//! are aligned in space, so that a whole head matched with a face crop is first cut
//! down to its face.
//!
//! Why: the matcher compares the surfaces through their flattenings (thesis §3.2.1). A
//! surface much larger than the part it shares with the other — a whole head with neck
//! against a face crop — spends most of its parameter square on the part without a
//! counterpart, and its flattening squeezes and skews the shared part there; the
//! similarity of the planes that starts the solve is then a poor guess and the solve
//! can settle on the wrong region (an ICT face crop onto the libigl head bust landed on
//! the top of the head: BENCHMARKS.md, "Whole heads against face crops"). Cut down to
//! the shared part, both flattenings spend the square on what matches.
//!
//! How: the surfaces are aligned rigidly in space (`super::rigid::align_surfaces`).
//! A vertex is *far* when its closest vertex of the other surface is more than
//! `τ = FAR · √area(smaller surface) + mean edge of the other` away. The faces with a
//! far vertex form connected pieces; a piece of at least [`MIN_PIECE`] of its
//! surface's area is cut off (small far pieces — an eyeball behind the other's eye
//! hole, a nostril — stay), and of what is left the largest connected piece is kept. A
//! surface is cropped only when that removes at least [`MIN_CROP`] of its area:
//! surfaces that overlap mostly (crops of one face on different sides, the partial
//! correspondences the solve's χ handles) are matched whole. A piece holding a vertex
//! of the user's guidance (a landmark, a feature curve) is never cut.

use super::super::options::ScaleB;
use super::super::rigid::{RigidAlignment, align_surfaces};
use crate::mesh::TriMesh;
use crate::mesh::closest::ClosestPoints;
use crate::mesh::repair::{FaceOrigins, fix_non_manifold, keep_faces};
use crate::vec3::{norm3 as norm, sub3 as sub};
use serde::Serialize;

/// Distance beyond which a vertex is far from the other surface, as a fraction of the
/// smaller surface's `√area` (plus the other surface's mean edge, since distances are
/// measured to its vertices): 0.1 — about 2.5 cm on a face. Two faces of different
/// people aligned rigidly are mostly within a few millimetres; the back of a head is
/// 10–25 cm from a face crop.
pub const FAR: f64 = 0.1;

/// A far piece is cut only from this fraction of its surface's area up.
pub const MIN_PIECE: f64 = 0.05;

/// A surface is cropped only when the cut removes at least this fraction of its area.
pub const MIN_CROP: f64 = 0.35;

/// What the crop of one surface keeps.
#[derive(Clone, Debug, Serialize)]
pub struct SurfaceCrop {
    /// Per face of the surface: kept.
    #[serde(skip)]
    pub keep: Vec<bool>,
    /// Fraction of the surface's area cut off.
    pub removed_area: f64,
    /// Faces kept, of all.
    pub kept_faces: usize,
    pub faces: usize,
}

/// The crops of both surfaces (`None`: matched whole).
#[derive(Clone, Debug, Serialize)]
pub struct OverlapCrops {
    pub a: Option<SurfaceCrop>,
    pub b: Option<SurfaceCrop>,
    /// The far distance τ used (mesh units of A).
    pub far_distance: f64,
    /// Fraction of each surface's area that lies far from the other (before the small
    /// pieces are spared).
    pub far_area_a: f64,
    pub far_area_b: f64,
}

impl OverlapCrops {
    pub fn any(&self) -> bool {
        self.a.is_some() || self.b.is_some()
    }
}

/// The crops of `a` and `b` to the region they share (see the module documentation).
/// `guide_a`/`guide_b` are vertices the user's guidance names (never cut away). `None`
/// when the surfaces cannot be aligned (too few vertices).
pub fn overlap_crops(
    a: &TriMesh,
    b: &TriMesh,
    guide_a: &[u32],
    guide_b: &[u32],
) -> Option<OverlapCrops> {
    let rigid = align_surfaces(
        (&a.positions, &a.triangles),
        (&b.positions, &b.triangles),
        &[],
        None,
    )?;
    Some(crops_from(a, b, &rigid, guide_a, guide_b))
}

/// [`overlap_crops`] with B at the size the match gives it ([`ScaleB`]), sparing the
/// vertices `guide_a` and `guide_b` (what the guidance names: `super::solve::Guidance::vertices`);
/// `None` when nothing is cut.
pub fn crops_for_match(
    a: &TriMesh,
    b: &TriMesh,
    guide_a: &[u32],
    guide_b: &[u32],
    scale_b: ScaleB,
) -> Option<OverlapCrops> {
    let factor = scale_b.factor(a.area(), b.area());
    let mut scaled = b.clone();
    for p in &mut scaled.positions {
        *p = p.map(|c| c * factor);
    }
    overlap_crops(a, &scaled, guide_a, guide_b).filter(OverlapCrops::any)
}

/// `mesh` cut as `crop` says (as it is for `None`), with the origins of its faces
/// ([`FaceOrigins`]: each face's face of the mesh as given, composed with `origins`,
/// the repairs' when the mesh was repaired first); the origins stay `None` when nothing
/// was cut or repaired. A vertex where the kept faces meet only at that vertex (the cut
/// can leave such pinches) is split into one copy per fan
/// ([`fix_non_manifold`]), so the cut surface is a disc where the mesh was one. The cut
/// mesh carries no UVs (the matcher flattens it itself).
pub fn cut(
    mesh: TriMesh,
    origins: Option<FaceOrigins>,
    crop: Option<&SurfaceCrop>,
) -> (TriMesh, Option<FaceOrigins>) {
    let Some(c) = crop else {
        return (mesh, origins);
    };
    let origins = origins.unwrap_or_else(|| FaceOrigins::identity(mesh.triangles.len()));
    let (mut kept, _) = fix_non_manifold(&keep_faces(&FaceOrigins::tag(&mesh), &c.keep));
    let later = FaceOrigins::read(&kept).expect("the cut keeps the faces' tags");
    kept.uvs = None;
    (kept, Some(origins.then(&later)))
}

/// [`overlap_crops`] from a given rigid alignment of A onto B.
pub fn crops_from(
    a: &TriMesh,
    b: &TriMesh,
    rigid: &RigidAlignment,
    guide_a: &[u32],
    guide_b: &[u32],
) -> OverlapCrops {
    let smaller = a.area().min(b.area()).sqrt();
    let moved_a: Vec<[f64; 3]> = a.positions.iter().map(|&p| rigid.motion.apply(p)).collect();
    let tau_a = FAR * smaller + mean_edge(b);
    let tau_b = FAR * smaller + mean_edge(a);
    let far_a = far_vertices(&moved_a, &b.positions, tau_a);
    let far_b = far_vertices(&b.positions, &moved_a, tau_b);
    let (crop_a, far_area_a) = crop_surface(a, &far_a, guide_a);
    let (crop_b, far_area_b) = crop_surface(b, &far_b, guide_b);
    OverlapCrops {
        a: crop_a,
        b: crop_b,
        far_distance: tau_a,
        far_area_a,
        far_area_b,
    }
}

/// Mean edge length of a mesh (each triangle's three edges).
fn mean_edge(mesh: &TriMesh) -> f64 {
    let n = mesh.triangles.len().max(1) as f64;
    mesh.triangles
        .iter()
        .map(|t| {
            let [p, q, r] = t.map(|i| mesh.positions[i as usize]);
            norm(sub(q, p)) + norm(sub(r, q)) + norm(sub(p, r))
        })
        .sum::<f64>()
        / (3.0 * n)
}

/// Which `points` lie more than `tau` from every point of `other`.
fn far_vertices(points: &[[f64; 3]], other: &[[f64; 3]], tau: f64) -> Vec<bool> {
    use rayon::prelude::*;
    let closest = ClosestPoints::new(other);
    points
        .par_iter()
        .map(|p| closest.closest(p).1 > tau * tau)
        .collect()
}

/// Union-find root with path halving.
fn root(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        parent[v as usize] = parent[parent[v as usize] as usize];
        v = parent[v as usize];
    }
    v
}

/// The connected pieces (through shared vertices) of the faces where `member`:
/// a piece id per face (`u32::MAX` for the others).
fn pieces(mesh: &TriMesh, member: &[bool]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if member[t] {
            let r0 = root(&mut parent, tri[0]);
            for &v in &tri[1..] {
                let r = root(&mut parent, v);
                if r != r0 {
                    parent[r as usize] = r0;
                }
            }
        }
    }
    mesh.triangles
        .iter()
        .enumerate()
        .map(|(t, tri)| {
            if member[t] {
                root(&mut parent, tri[0])
            } else {
                u32::MAX
            }
        })
        .collect()
}

/// The connected pieces (through shared edges) of the faces where `member`: a piece
/// id per face (`u32::MAX` for the others).
fn edge_pieces(mesh: &TriMesh, member: &[bool]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
    let mut first = std::collections::HashMap::<(u32, u32), u32>::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if !member[t] {
            continue;
        }
        for k in 0..3 {
            let (u, v) = (tri[k], tri[(k + 1) % 3]);
            match first.entry((u.min(v), u.max(v))) {
                std::collections::hash_map::Entry::Occupied(e) => {
                    let (r, s) = (root(&mut parent, *e.get()), root(&mut parent, t as u32));
                    if r != s {
                        parent[s as usize] = r;
                    }
                }
                std::collections::hash_map::Entry::Vacant(e) => {
                    e.insert(t as u32);
                }
            }
        }
    }
    (0..mesh.triangles.len())
        .map(|t| {
            if member[t] {
                root(&mut parent, t as u32)
            } else {
                u32::MAX
            }
        })
        .collect()
}

/// The crop of one surface given its far vertices, and the fraction of its area that
/// lies far.
fn crop_surface(mesh: &TriMesh, far: &[bool], guide: &[u32]) -> (Option<SurfaceCrop>, f64) {
    let nf = mesh.triangles.len();
    let total = mesh.area();
    if nf == 0 || total.is_nan() || total <= 0.0 {
        return (None, 0.0);
    }
    let area: Vec<f64> = (0..nf).map(|t| mesh.triangle_area(t)).collect();
    let is_far: Vec<bool> = mesh
        .triangles
        .iter()
        .map(|t| t.iter().any(|&v| far[v as usize]))
        .collect();
    // (+ 0.0: an empty sum is −0.0.)
    let far_area = (0..nf).filter(|&t| is_far[t]).map(|t| area[t]).sum::<f64>() / total + 0.0;
    if far_area < MIN_CROP {
        return (None, far_area);
    }
    // Far pieces, their areas, and whether guidance pins them.
    let piece = pieces(mesh, &is_far);
    let mut piece_area = std::collections::HashMap::<u32, f64>::new();
    for t in 0..nf {
        if is_far[t] {
            *piece_area.entry(piece[t]).or_default() += area[t];
        }
    }
    let mut guided = std::collections::HashSet::<u32>::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if is_far[t] && tri.iter().any(|v| guide.contains(v)) {
            guided.insert(piece[t]);
        }
    }
    let cut = |t: usize| {
        is_far[t] && !guided.contains(&piece[t]) && piece_area[&piece[t]] >= MIN_PIECE * total
    };
    // Of the rest, the largest piece connected through edges (by area): pieces that
    // touch at a vertex only are not one surface.
    let rest: Vec<bool> = (0..nf).map(|t| !cut(t)).collect();
    let rest_piece = edge_pieces(mesh, &rest);
    let mut rest_area = std::collections::HashMap::<u32, f64>::new();
    for t in 0..nf {
        if rest[t] {
            *rest_area.entry(rest_piece[t]).or_default() += area[t];
        }
    }
    let Some((&largest, _)) = rest_area.iter().max_by(|x, y| x.1.total_cmp(y.1)) else {
        return (None, far_area);
    };
    let keep: Vec<bool> = (0..nf)
        .map(|t| rest[t] && rest_piece[t] == largest)
        .collect();
    // A guided vertex outside the kept piece: keep the whole surface rather than lose it.
    let kept_vertex = {
        let mut k = vec![false; mesh.positions.len()];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            if keep[t] {
                tri.iter().for_each(|&v| k[v as usize] = true);
            }
        }
        k
    };
    if guide
        .iter()
        .any(|&v| !kept_vertex.get(v as usize).copied().unwrap_or(true))
    {
        return (None, far_area);
    }
    let kept_area: f64 = (0..nf).filter(|&t| keep[t]).map(|t| area[t]).sum();
    let removed_area = 1.0 - kept_area / total;
    if removed_area < MIN_CROP {
        return (None, far_area);
    }
    let kept_faces = keep.iter().filter(|&&k| k).count();
    (
        Some(SurfaceCrop {
            keep,
            removed_area,
            kept_faces,
            faces: nf,
        }),
        far_area,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matching::rigid::axis_angle_rotation;
    use crate::mesh::generate::bumpy_disc;
    use crate::testing::crop;

    /// A bumpy disc of radius 1 (an asymmetric height field) and, as A, its part with
    /// `x < cut` turned and moved in space; `ids[v]` is A's vertex `v`'s index in B.
    fn whole_and_part(cut: f64) -> (TriMesh, TriMesh) {
        let whole = bumpy_disc(30, 0.35);
        let (mut part, _) = crop(&whole, |p| p[0] < cut);
        let r = axis_angle_rotation([0.3, -0.5, 0.8], 0.4);
        for p in &mut part.positions {
            let q = *p;
            *p = std::array::from_fn(|i| {
                r[i][0] * q[0] + r[i][1] * q[1] + r[i][2] * q[2] + [0.7, -0.2, 0.4][i]
            });
        }
        (part, whole)
    }

    /// Faces of `mesh` with every vertex where `inside(x)` / with some vertex where not.
    fn kept_where(mesh: &TriMesh, keep: &[bool], inside: impl Fn(f64) -> bool) -> (usize, usize) {
        let mut kept_inside = 0;
        let mut kept_outside = 0;
        for (t, tri) in mesh.triangles.iter().enumerate() {
            if keep[t] {
                if tri.iter().all(|&v| inside(mesh.positions[v as usize][0])) {
                    kept_inside += 1;
                } else {
                    kept_outside += 1;
                }
            }
        }
        (kept_inside, kept_outside)
    }

    /// A part (x < −0.1, about 40 % of the disc's area) against the whole disc, moved
    /// apart in space: A is kept whole; B is cut down to the part near A — every face of
    /// B with its three vertices in A's region kept, nothing kept beyond the far distance
    /// τ (plus an edge) past A's border. Swapped, the same cut falls on A.
    #[test]
    fn a_whole_surface_is_cut_down_to_the_part_it_shares() {
        let (part, whole) = whole_and_part(-0.1);
        let crops = overlap_crops(&part, &whole, &[], &[]).unwrap();
        assert!(crops.a.is_none(), "the part was cropped: {crops:?}");
        let b = crops.b.as_ref().expect("the whole was not cropped");
        assert!(b.removed_area > MIN_CROP && b.removed_area < 0.7, "{b:?}");
        let tau = crops.far_distance;
        let (inside, _) = kept_where(&whole, &b.keep, |x| x < -0.1);
        let (all_inside, _) = kept_where(&whole, &vec![true; whole.triangles.len()], |x| x < -0.1);
        assert_eq!(inside, all_inside, "faces of the shared part were cut");
        let edge = mean_edge(&whole);
        let (_, beyond) = kept_where(&whole, &b.keep, |x| x < -0.1 + tau + 2.0 * edge);
        assert_eq!(beyond, 0, "faces beyond τ = {tau} kept");
        assert!(crops.far_area_b >= b.removed_area - 1e-12);
        // Either way round.
        let swapped = overlap_crops(&whole, &part, &[], &[]).unwrap();
        assert!(swapped.b.is_none());
        assert_eq!(swapped.a.as_ref().unwrap().keep, b.keep);
    }

    /// Surfaces that share most of their extent (a part of 85 % of the disc against the
    /// whole) are matched whole: the far part is below [`MIN_CROP`].
    #[test]
    fn surfaces_that_mostly_overlap_are_not_cropped() {
        let (part, whole) = whole_and_part(0.75);
        let crops = overlap_crops(&part, &whole, &[], &[]).unwrap();
        assert!(!crops.any(), "{crops:?}");
        assert!(
            crops.far_area_b > 0.0 && crops.far_area_b < MIN_CROP,
            "{crops:?}"
        );
        assert_eq!(crops.far_area_a, 0.0);
    }

    /// A cut that leaves the kept faces meeting at a single vertex (two of the six faces
    /// around an inner vertex of a disc removed, opposite each other; the rest of the
    /// disc still joins the two fans) gives a disc again: the vertex is split into one
    /// copy per fan, every kept face traced back to its face of the mesh, corner by
    /// corner.
    #[test]
    fn a_cut_that_pinches_a_vertex_splits_it() {
        let mesh = bumpy_disc(6, 0.2);
        let centre = 0u32;
        let around: Vec<usize> = (0..mesh.triangles.len())
            .filter(|&t| mesh.triangles[t].contains(&centre))
            .collect();
        assert_eq!(around.len(), 6);
        // Two faces of the centre's fan that share no edge (not neighbours around it).
        let shares_edge = |s: usize, t: usize| {
            mesh.triangles[s]
                .iter()
                .filter(|v| mesh.triangles[t].contains(v))
                .count()
                == 2
        };
        let first = around[0];
        let second = *around[1..]
            .iter()
            .find(|&&t| {
                !shares_edge(first, t)
                    && around
                        .iter()
                        .filter(|&&u| shares_edge(t, u) && shares_edge(first, u))
                        .count()
                        == 0
            })
            .unwrap();
        let keep: Vec<bool> = (0..mesh.triangles.len())
            .map(|t| t != first && t != second)
            .collect();
        let crop = SurfaceCrop {
            keep: keep.clone(),
            removed_area: 0.0,
            kept_faces: keep.iter().filter(|&&k| k).count(),
            faces: keep.len(),
        };
        let plain = keep_faces(&mesh, &keep);
        assert!(
            !crate::mesh::Topology::new(&plain)
                .non_manifold_vertices
                .is_empty()
        );
        let (cut_mesh, origins) = cut(mesh.clone(), None, Some(&crop));
        let topo = crate::mesh::Topology::new(&cut_mesh);
        assert!(topo.is_manifold(), "{:?}", topo.non_manifold_vertices);
        assert_eq!(cut_mesh.positions.len(), plain.positions.len() + 1);
        let origins = origins.unwrap();
        assert_eq!(origins.face.len(), crop.kept_faces);
        for (t, &f) in origins.face.iter().enumerate() {
            let given = mesh.triangles[f as usize].map(|v| mesh.positions[v as usize]);
            let corners = origins.corner[t].map(|k| given[k as usize]);
            let here = cut_mesh.triangles[t].map(|v| cut_mesh.positions[v as usize]);
            assert_eq!(corners, here, "face {t} (given face {f})");
        }
    }

    /// A landmark on the far part spares the piece it is on: nothing is cut then (the
    /// far part is one piece), and a landmark on the shared part changes nothing.
    #[test]
    fn a_far_piece_with_guidance_on_it_is_kept() {
        let (part, whole) = whole_and_part(-0.1);
        let far_vertex = (0..whole.positions.len())
            .max_by(|&u, &v| whole.positions[u][0].total_cmp(&whole.positions[v][0]))
            .unwrap() as u32;
        let near_vertex = (0..whole.positions.len())
            .min_by(|&u, &v| whole.positions[u][0].total_cmp(&whole.positions[v][0]))
            .unwrap() as u32;
        let guided = overlap_crops(&part, &whole, &[], &[far_vertex]).unwrap();
        assert!(!guided.any(), "{guided:?}");
        let near = overlap_crops(&part, &whole, &[], &[near_vertex]).unwrap();
        let plain = overlap_crops(&part, &whole, &[], &[]).unwrap();
        assert_eq!(near.b.unwrap().keep, plain.b.unwrap().keep);
    }
}
