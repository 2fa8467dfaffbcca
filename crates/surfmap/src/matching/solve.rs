//! The multiscale matching driver (thesis §3.2.4, Fig. 3.7) with the initial
//! alignment of the two parameter domains.
//!
//! Levels `k = k₀ … K` live on `(2^k + 1)²` grids; level `k` uses images filtered with
//! `σ_k = 2^−k` (the finest unfiltered) and the cut-off width `ε_k = 2^{1−k}` (thesis:
//! `ε = 2σ_k`; on the finest level, where `σ = 0`, two grid cells). Each level is
//! minimized by [`super::ncg`] and prolongated (exactly, as a P1 map) to the next; the
//! finest level stops at the looser [`NcgSettings::finest_tolerance`], and every level
//! within the same cost ([`NcgSettings::max_evaluations`]: 40 evaluations at 257², 160
//! at 129², …). Descent directions are taken in a Sobolev metric 4 cells of each level
//! wide; the coarsest level takes the first half of its iterations in one a quarter of
//! ω wide, which moves φ as a whole ([`COARSEST_SOBOLEV_WIDTH`]).
//!
//! Alignment: both flattenings preserve orientation, so ω_A and ω_B differ by a
//! similarity of the plane. With paired landmarks or features it is their
//! least-squares fit; otherwise the surfaces are aligned in space and the plane
//! similarity is fitted to the vertex pairs (`shape_alignment`). From that start a
//! search over similarities of φ on a coarse level may propose another start, which
//! the coarsest level's solve then accepts or rejects ([`super::similarity_search`]).

use rayon::prelude::*;
use serde::Serialize;

use super::MatchError;
use super::align::AlignmentScore;
use super::deformation::{Deformation, node};
use super::energy::{B_SD, B_X, Betas, LevelEnergy, Similarity3, Workspace, chi, robust};
use super::holes::add_hole_features;
use super::ncg::{LevelLog, NcgSettings, minimize};
use super::output::plausible_area_ratio;
use super::precondition::SobolevPreconditioner;
use super::rigid::{ClosestPoints, align_surfaces};
use super::similarity::{
    Similarity2, fit_affine_3d_near, fit_rotation_2d_at_scale, fit_similarity_2d,
    fit_similarity_2d_robust, fit_similarity_3d,
};
use super::similarity_search::{
    SearchWhen, SimilaritySearch, SimilaritySearchLog, matched_area, matched_area_ratio,
    search_similarity,
};
use super::surface::MatchSurface;
use crate::grid::Grid;
use crate::grid::pyramid::gaussian_filter_restricted;
use crate::mesh::validate::{Defect, DefectKind, validate};
use crate::mesh::{SurfacePoint, Topology, TriMesh};
use crate::raster::{FeatureCurve, FeatureFile};

/// Fewest paired features or landmarks (a landmark, or one curve's centroid, each a point
/// of the plane) from which [`Align::Auto`] aligns the planes by them; with fewer it
/// aligns the shapes in space and the features only guide the solve. One point fixes no
/// turn of the plane, two fix it poorly where the surfaces' flattenings differ around
/// them, and a similarity (4 unknowns) fitted to three or four cannot tell a misplaced
/// one from the others ([`fit_similarity_2d_robust`] drops one only from five on, keeping
/// four). Measured on the FLAME and ICT pairs given subsets of their landmarks
/// (BENCHMARKS.md, "Few landmarks"): from two mouth corners the features' start gave
/// 4–42 % within 0.05 where the shapes' gave 82–93 %; from three (the nose tip too)
/// 4–66 % where the shapes' gave 83–92 %; from four, 62 % on one pair against 84 %.
pub const FEATURES_TO_ALIGN: usize = 5;

/// How the initial similarity between ω_A and ω_B is found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Align {
    /// From the features/landmarks when [`FEATURES_TO_ALIGN`] or more are given, else
    /// from the surfaces' shapes ([`Align::Shape`]; fewer features still guide the
    /// solve).
    #[default]
    Auto,
    /// From the features/landmarks (an error with fewer than two: one point fixes no
    /// turn of the plane); two keep the size the meshes' units give.
    Features,
    /// From the surfaces' 3D shapes even when features are given: a rigid alignment
    /// in space by trimmed ICP ([`super::rigid`]) pairs the vertices, and their domain
    /// positions give the similarity of the planes.
    Shape,
    /// The domains as placed in ω (the thesis's "rough alignment").
    None,
}

/// Paired landmark points: `a[i]` on A corresponds to `b[i]` on B.
#[derive(Clone, Debug, PartialEq, serde::Deserialize, Serialize)]
pub struct Landmarks {
    pub names: Vec<String>,
    #[serde(rename = "A")]
    pub a: Vec<u32>,
    #[serde(rename = "B")]
    pub b: Vec<u32>,
}

impl Landmarks {
    /// The landmarks renumbered onto repaired meshes: `copies_a[v]` (`copies_b[v]`) is
    /// the repaired vertex of A (B) that stands for input vertex `v`
    /// ([`crate::mesh::repair::FaceOrigins::vertex_copies`]). An id beyond the input
    /// mesh, or whose vertex the repairs removed, is an error naming the landmark.
    pub fn renumbered(
        &self,
        copies_a: &[Option<u32>],
        copies_b: &[Option<u32>],
    ) -> Result<Self, MatchError> {
        let mut out = self.clone();
        for (side, ids, copies) in [("A", &mut out.a, copies_a), ("B", &mut out.b, copies_b)] {
            for (i, v) in ids.iter_mut().enumerate() {
                let name = self.names.get(i).map_or("?", |s| s.as_str());
                let Some(copy) = copies.get(*v as usize) else {
                    return Err(no_such_landmark_vertex(name, side, *v, copies.len()));
                };
                *v = copy.ok_or_else(|| {
                    MatchError::Guidance(format!(
                        "landmark '{name}': vertex {v} of {side} was removed by the repairs \
                         (every face around it went); pick a vertex of the part that is kept"
                    ))
                })?;
            }
        }
        Ok(out)
    }
}

/// A landmark whose vertex id is beyond its surface's `vertices`.
fn no_such_landmark_vertex(name: &str, side: &str, v: u32, vertices: usize) -> MatchError {
    MatchError::Guidance(format!(
        "landmark '{name}': vertex {v} of {side} does not exist ({side} has {vertices} vertices)"
    ))
}

/// Optional user guidance, paired by name between A and B.
#[derive(Clone, Debug, Default)]
pub struct Guidance {
    pub landmarks: Option<Landmarks>,
    pub features_a: Option<FeatureFile>,
    pub features_b: Option<FeatureFile>,
}

impl Guidance {
    /// Every vertex of A and of B the guidance names (feature curves' vertices, then
    /// landmarks), repeats included.
    pub fn vertices(&self) -> (Vec<u32>, Vec<u32>) {
        let curves = |f: &Option<FeatureFile>| -> Vec<u32> {
            f.iter()
                .flat_map(|f| f.features.iter().flat_map(|c| c.vertices.iter().copied()))
                .collect()
        };
        let (mut a, mut b) = (curves(&self.features_a), curves(&self.features_b));
        if let Some(lm) = &self.landmarks {
            a.extend(&lm.a);
            b.extend(&lm.b);
        }
        (a, b)
    }
}

