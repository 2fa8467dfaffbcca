//! Texture images: reading one ([`Texture`], bilinear sampling, `v` up), the texture
//! coordinates of each triangle corner, and rendering any function of surface points
//! into a UV layout ([`render_layout`]), the one rasterizer behind texture baking and
//! texture transfer.
//!
//! **Conventions** (as OBJ and glTF viewers use them): texture coordinate `(u, v)` is
//! the point `(u·W, (1 − v)·H)` of a `W × H` image whose row 0 is at the top; texel
//! `(x, y)` covers `[x, x + 1) × [y, y + 1)` and its centre is at `(u, v) =
//! ((x + ½)/W, 1 − (y + ½)/H)`.

use rayon::prelude::*;

use super::AppError;
use crate::mesh::{SurfacePoint, Uvs};

/// An RGB texture image with bilinear sampling (the geometry-image texture type).
pub use crate::raster::TextureImage as Texture;

/// Reads a texture image (PNG; alpha ignored).
pub fn read_texture(path: &std::path::Path) -> Result<Texture, AppError> {
    Texture::read(path).map_err(|e| AppError::Texture(e.to_string()))
}

/// The texture coordinates of every triangle corner: `corner_uvs[t][k]` for corner `k`
/// of triangle `t`, from per-vertex or per-corner UVs.
pub fn corner_uvs(uvs: &Uvs, triangles: &[[u32; 3]]) -> Result<Vec<[[f64; 2]; 3]>, AppError> {
    match uvs {
        Uvs::PerVertex(uv) => {
            crate::mesh::check_indices(triangles, uv.len())?;
            Ok(triangles
                .iter()
                .map(|t| t.map(|v| uv[v as usize]))
                .collect())
        }
        Uvs::PerCorner { coords, indices } => {
            if indices.len() != triangles.len() {
                return Err(AppError::Length {
                    what: "texture coordinate triples",
                    got: indices.len(),
                    expected: triangles.len(),
                    per: "triangles",
                    per_one: "triangle",
                });
            }
            crate::mesh::check_indices(indices, coords.len())?;
            Ok(indices
                .iter()
                .map(|t| t.map(|i| coords[i as usize]))
                .collect())
        }
    }
}

/// A rendered UV layout: a colour per texel, averaged over the texel's covered samples,
/// and how many of its samples a triangle covered.
#[derive(Clone, Debug, PartialEq)]
pub struct LayoutImage {
    pub width: u32,
    pub height: u32,
    /// Row-major, row 0 at the top; channels in `[0, 1]`; black where not covered.
    pub rgb: Vec<[f64; 3]>,
    /// Covered samples per texel, `0..=samples²`.
    pub coverage: Vec<u16>,
}

impl LayoutImage {
    /// Texels covered by at least one sample.
    pub fn covered(&self) -> Vec<bool> {
        self.coverage.iter().map(|&c| c > 0).collect()
    }
}

