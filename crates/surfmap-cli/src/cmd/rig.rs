//! `surfmap rig NEUTRAL KEY1 KEY2 … --match DIR1 --match DIR2 … -o rig.glb`: a
//! blend-shape rig (thesis §5.3): every key pose re-expressed on the neutral's
//! connectivity through its correspondence, one glTF with a named morph target per key
//! (and an animation showing them in turn), and each key as an OBJ in the neutral's
//! topology. With `--chain` the matches run neutral → KEY1 → KEY2 → … and key `i` uses
//! the composed map; `--direct` matches neutral → KEYi measure how far the composition
//! is from a direct match.
//!
//! Without `--match`, rig makes the matches itself (`surfmap::matching::match_meshes`
//! with the options `surfmap match` has by default): neutral → KEYi, or along the chain.
//! Each match's confidence verdict is printed; a key whose match is `failed` refuses
//! the rig (exit code 3, nothing but the matches written): its morph target would be
//! wrong where the match is, and nothing in a glTF says so. A `doubtful` key is kept
//! with a warning on stderr; `--strict` refuses it too. `--matches-dir DIR` writes the
//! matches made as match folders, to look at (`surfmap view`) or to pass back with
//! `--match` when a verdict is judged too harsh.

use std::path::PathBuf;

use anyhow::{Context, bail};
use serde::Serialize;
use surfmap::apps::correspondence::{MapDistance, compare_maps};
use surfmap::apps::gltf::{GltfMorphScene, GltfTarget, write_glb};
use surfmap::apps::rig::{ChainLink, chain_maps, rig_key};
use surfmap::fsutil::write_atomically;
use surfmap::matching::{Guidance, MatchError, MatchOptions, Verdict, match_meshes};
use surfmap::write_obj;

use super::advice::worded_match_error;
use super::load_mesh;
use super::matching::NotTrusted;
use super::matchio::{chart_of, load_match};
use super::morph::{extension_note, png_bytes, texture_of, write_stills};

#[derive(clap::Args)]
pub struct Args {
    /// The neutral surface: the rig's connectivity.
    pub neutral: PathBuf,
    /// Key poses, each a surface of its own triangulation.
    #[arg(required = true)]
    pub keys: Vec<PathBuf>,
    /// Match folders, one per key in order: neutral → KEYi, or with --chain
    /// KEY(i−1) → KEYi (the first from the neutral). Without --match the matches are
    /// made here, with `surfmap match`'s default options, and their verdicts printed; a
    /// key whose match is `failed` refuses the rig (exit code 3).
    #[arg(long = "match", value_name = "DIR")]
    pub matches: Vec<PathBuf>,
    /// Without --match: write the matches made into DIR/NAME/ (match folders, as
    /// `surfmap match` writes; pass one back with --match to use it as it is).
    #[arg(long, value_name = "DIR", conflicts_with = "matches")]
    pub matches_dir: Option<PathBuf>,
    /// Without --match: refuse the rig (exit code 3) when a key's match is `doubtful`
    /// too, not only when it is `failed`.
    #[arg(long, conflicts_with = "matches")]
    pub strict: bool,
    /// The matches form a chain; key i uses the composition of the first i matches.
    #[arg(long)]
    pub chain: bool,
    /// Direct matches neutral → KEYi, one per key, to report how far each composed map
    /// is from them (with --chain).
    #[arg(long, value_name = "DIR", requires = "chain")]
    pub direct: Vec<PathBuf>,
    /// Names of the morph targets, comma-separated (default: the keys' file names).
    #[arg(long, value_delimiter = ',')]
    pub names: Vec<String>,
    /// Output glTF binary (.glb).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Folder for the keys as OBJ in the neutral's topology (default: OUT's name with
    /// `_keys`).
    #[arg(long, value_name = "DIR")]
    pub keys_dir: Option<PathBuf>,
    /// Seconds each key takes in the animation (weight 0 → 1 → 0).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub seconds_per_key: f64,
    /// Write a stills sheet: the neutral and every key from one view.
    #[arg(long, value_name = "SHEET.png")]
    pub stills: Option<PathBuf>,
    /// The neutral's texture, for the stills and the glTF (default: its map_Kd).
    #[arg(long, value_name = "T.png")]
    pub texture: Option<PathBuf>,
    /// Write a JSON report (per key: matched and extended vertices, composed vs direct).
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Serialize)]
struct KeyReport {
    name: String,
    file: String,
    obj: String,
    matched: usize,
    extended: usize,
    max_extended_displacement: f64,
    /// With --chain and --direct: the composed map against the direct one on the key.
    composed_vs_direct: Option<MapDistance>,
    /// Without --match: the verdict of the match made for this key (`ok`, `doubtful`,
    /// `failed`) and its reasons.
    verdict: Option<Verdict>,
    reasons: Vec<String>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    if !args.matches.is_empty() && args.matches.len() != args.keys.len() {
        bail!(
            "{} keys but {} --match folders: give one match per key, in the same order (or none: rig then makes them)",
            args.keys.len(),
            args.matches.len()
        );
    }
    if !args.direct.is_empty() && args.direct.len() != args.keys.len() {
        bail!(
            "--direct: give one direct match per key ({} keys)",
            args.keys.len()
        );
    }
    check_rig_options(
        &args.names,
        args.keys.len(),
        &args.output,
        args.seconds_per_key,
    )?;
    let neutral_file = load_mesh(&args.neutral)?;
    let neutral = &neutral_file.mesh;
    let keys: Vec<_> = args
        .keys
        .iter()
        .map(|k| load_mesh(k))
        .collect::<Result<_, _>>()?;
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

