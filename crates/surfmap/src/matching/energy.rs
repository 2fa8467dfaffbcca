//! The discrete matching energy (thesis (2.16)) on the grid of one level, with its
//! exact gradient.
//!
//! ```text
//! E[φ] = βbend·E_bend^ε + βreg·E_reg + βF·E_F^ε + βpos·E_pos^ε
//! ```
//!
//! * `E_reg` (2.7) with density (2.8) `W(a, d) = αl·a + αa·(d + (αl/αa + 1)/d)` of
//!   `a = tr G`, `d = det G`, `G[φ] = g_A⁻¹ Dφᵀ (g_B∘φ) Dφ`, minus its value at an
//!   isometry so that `E_reg = 0` for a perfect match. One quadrature point per P1
//!   triangle (`Dφ` is constant there), `g_B∘φ` the mean of its three nodes' samples.
//!   Integrated over all of ω (no `χ`): outside ω_B, `g_B` is the harmonic extension
//!   made "softer" (thesis §2.2.5) by the factor `soft + (1 − soft)·χ_B`.
//! * `E_bend^ε` (2.9), (2.15): `∫ χ^ε (h_B∘φ − h_A)² √det g_A dξ`.
//! * `E_F^ε` (2.11), (2.15), for every labelled feature pair: the first term
//!   `∫ χ^ε η^ε(d_A) θ^ε(d_B∘φ) √det g_A` at the nodes, the second term rewritten over
//!   ω_A by the change of variables,
//!   `∫ χ^ε η^ε(d_B∘φ) θ^ε(d_A) √det g_B(φ) det Dφ`, one point per triangle (B's
//!   quantities the mean of the three nodes' samples).
//!   `η^ε(s) = max(1 − s/ε, 0)/ε`, `θ^ε(s) = min(s²/ε, 1)`.
//! * `E_pos^ε` (ours, not the thesis's): `∫ χ^ε |T(x_A) − x_B∘φ|² √det g_A` with a map
//!   `T(x) = M x + t` of ℝ³ fitted jointly ([`super::similarity`]): the surfaces' 3D
//!   shapes, compared after the best rigid motion and scale — by default allowing
//!   also a regularized affine part (`super::solve::PositionMap`) — plus, per node, the
//!   smooth part of the residual (`super::solve::POSITION_RELIEF`). The gradient holds
//!   `T` and that offset fixed; both are refitted to φ between iterations.
//!
//! `χ^ε(ξ) = χ_A^ε(ξ)·χ_B^ε(φ(ξ))` (2.14) with `χ_S^ε = max(1 − dist(·, S)/ε, 0)`,
//! computed from the signed boundary-distance images. Node integrals use the
//! trapezoidal rule (weights `h²`, halved on the border of ω, quartered at corners).
//! Quantities of B are sampled bilinearly at φ(ξ), so every gradient carries the
//! derivative of the interpolant (`∇h_B`, `∇g_B`, `∇d_B`, `∇χ_B`, `∇x_B`).
//!
//! A triangle with `det Dφ ≤ 0` makes the energy `+∞` (the line search never
//! accepts it; see [`super::deformation`]).

use rayon::prelude::*;
use serde::Serialize;

use super::deformation::{Deformation, cell_triangles, jacobian, jacobian_adjoint};
use super::similarity::Similarity3;
use crate::grid::{Grid, GridPoint};

/// `ε_k`, the cut-off width of level `k` (grid `2^k + 1`): `2^{1−k}`, two cells.
pub(crate) fn epsilon(k: usize) -> f64 {
    2.0 * 0.5f64.powi(k as i32)
}

/// Channel layout of B's sampled field.
pub(crate) const B_H: usize = 0;
pub(crate) const B_SD: usize = 1;
pub(crate) const B_G: usize = 2;
pub(crate) const B_X: usize = 5;
pub(crate) const B_CHANNELS: usize = 8;

/// Weights β of the energy terms.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Betas {
    pub bend: f64,
    pub reg: f64,
    pub features: f64,
    /// Weight of the position term (ours, beyond the thesis): A's 3D positions,
    /// moved by a jointly fitted map (`super::PositionMap`), against B's at φ
    /// (BENCHMARKS.md, "Matching"). In [`super::MatchOptions`] it is used as given only
    /// with [`super::PositionWeight::Fixed`] (default 1000); by default the solve sets it
    /// from the surfaces' disagreement in space. 0 turns the term off either way.
    pub position: f64,
    /// Cost per unit area of A left without a counterpart (ours): makes the data
    /// terms truncated least squares, so that leaving ω_B is not free.
    pub uncovered: f64,
}

/// The value of every term (weighted by its β) and their sum.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct EnergyTerms {
    pub bend: f64,
    pub reg: f64,
    pub features: f64,
    pub position: f64,
    pub uncovered: f64,
    pub total: f64,
}

impl EnergyTerms {
    fn add(mut self, o: Self) -> Self {
        self.bend += o.bend;
        self.reg += o.reg;
        self.features += o.features;
        self.position += o.position;
        self.uncovered += o.uncovered;
        self.total += o.total;
        self
    }

    fn infinite() -> Self {
        Self {
            total: f64::INFINITY,
            ..Self::default()
        }
    }
}

/// Surface A's fixed data at one level.
#[derive(Clone, Debug)]
pub(crate) struct LevelA {
    pub size: usize,
    /// `h_A` per node.
    pub h: Vec<f64>,
    /// Quadrature weight × `√det g_A` per node.
    pub weight: Vec<f64>,
    /// `χ_A^ε` per node.
    pub chi: Vec<f64>,
    /// 3D position per node (length unit ℓ).
    pub x: Vec<[f64; 3]>,
    /// Per feature: `η^ε(d_A)` per node.
    pub feature_eta: Vec<Vec<f64>>,
    /// Per node: the features whose `η^ε(d_A)` is not zero there
    /// ([`FeatureSet::nonzero`] of `feature_eta`), the only ones the first feature term reads.
    pub eta_set: Vec<FeatureSet>,
    /// Per triangle (`2·(i·(n−1) + j) + {0 lower, 1 upper}`).
    pub triangles: Vec<TriangleA>,
    /// Per feature, per triangle: `θ^ε(d_A)` at the centroid.
    pub feature_theta: Vec<Vec<f64>>,
}

