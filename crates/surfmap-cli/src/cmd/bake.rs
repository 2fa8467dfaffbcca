//! `surfmap bake IN -o OUT.obj`: texture baking (thesis §5.1). The surface is flattened
//! (flip-free, holes filled for the solve) and its old texture, seen through its old
//! texture coordinates, is rendered into the new parameter domain; OUT.obj gets the new
//! coordinates, OUT.mtl and OUT.png the new texture. A mesh without a texture can bake
//! per-vertex colours or a scalar field instead.

use std::path::PathBuf;

use anyhow::{Context, bail};
use surfmap::apps::bake::{
    BakeOptions, BakedTexture, bake_scalar_field, bake_texture, bake_vertex_colors,
};
use surfmap::apps::stills::bake_sheet;
use surfmap::apps::texture::{corner_uvs, read_texture};
use surfmap::mesh::io::ObjMaterial;
use surfmap::render::{Colormap, save_png};
use surfmap::{TriMesh, Uvs, write_obj};

use super::flatten::{SolverArgs, flatten_mesh, options};
use super::matchio::read_vertex_values;
use super::{RepairArgs, load_mesh};

#[derive(clap::Args)]
pub struct Args {
    /// Input mesh: an OBJ with texture coordinates (`vt`) and a material whose `map_Kd`
    /// names the texture, or any mesh with --texture, --colors or --scalar.
    pub input: PathBuf,
    /// Output OBJ; OUT.mtl and OUT.png are written beside it.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Texels per side of the new texture.
    #[arg(long, default_value_t = 2048)]
    pub size: u32,
    /// Samples per texel side (the texel averages samples²).
    #[arg(long, default_value_t = 2)]
    pub samples: u32,
    /// Rings of texels padded beyond the chart (mipmaps show no seam).
    #[arg(long, default_value_t = 8)]
    pub padding: u32,
    /// The old texture image (default: the OBJ material's map_Kd).
    #[arg(long, value_name = "T.png", conflicts_with_all = ["colors", "scalar"])]
    pub texture: Option<PathBuf>,
    /// Bake per-vertex colours instead: float64 .npy of shape (vertices, 3), in [0, 1].
    #[arg(long, value_name = "C.npy", conflicts_with = "scalar")]
    pub colors: Option<PathBuf>,
    /// Bake a per-vertex scalar field instead (float64 .npy of shape (vertices,)),
    /// coloured with viridis over --range.
    #[arg(long, value_name = "F.npy")]
    pub scalar: Option<PathBuf>,
    /// Colour range LOW,HIGH for --scalar (default: the field's minimum and maximum).
    #[arg(long, value_parser = parse_range, requires = "scalar")]
    pub range: Option<(f64, f64)>,
    #[command(flatten)]
    pub solver: SolverArgs,
    /// Also write a before/after sheet (old texture, baked texture, the surface with
    /// each; thesis fig. 5.2).
    #[arg(long, value_name = "SHEET.png")]
    pub sheet: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    pub repair: RepairArgs,
}

fn parse_range(s: &str) -> Result<(f64, f64), String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    match parts[..] {
        [a, b] => Ok((
            a.parse().map_err(|_| format!("{a:?} is not a number"))?,
            b.parse().map_err(|_| format!("{b:?} is not a number"))?,
        )),
        _ => Err(format!("expected LOW,HIGH, got {s:?}")),
    }
}

