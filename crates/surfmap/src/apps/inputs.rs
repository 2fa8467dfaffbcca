//! Generated inputs for the application commands, with correspondences known in
//! closed form (tests, the `apps_inputs` example, CI's glTF validation). Not part of the
//! API.
//!
//! - `scan.obj` + `scan.mtl` + `photos.png`: a curved surface textured from two
//!   "photographs" (orthographic views from the left and the right, side by side in one
//!   image), so its texture coordinates jump along the line where the photographs meet,
//!   as in a scan (thesis §5.1). The colour is a function of the 3D point (a grid of
//!   lines over a smooth colour ramp), so a correct bake shows it continuous.
//! - `a.obj`, `b.obj`, `match_ab/`: two different triangulations of two different
//!   curved surfaces and the correspondence A → B of a smooth map of the plane; a band
//!   along A's border has no counterpart (partial match). `b_height.npy`: B's heights.
//!   `match_scan_b/`: the generated scan → B (a textured morph with texture seams).
//! - `neutral.obj`, `key1.obj`, `key2.obj` with `match_n1/`, `match_12/` (a chain) and
//!   `match_n2/` (direct): inputs for `rig --chain --direct`.

use std::path::Path;

use super::Chart;
use super::match_folder::write_match_folder;
use super::pad::pad_colours;
use super::texture::{render_layout, to_rgb_image};
use crate::matching::{InputMesh, Inputs};
use crate::mesh::io::ObjMaterial;
use crate::mesh::{SurfacePoint, TriMesh, Uvs};

/// A graph `z = h(x, y)` over `[−s, s]²`, `n × n` squares, interior vertices jittered
/// deterministically by `jitter` of the spacing (so two such meshes share no vertex).
pub fn graph(n: usize, s: f64, jitter: f64, seed: u64, h: impl Fn(f64, f64) -> f64) -> TriMesh {
    let mut m = crate::mesh::generate::grid_disc(n);
    let mut rng = crate::testing::Rng(seed);
    for (i, p) in m.positions.iter_mut().enumerate() {
        let (col, row) = (i % (n + 1), i / (n + 1));
        let interior = col > 0 && col < n && row > 0 && row < n;
        let (mut x, mut y) = (s * (2.0 * p[0] - 1.0), s * (2.0 * p[1] - 1.0));
        if interior {
            x += jitter * 2.0 * s / n as f64 * rng.range(-0.5, 0.5);
            y += jitter * 2.0 * s / n as f64 * rng.range(-0.5, 0.5);
        }
        *p = [x, y, h(x, y)];
    }
    m
}

/// The correspondence of every vertex of `a` to the point of `b` over `f(x, y)` (both
/// graphs over the plane), `None` where `keep(x, y)` is false or `f` leaves `b`.
pub fn planar_map(
    a: &TriMesh,
    b: &TriMesh,
    f: impl Fn([f64; 2]) -> [f64; 2],
    keep: impl Fn(f64, f64) -> bool,
) -> Vec<Option<SurfacePoint>> {
    let chart = planar_chart(b);
    a.positions
        .iter()
        .map(|p| {
            if keep(p[0], p[1]) {
                chart.locate(f([p[0], p[1]]), 0.0)
            } else {
                None
            }
        })
        .collect()
}

/// Colour of a 3D point: a smooth ramp with dark grid lines every `cell` units.
fn paint(p: [f64; 3], cell: f64) -> [f64; 3] {
    let line = |x: f64| {
        let f = (x / cell).rem_euclid(1.0);
        (f.min(1.0 - f) * cell / (0.06 * cell)).min(1.0)
    };
    let l = line(p[0]).min(line(p[1])).min(line(p[2]));
    let t = 0.5 + 0.5 * (p[0] / (4.0 * cell)).tanh();
    let base = [
        0.95 - 0.5 * t,
        0.55 + 0.3 * (p[1] / (5.0 * cell)).sin(),
        0.35 + 0.5 * t,
    ];
    base.map(|c| 0.15 + (c - 0.15) * l)
}

