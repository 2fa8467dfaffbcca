//! `match(VA, FA, VB, FB, …)`: surface matching (thesis §2.2, §3.2) from Python — the
//! library's `surfmap::matching::match_meshes` with the fold check of `surfmap match`,
//! numpy in, numpy out, the GIL released for the solve.

use numpy::IntoPyArray;
use numpy::ndarray::Array2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use surfmap::matching::{
    Align, Guidance, HoleFeatures, Landmarks, MatchError, MatchOptions, ScaleB, SearchWhen, folder,
};

use crate::advice::match_defect_message;
use crate::arrays;
use crate::convert::to_dict;
use crate::errors::{SolverError, flatten_error_worded};

fn match_error(e: MatchError) -> PyErr {
    match e {
        MatchError::Flatten { surface, source } => flatten_error_worded(
            source,
            &surface.map_or(String::new(), |s| format!("surface {s}: ")),
            match_defect_message,
        ),
        MatchError::Guidance(_)
        | MatchError::Input(_)
        | MatchError::Option(_)
        | MatchError::Grid(_) => PyValueError::new_err(e.to_string()),
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
/// The keywords are the command line's flags, with their defaults (``fill_holes=False``:
/// ``--no-fill-holes``; ``pin_landmarks=False``: ``--free-landmarks``).
///
/// ``VA``, ``VB``: (n, 3) float arrays; ``FA``, ``FB``: (m, 3) integer arrays (discs,
/// holes filled for the solve).
///
/// Guidance. ``landmarks``: optional ``{"names": [...], "A": [vertex ids of A], "B":
/// [vertex ids of B]}``. ``features_a``, ``features_b``: feature curves of A and of B,
/// paired by name (both or neither): ``{"features": [{"name": str, "vertices": [int, …],
/// "closed": bool}, …]}`` — the JSON of ``--features-a`` — or just its list.
/// ``hole_features``: the rims of filled holes paired as features, ``"auto"`` (when both
/// surfaces have as many filled holes), ``"on"`` (an error when the counts differ) or
/// ``"off"``. ``whole_hole_rims``: match each hole rim as one closed curve (by default an
/// elongated pair — a mouth, an eye — is matched as two arcs split at its corners, upper
/// lip to upper lip). ``fill_holes``: ``False`` refuses surfaces with holes instead of
/// filling them for the solve.
///
/// Solve. ``size``: finest grid (2^k + 1). ``beta``: energy weights ``(B, R, F)`` —
/// bending, regularization, features (thesis 2.16; default ``(1, 0.01, 5)``), finite and
/// ≥ 0. ``position_weight``: a fixed weight ≥ 0 of the 3D position term (0: the thesis
/// energy alone); ``None`` sets it from the surfaces' distance along B's normals after
/// aligning them in space (``report["position_weight"]``, ``report["shape_residual"]``).
/// ``align``: ``"auto"`` (five or more features/landmarks when given, else the shapes in
/// space; fewer still guide the solve), ``"features"`` (two or more), ``"shape"``
/// or ``"none"``. ``features_start``: where φ starts with
/// features or landmarks, ``"both"`` (their similarity of the planes and, with three or
/// more, their alignment refined in space: the coarsest level is solved from both and the
/// second kept when it ends lower without matching less;
/// ``report["alignment"]["features_in_space"]``) or ``"plane"`` (the first alone).
/// ``similarity_search``: search the rotation, scale and translation of φ that lowers the
/// matching energy per matched area on a coarse level, ``"shape"`` (only when the start
/// comes from the shapes in space, without features or landmarks), ``"always"`` or
/// ``"off"`` (``report["alignment"]["search"]``). ``search_candidates``: the search's extra
/// starts ``(DEG, SCALE)``, rotated by ±DEG degrees and scaled by (1 ± SCALE), DEG ≥ 0 and
/// SCALE in [0, 1) (``None`` or ``(0, 0)``: from the start alone). ``search_level``: level
/// k ≥ 1 of the search's energy (grid 2^k + 1; at most the solve's coarsest level, 6).
/// ``budget``: most energy evaluations per level, counted at the finest level (a level
/// 2^j times coarser may use 4^j times as many), as ``surfmap match --budget``; 0 lets
/// every level run to its stopping rule (the thesis's).
///
/// Output. ``keep_folds``: keep the vertices of image triangles that turn over or
/// collapse in space (by default they are unmatched). ``rim_fit_rings``: rings of A's
/// vertices around each hole rim that follow it when the rim is carried exactly onto B's
/// paired rim (0: leave the rims where φ puts them). ``complete_rings``: rings of vertices
/// next to the matched region completed from their matched neighbours where φ just misses
/// B, after smoothing the matched border (0: leave them unmatched and φ's matches as they
/// are). ``pin_landmarks``: match each landmark exactly to its vertex of B in the output,
/// the vertices around it following (``False``: where φ puts it). ``rim_tolerance``: how
/// far past B's outer rim, in mean edges of the vertex, the prediction of a vertex φ left
/// unmatched may fall and the vertex still be matched to the rim (``--rim-tolerance``;
/// more matches more of A along a tight crop of B, and more vertices without a
/// counterpart). ``relief``: the position term compares the surfaces after their smooth
/// difference in shape, smoothed this wide (``--relief``; default 0.1, 0: off).
/// ``crop_overlap``: ``"auto"`` cuts each surface down to the part it shares with the
/// other first when its large far pieces make up 35 % of its area or more (a whole head
/// against a face crop; ``--crop-overlap``, the report's ``overlap_crop``), the rows
/// still one per vertex of A as given (the cut ones unmatched); ``"off"`` matches them whole
/// (as does ``hole_features="on"``, whose rims are paired as given).
/// ``scale_b``: ``None`` takes B as given unless the two sizes (√area) differ by more
/// than 5 times, then as in other units (B multiplied by the nearest power of ten for the
/// match; the report's ``scale_b``); a number multiplies B by it (1.0: as given).
///
/// Returns ``(correspondence, report)``: an (n_A, 4) float64 array of rows ``[triangle
/// of B, b0, b1, b2]`` (triangle −1 where A's vertex has no counterpart) — the command
/// line's ``correspondence.npy`` — and the dictionary of its ``match.json`` (the options
/// used under ``report["options"]``; with features or landmarks, how far each paired
/// feature of A lies from B's before and after the solve under ``report["feature_fit"]``).
/// Doubts about the result (``report["warnings"]``,
/// e.g. A squeezed into a small part of B) are also raised as ``RuntimeWarning``. A value
/// the command line would refuse raises ``ValueError`` naming the argument.
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
/// >>> corners = {"features": [{"name": f"c{k}", "vertices": [v]} for k, v in enumerate([0, n - 1, n * n - 1])]}
/// >>> C, report = surfmap.match(V, F, VB, F, size=65, align="features", features_a=corners, features_b=corners, beta=(1, 0.01, 10))
/// >>> report["alignment"]["method"], report["options"]["betas"]["features"]
/// ('features', 10.0)
#[pyfunction]
#[pyo3(name = "match", signature = (VA, FA, VB, FB, *, landmarks=None, features_a=None, features_b=None, size=257, align="auto", features_start="both", keep_folds=false, rim_fit_rings=8, complete_rings=4, pin_landmarks=true, scale_b=None, budget=40, hole_features="auto", whole_hole_rims=false, fill_holes=true, beta=None, position_weight=None, similarity_search="shape", search_candidates=None, search_level=4, rim_tolerance=0.5, relief=0.1, crop_overlap="auto"))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn match_meshes<'py>(
    py: Python<'py>,
    VA: &Bound<'py, PyAny>,
    FA: &Bound<'py, PyAny>,
    VB: &Bound<'py, PyAny>,
    FB: &Bound<'py, PyAny>,
    landmarks: Option<&Bound<'py, PyDict>>,
    features_a: Option<&Bound<'py, PyAny>>,
    features_b: Option<&Bound<'py, PyAny>>,
    size: usize,
    align: &str,
    features_start: &str,
    keep_folds: bool,
    rim_fit_rings: usize,
    complete_rings: usize,
    pin_landmarks: bool,
    scale_b: Option<f64>,
    budget: usize,
    hole_features: &str,
    whole_hole_rims: bool,
    fill_holes: bool,
    beta: Option<Vec<f64>>,
    position_weight: Option<f64>,
    similarity_search: &str,
    search_candidates: Option<Vec<f64>>,
    search_level: usize,
    rim_tolerance: f64,
    relief: f64,
    crop_overlap: &str,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    // As the command line's `--features-a` and `--features-b` (each requires the other).
    match (features_a.is_some(), features_b.is_some()) {
        (true, false) => {
            return Err(PyValueError::new_err(
                "features_a requires features_b: the feature curves of A are paired with B's by name",
            ));
        }
        (false, true) => {
            return Err(PyValueError::new_err(
                "features_b requires features_a: the feature curves of B are paired with A's by name",
            ));
        }
        _ => {}
    }
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
        fill_holes,
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
        features_in_space: match features_start {
            "both" => true,
            "plane" => false,
            other => {
                return Err(PyValueError::new_err(format!(
                    "features_start must be 'both' or 'plane', got '{other}'"
                )));
            }
        },
        hole_features: match hole_features {
            "auto" => HoleFeatures::Auto,
            "on" => HoleFeatures::On,
            "off" => HoleFeatures::Off,
            other => {
                return Err(PyValueError::new_err(format!(
                    "hole_features must be 'auto', 'on' or 'off', got '{other}'"
                )));
            }
        },
        split_hole_rims: if whole_hole_rims {
            0.0
        } else {
            surfmap::matching::options::SPLIT_HOLE_RIMS
        },
        ..Default::default()
    };
    if let Some(b) = &beta {
        options
            .set_betas(b, "beta")
            .map_err(PyValueError::new_err)?;
    }
    if let Some(w) = position_weight {
        options
            .set_position_weight(w, "position_weight")
            .map_err(PyValueError::new_err)?;
    }
    options.similarity_search.when = match similarity_search {
        "shape" => SearchWhen::Shape,
        "off" => SearchWhen::Off,
        "always" => SearchWhen::Always,
        other => {
            return Err(PyValueError::new_err(format!(
                "similarity_search must be 'shape', 'off' or 'always', got '{other}'"
            )));
        }
    };
    // Checked by the library (`MatchError::Option`, a ValueError here), as for the CLI.
    options.similarity_search.level = search_level;
    options.ncg.set_budget(budget);
    options
        .set_rim_tolerance(rim_tolerance, "rim_tolerance")
        .map_err(PyValueError::new_err)?;
    options
        .set_position_relief(relief, "relief")
        .map_err(PyValueError::new_err)?;
    if let Some(c) = &search_candidates {
        options
            .set_search_candidates(c, "search_candidates")
            .map_err(PyValueError::new_err)?;
    }
    let guidance = Guidance {
        landmarks: landmarks.map(self::landmarks).transpose()?,
        features_a: features_a
            .map(|f| arrays::feature_file(f, "features_a", a.num_vertices()))
            .transpose()?,
        features_b: features_b
            .map(|f| arrays::feature_file(f, "features_b", b.num_vertices()))
            .transpose()?,
    };
    options.crop_overlap = match crop_overlap {
        "auto" => true,
        "off" => false,
        other => {
            return Err(PyValueError::new_err(format!(
                "crop_overlap must be 'auto' or 'off', got '{other}'"
            )));
        }
    };
    let matched = py
        .detach(|| surfmap::matching::match_meshes(&a, &b, &guidance, &options))
        .map_err(match_error)?;
    let report = matched.report;
    let corr = matched.correspondence;
    // The report's doubts (`report["warnings"]`) also as Python warnings.
    for w in &report.warnings {
        let message = std::ffi::CString::new(w.as_str()).unwrap_or_default();
        let category = py.get_type::<pyo3::exceptions::PyRuntimeWarning>();
        PyErr::warn(py, category.as_any(), &message, 1)?;
    }
    let rows = Array2::from_shape_vec((corr.len(), 4), folder::correspondence_rows(&corr))
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
