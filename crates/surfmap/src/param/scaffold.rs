//! A scaffold of the free space around a chart (SCAF: Jiang, Schaefer, Zhou, Sorkine,
//! Panozzo 2017, "Simplicial complex augmentation framework for bijective maps"), with
//! progressive reference shapes (Liu, Ye, Wang, Liu 2018): the bijective mode's solve
//! from a crushed mean-value start, in place of the boundary barrier's
//! ([`super::barrier`]), whose steps such a start cuts short.
//!
//! The chart (a flip-free map of a disc) is surrounded by an annulus of *scaffold*
//! triangles between its boundary loop and an outer ring of free vertices. Chart and
//! scaffold together are a disc; a flip-free map of it whose outer ring is a simple
//! polygon is injective, so the chart's boundary cannot cross itself as long as no
//! scaffold triangle flips. Each scaffold iteration
//!
//! 1. re-meshes the scaffold: Lawson edge flips ([`make_delaunay`]) turn it into the
//!    constrained Delaunay triangulation of the free space (the chart's boundary edges
//!    and the ring are kept), so two parts of the boundary that approach each other are
//!    separated by a few well-shaped triangles instead of slivers;
//! 2. gives every scaffold triangle its current shape as rest shape and a small weight
//!    `w = `[`SCAFFOLD_WEIGHT`]` / #scaffold` (the chart has unit area), so the scaffold
//!    costs nothing where it is not deformed and grows to `+∞` where it would flip;
//! 3. takes one projected Newton step of `E_chart + w Σ_scaffold W` with the flip-free
//!    line search over chart *and* scaffold ([`super::newton`]).
//!
//! The contact of two boundary parts is thus resolved by the scaffold triangles between
//! them, which the re-meshing keeps fat, rather than by the first-contact bound of the
//! barrier; and the flips of crushed chart triangles, which cut every step from such a
//! start to 10⁻³–10⁻¹ of Newton's (measured on `elephant_holes.off`, BENCHMARKS.md
//! "Hard discs"), by the chart's reference shapes ([`reference_triangle`]): relative to
//! them no triangle is distorted by more than `e^{±1}`, so Newton's steps are full. The
//! iterations stop when the chart's energy stalls ([`MIN_GAIN`]): near its minimum under
//! the scaffold, not at it (the scaffold's weight biases it slightly).
//!
//! Cost per iteration: the re-meshing (linear in the boundary length), a new symbolic
//! factorization (the pattern changes with the scaffold) and one Newton step.

use super::element::RestTriangle;
use super::newton::{IterationLog, NewtonSettings, NewtonSolver};
use super::signed_uv_area;
use crate::energy::Density;
use crate::linsolve::{SolveError, VertexOrdering};
use std::f64::consts::TAU;
use std::time::Instant;

/// Total weight of the scaffold triangles, relative to the chart's (unit) area.
pub const SCAFFOLD_WEIGHT: f64 = 0.1;

/// Radius of the outer ring, in units of the chart's largest distance from the
/// boundary's centroid (the chart grows into it).
pub const RING_RADIUS_FACTOR: f64 = 6.0;

/// No neighbour in [`make_delaunay`]'s adjacency.
const NONE: u32 = u32::MAX;

