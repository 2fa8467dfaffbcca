//! Landmarks matched exactly in the output correspondence.
//!
//! In the energy a landmark is a point feature: its distance map (a cone) pulls φ
//! toward the pair but pins nothing (thesis §2.2.4, eq. 2.11), and where the surfaces differ most
//! (mouth corners of a smile, the corner of a closed eye) φ can stay a centimetre off.
//! φ itself is not forced — a bump in φ wide enough to be smooth folds the strongly
//! compressed filled holes around those corners (BENCHMARKS.md, "Matching") — but the
//! *reported* correspondence is: the user said that vertex `a` of A is vertex `b` of B.
//!
//! **Rule.** With `δᵢ = x_B(bᵢ) − y(aᵢ)` the miss of landmark `i` (`y(v)` the point of B
//! that v is matched to), every matched vertex of A moves by the Gaussian radial-basis
//! interpolant of the misses,
//!
//! `D(x) = Σᵢ wᵢ exp(−|x − x_A(aᵢ)|² / (2 rᵢ²))`,   `D(x_A(aⱼ)) = δⱼ` for every j,
//!
//! `rᵢ` half the distance from landmark i to the nearest other landmark in A (so each
//! correction is local to its landmark and the system is well conditioned), and is
//! re-matched to B's closest point to `y(v) + D(x_A(v))`, searched near its former
//! counterpart ([`SurfaceProjector::project_near`]); the landmarks get their vertices
//! exactly. Moves are made nearest the landmarks first, and one that would leave more
//! image triangles around its vertex turned over or collapsed than before is not made.
//! A vertex of an image triangle still folded afterwards is reported unmatched (never a
//! landmark, [`crate::matching::folds::drop_folds`]) and left to rim completion
//! ([`crate::matching::post::complete`]), which regrows it from its neighbours.

use glam::DVec3;
use rayon::prelude::*;

use super::super::folds::{ImageFold, image_fold};
use crate::mesh::closest::{SurfaceProjector, vertex_triangles};
use crate::mesh::{SurfacePoint, TriMesh};

/// What pinning did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Pinning {
    /// Landmarks matched exactly to their vertex of B.
    pub landmarks: usize,
    /// Other vertices moved by the interpolated correction.
    pub moved: usize,
    /// Largest landmark miss before pinning (B's length units).
    pub largest_miss: f64,
}

/// Gaussian weights below this are not applied (the vertex keeps its match).
const NEGLIGIBLE: f64 = 1e-4;

/// Matches the landmark pairs `(a, b)` exactly and carries the correction to the
/// vertices around them by the rule in the module documentation.
pub fn pin_landmarks(
    a: &TriMesh,
    b: &TriMesh,
    correspondence: &mut [Option<SurfacePoint>],
    pairs: &[(u32, u32)],
) -> Pinning {
    let mut done = Pinning::default();
    let image = |p: SurfacePoint| DVec3::from_array(p.position(&b.positions, &b.triangles));
    // Landmarks whose vertex of A is matched give a miss to interpolate.
    let known: Vec<(DVec3, DVec3)> = pairs
        .iter()
        .filter_map(|&(va, vb)| {
            let p = correspondence.get(va as usize).copied().flatten()?;
            let target = DVec3::from_array(*b.positions.get(vb as usize)?);
            Some((
                DVec3::from_array(a.positions[va as usize]),
                target - image(p),
            ))
        })
        .collect();
    done.largest_miss = known.iter().map(|k| k.1.length()).fold(0.0, f64::max);
    let radii: Vec<f64> = known
        .iter()
        .enumerate()
        .map(|(i, (c, _))| {
            let nearest = known
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, (d, _))| c.distance(*d))
                .fold(f64::INFINITY, f64::min);
            if nearest.is_finite() {
                0.5 * nearest
            } else {
                0.1 * a.area().sqrt()
            }
        })
        .collect();
    let kernel = |j: usize, x: DVec3| -> f64 {
        let d2 = x.distance_squared(known[j].0);
        (-d2 / (2.0 * radii[j] * radii[j])).exp()
    };
    let weights = crate::linsolve::dense::solve_square(
        known.len(),
        |i, j| kernel(j, known[i].0),
        &known.iter().map(|k| k.1.to_array()).collect::<Vec<_>>(),
    )
    .map(|w| w.into_iter().map(DVec3::from_array).collect::<Vec<_>>());
    for &(va, vb) in pairs {
        if let (Some(slot), Some(point)) = (
            correspondence.get_mut(va as usize),
            SurfacePoint::at_vertex(&b.triangles, vb),
        ) {
            *slot = Some(point);
            done.landmarks += 1;
        }
    }
    let Some(weights) = weights.filter(|_| !known.is_empty()) else {
        return done;
    };
    let projector = SurfaceProjector::new(b);
    let edge = mean_edge(b);
    let landmarks: Vec<u32> = pairs.iter().map(|p| p.0).collect();
    let mut moves: Vec<(usize, f64, SurfacePoint)> = (0..a.positions.len())
        .into_par_iter()
        .filter(|&v| !landmarks.contains(&(v as u32)))
        .filter_map(|v| {
            let former = correspondence[v]?;
            let x = DVec3::from_array(a.positions[v]);
            let mut shift = DVec3::ZERO;
            let mut reach = 0.0;
            for (j, w) in weights.iter().enumerate() {
                let k = kernel(j, x);
                shift += *w * k;
                reach += k;
            }
            if reach < NEGLIGIBLE {
                return None;
            }
            let rings = (shift.length() / edge).ceil() as usize + 2;
            let (point, _) = projector.project_near(
                (image(former) + shift).to_array(),
                &[former.triangle],
                rings,
            )?;
            Some((v, reach, point))
        })
        .collect();
    // Nearest the landmarks first; a move is made unless it leaves more image triangles
    // around the vertex folded than before.
    moves.sort_by(|x, y| y.1.total_cmp(&x.1));
    let (tri_start, tri_list) = vertex_triangles(&a.triangles, a.positions.len());
    let area_ratio = b.area() / a.area();
    let folded_around = |v: usize, correspondence: &[Option<SurfacePoint>]| -> usize {
        tri_list[tri_start[v] as usize..tri_start[v + 1] as usize]
            .iter()
            .filter(|&&f| {
                let tri = a.triangles[f as usize];
                let [Some(p0), Some(p1), Some(p2)] = tri.map(|u| correspondence[u as usize]) else {
                    return false;
                };
                image_fold(a, b, area_ratio, tri, [p0, p1, p2]) != ImageFold::None
            })
            .count()
    };
    for (v, _, point) in moves {
        let before = folded_around(v, correspondence);
        let former = correspondence[v];
        correspondence[v] = Some(point);
        if folded_around(v, correspondence) > before {
            correspondence[v] = former;
        } else {
            done.moved += 1;
        }
    }
    done
}

