//! `flatten(V, F, …)`: the one-call flattening with the command line's options as
//! keywords, returning the UVs and the report `surfmap flatten --report` writes: one UV
//! per vertex, or, when the call lets the surface be cut open (`cut`, `seams`,
//! `max_distortion`), per-corner UVs as the command line's OBJ writes them.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use surfmap::{
    Cut, EnergyKind, FlattenOptions, FlattenSettings, MaxDistortion, MultilevelKind, Preset,
    SettingsError, StartKind, UvLayout,
};

use crate::advice::{defect_message, option_message};
use crate::arrays;
use crate::convert::to_dict;
use crate::errors::flatten_error;

/// The flattening keywords shared by `flatten`, `flatten_file` and `flatten_many`, with
/// the command line's defaults (`surfmap flatten --help` describes each).
#[derive(Clone, Debug)]
pub struct FlattenArgs {
    /// The solver's: preset or α, energy, continuation, start, Newton's numbers.
    pub settings: FlattenSettings,
    /// `None`: filled when holes are not cut (`cut="auto"`), else not.
    pub fill_holes: Option<bool>,
    /// `"never"`, `"auto"` or `"holes"`; `None`: `"never"` unless `seams` or
    /// `max_distortion` ask for cuts, then `"auto"`.
    pub cut: Option<String>,
    /// The caller's seams (vertex pairs joined by an edge) instead of the automatic cut.
    pub seams: Option<Vec<[u32; 2]>>,
    pub max_distortion: Option<f64>,
    pub max_cut_rounds: usize,
    pub normalize: bool,
}

impl Default for FlattenArgs {
    fn default() -> Self {
        Self {
            settings: FlattenSettings::default(),
            fill_holes: None,
            cut: None,
            seams: None,
            max_distortion: None,
            max_cut_rounds: surfmap::param::optcuts::DEFAULT_MAX_ROUNDS,
            normalize: false,
        }
    }
}

