//! What a flattening is asked to do: [`FlattenOptions`] (the energy, the start, the
//! warm start, Newton's settings, holes, cuts, the bijective mode, a distortion bound)
//! and its checks ([`FlattenOptions::validate`], [`OptionError`]).

use crate::energy::Energy;
use crate::param::newton::NewtonSettings;
use crate::param::optcuts::MaxDistortion;
use crate::param::plan::Cut;

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
    /// This map: one UV per vertex in the mesh's length units (as [`Flattening::uvs`](super::Flattening::uvs)),
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

/// When [`Start::Auto`] uses the multilevel start ([`crate::param::multilevel`]): flatten a
/// decimated copy, re-insert the removed vertices flip-free, then run Newton on the full
/// mesh from there. If any stage fails, the single-level start is used (and the report
/// says why).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Multilevel {
    /// For meshes of at least 15 000 faces (`MULTILEVEL_MIN_FACES`).
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
    /// Vertices of the decimated copy (at least 16); `None`: 1/20 of the mesh, between
    /// 500 and 20 000 ([`CoarseLevel::size_for`]).
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
            polish_steps: crate::param::multilevel::DEFAULT_POLISH_STEPS,
            sweeps: crate::param::multilevel::DEFAULT_SWEEPS,
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
pub(crate) const MULTILEVEL_MIN_FACES: usize = 15_000;
pub(crate) const MULTILEVEL_MIN_COARSE_VERTICES: usize = 500;
pub(crate) const MULTILEVEL_MAX_COARSE_VERTICES: usize = 20_000;
/// The smallest coarse level one may ask for ([`CoarseLevel::vertices`]).
pub(crate) const MIN_COARSE_VERTICES: usize = 16;

/// When the flattening keeps the boundary from overlapping itself with the boundary
/// barrier ([`crate::param::barrier`]; Smith & Schaefer 2015): a flip-free map of a disc is
/// injective exactly when its boundary does not cross itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Bijective {
    /// Never: the result is flip-free (locally injective); its boundary may overlap
    /// itself ([`Flattening::boundary_crossings`](super::Flattening::boundary_crossings) says
    /// whether it does).
    Off,
    /// Solve as with `Off`; if the boundary of the result crosses itself, solve again
    /// with the barrier from a crossing-free start. Costs nothing where there is no
    /// overlap, and the result is the same as with `Off` there.
    #[default]
    WhenOverlapping,
    /// Always solve with the barrier, from a crossing-free start (LSCM if it is
    /// flip-free and crossing-free, else mean-value coordinates onto a circle; when
    /// that start is crushed, scaffold iterations instead of the barrier solve,
    /// [`crate::param::scaffold`]).
    Always,
}

/// Options of [`flatten`](super::flatten).
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
    /// filled) is cut open along seams ([`crate::param::plan`]; default: [`Cut::Auto`]).
    pub cut: Cut,
    /// Whether the boundary is kept from overlapping itself (default:
    /// [`Bijective::WhenOverlapping`]).
    pub bijective: Bijective,
    /// A bound on the distortion: while the map's mean symmetric Dirichlet distortion
    /// exceeds it, cut the chart open where the distortion concentrates and flatten
    /// again ([`crate::param::optcuts`]; default: none, one chart as it comes).
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

    /// Checks the numeric settings (called by [`flatten`](super::flatten)).
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
