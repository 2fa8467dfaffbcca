//! The Python exceptions and how the library's errors become them.
//!
//! * `ValueError`: an argument is wrong (dtype, shape, an unknown option name, a number
//!   out of range, seams that are no edges or do not open the surface into a disc): fix
//!   the call.
//! * `surfmap.MeshError` (a `ValueError`): the mesh itself cannot be used as given (not a
//!   disc, degenerate triangles, indices out of range, a file that does not parse); the
//!   message is the library's, naming the defect and the repair. Its `defects` attribute
//!   lists the defects (dictionaries as in `inspect(V, F)["defects"]`), empty when the
//!   error is not about defects.
//! * `surfmap.SolverError` (a `RuntimeError`): the computation failed on a valid mesh
//!   (a linear solve, an inadmissible start map); the message says what to try.
//! * `surfmap.MatchNotTrusted` (a `RuntimeError`): `match(..., strict=True)` made a
//!   match whose verdict is not ok; `correspondence` and `report` hold it.
//! * `OSError` (its subclasses `FileNotFoundError`, `PermissionError`, …): a file
//!   could not be read or written.

use pyo3::exceptions::{
    PyFileExistsError, PyFileNotFoundError, PyIsADirectoryError, PyNotADirectoryError, PyOSError,
    PyPermissionError, PyRuntimeError, PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::PyList;
use surfmap::mesh::cut::CutError;
use surfmap::mesh::io::{ReadError, WriteError};
use surfmap::mesh::validate::Defect;
use surfmap::report::ReportedDefect;

use crate::advice;
use surfmap::{FlattenError, MeasureError};

pyo3::create_exception!(
    surfmap,
    MeshError,
    PyValueError,
    "The mesh cannot be used as given: not a disc, degenerate triangles, indices out of\nrange, a file that does not parse. The message names every defect and its repair;\n`defects` lists them as dictionaries (kind, count, examples, message,\nblocks_flattening), empty when the error is not about defects."
);
pyo3::create_exception!(
    surfmap,
    SolverError,
    PyRuntimeError,
    "The computation failed on a valid mesh (a linear solve, an inadmissible start\nmap); the message says what to try."
);

pyo3::create_exception!(
    surfmap,
    MatchNotTrusted,
    PyRuntimeError,
    "match(..., strict=True) made a match whose verdict is not ok (doubtful or failed);\nthe message gives the verdict and its reasons, `correspondence` and `report` the\nmatch (report[\"confidence\"] as without strict)."
);

/// Adds the exception types to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("MeshError", py.get_type::<MeshError>())?;
    m.add("SolverError", py.get_type::<SolverError>())?;
    m.add("MatchNotTrusted", py.get_type::<MatchNotTrusted>())?;
    Ok(())
}

/// A `MeshError` with `message` and the defects it is about.
pub fn mesh_error(message: impl Into<String>, defects: &[Defect]) -> PyErr {
    mesh_error_worded(message, defects, advice::defect_message)
}

/// [`mesh_error`], the defects' messages worded by `wording`.
fn mesh_error_worded(
    message: impl Into<String>,
    defects: &[Defect],
    wording: surfmap::report::DefectWording,
) -> PyErr {
    let message = message.into();
    Python::attach(|py| {
        let err = MeshError::new_err(message);
        let list = defects
            .iter()
            .map(|d| crate::convert::to_python(py, &ReportedDefect::new(d, wording)))
            .collect::<PyResult<Vec<_>>>()
            .and_then(|items| PyList::new(py, items));
        match list.and_then(|l| err.value(py).setattr("defects", l)) {
            Ok(()) => err,
            Err(e) => e,
        }
    })
}

/// A flattening error as its Python exception: the library's message, remedies worded
/// as Python calls.
pub fn flatten_error(e: FlattenError) -> PyErr {
    flatten_error_about(e, "")
}

/// [`flatten_error`] with its message after `about` (e.g. `"surface A: "`).
pub fn flatten_error_about(e: FlattenError, about: &str) -> PyErr {
    flatten_error_worded(e, about, advice::defect_message)
}

/// As [`flatten_error_about`], the defects worded by `wording`.
pub fn flatten_error_worded(
    e: FlattenError,
    about: &str,
    wording: surfmap::report::DefectWording,
) -> PyErr {
    let message = format!("{about}{}", advice::worded_flatten_error(&e, wording));
    match e {
        FlattenError::NotADisc(defects) => mesh_error_worded(message, &defects, wording),
        FlattenError::Index(_)
        | FlattenError::Degenerate(_)
        | FlattenError::NoAdmissibleStart { .. }
        | FlattenError::NoAdmissibleStartAfterCuts { .. } => {
            mesh_error_worded(message, &[], wording)
        }
        FlattenError::Cut(CutError::Defects(defects)) => {
            mesh_error_worded(message, &defects, wording)
        }
        FlattenError::Cut(CutError::Index(_)) => mesh_error_worded(message, &[], wording),
        FlattenError::Option(_)
        | FlattenError::GivenStartLength { .. }
        | FlattenError::GivenStartFlipped(_)
        | FlattenError::GivenStartWithFilledHoles(_)
        | FlattenError::GivenStartWithCut(_)
        | FlattenError::Cut(_) => PyValueError::new_err(message),
        _ => SolverError::new_err(message),
    }
}

/// A measuring error: wrong UV arrays are the caller's (`ValueError`), the rest the mesh's.
pub fn measure_error(e: MeasureError) -> PyErr {
    match e {
        MeasureError::UvCount { .. }
        | MeasureError::UvIndexCount { .. }
        | MeasureError::UvIndexOutOfRange { .. } => PyValueError::new_err(e.to_string()),
        _ => mesh_error(e.to_string(), &[]),
    }
}

/// An `OSError` of the subclass Python uses for this kind of failure.
pub fn os_error(kind: std::io::ErrorKind, message: String) -> PyErr {
    use std::io::ErrorKind as K;
    match kind {
        K::NotFound => PyFileNotFoundError::new_err(message),
        K::PermissionDenied => PyPermissionError::new_err(message),
        K::AlreadyExists => PyFileExistsError::new_err(message),
        K::IsADirectory => PyIsADirectoryError::new_err(message),
        K::NotADirectory => PyNotADirectoryError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

pub fn read_error(e: ReadError) -> PyErr {
    match &e {
        ReadError::Io { source, .. } => os_error(source.kind(), e.to_string()),
        ReadError::UnknownExtension { .. } => PyValueError::new_err(e.to_string()),
        _ => mesh_error(e.to_string(), &[]),
    }
}

pub fn write_error(e: WriteError) -> PyErr {
    match &e {
        WriteError::Io { source, .. } => os_error(source.kind(), e.to_string()),
        WriteError::UnknownExtension { .. } => PyValueError::new_err(e.to_string()),
        WriteError::InvalidMesh { .. } => mesh_error(e.to_string(), &[]),
    }
}
