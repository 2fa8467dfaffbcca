//! Pictures of a match: A's checkerboard carried onto B (thesis fig. 4.9), the
//! deformed grid over B's curvature image, the energy staircase over all levels
//! (fig. 4.7), and the paired features before and after the solve.

use image::RgbImage;

use super::Pictures;
use super::align::AlignmentReport;
use super::deformation::Deformation;
use super::post::a_on_b;
use super::prepare::surface::MatchSurface;
use super::report::feature_fit::{CarriedFeature, carried_features};
use super::solve::Solved;
use super::solve::ncg::LevelLog;
use crate::mesh::{SurfacePoint, TriMesh};
use crate::render::canvas::{Canvas, rgb, to_rgb8};
use crate::render::colormap::{ColorScale, Colormap};
use crate::render::font::{draw_text, format_number, text_height, text_width};
use crate::render::plot::{PlotPanel, Series, line_plot};
use crate::render::sheet::contact_sheet;
use crate::render::surface::checker_render;

/// What the pictures read of a match: the surfaces as matched and φ.
pub(crate) struct MatchView<'a> {
    pub a: &'a MatchSurface,
    pub b: &'a MatchSurface,
    pub deformation: &'a Deformation,
    pub alignment: &'a AlignmentReport,
    pub levels: &'a [LevelLog],
}

impl MatchView<'_> {
    fn map_domain(&self, xi: [f64; 2]) -> [f64; 2] {
        self.deformation.apply(xi)
    }

    fn carried_features(&self, place: impl Fn([f64; 2]) -> [f64; 2]) -> Vec<CarriedFeature> {
        carried_features(self.a, self.b, place)
    }
}

/// Every picture of a match, with its file name (`features.png` only with paired
/// features).
pub(crate) fn all(p: &Pictures, solved: &Solved) -> Vec<(&'static str, RgbImage)> {
    let view = MatchView {
        a: &p.a,
        b: &p.b,
        deformation: &solved.deformation,
        alignment: &solved.alignment,
        levels: &solved.levels,
    };
    let placed = a_on_b(
        &p.mesh_a,
        &p.mesh_b,
        (&p.a, &p.b, p.scale_b),
        solved,
        &p.points,
    );
    let mut drawn = vec![
        (
            "checker_carried.png",
            checker_carried(&p.mesh_a, &placed, &view, &p.points, 700),
        ),
        ("deformed_grid.png", deformed_grid(&view, 800)),
        ("energy.png", energy_staircase(&view, (900, 500))),
    ];
    if let Some(img) = features_carried(&view, 700) {
        drawn.push(("features.png", img));
    }
    drawn
}

/// Side by side: A with a checkerboard of its parameter domain, and the same
/// checkerboard on A's triangles placed at their matched points of B (`placed`, from
/// `a_on_b`). Only triangles with three matched vertices are drawn,
/// in both panels, so the squares agree.
fn checker_carried(
    mesh_a: &TriMesh,
    placed: &TriMesh,
    matched: &MatchView,
    correspondence: &[Option<SurfacePoint>],
    tile: u32,
) -> RgbImage {
    let kept: Vec<[u32; 3]> = mesh_a
        .triangles
        .iter()
        .filter(|t| t.iter().all(|&v| correspondence[v as usize].is_some()))
        .copied()
        .collect();
    let corners: Vec<[[f64; 2]; 3]> = kept
        .iter()
        .map(|t| t.map(|v| matched.a.vertex_domain_position(v as usize)))
        .collect();
    let a = checker_render(&mesh_a.positions, &kept, &corners, 16, "", (tile, tile));
    let b = checker_render(&placed.positions, &kept, &corners, 16, "", (tile, tile));
    contact_sheet(
        &[
            ("A, ITS CHECKERBOARD".to_string(), a),
            ("CARRIED ONTO B".to_string(), b),
        ],
        2,
        tile,
    )
}

/// A square part of ω shown on a picture: lower-left corner `origin`, side `size`; y up,
/// as in every grid picture ([`crate::render::grid_image`]: grid row 0 at the bottom).
#[derive(Clone, Copy, Debug, PartialEq)]
struct View {
    origin: [f64; 2],
    size: f64,
}

impl View {
    /// All of ω.
    const WHOLE: View = View {
        origin: [0.0, 0.0],
        size: 1.0,
    };

