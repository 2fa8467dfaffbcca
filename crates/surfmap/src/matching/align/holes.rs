//! Hole rims as features: the rims of the holes filled for the flattenings (eyes,
//! mouth) are paired across the surfaces after the alignment and matched as labelled
//! feature curves (thesis §3.2.2's feature term, (2.11), with automatic features).

use super::super::MatchError;
use super::super::options::HoleFeatures;
use super::super::prepare::surface::MatchSurface;
use super::super::similarity::Similarity2;
use crate::raster::{FeatureCurve, FeatureFile};

/// A pair of hole rims: `(hole of A, hole of B, distance of their centres in ω after the
/// alignment)`.
pub type HolePair = (usize, usize, f64);

/// A rim split at its corners: the `upper` and the `lower` arc, as indices into the rim's
/// loop (the corners in both).
pub type RimArcs = [Vec<usize>; 2];

/// Pairs the hole rims of A and B by the distance of their centres in ω after the
/// alignment `s` (closest pairs first), adds each pair to both surfaces as labelled
/// features — one closed curve `hole:k`, or, when the rims are elongated (a mouth, an
/// eye; [`split_rim_pair`] with `split_min_elongation`), two arcs `hole:k:upper` and
/// `hole:k:lower` — and returns the pairs and which of them were split.
pub(crate) fn add_hole_features(
    sa: &mut MatchSurface,
    sb: &mut MatchSurface,
    s: &Similarity2,
    mode: HoleFeatures,
    split_min_elongation: f64,
) -> Result<(Vec<HolePair>, Vec<usize>), MatchError> {
    let (ra, rb) = (sa.hole_rims(), sb.hole_rims());
    if ra.len() != rb.len() || ra.is_empty() {
        return if mode == HoleFeatures::On {
            Err(MatchError::Guidance(format!(
                "hole features pair the rims one to one, but A has {} holes and B has {}; \
                 fill or cut the extra holes, or turn hole features off",
                ra.len(),
                rb.len()
            )))
        } else {
            Ok((vec![], vec![]))
        };
    }
    let centre = |surface: &MatchSurface, rim: &[u32]| {
        let m = rim.iter().fold([0.0; 2], |acc, &v| {
            let p = surface.vertex_domain_position(v as usize);
            [acc[0] + p[0], acc[1] + p[1]]
        });
        [m[0] / rim.len() as f64, m[1] / rim.len() as f64]
    };
    let ca: Vec<[f64; 2]> = ra.iter().map(|r| s.apply(centre(sa, r))).collect();
    let cb: Vec<[f64; 2]> = rb.iter().map(|r| centre(sb, r)).collect();
    let mut candidates = vec![];
    for (i, p) in ca.iter().enumerate() {
        for (j, q) in cb.iter().enumerate() {
            candidates.push(((p[0] - q[0]).hypot(p[1] - q[1]), i, j));
        }
    }
    candidates.sort_by(|x, y| x.0.total_cmp(&y.0));
    let (mut used_a, mut used_b) = (vec![false; ra.len()], vec![false; rb.len()]);
    let mut pairs = vec![];
    for (d, i, j) in candidates {
        if !used_a[i] && !used_b[j] {
            used_a[i] = true;
            used_b[j] = true;
            pairs.push((i, j, d));
        }
    }
    // A rim is paired unambiguously when its partner is clearly closer than any other
    // rim of B: the pairing distance below half the distance between B's rims.
    let spread = (0..cb.len())
        .flat_map(|i| (i + 1..cb.len()).map(move |j| (i, j)))
        .map(|(i, j)| (cb[i][0] - cb[j][0]).hypot(cb[i][1] - cb[j][1]))
        .fold(f64::INFINITY, f64::min);
    if pairs.iter().any(|p| p.2 > 0.5 * spread) {
        return if mode == HoleFeatures::On {
            Err(MatchError::Guidance(
                "the hole rims of A and B do not pair up after the alignment (a rim is as close to \
                 two rims of the other surface); give landmarks or turn hole features off"
                    .into(),
            ))
        } else {
            Ok((vec![], vec![]))
        };
    }
    let mut split_pairs = vec![];
    let (mut file_a, mut file_b) = (
        FeatureFile { features: vec![] },
        FeatureFile { features: vec![] },
    );
    for (k, &(i, j, _)) in pairs.iter().enumerate() {
        let pa: Vec<[f64; 2]> = ra[i]
            .iter()
            .map(|&v| s.apply(sa.vertex_domain_position(v as usize)))
            .collect();
        let pb: Vec<[f64; 2]> = rb[j]
            .iter()
            .map(|&v| sb.vertex_domain_position(v as usize))
            .collect();
        match split_rim_pair(&pa, &pb, split_min_elongation) {
            Some((arcs_a, arcs_b)) => {
                split_pairs.push(k);
                for (side, (xa, xb)) in ["upper", "lower"].iter().zip(arcs_a.iter().zip(&arcs_b)) {
                    let curve = |rim: &[u32], arc: &[usize]| FeatureCurve {
                        name: format!("hole:{k}:{side}"),
                        vertices: arc.iter().map(|&q| rim[q]).collect(),
                        closed: false,
                    };
                    file_a.features.push(curve(&ra[i], xa));
                    file_b.features.push(curve(&rb[j], xb));
                }
            }
            None => {
                let curve = |rim: &[u32]| FeatureCurve {
                    name: format!("hole:{k}"),
                    vertices: rim.to_vec(),
                    closed: true,
                };
                file_a.features.push(curve(&ra[i]));
                file_b.features.push(curve(&rb[j]));
            }
        }
    }
    // Both surfaces' distance maps at once (each is parallel over its few features).
    let (done_a, done_b) = rayon::join(
        || sa.add_curve_features(&file_a),
        || sb.add_curve_features(&file_b),
    );
    done_a?;
    done_b?;
    Ok((pairs, split_pairs))
}

