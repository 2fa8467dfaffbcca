//! Rigid alignment of two surfaces in space by trimmed point-to-plane ICP (iterative
//! closest points with the worst pairs dropped, Chetverikov et al. 2002; distances
//! measured along B's normals, Chen & Medioni 1991, so that a surface slides onto the
//! other instead of snapping vertex to vertex), started from the 24
//! rotations of the cube's symmetry group about the centroids (every rotation is within
//! 62.8° of one of them), from the four rotations that align the principal axes, from
//! those 28 again shifted across B's extent ([`SHIFT`]: crops that overlap in part have
//! centroids that do not correspond), and from the caller's candidates.
//!
//! Used by the matcher's automatic alignment (`super::solve`): the rigid motion
//! pairs A's vertices with their closest vertices of B, which gives the similarity of
//! the parameter domains. Trimming (the best [`KEEP`] of the pairs) lets a partial
//! overlap align without its unmatched rim dragging it. Cost: `O(starts · iterations ·
//! samples · log n_B)` with a k-d tree over B's vertices (`kiddo`); the many rough
//! starts pair with at most [`COARSE_TARGETS`] of B's vertices, so that their cost does
//! not grow with B's resolution, the shifted starts far behind the best after
//! `SCREEN_STEPS` stop there (`SCREEN_CUT`), any start far behind the best after
//! `COARSE_PROBE` steps stops there (`COARSE_CUT`), and only the best pose is
//! refined against all of B.

use rayon::prelude::*;

use super::similarity::Similarity3;
use crate::linsolve::dense::symmetric_eigen;
use crate::mesh::closest::ClosestPoints;
use crate::vec3::{cross3 as cross, dot3 as dot, norm3 as norm, sub3 as sub};

/// Fraction of the pairs (closest first) that each ICP step fits.
pub const KEEP: f64 = 0.7;

/// Most vertices of B that the coarse ICP starts of [`align_rigidly_ranked`] pair with (an even
/// subsample of B's vertices when it has more): 25 targets per coarse point of A (400),
/// so that B is sampled far more densely than A while the 52 starts' closest-vertex
/// queries — most of the alignment's time — no longer slow down with B's resolution
/// (a 47,653-vertex head scan: the coarse stage 0.80 → 0.30 s). The best pose is then
/// refined against all of B's vertices. Faces of ~10k vertices are not subsampled
/// (BENCHMARKS.md, "Matching": the coarse starts' targets).
pub const COARSE_TARGETS: usize = 10_000;

/// Pairings and steps of each coarse ICP start of [`align_rigidly_ranked`] (41: the 40
/// iterations of the earlier fixed loop and the final pairing's step).
const COARSE_STEPS: usize = 41;

/// Steps after which the coarse starts whose trimmed rms is more than [`COARSE_CUT`]
/// times the lowest stop: they are sliding into another pose than the best ones.
const COARSE_PROBE: usize = 21;

/// How far above the lowest rms after [`COARSE_PROBE`] steps a coarse start may be and
/// still go on. Measured on the 28 ICT and FLAME pairs (BENCHMARKS.md, "A cheaper rigid
/// alignment"): the start that ends best was at most 2.32 times the lowest after 21
/// steps (1.64 on the synthetic whole-onto-part test below, where it ranked only 18th
/// of 28 — a cut by rank would lose it); 4 times stops 9–42 of the ICT pairs' 48–52
/// starts, few of the coarser FLAME pairs'.
const COARSE_CUT: f64 = 4.0;

/// How far the shifted starts of [`align_rigidly_ranked`] move A from the centroid-to-centroid
/// starts: this fraction of B's extent, either way along each of B's two longest
/// principal axes (4 shifts of each cube and principal-axes start). Crops of a face on
/// opposite sides (a quarter of each without a counterpart) have centroids that do not
/// correspond, and from the centroids no start may reach the true pose: on two ICT pairs
/// of seed 8 the best pose found laid the face upside down (trimmed rms 0.27 cm) while
/// the true one fits at 0.11–0.13 cm; with the shifted starts both find it
/// (BENCHMARKS.md, "Shifted starts").
pub const SHIFT: f64 = 0.1;

/// Steps after which the shifted starts whose trimmed rms is more than [`SCREEN_CUT`]
/// times the lowest of all starts stop: running all 112 shifted starts the
/// [`COARSE_PROBE`] steps made the alignment about three times as slow (a seed-8 ICT
/// pair: 0.18 → 0.54 s).
const SCREEN_STEPS: usize = 5;

/// How far above the lowest rms after [`SCREEN_STEPS`] steps a shifted start may be and
/// still go on. The shifted starts that end best on the seed-8 pairs that needed them
/// were at 1.00–1.25 times the lowest then (BENCHMARKS.md, "Shifted starts").
const SCREEN_CUT: f64 = 1.5;

/// How much lower than the best unshifted start's rms a shifted start must end to be
/// taken instead. Where the shifted starts were needed (two seed-8 ICT partial pairs)
/// they end at 0.43 and 0.48 times it; where they merely slide a surface along another
/// of a different size, they end only slightly lower and the pose is no better: with
/// no margin, a copy shrunk to 0.8 of its size was laid off-centre (the matching test
/// `the_wide_metric_grows_a_shrunken_start_into_place`: 0.96 → 2.05 cells median
/// error) and five FLAME identity pairs moved (73.9 → 73.6 % within 0.02).
const SHIFTED_MARGIN: f64 = 0.7;

