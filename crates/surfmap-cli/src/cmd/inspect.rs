//! `surfmap inspect MESH [--json]`: counts, bounding box, area, topology, defects, and
//! what `flatten` will do with the mesh (as it is, fill holes, cut open, or refuse) and
//! why.

use super::advice::defect_message;
use super::load_mesh;
use surfmap::report::{InspectReport, MeshSource};

#[derive(clap::Args)]
pub struct Args {
    /// Mesh file (OBJ, OFF or PLY).
    pub mesh: std::path::PathBuf,
    /// Print one JSON object instead of the readable report.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let file = load_mesh(&args.mesh)?;
    let r = InspectReport::new(
        MeshSource::file(&args.mesh, &file),
        &file.mesh,
        defect_message,
    );
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    outln!(
        "{} ({})",
        args.mesh.display(),
        r.format.as_deref().unwrap_or_default()
    );
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
        if r.defects.iter().any(|d| !d.examples.is_empty()) {
            outln!("    ({})", surfmap::mesh::validate::NUMBERING);
        }
    }
    Ok(())
}
