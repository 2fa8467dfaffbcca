//! Fixed-boundary initial maps onto a convex polygon: mean-value coordinates
//! (M. Floater, *Mean value coordinates*, CAGD 2003) and the uniform Tutte embedding.
//!
//! Every interior vertex `i` is placed at a convex combination of its neighbours,
//! `Σ_j w_ij (u_i − u_j) = 0` with `w_ij > 0`, while the boundary loop is fixed on a
//! convex curve. By Tutte's and Floater's theorems the result is injective (no flipped
//! triangles) for any disc mesh when the boundary polygon is convex and (strictly)
//! every interior vertex has positive weights — which both weightings guarantee.
//! These are the fallback when the free-boundary conformal map of thesis §3.1.1
//! ([`super::lscm`]) is not admissible (flips a triangle).

use super::{InitialMapError, check_positions};
use crate::linsolve::{Unknowns, solve_general, solve_spd};
use crate::mesh::Disc;
use crate::vec3::{cross3, norm3 as norm, sub3 as sub};
use std::f64::consts::TAU;

/// The disc's boundary fixed on the unit circle by arc length: boundary vertex `k`
/// ([`Disc::boundary`]) goes to angle `2π s_k / L`, where `s_k` is the 3D length of the
/// loop from its first vertex to its `k`-th and `L` the total length. The loop has the
/// surface on its left, so the circle is run counter-clockwise and a map onto it
/// preserves orientation.
pub fn boundary_on_circle(
    positions: &[[f64; 3]],
    disc: &Disc,
) -> Result<Vec<[f64; 2]>, InitialMapError> {
    check_positions(positions, disc)?;
    circle_by_arc_length(positions, disc.boundary())
}

fn circle_by_arc_length(
    positions: &[[f64; 3]],
    boundary: &[u32],
) -> Result<Vec<[f64; 2]>, InitialMapError> {
    let b = boundary.len();
    let mut arc = Vec::with_capacity(b + 1);
    arc.push(0.0);
    for k in 0..b {
        let (p, q) = (
            positions[boundary[k] as usize],
            positions[boundary[(k + 1) % b] as usize],
        );
        let len = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
        arc.push(arc[k] + len);
    }
    let total = arc[b];
    if total <= 0.0 || !total.is_finite() {
        return Err(InitialMapError::DegenerateBoundary);
    }
    Ok(arc[..b]
        .iter()
        .map(|s| {
            let angle = TAU * s / total;
            [angle.cos(), angle.sin()]
        })
        .collect())
}

/// Mean-value map with the boundary on the unit circle by arc length
/// ([`boundary_on_circle`]); see [`mean_value_with_boundary`].
pub fn mean_value(positions: &[[f64; 3]], disc: &Disc) -> Result<Vec<[f64; 2]>, InitialMapError> {
    onto_circle(positions, disc, Weights::MeanValue)
}

