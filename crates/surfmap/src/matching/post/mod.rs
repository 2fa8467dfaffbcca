//! Stage 4, **post**: φ → the per-vertex correspondence the outputs hold
//! ([`Correspondence`]). Each vertex of A is carried through φ onto B ([`point_map`]),
//! A's hole rims first carried exactly onto B's paired rims ([`rim_fit`]); the vertices
//! of image triangles that turn over or collapse in space are unmatched
//! ([`super::folds`]); the landmarks are pinned to their vertices of B ([`pin`]); the
//! unmatched vertices next to matched ones are completed from their neighbours where φ
//! just missed B ([`complete`]); last, the correspondence is numbered as the meshes were
//! given and checked for folds once more on those meshes.

pub(crate) mod complete;
pub(crate) mod pin;
pub(crate) mod point_map;
pub(crate) mod rim_fit;

use rayon::prelude::*;

use super::MatchError;
use super::folds::{FoldCheck, check_folds, drop_folds};
use super::options::MatchOptions;
use super::prepare::Prepared;
use super::prepare::surface::MatchSurface;
use super::solve::Solved;
use crate::mesh::{SurfacePoint, TriMesh};
use complete::{Completion, complete_correspondence};
use pin::{Pinning, pin_landmarks};
use point_map::PointMap;
use rim_fit::RimFit;

/// The correspondence, in the numbering of the meshes matched and of the meshes given.
pub(crate) struct Correspondence {
    /// On the meshes matched, as the checks left it.
    pub checked: CheckedCorrespondence,
    /// One entry per vertex of A as given: its counterpart on B as given, or `None`.
    pub given: Vec<Option<SurfacePoint>>,
    /// The same on the meshes matched, unmatched where the fold check on the meshes as
    /// given unmatched (what the pictures show).
    pub matched: Vec<Option<SurfacePoint>>,
    /// Vertices unmatched by the fold check on the meshes as given (after a crop).
    pub dropped_as_given: usize,
    /// A's triangles placed on B, numbered as A was given ([`a_on_b`]).
    pub a_on_b: TriMesh,
}

/// The stage (module docs).
pub(crate) fn post(
    p: &Prepared<'_>,
    solved: &Solved,
    options: &MatchOptions,
) -> Result<Correspondence, MatchError> {
    let checked = checked_correspondence(p, solved, options)?;
    let mut matched = checked.points.clone();
    let Some(r) = &p.renumbering else {
        let a_on_b = a_on_b(
            &p.mesh_a,
            &p.mesh_b,
            (&p.a, &p.b, p.scale_b),
            solved,
            &matched,
        );
        return Ok(Correspondence {
            checked,
            given: matched.clone(),
            matched,
            dropped_as_given: 0,
            a_on_b,
        });
    };
    // The files' numbering: each vertex of A as given takes its copy's counterpart, each
    // point of B goes back to the face of B as given it lies on.
    let mut given = numbered_as_given(&matched, &r.copies_a, r.origins_b.as_ref());
    let mut dropped_as_given = 0;
    if p.crops.is_some() && !options.keep_folds {
        // The collapse test scales each image's area by the surfaces' area ratio, which
        // the cut changes: the fold check once more on the meshes as given (the test an
        // independent referee applies to the files).
        let pinned = if options.pin_landmarks {
            p.landmarks_a.clone()
        } else {
            vec![]
        };
        let folds = check_folds(p.given_a, p.given_b, &given);
        dropped_as_given = drop_folds(p.given_a, &folds, &mut given, &pinned);
    }
    let a_on_b = a_on_b(
        &faces_as_given(p, r),
        p.given_b,
        (&p.a, &p.b, p.scale_b),
        solved,
        &given,
    );
    // What that fold check unmatched, unmatched on the meshes matched too.
    for (v, c) in r.copies_a.iter().enumerate() {
        if let Some(c) = c
            && given[v].is_none()
        {
            matched[*c as usize] = None;
        }
    }
    Ok(Correspondence {
        checked,
        given,
        matched,
        dropped_as_given,
        a_on_b,
    })
}

