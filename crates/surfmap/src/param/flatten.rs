//! The one-call flattening: checks the input is a disc, computes the initial map
//! (free-boundary conformal, with an injective fallback), normalizes scale, runs
//! projected Newton (with optional α-continuation), verifies the result has no
//! flipped triangle, and returns UVs in the mesh's own units.

use super::arap::ArapStep;
use super::density::{EnergyKind, Litke};
use super::element::{RestTriangleError, rest_triangles};
use super::flip_free::max_flip_free_step;
use super::newton::{IterationLog, NewtonSettings, NewtonSolver, NewtonTimings, StopReason};
use super::{InitialMapError, count_flipped, lscm, signed_uv_area, tutte};
use crate::linsolve::{SolveError, VertexOrdering};
use crate::mesh::validate::{Defect, validate};
use crate::mesh::{Topology, TriMesh};
use serde::Serialize;
use std::time::Instant;

/// Which initial map to use (thesis §3.1.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StartChoice {
    /// LSCM, falling back to mean-value coordinates when LSCM flips a triangle.
    #[default]
    Auto,
    Lscm,
    MeanValue,
}

/// The initial map that was actually used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StartMap {
    /// Free-boundary least-squares conformal map.
    Lscm,
    /// Mean-value coordinates onto a circle (injective by construction), used because
    /// LSCM flipped or degenerated `lscm_flipped` triangles.
    MeanValue,
    /// The caller's map ([`FlattenOptions::initial_uv`]).
    Given,
    /// The flattening of a decimated copy, refined vertex by vertex
    /// ([`super::multilevel`]; details in [`Flattening::multilevel`]).
    Multilevel,
}

/// When to use the multilevel start ([`super::multilevel`]): flatten a decimated copy
/// (about `coarse_vertices` vertices), re-insert the removed vertices, then run Newton
/// on the full mesh from there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MultilevelOptions {
    /// Meshes with at least this many faces use it (`usize::MAX`: never, `0`: always).
    pub min_faces: usize,
    /// Vertices of the coarse copy; `None`: [`MultilevelOptions::coarse_size`].
    pub coarse_vertices: Option<usize>,
    /// Local Newton steps per re-inserted vertex.
    pub polish_steps: usize,
    /// Relaxation sweeps over the full mesh after the re-insertion.
    pub sweeps: usize,
}

impl Default for MultilevelOptions {
    fn default() -> Self {
        Self {
            min_faces: MULTILEVEL_MIN_FACES,
            coarse_vertices: None,
            polish_steps: super::multilevel::DEFAULT_POLISH_STEPS,
            sweeps: super::multilevel::DEFAULT_SWEEPS,
        }
    }
}

impl MultilevelOptions {
    /// The coarse size for a mesh of `vertices` vertices: the given one, or by default
    /// 1/20 of the mesh, between 500 and 20 000 vertices.
    pub fn coarse_size(&self, vertices: usize) -> usize {
        self.coarse_vertices.unwrap_or((vertices / 20).clamp(
            MULTILEVEL_MIN_COARSE_VERTICES,
            MULTILEVEL_MAX_COARSE_VERTICES,
        ))
    }

    /// Never use the multilevel start.
    pub fn off() -> Self {
        Self {
            min_faces: usize::MAX,
            ..Self::default()
        }
    }
}

/// Default size from which the multilevel start is used (measured in BENCHMARKS.md:
/// from ~15k faces it needs fewer full-size Newton iterations than the start map), and
/// the bounds of the default coarse size.
pub const MULTILEVEL_MIN_FACES: usize = 15_000;
pub const MULTILEVEL_MIN_COARSE_VERTICES: usize = 500;
pub const MULTILEVEL_MAX_COARSE_VERTICES: usize = 20_000;

/// What the multilevel start did (or why it was abandoned).
#[derive(Clone, Debug, Default, Serialize)]
pub struct MultilevelReport {
    pub coarse_vertices: usize,
    pub coarse_faces: usize,
    /// Newton iterations on the coarse mesh.
    pub coarse_iterations: usize,
    /// α values of the continuation stages solved on the coarse mesh (with
    /// `from_alpha`; the full mesh then goes straight to the target α).
    pub coarse_continuation: Vec<[f64; 3]>,
    /// Vertices re-inserted, of them placed at their star's kernel centroid, and local
    /// Newton steps taken.
    pub prolongation: super::multilevel::ProlongationStats,
    /// Seconds: decimation, coarse flattening, re-insertion.
    pub time_decimate: f64,
    pub time_coarse: f64,
    pub time_prolongate: f64,
    /// Set when the multilevel start failed and the single-level start was used instead.
    pub abandoned: Option<String>,
}

