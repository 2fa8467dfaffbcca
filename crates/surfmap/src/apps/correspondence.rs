//! Correspondences `A → B` as plain data (`&[Option<SurfacePoint>]`, one entry per vertex
//! of A): checking one against its meshes, carrying any point of A through it, composing
//! two of them, and measuring how far two maps are apart.
//!
//! **Points that are not vertices.** A correspondence fixes the image of every vertex of
//! A; a point `p = Σm λm·a_m` inside a triangle `(a_0, a_1, a_2)` of A is mapped
//! piecewise-linearly *in a parameter domain of B*: with a flip-free flattening
//! `u_B: B → ℝ²` (a [`Chart`]),
//!
//! ```text
//! φ(p) = u_B⁻¹( Σm λm · u_B(φ(a_m)) )
//! ```
//!
//! This is the discrete form of the thesis's `φ_M = x_B ∘ φ ∘ x_A⁻¹` (§5.2) when the
//! deformation `φ` of the parameter plane is interpolated linearly over A's triangles.
//! When the three images lie in one triangle of B the combination is taken there
//! exactly (no chart needed, and any chart gives the same point). Otherwise the chart is
//! needed; a chart other than the matcher's own flattening of B moves the result by a
//! second-order amount in the spacing of A's vertices. A combination that falls just
//! outside B's flattened domain (a concave stretch of the boundary, a hole) is clamped
//! to the nearest point of the domain if that is no farther than the images are from it.
//!
//! **Composition** (thesis §5.3): with `φ_AB: A → B` and `φ_BC: B → C`, the map
//! `φ_BC ∘ φ_AB` sends vertex `a` of A to `φ_BC(φ_AB(a))`, where `φ_AB(a)` is a point of
//! B (not a vertex) carried through `φ_BC` as above, in a chart of C. A vertex is
//! unmatched in the composition when it is unmatched in `φ_AB`, or when a corner of its
//! image triangle on B with a non-zero weight is unmatched in `φ_BC`.

use rayon::prelude::*;

use super::AppError;
use crate::mesh::{PointLocator, SurfacePoint};

/// Largest tolerated deviation of barycentric coordinates from a point of the triangle
/// (each `≥ −TOL`, `|Σ − 1| ≤ TOL`) in [`check_correspondence`].
pub const BARYCENTRIC_TOLERANCE: f64 = 1e-6;

/// Checks a correspondence `A → B`: one entry per vertex of A, triangles of B, and
/// barycentric coordinates that name a point of their triangle (finite, each
/// `≥ −1e-6`, sum within `1e-6` of 1).
pub fn check_correspondence(
    points: &[Option<SurfacePoint>],
    num_vertices_a: usize,
    num_triangles_b: usize,
) -> Result<(), AppError> {
    if points.len() != num_vertices_a {
        return Err(AppError::CorrespondenceLength {
            got: points.len(),
            expected: num_vertices_a,
        });
    }
    for (vertex, p) in points.iter().enumerate() {
        let Some(p) = p else { continue };
        if p.triangle as usize >= num_triangles_b {
            return Err(AppError::CorrespondenceTriangle {
                vertex,
                triangle: p.triangle,
                num_triangles: num_triangles_b,
            });
        }
        let b = p.barycentric;
        let sum: f64 = b.iter().sum();
        let ok = b
            .iter()
            .all(|x| x.is_finite() && *x >= -BARYCENTRIC_TOLERANCE)
            && (sum - 1.0).abs() <= BARYCENTRIC_TOLERANCE;
        if !ok {
            return Err(AppError::CorrespondenceBarycentric {
                vertex,
                barycentric: b,
            });
        }
    }
    Ok(())
}

/// How many vertices of A have a counterpart.
pub fn matched_count(points: &[Option<SurfacePoint>]) -> usize {
    points.iter().filter(|p| p.is_some()).count()
}

