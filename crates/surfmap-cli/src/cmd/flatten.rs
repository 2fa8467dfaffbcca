//! `surfmap flatten IN -o OUT.obj`: flip-free flattening of any connected, orientable,
//! manifold mesh: a disc as it is, holes filled for the solve (or cut open with
//! `--cut-holes`), closed and higher-genus surfaces cut open along seams (per-corner
//! `vt` in the OBJ).
//! `surfmap flatten A B … -o DIR/`: many meshes in parallel ([`super::batch`]).

use super::advice::{defect_message, flatten_error, option_message};
use super::{RepairArgs, load_mesh};
use anyhow::{Context, bail};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::Path;
use std::path::PathBuf;
use surfmap::measure::{Measure, per_triangle_measure};
use surfmap::mesh::io::ObjMaterial;
use surfmap::render;
use surfmap::{
    Alpha, Bijective, Cut, DistortionCuts, EnergyKind, FlatMesh, FlattenOptions, FlattenSettings,
    Flattening, Guarantee, IterationLog, MaxDistortion, MultilevelKind, Preset, SettingsError,
    StartKind, TriMesh, UvLayout, flatten_to_mesh, flatten_with_progress, write_obj,
};

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum PresetChoice {
    /// α = (0.005, 0.005, 0.99): nearly conformal (angle-preserving).
    Conformal,
    /// α = (1/3, 1/3, 1/3): length, area and angle weighted equally.
    Balanced,
    /// Area-preserving emphasis.
    Area,
    /// Length-preserving emphasis.
    Length,
}

