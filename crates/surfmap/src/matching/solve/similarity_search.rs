//! A search over the plane similarities applied to φ at the coarsest level: the global
//! rotation and translation (and, when asked, the scale) that the matching energy prefers.
//!
//! Why: NCG on the full displacement field is a local optimizer, and a global rotation
//! or scale of φ is its slowest mode (a low-frequency field that the gradient, dominated
//! by local residuals, barely points along). Measured on the FLAME pairs (BENCHMARKS.md,
//! "Faces never tuned on"), a start 6° or 7 % in scale off the similarity the energy
//! prefers is not corrected by the multiscale solve. Here the energy is minimized over
//! the parameters of a similarity `S` of the plane applied to the current φ,
//! `φ ← S∘φ`, before the solve: rotation and translation by default, the scale too
//! when asked (below).
//!
//! **Parametrization.** With `c` the centroid of φ over A's domain (node weights
//! `√det g_A·χ_A`) and `r` the RMS distance of those nodes' images from `c`,
//!
//! ```text
//! S_q(y) = c + e^{q₀/r} R(q₁/r) (y − c) + (q₂, q₃)
//! ```
//!
//! so that all four coordinates are lengths in ω (a unit of `q₀` or `q₁` moves a node at
//! the typical distance `r` by about one unit, as a unit of `q₂` does). By default the
//! scale `q₀` is held at 0 — a rotation and translation only
//! ([`SimilaritySearch::scale`]): with it, the ratio below favours shrinking A where A
//! is the larger face, and on the FLAME identity pairs the rotation alone ends lower
//! after the coarsest level's solve and nearer the truth. `S_0 = id`, and a
//! similarity of positive scale never folds a triangle, so every trial stays in the
//! admissible (fold-free) set; the energy's own `+∞` on a fold is still checked.
//!
//! **Gradient.** With `∇_k E = ∂E/∂φ_k` the exact gradient of `LevelEnergy::evaluate`
//! (the same as `∂E/∂u_k`), the chain rule through `φ_k(q) = S_q(φ_k)` at `q = 0` gives
//!
//! ```text
//! ∂E/∂q = Σ_k J_kᵀ ∇_k E,   J_k = [ (φ_k − c)/r | J(φ_k − c)/r | e₀ | e₁ ],   J(v) = (−v₁, v₀)
//! ```
//!
//! (the projection of the gradient onto the similarities' tangent space). Every
//! accepted step re-bases the parametrization at the new φ (the frame `c`, `r` is kept),
//! so the gradient is always taken at `q = 0`.
//!
//! **Objective: energy per matched area.** The data terms are cut off by `χ^ε`, so a
//! similarity that moves A's domain off ω_B lowers E by matching less (measured on
//! the FLAME partial pairs: E alone is halved by scaling φ up by 15–20 %, and the match
//! gets worse). The search therefore minimizes the ratio `E(q)/M(q)` with the matched
//! area `M = ∫ χ_A χ_B^ε∘φ √det g_A` (the criterion of the alignment search,
//! [`crate::matching::align::score`]), by Dinkelbach's iteration: each round minimizes
//! `E + λ·(|A| − M)` — the energy with the uncovered-area term weighted by `λ`
//! (`Betas::uncovered`, whose gradient the energy already has) — at the round's
//! `λ = E/M`; a fixed point of the rounds is a stationary point of the ratio.
//!
//! **Minimization.** BFGS on the four coordinates (Nocedal & Wright, Algorithm 6.1,
//! initial inverse Hessian scaled by (6.20)) with Armijo backtracking, the first trial
//! of a round moving A's nodes by about half a grid cell. The position term's similarity
//! of ℝ³ (`T` in [`crate::matching::energy`]) is refitted at the start of every round (the refit
//! never raises the energy), so that the search does not stay tied to the motion in
//! space found by the alignment. Optionally the search also starts from rotated and
//! scaled copies of the start ([`SimilaritySearch::candidate_angle`]) and keeps the
//! lowest ratio.
//!
//! **Where, and the choice of start** (the driver, [`super::solve`]). The search sees φ
//! only as a similarity of the alignment, before any local deformation, so its minimum
//! is that of the *rigid* misfit; where the surfaces differ locally (expression, a
//! partial overlap) that is not the similarity the solved φ wants. Measured on the
//! ICT and FLAME pairs (BENCHMARKS.md, "Similarity search before the solve"): kept
//! unconditionally, a search on the solve's coarsest level (65²) gains up to 20 points
//! within 0.05 on the FLAME pairs with the real face but loses 14–37 on the ICT partial
//! pairs, and coarser levels propose no better (up to 76 points lost at level 3, 31 at
//! level 4, where whole ICT faces get proposals of up to 18° and ×1.2). So the search
//! only proposes: the driver solves the coarsest level from both starts — the
//! alignment's and the searched one — and goes on from the searched one only when it
//! *dominates*: its solve ends with a lower energy and at least the same matched area
//! `M` — and, when the alignment's solve matches A at a plausible size (its matched part
//! covers 1/3–3 times its own area on B, `matched_area_ratio`), only if the searched
//! one does too: the ICT face crop matched to a whole head (same units) was squeezed by
//! the search's start to 0.11 of its area on B, against 0.65 from the alignment's, and
//! ended lower in energy and matching more (BENCHMARKS.md, "A squeezed start"). With
//! that rule the proposals of level 4 (17², `σ = 1/16`,
//! [`SimilaritySearch::level`]) gained most on the FLAME pairs (level 6: 92.3 %, 5:
//! 91.9 %, 4: 93.1 % on identity, measured with 4 rounds). The energy after local
//! deformation decides, not the rigid misfit; and the area condition, because on the
//! ICT whole-face pairs a
//! start scaled up by 9–13 % ended lower in energy (and per matched area) by matching
//! 7–10 % less, and was 0.7–3.2 points worse. The search run after the coarsest level's
//! NCG instead moves nothing (< 0.3°): by then the local deformation has absorbed the
//! global misfit.

