//! Development probe for the matcher: `match_probe A.obj B.obj OUT.npy [landmarks.json]
//! [key=value …]` writes one 3D point per vertex of A (NaN = unmatched), the format the
//! referee in `../shared/match_eval` scores, and prints the per-level log.
//! Keys: size, k0, bend, reg, feat, pos, soft, tol, ftol (finest level), align (auto|search|none|features),
//! rot (rotations tried), scale (0/1), alevels, maxev (evaluations on the finest level, 0: no cap),
//! sob (local metric width, cells), wide (the coarsest level's first metric, ω units).

use std::path::Path;
use surfmap::matching::{Align, Guidance, Landmarks, MatchOptions, match_surfaces};
use surfmap::mesh::io::read_mesh;
use surfmap::raster::npy::save_npy;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let a = read_mesh(Path::new(&args[0]))?.mesh;
    let b = read_mesh(Path::new(&args[1]))?.mesh;
    let out = &args[2];
    let mut guidance = Guidance::default();
    let mut options = MatchOptions::default();
    for arg in &args[3..] {
        if let Some((k, v)) = arg.split_once('=') {
            let f = || v.parse::<f64>().unwrap();
            match k {
                "size" => options.size = f() as usize,
                "k0" => options.coarsest_level = f() as usize,
                "bend" => options.betas.bend = f(),
                "reg" => options.betas.reg = f(),
                "feat" => options.betas.features = f(),
                "pos" => {
                    options.betas.position = f();
                    options.position_weight = surfmap::matching::PositionWeight::Fixed;
                }
                "out" => options.betas.uncovered = f(),
                "soft" => options.soft = f(),
                "tol" => options.ncg.tolerance = f(),
                "maxit" => options.ncg.max_iterations = f() as usize,
                "refit" => options.ncg.refit_every = f() as usize,
                "ftol" => options.ncg.finest_tolerance = f(),
                "maxev" => options.ncg.max_evaluations = f() as usize,
                "totev" => options.ncg.total_evaluations = f() as usize,
                "rot" => options.align_rotations = f() as usize,
                "scale" => options.allow_scale = f() != 0.0,
                // ridge of the position term's affine map; negative: a similarity
                "ridge" => {
                    options.position_map = if f() < 0.0 {
                        surfmap::matching::PositionMap::Similarity
                    } else {
                        surfmap::matching::PositionMap::AffineNearSimilarity { ridge: f() }
                    }
                }
                "sob" => options.sobolev_cells = f(),
                "wide" => options.coarsest_sobolev_width = f(),
                "fspace" => options.features_in_space = f() != 0.0,
                "band" => options.position_band = f(),
                "tau" => options.position_scale = f(),
                "relief" => options.position_relief = f(),
                "hsig" => options.curvature_sigma = f(),
                "snap" => options.snap_cells = f(),
                "split" => options.split_hole_rims = f(),
                "fit" => options.rim_fit_rings = f() as usize,
                "rings" => options.complete_rings = f() as usize,
                "ctol" => options.complete_tolerance.elsewhere = f(),
                "htol" => options.complete_tolerance.hole_rim = f(),
                "itol" => options.complete_tolerance.interior = f(),
                "smooth" => options.rim_smoothing.rings = f() as usize,
                "smoothit" => options.rim_smoothing.iterations = f() as usize,
                "pin" => options.pin_landmarks = f() != 0.0,
                "kappa" | "pcap" => {
                    let surfmap::matching::PositionWeight::FromShapeResidual { kappa, cap, .. } =
                        &mut options.position_weight
                    else {
                        panic!("kappa/pcap with a fixed position weight");
                    };
                    *if k == "kappa" { kappa } else { cap } = f();
                }
                "holes" => {
                    options.hole_features = match v {
                        "auto" => surfmap::matching::HoleFeatures::Auto,
                        "on" => surfmap::matching::HoleFeatures::On,
                        _ => surfmap::matching::HoleFeatures::Off,
                    }
                }
                "align" => {
                    options.align = match v {
                        "auto" => Align::Auto,
                        "shape" => Align::Shape,
                        "none" => Align::None,
                        "features" => Align::Features,
                        _ => panic!("align={v}"),
                    }
                }
                _ => panic!("unknown key {k}"),
            }
        } else {
            let lm: Landmarks = serde_json::from_str(&std::fs::read_to_string(arg)?)?;
            guidance.landmarks = Some(lm);
        }
    }
    let clock = std::time::Instant::now();
    let m = match_surfaces(&a, &b, &guidance, &options)?;
    let total = clock.elapsed().as_secs_f64();
    for l in &m.levels {
        println!(
            "level {} ({}²) ε={:.4}: {:3} it {:3} ev {:?} E {:.6e} → {:.6e} [bend {:.3e} reg {:.3e} feat {:.3e} pos {:.3e}] {:.3}s",
            l.level,
            l.size,
            l.epsilon,
            l.iterations,
            l.evaluations,
            l.stop,
            l.start.total,
            l.end.total,
            l.end.bend,
            l.end.reg,
            l.end.features,
            l.end.position,
            l.seconds
        );
    }
    println!(
        "alignment: {} angle {:.1}° scale {:.3}; holes {:?}",
        m.alignment.method,
        m.alignment.similarity.angle().to_degrees(),
        m.alignment.similarity.scale(),
        m.alignment.hole_pairs
    );
    println!(
        "position weight {:.1} (shape residual {:?})",
        m.position_weight, m.shape_residual
    );
    let pts = m.vertex_points();
    let matched = pts.iter().filter(|p| p.is_some()).count();
    println!(
        "flatten A {:.3}s B {:.3}s, images A {:.3}s B {:.3}s, solve {:.3}s, total {:.3}s; min det {:.4}; matched {}/{}",
        m.a.flatten_time,
        m.b.flatten_time,
        m.a.time_images,
        m.b.time_images,
        m.seconds_solve,
        total,
        m.min_det,
        matched,
        pts.len()
    );
    let checked = m.checked_correspondence(&a, &b, options.drop_folds)?;
    println!(
        "rim fit {:?}, completed {:?}, dropped {}",
        checked.rim_fit, checked.completion, checked.dropped
    );
    let corr = checked.points;
    let data = surfmap::matching::output::correspondence_rows(&corr);
    save_npy(Path::new(out), &[corr.len(), 4], &data)?;
    if let Ok(dir) = std::env::var("PROBE_DUMP") {
        let dir = Path::new(&dir);
        std::fs::create_dir_all(dir)?;
        let n = m.deformation.size;
        let phi: Vec<f64> = m.grid_positions().iter().flat_map(|p| *p).collect();
        save_npy(&dir.join("phi.npy"), &[n, n, 2], &phi)?;
        for (name, s) in [("A", &m.a), ("B", &m.b)] {
            let mask: Vec<f64> = s.images.boundary_distance.as_slice().to_vec();
            save_npy(&dir.join(format!("sd_{name}.npy")), &[n, n], &mask)?;
            let h: Vec<f64> = s.images.mean_curvature_extended.as_slice().to_vec();
            save_npy(&dir.join(format!("h_{name}.npy")), &[n, n], &h)?;
        }
    }
    Ok(())
}
