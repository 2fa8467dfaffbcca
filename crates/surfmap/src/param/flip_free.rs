//! The largest flip-free step along a search direction (thesis §3.1.3: the line search
//! must stay in the admissible set `det J > 0`).
//!
//! A step that makes any triangle's `det J ≤ 0` must be rejected: the energy can
//! *decrease* through a flip, because the barrier `1/d` only blows up at `d = 0`. With
//! UV corners `u_k + s·p_k`, the edge matrix is `Ds(s) = A + s·B`
//! (`A = [u2 − u1, u3 − u1]`, `B = [p2 − p1, p3 − p1]`), and since
//! `det J = det Ds / det Dm` with `det Dm > 0`,
//!
//! ```text
//! det Ds(s) = det A + s·(A00 B11 + A11 B00 − A01 B10 − A10 B01) + s²·det B
//! ```
//!
//! is a quadratic in `s`; its first positive root is the triangle's flip-free limit.
//! The line search should start strictly below the mesh minimum (e.g. `0.8·t`): at
//! `t` itself a triangle is degenerate.

use rayon::prelude::*;

/// Largest `t > 0` such that the UV triangle `uv + s·dir` keeps `det > 0`
/// (counter-clockwise orientation) for all `s ∈ [0, t)`; `f64::INFINITY` if it never
/// degenerates along the ray.
///
/// Returns `0.0` when the triangle is not positively oriented at `s = 0`
/// (`det ≤ 0`: no step is safe) or any input is not finite.
///
/// Roots of `c + b·s + a·s²` (`c = det A > 0`) are found without cancellation:
/// `q = −(b + sign(b)·√(b² − 4ac))/2`, roots `q/a` and `c/q`; `a = 0` is the linear
/// case `s = −c/b` (a root only when `b < 0`); a negative discriminant means no real
/// root. A double root (the triangle touches `det = 0` and recovers) whose
/// discriminant rounds below zero is reported as no root; the energy at such a point
/// is still `+∞` in `element::energy`.
#[inline]
pub fn flip_free_step(uv: [[f64; 2]; 3], dir: [[f64; 2]; 3]) -> f64 {
    match det_quadratic(uv, dir) {
        Some((a, b, c)) => smallest_positive_root(a, b, c),
        None => 0.0,
    }
}

/// `(a, b, c)` of `det Ds(s) = c + b·s + a·s²` (module docs), or `None` unless `c > 0` and
/// all three are finite.
#[inline]
fn det_quadratic(uv: [[f64; 2]; 3], dir: [[f64; 2]; 3]) -> Option<(f64, f64, f64)> {
    let a00 = uv[1][0] - uv[0][0];
    let a01 = uv[2][0] - uv[0][0];
    let a10 = uv[1][1] - uv[0][1];
    let a11 = uv[2][1] - uv[0][1];
    let b00 = dir[1][0] - dir[0][0];
    let b01 = dir[2][0] - dir[0][0];
    let b10 = dir[1][1] - dir[0][1];
    let b11 = dir[2][1] - dir[0][1];
    let c = a00 * a11 - a01 * a10;
    let b = a00 * b11 + a11 * b00 - a01 * b10 - a10 * b01;
    let a = b00 * b11 - b01 * b10;
    (c > 0.0 && c.is_finite() && b.is_finite() && a.is_finite()).then_some((a, b, c))
}

/// [`flip_free_step`] where it is below `limit`; otherwise some value `≥ limit`, found
/// without the root when the quadratic provably stays positive on `[0, limit]`:
/// `c + min(b, 0)·limit + min(a, 0)·limit² > 0` bounds `det` from below there (with a
/// relative margin of 10⁻⁹ so that a root within rounding of `limit` is still computed).
/// For the minimum over many triangles, with `limit` the minimum so far.
#[inline]
pub fn flip_free_step_below(uv: [[f64; 2]; 3], dir: [[f64; 2]; 3], limit: f64) -> f64 {
    let Some((a, b, c)) = det_quadratic(uv, dir) else {
        return 0.0;
    };
    if limit.is_finite() && c + b.min(0.0) * limit + a.min(0.0) * limit * limit > 1e-9 * c {
        return limit;
    }
    smallest_positive_root(a, b, c)
}

