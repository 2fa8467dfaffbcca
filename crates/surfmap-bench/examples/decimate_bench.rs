//! Decimation benchmark: `decimate_bench MESH LEVELS TARGET`.
//!
//! Reads MESH, subdivides it LEVELS times (midpoint 1 → 4), decimates it to TARGET
//! vertices and prints the times, the coarse V/F, the minimum face quality before and
//! after, the largest turn of a surviving face's normal (coarse vs original), and a
//! distance bound: for every removed vertex with a surviving original face, its
//! distance to that (coarse) face; this over-estimates its distance to the coarse
//! surface, so the max is an upper bound over those vertices.
use std::time::Instant;
use surfmap::mesh::decimate::{DecimateOptions, decimate_with};
use surfmap::mesh::io::read_mesh;
use surfmap::mesh::subdivide::subdivide_midpoint;
use surfmap::{Disc, Topology};

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn quality(p: [[f64; 3]; 3]) -> f64 {
    let n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
    let l2: f64 = (0..3)
        .map(|k| {
            let e = sub(p[(k + 1) % 3], p[k]);
            dot(e, e)
        })
        .sum();
    2.0 * 3f64.sqrt() * dot(n, n).sqrt() / l2
}

/// Distance from `x` to triangle `t` (closest point by region, Ericson §5.1.5).
fn point_triangle_distance(x: [f64; 3], t: [[f64; 3]; 3]) -> f64 {
    let [a, b, c] = t;
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(x, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    let closest = if d1 <= 0.0 && d2 <= 0.0 {
        a
    } else {
        let bp = sub(x, b);
        let (d3, d4) = (dot(ab, bp), dot(ac, bp));
        let cp = sub(x, c);
        let (d5, d6) = (dot(ab, cp), dot(ac, cp));
        let (vc, vb, va) = (d1 * d4 - d3 * d2, d5 * d2 - d1 * d6, d3 * d6 - d5 * d4);
        let lerp = |p: [f64; 3], q: [f64; 3], s: f64| -> [f64; 3] {
            [
                p[0] + s * (q[0] - p[0]),
                p[1] + s * (q[1] - p[1]),
                p[2] + s * (q[2] - p[2]),
            ]
        };
        if d3 >= 0.0 && d4 <= d3 {
            b
        } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            lerp(a, b, d1 / (d1 - d3))
        } else if d6 >= 0.0 && d5 <= d6 {
            c
        } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            lerp(a, c, d2 / (d2 - d6))
        } else if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            lerp(b, c, (d4 - d3) / ((d4 - d3) + (d5 - d6)))
        } else {
            let denom = 1.0 / (va + vb + vc);
            let (v, w) = (vb * denom, vc * denom);
            [
                a[0] + ab[0] * v + ac[0] * w,
                a[1] + ab[1] * v + ac[1] * w,
                a[2] + ab[2] * v + ac[2] * w,
            ]
        }
    };
    let d = sub(x, closest);
    dot(d, d).sqrt()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 3 {
        eprintln!("usage: decimate_bench MESH LEVELS TARGET");
        std::process::exit(2);
    }
    let levels: usize = args[1].parse().expect("LEVELS: a number");
    let target: usize = args[2].parse().expect("TARGET: a number");
    let mut mesh = read_mesh(std::path::Path::new(&args[0]))
        .expect("readable mesh")
        .mesh;
    for _ in 0..levels {
        mesh = subdivide_midpoint(&mesh);
    }
    println!(
        "fine: {} vertices, {} faces",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    let t = Instant::now();
    let disc = match Disc::new(&mesh) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let t_topology = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let options = DecimateOptions {
        target_vertices: target,
        ..Default::default()
    };
    let dec = match decimate_with(&mesh.positions, &disc, &options) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let t_decimate = t.elapsed().as_secs_f64();
    let (coarse, _) = dec.coarse_mesh(&mesh);
    println!(
        "Disc::new {t_topology:.3} s, decimate_with {t_decimate:.3} s ({} collapses, {} changed-face records)",
        dec.collapses.len(),
        dec.changed_faces.len()
    );
    println!(
        "coarse: {} vertices, {} faces, target reached: {}, disc: {}",
        coarse.positions.len(),
        coarse.triangles.len(),
        dec.reached_target,
        Topology::new(&coarse).is_disc()
    );
    let min_quality = |m: &surfmap::TriMesh| {
        (0..m.triangles.len())
            .map(|t| quality(m.triangle_positions(t)))
            .fold(f64::INFINITY, f64::min)
    };
    println!(
        "min face quality: fine {:.4}, coarse {:.4}",
        min_quality(&mesh),
        min_quality(&coarse)
    );
    let normal = |p: [[f64; 3]; 3]| cross(sub(p[1], p[0]), sub(p[2], p[0]));
    let tri = |f: [u32; 3]| f.map(|v| mesh.positions[v as usize]);
    let mut max_turn: f64 = 0.0;
    for (f, coarse_face) in dec.faces.iter().enumerate() {
        if let Some(cf) = coarse_face {
            let (n0, n1) = (normal(tri(mesh.triangles[f])), normal(tri(*cf)));
            let c = dot(n0, n1) / (dot(n0, n0) * dot(n1, n1)).sqrt();
            max_turn = max_turn.max(c.clamp(-1.0, 1.0).acos().to_degrees());
        }
    }
    println!("largest normal turn of a surviving face (coarse vs original): {max_turn:.1}°");
    // Distance bound for removed vertices with a surviving original face.
    let (lo, hi) = mesh.bounding_box().unwrap();
    let diagonal = dot(sub(hi, lo), sub(hi, lo)).sqrt();
    let mut first_face = vec![u32::MAX; mesh.positions.len()];
    for (f, t) in mesh.triangles.iter().enumerate() {
        for &v in t {
            if dec.faces[f].is_some() && first_face[v as usize] == u32::MAX {
                first_face[v as usize] = f as u32;
            }
        }
    }
    let (mut max_d, mut sum_d, mut measured, mut unmeasured) = (0f64, 0f64, 0usize, 0usize);
    for c in &dec.collapses {
        let f = first_face[c.removed as usize];
        if f == u32::MAX {
            unmeasured += 1;
            continue;
        }
        let d = point_triangle_distance(
            mesh.positions[c.removed as usize],
            tri(dec.faces[f as usize].unwrap()),
        );
        max_d = max_d.max(d);
        sum_d += d;
        measured += 1;
    }
    println!(
        "removed vertex → its surviving original face (coarse): max {:.3e}, mean {:.3e} of the bbox diagonal ({} vertices; {} without a surviving face)",
        max_d / diagonal,
        sum_d / measured.max(1) as f64 / diagonal,
        measured,
        unmeasured
    );
}
