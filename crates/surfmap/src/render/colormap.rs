//! Colour maps and value ranges for colouring triangles by a measure, and the colour
//! bar that explains them.

use image::RgbImage;

use super::canvas::Canvas;
use super::font::{draw_text, format_number, text_height};

/// Viridis, piecewise linear through 9 samples of the original map; `t ∈ [0, 1]`.
pub fn viridis(t: f64) -> [f32; 3] {
    const C: [[f32; 3]; 9] = [
        [0.267, 0.005, 0.329],
        [0.283, 0.141, 0.458],
        [0.254, 0.265, 0.530],
        [0.207, 0.372, 0.553],
        [0.164, 0.471, 0.558],
        [0.128, 0.567, 0.551],
        [0.135, 0.659, 0.518],
        [0.478, 0.821, 0.319],
        [0.993, 0.906, 0.144],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let x = t * (C.len() - 1) as f64;
    let i = (x.floor() as usize).min(C.len() - 2);
    let f = (x - i as f64) as f32;
    [0, 1, 2].map(|k| C[i][k] + f * (C[i + 1][k] - C[i][k]))
}

/// A value range mapped onto the colour map, linear or logarithmic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColorScale {
    pub lo: f64,
    pub hi: f64,
    pub log: bool,
}

impl ColorScale {
    /// Range from the 1st to the 99th percentile of the finite values (robust to a
    /// few extreme triangles); logarithmic when all are positive and span more than a
    /// factor of 10. `None` when there is no finite value.
    pub fn auto(values: &[f64]) -> Option<Self> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
        let (mut lo, mut hi) = (at(0.01), at(0.99));
        if hi <= lo {
            let m = lo.abs().max(1e-12);
            lo -= 1e-3 * m;
            hi += 1e-3 * m;
        }
        let log = lo > 0.0 && hi / lo > 10.0;
        Some(Self { lo, hi, log })
    }

    /// Position of `x` in `[0, 1]` (clamped; non-finite maps to 1).
    pub fn position(&self, x: f64) -> f64 {
        if !x.is_finite() {
            return 1.0;
        }
        let t = if self.log {
            (x.max(self.lo).ln() - self.lo.ln()) / (self.hi.ln() - self.lo.ln())
        } else {
            (x - self.lo) / (self.hi - self.lo)
        };
        t.clamp(0.0, 1.0)
    }

    pub fn color(&self, x: f64) -> [f32; 3] {
        viridis(self.position(x))
    }
}

/// Draws a vertical colour bar into the rectangle `(x, y, w, h)` of the canvas
/// (high values on top).
pub fn color_bar(canvas: &mut Canvas, x: f64, y: f64, w: f64, h: f64) {
    let steps = 128;
    for i in 0..steps {
        let t0 = i as f64 / steps as f64;
        let t1 = (i + 1) as f64 / steps as f64;
        canvas.fill_rect(
            x,
            y + h * (1.0 - t1),
            x + w,
            y + h * (1.0 - t0) + 0.01,
            viridis(0.5 * (t0 + t1)),
        );
    }
}

/// Labels a colour bar drawn at `bar = [x, y, w, h]`: the range ends beside it, and
/// `title` above it.
pub fn label_color_bar(
    img: &mut RgbImage,
    scale: &ColorScale,
    bar: [f64; 4],
    title: &str,
    font: u32,
) {
    let [x, y, w, h] = bar;
    let black = [20, 20, 20];
    let tx = (x + w) as i64 + 4;
    draw_text(img, tx, y as i64, &format_number(scale.hi), font, black);
    let mid = if scale.log {
        (scale.lo * scale.hi).sqrt()
    } else {
        0.5 * (scale.lo + scale.hi)
    };
    draw_text(
        img,
        tx,
        (y + 0.5 * h) as i64 - text_height(font) as i64 / 2,
        &format_number(mid),
        font,
        black,
    );
    draw_text(
        img,
        tx,
        (y + h) as i64 - text_height(font) as i64,
        &format_number(scale.lo),
        font,
        black,
    );
    draw_text(
        img,
        x as i64,
        y as i64 - text_height(font) as i64 - 4,
        title,
        font,
        black,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_runs_dark_to_bright() {
        let lum = |c: [f32; 3]| 0.3 * c[0] + 0.59 * c[1] + 0.11 * c[2];
        let mut prev = -1.0;
        for i in 0..=20 {
            let l = lum(viridis(i as f64 / 20.0));
            assert!(l > prev);
            prev = l;
        }
    }

    #[test]
    fn auto_scale_goes_log_over_a_decade() {
        let v: Vec<f64> = (0..100).map(|i| 10f64.powf(i as f64 / 33.0)).collect();
        let s = ColorScale::auto(&v).unwrap();
        assert!(s.log);
        assert!((s.position((s.lo * s.hi).sqrt()) - 0.5).abs() < 1e-9);
        let lin = ColorScale::auto(&[1.0, 2.0, f64::NAN, 3.0]).unwrap();
        assert!(!lin.log);
        assert_eq!(lin.position(2.0), 0.5);
        assert!(ColorScale::auto(&[f64::NAN]).is_none());
        let flat = ColorScale::auto(&[1.0, 1.0]).unwrap();
        assert!(flat.hi > flat.lo);
    }
}
