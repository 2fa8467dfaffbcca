//! The page of a folder of results: a table with one row per item and whatever columns
//! its summary has — `summary.csv` of a batch (`surfmap flatten A B … -o DIR/`, the
//! columns of [`crate::batch::BatchRow`]) or `summary.json` of a registration (a list
//! of objects: `name`, `status`, `verdict`, `matched_fraction`, …, `registered`,
//! `match`) — sortable by any column, each row linking to the item's own page.
//!
//! Item pages are written into the folder `STEM_items/` beside the table's page
//! `STEM.html` (each one self-contained, like the table): a batch row's flattened mesh
//! with its report, a registration row's match folder (its surfaces as `match.json`
//! names them) or, failing that, its registered mesh. A row whose page cannot be made
//! says why in the table, and the others are still written.

use std::path::{Path, PathBuf};

use serde_json::{Map, Value, json};

use super::page::PageData;
use super::{PageKind, PageWritten, ViewError, ViewInput, build_page, read_json, write_built};

/// The summary of a results folder: `summary.json` (a registration) or `summary.csv`
/// (a batch), when it has one.
pub fn summary_file(folder: &Path) -> Option<PathBuf> {
    ["summary.json", "summary.csv"]
        .iter()
        .map(|n| folder.join(n))
        .find(|p| p.is_file())
}

/// A summary as columns (in order of first appearance) and rows of values.
#[derive(Debug, Default, PartialEq)]
pub struct Summary {
    pub columns: Vec<String>,
    pub rows: Vec<Map<String, Value>>,
}

/// Reads `summary.csv` or `summary.json`.
pub fn read_summary(path: &Path) -> Result<Summary, ViewError> {
    if path.extension().is_some_and(|e| e == "json") {
        let doc = read_json(path)?;
        let list = doc
            .as_array()
            .or_else(|| doc.get("rows").and_then(Value::as_array))
            .ok_or_else(|| ViewError::input(path, "expected a list of rows (objects)"))?;
        let mut summary = Summary::default();
        for (i, row) in list.iter().enumerate() {
            let row = row
                .as_object()
                .ok_or_else(|| ViewError::input(path, format!("row {i} is not an object")))?;
            for key in row.keys() {
                if !summary.columns.contains(key) {
                    summary.columns.push(key.clone());
                }
            }
            summary.rows.push(row.clone());
        }
        // JSON objects come with sorted keys: the row's identity and outcome first.
        let first = ["name", "input", "status", "verdict"];
        summary
            .columns
            .sort_by_key(|c| first.iter().position(|f| f == c).unwrap_or(first.len()));
        return Ok(summary);
    }
    let text = std::fs::read_to_string(path).map_err(ViewError::io(path))?;
    let records = parse_csv(&text).map_err(|e| ViewError::input(path, e))?;
    let mut records = records.into_iter();
    let columns = records
        .next()
        .ok_or_else(|| ViewError::input(path, "empty: no header line"))?;
    let rows = records
        .enumerate()
        .map(|(i, fields)| {
            if fields.len() != columns.len() {
                return Err(ViewError::input(
                    path,
                    format!(
                        "record {} has {} fields, the header {}",
                        i + 1,
                        fields.len(),
                        columns.len()
                    ),
                ));
            }
            Ok(columns
                .iter()
                .cloned()
                .zip(fields.iter().map(|f| csv_value(f)))
                .collect())
        })
        .collect::<Result<_, _>>()?;
    Ok(Summary { columns, rows })
}

/// A CSV field as JSON: empty → null, a number, `true`/`false`, else text.
fn csv_value(field: &str) -> Value {
    if field.is_empty() {
        return Value::Null;
    }
    if let Ok(b) = field.parse::<bool>() {
        return json!(b);
    }
    match field.parse::<f64>() {
        Ok(x) if x.is_finite() => json!(x),
        _ => json!(field),
    }
}

