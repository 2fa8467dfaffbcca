//! Global overlap of a UV layout: does the UV boundary cross itself, and how much
//! UV area is covered more than once.
//!
//! A flip-free map can still be non-injective globally: its boundary may wrap around
//! and land on top of the layout. Local measures (flips, singular values) cannot see
//! that; these two can.
//!
//! * **Boundary** segments are the UV edges of triangle sides that have no partner
//!   face with the same two vertices *and* the same two UVs (mesh boundary and, for
//!   per-corner UVs, chart seams). Two such segments that share no endpoint and touch
//!   or cross are a *boundary crossing*.
//! * **Overlap area** `Σ_{i<j} |T_i ∩ T_j|` over pairs of UV triangles (exact convex
//!   clipping). It equals the area covered twice when at most two layers overlap
//!   anywhere (a triple layer counts three times). Adjacent triangles of a valid map
//!   meet only along edges and contribute nothing.
//!
//! Both use a uniform grid over triangle bounding boxes, so the cost is near linear
//! in the number of triangles for ordinary layouts.

use serde::Serialize;

/// Global overlap of a UV layout (see the module docs).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BoundaryOverlap {
    /// Whether any two UV boundary segments without a common endpoint touch or cross.
    pub self_intersecting: bool,
    /// Number of such boundary segment pairs.
    pub boundary_crossings: usize,
    /// `Σ_{i<j} |T_i ∩ T_j|` in the units of the UVs given (the report passes UVs
    /// scaled to the 3D surface area).
    pub overlap_area: f64,
    /// `overlap_area / Σ |T_i|`.
    pub overlap_fraction: f64,
    /// `false` when a heavily tangled layout exhausted the work budget
    /// ([`PAIR_BUDGET_PER_ITEM`] candidate pairs per element): the crossing count and
    /// the overlap area are then lower bounds.
    pub complete: bool,
}

/// Candidate pairs examined per triangle (or segment), plus a constant 10⁶, before
/// the overlap search gives up: a layout tangled enough to exceed it (thousands of
/// flipped, stretched triangles) would otherwise cost quadratic time.
pub const PAIR_BUDGET_PER_ITEM: usize = 200;

/// Computes [`BoundaryOverlap`] for triangles with per-corner UVs.
pub fn boundary_overlap(triangles: &[[u32; 3]], corner_uvs: &[[[f64; 2]; 3]]) -> BoundaryOverlap {
    let segments = boundary_segments(triangles, corner_uvs);
    let (crossings, complete_c) = count_segment_crossings(&segments);
    let (overlap, complete_o) = overlap_area(corner_uvs);
    let total: f64 = corner_uvs
        .iter()
        .map(|t| super::jacobian::signed_uv_area(*t).abs())
        .sum();
    BoundaryOverlap {
        self_intersecting: crossings > 0,
        boundary_crossings: crossings,
        overlap_area: overlap,
        overlap_fraction: if total > 0.0 { overlap / total } else { 0.0 },
        complete: complete_c && complete_o,
    }
}

/// UV segments of triangle sides without a partner face carrying the same two vertex
/// indices and the same two UVs.
pub fn boundary_segments(
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
) -> Vec<[[f64; 2]; 2]> {
    let sides = super::charts::sorted_uv_sides(triangles, corner_uvs);
    let mut out = Vec::new();
    let mut i = 0;
    while i < sides.len() {
        let mut j = i + 1;
        while j < sides.len() && sides[j].same_side(&sides[i]) {
            j += 1;
        }
        if j - i == 1 {
            let (t, k) = (sides[i].face as usize, sides[i].corner as usize);
            let uv = corner_uvs[t];
            out.push([uv[k], uv[(k + 1) % 3]]);
        }
        i = j;
    }
    out
}

/// Number of pairs of boundary edges of the map `uv` without a common endpoint that
/// cross or touch (`boundary`: one loop of vertex ids in order).
pub fn boundary_crossings(uv: &[[f64; 2]], boundary: &[u32]) -> usize {
    let n = boundary.len();
    let segments: Vec<[[f64; 2]; 2]> = (0..n)
        .map(|i| [uv[boundary[i] as usize], uv[boundary[(i + 1) % n] as usize]])
        .collect();
    count_segment_crossings(&segments).0
}

