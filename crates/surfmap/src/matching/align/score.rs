//! The initial alignment of ω_A onto ω_B when nothing is given (NOTES §2b
//! "Alignment"): both flattenings preserve orientation, so the domains differ by a
//! similarity of the plane `S(ξ) = z·ξ + t`. Each candidate `S` is scored by how well
//! it explains the surfaces' 3D shapes: the nodes of ω_A that `S` maps into ω_B pair
//! A's position `x_A(ξ)` with B's `x_B(S(ξ))`; after the best similarity of ℝ³
//! ([`fit_similarity_3d`]) the score is the trimmed mean squared residual (the best
//! 80 % of the overlap, so that a partial overlap's unmatched rim does not count),
//! divided by the overlap fraction. Candidates: a grid of rotations, translations and
//! scales around the centroid alignment, then a pattern search from the best few.
//! Cost: a few thousand candidates on a 33² grid, tens of milliseconds.

use rayon::prelude::*;
use serde::Serialize;

use super::super::energy::{B_SD, B_X, LevelA, LevelB};
use super::super::similarity::{Similarity2, Similarity3, fit_similarity_3d};

/// One scored candidate.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Candidate {
    pub similarity: Similarity2,
    pub score: f64,
    pub overlap: f64,
    /// The rigid motion of ℝ³ fitted to the candidate's pairs (ℓ units).
    pub motion: Similarity3,
}

/// Fraction of the best pairs kept by the trimmed score.
const KEEP: f64 = 0.8;
/// Candidates covering less of ω_A than this are rejected.
const MIN_OVERLAP: f64 = 0.35;

/// Scores similarity candidates at one level.
pub(crate) struct AlignmentScore<'a> {
    a: &'a LevelA,
    b: &'a LevelB,
    /// Nodes inside ω_A, with their weights.
    nodes: Vec<(usize, f64)>,
    total: f64,
    allow_scale: bool,
}

impl<'a> AlignmentScore<'a> {
    pub fn new(a: &'a LevelA, b: &'a LevelB, inside_a: &[bool], allow_scale: bool) -> Self {
        let nodes: Vec<(usize, f64)> = (0..a.size * a.size)
            .filter(|&q| inside_a[q] && a.weight[q] > 0.0)
            .map(|q| (q, a.weight[q]))
            .collect();
        let total = nodes.iter().map(|n| n.1).sum();
        Self {
            a,
            b,
            nodes,
            total,
            allow_scale,
        }
    }

    /// The score of `s` (lower is better; `∞` when the overlap is too small).
    pub fn score(&self, s: &Similarity2) -> Candidate {
        let n = self.a.size;
        let h = 1.0 / (n - 1) as f64;
        let mut p = Vec::with_capacity(self.nodes.len());
        let mut q = Vec::with_capacity(self.nodes.len());
        let mut w = Vec::with_capacity(self.nodes.len());
        for &(k, wk) in &self.nodes {
            let xi = [(k % n) as f64 * h, (k / n) as f64 * h];
            let v = self.b.field.sample(s.apply(xi));
            if v[B_SD] > 0.0 {
                continue;
            }
            p.push(self.a.x[k]);
            q.push([v[B_X], v[B_X + 1], v[B_X + 2]]);
            w.push(wk);
        }
        let overlap = w.iter().sum::<f64>() / self.total.max(f64::MIN_POSITIVE);
        let reject = Candidate {
            similarity: *s,
            score: f64::INFINITY,
            overlap,
            motion: Similarity3::identity(),
        };
        if overlap < MIN_OVERLAP {
            return reject;
        }
        let Some(t) = fit_similarity_3d(&p, &q, &w, self.allow_scale) else {
            return reject;
        };
        let mut r: Vec<(f64, f64)> = p
            .iter()
            .zip(&q)
            .zip(&w)
            .map(|((a, b), &wk)| {
                let y = t.apply(*a);
                ((0..3).map(|c| (y[c] - b[c]).powi(2)).sum::<f64>(), wk)
            })
            .collect();
        // Trimmed mean: the pairs with the smallest residuals, up to KEEP of the weight
        // (weights are nearly uniform, so a count quantile is enough).
        let keep = ((KEEP * r.len() as f64) as usize).clamp(1, r.len());
        r.select_nth_unstable_by(keep - 1, |x, y| x.0.total_cmp(&y.0));
        let (mut acc, mut sum) = (0.0, 0.0);
        for &(ri, wi) in &r[..keep] {
            acc += wi;
            sum += wi * ri;
        }
        Candidate {
            similarity: *s,
            score: sum / acc.max(f64::MIN_POSITIVE) / overlap,
            overlap,
            motion: t,
        }
    }

