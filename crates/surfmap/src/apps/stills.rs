//! A stills sheet of a morph or of rig keys (thesis figs. 5.3, 5.5): the surface at
//! several times, each frame on A's connectivity, all seen from one fixed view and
//! coloured the same way (A's texture carried through the morph, or a checkerboard
//! through A's texture coordinates), side by side.

use image::RgbImage;

use super::texture::Texture;
use crate::render::{View, contact_sheet, rgb, surface_render};

/// How a frame is coloured at a point with texture coordinate `uv`.
pub enum StillColour<'a> {
    /// A texture image, sampled bilinearly.
    Texture(&'a Texture),
    /// A checkerboard with `n` squares across `[0, 1]`.
    Checker(u32),
}

/// Renders every frame (one position per vertex of `triangles`, all the same
/// connectivity) through one view framing all of them, coloured through `corner_uvs`,
/// and tiles them with their labels, `columns` per row, `tile` pixels square.
pub fn stills_sheet(
    frames: &[(String, Vec<[f64; 3]>)],
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
    colour: &StillColour,
    columns: usize,
    tile: u32,
) -> RgbImage {
    let positions: Vec<&[[f64; 3]]> = frames.iter().map(|(_, p)| p.as_slice()).collect();
    let Some(view) = View::framing(&positions, triangles) else {
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
}
