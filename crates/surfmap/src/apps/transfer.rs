//! Transfer through a correspondence `φ: A → B` (one point of B per vertex of A): what
//! is defined on B is carried to A by evaluating it at the images, `f_A = f_B ∘ φ`.
//!
//! - **Values** (colours, scalar fields, any `[f64; D]` per vertex of B): linear
//!   interpolation in the image triangle, `f_A(a) = Σm λm f_B(b_m)`. For a smooth `f` the
//!   error is the linear interpolation error on B, `≤ ⅛ h² max|∇²f|` for triangles of
//!   diameter `h`.
//! - **Labels** (segment ids, material ids: values that must not be averaged): the label
//!   of the image triangle's corner with the largest barycentric coordinate (the nearest
//!   vertex within the triangle, in the barycentric sense).
//! - **Landmarks**: points of A (a vertex, or any surface point) carried to B, each point
//!   through [`push_point`] in a chart of B.
//! - **Texture coordinates**: A gets UVs into B's texture, interpolated from the image
//!   triangle's corner UVs. B's texture may be cut into charts (seams); a triangle of A
//!   whose corners land in different charts of B would stretch across the texture, and
//!   is reported ([`TransferredUvs::seam_triangles`]). For those, transfer the texture
//!   image itself instead.
//! - **Texture images**: B's texture re-rendered into A's own UV layout. Every texel of
//!   A's layout is a point of A, carried to B (a chart of B), where B's per-corner
//!   texture coordinates of the triangle it lands in give the colour: seams of B's
//!   texture are handled exactly, and A's texture is free of them where A's layout is.

use super::AppError;
use super::correspondence::{Chart, check_correspondence, push_point};
use super::pad::{PadReport, pad_colours};
use super::texture::{Texture, corner_uvs, render_layout, to_rgb_image};
use crate::mesh::{SurfacePoint, Uvs};

/// `f_B ∘ φ` for per-vertex values of B, linear in the image triangle; `None` where A's
/// vertex is unmatched.
pub fn transfer_values<const D: usize>(
    ab: &[Option<SurfacePoint>],
    triangles_b: &[[u32; 3]],
    values_b: &[[f64; D]],
) -> Result<Vec<Option<[f64; D]>>, AppError> {
    check_correspondence(ab, ab.len(), triangles_b.len())?;
    crate::mesh::check_indices(triangles_b, values_b.len())?;
    Ok(ab
        .iter()
        .map(|p| p.map(|p| p.interpolate(values_b, triangles_b)))
        .collect())
}

/// [`transfer_values`] for one scalar per vertex.
pub fn transfer_scalars(
    ab: &[Option<SurfacePoint>],
    triangles_b: &[[u32; 3]],
    values_b: &[f64],
) -> Result<Vec<Option<f64>>, AppError> {
    let wrapped: Vec<[f64; 1]> = values_b.iter().map(|&x| [x]).collect();
    Ok(transfer_values(ab, triangles_b, &wrapped)?
        .into_iter()
        .map(|v| v.map(|[x]| x))
        .collect())
}

/// The label of the image triangle's corner with the largest barycentric coordinate
/// (ties: the first corner); `None` where A's vertex is unmatched.
pub fn transfer_labels<L: Clone>(
    ab: &[Option<SurfacePoint>],
    triangles_b: &[[u32; 3]],
    labels_b: &[L],
) -> Result<Vec<Option<L>>, AppError> {
    check_correspondence(ab, ab.len(), triangles_b.len())?;
    crate::mesh::check_indices(triangles_b, labels_b.len())?;
    Ok(ab
        .iter()
        .map(|p| {
            p.map(|p| {
                let b = p.barycentric;
                let m = (1..3).fold(0, |best, k| if b[k] > b[best] { k } else { best });
                labels_b[triangles_b[p.triangle as usize][m] as usize].clone()
            })
        })
        .collect())
}

