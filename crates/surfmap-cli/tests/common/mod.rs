//! Shared helpers for the end-to-end tests: the `surfmap` binary and the real meshes
//! in the shared data folder (`surfmap::testing::shared_data`: tests skip with a note
//! when that folder is absent, and fail under `CI=true`).
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Command;

#[allow(unused_imports)]
pub use surfmap::testing::{shared_data, shared_file};

pub fn manifest() -> Option<(PathBuf, Vec<serde_json::Value>)> {
    let d = shared_data()?;
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("manifest.json")).unwrap()).unwrap();
    Some((d, m["files"].as_array().unwrap().clone()))
}

/// Disc meshes of the manifest: one boundary loop, genus 0.
pub fn disc_meshes() -> Vec<PathBuf> {
    let Some((d, files)) = manifest() else {
        return Vec::new();
    };
    files
        .iter()
        .filter(|f| f["boundary_loops"] == 1 && f["genus"] == 0)
        .map(|f| d.join(f["file"].as_str().unwrap()))
        .collect()
}

pub fn surfmap() -> Command {
    Command::new(env!("CARGO_BIN_EXE_surfmap"))
}

pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("surfmap-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `surfmap ARGS` in `dir`, asserting that it succeeded; returns its stdout.
pub fn run_in(dir: &std::path::Path, args: &[&str]) -> String {
    let out = surfmap().current_dir(dir).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "surfmap {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Runs `command`, asserting that it succeeded (its stderr in the message otherwise).
pub fn run_ok(command: &mut Command) -> std::process::Output {
    let out = command.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `surfmap demo -o dir --rings N` and returns its stdout; `dir` then holds
/// `surface.obj` (no texture coordinates) and `conformal.obj` / `balanced.obj` (the
/// same surface with a flattening as `vt`).
pub fn run_demo(dir: &std::path::Path, rings: usize) -> String {
    let out = surfmap()
        .arg("demo")
        .arg("-o")
        .arg(dir)
        .args(["--rings", &rings.to_string()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "demo failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Shape and element size of an `.npy` v1 file, checked against its length.
pub fn npy_shape(path: &std::path::Path) -> (Vec<usize>, usize) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..6], b"\x93NUMPY", "{}", path.display());
    assert_eq!(bytes[6], 1, "version 1");
    let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    assert_eq!((10 + hlen) % 64, 0, "header padded to 64 bytes");
    let header = std::str::from_utf8(&bytes[10..10 + hlen]).unwrap();
    assert!(header.contains("'fortran_order': False"), "{header}");
    let descr = header
        .split("'descr': '")
        .nth(1)
        .unwrap()
        .split('\'')
        .next()
        .unwrap();
    let elem: usize = descr[2..].parse().unwrap();
    let dims = header
        .split("'shape': (")
        .nth(1)
        .unwrap()
        .split(')')
        .next()
        .unwrap();
    let shape: Vec<usize> = dims
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap())
        .collect();
    assert_eq!(
        bytes.len() - 10 - hlen,
        shape.iter().product::<usize>() * elem,
        "{}: data length vs shape {shape:?}",
        path.display()
    );
    (shape, elem)
}

/// Shape and data of a little-endian float64 `.npy` v1 file (C order).
pub fn read_npy_f64(path: &std::path::Path) -> (Vec<usize>, Vec<f64>) {
    let (shape, elem) = npy_shape(path);
    assert_eq!(elem, 8, "{}: float64 expected", path.display());
    let bytes = std::fs::read(path).unwrap();
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let data = bytes[10 + header_len..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    (shape, data)
}
