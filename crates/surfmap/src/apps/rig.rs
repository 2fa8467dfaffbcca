//! Blend-shape rigs (thesis §5.3, figs. 5.4–5.5): every key pose, a surface of its own
//! triangulation, is re-expressed on the neutral's connectivity through a
//! correspondence neutral → key, as the morph target of that correspondence
//! ([`super::morph`]): key `i` on the neutral's mesh is `x + d_i`, and a blend is
//! `x + Σ_i w_i d_i`.
//!
//! **Chains.** Keys that are far from the neutral but close to each other (neutral →
//! smile → wide smile) are matched in sequence, `φ_01: N → K_1`, `φ_12: K_1 → K_2`, …,
//! and key `i` uses the composition `φ_(i−1)i ∘ … ∘ φ_01` ([`super::correspondence::compose`]).
//! The thesis uses it for the second segment of an animation, blending `φ_AB(M_A)` into
//! `M_C` with `φ_BC ∘ φ_AB`, which makes the two segments meet seamlessly: at the
//! transition both are the same surface on the same connectivity.

use super::AppError;
use super::correspondence::{Chart, compose};
use super::morph::{MorphTarget, morph_target};
use crate::mesh::{SurfacePoint, TriMesh};

/// One key of a rig on the neutral's connectivity.
#[derive(Clone, Debug)]
pub struct RigKey {
    pub name: String,
    /// The morph target neutral → key (displacements, matched and extended vertices).
    pub target: MorphTarget,
}

impl RigKey {
    /// The key as a mesh with the neutral's connectivity: `x + d`.
    pub fn mesh(&self, neutral: &TriMesh) -> TriMesh {
        TriMesh {
            positions: self.target.frame(&neutral.positions, 1.0),
            triangles: neutral.triangles.clone(),
            uvs: neutral.uvs.clone(),
        }
    }
}

/// Key `name` re-expressed on the neutral's connectivity through the correspondence
/// `neutral_to_key` (one entry per neutral vertex, points of `key`).
pub fn rig_key(
    name: &str,
    neutral: &TriMesh,
    neutral_to_key: &[Option<SurfacePoint>],
    key: &TriMesh,
) -> Result<RigKey, AppError> {
    Ok(RigKey {
        name: name.to_owned(),
        target: morph_target(
            &neutral.positions,
            &neutral.triangles,
            neutral_to_key,
            &key.positions,
            &key.triangles,
        )?,
    })
}

/// One link of a chain: the correspondence from the previous surface (the neutral for
/// the first link) to this key, with the key's triangles and a chart of it (needed
/// from the second link on, to compose).
pub struct ChainLink<'a> {
    pub map: &'a [Option<SurfacePoint>],
    pub triangles: &'a [[u32; 3]],
    pub chart: Option<&'a Chart>,
}

/// The correspondences neutral → key `i` of a chain neutral → K_1 → K_2 → …: the first
/// link as it is, then each composed with the next (`φ_i ∘ … ∘ φ_1`).
pub fn chain_maps(links: &[ChainLink]) -> Result<Vec<Vec<Option<SurfacePoint>>>, AppError> {
    let mut out: Vec<Vec<Option<SurfacePoint>>> = Vec::with_capacity(links.len());
    for (i, link) in links.iter().enumerate() {
        let composed = match out.last() {
            None => link.map.to_vec(),
            Some(previous) => {
                let chart = link.chart.ok_or_else(|| {
                    AppError::Option(format!(
                        "chain link {}: composing needs a chart (flattening) of key {}",
                        i + 1,
                        i + 1
                    ))
                })?;
                compose(previous, links[i - 1].triangles, link.map, chart)?
            }
        };
        out.push(composed);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::apps::correspondence::tests::{analytic_map, graph_mesh, planar_chart};

    #[test]
    fn keys_on_the_neutral_connectivity_follow_the_key_surfaces() {
        // Neutral and two keys: graphs of different heights over the square, each its own
        // triangulation; correspondences by vertical projection (identity in the plane).
        let neutral = graph_mesh(10, 0.5, 1, |_, _| 0.0);
        let k1 = graph_mesh(13, 0.5, 2, |x, _| 0.2 * x * x);
        let k2 = graph_mesh(12, 0.5, 3, |x, y| 0.2 * x * x + 0.1 * y);
        let m1 = analytic_map(&neutral, &k1, |p| p);
        let key = rig_key("smile", &neutral, &m1, &k1).unwrap();
        let mesh = key.mesh(&neutral);
        assert_eq!(mesh.triangles, neutral.triangles);
        for (p, q) in mesh.positions.iter().zip(&neutral.positions) {
            assert!((p[0] - q[0]).abs() < 1e-12 && (p[1] - q[1]).abs() < 1e-12);
            // Height on k1's piecewise-linear surface: within its interpolation error.
            assert!((p[2] - 0.2 * p[0] * p[0]).abs() < 0.2 * 0.25 * 0.2 * 0.2);
        }
        // The chain neutral → k1 → k2 composed equals the direct map (identity) on k2.
        let m12 = analytic_map(&k1, &k2, |p| p);
        let chart2 = planar_chart(&k2);
        let chain = chain_maps(&[
            ChainLink {
                map: &m1,
                triangles: &k1.triangles,
                chart: None,
            },
            ChainLink {
                map: &m12,
                triangles: &k2.triangles,
                chart: Some(&chart2),
            },
        ])
        .unwrap();
        assert_eq!(chain[0], m1);
        let direct = analytic_map(&neutral, &k2, |p| p);
        let d =
            crate::apps::compare_maps(&chain[1], &direct, &k2.positions, &k2.triangles).unwrap();
        assert_eq!(d.compared, neutral.num_vertices());
        assert!(d.max < 1e-12, "identity chain moved points by {:e}", d.max);
        // A missing chart is an error that says which.
        let err = chain_maps(&[
            ChainLink {
                map: &m1,
                triangles: &k1.triangles,
                chart: None,
            },
            ChainLink {
                map: &m12,
                triangles: &k2.triangles,
                chart: None,
            },
        ])
        .unwrap_err();
        assert!(err.to_string().contains("chart"), "{err}");
    }
}