/// Renders `colour(point)` for every point of a surface into the UV layout given by
/// `corner_uvs` (one triple per triangle, in `[0, 1]²` for the whole image), with
/// `samples × samples` samples per texel (a box filter: anti-aliased chart edges,
/// source textures averaged over the texel's footprint).
///
/// A sample belongs to the first triangle (by index) whose closed UV triangle contains
/// it, so shared edges are neither left out nor counted twice; `colour` gets that
/// triangle and the sample's barycentric coordinates, and may decline (`None`, e.g. a
/// point that a correspondence leaves unmatched): the sample is then not covered.
/// Triangles with zero UV area cover nothing. Rows are rendered in parallel bands; no
/// allocation per sample.
pub fn render_layout(
    corner_uvs: &[[[f64; 2]; 3]],
    width: u32,
    height: u32,
    samples: u32,
    colour: impl Fn(SurfacePoint) -> Option<[f64; 3]> + Sync,
) -> Result<LayoutImage, AppError> {
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err(AppError::Option(format!(
            "texture size {width}×{height}: each side must be 1 to 16384 texels"
        )));
    }
    if !(1..=8).contains(&samples) {
        return Err(AppError::Option(format!(
            "{samples} samples per texel side: use 1 to 8"
        )));
    }
    let (w, h, s) = (width as usize, height as usize, samples as usize);
    const BAND: usize = 16;
    let bands = h.div_ceil(BAND);
    // Triangles listed per band of rows they may touch (pixel-space y-extent).
    let mut band_start = vec![0u32; bands + 1];
    let extent = |uv: &[[f64; 2]; 3]| -> Option<(usize, usize)> {
        let ys = uv.map(|p| (1.0 - p[1]) * h as f64);
        if ys
            .iter()
            .chain(uv.iter().map(|p| &p[0]))
            .any(|y| !y.is_finite())
        {
            return None;
        }
        let lo = ys
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
            .floor()
            .max(0.0);
        let hi = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max).ceil();
        (hi >= 0.0 && lo < h as f64).then(|| (lo as usize / BAND, (hi as usize).min(h - 1) / BAND))
    };
    for uv in corner_uvs {
        if let Some((b0, b1)) = extent(uv) {
            for b in b0..=b1 {
                band_start[b + 1] += 1;
            }
        }
    }
    for b in 0..bands {
        band_start[b + 1] += band_start[b];
    }
    let mut fill = band_start.clone();
    let mut band_list = vec![0u32; band_start[bands] as usize];
    for (t, uv) in corner_uvs.iter().enumerate() {
        if let Some((b0, b1)) = extent(uv) {
            for b in b0..=b1 {
                band_list[fill[b] as usize] = t as u32;
                fill[b] += 1;
            }
        }
    }

    let mut rgb = vec![[0.0; 3]; w * h];
    let mut coverage = vec![0u16; w * h];
    rgb.par_chunks_mut(w * BAND)
        .zip(coverage.par_chunks_mut(w * BAND))
        .enumerate()
        .for_each(|(b, (rgb, coverage))| {
            let rows = rgb.len() / w;
            let y0 = b * BAND;
            // Samples of this band already taken by a lower-index triangle.
            let mut taken = vec![false; rows * s * w * s];
            let ws = (w * s) as f64;
            let hs = (h * s) as f64;
            for &t in &band_list[band_start[b] as usize..band_start[b + 1] as usize] {
                let uv = corner_uvs[t as usize];
                // Sample space: x_s = u·W·s, y_s = (1 − v)·H·s; sample (i, j) at (i + ½, j + ½).
                let q = uv.map(|p| [p[0] * ws, (1.0 - p[1]) * hs]);
                let area = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1])
                    - (q[2][0] - q[0][0]) * (q[1][1] - q[0][1]);
                if area == 0.0 || !area.is_finite() {
                    continue;
                }
                let inv = 1.0 / area;
                let xs = q.map(|p| p[0]);
                let ys = q.map(|p| p[1]);
                let fmin = |v: [f64; 3]| v[0].min(v[1]).min(v[2]);
                let fmax = |v: [f64; 3]| v[0].max(v[1]).max(v[2]);
                let i0 = (fmin(xs) - 0.5).ceil().max(0.0) as usize;
                let i1 = ((fmax(xs) - 0.5).floor()).min((w * s) as f64 - 1.0);
                let j0 = ((fmin(ys) - 0.5).ceil()).max((y0 * s) as f64) as usize;
                let j1 = ((fmax(ys) - 0.5).floor()).min(((y0 + rows) * s) as f64 - 1.0);
                if i1 < i0 as f64 || j1 < j0 as f64 {
                    continue;
                }
                let (i1, j1) = (i1 as usize, j1 as usize);
                for j in j0..=j1 {
                    let y = j as f64 + 0.5;
                    let local_row = j - y0 * s;
                    for i in i0..=i1 {
                        let slot = local_row * w * s + i;
                        if taken[slot] {
                            continue;
                        }
                        let x = i as f64 + 0.5;
                        let l0 =
                            ((q[1][0] - x) * (q[2][1] - y) - (q[2][0] - x) * (q[1][1] - y)) * inv;
                        let l1 =
                            ((q[2][0] - x) * (q[0][1] - y) - (q[0][0] - x) * (q[2][1] - y)) * inv;
                        let l2 = 1.0 - l0 - l1;
                        if l0 < 0.0 || l1 < 0.0 || l2 < 0.0 {
                            continue;
                        }
                        let point = SurfacePoint {
                            triangle: t,
                            barycentric: [l0, l1, l2],
                        };
                        if let Some(c) = colour(point) {
                            taken[slot] = true;
                            let texel = (local_row / s) * w + i / s;
                            for k in 0..3 {
                                rgb[texel][k] += c[k];
                            }
                            coverage[texel] += 1;
                        }
                    }
                }
            }
            for (c, &n) in rgb.iter_mut().zip(coverage.iter()) {
                if n > 0 {
                    *c = c.map(|x| x / n as f64);
                }
            }
        });
    Ok(LayoutImage {
        width,
        height,
        rgb,
        coverage,
    })
}