/// Opens the ears of a fixed-boundary map onto a circle: an ear is a triangle `(b, a, c)`
/// with two boundary edges, its tip `b` a boundary vertex with no other face. With the
/// boundary on a circle by arc length its three corners are consecutive points of the
/// circle, so its area is about `ℓ³/8` (`ℓ` the arc between its ends on the unit
/// circle): where a cut's seam meets the boundary, 10⁻⁶ of a typical triangle's area,
/// and any step that moves `a` or `c` inward turns it over at once (measured: an ICT
/// face opened with seams, whose warm-start step was held to 2·10⁻³ of its length by
/// one ear). The tip is moved to its conformal position `a' + z (c' − a')`, `z = (b −
/// a)/(c − a)` taken in the 3D triangle's plane (the ear similar to its 3D shape): on
/// the far side of the chord `a'c'` from the circle's centre, outside the circle, so no
/// other face changes and the map stays flip-free. Kept only where the ear grows, and only if the boundary then
/// crosses itself nowhere (else the map is left as it was). Returns the ears opened.
pub fn open_ears(positions: &[[f64; 3]], disc: &Disc, uv: &mut [[f64; 2]]) -> usize {
    let boundary = disc.boundary();
    let mut faces_at = vec![0u32; uv.len()];
    let mut face_of = vec![u32::MAX; uv.len()];
    for (f, t) in disc.triangles().iter().enumerate() {
        for &v in t {
            faces_at[v as usize] += 1;
            face_of[v as usize] = f as u32;
        }
    }
    let before = uv.to_vec();
    let mut opened = 0;
    for &tip in boundary {
        if faces_at[tip as usize] != 1 {
            continue;
        }
        let mut ear = disc.triangles()[face_of[tip as usize] as usize];
        while ear[0] != tip {
            ear.rotate_left(1);
        }
        let Some(p) = super::multilevel::conformal_position(positions, uv, &[ear], tip) else {
            continue;
        };
        let area = super::signed_uv_area([p, uv[ear[1] as usize], uv[ear[2] as usize]]);
        if area > super::signed_uv_area(ear.map(|v| uv[v as usize])) && area.is_finite() {
            uv[tip as usize] = p;
            opened += 1;
        }
    }
    if opened > 0 && crate::measure::overlap::boundary_crossings(uv, boundary) > 0 {
        uv.copy_from_slice(&before);
        return 0;
    }
    opened
}

/// Mean-value coordinates (Floater 2003, eq. 5.1) with the boundary loop fixed at
/// `boundary_uv[k]` for `disc.boundary()[k]`:
///
/// `w_ij = (tan(δ_ij / 2) + tan(γ_ij / 2)) / ‖x_j − x_i‖`, where `δ_ij, γ_ij` are the 3D
/// angles at `x_i` of the two triangles sharing the edge `ij`, and every interior vertex
/// satisfies `Σ_j w_ij (u_i − u_j) = 0`. The weights are not symmetric, so the system is
/// solved by sparse LU ([`solve_general`]). `tan(α/2)` is evaluated as
/// `‖e1 × e2‖ / (‖e1‖‖e2‖ + e1·e2)`.
///
/// Linear precision: a planar mesh whose boundary is fixed at its own positions is
/// reproduced exactly. Injective when `boundary_uv` is a convex polygon.
pub fn mean_value_with_boundary(
    positions: &[[f64; 3]],
    disc: &Disc,
    boundary_uv: &[[f64; 2]],
) -> Result<Vec<[f64; 2]>, InitialMapError> {
    check_positions(positions, disc)?;
    solve_fixed_boundary(positions, disc, boundary_uv, Weights::MeanValue)
}

/// Uniform Tutte embedding (Tutte 1963): `w_ij = 1` for every edge, boundary on the unit
/// circle by arc length. The system is the graph Laplacian restricted to the interior
/// vertices: symmetric positive definite, solved by sparse Cholesky ([`solve_spd`]).
pub fn tutte_uniform(
    positions: &[[f64; 3]],
    disc: &Disc,
) -> Result<Vec<[f64; 2]>, InitialMapError> {
    onto_circle(positions, disc, Weights::Uniform)
}

/// The fixed-boundary map with the boundary on the unit circle by arc length.
fn onto_circle(
    positions: &[[f64; 3]],
    disc: &Disc,
    weights: Weights,
) -> Result<Vec<[f64; 2]>, InitialMapError> {
    check_positions(positions, disc)?;
    let boundary_uv = circle_by_arc_length(positions, disc.boundary())?;
    solve_fixed_boundary(positions, disc, &boundary_uv, weights)
}

#[derive(Clone, Copy, PartialEq)]
enum Weights {
    Uniform,
    MeanValue,
}

