//! Hole rims fitted at mesh resolution: A's hole rims carried exactly onto B's.
//!
//! φ is solved on the filled surfaces and on a grid, so around a hole (an eye, the
//! mouth) it carries A's rim to B's only up to a grid cell or two: part of A's rim lands
//! in the fill of B's hole — not B's surface, so unmatched — and part a little inside
//! B's surface, where its neighbours crowd the rim and their image triangles fold. But
//! holes are matched to holes (eyes to eyes), so A's rim belongs on B's rim. This step
//! moves it there, in B's parameter plane, before the correspondence is read off:
//!
//! 1. **Pairing.** Each hole of A goes with the hole of B whose rim centre (in B's UV) is
//!    closest to the centre of the images `y(v)` of A's rim vertices, closest pairs
//!    first, one to one, and only when the distance is below the B rim's mean radius.
//! 2. **Rim targets.** Each rim vertex `v_k` of A (in loop order) is projected on B's
//!    rim polygon (in UV), giving an arc-length position `s_k` along B's rim (3D length);
//!    `a_k` is the 3D arc length along A's rim scaled by `L_B/L_A`. When the images wind
//!    once around B's hole — the unwrapped positions `S_k` increase by B's rim length
//!    `L_B` over the loop — they are kept, except that where they do not increase
//!    steadily (the projection bunches or reverses them) the offset `S_k − a_k` is
//!    smoothed along the loop until every step `S_{k+1} − S_k` is at least half of
//!    `a_{k+1} − a_k`. When they do not (a closed mouth's slit carried into an open
//!    mouth, a thin eye whose lids' images cross) B's rim is taken at A's arc length
//!    alone, `S_k = a_k + c`, with the offset `c` that brings the targets closest to the
//!    images (least squares, searched over `8·max(n_A, n_B)` steps of the rim). Each
//!    target `t(v_k)` is the point of B's rim at `S_k`.
//! 3. **Band.** The vertices within `w` rings of a fitted rim follow it. The band width
//!    `w` is `rings` ([`RIM_FIT_RINGS`](crate::matching::options::RIM_FIT_RINGS)), or two rings per rim edge of the rim's
//!    largest displacement if that is wider (at most 40), so the shear per ring stays
//!    under half an edge. First the displacement `d(v) = t(v) − y(v)` of the rim
//!    vertices is extended harmonically over A's mesh — `Σ_{u∈N(v)} (d(u) − d(v)) = 0`
//!    in the band, `d = 0` beyond — and every vertex in the band moved to `y(v) + d(v)`.
//!    Then the band's vertices not on a boundary of A are placed by the mean-value map
//!    (Floater 2003) with everything else as boundary values (the rim at its targets,
//!    φ's images beyond the band): `p(v) = Σ_u λ_vu p(u)`, `λ_vu` the mean-value weights
//!    of A's own UV, solved exactly (`crate::param::tutte::mean_value_with_fixed`). The weights reproduce affine maps, so
//!    where φ is affine on A's UV at the scale of a few edges the band stays where φ put
//!    it; where φ's images crowd against the rim or fold (a closed lower lip squeezed
//!    into an open mouth), they are straightened — the displacement alone moves the band
//!    but keeps its folds.
//!
//! The fold check after it ([`crate::matching::folds::drop_folds`]) still decides what is
//! reported; this step only changes where A's vertices land near the holes.

use glam::{DVec2, DVec3};

use super::super::prepare::surface::MatchSurface;
use crate::mesh::closest::compressed_rows;
use crate::mesh::{Topology, TriMesh};
use crate::param::tutte::mean_value_with_fixed;

/// A rim moved farther is followed by a wider band: two rings per mean rim edge of its
/// largest displacement, so that the shear per ring stays under half an edge and no
/// ring's images cross the next's (an open mouth's rim, carried from a closed mouth's
/// images, moves by many edges). Three (a third of an edge) did better on an open jaw
/// but sent a coarse face's mouth band across its nose (BENCHMARKS.md, "Hole rims
/// carried onto B's").
const RINGS_PER_EDGE_MOVED: f64 = 2.0;

