//! A stills sheet of a morph or of rig keys (thesis figs. 5.3, 5.5): the surface at
//! several times, each frame on A's connectivity, all seen from one fixed view and
//! coloured the same way (A's texture carried through the morph, or a checkerboard
//! through A's texture coordinates), side by side; and the before/after sheet of a
//! texture bake (thesis fig. 5.2).

use image::RgbImage;

use super::texture::Texture;
use crate::render::{View, contact_sheet, rgb, surface_render};

/// The stills' camera tilt (40°): oblique from above ([`View::framing_tilted`]), so that
/// shapes show in the outline.
pub const STILLS_TILT: f64 = 40.0 * std::f64::consts::PI / 180.0;

/// How a frame is coloured at a point with texture coordinate `uv`.
pub enum StillColour<'a> {
    /// A texture image, sampled bilinearly.
    Texture(&'a Texture),
    /// A checkerboard with `n` squares across `[0, 1]`.
    Checker(u32),
}

/// Renders every frame (one position per vertex of `triangles`, all the same
/// connectivity) through one view framing all of them (tilted by [`STILLS_TILT`]),
/// coloured through `corner_uvs`, and tiles them with their labels, `columns` per row,
/// `tile` pixels square.
pub fn stills_sheet(
    frames: &[(String, Vec<[f64; 3]>)],
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
    colour: &StillColour,
    columns: usize,
    tile: u32,
) -> RgbImage {
    let positions: Vec<&[[f64; 3]]> = frames.iter().map(|(_, p)| p.as_slice()).collect();
    let Some(view) = View::framing_tilted(&positions, triangles, STILLS_TILT) else {
        return contact_sheet(&[], columns, tile);
    };
    let (light, dark) = (rgb(245, 240, 230), rgb(215, 95, 35));
    let shade = |uv: [f64; 2]| -> [f32; 3] {
        match colour {
            StillColour::Texture(t) => t.sample_linear(uv).map(|c| (c / 255.0) as f32),
            StillColour::Checker(n) => {
                let cell = (uv[0] * *n as f64).floor() as i64 + (uv[1] * *n as f64).floor() as i64;
                if cell.rem_euclid(2) == 0 { light } else { dark }
            }
        }
    };
    let tiles: Vec<(String, RgbImage)> = frames
        .iter()
        .map(|(label, p)| {
            let img = surface_render(p, triangles, corner_uvs, &view, &shade, "", (tile, tile));
            (label.clone(), img)
        })
        .collect();
    contact_sheet(&tiles, columns, tile)
}

/// A texture image drawn into a `tile × tile` square, aspect kept, on white (each tile
/// pixel averages a 3 × 3 grid of bilinear lookups).
pub fn texture_tile(texture: &Texture, tile: u32) -> RgbImage {
    let (w, h) = (texture.width as f64, texture.height as f64);
    let scale = tile as f64 / w.max(h);
    let (dw, dh) = (w * scale, h * scale);
    let (x0, y0) = (0.5 * (tile as f64 - dw), 0.5 * (tile as f64 - dh));
    RgbImage::from_fn(tile, tile, |x, y| {
        let mut sum = [0.0; 3];
        for (sx, sy) in (0..9).map(|k| (k % 3, k / 3)) {
            let u = (x as f64 + (sx as f64 + 0.5) / 3.0 - x0) / dw;
            let v = 1.0 - (y as f64 + (sy as f64 + 0.5) / 3.0 - y0) / dh;
            let c = if (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v) {
                texture.sample_linear([u, v])
            } else {
                [255.0; 3]
            };
            for k in 0..3 {
                sum[k] += c[k] / 9.0;
            }
        }
        image::Rgb(sum.map(|c| c.round().clamp(0.0, 255.0) as u8))
    })
}

