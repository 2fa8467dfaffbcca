//! A match folder on disk: `DIR/correspondence.npy` (float64, shape `(n_A, 4)`, row `a`
//! = `[triangle of B, b0, b1, b2]`, triangle `−1` (or any negative or NaN value) for a
//! vertex of A without a counterpart) and `DIR/match.json` (whatever the matcher
//! recorded about the match; kept as JSON).

use std::path::Path;

use super::AppError;
use crate::mesh::SurfacePoint;
use crate::raster::npy::{read_npy_f64, save_npy};

/// File names inside a match folder and the row encoding: the matcher's
/// ([`crate::matching::folder`]), which writes the folders these functions read.
pub use crate::matching::folder::{CORRESPONDENCE_FILE, INFO_FILE, correspondence_rows};
use crate::matching::{InputMesh, Inputs};

/// A match folder's contents.
#[derive(Clone, Debug, PartialEq)]
pub struct MatchFolder {
    /// One entry per vertex of A.
    pub correspondence: Vec<Option<SurfacePoint>>,
    /// `match.json` (`Null` when the folder has none).
    pub info: serde_json::Value,
}

/// Decodes rows `[triangle, b0, b1, b2]` (negative or NaN triangle: unmatched). A
/// triangle that is not a whole number is an error naming the row.
pub fn correspondence_from_rows(rows: &[f64]) -> Result<Vec<Option<SurfacePoint>>, String> {
    if !rows.len().is_multiple_of(4) {
        return Err(format!("{} values do not form rows of 4", rows.len()));
    }
    rows.chunks_exact(4)
        .enumerate()
        .map(|(i, r)| {
            let t = r[0];
            if t.is_nan() || t < 0.0 {
                return Ok(None);
            }
            if t.fract() != 0.0 || t > u32::MAX as f64 {
                return Err(format!(
                    "row {i}: triangle {t} is not a triangle index (a whole number ≥ 0, or −1 for unmatched)"
                ));
            }
            Ok(Some(SurfacePoint {
                triangle: t as u32,
                barycentric: [r[1], r[2], r[3]],
            }))
        })
        .collect()
}

/// Reads a match folder. The correspondence is not checked against meshes here (see
/// [`super::correspondence::check_correspondence`]).
pub fn read_match_folder(dir: &Path) -> Result<MatchFolder, AppError> {
    if !dir.is_dir() {
        return Err(AppError::file(
            dir,
            "not a folder; a match folder holds correspondence.npy and match.json (written by `surfmap match`)",
        ));
    }
    let npy = dir.join(CORRESPONDENCE_FILE);
    let bytes = std::fs::read(&npy).map_err(AppError::io(&npy))?;
    let (shape, values) = read_npy_f64(&bytes).map_err(|e| AppError::file(&npy, e))?;
    if shape.len() != 2 || shape[1] != 4 {
        return Err(AppError::file(
            &npy,
            format!(
                "shape {shape:?}; a correspondence has shape (vertices of A, 4): rows [triangle of B, b0, b1, b2]"
            ),
        ));
    }
    let correspondence = correspondence_from_rows(&values).map_err(|e| AppError::file(&npy, e))?;
    let json = dir.join(INFO_FILE);
    let info = match std::fs::read(&json) {
        Ok(text) => serde_json::from_slice(&text)
            .map_err(|e| AppError::file(&json, format!("not valid JSON: {e}")))?,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => serde_json::Value::Null,
        Err(e) => return Err(AppError::io(&json)(e)),
    };
    Ok(MatchFolder {
        correspondence,
        info,
    })
}

impl MatchFolder {
    /// The meshes the match was made from, when `match.json` records them (folders
    /// written before it did have no record).
    pub fn inputs(&self) -> Option<Inputs> {
        serde_json::from_value(self.info.get("inputs")?.clone()).ok()
    }

    /// Whether `a` and `b` are the meshes the match was made from (by their content
    /// digests, [`crate::TriMesh::content_sha256`]); an error naming which is not — and
    /// saying so when A and B were swapped. Passes a folder without a record.
    pub fn check_meshes(&self, a: &crate::TriMesh, b: &crate::TriMesh) -> Result<(), String> {
        let Some(made) = self.inputs() else {
            return Ok(());
        };
        let (ha, hb) = (a.content_sha256(), b.content_sha256());
        if ha == made.a.sha256 && hb == made.b.sha256 {
            return Ok(());
        }
        let named = |m: &InputMesh| {
            format!(
                "{} ({} vertices, {} faces)",
                m.path.as_deref().unwrap_or("a mesh given as arrays"),
                m.vertices,
                m.faces
            )
        };
        if ha == made.b.sha256 && hb == made.a.sha256 {
            return Err(format!(
                "A and B are swapped: the match maps A = {} onto B = {}; give them in that order \
                 (or match the other way round)",
                named(&made.a),
                named(&made.b)
            ));
        }
        let wrong: Vec<String> = [("A", &ha, a, &made.a), ("B", &hb, b, &made.b)]
            .into_iter()
            .filter(|(_, h, _, m)| **h != m.sha256)
            .map(|(side, _, given, m)| {
                format!(
                    "{side} ({} vertices, {} faces) is not the mesh the match was made from, {}",
                    given.num_vertices(),
                    given.triangles.len(),
                    named(m)
                )
            })
            .collect();
        Err(format!(
            "{}; give the meshes the match was made from, or match these",
            wrong.join("; ")
        ))
    }
}

