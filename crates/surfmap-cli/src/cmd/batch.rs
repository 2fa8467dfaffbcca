//! `surfmap flatten A B … -o DIR/`: many meshes flattened in parallel with a progress
//! bar. Each mesh gets `DIR/NAME.obj` and its report `DIR/NAME.json`; a mesh that
//! cannot be read or flattened is reported and skipped; `DIR/summary.csv` lists every
//! mesh, failures with their reason ([`surfmap::batch`]). With `--seams FOLDER/`, each
//! mesh cut open along seams also gets `FOLDER/NAME.seams.obj`.

use std::io::IsTerminal;
use std::path::Path;
use std::time::Instant;

use anyhow::bail;
use indicatif::{ProgressBar, ProgressStyle};
use surfmap::FlattenError;
use surfmap::batch::{self, BatchOutput, FrontEnd};

use super::advice::defect_message;
use super::flatten::{Args, flatten_options, layout, material};
use super::load_mesh;

/// Whether the command is a batch: several inputs, or an output folder (ending in `/`
/// or an existing folder).
pub fn is_batch(args: &Args) -> bool {
    args.inputs.len() > 1 || names_folder(&args.output)
}

fn names_folder(path: &Path) -> bool {
    path.is_dir() || path.as_os_str().to_string_lossy().ends_with(['/', '\\'])
}

/// Flattens every input into the folder `args.output`.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let dir = &args.output;
    if !names_folder(dir) && surfmap::mesh::io::Format::from_path(dir).is_some() {
        bail!(
            "{} inputs need -o to name a folder, got the mesh file {}; end it with / (e.g. -o flat/)",
            args.inputs.len(),
            dir.display()
        );
    }
    if args.report.is_some() {
        bail!(
            "--report names one file; a batch writes every mesh's report to the output folder as NAME.json"
        );
    }
    if args.pictures.is_some() {
        bail!("--pictures is for one mesh; flatten that mesh on its own to draw its pictures");
    }
    if let Some(seams) = &args.seams
        && !names_folder(seams)
    {
        bail!(
            "--seams names one file; for a batch give a folder (ending in /, e.g. --seams seams/), which receives NAME.seams.obj per cut mesh"
        );
    }
    let opts = flatten_options(args)?;
    for folder in std::iter::once(dir).chain(&args.seams) {
        std::fs::create_dir_all(folder)
            .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", folder.display()))?;
    }
    let names = batch::output_names(&args.inputs);
    let bar = progress_bar(args.inputs.len(), args.quiet, "meshes");
    let material = material(args);
    let output = BatchOutput {
        dir,
        layout: layout(args),
        material: material.as_ref(),
        seams: args.seams.as_deref(),
    };
    // Repairs are not narrated per mesh; the report's counts show their effect.
    let read = |input: &Path| {
        load_mesh(input)
            .and_then(|file| args.repair.apply(file.mesh, true))
            .map_err(|e| crate::error_message(&e))
    };
    let front = FrontEnd {
        read: &read,
        flatten_error: flatten_error_message,
        wording: defect_message,
    };
    let clock = Instant::now();
    let rows = batch::run(
        &args.inputs,
        args.jobs,
        |i, input| batch::flatten_file(input, &names[i], &opts, &output, &front),
        |row| {
            if let Some(e) = &row.error {
                report_line(&bar, format!("error: {e}"));
            }
            bar.set_message(row.input.clone());
            bar.inc(1);
        },
    )?;
    bar.finish_and_clear();
    let seconds = clock.elapsed().as_secs_f64();
    let summary = dir.join("summary.csv");
    batch::write_csv(&summary, &rows)
        .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", summary.display()))?;
    let failed = rows.iter().filter(|r| !r.ok()).count();
    if !args.quiet {
        outln!(
            "flattened {} of {} meshes in {seconds:.2} s ({:.2} meshes/s) into {}; table {}",
            rows.len() - failed,
            rows.len(),
            rows.len() as f64 / seconds,
            dir.display(),
            summary.display()
        );
    }
    if failed > 0 {
        bail!(
            "{failed} of {} meshes failed (listed with their reasons in {})",
            rows.len(),
            summary.display()
        );
    }
    Ok(())
}

/// The progress bar of a batch of `len` items called `what` (`meshes`, `scans`), with
/// its ETA; hidden with `quiet` or when stderr is not a terminal.
pub fn progress_bar(len: usize, quiet: bool, what: &str) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    ProgressBar::new(len as u64).with_style(
        ProgressStyle::with_template(&format!(
            "{{bar:30}} {{pos}}/{{len}} {what} {{elapsed}} (eta {{eta}}) {{msg}}"
        ))
        .expect("valid template"),
    )
}

/// A line printed above the bar (on stderr when the bar is hidden).
pub fn report_line(bar: &ProgressBar, line: String) {
    if bar.is_hidden() {
        eprintln!("{line}");
    } else {
        bar.println(line);
    }
}

/// A flattening error as the single-mesh command words it (its remedy as flags).
fn flatten_error_message(e: &FlattenError) -> String {
    let worded = super::advice::flatten_error_message(e);
    worded.unwrap_or_else(|| crate::source_chain_message(e))
}
