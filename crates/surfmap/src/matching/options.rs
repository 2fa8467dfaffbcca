//! What a user sets for a match ([`MatchOptions`]): the grid size, the energy's
//! weights, the alignment, how guidance and holes are used, the crop, B's units, what
//! the output keeps — the flags of `surfmap match` and the keywords of the Python
//! `match`, one setting each — checked in one place ([`MatchOptions::validate`],
//! [`OptionError`], which a front end words with its own spelling of the setting).
//!
//! Below them, the internal tuning (`Tuning`): the values the solve and the
//! post-processing were measured with, each a named constant with the reason for its
//! value; tests vary them, users do not.

use serde::Serialize;

use super::energy::Betas;

/// Fewest paired features or landmarks (a landmark, or one curve's centroid, each a point
/// of the plane) from which [`Align::Auto`] aligns the planes by them; with fewer it
/// aligns the shapes in space and the features only guide the solve. One point fixes no
/// turn of the plane, two fix it poorly where the surfaces' flattenings differ around
/// them, and a similarity (4 unknowns) fitted to three or four cannot tell a misplaced
/// one from the others (`fit_similarity_2d_robust` drops one only from five on, keeping
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

/// What a user sets for [`super::match_meshes`]; `MatchOptions::default()` is what
/// `surfmap match` does without flags. Set fields on a default value
/// (`let mut o = MatchOptions::default(); o.size = 129;`); [`MatchOptions::validate`]
/// checks them (so does every match).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MatchOptions {
    /// Finest grid, `2^K + 1` nodes per side (default 257; 65 at least).
    pub size: usize,
    /// The weights β of the energy's terms (thesis 2.16).
    pub weights: Weights,
    /// The weight of the 3D position term (ours, beyond the thesis).
    pub position_weight: PositionWeight,
    /// Where φ starts.
    pub align: Align,
    /// With landmarks or features: whether the coarsest level is also solved from
    /// their alignment refined in space ([`FeaturesStart`]).
    pub features_start: FeaturesStart,
    /// When the similarity search looks for a better start ([`SearchWhen`]).
    pub similarity_search: SearchWhen,
    /// Most energy evaluations per level, counted at the finest level (a level `2^j`
    /// times coarser may use `4^j` times as many); 0: every level runs to its stopping
    /// rule (the thesis's). Default 40 ([`BUDGET`]).
    pub budget: usize,
    /// Fill holes (eyes, mouth) for the flattenings (else a surface with holes is refused).
    pub fill_holes: bool,
    /// Pair the rims of filled holes across the surfaces and match them as features.
    pub hole_features: HoleFeatures,
    /// Match a pair of elongated hole rims (a mouth, an eye) as two arcs split at
    /// their corners, upper lip to upper lip (else as one closed curve each).
    pub split_hole_rims: bool,
    /// Cut each surface down to the part it shares with the other first (a whole head
    /// against a face crop: [`super::prepare::overlap`]); not with [`HoleFeatures::On`],
    /// whose rims are paired as given.
    pub crop_overlap: bool,
    /// B's size for the match ([`ScaleB`]).
    pub scale_b: ScaleB,
    /// Keep the vertices of image triangles that turn over or collapse in space (by
    /// default they are reported unmatched: [`super::folds`]).
    pub keep_folds: bool,
    /// Match each landmark exactly to its vertex of B in the output, the vertices
    /// around it following (else where φ puts it).
    pub pin_landmarks: bool,
    /// Refuse a match whose verdict is not `ok` ([`super::Confidence`]): the match
    /// comes back as the error [`super::MatchError::NotTrusted`].
    pub strict: bool,
    /// Settings of the solve and the post-processing that rarely need changing.
    pub advanced: Advanced,
    #[serde(skip)]
    pub(crate) tuning: Tuning,
}

/// The weights β of the matching energy (thesis 2.16) a user sets: bending
/// (curvature), regularization (the metric's distortion) and features.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Weights {
    pub bending: f64,
    pub regularization: f64,
    pub features: f64,
}

impl Weights {
    /// Three weights `[bending, regularization, features]` (`surfmap match --beta B,R,F`).
    pub fn from_slice(b: &[f64]) -> Result<Self, OptionError> {
        match *b {
            [bending, regularization, features] => Ok(Self {
                bending,
                regularization,
                features,
            }),
            _ => Err(OptionError::Weights(b.to_vec())),
        }
    }
}

impl Default for Weights {
    fn default() -> Self {
        Self {
            bending: 1.0,
            regularization: 0.01,
            features: 5.0,
        }
    }
}

