//! Projected Newton minimization of the discrete elastic energy (thesis §3.1.3).
//!
//! `E(u) = Σ_T area3D(T) · W(a_T, d_T)` over the UV coordinates `u` of the vertices.
//! Each iteration:
//! 1. assembles the gradient and the per-triangle Hessians, each projected to positive
//!    semi-definite in closed form ([`element::gradient_and_projected_hessian`]);
//! 2. solves `H p = −∇E` (thesis (3.1) prints `+∇E`; the descent direction needs `−∇E`) with a sparse
//!    Cholesky whose symbolic factorization is computed once, in [`NewtonSolver::new`];
//! 3. steps along `p` with Armijo backtracking (thesis fig. 3.3) started at or below
//!    the largest flip-free step, so no accepted iterate has `det J ≤ 0` anywhere; an
//!    energy increase is never accepted, and when the full step was accepted and the
//!    flip-free bound allows, the step is doubled while the energy keeps dropping
//!    (barrier-dominated regions, where Newton steps are far too short).
//!
//! Once the Newton decrement is small (`λ² < 10⁻³·E`) the *exact* Hessian is tried
//! first: where its Cholesky succeeds (positive definite) the convergence is
//! quadratic, where it fails the projected one is used for the next few steps.
//! Stopping: `λ²/2 ≤ tolerance` (energy per unit area, scale-free), the iteration cap,
//! or no measurable decrease (the rounding floor).
//!
//! With the boundary barrier of the bijective mode ([`super::barrier`]) the line search
//! also stops short of the first boundary contact, and each active pair (boundary vertex
//! `v`, boundary edge `ab`) adds its Gauss–Newton Hessian `b''(d) ∇d ∇dᵀ`, which couples
//! `v` with `a` and `b`: vertices that are not mesh neighbours, so the sparse pattern
//! gets those couplings when a pair first needs them (re-analysed with the same
//! ordering, with a margin for the pairs about to come; it only grows). Without the
//! couplings (each vertex's own block only) Newton slides along contacts with tiny
//! steps; with them too early (a start far from the minimum with hundreds of pairs in
//! contact) the steps rush into new contacts, so they are used once `λ² < 0.3·E`.
//!
//! Rigid motions are removed by pinning three coordinates (both coordinates of one
//! vertex, the `v` coordinate of a second one after rotating it onto the `u` axis):
//! the energy is invariant under rigid motions, so this changes nothing but the
//! output's placement, and keeps the Cholesky factorization well-posed.

use super::barrier::BoundaryBarrier;
use super::element::{self, RestTriangle};
use super::flip_free::max_flip_free_step;
use crate::energy::Density;
use crate::linsolve::{FIXED, Ordering, SolveError, SpdSystem, Unknowns, VertexOrdering};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// One Newton iteration, as logged (the data of thesis fig. 4.1).
#[derive(Clone, Debug, Serialize)]
pub struct IterationLog {
    /// Iteration number within its stage (0 = the start).
    pub iteration: usize,
    /// Continuation stage (0 when there is no continuation).
    pub stage: usize,
    /// Energy after the iteration (per unit 3D area: the mean density).
    pub energy: f64,
    /// ‖∇E‖₂ before the step, in normalized units.
    pub gradient_norm: f64,
    /// Newton decrement `λ² = −∇Eᵀp` before the step.
    pub newton_decrement: f64,
    /// Accepted step length τ.
    pub step: f64,
    /// Largest flip-free step along `p`.
    pub flip_free_step: f64,
    /// Wall time since the start of the flattening, seconds.
    pub time: f64,
}

/// Why an iteration loop stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// Newton decrement below tolerance: a local minimum.
    Converged,
    /// The iteration cap was reached.
    IterationCap,
    /// The line search found no step that decreases the energy ("locking", §3.1.3).
    Locked,
    /// The energy's relative decrease per iteration fell below a threshold without a
    /// small Newton decrement: the scaffold iterations of the bijective mode
    /// ([`super::scaffold`]), near but not at the minimum.
    Stalled,
    /// The boundary of an iterate crossed itself
    /// ([`NewtonSolver::stop_when_boundary_crosses`]): the bijective mode's
    /// unconstrained attempt gives way to the barrier solve.
    BoundaryCrossed,
}

/// Line-search and stopping parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonSettings {
    /// Armijo sufficient-decrease constant `c` (thesis: 0.5).
    pub armijo_c: f64,
    /// Backtracking factor `ρ` (thesis: 0.8).
    pub armijo_rho: f64,
    /// Stop when `λ²/2 ≤ tolerance` (energy per unit area, so scale-free).
    pub tolerance: f64,
    pub max_iterations: usize,
    /// Take a chord step (reuse the last exact factorization) when the decrement
    /// estimate at the new point is below this fraction of the last decrement; 0 never
    /// (every step factorizes anew). See [`CHORD_CONTRACTION`].
    pub chord_contraction: f64,
    /// Chord steps only for systems of at least this many unknowns (see
    /// [`CHORD_MIN_UNKNOWNS`]).
    pub chord_min_unknowns: usize,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            armijo_c: 0.5,
            armijo_rho: 0.8,
            tolerance: 1e-12,
            max_iterations: 200,
            chord_contraction: CHORD_CONTRACTION,
            chord_min_unknowns: CHORD_MIN_UNKNOWNS,
        }
    }
}