impl From<PresetChoice> for Preset {
    fn from(choice: PresetChoice) -> Self {
        match choice {
            PresetChoice::Conformal => Preset::Conformal,
            PresetChoice::Balanced => Preset::Balanced,
            PresetChoice::Area => Preset::Area,
            PresetChoice::Length => Preset::Length,
        }
    }
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum EnergyChoice {
    /// Litke's energy (thesis (2.5)) with the chosen α.
    Litke,
    /// Symmetric Dirichlet: σ1² + σ2² + σ1⁻² + σ2⁻² (as libigl SLIM minimizes).
    Sd,
    /// MIPS: σ1/σ2 + σ2/σ1 (conformal; scale is free).
    Mips,
    /// As-rigid-as-possible: (σ1 − 1)² + (σ2 − 1)².
    Arap,
}

impl From<EnergyChoice> for EnergyKind {
    fn from(choice: EnergyChoice) -> Self {
        match choice {
            EnergyChoice::Litke => EnergyKind::Litke,
            EnergyChoice::Sd => EnergyKind::SymmetricDirichlet,
            EnergyChoice::Mips => EnergyKind::Mips,
            EnergyChoice::Arap => EnergyKind::Arap,
        }
    }
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum StartChoice {
    /// LSCM, or mean-value coordinates if LSCM flips a triangle; multilevel for large
    /// meshes (see --multilevel).
    Auto,
    Lscm,
    MeanValue,
}

impl From<StartChoice> for StartKind {
    fn from(choice: StartChoice) -> Self {
        match choice {
            StartChoice::Auto => StartKind::Auto,
            StartChoice::Lscm => StartKind::Lscm,
            StartChoice::MeanValue => StartKind::MeanValue,
        }
    }
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum BijectiveChoice {
    /// Solve again with the boundary barrier when the result's boundary overlaps itself.
    Auto,
    /// Always solve with the boundary barrier.
    Always,
    /// Never: flip-free only; the boundary may overlap itself.
    Off,
}

impl From<BijectiveChoice> for Bijective {
    fn from(choice: BijectiveChoice) -> Self {
        match choice {
            BijectiveChoice::Auto => Bijective::WhenOverlapping,
            BijectiveChoice::Always => Bijective::Always,
            BijectiveChoice::Off => Bijective::Off,
        }
    }
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum MultilevelChoice {
    /// For meshes of 15k faces and more.
    Auto,
    On,
    Off,
}

impl From<MultilevelChoice> for MultilevelKind {
    fn from(choice: MultilevelChoice) -> Self {
        match choice {
            MultilevelChoice::Auto => MultilevelKind::Auto,
            MultilevelChoice::On => MultilevelKind::On,
            MultilevelChoice::Off => MultilevelKind::Off,
        }
    }
}

#[derive(clap::Args)]
pub struct Args {
    /// Input meshes (OBJ, OFF or PLY): connected, orientable, manifold (a disc, a disc
    /// with holes, a closed surface, handles). Several inputs are flattened in parallel
    /// into the folder -o (a batch: a bad mesh is reported and skipped).
    #[arg(required = true, num_args = 1..)]
    pub inputs: Vec<PathBuf>,
    /// Output OBJ with texture coordinates (`vt`; per corner, split along the seams,
    /// when the surface was cut); for a batch a folder (ending in `/`, or existing),
    /// which receives NAME.obj and the report NAME.json per mesh and summary.csv.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Batch: meshes flattened at the same time; 0 = one per core. The batch runs on
    /// this many threads in total.
    #[arg(short, long, default_value_t = 0)]
    pub jobs: usize,
    #[command(flatten)]
    pub solver: SolverArgs,
    /// Scale and translate the UVs into `[0,1]²` (aspect ratio kept).
    #[arg(long)]
    pub normalize: bool,
    /// Write the flat mesh itself: positions (u, v, 0), for viewing the layout.
    #[arg(long)]
    pub uv_as_positions: bool,
    /// Reference a texture image from the OBJ (writes OUT.mtl with map_Kd).
    #[arg(long)]
    pub texture: Option<PathBuf>,
    /// Write a JSON report (measures, solver log, timings) here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write pictures into this folder: UV layout coloured by distortion, checkerboard
    /// render, energy/gradient decay plot.
    #[arg(long)]
    pub pictures: Option<PathBuf>,
    /// Do not print the summary line or progress.
    #[arg(short, long)]
    pub quiet: bool,
    /// Fill every boundary loop but the longest (eyes, mouth, scan holes) with a fan for
    /// the flattening; the output keeps the original faces, holes stay open in the UVs.
    /// This is the default; the flag is kept for scripts.
    #[arg(long, conflicts_with = "cut_holes")]
    pub fill_holes: bool,
    /// Open the holes with seams to the outer boundary instead of filling them.
    #[arg(long)]
    pub cut_holes: bool,
    /// Keep the boundary from overlapping itself (a bijective map) with a boundary
    /// barrier: when the unconstrained result overlaps (auto), always, or never.
    #[arg(long, value_enum, default_value = "auto")]
    pub bijective: BijectiveChoice,
    /// Cut along these seams instead of the automatic cut graph: an OBJ with `l` lines
    /// (as `--seams` writes; 1-based vertex indices), or a text file with one edge per
    /// line, two 0-based vertex indices (`#` starts a comment).
    #[arg(long, value_name = "EDGES")]
    pub cut_along: Option<PathBuf>,
    /// Write the seams (the cut edges) as an OBJ: the input's vertices and one `l` line
    /// per seam edge (nothing is written when the surface was not cut). In a batch,
    /// give a folder (ending in `/`): it receives NAME.seams.obj per cut mesh.
    #[arg(long, value_name = "SEAMS.obj")]
    pub seams: Option<PathBuf>,
    /// Cut the chart open where the distortion concentrates until its mean symmetric
    /// Dirichlet distortion (area-weighted mean of (σ1² + σ2² + σ1⁻² + σ2⁻²)/4 at equal
    /// UV and 3D area; 1 for an isometry) is at most D. Not met within --max-cut-rounds:
    /// the best map is written and the command fails, saying so.
    #[arg(long, value_name = "D", allow_negative_numbers = true)]
    pub max_distortion: Option<f64>,
    /// Cut rounds at most for --max-distortion (each cuts up to four seam paths and
    /// flattens again).
    #[arg(long, value_name = "N", default_value_t = surfmap::param::optcuts::DEFAULT_MAX_ROUNDS, requires = "max_distortion")]
    pub max_cut_rounds: usize,
    #[command(flatten)]
    pub repair: RepairArgs,
}

/// The flattening's options, shared by every command that flattens (`flatten`, `bake`).
#[derive(clap::Args)]
pub struct SolverArgs {
    /// Distortion trade-off preset.
    #[arg(long, value_enum, default_value = "balanced")]
    pub preset: PresetChoice,
    /// Custom α = L,A,C (length, area, angle weights; normalized to sum 1). Overrides --preset.
    #[arg(long, value_parser = parse_alpha, allow_hyphen_values = true)]
    pub alpha: Option<[f64; 3]>,
    /// Energy density.
    #[arg(long, value_enum, default_value = "litke")]
    pub energy: EnergyChoice,
    /// Continuation: minimize first at this α = L,A,C, then move to the target α in steps.
    #[arg(long, value_parser = parse_alpha, allow_hyphen_values = true)]
    pub from_alpha: Option<[f64; 3]>,
    /// Initial map (an explicit one is computed on the full mesh: no multilevel start).
    #[arg(long, value_enum, default_value = "auto")]
    pub start: StartChoice,
    /// Multilevel start (with --start auto): flatten a decimated copy, re-insert the
    /// removed vertices flip-free, then run Newton on the full mesh (far fewer
    /// full-size iterations).
    #[arg(long, value_enum, default_value = "auto")]
    pub multilevel: MultilevelChoice,
    /// Vertices of the decimated copy for --multilevel (default: 1/20 of the mesh,
    /// between 500 and 20000).
    #[arg(long)]
    pub coarse_vertices: Option<usize>,
    /// Newton iteration cap (per continuation stage).
    #[arg(long, default_value_t = 200)]
    pub max_iters: usize,
    /// Stop when half the Newton decrement (energy per unit area) is below this.
    #[arg(long, default_value_t = 1e-12, allow_negative_numbers = true)]
    pub tolerance: f64,
    /// Armijo sufficient-decrease constant c (thesis: 0.5).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub armijo_c: f64,
}

pub fn parse_alpha(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected three comma-separated numbers L,A,C (e.g. 1,1,1), got {s:?}"
        ));
    }
    let mut out = [0.0; 3];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = p
            .parse()
            .map_err(|_| format!("{p:?} is not a number (in α = {s:?})"))?;
    }
    Ok(out)
}

