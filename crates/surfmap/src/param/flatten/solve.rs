//! The solve of a disc (thesis §3.1): from the start ([`super::start`]) and the warm
//! start ([`super::warm_start`]), projected Newton with flip-free line search, with
//! α-continuation (§3.1.3) and, for a bijective map, the boundary barrier (or the
//! scaffold from a crushed start); the result checked ([`super::result::result_of`]).
//!
//! [`flatten_used`] leaves out unreferenced vertices; [`flatten_disc`] solves without
//! the barrier first and again with it when the result overlaps itself; [`solve_disc`]
//! is one such solve.

use super::error::FlattenError;
use super::options::{Bijective, FlattenOptions, Start};
use super::result::{Flattening, Solved, StartMap, result_of};
use super::start::{FlattenFn, InitialMap, SharedStart, Starts, check_given_length, initial_map};
use super::warm_start::arap_warm_start;
use crate::energy::Energy;
use crate::linsolve::VertexOrdering;
use crate::mesh::{Disc, Topology, TriMesh};
use crate::param::barrier::BoundaryBarrier;
use crate::param::element::{RestTriangle, rest_triangles};
use crate::param::newton::{
    CROSSING_PERSISTENCE, IterationLog, NewtonSettings, NewtonSolver, NewtonTimings, StopReason,
};
use crate::param::protrusions::StartMaps;
use crate::param::relief::{relieve_crushed_contacts, relieve_hot_spots};
use crate::param::tutte;
use std::time::Instant;

/// Mean energy density of a mean-value start above which the bijective solve uses the
/// scaffold ([`crate::param::scaffold`]) instead of the barrier solve. Measured (balanced α,
/// isometry ≈ 2): `elephant_holes.off` cut open 2.1·10⁷ (barrier solve: 200 iterations,
/// capped); `holes.off` and `ict_neutral.obj` cut open 138 and 124 (barrier solve: 22
/// and 19 iterations; the scaffold took 28 and 38).
const SCAFFOLD_START_ENERGY: f64 = 1e4;

/// The flattening of the vertices used by a triangle; the others are put at the origin.
/// `topology`: that of `mesh`, if already derived; `flatten`: the entry point, for the
/// multilevel start.
/// `maps`: the initial maps of `mesh`, when already computed.
pub(super) fn flatten_used(
    mesh: &TriMesh,
    topology: Option<Topology>,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&IterationLog),
    flatten: FlattenFn,
    maps: Option<StartMaps>,
) -> Result<Flattening, FlattenError> {
    let (compact, old_of_new) = without_unreferenced(mesh);
    let Some(compact) = compact else {
        return flatten_disc(mesh, topology, options, progress, flatten, maps);
    };
    let mut compact_options = options.clone();
    if let Start::Given(given) = &options.start {
        check_given_length(given, mesh)?;
        compact_options.start =
            Start::Given(old_of_new.iter().map(|&v| given[v as usize]).collect());
    }
    let mut result = flatten_disc(&compact, None, &compact_options, progress, flatten, None)?;
    let mut uvs = vec![[0.0, 0.0]; mesh.positions.len()];
    for (new, &old) in old_of_new.iter().enumerate() {
        uvs[old as usize] = result.uvs[new];
    }
    result.uvs = uvs;
    Ok(result)
}

/// The flattening of a mesh whose vertices are all used (`topology`: its topology, if
/// already derived; `maps`: its initial maps, if already computed).
fn flatten_disc(
    mesh: &TriMesh,
    topology: Option<Topology>,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&IterationLog),
    flatten: FlattenFn,
    maps: Option<StartMaps>,
) -> Result<Flattening, FlattenError> {
    let clock = Instant::now();
    let disc = match topology {
        Some(topology) => Disc::with_topology(mesh, topology)?,
        None => Disc::new(mesh)?,
    };
    let solve = match options.bijective {
        Bijective::Off => Solve::Unconstrained,
        Bijective::WhenOverlapping => Solve::UnlessStartCrosses,
        Bijective::Always => Solve::Barrier,
    };
    let mut context = Context {
        mesh,
        disc: &disc,
        options,
        starts: Starts {
            multilevel: SharedStart::NotTried,
            maps,
        },
        flatten,
        ordering: None,
        resume: None,
    };
    let first = match solve_disc(&mut context, progress, solve)? {
        SolveOutcome::Map(first) if first.boundary_crossings == 0 => return Ok(*first),
        SolveOutcome::Map(first) if options.bijective != Bijective::WhenOverlapping => {
            return Ok(*first);
        }
        SolveOutcome::Map(first) => first.time_start + first.time_newton,
        SolveOutcome::StartCrosses { time } => time,
    };
    // The unconstrained map (or its start) overlaps itself: solve with the boundary
    // barrier.
    let SolveOutcome::Map(second) = solve_disc(&mut context, progress, Solve::Barrier)? else {
        unreachable!("a barrier solve always returns a map")
    };
    let mut second = *second;
    second.time_start += first;
    second.time_total = clock.elapsed().as_secs_f64();
    Ok(second)
}

