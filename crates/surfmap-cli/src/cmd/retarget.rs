//! `surfmap retarget NEUTRAL KEY… --onto NEW -o r.glb`: a rig's expressions carried onto
//! a new subject (thesis §6.2): the keys, meshes in the neutral's topology (as `surfmap
//! rig` writes them into its `_keys` folder), become morph targets of the new neutral
//! through the match NEW → NEUTRAL, by displacement transfer
//! (`surfmap::apps::retarget`). Writes the glTF rig of the new neutral, its keys as OBJ
//! and a report, as `rig` does. Without `--match` the match is made here and its verdict
//! printed; a `failed` one refuses (exit code 3).

use std::path::PathBuf;

use anyhow::{Context, bail};
use surfmap::apps::gltf::{GltfMorphScene, GltfTarget, write_glb};
use surfmap::apps::retarget::retarget_keys;
use surfmap::fsutil::write_json;
use surfmap::matching::{Guidance, MatchOptions, Verdict, match_meshes};
use surfmap::{TriMesh, write_obj};

use super::advice::worded_match_error;
use super::load_mesh;
use super::matching::NotTrusted;
use super::matchio::load_match;
use super::rig::check_rig_options;

#[derive(clap::Args)]
pub struct Args {
    /// The rig's neutral.
    pub neutral: PathBuf,
    /// The rig's keys: meshes with the neutral's triangles and vertex order (`surfmap rig`
    /// writes them into OUT_keys/).
    #[arg(required = true)]
    pub keys: Vec<PathBuf>,
    /// The new subject's neutral, which gets the expressions.
    #[arg(long, value_name = "NEW")]
    pub onto: PathBuf,
    /// The match folder NEW → NEUTRAL (default: made here, with `surfmap match`'s
    /// default options; a `failed` verdict refuses, exit code 3).
    #[arg(long = "match", value_name = "DIR")]
    pub matching: Option<PathBuf>,
    /// Without --match: write the match made into DIR (a match folder).
    #[arg(long, value_name = "DIR", conflicts_with = "matching")]
    pub match_dir: Option<PathBuf>,
    /// Without --match: refuse a `doubtful` match too (exit code 3).
    #[arg(long, conflicts_with = "matching")]
    pub strict: bool,
    /// Names of the morph targets, comma-separated (default: the keys' file names).
    #[arg(long, value_delimiter = ',')]
    pub names: Vec<String>,
    /// Output glTF binary (.glb).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Folder for the new subject's keys as OBJ in its topology (default: OUT's name
    /// with `_keys`).
    #[arg(long, value_name = "DIR")]
    pub keys_dir: Option<PathBuf>,
    /// Seconds each key takes in the animation (weight 0 → 1 → 0).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub seconds_per_key: f64,
    /// Write a JSON report (the match's verdict, per key: extended vertices).
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
    /// Print nothing but errors and warnings.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    check_rig_options(
        &args.names,
        args.keys.len(),
        &args.output,
        args.seconds_per_key,
    )?;
    let neutral = load_mesh(&args.neutral)?.mesh;
    let onto = load_mesh(&args.onto)?.mesh;
    let mut displacements = vec![];
    for path in &args.keys {
        let key = load_mesh(path)?.mesh;
        if key.triangles != neutral.triangles || key.num_vertices() != neutral.num_vertices() {
            bail!(
                "the key {} does not have the neutral's triangles ({} vertices, {} triangles against {} and {}): give keys in the neutral's topology, as surfmap rig writes them (OUT_keys/)",
                path.display(),
                key.num_vertices(),
                key.triangles.len(),
                neutral.num_vertices(),
                neutral.triangles.len()
            );
        }
        displacements.push(
            key.positions
                .iter()
                .zip(&neutral.positions)
                .map(|(k, x)| std::array::from_fn(|c| k[c] - x[c]))
                .collect::<Vec<[f64; 3]>>(),
        );
    }
    let names: Vec<String> = if args.names.is_empty() {
        args.keys
            .iter()
            .map(|k| {
                k.file_stem()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .into_owned()
            })
            .collect()
    } else {
        args.names.clone()
    };

    // The correspondence NEW → NEUTRAL.
    let (map, verdict) = match &args.matching {
        Some(dir) => (
            load_match(dir, &onto, &args.onto, &neutral, &args.neutral)?,
            None,
        ),
        None => {
            let mut made = match_meshes(&onto, &neutral, &Guidance::default(), &MatchOptions::default())
                .map_err(|e| {
                    anyhow::anyhow!(worded_match_error(
                        &e,
                        &args.onto.display().to_string(),
                        &args.neutral.display().to_string()
                    ))
                })
                .with_context(|| {
                    format!(
                        "cannot match {} onto {} (make the match with landmarks, surfmap match --landmarks, and pass it with --match)",
                        args.onto.display(),
                        args.neutral.display()
                    )
                })?;
            made.report.inputs.a.path = Some(args.onto.display().to_string());
            made.report.inputs.b.path = Some(args.neutral.display().to_string());
            if let Some(dir) = &args.match_dir {
                made.write_folder(dir, false)
                    .with_context(|| format!("cannot write the match into {}", dir.display()))?;
            }
            if !args.quiet {
                outln!("match: {}", made.report.summary());
            }
            let confidence = &made.report.confidence;
            if confidence.verdict != Verdict::Ok {
                eprintln!(
                    "warning: the match {} → {} has {}",
                    args.onto.display(),
                    args.neutral.display(),
                    confidence.line()
                );
            }
            if confidence.verdict == Verdict::Failed
                || (args.strict && confidence.verdict != Verdict::Ok)
            {
                return Err(NotTrusted(
                    "the rig is not written: the match of the two neutrals is not trusted (the reasons above). Look at it (--match-dir DIR writes it; surfmap view DIR), make one with landmarks (surfmap match NEW NEUTRAL --landmarks L.json -o DIR) and pass it with --match".to_owned(),
                )
                .into());
            }
            (made.correspondence, Some(confidence.verdict))
        }
    };

    let (targets, similarity) = retarget_keys(&neutral, &displacements, &onto, &map)?;
    let keys_dir = args.keys_dir.clone().unwrap_or_else(|| {
        let stem = args
            .output
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy();
        args.output.with_file_name(format!("{stem}_keys"))
    });
    std::fs::create_dir_all(&keys_dir)
        .with_context(|| format!("cannot create {}", keys_dir.display()))?;
    let mut report_keys = vec![];
    let mut gltf_targets = vec![];
    for (name, target) in names.iter().zip(targets) {
        let mesh = TriMesh {
            positions: target.frame(&onto.positions, 1.0),
            triangles: onto.triangles.clone(),
            uvs: onto.uvs.clone(),
        };
        let obj = keys_dir.join(format!("{name}.obj"));
        write_obj(&obj, &mesh, None)?;
        report_keys.push(serde_json::json!({
            "name": name,
            "obj": obj.display().to_string(),
            "matched": target.matched,
            "extended": target.extended.len(),
            "max_extended_displacement": target.max_extended_displacement(),
        }));
        gltf_targets.push(GltfTarget {
            name: name.clone(),
            displacements: target.displacements,
        });
    }
    let mut scene = GltfMorphScene {
        name: "retargeted rig".into(),
        positions: onto.positions.clone(),
        triangles: onto.triangles.clone(),
        targets: gltf_targets,
        ..GltfMorphScene::default()
    };
    scene.animation = Some(scene.key_by_key_animation(args.seconds_per_key));
    let bytes = write_glb(&args.output, &scene)?;
    if let Some(path) = &args.report {
        write_json(
            path,
            &serde_json::json!({
                "neutral": args.neutral.display().to_string(),
                "onto": args.onto.display().to_string(),
                "verdict": verdict,
                "scale": similarity.scale(),
                "glb": args.output.display().to_string(),
                "glb_bytes": bytes,
                "keys": report_keys,
            }),
        )
        .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if !args.quiet {
        outln!(
            "retarget: {} keys of {} onto {} ({} vertices) → {} ({bytes} bytes), keys as OBJ in {}",
            names.len(),
            args.neutral.display(),
            args.onto.display(),
            onto.num_vertices(),
            args.output.display(),
            keys_dir.display()
        );
    }
    Ok(())
}
