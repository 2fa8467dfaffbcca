//! `surfmap inspect`. (to be written)

#[derive(clap::Args)]
pub struct Args {
    /// Mesh file (OBJ, OFF or PLY).
    pub mesh: std::path::PathBuf,
    /// Print one JSON object instead of the readable report.
    #[arg(long)]
    pub json: bool,
}

pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("not written yet")
}
