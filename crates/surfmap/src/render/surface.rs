//! Picture (b): the surface in 3D with a checkerboard through its UVs (thesis
//! Fig. 3.1 middle, Fig. 4.4 top), shaded, seen from an automatic view. A small
//! software rasterizer: orthographic projection, z-buffer, smooth vertex normals,
//! supersampling.
//!
//! **View**: from the surface's principal axes `e1, e2, e3` (eigenvectors of its second
//! moment `∫ (x − c)(x − c)ᵀ dA` about its centroid `c`, spreads `σ1 ≤ σ2 ≤ σ3`). A
//! patch (`σ1 < σ2 / 2`) is seen along `e1`, its depth. A bulky surface (a head, a
//! closed shape) is seen along whichever of `e1`, `e2` has the larger skewness: a head
//! is mirror-symmetric left to right but not front to back, so it is seen from the
//! front, never from above the skull (as the mean normal of a scan open at the neck
//! would have it) nor in profile. The side: the one the normals face when their sum
//! `Σ_T n_T` along the axis is at least 15 % of `Σ_T |n_T|`, else the side of the long
//! tail of the spread (a face's nose). **Up** is the world axis (Y, then Z, then X) most
//! perpendicular to the view direction.

use image::RgbImage;

use super::canvas::{Canvas, rgb};
use super::font::{draw_text, text_height};
use super::uv_layout::Rect;
use crate::measure::jacobian::{cross3, dot3, norm3, sub3};

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let n = norm3(v);
    if n > 0.0 {
        v.map(|x| x / n)
    } else {
        [0.0, 0.0, 1.0]
    }
}

fn valid_triangle(positions: &[[f64; 3]], t: &[u32; 3]) -> bool {
    t.iter().all(|&v| {
        (v as usize) < positions.len() && positions[v as usize].iter().all(|x| x.is_finite())
    })
}

/// Eigenvalues and unit eigenvectors of a symmetric 3×3 matrix (cyclic Jacobi), the
/// smallest eigenvalue first.
#[allow(clippy::needless_range_loop)]
fn eigen_sorted(mut a: [[f64; 3]; 3]) -> [(f64, [f64; 3]); 3] {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off < 1e-300 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut order = [0, 1, 2];
    order.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]));
    order.map(|i| (a[i][i], normalize([v[0][i], v[1][i], v[2][i]])))
}

/// Camera basis `(right, up, towards_viewer)` chosen as in the module docs.
pub fn automatic_view(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> [[f64; 3]; 3] {
    let tris: Vec<[[f64; 3]; 3]> = triangles
        .iter()
        .filter(|t| valid_triangle(positions, t))
        .map(|t| t.map(|v| positions[v as usize]))
        .collect();
    // The surface's centroid and second moment ∫ (x − c)(x − c)ᵀ dA (exact per triangle:
    // A/12 · (Σ dᵢdᵢᵀ + (Σ dᵢ)(Σ dᵢ)ᵀ), dᵢ = pᵢ − c), and the sum of the normals.
    let (mut area, mut centroid, mut normal) = (0.0, [0.0; 3], [0.0; 3]);
    for p in &tris {
        let n = cross3(sub3(p[1], p[0]), sub3(p[2], p[0]));
        let a = 0.5 * norm3(n);
        area += a;
        for k in 0..3 {
            centroid[k] += a * (p[0][k] + p[1][k] + p[2][k]) / 3.0;
            normal[k] += n[k];
        }
    }
    let centroid = centroid.map(|c| if area > 0.0 { c / area } else { 0.0 });
    let mut cov = [[0.0; 3]; 3];
    for p in &tris {
        let a = 0.5 * norm3(cross3(sub3(p[1], p[0]), sub3(p[2], p[0])));
        let d = p.map(|q| sub3(q, centroid));
        let s: [f64; 3] = [0, 1, 2].map(|k| d[0][k] + d[1][k] + d[2][k]);
        for i in 0..3 {
            for j in 0..3 {
                let corners: f64 = d.iter().map(|q| q[i] * q[j]).sum();
                cov[i][j] += a / 12.0 * (corners + s[i] * s[j]);
            }
        }
    }
    let d = view_direction(&tris, centroid, eigen_sorted(cov), normal);
    let axes = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]];
    let up0 = axes
        .iter()
        .copied()
        .find(|a| dot3(*a, d).abs() < 0.8)
        .unwrap_or([0.0, 1.0, 0.0]);
    let up_perp = normalize(sub3(up0, d.map(|x| x * dot3(up0, d))));
    let right = normalize(cross3(up_perp, d));
    let up = cross3(d, right);
    [right, up, d]
}

