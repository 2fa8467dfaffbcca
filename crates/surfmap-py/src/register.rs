//! Registration of one template onto many scans (`surfmap register`): `register_file`
//! (one scan: the unit of work of a batch and of a task on a Dask or Ray cluster) and
//! `_register_many` (a list of scans on a thread pool; the package's `register` adds the
//! scan discovery and the progress display). Rows are the library's [`RegisterRow`]s,
//! the lines of `summary.csv`, as dictionaries.
//!
//! The template is prepared once per process ([`template`]: checked, flattened and
//! rasterized) and kept for the next scans with the same file and options, so a cluster
//! worker pays its one-off cost once, not once per task.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyList;
use surfmap::apps::register::batch::{RegisterJob, RegisterRow, register_many, write_summary};
use surfmap::apps::register::{RegisterError, Template};
use surfmap::matching::{MatchError, MatchOptions};

use crate::convert::{to_dict, to_python};
use crate::errors::os_error;

/// The match options of a registration: the library's defaults, with the grid size and
/// the budget when given (as `surfmap register --size --budget`).
fn options(size: Option<usize>, budget: Option<usize>) -> PyResult<MatchOptions> {
    let mut o = MatchOptions::default();
    o.size = size.unwrap_or(o.size);
    o.budget = budget.unwrap_or(o.budget);
    o.validate()
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(o)
}

type TemplateKey = (PathBuf, Option<std::time::SystemTime>, u64, String);

/// The template at `path` prepared for `options`, from this process's cache when the
/// same file (path, modification time, length) was prepared with the same options.
fn template(path: &Path, options: &MatchOptions) -> PyResult<Arc<Template>> {
    static CACHE: Mutex<Option<HashMap<TemplateKey, Arc<Template>>>> = Mutex::new(None);
    let meta = std::fs::metadata(path).map_err(|e| {
        os_error(
            e.kind(),
            format!("cannot read the template {}: {e}", path.display()),
        )
    })?;
    let key: TemplateKey = (
        path.to_path_buf(),
        meta.modified().ok(),
        meta.len(),
        serde_json::to_string(options).unwrap_or_default(),
    );
    if let Some(t) = CACHE
        .lock()
        .ok()
        .and_then(|c| c.as_ref().and_then(|c| c.get(&key).cloned()))
    {
        return Ok(t);
    }
    let mesh = surfmap::read_mesh(path)
        .map_err(crate::errors::read_error)?
        .mesh;
    let prepared = Template::new(mesh, options).map_err(|e| {
        PyValueError::new_err(format!(
            "the template {} cannot be matched: {}",
            path.display(),
            match e {
                RegisterError::Match(m) => match_error_message(&m),
                other => other.to_string(),
            }
        ))
    })?;
    let prepared = Arc::new(prepared);
    if let Ok(mut c) = CACHE.lock() {
        c.get_or_insert_with(HashMap::new)
            .insert(key, prepared.clone());
    }
    Ok(prepared)
}

fn match_error_message(e: &MatchError) -> String {
    match e {
        MatchError::Flatten { surface, source } => {
            let message =
                crate::advice::worded_flatten_error(source, crate::advice::match_defect_message);
            let which = if *surface == Some('A') {
                "the template"
            } else {
                "the scan"
            };
            format!("cannot flatten {which}: {message}")
        }
        _ => e.to_string(),
    }
}

fn read(path: &Path) -> Result<surfmap::TriMesh, String> {
    surfmap::read_mesh(path)
        .map(|file| file.mesh)
        .map_err(|e| e.to_string())
}

/// The batch job of the template `t` with the options `o`, writing into `outdir`.
fn job<'a>(
    t: &'a Template,
    o: &'a MatchOptions,
    outdir: &'a Path,
    keep_matches: bool,
    landmarks_dir: Option<&'a Path>,
) -> RegisterJob<'a> {
    RegisterJob {
        template: t,
        options: o,
        dir: outdir,
        keep_matches,
        landmarks_dir,
        read: &read,
        match_error: match_error_message,
    }
}

fn create_dir(dir: &Path) -> PyResult<()> {
    std::fs::create_dir_all(dir.join("registered"))
        .map_err(|e| os_error(e.kind(), format!("cannot create {}: {e}", dir.display())))
}

/// Checks the template and the options without registering anything (a `ValueError`
/// naming the problem): what a cluster driver does before sending tasks. Returns the
/// seconds the template's one-off preparation took.
#[pyfunction]
#[pyo3(signature = (template, size=None, budget=None))]
pub fn _check_register(
    py: Python<'_>,
    template: PathBuf,
    size: Option<usize>,
    budget: Option<usize>,
) -> PyResult<f64> {
    let o = options(size, budget)?;
    let t = py.detach(|| self::template(&template, &o))?;
    Ok(t.one_off_seconds)
}

