//! How far a match can be trusted, from what the matcher knows without ground truth.
//!
//! A match that went wrong — a start turned or shifted so that the solve settled on the
//! wrong region, a surface squeezed into part of the other — is written like any
//! other; a user who registers a hundred scans cannot look at each. The measures below
//! see such failures in what the match computed:
//!
//! - **residual**: the correspondence against the best similarity of space carrying
//!   A's matched vertices onto their points on B (`T = s·R·x + t`, a proper rotation:
//!   [`fit_similarity_3d`]), `√(Σ aᵥ |T(x_A(v)) − y(v)|² / Σ aᵥ)` over the matched
//!   vertices with their areas `aᵥ`, in units of `√area(B)`. Two faces matched where
//!   they correspond differ from a similarity by their difference in shape (a few
//!   hundredths); a match turned or shifted on the face, or folded over itself, cannot be
//!   explained by one.
//! - **residual_ratio**: that residual over the surfaces' own distance in space after
//!   their rigid alignment (the trimmed ICP's RMS along B's normals, the shape residual
//!   the position weight was set from), where it was measured.
//! - **energy**: the finest level's final energy (thesis 2.16 plus the position term),
//!   per unit of A's area matched.
//! - **curvature disagreements** (`LevelEnergy::curvature_disagreement`): how much B's
//!   mean curvature at φ differs from A's, relative to the curvature both have (0 alike,
//!   about 1 unrelated) — on the finest level, on the coarsest level's smoothed images
//!   (`coarse_disagreement`: the shape without its fine detail), and with φ turned away
//!   from its place (`unrelated_disagreement`: what unrelated places give).
//! - **pose_offset**: the RMS distance between that similarity and the surfaces' rigid
//!   alignment in space, in units of `√area(B)`: a match that slid or turned on B.
//! - the matched fraction of A, the covered fraction of B and the area ratio
//!   ([`super::MatchReport`]).
//!
//! The verdict reads the coarse disagreement, the pose offset, the area ratio and the
//! matched fraction (thresholds below, calibrated on matches scored by an independent
//! referee). The finest disagreement and the residual are recorded, not judged: they
//! depend on how alike the two shapes are (two people's faces matched correctly differ
//! by 0.4 on the finest level, where two scans of one face differ by 0.1).

use serde::Serialize;

use super::super::similarity::{Similarity3, fit_similarity_3d};
use crate::mesh::SurfacePoint;
use crate::vec3::{cross3 as cross, norm3 as norm, sub3 as sub};

/// The verdict on a match ([`Confidence`]), from best to worst.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    Ok,
    Doubtful,
    Failed,
}

impl Verdict {
    /// The verdict as `match.json` writes it: `ok`, `doubtful` or `failed`.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Ok => "ok",
            Verdict::Doubtful => "doubtful",
            Verdict::Failed => "failed",
        }
    }
}

/// A verdict on a match, why, and what it was drawn from.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Confidence {
    pub verdict: Verdict,
    /// Each reason the verdict is not `ok`, worded for the user.
    pub reasons: Vec<String>,
    pub measures: Measures,
    /// When the first start's verdict was not `ok`: the other starts tried
    /// (`crate::matching::recover`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub recovery: Option<super::super::recover::Recovery>,
}

impl Default for Confidence {
    fn default() -> Self {
        Self {
            verdict: Verdict::Ok,
            reasons: vec![],
            measures: Measures::default(),
            recovery: None,
        }
    }
}

// The thresholds below were calibrated on 322 matches (scripts/verdict_calibration.py:
// 36 ICT referee pairs of seeds 7 and 9 and 10 FLAME pairs, each matched without input,
// with landmarks, and from five starts broken on purpose — turned by 90° and 180°,
// mirrored, shifted, unaligned) against the referee's fraction of A within 0.05, and
// checked on 216 held-out matches (ICT seeds 10, 11): matches that hold (≥ 90 %) keep
// a pose offset of at most 0.059 (99 % under 0.037), matches that failed (< 50 %) move
// at least 0.042 away. The coarse disagreement of matches that hold is ≤ 0.104 within
// one registered set, but 0.25–0.37 between faces of two sources matched correctly
// (ICT against FLAME or libigl's head: nose tip and mouth corners a few millimetres from
// their place): it says "the shapes differ", which a wrong place and two people both
// do. So it counts only together with a pose that moved (docs/bench/verdict.md), or
// where it is beyond every match that held (a match that followed a wrong alignment
// in space, whose pose offset is measured from that same alignment).