/// Options of [`match_surfaces`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MatchOptions {
    /// Finest grid, `2^K + 1` nodes per side.
    pub size: usize,
    /// Coarsest level `k₀` (grid `2^k₀ + 1`). Default 6 (65²): once the surfaces are
    /// aligned in space ([`Align::Shape`]), the coarser levels (σ ≥ 1/16 of the domain)
    /// mostly let the blurred energy drag φ away from a good start — measured on the
    /// ICT pairs, starting at level 3 lost 8–37 points of the fraction within 0.05 on
    /// whole faces, while a partial pair gained 8 (BENCHMARKS.md, "Matching").
    pub coarsest_level: usize,
    pub betas: Betas,
    /// `(αl, αa)` of the regularization density (2.8).
    pub alpha: (f64, f64),
    /// Factor of B's metric far outside ω_B (thesis §2.2.5: a "softer" material).
    pub soft: f64,
    pub ncg: NcgSettings,
    pub align: Align,
    /// Rotations tried by the alignment search.
    pub align_rotations: usize,
    /// A search over plane similarities of φ before the solve; the solve goes on from
    /// the similarity found only when the coarsest level solved from it ends with a
    /// lower energy without matching less, at a plausible size when the alignment's
    /// start gives one ([`super::similarity_search`]).
    pub similarity_search: SimilaritySearch,
    /// Fill holes (eyes, mouth) for the flattenings.
    pub fill_holes: bool,
    /// Pair the rims of filled holes and match them as features.
    pub hole_features: HoleFeatures,
    /// Split each pair of elongated hole rims (mouth, eyes) at its two corners into two
    /// arcs matched as separate features when the more elongated rim's principal extents
    /// differ by at least this ratio ([`super::holes::split_rim_pair`]); 0: one closed curve
    /// per rim.
    pub split_hole_rims: f64,
    /// Let the position term's similarity scale (else a rigid motion).
    pub allow_scale: bool,
    /// The map of ℝ³ the position term compares the surfaces after: that similarity,
    /// or an affine map held near it ([`PositionMap`]).
    pub position_map: PositionMap,
    /// Cut-off width (ω units) of the position term around ω_B: B's harmonically
    /// extended positions keep pulling A's rim into place up to this far outside.
    pub position_band: f64,
    /// Vertices of A mapped within this many finest-grid cells of B's surface are
    /// snapped onto it ([`SurfaceMatch::correspondence`]).
    pub snap_cells: f64,
    /// Width (finest-grid cells) of the Gaussian applied to the mean curvature before
    /// the pyramid (0: the thesis's unfiltered finest level).
    pub curvature_sigma: f64,
    /// Scale τ (ℓ units) of the position term's robust penalty: residuals beyond it
    /// stop pulling (0: plain squares).
    pub position_scale: f64,
    /// Width σ (ω units) of the Gaussian that smooths the position term's residual
    /// into its target (`relief_offsets`, [`POSITION_RELIEF`]); 0: none (the
    /// surfaces compared after the fitted map alone).
    pub position_relief: f64,
    /// Sobolev preconditioner width in grid cells of each level (`λ = (w·h_k)²`);
    /// 0: plain L² gradients, as the thesis.
    pub sobolev_cells: f64,
    /// Width (ω units) of the wide metric the coarsest level descends in first, for
    /// half of its iterations, before it goes on in the local one (`sobolev_cells`):
    /// [`COARSEST_SOBOLEV_WIDTH`]; 0: the local metric throughout.
    pub coarsest_sobolev_width: f64,
    /// With three or more paired features or landmarks, also solve the coarsest level
    /// from the features' alignment refined in space, and go on from whichever start
    /// ends lower without matching less ([`FeatureStarts`]; with two, which align the
    /// planes only with [`Align::Features`], from the shapes' own alignment in space);
    /// not when the similarity search runs after the features' alignment
    /// ([`SearchWhen::Always`]), which then takes the coarsest level.
    pub features_in_space: bool,
    /// Report the vertices of image triangles that turn over or collapse in space as
    /// unmatched rather than wrong ([`super::output::check_folds`]).
    pub drop_folds: bool,
    /// Rings of A's vertices around each hole rim that follow the rim when it is
    /// carried exactly onto B's paired rim ([`super::rim_fit`]); 0 turns the fit off.
    pub rim_fit_rings: usize,
    /// Rings of unmatched vertices next to matched ones that rim completion may match
    /// from their neighbours ([`super::complete`]); 0 turns it off.
    pub complete_rings: usize,
    /// Largest distance (fraction of the vertex's mean edge length) from a completed
    /// vertex's predicted point to B ([`super::complete::COMPLETE_TOLERANCE`]).
    pub complete_tolerance: super::complete::Tolerance,
    /// Smoothing of the matched border before completion
    /// ([`super::complete::RimSmoothing`]).
    pub rim_smoothing: super::complete::RimSmoothing,
    /// Match the landmarks exactly in the reported correspondence, carrying the
    /// correction to the vertices around them ([`super::pin`]); φ is only guided.
    pub pin_landmarks: bool,
    /// How the position term's weight is set: from the surfaces' disagreement in space
    /// (default) or `betas.position` as given.
    pub position_weight: PositionWeight,
    /// B's size for the match: as given, or multiplied by a power of ten when the two
    /// surfaces are evidently in different units ([`ScaleB`]).
    pub scale_b: ScaleB,
}

/// How B's size is reconciled with A's before matching.
///
/// The matcher keeps the surfaces' relative size (one length unit for both: a crop of a
/// face is matched as the part of the whole it is), and aligns them in space by rigid
/// motions. Two scans in different units — a face in centimetres and another in metres —
/// are then 100 times apart in size: no rigid motion lays one onto the other, and the
/// result is a fold-free but meaningless map (measured on ICT crops, in cm, against FLAME
/// crops, in m: nose tip and mouth corners a mean 41–52 mm off; 2–6 mm with B scaled and
/// [`super::rigid::align_surfaces`]; BENCHMARKS.md, "Faces from two sources").
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ScaleB {
    /// B as given unless the sizes `√area` differ by more than [`UNIT_MISMATCH`] times;
    /// then B is multiplied by the power of ten nearest to `√(area A / area B)` (the
    /// usual unit mismatches, mm / cm / m, are powers of ten; the faces' own difference
    /// in size stays for the similarity to take up).
    Auto,
    /// B's positions multiplied by this factor (1: as given).
    Factor(f64),
}

/// Ratio of the surfaces' sizes `√area` beyond which [`ScaleB::Auto`] reads a unit
/// mismatch: 25 times the area — more than separates a face crop from a whole head in
/// one unit, less than the factor 10 in length between mm and cm.
pub const UNIT_MISMATCH: f64 = 5.0;

impl ScaleB {
    /// The factor B's positions are multiplied by, for surfaces of areas `area_a` and
    /// `area_b` (in their own units).
    pub fn factor(self, area_a: f64, area_b: f64) -> f64 {
        match self {
            ScaleB::Factor(f) => f,
            ScaleB::Auto => {
                let ratio = (area_a / area_b).sqrt();
                if !(ratio.is_finite() && ratio > 0.0)
                    || (1.0 / UNIT_MISMATCH..=UNIT_MISMATCH).contains(&ratio)
                {
                    1.0
                } else {
                    10f64.powf(ratio.log10().round())
                }
            }
        }
    }
}

/// How the weight `β_pos` of the position term is set.
///
/// The position term `β_pos ∫ χ |T(x_A) − x_B∘φ|² dA` (ours, beyond the thesis) is a
/// squared residual; read as a Gaussian likelihood its weight is the inverse variance of
/// the residual one expects at the right correspondence, and that depends on the pair:
/// two scans of one face, or registered identities that differ by millimetres, agree in
/// space almost everywhere; two different people do not, and there positions must give
/// way to curvature and metric. So by default
///
/// `β_pos = κ / clamp(σ, σ_min, σ_max)²`,
///
/// `σ` the RMS distance (ℓ units) between the surfaces along B's normals after their
/// best rigid alignment in space (trimmed point-to-plane ICP,
/// [`super::rigid::align_rigidly`]: [`super::rigid::RigidAlignment::plane_rms`]; along
/// A's normals when B, the much smaller surface, is laid onto A:
/// [`super::rigid::align_surfaces`]),
/// `κ` = [`POSITION_KAPPA`] (the term's value per unit area at a residual of `σ`
/// everywhere), `σ_min` = [`POSITION_RESIDUAL_FLOOR`] (a surface and a moved copy of
/// itself have `σ` ≈ 10⁻¹⁶: the weight stays at most `κ/σ_min²` = 2·10⁵) and `σ_max` =
/// [`POSITION_RESIDUAL_CAP`]: a larger residual is not trusted to mean "the shapes
/// differ" — on a partial overlap it also measures how ambiguous the overlap is, where
/// the positions are what anchors the match — so the weight never falls below
/// `κ/σ_max²` = 2000.
///
/// Along the normals, not to B's closest vertices: the distance from a point of A to
/// the nearest *vertex* of B grows with B's edges, so a coarser B read as a worse
/// agreement — the same two ICT faces 0.0059 ℓ apart at one resolution and 0.0076 ℓ with
/// B remeshed 1.6× coarser, against 0.0040 and 0.0041 ℓ along the normals. Measured in
/// BENCHMARKS.md ("The position weight from distances along the normals", three runs
/// each, both modes): with `κ` = 0.2 (the closest-vertex distances had 0.1; 0.1 and 0.3
/// measured too) ICT partial 95.4 → 97.9 % within 0.02 without input and 91.5 → 97.4
/// with landmarks, resolution 96.6 → 97.7 without input, FLAME partial with landmarks
/// 61.6 → 65.7; FLAME identity within 0.02 71.0 → 68.9 without input and 72.3 → 70.3
/// with landmarks (within 0.05 with landmarks 97.1 → 96.1). Earlier, with the
/// closest-vertex distance ("Matching": "The position term weighted by the shapes'
/// disagreement"): a fixed weight of 1000 was too weak for the ICT pairs and 10⁴ too
/// strong for the FLAME identities (−6 points within 0.05), and `κ/σ²` without the cap
/// lost 2.6 points on the FLAME partial pairs with landmarks.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PositionWeight {
    /// `β_pos = κ / clamp(σ, floor, cap)²` (above).
    FromShapeResidual { kappa: f64, floor: f64, cap: f64 },
    /// `betas.position` as given (the thesis energy alone with 0).
    Fixed,
}

/// Width (ω units) of the metric the coarsest level descends in first
/// ([`MatchOptions::coarsest_sobolev_width`]): a quarter of ω, 16 cells of 65².
///
/// The Sobolev metric `⟨u, v⟩ = ∫ u·v + L² ∇u : ∇v` smooths every descent direction
/// over a length `L`. In the local metric (4 cells of each level) the descent absorbs a
/// global misfit of the start — a few percent of scale or a few degrees between two
/// faces, which the rigid alignment in space cannot see — into local deformation and
/// settles there; in a metric a quarter of ω wide each step moves φ over whole regions,
/// so the misfit is corrected first. The wide metric resolves detail slowly, though (a
/// retriangulated copy of a surface matched to 0.76 cells instead of 0.53, and the
/// finer levels' budgets do not make up for it), so it takes the first half of the
/// coarsest level's iterations and the local metric the second half: at most the same
/// 300 iterations as before (a level that used to converge early now runs both halves).
/// Measured on the 18 ICT and 10 FLAME pairs without input
/// (BENCHMARKS.md, "A wide metric for the coarsest level"): within 0.02 / 0.05, ICT
/// partial 91.6 / 96.6 → 95.8 / 98.4 %, FLAME partial 57.3 / 82.9 → 62.0 / 87.2 %, ICT
/// resolution 96.0 → 96.6 % within 0.02; FLAME identity within 0.05 96.3 → 95.2 % (one
/// pair); the solve's time unchanged in the median over the 18 ICT pairs.
pub const COARSEST_SOBOLEV_WIDTH: f64 = 0.25;