/// With landmarks or features, where the coarsest level starts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FeaturesStart {
    /// From the features' similarity of the planes and (with three or more, or two with
    /// [`Align::Features`]) from their alignment refined in space: both are solved on
    /// the coarsest level and the second kept when it ends lower without matching less
    /// ([`super::FeatureStarts`]).
    #[default]
    Both,
    /// From the features' similarity of the planes alone.
    Plane,
}

/// Settings of the solve and the post-processing that rarely need changing.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Advanced {
    /// Rings of A's vertices around each hole rim that follow the rim when it is
    /// carried exactly onto B's paired rim; 0 leaves the rims where φ puts them
    /// ([`RIM_FIT_RINGS`]).
    pub rim_fit_rings: usize,
    /// Rings of unmatched vertices next to matched ones that may be completed from
    /// their matched neighbours where φ just misses B; 0 turns it off
    /// ([`COMPLETE_RINGS`]).
    pub complete_rings: usize,
    /// How far past B's outer rim (in mean edges of the vertex) a completed vertex's
    /// prediction may fall and still be matched to the rim: ½ keeps partial
    /// correspondence, more matches more of A along a tight crop of B (and more vertices
    /// that have no counterpart).
    pub rim_tolerance: f64,
    /// Width (a fraction of the parameter square) of the Gaussian that smooths the
    /// position term's residual into its target, so that only the surfaces' detail
    /// pulls ([`POSITION_RELIEF`]); 0: off, in [0, 1].
    pub relief: f64,
    /// Level `k` of the similarity search's energy (grid `2^k + 1`; 1 to the solve's
    /// coarsest level, 6).
    pub search_level: usize,
    /// Extra starts of the similarity search: rotated by ±`[0]` degrees and scaled by
    /// (1 ± `[1]`); `[0, 0]` searches from the start alone.
    pub search_candidates: [f64; 2],
    /// When the verdict is not `ok`, try other starts before reporting
    /// (`crate::matching::recover`): the other poses of the alignment in space and the
    /// start turned, the whole match made again from the most promising. Not with
    /// [`Align::None`], where the user fixed the start.
    pub recover: bool,
    /// When a mouth opens between the surfaces (one much more open than the other), let
    /// the lip arcs lead: features weighted more, the automatic position weight capped
    /// (`crate::matching::align::mouth`).
    pub open_mouth: bool,
}

impl Default for Advanced {
    fn default() -> Self {
        Self {
            rim_fit_rings: RIM_FIT_RINGS,
            complete_rings: COMPLETE_RINGS,
            rim_tolerance: RIM_TOLERANCE,
            relief: POSITION_RELIEF,
            search_level: SEARCH_LEVEL,
            search_candidates: [0.0, 0.0],
            recover: true,
            open_mouth: true,
        }
    }
}

/// The default [`MatchOptions::budget`]: 40 evaluations on the finest level (640 at
/// 65², 160 at 129²). Measured over the referee's 18 ICT pairs and the 10 FLAME pairs,
/// the evaluations beyond it on the two finest levels (120 before) changed no track's
/// fraction within 0.01, 0.02 or 0.05 nor its mean error beyond the run-to-run noise,
/// and took a quarter of the solve; at 25 the partial pairs lost 1–3 points
/// (BENCHMARKS.md, "Matching").
pub const BUDGET: usize = 40;

/// The default level of the similarity search's energy ([`Advanced::search_level`]):
/// 17², where a start's misfit of a few degrees still shows and a candidate costs little.
pub const SEARCH_LEVEL: usize = 4;

/// A setting of [`MatchOptions`] that cannot be used, with the value given.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum OptionError {
    Size(usize),
    Weights(Vec<f64>),
    PositionWeight(f64),
    RimTolerance(f64),
    Relief(f64),
    SearchLevel(usize),
    SearchCandidates(Vec<f64>),
    ScaleB(f64),
}