    /// Grid search over rotations × translations × scales around `centre_a → centre_b`
    /// with base scale `scale`, then a pattern search from the best `refine`
    /// candidates. Returns the best candidate and every grid candidate's rotation
    /// score (the best over translations and scales, per rotation).
    pub fn search(
        &self,
        centre_a: [f64; 2],
        centre_b: [f64; 2],
        scale: f64,
        rotations: usize,
        refine: usize,
    ) -> (Vec<Candidate>, Vec<(f64, f64)>) {
        let offsets = [-0.3, -0.225, -0.15, -0.075, 0.0, 0.075, 0.15, 0.225, 0.3];
        let scales = [0.9, 1.0, 1.1];
        // The best grid candidate of every rotation; the best `refine` rotations are
        // refined (distinct rotations, so that one basin does not take every slot).
        let mut best_of_rotation: Vec<(Candidate, f64, f64, [f64; 2])> = (0..rotations)
            .into_par_iter()
            .map(|r| {
                let angle = std::f64::consts::TAU * r as f64 / rotations as f64;
                let mut best: Option<(Candidate, f64, f64, [f64; 2])> = None;
                for dx in offsets {
                    for dy in offsets {
                        for f in scales {
                            let target = [centre_b[0] + dx, centre_b[1] + dy];
                            let c =
                                self.score(&Similarity2::about(centre_a, angle, scale * f, target));
                            if best.as_ref().is_none_or(|b| c.score < b.0.score) {
                                best = Some((c, angle, f, [dx, dy]));
                            }
                        }
                    }
                }
                best.expect("non-empty grid")
            })
            .collect();
        let per_rotation = best_of_rotation
            .iter()
            .map(|b| (b.1.to_degrees(), b.0.score))
            .collect();
        best_of_rotation.sort_by(|x, y| x.0.score.total_cmp(&y.0.score));
        let all = best_of_rotation;
        let mut refined = vec![];
        for &(c, angle, f, d) in all.iter().take(refine) {
            if !c.score.is_finite() {
                continue;
            }
            // Pattern search on (angle, log scale, dx, dy).
            let mut x = [angle, f.ln(), d[0], d[1]];
            let mut best = c;
            let mut step = [
                std::f64::consts::TAU / rotations as f64 / 2.0,
                0.05,
                0.0375,
                0.0375,
            ];
            for _ in 0..40 {
                let mut improved = false;
                for axis in 0..4 {
                    for sign in [-1.0, 1.0] {
                        let mut y = x;
                        y[axis] += sign * step[axis];
                        let s = Similarity2::about(
                            centre_a,
                            y[0],
                            scale * y[1].exp(),
                            [centre_b[0] + y[2], centre_b[1] + y[3]],
                        );
                        let cand = self.score(&s);
                        if cand.score < best.score {
                            best = cand;
                            x = y;
                            improved = true;
                        }
                    }
                }
                if !improved {
                    step.iter_mut().for_each(|s| *s *= 0.5);
                    if step[2] < 1e-3 {
                        break;
                    }
                }
            }
            refined.push(best);
        }
        // The rotations that were not refined follow, as grid candidates.
        refined.extend(all.iter().skip(refine).map(|x| x.0));
        refined.sort_by(|x, y| x.score.total_cmp(&y.score));
        (refined, per_rotation)
    }
}
