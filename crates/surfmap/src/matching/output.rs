//! What a match hands back: the per-vertex correspondence checked for folds in space,
//! a map of any surface point of A, a serializable report, and the match folder
//! (`correspondence.npy/.csv`, `A_on_B.obj`, `deformation.npy`, `match.json`).
//!
//! φ is fold-free on the grid (min det Dφ > 0, [`super::deformation`]), but the
//! induced map of A's *triangles* onto B — each vertex carried to a point of B, the
//! triangle spanned by the three points — can still turn over where B bends more
//! sharply than the grid resolves (lip corners, ear folds), or shrink to nothing
//! where several vertices land on one point. [`check_folds`] finds those triangles in
//! space, by the same test an independent referee applies: the image triangle's normal
//! against B's normals at its corners (flip), and its area against A's (collapse).
//! By default their vertices are reported unmatched rather than wrong
//! ([`MatchOptions::drop_folds`](super::MatchOptions)).

use std::path::Path;

use rayon::prelude::*;
use serde::Serialize;

use super::complete::{Completion, complete_correspondence};
use super::pin::{Pinning, pin_landmarks};
use super::rim_fit::RimFit;
use super::solve::{MatchOptions, SurfaceMatch};
use super::{LevelLog, MatchError};
use crate::fsutil::write_atomically;
use crate::mesh::{PointLocator, SurfacePoint, TriMesh};
use crate::raster::npy::save_npy;
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

/// Maps surface points of A onto B through a match (built once: a point locator over
/// B's parameter domain).
pub struct PointMap<'a> {
    matched: &'a SurfaceMatch,
    locator: PointLocator,
    tolerance: f64,
}

impl<'a> PointMap<'a> {
    pub fn new(matched: &'a SurfaceMatch) -> Result<Self, MatchError> {
        let locator = PointLocator::new(&matched.b.uvs, &matched.b.triangles)
            .map_err(|e| MatchError::Option(format!("locating points on B: {e}")))?;
        let to_b = matched.b.images.transform;
        let tolerance = matched.snap_cells / (matched.deformation.size - 1) as f64 / to_b.scale;
        Ok(Self {
            matched,
            locator,
            tolerance,
        })
    }

    /// The counterpart on B of a point of A's parameter domain `uv` (A's UV units), or
    /// `None` where φ carries it off B's surface. A point that φ puts within
    /// [`MatchOptions::snap_cells`] grid cells of B's surface is snapped onto it.
    pub fn map_uv(&self, uv: [f64; 2]) -> Option<SurfacePoint> {
        self.locate(self.image(uv))
    }

    /// Where φ carries a point of A's parameter domain `uv` (A's UV units), in B's UV
    /// units (anywhere in the plane: off B's surface too).
    pub fn image(&self, uv: [f64; 2]) -> [f64; 2] {
        let xi = self.matched.a.images.transform.to_domain(uv);
        self.matched
            .b
            .images
            .transform
            .to_uv(self.matched.map_domain(xi))
    }

    /// The point of B's surface at `target` in B's UV, snapped onto it from within
    /// [`MatchOptions::snap_cells`] grid cells; `None` farther off.
    pub fn locate(&self, target: [f64; 2]) -> Option<SurfacePoint> {
        self.locator.locate(target).or_else(|| {
            self.locator
                .nearest(target)
                .filter(|n| n.distance <= self.tolerance)
                .map(|n| n.point)
        })
    }

    /// The counterpart on B of a point of A's surface (a triangle of A and barycentric
    /// coordinates), or `None`.
    pub fn map(&self, p: SurfacePoint) -> Option<SurfacePoint> {
        let a = &self.matched.a;
        if p.triangle as usize >= a.triangles.len() {
            return None;
        }
        let [u, v, w] = a.triangles[p.triangle as usize].map(|i| a.uvs[i as usize]);
        let b = p.barycentric;
        self.map_uv(std::array::from_fn(|c| {
            b[0] * u[c] + b[1] * v[c] + b[2] * w[c]
        }))
    }
}

/// One level of the solve, for reports.
#[derive(Clone, Debug, Serialize)]
pub struct LevelSummary {
    pub level: usize,
    pub size: usize,
    pub epsilon: f64,
    pub iterations: usize,
    pub evaluations: usize,
    pub stop: super::StopReason,
    pub energy_start: super::EnergyTerms,
    pub energy_end: super::EnergyTerms,
    pub seconds: f64,
}

