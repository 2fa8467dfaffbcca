//! `surfmap images MESH -o DIR`: geometry images of a surface (thesis §3.2). The mesh is
//! flattened with the balanced preset, placed in ω = `[0,1]²` and sampled on a
//! `size × size` grid; every image is written as a colour-mapped PNG and as raw `.npy`,
//! with `images.json` describing the transform, the grid, the units and the files.

use std::path::PathBuf;

use anyhow::{Context, bail};
use surfmap::FlattenOptions;
use surfmap::raster::output::write_image_set;
use surfmap::raster::{
    FeatureFile, FeatureMask, FeatureSource, GeometryImages, GeometryImagesOptions,
    GeometryPyramid, TextureImage,
};

use super::flatten::flatten_mesh;
use super::{RepairArgs, load_mesh};

#[derive(clap::Args)]
pub struct Args {
    /// Input mesh (OBJ, OFF or PLY) with disc topology.
    pub mesh: PathBuf,
    /// Output folder (created if missing).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Grid nodes per side, 2^k + 1 (e.g. 129, 257, 513, 1025, 2049).
    #[arg(long, default_value_t = 257)]
    pub size: usize,
    /// Feature curves: JSON `{"features": [{"name": "left_eye", "vertices": [12, 40], "closed": true}]}`.
    #[arg(long, value_name = "F.json", conflicts_with = "feature_mask")]
    pub features: Option<PathBuf>,
    /// Feature regions painted over the mesh's texture coordinates (PNG; one colour per
    /// region, black = none); must have the texture's size.
    #[arg(long, value_name = "M.png")]
    pub feature_mask: Option<PathBuf>,
    /// Texture image sampled through the mesh's texture coordinates (default: the OBJ
    /// material's `map_Kd`, when there is one).
    #[arg(long, value_name = "T.png")]
    pub texture: Option<PathBuf>,
    /// Skip the Gaussian scale pyramid.
    #[arg(long)]
    pub no_pyramid: bool,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
    /// Fill every boundary loop but the longest (eyes, mouth) for the flattening; the
    /// holes stay outside the surface mask and are covered by the harmonic extension.
    #[arg(long)]
    pub fill_holes: bool,
    #[command(flatten)]
    pub repair: RepairArgs,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let file = load_mesh(&args.mesh)?;
    // Feature ids are read in the file's numbering; the images are of the repaired mesh.
    let (mesh, origins) = args.repair.apply_tracked(&file.mesh, args.quiet)?;
    let copies = origins.map(|o| o.vertex_copies(&file.mesh, &mesh));
    // Check the cheap inputs before the flattening.
    let options = GeometryImagesOptions {
        size: args.size,
        pyramid: !args.no_pyramid,
        ..Default::default()
    };
    surfmap::grid::grid_level(args.size)?;
    let features = match &args.features {
        Some(p) => {
            let json = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read features file {}", p.display()))?;
            let parsed = match &copies {
                None => FeatureFile::parse(&json, mesh.num_vertices()),
                Some(c) => FeatureFile::parse(&json, c.len()).and_then(|f| f.renumbered(c)),
            };
            Some(parsed.with_context(|| format!("invalid features file {}", p.display()))?)
        }
        None => None,
    };
    let mask = match &args.feature_mask {
        Some(p) => Some(FeatureMask::read_png(p)?),
        None => None,
    };
    // An explicit --texture must be readable; the material's map_Kd is used when it is
    // (a missing or non-PNG file is reported and skipped).
    let texture = match (&args.texture, &file.texture) {
        (Some(p), _) => Some(TextureImage::read(p)?),
        (None, Some(p)) if mesh.uvs.is_some() => match TextureImage::read(p) {
            Ok(t) => Some(t),
            Err(e) => {
                if !args.quiet {
                    eprintln!("note: skipping the material's texture: {e}");
                }
                None
            }
        },
        _ => None,
    };
    if let (Some(m), Some(p)) = (&mask, &args.feature_mask) {
        m.validate(texture.as_ref().map(|t| (t.width, t.height)))
            .with_context(|| format!("invalid feature mask {}", p.display()))?;
        if mesh.uvs.is_none() {
            bail!(
                "feature mask {}: the mesh has no texture coordinates to paint it over",
                p.display()
            );
        }
    }
    if texture.is_some() && mesh.uvs.is_none() {
        bail!("the mesh has no texture coordinates, so the texture cannot be sampled");
    }

    // Geometry images need one UV per vertex over a disc: no cut, holes filled only on request.
    let balanced = FlattenOptions::default()
        .with_fill_holes(args.fill_holes)
        .with_cut(surfmap::Cut::Never);
    let flat = flatten_mesh(&mesh, &balanced, args.quiet)
        .with_context(|| format!("cannot flatten {}", args.mesh.display()))?;
    if !args.quiet {
        outln!(
            "{}: balanced flattening, start {}, {} iterations, {}, energy {:.6}, flipped triangles {}, {:.3} s",
            args.mesh.display(),
            flat.start_description(),
            flat.iterations,
            super::flatten::convergence(flat.converged),
            flat.energy,
            flat.flipped_triangles,
            flat.time_total
        );
    }
    let source = match (&features, &mask) {
        (Some(f), _) => FeatureSource::Curves(f),
        (None, Some(m)) => FeatureSource::Mask(m),
        (None, None) => FeatureSource::None,
    };
    let clock = std::time::Instant::now();
    let img = GeometryImages::compute(&mesh, &flat.uvs, source, texture.as_ref(), &options)
        .context("cannot compute the geometry images")?;
    let compute_time = clock.elapsed().as_secs_f64();
    let manifest = write_image_set(&args.output, &img)
        .with_context(|| format!("cannot write images into {}", args.output.display()))?;
    if !args.quiet {
        let inside = (0..img.size * img.size)
            .filter(|&k| img.raster.is_inside(k))
            .count();
        outln!(
            "images: {n}×{n} grid, {:.1}% of the nodes on the surface, length unit ℓ = {:.6} mesh units, {} feature(s), {:.3} s",
            100.0 * inside as f64 / (img.size * img.size) as f64,
            img.length_unit,
            img.features.len(),
            compute_time,
            n = img.size,
        );
        outln!("wrote into {}:", args.output.display());
        for e in &manifest.images {
            let png = e
                .png
                .as_deref()
                .map(|p| format!(" + {p}"))
                .unwrap_or_default();
            outln!("  {}{png}  {:?}  {}", e.npy, e.shape, e.description);
        }
        if !manifest.pyramid.is_empty() {
            let files: usize = manifest
                .pyramid
                .iter()
                .map(|l| l.images.len() + l.images.iter().filter(|e| e.png.is_some()).count())
                .sum();
            outln!(
                "  pyramid: {} levels ({}² … {}²) of {}, {files} files pyramid_KK_*",
                manifest.pyramid.len(),
                manifest.pyramid[0].size,
                manifest.pyramid[manifest.pyramid.len() - 1].size,
                GeometryPyramid::NAMES.join(", ")
            );
        }
        outln!("  images.json");
    }
    Ok(())
}
