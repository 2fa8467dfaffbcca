//! Stage 3, **solve**: the prepared surfaces and the [`Start`] → [`Solved`], φ found
//! coarse to fine (thesis §3.2.4, Fig. 3.7).
//!
//! Levels `k = k₀ … K` live on `(2^k + 1)²` grids; level `k` uses images filtered with
//! `σ_k = 2^−k` (the finest unfiltered) and the cut-off width `ε_k = 2^{1−k}` (thesis:
//! `ε = 2σ_k`; on the finest level, where `σ = 0`, two grid cells). Each level is
//! minimized by [`ncg`] and prolongated (exactly, as a P1 map) to the next; the
//! finest level stops at the looser [`NcgSettings::finest_tolerance`], and every level
//! within the same cost ([`NcgSettings::max_evaluations`]: 40 evaluations at 257², 160
//! at 129², …). Descent directions are taken in a Sobolev metric 4 cells of each level
//! wide ([`precondition`]); the coarsest level takes the first half of its iterations
//! in one a quarter of ω wide, which moves φ as a whole ([`COARSEST_SOBOLEV_WIDTH`](super::options::COARSEST_SOBOLEV_WIDTH)).
//! From the alignment's start a search over similarities of φ on a coarse level may
//! propose another start, which the coarsest level's solve then accepts or rejects
//! ([`similarity_search`]); with features, the coarsest level is solved from their
//! start and from their alignment refined in space ([`super::align::FeatureStarts`]).

pub(crate) mod ncg;
pub(crate) mod precondition;
pub(crate) mod similarity_search;

use rayon::prelude::*;

use super::align::{AlignmentReport, Start};
use super::deformation::{Deformation, node};
use super::energy::{B_SD, B_X, Betas, LevelEnergy, Workspace, chi, epsilon};
use super::options::{
    MatchOptions, NcgSettings, PositionMap, RELIEF_MIDDLE_BUDGET, RELIEF_PHASE_FRACTION,
};
use super::prepare::surface::MatchSurface;
use super::similarity::{Similarity2, Similarity3, fit_affine_3d_near, fit_similarity_3d};
use crate::grid::Grid;
use crate::grid::pyramid::gaussian_filter_restricted;
use ncg::{LevelLog, minimize};
use precondition::SobolevPreconditioner;
pub use similarity_search::{SimilaritySearchLog, plausible_area_ratio};
use similarity_search::{matched_area, matched_area_ratio, search_similarity};

/// What the solve found.
#[derive(Clone, Debug)]
pub(crate) struct Solved {
    /// φ on the finest grid.
    pub deformation: Deformation,
    pub levels: Vec<LevelLog>,
    /// The alignment's report, with what the coarsest level's starts did.
    pub alignment: AlignmentReport,
    /// The position term's map at the end (A's ℓ units → B's ℓ units): a similarity, or
    /// an affine map near one ([`PositionMap`]).
    pub similarity: Similarity3,
    /// The position term's weight `β_pos` used ([`super::PositionWeight`]).
    pub position_weight: f64,
    /// The surfaces' RMS distance along B's normals after their rigid alignment (ℓ
    /// units), from which the position weight was set (`None` with a fixed weight).
    pub shape_residual: Option<f64>,
    /// The start's rigid alignment in space ([`Start::pose`]).
    pub pose: Option<Similarity3>,
    pub min_det: f64,
}

impl Solved {
    /// φ(ξ) for a point ξ of ω_A.
    pub fn map_domain(&self, xi: [f64; 2]) -> [f64; 2] {
        self.deformation.apply(xi)
    }
}

