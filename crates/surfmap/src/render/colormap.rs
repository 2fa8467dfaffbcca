//! Colour maps (sequential [`Colormap::Viridis`], diverging [`Colormap::BlueWhiteRed`]),
//! value ranges that map numbers onto them ([`ColorScale`]), and the colour bar that
//! explains them.

use image::RgbImage;

use super::canvas::{Canvas, to_rgb8};
use super::font::{draw_text, format_number, text_height};

/// A colour map: piecewise linear in RGB through evenly spaced stops on `t ∈ [0, 1]`
/// (stop `k` of `n` sits at `t = k / (n − 1)`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colormap {
    /// Sequential, for magnitudes: matplotlib's viridis sampled at `t = k/8`; dark
    /// purple `#440154` at 0, teal `#21918c` at ½, yellow `#fde725` at 1, luminance
    /// increasing throughout.
    Viridis,
    /// Diverging, for signed values with 0 at `t = ½`: blue `(33, 77, 191)` at 0,
    /// near-white `(247, 247, 247)` at ½, red `(191, 31, 38)` at 1.
    BlueWhiteRed,
}

impl Colormap {
    /// The stops, 8-bit RGB.
    pub fn stops(self) -> &'static [[u8; 3]] {
        match self {
            Colormap::Viridis => &[
                [0x44, 0x01, 0x54],
                [0x47, 0x2d, 0x7b],
                [0x3b, 0x52, 0x8b],
                [0x2c, 0x72, 0x8e],
                [0x21, 0x91, 0x8c],
                [0x28, 0xae, 0x80],
                [0x5e, 0xc9, 0x62],
                [0xad, 0xdc, 0x30],
                [0xfd, 0xe7, 0x25],
            ],
            Colormap::BlueWhiteRed => &[[33, 77, 191], [247, 247, 247], [191, 31, 38]],
        }
    }

    /// The colour at `t` (clamped to `[0, 1]`; a non-finite `t` gives the colour at 1),
    /// RGB in `[0, 1]`.
    pub fn at(self, t: f64) -> [f32; 3] {
        let c = self.stops();
        let t = if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            1.0
        };
        let x = t * (c.len() - 1) as f64;
        let i = (x.floor() as usize).min(c.len() - 2);
        let f = (x - i as f64) as f32;
        [0, 1, 2].map(|k| {
            let (a, b) = (c[i][k] as f32, c[i + 1][k] as f32);
            (a + f * (b - a)) / 255.0
        })
    }

    /// [`Colormap::at`] as 8-bit RGB.
    pub fn at_rgb8(self, t: f64) -> [u8; 3] {
        to_rgb8(self.at(t))
    }
}

/// A value range and the colour map it is drawn with; linear or logarithmic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColorScale {
    pub lo: f64,
    pub hi: f64,
    pub log: bool,
    pub map: Colormap,
}

impl ColorScale {
    /// Viridis over the 1st to the 99th percentile of the finite values (robust to a
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
        Some(Self {
            lo,
            hi,
            log,
            map: Colormap::Viridis,
        })
    }

    /// Blue–white–red over `[−r, r]`, linear, with `r` the `q`-quantile of the finite
    /// values' magnitudes ([`abs_quantile`]): 0 is white, and the few values beyond
    /// `±r` saturate.
    pub fn symmetric(values: &[f64], q: f64) -> Self {
        let r = abs_quantile(values.iter().copied(), q);
        Self {
            lo: -r,
            hi: r,
            log: false,
            map: Colormap::BlueWhiteRed,
        }
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

    /// The colour of `x`: `map` at [`ColorScale::position`].
    pub fn color(&self, x: f64) -> [f32; 3] {
        self.map.at(self.position(x))
    }
}

/// The `q`-quantile of the finite values' magnitudes (a robust range for signed data);
/// 1 when there is no finite non-zero value to take it from.
pub fn abs_quantile(values: impl Iterator<Item = f64>, q: f64) -> f64 {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).map(f64::abs).collect();
    if v.is_empty() {
        return 1.0;
    }
    let k = ((v.len() - 1) as f64 * q.clamp(0.0, 1.0)) as usize;
    let (_, x, _) = v.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
    if *x > 0.0 { *x } else { 1.0 }
}