/// The direction towards the viewer (see the module docs), from the principal axes
/// `(λ, e)` of the surface's second moment (smallest first) and its normal sum.
fn view_direction(
    tris: &[[[f64; 3]; 3]],
    centroid: [f64; 3],
    axes: [(f64, [f64; 3]); 3],
    normal: [f64; 3],
) -> [f64; 3] {
    // Area-weighted skewness of the triangle centroids along e: E[x³] / E[x²]^{3/2}.
    let skew = |e: [f64; 3], lambda: f64| {
        let (mut m3, mut area) = (0.0, 0.0);
        for p in tris {
            let a = 0.5 * norm3(cross3(sub3(p[1], p[0]), sub3(p[2], p[0])));
            let c: [f64; 3] = [0, 1, 2].map(|k| (p[0][k] + p[1][k] + p[2][k]) / 3.0);
            m3 += a * dot3(sub3(c, centroid), e).powi(3);
            area += a;
        }
        if area > 0.0 && lambda > 0.0 {
            m3 / area / lambda.powf(1.5)
        } else {
            0.0
        }
    };
    let [(l1, e1), (l2, e2), _] = axes;
    let (s1, s2) = (skew(e1, l1), skew(e2, l2));
    // A patch (half as deep as wide, or less) is seen along its depth; a bulky surface
    // along the more skewed of its two shorter axes: a head is mirror-symmetric left to
    // right, and not front to back.
    let patch = l1 < 0.25 * l2;
    let (e, s) = if patch || s1.abs() >= s2.abs() {
        (e1, s1)
    } else {
        (e2, s2)
    };
    let total: f64 = tris
        .iter()
        .map(|p| norm3(cross3(sub3(p[1], p[0]), sub3(p[2], p[0]))))
        .sum();
    let facing = dot3(normal, e);
    // From the side the normals face when they clearly face one (15 % of their total
    // length), else from the side of the long tail (a face's nose).
    let positive = if facing.abs() >= 0.15 * total {
        facing > 0.0
    } else {
        s >= 0.0
    };
    if positive { e } else { e.map(|x| -x) }
}

/// A fixed orthographic view: camera axes `(right, up, towards_viewer)` and the
/// rectangle `[lo, hi]` of the projected plane it frames. One view for several frames
/// of an animation keeps them comparable.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub axes: [[f64; 3]; 3],
    pub lo: [f64; 2],
    pub hi: [f64; 2],
}

impl View {
    /// The [`automatic_view`] of the first frame, framing the valid triangles of every
    /// frame (each frame one position per vertex, all on `triangles`). `None` when no
    /// triangle is valid.
    pub fn framing(frames: &[&[[f64; 3]]], triangles: &[[u32; 3]]) -> Option<View> {
        Self::framing_tilted(frames, triangles, 0.0)
    }

    /// [`Self::framing`] with the camera tilted by `tilt` radians about its `right`
    /// axis, rising towards the picture's top: the surface is seen obliquely from
    /// above, so heights show in the outline and shading — an upright head (its top
    /// along the view's `up`) from above the forehead, not from under the chin.
    pub fn framing_tilted(
        frames: &[&[[f64; 3]]],
        triangles: &[[u32; 3]],
        tilt: f64,
    ) -> Option<View> {
        let [right, up, d] = automatic_view(frames.first()?, triangles);
        let (s, c) = tilt.sin_cos();
        let axes = [
            right,
            [0, 1, 2].map(|k| c * up[k] - s * d[k]),
            [0, 1, 2].map(|k| c * d[k] + s * up[k]),
        ];
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for positions in frames {
            for tri in triangles.iter().filter(|t| valid_triangle(positions, t)) {
                for &v in tri {
                    let s = [
                        dot3(positions[v as usize], axes[0]),
                        dot3(positions[v as usize], axes[1]),
                    ];
                    lo = [lo[0].min(s[0]), lo[1].min(s[1])];
                    hi = [hi[0].max(s[0]), hi[1].max(s[1])];
                }
            }
        }
        (lo[0] <= hi[0]).then_some(View { axes, lo, hi })
    }
}