fn cross(u: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// The (unnormalized) normal of a triangle.
fn triangle_normal(p: [[f64; 3]; 3]) -> [f64; 3] {
    cross(
        [0, 1, 2].map(|k| p[1][k] - p[0][k]),
        [0, 1, 2].map(|k| p[2][k] - p[0][k]),
    )
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// One photograph's camera pass: triangles nearest first, their corners in the
/// photograph, and the height towards the camera of the visible surface per texel.
struct PhotoView {
    order: Vec<usize>,
    corners: Vec<[[f64; 2]; 3]>,
    depth: Vec<f64>,
}

/// Textures `mesh` from two orthographic photographs (from the left and from the
/// right, each `side × side`, side by side in one image): per-corner UVs into the
/// photograph that faces each triangle better among those that see it (a depth test:
/// a triangle hidden behind another part of the surface in one photograph takes the
/// other).
pub fn two_photographs(
    mesh: &TriMesh,
    side: u32,
) -> (Vec<[u32; 3]>, Vec<[f64; 2]>, image::RgbImage) {
    let (lo, hi) = mesh.bounding_box().expect("a mesh with positions");
    let centre = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
    let radius = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let nt = mesh.num_triangles();
    // Cameras look at the surface along its mean normal `n`, turned ±35° about the y
    // axis made orthogonal to `n`; `d` points from the surface towards the camera.
    let normal = (0..nt).fold([0.0; 3], |acc, t| {
        let n = triangle_normal(mesh.triangle_positions(t));
        [0, 1, 2].map(|k| acc[k] + n[k])
    });
    let unit = |v: [f64; 3]| {
        let l = dot(v, v).sqrt();
        v.map(|x| x / l)
    };
    let n = unit(normal);
    let up = unit([-n[1] * n[0], 1.0 - n[1] * n[1], -n[1] * n[2]]);
    let side_axis = cross(up, n);
    let view = |angle: f64| -> ([f64; 3], [f64; 3], [f64; 3]) {
        let (c, s) = (angle.cos(), angle.sin());
        let d = [0, 1, 2].map(|i| c * n[i] + s * side_axis[i]);
        (cross(up, d), up, d)
    };
    let cameras = [view(-0.6), view(0.6)];
    // Coordinates of a point in photograph k, in [0, 1]² of that photograph.
    let photo = |k: usize, p: [f64; 3]| -> [f64; 2] {
        let (r, u, _) = cameras[k];
        let q = [0, 1, 2].map(|i| p[i] - centre[i]);
        [
            0.5 + 0.55 * dot(q, r) / radius,
            0.5 + 0.55 * dot(q, u) / radius,
        ]
    };
    // Per camera: triangles nearest first (the first triangle covering a texel wins in
    // `render_layout`), their photograph corners, and the height towards the camera of
    // the visible surface at each texel.
    let views: Vec<PhotoView> = (0..2)
        .map(|k| {
            let d = cameras[k].2;
            let height = |t: usize| {
                mesh.triangle_positions(t)
                    .iter()
                    .map(|q| dot(*q, d))
                    .sum::<f64>()
            };
            let mut order: Vec<usize> = (0..nt).collect();
            order.sort_by(|&a, &b| height(b).total_cmp(&height(a)));
            let corners: Vec<[[f64; 2]; 3]> = order
                .iter()
                .map(|&t| mesh.triangle_positions(t).map(|q| photo(k, q)))
                .collect();
            let point = |sp: &SurfacePoint| -> [f64; 3] {
                let p = mesh.triangle_positions(order[sp.triangle as usize]);
                let b = sp.barycentric;
                [0, 1, 2].map(|i| b[0] * p[0][i] + b[1] * p[1][i] + b[2] * p[2][i])
            };
            let depth = render_layout(&corners, side, side, 1, |sp| {
                Some([dot(point(&sp), d), 0.0, 0.0])
            })
            .expect("a depth buffer");
            let buffer = depth
                .rgb
                .iter()
                .zip(&depth.coverage)
                .map(|(c, &n)| if n > 0 { c[0] } else { f64::NEG_INFINITY })
                .collect();
            PhotoView {
                order,
                corners,
                depth: buffer,
            }
        })
        .collect();
    let visible = |k: usize, t: usize| -> bool {
        let p = mesh.triangle_positions(t);
        let c = [0, 1, 2].map(|i| (p[0][i] + p[1][i] + p[2][i]) / 3.0);
        let uv = photo(k, c);
        let (x, y) = (uv[0] * side as f64, (1.0 - uv[1]) * side as f64);
        if !(0.0..side as f64).contains(&x) || !(0.0..side as f64).contains(&y) {
            return false;
        }
        dot(c, cameras[k].2)
            >= views[k].depth[y as usize * side as usize + x as usize] - 0.01 * radius
    };
    let mut coords = vec![];
    let mut indices = vec![];
    for t in 0..nt {
        let p = mesh.triangle_positions(t);
        let n = triangle_normal(p);
        let facing = |k: usize| dot(n, cameras[k].2);
        let better = if facing(0) >= facing(1) { 0 } else { 1 };
        let k = if visible(better, t) || !visible(1 - better, t) {
            better
        } else {
            1 - better
        };
        let base = coords.len() as u32;
        coords.extend(p.map(|q| {
            let c = photo(k, q);
            [(c[0] + k as f64) / 2.0, c[1]]
        }));
        indices.push([base, base + 1, base + 2]);
    }
    // The photographs: the visible surface seen from each camera.
    let cell = radius / 12.0;
    let mut image = image::RgbImage::from_pixel(2 * side, side, image::Rgb([40, 40, 48]));
    for (k, view) in views.iter().enumerate() {
        let layout = render_layout(&view.corners, side, side, 2, |sp| {
            let p = mesh.triangle_positions(view.order[sp.triangle as usize]);
            let b = sp.barycentric;
            Some(paint(
                [0, 1, 2].map(|i| b[0] * p[0][i] + b[1] * p[1][i] + b[2] * p[2][i]),
                cell,
            ))
        })
        .expect("a photograph");
        // Photographs of a scan extend beyond the surface's silhouette: pad them, so a
        // lookup at the silhouette does not blend in the background.
        let mut rgb = layout.rgb;
        let mut filled: Vec<bool> = layout.coverage.iter().map(|&c| c > 0).collect();
        pad_colours(&mut rgb, &mut filled, side as usize, side as usize, 4);
        let img = to_rgb_image(side, side, &rgb);
        for (x, y, px) in img.enumerate_pixels() {
            if filled[(y * side + x) as usize] {
                image.put_pixel(x + k as u32 * side, y, *px);
            }
        }
    }
    (indices, coords, image)
}

/// Per-corner texture coordinates of a graph over the plane, from two "photographs":
/// each triangle's corners at `uv_of(x, y, right)`, `right` = its centroid has `x > 0`
/// (so the coordinates jump along `x = 0`, a texture seam).
pub fn seamed_uvs(mesh: &TriMesh, uv_of: impl Fn(f64, f64, bool) -> [f64; 2]) -> Uvs {
    let mut coords = vec![];
    let mut indices = vec![];
    for tri in &mesh.triangles {
        let p = tri.map(|v| mesh.positions[v as usize]);
        let right = p.iter().map(|q| q[0]).sum::<f64>() > 0.0;
        let base = coords.len() as u32;
        coords.extend(p.map(|q| uv_of(q[0], q[1], right)));
        indices.push([base, base + 1, base + 2]);
    }
    Uvs::PerCorner { coords, indices }
}

/// A `side × side` texture whose texel centres `(u, v)` (`v` up) hold `colour(u, v)`
/// (channels in `[0, 1]`).
pub fn texture_from(side: u32, colour: impl Fn(f64, f64) -> [f64; 3]) -> super::Texture {
    let texel = |i: u32| (i as f64 + 0.5) / side as f64;
    super::Texture {
        width: side,
        height: side,
        rgb: (0..side * side)
            .map(|i| {
                colour(texel(i % side), 1.0 - texel(i / side)).map(|c| (c * 255.0).round() as u8)
            })
            .collect(),
    }
}

/// The chart `(x, y)` of a mesh that is a graph over the plane.
pub fn planar_chart(m: &TriMesh) -> Chart {
    Chart::new(
        m.positions.iter().map(|p| [p[0], p[1]]).collect(),
        m.triangles.clone(),
    )
    .expect("a planar chart")
}

fn save(path: &Path, mesh: &TriMesh) {
    crate::write_mesh(path, mesh).unwrap_or_else(|e| panic!("{e}"));
}

/// Writes every input into `out` (created if missing); `scan` replaces the generated
/// scan surface. Returns a one-line summary. Panics on any failure (a test helper).
pub fn write_inputs(out: &Path, scan: Option<TriMesh>, photo_side: u32) -> String {
    std::fs::create_dir_all(out).unwrap();

    // The scan with two photographs.
    let generated = scan.is_none();
    let scan = scan.unwrap_or_else(|| {
        graph(60, 1.0, 0.5, 11, |x, y| {
            0.5 * (-(x * x + y * y)).exp() + 0.1 * (3.0 * x).sin() * y
        })
    });
    let (indices, coords, photos) = two_photographs(&scan, photo_side);
    photos.save(out.join("photos.png")).unwrap();
    let textured = TriMesh {
        uvs: Some(Uvs::PerCorner { coords, indices }),
        ..scan
    };
    crate::write_obj(
        &out.join("scan.obj"),
        &textured,
        Some(&ObjMaterial {
            texture: "photos.png".into(),
        }),
    )
    .unwrap();

    // A morph pair with a partial match.
    let a = graph(40, 1.0, 0.5, 1, |x, y| 0.3 * (-(2.0 * x * x + y * y)).exp());
    let b = graph(47, 1.1, 0.5, 2, |x, y| {
        0.45 * (-(x * x + 2.0 * y * y)).exp() + 0.1 * x
    });
    let f = |p: [f64; 2]| [0.9 * p[0] + 0.08 * p[1] * p[1], 0.95 * p[1] + 0.05 * p[0]];
    let ab = planar_map(&a, &b, f, |x, y| {
        x.abs().max(y.abs()) < 0.85 + 0.05 * (4.0 * y).sin()
    });
    save(&out.join("a.obj"), &a);
    save(&out.join("b.obj"), &b);
    // Each folder records the meshes it maps, as `surfmap match` does.
    let info = |from: (&str, &TriMesh), to: (&str, &TriMesh)| {
        let record = |(path, mesh): (&str, &TriMesh)| InputMesh {
            path: Some(path.into()),
            ..InputMesh::of(mesh)
        };
        let inputs = Inputs {
            a: record(from),
            b: record(to),
        };
        serde_json::json!({"inputs": inputs, "source": "apps_inputs: a closed-form map of the plane"})
    };
    write_match_folder(
        &out.join("match_ab"),
        &ab,
        &info(("a.obj", &a), ("b.obj", &b)),
    )
    .unwrap();
    if generated {
        let sb = planar_map(&textured, &b, f, |_, _| true);
        write_match_folder(
            &out.join("match_scan_b"),
            &sb,
            &info(("scan.obj", &textured), ("b.obj", &b)),
        )
        .unwrap();
    }

    // A rig: neutral → key1 → key2 (a chain) and neutral → key2 (direct).
    let neutral = graph(36, 1.0, 0.4, 3, |x, y| 0.3 * (-(x * x + y * y)).exp());
    let key1 = graph(41, 1.0, 0.4, 4, |x, y| {
        0.3 * (-(x * x + y * y)).exp() + 0.15 * x * x
    });
    let key2 = graph(39, 1.0, 0.4, 5, |x, y| {
        0.3 * (-(x * x + y * y)).exp() + 0.15 * x * x - 0.1 * y
    });
    let g1 = |p: [f64; 2]| [0.97 * p[0], 0.97 * p[1] + 0.02 * p[0]];
    let g2 = |p: [f64; 2]| [0.97 * p[0] + 0.02 * p[1], 0.97 * p[1]];
    let everywhere = |_: f64, _: f64| true;
    save(&out.join("neutral.obj"), &neutral);
    save(&out.join("key1.obj"), &key1);
    save(&out.join("key2.obj"), &key2);
    let n1 = planar_map(&neutral, &key1, g1, everywhere);
    let k12 = planar_map(&key1, &key2, g2, everywhere);
    let n2 = planar_map(&neutral, &key2, |p| g2(g1(p)), everywhere);
    let (n, k1, k2) = (
        ("neutral.obj", &neutral),
        ("key1.obj", &key1),
        ("key2.obj", &key2),
    );
    write_match_folder(&out.join("match_n1"), &n1, &info(n, k1)).unwrap();
    write_match_folder(&out.join("match_12"), &k12, &info(k1, k2)).unwrap();
    write_match_folder(&out.join("match_n2"), &n2, &info(n, k2)).unwrap();

    // Per-vertex values of B for `transfer --values`: its height.
    let heights: Vec<f64> = b.positions.iter().map(|p| p[2]).collect();
    crate::raster::npy::save_npy(&out.join("b_height.npy"), &[heights.len()], &heights).unwrap();
    format!(
        "wrote {}: scan.obj (+ photos.png, {} triangles), a.obj/b.obj/match_ab ({} of {} vertices matched), neutral/key1/key2 with match_n1, match_12, match_n2, b_height.npy",
        out.display(),
        textured.num_triangles(),
        ab.iter().filter(|p| p.is_some()).count(),
        a.num_vertices()
    )
}
