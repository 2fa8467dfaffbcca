//! `match(VA, FA, VB, FB, …)`: surface matching (thesis §2.2, §3.2) from Python — the
//! library's `surfmap::matching::match_meshes` with the fold check of `surfmap match`,
//! numpy in, numpy out, the GIL released for the solve.

use numpy::IntoPyArray;
use numpy::ndarray::Array2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use surfmap::matching::{
    Align, FeaturesStart, Guidance, HoleFeatures, Landmarks, MatchError, MatchOptions, OptionError,
    PositionWeight, ScaleB, SearchWhen, Verdict, Weights,
};

use crate::advice::match_defect_message;
use crate::arrays;
use crate::convert::to_dict;
use crate::errors::{MatchNotTrusted, SolverError, flatten_error_worded};

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

/// The value of `choices` named `given`, or a ValueError listing the names.
fn choice<T: Copy>(what: &str, given: &str, choices: &[(&str, T)]) -> PyResult<T> {
    choices
        .iter()
        .find(|(name, _)| *name == given)
        .map(|&(_, value)| value)
        .ok_or_else(|| {
            let names: Vec<String> = choices.iter().map(|(n, _)| format!("'{n}'")).collect();
            let list = match names.split_last() {
                Some((last, [])) => last.clone(),
                Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
                None => String::new(),
            };
            PyValueError::new_err(format!("{what} must be {list}, got '{given}'"))
        })
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
/// The keywords are the command line's flags (``fill_holes=False``: ``--no-fill-holes``;
/// ``pin_landmarks=False``: ``--free-landmarks``); one left out (``None``) keeps the
/// library's default, the command line's.
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
/// ``similarity_search``: search the rotation and translation of φ (and its scale, when
/// ``search_candidates`` has a SCALE above 0) that lowers the matching energy per matched
/// area on a coarse level, ``"shape"`` (only when the start
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
/// How far the match can be trusted is ``report["confidence"]``: ``"verdict"``
/// (``"ok"``, ``"doubtful"`` or ``"failed"``), ``"reasons"`` and the ``"measures"`` it
/// was drawn from (curvature disagreement, residual from a similarity, matched and
/// covered fractions, area ratio); a verdict other than ok and the doubts about single
/// features (``report["warnings"]``) are also raised as ``RuntimeWarning``. A match whose
/// verdict is not ok first tries other starts (``report["confidence"]["recovery"]``;
/// ``recover=False``: ``--no-recover``). Where one face's mouth is open and the other's
/// closed, the lip arcs lead (with landmarks or features, from their alignment refined in
/// space alone; ``report["alignment"]["mouth"]``; ``open_mouth=False``:
/// ``--no-open-mouth``); ``strict=True`` raises ``MatchNotTrusted`` for
/// it, the match on the exception (``correspondence``, ``report``). A value
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
/// >>> report["alignment"]["method"], report["options"]["weights"]["features"]
/// ('features', 10.0)
#[pyfunction]
#[pyo3(name = "match", signature = (VA, FA, VB, FB, *, landmarks=None, features_a=None, features_b=None, size=None, align=None, features_start=None, keep_folds=None, rim_fit_rings=None, complete_rings=None, pin_landmarks=None, scale_b=None, budget=None, hole_features=None, whole_hole_rims=None, fill_holes=None, beta=None, position_weight=None, similarity_search=None, search_candidates=None, search_level=None, rim_tolerance=None, relief=None, crop_overlap=None, strict=None, recover=None, open_mouth=None))]
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
    size: Option<usize>,
    align: Option<&str>,
    features_start: Option<&str>,
    keep_folds: Option<bool>,
    rim_fit_rings: Option<usize>,
    complete_rings: Option<usize>,
    pin_landmarks: Option<bool>,
    scale_b: Option<f64>,
    budget: Option<usize>,
    hole_features: Option<&str>,
    whole_hole_rims: Option<bool>,
    fill_holes: Option<bool>,
    beta: Option<Vec<f64>>,
    position_weight: Option<f64>,
    similarity_search: Option<&str>,
    search_candidates: Option<Vec<f64>>,
    search_level: Option<usize>,
    rim_tolerance: Option<f64>,
    relief: Option<f64>,
    crop_overlap: Option<&str>,
    strict: Option<bool>,
    recover: Option<bool>,
    open_mouth: Option<bool>,
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
    // Every keyword left out keeps the library's default (`MatchOptions::default()`).
    let mut o = MatchOptions::default();
    let a = arrays::mesh(VA, FA)?;
    let b = arrays::mesh(VB, FB)?;
    if let Some(f) = scale_b {
        if !(f.is_finite() && f > 0.0) {
            return Err(PyValueError::new_err(format!(
                "scale_b must be None (automatic) or a positive factor, got {f}"
            )));
        }
        o.scale_b = ScaleB::Factor(f);
    }
    let bad = |e: OptionError| PyValueError::new_err(e.to_string());
    o.size = size.unwrap_or(o.size);
    if let Some(b) = &beta {
        o.weights = Weights::from_slice(b).map_err(bad)?;
    }
    if let Some(w) = position_weight {
        o.position_weight = PositionWeight::Fixed(w);
    }
    if let Some(a) = align {
        o.align = choice(
            "align",
            a,
            &[
                ("auto", Align::Auto),
                ("features", Align::Features),
                ("shape", Align::Shape),
                ("none", Align::None),
            ],
        )?;
    }
    if let Some(f) = features_start {
        o.features_start = choice(
            "features_start",
            f,
            &[
                ("both", FeaturesStart::Both),
                ("plane", FeaturesStart::Plane),
            ],
        )?;
    }
    if let Some(h) = hole_features {
        o.hole_features = choice(
            "hole_features",
            h,
            &[
                ("auto", HoleFeatures::Auto),
                ("on", HoleFeatures::On),
                ("off", HoleFeatures::Off),
            ],
        )?;
    }
    if let Some(s) = similarity_search {
        o.similarity_search = choice(
            "similarity_search",
            s,
            &[
                ("shape", SearchWhen::Shape),
                ("off", SearchWhen::Off),
                ("always", SearchWhen::Always),
            ],
        )?;
    }
    if let Some(c) = crop_overlap {
        o.crop_overlap = choice("crop_overlap", c, &[("auto", true), ("off", false)])?;
    }
    o.keep_folds = keep_folds.unwrap_or(o.keep_folds);
    o.pin_landmarks = pin_landmarks.unwrap_or(o.pin_landmarks);
    o.strict = strict.unwrap_or(o.strict);
    o.budget = budget.unwrap_or(o.budget);
    o.fill_holes = fill_holes.unwrap_or(o.fill_holes);
    o.split_hole_rims = !whole_hole_rims.unwrap_or(!o.split_hole_rims);
    let adv = &mut o.advanced;
    adv.rim_fit_rings = rim_fit_rings.unwrap_or(adv.rim_fit_rings);
    adv.complete_rings = complete_rings.unwrap_or(adv.complete_rings);
    adv.rim_tolerance = rim_tolerance.unwrap_or(adv.rim_tolerance);
    adv.relief = relief.unwrap_or(adv.relief);
    adv.search_level = search_level.unwrap_or(adv.search_level);
    adv.recover = recover.unwrap_or(adv.recover);
    adv.open_mouth = open_mouth.unwrap_or(adv.open_mouth);
    match search_candidates.as_deref() {
        None => {}
        Some(&[deg, scale]) => adv.search_candidates = [deg, scale],
        Some(other) => return Err(bad(OptionError::SearchCandidates(other.to_vec()))),
    }
    o.validate().map_err(bad)?;
    let options = o;
    let guidance = Guidance {
        landmarks: landmarks.map(self::landmarks).transpose()?,
        features_a: features_a
            .map(|f| arrays::feature_file(f, "features_a", a.num_vertices()))
            .transpose()?,
        features_b: features_b
            .map(|f| arrays::feature_file(f, "features_b", b.num_vertices()))
            .transpose()?,
    };
    let matched = py.detach(|| surfmap::matching::match_meshes(&a, &b, &guidance, &options));
    let (matched, refused) = match matched {
        Ok(m) => (m, false),
        Err(MatchError::NotTrusted(m)) => (*m, true),
        Err(e) => return Err(match_error(e)),
    };
    let rows = Array2::from_shape_vec(
        (matched.correspondence.len(), 4),
        matched.correspondence_rows(),
    )
    .expect("four values per vertex")
    .into_pyarray(py)
    .into_any();
    let report = to_dict(py, &matched.report)?;
    let line = matched.report.confidence.line();
    if refused {
        // strict=True: the match as the exception's attributes.
        let err = MatchNotTrusted::new_err(line);
        let value = err.value(py);
        value.setattr("correspondence", rows)?;
        value.setattr("report", report)?;
        return Err(err);
    }
    // The report's doubts (`report["warnings"]`) and a verdict other than ok, as
    // Python warnings.
    let doubts = matched.report.warnings.iter().cloned();
    let verdict = (matched.report.confidence.verdict != Verdict::Ok).then_some(line);
    for w in doubts.chain(verdict) {
        let message = std::ffi::CString::new(w).unwrap_or_default();
        let category = py.get_type::<pyo3::exceptions::PyRuntimeWarning>();
        PyErr::warn(py, category.as_any(), &message, 1)?;
    }
    Ok((rows, report))
}

/// Adds the matching functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(match_meshes, m)?)?;
    Ok(())
}
