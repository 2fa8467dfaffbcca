//! Reads every mesh in the shared data folder and checks it against `manifest.json`, which was
//! written by an independent (Python) script: vertex records V, faces as stored F, the number
//! of triangles implied by the face-size histogram, and the bounding box of the used vertices.
//!
//! The folder is `surfmap::testing::shared_data()` (`../shared/data` beside the repository,
//! override: `SURFMAP_DATA`); when it is missing the test prints a note and passes, except
//! under `CI=true`, where it fails.

use std::collections::BTreeMap;
use std::path::Path;

use surfmap::mesh::io::{Format, read_mesh};

fn mesh_files(dir: &Path, root: &Path, out: &mut Vec<String>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            mesh_files(&path, root, out);
        } else if Format::from_path(&path).is_some() {
            let rel = path.strip_prefix(root).unwrap();
            out.push(rel.to_string_lossy().replace('\\', "/"));
        }
    }
}

#[test]
fn every_shared_mesh_matches_the_manifest() {
    let Some(dir) = surfmap::testing::shared_data() else {
        return;
    };
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("manifest.json")).unwrap()).unwrap();
    let entries: BTreeMap<String, &serde_json::Value> = manifest["files"]
        .as_array()
        .expect("manifest has a 'files' array")
        .iter()
        .map(|f| (f["file"].as_str().unwrap().to_owned(), f))
        .collect();

    let mut on_disk = Vec::new();
    mesh_files(&dir, &dir, &mut on_disk);
    let listed: Vec<&String> = entries.keys().collect();
    let mut sorted_disk = on_disk.clone();
    sorted_disk.sort();
    assert_eq!(
        sorted_disk.iter().collect::<Vec<_>>(),
        listed,
        "mesh files on disk and in manifest.json differ"
    );

    let mut failures = Vec::new();
    for name in &on_disk {
        let entry = entries[name];
        let file = match read_mesh(&dir.join(name)) {
            Ok(f) => f,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        let v = entry["V"].as_u64().unwrap() as usize;
        let f = entry["F"].as_u64().unwrap() as usize;
        if file.mesh.num_vertices() != v || file.stored_faces != f {
            failures.push(format!(
                "{name}: read V={} F={}, manifest V={v} F={f}",
                file.mesh.num_vertices(),
                file.stored_faces
            ));
        }
        // A polygon of n corners becomes n − 2 triangles.
        let triangles: u64 = entry["face_sizes"]
            .as_object()
            .unwrap()
            .iter()
            .map(|(n, count)| (n.parse::<u64>().unwrap() - 2) * count.as_u64().unwrap())
            .sum();
        if file.mesh.num_triangles() as u64 != triangles {
            failures.push(format!(
                "{name}: {} triangles, face sizes imply {triangles}",
                file.mesh.num_triangles()
            ));
        }
        // The manifest's box spans the vertices that faces use.
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &i in file.mesh.triangles.iter().flatten() {
            let p = file.mesh.positions[i as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        for k in 0..3 {
            let (elo, ehi) = (
                entry["bbox_min"][k].as_f64().unwrap(),
                entry["bbox_max"][k].as_f64().unwrap(),
            );
            // The manifest prints about 6 significant digits.
            let tol = 1e-5 * (ehi - elo).abs().max(elo.abs()).max(ehi.abs()).max(1e-9);
            if (lo[k] - elo).abs() > tol || (hi[k] - ehi).abs() > tol {
                failures.push(format!(
                    "{name}: bbox axis {k} [{}, {}], manifest [{elo}, {ehi}]",
                    lo[k], hi[k]
                ));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} files differ:\n{}",
        failures.len(),
        on_disk.len(),
        failures.join("\n")
    );
    println!("{} meshes match manifest.json", on_disk.len());
}