/// `κ` of [`PositionWeight::FromShapeResidual`].
pub const POSITION_KAPPA: f64 = 0.2;

/// The map `T` of ℝ³ in the position term `β_pos ∫ χ |T(x_A) − x_B∘φ|² dA`, refitted
/// to the current φ every few iterations (weighted least squares over the matched
/// nodes, [`NcgSettings::refit_every`]).
///
/// Two faces of different people differ by more than a rotation and a scale — one is
/// wider, or longer, or deeper than the other — and what a similarity leaves unexplained
/// the position term reads as a reason to slide the correspondence (towards B's closest
/// points). An affine map takes up such global proportions; left free, though, it is
/// decided by noise along a direction in which the matched points barely spread (the
/// depth of a crop that keeps one side of a face) and then distorts the comparison
/// everywhere. So by default `T` is the affine map held near the similarity by a ridge
/// ([`super::similarity::fit_affine_3d_near`], ridge [`POSITION_AFFINE_RIDGE`]: along a
/// direction whose spread equals the mean spread of the three, data and similarity weigh
/// alike). Measured in BENCHMARKS.md ("Matching": "The position term's map: affine near
/// the similarity").
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PositionMap {
    /// A similarity (a rigid motion when `allow_scale` is off).
    Similarity,
    /// The affine map nearest the data with `ridge · tr C / 3 · ‖M − M_sim‖²` added.
    AffineNearSimilarity { ridge: f64 },
}

/// The width σ (ω units) of the position term's relief (`relief_offsets`): the
/// default (`MatchOptions::position_relief`, `surfmap match --relief`; 0 turns it off).
///
/// The fitted map `T` of ℝ³ explains the two faces' difference in pose and proportions
/// but not in shape — a higher forehead, a longer nose — and where the shapes differ the
/// term pulls φ towards B's closest points to `T(x_A)`, which slide off the counterpart on
/// every slope. With the relief the target is `T(x_A) + R`, `R` the residual
/// `x_B∘φ − T(x_A)` smoothed by a Gaussian of width σ: the smooth part of the difference
/// is taken as given and only the detail pulls, as a non-rigid ICP takes a smooth
/// deformation as free. But it takes the smooth part of *any* residual as given, a
/// start's error too, so the coarsest level first places φ without it (the wide, then
/// the local metric, as by default) and only then goes on with it, in a third phase in
/// the local metric (a coarsest level without the wide phase goes without it); the finer
/// levels use it throughout, and the starts the coarsest level compares are compared
/// without it (`Solver::plain_energy`). (With the relief
/// from the start, a crop that covers one side of a face drifted, and a start a quarter
/// too small — `the_wide_metric_grows_a_shrunken_start_into_place` — was not grown into
/// place.) Measured in BENCHMARKS.md ("Matching": "The position term's relief"): FLAME
/// identity without input 68.9 → 74.1 % within 0.02, the ICT tracks within a few tenths.
/// The default since it was measured as one (BENCHMARKS.md, "The relief as the default");
/// σ was chosen from 0.05 / 0.1 / 0.2 on the FLAME pairs.
pub const POSITION_RELIEF: f64 = 0.1;

/// With the relief ([`POSITION_RELIEF`]), the coarsest level's third phase (the one with
/// it) gets this fraction of the level's iterations and evaluation budget, and every level
/// between the coarsest and the finest [`RELIEF_MIDDLE_BUDGET`] of its budget. With the
/// relief the middle level (129²) no longer converges but descends slowly until its
/// budget (160 evaluations against 63 without, on an ICT identity pair) — work the finest
/// level largely redoes — and the third phase at half the iterations was the other half
/// of the relief's cost (+15 % of the solve, median over the 18 ICT pairs). At a quarter
/// and 0.6 the solve costs what it did without the relief (interleaved median ratios 0.90
/// against a half and the whole budget, 1.015 against no relief), and the three-run
/// accuracy is within 0.15 points of the longer schedule's (BENCHMARKS.md, "A cheaper
/// schedule for the relief").
pub const RELIEF_PHASE_FRACTION: f64 = 0.25;

/// The fraction of their evaluation budget that levels between the coarsest and the
/// finest get with the relief on ([`RELIEF_PHASE_FRACTION`]).
pub const RELIEF_MIDDLE_BUDGET: f64 = 0.6;

/// Ridge of [`PositionMap::AffineNearSimilarity`].
pub const POSITION_AFFINE_RIDGE: f64 = 1.0;

/// `σ_min` (ℓ units) of [`PositionWeight::FromShapeResidual`].
pub const POSITION_RESIDUAL_FLOOR: f64 = 0.001;

/// `σ_max` (ℓ units) of [`PositionWeight::FromShapeResidual`].
pub const POSITION_RESIDUAL_CAP: f64 = 0.01;

impl PositionWeight {
    /// `β_pos` for the surfaces' RMS distance `sigma` in space (ℓ units), given the
    /// options' `betas.position`: that weight when fixed, when it is 0 (the term turned
    /// off: the thesis energy) or when `sigma` is unknown (the surfaces could not be
    /// aligned in space).
    pub fn weight(self, given: f64, sigma: Option<f64>) -> f64 {
        match (self, sigma) {
            (PositionWeight::FromShapeResidual { kappa, floor, cap }, Some(sigma))
                if given != 0.0 && sigma.is_finite() =>
            {
                // (not `clamp`, which panics on a floor above the cap: the cap wins)
                kappa / sigma.max(floor).min(cap).powi(2)
            }
            _ => given,
        }
    }
}

impl Default for MatchOptions {
    fn default() -> Self {
        Self {
            size: 257,
            coarsest_level: 6,
            betas: Betas {
                bend: 1.0,
                reg: 0.01,
                features: 5.0,
                position: 1000.0,
                uncovered: 0.0,
            },
            alpha: (0.5, 0.5),
            soft: 0.1,
            ncg: NcgSettings::default(),
            align: Align::Auto,
            align_rotations: 24,
            similarity_search: SimilaritySearch::default(),
            fill_holes: true,
            hole_features: HoleFeatures::Auto,
            split_hole_rims: super::holes::SPLIT_HOLE_RIMS,
            allow_scale: true,
            position_map: PositionMap::AffineNearSimilarity {
                ridge: POSITION_AFFINE_RIDGE,
            },
            sobolev_cells: 4.0,
            coarsest_sobolev_width: COARSEST_SOBOLEV_WIDTH,
            features_in_space: true,
            position_band: 0.0,
            curvature_sigma: 0.0,
            snap_cells: SNAP_CELLS,
            position_scale: 0.0,
            position_relief: POSITION_RELIEF,
            drop_folds: true,
            rim_fit_rings: super::rim_fit::RIM_FIT_RINGS,
            complete_rings: super::complete::COMPLETE_RINGS,
            complete_tolerance: super::complete::COMPLETE_TOLERANCE,
            rim_smoothing: super::complete::RIM_SMOOTHING,
            pin_landmarks: true,
            position_weight: PositionWeight::FromShapeResidual {
                kappa: POSITION_KAPPA,
                floor: POSITION_RESIDUAL_FLOOR,
                cap: POSITION_RESIDUAL_CAP,
            },
            scale_b: ScaleB::Auto,
        }
    }
}

/// The alignment that was used.
#[derive(Clone, Debug, Serialize)]
pub struct AlignmentReport {
    pub method: String,
    pub similarity: Similarity2,
    /// Hole rims paired as features: `(hole of A, hole of B, distance of their centres
    /// in ω after the alignment)`.
    pub hole_pairs: Vec<super::holes::HolePair>,
    /// The hole pairs (indices into `hole_pairs`) matched as two arcs each, split at
    /// their corners ([`super::holes::split_rim_pair`]); the others as one closed curve.
    pub split_holes: Vec<usize>,
    /// Features/landmarks left out of the alignment's similarity fit because the others
    /// disagreed with them ([`fit_similarity_2d_robust`]); they still guide the solve.
    pub left_out: Vec<String>,
    /// The similarity search, when it ran and found a lower energy per matched area
    /// ([`MatchOptions::similarity_search`]); `kept` says whether the solve went on
    /// from it.
    pub search: Option<SimilaritySearchLog>,
    /// With features: the second start from their alignment refined in space, and
    /// which start the solve went on from ([`MatchOptions::features_in_space`]).
    pub features_in_space: Option<FeatureStarts>,
}

/// The coarsest level solved from two starts when features or landmarks are given.
///
/// The features' similarity of the planes (a least-squares fit of their positions in
/// ω_A and ω_B) trusts a handful of points, and in the flattened domains: where some of
/// them moved with the surface — the mouth corners of a face with its jaw open — it is
/// off in scale (ICT neutral → jaw open: ×1.12 where the vertex pairs below give
/// ×1.036), and the position term, refitted to that start, holds φ there (the chin, the
/// forehead and one ear left unmatched). The second start: the rigid motion of the
/// features' 3D centroids, refined by trimmed ICP over the whole surfaces
/// ([`super::rigid::align_surfaces`]), and the plane similarity of the vertex pairs it
/// makes (as [`Align::Shape`] does). It cannot see a difference in size, which the
/// features can (two ICT identities 5 % apart in size, B remeshed coarser: the features'
/// start ends at energy 1.80, the one from space at 2.79). So both are minimized on the
/// coarsest level, side by side, and the one from space is kept only when it ends with a
/// lower energy and matches at least the same area (the rule of the similarity search).
/// Measured over three runs on the 28 referee pairs with landmarks (BENCHMARKS.md, "Two
/// starts with landmarks"): ICT expression 93.6 / 97.8 → 95.3 / 98.6 % within 0.02 /
/// 0.05, partial 97.4 / 98.1 → 98.0 / 98.5, identity, resolution and the FLAME pairs
/// unchanged or better.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FeatureStarts {
    /// The plane similarity from the alignment in space.
    pub similarity: Similarity2,
    /// Root-mean-square distance (mesh units) between the surfaces along the normals
    /// after that alignment.
    pub plane_rms: f64,
    /// The coarsest level's energy at the end, from the features' start.
    pub energy_features: f64,
    /// The same from the start in space.
    pub energy_space: f64,
    /// Whether the solve went on from the start in space.
    pub kept: bool,
}