/// Landmarks of A carried to B: each point of A (a triangle of `triangles_a` with
/// barycentric coordinates; a vertex is a corner `[1, 0, 0]`) through [`push_point`].
pub fn transfer_landmarks(
    landmarks_a: &[SurfacePoint],
    triangles_a: &[[u32; 3]],
    ab: &[Option<SurfacePoint>],
    chart_b: &Chart,
) -> Result<Vec<Option<SurfacePoint>>, AppError> {
    check_correspondence(ab, ab.len(), chart_b.triangles().len())?;
    crate::mesh::check_indices(triangles_a, ab.len())?;
    if let Some(i) = landmarks_a
        .iter()
        .position(|p| p.triangle as usize >= triangles_a.len())
    {
        return Err(AppError::Option(format!(
            "landmark {i} names triangle {} of A, which has {} triangles",
            landmarks_a[i].triangle,
            triangles_a.len()
        )));
    }
    Ok(landmarks_a
        .iter()
        .map(|&p| push_point(p, triangles_a, ab, chart_b))
        .collect())
}

/// Texture coordinates of A into B's texture.
#[derive(Clone, Debug, PartialEq)]
pub struct TransferredUvs {
    /// One UV per vertex of A (`None` where unmatched).
    pub uvs: Vec<Option<[f64; 2]>>,
    /// Triangles of A whose corners land in different charts of B's texture: their
    /// UVs span a seam of B's texture, and they show the texture wrongly.
    pub seam_triangles: Vec<u32>,
}

/// A's texture coordinates into B's texture (see the [module documentation](self)).
/// Charts of B's texture are the parts of B connected across edges whose two corner UVs
/// agree on both sides.
pub fn transfer_uvs(
    ab: &[Option<SurfacePoint>],
    triangles_a: &[[u32; 3]],
    triangles_b: &[[u32; 3]],
    uvs_b: &Uvs,
) -> Result<TransferredUvs, AppError> {
    check_correspondence(ab, ab.len(), triangles_b.len())?;
    crate::mesh::check_indices(triangles_a, ab.len())?;
    let corners = corner_uvs(uvs_b, triangles_b)?;
    let uvs: Vec<Option<[f64; 2]>> = ab
        .iter()
        .map(|p| {
            p.map(|p| {
                let c = corners[p.triangle as usize];
                let b = p.barycentric;
                [0, 1].map(|k| b[0] * c[0][k] + b[1] * c[1][k] + b[2] * c[2][k])
            })
        })
        .collect();
    let chart = texture_charts(triangles_b, &corners);
    let seam_triangles = triangles_a
        .iter()
        .enumerate()
        .filter(|(_, tri)| {
            let ids: Vec<u32> = tri
                .iter()
                .filter_map(|&v| ab[v as usize].map(|p| chart[p.triangle as usize]))
                .collect();
            ids.windows(2).any(|w| w[0] != w[1])
        })
        .map(|(t, _)| t as u32)
        .collect();
    Ok(TransferredUvs {
        uvs,
        seam_triangles,
    })
}

/// The chart id of every triangle of a textured mesh: triangles sharing an edge whose
/// texture coordinates agree at both ends are in one chart.
pub fn texture_charts(triangles: &[[u32; 3]], corners: &[[[f64; 2]; 3]]) -> Vec<u32> {
    use std::collections::HashMap;
    let mut parent: Vec<u32> = (0..triangles.len() as u32).collect();
    fn find(parent: &mut [u32], mut a: u32) -> u32 {
        while parent[a as usize] != a {
            parent[a as usize] = parent[parent[a as usize] as usize];
            a = parent[a as usize];
        }
        a
    }
    // Directed edge (i, j) of triangle t with its corner UVs.
    let mut edges: HashMap<(u32, u32), (u32, [u64; 4])> = HashMap::new();
    let key = |p: [f64; 2], q: [f64; 2]| {
        [
            p[0].to_bits(),
            p[1].to_bits(),
            q[0].to_bits(),
            q[1].to_bits(),
        ]
    };
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (i, j) = (tri[k], tri[(k + 1) % 3]);
            let (ui, uj) = (corners[t][k], corners[t][(k + 1) % 3]);
            // The neighbour traverses the edge as (j, i): its UVs must be (uj, ui).
            if let Some(&(s, uv)) = edges.get(&(j, i))
                && uv == key(uj, ui)
            {
                let (a, b) = (find(&mut parent, s), find(&mut parent, t as u32));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                }
            }
            edges.insert((i, j), (t as u32, key(ui, uj)));
        }
    }
    (0..triangles.len() as u32)
        .map(|t| find(&mut parent, t))
        .collect()
}

