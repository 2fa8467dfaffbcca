//! 3D morphs (thesis §5.2, fig. 5.3): `M(t) = (1 − t)·M_A + t·φ_M(M_A)` on A's
//! connectivity, `t ∈ [0, 1]`.
//!
//! Every vertex `x_a` of A moves along the straight line to its counterpart `φ_M(x_a)` on
//! B, so `M(t) = x + t·d` with the **morph target** (displacement) `d_a = φ_M(x_a) − x_a`:
//! at `t = 0` the morph is A, at `t = 1` every matched vertex lies on B. glTF stores
//! exactly `d` as a morph target and `t` as its weight.
//!
//! **Unmatched vertices** (A's border where B has no counterpart, thesis §2.2.5) must
//! not tear the morph. Their displacement is the harmonic extension of the matched
//! displacements over A's mesh: with the cotangent Laplacian
//! `(L d)_i = Σ_j w_ij (d_j − d_i)`, `w_ij = ½ (cot α_ij + cot β_ij)` (the angles of A
//! opposite edge `ij`), the unmatched values solve `(L d)_i = 0` for every unmatched `i`,
//! with the matched values fixed:
//!
//! ```text
//! L_UU d_U = −L_UM d_M      (one sparse SPD solve, three right-hand sides)
//! ```
//!
//! `L_UU` is the P1 stiffness matrix of A restricted to the unmatched vertices, positive
//! definite when every connected part of them touches a matched vertex. The extension
//! minimizes the Dirichlet energy `∫_A |∇d|²` among displacements that agree with the
//! matched ones, so it joins them without a jump. Inside the mesh it reproduces a
//! displacement that is affine on a flat region exactly (linear precision of the
//! cotangent weights); at A's own border it meets the natural boundary condition
//! `∂d/∂n = 0`, so the displacement levels off towards the border instead of being
//! extrapolated.
//! Vertices that no triangle uses keep a zero displacement.

use super::AppError;
use super::correspondence::check_correspondence;
use crate::linsolve::{Unknowns, solve_spd};
use crate::mesh::SurfacePoint;
use crate::vec3::{cross3, dot3, norm3, sub3};

/// A morph target of A towards B: one displacement per vertex of A.
#[derive(Clone, Debug, PartialEq)]
pub struct MorphTarget {
    /// `d_a = φ_M(x_a) − x_a` for a matched vertex, the harmonic extension for an
    /// unmatched one, zero for a vertex no triangle uses.
    pub displacements: Vec<[f64; 3]>,
    /// Vertices with a counterpart on B.
    pub matched: usize,
    /// Vertices whose displacement was extended harmonically (no counterpart on B).
    pub extended: Vec<u32>,
    /// Vertices that no triangle uses (zero displacement).
    pub unreferenced: usize,
}

impl MorphTarget {
    /// The positions of the morph at time `t`: `x + t·d`.
    pub fn frame(&self, positions_a: &[[f64; 3]], t: f64) -> Vec<[f64; 3]> {
        morph_frame(positions_a, &self.displacements, t)
    }

    /// The largest displacement length of the extended vertices (0 when there are none).
    pub fn max_extended_displacement(&self) -> f64 {
        self.extended
            .iter()
            .map(|&v| norm3(self.displacements[v as usize]))
            .fold(0.0, f64::max)
    }
}

/// `M(t) = (1 − t)·x + t·(x + d) = x + t·d` for every vertex.
pub fn morph_frame(positions: &[[f64; 3]], displacements: &[[f64; 3]], t: f64) -> Vec<[f64; 3]> {
    positions
        .iter()
        .zip(displacements)
        .map(|(x, d)| [x[0] + t * d[0], x[1] + t * d[1], x[2] + t * d[2]])
        .collect()
}

/// The morph target of A (`positions_a`, `triangles_a`) towards B along the
/// correspondence `ab` (one entry per vertex of A), unmatched vertices extended
/// harmonically (see the [module documentation](self)).
pub fn morph_target(
    positions_a: &[[f64; 3]],
    triangles_a: &[[u32; 3]],
    ab: &[Option<SurfacePoint>],
    positions_b: &[[f64; 3]],
    triangles_b: &[[u32; 3]],
) -> Result<MorphTarget, AppError> {
    crate::mesh::check_indices(triangles_a, positions_a.len())?;
    crate::mesh::check_indices(triangles_b, positions_b.len())?;
    check_correspondence(ab, positions_a.len(), triangles_b.len())?;
    let known: Vec<Option<[f64; 3]>> = ab
        .iter()
        .zip(positions_a)
        .map(|(p, x)| p.map(|p| sub3(p.position(positions_b, triangles_b), *x)))
        .collect();
    let matched = known.iter().filter(|d| d.is_some()).count();
    let extension = harmonic_extension(positions_a, triangles_a, &known)?;
    Ok(MorphTarget {
        displacements: extension.values,
        matched,
        extended: extension.extended,
        unreferenced: extension.unreferenced,
    })
}