/// How much B's curvature at φ disagrees with A's
/// ([`LevelEnergy::curvature_disagreement`]): on φ's own level (the finest, or the
/// coarsest after [`solve_coarsest`]); on the coarsest level's images, smoothed with
/// σ = 2⁻⁶ of ω (φ read at its nodes), where the surfaces' fine detail — a scan's noise,
/// a smooth template against a detailed face — no longer counts; and, as a baseline,
/// on φ's level with φ turned by a quarter, a half and three quarters of a turn about
/// where it puts ω_A's centre (the mean of the three: what unrelated places give).
pub(crate) fn curvature_disagreements(
    a: &MatchSurface,
    b: &MatchSurface,
    solved: &Solved,
    options: &MatchOptions,
) -> Disagreements {
    let energy = |k: usize| {
        let eps = epsilon(k);
        LevelEnergy {
            a: a.level_a(k, eps, &[]),
            b: b.level_b(k, eps, options.tuning.soft, &[]),
            epsilon: eps,
            betas: options.betas(),
            alpha: options.tuning.alpha,
            similarity: solved.similarity,
            position_offset: vec![],
            relief: false,
        }
    };
    let phi = &solved.deformation;
    let k = (phi.size - 1).trailing_zeros() as usize;
    let own = energy(k);
    let (ca, _) = a.domain_centroid_and_area();
    let centre = phi.apply(ca);
    let unrelated: Vec<f64> = [0.25, 0.5, 0.75]
        .iter()
        .filter_map(|turn| {
            let turned = Similarity2::about(centre, turn * std::f64::consts::TAU, 1.0, centre);
            own.curvature_disagreement_at(|n| turned.apply(phi.at(n)))
        })
        .collect();
    let k0 = options.tuning.coarsest_level.min(k);
    let coarse = energy(k0);
    let n0 = coarse.size();
    Disagreements {
        finest: own.curvature_disagreement(phi),
        coarse: coarse.curvature_disagreement_at(|n| phi.apply(node(n0, n))),
        unrelated: (!unrelated.is_empty())
            .then(|| unrelated.iter().sum::<f64>() / unrelated.len() as f64),
    }
}

/// [`curvature_disagreements`].
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Disagreements {
    pub finest: Option<f64>,
    pub coarse: Option<f64>,
    pub unrelated: Option<f64>,
}

/// The stage (module docs).
pub(crate) fn solve(
    a: &MatchSurface,
    b: &MatchSurface,
    start: Start,
    options: &MatchOptions,
) -> Solved {
    solve_levels(a, b, start, options, a.num_levels() - 1)
}

/// The coarsest level alone, from `start` (with its similarity search or second start,
/// as [`solve`]'s first level): what a match that went wrong compares its alternative
/// starts by.
pub(crate) fn solve_coarsest(
    a: &MatchSurface,
    b: &MatchSurface,
    start: Start,
    options: &MatchOptions,
) -> Solved {
    solve_levels(a, b, start, options, options.tuning.coarsest_level)
}

/// The levels from the coarsest up to `last`.
fn solve_levels(
    a: &MatchSurface,
    b: &MatchSurface,
    start: Start,
    options: &MatchOptions,
    last: usize,
) -> Solved {
    let Start {
        plane: s,
        motion: mut similarity,
        in_space,
        search,
        betas,
        shape_residual,
        pose,
        report: mut alignment,
    } = start;
    let top = last;
    let k0 = options.tuning.coarsest_level;
    let features: Vec<usize> = (0..a.feature_curves.len()).collect();
    let solver = Solver {
        a,
        b,
        features: &features,
        options,
        betas,
        spent: Default::default(),
    };
    let mut phi = Deformation::from_map(a.level_size(k0), |p| s.apply(p));
    let mut levels = vec![];
    for k in k0..=top {
        if k > k0 {
            phi = phi.prolongate();
        }
        if k == k0 && search {
            // The similarity search, when asked for with features (`SearchWhen::Always`),
            // takes the coarsest level instead of the start from space.
            let (log, searched) = solver.level_with_search(k0, s, &mut phi, &mut similarity);
            alignment.search = searched;
            alignment.features_in_space = None;
            levels.push(log);
        } else if k == k0
            && let Some((s_space, motion)) = &in_space
        {
            let starts =
                solver.level_from_two_starts(k0, &mut phi, &mut similarity, s_space, motion);
            if let Some(f) = alignment.features_in_space.as_mut() {
                (f.energy_features, f.energy_space, f.kept) = starts.1;
            }
            levels.push(starts.0);
        } else {
            levels.push(solver.level(k, &mut phi, &mut similarity));
        }
    }
    let min_det = phi.min_jacobian_determinant();
    Solved {
        deformation: phi,
        levels,
        alignment,
        similarity,
        position_weight: betas.position,
        shape_residual,
        pose,
        min_det,
    }
}