impl OptionError {
    /// The setting, as the Python `match` spells it (`surfmap match` with `--` and
    /// hyphens).
    pub fn setting(&self) -> &'static str {
        match self {
            OptionError::Size(_) => "size",
            OptionError::Weights(_) => "beta",
            OptionError::PositionWeight(_) => "position_weight",
            OptionError::RimTolerance(_) => "rim_tolerance",
            OptionError::Relief(_) => "relief",
            OptionError::SearchLevel(_) => "search_level",
            OptionError::SearchCandidates(_) => "search_candidates",
            OptionError::ScaleB(_) => "scale_b",
        }
    }

    /// The message with the setting spelled `name` (`--beta`, `beta`, …).
    pub fn worded(&self, name: &str) -> String {
        match self {
            OptionError::Size(n) => format!(
                "{name}: grid size {n} is not 2^k + 1 nodes per side with k ≥ 6 (65, 129, 257, 513, …)"
            ),
            OptionError::Weights(b) if b.len() != 3 => format!(
                "{name} takes three weights B,R,F (bending, regularization, features; default 1,0.01,5), got {}",
                b.len()
            ),
            OptionError::Weights(b) => format!("{name}: weights must be finite and ≥ 0, got {b:?}"),
            OptionError::PositionWeight(w) => format!("{name} must be finite and ≥ 0, got {w}"),
            OptionError::RimTolerance(e) => format!(
                "{name} must be a finite number of edges ≥ 0 (default {}), got {e}",
                COMPLETE_TOLERANCE.elsewhere
            ),
            OptionError::Relief(w) => format!(
                "{name} must be a width in [0, 1] of the parameter square (0: off; {POSITION_RELIEF} \
                 is what BENCHMARKS.md measured), got {w}"
            ),
            OptionError::SearchLevel(k) => format!(
                "{name}: the search level must be at least 1 and at most the solve's coarsest \
                 level, {COARSEST_LEVEL} (the similarity search's grid 2^k + 1), got {k}"
            ),
            OptionError::SearchCandidates(c) => {
                format!("{name} takes DEG,SCALE: degrees ≥ 0 and a scale step in [0, 1), got {c:?}")
            }
            OptionError::ScaleB(f) => {
                format!("{name} takes `auto` or a positive factor (1: B as given), got {f}")
            }
        }
    }
}

impl std::fmt::Display for OptionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.worded(self.setting()))
    }
}

impl std::error::Error for OptionError {}

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
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PositionWeight {
    /// `β_pos = κ / clamp(σ, σ_min, σ_max)²` (above).
    #[default]
    Auto,
    /// This weight (0: the term off, the thesis energy alone).
    Fixed(f64),
}

/// Width (ω units) of the metric the coarsest level descends in first
/// (`Tuning::coarsest_sobolev_width`): a quarter of ω, 16 cells of 65².
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
pub(crate) const COARSEST_SOBOLEV_WIDTH: f64 = 0.25;

/// `κ` of `PositionWeight::FromShapeResidual`.
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
pub(crate) enum PositionMap {
    /// A similarity (a rigid motion when `allow_scale` is off).
    /// Compared with the affine map in a test (`other_proportions_…`); not used otherwise.
    #[cfg_attr(not(test), allow(dead_code))]
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
pub(crate) const RELIEF_PHASE_FRACTION: f64 = 0.25;

/// The fraction of their evaluation budget that levels between the coarsest and the
/// finest get with the relief on ([`RELIEF_PHASE_FRACTION`]).
pub(crate) const RELIEF_MIDDLE_BUDGET: f64 = 0.6;

/// Ridge of [`PositionMap::AffineNearSimilarity`].
pub(crate) const POSITION_AFFINE_RIDGE: f64 = 1.0;

/// `σ_min` (ℓ units) of `PositionWeight::FromShapeResidual`.
pub const POSITION_RESIDUAL_FLOOR: f64 = 0.001;

/// `σ_max` (ℓ units) of `PositionWeight::FromShapeResidual`.
pub const POSITION_RESIDUAL_CAP: f64 = 0.01;

impl PositionWeight {
    /// `β_pos` for the surfaces' RMS distance `sigma` in space (ℓ units): the fixed
    /// weight, or `κ / clamp(σ, σ_min, σ_max)²`; [`POSITION_WEIGHT_UNALIGNED`] when the
    /// surfaces could not be aligned in space (`sigma` unknown).
    pub(crate) fn weight(self, sigma: Option<f64>) -> f64 {
        match (self, sigma) {
            (PositionWeight::Fixed(w), _) => w,
            (PositionWeight::Auto, Some(sigma)) if sigma.is_finite() => {
                POSITION_KAPPA
                    / sigma
                        .clamp(POSITION_RESIDUAL_FLOOR, POSITION_RESIDUAL_CAP)
                        .powi(2)
            }
            _ => POSITION_WEIGHT_UNALIGNED,
        }
    }
}

/// The position weight when the surfaces could not be aligned in space to measure how
/// far apart they are (too few vertices): the fixed weight matches were made with before
/// the weight was measured (BENCHMARKS.md, "Matching").
pub(crate) const POSITION_WEIGHT_UNALIGNED: f64 = 1000.0;

impl Default for MatchOptions {
    fn default() -> Self {
        Self {
            size: 257,
            weights: Weights::default(),
            position_weight: PositionWeight::Auto,
            align: Align::Auto,
            features_start: FeaturesStart::Both,
            similarity_search: SearchWhen::Shape,
            budget: BUDGET,
            fill_holes: true,
            hole_features: HoleFeatures::Auto,
            split_hole_rims: true,
            crop_overlap: true,
            scale_b: ScaleB::Auto,
            keep_folds: false,
            pin_landmarks: true,
            strict: false,
            advanced: Advanced::default(),
            tuning: Tuning::default(),
        }
    }
}

/// The internal tuning of a match: what the solve and the post-processing were measured
/// with (each value's constant says why). Not a user's setting; tests vary it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Tuning {
    /// Coarsest level `k₀` ([`COARSEST_LEVEL`]).
    pub coarsest_level: usize,
    /// `(αl, αa)` of the regularization density (2.8).
    pub alpha: (f64, f64),
    /// Factor of B's metric far outside ω_B (thesis §2.2.5: a "softer" material).
    pub soft: f64,
    /// One level's minimization (its `max_evaluations` is [`MatchOptions::budget`]).
    pub ncg: NcgSettings,
    /// Rotations tried by the alignment search.
    pub align_rotations: usize,
    /// The similarity search's rounds, iterations and tolerance.
    pub search: SimilaritySearch,
    /// Let the position term's map scale (else a rigid motion).
    pub allow_scale: bool,
    /// The map of ℝ³ the position term compares the surfaces after ([`PositionMap`]).
    pub position_map: PositionMap,
    /// Vertices of A mapped within this many finest-grid cells of B's surface are
    /// snapped onto it ([`SNAP_CELLS`]).
    pub snap_cells: f64,
    /// Sobolev preconditioner width in grid cells of each level (`λ = (w·h_k)²`);
    /// 0: plain L² gradients, as the thesis.
    pub sobolev_cells: f64,
    /// Width (ω units) of the wide metric the coarsest level descends in first
    /// ([`COARSEST_SOBOLEV_WIDTH`]; 0: the local metric throughout).
    pub coarsest_sobolev_width: f64,
    /// Rim completion's tolerances by where on B the closest point lies (the outer
    /// rim's is [`Advanced::rim_tolerance`]; [`COMPLETE_TOLERANCE`]).
    pub complete_tolerance: Tolerance,
    /// Smoothing of the matched border before completion ([`RIM_SMOOTHING`]).
    pub rim_smoothing: RimSmoothing,
}