/// Options of [`flatten`].
#[derive(Clone, Debug)]
pub struct FlattenOptions {
    /// The energy density to minimize (default: Litke's, balanced α).
    pub energy: EnergyKind,
    /// Continuation (§3.1.3): first minimize Litke's energy at this α, then move to
    /// `energy`'s α in steps (Litke energy only).
    pub from_alpha: Option<Litke>,
    pub start: StartChoice,
    pub newton: NewtonSettings,
    /// Move the start map toward an isometry with a few ARAP local/global steps before
    /// Newton (each one only accepted if flip-free and energy-decreasing).
    pub warm_start: bool,
    /// Start from this map (one UV per vertex in the mesh's length units, as
    /// [`Flattening::uvs`], no flipped triangle)
    /// instead of computing one; `start` is then ignored.
    pub initial_uv: Option<Vec<[f64; 2]>>,
    /// Multilevel start for large meshes (used when no `initial_uv` is given).
    pub multilevel: MultilevelOptions,
}

impl Default for FlattenOptions {
    fn default() -> Self {
        Self {
            energy: EnergyKind::Litke(Litke::balanced()),
            from_alpha: None,
            start: StartChoice::Auto,
            newton: NewtonSettings::default(),
            warm_start: true,
            initial_uv: None,
            multilevel: MultilevelOptions::default(),
        }
    }
}

/// Result of a flattening.
#[derive(Clone, Debug, Serialize)]
pub struct Flattening {
    /// One UV per vertex, in the mesh's length units (an isometry keeps lengths).
    pub uvs: Vec<[f64; 2]>,
    pub start: StartMap,
    /// Triangles LSCM flipped or degenerated (0 when LSCM was used).
    pub lscm_flipped: usize,
    /// ARAP warm-start steps accepted before Newton.
    pub warm_start_iterations: usize,
    /// Newton iterations, all stages together.
    pub iterations: usize,
    pub converged: bool,
    pub stop_reason: StopReason,
    /// Final energy per unit 3D area (mean density).
    pub energy: f64,
    /// Flipped or degenerate triangles in the output, counted on the output: always 0
    /// for a returned flattening (a non-zero count is an error instead).
    pub flipped_triangles: usize,
    /// α values of the continuation stages actually solved (empty without continuation).
    pub continuation: Vec<[f64; 3]>,
    pub log: Vec<IterationLog>,
    /// Seconds: initial map, Newton (all stages), total.
    pub time_start: f64,
    pub time_newton: f64,
    pub time_total: f64,
    /// Newton time by phase.
    pub newton_timings: NewtonTimings,
    /// The multilevel start, when it was tried.
    pub multilevel: Option<MultilevelReport>,
}

impl Flattening {
    /// The start map for people: `lscm`, `mean-value (LSCM flipped N)`, `given` or
    /// `multilevel (N coarse vertices)`.
    pub fn start_description(&self) -> String {
        match self.start {
            StartMap::Lscm => "lscm".to_string(),
            StartMap::MeanValue => format!("mean-value (LSCM flipped {})", self.lscm_flipped),
            StartMap::Given => "given".to_string(),
            StartMap::Multilevel => match &self.multilevel {
                Some(m) => format!("multilevel ({} coarse vertices)", m.coarse_vertices),
                None => "multilevel".to_string(),
            },
        }
    }
}