#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct TriangleA {
    /// `g_A⁻¹` as `[i11, i12, i22]`.
    pub g_inv: [f64; 3],
    /// `|T| · √det g_A`.
    pub weight: f64,
    /// `|T|` (for the second feature term, which carries `√det g_B(φ) det Dφ`).
    pub area: f64,
    /// `χ_A^ε` at the centroid.
    pub chi: f64,
}

/// Surface B's data at one level, sampled at φ(ξ).
#[derive(Clone, Debug)]
pub(crate) struct LevelB {
    /// `[h, signed boundary distance, g11, g12, g22 (softened outside), x, y, z]`.
    pub field: Grid<[f64; B_CHANNELS]>,
    /// Per feature: `d_B` (set through [`LevelB::new`], which also makes the packed copy).
    pub features: Vec<Grid<f64>>,
    /// The same distances node-major (`packed[node · n_features + f]`), so that one
    /// node's features are read from a few cache lines.
    packed: Vec<f64>,
    /// Per cell (indexed by its lower-left node): the features whose `d_B` may be below
    /// `near_distance` in the cell — a corner value is (the bilinear interpolant lies
    /// between its corners' values), or the feature's distance is negative somewhere.
    near: Vec<FeatureSet>,
    /// The distance below which a feature is "near" in `near`.
    pub near_distance: f64,
}

impl LevelB {
    /// `features` must be on `field`'s grid. `near_distance` must be at least `3ε` of the
    /// level's energy: the second feature term of a triangle is zero unless the mean of
    /// its three nodes' `d_B` is below ε, which needs every node's `d_B` below 3ε when no
    /// distance is negative ([`LevelEnergy::evaluate`] reads the feature only there).
    pub fn new(
        field: Grid<[f64; B_CHANNELS]>,
        features: Vec<Grid<f64>>,
        near_distance: f64,
    ) -> Self {
        let n = field.size();
        let nodes = n * n;
        let packed = (0..nodes)
            .flat_map(|k| features.iter().map(move |f| f.as_slice()[k]))
            .collect();
        let signed: Vec<bool> = features
            .iter()
            .map(|f| f.as_slice().iter().any(|&d| d.is_nan() || d < 0.0))
            .collect();
        let near = (0..nodes)
            .map(|k| {
                let (i, j) = (k / n, k % n);
                let mut set = FeatureSet::default();
                if i + 1 < n && j + 1 < n {
                    for (f, grid) in features.iter().enumerate() {
                        let d = grid.as_slice();
                        let lowest = d[k].min(d[k + 1]).min(d[k + n]).min(d[k + n + 1]);
                        if signed[f] || lowest < near_distance {
                            set.insert(f);
                        }
                    }
                }
                set
            })
            .collect();
        Self {
            field,
            features,
            packed,
            near,
            near_distance,
        }
    }

    /// Feature `f`'s distance `d_B` and its gradient at a located point.
    #[inline]
    fn sample_feature(&self, at: &GridPoint, f: usize, out: &mut FeatureSample) {
        let nf = self.features.len();
        let (d, dx, dy) =
            at.interpolate_with_gradient(at.corners().map(|c| self.packed[c * nf + f]));
        *out = FeatureSample { d, dx, dy };
    }

    /// The features that may be near (below `near_distance`) anywhere in the located cell.
    #[inline]
    fn near_features(&self, at: &GridPoint) -> FeatureSet {
        self.near[at.corners()[0]]
    }
}

/// A set of feature indices as the bits of a word; features 63 and beyond share the
/// last bit (a set holding it holds all of them), so a set is exact for up to 63 features
/// and conservative beyond.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct FeatureSet(u64);

impl FeatureSet {
    /// Per node, the features whose per-node value in `values` (one vector per feature)
    /// is not zero.
    pub fn nonzero(values: &[Vec<f64>], nodes: usize) -> Vec<Self> {
        (0..nodes)
            .map(|k| {
                let mut s = Self::default();
                for (f, v) in values.iter().enumerate() {
                    if v[k] != 0.0 {
                        s.insert(f);
                    }
                }
                s
            })
            .collect()
    }

    #[inline]
    pub fn insert(&mut self, f: usize) {
        self.0 |= 1 << f.min(63);
    }

    #[inline]
    pub fn intersection(self, other: Self) -> Self {
        Self(self.0 & other.0)
    }

