//! Stage 5, **report**: everything a match says about itself, from what the earlier
//! stages computed — counts, the area A's matched part covers on B, the fold check,
//! what post-processing did, the alignment, how far each paired feature ends from B's
//! ([`feature_fit`]), the solve's levels — as [`MatchReport`] (`match.json`, the
//! Python result's dictionary), with a verdict on how far it can be trusted ([`confidence`])
//! and the doubts about single features worded for the user.

pub mod confidence;
pub mod feature_fit;
mod summary;

use serde::Serialize;

use super::options::MatchOptions;
use super::post::Correspondence;
use super::post::rim_fit::RimFit;
use super::prepare::Prepared;
use super::solve::ncg::LevelLog;
use super::solve::{Solved, plausible_area_ratio};
use crate::vec3::{cross3 as cross, norm3 as norm, sub3 as sub};

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
    /// The meshes matched, as given.
    pub inputs: Inputs,
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
    /// How far the match can be trusted: a verdict, its reasons and the measures it was
    /// drawn from ([`confidence`]).
    pub confidence: confidence::Confidence,
    /// Doubts about the result, worded for the user (empty when none): see
    /// [`feature_fit::feature_warnings`] (the match as a whole: [`Self::confidence`]).
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
    /// so moved (`crate::matching::post::rim_fit`).
    pub rim_fit: RimFit,
    /// Vertices matched by rim completion from their neighbours
    /// (`crate::matching::post::complete`; included in `matched_vertices_a`).
    pub completed_vertices: usize,
    /// Matched vertices next to unmatched ones moved by the rim smoothing before
    /// completion (`crate::matching::options::RimSmoothing`).
    pub smoothed_vertices: usize,
    /// Landmarks matched exactly to their vertex of B in the output (`crate::matching::post::pin`), and
    /// the largest distance (B's units) φ had left one of them from it.
    pub pinned_landmarks: usize,
    pub largest_landmark_miss: f64,
    pub alignment: super::AlignmentReport,
    /// Every paired feature (curves, landmarks, hole rims paired automatically): the
    /// mean distance (B's units) from A's curve, carried into ω_B, to B's, at the start
    /// of the solve and after it (`super::feature_fit`); empty without features.
    pub feature_fit: Vec<super::FeatureFit>,
    /// The position term's map of ℝ³ at the end (a similarity, or an affine map near
    /// one: `super::PositionMap`), A's length units to B's (both in the shared unit ℓ).
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
    /// (the CLI's `--crop-overlap`, `crate::matching::prepare::overlap`); the cut vertices of A are
    /// unmatched in the outputs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overlap_crop: Option<super::prepare::overlap::OverlapCrops>,
    /// For the summary: A's size over B's (`√area` of the meshes matched, B in its own
    /// units), whether the caller repaired the meshes, and the whole match's time.
    #[serde(skip)]
    pub(crate) size_ratio: f64,
    #[serde(skip)]
    pub(crate) repaired: bool,
    #[serde(skip)]
    pub(crate) seconds_total: f64,
}

/// The two meshes a match was made from, as given (before any repair or crop): a
/// match folder is used only with these (`transfer`, `morph`, `rig` refuse others).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct Inputs {
    pub a: InputMesh,
    pub b: InputMesh,
}

/// One mesh a match was made from.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct InputMesh {
    /// The file it was read from (set by the command line; `null` from arrays).
    pub path: Option<String>,
    pub vertices: usize,
    pub faces: usize,
    /// [`crate::TriMesh::content_sha256`]: the same for the same mesh in any format.
    pub sha256: String,
}

