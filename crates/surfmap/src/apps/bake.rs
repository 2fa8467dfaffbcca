//! Texture baking (thesis §5.1, fig. 5.2): a surface whose texture coordinates are
//! discontinuous (several photographs stitched together) or badly distorted gets a new
//! parameterization (a flattening, flip-free), and a new texture image is rendered in
//! the new parameter domain: every point `p` of the surface takes the colour the old
//! texture gives it,
//!
//! ```text
//! new_texture( u_new(p) ) = old_texture( u_old(p) ),
//! ```
//!
//! with `u_old` and `u_new` linear on each triangle (per-corner old coordinates, so seams
//! of the old texture are fine). Each texel of the new image averages
//! `samples × samples` samples of its footprint (the old texture is sampled bilinearly),
//! and colours are padded a few texels beyond the chart's boundary ([`super::pad`]) so
//! that mipmapping shows no seam. A surface without a texture can bake per-vertex colours
//! or a scalar field through a colour map instead.

use image::RgbImage;

use super::AppError;
use super::pad::{PadReport, pad_colours};
use super::texture::{
    LayoutImage, Texture, place_in_unit_square, render_layout, rotate_to_fit, to_rgb_image,
};
use crate::render::Colormap;

/// Size and filtering of a baked texture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BakeOptions {
    /// Texels per side (the image is square).
    pub size: u32,
    /// Samples per texel side (box filter): 2 averages 4 samples per texel.
    pub samples: u32,
    /// Rings of texels padded beyond the chart's boundary (then the chart's mean colour
    /// everywhere else). 8 keeps mipmap levels 0–3 free of background colour.
    pub padding: u32,
}

impl Default for BakeOptions {
    fn default() -> Self {
        Self {
            size: 2048,
            samples: 2,
            padding: 8,
        }
    }
}

/// A baked texture with the texture coordinates it belongs to.
#[derive(Clone, Debug)]
pub struct BakedTexture {
    pub image: RgbImage,
    /// New texture coordinates, one per vertex: the flattening turned to fit the
    /// smallest square ([`rotate_to_fit`]) and placed in `[0, 1]²` with a margin of
    /// `padding + 1` texels (aspect kept).
    pub uvs: Vec<[f64; 2]>,
    /// Texels covered by the surface (row-major, row 0 at the top).
    pub covered: Vec<bool>,
    pub padding: PadReport,
}

impl BakedTexture {
    pub fn covered_texels(&self) -> usize {
        self.covered.iter().filter(|&&c| c).count()
    }
}

/// Bakes `texture`, mapped by the old texture coordinates `old_corner_uvs` (one triple
/// per triangle), into the parameter domain of the flattening `new_uvs` (one UV per
/// vertex, any scale; flip-free, as [`crate::flatten`] returns).
pub fn bake_texture(
    triangles: &[[u32; 3]],
    new_uvs: &[[f64; 2]],
    old_corner_uvs: &[[[f64; 2]; 3]],
    texture: &Texture,
    options: &BakeOptions,
) -> Result<BakedTexture, AppError> {
    if old_corner_uvs.len() != triangles.len() {
        return Err(AppError::Length {
            what: "old texture coordinates",
            got: old_corner_uvs.len(),
            expected: triangles.len(),
            per: "triangles",
            per_one: "triangle",
        });
    }
    if texture.width == 0 || texture.height == 0 {
        return Err(AppError::Texture("the texture image is empty".into()));
    }
    bake_with(triangles, new_uvs, options, |t, b| {
        let c = old_corner_uvs[t as usize];
        let uv = [0, 1].map(|k| b[0] * c[0][k] + b[1] * c[1][k] + b[2] * c[2][k]);
        texture.sample_linear(uv).map(|x| x / 255.0)
    })
}