/// The Newton solver for one mesh: rest triangles, the pinned-DOF map and the sparse
/// system with its symbolic factorization, all built once and reused across
/// iterations and continuation stages.
pub struct NewtonSolver<'m> {
    triangles: &'m [[u32; 3]],
    rest: Vec<RestTriangle>,
    /// The unknowns: coordinate `c` of vertex `v` is value `2·v + c`; the pins are fixed.
    dof: Unknowns,
    system: SpdSystem,
    /// For each triangle, the value slot of its 21 lower-triangle local pairs
    /// (`u32::MAX` where a pinned coordinate is involved).
    slots: Vec<[u32; 21]>,
    elem_grad: Vec<[f64; 6]>,
    elem_hess: Vec<[f64; 21]>,
    elem_energy: Vec<f64>,
    gradient: Vec<f64>,
    direction: Vec<[f64; 2]>,
    trial: Vec<[f64; 2]>,
    best: Vec<[f64; 2]>,
    /// The boundary barrier of the bijective mode ([`super::barrier`]).
    barrier: Option<BoundaryBarrier>,
    /// A boundary loop whose crossing for the given number of iterations in a row ends
    /// [`Self::minimize`] ([`StopReason::BoundaryCrossed`]).
    watched_boundary: Option<(Vec<u32>, usize)>,
    /// The last iterate whose watched boundary did not cross itself (empty until one
    /// was checked; [`Self::take_last_uncrossed`]).
    last_uncrossed: Vec<[f64; 2]>,
    /// The relative stopping threshold with the barrier ([`BARRIER_RELATIVE_TOLERANCE`]
    /// unless set, [`Self::set_barrier_relative_tolerance`]).
    barrier_relative_tolerance: f64,
    /// The barrier's pair terms at the last assembly ([`PairTerm`]).
    pairs: Vec<PairTerm>,
    /// The fill-reducing ordering of the unknowns, kept to re-analyse the pattern.
    ordering: Ordering,
    /// Couplings of unknowns beyond the triangles' in the sparse pattern: those of
    /// every barrier pair met so far (the pattern only grows, so a pair that comes
    /// back costs no new analysis).
    extra: Vec<(u32, u32)>,
    /// Whether the next assembly couples the vertices of each barrier pair (else it
    /// keeps only each vertex's own block of the pair's Hessian).
    couple_pairs: bool,
    /// Where the time went, accumulated over all calls of [`Self::minimize`].
    pub timings: NewtonTimings,
}

/// Seconds spent in each phase of the Newton iterations.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct NewtonTimings {
    /// Symbolic analysis of the sparse pattern (once per mesh).
    pub symbolic: f64,
    /// Element gradients and Hessians, scatter into the sparse matrix.
    pub assemble: f64,
    /// Numeric Cholesky factorizations (including failed exact-Hessian attempts).
    pub factorize: f64,
    /// Triangular solves.
    pub solve: f64,
    /// Flip-free bound and Armijo backtracking (energy evaluations).
    pub line_search: f64,
    /// Numeric factorizations, and how many of them were exact-Hessian attempts that
    /// failed (not positive definite) and were redone with the projected Hessian.
    pub factorizations: usize,
    pub exact_failures: usize,
    /// Chord steps: iterations that reused the previous exact factorization instead of
    /// a new one (see [`CHORD_CONTRACTION`]).
    pub chord_steps: usize,
    /// Symbolic re-analyses of the sparse pattern for new boundary-barrier pairs
    /// (their time is in `symbolic`).
    pub pattern_rebuilds: usize,
}

/// Which element Hessian to assemble.
#[derive(Clone, Copy, PartialEq, Eq)]
enum HessianKind {
    /// Projected to positive semi-definite per element: always a descent direction.
    Projected,
    /// The exact Hessian: quadratic convergence near a minimum, if positive definite.
    Exact,
    /// No Hessian: the gradient only (the matrix values are left as they are).
    None,
}

/// Consecutive iterations whose boundary crosses itself that end a watched solve
/// ([`NewtonSolver::stop_when_boundary_crosses`]) from a start far from the minimum:
/// one is not enough (a cone cut from its apex crosses transiently and unrolls to an
/// exact isometry; so do the coarse levels of ICT faces opened with seams, two iterates
/// crossing then none), two fail the same test.
pub const CROSSING_PERSISTENCE: usize = 3;

/// Relative stopping threshold with a boundary barrier: `λ²/2 ≤ 10⁻⁴·E` (the energy
/// is then within about that fraction of the minimum). Near a contact the barrier's
/// Hessian is approximated and convergence is linear: from 10⁻⁶ to 10⁻⁴ the ICT faces
/// opened with seams take 3–29 iterations instead of 6–32, at energies 0.004–0.024 %
/// higher (BENCHMARKS.md, "Hard discs").
pub(super) const BARRIER_RELATIVE_TOLERANCE: f64 = 1e-4;

/// Largest step tried with a boundary barrier (the contact search's reach).
const BARRIER_STEP_CAP: f64 = 16.0;

/// Pairs closer than this many times their barrier distance `ε` get their couplings
/// in the sparse pattern whenever it is re-analysed (a margin for the pairs to come;
/// measured on `ict_neutral` opened with seams: 14 re-analyses with no margin, 5 with
/// 2, 3 with 4).
const PATTERN_REACH: f64 = 4.0;

/// Couple the vertices of each boundary-barrier pair in the Hessian once the Newton
/// decrement is below this fraction of the energy (measured: from a mean-value start
/// with hundreds of pairs in contact, coupling earlier stalls the solve).
const COUPLING_SWITCH: f64 = 0.3;

/// Armijo constant for exact-Hessian steps (see the line search).
const EXACT_ARMIJO_C: f64 = 1e-4;

/// Try the exact Hessian once the Newton decrement is below this fraction of the energy.
const EXACT_SWITCH: f64 = 1e-3;

/// Default of [`NewtonSettings::chord_contraction`].
///
/// Chord steps (simplified Newton, Kelley, *Iterative Methods for Linear and Nonlinear
/// Equations*, 1995, §5.4): `p = −H_k⁻¹ ∇E(u)` with the factorization of the Hessian
/// `H_k` of the last full step. After a full exact-Newton (or chord) step the
/// convergence test already solves with `H_k`; when that decrement estimate is below
/// this fraction of the last decrement (the quadratic region, where
/// `H(u) = H_k + O(‖p_k‖)` and a chord step contracts the error by `O(‖p_k‖)`), its
/// direction is taken instead of factorizing `H(u)`. It is a descent direction (`H_k`
/// is positive definite) and goes through the same flip-free line search. Measured
/// (BENCHMARKS.md, "Scale"): on a 1.07M-face disc two of six factorizations become
/// solves, same energies to 9 digits; on the shared discs (three presets) 20 % more
/// iterations but less time (13.8 → 13.0 s in all, one run), same energies to 6 digits.
pub const CHORD_CONTRACTION: f64 = 0.1;

