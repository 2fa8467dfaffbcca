//! Distance on the surface, measured in the metric `g`, from a feature set (thesis
//! §2.2.4, §3.2.2): the viscosity solution of the anisotropic Eikonal equation
//! `√(∇dᵀ g⁻¹ ∇d) = 1` on the grid, `d = 0` on the features.
//!
//! Discretization: the semi-Lagrangian (Hopf–Lax) upwind update on the 8 triangles of each
//! node's 8-neighbourhood, the same update as Bornemann & Rasch's upwind finite elements
//! and Tsitsiklis's method on a linear-interpolation mesh:
//! `d(q) = min_T min_{λ∈[0,1]} λ d(a) + (1−λ) d(b) + ‖q − (λa + (1−λ)b)‖_{g(q)}`,
//! with `‖w‖_g = √(wᵀ g w)` in domain units; the inner minimum has a closed form (below).
//! The scheme is monotone for any metric. An anisotropic metric breaks the causality a
//! plain fast-marching sweep relies on, so nodes are processed in heap order but may be
//! reopened whenever their value drops (a label-correcting method): the result is the
//! fixed point of the update, and for moderate anisotropy almost every node is settled once.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::GridError;
use super::grid::Grid;

/// The 8-neighbourhood in counter-clockwise order as `(di, dj)` (row, column).
const RING: [(i64, i64); 8] = [
    (0, 1),
    (1, 1),
    (1, 0),
    (1, -1),
    (0, -1),
    (-1, -1),
    (-1, 0),
    (-1, 1),
];

#[derive(Clone, Copy, PartialEq)]
struct Entry(f64, u32);
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

/// `‖w‖_g` for `g = [g11, g12, g22]`.
#[inline]
pub(crate) fn metric_norm(g: [f64; 3], w: [f64; 2]) -> f64 {
    (g[0] * w[0] * w[0] + 2.0 * g[1] * w[0] * w[1] + g[2] * w[1] * w[1])
        .max(0.0)
        .sqrt()
}

#[inline]
fn inner(g: [f64; 3], a: [f64; 2], b: [f64; 2]) -> f64 {
    g[0] * a[0] * b[0] + g[1] * (a[0] * b[1] + a[1] * b[0]) + g[2] * a[1] * b[1]
}

/// Hopf–Lax update through the segment `[q + u, q + v]` with values `du`, `dv`:
/// `min_λ λ du + (1−λ) dv + ‖λu + (1−λ)v‖_g`. With `e = u − v`, `δ = du − dv`,
/// `A = eᵀge`, `B = eᵀgv`, `C = vᵀgv`, `D = AC − B²`, the interior stationary point has
/// `‖w‖² = D / (A − δ²)` (requires `δ² < A`) and `λ = (−δ‖w‖ − B) / A`; otherwise the
/// minimum is at an end point (the edge updates, done separately).
#[inline]
pub(crate) fn triangle_update(du: f64, dv: f64, u: [f64; 2], v: [f64; 2], g: [f64; 3]) -> f64 {
    let e = [u[0] - v[0], u[1] - v[1]];
    let delta = du - dv;
    let a = inner(g, e, e);
    let b = inner(g, e, v);
    let c = inner(g, v, v);
    let denom = a - delta * delta;
    if denom <= 0.0 {
        return f64::INFINITY;
    }
    let d = (a * c - b * b).max(0.0);
    let w = (d / denom).sqrt();
    let lambda = (-delta * w - b) / a;
    if (0.0..=1.0).contains(&lambda) {
        dv + lambda * delta + w
    } else {
        f64::INFINITY
    }
}

/// A node is reopened only when an update lowers its value by more than this fraction.
/// Smaller decrements are rounding-level: where a strongly anisotropic metric makes
/// neighbouring nodes depend on each other both ways, they lower each other in turn by
/// ever smaller amounts, and at 10⁻¹³ the whole FLAME head flattened from its neck
/// (eigenvalue ratio of `g` 19 at the median, 700 at the 99th percentile) took 96
/// million updates for 34,000 nodes and ran out of the budget; at 10⁻⁹ it takes 2.5
/// million, and the match is bit for bit the one the unlimited 10⁻¹³ run gives. Face
/// pairs settle in about one update per node either way; their distance maps move by
/// at most this fraction, which the solve turns into other last digits (half of the
/// benchmark's outputs changed, its scores by hundredths of a point: BENCHMARKS.md).
const REOPEN_TOLERANCE: f64 = 1e-9;

