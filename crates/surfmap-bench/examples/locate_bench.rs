//! Point location benchmark: `locate_bench [--runs N] [MESH]`.
//!
//! Flattens a 50k-face bumpy disc (or MESH, any disc mesh), builds a [`PointLocator`]
//! over the UVs and locates 100k points, uniform in the bounding box; prints the build
//! time and the median time of the 100k queries serially and with `locate_many` (in
//! parallel), over N runs (default 7), and the speed-up against a brute-force search
//! over all triangles (timed on 1k of the points). A second query set, one random point in
//! each of 100k random triangles (so distributed like the triangles, as the vertices
//! of another surface mapped into this one would be), shows the cost where the
//! flattening is dense; both sets are also timed with a single uniform grid
//! (`PointLocator::with_max_depth(.., 1)`). Last, `nearest` for the points outside,
//! all of them and those within 1 % of the bounding box's diagonal of the domain.
use std::hint::black_box;
use std::time::Instant;
use surfmap::PointLocator;
use surfmap::mesh::generate::bumpy_disc;
use surfmap::mesh::io::read_mesh;
use surfmap::param::flatten::{FlattenOptions, flatten};
use surfmap::testing::Rng;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Times `f` `runs` times; the median in seconds.
fn timed(runs: usize, mut f: impl FnMut()) -> f64 {
    median(
        (0..runs)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64()
            })
            .collect(),
    )
}

/// The lowest-index triangle containing `p` (barycentric coordinates ≥ −1e-12), by
/// testing every triangle.
fn brute_force(uvs: &[[f64; 2]], triangles: &[[u32; 3]], p: [f64; 2]) -> Option<u32> {
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    triangles
        .iter()
        .position(|t| {
            let [a, b, c] = t.map(|v| uvs[v as usize]);
            let area = orient(a, b, c);
            [orient(p, b, c), orient(a, p, c), orient(a, b, p)]
                .iter()
                .all(|&x| x / area >= -1e-12)
        })
        .map(|t| t as u32)
}

fn main() {
    let mut args = std::env::args().skip(1);
    let (mut runs, mut path) = (7usize, None);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--runs" => runs = args.next().and_then(|n| n.parse().ok()).expect("--runs N"),
            _ => path = Some(a),
        }
    }
    let mesh = match &path {
        Some(p) => {
            read_mesh(std::path::Path::new(p))
                .expect("readable mesh")
                .mesh
        }
        None => bumpy_disc(91, 0.5),
    };
    let map = flatten(&mesh, &FlattenOptions::default()).expect("a disc mesh");
    let (uvs, triangles) = (&map.uvs, &mesh.triangles);
    println!(
        "{}: {} vertices, {} faces, flattened ({} flipped)",
        path.as_deref().unwrap_or("bumpy_disc(91, 0.5)"),
        uvs.len(),
        triangles.len(),
        map.flipped_triangles
    );

    let build = timed(runs, || {
        black_box(PointLocator::new(uvs, triangles).unwrap());
    });
    let locator = PointLocator::new(uvs, triangles).unwrap();
    let (lo, hi) = locator.bounds();
    let mut rng = Rng(0x10ca7e);
    let uniform: Vec<[f64; 2]> = (0..100_000)
        .map(|_| [rng.range(lo[0], hi[0]), rng.range(lo[1], hi[1])])
        .collect();
    let dense: Vec<[f64; 2]> = (0..100_000)
        .map(|_| {
            let t = triangles[rng.below(triangles.len())];
            let (mut a, mut b) = (rng.uniform(), rng.uniform());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            let c = t.map(|v| uvs[v as usize]);
            [0, 1].map(|k| (1.0 - a - b) * c[0][k] + a * c[1][k] + b * c[2][k])
        })
        .collect();
    println!(
        "build: {:.2} ms (median of {runs}), {:.0} bytes per triangle; {:.1} % of the uniform points inside",
        1e3 * build,
        locator.memory_bytes() as f64 / triangles.len() as f64,
        100.0 * locator.locate_many(&uniform).iter().flatten().count() as f64 / 1e5
    );
    let single = PointLocator::with_max_depth(uvs, triangles, 1).unwrap();
    let mut serial_uniform = 0.0;
    for (name, points) in [("uniform in the box", &uniform), ("by triangle", &dense)] {
        let serial = timed(runs, || {
            for &p in points {
                black_box(locator.locate(p));
            }
        });
        let parallel = timed(runs, || {
            black_box(locator.locate_many(points));
        });
        let uniform_grid = timed(runs, || {
            for &p in points {
                black_box(single.locate(p));
            }
        });
        println!(
            "100k points {name}: serial {:.2} ms ({:.0} ns/point), locate_many {:.2} ms on {} threads; one uniform grid instead: serial {:.2} ms",
            1e3 * serial,
            1e9 * serial / 1e5,
            1e3 * parallel,
            rayon::current_num_threads(),
            1e3 * uniform_grid,
        );
        if serial_uniform == 0.0 {
            serial_uniform = serial;
        }
    }
    let outside: Vec<[f64; 2]> = uniform
        .iter()
        .copied()
        .filter(|&p| locator.locate(p).is_none())
        .collect();
    // Points slightly outside: within 1 % of the bounding box's diagonal of the domain.
    let diagonal = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    let near: Vec<[f64; 2]> = outside
        .iter()
        .copied()
        .filter(|&p| locator.nearest(p).unwrap().distance < 0.01 * diagonal)
        .collect();
    for (name, points) in [("all", &outside), ("within 1 % of the diagonal", &near)] {
        let nearest = timed(runs, || {
            for &p in points {
                black_box(locator.nearest(p));
            }
        });
        println!(
            "nearest, {} points outside ({name}): {:.2} ms ({:.2} µs/point, serial)",
            points.len(),
            1e3 * nearest,
            1e6 * nearest / points.len() as f64
        );
    }
    let sample = &uniform[..1000];
    let brute = timed(runs.min(3), || {
        for &p in sample {
            black_box(brute_force(uvs, triangles, p));
        }
    });
    let agree = sample
        .iter()
        .filter(|&&p| locator.locate(p).map(|s| s.triangle) == brute_force(uvs, triangles, p))
        .count();
    println!(
        "brute force on 1k of the uniform points: {:.1} µs/point, against the locator's {:.0} ns/point (100k points): {:.0}× slower; same triangle for {agree} of 1000",
        1e6 * brute / 1e3,
        1e9 * serial_uniform / 1e5,
        (brute / 1e3) / (serial_uniform / 1e5)
    );
}