/// Coarse curvature disagreement ([`Measures::coarse_disagreement`]) from which a match
/// whose pose moved ([`POSE_MOVED`]) is `failed`: above every match that held in
/// calibration (0.104), below all but one that failed.
pub const COARSE_DISAGREEMENT_FAILED: f64 = 0.12;

/// Coarse curvature disagreement from which a match is `failed` even where its pose did
/// not move ([`POSE_MOVED`]): then the match follows a rigid alignment in space that is
/// itself wrong — a face crop turned by 180° can lie on another with millimetres of RMS
/// — and the pose offset, measured from that alignment, cannot see it (found on a FLAME
/// partial pair matched with `--relief 0 --position-weight 20000`: 0.58 at a pose offset
/// of 0.040, 0.9 % within 0.05; its default match recovers from the same pose). Above
/// every match that held: 0.104 within one registered set, 0.13–0.42 between faces of
/// two sources (docs/bench/verdict.md).
pub const COARSE_DISAGREEMENT_UNMOVED_FAILED: f64 = 0.5;

/// Coarse curvature disagreement from which a match whose pose moved is `doubtful`
/// (matches that held on like surfaces: ≤ 0.03; on less alike ones up to 0.10).
pub const COARSE_DISAGREEMENT_DOUBTFUL: f64 = 0.06;

/// Pose offset ([`Measures::pose_offset`]) from which a coarse disagreement is read:
/// matches that held stay below it 99 % of the time (faces of two sources matched
/// correctly: ≤ 0.035), every match that failed in calibration is above it (≥ 0.042).
/// Without a pose offset (no alignment in space), the disagreement is read alone.
pub const POSE_MOVED: f64 = 0.04;

/// Pose offset ([`Measures::pose_offset`], units of `√area(B)`) from which a match is
/// `failed`: the match slid or turned a tenth of B's size away from where the shapes
/// lie on each other (held in calibration: ≤ 0.059).
pub const POSE_OFFSET_FAILED: f64 = 0.1;

/// Pose offset from which a match is `doubtful`.
pub const POSE_OFFSET_DOUBTFUL: f64 = 0.05;

/// Matched fraction of A below which a match is `doubtful`, and `failed`.
pub const MATCHED_DOUBTFUL: f64 = 0.4;
pub const MATCHED_FAILED: f64 = 0.15;

/// [`Measures::landmark_miss`] from which a match is `doubtful`
/// ([`Confidence::doubt_landmarks_left_behind`]). Measured with the referee's seven
/// landmarks (2026-12-07): ICT pairs of seeds 7, 10, 13 (54 matches, all 94–99.8 % of A
/// within 0.05) leave them at most 0.31 of the reach on identity, partial and resolution
/// pairs and 0.77 on the smiles; FLAME pairs (seeds 9–21, 70 matches) at most 0.94 on
/// whole faces, 0.3–11.8 on partial crops: the 50–80 % ones left `ok` 8 → 3, and 4 of 43
/// at 90 % or more made `doubtful` (partial crops at 90–94 %; docs/bench/verdict.md).
pub const LANDMARK_MISS_DOUBTFUL: f64 = 1.25;

/// `Failed` from `failed` on, `Doubtful` from `doubtful` on, else none.
fn graded(x: f64, doubtful: f64, failed: f64) -> Option<Verdict> {
    if x >= failed {
        Some(Verdict::Failed)
    } else if x >= doubtful {
        Some(Verdict::Doubtful)
    } else {
        None
    }
}