/// The best rigid motion found and its trimmed root-mean-square distances.
#[derive(Clone, Copy, Debug)]
pub struct RigidAlignment {
    pub motion: Similarity3,
    /// `√(Σ |p − q|² / n)` over the kept pairs: moved point `p`, its closest vertex `q`
    /// of the other surface. It grows with that surface's edges (a point halfway
    /// between two vertices is half an edge from either), so it measures the sampling
    /// as much as the shapes; used to pair vertices (a distance scale of the pairs).
    pub rms: f64,
    /// `√(Σ ((p − q)·n_q)² / n)` over the same pairs, `n_q` the other surface's vertex
    /// normal: the distance to `q`'s tangent plane, which the ICP step minimizes. On a
    /// smooth surface sampled with edges `h` the sampling adds only `O(κ h²)`
    /// (curvature `κ`), so this measures how far the shapes themselves are apart
    /// (`super::solve::PositionWeight`).
    pub plane_rms: f64,
}

/// The 24 rotations of the cube (signed permutation matrices with determinant +1).
fn cube_rotations() -> Vec<[[f64; 3]; 3]> {
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut out = vec![];
    for p in perms {
        for signs in 0..8 {
            let mut m = [[0.0; 3]; 3];
            for r in 0..3 {
                m[r][p[r]] = if signs >> r & 1 == 1 { -1.0 } else { 1.0 };
            }
            let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
            if det > 0.0 {
                out.push(m);
            }
        }
    }
    out
}

/// The four rotations that carry A's principal axes (of the point covariance) onto
/// B's, with the signs that keep them proper: the classic starting poses for shapes of
/// similar extent, whatever their relative orientation.
fn principal_axes_starts(
    a: &[[f64; 3]],
    b: &[[f64; 3]],
    ca: [f64; 3],
    cb: [f64; 3],
) -> Vec<Similarity3> {
    let (Some(ea), Some(eb)) = (principal_axes(a, ca), principal_axes(b, cb)) else {
        return vec![];
    };
    let mut out = vec![];
    for (s0, s1) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        // Columns: B's axes (third = cross product, keeping a proper rotation) times
        // A's axes transposed.
        let signs = [s0, s1];
        let mut fa = [[0.0; 3]; 3];
        let mut fb = [[0.0; 3]; 3];
        for k in 0..2 {
            for i in 0..3 {
                fa[k][i] = ea[k + 1][i];
                fb[k][i] = signs[k] * eb[k + 1][i];
            }
        }
        let cross = |u: [f64; 3], v: [f64; 3]| {
            [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ]
        };
        fa[2] = cross(fa[0], fa[1]);
        fb[2] = cross(fb[0], fb[1]);
        // R = Σ_k fb_k fa_kᵀ maps A's frame onto B's.
        let r: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| fb[k][i] * fa[k][j]).sum())
        });
        let rc: [f64; 3] =
            std::array::from_fn(|i| r[i][0] * ca[0] + r[i][1] * ca[1] + r[i][2] * ca[2]);
        out.push(Similarity3 {
            matrix: r,
            translation: std::array::from_fn(|i| cb[i] - rc[i]),
        });
    }
    out
}

/// The principal axes of `points` about their centroid `c`: the eigenvectors of the
/// point covariance, by increasing variance (for a face, the last two span its width
/// and height, the first is its depth).
fn principal_axes(points: &[[f64; 3]], c: [f64; 3]) -> Option<[[f64; 3]; 3]> {
    let mut m = [[0.0; 3]; 3];
    for x in points {
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += (x[i] - c[i]) * (x[j] - c[j]);
            }
        }
    }
    symmetric_eigen(&m).map(|(_, v)| v)
}

/// Every start of `starts` moved by `±SHIFT` times B's extent along each of B's two
/// longest principal axes (`b` the points, `cb` their centroid): 4 starts per start,
/// start by start.
fn shifted_starts(starts: &[Similarity3], b: &[[f64; 3]], cb: [f64; 3]) -> Vec<Similarity3> {
    let Some(axes) = principal_axes(b, cb) else {
        return vec![];
    };
    let mut shifts = vec![];
    for axis in [axes[2], axes[1]] {
        let (low, high) = b
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &p| {
                let t = dot(sub(p, cb), axis);
                (l.min(t), h.max(t))
            });
        for sign in [1.0, -1.0] {
            shifts.push(axis.map(|c| sign * SHIFT * (high - low) * c));
        }
    }
    starts
        .iter()
        .flat_map(|start| {
            shifts.iter().map(|d| Similarity3 {
                matrix: start.matrix,
                translation: std::array::from_fn(|i| start.translation[i] + d[i]),
            })
        })
        .collect()
}

/// `count` points of `points`, evenly spread over the index range (deterministic).
fn subsample(points: &[[f64; 3]], count: usize) -> Vec<[f64; 3]> {
    subsample_indices(points.len(), count)
        .into_iter()
        .map(|i| points[i])
        .collect()
}

/// `min(count, len)` indices of `0..len`, evenly spread (deterministic, increasing).
fn subsample_indices(len: usize, count: usize) -> Vec<usize> {
    let step = (len as f64 / count as f64).max(1.0);
    (0..count.min(len))
        .map(|i| ((i as f64 * step) as usize).min(len - 1))
        .collect()
}

fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
    let n = points.len().max(1) as f64;
    let s = points
        .iter()
        .fold([0.0; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]);
    s.map(|v| v / n)
}

/// Area-weighted vertex normals (unit; zero for isolated vertices).
pub fn vertex_normals(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<[f64; 3]> {
    let mut n = vec![[0.0; 3]; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let (u, v) = (sub(b, a), sub(c, a));
        let cr = cross(u, v);
        for &i in t {
            for k in 0..3 {
                n[i as usize][k] += cr[k];
            }
        }
    }
    for x in &mut n {
        let l = dot(*x, *x).sqrt();
        if l > 0.0 {
            *x = x.map(|c| c / l);
        }
    }
    n
}

/// The rotation by `angle` (radians, right-handed) about `axis` (any length; the
/// identity for a zero axis): Rodrigues' formula `R = cos θ I + sin θ [a]× + (1 − cos θ) a aᵀ`.
pub(crate) fn axis_angle_rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let n = dot(axis, axis).sqrt();
    if n == 0.0 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let a = axis.map(|v| v / n);
    let (s, c) = angle.sin_cos();
    let k = |i: usize, j: usize| a[i] * a[j] * (1.0 - c);
    [
        [c + k(0, 0), k(0, 1) - a[2] * s, k(0, 2) + a[1] * s],
        [k(1, 0) + a[2] * s, c + k(1, 1), k(1, 2) - a[0] * s],
        [k(2, 0) - a[1] * s, k(2, 1) + a[0] * s, c + k(2, 2)],
    ]
}

/// One linearized point-to-plane step (Chen & Medioni 1991, Low 2004): with the
/// pairs' current images `p`, targets `q` and target normals `n`, the small motion
/// `p ↦ p + ω × (p − c) + t` (c the centroid of the images) minimizing
/// `Σ ((p + ω × (p − c) + t − q) · n)²`, solved from the 6 × 6 normal equations by
/// eigen-decomposition with directions of (near) zero curvature left alone — the
/// motions along which the surface slides onto itself. Returned as the rigid motion
/// with the exact rotation of angle `|ω|` about `ω`.
fn point_to_plane_step(p: &[[f64; 3]], q: &[[f64; 3]], n: &[[f64; 3]]) -> Option<Similarity3> {
    let c = centroid(p);
    let mut a = [[0.0; 6]; 6];
    let mut b = [0.0; 6];
    for i in 0..p.len() {
        let pc = sub(p[i], c);
        let pn = cross(pc, n[i]);
        let j = [pn[0], pn[1], pn[2], n[i][0], n[i][1], n[i][2]];
        let r = dot(sub(p[i], q[i]), n[i]);
        for u in 0..6 {
            b[u] -= j[u] * r;
            for v in 0..6 {
                a[u][v] += j[u] * j[v];
            }
        }
    }
    let (values, vectors) = symmetric_eigen(&a)?;
    let largest = values.iter().fold(0.0f64, |m, &v| m.max(v));
    if largest <= 0.0 {
        return None;
    }
    let mut x = [0.0; 6];
    for k in 0..6 {
        if values[k] > 1e-9 * largest {
            let coefficient = (0..6).map(|u| vectors[k][u] * b[u]).sum::<f64>() / values[k];
            for u in 0..6 {
                x[u] += coefficient * vectors[k][u];
            }
        }
    }
    let omega = [x[0], x[1], x[2]];
    let angle = dot(omega, omega).sqrt();
    let r = axis_angle_rotation(omega, angle);
    // p ↦ R (p − c) + c + t.
    let rc: [f64; 3] = std::array::from_fn(|i| dot(r[i], c));
    Some(Similarity3 {
        matrix: r,
        translation: std::array::from_fn(|i| c[i] + x[3 + i] - rc[i]),
    })
}

/// Trimmed point-to-plane ICP from `start`: pairs each point of A (moved) with its
/// closest vertex of B, keeps the closest [`KEEP`] of the pairs and takes one
/// [`point_to_plane_step`] against B's vertex normals `normals`. Returns the motion
/// and the kept pairs' root-mean-square point-to-vertex and point-to-plane distances
/// (at the pairing of the last iteration).
fn icp(
    a: &[[f64; 3]],
    b: &[[f64; 3]],
    normals: &[[f64; 3]],
    closest: &ClosestPoints,
    start: Similarity3,
    iterations: usize,
) -> RigidAlignment {
    let mut run = IcpRun::new(start);
    run.advance(a, b, normals, closest, iterations + 1);
    run.alignment
}

/// An ICP that can be resumed: [`icp`]'s iterations `n` at a time, so that
/// `advance(n)` then `advance(m)` lands on the same motion, bit for bit, as
/// `advance(n + m)`.
#[derive(Clone, Copy, Debug)]
struct IcpRun {
    alignment: RigidAlignment,
    /// The last step moved the points by (almost) nothing, or could not be solved.
    stopped: bool,
}

impl IcpRun {
    fn new(start: Similarity3) -> Self {
        Self {
            alignment: RigidAlignment {
                motion: start,
                rms: f64::INFINITY,
                plane_rms: f64::INFINITY,
            },
            stopped: false,
        }
    }

