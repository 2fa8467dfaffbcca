//! Flattening benchmark over every disc mesh in `../shared/data` (one boundary loop,
//! genus 0): start map used, iterations, median wall time, final energy and flipped
//! triangles, for the conformal and balanced presets (and symmetric Dirichlet).
//!
//! `cargo run --release -p surfmap-bench --example flatten_bench [-- --repeat 3] [-- MESH...]`

use std::path::PathBuf;
use std::time::Instant;
use surfmap::param::count_flipped;
use surfmap::{Alpha, Energy, FlattenOptions, flatten, read_mesh};

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut repeat = 3;
    if let Some(i) = args.iter().position(|a| a == "--repeat") {
        repeat = args[i + 1].parse().expect("--repeat N");
        args.drain(i..i + 2);
    }
    let meshes: Vec<PathBuf> = if args.is_empty() {
        let Some(data) = surfmap::testing::shared_data() else {
            return;
        };
        let m: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(data.join("manifest.json")).expect("readable manifest"),
        )
        .unwrap();
        m["files"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|f| f["boundary_loops"] == 1 && f["genus"] == 0)
            .map(|f| data.join(f["file"].as_str().unwrap()))
            .collect()
    } else {
        args.iter().map(PathBuf::from).collect()
    };
    println!(
        "{:<24} {:>7} {:>7} {:<10} {:<28} {:>5} {:>9} {:>9} {:>12} {:>5}",
        "mesh", "V", "F", "energy", "start", "iters", "median_s", "min_s", "E/area", "flips"
    );
    for path in meshes {
        let file = read_mesh(&path).expect("readable");
        let mesh = file.mesh;
        for (label, energy) in [
            ("conformal", Energy::litke(Alpha::conformal())),
            ("balanced", Energy::litke(Alpha::balanced())),
            ("sd", Energy::SymmetricDirichlet),
        ] {
            let opts = FlattenOptions::new(energy);
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..repeat {
                let t = Instant::now();
                let r = flatten(&mesh, &opts);
                times.push(t.elapsed().as_secs_f64());
                last = Some(r);
            }
            times.sort_by(f64::total_cmp);
            let name = path.file_name().unwrap().to_string_lossy();
            match last.unwrap() {
                Ok(r) => println!(
                    "{:<24} {:>7} {:>7} {:<10} {:<28} {:>5} {:>9.3} {:>9.3} {:>12.6} {:>5}{}",
                    name,
                    mesh.positions.len(),
                    mesh.triangles.len(),
                    label,
                    r.start_description(),
                    r.iterations,
                    times[times.len() / 2],
                    times[0],
                    r.energy,
                    count_flipped(&r.uvs, &mesh.triangles),
                    if r.converged { "" } else { "  NOT CONVERGED" }
                ),
                Err(e) => println!("{name:<24} {label:<10} error: {e}"),
            }
        }
    }
}