/// Which solve [`solve_disc`] does.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Solve {
    /// Without the boundary barrier.
    Unconstrained,
    /// Without the barrier, unless the start map (not a given one) already crosses
    /// itself: then nothing ([`SolveOutcome::StartCrosses`]), for a barrier solve
    /// instead. Measured on every mesh in `../shared/data` (BENCHMARKS.md, "Hard
    /// discs"): each of the nine starts that crossed (elephant_holes: 92 crossing pairs;
    /// beetle, holes and six ICT faces opened with seams: 1–4) led to an overlapping
    /// minimum, so the unconstrained solve from them (elephant: 64 iterations) was
    /// spent for nothing.
    UnlessStartCrosses,
    /// With the boundary barrier, from a crossing-free start.
    Barrier,
}

/// What [`solve_disc`] returned.
enum SolveOutcome {
    Map(Box<Flattening>),
    /// [`Solve::UnlessStartCrosses`] gave up after `time` seconds (building the start).
    StartCrosses {
        time: f64,
    },
}

/// What the solves of one disc share: the mesh, its disc, the options, the multilevel
/// start (computed by the first solve that needs it), the entry point (for it) and the
/// initial maps when they were computed before the solve.
struct Context<'a> {
    mesh: &'a TriMesh,
    disc: &'a Disc<'a>,
    options: &'a FlattenOptions,
    starts: Starts,
    flatten: FlattenFn,
    /// The fill-reducing vertex ordering, once a solve computed it.
    ordering: Option<VertexOrdering>,
    /// The start of the barrier solve when the unconstrained solve found one
    /// ([`Resume`]).
    resume: Option<Resume>,
}

/// The relative stopping threshold of a barrier solve from a [`Resume`] (the default,
/// `BARRIER_RELATIVE_TOLERANCE` in `param::newton`, is 10⁻⁴). The energy of these
/// discs is 8–17 times an isometry's (the tubes cannot flatten), and the decrement of
/// the projected Hessian underestimates what is left there: measured on the tube discs
/// `octopus:6,8,30,1` / `8,6,20,1` / `8,8,20,1` (docs/bench/hard_discs.md), at 10⁻⁴ the
/// resumed solve stops 0.05 % / 0.05 % / 0.005 % above the minimum it converges to at
/// 10⁻⁹ (the one the solve from the crushed start reaches), at 10⁻⁵ within 0.001 %, for
/// 8 / 4 / 1 more iterations. The solve from the crushed start keeps 10⁻⁴: it reaches
/// the tail already slowed to steps that the decrement measures better.
const RESUMED_BARRIER_RELATIVE_TOLERANCE: f64 = 1e-5;

/// The last crossing-free iterate of an unconstrained solve from a crushed start that
/// ended because its boundary crossed itself (normalized and pinned as that solve's
/// iterates are), and the start map it came from: the barrier solve starts from it
/// instead of the crushed start. The crushed phase (the energy falling by a factor 2–4
/// per Newton step, each step cut by the first flip) is then taken once, not once per
/// solve.
struct Resume {
    uv: Vec<[f64; 2]>,
    map: StartMap,
    lscm_flipped: usize,
    /// The crushed start (scaled and pinned, before any warm start): the barrier's
    /// reach and weight are set from its boundary, as for a barrier solve from it.
    crushed: Vec<[f64; 2]>,
}