/// Draws the shaded, checkered surface into `rect` of the canvas (depth test on).
pub(crate) fn draw_surface(
    canvas: &mut Canvas,
    rect: Rect,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
    checks: u32,
) {
    let [r, u, d] = automatic_view(positions, triangles);
    let ok = valid_triangles(positions, triangles, corner_uvs);
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    let mut uvlo = [f64::INFINITY; 2];
    let mut uvhi = [f64::NEG_INFINITY; 2];
    for (t, tri) in triangles.iter().enumerate().filter(|(t, _)| ok[*t]) {
        let p = tri.map(|v| positions[v as usize]);
        for k in 0..3 {
            let s = [dot3(p[k], r), dot3(p[k], u)];
            lo = [lo[0].min(s[0]), lo[1].min(s[1])];
            hi = [hi[0].max(s[0]), hi[1].max(s[1])];
            let c = corner_uvs[t][k];
            uvlo = [uvlo[0].min(c[0]), uvlo[1].min(c[1])];
            uvhi = [uvhi[0].max(c[0]), uvhi[1].max(c[1])];
        }
    }
    let uv_span = (uvhi[0] - uvlo[0]).max(uvhi[1] - uvlo[1]).max(1e-300);
    let check = checks.max(1) as f64 / uv_span;
    let (light_c, dark_c) = (rgb(245, 240, 230), rgb(215, 95, 35));
    let view = View {
        axes: [r, u, d],
        lo,
        hi,
    };
    draw_shaded(
        canvas,
        rect,
        &view,
        positions,
        triangles,
        corner_uvs,
        &ok,
        &|uv| {
            let cell = ((uv[0] - uvlo[0]) * check).floor() as i64
                + ((uv[1] - uvlo[1]) * check).floor() as i64;
            if cell.rem_euclid(2) == 0 {
                light_c
            } else {
                dark_c
            }
        },
    );
}

fn valid_triangles(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
) -> Vec<bool> {
    triangles
        .iter()
        .zip(corner_uvs)
        .map(|(t, c)| valid_triangle(positions, t) && c.iter().flatten().all(|x| x.is_finite()))
        .collect()
}

/// Draws the triangles marked `ok` seen through `view` into `rect`, coloured by
/// `colour(uv)` at each sample's interpolated UV and Lambert-shaded with smooth vertex
/// normals (area-weighted face normals), depth test on.
#[allow(clippy::too_many_arguments)]
fn draw_shaded(
    canvas: &mut Canvas,
    rect: Rect,
    view: &View,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
    ok: &[bool],
    colour: &dyn Fn([f64; 2]) -> [f32; 3],
) {
    canvas.enable_depth();
    let ([r, u, d], lo, hi) = (view.axes, view.lo, view.hi);
    let mut vn = vec![[0.0f64; 3]; positions.len()];
    for tri in triangles
        .iter()
        .enumerate()
        .filter(|(t, _)| ok[*t])
        .map(|(_, t)| t)
    {
        let p = tri.map(|v| positions[v as usize]);
        let n = cross3(sub3(p[1], p[0]), sub3(p[2], p[0]));
        for k in 0..3 {
            let v = &mut vn[tri[k] as usize];
            *v = [v[0] + n[0], v[1] + n[1], v[2] + n[2]];
        }
    }
    if lo[0].is_nan() || hi[0].is_nan() || lo[0] > hi[0] {
        return;
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-300);
    let s = (rect.w / (hi[0] - lo[0]).max(span * 1e-9))
        .min(rect.h / (hi[1] - lo[1]).max(span * 1e-9))
        * 0.95;
    let ox = rect.x + 0.5 * (rect.w - s * (hi[0] - lo[0]));
    let oy = rect.y + 0.5 * (rect.h + s * (hi[1] - lo[1]));
    let light = normalize([
        d[0] + 0.35 * u[0] + 0.25 * r[0],
        d[1] + 0.35 * u[1] + 0.25 * r[1],
        d[2] + 0.35 * u[2] + 0.25 * r[2],
    ]);
    for (t, tri) in triangles.iter().enumerate().filter(|(t, _)| ok[*t]) {
        let p = tri.map(|v| positions[v as usize]);
        let scr = p.map(|q| [ox + s * (dot3(q, r) - lo[0]), oy - s * (dot3(q, u) - lo[1])]);
        let depth = p.map(|q| dot3(q, d));
        let n = tri.map(|v| normalize(vn[v as usize]));
        let c = corner_uvs[t];
        canvas.fill_triangle(scr, Some(depth), |b| {
            let uv = [
                b[0] * c[0][0] + b[1] * c[1][0] + b[2] * c[2][0],
                b[0] * c[0][1] + b[1] * c[1][1] + b[2] * c[2][1],
            ];
            let base = colour(uv);
            let nn = [0, 1, 2].map(|k| b[0] * n[0][k] + b[1] * n[1][k] + b[2] * n[2][k]);
            let lambert = (dot3(nn, light) / norm3(nn).max(1e-300)).abs();
            let shade = (0.25 + 0.75 * lambert) as f32;
            Some(base.map(|x| x * shade))
        });
    }
}

