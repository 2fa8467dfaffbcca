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
use surfmap::batch::{self, BatchRow};
use surfmap::{FlattenOptions, FlattenReport, flatten_with_progress};

use super::advice::{defect_message, flatten_error};
use super::flatten::{Args, flatten_options, write_json, write_output, write_seams};
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
    let bar = if args.quiet || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(args.inputs.len() as u64).with_style(
            ProgressStyle::with_template("{bar:30} {pos}/{len} meshes {elapsed} (eta {eta}) {msg}")
                .expect("valid template"),
        )
    };
    let clock = Instant::now();
    let rows = batch::run(
        &args.inputs,
        args.jobs,
        |i, input| flatten_one(args, &opts, input, dir, &names[i]),
        |row| {
            if let Some(e) = &row.error {
                let line = format!("error: {e}");
                if bar.is_hidden() {
                    eprintln!("{line}");
                } else {
                    bar.println(line);
                }
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

/// One mesh of the batch, written as `dir/name.obj` and `dir/name.json`: its row, or
/// the failed row with the message the single-mesh command would print.
fn flatten_one(
    args: &Args,
    opts: &FlattenOptions,
    input: &Path,
    dir: &Path,
    name: &str,
) -> BatchRow {
    let clock = Instant::now();
    let result = (|| -> anyhow::Result<BatchRow> {
        let file = load_mesh(input)?;
        // Repairs are not narrated per mesh; the report's counts show their effect.
        let mesh = args.repair.apply(file.mesh, true)?;
        let r = flatten_with_progress(&mesh, opts, &mut |_| {})
            .map_err(flatten_error)
            .map_err(|e| e.context(format!("cannot flatten {}", input.display())))?;
        let obj = dir.join(format!("{name}.obj"));
        write_output(args, &obj, &mesh, &r)?;
        if let (Some(folder), Some(seams)) = (&args.seams, &r.seams) {
            write_seams(&folder.join(format!("{name}.seams.obj")), &mesh, seams)?;
        }
        let report = FlattenReport::measure(Some(input), &mesh, &r, defect_message)?;
        let json = dir.join(format!("{name}.json"));
        write_json(&json, &report)?;
        Ok(BatchRow::done(
            input,
            &obj,
            &json,
            &report,
            clock.elapsed().as_secs_f64(),
        ))
    })();
    result.unwrap_or_else(|e| {
        BatchRow::failed(
            input,
            crate::error_message(&e),
            clock.elapsed().as_secs_f64(),
        )
    })
}