/// One solve of [`flatten_disc`]: with the boundary barrier for [`Solve::Barrier`]
/// (from a crossing-free start: the multilevel one when it is, else LSCM or mean-value
/// coordinates, with ARAP warm-start steps from a mean-value start kept short of any
/// boundary contact).
fn solve_disc(
    context: &mut Context<'_>,
    progress: &mut dyn FnMut(&IterationLog),
    solve: Solve,
) -> Result<SolveOutcome, FlattenError> {
    let clock = Instant::now();
    let (mesh, disc, options) = (context.mesh, context.disc, context.options);
    let barrier = solve == Solve::Barrier;
    // Scale normalization: work on the surface scaled to unit area, so energies and
    // tolerances are scale-free; the UVs are scaled back at the end.
    let (positions, scale) = mesh.unit_area_positions();
    let rest = rest_triangles(&positions, &mesh.triangles)?;
    let boundary = disc.boundary();
    // Initial map (§3.1.1), checked: any flipped or degenerate triangle → fallback.
    // The one fill-reducing vertex ordering of the ARAP and Newton systems depends on
    // the connectivity only, so it is computed on the second core while the start is
    // built (nested dissection takes seconds on a large mesh: 2.5–4 s at 0.5M vertices).
    let (start, ordering) = rayon::join(
        || {
            initial_map(
                mesh,
                disc,
                &positions,
                options,
                barrier,
                &mut context.starts,
                context.flatten,
            )
        },
        || match context.ordering.take() {
            Some(ordering) => Ok(ordering),
            None => VertexOrdering::fill_reducing(mesh.positions.len(), &mesh.triangles),
        },
    );
    // Kept in the context for a second solve of the same disc.
    let vertex_ordering = &*context.ordering.insert(ordering?);
    let mut start = start?;
    start.check(mesh, options)?;
    let resume = context.resume.take().filter(|_| barrier);
    if let Some(resume) = &resume {
        start.uv.clone_from(&resume.uv);
        (start.map, start.lscm_flipped) = (resume.map, resume.lscm_flipped);
    }
    if solve == Solve::UnlessStartCrosses && start.leads_to_overlap(boundary) {
        return Ok(SolveOutcome::StartCrosses {
            time: clock.elapsed().as_secs_f64(),
        });
    }
    let (p0, p1) = if resume.is_some() {
        // In normalized units already.
        start.pin(boundary)
    } else {
        start.scale_and_pin(mesh, boundary, scale)
    };
    // What the barrier is measured on: the crushed start of a resumed solve, else this
    // start (kept for a resume when an unconstrained solve crosses).
    let barrier_reference = match (&resume, solve) {
        (Some(resume), _) => Some(resume.crushed.clone()),
        (None, Solve::UnlessStartCrosses) => Some(start.uv.clone()),
        _ => None,
    };
    // A multilevel start is already close to the minimum: no warm start, and no
    // continuation (the coarse level did both).
    let objective = if start.map == StartMap::Multilevel {
        options.energy.without_continuation()
    } else {
        options.energy
    };
    let pins = [(p0, 0), (p0, 1), (p1, 1)];
    let solving = Solving {
        mesh,
        boundary,
        rest,
        objective: &objective,
        newton: &options.newton,
        pins: &pins,
        scale,
        clock,
        barrier,
        resumed: resume.is_some(),
        barrier_reference,
    };
    if resume.is_none()
        && let Some(map) = solving.scaffold_if_crushed(&mut start, progress)?
    {
        return Ok(SolveOutcome::Map(Box::new(map)));
    }
    // A mean-value start for the barrier solve gets its ears opened before the warm
    // start, whose steps an ear flat on the circle would stop at once (after the
    // crushed-start test above: the scaffold is measured from the plain mean-value map).
    // Measured: ICT id002 opened with seams 29 → 16 barrier iterations, id000 12 → 11,
    // holes opened 14 → 13 (BENCHMARKS.md, "Hard discs").
    if barrier && start.map == StartMap::MeanValue && resume.is_none() {
        tutte::open_ears(&positions, disc, &mut start.uv);
    }
    // ARAP warm start: only as search directions, accepted when flip-free and when they
    // lower the energy being minimized first (see `arap`). With the barrier, only a
    // mean-value start (a circle, far from the minimum) is warm started (measured: from
    // LSCM it costs Newton iterations), and no warm-start step may bring the boundary
    // into contact.
    let mut warm_start_iterations = 0;
    if options.warm_start
        && resume.is_none()
        && start.map != StartMap::Multilevel
        && (!barrier || start.map == StartMap::MeanValue)
    {
        warm_start_iterations = arap_warm_start(
            &mut start.uv,
            mesh,
            &solving.rest,
            barrier.then_some(boundary),
            &objective,
            (p0, p1),
            vertex_ordering,
        )?;
    }
    if start.map == StartMap::Multilevel && resume.is_none() {
        // Squeezed triangles of the re-insertion (camelhead subdivided 2×: 22 → 9
        // full-solve iterations, BENCHMARKS.md "Scale"). Where the map must not overlap,
        // the relief keeps it from crossing (and is skipped for a start that already
        // crosses: its unconstrained solve says so).
        let guard = options.bijective != Bijective::Off;
        if !guard || crate::measure::overlap::boundary_crossings(&start.uv, boundary) == 0 {
            start.relieve(
                |uv| {
                    relieve_hot_spots(
                        uv,
                        &mesh.triangles,
                        &solving.rest,
                        guard.then_some(boundary),
                        &objective,
                        &options.newton,
                    )
                },
                |report, relief| report.hot_spots = Some(relief),
            );
        }
    }
    if barrier && start.map == StartMap::Multilevel {
        // Crushed boundary contacts (a coarse slit's tip, its re-inserted sides a
        // sliver apart) opened before the barrier solve (the ICT face id000 opened with
        // seams: 17 → 5 barrier iterations, BENCHMARKS.md "Hard discs").
        start.relieve(
            |uv| {
                relieve_crushed_contacts(
                    uv,
                    &mesh.triangles,
                    &solving.rest,
                    boundary,
                    &objective,
                    &options.newton,
                )
            },
            |report, relief| report.relief = Some(relief),
        );
    }
    let (outcome, resume) = solving.newton(
        start,
        solve,
        warm_start_iterations,
        vertex_ordering,
        progress,
    )?;
    context.resume = resume;
    Ok(outcome)
}