pub fn alpha(a: [f64; 3]) -> anyhow::Result<Alpha> {
    Alpha::new(a[0], a[1], a[2]).context("invalid α")
}

/// The library options the command line asks for (the library resolves and checks
/// them, [`FlattenSettings::options`]).
pub fn options(args: &SolverArgs, fill_holes: bool) -> anyhow::Result<FlattenOptions> {
    let settings = FlattenSettings {
        preset: args.preset.into(),
        alpha: args.alpha,
        energy: args.energy.into(),
        from_alpha: args.from_alpha,
        start: args.start.into(),
        multilevel: args.multilevel.into(),
        coarse_vertices: args.coarse_vertices,
        max_iterations: args.max_iters,
        tolerance: args.tolerance,
        armijo_c: args.armijo_c,
    };
    let opts = settings.options().map_err(settings_message)?;
    // One UV per vertex for every command but `flatten` (`flatten_options`).
    Ok(opts.with_fill_holes(fill_holes).with_cut(Cut::Never))
}

/// Settings that make no options, as the flags that set them.
fn settings_message(e: SettingsError) -> anyhow::Error {
    match e {
        SettingsError::Alpha(e) | SettingsError::FromAlpha(e) => {
            anyhow::Error::new(e).context("invalid α")
        }
        SettingsError::Continuation(_) => {
            anyhow::anyhow!("--from-alpha is a continuation in Litke's α; it needs --energy litke")
        }
        SettingsError::MultilevelNeedsAutoStart => anyhow::anyhow!(
            "--multilevel on needs --start auto (an explicit start map is computed on the full mesh)"
        ),
        SettingsError::Option(e) => anyhow::anyhow!(option_message(&e)),
    }
}

