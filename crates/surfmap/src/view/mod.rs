//! `surfmap view`: one self-contained, interactive HTML page of a result — a
//! flattening, a match folder, a morph or rig (`.glb`), or a batch or registration
//! folder — that opens by double-click in a current browser, offline.
//!
//! The page is the viewer's own small WebGL2 renderer (`assets/viewer.js`, with its
//! HTML and CSS, embedded in the library with `include_str!`: neither building nor
//! using surfmap needs Node or a network) and the result's data, embedded as base64
//! typed arrays in a JSON document ([`page`]). Everything the page shows is computed
//! here, once, from the files: the per-triangle distortion measures
//! ([`crate::measure::per_triangle_measure`]), their colour ranges, the morph target of
//! a match ([`crate::apps::morph_target`], as `surfmap morph` computes it), the
//! initial camera ([`crate::render::surface::automatic_view`]); the page only draws.
//!
//! One entry point: [`ViewInput::detect`] tells what a path holds, [`write_page`]
//! writes its page (and, for a folder of many results, one page per item next to the
//! table). The pages are described for users in `docs/viewer.md`.
//!
//! | file | what it builds |
//! |---|---|
//! | [`page`] | the embedded document, base64 arrays, the HTML assembly |
//! | [`surface`] | a mesh's arrays, its seams and boundary, its camera |
//! | [`flattening`] | a flattened mesh (or any mesh) with its report and distortion measures |
//! | [`matching`] | a match folder with its meshes, the morph target and landmarks |
//! | [`morph`] | a `.glb` morph or rig: targets, their names, the animation |
//! | [`table`] | a batch (`summary.csv`) or registration (`summary.json`) folder |

pub mod flattening;
pub mod matching;
pub mod morph;
pub mod page;
pub mod surface;
pub mod table;

use std::path::{Path, PathBuf};

use crate::apps::AppError;
use crate::measure::MeasureError;
use crate::mesh::io::ReadError;

/// What went wrong while writing a page, and what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The input is not what the page needs (names the file and the problem).
    #[error("{path}: {problem}")]
    Input { path: String, problem: String },
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Read(#[from] ReadError),
    #[error(transparent)]
    App(#[from] AppError),
    #[error("measuring the map: {0}")]
    Measure(#[from] MeasureError),
}

impl ViewError {
    pub(crate) fn input(path: &Path, problem: impl Into<String>) -> Self {
        ViewError::Input {
            path: path.display().to_string(),
            problem: problem.into(),
        }
    }

    pub(crate) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ViewError + '_ {
        move |source| ViewError::Io {
            path: path.display().to_string(),
            source,
        }
    }
}

/// Files that go with the path to view; each is optional.
#[derive(Clone, Debug, Default)]
pub struct ViewOptions {
    /// A flattening's report (`surfmap flatten --report`); default: `OUT.json` beside
    /// the mesh, when it exists.
    pub report: Option<PathBuf>,
    /// A match's surface A (default: the one `match.json` names).
    pub a: Option<PathBuf>,
    /// A match's surface B (default: the one `match.json` names).
    pub b: Option<PathBuf>,
    /// Landmarks of a match, `{"names": [...], "A": [vertex ids], "B": [vertex ids]}`
    /// (the file `surfmap match --landmarks` reads).
    pub landmarks: Option<PathBuf>,
}

/// What a path holds, as [`ViewInput::detect`] found it.
#[derive(Clone, Debug, PartialEq)]
pub enum ViewInput {
    /// A mesh file (OBJ, OFF, PLY), flattened (with texture coordinates) or not, and
    /// the report of its flattening.
    Flattening {
        mesh: PathBuf,
        report: Option<PathBuf>,
    },
    /// A match folder (`correspondence.npy`, `match.json`) and its surfaces.
    Match {
        folder: PathBuf,
        a: Option<PathBuf>,
        b: Option<PathBuf>,
        landmarks: Option<PathBuf>,
    },
    /// A glTF binary with morph targets (`surfmap morph`, `surfmap rig`).
    Gltf { file: PathBuf },
    /// A folder of results: `summary.csv` (`surfmap flatten A B … -o DIR/`) or
    /// `summary.json` (a registration), with a page per item.
    Table { folder: PathBuf },
}

/// The kind of page written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PageKind {
    Flattening,
    Match,
    Morph,
    Table,
}

impl PageKind {
    pub fn name(self) -> &'static str {
        match self {
            PageKind::Flattening => "flattening",
            PageKind::Match => "match",
            PageKind::Morph => "morph",
            PageKind::Table => "table",
        }
    }
}

/// A page written: where, its size, what it shows, and the pages of a table's items.
#[derive(Clone, Debug)]
pub struct PageWritten {
    pub kind: PageKind,
    pub path: PathBuf,
    pub bytes: usize,
    /// Triangles drawn (all meshes of the page together).
    pub triangles: usize,
    /// What the page could not show and why (also shown on the page).
    pub notes: Vec<String>,
    /// A table's item pages (empty for other kinds).
    pub items: Vec<PageWritten>,
}