/// Values on every vertex from values on some (see the [module documentation](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct HarmonicExtension<const D: usize> {
    /// The known values where given, the extension elsewhere, zero on unused vertices.
    pub values: Vec<[f64; D]>,
    /// The vertices whose values were computed.
    pub extended: Vec<u32>,
    /// Vertices no triangle uses.
    pub unreferenced: usize,
}

/// The harmonic extension (cotangent Laplacian, Dirichlet data at the known vertices)
/// of per-vertex values known on some vertices (`Some`) to the others (`None`) of the
/// mesh `(positions, triangles)`. Degenerate triangles (zero area) contribute nothing.
///
/// Errors: nothing known ([`AppError::NothingMatched`]); an unknown vertex in a part of
/// the mesh without a known vertex ([`AppError::UnanchoredPart`]).
pub fn harmonic_extension<const D: usize>(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    known: &[Option<[f64; D]>],
) -> Result<HarmonicExtension<D>, AppError> {
    let n = positions.len();
    if known.len() != n {
        return Err(AppError::per_vertex("known values", known.len(), n));
    }
    crate::mesh::check_indices(triangles, n)?;
    let mut used = vec![false; n];
    for t in triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    if !known.iter().zip(&used).any(|(k, &u)| k.is_some() && u) {
        return Err(AppError::NothingMatched);
    }
    let unknown = Unknowns::new(n, (0..n).filter(|&i| known[i].is_some() || !used[i]));
    let mut values: Vec<[f64; D]> = known.iter().map(|k| k.unwrap_or([0.0; D])).collect();
    let extended: Vec<u32> = (0..n as u32)
        .filter(|&i| unknown.get(i as usize).is_some())
        .collect();
    let unreferenced = used.iter().filter(|&&u| !u).count();
    if extended.is_empty() {
        return Ok(HarmonicExtension {
            values,
            extended,
            unreferenced,
        });
    }

    // Stiffness matrix rows of the unknown vertices; known columns go to the right.
    let m = unknown.count();
    let mut triplets: Vec<(u32, u32, f64)> = Vec::with_capacity(3 * triangles.len() + m);
    let mut diagonal = vec![0.0; m];
    let mut rhs = vec![vec![0.0; m]; D];
    // Union-find over unknown vertices joined by edges; `anchored` per root.
    let mut parent: Vec<u32> = (0..m as u32).collect();
    let mut anchored = vec![false; m];
    for tri in triangles {
        let p = tri.map(|v| positions[v as usize]);
        let twice_area = norm3(cross3(sub3(p[1], p[0]), sub3(p[2], p[0])));
        if !(twice_area > 0.0 && twice_area.is_finite()) {
            continue;
        }
        for k in 0..3 {
            // Edge (i, j) opposite corner k: weight ½ cot θ_k = ½ (e1·e2)/|e1 × e2|.
            let (o, i, j) = (k, (k + 1) % 3, (k + 2) % 3);
            let w = 0.5 * dot3(sub3(p[i], p[o]), sub3(p[j], p[o])) / twice_area;
            let (vi, vj) = (tri[i] as usize, tri[j] as usize);
            match (unknown.get(vi), unknown.get(vj)) {
                (Some(a), Some(b)) => {
                    diagonal[a as usize] += w;
                    diagonal[b as usize] += w;
                    triplets.push((a, b, -w));
                    union(&mut parent, a, b);
                }
                (Some(a), None) | (None, Some(a)) => {
                    let known_vertex = if unknown.get(vi).is_some() { vj } else { vi };
                    diagonal[a as usize] += w;
                    let value = values[known_vertex].to_owned();
                    for (r, x) in rhs.iter_mut().zip(value) {
                        r[a as usize] += w * x;
                    }
                    anchored[a as usize] = true;
                }
                (None, None) => {}
            }
        }
    }
    // Every part of the unknown vertices must touch a known one.
    let mut root_anchored = vec![false; m];
    for a in 0..m as u32 {
        if anchored[a as usize] {
            root_anchored[find(&mut parent, a) as usize] = true;
        }
    }
    if let Some(&vertex) = extended
        .iter()
        .find(|&&v| !root_anchored[find(&mut parent, unknown.get(v as usize).unwrap()) as usize])
    {
        return Err(AppError::UnanchoredPart {
            vertex: vertex as usize,
        });
    }
    triplets.extend(
        diagonal
            .iter()
            .enumerate()
            .map(|(a, &d)| (a as u32, a as u32, d)),
    );
    let mut columns: Vec<&mut [f64]> = rhs.iter_mut().map(|r| r.as_mut_slice()).collect();
    solve_spd(m, &triplets, &mut columns)?;
    for &v in &extended {
        let a = unknown.get(v as usize).unwrap() as usize;
        for (c, r) in rhs.iter().enumerate() {
            values[v as usize][c] = r[a];
        }
    }
    Ok(HarmonicExtension {
        values,
        extended,
        unreferenced,
    })
}

