//! The page of a match folder: A and B side by side under one camera, A's checkerboard
//! carried onto B through the correspondence, the unmatched vertices of A, the
//! confidence verdict and the report's numbers, a point picked on A shown at its image
//! on B, landmarks with their names, and a morph slider from A (0) to A on B (1).
//!
//! A match folder does not hold its surfaces: they are given (`--a`, `--b`) or read
//! from `match.json`'s `inputs` (`{"a": {"path", "vertices", "faces", "sha256"}, "b":
//! …}`; older folders name them as `"a": "PATH"`), a relative path looked up from the
//! working folder, the match folder and the folder above it. Meshes whose vertex or
//! face counts differ from those the folder records, or that the correspondence does
//! not fit, are refused.
//!
//! The morph moves every vertex of A along `d = x_end − x_a`: `x_end` from
//! `A_on_B.obj` when the folder has it (matched vertices at their points of B, the
//! others carried by the match's similarity), else the morph target of `surfmap
//! morph` ([`crate::apps::morph_target`]: matched vertices at their points of B, a
//! harmonic extension for the others).

use std::path::{Path, PathBuf};

use serde::Deserialize;
use serde_json::{Value, json};

use super::page::PageData;
use super::surface::{add_mesh, camera};
use super::{BuiltPage, PageKind, ViewError, numbers};
use crate::apps::correspondence::check_correspondence;
use crate::apps::match_folder::read_match_folder;
use crate::mesh::{SurfacePoint, TriMesh};

/// The report's numbers a match page lists (those present in `match.json`).
const REPORT_NUMBERS: [(&str, &str); 18] = [
    ("confidence", "confidence.verdict"),
    ("vertices of A", "vertices_a"),
    ("vertices of B", "vertices_b"),
    ("matched vertices of A", "matched_vertices_a"),
    ("matched fraction of A", "matched_fraction_a"),
    ("covered fraction of B", "covered_fraction_b"),
    ("area ratio (images / A)", "area_ratio"),
    ("min det Dφ", "min_det"),
    ("flipped image triangles", "flipped_triangles"),
    ("collapsed image triangles", "collapsed_triangles"),
    ("vertices dropped at folds", "dropped_vertices"),
    ("landmarks pinned", "pinned_landmarks"),
    ("largest landmark miss", "largest_landmark_miss"),
    ("scale of B", "scale_b"),
    ("grid size", "grid_size"),
    ("iterations", "iterations"),
    ("energy", "energy"),
    ("solve time (s)", "seconds_solve"),
];

/// A landmarks file: `{"names": [...], "A": [vertex ids], "B": [vertex ids]}`.
#[derive(Deserialize)]
struct LandmarksFile {
    #[serde(default)]
    names: Vec<String>,
    #[serde(rename = "A")]
    a: Vec<u32>,
    #[serde(rename = "B")]
    b: Vec<u32>,
}

/// Which surface of the match: its letter, the path given, and what `match.json` says.
struct Side<'a> {
    letter: &'static str,
    given: Option<&'a Path>,
}

/// Builds the page of the match folder `folder`; `a`, `b` name its surfaces (default:
/// those `match.json` names), `landmarks` a landmarks file.
pub(crate) fn build(
    folder: &Path,
    a: Option<&Path>,
    b: Option<&Path>,
    landmarks: Option<&Path>,
) -> Result<BuiltPage, ViewError> {
    let matched = read_match_folder(folder)?;
    let info = &matched.info;
    let (a_path, mesh_a) = load_side(
        folder,
        info,
        &Side {
            letter: "a",
            given: a,
        },
    )?;
    let (b_path, mesh_b) = load_side(
        folder,
        info,
        &Side {
            letter: "b",
            given: b,
        },
    )?;
    matched
        .check_meshes(&mesh_a, &mesh_b)
        .map_err(|e| ViewError::input(folder, e))?;
    let correspondence = &matched.correspondence;
    check_correspondence(correspondence, mesh_a.num_vertices(), mesh_b.num_triangles())
        .map_err(|e| {
            ViewError::input(
                folder,
                format!(
                    "{e} (A = {}, B = {}; was the match made for other meshes, or the other direction?)",
                    a_path.display(),
                    b_path.display()
                ),
            )
        })?;
    let title = folder
        .file_name()
        .map_or("match".into(), |n| n.to_string_lossy().into_owned());
    let mut page = PageData::new("match", &format!("match {title}"));
    let mut notes = vec![];
    let mesh_json = add_mesh(&mut page, "a", &mesh_a.positions, &mesh_a.triangles);
    page.set("a", mesh_json);
    let mesh_json = add_mesh(&mut page, "b", &mesh_b.positions, &mesh_b.triangles);
    page.set("b", mesh_json);
    add_correspondence(&mut page, correspondence);
    let (displacements, source) =
        morph_displacements(folder, &mesh_a, &mesh_b, correspondence, &mut notes)?;
    page.add_points("morph.displacements", &displacements);
    page.set("morph_source", json!(source));
    page.set("checker", checker_frame(&mesh_a));
    if let Some(path) = landmarks {
        let pairs = read_landmarks(path, &mesh_a, &mesh_b)?;
        page.set("landmarks", pairs);
    }
    let matched_count = correspondence.iter().filter(|p| p.is_some()).count();
    page.set(
        "counts",
        json!({"matched": matched_count, "unmatched": correspondence.len() - matched_count}),
    );
    page.set("numbers", numbers(info, &REPORT_NUMBERS));
    page.set(
        "confidence",
        info.get("confidence").cloned().unwrap_or(Value::Null),
    );
    page.set(
        "files",
        json!({"folder": folder.display().to_string(), "a": a_path.display().to_string(), "b": b_path.display().to_string()}),
    );
    page.set("report", info.clone());
    Ok(BuiltPage {
        kind: PageKind::Match,
        data: page,
        triangles: mesh_a.num_triangles() + mesh_b.num_triangles(),
        notes,
    })
}

