//! The shape model of a registration folder, on disk: from the scans its
//! `summary.json` lists as registered with verdict `ok` (optionally also `doubtful`), the
//! model ([`super::model`]) written into `DIR/model/`:
//!
//! ```text
//! mean.obj     the mean shape, the template's triangles
//! model.npz    mean (n, 3), components (k, n, 3), variances (k,), vertex_order (n,):
//!              the template's vertex ids (row i of mean and of each mode is template
//!              vertex i)
//! model.json   the scans used, the variances and their cumulative explained fraction,
//!              the modes needed for 90 / 95 / 99 %
//! modes.png    the first modes at −2σ, 0, +2σ, coloured by the distance from the mean
//! ```

use std::path::{Path, PathBuf};

use image::{Rgb, RgbImage};
use serde::Serialize;

use super::batch::RegisterRow;
use super::model::{ModelError, ShapeModel, shape_model};
use crate::mesh::TriMesh;
use crate::raster::npy::{save_npz, write_npy};
use crate::render::colormap::Colormap;
use crate::render::font::{draw_text, format_number, text_height};
use crate::render::{View, contact_sheet, surface_render};

/// What `model.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModelSummary {
    /// The scans the model is built from (their names in `summary.json`).
    pub scans: Vec<String>,
    /// Scans left out: `(name, why)`.
    pub left_out: Vec<(String, String)>,
    pub vertices: usize,
    /// `σ_j²` by mode, and the cumulative fraction of the total variance.
    pub variances: Vec<f64>,
    pub explained: Vec<f64>,
    pub total_variance: f64,
    /// Modes needed for 90, 95 and 99 % of the variance.
    pub modes_90: usize,
    pub modes_95: usize,
    pub modes_99: usize,
    /// The mean centroid size of the scans (the model's scale).
    pub size: f64,
    pub procrustes_iterations: usize,
}

/// Builds the shape model of the registration folder `dir` and writes `dir/model/`
/// (module documentation). Returns the summary and the paths written.
pub fn build_model(
    dir: &Path,
    include_doubtful: bool,
) -> Result<(ModelSummary, Vec<PathBuf>), ModelFolderError> {
    let summary = dir.join("summary.json");
    let text = std::fs::read(&summary).map_err(|e| {
        ModelFolderError::Input(format!(
            "cannot read {}: {e}; give the folder a `surfmap register … -o DIR` wrote",
            summary.display()
        ))
    })?;
    let rows: Vec<RegisterRow> = serde_json::from_slice(&text).map_err(|e| {
        ModelFolderError::Input(format!(
            "{} is not a register summary: {e}",
            summary.display()
        ))
    })?;
    let mut shapes = Vec::new();
    let mut scans = Vec::new();
    let mut left_out = Vec::new();
    let mut triangles: Option<Vec<[u32; 3]>> = None;
    for row in &rows {
        let verdict = row.verdict.as_deref().unwrap_or("");
        let wanted = verdict == "ok" || (include_doubtful && verdict == "doubtful");
        if !row.ok() || !wanted {
            let why = if row.ok() {
                format!("verdict {verdict}")
            } else {
                "not registered".to_owned()
            };
            left_out.push((row.name.clone(), why));
            continue;
        }
        // The registered mesh beside the summary (the folder may have moved).
        let path = dir.join("registered").join(format!("{}.obj", row.name));
        let mesh = crate::read_mesh(&path)
            .map_err(|e| ModelFolderError::Input(e.to_string()))?
            .mesh;
        match &triangles {
            None => triangles = Some(mesh.triangles.clone()),
            Some(t) if *t != mesh.triangles => {
                return Err(ModelFolderError::Input(format!(
                    "{} has other triangles than the first registered scan: the folder mixes registrations of different templates; register them into separate folders",
                    path.display()
                )));
            }
            Some(_) => {}
        }
        shapes.push(mesh.positions);
        scans.push(row.name.clone());
    }
    let model = shape_model(&shapes)?;
    let triangles = triangles.unwrap_or_default();
    let out = dir.join("model");
    std::fs::create_dir_all(&out).map_err(|e| ModelFolderError::io(&out, e))?;
    let n = model.mean.len();
    let k = model.components.len();
    let written = write_model_files(&out, &model, &triangles)?;
    let summary = ModelSummary {
        scans,
        left_out,
        vertices: n,
        explained: (1..=k).map(|j| model.explained(j)).collect(),
        variances: model.variances.clone(),
        total_variance: model.total_variance,
        modes_90: model.modes_for(0.90),
        modes_95: model.modes_for(0.95),
        modes_99: model.modes_for(0.99),
        size: model.procrustes.size,
        procrustes_iterations: model.procrustes.iterations,
    };
    let json = out.join("model.json");
    crate::fsutil::write_json(&json, &summary).map_err(|e| ModelFolderError::io(&json, e))?;
    let mut all = written;
    all.push(json);
    Ok((summary, all))
}