/// Whether the rims of filled holes (eyes, mouth) are paired across the surfaces and
/// matched as labelled features.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HoleFeatures {
    /// When both surfaces have the same number of holes and the rims pair up
    /// unambiguously after the alignment.
    #[default]
    Auto,
    /// Always (an error when the hole counts differ or the rims do not pair up).
    On,
    Off,
}

/// A computed match.
#[derive(Clone, Debug)]
pub struct SurfaceMatch {
    pub a: MatchSurface,
    pub b: MatchSurface,
    /// φ on the finest grid.
    pub deformation: Deformation,
    pub levels: Vec<LevelLog>,
    pub alignment: AlignmentReport,
    /// The position term's map at the end (A's ℓ units → B's ℓ units): a similarity, or
    /// an affine map near one ([`PositionMap`]).
    pub similarity: Similarity3,
    /// The position term's weight `β_pos` used ([`PositionWeight`]).
    pub position_weight: f64,
    /// The surfaces' RMS distance along B's normals after their rigid alignment (ℓ
    /// units), from which the position weight was set (`None` with a fixed weight).
    pub shape_residual: Option<f64>,
    pub min_det: f64,
    pub seconds_solve: f64,
    /// See [`MatchOptions::snap_cells`].
    pub snap_cells: f64,
    /// See [`MatchOptions::rim_fit_rings`].
    pub rim_fit_rings: usize,
    /// See [`MatchOptions::complete_rings`].
    pub complete_rings: usize,
    /// See [`MatchOptions::complete_tolerance`].
    pub complete_tolerance: super::complete::Tolerance,
    /// See [`MatchOptions::rim_smoothing`].
    pub rim_smoothing: super::complete::RimSmoothing,
    /// Landmark pairs `(vertex of A, vertex of B)` matched exactly in the output
    /// ([`super::pin`]); empty without landmarks or with
    /// [`MatchOptions::pin_landmarks`] off.
    pub pinned_landmarks: Vec<(u32, u32)>,
    /// The factor B's positions were multiplied by for the match ([`ScaleB`]; 1 when
    /// as given). `b` holds the scaled surface; the correspondence (triangles and
    /// barycentric coordinates of B) does not depend on it.
    pub scale_b: f64,
}

/// Points mapped within this many finest-grid cells of B's surface are snapped onto it
/// ([`SurfaceMatch::correspondence`]). Half a cell: a vertex of A one ring past B's crop
/// lies about one mesh edge (1–1.5 cells at 257²) outside ω_B, so a snap of 1.5 cells
/// matched it falsely; the vertices on B's rim that φ carries farther than half a cell
/// out are left to rim completion ([`super::complete`]), which tells the two apart by
/// their neighbours (measured in BENCHMARKS.md, "Hole rims split at their corners").
pub const SNAP_CELLS: f64 = 0.5;

/// `ε_k` of level `k`.
fn epsilon(k: usize) -> f64 {
    2.0 * 0.5f64.powi(k as i32)
}

/// Pairs the features of A and B by name (landmarks become point features named
/// `landmark:NAME`); returns both feature files and, for the alignment, the paired
/// domain positions (feature centroids).
fn paired_features(
    a: &TriMesh,
    b: &TriMesh,
    g: &Guidance,
) -> Result<(Option<FeatureFile>, Option<FeatureFile>), MatchError> {
    let mut fa: Vec<FeatureCurve> = g.features_a.as_ref().map_or(vec![], |f| f.features.clone());
    let mut fb: Vec<FeatureCurve> = g.features_b.as_ref().map_or(vec![], |f| f.features.clone());
    for f in &fa {
        if !fb.iter().any(|x| x.name == f.name) {
            return Err(MatchError::Guidance(format!(
                "feature '{}' is given on A but not on B; features are paired by name",
                f.name
            )));
        }
    }
    for f in &fb {
        if !fa.iter().any(|x| x.name == f.name) {
            return Err(MatchError::Guidance(format!(
                "feature '{}' is given on B but not on A; features are paired by name",
                f.name
            )));
        }
    }
    fb.sort_by_key(|f| fa.iter().position(|x| x.name == f.name));
    if let Some(lm) = &g.landmarks {
        if lm.a.len() != lm.b.len() || lm.a.len() != lm.names.len() {
            return Err(MatchError::Guidance(format!(
                "landmarks: {} names, {} ids on A, {} on B; give one id per name on each surface",
                lm.names.len(),
                lm.a.len(),
                lm.b.len()
            )));
        }
        for (i, name) in lm.names.iter().enumerate() {
            for (side, ids, mesh) in [("A", &lm.a, a), ("B", &lm.b, b)] {
                if ids[i] as usize >= mesh.num_vertices() {
                    return Err(no_such_landmark_vertex(
                        name,
                        side,
                        ids[i],
                        mesh.num_vertices(),
                    ));
                }
            }
            fa.push(FeatureCurve {
                name: format!("landmark:{name}"),
                vertices: vec![lm.a[i]],
                closed: false,
            });
            fb.push(FeatureCurve {
                name: format!("landmark:{name}"),
                vertices: vec![lm.b[i]],
                closed: false,
            });
        }
    }
    if fa.is_empty() {
        return Ok((None, None));
    }
    Ok((
        Some(FeatureFile { features: fa }),
        Some(FeatureFile { features: fb }),
    ))
}

/// Domain centroid of every feature of a surface.
fn feature_centroids(s: &MatchSurface, f: &FeatureFile) -> Vec<[f64; 2]> {
    curve_means(f, |v| s.vertex_domain_position(v))
}

/// The mean of `point(v)` over each feature curve's vertices `v`.
fn curve_means<const N: usize>(
    f: &FeatureFile,
    point: impl Fn(usize) -> [f64; N],
) -> Vec<[f64; N]> {
    f.features
        .iter()
        .map(|c| {
            let mut m = [0.0; N];
            for &v in &c.vertices {
                let p = point(v as usize);
                (0..N).for_each(|i| m[i] += p[i]);
            }
            m.map(|x| x / c.vertices.len() as f64)
        })
        .collect()
}

/// The one length unit ℓ of both surfaces (mesh units): the geometric mean of their
/// `√area`, `ℓ = (area_A · area_B)^¼`, so that the energy's balance (NOTES §2: curvature
/// in `1/ℓ`, metric in `ℓ²`) does not depend on the units and the surfaces' relative size
/// is kept.
pub(crate) fn shared_length_unit(area_a: f64, area_b: f64) -> f64 {
    (area_a * area_b).sqrt().sqrt()
}

/// Matches surface A onto surface B.
pub fn match_surfaces(
    mesh_a: &TriMesh,
    mesh_b: &TriMesh,
    guidance: &Guidance,
    options: &MatchOptions,
) -> Result<SurfaceMatch, MatchError> {
    let area_a = measurable_area(mesh_a, 'A')?;
    let area_b = measurable_area(mesh_b, 'B')?;
    let scale_b = options.scale_b.factor(area_a, area_b);
    if !(scale_b.is_finite() && scale_b > 0.0) {
        return Err(MatchError::Option(format!(
            "B's scale factor must be finite and positive, got {scale_b}"
        )));
    }
    let scaled_b;
    let mesh_b = if scale_b == 1.0 {
        mesh_b
    } else {
        let mut m = mesh_b.clone();
        for p in &mut m.positions {
            *p = p.map(|c| c * scale_b);
        }
        scaled_b = m;
        &scaled_b
    };
    let (fa, fb) = paired_features(mesh_a, mesh_b, guidance)?;
    let unit = shared_length_unit(area_a, mesh_b.area());
    if !(unit.is_finite() && unit > 0.0) {
        // Both areas were checked above: only B's scaling can get here.
        return Err(MatchError::Option(format!(
            "B scaled by {scale_b:e} has no finite area; give B a smaller scale"
        )));
    }
    let (sa, sb) = rayon::join(
        || {
            MatchSurface::new(
                mesh_a,
                fa.as_ref(),
                options.size,
                options.fill_holes,
                unit,
                options.curvature_sigma,
            )
        },
        || {
            MatchSurface::new(
                mesh_b,
                fb.as_ref(),
                options.size,
                options.fill_holes,
                unit,
                options.curvature_sigma,
            )
        },
    );
    let (sa, sb) = (
        sa.map_err(|e| e.of_surface('A'))?,
        sb.map_err(|e| e.of_surface('B'))?,
    );
    let mut matched = solve(sa, sb, fa.as_ref(), fb.as_ref(), options)?;
    matched.scale_b = scale_b;
    Ok(matched)
}

