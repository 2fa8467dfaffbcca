//! Free-boundary least-squares conformal map (LSCM; Lévy, Petitjean, Ray, Maillot 2002),
//! equivalently the natural conformal map (Desbrun, Meyer, Alliez 2002): the initial
//! parameterization of thesis §3.1.1.
//!
//! It minimizes the conformal energy `E_C(u) = E_D(u) − A(u)`, where
//!
//! - `E_D(u) = ½ ∫ |∇u|² = ¼ Σ_T Σ_{edges ij of T} cot θ_k^T |u_i − u_j|²` is the Dirichlet
//!   energy with cotangent weights (`θ_k^T` the 3D angle of `T` opposite the edge), and
//! - `A(u) = ½ Σ_{boundary edges i→j} (u_i v_j − u_j v_i)` is the signed UV area,
//!   which only involves the boundary (the loop taken with the surface on its left).
//!
//! Per triangle `E_D − A = area3D · ½ (σ1 − σ2)²` for an orientation-preserving
//! Jacobian with singular values `σ1, σ2`, so `E_C ≥ 0` with equality exactly for a
//! conformal (similarity-per-triangle) map. `E_C(x) = xᵀ Q x` is a positive semi-definite
//! quadratic form whose null space on a disc is the 4-dimensional group of similarities;
//! pinning two vertices removes it and the reduced system `Q_ff x_f = −Q_fp x_p` is
//! symmetric positive definite (solved with `linsolve::solve_spd`).
//!
//! LSCM has no guarantee against flipped triangles (the thesis assumes an admissible
//! start, §3.1.1; CGAL's documentation says LSCM can fold): check the result
//! with [`super::count_flipped`] and fall back to [`super::tutte::mean_value`].

use super::{InitialMapError, check_positions};
use crate::linsolve::{Unknowns, solve_spd};
use crate::mesh::Disc;
use crate::vec3::{cross3, dot3, norm3, sub3};
use std::cmp::Ordering;

/// A free-boundary conformal map and the two boundary vertices that were pinned.
#[derive(Clone, Debug, PartialEq)]
pub struct LscmMap {
    /// UV per vertex.
    pub uv: Vec<[f64; 2]>,
    /// `pinned[0]` is mapped to `(0, 0)`, `pinned[1]` to `(1, 0)`.
    pub pinned: [u32; 2],
}

/// UV positions of the two pinned vertices.
pub const PIN_UV: [[f64; 2]; 2] = [[0.0, 0.0], [1.0, 0.0]];

/// Least-squares conformal map of a disc (thesis §3.1.1) with vertex positions
/// `positions` (the disc's own, or a rescaled copy): minimizes `E_D − A` (module docs)
/// with the two boundary vertices farthest apart in 3D pinned at `(0, 0)` and `(1, 0)`.
///
/// The map preserves the orientation of the triangles. The result does not depend on
/// the vertex numbering (up to rounding), since the pins are chosen by position.
/// Every vertex must be used by a triangle.
pub fn lscm(positions: &[[f64; 3]], disc: &Disc) -> Result<LscmMap, InitialMapError> {
    check_positions(positions, disc)?;
    let (triangles, boundary) = (disc.triangles(), disc.boundary());
    let pinned = farthest_boundary_pair(positions, boundary)?;
    let n = positions.len();

    // Unknowns: (u, v) of every non-pinned vertex, interleaved: dofs 2f, 2f + 1.
    let free_index = Unknowns::new(n, pinned.map(|v| v as usize));
    let pin_value = |v: u32, c: usize| {
        if v == pinned[0] {
            PIN_UV[0][c]
        } else {
            PIN_UV[1][c]
        }
    };
    let m = 2 * free_index.count();
    // Off-diagonal entries as triplets (one per triangle edge and component, plus the
    // boundary's u–v couplings), diagonal entries summed in place: the triangles would
    // otherwise list each diagonal entry about 12 times, for the pattern assembly to sort.
    let mut triplets: Vec<(u32, u32, f64)> =
        Vec::with_capacity(6 * triangles.len() + 2 * boundary.len() + m);
    let mut diagonal = vec![0.0; m];
    let mut rhs = vec![0.0; m];
    // Adds the symmetric entry `Q[(a, ca), (b, cb)] = Q[(b, cb), (a, ca)] += q` (once if the
    // two dofs coincide), moving pinned columns to the right-hand side.
    let mut add = |a: u32, ca: usize, b: u32, cb: usize, q: f64| {
        let da = free_index.get(a as usize).map(|f| 2 * f + ca as u32);
        let db = free_index.get(b as usize).map(|f| 2 * f + cb as u32);
        match (da, db) {
            (Some(i), Some(j)) if i == j => diagonal[i as usize] += q,
            (Some(i), Some(j)) => triplets.push((i, j, q)),
            (Some(i), None) => rhs[i as usize] -= q * pin_value(b, cb),
            (None, Some(j)) => rhs[j as usize] -= q * pin_value(a, ca),
            (None, None) => {}
        }
    };

    // Dirichlet energy: ¼ cot θ_k |u_i − u_j|² per triangle edge, for u and v.
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (o, i, j) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let cot = cotangent(
                positions[o as usize],
                positions[i as usize],
                positions[j as usize],
            )
            .ok_or(InitialMapError::DegenerateTriangle { triangle: t })?;
            let c = 0.25 * cot;
            for comp in 0..2 {
                add(i, comp, i, comp, c);
                add(j, comp, j, comp, c);
                add(i, comp, j, comp, -c);
            }
        }
    }
    // Minus the signed area: −½ (u_i v_j − u_j v_i) per boundary edge i → j (the
    // disc's loop has the surface on its left).
    let b = boundary.len();
    for k in 0..b {
        let (i, j) = (boundary[k], boundary[(k + 1) % b]);
        add(i, 0, j, 1, -0.25);
        add(j, 0, i, 1, 0.25);
    }
    triplets.extend(
        diagonal
            .iter()
            .enumerate()
            .map(|(i, &q)| (i as u32, i as u32, q)),
    );

    solve_spd(m, &triplets, &mut [&mut rhs])?;
    let mut uv = vec![[0.0; 2]; n];
    for (v, p) in uv.iter_mut().enumerate() {
        *p = match free_index.get(v) {
            Some(f) => [rhs[2 * f as usize], rhs[2 * f as usize + 1]],
            None => [pin_value(v as u32, 0), pin_value(v as u32, 1)],
        };
    }
    Ok(LscmMap { uv, pinned })
}