    // Correspondences neutral → key i (composed along the chain when asked).
    let from_of = |i: usize| {
        if args.chain && i > 0 {
            (&keys[i - 1].mesh, &args.keys[i - 1])
        } else {
            (neutral, &args.neutral)
        }
    };
    let mut maps = vec![];
    let mut verdicts = vec![];
    if args.matches.is_empty() {
        for (i, name) in names.iter().enumerate() {
            let (from, from_name) = from_of(i);
            let made = make_match(&args, from, from_name, &keys[i].mesh, &args.keys[i], name)?;
            maps.push(made.correspondence);
            verdicts.push((
                made.report.confidence.verdict,
                made.report.confidence.reasons,
            ));
        }
        refuse_untrusted(&args, &names, &verdicts)?;
    } else {
        for (i, dir) in args.matches.iter().enumerate() {
            let (from, from_name) = from_of(i);
            maps.push(load_match(
                dir,
                from,
                from_name,
                &keys[i].mesh,
                &args.keys[i],
            )?);
        }
    }
    let maps = if args.chain {
        let charts: Vec<Option<surfmap::apps::Chart>> = keys
            .iter()
            .enumerate()
            .map(|(i, k)| {
                (i > 0)
                    .then(|| chart_of(&k.mesh, &args.keys[i], args.quiet))
                    .transpose()
            })
            .collect::<Result<_, _>>()?;
        let links: Vec<ChainLink> = maps
            .iter()
            .zip(&keys)
            .zip(&charts)
            .map(|((m, k), c)| ChainLink {
                map: m,
                triangles: &k.mesh.triangles,
                chart: c.as_ref(),
            })
            .collect();
        chain_maps(&links)?
    } else {
        maps
    };

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
    let mut targets = vec![];
    let mut reports = vec![];
    let mut frames = vec![("neutral".to_owned(), neutral.positions.clone())];
    for (i, map) in maps.iter().enumerate() {
        let key = rig_key(&names[i], neutral, map, &keys[i].mesh)
            .with_context(|| format!("key {}", args.keys[i].display()))?;
        let mesh = key.mesh(neutral);
        let obj = keys_dir.join(format!("{}.obj", names[i]));
        write_obj(&obj, &mesh, None)?;
        let composed_vs_direct = match args.direct.get(i) {
            Some(dir) => {
                let direct = load_match(dir, neutral, &args.neutral, &keys[i].mesh, &args.keys[i])?;
                Some(compare_maps(
                    map,
                    &direct,
                    &keys[i].mesh.positions,
                    &keys[i].mesh.triangles,
                )?)
            }
            None => None,
        };
        if !args.quiet {
            let mut line = format!(
                "key {}: {}",
                names[i],
                extension_note(&key.target, neutral.num_vertices())
            );
            if let Some(d) = &composed_vs_direct {
                line += &format!(
                    "; composed vs direct map: mean {:.3e}, 95% {:.3e}, max {:.3e} ({:.3}% / {:.3}% of √area)",
                    d.mean,
                    d.p95,
                    d.max,
                    100.0 * d.mean / d.sqrt_area,
                    100.0 * d.p95 / d.sqrt_area
                );
            }
            outln!("{line}");
        }
        reports.push(KeyReport {
            name: names[i].clone(),
            file: args.keys[i].display().to_string(),
            obj: obj.display().to_string(),
            matched: key.target.matched,
            extended: key.target.extended.len(),
            max_extended_displacement: key.target.max_extended_displacement(),
            composed_vs_direct,
            verdict: verdicts.get(i).map(|v| v.0),
            reasons: verdicts.get(i).map(|v| v.1.clone()).unwrap_or_default(),
        });
        frames.push((names[i].clone(), mesh.positions.clone()));
        targets.push(GltfTarget {
            name: names[i].clone(),
            displacements: key.target.displacements,
        });
    }

