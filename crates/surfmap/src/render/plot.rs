//! Picture (c): energy and gradient-norm decay per Newton iteration on a logarithmic
//! axis (thesis Fig. 4.1 plots `log10 ‖∇E‖`; a quadratic tail shows as a steepening
//! curve).

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

/// One panel: `values[i]` at iteration `i` on a log10 axis. Non-positive or
/// non-finite values leave gaps.
fn log_panel(
    canvas: &mut Canvas,
    labels: &mut Vec<Label>,
    rect: Rect,
    values: &[f64],
    color: [f32; 3],
    title: &str,
    font: u32,
) {
    let axis = rgb(60, 60, 60);
    let grid = rgb(225, 225, 225);
    labels.push((
        rect.x as i64,
        rect.y as i64 - text_height(font) as i64 - 6,
        title.to_string(),
    ));
    let logs: Vec<Option<f64>> = values
        .iter()
        .map(|&v| (v > 0.0 && v.is_finite()).then(|| v.log10()))
        .collect();
    let finite: Vec<f64> = logs.iter().flatten().copied().collect();
    let n = values.len();
    let (mut lo, mut hi) = finite
        .iter()
        .fold(None, |acc: Option<(f64, f64)>, &x| {
            Some(acc.map_or((x, x), |(a, b)| (a.min(x), b.max(x))))
        })
        .unwrap_or((0.0, 1.0));
    if hi - lo < 1e-9 {
        lo -= 0.5;
        hi += 0.5;
    }
    let pad = 0.05 * (hi - lo);
    let (lo, hi) = (lo - pad, hi + pad);
    let xmax = (n.max(2) - 1) as f64;
    let sx = |i: f64| rect.x + rect.w * i / xmax;
    let sy = |l: f64| rect.y + rect.h * (1.0 - (l - lo) / (hi - lo));
    // Grid and y ticks.
    let span = hi - lo;
    let ticks: Vec<(f64, String)> = if span >= 1.0 {
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
    };
    for (l, text) in &ticks {
        let y = sy(*l);
        canvas.line([rect.x, y], [rect.x + rect.w, y], 0.8, grid);
        canvas.line([rect.x - 4.0, y], [rect.x, y], 1.0, axis);
        labels.push((
            rect.x as i64 - 6 - text_width(text, font) as i64,
            y as i64 - text_height(font) as i64 / 2,
            text.clone(),
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
    // Curve with markers.
    for w in 0..n.saturating_sub(1) {
        if let (Some(a), Some(b)) = (logs[w], logs[w + 1]) {
            canvas.line(
                [sx(w as f64), sy(a)],
                [sx(w as f64 + 1.0), sy(b)],
                2.0,
                color,
            );
        }
    }
    let r = if n > 60 { 1.5 } else { 3.0 };
    for (i, l) in logs.iter().enumerate() {
        if let Some(l) = l {
            let (x, y) = (sx(i as f64), sy(*l));
            canvas.fill_rect(x - r, y - r, x + r, y + r, color);
        }
    }
    // Frame.
    canvas.stroke_rect(rect.x, rect.y, rect.x + rect.w, rect.y + rect.h, 1.2, axis);
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
    let ph = ((h as f64 - top - bottom - gap) / 2.0).max(10.0);
    let pw = (w as f64 - left - right).max(10.0);
    let energy: Vec<f64> = history.iter().map(|p| p.0).collect();
    let grad: Vec<f64> = history.iter().map(|p| p.1).collect();
    let r1 = Rect {
        x: left,
        y: top,
        w: pw,
        h: ph,
    };
    let r2 = Rect {
        x: left,
        y: top + ph + gap,
        w: pw,
        h: ph,
    };
    log_panel(
        &mut canvas,
        &mut labels,
        r1,
        &energy,
        rgb(30, 90, 200),
        energy_label,
        font,
    );
    log_panel(
        &mut canvas,
        &mut labels,
        r2,
        &grad,
        rgb(210, 60, 30),
        "GRADIENT NORM |GRAD E|",
        font,
    );
    let mut img = canvas.into_image();
    for (x, y, t) in &labels {
        draw_text(&mut img, *x, *y, t, font, [20, 20, 20]);
    }
    draw_text_centered(
        &mut img,
        (left + pw / 2.0) as i64,
        h as i64 - th as i64 - 6,
        "ITERATION",
        font,
        [20, 20, 20],
    );
    draw_text(
        &mut img,
        8,
        6,
        "CONVERGENCE (LOG SCALE)",
        font,
        [20, 20, 20],
    );
    img
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
}
