//! `surfmap flatten A B … -o DIR/`: the batch writes per mesh what the single-mesh
//! command writes, lists every bad mesh with its reason in `summary.csv` without
//! stopping, cuts surfaces that are not discs open as the single-mesh command does,
//! gives the same results on any number of threads, and refuses options that name one
//! file.

mod common;
use common::*;
use std::path::{Path, PathBuf};
use surfmap::mesh::generate::bumpy_disc;
use surfmap::mesh::io::read_mesh;

/// Generated meshes (two with the same stem, in two folders) and broken ones.
fn inputs(dir: &Path) -> (Vec<PathBuf>, Vec<PathBuf>) {
    std::fs::create_dir_all(dir.join("b")).unwrap();
    let good = vec![
        dir.join("disc.obj"),
        dir.join("b").join("disc.off"),
        dir.join("flat.ply"),
    ];
    surfmap::write_mesh(&good[0], &bumpy_disc(6, 0.4)).unwrap();
    surfmap::write_mesh(&good[1], &bumpy_disc(8, 0.2)).unwrap();
    surfmap::write_mesh(&good[2], &bumpy_disc(5, 0.0)).unwrap();
    let bad = vec![
        dir.join("truncated.off"),
        dir.join("two.obj"),
        dir.join("missing.obj"),
    ];
    std::fs::write(&bad[0], "OFF\n3 1 0\n0 0 0\n").unwrap();
    // Two separate squares: no fill or cut makes one disc of them.
    let square = surfmap::mesh::generate::unit_square();
    let mut two = square.clone();
    two.positions
        .extend(square.positions.iter().map(|p| [p[0] + 3.0, p[1], p[2]]));
    two.triangles
        .extend(square.triangles.iter().map(|t| t.map(|i| i + 4)));
    surfmap::write_mesh(&bad[1], &two).unwrap();
    (good, bad)
}

fn batch(inputs: &[PathBuf], out: &str, extra: &[&str]) -> std::process::Output {
    surfmap()
        .arg("flatten")
        .args(inputs)
        .args(["-o", out, "--quiet"])
        .args(extra)
        .output()
        .unwrap()
}

/// The summary table as header + records (an RFC 4180 reader: quoted fields may hold
/// commas, doubled quotes and line breaks).
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut records = vec![vec![String::new()]];
    let mut quoted = false;
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        let record = records.last_mut().unwrap();
        match (quoted, c) {
            (false, ',') => record.push(String::new()),
            (false, '\n') => records.push(vec![String::new()]),
            (false, '"') => quoted = true,
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                record.last_mut().unwrap().push('"');
            }
            (true, '"') => quoted = false,
            (_, c) => record.last_mut().unwrap().push(c),
        }
    }
    records.pop(); // after the last line break
    let header = records.remove(0);
    (header, records)
}

/// The largest coordinate difference between two lists of UVs.
fn max_abs_diff(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| [(p[0] - q[0]).abs(), (p[1] - q[1]).abs()])
        .fold(0.0, f64::max)
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

fn vertex_uvs(path: &Path) -> Vec<[f64; 2]> {
    read_mesh(path).unwrap().mesh.vertex_uvs().unwrap().to_vec()
}

