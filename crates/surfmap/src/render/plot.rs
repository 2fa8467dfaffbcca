//! Picture (c): line plots. [`line_plot`] stacks panels of series over the iteration
//! index, each on a log10 or linear y axis, with optional staircases and markers only
//! where something changes (e.g. the level of a multiscale solve).
//! [`convergence_plot`] is its common case: energy and gradient-norm decay per Newton
//! iteration on log axes (thesis Fig. 4.1 plots `log10 ‖∇E‖`; a quadratic tail shows
//! as a steepening curve).

use image::RgbImage;

use super::canvas::{Canvas, rgb};
use super::font::{draw_text, draw_text_centered, format_number, text_height, text_width};
use super::uv_layout::Rect;

/// A text label placed after the canvas is downsampled.
type Label = (i64, i64, String);

/// A "nice" tick step (1, 2 or 5 × 10^k) giving about `target` ticks over `span`.
fn nice_step(span: f64, target: f64) -> f64 {
    let raw = (span / target).max(1e-300);
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    mag * if f <= 1.0 {
        1.0
    } else if f <= 2.0 {
        2.0
    } else if f <= 5.0 {
        5.0
    } else {
        10.0
    }
}

/// One curve of a [`PlotPanel`]: `values[i]` is drawn at `x = i`. Values the axis
/// cannot show (non-finite; non-positive on a log axis) leave gaps.
#[derive(Clone, Debug)]
pub struct Series<'a> {
    /// Legend entry, drawn in the series' colour at the panel's top right; empty for
    /// none.
    pub name: String,
    pub values: &'a [f64],
    pub color: [f32; 3],
    /// Samples with a square marker: `None` marks every sample; `Some(&[i, j, …])` only
    /// those (e.g. the first iteration of each level of a multiscale solve), each with
    /// a pale vertical guide across the panel and a marker of at least 4 pixels.
    pub marks: Option<&'a [usize]>,
    /// Draw a staircase (from each sample horizontally to the next `x`, then
    /// vertically) instead of straight segments between samples.
    pub steps: bool,
}

impl<'a> Series<'a> {
    /// A named line through `values`, every sample marked.
    pub fn new(name: impl Into<String>, values: &'a [f64], color: [f32; 3]) -> Self {
        Self {
            name: name.into(),
            values,
            color,
            marks: None,
            steps: false,
        }
    }
}

/// One panel of a [`line_plot`]: a title, the y axis (log10 or linear) and its curves.
#[derive(Clone, Debug)]
pub struct PlotPanel<'a> {
    pub title: String,
    pub log_y: bool,
    pub series: Vec<Series<'a>>,
}