/// The coarsest level `k₀` of the solve (grid `2^k₀ + 1`): 6 (65²). Once the surfaces
/// are aligned in space ([`Align::Shape`]), the coarser levels (σ ≥ 1/16 of the domain)
/// mostly let the blurred energy drag φ away from a good start — measured on the ICT
/// pairs, starting at level 3 lost 8–37 points of the fraction within 0.05 on whole
/// faces, while a partial pair gained 8 (BENCHMARKS.md, "Matching").
pub(crate) const COARSEST_LEVEL: usize = 6;

impl Default for Tuning {
    fn default() -> Self {
        Self {
            coarsest_level: COARSEST_LEVEL,
            alpha: (0.5, 0.5),
            soft: 0.1,
            ncg: NcgSettings::default(),
            align_rotations: 24,
            search: SimilaritySearch::default(),
            allow_scale: true,
            position_map: PositionMap::AffineNearSimilarity {
                ridge: POSITION_AFFINE_RIDGE,
            },
            snap_cells: SNAP_CELLS,
            sobolev_cells: 4.0,
            coarsest_sobolev_width: COARSEST_SOBOLEV_WIDTH,
            complete_tolerance: COMPLETE_TOLERANCE,
            rim_smoothing: RIM_SMOOTHING,
        }
    }
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

/// Settings of one level's minimization.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub(crate) struct NcgSettings {
    /// Stop when `(E_k − E_{k+1}) / E_k` is below this.
    pub tolerance: f64,
    /// The same on the finest level of the multiscale solve (unfiltered images): looser
    /// than `tolerance` because there, measured on the ICT pairs, the last iterations
    /// cost most of the time and do not change the accuracy (BENCHMARKS.md, "Matching").
    pub finest_tolerance: f64,
    pub max_iterations: usize,
    /// Iterations over which the relative decrease is averaged for the stopping rule
    /// (at least 1; 1, the default, is the plain per-step rule). No level stops as
    /// converged before this many iterations.
    pub window: usize,
    /// The window on the coarsest level of the multiscale solve, where the plain rule
    /// stopped too early (module docs); measured on the referee's pairs over three runs
    /// each, a window on the finer levels too changed no track's accuracy and cost time
    /// (BENCHMARKS.md, "Matching": the stopping rule).
    pub coarsest_window: usize,
    /// Armijo sufficient-decrease constant.
    pub armijo_c: f64,
    /// Refit the position term's similarity every this many iterations (0: never).
    pub refit_every: usize,
    /// Most energy evaluations on the finest level of the multiscale solve (0: no cap);
    /// a level `2^j` times coarser may use `4^j` times as many, the same cost
    /// ([`NcgSettings::level_evaluations`]). The level then stops with
    /// `StopReason::Budget`. Default 40 (640 at 65², 160 at 129²; with the position
    /// term's relief 96 at 129², `super::solve::RELIEF_MIDDLE_BUDGET`, and the coarsest
    /// level's relief phase a quarter of its budget on top,
    /// `super::solve::RELIEF_PHASE_FRACTION`): measured over the
    /// referee's 18 ICT pairs and the 10 FLAME pairs, the evaluations beyond it on the
    /// two finest levels (120 before) changed no track's fraction within 0.01, 0.02 or
    /// 0.05 nor its mean error beyond the run-to-run noise, and took a quarter of the
    /// solve; at 25 the partial pairs lost 1–3 points (BENCHMARKS.md, "Matching").
    pub max_evaluations: usize,
    /// Most energy evaluations of a whole multiscale solve, counted in finest-level
    /// evaluations (one on a grid `2^j` times coarser counts `4^-j`); 0: no cap. A level
    /// gets at most what the levels before it left, so the solve's cost is bounded even
    /// when every level would use its own budget ([`NcgSettings::max_evaluations`]).
    pub total_evaluations: usize,
}

