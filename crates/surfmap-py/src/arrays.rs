//! numpy arrays in and out: every input array is checked (type, dtype, shape, values)
//! with an error that names the argument, what it must be and how to get there; any
//! memory layout is accepted (the rows are copied into the library's plain data, so
//! Fortran order and strided views read correctly). Outputs are fresh C-ordered arrays.

use numpy::ndarray::{Array2, Ix2};
use numpy::{Element, IntoPyArray, PyArray, PyArray2, PyUntypedArray, PyUntypedArrayMethods};
use numpy::{PyArrayDescrMethods, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use surfmap::TriMesh;

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

/// Triangles `F`: shape (m, 3), any integer dtype, every index in `0..num_vertices`
/// (out of range: `MeshError`, in the library's words for indices it can hold).
pub fn triangles(
    obj: &Bound<'_, PyAny>,
    name: &str,
    num_vertices: usize,
) -> PyResult<Vec<[u32; 3]>> {
    let arr = two_d(obj, name, 3, "three vertex indices per triangle")?;
    let wide: Vec<[i128; 3]> = if let Some(r) = rows_of::<i64, 3>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<i32, 3>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<u32, 3>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<u64, 3>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<i16, 3>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<u16, 3>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<u8, 3>(arr)? {
        widen(r)
    } else if let Some(r) = rows_of::<i8, 3>(arr)? {
        widen(r)
    } else {
        return Err(PyValueError::new_err(format!(
            "{name} must hold integers (vertex indices), got dtype {}; convert it with {name}.astype(numpy.int64)",
            dtype_name(arr)
        )));
    };
    let mut out = Vec::with_capacity(wide.len());
    for (t, tri) in wide.iter().enumerate() {
        let mut row = [0u32; 3];
        for (c, &v) in tri.iter().enumerate() {
            row[c] = u32::try_from(v).map_err(|_| {
                mesh_error(
                    format!(
                        "{name}[{t}, {c}] = {v}: vertex indices count from 0 and must be below the number of vertices ({num_vertices})"
                    ),
                    &[],
                )
            })?;
        }
        out.push(row);
    }
    surfmap::mesh::check_indices(&out, num_vertices).map_err(|e| mesh_error(e.to_string(), &[]))?;
    Ok(out)
}

fn widen<T: Into<i128> + Copy>(rows: Vec<[T; 3]>) -> Vec<[i128; 3]> {
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