    let texture = texture_of(&neutral_file, args.texture.as_deref())?;
    let mut scene = GltfMorphScene {
        name: "rig".into(),
        positions: neutral.positions.clone(),
        triangles: neutral.triangles.clone(),
        targets,
        ..GltfMorphScene::default()
    };
    scene.animation = Some(scene.key_by_key_animation(args.seconds_per_key));
    if let Some((uvs, path)) = &texture {
        scene.uvs = Some(uvs.clone());
        scene.texture_png = Some(png_bytes(path)?);
    }
    let bytes = write_glb(&args.output, &scene)?;
    if let Some(path) = &args.stills {
        write_stills(path, neutral, &frames, texture.as_ref(), args.quiet)?;
    }
    if let Some(path) = &args.report {
        let json = serde_json::to_vec_pretty(&serde_json::json!({
            "neutral": args.neutral.display().to_string(),
            "chain": args.chain,
            "glb": args.output.display().to_string(),
            "glb_bytes": bytes,
            "keys": reports,
        }))?;
        write_atomically(path, |w| w.write_all(&json))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if !args.quiet {
        outln!(
            "rig: {} keys on {}'s connectivity ({} vertices) → {} ({bytes} bytes), keys as OBJ in {}",
            names.len(),
            args.neutral.display(),
            neutral.num_vertices(),
            args.output.display(),
            keys_dir.display()
        );
    }
    Ok(())
}

/// Makes the match `from` → `key` for the key called `name` (default match options),
/// prints its summary and verdict, writes it into `--matches-dir` when asked, and
/// returns it.
fn make_match(
    args: &Args,
    from: &surfmap::TriMesh,
    from_name: &std::path::Path,
    key: &surfmap::TriMesh,
    key_name: &std::path::Path,
    name: &str,
) -> anyhow::Result<surfmap::matching::Match> {
    let options = MatchOptions::default();
    let mut made = match_meshes(from, key, &Guidance::default(), &options)
        .map_err(|e: MatchError| {
            anyhow::anyhow!(worded_match_error(
                &e,
                &from_name.display().to_string(),
                &key_name.display().to_string()
            ))
        })
        .with_context(|| {
            format!(
                "key {name}: cannot match {} onto {} (make the match with landmarks, surfmap match --landmarks, and pass it with --match)",
                from_name.display(),
                key_name.display()
            )
        })?;
    made.report.inputs.a.path = Some(from_name.display().to_string());
    made.report.inputs.b.path = Some(key_name.display().to_string());
    if let Some(dir) = &args.matches_dir {
        let folder = dir.join(name);
        made.write_folder(&folder, false)
            .with_context(|| format!("cannot write the match into {}", folder.display()))?;
    }
    if !args.quiet {
        outln!("key {name}: {}", made.report.summary());
    }
    let confidence = &made.report.confidence;
    if confidence.verdict != Verdict::Ok {
        eprintln!(
            "warning: key {name}: the match {} → {} has {}",
            from_name.display(),
            key_name.display(),
            confidence.line()
        );
    }
    Ok(made)
}

/// Refuses the rig (exit code 3) when a key's match is `failed`, or not `ok` with
/// `--strict`, naming every such key and what to do.
fn refuse_untrusted(
    args: &Args,
    names: &[String],
    verdicts: &[(Verdict, Vec<String>)],
) -> anyhow::Result<()> {
    let refused: Vec<String> = names
        .iter()
        .zip(verdicts)
        .filter(|(_, (v, _))| *v == Verdict::Failed || (args.strict && *v != Verdict::Ok))
        .map(|(name, (v, _))| {
            let v = serde_json::to_value(v)
                .ok()
                .and_then(|v| v.as_str().map(str::to_owned))
                .unwrap_or_default();
            format!("key {name} ({v})")
        })
        .collect();
    if refused.is_empty() {
        return Ok(());
    }
    let saved = match &args.matches_dir {
        Some(dir) => format!("the matches are in {}", dir.display()),
        None => "--matches-dir DIR writes them".to_owned(),
    };
    Err(NotTrusted(format!(
        "the rig is not written: {} not trusted (the reasons above): {}. Look at the matches ({saved}; surfmap view DIR/NAME), make a match with landmarks (surfmap match NEUTRAL KEY --landmarks L.json -o DIR) and pass the matches with --match, one per key",
        if refused.len() == 1 { "1 key's match is".to_owned() } else { format!("{} keys' matches are", refused.len()) },
        refused.join(", ")
    ))
    .into())
}

/// The checks `rig` and `retarget` share: one name per key, a `.glb` output, a positive
/// duration per key.
pub(crate) fn check_rig_options(
    names: &[String],
    keys: usize,
    output: &std::path::Path,
    seconds_per_key: f64,
) -> anyhow::Result<()> {
    if !names.is_empty() && names.len() != keys {
        bail!("--names: give one name per key ({keys} keys)");
    }
    if output
        .extension()
        .is_none_or(|e| !e.eq_ignore_ascii_case("glb"))
    {
        bail!("the rig is written as glTF binary: name the output OUT.glb");
    }
    if !(seconds_per_key.is_finite() && seconds_per_key > 0.0) {
        bail!("--seconds-per-key must be > 0");
    }
    Ok(())
}
