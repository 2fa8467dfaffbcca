use super::batch::{RegisterJob, RegisterRow, register_many, write_summary};
use super::*;
use crate::matching::similarity::Similarity3;
use crate::mesh::SurfacePoint;
use crate::mesh::generate::bumpy_disc;
use crate::mesh::repair::keep_faces;
use crate::vec3::norm3;

/// The rotation by `angle` about the unit axis `axis`, times `scale` (Rodrigues).
fn similarity(axis: [f64; 3], angle: f64, scale: f64, translation: [f64; 3]) -> Similarity3 {
    let n = norm3(axis);
    let [x, y, z] = axis.map(|c| c / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    let r = [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ];
    Similarity3 {
        matrix: r.map(|row| row.map(|v| scale * v)),
        translation,
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm3(sub3(a, b))
}

/// A scan that is the template moved and scaled (same vertices, same triangles), matched
/// everywhere but on its outer rings and a few inner vertices: the matched vertices land
/// on their points, and the unmatched ones exactly where the motion puts them (the
/// residual is zero, and so is its harmonic extension).
#[test]
fn a_moved_copy_is_placed_exactly_with_unmatched_vertices() {
    let template = bumpy_disc(8, 0.3);
    let motion = similarity([1.0, 2.0, 3.0], 0.6, 1.7, [0.3, -2.0, 5.0]);
    let scan = TriMesh::new(
        template
            .positions
            .iter()
            .map(|&p| motion.apply(p))
            .collect(),
        template.triangles.clone(),
    );
    let correspondence: Vec<Option<SurfacePoint>> = (0..template.num_vertices())
        .map(|v| {
            let [x, y, _] = template.positions[v];
            let unmatched = x.hypot(y) > 0.7 || v % 17 == 5;
            if unmatched {
                None
            } else {
                SurfacePoint::at_vertex(&scan.triangles, v as u32)
            }
        })
        .collect();
    let unmatched = correspondence.iter().filter(|p| p.is_none()).count();
    assert!(unmatched > 40, "{unmatched}");
    let placed = place_on_scan(&template, &scan, &correspondence).unwrap();
    assert_eq!(placed.extended.len(), unmatched);
    assert_eq!(placed.matched, template.num_vertices() - unmatched);
    for (p, q) in placed.positions.iter().zip(&scan.positions) {
        assert!(distance(*p, *q) < 1e-9, "{p:?} vs {q:?}");
    }
    assert!((placed.similarity.scale() - 1.7).abs() < 1e-9);
}

/// An unmatched band on a bent copy: the truth is a smooth bend `z += 0.2 x²`, and
/// nothing of it is known on the band `r > 0.75`. The extension continues the bend the
/// matched part shows, so the band lands closer to the truth than the fitted similarity
/// alone puts it (the rigid continuation), on average and at worst.
#[test]
fn an_unmatched_band_is_continued_smoothly() {
    let template = bumpy_disc(10, 0.3);
    let bend = |p: [f64; 3]| [p[0], p[1], p[2] + 0.2 * p[0] * p[0]];
    let scan = TriMesh::new(
        template.positions.iter().map(|&p| bend(p)).collect(),
        template.triangles.clone(),
    );
    let correspondence: Vec<Option<SurfacePoint>> = (0..template.num_vertices())
        .map(|v| {
            let [x, y, _] = template.positions[v];
            (x.hypot(y) <= 0.75)
                .then(|| SurfacePoint::at_vertex(&scan.triangles, v as u32))
                .flatten()
        })
        .collect();
    let placed = place_on_scan(&template, &scan, &correspondence).unwrap();
    assert!(placed.extended.len() > 30);
    let (mut worst, mut worst_rigid, mut sum, mut sum_rigid) = (0.0f64, 0.0f64, 0.0, 0.0);
    for &v in &placed.extended {
        let truth = scan.positions[v as usize];
        let e = distance(placed.positions[v as usize], truth);
        let rigid = distance(
            placed.similarity.apply(template.positions[v as usize]),
            truth,
        );
        (worst, worst_rigid) = (worst.max(e), worst_rigid.max(rigid));
        (sum, sum_rigid) = (sum + e, sum_rigid + rigid);
    }
    assert!(worst < worst_rigid, "worst {worst} vs rigid {worst_rigid}");
    assert!(sum < 0.8 * sum_rigid, "mean {sum} vs rigid {sum_rigid}");
}

/// A bad correspondence is an error naming the defect, not a panic.
#[test]
fn a_correspondence_of_another_mesh_is_refused() {
    let template = bumpy_disc(4, 0.3);
    let err = place_on_scan(&template, &template, &[None; 3]).unwrap_err();
    assert!(err.to_string().contains("entries"), "{err}");
    let none = vec![None; template.num_vertices()];
    let err = place_on_scan(&template, &template, &none).unwrap_err();
    assert!(err.to_string().contains("no vertex of A"), "{err}");
}

/// The template's surface `z = h(x, y)` of `bumpy_disc`, bent by the smooth map `warp`
/// and moved by `motion`, sampled by a finer, different triangulation and cropped to
/// `r < crop` (in the undeformed plane): a scan whose truth for template vertex `x` is
/// `motion(warp(x))`.
fn warped_scan(rings: usize, crop: f64, motion: &Similarity3) -> TriMesh {
    let fine = bumpy_disc(rings, 0.35);
    let keep: Vec<bool> = fine
        .triangles
        .iter()
        .map(|t| {
            t.iter().all(|&v| {
                let [x, y, _] = fine.positions[v as usize];
                x.hypot(y) < crop
            })
        })
        .collect();
    let mut scan = keep_faces(&fine, &keep);
    for p in &mut scan.positions {
        *p = motion.apply(warp(*p));
    }
    scan
}

fn warp(p: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = p;
    [
        x + 0.05 * (1.5 * y).sin(),
        y + 0.04 * (2.0 * x).cos() * y,
        z + 0.08 * x * y,
    ]
}

fn test_options() -> MatchOptions {
    MatchOptions {
        size: 129,
        ..MatchOptions::default()
    }
}

/// The matcher and the placement together on a scan whose truth is known: the template
/// (a bumpy disc, 12 rings) onto its surface warped, remeshed (19 rings), cropped to
/// r < 0.85 and moved. Matched vertices must lie within a few percent of the face width
/// (2) of the truth, and the template's rim beyond the crop, extended, within more.
#[test]
fn a_warped_remeshed_cropped_scan_is_registered_near_the_truth() {
    let template = Template::new(bumpy_disc(12, 0.35), &test_options()).unwrap();
    assert!(template.one_off_seconds > 0.0);
    let motion = similarity([0.3, -1.0, 0.5], 0.4, 1.0, [0.5, 0.2, -0.3]);
    let scan = warped_scan(19, 0.85, &motion);
    let r = register_scan(&template, &scan, &Guidance::default(), &test_options()).unwrap();
    let width = 2.0;
    let errors: Vec<(bool, f64)> = template
        .mesh
        .positions
        .iter()
        .zip(&r.placement.positions)
        .zip(&r.matched_with.correspondence)
        .map(|((x, p), c)| (c.is_some(), distance(*p, motion.apply(warp(*x))) / width))
        .collect();
    let stats = |matched: bool| {
        let mut e: Vec<f64> = errors
            .iter()
            .filter(|(m, _)| *m == matched)
            .map(|(_, e)| *e)
            .collect();
        e.sort_by(f64::total_cmp);
        let mean = e.iter().sum::<f64>() / e.len().max(1) as f64;
        (e.len(), mean, e[(e.len() * 95 / 100).min(e.len() - 1)])
    };
    let (n_matched, mean, p95) = stats(true);
    let (n_extended, mean_ext, p95_ext) = stats(false);
    eprintln!(
        "matched {n_matched}: mean {mean:.4} p95 {p95:.4}; extended {n_extended}: mean {mean_ext:.4} p95 {p95_ext:.4}; verdict {:?}",
        r.matched_with.report.confidence.verdict
    );
    // The template's rim beyond the crop (r > 0.85: about a quarter of its vertices)
    // cannot be matched.
    assert!(
        n_extended as f64 > 0.15 * errors.len() as f64,
        "{n_extended}"
    );
    assert_eq!(n_extended, r.placement.extended.len());
    assert!(
        mean < 0.01 && p95 < 0.025,
        "matched: mean {mean}, p95 {p95}"
    );
    assert!(
        mean_ext < 0.03 && p95_ext < 0.06,
        "extended: mean {mean_ext}, p95 {p95_ext}"
    );
}

fn write(path: &std::path::Path, mesh: &TriMesh) {
    crate::write_obj(path, mesh, None).unwrap();
}

/// A folder with good scans and bad ones (not a surface the matcher takes, NaN, empty,
/// no file): every bad one is a failed row naming its problem, every good one
/// registered, the summary in input order; a scan of the wrong object (a closed sphere:
/// the matcher cuts it open) is registered with a verdict that is not `ok` and its
/// reasons; a rerun with `resume` keeps the rows of the scans done.
#[test]
fn a_batch_lists_the_bad_scans_and_resumes() {
    use std::path::{Path, PathBuf};
    let dir = std::env::temp_dir().join(format!("surfmap-register-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scans = dir.join("scans");
    std::fs::create_dir_all(&scans).unwrap();
    let options = test_options();
    let template = Template::new(bumpy_disc(10, 0.35), &options).unwrap();
    let motion = similarity([1.0, 0.0, 0.2], 0.2, 1.0, [0.0, 0.0, 1.0]);
    write(&scans.join("good.obj"), &warped_scan(15, 0.9, &motion));
    write(&scans.join("sphere.obj"), &crate::mesh::generate::sphere(2));
    // Three triangles on one edge: no surface at all.
    std::fs::write(
        scans.join("fin.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
    )
    .unwrap();
    std::fs::write(
        scans.join("nan.obj"),
        "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    std::fs::write(scans.join("empty.obj"), "").unwrap();
    let inputs: Vec<PathBuf> = ["good", "sphere", "fin", "nan", "empty", "missing"]
        .iter()
        .map(|n| scans.join(format!("{n}.obj")))
        .collect();
    let names = crate::batch::output_names(&inputs);
    let out = dir.join("out");
    let read = |p: &Path| {
        crate::read_mesh(p)
            .map(|f| f.mesh)
            .map_err(|e| e.to_string())
    };
    let job = RegisterJob {
        template: &template,
        options: &options,
        dir: &out,
        keep_matches: true,
        landmarks_dir: None,
        read: &read,
        match_error: |e| e.to_string(),
    };
    let rows = register_many(&job, &inputs, &names, 2, false, |_| {}).unwrap();
    let [csv, json] = write_summary(&out, &rows).unwrap();
    let names_back: Vec<&str> = rows.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(
        names_back,
        ["good", "sphere", "fin", "nan", "empty", "missing"]
    );
    let good = &rows[0];
    assert!(good.ok(), "{good:?}");
    let registered = crate::read_mesh(Path::new(good.output.as_deref().unwrap()))
        .unwrap()
        .mesh;
    assert_eq!(registered.triangles, template.mesh.triangles);
    assert!(out.join("matches/good/match.json").is_file());
    let frac = good.matched_fraction.unwrap();
    assert!(frac > 0.5 && frac <= 1.0, "{frac}");
    let sphere = &rows[1];
    assert!(sphere.ok(), "{sphere:?}");
    assert_ne!(sphere.verdict.as_deref(), Some("ok"), "{sphere:?}");
    assert!(sphere.reasons.as_deref().is_some_and(|r| r.len() > 20));
    for (row, what) in rows[2..].iter().zip(["edge", "nan", "empty", "missing"]) {
        assert_eq!(row.status, "failed", "{row:?}");
        let e = row.error.as_deref().unwrap().to_lowercase();
        assert!(
            e.contains(what)
                || (what == "empty" && e.contains("no "))
                || (what == "missing" && e.contains("no such file")),
            "{}: {e}",
            row.name
        );
        assert!(!out.join(format!("registered/{}.obj", row.name)).exists());
    }
    // The summary on disk: a header and one record per scan (an error may span lines,
    // quoted); the JSON reads back.
    let text = std::fs::read_to_string(&csv).unwrap();
    for r in &rows {
        assert!(
            text.contains(&format!("\n{},{},", r.name, r.input)),
            "{text}"
        );
    }
    assert!(text.starts_with(&RegisterRow::CSV_HEADER.join(",")));
    let back: Vec<RegisterRow> = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(back, rows);
    // Resume: the good scan is not registered again (its row, time included, is the
    // one written then); the failed ones are tried again.
    let again = register_many(&job, &inputs, &names, 2, true, |_| {}).unwrap();
    assert_eq!(again[0], rows[0]);
    assert_eq!(again[1], rows[1]);
    assert!(again[2..].iter().all(|r| r.status == "failed"));
    // No temporary files left.
    for entry in std::fs::read_dir(out.join("registered")).unwrap() {
        let name = entry.unwrap().file_name();
        assert!(!name.to_string_lossy().starts_with('.'), "{name:?}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--landmarks-dir`: each scan's `STEM.json` guides its match, and a pinned landmark's
/// template vertex lands exactly on its scan vertex; a scan without its file fails with a
/// reason that names the file.
#[test]
fn landmark_files_are_read_per_scan() {
    use std::path::{Path, PathBuf};
    let dir = std::env::temp_dir().join(format!("surfmap-register-lm-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (scans, marks) = (dir.join("scans"), dir.join("landmarks"));
    std::fs::create_dir_all(&scans).unwrap();
    std::fs::create_dir_all(&marks).unwrap();
    let options = test_options();
    let template = Template::new(bumpy_disc(10, 0.35), &options).unwrap();
    let motion = similarity([0.0, 1.0, 0.3], 0.3, 1.0, [1.0, 0.0, 0.0]);
    let scan = warped_scan(14, 0.95, &motion);
    write(&scans.join("a.obj"), &scan);
    write(&scans.join("b.obj"), &scan);
    // Five template vertices and the scan vertices nearest their true places.
    let ids: Vec<u32> = vec![0, 37, 75, 120, 190];
    let nearest: Vec<u32> = ids
        .iter()
        .map(|&i| {
            let truth = motion.apply(warp(template.mesh.positions[i as usize]));
            (0..scan.num_vertices() as u32)
                .min_by(|&a, &b| {
                    distance(scan.positions[a as usize], truth)
                        .total_cmp(&distance(scan.positions[b as usize], truth))
                })
                .unwrap()
        })
        .collect();
    let landmarks = serde_json::json!({
        "names": ["l0", "l1", "l2", "l3", "l4"], "A": ids, "B": nearest,
    });
    std::fs::write(marks.join("a.json"), landmarks.to_string()).unwrap();
    let read = |p: &Path| {
        crate::read_mesh(p)
            .map(|f| f.mesh)
            .map_err(|e| e.to_string())
    };
    let out = dir.join("out");
    let job = RegisterJob {
        template: &template,
        options: &options,
        dir: &out,
        keep_matches: false,
        landmarks_dir: Some(&marks),
        read: &read,
        match_error: |e| e.to_string(),
    };
    let inputs: Vec<PathBuf> = vec![scans.join("a.obj"), scans.join("b.obj")];
    let rows = register_many(&job, &inputs, &["a".into(), "b".into()], 1, false, |_| {}).unwrap();
    assert!(rows[0].ok(), "{:?}", rows[0]);
    let registered = crate::read_mesh(Path::new(rows[0].output.as_deref().unwrap()))
        .unwrap()
        .mesh;
    for (&i, &j) in ids.iter().zip(&nearest) {
        let d = distance(registered.positions[i as usize], scan.positions[j as usize]);
        assert!(d < 1e-9, "landmark {i} → {j}: {d}");
    }
    let e = rows[1].error.as_deref().unwrap();
    assert!(e.contains("b.json") && e.contains("landmarks"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
