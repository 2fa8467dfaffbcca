//! The one-call flattening (thesis §3.1): checks that the input is a disc, computes the
//! initial map (free-boundary conformal, with an injective fallback, or the multilevel
//! start for large meshes), normalizes scale, runs projected Newton (with optional
//! α-continuation), verifies the result has no flipped triangle, and returns UVs in the
//! mesh's own units.
//!
//! [`FlattenOptions`] says what to minimize ([`Energy`]), where to start ([`Start`],
//! [`Multilevel`]) and whether holes are filled for the solve; the defaults (balanced
//! α, automatic start, ARAP warm start) suit most meshes.

use super::arap::ArapStep;
use super::barrier::BoundaryBarrier;
use super::element::{RestTriangleError, rest_triangles};
use super::flip_free::max_flip_free_step;
use super::newton::{CROSSING_PERSISTENCE, NewtonSolver};
pub use super::newton::{IterationLog, NewtonSettings, NewtonTimings, StopReason};
pub use super::optcuts::{CutRound, CutStop, DistortionCuts, MaxDistortion};
pub use super::plan::{Cut, CutReason, Seams};
use super::plan::{Plan, map_back, plan_with_topology, prepare};
use super::{InitialMapError, count_flipped, lscm, signed_uv_area, tutte};
use crate::energy::Energy;
use crate::linsolve::{SolveError, VertexOrdering};
use crate::measure::overlap::boundary_crossings;
use crate::mesh::cut::CutError;
use crate::mesh::disc::list_defects;
use crate::mesh::validate::Defect;
use crate::mesh::{Disc, IndexError, NotADisc, Topology, TriMesh, Uvs};
use serde::Serialize;
use std::time::Instant;

/// Where the flattening starts (thesis §3.1.1): the initial map, which must be
/// admissible (no flipped triangle).
#[derive(Clone, Debug, PartialEq)]
pub enum Start {
    /// LSCM, falling back to mean-value coordinates when LSCM flips a triangle; for
    /// large meshes (see [`Multilevel`]) the flattening of a decimated copy instead.
    Auto { multilevel: Multilevel },
    /// LSCM on the full mesh; an error if it flips a triangle.
    Lscm,
    /// Mean-value coordinates onto a circle on the full mesh (injective by
    /// construction).
    MeanValue,
    /// This map: one UV per vertex in the mesh's length units (as [`Flattening::uvs`]),
    /// no flipped triangle.
    Given(Vec<[f64; 2]>),
}

impl Default for Start {
    /// `Auto` with the automatic multilevel choice.
    fn default() -> Self {
        Start::Auto {
            multilevel: Multilevel::default(),
        }
    }
}

/// When [`Start::Auto`] uses the multilevel start ([`super::multilevel`]): flatten a
/// decimated copy, re-insert the removed vertices flip-free, then run Newton on the full
/// mesh from there. If any stage fails, the single-level start is used (and the report
/// says why).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Multilevel {
    /// For meshes of at least [`MULTILEVEL_MIN_FACES`] faces.
    Auto(CoarseLevel),
    /// For every mesh.
    Always(CoarseLevel),
    /// Never.
    Never,
}

impl Default for Multilevel {
    fn default() -> Self {
        Multilevel::Auto(CoarseLevel::default())
    }
}

impl Multilevel {
    /// The coarse level to use for a mesh of `faces` faces, or `None` for the
    /// single-level start.
    pub fn coarse_level(&self, faces: usize) -> Option<&CoarseLevel> {
        match self {
            Multilevel::Auto(c) if faces >= MULTILEVEL_MIN_FACES => Some(c),
            Multilevel::Always(c) => Some(c),
            _ => None,
        }
    }
}

/// The coarse level of the multilevel start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoarseLevel {
    /// Vertices of the decimated copy (at least [`MIN_COARSE_VERTICES`]); `None`: 1/20
    /// of the mesh, between [`MULTILEVEL_MIN_COARSE_VERTICES`] and
    /// [`MULTILEVEL_MAX_COARSE_VERTICES`] ([`CoarseLevel::size_for`]).
    pub vertices: Option<usize>,
    /// Local Newton steps per re-inserted vertex.
    pub polish_steps: usize,
    /// Relaxation sweeps over the full mesh after the re-insertion.
    pub sweeps: usize,
}

impl Default for CoarseLevel {
    fn default() -> Self {
        Self {
            vertices: None,
            polish_steps: super::multilevel::DEFAULT_POLISH_STEPS,
            sweeps: super::multilevel::DEFAULT_SWEEPS,
        }
    }
}

impl CoarseLevel {
    /// The default level with `vertices` coarse vertices.
    pub fn with_vertices(vertices: usize) -> Self {
        Self {
            vertices: Some(vertices),
            ..Self::default()
        }
    }

    /// The coarse size for a mesh of `vertices` vertices: the given one, or by default
    /// 1/20 of the mesh, between 500 and 20 000 vertices.
    pub fn size_for(&self, vertices: usize) -> usize {
        self.vertices.unwrap_or((vertices / 20).clamp(
            MULTILEVEL_MIN_COARSE_VERTICES,
            MULTILEVEL_MAX_COARSE_VERTICES,
        ))
    }
}

/// Size from which [`Multilevel::Auto`] uses the multilevel start (measured in
/// BENCHMARKS.md: from ~15k faces it needs fewer full-size Newton iterations than the
/// start map), and the bounds of the default coarse size.
pub const MULTILEVEL_MIN_FACES: usize = 15_000;
pub const MULTILEVEL_MIN_COARSE_VERTICES: usize = 500;
pub const MULTILEVEL_MAX_COARSE_VERTICES: usize = 20_000;
/// The smallest coarse level one may ask for ([`CoarseLevel::vertices`]).
pub const MIN_COARSE_VERTICES: usize = 16;

/// Which initial map was actually used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StartMap {
    /// Free-boundary least-squares conformal map.
    Lscm,
    /// Mean-value coordinates onto a circle (injective by construction), used because
    /// LSCM flipped or degenerated `lscm_flipped` triangles, or by request.
    MeanValue,
    /// The caller's map ([`Start::Given`]).
    Given,
    /// The flattening of a decimated copy, refined vertex by vertex
    /// ([`super::multilevel`]; details in [`Flattening::multilevel`]).
    Multilevel,
}

/// What the multilevel start did (or why it was abandoned).
#[derive(Clone, Debug, Default, Serialize)]
pub struct MultilevelReport {
    pub coarse_vertices: usize,
    pub coarse_faces: usize,
    /// Newton iterations on the coarse mesh.
    pub coarse_iterations: usize,
    /// Whether the coarse mesh was solved with the boundary barrier: because its
    /// unconstrained minimum overlapped itself, or outright where the boundary runs
    /// along itself in 3D (the sides of seams). The bijective mode then solves the full mesh
    /// with the barrier from the start (measured: every ICT face opened with seams
    /// ends in the barrier solve).
    pub coarse_barrier: bool,
    /// α values of the continuation stages solved on the coarse mesh (with a
    /// continuation start; the full mesh then goes straight to the target α).
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
    /// The local solve that opened the start's crushed boundary contacts before the
    /// barrier solve, when it had any ([`super::relief`]).
    pub relief: Option<super::relief::ContactRelief>,
}

