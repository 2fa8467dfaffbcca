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
    about = "Variational surface maps: flip-free flattening, distortion reports, geometry images, surface matching, texture baking, morphs and rigs"
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
    /// Match surface A onto surface B: a fold-free correspondence through their geometry images.
    Match(cmd::matching::Args),
    /// Cut a surface to a ball around a point (the face of a head scan), to match surfaces of different extent.
    Crop(cmd::crop::Args),
    /// Texture baking: flatten, render the old texture into the new domain (OBJ + MTL + PNG).
    Bake(cmd::bake::Args),
    /// Carry values, labels, landmarks, texture coordinates or a texture from B to A through a match.
    Transfer(cmd::transfer::Args),
    /// 3D morph A → B through a match, as glTF (one morph target, weight animated 0 → 1).
    Morph(cmd::morph::Args),
    /// Blend-shape rig: key poses on the neutral's connectivity, one glTF with a target per key.
    Rig(cmd::rig::Args),
    /// A rig's expressions carried onto a new neutral through the match of the two neutrals.
    Retarget(cmd::retarget::Args),
    /// Register one template onto many scans: each scan in the template's topology, a summary table.
    Register(cmd::register::Args),
    /// One self-contained interactive HTML page of a flattening, a match, a morph or rig, or a batch.
    View(cmd::view::Args),
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
        Command::Match(a) => cmd::matching::run(a),
        Command::Crop(a) => cmd::crop::run(a),
        Command::Bake(a) => cmd::bake::run(a),
        Command::Transfer(a) => cmd::transfer::run(a),
        Command::Morph(a) => cmd::morph::run(a),
        Command::Rig(a) => cmd::rig::run(a),
        Command::Retarget(a) => cmd::retarget::run(a),
        Command::Register(a) => cmd::register::run(a),
        Command::View(a) => cmd::view::run(a),
    };
    if let Err(e) = result {
        eprintln!("error: {}", error_message(&e));
        // 3: `match --strict` refused a match it made (its verdict not `ok`).
        let code = if e.downcast_ref::<cmd::matching::NotTrusted>().is_some() {
            3
        } else {
            1
        };
        std::process::exit(code);
    }
}

/// The chain of causes in one line, each piece once: a cause the message already quotes
/// is skipped, and a context that its cause quotes (such as "cannot write X" around an
/// error that names X itself) gives way to the cause.
fn error_message(e: &anyhow::Error) -> String {
    chain_message(e.chain())
}

/// [`error_message`] of a library error and its sources.
fn source_chain_message(e: &(dyn std::error::Error + 'static)) -> String {
    chain_message(std::iter::successors(Some(e), |e| e.source()))
}

fn chain_message<'a>(
    mut chain: impl Iterator<Item = &'a (dyn std::error::Error + 'static)>,
) -> String {
    let mut pieces = vec![chain.next().map_or_else(String::new, |e| e.to_string())];
    for cause in chain {
        let c = cause.to_string();
        if pieces.join(": ").contains(&c) {
            continue;
        }
        let last = pieces.last_mut().expect("one piece at least");
        if c.contains(last.as_str()) {
            *last = c;
        } else {
            pieces.push(c);
        }
    }
    pieces.join(": ")
}

#[cfg(test)]
mod tests {
    use super::error_message;
    use anyhow::Context;

    #[test]
    fn each_piece_of_an_error_appears_once() {
        let io = std::io::Error::other("permission denied");
        let inner: anyhow::Result<()> = Err(anyhow::Error::new(io).context("cannot write a.obj"));
        // A context that repeats its cause's own text.
        let e = inner.context("cannot write a.obj").unwrap_err();
        assert_eq!(error_message(&e), "cannot write a.obj: permission denied");
        // A cause that repeats the context: the cause alone.
        let e = anyhow::anyhow!("cannot write b.obj: disk full").context("cannot write b.obj");
        assert_eq!(error_message(&e), "cannot write b.obj: disk full");
        // Distinct pieces are all kept, in order.
        let e = anyhow::anyhow!("no such file").context("cannot read c.off");
        assert_eq!(error_message(&e), "cannot read c.off: no such file");
    }
}
