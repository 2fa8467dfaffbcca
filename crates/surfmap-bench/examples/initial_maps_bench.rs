//! Timing of the initial maps (LSCM, mean-value, uniform Tutte) on a generated bumpy
//! disc (`1 + 3n(n + 1)` vertices; default n = 258, about 200k vertices), with the
//! number of flipped triangles of each result.
//!
//! Run: `cargo run --release -p surfmap-bench --example initial_maps_bench [n]`

use std::time::Instant;
use surfmap::Disc;
use surfmap::mesh::generate::bumpy_disc;
use surfmap::param::{count_flipped, lscm::lscm, tutte};

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(258);
    let mesh = bumpy_disc(n, 0.5);
    let disc = Disc::new(&mesh).expect("disc");
    println!(
        "bumpy_disc({n}, 0.5): {} vertices, {} triangles, {} boundary vertices",
        mesh.num_vertices(),
        mesh.num_triangles(),
        disc.boundary().len()
    );
    let (p, t, d) = (&mesh.positions, &mesh.triangles, &disc);
    let time = |name: &str, f: &dyn Fn() -> Vec<[f64; 2]>| {
        let start = Instant::now();
        let uv = f();
        let ms = start.elapsed().as_secs_f64() * 1e3;
        println!(
            "  {name:<12} {ms:8.1} ms, flipped {}",
            count_flipped(&uv, t)
        );
    };
    time("lscm", &|| lscm(p, d).expect("lscm").uv);
    time("mean_value", &|| {
        tutte::mean_value(p, d).expect("mean value")
    });
    time("uniform", &|| tutte::tutte_uniform(p, d).expect("uniform"));
}
