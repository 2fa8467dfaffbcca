//! numpy arrays in and out: every input array is checked (type, dtype, shape, values)
//! with an error that names the argument, what it must be and how to get there; any
//! memory layout is accepted (the rows are copied into the library's plain data, so
//! Fortran order and strided views read correctly). Outputs are fresh C-ordered arrays.

use numpy::ndarray::{Array2, Ix2};
use numpy::{Element, IntoPyArray, PyArray, PyArray2, PyUntypedArray, PyUntypedArrayMethods};
use numpy::{PyArrayDescrMethods, PyArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use surfmap::TriMesh;
use surfmap::raster::FeatureFile;

use crate::errors::mesh_error;

/// `obj` as a 2-D numpy array with `k` columns, or the `ValueError` saying what `name`
/// must be (`what`: the meaning of one row).
fn two_d<'a, 'py>(
    obj: &'a Bound<'py, PyAny>,
    name: &str,
    k: usize,
    what: &str,
) -> PyResult<&'a Bound<'py, PyUntypedArray>> {
    let arr = obj.cast::<PyUntypedArray>().map_err(|_| {
        let ty = obj
            .get_type()
            .name()
            .map_or_else(|_| "?".to_owned(), |n| n.to_string());
        PyValueError::new_err(format!(
            "{name} must be a numpy array of shape (n, {k}) ({what}), got a {ty}; convert it with numpy.asarray({name})"
        ))
    })?;
    let shape = arr.shape();
    if shape.len() != 2 || shape[1] != k {
        return Err(PyValueError::new_err(format!(
            "{name} must have shape (n, {k}) ({what}), got shape {}",
            shape_text(shape)
        )));
    }
    Ok(arr)
}

fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

fn dtype_name(arr: &Bound<'_, PyUntypedArray>) -> String {
    arr.dtype()
        .str()
        .map_or_else(|_| "?".to_owned(), |s| s.to_string())
}

/// The rows of `arr` if its dtype is `T` (`None` otherwise), in any memory layout.
fn rows_of<T: Element + Copy, const K: usize>(
    arr: &Bound<'_, PyUntypedArray>,
) -> PyResult<Option<Vec<[T; K]>>> {
    if !arr.dtype().is_equiv_to(&numpy::dtype::<T>(arr.py())) {
        return Ok(None);
    }
    let typed = arr.cast::<PyArray<T, Ix2>>()?;
    let view = typed.try_readonly()?;
    // `as_slice` also accepts Fortran order, whose memory runs down the columns: only
    // C order is read as rows.
    let c_order = arr
        .is_c_contiguous()
        .then(|| view.as_slice().ok())
        .flatten();
    let rows = match c_order {
        Some(flat) => flat
            .chunks_exact(K)
            .map(|c| std::array::from_fn(|k| c[k]))
            .collect(),
        None => view
            .as_array()
            .rows()
            .into_iter()
            .map(|r| std::array::from_fn(|k| r[k]))
            .collect(),
    };
    Ok(Some(rows))
}

/// Real coordinates: float64 as they are, float32 widened exactly.
fn real_rows<const K: usize>(
    obj: &Bound<'_, PyAny>,
    name: &str,
    what: &str,
) -> PyResult<Vec<[f64; K]>> {
    let arr = two_d(obj, name, K, what)?;
    if let Some(rows) = rows_of::<f64, K>(arr)? {
        return Ok(rows);
    }
    if let Some(rows) = rows_of::<f32, K>(arr)? {
        return Ok(rows.into_iter().map(|r| r.map(f64::from)).collect());
    }
    Err(PyValueError::new_err(format!(
        "{name} must hold floats (float64 or float32), got dtype {}; convert it with {name}.astype(numpy.float64)",
        dtype_name(arr)
    )))
}

/// Vertex positions `V`: shape (n, 3), float64 or float32.
pub fn positions(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<[f64; 3]>> {
    real_rows(obj, name, "x, y, z per vertex")
}

/// Texture coordinates, any number of rows: shape (n, 2), float64 or float32.
pub fn uv_rows(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<[f64; 2]>> {
    real_rows(obj, name, "u, v per row")
}

/// Texture coordinates: shape (`num_vertices`, 2), float64 or float32.
pub fn uvs(obj: &Bound<'_, PyAny>, name: &str, num_vertices: usize) -> PyResult<Vec<[f64; 2]>> {
    let uv = real_rows(obj, name, "u, v per vertex")?;
    if uv.len() != num_vertices {
        return Err(PyValueError::new_err(format!(
            "{name} has {} rows but the mesh has {num_vertices} vertices; give one (u, v) per vertex",
            uv.len()
        )));
    }
    Ok(uv)
}

/// Rows of `K` non-negative integer indices (any integer dtype), as `u32`; `what`: the
/// meaning of one row, `noun` and `below`: what the indices are and their bound, for
/// the message. A negative or too large index is a `MeshError` naming the entry.
fn index_rows<const K: usize>(
    obj: &Bound<'_, PyAny>,
    name: &str,
    what: &str,
    [noun, below]: [&str; 2],
) -> PyResult<Vec<[u32; K]>> {
    let arr = two_d(obj, name, K, what)?;
    let wide: Vec<[i128; K]> = if let Some(r) = rows_of::<i64, K>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<i32, K>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<u32, K>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<u64, K>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<i16, K>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<u16, K>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<u8, K>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<i8, K>(arr)? {
        widen(r)
    } else {
        return Err(PyValueError::new_err(format!(
            "{name} must hold integers ({noun}), got dtype {}; convert it with {name}.astype(numpy.int64)",
            dtype_name(arr)
        )));
    };
    let mut out = Vec::with_capacity(wide.len());
    for (t, row) in wide.iter().enumerate() {
        let mut indices = [0u32; K];
        for (c, &v) in row.iter().enumerate() {
            indices[c] = u32::try_from(v).map_err(|_| {
                mesh_error(
                    format!(
                        "{name}[{t}, {c}] = {v}: {noun} count from 0 and must be below {below}"
                    ),
                    &[],
                )
            })?;
        }
        out.push(indices);
    }
    Ok(out)
}

/// Triangles `F`: shape (m, 3), any integer dtype, every index in `0..num_vertices`
/// (out of range: `MeshError`, in the library's words for indices it can hold).
pub fn triangles(
    obj: &Bound<'_, PyAny>,
    name: &str,
    num_vertices: usize,
) -> PyResult<Vec<[u32; 3]>> {
    let below = format!("the number of vertices ({num_vertices})");
    let out = index_rows(
        obj,
        name,
        "three vertex indices per triangle",
        ["vertex indices", &below],
    )?;
    surfmap::mesh::check_indices(&out, num_vertices).map_err(|e| mesh_error(e.to_string(), &[]))?;
    Ok(out)
}

/// Edges (seams): shape (k, 2), any integer dtype, two vertex indices per edge (whether
/// they are edges of the mesh is the library's check).
pub fn edges(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<[u32; 2]>> {
    index_rows(
        obj,
        name,
        "two vertex indices per edge",
        ["vertex indices", "the number of vertices"],
    )
}

/// Per-corner UV indices `FUV`: shape (`num_triangles`, 3), the corners of triangle `t`
/// taking their UVs from rows `FUV[t]` of a UV array of `num_uvs` rows (OBJ's `vt`
/// indices, from 0). Wrong counts or indices are the caller's: `ValueError`.
pub fn uv_triangles(
    obj: &Bound<'_, PyAny>,
    name: &str,
    num_uvs: usize,
    num_triangles: usize,
) -> PyResult<Vec<[u32; 3]>> {
    let below = format!("the number of UV rows ({num_uvs})");
    let out: Vec<[u32; 3]> = index_rows(
        obj,
        name,
        "three UV indices per triangle",
        ["UV indices", &below],
    )?;
    if out.len() != num_triangles {
        return Err(PyValueError::new_err(format!(
            "{name} has {} rows but F has {num_triangles} triangles; give the UV indices of each triangle's corners",
            out.len()
        )));
    }
    if let Some((t, c, v)) = out
        .iter()
        .enumerate()
        .flat_map(|(t, row)| row.iter().enumerate().map(move |(c, &v)| (t, c, v)))
        .find(|&(_, _, v)| v as usize >= num_uvs)
    {
        return Err(PyValueError::new_err(format!(
            "{name}[{t}, {c}] = {v}: UV indices count from 0 and must be below {below}"
        )));
    }
    Ok(out)
}

fn widen<T: Into<i128> + Copy, const K: usize>(rows: Vec<[T; K]>) -> Vec<[i128; K]> {
    rows.into_iter().map(|r| r.map(Into::into)).collect()
}

/// The mesh of `V` and `F`, checked.
pub fn mesh(v: &Bound<'_, PyAny>, f: &Bound<'_, PyAny>) -> PyResult<TriMesh> {
    let positions = positions(v, "V")?;
    let triangles = triangles(f, "F", positions.len())?;
    Ok(TriMesh::new(positions, triangles))
}

/// Rows as an (n, K) array (the vector's memory handed over, no copy).
pub fn array<T: Element, const K: usize>(
    py: Python<'_>,
    rows: Vec<[T; K]>,
) -> Bound<'_, PyArray2<T>> {
    let n = rows.len();
    Array2::from_shape_vec((n, K), rows.into_flattened())
        .expect("n rows of K values")
        .into_pyarray(py)
}

/// A mesh as numpy arrays: `(V, F)`, positions (n, 3) float64 and triangles (m, 3) int64.
pub type MeshArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);

/// The arrays `(V, F)` of a mesh's positions and triangles.
pub fn mesh_arrays<'py>(
    py: Python<'py>,
    positions: Vec<[f64; 3]>,
    triangles: &[[u32; 3]],
) -> MeshArrays<'py> {
    let f = triangle_array(py, triangles);
    (array(py, positions), f)
}

