//! A sequence of frames (one face moving, thesis §6.2) registered in order, each frame
//! from the previous one's result, and how much the registered vertices jitter.
//!
//! **Each frame from the template** (the default of `surfmap register --sequence`):
//! every frame is registered as any scan is ([`super::register_scan`]); the sequence adds
//! the order and the jitter measures below.
//!
//! **Warm start** (optional): frame 0 is registered from the template; frame `k` from
//! frame `k − 1`'s result: the template's triangles at the positions registered on frame
//! `k − 1` (`R_{k−1}`) are matched onto frame `k`, and [`super::place_on_scan`] places
//! `R_{k−1}`'s vertices (numbered as the template's) on frame `k`. Consecutive frames
//! differ by a small motion, so that match compares two nearly equal shapes, and the
//! matching energy, which keeps φ close to the source's own parametrization, keeps each
//! vertex near where it sat on the previous frame instead of pulling it towards the
//! template's shape. It costs one match per frame, as without it, and needs nothing the
//! matcher does not take already (no initial φ: `match_meshes` has no such input). The
//! price is drift: frame `k`'s error is frame `k − 1`'s plus the new match's own.
//! Measured on ICT sequences (docs/bench/sequence.md) the new match's own error is
//! about as large as a match from the template, so the errors add up (mean error
//! 0.50 % against 0.34 % of the face width over 8 frames of a smile) and the jitter does
//! not drop: the warm start is not the default.
//!
//! With the warm start, a frame that cannot be registered, or whose verdict is not `ok`,
//! is never a start:
//! the next frame starts from the last good registration (the template if none), so one
//! bad frame does not carry into the rest.
//!
//! **Jitter** without ground truth ([`frame_motions`]): with `R_k` the registered
//! positions of frame `k` and `T_{j→k}` the rigid motion (rotation + translation, least
//! squares over all vertices, Horn's closed form) carrying `R_j` onto `R_k`,
//!
//! ```text
//! motion_k = mean_i |R_k,i − T_{k−1→k}(R_{k−1,i})|                 (non-rigid motion since k − 1)
//! jitter_k,i = |R_k,i − ½ (T_{k−1→k}(R_{k−1,i}) + T_{k+1→k}(R_{k+1,i}))|
//! ```
//!
//! `jitter` is half the second difference in time after the head's rigid motion is
//! taken out: zero for any vertex that moves on a straight line at a steady pace
//! between the three frames (as a linear blend of two expressions does), large for a
//! vertex that slides back and forth on the skin from frame to frame. Its mean and 95th
//! percentile go into the summary; the first and last frame have none.

use super::{RegisterError, Registered, Template, place_on_scan};
use crate::matching::similarity::fit_similarity_3d;
use crate::matching::{Guidance, MatchOptions, match_meshes};
use crate::mesh::TriMesh;

/// Registers `scan` from an earlier registration `previous` (the template's vertices
/// registered on the frame before, in the template's order), as the
/// [module documentation](self) says; `None` registers from the template. The guidance
/// is numbered as the template and the scan are.
pub fn register_frame(
    template: &Template,
    previous: Option<&[[f64; 3]]>,
    scan: &TriMesh,
    guidance: &Guidance,
    options: &MatchOptions,
) -> Result<Registered, RegisterError> {
    let Some(previous) = previous else {
        return super::register_scan(template, scan, guidance, options);
    };
    if previous.len() != template.mesh.num_vertices() {
        return Err(RegisterError::Template(format!(
            "the previous frame's registration has {} vertices, the template {}: it belongs to another template",
            previous.len(),
            template.mesh.num_vertices()
        )));
    }
    let source = TriMesh::new(previous.to_vec(), template.mesh.triangles.clone());
    let matched_with = match_meshes(&source, scan, guidance, options)?;
    let placement = place_on_scan(&source, scan, &matched_with.correspondence)?;
    Ok(Registered {
        placement,
        matched_with,
    })
}

/// The motion of one frame of a registered sequence ([module documentation](self)), in
/// the scans' units; `None` where a neighbour frame is missing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameMotion {
    /// Mean non-rigid displacement since the previous frame.
    pub motion_mean: Option<f64>,
    /// Mean and 95th percentile (nearest rank) of half the rigidly aligned second
    /// difference.
    pub jitter_mean: Option<f64>,
    pub jitter_p95: Option<f64>,
}

