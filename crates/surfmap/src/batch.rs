//! Many meshes at once: a thread pool that runs one job per input file and never lets
//! one bad mesh stop the others ([`run`]), the job itself — read, flatten, write the
//! mesh, its seams and its report ([`flatten_file`]) —, unique output names for the
//! inputs ([`output_names`]), and the summary table, one [`BatchRow`] per mesh, written
//! as CSV ([`write_csv`]).
//!
//! The command line's `surfmap flatten a.obj b.obj … -o DIR/` and the Python package's
//! `flatten_many` and `flatten_file` (also the unit of work on a Dask or Ray cluster)
//! produce these rows, so their tables have the same columns.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Serialize;

use crate::mesh::TriMesh;
use crate::mesh::io::ObjMaterial;
use crate::output::{UvLayout, flatten_to_mesh};
use crate::param::flatten::{FlattenError, FlattenOptions};
use crate::report::{DefectWording, FlattenReport};

/// One mesh of a batch: what was written, what was done to it, and the headline numbers
/// of its report (the same values as in its `NAME.json`), or why it failed. Numbers are
/// `None` for a failed mesh.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BatchRow {
    /// The input file, as given.
    pub input: String,
    /// `"ok"` or `"failed"`.
    pub status: &'static str,
    /// The flattened mesh written (OBJ with texture coordinates).
    pub output: Option<String>,
    /// The full report written (JSON, the fields of [`FlattenReport`]).
    pub report: Option<String>,
    pub vertices: Option<usize>,
    pub triangles: Option<usize>,
    /// What was done around the solve ([`FlattenReport::plan`]): `disc as is`, `fill 2
    /// holes`, `cut open along seams (closed, genus 0)`, `…, then cut open to lower the
    /// distortion`.
    pub plan: Option<String>,
    /// Initial map used (`lscm`, `mean_value`, `given`, `multilevel`).
    pub start: Option<String>,
    pub iterations: Option<usize>,
    pub converged: Option<bool>,
    /// Final energy per unit 3D area.
    pub energy: Option<f64>,
    /// Symmetric Dirichlet energy `σ1² + σ2² + σ1⁻² + σ2⁻²` (isometry = 4): area-weighted
    /// mean and maximum over the triangles, after the UVs are scaled to the 3D area.
    pub symmetric_dirichlet: Option<f64>,
    pub symmetric_dirichlet_max: Option<f64>,
    /// Thesis angle distortion `σ1/σ2`: area-weighted mean and maximum (ideal 1).
    pub angle_mean: Option<f64>,
    pub angle_max: Option<f64>,
    /// Thesis area distortion `σ1σ2` after scaling: minimum, area-weighted mean and
    /// maximum (ideal 1).
    pub area_min: Option<f64>,
    pub area_mean: Option<f64>,
    pub area_max: Option<f64>,
    pub flipped_triangles: Option<usize>,
    /// Whether the boundary of the map crosses itself.
    pub boundary_overlap: Option<bool>,
    /// `bijective` or `locally_injective` ([`crate::Guarantee`]).
    pub guarantee: Option<String>,
    pub holes_filled: Option<usize>,
    /// Seam edges of the map and their 3D length, all cuts together (0 for a map that
    /// was not cut open).
    pub seam_edges: Option<usize>,
    pub seam_length: Option<f64>,
    /// The distortion-driven cutting ([`crate::FlattenOptions::max_distortion`]; all
    /// empty without it): the bound on the mean symmetric Dirichlet distortion (1 for an
    /// isometry: the mean of [`Self::symmetric_dirichlet`]'s density over 4), whether the
    /// map meets it, the seam paths the map has from it and their 3D length.
    pub distortion_bound: Option<f64>,
    pub distortion_bound_met: Option<bool>,
    pub distortion_cuts: Option<usize>,
    pub distortion_seam_length: Option<f64>,
    /// Wall-clock seconds for this mesh: reading, flattening, measuring, writing.
    pub time_s: f64,
    /// Why the mesh failed (the error message, remedy included).
    pub error: Option<String>,
}

