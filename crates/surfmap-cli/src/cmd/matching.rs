//! `surfmap match A B -o DIR`: a fold-free correspondence from surface A onto surface B
//! (thesis §2.2, §3.2): both are flattened and turned into geometry images, φ is
//! found coarse to fine, and the per-vertex table, A placed on B, φ and a report are
//! written into DIR (library: `surfmap::matching`).

use std::path::PathBuf;

use super::advice::{match_defect_message, worded_flatten_error};
use anyhow::{Context, bail};
use surfmap::TriMesh;
use surfmap::matching::overlap::{SurfaceCrop, crops_for_match, cut, drop_folds_as_given};
use surfmap::matching::{
    Align, Guidance, HoleFeatures, InputNumbering, Landmarks, MatchError, MatchOptions, ScaleB,
    SearchWhen, match_surfaces, output, pictures, write_match_folder,
};
use surfmap::mesh::repair::FaceOrigins;
use surfmap::raster::FeatureFile;
use surfmap::render::save_png;

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
    /// Search the rotation, scale and translation of φ that lowers the matching energy
    /// per matched area on a coarse level, and go on from it when the coarsest level
    /// solved from it ends lower without matching less (and, when the alignment's start
    /// matches A at a plausible size, 1/3–3 times its area on B, does too).
    #[arg(long, value_enum, default_value = "shape")]
    pub similarity_search: SearchArg,
    /// Extra starts of the similarity search: rotated by ±DEG degrees and scaled by
    /// (1 ± SCALE) (the lowest energy is kept); 0,0 searches from the start alone.
    #[arg(long, value_name = "DEG,SCALE", value_delimiter = ',')]
    pub search_candidates: Option<Vec<f64>>,
    /// Level k of the similarity search's energy (grid 2^k + 1; at least 1, at most the
    /// solve's coarsest level, 6).
    #[arg(long, value_name = "K", default_value_t = 4)]
    pub search_level: usize,
    /// Most energy evaluations per level, counted at the finest level (a level 2^j
    /// times coarser may use 4^j times as many): a level stops there if its energy
    /// has not stopped decreasing first (relative decrease 10⁻⁶, 10⁻⁵ on the finest
    /// level, or 300 iterations), and the whole solve after 220. 0 lifts both caps:
    /// every level runs to its stopping rule (the thesis's). Default 40: more changed no
    /// accuracy measure on 28 face pairs and costs time (BENCHMARKS.md). With the relief
    /// (--relief) the levels between the coarsest and the finest get 0.6 of theirs, and
    /// the coarsest level's phase with the relief a quarter of its own on top.
    #[arg(long, value_name = "N", default_value_t = surfmap::matching::NcgSettings::default().max_evaluations)]
    pub budget: usize,
    /// Keep the vertices of image triangles that turn over or collapse in space
    /// (by default they are reported unmatched).
    #[arg(long)]
    pub keep_folds: bool,
    /// Rings of vertices next to the matched region that may be completed from their
    /// matched neighbours where φ just misses B (its rim, the fill of its holes), after
    /// the two rings of matched vertices next to them are smoothed; 0 reports them
    /// unmatched and keeps φ's matches as they are.
    #[arg(long, value_name = "N", default_value_t = surfmap::matching::complete::COMPLETE_RINGS)]
    pub complete_rings: usize,
    /// How far past B's outer rim (in mean edges of the vertex) the prediction of a vertex
    /// that φ left unmatched may fall and the vertex still be matched to the rim. The
    /// default, half an edge, keeps partial correspondence (the part of A beyond B's crop
    /// unmatched); more matches more of A along a tight crop of B, and more vertices that
    /// have no counterpart (BENCHMARKS.md: 3 edges matches every vertex near the rim).
    #[arg(long, value_name = "EDGES", default_value_t = surfmap::matching::complete::COMPLETE_TOLERANCE.elsewhere)]
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
    #[arg(long, value_name = "N", default_value_t = surfmap::matching::rim_fit::RIM_FIT_RINGS)]
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
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    pub repair: RepairArgs,
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
    let clock = std::time::Instant::now();
    // Repaired meshes are matched; the outputs (and the landmark and feature ids read)
    // are numbered as the files are.
    let input_a = load_mesh(&args.a)?.mesh;
    let input_b = load_mesh(&args.b)?.mesh;
    let (mesh_a, origins_a) = args.repair.apply_tracked(&input_a, args.quiet)?;
    let (mesh_b, origins_b) = args.repair.apply_tracked(&input_b, args.quiet)?;
    let copies = |input: &TriMesh, repaired: &TriMesh, origins: &Option<FaceOrigins>| match origins
    {
        Some(o) => o.vertex_copies(input, repaired),
        None => (0..input.num_vertices() as u32).map(Some).collect(),
    };
    let copies_a = copies(&input_a, &mesh_a, &origins_a);
    let copies_b = copies(&input_b, &mesh_b, &origins_b);
    let mut options = MatchOptions {
        size: args.size,
        fill_holes: !args.no_fill_holes,
        drop_folds: !args.keep_folds,
        complete_rings: args.complete_rings,
        rim_fit_rings: args.rim_fit_rings,
        pin_landmarks: !args.free_landmarks,
        features_in_space: matches!(args.features_start, FeaturesStartArg::Both),
        align: match args.align {
            AlignArg::Auto => Align::Auto,
            AlignArg::Features => Align::Features,
            AlignArg::Shape => Align::Shape,
            AlignArg::None => Align::None,
        },
        hole_features: match args.hole_features {
            HoleArg::Auto => HoleFeatures::Auto,
            HoleArg::On => HoleFeatures::On,
            HoleArg::Off => HoleFeatures::Off,
        },
        split_hole_rims: if args.whole_hole_rims {
            0.0
        } else {
            surfmap::matching::holes::SPLIT_HOLE_RIMS
        },
        ..Default::default()
    };
    if let Some(b) = &args.beta {
        options.set_betas(b, "--beta").map_err(anyhow::Error::msg)?;
    }
    if let Some(w) = args.position_weight {
        options
            .set_position_weight(w, "--position-weight")
            .map_err(anyhow::Error::msg)?;
    }
    options.similarity_search.when = match args.similarity_search {
        SearchArg::Off => SearchWhen::Off,
        SearchArg::Shape => SearchWhen::Shape,
        SearchArg::Always => SearchWhen::Always,
    };
    options.similarity_search.level = args.search_level;
    options.ncg.set_budget(args.budget);
    options
        .set_rim_tolerance(args.rim_tolerance, "--rim-tolerance")
        .map_err(anyhow::Error::msg)?;
    options
        .set_position_relief(args.relief, "--relief")
        .map_err(anyhow::Error::msg)?;
    if let Some(c) = &args.search_candidates {
        options
            .set_search_candidates(c, "--search-candidates")
            .map_err(anyhow::Error::msg)?;
    }
    options.scale_b = match args.scale_b.as_str() {
        "auto" => ScaleB::Auto,
        text => match text.parse::<f64>() {
            Ok(f) if f.is_finite() && f > 0.0 => ScaleB::Factor(f),
            _ => bail!("--scale-b takes `auto` or a positive factor (1: B as given), got {text:?}"),
        },
    };
    surfmap::grid::grid_level(args.size).context("--size")?;
    // The guidance as the files number it.
    let raw = Guidance {
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
    // The crop to the part the surfaces share, sparing every vertex the guidance names
    // (in the repaired meshes' numbering). Not with `--hole-features on`: a cut could
    // take away holes the user pairs.
    let crops = if args.crop_overlap == CropArg::Auto && options.hole_features != HoleFeatures::On {
        let (ids_a, ids_b) = raw.vertices();
        let on_repaired = |ids: Vec<u32>, copies: &[Option<u32>]| -> Vec<u32> {
            ids.into_iter()
                .filter_map(|v| copies.get(v as usize).copied().flatten())
                .collect()
        };
        crops_for_match(
            &mesh_a,
            &mesh_b,
            &on_repaired(ids_a, &copies_a),
            &on_repaired(ids_b, &copies_b),
            options.scale_b,
        )
    } else {
        None
    };
    let (mesh_a, origins_a) = cut(mesh_a, origins_a, crops.as_ref().and_then(|c| c.a.as_ref()));
    let (mesh_b, origins_b) = cut(mesh_b, origins_b, crops.as_ref().and_then(|c| c.b.as_ref()));
    let renumber = origins_a.is_some() || origins_b.is_some();
    let copies_a = copies(&input_a, &mesh_a, &origins_a);
    let copies_b = copies(&input_b, &mesh_b, &origins_b);
    // Landmarks of A in the files' numbering: spared by the fold check on the given meshes.
    let landmarks_a: Vec<u32> = raw.landmarks.as_ref().map_or(vec![], |lm| lm.a.clone());
    let named = |path: &Option<PathBuf>| {
        path.as_ref()
            .map_or(String::new(), |p| p.display().to_string())
    };
    let guidance = if renumber {
        let features = |file: &Option<FeatureFile>, copies: &[Option<u32>], path| {
            file.as_ref()
                .map(|f| f.renumbered(copies))
                .transpose()
                .with_context(|| format!("features file {}", named(path)))
        };
        Guidance {
            landmarks: raw
                .landmarks
                .as_ref()
                .map(|lm| lm.renumbered(&copies_a, &copies_b))
                .transpose()
                .with_context(|| format!("landmarks file {}", named(&args.landmarks)))?,
            features_a: features(&raw.features_a, &copies_a, &args.features_a)?,
            features_b: features(&raw.features_b, &copies_b, &args.features_b)?,
        }
    } else {
        raw
    };
    let matched = match_surfaces(&mesh_a, &mesh_b, &guidance, &options)
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
    let checked = matched.checked_correspondence(&mesh_a, &mesh_b, options.drop_folds)?;
    let mut report = matched.report(&checked, &options);
    let mut corr = checked.points;
    // The files' numbering: each input vertex of A takes its copy's counterpart, each
    // point of B goes back to the input face it lies on.
    let numbered = renumber.then(|| {
        let mut points = output::numbered_as_given(&corr, &copies_a, origins_b.as_ref());
        if crops.is_some() && options.drop_folds {
            let pinned = if options.pin_landmarks {
                landmarks_a.clone()
            } else {
                vec![]
            };
            let n = drop_folds_as_given(&input_a, &input_b, &mut points, &pinned);
            report.count_dropped(n);
        }
        // A's faces as matched (the repaired ones, consistently oriented), on the input's
        // vertex numbers; where a repair split a vertex into copies, its row is one
        // copy's, and the faces around the others are left out (their corner's place on
        // B is not the row's).
        let faces_a = match &origins_a {
            Some(o) => TriMesh::new(
                input_a.positions.clone(),
                (0..mesh_a.triangles.len())
                    .filter_map(|t| {
                        let source = input_a.triangles[o.face[t] as usize];
                        let tri = o.corner[t].map(|k| source[k as usize]);
                        (0..3)
                            .all(|k| copies_a[tri[k] as usize] == Some(mesh_a.triangles[t][k]))
                            .then_some(tri)
                    })
                    .collect(),
            ),
            None => input_a.clone(),
        };
        let placed = output::a_on_b(&faces_a, &input_b, &matched, &points);
        report.overlap_crop = crops.clone();
        report.input_numbering = Some(InputNumbering {
            vertices_a: input_a.num_vertices(),
            vertices_b: input_b.num_vertices(),
            triangles_b: input_b.triangles.len(),
            removed_vertices_a: copies_a.iter().filter(|c| c.is_none()).count(),
        });
        (points, placed)
    });
    // The fold check on the given meshes (after a cut) may have unmatched more vertices:
    // the pictures show them unmatched too.
    if let Some((points, _)) = &numbered {
        for (v, c) in copies_a.iter().enumerate() {
            if let Some(c) = c
                && points[v].is_none()
            {
                corr[*c as usize] = None;
            }
        }
    }
    // Pictures are drawn before anything is written: an error leaves no partial folder.
    let placed = output::a_on_b(&mesh_a, &mesh_b, &matched, &corr);
    let drawn = if args.pictures {
        let mut drawn = vec![
            (
                "checker_carried.png",
                pictures::checker_carried(&mesh_a, &placed, &matched, &corr, 700),
            ),
            ("deformed_grid.png", pictures::deformed_grid(&matched, 800)),
            (
                "energy.png",
                pictures::energy_staircase(&matched, (900, 500)),
            ),
        ];
        if let Some(img) = pictures::features_carried(&matched, 700) {
            drawn.push(("features.png", img));
        }
        drawn
    } else {
        vec![]
    };
    let (out_corr, out_placed) = numbered.as_ref().map_or((&corr, &placed), |(c, p)| (c, p));
    let mut written = write_match_folder(&args.output, &matched, out_corr, out_placed, &report)
        .with_context(|| format!("cannot write the match into {}", args.output.display()))?;
    for (name, img) in &drawn {
        let path = args.output.join(name);
        save_png(&path, img).with_context(|| format!("cannot write {}", path.display()))?;
        written.push(path);
    }
    if !args.quiet {
        let paired = match (
            report.alignment.hole_pairs.len(),
            report.alignment.split_holes.len(),
        ) {
            (0, _) => String::new(),
            (p, 0) => format!(", {p} hole rims paired as features"),
            (p, s) => format!(", {p} hole rims paired as features ({s} split at their corners)"),
        };
        let filled = match (report.holes_filled_a, report.holes_filled_b) {
            (0, 0) => String::new(),
            (a, b) => format!(", holes filled for the solve A {a} B {b}{paired}"),
        };
        let pinned = match report.pinned_landmarks {
            0 => String::new(),
            n => format!(
                ", {n} landmarks matched exactly (φ had left them up to {:.3} of B's units off)",
                report.largest_landmark_miss
            ),
        };
        let searched = match &report.alignment.search {
            None => String::new(),
            Some(s) => format!(
                ", similarity search {:+.2}°, scale {:.3} (energy per matched area {:.4e} → {:.4e}, {} evaluations; {})",
                s.similarity.angle().to_degrees(),
                s.similarity.scale(),
                s.energy_start,
                s.energy_end,
                s.evaluations,
                match (s.kept, s.implausible_size, s.area_ratio_search, s.area_ratio_alignment) {
                    (true, ..) => "kept".to_string(),
                    (false, true, Some(searched), Some(aligned)) => format!(
                        "not kept: solved from it, the coarsest level matched A at {searched:.2}× its area on B, \
                         from the alignment at {aligned:.2}×"
                    ),
                    _ => "not kept: solved from it, the coarsest level did not end lower without matching less"
                        .to_string(),
                }
            ),
        };
        let in_space = match &report.alignment.features_in_space {
            None => String::new(),
            Some(f) => format!(
                ", the features' alignment refined in space {} (coarsest level's energy {:.4e} from the features' start, {:.4e} from it)",
                if f.kept { "kept" } else { "not kept" },
                f.energy_features,
                f.energy_space
            ),
        };
        let position = match report.shape_residual {
            Some(sigma) => format!(
                ", position weight {:.3e} (the surfaces {sigma:.4} of √area apart in space, along the normals)",
                report.position_weight
            ),
            None => format!(", position weight {:.3e} (fixed)", report.position_weight),
        };
        let fit = report.rim_fit;
        let rims = match (fit.holes, fit.by_arc_length) {
            (0, _) => String::new(),
            (h, 0) => format!(
                ", {h} hole rims carried onto B's ({} vertices moved)",
                fit.moved
            ),
            (h, l) => format!(
                ", {h} hole rims carried onto B's ({l} by arc length alone; {} vertices moved)",
                fit.moved
            ),
        };
        let left_out = match report.alignment.left_out.as_slice() {
            [] => String::new(),
            names => format!(
                " (left out of its fit, the others disagreeing: {}; they still guide the solve)",
                names.join(", ")
            ),
        };
        let crop_note = |side: char, other: char, c: &Option<SurfaceCrop>| {
            c.as_ref().map(|c| {
                format!(
                    "{side} cut to the part near {other} ({:.0}% of its area far from {other} left out)",
                    100.0 * c.removed_area
                )
            })
        };
        let crop = match &crops {
            Some(c) => format!(
                "{}; --crop-overlap off to match whole, ",
                [crop_note('A', 'B', &c.a), crop_note('B', 'A', &c.b)]
                    .into_iter()
                    .flatten()
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            None => String::new(),
        };
        let scaled = if report.scale_b == 1.0 {
            String::new()
        } else {
            let sizes = (mesh_a.area() / mesh_b.area()).sqrt();
            format!(
                "B ×{} for the match ({}; outputs in B's units), ",
                report.scale_b,
                match options.scale_b {
                    ScaleB::Auto => format!(
                        "A is {sizes:.3}× B's size (√area): taken for different units; --scale-b 1 to match as given"
                    ),
                    ScaleB::Factor(_) => "--scale-b".into(),
                }
            )
        };
        outln!(
            "match: {crop}{scaled}{} levels up to {n}², {} iterations, energy {:.4e}, min det Dφ {:.3}, matched {:.1}% of A ({} of {}, {} completed at rims){rims}, {:.1}% of B covered{filled}, {} vertices unmatched for folds ({} flipped, {} collapsed){pinned}, alignment {}{left_out}{in_space}{searched}{position}, {:.2} s",
            report.levels.len(),
            report.iterations,
            report.energy,
            report.min_det,
            100.0 * report.matched_fraction_a,
            report.matched_vertices_a,
            report.vertices_a,
            report.completed_vertices,
            100.0 * report.covered_fraction_b,
            report.dropped_vertices,
            report.flipped_triangles,
            report.collapsed_triangles,
            report.alignment.method,
            clock.elapsed().as_secs_f64(),
            n = report.grid_size,
        );
        if let Some(n) = &report.input_numbering {
            outln!(
                "outputs numbered as the files given ({} vertices of A, {} triangles of B){}",
                n.vertices_a,
                n.triangles_b,
                match n.removed_vertices_a {
                    0 => String::new(),
                    r => format!(
                        "; {r} vertices of A removed by the {} are unmatched",
                        match (
                            args.repair.asked(),
                            crops.as_ref().is_some_and(|c| c.a.is_some())
                        ) {
                            (true, true) => "repairs and the crop",
                            (false, true) => "crop",
                            _ => "repairs",
                        }
                    ),
                }
            );
        }
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
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}
