//! The page of a flattened mesh: the surface in 3D with a checkerboard (or its texture)
//! beside its UV layout, both coloured on request by a per-triangle distortion measure
//! with a legend that states its range and what it clips, the seams drawn on both, and
//! the report's numbers. A mesh without texture coordinates gets the 3D view alone.
//!
//! The measures are those of the report ([`crate::measure::per_triangle_measure`]: the
//! thesis's angle `σ1/σ2`, area `σ1σ2` and length `√(σ1² + σ2²)`, and the symmetric
//! Dirichlet density `σ1² + σ2² + σ1⁻² + σ2⁻²`, after the UVs are scaled to the 3D
//! area), computed here from the file's texture coordinates: a report holds only their
//! summaries.

use std::path::Path;

use serde_json::{Value, json};

use super::page::PageData;
use super::surface::{add_mesh, boundary_half_edges, seam_half_edges};
use super::{BuiltPage, PageKind, ViewError, numbers, read_json};
use crate::measure::report::{Measure, triangle_singular_values};
use crate::measure::{MeasureOptions, distortion_report};
use crate::mesh::{TriMesh, Uvs};
use crate::render::colormap::{ColorScale, Colormap};

/// The report's numbers a flattening page lists (those present).
const REPORT_NUMBERS: [(&str, &str); 20] = [
    ("vertices", "vertices"),
    ("triangles", "triangles"),
    ("plan", "plan"),
    ("start map", "start"),
    ("Newton iterations", "iterations"),
    ("converged", "converged"),
    ("energy (per unit area)", "energy"),
    ("flipped triangles", "flipped_triangles"),
    ("guarantee", "guarantee"),
    ("holes filled", "holes_filled"),
    ("symmetric Dirichlet, mean", "symmetric_dirichlet"),
    (
        "symmetric Dirichlet, max",
        "measures.symmetric_dirichlet_max",
    ),
    ("angle σ1/σ2, mean", "measures.measures.angle.mean"),
    ("angle σ1/σ2, max", "measures.measures.angle.max"),
    ("area σ1σ2, min", "measures.measures.area.min"),
    ("area σ1σ2, max", "measures.measures.area.max"),
    ("length, mean", "measures.measures.length.mean"),
    ("seam length", "seams.length"),
    (
        "boundary overlaps itself",
        "boundary_overlap.self_intersecting",
    ),
    ("time, total (s)", "time_total_s"),
];

/// The same numbers in a distortion report measured here (no report file).
const MEASURED_NUMBERS: [(&str, &str); 9] = [
    ("vertices", "num_vertices"),
    ("triangles", "num_triangles"),
    ("flipped triangles", "flipped_triangles"),
    ("symmetric Dirichlet, mean", "symmetric_dirichlet"),
    ("symmetric Dirichlet, max", "symmetric_dirichlet_max"),
    ("angle σ1/σ2, mean", "measures.angle.mean"),
    ("angle σ1/σ2, max", "measures.angle.max"),
    ("area σ1σ2, min", "measures.area.min"),
    ("area σ1σ2, max", "measures.area.max"),
];

/// The measures a page colours by: key, legend label, measure.
const MEASURES: [(&str, &str, Measure); 4] = [
    ("angle", "angle distortion σ1/σ2", Measure::Angle),
    ("area", "area distortion σ1σ2", Measure::Area),
    ("length", "length distortion √(σ1²+σ2²)", Measure::Length),
    (
        "symmetric_dirichlet",
        "symmetric Dirichlet σ1²+σ2²+σ1⁻²+σ2⁻²",
        Measure::SymmetricDirichlet,
    ),
];