/// What is baked, read and checked before the flattening.
enum Source {
    Texture(Vec<[[f64; 2]; 3]>, surfmap::apps::Texture, PathBuf),
    Colors(Vec<[f64; 3]>),
    Scalar(Vec<f64>, (f64, f64)),
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let file = load_mesh(&args.input)?;
    let mesh = args.repair.apply(file.mesh, args.quiet)?;
    let opts = options(&args.solver, true)?;
    if args
        .output
        .extension()
        .is_none_or(|e| !e.eq_ignore_ascii_case("obj"))
    {
        bail!("the output must be an .obj (its .mtl and .png are written beside it)");
    }
    let n = mesh.num_vertices();
    let source = if let Some(path) = &args.colors {
        let (values, k) = read_vertex_values(path, n, "the mesh")?;
        if k != 3 {
            bail!(
                "{}: per-vertex colours need 3 columns (r, g, b in [0, 1]), got {k}",
                path.display()
            );
        }
        Source::Colors(values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    } else if let Some(path) = &args.scalar {
        let (values, k) = read_vertex_values(path, n, "the mesh")?;
        if k != 1 {
            bail!(
                "{}: a scalar field has one value per vertex, got {k} columns",
                path.display()
            );
        }
        let range = args.range.unwrap_or_else(|| {
            let finite = values.iter().copied().filter(|x| x.is_finite());
            let lo = finite.clone().fold(f64::INFINITY, f64::min);
            let hi = finite.fold(f64::NEG_INFINITY, f64::max);
            if hi > lo {
                (lo, hi)
            } else {
                (lo - 0.5, lo + 0.5)
            }
        });
        Source::Scalar(values, range)
    } else {
        let texture_path = args.texture.clone().or(file.texture.clone()).ok_or_else(|| {
            anyhow::anyhow!(
                "{} names no texture: give --texture T.png, or bake --colors C.npy or --scalar F.npy",
                args.input.display()
            )
        })?;
        let uvs = mesh.uvs.as_ref().ok_or_else(|| {
            anyhow::anyhow!(
                "{} has no texture coordinates (vt on every face), so its texture cannot be read; bake --colors or --scalar instead",
                args.input.display()
            )
        })?;
        let corners = corner_uvs(uvs, &mesh.triangles)?;
        let texture = read_texture(&texture_path)?;
        Source::Texture(corners, texture, texture_path)
    };
    let bake_options = BakeOptions {
        size: args.size,
        samples: args.samples,
        padding: args.padding,
    };

    let flat = flatten_mesh(&mesh, &opts, args.quiet)
        .with_context(|| format!("cannot flatten {}", args.input.display()))?;
    let clock = std::time::Instant::now();
    let baked: BakedTexture = match &source {
        Source::Texture(corners, texture, _) => {
            bake_texture(&mesh.triangles, &flat.uvs, corners, texture, &bake_options)?
        }
        Source::Colors(c) => bake_vertex_colors(&mesh.triangles, &flat.uvs, c, &bake_options)?,
        Source::Scalar(v, range) => bake_scalar_field(
            &mesh.triangles,
            &flat.uvs,
            v,
            Colormap::Viridis,
            *range,
            &bake_options,
        )?,
    };
    let bake_time = clock.elapsed().as_secs_f64();

    // The texture first, the OBJ last: an OBJ on disk always has its texture.
    let png = args.output.with_extension("png");
    save_png(&png, &baked.image).with_context(|| format!("cannot write {}", png.display()))?;
    let out = TriMesh {
        positions: mesh.positions.clone(),
        triangles: mesh.triangles.clone(),
        uvs: Some(Uvs::PerVertex(baked.uvs.clone())),
    };
    let material = ObjMaterial {
        texture: PathBuf::from(png.file_name().expect("a file name")),
    };
    write_obj(&args.output, &out, Some(&material))?;
    if let Some(path) = &args.sheet {
        let old = match &source {
            Source::Texture(corners, texture, _) => Some((texture, corners.as_slice())),
            _ => None,
        };
        let baked_texture = surfmap::apps::Texture {
            width: baked.image.width(),
            height: baked.image.height(),
            rgb: baked.image.pixels().map(|p| p.0).collect(),
        };
        let sheet = bake_sheet(
            &mesh.positions,
            &mesh.triangles,
            old,
            &baked_texture,
            &baked.uvs,
            480,
        );
        save_png(path, &sheet).with_context(|| format!("cannot write {}", path.display()))?;
    }
    if !args.quiet {
        let what = match &source {
            Source::Texture(_, t, p) => format!("{} ({}×{})", p.display(), t.width, t.height),
            Source::Colors(_) => "vertex colours".into(),
            Source::Scalar(_, (lo, hi)) => format!("scalar field over [{lo}, {hi}]"),
        };
        outln!(
            "{}: flattened (start {}, {} iterations, {}, flipped triangles {}, {:.3} s), baked {what} into {}×{} ({:.1}% covered, {} texels padded) in {:.3} s → {}, {}",
            args.input.display(),
            flat.start_description(),
            flat.iterations,
            super::flatten::convergence(flat.converged),
            flat.flipped_triangles,
            flat.time_total,
            args.size,
            args.size,
            100.0 * baked.covered_texels() as f64 / (args.size as f64 * args.size as f64),
            baked.padding.dilated,
            bake_time,
            args.output.display(),
            png.display()
        );
    }
    Ok(())
}