/// The scaffold around a map whose boundary loop `boundary` (counter-clockwise, the
/// chart on its left) is a convex polygon, strictly star-shaped from its centroid (e.g.
/// the circle of [`super::tutte::mean_value`]): appends the outer ring's vertices to
/// `uv` (one per two boundary vertices, at least 16, on a circle
/// [`RING_RADIUS_FACTOR`] times the chart's radius) and returns the scaffold
/// triangles, counter-clockwise. `None` when the boundary's angles around the centroid
/// do not increase (not star-shaped), or a triangle would be flipped.
pub fn around_convex(uv: &mut Vec<[f64; 2]>, boundary: &[u32]) -> Option<Vec<[u32; 3]>> {
    let n = boundary.len();
    if n < 3 {
        return None;
    }
    let mut c = [0.0; 2];
    for &v in boundary {
        c = [c[0] + uv[v as usize][0], c[1] + uv[v as usize][1]];
    }
    c = [c[0] / n as f64, c[1] / n as f64];
    let radius = uv
        .iter()
        .map(|p| (p[0] - c[0]).hypot(p[1] - c[1]))
        .fold(0.0, f64::max);
    if !(radius.is_finite() && radius > 0.0) {
        return None;
    }
    // Unwrapped boundary angles, increasing by less than a full turn in total.
    let angle = |v: u32| (uv[v as usize][1] - c[1]).atan2(uv[v as usize][0] - c[0]);
    let a0 = angle(boundary[0]);
    let mut angles = Vec::with_capacity(n + 1);
    angles.push(0.0);
    for k in 1..n {
        let a = (angle(boundary[k]) - a0).rem_euclid(TAU);
        if a <= angles[k - 1] {
            return None;
        }
        angles.push(a);
    }
    angles.push(TAU);
    let m = (n / 2).max(16);
    let first_ring = uv.len() as u32;
    let big = RING_RADIUS_FACTOR * radius;
    for j in 0..m {
        let a = a0 + TAU * j as f64 / m as f64;
        uv.push([c[0] + big * a.cos(), c[1] + big * a.sin()]);
    }
    let ring = |j: usize| first_ring + (j % m) as u32;
    let ring_angle = |j: usize| TAU * j as f64 / m as f64;
    // Merge the two loops by angle: each triangle advances one of them by one edge.
    let mut triangles = Vec::with_capacity(n + m);
    let (mut i, mut j) = (0, 0);
    while i < n || j < m {
        let advance_boundary = j == m || (i < n && angles[i + 1] <= ring_angle(j + 1));
        if advance_boundary {
            triangles.push([boundary[(i + 1) % n], boundary[i], ring(j)]);
            i += 1;
        } else {
            triangles.push([ring(j), ring(j + 1), boundary[i % n]]);
            j += 1;
        }
    }
    if super::count_flipped(uv, &triangles) > 0 {
        uv.truncate(first_ring as usize);
        return None;
    }
    Some(triangles)
}

/// `> 0` when `d` lies inside the circle through the counter-clockwise `a, b, c` (the
/// classic determinant, relative to `d`).
fn in_circle(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    let (ax, ay) = (a[0] - d[0], a[1] - d[1]);
    let (bx, by) = (b[0] - d[0], b[1] - d[1]);
    let (cx, cy) = (c[0] - d[0], c[1] - d[1]);
    let (a2, b2, c2) = (ax * ax + ay * ay, bx * bx + by * by, cx * cx + cy * cy);
    ax * (by * c2 - b2 * cy) - ay * (bx * c2 - b2 * cx) + a2 * (bx * cy - by * cx)
}

