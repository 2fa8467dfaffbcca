//! `surfmap measure`: score the texture coordinates of a mesh (an OBJ with `vt`):
//! the thesis's and the field's distortion measures, flips, global overlap, and the
//! Shay–Solomon–Stein benchmark columns; optional pictures.

use std::path::PathBuf;

use anyhow::{Context, bail};
use surfmap::Uvs;
use surfmap::measure::{
    BENCHMARK_CSV_HEADER, DistortionReport, Measure, MeasureOptions, corner_uvs_from_indexed,
    corner_uvs_from_vertex_uvs, distortion_report, per_triangle_measure,
};
use surfmap::render;

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum ColorBy {
    Angle,
    Area,
    Length,
    LogArea,
    SymmetricDirichlet,
}

impl From<ColorBy> for Measure {
    fn from(c: ColorBy) -> Self {
        match c {
            ColorBy::Angle => Measure::Angle,
            ColorBy::Area => Measure::Area,
            ColorBy::Length => Measure::Length,
            ColorBy::LogArea => Measure::LogArea,
            ColorBy::SymmetricDirichlet => Measure::SymmetricDirichlet,
        }
    }
}

#[derive(clap::Args)]
pub struct Args {
    /// Mesh with texture coordinates (OBJ with `vt`).
    pub mesh: PathBuf,
    /// Print one JSON object (the full report) instead of the readable summary.
    #[arg(long, conflicts_with = "csv")]
    pub json: bool,
    /// Print a CSV header and one row with the Shay–Solomon–Stein benchmark columns.
    #[arg(long)]
    pub csv: bool,
    /// Do not scale the UVs to the 3D surface area before measuring.
    #[arg(long)]
    pub raw: bool,
    /// Skip the global overlap test (boundary crossings, overlap area).
    #[arg(long)]
    pub no_overlap: bool,
    /// Write a picture of the UV layout coloured by `--color-by`.
    #[arg(long, value_name = "PNG")]
    pub uv_png: Option<PathBuf>,
    /// Measure that colours the UV layout picture.
    #[arg(long, value_enum, default_value = "angle")]
    pub color_by: ColorBy,
    /// Write a shaded checkerboard rendering of the surface through its UVs.
    #[arg(long, value_name = "PNG")]
    pub checker_png: Option<PathBuf>,
    /// Picture size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "800x800", value_parser = parse_size)]
    pub size: (u32, u32),
}

pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or("expected WIDTHxHEIGHT, e.g. 800x600")?;
    let w: u32 = w.trim().parse().map_err(|_| format!("bad width {w:?}"))?;
    let h: u32 = h.trim().parse().map_err(|_| format!("bad height {h:?}"))?;
    if !(16..=16384).contains(&w) || !(16..=16384).contains(&h) {
        return Err("width and height must be between 16 and 16384".into());
    }
    Ok((w, h))
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let file = super::load_mesh(&args.mesh)?;
    let mesh = file.mesh;
    let corners = match &mesh.uvs {
        Some(Uvs::PerVertex(uv)) => {
            if uv.len() != mesh.positions.len() {
                bail!(
                    "{}: {} UVs for {} vertices",
                    args.mesh.display(),
                    uv.len(),
                    mesh.positions.len()
                );
            }
            corner_uvs_from_vertex_uvs(&mesh.triangles, uv)?
        }
        Some(Uvs::PerCorner { coords, indices }) => {
            corner_uvs_from_indexed(mesh.triangles.len(), coords, indices)?
        }
        None => bail!(
            "{} has no texture coordinates: `surfmap measure` scores a map given as an OBJ \
             with `vt` lines (for example the output of `surfmap flatten`)",
            args.mesh.display()
        ),
    };
    let options = MeasureOptions {
        normalize: !args.raw,
        overlap: !args.no_overlap,
    };
    let report = distortion_report(&mesh.positions, &mesh.triangles, &corners, &options)
        .with_context(|| format!("cannot measure {}", args.mesh.display()))?;
    if args.json {
        let mut value = serde_json::to_value(&report)?;
        if let Some(obj) = value.as_object_mut() {
            obj.insert(
                "mesh".into(),
                serde_json::Value::String(args.mesh.display().to_string()),
            );
        }
        outln!("{}", serde_json::to_string_pretty(&value)?);
    } else if args.csv {
        outln!("Filename,{}", BENCHMARK_CSV_HEADER.join(","));
        let name = args
            .mesh
            .file_name()
            .map(|n| n.to_string_lossy().replace(',', "_"))
            .unwrap_or_default();
        outln!("{name},{}", report.benchmark.csv_values().join(","));
    } else {
        print_summary(&args.mesh.display().to_string(), &report);
    }
    if let Some(path) = &args.uv_png {
        let measure = Measure::from(args.color_by);
        let values = per_triangle_measure(&mesh.positions, &mesh.triangles, &corners, measure)?;
        let title = args
            .mesh
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        let img = render::uv_layout(
            &mesh.triangles,
            &corners,
            Some((&values, measure.label())),
            &title,
            args.size,
        );
        render::save_png(path, &img).with_context(|| format!("cannot write {}", path.display()))?;
    }
    if let Some(path) = &args.checker_png {
        let title = args
            .mesh
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        let img = render::checker_render(
            &mesh.positions,
            &mesh.triangles,
            &corners,
            16,
            &title,
            args.size,
        );
        render::save_png(path, &img).with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}

fn print_summary(name: &str, r: &DistortionReport) {
    let m = &r.measures;
    outln!("{name}");
    outln!(
        "  triangles {}  vertices {}  charts {} (mirrored {})  degenerate 3D {}  degenerate UV {}",
        r.num_triangles,
        r.num_vertices,
        r.charts,
        r.mirrored_charts,
        r.degenerate_3d,
        r.degenerate_uv
    );
    outln!("  flipped triangles      {}", r.flipped_triangles);
    outln!(
        "  boundary overlap       {} ({} crossings), overlap area {:.6} ({:.4}% of UV area)",
        if r.boundary_overlap.self_intersecting {
            "yes"
        } else {
            "no"
        },
        r.boundary_overlap.boundary_crossings,
        r.boundary_overlap.overlap_area,
        100.0 * r.boundary_overlap.overlap_fraction
    );
    if !r.boundary_overlap.complete {
        outln!(
            "                         (tangled layout: search stopped early, these are lower bounds)"
        );
    }
    outln!("  UV scale               {:.6}", r.uv_scale);
    outln!(
        "  symmetric Dirichlet    mean {:.6}  max {:.6}   (isometry 4)",
        r.symmetric_dirichlet,
        r.symmetric_dirichlet_max
    );
    outln!(
        "  conformal s1/s2        mean {:.6}  max {:.6}",
        r.conformal_mean,
        r.conformal_max
    );
    outln!(
        "  area s1*s2             min {:.6}  max {:.6}  mean |log| {:.6}  max |log| {:.6}",
        r.area_distortion.min,
        r.area_distortion.max,
        r.area_distortion.log_mean_abs,
        r.area_distortion.log_max_abs
    );
    outln!(
        "  stretch (Sander)       L2 {:.6}  Linf {:.6}  L2 forward {:.6}",
        r.stretch.l2,
        r.stretch.linf,
        r.stretch.l2_forward
    );
    outln!("  thesis (min / mean / max, 3D-area weighted mean)");
    for (label, s) in [
        ("angle  √(Γ/γ)", m.angle),
        ("area   √(Γγ)", m.area),
        ("length √(Γ+γ)", m.length),
    ] {
        outln!(
            "    {label:<14} {:>12.6} {:>12.6} {:>12.6}",
            s.min,
            s.mean,
            s.max
        );
    }
}