    #[inline]
    pub fn union(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    #[inline]
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Calls `body` on every feature of the set, in increasing order (`nf`: the number of
    /// features, for the shared last bit).
    #[inline]
    pub fn for_each(self, nf: usize, mut body: impl FnMut(usize)) {
        let mut bits = self.0;
        while bits != 0 {
            let b = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            if b < 63 {
                body(b);
            } else {
                (63..nf).for_each(&mut body);
            }
        }
    }
}

/// The energy of one level: A's and B's images at the level's scale, ε, β, α.
#[derive(Clone, Debug)]
pub(crate) struct LevelEnergy {
    pub a: LevelA,
    pub b: LevelB,
    pub epsilon: f64,
    pub betas: Betas,
    /// `(αl, αa)` of (2.8).
    pub alpha: (f64, f64),
    pub similarity: Similarity3,
    /// Per node, added to `T(x_A)` in the position term (empty: nothing): the smooth
    /// part of the term's residual ([`super::solve::relief_offsets`]), held fixed like
    /// `T` and refitted with it.
    pub position_offset: Vec<[f64; 3]>,
    /// Whether the refits set `position_offset` (off until the coarsest level has
    /// placed φ; [`super::options::POSITION_RELIEF`]).
    pub relief: bool,
}

/// `χ^ε_S` from a signed distance (negative inside S) and its derivative in the distance.
#[inline]
pub(crate) fn chi(sd: f64, eps: f64) -> (f64, f64) {
    if sd <= 0.0 {
        (1.0, 0.0)
    } else if sd < eps {
        (1.0 - sd / eps, -1.0 / eps)
    } else {
        (0.0, 0.0)
    }
}

/// `η^ε(s) = max(1 − s/ε, 0)/ε` and its derivative.
#[inline]
pub(crate) fn eta(s: f64, eps: f64) -> (f64, f64) {
    if s < eps {
        ((1.0 - s / eps) / eps, -1.0 / (eps * eps))
    } else {
        (0.0, 0.0)
    }
}

/// `θ^ε(s) = min(s²/ε, 1)` and its derivative.
#[inline]
pub(crate) fn theta(s: f64, eps: f64) -> (f64, f64) {
    let v = s * s / eps;
    if v < 1.0 {
        (v, 2.0 * s / eps)
    } else {
        (1.0, 0.0)
    }
}

impl LevelEnergy {
    /// How much B's mean curvature at φ disagrees with A's where both are matched,
    /// relative to how much curvature there is:
    /// `D = ∫ χ (h_B∘φ − h_A)² / ∫ χ (h_A² + (h_B∘φ)²)` (node quadrature, weights
    /// `√det g_A`): 0 when the curvatures agree everywhere, about 1 when they are
    /// unrelated (a match turned or shifted off its place), 2 when opposite. The
    /// bending term (2.9) over the curvature both surfaces have, so that it does not
    /// depend on how curved the surfaces are. `None` where nothing is matched.
    pub(crate) fn curvature_disagreement(&self, phi: &Deformation) -> Option<f64> {
        self.curvature_disagreement_at(|k| phi.at(k))
    }

    /// [`Self::curvature_disagreement`] with node `k` of A's grid placed at `place(k)`
    /// in ω_B.
    pub(crate) fn curvature_disagreement_at(
        &self,
        place: impl Fn(usize) -> [f64; 2],
    ) -> Option<f64> {
        let (mut miss, mut total) = (0.0, 0.0);
        for k in 0..self.a.h.len() {
            let w = self.a.weight[k] * self.a.chi[k];
            if w == 0.0 {
                continue;
            }
            let sv = self.b.field.sample(place(k));
            let c = w * chi(sv[B_SD], self.epsilon).0;
            let (ha, hb) = (self.a.h[k], sv[B_H]);
            miss += c * (hb - ha) * (hb - ha);
            total += c * (ha * ha + hb * hb);
        }
        (total > 0.0).then(|| miss / total)
    }

    pub fn size(&self) -> usize {
        self.a.size
    }

    /// `W(2, 1)`, the density at an isometry (subtracted so `E_reg ≥ 0`).
    fn w_isometry(&self) -> f64 {
        let (l, a) = self.alpha;
        2.0 * l + a + (l + a)
    }

    /// The energy at `φ = id + u` and its gradient `∂E/∂u` (written into `grad`).
    /// Returns `total = +∞` (and an unspecified gradient) if any triangle folds.
    ///
    /// Three passes, each parallel over grid rows and allocation-free: (1) every node
    /// samples B at φ(ξ) once (value and gradient) and adds its node terms; (2) every
    /// triangle adds its terms, with B's metric, boundary distance and feature distances
    /// taken as the mean of its three nodes' samples, scattering `∂E/∂Dφ` into the
    /// gradient and `∂E/∂(sampled value)` into per-node adjoints (even cell rows, then
    /// odd ones, so that rows written in parallel are disjoint); (3) every node turns
    /// its adjoints into gradient with its samples' derivatives.
    pub fn evaluate(
        &self,
        u: &[[f64; 2]],
        grad: &mut [[f64; 2]],
        work: &mut Workspace,
    ) -> EnergyTerms {
        let n = self.size();
        let nf = self.b.features.len();
        assert_eq!(u.len(), n * n);
        assert_eq!(grad.len(), n * n);
        debug_assert!(nf == 0 || self.b.near_distance >= 3.0 * self.epsilon);
        work.resize(n, nf);
        let Workspace {
            samples,
            feature_samples,
            near,
            adjoint,
            feature_adjoint,
            node_terms,
            cell_terms,
        } = work;
        let fstride = nf.max(1);
        // Each row's terms go to its own slot and are summed in row order afterwards:
        // a parallel `reduce` would associate the sums as work stealing happens to split
        // them, and the same input must give the same energy to the last bit.
        grad.par_chunks_mut(n)
            .zip(samples.par_chunks_mut(n))
            .zip(feature_samples.par_chunks_mut(n * fstride))
            .zip(near.par_chunks_mut(n))
            .zip(feature_adjoint.par_chunks_mut(n * fstride))
            .zip(node_terms.par_iter_mut())
            .enumerate()
            .for_each(|(i, (((((g, s), fs), near), fadj), t))| {
                *t = self.node_row(u, i, g, s, fs, near, fadj)
            });
        let nodes = node_terms
            .iter()
            .fold(EnergyTerms::default(), |a, &t| a.add(t));
        adjoint.iter_mut().for_each(|a| *a = [0.0; 4]);
        for parity in 0..2 {
            grad[parity * n..]
                .par_chunks_mut(2 * n)
                .zip(adjoint[parity * n..].par_chunks_mut(2 * n))
                .zip(feature_adjoint[parity * n * fstride..].par_chunks_mut(2 * n * fstride))
                .zip(cell_terms[parity..].par_chunks_mut(2))
                .enumerate()
                .filter(|(c, _)| 2 * c + parity < n - 1)
                .for_each(|(c, (((g, adj), fadj), t))| {
                    t[0] = self.cell_row(
                        2 * c + parity,
                        u,
                        samples,
                        feature_samples,
                        near,
                        g,
                        adj,
                        fadj,
                    )
                });
        }
        let cells = cell_terms[..n - 1]
            .iter()
            .fold(EnergyTerms::default(), |a, &t| a.add(t));
        if !cells.total.is_finite() {
            return EnergyTerms::infinite();
        }
        grad.par_iter_mut()
            .zip(samples.par_iter())
            .zip(adjoint.par_iter())
            .zip(feature_samples.par_chunks(fstride))
            .zip(feature_adjoint.par_chunks(fstride))
            .zip(near.par_iter())
            .for_each(|(((((g, s), a), fs), fa), near)| {
                for (c, ac) in a.iter().take(3).enumerate() {
                    g[0] += ac * s.g_dx[c];
                    g[1] += ac * s.g_dy[c];
                }
                g[0] += a[3] * s.sd_dx;
                g[1] += a[3] * s.sd_dy;
                near.for_each(nf, |f| {
                    g[0] += fa[f] * fs[f].dx;
                    g[1] += fa[f] * fs[f].dy;
                });
            });
        nodes.add(cells)
    }

    /// Pass 1 for row `i`: samples B at every node's φ(ξ) into `samples`, adds the node
    /// terms (bend, position, first feature term, uncovered area) and sets the row's
    /// gradient to theirs. Feature distances are sampled into `feature_samples` only
    /// where a term can read them: the features near φ(ξ) in B (recorded in `near`,
    /// their entries of `feature_adjoint` zeroed for pass 2) and those of the first term
    /// (`η^ε(d_A) ≠ 0` at the node). The other entries keep stale values nobody reads.
    #[allow(clippy::too_many_arguments)]
    fn node_row(
        &self,
        u: &[[f64; 2]],
        i: usize,
        grad: &mut [[f64; 2]],
        samples: &mut [NodeSample],
        feature_samples: &mut [FeatureSample],
        near: &mut [FeatureSet],
        feature_adjoint: &mut [f64],
    ) -> EnergyTerms {
        let n = self.size();
        let h = 1.0 / (n - 1) as f64;
        let eps = self.epsilon;
        let beta = self.betas;
        let nf = self.b.features.len();
        let mut terms = EnergyTerms::default();
        for (j, (g, sample)) in grad.iter_mut().zip(samples.iter_mut()).enumerate() {
            let k = i * n + j;
            *g = [0.0; 2];
            let phi = [j as f64 * h + u[k][0], i as f64 * h + u[k][1]];
            let at = GridPoint::locate(n, phi);
            let (sv, sdx, sdy) = self.b.field.sample_with_gradient_at(&at);
            *sample = NodeSample {
                g: [sv[B_G], sv[B_G + 1], sv[B_G + 2]],
                g_dx: [sdx[B_G], sdx[B_G + 1], sdx[B_G + 2]],
                g_dy: [sdy[B_G], sdy[B_G + 1], sdy[B_G + 2]],
                sd: sv[B_SD],
                sd_dx: sdx[B_SD],
                sd_dy: sdy[B_SD],
            };
            if nf > 0 {
                let near_b = self.b.near_features(&at);
                near[j] = near_b;
                let fs = &mut feature_samples[j * nf..(j + 1) * nf];
                near_b
                    .union(self.a.eta_set[k])
                    .for_each(nf, |f| self.b.sample_feature(&at, f, &mut fs[f]));
                near_b.for_each(nf, |f| feature_adjoint[j * nf + f] = 0.0);
            }
            let chi_a = self.a.chi[k];
            let w = self.a.weight[k];
            if chi_a == 0.0 || w == 0.0 {
                continue;
            }
            let (chi_b, dchi_b) = chi(sv[B_SD], eps);
            let chi_v = chi_a * chi_b;
            let dchi = [chi_a * dchi_b * sdx[B_SD], chi_a * dchi_b * sdy[B_SD]];
            // Uncovered area: ∫ χ_A (1 − χ_B∘φ) √det g_A.
            if beta.uncovered != 0.0 {
                let c = beta.uncovered * w;
                terms.uncovered += c * (chi_a - chi_v);
                g[0] -= c * dchi[0];
                g[1] -= c * dchi[1];
            }
            // Position (ours): `β_pos χ^ε |T(x_A) + R − x_B∘φ|²`.
            if beta.position != 0.0 {
                let mut y = self.similarity.apply(self.a.x[k]);
                if let Some(o) = self.position_offset.get(k) {
                    y = std::array::from_fn(|c| y[c] + o[c]);
                }
                let r: [f64; 3] = std::array::from_fn(|c| y[c] - sv[B_X + c]);
                let r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
                let rdx = r[0] * sdx[B_X] + r[1] * sdx[B_X + 1] + r[2] * sdx[B_X + 2];
                let rdy = r[0] * sdy[B_X] + r[1] * sdy[B_X + 1] + r[2] * sdy[B_X + 2];
                let c = beta.position * w;
                terms.position += c * chi_v * r2;
                g[0] += c * (dchi[0] * r2 - 2.0 * chi_v * rdx);
                g[1] += c * (dchi[1] * r2 - 2.0 * chi_v * rdy);
            }
            if chi_v == 0.0 && dchi == [0.0, 0.0] {
                continue;
            }
            // Bending (2.9).
            if beta.bend != 0.0 {
                let r = sv[B_H] - self.a.h[k];
                let c = beta.bend * w;
                terms.bend += c * chi_v * r * r;
                g[0] += c * (dchi[0] * r * r + chi_v * 2.0 * r * sdx[B_H]);
                g[1] += c * (dchi[1] * r * r + chi_v * 2.0 * r * sdy[B_H]);
            }
            // Features, first term of (2.11).
            if beta.features != 0.0 {
                self.a.eta_set[k].for_each(nf, |f| {
                    let e = self.a.feature_eta[f][k];
                    if e == 0.0 {
                        return;
                    }
                    let fs = feature_samples[j * nf + f];
                    let (th, dth) = theta(fs.d, eps);
                    let c = beta.features * w * e;
                    terms.features += c * chi_v * th;
                    g[0] += c * (dchi[0] * th + chi_v * dth * fs.dx);
                    g[1] += c * (dchi[1] * th + chi_v * dth * fs.dy);
                });
            }
        }
        terms.total = terms.bend + terms.position + terms.features + terms.uncovered;
        terms
    }

    /// Pass 2 for cell row `i`: the triangle terms (regularization, second feature
    /// term). `grad`, `adjoint` and `feature_adjoint` are node rows `i` and `i + 1`;
    /// `samples` and `feature_samples` are the whole grid's.
    #[allow(clippy::too_many_arguments)]
    fn cell_row(
        &self,
        i: usize,
        u: &[[f64; 2]],
        samples: &[NodeSample],
        feature_samples: &[FeatureSample],
        near: &[FeatureSet],
        grad: &mut [[f64; 2]],
        adjoint: &mut [[f64; 4]],
        feature_adjoint: &mut [f64],
    ) -> EnergyTerms {
        let n = self.size();
        let h = 1.0 / (n - 1) as f64;
        let inv_h = (n - 1) as f64;
        let eps = self.epsilon;
        let beta = self.betas;
        let nf = self.b.features.len();
        let with_features = beta.features != 0.0 && nf > 0;
        let (al, aa) = self.alpha;
        let w0 = self.w_isometry();
        let mut terms = EnergyTerms::default();
        let base = i * n;
        let (y0, y1) = (i as f64 * h, (i + 1) as f64 * h);
        for j in 0..n - 1 {
            let (x0, x1) = (j as f64 * h, (j + 1) as f64 * h);
            for (t, tri) in cell_triangles(n, i, j).into_iter().enumerate() {
                let upper = t == 1;
                let ta = &self.a.triangles[2 * (i * (n - 1) + j) + t];
                let xi = if upper {
                    [[x1, y1], [x0, y1], [x1, y0]]
                } else {
                    [[x0, y0], [x1, y0], [x0, y1]]
                };
                let phi: [[f64; 2]; 3] =
                    std::array::from_fn(|v| [xi[v][0] + u[tri[v]][0], xi[v][1] + u[tri[v]][1]]);
                let d = jacobian(phi, upper, inv_h);
                let det_d = d[0][0] * d[1][1] - d[0][1] * d[1][0];
                if det_d.is_nan() || det_d <= 0.0 {
                    terms.total = f64::INFINITY;
                    return terms;
                }
                let [s0, s1, s2] = tri.map(|k| &samples[k]);
                let bm: [f64; 3] = std::array::from_fn(|c| (s0.g[c] + s1.g[c] + s2.g[c]) / 3.0);
                let det_b = bm[0] * bm[2] - bm[1] * bm[1];
                // ∂E/∂Dφ and ∂E/∂(mean sampled value) [g11, g12, g22, sd] of this triangle.
                let mut p = [[0.0; 2]; 2];
                let mut q = [0.0; 4];
                let cof = [[d[1][1], -d[1][0]], [-d[0][1], d[0][0]]];
                if beta.reg != 0.0 {
                    let gi = ta.g_inv;
                    let det_gi = gi[0] * gi[2] - gi[1] * gi[1];
                    // K = Dφ g_A⁻¹ Dφᵀ; a = tr(g_A⁻¹ Dφᵀ B Dφ) = Σ B_ab K_ab.
                    let dg = [
                        [
                            d[0][0] * gi[0] + d[0][1] * gi[1],
                            d[0][0] * gi[1] + d[0][1] * gi[2],
                        ],
                        [
                            d[1][0] * gi[0] + d[1][1] * gi[1],
                            d[1][0] * gi[1] + d[1][1] * gi[2],
                        ],
                    ];
                    let k11 = dg[0][0] * d[0][0] + dg[0][1] * d[0][1];
                    let k12 = dg[0][0] * d[1][0] + dg[0][1] * d[1][1];
                    let k22 = dg[1][0] * d[1][0] + dg[1][1] * d[1][1];
                    let a = bm[0] * k11 + 2.0 * bm[1] * k12 + bm[2] * k22;
                    let dd = det_d * det_d * det_b * det_gi;
                    if dd.is_nan() || dd <= 0.0 {
                        terms.total = f64::INFINITY;
                        return terms;
                    }
                    let wv = al * a + aa * dd + (al + aa) / dd - w0;
                    let wa = al;
                    let wd = aa - (al + aa) / (dd * dd);
                    let c = beta.reg * ta.weight;
                    terms.reg += c * wv;
                    // ∂a/∂Dφ = 2 B Dφ g_A⁻¹; ∂d/∂Dφ = 2 det(Dφ) det B det g_A⁻¹ cof(Dφ).
                    let bdg = [
                        [
                            bm[0] * dg[0][0] + bm[1] * dg[1][0],
                            bm[0] * dg[0][1] + bm[1] * dg[1][1],
                        ],
                        [
                            bm[1] * dg[0][0] + bm[2] * dg[1][0],
                            bm[1] * dg[0][1] + bm[2] * dg[1][1],
                        ],
                    ];
                    let f = 2.0 * det_d * det_b * det_gi;
                    for r in 0..2 {
                        for cc in 0..2 {
                            p[r][cc] += c * (wa * 2.0 * bdg[r][cc] + wd * f * cof[r][cc]);
                        }
                    }
                    // ∂a/∂B = (K11, 2K12, K22); ∂d/∂B = det(Dφ)² det g_A⁻¹ (B22, −2B12, B11).
                    let e = det_d * det_d * det_gi;
                    let da = [k11, 2.0 * k12, k22];
                    let ddb = [e * bm[2], -2.0 * e * bm[1], e * bm[0]];
                    for m in 0..3 {
                        q[m] += c * (wa * da[m] + wd * ddb[m]);
                    }
                }
                // Only features near all three nodes can have a mean `d_B` below ε.
                let active = if with_features && ta.chi != 0.0 {
                    near[tri[0]]
                        .intersection(near[tri[1]])
                        .intersection(near[tri[2]])
                } else {
                    FeatureSet::default()
                };
                if !active.is_empty() {
                    // χ_B and √det g_B of the triangle, computed at its first active feature.
                    let mut shared = None;
                    let cell = 2 * (i * (n - 1) + j) + t;
                    active.for_each(nf, |f| {
                        let th = self.a.feature_theta[f][cell];
                        if th == 0.0 {
                            return;
                        }
                        let db = tri
                            .iter()
                            .map(|&k| feature_samples[k * nf + f].d)
                            .sum::<f64>()
                            / 3.0;
                        let (e, de) = eta(db, eps);
                        if e == 0.0 && de == 0.0 {
                            return;
                        }
                        let (chi_v, dchi_b, sqrt_b, dsqrt) = *shared.get_or_insert_with(|| {
                            let sd = (s0.sd + s1.sd + s2.sd) / 3.0;
                            let (chi_b, dchi_b) = chi(sd, eps);
                            let sqrt_b = det_b.max(0.0).sqrt();
                            let dsqrt = if sqrt_b > 0.0 {
                                [0.5 * bm[2] / sqrt_b, -bm[1] / sqrt_b, 0.5 * bm[0] / sqrt_b]
                            } else {
                                [0.0; 3]
                            };
                            (ta.chi * chi_b, dchi_b, sqrt_b, dsqrt)
                        });
                        let c = beta.features * ta.area * th;
                        let core = e * sqrt_b * det_d;
                        terms.features += c * chi_v * core;
                        // Through the sampled values: χ_B(sd), η(d_B), √det g_B.
                        q[3] += c * ta.chi * dchi_b * core;
                        let adj_d = c * chi_v * de * sqrt_b * det_d / 3.0;
                        for &k in &tri {
                            feature_adjoint[(k - base) * nf + f] += adj_d;
                        }
                        for m in 0..3 {
                            q[m] += c * chi_v * e * det_d * dsqrt[m];
                        }
                        // Through det Dφ.
                        let coef = c * chi_v * e * sqrt_b;
                        for r in 0..2 {
                            for cc in 0..2 {
                                p[r][cc] += coef * cof[r][cc];
                            }
                        }
                    });
                }
                let adj = jacobian_adjoint(p, upper, inv_h);
                let q = q.map(|x| x / 3.0);
                for v in 0..3 {
                    let local = tri[v] - base;
                    grad[local][0] += adj[v][0];
                    grad[local][1] += adj[v][1];
                    for m in 0..4 {
                        adjoint[local][m] += q[m];
                    }
                }
            }
        }
        terms.total = terms.reg + terms.features;
        terms
    }
}

/// B's metric and boundary distance sampled at one node's φ(ξ), with their gradients.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct NodeSample {
    g: [f64; 3],
    g_dx: [f64; 3],
    g_dy: [f64; 3],
    sd: f64,
    sd_dx: f64,
    sd_dy: f64,
}

/// One feature distance of B sampled at a node's φ(ξ), with its gradient.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct FeatureSample {
    d: f64,
    dx: f64,
    dy: f64,
}

