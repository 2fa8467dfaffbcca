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
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            armijo_c: 0.5,
            armijo_rho: 0.8,
            tolerance: 1e-12,
            max_iterations: 200,
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
    /// The boundary barrier of the bijective mode ([`super::barrier`]), and the value
    /// slots of every vertex's own 2×2 block (`[uu, vu, vv]`, `u32::MAX` where pinned).
    barrier: Option<(BoundaryBarrier, Vec<[u32; 3]>)>,
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

/// Relative stopping threshold with a boundary barrier: `λ²/2 ≤ 10⁻⁶·E` (the energy
/// is then within about that fraction of the minimum).
const BARRIER_RELATIVE_TOLERANCE: f64 = 1e-6;

/// Largest step tried with a boundary barrier (the contact search's reach).
const BARRIER_STEP_CAP: f64 = 16.0;

/// Armijo constant for exact-Hessian steps (see the line search).
const EXACT_ARMIJO_C: f64 = 1e-4;

/// Try the exact Hessian once the Newton decrement is below this fraction of the energy.
const EXACT_SWITCH: f64 = 1e-3;

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
        let local_dofs = |t: &[u32; 3]| -> [u32; 6] {
            std::array::from_fn(|i| dof.as_slice()[2 * t[i / 2] as usize + i % 2])
        };
        let mut entries = Vec::with_capacity(triangles.len() * 21);
        for t in triangles {
            let ld = local_dofs(t);
            for &(i, j) in &LOWER_PAIRS {
                if ld[i] != FIXED && ld[j] != FIXED {
                    entries.push((ld[i], ld[j]));
                }
            }
        }
        let t_symbolic = Instant::now();
        let ordering = match ordering {
            Some(vertices) => vertices.expand(2, &dof)?,
            None => Ordering::Amd,
        };
        let (system, entry_slots) = SpdSystem::with_ordering(n, &entries, &ordering)?;
        let symbolic_time = t_symbolic.elapsed().as_secs_f64();
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
            timings: NewtonTimings {
                symbolic: symbolic_time,
                ..Default::default()
            },
        })
    }

    /// Adds the boundary barrier `barrier` to the energy, and its contact bound to the
    /// line search (the bijective mode, [`super::barrier`]).
    pub fn set_barrier(&mut self, barrier: BoundaryBarrier) {
        let mut blocks = vec![[u32::MAX; 3]; self.direction.len()];
        // Local pairs (2k, 2k), (2k + 1, 2k), (2k + 1, 2k + 1) of corner k.
        let index = |i: usize, j: usize| LOWER_PAIRS.iter().position(|&p| p == (i, j)).unwrap();
        for (t, tri) in self.triangles.iter().enumerate() {
            for (k, &v) in tri.iter().enumerate() {
                blocks[v as usize] = [
                    self.slots[t][index(2 * k, 2 * k)],
                    self.slots[t][index(2 * k + 1, 2 * k)],
                    self.slots[t][index(2 * k + 1, 2 * k + 1)],
                ];
            }
        }
        self.barrier = Some((barrier, blocks));
    }

    /// The stopping threshold on `λ²/2`: the settings' tolerance, or with the barrier
    /// (whose Hessian is approximated, so convergence is linear near contacts) at least
    /// [`BARRIER_RELATIVE_TOLERANCE`] of the energy.
    fn tolerance(&self, settings: &NewtonSettings, energy: f64) -> f64 {
        match self.barrier {
            Some(_) => settings
                .tolerance
                .max(BARRIER_RELATIVE_TOLERANCE * energy.abs()),
            None => settings.tolerance,
        }
    }

    /// The barrier energy at `uv` (0 without a barrier).
    fn barrier_energy(&self, uv: &[[f64; 2]]) -> f64 {
        self.barrier.as_ref().map_or(0.0, |(b, _)| b.energy(uv))
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
        for it in 1..=settings.max_iterations {
            if last_step_full_exact {
                // After a full exact-Newton step the decrement has dropped quadratically:
                // test convergence with the previous factorization (a Hessian that differs
                // by O(step), so the estimate is accurate to that order) before paying
                // for a new one. Not converged: go on as usual.
                let t0 = Instant::now();
                self.assemble(uv, density, HessianKind::None);
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
            }
            let try_exact =
                it >= exact_blocked_until && decrement_prev < EXACT_SWITCH * energy.abs().max(1.0);
            let mut p = Vec::new();
            let mut solved = false;
            let mut solved_exact = false;
            if try_exact {
                let t0 = Instant::now();
                self.assemble(uv, density, HessianKind::Exact);
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
                self.assemble(uv, density, HessianKind::Projected);
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
            if !(decrement.is_finite()) || decrement <= 0.0 {
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
            if let Some((barrier, _)) = &self.barrier {
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
        }
        Ok((StopReason::IterationCap, settings.max_iterations, energy))
    }

    /// Fills the gradient and the projected Hessian values for the current `uv`.
    fn assemble<D: Density + ?Sized>(&mut self, uv: &[[f64; 2]], density: &D, kind: HessianKind) {
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
        self.gradient.iter_mut().for_each(|g| *g = 0.0);
        let with_hessian = kind != HessianKind::None;
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
        if let Some((barrier, blocks)) = &self.barrier {
            let (dof, gradient) = (&self.dof, &mut self.gradient);
            barrier.add_derivatives(
                uv,
                &mut |v, g| {
                    for (c, gc) in g.iter().enumerate() {
                        if let Some(k) = dof.get(2 * v as usize + c) {
                            gradient[k as usize] += gc;
                        }
                    }
                },
                &mut |v, h| {
                    if let Some(values) = values.as_deref_mut() {
                        for (&s, hc) in blocks[v as usize].iter().zip(h) {
                            if s != u32::MAX {
                                values[s as usize] += hc;
                            }
                        }
                    }
                },
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::Alpha;
    use crate::mesh::Disc;
    use crate::mesh::generate::bumpy_disc;
    use crate::param::element::rest_triangles;
    use crate::param::tutte::mean_value;

    #[test]
    fn convergence_is_judged_by_the_decrement_at_the_returned_map() {
        // The stopping test after a full exact step reuses the previous factorization;
        // check its verdict against a fresh factorization at the returned map.
        let mesh = bumpy_disc(10, 0.5);
        let scale = mesh.area().sqrt();
        let positions: Vec<[f64; 3]> = mesh
            .positions
            .iter()
            .map(|p| p.map(|x| x / scale))
            .collect();
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
        // The last verdict came without a factorization of its own.
        assert_eq!(
            solver.timings.factorizations,
            iterations + solver.timings.exact_failures
        );
        solver.assemble(&uv, &density, HessianKind::Exact);
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