impl From<&LevelLog> for LevelSummary {
    fn from(l: &LevelLog) -> Self {
        Self {
            level: l.level,
            size: l.size,
            epsilon: l.epsilon,
            iterations: l.iterations,
            evaluations: l.evaluations,
            stop: l.stop,
            energy_start: l.start,
            energy_end: l.end,
            seconds: l.seconds,
        }
    }
}

/// Everything `match.json` says about a match.
#[derive(Clone, Debug, Serialize)]
pub struct MatchReport {
    pub vertices_a: usize,
    pub vertices_b: usize,
    /// Vertices of A with a counterpart on B (after dropping folds).
    pub matched_vertices_a: usize,
    pub matched_fraction_a: f64,
    /// Area of B covered by the images of A's fully matched triangles, as a fraction of
    /// B's area (capped at 1; φ is injective, so the images barely overlap).
    pub covered_fraction_b: f64,
    /// Area of the images on B of A's fully matched triangles over those triangles' own
    /// area (both in the shared unit, B × `scale_b`): near 1 when surfaces of like size
    /// are matched where they correspond (0.82–1.16 on the 86 good matches of the
    /// benchmarked face pairs); far from it, A was squeezed into (or stretched over) part
    /// of B. `null` when nothing matched.
    pub area_ratio: Option<f64>,
    /// Doubts about the result, worded for the user (empty when none): see
    /// [`match_warnings`] and [`super::feature_fit::feature_warnings`].
    pub warnings: Vec<String>,
    pub holes_filled_a: usize,
    pub holes_filled_b: usize,
    /// Minimum det Dφ over the grid's triangles (> 0: φ has no fold).
    pub min_det: f64,
    /// Image triangles that turned over or collapsed in space, before dropping.
    pub flipped_triangles: usize,
    pub collapsed_triangles: usize,
    /// Vertices unmatched in the output because a triangle around them folded (dropped
    /// by the fold check and not matched again by rim completion).
    pub dropped_vertices: usize,
    /// Holes of A whose rims were carried onto B's paired rims, and the vertices of A
    /// so moved ([`super::rim_fit`]).
    pub rim_fit: RimFit,
    /// Vertices matched by rim completion from their neighbours
    /// ([`super::complete`]; included in `matched_vertices_a`).
    pub completed_vertices: usize,
    /// Matched vertices next to unmatched ones moved by the rim smoothing before
    /// completion ([`super::complete::RimSmoothing`]).
    pub smoothed_vertices: usize,
    /// Landmarks matched exactly to their vertex of B in the output ([`super::pin`]), and
    /// the largest distance (B's units) φ had left one of them from it.
    pub pinned_landmarks: usize,
    pub largest_landmark_miss: f64,
    pub alignment: super::AlignmentReport,
    /// Every paired feature (curves, landmarks, hole rims paired automatically): the
    /// mean distance (B's units) from A's curve, carried into ω_B, to B's, at the start
    /// of the solve and after it ([`super::feature_fit`]); empty without features.
    pub feature_fit: Vec<super::FeatureFit>,
    /// The position term's map of ℝ³ at the end (a similarity, or an affine map near
    /// one: [`super::PositionMap`]), A's length units to B's (both in the shared unit ℓ).
    pub similarity: super::Similarity3,
    /// The position term's weight `β_pos` used, and the surfaces' RMS distance in space
    /// along B's normals (ℓ units) it was set from ([`super::PositionWeight`]; `null`
    /// when fixed).
    pub position_weight: f64,
    pub shape_residual: Option<f64>,
    /// The factor B's positions were multiplied by for the match (1: as given; another
    /// power of ten when the sizes said the units differ, [`super::ScaleB`]). The
    /// outputs are in B's own units.
    pub scale_b: f64,
    pub length_unit: f64,
    pub grid_size: usize,
    pub levels: Vec<LevelSummary>,
    pub iterations: usize,
    pub energy: f64,
    pub seconds_flatten: f64,
    pub seconds_images: f64,
    pub seconds_solve: f64,
    pub options: MatchOptions,
    /// Set when the surfaces were repaired or cropped before the match (the CLI's
    /// `--repair` and the like, `--crop-overlap`): the counts above are of the matched
    /// meshes, while the outputs (`correspondence.npy`, `A_on_B.obj`) are numbered as
    /// the meshes were given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub input_numbering: Option<InputNumbering>,
    /// Set when the surfaces were cut down to the part they share before the match
    /// (the CLI's `--crop-overlap`, [`super::overlap`]); the cut vertices of A are
    /// unmatched in the outputs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overlap_crop: Option<super::overlap::OverlapCrops>,
}