use serde::Serialize;

use super::super::deformation::{Deformation, cell_triangles, jacobian, node};
use super::super::energy::{B_CHANNELS, B_G, B_SD, LevelEnergy, Workspace, chi};
use super::super::options::SimilaritySearch;
use super::super::similarity::{Similarity2, Similarity3, fit_similarity_2d};

/// What the similarity search did.
#[derive(Clone, Debug, Serialize)]
pub struct SimilaritySearchLog {
    /// The similarity applied to φ (new φ = similarity ∘ old φ).
    pub similarity: Similarity2,
    /// Energy per matched area `E/M` before and after (module docs).
    pub energy_start: f64,
    pub energy_end: f64,
    /// Starts tried (`SimilaritySearch::candidate_angle`).
    pub candidates: usize,
    pub evaluations: usize,
    pub seconds: f64,
    /// Whether the solve went on from the similarity found: its coarsest level ended
    /// with a lower energy and at least the same matched area as from the alignment's
    /// start, and not at an implausible size (module docs).
    pub kept: bool,
    /// The area A's matched part covers on B over its own area after the coarsest level
    /// solved from the alignment's start and from the search's (`matched_area_ratio`;
    /// `None` when nothing matched).
    pub area_ratio_alignment: Option<f64>,
    pub area_ratio_search: Option<f64>,
    /// From the search's start the coarsest level matched A at an implausible size
    /// (outside 1/3–3 times its area, `crate::matching::solve::plausible_area_ratio`) and from
    /// the alignment's it did not: the searched start is then not kept, whatever the
    /// energies.
    pub implausible_size: bool,
}

/// The frame of the parametrization `S_q` (module docs): centre `c`, radius `r`.
#[derive(Clone, Copy, Debug)]
struct Frame {
    centre: [f64; 2],
    radius: f64,
}

