//! What the application commands (`transfer`, `morph`, `rig`) share: reading a match
//! folder and checking it against its meshes, a chart (flattening) of a surface to
//! carry points through, and per-vertex values from `.npy` files.

use std::path::Path;

use anyhow::{Context, bail};
use surfmap::apps::Chart;
use surfmap::apps::correspondence::check_correspondence;
use surfmap::apps::match_folder::read_match_folder;
use surfmap::{FlattenOptions, SurfacePoint, TriMesh};

/// The correspondence A → B of a match folder, checked against A and B.
pub fn load_match(
    dir: &Path,
    a: &TriMesh,
    a_name: &Path,
    b: &TriMesh,
    b_name: &Path,
) -> anyhow::Result<Vec<Option<SurfacePoint>>> {
    let folder = read_match_folder(dir)?;
    folder.check_meshes(a, b).map_err(|why| {
        anyhow::anyhow!(
            "the match {} was not made from {} → {}: {why}",
            dir.display(),
            a_name.display(),
            b_name.display()
        )
    })?;
    check_correspondence(&folder.correspondence, a.num_vertices(), b.num_triangles()).with_context(
        || {
            format!(
                "the match {} does not fit {} → {} (was it made for other meshes, or the other direction?)",
                dir.display(),
                a_name.display(),
                b_name.display()
            )
        },
    )?;
    if folder.correspondence.iter().all(Option::is_none) {
        bail!(
            "the match {} leaves every vertex of {} unmatched",
            dir.display(),
            a_name.display()
        );
    }
    Ok(folder.correspondence)
}

/// A chart of `mesh` to carry points through: its balanced flattening (holes filled for
/// the solve).
pub fn chart_of(mesh: &TriMesh, name: &Path, quiet: bool) -> anyhow::Result<Chart> {
    // A chart is one UV per vertex over a disc: never cut.
    let options = FlattenOptions::default()
        .with_fill_holes(true)
        .with_cut(surfmap::Cut::Never);
    let flat = super::flatten::flatten_mesh(mesh, &options, true)
        .with_context(|| format!("cannot flatten {} for its chart", name.display()))?;
    if !quiet {
        eprintln!(
            "chart: flattened {} ({} iterations, {:.3} s)",
            name.display(),
            flat.iterations,
            flat.time_total
        );
    }
    Ok(Chart::new(flat.uvs, mesh.triangles.clone())?)
}

/// Per-vertex values from a float64 `.npy` of shape `(n,)` or `(n, k)`: the values row by
/// row and `k` (1 for a vector).
pub fn read_vertex_values(path: &Path, n: usize, of: &str) -> anyhow::Result<(Vec<f64>, usize)> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let (shape, values) = surfmap::raster::npy::read_npy_f64(&bytes)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let k = match shape[..] {
        [rows] if rows == n => 1,
        [rows, k] if rows == n && k > 0 => k,
        _ => bail!(
            "{}: shape {shape:?}, but {of} has {n} vertices: give one row per vertex, shape ({n},) or ({n}, k)",
            path.display()
        ),
    };
    Ok((values, k))
}