/// The options of `surfmap flatten` (one mesh or a batch): the solver's, with the holes
/// filled unless `--cut-holes`, surfaces that are not discs cut open (automatically or
/// along `--cut-along`), and the `--bijective` mode.
pub fn flatten_options(args: &Args) -> anyhow::Result<FlattenOptions> {
    let cut = match &args.cut_along {
        Some(path) => Cut::Along(read_seams(path)?),
        None => Cut::Auto,
    };
    let opts = FlattenOptions {
        max_distortion: args.max_distortion.map(|bound| MaxDistortion {
            bound,
            max_rounds: args.max_cut_rounds,
        }),
        ..options(&args.solver, !args.cut_holes)?
            .with_cut(cut)
            .with_bijective(args.bijective.into())
    };
    opts.validate()
        .map_err(|e| anyhow::anyhow!(option_message(&e)))?;
    Ok(opts)
}

/// The layout `--normalize` and `--uv-as-positions` ask for.
pub fn layout(args: &Args) -> UvLayout {
    UvLayout {
        normalize: args.normalize,
        uv_as_positions: args.uv_as_positions,
    }
}

/// Runs `solve` with a progress spinner on a terminal for meshes of more than 20k
/// faces (`faces`), unless `quiet`.
fn with_progress<T>(
    faces: usize,
    quiet: bool,
    solve: impl FnOnce(&mut dyn FnMut(&IterationLog)) -> T,
) -> T {
    let bar = (!quiet && std::io::stderr().is_terminal() && faces > 20_000).then(|| {
        let b = ProgressBar::new_spinner();
        b.set_style(
            ProgressStyle::with_template("{spinner} {elapsed} {msg}").expect("valid template"),
        );
        b
    });
    let result = solve(&mut |it| {
        if let Some(b) = &bar {
            b.set_message(format!(
                "stage {} iteration {}: energy {:.6}",
                it.stage, it.iteration, it.energy
            ));
            b.tick();
        }
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    result
}

/// Says on stderr that holes were filled (unless `quiet`).
fn note_filled_holes(result: &Flattening, quiet: bool) {
    if !quiet && result.holes_filled > 0 {
        eprintln!(
            "repair: filled {} holes for the flattening (the output keeps them open)",
            result.holes_filled
        );
    }
}

/// Runs the flattening with a progress spinner on a terminal; errors name the flags
/// that fix them.
pub fn flatten_mesh(
    mesh: &TriMesh,
    opts: &FlattenOptions,
    quiet: bool,
) -> anyhow::Result<Flattening> {
    let result = with_progress(mesh.triangles.len(), quiet, |progress| {
        flatten_with_progress(mesh, opts, progress)
    })
    .map_err(flatten_error)?;
    note_filled_holes(&result, quiet);
    Ok(result)
}

/// [`flatten_mesh`] giving the mesh to write too ([`surfmap::flatten_to_mesh`]).
pub fn flatten_for_writing(
    mesh: TriMesh,
    opts: &FlattenOptions,
    layout: UvLayout,
    quiet: bool,
) -> anyhow::Result<FlatMesh> {
    let flat = with_progress(mesh.triangles.len(), quiet, |progress| {
        flatten_to_mesh(mesh, opts, layout, progress)
    })
    .map_err(flatten_error)?;
    note_filled_holes(&flat.flattening, quiet);
    Ok(flat)
}

/// Reads seams for `--cut-along`: OBJ `l` lines (1-based, consecutive pairs of a
/// polyline), or lines of two 0-based vertex indices.
pub fn read_seams(path: &Path) -> anyhow::Result<Vec<[u32; 2]>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read seams from {}", path.display()))?;
    let obj = text.lines().any(|l| l.trim_start().starts_with("l "));
    let mut seams = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        let bad = || {
            anyhow::anyhow!(
                "{}:{}: expected {}, got {line:?}",
                path.display(),
                number + 1,
                if obj {
                    "`l A B …` with 1-based vertex indices"
                } else {
                    "two 0-based vertex indices"
                }
            )
        };
        let fields: Vec<&str> = line.split_whitespace().collect();
        if obj {
            if fields.first() != Some(&"l") {
                continue;
            }
            let vertices: Vec<u32> = fields[1..]
                .iter()
                .map(|f| f.split('/').next().unwrap_or("").parse::<u32>())
                .collect::<Result<_, _>>()
                .map_err(|_| bad())?;
            if vertices.len() < 2 || vertices.contains(&0) {
                return Err(bad());
            }
            seams.extend(vertices.windows(2).map(|w| [w[0] - 1, w[1] - 1]));
        } else if !fields.is_empty() {
            match fields[..] {
                [a, b] => {
                    seams.push([a.parse().map_err(|_| bad())?, b.parse().map_err(|_| bad())?])
                }
                _ => return Err(bad()),
            }
        }
    }
    Ok(seams)
}

