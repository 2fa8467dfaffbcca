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
        let xmin = q
            .iter()
            .map(|v| v[0])
            .fold(f64::INFINITY, f64::min)
            .floor()
            .max(0.0);
        let xmax = q
            .iter()
            .map(|v| v[0])
            .fold(f64::NEG_INFINITY, f64::max)
            .ceil()
            .min(self.width as f64);
        let ymin = q
            .iter()
            .map(|v| v[1])
            .fold(f64::INFINITY, f64::min)
            .floor()
            .max(0.0);
        let ymax = q
            .iter()
            .map(|v| v[1])
            .fold(f64::NEG_INFINITY, f64::max)
            .ceil()
            .min(self.height as f64);
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

    /// Draws a segment of `width` output pixels (drawn on top, no depth test).
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

    pub fn line(&mut self, a: [f64; 2], b: [f64; 2], width: f64, color: [f32; 3]) {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = (dx * dx + dy * dy).sqrt();
        if len.is_nan() || len <= 0.0 || !len.is_finite() {
            return;
        }
        let h = 0.5 * width / len;
        let (nx, ny) = (-dy * h, dx * h);
        // Extend the ends by half a width so polylines join without gaps.
        let (ex, ey) = (dx * h, dy * h);
        let p0 = [a[0] - ex + nx, a[1] - ey + ny];
        let p1 = [b[0] + ex + nx, b[1] + ey + ny];
        let p2 = [b[0] + ex - nx, b[1] + ey - ny];
        let p3 = [a[0] - ex - nx, a[1] - ey - ny];
        self.fill_triangle([p0, p1, p2], None, |_| Some(color));
        self.fill_triangle([p0, p2, p3], None, |_| Some(color));
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
                let px = acc.map(|v| ((v / n).clamp(0.0, 1.0) * 255.0 + 0.5) as u8);
                img.put_pixel(ox as u32, oy as u32, Rgb(px));
            }
        }
        img
    }
}

/// An RGB colour from 8-bit components.
pub fn rgb(r: u8, g: u8, b: u8) -> [f32; 3] {
    [r as f32 / 255.0, g as f32 / 255.0, b as f32 / 255.0]
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
}