/// The 3D position on B of every vertex of A (`None` where unmatched).
pub fn image_positions(
    points: &[Option<SurfacePoint>],
    positions_b: &[[f64; 3]],
    triangles_b: &[[u32; 3]],
) -> Vec<Option<[f64; 3]>> {
    points
        .iter()
        .map(|p| p.map(|p| p.position(positions_b, triangles_b)))
        .collect()
}

/// A parameter domain of a surface: a flip-free flattening (one UV per vertex) with a
/// point locator, through which points of the surface are combined linearly (see the
/// [module documentation](self)).
#[derive(Clone, Debug)]
pub struct Chart {
    uvs: Vec<[f64; 2]>,
    triangles: Vec<[u32; 3]>,
    locator: PointLocator,
}

impl Chart {
    /// A chart from a flattening of the surface (`uvs[i]` for vertex `i`) and its
    /// triangles. Fails when the locator cannot be built (no triangles, UVs that are
    /// not finite, a UV list that does not fit the triangles).
    pub fn new(uvs: Vec<[f64; 2]>, triangles: Vec<[u32; 3]>) -> Result<Self, AppError> {
        let locator = PointLocator::new(&uvs, &triangles)?;
        Ok(Self {
            uvs,
            triangles,
            locator,
        })
    }

    /// The surface's triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The flattening, one UV per vertex.
    pub fn uvs(&self) -> &[[f64; 2]] {
        &self.uvs
    }

    /// The UV of a point of the surface.
    #[inline]
    pub fn uv(&self, p: &SurfacePoint) -> [f64; 2] {
        p.interpolate(&self.uvs, &self.triangles)
    }

    /// The point of the surface at `uv`, or the domain's nearest point when `uv` is
    /// outside by at most `reach`; `None` otherwise.
    #[inline]
    pub fn locate(&self, uv: [f64; 2], reach: f64) -> Option<SurfacePoint> {
        if let Some(p) = self.locator.locate(uv) {
            return Some(p);
        }
        self.locator
            .nearest(uv)
            .filter(|n| n.distance <= reach)
            .map(|n| n.point)
    }

    /// The weighted combination `u⁻¹(Σ w_k · u(p_k))` of points of the surface, weights
    /// summing to 1. When every point lies in one triangle the barycentric coordinates
    /// are combined there directly (exact, no location); otherwise the UV is located, and
    /// when it falls outside the domain it is clamped onto it if that is no farther than
    /// the farthest point `p_k` (with a non-zero weight) is from it.
    pub fn combine(&self, points: &[(f64, SurfacePoint)]) -> Option<SurfacePoint> {
        let first = points.first()?.1.triangle;
        if points.iter().all(|(_, p)| p.triangle == first) {
            let mut barycentric = [0.0; 3];
            for (w, p) in points {
                for (b, x) in barycentric.iter_mut().zip(p.barycentric) {
                    *b += w * x;
                }
            }
            return Some(SurfacePoint {
                triangle: first,
                barycentric,
            });
        }
        let mut uv = [0.0; 2];
        for (w, p) in points {
            let q = self.uv(p);
            uv = [uv[0] + w * q[0], uv[1] + w * q[1]];
        }
        let reach = points
            .iter()
            .filter(|(w, _)| *w != 0.0)
            .map(|(_, p)| {
                let q = self.uv(p);
                (q[0] - uv[0]).hypot(q[1] - uv[1])
            })
            .fold(0.0, f64::max);
        self.locate(uv, reach)
    }
}

/// The image under `ab: A → B` of a point `p` of A (a triangle of `triangles_a` and
/// barycentric coordinates): the images of the triangle's corners combined with `p`'s
/// weights in the chart of B ([`Chart::combine`]). `None` when a corner with a non-zero
/// weight is unmatched.
///
/// Panics if `p.triangle` is not a triangle of `triangles_a` or a corner has no entry
/// in `ab` (check the correspondence first with [`check_correspondence`]).
pub fn push_point(
    p: SurfacePoint,
    triangles_a: &[[u32; 3]],
    ab: &[Option<SurfacePoint>],
    chart_b: &Chart,
) -> Option<SurfacePoint> {
    let tri = triangles_a[p.triangle as usize];
    let mut weighted = [(
        0.0,
        SurfacePoint {
            triangle: 0,
            barycentric: [0.0; 3],
        },
    ); 3];
    let mut n = 0;
    for (m, &v) in tri.iter().enumerate() {
        let w = p.barycentric[m];
        if w == 0.0 {
            continue;
        }
        weighted[n] = (w, ab[v as usize]?);
        n += 1;
    }
    chart_b.combine(&weighted[..n])
}