/// Why a flattening failed.
#[derive(Debug, thiserror::Error)]
pub enum FlattenError {
    #[error("the mesh cannot be flattened as a disc:\n{}", .0.iter().map(|d| format!("  - {}", d.message)).collect::<Vec<_>>().join("\n"))]
    NotADisc(Vec<Defect>),
    #[error("{0}; run with --drop-degenerate or fix the mesh")]
    Degenerate(#[from] RestTriangleError),
    #[error("linear solve failed: {0}")]
    Solve(#[from] SolveError),
    #[error("triangle {triangle} uses vertex {vertex}, but the mesh has {vertices} vertices")]
    InvalidIndex {
        triangle: usize,
        vertex: u32,
        vertices: usize,
    },
    #[error(
        "continuation (--from-alpha) blends Litke α values; it needs the Litke energy as the target"
    )]
    ContinuationNeedsLitke,
    #[error("initial map: {0}")]
    InitialMap(#[from] InitialMapError),
    #[error(
        "both initial maps flipped triangles (LSCM: {lscm}, mean-value: {mean_value}); the mesh geometry is probably broken (non-finite or coincident vertices)"
    )]
    NoAdmissibleStart { lscm: usize, mean_value: usize },
    #[error(
        "the LSCM start flips or degenerates {0} triangles; use --start auto (falls back to mean-value coordinates, injective by construction)"
    )]
    LscmFlipped(usize),
    #[error("the given initial map has {uvs} UVs, but the mesh has {vertices} vertices")]
    GivenStartLength { uvs: usize, vertices: usize },
    #[error(
        "the given initial map flips or degenerates {0} triangles; a start map must be injective"
    )]
    GivenStartFlipped(usize),
    #[error("internal error: the result has {0} flipped triangles; please report this mesh")]
    FlippedResult(usize),
}

/// Flattens a disc-topology mesh. See the module docs.
pub fn flatten(mesh: &TriMesh, options: &FlattenOptions) -> Result<Flattening, FlattenError> {
    flatten_with_progress(mesh, options, &mut |_| {})
}