impl Frame {
    /// Centroid and RMS radius of φ over A's domain (weights `√det g_A·χ_A`); `None`
    /// when A has no weight or φ maps it to one point.
    fn of(energy: &LevelEnergy, phi: &Deformation) -> Option<Self> {
        let (mut w, mut m) = (0.0, [0.0; 2]);
        for k in 0..phi.displacement.len() {
            let wk = energy.a.weight[k] * energy.a.chi[k];
            let y = phi.at(k);
            w += wk;
            m = [m[0] + wk * y[0], m[1] + wk * y[1]];
        }
        if w.is_nan() || w <= 0.0 {
            return None;
        }
        let centre = [m[0] / w, m[1] / w];
        let mut r2 = 0.0;
        for k in 0..phi.displacement.len() {
            let y = phi.at(k);
            r2 += energy.a.weight[k]
                * energy.a.chi[k]
                * ((y[0] - centre[0]).powi(2) + (y[1] - centre[1]).powi(2));
        }
        let radius = (r2 / w).sqrt();
        (radius > 0.0 && radius.is_finite()).then_some(Self { centre, radius })
    }

    /// `to = S_q ∘ from` at the nodes.
    fn apply(&self, q: [f64; 4], from: &Deformation, to: &mut Deformation) {
        let n = from.size;
        let z = {
            let s = (q[0] / self.radius).exp();
            let a = q[1] / self.radius;
            [s * a.cos(), s * a.sin()]
        };
        let c = self.centre;
        for (k, (out, u)) in to
            .displacement
            .iter_mut()
            .zip(&from.displacement)
            .enumerate()
        {
            let x = node(n, k);
            let v = [x[0] + u[0] - c[0], x[1] + u[1] - c[1]];
            let y = [
                c[0] + z[0] * v[0] - z[1] * v[1] + q[2],
                c[1] + z[0] * v[1] + z[1] * v[0] + q[3],
            ];
            *out = [y[0] - x[0], y[1] - x[1]];
        }
    }

    /// `∂E/∂q` at `q = 0` from `grad = ∂E/∂φ` (module docs).
    fn project(&self, phi: &Deformation, grad: &[[f64; 2]]) -> [f64; 4] {
        let (c, r) = (self.centre, self.radius);
        let mut g = [0.0; 4];
        for (k, d) in grad.iter().enumerate() {
            let y = phi.at(k);
            let v = [(y[0] - c[0]) / r, (y[1] - c[1]) / r];
            g[0] += d[0] * v[0] + d[1] * v[1];
            g[1] += -d[0] * v[1] + d[1] * v[0];
            g[2] += d[0];
            g[3] += d[1];
        }
        g
    }
}

/// `E/M` at `phi` with the energy's own weights (module docs), and `M`.
fn ratio(energy: &LevelEnergy, phi: &Deformation, buf: &mut Buffers) -> (f64, f64) {
    let e = energy
        .evaluate(&phi.displacement, &mut buf.grad, &mut buf.work)
        .total;
    buf.evaluations += 1;
    let m = matched_area(energy, phi);
    if m > 0.0 && e.is_finite() {
        (e / m, m)
    } else {
        (f64::INFINITY, m)
    }
}

