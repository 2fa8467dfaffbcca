//! `geometry_images(V, F, …)`: the images of `surfmap images` as numpy arrays.

use numpy::ndarray::{Array2, Array3};
use numpy::{Element, IntoPyArray};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use surfmap::grid::Grid;
use surfmap::raster::{FeatureSource, GeometryPyramid, RasterError};
use surfmap::{FlattenOptions, GeometryImages, GeometryImagesOptions};

use crate::arrays;
use crate::convert::to_python;
use crate::errors::{SolverError, flatten_error, mesh_error};

/// A grid of scalars as an (N, N) array.
fn scalar<'py, T: Element + Copy>(py: Python<'py>, g: &Grid<T>) -> Bound<'py, PyAny> {
    let n = g.size();
    Array2::from_shape_vec((n, n), g.as_slice().to_vec())
        .expect("N² nodes")
        .into_pyarray(py)
        .into_any()
}

/// A grid of `[T; 3]` as an (N, N, 3) array.
fn triple<'py, T: Element + Copy>(py: Python<'py>, n: usize, flat: &[T]) -> Bound<'py, PyAny> {
    Array3::from_shape_vec((n, n, 3), flat.to_vec())
        .expect("N² nodes of 3 values")
        .into_pyarray(py)
        .into_any()
}

fn raster_error(e: RasterError) -> PyErr {
    match e {
        RasterError::Grid(_) | RasterError::UvCount { .. } | RasterError::Feature { .. } => {
            PyValueError::new_err(e.to_string())
        }
        RasterError::FeatureFile(_) => PyValueError::new_err(format!("features: {e}")),
        RasterError::Index(_) | RasterError::FlippedTriangle { .. } => {
            mesh_error(e.to_string(), &[])
        }
        _ => SolverError::new_err(e.to_string()),
    }
}