/// [`flatten`] with a callback receiving every iteration's log entry as it happens
/// (for progress bars).
pub fn flatten_with_progress(
    mesh: &TriMesh,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&IterationLog),
) -> Result<Flattening, FlattenError> {
    let clock = Instant::now();
    if let Some((t, k)) = mesh.first_invalid_index() {
        return Err(FlattenError::InvalidIndex {
            triangle: t,
            vertex: mesh.triangles[t][k],
            vertices: mesh.positions.len(),
        });
    }
    if options.from_alpha.is_some() && !matches!(options.energy, EnergyKind::Litke(_)) {
        return Err(FlattenError::ContinuationNeedsLitke);
    }
    // Vertices used by no face get no UV from the solve: flatten the used part and
    // put them at the origin afterwards.
    let (compact, old_of_new) = without_unreferenced(mesh);
    if let Some(compact) = compact {
        let mut compact_options = options.clone();
        if let Some(given) = &options.initial_uv {
            check_given_length(given, mesh)?;
            compact_options.initial_uv =
                Some(old_of_new.iter().map(|&v| given[v as usize]).collect());
        }
        let mut result = flatten_with_progress(&compact, &compact_options, progress)?;
        let mut uvs = vec![[0.0, 0.0]; mesh.positions.len()];
        for (new, &old) in old_of_new.iter().enumerate() {
            uvs[old as usize] = result.uvs[new];
        }
        result.uvs = uvs;
        return Ok(result);
    }
    let topo = Topology::new(mesh);
    if !topo.is_disc()
        || !topo.inconsistent_edges.is_empty()
        || mesh
            .positions
            .iter()
            .any(|p| p.iter().any(|x| !x.is_finite()))
    {
        let defects: Vec<Defect> = validate(mesh, &topo)
            .into_iter()
            .filter(|d| d.blocks_flattening)
            .collect();
        if !defects.is_empty() || !topo.is_disc() {
            return Err(FlattenError::NotADisc(defects));
        }
    }
    // Scale normalization: work on the surface scaled to unit area, so energies and
    // tolerances are scale-free; the UVs are scaled back at the end.
    let area = mesh.area();
    let scale = area.sqrt();
    let positions: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .map(|p| p.map(|x| x / scale))
        .collect();
    let rest = rest_triangles(&positions, &mesh.triangles)?;
    let boundary = &topo.boundary_loops[0].vertices;

    // Initial map (§3.1.1), checked: any flipped or degenerate triangle → fallback.
    let admissible = |uv: &mut Vec<[f64; 2]>| -> usize {
        // A reflected map is as good as any: mirror if most triangles are negative.
        let negative = mesh
            .triangles
            .iter()
            .filter(|t| {
                signed_uv_area([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]]) < 0.0
            })
            .count();
        if 2 * negative > mesh.triangles.len() {
            uv.iter_mut().for_each(|p| p[1] = -p[1]);
        }
        count_flipped(uv, &mesh.triangles)
    };
    let mut lscm_flipped = 0;
    let mut multilevel = None;
    let mut given = options.initial_uv.clone().map(|uv| (uv, StartMap::Given));
    if given.is_none() && mesh.triangles.len() >= options.multilevel.min_faces {
        let (uv, report) = multilevel_start(mesh, &topo, options);
        given = uv.map(|uv| (uv, StartMap::Multilevel));
        multilevel = Some(report);
    }
    let (mut uv, start) = match (given, options.start) {
        (Some((given, kind)), _) => {
            check_given_length(&given, mesh)?;
            (given, kind)
        }
        (None, StartChoice::MeanValue) => (
            tutte::mean_value(&positions, &mesh.triangles, boundary)?,
            StartMap::MeanValue,
        ),
        (None, StartChoice::Auto | StartChoice::Lscm) => {
            let mut uv = lscm::lscm(&positions, &mesh.triangles, boundary)?.uv;
            lscm_flipped = admissible(&mut uv);
            if lscm_flipped == 0 || options.start == StartChoice::Lscm {
                (uv, StartMap::Lscm)
            } else {
                (
                    tutte::mean_value(&positions, &mesh.triangles, boundary)?,
                    StartMap::MeanValue,
                )
            }
        }
    };
    let start_flipped = admissible(&mut uv);
    if start_flipped > 0 && matches!(start, StartMap::Given | StartMap::Multilevel) {
        return Err(FlattenError::GivenStartFlipped(start_flipped));
    }
    if start_flipped > 0 && options.start == StartChoice::Lscm {
        return Err(FlattenError::LscmFlipped(start_flipped));
    }
    if start_flipped > 0 {
        return Err(FlattenError::NoAdmissibleStart {
            lscm: lscm_flipped,
            mean_value: start_flipped,
        });
    }
    // Scale the start so its area matches the (unit) surface area: lengths scale by
    // √(area3D / areaUV) (NOTES.md §1).
    let uv_area: f64 = mesh
        .triangles
        .iter()
        .map(|t| signed_uv_area([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]]))
        .sum();
    // A given map is in the mesh's units: only the normalization applies to it.
    let s = if matches!(start, StartMap::Given | StartMap::Multilevel) {
        1.0 / scale
    } else {
        (1.0 / uv_area).sqrt()
    };
    // Rigid-motion pins: the two boundary vertices farthest apart in the start map,
    // rotated onto the u axis.
    let (p0, p1) = farthest_pair(&uv, boundary);
    uv.iter_mut().for_each(|p| *p = [s * p[0], s * p[1]]);
    align_pins(&mut uv, p0, p1);

    // One fill-reducing vertex ordering for the ARAP and Newton systems.
    let vertex_ordering = VertexOrdering::of_triangles(mesh.positions.len(), &mesh.triangles)?;
    // ARAP warm start: only as search directions, accepted when flip-free and when
    // they lower the energy being minimized first (see `arap`).
    let mut warm_start_iterations = 0;
    // A multilevel start is already close to the minimum: no warm start, and no
    // continuation (the coarse level did it).
    let from_alpha = options.from_alpha.filter(|_| start != StartMap::Multilevel);
    if options.warm_start && start != StartMap::Multilevel {
        let first_energy = match (&options.energy, &from_alpha) {
            (_, Some(from)) => EnergyKind::Litke(*from),
            (e, None) => *e,
        };
        let arap = ArapStep::new(
            mesh.positions.len(),
            &mesh.triangles,
            &rest,
            p0,
            Some(&vertex_ordering),
        )?;
        let evaluate = NewtonSolver::energy_of(&rest, &mesh.triangles);
        let mut energy = evaluate(&uv, &first_energy);
        let (mut target, mut direction, mut trial) =
            (Vec::new(), vec![[0.0; 2]; uv.len()], uv.clone());
        for _ in 0..WARM_START_MAX_ITERATIONS {
            arap.target(&uv, &mut target)?;
            for ((d, t), u) in direction.iter_mut().zip(&target).zip(&uv) {
                *d = [t[0] - u[0], t[1] - u[1]];
            }
            let mut step = 1.0f64.min(0.9 * max_flip_free_step(&uv, &mesh.triangles, &direction));
            let mut accepted = None;
            for _ in 0..6 {
                for ((tr, u), d) in trial.iter_mut().zip(&uv).zip(&direction) {
                    *tr = [u[0] + step * d[0], u[1] + step * d[1]];
                }
                let e = evaluate(&trial, &first_energy);
                if e < energy {
                    accepted = Some(e);
                    break;
                }
                step *= 0.5;
            }
            let Some(e) = accepted else { break };
            let gain = (energy - e) / energy;
            std::mem::swap(&mut uv, &mut trial);
            energy = e;
            warm_start_iterations += 1;
            if gain < WARM_START_MIN_GAIN {
                break;
            }
        }
        align_pins(&mut uv, p0, p1);
    }
    let time_start = clock.elapsed().as_secs_f64();

    let mut solver = NewtonSolver::new(
        mesh.positions.len(),
        &mesh.triangles,
        rest,
        &[(p0, 0), (p0, 1), (p1, 1)],
        Some(&vertex_ordering),
    )?;
    let mut log = Vec::new();
    let mut record = |entry: IterationLog| {
        progress(&entry);
        log.push(entry);
    };
    let mut iterations = 0;
    let mut continuation = Vec::new();
    let (stop, energy) = match (&options.energy, &from_alpha) {
        (EnergyKind::Litke(target), Some(from)) => {
            // Continuation (§3.1.3): θ from 0 to 1, halving the step when a stage locks.
            // Stage 0 only prepares a start: a locked or capped stage 0 is still a
            // valid (flip-free) start for the next stage.
            let (_, it0, _) =
                solver.minimize(&mut uv, from, &options.newton, 0, clock, &mut record)?;
            iterations += it0;
            continuation.push(from.alphas());
            let (mut theta, mut dtheta) = (0.0f64, 1.0f64);
            let mut stage = 1;
            let mut last = (StopReason::Converged, f64::NAN);
            while theta < 1.0 {
                let next = (theta + dtheta).min(1.0);
                let alpha = from.blend(target, next);
                let mut trial = uv.clone();
                let (stop, it, e) = solver.minimize(
                    &mut trial,
                    &alpha,
                    &options.newton,
                    stage,
                    clock,
                    &mut record,
                )?;
                iterations += it;
                stage += 1;
                if stop == StopReason::Locked && dtheta > 1.0 / 64.0 {
                    dtheta *= 0.5;
                    continue;
                }
                uv = trial;
                theta = next;
                continuation.push(alpha.alphas());
                last = (stop, e);
                dtheta = (2.0 * dtheta).min(1.0);
            }
            last
        }
        (energy, _) => {
            let (stop, it, e) =
                solver.minimize(&mut uv, energy, &options.newton, 0, clock, &mut record)?;
            iterations += it;
            (stop, e)
        }
    };
    let time_newton = clock.elapsed().as_secs_f64() - time_start;
    let flipped = count_flipped(&uv, &mesh.triangles);
    if flipped > 0 {
        return Err(FlattenError::FlippedResult(flipped));
    }
    let uvs = uv.iter().map(|p| [p[0] * scale, p[1] * scale]).collect();
    Ok(Flattening {
        uvs,
        start,
        lscm_flipped,
        warm_start_iterations,
        iterations,
        converged: stop == StopReason::Converged,
        stop_reason: stop,
        energy,
        flipped_triangles: flipped,
        continuation,
        log,
        time_start,
        time_newton,
        time_total: clock.elapsed().as_secs_f64(),
        newton_timings: solver.timings,
        multilevel,
    })
}