/// Refuses a surface whose area is zero or not finite (no faces, NaN coordinates, only
/// degenerate faces, coordinates so large that the area overflows) before anything is
/// computed: by the defects the flattening would name, with their remedies
/// ([`validate`]), else by its size. Returns the area.
fn measurable_area(mesh: &TriMesh, which: char) -> Result<f64, MatchError> {
    let area = mesh.area();
    if area.is_finite() && area > 0.0 {
        return Ok(area);
    }
    let defects: Vec<Defect> = validate(mesh, &Topology::new(mesh))
        .into_iter()
        .filter(|d| {
            matches!(
                d.kind,
                DefectKind::NonFiniteCoordinates
                    | DefectKind::NoFaces
                    | DefectKind::RepeatedIndexFaces
                    | DefectKind::ZeroAreaFaces
            )
        })
        .collect();
    if defects.is_empty() {
        let largest = mesh
            .positions
            .iter()
            .flatten()
            .fold(0.0f64, |m, c| m.max(c.abs()));
        return Err(MatchError::Input(format!(
            "surface {which}'s area is {area} (coordinates up to {largest:e} in size): it cannot \
             be measured in floating point; scale the surface to a smaller unit first"
        )));
    }
    Err(MatchError::Flatten {
        surface: Some(which),
        source: crate::param::flatten::FlattenError::NotADisc(defects),
    })
}

/// The landmark pairs among the paired features (point features named `landmark:NAME`,
/// [`paired_features`]): `(vertex of A, vertex of B)`.
fn landmark_pairs(fa: Option<&FeatureFile>, fb: Option<&FeatureFile>) -> Vec<(u32, u32)> {
    let (Some(fa), Some(fb)) = (fa, fb) else {
        return vec![];
    };
    fa.features
        .iter()
        .filter(|f| f.name.starts_with("landmark:") && f.vertices.len() == 1)
        .filter_map(|f| {
            let g = fb.features.iter().find(|g| g.name == f.name)?;
            (g.vertices.len() == 1).then(|| (f.vertices[0], g.vertices[0]))
        })
        .collect()
}

/// The multiscale solve on prepared surfaces.
pub fn solve(
    mut sa: MatchSurface,
    mut sb: MatchSurface,
    fa: Option<&FeatureFile>,
    fb: Option<&FeatureFile>,
    options: &MatchOptions,
) -> Result<SurfaceMatch, MatchError> {
    let clock = std::time::Instant::now();
    let top = sa.num_levels() - 1;
    if options.coarsest_level > top {
        return Err(MatchError::Option(format!(
            "coarsest level {} is finer than the finest grid (level {top})",
            options.coarsest_level
        )));
    }
    if options.similarity_search.when != SearchWhen::Off && options.similarity_search.level == 0 {
        return Err(MatchError::Option(
            "search level must be at least 1 (the similarity search's grid 2^k + 1), got 0".into(),
        ));
    }
    let k0 = options.coarsest_level;
    if options.hole_features == HoleFeatures::On {
        let (ha, hb) = (sa.hole_rims().len(), sb.hole_rims().len());
        if ha != hb || ha == 0 {
            return Err(MatchError::Guidance(format!(
                "hole features pair the rims one to one, but A has {ha} filled holes and B has {hb}; \
                 fill or cut the extra holes, or turn hole features off"
            )));
        }
    }
    // UVs are in mesh units and both meshes share ℓ: corresponding lengths match when
    // ω_A is scaled by the ratio of the domain transforms.
    let scale = sb.images.transform.scale / sa.images.transform.scale;
    // With fewer than FEATURES_TO_ALIGN features, `auto` aligns the shapes and the
    // features only guide.
    let features_given = fa.map_or(0, |f| f.features.len());
    let too_few_to_align = (1..FEATURES_TO_ALIGN).contains(&features_given);
    let use_features = match options.align {
        Align::Features => {
            if fa.is_none() {
                return Err(MatchError::Guidance(
                    "alignment from features needs features or landmarks".into(),
                ));
            }
            if features_given < 2 {
                return Err(MatchError::Guidance(
                    "alignment from features needs two or more features or landmarks: one \
                     fixes where A goes but not how it turns; give another, or align with \
                     `auto` (the shapes in space, the feature still guiding the solve)"
                        .into(),
                ));
            }
            true
        }
        Align::Auto => features_given >= FEATURES_TO_ALIGN,
        Align::Shape | Align::None => false,
    };
    // With features, the second start from their alignment refined in space
    // ([`FeatureStarts`]); its ICP also measures the position weight's residual.
    // With two features (no rigid motion in space from their centroids) that second start
    // is the shapes' own alignment.
    let in_space = match features_motion(&sa, &sb, fa, fb) {
        _ if !(use_features && options.features_in_space) => None,
        Some(start) => shape_alignment(&sa, &sb, scale, 1, Some(start)).ok(),
        None => shape_alignment(&sa, &sb, scale, options.align_rotations.max(1), None).ok(),
    };
    let (s, mut similarity, mut alignment, residual) = if use_features {
        let pa = feature_centroids(&sa, fa.unwrap());
        let pb = feature_centroids(&sb, fb.unwrap());
        let at_one_point =
            || MatchError::Guidance("the features/landmarks of A all lie at one point".into());
        // Two points (`Align::Features` only) fix the size poorly: two mouth corners lie
        // closer together on a closed mouth than on an open one (FLAME template →
        // registered: ×1.26 where the shapes give ×1.07; 42 % within 0.05, 93 % at the
        // size the meshes' units give), so two features keep that size (BENCHMARKS.md,
        // "Few landmarks").
        let (s, left_out) = if pa.len() >= 3 {
            fit_similarity_2d_robust(&pa, &pb).ok_or_else(at_one_point)?
        } else {
            (
                fit_rotation_2d_at_scale(&pa, &pb, scale).ok_or_else(at_one_point)?,
                vec![],
            )
        };
        let names = &fa.unwrap().features;
        let report = AlignmentReport {
            method: "features".into(),
            similarity: s,
            hole_pairs: vec![],
            split_holes: vec![],
            left_out: left_out.iter().map(|&i| names[i].name.clone()).collect(),
            search: None,
            features_in_space: in_space.as_ref().map(|x| FeatureStarts {
                similarity: x.0,
                plane_rms: x.3 * sa.length_unit,
                energy_features: f64::NAN,
                energy_space: f64::NAN,
                kept: false,
            }),
        };
        (
            s,
            Similarity3::identity(),
            report,
            in_space.as_ref().map(|x| x.3),
        )
    } else if options.align == Align::None {
        let s = Similarity2::identity();
        let report = AlignmentReport {
            method: "none".into(),
            similarity: s,
            hole_pairs: vec![],
            split_holes: vec![],
            left_out: vec![],
            search: None,
            features_in_space: None,
        };
        (s, Similarity3::identity(), report, None)
    } else {
        let (s, motion, mut report, residual) =
            shape_alignment(&sa, &sb, scale, options.align_rotations.max(1), None)?;
        if too_few_to_align && options.align == Align::Auto {
            report.method = format!(
                "{} ({features_given} of the {FEATURES_TO_ALIGN} features or landmarks it \
                 takes to align by them; they still guide the solve)",
                report.method
            );
        }
        (s, motion, report, Some(residual))
    };
    // The position term's weight from the surfaces' disagreement in space
    // ([`PositionWeight`]); the shape alignment measured it already.
    let shape_residual = match (options.position_weight, residual) {
        (PositionWeight::Fixed, _) => None,
        _ if options.betas.position == 0.0 => None,
        (_, Some(r)) => Some(r),
        _ => shape_residual(&sa, &sb, fa, fb),
    };
    let betas = Betas {
        position: options
            .position_weight
            .weight(options.betas.position, shape_residual),
        ..options.betas
    };
    if options.hole_features != HoleFeatures::Off {
        (alignment.hole_pairs, alignment.split_holes) = add_hole_features(
            &mut sa,
            &mut sb,
            &s,
            options.hole_features,
            options.split_hole_rims,
        )?;
    }
    let features: Vec<usize> = (0..sa.feature_curves.len()).collect();
    let solver = Solver {
        a: &sa,
        b: &sb,
        features: &features,
        options,
        betas,
        spent: Default::default(),
    };
    let search = match options.similarity_search.when {
        SearchWhen::Off => false,
        SearchWhen::Shape => !use_features && options.align != Align::None,
        SearchWhen::Always => true,
    };
    let mut phi = Deformation::from_map(sa.level_size(k0), |p| s.apply(p));
    let mut levels = vec![];
    for k in k0..=top {
        if k > k0 {
            phi = phi.prolongate();
        }
        if k == k0 && search {
            // The similarity search, when asked for with features (`SearchWhen::Always`),
            // takes the coarsest level instead of the start from space.
            let (log, searched) = solver.level_with_search(k0, s, &mut phi, &mut similarity);
            alignment.search = searched;
            alignment.features_in_space = None;
            levels.push(log);
        } else if k == k0
            && let Some((s_space, motion, _, _)) = &in_space
        {
            let starts =
                solver.level_from_two_starts(k0, &mut phi, &mut similarity, s_space, motion);
            if let Some(f) = alignment.features_in_space.as_mut() {
                (f.energy_features, f.energy_space, f.kept) = starts.1;
            }
            levels.push(starts.0);
        } else {
            levels.push(solver.level(k, &mut phi, &mut similarity));
        }
    }
    let min_det = phi.min_jacobian_determinant();
    Ok(SurfaceMatch {
        a: sa,
        b: sb,
        deformation: phi,
        levels,
        alignment,
        similarity,
        position_weight: betas.position,
        shape_residual,
        min_det,
        seconds_solve: clock.elapsed().as_secs_f64(),
        snap_cells: options.snap_cells,
        rim_fit_rings: options.rim_fit_rings,
        complete_rings: options.complete_rings,
        complete_tolerance: options.complete_tolerance,
        rim_smoothing: options.rim_smoothing,
        pinned_landmarks: if options.pin_landmarks {
            landmark_pairs(fa, fb)
        } else {
            vec![]
        },
        scale_b: 1.0,
    })
}