impl BatchRow {
    /// The column names of [`BatchRow::csv_record`], in order (the field names).
    pub const CSV_HEADER: [&'static str; 30] = [
        "input",
        "status",
        "output",
        "report",
        "vertices",
        "triangles",
        "plan",
        "start",
        "iterations",
        "converged",
        "energy",
        "symmetric_dirichlet",
        "symmetric_dirichlet_max",
        "angle_mean",
        "angle_max",
        "area_min",
        "area_mean",
        "area_max",
        "flipped_triangles",
        "boundary_overlap",
        "guarantee",
        "holes_filled",
        "seam_edges",
        "seam_length",
        "distortion_bound",
        "distortion_bound_met",
        "distortion_cuts",
        "distortion_seam_length",
        "time_s",
        "error",
    ];

    /// A mesh flattened and written to `output`, its report to `report_file`: the
    /// report's own numbers.
    pub fn done(
        input: &Path,
        output: &Path,
        report_file: &Path,
        report: &FlattenReport<'_>,
        time_s: f64,
    ) -> Self {
        let m = &report.measures;
        let cuts = report.distortion_cuts;
        let as_text = |v: serde_json::Result<serde_json::Value>| {
            v.ok().and_then(|v| v.as_str().map(str::to_owned))
        };
        Self {
            input: input.display().to_string(),
            status: "ok",
            output: Some(output.display().to_string()),
            report: Some(report_file.display().to_string()),
            vertices: Some(report.vertices),
            triangles: Some(report.triangles),
            plan: Some(report.plan.clone()),
            start: as_text(serde_json::to_value(report.start)),
            iterations: Some(report.iterations),
            converged: Some(report.converged),
            energy: Some(report.energy),
            symmetric_dirichlet: Some(report.symmetric_dirichlet),
            symmetric_dirichlet_max: Some(m.symmetric_dirichlet_max),
            angle_mean: Some(m.measures.angle.mean),
            angle_max: Some(m.measures.angle.max),
            area_min: Some(m.measures.area.min),
            area_mean: Some(m.measures.area.mean),
            area_max: Some(m.measures.area.max),
            flipped_triangles: Some(report.flipped_triangles),
            boundary_overlap: Some(m.boundary_overlap.self_intersecting),
            guarantee: as_text(serde_json::to_value(report.guarantee)),
            holes_filled: Some(report.holes_filled),
            seam_edges: Some(report.seams.map_or(0, |s| s.edges.len())),
            seam_length: Some(report.seams.map_or(0.0, |s| s.length)),
            distortion_bound: cuts.map(|c| c.bound),
            distortion_bound_met: cuts.map(|c| c.met),
            distortion_cuts: cuts.map(|c| {
                c.history[..c.best_round]
                    .iter()
                    .map(|r| r.from_vertices.len())
                    .sum()
            }),
            distortion_seam_length: cuts.map(|c| c.seam_length_added),
            time_s,
            error: None,
        }
    }

    /// A mesh that failed with `error`.
    pub fn failed(input: &Path, error: String, time_s: f64) -> Self {
        Self {
            input: input.display().to_string(),
            status: "failed",
            output: None,
            report: None,
            vertices: None,
            triangles: None,
            plan: None,
            start: None,
            iterations: None,
            converged: None,
            energy: None,
            symmetric_dirichlet: None,
            symmetric_dirichlet_max: None,
            angle_mean: None,
            angle_max: None,
            area_min: None,
            area_mean: None,
            area_max: None,
            flipped_triangles: None,
            boundary_overlap: None,
            guarantee: None,
            holes_filled: None,
            seam_edges: None,
            seam_length: None,
            distortion_bound: None,
            distortion_bound_met: None,
            distortion_cuts: None,
            distortion_seam_length: None,
            time_s,
            error: Some(error),
        }
    }

    /// Whether the mesh was flattened.
    pub fn ok(&self) -> bool {
        self.error.is_none()
    }