/// `mean.obj`, `model.npz` and `modes.png` of `model` into `out`.
fn write_model_files(
    out: &Path,
    model: &ShapeModel,
    triangles: &[[u32; 3]],
) -> Result<Vec<PathBuf>, ModelFolderError> {
    let n = model.mean.len();
    let k = model.components.len();
    let mean_obj = out.join("mean.obj");
    crate::write_obj(
        &mean_obj,
        &TriMesh::new(model.mean.clone(), triangles.to_vec()),
        None,
    )
    .map_err(|e| ModelFolderError::Input(e.to_string()))?;
    let npy = |shape: &[usize], data: &[f64]| -> Result<Vec<u8>, ModelFolderError> {
        let mut bytes = Vec::new();
        write_npy(&mut bytes, shape, data).map_err(|e| ModelFolderError::io(out, e))?;
        Ok(bytes)
    };
    let mut ids = Vec::new();
    let order: Vec<u32> = (0..n as u32).collect();
    write_npy(&mut ids, &[n], &order).map_err(|e| ModelFolderError::io(out, e))?;
    let flat = |v: &[[f64; 3]]| v.iter().flatten().copied().collect::<Vec<f64>>();
    let components: Vec<f64> = model.components.iter().flat_map(|c| flat(c)).collect();
    let npz = out.join("model.npz");
    save_npz(
        &npz,
        &[
            ("mean", npy(&[n, 3], &flat(&model.mean))?),
            ("components", npy(&[k, n, 3], &components)?),
            ("variances", npy(&[k], &model.variances)?),
            ("vertex_order", ids),
        ],
    )
    .map_err(|e| ModelFolderError::io(&npz, e))?;
    let png = out.join("modes.png");
    crate::render::save_png(&png, &modes_picture(model, triangles, 3, 300))
        .map_err(|e| ModelFolderError::io(&png, e))?;
    Ok(vec![mean_obj, npz, png])
}