/// When the flattening keeps the boundary from overlapping itself with the boundary
/// barrier ([`super::barrier`]; Smith & Schaefer 2015): a flip-free map of a disc is
/// injective exactly when its boundary does not cross itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Bijective {
    /// Never: the result is flip-free (locally injective); its boundary may overlap
    /// itself ([`Flattening::boundary_crossings`] says whether it does).
    Off,
    /// Solve as with `Off`; if the boundary of the result crosses itself, solve again
    /// with the barrier from a crossing-free start. Costs nothing where there is no
    /// overlap, and the result is the same as with `Off` there.
    #[default]
    WhenOverlapping,
    /// Always solve with the barrier, from a crossing-free start (LSCM if it is
    /// flip-free and crossing-free, else mean-value coordinates onto a circle; when
    /// that start is crushed, scaffold iterations instead of the barrier solve,
    /// [`super::scaffold`]).
    Always,
}

/// What the result is guaranteed to be (checked on the result, not assumed).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Guarantee {
    /// Flip-free, and the boundary does not cross itself: the map is injective.
    Bijective,
    /// Flip-free, but the boundary crosses itself ([`Flattening::boundary_crossings`]):
    /// locally injective only.
    LocallyInjective,
}

/// Options of [`flatten`].
#[derive(Clone, Debug, PartialEq)]
pub struct FlattenOptions {
    /// The energy to minimize, with an optional continuation (default: Litke's density
    /// with balanced α, [`Energy::default`]).
    pub energy: Energy,
    /// The initial map (default: automatic, multilevel from 15k faces).
    pub start: Start,
    /// Move the single-level start map (LSCM, mean-value or given) toward an isometry
    /// with a few ARAP steps before Newton (each one accepted only if flip-free and
    /// energy-decreasing). Under the multilevel start they run on the coarse level.
    pub warm_start: bool,
    /// Newton's line search and stopping rule.
    pub newton: NewtonSettings,
    /// Fill every boundary loop but the longest (eyes, mouth, scan holes) with a fan
    /// for the solve ([`crate::mesh::repair::fill_holes`]); the result has UVs for the
    /// original vertices only, so the holes stay open in the map. Default: on; off, the
    /// holes are joined to the outer boundary by seams instead (with [`Cut::Auto`]).
    pub fill_holes: bool,
    /// How a surface that is not a disc (closed, with handles, or with holes not
    /// filled) is cut open along seams ([`super::plan`]; default: [`Cut::Auto`]).
    pub cut: Cut,
    /// Whether the boundary is kept from overlapping itself (default:
    /// [`Bijective::WhenOverlapping`]).
    pub bijective: Bijective,
    /// A bound on the distortion: while the map's mean symmetric Dirichlet distortion
    /// exceeds it, cut the chart open where the distortion concentrates and flatten
    /// again ([`super::optcuts`]; default: none, one chart as it comes).
    pub max_distortion: Option<MaxDistortion>,
}

impl Default for FlattenOptions {
    fn default() -> Self {
        Self {
            energy: Energy::default(),
            start: Start::default(),
            warm_start: true,
            newton: NewtonSettings::default(),
            fill_holes: true,
            cut: Cut::Auto,
            bijective: Bijective::default(),
            max_distortion: None,
        }
    }
}

impl FlattenOptions {
    /// The default options with this energy (e.g. `FlattenOptions::new(Alpha::conformal())`).
    pub fn new(energy: impl Into<Energy>) -> Self {
        Self {
            energy: energy.into(),
            ..Self::default()
        }
    }

    /// These options with the start `start`.
    pub fn with_start(self, start: Start) -> Self {
        Self { start, ..self }
    }

    /// These options with holes filled for the solve (or not).
    pub fn with_fill_holes(self, fill_holes: bool) -> Self {
        Self { fill_holes, ..self }
    }

    /// These options with the cut `cut`.
    pub fn with_cut(self, cut: Cut) -> Self {
        Self { cut, ..self }
    }

    /// These options with the bijective mode `bijective`.
    pub fn with_bijective(self, bijective: Bijective) -> Self {
        Self { bijective, ..self }
    }

    /// These options with the distortion bound `bound` ([`MaxDistortion::new`]).
    pub fn with_max_distortion(self, bound: f64) -> Self {
        Self {
            max_distortion: Some(MaxDistortion::new(bound)),
            ..self
        }
    }

    /// Checks the numeric settings (called by [`flatten`]).
    pub fn validate(&self) -> Result<(), OptionError> {
        if let Some(m) = &self.max_distortion
            && !(m.bound >= 1.0 && m.bound.is_finite())
        {
            return Err(OptionError::MaxDistortion(m.bound));
        }
        let n = &self.newton;
        if n.tolerance.is_nan() || n.tolerance <= 0.0 {
            return Err(OptionError::Tolerance(n.tolerance));
        }
        if !(n.armijo_c > 0.0 && n.armijo_c < 1.0) {
            return Err(OptionError::ArmijoC(n.armijo_c));
        }
        if !(n.armijo_rho > 0.0 && n.armijo_rho < 1.0) {
            return Err(OptionError::ArmijoRho(n.armijo_rho));
        }
        if let Start::Auto {
            multilevel: Multilevel::Auto(c) | Multilevel::Always(c),
        } = &self.start
            && let Some(v) = c.vertices.filter(|&v| v < MIN_COARSE_VERTICES)
        {
            return Err(OptionError::CoarseVertices(v));
        }
        Ok(())
    }
}

/// A numeric option out of its range (see [`FlattenOptions::validate`]).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum OptionError {
    #[error("NewtonSettings::tolerance must be positive, got {0}")]
    Tolerance(f64),
    #[error("NewtonSettings::armijo_c must be in (0, 1), got {0}")]
    ArmijoC(f64),
    #[error("NewtonSettings::armijo_rho must be in (0, 1), got {0}")]
    ArmijoRho(f64),
    #[error("CoarseLevel::vertices must be at least {MIN_COARSE_VERTICES}, got {0}")]
    CoarseVertices(usize),
    #[error(
        "MaxDistortion::bound must be a finite number of at least 1 (the mean symmetric Dirichlet distortion of an isometry, the least any map has), got {0}"
    )]
    MaxDistortion(f64),
}