/// B's texture re-rendered into A's UV layout.
#[derive(Clone, Debug)]
pub struct TransferredTexture {
    pub image: image::RgbImage,
    /// Texels covered by matched points of A.
    pub covered: Vec<bool>,
    pub padding: PadReport,
}

/// Renders B's texture (`texture_b` through B's texture coordinates `uvs_b`) into A's
/// own UV layout `uvs_a` (per vertex or per corner, in `[0, 1]²`), as a
/// `size × size` image with `samples²` samples per texel and `padding` rings of padding.
/// Each sample is a point of A, carried to B in `chart_b` (a flattening of B).
#[allow(clippy::too_many_arguments)]
pub fn transfer_texture(
    triangles_a: &[[u32; 3]],
    uvs_a: &Uvs,
    ab: &[Option<SurfacePoint>],
    chart_b: &Chart,
    uvs_b: &Uvs,
    texture_b: &Texture,
    size: u32,
    samples: u32,
    padding: u32,
) -> Result<TransferredTexture, AppError> {
    check_correspondence(ab, ab.len(), chart_b.triangles().len())?;
    crate::mesh::check_indices(triangles_a, ab.len())?;
    let layout = corner_uvs(uvs_a, triangles_a)?;
    let corners_b = corner_uvs(uvs_b, chart_b.triangles())?;
    if texture_b.width == 0 || texture_b.height == 0 {
        return Err(AppError::Texture("B's texture image is empty".into()));
    }
    let image = render_layout(&layout, size, size, samples, |p| {
        let q = push_point(p, triangles_a, ab, chart_b)?;
        let c = corners_b[q.triangle as usize];
        let b = q.barycentric;
        let uv = [0, 1].map(|k| b[0] * c[0][k] + b[1] * c[1][k] + b[2] * c[2][k]);
        Some(texture_b.sample_linear(uv).map(|x| x / 255.0))
    })?;
    let covered = image.covered();
    let mut filled = covered.clone();
    let mut rgb = image.rgb;
    let padding = pad_colours(
        &mut rgb,
        &mut filled,
        size as usize,
        size as usize,
        padding as usize,
    );
    Ok(TransferredTexture {
        image: to_rgb_image(size, size, &rgb),
        covered,
        padding,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::apps::correspondence::tests::{analytic_map, graph_mesh, planar_chart};

    fn bump(x: f64, y: f64) -> f64 {
        0.2 * (1.4 * x).sin() * (1.7 * y + 0.3).cos()
    }

    #[test]
    fn scalar_field_there_and_back_returns_within_interpolation_error() {
        // f on A; g: B → A and its inverse f⁻¹... the analytic pair φ_AB(x) = F(x),
        // φ_BA(y) = F⁻¹(y) between two different triangulations. Pull f to B through
        // φ_BA, then back to A through φ_AB: f again, up to twice the linear
        // interpolation error ⅛ h² max|∇²f| (h the longest edge).
        let f = |x: f64, y: f64| (2.0 * x).sin() + 0.5 * (3.0 * y).cos() + x * y;
        let hess = 4.0 + 4.5 + 1.0; // |∂²f| bounded by 2²·1 + 3²·0.5 + 1 (all entries)
        let forward = |p: [f64; 2]| [0.8 * p[0] + 0.1 * p[1], 0.85 * p[1] - 0.05 * p[0]];
        let det = 0.8 * 0.85 + 0.1 * 0.05;
        let inverse = |q: [f64; 2]| {
            [
                (0.85 * q[0] - 0.1 * q[1]) / det,
                (0.8 * q[1] + 0.05 * q[0]) / det,
            ]
        };
        let mut errors = vec![];
        for n in [12usize, 24] {
            let a = graph_mesh(n, 0.5, 1, bump);
            let b = graph_mesh(n + 5, 0.5, 2, bump);
            let ab = analytic_map(&a, &b, forward);
            // B → A: only B's vertices whose image lies in A's square are matched.
            let ba = analytic_map(&b, &a, inverse);
            let on_a: Vec<f64> = a.positions.iter().map(|p| f(p[0], p[1])).collect();
            let on_b = transfer_scalars(&ba, &a.triangles, &on_a).unwrap();
            assert!(on_b.iter().any(Option::is_none) && on_b.iter().any(Option::is_some));
            // B's vertices without a value: A's vertices whose image triangle uses one
            // come back unmatched. Fill with NaN to see them.
            let on_b: Vec<f64> = on_b.iter().map(|v| v.unwrap_or(f64::NAN)).collect();
            let back = transfer_scalars(&ab, &b.triangles, &on_b).unwrap();
            let h = 2.0 * 2.0f64.sqrt() / n as f64 * 1.5; // longest edge, jitter included
            let bound = 2.0 * hess * h * h / 8.0;
            let mut worst = 0.0f64;
            let mut compared = 0;
            for (v, w) in back.iter().zip(&on_a) {
                if let Some(v) = v.filter(|v| v.is_finite()) {
                    worst = worst.max((v - w).abs());
                    compared += 1;
                }
            }
            assert!(compared > a.num_vertices() / 2, "{compared}");
            assert!(
                worst < bound,
                "n {n}: error {worst:e} above the bound {bound:e}"
            );
            errors.push(worst);
        }
        assert!(errors[1] < 0.45 * errors[0], "not second order: {errors:?}");
    }

    #[test]
    fn labels_take_the_nearest_corner_and_values_interpolate() {
        let tris = [[0, 1, 2]];
        let p = |b| {
            Some(SurfacePoint {
                triangle: 0,
                barycentric: b,
            })
        };
        let ab = [p([0.2, 0.5, 0.3]), None, p([0.4, 0.2, 0.4])];
        let labels = transfer_labels(&ab, &tris, &["eye", "nose", "mouth"]).unwrap();
        assert_eq!(labels, vec![Some("nose"), None, Some("eye")]);
        let colours = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let v = transfer_values(&ab, &tris, &colours).unwrap();
        assert_eq!(v[0], Some([0.2, 0.5, 0.3]));
        assert!(transfer_values(&ab, &tris, &colours[..2]).is_err());
    }

    #[test]
    fn landmarks_land_at_their_analytic_images() {
        let a = graph_mesh(10, 0.5, 1, bump);
        let b = graph_mesh(13, 0.5, 2, bump);
        let f = |p: [f64; 2]| [0.7 * p[0] + 0.05 * p[1] * p[1], 0.75 * p[1]];
        let ab = analytic_map(&a, &b, f);
        let chart = planar_chart(&b);
        let vertex = SurfacePoint::at_vertex(&a.triangles, 17).unwrap();
        let inside = SurfacePoint {
            triangle: 40,
            barycentric: [0.2, 0.3, 0.5],
        };
        let out = transfer_landmarks(&[vertex, inside], &a.triangles, &ab, &chart).unwrap();
        // A vertex lands exactly on its correspondence's point.
        let on_b = |p: SurfacePoint| p.position(&b.positions, &b.triangles);
        let exact = on_b(ab[17].unwrap());
        assert_eq!(on_b(out[0].unwrap()), exact);
        // A point inside a triangle lands within the interpolation error of f(x).
        let x = inside.position(&a.positions, &a.triangles);
        let y = on_b(out[1].unwrap());
        let want = f([x[0], x[1]]);
        assert!(
            (y[0] - want[0]).abs() < 2e-3 && (y[1] - want[1]).abs() < 2e-3,
            "{y:?} vs {want:?}"
        );
        let bad = SurfacePoint {
            triangle: 9999,
            barycentric: [1.0, 0.0, 0.0],
        };
        assert!(transfer_landmarks(&[bad], &a.triangles, &ab, &chart).is_err());
    }

    #[test]
    fn uvs_into_a_seamed_texture_report_the_triangles_across_the_seam() {
        // B: the square, its texture cut along x = 0 into two charts (the right half
        // shifted by 0.5 in u). A: another triangulation, mapped by the identity.
        let n = 8;
        let mut b = graph_mesh(n, 0.0, 2, |_, _| 0.0);
        for p in &mut b.positions {
            if p[0].abs() < 1e-9 {
                p[0] = 0.0;
            }
        }
        let a = graph_mesh(11, 0.4, 3, |_, _| 0.0);
        let ab = analytic_map(&a, &b, |p| p);
        let uv_of = |x: f64, y: f64, right: bool| {
            [
                0.25 * (x + 1.0) + if right { 0.5 } else { 0.0 },
                0.5 * (y + 1.0),
            ]
        };
        let uvs_b = crate::apps::inputs::seamed_uvs(&b, uv_of);
        let out = transfer_uvs(&ab, &a.triangles, &b.triangles, &uvs_b).unwrap();
        // Away from the seam, A's UV is the analytic one.
        for (p, uv) in a.positions.iter().zip(&out.uvs) {
            if p[0].abs() > 0.01 {
                let want = uv_of(p[0], p[1], p[0] > 0.0);
                let uv = uv.unwrap();
                assert!((uv[0] - want[0]).abs() < 1e-12 && (uv[1] - want[1]).abs() < 1e-12);
            }
        }
        // Seam triangles: exactly A's triangles with corners on both sides of x = 0.
        for (t, tri) in a.triangles.iter().enumerate() {
            let xs = tri.map(|v| a.positions[v as usize][0]);
            let straddles = xs.iter().any(|&x| x < 0.0) && xs.iter().any(|&x| x > 0.0);
            assert_eq!(
                out.seam_triangles.contains(&(t as u32)),
                straddles,
                "triangle {t} {xs:?}"
            );
        }
        let charts = texture_charts(&b.triangles, &corner_uvs(&uvs_b, &b.triangles).unwrap());
        let distinct: std::collections::HashSet<u32> = charts.into_iter().collect();
        assert_eq!(distinct.len(), 2);
    }

    #[test]
    fn texture_transfer_follows_the_map_across_seams_of_b() {
        // B's texture holds a pattern of the square through a seamed layout (two charts,
        // the right one mirrored); A's own layout is a plain scaled copy. The texture
        // rendered for A must show the pattern at the analytic image of each point.
        let pattern = |x: f64, y: f64| {
            [
                0.5 + 0.4 * (2.0 * x).sin(),
                0.5 + 0.4 * (1.5 * y).cos(),
                0.5,
            ]
        };
        let n = 12;
        let mut b = graph_mesh(n, 0.3, 2, bump);
        let h = 2.0 / n as f64;
        for p in &mut b.positions {
            if p[0].abs() < 0.16 * h {
                p[0] = 0.0;
            }
        }
        let a = graph_mesh(15, 0.4, 3, |x, y| 0.1 * x * y);
        let f = |p: [f64; 2]| [0.8 * p[0] + 0.05 * p[1], 0.8 * p[1]];
        let ab = analytic_map(&a, &b, f);
        let side = 256u32;
        let b_uv = |x: f64, y: f64, right: bool| {
            let v = 0.5 * (y + 1.0);
            // Two photographs with a gap between them (no bleeding across u = ½).
            if right {
                [0.95 - 0.4 * x, v]
            } else {
                [0.05 + 0.2 * (x + 1.0), v]
            }
        };
        let uvs_b = crate::apps::inputs::seamed_uvs(&b, b_uv);
        let texture_b = crate::apps::inputs::texture_from(side, |u, v| {
            let y = 2.0 * v - 1.0;
            let x = if u < 0.5 {
                (u - 0.05) / 0.2 - 1.0
            } else {
                (0.95 - u) / 0.4
            };
            pattern(x, y)
        });
        let uvs_a = Uvs::PerVertex(
            a.positions
                .iter()
                .map(|p| [0.5 * (p[0] + 1.0), 0.5 * (p[1] + 1.0)])
                .collect(),
        );
        let out = transfer_texture(
            &a.triangles,
            &uvs_a,
            &ab,
            &planar_chart(&b),
            &uvs_b,
            &texture_b,
            128,
            2,
            4,
        )
        .unwrap();
        let got = Texture {
            width: 128,
            height: 128,
            rgb: out.image.pixels().map(|p| p.0).collect(),
        };
        let mut worst = 0.0f64;
        for yy in (4..124).step_by(5) {
            for xx in (4..124).step_by(5) {
                let (u, v) = ((xx as f64 + 0.5) / 128.0, 1.0 - (yy as f64 + 0.5) / 128.0);
                let q = f([2.0 * u - 1.0, 2.0 * v - 1.0]);
                let want = pattern(q[0], q[1]);
                let c = got.sample_linear([u, v]).map(|x| x / 255.0);
                for k in 0..3 {
                    worst = worst.max((c[k] - want[k]).abs());
                }
            }
        }
        assert!(worst < 0.03, "colour error {worst}");
        assert!(
            out.covered.iter().all(|&c| c),
            "A's layout covers the whole image"
        );
    }
}