    /// The square around `points` with a margin of a sixth of their extent on every
    /// side (at least 0.04 of ω across, so that a single landmark is not blown up).
    fn around(points: impl Iterator<Item = [f64; 2]>) -> View {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points.filter(|p| p[0].is_finite() && p[1].is_finite()) {
            for c in 0..2 {
                lo[c] = lo[c].min(p[c]);
                hi[c] = hi[c].max(p[c]);
            }
        }
        if !(lo[0] <= hi[0] && lo[1] <= hi[1]) {
            return View::WHOLE;
        }
        let size = ((hi[0] - lo[0]).max(hi[1] - lo[1]) * (1.0 + 2.0 / 6.0)).max(0.04);
        let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        View {
            origin: [centre[0] - 0.5 * size, centre[1] - 0.5 * size],
            size,
        }
    }

    /// The pixel of the point `p` of ω on a canvas `w` pixels wide showing this view.
    fn pixel(&self, p: [f64; 2], w: f64) -> [f64; 2] {
        [
            (p[0] - self.origin[0]) / self.size * w,
            (1.0 - (p[1] - self.origin[1]) / self.size) * w,
        ]
    }
}

/// B's mean-curvature image (grey outside B's surface) on a `pixels`-wide square
/// canvas showing `view` of ω; returns the canvas, its width and the colour scale.
fn curvature_canvas(matched: &MatchView, pixels: u32, view: View) -> (Canvas, f64, ColorScale) {
    let b = &matched.b.images;
    let n = b.size;
    let h = b.mean_curvature_extended.as_slice();
    let inside: Vec<f64> = (0..n * n)
        .filter(|&k| b.raster.is_inside(k))
        .map(|k| h[k])
        .collect();
    let scale = ColorScale::symmetric(&inside, 0.98);
    let background = crate::render::grid_image(n, n, |k| {
        if b.raster.is_inside(k) {
            to_rgb8(scale.color(h[k]))
        } else {
            [200, 200, 200]
        }
    });
    let pixels = pixels.max(64);
    let w = pixels as f64;
    // Past ω the same grey as outside B's surface.
    let mut canvas = Canvas::new(pixels, pixels, 2, rgb(200, 200, 200));
    // The image's top-left corner is the point (0, 1) of ω.
    let corner = view.pixel([0.0, 1.0], w);
    canvas.draw_image(
        corner[0],
        corner[1],
        w / view.size,
        w / view.size,
        &background,
    );
    (canvas, w, scale)
}

/// A sample drawn in a legend: a line of a colour and width (a pale one on a white
/// halo, as B's features are drawn), or a square marker.
#[derive(Clone, Copy)]
enum Key {
    Line([f32; 3], f64),
    Halo([f32; 3], f64),
    Square([f32; 3]),
}

/// `picture` with a legend band under it: B's mean-curvature colour bar (blue–white–red
/// over `±r`, values beyond it in the end colours), the grey of ω outside B's surface,
/// and the `keys` of what is drawn over them.
fn with_legend(picture: RgbImage, scale: &ColorScale, keys: &[(Key, &str)]) -> RgbImage {
    let w = picture.width();
    let font = if w >= 1000 { 2 } else { 1 };
    let th = text_height(font) as f64;
    let row = th + 10.0;
    let rows = 2 + keys.len();
    let band = (rows as f64 * row + 12.0) as u32;
    let mut canvas = Canvas::new(w, picture.height() + band, 2, [1.0; 3]);
    canvas.draw_image(0.0, 0.0, w as f64, picture.height() as f64, &picture);
    let (x0, mut y) = (12.0, picture.height() as f64 + 8.0);
    let bar_w = 160.0 * font as f64;
    let mut texts: Vec<(f64, f64, String)> = vec![];
    // Row 1: the colour bar, its ends and its middle.
    for i in 0..128 {
        let t = (i as f64 + 0.5) / 128.0;
        let x = x0 + bar_w * i as f64 / 128.0;
        canvas.fill_rect(
            x,
            y,
            x + bar_w / 128.0 + 0.3,
            y + th,
            Colormap::BlueWhiteRed.at(t),
        );
    }
    let ends = format!(
        "{} .. 0 .. {}: B'S MEAN CURVATURE (CLIPPED BEYOND)",
        format_number(scale.lo),
        format_number(scale.hi)
    );
    texts.push((x0 + bar_w + 10.0, y, ends));
    y += row;
    // Row 2: outside B.
    canvas.fill_rect(x0, y, x0 + 3.0 * th, y + th, rgb(200, 200, 200));
    texts.push((x0 + 3.0 * th + 10.0, y, "OUTSIDE B'S SURFACE".into()));
    for (key, text) in keys {
        y += row;
        let mid = y + 0.5 * th;
        let (a, b) = ([x0, mid], [x0 + 3.0 * th, mid]);
        match *key {
            Key::Line(c, width) => canvas.line(a, b, width, c),
            Key::Halo(c, width) => {
                canvas.line(a, b, width + 2.5, rgb(255, 255, 255));
                canvas.line(a, b, width, c);
            }
            Key::Square(c) => canvas.marker([x0 + 1.5 * th, mid], 0.5 * th, c),
        }
        texts.push((x0 + 3.0 * th + 10.0, y, text.to_string()));
    }
    let mut img = canvas.into_image();
    for (x, y, text) in texts {
        let fits = x as u32 + text_width(&text, font) <= w;
        let shown = if fits {
            text
        } else {
            text.chars()
                .take(((w as f64 - x) / (6.0 * font as f64)) as usize)
                .collect()
        };
        draw_text(&mut img, x as i64, y as i64, &shown, font, [20, 20, 20]);
    }
    img
}

