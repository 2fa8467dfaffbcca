//! Protruding shapes (issue 50): closed bodies with long thin tentacles
//! ([`surfmap::mesh::generate::tentacles`]) and discs with long tubes
//! ([`surfmap::mesh::generate::octopus_disc`]), flattened with the default options: one
//! chart, cut along the protrusions where no single chart embeds
//! ([`surfmap::param::protrusions`]).
//!
//! `cargo run --release -p surfmap-bench --example protrusions [-- --save DIR] [-- NAME...]`
//!
//! Names: `tentacles:L` (8 tentacles `L` radii long), `tentacles:L,A` (`A` tentacles),
//! `octopus:L` (the octopus disc with tubes `L` rows long); without names, the table of
//! `docs/bench/protrusions.md`. Per mesh: faces, the cuts along protrusions and their
//! seam length, the total seam length, the charts, flipped triangles and boundary
//! overlap of the map (measured on the written corners), the mean symmetric Dirichlet
//! distortion `D` (1: isometry), the area distortion (`exp` of the area-weighted mean
//! `|ln σ1σ2|`, and its maximum `σ1σ2`), and the wall time of the `flatten` call.
//! `--save DIR` writes every mesh as `DIR/NAME.obj` (for `scripts/protrusion_peers.py`).

use std::path::PathBuf;
use std::time::Instant;
use surfmap::mesh::generate::{Octopus, Tentacles, octopus_disc, tentacles};
use surfmap::{FlattenOptions, MeasureOptions, TriMesh, distortion_report, flatten};

/// The generated mesh named `name`, or `None`.
fn generated(name: &str) -> Option<TriMesh> {
    let (kind, args) = name.split_once(':')?;
    let v: Vec<f64> = args
        .split(',')
        .map(|x| x.parse().ok())
        .collect::<Option<_>>()?;
    match (kind, v.as_slice()) {
        ("tentacles", [length]) => Some(tentacles(&Tentacles {
            length: *length,
            ..Default::default()
        })),
        ("tentacles", [length, arms]) => Some(tentacles(&Tentacles {
            length: *length,
            arms: *arms as usize,
            segments: 6 * *arms as usize,
            ..Default::default()
        })),
        ("octopus", [length]) => Some(octopus_disc(&Octopus {
            length: *length as usize,
            ..Default::default()
        })),
        _ => None,
    }
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut save = None;
    if let Some(i) = args.iter().position(|a| a == "--save") {
        save = Some(PathBuf::from(&args[i + 1]));
        args.drain(i..i + 2);
    }
    if args.is_empty() {
        args = [
            "tentacles:12",
            "tentacles:16",
            "tentacles:20",
            "tentacles:24",
            "tentacles:30",
            "tentacles:24,12",
            "octopus:20",
            "octopus:30",
            "octopus:40",
        ]
        .map(String::from)
        .to_vec();
    }
    println!(
        "| {:<16} | {:>6} | {:>5} | {:>9} | {:>10} | {:>6} | {:>7} | {:>7} | {:>8} | {:>8} | {:>8} | {:>7} |",
        "mesh",
        "F",
        "cuts",
        "cut seam",
        "seam total",
        "charts",
        "flipped",
        "overlap",
        "D",
        "area avg",
        "area max",
        "time s"
    );
    println!(
        "|{:-<18}|{:->8}|{:->7}|{:->11}|{:->12}|{:->8}|{:->9}|{:->9}|{:->10}|{:->10}|{:->10}|{:->9}|",
        "", "", "", "", "", "", "", "", "", "", "", ""
    );
    for name in &args {
        let Some(mesh) = generated(name) else {
            eprintln!("{name}: not a generated mesh (tentacles:L[,A] or octopus:L)");
            continue;
        };
        if let Some(dir) = &save {
            let file = dir.join(format!("{}.obj", name.replace([':', ','], "_")));
            surfmap::write_mesh(&file, &mesh).expect("written");
        }
        let clock = Instant::now();
        let map = match flatten(&mesh, &FlattenOptions::default()) {
            Ok(map) => map,
            Err(e) => {
                println!("| {name:<16} | {:>6} | refused: {e}", mesh.triangles.len());
                continue;
            }
        };
        let time = clock.elapsed().as_secs_f64();
        let measured = distortion_report(
            &mesh.positions,
            &mesh.triangles,
            &map.corner_uvs(&mesh.triangles),
            &MeasureOptions::default(),
        )
        .expect("measured");
        let (cuts, cut_length) = map
            .protrusion_cuts
            .as_ref()
            .map_or((0, 0.0), |c| (c.cuts, c.seam_length));
        let overlap = &measured.boundary_overlap;
        println!(
            "| {:<16} | {:>6} | {:>5} | {:>9.3} | {:>10.3} | {:>6} | {:>7} | {:>7} | {:>8.4} | {:>8.4} | {:>8.3} | {:>7.3} |",
            name,
            mesh.triangles.len(),
            cuts,
            cut_length,
            map.seams.as_ref().map_or(0.0, |s| s.length),
            measured.charts,
            measured.flipped_triangles,
            if overlap.self_intersecting || overlap.overlap_area > 0.0 {
                "yes"
            } else {
                "no"
            },
            measured.symmetric_dirichlet / 4.0,
            measured.area_distortion.log_mean_abs.exp(),
            measured.area_distortion.max,
            time
        );
    }
}