/// A's faces as matched (the repaired ones, consistently oriented), on the vertex
/// numbers of A as given; where a repair split a vertex into copies, its row is one
/// copy's, and the faces around the others are left out (their corner's place on B is
/// not the row's).
fn faces_as_given(p: &Prepared<'_>, r: &super::prepare::Renumbering) -> TriMesh {
    let given = p.given_a;
    match &r.origins_a {
        Some(o) => TriMesh::new(
            given.positions.clone(),
            (0..p.mesh_a.triangles.len())
                .filter_map(|t| {
                    let source = given.triangles[o.face[t] as usize];
                    let tri = o.corner[t].map(|k| source[k as usize]);
                    (0..3)
                        .all(|k| r.copies_a[tri[k] as usize] == Some(p.mesh_a.triangles[t][k]))
                        .then_some(tri)
                })
                .collect(),
        ),
        None => given.clone(),
    }
}

/// For every vertex of A, its counterpart on B (a triangle of B and barycentric
/// coordinates), or `None` where φ maps it outside B's surface (beyond ω_B's border or
/// into one of B's holes), and what the rim fit did. A point that φ puts within
/// [`super::options::SNAP_CELLS`] grid cells of B's surface is snapped onto it: a vertex
/// on A's rim lies exactly on ω_A's border, and at the grid's resolution "on the
/// border" and "just outside" are the same answer. Around the holes A's rims are first
/// carried exactly onto B's ([`rim_fit`]).
pub(crate) fn fitted_correspondence(
    a: &MatchSurface,
    b: &MatchSurface,
    solved: &Solved,
    options: &MatchOptions,
) -> Result<(Vec<Option<SurfacePoint>>, RimFit), MatchError> {
    let map = PointMap::new(a, b, solved, options.tuning.snap_cells)?;
    let mut images: Vec<[f64; 2]> = a.uvs.par_iter().map(|&uv| map.image(uv)).collect();
    let fit = rim_fit::fit_hole_rims(a, b, &mut images, options.advanced.rim_fit_rings);
    Ok((images.par_iter().map(|&y| map.locate(y)).collect(), fit))
}

/// A per-vertex correspondence after the checks of [`crate::matching::post::post`].
#[derive(Clone, Debug)]
pub(crate) struct CheckedCorrespondence {
    /// One entry per vertex of A: its counterpart on B, or `None`.
    pub points: Vec<Option<SurfacePoint>>,
    /// Folded image triangles of φ's own correspondence, before anything was dropped;
    /// when folds are kept (`drop` false), those of the output itself.
    pub folds: FoldCheck,
    /// Vertices unmatched in `points` because a triangle around them folded (φ's folds
    /// and any that pinning or completion made); a dropped vertex that completion
    /// matched again is not counted.
    pub dropped: usize,
    /// What fitting the hole rims did ([`crate::matching::post::rim_fit`]).
    pub rim_fit: RimFit,
    /// What rim completion added ([`crate::matching::post::complete`]).
    pub completion: Completion,
    /// What pinning the landmarks did ([`crate::matching::post::pin`]).
    pub pinning: Pinning,
}

