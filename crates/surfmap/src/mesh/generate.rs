//! Deterministic generated meshes for tests, examples and benchmarks.
//!
//! Every generator returns a [`TriMesh`] with counter-clockwise triangles (normals
//! pointing to +z for the planar and bumpy discs, outward for the cap, the cylinder and
//! the closed surfaces). The discs are discs topologically; the closed surfaces
//! ([`octahedron`], [`sphere`], [`torus`], [`holed_plate`]) are for what has to be cut
//! first. Same arguments, same mesh, bit for bit.
//!
//! Vertex order: discs and caps are built ring by ring from the center (vertex 0), so
//! the last ring is the boundary; grids are row-major.

use super::TriMesh;
use std::f64::consts::TAU;

/// The unit square `[0, 1]² × {0}` as two counter-clockwise triangles.
pub fn unit_square() -> TriMesh {
    TriMesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

/// The regular octahedron with vertices `±e_x, ±e_y, ±e_z`, outward-facing: a closed
/// surface (genus 0, no boundary), for tests of what is not a disc.
pub fn octahedron() -> TriMesh {
    TriMesh::new(
        vec![
            [1., 0., 0.],
            [-1., 0., 0.],
            [0., 1., 0.],
            [0., -1., 0.],
            [0., 0., 1.],
            [0., 0., -1.],
        ],
        vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ],
    )
}

/// The unit sphere: the [`octahedron`] subdivided `levels` times at edge midpoints,
/// every vertex pushed onto the sphere (`8·4^levels` triangles, genus 0, closed).
pub fn sphere(levels: usize) -> TriMesh {
    let mut mesh = octahedron();
    for _ in 0..levels {
        mesh = super::subdivide::subdivide_midpoint(&mesh);
    }
    for p in &mut mesh.positions {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        *p = p.map(|x| x / r);
    }
    mesh
}

/// The torus of tube radius `minor` around a circle of radius `major > minor` in the
/// xy plane: `n` steps around the z axis, `m` around the tube (both ≥ 3); vertex
/// `(i, j)` at angle `2πi/n` around the axis and `2πj/m` around the tube has index
/// `i·m + j`. Closed, genus 1.
pub fn torus(major: f64, minor: f64, n: usize, m: usize) -> TriMesh {
    let (n, m) = (n.max(3), m.max(3));
    let mut positions = Vec::with_capacity(n * m);
    for i in 0..n {
        let u = TAU * i as f64 / n as f64;
        for j in 0..m {
            let v = TAU * j as f64 / m as f64;
            let r = major + minor * v.cos();
            positions.push([r * u.cos(), r * u.sin(), minor * v.sin()]);
        }
    }
    let triangles = quad_triangles(n, m, |i, j| ((i % n) * m + j % m) as u32);
    TriMesh::new(positions, triangles)
}

/// The surface of a plate of `(2·holes + 1) × 3 × 1` unit cubes with `holes` square
/// holes through it (cube `(2k + 1, 1)` left out for `k < holes`): a closed surface of
/// genus `holes` with flat faces and right-angled creases, every cube face split into
/// `subdivisions × subdivisions` squares of two triangles. Closed, manifold, outward.
pub fn holed_plate(holes: usize, subdivisions: usize) -> TriMesh {
    let s = subdivisions.max(1);
    let (nx, ny) = (2 * holes + 1, 3);
    let filled = |x: i64, y: i64, z: i64| -> bool {
        (0..nx as i64).contains(&x) && (0..ny).contains(&y) && z == 0 && !(y == 1 && x % 2 == 1)
    };
    let mut index = std::collections::HashMap::new();
    let mut positions = Vec::new();
    let mut vertex = |p: [i64; 3]| -> u32 {
        *index.entry(p).or_insert_with(|| {
            positions.push(p.map(|c| c as f64 / s as f64));
            (positions.len() - 1) as u32
        })
    };
    let mut triangles = Vec::new();
    for x in 0..nx as i64 {
        for y in 0..ny {
            if !filled(x, y, 0) {
                continue;
            }
            for axis in 0..3 {
                for side in [0i64, 1] {
                    let mut n = [x, y, 0];
                    n[axis] += 2 * side - 1;
                    if filled(n[0], n[1], n[2]) {
                        continue;
                    }
                    // The face's two in-plane axes, ordered so that (a, b, outward)
                    // is right-handed.
                    let (a, b) = if side == 1 {
                        ((axis + 1) % 3, (axis + 2) % 3)
                    } else {
                        ((axis + 2) % 3, (axis + 1) % 3)
                    };
                    let corner = |i: i64, j: i64| {
                        let mut p = [x * s as i64, y * s as i64, 0];
                        p[axis] += side * s as i64;
                        p[a] += i;
                        p[b] += j;
                        p
                    };
                    for i in 0..s as i64 {
                        for j in 0..s as i64 {
                            let q = [
                                vertex(corner(i, j)),
                                vertex(corner(i + 1, j)),
                                vertex(corner(i + 1, j + 1)),
                                vertex(corner(i, j + 1)),
                            ];
                            triangles.push([q[0], q[1], q[2]]);
                            triangles.push([q[0], q[2], q[3]]);
                        }
                    }
                }
            }
        }
    }
    TriMesh::new(positions, triangles)
}

