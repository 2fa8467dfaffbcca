//! How well the paired features agree, before and after the solve.
//!
//! For a feature `f` paired between A and B (a curve, a landmark — a one-vertex feature —
//! or a hole rim paired automatically), each vertex `v` of A's curve is placed in ω_B
//! twice: by the plane similarity φ started from on the coarsest level
//! (`AlignmentReport::start`), and by φ itself. At each place B's distance map of the
//! same feature `d_B^f` (the one the feature term (2.11) reads: the geodesic distance to
//! B's curve in B's metric, extended past B's rim) is read bilinearly:
//!
//! `before_f = mean_v d_B^f(s(ξ_A(v)))`,   `after_f = mean_v d_B^f(φ(ξ_A(v)))`,
//!
//! in B's own length units. `after` near zero says φ lays A's curve onto B's; a large
//! `after` on one feature when the others fit says that feature disagrees with the rest
//! (a mislabelled curve, a landmark on the wrong vertex) or that the other terms
//! outweighed it there — which the match cannot tell from the energy alone.
//!
//! **Reach.** The feature term's penalty `θ^ε(s) = min(s²/ε, 1)` stops growing at
//! `s = √ε` (`s` in ℓ units, ε of the finest level): a feature that φ leaves farther
//! than that exerts no pull on the finest level, whatever βF. The report warns when a
//! feature's mean distance ends beyond it ([`feature_warnings`]). Measured (BENCHMARKS.md,
//! "Features before and after"): on the 18 ICT referee pairs, with and without the 7
//! landmarks, every feature ends within 0.83 of its reach (median 0.1); on the 10 FLAME
//! pairs five landmarks end beyond it, all on the three partial pairs matched worst —
//! the output's pinning puts the landmark itself on B's vertex, but the region around it
//! was matched by φ.

use serde::Serialize;

use super::super::prepare::surface::MatchSurface;
use super::super::solve::Solved;

/// One paired feature's distance from A's curve, carried into ω_B, to B's curve.
#[derive(Clone, Debug, Serialize)]
pub struct FeatureFit {
    pub name: String,
    /// Vertices of A's curve.
    pub vertices: usize,
    /// Mean distance (B's units) at the start of the solve.
    pub before: f64,
    /// Mean and largest distance (B's units) after it.
    pub after: f64,
    pub after_max: f64,
    /// The distance (B's units) beyond which the feature term no longer pulls on the
    /// finest level (module docs).
    pub reach: f64,
}

impl FeatureFit {
    /// For a landmark the user gave (a `landmark:` feature), its distance from B's after
    /// the solve over the feature term's reach (`Measures::landmark_miss`); `None` for
    /// other features.
    pub fn landmark_miss(&self) -> Option<f64> {
        (self.name.starts_with("landmark:") && self.reach > 0.0).then(|| self.after / self.reach)
    }
}

/// One warning per feature whose mean distance from B's ends beyond the feature term's
/// reach (module docs), worded for the user.
pub fn feature_warnings(fits: &[FeatureFit]) -> Vec<String> {
    fits.iter()
        .filter(|f| f.after > f.reach)
        .map(|f| {
            format!(
                "feature {:?} ends {:.3} (B's units) from B's on average, beyond the reach of the \
                 feature term on the finest level ({:.3}): the other terms outweighed it there, so \
                 the region around it may be matched poorly (an output landmark is still pinned \
                 to its vertex of B). Check that the feature names the same place on both \
                 surfaces, and look at features.png (--pictures).",
                f.name, f.after, f.reach
            )
        })
        .collect()
}

/// One paired feature in ω_B (`SurfaceMatch::carried_features`).
#[derive(Clone, Debug)]
pub struct CarriedFeature {
    pub name: String,
    /// A's curve, carried into ω_B.
    pub a: Vec<[f64; 2]>,
    /// B's curve.
    pub b: Vec<[f64; 2]>,
    pub closed: bool,
}

/// The features' domain positions on A and B, paired: for every feature of A (in
/// order), A's curve carried into ω_B by `place`, and B's curve in ω_B.
pub fn carried_features(
    a: &MatchSurface,
    b: &MatchSurface,
    place: impl Fn([f64; 2]) -> [f64; 2],
) -> Vec<CarriedFeature> {
    a.feature_curves
        .iter()
        .zip(&b.feature_curves)
        .map(|(fa, fb)| {
            let a = fa
                .vertices
                .iter()
                .map(|&v| place(a.vertex_domain_position(v as usize)))
                .collect();
            let b = fb
                .vertices
                .iter()
                .map(|&v| b.vertex_domain_position(v as usize))
                .collect();
            CarriedFeature {
                name: fa.name.clone(),
                a,
                b,
                closed: fa.closed,
            }
        })
        .collect()
}

/// Every paired feature's fit before and after the solve (module docs); empty
/// without features.
pub(crate) fn feature_fits(
    a: &MatchSurface,
    b: &MatchSurface,
    solved: &Solved,
    scale_b: f64,
) -> Vec<FeatureFit> {
    let start = solved.alignment.start();
    // ℓ units → B's own units (B was scaled by `scale_b` for the match).
    let unit = a.length_unit / scale_b;
    let reach = solved.levels.last().map_or(f64::NAN, |l| l.epsilon.sqrt()) * unit;
    let before = carried_features(a, b, |xi| start.apply(xi));
    let after = carried_features(a, b, |xi| solved.map_domain(xi));
    before
        .iter()
        .zip(&after)
        .enumerate()
        .map(|(f, (before, after))| {
            let distance = b.feature_distance(f);
            let at = |p: &[f64; 2]| distance.sample(*p) * unit;
            let count = before.a.len().max(1) as f64;
            FeatureFit {
                name: before.name.clone(),
                vertices: before.a.len(),
                before: before.a.iter().map(at).sum::<f64>() / count,
                after: after.a.iter().map(at).sum::<f64>() / count,
                after_max: after.a.iter().map(at).fold(0.0, f64::max),
                reach,
            }
        })
        .collect()
}
