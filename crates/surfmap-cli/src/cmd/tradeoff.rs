//! `surfmap tradeoff MESH -o sheet.png`: one mesh flattened at several α, side by
//! side, with min / mean / max of the thesis's angle, area and length distortion under
//! each (thesis fig. 4.4).

use super::{RepairArgs, load_mesh};
use anyhow::Context;
use std::path::PathBuf;
use surfmap::render::{TradeoffPanel, save_png, tradeoff_sheet};
use surfmap::{Alpha, FlattenOptions};

#[derive(clap::Args)]
pub struct Args {
    /// Input mesh with disc topology.
    pub input: PathBuf,
    /// Output PNG.
    #[arg(short, long)]
    pub output: PathBuf,
    /// α values to compare, each L,A,C; default: conformal, length, balanced, area presets.
    #[arg(long = "alpha", value_parser = super::flatten::parse_alpha, allow_hyphen_values = true)]
    pub alphas: Vec<[f64; 3]>,
    /// Sheet size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1600x700", value_parser = super::measure::parse_size)]
    pub size: (u32, u32),
    #[command(flatten)]
    pub repair: RepairArgs,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mesh = args.repair.apply(load_mesh(&args.input)?.mesh, false)?;
    let size = args.size;
    let alphas: Vec<Alpha> = if args.alphas.is_empty() {
        vec![
            Alpha::conformal(),
            Alpha::length(),
            Alpha::balanced(),
            Alpha::area(),
        ]
    } else {
        args.alphas
            .iter()
            .map(|&a| super::flatten::alpha(a))
            .collect::<anyhow::Result<_>>()?
    };
    let mut maps = Vec::new();
    for alpha in &alphas {
        // The panels draw one UV per vertex: never cut.
        let opts = FlattenOptions::new(*alpha).with_cut(surfmap::Cut::Never);
        let r = super::flatten::flatten_mesh(&mesh, &opts, false)
            .with_context(|| format!("cannot flatten {}", args.input.display()))?;
        let a = alpha.alphas();
        eprintln!(
            "α = ({:.3}, {:.3}, {:.3}): {} iterations, energy {:.6}, flipped triangles {}",
            a[0], a[1], a[2], r.iterations, r.energy, r.flipped_triangles
        );
        maps.push((a, r.uvs));
    }
    let panels: Vec<TradeoffPanel> = maps
        .iter()
        .map(|(a, uvs)| TradeoffPanel {
            title: format!("A = {:.2} {:.2} {:.2}", a[0], a[1], a[2]),
            positions: &mesh.positions,
            triangles: &mesh.triangles,
            uvs,
        })
        .collect();
    save_png(&args.output, &tradeoff_sheet(&panels, size))
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    outln!("wrote {}", args.output.display());
    Ok(())
}