/// Planar `n × n` grid of squares on `[0, 1]² × {0}`: `(n + 1)²` vertices, vertex
/// `(i, j)` (row `j`, column `i`) at `(i/n, j/n, 0)` has index `j·(n + 1) + i`. Each
/// square is split along the diagonal from `(i, j)` to `(i + 1, j + 1)`. `n ≥ 1`
/// (`n = 0` is treated as 1).
pub fn grid_disc(n: usize) -> TriMesh {
    let n = n.max(1);
    let mut positions = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            positions.push([i as f64 / n as f64, j as f64 / n as f64, 0.0]);
        }
    }
    TriMesh::new(positions, grid_triangles(n, n))
}

/// Triangles of a row-major `(cols + 1) × (rows + 1)` vertex grid, counter-clockwise
/// when column index grows along x and row index along y.
fn grid_triangles(cols: usize, rows: usize) -> Vec<[u32; 3]> {
    quad_triangles(cols, rows, |i, j| (j * (cols + 1) + i) as u32)
}

/// Two triangles `(a, b, c)`, `(a, c, d)` per quad `(i, j)`, `i < cols`, `j < rows`,
/// with corners `a = id(i, j)`, `b = id(i + 1, j)`, `c = id(i + 1, j + 1)`,
/// `d = id(i, j + 1)`, rows outermost.
fn quad_triangles(cols: usize, rows: usize, id: impl Fn(usize, usize) -> u32) -> Vec<[u32; 3]> {
    let mut triangles = Vec::with_capacity(2 * cols * rows);
    for j in 0..rows {
        for i in 0..cols {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    triangles
}

/// Connectivity of a disc built from concentric rings: vertex 0 is the center, ring
/// `k = 1..=rings` has `ring_len(k)` vertices at angles `2π m / ring_len(k)`,
/// `m = 0..ring_len(k)`, stored consecutively. Consecutive rings are stitched by
/// merging their angle sequences, so any ring sizes ≥ 3 work.
///
/// Returns `(ring_of_vertex, fraction_of_turn, triangles)`.
fn ring_disc(
    rings: usize,
    ring_len: impl Fn(usize) -> usize,
) -> (Vec<(usize, f64)>, Vec<[u32; 3]>) {
    let mut vertices = vec![(0usize, 0.0f64)];
    let mut ring_start = vec![0usize];
    for k in 1..=rings {
        ring_start.push(vertices.len());
        let len = ring_len(k).max(3);
        for m in 0..len {
            vertices.push((k, m as f64 / len as f64));
        }
    }
    ring_start.push(vertices.len());
    let ring = |k: usize| {
        (ring_start[k]..ring_start[k + 1])
            .map(|v| v as u32)
            .collect::<Vec<_>>()
    };
    let mut triangles = Vec::new();
    // Center fan.
    if rings >= 1 {
        let r1 = ring(1);
        for m in 0..r1.len() {
            triangles.push([0, r1[m], r1[(m + 1) % r1.len()]]);
        }
    }
    // Stitch ring k−1 (inner, a vertices) to ring k (outer, b vertices): a + b triangles.
    for k in 2..=rings {
        let (inner, outer) = (ring(k - 1), ring(k));
        let (a, b) = (inner.len(), outer.len());
        let (mut i, mut j) = (0usize, 0usize);
        while i < a || j < b {
            // Advance the ring whose next vertex comes first in angle ((i+1)/a vs (j+1)/b).
            let advance_inner = j == b || (i < a && (i + 1) * b < (j + 1) * a);
            if advance_inner {
                triangles.push([inner[i % a], outer[j % b], inner[(i + 1) % a]]);
                i += 1;
            } else {
                triangles.push([inner[i % a], outer[j % b], outer[(j + 1) % b]]);
                j += 1;
            }
        }
    }
    (vertices, triangles)
}

/// Planar unit disc from a polar grid: the center plus `rings` circles of radius
/// `k / rings`, each with `segments` vertices (`segments ≥ 3`, `rings ≥ 1`). Vertex
/// `1 + (k − 1)·segments + m` is at radius `k / rings`, angle `2π m / segments`.
pub fn polar_disc(rings: usize, segments: usize) -> TriMesh {
    let rings = rings.max(1);
    let (vertices, triangles) = ring_disc(rings, |_| segments);
    let positions = vertices
        .iter()
        .map(|&(k, t)| {
            let r = k as f64 / rings as f64;
            [r * (TAU * t).cos(), r * (TAU * t).sin(), 0.0]
        })
        .collect();
    TriMesh::new(positions, triangles)
}

/// Cap of the sphere of radius `radius` centered at the origin around the pole
/// `(0, 0, radius)`: all points with polar angle `θ ≤ opening_angle` (`π/2` gives a
/// hemisphere; must be `< π` to stay a disc). Ring `k` lies at `θ = opening_angle·k/rings`
/// with `segments` vertices at azimuth `2π m / segments`; vertex 0 is the pole.
/// Normals point outward.
pub fn spherical_cap(radius: f64, opening_angle: f64, rings: usize, segments: usize) -> TriMesh {
    let rings = rings.max(1);
    let (vertices, triangles) = ring_disc(rings, |_| segments);
    let positions = vertices
        .iter()
        .map(|&(k, t)| {
            let theta = opening_angle * k as f64 / rings as f64;
            let phi = TAU * t;
            [
                radius * theta.sin() * phi.cos(),
                radius * theta.sin() * phi.sin(),
                radius * theta.cos(),
            ]
        })
        .collect();
    TriMesh::new(positions, triangles)
}

/// Lateral surface of the right circular cone with apex `(0, 0, height)` over the circle
/// of radius `radius` in the plane `z = 0` (no base: a disc). Ring `k` lies at height
/// `height·(1 − k/rings)` with `segments` vertices at azimuth `2π m / segments`; vertex 0
/// is the apex. Every quad between two rings lies in the plane of its two generators, so
/// the surface is developable but at the apex: cut along a generator, it unrolls
/// isometrically onto a sector of angle `2π·radius/√(radius² + height²)`. Normals point
/// outward.
pub fn cone(radius: f64, height: f64, rings: usize, segments: usize) -> TriMesh {
    let rings = rings.max(1);
    let (vertices, triangles) = ring_disc(rings, |_| segments);
    let positions = vertices
        .iter()
        .map(|&(k, t)| {
            let s = k as f64 / rings as f64;
            let phi = TAU * t;
            [
                radius * s * phi.cos(),
                radius * s * phi.sin(),
                height * (1.0 - s),
            ]
        })
        .collect();
    TriMesh::new(positions, triangles)
}

/// Patch of the cylinder of radius `radius` around the z axis: azimuth `φ ∈ [0, angle]`
/// in `n` steps, height `z ∈ [0, height]` in `m` steps; `(n + 1)(m + 1)` vertices, vertex
/// `(i, j)` at `(R cos φ_i, R sin φ_i, z_j)` with index `j·(n + 1) + i`. Every grid quad is
/// a planar rectangle, so the triangulated patch is exactly developable: it unrolls
/// isometrically onto a `n·2R sin(angle/2n) × height` rectangle. Normals point outward.
pub fn cylinder_patch(radius: f64, angle: f64, height: f64, n: usize, m: usize) -> TriMesh {
    let (n, m) = (n.max(1), m.max(1));
    let mut positions = Vec::with_capacity((n + 1) * (m + 1));
    for j in 0..=m {
        for i in 0..=n {
            let phi = angle * i as f64 / n as f64;
            let z = height * j as f64 / m as f64;
            positions.push([radius * phi.cos(), radius * phi.sin(), z]);
        }
    }
    TriMesh::new(positions, grid_triangles(n, m))
}

/// Unit disc with `n` rings of nearly equilateral triangles (ring `k` has `6k` vertices
/// at radius `k/n`, as in a hexagonal disc) lifted to the height field
/// `z = amplitude · (1 − r²) · (sin 4x · cos 3y + ½ cos 5r)`, which is smooth, not
/// rotationally symmetric, and has several bumps and dips.
pub fn bumpy_disc(n: usize, amplitude: f64) -> TriMesh {
    let n = n.max(1);
    let (vertices, triangles) = ring_disc(n, |k| 6 * k);
    let positions = vertices
        .iter()
        .map(|&(k, t)| {
            let r = k as f64 / n as f64;
            let (x, y) = (r * (TAU * t).cos(), r * (TAU * t).sin());
            let z = amplitude
                * (1.0 - r * r)
                * ((4.0 * x).sin() * (3.0 * y).cos() + 0.5 * (5.0 * r).cos());
            [x, y, z]
        })
        .collect();
    TriMesh::new(positions, triangles)
}

/// Shape of an [`octopus_disc`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Octopus {
    /// Number of arms (≥ 1).
    pub arms: usize,
    /// Arm width at its base, in edges of the hub's rim (≥ 3 for a tube).
    pub width: usize,
    /// Arm length, in rows of roughly square quads.
    pub length: usize,
    /// Rings of the hub (≥ 1).
    pub rings: usize,
    /// Height of the hub's dome over its rim (the hub has radius 1).
    pub dome: f64,
    /// Amplitude of a flat arm's saddle twist, in arm half-widths (unused for tubes).
    pub twist: f64,
    /// Whether each arm is a closed tube (a tentacle: its two long sides glued, its tip
    /// capped) instead of a flat strip.
    pub tube: bool,
}

impl Default for Octopus {
    /// Eight tentacles, tubes of 8 edges around and 14 rows long (length over diameter
    /// about 5.5, so a conformal map shrinks their tips by about e^{−11} against their
    /// base), on a hub of 8 rings with a dome of height 1: 2,896 triangles.
    fn default() -> Self {
        Self {
            arms: 8,
            width: 8,
            length: 14,
            rings: 8,
            dome: 1.0,
            twist: 0.0,
            tube: true,
        }
    }
}

/// A disc with long thin arms (a hard case for flattening, issue 50): a hub, the unit
/// disc lifted to the dome `z = dome·(1 − r²)²` (ring `k` of `max(6, n·k/rings)` vertices,
/// `n = 2·arms·width` on the rim), with `arms` arms of `width × length` quads of side
/// `h = 2π/n` attached to every other run of `width` rim edges, pointing radially
/// outward.
///
/// - A flat arm (`tube: false`) narrows linearly to half its width at the tip and is
///   lifted by the saddle twist `z = twist·w·t·sin(2π s / (4 w))` (`t ∈ [−1, 1]` across,
///   `s` along it, `w` its local half width): nearly developable, so its conformal scale
///   hardly varies.
/// - A tube (`tube: true`) has its two long sides glued from the first row on (a circle
///   of `width` vertices and radius `width·h/2π` around the arm's axis) and its tip capped
///   by one vertex; it joins the rim through one vertex, where the boundary dips in. A
///   conformal map of a tube shrinks it exponentially along its length, by `e^{−ℓ/ρ}`
///   over a length `ℓ` (radius `ρ`), which is what makes such discs hard: the thin
///   protrusions a cut closed mesh has when its cut does not run into them.
///
/// Counter-clockwise seen from +z on the hub and the flat arms, consistently oriented
/// everywhere; the arms' vertices follow the hub's, arm by arm, row by row.
pub fn octopus_disc(shape: &Octopus) -> TriMesh {
    let arms = shape.arms.max(1);
    let width = shape.width.max(if shape.tube { 3 } else { 1 });
    let rings = shape.rings.max(1);
    let rim = 2 * arms * width;
    let (vertices, mut triangles) = ring_disc(rings, |k| (rim * k / rings).max(6));
    let mut positions: Vec<[f64; 3]> = vertices
        .iter()
        .map(|&(k, t)| {
            let r = k as f64 / rings as f64;
            let z = shape.dome * (1.0 - r * r).powi(2);
            [r * (TAU * t).cos(), r * (TAU * t).sin(), z]
        })
        .collect();
    let rim_start = positions.len() - rim;
    let edge = TAU / rim as f64;
    let half = (0.5 * edge * width as f64).sin();
    let root = (0.5 * edge * width as f64).cos();
    let radius = width as f64 * edge / TAU;
    for a in 0..arms {
        let first = 2 * a * width;
        let angle = TAU * (first as f64 + 0.5 * width as f64) / rim as f64;
        let (dir, across) = ([angle.cos(), angle.sin()], [-angle.sin(), angle.cos()]);
        let base: Vec<u32> = (0..=width)
            .map(|j| (rim_start + (first + j) % rim) as u32)
            .collect();
        let mut rows = vec![base];
        let mut push = |p: [f64; 3]| {
            positions.push(p);
            (positions.len() - 1) as u32
        };
        for i in 1..=shape.length {
            let s = i as f64 * edge;
            let along = root + s;
            let row: Vec<u32> = if shape.tube {
                // Vertex j at angle 2πj/width around the axis, from its lowest point.
                let mut row: Vec<u32> = (0..width)
                    .map(|j| {
                        let phi = TAU * j as f64 / width as f64;
                        let (x, z) = (-radius * phi.sin(), -radius * phi.cos());
                        push([
                            along * dir[0] + x * across[0],
                            along * dir[1] + x * across[1],
                            radius + z,
                        ])
                    })
                    .collect();
                row.push(row[0]);
                row
            } else {
                let shrink = 1.0 - 0.5 * i as f64 / shape.length as f64;
                (0..=width)
                    .map(|j| {
                        let t = 2.0 * j as f64 / width as f64 - 1.0;
                        let offset = t * half * shrink;
                        let z = shape.twist * half * shrink * t * (TAU * s / (8.0 * half)).sin();
                        push([
                            along * dir[0] + offset * across[0],
                            along * dir[1] + offset * across[1],
                            z,
                        ])
                    })
                    .collect()
            };
            rows.push(row);
        }
        if shape.tube {
            let tip = push([
                (root + (shape.length as f64) * edge + radius) * dir[0],
                (root + (shape.length as f64) * edge + radius) * dir[1],
                radius,
            ]);
            rows.push(vec![tip; width + 1]);
        }
        // Quad (i, j) → two triangles, oriented as the hub (checked on the flat arm's
        // base row: the rim runs along `across`, the rows along `dir`).
        for i in 0..rows.len() - 1 {
            let (p, q) = (&rows[i], &rows[i + 1]);
            for j in 0..width {
                for tri in [[p[j], q[j + 1], p[j + 1]], [p[j], q[j], q[j + 1]]] {
                    if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
                        triangles.push(tri);
                    }
                }
            }
        }
    }
    TriMesh::new(positions, triangles)
}