struct Solver<'s> {
    a: &'s MatchSurface,
    b: &'s MatchSurface,
    features: &'s [usize],
    options: &'s MatchOptions,
    /// The energy's weights (`options.betas` with the position weight set,
    /// [`PositionWeight`](super::PositionWeight)).
    betas: Betas,
    /// Energy evaluations spent so far, in finest-level evaluations (one on a grid `2^j`
    /// times coarser counts `4^-j`), for [`NcgSettings::total_evaluations`]: the bits of
    /// an `f64`, atomic so that two levels can be minimized at once
    /// ([`Solver::level_with_search`]).
    spent: std::sync::atomic::AtomicU64,
}

impl Solver<'_> {
    fn energy(&self, k: usize, similarity: Similarity3) -> LevelEnergy {
        let eps = epsilon(k);
        LevelEnergy {
            a: self.a.level_a(k, eps, self.features),
            b: self
                .b
                .level_b(k, eps, self.options.tuning.soft, self.features),
            epsilon: eps,
            betas: self.betas,
            alpha: self.options.tuning.alpha,
            similarity,
            position_offset: vec![],
            relief: false,
        }
    }

    /// Refits the position term's map of `e` to `phi` (when the term is on).
    fn refit(&self, e: &mut LevelEnergy, phi: &Deformation) {
        if self.betas.position != 0.0
            && let Some(s) = fit_position_map(e, phi, self.options)
        {
            e.similarity = s;
            if self.options.advanced.relief > 0.0 && e.relief {
                e.position_offset = relief_offsets(e, phi, self.options.advanced.relief);
            }
        }
    }

    /// The coarsest level `k0` with the similarity search ([`crate::matching::solve::similarity_search`]):
    /// the search runs on level [`Advanced::search_level`](super::Advanced::search_level) from the alignment's
    /// similarity `s`; when it finds a lower energy per matched area, level `k0` is
    /// solved from both starts, and the searched one is kept (in `phi` and
    /// `similarity`) only when its solve ends with a lower energy *and* at least the
    /// same matched area, *and* — when the alignment's solve matches A at a plausible
    /// size ([`plausible_area_ratio`] of [`matched_area_ratio`]) — does too. `phi` is
    /// `s` on level `k0`'s grid.
    fn level_with_search(
        &self,
        k0: usize,
        s: Similarity2,
        phi: &mut Deformation,
        similarity: &mut Similarity3,
    ) -> (LevelLog, Option<SimilaritySearchLog>) {
        let settings = &self.options.search();
        let ks = settings.level.min(k0);
        let mut searched_similarity = *similarity;
        let mut energy = self.energy(ks, searched_similarity);
        let mut start = Deformation::from_map(self.a.level_size(ks), |p| s.apply(p));
        let found = search_similarity(&mut energy, &mut start, settings, &mut |e, phi| {
            self.refit(e, phi)
        });
        let Some(mut found) = found else {
            return (self.level(k0, phi, similarity), None);
        };
        searched_similarity = energy.similarity;
        let moved = found.similarity.after(&s);
        let mut other = Deformation::from_map(phi.size, |p| moved.apply(p));
        let (from_alignment, from_search) = self.level_from_both(
            k0,
            (phi, similarity),
            (&mut other, &mut searched_similarity),
        );
        // Kept only when it dominates — a lower energy without matching less — and
        // matches A at a plausible size whenever the alignment's start does (the ICT
        // face crop squeezed to a tenth of its area on a whole head ended lower:
        // BENCHMARKS.md).
        // Both measures read level k0's data only (not the position term's similarity),
        // so one level serves both starts.
        let level = self.energy(k0, *similarity);
        found.area_ratio_alignment = matched_area_ratio(&level, phi);
        found.area_ratio_search = matched_area_ratio(&level, &other);
        let plausible = |r: Option<f64>| r.is_some_and(plausible_area_ratio);
        found.implausible_size =
            plausible(found.area_ratio_alignment) && !plausible(found.area_ratio_search);
        found.kept = self.second_ends_lower(
            k0,
            (phi, *similarity, from_alignment.end.total),
            (&other, searched_similarity, from_search.end.total),
        ) && matched_area(&level, &other) >= matched_area(&level, phi)
            && !found.implausible_size;
        if found.kept {
            *phi = other;
            *similarity = searched_similarity;
            (from_search, Some(found))
        } else {
            (from_alignment, Some(found))
        }
    }

    /// The coarsest level `k0` solved from `phi` (the features' start) and from the
    /// start in space `s_space` (with `motion`, the position term's start) side by side
    /// ([`FeatureStarts`](super::FeatureStarts)): the second is kept (in `phi` and `similarity`) only when it
    /// ends with a lower energy and matches at least the same area. Returns the kept
    /// start's log and (energy from the features, energy from space, kept).
    fn level_from_two_starts(
        &self,
        k0: usize,
        phi: &mut Deformation,
        similarity: &mut Similarity3,
        s_space: &Similarity2,
        motion: &Similarity3,
    ) -> (LevelLog, (f64, f64, bool)) {
        let mut other = Deformation::from_map(phi.size, |p| s_space.apply(p));
        let mut other_similarity = *motion;
        let (from_features, from_space) =
            self.level_from_both(k0, (phi, similarity), (&mut other, &mut other_similarity));
        let level = self.energy(k0, *similarity);
        let kept = self.second_ends_lower(
            k0,
            (phi, *similarity, from_features.end.total),
            (&other, other_similarity, from_space.end.total),
        ) && matched_area(&level, &other) >= matched_area(&level, phi);
        let energies = (from_features.end.total, from_space.end.total, kept);
        if kept {
            *phi = other;
            *similarity = other_similarity;
            (from_space, energies)
        } else {
            (from_features, energies)
        }
    }

    /// Level `k` minimized from two starts at once, each on its own φ and position
    /// similarity, with the budget left before both (charged together afterwards).
    fn level_from_both(
        &self,
        k: usize,
        first: (&mut Deformation, &mut Similarity3),
        second: (&mut Deformation, &mut Similarity3),
    ) -> (LevelLog, LevelLog) {
        let spent = self.spent();
        let ((log_first, cost_first), (log_second, cost_second)) = rayon::join(
            || self.level_charged(k, first.0, first.1, spent),
            || self.level_charged(k, second.0, second.1, spent),
        );
        self.charge(cost_first + cost_second);
        (log_first, log_second)
    }

    /// Minimizes level `k` from `phi` (already on level k's grid).
    fn level(&self, k: usize, phi: &mut Deformation, similarity: &mut Similarity3) -> LevelLog {
        let (log, cost) = self.level_charged(k, phi, similarity, self.spent());
        self.charge(cost);
        log
    }

    /// Whether the second of two solves of level `k` (each: its φ, its position map and
    /// the energy its solve ended with) ends lower: by [`Solver::plain_energy`] when the
    /// relief is on, else by the solves' own final energies.
    fn second_ends_lower(
        &self,
        k: usize,
        first: (&Deformation, Similarity3, f64),
        second: (&Deformation, Similarity3, f64),
    ) -> bool {
        match (
            self.plain_energy(k, first.0, first.1),
            self.plain_energy(k, second.0, second.1),
        ) {
            (Some(f), Some(s)) => s < f,
            _ => second.2 < first.2,
        }
    }

    /// The energy of level `k` at `phi` with the position term's map refitted and no
    /// relief ([`relief_offsets`]): what two starts are compared by, since the relief
    /// absorbs the smooth part of a start's error along with the surfaces' difference.
    /// `None` when the relief is off (the solves' own final energies compare alike).
    fn plain_energy(&self, k: usize, phi: &Deformation, similarity: Similarity3) -> Option<f64> {
        if self.options.advanced.relief <= 0.0 {
            return None;
        }
        let mut e = self.energy(k, similarity);
        e.relief = false;
        self.refit(&mut e, phi);
        let mut grad = vec![[0.0; 2]; phi.displacement.len()];
        Some(
            e.evaluate(&phi.displacement, &mut grad, &mut Workspace::default())
                .total,
        )
    }

    /// Evaluations spent so far ([`Solver::spent`]).
    fn spent(&self) -> f64 {
        f64::from_bits(self.spent.load(std::sync::atomic::Ordering::Relaxed))
    }

    /// Adds `cost` finest-level evaluations to [`Solver::spent`].
    fn charge(&self, cost: f64) {
        let total = self.spent() + cost;
        self.spent
            .store(total.to_bits(), std::sync::atomic::Ordering::Relaxed);
    }

    /// Minimizes level `k` from `phi` with the budget left after `spent` evaluations;
    /// returns its log and its cost in finest-level evaluations, not yet charged.
    fn level_charged(
        &self,
        k: usize,
        phi: &mut Deformation,
        similarity: &mut Similarity3,
        spent: f64,
    ) -> (LevelLog, f64) {
        let mut energy = self.energy(k, *similarity);
        let mut refit = |e: &mut LevelEnergy, phi: &Deformation| self.refit(e, phi);
        let n = phi.size;
        let metric =
            |width: f64| (width > 0.0).then(|| SobolevPreconditioner::new(n, width * width));
        let local = metric(self.options.tuning.sobolev_cells / (n - 1) as f64);
        let mut settings = self.options.ncg();
        if k == self.a.num_levels() - 1 {
            settings.tolerance = settings.finest_tolerance;
        }
        let coarsest = k == self.options.tuning.coarsest_level;
        if coarsest {
            settings.window = settings.coarsest_window;
        }
        let finest = self.a.level_size(self.a.num_levels() - 1);
        let cost = ((n - 1) as f64 / (finest - 1) as f64).powi(2);
        let mut budget = settings.level_evaluations(n, finest);
        let relief = self.options.advanced.relief > 0.0;
        if relief && !coarsest && n < finest && budget != usize::MAX {
            budget = (budget as f64 * RELIEF_MIDDLE_BUDGET).ceil() as usize;
        }
        if settings.total_evaluations > 0 {
            let left = (settings.total_evaluations as f64 - spent).max(0.0);
            budget = budget.min((left / cost) as usize);
        }
        let mut run = |max_iterations: usize,
                       budget: usize,
                       metric: Option<&SobolevPreconditioner>,
                       relief: bool| {
            let settings = NcgSettings {
                max_iterations,
                ..settings
            };
            energy.relief = relief;
            minimize(&mut energy, phi, &settings, budget, k, metric, &mut refit)
        };
        let wide = self.options.tuning.coarsest_sobolev_width;
        let log = if coarsest && wide > 0.0 {
            // First the wide metric, then the local one, half of the iterations and
            // of the evaluations each ([`COARSEST_SOBOLEV_WIDTH`](super::options::COARSEST_SOBOLEV_WIDTH)).
            let first = run(
                settings.max_iterations.div_ceil(2),
                budget.div_ceil(2),
                metric(wide).as_ref(),
                false,
            );
            let second = run(
                settings.max_iterations / 2,
                budget.saturating_sub(first.evaluations),
                local.as_ref(),
                false,
            );
            if relief {
                // With the relief, a third phase in the local metric: only once φ is
                // placed without it ([`POSITION_RELIEF`]), and shorter
                // ([`RELIEF_PHASE_FRACTION`]).
                let share = |count: usize| (count as f64 * RELIEF_PHASE_FRACTION).ceil() as usize;
                let third = run(
                    share(settings.max_iterations),
                    share(budget),
                    local.as_ref(),
                    true,
                );
                first.then(second).then(third)
            } else {
                first.then(second)
            }
        } else {
            run(settings.max_iterations, budget, local.as_ref(), !coarsest)
        };
        *similarity = energy.similarity;
        let charged = log.evaluations as f64 * cost;
        (log, charged)
    }
}