    /// At most `steps` more pairings and steps (fewer once stopped).
    fn advance(
        &mut self,
        a: &[[f64; 3]],
        b: &[[f64; 3]],
        normals: &[[f64; 3]],
        closest: &ClosestPoints,
        steps: usize,
    ) {
        let RigidAlignment {
            mut motion,
            mut rms,
            mut plane_rms,
        } = self.alignment;
        let mut pairs: Vec<(f64, usize, usize)> = Vec::with_capacity(a.len());
        let (mut p, mut q, mut n) = (vec![], vec![], vec![]);
        for _ in 0..steps {
            if self.stopped {
                break;
            }
            pairs.clear();
            for (i, x) in a.iter().enumerate() {
                let (j, d2) = closest.closest(&motion.apply(*x));
                pairs.push((d2, i, j));
            }
            let keep = ((KEEP * pairs.len() as f64) as usize).clamp(3, pairs.len());
            pairs.select_nth_unstable_by(keep - 1, |x, y| x.0.total_cmp(&y.0));
            let kept = &pairs[..keep];
            rms = (kept.iter().map(|x| x.0).sum::<f64>() / keep as f64).sqrt();
            p.clear();
            q.clear();
            n.clear();
            for &(_, i, j) in kept {
                p.push(motion.apply(a[i]));
                q.push(b[j]);
                n.push(normals[j]);
            }
            plane_rms = (p
                .iter()
                .zip(&q)
                .zip(&n)
                .map(|((&x, &y), &normal)| dot(sub(x, y), normal).powi(2))
                .sum::<f64>()
                / keep as f64)
                .sqrt();
            let Some(step) = point_to_plane_step(&p, &q, &n) else {
                self.stopped = true;
                break;
            };
            let next = Similarity3 {
                matrix: std::array::from_fn(|i| {
                    std::array::from_fn(|j| {
                        (0..3)
                            .map(|k| step.matrix[i][k] * motion.matrix[k][j])
                            .sum()
                    })
                }),
                translation: step.apply(motion.translation),
            };
            // Size of the step: how far it moves the kept points at most (rotation part
            // bounded by the spread of the points).
            let moved = p
                .iter()
                .map(|x| {
                    let y = step.apply(*x);
                    dot(sub(y, *x), sub(y, *x))
                })
                .fold(0.0f64, f64::max)
                .sqrt();
            motion = next;
            if moved <= 1e-9 * (1.0 + rms) {
                self.stopped = true;
            }
        }
        self.alignment = RigidAlignment {
            motion,
            rms,
            plane_rms,
        };
    }
}

/// The rigid motion of ℝ³ that best puts surface A (points `a`) onto surface B
/// (points `b`): trimmed ICP on a subsample from 24 rotations about the centroids, the
/// four principal-axes poses, those 28 shifted (`shifted_starts`) and the caller's
/// `starts`, the best refined on more points; then up to `count − 1` other poses its
/// starts ended in, each distinct from those before it ([`distinct_poses`]), lowest rms first, each
/// refined as the first is: the alternatives a match that went wrong tries
/// (`crate::matching::align::alternatives`).
pub fn align_rigidly_ranked(
    a: &[[f64; 3]],
    b: &[[f64; 3]],
    normals: &[[f64; 3]],
    starts: &[Similarity3],
    count: usize,
) -> Vec<RigidAlignment> {
    align_rigidly_with(a, b, normals, starts, COARSE_TARGETS, true, count)
}

/// Whether two poses of A differ enough to be different alignments: turned more than
/// [`DISTINCT_ANGLE`] apart, or their translations (at A's centroid `c`) more than
/// `DISTINCT_SHIFT` of `extent` apart.
fn distinct_poses(p: &Similarity3, q: &Similarity3, c: [f64; 3], extent: f64) -> bool {
    let (m, n) = (p.matrix, q.matrix);
    // cos θ of the relative rotation Mᵀ N (both proper rotations): (tr − 1) / 2.
    let trace: f64 = (0..3)
        .map(|i| (0..3).map(|k| m[k][i] * n[k][i]).sum::<f64>())
        .sum();
    let angle = ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos();
    let (x, y) = (p.apply(c), q.apply(c));
    angle > DISTINCT_ANGLE || norm(sub(x, y)) > DISTINCT_SHIFT * extent
}

/// Poses turned further apart than this (radians, 30°) are different alignments.
const DISTINCT_ANGLE: f64 = std::f64::consts::PI / 6.0;

/// Poses whose A-centroids lie further apart than this fraction of B's extent are
/// different alignments.
const DISTINCT_SHIFT: f64 = 0.1;