/// The surface seen through a fixed `view` (see [`View::framing`]), coloured by
/// `colour(uv)` at the UV interpolated from `corner_uvs` (a texture lookup, a
/// checkerboard, …) and shaded, with an optional title, `size = (width, height)`.
/// Triangles with bad indices or non-finite coordinates are skipped.
pub fn surface_render(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
    view: &View,
    colour: &dyn Fn([f64; 2]) -> [f32; 3],
    title: &str,
    size: (u32, u32),
) -> RgbImage {
    titled_picture(title, size, |canvas, rect| {
        if corner_uvs.len() == triangles.len() {
            let ok = valid_triangles(positions, triangles, corner_uvs);
            draw_shaded(
                canvas, rect, view, positions, triangles, corner_uvs, &ok, colour,
            );
        }
    })
}

/// The surface rendered with a checkerboard of `checks` squares across the UV layout's
/// longer side, `size = (width, height)`. Triangles with bad indices or non-finite
/// coordinates are skipped.
pub fn checker_render(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
    checks: u32,
    title: &str,
    size: (u32, u32),
) -> RgbImage {
    titled_picture(title, size, |canvas, rect| {
        if corner_uvs.len() == triangles.len() {
            draw_surface(canvas, rect, positions, triangles, corner_uvs, checks);
        }
    })
}

