//! Picture (a): the UV layout with its edges, triangles coloured by a measure
//! (thesis Fig. 3.1 right, Fig. 4.4 bottom), with a colour bar.

use image::RgbImage;

use super::canvas::{Canvas, rgb};
use super::colormap::{Clipping, ColorScale, color_bar, label_color_bar, note_height};
use super::font::{draw_text, text_height};
use crate::measure::jacobian::signed_uv_area;
use crate::measure::overlap::boundary_segments;

/// Where the layout goes on a canvas, in output pixels.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rect {
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
}

/// Maps UVs into `rect` preserving aspect ratio (v up), centred.
pub(crate) fn fit_uvs(
    corner_uvs: &[[[f64; 2]; 3]],
    rect: Rect,
) -> impl Fn([f64; 2]) -> [f64; 2] + use<> {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in corner_uvs
        .iter()
        .flatten()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
    {
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    if lo[0].is_nan() || hi[0].is_nan() || lo[0] > hi[0] {
        lo = [0.0; 2];
        hi = [1.0; 2];
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-300);
    let s =
        (rect.w / (hi[0] - lo[0]).max(span * 1e-9)).min(rect.h / (hi[1] - lo[1]).max(span * 1e-9));
    let ox = rect.x + 0.5 * (rect.w - s * (hi[0] - lo[0]));
    let oy = rect.y + 0.5 * (rect.h + s * (hi[1] - lo[1]));
    move |p: [f64; 2]| [ox + s * (p[0] - lo[0]), oy - s * (p[1] - lo[1])]
}

/// Draws the layout into `rect`: triangles filled with `fill(t)`, all edges thin,
/// boundary (and seam) edges thick.
pub(crate) fn draw_layout(
    canvas: &mut Canvas,
    rect: Rect,
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
    fill: impl Fn(usize) -> [f32; 3],
) {
    let map = fit_uvs(corner_uvs, rect);
    let screen: Vec<[[f64; 2]; 3]> = corner_uvs.iter().map(|t| t.map(&map)).collect();
    for (t, s) in screen.iter().enumerate() {
        let c = fill(t);
        canvas.fill_triangle(*s, None, |_| Some(c));
    }
    // Edge width from the mean on-screen triangle size: dense meshes get faint edges.
    let mean_area = screen
        .iter()
        .map(|s| signed_uv_area(*s).abs())
        .filter(|a| a.is_finite())
        .sum::<f64>()
        / screen.len().max(1) as f64;
    let edge_w = (mean_area.sqrt() / 10.0).clamp(0.08, 0.7);
    let edge_c = rgb(40, 40, 40);
    for s in &screen {
        for k in 0..3 {
            canvas.line(s[k], s[(k + 1) % 3], edge_w, edge_c);
        }
    }
    if triangles.len() == corner_uvs.len() {
        for seg in boundary_segments(triangles, corner_uvs) {
            canvas.line(map(seg[0]), map(seg[1]), 1.2, rgb(0, 0, 0));
        }
    }
}

/// Fill for a layout without values: light grey, and red where a triangle is flipped
/// (its signed UV area has the opposite sign of the layout's total signed area).
pub(crate) fn orientation_fill(corner_uvs: &[[[f64; 2]; 3]]) -> impl Fn(usize) -> [f32; 3] + '_ {
    let total: f64 = corner_uvs
        .iter()
        .map(|t| signed_uv_area(*t))
        .filter(|a| a.is_finite())
        .sum();
    let orientation = if total < 0.0 { -1.0 } else { 1.0 };
    move |t| {
        if orientation * signed_uv_area(corner_uvs[t]) < 0.0 {
            rgb(230, 40, 40)
        } else {
            rgb(225, 228, 235)
        }
    }
}