/// Splits a pair of hole rims, given as closed polygons in one frame (A's after the
/// alignment, B's), at their corners into two arcs each, paired side by side.
///
/// The axis is the principal axis of the more elongated rim (the eigenvector of the
/// larger eigenvalue of its length-weighted second moment; elongation `√(λ₁/λ₂)`), used
/// for both so the corners correspond: each rim's corners are its extreme vertices along
/// that axis, its two arcs the loop's runs from one corner to the other (corners in
/// both), and the arc lying farther along the normal `n` of the axis is the `upper` one
/// on both rims. A closed mouth (a slit) then pairs its upper lip with the open mouth's
/// upper lip — as one closed curve it could sit on either lip of the other. Returns
/// `None` (keep one closed curve) when neither rim is elongated by `min_elongation`,
/// where the corners would be arbitrary, when `min_elongation` is 0 (never split), or
/// when a rim has fewer than four vertices or all of them at one point.
pub fn split_rim_pair(
    pa: &[[f64; 2]],
    pb: &[[f64; 2]],
    min_elongation: f64,
) -> Option<(RimArcs, RimArcs)> {
    if pa.len() < 4 || pb.len() < 4 || min_elongation <= 0.0 {
        return None;
    }
    let axis = |p: &[[f64; 2]]| -> Option<([f64; 2], f64)> {
        let n = p.len();
        // Each vertex weighs half its two edges' lengths.
        let d = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
        let weights: Vec<f64> = (0..n)
            .map(|i| 0.5 * (d(p[i], p[(i + 1) % n]) + d(p[i], p[(i + n - 1) % n])))
            .collect();
        let (mut w, mut c) = (0.0, [0.0; 2]);
        for (q, &wi) in p.iter().zip(&weights) {
            w += wi;
            c = [c[0] + wi * q[0], c[1] + wi * q[1]];
        }
        if w <= 0.0 || !w.is_finite() {
            return None; // all vertices at one point
        }
        let c = [c[0] / w, c[1] / w];
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for (q, &wi) in p.iter().zip(&weights) {
            let (x, y) = (q[0] - c[0], q[1] - c[1]);
            sxx += wi * x * x;
            sxy += wi * x * y;
            syy += wi * y * y;
        }
        // Eigen-decomposition of the symmetric 2×2 moment.
        let (m, d) = (
            0.5 * (sxx + syy),
            (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt(),
        );
        let (l1, l2) = (m + d, (m - d).max(0.0));
        let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let elongation = if l2 > 0.0 {
            (l1 / l2).sqrt()
        } else {
            f64::INFINITY
        };
        Some(([angle.cos(), angle.sin()], elongation))
    };
    let (ua, ea) = axis(pa)?;
    let (ub, eb) = axis(pb)?;
    let (u, e) = if ea >= eb { (ua, ea) } else { (ub, eb) };
    if e < min_elongation {
        return None;
    }
    let normal = [-u[1], u[0]];
    let arcs = |p: &[[f64; 2]]| -> Option<RimArcs> {
        let n = p.len();
        let along = |q: &[f64; 2]| q[0] * u[0] + q[1] * u[1];
        let first = (0..n).min_by(|&x, &y| along(&p[x]).total_cmp(&along(&p[y])))?;
        let last = (0..n).max_by(|&x, &y| along(&p[x]).total_cmp(&along(&p[y])))?;
        if first == last {
            return None;
        }
        let run = |from: usize, to: usize| -> Vec<usize> {
            let len = (to + n - from) % n;
            (0..=len).map(|t| (from + t) % n).collect()
        };
        let (one, two) = (run(first, last), run(last, first));
        let side = |arc: &[usize]| {
            arc.iter()
                .map(|&q| p[q][0] * normal[0] + p[q][1] * normal[1])
                .sum::<f64>()
                / arc.len() as f64
        };
        Some(if side(&one) >= side(&two) {
            [one, two]
        } else {
            [two, one]
        })
    };
    Some((arcs(pa)?, arcs(pb)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An ellipse with semi-axes `a` (along `angle`) and `b`, centred at `c`, sampled at
    /// `n` points starting at parameter `t0`, counter-clockwise unless `clockwise`.
    fn ellipse(
        n: usize,
        (a, b): (f64, f64),
        angle: f64,
        c: [f64; 2],
        t0: f64,
        clockwise: bool,
    ) -> Vec<[f64; 2]> {
        (0..n)
            .map(|k| {
                let t = t0 + std::f64::consts::TAU * k as f64 / n as f64;
                let t = if clockwise { -t } else { t };
                let (x, y) = (a * t.cos(), b * t.sin());
                let (s, co) = angle.sin_cos();
                [c[0] + co * x - s * y, c[1] + s * x + co * y]
            })
            .collect()
    }

    /// The signed distance of `p` from the line through `c` along `angle`.
    fn side(p: [f64; 2], c: [f64; 2], angle: f64) -> f64 {
        let (s, co) = angle.sin_cos();
        -(p[0] - c[0]) * s + (p[1] - c[1]) * co
    }

    #[test]
    fn a_closed_mouth_pairs_its_lips_with_an_open_mouths() {
        // A: a slit (a closed mouth), 40 vertices, starting mid-lip, counter-clockwise;
        // B: an open mouth (elongation 1.4), 26 vertices, starting elsewhere, clockwise,
        // slightly turned and moved. Both in one frame, as after the alignment.
        let (ca, cb) = ([0.5, 0.4], [0.51, 0.39]);
        let pa = ellipse(40, (0.1, 0.004), 0.0, ca, 0.3, false);
        let pb = ellipse(26, (0.09, 0.064), 0.1, cb, 2.0, true);
        let (arcs_a, arcs_b) = split_rim_pair(&pa, &pb, 2.0).expect("a slit is elongated");
        for (p, arcs, c, angle) in [(&pa, &arcs_a, ca, 0.0), (&pb, &arcs_b, cb, 0.1)] {
            let [upper, lower] = arcs;
            // The corners (the arcs' shared ends) are the rim's extreme vertices along the
            // slit's axis; together the arcs cover the rim once plus the two corners.
            assert_eq!(upper.first(), lower.last());
            assert_eq!(upper.last(), lower.first());
            assert_eq!(upper.len() + lower.len(), p.len() + 2);
            let mut all: Vec<usize> = upper.iter().chain(lower).copied().collect();
            all.sort_unstable();
            all.dedup();
            assert_eq!(all.len(), p.len());
            let along = |q: usize| p[q][0];
            let ends = [upper[0], *upper.last().unwrap()];
            let min = (0..p.len())
                .min_by(|&x, &y| along(x).total_cmp(&along(y)))
                .unwrap();
            let max = (0..p.len())
                .max_by(|&x, &y| along(x).total_cmp(&along(y)))
                .unwrap();
            assert!(
                ends.contains(&min) && ends.contains(&max),
                "{ends:?} {min} {max}"
            );
            // Every inner vertex of the upper arc lies on the upper side, and the lower's
            // below.
            for &q in &upper[1..upper.len() - 1] {
                assert!(side(p[q], c, angle) > 0.0, "upper {q}: {:?}", p[q]);
            }
            for &q in &lower[1..lower.len() - 1] {
                assert!(side(p[q], c, angle) < 0.0, "lower {q}: {:?}", p[q]);
            }
        }
    }

    #[test]
    fn round_or_tiny_rims_stay_whole() {
        let circle = ellipse(30, (0.05, 0.05), 0.0, [0.5, 0.5], 0.0, false);
        let oval = ellipse(30, (0.06, 0.04), 0.7, [0.5, 0.5], 0.0, false);
        let slit = ellipse(30, (0.06, 0.01), 0.7, [0.5, 0.5], 0.0, false);
        assert!(split_rim_pair(&circle, &oval, 2.0).is_none());
        assert!(split_rim_pair(&circle, &slit, 2.0).is_some());
        assert!(
            split_rim_pair(&circle, &slit, 0.0).is_none(),
            "0 never splits"
        );
        assert!(split_rim_pair(&slit[..3], &slit, 2.0).is_none());
        let point = vec![[0.5, 0.5]; 6];
        assert!(split_rim_pair(&point, &point, 2.0).is_none(), "no axis");
    }
}
