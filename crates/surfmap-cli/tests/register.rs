//! End-to-end test of `surfmap register`: the ICT neutral face registered onto other ICT
//! faces (registered to it: vertex i ↔ vertex i), moved in space, with broken scans in
//! the folder; then a rerun with `--resume`. Skips with a note without ../shared.

mod common;

use common::{shared_file, surfmap, temp_dir};
use std::path::Path;

/// `mesh` moved by a rotation of `angle` about z and a translation (cm).
fn moved(mesh: &surfmap::TriMesh, angle: f64, t: [f64; 3]) -> surfmap::TriMesh {
    let (s, c) = angle.sin_cos();
    let positions = mesh
        .positions
        .iter()
        .map(|p| {
            [
                c * p[0] - s * p[1] + t[0],
                s * p[0] + c * p[1] + t[1],
                p[2] + t[2],
            ]
        })
        .collect();
    surfmap::TriMesh::new(positions, mesh.triangles.clone())
}

fn summary(dir: &Path) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    serde_json::from_str::<serde_json::Value>(&text)
        .unwrap()
        .as_array()
        .unwrap()
        .clone()
}

#[test]
fn ict_faces_are_registered_and_broken_scans_listed() {
    let (Some(template), Some(id), Some(smile)) = (
        shared_file("faces/ict/ict_neutral.obj"),
        shared_file("faces/ict/ict_id002.obj"),
        shared_file("faces/ict/ict_smile_l.obj"),
    ) else {
        eprintln!("note: ../shared/data/faces/ict is absent; skipping the ICT registration test");
        return;
    };
    let dir = temp_dir("register-ict");
    let scans = dir.join("scans");
    std::fs::create_dir_all(&scans).unwrap();
    let mut truths = Vec::new();
    for (name, path, angle) in [("id002", &id, 0.3), ("smile_l", &smile, -0.2)] {
        let face = surfmap::read_mesh(path).unwrap().mesh;
        let scan = moved(&face, angle, [3.0, -2.0, 1.0]);
        surfmap::write_obj(&scans.join(format!("{name}.obj")), &scan, None).unwrap();
        truths.push((name, scan));
    }
    std::fs::write(scans.join("empty.obj"), "").unwrap();
    std::fs::write(
        scans.join("nan.obj"),
        "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let out = dir.join("out");
    let run = |extra: &[&str]| {
        surfmap()
            .arg("register")
            .arg(&template)
            .arg(&scans)
            .arg("-o")
            .arg(&out)
            .args(["--jobs", "2"])
            .args(extra)
            .output()
            .unwrap()
    };
    let first = run(&["--keep-matches"]);
    // Two scans failed: exit code 1, the reasons in the table.
    assert_eq!(first.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&first.stderr);
    assert!(stderr.contains("2 of 4 scans failed"), "{stderr}");
    let rows = summary(&out);
    let names: Vec<&str> = rows.iter().map(|r| r["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["empty", "id002", "nan", "smile_l"]);
    for bad in [&rows[0], &rows[2]] {
        assert_eq!(bad["status"], "failed");
        assert!(bad["error"].as_str().unwrap().len() > 10, "{bad}");
    }
    let template_mesh = surfmap::read_mesh(&template).unwrap().mesh;
    let width = {
        let xs = template_mesh.positions.iter().map(|p| p[0]);
        xs.clone().fold(f64::MIN, f64::max) - xs.fold(f64::MAX, f64::min)
    };
    for (row, (name, truth)) in [&rows[1], &rows[3]].into_iter().zip(&truths) {
        assert_eq!(row["status"], "ok", "{row}");
        let registered = surfmap::read_mesh(Path::new(row["output"].as_str().unwrap()))
            .unwrap()
            .mesh;
        assert_eq!(registered.triangles, template_mesh.triangles);
        let mut e: Vec<f64> = registered
            .positions
            .iter()
            .zip(&truth.positions)
            .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>().sqrt() / width)
            .collect();
        e.sort_by(f64::total_cmp);
        let mean = e.iter().sum::<f64>() / e.len() as f64;
        let p95 = e[e.len() * 95 / 100];
        eprintln!("{name}: mean {mean:.4}, p95 {p95:.4} of the face width; {row}");
        assert!(mean < 0.02 && p95 < 0.05, "{name}: mean {mean}, p95 {p95}");
        assert!(out.join(format!("matches/{name}/match.json")).is_file());
    }
    // The CSV has the same rows (an error may span lines, quoted).
    let csv = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert!(csv.starts_with("name,input,status,output,verdict,reasons,matched_fraction"));
    for r in &rows {
        let record = format!(
            "\n{},{},{},",
            r["name"].as_str().unwrap(),
            r["input"].as_str().unwrap(),
            r["status"].as_str().unwrap()
        );
        assert!(csv.contains(&record), "{record} in {csv}");
    }
    // Two registered scans: their shape model.
    let model = std::fs::read_to_string(out.join("model/model.json")).unwrap();
    let model: serde_json::Value = serde_json::from_str(&model).unwrap();
    assert_eq!(model["scans"], serde_json::json!(["id002", "smile_l"]));
    assert_eq!(model["variances"].as_array().unwrap().len(), 1);
    assert!(out.join("model/model.npz").is_file() && out.join("model/modes.png").is_file());
    // Resume: the registered scans keep their rows (not registered again).
    let second = run(&["--resume", "-q"]);
    assert_eq!(second.status.code(), Some(1));
    let again = summary(&out);
    assert_eq!(again[1], rows[1]);
    assert_eq!(again[3], rows[3]);
}

#[test]
fn bad_arguments_are_refused_with_their_remedy() {
    let dir = temp_dir("register-args");
    let template = dir.join("t.obj");
    surfmap::write_obj(
        &template,
        &surfmap::mesh::generate::bumpy_disc(6, 0.3),
        None,
    )
    .unwrap();
    let out = surfmap()
        .arg("register")
        .arg(&template)
        .arg(dir.join("*.ply"))
        .arg("-o")
        .arg(dir.join("o"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no scan in"));
    // A template that is no disc fails before any scan.
    let closed = dir.join("closed.obj");
    surfmap::write_obj(&closed, &surfmap::mesh::generate::sphere(2), None).unwrap();
    let out = surfmap()
        .arg("register")
        .arg(&closed)
        .arg(&template)
        .arg("-o")
        .arg(dir.join("o"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("template"), "{stderr}");
    assert!(!dir.join("o/summary.csv").exists());
}