impl NcgSettings {
    /// Sets the per-level budget ([`NcgSettings::max_evaluations`]); 0 lifts it and the
    /// whole solve's cap ([`NcgSettings::total_evaluations`]) too, so that every level
    /// runs to its stopping rule (the thesis's). `surfmap match --budget` and the Python
    /// `match(..., budget=)`.
    /// The evaluation cap of a level with `size` nodes per side when the finest level has
    /// `finest` (both `2^k + 1`): [`NcgSettings::max_evaluations`] × `((finest − 1)/(size − 1))²`,
    /// or `usize::MAX` without a cap.
    pub fn level_evaluations(&self, size: usize, finest: usize) -> usize {
        if self.max_evaluations == 0 {
            return usize::MAX;
        }
        let ratio = (finest - 1) / (size - 1).max(1);
        self.max_evaluations
            .saturating_mul(ratio.saturating_mul(ratio))
    }
}

impl Default for NcgSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-6,
            finest_tolerance: 1e-5,
            max_iterations: 300,
            window: 1,
            coarsest_window: 10,
            armijo_c: 1e-4,
            refit_every: 10,
            max_evaluations: 40,
            total_evaluations: 220,
        }
    }
}

/// When the coarsest level searches over similarities of φ before its NCG.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SearchWhen {
    /// Never.
    Off,
    /// Only when the start comes from the surfaces' shapes ([`super::Align::Shape`], or
    /// `Auto` without features or landmarks): the default. With landmarks the start is
    /// their similarity and the feature term holds φ to it (an early variant of the
    /// search — on 65², always kept — lost 12 points within 0.05 with landmarks on the
    /// FLAME identity pairs).
    #[default]
    Shape,
    /// For every alignment.
    Always,
}

/// Settings of the similarity search (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub(crate) struct SimilaritySearch {
    pub when: SearchWhen,
    /// The level `k` whose energy is searched (grid `2^k + 1`, images filtered with
    /// `σ = 2^−k`); at most the solve's coarsest level. φ there is the alignment's
    /// similarity, and the similarity found starts the solve.
    pub level: usize,
    /// Most rounds of (refit the position term's similarity, set `λ = E/M`, then BFGS);
    /// they stop earlier once a round lowers `E/M` by less than 10⁻⁴ of it. The refit
    /// and the plane similarity are coupled through the position term, so the rounds
    /// converge slowly: with 4, a start 12° off a synthetic self-match stopped 6° short
    /// (the test in `super::solve`); 20 reach it.
    pub rounds: usize,
    /// Most BFGS iterations per round.
    pub iterations: usize,
    /// A round stops when an iteration lowers the energy by less than this fraction.
    pub tolerance: f64,
    /// Extra starts: rotations by `±candidate_angle` (radians) and scalings by
    /// `e^{±candidate_log_scale}` of the start, `(0, 0)` for none; the combinations of
    /// `{−1, 0, 1}` steps of both (8 extra starts) are tried when both are non-zero.
    /// Off by default: ±5° and ±5 % changed nothing beyond noise on the FLAME and ICT
    /// pairs (BENCHMARKS.md).
    pub candidate_angle: f64,
    pub candidate_log_scale: f64,
    /// Search the scale too (four parameters), else rotation and translation only
    /// (the scale coordinate held at 0, and `candidate_log_scale` unused). Turned on
    /// by extra starts with a scale (`Advanced::search_candidates`' `SCALE > 0`). Off by
    /// default: with the scale, the energy per matched area the search minimizes
    /// favours a shrunk A where A is the larger face (FLAME identity pairs from
    /// `registered`: proposals ×0.90–0.99; on the BENCHMARKS pair registered → lmkfit
    /// ×0.91, which shrank the matched area ratio from 0.94 to 0.73), while the rotation
    /// alone ends lower in the coarsest level's energy there (10.00 against 10.28) and
    /// nearer the truth: FLAME identity without input, 48 pairs (the BENCHMARKS set and
    /// seeds 9–21), 95.5 → 96.4 % within 0.05; ICT seeds 7, 10, 13: 104 of 108 outputs
    /// byte-identical, 4 within ±0.1 point (docs/experiments/matching.md, "The
    /// similarity search without its scale").
    pub scale: bool,
}