/// Widest band.
const MAX_RINGS: usize = 40;

/// Gauss–Seidel sweeps of the band's harmonic extension, per ring of width.
const SWEEPS_PER_RING: usize = 12;

/// What the rim fit did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct RimFit {
    /// Holes of A whose rim was carried onto the paired rim of B.
    pub holes: usize,
    /// Of those, holes whose images did not wind once around B's hole, carried onto B's
    /// rim by arc length alone.
    pub by_arc_length: usize,
    /// Holes paired but left as φ put them (a degenerate rim).
    pub skipped: usize,
    /// Vertices of A moved (rims and bands).
    pub moved: usize,
}

/// How a rim's targets were found (step 2 of the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RimTargets {
    /// φ's images projected on B's rim.
    Projected,
    /// A's arc length from the best-fitting offset.
    ArcLength,
}

/// The 3D arc length along a closed loop of the surface's vertices from its first vertex:
/// `n + 1` values, the last the loop's length.
fn loop_arc_length(surface: &MatchSurface, rim: &[u32]) -> Vec<f64> {
    let n = rim.len();
    let mut cumulative = Vec::with_capacity(n + 1);
    cumulative.push(0.0);
    for k in 0..n {
        let p = DVec3::from_array(surface.positions[rim[k] as usize]);
        let q = DVec3::from_array(surface.positions[rim[(k + 1) % n] as usize]);
        cumulative.push(cumulative[k] + p.distance(q));
    }
    cumulative
}

/// A rim of B as a closed polygon in B's UV, with its 3D arc length.
struct RimPolygon {
    uv: Vec<DVec2>,
    /// `cumulative[k]`: 3D length from vertex 0 to vertex k; `cumulative[n]` the whole.
    cumulative: Vec<f64>,
}

impl RimPolygon {
    fn new(surface: &MatchSurface, rim: &[u32]) -> Self {
        let uv = rim
            .iter()
            .map(|&v| DVec2::from_array(surface.uvs[v as usize]))
            .collect();
        let cumulative = loop_arc_length(surface, rim);
        Self { uv, cumulative }
    }

    fn length(&self) -> f64 {
        self.cumulative[self.uv.len()]
    }

    fn centre(&self) -> DVec2 {
        self.uv.iter().sum::<DVec2>() / self.uv.len() as f64
    }

    fn mean_radius(&self) -> f64 {
        let c = self.centre();
        self.uv.iter().map(|p| p.distance(c)).sum::<f64>() / self.uv.len() as f64
    }

