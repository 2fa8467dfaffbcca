//! `flatten(V, F, …)`: the one-call flattening with the command line's options as
//! keywords, returning the UVs and the report `surfmap flatten --report` writes.

use numpy::PyArray2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use surfmap::{Alpha, CoarseLevel, Cut, Energy, FlattenOptions, FlattenReport, Multilevel, Start};

use crate::advice::{defect_message, option_message};
use crate::arrays;
use crate::convert::to_dict;
use crate::errors::flatten_error;

/// The flattening keywords shared by `flatten`, `flatten_file` and `flatten_many`, with
/// the command line's defaults (`surfmap flatten --help` describes each).
#[derive(Clone, Debug)]
pub struct FlattenArgs {
    pub preset: String,
    pub alpha: Option<[f64; 3]>,
    pub energy: String,
    pub from_alpha: Option<[f64; 3]>,
    pub start: String,
    pub multilevel: String,
    pub coarse_vertices: Option<usize>,
    pub fill_holes: bool,
    pub max_iters: usize,
    pub tolerance: f64,
    pub armijo_c: f64,
    pub normalize: bool,
}

impl Default for FlattenArgs {
    fn default() -> Self {
        Self {
            preset: "balanced".into(),
            alpha: None,
            energy: "litke".into(),
            from_alpha: None,
            start: "auto".into(),
            multilevel: "auto".into(),
            coarse_vertices: None,
            fill_holes: false,
            max_iters: 200,
            tolerance: 1e-12,
            armijo_c: 0.5,
            normalize: false,
        }
    }
}