/// The `--texture` material of the OBJ written.
pub fn material(args: &Args) -> Option<ObjMaterial> {
    args.texture
        .as_ref()
        .map(|t| ObjMaterial { texture: t.clone() })
}

pub fn run(args: Args) -> anyhow::Result<()> {
    if super::batch::is_batch(&args) {
        return super::batch::run(&args);
    }
    let input = &args.inputs[0];
    let file = load_mesh(input)?;
    let opts = flatten_options(&args)?;
    let mesh = args.repair.apply(file.mesh, args.quiet)?;
    let flat = flatten_for_writing(mesh, &opts, layout(&args), args.quiet)
        .with_context(|| format!("cannot flatten {}", input.display()))?;
    // The writer's error names the file already.
    write_obj(&args.output, &flat.output, material(&args).as_ref())?;
    if let Some(path) = &args.report {
        // Measured on the written map (its own scale; the measures normalize area).
        write_json(path, &flat.report(Some(input), defect_message)?)?;
    }
    if let Some(path) = &args.seams {
        flat.write_seams(path)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let result = &flat.flattening;
    if let Some(dir) = &args.pictures {
        let written = write_pictures(dir, &flat.input, result)?;
        if !args.quiet {
            for p in written {
                eprintln!("wrote {}", p.display());
            }
        }
    }
    if !args.quiet {
        if let Some(reason) = result
            .multilevel
            .as_ref()
            .and_then(|m| m.abandoned.as_ref())
        {
            eprintln!("note: multilevel start abandoned ({reason}); used the single-level start");
        }
        outln!("{}", summary_line(input, result, &args.output));
    }
    if let Some(cuts) = result.distortion_cuts.as_ref().filter(|c| !c.met) {
        bail!(
            "the distortion bound {} was not met: the best map reaches {:.6} (one chart: {:.6}) after {} cut rounds ({}); it was written to {}. Allow more rounds (--max-cut-rounds) or a higher --max-distortion",
            cuts.bound,
            cuts.after,
            cuts.before,
            cuts.rounds,
            cut_stop_words(&cuts.stop),
            args.output.display()
        );
    }
    Ok(())
}

/// The line `surfmap flatten` prints for one mesh: what was done, the start, the
/// iterations, the energy, the guarantee, the time and the output.
fn summary_line(input: &Path, result: &Flattening, output: &Path) -> String {
    format!(
        "{}: {}{}start {}{}, {} iterations, {}, energy {:.6}, flipped triangles {}{}, {:.3} s → {}",
        input.display(),
        match &result.seams {
            None => String::new(),
            Some(s) => format!(
                "{} ({} seam edges, length {:.4}), ",
                result.describe_plan(),
                s.edges.len(),
                s.length
            ),
        },
        result
            .distortion_cuts
            .as_ref()
            .map_or_else(String::new, distortion_summary),
        result.start_description(),
        match result.warm_start_iterations {
            0 => String::new(),
            n => format!(" + {n} ARAP steps"),
        },
        result.iterations,
        if result.stop_reason == surfmap::StopReason::Stalled {
            "stopped near the minimum (scaffold: energy decrease below 1e-3 per step)"
        } else {
            convergence(result.converged)
        },
        result.energy,
        result.flipped_triangles,
        match (result.guarantee, result.barrier) {
            (Guarantee::LocallyInjective, _) => format!(
                ", boundary overlaps itself ({} crossings; see --bijective)",
                result.boundary_crossings
            ),
            (Guarantee::Bijective, true) if result.stop_reason == surfmap::StopReason::Stalled => {
                ", no overlap (scaffold)".to_string()
            }
            (Guarantee::Bijective, true) => ", no overlap (boundary barrier)".to_string(),
            (Guarantee::Bijective, false) => String::new(),
        },
        result.time_total,
        output.display()
    )
}

/// `distortion 1.3160 → 1.0416 ≤ 1.05 (2 cut rounds, 6 seam edges added, length
/// 0.3310), ` for the summary line.
fn distortion_summary(cuts: &DistortionCuts) -> String {
    format!(
        "distortion {:.4} → {:.4} {} {} ({} cut rounds, {} seam edges added, length {:.4}), ",
        cuts.before,
        cuts.after,
        if cuts.met { "≤" } else { ">" },
        cuts.bound,
        cuts.rounds,
        cuts.seam_edges_added,
        cuts.seam_length_added,
    )
}

/// Why the cut loop stopped, for people.
fn cut_stop_words(stop: &surfmap::CutStop) -> String {
    use surfmap::CutStop;
    match stop {
        CutStop::Met => "bound met".to_string(),
        CutStop::RoundCap => "round cap reached".to_string(),
        CutStop::NoProgress => "two rounds in a row gained less than 1% of the excess".to_string(),
        CutStop::NoCandidate => "no interior vertex left to cut to".to_string(),
        CutStop::SolveFailed(reason) => format!("a round's flattening failed: {reason}"),
    }
}

/// Writes `value` as pretty JSON (atomically).
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> anyhow::Result<()> {
    surfmap::fsutil::write_json(path, value)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Writes the UV layout (coloured by angle distortion), the checkerboard render and
/// the convergence plot into `dir`; returns the paths written.
pub fn write_pictures(dir: &Path, mesh: &TriMesh, r: &Flattening) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let corners = r.corner_uvs(&mesh.triangles);
    let angle = per_triangle_measure(&mesh.positions, &mesh.triangles, &corners, Measure::Angle)?;
    let mut written = Vec::new();
    let mut save = |name: &str, img: render::RgbImage| -> anyhow::Result<()> {
        let p = dir.join(name);
        render::save_png(&p, &img).with_context(|| format!("cannot write {}", p.display()))?;
        written.push(p);
        Ok(())
    };
    save(
        "uv_layout.png",
        render::uv_layout(
            &mesh.triangles,
            &corners,
            Some((&angle, "angle")),
            "UV layout",
            (900, 900),
        ),
    )?;
    save(
        "checker.png",
        render::checker_render(
            &mesh.positions,
            &mesh.triangles,
            &corners,
            16,
            "checkerboard through the UVs",
            (900, 900),
        ),
    )?;
    // Iterate k: energy E_k (entry k) and the gradient there (recorded with entry
    // k + 1, before its step). Plotted as E_k − E_final, whose decay shows the rate.
    let last = r.log.last().map_or(f64::NAN, |l| l.energy);
    let history: Vec<(f64, f64)> = r
        .log
        .windows(2)
        .filter(|w| w[1].stage == w[0].stage)
        .map(|w| (w[0].energy - last, w[1].gradient_norm))
        .collect();
    save(
        "convergence.png",
        render::convergence_plot_labeled(&history, "E - E_FINAL (PER UNIT AREA)", (900, 600)),
    )?;
    Ok(written)
}

/// "converged" or "NOT converged", for the one-line summaries.
pub fn convergence(converged: bool) -> &'static str {
    if converged {
        "converged"
    } else {
        "NOT converged"
    }
}