/// Number of segment pairs that share no endpoint and touch or cross, and whether the
/// search finished within its budget.
pub fn count_segment_crossings(segments: &[[[f64; 2]; 2]]) -> (usize, bool) {
    let boxes: Vec<[f64; 4]> = segments.iter().map(|s| bbox(s)).collect();
    let mut count = 0;
    let complete = for_each_overlapping_pair(&boxes, |i, j| {
        let (a, b) = (segments[i], segments[j]);
        let shares = a.iter().any(|p| b.iter().any(|q| p == q));
        if !shares && segments_intersect(a[0], a[1], b[0], b[1]) {
            count += 1;
        }
    });
    (count, complete)
}

/// `Σ_{i<j} |T_i ∩ T_j|` over UV triangles (see the module docs). Intersections below
/// `1e-9` of the smaller triangle's area (shared edges, rounding) are ignored. The flag
/// tells whether the search finished within its budget.
pub fn overlap_area(corner_uvs: &[[[f64; 2]; 3]]) -> (f64, bool) {
    let boxes: Vec<[f64; 4]> = corner_uvs.iter().map(|t| bbox(t)).collect();
    let mut total = 0.0;
    let complete = for_each_overlapping_pair(&boxes, |i, j| {
        let (a, b) = (corner_uvs[i], corner_uvs[j]);
        let (aa, ab) = (
            super::jacobian::signed_uv_area(a).abs(),
            super::jacobian::signed_uv_area(b).abs(),
        );
        if aa <= 0.0 || ab <= 0.0 {
            return;
        }
        let area = triangle_intersection_area(a, b);
        if area > 1e-9 * aa.min(ab) {
            total += area;
        }
    });
    (total, complete)
}

/// Area of the intersection of two triangles (any orientation) by Sutherland–Hodgman
/// clipping of `a` against the three edges of `b`. Allocation-free.
pub fn triangle_intersection_area(a: [[f64; 2]; 3], b: [[f64; 2]; 3]) -> f64 {
    let b = if super::jacobian::signed_uv_area(b) < 0.0 {
        [b[0], b[2], b[1]]
    } else {
        b
    };
    let mut poly = [[0.0f64; 2]; 9];
    let mut n = 3;
    poly[..3].copy_from_slice(&a);
    let mut next = [[0.0f64; 2]; 9];
    for k in 0..3 {
        let (p, q) = (b[k], b[(k + 1) % 3]);
        let side = |x: [f64; 2]| (q[0] - p[0]) * (x[1] - p[1]) - (q[1] - p[1]) * (x[0] - p[0]);
        let mut m = 0;
        for i in 0..n {
            let (cur, prev) = (poly[i], poly[(i + n - 1) % n]);
            let (sc, sp) = (side(cur), side(prev));
            if sc >= 0.0 {
                if sp < 0.0 && m < 9 {
                    next[m] = lerp(prev, cur, sp / (sp - sc));
                    m += 1;
                }
                if m < 9 {
                    next[m] = cur;
                    m += 1;
                }
            } else if sp >= 0.0 && m < 9 {
                next[m] = lerp(prev, cur, sp / (sp - sc));
                m += 1;
            }
        }
        n = m;
        poly = next;
        if n < 3 {
            return 0.0;
        }
    }
    let mut twice = 0.0;
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        twice += p[0] * q[1] - q[0] * p[1];
    }
    0.5 * twice.abs()
}

fn lerp(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
}

fn bbox(pts: &[[f64; 2]]) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in pts {
        b[0] = b[0].min(p[0]);
        b[1] = b[1].min(p[1]);
        b[2] = b[2].max(p[0]);
        b[3] = b[3].max(p[1]);
    }
    b
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn on_segment(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

/// Whether closed segments `ab` and `cd` have a point in common.
pub fn segments_intersect(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on_segment(c, d, a))
        || (d2 == 0.0 && on_segment(c, d, b))
        || (d3 == 0.0 && on_segment(a, b, c))
        || (d4 == 0.0 && on_segment(a, b, d))
}

