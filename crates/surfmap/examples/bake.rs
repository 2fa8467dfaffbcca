//! Texture baking (thesis §5.1): a generated bumpy disc whose texture is split over two
//! charts of an atlas (a seam down the middle, as when two photographs are stitched)
//! gets a new, flip-free flattening, and its texture is rendered anew in that single
//! chart: a PNG and an OBJ using it are written into a temporary folder, and the baked
//! colours are checked against the old texture at every triangle corner.
//!
//! `cargo run --release -p surfmap --example bake`

use std::time::Instant;

use surfmap::apps::{BakeOptions, Texture, bake_texture};
use surfmap::mesh::io::{ObjMaterial, write_obj};
use surfmap::{Alpha, FlattenOptions, TriMesh, Uvs};

/// The old texture: a 512 × 256 atlas of two charts side by side, each an 8 × 8
/// checkerboard over the disc seen from above, the left chart tinted red, the right blue.
fn atlas() -> Texture {
    let (width, height) = (512u32, 256u32);
    let mut rgb = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let (chart, s) = (x / 256, (x % 256) as f64 / 256.0);
            let t = 1.0 - y as f64 / height as f64; // row 0 is the top (v = 1)
            let dark = ((8.0 * s) as u32 + (8.0 * t) as u32).is_multiple_of(2);
            let level = if dark { 60 } else { 230 };
            rgb.push(if chart == 0 {
                [230, level, level]
            } else {
                [level, level, 230]
            });
        }
    }
    Texture { width, height, rgb }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mesh = surfmap::mesh::generate::bumpy_disc(40, 0.5);

    // The old texture coordinates, one triple per triangle (per corner, so the seam is
    // fine): the disc projected from above, (x, y) in [-1, 1]², into the left chart for
    // triangles left of x = 0 and into the right one otherwise.
    let old_corners: Vec<[[f64; 2]; 3]> = mesh
        .triangles
        .iter()
        .map(|tri| {
            let x_mean: f64 = tri.iter().map(|&v| mesh.positions[v as usize][0]).sum();
            let chart = if x_mean < 0.0 { 0.0 } else { 1.0 };
            tri.map(|v| {
                let [x, y, _] = mesh.positions[v as usize];
                [(chart + (x + 1.0) / 2.0) / 2.0, (y + 1.0) / 2.0]
            })
        })
        .collect();
    let texture = atlas();

    // The new parameterization: a flattening (one chart, no flips), then the bake.
    let clock = Instant::now();
    let flat = surfmap::flatten(&mesh, &FlattenOptions::new(Alpha::balanced()))?;
    let options = BakeOptions {
        size: 512,
        ..BakeOptions::default() // 2 × 2 samples per texel, 8 texels of padding
    };
    let baked = bake_texture(&mesh.triangles, &flat.uvs, &old_corners, &texture, &options)?;
    println!(
        "flattened in {} Newton iterations, baked {}×{} ({} texels covered, {} padded) in {:.2} s",
        flat.iterations,
        baked.image.width(),
        baked.image.height(),
        baked.covered_texels(),
        baked.padding.dilated,
        clock.elapsed().as_secs_f64()
    );

    // Check: at every triangle corner, the new texture at the new UV should show the
    // colour the old texture showed at the old UV (up to filtering at checker edges).
    let new_texture = Texture {
        width: baked.image.width(),
        height: baked.image.height(),
        rgb: baked.image.pixels().map(|p| p.0).collect(),
    };
    let mut difference = 0.0;
    for (tri, corners) in mesh.triangles.iter().zip(&old_corners) {
        for (&v, &old_uv) in tri.iter().zip(corners) {
            let old = texture.sample(old_uv);
            let new = new_texture.sample(baked.uvs[v as usize]);
            difference += (0..3).map(|c| old[c].abs_diff(new[c]) as f64).sum::<f64>() / 3.0;
        }
    }
    let corners = 3.0 * mesh.num_triangles() as f64;
    println!(
        "mean colour difference old → new at the corners: {:.1} of 255",
        difference / corners
    );

    // The PNG first, then the OBJ (+ .mtl) that names it: `baked.uvs` are the new
    // texture coordinates in [0, 1]², one per vertex. Both writes are atomic.
    let dir = std::env::temp_dir().join(format!("surfmap-bake-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let png = dir.join("baked.png");
    surfmap::render::save_png(&png, &baked.image)?;
    let out = TriMesh {
        uvs: Some(Uvs::PerVertex(baked.uvs.clone())),
        ..mesh
    };
    let material = ObjMaterial {
        texture: "baked.png".into(),
    };
    write_obj(&dir.join("baked.obj"), &out, Some(&material))?;
    println!("wrote {} and baked.obj", png.display());
    Ok(())
}
