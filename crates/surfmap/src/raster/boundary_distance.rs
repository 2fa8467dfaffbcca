//! Signed distance to the domain boundary `∂ω_A` (for `χ^ε` of thesis (2.14), §3.2.3),
//! measured in domain units of ω (Euclidean in the parameter plane): negative inside
//! the flattened surface, positive outside, so `dist(ξ, ω_A) = max(d, 0)`.
//!
//! The boundary is the polygon of the flattening's boundary edges. Every node learns the
//! index of its nearest boundary segment: nodes next to a segment are seeded exactly, then
//! two raster sweeps (forward and backward, 8-neighbourhood) pass segment indices on, and
//! each candidate is evaluated exactly (closest-feature propagation, as in vector distance
//! transforms; exact except in rare configurations where the error is a small fraction
//! of a node spacing). Cost `O(N² + boundary length / spacing)`.

use super::rasterize::Rasterization;
use crate::grid::Grid;

const NONE: u32 = u32::MAX;

/// Signed distance (domain units) from every grid node to the polygon formed by
/// `segments` (endpoints in domain coordinates); the sign comes from `raster`'s mask.
pub fn signed_boundary_distance(raster: &Rasterization, segments: &[[[f64; 2]; 2]]) -> Grid<f64> {
    let n = raster.size();
    let s = (n - 1) as f64;
    let segs: Vec<[[f64; 2]; 2]> = segments
        .iter()
        .map(|sg| sg.map(|p| [p[0] * s, p[1] * s]))
        .collect();
    let mut best = vec![NONE; n * n];
    let mut dist = vec![f64::INFINITY; n * n];
    let dist_to = |k: usize, sid: u32| -> f64 {
        let (i, j) = (k / n, k % n);
        point_segment_distance([j as f64, i as f64], segs[sid as usize])
    };
    // Seed nodes around every segment.
    for (sid, sg) in segs.iter().enumerate() {
        let [a, b] = *sg;
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let steps = (2.0 * len).ceil().max(1.0) as usize;
        for t in 0..=steps {
            let f = t as f64 / steps as f64;
            let p = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
            let (x0, y0) = (p[0].floor() as i64, p[1].floor() as i64);
            for y in y0 - 1..=y0 + 2 {
                for x in x0 - 1..=x0 + 2 {
                    if x < 0 || y < 0 || x >= n as i64 || y >= n as i64 {
                        continue;
                    }
                    let k = y as usize * n + x as usize;
                    let d = point_segment_distance([x as f64, y as f64], *sg);
                    if d < dist[k] {
                        dist[k] = d;
                        best[k] = sid as u32;
                    }
                }
            }
        }
    }
    let relax = |k: usize, q: usize, dist: &mut [f64], best: &mut [u32]| {
        let sid = best[q];
        if sid != NONE && sid != best[k] {
            let d = dist_to(k, sid);
            if d < dist[k] {
                dist[k] = d;
                best[k] = sid;
            }
        }
    };
    for _round in 0..2 {
        for i in 0..n {
            for j in 0..n {
                let k = i * n + j;
                if i > 0 {
                    relax(k, k - n, &mut dist, &mut best);
                    if j > 0 {
                        relax(k, k - n - 1, &mut dist, &mut best);
                    }
                    if j + 1 < n {
                        relax(k, k - n + 1, &mut dist, &mut best);
                    }
                }
                if j > 0 {
                    relax(k, k - 1, &mut dist, &mut best);
                }
            }
            for j in (0..n.saturating_sub(1)).rev() {
                relax(i * n + j, i * n + j + 1, &mut dist, &mut best);
            }
        }
        for i in (0..n).rev() {
            for j in (0..n).rev() {
                let k = i * n + j;
                if i + 1 < n {
                    relax(k, k + n, &mut dist, &mut best);
                    if j > 0 {
                        relax(k, k + n - 1, &mut dist, &mut best);
                    }
                    if j + 1 < n {
                        relax(k, k + n + 1, &mut dist, &mut best);
                    }
                }
                if j + 1 < n {
                    relax(k, k + 1, &mut dist, &mut best);
                }
            }
            for j in 1..n {
                relax(i * n + j, i * n + j - 1, &mut dist, &mut best);
            }
        }
    }
    let signed = dist
        .iter()
        .enumerate()
        .map(|(k, &d)| {
            let d = d / s;
            if raster.is_inside(k) { -d } else { d }
        })
        .collect();
    Grid::from_parts(n, signed)
}

/// Euclidean distance from `p` to the segment `[a, b]`.
#[inline]
pub fn point_segment_distance(p: [f64; 2], [a, b]: [[f64; 2]; 2]) -> f64 {
    let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
    let (px, py) = (p[0] - a[0], p[1] - a[1]);
    let len2 = ex * ex + ey * ey;
    let t = if len2 > 0.0 {
        ((px * ex + py * ey) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((px - t * ex).powi(2) + (py - t * ey).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::boundary::boundary_edges;

    #[test]
    fn matches_brute_force_on_a_star_polygon() {
        // A non-convex star fan around (0.5, 0.5).
        let m = 14;
        let mut xi = vec![[0.47, 0.52]];
        for i in 0..m {
            let a = std::f64::consts::TAU * i as f64 / m as f64;
            let r = if i % 2 == 0 { 0.4 } else { 0.17 };
            xi.push([0.5 + r * a.cos(), 0.5 + r * a.sin()]);
        }
        let tris: Vec<[u32; 3]> = (0..m as u32)
            .map(|i| [0, 1 + i, 1 + (i + 1) % m as u32])
            .collect();
        let n = 129;
        let raster = Rasterization::new(&xi, &tris, n).unwrap();
        let segs: Vec<[[f64; 2]; 2]> = boundary_edges(&tris)
            .iter()
            .map(|e| [xi[e[0] as usize], xi[e[1] as usize]])
            .collect();
        let d = signed_boundary_distance(&raster, &segs);
        let mut max_err = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let p = d.node(i, j);
                let exact = segs
                    .iter()
                    .map(|&s| point_segment_distance(p, s))
                    .fold(f64::INFINITY, f64::min);
                max_err = max_err.max((d[(i, j)].abs() - exact).abs());
                if exact > 1e-9 {
                    assert_eq!(d[(i, j)] < 0.0, raster.is_inside(i * n + j));
                }
            }
        }
        assert!(max_err < 1e-3 / (n - 1) as f64, "max error {max_err}");
    }
}
