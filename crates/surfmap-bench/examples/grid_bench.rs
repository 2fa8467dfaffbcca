//! Speed of the grid kernels the matcher leans on: bilinear sampling with gradient at 1M
//! points on a 257² `Grid<f64>` and `Grid<[f64; 3]>` (one thread, and all threads with
//! rayon), and building the Gaussian pyramid of a 257² and a 1025² metric grid. Median of
//! `RUNS` runs (default 7).
//!
//! Two point sets: uniformly random over ω and a 2% margin (every sample a cache miss on
//! the larger grids), and "coherent": a 1000 × 1000 lattice in row order, each point
//! jittered by up to two cells, as the matcher visits `φ(ξ)` for `ξ` in grid order.
//!
//! `cargo run --release -p surfmap-bench --example grid_bench`

use std::hint::black_box;
use std::time::Instant;

use rayon::prelude::*;
use surfmap::grid::{Grid, MetricPyramid, Pyramid, Vector};
use surfmap::testing::Rng;

/// Median wall-clock seconds of `runs` calls of `f`.
fn median_seconds(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[runs / 2]
}

/// Sum of every component of value and gradient, so that no sample can be skipped.
#[inline]
fn total<T: Vector>((v, d0, d1): (T, T, T)) -> f64 {
    v.add(d0).add(d1).components().iter().sum()
}

fn bench_sampling<T: Vector>(
    name: &str,
    grid: &Grid<T>,
    (order, points): (&str, &[[f64; 2]]),
    runs: usize,
) {
    let serial = median_seconds(runs, || {
        let mut acc = 0.0;
        for &p in points {
            acc += total(grid.sample_with_gradient(p));
        }
        black_box(acc);
    });
    let parallel = median_seconds(runs, || {
        let acc: f64 = points
            .par_chunks(4096)
            .map(|chunk| {
                chunk
                    .iter()
                    .map(|&p| total(grid.sample_with_gradient(p)))
                    .sum::<f64>()
            })
            .sum();
        black_box(acc);
    });
    let per = |t: f64| 1e9 * t / points.len() as f64;
    println!(
        "sample_with_gradient, {name} {0}×{0}, {1} {order} points: serial {2:.1} ms \
         ({3:.1} ns/point), parallel {4:.1} ms ({5:.1} ns/point, {6} threads)",
        grid.size(),
        points.len(),
        1e3 * serial,
        per(serial),
        1e3 * parallel,
        per(parallel),
        rayon::current_num_threads()
    );
}

/// An SPD metric with varying anisotropy and orientation.
fn metric_grid(n: usize) -> Grid<[f64; 3]> {
    let s = (n - 1) as f64;
    Grid::from_fn(n, |i, j| {
        let (x, y) = (j as f64 / s, i as f64 / s);
        let (sn, cs) = (5.0 * x + 3.0 * y).sin_cos();
        let (l1, l2) = (1.0 + 20.0 * x * y, 0.1 + y);
        [
            l1 * cs * cs + l2 * sn * sn,
            (l1 - l2) * cs * sn,
            l1 * sn * sn + l2 * cs * cs,
        ]
    })
    .expect("valid size")
}

fn main() {
    let runs: usize = std::env::var("RUNS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(7)
        .max(1);
    let n = 257;
    let s = (n - 1) as f64;
    // Points over ω and a margin around it (8% of them clamped).
    let mut rng = Rng(12345);
    let random: Vec<[f64; 2]> = (0..1_000_000)
        .map(|_| [rng.range(-0.02, 1.02), rng.range(-0.02, 1.02)])
        .collect();
    let jitter = 2.0 / s;
    let coherent: Vec<[f64; 2]> = (0..1_000_000)
        .map(|k| {
            let (i, j) = ((k / 1000) as f64 / 999.0, (k % 1000) as f64 / 999.0);
            [
                j + rng.range(-jitter, jitter),
                i + rng.range(-jitter, jitter),
            ]
        })
        .collect();
    let scalar = Grid::from_fn(n, |i, j| {
        (7.0 * j as f64 / s).sin() * (3.0 * i as f64 / s).cos()
    })
    .expect("valid size");
    let vector = metric_grid(n);
    for points in [("random", &random[..]), ("coherent", &coherent[..])] {
        bench_sampling("Grid<f64>", &scalar, points, runs);
        bench_sampling("Grid<[f64; 3]>", &vector, points, runs);
    }

    for n in [257, 1025] {
        let g = metric_grid(n);
        let mut levels = 0;
        let t = median_seconds(runs, || {
            let p: MetricPyramid = Pyramid::new(g.clone());
            levels = p.num_levels();
            black_box(p);
        });
        println!(
            "metric pyramid (Pyramid<[f64; 3]>) of {n}×{n}: {:.1} ms, {levels} levels, {} threads",
            1e3 * t,
            rayon::current_num_threads()
        );
    }
}
