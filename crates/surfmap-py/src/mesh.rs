//! Meshes as arrays: `inspect`, `measure`, `read_mesh`, `write_obj`, `repair`.

use std::path::PathBuf;

use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use surfmap::report::{InspectReport, MeshSource};
use surfmap::{MeasureOptions, TriMesh, Uvs};

use crate::advice::defect_message;
use crate::arrays;
use crate::convert::to_dict;
use crate::errors::{measure_error, read_error, write_error};

/// Counts, bounding box, area, topology and defects of a mesh: the dictionary of
/// ``surfmap inspect --json`` (``file`` and ``format`` are None for arrays, ``faces``
/// counts the triangles).
///
/// Every defect that matters for flattening is listed with its repair in
/// ``["defects"]``; ``["disc"]`` says whether ``flatten`` accepts the mesh as it is.
///
/// >>> import numpy as np, surfmap
/// >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
/// >>> info = surfmap.inspect(V, np.array([[0, 1, 2], [0, 2, 3]]))
/// >>> info["disc"], info["boundary_loops"], info["area"]
/// (True, 1, 1.0)
#[pyfunction]
#[pyo3(signature = (V, F))]
#[allow(non_snake_case)]
pub fn inspect<'py>(
    py: Python<'py>,
    V: &Bound<'py, PyAny>,
    F: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let mesh = arrays::mesh(V, F)?;
    let report = py.detach(|| InspectReport::new(MeshSource::ARRAYS, &mesh, defect_message));
    to_dict(py, &report)
}

/// Scores a map V, F → UV: the dictionary of ``surfmap measure --json``.
///
/// The thesis's angle, area and length distortion (min / mean / max), symmetric
/// Dirichlet, conformal and area distortion, Sander's stretch, flipped triangles, UV
/// charts and the global overlap of the boundary. UV: (n, 2) floats, one per vertex;
/// or, with ``FUV`` ((m, 3) integers, as ``flatten(..., cut="auto")`` returns), any
/// number of rows, corner ``j`` of triangle ``t`` having UV ``UV[FUV[t, j]]``.
/// ``normalize`` scales the UVs to the surface's area first (as the command does
/// unless ``--raw``); ``overlap`` computes the boundary crossings and overlap area.
///
/// >>> import numpy as np, surfmap
/// >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
/// >>> F = np.array([[0, 1, 2], [0, 2, 3]])
/// >>> m = surfmap.measure(V, F, 3 * V[:, :2])  # a similarity: no distortion
/// >>> round(m["measures"]["angle"]["max"], 12), m["flipped_triangles"]
/// (1.0, 0)
#[pyfunction]
#[pyo3(signature = (V, F, UV, FUV=None, *, normalize=true, overlap=true))]
#[allow(non_snake_case)]
pub fn measure<'py>(
    py: Python<'py>,
    V: &Bound<'py, PyAny>,
    F: &Bound<'py, PyAny>,
    UV: &Bound<'py, PyAny>,
    FUV: Option<&Bound<'py, PyAny>>,
    normalize: bool,
    overlap: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let mesh = arrays::mesh(V, F)?;
    let uvs = texture_coordinates(&mesh, UV, FUV)?;
    let options = MeasureOptions { normalize, overlap };
    let (p, t) = (&mesh.positions, &mesh.triangles);
    let report = py
        .detach(|| match &uvs {
            Uvs::PerVertex(uvs) => surfmap::distortion_report_per_vertex(p, t, uvs, &options),
            Uvs::PerCorner { coords, indices } => {
                let corners = surfmap::measure::corner_uvs_from_indexed(t.len(), coords, indices)?;
                surfmap::distortion_report(p, t, &corners, &options)
            }
        })
        .map_err(measure_error)?;
    to_dict(py, &report)
}

