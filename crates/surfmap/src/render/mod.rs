//! PNG pictures: the one picture stack of the crate. The building blocks are a
//! supersampled [`Canvas`] (triangles, lines, polylines, images), colour maps with
//! colour bars ([`colormap`]), a bitmap [`font`], grids of values as pictures
//! ([`grid_image`](mod@grid_image)), line plots ([`plot`]) and [`save_png`]. On them sit the pictures of
//! maps: (a) the UV layout coloured by a measure, (b) the surface with a checkerboard
//! through its UVs, (c) convergence plots, (d) the α trade-off sheet (thesis Fig. 3.1,
//! 4.1, 4.4); geometry-image pictures (thesis Fig. 3.6) are drawn through them by
//! [`crate::raster::picture`]. Every picture is a function returning an
//! [`image::RgbImage`]; [`save_png`] writes one atomically.

pub mod canvas;
pub mod colormap;
pub mod font;
pub mod grid_image;
pub mod plot;
pub mod sheet;
pub mod surface;
pub mod tradeoff;
pub mod uv_layout;

pub use canvas::{Canvas, rgb};
pub use colormap::{ColorScale, Colormap, color_bar};
pub use grid_image::{NO_DATA, grid_image, image_with_colormap};
pub use image::RgbImage;
pub use plot::{PlotPanel, Series, convergence_plot, convergence_plot_labeled, line_plot};
pub use sheet::contact_sheet;
pub use surface::{View, automatic_view, checker_render, surface_render};
pub use tradeoff::{TradeoffPanel, tradeoff_sheet};
pub use uv_layout::uv_layout;

use std::path::Path;

