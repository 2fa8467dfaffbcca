//! Many scans registered onto one template: the job of one scan ([`RegisterJob::register_file`]:
//! read, match, place, write), the table of all of them, one [`RegisterRow`] per scan
//! (`summary.csv` and `summary.json`), and a rerun that skips what is done
//! ([`register_many`] with `resume`).
//!
//! Files under the output folder `DIR`, each written to a temporary file and renamed into
//! place ([`crate::fsutil::write_atomically`]), so an interrupted batch leaves none half
//! written:
//!
//! ```text
//! DIR/registered/NAME.obj    the template's triangles at the registered positions
//! DIR/registered/NAME.json   the scan's row (written last: the scan is done)
//! DIR/matches/NAME/          the match folder (with keep_matches)
//! DIR/summary.csv, .json     every scan's row, in input order
//! ```
//!
//! A sequence ([`register_sequence`]) registers the frames one after the other (with the
//! warm start each from the previous frame's result, [`super::sequence`]) and fills the
//! rows' `started_from` and motion and jitter columns.
//!
//! A scan that cannot be read or matched is a failed row with the reason; it never stops
//! the others. The thread pool, panics included, is [`crate::batch::run`]'s.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::sequence::{frame_motions, register_frame};
use super::{RegisterError, Template};
use crate::batch::{FailedRow, PoolError, csv_line, opt};
use crate::matching::{Guidance, Landmarks, MatchError, MatchOptions};
use crate::mesh::TriMesh;

/// One scan of a registration batch: what was written and the match's headline numbers,
/// or why it failed (numbers `None`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegisterRow {
    /// The output name (`registered/NAME.obj`): the scan's file stem, made unique.
    pub name: String,
    /// The scan file, as given.
    pub input: String,
    /// `"ok"` (registered; see `verdict`) or `"failed"` (see `error`).
    pub status: String,
    /// The registered mesh written.
    pub output: Option<String>,
    /// The match's confidence verdict: `ok`, `doubtful` or `failed`.
    pub verdict: Option<String>,
    /// Why the verdict is not `ok` (the report's reasons, joined by `; `).
    pub reasons: Option<String>,
    /// Template vertices matched on the scan, over all template vertices.
    pub matched_fraction: Option<f64>,
    /// Template vertices placed by the harmonic extension (no counterpart).
    pub extended: Option<usize>,
    /// The match's final energy (per unit area).
    pub energy: Option<f64>,
    /// Wall-clock seconds for this scan: reading, matching, placing, writing.
    pub seconds: f64,
    /// Why the scan failed (the message, remedy included).
    pub error: Option<String>,
    /// In a sequence: the frame whose registration this one started from (its name), or
    /// `template`.
    #[serde(default)]
    pub started_from: Option<String>,
    /// In a sequence: the mean non-rigid displacement of the registered vertices since
    /// the previous frame, and the mean and 95th percentile of their jitter (half the
    /// rigidly aligned second difference in time), in the scans' units
    /// ([`super::sequence::frame_motions`]).
    #[serde(default)]
    pub motion_mean: Option<f64>,
    #[serde(default)]
    pub jitter_mean: Option<f64>,
    #[serde(default)]
    pub jitter_p95: Option<f64>,
}

impl RegisterRow {
    /// The column names of [`RegisterRow::csv_record`], in order (the field names).
    pub const CSV_HEADER: [&'static str; 15] = [
        "name",
        "input",
        "status",
        "output",
        "verdict",
        "reasons",
        "matched_fraction",
        "extended",
        "energy",
        "seconds",
        "error",
        "started_from",
        "motion_mean",
        "jitter_mean",
        "jitter_p95",
    ];

    /// The row's values as CSV fields (empty for `None`, quoted when needed).
    pub fn csv_record(&self) -> String {
        let fields: [String; Self::CSV_HEADER.len()] = [
            self.name.clone(),
            self.input.clone(),
            self.status.clone(),
            opt(&self.output),
            opt(&self.verdict),
            opt(&self.reasons),
            opt(&self.matched_fraction),
            opt(&self.extended),
            opt(&self.energy),
            self.seconds.to_string(),
            opt(&self.error),
            opt(&self.started_from),
            opt(&self.motion_mean),
            opt(&self.jitter_mean),
            opt(&self.jitter_p95),
        ];
        csv_line(&fields)
    }

