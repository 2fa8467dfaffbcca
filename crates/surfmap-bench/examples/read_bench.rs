//! Median wall-clock time of N reads of each mesh file given on the command line, and
//! of reading plus building its topology (`Topology::new`) — the target is
//! igea.ply (269k faces) read and topology built in ≤ 0.3 s.
//!
//! `cargo run --release -p surfmap-bench --example read_bench -- [-n N] FILE...`

use std::path::Path;
use std::time::Instant;

use surfmap::Topology;
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
        let mut with_topology = Vec::with_capacity(runs);
        let mut summary = String::new();
        for _ in 0..runs {
            let start = Instant::now();
            match read_mesh(Path::new(file)) {
                Ok(m) => {
                    times.push(start.elapsed().as_secs_f64());
                    let topo = Topology::new(&m.mesh);
                    with_topology.push(start.elapsed().as_secs_f64());
                    std::hint::black_box(&topo);
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
        with_topology.sort_by(f64::total_cmp);
        println!(
            "{file}: read median {:.1} ms (min {:.1}, max {:.1}); read + topology median {:.1} ms (min {:.1}); {runs} runs; {summary}",
            1e3 * times[runs / 2],
            1e3 * times[0],
            1e3 * times[runs - 1],
            1e3 * with_topology[runs / 2],
            1e3 * with_topology[0],
        );
    }
}
