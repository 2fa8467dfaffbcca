//! A supersampled RGB canvas: triangles (flat or per-pixel shaded, optionally
//! depth-tested) and thick lines are drawn at `ss×` resolution and box-filtered down,
//! which anti-aliases every edge.

use image::{Rgb, RgbImage};

/// Supersampled drawing surface. Coordinates passed to the drawing calls are in
/// *output* pixels (floating point); the canvas scales them internally.
pub struct Canvas {
    width: usize,
    height: usize,
    ss: usize,
    color: Vec<[f32; 3]>,
    depth: Vec<f32>,
}

impl Canvas {
    /// A canvas for a `width × height` output image, `ss` samples per pixel along
    /// each axis, filled with `background` (RGB in `[0, 1]`).
    pub fn new(width: u32, height: u32, ss: u32, background: [f32; 3]) -> Self {
        let ss = ss.clamp(1, 8) as usize;
        let (w, h) = (width.max(1) as usize * ss, height.max(1) as usize * ss);
        Self {
            width: w,
            height: h,
            ss,
            color: vec![background; w * h],
            depth: Vec::new(),
        }
    }

    /// Turns on depth testing (larger depth = closer), reset to −∞.
    pub fn enable_depth(&mut self) {
        self.depth = vec![f32::NEG_INFINITY; self.width * self.height];
    }

    /// Fills the triangle `p` (output-pixel coordinates). For every covered sample,
    /// `shade(b)` gets the barycentric coordinates and returns a colour, or `None` to
    /// leave the sample. With depth testing on, `depth` (per corner) is interpolated
    /// and only closer samples are written. Triangles with non-finite corners are
    /// skipped.
    pub fn fill_triangle(
        &mut self,
        p: [[f64; 2]; 3],
        depth: Option<[f64; 3]>,
        mut shade: impl FnMut([f64; 3]) -> Option<[f32; 3]>,
    ) {
        let s = self.ss as f64;
        let q = p.map(|v| [v[0] * s, v[1] * s]);
        if q.iter().flatten().any(|x| !x.is_finite()) {
            return;
        }
        let area =
            (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[2][0] - q[0][0]) * (q[1][1] - q[0][1]);
        if area == 0.0 || !area.is_finite() {
            return;
        }
        // Bounding box of the samples the triangle may cover, clipped to the canvas.
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for v in &q {
            for k in 0..2 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        let (xmin, ymin) = (lo[0].floor().max(0.0), lo[1].floor().max(0.0));
        let xmax = hi[0].ceil().min(self.width as f64);
        let ymax = hi[1].ceil().min(self.height as f64);
        if xmin >= xmax || ymin >= ymax {
            return;
        }
        let inv = 1.0 / area;
        let use_depth = depth.is_some() && !self.depth.is_empty();
        for py in ymin as usize..ymax as usize {
            let y = py as f64 + 0.5;
            for px in xmin as usize..xmax as usize {
                let x = px as f64 + 0.5;
                let w0 = ((q[1][0] - x) * (q[2][1] - y) - (q[2][0] - x) * (q[1][1] - y)) * inv;
                let w1 = ((q[2][0] - x) * (q[0][1] - y) - (q[0][0] - x) * (q[2][1] - y)) * inv;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let i = py * self.width + px;
                if use_depth {
                    let d = depth.unwrap();
                    let z = (w0 * d[0] + w1 * d[1] + w2 * d[2]) as f32;
                    if z <= self.depth[i] {
                        continue;
                    }
                    if let Some(c) = shade([w0, w1, w2]) {
                        self.depth[i] = z;
                        self.color[i] = c;
                    }
                } else if let Some(c) = shade([w0, w1, w2]) {
                    self.color[i] = c;
                }
            }
        }
    }

    /// Fills an axis-aligned rectangle `[x0, x1) × [y0, y1)` (output pixels).
    pub fn fill_rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, color: [f32; 3]) {
        self.fill_triangle([[x0, y0], [x1, y0], [x1, y1]], None, |_| Some(color));
        self.fill_triangle([[x0, y0], [x1, y1], [x0, y1]], None, |_| Some(color));
    }

    /// A square marker of half-width `r` centred on `p`.
    pub fn marker(&mut self, p: [f64; 2], r: f64, color: [f32; 3]) {
        self.fill_rect(p[0] - r, p[1] - r, p[0] + r, p[1] + r, color);
    }