/// `name` must name one of `choices` (`name_of` gives their names; the error lists
/// them).
fn choice<T: Copy>(
    what: &str,
    name: &str,
    choices: &[T],
    name_of: fn(T) -> &'static str,
) -> PyResult<T> {
    choices
        .iter()
        .copied()
        .find(|&c| name_of(c).eq_ignore_ascii_case(name))
        .ok_or_else(|| {
            PyValueError::new_err(format!(
                "unknown {what} {name:?}; choose one of {}",
                choices
                    .iter()
                    .map(|&c| format!("{:?}", name_of(c)))
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
}

/// The preset named `name`.
fn preset(name: &str) -> PyResult<Preset> {
    choice("preset", name, &Preset::ALL, Preset::name)
}

/// The energy named `name`.
fn energy(name: &str) -> PyResult<EnergyKind> {
    choice("energy", name, &EnergyKind::ALL, EnergyKind::name)
}

/// The start named `name`.
fn start(name: &str) -> PyResult<StartKind> {
    choice("start", name, &StartKind::ALL, StartKind::name)
}

/// The multilevel choice named `name`.
fn multilevel(name: &str) -> PyResult<MultilevelKind> {
    choice(
        "multilevel",
        name,
        &MultilevelKind::ALL,
        MultilevelKind::name,
    )
}

/// Weights `(L, A, C)` given as any sequence of three numbers, or None.
pub fn weights(name: &str, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<[f64; 3]>> {
    match obj {
        None => Ok(None),
        Some(o) if o.is_none() => Ok(None),
        Some(o) => o.extract::<[f64; 3]>().map(Some).map_err(|_| {
            let shown = o.repr().map_or_else(|_| "?".to_owned(), |r| r.to_string());
            PyValueError::new_err(format!(
                "{name} must be three numbers (length, area, angle weights), e.g. (1, 1, 2); got {shown}"
            ))
        }),
    }
}

/// Settings that make no options, as the keywords that set them.
fn settings_message(e: SettingsError) -> PyErr {
    PyValueError::new_err(match e {
        SettingsError::Alpha(e) => format!("alpha: {e}"),
        SettingsError::FromAlpha(e) => format!("from_alpha: {e}"),
        SettingsError::Continuation(e) => format!("from_alpha: {e}"),
        SettingsError::MultilevelNeedsAutoStart => "multilevel=\"on\" needs start=\"auto\" (an explicit start map is computed on the full mesh)".to_owned(),
        SettingsError::Option(e) => option_message(&e),
    })
}

impl FlattenArgs {
    /// The keyword names, in signature order.
    pub const NAMES: [&'static str; 16] = [
        "preset",
        "alpha",
        "energy",
        "from_alpha",
        "start",
        "multilevel",
        "coarse_vertices",
        "fill_holes",
        "cut",
        "seams",
        "max_distortion",
        "max_cut_rounds",
        "max_iters",
        "tolerance",
        "armijo_c",
        "normalize",
    ];

    /// The keywords of a `**options` dictionary; an unknown name is a `ValueError`
    /// listing the known ones.
    pub fn from_kwargs(kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let mut a = Self::default();
        let Some(kwargs) = kwargs else {
            return Ok(a);
        };
        for (key, value) in kwargs.iter() {
            let key: String = key.extract()?;
            let bad = |e: PyErr| PyValueError::new_err(format!("option {key}: {e}"));
            match key.as_str() {
                "preset" => a.settings.preset = preset(&value.extract::<String>().map_err(bad)?)?,
                "alpha" => a.settings.alpha = weights("alpha", Some(&value))?,
                "energy" => a.settings.energy = energy(&value.extract::<String>().map_err(bad)?)?,
                "from_alpha" => a.settings.from_alpha = weights("from_alpha", Some(&value))?,
                "start" => a.settings.start = start(&value.extract::<String>().map_err(bad)?)?,
                "multilevel" => {
                    a.settings.multilevel = multilevel(&value.extract::<String>().map_err(bad)?)?
                }
                "coarse_vertices" => a.settings.coarse_vertices = value.extract().map_err(bad)?,
                "fill_holes" => a.fill_holes = value.extract().map_err(bad)?,
                "cut" => a.cut = value.extract().map_err(bad)?,
                "seams" => a.seams = seams(Some(&value))?,
                "max_distortion" => a.max_distortion = value.extract().map_err(bad)?,
                "max_cut_rounds" => a.max_cut_rounds = value.extract().map_err(bad)?,
                "max_iters" => a.settings.max_iterations = value.extract().map_err(bad)?,
                "tolerance" => a.settings.tolerance = value.extract().map_err(bad)?,
                "armijo_c" => a.settings.armijo_c = value.extract().map_err(bad)?,
                "normalize" => a.normalize = value.extract().map_err(bad)?,
                other => {
                    return Err(PyValueError::new_err(format!(
                        "unknown option {other:?}; the flattening options are {}",
                        Self::NAMES.join(", ")
                    )));
                }
            }
        }
        Ok(a)
    }

    /// The library options these keywords ask for (the command line's flags map onto
    /// the same [`FlattenSettings`]), checked; the cut and holes as [`Self::cut_mode`]
    /// says.
    pub fn options(&self) -> PyResult<FlattenOptions> {
        let (fill_holes, cut) = self.cut_and_fill()?;
        let mut opts = self
            .settings
            .options()
            .map_err(settings_message)?
            .with_fill_holes(fill_holes)
            .with_cut(cut);
        opts.max_distortion = self.max_distortion.map(|bound| MaxDistortion {
            bound,
            max_rounds: self.max_cut_rounds,
        });
        opts.validate()
            .map_err(|e| PyValueError::new_err(option_message(&e)))?;
        Ok(opts)
    }

    /// How the map is returned or written.
    pub fn layout(&self) -> UvLayout {
        UvLayout {
            normalize: self.normalize,
            uv_as_positions: false,
        }
    }
}

impl FlattenArgs {
    /// The cut asked for: `"never"` (one UV per vertex; a surface that is not a disc,
    /// once its holes are filled if asked, is refused), `"auto"` (holes filled unless
    /// `fill_holes=False`, the rest cut open along seams) or `"holes"` (holes cut open
    /// too). Unset, cutting options (`seams`, `max_distortion`) make it `"auto"`.
    pub fn cut_mode(&self) -> PyResult<&'static str> {
        let asks_for_cuts = self.seams.is_some() || self.max_distortion.is_some();
        let Some(cut) = &self.cut else {
            return Ok(if asks_for_cuts { "auto" } else { "never" });
        };
        let mode = choice("cut", cut, &["never", "auto", "holes"], |c| c)?;
        if mode == "never" && asks_for_cuts {
            let what = if self.seams.is_some() {
                "seams"
            } else {
                "max_distortion"
            };
            return Err(PyValueError::new_err(format!(
                "{what} cuts the surface open, but cut=\"never\"; pass cut=\"auto\" (or leave cut unset): the result then has per-corner UVs (UV, FUV, report)"
            )));
        }
        Ok(mode)
    }

    /// Whether the result is returned per corner (`(UV, FUV, report)`): the surface may
    /// be cut.
    pub fn per_corner(&self) -> PyResult<bool> {
        Ok(self.cut_mode()? != "never")
    }

    /// Whether holes are filled for the solve, and the library's cut.
    fn cut_and_fill(&self) -> PyResult<(bool, Cut)> {
        let mode = self.cut_mode()?;
        let fill_holes = match (mode, self.fill_holes) {
            ("holes", Some(true)) => {
                return Err(PyValueError::new_err(
                    "fill_holes=True fills the holes that cut=\"holes\" opens with seams; give one of them",
                ));
            }
            ("holes", _) => false,
            ("auto", fill) => fill.unwrap_or(true),
            (_, fill) => fill.unwrap_or(false),
        };
        let cut = match (&self.seams, mode) {
            (Some(seams), _) => Cut::Along(seams.clone()),
            (None, "never") => Cut::Never,
            (None, _) => Cut::Auto,
        };
        Ok((fill_holes, cut))
    }
}

/// Seams given as a (k, 2) integer array of vertex pairs (or None).
pub fn seams(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Vec<[u32; 2]>>> {
    match obj {
        None => Ok(None),
        Some(o) if o.is_none() => Ok(None),
        Some(o) => arrays::edges(o, "seams").map(Some),
    }
}

/// Flattens a mesh to the plane without flipped triangles (Litke's projected Newton,
/// thesis §3.1) and reports the result.
///
/// V: (n, 3) float array of vertex positions; F: (m, 3) integer array of
/// counter-clockwise triangles. Keywords are the options of `surfmap flatten`:
/// ``preset`` ("conformal", "balanced", "area", "length") or ``alpha=(L, A, C)``
/// (length, area, angle weights of the energy (2.5), normalized to sum 1);
/// ``energy`` ("litke", "sd", "mips", "arap"); ``from_alpha`` (continuation start);
/// ``start`` ("auto", "lscm", "mean_value"); ``multilevel`` ("auto", "on", "off") and
/// ``coarse_vertices``; ``fill_holes`` (fill all boundary loops but the longest for the
/// solve; they stay open in the map); ``cut``, ``seams``, ``max_distortion`` and
/// ``max_cut_rounds`` (below); Newton's ``max_iters``, ``tolerance`` and
/// ``armijo_c``; ``normalize`` (return UVs scaled into [0, 1]²).
///
/// Returns ``(UV, report)``: UV is an (n, 2) float64 array, one row per vertex, in the
/// mesh's length units (vertices no triangle uses are at the origin); report is the
/// dictionary of ``surfmap flatten --report`` (start, iterations, energy, measures, the
/// Newton log, …; ``input`` is None). The solve releases the GIL, so threads flatten
/// meshes in parallel. Without ``cut`` the surface is never cut open: a closed surface,
/// one with handles, or one with holes (unless ``fill_holes=True``) raises ``MeshError``.
///
/// **Cutting.** ``cut="auto"`` flattens any connected, orientable, manifold mesh as the
/// command line does: holes are filled for the solve (unless ``fill_holes=False``), a
/// closed or higher-genus surface is cut open into a disc along seams. ``cut="holes"``
/// opens the holes with seams to the outer boundary instead of filling them.
/// ``seams`` ((k, 2) integer array of vertex pairs joined by an edge) cuts along these
/// edges instead of the automatic cut graph. ``max_distortion=D`` cuts the chart
/// open where the distortion concentrates until its mean symmetric Dirichlet
/// distortion (area-weighted mean of (σ1² + σ2² + σ1⁻² + σ2⁻²)/4 with UV area = 3D
/// area; 1 for an isometry) is at most D, in at most ``max_cut_rounds`` rounds (the
/// best map is returned either way; ``report["distortion_cuts"]["met"]`` says whether
/// the bound holds). ``seams`` or ``max_distortion`` alone imply ``cut="auto"``.
///
/// With any of them the result is per corner, ``(UV, FUV, report)`` — as an OBJ file's
/// ``vt`` and ``f v/vt``: UV is a (k, 2) float64 array (a vertex on a seam has one row
/// per side), FUV an (m, 3) int64 array, corner ``j`` of triangle ``t`` having UV
/// ``UV[FUV[t, j]]``. A surface that needed no cut gives one row per vertex and FUV
/// equal to F. The seams are ``report["seams"]`` (``edges``: vertex pairs of V,
/// ``length``, ``reason``), None when nothing was cut; ``report["plan"]`` says what was
/// done and ``report["guarantee"]`` whether the map is bijective.
///
/// Raises ``MeshError`` when the mesh cannot be flattened as asked (``err.defects``
/// lists why, each with its repair), ``ValueError`` for bad arrays, options or seams,
/// ``SolverError`` when the solve fails.
///
/// >>> import numpy as np, surfmap
/// >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0.2], [0, 1, 0]], dtype=float)
/// >>> F = np.array([[0, 1, 2], [0, 2, 3]])
/// >>> UV, report = surfmap.flatten(V, F)
/// >>> UV.shape, report["flipped_triangles"], report["converged"]
/// ((4, 2), 0, True)
/// >>> V = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [0, 0, -1]], dtype=float)
/// >>> F = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1], [5, 2, 1], [5, 3, 2], [5, 4, 3], [5, 1, 4]])
/// >>> UV, FUV, report = surfmap.flatten(V, F, cut="auto")  # a closed octahedron, cut open
/// >>> FUV.shape, len(UV) > len(V), report["plan"], report["guarantee"]
/// ((8, 3), True, 'cut open along seams (closed, genus 0)', 'bijective')
#[pyfunction]
#[pyo3(signature = (V, F, *, preset="balanced", alpha=None, energy="litke", from_alpha=None,
    start="auto", multilevel="auto", coarse_vertices=None, fill_holes=None, cut=None,
    seams=None, max_distortion=None, max_cut_rounds=30, max_iters=200, tolerance=1e-12,
    armijo_c=0.5, normalize=false))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn flatten<'py>(
    py: Python<'py>,
    V: &Bound<'py, PyAny>,
    F: &Bound<'py, PyAny>,
    preset: &str,
    alpha: Option<&Bound<'py, PyAny>>,
    energy: &str,
    from_alpha: Option<&Bound<'py, PyAny>>,
    start: &str,
    multilevel: &str,
    coarse_vertices: Option<usize>,
    fill_holes: Option<bool>,
    cut: Option<String>,
    seams: Option<&Bound<'py, PyAny>>,
    max_distortion: Option<f64>,
    max_cut_rounds: usize,
    max_iters: usize,
    tolerance: f64,
    armijo_c: f64,
    normalize: bool,
) -> PyResult<Bound<'py, PyTuple>> {
    let args = FlattenArgs {
        settings: FlattenSettings {
            preset: self::preset(preset)?,
            alpha: weights("alpha", alpha)?,
            energy: self::energy(energy)?,
            from_alpha: weights("from_alpha", from_alpha)?,
            start: self::start(start)?,
            multilevel: self::multilevel(multilevel)?,
            coarse_vertices,
            max_iterations: max_iters,
            tolerance,
            armijo_c,
        },
        fill_holes,
        cut,
        seams: self::seams(seams)?,
        max_distortion,
        max_cut_rounds,
        normalize,
    };
    let options = args.options()?;
    let mesh = arrays::mesh(V, F)?;
    let flat = py
        .detach(|| surfmap::flatten_to_mesh(mesh, &options, args.layout(), &mut |_| {}))
        .map_err(flatten_error)?;
    let report = {
        let report = py
            .detach(|| flat.report(None, defect_message))
            .map_err(crate::errors::measure_error)?;
        to_dict(py, &report)?
    };
    let (uv, fuv) = flat.uv_arrays();
    let uv = arrays::array(py, uv.to_vec()).into_any();
    if args.per_corner()? {
        let fuv = arrays::triangle_array(py, fuv).into_any();
        PyTuple::new(py, [uv, fuv, report.into_any()])
    } else {
        PyTuple::new(py, [uv, report.into_any()])
    }
}