/// Result of a flattening.
#[derive(Clone, Debug, Serialize)]
pub struct Flattening {
    /// The UVs, in the mesh's length units (an isometry keeps lengths): one per vertex
    /// (vertices used by no triangle at the origin), or, when the surface was cut
    /// ([`Self::seams`]), one per UV vertex of the cut map, indexed per corner by
    /// [`Seams::uv_triangles`]. [`Self::texture_coordinates`] gives either as [`Uvs`].
    pub uvs: Vec<[f64; 2]>,
    /// What was done before the solve: a disc as is, holes filled, or cut open.
    pub plan: Plan,
    /// The seams when the surface was cut open (then [`Self::uvs`] are per UV vertex).
    pub seams: Option<Seams>,
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
    /// Pairs of boundary edges of the solved disc (after filling and cutting) that
    /// cross or touch, checked on the result: 0 means the map is injective.
    pub boundary_crossings: usize,
    /// What the result is guaranteed to be (from the check above).
    pub guarantee: Guarantee,
    /// Whether the boundary barrier was used: with [`Bijective::Always`], or because
    /// the unconstrained result overlapped ([`Bijective::WhenOverlapping`]; then
    /// [`Self::iterations`] and the log are those of the barrier solve, and the times
    /// include both). From a crushed mean-value start the scaffold iterations
    /// ([`super::scaffold`]) take the barrier solve's place: then the iterations and
    /// the log are theirs and the stop reason is [`StopReason::Stalled`] (or the cap).
    pub barrier: bool,
    /// Holes filled for the solve ([`FlattenOptions::fill_holes`]).
    pub holes_filled: usize,
    /// α values of the continuation stages actually solved (empty without continuation).
    pub continuation: Vec<[f64; 3]>,
    pub log: Vec<IterationLog>,
    /// Seconds: filling holes and cutting, initial map, Newton (all stages), total.
    pub time_prepare: f64,
    pub time_start: f64,
    pub time_newton: f64,
    pub time_total: f64,
    /// Newton time by phase.
    pub newton_timings: NewtonTimings,
    /// The multilevel start, when it was tried.
    pub multilevel: Option<MultilevelReport>,
    /// What the distortion-driven cutting did ([`FlattenOptions::max_distortion`]):
    /// the distortion before and after, the rounds, the seam length added, whether the
    /// bound holds. The other fields describe the solve of the map returned (the best
    /// one found), [`Self::time_total`] every round.
    pub distortion_cuts: Option<DistortionCuts>,
}

impl Flattening {
    /// The start map for people: `lscm`, `mean-value (LSCM flipped N)`, `given` or
    /// `multilevel (N coarse vertices)` (`…, K crushed boundary contacts relieved` when
    /// [`MultilevelReport::relief`] opened some).
    pub fn start_description(&self) -> String {
        match self.start {
            StartMap::Lscm => "lscm".to_string(),
            StartMap::MeanValue if self.lscm_flipped > 0 => {
                format!("mean-value (LSCM flipped {})", self.lscm_flipped)
            }
            StartMap::MeanValue => "mean-value".to_string(),
            StartMap::Given => "given".to_string(),
            StartMap::Multilevel => match &self.multilevel {
                Some(m) => match m.relief {
                    Some(r) => format!(
                        "multilevel ({} coarse vertices, {} crushed boundary contacts relieved)",
                        m.coarse_vertices, r.crushed_pairs
                    ),
                    None => format!("multilevel ({} coarse vertices)", m.coarse_vertices),
                },
                None => "multilevel".to_string(),
            },
        }
    }

    /// What was done around the solve, for people: the plan ([`Plan::describe`]),
    /// followed by the distortion cuts when the map kept some
    /// ([`FlattenOptions::max_distortion`]): `disc as is`, `cut open to lower the
    /// distortion`, `cut open along seams (closed, genus 0), then cut open to lower the
    /// distortion`.
    pub fn describe_plan(&self) -> String {
        let distortion_cuts = self
            .distortion_cuts
            .as_ref()
            .is_some_and(|c| c.seam_edges_added > 0);
        match (distortion_cuts, self.plan.is_disc_as_is()) {
            (false, _) => self.plan.describe(),
            (true, true) => "cut open to lower the distortion".to_string(),
            (true, false) => format!(
                "{}, then cut open to lower the distortion",
                self.plan.describe()
            ),
        }
    }

    /// The UVs mapped into `[0, 1]²` with the aspect ratio kept
    /// ([`super::normalize_uvs`]), e.g. for texture coordinates.
    pub fn normalized_uvs(&self) -> Vec<[f64; 2]> {
        let mut uvs = self.uvs.clone();
        super::normalize_uvs(&mut uvs);
        uvs
    }

    /// The texture coordinates of the input mesh: per vertex, or per corner when the
    /// surface was cut; in `[0, 1]²` when `normalized` ([`Self::normalized_uvs`]).
    pub fn texture_coordinates(&self, normalized: bool) -> Uvs {
        let coords = if normalized {
            self.normalized_uvs()
        } else {
            self.uvs.clone()
        };
        match &self.seams {
            None => Uvs::PerVertex(coords),
            Some(seams) => Uvs::PerCorner {
                coords,
                indices: seams.uv_triangles.clone(),
            },
        }
    }

    /// The UV triangle of every input triangle, corner by corner.
    pub fn corner_uvs(&self, triangles: &[[u32; 3]]) -> Vec<[[f64; 2]; 3]> {
        let indices = self.seams.as_ref().map_or(triangles, |s| &s.uv_triangles);
        indices
            .iter()
            .map(|t| t.map(|v| self.uvs[v as usize]))
            .collect()
    }
}