/// A solve from its start on: what the scaffold and Newton stages read.
struct Solving<'a> {
    mesh: &'a TriMesh,
    boundary: &'a [u32],
    /// Rest triangles of the surface scaled to unit area.
    rest: Vec<RestTriangle>,
    objective: &'a Energy,
    newton: &'a NewtonSettings,
    /// Pinned coordinates: `(vertex, 0 for u / 1 for v)`.
    pins: &'a [(u32, usize); 3],
    /// Back to the mesh's units.
    scale: f64,
    /// Started with the solve.
    clock: Instant,
    barrier: bool,
    /// Whether the start is a [`Resume`].
    resumed: bool,
    /// The map whose boundary sets the barrier's reach and weight (`None`: the start).
    barrier_reference: Option<Vec<[f64; 2]>>,
}

impl Solving<'_> {
    /// With the barrier from a crushed mean-value start (energy above
    /// [`SCAFFOLD_START_ENERGY`], no continuation): the scaffold iterations (SCAF with
    /// progressive reference shapes, [`crate::param::scaffold`]) instead of the barrier
    /// solve, whose steps such a start cuts short at the first flip or contact. `None`
    /// when the start is not crushed or no scaffold can be built around it.
    fn scaffold_if_crushed(
        &self,
        start: &mut InitialMap,
        progress: &mut dyn FnMut(&IterationLog),
    ) -> Result<Option<Flattening>, FlattenError> {
        let mesh = self.mesh;
        let crushed = self.barrier
            && start.map == StartMap::MeanValue
            && self.objective.continuation_start().is_none()
            && NewtonSolver::energy_of(&self.rest, &mesh.triangles)(&start.uv, self.objective)
                > SCAFFOLD_START_ENERGY;
        if !crushed {
            return Ok(None);
        }
        let time_start = self.clock.elapsed().as_secs_f64();
        let mut log = Vec::new();
        let stats = crate::param::scaffold::solve(
            &mut start.uv,
            &mesh.triangles,
            &self.rest,
            self.boundary,
            self.pins,
            self.objective,
            self.clock,
            &mut |entry| {
                progress(&entry);
                log.push(entry);
            },
        )?;
        let Some(stats) = stats else {
            return Ok(None);
        };
        let stop = if stats.stalled {
            StopReason::Stalled
        } else {
            StopReason::IterationCap
        };
        let time_newton = self.clock.elapsed().as_secs_f64() - time_start;
        let solved = Solved {
            start: start.map,
            lscm_flipped: start.lscm_flipped,
            warm_start_iterations: 0,
            iterations: stats.iterations,
            stop,
            energy: stats.energy,
            barrier: self.barrier,
            continuation: Vec::new(),
            log,
            time_start,
            time_newton,
            newton_timings: NewtonTimings::default(),
            multilevel: start.multilevel.take(),
            barrier_resumed: false,
        };
        let map = result_of(
            &start.uv,
            mesh,
            self.boundary,
            self.scale,
            self.clock,
            solved,
        )?;
        Ok(Some(map))
    }

    /// Projected Newton from `start` (with the continuation, if any), and the result.
    fn newton(
        self,
        start: InitialMap,
        solve: Solve,
        warm_start_iterations: usize,
        vertex_ordering: &VertexOrdering,
        progress: &mut dyn FnMut(&IterationLog),
    ) -> Result<(SolveOutcome, Option<Resume>), FlattenError> {
        let InitialMap {
            mut uv,
            map,
            lscm_flipped,
            multilevel,
        } = start;
        let time_start = self.clock.elapsed().as_secs_f64();
        let mut solver = NewtonSolver::new(
            self.mesh.positions.len(),
            &self.mesh.triangles,
            self.rest,
            self.pins,
            Some(vertex_ordering),
        )?;
        if self.barrier {
            solver.set_barrier(
                BoundaryBarrier::new(
                    self.boundary,
                    self.barrier_reference.as_deref().unwrap_or(&uv),
                )
                .with_faces(&self.mesh.triangles),
            );
            if self.resumed {
                solver.set_barrier_relative_tolerance(RESUMED_BARRIER_RELATIVE_TOLERANCE);
            }
        } else if solve == Solve::UnlessStartCrosses {
            // The bijective mode solves again with the barrier when the result overlaps
            // itself; an iterate whose boundary crosses already says it will
            // (BENCHMARKS.md, "Hard discs"), so the rest of this solve would be spent for
            // nothing. From a multilevel start (whose coarse level is solved: near the
            // minimum) one crossing iterate says so: on the ICT faces opened with seams
            // every such crossing lasted to the end (measured, BENCHMARKS.md); from the
            // other starts, transient crossings happen ([`CROSSING_PERSISTENCE`]).
            let persistence = if map == StartMap::Multilevel {
                1
            } else {
                CROSSING_PERSISTENCE
            };
            solver.stop_when_boundary_crosses(self.boundary.to_vec(), persistence);
        }
        let mut log = Vec::new();
        let mut record = |entry: IterationLog| {
            progress(&entry);
            log.push(entry);
        };
        let minimized = minimize(
            &mut solver,
            &mut uv,
            self.objective,
            self.newton,
            self.clock,
            &mut record,
        )?;
        let time_newton = self.clock.elapsed().as_secs_f64() - time_start;
        let resume = (minimized.progressive > 0 && minimized.stop == StopReason::BoundaryCrossed)
            .then(|| solver.take_last_uncrossed())
            .flatten()
            .zip(self.barrier_reference)
            .map(|(uv, crushed)| Resume {
                uv,
                map,
                lscm_flipped,
                crushed,
            });
        let solved = Solved {
            start: map,
            lscm_flipped,
            warm_start_iterations,
            iterations: minimized.iterations,
            stop: minimized.stop,
            energy: minimized.energy,
            barrier: self.barrier,
            continuation: minimized.continuation,
            log,
            time_start,
            time_newton,
            newton_timings: solver.timings,
            multilevel,
            barrier_resumed: self.resumed,
        };
        let map = result_of(
            &uv,
            self.mesh,
            self.boundary,
            self.scale,
            self.clock,
            solved,
        )?;
        Ok((SolveOutcome::Map(Box::new(map)), resume))
    }
}