/// The area that A's matched part covers on B over its own area, at `phi`:
///
/// ```text
/// Σ_T w_T |T| √det g_B(φ(T)) det Dφ_T  /  Σ_T w_T |T| √det g_A(T),   w_T = χ_A(T) χ_B^ε(φ(T))
/// ```
///
/// over the grid's triangles `T` (B's metric and signed distance the means of the
/// corners' samples, as in the energy's triangle terms). Near 1 when surfaces of like
/// size are matched where they correspond; the report's area ratio
/// ([`crate::matching::MatchReport::area_ratio`]) measures the same in space on the
/// output. `None` when nothing is matched or φ folds.
pub(crate) fn matched_area_ratio(energy: &LevelEnergy, phi: &Deformation) -> Option<f64> {
    let n = phi.size;
    let inv_h = (n - 1) as f64;
    let points: Vec<[f64; 2]> = (0..n * n).map(|k| phi.at(k)).collect();
    let samples: Vec<[f64; B_CHANNELS]> =
        points.iter().map(|&p| energy.b.field.sample(p)).collect();
    let (mut on_a, mut on_b) = (0.0, 0.0);
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            for (t, tri) in cell_triangles(n, i, j).into_iter().enumerate() {
                let ta = &energy.a.triangles[2 * (i * (n - 1) + j) + t];
                if ta.chi == 0.0 {
                    continue;
                }
                let mean = |c: usize| tri.iter().map(|&k| samples[k][c]).sum::<f64>() / 3.0;
                let w = ta.chi * chi(mean(B_SD), energy.epsilon).0;
                if w == 0.0 {
                    continue;
                }
                let d = jacobian(tri.map(|k| points[k]), t == 1, inv_h);
                let det_d = d[0][0] * d[1][1] - d[0][1] * d[1][0];
                let det_b = mean(B_G) * mean(B_G + 2) - mean(B_G + 1).powi(2);
                if det_d.is_nan() || det_d <= 0.0 {
                    return None;
                }
                on_a += w * ta.weight;
                on_b += w * ta.area * det_b.max(0.0).sqrt() * det_d;
            }
        }
    }
    (on_a > 0.0).then(|| on_b / on_a)
}

/// `M = Σ_k w_k χ_A,k χ_B^ε(φ_k)` (node weights `√det g_A` × quadrature).
pub(crate) fn matched_area(energy: &LevelEnergy, phi: &Deformation) -> f64 {
    (0..phi.displacement.len())
        .map(|k| {
            let wa = energy.a.weight[k] * energy.a.chi[k];
            if wa == 0.0 {
                return 0.0;
            }
            let sd = energy.b.field.sample(phi.at(k))[B_SD];
            wa * chi(sd, energy.epsilon).0
        })
        .sum()
}

fn dot4(a: [f64; 4], b: [f64; 4]) -> f64 {
    a.iter().zip(&b).map(|(x, y)| x * y).sum()
}

/// Buffers of one search, allocated once.
struct Buffers {
    grad: Vec<[f64; 2]>,
    trial: Deformation,
    trial_grad: Vec<[f64; 2]>,
    work: Workspace,
    evaluations: usize,
}