/// The multilevel start (see [`super::multilevel`]) in the mesh's units, or `None`
/// (with the reason in the report) when any stage failed.
fn multilevel_start(
    mesh: &TriMesh,
    topo: &Topology,
    options: &FlattenOptions,
) -> (Option<Vec<[f64; 2]>>, MultilevelReport) {
    use crate::mesh::decimate::{DecimateOptions, decimate_with};
    let mut report = MultilevelReport::default();
    let clock = Instant::now();
    let run = |report: &mut MultilevelReport| -> Result<Vec<[f64; 2]>, String> {
        let coarse_size = options.multilevel.coarse_size(mesh.positions.len());
        if mesh.positions.len() < 2 * coarse_size {
            return Err(format!(
                "the mesh has {} vertices, not even twice the {coarse_size} of the coarse level",
                mesh.positions.len(),
            ));
        }
        let decimation = decimate_with(
            mesh,
            topo,
            &DecimateOptions {
                target_vertices: coarse_size,
                ..Default::default()
            },
        )
        .map_err(|e| format!("decimation: {e}"))?;
        let (coarse, original_of_coarse) = decimation.coarse_mesh(mesh);
        report.coarse_vertices = coarse.positions.len();
        report.coarse_faces = coarse.triangles.len();
        report.time_decimate = clock.elapsed().as_secs_f64();
        let coarse_options = FlattenOptions {
            multilevel: MultilevelOptions::off(),
            initial_uv: None,
            ..options.clone()
        };
        let flat = flatten(&coarse, &coarse_options).map_err(|e| format!("coarse mesh: {e}"))?;
        report.coarse_iterations = flat.iterations;
        report.coarse_continuation = flat.continuation;
        report.time_coarse = clock.elapsed().as_secs_f64() - report.time_decimate;
        let mut uv = vec![[f64::NAN; 2]; mesh.positions.len()];
        for (c, &v) in original_of_coarse.iter().enumerate() {
            uv[v as usize] = flat.uvs[c];
        }
        report.prolongation = super::multilevel::prolongate(
            &mesh.positions,
            &decimation,
            &mut uv,
            &options.energy,
            options.multilevel.polish_steps,
            options.multilevel.sweeps,
        )
        .map_err(|e| format!("re-insertion: {e}"))?;
        let flipped = count_flipped(&uv, &mesh.triangles);
        if flipped > 0 {
            return Err(format!("re-insertion left {flipped} flipped triangles"));
        }
        report.time_prolongate =
            clock.elapsed().as_secs_f64() - report.time_decimate - report.time_coarse;
        Ok(uv)
    };
    match run(&mut report) {
        Ok(uv) => (Some(uv), report),
        Err(reason) => {
            report.abandoned = Some(reason);
            (None, report)
        }
    }
}