/// Triangles as an (m, 3) int64 array, numpy's default integer.
pub fn triangle_array<'py>(py: Python<'py>, triangles: &[[u32; 3]]) -> Bound<'py, PyArray2<i64>> {
    array(
        py,
        triangles
            .iter()
            .map(|t| t.map(i64::from))
            .collect::<Vec<_>>(),
    )
}

/// Feature curves given as `argument` for a mesh of `vertices` vertices: the JSON of
/// `surfmap match --features-a` or `surfmap images --features` as a dict,
/// `{"features": [{"name", "vertices", "closed"}, …]}`, or just its list; numpy integers
/// and arrays are read as their values. Not JSON data: a `TypeError`; a bad file (names,
/// ids out of range): a `ValueError`, both naming the argument.
pub fn feature_file(
    value: &Bound<'_, PyAny>,
    argument: &str,
    vertices: usize,
) -> PyResult<FeatureFile> {
    let py = value.py();
    let wrapped = if value.is_instance_of::<PyDict>() {
        value.clone()
    } else {
        let d = PyDict::new(py);
        d.set_item("features", value)?;
        d.into_any()
    };
    let kwargs = PyDict::new(py);
    kwargs.set_item(
        "default",
        py.import("operator")?
            .call_method1("methodcaller", ("tolist",))?,
    )?;
    let json: String = py
        .import("json")?
        .call_method("dumps", (wrapped,), Some(&kwargs))
        .map_err(|e| {
            PyTypeError::new_err(format!(
                "{argument}: expected {{\"features\": [{{\"name\": str, \"vertices\": [int, …], \"closed\": bool}}, …]}} or its list, \
                 not convertible to JSON: {e}"
            ))
        })?
        .extract()?;
    FeatureFile::parse(&json, vertices)
        .map_err(|e| PyValueError::new_err(format!("{argument}: {e}")))
}