/// BFGS over `q` from `phi` (in place) with the energy's current position similarity;
/// returns the final energy.
fn bfgs(
    energy: &LevelEnergy,
    phi: &mut Deformation,
    frame: &Frame,
    settings: &SimilaritySearch,
    buf: &mut Buffers,
) -> f64 {
    const ARMIJO_C: f64 = 1e-4;
    let h = 1.0 / (phi.size - 1) as f64;
    let mut e = energy
        .evaluate(&phi.displacement, &mut buf.grad, &mut buf.work)
        .total;
    buf.evaluations += 1;
    if !e.is_finite() {
        return e;
    }
    // Without the scale (`SimilaritySearch::scale` off) its coordinate's gradient is
    // zero, so every step, and every BFGS update (s₀ = y₀ = 0 keep the inverse
    // Hessian's row 0 at γ·e₀), leaves q₀ at 0.
    let project = |phi: &Deformation, grad: &[[f64; 2]]| {
        let mut g = frame.project(phi, grad);
        if !settings.scale {
            g[0] = 0.0;
        }
        g
    };
    let mut g = project(phi, &buf.grad);
    // Inverse Hessian approximation; `None` until the first update (then scaled, (6.20)).
    let mut inv: Option<[[f64; 4]; 4]> = None;
    for _ in 0..settings.iterations {
        let gnorm = dot4(g, g).sqrt();
        if gnorm.is_nan() || gnorm <= 0.0 {
            break;
        }
        let mut d = match &inv {
            Some(m) => std::array::from_fn(|i| -dot4(m[i], g)),
            None => g.map(|x| -0.5 * h * x / gnorm),
        };
        let mut slope = dot4(g, d);
        if slope.is_nan() || slope >= 0.0 {
            d = g.map(|x| -0.5 * h * x / gnorm);
            slope = dot4(g, d);
            inv = None;
        }
        let mut t = 1.0;
        let mut accepted = None;
        for _ in 0..30 {
            let step = d.map(|x| t * x);
            frame.apply(step, phi, &mut buf.trial);
            let et = energy
                .evaluate(&buf.trial.displacement, &mut buf.trial_grad, &mut buf.work)
                .total;
            buf.evaluations += 1;
            if et.is_finite() && et <= e + ARMIJO_C * t * slope {
                accepted = Some((step, et));
                break;
            }
            t *= 0.5;
        }
        let Some((s, et)) = accepted else { break };
        std::mem::swap(phi, &mut buf.trial);
        std::mem::swap(&mut buf.grad, &mut buf.trial_grad);
        let g_new = project(phi, &buf.grad);
        let y: [f64; 4] = std::array::from_fn(|i| g_new[i] - g[i]);
        let sy = dot4(s, y);
        if sy > 0.0 {
            // H ← (I − ρ s yᵀ) H (I − ρ y sᵀ) + ρ s sᵀ, ρ = 1/yᵀs.
            let m = inv.unwrap_or_else(|| {
                let gamma = sy / dot4(y, y);
                std::array::from_fn(|i| std::array::from_fn(|j| if i == j { gamma } else { 0.0 }))
            });
            let rho = 1.0 / sy;
            let hy: [f64; 4] = std::array::from_fn(|i| dot4(m[i], y));
            let yhy = dot4(y, hy);
            inv = Some(std::array::from_fn(|i| {
                std::array::from_fn(|j| {
                    m[i][j] - rho * (hy[i] * s[j] + s[i] * hy[j])
                        + (rho * rho * yhy + rho) * s[i] * s[j]
                })
            }));
        }
        let decrease = (e - et) / e.abs().max(f64::MIN_POSITIVE);
        e = et;
        g = g_new;
        if decrease < settings.tolerance {
            break;
        }
    }
    e
}

