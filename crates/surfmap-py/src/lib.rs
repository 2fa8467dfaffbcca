//! `surfmap` for Python: the library's one-call functions on numpy arrays, and batches of
//! mesh files on a thread pool or a cluster. A thin layer with no algorithms: every
//! function checks its arrays (module `arrays`), releases the GIL for the library call, and
//! returns numpy arrays and the library's reports as dictionaries (module `convert`). Errors
//! become `ValueError`, `surfmap.MeshError`, `surfmap.SolverError` or `OSError`
//! (module `errors`).
//!
//! Built by maturin as `surfmap._surfmap` (an abi3 wheel: one wheel for CPython ≥ 3.9);
//! the Python package `python/surfmap` re-exports it and adds `flatten_many`'s progress
//! display and the Dask/Ray recipes (`surfmap.distributed`).
//!
//! | file | Python |
//! |---|---|
//! | `mesh.rs` | `inspect`, `measure`, `read_mesh`, `write_obj`, `repair` |
//! | `advice.rs` | the library's remedies worded as Python calls |
//! | `flatten.rs` | `flatten` and the flattening keywords |
//! | `images.rs` | `geometry_images` |
//! | `batch.rs` | `flatten_file`, `flatten_many` (its engine), `output_names`, `BATCH_COLUMNS` |
//! | `register.rs` | `register_file`, `_register_many` (the engine of `register`), `REGISTER_COLUMNS` |
//! | `matching.rs` | `match` (the place for it; not bound yet) |

mod advice;
mod arrays;
mod batch;
mod convert;
mod errors;
mod flatten;
mod images;
mod matching;
mod mesh;
mod register;

use pyo3::prelude::*;

/// Variational surface maps (N. Litke's thesis): flip-free flattening, distortion
/// measures and geometry images of triangle meshes given as numpy arrays.
#[pymodule]
fn _surfmap(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add_function(wrap_pyfunction!(mesh::inspect, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::measure, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::write_obj, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::repair, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::crop, m)?)?;
    m.add_function(wrap_pyfunction!(flatten::flatten, m)?)?;
    m.add_function(wrap_pyfunction!(images::geometry_images, m)?)?;
    m.add_function(wrap_pyfunction!(batch::flatten_file, m)?)?;
    m.add_function(wrap_pyfunction!(batch::output_names, m)?)?;
    m.add_function(wrap_pyfunction!(batch::_check_flatten_options, m)?)?;
    m.add_function(wrap_pyfunction!(batch::_flatten_many, m)?)?;
    m.add(
        "BATCH_COLUMNS",
        surfmap::batch::BatchRow::CSV_HEADER.to_vec(),
    )?;
    m.add_function(wrap_pyfunction!(register::register_file, m)?)?;
    m.add_function(wrap_pyfunction!(register::_register_many, m)?)?;
    m.add_function(wrap_pyfunction!(register::_check_register, m)?)?;
    m.add(
        "REGISTER_COLUMNS",
        surfmap::apps::register::batch::RegisterRow::CSV_HEADER.to_vec(),
    )?;
    matching::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