/// RFC 4180 records: fields separated by commas, quoted fields may hold commas, doubled
/// quotes and line breaks.
pub fn parse_csv(text: &str) -> Result<Vec<Vec<String>>, String> {
    let mut records = vec![];
    let mut record = vec![];
    let mut field = String::new();
    let mut chars = text.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                field.push('"');
            }
            (true, '"') => quoted = false,
            (true, c) => field.push(c),
            (false, '"') if field.is_empty() => quoted = true,
            (false, ',') => record.push(std::mem::take(&mut field)),
            (false, '\r') => {}
            (false, '\n') => {
                record.push(std::mem::take(&mut field));
                records.push(std::mem::take(&mut record));
            }
            (false, c) => field.push(c),
        }
    }
    if quoted {
        return Err("a quoted field is not closed".into());
    }
    if !field.is_empty() || !record.is_empty() {
        record.push(field);
        records.push(record);
    }
    Ok(records)
}

/// What a row's page is made of, found in the folder.
fn item_input(folder: &Path, row: &Map<String, Value>) -> Result<ViewInput, String> {
    let file = |key: &str| -> Option<PathBuf> {
        let named = Path::new(row.get(key)?.as_str()?);
        // As written (relative to the folder), or by file name in the folder (a batch
        // records its outputs as the command line named them).
        [folder.join(named), folder.join(named.file_name()?)]
            .into_iter()
            .find(|p| p.exists())
    };
    if let Some(dir) = file("match").filter(|d| d.is_dir()) {
        return Ok(ViewInput::Match {
            folder: dir,
            a: None,
            b: None,
            landmarks: None,
        });
    }
    if let Some(mesh) = file("output").or_else(|| file("registered")) {
        return Ok(ViewInput::Flattening {
            mesh,
            report: file("report"),
        });
    }
    Err(match row.get("error").and_then(Value::as_str) {
        Some(e) if !e.is_empty() => format!("failed: {e}"),
        _ => "no output file found in the folder".into(),
    })
}

/// A file name for an item's page: its `name` (or input's stem, or row number) with
/// anything but letters, digits, `-`, `_` and `.` replaced, made unique.
fn page_name(row: &Map<String, Value>, index: usize, taken: &mut Vec<String>) -> String {
    let raw = row
        .get("name")
        .and_then(Value::as_str)
        .map(str::to_owned)
        .or_else(|| {
            let input = row.get("input")?.as_str()?;
            Some(Path::new(input).file_stem()?.to_string_lossy().into_owned())
        })
        .unwrap_or_else(|| format!("item{}", index + 1));
    let safe: String = raw
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    let mut name = safe.clone();
    let mut k = 2;
    while taken.contains(&name) {
        name = format!("{safe}-{k}");
        k += 1;
    }
    taken.push(name.clone());
    name
}