/// The correspondence as two arrays: `corr.triangle` (i32, −1 unmatched) and
/// `corr.barycentric` (three f32 per vertex of A).
fn add_correspondence(page: &mut PageData, correspondence: &[Option<SurfacePoint>]) {
    page.add_i32(
        "corr.triangle",
        correspondence
            .iter()
            .map(|p| p.map_or(-1, |s| s.triangle as i32)),
    );
    page.add_f32(
        "corr.barycentric",
        correspondence
            .iter()
            .flat_map(|p| p.map_or([0.0; 3], |s| s.barycentric)),
        0.0,
    );
}

/// The morph's displacement per vertex of A and where it came from (see the module
/// docs).
fn morph_displacements(
    folder: &Path,
    a: &TriMesh,
    b: &TriMesh,
    correspondence: &[Option<SurfacePoint>],
    notes: &mut Vec<String>,
) -> Result<(Vec<[f64; 3]>, &'static str), ViewError> {
    let placed_path = folder.join("A_on_B.obj");
    if placed_path.is_file() {
        let placed = crate::read_mesh(&placed_path)?.mesh;
        if placed.num_vertices() == a.num_vertices() {
            let d = placed
                .positions
                .iter()
                .zip(&a.positions)
                .map(|(q, p)| [q[0] - p[0], q[1] - p[1], q[2] - p[2]])
                .collect();
            return Ok((d, "A_on_B.obj"));
        }
        notes.push(format!(
            "{} has {} vertices, A has {}: the morph follows the correspondence instead",
            placed_path.display(),
            placed.num_vertices(),
            a.num_vertices()
        ));
    }
    match crate::apps::morph_target(
        &a.positions,
        &a.triangles,
        correspondence,
        &b.positions,
        &b.triangles,
    ) {
        Ok(target) => Ok((
            target.displacements,
            "correspondence, unmatched vertices extended harmonically (as surfmap morph)",
        )),
        Err(e) => {
            notes.push(format!(
                "the morph's unmatched vertices stay where they are ({e})"
            ));
            let d = correspondence
                .iter()
                .zip(&a.positions)
                .map(|(s, p)| match s {
                    Some(s) => {
                        let q = s.position(&b.positions, &b.triangles);
                        [q[0] - p[0], q[1] - p[1], q[2] - p[2]]
                    }
                    None => [0.0; 3],
                })
                .collect();
            Ok((d, "correspondence, unmatched vertices fixed"))
        }
    }
}

/// The solid checkerboard of A: coordinates `(x − center)·axes / cell` in A's camera
/// frame, cells an eighth of its bounding radius. The page colours A by it and carries
/// it to B with the vertices.
fn checker_frame(a: &TriMesh) -> Value {
    let c = camera(&a.positions, &a.triangles);
    let cell = c["radius"].as_f64().unwrap_or(1.0) / 8.0;
    json!({"axes": c["axes"], "center": c["center"], "cell": cell})
}