#[test]
fn a_batch_flattens_the_good_meshes_and_lists_the_bad_ones() {
    let dir = temp_dir("batch");
    let (good, bad) = inputs(&dir);
    let all: Vec<PathBuf> = good.iter().chain(&bad).cloned().collect();
    let out = dir.join("out");
    let run = batch(&all, &format!("{}/", out.display()), &["--jobs", "2"]);
    assert_eq!(run.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("3 of 6 meshes failed"), "{stderr}");

    let (header, rows) = read_csv(&out.join("summary.csv"));
    assert_eq!(header, surfmap::batch::BatchRow::CSV_HEADER);
    assert_eq!(rows.len(), 6);
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    for (row, input) in rows.iter().zip(&all) {
        assert_eq!(row[col("input")], input.display().to_string());
    }
    // Each good mesh: what `surfmap flatten MESH -o X --report R` writes.
    let names = ["disc", "disc-2", "flat"];
    for ((row, input), name) in rows.iter().zip(&good).zip(names) {
        assert_eq!(row[col("status")], "ok");
        assert_eq!(row[col("error")], "");
        let obj = out.join(format!("{name}.obj"));
        assert_eq!(row[col("output")], obj.display().to_string());
        let single = dir.join(format!("single-{name}.obj"));
        let report = dir.join(format!("single-{name}.json"));
        let run = surfmap()
            .arg("flatten")
            .arg(input)
            .arg("-o")
            .arg(&single)
            .arg("--report")
            .arg(&report)
            .output()
            .unwrap();
        assert!(run.status.success());
        let (a, b) = (vertex_uvs(&obj), vertex_uvs(&single));
        let max_diff = max_abs_diff(&a, &b);
        assert!(max_diff <= 1e-12, "{name}: {max_diff}");
        let batch_report = read_json(&out.join(format!("{name}.json")));
        let single_report = read_json(&report);
        for key in ["iterations", "energy", "measures", "start", "input_defects"] {
            assert_eq!(batch_report[key], single_report[key], "{name}: {key}");
        }
        assert_eq!(
            row[col("iterations")],
            single_report["iterations"].to_string()
        );
        assert_eq!(row[col("energy")], single_report["energy"].to_string());
    }
    // Each bad mesh: failed, with the reason the single-mesh command gives.
    for (row, input) in rows[3..].iter().zip(&bad) {
        assert_eq!(row[col("status")], "failed");
        assert_eq!(row[col("output")], "");
        let error = &row[col("error")];
        assert!(error.contains(&input.display().to_string()), "{error}");
        let single = surfmap()
            .arg("flatten")
            .arg(input)
            .arg("-o")
            .arg(dir.join("x.obj"))
            .output()
            .unwrap();
        let message = String::from_utf8_lossy(&single.stderr);
        assert_eq!(format!("error: {error}\n"), message);
    }
    assert!(
        rows[4][col("error")].contains("components"),
        "{}",
        rows[4][col("error")]
    );
    // Nothing written for a failed mesh.
    let mut written: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    written.sort();
    assert_eq!(
        written,
        [
            "disc-2.json",
            "disc-2.obj",
            "disc.json",
            "disc.obj",
            "flat.json",
            "flat.obj",
            "summary.csv"
        ]
    );
}

#[test]
fn one_thread_and_two_give_the_same_maps() {
    let dir = temp_dir("batch-threads");
    let (good, _) = inputs(&dir);
    for jobs in ["1", "2"] {
        let run = batch(&good, &format!("{}/j{jobs}/", dir.display()), &["-j", jobs]);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
    }
    for name in ["disc", "disc-2", "flat"] {
        let one = vertex_uvs(&dir.join("j1").join(format!("{name}.obj")));
        let two = vertex_uvs(&dir.join("j2").join(format!("{name}.obj")));
        let max_diff = max_abs_diff(&one, &two);
        assert!(max_diff <= 1e-12, "{name}: {max_diff}");
    }
}

#[test]
fn an_existing_folder_makes_one_input_a_batch_and_flags_apply() {
    let dir = temp_dir("batch-one");
    let (good, _) = inputs(&dir);
    let out = dir.join("existing");
    std::fs::create_dir_all(&out).unwrap();
    let run = batch(
        &good[..1],
        &out.display().to_string(),
        &["--normalize", "--preset", "conformal"],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let uv = vertex_uvs(&out.join("disc.obj"));
    let (lo, hi) = uv
        .iter()
        .flatten()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &x| (lo.min(x), hi.max(x)));
    assert!(lo >= 0.0 && (hi - 1.0).abs() < 1e-12, "{lo} {hi}");
    let (_, rows) = read_csv(&out.join("summary.csv"));
    assert_eq!(rows.len(), 1);
}

#[test]
fn options_that_name_one_file_are_refused_in_a_batch() {
    let dir = temp_dir("batch-usage");
    let (good, _) = inputs(&dir);
    let out = format!("{}/o/", dir.display());
    let run = batch(&good, &out, &["--report", "r.json"]);
    assert_eq!(run.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&run.stderr).contains("NAME.json"));
    let run = batch(&good, &out, &["--seams", "seams.obj"]);
    assert!(String::from_utf8_lossy(&run.stderr).contains("NAME.seams.obj"));
    let run = batch(&good, &out, &["--pictures", "p"]);
    assert!(String::from_utf8_lossy(&run.stderr).contains("--pictures is for one mesh"));
    let run = batch(&good, &dir.join("flat.obj").display().to_string(), &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("end it with /"), "{stderr}");
    assert!(!dir.join("o").exists());
}