/// Lawson's edge flips on the counter-clockwise triangles `triangles` in the map `uv`:
/// every edge shared by two of them whose quadrilateral has the fourth vertex inside
/// the first triangle's circumcircle is flipped, until none is (then the triangulation
/// is the constrained Delaunay triangulation of its region, the edges not shared by two
/// of `triangles` being the constraints). Flips keep every triangle counter-clockwise
/// (only strictly convex quadrilaterals are flipped). Returns the number of flips; at
/// most `100 · #triangles` are made (a guard against cycles from rounding on
/// co-circular points).
pub fn make_delaunay(uv: &[[f64; 2]], triangles: &mut [[u32; 3]]) -> usize {
    let nt = triangles.len();
    // adjacency[t][k]: the triangle across edge k (from corner k to corner k + 1) and
    // the edge's index there, packed as 3·t' + k'.
    let mut adjacency = vec![[NONE; 3]; nt];
    {
        let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * nt);
        for (t, tri) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                edges.push((a.min(b), a.max(b), (3 * t + k) as u32));
            }
        }
        edges.sort_unstable();
        for w in edges.windows(2) {
            if (w[0].0, w[0].1) == (w[1].0, w[1].1) {
                let (p, q) = (w[0].2, w[1].2);
                adjacency[(p / 3) as usize][(p % 3) as usize] = q;
                adjacency[(q / 3) as usize][(q % 3) as usize] = p;
            }
        }
    }
    let p = |v: u32| uv[v as usize];
    let mut stack: Vec<u32> = (0..3 * nt as u32).collect();
    let mut flips = 0;
    while let Some(e) = stack.pop() {
        if flips >= 100 * nt {
            break;
        }
        let (t1, k1) = ((e / 3) as usize, (e % 3) as usize);
        let across = adjacency[t1][k1];
        if across == NONE {
            continue;
        }
        let (t2, k2) = ((across / 3) as usize, (across % 3) as usize);
        // t1 = (a, b, c) with the edge a → b; t2 = (b, a, d).
        let (a, b, c) = (
            triangles[t1][k1],
            triangles[t1][(k1 + 1) % 3],
            triangles[t1][(k1 + 2) % 3],
        );
        let d = triangles[t2][(k2 + 2) % 3];
        let scale = [a, b, c]
            .iter()
            .map(|&v| {
                let (x, y) = (p(v)[0] - p(d)[0], p(v)[1] - p(d)[1]);
                x * x + y * y
            })
            .fold(0.0, f64::max);
        if in_circle(p(a), p(b), p(c), p(d)) <= 1e-12 * scale * scale {
            continue;
        }
        // New triangles (a, d, c) and (d, b, c): both must be counter-clockwise.
        if !(signed_uv_area([p(a), p(d), p(c)]) > 0.0 && signed_uv_area([p(d), p(b), p(c)]) > 0.0) {
            continue;
        }
        // Outer edges before the flip: b→c (t1), c→a (t1), a→d (t2), d→b (t2).
        let bc = adjacency[t1][(k1 + 1) % 3];
        let ca = adjacency[t1][(k1 + 2) % 3];
        let ad = adjacency[t2][(k2 + 1) % 3];
        let db = adjacency[t2][(k2 + 2) % 3];
        // t1 := (a, d, c): edges a→d, d→c (shared), c→a. t2 := (d, b, c): edges d→b,
        // b→c, c→d (shared).
        triangles[t1] = [a, d, c];
        triangles[t2] = [d, b, c];
        let (t1u, t2u) = (t1 as u32, t2 as u32);
        adjacency[t1] = [ad, 3 * t2u + 2, ca];
        adjacency[t2] = [db, bc, 3 * t1u + 1];
        let mut link = |outer: u32, inner: u32| {
            if outer != NONE {
                adjacency[(outer / 3) as usize][(outer % 3) as usize] = inner;
            }
        };
        link(ad, 3 * t1u);
        link(ca, 3 * t1u + 2);
        link(db, 3 * t2u);
        link(bc, 3 * t2u + 1);
        flips += 1;
        stack.extend([3 * t1u, 3 * t1u + 2, 3 * t2u, 3 * t2u + 1]);
    }
    flips
}

/// Bound on `|ln σ|` (σ: singular values) of the chart's map relative to its
/// progressive reference shapes ([`reference_triangle`]).
pub const REFERENCE_MAX_LOG: f64 = 1.0;