    /// Whether the scan was registered (whatever its verdict).
    pub fn ok(&self) -> bool {
        self.status == "ok"
    }
}

impl FailedRow for RegisterRow {
    fn failed(input: &Path, error: String, time_s: f64) -> Self {
        Self {
            name: input
                .file_stem()
                .map_or_else(|| "scan".to_owned(), |s| s.to_string_lossy().into_owned()),
            input: input.display().to_string(),
            status: "failed".to_owned(),
            output: None,
            verdict: None,
            reasons: None,
            matched_fraction: None,
            extended: None,
            energy: None,
            seconds: time_s,
            error: Some(error),
            started_from: None,
            motion_mean: None,
            jitter_mean: None,
            jitter_p95: None,
        }
    }
}

/// What every scan of a batch shares: the template, the match options, where to write,
/// and how the front end reads meshes and words a match's errors.
#[derive(Clone, Copy)]
pub struct RegisterJob<'a> {
    pub template: &'a Template,
    pub options: &'a MatchOptions,
    /// The output folder `DIR` (module documentation).
    pub dir: &'a Path,
    /// Also write each scan's match folder `DIR/matches/NAME/`.
    pub keep_matches: bool,
    /// A folder with one landmarks file per scan, `STEM.json` (the scan's file stem), as
    /// `surfmap match --landmarks` reads: `{"names": [...], "A": [template vertex ids],
    /// "B": [scan vertex ids]}`.
    pub landmarks_dir: Option<&'a Path>,
    /// Reads (and repairs, if asked) a scan; the error is the row's message.
    pub read: &'a (dyn Fn(&Path) -> Result<TriMesh, String> + Sync),
    /// A match error worded for the front end (its remedies as its options).
    pub match_error: fn(&MatchError) -> String,
}

/// The landmarks file of `scan` in `dir`: `dir/STEM.json`.
pub fn landmarks_file(dir: &Path, scan: &Path) -> PathBuf {
    let stem = scan.file_stem().unwrap_or_default();
    let mut name = stem.to_os_string();
    name.push(".json");
    dir.join(name)
}

/// Reads a landmarks file (`{"names", "A", "B"}`); the error names the file and the
/// expected form.
pub fn read_landmarks(path: &Path) -> Result<Landmarks, String> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        format!(
            "cannot read landmarks file {}: {e} (--landmarks-dir needs one STEM.json per scan)",
            path.display()
        )
    })?;
    serde_json::from_str(&text).map_err(|e| {
        format!(
            "invalid landmarks file {}: {e}; expected {{\"names\": [...], \"A\": [template vertex ids], \"B\": [scan vertex ids]}}",
            path.display()
        )
    })
}

