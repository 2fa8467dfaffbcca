//! Small analytic test meshes (test builds only): a disc of concentric rings in the
//! parameter plane, mapped onto a surface by a known parameterization.

/// `(positions, uv, triangles)`.
pub type TestMesh = (Vec<[f64; 3]>, Vec<[f64; 2]>, Vec<[u32; 3]>);

use std::f64::consts::TAU;

/// Ring-disc mesh of radius `radius` with `n` rings (ring `k` has `6k` vertices), mapped
/// by `map(u, v)`. Returns `(positions, uv, triangles)`; triangles are counter-clockwise
/// in the `(u, v)` plane.
pub fn disc(n: usize, radius: f64, map: impl Fn(f64, f64) -> [f64; 3]) -> TestMesh {
    let mut uv = vec![[0.0, 0.0]];
    let mut ring_start = vec![0usize];
    for k in 1..=n {
        ring_start.push(uv.len());
        let m = 6 * k;
        let r = radius * k as f64 / n as f64;
        for i in 0..m {
            let a = TAU * i as f64 / m as f64;
            uv.push([r * a.cos(), r * a.sin()]);
        }
    }
    let mut tris = vec![];
    for k in 1..=n {
        let (ma, mb) = (if k == 1 { 1 } else { 6 * (k - 1) }, 6 * k);
        let (sa, sb) = (ring_start[k - 1], ring_start[k]);
        let ang = |i: usize, m: usize| i as f64 / m as f64;
        let (mut i, mut j) = (0, 0);
        while i < ma || j < mb {
            let ai = |i: usize| (sa + i % ma) as u32;
            let bj = |j: usize| (sb + j % mb) as u32;
            let advance_b = if k == 1 {
                true
            } else {
                j < mb && (i >= ma || ang(j + 1, mb) <= ang(i + 1, ma))
            };
            if advance_b {
                tris.push([ai(i), bj(j), bj(j + 1)]);
                j += 1;
            } else {
                tris.push([ai(i), bj(j), ai(i + 1)]);
                i += 1;
            }
            if k == 1 && j == mb {
                break;
            }
        }
    }
    let x = uv.iter().map(|p| map(p[0], p[1])).collect();
    (x, uv, tris)
}

/// Regular `n × n`-cell grid over `[−a, a]²` (every cell split along the same diagonal, so
/// every interior one-ring is centrally symmetric), mapped by `map(u, v)`.
pub fn grid(n: usize, a: f64, map: impl Fn(f64, f64) -> [f64; 3]) -> TestMesh {
    let mut uv = vec![];
    for i in 0..=n {
        for j in 0..=n {
            uv.push([
                -a + 2.0 * a * j as f64 / n as f64,
                -a + 2.0 * a * i as f64 / n as f64,
            ]);
        }
    }
    let id = |i: usize, j: usize| (i * (n + 1) + j) as u32;
    let mut tris = vec![];
    for i in 0..n {
        for j in 0..n {
            tris.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
        }
    }
    let x = uv.iter().map(|p| map(p[0], p[1])).collect();
    (x, uv, tris)
}

/// Spherical cap of radius `r` over the square `[−a, a]²`, `a < r/√2` (orthographic
/// parameterization `(u, v) ↦ (u, v, √(r² − u² − v²))`, outward normals up).
pub fn sphere_cap(n: usize, r: f64, a: f64) -> TestMesh {
    grid(n, a, |u, v| [u, v, (r * r - u * u - v * v).sqrt()])
}

/// Cylinder patch of radius `r`, axis along y, isometric parameterization
/// `(u, v) ↦ (r sin(u/r), v, r cos(u/r))` over `[−1, 1]²` (outward normals).
pub fn cylinder_patch(n: usize, r: f64) -> TestMesh {
    grid(n, 1.0, |u, v| [r * (u / r).sin(), v, r * (u / r).cos()])
}

#[test]
fn disc_is_a_ccw_disc() {
    let (x, uv, tris) = disc(5, 1.0, |u, v| [u, v, 0.0]);
    assert_eq!(uv.len(), 1 + 3 * 5 * 6);
    // Euler characteristic V − E + F = 1 and total area ≈ polygon area.
    let e = super::boundary::boundary_edges(&tris).len();
    assert_eq!(e, 30);
    let area: f64 = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| uv[v as usize]);
            let s = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
            assert!(s > 0.0);
            s
        })
        .sum();
    let poly = 0.5 * 30.0 * (TAU / 30.0).sin();
    assert!((area - poly).abs() < 1e-12, "{area} {poly}");
    assert_eq!(x.len(), uv.len());
}