/// `tan(α/2)` for the angle `α` between `e1` and `e2`, or `None` if it is undefined
/// (zero-length edge or `α = π`).
fn tan_half_angle(e1: [f64; 3], e2: [f64; 3]) -> Option<f64> {
    let sin_part = norm(cross3(e1, e2));
    let (l1, l2) = (norm(e1), norm(e2));
    // Summed left to right (as `l1·l2 + e1·e2` term by term) on purpose: the start
    // map's bits, and so the flattening's iteration counts, depend on it.
    let denom = l1 * l2 + e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
    let t = sin_part / denom;
    (l1 > 0.0 && l2 > 0.0 && denom > 0.0 && t.is_finite()).then_some(t)
}

/// The boundary placed at `boundary_uv` and `Σ_j w_ij (u_i − u_j) = 0` solved for the
/// interior vertices ([`solve_with_fixed`]); positions already checked.
fn solve_fixed_boundary(
    positions: &[[f64; 3]],
    disc: &Disc,
    boundary_uv: &[[f64; 2]],
    weights: Weights,
) -> Result<Vec<[f64; 2]>, InitialMapError> {
    let (triangles, boundary) = (disc.triangles(), disc.boundary());
    if boundary_uv.len() != boundary.len() {
        return Err(InitialMapError::BoundaryUvCount {
            expected: boundary.len(),
            got: boundary_uv.len(),
        });
    }
    let n = positions.len();
    let mut uv = vec![[0.0; 2]; n];
    for (&v, &p) in boundary.iter().zip(boundary_uv) {
        uv[v as usize] = p;
    }
    let index = Unknowns::new(n, boundary.iter().map(|&v| v as usize));
    solve_with_fixed(positions, triangles, uv, &index, weights)
}

/// The mean-value map (weights from `positions`, as [`mean_value_with_boundary`]) that
/// moves only the vertices `free` and keeps every other vertex at its `uv`: solves
/// `Σ_j w_ij (u_i − u_j) = 0` for the free vertices. Each free vertex must have its whole
/// fan of triangles in `triangles` (an interior vertex), for linear precision.
pub(crate) fn mean_value_with_fixed(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    uv: Vec<[f64; 2]>,
    free: &[usize],
) -> Result<Vec<[f64; 2]>, InitialMapError> {
    let mut is_free = vec![false; positions.len()];
    free.iter().for_each(|&v| is_free[v] = true);
    let index = Unknowns::new(
        positions.len(),
        (0..positions.len()).filter(|&v| !is_free[v]),
    );
    solve_with_fixed(positions, triangles, uv, &index, Weights::MeanValue)
}