/// [`align_rigidly_ranked`] with the coarse starts paired with at most `coarse_targets` of B's
/// vertices (an even subsample of them, with their normals, when B has more), with or
/// without the `shifted` starts.
fn align_rigidly_with(
    a: &[[f64; 3]],
    b: &[[f64; 3]],
    normals: &[[f64; 3]],
    starts: &[Similarity3],
    coarse_targets: usize,
    shifted: bool,
    count: usize,
) -> Vec<RigidAlignment> {
    if a.len() < 3 || b.len() < 3 {
        return vec![];
    }
    let closest = ClosestPoints::new(b);
    let subsampled;
    let (coarse_b, coarse_normals, coarse_closest) = if b.len() > coarse_targets.max(3) {
        let picked = subsample_indices(b.len(), coarse_targets.max(3));
        let points: Vec<[f64; 3]> = picked.iter().map(|&i| b[i]).collect();
        let picked_normals: Vec<[f64; 3]> = picked.iter().map(|&i| normals[i]).collect();
        let tree = ClosestPoints::new(&points);
        subsampled = (points, picked_normals, tree);
        (&subsampled.0[..], &subsampled.1[..], &subsampled.2)
    } else {
        (b, normals, &closest)
    };
    let (ca, cb) = (centroid(a), centroid(b));
    let coarse = subsample(a, 400);
    let mut all: Vec<Similarity3> = cube_rotations()
        .into_iter()
        .map(|r| {
            let rc: [f64; 3] =
                std::array::from_fn(|i| r[i][0] * ca[0] + r[i][1] * ca[1] + r[i][2] * ca[2]);
            Similarity3 {
                matrix: r,
                translation: std::array::from_fn(|i| cb[i] - rc[i]),
            }
        })
        .collect();
    all.extend(principal_axes_starts(a, b, ca, cb));
    let shifted = if shifted {
        shifted_starts(&all, b, cb)
    } else {
        vec![]
    };
    // The caller's starts can repeat (the plane search's refinements of neighbouring
    // rotations may end on one similarity: 0–5 of the 52 starts on the 28 ICT and FLAME
    // pairs); a repeat would only redo the same ICP bit for bit, so the first is kept.
    for start in starts {
        if !all.contains(start) {
            all.push(*start);
        }
    }
    let unshifted = all.len();
    all.extend(shifted);
    // Every start for SCREEN_STEPS steps; the shifted ones go on only within
    // SCREEN_CUT of the lowest rms. Then every start left to COARSE_PROBE steps; only
    // those within COARSE_CUT of the lowest of their kind (the unshifted ones: of the
    // unshifted) go on to the full COARSE_STEPS. Runs resume bit for bit, so the best
    // unshifted start ends as it did without the shifted ones; a shifted one replaces
    // it only when it ends below SHIFTED_MARGIN times its rms.
    let advance = |runs: Vec<(bool, IcpRun)>, steps: usize| -> Vec<(bool, IcpRun)> {
        runs.into_par_iter()
            .map(|(shifted, mut run)| {
                run.advance(&coarse, coarse_b, coarse_normals, coarse_closest, steps);
                (shifted, run)
            })
            .collect()
    };
    let lowest = |runs: &[(bool, IcpRun)], only_unshifted: bool| {
        runs.iter()
            .filter(|(shifted, _)| !(only_unshifted && *shifted))
            .map(|(_, run)| run.alignment.rms)
            .fold(f64::INFINITY, f64::min)
    };
    let runs = all
        .into_iter()
        .enumerate()
        .map(|(k, start)| (k >= unshifted, IcpRun::new(start)))
        .collect();
    let mut runs = advance(runs, SCREEN_STEPS);
    let screen = SCREEN_CUT * lowest(&runs, false);
    runs.retain(|(shifted, run)| !shifted || run.alignment.rms <= screen);
    let mut runs = advance(runs, COARSE_PROBE - SCREEN_STEPS);
    let (cut_unshifted, cut) = (
        COARSE_CUT * lowest(&runs, true),
        COARSE_CUT * lowest(&runs, false),
    );
    runs.retain(|(shifted, run)| run.alignment.rms <= if *shifted { cut } else { cut_unshifted });
    let runs = advance(runs, COARSE_STEPS - COARSE_PROBE);
    // In the starts' own order, so that ties resolve as without the cuts.
    let best_of = |kind: bool| {
        runs.iter()
            .filter(|(shifted, _)| *shifted == kind)
            .map(|(_, run)| run.alignment)
            .min_by(|x, y| x.rms.total_cmp(&y.rms))
    };
    let best = match (best_of(false), best_of(true)) {
        (Some(unshifted), Some(shifted)) if shifted.rms < SHIFTED_MARGIN * unshifted.rms => shifted,
        (Some(unshifted), _) => unshifted,
        (None, Some(shifted)) => shifted,
        (None, None) => return vec![],
    };
    let mut chosen = vec![best];
    if count > 1 {
        let mut others: Vec<RigidAlignment> = runs.iter().map(|(_, run)| run.alignment).collect();
        others.sort_by(|x, y| x.rms.total_cmp(&y.rms));
        let extent = crate::mesh::bounding_box(b).map_or(0.0, |(lo, hi)| norm(sub(hi, lo)));
        for pose in others {
            if chosen.len() == count {
                break;
            }
            if chosen
                .iter()
                .all(|c| distinct_poses(&c.motion, &pose.motion, ca, extent))
            {
                chosen.push(pose);
            }
        }
    }
    let fine = subsample(a, 3000);
    chosen
        .into_iter()
        .map(|pose| icp(&fine, b, normals, &closest, pose.motion, 100))
        .collect()
}