fn check_given_length(given: &[[f64; 2]], mesh: &TriMesh) -> Result<(), FlattenError> {
    if given.len() == mesh.positions.len() {
        Ok(())
    } else {
        Err(FlattenError::GivenStartLength {
            uvs: given.len(),
            vertices: mesh.positions.len(),
        })
    }
}

/// ARAP warm-start iterations at most, and the relative energy decrease below which
/// they stop (Newton takes over).
const WARM_START_MAX_ITERATIONS: usize = 30;
const WARM_START_MIN_GAIN: f64 = 0.05;

/// Moves `p0` to the origin and rotates `p1` onto the positive u axis (a rigid motion:
/// the energy does not change), so pinning `p0` and the v coordinate of `p1` removes
/// exactly the rigid motions.
fn align_pins(uv: &mut [[f64; 2]], p0: u32, p1: u32) {
    let origin = uv[p0 as usize];
    let (dx, dy) = (
        uv[p1 as usize][0] - origin[0],
        uv[p1 as usize][1] - origin[1],
    );
    let len = dx.hypot(dy).max(f64::MIN_POSITIVE);
    let (c, sn) = (dx / len, dy / len);
    for p in uv.iter_mut() {
        let (x, y) = (p[0] - origin[0], p[1] - origin[1]);
        *p = [c * x + sn * y, -sn * x + c * y];
    }
}

