//! `surfmap register TEMPLATE SCAN… -o DIR`: one template registered onto many scans,
//! in parallel with a progress bar. Every scan gets `DIR/registered/NAME.obj` (the
//! template's topology and vertex order, unmatched vertices extended smoothly), with
//! `--keep-matches` its match folder `DIR/matches/NAME/`; `DIR/summary.csv` and
//! `summary.json` list every scan with its verdict or its error; then the shape model of
//! the scans with verdict `ok` goes into `DIR/model/` (`--model-only DIR` rebuilds it)
//! With `--sequence` the scans are frames of one moving face, registered in the order
//! given (with `--warm-start` each from the previous frame's result), with each frame's
//! motion and jitter in the summary (library: `surfmap::apps::register`, `register::sequence`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use surfmap::apps::register::Template;
use surfmap::apps::register::batch::{
    RegisterJob, register_many, register_sequence, write_summary,
};
use surfmap::matching::{MatchError, MatchOptions};

use super::advice::worded_match_error;
use super::batch::{progress_bar, report_line};
use super::{RepairArgs, load_mesh};

#[derive(clap::Args)]
pub struct Args {
    /// The template (OBJ, OFF or PLY): a disc, possibly with holes; every scan comes out
    /// in its topology and vertex order.
    #[arg(required_unless_present = "model_only")]
    pub template: Option<PathBuf>,
    /// The scans: files, folders (every OBJ, OFF and PLY file in them) or glob patterns
    /// in quotes (`'scans/*.ply'`; `*` and `?` in the file name).
    #[arg(required_unless_present = "model_only")]
    pub scans: Vec<PathBuf>,
    /// Output folder (created if missing).
    #[arg(short, long, required_unless_present = "model_only")]
    pub output: Option<PathBuf>,
    /// Only (re)build the shape model of the registration folder DIR (from its
    /// summary.json and registered/ meshes) into DIR/model/.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["template", "output", "resume"])]
    pub model_only: Option<PathBuf>,
    /// Do not build the shape model after registering.
    #[arg(long, conflicts_with = "model_only")]
    pub no_model: bool,
    /// Build the shape model from the scans with verdict `doubtful` too (by default
    /// only `ok`): generalized Procrustes alignment, mean.obj, the PCA modes in
    /// model.npz, model.json (modes for 90/95/99 %), modes.png.
    #[arg(long)]
    pub model_include_doubtful: bool,
    /// A folder with one landmarks file per scan, named after the scan (`face01.ply` →
    /// `face01.json`), as `surfmap match --landmarks` reads: `{"names": [...], "A":
    /// [template vertex ids], "B": [scan vertex ids]}`. A scan without its file fails.
    #[arg(long, value_name = "FOLDER")]
    pub landmarks_dir: Option<PathBuf>,
    /// Scans registered at the same time; 0 = one per core. The batch runs on this many
    /// threads in total.
    #[arg(short, long, default_value_t = 0)]
    pub jobs: usize,
    /// Also write each scan's match folder `DIR/matches/NAME/` (as `surfmap match`).
    #[arg(long)]
    pub keep_matches: bool,
    /// Skip the scans an earlier run registered into DIR (their `registered/NAME.json`
    /// and `.obj` are there); failed scans are tried again.
    #[arg(long)]
    pub resume: bool,
    /// The scans are frames of one sequence, in the order given (a folder's files sorted
    /// by name), registered one after the other; summary.csv gets `started_from` and, per
    /// frame, the mean non-rigid motion since the previous frame and the mean and 95th
    /// percentile of the jitter (half the rigidly aligned second difference in time, in
    /// the scans' units). --jobs is the threads of each match.
    #[arg(long, conflicts_with_all = ["resume", "model_only"])]
    pub sequence: bool,
    /// With --sequence: register each frame from the previous frame's registration (the
    /// template's triangles at the positions registered there, matched onto the next
    /// frame) instead of from the template; a frame whose verdict is not `ok` is never a
    /// start. Consecutive matches then compare nearly equal shapes, but their errors add
    /// up: on the ICT sequences of docs/bench/sequence.md it drifts (mean error 0.50 %
    /// against 0.34 % of the face width over 8 frames of a smile) and does not lower the
    /// jitter.
    #[arg(long, requires = "sequence")]
    pub warm_start: bool,
    /// Finest grid of each match, 2^k + 1 nodes per side (as `surfmap match --size`).
    #[arg(long, default_value_t = 257)]
    pub size: usize,
    /// Most energy evaluations per level (as `surfmap match --budget`).
    #[arg(long, value_name = "N", default_value_t = surfmap::matching::options::BUDGET)]
    pub budget: usize,
    /// Print nothing but errors and warnings.
    #[arg(short, long)]
    pub quiet: bool,
    /// Repairs applied to every scan (not to the template) before its match.
    #[command(flatten)]
    pub repair: RepairArgs,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(dir) = &args.model_only {
        return model(dir, args.model_include_doubtful, args.quiet);
    }
    let (Some(template_path), Some(output)) = (&args.template, &args.output) else {
        bail!("give the template, the scans and -o DIR (or --model-only DIR)");
    };
    let inputs = expand_scans(&args.scans)?;
    let mut options = MatchOptions::default();
    options.size = args.size;
    options.budget = args.budget;
    options
        .validate()
        .map_err(|e| anyhow::anyhow!(e.worded(&format!("--{}", e.setting().replace('_', "-")))))?;
    if let Some(d) = &args.landmarks_dir
        && !d.is_dir()
    {
        bail!(
            "--landmarks-dir {} is not a folder; give the folder holding one STEM.json per scan",
            d.display()
        );
    }
    let clock = Instant::now();
    let template = Template::new(load_mesh(template_path)?.mesh, &options)
        .map_err(|e| match e {
            surfmap::apps::register::RegisterError::Match(m) => {
                anyhow::anyhow!(match_error_message(&m))
            }
            other => other.into(),
        })
        .with_context(|| format!("the template {} cannot be matched", template_path.display()))?;
    if !args.quiet {
        eprintln!(
            "template {}: {} vertices, prepared in {:.2} s; {} scans",
            template_path.display(),
            template.mesh.num_vertices(),
            template.one_off_seconds,
            inputs.len()
        );
    }
    std::fs::create_dir_all(output)
        .with_context(|| format!("cannot create {}", output.display()))?;
    let names = surfmap::batch::output_names(&inputs);
    let read = |input: &Path| {
        load_mesh(input)
            .and_then(|file| args.repair.apply(file.mesh, true))
            .map_err(|e| crate::error_message(&e))
    };
    let job = RegisterJob {
        template: &template,
        options: &options,
        dir: output,
        keep_matches: args.keep_matches,
        landmarks_dir: args.landmarks_dir.as_deref(),
        read: &read,
        match_error: match_error_message,
    };
    let bar = progress_bar(inputs.len(), args.quiet, "scans");
    let on_done = |row: &surfmap::apps::register::batch::RegisterRow| {
        if let Some(e) = &row.error {
            report_line(&bar, format!("error: {}: {e}", row.input));
        }
        bar.set_message(row.name.clone());
        bar.inc(1);
    };
    let rows = if args.sequence {
        register_sequence(&job, &inputs, &names, args.jobs, args.warm_start, on_done)?
    } else {
        register_many(&job, &inputs, &names, args.jobs, args.resume, on_done)?
    };
    bar.finish_and_clear();
    let [csv, _] = write_summary(output, &rows)?;
    let seconds = clock.elapsed().as_secs_f64();
    let failed = rows.iter().filter(|r| !r.ok()).count();
    let not_ok = rows
        .iter()
        .filter(|r| r.ok() && r.verdict.as_deref() != Some("ok"))
        .count();
    if !args.quiet {
        outln!(
            "registered {} of {} scans in {seconds:.1} s ({:.2} scans/min) into {}; table {}",
            rows.len() - failed,
            rows.len(),
            60.0 * rows.len() as f64 / seconds,
            output.display(),
            csv.display()
        );
    }
    if args.sequence && !args.quiet {
        let jitter: Vec<f64> = rows.iter().filter_map(|r| r.jitter_mean).collect();
        if !jitter.is_empty() {
            outln!(
                "sequence: mean jitter {:.4e} (mean over {} frames; per frame in {})",
                jitter.iter().sum::<f64>() / jitter.len() as f64,
                jitter.len(),
                csv.display()
            );
        }
    }
    if not_ok > 0 {
        eprintln!(
            "warning: {not_ok} registered scans have a verdict other than ok (their reasons in {})",
            csv.display()
        );
    }
    let usable = rows
        .iter()
        .filter(|r| {
            r.ok()
                && (r.verdict.as_deref() == Some("ok")
                    || (args.model_include_doubtful && r.verdict.as_deref() == Some("doubtful")))
        })
        .count();
    if !args.no_model {
        if usable >= 2 {
            model(output, args.model_include_doubtful, args.quiet)?;
        } else if !args.quiet {
            eprintln!(
                "note: no shape model: {usable} scans qualify, 2 are needed (--model-include-doubtful counts doubtful ones)"
            );
        }
    }
    if failed > 0 {
        bail!(
            "{failed} of {} scans failed (listed with their reasons in {})",
            rows.len(),
            csv.display()
        );
    }
    Ok(())
}