/// Builds the page of the mesh file `mesh_path` and, when given, its flattening report.
pub(crate) fn build(mesh_path: &Path, report: Option<&Path>) -> Result<BuiltPage, ViewError> {
    let file = crate::read_mesh(mesh_path)?;
    let name = mesh_path
        .file_name()
        .map_or("mesh".into(), |n| n.to_string_lossy().into_owned());
    let mut page = PageData::new("flattening", &name);
    let mut notes = vec![];
    let mesh = &file.mesh;
    if mesh.triangles.is_empty() {
        return Err(ViewError::input(
            mesh_path,
            "the mesh has no triangle to show",
        ));
    }
    let surface = add_mesh(&mut page, "surface", &mesh.positions, &mesh.triangles);
    page.set("surface", surface);
    page.add_u32("surface.boundary", boundary_half_edges(&mesh.triangles));
    let report_doc = match report {
        Some(path) => Some((path, read_json(path)?)),
        None => None,
    };
    match &mesh.uvs {
        Some(uvs) => {
            add_layout(&mut page, mesh, uvs)?;
            let (source, doc, fields): (String, Value, &[(&str, &str)]) = match report_doc {
                Some((path, doc)) => {
                    check_report(path, &doc, mesh)?;
                    (path.display().to_string(), doc, &REPORT_NUMBERS)
                }
                None => (
                    "measured when this page was written (no report file)".into(),
                    measured_report(mesh, uvs)?,
                    &MEASURED_NUMBERS,
                ),
            };
            page.set("numbers", numbers(&doc, fields));
            page.set("report_source", json!(source));
            page.set("report", doc);
        }
        None => {
            notes.push(format!(
                "{name} has no texture coordinates: the 3D view only (no UV layout, no distortion measures)"
            ));
            if let Some((path, doc)) = report_doc {
                page.set("numbers", numbers(&doc, &REPORT_NUMBERS));
                page.set("report_source", json!(path.display().to_string()));
                page.set("report", doc);
            }
        }
    }
    if let Some(texture) = &file.texture {
        match texture_data_url(texture) {
            Ok(url) => page.set("texture", json!(url)),
            Err(problem) => notes.push(problem),
        }
    }
    Ok(BuiltPage {
        kind: PageKind::Flattening,
        data: page,
        triangles: mesh.num_triangles(),
        notes,
    })
}

/// The texture coordinates, seams and per-triangle measures with their colour ranges.
fn add_layout(page: &mut PageData, mesh: &TriMesh, uvs: &Uvs) -> Result<(), ViewError> {
    let corners = crate::apps::texture::corner_uvs(uvs, &mesh.triangles)?;
    let (coords, indices): (&[[f64; 2]], &[[u32; 3]]) = match uvs {
        Uvs::PerVertex(uv) => (uv, &mesh.triangles),
        Uvs::PerCorner { coords, indices } => (coords, indices),
    };
    page.add_points("uv.coords", coords);
    page.add_triangles("uv.triangles", indices);
    page.add_u32("surface.seams", seam_half_edges(&mesh.triangles, uvs));
    let sv = triangle_singular_values(&mesh.positions, &mesh.triangles, &corners, true)?;
    let mut measures = vec![];
    for (key, label, measure) in MEASURES {
        let values = sv.values(measure);
        let array = format!("measure.{key}");
        // Left-out triangles are stored as −1: every measure is ≥ 0.
        page.add_f32(&array, values.iter().copied(), -1.0);
        let mut scale = colour_range(measure, &values);
        scale["key"] = json!(key);
        scale["label"] = json!(label);
        scale["array"] = json!(array);
        measures.push(scale);
    }
    page.set("measures", json!(measures));
    page.set(
        "colormaps",
        json!({
            "viridis": Colormap::Viridis.stops(),
            "blue_white_red": Colormap::BlueWhiteRed.stops(),
        }),
    );
    Ok(())
}

