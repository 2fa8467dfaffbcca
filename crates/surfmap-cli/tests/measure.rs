//! End-to-end tests of `surfmap measure` on small OBJ files written here (known
//! answers) and on the real meshes with `vt` in the shared data folder (skipped with a
//! note when that folder is missing, failing under `CI=true`).

use assert_cmd::Command;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn surfmap() -> Command {
    Command::cargo_bin("surfmap").unwrap()
}

/// An n×n grid on [0,1]² lifted to z = 0 with UVs = f(x, y), as OBJ text with `vt`.
fn grid_obj(n: usize, uv: impl Fn(f64, f64) -> [f64; 2]) -> String {
    let mut s = String::new();
    for i in 0..=n {
        for j in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            writeln!(s, "v {x} {y} 0").unwrap();
        }
    }
    for i in 0..=n {
        for j in 0..=n {
            let [u, v] = uv(i as f64 / n as f64, j as f64 / n as f64);
            writeln!(s, "vt {u} {v}").unwrap();
        }
    }
    let id = |i: usize, j: usize| i * (n + 1) + j + 1;
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            writeln!(s, "f {a}/{a} {b}/{b} {c}/{c}").unwrap();
            writeln!(s, "f {a}/{a} {c}/{c} {d}/{d}").unwrap();
        }
    }
    s
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn json_of(path: &Path) -> serde_json::Value {
    let out = surfmap()
        .arg("measure")
        .arg("--json")
        .arg(path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn identity_map_is_ideal_and_shear_has_known_singular_values() {
    let dir = tempfile::tempdir().unwrap();
    let id = write(dir.path(), "id.obj", &grid_obj(5, |x, y| [x, y]));
    let r = json_of(&id);
    assert_eq!(r["flipped_triangles"], 0);
    assert!((r["symmetric_dirichlet"].as_f64().unwrap() - 4.0).abs() < 1e-9);
    assert!((r["measures"]["angle"]["max"].as_f64().unwrap() - 1.0).abs() < 1e-9);
    assert_eq!(r["boundary_overlap"]["self_intersecting"], false);

    let k = 0.75;
    let sh = write(dir.path(), "shear.obj", &grid_obj(4, |x, y| [x + k * y, y]));
    let r = json_of(&sh);
    let s1 = ((k * k + 4.0f64).sqrt() + k) / 2.0;
    let s2 = ((k * k + 4.0f64).sqrt() - k) / 2.0;
    assert!((r["measures"]["angle"]["mean"].as_f64().unwrap() - s1 / s2).abs() < 1e-9);
    assert!((r["benchmark"]["max_singular_value"].as_f64().unwrap() - s1).abs() < 1e-9);
}

#[test]
fn csv_has_the_benchmark_header_and_one_row() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "scaled.obj", &grid_obj(3, |x, y| [2.0 * x, y]));
    let out = surfmap()
        .arg("measure")
        .arg("--csv")
        .arg(&p)
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2);
    assert_eq!(
        lines[0],
        "Filename,Faces,Vertices,Max Area Distortion,Average Area Discrepancy,Min Singular Value,\
         Max Singular Value,Proportion Flipped Triangles,Max Angle Distortion,\
         Average Angle Discrepancy,Symmetric Dirichlet Energy"
    );
    let row: Vec<&str> = lines[1].split(',').collect();
    assert_eq!(row[0], "scaled.obj");
    assert_eq!(row[1], "18");
    assert_eq!(row[2], "16");
    // Normalized (u, v) = (2x, y) is (√2 x, y/√2): max angle distortion 2 + 1/2 − 2.
    let max_angle: f64 = row[8].parse().unwrap();
    assert!((max_angle - 0.5).abs() < 1e-9);
}

#[test]
fn flipped_triangle_is_counted_and_pictures_are_written() {
    let dir = tempfile::tempdir().unwrap();
    // Fold vertex (2, 2) of a 4×4 grid past its neighbours.
    let mut text = grid_obj(4, |x, y| [x, y]);
    text = text.replace("vt 0.5 0.5\n", "vt 0.9 0.5\n");
    let p = write(dir.path(), "fold.obj", &text);
    let r = json_of(&p);
    assert!(r["flipped_triangles"].as_u64().unwrap() >= 1);
    assert!(r["boundary_overlap"]["overlap_area"].as_f64().unwrap() > 0.0);
    let (uv_png, checker_png) = (dir.path().join("uv.png"), dir.path().join("checker.png"));
    surfmap()
        .args([
            "measure",
            "--color-by",
            "area",
            "--size",
            "320x200",
            "--uv-png",
        ])
        .arg(&uv_png)
        .arg("--checker-png")
        .arg(&checker_png)
        .arg(&p)
        .assert()
        .success();
    for png in [&uv_png, &checker_png] {
        // PNG signature, then the IHDR chunk: width and height as big-endian u32.
        let bytes = std::fs::read(png).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
        assert_eq!((be(16), be(20)), (320, 200));
    }
}

#[test]
fn mesh_without_uvs_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "plain.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let out = surfmap().arg("measure").arg(&p).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no texture coordinates"), "{err}");
}

#[test]
fn real_meshes_with_vt_are_measured() {
    let Some(data) = surfmap::testing::shared_data() else {
        return;
    };
    for name in [
        "faces/mp_canonical.obj",
        "sphere.obj",
        "punctured_torus.obj",
    ] {
        let p = data.join(name);
        let r = json_of(&p);
        let n = r["num_triangles"].as_u64().unwrap();
        assert!(n > 0, "{name}");
        let sd = r["symmetric_dirichlet"].as_f64().unwrap_or(f64::INFINITY);
        assert!(
            sd >= 4.0 - 1e-9,
            "{name}: symmetric Dirichlet {sd} below the isometry value"
        );
        assert!(r["charts"].as_u64().unwrap() >= 1);
    }
}