/// Bakes per-vertex colours (channels in `[0, 1]`), interpolated linearly over each
/// triangle, into the parameter domain of `new_uvs`.
pub fn bake_vertex_colors(
    triangles: &[[u32; 3]],
    new_uvs: &[[f64; 2]],
    colors: &[[f64; 3]],
    options: &BakeOptions,
) -> Result<BakedTexture, AppError> {
    if colors.len() != new_uvs.len() {
        return Err(AppError::per_vertex(
            "vertex colours",
            colors.len(),
            new_uvs.len(),
        ));
    }
    bake_with(triangles, new_uvs, options, |t, b| {
        let tri = triangles[t as usize];
        std::array::from_fn(|k| (0..3).map(|m| b[m] * colors[tri[m] as usize][k]).sum())
    })
}

/// Bakes a per-vertex scalar field through a colour map: the field is interpolated
/// linearly, then coloured with `colormap` over `range = (low, high)` (clamped).
pub fn bake_scalar_field(
    triangles: &[[u32; 3]],
    new_uvs: &[[f64; 2]],
    values: &[f64],
    colormap: Colormap,
    range: (f64, f64),
    options: &BakeOptions,
) -> Result<BakedTexture, AppError> {
    if values.len() != new_uvs.len() {
        return Err(AppError::per_vertex(
            "scalar field",
            values.len(),
            new_uvs.len(),
        ));
    }
    let (lo, hi) = range;
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Err(AppError::Option(format!(
            "colour range ({lo}, {hi}): needs finite low < high"
        )));
    }
    bake_with(triangles, new_uvs, options, |t, b| {
        let tri = triangles[t as usize];
        let x: f64 = (0..3).map(|m| b[m] * values[tri[m] as usize]).sum();
        colormap.at((x - lo) / (hi - lo)).map(f64::from)
    })
}