/// The colour range of a measure and what it leaves out: the range drawn (`lo`, `hi`,
/// logarithmic or not, the colour map), the values' `min` and `max`, the triangles
/// below `lo` and above `hi` (drawn in the end colours: the legend says the range
/// clips) and those left out (degenerate in 3D, drawn grey).
///
/// Angle, length and symmetric Dirichlet: viridis over the 1st to 99th percentile
/// ([`ColorScale::auto`]). Area: blue–white–red on a log scale symmetric about 1
/// (white = area kept), over `[1/r, r]` with `r` the larger of the 99th percentile and
/// the inverse of the 1st.
pub fn colour_range(measure: Measure, values: &[f64]) -> Value {
    let finite: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let scale = match measure {
        Measure::Area => {
            let mut v: Vec<f64> = finite.iter().copied().filter(|&x| x > 0.0).collect();
            v.sort_by(f64::total_cmp);
            let r = if v.is_empty() {
                2.0
            } else {
                let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
                at(0.99).max(1.0 / at(0.01)).max(1.0 + 1e-3)
            };
            ColorScale {
                lo: 1.0 / r,
                hi: r,
                log: true,
                map: Colormap::BlueWhiteRed,
            }
        }
        _ => ColorScale::auto(&finite).unwrap_or(ColorScale {
            lo: 0.0,
            hi: 1.0,
            log: false,
            map: Colormap::Viridis,
        }),
    };
    let min = finite.iter().copied().fold(f64::INFINITY, f64::min);
    let max = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let infinite = values.iter().filter(|x| x.is_infinite()).count();
    json!({
        "lo": scale.lo,
        "hi": scale.hi,
        "log": scale.log,
        "map": match scale.map { Colormap::Viridis => "viridis", Colormap::BlueWhiteRed => "blue_white_red" },
        "min": if min.is_finite() { json!(min) } else { Value::Null },
        "max": if max.is_finite() { json!(max) } else { Value::Null },
        "below": finite.iter().filter(|&&x| x < scale.lo).count(),
        "above": finite.iter().filter(|&&x| x > scale.hi).count() + infinite,
        "left_out": values.iter().filter(|x| x.is_nan()).count(),
        "count": values.len(),
    })
}

/// A report must describe this mesh: its vertex and triangle counts, when it states them.
fn check_report(path: &Path, doc: &Value, mesh: &TriMesh) -> Result<(), ViewError> {
    for (key, have) in [
        ("vertices", mesh.num_vertices()),
        ("triangles", mesh.num_triangles()),
    ] {
        if let Some(n) = doc.get(key).and_then(Value::as_u64)
            && n as usize != have
        {
            return Err(ViewError::input(
                path,
                format!(
                    "the report is of a mesh with {n} {key}, the mesh has {have}: it belongs to another flattening (give the right one with --report)"
                ),
            ));
        }
    }
    Ok(())
}

/// The distortion report of the file's own texture coordinates (default options).
fn measured_report(mesh: &TriMesh, uvs: &Uvs) -> Result<Value, ViewError> {
    let corners = crate::apps::texture::corner_uvs(uvs, &mesh.triangles)?;
    let report = distortion_report(
        &mesh.positions,
        &mesh.triangles,
        &corners,
        &MeasureOptions::default(),
    )?;
    Ok(serde_json::to_value(&report).unwrap_or(Value::Null))
}

/// A texture image as a `data:` URL (PNG or JPEG, by its first bytes), or why not.
pub fn texture_data_url(path: &Path) -> Result<String, String> {
    let bytes = std::fs::read(path)
        .map_err(|e| format!("texture {}: {e}; drawn with a checkerboard", path.display()))?;
    let mime = if bytes.starts_with(b"\x89PNG") {
        "image/png"
    } else if bytes.starts_with(&[0xff, 0xd8]) {
        "image/jpeg"
    } else {
        return Err(format!(
            "texture {}: neither PNG nor JPEG; drawn with a checkerboard",
            path.display()
        ));
    };
    Ok(format!(
        "data:{mime};base64,{}",
        super::page::base64(&bytes)
    ))
}

