//! Median wall-clock time of N reads of each mesh file given on the command line.
//!
//! `cargo run --release --example read_bench -- [-n N] FILE...`

use std::path::Path;
use std::time::Instant;

use surfmap::mesh::io::read_mesh;

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut runs = 11;
    if let Some(i) = args.iter().position(|a| a == "-n") {
        runs = args.get(i + 1).and_then(|n| n.parse().ok()).unwrap_or(runs);
        args.drain(i..(i + 2).min(args.len()));
    }
    if args.is_empty() {
        eprintln!("usage: read_bench [-n N] FILE...");
        std::process::exit(2);
    }
    for file in &args {
        let mut times = Vec::with_capacity(runs);
        let mut summary = String::new();
        for _ in 0..runs {
            let start = Instant::now();
            match read_mesh(Path::new(file)) {
                Ok(m) => {
                    times.push(start.elapsed().as_secs_f64());
                    summary = format!(
                        "V={} F={} triangles={} uvs={}",
                        m.mesh.num_vertices(),
                        m.stored_faces,
                        m.mesh.num_triangles(),
                        m.mesh.uvs.is_some()
                    );
                }
                Err(e) => {
                    eprintln!("{e}");
                    std::process::exit(1);
                }
            }
        }
        times.sort_by(f64::total_cmp);
        println!(
            "{file}: median {:.1} ms (min {:.1}, max {:.1}, {runs} reads) {summary}",
            1e3 * times[runs / 2],
            1e3 * times[0],
            1e3 * times[runs - 1]
        );
    }
}