/// The UV layout of a map, `size = (width, height)` in pixels.
///
/// With `values = Some((per_triangle_values, label))` triangles are coloured by the
/// values (viridis, range from [`ColorScale::auto`]) and a labelled colour bar is
/// drawn, which says where the values reach beyond its range (`CLIPPED`, the maximum
/// and minimum, `+`/`-` on the clipped ends); without, triangles are light grey and flipped ones (negative signed UV area
/// while most of the area is positive) red. Triangles with bad indices or non-finite
/// UVs are skipped, never a panic.
pub fn uv_layout(
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
    values: Option<(&[f64], &str)>,
    title: &str,
    size: (u32, u32),
) -> RgbImage {
    let (w, h) = (size.0.clamp(64, 16384), size.1.clamp(64, 16384));
    let font = if w.min(h) >= 600 { 2 } else { 1 };
    let mut canvas = Canvas::new(w, h, 3, [1.0; 3]);
    let top = if title.is_empty() {
        8.0
    } else {
        text_height(font) as f64 + 16.0
    };
    let scale = values.and_then(|(v, _)| {
        if v.len() == corner_uvs.len() {
            ColorScale::auto(v)
        } else {
            None
        }
    });
    let bar_space = if scale.is_some() {
        30.0 + 70.0 * font as f64
    } else {
        0.0
    };
    let margin = 0.04 * w.min(h) as f64;
    let rect = Rect {
        x: margin,
        y: top + margin,
        w: w as f64 - 2.0 * margin - bar_space,
        h: h as f64 - top - 2.0 * margin,
    };
    match (scale, values) {
        (Some(sc), Some((v, _))) => {
            draw_layout(&mut canvas, rect, triangles, corner_uvs, |t| sc.color(v[t]))
        }
        _ => draw_layout(
            &mut canvas,
            rect,
            triangles,
            corner_uvs,
            orientation_fill(corner_uvs),
        ),
    }
    // The range drawn stops at the 1st and 99th percentile: the values beyond it are
    // said under the bar.
    let clipping = match (scale, values) {
        (Some(sc), Some((v, _))) => Clipping::of(&sc, v),
        _ => Clipping::default(),
    };
    let bar = Rect {
        x: w as f64 - bar_space + 10.0,
        y: rect.y + 10.0 * font as f64,
        w: 16.0,
        h: rect.h - 20.0 * font as f64 - note_height(&clipping, font),
    };
    if let Some(sc) = scale {
        color_bar(&mut canvas, sc.map, bar.x, bar.y, bar.w, bar.h);
    }
    let mut img = canvas.into_image();
    if let (Some(sc), Some((_, label))) = (scale, values) {
        label_color_bar(
            &mut img,
            &sc,
            [bar.x, bar.y, bar.w, bar.h],
            label,
            font,
            clipping,
        );
    }
    draw_text(&mut img, margin as i64, 8, title, font, [20, 20, 20]);
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::colormap::Colormap;
    use crate::render::tests::{assert_not_blank, disc_map};
    use image::GenericImageView;

    #[test]
    fn layout_is_the_requested_size_not_blank_and_deterministic() {
        let (_, tris, uv) = disc_map(12);
        let vals: Vec<f64> = (0..tris.len()).map(|t| 1.0 + (t % 7) as f64).collect();
        let a = uv_layout(&tris, &uv, Some((&vals, "ANGLE")), "DISC", (320, 240));
        assert_eq!(a.dimensions(), (320, 240));
        assert_not_blank(&a);
        let b = uv_layout(&tris, &uv, Some((&vals, "ANGLE")), "DISC", (320, 240));
        assert_eq!(a, b);
        let plain = uv_layout(&tris, &uv, None, "", (100, 100));
        assert_not_blank(&plain);
    }

    #[test]
    fn flipped_triangles_show_red() {
        let (_, tris, mut uv) = disc_map(8);
        let t = &mut uv[5];
        t.swap(1, 2);
        let img = uv_layout(&tris, &uv, None, "", (300, 300));
        assert!(
            img.pixels()
                .any(|p| p.0[0] > 200 && p.0[1] < 90 && p.0[2] < 90)
        );
    }

    /// Bounding box `[x0, y0, x1, y1)` of the pixels that are not white.
    fn drawn_box(img: &RgbImage) -> [u32; 4] {
        img.enumerate_pixels()
            .filter(|(_, _, p)| p.0 != [255; 3])
            .fold([u32::MAX, u32::MAX, 0, 0], |b, (x, y, _)| {
                [b[0].min(x), b[1].min(y), b[2].max(x + 1), b[3].max(y + 1)]
            })
    }

    #[test]
    fn a_right_triangle_lands_with_its_right_angle_bottom_left() {
        // Right angle at UV (0, 0); v points up, so the filled half of its bounding box
        // is the lower-left one. A mirrored layout (u or v flipped) fills another half.
        let tris = [[0, 1, 2]];
        let uv = [[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]];
        let img = uv_layout(&tris, &uv, None, "", (200, 200));
        let [x0, y0, x1, y1] = drawn_box(&img);
        let (w, h) = ((x1 - x0) as f64, (y1 - y0) as f64);
        // Aspect ratio kept (a unit right triangle spans a square), centred in the picture.
        assert!((w - h).abs() <= 2.0, "{w} × {h}");
        assert!(w > 150.0, "the layout fills the picture: {w}");
        assert!(((x0 + x1) as f64 / 2.0 - 100.0).abs() <= 3.0);
        let at = |fx: f64, fy: f64| {
            img.get_pixel((x0 as f64 + fx * w) as u32, (y0 as f64 + fy * h) as u32)
                .0
        };
        let grey = [225, 228, 235];
        assert_eq!(at(1.0 / 3.0, 2.0 / 3.0), grey, "centroid");
        assert_eq!(at(0.15, 0.85), grey, "near the right angle");
        assert_eq!(at(0.8, 0.2), [255; 3], "upper right is outside");
        assert_eq!(at(0.1, 0.2), grey, "left edge runs up");
        assert_eq!(at(0.8, 0.9), grey, "bottom edge runs right");
        assert_eq!(img.get_pixel(2, 2).0, [255; 3]);
        assert_eq!(img.get_pixel(197, 197).0, [255; 3]);
    }

    #[test]
    fn each_triangle_takes_the_colour_of_its_own_value() {
        // A unit square cut along its diagonal: the lower-right triangle has value 1
        // (the scale's low end, dark purple), the upper-left one 10 (yellow).
        let tris = [[0, 1, 2], [0, 2, 3]];
        let (a, b, c, d) = ([0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]);
        let uv = [[a, b, c], [a, c, d]];
        let vals = [1.0, 10.0];
        let img = uv_layout(&tris, &uv, Some((&vals, "V")), "", (300, 240));
        // The colour bar sits right of the layout; find the layout's box left of it.
        let left = img.view(0, 0, 200, 240).to_image();
        let [x0, y0, x1, y1] = drawn_box(&left);
        let (w, h) = ((x1 - x0) as f64, (y1 - y0) as f64);
        let at = |fx: f64, fy: f64| {
            img.get_pixel((x0 as f64 + fx * w) as u32, (y0 as f64 + fy * h) as u32)
                .0
        };
        let lo = Colormap::Viridis.at_rgb8(0.0);
        let hi = Colormap::Viridis.at_rgb8(1.0);
        assert_eq!(at(0.75, 0.75), lo, "lower right: value 1");
        assert_eq!(at(0.25, 0.25), hi, "upper left: value 10");
        // The bar: the high colour at its top, the low one at its bottom.
        // The bar: the column right of the layout with the most colour in it.
        let bar_x = (200..300)
            .max_by_key(|&x| {
                (0..240)
                    .filter(|&y| img.get_pixel(x, y).0 != [255; 3])
                    .count()
            })
            .unwrap();
        let column: Vec<[u8; 3]> = (0..240).map(|y| img.get_pixel(bar_x, y).0).collect();
        // The bar is the longest run of colour in that column (its title sits above).
        let mut runs: Vec<(usize, usize)> = Vec::new(); // (start, end)
        for (y, c) in column.iter().enumerate() {
            match runs.last_mut() {
                Some(r) if r.1 == y && *c != [255; 3] => r.1 = y + 1,
                _ if *c != [255; 3] => runs.push((y, y + 1)),
                _ => {}
            }
        }
        let (first, end) = runs.into_iter().max_by_key(|r| r.1 - r.0).unwrap();
        let last = end - 1;
        assert!(last - first > 100, "bar rows {first}..{end}");
        // One pixel in from the (anti-aliased) ends: within a band or two of t = 1, 0.
        let near = |p: [u8; 3], q: [u8; 3]| (0..3).all(|k| p[k].abs_diff(q[k]) <= 12);
        let (top, bottom) = (column[first + 1], column[last - 1]);
        assert!(near(top, hi), "bar top {top:?}");
        assert!(near(bottom, lo), "bar bottom {bottom:?}");
    }
}
