//! surfmap as a library, start to finish, without the command-line tool: a surface built
//! from plain arrays in code (a bumpy patch with two "eyes" and a "mouth" cut out), refused
//! as it is (not a disc: four boundary loops), flattened with its holes filled for the
//! solve, its report read (iterations, energy, flips, distortion), its UVs normalized into
//! [0, 1]² and written as an OBJ into a temporary folder; then points of the parameter
//! domain located on the surface, and the patch matched onto a moved copy of itself.
//!
//! `cargo run --release -p surfmap --example library`

use surfmap::mesh::validate::DefectKind;
use surfmap::{Alpha, Cut, FlattenError, FlattenOptions, MeasureOptions, TriMesh, Uvs};

/// A bumpy square patch of `n × n` quads (two triangles each) with three holes: strips
/// of quads removed (two eyes, one mouth). A strip one quad high leaves no vertex
/// without a triangle, so every vertex gets a UV.
fn patch_with_holes(n: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut positions = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64 - 0.5, j as f64 / n as f64 - 0.5);
            let z = 0.3 * (-8.0 * (x * x + y * y)).exp() + 0.04 * (9.0 * x).sin() * (7.0 * y).cos();
            positions.push([x, y, z]);
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let (eye_row, mouth_row) = (2 * n / 3, n / 4);
    let removed = |i: usize, j: usize| {
        let left_eye = j == eye_row && (n / 4..n / 4 + n / 10).contains(&i);
        let right_eye = j == eye_row && (3 * n / 4 - n / 10..3 * n / 4).contains(&i);
        let mouth = j == mouth_row && (3 * n / 8..5 * n / 8).contains(&i);
        left_eye || right_eye || mouth
    };
    let mut triangles = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            if removed(i, j) {
                continue;
            }
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (positions, triangles)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (positions, triangles) = patch_with_holes(40);
    let mesh = TriMesh::new(positions, triangles);
    println!(
        "patch: {} vertices, {} triangles",
        mesh.num_vertices(),
        mesh.num_triangles()
    );

    // As it is, the patch is not a disc: asked neither to fill its holes nor to cut it
    // open, the flattening refuses it, and the error lists every defect with its remedy.
    let options = FlattenOptions::new(Alpha::balanced());
    let as_is = options.clone().with_fill_holes(false).with_cut(Cut::Never);
    match surfmap::flatten(&mesh, &as_is) {
        Err(FlattenError::NotADisc(defects)) => {
            for d in &defects {
                println!("refused: {}", d.message());
            }
            assert!(
                defects
                    .iter()
                    .any(|d| d.kind == DefectKind::SeveralBoundaryLoops)
            );
        }
        other => panic!("expected a refusal, got {other:?}"),
    }

    // By default the holes are filled for the solve and stay open in the map (UVs for
    // the patch's own vertices only).
    let map = surfmap::flatten(&mesh, &options)?;
    assert_eq!(map.uvs.len(), mesh.num_vertices());
    println!(
        "flattened: {} holes filled, start {}, {} warm-start steps, {} Newton iterations, {}, energy {:.6} per unit area, {} flipped triangles, {:.3} s",
        map.holes_filled,
        map.start_description(),
        map.warm_start_iterations,
        map.iterations,
        if map.converged {
            "converged"
        } else {
            "NOT converged"
        },
        map.energy,
        map.flipped_triangles,
        map.time_total
    );
    for entry in &map.log {
        println!(
            "  stage {} iteration {:>2}: energy {:.8}, step {:.3}",
            entry.stage, entry.iteration, entry.energy, entry.step
        );
    }

    // Distortion, as for any other tool's map (thesis §4.1.4: min / mean / max).
    let report = surfmap::distortion_report_per_vertex(
        &mesh.positions,
        &mesh.triangles,
        &map.uvs,
        &MeasureOptions::default(),
    )?;
    let m = &report.measures;
    println!(
        "distortion (min / mean / max): angle {:.4} / {:.4} / {:.4}, area {:.4} / {:.4} / {:.4}, length {:.4} / {:.4} / {:.4}",
        m.angle.min,
        m.angle.mean,
        m.angle.max,
        m.area.min,
        m.area.mean,
        m.area.max,
        m.length.min,
        m.length.mean,
        m.length.max
    );
    println!(
        "flips {}, boundary self-intersecting: {}, symmetric Dirichlet {:.6}",
        report.flipped_triangles,
        report.boundary_overlap.self_intersecting,
        report.symmetric_dirichlet
    );

    // Texture coordinates in [0, 1]², written with the surface as an OBJ.
    let uvs = map.normalized_uvs();
    let dir = std::env::temp_dir().join(format!("surfmap-library-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("patch.obj");
    let out = TriMesh {
        uvs: Some(Uvs::PerVertex(uvs)),
        ..mesh
    };
    surfmap::write_mesh(&path, &out)?;
    let back = surfmap::read_mesh(&path)?.mesh;
    assert_eq!(back.vertex_uvs().map(<[_]>::len), Some(out.num_vertices()));
    println!("wrote {}", path.display());

    // Any point of the parameter domain back on the surface: a triangle and barycentric
    // coordinates, or None outside the map (here: in a hole, or beyond the border).
    let locator = surfmap::PointLocator::new(&map.uvs, &out.triangles)?;
    let centre = map
        .uvs
        .iter()
        .fold([0.0; 2], |c, p| [c[0] + p[0], c[1] + p[1]]);
    let centre = centre.map(|c| c / map.uvs.len() as f64);
    let hit = locator
        .locate(centre)
        .expect("the centre of the map lies on the patch");
    let p = hit.position(&out.positions, &out.triangles);
    println!(
        "uv ({:.3}, {:.3}) lies in triangle {} at ({:.3}, {:.3}, {:.3}); uv (1e3, 1e3) is {:?}",
        centre[0],
        centre[1],
        hit.triangle,
        p[0],
        p[1],
        p[2],
        locator.locate([1e3, 1e3])
    );

    // Matching: the patch onto a rotated, shifted copy of itself; every vertex should
    // land where the motion puts it.
    let (s, c) = 0.5f64.sin_cos();
    let moved = TriMesh::new(
        out.positions
            .iter()
            .map(|p| [c * p[0] - s * p[2] + 1.0, p[1] - 2.0, s * p[0] + c * p[2]])
            .collect(),
        out.triangles.clone(),
    );
    let mut options = surfmap::matching::MatchOptions::default();
    options.size = 129;
    let m = surfmap::matching::match_meshes(&out, &moved, &Default::default(), &options)?;
    let (correspondence, report) = (&m.correspondence, &m.report);
    let errors: Vec<f64> = correspondence
        .iter()
        .enumerate()
        .filter_map(|(v, q)| {
            let q = (*q)?.position(&moved.positions, &moved.triangles);
            let t = moved.positions[v];
            Some(((0..3).map(|k| (q[k] - t[k]).powi(2)).sum::<f64>()).sqrt())
        })
        .collect();
    let mean = errors.iter().sum::<f64>() / errors.len().max(1) as f64;
    println!(
        "matched {} of {} vertices (min det Dφ {:.3}, {} folded image triangles, {} vertices dropped), mean error {:.4} (patch width 1)",
        errors.len(),
        correspondence.len(),
        report.min_det,
        report.flipped_triangles + report.collapsed_triangles,
        report.dropped_vertices,
        mean
    );
    assert!(report.min_det > 0.0 && mean < 0.02);
    Ok(())
}