/// Geometry images of a surface (thesis §3.2): the mesh flattened (balanced preset,
/// or the given ``UV``), placed in ω = [0, 1]² and sampled on a ``size`` × ``size`` grid
/// (``size`` = 2^k + 1).
///
/// Returns a dictionary with the arrays of ``surfmap images`` (same names, dtypes and
/// values as its ``.npy`` files; node (i, j) at ξ = (j, i)/(size − 1); NaN outside the
/// surface unless stated): ``mask`` (uint8, 1 on the surface), ``triangle`` (uint32,
/// 4294967295 outside), ``barycentric`` (float32, N×N×3), ``position`` (N×N×3, mesh
/// units), ``metric`` and ``metric_extended`` ([g11, g12, g22], N×N×3),
/// ``mean_curvature`` and ``mean_curvature_extended``, ``boundary_distance`` (domain
/// units, negative inside), ``feature_distance`` and ``feature_0``, ``feature_1``, …
/// (with ``features``); ``pyramid``, a list of levels ``{"level", "size", "sigma", "h",
/// "g11", "g12", "g22"}`` (with ``pyramid=True``); and ``size``, ``transform``
/// (``{"scale", "offset"}``: ξ = scale · uv + offset), ``scale``, ``length_unit`` (ℓ in
/// mesh units), ``features`` (names) and ``uv`` (the flattening used).
///
/// ``features``: a list of ``{"name": str, "vertices": [int, …], "closed": bool}``
/// curves on the mesh (eyes, mouth); ``fill_holes`` fills holes for the flattening.
///
/// >>> import numpy as np, surfmap
/// >>> n = 9
/// >>> x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
/// >>> V = np.c_[x.ravel(), y.ravel(), 0.1 * np.sin(3 * x.ravel())]
/// >>> F = np.array([[i * n + j, i * n + j + 1, (i + 1) * n + j + 1] for i in range(n - 1) for j in range(n - 1)]
/// ...            + [[i * n + j, (i + 1) * n + j + 1, (i + 1) * n + j] for i in range(n - 1) for j in range(n - 1)])
/// >>> img = surfmap.geometry_images(V, F, size=33, pyramid=False)
/// >>> img["position"].shape, img["mask"].dtype.name
/// ((33, 33, 3), 'uint8')
#[pyfunction]
#[pyo3(signature = (V, F, *, size=257, UV=None, pyramid=true, features=None, fill_holes=false))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub fn geometry_images<'py>(
    py: Python<'py>,
    V: &Bound<'py, PyAny>,
    F: &Bound<'py, PyAny>,
    size: usize,
    UV: Option<&Bound<'py, PyAny>>,
    pyramid: bool,
    features: Option<&Bound<'py, PyAny>>,
    fill_holes: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let mesh = arrays::mesh(V, F)?;
    surfmap::grid::grid_level(size).map_err(|e| PyValueError::new_err(format!("size: {e}")))?;
    let features = features
        .map(|f| arrays::feature_file(f, "features", mesh.num_vertices()))
        .transpose()?;
    let uvs = match UV {
        Some(uv) => arrays::uvs(uv, "UV", mesh.num_vertices())?,
        None => {
            // Geometry images need one UV per vertex over a disc: never cut.
            let balanced = FlattenOptions::default()
                .with_fill_holes(fill_holes)
                .with_cut(surfmap::Cut::Never);
            py.detach(|| surfmap::flatten(&mesh, &balanced))
                .map_err(flatten_error)?
                .uvs
        }
    };
    let options = GeometryImagesOptions {
        size,
        pyramid,
        ..Default::default()
    };
    let source = match &features {
        Some(f) => FeatureSource::Curves(f),
        None => FeatureSource::None,
    };
    let img = py
        .detach(|| GeometryImages::compute(&mesh, &uvs, source, None, &options))
        .map_err(raster_error)?;

    let n = img.size;
    let out = PyDict::new(py);
    out.set_item("size", n)?;
    out.set_item("transform", to_python(py, &img.transform)?)?;
    out.set_item("scale", to_python(py, &img.scale)?)?;
    out.set_item("length_unit", img.length_unit)?;
    let inside: Vec<u8> = (0..n * n).map(|k| img.raster.is_inside(k) as u8).collect();
    out.set_item(
        "mask",
        Array2::from_shape_vec((n, n), inside)
            .expect("N² nodes")
            .into_pyarray(py),
    )?;
    out.set_item("triangle", scalar(py, &img.raster.triangle))?;
    out.set_item(
        "barycentric",
        triple(py, n, img.raster.bary.as_slice().as_flattened()),
    )?;
    out.set_item("position", triple(py, n, img.position.as_flattened()))?;
    out.set_item("metric", triple(py, n, img.metric.as_flattened()))?;
    out.set_item(
        "metric_extended",
        triple(py, n, img.metric_extended.as_flattened()),
    )?;
    out.set_item("mean_curvature", scalar(py, &img.mean_curvature))?;
    out.set_item(
        "mean_curvature_extended",
        scalar(py, &img.mean_curvature_extended),
    )?;
    out.set_item("boundary_distance", scalar(py, &img.boundary_distance))?;
    for (i, f) in img.features.iter().enumerate() {
        out.set_item(format!("feature_{i}"), scalar(py, &f.distance))?;
    }
    if let Some(d) = &img.feature_distance {
        out.set_item("feature_distance", scalar(py, d))?;
    }
    out.set_item(
        "features",
        img.features
            .iter()
            .map(|f| f.name.clone())
            .collect::<Vec<_>>(),
    )?;
    if let Some(pyr) = &img.pyramid {
        let levels = PyList::empty(py);
        for (k, (lvl, sigma)) in pyr.mean_curvature.iter().enumerate() {
            let level = PyDict::new(py);
            level.set_item("level", lvl.level())?;
            level.set_item("size", lvl.size())?;
            level.set_item("sigma", sigma)?;
            for (c, name) in GeometryPyramid::NAMES.iter().enumerate() {
                level.set_item(*name, scalar(py, &pyr.scalar_level(k, c)))?;
            }
            levels.append(level)?;
        }
        out.set_item("pyramid", levels)?;
    }
    out.set_item("uv", arrays::array(py, uvs))?;
    Ok(out)
}