/// `cot θ` for the angle `θ` at `o` between `i − o` and `j − o`: `(e1·e2) / ‖e1 × e2‖`;
/// `None` for a degenerate triangle.
fn cotangent(o: [f64; 3], i: [f64; 3], j: [f64; 3]) -> Option<f64> {
    let (e1, e2) = (sub3(i, o), sub3(j, o));
    let sin_part = norm3(cross3(e1, e2));
    let cot = dot3(e1, e2) / sin_part;
    (sin_part > 0.0 && cot.is_finite()).then_some(cot)
}

/// Lexicographic order of positions (`total_cmp` per coordinate).
fn position_order(a: &[f64; 3], b: &[f64; 3]) -> Ordering {
    a[0].total_cmp(&b[0])
        .then(a[1].total_cmp(&b[1]))
        .then(a[2].total_cmp(&b[2]))
}

/// The two boundary vertices farthest apart in 3D, the one with the lexicographically
/// smaller position first. Ties in distance go to the pair whose (smaller, larger)
/// positions are lexicographically smallest, so the choice depends on positions only,
/// not on vertex numbering or where the loop starts (vertices at identical positions
/// excepted). Exact, `O(B²)` in the boundary length `B` (which is `O(√V)` for a
/// reasonable disc mesh). Precondition: every boundary vertex indexes `positions`.
fn farthest_boundary_pair(
    positions: &[[f64; 3]],
    boundary: &[u32],
) -> Result<[u32; 2], InitialMapError> {
    let mut best: Option<(f64, u32, u32)> = None;
    for (k, &a) in boundary.iter().enumerate() {
        for &b in &boundary[k + 1..] {
            let (lo, hi) = match position_order(&positions[a as usize], &positions[b as usize]) {
                Ordering::Greater => (b, a),
                _ => (a, b),
            };
            let (p, q) = (positions[lo as usize], positions[hi as usize]);
            let d2 = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2);
            let better = match best {
                None => true,
                Some((best_d2, blo, bhi)) => match d2.total_cmp(&best_d2) {
                    Ordering::Greater => true,
                    Ordering::Less => false,
                    Ordering::Equal => position_order(&p, &positions[blo as usize])
                        .then(position_order(&q, &positions[bhi as usize]))
                        .is_lt(),
                },
            };
            if better {
                best = Some((d2, lo, hi));
            }
        }
    }
    match best {
        Some((d2, lo, hi)) if d2 > 0.0 => Ok([lo, hi]),
        _ => Err(InitialMapError::DegenerateBoundary),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;
    use crate::mesh::generate::{
        bumpy_disc, cylinder_patch, disc_boundary, grid_disc, polar_disc, spherical_cap,
    };
    use crate::param::count_flipped;

    fn run(mesh: &TriMesh) -> LscmMap {
        lscm(&mesh.positions, &Disc::new(mesh).unwrap()).unwrap()
    }

    use crate::vec3::norm3 as len3;
    fn lift(p: [f64; 2]) -> [f64; 3] {
        [p[0], p[1], 0.0]
    }

    /// Interior angles of a triangle (by the law of cosines from its edge lengths).
    fn angles(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
        let (la, lb, lc) = (len3(sub3(b, c)), len3(sub3(c, a)), len3(sub3(a, b)));
        let angle =
            |opp: f64, s1: f64, s2: f64| ((s1 * s1 + s2 * s2 - opp * opp) / (2.0 * s1 * s2)).acos();
        [angle(la, lb, lc), angle(lb, lc, la), angle(lc, la, lb)]
    }

    /// A planar mesh with jittered interior, embedded in a tilted plane of R³.
    fn tilted_planar_mesh() -> TriMesh {
        let mut mesh = polar_disc(5, 11);
        for (v, p) in mesh.positions.iter_mut().enumerate() {
            let s = (v as f64 * 78.233).sin() * 43_758.545;
            let j = 0.04 * (s - s.floor() - 0.5);
            p[0] += j;
            p[1] += 0.5 * j;
        }
        let (c, s) = (0.28f64, 0.96f64);
        for p in &mut mesh.positions {
            *p = [c * p[0] - 1.0, p[1] + 3.0, s * p[0]];
        }
        mesh
    }

    #[test]
    fn planar_mesh_maps_to_a_similarity_of_itself() {
        let mesh = tilted_planar_mesh();
        let map = run(&mesh);
        assert_eq!(count_flipped(&map.uv, &mesh.triangles), 0);
        for tri in &mesh.triangles {
            let [a, b, c] = tri.map(|v| mesh.positions[v as usize]);
            let [p, q, r] = tri.map(|v| lift(map.uv[v as usize]));
            let (a3, a2) = (angles(a, b, c), angles(p, q, r));
            for k in 0..3 {
                assert!((a3[k] - a2[k]).abs() < 1e-8, "{a3:?} vs {a2:?}");
            }
        }
        assert_eq!(map.uv[map.pinned[0] as usize], PIN_UV[0]);
        assert_eq!(map.uv[map.pinned[1] as usize], PIN_UV[1]);
    }

    #[test]
    fn developable_cylinder_patch_maps_isometrically_up_to_scale() {
        let mesh = cylinder_patch(1.0, 2.0, 1.5, 12, 6);
        let map = run(&mesh);
        let ratios: Vec<f64> = mesh
            .triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(i, j)| {
                let uv = len3(sub3(lift(map.uv[i as usize]), lift(map.uv[j as usize])));
                uv / len3(sub3(mesh.positions[i as usize], mesh.positions[j as usize]))
            })
            .collect();
        let (lo, hi) = ratios
            .iter()
            .fold((f64::MAX, 0.0f64), |(lo, hi), &r| (lo.min(r), hi.max(r)));
        assert!((hi - lo) / hi < 1e-8, "edge length ratios range {lo}..{hi}");
        assert_eq!(count_flipped(&map.uv, &mesh.triangles), 0);
    }

    #[test]
    fn result_does_not_depend_on_vertex_order() {
        let mesh = bumpy_disc(5, 0.4);
        let map = run(&mesh);
        let n = mesh.num_vertices();
        // A deterministic scrambling permutation: v ↦ (v·a + c) mod n with gcd(a, n) = 1.
        let a = (2..n).find(|a| gcd(*a, n) == 1 && *a > n / 3).unwrap();
        let perm: Vec<u32> = (0..n).map(|v| ((v * a + 5) % n) as u32).collect();
        let mut positions = vec![[0.0; 3]; n];
        for (v, &p) in perm.iter().enumerate() {
            positions[p as usize] = mesh.positions[v];
        }
        // Rotate corners, reverse triangle order.
        let triangles: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .rev()
            .map(|t| {
                [
                    perm[t[1] as usize],
                    perm[t[2] as usize],
                    perm[t[0] as usize],
                ]
            })
            .collect();
        let permuted = TriMesh::new(positions, triangles);
        let permuted = run(&permuted);
        assert_eq!(permuted.pinned, map.pinned.map(|v| perm[v as usize]));
        for (p, &pv) in map.uv.iter().zip(&perm) {
            let q = permuted.uv[pv as usize];
            assert!((p[0] - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9);
        }
    }

    #[test]
    fn positions_must_fit_the_disc() {
        // The checks themselves are tested with `check_positions`; here only that LSCM
        // runs them.
        let mesh = grid_disc(2);
        let disc = Disc::new(&mesh).unwrap();
        assert!(matches!(
            lscm(&mesh.positions[1..], &disc),
            Err(InitialMapError::Positions(_))
        ));
    }

    fn gcd(a: usize, b: usize) -> usize {
        if b == 0 { a } else { gcd(b, a % b) }
    }

    #[test]
    fn hemisphere_has_no_flipped_triangles() {
        for mesh in [
            spherical_cap(1.0, std::f64::consts::FRAC_PI_2, 12, 32),
            spherical_cap(2.0, 0.6 * std::f64::consts::PI, 10, 24),
            bumpy_disc(8, 0.5),
        ] {
            let map = run(&mesh);
            assert_eq!(count_flipped(&map.uv, &mesh.triangles), 0);
        }
    }

    /// Conformal energy from per-triangle Jacobians, independent of the cotangent
    /// assembly: `Σ_T area3D · (½ ‖J‖_F² − det J)` (= `½ area (σ1 − σ2)²` when det J > 0).
    fn conformal_energy(mesh: &TriMesh, uv: &[[f64; 2]]) -> f64 {
        let mut e = 0.0;
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|v| mesh.positions[v as usize]);
            // Orthonormal frame of the triangle's plane: x along b − a.
            let (e1, e2) = (sub3(b, a), sub3(c, a));
            let l1 = len3(e1);
            let x = e1.map(|v| v / l1);
            let d = e2[0] * x[0] + e2[1] * x[1] + e2[2] * x[2];
            let h = len3([e2[0] - d * x[0], e2[1] - d * x[1], e2[2] - d * x[2]]);
            // P = [[l1, d], [0, h]] maps (1,0),(0,1) to the local edge vectors.
            let [p, q, r] = tri.map(|v| uv[v as usize]);
            let du = [[q[0] - p[0], r[0] - p[0]], [q[1] - p[1], r[1] - p[1]]];
            // J = du · P⁻¹, P⁻¹ = [[1/l1, −d/(l1 h)], [0, 1/h]]
            let j = [
                [du[0][0] / l1, (du[0][1] - du[0][0] * d / l1) / h],
                [du[1][0] / l1, (du[1][1] - du[1][0] * d / l1) / h],
            ];
            let frob = j[0][0].powi(2) + j[0][1].powi(2) + j[1][0].powi(2) + j[1][1].powi(2);
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            e += mesh.triangle_area(t) * (0.5 * frob - det);
        }
        e
    }

    #[test]
    fn result_is_stationary_for_the_conformal_energy() {
        let mesh = bumpy_disc(5, 0.5);
        let map = run(&mesh);
        let e0 = conformal_energy(&mesh, &map.uv);
        assert!(
            e0 > 0.0,
            "a curved disc cannot be mapped conformally by a PL map"
        );
        let h = 1e-3;
        for seed in 0..4u32 {
            let dir: Vec<[f64; 2]> = (0..mesh.num_vertices() as u32)
                .map(|v| {
                    if map.pinned.contains(&v) {
                        return [0.0, 0.0];
                    }
                    let s = ((v * 31 + seed * 17) as f64 * 12.9898).sin() * 43_758.545;
                    let f = s - s.floor() - 0.5;
                    [f, 0.7 - f * f]
                })
                .collect();
            let shifted = |t: f64| -> Vec<[f64; 2]> {
                map.uv
                    .iter()
                    .zip(&dir)
                    .map(|(p, d)| [p[0] + t * d[0], p[1] + t * d[1]])
                    .collect()
            };
            let (ep, em) = (
                conformal_energy(&mesh, &shifted(h)),
                conformal_energy(&mesh, &shifted(-h)),
            );
            let slope = (ep - em) / (2.0 * h);
            let curvature = (ep + em - 2.0 * e0) / (h * h);
            assert!(curvature > 0.0);
            assert!(
                slope.abs() < 1e-6 * curvature,
                "slope {slope}, curvature {curvature}"
            );
        }
    }

    #[test]
    fn farthest_pair_is_chosen_by_position() {
        // Unit square boundary: both diagonals tie; the pair with the smallest positions
        // wins: (0,0) — (1,1), whatever the loop's start or direction.
        let mesh = grid_disc(3);
        let mut b = disc_boundary(&mesh.triangles).unwrap();
        let corner = |x: f64, y: f64| {
            mesh.positions
                .iter()
                .position(|p| *p == [x, y, 0.0])
                .unwrap() as u32
        };
        let expect = [corner(0.0, 0.0), corner(1.0, 1.0)];
        for shift in 0..b.len() {
            b.rotate_left(1);
            assert_eq!(
                farthest_boundary_pair(&mesh.positions, &b).unwrap(),
                expect,
                "{shift}"
            );
        }
        b.reverse();
        assert_eq!(farthest_boundary_pair(&mesh.positions, &b).unwrap(), expect);
        let same = vec![[1.0, 2.0, 3.0]; 3];
        assert_eq!(
            farthest_boundary_pair(&same, &[0, 1, 2]),
            Err(InitialMapError::DegenerateBoundary)
        );
    }
}