/// Registers the template onto one scan file, writing into the folder ``outdir``:
/// ``outdir/registered/NAME.obj`` (the template's triangles and vertex order at their
/// places on the scan; unmatched vertices continued smoothly), ``registered/NAME.json``
/// (its row) and, with ``keep_matches``, the match folder ``outdir/matches/NAME/``.
/// NAME is ``name`` or the scan's stem. ``landmarks_dir``: a folder with ``STEM.json``
/// per scan, ``{"names": [...], "A": [template ids], "B": [scan ids]}``. ``size``,
/// ``budget``: as ``surfmap register --size --budget``.
///
/// Never raises for a bad scan: returns the row of the summary table (columns
/// ``REGISTER_COLUMNS``): ``name``, ``input``, ``status`` ("ok" or "failed"),
/// ``output``, ``verdict`` (the match's ``ok``, ``doubtful`` or ``failed``),
/// ``reasons``, ``matched_fraction``, ``extended``, ``energy``, ``seconds``, ``error``.
/// A template that cannot be matched raises ``ValueError`` (it would fail every scan).
/// The template is prepared once per process and reused. Releases the GIL.
///
/// >>> import os, tempfile, numpy as np, surfmap
/// >>> x, y = np.meshgrid(np.linspace(0, 1, 8), np.linspace(0, 1, 8))
/// >>> V = np.c_[x.ravel(), y.ravel(), 0.2 * np.sin(3 * x.ravel())]
/// >>> F = np.array([[i, i + 1, i + 9] for i in range(56) if i % 8 < 7]
/// ...              + [[i, i + 9, i + 8] for i in range(56) if i % 8 < 7])
/// >>> d = tempfile.mkdtemp()
/// >>> surfmap.write_obj(os.path.join(d, "template.obj"), V, F)
/// >>> row = surfmap.register_file(os.path.join(d, "template.obj"), "no/such/scan.obj", d, size=129)
/// >>> row["status"], row["output"], "no/such/scan.obj" in row["error"]
/// ('failed', None, True)
#[pyfunction]
#[pyo3(signature = (template, scan, outdir, name=None, landmarks_dir=None, keep_matches=false, size=None, budget=None))]
#[allow(clippy::too_many_arguments)]
pub fn register_file<'py>(
    py: Python<'py>,
    template: PathBuf,
    scan: PathBuf,
    outdir: PathBuf,
    name: Option<String>,
    landmarks_dir: Option<PathBuf>,
    keep_matches: bool,
    size: Option<usize>,
    budget: Option<usize>,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    let o = options(size, budget)?;
    create_dir(&outdir)?;
    let name =
        name.unwrap_or_else(|| surfmap::batch::output_names(std::slice::from_ref(&scan)).remove(0));
    let row = py.detach(|| -> PyResult<RegisterRow> {
        let t = self::template(&template, &o)?;
        let job = job(&t, &o, &outdir, keep_matches, landmarks_dir.as_deref());
        Ok(job.register_file(&scan, &name))
    })?;
    to_dict(py, &row)
}

/// The engine of ``register``: every scan on a pool of ``workers`` threads (0: one per
/// core), ``callback(row)`` as each finishes, ``summary.csv`` and ``summary.json``
/// written; returns the rows in input order.
#[pyfunction]
#[pyo3(signature = (template, scans, outdir, workers=0, callback=None, landmarks_dir=None, keep_matches=false, resume=false, size=None, budget=None))]
#[allow(clippy::too_many_arguments)]
pub fn _register_many<'py>(
    py: Python<'py>,
    template: PathBuf,
    scans: Vec<PathBuf>,
    outdir: PathBuf,
    workers: usize,
    callback: Option<Py<PyAny>>,
    landmarks_dir: Option<PathBuf>,
    keep_matches: bool,
    resume: bool,
    size: Option<usize>,
    budget: Option<usize>,
) -> PyResult<Bound<'py, PyList>> {
    let o = options(size, budget)?;
    create_dir(&outdir)?;
    let names = surfmap::batch::output_names(&scans);
    let rows = py.detach(|| -> PyResult<Vec<RegisterRow>> {
        let t = self::template(&template, &o)?;
        let job = job(&t, &o, &outdir, keep_matches, landmarks_dir.as_deref());
        let rows = register_many(&job, &scans, &names, workers, resume, |row| {
            if let Some(cb) = &callback {
                Python::attach(|py| {
                    // A failing callback must not lose the batch: report and go on.
                    if let Err(e) = to_python(py, row).and_then(|r| cb.call1(py, (r,))) {
                        e.write_unraisable(py, None);
                    }
                });
            }
        })
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        write_summary(&outdir, &rows)
            .map_err(|e| pyo3::exceptions::PyOSError::new_err(e.to_string()))?;
        Ok(rows)
    })?;
    to_python(py, &rows)?
        .cast_into::<PyList>()
        .map_err(Into::into)
}
