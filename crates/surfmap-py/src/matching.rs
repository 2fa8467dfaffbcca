//! Surface matching (thesis §3.2) from Python: the place for `surfmap.match`, to be
//! bound when the library's matcher lands. Nothing is registered yet.
//!
//! The intended shape, in the manner of the rest of this crate (numpy in, numpy out,
//! the GIL released for the solve, library errors mapped by `crate::errors`):
//!
//! ```text
//! m = surfmap.match(VA, FA, VB, FB, landmarks=[(a0, b0), …], **options)
//! m.correspondence   # (n_A, 4) float64: [triangle of B, b0, b1, b2]; triangle −1 = unmatched
//! m.map(points)      # (k, 3) points on A (or SurfacePoints) → their images on B
//! m.report           # dict, the JSON the command line writes
//! ```
//!
//! To add it: a `#[pyclass] SurfaceMatch` holding the library's match, a `#[pyfunction]
//! r#match` (Python's `match` is a soft keyword, a valid function name), both added in
//! [`register`]; then their stubs in `python/surfmap/_surfmap.pyi` and the re-export in
//! `python/surfmap/__init__.py` (a placeholder comment in each), and a test in `tests/`
//! (`tests/test_docs.py` already requires a stub and a docstring example for every
//! function the module registers).

use pyo3::prelude::*;

/// Adds the matching functions and classes to the module (none yet).
pub fn register(_m: &Bound<'_, PyModule>) -> PyResult<()> {
    Ok(())
}
