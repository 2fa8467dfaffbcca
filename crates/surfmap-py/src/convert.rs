//! The library's serializable reports as Python objects: the JSON text the command line
//! writes, read back with Python's `json.loads`. So a report from Python and one from
//! `surfmap … --report` are the same tree, key order and float bits included (objects →
//! `dict`, arrays → `list`, a non-finite float → `None` as in the JSON).

use pyo3::prelude::*;
use pyo3::types::PyDict;

/// `value` as the Python object of its JSON text.
pub fn to_python<'py>(
    py: Python<'py>,
    value: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// `value` as a Python `dict` (for reports, which serialize as JSON objects).
pub fn to_dict<'py>(
    py: Python<'py>,
    value: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyDict>> {
    Ok(to_python(py, value)?.cast_into::<PyDict>()?)
}
