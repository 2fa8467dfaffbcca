//! Benchmark of the geometry images of `face_igl.obj` (51.7k faces): the full image set
//! plus the pyramid at 257² and 1025², median of several runs, per-stage times.
//!
//! `cargo run --release --example images_bench [-- path/to/mesh.obj [sheet.png]]`
//!
//! Until `param::flatten` exists, the flattening here is a uniform-weight Tutte embedding
//! onto a circle (flip-free, NOT the balanced preset of §3.2.1); its time is reported
//! separately and excluded from the image timings.

use std::path::PathBuf;
use std::time::Instant;

use surfmap::TriMesh;
use surfmap::raster::boundary::boundary_edges;
use surfmap::raster::picture::{
    contact_sheet, distance_picture, diverging_picture, metric_picture,
};
use surfmap::raster::{
    FeatureCurve, FeatureFile, FeatureSource, GeometryImages, GeometryImagesOptions,
};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    // The shared data folder sits three or four levels above the crate (main checkout or worktree).
    let path = args
        .get(1)
        .filter(|s| !s.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            ["/../../../shared/data", "/../../../../shared/data"]
                .iter()
                .map(|d| {
                    PathBuf::from(format!(
                        "{}{d}/faces/face_igl.obj",
                        env!("CARGO_MANIFEST_DIR")
                    ))
                })
                .find(|p| p.exists())
                .unwrap_or_default()
        });
    if !path.is_file() {
        println!("note: {} not found; nothing to benchmark", path.display());
        return;
    }
    let (models, _) = tobj::load_obj(&path, &tobj::GPU_LOAD_OPTIONS).expect("read OBJ");
    let m = &models[0].mesh;
    let positions: Vec<[f64; 3]> = m
        .positions
        .chunks(3)
        .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
        .collect();
    let triangles: Vec<[u32; 3]> = m.indices.chunks(3).map(|t| [t[0], t[1], t[2]]).collect();
    let mesh = TriMesh::new(positions, triangles);
    println!(
        "mesh {}: {} vertices, {} faces",
        path.display(),
        mesh.num_vertices(),
        mesh.num_triangles()
    );

    let t = Instant::now();
    let uvs = tutte(&mesh);
    println!(
        "placeholder Tutte flattening: {:.3} s (excluded below)",
        t.elapsed().as_secs_f64()
    );

    // Two point-like features, to include the Eikonal solves in the timing.
    let features = FeatureFile {
        features: vec![
            FeatureCurve {
                name: "a".into(),
                vertices: vec![0, 1],
                closed: false,
            },
            FeatureCurve {
                name: "b".into(),
                vertices: vec![(mesh.num_vertices() / 2) as u32],
                closed: false,
            },
        ],
    };
    let runs: usize = std::env::var("RUNS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    for size in [257usize, 1025] {
        let options = GeometryImagesOptions {
            size,
            ..Default::default()
        };
        let mut times = vec![];
        let mut last = None;
        for _ in 0..runs {
            let t = Instant::now();
            let img = GeometryImages::compute(
                &mesh,
                &uvs,
                FeatureSource::Curves(&features),
                None,
                &options,
            )
            .expect("images");
            times.push(t.elapsed().as_secs_f64());
            last = Some(img);
        }
        times.sort_by(f64::total_cmp);
        println!(
            "size {size}: median {:.3} s (min {:.3}, max {:.3}) over {runs} runs, {} threads",
            times[runs / 2],
            times[0],
            times[runs - 1],
            rayon::current_num_threads()
        );
        if let Some(img) = &last {
            let stages: Vec<String> = img
                .timings
                .iter()
                .map(|(s, t)| format!("{s} {t:.3}"))
                .collect();
            println!("  last run stages (s): {}", stages.join(", "));
        }
        if size == 257
            && let (Some(img), Some(out)) = (last, args.get(2))
        {
            {
                let n = img.size;
                let outside: Vec<bool> = (0..n * n).map(|k| !img.raster.is_inside(k)).collect();
                let pyr = img.pyramid.as_ref().unwrap();
                let lvl = &pyr.levels[5];
                let tiles = vec![
                    (
                        "mean curvature h".to_string(),
                        diverging_picture(n, &img.mean_curvature),
                    ),
                    (
                        "h extended".to_string(),
                        diverging_picture(n, &img.mean_curvature_extended),
                    ),
                    ("metric g (rgb)".to_string(), metric_picture(n, &img.metric)),
                    (
                        "boundary distance".to_string(),
                        distance_picture(n, &img.boundary_distance, Some(&outside)),
                    ),
                    (
                        "feature distance".to_string(),
                        distance_picture(n, img.feature_distance.as_ref().unwrap(), Some(&outside)),
                    ),
                    (
                        format!("h level {} s=1/{}", lvl.level, 1 << lvl.level),
                        diverging_picture(lvl.size, &lvl.images[0]),
                    ),
                ];
                contact_sheet(&tiles, 3, 320)
                    .save_png(std::path::Path::new(out))
                    .expect("write sheet");
                println!("wrote {out}");
            }
        }
    }
}