/// φ's grid lines (every `n/32`-th node line, where A's surface is) drawn in ω_B over
/// B's mean-curvature image (grey outside B's surface), y up.
fn deformed_grid(matched: &MatchView, pixels: u32) -> RgbImage {
    let (mut canvas, w, scale) = curvature_canvas(matched, pixels, View::WHOLE);
    let phi = matched.deformation;
    let m = phi.size;
    let step = ((m - 1) / 32).max(1);
    let inside_a = |i: usize, j: usize| {
        // Node (i, j) of φ's grid, looked up in A's mask at the same domain point.
        let na = matched.a.images.size;
        let (ia, ja) = (i * (na - 1) / (m - 1), j * (na - 1) / (m - 1));
        matched.a.images.raster.is_inside(ja * na + ia)
    };
    let to_px = |p: [f64; 2]| View::WHOLE.pixel(p, w);
    let line = rgb(20, 20, 20);
    for fixed in (0..m).step_by(step) {
        for along in 0..m - 1 {
            for (i0, j0, i1, j1) in [
                (fixed, along, fixed, along + 1),
                (along, fixed, along + 1, fixed),
            ] {
                if inside_a(i0, j0) && inside_a(i1, j1) {
                    let p = to_px(phi.at(j0 * m + i0));
                    let q = to_px(phi.at(j1 * m + i1));
                    canvas.line(p, q, 1.2, line);
                }
            }
        }
    }
    let text =
        format!("THE DEFORMATION'S GRID LINES (EVERY {step}TH OF {m}) OVER A, IN B'S DOMAIN");
    with_legend(
        canvas.into_image(),
        &scale,
        &[(Key::Line(line, 1.2), &text)],
    )
}

/// Colours of the paired features, in turn (dark and saturated: they must stand out on
/// the red–white–blue curvature image).
const FEATURE_COLORS: [[u8; 3]; 12] = [
    [0, 150, 40],
    [20, 20, 20],
    [240, 130, 0],
    [130, 0, 170],
    [0, 170, 190],
    [200, 180, 0],
    [120, 70, 20],
    [220, 0, 200],
    [0, 100, 100],
    [150, 220, 0],
    [20, 30, 120],
    [255, 120, 180],
];

