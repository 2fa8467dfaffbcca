//! End-to-end test of `surfmap register`: the ICT neutral face registered onto other ICT
//! faces (registered to it: vertex i ↔ vertex i), moved in space, with broken scans in
//! the folder; then a rerun with `--resume`. Skips with a note without ../shared.

mod common;

use common::{distances, moved, shared_file, surfmap, temp_dir, width_x};
use std::path::Path;

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
    let width = width_x(&template_mesh);
    for (row, (name, truth)) in [&rows[1], &rows[3]].into_iter().zip(&truths) {
        assert_eq!(row["status"], "ok", "{row}");
        let registered = surfmap::read_mesh(Path::new(row["output"].as_str().unwrap()))
            .unwrap()
            .mesh;
        assert_eq!(registered.triangles, template_mesh.triangles);
        let mut e: Vec<f64> = distances(&registered.positions, &truth.positions)
            .into_iter()
            .map(|d| d / width)
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

#[test]
fn a_sequence_is_registered_in_order_with_its_jitter() {
    let (Some(template), Some(smile)) = (
        shared_file("faces/ict/ict_neutral.obj"),
        shared_file("faces/ict/ict_smile_l.obj"),
    ) else {
        eprintln!("note: ../shared/data/faces/ict is absent; skipping the sequence test");
        return;
    };
    let dir = temp_dir("register-sequence");
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    // Three frames blending the neutral into the smile (vertex by vertex: the ICT crops
    // are registered), the head turning and drifting; the truth of template vertex i on
    // frame k is vertex i of the blend, moved.
    let neutral = surfmap::read_mesh(&template).unwrap().mesh;
    let smile = surfmap::read_mesh(&smile).unwrap().mesh;
    let mut truths = Vec::new();
    for k in 0..3 {
        let s = 0.5 * k as f64;
        let blend = surfmap::TriMesh::new(
            neutral
                .positions
                .iter()
                .zip(&smile.positions)
                .map(|(p, q)| std::array::from_fn(|c| (1.0 - s) * p[c] + s * q[c]))
                .collect(),
            neutral.triangles.clone(),
        );
        let frame = moved(
            &blend,
            0.03 * k as f64,
            [0.3 * k as f64, -0.1 * k as f64, 0.0],
        );
        surfmap::write_obj(&frames.join(format!("frame{k}.obj")), &frame, None).unwrap();
        truths.push(frame);
    }
    let out = dir.join("out");
    let run = surfmap()
        .arg("register")
        .arg(&template)
        .arg(&frames)
        .arg("-o")
        .arg(&out)
        .args(["--sequence", "--warm-start", "--no-model", "--jobs", "2"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let rows = summary(&out);
    let width = width_x(&neutral);
    let mut mean_errors = Vec::new();
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row["name"], format!("frame{k}"));
        assert_eq!(row["status"], "ok", "{row}");
        // Each frame from the previous one (when that one's verdict is ok).
        let from = row["started_from"].as_str().unwrap();
        if k == 0 || rows[k - 1]["verdict"] != "ok" {
            assert_eq!(from, "template");
        } else {
            assert_eq!(from, format!("frame{}", k - 1));
        }
        let registered = surfmap::read_mesh(Path::new(row["output"].as_str().unwrap()))
            .unwrap()
            .mesh;
        let e = distances(&registered.positions, &truths[k].positions);
        let mean = e.iter().sum::<f64>() / e.len() as f64;
        eprintln!(
            "frame {k}: mean error {:.3} % of the face width; {row}",
            100.0 * mean / width
        );
        assert!(mean < 0.01 * width, "frame {k}: mean {mean}");
        mean_errors.push(mean);
    }
    // Motion since the previous frame on frames 1 and 2; jitter on the middle frame only.
    assert!(rows[0]["motion_mean"].is_null() && rows[0]["jitter_mean"].is_null());
    assert!(rows[2]["jitter_mean"].is_null());
    // The true jitter is 0 (a linear blend moved rigidly, up to the rigid fits); the
    // registered one is bounded by the errors: |y_1 − ½(y_0 + y_2)| ≤ e_1 + ½(e_0 + e_2)
    // vertex by vertex (with the rigid fits' small share).
    let jitter = rows[1]["jitter_mean"].as_f64().unwrap();
    let bound = mean_errors[1] + 0.5 * (mean_errors[0] + mean_errors[2]);
    assert!(
        jitter > 0.0 && jitter < 1.2 * bound,
        "jitter {jitter}, bound {bound}"
    );
    assert!(rows[1]["jitter_p95"].as_f64().unwrap() >= jitter);
    // The motion is the smile's half step (non-rigid), within the two frames' errors.
    for k in 1..3 {
        let truth_step = neutral
            .positions
            .iter()
            .zip(&smile.positions)
            .map(|(p, q)| 0.5 * (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>().sqrt())
            .sum::<f64>()
            / neutral.positions.len() as f64;
        let motion = rows[k]["motion_mean"].as_f64().unwrap();
        let slack = mean_errors[k] + mean_errors[k - 1];
        assert!(
            (motion - truth_step).abs() < 1.2 * slack + 0.2 * truth_step,
            "frame {k}: motion {motion}, true step {truth_step}, errors {slack}"
        );
    }
    let csv = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .ends_with("started_from,motion_mean,jitter_mean,jitter_p95")
    );
}
