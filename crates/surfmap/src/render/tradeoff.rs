//! Picture (d): the trade-off sheet of thesis Fig. 4.4: several flattenings of one
//! mesh (different α) side by side, each as a checkered surface over its parameter
//! domain, with the min / mean / max of the thesis's angle, area and length distortion
//! under each, and a strip of graphs of those numbers across the panels (log axes,
//! the panels' numbers under their points, a legend of the min / mean / max lines).

use image::RgbImage;

use super::canvas::{Canvas, rgb};
use super::font::{
    draw_text, draw_text_centered, format_number, format_short, text_height, text_width,
};
use super::surface::draw_surface;
use super::uv_layout::{Rect, draw_layout, orientation_fill};
use crate::measure::{
    MeasureOptions, MinMeanMax, ThesisMeasures, corner_uvs_from_vertex_uvs,
    distortion_report_per_vertex,
};

/// One flattening on the sheet: a title (e.g. the α used) and the map.
#[derive(Clone, Debug)]
pub struct TradeoffPanel<'a> {
    pub title: String,
    pub positions: &'a [[f64; 3]],
    pub triangles: &'a [[u32; 3]],
    /// Per-vertex UVs.
    pub uvs: &'a [[f64; 2]],
}

/// The sheet, `size = (width, height)`. Panels whose map cannot be measured (bad
/// indices, UV count) are drawn empty and marked "INVALID".
pub fn tradeoff_sheet(panels: &[TradeoffPanel], size: (u32, u32)) -> RgbImage {
    let (w, h) = (size.0.clamp(128, 16384), size.1.clamp(128, 16384));
    let font = if w.min(h) >= 900 { 2 } else { 1 };
    let th = text_height(font) as f64;
    let mut canvas = Canvas::new(w, h, 3, [1.0; 3]);
    let mut labels: Vec<(i64, i64, String, bool)> = Vec::new(); // (x, y, text, centred)
    let n = panels.len().max(1);
    let col_w = w as f64 / n as f64;
    let graphs_h = (0.22 * h as f64).max(60.0);
    let table_h = 5.0 * (th + 4.0) + 8.0;
    let pic_top = th + 14.0;
    let pic_h = ((h as f64 - pic_top - table_h - graphs_h - 8.0) / 2.0).max(8.0);
    let measures: Vec<Option<ThesisMeasures>> = panels
        .iter()
        .map(|p| {
            distortion_report_per_vertex(
                p.positions,
                p.triangles,
                p.uvs,
                &MeasureOptions {
                    normalize: true,
                    overlap: false,
                },
            )
            .ok()
            .map(|r| r.measures)
        })
        .collect();
    for (i, p) in panels.iter().enumerate() {
        let x0 = i as f64 * col_w;
        let cx = (x0 + col_w / 2.0) as i64;
        labels.push((cx, 6, format!("{}: {}", i + 1, p.title), true));
        let pad = 0.04 * col_w;
        let Ok(corners) = corner_uvs_from_vertex_uvs(p.triangles, p.uvs) else {
            continue;
        };
        if measures[i].is_none() {
            labels.push((cx, (pic_top + pic_h) as i64, "INVALID".into(), true));
            continue;
        }
        let r3 = Rect {
            x: x0 + pad,
            y: pic_top,
            w: col_w - 2.0 * pad,
            h: pic_h - pad,
        };
        draw_surface(&mut canvas, r3, p.positions, p.triangles, &corners, 12);
        let ruv = Rect {
            x: x0 + pad,
            y: pic_top + pic_h,
            w: col_w - 2.0 * pad,
            h: pic_h - pad,
        };
        draw_layout(
            &mut canvas,
            ruv,
            p.triangles,
            &corners,
            orientation_fill(&corners),
        );
    }
    // Table under each panel.
    let table_y = pic_top + 2.0 * pic_h + 4.0;
    for (i, m) in measures.iter().enumerate() {
        let x0 = i as f64 * col_w + 0.04 * col_w;
        let Some(m) = m else { continue };
        let row = |k: usize| (table_y + k as f64 * (th + 4.0)) as i64;
        labels.push((x0 as i64, row(0), "       MIN   MEAN    MAX".into(), false));
        for (k, (name, s)) in [("ANGLE", m.angle), ("AREA ", m.area), ("LEN  ", m.length)]
            .iter()
            .enumerate()
        {
            let text = format!(
                "{name} {:>6} {:>6} {:>6}",
                format_short(s.min),
                format_short(s.mean),
                format_short(s.max)
            );
            labels.push((x0 as i64, row(k + 1), text, false));
        }
    }
    // Graphs across panels: one per measure, lines for max / mean / min (log10 axis).
    let gy = h as f64 - graphs_h + th + 6.0;
    let gh = graphs_h - 2.0 * th - 16.0;
    let gw = w as f64 / 3.0;
    let pick: [fn(&ThesisMeasures) -> MinMeanMax; 3] = [|m| m.angle, |m| m.area, |m| m.length];
    for (g, (name, get)) in ["ANGLE", "AREA", "LENGTH"].iter().zip(pick).enumerate() {
        let lab = text_width("0.0000", font) as f64 + 8.0;
        let rect = Rect {
            x: g as f64 * gw + lab,
            y: gy,
            w: gw - lab - 12.0,
            h: gh,
        };
        let series: Vec<Option<MinMeanMax>> =
            measures.iter().map(|m| m.as_ref().map(get)).collect();
        let logs: Vec<f64> = series
            .iter()
            .flatten()
            .flat_map(|s| [s.min, s.mean, s.max])
            .filter(|v| *v > 0.0 && v.is_finite())
            .map(f64::log10)
            .collect();
        let (mut lo, mut hi) = logs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        if lo.is_nan() || hi.is_nan() || lo > hi {
            lo = 0.0;
            hi = 1.0;
        }
        if hi - lo < 1e-6 {
            lo -= 0.1;
            hi += 0.1;
        }
        let frame = rgb(90, 90, 90);
        canvas.stroke_rect(rect.x, rect.y, rect.x + rect.w, rect.y + rect.h, 1.0, frame);
        let sx = |i: usize| {
            if n > 1 {
                rect.x + rect.w * (0.05 + 0.9 * i as f64 / (n - 1) as f64)
            } else {
                rect.x + rect.w / 2.0
            }
        };
        let sy = |v: f64| rect.y + rect.h * (1.0 - (v.log10() - lo) / (hi - lo));
        let colors = [rgb(40, 90, 210), rgb(20, 20, 20), rgb(210, 50, 40)];
        for (k, sel) in [
            |s: &MinMeanMax| s.min,
            |s: &MinMeanMax| s.mean,
            |s: &MinMeanMax| s.max,
        ]
        .iter()
        .enumerate()
        {
            let pts: Vec<[f64; 2]> = series
                .iter()
                .enumerate()
                .map(|(i, s)| {
                    s.as_ref()
                        .map(sel)
                        .filter(|v| *v > 0.0 && v.is_finite())
                        .map_or([f64::NAN; 2], |v| [sx(i), sy(v)])
                })
                .collect();
            canvas.polyline(&pts, 1.6, colors[k]);
            for p in pts.iter().filter(|p| p[0].is_finite()) {
                canvas.marker(*p, 2.5, colors[k]);
            }
        }
        // Axis labels: the measure on a log axis (title), the number of the panel each
        // point belongs to under it; the legend of the three lines at the title's right.
        labels.push((
            rect.x as i64,
            (rect.y - th - 4.0) as i64,
            format!("{name} (LOG AXIS)"),
            false,
        ));
        for i in 0..panels.len() {
            labels.push((
                sx(i) as i64,
                (rect.y + rect.h + 4.0) as i64,
                format!("{}", i + 1),
                true,
            ));
        }
        let mut right = rect.x + rect.w;
        for (k, key) in ["MIN", "MEAN", "MAX"].iter().enumerate() {
            let tw = text_width(key, font) as f64;
            let x = right - tw;
            let mid = rect.y - 4.0 - 0.5 * th;
            canvas.line([x - 18.0, mid], [x - 4.0, mid], 1.6, colors[k]);
            labels.push((x as i64, (rect.y - th - 4.0) as i64, key.to_string(), false));
            right = x - 26.0;
        }
        let hi_t = format_number(10f64.powf(hi));
        let lo_t = format_number(10f64.powf(lo));
        labels.push((
            rect.x as i64 - text_width(&hi_t, font) as i64 - 3,
            rect.y as i64,
            hi_t,
            false,
        ));
        labels.push((
            rect.x as i64 - text_width(&lo_t, font) as i64 - 3,
            (rect.y + rect.h - th) as i64,
            lo_t,
            false,
        ));
    }
    let mut img = canvas.into_image();
    for (x, y, t, centred) in &labels {
        if *centred {
            draw_text_centered(&mut img, *x, *y, t, font, [20, 20, 20]);
        } else {
            draw_text(&mut img, *x, *y, t, font, [20, 20, 20]);
        }
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::tests::{assert_not_blank, disc_map};

    #[test]
    fn sheet_with_three_panels_is_drawn_and_deterministic() {
        let (pos, tris, corners) = disc_map(10);
        // Per-vertex UVs from the disc map, then two distorted versions.
        let mut uv = vec![[0.0; 2]; pos.len()];
        for (t, c) in tris.iter().zip(&corners) {
            for k in 0..3 {
                uv[t[k] as usize] = c[k];
            }
        }
        let squeezed: Vec<[f64; 2]> = uv.iter().map(|p| [p[0] * 2.0, p[1]]).collect();
        let warped: Vec<[f64; 2]> = uv
            .iter()
            .map(|p| [p[0] + 0.3 * p[1] * p[1], p[1]])
            .collect();
        let panels = [
            TradeoffPanel {
                title: "α = (1, 0, 0)".into(),
                positions: &pos,
                triangles: &tris,
                uvs: &uv,
            },
            TradeoffPanel {
                title: "SQUEEZED".into(),
                positions: &pos,
                triangles: &tris,
                uvs: &squeezed,
            },
            TradeoffPanel {
                title: "WARPED".into(),
                positions: &pos,
                triangles: &tris,
                uvs: &warped,
            },
        ];
        let a = tradeoff_sheet(&panels, (900, 700));
        assert_eq!(a.dimensions(), (900, 700));
        assert_not_blank(&a);
        assert_eq!(a, tradeoff_sheet(&panels, (900, 700)));
        // A broken panel does not panic.
        let bad = [TradeoffPanel {
            title: "BAD".into(),
            positions: &pos,
            triangles: &tris,
            uvs: &uv[..3],
        }];
        let _ = tradeoff_sheet(&bad, (300, 300));
        let _ = tradeoff_sheet(&[], (300, 300));
    }
}