/// Draws a vertical colour bar of `map` into the rectangle `(x, y, w, h)` of the canvas
/// (`t = 1`, the high values, on top).
pub fn color_bar(canvas: &mut Canvas, map: Colormap, x: f64, y: f64, w: f64, h: f64) {
    let steps = 128;
    for i in 0..steps {
        let t0 = i as f64 / steps as f64;
        let t1 = (i + 1) as f64 / steps as f64;
        canvas.fill_rect(
            x,
            y + h * (1.0 - t1),
            x + w,
            y + h * (1.0 - t0) + 0.01,
            map.at(0.5 * (t0 + t1)),
        );
    }
}

/// What the values drawn with a scale reach beyond it: their minimum and maximum, when
/// they fall below `lo` or rise above `hi` (those values get the end colours).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Clipping {
    pub below: Option<f64>,
    pub above: Option<f64>,
}

impl Clipping {
    /// Where the finite `values` leave `scale`'s range.
    pub fn of(scale: &ColorScale, values: &[f64]) -> Self {
        let finite = values.iter().copied().filter(|x| x.is_finite());
        let (min, max) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
        Self {
            below: (min < scale.lo).then_some(min),
            above: (max > scale.hi).then_some(max),
        }
    }

    /// Lines of text under a colour bar that say so (`CLIPPED`, `MAX x`, `MIN y`);
    /// none when nothing is clipped.
    pub fn note(&self) -> Vec<String> {
        if self.below.is_none() && self.above.is_none() {
            return vec![];
        }
        let mut lines = vec!["CLIPPED".to_string()];
        lines.extend(self.above.map(|x| format!("MAX {}", format_number(x))));
        lines.extend(self.below.map(|x| format!("MIN {}", format_number(x))));
        lines
    }
}

