//! The `surfmap` command-line tool: argument parsing, progress and files only; the
//! algorithms live in the `surfmap` library.

/// `println!` that ignores a closed standard output (`surfmap … | head` must not
/// panic on a broken pipe).
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

mod cmd;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "surfmap",
    version,
    about = "Variational surface maps: flip-free flattening, distortion reports, geometry images"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Read a mesh and report counts, bounding box, area, topology and defects.
    Inspect(cmd::inspect::Args),
    /// Flatten a disc-topology mesh to the plane without flipped triangles.
    Flatten(cmd::flatten::Args),
    /// Flatten one mesh at several α and draw the results side by side (thesis fig. 4.4).
    Tradeoff(cmd::tradeoff::Args),
    /// Generate a curved surface, flatten it with two presets, write results and pictures.
    Demo(cmd::demo::Args),
    /// Score a map: distortion measures, flips and overlap of a mesh's texture coordinates.
    Measure(cmd::measure::Args),
    /// Geometry images: flatten (balanced), rasterize h, g, distances, pyramid; PNG + .npy.
    Images(cmd::images::Args),
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Inspect(a) => cmd::inspect::run(a),
        Command::Flatten(a) => cmd::flatten::run(a),
        Command::Tradeoff(a) => cmd::tradeoff::run(a),
        Command::Demo(a) => cmd::demo::run(a),
        Command::Measure(a) => cmd::measure::run(a),
        Command::Images(a) => cmd::images::run(a),
    };
    if let Err(e) = result {
        // Print the chain of causes, skipping a cause its parent already quotes.
        let mut message = e.to_string();
        for cause in e.chain().skip(1) {
            let c = cause.to_string();
            if !message.contains(&c) {
                message = format!("{message}: {c}");
            }
        }
        eprintln!("error: {message}");
        std::process::exit(1);
    }
}