/// The meshes as given, when the outputs were numbered back to them from repaired ones
/// ([`crate::mesh::repair::FaceOrigins`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct InputNumbering {
    /// Vertices of A as given: the rows of `correspondence.npy`.
    pub vertices_a: usize,
    /// Vertices and faces of B as given: the triangles the rows point into.
    pub vertices_b: usize,
    pub triangles_b: usize,
    /// Vertices of A as given that the repairs or the crop to the shared part removed
    /// (their rows are unmatched).
    pub removed_vertices_a: usize,
}

/// A per-vertex correspondence after the checks of [`SurfaceMatch::checked_correspondence`].
#[derive(Clone, Debug)]
pub struct CheckedCorrespondence {
    /// One entry per vertex of A: its counterpart on B, or `None`.
    pub points: Vec<Option<SurfacePoint>>,
    /// Folded image triangles of φ's own correspondence, before anything was dropped;
    /// when folds are kept (`drop` false), those of the output itself.
    pub folds: FoldCheck,
    /// Vertices unmatched in `points` because a triangle around them folded (φ's folds
    /// and any that pinning or completion made); a dropped vertex that completion
    /// matched again is not counted.
    pub dropped: usize,
    /// What fitting the hole rims did ([`super::rim_fit`]).
    pub rim_fit: RimFit,
    /// What rim completion added ([`super::complete`]).
    pub completion: Completion,
    /// What pinning the landmarks did ([`super::pin`]).
    pub pinning: Pinning,
}