impl RegisterJob<'_> {
    /// `DIR/registered`.
    pub fn registered_dir(&self) -> PathBuf {
        self.dir.join("registered")
    }

    /// Creates `DIR/registered` (if missing) and returns it.
    fn create_registered_dir(&self) -> Result<PathBuf, RegisterBatchError> {
        let folder = self.registered_dir();
        std::fs::create_dir_all(&folder).map_err(|source| RegisterBatchError::Io {
            path: folder.clone(),
            source,
        })?;
        Ok(folder)
    }

    /// Registers one scan under `name` and writes its files: its row, or the failed row
    /// with the reason (a failure never stops the batch).
    pub fn register_file(&self, input: &Path, name: &str) -> RegisterRow {
        self.register_frame_file(input, name, None).0
    }

    /// [`RegisterJob::register_file`] from an earlier registration `start`: the name of
    /// its frame and the template's vertices registered on it ([`register_frame`];
    /// `None`: from the template). Also returns the registered positions.
    pub fn register_frame_file(
        &self,
        input: &Path,
        name: &str,
        start: Option<(&str, &[[f64; 3]])>,
    ) -> (RegisterRow, Option<Vec<[f64; 3]>>) {
        let clock = std::time::Instant::now();
        let mut positions = None;
        let mut row = || -> Result<RegisterRow, String> {
            let scan = (self.read)(input)?;
            let landmarks = match self.landmarks_dir {
                Some(dir) => Some(read_landmarks(&landmarks_file(dir, input))?),
                None => None,
            };
            let guidance = Guidance {
                landmarks,
                ..Guidance::default()
            };
            let previous = start.map(|s| s.1);
            let registered =
                match register_frame(self.template, previous, &scan, &guidance, self.options) {
                    Ok(r) => r,
                    Err(RegisterError::Match(e)) => {
                        return Err(format!(
                            "cannot match the template onto this scan: {}",
                            (self.match_error)(&e)
                        ));
                    }
                    Err(e) => return Err(e.to_string()),
                };
            let folder = self.registered_dir();
            let obj = folder.join(format!("{name}.obj"));
            crate::write_obj(&obj, &registered.mesh(self.template), None)
                .map_err(|e| e.to_string())?;
            if self.keep_matches {
                let dir = self.dir.join("matches").join(name);
                registered
                    .matched_with
                    .write_folder(&dir, false)
                    .map_err(|e| format!("cannot write the match into {}: {e}", dir.display()))?;
            }
            let report = &registered.matched_with.report;
            let confidence = &report.confidence;
            let row = RegisterRow {
                name: name.to_owned(),
                input: input.display().to_string(),
                status: "ok".to_owned(),
                output: Some(obj.display().to_string()),
                verdict: serde_json::to_value(confidence.verdict)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_owned)),
                reasons: (!confidence.reasons.is_empty()).then(|| confidence.reasons.join("; ")),
                matched_fraction: Some(registered.placement.matched_fraction()),
                extended: Some(registered.placement.extended.len()),
                energy: Some(report.energy),
                seconds: clock.elapsed().as_secs_f64(),
                error: None,
                started_from: None,
                motion_mean: None,
                jitter_mean: None,
                jitter_p95: None,
            };
            let json = folder.join(format!("{name}.json"));
            crate::fsutil::write_json(&json, &row)
                .map_err(|e| format!("cannot write {}: {e}", json.display()))?;
            positions = Some(registered.placement.positions);
            Ok(row)
        };
        let row = row().unwrap_or_else(|e| {
            let mut failed = RegisterRow::failed(input, e, clock.elapsed().as_secs_f64());
            failed.name = name.to_owned();
            failed
        });
        (row, positions)
    }

    /// The row of a scan registered by an earlier run (for `--resume`): its
    /// `registered/NAME.json` says `ok` for the same input and its mesh is there.
    pub fn done_row(&self, input: &Path, name: &str) -> Option<RegisterRow> {
        let json = self.registered_dir().join(format!("{name}.json"));
        let row: RegisterRow = serde_json::from_slice(&std::fs::read(json).ok()?).ok()?;
        let same = row.ok() && row.input == input.display().to_string();
        (same && Path::new(row.output.as_deref()?).is_file()).then_some(row)
    }
}

/// Registers every scan of `inputs` under `names` on `threads` threads (0: one per core)
/// and returns the rows in input order; with `resume`, scans done by an earlier run
/// ([`RegisterJob::done_row`]) keep their rows and are not registered again. `on_done`
/// sees each row as it finishes (resumed ones first). Creates `DIR/registered`.
pub fn register_many(
    job: &RegisterJob<'_>,
    inputs: &[PathBuf],
    names: &[String],
    threads: usize,
    resume: bool,
    on_done: impl Fn(&RegisterRow) + Sync,
) -> Result<Vec<RegisterRow>, RegisterBatchError> {
    job.create_registered_dir()?;
    let mut rows: Vec<Option<RegisterRow>> = inputs
        .iter()
        .zip(names)
        .map(|(input, name)| resume.then(|| job.done_row(input, name)).flatten())
        .collect();
    for row in rows.iter().flatten() {
        on_done(row);
    }
    let todo: Vec<usize> = (0..inputs.len()).filter(|&i| rows[i].is_none()).collect();
    let paths: Vec<PathBuf> = todo.iter().map(|&i| inputs[i].clone()).collect();
    let done = crate::batch::run(
        &paths,
        threads,
        |k, input| job.register_file(input, &names[todo[k]]),
        on_done,
    )?;
    for (k, mut row) in done.into_iter().enumerate() {
        // A panicking job's row was named from its file stem: give it its unique name.
        row.name.clone_from(&names[todo[k]]);
        rows[todo[k]] = Some(row);
    }
    Ok(rows.into_iter().flatten().collect())
}