/// Shape of a [`tentacles`] body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tentacles {
    /// Number of tentacles (≥ 1), evenly spaced around the body's equator.
    pub arms: usize,
    /// Side of the square window of the body's grid a tentacle grows from, in quads
    /// (≥ 1): a tentacle has `4·window` vertices around.
    pub window: usize,
    /// Tentacle length over its radius: a conformal map shrinks a tentacle's tip by
    /// about `e^{−length}` against its base.
    pub length: f64,
    /// Segments around the body (raised to `arms·(window + 1)` so that windows do not
    /// touch); the body has `segments / 2` latitude bands.
    pub segments: usize,
}

impl Default for Tentacles {
    /// Eight tentacles of 8 vertices around and 36 radii long on a body of 48 × 24
    /// segments: 8,096 triangles, tips shrunk by about e^{−36} in a conformal map, so
    /// that both initial maps flip triangles (the failing case of issue 50).
    fn default() -> Self {
        Self {
            arms: 8,
            window: 2,
            length: 36.0,
            segments: 48,
        }
    }
}

/// A closed genus-0 surface with long thin tentacles (issue 50): the unit sphere as a
/// latitude–longitude grid (`segments` around, `segments / 2` bands, one vertex per
/// pole), with `arms` square windows of `window × window` quads around the equator
/// removed, and from every window's boundary loop a tube of radius
/// `ρ = 0.35·window·h` (`h = 2π/segments`, the grid's spacing at the equator) along the
/// window's outward normal, `length·ρ` long in rows `2πρ/(4·window)` apart (roughly
/// square quads), capped by one tip vertex. Every vertex of a tube row sits at the
/// angle around the axis of its window-boundary vertex, so the tube does not twist.
/// Triangles are oriented outward (checked per triangle against the sphere's centre or
/// the tube's axis); the tubes' vertices follow the sphere's (the grid vertices inside
/// the windows left out), arm by arm, row by row.
pub fn tentacles(shape: &Tentacles) -> TriMesh {
    use crate::vec3::{cross3, dot3, sub3};
    let arms = shape.arms.max(1);
    let w = shape.window.max(1);
    let segments = shape.segments.max(arms * (w + 1)).max(2 * w + 4);
    let bands = (segments / 2).max(w + 2);
    // Grid vertex (ring r in 1..bands, column c) and the poles 0 (north) and 1 (south).
    let id = |r: usize, c: usize| (2 + (r - 1) * segments + c % segments) as u32;
    let mut positions = vec![[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
    for r in 1..bands {
        let theta = std::f64::consts::PI * r as f64 / bands as f64;
        for c in 0..segments {
            let phi = TAU * c as f64 / segments as f64;
            positions.push([
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ]);
        }
    }
    let r0 = (bands - w) / 2;
    let column = |a: usize| a * segments / arms;
    let in_window = |r: usize, c: usize| {
        (r0..r0 + w).contains(&r) && (0..arms).any(|a| (column(a)..column(a) + w).contains(&c))
    };
    // Triangles with the point they must face away from.
    let mut faces: Vec<([u32; 3], [f64; 3])> = Vec::new();
    let origin = [0.0; 3];
    for c in 0..segments {
        faces.push(([0, id(1, c), id(1, c + 1)], origin));
        faces.push(([1, id(bands - 1, c + 1), id(bands - 1, c)], origin));
        for r in 1..bands - 1 {
            if !in_window(r, c) {
                let (a, b, p, q) = (id(r, c), id(r, c + 1), id(r + 1, c), id(r + 1, c + 1));
                faces.push(([a, q, b], origin));
                faces.push(([a, p, q], origin));
            }
        }
    }
    let h = TAU / segments as f64;
    let rho = 0.35 * w as f64 * h;
    let around = 4 * w;
    let spacing = TAU * rho / around as f64;
    let rows = ((shape.length.max(0.0) * rho / spacing).round() as usize).max(1);
    for a in 0..arms {
        let c0 = column(a);
        // The window's boundary loop, once around.
        let mut base: Vec<u32> = (0..w).map(|k| id(r0, c0 + k)).collect();
        base.extend((0..w).map(|k| id(r0 + k, c0 + w)));
        base.extend((0..w).map(|k| id(r0 + w, c0 + w - k)));
        base.extend((0..w).map(|k| id(r0 + w - k, c0)));
        let theta = std::f64::consts::PI * (r0 as f64 + 0.5 * w as f64) / bands as f64;
        let phi = TAU * (c0 as f64 + 0.5 * w as f64) / segments as f64;
        let axis = [
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        ];
        let e1 = [-phi.sin(), phi.cos(), 0.0];
        let e2 = [
            theta.cos() * phi.cos(),
            theta.cos() * phi.sin(),
            -theta.sin(),
        ];
        let angles: Vec<f64> = base
            .iter()
            .map(|&v| {
                let d = sub3(positions[v as usize], axis);
                dot3(d, e2).atan2(dot3(d, e1))
            })
            .collect();
        let at = |s: f64, radius: f64, angle: f64| -> [f64; 3] {
            let (cos, sin) = (angle.cos(), angle.sin());
            [0, 1, 2].map(|k| (1.0 + s) * axis[k] + radius * (cos * e1[k] + sin * e2[k]))
        };
        let mut previous = base;
        for i in 1..=rows {
            let s = i as f64 * spacing;
            let row: Vec<u32> = angles
                .iter()
                .map(|&angle| {
                    positions.push(at(s, rho, angle));
                    (positions.len() - 1) as u32
                })
                .collect();
            let inside = axis.map(|x| x * (1.0 + s - 0.5 * spacing));
            for j in 0..around {
                let (p, q) = (previous[j], previous[(j + 1) % around]);
                let (x, y) = (row[j], row[(j + 1) % around]);
                faces.push(([p, q, y], inside));
                faces.push(([p, y, x], inside));
            }
            previous = row;
        }
        let end = 1.0 + rows as f64 * spacing;
        positions.push(axis.map(|x| x * (end + spacing)));
        let tip = (positions.len() - 1) as u32;
        for j in 0..around {
            faces.push((
                [previous[j], previous[(j + 1) % around], tip],
                axis.map(|x| x * end),
            ));
        }
    }
    let triangles: Vec<[u32; 3]> = faces
        .into_iter()
        .map(|(t, inside)| {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            let centroid = [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0);
            let normal = cross3(sub3(b, a), sub3(c, a));
            if dot3(normal, sub3(centroid, inside)) >= 0.0 {
                t
            } else {
                [t[0], t[2], t[1]]
            }
        })
        .collect();
    // Without the grid vertices inside the windows.
    let (mesh, _) = super::repair::drop_unreferenced(&TriMesh::new(positions, triangles));
    mesh
}

/// The boundary loop of a generated disc, surface on the left (counter-clockwise when
/// seen from the normal side), starting at its smallest vertex index. For tests that
/// must not depend on [`super::Topology`]; `None` if the boundary is not one loop.
pub fn disc_boundary(triangles: &[[u32; 3]]) -> Option<Vec<u32>> {
    use std::collections::{HashMap, HashSet};
    let directed: HashSet<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    let next: HashMap<u32, u32> = directed
        .iter()
        .filter(|&&(a, b)| !directed.contains(&(b, a)))
        .map(|&(a, b)| (a, b))
        .collect();
    let start = *next.keys().min()?;
    let mut boundary = vec![start];
    let mut v = next[&start];
    while v != start {
        if boundary.len() > next.len() {
            return None;
        }
        boundary.push(v);
        v = *next.get(&v)?;
    }
    (boundary.len() == next.len()).then_some(boundary)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::vec3::{cross3 as cross, dot3 as dot, sub3 as sub};

    /// Disc checks: Euler characteristic 1, one boundary loop, every triangle
    /// non-degenerate with its normal on the side given by `outward(centroid)`.
    fn check_disc(mesh: &TriMesh, outward: impl Fn([f64; 3]) -> [f64; 3]) -> Vec<u32> {
        let mut edges = std::collections::HashSet::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.insert((a.min(b), a.max(b)));
            }
        }
        let chi = mesh.positions.len() as i64 - edges.len() as i64 + mesh.triangles.len() as i64;
        assert_eq!(chi, 1, "a disc has Euler characteristic 1");
        for t in 0..mesh.num_triangles() {
            let [a, b, c] = mesh.triangle_positions(t);
            let nrm = cross(sub(b, a), sub(c, a));
            let centroid = [
                (a[0] + b[0] + c[0]) / 3.0,
                (a[1] + b[1] + c[1]) / 3.0,
                (a[2] + b[2] + c[2]) / 3.0,
            ];
            assert!(mesh.triangle_area(t) > 1e-6, "degenerate triangle {t}");
            assert!(
                dot(nrm, outward(centroid)) > 0.0,
                "triangle {t} is oriented inward"
            );
        }
        disc_boundary(&mesh.triangles).expect("one boundary loop")
    }

    /// Signed volume enclosed by a closed mesh, `Σ a·(b × c)/6` (positive when outward).
    fn enclosed_volume(mesh: &TriMesh) -> f64 {
        (0..mesh.num_triangles())
            .map(|t| {
                let [a, b, c] = mesh.triangle_positions(t);
                dot(a, cross(b, c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn octopus_discs_are_oriented_discs() {
        // Flat arms: counter-clockwise from +z, every triangle (the hub's dome included).
        let flat = Octopus {
            tube: false,
            width: 3,
            length: 45,
            twist: 1.0,
            ..Octopus::default()
        };
        let mesh = octopus_disc(&flat);
        check_disc(&mesh, |_| [0.0, 0.0, 1.0]);
        let hub = ring_disc(8, |k| (48 * k / 8).max(6)).1.len();
        assert_eq!(mesh.num_triangles(), hub + 2 * 8 * 3 * 45);
        // Tubes: a disc (χ = 1, one boundary loop), consistently oriented.
        let mesh = octopus_disc(&Octopus::default());
        let boundary = crate::mesh::Disc::new(&mesh)
            .expect("a disc")
            .boundary()
            .len();
        assert_eq!(boundary, 2 * 8 * 8 - 8 * 8 + 8 * 2);
        assert!((0..mesh.num_triangles()).all(|t| mesh.triangle_area(t) > 1e-6));
    }

    #[test]
    fn closed_surfaces_have_their_genus_and_enclose_their_volume() {
        use crate::mesh::Topology;
        let check = |mesh: &TriMesh, genus: u32, volume: f64, tolerance: f64| {
            let topo = Topology::new(mesh);
            assert!(topo.is_manifold() && topo.inconsistent_edges.is_empty());
            assert_eq!(topo.boundary_loops.len(), 0);
            assert_eq!(topo.genus(), Some(genus));
            let v = enclosed_volume(mesh);
            assert!((v - volume).abs() <= tolerance * volume, "{v} vs {volume}");
        };
        // Inscribed polyhedra: the volume converges to the smooth one from below.
        check(&sphere(4), 0, 4.0 / 3.0 * std::f64::consts::PI, 0.02);
        let (big, small) = (1.0, 0.4);
        check(
            &torus(big, small, 64, 32),
            1,
            2.0 * std::f64::consts::PI.powi(2) * big * small * small,
            0.01,
        );
        // Unit cubes, exactly: 3 rows of 2h + 1 minus the h holes.
        for h in 1..=3 {
            check(
                &holed_plate(h, 2),
                h as u32,
                (3 * (2 * h + 1) - h) as f64,
                1e-12,
            );
        }
        // The tentacle body: a closed sphere with 8 tubes, every triangle outward: the
        // volume is the ball's and 8 cylinders' of radius ρ = 0.35·2·2π/48 and length
        // 36ρ (the inscribed polygons a little less).
        let body = tentacles(&Tentacles::default());
        assert_eq!(body.triangles.len(), 8096);
        assert_eq!(body.positions.len(), 8096 / 2 + 2, "every vertex used");
        assert!((0..body.num_triangles()).all(|t| body.triangle_area(t) > 1e-6));
        let rho = 0.35 * 2.0 * TAU / 48.0;
        let pi = std::f64::consts::PI;
        check(
            &body,
            0,
            4.0 / 3.0 * pi + 8.0 * pi * rho * rho * 36.0 * rho,
            0.03,
        );
    }

    #[test]
    fn grid_disc_is_the_unit_square() {
        let mesh = grid_disc(4);
        assert_eq!(mesh.num_vertices(), 25);
        assert_eq!(mesh.num_triangles(), 32);
        assert!((mesh.area() - 1.0).abs() < 1e-14);
        let boundary = check_disc(&mesh, |_| [0.0, 0.0, 1.0]);
        assert_eq!(boundary.len(), 16);
        assert_eq!(
            &boundary[..3],
            &[0, 1, 2],
            "counter-clockwise from the origin"
        );
    }

    #[test]
    fn polar_and_bumpy_discs_are_discs() {
        let mesh = polar_disc(5, 12);
        assert_eq!(mesh.num_vertices(), 1 + 5 * 12);
        let boundary = check_disc(&mesh, |_| [0.0, 0.0, 1.0]);
        assert_eq!(boundary.len(), 12);
        // Area of the inscribed 12-gon of the unit circle: 12·½·sin(2π/12) = 3.
        assert!((mesh.area() - 3.0).abs() < 1e-12);
        let bumpy = bumpy_disc(6, 0.3);
        assert_eq!(bumpy.num_vertices(), 1 + 3 * 6 * 7);
        assert_eq!(bumpy.num_triangles(), 6 * 36);
        let boundary = check_disc(&bumpy, |_| [0.0, 0.0, 1.0]);
        assert_eq!(boundary.len(), 36);
        assert!(bumpy.positions.iter().any(|p| p[2].abs() > 0.05));
        assert_eq!(bumpy, bumpy_disc(6, 0.3), "deterministic");
    }

    #[test]
    fn spherical_cap_lies_on_the_sphere() {
        let (r, opening) = (2.0, 0.8 * std::f64::consts::PI);
        let mesh = spherical_cap(r, opening, 8, 24);
        for p in &mesh.positions {
            assert!((dot(*p, *p).sqrt() - r).abs() < 1e-12);
        }
        let boundary = check_disc(&mesh, |c| c);
        assert_eq!(boundary.len(), 24);
        for &v in &boundary {
            assert!((mesh.positions[v as usize][2] - r * opening.cos()).abs() < 1e-12);
        }
        // Polyhedral area approaches the cap area 2πr²(1 − cos θ) from below.
        let exact = TAU * r * r * (1.0 - opening.cos());
        let fine = spherical_cap(r, opening, 40, 160).area();
        assert!(mesh.area() < fine && fine < exact && (exact - fine) / exact < 2e-3);
    }

    #[test]
    fn cylinder_patch_is_developable() {
        let (r, angle, h, n, m) = (1.5, 2.0, 3.0, 10, 4);
        let mesh = cylinder_patch(r, angle, h, n, m);
        let boundary = check_disc(&mesh, |c| [c[0], c[1], 0.0]);
        assert_eq!(boundary.len(), 2 * (n + m));
        let width = n as f64 * 2.0 * r * (angle / (2.0 * n as f64)).sin();
        assert!((mesh.area() - width * h).abs() < 1e-12);
        // Interior vertex angle sums are 2π (zero Gaussian curvature).
        let mut angle_sum = vec![0.0; mesh.num_vertices()];
        for t in &mesh.triangles {
            for k in 0..3 {
                let p = mesh.positions[t[k] as usize];
                let e1 = sub(mesh.positions[t[(k + 1) % 3] as usize], p);
                let e2 = sub(mesh.positions[t[(k + 2) % 3] as usize], p);
                angle_sum[t[k] as usize] +=
                    dot(cross(e1, e2), cross(e1, e2)).sqrt().atan2(dot(e1, e2));
            }
        }
        for (v, sum) in angle_sum.iter().enumerate() {
            if !boundary.contains(&(v as u32)) {
                assert!((sum - TAU).abs() < 1e-12);
            }
        }
    }
}