/// The y range `[lo, hi]` of the axis values, padded by 5 % (±0.5 around a single
/// value; `[0, 1]` when there is none).
fn padded_range(ys: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = ys
        .fold(None, |acc: Option<(f64, f64)>, x| {
            Some(acc.map_or((x, x), |(a, b)| (a.min(x), b.max(x))))
        })
        .unwrap_or((0.0, 1.0));
    if hi - lo < 1e-9 {
        lo -= 0.5;
        hi += 0.5;
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// Y ticks `(axis value, label)` over `[lo, hi]`: on a log axis powers of ten (or four
/// values when the range spans less than a decade), else multiples of a nice step.
fn y_ticks(lo: f64, hi: f64, log_y: bool) -> Vec<(f64, String)> {
    let span = hi - lo;
    if !log_y {
        let step = nice_step(span, 5.0);
        let (first, last) = ((lo / step).ceil() as i64, (hi / step).floor() as i64);
        // As many decimals as the step needs (20 → "60", 0.05 → "0.15").
        let decimals = (-step.log10().floor()).max(0.0) as usize;
        let plain = (1e-3..1e5).contains(&step) && lo.abs().max(hi.abs()) < 1e5;
        let label = |v: f64| {
            if plain {
                format!("{v:.decimals$}")
            } else {
                format_number(v)
            }
        };
        return (first..=last)
            .map(|k| (k as f64 * step, label(k as f64 * step)))
            .collect();
    }
    if span >= 1.0 {
        let step = nice_step(span, 5.0).max(1.0).round();
        let mut k = (lo / step).ceil() * step;
        let mut t = Vec::new();
        while k <= hi {
            t.push((k, format!("1E{}", k as i64)));
            k += step;
        }
        t
    } else {
        (0..4)
            .map(|i| {
                let l = lo + span * (0.1 + 0.8 * i as f64 / 3.0);
                (l, format_number(10f64.powf(l)))
            })
            .collect()
    }
}

/// Draws one panel into `rect`: grid, ticks, curves with markers, frame; text goes to
/// `labels` (drawn after the canvas is downsampled).
fn draw_panel(
    canvas: &mut Canvas,
    labels: &mut Vec<Label>,
    rect: Rect,
    panel: &PlotPanel,
    font: u32,
) {
    let axis = rgb(60, 60, 60);
    let grid = rgb(225, 225, 225);
    let th = text_height(font) as i64;
    labels.push((rect.x as i64, rect.y as i64 - th - 6, panel.title.clone()));
    let to_axis = |v: f64| -> f64 {
        match (panel.log_y, v.is_finite()) {
            (true, true) if v > 0.0 => v.log10(),
            (false, true) => v,
            _ => f64::NAN,
        }
    };
    let all = panel.series.iter().flat_map(|s| s.values.iter());
    let (lo, hi) = padded_range(all.map(|&v| to_axis(v)).filter(|y| y.is_finite()));
    let n = panel
        .series
        .iter()
        .map(|s| s.values.len())
        .max()
        .unwrap_or(0);
    let xmax = (n.max(2) - 1) as f64;
    let sx = |i: f64| rect.x + rect.w * i / xmax;
    let sy = |l: f64| rect.y + rect.h * (1.0 - (l - lo) / (hi - lo));
    for (l, text) in y_ticks(lo, hi, panel.log_y) {
        let y = sy(l);
        canvas.line([rect.x, y], [rect.x + rect.w, y], 0.8, grid);
        canvas.line([rect.x - 4.0, y], [rect.x, y], 1.0, axis);
        labels.push((
            rect.x as i64 - 6 - text_width(&text, font) as i64,
            y as i64 - th / 2,
            text,
        ));
    }
    let xstep = nice_step(xmax, 6.0).max(1.0);
    let mut i = 0.0;
    while i <= xmax + 1e-9 {
        let x = sx(i);
        canvas.line([x, rect.y + rect.h], [x, rect.y + rect.h + 4.0], 1.0, axis);
        let text = format!("{}", i as i64);
        labels.push((
            x as i64 - text_width(&text, font) as i64 / 2,
            (rect.y + rect.h) as i64 + 7,
            text,
        ));
        i += xstep;
    }
    let r: f64 = if n > 60 { 1.5 } else { 3.0 };
    // Samples marked by choice (not every sample) get a pale vertical guide across the
    // panel and a marker large enough to see among hundreds of samples.
    for s in &panel.series {
        let pale = s.color.map(|c| c + 0.65 * (1.0 - c));
        for &i in s.marks.unwrap_or(&[]) {
            if i < s.values.len() {
                let x = sx(i as f64);
                canvas.line([x, rect.y], [x, rect.y + rect.h], 1.0, pale);
            }
        }
    }
    for s in &panel.series {
        let pts: Vec<[f64; 2]> = s
            .values
            .iter()
            .enumerate()
            .map(|(i, &v)| [sx(i as f64), sy(to_axis(v))])
            .collect();
        if s.steps {
            for w in pts.windows(2) {
                if w[0][1].is_finite() && w[1][1].is_finite() {
                    let corner = [w[1][0], w[0][1]];
                    canvas.polyline(&[w[0], corner, w[1]], 2.0, s.color);
                }
            }
        } else {
            let gaps: Vec<[f64; 2]> = pts
                .iter()
                .map(|p| if p[1].is_finite() { *p } else { [f64::NAN; 2] })
                .collect();
            canvas.polyline(&gaps, 2.0, s.color);
        }
        let marked = |i: usize| s.marks.is_none_or(|m| m.contains(&i));
        let radius = if s.marks.is_some() { r.max(4.0) } else { r };
        for (i, p) in pts.iter().enumerate() {
            if p[1].is_finite() && marked(i) {
                canvas.marker(*p, radius, s.color);
            }
        }
    }
    // Legend: one line per named series at the top right, on white over the curves.
    let named: Vec<&Series> = panel.series.iter().filter(|s| !s.name.is_empty()).collect();
    if let Some(wmax) = named.iter().map(|s| text_width(&s.name, font)).max() {
        let right = rect.x + rect.w - 8.0;
        let (x0, y0) = (right - wmax as f64 - 30.0, rect.y + 3.0);
        let y1 = y0 + named.len() as f64 * (th + 6) as f64 + 3.0;
        canvas.fill_rect(x0, y0, right + 5.0, y1, [1.0; 3]);
        for (j, s) in named.iter().enumerate() {
            let ly = rect.y as i64 + 6 + j as i64 * (th + 6);
            let lx = right as i64 - text_width(&s.name, font) as i64;
            let mid = ly as f64 + 0.5 * th as f64;
            canvas.line(
                [lx as f64 - 24.0, mid],
                [lx as f64 - 6.0, mid],
                2.0,
                s.color,
            );
            labels.push((lx, ly, s.name.clone()));
        }
    }
    canvas.stroke_rect(rect.x, rect.y, rect.x + rect.w, rect.y + rect.h, 1.2, axis);
}

/// Panels stacked top to bottom over a shared x axis (the sample index, labelled
/// `x_label`), under `title`; `size = (width, height)`. Each panel has its own y range
/// over all its series. Empty or unplottable series leave an empty frame, never a
/// panic.
pub fn line_plot(title: &str, x_label: &str, panels: &[PlotPanel], size: (u32, u32)) -> RgbImage {
    let (w, h) = (size.0.clamp(128, 16384), size.1.clamp(128, 16384));
    let font = if w.min(h) >= 700 { 2 } else { 1 };
    let th = text_height(font) as f64;
    let mut canvas = Canvas::new(w, h, 3, [1.0; 3]);
    let mut labels: Vec<Label> = Vec::new();
    let left = 16.0 + text_width("1.00E-10", font) as f64;
    let right = 16.0;
    let gap = 3.0 * th + 22.0;
    let top = 2.0 * th + 24.0;
    let bottom = 2.0 * th + 24.0;
    let k = panels.len().max(1) as f64;
    let ph = ((h as f64 - top - bottom - gap * (k - 1.0)) / k).max(10.0);
    let pw = (w as f64 - left - right).max(10.0);
    for (i, panel) in panels.iter().enumerate() {
        let rect = Rect {
            x: left,
            y: top + i as f64 * (ph + gap),
            w: pw,
            h: ph,
        };
        draw_panel(&mut canvas, &mut labels, rect, panel, font);
    }
    let mut img = canvas.into_image();
    for (x, y, t) in &labels {
        draw_text(&mut img, *x, *y, t, font, [20, 20, 20]);
    }
    draw_text_centered(
        &mut img,
        (left + pw / 2.0) as i64,
        h as i64 - th as i64 - 6,
        x_label,
        font,
        [20, 20, 20],
    );
    draw_text(&mut img, 8, 6, title, font, [20, 20, 20]);
    img
}

/// Energy (top) and gradient norm (bottom) per iteration, both on log10 axes, from
/// `history[i] = (E_i, ‖∇E_i‖)`. `size = (width, height)`.
pub fn convergence_plot(history: &[(f64, f64)], size: (u32, u32)) -> RgbImage {
    convergence_plot_labeled(history, "ENERGY E", size)
}

/// [`convergence_plot`] with its own label for the top series (e.g. `E − E_final`,
/// which shows the rate of convergence on a log axis).
pub fn convergence_plot_labeled(
    history: &[(f64, f64)],
    energy_label: &str,
    size: (u32, u32),
) -> RgbImage {
    let energy: Vec<f64> = history.iter().map(|p| p.0).collect();
    let grad: Vec<f64> = history.iter().map(|p| p.1).collect();
    fn panel<'a>(title: &str, values: &'a [f64], color: [f32; 3]) -> PlotPanel<'a> {
        PlotPanel {
            title: title.into(),
            log_y: true,
            series: vec![Series::new("", values, color)],
        }
    }
    line_plot(
        "CONVERGENCE (LOG SCALE)",
        "ITERATION",
        &[
            panel(energy_label, &energy, rgb(30, 90, 200)),
            panel("GRADIENT NORM |GRAD E|", &grad, rgb(210, 60, 30)),
        ],
        size,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::tests::assert_not_blank;

    #[test]
    fn plot_of_a_quadratic_tail_is_drawn_and_deterministic() {
        let mut hist = Vec::new();
        let mut g: f64 = 10.0;
        for i in 0..12 {
            hist.push((5.0 + g, g));
            g = if i < 5 { g * 0.5 } else { (g * g).max(1e-14) };
        }
        let a = convergence_plot(&hist, (480, 360));
        assert_eq!(a.dimensions(), (480, 360));
        assert_not_blank(&a);
        // Both curve colours are present.
        assert!(a.pixels().any(|p| p.0[2] > 150 && p.0[0] < 80));
        assert!(a.pixels().any(|p| p.0[0] > 150 && p.0[2] < 80));
        assert_eq!(a, convergence_plot(&hist, (480, 360)));
        // Degenerate histories do not panic.
        let _ = convergence_plot(&[], (100, 100));
        let _ = convergence_plot(&[(0.0, f64::NAN), (-1.0, 0.0)], (200, 200));
        let _ = convergence_plot(&[(1.0, 1.0)], (200, 200));
    }

    #[test]
    fn nice_steps() {
        assert_eq!(nice_step(10.0, 5.0), 2.0);
        assert_eq!(nice_step(100.0, 6.0), 20.0);
        assert_eq!(nice_step(7.0, 6.0), 2.0);
    }

    #[test]
    fn ticks_on_linear_and_log_axes() {
        // Span 8.5 over about 5 ticks: step 1.7 rounds up to 2.
        let lin: Vec<f64> = y_ticks(-0.3, 8.2, false).iter().map(|t| t.0).collect();
        assert_eq!(lin, [0.0, 2.0, 4.0, 6.0, 8.0]);
        assert_eq!(y_ticks(-0.3, 8.2, false)[1].1, "2");
        let neg: Vec<(f64, String)> = y_ticks(-0.07, -0.01, false);
        assert_eq!(neg.len(), 3, "{neg:?}");
        assert!((neg[0].0 + 0.06).abs() < 1e-12 && (neg[2].0 + 0.02).abs() < 1e-12);
        assert_eq!((neg[0].1.as_str(), neg[2].1.as_str()), ("-0.06", "-0.02"));
        assert_eq!(y_ticks(0.0, 3e6, false)[1].1, "1.00E6");
        let log: Vec<String> = y_ticks(-6.2, 0.4, true).into_iter().map(|t| t.1).collect();
        assert_eq!(log, ["1E-6", "1E-4", "1E-2", "1E0"]);
        assert_eq!(padded_range([2.0, 4.0].into_iter()), (1.9, 4.1));
        assert_eq!(padded_range(std::iter::empty()), (-0.05, 1.05));
    }

    /// Pixels of exactly colour `c`, as `(x, y)`.
    fn pixels_of(img: &RgbImage, c: [u8; 3]) -> Vec<(u32, u32)> {
        img.enumerate_pixels()
            .filter(|(_, _, p)| p.0 == c)
            .map(|(x, y, _)| (x, y))
            .collect()
    }

    fn panel<'a>(log_y: bool, series: Vec<Series<'a>>) -> PlotPanel<'a> {
        PlotPanel {
            title: "P".into(),
            log_y,
            series,
        }
    }

    #[test]
    fn markers_sit_only_at_the_marked_samples() {
        // A flat line of 7 samples (x = 0 … 6) with markers at samples 2 and 5: the
        // line is 2 px tall, markers 6 px, so the columns with a tall run of the colour
        // are the markers', at 2/6 and 5/6 of the way along the line.
        let green = [0, 200, 0];
        let v = [1.0; 7];
        let s = Series {
            marks: Some(&[2, 5]),
            ..Series::new("", &v, rgb(0, 200, 0))
        };
        let img = line_plot("", "", &[panel(false, vec![s])], (400, 200));
        let px = pixels_of(&img, green);
        let (first, last) = (
            px.iter().map(|p| p.0).min().unwrap(),
            px.iter().map(|p| p.0).max().unwrap(),
        );
        // The line runs from sample 0 to 6, extended by half its width (1 px) at both ends.
        let (x_at0, x_at6) = (first as f64 + 1.0, last as f64);
        let tall: Vec<u32> = (first..=last)
            .filter(|&x| px.iter().filter(|p| p.0 == x).count() >= 5)
            .collect();
        assert!(!tall.is_empty());
        let clusters: Vec<f64> = tall
            .chunk_by(|a, b| b - a == 1)
            .map(|c| (c[0] + c[c.len() - 1]) as f64 / 2.0)
            .collect();
        assert_eq!(clusters.len(), 2, "tall columns {tall:?}");
        for (c, i) in clusters.iter().zip([2.0, 5.0]) {
            let want = x_at0 + (x_at6 - x_at0) * i / 6.0;
            assert!((c - want).abs() <= 1.5, "marker {i} at {c}, want {want}");
        }
    }

    /// Among hundreds of samples (where every-sample markers shrink to 1.5 px), chosen
    /// marks stay visible: 8 px markers and a pale guide from the top of the panel to
    /// its bottom, at the marked samples only.
    #[test]
    fn chosen_marks_show_among_many_samples() {
        let v: Vec<f64> = (0..400).map(|i| 1.0 + i as f64 * 0.001).collect();
        let s = Series {
            marks: Some(&[100, 300]),
            ..Series::new("", &v, rgb(0, 200, 0))
        };
        let img = line_plot("", "", &[panel(false, vec![s])], (800, 300));
        let green = pixels_of(&img, [0, 200, 0]);
        let tall: Vec<u32> = (0..img.width())
            .filter(|&x| green.iter().filter(|p| p.0 == x).count() >= 7)
            .collect();
        let clusters = tall.chunk_by(|a, b| b - a == 1).count();
        assert_eq!(clusters, 2, "tall columns {tall:?}");
        // Pale guides: columns where pale green (the guide's colour, blended with the
        // white behind it: red and blue alike and well above 0, green above them) runs
        // most of the image's height.
        let pale =
            |p: [u8; 3]| p[0] > 120 && p[1] as i32 > p[0] as i32 + 25 && p[0].abs_diff(p[2]) < 10;
        let guides: Vec<u32> = (0..img.width())
            .filter(|&x| {
                (0..img.height())
                    .filter(|&y| pale(img.get_pixel(x, y).0))
                    .count()
                    > 150
            })
            .collect();
        assert_eq!(
            guides.chunk_by(|a, b| b - a == 1).count(),
            2,
            "guides {guides:?}"
        );
    }

    #[test]
    fn staircase_drops_vertically_and_a_line_slopes() {
        // Levels 4, 4, 4, 1, 1, 1 on a linear axis: the staircase has one vertical drop;
        // the straight-line series goes diagonally from sample 2 to 3.
        let v = [4.0, 4.0, 4.0, 1.0, 1.0, 1.0];
        let green = [0, 200, 0];
        let between_columns = |steps: bool| {
            let s = Series {
                steps,
                marks: Some(&[]),
                ..Series::new("", &v, rgb(0, 200, 0))
            };
            let img = line_plot("", "", &[panel(false, vec![s])], (600, 300));
            let px = pixels_of(&img, green);
            // The levels: rows with a long horizontal run of the colour.
            let level_rows: Vec<u32> = (0..300)
                .filter(|&y| px.iter().filter(|p| p.1 == y).count() > 80)
                .collect();
            let (ya, yb) = (level_rows[0], *level_rows.last().unwrap());
            assert!(yb - ya > 100, "levels at rows {ya} and {yb}");
            let mut cols: Vec<u32> = px
                .iter()
                .filter(|p| p.1 > ya + 4 && p.1 + 4 < yb)
                .map(|p| p.0)
                .collect();
            cols.sort_unstable();
            cols.dedup();
            cols.len()
        };
        let steps = between_columns(true);
        let line = between_columns(false);
        assert!(steps <= 3, "a staircase drops within {steps} columns");
        assert!(line >= 40, "a line slopes across {line} columns");
    }

    #[test]
    fn series_share_a_panel_range_and_rising_values_rise() {
        // Two series on one log panel: 1 … 1e4 rising, 1e4 … 1 falling. The rising
        // one is low on the left, high on the right; the falling one the reverse.
        let up: Vec<f64> = (0..5).map(|i| 10f64.powi(i)).collect();
        let down: Vec<f64> = up.iter().rev().copied().collect();
        let (red, blue) = ([220, 0, 0], [0, 0, 220]);
        let p = panel(
            true,
            vec![
                Series::new("UP", &up, rgb(220, 0, 0)),
                Series::new("DOWN", &down, rgb(0, 0, 220)),
            ],
        );
        let img = line_plot("T", "X", &[p], (500, 400));
        let mean_y = |c: [u8; 3], left: bool| {
            let px: Vec<(u32, u32)> = pixels_of(&img, c)
                .into_iter()
                .filter(|p| (p.0 < 200) == left && p.1 > 60)
                .collect();
            px.iter().map(|p| p.1 as f64).sum::<f64>() / px.len().max(1) as f64
        };
        // Image y grows downwards: high values have small y.
        assert!(mean_y(red, true) > mean_y(red, false) + 50.0);
        assert!(mean_y(blue, true) + 50.0 < mean_y(blue, false));
        // Legend entries in the series' colours near the top right of the panel.
        let legend = |c: [u8; 3]| pixels_of(&img, c).iter().any(|p| p.0 > 350 && p.1 < 80);
        assert!(legend(red) && legend(blue));
    }
}