impl Default for SimilaritySearch {
    fn default() -> Self {
        Self {
            when: SearchWhen::Shape,
            level: 4,
            rounds: 20,
            iterations: 30,
            tolerance: 1e-7,
            candidate_angle: 0.0,
            candidate_log_scale: 0.0,
            scale: false,
        }
    }
}

impl SimilaritySearch {
    /// The starts tried, as `(angle, log scale)` relative to the given φ.
    pub(crate) fn candidates(&self) -> Vec<(f64, f64)> {
        let a = self.candidate_angle;
        let s = if self.scale {
            self.candidate_log_scale
        } else {
            0.0
        };
        let steps = |x: f64| if x > 0.0 { vec![0.0, -x, x] } else { vec![0.0] };
        let mut out = vec![];
        for &da in &steps(a) {
            for &ds in &steps(s) {
                out.push((da, ds));
            }
        }
        out
    }
}

/// Default number of rings grown from the matched region.
pub const COMPLETE_RINGS: usize = 4;

/// Largest distance from a predicted point to B's surface, as a fraction of the vertex's
/// mean edge length (scaled to B), by where on B the closest point lies.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub(crate) struct Tolerance {
    /// When the closest point is on the rim of one of B's holes (every boundary loop but
    /// the longest, which [`crate::mesh::repair`] fills for the flattening): the holes
    /// are matched to A's (eyes to eyes), so the vertices around A's hole have their
    /// counterparts around B's, and φ, solved on the filled surfaces, carries them into
    /// the fill by up to a few grid cells.
    pub hole_rim: f64,
    /// When the closest point is on B's outer rim: A may simply extend beyond B (partial
    /// overlap); a vertex of A on the rim's cut misses it by the prediction's error (a
    /// median 0.2–0.5 edge on the ICT pairs), one ring past it by about one edge: so half
    /// an edge, halfway between (a quarter before: BENCHMARKS.md, "Matching").
    pub elsewhere: f64,
    /// When the closest point is inside B (on no boundary loop): the predicted point lies
    /// over B's surface, not past its rim, so there is a counterpart to find; the
    /// distance is the prediction's error normal to B, largest where the surface bends
    /// (ears, nostrils, lips): one edge.
    pub interior: f64,
}

/// The default [`Advanced::rim_tolerance`] (half an edge: `COMPLETE_TOLERANCE`).
pub const RIM_TOLERANCE: f64 = COMPLETE_TOLERANCE.elsewhere;

pub(crate) const COMPLETE_TOLERANCE: Tolerance = Tolerance {
    hole_rim: 1.5,
    elsewhere: 0.5,
    interior: 1.0,
};

/// Smoothing of the correspondence along the unmatched region's border before it is
/// completed (`complete_correspondence`).
///
/// φ is smooth on the grid, but where it carries A's vertices next to B's rims (or next
/// to the triangles `crate::matching::folds::drop_folds` gave up) its error in space is about
/// an edge, and so the neighbours a completed vertex is placed among are off by as much:
/// completing it at its right place turns an image triangle over, and it stays
/// unmatched. So the offsets `o(v)` (module documentation) of the matched vertices
/// within `rings` rings of an unmatched one are first smoothed by `iterations` Jacobi
/// sweeps of the umbrella average
///
/// `o(v) ← (o(v) + Σ_{u∈N(v), matched} o(u)) / (1 + |N(v) matched|)`,
///
/// the vertices farther in, which φ places well, staying fixed as anchors; each
/// smoothed vertex is re-matched to the point of B closest to `S(x_A(v)) + o(v)`,
/// searched near its former counterpart (`SurfaceProjector::project_near`), unless
/// that would fold an image triangle. On the rim the average is one-sided, so it
/// carries the anchors' offsets outward rather than fitting the rim's own: this removes
/// φ's systematic error there (measured better on the ICT pairs than a local affine
/// fit, which keeps it; BENCHMARKS.md, "Matching"), at the price of a small bias where
/// the offsets vary fast (a strong bend; see the tests).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub(crate) struct RimSmoothing {
    /// Rings of matched vertices next to unmatched ones that are smoothed; 0 turns the
    /// smoothing off.
    pub rings: usize,
    /// Jacobi sweeps.
    pub iterations: usize,
}