/// The motion and jitter of every frame of a registered sequence: `frames[k]` the
/// registered positions of frame `k` (all with the template's vertex count), `None` for a
/// frame that was not registered (its neighbours then have no jitter).
pub fn frame_motions(frames: &[Option<&[[f64; 3]]>]) -> Vec<FrameMotion> {
    // `a` carried rigidly onto `b` (None when the fit is degenerate or counts differ).
    let onto = |a: &[[f64; 3]], b: &[[f64; 3]]| -> Option<Vec<[f64; 3]>> {
        if a.len() != b.len() || a.is_empty() {
            return None;
        }
        let t = fit_similarity_3d(a, b, &vec![1.0; a.len()], false)?;
        Some(a.iter().map(|&p| t.apply(p)).collect())
    };
    let dist = |p: [f64; 3], q: [f64; 3]| crate::vec3::norm3(crate::vec3::sub3(p, q));
    (0..frames.len())
        .map(|k| {
            let Some(current) = frames[k] else {
                return FrameMotion::default();
            };
            let before = k
                .checked_sub(1)
                .and_then(|j| frames[j])
                .and_then(|p| onto(p, current));
            let after = frames
                .get(k + 1)
                .copied()
                .flatten()
                .and_then(|n| onto(n, current));
            let motion_mean = before.as_ref().map(|b| {
                b.iter()
                    .zip(current)
                    .map(|(&p, &q)| dist(p, q))
                    .sum::<f64>()
                    / current.len() as f64
            });
            let (jitter_mean, jitter_p95) = match (&before, &after) {
                (Some(b), Some(a)) => {
                    let mut jitter: Vec<f64> = current
                        .iter()
                        .zip(b.iter().zip(a))
                        .map(|(&y, (&p, &n))| dist(y, std::array::from_fn(|c| 0.5 * (p[c] + n[c]))))
                        .collect();
                    let (mean, p95, _) = crate::apps::correspondence::summary(&mut jitter);
                    (Some(mean), Some(p95))
                }
                _ => (None, None),
            };
            FrameMotion {
                motion_mean,
                jitter_mean,
                jitter_p95,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dist3(p: [f64; 3], q: [f64; 3]) -> f64 {
        crate::vec3::norm3(crate::vec3::sub3(p, q))
    }

    /// A small cloud moved by the rotation `angle` about z and the translation `t`.
    fn moved(points: &[[f64; 3]], angle: f64, t: [f64; 3]) -> Vec<[f64; 3]> {
        let (s, c) = angle.sin_cos();
        points
            .iter()
            .map(|p| {
                [
                    c * p[0] - s * p[1] + t[0],
                    s * p[0] + c * p[1] + t[1],
                    p[2] + t[2],
                ]
            })
            .collect()
    }

    #[test]
    fn jitter_is_zero_for_steady_motion_and_measures_a_wobble() {
        let base: Vec<[f64; 3]> = (0..40)
            .map(|i| {
                let x = (i % 8) as f64;
                let y = (i / 8) as f64;
                [x, y, 0.1 * x * y]
            })
            .collect();
        // The cloud grows by 1 % of its size per frame about its centroid (non-rigid, and
        // nothing a rigid motion can take out) and every frame is moved rigidly by a
        // pose of its own: the jitter is 0 (steady growth), the motion 1 % of the mean
        // distance from the centroid.
        let n = base.len() as f64;
        let c: [f64; 3] = std::array::from_fn(|d| base.iter().map(|p| p[d]).sum::<f64>() / n);
        let grown = |k: usize| -> Vec<[f64; 3]> {
            let s = 1.0 + 0.01 * k as f64;
            base.iter()
                .map(|p| std::array::from_fn(|d| c[d] + s * (p[d] - c[d])))
                .collect()
        };
        let frames: Vec<Vec<[f64; 3]>> = (0..4)
            .map(|k| moved(&grown(k), 0.2 * k as f64, [k as f64, -2.0 * k as f64, 0.5]))
            .collect();
        let views: Vec<Option<&[[f64; 3]]>> = frames.iter().map(|f| Some(&f[..])).collect();
        let m = frame_motions(&views);
        assert_eq!(m[0].motion_mean, None);
        assert_eq!(m[0].jitter_mean, None);
        assert_eq!(m[3].jitter_mean, None);
        let spread = base.iter().map(|p| dist3(*p, c)).sum::<f64>() / n;
        for (k, f) in m.iter().enumerate().skip(1) {
            let motion = f.motion_mean.unwrap();
            assert!((motion - 0.01 * spread).abs() < 1e-9, "{k}: {motion}");
        }
        for f in &m[1..3] {
            assert!(f.jitter_mean.unwrap() < 1e-9, "{f:?}");
        }
        // Vertex 5 of frame 2 slides by 0.4 along x and back: the rigid fits onto frame 2
        // take a share of it to every vertex (a translation of ≈ 0.4 / 40), so the mean
        // jitter is between 0.4 / 40 (vertex 5 alone) and twice that; the 95th
        // percentile, below the one large value, stays small.
        let mut wobbly = frames.clone();
        let mut f2 = grown(2);
        f2[5][0] += 0.4;
        wobbly[2] = moved(&f2, 0.4, [2.0, -4.0, 0.5]);
        let views: Vec<Option<&[[f64; 3]]>> = wobbly.iter().map(|f| Some(&f[..])).collect();
        let m = frame_motions(&views);
        let j = m[2].jitter_mean.unwrap();
        assert!(j > 0.4 / n && j < 2.2 * 0.4 / n, "{j}");
        assert!(m[2].jitter_p95.unwrap() < 0.05, "{:?}", m[2]);
        // A missing frame leaves its neighbours without jitter.
        let views = [Some(&frames[0][..]), None, Some(&frames[2][..])];
        let m = frame_motions(&views);
        assert!(m.iter().all(|f| f.jitter_mean.is_none()));
        assert_eq!(m[2].motion_mean, None);
    }
}