    /// Outline of the axis-aligned rectangle `[x0, x1] × [y0, y1]`.
    pub fn stroke_rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, width: f64, color: [f32; 3]) {
        for (a, b) in [
            ([x0, y0], [x1, y0]),
            ([x1, y0], [x1, y1]),
            ([x1, y1], [x0, y1]),
            ([x0, y1], [x0, y0]),
        ] {
            self.line(a, b, width, color);
        }
    }

    /// Draws the segment `a`–`b`, `width` output pixels wide, on top (no depth test).
    /// The ends extend by half the width, so consecutive segments join without gaps.
    pub fn line(&mut self, a: [f64; 2], b: [f64; 2], width: f64, color: [f32; 3]) {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = (dx * dx + dy * dy).sqrt();
        if len.is_nan() || len <= 0.0 || !len.is_finite() {
            return;
        }
        let h = 0.5 * width / len;
        let (nx, ny) = (-dy * h, dx * h);
        let (ex, ey) = (dx * h, dy * h);
        let p0 = [a[0] - ex + nx, a[1] - ey + ny];
        let p1 = [b[0] + ex + nx, b[1] + ey + ny];
        let p2 = [b[0] + ex - nx, b[1] + ey - ny];
        let p3 = [a[0] - ex - nx, a[1] - ey - ny];
        self.fill_triangle([p0, p1, p2], None, |_| Some(color));
        self.fill_triangle([p0, p2, p3], None, |_| Some(color));
    }

    /// Draws the polyline through `points` (output pixels): a segment joins each pair of
    /// consecutive points whose coordinates are all finite, so a non-finite point (e.g.
    /// `[f64::NAN; 2]`) breaks the line. For a deformed grid, call it once per grid
    /// line.
    pub fn polyline(&mut self, points: &[[f64; 2]], width: f64, color: [f32; 3]) {
        let finite = |p: &[f64; 2]| p[0].is_finite() && p[1].is_finite();
        for pair in points.windows(2) {
            if finite(&pair[0]) && finite(&pair[1]) {
                self.line(pair[0], pair[1], width, color);
            }
        }
    }

    /// Draws `img` stretched over the rectangle `[x, x + w) × [y, y + h)` (output
    /// pixels), nearest-neighbour: each sample takes the colour of the image pixel it
    /// falls in. Parts outside the canvas are clipped; an empty image or rectangle draws
    /// nothing.
    pub fn draw_image(&mut self, x: f64, y: f64, w: f64, h: f64, img: &RgbImage) {
        let (iw, ih) = (img.width() as usize, img.height() as usize);
        let s = self.ss as f64;
        let (x0, y0, x1, y1) = (x * s, y * s, (x + w) * s, (y + h) * s);
        if iw == 0 || ih == 0 || !(x1 > x0 && y1 > y0 && x0.is_finite() && y0.is_finite()) {
            return;
        }
        let clip = |v: f64, n: usize| v.max(0.0).min(n as f64) as usize;
        let (sx0, sx1) = (clip(x0.round(), self.width), clip(x1.round(), self.width));
        let (sy0, sy1) = (clip(y0.round(), self.height), clip(y1.round(), self.height));
        let (fx, fy) = (iw as f64 / (x1 - x0), ih as f64 / (y1 - y0));
        for sy in sy0..sy1 {
            let r = (((sy as f64 + 0.5 - y0) * fy) as usize).min(ih - 1);
            for sx in sx0..sx1 {
                let c = (((sx as f64 + 0.5 - x0) * fx) as usize).min(iw - 1);
                let p = img.get_pixel(c as u32, r as u32).0;
                self.color[sy * self.width + sx] = rgb(p[0], p[1], p[2]);
            }
        }
    }

    /// Box-filters the samples down to the output image.
    pub fn into_image(self) -> RgbImage {
        let (ow, oh) = (self.width / self.ss, self.height / self.ss);
        let n = (self.ss * self.ss) as f32;
        let mut img = RgbImage::new(ow as u32, oh as u32);
        for oy in 0..oh {
            for ox in 0..ow {
                let mut acc = [0.0f32; 3];
                for sy in 0..self.ss {
                    let row = (oy * self.ss + sy) * self.width + ox * self.ss;
                    for c in &self.color[row..row + self.ss] {
                        acc[0] += c[0];
                        acc[1] += c[1];
                        acc[2] += c[2];
                    }
                }
                img.put_pixel(ox as u32, oy as u32, Rgb(to_rgb8(acc.map(|v| v / n))));
            }
        }
        img
    }
}

/// An RGB colour in `[0, 1]` from 8-bit components.
pub fn rgb(r: u8, g: u8, b: u8) -> [f32; 3] {
    [r as f32 / 255.0, g as f32 / 255.0, b as f32 / 255.0]
}

