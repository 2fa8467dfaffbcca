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

/// A damaged input made here: its file, the defect kind `inspect` must list (`None`: the
/// file cannot be read at all) and the words both `inspect` and `flatten` must say.
pub struct Damaged {
    pub name: &'static str,
    pub path: PathBuf,
    pub kind: Option<&'static str>,
    pub words: &'static str,
}

/// A 4×4 grid disc (25 vertices, 32 faces) as OBJ text, with `edit` applied to its
/// vertex coordinates and face list first.
fn grid_obj(edit: impl FnOnce(&mut Vec<[f64; 3]>, &mut Vec<[u32; 3]>)) -> String {
    let n = 4;
    let mut v: Vec<[f64; 3]> = (0..=n)
        .flat_map(|j| {
            (0..=n).map(move |i| [i as f64 / 4.0, j as f64 / 4.0, 0.1 * ((i * j) % 3) as f64])
        })
        .collect();
    let mut f = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            f.push([a, a + 1, a + n + 2]);
            f.push([a, a + n + 2, a + n + 1]);
        }
    }
    edit(&mut v, &mut f);
    let mut text = String::new();
    for p in &v {
        text += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for t in &f {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    text
}

/// The damaged inputs of issue 50, written into `dir`: a binary file named `.obj`, a
/// NaN coordinate on a face, coordinates of 1e300 (finite, but every area overflows),
/// and a face given twice.
pub fn damaged_inputs(dir: &std::path::Path) -> Vec<Damaged> {
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    };
    let binary: Vec<u8> = (0..=255u8).cycle().take(4096).collect();
    vec![
        Damaged {
            name: "binary",
            path: write("binary.obj", &binary),
            kind: None,
            words: "byte 0x00 is not text, but a .obj file is text",
        },
        Damaged {
            name: "nan",
            path: write("nan.obj", grid_obj(|v, _| v[7][0] = f64::NAN).as_bytes()),
            kind: Some("non_finite_coordinates"),
            words: "1 vertex has NaN or infinite coordinates (first: 7) and is used by faces",
        },
        Damaged {
            name: "huge",
            path: write(
                "huge.obj",
                grid_obj(|v, _| v.iter_mut().flatten().for_each(|x| *x *= 1e300)).as_bytes(),
            ),
            kind: Some("overflowing_coordinates"),
            words: "32 faces have edge lengths or areas that overflow to infinity",
        },
        Damaged {
            name: "repeated face",
            path: write(
                "repeated.obj",
                grid_obj(|_, f| f.push([f[1][0], f[1][2], f[1][1]])).as_bytes(),
            ),
            kind: Some("duplicate_faces"),
            words: "1 face repeats an earlier face with the same three vertices (repeat and first: (32, 1))",
        },
    ]
}

/// `mesh` turned by `angle` about z and moved by `t` (a face moved in space).
pub fn moved(mesh: &surfmap::TriMesh, angle: f64, t: [f64; 3]) -> surfmap::TriMesh {
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

/// The extent of `mesh` along x (a face's width: the unit of the ICT errors).
pub fn width_x(mesh: &surfmap::TriMesh) -> f64 {
    let xs = mesh.positions.iter().map(|p| p[0]);
    xs.clone().fold(f64::MIN, f64::max) - xs.fold(f64::MAX, f64::min)
}

/// The distance of every point of `a` from the point of `b` with its index.
pub fn distances(a: &[[f64; 3]], b: &[[f64; 3]]) -> Vec<f64> {
    a.iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>().sqrt())
        .collect()
}
