//! The fold check of a correspondence in space: which of A's triangles, carried onto B
//! vertex by vertex, turn over or collapse.
//!
//! φ is fold-free on the grid (min det Dφ > 0, [`super::deformation`]), but the
//! induced map of A's *triangles* onto B — each vertex carried to a point of B, the
//! triangle spanned by the three points — can still turn over where B bends more
//! sharply than the grid resolves (lip corners, ear folds), or shrink to nothing
//! where several vertices land on one point. [`check_folds`] finds those triangles in
//! space, by the same test an independent referee applies: the image triangle's normal
//! against B's normals at its corners (flip), and its area against A's (collapse).
//! By default their vertices are reported unmatched rather than wrong ([`drop_folds`]).
//! Post-processing (`super::post`) and the report ([`super::report`]) both call it.

use rayon::prelude::*;
use serde::Serialize;

use crate::mesh::{SurfacePoint, TriMesh};
use crate::vec3::{cross3 as cross, norm3 as norm, sub3 as sub};

/// Triangles of A whose image on B turns over or collapses.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FoldCheck {
    /// Triangles of A with all three vertices matched (before dropping).
    pub matched_triangles: usize,
    /// Image normal opposite to B's normals at the three points.
    pub flipped: Vec<u32>,
    /// Image area below [`COLLAPSE_RATIO`] of A's area (scaled by area B / area A).
    pub collapsed: Vec<u32>,
}

/// An image triangle smaller than this fraction of its (area-scaled) source collapses.
pub const COLLAPSE_RATIO: f64 = 0.01;

/// How an image triangle of A on B sits: as it should, turned over, or collapsed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFold {
    None,
    Flipped,
    Collapsed,
}

/// The fold test of one triangle `tri` of A whose vertices are matched to `points` of B:
/// with `n = (p_j − p_i) × (p_k − p_i)` the image is *collapsed* when
/// `|n|/2 < COLLAPSE_RATIO · area_A(t) · area_ratio` (`area_ratio = area(B)/area(A)`) and
/// otherwise *flipped* when `n · (N_B(t_i) + N_B(t_j) + N_B(t_k)) < 0`, `N_B(t)` the unit
/// normal of the triangle of B that hosts each point.
pub fn image_fold(
    a: &TriMesh,
    b: &TriMesh,
    area_ratio: f64,
    tri: [u32; 3],
    points: [SurfacePoint; 3],
) -> ImageFold {
    let normal_b = |t: u32| {
        let [p, q, r] = b.triangles[t as usize].map(|i| b.positions[i as usize]);
        let n = cross(sub(q, p), sub(r, p));
        let l = norm(n);
        if l > 0.0 { n.map(|c| c / l) } else { n }
    };
    let x = points.map(|s| s.position(&b.positions, &b.triangles));
    let n = cross(sub(x[1], x[0]), sub(x[2], x[0]));
    let [u, v, w] = tri.map(|i| a.positions[i as usize]);
    let area_a = 0.5 * norm(cross(sub(v, u), sub(w, u)));
    if 0.5 * norm(n) < COLLAPSE_RATIO * area_a * area_ratio {
        return ImageFold::Collapsed;
    }
    let reference = points
        .map(|s| normal_b(s.triangle))
        .into_iter()
        .fold([0.0; 3], |s, m| [s[0] + m[0], s[1] + m[1], s[2] + m[2]]);
    if n[0] * reference[0] + n[1] * reference[1] + n[2] * reference[2] < 0.0 {
        ImageFold::Flipped
    } else {
        ImageFold::None
    }
}

/// Flipped and collapsed image triangles of A on B under `correspondence` (one entry
/// per vertex of A): [`image_fold`] of every triangle with three matched vertices.
pub fn check_folds(a: &TriMesh, b: &TriMesh, correspondence: &[Option<SurfacePoint>]) -> FoldCheck {
    let ratio = b.area() / a.area();
    let results: Vec<(u32, ImageFold)> = a
        .triangles
        .par_iter()
        .enumerate()
        .filter_map(|(t, &tri)| {
            let pts = tri.map(|v| correspondence.get(v as usize).copied().flatten());
            let [Some(p0), Some(p1), Some(p2)] = pts else {
                return None;
            };
            Some((t as u32, image_fold(a, b, ratio, tri, [p0, p1, p2])))
        })
        .collect();
    let of = |kind: ImageFold| {
        results
            .iter()
            .filter(|r| r.1 == kind)
            .map(|r| r.0)
            .collect()
    };
    FoldCheck {
        matched_triangles: results.len(),
        flipped: of(ImageFold::Flipped),
        collapsed: of(ImageFold::Collapsed),
    }
}

/// Marks vertices of the flipped and collapsed triangles unmatched, as few as it
/// takes: one vertex per folded triangle, greedily the one shared by the most folded
/// triangles not yet cleared (a vertex cover of the folded triangles). Returns how many
/// vertices were dropped. No fully matched triangle is then flipped or collapsed: the
/// remaining ones keep their images. Vertices in `keep` (pinned landmarks) are dropped
/// only when a folded triangle has no other vertex to drop.
pub fn drop_folds(
    a: &TriMesh,
    folds: &FoldCheck,
    correspondence: &mut [Option<SurfacePoint>],
    keep: &[u32],
) -> usize {
    let folded: Vec<u32> = folds
        .flipped
        .iter()
        .chain(&folds.collapsed)
        .copied()
        .collect();
    let mut count = std::collections::HashMap::<u32, usize>::new();
    for &t in &folded {
        for v in a.triangles[t as usize] {
            *count.entry(v).or_default() += 1;
        }
    }
    let mut dropped = 0;
    // Triangles whose vertices are shared most go first, so that one drop clears many.
    let mut order = folded;
    order.sort_by_key(|&t| {
        std::cmp::Reverse(
            a.triangles[t as usize]
                .iter()
                .map(|v| count[v])
                .max()
                .unwrap_or(0),
        )
    });
    for t in order {
        let tri = a.triangles[t as usize];
        if tri.iter().any(|&v| correspondence[v as usize].is_none()) {
            continue;
        }
        let v = *tri
            .iter()
            .max_by_key(|v| (!keep.contains(v), count[v]))
            .expect("three vertices");
        correspondence[v as usize] = None;
        dropped += 1;
    }
    dropped
}