/// The composed correspondence `φ_BC ∘ φ_AB: A → C` (thesis §5.3; defined in the
/// [module documentation](self)): every vertex image of `ab` (a point of B, a triangle
/// of `triangles_b`) carried through `bc` in the chart of C.
pub fn compose(
    ab: &[Option<SurfacePoint>],
    triangles_b: &[[u32; 3]],
    bc: &[Option<SurfacePoint>],
    chart_c: &Chart,
) -> Result<Vec<Option<SurfacePoint>>, AppError> {
    check_correspondence(ab, ab.len(), triangles_b.len())?;
    let num_b = triangles_b
        .iter()
        .flatten()
        .map(|&v| v as usize + 1)
        .max()
        .unwrap_or(0);
    if bc.len() < num_b {
        return Err(AppError::CorrespondenceLength {
            got: bc.len(),
            expected: num_b,
        });
    }
    check_correspondence(bc, bc.len(), chart_c.triangles().len())?;
    Ok(ab
        .par_iter()
        .with_min_len(1024)
        .map(|p| p.and_then(|p| push_point(p, triangles_b, bc, chart_c)))
        .collect())
}

/// How far two maps `A → C` are apart: 3D distances on C between the images of each
/// vertex of A that both maps match.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MapDistance {
    /// Vertices matched by both maps (the distances below are over these).
    pub compared: usize,
    /// Vertices matched by the first map only, by the second only.
    pub only_first: usize,
    pub only_second: usize,
    /// Mean, 95th percentile and largest Euclidean distance between the two images,
    /// in C's units.
    pub mean: f64,
    pub p95: f64,
    pub max: f64,
    /// `√area(C)`, the scale the distances are usually divided by (as the matching
    /// benchmarks do).
    pub sqrt_area: f64,
}

/// The distances between the images of the two maps `first, second: A → C` on C (a
/// straight-line distance, which for nearby points on a smooth surface is the geodesic
/// one to second order).
pub fn compare_maps(
    first: &[Option<SurfacePoint>],
    second: &[Option<SurfacePoint>],
    positions_c: &[[f64; 3]],
    triangles_c: &[[u32; 3]],
) -> Result<MapDistance, AppError> {
    check_correspondence(second, first.len(), triangles_c.len())?;
    check_correspondence(first, first.len(), triangles_c.len())?;
    crate::mesh::check_indices(triangles_c, positions_c.len())?;
    let mut distances = Vec::with_capacity(first.len());
    let (mut only_first, mut only_second) = (0, 0);
    for (p, q) in first.iter().zip(second) {
        match (p, q) {
            (Some(p), Some(q)) => {
                let (x, y) = (
                    p.position(positions_c, triangles_c),
                    q.position(positions_c, triangles_c),
                );
                distances.push(crate::vec3::norm3(crate::vec3::sub3(x, y)));
            }
            (Some(_), None) => only_first += 1,
            (None, Some(_)) => only_second += 1,
            (None, None) => {}
        }
    }
    let (mean, p95, max) = summary(&mut distances);
    let area: f64 = (0..triangles_c.len())
        .map(|t| {
            let [a, b, c] = triangles_c[t].map(|v| positions_c[v as usize]);
            0.5 * crate::vec3::norm3(crate::vec3::cross3(
                crate::vec3::sub3(b, a),
                crate::vec3::sub3(c, a),
            ))
        })
        .sum();
    Ok(MapDistance {
        compared: distances.len(),
        only_first,
        only_second,
        mean,
        p95,
        max,
        sqrt_area: area.sqrt(),
    })
}