/// Solves the Eikonal equation on the grid of the per-node metric `metric`
/// (`[g11, g12, g22]`, domain units).
///
/// `value` holds the initial data: finite at seeds (their distance to the feature, e.g.
/// from [`seed_polyline`] or [`seed_region_boundary`]), `∞` elsewhere; it is overwritten
/// with the distance. Only nodes with `updatable` set change; every finite node is a
/// source. Nodes never reached stay `∞`. All three grids must have the same size.
pub fn solve_eikonal(
    metric: &Grid<[f64; 3]>,
    updatable: &Grid<bool>,
    value: &mut Grid<f64>,
) -> Result<(), GridError> {
    metric.check_same_size(updatable, "the updatable mask")?;
    metric.check_same_size(value, "the distance grid")?;
    let n = metric.size();
    let (metric, updatable, value) = (
        metric.as_slice(),
        updatable.as_slice(),
        value.as_mut_slice(),
    );
    let h = 1.0 / (n - 1) as f64;
    // Sources: finite nodes that can update someone, i.e. updatable themselves or with an
    // updatable 8-neighbour (a frozen node inside a frozen region never needs a visit).
    let near_updatable = |k: usize| {
        let (i, j) = ((k / n) as i64, (k % n) as i64);
        updatable[k]
            || RING.iter().any(|&(di, dj)| {
                let (a, b) = (i + di, j + dj);
                a >= 0
                    && b >= 0
                    && a < n as i64
                    && b < n as i64
                    && updatable[a as usize * n + b as usize]
            })
    };
    let mut heap: BinaryHeap<Entry> = value
        .iter()
        .enumerate()
        .filter(|&(k, v)| v.is_finite() && near_updatable(k))
        .map(|(k, &v)| Entry(v, k as u32))
        .collect();
    let max_pops = 64 * n * n + 1024;
    let mut pops = 0usize;
    let edge_len: [[f64; 2]; 8] = RING.map(|(di, dj)| [dj as f64 * h, di as f64 * h]);
    while let Some(Entry(dp, p)) = heap.pop() {
        let p = p as usize;
        if dp > value[p] {
            continue; // stale entry
        }
        pops += 1;
        if pops > max_pops {
            return Err(GridError::EikonalStalled { pops });
        }
        let (pi, pj) = ((p / n) as i64, (p % n) as i64);
        for (m, &(di, dj)) in RING.iter().enumerate() {
            // q = p − offset, so p = q + RING[m].
            let (qi, qj) = (pi - di, pj - dj);
            if qi < 0 || qj < 0 || qi >= n as i64 || qj >= n as i64 {
                continue;
            }
            let q = qi as usize * n + qj as usize;
            if !updatable[q] {
                continue;
            }
            let g = metric[q];
            let u = edge_len[m];
            let mut best = dp + metric_norm(g, u);
            for side in [7, 1] {
                let r = (m + side) % 8;
                let (ri, rj) = (qi + RING[r].0, qj + RING[r].1);
                if ri < 0 || rj < 0 || ri >= n as i64 || rj >= n as i64 {
                    continue;
                }
                let dr = value[ri as usize * n + rj as usize];
                if dr.is_finite() {
                    best = best.min(triangle_update(dp, dr, u, edge_len[r], g));
                }
            }
            if best < value[q] * (1.0 - REOPEN_TOLERANCE) {
                value[q] = best;
                heap.push(Entry(best, q as u32));
            }
        }
    }
    Ok(())
}

/// Half-width (in nodes) of the box around a feature curve where distances are
/// initialized directly; a wide band removes most of the error a point source causes.
const SEED_RADIUS: i64 = 6;

