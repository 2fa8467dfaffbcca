//! The match folder on disk: `correspondence.npy` (float64 (n_A, 4), rows `[triangle
//! of B, b0, b1, b2]`), `correspondence.csv`, `A_on_B.obj`, `deformation.npy` (φ at the
//! grid nodes) and `match.json` (the report), each written to a temporary name and
//! renamed into place. Read back by [`crate::apps::match_folder`].

use std::path::Path;

use super::MatchError;
use super::deformation::Deformation;
use super::report::MatchReport;
use crate::fsutil::write_atomically;
use crate::mesh::{SurfacePoint, TriMesh};
use crate::raster::npy::save_npy;

/// File names inside a match folder (read back by [`crate::apps::match_folder`]).
pub const CORRESPONDENCE_FILE: &str = "correspondence.npy";

pub const INFO_FILE: &str = "match.json";

/// The correspondence as rows `[triangle of B, b0, b1, b2]` (triangle −1 and zeros
/// where unmatched), row-major (n_A, 4).
pub fn correspondence_rows(correspondence: &[Option<SurfacePoint>]) -> Vec<f64> {
    correspondence
        .iter()
        .flat_map(|p| match p {
            Some(s) => [
                s.triangle as f64,
                s.barycentric[0],
                s.barycentric[1],
                s.barycentric[2],
            ],
            None => [-1.0, 0.0, 0.0, 0.0],
        })
        .collect()
}

/// Writes the match folder: `correspondence.npy` (float64 (n_A, 4)),
/// `correspondence.csv` (`vertex,triangle,b0,b1,b2`), `A_on_B.obj`, `deformation.npy`
/// (float64 (n, n, 2): φ at the grid nodes, in ω_B) and `match.json` (the report).
/// `placed` is A on B from `a_on_b` (computed once by the caller, who may also draw
/// it). Every file is written to a temporary name and renamed into place; the folder is
/// created if missing. Returns the paths written.
pub(crate) fn write_match_folder(
    dir: &Path,
    deformation: &Deformation,
    correspondence: &[Option<SurfacePoint>],
    placed: &TriMesh,
    report: &MatchReport,
) -> Result<Vec<std::path::PathBuf>, MatchError> {
    let io = |what: &str, e: &dyn std::fmt::Display| MatchError::Output(format!("{what}: {e}"));
    std::fs::create_dir_all(dir)
        .map_err(|e| io(&format!("cannot create {}", dir.display()), &e))?;
    // Everything is computed before the first file is written.
    let rows = correspondence_rows(correspondence);
    let n = deformation.size;
    let phi: Vec<f64> = deformation.positions().iter().flat_map(|p| *p).collect();
    let json =
        serde_json::to_string_pretty(report).map_err(|e| io("cannot encode the report", &e))?;
    let mut csv = String::with_capacity(correspondence.len() * 48);
    csv.push_str("vertex,triangle,b0,b1,b2\n");
    for (v, r) in rows.chunks_exact(4).enumerate() {
        csv.push_str(&format!("{v},{},{},{},{}\n", r[0] as i64, r[1], r[2], r[3]));
    }
    let mut written = vec![];
    let mut file = |name: &str, f: &mut dyn FnMut(&Path) -> Result<(), MatchError>| {
        let path = dir.join(name);
        f(&path)?;
        written.push(path);
        Ok::<(), MatchError>(())
    };
    file(CORRESPONDENCE_FILE, &mut |p| {
        save_npy(p, &[correspondence.len(), 4], &rows)
            .map_err(|e| io(&format!("cannot write {}", p.display()), &e))
    })?;
    file("correspondence.csv", &mut |p| {
        write_atomically(p, |w| w.write_all(csv.as_bytes()))
            .map_err(|e| io(&format!("cannot write {}", p.display()), &e))
    })?;
    file("A_on_B.obj", &mut |p| {
        crate::mesh::io::write_obj(p, placed, None)
            .map_err(|e| io(&format!("cannot write {}", p.display()), &e))
    })?;
    file("deformation.npy", &mut |p| {
        save_npy(p, &[n, n, 2], &phi).map_err(|e| io(&format!("cannot write {}", p.display()), &e))
    })?;
    file(INFO_FILE, &mut |p| {
        write_atomically(p, |w| w.write_all(json.as_bytes()))
            .map_err(|e| io(&format!("cannot write {}", p.display()), &e))
    })?;
    Ok(written)
}
