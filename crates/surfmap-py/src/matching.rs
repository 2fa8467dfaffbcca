//! `match(VA, FA, VB, FB, …)`: surface matching (thesis §2.2, §3.2) from Python — the
//! library's `surfmap::matching::match_surfaces` with the fold check of `surfmap match`,
//! numpy in, numpy out, the GIL released for the solve.

use numpy::IntoPyArray;
use numpy::ndarray::Array2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use surfmap::matching::{
    Align, Guidance, Landmarks, MatchError, MatchOptions, ScaleB, match_surfaces, output,
};

use crate::arrays;
use crate::convert::to_dict;
use crate::errors::{SolverError, flatten_error_about};

fn match_error(e: MatchError) -> PyErr {
    match e {
        MatchError::Flatten { surface, source } => flatten_error_about(
            source,
            &surface.map_or(String::new(), |s| format!("surface {s}: ")),
        ),
        MatchError::Guidance(_) | MatchError::Option(_) | MatchError::Grid(_) => {
            PyValueError::new_err(e.to_string())
        }
        _ => SolverError::new_err(e.to_string()),
    }
}

/// `{"names": [...], "A": [...], "B": [...]}` → landmarks.
fn landmarks(d: &Bound<'_, PyDict>) -> PyResult<Landmarks> {
    let get = |k: &str| {
        d.get_item(k)?.ok_or_else(|| {
            PyValueError::new_err(format!(
                "landmarks: missing key '{k}'; give {{\"names\": [...], \"A\": [vertex ids of A], \"B\": [vertex ids of B]}}"
            ))
        })
    };
    Ok(Landmarks {
        names: get("names")?.extract()?,
        a: get("A")?.extract()?,
        b: get("B")?.extract()?,
    })
}