/// The progressive reference shape of a triangle (Liu, Ye, Wang, Liu 2018,
/// "Progressive parameterizations"): between its rest shape and its current UV shape,
/// so that the map relative to it distorts by at most `e^max_log`.
///
/// With `J = Ds Dm⁻¹ = R S` (polar: `S = (JᵀJ)^½ = V diag(σ1, σ2) Vᵀ`), the reference is
/// the rest triangle deformed by `M = S^θ`, `Dm_ref = M Dm`, so the map relative to it
/// is `J M⁻¹ = R S^{1−θ}`, with singular values `σ_i^{1−θ}`; `θ = max(0, 1 − max_log /
/// max_i |ln σ_i|)` is the least that brings them within `e^{±max_log}`. The weight
/// (`area`) stays the rest triangle's. `None` for a flipped or degenerate UV triangle.
pub fn reference_triangle(
    rest: &RestTriangle,
    uv: &[[f64; 2]; 3],
    max_log: f64,
) -> Option<RestTriangle> {
    let j = super::element::jacobian(rest, uv);
    let (s1, s2) = crate::measure::jacobian::signed_singular_values(j);
    if !(s2 > 0.0 && s1.is_finite()) {
        return None;
    }
    let worst = s1.ln().abs().max(s2.ln().abs());
    if worst <= max_log {
        return Some(*rest);
    }
    let theta = 1.0 - max_log / worst;
    // JᵀJ = [[p, q], [q, r]]; v1: its eigenvector of the eigenvalue σ1².
    let p = j[0][0] * j[0][0] + j[1][0] * j[1][0];
    let q = j[0][0] * j[0][1] + j[1][0] * j[1][1];
    let r = j[0][1] * j[0][1] + j[1][1] * j[1][1];
    let l1 = s1 * s1;
    let (x, y) = if (l1 - r).abs() >= (l1 - p).abs() {
        (l1 - r, q)
    } else {
        (q, l1 - p)
    };
    let len = x.hypot(y);
    let (x, y) = if len > 0.0 {
        (x / len, y / len)
    } else {
        (1.0, 0.0)
    };
    // S^{−θ} = σ2^{−θ} I + (σ1^{−θ} − σ2^{−θ}) v1 v1ᵀ
    let (a1, a2) = (s1.powf(-theta), s2.powf(-theta));
    let m = [
        [a2 + (a1 - a2) * x * x, (a1 - a2) * x * y],
        [(a1 - a2) * x * y, a2 + (a1 - a2) * y * y],
    ];
    let d = &rest.dm_inv;
    Some(RestTriangle {
        dm_inv: [
            [
                d[0][0] * m[0][0] + d[0][1] * m[1][0],
                d[0][0] * m[0][1] + d[0][1] * m[1][1],
            ],
            [
                d[1][0] * m[0][0] + d[1][1] * m[1][0],
                d[1][0] * m[0][1] + d[1][1] * m[1][1],
            ],
        ],
        area: rest.area,
    })
}

/// Scaffold iterations at most, and the relative decrease of the chart's energy per
/// iteration below which they stop: measured on `elephant_holes.off`, the energy is
/// then within 1 % of the barrier solve's minimum (1.708 after 29 iterations against
/// 1.692), and the tail is slow (1.700 after 80: the scaffold's re-meshing keeps Newton
/// from converging quadratically).
pub const MAX_ITERATIONS: usize = 40;
pub const MIN_GAIN: f64 = 1e-3;

/// What [`solve`] did.
#[derive(Clone, Copy, Debug, Default)]
pub struct ScaffoldStats {
    /// Newton steps taken on chart and scaffold together.
    pub iterations: usize,
    /// The chart's energy at the end (per unit area).
    pub energy: f64,
    /// Whether the iterations stopped because the energy stalled ([`MIN_GAIN`]), not
    /// at the cap.
    pub stalled: bool,
    /// Lawson flips over all re-meshings.
    pub flips: usize,
}