/// First positive root of `c + b·s + a·s²` with `c > 0` (finite inputs), or
/// `f64::INFINITY`.
#[inline]
fn smallest_positive_root(a: f64, b: f64, c: f64) -> f64 {
    if a == 0.0 {
        return if b < 0.0 { c / -b } else { f64::INFINITY };
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return f64::INFINITY;
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    // q ≠ 0: disc = 0 with b = 0 would need a·c = 0.
    let mut best = f64::INFINITY;
    for root in [q / a, c / q] {
        if root > 0.0 && root < best {
            best = root;
        }
    }
    best
}

/// Minimum of [`flip_free_step`] over all triangles of a mesh with per-vertex UVs
/// `uvs` and per-vertex direction `dir`: the largest `t` such that no triangle
/// degenerates or flips for any step `s ∈ [0, t)`.
///
/// Returns `0.0` (no safe step) if `dir.len() != uvs.len()`, a triangle refers to a
/// vertex out of range, or any triangle is already non-positive; `f64::INFINITY` for
/// a direction that can never flip (e.g. a rigid translation, or no triangles).
/// Parallel (rayon) above a few thousand triangles; no allocation.
pub fn max_flip_free_step(uvs: &[[f64; 2]], triangles: &[[u32; 3]], dir: &[[f64; 2]]) -> f64 {
    if dir.len() != uvs.len() {
        return 0.0;
    }
    let step_of = |&[i, j, k]: &[u32; 3]| -> f64 {
        let (i, j, k) = (i as usize, j as usize, k as usize);
        match (uvs.get(i), uvs.get(j), uvs.get(k)) {
            (Some(&ui), Some(&uj), Some(&uk)) => {
                flip_free_step([ui, uj, uk], [dir[i], dir[j], dir[k]])
            }
            _ => 0.0,
        }
    };
    const PARALLEL_ABOVE: usize = 16_384;
    if triangles.len() < PARALLEL_ABOVE {
        triangles.iter().map(step_of).fold(f64::INFINITY, f64::min)
    } else {
        triangles
            .par_iter()
            .with_min_len(4096)
            .map(step_of)
            .reduce(|| f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::testing::Rng;

    fn det_at(uv: [[f64; 2]; 3], dir: [[f64; 2]; 3], s: f64) -> f64 {
        let p: Vec<[f64; 2]> = (0..3)
            .map(|k| [uv[k][0] + s * dir[k][0], uv[k][1] + s * dir[k][1]])
            .collect();
        (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])
    }

    fn ccw_triangle(rng: &mut Rng) -> [[f64; 2]; 3] {
        loop {
            let t = [rng.point(1.0), rng.point(1.0), rng.point(1.0)];
            let d = det_at(t, [[0.0; 2]; 3], 0.0);
            if d > 1e-3 {
                return t;
            }
            if d < -1e-3 {
                return [t[0], t[2], t[1]];
            }
        }
    }

    /// The triangle (0,0), (1,0), (0,1) with the apex moving down by 2·s collapses
    /// exactly at s = 0.5 (det = 1 − 2s).
    #[test]
    fn constructed_collapse_at_one_half() {
        let uv = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let dir = [[0.0, 0.0], [0.0, 0.0], [0.0, -2.0]];
        assert_eq!(flip_free_step(uv, dir), 0.5);
        // Quadratic case: both edges shrink, det = (1 − s)² · ... with a = det B ≠ 0:
        // corners 2 and 3 move toward corner 1: det = (1 − s)(1 − 2s), roots 0.5 and 1.
        let dir = [[0.0, 0.0], [-1.0, 0.0], [0.0, -2.0]];
        assert!((flip_free_step(uv, dir) - 0.5).abs() < 1e-15);
        // Reverse order of the roots: det = (1 − 4s)(1 − s/2) → 0.25.
        let dir = [[0.0, 0.0], [-0.5, 0.0], [0.0, -4.0]];
        assert!((flip_free_step(uv, dir) - 0.25).abs() < 1e-15);
    }

    #[test]
    fn rigid_motions_and_growth_never_flip() {
        let uv = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        // Translation: det constant.
        assert_eq!(flip_free_step(uv, [[0.3, -0.2]; 3]), f64::INFINITY);
        // Uniform growth: det = (1 + s)² > 0 for s > 0.
        assert_eq!(flip_free_step(uv, uv), f64::INFINITY);
        // Linear growth of one edge.
        let dir = [[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]];
        assert_eq!(flip_free_step(uv, dir), f64::INFINITY);
        // Infinitesimal rotation (linearized): det = 1 + s² never vanishes.
        let rot = [[0.0, 0.0], [0.0, 1.0], [-1.0, 0.0]];
        assert_eq!(flip_free_step(uv, rot), f64::INFINITY);
    }

    #[test]
    fn non_positive_or_non_finite_start_gives_zero() {
        let uv = [[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]]; // clockwise
        assert_eq!(flip_free_step(uv, [[0.0; 2]; 3]), 0.0);
        let flat = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
        assert_eq!(flip_free_step(flat, [[0.0, 1.0]; 3]), 0.0);
        let ccw = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert_eq!(flip_free_step(ccw, [[f64::NAN, 0.0]; 3]), 0.0);
        assert_eq!(
            flip_free_step([[f64::INFINITY, 0.0]; 3], [[0.0; 2]; 3]),
            0.0
        );
    }

    /// Against brute force: det > 0 at sampled s < t, and det changes sign (or hits
    /// zero) just after t; when t = ∞, no sample on a long range is ≤ 0.
    #[test]
    fn matches_brute_force_sampling() {
        let mut rng = Rng(0x2545f4914f6cdd1d);
        let mut finite = 0;
        for _ in 0..2000 {
            let uv = ccw_triangle(&mut rng);
            let dir = [rng.point(2.0), rng.point(2.0), rng.point(2.0)];
            let t = flip_free_step(uv, dir);
            assert!(t > 0.0);
            let horizon = if t.is_finite() { t } else { 100.0 };
            let n = 2000;
            for i in 0..n {
                let s = horizon * (i as f64) / (n as f64) * (1.0 - 1e-9);
                assert!(det_at(uv, dir, s) > 0.0, "det ≤ 0 at s = {s} < t = {t}");
            }
            if t.is_finite() {
                finite += 1;
                // Root accuracy: det(t) ≈ 0 relative to the polynomial's scale, and
                // det < 0 somewhere just after t unless t is a touching double root.
                // Size of the products summed in det at s = t.
                let extent =
                    |p: [[f64; 2]; 3]| p.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
                let scale = (2.0 * extent(uv) + 2.0 * t * extent(dir)).powi(2);
                assert!(
                    det_at(uv, dir, t).abs() <= 1e-12 * scale,
                    "det(t) = {}",
                    det_at(uv, dir, t)
                );
                let after = det_at(uv, dir, t * (1.0 + 1e-6) + 1e-12);
                assert!(after <= 1e-9 * scale, "det after t = {after}");
            }
        }
        assert!(finite > 500, "too few finite cases ({finite}) to be a test");
    }

    #[test]
    fn step_below_a_limit_is_the_step_or_at_least_the_limit() {
        // The early exit must never hide a root below the limit; above it, any value
        // ≥ limit is allowed. Limits at, around and far from the true step.
        let mut rng = Rng(0x9e3779b97f4a7c15);
        let (mut skipped, mut exact) = (0, 0);
        for _ in 0..4000 {
            let uv = ccw_triangle(&mut rng);
            let dir = [rng.point(2.0), rng.point(2.0), rng.point(2.0)];
            let t = flip_free_step(uv, dir);
            let scale = if t.is_finite() { t } else { 1.0 };
            for limit in [
                f64::INFINITY,
                scale * rng.range(0.0, 3.0),
                scale,
                scale * (1.0 + 1e-12),
            ] {
                let b = flip_free_step_below(uv, dir, limit);
                if t < limit {
                    assert_eq!(b, t, "limit {limit}: {b} vs the step {t}");
                    exact += 1;
                } else {
                    assert!(b >= limit || b == t, "limit {limit}: {b} < limit, step {t}");
                    skipped += usize::from(b == limit && t != limit);
                }
            }
        }
        assert!(
            skipped > 1000 && exact > 1000,
            "{skipped} skipped, {exact} exact"
        );
        let clockwise = [[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]];
        assert_eq!(flip_free_step_below(clockwise, [[0.0; 2]; 3], 1.0), 0.0);
    }

    /// Exactly linear case (a = 0) and near-linear case (tiny a): the stable formula
    /// gives the small root without cancellation.
    #[test]
    fn near_linear_quadratic_is_accurate() {
        // c = 1, b = −1, a = ε: small root = (1 − √(1 − 4ε))/(2ε) ≈ 1 + ε + 2ε².
        for eps in [1e-20, 1e-12, 1e-8] {
            let r = smallest_positive_root(eps, -1.0, 1.0);
            let want = 1.0 + eps + 2.0 * eps * eps;
            assert!(
                (r - want).abs() <= 4.0 * f64::EPSILON,
                "eps {eps}: {r} vs {want}"
            );
        }
        assert_eq!(smallest_positive_root(0.0, -4.0, 1.0), 0.25);
        assert_eq!(smallest_positive_root(0.0, 4.0, 1.0), f64::INFINITY);
        // a < 0: one positive root, c/q or q/a whichever is positive: 1 − s² → 1.
        assert_eq!(smallest_positive_root(-1.0, 0.0, 1.0), 1.0);
        // No real roots: 1 + s².
        assert_eq!(smallest_positive_root(1.0, 0.0, 1.0), f64::INFINITY);
        // Both roots negative: (1 + s)(1 + 2s).
        assert_eq!(smallest_positive_root(2.0, 3.0, 1.0), f64::INFINITY);
    }

    #[test]
    fn mesh_minimum_and_bad_input() {
        // Two triangles sharing the edge 1–2 of a unit square; moving vertex 3
        // towards the shared edge (x + y = 1) flips triangle (1, 3, 2) at s = 0.5.
        let uvs = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        let tris = [[0, 1, 2], [1, 3, 2]];
        let dir = [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [-1.0, -1.0]];
        assert!((max_flip_free_step(&uvs, &tris, &dir) - 0.5).abs() < 1e-15);
        assert_eq!(
            max_flip_free_step(&uvs, &tris, &[[0.0; 2]; 4]),
            f64::INFINITY
        );
        assert_eq!(max_flip_free_step(&uvs, &[], &dir), f64::INFINITY);
        assert_eq!(max_flip_free_step(&uvs, &tris, &dir[..3]), 0.0);
        assert_eq!(max_flip_free_step(&uvs, &[[0, 1, 9]], &dir), 0.0);
    }

    /// The parallel path agrees with the per-triangle minimum on a large grid.
    #[test]
    fn parallel_reduction_matches_serial() {
        let n = 120; // 2·119² ≈ 28k triangles > PARALLEL_ABOVE
        let mut rng = Rng(99);
        let mut uvs = Vec::new();
        let mut dir = Vec::new();
        for y in 0..n {
            for x in 0..n {
                uvs.push([x as f64, y as f64]);
                dir.push(rng.point(1.0));
            }
        }
        let mut tris = Vec::new();
        for y in 0..n - 1 {
            for x in 0..n - 1 {
                let v = (y * n + x) as u32;
                let n = n as u32;
                tris.push([v, v + 1, v + n]);
                tris.push([v + 1, v + n + 1, v + n]);
            }
        }
        let serial = tris
            .iter()
            .map(|&[i, j, k]| {
                let (i, j, k) = (i as usize, j as usize, k as usize);
                flip_free_step([uvs[i], uvs[j], uvs[k]], [dir[i], dir[j], dir[k]])
            })
            .fold(f64::INFINITY, f64::min);
        assert!(serial.is_finite());
        assert_eq!(max_flip_free_step(&uvs, &tris, &dir), serial);
    }
}