/// What [`minimize`] did.
struct Minimized {
    stop: StopReason,
    energy: f64,
    /// Newton iterations, all stages together.
    iterations: usize,
    /// α values of the continuation stages solved (empty without continuation).
    continuation: Vec<[f64; 3]>,
    /// Progressive iterations among them (0: the start was not crushed).
    progressive: usize,
}

/// Minimizes `objective` from `uv` with `solver`: directly, or for Litke's energy with a
/// continuation start by continuation (§3.1.3): θ from 0 to 1, halving the step when a
/// stage locks. Stage 0 only prepares a start: a locked or capped stage 0 is still a
/// valid (flip-free) start for the next stage.
fn minimize(
    solver: &mut NewtonSolver<'_>,
    uv: &mut Vec<[f64; 2]>,
    objective: &Energy,
    settings: &NewtonSettings,
    clock: Instant,
    record: &mut dyn FnMut(IterationLog),
) -> Result<Minimized, FlattenError> {
    let Energy::Litke {
        alpha: target,
        from: Some(from),
    } = objective
    else {
        let before = progressive(solver, uv, objective, settings, clock, record)?;
        let (stop, iterations, energy) =
            solver.minimize(uv, objective, settings, 0, clock, record)?;
        return Ok(Minimized {
            stop,
            energy,
            iterations: before + iterations,
            continuation: Vec::new(),
            progressive: before,
        });
    };
    let (stop0, it0, e0) = solver.minimize(uv, from, settings, 0, clock, record)?;
    let mut iterations = it0;
    let mut continuation = vec![from.alphas()];
    let (mut theta, mut dtheta) = (0.0f64, 1.0f64);
    let mut stage = 1;
    let mut last = (StopReason::Converged, f64::NAN);
    if stop0 == StopReason::BoundaryCrossed {
        (theta, last) = (1.0, (stop0, e0));
    }
    while theta < 1.0 {
        let next = (theta + dtheta).min(1.0);
        let alpha = from.blend(target, next);
        let mut trial = uv.clone();
        let (stop, it, e) = solver.minimize(&mut trial, &alpha, settings, stage, clock, record)?;
        iterations += it;
        stage += 1;
        if stop == StopReason::BoundaryCrossed {
            *uv = trial;
            last = (stop, e);
            break;
        }
        if stop == StopReason::Locked && dtheta > 1.0 / 64.0 {
            dtheta *= 0.5;
            continue;
        }
        *uv = trial;
        theta = next;
        continuation.push(alpha.alphas());
        last = (stop, e);
        dtheta = (2.0 * dtheta).min(1.0);
    }
    Ok(Minimized {
        stop: last.0,
        energy: last.1,
        iterations,
        continuation,
        progressive: 0,
    })
}