/// The mesh of one side: the path given, or the one `match.json` names, resolved and
/// read, its counts checked against the folder's record.
fn load_side(
    folder: &Path,
    info: &Value,
    side: &Side<'_>,
) -> Result<(PathBuf, TriMesh), ViewError> {
    let letter = side.letter;
    let upper = letter.to_ascii_uppercase();
    let record = info.get("inputs").and_then(|i| i.get(letter));
    let named = record
        .and_then(|r| r.get("path"))
        .or_else(|| info.get(letter))
        .and_then(Value::as_str);
    let path = match (side.given, named) {
        (Some(p), _) => p.to_path_buf(),
        (None, Some(name)) => resolve(folder, name).ok_or_else(|| {
            ViewError::input(
                folder,
                format!(
                    "match.json names {name} as surface {upper}, but it is not found (looked from the working folder, the match folder and the folder above it); give it with --{letter} {upper}.obj"
                ),
            )
        })?,
        (None, None) => {
            return Err(ViewError::input(
                folder,
                format!(
                    "the match folder does not say which mesh surface {upper} is; give it with --{letter} {upper}.obj"
                ),
            ));
        }
    };
    let file = crate::read_mesh(&path)?;
    // A record with content digests is checked for both meshes at once in `build`
    // (it can tell swapped meshes apart); an older record by its counts here.
    if let Some(record) = record.filter(|r| r.get("sha256").is_none()) {
        check_counts(&path, &upper, record, &file)?;
    }
    Ok((path, file.mesh))
}

/// A relative `name` from the working folder, the match folder or the folder above it.
fn resolve(folder: &Path, name: &str) -> Option<PathBuf> {
    let p = Path::new(name);
    let mut candidates = vec![p.to_path_buf(), folder.join(p)];
    if let Some(up) = folder.parent() {
        candidates.push(up.join(p));
    }
    candidates.into_iter().find(|c| c.is_file())
}

/// The mesh's vertex and face counts must be those the match folder recorded.
fn check_counts(
    path: &Path,
    upper: &str,
    record: &Value,
    file: &crate::MeshFile,
) -> Result<(), ViewError> {
    let vertices = file.mesh.num_vertices();
    let faces = [file.stored_faces, file.mesh.num_triangles()];
    let recorded = |key: &str| record.get(key).and_then(Value::as_u64).map(|n| n as usize);
    let wrong_vertices = recorded("vertices").filter(|&n| n != vertices);
    let wrong_faces = recorded("faces").filter(|n| !faces.contains(n));
    if wrong_vertices.is_some() || wrong_faces.is_some() {
        return Err(ViewError::input(
            path,
            format!(
                "{vertices} vertices and {} faces, but the match was made with a surface {upper} of {} vertices and {} faces: give the mesh the match was made from",
                faces[0],
                recorded("vertices").map_or("?".into(), |n| n.to_string()),
                recorded("faces").map_or("?".into(), |n| n.to_string()),
            ),
        ));
    }
    Ok(())
}

/// A landmarks file checked against the meshes: `[{"name", "a", "b"}]`.
fn read_landmarks(path: &Path, a: &TriMesh, b: &TriMesh) -> Result<Value, ViewError> {
    let text = std::fs::read(path).map_err(ViewError::io(path))?;
    let file: LandmarksFile = serde_json::from_slice(&text).map_err(|e| {
        ViewError::input(
            path,
            format!("expected {{\"names\": [...], \"A\": [vertex ids], \"B\": [vertex ids]}}: {e}"),
        )
    })?;
    if file.a.len() != file.b.len() || (!file.names.is_empty() && file.names.len() != file.a.len())
    {
        return Err(ViewError::input(
            path,
            format!(
                "{} landmarks on A, {} on B and {} names: give one of each per landmark",
                file.a.len(),
                file.b.len(),
                file.names.len()
            ),
        ));
    }
    let mut out = vec![];
    for (i, (&va, &vb)) in file.a.iter().zip(&file.b).enumerate() {
        for (v, mesh, letter) in [(va, a, "A"), (vb, b, "B")] {
            if v as usize >= mesh.num_vertices() {
                return Err(ViewError::input(
                    path,
                    format!(
                        "landmark {i}: vertex {v} of {letter}, which has {} vertices",
                        mesh.num_vertices()
                    ),
                ));
            }
        }
        let name = file
            .names
            .get(i)
            .cloned()
            .unwrap_or_else(|| format!("{}", i + 1));
        out.push(json!({"name": name, "a": va, "b": vb}));
    }
    Ok(Value::Array(out))
}