/// Matches surface A onto surface B: a smooth, fold-free correspondence found by
/// multiscale registration of their geometry images (``surfmap match``; thesis §2.2).
///
/// ``VA``, ``VB``: (n, 3) float arrays; ``FA``, ``FB``: (m, 3) integer arrays (discs,
/// holes filled for the solve). ``landmarks``: optional ``{"names": [...], "A": [vertex
/// ids of A], "B": [vertex ids of B]}``. ``size``: finest grid (2^k + 1). ``align``:
/// ``"auto"`` (landmarks when given, else the shapes in space), ``"features"``,
/// ``"shape"`` or ``"none"``. ``keep_folds``: keep the vertices of image triangles that
/// turn over or collapse in space (by default they are unmatched). ``rim_fit_rings``:
/// rings of A's vertices around each hole rim that follow it when the rim is carried
/// exactly onto B's paired rim (0: leave the rims where φ puts them). ``complete_rings``:
/// rings of vertices next to the matched region completed from their matched neighbours
/// where φ just misses B, after smoothing the matched border (0: leave them unmatched and
/// φ's matches as they are). ``pin_landmarks``: match each landmark exactly to its vertex
/// of B in the output, the vertices around it following (``False``: where φ puts it).
/// ``scale_b``: ``None`` takes B as given unless the two sizes (√area) differ by more
/// than 5 times, then as in other units (B multiplied by the nearest power of ten for the
/// match; the report's ``scale_b``); a number multiplies B by it (1.0: as given).
/// ``budget``: most energy evaluations per level, counted at the finest level (a level
/// 2^j times coarser may use 4^j times as many), as ``surfmap match --budget``; 0 lets
/// every level run to its stopping rule (the thesis's).
///
/// Returns ``(correspondence, report)``: an (n_A, 4) float64 array of rows ``[triangle
/// of B, b0, b1, b2]`` (triangle −1 where A's vertex has no counterpart) — the command
/// line's ``correspondence.npy`` — and the dictionary of its ``match.json``. Doubts about
/// the result (``report["warnings"]``, e.g. A squeezed into a small part of B) are also
/// raised as ``RuntimeWarning``.
///
/// >>> import numpy as np, surfmap
/// >>> n = 17
/// >>> x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
/// >>> V = np.c_[x.ravel(), y.ravel(), 0.3 * np.exp(-2 * ((x - 0.3)**2 + y**2)).ravel() + 0.1 * x.ravel() * y.ravel()]
/// >>> i = np.arange(n * (n - 1)).reshape(n - 1, n)[:, :-1].ravel()
/// >>> F = np.r_[np.c_[i, i + 1, i + n + 1], np.c_[i, i + n + 1, i + n]]
/// >>> c, s = np.cos(0.4), np.sin(0.4)
/// >>> VB = V @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T + [2.0, 0.0, 1.0]
/// >>> C, report = surfmap.match(V, F, VB, F, size=65)
/// >>> C.shape, report["min_det"] > 0, report["matched_fraction_a"] > 0.9
/// ((289, 4), True, True)
#[pyfunction]
#[pyo3(name = "match", signature = (VA, FA, VB, FB, *, landmarks=None, size=257, align="auto", keep_folds=false, rim_fit_rings=8, complete_rings=4, pin_landmarks=true, scale_b=None, budget=40))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn match_meshes<'py>(
    py: Python<'py>,
    VA: &Bound<'py, PyAny>,
    FA: &Bound<'py, PyAny>,
    VB: &Bound<'py, PyAny>,
    FB: &Bound<'py, PyAny>,
    landmarks: Option<&Bound<'py, PyDict>>,
    size: usize,
    align: &str,
    keep_folds: bool,
    rim_fit_rings: usize,
    complete_rings: usize,
    pin_landmarks: bool,
    scale_b: Option<f64>,
    budget: usize,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    surfmap::grid::grid_level(size).map_err(|e| PyValueError::new_err(format!("size: {e}")))?;
    let a = arrays::mesh(VA, FA)?;
    let b = arrays::mesh(VB, FB)?;
    let scale_b = match scale_b {
        None => ScaleB::Auto,
        Some(f) if f.is_finite() && f > 0.0 => ScaleB::Factor(f),
        Some(f) => {
            return Err(PyValueError::new_err(format!(
                "scale_b must be None (automatic) or a positive factor, got {f}"
            )));
        }
    };
    let mut options = MatchOptions {
        size,
        scale_b,
        drop_folds: !keep_folds,
        rim_fit_rings,
        complete_rings,
        pin_landmarks,
        align: match align {
            "auto" => Align::Auto,
            "features" => Align::Features,
            "shape" => Align::Shape,
            "none" => Align::None,
            other => {
                return Err(PyValueError::new_err(format!(
                    "align must be 'auto', 'features', 'shape' or 'none', got '{other}'"
                )));
            }
        },
        ..Default::default()
    };
    options.ncg.set_budget(budget);
    let guidance = Guidance {
        landmarks: landmarks.map(self::landmarks).transpose()?,
        ..Default::default()
    };
    let (corr, report) = py
        .detach(|| -> Result<_, MatchError> {
            let m = match_surfaces(&a, &b, &guidance, &options)?;
            let checked = m.checked_correspondence(&a, &b, options.drop_folds)?;
            let report = m.report(&checked, &options);
            Ok((checked.points, report))
        })
        .map_err(match_error)?;
    // The report's doubts (`report["warnings"]`) also as Python warnings.
    for w in &report.warnings {
        let message = std::ffi::CString::new(w.as_str()).unwrap_or_default();
        let category = py.get_type::<pyo3::exceptions::PyRuntimeWarning>();
        PyErr::warn(py, category.as_any(), &message, 1)?;
    }
    let rows = Array2::from_shape_vec((corr.len(), 4), output::correspondence_rows(&corr))
        .expect("four values per vertex")
        .into_pyarray(py)
        .into_any();
    Ok((rows, to_dict(py, &report)?))
}

/// Adds the matching functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(match_meshes, m)?)?;
    Ok(())
}
