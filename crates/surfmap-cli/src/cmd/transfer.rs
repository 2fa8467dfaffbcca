//! `surfmap transfer A B --match DIR …`: carry what is defined on B to A through the
//! correspondence A → B of a match folder (one point of B per vertex of A): per-vertex
//! values or labels, landmarks, texture coordinates into B's texture, or B's texture
//! re-rendered into A's own UV layout.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use serde::{Deserialize, Serialize};
use surfmap::apps::morph::harmonic_extension;
use surfmap::apps::texture::read_texture;
use surfmap::apps::transfer::{
    transfer_labels, transfer_landmarks, transfer_texture, transfer_uvs, transfer_values,
};
use surfmap::fsutil::write_atomically;
use surfmap::mesh::io::ObjMaterial;
use surfmap::raster::npy::save_npy;
use surfmap::render::save_png;
use surfmap::{SurfacePoint, TriMesh, Uvs, write_obj};

use super::load_mesh;
use super::matchio::{chart_of, load_match, read_vertex_values};

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("what").required(true).args(["values", "labels", "landmarks", "uvs", "texture"])))]
pub struct Args {
    /// Surface A (receives).
    pub a: PathBuf,
    /// Surface B (gives).
    pub b: PathBuf,
    /// Match folder of A → B (correspondence.npy, match.json).
    #[arg(long = "match", value_name = "DIR")]
    pub matching: PathBuf,
    /// Per-vertex values of B (float64 .npy, shape (n_B,) or (n_B, k)), interpolated →
    /// OUT.npy of shape (n_A,) or (n_A, k), NaN where A is unmatched.
    #[arg(long, value_name = "B.npy")]
    pub values: Option<PathBuf>,
    /// Per-vertex labels of B (whole numbers in a float64 .npy, shape (n_B,)), nearest
    /// vertex → OUT.npy, −1 where A is unmatched.
    #[arg(long, value_name = "B.npy")]
    pub labels: Option<PathBuf>,
    /// Landmarks of A (JSON: {"landmarks": [{"name": "nose", "vertex": 12}, {"name": "x",
    /// "triangle": 3, "barycentric": [0.2, 0.3, 0.5]}]}) → OUT.json with their points on B.
    #[arg(long, value_name = "L.json")]
    pub landmarks: Option<PathBuf>,
    /// A gets texture coordinates into B's texture (B needs vt and a texture) →
    /// OUT.obj + OUT.mtl referencing B's texture.
    #[arg(long)]
    pub uvs: bool,
    /// B's texture re-rendered into A's own UV layout (A's vt, or A's balanced
    /// flattening when it has none) → OUT.obj + OUT.mtl + OUT.png.
    #[arg(long)]
    pub texture: bool,
    /// B's texture image (default: B's material map_Kd), for --uvs and --texture.
    #[arg(long, value_name = "T.png")]
    pub b_texture: Option<PathBuf>,
    /// Texels per side of the image written by --texture.
    #[arg(long, default_value_t = 1024)]
    pub size: u32,
    /// Output file (.npy, .json or .obj by what is transferred).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Deserialize)]
struct LandmarkFile {
    landmarks: Vec<LandmarkIn>,
}

#[derive(Deserialize)]
struct LandmarkIn {
    name: String,
    vertex: Option<u32>,
    triangle: Option<u32>,
    barycentric: Option<[f64; 3]>,
}

#[derive(Serialize)]
struct LandmarkOut {
    name: String,
    /// The landmark's point on B, or null when it has no counterpart.
    on_b: Option<SurfacePoint>,
    position: Option<[f64; 3]>,
}

fn want_extension(path: &Path, ext: &str, what: &str) -> anyhow::Result<()> {
    if path
        .extension()
        .is_none_or(|e| !e.eq_ignore_ascii_case(ext))
    {
        bail!("{what} are written as .{ext}: name the output OUT.{ext}");
    }
    Ok(())
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let a_file = load_mesh(&args.a)?;
    let b_file = load_mesh(&args.b)?;
    let (a, b) = (&a_file.mesh, &b_file.mesh);
    let ab = load_match(&args.matching, a, &args.a, b, &args.b)?;
    let matched = ab.iter().filter(|p| p.is_some()).count();
    let summary: String;
    if let Some(path) = &args.values {
        want_extension(&args.output, "npy", "values")?;
        let (values, k) = read_vertex_values(path, b.num_vertices(), "B")?;
        let rows: Vec<Vec<f64>> = values.chunks_exact(k).map(<[f64]>::to_vec).collect();
        // Interpolate each column (any k) through the same points.
        let mut out = vec![f64::NAN; a.num_vertices() * k];
        for c in 0..k {
            let column: Vec<[f64; 1]> = rows.iter().map(|r| [r[c]]).collect();
            let t = transfer_values(&ab, &b.triangles, &column)?;
            for (i, v) in t.iter().enumerate() {
                if let Some([x]) = v {
                    out[i * k + c] = *x;
                }
            }
        }
        let shape = if k == 1 {
            vec![a.num_vertices()]
        } else {
            vec![a.num_vertices(), k]
        };
        save_npy(&args.output, &shape, &out)
            .with_context(|| format!("cannot write {}", args.output.display()))?;
        summary = format!("values ({k} per vertex)");
    } else if let Some(path) = &args.labels {
        want_extension(&args.output, "npy", "labels")?;
        let (values, k) = read_vertex_values(path, b.num_vertices(), "B")?;
        if k != 1 {
            bail!(
                "{}: labels are one value per vertex, got {k} columns",
                path.display()
            );
        }
        let t = transfer_labels(&ab, &b.triangles, &values)?;
        let out: Vec<f64> = t.iter().map(|v| v.unwrap_or(-1.0)).collect();
        save_npy(&args.output, &[a.num_vertices()], &out)
            .with_context(|| format!("cannot write {}", args.output.display()))?;
        summary = "labels".into();
    } else if let Some(path) = &args.landmarks {
        want_extension(&args.output, "json", "landmarks")?;
        let text =
            std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
        let file: LandmarkFile = serde_json::from_slice(&text)
            .with_context(|| format!("{}: not a landmark file", path.display()))?;
        let mut points = vec![];
        for l in &file.landmarks {
            let p = match (l.vertex, l.triangle, l.barycentric) {
                (Some(v), None, None) => surfmap::SurfacePoint::at_vertex(&a.triangles, v)
                    .ok_or_else(|| {
                        anyhow::anyhow!("landmark '{}': vertex {v} is on no triangle of A", l.name)
                    })?,
                (None, Some(triangle), Some(barycentric)) => SurfacePoint {
                    triangle,
                    barycentric,
                },
                _ => bail!(
                    "landmark '{}': give either \"vertex\" or \"triangle\" with \"barycentric\"",
                    l.name
                ),
            };
            points.push(p);
        }
        let chart = chart_of(b, &args.b, args.quiet)?;
        let on_b = transfer_landmarks(&points, &a.triangles, &ab, &chart)?;
        let out: Vec<LandmarkOut> = file
            .landmarks
            .iter()
            .zip(on_b)
            .map(|(l, p)| LandmarkOut {
                name: l.name.clone(),
                on_b: p,
                position: p.map(|p| p.position(&b.positions, &b.triangles)),
            })
            .collect();
        let json = serde_json::to_vec_pretty(&serde_json::json!({ "landmarks": out }))?;
        write_atomically(&args.output, |w| w.write_all(&json))
            .with_context(|| format!("cannot write {}", args.output.display()))?;
        summary = format!("{} landmarks", out.len());
    } else if args.uvs {
        want_extension(&args.output, "obj", "meshes with texture coordinates")?;
        let uvs_b = b.uvs.as_ref().ok_or_else(|| {
            anyhow::anyhow!(
                "{} has no texture coordinates to transfer",
                args.b.display()
            )
        })?;
        let texture = args.b_texture.clone().or(b_file.texture.clone());
        let t = transfer_uvs(&ab, &a.triangles, &b.triangles, uvs_b)?;
        // Unmatched vertices get a harmonic extension of the transferred coordinates.
        let ext = harmonic_extension(&a.positions, &a.triangles, &t.uvs)?;
        let out = TriMesh {
            positions: a.positions.clone(),
            triangles: a.triangles.clone(),
            uvs: Some(Uvs::PerVertex(ext.values)),
        };
        let material = texture.map(|t| ObjMaterial {
            texture: std::path::absolute(&t).unwrap_or(t),
        });
        write_obj(&args.output, &out, material.as_ref())?;
        summary = format!(
            "texture coordinates ({} vertices extended, {} triangles across a seam of B's texture)",
            ext.extended.len(),
            t.seam_triangles.len()
        );
    } else {
        want_extension(&args.output, "obj", "textured meshes")?;
        let uvs_b = b.uvs.as_ref().ok_or_else(|| {
            anyhow::anyhow!(
                "{} has no texture coordinates, so it has no texture to transfer",
                args.b.display()
            )
        })?;
        let texture_path = args
            .b_texture
            .clone()
            .or(b_file.texture.clone())
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "{} names no texture: give --b-texture T.png",
                    args.b.display()
                )
            })?;
        let texture_b = read_texture(&texture_path)?;
        let uvs_a = super::morph::uvs_or_flattening(a, 0.02, args.quiet)?;
        let chart = chart_of(b, &args.b, args.quiet)?;
        let t = transfer_texture(
            &a.triangles,
            &uvs_a,
            &ab,
            &chart,
            uvs_b,
            &texture_b,
            args.size,
            2,
            8,
        )?;
        let png = args.output.with_extension("png");
        save_png(&png, &t.image).with_context(|| format!("cannot write {}", png.display()))?;
        let out = TriMesh {
            positions: a.positions.clone(),
            triangles: a.triangles.clone(),
            uvs: Some(uvs_a),
        };
        let material = ObjMaterial {
            texture: PathBuf::from(png.file_name().expect("a file name")),
        };
        write_obj(&args.output, &out, Some(&material))?;
        summary = format!(
            "texture {}×{} ({} texels covered)",
            args.size,
            args.size,
            t.covered.iter().filter(|&&c| c).count()
        );
    }
    if !args.quiet {
        outln!(
            "{} → {}: {matched} of {} vertices matched; transferred {summary} → {}",
            args.b.display(),
            args.a.display(),
            a.num_vertices(),
            args.output.display()
        );
    }
    Ok(())
}