    /// The row's values as CSV fields, in the order of [`BatchRow::CSV_HEADER`]:
    /// empty for `None`, floats in their shortest exact form, text quoted when needed
    /// (an error message may span lines: a list of defects; a plan has commas).
    pub fn csv_record(&self) -> String {
        let fields: [String; Self::CSV_HEADER.len()] = [
            self.input.clone(),
            self.status.to_owned(),
            opt(&self.output),
            opt(&self.report),
            opt(&self.vertices),
            opt(&self.triangles),
            opt(&self.plan),
            opt(&self.start),
            opt(&self.iterations),
            opt(&self.converged),
            opt(&self.energy),
            opt(&self.symmetric_dirichlet),
            opt(&self.symmetric_dirichlet_max),
            opt(&self.angle_mean),
            opt(&self.angle_max),
            opt(&self.area_min),
            opt(&self.area_mean),
            opt(&self.area_max),
            opt(&self.flipped_triangles),
            opt(&self.boundary_overlap),
            opt(&self.guarantee),
            opt(&self.holes_filled),
            opt(&self.seam_edges),
            opt(&self.seam_length),
            opt(&self.distortion_bound),
            opt(&self.distortion_bound_met),
            opt(&self.distortion_cuts),
            opt(&self.distortion_seam_length),
            self.time_s.to_string(),
            opt(&self.error),
        ];
        csv_line(&fields)
    }
}

/// A table cell: empty for `None`, else the value's text (floats in their shortest
/// exact form).
pub fn opt<T: ToString>(v: &Option<T>) -> String {
    v.as_ref().map(T::to_string).unwrap_or_default()
}

/// One CSV record: the fields quoted as [`csv_field`] says, joined by commas.
pub fn csv_line(fields: &[String]) -> String {
    fields
        .iter()
        .map(|f| csv_field(f))
        .collect::<Vec<_>>()
        .join(",")
}

/// One CSV field (RFC 4180): quoted, with quotes doubled, when it holds a comma, a
/// quote or a line break.
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// Writes the summary table: a header and one line per row (atomically).
pub fn write_csv(path: &Path, rows: &[BatchRow]) -> std::io::Result<()> {
    write_table(
        path,
        &BatchRow::CSV_HEADER,
        rows.iter().map(BatchRow::csv_record),
    )
}

/// Writes a CSV table atomically: the `header` line, then one line per record (each
/// record's fields already joined, as [`csv_field`] quotes them).
pub fn write_table(
    path: &Path,
    header: &[&str],
    records: impl Iterator<Item = String>,
) -> std::io::Result<()> {
    crate::fsutil::write_atomically(path, |w| {
        writeln!(w, "{}", header.join(","))?;
        for r in records {
            writeln!(w, "{r}")?;
        }
        Ok(())
    })
}

/// An output name per input: the file stem, made unique by `-2`, `-3`, … in input
/// order where stems repeat (`a/x.obj`, `b/x.off` → `x`, `x-2`).
pub fn output_names(inputs: &[PathBuf]) -> Vec<String> {
    let mut taken: HashMap<String, usize> = HashMap::new();
    let stems: Vec<String> = inputs
        .iter()
        .map(|p| {
            p.file_stem()
                .map_or_else(|| "mesh".to_owned(), |s| s.to_string_lossy().into_owned())
        })
        .collect();
    let mut used: std::collections::HashSet<String> = stems.iter().cloned().collect();
    stems
        .into_iter()
        .map(|stem| {
            let seen = taken.entry(stem.clone()).or_insert(0);
            *seen += 1;
            if *seen == 1 {
                return stem;
            }
            // The next free `stem-k` (an input may itself be called `x-2`).
            let mut k = *seen;
            loop {
                let name = format!("{stem}-{k}");
                if used.insert(name.clone()) {
                    return name;
                }
                k += 1;
            }
        })
        .collect()
}