/// Why a flattening failed. The messages name the problem and the remedy in the
/// library's terms (options, `mesh::repair` functions).
#[derive(Debug, thiserror::Error)]
pub enum FlattenError {
    #[error(transparent)]
    Index(#[from] IndexError),
    #[error("the mesh cannot be flattened as a disc:\n{}", list_defects(.0))]
    NotADisc(Vec<Defect>),
    #[error("{0}; `repair::drop_degenerate` removes them")]
    Degenerate(#[from] RestTriangleError),
    #[error("invalid option: {0}")]
    Option(#[from] OptionError),
    #[error("linear solve failed: {0}")]
    Solve(#[from] SolveError),
    #[error("initial map: {0}")]
    InitialMap(#[from] InitialMapError),
    #[error(
        "both initial maps flipped triangles (LSCM: {lscm}, mean-value: {mean_value}); the mesh geometry is probably broken (non-finite or coincident vertices)"
    )]
    NoAdmissibleStart { lscm: usize, mean_value: usize },
    #[error(
        "the LSCM start flips or degenerates {0} triangles; use `Start::Auto` (falls back to mean-value coordinates, injective by construction)"
    )]
    LscmFlipped(usize),
    #[error("the given initial map has {uvs} UVs, but the mesh has {vertices} vertices")]
    GivenStartLength { uvs: usize, vertices: usize },
    #[error(
        "the given initial map flips or degenerates {0} triangles; a start map must be injective"
    )]
    GivenStartFlipped(usize),
    #[error(
        "a given start map has no UVs for the {0} filled holes; fill them yourself (`repair::fill_holes`) and give UVs for the filled mesh, or use `Start::Auto`"
    )]
    GivenStartWithFilledHoles(usize),
    #[error(
        "a given start map has one UV per vertex, but the surface is cut open along seams ({0}); cut it yourself (`mesh::cut`) and give UVs for the opened mesh, or use `Start::Auto`"
    )]
    GivenStartWithCut(String),
    #[error(transparent)]
    Cut(#[from] CutError),
    #[error("internal error: the result has {0} flipped triangles; please report this mesh")]
    FlippedResult(usize),
    #[error("measuring the distortion for the distortion bound: {0}")]
    Distortion(#[from] crate::measure::MeasureError),
}

impl From<NotADisc> for FlattenError {
    fn from(e: NotADisc) -> Self {
        match e {
            NotADisc::Index(e) => FlattenError::Index(e),
            NotADisc::Defects(d) => FlattenError::NotADisc(d),
        }
    }
}

/// Flattens a disc-topology mesh (module docs) with `options`.
///
/// Errors name the problem and the remedy: a mesh that is not a disc gets every defect
/// with the repair that fixes it ([`FlattenError::NotADisc`]).
pub fn flatten(mesh: &TriMesh, options: &FlattenOptions) -> Result<Flattening, FlattenError> {
    flatten_with_progress(mesh, options, &mut |_| {})
}

/// [`flatten`] with a callback receiving every Newton iteration's log entry as it
/// happens (for progress bars; the same entries end up in [`Flattening::log`]).
pub fn flatten_with_progress(
    mesh: &TriMesh,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&IterationLog),
) -> Result<Flattening, FlattenError> {
    let clock = Instant::now();
    options.validate()?;
    mesh.check_indices()?;
    let topology = Topology::new(mesh);
    let mut plan = plan_with_topology(mesh, &topology, options)?;
    if plan.is_disc_as_is() && options.max_distortion.is_none() {
        let mut result = flatten_used(mesh, Some(topology), options, progress)?;
        result.plan = plan;
        result.time_total = clock.elapsed().as_secs_f64();
        return Ok(result);
    }
    drop(topology);
    if matches!(options.start, Start::Given(_)) && !plan.is_disc_as_is() {
        return Err(match plan.cut {
            None => FlattenError::GivenStartWithFilledHoles(plan.holes_to_fill),
            Some(_) => FlattenError::GivenStartWithCut(plan.describe()),
        });
    }
    // The fill's vertices come after the original ones and the cut's copies after
    // those: mapping back drops them (the holes stay open in the map).
    let mut prepared = prepare(mesh, &mut plan, options)?;
    let time_prepare = clock.elapsed().as_secs_f64();
    let mut result = flatten_used(&prepared.mesh, None, options, progress)?;
    if let Some(bound) = &options.max_distortion {
        (prepared, result) = super::optcuts::cut_to_bound(
            mesh.triangles.len(),
            prepared,
            result,
            bound,
            options,
            progress,
        )?;
    }
    // Seams with no topological reason were cut for the distortion bound.
    let reason = plan.cut.clone().unwrap_or(CutReason::Distortion);
    let (uvs, seams) = map_back(mesh, prepared, reason, std::mem::take(&mut result.uvs));
    result.uvs = uvs;
    result.seams = seams;
    result.holes_filled = plan.holes_to_fill;
    result.plan = plan;
    result.time_prepare = time_prepare;
    result.time_total = clock.elapsed().as_secs_f64();
    Ok(result)
}

/// The flattening of the vertices used by a triangle; the others are put at the origin.
/// `topology`: that of `mesh`, if already derived.
pub(super) fn flatten_used(
    mesh: &TriMesh,
    topology: Option<Topology>,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&IterationLog),
) -> Result<Flattening, FlattenError> {
    let (compact, old_of_new) = without_unreferenced(mesh);
    let Some(compact) = compact else {
        return flatten_disc(mesh, topology, options, progress);
    };
    let mut compact_options = options.clone();
    if let Start::Given(given) = &options.start {
        check_given_length(given, mesh)?;
        compact_options.start =
            Start::Given(old_of_new.iter().map(|&v| given[v as usize]).collect());
    }
    let mut result = flatten_disc(&compact, None, &compact_options, progress)?;
    let mut uvs = vec![[0.0, 0.0]; mesh.positions.len()];
    for (new, &old) in old_of_new.iter().enumerate() {
        uvs[old as usize] = result.uvs[new];
    }
    result.uvs = uvs;
    Ok(result)
}