#[cfg(test)]
mod tests {
    use super::super::page::tests::{array, embedded};
    use super::super::{ViewInput, ViewOptions, write_page};
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("surfmap-view-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// The generated inputs with a closed-form match (`apps_inputs`), small.
    fn inputs(dir: &Path) {
        crate::apps::inputs::write_inputs(dir, None, 64);
    }

    #[test]
    fn a_match_page_embeds_both_meshes_the_correspondence_and_the_morph() {
        let dir = temp("match");
        inputs(&dir);
        let folder = dir.join("match_ab");
        let landmarks = dir.join("landmarks.json");
        std::fs::write(
            &landmarks,
            r#"{"names": ["tip", "corner"], "A": [5, 40], "B": [7, 50]}"#,
        )
        .unwrap();
        let options = ViewOptions {
            landmarks: Some(landmarks),
            ..ViewOptions::default()
        };
        // match.json names a.obj and b.obj relative to the folder above it.
        let input = ViewInput::detect(&folder, &options).unwrap();
        let page = dir.join("match.html");
        let written = write_page(&input, &page).unwrap();
        assert_eq!(written.kind, PageKind::Match);
        let doc = embedded(&std::fs::read_to_string(&page).unwrap());
        let a = crate::read_mesh(&dir.join("a.obj")).unwrap().mesh;
        let b = crate::read_mesh(&dir.join("b.obj")).unwrap().mesh;
        assert_eq!(written.triangles, a.num_triangles() + b.num_triangles());
        let folder_data = read_match_folder(&folder).unwrap();
        let tri = array(&doc, "corr.triangle", i32::from_le_bytes);
        let bary = array(&doc, "corr.barycentric", f32::from_le_bytes);
        let disp = array(&doc, "morph.displacements", f32::from_le_bytes);
        let pos = array(&doc, "a.positions", f32::from_le_bytes);
        assert_eq!(tri.len(), a.num_vertices());
        let mut unmatched = 0;
        for (v, p) in folder_data.correspondence.iter().enumerate() {
            match p {
                None => {
                    assert_eq!(tri[v], -1);
                    unmatched += 1;
                }
                Some(s) => {
                    assert_eq!(tri[v], s.triangle as i32);
                    for k in 0..3 {
                        assert_eq!(bary[3 * v + k], s.barycentric[k] as f32);
                    }
                    // At t = 1 a matched vertex is at its point of B.
                    let q = s.position(&b.positions, &b.triangles);
                    for k in 0..3 {
                        let end = pos[3 * v + k] + disp[3 * v + k];
                        assert!((end as f64 - q[k]).abs() < 1e-5, "vertex {v}");
                    }
                }
            }
        }
        assert!(unmatched > 0, "the generated match is partial");
        assert_eq!(doc["counts"]["unmatched"], unmatched);
        assert_eq!(
            doc["landmarks"][1],
            json!({"name": "corner", "a": 40, "b": 50})
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn meshes_that_do_not_fit_the_folder_are_refused() {
        let dir = temp("match-wrong");
        inputs(&dir);
        let folder = dir.join("match_ab");
        let page = dir.join("p.html");
        let write = |a: Option<&str>, b: Option<&str>| {
            let options = ViewOptions {
                a: a.map(|n| dir.join(n)),
                b: b.map(|n| dir.join(n)),
                ..ViewOptions::default()
            };
            write_page(&ViewInput::detect(&folder, &options).unwrap(), &page)
                .unwrap_err()
                .to_string()
        };
        // Swapped meshes: the correspondence does not fit.
        let e = write(Some("b.obj"), Some("a.obj"));
        assert!(e.contains("A and B are swapped"), "{e}");
        // A folder whose match.json records other counts than the mesh given.
        let mut info: Value =
            serde_json::from_slice(&std::fs::read(folder.join("match.json")).unwrap()).unwrap();
        info["inputs"] =
            json!({"a": {"path": "a.obj", "vertices": 12, "faces": 3}, "b": {"path": "b.obj"}});
        std::fs::write(
            folder.join("match.json"),
            serde_json::to_vec(&info).unwrap(),
        )
        .unwrap();
        let e = write(None, None);
        assert!(
            e.contains("a.obj") && e.contains("12 vertices and 3 faces"),
            "{e}"
        );
        // A folder naming a mesh that is not there, and one naming none.
        info["inputs"]["a"] = json!({"path": "gone.obj"});
        std::fs::write(
            folder.join("match.json"),
            serde_json::to_vec(&info).unwrap(),
        )
        .unwrap();
        let e = write(None, None);
        assert!(e.contains("gone.obj") && e.contains("--a"), "{e}");
        std::fs::write(folder.join("match.json"), "{}").unwrap();
        let e = write(None, Some("b.obj"));
        assert!(e.contains("--a A.obj"), "{e}");
        assert!(!page.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