/// Default of [`NewtonSettings::chord_min_unknowns`]: chord steps are taken on systems of
/// 200k unknowns (100k vertices) and more, where a factorization costs seconds. Below,
/// every step factorizes: the gain there was 6 % of the time, and the flattenings the
/// matcher was calibrated on (faces of 10–50k vertices) stay bit for bit what they were
/// (with chord steps they move by ~10⁻⁶, which changed the outcome of two synthetic
/// matching tests — a sensitivity of the matcher, not of the flattening).
pub const CHORD_MIN_UNKNOWNS: usize = 200_000;

/// Local pairs `(i, j)` with `j ≤ i` of a 6×6 element matrix, in a fixed order.
const LOWER_PAIRS: [(usize, usize); 21] = {
    let mut out = [(0, 0); 21];
    let mut k = 0;
    let mut i = 0;
    while i < 6 {
        let mut j = 0;
        while j <= i {
            out[k] = (i, j);
            k += 1;
            j += 1;
        }
        i += 1;
    }
    out
};

impl<'m> NewtonSolver<'m> {
    /// Builds the solver from the rest triangles (one per triangle, from positions the
    /// caller normalized to unit area), the pinned coordinates `pins`
    /// (`(vertex, coordinate)`), the sparse pattern and its symbolic factorization.
    /// `ordering`: the mesh's shared vertex ordering, each vertex's `(u, v)` eliminated
    /// consecutively, or `None` for AMD on the `2n − 3` system's own pattern.
    pub fn new(
        num_vertices: usize,
        triangles: &'m [[u32; 3]],
        rest: Vec<RestTriangle>,
        pins: &[(u32, usize)],
        ordering: Option<&VertexOrdering>,
    ) -> Result<Self, SolveError> {
        let nv = num_vertices;
        let dof = Unknowns::new(2 * nv, pins.iter().map(|&(v, c)| 2 * v as usize + c));
        let n = dof.count();
        let t_symbolic = Instant::now();
        let ordering = match ordering {
            Some(vertices) => vertices.expand(2, &dof)?,
            None => Ordering::Amd,
        };
        let (system, slots) = build_system(&dof, triangles, &[], &ordering)?;
        let symbolic_time = t_symbolic.elapsed().as_secs_f64();
        let nf = triangles.len();
        Ok(Self {
            triangles,
            rest,
            dof,
            system,
            slots,
            elem_grad: vec![[0.0; 6]; nf],
            elem_hess: vec![[0.0; 21]; nf],
            elem_energy: vec![0.0; nf],
            gradient: vec![0.0; n],
            direction: vec![[0.0; 2]; nv],
            trial: vec![[0.0; 2]; nv],
            best: vec![[0.0; 2]; nv],
            barrier: None,
            watched_boundary: None,
            last_uncrossed: Vec::new(),
            barrier_relative_tolerance: BARRIER_RELATIVE_TOLERANCE,
            pairs: Vec::new(),
            ordering,
            extra: Vec::new(),
            couple_pairs: true,
            timings: NewtonTimings {
                symbolic: symbolic_time,
                ..Default::default()
            },
        })
    }