/// Minimizes the energy per matched area of `energy` over plane similarities applied
/// to `phi` (module docs), from `phi` and from the candidates around it
/// ([`SimilaritySearch::candidate_angle`]), and leaves the lowest in `phi` with its
/// refitted position similarity in `energy`. `refit` refits the position term's
/// similarity (it must not raise the energy). Returns `None` (and leaves both unchanged)
/// when A has no weight at this level or no similarity lowers the ratio.
pub(crate) fn search_similarity(
    energy: &mut LevelEnergy,
    phi: &mut Deformation,
    settings: &SimilaritySearch,
    refit: &mut dyn FnMut(&mut LevelEnergy, &Deformation),
) -> Option<SimilaritySearchLog> {
    let clock = std::time::Instant::now();
    let frame = Frame::of(energy, phi)?;
    let n = phi.size;
    let mut buf = Buffers {
        grad: vec![[0.0; 2]; n * n],
        trial: phi.clone(),
        trial_grad: vec![[0.0; 2]; n * n],
        work: Workspace::default(),
        evaluations: 0,
    };
    let start_similarity = energy.similarity;
    let uncovered = energy.betas.uncovered;
    let (ratio_start, _) = ratio(energy, phi, &mut buf);
    let candidates = settings.candidates();
    let mut best: Option<(f64, Deformation, Similarity3)> = None;
    let mut current = phi.clone();
    for &(angle, log_scale) in &candidates {
        frame.apply(
            [log_scale * frame.radius, angle * frame.radius, 0.0, 0.0],
            phi,
            &mut current,
        );
        energy.similarity = start_similarity;
        let mut r = f64::INFINITY;
        for _ in 0..settings.rounds.max(1) {
            refit(energy, &current);
            let (lambda, _) = ratio(energy, &current, &mut buf);
            if !lambda.is_finite() {
                break;
            }
            energy.betas.uncovered = uncovered + lambda;
            bfgs(energy, &mut current, &frame, settings, &mut buf);
            energy.betas.uncovered = uncovered;
            let before = r;
            r = ratio(energy, &current, &mut buf).0;
            if !r.is_finite() || before - r <= 1e-4 * r.abs() {
                break;
            }
        }
        if r.is_finite() && best.as_ref().is_none_or(|b| r < b.0) {
            best = Some((r, current.clone(), energy.similarity));
        }
    }
    let Some((energy_end, found, similarity3)) = best else {
        energy.similarity = start_similarity;
        return None;
    };
    let energy_start = ratio_start;
    if energy_end >= energy_start {
        energy.similarity = start_similarity;
        return None;
    }
    // The applied similarity, recovered from the nodes (exact for a similarity).
    let before: Vec<[f64; 2]> = (0..n * n).map(|k| phi.at(k)).collect();
    let after: Vec<[f64; 2]> = (0..n * n).map(|k| found.at(k)).collect();
    let similarity = fit_similarity_2d(&before, &after)?;
    *phi = found;
    energy.similarity = similarity3;
    Some(SimilaritySearchLog {
        similarity,
        energy_start,
        energy_end,
        candidates: candidates.len(),
        evaluations: buf.evaluations,
        seconds: clock.elapsed().as_secs_f64(),
        kept: false,
        area_ratio_alignment: None,
        area_ratio_search: None,
        implausible_size: false,
    })
}
/// Largest factor by which a plausible match changes the matched part's area (either
/// way) before [`match_warnings`](crate::matching::report::match_warnings) doubts it. Faces of different people, expressions,
/// crops and sources stay within 0.82–1.16 (BENCHMARKS, "Doubtful matches"); a factor of
/// 3 is a different kind of result (a head scan squeezed into a template: 0.27), not a
/// worse one of the same kind. It does not catch a moderately wrong match (0.56 on the
/// worst ICT → FLAME pair, 45 mm off), and it leaves room for faces of different sizes
/// (a child's onto an adult's).
pub const AREA_RATIO_DOUBT: f64 = 3.0;