/// Scratch buffers of [`LevelEnergy::evaluate`], reused across evaluations.
#[derive(Clone, Debug, Default)]
pub(crate) struct Workspace {
    samples: Vec<NodeSample>,
    feature_samples: Vec<FeatureSample>,
    /// Per node: the features near φ(ξ) in B ([`LevelB::near_features`]).
    near: Vec<FeatureSet>,
    adjoint: Vec<[f64; 4]>,
    feature_adjoint: Vec<f64>,
    /// Per grid row: the terms of its nodes, and of its cells (row `i` of cells lies
    /// between node rows `i` and `i + 1`).
    node_terms: Vec<EnergyTerms>,
    cell_terms: Vec<EnergyTerms>,
}

impl Workspace {
    /// Sizes every buffer for an `n × n` grid with `features` feature channels.
    fn resize(&mut self, n: usize, features: usize) {
        let nodes = n * n;
        let f = features.max(1);
        self.samples.resize(nodes, NodeSample::default());
        self.feature_samples
            .resize(nodes * f, FeatureSample::default());
        self.near.resize(nodes, FeatureSet::default());
        self.adjoint.resize(nodes, [0.0; 4]);
        self.feature_adjoint.resize(nodes * f, 0.0);
        self.node_terms.resize(n, EnergyTerms::default());
        self.cell_terms.resize(n, EnergyTerms::default());
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::matching::deformation::{cell_triangles, node};
    use crate::testing::Rng;

    /// A synthetic level: smooth A and B data with boundary bands (χ between 0 and 1)
    /// crossing the grid, one feature per side, SPD metrics.
    pub(crate) fn synthetic(n: usize, betas: Betas) -> LevelEnergy {
        synthetic_with(n, betas, 0.3, [[0.3, 0.4], [0.35, 0.3]])
    }

    /// [`synthetic`] with another ε (the width of the boundary and feature bands) and
    /// other feature points (of A, of B).
    fn synthetic_with(n: usize, betas: Betas, eps: f64, points: [[f64; 2]; 2]) -> LevelEnergy {
        let xy = |q: usize| node(n, q);
        let h = 1.0 / (n - 1) as f64;
        let metric_a = |p: [f64; 2]| [1.2 + 0.3 * p[0], 0.2 * p[1] - 0.1, 0.9 + 0.4 * p[1] * p[0]];
        let sd_a = |p: [f64; 2]| p[0] - 0.6; // χ_A band over x ∈ (0.6, 0.9)
        let [fa, fb] = points;
        let d_a = |p: [f64; 2]| ((p[0] - fa[0]).powi(2) + (p[1] - fa[1]).powi(2)).sqrt();
        let node_w = |q: usize| {
            let (i, j) = (q / n, q % n);
            let e = |t: usize| if t == 0 || t == n - 1 { 0.5 } else { 1.0 };
            h * h * e(i) * e(j)
        };
        let mut triangles = vec![];
        let mut feature_theta = vec![vec![]];
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                for tri in cell_triangles(n, i, j) {
                    let c = tri.iter().fold([0.0; 2], |a, &q| {
                        let p = xy(q);
                        [a[0] + p[0] / 3.0, a[1] + p[1] / 3.0]
                    });
                    let g = metric_a(c);
                    let det = g[0] * g[2] - g[1] * g[1];
                    triangles.push(TriangleA {
                        g_inv: [g[2] / det, -g[1] / det, g[0] / det],
                        weight: 0.5 * h * h * det.sqrt(),
                        area: 0.5 * h * h,
                        chi: chi(sd_a(c), eps).0,
                    });
                    feature_theta[0].push(theta(d_a(c), eps).0);
                }
            }
        }
        let mut a = LevelA {
            size: n,
            h: (0..n * n)
                .map(|q| (3.0 * xy(q)[0]).sin() + xy(q)[1])
                .collect(),
            weight: (0..n * n)
                .map(|q| {
                    let g = metric_a(xy(q));
                    node_w(q) * (g[0] * g[2] - g[1] * g[1]).sqrt()
                })
                .collect(),
            chi: (0..n * n).map(|q| chi(sd_a(xy(q)), eps).0).collect(),
            x: (0..n * n)
                .map(|q| {
                    let p = xy(q);
                    [p[0], p[1], 0.3 * (p[0] * p[0] - p[1])]
                })
                .collect(),
            feature_eta: vec![(0..n * n).map(|q| eta(d_a(xy(q)), eps).0).collect()],
            eta_set: vec![],
            triangles,
            feature_theta,
        };
        a.eta_set = FeatureSet::nonzero(&a.feature_eta, n * n);
        let b_data = (0..n * n)
            .map(|q| {
                let p = xy(q);
                [
                    (2.0 * p[1]).cos() + 0.5 * p[0],
                    0.45 - p[1], // χ_B band over y ∈ (0.15, 0.45)
                    1.0 + 0.5 * p[1],
                    0.1 * p[0],
                    1.1 - 0.3 * p[0] * p[1],
                    p[0] + 0.1,
                    0.9 * p[1],
                    0.2 * (p[0] + p[1]).powi(2),
                ]
            })
            .collect();
        let b = LevelB::new(
            Grid::from_vec(n, b_data).unwrap(),
            vec![
                Grid::from_vec(
                    n,
                    (0..n * n)
                        .map(|q| {
                            let p = xy(q);
                            ((p[0] - fb[0]).powi(2) + (p[1] - fb[1]).powi(2)).sqrt()
                        })
                        .collect(),
                )
                .unwrap(),
            ],
            3.0 * eps,
        );
        LevelEnergy {
            a,
            b,
            epsilon: eps,
            betas,
            alpha: (0.4, 0.6),
            similarity: Similarity3 {
                matrix: [[0.9, -0.1, 0.0], [0.1, 0.9, 0.05], [0.0, -0.05, 0.95]],
                translation: [0.02, -0.01, 0.03],
            },
            position_offset: vec![],
            relief: false,
        }
    }

    fn random_displacement(n: usize, seed: u64, amount: f64) -> Vec<[f64; 2]> {
        let mut rng = Rng(seed);
        (0..n * n)
            .map(|_| [amount * rng.range(-1.0, 1.0), amount * rng.range(-1.0, 1.0)])
            .collect()
    }

    /// Central finite differences of the total energy against the analytic gradient.
    fn check_gradient(betas: Betas, seed: u64) {
        let n = 9;
        let e = synthetic(n, betas);
        let u = random_displacement(n, seed, 0.02);
        let mut grad = vec![[0.0; 2]; n * n];
        let base = e.evaluate(&u, &mut grad, &mut Workspace::default());
        assert!(base.total.is_finite() && base.total > 0.0, "{base:?}");
        let mut scratch = vec![[0.0; 2]; n * n];
        let step = 1e-7;
        let scale = grad
            .iter()
            .map(|g| g[0].abs().max(g[1].abs()))
            .fold(0.0, f64::max);
        assert!(scale > 0.0);
        for q in 0..n * n {
            for c in 0..2 {
                let mut up = u.clone();
                up[q][c] += step;
                let mut down = u.clone();
                down[q][c] -= step;
                let fd = (e
                    .evaluate(&up, &mut scratch, &mut Workspace::default())
                    .total
                    - e.evaluate(&down, &mut scratch, &mut Workspace::default())
                        .total)
                    / (2.0 * step);
                assert!(
                    (fd - grad[q][c]).abs() <= 1e-5 * scale + 1e-6 * fd.abs(),
                    "{betas:?} node {q} comp {c}: fd {fd} vs analytic {}",
                    grad[q][c]
                );
            }
        }
    }

    const ONLY: fn(usize) -> Betas = |t| {
        let mut b = [0.0; 5];
        b[t] = 1.0;
        Betas {
            bend: b[0],
            reg: b[1],
            features: b[2],
            position: b[3],
            uncovered: b[4],
        }
    };

    #[test]
    fn bending_gradient_matches_finite_differences() {
        check_gradient(ONLY(0), 1);
    }

    #[test]
    fn regularization_gradient_matches_finite_differences() {
        check_gradient(ONLY(1), 2);
    }

    #[test]
    fn feature_gradient_matches_finite_differences() {
        check_gradient(ONLY(2), 3);
    }

    #[test]
    fn position_gradient_matches_finite_differences() {
        check_gradient(ONLY(3), 4);
    }

    #[test]
    fn uncovered_area_gradient_matches_finite_differences() {
        check_gradient(ONLY(4), 6);
    }

    #[test]
    fn all_terms_together_match_finite_differences() {
        check_gradient(
            Betas {
                bend: 1.0,
                reg: 0.01,
                features: 5.0,
                position: 30.0,
                uncovered: 2.0,
            },
            5,
        );
    }

    #[test]
    fn the_bands_of_chi_are_active_in_the_synthetic_level() {
        // The FD tests above only mean something if χ takes values strictly between 0
        // and 1 at some nodes, and η, θ are active.
        let e = synthetic(9, ONLY(0));
        assert!(e.a.chi.iter().any(|&c| c > 0.0 && c < 1.0));
        assert!(e.a.chi.contains(&0.0));
        let mut grad = vec![[0.0; 2]; 81];
        let u = random_displacement(9, 1, 0.02);
        let partial = (0..81).filter(|&q| {
            let p = node(9, q);
            let s = e.b.field.sample([p[0] + u[q][0], p[1] + u[q][1]])[B_SD];
            s > 0.0 && s < e.epsilon
        });
        assert!(partial.count() > 5);
        assert!(e.a.feature_eta[0].iter().any(|&v| v > 0.0));
        assert!(e.evaluate(&u, &mut grad, &mut Workspace::default()).total > 0.0);
    }

    /// The synthetic level with B = A (same curvature, metric, positions; T = id, χ_A = 1):
    /// φ = id is an exact match of zero energy.
    pub(crate) fn self_match(n: usize) -> LevelEnergy {
        let mut e = synthetic(
            n,
            Betas {
                bend: 1.0,
                reg: 1.0,
                features: 0.0,
                position: 1.0,
                uncovered: 1.0,
            },
        );
        e.similarity = Similarity3::identity();
        let data = (0..n * n)
            .map(|q| {
                let p = node(n, q);
                let g = [1.2 + 0.3 * p[0], 0.2 * p[1] - 0.1, 0.9 + 0.4 * p[1] * p[0]];
                let x = e.a.x[q];
                [e.a.h[q], -1.0, g[0], g[1], g[2], x[0], x[1], x[2]]
            })
            .collect();
        e.b.field = Grid::from_vec(n, data).unwrap();
        e.a.chi = vec![1.0; n * n];
        // A's triangle metric as the mean of B's node metrics, so G = I exactly.
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                for (t, tri) in cell_triangles(n, i, j).iter().enumerate() {
                    let data = e.b.field.as_slice();
                    let g: [f64; 3] = std::array::from_fn(|c| {
                        tri.iter().map(|&q| data[q][B_G + c]).sum::<f64>() / 3.0
                    });
                    let det = g[0] * g[2] - g[1] * g[1];
                    e.a.triangles[2 * (i * (n - 1) + j) + t].g_inv =
                        [g[2] / det, -g[1] / det, g[0] / det];
                }
            }
        }
        e
    }

    #[test]
    fn identity_match_of_a_surface_with_itself_has_zero_energy_and_gradient() {
        let n = 9;
        let e = self_match(n);
        let mut grad = vec![[0.0; 2]; n * n];
        let t = e.evaluate(&vec![[0.0; 2]; n * n], &mut grad, &mut Workspace::default());
        assert!(t.total.abs() < 1e-12, "{t:?}");
        // The regularization is stationary at an isometry (∂W/∂Dφ = 0, and
        // αl·g_A⁻¹ − αl·adj(g_B)/det g_B = 0 through g_B); the data terms vanish with
        // their residuals.
        let gmax = grad
            .iter()
            .map(|g| g[0].abs().max(g[1].abs()))
            .fold(0.0, f64::max);
        assert!(gmax < 1e-10, "{gmax}");
    }

    #[test]
    fn packed_features_sample_like_their_grids() {
        let n = 9;
        let mut e = synthetic(n, ONLY(2));
        let mut rng = Rng(8);
        let second: Vec<f64> = (0..n * n).map(|_| rng.range(0.0, 1.0)).collect();
        let features = vec![e.b.features[0].clone(), Grid::from_vec(n, second).unwrap()];
        e.b = LevelB::new(e.b.field.clone(), features, 3.0 * e.epsilon);
        let mut out = [FeatureSample::default(); 2];
        for _ in 0..200 {
            // Inside ω and beyond its border (clamped).
            let p = [rng.range(-0.2, 1.2), rng.range(-0.2, 1.2)];
            for (f, o) in out.iter_mut().enumerate() {
                e.b.sample_feature(&GridPoint::locate(n, p), f, o);
                let (d, dx, dy) = e.b.features[f].sample_with_gradient(p);
                assert_eq!((o.d, o.dx, o.dy), (d, dx, dy), "feature {f} at {p:?}");
            }
        }
    }

    /// Features are read only where B's feature is near; the result is the dense
    /// evaluation's bit for bit, also when the workspace holds another φ's stale samples.
    #[test]
    fn features_read_only_where_near_give_the_dense_result() {
        let n = 33;
        let all = Betas {
            bend: 1.0,
            reg: 1.0,
            features: 1.0,
            position: 1.0,
            uncovered: 1.0,
        };
        // Both feature points inside ω_A and ω_B (χ = 1), so both feature terms are active.
        let pruned = synthetic_with(n, all, 0.05, [[0.3, 0.6], [0.32, 0.62]]);
        let mut dense = pruned.clone();
        dense.b = LevelB::new(
            pruned.b.field.clone(),
            pruned.b.features.clone(),
            f64::INFINITY,
        );
        let empty = pruned.b.near.iter().filter(|s| s.is_empty()).count();
        assert!(empty > n * n / 2, "only {empty} of {} cells pruned", n * n);
        let first = random_displacement(n, 11, 0.004);
        let second = random_displacement(n, 12, 0.004);
        let mut work = Workspace::default();
        let mut grad = vec![[0.0; 2]; n * n];
        pruned.evaluate(&first, &mut grad, &mut work);
        let got = pruned.evaluate(&second, &mut grad, &mut work);
        let mut want_grad = vec![[0.0; 2]; n * n];
        let want = dense.evaluate(&second, &mut want_grad, &mut Workspace::default());
        assert!(want.features > 0.0 && want.total.is_finite(), "{want:?}");
        assert_eq!(got, want);
        assert_eq!(grad, want_grad);
    }

    #[test]
    fn feature_sets_share_the_last_bit_beyond_63_features() {
        let mut set = FeatureSet::default();
        set.insert(2);
        set.insert(70);
        let mut seen = vec![];
        set.for_each(72, |f| seen.push(f));
        let mut want = vec![2];
        want.extend(63..72);
        assert_eq!(seen, want);
        let values: Vec<Vec<f64>> = (0..3).map(|f| vec![0.0, f as f64]).collect();
        let sets = FeatureSet::nonzero(&values, 2);
        assert!(sets[0].is_empty());
        let mut seen = vec![];
        sets[1].for_each(3, |f| seen.push(f));
        assert_eq!(seen, vec![1, 2]);
    }

    #[test]
    fn a_fold_makes_the_energy_infinite() {
        let n = 9;
        let e = synthetic(n, ONLY(1));
        let mut u = vec![[0.0; 2]; n * n];
        // Push node (4, 4) past its right neighbour: its cells invert.
        u[4 * n + 4] = [0.2, 0.0];
        let mut grad = vec![[0.0; 2]; n * n];
        assert!(
            e.evaluate(&u, &mut grad, &mut Workspace::default())
                .total
                .is_infinite()
        );
    }
}