/// Default rim smoothing: the two rings next to the unmatched region, ten sweeps.
pub(crate) const RIM_SMOOTHING: RimSmoothing = RimSmoothing {
    rings: 2,
    iterations: 10,
};

/// Default (and narrowest) band: the rings of A's vertices around a fitted rim that
/// follow it. Eight: the rim moves by a grid cell or two (about as many mesh edges), so
/// each ring's triangles are sheared by a small fraction of an edge.
pub const RIM_FIT_RINGS: usize = 8;

/// Default elongation from which paired hole rims are split
/// ([`super::MatchOptions::split_hole_rims`]).
pub(crate) const SPLIT_HOLE_RIMS: f64 = 2.0;

/// Points mapped within this many finest-grid cells of B's surface are snapped onto it
/// (`crate::matching::post::fitted_correspondence`). Half a cell: a vertex of A one ring past B's crop
/// lies about one mesh edge (1–1.5 cells at 257²) outside ω_B, so a snap of 1.5 cells
/// matched it falsely; the vertices on B's rim that φ carries farther than half a cell
/// out are left to rim completion (`crate::matching::post::complete`), which tells the two apart by
/// their neighbours (measured in BENCHMARKS.md, "Hole rims split at their corners").
pub(crate) const SNAP_CELLS: f64 = 0.5;