/// The similarity of the planes from a rigid alignment of the surfaces in space
/// ([`super::rigid`]): every vertex of A within the trimmed pairs' distance of B is paired
/// with its closest vertex of B, and the least-squares similarity of their domain
/// positions is refitted once without the pairs it explains worst (beyond three times
/// the median residual). Also returns the rigid motion, in ℓ units, as the start of the
/// position term's map. The rigid alignment is searched from many starts, or refined
/// from `refine_from` (an A → B motion in mesh units) alone.
fn shape_alignment(
    sa: &MatchSurface,
    sb: &MatchSurface,
    scale: f64,
    rotations: usize,
    refine_from: Option<Similarity3>,
) -> Result<(Similarity2, Similarity3, AlignmentReport, f64), MatchError> {
    let unit = sa.length_unit;
    let starts: Vec<Similarity3> = if refine_from.is_some() {
        vec![]
    } else {
        // Extra ICP starts: the rigid motions of the best similarities of the planes
        // (a search over rotations, translations and scales of ω_A scored by the 3D
        // fit, [`super::align`]); they reach poses that the rotations about the
        // centroids miss when the surfaces overlap only in part.
        let ks = 5.min(sa.num_levels() - 1);
        let eps = epsilon(ks);
        let level_a = sa.level_a(ks, eps, &[]);
        let level_b = sb.level_b(ks, eps, 1.0, &[]);
        let inside: Vec<bool> = level_a.chi.iter().map(|&c| c == 1.0).collect();
        let (ca, _) = sa.domain_centroid_and_area();
        let (cb, _) = sb.domain_centroid_and_area();
        let search = AlignmentScore::new(&level_a, &level_b, &inside, false);
        let (found, _) = search.search(ca, cb, scale, rotations, 8);
        found
            .iter()
            .filter(|c| c.score.is_finite())
            .map(|c| Similarity3 {
                matrix: c.motion.matrix,
                translation: c.motion.translation.map(|t| t * unit),
            })
            .collect()
    };
    let rigid = align_surfaces(
        (&sa.positions, &sa.triangles),
        (&sb.positions, &sb.triangles),
        &starts,
        refine_from,
    )
    .ok_or_else(|| {
        MatchError::Guidance("cannot align the surfaces in space: too few vertices".into())
    })?;
    let closest = ClosestPoints::new(&sb.positions);
    let limit = (2.5 * rigid.rms).powi(2);
    let step = (sa.positions.len() / 4000).max(1);
    let mut pa = vec![];
    let mut pb = vec![];
    for v in (0..sa.positions.len()).step_by(step) {
        let (w, d2) = closest.closest(&rigid.motion.apply(sa.positions[v]));
        if d2 <= limit {
            pa.push(sa.vertex_domain_position(v));
            pb.push(sb.vertex_domain_position(w));
        }
    }
    let fail =
        || MatchError::Guidance("the surfaces do not overlap after aligning them in space".into());
    let mut s = fit_similarity_2d(&pa, &pb).ok_or_else(fail)?;
    let residual = |s: &Similarity2, a: &[f64; 2], b: &[f64; 2]| {
        let y = s.apply(*a);
        (y[0] - b[0]).hypot(y[1] - b[1])
    };
    let mut r: Vec<f64> = pa
        .iter()
        .zip(&pb)
        .map(|(a, b)| residual(&s, a, b))
        .collect();
    let mut sorted = r.clone();
    sorted.sort_by(f64::total_cmp);
    let cut = 3.0 * sorted[sorted.len() / 2];
    let keep: Vec<usize> = (0..r.len()).filter(|&i| r[i] <= cut).collect();
    if keep.len() >= 3 {
        let qa: Vec<[f64; 2]> = keep.iter().map(|&i| pa[i]).collect();
        let qb: Vec<[f64; 2]> = keep.iter().map(|&i| pb[i]).collect();
        s = fit_similarity_2d(&qa, &qb).ok_or_else(fail)?;
        r = keep.iter().map(|&i| residual(&s, &pa[i], &pb[i])).collect();
    }
    let motion = Similarity3 {
        matrix: rigid.motion.matrix,
        translation: rigid.motion.translation.map(|t| t / unit),
    };
    let report = AlignmentReport {
        method: format!(
            "shape: trimmed ICP in space (RMS {:.4} mesh units to the closest vertices, {:.4} along the normals), {} vertex pairs, domain residual median {:.4}",
            rigid.rms,
            rigid.plane_rms,
            r.len(),
            {
                let mut x = r.clone();
                x.sort_by(f64::total_cmp);
                x[x.len() / 2]
            }
        ),
        similarity: s,
        hole_pairs: vec![],
        split_holes: vec![],
        left_out: vec![],
        search: None,
        features_in_space: None,
    };
    Ok((s, motion, report, rigid.plane_rms / unit))
}

/// The RMS distance (ℓ units) along B's normals between the surfaces after their best
/// rigid alignment in space: trimmed ICP from the rigid motion of the paired features'
/// 3D centroids when there are three or more, else from the usual starts
/// ([`align_surfaces`], either way round); `None` when they cannot be aligned.
fn shape_residual(
    sa: &MatchSurface,
    sb: &MatchSurface,
    fa: Option<&FeatureFile>,
    fb: Option<&FeatureFile>,
) -> Option<f64> {
    let start = features_motion(sa, sb, fa, fb);
    align_surfaces(
        (&sa.positions, &sa.triangles),
        (&sb.positions, &sb.triangles),
        &[],
        start,
    )
    .map(|rigid| rigid.plane_rms / sa.length_unit)
}

/// The rigid motion (mesh units) that best carries the paired features' 3D centroids of
/// A onto B's, when there are three or more.
fn features_motion(
    sa: &MatchSurface,
    sb: &MatchSurface,
    fa: Option<&FeatureFile>,
    fb: Option<&FeatureFile>,
) -> Option<Similarity3> {
    match (fa, fb) {
        (Some(fa), Some(fb)) if fa.features.len() >= 3 => {
            let pa = curve_means(fa, |v| sa.positions[v]);
            let pb = curve_means(fb, |v| sb.positions[v]);
            fit_similarity_3d(&pa, &pb, &vec![1.0; pa.len()], false)
        }
        _ => None,
    }
}

struct Solver<'s> {
    a: &'s MatchSurface,
    b: &'s MatchSurface,
    features: &'s [usize],
    options: &'s MatchOptions,
    /// The energy's weights (`options.betas` with the position weight set,
    /// [`PositionWeight`]).
    betas: Betas,
    /// Energy evaluations spent so far, in finest-level evaluations (one on a grid `2^j`
    /// times coarser counts `4^-j`), for [`NcgSettings::total_evaluations`]: the bits of
    /// an `f64`, atomic so that two levels can be minimized at once
    /// ([`Solver::level_with_search`]).
    spent: std::sync::atomic::AtomicU64,
}