/// Builds the shape model of the registration folder `dir` into `dir/model/`.
fn model(dir: &Path, include_doubtful: bool, quiet: bool) -> anyhow::Result<()> {
    let (summary, written) =
        surfmap::apps::register::model_folder::build_model(dir, include_doubtful)
            .with_context(|| format!("cannot build the shape model of {}", dir.display()))?;
    if !quiet {
        let pct = |k: usize| {
            100.0
                * summary
                    .explained
                    .get(k.wrapping_sub(1))
                    .copied()
                    .unwrap_or(0.0)
        };
        outln!(
            "shape model of {} scans ({} left out): {} modes; 90 % of the variance in {}, 95 % in {}, 99 % in {}; mode 1 {:.1} %, modes 1-3 {:.1} %",
            summary.scans.len(),
            summary.left_out.len(),
            summary.variances.len(),
            summary.modes_90,
            summary.modes_95,
            summary.modes_99,
            pct(1),
            pct(3.min(summary.variances.len())),
        );
        for p in &written {
            outln!("  {}", p.display());
        }
    }
    Ok(())
}

/// A match error worded as `surfmap match` words it, A named the template, B the scan.
fn match_error_message(e: &MatchError) -> String {
    worded_match_error(e, "the template", "the scan")
}

/// The scan files named by `args`: files as given (a missing one fails in its row),
/// every mesh file of a folder (sorted), and the files a glob pattern's last component
/// matches (sorted). A folder or pattern with no mesh file is an error.
fn expand_scans(args: &[PathBuf]) -> anyhow::Result<Vec<PathBuf>> {
    let is_mesh = |p: &Path| p.is_file() && surfmap::mesh::io::Format::from_path(p).is_some();
    let mut out = Vec::new();
    for arg in args {
        let name = arg
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let listed = |dir: &Path, keep: &dyn Fn(&Path) -> bool| -> anyhow::Result<Vec<PathBuf>> {
            let mut found: Vec<PathBuf> = std::fs::read_dir(dir)
                .with_context(|| format!("cannot list the scans in {}", dir.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| keep(p))
                .collect();
            found.sort();
            Ok(found)
        };
        let found = if arg.is_dir() {
            listed(arg, &is_mesh)?
        } else if name.contains(['*', '?']) {
            let dir = match arg.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
            listed(dir, &|p: &Path| {
                p.is_file()
                    && p.file_name()
                        .is_some_and(|n| wildcard_match(&name, &n.to_string_lossy()))
            })?
        } else {
            vec![arg.clone()]
        };
        if found.is_empty() {
            bail!(
                "no scan in {}: give mesh files (OBJ, OFF, PLY), a folder holding some, or a pattern such as 'scans/*.ply'",
                arg.display()
            );
        }
        out.extend(found);
    }
    Ok(out)
}

/// Whether `text` matches the shell pattern `pattern` (`*`: any run of characters,
/// `?`: one character, anything else itself).
fn wildcard_match(pattern: &str, text: &str) -> bool {
    let (p, t): (Vec<char>, Vec<char>) = (pattern.chars().collect(), text.chars().collect());
    // Greedy matching with backtracking to the last `*`.
    let (mut i, mut j, mut star, mut mark) = (0, 0, None, 0);
    while j < t.len() {
        if i < p.len() && (p[i] == '?' || p[i] == t[j]) {
            i += 1;
            j += 1;
        } else if i < p.len() && p[i] == '*' {
            star = Some(i);
            mark = j;
            i += 1;
        } else if let Some(s) = star {
            i = s + 1;
            mark += 1;
            j = mark;
        } else {
            return false;
        }
    }
    p[i..].iter().all(|&c| c == '*')
}

#[cfg(test)]
mod tests {
    use super::wildcard_match;

    #[test]
    fn patterns_match_as_a_shell_does() {
        assert!(wildcard_match("*.ply", "face01.ply"));
        assert!(!wildcard_match("*.ply", "face01.obj"));
        assert!(wildcard_match("face??.*", "face01.obj"));
        assert!(!wildcard_match("face??.*", "face1.obj"));
        assert!(wildcard_match("*a*b*", "xxaYYbzz"));
        assert!(!wildcard_match("*a*b", "xxaYYbzz"));
        assert!(wildcard_match("*", ""));
    }
}