/// Seeds `value` near a polyline (domain coordinates; one point is a point feature):
/// every updatable node within 6 nodes of the curve gets its distance to the curve in
/// its own metric, `min_t ‖ξ − a − t(b − a)‖_{g(ξ)}`, if that is smaller than its value.
/// Points must be finite and lie in `[−1, 2]²`; all three grids must have the same size.
pub fn seed_polyline(
    metric: &Grid<[f64; 3]>,
    updatable: &Grid<bool>,
    points: &[[f64; 2]],
    closed: bool,
    value: &mut Grid<f64>,
) -> Result<(), GridError> {
    metric.check_same_size(updatable, "the updatable mask")?;
    metric.check_same_size(value, "the distance grid")?;
    if let Some((index, &point)) = points
        .iter()
        .enumerate()
        .find(|(_, p)| !p.iter().all(|c| (-1.0..=2.0).contains(c)))
    {
        return Err(GridError::BadPoint { index, point });
    }
    let n = metric.size();
    let (metric, updatable, value) = (
        metric.as_slice(),
        updatable.as_slice(),
        value.as_mut_slice(),
    );
    let s = (n - 1) as f64;
    let count = if closed && points.len() > 2 {
        points.len()
    } else {
        points.len().saturating_sub(1).max(1)
    };
    for k in 0..count.min(points.len()) {
        let a = points[k];
        let b = points[(k + 1) % points.len()];
        let b = if points.len() == 1 { a } else { b };
        let len_nodes = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt() * s;
        let steps = (2.0 * len_nodes).ceil().max(1.0) as usize;
        for t in 0..=steps {
            let f = t as f64 / steps as f64;
            let p = [
                (a[0] + f * (b[0] - a[0])) * s,
                (a[1] + f * (b[1] - a[1])) * s,
            ];
            let (x0, y0) = (p[0].floor() as i64, p[1].floor() as i64);
            for y in y0 - SEED_RADIUS + 1..=y0 + SEED_RADIUS {
                for x in x0 - SEED_RADIUS + 1..=x0 + SEED_RADIUS {
                    if x < 0 || y < 0 || x >= n as i64 || y >= n as i64 {
                        continue;
                    }
                    let q = y as usize * n + x as usize;
                    if !updatable[q] {
                        continue;
                    }
                    let xi = [x as f64 / s, y as f64 / s];
                    let d = metric_point_segment_distance(metric[q], xi, a, b);
                    if d < value[q] {
                        value[q] = d;
                    }
                }
            }
        }
    }
    Ok(())
}

/// Seeds `value` on both sides of the boundary of a node region: for every grid edge
/// `(p, q)` between updatable nodes with `in_region[p] ≠ in_region[q]`, the boundary is
/// put at the edge midpoint, so each end gets half the edge's length in its metric (if
/// that is smaller than its value). All four grids must have the same size.
pub fn seed_region_boundary(
    metric: &Grid<[f64; 3]>,
    updatable: &Grid<bool>,
    in_region: &Grid<bool>,
    value: &mut Grid<f64>,
) -> Result<(), GridError> {
    metric.check_same_size(updatable, "the updatable mask")?;
    metric.check_same_size(in_region, "the region mask")?;
    metric.check_same_size(value, "the distance grid")?;
    let n = metric.size();
    let (metric, updatable, in_region, value) = (
        metric.as_slice(),
        updatable.as_slice(),
        in_region.as_slice(),
        value.as_mut_slice(),
    );
    let h = 1.0 / (n - 1) as f64;
    for i in 0..n {
        for j in 0..n {
            let p = i * n + j;
            for (q, w) in [(p + 1, [h, 0.0]), (p + n, [0.0, h])] {
                let ok = if w[0] > 0.0 { j + 1 < n } else { i + 1 < n };
                if !ok || !updatable[p] || !updatable[q] || in_region[p] == in_region[q] {
                    continue;
                }
                value[p] = value[p].min(0.5 * metric_norm(metric[p], w));
                value[q] = value[q].min(0.5 * metric_norm(metric[q], w));
            }
        }
    }
    Ok(())
}