impl Solver<'_> {
    fn energy(&self, k: usize, similarity: Similarity3) -> LevelEnergy {
        let eps = epsilon(k);
        LevelEnergy {
            a: self.a.level_a(k, eps, self.features),
            b: self.b.level_b(k, eps, self.options.soft, self.features),
            epsilon: eps,
            betas: self.betas,
            alpha: self.options.alpha,
            similarity,
            position_offset: vec![],
            relief: false,
            position_band: self.options.position_band,
            position_scale: self.options.position_scale,
        }
    }

    /// Refits the position term's map of `e` to `phi` (when the term is on).
    fn refit(&self, e: &mut LevelEnergy, phi: &Deformation) {
        if self.betas.position != 0.0
            && let Some(s) = fit_position_map(e, phi, self.options)
        {
            e.similarity = s;
            if self.options.position_relief > 0.0 && e.relief {
                e.position_offset = relief_offsets(e, phi, self.options.position_relief);
            }
        }
    }

    /// The coarsest level `k0` with the similarity search ([`super::similarity_search`]):
    /// the search runs on level [`SimilaritySearch::level`] from the alignment's
    /// similarity `s`; when it finds a lower energy per matched area, level `k0` is
    /// solved from both starts, and the searched one is kept (in `phi` and
    /// `similarity`) only when its solve ends with a lower energy *and* at least the
    /// same matched area, *and* — when the alignment's solve matches A at a plausible
    /// size ([`plausible_area_ratio`] of [`matched_area_ratio`]) — does too. `phi` is
    /// `s` on level `k0`'s grid.
    fn level_with_search(
        &self,
        k0: usize,
        s: Similarity2,
        phi: &mut Deformation,
        similarity: &mut Similarity3,
    ) -> (LevelLog, Option<SimilaritySearchLog>) {
        let settings = &self.options.similarity_search;
        let ks = settings.level.min(k0);
        let mut searched_similarity = *similarity;
        let mut energy = self.energy(ks, searched_similarity);
        let mut start = Deformation::from_map(self.a.level_size(ks), |p| s.apply(p));
        let found = search_similarity(&mut energy, &mut start, settings, &mut |e, phi| {
            self.refit(e, phi)
        });
        let Some(mut found) = found else {
            return (self.level(k0, phi, similarity), None);
        };
        searched_similarity = energy.similarity;
        let moved = found.similarity.after(&s);
        let mut other = Deformation::from_map(phi.size, |p| moved.apply(p));
        let (from_alignment, from_search) = self.level_from_both(
            k0,
            (phi, similarity),
            (&mut other, &mut searched_similarity),
        );
        // Kept only when it dominates — a lower energy without matching less — and
        // matches A at a plausible size whenever the alignment's start does (the ICT
        // face crop squeezed to a tenth of its area on a whole head ended lower:
        // BENCHMARKS.md).
        // Both measures read level k0's data only (not the position term's similarity),
        // so one level serves both starts.
        let level = self.energy(k0, *similarity);
        found.area_ratio_alignment = matched_area_ratio(&level, phi);
        found.area_ratio_search = matched_area_ratio(&level, &other);
        let plausible = |r: Option<f64>| r.is_some_and(plausible_area_ratio);
        found.implausible_size =
            plausible(found.area_ratio_alignment) && !plausible(found.area_ratio_search);
        found.kept = self.second_ends_lower(
            k0,
            (phi, *similarity, from_alignment.end.total),
            (&other, searched_similarity, from_search.end.total),
        ) && matched_area(&level, &other) >= matched_area(&level, phi)
            && !found.implausible_size;
        if found.kept {
            *phi = other;
            *similarity = searched_similarity;
            (from_search, Some(found))
        } else {
            (from_alignment, Some(found))
        }
    }

    /// The coarsest level `k0` solved from `phi` (the features' start) and from the
    /// start in space `s_space` (with `motion`, the position term's start) side by side
    /// ([`FeatureStarts`]): the second is kept (in `phi` and `similarity`) only when it
    /// ends with a lower energy and matches at least the same area. Returns the kept
    /// start's log and (energy from the features, energy from space, kept).
    fn level_from_two_starts(
        &self,
        k0: usize,
        phi: &mut Deformation,
        similarity: &mut Similarity3,
        s_space: &Similarity2,
        motion: &Similarity3,
    ) -> (LevelLog, (f64, f64, bool)) {
        let mut other = Deformation::from_map(phi.size, |p| s_space.apply(p));
        let mut other_similarity = *motion;
        let (from_features, from_space) =
            self.level_from_both(k0, (phi, similarity), (&mut other, &mut other_similarity));
        let level = self.energy(k0, *similarity);
        let kept = self.second_ends_lower(
            k0,
            (phi, *similarity, from_features.end.total),
            (&other, other_similarity, from_space.end.total),
        ) && matched_area(&level, &other) >= matched_area(&level, phi);
        let energies = (from_features.end.total, from_space.end.total, kept);
        if kept {
            *phi = other;
            *similarity = other_similarity;
            (from_space, energies)
        } else {
            (from_features, energies)
        }
    }

    /// Level `k` minimized from two starts at once, each on its own φ and position
    /// similarity, with the budget left before both (charged together afterwards).
    fn level_from_both(
        &self,
        k: usize,
        first: (&mut Deformation, &mut Similarity3),
        second: (&mut Deformation, &mut Similarity3),
    ) -> (LevelLog, LevelLog) {
        let spent = self.spent();
        let ((log_first, cost_first), (log_second, cost_second)) = rayon::join(
            || self.level_charged(k, first.0, first.1, spent),
            || self.level_charged(k, second.0, second.1, spent),
        );
        self.charge(cost_first + cost_second);
        (log_first, log_second)
    }

    /// Minimizes level `k` from `phi` (already on level k's grid).
    fn level(&self, k: usize, phi: &mut Deformation, similarity: &mut Similarity3) -> LevelLog {
        let (log, cost) = self.level_charged(k, phi, similarity, self.spent());
        self.charge(cost);
        log
    }

    /// Whether the second of two solves of level `k` (each: its φ, its position map and
    /// the energy its solve ended with) ends lower: by [`Solver::plain_energy`] when the
    /// relief is on, else by the solves' own final energies.
    fn second_ends_lower(
        &self,
        k: usize,
        first: (&Deformation, Similarity3, f64),
        second: (&Deformation, Similarity3, f64),
    ) -> bool {
        match (
            self.plain_energy(k, first.0, first.1),
            self.plain_energy(k, second.0, second.1),
        ) {
            (Some(f), Some(s)) => s < f,
            _ => second.2 < first.2,
        }
    }

    /// The energy of level `k` at `phi` with the position term's map refitted and no
    /// relief ([`relief_offsets`]): what two starts are compared by, since the relief
    /// absorbs the smooth part of a start's error along with the surfaces' difference.
    /// `None` when the relief is off (the solves' own final energies compare alike).
    fn plain_energy(&self, k: usize, phi: &Deformation, similarity: Similarity3) -> Option<f64> {
        if self.options.position_relief <= 0.0 {
            return None;
        }
        let mut e = self.energy(k, similarity);
        e.relief = false;
        self.refit(&mut e, phi);
        let mut grad = vec![[0.0; 2]; phi.displacement.len()];
        Some(
            e.evaluate(&phi.displacement, &mut grad, &mut Workspace::default())
                .total,
        )
    }

    /// Evaluations spent so far ([`Solver::spent`]).
    fn spent(&self) -> f64 {
        f64::from_bits(self.spent.load(std::sync::atomic::Ordering::Relaxed))
    }

    /// Adds `cost` finest-level evaluations to [`Solver::spent`].
    fn charge(&self, cost: f64) {
        let total = self.spent() + cost;
        self.spent
            .store(total.to_bits(), std::sync::atomic::Ordering::Relaxed);
    }

    /// Minimizes level `k` from `phi` with the budget left after `spent` evaluations;
    /// returns its log and its cost in finest-level evaluations, not yet charged.
    fn level_charged(
        &self,
        k: usize,
        phi: &mut Deformation,
        similarity: &mut Similarity3,
        spent: f64,
    ) -> (LevelLog, f64) {
        let mut energy = self.energy(k, *similarity);
        let mut refit = |e: &mut LevelEnergy, phi: &Deformation| self.refit(e, phi);
        let n = phi.size;
        let metric =
            |width: f64| (width > 0.0).then(|| SobolevPreconditioner::new(n, width * width));
        let local = metric(self.options.sobolev_cells / (n - 1) as f64);
        let mut settings = self.options.ncg;
        if k == self.a.num_levels() - 1 {
            settings.tolerance = settings.finest_tolerance;
        }
        let coarsest = k == self.options.coarsest_level;
        if coarsest {
            settings.window = settings.coarsest_window;
        }
        let finest = self.a.level_size(self.a.num_levels() - 1);
        let cost = ((n - 1) as f64 / (finest - 1) as f64).powi(2);
        let mut budget = settings.level_evaluations(n, finest);
        let relief = self.options.position_relief > 0.0;
        if relief && !coarsest && n < finest && budget != usize::MAX {
            budget = (budget as f64 * RELIEF_MIDDLE_BUDGET).ceil() as usize;
        }
        if settings.total_evaluations > 0 {
            let left = (settings.total_evaluations as f64 - spent).max(0.0);
            budget = budget.min((left / cost) as usize);
        }
        let mut run = |max_iterations: usize,
                       budget: usize,
                       metric: Option<&SobolevPreconditioner>,
                       relief: bool| {
            let settings = NcgSettings {
                max_iterations,
                ..settings
            };
            energy.relief = relief;
            minimize(&mut energy, phi, &settings, budget, k, metric, &mut refit)
        };
        let wide = self.options.coarsest_sobolev_width;
        let log = if coarsest && wide > 0.0 {
            // First the wide metric, then the local one, half of the iterations and
            // of the evaluations each ([`COARSEST_SOBOLEV_WIDTH`]).
            let first = run(
                settings.max_iterations.div_ceil(2),
                budget.div_ceil(2),
                metric(wide).as_ref(),
                false,
            );
            let second = run(
                settings.max_iterations / 2,
                budget.saturating_sub(first.evaluations),
                local.as_ref(),
                false,
            );
            if relief {
                // With the relief, a third phase in the local metric: only once φ is
                // placed without it ([`POSITION_RELIEF`]), and shorter
                // ([`RELIEF_PHASE_FRACTION`]).
                let share = |count: usize| (count as f64 * RELIEF_PHASE_FRACTION).ceil() as usize;
                let third = run(
                    share(settings.max_iterations),
                    share(budget),
                    local.as_ref(),
                    true,
                );
                first.then(second).then(third)
            } else {
                first.then(second)
            }
        } else {
            run(settings.max_iterations, budget, local.as_ref(), !coarsest)
        };
        *similarity = energy.similarity;
        let charged = log.evaluations as f64 * cost;
        (log, charged)
    }
}

/// The map of ℝ³ ([`PositionMap`]) that best carries A's positions onto B's matched
/// positions, weighted by the node weights and `χ^ε`.
fn fit_position_map(
    e: &LevelEnergy,
    phi: &Deformation,
    options: &MatchOptions,
) -> Option<Similarity3> {
    let n = e.size();
    let mut p = Vec::with_capacity(n * n);
    let mut q = Vec::with_capacity(n * n);
    let mut w = Vec::with_capacity(n * n);
    for k in 0..n * n {
        let wa = e.a.weight[k] * e.a.chi[k];
        if wa == 0.0 {
            continue;
        }
        let s = e.b.field.sample(phi.at(k));
        let c = chi(s[B_SD], e.epsilon).0;
        if c == 0.0 {
            continue;
        }
        let x = [s[B_X], s[B_X + 1], s[B_X + 2]];
        // Iteratively reweighted: the robust penalty's weight at the current residual.
        let y = e.similarity.apply(e.a.x[k]);
        let r2 = (0..3).map(|i| (y[i] - x[i]).powi(2)).sum::<f64>();
        p.push(e.a.x[k]);
        q.push(x);
        w.push(wa * c * robust(r2, e.position_scale).1);
    }
    let similarity = fit_similarity_3d(&p, &q, &w, options.allow_scale)?;
    match options.position_map {
        PositionMap::Similarity => Some(similarity),
        PositionMap::AffineNearSimilarity { ridge } => {
            fit_affine_3d_near(&p, &q, &w, &similarity, ridge).or(Some(similarity))
        }
    }
}