/// Writes a match folder (created if missing): the correspondence and `info` as
/// `match.json`, each file atomically.
pub fn write_match_folder(
    dir: &Path,
    correspondence: &[Option<SurfacePoint>],
    info: &serde_json::Value,
) -> Result<(), AppError> {
    std::fs::create_dir_all(dir).map_err(AppError::io(dir))?;
    let npy = dir.join(CORRESPONDENCE_FILE);
    save_npy(
        &npy,
        &[correspondence.len(), 4],
        &correspondence_rows(correspondence),
    )
    .map_err(AppError::io(&npy))?;
    let json = dir.join(INFO_FILE);
    let text = serde_json::to_vec_pretty(info).map_err(|e| AppError::file(&json, e.to_string()))?;
    crate::fsutil::write_atomically(&json, |w| w.write_all(&text)).map_err(AppError::io(&json))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder is used only with the meshes it was made from: the same meshes pass
    /// (also re-read, the digest is of the content), swapped ones are named as swapped,
    /// another key as the side that differs; a folder without a record passes.
    #[test]
    fn a_folder_refuses_meshes_it_was_not_made_from() {
        let a = crate::mesh::generate::bumpy_disc(6, 0.3);
        let b = crate::mesh::generate::bumpy_disc(7, 0.3);
        let mut other = b.clone();
        other.positions[3][2] += 1e-9;
        let inputs = Inputs {
            a: InputMesh {
                path: Some("neutral.obj".into()),
                ..InputMesh::of(&a)
            },
            b: InputMesh {
                path: Some("smile.obj".into()),
                ..InputMesh::of(&b)
            },
        };
        let folder = MatchFolder {
            correspondence: vec![],
            info: serde_json::json!({ "inputs": inputs }),
        };
        assert_eq!(folder.inputs(), Some(inputs));
        assert_eq!(folder.check_meshes(&a, &b.clone()), Ok(()));
        let e = folder.check_meshes(&b, &a).unwrap_err();
        assert!(
            e.starts_with("A and B are swapped") && e.contains("neutral.obj"),
            "{e}"
        );
        let e = folder.check_meshes(&a, &other).unwrap_err();
        assert!(
            e.starts_with("B (") && e.contains("smile.obj") && !e.contains("A ("),
            "{e}"
        );
        let old = MatchFolder {
            correspondence: vec![],
            info: serde_json::json!({}),
        };
        assert_eq!(old.check_meshes(&a, &other), Ok(()));
    }

    #[test]
    fn folders_round_trip_and_bad_files_are_named() {
        let dir = std::env::temp_dir().join(format!("surfmap-match-folder-{}", std::process::id()));
        let points = vec![
            Some(SurfacePoint {
                triangle: 3,
                barycentric: [0.25, 0.5, 0.25],
            }),
            None,
            Some(SurfacePoint {
                triangle: 0,
                barycentric: [1.0, 0.0, 0.0],
            }),
        ];
        let info = serde_json::json!({"a": "neutral.obj", "b": "smile.obj"});
        write_match_folder(&dir, &points, &info).unwrap();
        let back = read_match_folder(&dir).unwrap();
        assert_eq!(back.correspondence, points);
        assert_eq!(back.info, info);
        // NaN triangles are unmatched too; a fractional one is an error naming its row.
        assert_eq!(
            correspondence_from_rows(&[f64::NAN, 0.0, 0.0, 0.0]).unwrap(),
            vec![None]
        );
        let e = correspondence_from_rows(&[0.0, 1.0, 0.0, 0.0, 2.5, 1.0, 0.0, 0.0]).unwrap_err();
        assert!(e.contains("row 1"), "{e}");
        // A wrong shape names the file and the expected shape.
        save_npy(&dir.join(CORRESPONDENCE_FILE), &[2, 3], &[0.0f64; 6]).unwrap();
        let e = read_match_folder(&dir).unwrap_err().to_string();
        assert!(
            e.contains("correspondence.npy") && e.contains("(vertices of A, 4)"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
        let e = read_match_folder(&dir).unwrap_err().to_string();
        assert!(e.contains("not a folder"), "{e}");
    }
}
