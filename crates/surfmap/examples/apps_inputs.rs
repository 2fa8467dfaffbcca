//! Writes inputs for the application commands (`surfmap bake`, `transfer`, `morph`,
//! `rig`) into a folder, all generated, with correspondences known in closed form (see
//! `surfmap::apps::inputs`).
//!
//! `cargo run --release -p surfmap --example apps_inputs -- OUT_DIR [--scan MESH]`
//! (`--scan` textures a given disc mesh instead of the generated one, e.g. a face).

use std::path::{Path, PathBuf};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(out) = args.first().map(PathBuf::from) else {
        eprintln!("usage: apps_inputs OUT_DIR [--scan MESH]");
        std::process::exit(2);
    };
    let scan = args
        .iter()
        .position(|a| a == "--scan")
        .map(|i| surfmap::read_mesh(Path::new(&args[i + 1])).unwrap().mesh);
    println!("{}", surfmap::apps::inputs::write_inputs(&out, scan, 1024));
}