/// The smooth part of the position term's residual, per node: with
/// `r = x_B∘φ − T(x_A)` over the nodes both surfaces cover (weights `w·χ`),
/// `R = G_σ * (w r) / G_σ * (w)`. Added to `T(x_A)`, it lets the position term compare
/// the surfaces after their smooth difference in shape (one forehead higher, one nose
/// longer than the other) instead of pulling φ towards B's closest points under one
/// global map; what is left to pull is the residual's detail.
pub(crate) fn relief_offsets(e: &LevelEnergy, phi: &Deformation, width: f64) -> Vec<[f64; 3]> {
    let n = e.size();
    let data: Vec<[f64; 4]> = (0..n * n)
        .into_par_iter()
        .map(|k| {
            let wa = e.a.weight[k] * e.a.chi[k];
            if wa == 0.0 {
                return [0.0; 4];
            }
            let sb = e.b.field.sample(phi.at(k));
            let w = wa * chi(sb[B_SD], e.epsilon).0;
            if w == 0.0 {
                return [0.0; 4];
            }
            let y = e.similarity.apply(e.a.x[k]);
            [
                w * (sb[B_X] - y[0]),
                w * (sb[B_X + 1] - y[1]),
                w * (sb[B_X + 2] - y[2]),
                w,
            ]
        })
        .collect();
    let peak = data.iter().map(|d| d[3]).fold(0.0, f64::max);
    // A wide Gaussian is computed on every `step`-th row and column (σ at least 4 of
    // their spacings) and read back bilinearly: 1/16 of the work at 257².
    let sigma = width * (n - 1) as f64;
    let mut step = 1;
    while (8 * step) as f64 <= sigma
        && (n - 1).is_multiple_of(2 * step)
        && (n - 1) / (2 * step) >= 16
    {
        step *= 2;
    }
    let smooth = gaussian_filter_restricted(&Grid::from_parts(n, data), sigma, step);
    let floor = 1e-3 * peak;
    (0..n * n)
        .into_par_iter()
        .map(|k| {
            let d = smooth.sample(node(n, k));
            if d[3] > floor {
                [d[0] / d[3], d[1] / d[3], d[2] / d[3]]
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

impl SurfaceMatch {
    /// φ(ξ) for a point ξ of ω_A.
    pub fn map_domain(&self, xi: [f64; 2]) -> [f64; 2] {
        self.deformation.apply(xi)
    }

    /// For every vertex of A, its matched point on B in B's mesh units (bilinear in
    /// B's position image), or `None` where φ leaves ω_B.
    pub fn vertex_points(&self) -> Vec<Option<[f64; 3]>> {
        let field = self.b.finest_position_and_distance();
        (0..self.a.uvs.len())
            .map(|v| {
                let xi = self.a.vertex_domain_position(v);
                let y = self.map_domain(xi);
                let s = field.sample(y);
                (s[3] <= 0.0).then_some([s[0], s[1], s[2]])
            })
            .collect()
    }

    /// For every vertex of A, its counterpart on B (a triangle of B and barycentric
    /// coordinates), or `None` where φ maps it outside B's surface (beyond ω_B's border
    /// or into one of B's holes). A point that φ puts within [`SNAP_CELLS`] grid cells
    /// of B's surface is snapped onto it: a vertex on A's rim lies exactly on ω_A's
    /// border, and at the grid's resolution "on the border" and "just outside" are the
    /// same answer. Around the holes A's rims are first carried exactly onto B's
    /// ([`super::rim_fit`]).
    pub fn correspondence(&self) -> Result<Vec<Option<SurfacePoint>>, MatchError> {
        Ok(self.fitted_correspondence()?.0)
    }

    /// [`SurfaceMatch::correspondence`] and what its rim fit did.
    pub fn fitted_correspondence(
        &self,
    ) -> Result<(Vec<Option<SurfacePoint>>, super::rim_fit::RimFit), MatchError> {
        let map = super::output::PointMap::new(self)?;
        let mut images: Vec<[f64; 2]> = self.a.uvs.par_iter().map(|&uv| map.image(uv)).collect();
        let fit = super::rim_fit::fit_hole_rims(&self.a, &self.b, &mut images, self.rim_fit_rings);
        Ok((images.par_iter().map(|&y| map.locate(y)).collect(), fit))
    }

    /// Node positions of φ (for pictures).
    pub fn grid_positions(&self) -> Vec<[f64; 2]> {
        let n = self.deformation.size;
        (0..n * n)
            .map(|k| self.deformation.at(k))
            .collect::<Vec<_>>()
    }

    /// Fraction of grid nodes used (for reports): ξ itself.
    pub fn node(&self, k: usize) -> [f64; 2] {
        node(self.deformation.size, k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::bumpy_disc;

    /// The relief is the smooth part of the residual `x_B∘φ − T(x_A)`: B's positions
    /// are A's moved by a constant `c` plus a node checkerboard `±δ` (detail at the
    /// grid's own scale) — the offsets must be `c` to within a small fraction of `δ`,
    /// on grids where the Gaussian is computed in full (65²) and restricted (257²:
    /// every 4th row and column), and with B's cover cut to half of ω (no weight
    /// beyond x = ½: the offsets up to one σ past the cut are read from the covered
    /// part, still `c`; far beyond it, where the Gaussian's weight has died out, 0).
    /// (`χ_A = 1` and the node weights halve on ω's border, so the normalization is
    /// exercised too.)
    #[test]
    fn the_relief_is_the_smooth_part_of_the_residual() {
        let c = [0.03, -0.02, 0.01];
        let delta = 0.01;
        for (n, cut) in [(65, false), (257, false), (257, true)] {
            let mut e = crate::matching::energy::tests::self_match(n);
            let mut field = e.b.field.as_slice().to_vec();
            for (k, v) in field.iter_mut().enumerate() {
                let (i, j) = (k / n, k % n);
                let sign = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
                for a in 0..3 {
                    v[B_X + a] += c[a] + sign * delta;
                }
                if cut && node(n, k)[0] > 0.5 {
                    v[B_SD] = 1.0;
                }
            }
            e.b.field = Grid::from_vec(n, field).unwrap();
            let phi = Deformation::identity(n);
            let offsets = relief_offsets(&e, &phi, 0.1);
            let x = |k: usize| node(n, k)[0];
            let worst = (0..n * n)
                .filter(|&k| !cut || x(k) <= 0.6)
                .flat_map(|k| {
                    let o = offsets[k];
                    (0..3).map(move |a| (o[a] - c[a]).abs())
                })
                .fold(0.0, f64::max);
            assert!(worst < 0.02 * delta, "n {n} cut {cut}: worst {worst}");
            if cut {
                assert!(
                    (0..n * n)
                        .filter(|&k| x(k) > 0.95)
                        .all(|k| offsets[k] == [0.0; 3])
                );
            }
        }
    }

    /// A surface and a re-triangulated copy: the true plane similarity is fitted to
    /// the domain positions of every vertex of A and B's nearest vertex (the same point
    /// in space). Started 12° and 10 % in scale off it, the search must find it, and
    /// the coarsest level must end near it from whichever start it keeps.
    #[test]
    fn the_search_brings_a_turned_and_scaled_start_back() {
        let (mesh_a, mesh_b) = (bumpy_disc(18, 0.4), bumpy_disc(23, 0.4));
        let unit = shared_length_unit(mesh_a.area(), mesh_b.area());
        let options = MatchOptions {
            size: 129,
            ..Default::default()
        };
        let surface = |m: &TriMesh| MatchSurface::new(m, None, 129, true, unit, 0.0).unwrap();
        let (sa, sb) = (surface(&mesh_a), surface(&mesh_b));
        let closest = ClosestPoints::new(&sb.positions);
        let (pa, pb): (Vec<[f64; 2]>, Vec<[f64; 2]>) = (0..sa.positions.len())
            .map(|v| {
                let (w, _) = closest.closest(&sa.positions[v]);
                (sa.vertex_domain_position(v), sb.vertex_domain_position(w))
            })
            .unzip();
        let truth = fit_similarity_2d(&pa, &pb).unwrap();
        let (ca, _) = sa.domain_centroid_and_area();
        let off = Similarity2::about(truth.apply(ca), 12f64.to_radians(), 1.1, truth.apply(ca));
        let start = off.after(&truth);
        let solver = Solver {
            a: &sa,
            b: &sb,
            features: &[],
            options: &options,
            betas: options.betas,
            spent: Default::default(),
        };
        let k0 = options.coarsest_level;
        let mut phi = Deformation::from_map(sa.level_size(k0), |p| start.apply(p));
        let mut similarity = Similarity3::identity();
        let (_, found) = solver.level_with_search(k0, start, &mut phi, &mut similarity);
        let found = found.expect("the search lowers the energy");
        let moved = found.similarity.after(&start);
        let angle = (moved.angle() - truth.angle()).to_degrees();
        let scale = moved.scale() / truth.scale();
        assert!(
            angle.abs() < 2.0 && (scale - 1.0).abs() < 0.02,
            "{angle}° and scale {scale} off the truth ({found:?})"
        );
        // φ over A's vertices against the truth, in cells of the 65² grid.
        let cell = 1.0 / (phi.size - 1) as f64;
        let mut off_truth: Vec<f64> = pa
            .iter()
            .map(|&p| {
                let (y, t) = (phi.apply(p), truth.apply(p));
                (y[0] - t[0]).hypot(y[1] - t[1]) / cell
            })
            .collect();
        off_truth.sort_by(f64::total_cmp);
        let median = off_truth[off_truth.len() / 2];
        assert!(median < 0.5, "median {median} cells off the truth");
    }
}
