//! Colour-mapped pictures of geometry images (like thesis Fig. 3.6, 3.8): which colour
//! map and range each kind of image gets. Drawing, colour maps and PNG writing are
//! [`crate::render`]'s; grid row `i = 0` (`ξ_y = 0`) is at the bottom of the picture.

use image::RgbImage;

use crate::render::colormap::{ColorScale, Colormap, abs_quantile};
use crate::render::grid_image::{NO_DATA, grid_image, image_with_colormap};

/// Colour of nodes outside the surface.
pub const OUTSIDE_GREY: [u8; 3] = NO_DATA;

/// Scalar image with the blue–white–red map symmetric about 0 (range: 98th percentile
/// of |v|); non-finite nodes grey. Only the `⌊len / size⌋` full rows are drawn.
pub fn diverging_picture(size: usize, values: &[f64]) -> RgbImage {
    image_with_colormap(values, size, &ColorScale::symmetric(values, 0.98))
}

/// Distance image: viridis over `[0, max]` with dark iso-lines every `max/10`;
/// `NaN`/`∞` (and nodes past the end of `values`) grey; `dim` darkens nodes where `dim[k]` is true (e.g. outside the surface).
pub fn distance_picture(size: usize, values: &[f64], dim: Option<&[bool]>) -> RgbImage {
    let max = values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |a, b| a.max(b.abs()));
    let max = if max > 0.0 { max } else { 1.0 };
    let step = max / 10.0;
    let line = 0.6 * max / size as f64;
    grid_image(size, size, |k| {
        let Some(&v) = values.get(k).filter(|v| v.is_finite()) else {
            return OUTSIDE_GREY;
        };
        let mut c = Colormap::Viridis.at_rgb8(v.abs() / max);
        let r = v.abs() % step;
        if r < line || step - r < line {
            c = c.map(|x| x / 3);
        }
        if dim.is_some_and(|d| d.get(k) == Some(&true)) {
            c = c.map(|x| x / 2 + 32);
        }
        c
    })
}

/// Metric `[g11, g12, g22]` as RGB (thesis Fig. 3.6b): `g11`, `g22` scaled by their
/// 98th percentile, `g12` mapped from `[−r, r]`; nodes outside (`NaN`, or past the end
/// of `g`) grey.
pub fn metric_picture(size: usize, g: &[[f64; 3]]) -> RgbImage {
    let r11 = abs_quantile(g.iter().map(|g| g[0]), 0.98);
    let r12 = abs_quantile(g.iter().map(|g| g[1]), 0.98);
    let r22 = abs_quantile(g.iter().map(|g| g[2]), 0.98);
    grid_image(size, size, |k| {
        let Some(&[a, b, c]) = g.get(k).filter(|g| !g[0].is_nan()) else {
            return OUTSIDE_GREY;
        };
        let to = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
        [to(a / r11), to(0.5 + 0.5 * b / r12), to(c / r22)]
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curvature_sign_shows_as_red_and_blue_with_grid_row_zero_at_the_bottom() {
        // 3 × 3 grid: bottom row positive, middle row zero, top row negative, one gap.
        let h = [1.0, 1.0, 1.0, 0.0, 0.0, f64::NAN, -1.0, -1.0, -1.0];
        let p = diverging_picture(3, &h);
        assert_eq!(p.get_pixel(0, 2).0, Colormap::BlueWhiteRed.at_rgb8(1.0));
        assert_eq!(p.get_pixel(1, 1).0, [247, 247, 247]);
        assert_eq!(p.get_pixel(2, 1).0, OUTSIDE_GREY);
        assert_eq!(p.get_pixel(2, 0).0, Colormap::BlueWhiteRed.at_rgb8(0.0));
    }

    #[test]
    fn distance_picture_has_iso_lines_and_dims_the_outside() {
        // Each row holds the distances 0, 0.05, …, 1: iso-lines at the multiples of 0.1
        // (half-width 0.6/21 ≈ 0.029), so even columns lie on lines, odd ones between.
        let n = 21;
        let v: Vec<f64> = (0..n * n)
            .map(|k| (k % n) as f64 / (n - 1) as f64)
            .collect();
        let p = distance_picture(n, &v, None);
        // Node 0 (distance 0) is on an iso-line: a third of the map's start colour.
        let start = Colormap::Viridis.at_rgb8(0.0).map(|x| x / 3);
        assert_eq!(p.get_pixel(0, (n - 1) as u32).0, start);
        // Node 5 (0.25) is midway between lines: the plain map colour.
        assert_eq!(p.get_pixel(5, 0).0, Colormap::Viridis.at_rgb8(0.25));
        // Dimmed nodes: halved and lifted.
        let dim = vec![true; n * n];
        let q = distance_picture(n, &v, Some(&dim));
        let plain = Colormap::Viridis.at_rgb8(0.25);
        assert_eq!(q.get_pixel(5, 0).0, plain.map(|x| x / 2 + 32));
    }

    #[test]
    fn metric_components_go_to_their_channels() {
        // g = identity on every node, except one node with g12 = −g11 and one outside.
        let mut g = vec![[1.0, 0.0, 1.0]; 4];
        g[1] = [1.0, -1.0, 0.5];
        g[3] = [f64::NAN; 3];
        let p = metric_picture(2, &g);
        assert_eq!(p.get_pixel(0, 1).0, [255, 128, 255]); // node 0, bottom-left
        assert_eq!(p.get_pixel(1, 1).0, [255, 0, 128]); // node 1, bottom-right
        assert_eq!(p.get_pixel(1, 0).0, OUTSIDE_GREY); // node 3, top-right
        // Too few values for the grid: the missing nodes are grey, no panic.
        assert_eq!(metric_picture(3, &g).get_pixel(2, 0).0, OUTSIDE_GREY);
        assert_eq!(
            distance_picture(3, &[0.5; 4], None).get_pixel(2, 0).0,
            OUTSIDE_GREY
        );
        assert_eq!(diverging_picture(3, &[0.5; 4]).dimensions(), (3, 1));
    }
}