/// Calls `f(i, j)` once for every pair `i < j` of boxes `[xmin, ymin, xmax, ymax]` that
/// overlap (closed), using a uniform grid. Non-finite boxes are skipped. Returns
/// `false` if it stopped early because the candidate-pair budget ran out.
fn for_each_overlapping_pair(boxes: &[[f64; 4]], mut f: impl FnMut(usize, usize)) -> bool {
    let valid: Vec<usize> = (0..boxes.len())
        .filter(|&i| boxes[i].iter().all(|x| x.is_finite()))
        .collect();
    if valid.len() < 2 {
        return true;
    }
    let mut budget = PAIR_BUDGET_PER_ITEM * valid.len() + 1_000_000;
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    let mut mean_extent = 0.0;
    for &i in &valid {
        let b = boxes[i];
        lo = [lo[0].min(b[0]), lo[1].min(b[1])];
        hi = [hi[0].max(b[2]), hi[1].max(b[3])];
        mean_extent += (b[2] - b[0]).max(b[3] - b[1]);
    }
    mean_extent /= valid.len() as f64;
    let (w, h) = ((hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300));
    // Cells about the size of an average box, at most ~4 cells per item.
    let max_cells = (4 * valid.len()).max(16) as f64;
    let mut cell = mean_extent
        .max((w * h / max_cells).sqrt())
        .max(w.max(h) / 4096.0);
    if cell <= 0.0 || !cell.is_finite() {
        cell = w.max(h).max(1e-300);
    }
    let nx = ((w / cell).floor() as usize + 1).min(4097);
    let ny = ((h / cell).floor() as usize + 1).min(4097);
    let cell_of = |x: f64, y: f64| -> (usize, usize) {
        let cx = (((x - lo[0]) / cell).floor().max(0.0) as usize).min(nx - 1);
        let cy = (((y - lo[1]) / cell).floor().max(0.0) as usize).min(ny - 1);
        (cx, cy)
    };
    // Counting sort of (cell, item) into CSR.
    let mut start = vec![0u32; nx * ny + 1];
    for &i in &valid {
        let b = boxes[i];
        let (x0, y0) = cell_of(b[0], b[1]);
        let (x1, y1) = cell_of(b[2], b[3]);
        for cy in y0..=y1 {
            for cx in x0..=x1 {
                start[cy * nx + cx + 1] += 1;
            }
        }
    }
    for c in 0..nx * ny {
        start[c + 1] += start[c];
    }
    let mut fill = start.clone();
    let mut items = vec![0u32; start[nx * ny] as usize];
    for &i in &valid {
        let b = boxes[i];
        let (x0, y0) = cell_of(b[0], b[1]);
        let (x1, y1) = cell_of(b[2], b[3]);
        for cy in y0..=y1 {
            for cx in x0..=x1 {
                let c = cy * nx + cx;
                items[fill[c] as usize] = i as u32;
                fill[c] += 1;
            }
        }
    }
    for cy in 0..ny {
        for cx in 0..nx {
            let c = cy * nx + cx;
            let list = &items[start[c] as usize..start[c + 1] as usize];
            for (k, &i) in list.iter().enumerate() {
                for &j in &list[k + 1..] {
                    if budget == 0 {
                        return false;
                    }
                    budget -= 1;
                    let (a, b) = (boxes[i as usize], boxes[j as usize]);
                    if a[0] > b[2] || b[0] > a[2] || a[1] > b[3] || b[1] > a[3] {
                        continue;
                    }
                    // Report the pair only in the cell holding the low corner of the overlap.
                    if cell_of(a[0].max(b[0]), a[1].max(b[1])) != (cx, cy) {
                        continue;
                    }
                    let (i, j) = (i.min(j) as usize, i.max(j) as usize);
                    f(i, j);
                }
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan of `n` triangles around the origin whose outer angles sum to `turns` full turns.
    fn spiral_fan(n: usize, turns: f64) -> (Vec<[u32; 3]>, Vec<[[f64; 2]; 3]>) {
        let mut tris = Vec::new();
        let mut uvs = Vec::new();
        let rim = |k: usize| {
            let th = turns * std::f64::consts::TAU * k as f64 / n as f64;
            [th.cos(), th.sin()]
        };
        for k in 0..n {
            tris.push([0, k as u32 + 1, k as u32 + 2]);
            uvs.push([[0.0, 0.0], rim(k), rim(k + 1)]);
        }
        (tris, uvs)
    }

    #[test]
    fn intersection_area_of_known_triangles() {
        let a = [[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]];
        // Identical: full area; reversed orientation of b: same.
        assert!((triangle_intersection_area(a, a) - 2.0).abs() < 1e-14);
        assert!((triangle_intersection_area(a, [a[0], a[2], a[1]]) - 2.0).abs() < 1e-14);
        // The unit square's lower-left half inside a: area 0.5.
        let b = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert!((triangle_intersection_area(a, b) - 0.5).abs() < 1e-14);
        // Disjoint and edge-sharing: zero.
        assert_eq!(
            triangle_intersection_area(a, [[5.0, 5.0], [6.0, 5.0], [5.0, 6.0]]),
            0.0
        );
        let c = [[2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        assert!(triangle_intersection_area(a, c) < 1e-14);
        // Star of David: two triangles of side 3 → overlap is a hexagon of 2/3 the area.
        let s = 3.0f64;
        let h = s * 3f64.sqrt() / 2.0;
        let up = [[0.0, 0.0], [s, 0.0], [s / 2.0, h]];
        let down = [
            [0.0, 2.0 * h / 3.0],
            [s / 2.0, -h / 3.0],
            [s, 2.0 * h / 3.0],
        ];
        let tri_area = 0.5 * s * h;
        assert!((triangle_intersection_area(up, down) - tri_area * 2.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn a_flat_fan_has_no_overlap_and_no_crossing() {
        let (tris, uvs) = spiral_fan(24, 0.9);
        let o = boundary_overlap(&tris, &uvs);
        assert!(!o.self_intersecting);
        assert!(o.overlap_area < 1e-12);
        assert!(o.complete);
    }

    #[test]
    fn a_hopelessly_tangled_layout_stops_within_budget() {
        // Every triangle is a long sliver across the same square: all pairs overlap.
        let n = 3000;
        let uvs: Vec<[[f64; 2]; 3]> = (0..n)
            .map(|k| {
                let t = k as f64 / n as f64;
                [[0.0, t], [1.0, 1.0 - t], [0.5, 0.5 + 0.01]]
            })
            .collect();
        let tris: Vec<[u32; 3]> = (0..n as u32)
            .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
            .collect();
        let o = boundary_overlap(&tris, &uvs);
        assert!(!o.complete);
        assert!(o.overlap_area > 0.0 && o.self_intersecting);
    }

    #[test]
    fn a_fan_wound_past_a_full_turn_overlaps_by_the_extra_sector() {
        // 1.25 turns: the last quarter lies on top of the first, every triangle flip-free.
        let n = 40;
        let (tris, uvs) = spiral_fan(n, 1.25);
        let o = boundary_overlap(&tris, &uvs);
        // Each triangle has area sin(θ)/2 with θ = 2.5π/n; a quarter of them are doubled.
        let th = 1.25 * std::f64::consts::TAU / n as f64;
        let want = (n / 5) as f64 * 0.5 * th.sin();
        assert!(
            (o.overlap_area - want).abs() < 1e-9 * want,
            "{} vs {want}",
            o.overlap_area
        );
    }

    #[test]
    fn a_fan_wound_past_a_full_turn_has_a_self_crossing_boundary() {
        // 1.3 turns: the last radial edge ends on the rim between two rim vertices of
        // the first turn, crossing the chord there.
        let (tris, uvs) = spiral_fan(37, 1.3);
        let o = boundary_overlap(&tris, &uvs);
        assert!(o.self_intersecting && o.boundary_crossings >= 1);
        assert!(o.overlap_fraction > 0.1);
    }

    #[test]
    fn per_corner_seams_are_boundary() {
        // Two triangles sharing vertices 1,2 but with different UVs there (a seam).
        let tris = [[0, 1, 2], [2, 1, 3]];
        let uvs = [
            [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            [[5.0, 1.0], [5.0, 0.0], [6.0, 1.0]],
        ];
        assert_eq!(boundary_segments(&tris, &uvs).len(), 6);
        let joined = [uvs[0], [[0.0, 1.0], [1.0, 0.0], [1.0, 1.0]]];
        assert_eq!(boundary_segments(&tris, &joined).len(), 4);
    }

    #[test]
    fn crossing_segments() {
        assert!(segments_intersect(
            [0.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [1.0, 0.0]
        ));
        assert!(!segments_intersect(
            [0.0, 0.0],
            [1.0, 0.0],
            [0.0, 1.0],
            [1.0, 1.0]
        ));
        assert!(segments_intersect(
            [0.0, 0.0],
            [2.0, 0.0],
            [1.0, 0.0],
            [3.0, 0.0]
        ));
        assert!(segments_intersect(
            [0.0, 0.0],
            [2.0, 0.0],
            [1.0, 0.0],
            [1.0, 5.0]
        ));
    }
}