impl InputMesh {
    /// The record of `mesh` (no path).
    pub fn of(mesh: &crate::TriMesh) -> Self {
        Self {
            path: None,
            vertices: mesh.num_vertices(),
            faces: mesh.triangles.len(),
            sha256: mesh.content_sha256(),
        }
    }
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

impl MatchReport {
    /// Counts `n` more vertices of A unmatched for folds (a fold check after the
    /// report was made: `crate::matching::post::post`).
    pub fn count_dropped(&mut self, n: usize) {
        self.dropped_vertices += n;
        self.matched_vertices_a -= n.min(self.matched_vertices_a);
        self.matched_fraction_a = self.matched_vertices_a as f64 / self.vertices_a.max(1) as f64;
    }
}

/// The stage (module docs): the report of a match, its counts of the meshes matched
/// (with what the fold check on the meshes as given unmatched after a crop taken off).
pub(crate) fn report(
    p: &Prepared<'_>,
    solved: &Solved,
    c: &Correspondence,
    options: &MatchOptions,
    seconds_solve: f64,
) -> MatchReport {
    let checked = &c.checked;
    let (a, b) = (&p.a, &p.b);
    let correspondence = &checked.points;
    let folds = &checked.folds;
    let matched = correspondence.iter().filter(|p| p.is_some()).count();
    let mut covered = 0.0;
    let mut matched_area_a = 0.0;
    let mut area_b = 0.0;
    for t in &b.triangles {
        let [p, q, r] = t.map(|i| b.positions[i as usize]);
        area_b += 0.5 * norm(cross(sub(q, p), sub(r, p)));
    }
    for t in &a.triangles {
        let pts = t.map(|v| correspondence[v as usize]);
        if let [Some(p), Some(q), Some(r)] = pts {
            let [p, q, r] = [p, q, r].map(|s| s.position(&b.positions, &b.triangles));
            covered += 0.5 * norm(cross(sub(q, p), sub(r, p)));
            let [p, q, r] = t.map(|v| a.positions[v as usize]);
            matched_area_a += 0.5 * norm(cross(sub(q, p), sub(r, p)));
        }
    }
    let area_ratio = (matched_area_a > 0.0).then(|| covered / matched_area_a);
    let feature_fit = feature_fit::feature_fits(a, b, solved, p.scale_b);
    let warnings = feature_fit::feature_warnings(&feature_fit);
    let levels: Vec<LevelSummary> = solved.levels.iter().map(LevelSummary::from).collect();
    let mut report = MatchReport {
        inputs: Inputs {
            a: InputMesh::of(p.given_a),
            b: InputMesh::of(p.given_b),
        },
        vertices_a: correspondence.len(),
        vertices_b: b.positions.len(),
        matched_vertices_a: matched,
        matched_fraction_a: matched as f64 / correspondence.len().max(1) as f64,
        covered_fraction_b: (covered / area_b.max(f64::MIN_POSITIVE)).min(1.0),
        area_ratio,
        confidence: confidence::Confidence::default(),
        warnings,
        holes_filled_a: a.filled_holes,
        holes_filled_b: b.filled_holes,
        min_det: solved.min_det,
        flipped_triangles: folds.flipped.len(),
        collapsed_triangles: folds.collapsed.len(),
        dropped_vertices: checked.dropped,
        rim_fit: checked.rim_fit,
        completed_vertices: checked.completion.completed,
        smoothed_vertices: checked.completion.smoothed,
        pinned_landmarks: checked.pinning.landmarks,
        largest_landmark_miss: checked.pinning.largest_miss,
        alignment: solved.alignment.clone(),
        feature_fit,
        similarity: solved.similarity,
        position_weight: solved.position_weight,
        shape_residual: solved.shape_residual,
        scale_b: p.scale_b,
        length_unit: a.length_unit,
        grid_size: solved.deformation.size,
        iterations: levels.iter().map(|l| l.iterations).sum(),
        energy: levels.last().map_or(f64::NAN, |l| l.energy_end.total),
        levels,
        seconds_flatten: a.flatten_time + b.flatten_time,
        seconds_images: a.time_images + b.time_images,
        seconds_solve,
        options: options.clone(),
        input_numbering: None,
        overlap_crop: None,
        size_ratio: (p.mesh_a.area() / p.mesh_b.area()).sqrt(),
        repaired: p.repaired,
        seconds_total: 0.0,
    };
    report.count_dropped(c.dropped_as_given);
    let unit = a.length_unit;
    let disagreements = super::solve::curvature_disagreements(a, b, solved, options);
    let fit = confidence::similarity_residual(
        (&a.positions, &a.triangles),
        (&b.positions, &b.triangles),
        correspondence,
        solved.pose.as_ref(),
        unit,
    );
    report.confidence = confidence::Confidence::of(
        confidence::Measures {
            residual: fit.map(|f| f.0 / area_b.sqrt()),
            pose_offset: fit.and_then(|f| f.1).map(|o| o / area_b.sqrt()),
            residual_ratio: None,
            curvature_disagreement: disagreements.finest,
            coarse_disagreement: disagreements.coarse,
            unrelated_disagreement: disagreements.unrelated,
            energy: report.energy / (matched_area_a / (unit * unit)).max(f64::MIN_POSITIVE),
            matched_fraction_a: report.matched_fraction_a,
            covered_fraction_b: report.covered_fraction_b,
            area_ratio: report.area_ratio,
            landmark_miss: report
                .feature_fit
                .iter()
                .filter_map(super::FeatureFit::landmark_miss)
                .reduce(f64::max),
        }
        .with_shape_residual(solved.shape_residual, unit / area_b.sqrt()),
    );
    if let Some(r) = &p.renumbering {
        report.overlap_crop = p.crops.clone();
        report.input_numbering = Some(InputNumbering {
            vertices_a: p.given_a.num_vertices(),
            vertices_b: p.given_b.num_vertices(),
            triangles_b: p.given_b.triangles.len(),
            removed_vertices_a: r.copies_a.iter().filter(|c| c.is_none()).count(),
        });
    }
    report
}
