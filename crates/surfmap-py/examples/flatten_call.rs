//! The Rust side of the Python call-overhead benchmark (`examples/python_bench.py
//! overhead`): what `surfmap.flatten(V, F)` computes, called from Rust on a mesh already
//! in memory: `surfmap::flatten` with the balanced preset, then the report
//! (`FlattenReport::measure`, the dictionary Python returns). Prints one wall time per
//! call, in seconds, on a line starting with `times:`; a second line `flatten:` has the
//! time of `flatten` alone in each call.
//!
//! `cargo run --release -p surfmap-py --example flatten_call -- MESH [--repeat N]`

use std::time::Instant;

use surfmap::{FlattenOptions, FlattenReport, read_mesh};

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut repeat = 21;
    if let Some(i) = args.iter().position(|a| a == "--repeat") {
        repeat = args
            .get(i + 1)
            .and_then(|n| n.parse().ok())
            .expect("--repeat N");
        args.drain(i..i + 2);
    }
    let [path] = args.as_slice() else {
        eprintln!("usage: flatten_call MESH [--repeat N]");
        std::process::exit(2);
    };
    let mesh = read_mesh(std::path::Path::new(path))
        .unwrap_or_else(|e| panic!("cannot read {path}: {e}"))
        .mesh;
    let options = FlattenOptions::default();
    let mut total = Vec::with_capacity(repeat);
    let mut solve = Vec::with_capacity(repeat);
    for _ in 0..repeat {
        let clock = Instant::now();
        let r = surfmap::flatten(&mesh, &options).expect("a disc mesh");
        let solved = clock.elapsed().as_secs_f64();
        let report = FlattenReport::measure(None, &mesh, &r, |d| d.message()).expect("measured");
        std::hint::black_box((&r.uvs, &report));
        total.push(clock.elapsed().as_secs_f64());
        solve.push(solved);
    }
    let line = |t: &[f64]| {
        t.iter()
            .map(|s| format!("{s:.9}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    println!("times: {}", line(&total));
    println!("flatten: {}", line(&solve));
}