impl Confidence {
    /// The verdict on `measures`: the worst any measure gives, each reason worded.
    pub(crate) fn of(measures: Measures) -> Self {
        let mut verdict = Verdict::Ok;
        let mut reasons = vec![];
        let mut find = |v: Verdict, reason: String| {
            verdict = verdict.max(v);
            reasons.push(reason);
        };
        // The shapes' disagreement condemns a match only where its pose moved too, or
        // where it is beyond any match that held.
        let moved = measures.pose_offset.is_none_or(|o| o >= POSE_MOVED);
        if let Some(d) = measures.coarse_disagreement
            && (moved || d >= COARSE_DISAGREEMENT_UNMOVED_FAILED)
            && let Some(v) = graded(d, COARSE_DISAGREEMENT_DOUBTFUL, COARSE_DISAGREEMENT_FAILED)
        {
            find(
                v,
                format!(
                    "B's shape where A is matched disagrees with A's by {:.0}% of the curvature \
                     both have, at the coarsest scale (matches that hold: under {:.0}%; an \
                     unrelated place on these surfaces: {}){}: A was probably laid onto the \
                     wrong part of B, turned or mirrored",
                    100.0 * d,
                    100.0 * COARSE_DISAGREEMENT_DOUBTFUL,
                    measures
                        .unrelated_disagreement
                        .map_or("-".into(), |u| format!("{:.0}%", 100.0 * u)),
                    match measures.pose_offset {
                        None => String::new(),
                        Some(o) if moved => format!(
                            ", and the match moved {o:.3} of B's size from the surfaces' \
                             rigid alignment"
                        ),
                        Some(_) => " (although the match lies where the surfaces' rigid \
                                    alignment in space puts it, that alignment is probably \
                                    wrong too)"
                            .into(),
                    }
                ),
            );
        }
        if let Some(o) = measures.pose_offset
            && let Some(v) = graded(o, POSE_OFFSET_DOUBTFUL, POSE_OFFSET_FAILED)
        {
            find(
                v,
                format!(
                    "the match as a whole lies {o:.3} of B's size (RMS) away from where the \
                     surfaces lie on each other in space (their rigid alignment): it slid or \
                     turned on B"
                ),
            );
        }
        if let Some(r) = measures.area_ratio
            && !super::plausible_area_ratio(r)
        {
            find(
                Verdict::Failed,
                format!(
                    "A's matched part lands on B at {r:.2}× its own area ({}): no match of like \
                     surfaces does that (a face against a whole head or a scan with \
                     shoulders: crop both to the region they share, or give landmarks)",
                    if r < 1.0 { "squeezed" } else { "stretched" }
                ),
            );
        }
        let m = measures.matched_fraction_a;
        if m < MATCHED_DOUBTFUL {
            find(
                if m < MATCHED_FAILED {
                    Verdict::Failed
                } else {
                    Verdict::Doubtful
                },
                format!("only {:.0}% of A is matched", 100.0 * m),
            );
        }
        Self {
            verdict,
            reasons,
            measures,
            recovery: None,
        }
    }
}

impl Confidence {
    /// A match that leaves a landmark the user gave far from B's
    /// ([`LANDMARK_MISS_DOUBTFUL`] times the feature term's reach) is at most
    /// `doubtful`: the other terms outweighed the landmark there, so A's region around it
    /// lies elsewhere on B than the user said — on partial crops, where every other
    /// measure reads like a match that holds (docs/bench/verdict.md). `fits`: the
    /// report's feature fits, to name the landmark. Applied to the match reported, after
    /// recovery (a start is not what such a match gets wrong), and only where the feature
    /// term has a weight: with weight 0 the landmarks only placed the start.
    pub(crate) fn doubt_landmarks_left_behind(&mut self, fits: &[super::super::FeatureFit]) {
        let Some(miss) = self.measures.landmark_miss else {
            return;
        };
        if miss < LANDMARK_MISS_DOUBTFUL || self.verdict == Verdict::Failed {
            return;
        }
        let worst = fits
            .iter()
            .filter_map(|f| Some((f, f.landmark_miss()?)))
            .max_by(|x, y| x.1.total_cmp(&y.1))
            .map(|(f, _)| f);
        self.verdict = Verdict::Doubtful;
        self.reasons.push(format!(
            "the match leaves {} {:.1} times the feature term's reach from B's (matches that \
             follow their landmarks: under {LANDMARK_MISS_DOUBTFUL}): the region around it \
             probably lies elsewhere on B than the landmarks say; check that landmark, or \
             look at the match (`surfmap view`)",
            worst.map_or("a landmark".into(), |f| format!("{:?}", f.name)),
            miss
        ));
    }
}

impl Confidence {
    /// One line for a command line: the verdict, the measures it read and, when it is
    /// not `ok`, why.
    pub fn line(&self) -> String {
        let m = &self.measures;
        let num = |x: Option<f64>, digits: usize| x.map_or("-".into(), |x| format!("{x:.digits$}"));
        let measures = format!(
            "coarse disagreement {}, pose offset {} of B's size, residual {}, energy {:.3} per unit area, {:.1}% of A matched",
            num(m.coarse_disagreement, 3),
            num(m.pose_offset, 3),
            num(m.residual, 4),
            m.energy,
            100.0 * m.matched_fraction_a
        );
        match self.verdict {
            Verdict::Ok => format!("verdict ok: {measures}"),
            v => format!(
                "verdict {}: {}; {measures}",
                v.name().to_uppercase(),
                self.reasons.join("; ")
            ),
        }
    }
}

impl Measures {
    /// With the ratio of the residual to the surfaces' distance `sigma` after their
    /// rigid alignment (ℓ units; `to_b` converts ℓ to units of `√area(B)`).
    pub(crate) fn with_shape_residual(mut self, sigma: Option<f64>, to_b: f64) -> Self {
        self.residual_ratio = match (self.residual, sigma) {
            (Some(r), Some(s)) if s > 0.0 => Some(r / (s * to_b)),
            _ => None,
        };
        self
    }
}