/// A page's document before it is written: its data and what [`PageWritten`] reports.
pub(crate) struct BuiltPage {
    pub kind: PageKind,
    pub data: page::PageData,
    pub triangles: usize,
    pub notes: Vec<String>,
}

impl ViewInput {
    /// What `path` holds: a match folder (it has `correspondence.npy`), a batch or
    /// registration folder (`summary.csv` or `summary.json`), a `.glb`, or a mesh file
    /// (its report from `options.report`, else `MESH.json` beside it when present).
    pub fn detect(path: &Path, options: &ViewOptions) -> Result<ViewInput, ViewError> {
        if path.is_dir() {
            if path
                .join(crate::apps::match_folder::CORRESPONDENCE_FILE)
                .is_file()
            {
                return Ok(ViewInput::Match {
                    folder: path.to_path_buf(),
                    a: options.a.clone(),
                    b: options.b.clone(),
                    landmarks: options.landmarks.clone(),
                });
            }
            if table::summary_file(path).is_some() {
                return Ok(ViewInput::Table {
                    folder: path.to_path_buf(),
                });
            }
            return Err(ViewError::input(
                path,
                "a folder without correspondence.npy (a match folder of `surfmap match`), summary.csv (a batch of `surfmap flatten A B … -o DIR/`) or summary.json (a registration): nothing to view",
            ));
        }
        if !path.exists() {
            return Err(ViewError::input(path, "no such file or folder"));
        }
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if extension.as_deref() == Some("glb") {
            return Ok(ViewInput::Gltf {
                file: path.to_path_buf(),
            });
        }
        if crate::mesh::io::Format::from_path(path).is_none() {
            return Err(ViewError::input(
                path,
                "not a file the viewer reads: give a mesh (.obj, .off, .ply), a .glb, a match folder or a batch folder",
            ));
        }
        let sibling = path.with_extension("json");
        let report = options
            .report
            .clone()
            .or_else(|| sibling.is_file().then_some(sibling));
        Ok(ViewInput::Flattening {
            mesh: path.to_path_buf(),
            report,
        })
    }
}

/// Writes the page of `input` to `output` (atomically). A table also writes one page
/// per item into the folder `OUTPUT_STEM_items/` beside `output`, which its rows link
/// to (each page self-contained too).
pub fn write_page(input: &ViewInput, output: &Path) -> Result<PageWritten, ViewError> {
    if let ViewInput::Table { folder } = input {
        return table::write_table(folder, output);
    }
    let built = build_page(input)?;
    write_built(built, output)
}

/// The document of a page of one result (not a table).
pub(crate) fn build_page(input: &ViewInput) -> Result<BuiltPage, ViewError> {
    match input {
        ViewInput::Flattening { mesh, report } => flattening::build(mesh, report.as_deref()),
        ViewInput::Match {
            folder,
            a,
            b,
            landmarks,
        } => matching::build(folder, a.as_deref(), b.as_deref(), landmarks.as_deref()),
        ViewInput::Gltf { file } => morph::build(file),
        ViewInput::Table { folder } => Err(ViewError::input(
            folder,
            "internal error: a table is written by write_page",
        )),
    }
}

pub(crate) fn write_built(built: BuiltPage, output: &Path) -> Result<PageWritten, ViewError> {
    let mut data = built.data;
    data.set("notes", serde_json::json!(built.notes));
    let html = data.html();
    crate::fsutil::write_atomically(output, |w| w.write_all(html.as_bytes()))
        .map_err(ViewError::io(output))?;
    Ok(PageWritten {
        kind: built.kind,
        path: output.to_path_buf(),
        bytes: html.len(),
        triangles: built.triangles,
        notes: built.notes,
        items: vec![],
    })
}

/// Reads a JSON file.
pub(crate) fn read_json(path: &Path) -> Result<serde_json::Value, ViewError> {
    let text = std::fs::read(path).map_err(ViewError::io(path))?;
    serde_json::from_slice(&text)
        .map_err(|e| ViewError::input(path, format!("not valid JSON: {e}")))
}

/// The value at a dotted `path` of a JSON document (`"measures.angle.mean"`).
pub(crate) fn json_at<'a>(doc: &'a serde_json::Value, path: &str) -> Option<&'a serde_json::Value> {
    path.split('.').try_fold(doc, |v, key| v.get(key))
}

/// The report's numbers a page lists: for every `(label, path)` whose value exists in
/// `doc` and is a number, a string or a boolean, `{"label", "path", "value"}`.
pub(crate) fn numbers(doc: &serde_json::Value, fields: &[(&str, &str)]) -> serde_json::Value {
    fields
        .iter()
        .filter_map(|(label, path)| {
            let v = json_at(doc, path)?;
            (v.is_number() || v.is_string() || v.is_boolean())
                .then(|| serde_json::json!({"label": label, "path": path, "value": v}))
        })
        .collect()
}