#[cfg(test)]
mod tests {
    use super::super::page::tests::{array, embedded};
    use super::super::{ViewInput, ViewOptions, write_page};
    use super::*;
    use crate::measure::report::per_triangle_measure;
    use crate::{FlattenOptions, FlattenReport, flatten};

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("surfmap-view-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A flattened bumpy disc written with its report, as `surfmap flatten` does.
    fn flattened(dir: &Path) -> (TriMesh, std::path::PathBuf, Value) {
        let mesh = crate::mesh::generate::bumpy_disc(8, 0.4);
        let r = flatten(&mesh, &FlattenOptions::default()).unwrap();
        let report =
            FlattenReport::measure(None, &mesh, &r, crate::mesh::validate::Defect::message)
                .unwrap();
        let out = TriMesh {
            uvs: Some(r.texture_coordinates(true)),
            ..mesh
        };
        let path = dir.join("flat.obj");
        crate::write_mesh(&path, &out).unwrap();
        let doc = serde_json::to_value(&report).unwrap();
        std::fs::write(dir.join("flat.json"), serde_json::to_vec(&doc).unwrap()).unwrap();
        (out, path, doc)
    }

    #[test]
    fn a_flattening_page_embeds_the_mesh_its_measures_and_the_reports_numbers() {
        let dir = temp("flat");
        let (mesh, path, report) = flattened(&dir);
        // The sibling report is found by name.
        let input = ViewInput::detect(&path, &ViewOptions::default()).unwrap();
        assert_eq!(
            input,
            ViewInput::Flattening {
                mesh: path.clone(),
                report: Some(dir.join("flat.json"))
            }
        );
        let page = dir.join("page.html");
        let written = write_page(&input, &page).unwrap();
        assert_eq!(written.kind, PageKind::Flattening);
        assert_eq!(written.triangles, mesh.num_triangles());
        let html = std::fs::read_to_string(&page).unwrap();
        assert_eq!(written.bytes, html.len());
        let doc = embedded(&html);
        assert_eq!(doc["kind"], "flattening");
        // Positions and triangles as written (the OBJ's positions, in f32).
        let read = crate::read_mesh(&path).unwrap().mesh;
        let p = array(&doc, "surface.positions", f32::from_le_bytes);
        let expected: Vec<f32> = read.positions.iter().flatten().map(|&x| x as f32).collect();
        assert_eq!(p, expected);
        let t = array(&doc, "surface.triangles", u32::from_le_bytes);
        assert_eq!(
            t,
            mesh.triangles.iter().flatten().copied().collect::<Vec<_>>()
        );
        // The angle measure equals an independent per-triangle measurement.
        let corners =
            crate::apps::texture::corner_uvs(read.uvs.as_ref().unwrap(), &read.triangles).unwrap();
        let angle =
            per_triangle_measure(&read.positions, &read.triangles, &corners, Measure::Angle)
                .unwrap();
        let embedded_angle = array(&doc, "measure.angle", f32::from_le_bytes);
        for (a, b) in embedded_angle.iter().zip(&angle) {
            assert_eq!(*a, *b as f32);
        }
        // Every listed number is the report's own value at its path.
        let listed = doc["numbers"].as_array().unwrap();
        assert!(listed.len() >= 12, "{listed:?}");
        for n in listed {
            let path = n["path"].as_str().unwrap();
            assert_eq!(
                &n["value"],
                super::super::json_at(&report, path).unwrap(),
                "{path}"
            );
        }
        // A bumpy disc flattened as it is has a boundary and no seam.
        assert!(!array(&doc, "surface.boundary", u32::from_le_bytes).is_empty());
        assert!(array(&doc, "surface.seams", u32::from_le_bytes).is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_report_of_another_mesh_is_refused() {
        let dir = temp("wrong-report");
        let (_, path, mut report) = flattened(&dir);
        report["triangles"] = json!(3);
        let wrong = dir.join("other.json");
        std::fs::write(&wrong, serde_json::to_vec(&report).unwrap()).unwrap();
        let options = ViewOptions {
            report: Some(wrong),
            ..ViewOptions::default()
        };
        let input = ViewInput::detect(&path, &options).unwrap();
        let e = write_page(&input, &dir.join("p.html"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("other.json") && e.contains("another flattening"),
            "{e}"
        );
        assert!(!dir.join("p.html").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn colour_ranges_say_what_they_clip() {
        let mut values: Vec<f64> = (0..1000).map(|i| 1.0 + i as f64 / 1000.0).collect();
        values.push(50.0);
        values.push(f64::NAN);
        let r = colour_range(Measure::Angle, &values);
        assert_eq!(r["max"], 50.0);
        assert!(r["hi"].as_f64().unwrap() < 2.0);
        // The 1 % above the 99th percentile (10 values and the outlier) clip.
        let above = r["above"].as_u64().unwrap();
        assert!((9..=12).contains(&above), "{above}");
        assert_eq!(r["left_out"], 1);
        // Area: symmetric about 1 on a log scale.
        let area = colour_range(Measure::Area, &[0.5, 1.0, 1.5]);
        let (lo, hi) = (area["lo"].as_f64().unwrap(), area["hi"].as_f64().unwrap());
        assert!((lo * hi - 1.0).abs() < 1e-12 && hi >= 1.5);
        assert_eq!(area["map"], "blue_white_red");
    }
}