/// The shared pipeline: place the flattening, render `colour(triangle, barycentric)`
/// into it, pad.
fn bake_with(
    triangles: &[[u32; 3]],
    new_uvs: &[[f64; 2]],
    options: &BakeOptions,
    colour: impl Fn(u32, [f64; 3]) -> [f64; 3] + Sync,
) -> Result<BakedTexture, AppError> {
    crate::mesh::check_indices(triangles, new_uvs.len())?;
    if let Some(v) = new_uvs
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(AppError::Option(format!(
            "the new UV of vertex {v} is not finite: flatten the mesh again"
        )));
    }
    let size = options.size;
    if !(16..=16384).contains(&size) {
        return Err(AppError::Option(format!(
            "texture size {size}: use 16 to 16384 texels per side"
        )));
    }
    let margin = ((options.padding + 1) as f64 / size as f64).min(0.25);
    let uvs = place_in_unit_square(&rotate_to_fit(new_uvs), margin);
    let corners: Vec<[[f64; 2]; 3]> = triangles
        .iter()
        .map(|t| t.map(|v| uvs[v as usize]))
        .collect();
    let LayoutImage {
        mut rgb, coverage, ..
    } = render_layout(&corners, size, size, options.samples, |p| {
        Some(colour(p.triangle, p.barycentric))
    })?;
    let covered: Vec<bool> = coverage.iter().map(|&c| c > 0).collect();
    let mut filled = covered.clone();
    let padding = pad_colours(
        &mut rgb,
        &mut filled,
        size as usize,
        size as usize,
        options.padding as usize,
    );
    Ok(BakedTexture {
        image: to_rgb_image(size, size, &rgb),
        uvs,
        covered,
        padding,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::apps::correspondence::tests::graph_mesh;

    /// A smooth procedural texture: colour as a function of a point of the plane.
    fn pattern(x: f64, y: f64) -> [f64; 3] {
        [
            0.5 + 0.4 * (3.0 * x).sin(),
            0.5 + 0.4 * (2.0 * y + 0.5).cos(),
            0.5 + 0.3 * (2.0 * x + 3.0 * y).sin(),
        ]
    }

    #[test]
    fn baking_through_a_known_map_reproduces_the_texture() {
        // The surface is the square [−1, 1]² (irregular triangulation). Old texture
        // coordinates: two "photographs" — the left half maps into the left part of the
        // image, the right half (x ≥ 0) into the right part *mirrored*, with a gap
        // between them, so the old map is discontinuous along x = 0 (per-corner UVs).
        // The old image holds the pattern through that map. New UVs: a smooth,
        // non-affine warp of the square. Then the baked image at the new UV of any
        // point must be the pattern there.
        let n = 24;
        let mut mesh = graph_mesh(n, 0.5, 3, |_, _| 0.0);
        // Snap the vertices nearest x = 0 onto it, so no triangle straddles the seam.
        let h = 2.0 / n as f64;
        for p in &mut mesh.positions {
            if p[0].abs() < 0.26 * h {
                p[0] = 0.0;
            }
        }
        let side = 512u32;
        let old_uv = |x: f64, y: f64, right: bool| -> [f64; 2] {
            let v = 0.05 + 0.9 * (y + 1.0) / 2.0;
            if right {
                [0.95 - 0.4 * x, v]
            } else {
                [0.05 + 0.4 * (x + 1.0), v]
            }
        };
        // The old texture image: texel centres carry the pattern at the surface point
        // that maps there (left photo for u < 0.5, right photo beyond).
        let texture = crate::apps::inputs::texture_from(side, |u, v| {
            let y = (v - 0.05) / 0.9 * 2.0 - 1.0;
            let x = if u < 0.5 {
                (u - 0.05) / 0.4 - 1.0
            } else {
                (0.95 - u) / 0.4
            };
            pattern(x, y)
        });
        let corner_uvs = crate::apps::texture::corner_uvs(
            &crate::apps::inputs::seamed_uvs(&mesh, old_uv),
            &mesh.triangles,
        )
        .unwrap();
        let warp = |x: f64, y: f64| [x + 0.15 * (1.5 * y).sin(), y + 0.1 * x * x];
        let new_uvs: Vec<[f64; 2]> = mesh.positions.iter().map(|p| warp(p[0], p[1])).collect();
        let options = BakeOptions {
            size: 256,
            samples: 2,
            padding: 6,
        };
        let baked =
            bake_texture(&mesh.triangles, &new_uvs, &corner_uvs, &texture, &options).unwrap();
        let baked_tex = Texture {
            width: 256,
            height: 256,
            rgb: baked.image.pixels().map(|p| p.0).collect(),
        };
        // Sample at the centroids of many triangles (away from the chart boundary).
        // Error budget: the pattern's change over a baked texel and an old texel
        // (|∇| ≤ 1.4 per unit, texel ≈ 2/230 and 2/230 units) plus 8-bit rounding twice
        // and the piecewise-linear approximation of the warp: < 0.03.
        let mut worst = 0.0f64;
        for tri in mesh.triangles.iter().step_by(3) {
            let p = tri.map(|v| mesh.positions[v as usize]);
            let c = [0, 1].map(|k| (p[0][k] + p[1][k] + p[2][k]) / 3.0);
            if c[0].abs().max(c[1].abs()) > 0.9 {
                continue;
            }
            let uv = tri.map(|v| baked.uvs[v as usize]);
            let at = [0, 1].map(|k| (uv[0][k] + uv[1][k] + uv[2][k]) / 3.0);
            let got = baked_tex.sample_linear(at).map(|x| x / 255.0);
            let want = pattern(c[0], c[1]);
            for k in 0..3 {
                worst = worst.max((got[k] - want[k]).abs());
            }
        }
        assert!(worst < 0.03, "colour error {worst}");
    }

    #[test]
    fn padding_covers_the_texels_that_filtering_reads_at_the_boundary() {
        // Per-vertex colours on a disc: every bilinear lookup at a point of the chart
        // (at mip level 0) and every 2×2 and 4×4 mip texel touching the chart must read
        // only filled texels, with colours close to the surface's colours there.
        let mesh = crate::mesh::generate::bumpy_disc(10, 0.3);
        let uv: Vec<[f64; 2]> = mesh.positions.iter().map(|p| [p[0], p[1]]).collect();
        let colors: Vec<[f64; 3]> = mesh
            .positions
            .iter()
            .map(|p| [0.5 + 0.5 * p[0], 0.5 + 0.5 * p[1], 0.3])
            .collect();
        let options = BakeOptions {
            size: 128,
            samples: 2,
            padding: 4,
        };
        let baked = bake_vertex_colors(&mesh.triangles, &uv, &colors, &options).unwrap();
        let w = 128usize;
        assert!(baked.padding.dilated > 0 && baked.padding.background > 0);
        // Texels within Chebyshev distance 4 of a covered texel are filled (dilated),
        // with a colour within one texel's colour change (|∇c| ≤ 0.5·√2 per unit, a
        // texel ≈ 2.1/128 units) times the ring distance of the covered colours.
        let img = &baked.image;
        let colour_at = |x: usize, y: usize| {
            img.get_pixel(x as u32, y as u32)
                .0
                .map(|c| c as f64 / 255.0)
        };
        let covered = |x: usize, y: usize| baked.covered[y * w + x];
        let mut checked = 0;
        for y in 0..w {
            for x in 0..w {
                if covered(x, y) {
                    continue;
                }
                // Nearest covered texel within the padding.
                let mut best: Option<(usize, [f64; 3])> = None;
                for dy in -4i64..=4 {
                    for dx in -4i64..=4 {
                        let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                        if (0..w as i64).contains(&nx)
                            && (0..w as i64).contains(&ny)
                            && covered(nx as usize, ny as usize)
                        {
                            let d = dx.abs().max(dy.abs()) as usize;
                            if best.is_none_or(|b| d < b.0) {
                                best = Some((d, colour_at(nx as usize, ny as usize)));
                            }
                        }
                    }
                }
                if let Some((d, near)) = best {
                    let c = colour_at(x, y);
                    let tol = 0.02 * d as f64 + 2.0 / 255.0;
                    for k in 0..3 {
                        assert!(
                            (c[k] - near[k]).abs() <= tol,
                            "({x}, {y}) ring {d}: {c:?} vs {near:?}"
                        );
                    }
                    checked += 1;
                } else {
                    // Beyond the padding: the chart's mean colour, never black.
                    assert!(colour_at(x, y)[2] > 0.25, "background at ({x}, {y})");
                }
            }
        }
        assert!(checked > 4 * 128, "only {checked} padded texels");
        // Mip level 2 (4×4 blocks): a block that touches the chart has no black texel.
        for by in 0..w / 4 {
            for bx in 0..w / 4 {
                let texels = || (0..16).map(|k| (4 * bx + k % 4, 4 * by + k / 4));
                if texels().any(|(x, y)| covered(x, y)) {
                    assert!(
                        texels().all(|(x, y)| colour_at(x, y)[2] > 0.25),
                        "block ({bx}, {by})"
                    );
                }
            }
        }
    }

    #[test]
    fn scalar_fields_bake_through_the_colour_map() {
        let mesh = crate::mesh::generate::grid_disc(8);
        let uv: Vec<[f64; 2]> = mesh.positions.iter().map(|p| [p[0], p[1]]).collect();
        let values: Vec<f64> = mesh.positions.iter().map(|p| p[0]).collect();
        let options = BakeOptions {
            size: 64,
            samples: 1,
            padding: 2,
        };
        let baked = bake_scalar_field(
            &mesh.triangles,
            &uv,
            &values,
            Colormap::Viridis,
            (0.0, 1.0),
            &options,
        )
        .unwrap();
        // The chart fills [m, 1 − m]² with m = 3/64; texel x has value (x + ½)/64 mapped back.
        let m = 3.0 / 64.0;
        for x in [8usize, 20, 32, 44, 55] {
            let u = (x as f64 + 0.5) / 64.0;
            let value = (u - m) / (1.0 - 2.0 * m);
            let want = Colormap::Viridis.at_rgb8(value);
            let got = baked.image.get_pixel(x as u32, 32).0;
            for k in 0..3 {
                assert!(got[k].abs_diff(want[k]) <= 2, "x {x}: {got:?} vs {want:?}");
            }
        }
        assert!(
            bake_scalar_field(
                &mesh.triangles,
                &uv,
                &values,
                Colormap::Viridis,
                (1.0, 1.0),
                &options
            )
            .is_err()
        );
        assert!(bake_vertex_colors(&mesh.triangles, &uv, &[[0.0; 3]], &options).is_err());
    }
}
