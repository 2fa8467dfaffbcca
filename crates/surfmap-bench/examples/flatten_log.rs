//! Prints the per-iteration Newton log of one flattening (thesis fig. 4.1 data).
//! `cargo run --release -p surfmap-bench --example flatten_log -- MESH [conformal|balanced|sd]`
use surfmap::{Alpha, Energy, FlattenOptions, flatten};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mesh = surfmap::mesh::io::read_mesh(std::path::Path::new(&args[0]))
        .expect("readable")
        .mesh;
    let energy = match args.get(1).map(String::as_str) {
        Some("conformal") => Energy::litke(Alpha::conformal()),
        Some("sd") => Energy::SymmetricDirichlet,
        _ => Energy::litke(Alpha::balanced()),
    };
    let r = flatten(&mesh, &FlattenOptions::new(energy)).expect("flattened");
    println!(
        "start {:?}, {} warm-start steps, {} iterations, stop {:?}, total {:.3} s (start map + warm start {:.3} s)",
        r.start, r.warm_start_iterations, r.iterations, r.stop_reason, r.time_total, r.time_start
    );
    println!("{:?}", r.newton_timings);
    println!(
        "{:>4} {:>14} {:>10} {:>10} {:>8} {:>10} {:>7}",
        "it", "energy", "|grad|", "decrement", "step", "flipfree", "time"
    );
    for l in &r.log {
        println!(
            "{:>4} {:>14.8} {:>10.3e} {:>10.3e} {:>8.4} {:>10.3e} {:>7.3}",
            l.iteration,
            l.energy,
            l.gradient_norm,
            l.newton_decrement,
            l.step,
            l.flip_free_step,
            l.time
        );
    }
}