impl MatchOptions {
    /// Checks every setting: the first that cannot be used is the error.
    pub fn validate(&self) -> Result<(), OptionError> {
        let k = crate::grid::grid_level(self.size).map_err(|_| OptionError::Size(self.size))?;
        if (k as usize) < self.tuning.coarsest_level {
            return Err(OptionError::Size(self.size));
        }
        let w = self.weights;
        let b = [w.bending, w.regularization, w.features];
        if b.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(OptionError::Weights(b.to_vec()));
        }
        if let PositionWeight::Fixed(w) = self.position_weight
            && !(w.is_finite() && w >= 0.0)
        {
            return Err(OptionError::PositionWeight(w));
        }
        if let ScaleB::Factor(f) = self.scale_b
            && !(f.is_finite() && f > 0.0)
        {
            return Err(OptionError::ScaleB(f));
        }
        let a = &self.advanced;
        if !(a.rim_tolerance.is_finite() && a.rim_tolerance >= 0.0) {
            return Err(OptionError::RimTolerance(a.rim_tolerance));
        }
        if !(a.relief.is_finite() && (0.0..=1.0).contains(&a.relief)) {
            return Err(OptionError::Relief(a.relief));
        }
        if self.similarity_search != SearchWhen::Off
            && !(1..=COARSEST_LEVEL).contains(&a.search_level)
        {
            return Err(OptionError::SearchLevel(a.search_level));
        }
        let [deg, scale] = a.search_candidates;
        if !(deg.is_finite() && deg >= 0.0 && scale.is_finite() && (0.0..1.0).contains(&scale)) {
            return Err(OptionError::SearchCandidates(a.search_candidates.to_vec()));
        }
        Ok(())
    }

    /// The energy's weights, the position term's to be set by the alignment
    /// ([`PositionWeight`]).
    pub(crate) fn betas(&self) -> Betas {
        Betas {
            bend: self.weights.bending,
            reg: self.weights.regularization,
            features: self.weights.features,
            position: 0.0,
            uncovered: 0.0,
        }
    }

    /// One level's minimization, with the budget: [`MatchOptions::budget`] per level,
    /// and (unless it is 0, which lifts both caps) the whole solve's cap.
    pub(crate) fn ncg(&self) -> NcgSettings {
        let mut ncg = self.tuning.ncg;
        ncg.max_evaluations = self.budget;
        if self.budget == 0 {
            ncg.total_evaluations = 0;
        }
        ncg
    }

    /// The similarity search's settings.
    pub(crate) fn search(&self) -> SimilaritySearch {
        let [deg, scale] = self.advanced.search_candidates;
        SimilaritySearch {
            when: self.similarity_search,
            level: self.advanced.search_level,
            candidate_angle: deg.to_radians(),
            candidate_log_scale: (1.0 + scale).ln(),
            // Scaled starts are asked for: search the scale too.
            scale: self.tuning.search.scale || scale > 0.0,
            ..self.tuning.search
        }
    }

    /// Rim completion's tolerances.
    pub(crate) fn complete_tolerance(&self) -> Tolerance {
        Tolerance {
            elsewhere: self.advanced.rim_tolerance,
            ..self.tuning.complete_tolerance
        }
    }

    /// The elongation from which paired hole rims are split (0: never).
    pub(crate) fn split_ratio(&self) -> f64 {
        if self.split_hole_rims {
            SPLIT_HOLE_RIMS
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The search keeps the scale unless scaled starts are asked for; then it searches
    /// it, from the starts `e^{±ln(1 + SCALE)}` as well as the given one.
    #[test]
    fn scaled_extra_starts_turn_the_scale_search_on() {
        let mut o = MatchOptions::default();
        let search = o.search();
        assert!(!search.scale);
        assert_eq!(search.candidates(), vec![(0.0, 0.0)]);
        o.advanced.search_candidates = [5.0, 0.0];
        assert!(!o.search().scale);
        assert!(o.search().candidates().iter().all(|&(_, s)| s == 0.0));
        o.advanced.search_candidates = [0.0, 0.05];
        let search = o.search();
        assert!(search.scale);
        let scales: Vec<f64> = search.candidates().iter().map(|c| c.1).collect();
        assert_eq!(scales, vec![0.0, -(1.05f64).ln(), (1.05f64).ln()]);
    }

    /// Each setting out of range is refused by name, with the value given, worded with
    /// the front end's spelling; the defaults pass.
    #[test]
    fn every_setting_out_of_range_is_named() {
        assert_eq!(MatchOptions::default().validate(), Ok(()));
        let refused = |set: &dyn Fn(&mut MatchOptions)| {
            let mut o = MatchOptions::default();
            set(&mut o);
            o.validate().unwrap_err()
        };
        let cases: Vec<(OptionError, &str)> = vec![
            (refused(&|o| o.size = 100), "size"),
            (refused(&|o| o.size = 33), "size"),
            (refused(&|o| o.weights.features = -1.0), "beta"),
            (refused(&|o| o.weights.bending = f64::NAN), "beta"),
            (
                refused(&|o| o.position_weight = PositionWeight::Fixed(f64::INFINITY)),
                "position_weight",
            ),
            (refused(&|o| o.scale_b = ScaleB::Factor(0.0)), "scale_b"),
            (
                refused(&|o| o.advanced.rim_tolerance = -0.1),
                "rim_tolerance",
            ),
            (refused(&|o| o.advanced.relief = 1.5), "relief"),
            (refused(&|o| o.advanced.search_level = 0), "search_level"),
            (refused(&|o| o.advanced.search_level = 7), "search_level"),
            (
                refused(&|o| o.advanced.search_candidates = [5.0, 1.0]),
                "search_candidates",
            ),
            (
                refused(&|o| o.advanced.search_candidates = [-5.0, 0.1]),
                "search_candidates",
            ),
        ];
        for (e, setting) in cases {
            assert_eq!(e.setting(), setting, "{e}");
            assert!(e.to_string().starts_with(setting), "{e}");
            let flag = format!("--{}", setting.replace('_', "-"));
            assert!(e.worded(&flag).starts_with(&flag), "{e}");
        }
        assert!(
            Weights::from_slice(&[1.0, 2.0])
                .unwrap_err()
                .to_string()
                .starts_with("beta takes three weights")
        );
        // No search: its level is not used, so not checked.
        let mut o = MatchOptions::default();
        (o.similarity_search, o.advanced.search_level) = (SearchWhen::Off, 0);
        assert_eq!(o.validate(), Ok(()));
    }

    /// The settings reach the solver in its units: the candidates in radians and log
    /// scale, the outer-rim tolerance into completion's, a budget of 0 lifting the whole
    /// solve's cap too.
    #[test]
    fn the_settings_reach_the_solver_in_its_units() {
        let mut o = MatchOptions::default();
        o.advanced.search_candidates = [90.0, 0.1];
        let s = o.search();
        assert!((s.candidate_angle - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((s.candidate_log_scale.exp() - 1.1).abs() < 1e-15);
        o.advanced.rim_tolerance = 3.0;
        let t = o.complete_tolerance();
        assert_eq!(
            (t.elsewhere, t.interior),
            (3.0, COMPLETE_TOLERANCE.interior)
        );
        assert_eq!(o.ncg().max_evaluations, BUDGET);
        assert!(o.ncg().total_evaluations > 0);
        o.budget = 0;
        assert_eq!((o.ncg().max_evaluations, o.ncg().total_evaluations), (0, 0));
        assert_eq!(PositionWeight::Fixed(7.0).weight(Some(0.005)), 7.0);
        let auto = PositionWeight::Auto.weight(Some(0.005));
        assert!((auto - POSITION_KAPPA / 0.005f64.powi(2)).abs() < 1e-9 * auto);
        assert_eq!(
            PositionWeight::Auto.weight(Some(1.0)),
            POSITION_KAPPA / POSITION_RESIDUAL_CAP.powi(2)
        );
        assert_eq!(PositionWeight::Auto.weight(None), POSITION_WEIGHT_UNALIGNED);
    }
}