/// Assembles and solves `Σ_j w_ij (u_i − u_j) = 0` for the unknowns of `index`, the
/// other vertices fixed at their `uv`.
fn solve_with_fixed(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    mut uv: Vec<[f64; 2]>,
    index: &Unknowns,
    weights: Weights,
) -> Result<Vec<[f64; 2]>, InitialMapError> {
    let m = index.count();
    if m == 0 {
        return Ok(uv);
    }
    let mut triplets: Vec<(u32, u32, f64)> = Vec::with_capacity(9 * triangles.len());
    let (mut rhs_u, mut rhs_v) = (vec![0.0; m], vec![0.0; m]);
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (i, j, l) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            match weights {
                Weights::Uniform => {
                    // Each edge (i, j) is seen from both of its triangles (it touches an
                    // interior vertex, so it is an interior edge): ½ per triangle sums to 1.
                    let w = 0.5;
                    let (fi, fj) = (index.get(i as usize), index.get(j as usize));
                    for (f, fo, other) in [(fi, fj, j), (fj, fi, i)] {
                        if let Some(f) = f {
                            triplets.push((f, f, w));
                            if fo.is_none() {
                                rhs_u[f as usize] += w * uv[other as usize][0];
                                rhs_v[f as usize] += w * uv[other as usize][1];
                            }
                        }
                    }
                    if let (Some(fi), Some(fj)) = (fi, fj) {
                        triplets.push((fi, fj, -w));
                    }
                }
                Weights::MeanValue => {
                    let Some(fi) = index.get(i as usize) else {
                        continue;
                    };
                    let x = positions[i as usize];
                    let ej = sub(positions[j as usize], x);
                    let el = sub(positions[l as usize], x);
                    let tan_half = tan_half_angle(ej, el)
                        .ok_or(InitialMapError::DegenerateTriangle { triangle: t })?;
                    for (other, e) in [(j, ej), (l, el)] {
                        let w = tan_half / norm(e);
                        triplets.push((fi, fi, w));
                        match index.get(other as usize) {
                            None => {
                                rhs_u[fi as usize] += w * uv[other as usize][0];
                                rhs_v[fi as usize] += w * uv[other as usize][1];
                            }
                            Some(fo) => triplets.push((fi, fo, -w)),
                        }
                    }
                }
            }
        }
    }
    match weights {
        Weights::Uniform => solve_spd(m, &triplets, &mut [&mut rhs_u, &mut rhs_v])?,
        Weights::MeanValue => solve_general(m, &triplets, &mut [&mut rhs_u, &mut rhs_v])?,
    }
    for (v, p) in uv.iter_mut().enumerate() {
        if let Some(f) = index.get(v) {
            *p = [rhs_u[f as usize], rhs_v[f as usize]];
        }
    }
    Ok(uv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;
    use crate::mesh::generate::{bumpy_disc, grid_disc, polar_disc, spherical_cap};
    use crate::param::count_flipped;

    fn disc(mesh: &TriMesh) -> Disc<'_> {
        Disc::new(mesh).unwrap()
    }

    #[test]
    fn ears_flat_on_the_circle_are_opened_to_their_3d_shape() {
        // A 6 × 6 grid split along one diagonal: corners (6, 0) and (0, 6) have one
        // face each, a right isosceles triangle, nearly flat on the circle.
        let mesh = grid_disc(6);
        let d = disc(&mesh);
        let mut uv = mean_value(&mesh.positions, &d).unwrap();
        let before = uv.clone();
        let ears = [6u32, 42];
        let angle_at_tip = |uv: &[[f64; 2]], tip: u32| {
            let face = mesh.triangles.iter().find(|t| t.contains(&tip)).unwrap();
            let others: Vec<[f64; 2]> = face
                .iter()
                .filter(|&&w| w != tip)
                .map(|&w| uv[w as usize])
                .collect();
            let p = uv[tip as usize];
            let (e1, e2) = (
                [others[0][0] - p[0], others[0][1] - p[1]],
                [others[1][0] - p[0], others[1][1] - p[1]],
            );
            (e1[0] * e2[1] - e1[1] * e2[0])
                .abs()
                .atan2(e1[0] * e2[0] + e1[1] * e2[1])
        };
        let right = std::f64::consts::FRAC_PI_2;
        for &tip in &ears {
            let angle = angle_at_tip(&uv, tip);
            assert!(angle > 2.5, "flat before: {angle}");
        }
        assert_eq!(open_ears(&mesh.positions, &d, &mut uv), 2);
        for &tip in &ears {
            let angle = angle_at_tip(&uv, tip);
            assert!((angle - right).abs() < 1e-9, "a right angle after: {angle}");
        }
        assert_eq!(count_flipped(&uv, &mesh.triangles), 0);
        assert_eq!(
            crate::measure::overlap::boundary_crossings(&uv, d.boundary()),
            0
        );
        for v in 0..uv.len() as u32 {
            if !ears.contains(&v) {
                assert_eq!(uv[v as usize], before[v as usize]);
            }
        }
    }

    /// Checks injectivity (all UV triangles positive) and the boundary on the unit circle.
    fn check_embedding(mesh: &TriMesh, uv: &[[f64; 2]], boundary: &[u32]) {
        assert_eq!(count_flipped(uv, &mesh.triangles), 0);
        for &v in boundary {
            let [x, y] = uv[v as usize];
            assert!(((x * x + y * y).sqrt() - 1.0).abs() < 1e-12);
        }
        // Positive triangles inside a circle tile the disc polygon: their areas sum to it.
        let polygon: f64 = (0..boundary.len())
            .map(|k| {
                let (a, b) = (
                    uv[boundary[k] as usize],
                    uv[boundary[(k + 1) % boundary.len()] as usize],
                );
                0.5 * (a[0] * b[1] - a[1] * b[0])
            })
            .sum();
        let total: f64 = mesh
            .triangles
            .iter()
            .map(|t| crate::param::signed_uv_area(t.map(|v| uv[v as usize])))
            .sum();
        assert!((polygon.abs() - total).abs() < 1e-10);
    }

    #[test]
    fn mean_value_and_uniform_are_injective_on_curved_discs() {
        let meshes = [
            bumpy_disc(8, 0.6),
            spherical_cap(1.0, 0.9 * std::f64::consts::PI, 12, 30),
            spherical_cap(3.0, std::f64::consts::FRAC_PI_2, 6, 7),
        ];
        for mesh in &meshes {
            let d = disc(mesh);
            let mv = mean_value(&mesh.positions, &d).unwrap();
            check_embedding(mesh, &mv, d.boundary());
            let un = tutte_uniform(&mesh.positions, &d).unwrap();
            check_embedding(mesh, &un, d.boundary());
        }
    }

    #[test]
    fn mirrored_triangles_still_give_positive_triangles() {
        // Every triangle turned around: the boundary loop runs the other way round the
        // surface, and the map still preserves (the new) orientation.
        let mut mesh = bumpy_disc(4, 0.3);
        mesh.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        let d = disc(&mesh);
        let b = d.boundary();
        let directed: std::collections::HashSet<(u32, u32)> = mesh
            .triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .collect();
        assert!((0..b.len()).all(|k| directed.contains(&(b[k], b[(k + 1) % b.len()]))));
        let uv = mean_value(&mesh.positions, &d).unwrap();
        check_embedding(&mesh, &uv, d.boundary());
    }

    #[test]
    fn boundary_placement_follows_arc_length() {
        // Unit square boundary of a 2×2 grid: 8 edges of length ½, so angles step by π/4.
        let mesh = grid_disc(2);
        let circle = boundary_on_circle(&mesh.positions, &disc(&mesh)).unwrap();
        for (k, p) in circle.iter().enumerate() {
            let angle = TAU * k as f64 / 8.0;
            assert!((p[0] - angle.cos()).abs() < 1e-14 && (p[1] - angle.sin()).abs() < 1e-14);
        }
    }

    #[test]
    fn mean_value_has_linear_precision() {
        // A planar convex mesh, jittered, in a tilted plane; boundary fixed at its own
        // in-plane coordinates must reproduce every interior vertex.
        let mut mesh = polar_disc(6, 14);
        for (v, p) in mesh.positions.iter_mut().enumerate().skip(1) {
            if v <= 5 * 14 {
                let s = (v as f64 * 12.9898).sin() * 43_758.545;
                let j = 0.03 * (s - s.floor() - 0.5);
                p[0] += j;
                p[1] -= 0.7 * j;
            }
        }
        let planar: Vec<[f64; 2]> = mesh.positions.iter().map(|p| [p[0], p[1]]).collect();
        let (c, s) = (0.6f64, 0.8f64); // rotate the plane about the x axis
        let lifted: Vec<[f64; 3]> = mesh
            .positions
            .iter()
            .map(|p| [p[0] + 2.0, c * p[1], s * p[1] - 1.0])
            .collect();
        let d = disc(&mesh);
        let b_uv: Vec<[f64; 2]> = d.boundary().iter().map(|&v| planar[v as usize]).collect();
        let uv = mean_value_with_boundary(&lifted, &d, &b_uv).unwrap();
        for (p, q) in uv.iter().zip(&planar) {
            assert!(
                (p[0] - q[0]).abs() < 1e-12 && (p[1] - q[1]).abs() < 1e-12,
                "{p:?} vs {q:?}"
            );
        }
    }

    #[test]
    fn uniform_tutte_places_interior_vertex_at_neighbour_average() {
        // One interior vertex (center of polar_disc(1, 5)): it must land at the mean of the
        // five boundary positions, which are equally spaced, i.e. at the origin.
        let mesh = polar_disc(1, 5);
        let uv = tutte_uniform(&mesh.positions, &disc(&mesh)).unwrap();
        assert!(uv[0][0].abs() < 1e-14 && uv[0][1].abs() < 1e-14);
        // Uniform weights on a 2-ring polar disc: each interior vertex is the average of its
        // neighbours (checked directly on the result).
        let mesh = polar_disc(3, 9);
        let d = disc(&mesh);
        let b = d.boundary();
        let uv = tutte_uniform(&mesh.positions, &d).unwrap();
        let mut nbrs = vec![std::collections::BTreeSet::new(); mesh.num_vertices()];
        for t in &mesh.triangles {
            for k in 0..3 {
                nbrs[t[k] as usize].insert(t[(k + 1) % 3]);
                nbrs[t[(k + 1) % 3] as usize].insert(t[k]);
            }
        }
        for v in 0..mesh.num_vertices() {
            if b.contains(&(v as u32)) {
                continue;
            }
            let k = nbrs[v].len() as f64;
            let avg = nbrs[v].iter().fold([0.0, 0.0], |a, &u| {
                [a[0] + uv[u as usize][0] / k, a[1] + uv[u as usize][1] / k]
            });
            assert!((avg[0] - uv[v][0]).abs() < 1e-12 && (avg[1] - uv[v][1]).abs() < 1e-12);
        }
    }

    #[test]
    fn degenerate_input_is_an_error() {
        let mesh = polar_disc(2, 6);
        let mut collapsed = mesh.positions.clone();
        collapsed[1] = collapsed[0]; // zero-length edge at the center
        assert!(matches!(
            mean_value(&collapsed, &disc(&mesh)),
            Err(InitialMapError::DegenerateTriangle { .. })
        ));
        let b_uv = vec![[0.0, 0.0]; 3];
        assert!(matches!(
            mean_value_with_boundary(&mesh.positions, &disc(&mesh), &b_uv),
            Err(InitialMapError::BoundaryUvCount {
                expected: 6,
                got: 3
            })
        ));
    }
}