/// UVs placed in `[0, 1]²` with a margin of `margin` (a fraction of the side) on every
/// side: scaled uniformly (aspect kept) and centred.
pub fn place_in_unit_square(uvs: &[[f64; 2]], margin: f64) -> Vec<[f64; 2]> {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in uvs.iter().filter(|p| p[0].is_finite() && p[1].is_finite()) {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if !(span > 0.0 && span.is_finite()) {
        return vec![[0.5, 0.5]; uvs.len()];
    }
    let scale = (1.0 - 2.0 * margin) / span;
    let offset = [0, 1].map(|k| 0.5 - 0.5 * scale * (lo[k] + hi[k]));
    uvs.iter()
        .map(|p| [scale * p[0] + offset[0], scale * p[1] + offset[1]])
        .collect()
}

/// The UVs rotated about the origin so that they fit the smallest square: the angle in
/// `[0°, 90°)`, in steps of ½°, that minimizes the longer side of their bounding box
/// (a flattening is defined up to a rotation; a chart standing on a corner would waste
/// half the texture).
pub fn rotate_to_fit(uvs: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let side = |angle: f64| -> f64 {
        let (s, c) = angle.sin_cos();
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in uvs.iter().filter(|p| p[0].is_finite() && p[1].is_finite()) {
            let q = [c * p[0] - s * p[1], s * p[0] + c * p[1]];
            for k in 0..2 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        (hi[0] - lo[0]).max(hi[1] - lo[1])
    };
    let best = (0..180)
        .map(|k| (k as f64 * 0.5).to_radians())
        .min_by(|&a, &b| side(a).total_cmp(&side(b)))
        .unwrap_or(0.0);
    let (s, c) = best.sin_cos();
    uvs.iter()
        .map(|p| [c * p[0] - s * p[1], s * p[0] + c * p[1]])
        .collect()
}

/// An `RgbImage` from colours in `[0, 1]` (rounded, clamped).
pub fn to_rgb_image(width: u32, height: u32, rgb: &[[f64; 3]]) -> image::RgbImage {
    let mut img = image::RgbImage::new(width, height);
    for (p, c) in img.pixels_mut().zip(rgb) {
        p.0 = c.map(|x| (x * 255.0).round().clamp(0.0, 255.0) as u8);
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_of_two_triangles_covers_the_square_once() {
        // The unit square as two triangles sharing a diagonal: every sample is covered
        // exactly once, and the colour is affine in the UV (exact at texel centres).
        let uv = [
            [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
            [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        ];
        let f = |p: [f64; 2]| [p[0], p[1], 0.5];
        let img = render_layout(&uv, 37, 21, 3, |p| {
            let c = uv[p.triangle as usize];
            let b = p.barycentric;
            Some(f(
                [0, 1].map(|k| b[0] * c[0][k] + b[1] * c[1][k] + b[2] * c[2][k])
            ))
        })
        .unwrap();
        assert!(
            img.coverage.iter().all(|&c| c == 9),
            "a sample counted twice or missed"
        );
        for y in 0..21 {
            for x in 0..37 {
                let want = f([(x as f64 + 0.5) / 37.0, 1.0 - (y as f64 + 0.5) / 21.0]);
                let got = img.rgb[y * 37 + x];
                for k in 0..3 {
                    assert!(
                        (got[k] - want[k]).abs() < 1e-12,
                        "({x}, {y}): {got:?} vs {want:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn partial_coverage_counts_samples_and_declined_points_stay_empty() {
        // A triangle covering the lower-left half of a 4×4 image: diagonal texels are
        // half covered (with 4×4 samples: 6 of 16 strictly below, ties on the diagonal
        // belong to the triangle).
        let uv = [[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]];
        let img = render_layout(&uv, 4, 4, 4, |_| Some([1.0; 3])).unwrap();
        // Texel (x, y) with y from the top: covered fully when x + (3 − y) < 3.
        for y in 0..4 {
            for x in 0..4 {
                let c = img.coverage[y * 4 + x];
                let d = x as i32 + (3 - y as i32);
                let want = match d.cmp(&3) {
                    std::cmp::Ordering::Less => 16,
                    std::cmp::Ordering::Equal => 10, // 6 below the diagonal + 4 on it
                    std::cmp::Ordering::Greater => 0,
                };
                assert_eq!(c, want, "texel ({x}, {y})");
            }
        }
        let none = render_layout(&uv, 4, 4, 2, |_| None).unwrap();
        assert!(none.coverage.iter().all(|&c| c == 0));
        assert!(render_layout(&uv, 0, 4, 2, |_| None).is_err());
        assert!(render_layout(&uv, 4, 4, 9, |_| None).is_err());
    }

    #[test]
    fn placement_keeps_aspect_and_margin() {
        let p = place_in_unit_square(&[[2.0, 1.0], [6.0, 1.0], [2.0, 3.0]], 0.1);
        let want = [[0.1, 0.3], [0.9, 0.3], [0.1, 0.7]];
        assert!(
            crate::testing::max_uv_difference(&p, &want) < 1e-15,
            "{p:?}"
        );
    }

    #[test]
    fn a_square_on_its_corner_is_turned_upright() {
        let diamond = [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]];
        let upright = rotate_to_fit(&diamond);
        for p in &upright {
            assert!((p[0].abs() - 0.5f64.sqrt()).abs() < 1e-12, "{p:?}");
            assert!((p[1].abs() - 0.5f64.sqrt()).abs() < 1e-12, "{p:?}");
        }
    }

    #[test]
    fn corner_uvs_follow_their_indices() {
        let tris = [[0, 1, 2], [2, 1, 3]];
        let per_vertex = Uvs::PerVertex(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]);
        let c = corner_uvs(&per_vertex, &tris).unwrap();
        assert_eq!(c[1], [[0.0, 1.0], [1.0, 0.0], [1.0, 1.0]]);
        let per_corner = Uvs::PerCorner {
            coords: vec![[0.5, 0.5], [0.25, 0.0]],
            indices: vec![[0, 1, 0], [1, 1, 0]],
        };
        assert_eq!(corner_uvs(&per_corner, &tris).unwrap()[1][2], [0.5, 0.5]);
        let short = Uvs::PerVertex(vec![[0.0; 2]; 3]);
        assert!(corner_uvs(&short, &tris).is_err());
    }
}
