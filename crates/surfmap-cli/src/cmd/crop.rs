//! `surfmap crop MESH -o OUT --radius R (--center X,Y,Z | --center-vertex V) [--geodesic]`:
//! the part of a surface within a ball around a point (the face of a head scan), for
//! matching two surfaces of different extent on the region they share.

use std::path::PathBuf;

use anyhow::{Context, bail};
use surfmap::mesh::crop::{CropDistance, crop_ball};
use surfmap::mesh::io::write_mesh;

use super::{RepairArgs, load_mesh};

#[derive(clap::Args)]
pub struct Args {
    /// Mesh file (OBJ, OFF or PLY).
    pub mesh: PathBuf,
    /// Output mesh (OBJ, OFF or PLY, by extension).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Radius of the ball, in the mesh's units.
    #[arg(long, allow_negative_numbers = true)]
    pub radius: f64,
    /// Centre of the ball: a point in space, e.g. the nose tip.
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_delimiter = ',',
        allow_hyphen_values = true,
        conflicts_with = "center_vertex",
        required_unless_present = "center_vertex"
    )]
    pub center: Option<Vec<f64>>,
    /// Centre of the ball: a vertex of the mesh (0-based, as numbered in the file, also
    /// with repairs).
    #[arg(long, value_name = "V")]
    pub center_vertex: Option<usize>,
    /// Measure distance along the surface (shortest paths over the edges) instead of in
    /// a straight line: a ball on a face then stops at the cheeks instead of taking in
    /// the ears.
    #[arg(long)]
    pub geodesic: bool,
    /// Also write, one per line, the vertex of the file each output vertex came from
    /// (0-based, as numbered in the file, also with repairs).
    #[arg(long, value_name = "FILE")]
    pub ids: Option<PathBuf>,
    #[command(flatten)]
    pub repair: RepairArgs,
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    // Vertex ids in and out are the file's; the crop runs on the repaired mesh.
    let input = load_mesh(&args.mesh)?.mesh;
    let (mesh, origins) = args.repair.apply_tracked(&input, args.quiet)?;
    let sources = origins.map(|o| o.vertex_sources(&input, &mesh));
    let file_id = |v: u32| sources.as_ref().map_or(v, |s| s[v as usize].unwrap_or(v));
    let centre = match (&args.center, args.center_vertex) {
        (Some(c), _) => match c[..] {
            [x, y, z] => [x, y, z],
            _ => bail!("--center takes three numbers X,Y,Z, got {}", c.len()),
        },
        (None, Some(v)) => match input.positions.get(v) {
            Some(&p) => p,
            None => bail!(
                "--center-vertex {v}: the mesh has {} vertices (0-based)",
                input.positions.len()
            ),
        },
        (None, None) => bail!("give --center X,Y,Z or --center-vertex V"),
    };
    let distance = if args.geodesic {
        CropDistance::Geodesic
    } else {
        CropDistance::Euclidean
    };
    let crop = crop_ball(&mesh, centre, args.radius, distance)
        .with_context(|| format!("cannot crop {}", args.mesh.display()))?;
    write_mesh(&args.output, &crop.mesh)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    if let Some(path) = &args.ids {
        let text: String = crop
            .vertex_ids
            .iter()
            .map(|&v| format!("{}\n", file_id(v)))
            .collect();
        surfmap::fsutil::write_atomically(path, |w| w.write_all(text.as_bytes()))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if !args.quiet {
        let topo = surfmap::Topology::new(&crop.mesh);
        outln!(
            "{}: kept {} of {} faces ({} vertices) within {} {} of [{:.4}, {:.4}, {:.4}] (nearest vertex {}), {} boundary loop(s){} → {}",
            args.mesh.display(),
            crop.mesh.triangles.len(),
            mesh.triangles.len(),
            crop.mesh.positions.len(),
            args.radius,
            if args.geodesic {
                "along the surface"
            } else {
                "in space"
            },
            centre[0],
            centre[1],
            centre[2],
            file_id(crop.seed),
            topo.boundary_loops.len(),
            if topo.is_disc() { ", a disc" } else { "" },
            args.output.display()
        );
    }
    Ok(())
}