/// The per-vertex correspondence, checked: φ's correspondence
/// ([`crate::matching::post::fitted_correspondence`]); when `drop`, the vertices of folded image
/// triangles unmatched ([`drop_folds`]); the landmarks pinned
/// ([`crate::matching::post::pin`], [`MatchOptions::pin_landmarks`]) and folds so made dropped
/// again (never a landmark); then, unless
/// [`Advanced::complete_rings`](super::Advanced::complete_rings) is 0, unmatched vertices next to matched ones
/// completed from their neighbours ([`complete_correspondence`]) and the fold check
/// run again on the result.
fn checked_correspondence(
    p: &Prepared<'_>,
    solved: &Solved,
    options: &MatchOptions,
) -> Result<CheckedCorrespondence, MatchError> {
    let (mesh_a, mesh_b, drop) = (&p.mesh_a, &p.mesh_b, !options.keep_folds);
    let pinned_landmarks = if options.pin_landmarks {
        p.landmark_pairs()
    } else {
        vec![]
    };
    let (mut points, rim_fit) = fitted_correspondence(&p.a, &p.b, solved, options)?;
    let folds = check_folds(mesh_a, mesh_b, &points);
    let pinned: Vec<u32> = pinned_landmarks.iter().map(|p| p.0).collect();
    // Every vertex a fold check unmatched; completion may match some of them again.
    let mut dropped_ever = vec![false; points.len()];
    let mut drop_and_mark =
        |points: &mut Vec<Option<SurfacePoint>>, folds: &FoldCheck, keep: &[u32]| {
            let before: Vec<bool> = points.iter().map(Option::is_some).collect();
            drop_folds(mesh_a, folds, points, keep);
            for (v, was) in before.into_iter().enumerate() {
                dropped_ever[v] |= was && points[v].is_none();
            }
        };
    if drop {
        // φ's own folds: no landmark is pinned yet, so none is kept.
        drop_and_mark(&mut points, &folds, &[]);
    }
    let pinning = pin_landmarks(mesh_a, mesh_b, &mut points, &pinned_landmarks);
    if drop && pinning.landmarks > 0 {
        let folds = check_folds(mesh_a, mesh_b, &points);
        drop_and_mark(&mut points, &folds, &pinned);
    }
    let completion = complete_correspondence(
        mesh_a,
        mesh_b,
        &mut points,
        options.advanced.complete_rings,
        options.complete_tolerance(),
        options.tuning.rim_smoothing,
        &pinned,
    );
    if drop && completion.completed > 0 {
        let folds = check_folds(mesh_a, mesh_b, &points);
        drop_and_mark(&mut points, &folds, &pinned);
    }
    let dropped = (0..points.len())
        .filter(|&v| dropped_ever[v] && points[v].is_none())
        .count();
    // Kept folds are reported as they are in the output (pinning may have added some
    // around a landmark).
    let folds = if drop {
        folds
    } else {
        check_folds(mesh_a, mesh_b, &points)
    };
    Ok(CheckedCorrespondence {
        points,
        folds,
        dropped,
        rim_fit,
        completion,
        pinning,
    })
}

/// A correspondence found on repaired or cropped meshes, numbered as the meshes were
/// given: input vertex `v` of A takes the counterpart of its copy `copies_a[v]` (`None`:
/// removed, unmatched), and each point goes back to the input face of B it lies on
/// (`origins_b`, when B's faces changed).
pub(crate) fn numbered_as_given(
    correspondence: &[Option<SurfacePoint>],
    copies_a: &[Option<u32>],
    origins_b: Option<&crate::mesh::repair::FaceOrigins>,
) -> Vec<Option<SurfacePoint>> {
    copies_a
        .iter()
        .map(|c| {
            let p = c.and_then(|v| correspondence[v as usize])?;
            Some(origins_b.map_or(p, |o| o.point(p)))
        })
        .collect()
}

/// A's triangles at their matched positions on B: every vertex of A at its point on B
/// (unmatched vertices at their position moved by the position term's final map, so
/// the file keeps A's numbering), triangles with an unmatched vertex left out. In B's
/// own units (`mesh_b` as given, before [`super::ScaleB`]).
pub(crate) fn a_on_b(
    mesh_a: &TriMesh,
    mesh_b: &TriMesh,
    (a, b, scale_b): (&MatchSurface, &MatchSurface, f64),
    solved: &Solved,
    correspondence: &[Option<SurfacePoint>],
) -> TriMesh {
    let unit_a = a.length_unit;
    // B's ℓ in the units of the surface that was matched (B × `scale_b`), back to B's own.
    let unit_b = b.length_unit / scale_b;
    let positions = correspondence
        .iter()
        .zip(&mesh_a.positions)
        .map(|(p, x)| match p {
            Some(s) => s.position(&mesh_b.positions, &mesh_b.triangles),
            None => solved
                .similarity
                .apply(x.map(|c| c / unit_a))
                .map(|c| c * unit_b),
        })
        .collect();
    let triangles = mesh_a
        .triangles
        .iter()
        .filter(|t| t.iter().all(|&v| correspondence[v as usize].is_some()))
        .copied()
        .collect();
    TriMesh::new(positions, triangles)
}