/// Where a batch writes each mesh: `dir/NAME.obj` (laid out as `layout` asks, with the
/// `material`), `dir/NAME.json` (its report) and, for a surface cut open, with `seams`
/// a folder, `seams/NAME.seams.obj`.
#[derive(Clone, Copy, Debug)]
pub struct BatchOutput<'a> {
    pub dir: &'a Path,
    pub layout: UvLayout,
    pub material: Option<&'a ObjMaterial>,
    pub seams: Option<&'a Path>,
}

/// How a front end reads a mesh and words what went wrong.
#[derive(Clone, Copy)]
pub struct FrontEnd<'a> {
    /// Reads a mesh file (and repairs it, if the front end was asked to); the error is
    /// the message for the row.
    pub read: &'a (dyn Fn(&Path) -> Result<TriMesh, String> + Sync),
    /// A flattening error's message, its remedy in the front end's terms.
    pub flatten_error: fn(&FlattenError) -> String,
    /// A defect's message in the report.
    pub wording: DefectWording,
}

/// One mesh of a batch: reads `input`, flattens it with `options` and writes it as
/// `output` says under the name `name`. Returns its row, or the failed row with the
/// message (a failure never stops the batch).
pub fn flatten_file(
    input: &Path,
    name: &str,
    options: &FlattenOptions,
    output: &BatchOutput<'_>,
    front: &FrontEnd<'_>,
) -> BatchRow {
    let clock = std::time::Instant::now();
    let row = || -> Result<BatchRow, String> {
        let mesh = (front.read)(input)?;
        let flat = flatten_to_mesh(mesh, options, output.layout, &mut |_| {}).map_err(|e| {
            format!(
                "cannot flatten {}: {}",
                input.display(),
                (front.flatten_error)(&e)
            )
        })?;
        let obj = output.dir.join(format!("{name}.obj"));
        crate::write_obj(&obj, &flat.output, output.material).map_err(|e| e.to_string())?;
        if let Some(folder) = output.seams {
            let path = folder.join(format!("{name}.seams.obj"));
            flat.write_seams(&path)
                .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        }
        let report = flat
            .report(Some(input), front.wording)
            .map_err(|e| format!("cannot measure {}: {e}", input.display()))?;
        let json = output.dir.join(format!("{name}.json"));
        crate::fsutil::write_json(&json, &report)
            .map_err(|e| format!("cannot write {}: {e}", json.display()))?;
        Ok(BatchRow::done(
            input,
            &obj,
            &json,
            &report,
            clock.elapsed().as_secs_f64(),
        ))
    };
    row().unwrap_or_else(|e| BatchRow::failed(input, e, clock.elapsed().as_secs_f64()))
}

/// A thread pool of `threads` threads (0: one per core) for a batch.
pub fn pool(threads: usize) -> Result<rayon::ThreadPool, PoolError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|source| PoolError { threads, source })
}

/// Why a batch could not start.
#[derive(Debug, thiserror::Error)]
#[error("cannot start {threads} worker threads: {source}")]
pub struct PoolError {
    pub threads: usize,
    #[source]
    pub source: rayon::ThreadPoolBuildError,
}

/// A row of a batch table that can stand for an input whose job failed.
pub trait FailedRow {
    /// The row of `input` that failed with `error` after `time_s` seconds.
    fn failed(input: &Path, error: String, time_s: f64) -> Self;
}

impl FailedRow for BatchRow {
    fn failed(input: &Path, error: String, time_s: f64) -> Self {
        BatchRow::failed(input, error, time_s)
    }
}