/// `min_t ‖x − a − t(b − a)‖_g` over `t ∈ [0, 1]`.
pub(crate) fn metric_point_segment_distance(
    g: [f64; 3],
    x: [f64; 2],
    a: [f64; 2],
    b: [f64; 2],
) -> f64 {
    let e = [b[0] - a[0], b[1] - a[1]];
    let p = [x[0] - a[0], x[1] - a[1]];
    let ee = inner(g, e, e);
    let t = if ee > 0.0 {
        (inner(g, p, e) / ee).clamp(0.0, 1.0)
    } else {
        0.0
    };
    metric_norm(g, [p[0] - t * e[0], p[1] - t * e[1]])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constant_metric_point_error(n: usize, g: [f64; 3]) -> f64 {
        let metric = Grid::new(n, g).unwrap();
        let all = Grid::new(n, true).unwrap();
        let mut d = Grid::new(n, f64::INFINITY).unwrap();
        let c = [0.43, 0.51];
        seed_polyline(&metric, &all, &[c], false, &mut d).unwrap();
        solve_eikonal(&metric, &all, &mut d).unwrap();
        let mut max_rel = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let p = d.node(i, j);
                let exact = metric_norm(g, [p[0] - c[0], p[1] - c[1]]);
                if exact > 0.3 {
                    max_rel = max_rel.max((d[(i, j)] - exact).abs() / exact);
                }
            }
        }
        max_rel
    }

    #[test]
    fn constant_anisotropic_metric_gives_metric_distance() {
        // g with eigenvalues 9 and 1 along a 30° frame: anisotropy ratio 3.
        let (s, c) = 30f64.to_radians().sin_cos();
        let (l1, l2) = (9.0, 1.0);
        let g = [
            l1 * c * c + l2 * s * s,
            (l1 - l2) * c * s,
            l1 * s * s + l2 * c * c,
        ];
        let e65 = constant_metric_point_error(65, g);
        let e257 = constant_metric_point_error(257, g);
        assert!(e257 < 0.7 * e65 && e257 < 0.03, "{e65} {e257}");
    }

    #[test]
    fn identity_metric_line_distance_is_exact() {
        // Distance to a straight line is linear: the scheme reproduces it up to rounding.
        let n = 65;
        let metric = Grid::new(n, [1.0, 0.0, 1.0]).unwrap();
        let all = Grid::new(n, true).unwrap();
        let mut d = Grid::new(n, f64::INFINITY).unwrap();
        let (a, b) = ([-0.5, 0.075], [1.5, 0.575]);
        seed_polyline(&metric, &all, &[a, b], false, &mut d).unwrap();
        solve_eikonal(&metric, &all, &mut d).unwrap();
        let (a, nrm) = ([0.0, 0.2], (0.25f64 * 0.25 + 1.0).sqrt());
        for i in 0..n {
            for j in 0..n {
                let p = d.node(i, j);
                let exact = ((p[1] - a[1]) * 1.0 - (p[0] - a[0]) * 0.25).abs() / nrm;
                // Away from the grid's sides, whose characteristics start outside the grid.
                if !(0.3..=0.7).contains(&p[0]) {
                    continue;
                }
                assert!(
                    (d[(i, j)] - exact).abs() < 1e-9,
                    "{i},{j}: {} vs {exact}",
                    d[(i, j)]
                );
            }
        }
    }

    #[test]
    fn region_boundary_seeds_sit_at_edge_midpoints() {
        let n = 17;
        let metric = Grid::new(n, [4.0, 0.0, 1.0]).unwrap();
        let all = Grid::new(n, true).unwrap();
        let region = Grid::from_fn(n, |_, j| j < 8).unwrap(); // columns 0..7
        let mut d = Grid::new(n, f64::INFINITY).unwrap();
        seed_region_boundary(&metric, &all, &region, &mut d).unwrap();
        solve_eikonal(&metric, &all, &mut d).unwrap();
        // Boundary at ξ_x = 7.5 h; metric stretches x by 2.
        let h = 1.0 / 16.0;
        for i in 0..n {
            for j in 0..n {
                let exact = 2.0 * (j as f64 - 7.5).abs() * h;
                assert!((d[(i, j)] - exact).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn unreachable_and_frozen_nodes() {
        let n = 9;
        let metric = Grid::new(n, [1.0, 0.0, 1.0]).unwrap();
        // A wall of non-updatable nodes in column 4 cuts the grid in two.
        let upd = Grid::from_fn(n, |_, j| j != 4).unwrap();
        let mut d = Grid::new(n, f64::INFINITY).unwrap();
        d[(0, 0)] = 0.0;
        solve_eikonal(&metric, &upd, &mut d).unwrap();
        for i in 0..n {
            for j in 0..n {
                assert_eq!(j < 4, d[(i, j)].is_finite(), "{i},{j}");
            }
        }
    }

    #[test]
    fn mismatched_grids_and_bad_points_are_errors() {
        let metric = Grid::new(9, [1.0, 0.0, 1.0]).unwrap();
        let all = Grid::new(9, true).unwrap();
        let mut small = Grid::new(5, f64::INFINITY).unwrap();
        let err = solve_eikonal(&metric, &all, &mut small).unwrap_err();
        assert_eq!(
            err,
            GridError::SizeMismatch {
                what: "the distance grid",
                got: 5,
                want: 9
            }
        );
        assert!(
            seed_polyline(
                &metric,
                &Grid::new(17, true).unwrap(),
                &[[0.5; 2]],
                false,
                &mut small
            )
            .is_err()
        );
        let mut d = Grid::new(9, f64::INFINITY).unwrap();
        for bad in [[f64::NAN, 0.5], [0.5, 1e300], [-1.5, 0.0]] {
            let err = seed_polyline(&metric, &all, &[[0.5; 2], bad], false, &mut d).unwrap_err();
            assert!(matches!(err, GridError::BadPoint { index: 1, .. }), "{err}");
        }
        assert!(d.iter().all(|v| v.is_infinite()));
    }
}
