//! `surfmap morph A B --match DIR -o morph.glb`: the 3D morph of thesis §5.2,
//! `M(t) = (1 − t)·M_A + t·φ_M(M_A)` on A's connectivity, as glTF 2.0 (one morph
//! target, its weight animated 0 → 1), optionally frames as OBJ and a stills sheet.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use surfmap::apps::gltf::{GltfMorphScene, write_glb};
use surfmap::apps::morph::{MorphTarget, morph_target};
use surfmap::apps::stills::{StillColour, stills_sheet};
use surfmap::apps::texture::{corner_uvs, place_in_unit_square, read_texture};
use surfmap::mesh::io::MeshFile;
use surfmap::render::save_png;
use surfmap::{TriMesh, Uvs, write_obj};

use super::load_mesh;
use super::matchio::load_match;

#[derive(clap::Args)]
pub struct Args {
    /// Surface A (the morph's connectivity and start).
    pub a: PathBuf,
    /// Surface B (the morph's end).
    pub b: PathBuf,
    /// Match folder of A → B (correspondence.npy, match.json).
    #[arg(long = "match", value_name = "DIR")]
    pub matching: PathBuf,
    /// Output glTF binary (.glb).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Length of the animation in seconds.
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub seconds: f64,
    /// Also write N frames t = 0, 1/(N−1), …, 1 as OBJ into --frames-dir.
    #[arg(long, value_name = "N")]
    pub frames: Option<usize>,
    /// Folder for --frames (default: OUT's name with `_frames`).
    #[arg(long, value_name = "DIR", requires = "frames")]
    pub frames_dir: Option<PathBuf>,
    /// Write a stills sheet (thesis fig. 5.3): 5 frames from one view, A's texture (or a
    /// checkerboard through A's texture coordinates) carried through the morph.
    #[arg(long, value_name = "SHEET.png")]
    pub stills: Option<PathBuf>,
    /// A's texture image, drawn on the stills and embedded in the glTF (default: A's
    /// material map_Kd).
    #[arg(long, value_name = "T.png")]
    pub texture: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// A's texture coordinates and texture, when it has both (or when --texture names one).
pub fn texture_of(
    file: &MeshFile,
    explicit: Option<&Path>,
) -> anyhow::Result<Option<(Uvs, PathBuf)>> {
    let path = explicit.map(Path::to_path_buf).or(file.texture.clone());
    match (&file.mesh.uvs, path) {
        (Some(uvs), Some(p)) => Ok(Some((uvs.clone(), p))),
        (None, Some(p)) if explicit.is_some() => bail!(
            "{} is given as the texture, but the mesh has no texture coordinates",
            p.display()
        ),
        _ => Ok(None),
    }
}

/// The stills sheet of frames at t = 0, ¼, ½, ¾, 1 (or of the given frames).
pub fn write_stills(
    path: &Path,
    a: &TriMesh,
    frames: &[(String, Vec<[f64; 3]>)],
    texture: Option<&(Uvs, PathBuf)>,
    quiet: bool,
) -> anyhow::Result<()> {
    let loaded;
    let (corners, colour) = match texture {
        Some((uvs, p)) => {
            loaded = read_texture(p)?;
            (
                corner_uvs(uvs, &a.triangles)?,
                StillColour::Texture(&loaded),
            )
        }
        None => {
            // A checkerboard through A's texture coordinates, or through its flattening.
            let uvs = uvs_or_flattening(a, 0.0, quiet)?;
            (corner_uvs(&uvs, &a.triangles)?, StillColour::Checker(12))
        }
    };
    let sheet = stills_sheet(frames, &a.triangles, &corners, &colour, frames.len(), 360);
    save_png(path, &sheet).with_context(|| format!("cannot write {}", path.display()))
}

/// The PNG bytes of a texture file, for embedding (glTF embeds PNG or JPEG; this tool
/// reads PNG).
/// The mesh's own texture coordinates, or else a flattening (holes filled, never cut:
/// one UV per vertex) placed in the unit square with `margin`.
pub fn uvs_or_flattening(mesh: &TriMesh, margin: f64, quiet: bool) -> anyhow::Result<Uvs> {
    if let Some(u) = &mesh.uvs {
        return Ok(u.clone());
    }
    let options = surfmap::FlattenOptions::default()
        .with_fill_holes(true)
        .with_cut(surfmap::Cut::Never);
    let flat = super::flatten::flatten_mesh(mesh, &options, quiet)?;
    Ok(Uvs::PerVertex(place_in_unit_square(&flat.uvs, margin)))
}

pub fn png_bytes(path: &Path) -> anyhow::Result<Vec<u8>> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    if !bytes.starts_with(b"\x89PNG") {
        bail!(
            "{}: not a PNG; convert the texture to PNG to embed it",
            path.display()
        );
    }
    Ok(bytes)
}