/// The texture coordinates of `mesh` given as `UV` (one per vertex) or `UV` and `FUV`
/// (per corner), checked.
#[allow(non_snake_case)]
fn texture_coordinates(
    mesh: &TriMesh,
    UV: &Bound<'_, PyAny>,
    FUV: Option<&Bound<'_, PyAny>>,
) -> PyResult<Uvs> {
    match FUV.filter(|f| !f.is_none()) {
        None => Ok(Uvs::PerVertex(arrays::uvs(UV, "UV", mesh.num_vertices())?)),
        Some(fuv) => {
            let coords = arrays::uv_rows(UV, "UV")?;
            let indices = arrays::uv_triangles(fuv, "FUV", coords.len(), mesh.triangles.len())?;
            Ok(Uvs::PerCorner { coords, indices })
        }
    }
}

/// Reads a mesh file (OBJ, OFF or PLY, chosen by the extension; polygons are split
/// into triangles) and returns ``(V, F)``: an (n, 3) float64 array of positions and an
/// (m, 3) int64 array of triangles.
///
/// Raises ``FileNotFoundError`` (and the other ``OSError`` kinds) when the file cannot
/// be read, ``MeshError`` naming the line or byte when it does not parse.
///
/// >>> import os, tempfile, surfmap
/// >>> path = os.path.join(tempfile.mkdtemp(), "quad.off")
/// >>> _ = open(path, "w").write("OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")
/// >>> V, F = surfmap.read_mesh(path)
/// >>> V.shape, F.tolist()
/// ((4, 3), [[0, 1, 2], [0, 2, 3]])
#[pyfunction]
pub fn read_mesh(py: Python<'_>, path: PathBuf) -> PyResult<arrays::MeshArrays<'_>> {
    let file = py
        .detach(|| surfmap::read_mesh(&path))
        .map_err(read_error)?;
    Ok(arrays::mesh_arrays(
        py,
        file.mesh.positions,
        &file.mesh.triangles,
    ))
}

/// Writes an OBJ file: vertices ``V``, triangles ``F`` and, when given, the texture
/// coordinates ``vt``: one per vertex from ``UV`` (n, 2), or, with ``FUV`` ((m, 3)
/// integers: the result of ``flatten(..., cut="auto")``), the rows of ``UV`` with faces
/// ``f v/vt`` indexing them per corner. Written atomically (a temporary file renamed into
/// place); the numbers are written exactly (shortest round-trip form).
///
/// >>> import numpy as np, os, tempfile, surfmap
/// >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
/// >>> path = os.path.join(tempfile.mkdtemp(), "tri.obj")
/// >>> surfmap.write_obj(path, V, np.array([[0, 1, 2]]), UV=V[:, :2])
/// >>> W, G = surfmap.read_mesh(path)
/// >>> bool((W == V).all()), G.tolist()
/// (True, [[0, 1, 2]])
#[pyfunction]
#[pyo3(signature = (path, V, F, UV=None, FUV=None))]
#[allow(non_snake_case)]
pub fn write_obj(
    py: Python<'_>,
    path: PathBuf,
    V: &Bound<'_, PyAny>,
    F: &Bound<'_, PyAny>,
    UV: Option<&Bound<'_, PyAny>>,
    FUV: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let mut mesh: TriMesh = arrays::mesh(V, F)?;
    match UV.filter(|uv| !uv.is_none()) {
        Some(uv) => mesh.uvs = Some(texture_coordinates(&mesh, uv, FUV)?),
        None if FUV.is_some_and(|f| !f.is_none()) => {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "FUV indexes the rows of UV; give UV too",
            ));
        }
        None => {}
    }
    py.detach(|| surfmap::write_obj(&path, &mesh, None))
        .map_err(write_error)
}