/// The measures a verdict is drawn from (module docs).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Measures {
    /// RMS distance (units of `√area(B)`) of the correspondence from the best similarity
    /// of space.
    pub residual: Option<f64>,
    /// RMS distance (units of `√area(B)`) between that similarity and the surfaces'
    /// rigid alignment in space: a match that slid or turned away from where the shapes
    /// lie on each other; `None` without an alignment in space.
    pub pose_offset: Option<f64>,
    /// `residual` over the surfaces' distance after their rigid alignment (both in the
    /// shared length unit); `None` when that was not measured.
    pub residual_ratio: Option<f64>,
    /// The final energy per unit of A's matched area (ℓ²).
    pub energy: f64,
    /// How much B's curvature at φ disagrees with A's, relative to the curvature both
    /// have (0: alike, about 1: unrelated; `LevelEnergy::curvature_disagreement`).
    pub curvature_disagreement: Option<f64>,
    /// The same on the coarsest level's smoothed images (fine detail not counted).
    pub coarse_disagreement: Option<f64>,
    /// The same with φ turned away from its place (the mean over three turns): what
    /// unrelated places give on these surfaces.
    pub unrelated_disagreement: Option<f64>,
    pub matched_fraction_a: f64,
    pub covered_fraction_b: f64,
    pub area_ratio: Option<f64>,
    /// The largest distance at which the match leaves one of the given landmarks from
    /// B's, over the feature term's reach on the finest level (`FeatureFit::after /
    /// reach` of the `landmark:` features; above 1 the landmark is also warned about);
    /// `None` without landmarks.
    pub landmark_miss: Option<f64>,
}