#[cfg(test)]
mod real_mesh_tests {
    use super::*;
    use crate::param::{count_flipped, lscm::lscm, test_meshes};

    /// Floater's theorem on real scans: mean-value and uniform maps onto a circle are
    /// injective. LSCM flips are printed (no guarantee), and must be 0 on the hemisphere.
    #[test]
    fn fixed_boundary_maps_of_real_discs_are_injective() {
        for name in ["nefertiti_small.off", "three_peaks.off", "hemisphere.obj"] {
            let Some(mesh) = test_meshes::read(name) else {
                return;
            };
            let disc = Disc::new(&mesh).expect("a disc");
            let mv = mean_value(&mesh.positions, &disc).unwrap();
            assert_eq!(count_flipped(&mv, &mesh.triangles), 0, "{name}: mean value");
            let un = tutte_uniform(&mesh.positions, &disc).unwrap();
            assert_eq!(count_flipped(&un, &mesh.triangles), 0, "{name}: uniform");
            let conformal = lscm(&mesh.positions, &disc).unwrap();
            let flips = count_flipped(&conformal.uv, &mesh.triangles);
            eprintln!("{name}: LSCM flipped triangles: {flips}");
            if name == "hemisphere.obj" {
                assert_eq!(flips, 0);
            }
        }
    }
}