/// Opt-in repairs of a mesh, the ones the defects of ``inspect`` and ``MeshError`` name,
/// applied in the order of the command line's repair flags: ``weld`` (merge vertices
/// closer than this tolerance; 0.0: exactly coincident ones), ``drop_degenerate`` (faces
/// with a repeated vertex or zero area, and faces repeating another face), ``reorient`` (flip faces for a consistent
/// orientation), ``fix_non_manifold`` (cut every edge shared by more than two faces
/// apart into sheets, faces paired by how smoothly they continue each other, a fin cut
/// loose; split a vertex that joins separate fans of faces into one copy per fan,
/// appended after the others; faces are removed only where the sheets cannot be cut
/// apart), ``keep_largest`` or ``component=N`` (keep one connected component, as numbered
/// by the defect message), ``drop_unreferenced`` (vertices no face uses). For a raw scan,
/// what the command line's ``--repair`` does: ``drop_degenerate=True,
/// fix_non_manifold=True, reorient=True, keep_largest=True, drop_unreferenced=True``
/// (``reorient`` raises on a non-orientable surface, which ``--repair`` leaves as it is).
///
/// Returns ``(V, F, done)``: the repaired arrays (vertex indices change when vertices
/// are merged or dropped) and a dictionary counting what each requested repair changed
/// (``welded``, ``dropped_degenerate``, ``flipped``, ``cut_edges``, ``unpaired_faces``,
/// ``dropped_non_manifold_faces`` and ``split_vertices``, ``dropped_faces``,
/// ``dropped_unreferenced``).
///
/// >>> import numpy as np, surfmap
/// >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0]], dtype=float)
/// >>> F = np.array([[0, 1, 2], [3, 4, 2]])  # vertex 3 duplicates vertex 1
/// >>> W, G, done = surfmap.repair(V, F, weld=0.0)
/// >>> len(W), G.tolist(), done
/// (4, [[0, 1, 2], [1, 3, 2]], {'welded': 1})
#[pyfunction]
#[pyo3(signature = (V, F, *, weld=None, drop_degenerate=false, reorient=false, keep_largest=false,
    component=None, drop_unreferenced=false, fix_non_manifold=false))]
#[allow(non_snake_case, clippy::too_many_arguments, clippy::type_complexity)]
pub fn repair<'py>(
    py: Python<'py>,
    V: &Bound<'py, PyAny>,
    F: &Bound<'py, PyAny>,
    weld: Option<f64>,
    drop_degenerate: bool,
    reorient: bool,
    keep_largest: bool,
    component: Option<usize>,
    drop_unreferenced: bool,
    fix_non_manifold: bool,
) -> PyResult<(
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, PyDict>,
)> {
    use pyo3::exceptions::PyValueError;
    use surfmap::mesh::repair;
    let mut mesh = arrays::mesh(V, F)?;
    let done = PyDict::new(py);
    if keep_largest && component.is_some() {
        return Err(PyValueError::new_err(
            "keep_largest and component both choose a component; give one of them",
        ));
    }
    if let Some(tol) = weld {
        if tol.is_nan() || tol < 0.0 {
            return Err(PyValueError::new_err(format!(
                "weld tolerance must be ≥ 0, got {tol}"
            )));
        }
        let (m, n) = py.detach(|| repair::weld(&mesh, tol));
        done.set_item("welded", n)?;
        mesh = m;
    }
    if drop_degenerate {
        let (m, n) = repair::drop_degenerate(&mesh);
        done.set_item("dropped_degenerate", n)?;
        mesh = m;
    }
    // Vertices no face uses are dropped first, so that they are counted even when
    // keeping one component would remove them with the others; and once more at the
    // end, for those whose faces a repair removed.
    let mut unreferenced = 0;
    if drop_unreferenced {
        let (m, n) = repair::drop_unreferenced(&mesh);
        unreferenced += n;
        mesh = m;
    }
    if fix_non_manifold {
        let (m, fix) = py.detach(|| repair::fix_non_manifold(&mesh));
        done.set_item("cut_edges", fix.cut_edges)?;
        done.set_item("unpaired_faces", fix.unpaired_faces)?;
        done.set_item("dropped_non_manifold_faces", fix.dropped_faces)?;
        done.set_item("split_vertices", fix.split_vertices)?;
        mesh = m;
    }
    if reorient {
        let (m, n) = py.detach(|| repair::reorient(&mesh)).ok_or_else(|| {
            crate::errors::mesh_error(
                "reorient: the surface is not orientable (a Möbius-like piece); it cannot be made consistent",
                &[],
            )
        })?;
        done.set_item("flipped", n)?;
        mesh = m;
    }
    if keep_largest || component.is_some() {
        let choice = match component {
            Some(i) => repair::ComponentChoice::Index(i),
            None => repair::ComponentChoice::Largest,
        };
        let (m, n) = py
            .detach(|| repair::keep_component(&mesh, choice))
            .ok_or_else(|| {
                PyValueError::new_err(format!(
                    "component {}: no such component ({} found)",
                    component.unwrap_or(0),
                    surfmap::Topology::new(&mesh).num_components
                ))
            })?;
        done.set_item("dropped_faces", n)?;
        mesh = m;
    }
    if drop_unreferenced {
        let (m, n) = repair::drop_unreferenced(&mesh);
        done.set_item("dropped_unreferenced", unreferenced + n)?;
        mesh = m;
    }
    let (v, f) = arrays::mesh_arrays(py, mesh.positions, &mesh.triangles);
    Ok((v, f, done))
}

