//! Mesh files in, files out: `flatten_file` (one mesh: the unit of work of a batch, and
//! of a task on a Dask or Ray cluster) and `_flatten_many` (a folder's worth on a thread
//! pool; the package's `flatten_many` adds the progress display). Rows are the library's
//! [`BatchRow`]s, the lines of `summary.csv`, as dictionaries.

use std::path::{Path, PathBuf};

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use surfmap::batch::{self, BatchOutput, BatchRow, FrontEnd};
use surfmap::{FlattenOptions, UvLayout};

use crate::advice::{defect_message, flatten_error_message};
use crate::convert::{to_dict, to_python};
use crate::errors::os_error;
use crate::flatten::FlattenArgs;

/// Reads `input`, flattens it, writes `dir/name.obj` and the report `dir/name.json`:
/// the row, or the failed row with the library's message ([`batch::flatten_file`]).
fn flatten_one(
    input: &Path,
    dir: &Path,
    name: &str,
    options: &FlattenOptions,
    layout: UvLayout,
) -> BatchRow {
    let read = |path: &Path| {
        surfmap::read_mesh(path)
            .map(|file| file.mesh)
            .map_err(|e| e.to_string())
    };
    let output = BatchOutput {
        dir,
        layout,
        material: None,
        seams: None,
    };
    let front = FrontEnd {
        read: &read,
        flatten_error: flatten_error_message,
        wording: defect_message,
    };
    batch::flatten_file(input, name, options, &output, &front)
}

fn create_dir(dir: &Path) -> PyResult<()> {
    std::fs::create_dir_all(dir)
        .map_err(|e| os_error(e.kind(), format!("cannot create {}: {e}", dir.display())))
}

/// Flattens one mesh file into the folder ``outdir``: writes ``outdir/NAME.obj`` (the
/// mesh with its texture coordinates: one per vertex, or per corner, split along the
/// seams, when the surface was cut) and ``outdir/NAME.json`` (the report of ``surfmap
/// flatten --report``), NAME being ``name`` or the file's stem.
///
/// Never raises for a bad mesh: returns the row of the batch table (``summary.csv`` of
/// ``flatten_many``; columns ``BATCH_COLUMNS``), a dictionary with ``input``, ``status``
/// ("ok" or "failed"), ``output``, ``report``, what was done (``plan``,
/// ``holes_filled``, ``seam_edges``, ``seam_length``, ``guarantee``, the
/// ``distortion_*`` columns of ``max_distortion``), the headline numbers of the report
/// (``vertices``, ``iterations``, ``energy``, ``symmetric_dirichlet`` and its ``_max``,
/// ``angle_mean``, ``area_max``, …), ``time_s`` and ``error`` (None, or why it failed).
/// This makes it the unit of work on a cluster: see ``surfmap.distributed``.
/// ``options`` are the keywords of ``flatten``. Releases the GIL.
///
/// >>> import os, tempfile, surfmap
/// >>> row = surfmap.flatten_file("no/such/mesh.obj", tempfile.mkdtemp())
/// >>> row["status"], "no/such/mesh.obj" in row["error"]
/// ('failed', True)
#[pyfunction]
#[pyo3(signature = (path, outdir, name=None, **options))]
pub fn flatten_file<'py>(
    py: Python<'py>,
    path: PathBuf,
    outdir: PathBuf,
    name: Option<String>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let args = FlattenArgs::from_kwargs(options)?;
    let opts = args.options()?;
    create_dir(&outdir)?;
    let name = name.unwrap_or_else(|| batch::output_names(std::slice::from_ref(&path)).remove(0));
    let row = py.detach(|| flatten_one(&path, &outdir, &name, &opts, args.layout()));
    to_dict(py, &row)
}

/// Checks flattening keywords without flattening anything (a `ValueError` for an
/// unknown name or a bad value): what a cluster driver does before sending tasks.
#[pyfunction]
#[pyo3(signature = (**options))]
pub fn _check_flatten_options(options: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
    FlattenArgs::from_kwargs(options)?.options().map(|_| ())
}

/// Output names for mesh files: each file's stem, made unique by ``-2``, ``-3``, … in
/// order where stems repeat (the names ``flatten_many`` writes under).
///
/// >>> import surfmap
/// >>> surfmap.output_names(["a/face.obj", "b/face.off", "head.ply"])
/// ['face', 'face-2', 'head']
#[pyfunction]
pub fn output_names(paths: Vec<PathBuf>) -> Vec<String> {
    batch::output_names(&paths)
}

/// The engine of ``flatten_many``: every path on a pool of ``workers`` threads (0: one
/// per core), ``callback(row)`` as each finishes, ``summary.csv`` written; returns the
/// rows in input order.
#[pyfunction]
#[pyo3(signature = (paths, outdir, workers=0, callback=None, **options))]
pub fn _flatten_many<'py>(
    py: Python<'py>,
    paths: Vec<PathBuf>,
    outdir: PathBuf,
    workers: usize,
    callback: Option<Py<PyAny>>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let args = FlattenArgs::from_kwargs(options)?;
    let opts = args.options()?;
    create_dir(&outdir)?;
    let names = batch::output_names(&paths);
    let rows = py.detach(|| {
        batch::run(
            &paths,
            workers,
            |i, input| flatten_one(input, &outdir, &names[i], &opts, args.layout()),
            |row| {
                if let Some(cb) = &callback {
                    Python::attach(|py| {
                        // A failing callback must not lose the batch: report and go on.
                        if let Err(e) = to_python(py, row).and_then(|r| cb.call1(py, (r,))) {
                            e.write_unraisable(py, None);
                        }
                    });
                }
            },
        )
    });
    let rows = rows.map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    let summary = outdir.join("summary.csv");
    batch::write_csv(&summary, &rows)
        .map_err(|e| os_error(e.kind(), format!("cannot write {}: {e}", summary.display())))?;
    to_python(py, &rows)?
        .cast_into::<PyList>()
        .map_err(Into::into)
}