/// The paired features before and after the solve, side by side over B's
/// mean-curvature image in ω_B: B's curves thick and pale (on a white halo), A's carried
/// into ω_B thin and full in the same colour — on the left by the plane similarity φ started from
/// ([`super::AlignmentReport::start`]), on the right by φ. Landmarks (one-vertex
/// features) are squares. Where the solve did its work, the thin curves lie on the
/// thick ones on the right (`feature_fits` gives the distances).
/// `None` without features.
fn features_carried(matched: &MatchView, tile: u32) -> Option<RgbImage> {
    if matched.a.feature_curves.is_empty() {
        return None;
    }
    let start = matched.alignment.start();
    let before = matched.carried_features(|xi| start.apply(xi));
    let after = matched.carried_features(|xi| matched.map_domain(xi));
    // Both panels show the same part of ω: around every curve, in both placements.
    let view = View::around(
        before
            .iter()
            .chain(&after)
            .flat_map(|f| f.a.iter().chain(&f.b).copied()),
    );
    let mut scale = None;
    let mut panel = |features: &[CarriedFeature]| {
        let (mut canvas, w, s) = curvature_canvas(matched, tile, view);
        scale = Some(s);
        let px = |p: [f64; 2]| view.pixel(p, w);
        let pale = |c: [u8; 3]| {
            let [r, g, b] = c.map(|x| (x as u16 + 2 * 255) / 3);
            rgb(r as u8, g as u8, b as u8)
        };
        for (pass, (thick, mark)) in [(4.5, 7.0), (1.6, 3.5)].into_iter().enumerate() {
            for (f, feature) in features.iter().enumerate() {
                let c = FEATURE_COLORS[f % FEATURE_COLORS.len()];
                let (points, color) = if pass == 0 {
                    (&feature.b, pale(c))
                } else {
                    (&feature.a, rgb(c[0], c[1], c[2]))
                };
                let mut line: Vec<[f64; 2]> = points.iter().map(|&p| px(p)).collect();
                // B's pale curves on a white halo, so that they stand apart from the
                // grey outside B's surface and from the curvature's colours.
                let halo = (pass == 0).then_some(2.5);
                if line.len() == 1 {
                    if let Some(h) = halo {
                        canvas.marker(line[0], mark + 0.5 * h, rgb(255, 255, 255));
                    }
                    canvas.marker(line[0], mark, color);
                    continue;
                }
                if feature.closed {
                    line.push(line[0]);
                }
                if let Some(h) = halo {
                    canvas.polyline(&line, thick + h, rgb(255, 255, 255));
                }
                canvas.polyline(&line, thick, color);
            }
        }
        canvas.into_image()
    };
    let sheet = contact_sheet(
        &[
            ("FEATURES AT THE START".to_string(), panel(&before)),
            ("AFTER THE SOLVE".to_string(), panel(&after)),
        ],
        2,
        tile,
    );
    let c = FEATURE_COLORS[0];
    let (full, pale) = (rgb(c[0], c[1], c[2]), {
        let [r, g, b] = c.map(|x| ((x as u16 + 2 * 255) / 3) as u8);
        rgb(r, g, b)
    });
    Some(with_legend(
        sheet,
        &scale.expect("two panels drawn"),
        &[
            (
                Key::Halo(pale, 4.5),
                "B'S FEATURE: THICK AND PALE (ONE COLOUR PER FEATURE)",
            ),
            (
                Key::Line(full, 1.6),
                "A'S SAME FEATURE CARRIED INTO B'S DOMAIN: THIN, FULL COLOUR",
            ),
            (
                Key::Square(full),
                "LANDMARKS (ONE VERTEX): SQUARES, B'S LARGE AND PALE",
            ),
        ],
    ))
}

/// Total energy after every iteration of every level, one curve, log axis; the first
/// iteration of each level marked (the jumps are the changes of ε and resolution).
fn energy_staircase(matched: &MatchView, size: (u32, u32)) -> RgbImage {
    let mut values = vec![];
    let mut starts = vec![];
    for l in matched.levels {
        starts.push(values.len());
        values.extend_from_slice(&l.history);
    }
    let mut series = Series::new("TOTAL", &values, rgb(200, 60, 30));
    series.marks = Some(&starts);
    line_plot(
        "MATCHING ENERGY OVER ALL LEVELS (MARKS: NEW LEVEL)",
        "ITERATION",
        &[PlotPanel {
            title: "ENERGY".into(),
            log_y: true,
            series: vec![series],
        }],
        size,
    )
}

#[cfg(test)]
mod tests {
    use super::View;

    /// A point of ω drawn on a canvas lands on the pixel that shows its grid node in the
    /// background, whose grid row 0 is at the bottom ([`crate::render::grid_image`]). The
    /// deformed grid was drawn upside down against B's image before this was checked.
    #[test]
    fn a_point_of_omega_lands_on_its_node_in_the_background() {
        let n = 9;
        for (row, column) in [(0, 0), (2, 7), (8, 3), (5, 5)] {
            let image = crate::render::grid_image(n, n, |k| {
                if k == row * n + column {
                    [255, 0, 0]
                } else {
                    [0, 0, 0]
                }
            });
            let h = 1.0 / (n - 1) as f64;
            let p = View::WHOLE.pixel([column as f64 * h, row as f64 * h], n as f64);
            let at = p.map(|c| (c.floor() as u32).min(n as u32 - 1));
            assert_eq!(
                image.get_pixel(at[0], at[1]).0,
                [255, 0, 0],
                "node ({row}, {column}) drawn at {p:?}"
            );
        }
        // A zoomed view: its lower-left corner at the bottom-left pixel, the upper-right
        // at the top-right, with a margin of a sixth of the points' extent.
        let view = View::around([[0.2, 0.3], [0.5, 0.4]].into_iter());
        let w = 600.0;
        let lo = view.pixel([0.2, 0.3], w);
        let hi = view.pixel([0.5, 0.4], w);
        assert!((lo[0] - w / 8.0).abs() < 1e-9 && (hi[0] - 7.0 * w / 8.0).abs() < 1e-9);
        assert!(
            lo[1] > hi[1] && (lo[1] + hi[1] - w).abs() < 1e-9,
            "{lo:?} {hi:?}"
        );
    }
}