/// The first `modes` modes at `−2σ`, the mean and `+2σ` (one row each, one view for
/// all), coloured by each vertex's distance from the mean (viridis, 0 to the largest
/// over the pictures), with a colour bar and the modes' shares of the variance.
pub fn modes_picture(
    model: &ShapeModel,
    triangles: &[[u32; 3]],
    modes: usize,
    tile: u32,
) -> RgbImage {
    let modes = modes.min(model.components.len());
    let mut frames: Vec<(String, Vec<[f64; 3]>)> = Vec::new();
    for j in 0..modes {
        let sigma = model.variances[j].sqrt();
        let share = 100.0 * model.variances[j] / model.total_variance.max(f64::MIN_POSITIVE);
        // Labels fit a tile (font scale 3: 18 px a character): the share on the middle.
        for (b, label) in [
            (-2.0, format!("MODE {} -2σ", j + 1)),
            (0.0, format!("MODE {}: {share:.0}%", j + 1)),
            (2.0, format!("MODE {} +2σ", j + 1)),
        ] {
            frames.push((label, model.along(j, b * sigma)));
        }
    }
    let distance = |p: &[[f64; 3]]| -> Vec<f64> {
        p.iter()
            .zip(&model.mean)
            .map(|(a, m)| (0..3).map(|c| (a[c] - m[c]).powi(2)).sum::<f64>().sqrt())
            .collect()
    };
    let largest = frames
        .iter()
        .flat_map(|(_, p)| distance(p))
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let positions: Vec<&[[f64; 3]]> = frames.iter().map(|(_, p)| p.as_slice()).collect();
    let view = View::framing_tilted(&positions, triangles, super::super::stills::STILLS_TILT);
    let tiles: Vec<(String, RgbImage)> = frames
        .iter()
        .map(|(label, p)| {
            let d = distance(p);
            // The distance rides in the first texture coordinate.
            let corners: Vec<[[f64; 2]; 3]> = triangles
                .iter()
                .map(|t| t.map(|v| [d[v as usize] / largest, 0.0]))
                .collect();
            let colour = |uv: [f64; 2]| Colormap::Viridis.at(uv[0]);
            let img = match &view {
                Some(view) => {
                    surface_render(p, triangles, &corners, view, &colour, "", (tile, tile))
                }
                None => RgbImage::from_pixel(tile, tile, Rgb([255, 255, 255])),
            };
            (label.clone(), img)
        })
        .collect();
    let sheet = contact_sheet(&tiles, 3, tile);
    with_colour_bar(sheet, largest)
}

/// `sheet` with a colour bar on its right: viridis from 0 (bottom) to `largest` (top),
/// titled as the distance from the mean.
fn with_colour_bar(sheet: RgbImage, largest: f64) -> RgbImage {
    let extra = 230;
    let (w, h) = (sheet.width() + extra, sheet.height().max(420));
    let mut img = RgbImage::from_pixel(w, h, Rgb([255, 255, 255]));
    image::imageops::replace(&mut img, &sheet, 0, 0);
    let (x0, y0, bw, bh) = (sheet.width() + 20, 70u32, 24u32, (h - 200).min(400));
    for y in 0..bh {
        let t = 1.0 - y as f64 / (bh - 1) as f64;
        let c = Colormap::Viridis.at_rgb8(t);
        for x in 0..bw {
            img.put_pixel(x0 + x, y0 + y, Rgb(c));
        }
    }
    let black = [20, 20, 20];
    let font = 2;
    let line = text_height(font) as i64 + 4;
    draw_text(&mut img, x0 as i64, 12, "DISTANCE FROM", font, black);
    draw_text(&mut img, x0 as i64, 12 + line, "THE MEAN", font, black);
    let tx = (x0 + bw + 6) as i64;
    draw_text(
        &mut img,
        tx,
        y0 as i64,
        &format_number(largest),
        font,
        black,
    );
    draw_text(
        &mut img,
        tx,
        (y0 + bh / 2) as i64 - line / 2,
        &format_number(0.5 * largest),
        font,
        black,
    );
    draw_text(&mut img, tx, (y0 + bh) as i64 - line, "0", font, black);
    draw_text(
        &mut img,
        x0 as i64,
        (y0 + bh + 12) as i64,
        "(SCAN UNITS)",
        font,
        black,
    );
    draw_text(
        &mut img,
        x0 as i64,
        (y0 + bh + 12) as i64 + line,
        "MODE K: N% -",
        font,
        black,
    );
    draw_text(
        &mut img,
        x0 as i64,
        (y0 + bh + 12) as i64 + 2 * line,
        "ITS SHARE OF THE",
        font,
        black,
    );
    draw_text(
        &mut img,
        x0 as i64,
        (y0 + bh + 12) as i64 + 3 * line,
        "VARIANCE",
        font,
        black,
    );
    img
}

/// Why a model folder cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum ModelFolderError {
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("{0}")]
    Input(String),
    #[error("cannot write {}: {source}", .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl ModelFolderError {
    fn io(path: &Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}
