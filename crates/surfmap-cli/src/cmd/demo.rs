//! `surfmap demo`: the README's first command. Generates a curved disc surface in code
//! (no external data), flattens it with the conformal and balanced presets, and writes
//! meshes with UVs, reports, pictures and a trade-off sheet into a folder.

use anyhow::Context;
use std::path::PathBuf;
use surfmap::mesh::generate::bumpy_disc;
use surfmap::render::{TradeoffPanel, save_png, tradeoff_sheet};
use surfmap::{FlattenOptions, Preset, UvLayout, write_mesh, write_obj};

#[derive(clap::Args)]
pub struct Args {
    /// Output folder (created if missing).
    #[arg(short, long, default_value = "surfmap-demo")]
    pub output: PathBuf,
    /// Rings of the generated disc (about 6·rings² triangles).
    #[arg(long, default_value_t = 60)]
    pub rings: usize,
    /// Height of the bumps relative to the disc radius.
    #[arg(long, default_value_t = 0.6, allow_negative_numbers = true)]
    pub amplitude: f64,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    if args.rings < 2 || args.rings > 2000 {
        anyhow::bail!("--rings must be between 2 and 2000, got {}", args.rings);
    }
    if !args.amplitude.is_finite() {
        anyhow::bail!("--amplitude must be a finite number");
    }
    let dir = &args.output;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mesh = bumpy_disc(args.rings, args.amplitude);
    let mut written = Vec::new();
    let input = dir.join("surface.obj");
    write_mesh(&input, &mesh)?;
    written.push(input);
    outln!(
        "generated a bumpy disc: {} vertices, {} triangles (z = {}·(1 − r²)·(sin 4x·cos 3y + ½ cos 5r))",
        mesh.positions.len(),
        mesh.triangles.len(),
        args.amplitude
    );
    let mut maps = Vec::new();
    for preset in [Preset::Conformal, Preset::Balanced] {
        let name = preset.name();
        let opts = FlattenOptions::new(preset.alpha());
        let flat =
            super::flatten::flatten_for_writing(mesh.clone(), &opts, UvLayout::default(), false)?;
        let obj = dir.join(format!("{name}.obj"));
        write_obj(&obj, &flat.output, None)?;
        written.push(obj);
        let report = flat.report(
            Some(&dir.join("surface.obj")),
            super::advice::defect_message,
        )?;
        let report_path = dir.join(format!("{name}.json"));
        super::flatten::write_json(&report_path, &report)?;
        written.push(report_path);
        let measures = &report.measures;
        let r = &flat.flattening;
        written.extend(super::flatten::write_pictures(&dir.join(name), &mesh, r)?);
        outln!(
            "{name:>9}: start {}, {} iterations, {}, energy {:.5}, flipped triangles {}, angle distortion mean {:.4} max {:.4}, {:.3} s",
            r.start_description(),
            r.iterations,
            super::flatten::convergence(r.converged),
            r.energy,
            measures.flipped_triangles,
            measures.measures.angle.mean,
            measures.measures.angle.max,
            r.time_total
        );
        maps.push((name, r.uvs.clone()));
    }
    let panels: Vec<TradeoffPanel> = maps
        .iter()
        .map(|(name, uvs)| TradeoffPanel {
            title: name.to_uppercase(),
            positions: &mesh.positions,
            triangles: &mesh.triangles,
            uvs,
        })
        .collect();
    let sheet = dir.join("tradeoff.png");
    save_png(&sheet, &tradeoff_sheet(&panels, (1000, 620)))
        .with_context(|| format!("cannot write {}", sheet.display()))?;
    written.push(sheet);
    outln!("wrote:");
    for p in &written {
        outln!("  {}", p.display());
    }
    Ok(())
}