/// The inverse of an affine motion `x ↦ M x + t` (M invertible): `y ↦ M⁻¹ (y − t)`.
fn inverse(m: &Similarity3) -> Similarity3 {
    let a = m.matrix;
    let cof = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]
    };
    let det = (0..3).map(|j| a[0][j] * cof(0, j)).sum::<f64>();
    let matrix: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| cof(j, i) / det));
    let t = m.translation;
    let translation = std::array::from_fn(|i| -(0..3).map(|j| matrix[i][j] * t[j]).sum::<f64>());
    Similarity3 {
        matrix,
        translation,
    }
}

/// Total area of a triangle mesh.
fn area(points: &[[f64; 3]], triangles: &[[u32; 3]]) -> f64 {
    triangles
        .iter()
        .map(|t| {
            let [p, q, r] = t.map(|i| points[i as usize]);
            0.5 * norm(cross(sub(q, p), sub(r, p)))
        })
        .sum()
}

/// The rigid motion that best lays surface A (`a`, triangles `ta`) onto surface B, by
/// [`align_rigidly_ranked`] from `starts` (A → B motions), or by [`refine_rigidly`] from
/// `refine_from` when given — either way round.
///
/// Trimmed ICP fits the closest [`KEEP`] of the moved surface's points, so it can lay A
/// onto B only when that much of A can have a counterpart on B. When B's area is below
/// `KEEP` times A's (a face with forehead, ears and neck against a face alone: on ICT
/// crops against FLAME crops, 0.3), most of A cannot, and the trimmed fit settles on a
/// wrong pose; then B is laid onto A (from the inverted starts) and the motion inverted.
/// The returned `rms` is then measured from B's points.
pub fn align_surfaces(
    a: (&[[f64; 3]], &[[u32; 3]]),
    b: (&[[f64; 3]], &[[u32; 3]]),
    starts: &[Similarity3],
    refine_from: Option<Similarity3>,
) -> Option<RigidAlignment> {
    align_surfaces_ranked(a, b, starts, refine_from, 1)
        .into_iter()
        .next()
}

/// [`align_surfaces`]'s pose first, then up to `count − 1` distinct others
/// ([`align_rigidly_ranked`]; none when refining `refine_from`).
pub fn align_surfaces_ranked(
    (a, ta): (&[[f64; 3]], &[[u32; 3]]),
    (b, tb): (&[[f64; 3]], &[[u32; 3]]),
    starts: &[Similarity3],
    refine_from: Option<Similarity3>,
    count: usize,
) -> Vec<RigidAlignment> {
    let run = |x: &[[f64; 3]], y: &[[f64; 3]], ty: &[[u32; 3]], starts: &[Similarity3], from| {
        let normals = vertex_normals(y, ty);
        match from {
            Some(start) => refine_rigidly(x, y, &normals, start).into_iter().collect(),
            None => align_rigidly_ranked(x, y, &normals, starts, count),
        }
    };
    if area(b, tb) >= KEEP * area(a, ta) {
        return run(a, b, tb, starts, refine_from);
    }
    let starts: Vec<Similarity3> = starts.iter().map(inverse).collect();
    run(b, a, ta, &starts, refine_from.as_ref().map(inverse))
        .into_iter()
        .map(|back| RigidAlignment {
            motion: inverse(&back.motion),
            rms: back.rms,
            plane_rms: back.plane_rms,
        })
        .collect()
}