    /// The triangles of the mesh being solved.
    pub fn triangles(&self) -> &'m [[u32; 3]] {
        self.triangles
    }

    /// Exchanges the rest triangles the energy is measured against with `rest` (the
    /// progressive reference shapes of a crushed start, [`super::flatten`]); the solver
    /// must hold one per triangle whenever it evaluates or minimizes.
    pub fn swap_rest(&mut self, rest: &mut Vec<RestTriangle>) {
        std::mem::swap(&mut self.rest, rest);
    }

    /// Ends [`Self::minimize`] with [`StopReason::BoundaryCrossed`] once `persistence`
    /// iterations in a row (at least one) have mapped `boundary` (a loop of vertex ids)
    /// across itself.
    pub fn stop_when_boundary_crosses(&mut self, boundary: Vec<u32>, persistence: usize) {
        self.watched_boundary = Some((boundary, persistence.max(1)));
    }

    /// The last iterate of [`Self::minimize`] whose watched boundary
    /// ([`Self::stop_when_boundary_crosses`]) did not cross itself, if one was checked
    /// (a flip-free, crossing-free map: a start for the barrier solve).
    pub fn take_last_uncrossed(&mut self) -> Option<Vec<[f64; 2]>> {
        Some(std::mem::take(&mut self.last_uncrossed)).filter(|uv| !uv.is_empty())
    }

    /// Adds the boundary barrier `barrier` to the energy, and its contact bound to the
    /// line search (the bijective mode, [`super::barrier`]).
    pub fn set_barrier(&mut self, barrier: BoundaryBarrier) {
        self.barrier = Some(barrier);
    }

    /// Sets the relative stopping threshold with the barrier (default
    /// [`BARRIER_RELATIVE_TOLERANCE`]).
    pub fn set_barrier_relative_tolerance(&mut self, tolerance: f64) {
        self.barrier_relative_tolerance = tolerance;
    }

    /// The stopping threshold on `λ²/2`: the settings' tolerance, or with the barrier
    /// (whose Hessian is approximated, so convergence is linear near contacts) at least
    /// [`BARRIER_RELATIVE_TOLERANCE`] of the energy (or the threshold set by
    /// [`Self::set_barrier_relative_tolerance`]).
    fn tolerance(&self, settings: &NewtonSettings, energy: f64) -> f64 {
        match self.barrier {
            Some(_) => settings
                .tolerance
                .max(self.barrier_relative_tolerance * energy.abs()),
            None => settings.tolerance,
        }
    }

    /// The barrier energy at `uv` (0 without a barrier).
    fn barrier_energy(&self, uv: &[[f64; 2]]) -> f64 {
        self.barrier.as_ref().map_or(0.0, |b| b.energy(uv))
    }

    #[inline]
    fn corners(&self, uv: &[[f64; 2]], t: usize) -> [[f64; 2]; 3] {
        let tri = self.triangles[t];
        [
            uv[tri[0] as usize],
            uv[tri[1] as usize],
            uv[tri[2] as usize],
        ]
    }

    /// The energy function of a mesh without building a solver (for the warm start).
    pub fn energy_of<'a, D: Density + ?Sized>(
        rest: &'a [RestTriangle],
        triangles: &'a [[u32; 3]],
    ) -> impl Fn(&[[f64; 2]], &D) -> f64 + 'a {
        move |uv, density| {
            (0..triangles.len())
                .into_par_iter()
                .with_min_len(4096)
                .map(|t| {
                    let tri = triangles[t];
                    element::energy(
                        &rest[t],
                        &[
                            uv[tri[0] as usize],
                            uv[tri[1] as usize],
                            uv[tri[2] as usize],
                        ],
                        density,
                    )
                })
                .sum()
        }
    }

    /// `E(u) = Σ_T area(T)·W` (thesis (2.5) summed per triangle); `+∞` if any
    /// triangle is flipped or degenerate.
    pub fn energy<D: Density + ?Sized>(&self, uv: &[[f64; 2]], density: &D) -> f64 {
        (0..self.triangles.len())
            .into_par_iter()
            .with_min_len(4096)
            .map(|t| element::energy(&self.rest[t], &self.corners(uv, t), density))
            .sum()
    }

    /// Runs Newton iterations from `uv` (modified in place) until convergence, the
    /// iteration cap or locking. `log` receives one entry per iteration.
    pub fn minimize<D: Density + ?Sized>(
        &mut self,
        uv: &mut [[f64; 2]],
        density: &D,
        settings: &NewtonSettings,
        stage: usize,
        clock: Instant,
        log: &mut dyn FnMut(IterationLog),
    ) -> Result<(StopReason, usize, f64), SolveError> {
        let mut energy = self.energy(uv, density) + self.barrier_energy(uv);
        log(IterationLog {
            iteration: 0,
            stage,
            energy,
            gradient_norm: f64::NAN,
            newton_decrement: f64::NAN,
            step: 0.0,
            flip_free_step: f64::NAN,
            time: clock.elapsed().as_secs_f64(),
        });
        // Projected Hessians guarantee descent but converge only linearly where element
        // Hessians are indefinite at the minimum; close to it we try the exact Hessian
        // (quadratic convergence) and keep it while its Cholesky succeeds.
        let mut exact_blocked_until = 0;
        let mut decrement_prev = f64::INFINITY;
        let mut last_step_full_exact = false;
        let mut crossing_iterations = 0;
        for it in 1..=settings.max_iterations {
            // Far from the minimum (a start that squeezed the boundary together, with
            // hundreds of pairs in contact) the coupled pair Hessian lets the step rush
            // into new contacts; there each vertex keeps its own block only.
            self.couple_pairs = decrement_prev < COUPLING_SWITCH * energy.abs();
            let mut chord = None;
            if last_step_full_exact {
                // After a full exact-Newton step the decrement has dropped quadratically:
                // test convergence with the previous factorization (a Hessian that differs
                // by O(step), so the estimate is accurate to that order) before paying
                // for a new one. Not converged: go on as usual.
                let t0 = Instant::now();
                self.assemble(uv, density, HessianKind::None)?;
                let t1 = Instant::now();
                let mut q: Vec<f64> = self.gradient.iter().map(|g| -g).collect();
                self.system.solve_in_place(&mut q)?;
                let estimate = -self
                    .gradient
                    .iter()
                    .zip(&q)
                    .map(|(g, q)| g * q)
                    .sum::<f64>();
                self.timings.assemble += (t1 - t0).as_secs_f64();
                self.timings.solve += t1.elapsed().as_secs_f64();
                if estimate.is_finite() && 0.5 * estimate.abs() <= self.tolerance(settings, energy)
                {
                    return Ok((StopReason::Converged, it - 1, energy));
                }
                if estimate.is_finite()
                    && estimate > 0.0
                    && estimate <= settings.chord_contraction * decrement_prev
                    && self.dof.count() >= settings.chord_min_unknowns
                {
                    chord = Some(q);
                }
            }
            let try_exact = chord.is_none()
                && it >= exact_blocked_until
                && decrement_prev < EXACT_SWITCH * energy.abs().max(1.0);
            let mut p = Vec::new();
            let mut solved = false;
            let mut solved_exact = false;
            if let Some(q) = chord {
                // The chord step: H_k's direction at the new point (see CHORD_CONTRACTION).
                p = q;
                solved = true;
                solved_exact = true;
                self.timings.chord_steps += 1;
            }
            if try_exact {
                let t0 = Instant::now();
                self.assemble(uv, density, HessianKind::Exact)?;
                let t1 = Instant::now();
                let ok = self.system.factorize_unshifted().is_ok();
                self.timings.factorizations += 1;
                self.timings.exact_failures += usize::from(!ok);
                self.timings.assemble += (t1 - t0).as_secs_f64();
                self.timings.factorize += t1.elapsed().as_secs_f64();
                if ok {
                    let t2 = Instant::now();
                    p = self.gradient.iter().map(|g| -g).collect();
                    self.system.solve_in_place(&mut p)?;
                    self.timings.solve += t2.elapsed().as_secs_f64();
                    solved = true;
                    solved_exact = true;
                } else {
                    exact_blocked_until = it + 3;
                }
            }
            if !solved {
                let t0 = Instant::now();
                self.assemble(uv, density, HessianKind::Projected)?;
                let t1 = Instant::now();
                self.system.factorize()?;
                self.timings.factorizations += 1;
                let t2 = Instant::now();
                p = self.gradient.iter().map(|g| -g).collect();
                self.system.solve_in_place(&mut p)?;
                self.timings.assemble += (t1 - t0).as_secs_f64();
                self.timings.factorize += (t2 - t1).as_secs_f64();
                self.timings.solve += t2.elapsed().as_secs_f64();
            }
            let gradient_norm = self.gradient.iter().map(|g| g * g).sum::<f64>().sqrt();
            let decrement = -self
                .gradient
                .iter()
                .zip(&p)
                .map(|(g, p)| g * p)
                .sum::<f64>();
            decrement_prev = decrement;
            if !decrement.is_finite() {
                // Overflow in the step: no progress is possible, and nothing says
                // this is a minimum (it used to be reported as converged).
                return Ok((StopReason::Locked, it - 1, energy));
            }
            if decrement <= 0.0 {
                // The matrix is positive definite, so p is a descent direction unless
                // the gradient vanished to rounding: we are at the minimum.
                return Ok((StopReason::Converged, it - 1, energy));
            }
            if 0.5 * decrement <= self.tolerance(settings, energy) {
                return Ok((StopReason::Converged, it - 1, energy));
            }
            for (v, d) in self.direction.iter_mut().enumerate() {
                for (c, dc) in d.iter_mut().enumerate() {
                    *dc = self.dof.get(2 * v + c).map_or(0.0, |k| p[k as usize]);
                }
            }
            let t_search = Instant::now();
            let mut t_max = max_flip_free_step(uv, self.triangles, &self.direction);
            if let Some(barrier) = &self.barrier {
                // No step past the first boundary contact; the contact search covers
                // steps up to a cap (the doubling below stays under it).
                let cap = t_max.min(BARRIER_STEP_CAP);
                t_max = cap.min(barrier.max_step(uv, &self.direction, cap));
            }
            // Start at the full Newton step, or 90% of the way to the first flip.
            let mut step = 1.0f64.min(0.9 * t_max);
            let slope = -decrement; // ∇Eᵀp
            // With the exact Hessian the unit step's predicted decrease is exactly
            // λ²/2, so the thesis's c = ½ rejects it as soon as the third derivative
            // is non-zero, and Newton loses its quadratic convergence (steps of 0.8
            // for ever). Exact steps use the textbook c = 10⁻⁴ (Nocedal & Wright
            // §3.1); projected steps keep the configured constant.
            let armijo_c = if solved_exact {
                settings.armijo_c.min(EXACT_ARMIJO_C)
            } else {
                settings.armijo_c
            };
            let mut accepted = None;
            // Roundoff guard: near the minimum E(u + τp) − E(u) drowns in the rounding
            // of the sum; allow that much slack.
            let slack = 1e-13 * energy.abs();
            let mut at_rounding_floor = false;
            for _ in 0..200 {
                for (tr, (u, d)) in self.trial.iter_mut().zip(uv.iter().zip(&self.direction)) {
                    *tr = [u[0] + step * d[0], u[1] + step * d[1]];
                }
                let e = self.energy(&self.trial, density) + self.barrier_energy(&self.trial);
                // Sufficient decrease (thesis fig. 3.3), but never an increase.
                if e.is_finite() && e < energy && e <= energy + armijo_c * step * slope + slack {
                    accepted = Some(e);
                    break;
                }
                if e.is_finite() && (e - energy).abs() <= slack {
                    // No decrease is measurable any more: a minimum to rounding.
                    at_rounding_floor = true;
                    break;
                }
                step *= settings.armijo_rho;
                if step < 1e-14 {
                    break;
                }
            }
            let Some(mut e_new) = accepted else {
                let reason = if at_rounding_floor {
                    StopReason::Converged
                } else {
                    StopReason::Locked
                };
                return Ok((reason, it - 1, energy));
            };
            // Barrier-dominated regions (triangles the start map shrank a lot) take
            // Newton steps that are far too short (a 1/d barrier grows a shrunk
            // triangle by only ~20% per full step): when the full step was accepted and
            // the flip-free bound allows, try doubling it while the energy still drops.
            if step == 1.0 && 0.9 * t_max > 2.0 && energy - e_new > 1e3 * slack {
                std::mem::swap(&mut self.trial, &mut self.best);
                let mut t = 2.0;
                while t <= 0.9 * t_max {
                    for (tr, (u, d)) in self.trial.iter_mut().zip(uv.iter().zip(&self.direction)) {
                        *tr = [u[0] + t * d[0], u[1] + t * d[1]];
                    }
                    let e = self.energy(&self.trial, density) + self.barrier_energy(&self.trial);
                    if e.is_nan() || e >= e_new {
                        break;
                    }
                    e_new = e;
                    step = t;
                    std::mem::swap(&mut self.trial, &mut self.best);
                    t *= 2.0;
                }
                std::mem::swap(&mut self.trial, &mut self.best);
            }
            uv.copy_from_slice(&self.trial);
            last_step_full_exact = solved_exact && step == 1.0;
            self.timings.line_search += t_search.elapsed().as_secs_f64();
            energy = e_new;
            log(IterationLog {
                iteration: it,
                stage,
                energy,
                gradient_norm,
                newton_decrement: decrement,
                step,
                flip_free_step: t_max,
                time: clock.elapsed().as_secs_f64(),
            });
            if let Some((boundary, persistence)) = &self.watched_boundary {
                if crate::measure::overlap::boundary_crossings(uv, boundary) > 0 {
                    crossing_iterations += 1;
                    if crossing_iterations >= *persistence {
                        return Ok((StopReason::BoundaryCrossed, it, energy));
                    }
                } else {
                    crossing_iterations = 0;
                    self.last_uncrossed.clear();
                    self.last_uncrossed.extend_from_slice(uv);
                }
            }
        }
        Ok((StopReason::IterationCap, settings.max_iterations, energy))
    }

    /// Fills the gradient and the Hessian values of `kind` for the current `uv` (the
    /// boundary barrier's pairs with their full Gauss–Newton Hessian, the pattern
    /// re-analysed first if a pair couples unknowns it does not hold yet).
    fn assemble<D: Density + ?Sized>(
        &mut self,
        uv: &[[f64; 2]],
        density: &D,
        kind: HessianKind,
    ) -> Result<(), SolveError> {
        let triangles = self.triangles;
        let rest = &self.rest;
        self.elem_grad
            .par_iter_mut()
            .zip(self.elem_hess.par_iter_mut())
            .zip(self.elem_energy.par_iter_mut())
            .enumerate()
            .with_min_len(1024)
            .for_each(|(t, ((g, h), e))| {
                let tri = triangles[t];
                let corners = [
                    uv[tri[0] as usize],
                    uv[tri[1] as usize],
                    uv[tri[2] as usize],
                ];
                let mut hess = [[0.0; 6]; 6];
                *e = match kind {
                    HessianKind::None => element::gradient(&rest[t], &corners, density, g),
                    HessianKind::Projected => element::gradient_and_projected_hessian(
                        &rest[t], &corners, density, g, &mut hess,
                    ),
                    HessianKind::Exact => {
                        element::exact_hessian(&rest[t], &corners, density, g, &mut hess)
                    }
                };
                if kind != HessianKind::None {
                    for (p, &(i, j)) in LOWER_PAIRS.iter().enumerate() {
                        h[p] = hess[i][j];
                    }
                }
            });
        let with_hessian = kind != HessianKind::None;
        if let Some(barrier) = &self.barrier {
            let (dof, pairs) = (&self.dof, &mut self.pairs);
            pairs.clear();
            barrier.for_each_pair_term(uv, |vertices, c, n, f1, f2| {
                pairs.push(PairTerm {
                    dofs: std::array::from_fn(|i| {
                        dof.as_slice()[2 * vertices[i / 2] as usize + i % 2]
                    }),
                    c,
                    n,
                    f1,
                    f2,
                    slots: [u32::MAX; 21],
                });
            });
            if with_hessian && self.couple_pairs {
                self.ensure_pair_pattern(uv)?;
            } else if with_hessian {
                // Each vertex's own block is always in the pattern.
                for pair in &mut self.pairs {
                    pair.find_slots(&self.system);
                }
            }
        }
        self.gradient.iter_mut().for_each(|g| *g = 0.0);
        // Only a new Hessian touches the matrix (and invalidates its factorization).
        let mut values = with_hessian.then(|| self.system.values_mut());
        if let Some(values) = values.as_deref_mut() {
            values.iter_mut().for_each(|v| *v = 0.0);
        }
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(values) = values.as_deref_mut() {
                let slots = &self.slots[t];
                let h = &self.elem_hess[t];
                for p in 0..21 {
                    let s = slots[p];
                    if s != u32::MAX {
                        values[s as usize] += h[p];
                    }
                }
            }
            let g = &self.elem_grad[t];
            for i in 0..6 {
                if let Some(k) = self.dof.get(2 * tri[i / 2] as usize + i % 2) {
                    self.gradient[k as usize] += g[i];
                }
            }
        }
        for pair in &self.pairs {
            for i in 0..6 {
                if pair.dofs[i] != FIXED {
                    self.gradient[pair.dofs[i] as usize] += pair.f1 * pair.c[i / 2] * pair.n[i % 2];
                }
            }
            if let Some(values) = values.as_deref_mut() {
                for (&s, &(i, j)) in pair.slots.iter().zip(&LOWER_PAIRS) {
                    if s != u32::MAX && (self.couple_pairs || i / 2 == j / 2) {
                        values[s as usize] += pair.f2
                            * (pair.c[i / 2] * pair.c[j / 2])
                            * (pair.n[i % 2] * pair.n[j % 2]);
                    }
                }
            }
        }
        Ok(())
    }

    /// Finds the value slots of every barrier pair's Hessian; where the pattern lacks a
    /// coupling, adds those of every pair closer than [`PATTERN_REACH`]` · ε` to it and
    /// re-analyses it (symbolic factorization with the same ordering).
    fn ensure_pair_pattern(&mut self, uv: &[[f64; 2]]) -> Result<(), SolveError> {
        let mut complete = true;
        for pair in &mut self.pairs {
            complete &= pair.find_slots(&self.system);
        }
        if complete {
            return Ok(());
        }
        let t0 = Instant::now();
        let (dof, extra) = (&self.dof, &mut self.extra);
        if let Some(barrier) = &self.barrier {
            barrier.for_each_pair_within(uv, PATTERN_REACH, |vertices| {
                let dofs: [u32; 6] =
                    std::array::from_fn(|i| dof.as_slice()[2 * vertices[i / 2] as usize + i % 2]);
                for &(i, j) in &LOWER_PAIRS {
                    let (a, b) = (dofs[i], dofs[j]);
                    if i / 2 != j / 2 && a != FIXED && b != FIXED {
                        extra.push((a.max(b), a.min(b)));
                    }
                }
            });
        }
        self.extra.sort_unstable();
        self.extra.dedup();
        let (system, slots) = build_system(&self.dof, self.triangles, &self.extra, &self.ordering)?;
        self.system = system;
        self.slots = slots;
        for pair in &mut self.pairs {
            pair.find_slots(&self.system);
        }
        self.timings.symbolic += t0.elapsed().as_secs_f64();
        self.timings.pattern_rebuilds += 1;
        Ok(())
    }
}