impl SurfaceMatch {
    /// The per-vertex correspondence, checked: φ's correspondence
    /// ([`SurfaceMatch::correspondence`]); when `drop`, the vertices of folded image
    /// triangles unmatched ([`drop_folds`]); the landmarks pinned
    /// ([`super::pin`], [`MatchOptions::pin_landmarks`]) and folds so made dropped
    /// again (never a landmark); then, unless
    /// [`MatchOptions::complete_rings`] is 0, unmatched vertices next to matched ones
    /// completed from their neighbours ([`complete_correspondence`]) and the fold check
    /// run again on the result.
    pub fn checked_correspondence(
        &self,
        mesh_a: &TriMesh,
        mesh_b: &TriMesh,
        drop: bool,
    ) -> Result<CheckedCorrespondence, MatchError> {
        let (mut points, rim_fit) = self.fitted_correspondence()?;
        let folds = check_folds(mesh_a, mesh_b, &points);
        let pinned: Vec<u32> = self.pinned_landmarks.iter().map(|p| p.0).collect();
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
        let pinning = pin_landmarks(mesh_a, mesh_b, &mut points, &self.pinned_landmarks);
        if drop && pinning.landmarks > 0 {
            let folds = check_folds(mesh_a, mesh_b, &points);
            drop_and_mark(&mut points, &folds, &pinned);
        }
        let completion = complete_correspondence(
            mesh_a,
            mesh_b,
            &mut points,
            self.complete_rings,
            self.complete_tolerance,
            self.rim_smoothing,
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

    /// The report of `match.json` for a correspondence from
    /// [`SurfaceMatch::checked_correspondence`].
    pub fn report(&self, checked: &CheckedCorrespondence, options: &MatchOptions) -> MatchReport {
        let correspondence = &checked.points;
        let folds = &checked.folds;
        let matched = correspondence.iter().filter(|p| p.is_some()).count();
        let mut covered = 0.0;
        let mut matched_area_a = 0.0;
        let mut area_b = 0.0;
        for t in &self.b.triangles {
            let [p, q, r] = t.map(|i| self.b.positions[i as usize]);
            area_b += 0.5 * norm(cross(sub(q, p), sub(r, p)));
        }
        for t in &self.a.triangles {
            let pts = t.map(|v| correspondence[v as usize]);
            if let [Some(p), Some(q), Some(r)] = pts {
                let [p, q, r] = [p, q, r].map(|s| s.position(&self.b.positions, &self.b.triangles));
                covered += 0.5 * norm(cross(sub(q, p), sub(r, p)));
                let [p, q, r] = t.map(|v| self.a.positions[v as usize]);
                matched_area_a += 0.5 * norm(cross(sub(q, p), sub(r, p)));
            }
        }
        let area_ratio = (matched_area_a > 0.0).then(|| covered / matched_area_a);
        let feature_fit = self.feature_fits();
        let mut warnings = match_warnings(area_ratio);
        warnings.extend(super::feature_fit::feature_warnings(&feature_fit));
        let levels: Vec<LevelSummary> = self.levels.iter().map(LevelSummary::from).collect();
        MatchReport {
            vertices_a: correspondence.len(),
            vertices_b: self.b.positions.len(),
            matched_vertices_a: matched,
            matched_fraction_a: matched as f64 / correspondence.len().max(1) as f64,
            covered_fraction_b: (covered / area_b.max(f64::MIN_POSITIVE)).min(1.0),
            area_ratio,
            warnings,
            holes_filled_a: self.a.filled_holes,
            holes_filled_b: self.b.filled_holes,
            min_det: self.min_det,
            flipped_triangles: folds.flipped.len(),
            collapsed_triangles: folds.collapsed.len(),
            dropped_vertices: checked.dropped,
            rim_fit: checked.rim_fit,
            completed_vertices: checked.completion.completed,
            smoothed_vertices: checked.completion.smoothed,
            pinned_landmarks: checked.pinning.landmarks,
            largest_landmark_miss: checked.pinning.largest_miss,
            alignment: self.alignment.clone(),
            feature_fit,
            similarity: self.similarity,
            position_weight: self.position_weight,
            shape_residual: self.shape_residual,
            scale_b: self.scale_b,
            length_unit: self.a.length_unit,
            grid_size: self.deformation.size,
            iterations: levels.iter().map(|l| l.iterations).sum(),
            energy: levels.last().map_or(f64::NAN, |l| l.energy_end.total),
            levels,
            seconds_flatten: self.a.flatten_time + self.b.flatten_time,
            seconds_images: self.a.time_images + self.b.time_images,
            seconds_solve: self.seconds_solve,
            options: options.clone(),
            input_numbering: None,
            overlap_crop: None,
        }
    }
}

/// Largest factor by which a plausible match changes the matched part's area (either
/// way) before [`match_warnings`] doubts it. Faces of different people, expressions,
/// crops and sources stay within 0.82–1.16 (BENCHMARKS, "Doubtful matches"); a factor of
/// 3 is a different kind of result (a head scan squeezed into a template: 0.27), not a
/// worse one of the same kind. It does not catch a moderately wrong match (0.56 on the
/// worst ICT → FLAME pair, 45 mm off), and it leaves room for faces of different sizes
/// (a child's onto an adult's).
pub const AREA_RATIO_DOUBT: f64 = 3.0;

/// Whether a match that changes the matched part's area by the factor `r` is of the
/// kind surfaces of like size give: `1/`[`AREA_RATIO_DOUBT`]` ≤ r ≤ `[`AREA_RATIO_DOUBT`].
/// The report warns outside ([`match_warnings`]); the similarity search's start is not
/// kept when it leads outside and the alignment's does not ([`super::similarity_search`]).
pub fn plausible_area_ratio(r: f64) -> bool {
    (1.0 / AREA_RATIO_DOUBT..=AREA_RATIO_DOUBT).contains(&r)
}

/// What a match report should warn about, from the matched area: the matched part of A
/// lands on B at less than 1/[`AREA_RATIO_DOUBT`] or more than [`AREA_RATIO_DOUBT`]
/// times its own area — the surfaces were matched in a way no pair of like surfaces is
/// (a whole head squeezed into the face of another, a face spread over a head). The
/// report adds a warning per feature φ left beyond the feature term's reach
/// ([`super::feature_fit::feature_warnings`]).
pub fn match_warnings(area_ratio: Option<f64>) -> Vec<String> {
    let mut warnings = Vec::new();
    if let Some(r) = area_ratio
        && !plausible_area_ratio(r)
    {
        warnings.push(format!(
            "A's matched part lands on B at {r:.2}× its own area ({}): the surfaces probably \
             do not correspond the way they were matched. Check the pictures (--pictures); \
             crop both to the region they share (a face against a whole head or a scan \
             with shoulders does not match), or give landmarks.",
            if r < 1.0 { "squeezed" } else { "stretched" }
        ));
    }
    warnings
}

impl MatchReport {
    /// Counts `n` more vertices of A unmatched for folds (a fold check after the
    /// report was made: [`super::overlap::drop_folds_as_given`]).
    pub fn count_dropped(&mut self, n: usize) {
        self.dropped_vertices += n;
        self.matched_vertices_a -= n.min(self.matched_vertices_a);
        self.matched_fraction_a = self.matched_vertices_a as f64 / self.vertices_a.max(1) as f64;
    }
}

/// A correspondence found on repaired or cropped meshes, numbered as the meshes were
/// given: input vertex `v` of A takes the counterpart of its copy `copies_a[v]` (`None`:
/// removed, unmatched), and each point goes back to the input face of B it lies on
/// (`origins_b`, when B's faces changed).
pub fn numbered_as_given(
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

/// File names inside a match folder (read back by [`crate::apps::match_folder`]).
pub const CORRESPONDENCE_FILE: &str = "correspondence.npy";
pub const INFO_FILE: &str = "match.json";

/// The correspondence as rows `[triangle of B, b0, b1, b2]` (triangle −1 and zeros
/// where unmatched), row-major (n_A, 4).
pub fn correspondence_rows(correspondence: &[Option<SurfacePoint>]) -> Vec<f64> {
    correspondence
        .iter()
        .flat_map(|p| match p {
            Some(s) => [
                s.triangle as f64,
                s.barycentric[0],
                s.barycentric[1],
                s.barycentric[2],
            ],
            None => [-1.0, 0.0, 0.0, 0.0],
        })
        .collect()
}

/// A's triangles at their matched positions on B: every vertex of A at its point on B
/// (unmatched vertices at their position moved by the position term's final map, so
/// the file keeps A's numbering), triangles with an unmatched vertex left out. In B's
/// own units (`mesh_b` as given, before [`super::ScaleB`]).
pub fn a_on_b(
    mesh_a: &TriMesh,
    mesh_b: &TriMesh,
    matched: &SurfaceMatch,
    correspondence: &[Option<SurfacePoint>],
) -> TriMesh {
    let unit_a = matched.a.length_unit;
    // B's ℓ in the units of the surface that was matched (B × `scale_b`), back to B's own.
    let unit_b = matched.b.length_unit / matched.scale_b;
    let positions = correspondence
        .iter()
        .zip(&mesh_a.positions)
        .map(|(p, x)| match p {
            Some(s) => s.position(&mesh_b.positions, &mesh_b.triangles),
            None => matched
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

/// Writes the match folder: `correspondence.npy` (float64 (n_A, 4)),
/// `correspondence.csv` (`vertex,triangle,b0,b1,b2`), `A_on_B.obj`, `deformation.npy`
/// (float64 (n, n, 2): φ at the grid nodes, in ω_B) and `match.json` (the report).
/// `placed` is A on B from [`a_on_b`] (computed once by the caller, who may also draw
/// it). Every file is written to a temporary name and renamed into place; the folder is
/// created if missing. Returns the paths written.
pub fn write_match_folder(
    dir: &Path,
    matched: &SurfaceMatch,
    correspondence: &[Option<SurfacePoint>],
    placed: &TriMesh,
    report: &MatchReport,
) -> Result<Vec<std::path::PathBuf>, MatchError> {
    let io = |what: &str, e: &dyn std::fmt::Display| MatchError::Output(format!("{what}: {e}"));
    std::fs::create_dir_all(dir)
        .map_err(|e| io(&format!("cannot create {}", dir.display()), &e))?;
    // Everything is computed before the first file is written.
    let rows = correspondence_rows(correspondence);
    let n = matched.deformation.size;
    let phi: Vec<f64> = matched.grid_positions().iter().flat_map(|p| *p).collect();
    let json =
        serde_json::to_string_pretty(report).map_err(|e| io("cannot encode the report", &e))?;
    let mut csv = String::with_capacity(correspondence.len() * 48);
    csv.push_str("vertex,triangle,b0,b1,b2\n");
    for (v, r) in rows.chunks_exact(4).enumerate() {
        csv.push_str(&format!("{v},{},{},{},{}\n", r[0] as i64, r[1], r[2], r[3]));
    }
    let mut written = vec![];
    let mut file = |name: &str, f: &mut dyn FnMut(&Path) -> Result<(), MatchError>| {
        let path = dir.join(name);
        f(&path)?;
        written.push(path);
        Ok::<(), MatchError>(())
    };
    file(CORRESPONDENCE_FILE, &mut |p| {
        save_npy(p, &[correspondence.len(), 4], &rows)
            .map_err(|e| io(&format!("cannot write {}", p.display()), &e))
    })?;
    file("correspondence.csv", &mut |p| {
        write_atomically(p, |w| w.write_all(csv.as_bytes()))
            .map_err(|e| io(&format!("cannot write {}", p.display()), &e))
    })?;
    file("A_on_B.obj", &mut |p| {
        crate::mesh::io::write_obj(p, placed, None)
            .map_err(|e| io(&format!("cannot write {}", p.display()), &e))
    })?;
    file("deformation.npy", &mut |p| {
        save_npy(p, &[n, n, 2], &phi).map_err(|e| io(&format!("cannot write {}", p.display()), &e))
    })?;
    file(INFO_FILE, &mut |p| {
        write_atomically(p, |w| w.write_all(json.as_bytes()))
            .map_err(|e| io(&format!("cannot write {}", p.display()), &e))
    })?;
    Ok(written)
}
