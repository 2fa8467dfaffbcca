//! A mouth that opens between A and B (neutral → jaw open): the weights that let the
//! lips lead the solve.
//!
//! When one face's mouth is open and the other's closed, the lower lip, the chin and
//! everything between move by centimetres against the rest of the face. With the default
//! weights the solve does not follow: the position term (which compares the surfaces in
//! space after one map `T` of the whole face, plus the smooth part of their residual)
//! holds the chin near `T`'s place, and the lip rims' feature term (thesis (2.11)) — the
//! only term that knows where the lower lip went — is too weak to drag it (measured on
//! the ICT neutral → jaw-open pairs, seeds 10–12: the region 1–4 cm below A's mouth
//! followed only 40–50 % of the jaw's motion, and the lower-lip rim stayed 2 cm from
//! B's). The thesis's answer is the feature curves: with the lip arcs weighted
//! [`OPEN_FEATURE_FACTOR`] times more and the position weight capped at
//! [`OPEN_POSITION_WEIGHT`], the same pairs follow the motion fully (0.97–1.02 of it),
//! and the rig's jaw-open key comes closer to the truth on every referee seed tried
//! (7, 10–13: 1.31–1.52 → 1.05–1.32 % of the face width; BENCHMARKS.md, "Rig accuracy").
//! Elsewhere the position term is what makes matches of different faces close, so the
//! change applies only when a mouth opens. The cap holds over the whole face: capped
//! only within `r` mouth widths of A's rim (full weight beyond, smoothly between) it was
//! worse — `r` = 0.5–1.3: 1.43–1.62 % on seeds 10 and 12, `r` = 1.5–2.5: 1.28 / 1.05 —
//! as the face held beyond holds the chin back; so was a full weight kept where A,
//! placed by the rigid alignment, already lies on B (factor `f + (1 − f)·exp(−(d/w)²)`,
//! `d` the distance to B, `w` 0.2–0.5 mouth widths: 1.40–1.57 % on seeds 10, 12, 13).
//!
//! **With landmarks or features: from their alignment refined in space, alone.** With
//! the referee's seven landmarks the same weights, applied to the better of the two
//! starts as before, made the jaw-open key worse — seeds 7 / 10 / 13: 1.43 / 1.53 /
//! 1.45 % before, 1.87 / 1.55 / 1.97 % with only the rims weighted up: the landmarks'
//! plane similarity (its scale off by the mouth corners that moved with the jaw) then
//! wins the comparison of the two starts, and its lower lip stays 1.3 cm from B's. So
//! when a mouth opens and the landmarks' alignment refined in space exists, the solve
//! starts from it alone (the two starts are not compared) with the weights above: rig
//! jaw key 1.45 / 1.43 / 1.53 → 1.34 / 1.40 / 1.14 % (lips p95 6.25 / 6.36 / 6.17 →
//! 3.37 / 5.60 / 4.56 %), the referee's jaw pair 94.0 / 93.9 / 93.5 → 97.4 / 94.9 /
//! 98.9 % within 0.05. Kept comparing the two starts it was 2.03 / 1.96 / 1.57 %. With
//! no alignment in space (`--features-start plane`) the rule does not apply.
//!
//! **Opening.** A rim split at its corners ([`super::holes::split_rim_pair`]: upper and
//! lower arc) has the opening `o` = the mean distance between its arcs, resampled corner
//! to corner at equal fractions of their 3D arc length, over the middle half, divided by
//! the distance of the corners. A mouth *opens* between A and B when
//! `max(o_A, o_B) ≥` [`OPEN_MIN`] and `max ≥` [`OPEN_RATIO`]` · min` (either way round).
//! Measured on the ICT crops: neutral 0.22, smiles 0.18, pucker 0.26, jaw open 0.96.
//!
//! **A mouth ajar is not a jaw that opens.** The FLAME meshes' mouth loops lie deep in the
//! mouth, past the lips' inside: `template` 0.29–0.30, `sample02` 0.23, `registered` and
//! `lmkfit` 0.44–0.69 (the last varies with B's remeshing). With the earlier
//! [`OPEN_MIN`] of 0.4, 13 of the 120 FLAME matches of seeds 7–17 (`scripts/flame_pairs.py`,
//! without input and with landmarks) were taken for a jaw that opens, where the ratio of
//! 2 was met by a hair (0.45 against 0.227), and the weights above cost the partial pairs
//! 2.4–13 points within 0.05 (`sample02 → lmkfit`, seeds 9, 15, 17: 68.1–85.2 → 74.4–96.1 %;
//! `registered → sample02`, seed 17, identity: 79.9 → 91.5 %) for at most 0.7 on two
//! identity pairs (99.8 → 99.1 %). [`OPEN_MIN`] is now 0.8, between the most open mouth
//! ajar seen (0.69) and the ICT jaw open (0.96), which still opens on every seed.

use super::super::prepare::surface::MatchSurface;
use super::holes::HolePair;
use crate::vec3::{norm3, sub3};

/// Least opening (arc gap over corner distance) of the more open mouth (module docs:
/// 0.4 took mouths ajar for a jaw that opens).
pub(crate) const OPEN_MIN: f64 = 0.8;

/// The more open mouth must open this many times more than the other.
pub(crate) const OPEN_RATIO: f64 = 2.0;