/// A start is crushed, for [`progressive`], when some triangle's map distorts by more
/// than `e^CRUSHED_LOG` (`max_i |ln σ_i| > CRUSHED_LOG`, σ: singular values of its
/// Jacobian). Measured (docs/bench/hard_discs.md): at 4 the starts of camelhead,
/// lionhead, cowhead, mannequin_devil, face_bff, bunny and ict_neutral opened with seams
/// count as crushed (outputs changed, energies the same to 10⁻⁶ or 4·10⁻⁵ lower), at 6
/// those of cowhead, mannequin_devil and face_bff; at 8 none of the shared meshes, while
/// the generated discs with thin tubes
/// ([`crate::mesh::generate::octopus_disc`]) that need 75–110 iterations still do.
const CRUSHED_LOG: f64 = 8.0;

/// Bound on `|ln σ_i|` of the map relative to the progressive reference shapes
/// (measured on the tube discs: 1 and 3 take 1–52 % more iterations than 2).
const PROGRESSIVE_MAX_LOG: f64 = 2.0;

/// Progressive iterations at most before plain Newton takes over.
const PROGRESSIVE_MAX_ITERATIONS: usize = 60;

/// Progressive parameterization (Liu, Ye, Wang, Liu 2018, "Progressive
/// parameterizations", §4) for a crushed start (some triangle distorted beyond
/// `e^CRUSHED_LOG`: a conformal map shrinks thin protrusions exponentially along them):
/// each iteration replaces every triangle's rest shape by its reference
/// ([`crate::param::scaffold::reference_triangle`]: the rest shape deformed by `S^θ`,
/// `J = R S`, with the least `θ` that keeps the map relative to it within
/// `e^{±PROGRESSIVE_MAX_LOG}`), and takes one Newton step on that mild energy (flip-free
/// line search as usual, on the barrier too where there is one). It goes on while the
/// map is crushed, and ends when no triangle is (the test that started it), when a step
/// would raise the true energy (the surface's, without the barrier; the step is undone),
/// or after [`PROGRESSIVE_MAX_ITERATIONS`]; plain Newton goes on from there. Without it,
/// each Newton step on the true energy is cut by the first flip to 0.1–0.5 and grows a
/// crushed triangle by a constant factor, so the iterations grow with the logarithm of
/// the crush. (It used to end also once a step left more than half of the true energy:
/// where a flip cut the second step short, that handed plain Newton a map still crushed,
/// energy 5·10¹³ against 10⁴ once no triangle is, and 60–89 iterations of de-crushing;
/// docs/bench/hard_discs.md.) Returns the iterations taken; the log gets one entry per
/// iteration with the true energy.
fn progressive(
    solver: &mut NewtonSolver<'_>,
    uv: &mut [[f64; 2]],
    objective: &Energy,
    settings: &NewtonSettings,
    clock: Instant,
    record: &mut dyn FnMut(IterationLog),
) -> Result<usize, FlattenError> {
    use crate::param::scaffold::reference_triangle;
    let mut rest = Vec::new();
    solver.swap_rest(&mut rest);
    let triangles = solver.triangles();
    if largest_log_distortion(triangles, &rest, uv) <= CRUSHED_LOG {
        solver.swap_rest(&mut rest);
        return Ok(0);
    }
    let one_step = NewtonSettings {
        max_iterations: 1,
        ..*settings
    };
    let mut iterations = 0;
    let mut references = rest.clone();
    solver.swap_rest(&mut rest);
    let mut energy = solver.energy(uv, objective);
    solver.swap_rest(&mut rest);
    let mut previous = uv.to_vec();
    while iterations < PROGRESSIVE_MAX_ITERATIONS {
        // The map is still crushed here, so some triangle is beyond the references' bound.
        for ((reference, r), t) in references.iter_mut().zip(&rest).zip(triangles) {
            let corners = t.map(|v| uv[v as usize]);
            *reference = reference_triangle(r, &corners, PROGRESSIVE_MAX_LOG).unwrap_or(*r);
        }
        previous.copy_from_slice(uv);
        solver.swap_rest(&mut references);
        let mut last = None;
        let stepped = solver.minimize(uv, objective, &one_step, 0, clock, &mut |entry| {
            if entry.iteration > 0 {
                last = Some(entry);
            }
        });
        solver.swap_rest(&mut references);
        let (_, steps, _) = stepped?;
        if steps == 0 {
            break;
        }
        solver.swap_rest(&mut rest);
        let e = solver.energy(uv, objective);
        solver.swap_rest(&mut rest);
        if e.is_nan() || e >= energy {
            // The references now lead away from the true minimum: back to the last
            // iterate, plain Newton from there.
            uv.copy_from_slice(&previous);
            break;
        }
        iterations += 1;
        if let Some(mut entry) = last {
            entry.iteration = iterations;
            entry.energy = e;
            record(entry);
        }
        energy = e;
        if largest_log_distortion(triangles, &rest, uv) <= CRUSHED_LOG {
            break;
        }
    }
    solver.swap_rest(&mut rest);
    Ok(iterations)
}