/// The two loop vertices farthest apart (approximately: farthest from the loop's
/// first vertex, then farthest from that), deterministic for a given map.
fn farthest_pair(uv: &[[f64; 2]], boundary: &[u32]) -> (u32, u32) {
    let far = |from: u32| -> u32 {
        let o = uv[from as usize];
        *boundary
            .iter()
            .max_by(|&&a, &&b| {
                let da = (uv[a as usize][0] - o[0]).hypot(uv[a as usize][1] - o[1]);
                let db = (uv[b as usize][0] - o[0]).hypot(uv[b as usize][1] - o[1]);
                da.total_cmp(&db)
            })
            .expect("a disc has a boundary")
    };
    let a = far(boundary[0]);
    let b = far(a);
    (a, b)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::bumpy_disc;
    use crate::mesh::repair::reorient;

    #[test]
    fn inconsistent_orientation_is_refused_with_advice_and_reorient_fixes_it() {
        let mut mesh = bumpy_disc(6, 0.3);
        mesh.triangles[40].swap(1, 2);
        let err = flatten(&mesh, &FlattenOptions::default()).unwrap_err();
        assert!(matches!(err, FlattenError::NotADisc(_)), "{err}");
        assert!(err.to_string().contains("--reorient"), "{err}");
        let (fixed, flipped) = reorient(&mesh).unwrap();
        assert_eq!(flipped, 1);
        let map = flatten(&fixed, &FlattenOptions::default()).unwrap();
        assert_eq!(map.flipped_triangles, 0);
    }

    #[test]
    fn unreferenced_vertices_are_carried_through() {
        let mut mesh = bumpy_disc(5, 0.3);
        mesh.positions.push([9.0, 9.0, 9.0]);
        let map = flatten(&mesh, &FlattenOptions::default()).unwrap();
        assert_eq!(map.uvs.len(), mesh.positions.len());
        assert_eq!(count_flipped(&map.uvs, &mesh.triangles), 0);
    }

    #[test]
    fn warm_start_reaches_the_same_minimum_with_fewer_newton_iterations() {
        // A cap deep enough that the conformal start squeezes its pole region.
        let mesh = crate::mesh::generate::spherical_cap(1.0, 2.4, 16, 48);
        let cold = flatten(
            &mesh,
            &FlattenOptions {
                warm_start: false,
                ..Default::default()
            },
        )
        .unwrap();
        let warm = flatten(&mesh, &FlattenOptions::default()).unwrap();
        assert!(warm.warm_start_iterations > 0);
        assert!(warm.converged && cold.converged);
        assert!(
            (warm.energy - cold.energy).abs() <= 1e-9 * cold.energy,
            "{} vs {}",
            warm.energy,
            cold.energy
        );
        assert!(
            warm.iterations < cold.iterations,
            "{} vs {}",
            warm.iterations,
            cold.iterations
        );
        assert_eq!(warm.flipped_triangles, 0);
    }

    #[test]
    fn a_given_start_is_used_in_mesh_units_and_checked() {
        let mesh = bumpy_disc(8, 0.4);
        let first = flatten(&mesh, &FlattenOptions::default()).unwrap();
        // Restarting from a converged map (in the mesh's units) needs no iteration.
        let again = flatten(
            &mesh,
            &FlattenOptions {
                initial_uv: Some(first.uvs.clone()),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(again.start, StartMap::Given);
        assert_eq!(again.start_description(), "given");
        assert!(again.iterations <= 1, "{}", again.iterations);
        assert!((again.energy - first.energy).abs() <= 1e-10 * first.energy);
        // A start with a flipped triangle is refused, not repaired silently.
        let mut folded = first.uvs.clone();
        let t = mesh.triangles[0];
        folded[t[0] as usize] = [
            folded[t[1] as usize][0] + folded[t[2] as usize][0] - folded[t[0] as usize][0],
            folded[t[1] as usize][1] + folded[t[2] as usize][1] - folded[t[0] as usize][1],
        ];
        let err = flatten(
            &mesh,
            &FlattenOptions {
                initial_uv: Some(folded),
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(
            matches!(err, FlattenError::GivenStartFlipped(n) if n >= 1),
            "{err}"
        );
        let err = flatten(
            &mesh,
            &FlattenOptions {
                initial_uv: Some(vec![[0.0; 2]; 3]),
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(err.to_string().contains("3 UVs"), "{err}");
    }

    #[test]
    fn out_of_range_index_is_an_error_not_a_panic() {
        let mut mesh = bumpy_disc(3, 0.3);
        mesh.triangles[2][1] = 10_000;
        let err = flatten(&mesh, &FlattenOptions::default()).unwrap_err();
        assert!(
            matches!(
                err,
                FlattenError::InvalidIndex {
                    triangle: 2,
                    vertex: 10_000,
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn continuation_needs_the_litke_energy() {
        let mesh = bumpy_disc(4, 0.3);
        let options = FlattenOptions {
            energy: EnergyKind::SymmetricDirichlet,
            from_alpha: Some(Litke::conformal()),
            ..Default::default()
        };
        assert!(matches!(
            flatten(&mesh, &options),
            Err(FlattenError::ContinuationNeedsLitke)
        ));
    }
}