/// Writes `img` as a PNG at `path` through [`crate::fsutil::write_atomically`]
/// (temporary file beside it, then rename: a reader never sees half a file).
pub fn save_png(path: &Path, img: &image::RgbImage) -> std::io::Result<()> {
    crate::fsutil::write_atomically(path, |w| {
        let mut buf = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut buf), image::ImageFormat::Png)
            .map_err(std::io::Error::other)?;
        w.write_all(&buf)
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use image::RgbImage;

    /// A disc of `n` rings triangulated as a fan of rings, lifted onto the tilted plane
    /// z = 0.5 x; UVs are the planar coordinates (per corner).
    pub type Map = (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<[[f64; 2]; 3]>);

    pub fn disc_map(n: usize) -> Map {
        let mut p2 = vec![[0.0, 0.0]];
        let seg = 6;
        for r in 1..=n {
            let m = seg * r;
            for k in 0..m {
                let th = std::f64::consts::TAU * k as f64 / m as f64;
                let rad = r as f64 / n as f64;
                p2.push([rad * th.cos(), rad * th.sin()]);
            }
        }
        let ring_start = |r: usize| if r == 0 { 0 } else { 1 + seg * r * (r - 1) / 2 };
        let mut tris = Vec::new();
        for r in 1..=n {
            let (m_in, m_out) = (if r == 1 { 1 } else { seg * (r - 1) }, seg * r);
            let (s_in, s_out) = (ring_start(r - 1), ring_start(r));
            // Walk both rings by angle.
            let (mut i, mut o) = (0usize, 0usize);
            while i < m_in.max(1) && (o < m_out || i < m_in) && tris.len() < 100_000 {
                let ia = (i as f64 + 1.0) / m_in as f64;
                let oa = (o as f64 + 1.0) / m_out as f64;
                let inner = |k: usize| (s_in + if m_in == 1 { 0 } else { k % m_in }) as u32;
                let outer = |k: usize| (s_out + k % m_out) as u32;
                if o < m_out && (oa <= ia || m_in == 1) {
                    tris.push([inner(i), outer(o), outer(o + 1)]);
                    o += 1;
                } else {
                    tris.push([inner(i), outer(o), inner(i + 1)]);
                    i += 1;
                }
                if m_in == 1 && o == m_out {
                    break;
                }
            }
        }
        let pos: Vec<[f64; 3]> = p2.iter().map(|q| [q[0], q[1], 0.5 * q[0]]).collect();
        let uv: Vec<[[f64; 2]; 3]> = tris
            .iter()
            .map(|t: &[u32; 3]| t.map(|v| p2[v as usize]))
            .collect();
        (pos, tris, uv)
    }

    /// Not blank: several distinct colours and a non-trivial spread of brightness.
    pub fn assert_not_blank(img: &RgbImage) {
        let mut colors: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
        colors.sort_unstable();
        colors.dedup();
        assert!(colors.len() > 20, "only {} distinct colours", colors.len());
        let lum: Vec<f64> = img
            .pixels()
            .map(|p| p.0.iter().map(|&c| c as f64).sum::<f64>() / 3.0)
            .collect();
        let mean = lum.iter().sum::<f64>() / lum.len() as f64;
        let var = lum.iter().map(|l| (l - mean) * (l - mean)).sum::<f64>() / lum.len() as f64;
        assert!(var.sqrt() > 5.0, "brightness spread {}", var.sqrt());
    }

    #[test]
    fn disc_map_is_a_valid_flip_free_disc() {
        let (pos, tris, uv) = disc_map(5);
        assert!(tris.iter().flatten().all(|&v| (v as usize) < pos.len()));
        for t in &uv {
            assert!(crate::measure::jacobian::signed_uv_area(*t) > 0.0);
        }
        let area: f64 = uv
            .iter()
            .map(|t| crate::measure::jacobian::signed_uv_area(*t))
            .sum();
        // Inscribed polygon of the unit disc: a bit below π.
        assert!(area > 3.0 && area < std::f64::consts::PI, "{area}");
    }

    /// Writes every picture of a cap (disc lifted onto a sphere, UVs = projection) to
    /// `$TMPDIR/surfmap-pictures/` for looking at: `cargo test -p surfmap
    /// write_sample_pictures -- --ignored`.
    #[test]
    #[ignore]
    fn write_sample_pictures() {
        use crate::measure::{Measure, per_triangle_measure};
        let (flat, tris, uv) = disc_map(24);
        let pos: Vec<[f64; 3]> = flat
            .iter()
            .map(|p| {
                [
                    p[0],
                    p[1],
                    0.9 * (1.0 - (p[0] * p[0] + p[1] * p[1]) * 0.8).max(0.0).sqrt(),
                ]
            })
            .collect();
        let dir = std::env::temp_dir().join("surfmap-pictures");
        std::fs::create_dir_all(&dir).unwrap();
        let vals = per_triangle_measure(&pos, &tris, &uv, Measure::Area).unwrap();
        let a = super::uv_layout(
            &tris,
            &uv,
            Some((&vals, Measure::Area.label())),
            "CAP: AREA DISTORTION",
            (700, 600),
        );
        super::save_png(&dir.join("uv_layout.png"), &a).unwrap();
        let b = super::checker_render(&pos, &tris, &uv, 10, "CAP", (600, 500));
        super::save_png(&dir.join("checker.png"), &b).unwrap();
        let mut hist = Vec::new();
        let mut g: f64 = 30.0;
        for i in 0..14 {
            hist.push((4.0 + g * 0.2, g));
            g = if i < 7 {
                g * 0.45
            } else {
                (g * g * 0.3).max(1e-13)
            };
        }
        let c = super::convergence_plot(&hist, (640, 480));
        super::save_png(&dir.join("convergence.png"), &c).unwrap();
        let mut vuv = vec![[0.0; 2]; pos.len()];
        for (t, cuv) in tris.iter().zip(&uv) {
            for k in 0..3 {
                vuv[t[k] as usize] = cuv[k];
            }
        }
        let radial = |s: f64| -> Vec<[f64; 2]> {
            vuv.iter()
                .map(|p| {
                    let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
                    let f = r.powf(s - 1.0).min(1e6);
                    [p[0] * f, p[1] * f]
                })
                .collect()
        };
        let (u1, u2) = (radial(0.8), radial(1.3));
        let panels = [
            super::TradeoffPanel {
                title: "α = (0.1, 0.1, 0.8)".into(),
                positions: &pos,
                triangles: &tris,
                uvs: &vuv,
            },
            super::TradeoffPanel {
                title: "α = (0.4, 0.4, 0.2)".into(),
                positions: &pos,
                triangles: &tris,
                uvs: &u1,
            },
            super::TradeoffPanel {
                title: "α = (0.1, 0.8, 0.1)".into(),
                positions: &pos,
                triangles: &tris,
                uvs: &u2,
            },
        ];
        let d = super::tradeoff_sheet(&panels, (1200, 900));
        super::save_png(&dir.join("tradeoff.png"), &d).unwrap();
        // A multiscale-like staircase: energy per iteration over three levels, markers
        // at the level starts, and the grid size as steps on a second panel.
        let energy: Vec<f64> = (0..30)
            .map(|i| {
                let level = i / 10;
                10f64.powi(2 - level) * (1.0 + 0.5 * (-(i % 10) as f64).exp())
            })
            .collect();
        let size: Vec<f64> = (0..30).map(|i| (17 << (i / 10)) as f64).collect();
        let starts = [0, 10, 20];
        let staircase = super::line_plot(
            "MULTISCALE",
            "ITERATION",
            &[
                super::PlotPanel {
                    title: "ENERGY".into(),
                    log_y: true,
                    series: vec![super::Series {
                        marks: Some(&starts),
                        ..super::Series::new("E", &energy, super::rgb(30, 90, 200))
                    }],
                },
                super::PlotPanel {
                    title: "GRID NODES PER SIDE".into(),
                    log_y: false,
                    series: vec![super::Series {
                        marks: Some(&starts),
                        steps: true,
                        ..super::Series::new("N", &size, super::rgb(210, 60, 30))
                    }],
                },
            ],
            (700, 600),
        );
        super::save_png(&dir.join("staircase.png"), &staircase).unwrap();
        // A swirl φ drawn as a deformed grid over a colour-mapped image.
        let n = 65;
        let h: Vec<f64> = (0..n * n)
            .map(|k| {
                let (x, y) = ((k % n) as f64 / 64.0, (k / n) as f64 / 64.0);
                (6.0 * x).sin() * (4.0 * y).cos()
            })
            .collect();
        let img = super::image_with_colormap(&h, n, &super::ColorScale::symmetric(&h, 0.98));
        let mut c = super::Canvas::new(500, 500, 3, [1.0; 3]);
        let to_px = |p: [f64; 2]| [20.0 + 460.0 * p[0], 480.0 - 460.0 * p[1]];
        let d = 0.5 / 64.0;
        let (a, b) = (to_px([-d, 1.0 + d]), to_px([1.0 + d, -d]));
        c.draw_image(a[0], a[1], b[0] - a[0], b[1] - a[1], &img);
        let phi = |p: [f64; 2]| {
            let (dx, dy) = (p[0] - 0.5, p[1] - 0.5);
            let t = 0.8 * (1.0 - 2.0 * (dx * dx + dy * dy).sqrt()).max(0.0);
            to_px([
                0.5 + t.cos() * dx - t.sin() * dy,
                0.5 + t.sin() * dx + t.cos() * dy,
            ])
        };
        for k in 0..=16 {
            let t = k as f64 / 16.0;
            let v: Vec<[f64; 2]> = (0..=64).map(|i| phi([t, i as f64 / 64.0])).collect();
            let u: Vec<[f64; 2]> = (0..=64).map(|i| phi([i as f64 / 64.0, t])).collect();
            c.polyline(&v, 1.2, super::rgb(20, 20, 20));
            c.polyline(&u, 1.2, super::rgb(20, 20, 20));
        }
        super::save_png(&dir.join("deformed_grid.png"), &c.into_image()).unwrap();
        println!("wrote {}", dir.display());
    }

    /// A deformed grid drawn over a colour-mapped image, as the matcher shows a
    /// deformation φ over a geometry image: image pixels and grid lines land where the
    /// documented coordinate conventions put them.
    #[test]
    fn deformed_grid_over_a_colour_mapped_image() {
        use super::{Canvas, ColorScale, image_with_colormap, rgb};
        // h(ξ) = ξy − ½ on a 17 × 17 grid: blue at the bottom, red at the top.
        let n = 17;
        let h: Vec<f64> = (0..n * n).map(|k| (k / n) as f64 / 16.0 - 0.5).collect();
        let img = image_with_colormap(&h, n, &ColorScale::symmetric(&h, 1.0));
        // ω = [0,1]² onto the square [15, 185]², y up; the image covers ω grown by half
        // a cell so node j sits at ξ = j/16.
        let to_px = |p: [f64; 2]| [15.0 + 170.0 * p[0], 185.0 - 170.0 * p[1]];
        let d = 0.5 / 16.0;
        let (a, b) = (to_px([-d, 1.0 + d]), to_px([1.0 + d, -d]));
        let mut c = Canvas::new(200, 200, 3, [1.0; 3]);
        c.draw_image(a[0], a[1], b[0] - a[0], b[1] - a[1], &img);
        // φ(ξ) = ξ + (0.1, 0): the grid lines ξx = k/4 move right by 0.1.
        let phi = |p: [f64; 2]| to_px([p[0] + 0.1, p[1]]);
        let black = rgb(0, 0, 0);
        for k in 0..=4 {
            let t = k as f64 / 4.0;
            let vertical: Vec<[f64; 2]> = (0..=8).map(|i| phi([t, i as f64 / 8.0])).collect();
            let horizontal: Vec<[f64; 2]> = (0..=8).map(|i| phi([i as f64 / 8.0, t])).collect();
            c.polyline(&vertical, 2.0, black);
            c.polyline(&horizontal, 2.0, black);
        }
        let out = c.into_image();
        let at = |x: f64, y: f64| {
            let p = to_px([x, y]);
            out.get_pixel(p[0] as u32, p[1] as u32).0
        };
        // Lines where φ puts them, not where the undeformed grid was.
        assert_eq!(at(0.6, 0.4), [0, 0, 0]);
        assert_eq!(at(0.35, 0.9), [0, 0, 0]);
        assert_eq!(at(0.2, 0.5), [0, 0, 0]);
        assert_ne!(at(0.5, 0.4), [0, 0, 0]);
        // The image between the lines: blue low, red high, near-white at ξy = ½ ± 0.03.
        let (lo, hi, mid) = (at(0.2, 0.1), at(0.2, 0.9), at(0.2, 0.47));
        assert!(lo[2] > 150 && lo[0] < 120, "bottom {lo:?}");
        assert!(hi[0] > 150 && hi[2] < 120, "top {hi:?}");
        assert!(mid.iter().all(|&v| v > 200), "middle {mid:?}");
        // Outside ω (and its half-cell margin): background.
        assert_eq!(out.get_pixel(3, 3).0, [255; 3]);
    }

    #[test]
    fn saved_png_decodes_to_the_same_pixels() {
        let (pos, tris, uv) = disc_map(6);
        let img = super::checker_render(&pos, &tris, &uv, 6, "T", (96, 80));
        let dir = std::env::temp_dir().join(format!("surfmap-render-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("x.png");
        super::save_png(&path, &img).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let back = image::load_from_memory(&bytes).unwrap().to_rgb8();
        assert_eq!(back, img);
        super::save_png(&path, &img).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), bytes, "same bytes twice");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