/// Labels a colour bar drawn at `bar = [x, y, w, h]`: the range ends beside it, and
/// `title` above it. Where the values reach beyond the range (`clipping`), the end's
/// label gets a `+` (top) or `-` (bottom) and the lines of [`Clipping::note`] go under
/// the bar (the caller leaves [`note_height`] free there).
pub fn label_color_bar(
    img: &mut RgbImage,
    scale: &ColorScale,
    bar: [f64; 4],
    title: &str,
    font: u32,
    clipping: Clipping,
) {
    let [x, y, w, h] = bar;
    let black = [20, 20, 20];
    let tx = (x + w) as i64 + 4;
    let top = format_number(scale.hi) + if clipping.above.is_some() { "+" } else { "" };
    draw_text(img, tx, y as i64, &top, font, black);
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
    let bottom = format_number(scale.lo) + if clipping.below.is_some() { "-" } else { "" };
    draw_text(
        img,
        tx,
        (y + h) as i64 - text_height(font) as i64,
        &bottom,
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
    let line = text_height(font) as i64 + 3;
    for (i, text) in clipping.note().iter().enumerate() {
        draw_text(
            img,
            x as i64,
            (y + h) as i64 + 6 + i as i64 * line,
            text,
            font,
            [150, 20, 20],
        );
    }
}

/// Height in pixels that [`Clipping::note`]'s lines take under a colour bar.
pub fn note_height(clipping: &Clipping, font: u32) -> f64 {
    let lines = clipping.note().len();
    if lines == 0 {
        0.0
    } else {
        6.0 + lines as f64 * (text_height(font) as f64 + 3.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative luminance (Rec. 709 weights) of an RGB colour in `[0, 1]`.
    fn luminance(c: [f32; 3]) -> f32 {
        0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
    }

    #[test]
    fn viridis_runs_dark_to_bright() {
        let mut prev = -1.0;
        for i in 0..=64 {
            let l = luminance(Colormap::Viridis.at(i as f64 / 64.0));
            assert!(l > prev, "luminance falls at t = {}/64", i);
            prev = l;
        }
    }

    #[test]
    fn maps_hit_their_documented_colours() {
        // Endpoints and midpoint, as the docs state them (viridis: matplotlib's values).
        let v = Colormap::Viridis;
        assert_eq!(v.at_rgb8(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(v.at_rgb8(0.5), [0x21, 0x91, 0x8c]);
        assert_eq!(v.at_rgb8(1.0), [0xfd, 0xe7, 0x25]);
        let d = Colormap::BlueWhiteRed;
        assert_eq!(d.at_rgb8(0.0), [33, 77, 191]);
        assert_eq!(d.at_rgb8(0.5), [247, 247, 247]);
        assert_eq!(d.at_rgb8(1.0), [191, 31, 38]);
        // Out of range clamps; non-finite gives the top colour.
        assert_eq!(v.at_rgb8(-3.0), v.at_rgb8(0.0));
        assert_eq!(d.at_rgb8(7.0), d.at_rgb8(1.0));
        assert_eq!(v.at_rgb8(f64::NAN), v.at_rgb8(1.0));
        // Halfway between two stops is their mean (piecewise linear in RGB).
        let (a, b) = (v.stops()[2], v.stops()[3]);
        let mid = v.at(2.5 / 8.0);
        for k in 0..3 {
            assert!((mid[k] * 255.0 - 0.5 * (a[k] as f32 + b[k] as f32)).abs() < 1e-3);
        }
        // The diverging map is blue below ½ and red above, whiter towards ½.
        let (lo, hi) = (d.at(0.3), d.at(0.7));
        assert!(lo[2] > lo[0] && hi[0] > hi[2]);
        assert!(luminance(d.at(0.4)) > luminance(d.at(0.1)));
    }

    #[test]
    fn symmetric_scale_centres_zero_on_white() {
        let v: Vec<f64> = (0..=100)
            .map(|i| i as f64 - 50.0)
            .chain([1e9, f64::NAN])
            .collect();
        let s = ColorScale::symmetric(&v, 0.9);
        // |v| sorted: 0, 1, 1, 2, 2, …, 50, 50, 1e9 (102 finite values); k = 90.
        assert_eq!((s.lo, s.hi, s.log), (-45.0, 45.0, false));
        assert_eq!(to_rgb8(s.color(0.0)), [247, 247, 247]);
        assert_eq!(to_rgb8(s.color(1e9)), [191, 31, 38]);
        assert_eq!(to_rgb8(s.color(-45.0)), [33, 77, 191]);
        // Nothing to take a range from: ±1.
        assert_eq!(ColorScale::symmetric(&[f64::NAN, 0.0], 0.98).hi, 1.0);
    }

    #[test]
    fn colour_bar_runs_from_the_low_colour_at_the_bottom_to_the_high_colour_on_top() {
        for map in [Colormap::Viridis, Colormap::BlueWhiteRed] {
            let mut c = Canvas::new(20, 140, 1, [1.0; 3]);
            color_bar(&mut c, map, 5.0, 6.0, 10.0, 128.0);
            let img = c.into_image();
            let px = |y: u32| img.get_pixel(10, y).0;
            // Each of the 128 bands is one pixel high; band i, i pixels above the
            // bottom, holds the colour at t = (i + ½)/128.
            let band = |i: f64| map.at_rgb8((i + 0.5) / 128.0);
            let close = |a: [u8; 3], b: [u8; 3]| (0..3).all(|k| a[k].abs_diff(b[k]) <= 1);
            assert!(close(px(6), band(127.0)), "{map:?} top {:?}", px(6));
            assert!(close(px(133), band(0.0)), "{map:?} bottom {:?}", px(133));
            assert!(close(px(70), band(63.0)), "{map:?} middle {:?}", px(70));
            assert!(!close(px(6), px(133)));
            // Outside the bar: background.
            assert_eq!(img.get_pixel(2, 50).0, [255; 3]);
            assert_eq!(img.get_pixel(10, 2).0, [255; 3]);
        }
    }

    #[test]
    fn clipping_names_the_values_beyond_the_range() {
        let s = ColorScale {
            lo: 1.0,
            hi: 2.0,
            log: false,
            map: Colormap::Viridis,
        };
        assert_eq!(
            Clipping::of(&s, &[1.0, 1.5, 2.0, f64::NAN]),
            Clipping::default()
        );
        assert!(Clipping::default().note().is_empty());
        let c = Clipping::of(&s, &[0.5, 1.5, 7.25, f64::INFINITY]);
        assert_eq!(c.below, Some(0.5));
        assert_eq!(c.above, Some(7.25));
        assert_eq!(c.note(), ["CLIPPED", "MAX 7.250", "MIN 0.5000"]);
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
