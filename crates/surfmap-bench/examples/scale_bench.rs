//! Scaling benchmark: a real disc mesh subdivided in code (midpoint 1 → 4, `k` times;
//! the result is synthetic) and flattened with the balanced preset. Prints size,
//! iterations, time by phase and peak resident memory, with the multilevel start and
//! without it (same run; the multilevel run first, so the peak memory line of the
//! first run is its own).
//!
//! `cargo run --release -p surfmap-bench --example scale_bench -- MESH LEVELS [multi|single|both] [COARSE_VERTICES|- [SWEEPS [POLISH_STEPS]]]`
//! e.g. `../shared/data/faces/face_bff.obj 3` (34k → 2.2M faces).

use surfmap::mesh::io::read_mesh;
use surfmap::mesh::subdivide::subdivide_midpoint;
use surfmap::param::count_flipped;
use surfmap::{CoarseLevel, FlattenOptions, Multilevel, Start, flatten};

fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .map(|l| l.to_string())
        })
        .and_then(|l| {
            l.split_whitespace()
                .nth(1)
                .and_then(|k| k.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kib| kib / 1024.0)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args.first().expect("MESH LEVELS");
    let levels: usize = args.get(1).map_or(3, |s| s.parse().expect("LEVELS"));
    let mut mesh = read_mesh(std::path::Path::new(path))
        .expect("readable")
        .mesh;
    for _ in 0..levels {
        mesh = subdivide_midpoint(&mesh);
    }
    println!(
        "{path} subdivided {levels}×: {} vertices, {} faces",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    let which = args.get(2).map_or("both", String::as_str);
    // Optional 4th argument: the coarse level's vertices (default: CoarseLevel's own).
    let mut coarse = match args.get(3).map(String::as_str) {
        Some(v) if v != "-" => CoarseLevel::with_vertices(v.parse().expect("COARSE_VERTICES")),
        _ => CoarseLevel::default(),
    };
    // Optional 5th and 6th: the relaxation sweeps and local steps per re-inserted vertex.
    if let Some(s) = args.get(4) {
        coarse.sweeps = s.parse().expect("SWEEPS");
    }
    if let Some(s) = args.get(5) {
        coarse.polish_steps = s.parse().expect("POLISH_STEPS");
    }
    let on = Multilevel::Always(coarse);
    let runs: Vec<(&str, Multilevel)> = match which {
        "single" => vec![("single-level", Multilevel::Never)],
        "multi" => vec![("multilevel", on)],
        _ => vec![("multilevel", on), ("single-level", Multilevel::Never)],
    };
    let mut totals = Vec::new();
    for (name, multilevel) in runs {
        let t = std::time::Instant::now();
        let options = FlattenOptions::default().with_start(Start::Auto { multilevel });
        let r = flatten(&mesh, &options).expect("flattened");
        let total = t.elapsed().as_secs_f64();
        totals.push(total);
        println!(
            "{name}, balanced: start {}, {} iterations, converged {}, energy {:.6}, flipped {}, total {:.2} s (start map {:.2} s), peak RSS so far {:.0} MiB",
            r.start_description(),
            r.iterations,
            r.converged,
            r.energy,
            count_flipped(&r.uvs, &mesh.triangles),
            total,
            r.time_start,
            peak_rss_mib()
        );
        println!("  {:?}", r.newton_timings);
        if let Some(m) = &r.multilevel {
            println!("  {m:?}");
        }
        for l in &r.log {
            println!(
                "  {:>3} {:.8} {:.3e} {:.3} {:.2}",
                l.iteration, l.energy, l.newton_decrement, l.step, l.time
            );
        }
    }
    if totals.len() == 2 {
        println!(
            "single-level / multilevel time: {:.2}×",
            totals[1] / totals[0]
        );
    }
}