/// The feature weight's factor when a mouth opens. Swept on the ICT jaw-open pairs of
/// seeds 10–12 (rig key mean error, % of the face width, with the position cap of
/// 1000): ×10 1.09–1.23, ×20 1.09–1.16 (seeds 11, 12), ×40 1.05–1.18, ×100 1.37 on
/// seed 10 (without either change 1.31–1.47).
pub(crate) const OPEN_FEATURE_FACTOR: f64 = 40.0;

/// The position weight's cap when a mouth opens (the automatic weight is 2000–2·10⁵,
/// ≈ 5·10⁴ on the ICT expression pairs). Swept with the feature factor ×40: 2000 up to
/// 0.05 worse than 1000 (seeds 11, 12), 3000 0.12 and 300 0.2 worse (seed 10).
pub(crate) const OPEN_POSITION_WEIGHT: f64 = 1000.0;

/// Samples of each arc, corner to corner.
const ARC_SAMPLES: usize = 41;

/// The mouth — of the hole pairs split at their corners, the one whose rim on A is
/// widest in space — as `(its index into the pairs, (o_A, o_B))`, or `None` without a
/// split pair.
pub(crate) fn mouth_openings(
    sa: &MatchSurface,
    sb: &MatchSurface,
    pairs: &[HolePair],
    split: &[usize],
) -> Option<(usize, (f64, f64))> {
    split
        .iter()
        .filter(|&&k| k < pairs.len())
        .filter_map(|&k| Some((k, opening(sa, k)?, opening(sb, k)?)))
        .max_by(|x, y| x.1.1.total_cmp(&y.1.1))
        .map(|(k, (oa, _), (ob, _))| (k, (oa, ob)))
}

/// Whether the openings say that a mouth opens between the surfaces (module docs).
pub(crate) fn opens(openings: Option<(f64, f64)>) -> bool {
    openings.is_some_and(|(a, b)| {
        let (lo, hi) = (a.min(b), a.max(b));
        hi >= OPEN_MIN && hi >= OPEN_RATIO * lo
    })
}

/// The opening of the split rim `hole:k` of `surface` and its corner distance (mesh
/// units), or `None` when the arcs are missing or degenerate.
fn opening(surface: &MatchSurface, k: usize) -> Option<(f64, f64)> {
    let arc = |side: &str| {
        let name = format!("hole:{k}:{side}");
        let curve = surface.feature_curves.iter().find(|c| c.name == name)?;
        let points: Vec<[f64; 3]> = curve
            .vertices
            .iter()
            .map(|&v| surface.positions.get(v as usize).copied())
            .collect::<Option<_>>()?;
        (points.len() >= 2).then(|| resample(&points, ARC_SAMPLES))
    };
    let (upper, mut lower) = (arc("upper")?, arc("lower")?);
    // Both arcs from the same corner.
    if dist(upper[0], lower[0]) > dist(upper[0], lower[ARC_SAMPLES - 1]) {
        lower.reverse();
    }
    let width = dist(upper[0], upper[ARC_SAMPLES - 1]);
    if width.is_nan() || width <= 0.0 {
        return None;
    }
    let middle = ARC_SAMPLES / 4..=3 * ARC_SAMPLES / 4;
    let gap = middle
        .clone()
        .map(|i| dist(upper[i], lower[i]))
        .sum::<f64>()
        / middle.count() as f64;
    Some((gap / width, width))
}

/// A polyline resampled at `count ≥ 2` equal fractions of its arc length.
fn resample(points: &[[f64; 3]], count: usize) -> Vec<[f64; 3]> {
    let mut cumulative = Vec::with_capacity(points.len());
    cumulative.push(0.0);
    for w in points.windows(2) {
        cumulative.push(cumulative.last().unwrap() + dist(w[0], w[1]));
    }
    let total = *cumulative.last().unwrap();
    (0..count)
        .map(|j| {
            let s = total * j as f64 / (count - 1) as f64;
            let k = cumulative[1..]
                .partition_point(|&c| c < s)
                .min(points.len() - 2);
            let span = cumulative[k + 1] - cumulative[k];
            let t = if span > 0.0 {
                ((s - cumulative[k]) / span).clamp(0.0, 1.0)
            } else {
                0.0
            };
            std::array::from_fn(|c| points[k][c] + t * (points[k + 1][c] - points[k][c]))
        })
        .collect()
}

fn dist(p: [f64; 3], q: [f64; 3]) -> f64 {
    norm3(sub3(p, q))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Resampling a straight polyline of uneven pieces gives equal steps.
    #[test]
    fn resampling_spaces_points_equally_along_the_curve() {
        let pts = [
            [0.0, 0.0, 0.0],
            [0.1, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 2.0, 0.0],
        ];
        let r = resample(&pts, 7);
        for w in r.windows(2) {
            assert!((dist(w[0], w[1]) - 0.5).abs() < 1e-12, "{r:?}");
        }
        assert_eq!(r[6], [1.0, 2.0, 0.0]);
    }

    #[test]
    fn a_mouth_opens_only_when_one_is_open_and_much_more_than_the_other() {
        assert!(opens(Some((0.22, 0.96))));
        assert!(opens(Some((0.96, 0.22))), "either way round");
        assert!(!opens(Some((0.22, 0.26))), "pucker");
        assert!(!opens(Some((0.3, 0.5))), "open, but less than twice");
        assert!(!opens(Some((0.1, 0.35))), "twice, but not open");
        assert!(
            !opens(Some((0.227, 0.69))),
            "ajar (FLAME sample02 → lmkfit), not a jaw"
        );
        assert!(!opens(Some((0.45, 0.22))), "ajar, twice a closed one's");
        assert!(!opens(None));
    }
}