/// The map of ℝ³ ([`PositionMap`]) that best carries A's positions onto B's matched
/// positions, weighted by the node weights and `χ^ε`.
fn fit_position_map(
    e: &LevelEnergy,
    phi: &Deformation,
    options: &MatchOptions,
) -> Option<Similarity3> {
    let n = e.size();
    let mut p = Vec::with_capacity(n * n);
    let mut q = Vec::with_capacity(n * n);
    let mut w = Vec::with_capacity(n * n);
    for k in 0..n * n {
        let wa = e.a.weight[k] * e.a.chi[k];
        if wa == 0.0 {
            continue;
        }
        let s = e.b.field.sample(phi.at(k));
        let c = chi(s[B_SD], e.epsilon).0;
        if c == 0.0 {
            continue;
        }
        let x = [s[B_X], s[B_X + 1], s[B_X + 2]];
        p.push(e.a.x[k]);
        q.push(x);
        w.push(wa * c);
    }
    let similarity = fit_similarity_3d(&p, &q, &w, options.tuning.allow_scale)?;
    match options.tuning.position_map {
        PositionMap::Similarity => Some(similarity),
        PositionMap::AffineNearSimilarity { ridge } => {
            fit_affine_3d_near(&p, &q, &w, &similarity, ridge).or(Some(similarity))
        }
    }
}

