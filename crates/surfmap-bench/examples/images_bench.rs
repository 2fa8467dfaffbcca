//! Benchmark of the geometry images of `face_igl.obj` (51.7k faces): the full image set
//! plus the pyramid at 257² and 1025², median of several runs, per-stage times.
//!
//! `cargo run --release -p surfmap-bench --example images_bench [-- path/to/mesh.obj [sheet.png]]`
//!
//! The flattening is `param::flatten` with the balanced preset (thesis §3.2.1); its time is
//! reported separately and excluded from the image timings. `RUNS` sets the number of runs,
//! `SIZES` the grid sizes (comma-separated).

use std::path::PathBuf;
use std::time::Instant;

use surfmap::raster::output::position_picture;
use surfmap::raster::picture::{distance_picture, diverging_picture, metric_picture};
use surfmap::raster::{
    FeatureCurve, FeatureFile, FeatureSource, GeometryImages, GeometryImagesOptions,
};
use surfmap::render::{contact_sheet, save_png};
use surfmap::{FlattenOptions, flatten, read_mesh};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = match args.get(1).filter(|s| !s.is_empty()) {
        Some(p) => PathBuf::from(p),
        None => match surfmap::testing::shared_file("faces/face_igl.obj") {
            Some(p) => p,
            None => return,
        },
    };
    if !path.is_file() {
        println!("note: {} not found; nothing to benchmark", path.display());
        return;
    }
    let mesh = read_mesh(&path).expect("read mesh").mesh;
    println!(
        "mesh {}: {} vertices, {} faces",
        path.display(),
        mesh.num_vertices(),
        mesh.num_triangles()
    );

    let flatten_runs = 3;
    let mut flatten_times = vec![];
    let mut flat = None;
    for _ in 0..flatten_runs {
        let t = Instant::now();
        flat = Some(flatten(&mesh, &FlattenOptions::default()).expect("flatten"));
        flatten_times.push(t.elapsed().as_secs_f64());
    }
    flatten_times.sort_by(f64::total_cmp);
    let flat = flat.unwrap();
    println!(
        "balanced flattening: median {:.3} s over {flatten_runs} runs ({} Newton iterations, converged {}; excluded below)",
        flatten_times[flatten_runs / 2],
        flat.iterations,
        flat.converged
    );
    let uvs = flat.uvs;

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
    // SIZES=257,1025 (default) picks the grid sizes.
    let sizes: Vec<usize> = std::env::var("SIZES")
        .unwrap_or_else(|_| "257,1025".into())
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    for size in sizes {
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
                let lvl = pyr.mean_curvature.level(5);
                let tiles = vec![
                    (
                        "H (RED +, BLUE -)".to_string(),
                        diverging_picture(n, img.mean_curvature.as_slice()),
                    ),
                    (
                        "H EXTENDED".to_string(),
                        diverging_picture(n, img.mean_curvature_extended.as_slice()),
                    ),
                    (
                        format!("H, σ=1/{} ({}²)", 1 << lvl.level(), lvl.size()),
                        diverging_picture(lvl.size(), lvl.as_slice()),
                    ),
                    (
                        "POSITION XYZ=RGB".to_string(),
                        position_picture(&img.position),
                    ),
                    (
                        "METRIC G (RGB)".to_string(),
                        metric_picture(n, img.metric.as_slice()),
                    ),
                    (
                        "G EXTENDED (RGB)".to_string(),
                        metric_picture(n, img.metric_extended.as_slice()),
                    ),
                    (
                        "BOUNDARY DISTANCE".to_string(),
                        distance_picture(n, img.boundary_distance.as_slice(), Some(&outside)),
                    ),
                    (
                        "FEATURE DISTANCE".to_string(),
                        distance_picture(
                            n,
                            img.feature_distance.as_ref().unwrap().as_slice(),
                            Some(&outside),
                        ),
                    ),
                ];
                save_png(std::path::Path::new(out), &contact_sheet(&tiles, 4, 320))
                    .expect("write sheet");
                println!("wrote {out}");
            }
        }
    }
}
