//! Matching with landmarks: a generated bumpy disc (or your own disc-like mesh) matched
//! onto a bent, stretched, turned and shifted copy of itself, guided by five landmarks;
//! the report's summary and confidence verdict printed, and the error measured against
//! the known truth (vertex `i` of the copy is where vertex `i` of the original went).
//!
//! `cargo run --release -p surfmap --example match_landmarks [-- MESH.obj|off|ply]`

use std::path::Path;
use std::time::Instant;

use surfmap::TriMesh;
use surfmap::matching::{Guidance, Landmarks, MatchOptions, match_meshes};

/// The centre of `mesh`'s bounding box and half its widest side.
fn centre_and_radius(mesh: &TriMesh) -> ([f64; 3], f64) {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &mesh.positions {
        lo = [0, 1, 2].map(|k| lo[k].min(p[k]));
        hi = [0, 1, 2].map(|k| hi[k].max(p[k]));
    }
    let radius = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max) / 2.0;
    ([0, 1, 2].map(|k| (lo[k] + hi[k]) / 2.0), radius)
}

/// The vertex of `mesh` nearest to the point `(x, y)` seen from above (landmarks are
/// vertex ids; in practice they come from a viewer or a landmark detector).
fn vertex_near(mesh: &TriMesh, x: f64, y: f64) -> u32 {
    let d = |p: &[f64; 3]| (p[0] - x).powi(2) + (p[1] - y).powi(2);
    (0..mesh.num_vertices())
        .min_by(|&i, &j| d(&mesh.positions[i]).total_cmp(&d(&mesh.positions[j])))
        .expect("a mesh with vertices") as u32
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // Surface A: a mesh file if one is given, else a bumpy disc of 30 rings built in code.
    let a = match std::env::args().nth(1) {
        Some(path) => surfmap::read_mesh(Path::new(&path))?.mesh,
        None => surfmap::mesh::generate::bumpy_disc(30, 0.5),
    };

    // Surface B: A bent and stretched (a smooth non-rigid change of shape), then turned
    // by 0.6 rad about the y axis and shifted; in units of A's size `r` about its centre
    // `o`, so that any mesh works. Same triangles, so the truth is known.
    let (o, r) = centre_and_radius(&a);
    let (s, c) = 0.6f64.sin_cos();
    let b = TriMesh::new(
        a.positions
            .iter()
            .map(|p| {
                let [x, y, z] = [0, 1, 2].map(|k| (p[k] - o[k]) / r);
                let (x, y, z) = (1.1 * x, y + 0.05 * x * x, z + 0.15 * (x * x - y * y));
                let q = [c * x + s * z + 3.0, y - 1.0, -s * x + c * z + 0.5];
                [0, 1, 2].map(|k| o[k] + r * q[k])
            })
            .collect(),
        a.triangles.clone(),
    );

    // Landmarks: pairs of vertex ids, A's in `a`, B's in `b`, named (as the JSON file
    // `surfmap match --landmarks` reads: {"names": [...], "A": [...], "B": [...]}).
    // Here the same ids on both sides, since B is a copy; for two different surfaces
    // pick each side's own vertex. Five or more also set where the solve starts (fewer
    // only guide it, the start coming from the surfaces aligned in space), and by
    // default each lands exactly on its partner (`options.pin_landmarks`).
    let spots = [
        ("left", -0.5, 0.0),
        ("right", 0.5, 0.0),
        ("top", 0.0, 0.5),
        ("bottom", 0.0, -0.5),
        ("centre", 0.0, 0.0),
    ];
    let mut landmarks = Landmarks {
        names: vec![],
        a: vec![],
        b: vec![],
    };
    for (name, x, y) in spots {
        let v = vertex_near(&a, o[0] + r * x, o[1] + r * y);
        landmarks.names.push(name.to_owned());
        landmarks.a.push(v);
        landmarks.b.push(v);
    }
    let guidance = Guidance {
        landmarks: Some(landmarks),
        ..Guidance::default()
    };

    // A 129 × 129 grid for speed (the default, 257, is finer and slower). Other options
    // keep their defaults: fill holes, align, recover from a doubtful start, …
    // (`MatchOptions` has private fields: start from the default and set what you need.)
    let mut options = MatchOptions::default();
    options.size = 129;
    let clock = Instant::now();
    let matched = match_meshes(&a, &b, &guidance, &options)?;
    let seconds = clock.elapsed().as_secs_f64();
    let report = &matched.report;

    // The summary `surfmap match` prints (its last line: `report.confidence.line()`), and
    // the verdict: `Ok`, `Doubtful` or `Failed`, and when not `Ok`, why. With
    // `options.strict` a verdict other than `Ok` comes back as `MatchError::NotTrusted`.
    println!("{}", report.summary());
    let confidence = &report.confidence;
    println!("verdict: {:?} ({seconds:.2} s)", confidence.verdict);
    for reason in &confidence.reasons {
        println!("  because {reason}");
    }

    // The correspondence: one entry per vertex of A, a point of B (a triangle of B and
    // barycentric coordinates) or None. Its distance to the truth, B's vertex i:
    let errors: Vec<f64> = matched
        .correspondence
        .iter()
        .enumerate()
        .filter_map(|(i, point)| {
            let q = (*point)?.position(&b.positions, &b.triangles);
            let t = b.positions[i];
            Some((0..3).map(|k| (q[k] - t[k]).powi(2)).sum::<f64>().sqrt())
        })
        .collect();
    let mean = errors.iter().sum::<f64>() / errors.len().max(1) as f64;
    let max = errors.iter().copied().fold(0.0, f64::max);
    println!(
        "{} of {} vertices matched; error to the truth: mean {:.4} ({:.2} % of A's width), max {:.4} ({:.2} %)",
        errors.len(),
        a.num_vertices(),
        mean,
        50.0 * mean / r,
        max,
        50.0 * max / r
    );
    Ok(())
}