/// The part of a surface within a ball around a point: the face of a head scan (a ball
/// around the nose tip), to match two surfaces of different extent on the region they
/// share (``surfmap crop``). ``center``: three numbers; ``radius`` in the mesh's units;
/// ``geodesic``: measure distance along the mesh's edges (a ball on a face then stops at
/// the cheeks instead of taking in the ears). Keeps the faces whose three vertices lie
/// inside, and of those the piece around the vertex nearest the centre.
///
/// Returns ``(V, F, ids)``: the cropped arrays and, per cropped vertex, its row in ``V``
/// (int64, rising).
///
/// >>> import numpy as np, surfmap
/// >>> x, y = np.meshgrid(np.linspace(0, 1, 11), np.linspace(0, 1, 11))
/// >>> V = np.c_[x.ravel(), y.ravel(), np.zeros(121)]
/// >>> i = np.arange(110).reshape(10, 11)[:, :-1].ravel()
/// >>> F = np.r_[np.c_[i, i + 1, i + 12], np.c_[i, i + 12, i + 11]]
/// >>> W, G, ids = surfmap.crop(V, F, center=[0.5, 0.5, 0.0], radius=0.25)
/// >>> bool(np.all(np.linalg.norm(W - [0.5, 0.5, 0.0], axis=1) <= 0.25)), np.array_equal(W, V[ids])
/// (True, True)
#[pyfunction]
#[pyo3(signature = (V, F, *, center, radius, geodesic=false))]
#[allow(non_snake_case, clippy::type_complexity)]
pub fn crop<'py>(
    py: Python<'py>,
    V: &Bound<'py, PyAny>,
    F: &Bound<'py, PyAny>,
    center: [f64; 3],
    radius: f64,
    geodesic: bool,
) -> PyResult<(
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, numpy::PyArray1<i64>>,
)> {
    use surfmap::mesh::crop::{CropDistance, crop_ball};
    let mesh = arrays::mesh(V, F)?;
    let distance = if geodesic {
        CropDistance::Geodesic
    } else {
        CropDistance::Euclidean
    };
    let crop = py
        .detach(|| crop_ball(&mesh, center, radius, distance))
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    let ids: Vec<i64> = crop.vertex_ids.iter().map(|&v| v as i64).collect();
    let (v, f) = arrays::mesh_arrays(py, crop.mesh.positions, &crop.mesh.triangles);
    Ok((v, f, numpy::PyArray1::from_vec(py, ids)))
}
