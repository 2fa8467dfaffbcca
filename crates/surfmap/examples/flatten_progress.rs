//! Flattening with progress: a generated bumpy disc (or your own mesh) flattened with a
//! callback that sees every Newton iteration as it happens, the result's report read
//! (plan, start, iterations, energy, flips, guarantee, distortion) and the surface
//! written with texture coordinates in [0, 1]² as an OBJ into a temporary folder.
//!
//! `cargo run --release -p surfmap --example flatten_progress [-- MESH.obj|off|ply]`

use std::path::Path;
use std::time::Instant;

use surfmap::{Alpha, FlattenOptions, IterationLog, UvLayout};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The surface: a mesh file if one is given (OBJ, OFF or PLY), else a disc of 60 rings
    // (about 11,000 vertices) lifted to a bumpy height field, built in code.
    let mesh = match std::env::args().nth(1) {
        Some(path) => surfmap::read_mesh(Path::new(&path))?.mesh,
        None => surfmap::mesh::generate::bumpy_disc(60, 0.5),
    };
    println!(
        "surface: {} vertices, {} triangles",
        mesh.num_vertices(),
        mesh.num_triangles()
    );

    // Litke's energy with balanced weights (length, area, angle); holes are filled for
    // the solve by default, and a surface that is not a disc is refused with the repair.
    let options = FlattenOptions::new(Alpha::balanced());

    // The progress callback: called once per Newton iteration with its log entry (the
    // same entries end up in `Flattening::log`). There is no total to count towards
    // (the solve stops when it converges), so a progress bar would be a spinner; here a
    // line per iteration on stderr. The command line draws an `indicatif` spinner from
    // the same callback (crates/surfmap-cli/src/cmd/flatten.rs).
    let clock = Instant::now();
    let mut progress = |it: &IterationLog| {
        if it.iteration == 0 {
            // Iteration 0 of a stage is its start: the energy before any step.
            eprintln!(
                "  [{:6.2} s] stage {} starts at energy {:.6}",
                it.time, it.stage, it.energy
            );
        } else {
            eprintln!(
                "  [{:6.2} s] stage {} iteration {:>3}: energy {:.6}, step {:.3}",
                it.time, it.stage, it.iteration, it.energy, it.step
            );
        }
    };

    // `flatten_to_mesh` flattens and lays the result out as the mesh to write: here the
    // input's positions with per-vertex UVs scaled into [0, 1]² (aspect kept).
    // (`surfmap::flatten_with_progress(&mesh, &options, &mut progress)` gives the bare
    // `Flattening` instead.)
    let layout = UvLayout {
        normalize: true,
        uv_as_positions: false,
    };
    let flat = surfmap::flatten_to_mesh(mesh, &options, layout, &mut progress)?;
    let seconds = clock.elapsed().as_secs_f64();

    // The report: what was done, how the solve went, and what is guaranteed (checked on
    // the result, not assumed). Flipped triangles are counted on the output: always 0.
    let map = &flat.flattening;
    println!("plan: {}", map.describe_plan());
    println!("start: {}", map.start_description());
    println!(
        "{} warm-start steps, {} Newton iterations ({:?}), energy {:.6} per unit area, {:.2} s",
        map.warm_start_iterations, map.iterations, map.stop_reason, map.energy, seconds
    );
    println!(
        "flipped triangles: {}, guarantee: {:?}",
        map.flipped_triangles, map.guarantee
    );
    assert_eq!(
        map.flipped_triangles, 0,
        "a flattening never flips a triangle"
    );

    // Distortion of the map (mean and max; 1 is no distortion), as for any map. Per
    // corner: a closed or non-disc mesh is cut open, its seam vertices get several UVs.
    let triangles = &flat.input.triangles;
    let report = surfmap::distortion_report(
        &flat.input.positions,
        triangles,
        &map.corner_uvs(triangles),
        &surfmap::MeasureOptions::default(),
    )?;
    let m = &report.measures;
    println!(
        "distortion mean (max): angle {:.4} ({:.3}), area {:.4} ({:.3}), length {:.4} ({:.3})",
        m.angle.mean, m.angle.max, m.area.mean, m.area.max, m.length.mean, m.length.max
    );

    // Writers are atomic (a temporary file renamed into place), so a crash never leaves
    // half an OBJ behind.
    let dir = std::env::temp_dir().join(format!("surfmap-flatten-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("flat.obj");
    surfmap::write_mesh(&path, &flat.output)?;
    println!("wrote {}", path.display());
    Ok(())
}