/// Runs scaffold iterations (module docs) on the chart `uv` (normalized to unit area,
/// flip-free, its boundary loop `boundary` convex: see [`around_convex`]) with rest
/// triangles `rest` of `triangles`, the density `density` and the pinned coordinates
/// `pins`; `uv` is moved in place. `log` receives an entry per iteration (the chart's
/// energy alone). Returns `Ok(None)` (and leaves `uv` alone) when no scaffold can be
/// built around the start.
#[allow(clippy::too_many_arguments)]
pub fn solve<D: Density + ?Sized>(
    uv: &mut [[f64; 2]],
    triangles: &[[u32; 3]],
    rest: &[RestTriangle],
    boundary: &[u32],
    pins: &[(u32, usize)],
    density: &D,
    clock: Instant,
    log: &mut dyn FnMut(IterationLog),
) -> Result<Option<ScaffoldStats>, SolveError> {
    let n = uv.len();
    let mut all = uv.to_vec();
    let Some(mut scaffold) = around_convex(&mut all, boundary) else {
        return Ok(None);
    };
    let chart_energy = NewtonSolver::energy_of(rest, triangles);
    let mut energy = chart_energy(uv, density);
    let mut stats = ScaffoldStats {
        energy,
        ..ScaffoldStats::default()
    };
    let settings = NewtonSettings {
        max_iterations: 1,
        ..NewtonSettings::default()
    };
    let mut combined = Vec::with_capacity(triangles.len() + scaffold.len());
    let mut combined_rest = Vec::with_capacity(triangles.len() + scaffold.len());
    // The fill-reducing ordering: AMD on the vertex graph, anew each iteration (the
    // re-meshing flips up to 6× as many edges as there are scaffold triangles, so a
    // reused ordering fills badly: 2.3× slower on elephant_holes), which costs a
    // quarter of AMD on the 2n unknowns.
    for it in 1..=MAX_ITERATIONS {
        stats.flips += make_delaunay(&all, &mut scaffold);
        let weight = SCAFFOLD_WEIGHT / scaffold.len() as f64;
        combined.clear();
        combined.extend_from_slice(triangles);
        combined.extend_from_slice(&scaffold);
        combined_rest.clear();
        for (t, tri) in triangles.iter().enumerate() {
            let corners = tri.map(|v| all[v as usize]);
            match reference_triangle(&rest[t], &corners, REFERENCE_MAX_LOG) {
                Some(r) => combined_rest.push(r),
                None => return Ok(finish(uv, &all, n, stats)),
            }
        }
        for t in &scaffold {
            let [a, b, c] = t.map(|v| [all[v as usize][0], all[v as usize][1], 0.0]);
            let Some(mut r) = RestTriangle::new(a, b, c) else {
                // A scaffold triangle at rounding level: stop here, the map is valid.
                return Ok(finish(uv, &all, n, stats));
            };
            r.area = weight;
            combined_rest.push(r);
        }
        let ordering = VertexOrdering::fill_reducing(all.len(), &combined)?;
        let mut solver = NewtonSolver::new(
            all.len(),
            &combined,
            combined_rest.clone(),
            pins,
            Some(&ordering),
        )?;
        let mut last = None;
        let (_, steps, _) =
            solver.minimize(&mut all, density, &settings, 0, clock, &mut |entry| {
                if entry.iteration > 0 {
                    last = Some(entry)
                }
            })?;
        if steps == 0 {
            stats.stalled = true;
            break;
        }
        stats.iterations += 1;
        let e = chart_energy(&all[..n], density);
        stats.energy = e;
        if let Some(mut entry) = last {
            entry.iteration = it;
            entry.energy = e;
            log(entry);
        }
        let gain = (energy - e) / energy;
        energy = e;
        if gain < MIN_GAIN {
            stats.stalled = true;
            break;
        }
    }
    Ok(finish(uv, &all, n, stats))
}