/// Registers the frames `inputs` (named `names`) in order and fills every row's
/// `started_from`, motion and jitter columns ([`super::sequence`]). With `warm_start`,
/// each frame is registered from the last frame registered with verdict `ok` before it
/// (the template for the first, and while none is); without, every frame from the
/// template. `on_done` sees each row as it finishes (without the motion columns, which
/// need the next frame). Creates `DIR/registered`.
/// The frames run one at a time, each match's parallel loops on a pool of `threads`
/// threads (0: one per core).
pub fn register_sequence(
    job: &RegisterJob<'_>,
    inputs: &[PathBuf],
    names: &[String],
    threads: usize,
    warm_start: bool,
    on_done: impl Fn(&RegisterRow) + Sync,
) -> Result<Vec<RegisterRow>, RegisterBatchError> {
    crate::batch::pool(threads)?
        .install(|| sequence_on_pool(job, inputs, names, warm_start, &on_done))
}

fn sequence_on_pool(
    job: &RegisterJob<'_>,
    inputs: &[PathBuf],
    names: &[String],
    warm_start: bool,
    on_done: &(impl Fn(&RegisterRow) + Sync),
) -> Result<Vec<RegisterRow>, RegisterBatchError> {
    let folder = job.create_registered_dir()?;
    let mut rows = Vec::with_capacity(inputs.len());
    let mut frames: Vec<Option<Vec<[f64; 3]>>> = Vec::with_capacity(inputs.len());
    let mut start: Option<(String, Vec<[f64; 3]>)> = None;
    for (input, name) in inputs.iter().zip(names) {
        let from = start.as_ref().map(|(n, p)| (n.as_str(), &p[..]));
        let (mut row, positions) = job.register_frame_file(input, name, from);
        if row.ok() {
            row.started_from = Some(from.map_or_else(|| "template".to_owned(), |f| f.0.to_owned()));
        }
        if let Some(p) = &positions
            && warm_start
            && row.verdict.as_deref() == Some("ok")
        {
            start = Some((name.clone(), p.clone()));
        }
        on_done(&row);
        rows.push(row);
        frames.push(positions);
    }
    let views: Vec<Option<&[[f64; 3]]>> = frames.iter().map(|f| f.as_deref()).collect();
    for (row, m) in rows.iter_mut().zip(frame_motions(&views)) {
        row.motion_mean = m.motion_mean;
        row.jitter_mean = m.jitter_mean;
        row.jitter_p95 = m.jitter_p95;
        if row.ok() {
            // The frame's own row file gets the columns too (resumable runs read it).
            let json = folder.join(format!("{}.json", row.name));
            crate::fsutil::write_json(&json, &*row).map_err(|source| RegisterBatchError::Io {
                path: json.clone(),
                source,
            })?;
        }
    }
    Ok(rows)
}

/// Writes `DIR/summary.csv` and `DIR/summary.json` (the rows in order); returns their
/// paths.
pub fn write_summary(dir: &Path, rows: &[RegisterRow]) -> Result<[PathBuf; 2], RegisterBatchError> {
    let csv = dir.join("summary.csv");
    crate::batch::write_table(
        &csv,
        &RegisterRow::CSV_HEADER,
        rows.iter().map(RegisterRow::csv_record),
    )
    .map_err(|source| RegisterBatchError::Io {
        path: csv.clone(),
        source,
    })?;
    let json = dir.join("summary.json");
    crate::fsutil::write_json(&json, &rows).map_err(|source| RegisterBatchError::Io {
        path: json.clone(),
        source,
    })?;
    Ok([csv, json])
}

/// Why a batch could not run (a scan's own failure is its row, never this).
#[derive(Debug, thiserror::Error)]
pub enum RegisterBatchError {
    #[error(transparent)]
    Pool(#[from] PoolError),
    #[error("cannot write {}: {source}", .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}