/// The sparse system over the couplings of every triangle's unknowns and `extra`,
/// with its symbolic factorization in `ordering`, and for each triangle the value slots
/// of its 21 lower-triangle local pairs (`u32::MAX` where a pinned coordinate is involved).
fn build_system(
    dof: &Unknowns,
    triangles: &[[u32; 3]],
    extra: &[(u32, u32)],
    ordering: &Ordering,
) -> Result<(SpdSystem, Vec<[u32; 21]>), SolveError> {
    let local_dofs = |t: &[u32; 3]| -> [u32; 6] {
        std::array::from_fn(|i| dof.as_slice()[2 * t[i / 2] as usize + i % 2])
    };
    let mut entries = Vec::with_capacity(triangles.len() * 21 + extra.len());
    for t in triangles {
        let ld = local_dofs(t);
        for &(i, j) in &LOWER_PAIRS {
            if ld[i] != FIXED && ld[j] != FIXED {
                entries.push((ld[i], ld[j]));
            }
        }
    }
    entries.extend_from_slice(extra);
    let (system, entry_slots) = SpdSystem::with_ordering(dof.count(), &entries, ordering)?;
    drop(entries);
    let mut slots = vec![[u32::MAX; 21]; triangles.len()];
    let mut k = 0;
    for (t, tri) in triangles.iter().enumerate() {
        let ld = local_dofs(tri);
        for (p, &(i, j)) in LOWER_PAIRS.iter().enumerate() {
            if ld[i] != FIXED && ld[j] != FIXED {
                slots[t][p] = entry_slots[k];
                k += 1;
            }
        }
    }
    Ok((system, slots))
}