/// The smooth part of the position term's residual, per node: with
/// `r = x_B∘φ − T(x_A)` over the nodes both surfaces cover (weights `w·χ`),
/// `R = G_σ * (w r) / G_σ * (w)`. Added to `T(x_A)`, it lets the position term compare
/// the surfaces after their smooth difference in shape (one forehead higher, one nose
/// longer than the other) instead of pulling φ towards B's closest points under one
/// global map; what is left to pull is the residual's detail.
pub(crate) fn relief_offsets(e: &LevelEnergy, phi: &Deformation, width: f64) -> Vec<[f64; 3]> {
    let n = e.size();
    let data: Vec<[f64; 4]> = (0..n * n)
        .into_par_iter()
        .map(|k| {
            let wa = e.a.weight[k] * e.a.chi[k];
            if wa == 0.0 {
                return [0.0; 4];
            }
            let sb = e.b.field.sample(phi.at(k));
            let w = wa * chi(sb[B_SD], e.epsilon).0;
            if w == 0.0 {
                return [0.0; 4];
            }
            let y = e.similarity.apply(e.a.x[k]);
            [
                w * (sb[B_X] - y[0]),
                w * (sb[B_X + 1] - y[1]),
                w * (sb[B_X + 2] - y[2]),
                w,
            ]
        })
        .collect();
    let peak = data.iter().map(|d| d[3]).fold(0.0, f64::max);
    // A wide Gaussian is computed on every `step`-th row and column (σ at least 4 of
    // their spacings) and read back bilinearly: 1/16 of the work at 257².
    let sigma = width * (n - 1) as f64;
    let mut step = 1;
    while (8 * step) as f64 <= sigma
        && (n - 1).is_multiple_of(2 * step)
        && (n - 1) / (2 * step) >= 16
    {
        step *= 2;
    }
    let smooth = gaussian_filter_restricted(&Grid::from_parts(n, data), sigma, step);
    let floor = 1e-3 * peak;
    (0..n * n)
        .into_par_iter()
        .map(|k| {
            let d = smooth.sample(node(n, k));
            if d[3] > floor {
                [d[0] / d[3], d[1] / d[3], d[2] / d[3]]
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matching::prepare::shared_length_unit;
    use crate::matching::similarity::fit_similarity_2d;
    use crate::mesh::TriMesh;
    use crate::mesh::closest::ClosestPoints;
    use crate::mesh::generate::bumpy_disc;

    /// The relief is the smooth part of the residual `x_B∘φ − T(x_A)`: B's positions
    /// are A's moved by a constant `c` plus a node checkerboard `±δ` (detail at the
    /// grid's own scale) — the offsets must be `c` to within a small fraction of `δ`,
    /// on grids where the Gaussian is computed in full (65²) and restricted (257²:
    /// every 4th row and column), and with B's cover cut to half of ω (no weight
    /// beyond x = ½: the offsets up to one σ past the cut are read from the covered
    /// part, still `c`; far beyond it, where the Gaussian's weight has died out, 0).
    /// (`χ_A = 1` and the node weights halve on ω's border, so the normalization is
    /// exercised too.)
    #[test]
    fn the_relief_is_the_smooth_part_of_the_residual() {
        let c = [0.03, -0.02, 0.01];
        let delta = 0.01;
        for (n, cut) in [(65, false), (257, false), (257, true)] {
            let mut e = crate::matching::energy::tests::self_match(n);
            let mut field = e.b.field.as_slice().to_vec();
            for (k, v) in field.iter_mut().enumerate() {
                let (i, j) = (k / n, k % n);
                let sign = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
                for a in 0..3 {
                    v[B_X + a] += c[a] + sign * delta;
                }
                if cut && node(n, k)[0] > 0.5 {
                    v[B_SD] = 1.0;
                }
            }
            e.b.field = Grid::from_vec(n, field).unwrap();
            let phi = Deformation::identity(n);
            let offsets = relief_offsets(&e, &phi, 0.1);
            let x = |k: usize| node(n, k)[0];
            let worst = (0..n * n)
                .filter(|&k| !cut || x(k) <= 0.6)
                .flat_map(|k| {
                    let o = offsets[k];
                    (0..3).map(move |a| (o[a] - c[a]).abs())
                })
                .fold(0.0, f64::max);
            assert!(worst < 0.02 * delta, "n {n} cut {cut}: worst {worst}");
            if cut {
                assert!(
                    (0..n * n)
                        .filter(|&k| x(k) > 0.95)
                        .all(|k| offsets[k] == [0.0; 3])
                );
            }
        }
    }

    /// A surface and a re-triangulated copy: the true plane similarity is fitted to
    /// the domain positions of every vertex of A and B's nearest vertex (the same point
    /// in space). Started 12° and 10 % in scale off it, the search must find it, and
    /// the coarsest level must end near it from whichever start it keeps.
    #[test]
    fn the_search_brings_a_turned_and_scaled_start_back() {
        let (mesh_a, mesh_b) = (bumpy_disc(18, 0.4), bumpy_disc(23, 0.4));
        let unit = shared_length_unit(mesh_a.area(), mesh_b.area());
        let mut options = MatchOptions {
            size: 129,
            ..Default::default()
        };
        // The search with its scale (off by default, `SimilaritySearch::scale`).
        options.tuning.search.scale = true;
        let surface = |m: &TriMesh| MatchSurface::new(m, None, 129, true, unit).unwrap();
        let (sa, sb) = (surface(&mesh_a), surface(&mesh_b));
        let closest = ClosestPoints::new(&sb.positions);
        let (pa, pb): (Vec<[f64; 2]>, Vec<[f64; 2]>) = (0..sa.positions.len())
            .map(|v| {
                let (w, _) = closest.closest(&sa.positions[v]);
                (sa.vertex_domain_position(v), sb.vertex_domain_position(w))
            })
            .unzip();
        let truth = fit_similarity_2d(&pa, &pb).unwrap();
        let (ca, _) = sa.domain_centroid_and_area();
        let off = Similarity2::about(truth.apply(ca), 12f64.to_radians(), 1.1, truth.apply(ca));
        let start = off.after(&truth);
        let solver = Solver {
            a: &sa,
            b: &sb,
            features: &[],
            options: &options,
            // The weight the test was measured with.
            betas: Betas {
                position: 1000.0,
                ..options.betas()
            },
            spent: Default::default(),
        };
        let k0 = options.tuning.coarsest_level;
        let mut phi = Deformation::from_map(sa.level_size(k0), |p| start.apply(p));
        let mut similarity = Similarity3::identity();
        let (_, found) = solver.level_with_search(k0, start, &mut phi, &mut similarity);
        let found = found.expect("the search lowers the energy");
        let moved = found.similarity.after(&start);
        let angle = (moved.angle() - truth.angle()).to_degrees();
        let scale = moved.scale() / truth.scale();
        assert!(
            angle.abs() < 2.0 && (scale - 1.0).abs() < 0.02,
            "{angle}° and scale {scale} off the truth ({found:?})"
        );
        // φ over A's vertices against the truth, in cells of the 65² grid.
        let cell = 1.0 / (phi.size - 1) as f64;
        let mut off_truth: Vec<f64> = pa
            .iter()
            .map(|&p| {
                let (y, t) = (phi.apply(p), truth.apply(p));
                (y[0] - t[0]).hypot(y[1] - t[1]) / cell
            })
            .collect();
        off_truth.sort_by(f64::total_cmp);
        let median = off_truth[off_truth.len() / 2];
        assert!(median < 0.5, "median {median} cells off the truth");
    }
}