/// A white `size` picture with `title` on top and `draw` filling the rest (less a 3 %
/// margin), supersampled 3×.
fn titled_picture(title: &str, size: (u32, u32), draw: impl FnOnce(&mut Canvas, Rect)) -> RgbImage {
    let (w, h) = (size.0.clamp(64, 16384), size.1.clamp(64, 16384));
    let font = if w.min(h) >= 600 { 2 } else { 1 };
    let top = if title.is_empty() {
        0.0
    } else {
        text_height(font) as f64 + 12.0
    };
    let mut canvas = Canvas::new(w, h, 3, [1.0; 3]);
    let m = 0.03 * w.min(h) as f64;
    let rect = Rect {
        x: m,
        y: top + m,
        w: w as f64 - 2.0 * m,
        h: h as f64 - top - 2.0 * m,
    };
    draw(&mut canvas, rect);
    let mut img = canvas.into_image();
    draw_text(&mut img, 8, 6, title, font, [20, 20, 20]);
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::tests::{assert_not_blank, disc_map};

    #[test]
    fn view_of_a_tilted_plane_looks_along_its_normal() {
        let (pos, tris, _) = disc_map(6);
        let [r, u, d] = automatic_view(&pos, &tris);
        // disc_map lifts the disc into the plane z = 0.5 x (normal ∝ (−0.5, 0, 1)).
        let n = normalize([-0.5, 0.0, 1.0]);
        assert!((dot3(d, n) - 1.0).abs() < 1e-9, "{d:?}");
        assert!(dot3(r, u).abs() < 1e-12 && dot3(r, d).abs() < 1e-12 && dot3(u, d).abs() < 1e-12);
        // Right-handed: r × u = d.
        let c = cross3(r, u);
        assert!((dot3(c, d) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_tilted_view_looks_down_from_above_the_picture() {
        let (pos, tris, _) = disc_map(6);
        let [_, u, d] = automatic_view(&pos, &tris);
        let tilt = 0.5f64;
        let view = View::framing_tilted(&[&pos], &tris, tilt).unwrap();
        let [_, up, towards_viewer] = view.axes;
        // The viewer rises along the untilted `up`, and the picture's `up` leans away.
        assert!((dot3(towards_viewer, u) - tilt.sin()).abs() < 1e-12);
        assert!((dot3(towards_viewer, d) - tilt.cos()).abs() < 1e-12);
        assert!((dot3(up, d) + tilt.sin()).abs() < 1e-12);
        assert!(dot3(up, towards_viewer).abs() < 1e-12);
    }

    /// A quarter of an ellipsoid, x²/a² + y²/b² + z²/c² = 1 with y ≥ 0 and z ≥ 0 (the
    /// upper front of a head, shallow in depth: c < a < b): its mean normal leans 45°
    /// up, but it is seen from the front, within 15° of +z (its axis of least spread
    /// leans a little, as the shape does).
    #[test]
    fn the_front_of_a_head_is_seen_from_the_front() {
        let (a, b, c) = (1.0, 1.4, 0.6);
        let n = 24;
        let mut pos = vec![];
        for i in 0..=n {
            // Polar angle from +y down to the equator, azimuth across the front half.
            let theta = std::f64::consts::FRAC_PI_2 * i as f64 / n as f64;
            for j in 0..=n {
                let phi = std::f64::consts::PI * j as f64 / n as f64;
                pos.push([
                    a * theta.sin() * phi.cos(),
                    b * theta.cos(),
                    c * theta.sin() * phi.sin(),
                ]);
            }
        }
        let mut tris = vec![];
        for i in 0..n as u32 {
            for j in 0..n as u32 {
                let v = i * (n as u32 + 1) + j;
                let w = v + n as u32 + 1;
                tris.push([v, v + 1, w + 1]);
                tris.push([v, w + 1, w]);
            }
        }
        // Orient the triangles outwards (their normals away from the centre).
        let outward = tris.iter().fold(0.0, |s, t| {
            let p = t.map(|v| pos[v as usize]);
            let g: [f64; 3] = [0, 1, 2].map(|k| p[0][k] + p[1][k] + p[2][k]);
            s + dot3(cross3(sub3(p[1], p[0]), sub3(p[2], p[0])), g)
        });
        if outward < 0.0 {
            tris.iter_mut().for_each(|t| t.swap(1, 2));
        }
        let [_, up, d] = automatic_view(&pos, &tris);
        assert!(
            d[2] > 15f64.to_radians().cos(),
            "seen along {d:?}, not from the front"
        );
        assert!(
            d[0].abs() < 1e-9 && up[0].abs() < 1e-9,
            "left–right symmetric: {d:?} {up:?}"
        );
        assert!(up[1] > 0.95, "up {up:?}");
    }

    /// A head: an ellipsoid narrower left to right (x) than front to back (z) and tall
    /// (y), open at the neck (y < −0.8·b), with a nose on its front (+z). It is seen
    /// from the front, along +z: not in profile (x, its least spread) nor from above
    /// (y, where its normals add up, through the neck's opening).
    #[test]
    fn a_head_open_at_the_neck_is_seen_from_the_front() {
        let (a, b, c) = (0.75, 1.5, 0.95);
        let (rings, segments) = (40u32, 64u32);
        let theta_max = (-0.8f64).acos();
        let mut pos = vec![];
        for i in 0..=rings {
            let theta = theta_max * i as f64 / rings as f64;
            for j in 0..segments {
                let phi = std::f64::consts::TAU * j as f64 / segments as f64;
                let (x, y, z) = (
                    a * theta.sin() * phi.sin(),
                    b * theta.cos(),
                    c * theta.sin() * phi.cos(),
                );
                let nose = 0.3 * (-(x * x + y * y) / 0.03).exp() * (z > 0.0) as u8 as f64;
                pos.push([x, y, z + nose]);
            }
        }
        let mut tris = vec![];
        for i in 0..rings {
            for j in 0..segments {
                let at = |i: u32, j: u32| i * segments + j % segments;
                let (v, w) = (at(i, j), at(i + 1, j));
                let (v1, w1) = (at(i, j + 1), at(i + 1, j + 1));
                tris.push([v, w, w1]);
                tris.push([v, w1, v1]);
            }
        }
        let [_, up, d] = automatic_view(&pos, &tris);
        assert!(d[2] > 0.99, "seen along {d:?}, not from the front");
        assert!(up[1] > 0.99, "up {up:?}");
    }

    #[test]
    fn closed_surface_falls_back_to_principal_axes() {
        // A flat box (octahedron squashed along z): mean normal is zero; least spread is z.
        let pos = [
            [2.0, 0.0, 0.0],
            [-2.0, 0.0, 0.0],
            [0.0, 1.5, 0.0],
            [0.0, -1.5, 0.0],
            [0.0, 0.0, 0.3],
            [0.0, 0.0, -0.3],
        ];
        let tris = [
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        let [_, _, d] = automatic_view(&pos, &tris);
        assert!(d[2].abs() > 0.99, "{d:?}");
    }

    #[test]
    fn render_has_both_checker_colours_and_is_deterministic() {
        let (pos, tris, uv) = disc_map(16);
        let a = checker_render(&pos, &tris, &uv, 8, "CHECKER", (200, 160));
        assert_eq!(a.dimensions(), (200, 160));
        assert_not_blank(&a);
        let orange = a
            .pixels()
            .filter(|p| p.0[0] as i32 > p.0[2] as i32 + 60)
            .count();
        let pale = a
            .pixels()
            .filter(|p| p.0[0] > 150 && p.0[2] > 140 && p.0[0] < 250)
            .count();
        assert!(orange > 500 && pale > 500, "orange {orange}, pale {pale}");
        assert_eq!(
            a,
            checker_render(&pos, &tris, &uv, 8, "CHECKER", (200, 160))
        );
        // Bad input: no panic.
        let _ = checker_render(&pos, &[[0, 1, 999]], &uv[..1], 8, "", (64, 64));
    }

    #[test]
    fn checkerboard_of_a_flat_square_alternates_across_the_known_edges() {
        // The unit square in the plane z = 0, UVs = (x, y), 2 × 2 checks: the view looks
        // down +z with +y up and +x right, so the cell [0, ½)² (even, light) is bottom
        // left, [½, 1) × [0, ½) (odd, dark) bottom right, and so on.
        let square = crate::mesh::generate::unit_square();
        let (pos, tris) = (&square.positions, &square.triangles);
        let uv_of = |t: &[u32; 3]| t.map(|v| [pos[v as usize][0], pos[v as usize][1]]);
        let uv: Vec<[[f64; 2]; 3]> = tris.iter().map(uv_of).collect();
        let img = checker_render(pos, tris, &uv, 2, "", (200, 200));
        let [x0, y0, x1, y1] = img
            .enumerate_pixels()
            .filter(|(_, _, p)| p.0 != [255; 3])
            .fold([u32::MAX, u32::MAX, 0, 0], |b, (x, y, _)| {
                [b[0].min(x), b[1].min(y), b[2].max(x + 1), b[3].max(y + 1)]
            });
        let (w, h) = ((x1 - x0) as f64, (y1 - y0) as f64);
        assert!((w - h).abs() <= 2.0 && w > 150.0, "{w} × {h}");
        // Pixel at the point (u, v) of the square.
        let at = |u: f64, v: f64| {
            img.get_pixel((x0 as f64 + u * w) as u32, (y1 as f64 - v * h) as u32)
                .0
        };
        // Seen head-on, Lambert shading scales both colours by 0.25 + 0.75 cos θ, with θ
        // the angle to the light direction (1, 0.35, 0.25) in the (view, up, right) frame.
        let shade = 0.25 + 0.75 / (1.0f64 + 0.35 * 0.35 + 0.25 * 0.25).sqrt();
        let expect = |c: [f64; 3]| c.map(|x| (x * shade).round() as u8);
        let (light, dark) = (expect([245.0, 240.0, 230.0]), expect([215.0, 95.0, 35.0]));
        let near = |p: [u8; 3], q: [u8; 3]| (0..3).all(|k| p[k].abs_diff(q[k]) <= 2);
        for (u, v, want, cell) in [
            (0.25, 0.25, light, "bottom left"),
            (0.75, 0.25, dark, "bottom right"),
            (0.25, 0.75, dark, "top left"),
            (0.75, 0.75, light, "top right"),
        ] {
            assert!(near(at(u, v), want), "{cell}: {:?} vs {want:?}", at(u, v));
        }
        // Across the check edge u = ½ the colour flips; across the mesh's diagonal edge
        // (inside one check) it does not: the UVs interpolate continuously.
        assert!(near(at(0.45, 0.2), light) && near(at(0.55, 0.2), dark));
        assert!(near(at(0.3, 0.2), light) && near(at(0.2, 0.3), light));
        assert!(near(at(0.8, 0.7), light) && near(at(0.7, 0.8), light));
        // Mirrored UVs (u → 1 − u) swap the bottom-left check.
        let mirrored: Vec<[[f64; 2]; 3]> =
            uv.iter().map(|t| t.map(|p| [1.0 - p[0], p[1]])).collect();
        let m = checker_render(pos, tris, &mirrored, 2, "", (200, 200));
        let p = m
            .get_pixel((x0 as f64 + 0.25 * w) as u32, (y1 as f64 - 0.25 * h) as u32)
            .0;
        assert!(near(p, dark), "mirrored bottom left {p:?}");
    }
}