/// One boundary-barrier pair (vertex `v`, edge `ab`) at the current map: its term's
/// gradient `f1 · c_k · n` on vertex `k` of `(v, a, b)` and its Gauss–Newton Hessian
/// `f2 · (c cᵀ) ⊗ (n nᵀ)` ([`BoundaryBarrier::for_each_pair_term`]), over the unknowns
/// `dofs` (`u, v` of each vertex; `FIXED` where pinned).
struct PairTerm {
    dofs: [u32; 6],
    c: [f64; 3],
    n: [f64; 2],
    f1: f64,
    f2: f64,
    /// Value slots of the 21 lower-triangle local pairs (`u32::MAX` where pinned).
    slots: [u32; 21],
}

impl PairTerm {
    /// Looks up the value slots in `system`'s pattern; `false` if one is missing.
    fn find_slots(&mut self, system: &SpdSystem) -> bool {
        let (col_ptr, row_idx) = system.pattern();
        let mut complete = true;
        for (slot, &(i, j)) in self.slots.iter_mut().zip(&LOWER_PAIRS) {
            let (a, b) = (self.dofs[i], self.dofs[j]);
            *slot = u32::MAX;
            if a == FIXED || b == FIXED {
                continue;
            }
            let (row, col) = (a.max(b), a.min(b));
            let start = col_ptr[col as usize] as usize;
            let rows = &row_idx[start..col_ptr[col as usize + 1] as usize];
            match rows.binary_search(&row) {
                Ok(k) => *slot = (start + k) as u32,
                Err(_) => complete = false,
            }
        }
        complete
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::Alpha;
    use crate::mesh::Disc;
    use crate::mesh::generate::bumpy_disc;
    use crate::param::barrier::BoundaryBarrier;
    use crate::param::element::rest_triangles;
    use crate::param::tutte::mean_value;

    #[test]
    fn convergence_is_judged_by_the_decrement_at_the_returned_map() {
        // The stopping test after a full exact step reuses the previous factorization;
        // check its verdict against a fresh factorization at the returned map.
        let mesh = bumpy_disc(10, 0.5);
        let (positions, _) = mesh.unit_area_positions();
        let disc = Disc::new(&mesh).unwrap();
        let boundary = disc.boundary();
        let mut uv = mean_value(&positions, &disc).unwrap();
        let rest = rest_triangles(&positions, &mesh.triangles).unwrap();
        let (p0, p1) = (boundary[0], boundary[boundary.len() / 2]);
        let mut solver = NewtonSolver::new(
            uv.len(),
            &mesh.triangles,
            rest,
            &[(p0, 0), (p0, 1), (p1, 1)],
            None,
        )
        .unwrap();
        let density = Alpha::balanced();
        let settings = NewtonSettings::default();
        let (stop, iterations, _) = solver
            .minimize(&mut uv, &density, &settings, 0, Instant::now(), &mut |_| {})
            .unwrap();
        assert_eq!(stop, StopReason::Converged);
        assert!(iterations > 2);
        // The last verdict came without a factorization of its own, and so did the
        // chord steps.
        assert_eq!(
            solver.timings.factorizations + solver.timings.chord_steps,
            iterations + solver.timings.exact_failures
        );
        solver.assemble(&uv, &density, HessianKind::Exact).unwrap();
        solver.system.factorize().unwrap();
        let mut p: Vec<f64> = solver.gradient.iter().map(|g| -g).collect();
        solver.system.solve_in_place(&mut p).unwrap();
        let decrement = -solver
            .gradient
            .iter()
            .zip(&p)
            .map(|(g, p)| g * p)
            .sum::<f64>();
        assert!(
            0.5 * decrement.abs() <= 2.0 * settings.tolerance,
            "decrement {decrement:e} at the returned map"
        );
    }

    #[test]
    fn chord_steps_reach_the_minimum_of_full_newton_with_fewer_factorizations() {
        // Same start, same settings but for chord steps (default) or none: the same
        // minimum (both converged; energies equal to the tolerance's order), the chord
        // run with steps that reused a factorization and fewer factorizations in all.
        let mesh = bumpy_disc(16, 0.6);
        let (positions, _) = mesh.unit_area_positions();
        let disc = Disc::new(&mesh).unwrap();
        let boundary = disc.boundary();
        let start = mean_value(&positions, &disc).unwrap();
        let rest = rest_triangles(&positions, &mesh.triangles).unwrap();
        let (p0, p1) = (boundary[0], boundary[boundary.len() / 2]);
        let density = Alpha::balanced();
        let run = |chord_contraction: f64| {
            let mut solver = NewtonSolver::new(
                start.len(),
                &mesh.triangles,
                rest.clone(),
                &[(p0, 0), (p0, 1), (p1, 1)],
                None,
            )
            .unwrap();
            let settings = NewtonSettings {
                chord_contraction,
                chord_min_unknowns: 0,
                ..Default::default()
            };
            let mut uv = start.clone();
            let (stop, _, energy) = solver
                .minimize(&mut uv, &density, &settings, 0, Instant::now(), &mut |_| {})
                .unwrap();
            assert_eq!(stop, StopReason::Converged);
            (uv, energy, solver.timings)
        };
        let (uv_full, e_full, full) = run(0.0);
        let (uv_chord, e_chord, chord) = run(CHORD_CONTRACTION);
        assert_eq!(full.chord_steps, 0);
        assert!(chord.chord_steps > 0);
        assert!(
            chord.factorizations < full.factorizations,
            "{} vs {}",
            chord.factorizations,
            full.factorizations
        );
        assert!(
            (e_full - e_chord).abs() <= 1e-10 * e_full,
            "{e_full} vs {e_chord}"
        );
        let diff = crate::testing::max_uv_difference(&uv_full, &uv_chord);
        assert!(diff < 1e-5, "{diff}");
        assert_eq!(crate::param::count_flipped(&uv_chord, &mesh.triangles), 0);
    }

    /// A strip of `m` quads bent into a ring open by the angle `gap`, radius 1 to 1.2:
    /// its two end edges face each other `gap` apart.
    fn open_ring(m: usize, gap: f64) -> crate::mesh::TriMesh {
        let mut positions = Vec::new();
        for i in 0..=m {
            let t = i as f64 / m as f64 * (std::f64::consts::TAU - gap);
            for r in [1.0, 1.2] {
                positions.push([r * t.cos(), r * t.sin(), 0.0]);
            }
        }
        let mut triangles = Vec::new();
        for i in 0..m as u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
        crate::mesh::TriMesh::new(positions, triangles)
    }

    #[test]
    fn barrier_pairs_are_coupled_in_the_assembled_hessian() {
        // The ring's end edges are closer than ε: the assembled matrix must be the
        // elastic one plus Σ f2 g gᵀ over the pairs (g = c ⊗ n on the unknowns),
        // computed here from the barrier alone, once the pattern holds the couplings.
        let mesh = open_ring(40, 0.02);
        let disc = Disc::new(&mesh).unwrap();
        let uv: Vec<[f64; 2]> = mesh.positions.iter().map(|p| [p[0], p[1]]).collect();
        let rest = rest_triangles(&mesh.positions, &mesh.triangles).unwrap();
        let pins = [(10, 0), (10, 1), (60, 1)];
        let n = uv.len();
        let mut plain = NewtonSolver::new(n, &mesh.triangles, rest.clone(), &pins, None).unwrap();
        let mut solver = NewtonSolver::new(n, &mesh.triangles, rest, &pins, None).unwrap();
        let barrier = BoundaryBarrier::new(disc.boundary(), &uv);
        let mut expected_pairs = Vec::new();
        barrier.for_each_pair_term(&uv, |vertices, c, n, _, f2| {
            expected_pairs.push((vertices, c, n, f2))
        });
        assert!(expected_pairs.len() >= 2, "{}", expected_pairs.len());
        solver.set_barrier(barrier);
        let density = Alpha::balanced();
        plain
            .assemble(&uv, &density, HessianKind::Projected)
            .unwrap();
        solver.couple_pairs = true;
        solver
            .assemble(&uv, &density, HessianKind::Projected)
            .unwrap();
        assert_eq!(solver.timings.pattern_rebuilds, 1);
        let unknowns = solver.dof.count();
        let x: Vec<f64> = (0..unknowns)
            .map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0)
            .collect();
        let (mut y, mut y0) = (vec![0.0; unknowns], vec![0.0; unknowns]);
        solver.system.mul_vec(&x, &mut y).unwrap();
        plain.system.mul_vec(&x, &mut y0).unwrap();
        let unknown_of = solver.dof.as_slice().to_vec();
        let dof = |v: u32, k: usize| Some(unknown_of[2 * v as usize + k]).filter(|&d| d != FIXED);
        for (vertices, c, nrm, f2) in &expected_pairs {
            // g on the unknowns: c_i n_k at coordinate k of vertex i (none where pinned).
            let g: Vec<(usize, f64)> = vertices
                .iter()
                .zip(c)
                .flat_map(|(v, ci)| nrm.iter().enumerate().map(move |(k, nk)| (*v, k, ci * nk)))
                .filter_map(|(v, k, gk)| dof(v, k).map(|d| (d as usize, gk)))
                .collect();
            let gx: f64 = g.iter().map(|&(d, gk)| gk * x[d]).sum();
            for &(d, gk) in &g {
                y0[d] += f2 * gx * gk;
            }
        }
        let scale = y0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in y.iter().zip(&y0) {
            assert!((a - b).abs() <= 1e-9 * scale, "{a} vs {b}");
        }
        // Again at the same map: the pattern holds the pairs already.
        solver
            .assemble(&uv, &density, HessianKind::Projected)
            .unwrap();
        assert_eq!(solver.timings.pattern_rebuilds, 1);
        // Uncoupled (far from the minimum): each vertex's own block only, no new pattern.
        let rest = rest_triangles(&mesh.positions, &mesh.triangles).unwrap();
        let mut uncoupled = NewtonSolver::new(n, &mesh.triangles, rest, &pins, None).unwrap();
        uncoupled.set_barrier(BoundaryBarrier::new(disc.boundary(), &uv));
        uncoupled.couple_pairs = false;
        uncoupled
            .assemble(&uv, &density, HessianKind::Projected)
            .unwrap();
        assert_eq!(uncoupled.timings.pattern_rebuilds, 0);
        let mut y1 = vec![0.0; unknowns];
        uncoupled.system.mul_vec(&x, &mut y1).unwrap();
        plain.system.mul_vec(&x, &mut y0).unwrap();
        for (vertices, c, nrm, f2) in &expected_pairs {
            for (v, ci) in vertices.iter().zip(c) {
                let own: f64 = (0..2)
                    .filter_map(|k| dof(*v, k).map(|d| nrm[k] * x[d as usize]))
                    .sum();
                for (k, nk) in nrm.iter().enumerate() {
                    if let Some(d) = dof(*v, k) {
                        y0[d as usize] += f2 * ci * ci * own * nk;
                    }
                }
            }
        }
        for (a, b) in y1.iter().zip(&y0) {
            assert!((a - b).abs() <= 1e-9 * scale, "{a} vs {b}");
        }
    }

