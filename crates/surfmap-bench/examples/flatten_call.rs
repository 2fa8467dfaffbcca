//! The Rust side of the Python call-overhead benchmark (`examples/python_bench.py
//! overhead`): what `surfmap.flatten(V, F)` computes, called from Rust on a mesh already
//! in memory: `surfmap::flatten` with the balanced preset, then the report
//! (`FlattenReport::measure`, the dictionary Python returns). Prints one wall time per
//! call, in seconds, on a line starting with `times:`; a second line `flatten:` has the
//! time of `flatten` alone in each call, and `cpu:` the CPU time of each call (all
//! threads of the process, the clock of Python's `time.process_time`), which other
//! jobs on a shared machine do not inflate as much as the wall time.
//!
//! `cargo run --release -p surfmap-bench --example flatten_call -- MESH [--repeat N]`

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
    let mut cpu = Vec::with_capacity(repeat);
    for _ in 0..repeat {
        let cpu_start = cpu_seconds();
        let clock = Instant::now();
        let r = surfmap::flatten(&mesh, &options).expect("a disc mesh");
        let solved = clock.elapsed().as_secs_f64();
        let report = FlattenReport::measure(None, &mesh, &r, |d| d.message()).expect("measured");
        std::hint::black_box((&r.uvs, &report));
        total.push(clock.elapsed().as_secs_f64());
        cpu.push(cpu_seconds() - cpu_start);
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
    println!("cpu: {}", line(&cpu));
}

/// CPU seconds used so far by all threads of this process: the clock Python's
/// `time.process_time` reads.
fn cpu_seconds() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; the clock id is a constant Linux and
    // every POSIX system with threads provide.
    let status = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    assert_eq!(status, 0, "clock_gettime(CLOCK_PROCESS_CPUTIME_ID) failed");
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}
