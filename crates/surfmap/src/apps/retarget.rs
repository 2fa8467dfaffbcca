//! Retargeting a rig (thesis §6.2, new subjects): the expressions of a rig made on one
//! neutral `X` carried onto another neutral `Y` through the correspondence `φ: Y → X`
//! (a match of the two neutrals), by **displacement transfer**.
//!
//! A key of the rig is a displacement field `d` on X's vertices (`x + d` is the key,
//! [`super::rig`]). Vertex `j` of Y corresponds to the point `φ(y_j)` of X, in triangle
//! `(a, b, c)` with barycentric coordinates `β`; its displacement is X's interpolated
//! there and turned into Y's frame:
//!
//! ```text
//! d_Y(j) = s·R · (β_a d_a + β_b d_b + β_c d_c)
//! ```
//!
//! where `S(p) = s·R·p + t` is the similarity from X to Y fitted by least squares on the
//! matched pairs `(φ(y_j), y_j)` (Horn's closed form): a Y that lies turned, moved or
//! scaled against X gets the expressions turned and scaled with it, and a Y in X's pose
//! gets them unchanged (`s·R ≈ I`). Vertices of Y without a counterpart get the harmonic
//! extension of the transferred displacements ([`super::morph::harmonic_extension`]), as
//! a morph's unmatched vertices do.
//!
//! This is exact when expressions add to identities, as in a linear face model (ICT's:
//! `identity + (expression − neutral)`, vertex by vertex), and the correspondence is
//! right; it is what the simplest deformation transfer does. It does not adapt an
//! expression to the new face's shape (a wider mouth opens by the same amount): per-triangle
//! deformation gradients solved in least squares (Sumner & Popović 2004) would, at the
//! cost of a Poisson solve per key (not done here).

use super::AppError;
use super::correspondence::check_correspondence;
use super::morph::{MorphTarget, harmonic_extension};
use crate::matching::similarity::{Similarity3, fit_similarity_3d};
use crate::mesh::{SurfacePoint, TriMesh};

/// Carries the keys `displacements_x` (one field per key, each one displacement per
/// vertex of `x`) onto `y` through `y_to_x` (one entry per vertex of `y`: a point of `x`,
/// or `None`), as the [module documentation](self) says. Returns one morph target per
/// key, on `y`'s vertices, and the similarity X → Y the displacements were turned by.
pub fn retarget_keys(
    x: &TriMesh,
    displacements_x: &[Vec<[f64; 3]>],
    y: &TriMesh,
    y_to_x: &[Option<SurfacePoint>],
) -> Result<(Vec<MorphTarget>, Similarity3), AppError> {
    check_correspondence(y_to_x, y.num_vertices(), x.triangles.len())?;
    crate::mesh::check_indices(&x.triangles, x.positions.len())?;
    for d in displacements_x {
        if d.len() != x.num_vertices() {
            return Err(AppError::per_vertex(
                "key displacements",
                d.len(),
                x.num_vertices(),
            ));
        }
    }
    let (from, to): (Vec<[f64; 3]>, Vec<[f64; 3]>) = y_to_x
        .iter()
        .zip(&y.positions)
        .filter_map(|(p, q)| p.map(|p| (p.position(&x.positions, &x.triangles), *q)))
        .unzip();
    if from.is_empty() {
        return Err(AppError::NothingMatched);
    }
    let similarity = fit_similarity_3d(&from, &to, &vec![1.0; from.len()], true)
        .filter(|s| s.scale().is_finite() && s.scale() > 0.0)
        .unwrap_or_else(Similarity3::identity);
    let m = similarity.matrix;
    let turn = |d: [f64; 3]| -> [f64; 3] {
        std::array::from_fn(|r| m[r][0] * d[0] + m[r][1] * d[1] + m[r][2] * d[2])
    };
    let matched = from.len();
    let mut targets = Vec::with_capacity(displacements_x.len());
    for d in displacements_x {
        let known: Vec<Option<[f64; 3]>> = y_to_x
            .iter()
            .map(|p| {
                p.map(|p| {
                    let [a, b, c] = x.triangles[p.triangle as usize].map(|v| d[v as usize]);
                    let w = p.barycentric;
                    turn(std::array::from_fn(|k| {
                        w[0] * a[k] + w[1] * b[k] + w[2] * c[k]
                    }))
                })
            })
            .collect();
        let extension = harmonic_extension(&y.positions, &y.triangles, &known)?;
        targets.push(MorphTarget {
            displacements: extension.values,
            matched,
            extended: extension.extended,
            unreferenced: extension.unreferenced,
        });
    }
    Ok((targets, similarity))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::apps::correspondence::tests::{analytic_map, graph_mesh};

    #[test]
    fn displacements_follow_the_correspondence_and_the_pose() {
        // X: a tilted plane (both triangulations are exactly the same surface, so the fit
        // is exact); its key moves every point by (0.05, 0, 0.1·x) (linear, so
        // interpolation is exact). Y: another triangulation of the same surface, turned
        // by 90° about z and moved; the map Y → X is the inverse motion.
        let x = graph_mesh(10, 0.5, 1, |u, v| 0.2 * u + 0.1 * v);
        let key: Vec<[f64; 3]> = x
            .positions
            .iter()
            .map(|p| [0.05, 0.0, 0.1 * p[0]])
            .collect();
        let y0 = graph_mesh(13, 0.5, 2, |u, v| 0.2 * u + 0.1 * v);
        let y_to_x = analytic_map(&y0, &x, |p| p);
        let turned = TriMesh::new(
            y0.positions
                .iter()
                .map(|p| [-p[1] + 3.0, p[0], p[2] - 1.0])
                .collect(),
            y0.triangles.clone(),
        );
        let (targets, s) = retarget_keys(&x, &[key], &turned, &y_to_x).unwrap();
        assert!((s.scale() - 1.0).abs() < 1e-9);
        let t = &targets[0];
        assert_eq!(t.matched, y0.num_vertices());
        for (d, p) in t.displacements.iter().zip(&y0.positions) {
            // The turn (x, y) ↦ (−y, x) carries X's x-direction onto Y's y-direction and
            // keeps z; the lift is X's at the corresponding point, 0.1·u of Y's own
            // (unturned) coordinates.
            assert!(d[0].abs() < 1e-9 && (d[1] - 0.05).abs() < 1e-9, "{d:?}");
            assert!((d[2] - 0.1 * p[0]).abs() < 1e-9, "{d:?} at {p:?}");
        }
        // Wrong lengths are errors that say what is wrong.
        let err = retarget_keys(&x, &[vec![[0.0; 3]; 3]], &turned, &y_to_x).unwrap_err();
        assert!(err.to_string().contains("key displacements"), "{err}");
    }
}