/// Uniform-weight Tutte embedding of a disc onto the unit circle (boundary spaced by
/// arc length), solved by conjugate gradients.
fn tutte(mesh: &TriMesh) -> Vec<[f64; 2]> {
    let nv = mesh.num_vertices();
    let edges = boundary_edges(&mesh.triangles);
    let mut next = vec![u32::MAX; nv];
    for e in &edges {
        next[e[0] as usize] = e[1];
    }
    let start = edges[0][0];
    let mut ring = vec![start];
    while let Some(&v) = ring.last() {
        let w = next[v as usize];
        if w == start || w == u32::MAX {
            break;
        }
        ring.push(w);
    }
    let len = |a: u32, b: u32| {
        let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    };
    let total: f64 = (0..ring.len())
        .map(|i| len(ring[i], ring[(i + 1) % ring.len()]))
        .sum();
    let mut uv = vec![[0.0; 2]; nv];
    let mut fixed = vec![false; nv];
    let mut acc = 0.0;
    for i in 0..ring.len() {
        let a = std::f64::consts::TAU * acc / total;
        uv[ring[i] as usize] = [a.cos(), a.sin()];
        fixed[ring[i] as usize] = true;
        acc += len(ring[i], ring[(i + 1) % ring.len()]);
    }
    let mut nbrs: Vec<Vec<u32>> = vec![vec![]; nv];
    for t in &mesh.triangles {
        for k in 0..3 {
            nbrs[t[k] as usize].push(t[(k + 1) % 3]);
            nbrs[t[(k + 1) % 3] as usize].push(t[k]);
        }
    }
    for l in &mut nbrs {
        l.sort_unstable();
        l.dedup();
    }
    // CG on the free vertices: deg·u_i − Σ_free u_j = Σ_fixed u_j.
    for d in 0..2 {
        let apply = |x: &[f64], y: &mut [f64]| {
            for i in 0..nv {
                y[i] = if fixed[i] {
                    0.0
                } else {
                    nbrs[i].len() as f64 * x[i]
                        - nbrs[i]
                            .iter()
                            .filter(|&&j| !fixed[j as usize])
                            .map(|&j| x[j as usize])
                            .sum::<f64>()
                };
            }
        };
        let b: Vec<f64> = (0..nv)
            .map(|i| {
                if fixed[i] {
                    0.0
                } else {
                    nbrs[i]
                        .iter()
                        .filter(|&&j| fixed[j as usize])
                        .map(|&j| uv[j as usize][d])
                        .sum()
                }
            })
            .collect();
        let mut x = vec![0.0; nv];
        let mut r = b.clone();
        let mut p = r.clone();
        let mut ap = vec![0.0; nv];
        let mut rr: f64 = r.iter().map(|v| v * v).sum();
        let b2 = rr;
        for _ in 0..20000 {
            apply(&p, &mut ap);
            let alpha = rr / p.iter().zip(&ap).map(|(a, b)| a * b).sum::<f64>();
            for i in 0..nv {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
            }
            let rr_new: f64 = r.iter().map(|v| v * v).sum();
            if rr_new < 1e-24 * b2 {
                break;
            }
            for i in 0..nv {
                p[i] = r[i] + rr_new / rr * p[i];
            }
            rr = rr_new;
        }
        for (i, p) in uv.iter_mut().enumerate() {
            if !fixed[i] {
                p[d] = x[i];
            }
        }
    }
    uv
}
