//! Pictures of values on a regular grid, one pixel per node, row 0 at the *bottom*
//! (y up, as for grids over ω = \[0,1\]² and for UV layouts): [`grid_image`] takes a
//! colour per node, [`image_with_colormap`] maps values through a [`ColorScale`]. Draw
//! one under a deformed grid with [`Canvas::draw_image`](super::Canvas::draw_image) and
//! [`Canvas::polyline`](super::Canvas::polyline): a grid of `N` nodes per side over
//! ω = \[0,1\]² puts node `j` at `ξ = j/(N − 1)`, the centre of its pixel, when the image
//! covers ω grown by half a cell, `[−δ, 1 + δ]²` with `δ = 1/(2(N − 1))`.

use image::{Rgb, RgbImage};

use super::canvas::to_rgb8;
use super::colormap::ColorScale;

/// Colour of nodes without a value (non-finite, e.g. outside the surface).
pub const NO_DATA: [u8; 3] = [96, 96, 96];

/// A `width × height` picture of a grid stored row by row (`node = row · width +
/// column`), `colour(node)` per pixel, grid row 0 at the bottom of the picture.
pub fn grid_image(width: usize, height: usize, colour: impl Fn(usize) -> [u8; 3]) -> RgbImage {
    RgbImage::from_fn(width as u32, height as u32, |x, y| {
        let row = height - 1 - y as usize;
        Rgb(colour(row * width + x as usize))
    })
}

/// `values` (row by row, `width` per row; a trailing partial row is dropped) through
/// `scale`, grid row 0 at the bottom; non-finite values are [`NO_DATA`] grey.
pub fn image_with_colormap(values: &[f64], width: usize, scale: &ColorScale) -> RgbImage {
    let height = values.len().checked_div(width).unwrap_or(0);
    grid_image(width, height, |k| {
        let v = values[k];
        if v.is_finite() {
            to_rgb8(scale.color(v))
        } else {
            NO_DATA
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::colormap::Colormap;

    #[test]
    fn row_zero_is_at_the_bottom_and_columns_run_left_to_right() {
        // A 3 × 2 grid: node k has red = k.
        let img = grid_image(3, 2, |k| [k as u8, 0, 0]);
        assert_eq!(img.dimensions(), (3, 2));
        assert_eq!(img.get_pixel(0, 1).0, [0, 0, 0]); // bottom-left = node 0
        assert_eq!(img.get_pixel(2, 1).0, [2, 0, 0]); // bottom-right = node 2
        assert_eq!(img.get_pixel(0, 0).0, [3, 0, 0]); // top-left = node 3 (row 1)
        assert_eq!(img.get_pixel(2, 0).0, [5, 0, 0]);
    }

    #[test]
    fn values_take_the_scale_colours_and_gaps_are_grey() {
        let scale = ColorScale {
            lo: 0.0,
            hi: 4.0,
            log: false,
            map: Colormap::Viridis,
        };
        // Bottom row 0, 2, 4; top row NaN, −1 (clamped to lo), ∞.
        let v = [0.0, 2.0, 4.0, f64::NAN, -1.0, f64::INFINITY, 9.0];
        let img = image_with_colormap(&v, 3, &scale);
        assert_eq!(img.dimensions(), (3, 2), "the partial row is dropped");
        assert_eq!(img.get_pixel(0, 1).0, [0x44, 0x01, 0x54]);
        assert_eq!(img.get_pixel(1, 1).0, [0x21, 0x91, 0x8c]);
        assert_eq!(img.get_pixel(2, 1).0, [0xfd, 0xe7, 0x25]);
        assert_eq!(img.get_pixel(0, 0).0, NO_DATA);
        assert_eq!(img.get_pixel(1, 0).0, [0x44, 0x01, 0x54]);
        assert_eq!(img.get_pixel(2, 0).0, NO_DATA);
        assert_eq!(image_with_colormap(&v, 0, &scale).dimensions(), (0, 0));
    }
}