/// Runs `job` on every input on a pool of `threads` threads (0: one per core) and
/// returns the rows in input order (flattening: [`BatchRow`]; registration:
/// [`crate::apps::register::batch::RegisterRow`]). Everything `job` computes runs on that pool, its
/// parallel loops included, so `threads` bounds the cores used. `on_done` sees each row
/// as it finishes (from the worker thread; for progress). A job that panics gives a
/// failed row naming the panic instead of stopping the batch.
pub fn run<R: FailedRow + Send>(
    inputs: &[PathBuf],
    threads: usize,
    job: impl Fn(usize, &Path) -> R + Sync,
    on_done: impl Fn(&R) + Sync,
) -> Result<Vec<R>, PoolError> {
    Ok(pool(threads)?.install(|| {
        inputs
            .par_iter()
            .enumerate()
            .with_max_len(1)
            .map(|(i, input)| {
                let clock = std::time::Instant::now();
                let row = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| job(i, input)))
                    .unwrap_or_else(|panic| {
                        let what = panic
                            .downcast_ref::<&str>()
                            .map(|s| s.to_string())
                            .or_else(|| panic.downcast_ref::<String>().cloned())
                            .unwrap_or_default();
                        R::failed(
                            input,
                            format!("internal error ({what}); please report this mesh"),
                            clock.elapsed().as_secs_f64(),
                        )
                    });
                on_done(&row);
                row
            })
            .collect()
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table's columns are the row's fields, in order: the dictionaries the Python
    /// package returns and the CSV lines have the same names.
    #[test]
    fn the_csv_columns_are_the_fields() {
        let row = BatchRow::failed(Path::new("m.obj"), "bad".into(), 1.0);
        let value = serde_json::to_value(&row).unwrap();
        assert_eq!(value.as_object().unwrap().len(), BatchRow::CSV_HEADER.len());
        // The serialized text keeps the fields' order (what Python's dictionaries get).
        let text = serde_json::to_string(&row).unwrap();
        let at: Vec<usize> = BatchRow::CSV_HEADER
            .iter()
            .map(|name| text.find(&format!("\"{name}\":")).expect(name))
            .collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "{text}");
    }

    /// A cone cut for a distortion bound: one generator from the apex to the rim unrolls
    /// it (one cut, the slant height long, 12 edges for 12 rings); the row says so and
    /// repeats its report's numbers.
    #[test]
    fn a_row_says_what_was_done_and_repeats_the_report() {
        use crate::mesh::validate::Defect;
        let (radius, height) = (1.0, 3.0);
        let mesh = crate::mesh::generate::cone(radius, height, 12, 48);
        let options = crate::FlattenOptions::default().with_max_distortion(1.01);
        let r = crate::flatten(&mesh, &options).unwrap();
        let report = FlattenReport::measure(None, &mesh, &r, Defect::message).unwrap();
        let row = BatchRow::done(
            Path::new("cone.obj"),
            Path::new("out/cone.obj"),
            Path::new("out/cone.json"),
            &report,
            0.5,
        );
        assert_eq!(
            row.plan.as_deref(),
            Some("cut open to lower the distortion")
        );
        assert_eq!(row.seam_edges, Some(12));
        let slant = radius.hypot(height);
        assert!((row.seam_length.unwrap() - slant).abs() < 1e-12);
        assert_eq!(row.distortion_seam_length, row.seam_length);
        assert_eq!(row.distortion_cuts, Some(1));
        assert_eq!(row.distortion_bound, Some(1.01));
        assert_eq!(row.distortion_bound_met, Some(true));
        assert_eq!(row.guarantee.as_deref(), Some("bijective"));
        assert_eq!(row.holes_filled, Some(0));
        // The measures, as an independent measurement of the map's corners gives them.
        let again = crate::distortion_report(
            &mesh.positions,
            &mesh.triangles,
            &r.corner_uvs(&mesh.triangles),
            &crate::MeasureOptions::default(),
        )
        .unwrap();
        assert_eq!(row.symmetric_dirichlet, Some(again.symmetric_dirichlet));
        assert_eq!(
            row.symmetric_dirichlet_max,
            Some(again.symmetric_dirichlet_max)
        );
        assert_eq!(row.area_mean, Some(again.measures.area.mean));
        assert!(row.symmetric_dirichlet_max >= row.symmetric_dirichlet);
        // The bound is on the mean over 4 (an isometry's density is 4).
        assert!(row.symmetric_dirichlet.unwrap() / 4.0 <= 1.01);

        // A disc as is: no seam, no distortion columns.
        let disc = crate::mesh::generate::bumpy_disc(6, 0.3);
        let r = crate::flatten(&disc, &crate::FlattenOptions::default()).unwrap();
        let report = FlattenReport::measure(None, &disc, &r, Defect::message).unwrap();
        let row = BatchRow::done(Path::new("d"), Path::new("o"), Path::new("j"), &report, 0.1);
        assert_eq!(row.plan.as_deref(), Some("disc as is"));
        assert_eq!((row.seam_edges, row.seam_length), (Some(0), Some(0.0)));
        assert_eq!((row.distortion_bound, row.distortion_cuts), (None, None));
        let fields = row.csv_record();
        assert!(
            fields.contains(",disc as is,") && fields.contains(",bijective,"),
            "{fields}"
        );
    }

    #[test]
    fn output_names_are_unique_stems() {
        let inputs: Vec<PathBuf> = ["a/x.obj", "b/x.off", "y.ply", "c/x.obj", "x-2.obj"]
            .iter()
            .map(PathBuf::from)
            .collect();
        assert_eq!(output_names(&inputs), ["x", "x-3", "y", "x-4", "x-2"]);
    }

    /// Quoted fields survive a round trip through an independent reading of RFC 4180.
    #[test]
    fn csv_quotes_commas_quotes_and_line_breaks() {
        let row = BatchRow::failed(
            Path::new("dir,with comma/m.obj"),
            "the mesh cannot be flattened as a disc:\n  - 2 \"holes\", fill them".into(),
            0.25,
        );
        let line = row.csv_record();
        let fields = parse_csv_line(&line);
        assert_eq!(fields.len(), BatchRow::CSV_HEADER.len());
        assert_eq!(fields[0], "dir,with comma/m.obj");
        assert_eq!(fields[1], "failed");
        let n = BatchRow::CSV_HEADER.len();
        assert_eq!(fields[n - 2], "0.25");
        assert_eq!(fields[n - 1], row.error.as_deref().unwrap());
        assert!(fields[2..n - 2].iter().all(String::is_empty));
    }

    /// A minimal RFC 4180 reader for one record (the test's oracle).
    fn parse_csv_line(s: &str) -> Vec<String> {
        let mut out = vec![String::new()];
        let mut quoted = false;
        let mut chars = s.chars().peekable();
        while let Some(c) = chars.next() {
            match (quoted, c) {
                (false, ',') => out.push(String::new()),
                (false, '"') => quoted = true,
                (true, '"') if chars.peek() == Some(&'"') => {
                    chars.next();
                    out.last_mut().unwrap().push('"');
                }
                (true, '"') => quoted = false,
                (_, c) => out.last_mut().unwrap().push(c),
            }
        }
        out
    }

    /// Every input gets its row in order; a panicking job fails its own row only; the
    /// pool has the threads asked for, and the job's own parallel loops run on it.
    #[test]
    fn run_isolates_failures_and_keeps_order() {
        let inputs: Vec<PathBuf> = (0..6).map(|i| PathBuf::from(format!("m{i}.obj"))).collect();
        let done = std::sync::atomic::AtomicUsize::new(0);
        let rows = run(
            &inputs,
            2,
            |i, input| {
                assert_eq!(rayon::current_num_threads(), 2);
                if i == 3 {
                    panic!("boom at {}", input.display());
                }
                let inner: usize = (0..100usize).into_par_iter().sum();
                BatchRow::failed(input, format!("job {i}: {inner}"), 0.0)
            },
            |_| {
                done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            },
        )
        .unwrap();
        assert_eq!(done.into_inner(), 6);
        for (i, r) in rows.iter().enumerate() {
            assert_eq!(r.input, format!("m{i}.obj"));
            if i == 3 {
                let e = r.error.as_deref().unwrap();
                assert!(
                    e.contains("boom at m3.obj") && e.contains("internal error"),
                    "{e}"
                );
            } else {
                assert_eq!(r.error.as_deref(), Some(format!("job {i}: 4950").as_str()));
            }
        }
    }
}