/// Notes about unmatched vertices whose displacement was extended.
pub fn extension_note(target: &MorphTarget, n: usize) -> String {
    if target.extended.is_empty() {
        format!("all {n} vertices matched")
    } else {
        format!(
            "{} of {n} vertices matched, {} unmatched moved by the harmonic extension of the matched displacements (largest {:.4})",
            target.matched,
            target.extended.len(),
            target.max_extended_displacement()
        )
    }
}

pub fn run(args: Args) -> anyhow::Result<()> {
    if args
        .output
        .extension()
        .is_none_or(|e| !e.eq_ignore_ascii_case("glb"))
    {
        bail!("the morph is written as glTF binary: name the output OUT.glb");
    }
    if !(args.seconds.is_finite() && args.seconds > 0.0) {
        bail!("--seconds must be > 0, got {}", args.seconds);
    }
    if args.frames.is_some_and(|n| n < 2) {
        bail!("--frames needs at least 2 (t = 0 and t = 1)");
    }
    let a_file = load_mesh(&args.a)?;
    let b_file = load_mesh(&args.b)?;
    let (a, b) = (&a_file.mesh, &b_file.mesh);
    let ab = load_match(&args.matching, a, &args.a, b, &args.b)?;
    let texture = texture_of(&a_file, args.texture.as_deref())?;
    let target = morph_target(&a.positions, &a.triangles, &ab, &b.positions, &b.triangles)?;

    let name = format!(
        "{} to {}",
        args.a.file_stem().unwrap_or_default().to_string_lossy(),
        args.b.file_stem().unwrap_or_default().to_string_lossy()
    );
    let mut scene = GltfMorphScene::morph(
        a.positions.clone(),
        a.triangles.clone(),
        &name,
        target.displacements.clone(),
        args.seconds,
    );
    if let Some((uvs, path)) = &texture {
        scene.uvs = Some(uvs.clone());
        scene.texture_png = Some(png_bytes(path)?);
    }
    let bytes = write_glb(&args.output, &scene)?;
    let mut written = vec![format!("{} ({bytes} bytes)", args.output.display())];

    if let Some(n) = args.frames {
        let dir = args.frames_dir.clone().unwrap_or_else(|| {
            let stem = args
                .output
                .file_stem()
                .unwrap_or_default()
                .to_string_lossy();
            args.output.with_file_name(format!("{stem}_frames"))
        });
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        for k in 0..n {
            let t = k as f64 / (n - 1) as f64;
            let frame = TriMesh {
                positions: target.frame(&a.positions, t),
                triangles: a.triangles.clone(),
                uvs: a.uvs.clone(),
            };
            write_obj(&dir.join(format!("frame_{k:03}.obj")), &frame, None)?;
        }
        written.push(format!("{n} frames in {}", dir.display()));
    }
    if let Some(path) = &args.stills {
        let frames: Vec<(String, Vec<[f64; 3]>)> = [0.0, 0.25, 0.5, 0.75, 1.0]
            .iter()
            .map(|&t| (format!("t = {t}"), target.frame(&a.positions, t)))
            .collect();
        write_stills(path, a, &frames, texture.as_ref(), args.quiet)?;
        written.push(path.display().to_string());
    }
    if !args.quiet {
        outln!(
            "{} → {}: {}; wrote {}",
            args.a.display(),
            args.b.display(),
            extension_note(&target, a.num_vertices()),
            written.join(", ")
        );
    }
    Ok(())
}