/// 8-bit components of an RGB colour in `[0, 1]` (clamped, rounded to nearest).
pub fn to_rgb8(c: [f32; 3]) -> [u8; 3] {
    c.map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_square_covers_half_the_pixels_and_edges_are_antialiased() {
        let mut c = Canvas::new(40, 40, 4, [0.0; 3]);
        c.fill_triangle([[0.0, 0.0], [40.0, 0.0], [0.0, 40.0]], None, |_| {
            Some([1.0; 3])
        });
        let img = c.into_image();
        let total: f64 = img.pixels().map(|p| p.0[0] as f64 / 255.0).sum();
        assert!((total - 800.0).abs() < 8.0, "coverage {total}");
        let partial = img.pixels().filter(|p| p.0[0] > 10 && p.0[0] < 245).count();
        assert!(
            partial >= 30,
            "diagonal should be anti-aliased, {partial} partial pixels"
        );
    }

    #[test]
    fn depth_test_keeps_the_closer_triangle() {
        let mut c = Canvas::new(10, 10, 1, [0.0; 3]);
        c.enable_depth();
        let t = [[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]];
        c.fill_triangle(t, Some([1.0; 3]), |_| Some([1.0, 0.0, 0.0]));
        c.fill_triangle(t, Some([0.0; 3]), |_| Some([0.0, 1.0, 0.0]));
        assert_eq!(c.into_image().get_pixel(1, 1).0, [255, 0, 0]);
    }

    #[test]
    fn garbage_coordinates_are_ignored() {
        let mut c = Canvas::new(8, 8, 2, [0.0; 3]);
        c.fill_triangle([[f64::NAN, 0.0], [1.0, 0.0], [0.0, 1.0]], None, |_| {
            Some([1.0; 3])
        });
        c.fill_triangle([[-1e300, 0.0], [1e300, 0.0], [0.0, 1e300]], None, |_| {
            Some([1.0; 3])
        });
        c.line([0.0, 0.0], [0.0, 0.0], 1.0, [1.0; 3]);
        let _ = c.into_image();
    }

    #[test]
    fn polyline_inks_its_segments_and_breaks_at_non_finite_points() {
        let mut c = Canvas::new(40, 40, 3, [0.0; 3]);
        // An L from (5, 10) right to (35, 10), then down to (35, 30); a NaN point, then
        // a lone point (nothing to join) and a segment on row 35.
        let nan = [f64::NAN; 2];
        let pts = [
            [5.0, 10.0],
            [35.0, 10.0],
            [35.0, 30.0],
            nan,
            [5.0, 30.0],
            nan,
            [5.0, 35.0],
            [20.0, 35.0],
        ];
        c.polyline(&pts, 2.0, [1.0; 3]);
        let img = c.into_image();
        let ink = |x: u32, y: u32| img.get_pixel(x, y).0[0];
        // On the segments (pixel centres within 1 px of the centre line): full ink.
        assert_eq!(ink(20, 9), 255);
        assert_eq!(ink(20, 10), 255);
        assert_eq!(ink(34, 20), 255);
        assert_eq!(ink(12, 35), 255);
        // The segment 35,30 → 5,30 across the NaN is not drawn, nor is 5,30 → 5,35.
        assert_eq!(ink(20, 30), 0);
        assert_eq!(ink(4, 32), 0);
        // Away from every segment: background.
        assert_eq!(ink(20, 20), 0);
        assert_eq!(ink(20, 13), 0);
        let inked = img.pixels().filter(|p| p.0[0] > 0).count();
        // Two 2 px wide strokes of 30 + 20 px and one of 15 px, plus joins and fringes.
        assert!((120..=190).contains(&inked), "{inked} inked pixels");
    }

    #[test]
    fn drawn_image_keeps_its_orientation_and_scales_by_nearest_neighbour() {
        // 2 × 2 image: red top-left, green top-right, blue bottom-left, white bottom-right.
        let mut src = RgbImage::new(2, 2);
        src.put_pixel(0, 0, Rgb([255, 0, 0]));
        src.put_pixel(1, 0, Rgb([0, 255, 0]));
        src.put_pixel(0, 1, Rgb([0, 0, 255]));
        src.put_pixel(1, 1, Rgb([255, 255, 255]));
        let mut c = Canvas::new(30, 30, 2, [0.0; 3]);
        c.draw_image(5.0, 10.0, 20.0, 10.0, &src);
        let img = c.into_image();
        let px = |x: u32, y: u32| img.get_pixel(x, y).0;
        assert_eq!(px(5, 10), [255, 0, 0]);
        assert_eq!(px(14, 14), [255, 0, 0]);
        assert_eq!(px(15, 10), [0, 255, 0]);
        assert_eq!(px(24, 14), [0, 255, 0]);
        assert_eq!(px(5, 15), [0, 0, 255]);
        assert_eq!(px(24, 19), [255, 255, 255]);
        // Outside the rectangle: background.
        for (x, y) in [(4, 12), (25, 12), (10, 9), (10, 20)] {
            assert_eq!(px(x, y), [0, 0, 0], "({x}, {y})");
        }
        // Clipped and degenerate placements do not panic.
        let mut c = Canvas::new(10, 10, 2, [0.0; 3]);
        c.draw_image(-50.0, -50.0, 1e6, 1e6, &src);
        c.draw_image(0.0, 0.0, f64::NAN, 3.0, &src);
        c.draw_image(0.0, 0.0, 3.0, 3.0, &RgbImage::new(0, 0));
        // The canvas lies inside the stretched image's top-left (red) pixel.
        assert_eq!(c.into_image().get_pixel(9, 9).0, [255, 0, 0]);
    }

    #[test]
    fn rgb8_round_trips() {
        for v in [0u8, 1, 127, 128, 254, 255] {
            assert_eq!(to_rgb8(rgb(v, v, v)), [v; 3]);
        }
        assert_eq!(to_rgb8([-1.0, 2.0, 0.5]), [0, 255, 128]);
    }
}