    #[test]
    fn shared_vertex_ordering_does_not_change_the_iterates() {
        // A few projected Newton steps from a stretched planar map, with AMD on the
        // 2n − 3 system and with the expanded vertex ordering: same iterates up to rounding.
        let mesh = crate::mesh::generate::grid_disc(6);
        let rest = rest_triangles(&mesh.positions, &mesh.triangles).unwrap();
        let n = mesh.num_vertices();
        let start: Vec<[f64; 2]> = mesh
            .positions
            .iter()
            .map(|p| [p[0] * (1.0 + 0.5 * p[0]), 0.7 * p[1] + 0.1 * p[0]])
            .collect();
        let pins = [(0, 0), (0, 1), (6, 1)];
        let settings = NewtonSettings {
            max_iterations: 4,
            ..Default::default()
        };
        let ordering = VertexOrdering::of_triangles(n, &mesh.triangles).unwrap();
        let run = |ordering: Option<&VertexOrdering>| {
            let mut solver =
                NewtonSolver::new(n, &mesh.triangles, rest.clone(), &pins, ordering).unwrap();
            let mut uv = start.clone();
            let (_, iterations, energy) = solver
                .minimize(
                    &mut uv,
                    &Alpha::balanced(),
                    &settings,
                    0,
                    Instant::now(),
                    &mut |_| {},
                )
                .unwrap();
            (uv, iterations, energy)
        };
        let (a, it_a, e_a) = run(None);
        let (b, it_b, e_b) = run(Some(&ordering));
        assert_eq!(it_a, it_b);
        assert!(it_a > 0 && (e_a - e_b).abs() <= 1e-12 * e_a.abs());
        let diff = crate::testing::max_uv_difference(&a, &b);
        assert!(diff < 1e-9, "{diff}");
    }
}