fn finish(
    uv: &mut [[f64; 2]],
    all: &[[f64; 2]],
    n: usize,
    stats: ScaffoldStats,
) -> Option<ScaffoldStats> {
    uv.copy_from_slice(&all[..n]);
    Some(stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::param::count_flipped;

    /// `n` boundary vertices on the unit circle, counter-clockwise, and a centre vertex
    /// fanned to them: a convex chart.
    fn fan(n: usize) -> (Vec<[f64; 2]>, Vec<[u32; 3]>, Vec<u32>) {
        let mut uv: Vec<[f64; 2]> = (0..n)
            .map(|k| {
                let a = TAU * k as f64 / n as f64 + 0.3;
                [a.cos(), a.sin()]
            })
            .collect();
        uv.push([0.1, -0.05]);
        let c = n as u32;
        let triangles = (0..n as u32).map(|k| [k, (k + 1) % n as u32, c]).collect();
        (uv, triangles, (0..n as u32).collect())
    }

    /// The boundary edges of `triangles` ([`crate::raster::boundary::boundary_edges`]),
    /// after checking that no directed edge is used twice (a manifold, consistently
    /// oriented triangulation).
    fn boundary_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
        let mut edges: Vec<(u32, u32)> = triangles
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .collect();
        edges.sort_unstable();
        if let Some(w) = edges.windows(2).find(|w| w[0] == w[1]) {
            panic!(
                "edge {}→{} twice in one direction: not a manifold triangulation",
                w[0].0, w[0].1
            );
        }
        crate::raster::boundary::boundary_edges(triangles)
            .into_iter()
            .map(|[a, b]| (a, b))
            .collect()
    }

    #[test]
    fn scaffold_fills_the_annulus_between_chart_and_ring() {
        for n in [5, 12, 40, 101] {
            let (mut uv, chart, boundary) = fan(n);
            let chart_vertices = uv.len();
            let scaffold = around_convex(&mut uv, &boundary).unwrap();
            let m = uv.len() - chart_vertices;
            assert_eq!(m, (n / 2).max(16));
            // One triangle per boundary edge and per ring edge, none flipped.
            assert_eq!(scaffold.len(), n + m);
            assert_eq!(count_flipped(&uv, &scaffold), 0);
            // Chart + scaffold: a disc whose only boundary is the ring, run
            // counter-clockwise; the scaffold covers the annulus's area exactly.
            let mut all = chart.clone();
            all.extend_from_slice(&scaffold);
            let mut outer = boundary_edges(&all);
            outer.sort_unstable();
            let first = chart_vertices as u32;
            let mut ring: Vec<(u32, u32)> = (0..m as u32)
                .map(|j| (first + j, first + (j + 1) % m as u32))
                .collect();
            ring.sort_unstable();
            assert_eq!(outer, ring, "n = {n}");
            let area = |tris: &[[u32; 3]]| -> f64 {
                tris.iter()
                    .map(|t| signed_uv_area(t.map(|v| uv[v as usize])))
                    .sum()
            };
            let ring_area = 0.5
                * (0..m)
                    .map(|j| {
                        let (p, q) = (uv[chart_vertices + j], uv[chart_vertices + (j + 1) % m]);
                        p[0] * q[1] - p[1] * q[0]
                    })
                    .sum::<f64>();
            let total = area(&chart) + area(&scaffold);
            assert!(
                (total - ring_area).abs() < 1e-12 * ring_area,
                "{total} vs {ring_area}"
            );
        }
    }

    #[test]
    fn a_concave_start_gets_no_scaffold() {
        let (mut uv, _, boundary) = fan(12);
        // Pull one boundary vertex past the centre: the angles no longer increase.
        uv[3] = [-0.5, -0.4];
        let before = uv.len();
        assert!(around_convex(&mut uv, &boundary).is_none());
        assert_eq!(uv.len(), before);
    }

    /// Triangles of `triangles` whose circumcircle strictly contains a vertex of a
    /// neighbour across a shared edge (brute force over all pairs).
    fn non_delaunay_edges(uv: &[[f64; 2]], triangles: &[[u32; 3]]) -> usize {
        let mut count = 0;
        for t in triangles {
            for s in triangles {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    for l in 0..3 {
                        if (s[l], s[(l + 1) % 3]) == (b, a) {
                            let d = s[(l + 2) % 3];
                            let c = t[(k + 2) % 3];
                            let p = |v: u32| uv[v as usize];
                            if in_circle(p(a), p(b), p(c), p(d)) > 1e-9 {
                                count += 1;
                            }
                        }
                    }
                }
            }
        }
        count
    }

    #[test]
    fn lawson_flips_give_a_delaunay_triangulation_of_the_same_region() {
        // The fan-strip scaffold of a many-sided chart has long thin triangles.
        let (mut uv, _, boundary) = fan(60);
        let mut scaffold = around_convex(&mut uv, &boundary).unwrap();
        let before_edges = {
            let mut e = boundary_edges(&scaffold);
            e.sort_unstable();
            e
        };
        assert!(non_delaunay_edges(&uv, &scaffold) > 0);
        let flips = make_delaunay(&uv, &mut scaffold);
        assert!(flips > 0);
        assert_eq!(non_delaunay_edges(&uv, &scaffold), 0);
        // Still valid, still the same region (same constrained edges: the chart's
        // boundary and the ring), every vertex still used.
        assert_eq!(count_flipped(&uv, &scaffold), 0);
        let mut after_edges = boundary_edges(&scaffold);
        after_edges.sort_unstable();
        assert_eq!(before_edges, after_edges);
        // Already Delaunay: nothing to do.
        assert_eq!(make_delaunay(&uv, &mut scaffold), 0);
    }

    #[test]
    fn reference_shapes_bound_the_distortion_relative_to_them() {
        let rest = RestTriangle::new([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.3, 0.8, 0.0]).unwrap();
        let sv = |r: &RestTriangle, uv: &[[f64; 2]; 3]| {
            crate::measure::jacobian::signed_singular_values(super::super::element::jacobian(r, uv))
        };
        let max_log = 1.0;
        for uv in [
            // Crushed 1000× along a slanted direction, and rotated.
            [[0.0, 0.0], [0.001, 0.0005], [0.2, 0.9]],
            // Stretched 50× and squeezed.
            [[0.0, 0.0], [50.0, 0.0], [10.0, 0.02]],
            // Mild: within e^{±1} of the rest shape, so the rest shape itself.
            [[0.0, 0.0], [1.2, 0.1], [0.3, 0.7]],
        ] {
            let (s1, s2) = sv(&rest, &uv);
            let reference = reference_triangle(&rest, &uv, max_log).unwrap();
            assert_eq!(reference.area, rest.area);
            let (r1, r2) = sv(&reference, &uv);
            let worst = s1.ln().abs().max(s2.ln().abs());
            if worst <= max_log {
                assert_eq!(reference, rest);
                continue;
            }
            // Relative to the reference the singular values are σ^{1−θ}: the worst one
            // exactly at the bound, the other one the same power of its own.
            let theta = 1.0 - max_log / worst;
            let mut expected = [s1.powf(1.0 - theta), s2.powf(1.0 - theta)];
            expected.sort_by(|a, b| b.total_cmp(a));
            assert!((r1 - expected[0]).abs() < 1e-9 * r1, "{r1} vs {expected:?}");
            assert!((r2 - expected[1]).abs() < 1e-9 * r1, "{r2} vs {expected:?}");
            assert!((r1.ln().abs().max(r2.ln().abs()) - max_log).abs() < 1e-9);
        }
        // A flipped triangle has no reference shape.
        assert!(reference_triangle(&rest, &[[0.0, 0.0], [0.3, 0.8], [1.0, 0.0]], 1.0).is_none());
    }

    #[test]
    fn scaffold_iterations_lower_the_energy_and_keep_the_map_injective() {
        use crate::mesh::Disc;
        use crate::param::element::rest_triangles;
        // A deep spherical cap: its mean-value map onto the circle squeezes the pole.
        let mesh = crate::mesh::generate::spherical_cap(1.0, 2.6, 12, 40);
        let disc = Disc::new(&mesh).unwrap();
        let (positions, _) = mesh.unit_area_positions();
        let mut uv = crate::param::tutte::mean_value(&positions, &disc).unwrap();
        let area: f64 = mesh
            .triangles
            .iter()
            .map(|t| signed_uv_area(t.map(|v| uv[v as usize])))
            .sum();
        uv.iter_mut()
            .for_each(|p| *p = [p[0] / area.sqrt(), p[1] / area.sqrt()]);
        let rest = rest_triangles(&positions, &mesh.triangles).unwrap();
        let boundary = disc.boundary();
        let pins = [(boundary[0], 0), (boundary[0], 1), (boundary[7], 1)];
        let density = crate::energy::Alpha::balanced();
        let energy = NewtonSolver::energy_of(&rest, &mesh.triangles);
        let before = energy(&uv, &density);
        let mut entries = 0;
        let stats = solve(
            &mut uv,
            &mesh.triangles,
            &rest,
            boundary,
            &pins,
            &density,
            Instant::now(),
            &mut |_| entries += 1,
        )
        .unwrap()
        .unwrap();
        assert!(stats.iterations > 0 && entries == stats.iterations);
        let after = energy(&uv, &density);
        assert!((after - stats.energy).abs() <= 1e-12 * after);
        assert!(after < 0.5 * before, "{after} vs {before}");
        assert_eq!(count_flipped(&uv, &mesh.triangles), 0);
        let n = boundary.len();
        let segments: Vec<[[f64; 2]; 2]> = (0..n)
            .map(|i| [uv[boundary[i] as usize], uv[boundary[(i + 1) % n] as usize]])
            .collect();
        assert_eq!(
            crate::measure::overlap::count_segment_crossings(&segments).0,
            0
        );
    }

    #[test]
    fn in_circle_sign() {
        let (a, b, c) = ([1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]);
        assert!(in_circle(a, b, c, [0.0, 0.0]) > 0.0);
        assert!(in_circle(a, b, c, [0.0, 2.0]) < 0.0);
        assert!(in_circle(a, b, c, [0.0, -1.0]).abs() < 1e-15);
    }
}