/// The before/after sheet of a bake (thesis fig. 5.2): the old texture, the baked
/// texture, and the surface seen from one view with each (`old` = the old texture and
/// its corner UVs, absent when colours or a scalar field were baked), `tile` pixels per
/// picture, in one row.
pub fn bake_sheet(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    old: Option<(&Texture, &[[[f64; 2]; 3]])>,
    baked: &Texture,
    baked_uvs: &[[f64; 2]],
    tile: u32,
) -> RgbImage {
    let new_corners: Vec<[[f64; 2]; 3]> = triangles
        .iter()
        .map(|t| t.map(|v| baked_uvs[v as usize]))
        .collect();
    let mut tiles = vec![];
    if let Some((texture, _)) = old {
        tiles.push(("old texture".to_owned(), texture_tile(texture, tile)));
    }
    tiles.push(("baked texture".to_owned(), texture_tile(baked, tile)));
    if let Some(view) = View::framing(&[positions], triangles) {
        let mut render = |label: &str, texture: &Texture, corners: &[[[f64; 2]; 3]]| {
            let shade = |uv: [f64; 2]| texture.sample_linear(uv).map(|c| (c / 255.0) as f32);
            let img = surface_render(
                positions,
                triangles,
                corners,
                &view,
                &shade,
                "",
                (tile, tile),
            );
            tiles.push((label.to_owned(), img));
        };
        if let Some((texture, corners)) = old {
            render("surface, old texture", texture, corners);
        }
        render("surface, baked texture", baked, &new_corners);
    }
    contact_sheet(&tiles, tiles.len(), tile)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_share_one_view() {
        // The unit square and a copy moved right by its width: with one view framing
        // both, the first still shows the square in the left half of its tile, the
        // second in the right half.
        let square = crate::mesh::generate::unit_square();
        let moved: Vec<[f64; 3]> = square
            .positions
            .iter()
            .map(|p| [p[0] + 1.0, p[1], p[2]])
            .collect();
        let uv: Vec<[[f64; 2]; 3]> = square
            .triangles
            .iter()
            .map(|t| {
                t.map(|v| {
                    [
                        square.positions[v as usize][0],
                        square.positions[v as usize][1],
                    ]
                })
            })
            .collect();
        let frames = vec![
            ("t 0".to_owned(), square.positions.clone()),
            ("t 1".to_owned(), moved),
        ];
        let sheet = stills_sheet(
            &frames,
            &square.triangles,
            &uv,
            &StillColour::Checker(2),
            2,
            200,
        );
        // Tiles: pad 8, label 30; tile k spans x in [8 + 208k, 208 + 208k).
        let painted_x = |k: u32| -> (u32, u32) {
            let (mut lo, mut hi) = (u32::MAX, 0);
            for y in 38..238 {
                for x in 8 + 208 * k..208 + 208 * k {
                    if sheet.get_pixel(x, y).0 != [255; 3] {
                        lo = lo.min(x - 208 * k - 8);
                        hi = hi.max(x - 208 * k - 8);
                    }
                }
            }
            (lo, hi)
        };
        let (a, b) = (painted_x(0), painted_x(1));
        assert!(a.1 < 110 && b.0 > 90, "first {a:?}, second {b:?}");
    }

    #[test]
    fn texture_tiles_keep_the_aspect_on_white() {
        // A 4 × 2 texture, left half red, right half blue, in a 40 × 40 tile: rows
        // 10..30 painted (red left of x = 20, blue right), white above and below.
        let texture = Texture {
            width: 4,
            height: 2,
            rgb: (0..8)
                .map(|i| if i % 4 < 2 { [255, 0, 0] } else { [0, 0, 255] })
                .collect(),
        };
        let tile = texture_tile(&texture, 40);
        assert_eq!(tile.get_pixel(20, 5).0, [255; 3]);
        assert_eq!(tile.get_pixel(20, 35).0, [255; 3]);
        assert_eq!(tile.get_pixel(5, 20).0, [255, 0, 0]);
        assert_eq!(tile.get_pixel(35, 20).0, [0, 0, 255]);
    }
}