/// `max |ln σ_i|` over the triangles' maps from their rest shapes (σ: the singular values
/// of the Jacobian; infinite where one is degenerate or flipped).
fn largest_log_distortion(
    triangles: &[[u32; 3]],
    rest: &[crate::param::element::RestTriangle],
    uv: &[[f64; 2]],
) -> f64 {
    triangles
        .iter()
        .zip(rest)
        .map(|(t, r)| {
            let j = crate::param::element::jacobian(r, &t.map(|v| uv[v as usize]));
            let (s1, s2) = crate::measure::jacobian::signed_singular_values(j);
            s1.ln().abs().max(s2.ln().abs())
        })
        .fold(
            0.0f64,
            |a, b| if b.is_nan() { f64::INFINITY } else { a.max(b) },
        )
}

/// The mesh without unreferenced vertices (`None` when all are used) and, for each
/// kept vertex, its old index.
fn without_unreferenced(mesh: &TriMesh) -> (Option<TriMesh>, Vec<u32>) {
    let mut used = vec![false; mesh.positions.len()];
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    if used.iter().all(|&u| u) {
        return (None, Vec::new());
    }
    let old_of_new: Vec<u32> = (0..used.len() as u32)
        .filter(|&v| used[v as usize])
        .collect();
    let (compact, _) = crate::mesh::repair::drop_unreferenced(mesh);
    (Some(compact), old_of_new)
}