/// Whether a match that changes the matched part's area by the factor `r` is of the
/// kind surfaces of like size give: `1/`[`AREA_RATIO_DOUBT`]` ≤ r ≤ `[`AREA_RATIO_DOUBT`].
/// The report warns outside ([`match_warnings`](crate::matching::report::match_warnings)); the similarity search's start is not
/// kept when it leads outside and the alignment's does not ([`crate::matching::solve::similarity_search`]).
pub fn plausible_area_ratio(r: f64) -> bool {
    (1.0 / AREA_RATIO_DOUBT..=AREA_RATIO_DOUBT).contains(&r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matching::energy::Betas;
    use crate::matching::energy::tests::{self_match, synthetic};
    use crate::matching::options::SearchWhen;

    fn all_terms() -> Betas {
        Betas {
            bend: 1.0,
            reg: 0.5,
            features: 0.7,
            position: 2.0,
            uncovered: 0.3,
        }
    }

    /// With one constant metric on both sides, φ scaling the plane by `s` about a point
    /// (its image inside ω_B) gives A's matched part `s²` times its area on B, whatever
    /// A's cut-off `χ_A`; the identity gives 1; a fold gives no ratio.
    #[test]
    fn matched_area_ratio_of_a_scaling_is_its_square() {
        let n = 17;
        let mut e = self_match(n);
        let g: [f64; 3] = [1.3, 0.1, 0.8];
        let root_det = (g[0] * g[2] - g[1] * g[1]).sqrt();
        let mut data = e.b.field.as_slice().to_vec();
        for v in &mut data {
            v[B_G..B_G + 3].copy_from_slice(&g);
        }
        e.b.field = crate::grid::Grid::from_vec(n, data).unwrap();
        for t in &mut e.a.triangles {
            t.weight = t.area * root_det;
        }
        assert!(
            e.a.triangles.iter().any(|t| t.chi < 1.0),
            "χ_A is not constant"
        );
        let scaled = |s: f64| {
            Deformation::from_map(n, |p| [0.4 + s * (p[0] - 0.4), 0.55 + s * (p[1] - 0.55)])
        };
        for s in [1.0, 0.8, 0.35] {
            let r = matched_area_ratio(&e, &scaled(s)).unwrap();
            assert!((r - s * s).abs() < 1e-12, "s {s}: ratio {r}");
        }
        // A fold: one node pushed across its neighbours.
        let mut folded = scaled(1.0);
        folded.displacement[n * (n / 2) + n / 2][0] += 2.0 / (n - 1) as f64;
        assert_eq!(matched_area_ratio(&e, &folded), None);
    }

    /// `∂E/∂q` from the projection against central differences of `E(S_q∘φ)`.
    #[test]
    fn projected_gradient_matches_finite_differences() {
        let n = 9;
        let e = synthetic(n, all_terms());
        // A smooth, fold-free φ away from the identity.
        let phi = Deformation::from_map(n, |p| {
            [
                0.05 + 0.9 * p[0] + 0.05 * (2.0 * p[1]).sin(),
                0.02 + 0.95 * p[1] + 0.04 * p[0] * p[0],
            ]
        });
        let frame = Frame::of(&e, &phi).unwrap();
        let mut grad = vec![[0.0; 2]; n * n];
        let mut work = Workspace::default();
        let base = e.evaluate(&phi.displacement, &mut grad, &mut work).total;
        assert!(base.is_finite() && base > 0.0);
        let g = frame.project(&phi, &grad);
        let mut trial = phi.clone();
        let mut at = |q: [f64; 4]| {
            frame.apply(q, &phi, &mut trial);
            e.evaluate(&trial.displacement, &mut grad, &mut work).total
        };
        let step = 1e-6;
        let scale = g.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(scale > 0.0);
        for i in 0..4 {
            let mut up = [0.0; 4];
            up[i] = step;
            let mut down = [0.0; 4];
            down[i] = -step;
            let fd = (at(up) - at(down)) / (2.0 * step);
            assert!(
                (fd - g[i]).abs() <= 1e-5 * scale,
                "coordinate {i}: fd {fd} vs projected {}",
                g[i]
            );
        }
    }

    #[test]
    fn the_parametrization_is_a_similarity_with_the_stated_factors() {
        let n = 9;
        let e = synthetic(n, all_terms());
        let phi = Deformation::from_map(n, |p| [0.1 + 0.8 * p[0], 0.05 + 0.8 * p[1]]);
        let frame = Frame::of(&e, &phi).unwrap();
        let (angle, log_scale, t) = (0.3, -0.2, [0.01, -0.02]);
        let mut out = phi.clone();
        frame.apply(
            [log_scale * frame.radius, angle * frame.radius, t[0], t[1]],
            &phi,
            &mut out,
        );
        let before: Vec<[f64; 2]> = (0..n * n).map(|k| phi.at(k)).collect();
        let after: Vec<[f64; 2]> = (0..n * n).map(|k| out.at(k)).collect();
        let s = fit_similarity_2d(&before, &after).unwrap();
        assert!((s.angle() - angle).abs() < 1e-12);
        assert!((s.scale() - log_scale.exp()).abs() < 1e-12);
        // The centre moves by the translation only.
        let c = s.apply(frame.centre);
        assert!((c[0] - frame.centre[0] - t[0]).abs() < 1e-12);
        assert!((c[1] - frame.centre[1] - t[1]).abs() < 1e-12);
        for k in 0..n * n {
            let y = s.apply(before[k]);
            assert!((y[0] - after[k][0]).hypot(y[1] - after[k][1]) < 1e-12);
        }
    }

    /// The search on B = A from a start turned by 0.06 rad, scaled by 1.05 and moved,
    /// with or without the scale: its log, the φ it leaves, and the start.
    fn search_a_turned_and_scaled_self_match(
        scale: bool,
    ) -> (SimilaritySearchLog, Deformation, Similarity2) {
        let n = 17;
        let mut e = self_match(n);
        let start = Similarity2::about([0.5, 0.5], 0.06, 1.05, [0.51, 0.485]);
        let mut phi = Deformation::from_map(n, |p| start.apply(p));
        let settings = SimilaritySearch {
            when: SearchWhen::Always,
            iterations: 100,
            tolerance: 1e-14,
            scale,
            ..Default::default()
        };
        let log = search_similarity(&mut e, &mut phi, &settings, &mut |_, _| {}).unwrap();
        (log, phi, start)
    }

    /// B = A: the identity is the exact match; from a rotated, scaled and moved start
    /// the search must return to it (the position similarity kept at the identity).
    #[test]
    fn search_recovers_the_identity_of_a_self_match() {
        let (log, phi, _) = search_a_turned_and_scaled_self_match(true);
        assert!(log.energy_end < 1e-6 * log.energy_start, "{log:?}");
        let worst = phi
            .displacement
            .iter()
            .fold(0.0f64, |m, u| m.max(u[0].hypot(u[1])));
        assert!(worst < 1e-4, "largest displacement left {worst}");
        // The reported similarity undoes the start.
        let back = log.similarity;
        assert!((back.angle() + 0.06).abs() < 1e-4, "{back:?}");
        assert!((back.scale() * 1.05 - 1.0).abs() < 1e-4, "{back:?}");
    }

    /// Without the scale (the default) the same self-match, started turned *and*
    /// scaled, is turned back and moved, and its scale left exactly as it was: the
    /// reported similarity has scale 1 to rounding, and it undoes most of the start's
    /// rotation.
    #[test]
    fn without_the_scale_the_search_turns_back_and_keeps_the_scale() {
        assert!(
            !SimilaritySearch::default().scale,
            "the default searches the scale"
        );
        let (log, _, start) = search_a_turned_and_scaled_self_match(false);
        let back = log.similarity;
        assert!((back.scale() - 1.0).abs() < 1e-12, "{back:?}");
        // The rotation alone cannot undo a scaled start exactly; it comes back to
        // within a third of the start's 0.06 rad (measured: 0.010).
        assert!((back.angle() + 0.06).abs() < 0.02, "{back:?}");
        assert!(log.energy_end < log.energy_start, "{log:?}");
        // The start's scale is still there: every node's image is 5 % too far from
        // the centre, not where the identity puts it.
        let moved = back.after(&start);
        assert!((moved.scale() - 1.05).abs() < 1e-9, "{moved:?}");
    }

    /// Candidates: a start far off in rotation (beyond the basin of the local search
    /// from the start) is recovered when one candidate lies near the answer, and never
    /// does worse than the start alone.
    #[test]
    fn candidates_never_do_worse_than_the_start_alone() {
        let n = 17;
        let start = Similarity2::about([0.5, 0.5], 0.35, 1.0, [0.5, 0.5]);
        let run = |angle: f64| {
            let mut e = self_match(n);
            let mut phi = Deformation::from_map(n, |p| start.apply(p));
            let settings = SimilaritySearch {
                when: SearchWhen::Always,
                candidate_angle: angle,
                ..Default::default()
            };
            search_similarity(&mut e, &mut phi, &settings, &mut |_, _| {}).unwrap()
        };
        let alone = run(0.0);
        let with = run(0.35);
        assert_eq!((alone.candidates, with.candidates), (1, 3));
        assert!(with.energy_end <= alone.energy_end, "{alone:?} {with:?}");
        assert!((with.similarity.angle() + 0.35).abs() < 1e-3, "{with:?}");
    }
}