fn find(parent: &mut [u32], mut a: u32) -> u32 {
    while parent[a as usize] != a {
        parent[a as usize] = parent[parent[a as usize] as usize];
        a = parent[a as usize];
    }
    a
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::apps::correspondence::tests::{analytic_map, graph_mesh};
    use crate::mesh::TriMesh;

    fn bump(x: f64, y: f64) -> f64 {
        0.25 * (1.3 * x + 0.4).sin() * (1.1 * y).cos()
    }

    /// Squared distance from `p` to the triangle `(a, b, c)` (closest point by the
    /// region test of Ericson, *Real-Time Collision Detection*, §5.1.5).
    fn distance_to_triangle(p: [f64; 3], [a, b, c]: [[f64; 3]; 3]) -> f64 {
        let (ab, ac, ap) = (sub3(b, a), sub3(c, a), sub3(p, a));
        let (d1, d2) = (dot3(ab, ap), dot3(ac, ap));
        let at = |s: f64, t: f64| {
            let q = [0, 1, 2].map(|k| a[k] + s * ab[k] + t * ac[k]);
            norm3(sub3(p, q))
        };
        if d1 <= 0.0 && d2 <= 0.0 {
            return norm3(ap);
        }
        let bp = sub3(p, b);
        let (d3, d4) = (dot3(ab, bp), dot3(ac, bp));
        if d3 >= 0.0 && d4 <= d3 {
            return norm3(bp);
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return at(d1 / (d1 - d3), 0.0);
        }
        let cp = sub3(p, c);
        let (d5, d6) = (dot3(ab, cp), dot3(ac, cp));
        if d6 >= 0.0 && d5 <= d6 {
            return norm3(cp);
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return at(0.0, d2 / (d2 - d6));
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            return at(1.0 - w, w);
        }
        let denom = 1.0 / (va + vb + vc);
        at(vb * denom, vc * denom)
    }

    fn distance_to_mesh(p: [f64; 3], m: &TriMesh) -> f64 {
        (0..m.num_triangles())
            .map(|t| distance_to_triangle(p, m.triangle_positions(t)))
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn morph_starts_at_a_and_ends_on_b() {
        let a = graph_mesh(12, 0.5, 1, bump);
        // B: another triangulation of another surface over a larger square.
        let mut b = graph_mesh(15, 0.5, 2, |x, y| 0.2 * x * y - 0.1);
        for p in &mut b.positions {
            p[0] *= 1.2;
            p[1] *= 1.2;
        }
        let ab = analytic_map(&a, &b, |p| [0.9 * p[0] + 0.1 * p[1], 1.1 * p[1]]);
        assert!(ab.iter().all(Option::is_some));
        let target =
            morph_target(&a.positions, &a.triangles, &ab, &b.positions, &b.triangles).unwrap();
        assert_eq!(
            (target.matched, target.extended.len()),
            (a.num_vertices(), 0)
        );
        assert_eq!(target.frame(&a.positions, 0.0), a.positions);
        let end = target.frame(&a.positions, 1.0);
        let worst = end
            .iter()
            .map(|&p| distance_to_mesh(p, &b))
            .fold(0.0, f64::max);
        assert!(worst < 1e-12, "a vertex at t = 1 is {worst:e} off B");
        // Half way: the midpoint of each vertex and its image.
        let mid = target.frame(&a.positions, 0.5);
        for ((m, x), y) in mid.iter().zip(&a.positions).zip(&end) {
            for k in 0..3 {
                assert!((m[k] - 0.5 * (x[k] + y[k])).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn extension_reproduces_an_affine_displacement_inside_a_flat_mesh() {
        // Flat, irregular mesh; the displacement is affine; an interior region is
        // unknown. Linear precision of the cotangent Laplacian at interior vertices:
        // the extension is exact there.
        let a = graph_mesh(14, 0.7, 3, |_, _| 0.0);
        let d = |p: [f64; 3]| {
            [
                0.3 * p[0] - 0.2 * p[1] + 0.1,
                0.05 * p[0] + 0.4 * p[1],
                -0.5 * p[0] + 0.2,
            ]
        };
        let known: Vec<Option<[f64; 3]>> = a
            .positions
            .iter()
            .map(|&p| ((p[0] - 0.1).hypot(p[1]) > 0.6).then(|| d(p)))
            .collect();
        let ext = harmonic_extension(&a.positions, &a.triangles, &known).unwrap();
        assert!(ext.extended.len() > 40, "{}", ext.extended.len());
        for (v, p) in ext.values.iter().zip(&a.positions) {
            let want = d(*p);
            for k in 0..3 {
                assert!((v[k] - want[k]).abs() < 1e-10, "{v:?} vs {want:?}");
            }
        }
    }

    #[test]
    fn unmatched_border_moves_without_a_jump() {
        // A curved mesh matched to a smoothly deformed copy everywhere but a border band
        // of varying width; the extended displacements must continue the matched ones:
        // across the matched/extended seam, the displacement changes along an edge no
        // more than it does along edges inside the matched region.
        let a = graph_mesh(20, 0.5, 5, bump);
        let b = graph_mesh(24, 0.5, 6, |x, y| bump(x, y) + 0.3 * (x * x - y));
        let mut ab = analytic_map(&a, &b, |p| [0.85 * p[0] + 0.05 * p[1] * p[1], 0.85 * p[1]]);
        for (p, x) in ab.iter_mut().zip(&a.positions) {
            let r = x[0].abs().max(x[1].abs());
            if r > 0.7 + 0.1 * (3.0 * x[0]).sin() {
                *p = None;
            }
        }
        let target =
            morph_target(&a.positions, &a.triangles, &ab, &b.positions, &b.triangles).unwrap();
        assert!(!target.extended.is_empty() && target.matched > 0);
        let is_extended: Vec<bool> = ab.iter().map(Option::is_none).collect();
        let topology = crate::mesh::Topology::new(&a);
        let (mut inside, mut seam) = (0.0f64, 0.0f64);
        for &[i, j] in &topology.edges {
            let (i, j) = (i as usize, j as usize);
            let jump = norm3(sub3(target.displacements[i], target.displacements[j]))
                / norm3(sub3(a.positions[i], a.positions[j]));
            match (is_extended[i], is_extended[j]) {
                (false, false) => inside = inside.max(jump),
                (true, false) | (false, true) => seam = seam.max(jump),
                (true, true) => {}
            }
        }
        assert!(
            seam <= 1.5 * inside,
            "seam gradient {seam} vs inside {inside}"
        );
        // Without the extension (unmatched vertices left in place) the seam tears: the
        // same measure is many times larger, so the check above can fail.
        let torn = topology
            .edges
            .iter()
            .filter(|&&[i, j]| is_extended[i as usize] != is_extended[j as usize])
            .map(|&[i, j]| {
                let (i, j) = (i as usize, j as usize);
                let di = if is_extended[i] {
                    [0.0; 3]
                } else {
                    target.displacements[i]
                };
                let dj = if is_extended[j] {
                    [0.0; 3]
                } else {
                    target.displacements[j]
                };
                norm3(sub3(di, dj)) / norm3(sub3(a.positions[i], a.positions[j]))
            })
            .fold(0.0, f64::max);
        assert!(torn > 4.0 * inside, "torn {torn} vs inside {inside}");
        // And the morph at t = 1 keeps every extended vertex near B (the band is narrow).
        assert!(target.max_extended_displacement() < 1.0);
    }

    #[test]
    fn errors_name_the_problem() {
        let a = graph_mesh(4, 0.0, 1, |_, _| 0.0);
        let none: Vec<Option<[f64; 3]>> = vec![None; a.num_vertices()];
        assert!(matches!(
            harmonic_extension(&a.positions, &a.triangles, &none),
            Err(AppError::NothingMatched)
        ));
        // Two separate squares, only one has known values.
        let mut two = a.clone();
        let n = a.num_vertices() as u32;
        two.positions
            .extend(a.positions.iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
        two.triangles
            .extend(a.triangles.iter().map(|t| t.map(|v| v + n)));
        let mut known: Vec<Option<[f64; 1]>> = vec![None; two.num_vertices()];
        known[0] = Some([1.0]);
        let e = harmonic_extension(&two.positions, &two.triangles, &known).unwrap_err();
        assert!(
            matches!(e, AppError::UnanchoredPart { vertex } if vertex >= n as usize),
            "{e}"
        );
        assert!(matches!(
            harmonic_extension(&a.positions, &a.triangles, &known[..3]),
            Err(AppError::Length { .. })
        ));
    }
}
