//! Pictures of a match: A's checkerboard carried onto B (thesis fig. 4.9), the
//! deformed grid over B's curvature image, and the energy staircase over all levels
//! (fig. 4.7).

use image::RgbImage;

use super::solve::SurfaceMatch;
use crate::mesh::{SurfacePoint, TriMesh};
use crate::render::canvas::{Canvas, rgb, to_rgb8};
use crate::render::colormap::ColorScale;
use crate::render::plot::{PlotPanel, Series, line_plot};
use crate::render::sheet::contact_sheet;
use crate::render::surface::checker_render;

/// Side by side: A with a checkerboard of its parameter domain, and the same
/// checkerboard on A's triangles placed at their matched points of B (`placed`, from
/// [`super::output::a_on_b`]). Only triangles with three matched vertices are drawn,
/// in both panels, so the squares agree.
pub fn checker_carried(
    mesh_a: &TriMesh,
    placed: &TriMesh,
    matched: &SurfaceMatch,
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

/// φ's grid lines (every `n/32`-th node line, where A's surface is) drawn in ω_B over
/// B's mean-curvature image (grey outside B's surface). Row 0 of the picture is y = 0.
pub fn deformed_grid(matched: &SurfaceMatch, pixels: u32) -> RgbImage {
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
    let w = pixels.max(64) as f64;
    let mut canvas = Canvas::new(pixels.max(64), pixels.max(64), 2, [1.0; 3]);
    canvas.draw_image(0.0, 0.0, w, w, &background);
    let phi = &matched.deformation;
    let m = phi.size;
    let step = ((m - 1) / 32).max(1);
    let inside_a = |i: usize, j: usize| {
        // Node (i, j) of φ's grid, looked up in A's mask at the same domain point.
        let na = matched.a.images.size;
        let (ia, ja) = (i * (na - 1) / (m - 1), j * (na - 1) / (m - 1));
        matched.a.images.raster.is_inside(ja * na + ia)
    };
    let to_px = |p: [f64; 2]| [p[0] * w, p[1] * w];
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
    canvas.into_image()
}

/// Total energy after every iteration of every level, one curve, log axis; the first
/// iteration of each level marked (the jumps are the changes of ε and resolution).
pub fn energy_staircase(matched: &SurfaceMatch, size: (u32, u32)) -> RgbImage {
    let mut values = vec![];
    let mut starts = vec![];
    for l in &matched.levels {
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