/// `name` must be one of `choices` (the error lists them).
fn choice<'a>(what: &str, name: &str, choices: &[&'a str]) -> PyResult<&'a str> {
    choices
        .iter()
        .find(|c| c.eq_ignore_ascii_case(name))
        .copied()
        .ok_or_else(|| {
            PyValueError::new_err(format!(
                "unknown {what} {name:?}; choose one of {}",
                choices
                    .iter()
                    .map(|c| format!("{c:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
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

fn alpha(what: &str, a: [f64; 3]) -> PyResult<Alpha> {
    Alpha::new(a[0], a[1], a[2]).map_err(|e| PyValueError::new_err(format!("{what}: {e}")))
}

impl FlattenArgs {
    /// The keyword names, in signature order.
    pub const NAMES: [&'static str; 12] = [
        "preset",
        "alpha",
        "energy",
        "from_alpha",
        "start",
        "multilevel",
        "coarse_vertices",
        "fill_holes",
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
                "preset" => a.preset = value.extract().map_err(bad)?,
                "alpha" => a.alpha = weights("alpha", Some(&value))?,
                "energy" => a.energy = value.extract().map_err(bad)?,
                "from_alpha" => a.from_alpha = weights("from_alpha", Some(&value))?,
                "start" => a.start = value.extract().map_err(bad)?,
                "multilevel" => a.multilevel = value.extract().map_err(bad)?,
                "coarse_vertices" => a.coarse_vertices = value.extract().map_err(bad)?,
                "fill_holes" => a.fill_holes = value.extract().map_err(bad)?,
                "max_iters" => a.max_iters = value.extract().map_err(bad)?,
                "tolerance" => a.tolerance = value.extract().map_err(bad)?,
                "armijo_c" => a.armijo_c = value.extract().map_err(bad)?,
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

    /// The library options these keywords ask for (the same mapping as the command
    /// line's flags), checked.
    pub fn options(&self) -> PyResult<FlattenOptions> {
        let target = match self.alpha {
            Some(a) => alpha("alpha", a)?,
            None => match choice(
                "preset",
                &self.preset,
                &["conformal", "balanced", "area", "length"],
            )? {
                "conformal" => Alpha::conformal(),
                "area" => Alpha::area(),
                "length" => Alpha::length(),
                _ => Alpha::balanced(),
            },
        };
        let mut energy = match choice("energy", &self.energy, &["litke", "sd", "mips", "arap"])? {
            "sd" => Energy::SymmetricDirichlet,
            "mips" => Energy::Mips,
            "arap" => Energy::Arap,
            _ => Energy::litke(target),
        };
        if let Some(from) = self.from_alpha {
            energy = energy
                .with_continuation(alpha("from_alpha", from)?)
                .map_err(|e| PyValueError::new_err(format!("from_alpha: {e}")))?;
        }
        let coarse = CoarseLevel {
            vertices: self.coarse_vertices,
            ..CoarseLevel::default()
        };
        let multilevel = match choice("multilevel", &self.multilevel, &["auto", "on", "off"])? {
            "on" => Multilevel::Always(coarse),
            "off" => Multilevel::Never,
            _ => Multilevel::Auto(coarse),
        };
        let start = match choice("start", &self.start, &["auto", "lscm", "mean_value"])? {
            "lscm" | "mean_value" if matches!(multilevel, Multilevel::Always(_)) => {
                return Err(PyValueError::new_err(
                    "multilevel=\"on\" needs start=\"auto\" (an explicit start map is computed on the full mesh)",
                ));
            }
            "lscm" => Start::Lscm,
            "mean_value" => Start::MeanValue,
            _ => Start::Auto { multilevel },
        };
        // The arrays returned and the OBJ written have one UV per vertex: never cut
        // (a surface that is not a disc, once holes are filled if asked, is refused).
        let mut opts = FlattenOptions::new(energy)
            .with_start(start)
            .with_fill_holes(self.fill_holes)
            .with_cut(Cut::Never);
        opts.newton.max_iterations = self.max_iters;
        opts.newton.tolerance = self.tolerance;
        opts.newton.armijo_c = self.armijo_c;
        opts.validate()
            .map_err(|e| PyValueError::new_err(option_message(&e)))?;
        Ok(opts)
    }
}

/// Flattens a disc-topology mesh to the plane without flipped triangles (Litke's
/// projected Newton, thesis §3.1) and reports the result.
///
/// V: (n, 3) float array of vertex positions; F: (m, 3) integer array of
/// counter-clockwise triangles. Keywords are the options of `surfmap flatten`:
/// ``preset`` ("conformal", "balanced", "area", "length") or ``alpha=(L, A, C)``
/// (length, area, angle weights of the energy (2.5), normalized to sum 1);
/// ``energy`` ("litke", "sd", "mips", "arap"); ``from_alpha`` (continuation start);
/// ``start`` ("auto", "lscm", "mean_value"); ``multilevel`` ("auto", "on", "off") and
/// ``coarse_vertices``; ``fill_holes`` (fill all boundary loops but the longest for the
/// solve; they stay open in the map); Newton's ``max_iters``, ``tolerance`` and
/// ``armijo_c``; ``normalize`` (return UVs scaled into [0, 1]²).
///
/// Returns ``(UV, report)``: UV is an (n, 2) float64 array, one row per vertex, in the
/// mesh's length units (vertices no triangle uses are at the origin); report is the
/// dictionary of ``surfmap flatten --report`` (start, iterations, energy, measures, the
/// Newton log, …; ``input`` is None). The solve releases the GIL, so threads flatten
/// meshes in parallel.
///
/// The surface is never cut open along seams (the UVs are one per vertex): a closed
/// surface or one with handles raises; ``surfmap flatten`` on the command line cuts it.
///
/// Raises ``MeshError`` when the mesh is not a disc (``err.defects`` lists why, each
/// with its repair), ``ValueError`` for bad arrays or options, ``SolverError`` when the
/// solve fails.
///
/// >>> import numpy as np, surfmap
/// >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0.2], [0, 1, 0]], dtype=float)
/// >>> F = np.array([[0, 1, 2], [0, 2, 3]])
/// >>> UV, report = surfmap.flatten(V, F)
/// >>> UV.shape, report["flipped_triangles"], report["converged"]
/// ((4, 2), 0, True)
#[pyfunction]
#[pyo3(signature = (V, F, *, preset="balanced", alpha=None, energy="litke", from_alpha=None,
    start="auto", multilevel="auto", coarse_vertices=None, fill_holes=false, max_iters=200,
    tolerance=1e-12, armijo_c=0.5, normalize=false))]
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
    fill_holes: bool,
    max_iters: usize,
    tolerance: f64,
    armijo_c: f64,
    normalize: bool,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyDict>)> {
    let args = FlattenArgs {
        preset: preset.into(),
        alpha: weights("alpha", alpha)?,
        energy: energy.into(),
        from_alpha: weights("from_alpha", from_alpha)?,
        start: start.into(),
        multilevel: multilevel.into(),
        coarse_vertices,
        fill_holes,
        max_iters,
        tolerance,
        armijo_c,
        normalize,
    };
    let options = args.options()?;
    let mesh = arrays::mesh(V, F)?;
    let r = py
        .detach(|| surfmap::flatten(&mesh, &options))
        .map_err(flatten_error)?;
    let report = {
        let report = py
            .detach(|| FlattenReport::measure(None, &mesh, &r, defect_message))
            .map_err(crate::errors::measure_error)?;
        to_dict(py, &report)?
    };
    let uvs = if normalize { r.normalized_uvs() } else { r.uvs };
    Ok((arrays::array(py, uvs), report))
}