    /// Arc-length position (3D) of the point of the polygon closest to `p` (in UV).
    fn project(&self, p: DVec2) -> f64 {
        let n = self.uv.len();
        let mut best = (f64::INFINITY, 0.0);
        for k in 0..n {
            let (a, b) = (self.uv[k], self.uv[(k + 1) % n]);
            let ab = b - a;
            let t = if ab.length_squared() > 0.0 {
                ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let d = p.distance_squared(a + t * ab);
            if d < best.0 {
                let s = self.cumulative[k] + t * (self.cumulative[k + 1] - self.cumulative[k]);
                best = (d, s);
            }
        }
        best.1
    }

    /// The UV point at arc-length position `s` (taken modulo the length).
    fn at(&self, s: f64) -> DVec2 {
        let n = self.uv.len();
        let s = s.rem_euclid(self.length());
        let k = self.cumulative[1..].partition_point(|&c| c <= s).min(n - 1);
        let span = self.cumulative[k + 1] - self.cumulative[k];
        let t = if span > 0.0 {
            ((s - self.cumulative[k]) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        self.uv[k].lerp(self.uv[(k + 1) % n], t)
    }
}

/// `x` wrapped into `[−L/2, L/2)`.
fn wrap(x: f64, length: f64) -> f64 {
    (x + 0.5 * length).rem_euclid(length) - 0.5 * length
}

/// Targets on B's rim for A's rim vertices, in loop order (step 2 of the module
/// documentation) and how they were found, or `None` for a degenerate rim.
fn rim_targets(
    a: &MatchSurface,
    rim_a: &[u32],
    images: &[DVec2],
    b: &RimPolygon,
) -> Option<(Vec<DVec2>, RimTargets)> {
    let n = rim_a.len();
    let length_b = b.length();
    if n < 3 || length_b <= 0.0 {
        return None;
    }
    // A's arc length, scaled to B's rim.
    let arc = loop_arc_length(a, rim_a);
    if arc[n] <= 0.0 {
        return None;
    }
    let ratio = length_b / arc[n];
    let arc: Vec<f64> = arc.iter().map(|x| x * ratio).collect();
    let y: Vec<DVec2> = rim_a.iter().map(|&v| images[v as usize]).collect();
    let s: Vec<f64> = y.iter().map(|&p| b.project(p)).collect();
    // Unwrapped positions along B's rim.
    let mut unwrapped = Vec::with_capacity(n + 1);
    unwrapped.push(s[0]);
    for k in 0..n {
        let step = wrap(s[(k + 1) % n] - s[k], length_b);
        unwrapped.push(unwrapped[k] + step);
    }
    // Each wrapped step differs from the true one by a multiple of L_B: the winding
    // number is an integer.
    if ((unwrapped[n] - unwrapped[0]) / length_b).round() != 1.0 {
        // The images do not go once around B's hole (a closed mouth carried into an
        // open one, a thin eye whose lids' images cross): B's rim at A's arc length, from
        // the offset that fits the images best.
        let trials = 8 * n.max(b.uv.len());
        let misfit = |c: f64| -> f64 {
            (0..n)
                .map(|k| y[k].distance_squared(b.at(arc[k] + c)))
                .sum()
        };
        let best = (0..trials)
            .map(|j| length_b * j as f64 / trials as f64)
            .min_by(|&c, &d| misfit(c).total_cmp(&misfit(d)))?;
        return Some((
            (0..n).map(|k| b.at(arc[k] + best)).collect(),
            RimTargets::ArcLength,
        ));
    }
    // The offset S_k − a_k, periodic (S_n − a_n = S_0 + L_B − L_B).
    let mut offset: Vec<f64> = (0..n).map(|k| unwrapped[k] - arc[k]).collect();
    let steady = |offset: &[f64]| {
        (0..n).all(|k| {
            let next = if k + 1 < n {
                offset[k + 1] + arc[k + 1]
            } else {
                offset[0] + arc[n]
            };
            next - (offset[k] + arc[k]) >= 0.5 * (arc[k + 1] - arc[k])
        })
    };
    let mut sweeps = 0;
    while !steady(&offset) {
        if sweeps == 4 * n {
            let mean = offset.iter().sum::<f64>() / n as f64;
            offset.iter_mut().for_each(|o| *o = mean);
            break;
        }
        let previous = offset.clone();
        for k in 0..n {
            offset[k] =
                0.25 * previous[(k + n - 1) % n] + 0.5 * previous[k] + 0.25 * previous[(k + 1) % n];
        }
        sweeps += 1;
    }
    Some((
        (0..n).map(|k| b.at(offset[k] + arc[k])).collect(),
        RimTargets::Projected,
    ))
}

/// Carries the hole rims of A onto the paired rims of B (module documentation).
/// `images[v]` is where φ puts vertex v of A, in B's UV; moved in place. `rings` 0 turns
/// the step off.
pub fn fit_hole_rims(
    a: &MatchSurface,
    b: &MatchSurface,
    images: &mut [[f64; 2]],
    rings: usize,
) -> RimFit {
    let mut fit = RimFit::default();
    let n = images.len();
    if rings == 0 || n != a.uvs.len() {
        return fit;
    }
    let (rims_a, rims_b) = (a.hole_rims(), b.hole_rims());
    if rims_a.is_empty() || rims_b.is_empty() {
        return fit;
    }
    let y: Vec<DVec2> = images.iter().map(|&p| DVec2::from_array(p)).collect();
    let polygons: Vec<RimPolygon> = rims_b.iter().map(|r| RimPolygon::new(b, r)).collect();
    // Pairing, closest centres first.
    let mut candidates = vec![];
    for (i, rim) in rims_a.iter().enumerate() {
        let centre = rim.iter().map(|&v| y[v as usize]).sum::<DVec2>() / rim.len().max(1) as f64;
        for (j, polygon) in polygons.iter().enumerate() {
            let distance = centre.distance(polygon.centre());
            if distance < polygon.mean_radius() {
                candidates.push((distance, i, j));
            }
        }
    }
    candidates.sort_by(|x, y| x.0.total_cmp(&y.0));
    let (mut used_a, mut used_b) = (vec![false; rims_a.len()], vec![false; rims_b.len()]);
    // Dirichlet values: the rims' displacements.
    let mut fixed: Vec<Option<DVec2>> = vec![None; n];
    // Per vertex: the band width (rings) of the rim it is on.
    let mut width = vec![0usize; n];
    for (_, i, j) in candidates {
        if used_a[i] || used_b[j] {
            continue;
        }
        used_a[i] = true;
        used_b[j] = true;
        match rim_targets(a, &rims_a[i], &y, &polygons[j]) {
            Some((targets, how)) => {
                let rim = &rims_a[i];
                let edge = (0..rim.len())
                    .map(|k| y[rim[k] as usize].distance(y[rim[(k + 1) % rim.len()] as usize]))
                    .sum::<f64>()
                    / rim.len() as f64;
                let largest = rim
                    .iter()
                    .zip(&targets)
                    .map(|(&v, t)| t.distance(y[v as usize]))
                    .fold(0.0, f64::max);
                let rings_here = if edge > 0.0 {
                    rings.max(
                        ((RINGS_PER_EDGE_MOVED * largest / edge).ceil() as usize).min(MAX_RINGS),
                    )
                } else {
                    rings
                };
                for (&v, t) in rim.iter().zip(targets) {
                    fixed[v as usize] = Some(t - y[v as usize]);
                    width[v as usize] = rings_here;
                }
                fit.holes += 1;
                if how == RimTargets::ArcLength {
                    fit.by_arc_length += 1;
                }
            }
            None => fit.skipped += 1,
        }
    }
    if fit.holes == 0 {
        return fit;
    }
    // The band: the vertices within their rim's width (in rings) of a fitted rim.
    let mesh = TriMesh::new(a.positions.clone(), a.triangles.clone());
    let topology = Topology::new(&mesh);
    let (ring_start, ring_list) = compressed_rows(
        n,
        topology
            .edges
            .iter()
            .flat_map(|e| [(e[0], e[1]), (e[1], e[0])]),
    );
    let neighbours = |v: usize| &ring_list[ring_start[v] as usize..ring_start[v + 1] as usize];
    let mut distance = vec![usize::MAX; n];
    let mut queue: std::collections::VecDeque<usize> =
        (0..n).filter(|&v| fixed[v].is_some()).collect();
    for &v in &queue {
        distance[v] = 0;
    }
    while let Some(v) = queue.pop_front() {
        if distance[v] >= width[v] {
            continue;
        }
        for &u in neighbours(v) {
            if distance[u as usize] == usize::MAX {
                distance[u as usize] = distance[v] + 1;
                width[u as usize] = width[v];
                queue.push_back(u as usize);
            }
        }
    }
    let widest = width.iter().copied().max().unwrap_or(0);
    let band: Vec<usize> = (0..n)
        .filter(|&v| (1..=width[v]).contains(&distance[v]))
        .collect();
    let mut displacement: Vec<DVec2> = fixed.iter().map(|d| d.unwrap_or(DVec2::ZERO)).collect();
    for _ in 0..SWEEPS_PER_RING * widest {
        for &v in &band {
            let ring = neighbours(v);
            displacement[v] = ring
                .iter()
                .map(|&u| displacement[u as usize])
                .sum::<DVec2>()
                / ring.len() as f64;
        }
    }
    let mut moved: Vec<DVec2> = (0..n).map(|v| y[v] + displacement[v]).collect();
    let mut on_boundary = vec![false; n];
    for l in &topology.boundary_loops {
        for &v in &l.vertices {
            on_boundary[v as usize] = true;
        }
    }
    // The band's inner vertices placed by the mean-value map with these positions as
    // boundary values: the rim's targets, φ's images beyond the band, A's other boundary
    // vertices where the displacement put them.
    // (A's UV triangles come from a flip-free flattening; should one be degenerate, the
    // band keeps the displacement's positions.)
    let inner: Vec<usize> = band.iter().copied().filter(|&v| !on_boundary[v]).collect();
    let uv3: Vec<[f64; 3]> = a.uvs.iter().map(|&[u, v]| [u, v, 0.0]).collect();
    let start: Vec<[f64; 2]> = moved.iter().map(|p| p.to_array()).collect();
    if let Ok(placed) = mean_value_with_fixed(&uv3, &a.triangles, start, &inner) {
        for &v in &inner {
            moved[v] = DVec2::from_array(placed[v]);
        }
    }
    for v in (0..n).filter(|&v| distance[v] <= width[v]) {
        images[v] = moved[v].to_array();
        fit.moved += 1;
    }
    fit
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matching::options::RIM_FIT_RINGS;
    use crate::mesh::generate::bumpy_disc;
    use crate::testing::crop;

    /// A bumpy disc with a round hole, as a match surface (flattened with the hole
    /// filled); also the hole's centre in its UV and the mean edge length in UV.
    fn holed_surface() -> (MatchSurface, DVec2, f64) {
        let disc = bumpy_disc(20, 0.3);
        let (mesh, _) = crop(&disc, |p| (p[0] - 0.15).hypot(p[1] - 0.05) > 0.3);
        let unit = mesh.area().sqrt();
        let surface = MatchSurface::new(&mesh, None, 65, true, unit).unwrap();
        let rim = &surface.hole_rims()[0];
        let centre = rim
            .iter()
            .map(|&v| DVec2::from_array(surface.uvs[v as usize]))
            .sum::<DVec2>()
            / rim.len() as f64;
        let edge = surface
            .triangles
            .iter()
            .flat_map(|t| (0..3).map(move |k| [t[k], t[(k + 1) % 3]]))
            .map(|[u, v]| {
                DVec2::from_array(surface.uvs[u as usize])
                    .distance(DVec2::from_array(surface.uvs[v as usize]))
            })
            .sum::<f64>()
            / (3 * surface.triangles.len()) as f64;
        (surface, centre, edge)
    }

    /// Signed areas of the surface's triangles at the given UV positions.
    fn signed_areas(surface: &MatchSurface, uv: &[[f64; 2]]) -> Vec<f64> {
        surface
            .triangles
            .iter()
            .map(|t| {
                let [p, q, r] = t.map(|v| DVec2::from_array(uv[v as usize]));
                0.5 * (q - p).perp_dot(r - p)
            })
            .collect()
    }

    fn distance(p: [f64; 2], q: [f64; 2]) -> f64 {
        DVec2::from_array(p).distance(DVec2::from_array(q))
    }

    #[test]
    fn the_rim_polygon_walks_its_own_arc_length() {
        let (surface, _, _) = holed_surface();
        let rim = &surface.hole_rims()[0];
        let polygon = RimPolygon::new(&surface, rim);
        assert!(polygon.length() > 0.0);
        for (k, &v) in rim.iter().enumerate() {
            // A vertex of the rim sits at its own arc length, and projects there.
            let at = polygon.at(polygon.cumulative[k]);
            assert!(at.distance(DVec2::from_array(surface.uvs[v as usize])) < 1e-12);
            let s = polygon.project(at);
            assert!(wrap(s - polygon.cumulative[k], polygon.length()).abs() < 1e-9);
        }
        // Past the end it wraps around.
        let whole = polygon.at(polygon.length() + polygon.cumulative[1]);
        assert!(whole.distance(polygon.uv[1]) < 1e-12);
    }

    /// φ's images with the hole's neighbourhood pulled toward the hole's centre (as φ
    /// carries A's rim into B's fill): the rim moves in by `pull` at the rim, fading to
    /// nothing `fade` away from it. Returns the images.
    fn pulled_in(surface: &MatchSurface, centre: DVec2, pull: f64, fade: f64) -> Vec<[f64; 2]> {
        let rim = &surface.hole_rims()[0];
        let radius = rim
            .iter()
            .map(|&v| DVec2::from_array(surface.uvs[v as usize]).distance(centre))
            .sum::<f64>()
            / rim.len() as f64;
        surface
            .uvs
            .iter()
            .map(|&uv| {
                let p = DVec2::from_array(uv);
                let r = p.distance(centre);
                let weight = (1.0 - (r - radius).max(0.0) / fade).max(0.0);
                (p + pull * weight * (centre - p) / r).to_array()
            })
            .collect()
    }

    #[test]
    fn a_rim_carried_into_the_fill_is_put_back_on_its_own_rim() {
        // A against itself: every vertex's true image is its own UV. The images of the
        // rim are pulled a mesh edge into the hole; the fit must put the rim back on the
        // rim, bring the band back toward the truth and turn no triangle over.
        let (surface, centre, edge) = holed_surface();
        let truth = surface.uvs.clone();
        let mut images = pulled_in(&surface, centre, edge, 6.0 * edge);
        let before = images.clone();
        let fit = fit_hole_rims(&surface, &surface, &mut images, RIM_FIT_RINGS);
        assert_eq!((fit.holes, fit.by_arc_length, fit.skipped), (1, 0, 0));
        let rim = &surface.hole_rims()[0];
        let polygon = RimPolygon::new(&surface, rim);
        for &v in rim {
            let y = DVec2::from_array(images[v as usize]);
            // On B's rim...
            let on = polygon.at(polygon.project(y));
            assert!(
                on.distance(y) < 1e-9 * edge.max(1.0),
                "vertex {v} off the rim"
            );
        }
        // ...near its own place: a point pulled straight in projects back onto the
        // rim's nearest edge, which on a jagged rim may be the next one over.
        let errors: Vec<f64> = rim
            .iter()
            .map(|&v| distance(images[v as usize], truth[v as usize]) / edge)
            .collect();
        let mean = errors.iter().sum::<f64>() / errors.len() as f64;
        let largest = errors.iter().copied().fold(0.0, f64::max);
        assert!(
            mean < 0.25 && largest < 0.6,
            "rim errors (edges): mean {mean}, largest {largest}"
        );
        let total =
            |y: &[[f64; 2]]| -> f64 { (0..y.len()).map(|v| distance(y[v], truth[v])).sum() };
        assert!(
            total(&images) < 0.4 * total(&before),
            "error {} → {}",
            total(&before),
            total(&images)
        );
        let (was, now) = (
            signed_areas(&surface, &truth),
            signed_areas(&surface, &images),
        );
        assert!(
            was.iter().zip(&now).all(|(a, b)| a * b > 0.0),
            "a triangle turned over"
        );
        // Vertices beyond the band are not touched.
        assert!(fit.moved < images.len());
        let untouched = (0..images.len())
            .filter(|&v| images[v] == before[v])
            .count();
        assert_eq!(untouched + fit.moved, images.len());
    }

    #[test]
    fn images_folded_against_the_rim_are_straightened() {
        // The rim pushed two edges out, into B's surface, fading out within one edge:
        // the rim's images cross the next ring's and the triangles between turn over.
        // The harmonic displacement alone would carry the folds along; the mean-value
        // map must leave none.
        let (surface, centre, edge) = holed_surface();
        let truth = surface.uvs.clone();
        let mut images = pulled_in(&surface, centre, -2.0 * edge, edge);
        let turned = |y: &[[f64; 2]]| -> usize {
            let (was, now) = (signed_areas(&surface, &truth), signed_areas(&surface, y));
            was.iter().zip(&now).filter(|(a, b)| *a * *b <= 0.0).count()
        };
        assert!(turned(&images) > 0, "the set-up must fold");
        let fit = fit_hole_rims(&surface, &surface, &mut images, RIM_FIT_RINGS);
        assert_eq!(fit.holes, 1);
        assert_eq!(turned(&images), 0);
        let largest = (0..images.len())
            .map(|v| distance(images[v], truth[v]))
            .fold(0.0, f64::max);
        assert!(largest < edge, "largest error {largest} (edge {edge})");
    }

    #[test]
    fn a_rim_squashed_to_a_slit_is_spread_by_arc_length() {
        // The rim's images squashed onto a line through the hole (a closed mouth carried
        // into an open one): they do not wind around B's hole, so B's rim is taken at
        // A's arc length from the best offset — here the true one, A being B.
        let (surface, centre, edge) = holed_surface();
        let truth = surface.uvs.clone();
        let rim = surface.hole_rims()[0].clone();
        let mut images = truth.clone();
        for &v in &rim {
            images[v as usize][1] = centre.y;
        }
        let fit = fit_hole_rims(&surface, &surface, &mut images, RIM_FIT_RINGS);
        assert_eq!((fit.holes, fit.by_arc_length), (1, 1));
        for &v in &rim {
            let error = distance(images[v as usize], truth[v as usize]);
            assert!(error < 0.35 * edge, "rim vertex {v}: {error} (edge {edge})");
        }
        // The rim moved by about the hole's radius: the band widened beyond the default.
        let band = (0..truth.len())
            .filter(|&v| !rim.contains(&(v as u32)) && images[v] != truth[v])
            .count();
        assert!(fit.moved > rim.len() + band / 2 && band > 0);
    }

    #[test]
    fn images_that_already_match_are_left_where_they_are() {
        // φ exact (A against itself, images = A's UV): the rim is on B's rim already, its
        // displacement is 0, and the mean-value weights reproduce the (identity) map, so
        // nothing moves beyond rounding; the same for an affine map of a copy of B.
        let (surface, _, edge) = holed_surface();
        let mut images = surface.uvs.clone();
        let fit = fit_hole_rims(&surface, &surface, &mut images, RIM_FIT_RINGS);
        assert_eq!((fit.holes, fit.by_arc_length), (1, 0));
        assert!(fit.moved > 0);
        let moved = (0..images.len())
            .map(|v| distance(images[v], surface.uvs[v]))
            .fold(0.0, f64::max);
        assert!(moved < 1e-9 * edge, "moved {moved} (edge {edge})");
        // B's plane an affine image of A's (sheared, turned, moved), φ that map.
        let affine = |[u, v]: [f64; 2]| [1.3 * u + 0.4 * v + 2.0, -0.2 * u + 0.9 * v - 1.0];
        let mut b = surface.clone();
        b.uvs = surface.uvs.iter().map(|&p| affine(p)).collect();
        let mut images = b.uvs.clone();
        let fit = fit_hole_rims(&surface, &b, &mut images, RIM_FIT_RINGS);
        assert_eq!((fit.holes, fit.by_arc_length), (1, 0));
        let moved = (0..images.len())
            .map(|v| distance(images[v], b.uvs[v]))
            .fold(0.0, f64::max);
        assert!(moved < 1e-9 * edge, "affine: moved {moved} (edge {edge})");
    }

    #[test]
    fn a_hole_whose_images_are_elsewhere_is_left_alone() {
        // Images of the rim farther from B's hole than its radius: no pairing, nothing
        // moved; and 0 rings turns the fit off.
        let (surface, centre, _) = holed_surface();
        let rim = &surface.hole_rims()[0];
        let radius = RimPolygon::new(&surface, rim).mean_radius();
        let shifted: Vec<[f64; 2]> = surface
            .uvs
            .iter()
            .map(|&[u, v]| [u + 3.0 * radius, v])
            .collect();
        let mut images = shifted.clone();
        let fit = fit_hole_rims(&surface, &surface, &mut images, RIM_FIT_RINGS);
        assert_eq!(fit, RimFit::default());
        assert_eq!(images, shifted);
        let mut images = pulled_in(&surface, centre, 0.01, 0.1);
        let before = images.clone();
        assert_eq!(
            fit_hole_rims(&surface, &surface, &mut images, 0),
            RimFit::default()
        );
        assert_eq!(images, before);
    }
}