/// Mean, 95th percentile (nearest rank) and maximum of the values (reordered); NaN for
/// none.
pub(crate) fn summary(values: &mut [f64]) -> (f64, f64, f64) {
    if values.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    values.sort_unstable_by(f64::total_cmp);
    let n = values.len();
    let mean = values.iter().sum::<f64>() / n as f64;
    let rank = ((0.95 * n as f64).ceil() as usize).clamp(1, n);
    (mean, values[rank - 1], values[n - 1])
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::mesh::TriMesh;

    pub use crate::apps::inputs::planar_chart;

    /// The correspondence of every vertex of `a` to the point of `b` over `f(x, y)`
    /// (both graphs over the plane): an analytic map between two triangulations.
    pub fn analytic_map(
        a: &TriMesh,
        b: &TriMesh,
        f: impl Fn([f64; 2]) -> [f64; 2],
    ) -> Vec<Option<SurfacePoint>> {
        crate::apps::inputs::planar_map(a, b, f, |_, _| true)
    }

    /// A graph `z = h(x, y)` over `[−1, 1]²`, `n × n` squares, interior vertices jittered.
    pub fn graph_mesh(n: usize, jitter: f64, seed: u64, h: impl Fn(f64, f64) -> f64) -> TriMesh {
        crate::apps::inputs::graph(n, 1.0, jitter, seed, h)
    }

    fn bump(x: f64, y: f64) -> f64 {
        0.3 * (1.5 * x).sin() * (1.2 * y).cos()
    }

    #[test]
    fn check_names_the_defect() {
        let p = |t, b| {
            Some(SurfacePoint {
                triangle: t,
                barycentric: b,
            })
        };
        assert!(check_correspondence(&[p(1, [0.2, 0.3, 0.5]), None], 2, 2).is_ok());
        let e = check_correspondence(&[None], 2, 2).unwrap_err();
        assert!(
            matches!(
                e,
                AppError::CorrespondenceLength {
                    got: 1,
                    expected: 2
                }
            ),
            "{e}"
        );
        let e = check_correspondence(&[None, p(2, [1.0, 0.0, 0.0])], 2, 2).unwrap_err();
        assert!(matches!(
            e,
            AppError::CorrespondenceTriangle {
                vertex: 1,
                triangle: 2,
                ..
            }
        ));
        for bad in [[0.5, 0.6, 0.0], [-0.1, 0.6, 0.5], [f64::NAN, 0.5, 0.5]] {
            let e = check_correspondence(&[p(0, bad), None], 2, 2).unwrap_err();
            assert!(
                matches!(e, AppError::CorrespondenceBarycentric { vertex: 0, .. }),
                "{e}"
            );
        }
    }

    #[test]
    fn pushing_points_of_a_linear_map_is_exact() {
        // B is A's domain mapped by an affine map; the correspondence of A's vertices
        // is exact, and so must be the image of any point of A.
        let a = graph_mesh(8, 0.6, 3, |_, _| 0.0);
        let b = graph_mesh(11, 0.6, 5, |_, _| 0.0);
        let f = |p: [f64; 2]| {
            [
                0.7 * p[0] + 0.1 * p[1] + 0.05,
                -0.2 * p[0] + 0.6 * p[1] - 0.1,
            ]
        };
        let ab = analytic_map(&a, &b, f);
        assert_eq!(matched_count(&ab), a.num_vertices());
        let chart = planar_chart(&b);
        let mut rng = crate::testing::Rng(9);
        for _ in 0..500 {
            let t = rng.below(a.num_triangles());
            let (s, r) = (rng.uniform(), rng.uniform());
            let (s, r) = if s + r > 1.0 {
                (1.0 - s, 1.0 - r)
            } else {
                (s, r)
            };
            let p = SurfacePoint {
                triangle: t as u32,
                barycentric: [1.0 - s - r, s, r],
            };
            let x = p.position(&a.positions, &a.triangles);
            let q = push_point(p, &a.triangles, &ab, &chart).expect("inside");
            let y = q.position(&b.positions, &b.triangles);
            let want = f([x[0], x[1]]);
            assert!((y[0] - want[0]).abs() < 1e-12 && (y[1] - want[1]).abs() < 1e-12);
        }
    }

    #[test]
    fn composition_of_analytic_maps_is_the_analytic_composition() {
        // Three different triangulations of curved graphs; f: A → B and g: B → C are
        // smooth maps of the domain, so g ∘ f is known. The composed correspondence
        // agrees with the direct one up to linear interpolation error (O(h²)), and the
        // error shrinks by about 4× when the meshes are refined by 2×.
        let f = |p: [f64; 2]| [0.8 * p[0] + 0.1 * p[1] * p[1], 0.8 * p[1] + 0.05 * p[0]];
        let g = |p: [f64; 2]| {
            [
                0.9 * p[0] + 0.05 * (2.0 * p[1]).sin(),
                0.9 * p[1] - 0.05 * p[0] * p[0],
            ]
        };
        let mut errors = vec![];
        for n in [10, 20] {
            let a = graph_mesh(n, 0.5, 1, bump);
            let b = graph_mesh(n + 3, 0.5, 2, bump);
            let c = graph_mesh(n + 1, 0.5, 4, bump);
            let ab = analytic_map(&a, &b, f);
            let bc = analytic_map(&b, &c, g);
            let ac = analytic_map(&a, &c, |p| g(f(p)));
            let composed = compose(&ab, &b.triangles, &bc, &planar_chart(&c)).unwrap();
            assert_eq!(matched_count(&composed), a.num_vertices());
            let d = compare_maps(&composed, &ac, &c.positions, &c.triangles).unwrap();
            assert_eq!(
                (d.compared, d.only_first, d.only_second),
                (a.num_vertices(), 0, 0)
            );
            let h = 2.0 / n as f64;
            assert!(d.max < 0.05 * h, "n {n}: max {:e} vs spacing {h}", d.max);
            errors.push(d.max);
        }
        assert!(
            errors[1] < 0.4 * errors[0],
            "no second-order convergence: {errors:?}"
        );
    }

    #[test]
    fn composition_leaves_unmatched_what_either_map_leaves_unmatched() {
        let a = graph_mesh(6, 0.3, 1, bump);
        let b = graph_mesh(7, 0.3, 2, bump);
        let c = graph_mesh(5, 0.3, 3, bump);
        let ab = analytic_map(&a, &b, |p| p);
        let mut bc = analytic_map(&b, &c, |p| p);
        // Unmatch one vertex of B: every A vertex whose image uses it with a non-zero
        // weight is unmatched in the composition, no other.
        let hole = 20usize;
        bc[hole] = None;
        let composed = compose(&ab, &b.triangles, &bc, &planar_chart(&c)).unwrap();
        for (i, (p, q)) in ab.iter().zip(&composed).enumerate() {
            let p = p.unwrap();
            let uses = b.triangles[p.triangle as usize]
                .iter()
                .zip(p.barycentric)
                .any(|(&v, w)| v as usize == hole && w != 0.0);
            assert_eq!(q.is_none(), uses, "vertex {i}");
        }
        let d = compare_maps(
            &composed,
            &analytic_map(&a, &c, |p| p),
            &c.positions,
            &c.triangles,
        )
        .unwrap();
        assert_eq!(d.only_second, a.num_vertices() - d.compared);
        assert!(d.only_second > 0);
    }

    #[test]
    fn summary_uses_nearest_rank() {
        let mut v: Vec<f64> = (1..=100).rev().map(f64::from).collect();
        assert_eq!(summary(&mut v), (50.5, 95.0, 100.0));
        let mut one = [3.0];
        assert_eq!(summary(&mut one), (3.0, 3.0, 3.0));
        assert!(summary(&mut []).0.is_nan());
    }
}