/// Writes the item pages and the table (see the module docs).
pub(crate) fn write_table(folder: &Path, output: &Path) -> Result<PageWritten, ViewError> {
    let summary_path = summary_file(folder).ok_or_else(|| {
        ViewError::input(
            folder,
            "no summary.csv or summary.json: not a batch or registration folder",
        )
    })?;
    let summary = read_summary(&summary_path)?;
    let stem = output
        .file_stem()
        .map_or("view".into(), |s| s.to_string_lossy().into_owned());
    let items_dir_name = format!("{stem}_items");
    let items_dir = output
        .parent()
        .unwrap_or(Path::new(""))
        .join(&items_dir_name);
    let mut items = vec![];
    let mut links = vec![];
    let mut item_notes = vec![];
    let mut taken = vec![];
    for (i, row) in summary.rows.iter().enumerate() {
        let built =
            item_input(folder, row).and_then(|input| build_page(&input).map_err(|e| e.to_string()));
        match built {
            Ok(built) => {
                std::fs::create_dir_all(&items_dir).map_err(ViewError::io(&items_dir))?;
                let name = format!("{}.html", page_name(row, i, &mut taken));
                let written = write_built(built, &items_dir.join(&name))?;
                links.push(json!(format!("{items_dir_name}/{name}")));
                item_notes.push(json!(written.notes.join("; ")));
                items.push(written);
            }
            Err(problem) => {
                links.push(Value::Null);
                item_notes.push(json!(problem));
            }
        }
    }
    let title = folder
        .file_name()
        .map_or("results".into(), |n| n.to_string_lossy().into_owned());
    let mut page = PageData::new("table", &title);
    let rows: Vec<Vec<Value>> = summary
        .rows
        .iter()
        .map(|r| {
            summary
                .columns
                .iter()
                .map(|c| r.get(c).cloned().unwrap_or(Value::Null))
                .collect()
        })
        .collect();
    page.set("columns", json!(summary.columns));
    page.set("rows", json!(rows));
    page.set("links", json!(links));
    page.set("item_notes", json!(item_notes));
    page.set("source", json!(summary_path.display().to_string()));
    let mut written = write_built(
        super::BuiltPage {
            kind: PageKind::Table,
            data: page,
            triangles: 0,
            notes: vec![],
        },
        output,
    )?;
    written.triangles = items.iter().map(|p| p.triangles).sum();
    written.items = items;
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::super::page::tests::embedded;
    use super::super::{ViewInput, ViewOptions, write_page};
    use super::*;

    #[test]
    fn csv_fields_follow_rfc_4180() {
        let text = "a,b,c\n1,\"x, y\",\"say \"\"hi\"\"\"\r\n2,,\"two\nlines\"\n";
        assert_eq!(
            parse_csv(text).unwrap(),
            vec![
                vec!["a", "b", "c"],
                vec!["1", "x, y", "say \"hi\""],
                vec!["2", "", "two\nlines"],
            ]
        );
        assert!(parse_csv("a,\"open\n").is_err());
    }

    #[test]
    fn a_batch_folder_gets_a_table_and_a_page_per_flattened_mesh() {
        let dir = std::env::temp_dir().join(format!("surfmap-view-table-{}", std::process::id()));
        let batch = dir.join("flat");
        std::fs::create_dir_all(&batch).unwrap();
        let mesh = crate::mesh::generate::bumpy_disc(6, 0.3);
        let r = crate::flatten(&mesh, &crate::FlattenOptions::default()).unwrap();
        let out = crate::TriMesh {
            uvs: Some(r.texture_coordinates(true)),
            ..mesh
        };
        crate::write_mesh(&batch.join("disc.obj"), &out).unwrap();
        // One good row (outputs named as the command line gave them) and one failure.
        let csv = "input,status,output,report,triangles,time_s,error\n\
                   in/disc.obj,ok,flat/disc.obj,,150,0.5,\n\
                   in/torus.obj,failed,,,,0.1,\"the mesh is closed, cut it\"\n";
        std::fs::write(batch.join("summary.csv"), csv).unwrap();
        let input = ViewInput::detect(&batch, &ViewOptions::default()).unwrap();
        assert_eq!(
            input,
            ViewInput::Table {
                folder: batch.clone()
            }
        );
        let page = dir.join("index.html");
        let written = write_page(&input, &page).unwrap();
        assert_eq!(written.kind, PageKind::Table);
        assert_eq!(written.items.len(), 1);
        assert_eq!(written.items[0].path, dir.join("index_items/disc.html"));
        assert!(written.items[0].path.is_file());
        let doc = embedded(&std::fs::read_to_string(&page).unwrap());
        assert_eq!(doc["columns"][1], "status");
        assert_eq!(doc["rows"][0][4], 150.0);
        assert_eq!(doc["links"], json!(["index_items/disc.html", null]));
        assert_eq!(doc["item_notes"][1], "failed: the mesh is closed, cut it");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_registration_summary_shows_its_own_columns() {
        let dir = std::env::temp_dir().join(format!("surfmap-view-reg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rows = json!([
            {"name": "s1", "status": "ok", "verdict": "ok", "matched_fraction": 0.97, "registered": "registered/s1.obj", "match": "matches/s1"},
            {"name": "s2", "status": "failed", "error": "no overlap", "seconds": 3.5}
        ]);
        std::fs::write(dir.join("summary.json"), rows.to_string()).unwrap();
        let s = read_summary(&dir.join("summary.json")).unwrap();
        assert_eq!(
            s.columns,
            [
                "name",
                "status",
                "verdict",
                "match",
                "matched_fraction",
                "registered",
                "error",
                "seconds"
            ]
        );
        let page = dir.join("t.html");
        let written = write_page(
            &ViewInput::Table {
                folder: dir.clone(),
            },
            &page,
        )
        .unwrap();
        assert!(written.items.is_empty());
        let doc = embedded(&std::fs::read_to_string(&page).unwrap());
        assert_eq!(
            doc["item_notes"],
            json!(["no output file found in the folder", "failed: no overlap"])
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
