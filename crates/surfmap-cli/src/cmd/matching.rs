//! `surfmap match A B -o DIR`: a fold-free correspondence from surface A onto surface B
//! (thesis §2.2, §3.2): both are flattened and turned into geometry images, φ is
//! found coarse to fine, and the per-vertex table, A placed on B, φ and a report are
//! written into DIR (library: `surfmap::matching`).

use std::path::PathBuf;

use super::advice::{match_defect_message, worded_flatten_error};
use anyhow::Context;
use surfmap::TriMesh;
use surfmap::matching::{
    Advanced, Align, FeaturesStart, Guidance, HoleFeatures, Landmarks, MatchError, MatchInput,
    MatchOptions, OptionError, PositionWeight, ScaleB, SearchWhen, Verdict, Weights, match_meshes,
};
use surfmap::mesh::repair::FaceOrigins;
use surfmap::raster::FeatureFile;

use super::{RepairArgs, load_mesh};

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum AlignArg {
    /// From features/landmarks when five or more are given, else from the shapes in space (fewer still guide the solve: a plane fitted to so few points cannot tell a misplaced one).
    Auto,
    /// From the features/landmarks (an error with fewer than two; two keep the size the meshes' units give).
    Features,
    /// From the shapes in space (trimmed point-to-plane ICP), even with features.
    Shape,
    /// The flattened domains as placed in ω.
    None,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum SearchArg {
    /// No search: the solve from the alignment's start.
    Off,
    /// Only when the start comes from the shapes in space (no features or landmarks).
    Shape,
    /// After every alignment.
    Always,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum FeaturesStartArg {
    /// The features' similarity of the planes, and (with three or more) their rigid
    /// alignment refined in space: the coarsest level is solved from both and the
    /// second kept when it ends lower without matching less (with two, `--align features`,
    /// the second is the shapes' own alignment in space).
    Both,
    /// The features' similarity of the planes only.
    Plane,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CropArg {
    /// Crop a surface whose far pieces make up at least 35 % of its area.
    Auto,
    /// Match the surfaces whole.
    Off,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum HoleArg {
    /// Pair hole rims when both surfaces have the same number of filled holes.
    Auto,
    /// Pair hole rims; an error when the hole counts differ.
    On,
    Off,
}

#[derive(clap::Args)]
pub struct Args {
    /// Surface A (OBJ, OFF or PLY): a disc, possibly with holes.
    pub a: PathBuf,
    /// Surface B.
    pub b: PathBuf,
    /// Output folder (created if missing).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Landmarks: JSON `{"names": [...], "A": [vertex ids of A], "B": [vertex ids of B]}`.
    #[arg(long, value_name = "L.json")]
    pub landmarks: Option<PathBuf>,
    /// Feature curves of A, as for `surfmap images --features`; paired with B's by name.
    #[arg(long, value_name = "FA.json", requires = "features_b")]
    pub features_a: Option<PathBuf>,
    /// Feature curves of B.
    #[arg(long, value_name = "FB.json", requires = "features_a")]
    pub features_b: Option<PathBuf>,
    /// Hole rims as paired features (after alignment).
    #[arg(long, value_enum, default_value = "auto")]
    pub hole_features: HoleArg,
    /// Match each hole rim as one closed curve; by default an elongated pair (a mouth,
    /// an eye) is matched as two arcs split at its corners, upper lip to upper lip.
    #[arg(long)]
    pub whole_hole_rims: bool,
    /// Refuse surfaces with holes instead of filling them for the solve.
    #[arg(long)]
    pub no_fill_holes: bool,
    /// Cut each surface down to the part it shares with the other before matching
    /// (`auto`): aligned in space, a surface's large pieces far from the other — the back
    /// of a whole head against a face crop, shoulders — are cut off when they are at
    /// least 35 % of its area, so that both flattenings spend their square on what can
    /// match. Their vertices are reported unmatched; the outputs keep the files'
    /// numbering. `off` matches the surfaces whole (as does `--hole-features on`, whose
    /// rims are paired as given).
    #[arg(long, value_enum, default_value = "auto")]
    pub crop_overlap: CropArg,
    /// Finest grid, 2^k + 1 nodes per side.
    #[arg(long, default_value_t = 257)]
    pub size: usize,
    /// Energy weights β: bending, regularization, features (thesis 2.16).
    #[arg(long, value_name = "B,R,F", value_delimiter = ',')]
    pub beta: Option<Vec<f64>>,
    /// A fixed weight of the 3D position term (0 = the thesis energy alone); by default
    /// it is 0.2/σ², σ the surfaces' RMS distance along B's normals after aligning them
    /// in space (in units of √area, counted between 0.001 and 0.01: so between 2000 and
    /// 2·10⁵).
    #[arg(long)]
    pub position_weight: Option<f64>,
    /// Initial alignment.
    #[arg(long, value_enum, default_value = "auto")]
    pub align: AlignArg,
    /// Where φ starts with features or landmarks (`--align auto` or `features`).
    #[arg(long, value_enum, default_value = "both")]
    pub features_start: FeaturesStartArg,
    /// Search the rotation and translation of φ (and its scale, with --search-candidates
    /// DEG,SCALE and SCALE > 0) that lowers the matching energy per matched area on a
    /// coarse level, and go on from it when the coarsest level
    /// solved from it ends lower without matching less (and, when the alignment's start
    /// matches A at a plausible size, 1/3–3 times its area on B, does too).
    #[arg(long, value_enum, default_value = "shape")]
    pub similarity_search: SearchArg,
    /// Extra starts of the similarity search: rotated by ±DEG degrees and scaled by
    /// (1 ± SCALE) (the lowest energy is kept); 0,0 searches from the start alone. A SCALE
    /// above 0 also lets the search change the scale (by default it keeps it).
    #[arg(long, value_name = "DEG,SCALE", value_delimiter = ',')]
    pub search_candidates: Option<Vec<f64>>,
    /// Level k of the similarity search's energy (grid 2^k + 1; at least 1, at most the
    /// solve's coarsest level, 6).
    #[arg(long, value_name = "K", default_value_t = surfmap::matching::options::SEARCH_LEVEL)]
    pub search_level: usize,
    /// Most energy evaluations per level, counted at the finest level (a level 2^j
    /// times coarser may use 4^j times as many): a level stops there if its energy
    /// has not stopped decreasing first (relative decrease 10⁻⁶, 10⁻⁵ on the finest
    /// level, or 300 iterations), and the whole solve after 220. 0 lifts both caps:
    /// every level runs to its stopping rule (the thesis's). Default 40: more changed no
    /// accuracy measure on 28 face pairs and costs time (BENCHMARKS.md). With the relief
    /// (--relief) the levels between the coarsest and the finest get 0.6 of theirs, and
    /// the coarsest level's phase with the relief a quarter of its own on top.
    #[arg(long, value_name = "N", default_value_t = surfmap::matching::options::BUDGET)]
    pub budget: usize,
    /// Keep the vertices of image triangles that turn over or collapse in space
    /// (by default they are reported unmatched).
    #[arg(long)]
    pub keep_folds: bool,
    /// Rings of vertices next to the matched region that may be completed from their
    /// matched neighbours where φ just misses B (its rim, the fill of its holes), after
    /// the two rings of matched vertices next to them are smoothed; 0 reports them
    /// unmatched and keeps φ's matches as they are.
    #[arg(long, value_name = "N", default_value_t = surfmap::matching::options::COMPLETE_RINGS)]
    pub complete_rings: usize,
    /// How far past B's outer rim (in mean edges of the vertex) the prediction of a vertex
    /// that φ left unmatched may fall and the vertex still be matched to the rim. The
    /// default, half an edge, keeps partial correspondence (the part of A beyond B's crop
    /// unmatched); more matches more of A along a tight crop of B, and more vertices that
    /// have no counterpart (BENCHMARKS.md: 3 edges matches every vertex near the rim).
    #[arg(long, value_name = "EDGES", default_value_t = surfmap::matching::options::RIM_TOLERANCE)]
    pub rim_tolerance: f64,
    /// Compare the surfaces in space after their smooth difference in shape: the position
    /// term's residual smoothed by a Gaussian this wide (a fraction of the parameter
    /// square) becomes part of its target, so only the detail pulls; the
    /// coarsest level places the match without it first. For faces of different people
    /// it matches more of the face closely (FLAME identity pairs: 69 → 74 % within 0.02;
    /// BENCHMARKS.md, "The position term's relief"). 0: off (the fitted map alone).
    #[arg(long, value_name = "WIDTH", default_value_t = surfmap::matching::POSITION_RELIEF)]
    pub relief: f64,
    /// Rings of A's vertices around each hole rim that follow it when the rim is carried
    /// exactly onto B's paired rim (holes match holes: eyes to eyes, mouth to mouth);
    /// wider where the rim moves far; 0 leaves the rims where φ puts them.
    #[arg(long, value_name = "N", default_value_t = surfmap::matching::options::RIM_FIT_RINGS)]
    pub rim_fit_rings: usize,
    /// Leave the landmarks where φ puts them: by default each landmark of A is matched
    /// exactly to its vertex of B in the output, and the vertices around it follow.
    #[arg(long)]
    pub free_landmarks: bool,
    /// B's size for the match: `auto` keeps it unless the two surfaces' sizes (√area)
    /// differ by more than 5 times — then they are taken to be in different units (mm,
    /// cm, m) and B is multiplied by the nearest power of ten; a number multiplies B by
    /// it (1: as given). The outputs stay in B's own units.
    #[arg(long, value_name = "auto|FACTOR", default_value = "auto")]
    pub scale_b: String,
    /// Also draw pictures: checkerboard carried across, deformed grid, energy staircase.
    #[arg(long)]
    pub pictures: bool,
    /// Report a match whose verdict is not `ok` as it is, without first trying other
    /// starts (the alignment's other poses in space, the start turned).
    #[arg(long)]
    pub no_recover: bool,
    /// Keep the weights as given when one face's mouth is open and the other's closed
    /// (lip gap over mouth width ≥ 0.8 and at least twice the other's). By default the
    /// lip arcs then lead: the feature weight ×40 and the automatic position weight
    /// capped at 1000, so that the chin follows the jaw; with landmarks or features the
    /// solve starts from their alignment refined in space alone (match.json:
    /// `alignment.mouth`).
    #[arg(long)]
    pub no_open_mouth: bool,
    /// Exit with code 3 when the match's verdict is not `ok` (doubtful or failed; the
    /// match is still written, its verdict and reasons in match.json's `confidence`).
    #[arg(long)]
    pub strict: bool,
    /// Print nothing but errors and warnings (a verdict other than `ok` is a warning).
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    pub repair: RepairArgs,
}

/// The flags as [`MatchOptions`], checked.
fn match_options(args: &Args) -> Result<MatchOptions, OptionError> {
    let mut o = MatchOptions::default();
    o.size = args.size;
    if let Some(b) = &args.beta {
        o.weights = Weights::from_slice(b)?;
    }
    if let Some(w) = args.position_weight {
        o.position_weight = PositionWeight::Fixed(w);
    }
    o.align = match args.align {
        AlignArg::Auto => Align::Auto,
        AlignArg::Features => Align::Features,
        AlignArg::Shape => Align::Shape,
        AlignArg::None => Align::None,
    };
    o.features_start = match args.features_start {
        FeaturesStartArg::Both => FeaturesStart::Both,
        FeaturesStartArg::Plane => FeaturesStart::Plane,
    };
    o.similarity_search = match args.similarity_search {
        SearchArg::Off => SearchWhen::Off,
        SearchArg::Shape => SearchWhen::Shape,
        SearchArg::Always => SearchWhen::Always,
    };
    o.budget = args.budget;
    o.fill_holes = !args.no_fill_holes;
    o.hole_features = match args.hole_features {
        HoleArg::Auto => HoleFeatures::Auto,
        HoleArg::On => HoleFeatures::On,
        HoleArg::Off => HoleFeatures::Off,
    };
    o.split_hole_rims = !args.whole_hole_rims;
    o.crop_overlap = args.crop_overlap == CropArg::Auto;
    o.scale_b = match args.scale_b.as_str() {
        "auto" => ScaleB::Auto,
        text => ScaleB::Factor(text.parse::<f64>().unwrap_or(f64::NAN)),
    };
    o.keep_folds = args.keep_folds;
    o.pin_landmarks = !args.free_landmarks;
    o.strict = args.strict;
    o.advanced = Advanced {
        rim_fit_rings: args.rim_fit_rings,
        complete_rings: args.complete_rings,
        rim_tolerance: args.rim_tolerance,
        relief: args.relief,
        search_level: args.search_level,
        search_candidates: match args.search_candidates.as_deref() {
            None => o.advanced.search_candidates,
            Some(&[deg, scale]) => [deg, scale],
            Some(other) => return Err(OptionError::SearchCandidates(other.to_vec())),
        },
        recover: !args.no_recover,
        open_mouth: !args.no_open_mouth,
    };
    o.validate()?;
    Ok(o)
}

fn read_features(path: &Option<PathBuf>, vertices: usize) -> anyhow::Result<Option<FeatureFile>> {
    let Some(p) = path else { return Ok(None) };
    let json = std::fs::read_to_string(p)
        .with_context(|| format!("cannot read features file {}", p.display()))?;
    Ok(Some(FeatureFile::parse(&json, vertices).with_context(
        || format!("invalid features file {}", p.display()),
    )?))
}

pub fn run(args: Args) -> anyhow::Result<()> {
    // Repaired meshes are matched; the outputs (and the landmark and feature ids read)
    // are numbered as the files are.
    let input_a = load_mesh(&args.a)?.mesh;
    let input_b = load_mesh(&args.b)?.mesh;
    let repaired = |input| -> anyhow::Result<Option<(TriMesh, FaceOrigins)>> {
        let (mesh, origins) = args.repair.apply_tracked(input, args.quiet)?;
        Ok(origins.map(|o| (mesh, o)))
    };
    let a = MatchInput {
        given: &input_a,
        repaired: repaired(&input_a)?,
    };
    let b = MatchInput {
        given: &input_b,
        repaired: repaired(&input_b)?,
    };
    let options = match_options(&args)
        .map_err(|e| anyhow::anyhow!(e.worded(&format!("--{}", e.setting().replace('_', "-")))))?;
    // The guidance as the files number it.
    let guidance = Guidance {
        landmarks: match &args.landmarks {
            Some(p) => {
                let json = std::fs::read_to_string(p)
                    .with_context(|| format!("cannot read landmarks file {}", p.display()))?;
                Some(serde_json::from_str::<Landmarks>(&json).with_context(|| {
                    format!(
                        "invalid landmarks file {}: expected {{\"names\": [...], \"A\": [vertex ids], \"B\": [vertex ids]}}",
                        p.display()
                    )
                })?)
            }
            None => None,
        },
        features_a: read_features(&args.features_a, input_a.num_vertices())?,
        features_b: read_features(&args.features_b, input_b.num_vertices())?,
    };
    let (mut matched, refused) = match match_meshes(a, b, &guidance, &options) {
        Ok(m) => Ok((m, false)),
        Err(MatchError::NotTrusted(m)) => Ok((*m, true)),
        Err(e) => Err(e),
    }
    .map_err(|e| match &e {
        // The flattening's remedies as this command's flags.
        MatchError::Flatten { surface, source } => {
            match worded_flatten_error(source, match_defect_message) {
                Some(message) => anyhow::anyhow!(
                    "cannot flatten {}: {message}",
                    surface.map_or("the surface".to_string(), |s| format!("surface {s}"))
                ),
                None => e.into(),
            }
        }
        _ => e.into(),
    })
    .with_context(|| {
        format!(
            "cannot match {} onto {}",
            args.a.display(),
            args.b.display()
        )
    })?;
    matched.report.inputs.a.path = Some(args.a.display().to_string());
    matched.report.inputs.b.path = Some(args.b.display().to_string());
    let written = matched
        .write_folder(&args.output, args.pictures)
        .with_context(|| format!("cannot write the match into {}", args.output.display()))?;
    if !args.quiet {
        outln!("{}", matched.report.summary());
        outln!("wrote into {}:", args.output.display());
        for p in &written {
            outln!(
                "  {}",
                p.file_name()
                    .map_or(p.display().to_string(), |n| n.to_string_lossy().into())
            );
        }
    }
    // Doubts are printed even with --quiet (and kept in match.json's `warnings`).
    for w in &matched.report.warnings {
        eprintln!("warning: {w}");
    }
    let confidence = &matched.report.confidence;
    if refused {
        return Err(NotTrusted(format!(
            "{} (the match is written into {}; --strict refuses it)",
            confidence.line(),
            args.output.display()
        ))
        .into());
    }
    if confidence.verdict != Verdict::Ok {
        eprintln!("warning: {}", confidence.line());
    }
    Ok(())
}

/// `--strict` refused the match: its verdict is not `ok` (exit code 3).
#[derive(Debug)]
pub struct NotTrusted(pub String);

impl std::fmt::Display for NotTrusted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for NotTrusted {}
