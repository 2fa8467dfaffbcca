//! `surfmap inspect MESH [--json]`: counts, bounding box, area, topology, defects, and
//! what `flatten` will do with the mesh (as it is, fill holes, cut open, or refuse) and
//! why.

use super::advice::CliDefect;
use super::load_mesh;
use serde::Serialize;
use surfmap::mesh::validate::validate;
use surfmap::{FlattenOptions, Topology, TriMesh};

#[derive(clap::Args)]
pub struct Args {
    /// Mesh file (OBJ, OFF or PLY).
    pub mesh: std::path::PathBuf,
    /// Print one JSON object instead of the readable report.
    #[arg(long)]
    pub json: bool,
}

/// The JSON report of `surfmap inspect --json`.
#[derive(Serialize)]
pub struct InspectReport {
    pub file: String,
    pub format: String,
    /// Vertex records in the file.
    pub vertices: usize,
    /// Faces as stored (a quad counts once).
    pub faces: usize,
    /// Triangles after fan triangulation.
    pub triangles: usize,
    pub edges: usize,
    pub boundary_loops: usize,
    /// Edge count of each boundary loop, longest first.
    pub boundary_loop_lengths: Vec<usize>,
    pub components: usize,
    pub euler_characteristic: i64,
    pub genus: Option<u32>,
    pub manifold: bool,
    pub orientable: bool,
    pub disc: bool,
    /// What `surfmap flatten` does with the mesh by default: `disc as is`, `fill N
    /// holes`, `cut open along seams (why)`, or `refused` (see the defects).
    pub flatten: String,
    /// Holes `flatten` fills, and whether it cuts the surface open (default options).
    pub flatten_fills_holes: usize,
    pub flatten_cuts: bool,
    pub has_uvs: bool,
    pub bbox_min: Option<[f64; 3]>,
    pub bbox_max: Option<[f64; 3]>,
    pub area: f64,
    /// Every defect, with the flags that repair it.
    pub defects: Vec<CliDefect>,
}

pub fn report(
    path: &std::path::Path,
    format: String,
    stored_faces: usize,
    mesh: &TriMesh,
) -> InspectReport {
    let topo = Topology::new(mesh);
    let mut loop_lengths: Vec<usize> = topo
        .boundary_loops
        .iter()
        .map(|l| l.vertices.len())
        .collect();
    loop_lengths.sort_unstable_by(|a, b| b.cmp(a));
    let bbox = mesh.bounding_box();
    let plan = surfmap::plan(mesh, &FlattenOptions::default()).ok();
    InspectReport {
        file: path.display().to_string(),
        format,
        vertices: mesh.positions.len(),
        faces: stored_faces,
        triangles: mesh.triangles.len(),
        edges: topo.edges.len(),
        boundary_loops: topo.boundary_loops.len(),
        boundary_loop_lengths: loop_lengths,
        components: topo.num_components,
        euler_characteristic: topo.euler_characteristic(),
        genus: topo.genus(),
        manifold: topo.is_manifold(),
        orientable: topo.orientable,
        disc: topo.is_disc(),
        flatten: plan
            .as_ref()
            .map_or_else(|| "refused".to_string(), |p| p.describe()),
        flatten_fills_holes: plan.as_ref().map_or(0, |p| p.holes_to_fill),
        flatten_cuts: plan.as_ref().is_some_and(|p| p.cut.is_some()),
        has_uvs: mesh.uvs.is_some(),
        bbox_min: bbox.map(|b| b.0),
        bbox_max: bbox.map(|b| b.1),
        area: mesh.area(),
        defects: validate(mesh, &topo).iter().map(CliDefect::from).collect(),
    }
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let file = load_mesh(&args.mesh)?;
    let r = report(
        &args.mesh,
        format!("{:?}", file.format),
        file.stored_faces,
        &file.mesh,
    );
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    outln!("{} ({})", r.file, r.format);
    outln!("  vertices   {:>10}", r.vertices);
    outln!("  faces      {:>10}   ({} triangles)", r.faces, r.triangles);
    outln!("  edges      {:>10}", r.edges);
    if let (Some(lo), Some(hi)) = (r.bbox_min, r.bbox_max) {
        outln!(
            "  bbox       [{:.4}, {:.4}, {:.4}] – [{:.4}, {:.4}, {:.4}]  (size {:.4} × {:.4} × {:.4})",
            lo[0],
            lo[1],
            lo[2],
            hi[0],
            hi[1],
            hi[2],
            hi[0] - lo[0],
            hi[1] - lo[1],
            hi[2] - lo[2]
        );
    }
    outln!("  area       {:.6}", r.area);
    outln!(
        "  topology   {} component(s), {} boundary loop(s), χ = {}, genus {}, {}, {}",
        r.components,
        r.boundary_loops,
        r.euler_characteristic,
        r.genus.map_or("undefined".to_string(), |g| g.to_string()),
        if r.manifold {
            "manifold"
        } else {
            "NON-MANIFOLD"
        },
        if r.orientable {
            "orientable"
        } else {
            "NOT orientable"
        },
    );
    outln!("  disc       {}", if r.disc { "yes" } else { "no" });
    outln!(
        "  flatten    {}",
        match r.flatten.as_str() {
            "refused" => "refused: repair the defects marked below first".to_string(),
            "disc as is" => "the disc as it is".to_string(),
            plan if r.flatten_cuts && r.flatten_fills_holes == 0 && r.boundary_loops > 1 => {
                format!("{plan}: the holes are joined to the outer boundary")
            }
            plan if r.flatten_cuts =>
                format!("{plan}: a disc map needs one boundary loop and no handle"),
            plan => format!(
                "{plan} for the solve (they stay open in the map; --cut-holes opens them with seams instead)"
            ),
        }
    );
    if r.defects.is_empty() {
        outln!("  defects    none");
    } else {
        outln!("  defects    {}", r.defects.len());
        for d in &r.defects {
            outln!(
                "    - [{}] {}",
                serde_json::to_value(d.kind)?.as_str().unwrap_or("?"),
                d.message
            );
        }
    }
    Ok(())
}