/// Trimmed ICP of A onto B from one `start` only (on the same subsample as the
/// refinement of [`align_rigidly_ranked`]): for a pose already known roughly, e.g. from paired
/// landmarks.
pub fn refine_rigidly(
    a: &[[f64; 3]],
    b: &[[f64; 3]],
    normals: &[[f64; 3]],
    start: Similarity3,
) -> Option<RigidAlignment> {
    if a.len() < 3 || b.len() < 3 {
        return None;
    }
    let closest = ClosestPoints::new(b);
    Some(icp(&subsample(a, 3000), b, normals, &closest, start, 100))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::bumpy_disc;

    use super::axis_angle_rotation as rotation;

    /// An asymmetric height field over a disc with one bump (a "nose").
    fn surface() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut mesh = bumpy_disc(24, 0.0);
        for p in &mut mesh.positions {
            let (x, y) = (p[0], p[1]);
            p[2] = 0.4 * x * x + 0.25 * x * y - 0.3 * y * y * y
                + 0.2 * (3.0 * x + 1.0).sin()
                + 0.6 * (-((x - 0.2).powi(2) + (y + 0.1).powi(2)) / 0.05).exp();
        }
        (mesh.positions, mesh.triangles)
    }

    /// ICP from the truth stays there; the search finds a pose whose image of every
    /// point of A lies within `tolerance` of the true image.
    fn check(a: &[[f64; 3]], b: &[[f64; 3]], bt: &[[u32; 3]], truth: &Similarity3, tolerance: f64) {
        let closest = ClosestPoints::new(b);
        let normals = vertex_normals(b, bt);
        assert!(icp(a, b, &normals, &closest, *truth, 10).rms < 1e-9);
        let found = align_rigidly_ranked(a, b, &normals, &[], 1)[0];
        assert_same_pose(a, &found.motion, truth, tolerance);
    }

    /// Every point of `a` lands within `tolerance` of where `truth` puts it.
    fn assert_same_pose(a: &[[f64; 3]], found: &Similarity3, truth: &Similarity3, tolerance: f64) {
        for p in a {
            let (x, y) = (found.apply(*p), truth.apply(*p));
            let d = ((0..3).map(|c| (x[c] - y[c]).powi(2)).sum::<f64>()).sqrt();
            assert!(d < tolerance, "{x:?} vs {y:?}");
        }
    }

    /// Points of A, points and triangles of B, and the true motion A → B.
    type Copy = (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[u32; 3]>, Similarity3);

    /// A part of the surface (A, a partial overlap, as two crops of one scan) and the
    /// whole moved by a rigid motion turned 40° (B).
    fn partial_copy() -> Copy {
        let truth = Similarity3 {
            matrix: rotation([0.3, -0.5, 0.8], 40f64.to_radians()),
            translation: [0.4, -1.0, 2.0],
        };
        let (whole, triangles) = surface();
        let b: Vec<[f64; 3]> = whole.iter().map(|&p| truth.apply(p)).collect();
        let a: Vec<[f64; 3]> = whole.iter().copied().filter(|p| p[0] > -0.3).collect();
        (a, b, triangles, truth)
    }

    #[test]
    fn a_resumed_icp_lands_where_an_uninterrupted_one_does() {
        // The coarse starts' cut relies on it: a start that survives ends on the motion,
        // bit for bit, that it would have reached without the pause.
        let (a, b, triangles, truth) = partial_copy();
        let normals = vertex_normals(&b, &triangles);
        let closest = ClosestPoints::new(&b);
        let start = Similarity3 {
            matrix: rotation([1.0, 0.2, -0.4], 35f64.to_radians()),
            translation: truth.translation.map(|t| t + 0.3),
        };
        let whole = icp(&a, &b, &normals, &closest, start, COARSE_STEPS - 1);
        let mut run = IcpRun::new(start);
        run.advance(&a, &b, &normals, &closest, 3);
        let paused = run.alignment;
        run.advance(&a, &b, &normals, &closest, COARSE_STEPS - 3);
        assert_eq!(run.alignment.motion, whole.motion);
        assert_eq!(run.alignment.rms.to_bits(), whole.rms.to_bits());
        // The pause came before convergence, so the test compares two real runs.
        assert!(paused.motion != whole.motion, "converged before the pause");
    }

    #[test]
    fn a_whole_surface_is_laid_onto_a_small_part_of_it() {
        // B is a third of the surface (less than KEEP of A's area), moved: A onto B
        // trims to 70 % of A's points, most of which have no counterpart, and misses
        // the pose; B onto A, inverted, finds it.
        let truth = Similarity3 {
            matrix: rotation([0.3, -0.5, 0.8], 40f64.to_radians()),
            translation: [0.4, -1.0, 2.0],
        };
        let (whole, triangles) = surface();
        let keep: Vec<bool> = whole.iter().map(|p| p[0] > 0.25).collect();
        let mut index = vec![u32::MAX; whole.len()];
        let mut part = vec![];
        for (v, p) in whole.iter().enumerate() {
            if keep[v] {
                index[v] = part.len() as u32;
                part.push(truth.apply(*p));
            }
        }
        let part_triangles: Vec<[u32; 3]> = triangles
            .iter()
            .filter(|t| t.iter().all(|&v| keep[v as usize]))
            .map(|t| t.map(|v| index[v as usize]))
            .collect();
        assert!(area(&part, &part_triangles) < 0.5 * area(&whole, &triangles));
        let found =
            align_surfaces((&whole, &triangles), (&part, &part_triangles), &[], None).unwrap();
        assert_same_pose(&whole, &found.motion, &truth, 1e-6);
        let one_way = align_rigidly_ranked(
            &whole,
            &part,
            &vertex_normals(&part, &part_triangles),
            &[],
            1,
        )[0];
        let off = whole
            .iter()
            .map(|&p| {
                let (x, y) = (one_way.motion.apply(p), truth.apply(p));
                ((0..3).map(|c| (x[c] - y[c]).powi(2)).sum::<f64>()).sqrt()
            })
            .fold(0.0f64, f64::max);
        assert!(off > 0.05, "A onto B found the pose too: {off}");
    }

    #[test]
    fn the_inverse_undoes_a_motion() {
        let m = Similarity3 {
            matrix: rotation([0.2, 0.9, -0.4], 1.1).map(|r| r.map(|c| 1.7 * c)),
            translation: [0.3, -2.0, 5.0],
        };
        let back = inverse(&m);
        for p in [[1.0, 2.0, 3.0], [-0.5, 0.0, 4.0]] {
            let q = back.apply(m.apply(p));
            assert!(
                (0..3).all(|c| (q[c] - p[c]).abs() < 1e-12),
                "{q:?} vs {p:?}"
            );
        }
    }

    #[test]
    fn recovers_any_rotation_of_a_whole_copy() {
        let truth = Similarity3 {
            matrix: rotation([0.3, -0.5, 0.8], 100f64.to_radians()),
            translation: [0.4, -1.0, 2.0],
        };
        let (a, triangles) = surface();
        let b: Vec<[f64; 3]> = a.iter().map(|&p| truth.apply(p)).collect();
        check(&a, &b, &triangles, &truth, 1e-5);
    }

    /// On a flat ellipse of points (4 wide, 2 high, in a tilted plane), each start gets
    /// four copies moved by ±0.4 along the width and ±0.2 along the height (a tenth of
    /// the extents), never across the plane, with the rotation kept.
    #[test]
    fn shifted_starts_move_across_the_long_axes_of_b() {
        let tilt = rotation([0.4, 1.0, -0.3], 0.7);
        let centre = [1.0, -2.0, 3.0];
        let mut b = vec![];
        for i in 0..40 {
            for r in 1..=5 {
                let (t, r) = (i as f64 * std::f64::consts::TAU / 40.0, r as f64 / 5.0);
                let local = [2.0 * r * t.cos(), r * t.sin(), 0.0];
                b.push(std::array::from_fn(|k| centre[k] + dot(tilt[k], local)));
            }
        }
        let column = |k: usize| -> [f64; 3] { std::array::from_fn(|i| tilt[i][k]) };
        let (width, height, across) = (column(0), column(1), column(2));
        let starts = [
            Similarity3 {
                matrix: rotation([0.0, 0.0, 1.0], 0.3),
                translation: [0.5, 0.0, -1.0],
            },
            Similarity3 {
                matrix: rotation([1.0, 1.0, 0.0], 2.0),
                translation: [0.0, 2.0, 0.0],
            },
        ];
        let shifted = shifted_starts(&starts, &b, centroid(&b));
        assert_eq!(shifted.len(), 8);
        for (k, start) in starts.iter().enumerate() {
            let mut along = vec![];
            for s in &shifted[4 * k..4 * k + 4] {
                assert_eq!(s.matrix, start.matrix);
                let d = sub(s.translation, start.translation);
                assert!(dot(d, across).abs() < 1e-12);
                along.push([dot(d, width), dot(d, height)]);
            }
            along.sort_by(|x, y| x[0].total_cmp(&y[0]).then(x[1].total_cmp(&y[1])));
            let expected = [[-0.4, 0.0], [0.0, -0.2], [0.0, 0.2], [0.4, 0.0]];
            for (got, want) in along.iter().zip(expected) {
                assert!(
                    (got[0] - want[0]).abs() < 1e-9 && (got[1] - want[1]).abs() < 1e-9,
                    "{got:?} vs {want:?}"
                );
            }
        }
    }

    /// Where the centroid starts already find the pose, the shifted starts leave it as
    /// it is, bit for bit: a partial copy, and a copy shrunk to 0.8 of its size. (The
    /// margin itself is what the matching test
    /// `the_wide_metric_grows_a_shrunken_start_into_place` needs: without it a shifted
    /// start lays that test's shrunk copy off-centre.)
    #[test]
    fn shifted_starts_keep_a_pose_the_centroid_starts_find() {
        let (a, b, triangles, _) = partial_copy();
        let (whole, _) = surface();
        let shrunk: Vec<[f64; 3]> = whole.iter().map(|p| p.map(|c| 0.8 * c)).collect();
        for (a, b) in [(&a, &b), (&whole, &shrunk)] {
            let normals = vertex_normals(b, &triangles);
            let [with, without] = [true, false].map(|shifted| {
                align_rigidly_with(a, b, &normals, &[], COARSE_TARGETS, shifted, 1)[0]
            });
            assert_eq!(with.motion, without.motion);
            assert_eq!(with.rms.to_bits(), without.rms.to_bits());
        }
    }

    #[test]
    fn recovers_the_pose_of_a_partial_copy() {
        let (a, b, triangles, truth) = partial_copy();
        check(&a, &b, &triangles, &truth, 1e-5);
    }

    /// The coarse starts paired with a fifth of B's vertices (fewer than the 400 coarse
    /// points of A): the refinement against all of B still lands on the true pose.
    #[test]
    fn coarse_starts_on_a_subsample_of_b_find_the_pose() {
        let (a, b, triangles, truth) = partial_copy();
        let targets = b.len() / 5;
        assert!(targets < 400 && targets < a.len());
        let normals = vertex_normals(&b, &triangles);
        let found = align_rigidly_with(&a, &b, &normals, &[], targets, true, 1)[0];
        assert!(found.rms < 1e-6, "rms {}", found.rms);
        assert_same_pose(&a, &found.motion, &truth, 1e-5);
    }

    /// From a start turned 8° and moved 0.17 (the surface is 2 across) off the truth, as
    /// a fit to a few landmarks may be, the single-start refinement lands on the true
    /// pose of a partial copy, with RMS ≈ 0.
    #[test]
    fn refining_from_a_rough_pose_finds_the_true_one() {
        let (a, b, triangles, truth) = partial_copy();
        let off = Similarity3 {
            matrix: rotation([0.3, -0.5, 0.8], 48f64.to_radians()),
            translation: [0.5, -0.9, 2.1],
        };
        let normals = vertex_normals(&b, &triangles);
        let found = refine_rigidly(&a, &b, &normals, off).unwrap();
        assert!(found.rms < 1e-6, "rms {}", found.rms);
        assert_same_pose(&a, &found.motion, &truth, 1e-5);
    }

    #[test]
    fn the_cube_group_has_24_proper_rotations() {
        let r = cube_rotations();
        assert_eq!(r.len(), 24);
        for m in &r {
            for i in 0..3 {
                for j in 0..3 {
                    let dot: f64 = (0..3).map(|k| m[i][k] * m[j][k]).sum();
                    assert_eq!(dot, if i == j { 1.0 } else { 0.0 });
                }
            }
        }
    }
}