/// Closed and higher-genus meshes in a batch are cut open as `surfmap flatten MESH -o X
/// --seams S --report R` cuts them: the same per-corner UVs, seams and plan; a disc in
/// the same batch writes no seams.
#[test]
fn a_batch_cuts_surfaces_that_are_not_discs_as_one_mesh_does() {
    let dir = temp_dir("batch-cut");
    let inputs = [
        dir.join("sphere.obj"),
        dir.join("torus.obj"),
        dir.join("disc.obj"),
    ];
    surfmap::write_mesh(&inputs[0], &surfmap::mesh::generate::sphere(2)).unwrap();
    surfmap::write_mesh(&inputs[1], &surfmap::mesh::generate::torus(1.0, 0.4, 16, 8)).unwrap();
    surfmap::write_mesh(&inputs[2], &bumpy_disc(6, 0.4)).unwrap();
    let out = dir.join("out");
    let seams = dir.join("seams");
    let run = batch(
        &inputs,
        &format!("{}/", out.display()),
        &["--seams", &format!("{}/", seams.display())],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for (input, name) in inputs[..2].iter().zip(["sphere", "torus"]) {
        let single = dir.join(format!("single-{name}.obj"));
        let single_seams = dir.join(format!("single-{name}.seams.obj"));
        let report = dir.join(format!("single-{name}.json"));
        let run = surfmap()
            .arg("flatten")
            .arg(input)
            .arg("-o")
            .arg(&single)
            .arg("--seams")
            .arg(&single_seams)
            .arg("--report")
            .arg(&report)
            .output()
            .unwrap();
        assert!(run.status.success());
        let corner_uvs = |path: &Path| match read_mesh(path).unwrap().mesh.uvs {
            Some(surfmap::Uvs::PerCorner { coords, indices }) => (coords, indices),
            other => panic!("{name}: per-corner UVs expected, got {other:?}"),
        };
        let ((a, ia), (b, ib)) = (
            corner_uvs(&out.join(format!("{name}.obj"))),
            corner_uvs(&single),
        );
        assert_eq!(ia, ib, "{name}");
        let max_diff = max_abs_diff(&a, &b);
        assert!(max_diff <= 1e-12, "{name}: {max_diff}");
        assert_eq!(
            std::fs::read(seams.join(format!("{name}.seams.obj"))).unwrap(),
            std::fs::read(&single_seams).unwrap(),
            "{name}"
        );
        let batch_report = read_json(&out.join(format!("{name}.json")));
        let single_report = read_json(&report);
        assert!(
            batch_report["plan"]
                .as_str()
                .unwrap()
                .starts_with("cut open along seams"),
            "{name}: {}",
            batch_report["plan"]
        );
        assert_eq!(batch_report["guarantee"], "bijective", "{name}");
        for key in ["plan", "seams", "guarantee", "barrier", "measures"] {
            assert_eq!(batch_report[key], single_report[key], "{name}: {key}");
        }
    }
    assert!(!seams.join("disc.seams.obj").exists());
    assert!(
        read_mesh(&out.join("disc.obj"))
            .unwrap()
            .mesh
            .vertex_uvs()
            .is_some()
    );
}

/// The summary's distortion and what-was-done columns are the numbers of each mesh's
/// `NAME.json`, on a batch that does everything: a cone cut for the distortion bound (one
/// generator from the apex unrolls it: one cut, 12 edges), a sphere cut open for its
/// topology, a flat disc with two holes (filled), a flat disc as is.
#[test]
fn the_summary_columns_are_the_numbers_of_each_report() {
    let dir = temp_dir("batch-columns");
    let mut holed = surfmap::mesh::generate::grid_disc(8);
    holed
        .triangles
        .retain(|t| !t.contains(&(2 * 9 + 2)) && !t.contains(&(5 * 9 + 5)));
    let meshes = [
        ("cone", surfmap::mesh::generate::cone(1.0, 3.0, 12, 48)),
        ("sphere", surfmap::mesh::generate::sphere(2)),
        ("holed", holed),
        // Flat: an isometry flattens it, under any bound.
        ("disc", bumpy_disc(6, 0.0)),
    ];
    let inputs: Vec<PathBuf> = meshes
        .iter()
        .map(|(name, mesh)| {
            let path = dir.join(format!("{name}.obj"));
            surfmap::write_mesh(&path, mesh).unwrap();
            path
        })
        .collect();
    let out = dir.join("out");
    let bound = 1.01;
    let run = batch(
        &inputs,
        &format!("{}/", out.display()),
        &[
            "--max-distortion",
            &bound.to_string(),
            "--max-cut-rounds",
            "2",
        ],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (header, rows) = read_csv(&out.join("summary.csv"));
    let col = |row: &[String], name: &str| -> String {
        let i = header.iter().position(|h| h == name);
        row[i.unwrap_or_else(|| panic!("no column {name}"))].clone()
    };
    let number = |row: &[String], name: &str| -> f64 {
        let cell = col(row, name);
        cell.parse()
            .unwrap_or_else(|_| panic!("{name}: {cell:?} is no number"))
    };
    for (row, (name, _)) in rows.iter().zip(&meshes) {
        let json = read_json(&out.join(format!("{name}.json")));
        let m = &json["measures"];
        let t = &m["measures"];
        // Numbers: the JSON's, to the last bit or two (serde_json's default parser may
        // round a decimal's last bit; the CSV is Rust's shortest exact form).
        let same = |a: f64, b: f64| a == b || (a - b).abs() <= 1e-15 * a.abs().max(b.abs());
        for (column, value) in [
            ("energy", &json["energy"]),
            ("symmetric_dirichlet", &json["symmetric_dirichlet"]),
            ("symmetric_dirichlet_max", &m["symmetric_dirichlet_max"]),
            ("angle_mean", &t["angle"]["mean"]),
            ("angle_max", &t["angle"]["max"]),
            ("area_min", &t["area"]["min"]),
            ("area_mean", &t["area"]["mean"]),
            ("area_max", &t["area"]["max"]),
            ("distortion_bound", &json["distortion_cuts"]["bound"]),
            (
                "distortion_seam_length",
                &json["distortion_cuts"]["seam_length_added"],
            ),
        ] {
            let (a, b) = (number(row, column), value.as_f64().unwrap());
            assert!(same(a, b), "{name}: {column}: {a} vs {b}");
        }
        let seams = &json["seams"];
        let seam_edges = seams["edges"].as_array().map_or(0, Vec::len);
        assert_eq!(col(row, "seam_edges"), seam_edges.to_string(), "{name}");
        let (a, b) = (
            number(row, "seam_length"),
            seams["length"].as_f64().unwrap_or(0.0),
        );
        assert!(same(a, b), "{name}: seam_length {a} vs {b}");
        for (column, value) in [
            ("plan", &json["plan"]),
            ("guarantee", &json["guarantee"]),
            ("start", &json["start"]),
        ] {
            assert_eq!(
                col(row, column),
                value.as_str().unwrap(),
                "{name}: {column}"
            );
        }
        for (column, value) in [
            ("vertices", &json["vertices"]),
            ("triangles", &json["triangles"]),
            ("iterations", &json["iterations"]),
            ("converged", &json["converged"]),
            ("flipped_triangles", &json["flipped_triangles"]),
            ("holes_filled", &json["holes_filled"]),
            (
                "boundary_overlap",
                &json["boundary_overlap"]["self_intersecting"],
            ),
            ("distortion_bound_met", &json["distortion_cuts"]["met"]),
        ] {
            assert_eq!(col(row, column), value.to_string(), "{name}: {column}");
        }
        // The cut paths the map keeps: those of the rounds up to the best one.
        let cuts = &json["distortion_cuts"];
        let best = cuts["best_round"].as_u64().unwrap() as usize;
        let paths: usize = cuts["history"].as_array().unwrap()[..best]
            .iter()
            .map(|r| r["from_vertices"].as_array().unwrap().len())
            .sum();
        assert_eq!(col(row, "distortion_cuts"), paths.to_string(), "{name}");
        // The bound holds exactly when the mean symmetric Dirichlet energy over 4 (1
        // for an isometry) is under it.
        let d = number(row, "symmetric_dirichlet") / 4.0;
        assert_eq!(
            col(row, "distortion_bound_met"),
            (d <= bound).to_string(),
            "{name}: {d}"
        );
        assert!(number(row, "symmetric_dirichlet_max") >= number(row, "symmetric_dirichlet"));
    }
    // What was done, independently of the reports.
    let by_name = |name: &str| &rows[meshes.iter().position(|m| m.0 == name).unwrap()];
    let cone = by_name("cone");
    assert_eq!(col(cone, "plan"), "cut open to lower the distortion");
    assert_eq!(
        (col(cone, "distortion_cuts"), col(cone, "seam_edges")),
        ("1".into(), "12".into())
    );
    assert!((number(cone, "seam_length") - 1f64.hypot(3.0)).abs() < 1e-12);
    assert_eq!(col(cone, "distortion_bound_met"), "true");
    assert!(col(by_name("sphere"), "plan").starts_with("cut open along seams (closed, genus 0)"));
    assert!(number(by_name("sphere"), "seam_length") > 0.0);
    let holed = by_name("holed");
    assert_eq!(
        (col(holed, "plan"), col(holed, "holes_filled")),
        ("fill 2 holes".into(), "2".into())
    );
    assert_eq!(col(holed, "seam_edges"), "0");
    let disc = by_name("disc");
    assert_eq!(col(disc, "plan"), "disc as is");
    assert_eq!(col(disc, "distortion_cuts"), "0");
    for row in &rows {
        assert_eq!(col(row, "guarantee"), "bijective");
    }
}