/// The flattening of a mesh whose vertices are all used (`topology`: its topology, if
/// already derived).
fn flatten_disc(
    mesh: &TriMesh,
    topology: Option<Topology>,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&IterationLog),
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
    let mut shared = SharedStart::NotTried;
    let first = match solve_disc(mesh, &disc, options, progress, solve, &mut shared)? {
        SolveOutcome::Map(first) if first.boundary_crossings == 0 => return Ok(*first),
        SolveOutcome::Map(first) if options.bijective != Bijective::WhenOverlapping => {
            return Ok(*first);
        }
        SolveOutcome::Map(first) => first.time_start + first.time_newton,
        SolveOutcome::StartCrosses { time } => time,
    };
    // The unconstrained map (or its start) overlaps itself: solve with the boundary
    // barrier.
    let SolveOutcome::Map(second) =
        solve_disc(mesh, &disc, options, progress, Solve::Barrier, &mut shared)?
    else {
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

/// The multilevel start, computed once by the first solve of [`flatten_disc`] and
/// reused by the barrier solve when its boundary does not cross itself (its coarse
/// level was solved with the same [`Bijective`] option, so it is overlap-free there).
enum SharedStart {
    NotTried,
    /// No coarse level for this mesh size or options.
    None,
    /// The start (`None` when abandoned) and its report.
    Tried(Option<Vec<[f64; 2]>>, Box<MultilevelReport>),
}

/// What [`solve_disc`] returned.
enum SolveOutcome {
    Map(Box<Flattening>),
    /// [`Solve::UnlessStartCrosses`] gave up after `time` seconds (building the start).
    StartCrosses {
        time: f64,
    },
}

/// One solve of [`flatten_disc`]: with the boundary barrier for [`Solve::Barrier`]
/// (from a crossing-free start: the multilevel one when it is, else LSCM or mean-value
/// coordinates, with ARAP warm-start steps from a mean-value start kept short of any
/// boundary contact). `shared`: the multilevel start, computed by the first solve that
/// needs it.
fn solve_disc(
    mesh: &TriMesh,
    disc: &Disc,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&IterationLog),
    solve: Solve,
    shared: &mut SharedStart,
) -> Result<SolveOutcome, FlattenError> {
    let clock = Instant::now();
    let barrier = solve == Solve::Barrier;
    // Scale normalization: work on the surface scaled to unit area, so energies and
    // tolerances are scale-free; the UVs are scaled back at the end.
    let (positions, scale) = mesh.unit_area_positions();
    let rest = rest_triangles(&positions, &mesh.triangles)?;
    let boundary = disc.boundary();

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
    // LSCM, with the mean-value fallback when `fallback` (else LSCM as it is).
    let mut lscm_start = |fallback: bool| -> Result<(Vec<[f64; 2]>, StartMap), FlattenError> {
        let mut uv = lscm::lscm(&positions, disc)?.uv;
        lscm_flipped = admissible(&mut uv);
        // With the barrier, the start must not overlap itself either.
        let usable = lscm_flipped == 0 && (!barrier || boundary_crossings(&uv, boundary) == 0);
        if usable || !fallback {
            Ok((uv, StartMap::Lscm))
        } else {
            Ok((tutte::mean_value(&positions, disc)?, StartMap::MeanValue))
        }
    };
    let (mut uv, start) = match &options.start {
        Start::Given(given) => {
            check_given_length(given, mesh)?;
            let mut uv = given.clone();
            if barrier && (admissible(&mut uv) > 0 || boundary_crossings(&uv, boundary) > 0) {
                (tutte::mean_value(&positions, disc)?, StartMap::MeanValue)
            } else {
                (given.clone(), StartMap::Given)
            }
        }
        Start::MeanValue => (tutte::mean_value(&positions, disc)?, StartMap::MeanValue),
        Start::Lscm => lscm_start(barrier)?,
        Start::Auto { multilevel: choice } => {
            if matches!(shared, SharedStart::NotTried) {
                *shared = match choice.coarse_level(mesh.triangles.len()) {
                    Some(coarse) => {
                        let (uv, report) = multilevel_start(mesh, disc, options, coarse);
                        SharedStart::Tried(uv, Box::new(report))
                    }
                    None => SharedStart::None,
                };
            }
            match shared {
                SharedStart::Tried(Some(uv), report)
                    if !barrier || boundary_crossings(uv, boundary) == 0 =>
                {
                    multilevel = Some(MultilevelReport::clone(report));
                    (uv.clone(), StartMap::Multilevel)
                }
                SharedStart::Tried(uv, report) => {
                    let mut report = MultilevelReport::clone(report);
                    if uv.is_some() {
                        report.abandoned =
                            Some("its boundary crosses itself (a barrier solve)".into());
                    }
                    multilevel = Some(report);
                    lscm_start(true)?
                }
                SharedStart::None | SharedStart::NotTried => lscm_start(true)?,
            }
        }
    };
    let start_flipped = admissible(&mut uv);
    // (A given start is the user's: it is solved from as given.) A multilevel start
    // whose coarse level needed the barrier leads to an overlapping minimum too
    // (measured: ICT faces opened with seams, BENCHMARKS.md "Hard discs"), so it goes
    // to the barrier solve at once; so does one whose coarse level was solved with the
    // barrier because its boundary runs along itself (seams).
    let coarse_overlapped =
        start == StartMap::Multilevel && multilevel.as_ref().is_some_and(|m| m.coarse_barrier);
    if solve == Solve::UnlessStartCrosses
        && start != StartMap::Given
        && start_flipped == 0
        && (coarse_overlapped || boundary_crossings(&uv, boundary) > 0)
    {
        return Ok(SolveOutcome::StartCrosses {
            time: clock.elapsed().as_secs_f64(),
        });
    }
    if start_flipped > 0 && matches!(start, StartMap::Given | StartMap::Multilevel) {
        return Err(FlattenError::GivenStartFlipped(start_flipped));
    }
    if start_flipped > 0 && matches!(options.start, Start::Lscm) {
        return Err(FlattenError::LscmFlipped(start_flipped));
    }
    if start_flipped > 0 {
        return Err(FlattenError::NoAdmissibleStart {
            lscm: lscm_flipped,
            mean_value: start_flipped,
        });
    }
    // Scale the start so its area matches the (unit) surface area: lengths scale by
    // √(area3D / areaUV) (the thesis's "ratio of the surface area versus the area of the
    // domain", §3.1.1, taken for lengths).
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
    // continuation (the coarse level did both).
    let objective = if start == StartMap::Multilevel {
        options.energy.without_continuation()
    } else {
        options.energy
    };
    // With the barrier, only a mean-value start (a circle, far from the minimum) is warm
    // started (measured: from LSCM it costs Newton iterations), and no warm-start step
    // may bring the boundary into contact.
    let pins = [(p0, 0), (p0, 1), (p1, 1)];
    // With the barrier from a crushed mean-value start (energy above
    // `SCAFFOLD_START_ENERGY`, no continuation): the scaffold iterations (SCAF with
    // progressive reference shapes, `scaffold`) instead of the barrier solve, whose
    // steps such a start cuts short at the first flip or contact.
    let crushed = barrier
        && start == StartMap::MeanValue
        && objective.continuation_start().is_none()
        && NewtonSolver::energy_of(&rest, &mesh.triangles)(&uv, &objective) > SCAFFOLD_START_ENERGY;
    if crushed {
        let time_start = clock.elapsed().as_secs_f64();
        let mut log = Vec::new();
        let stats = super::scaffold::solve(
            &mut uv,
            &mesh.triangles,
            &rest,
            boundary,
            &pins,
            &objective,
            clock,
            &mut |entry| {
                progress(&entry);
                log.push(entry);
            },
        )?;
        if let Some(stats) = stats {
            let stop = if stats.stalled {
                StopReason::Stalled
            } else {
                StopReason::IterationCap
            };
            let time_newton = clock.elapsed().as_secs_f64() - time_start;
            return result_of(
                &uv,
                mesh,
                boundary,
                scale,
                clock,
                Solved {
                    start,
                    lscm_flipped,
                    warm_start_iterations: 0,
                    iterations: stats.iterations,
                    stop,
                    energy: stats.energy,
                    barrier,
                    continuation: Vec::new(),
                    log,
                    time_start,
                    time_newton,
                    newton_timings: NewtonTimings::default(),
                    multilevel,
                },
            )
            .map(|map| SolveOutcome::Map(Box::new(map)));
        }
    }
    // A mean-value start for the barrier solve gets its ears opened before the warm
    // start, whose steps an ear flat on the circle would stop at once (after the
    // crushed-start test above: the scaffold is measured from the plain mean-value map).
    // Measured: ICT id002 opened with seams 29 → 16 barrier iterations, id000 12 → 11,
    // holes opened 14 → 13 (BENCHMARKS.md, "Hard discs").
    if barrier && start == StartMap::MeanValue {
        tutte::open_ears(&positions, disc, &mut uv);
    }
    if options.warm_start
        && start != StartMap::Multilevel
        && (!barrier || start == StartMap::MeanValue)
    {
        let contact =
            barrier.then(|| BoundaryBarrier::new(boundary, &uv).with_faces(&mesh.triangles));
        let first_energy = match objective.continuation_start() {
            Some(from) => Energy::litke(from),
            None => objective,
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
            let mut bound = max_flip_free_step(&uv, &mesh.triangles, &direction);
            if let Some(contact) = &contact {
                bound = bound.min(contact.max_step(&uv, &direction, bound.min(1.0)));
            }
            let mut step = 1.0f64.min(0.9 * bound);
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
    // A multilevel start's crushed boundary contacts (a coarse slit's tip, its
    // re-inserted sides a sliver apart) are opened by a local barrier solve first
    // (measured: the ICT face id000 opened with seams 17 → 5 barrier iterations,
    // BENCHMARKS.md "Hard discs"). It only shortens the solve: should its linear
    // algebra fail, the full solve starts from the start as it was.
    if barrier && start == StartMap::Multilevel {
        let mut relieved = uv.clone();
        if let Ok(Some(relief)) = super::relief::relieve_crushed_contacts(
            &mut relieved,
            &mesh.triangles,
            &rest,
            boundary,
            &objective,
            &options.newton,
        ) {
            uv = relieved;
            if let Some(report) = multilevel.as_mut() {
                report.relief = Some(relief);
            }
        }
    }
    let time_start = clock.elapsed().as_secs_f64();

    let mut solver = NewtonSolver::new(
        mesh.positions.len(),
        &mesh.triangles,
        rest,
        &pins,
        Some(&vertex_ordering),
    )?;
    if barrier {
        solver.set_barrier(BoundaryBarrier::new(boundary, &uv).with_faces(&mesh.triangles));
    } else if solve == Solve::UnlessStartCrosses {
        // The bijective mode solves again with the barrier when the result overlaps
        // itself; an iterate whose boundary crosses already says it will (BENCHMARKS.md,
        // "Hard discs"), so the rest of this solve would be spent for nothing. From a
        // multilevel start (whose coarse level is solved: near the minimum) one crossing
        // iterate says so: on the ICT faces opened with seams every such crossing lasted
        // to the end (measured, BENCHMARKS.md); from the other starts, transient
        // crossings happen ([`CROSSING_PERSISTENCE`]).
        let persistence = if start == StartMap::Multilevel {
            1
        } else {
            CROSSING_PERSISTENCE
        };
        solver.stop_when_boundary_crosses(boundary.to_vec(), persistence);
    }
    let mut log = Vec::new();
    let mut record = |entry: IterationLog| {
        progress(&entry);
        log.push(entry);
    };
    let mut iterations = 0;
    let mut continuation = Vec::new();
    let (stop, energy) = match &objective {
        Energy::Litke {
            alpha: target,
            from: Some(from),
        } => {
            // Continuation (§3.1.3): θ from 0 to 1, halving the step when a stage locks.
            // Stage 0 only prepares a start: a locked or capped stage 0 is still a
            // valid (flip-free) start for the next stage.
            let (stop0, it0, e0) =
                solver.minimize(&mut uv, from, &options.newton, 0, clock, &mut record)?;
            iterations += it0;
            continuation.push(from.alphas());
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
                if stop == StopReason::BoundaryCrossed {
                    uv = trial;
                    last = (stop, e);
                    break;
                }
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
        energy => {
            let (stop, it, e) =
                solver.minimize(&mut uv, energy, &options.newton, 0, clock, &mut record)?;
            iterations += it;
            (stop, e)
        }
    };
    let time_newton = clock.elapsed().as_secs_f64() - time_start;
    result_of(
        &uv,
        mesh,
        boundary,
        scale,
        clock,
        Solved {
            start,
            lscm_flipped,
            warm_start_iterations,
            iterations,
            stop,
            energy,
            barrier,
            continuation,
            log,
            time_start,
            time_newton,
            newton_timings: solver.timings,
            multilevel,
        },
    )
    .map(|map| SolveOutcome::Map(Box::new(map)))
}

/// What a solve of [`solve_disc`] did, for [`result_of`].
struct Solved {
    start: StartMap,
    lscm_flipped: usize,
    warm_start_iterations: usize,
    iterations: usize,
    stop: StopReason,
    energy: f64,
    barrier: bool,
    continuation: Vec<[f64; 3]>,
    log: Vec<IterationLog>,
    time_start: f64,
    time_newton: f64,
    newton_timings: NewtonTimings,
    multilevel: Option<MultilevelReport>,
}

/// The flattening of the solved map `uv` (normalized units; `scale` back to the
/// mesh's), with its flips and boundary crossings counted on it (`clock`: started with
/// the solve).
fn result_of(
    uv: &[[f64; 2]],
    mesh: &TriMesh,
    boundary: &[u32],
    scale: f64,
    clock: Instant,
    solved: Solved,
) -> Result<Flattening, FlattenError> {
    let flipped = count_flipped(uv, &mesh.triangles);
    if flipped > 0 {
        return Err(FlattenError::FlippedResult(flipped));
    }
    let crossings = boundary_crossings(uv, boundary);
    let uvs = uv.iter().map(|p| [p[0] * scale, p[1] * scale]).collect();
    Ok(Flattening {
        uvs,
        plan: Plan {
            holes_to_fill: 0,
            cut: None,
        },
        seams: None,
        start: solved.start,
        lscm_flipped: solved.lscm_flipped,
        warm_start_iterations: solved.warm_start_iterations,
        iterations: solved.iterations,
        converged: solved.stop == StopReason::Converged,
        stop_reason: solved.stop,
        energy: solved.energy,
        flipped_triangles: flipped,
        boundary_crossings: crossings,
        guarantee: if crossings == 0 {
            Guarantee::Bijective
        } else {
            Guarantee::LocallyInjective
        },
        barrier: solved.barrier,
        holes_filled: 0,
        continuation: solved.continuation,
        log: solved.log,
        time_prepare: 0.0,
        time_start: solved.time_start,
        time_newton: solved.time_newton,
        time_total: clock.elapsed().as_secs_f64(),
        newton_timings: solved.newton_timings,
        multilevel: solved.multilevel,
        distortion_cuts: None,
    })
}

/// The multilevel start (see [`super::multilevel`]) in the mesh's units, or `None`
/// (with the reason in the report) when any stage failed.
fn multilevel_start(
    mesh: &TriMesh,
    disc: &Disc,
    options: &FlattenOptions,
    coarse_level: &CoarseLevel,
) -> (Option<Vec<[f64; 2]>>, MultilevelReport) {
    use crate::mesh::decimate::{DecimateOptions, decimate_with};
    let mut report = MultilevelReport::default();
    let clock = Instant::now();
    let run = |report: &mut MultilevelReport| -> Result<Vec<[f64; 2]>, String> {
        let coarse_size = coarse_level.size_for(mesh.positions.len());
        if mesh.positions.len() < 2 * coarse_size {
            return Err(format!(
                "the mesh has {} vertices, not even twice the {coarse_size} of the coarse level",
                mesh.positions.len(),
            ));
        }
        let decimation = decimate_with(
            &mesh.positions,
            disc,
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
            start: Start::Auto {
                multilevel: Multilevel::Never,
            },
            // Overlap-free on the coarse level unless overlap is allowed, so that a
            // barrier solve can start from it too (the full mesh's solve checks and
            // prevents overlap in any case). Where the boundary runs along itself in 3D
            // (the two sides of a seam) it is solved with the barrier outright: the coarse
            // map then keeps the sides of each slit apart by the barrier's reach (a
            // quarter of a coarse boundary edge), room for the re-inserted vertices
            // between them; without it the coarse mouth of the ICT face id000 opened
            // with seams closed to a slit whose re-inserted lips crossed (the start
            // was abandoned), and id003 / id005 took 11 / 15 fine barrier iterations
            // against 6 / 9 (BENCHMARKS.md, "Hard discs").
            bijective: if options.bijective == Bijective::WhenOverlapping
                && boundary_runs_along_itself(&mesh.positions, disc.boundary())
            {
                Bijective::Always
            } else {
                options.bijective
            },
            max_distortion: None,
            ..options.clone()
        };
        let flat = flatten(&coarse, &coarse_options).map_err(|e| format!("coarse mesh: {e}"))?;
        report.coarse_iterations = flat.iterations;
        report.coarse_barrier = flat.barrier;
        report.coarse_continuation = flat.continuation;
        report.time_coarse = clock.elapsed().as_secs_f64() - report.time_decimate;
        let mut uv = vec![[f64::NAN; 2]; mesh.positions.len()];
        for (c, &v) in original_of_coarse.iter().enumerate() {
            uv[v as usize] = flat.uvs[c];
        }
        report.prolongation = super::multilevel::prolongate(
            &mesh.positions,
            &decimation,
            // Kept from crossing itself where the result must not overlap.
            if options.bijective == Bijective::Off {
                &[]
            } else {
                disc.boundary()
            },
            &mut uv,
            &options.energy,
            coarse_level.polish_steps,
            coarse_level.sweeps,
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

/// Whether the boundary runs along itself in 3D: a boundary edge whose reverse, from
/// the same point to the same point, is a boundary edge too (the two sides of a seam
/// edge, split into copies by [`crate::mesh::cut::open_along`] or by whoever cut the
/// mesh). A single point where the boundary touches itself (beetle.off: two loops meet
/// at one vertex) is not a seam.
fn boundary_runs_along_itself(positions: &[[f64; 3]], boundary: &[u32]) -> bool {
    let n = boundary.len();
    let at = |k: usize| positions[boundary[k % n] as usize].map(f64::to_bits);
    let edges: std::collections::HashSet<_> = (0..n).map(|k| (at(k), at(k + 1))).collect();
    (0..n).any(|k| edges.contains(&(at(k + 1), at(k))))
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

/// Mean energy density of a mean-value start above which the bijective solve uses the
/// scaffold ([`super::scaffold`]) instead of the barrier solve. Measured (balanced α,
/// isometry ≈ 2): `elephant_holes.off` cut open 2.1·10⁷ (barrier solve: 200 iterations,
/// capped); `holes.off` and `ict_neutral.obj` cut open 138 and 124 (barrier solve: 22
/// and 19 iterations; the scaffold took 28 and 38).
const SCAFFOLD_START_ENERGY: f64 = 1e4;

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
    use crate::energy::Alpha;
    use crate::mesh::generate::{bumpy_disc, grid_disc};
    use crate::mesh::repair::{fill_holes, reorient};

    #[test]
    fn inconsistent_orientation_is_refused_with_advice_and_reorient_fixes_it() {
        let mut mesh = bumpy_disc(6, 0.3);
        mesh.triangles[40].swap(1, 2);
        let err = flatten(&mesh, &FlattenOptions::default()).unwrap_err();
        assert!(matches!(err, FlattenError::NotADisc(_)), "{err}");
        assert!(err.to_string().contains("repair::reorient"), "{err}");
        let (fixed, flipped) = reorient(&mesh).unwrap();
        assert_eq!(flipped, 1);
        let map = flatten(&fixed, &FlattenOptions::default()).unwrap();
        assert_eq!(map.flipped_triangles, 0);
    }

    #[test]
    fn a_boundary_running_along_itself_is_a_seam_and_a_touching_point_is_not() {
        // A torus cut into a disc: every seam edge is on the boundary twice, reversed.
        let torus = crate::mesh::generate::torus(2.0, 0.5, 12, 8);
        let opened = crate::mesh::cut::cut_to_disc(&torus).unwrap();
        let disc = Disc::new(&opened.mesh).unwrap();
        assert!(boundary_runs_along_itself(
            &opened.mesh.positions,
            disc.boundary()
        ));
        // A plain disc does not.
        let plain = grid_disc(6);
        let disc = Disc::new(&plain).unwrap();
        assert!(!boundary_runs_along_itself(
            &plain.positions,
            disc.boundary()
        ));
        // Nor a loop that passes one point twice (a pinch, like where two of
        // beetle.off's loops meet at a vertex).
        let p = |x: f64, y: f64| [x, y, 0.0];
        let positions = [
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(2.0, -1.0),
            p(2.0, 1.0),
            p(1.0, 0.0),
            p(0.0, 1.0),
        ];
        assert!(!boundary_runs_along_itself(&positions, &[0, 1, 2, 3, 4, 5]));
        // ... but the same edge walked back is: 0 → 1 → 2 → 3 (= 1) → 4 (= 0).
        let positions = [
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(2.0, 1.0),
            p(1.0, 0.0),
            p(0.0, 0.0),
        ];
        assert!(boundary_runs_along_itself(&positions, &[0, 1, 2, 3, 4]));
    }

    #[test]
    fn unreferenced_vertices_are_carried_through() {
        let mut mesh = bumpy_disc(5, 0.3);
        mesh.positions.push([9.0, 9.0, 9.0]);
        let map = flatten(&mesh, &FlattenOptions::default()).unwrap();
        assert_eq!(map.uvs.len(), mesh.positions.len());
        assert_eq!(map.uvs[mesh.positions.len() - 1], [0.0, 0.0]);
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
            &FlattenOptions::default().with_start(Start::Given(first.uvs.clone())),
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
            &FlattenOptions::default().with_start(Start::Given(folded)),
        )
        .unwrap_err();
        assert!(
            matches!(err, FlattenError::GivenStartFlipped(n) if n >= 1),
            "{err}"
        );
        let err = flatten(
            &mesh,
            &FlattenOptions::default().with_start(Start::Given(vec![[0.0; 2]; 3])),
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
                FlattenError::Index(IndexError {
                    triangle: 2,
                    corner: 1,
                    vertex: 10_000,
                    ..
                })
            ),
            "{err}"
        );
        // Also with holes to fill (the fill needs the topology, hence valid indices).
        let err = flatten(&mesh, &FlattenOptions::default().with_fill_holes(true)).unwrap_err();
        assert!(matches!(err, FlattenError::Index(_)), "{err}");
    }

    /// A grid disc with two interior faces' stars removed: three boundary loops.
    fn disc_with_two_holes() -> TriMesh {
        let mut mesh = grid_disc(8);
        // Vertices (2, 2) and (5, 4) of the 9×9 grid, index j·9 + i.
        let holes = [2 * 9 + 2, 4 * 9 + 5];
        mesh.triangles
            .retain(|t| !holes.iter().any(|h| t.contains(h)));
        mesh
    }

    #[test]
    fn holes_are_filled_for_the_solve_and_stay_open_in_the_map() {
        let mesh = disc_with_two_holes();
        let never = FlattenOptions::default()
            .with_fill_holes(false)
            .with_cut(Cut::Never);
        let err = flatten(&mesh, &never).unwrap_err();
        assert!(err.to_string().contains("fill_holes"), "{err}");
        let map = flatten(&mesh, &FlattenOptions::default()).unwrap();
        assert_eq!(map.plan.describe(), "fill 2 holes");
        assert!(map.seams.is_none());
        assert_eq!(map.holes_filled, 2);
        assert_eq!(map.uvs.len(), mesh.positions.len());
        assert_eq!(count_flipped(&map.uvs, &mesh.triangles), 0);
        // The same as filling by hand and dropping the fill's vertices.
        let (filled, holes) = fill_holes(&mesh);
        assert_eq!(holes, 2);
        let by_hand = flatten(&filled, &FlattenOptions::default()).unwrap();
        assert_eq!(&by_hand.uvs[..mesh.positions.len()], &map.uvs[..]);
        // A planar grid flattens to an isometry: hole or not, every edge keeps its length.
        for t in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
                let l3 =
                    crate::vec3::norm3(crate::vec3::sub3(mesh.positions[a], mesh.positions[b]));
                let l2 = (map.uvs[a][0] - map.uvs[b][0]).hypot(map.uvs[a][1] - map.uvs[b][1]);
                assert!((l2 - l3).abs() < 1e-6 * l3, "{l2} vs {l3}");
            }
        }
        // Without holes the option changes nothing.
        let plain = grid_disc(4);
        let a = flatten(&plain, &FlattenOptions::default()).unwrap();
        let b = flatten(&plain, &FlattenOptions::default().with_fill_holes(true)).unwrap();
        assert_eq!((a.uvs, b.holes_filled), (b.uvs, 0));
        // A given start has no UVs for the fill.
        let err = flatten(
            &mesh,
            &FlattenOptions::default()
                .with_fill_holes(true)
                .with_start(Start::Given(map.uvs.clone())),
        )
        .unwrap_err();
        assert!(
            matches!(err, FlattenError::GivenStartWithFilledHoles(2)),
            "{err}"
        );
    }

    #[test]
    fn normalized_uvs_fit_the_unit_square() {
        let mesh = bumpy_disc(6, 0.3);
        let map = flatten(&mesh, &FlattenOptions::default()).unwrap();
        let n = map.normalized_uvs();
        let (lo, hi) = n
            .iter()
            .fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), p| {
                (
                    [lo[0].min(p[0]), lo[1].min(p[1])],
                    [hi[0].max(p[0]), hi[1].max(p[1])],
                )
            });
        assert_eq!(lo, [0.0, 0.0]);
        assert!((hi[0].max(hi[1]) - 1.0).abs() < 1e-15, "{hi:?}");
        // One translation and one scale: UV edges keep their directions and ratios.
        let s = (n[1][0] - n[0][0]) / (map.uvs[1][0] - map.uvs[0][0]);
        for (p, q) in n.iter().zip(&map.uvs) {
            let d = [p[0] - n[0][0], p[1] - n[0][1]];
            let e = [q[0] - map.uvs[0][0], q[1] - map.uvs[0][1]];
            assert!((d[0] - s * e[0]).abs() < 1e-12 && (d[1] - s * e[1]).abs() < 1e-12);
        }
    }

    #[test]
    fn an_explicit_start_is_single_level_and_options_are_checked() {
        let mesh = bumpy_disc(4, 0.3);
        for (start, used) in [
            (Start::Lscm, StartMap::Lscm),
            (Start::MeanValue, StartMap::MeanValue),
        ] {
            let map = flatten(&mesh, &FlattenOptions::default().with_start(start)).unwrap();
            assert_eq!((map.start, map.multilevel.is_none()), (used, true));
        }
        let always = Start::Auto {
            multilevel: Multilevel::Always(CoarseLevel::with_vertices(30)),
        };
        let map = flatten(&mesh, &FlattenOptions::default().with_start(always)).unwrap();
        assert_eq!(map.start, StartMap::Multilevel);
        assert_eq!(map.multilevel.as_ref().unwrap().coarse_vertices, 30);
        let bad = |o: FlattenOptions| flatten(&mesh, &o).unwrap_err().to_string();
        let mut o = FlattenOptions::default();
        o.newton.tolerance = 0.0;
        assert!(bad(o).contains("tolerance"));
        let mut o = FlattenOptions::default();
        o.newton.armijo_c = 1.0;
        assert!(bad(o).contains("armijo_c"));
        let o = FlattenOptions::default().with_start(Start::Auto {
            multilevel: Multilevel::Auto(CoarseLevel::with_vertices(3)),
        });
        assert!(bad(o).contains("CoarseLevel::vertices must be at least 16, got 3"));
    }

    #[test]
    fn continuation_reaches_the_target_alpha() {
        let mesh = bumpy_disc(5, 0.3);
        let energy = Energy::litke(Alpha::length())
            .with_continuation(Alpha::conformal())
            .unwrap();
        let map = flatten(&mesh, &FlattenOptions::new(energy)).unwrap();
        assert_eq!(map.continuation.first(), Some(&Alpha::conformal().alphas()));
        assert_eq!(map.continuation.last(), Some(&Alpha::length().alphas()));
        let direct = flatten(&mesh, &FlattenOptions::new(Alpha::length())).unwrap();
        assert!(direct.continuation.is_empty());
        assert!((map.energy - direct.energy).abs() <= 1e-9 * direct.energy);
    }
}
