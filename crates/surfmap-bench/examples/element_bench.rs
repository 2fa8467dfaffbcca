//! Per-element cost of the Newton kernels: energy, gradient + PSD-projected Hessian,
//! and the flip-free step, in ns per triangle (median of several runs, one thread).
//!
//! Run: `cargo run --release -p surfmap-bench --example element_bench [triangles]`

use std::hint::black_box;
use std::time::Instant;

use surfmap::param::element::{RestTriangle, energy, gradient_and_projected_hessian};
use surfmap::param::flip_free::flip_free_step;
use surfmap::{Alpha, Energy};

use surfmap::testing::Rng;

fn median_ns_per_item(runs: usize, items: usize, mut f: impl FnMut() -> f64) -> f64 {
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let start = Instant::now();
            black_box(f());
            start.elapsed().as_nanos() as f64 / items as f64
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[runs / 2]
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(200_000);
    let mut rng = Rng(0x9e3779b97f4a7c15);
    let mut rest = Vec::with_capacity(n);
    let mut uvs = Vec::with_capacity(n);
    let mut dirs = Vec::with_capacity(n);
    while rest.len() < n {
        let p: [[f64; 3]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| rng.uniform()));
        let Some(r) = RestTriangle::new(p[0], p[1], p[2]) else {
            continue;
        };
        // UV: the rest triangle's own frame, perturbed, kept counter-clockwise.
        let uv: [[f64; 2]; 3] = std::array::from_fn(|_| [rng.uniform(), rng.uniform()]);
        let det = (uv[1][0] - uv[0][0]) * (uv[2][1] - uv[0][1])
            - (uv[2][0] - uv[0][0]) * (uv[1][1] - uv[0][1]);
        if det.abs() < 1e-3 {
            continue;
        }
        let uv = if det > 0.0 { uv } else { [uv[0], uv[2], uv[1]] };
        rest.push(r);
        uvs.push(uv);
        dirs.push(std::array::from_fn(|_| {
            [rng.uniform() - 0.5, rng.uniform() - 0.5]
        }));
    }
    let density = Energy::litke(Alpha::balanced());
    let runs = 9;

    let e_ns = median_ns_per_item(runs, n, || {
        rest.iter()
            .zip(&uvs)
            .map(|(r, uv)| energy(r, uv, &density))
            .sum()
    });
    let gh_ns = median_ns_per_item(runs, n, || {
        let (mut g, mut h) = ([0.0; 6], [[0.0; 6]; 6]);
        let mut acc = 0.0;
        for (r, uv) in rest.iter().zip(&uvs) {
            acc += gradient_and_projected_hessian(r, uv, &density, &mut g, &mut h);
            acc += g[0] + h[0][5];
        }
        acc
    });
    let ff_ns = median_ns_per_item(runs, n, || {
        uvs.iter()
            .zip(&dirs)
            .map(|(uv, d)| flip_free_step(*uv, *d))
            .fold(f64::INFINITY, f64::min)
    });
    println!("triangles: {n}, runs: {runs} (median), density: Litke balanced, 1 thread");
    println!("energy:                          {e_ns:7.1} ns/triangle");
    println!("gradient + projected Hessian:    {gh_ns:7.1} ns/triangle");
    println!("flip-free step:                  {ff_ns:7.1} ns/triangle");
}