/// Mean edge length of a mesh (over triangle sides; interior edges counted twice).
fn mean_edge(mesh: &TriMesh) -> f64 {
    let mut sum = 0.0;
    for tri in &mesh.triangles {
        for k in 0..3 {
            let p = DVec3::from_array(mesh.positions[tri[k] as usize]);
            let q = DVec3::from_array(mesh.positions[tri[(k + 1) % 3] as usize]);
            sum += p.distance(q);
        }
    }
    sum / (3 * mesh.triangles.len()).max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::bumpy_disc;

    #[test]
    fn pinning_matches_landmarks_exactly_and_pulls_their_surroundings_along() {
        // A: a bumpy disc; B: the same surface; the correspondence is the identity
        // except for a smooth miss around two "landmarks" (a Gaussian slide along the
        // surface of up to 1.5 edges, about as wide as the landmarks are apart), as φ
        // leaves it near features it only pulls.
        let a = bumpy_disc(16, 0.3);
        let b = a.clone();
        let edge = 1.0 / 16.0;
        let projector = SurfaceProjector::new(&b);
        let nearest = |p: [f64; 3]| {
            (0..a.num_vertices())
                .min_by(|&u, &v| {
                    let d =
                        |w: usize| DVec3::from_array(a.positions[w]).distance(DVec3::from_array(p));
                    d(u).total_cmp(&d(v))
                })
                .expect("vertices") as u32
        };
        let landmarks = [nearest([0.4, 0.1, 0.0]), nearest([-0.3, -0.4, 0.0])];
        let miss = |x: DVec3| -> DVec3 {
            landmarks
                .iter()
                .map(|&l| {
                    let c = DVec3::from_array(a.positions[l as usize]);
                    DVec3::new(1.5 * edge, 0.5 * edge, 0.0)
                        * (-(x - c).length_squared() / (2.0 * 0.3 * 0.3)).exp()
                })
                .sum()
        };
        let mut corr: Vec<Option<SurfacePoint>> = (0..a.num_vertices())
            .map(|v| {
                let x = DVec3::from_array(a.positions[v]);
                projector.project((x + miss(x)).to_array()).map(|(p, _)| p)
            })
            .collect();
        let error = |corr: &[Option<SurfacePoint>], v: usize| -> f64 {
            let p = corr[v]
                .expect("matched")
                .position(&b.positions, &b.triangles);
            DVec3::from_array(p).distance(DVec3::from_array(a.positions[v]))
        };
        let near: Vec<usize> = (0..a.num_vertices())
            .filter(|&v| {
                let x = DVec3::from_array(a.positions[v]);
                landmarks
                    .iter()
                    .any(|&l| x.distance(DVec3::from_array(a.positions[l as usize])) < 0.15)
            })
            .collect();
        let mean = |corr: &[Option<SurfacePoint>]| {
            near.iter().map(|&v| error(corr, v)).sum::<f64>() / near.len() as f64
        };
        let before = mean(&corr);
        let pairs: Vec<(u32, u32)> = landmarks.iter().map(|&l| (l, l)).collect();
        let done = pin_landmarks(&a, &b, &mut corr, &pairs);
        let after = mean(&corr);
        println!("{done:?}: mean error near the landmarks {before:.5} -> {after:.5}");
        assert_eq!(done.landmarks, 2);
        assert!(done.largest_miss > edge, "{done:?}");
        for &l in &landmarks {
            assert!(error(&corr, l as usize) < 1e-12, "landmark {l} not exact");
        }
        // The interpolant matches the miss at the landmarks, not its exact shape between
        // them: a part of the miss stays.
        assert!(after < 0.65 * before, "{before} -> {after}");
        // As `checked_correspondence` does: the vertices of any image triangle left
        // folded are unmatched, never a landmark, and then nothing is folded.
        let folds = crate::matching::folds::check_folds(&a, &b, &corr);
        let dropped = crate::matching::folds::drop_folds(&a, &folds, &mut corr, &landmarks);
        assert!(dropped <= 10, "{dropped} vertices dropped for folds");
        for &l in &landmarks {
            assert!(corr[l as usize].is_some(), "landmark {l} dropped");
        }
        let folds = crate::matching::folds::check_folds(&a, &b, &corr);
        assert!(
            folds.flipped.is_empty() && folds.collapsed.is_empty(),
            "{folds:?}"
        );
    }
}