/// The correspondence against similarities of space: the weighted RMS distance of
/// `points` (on B) from the best similarity image `T` of A's positions (vertex areas as
/// weights), and the RMS distance between `T` and `pose` (the surfaces' rigid alignment
/// in space, when known) over the same vertices — both meshes in one length unit (ℓ
/// for `pose`, which `unit` converts to). `None` with fewer than four matched vertices
/// or a degenerate fit.
pub(crate) fn similarity_residual(
    (a_positions, a_triangles): (&[[f64; 3]], &[[u32; 3]]),
    (b_positions, b_triangles): (&[[f64; 3]], &[[u32; 3]]),
    points: &[Option<SurfacePoint>],
    pose: Option<&Similarity3>,
    unit: f64,
) -> Option<(f64, Option<f64>)> {
    let mut area = vec![0.0; a_positions.len()];
    for t in a_triangles {
        let [p, q, r] = t.map(|v| a_positions[v as usize]);
        let third = norm(cross(sub(q, p), sub(r, p))) / 6.0;
        t.iter().for_each(|&v| area[v as usize] += third);
    }
    let (mut p, mut q, mut w) = (vec![], vec![], vec![]);
    for (v, y) in points.iter().enumerate() {
        if let Some(y) = y {
            p.push(a_positions[v]);
            q.push(y.position(b_positions, b_triangles));
            w.push(area[v]);
        }
    }
    if p.len() < 4 {
        return None;
    }
    let t = fit_similarity_3d(&p, &q, &w, true)?;
    let rms = |d: &dyn Fn(usize) -> f64| {
        let (mut sum, mut total) = (0.0, 0.0);
        for (k, &wk) in w.iter().enumerate() {
            sum += wk * d(k);
            total += wk;
        }
        (total > 0.0).then(|| (sum / total).sqrt())
    };
    let squared = |x: [f64; 3], y: [f64; 3]| (0..3).map(|c| (x[c] - y[c]).powi(2)).sum::<f64>();
    let residual = rms(&|k| squared(t.apply(p[k]), q[k]))?;
    let offset = pose.and_then(|pose| {
        rms(&|k| {
            let x = p[k].map(|c| c / unit);
            squared(t.apply(p[k]), pose.apply(x).map(|c| c * unit))
        })
    });
    Some((residual, offset))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Measures of a whole, same-sized match with the given coarse disagreement and pose
    /// offset.
    fn measures(coarse: f64, pose_offset: Option<f64>) -> Measures {
        Measures {
            coarse_disagreement: Some(coarse),
            pose_offset,
            unrelated_disagreement: Some(0.95),
            matched_fraction_a: 0.98,
            covered_fraction_b: 0.9,
            area_ratio: Some(1.0),
            ..Measures::default()
        }
    }

    /// Two people's faces from two sources matched in place (measured: ICT onto libigl's
    /// head, coarse disagreement 0.37 at a pose offset of 0.003; FLAME onto ICT, 0.31
    /// at 0.035, nose and mouth corners 1.2 mm off) are not condemned by
    /// their shapes' difference; the same difference with the match moved off the
    /// surfaces' rigid pose (ICT onto a whole head, 0.67 at 0.048) is a failure, and so
    /// is any match that slid a tenth of B's size.
    #[test]
    fn a_shape_disagreement_condemns_only_a_match_that_moved() {
        let verdict = |coarse, offset| Confidence::of(measures(coarse, offset)).verdict;
        assert_eq!(verdict(0.37, Some(0.003)), Verdict::Ok);
        assert_eq!(verdict(0.67, Some(0.048)), Verdict::Failed);
        assert_eq!(verdict(0.31, Some(0.035)), Verdict::Ok);
        // Beyond any match that held (cross-source: ≤ 0.42), the disagreement fails a
        // match that followed a wrong rigid alignment (FLAME partial, turned: 0.58 at
        // 0.040, 0.9 % correct).
        assert_eq!(verdict(0.42, Some(0.03)), Verdict::Ok);
        assert_eq!(verdict(0.58, Some(0.039)), Verdict::Failed);
        let unmoved = Confidence::of(measures(0.58, Some(0.039)));
        assert!(
            unmoved.reasons[0].contains("alignment is probably wrong"),
            "{:?}",
            unmoved.reasons
        );
        assert_eq!(verdict(0.08, Some(0.045)), Verdict::Doubtful);
        assert_eq!(verdict(0.02, Some(0.045)), Verdict::Ok);
        assert_eq!(verdict(0.02, Some(0.07)), Verdict::Doubtful);
        assert_eq!(verdict(0.02, Some(0.16)), Verdict::Failed);
        // Without an alignment in space the disagreement is all there is to read.
        assert_eq!(verdict(0.37, None), Verdict::Failed);
        assert_eq!(verdict(0.08, None), Verdict::Doubtful);
        let moved = Confidence::of(measures(0.67, Some(0.048)));
        assert!(
            moved.reasons[0].contains("moved 0.048 of B's size"),
            "{:?}",
            moved.reasons
        );
    }

    /// The area ratio and the matched fraction fail a match whatever its shape says.
    #[test]
    fn a_squeezed_or_barely_matched_a_fails() {
        let mut m = measures(0.01, Some(0.01));
        m.area_ratio = Some(0.2);
        let squeezed = Confidence::of(m.clone());
        assert_eq!(squeezed.verdict, Verdict::Failed);
        assert!(squeezed.reasons[0].contains("squeezed"));
        m.area_ratio = Some(1.0);
        m.matched_fraction_a = 0.3;
        assert_eq!(Confidence::of(m.clone()).verdict, Verdict::Doubtful);
        m.matched_fraction_a = 0.1;
        assert_eq!(Confidence::of(m).verdict, Verdict::Failed);
    }

    /// A landmark left beyond 1.25 reaches makes an `ok` match `doubtful` and names the
    /// landmark (the worst of them); one within it, or no landmarks, changes nothing, and
    /// a `failed` match stays `failed`.
    #[test]
    fn a_landmark_left_behind_makes_a_match_doubtful() {
        let fit = |name: &str, after: f64| super::super::super::FeatureFit {
            name: name.into(),
            vertices: 1,
            before: 0.02,
            after,
            after_max: after,
            reach: 0.01,
        };
        let fits = [
            fit("landmark:nose_tip", 0.001),
            fit("landmark:mouth_corner_l", 0.02),
            fit("landmark:eye_inner_l", 0.013),
            fit("hole:0:upper", 0.05),
        ];
        let with_miss = |miss: Option<f64>, coarse: f64| {
            let mut c = Confidence::of(Measures {
                landmark_miss: miss,
                ..measures(coarse, Some(0.01))
            });
            c.doubt_landmarks_left_behind(&fits);
            c
        };
        let left = with_miss(Some(2.0), 0.01);
        assert_eq!(left.verdict, Verdict::Doubtful);
        assert!(
            left.reasons[0].contains("\"landmark:mouth_corner_l\" 2.0 times"),
            "{:?}",
            left.reasons
        );
        assert_eq!(with_miss(Some(1.2), 0.01).verdict, Verdict::Ok);
        assert_eq!(with_miss(None, 0.01).verdict, Verdict::Ok);
        let failed = with_miss(Some(2.0), 0.67);
        assert_eq!(failed.verdict, Verdict::Failed);
        assert_eq!(failed.reasons.len(), 1, "{:?}", failed.reasons);
    }
}
