//! `surfmap flatten` end to end on every disc mesh in `../shared/data`: presets
//! conformal and balanced converge, and the written OBJ — read back and checked here
//! with our own signed areas — has no flipped or degenerate triangle.

mod common;
use common::*;
use std::path::Path;
use std::process::Output;
use surfmap::mesh::io::read_mesh;

/// `surfmap flatten INPUT OPTIONS… -o OUT`.
fn flatten(input: &Path, options: &[&str], out: &Path) -> Output {
    surfmap()
        .arg("flatten")
        .arg(input)
        .args(options)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap()
}

/// Signed area of every UV triangle of an OBJ written by `flatten`, computed here.
fn min_signed_uv_area(path: &std::path::Path) -> (f64, usize) {
    let file = read_mesh(path).expect("our own output reads back");
    let mesh = file.mesh;
    let uv = mesh.vertex_uvs().expect("per-vertex UVs").to_vec();
    let mut min = f64::INFINITY;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| uv[v as usize]);
        let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
        min = min.min(area);
    }
    (min, mesh.triangles.len())
}

#[test]
fn every_disc_mesh_flattens_without_flips_at_both_presets() {
    let meshes = disc_meshes();
    if meshes.is_empty() {
        return;
    }
    let dir = temp_dir("flatten-all");
    for mesh in &meshes {
        for preset in ["conformal", "balanced"] {
            let name = mesh.file_stem().unwrap().to_string_lossy();
            let out = dir.join(format!("{name}-{preset}.obj"));
            let report = dir.join(format!("{name}-{preset}.json"));
            let report_arg = report.to_string_lossy();
            let run = flatten(mesh, &["--preset", preset, "--report", &report_arg], &out);
            assert!(
                run.status.success(),
                "{name} {preset}: {}",
                String::from_utf8_lossy(&run.stderr)
            );
            let r: serde_json::Value =
                serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
            assert_eq!(
                r["converged"], true,
                "{name} {preset}: not converged ({})",
                r["stop_reason"]
            );
            assert_eq!(r["flipped_triangles"], 0, "{name} {preset}");
            for key in [
                "symmetric_dirichlet",
                "iterations",
                "boundary_overlap",
                "measures",
                "log",
            ] {
                assert!(!r[key].is_null(), "{name} {preset}: report lacks {key}");
            }
            assert_eq!(
                r["boundary_overlap"]["self_intersecting"], false,
                "{name} {preset}: boundary overlaps"
            );
            let (min_area, n) = min_signed_uv_area(&out);
            assert!(
                min_area > 0.0,
                "{name} {preset}: a UV triangle of {n} has signed area {min_area}"
            );
            let summary = String::from_utf8_lossy(&run.stdout);
            assert!(summary.contains("flipped triangles 0"), "{summary}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn what_cannot_be_cut_into_a_disc_gets_a_clear_error() {
    let Some(data) = shared_data() else { return };
    let dir = temp_dir("flatten-nondisc");
    for (file, says) in [
        ("mask_cone.off", "--keep-largest"),
        ("moebius.obj", "not orientable"),
        ("beetle_messy.obj", "shared by more than two faces"),
    ] {
        let run = flatten(&data.join(file), &[], &dir.join("x.obj"));
        assert_eq!(run.status.code(), Some(1), "{file}");
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(err.contains(says), "{file}: expected {says:?} in: {err}");
        assert!(
            !dir.join("x.obj").exists(),
            "{file}: no output may be written on failure"
        );
    }
    // A repair that makes it a disc: the mask without the cone.
    let out = dir.join("mask.obj");
    let run = flatten(&data.join("mask_cone.off"), &["--keep-largest"], &out);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(String::from_utf8_lossy(&run.stderr).contains("repair: kept one component"));
    assert!(min_signed_uv_area(&out).0 > 0.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Raw scans with edges shared by more than two faces and pinched vertices (the FLAME
/// head scan, the messy beetle, the Snowden bust) are refused as given, the error naming
/// the flag that fixes them; with `--repair` they flatten (the bust cut open along seams:
/// it has handles), the output one manifold piece without a flipped UV triangle.
#[test]
fn raw_scans_flatten_after_repair() {
    let Some(data) = shared_data() else { return };
    let dir = temp_dir("flatten-repair");
    let out = dir.join("x.obj");
    for file in [
        "faces/flame/flame_scan.obj",
        "beetle_messy.obj",
        "snowden.obj",
    ] {
        let input = data.join(file);
        let run = flatten(&input, &[], &out);
        assert_eq!(run.status.code(), Some(1), "{file}");
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(err.contains("--fix-non-manifold"), "{file}: {err}");
        assert!(!out.exists());
        let run = flatten(&input, &["--repair"], &out);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{file}: {err}");
        assert!(err.contains("repair: non-manifold: cut"), "{file}: {err}");
        // The input's vertices used by no face are counted on their own line (they are
        // not hidden in the dropped components).
        let given_mesh = read_mesh(&input).unwrap().mesh;
        let mut used = vec![false; given_mesh.positions.len()];
        for t in &given_mesh.triangles {
            for &v in t {
                used[v as usize] = true;
            }
        }
        let unused = used.iter().filter(|&&u| !u).count();
        let line = format!("repair: dropped {unused} unreferenced vertices");
        assert_eq!(
            err.contains(&line),
            unused > 0,
            "{file}: {unused} unused; {err}"
        );
        let written = read_mesh(&out).unwrap().mesh;
        // Signed UV areas by our own arithmetic, per vertex or per corner.
        let corner_uv = |t: usize, k: usize| match &written.uvs {
            Some(surfmap::Uvs::PerVertex(uv)) => uv[written.triangles[t][k] as usize],
            Some(surfmap::Uvs::PerCorner { coords, indices }) => coords[indices[t][k] as usize],
            None => panic!("{file}: no UVs written"),
        };
        for t in 0..written.triangles.len() {
            let [a, b, c] = [0, 1, 2].map(|k| corner_uv(t, k));
            let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(area > 0.0, "{file}: UV triangle {t} flipped or degenerate");
        }
        let topo = surfmap::Topology::new(&written);
        assert!(topo.is_manifold() && topo.num_components == 1, "{file}");
        let (faces, given) = (written.triangles.len(), given_mesh.triangles.len());
        assert!(
            faces < given && faces > given * 9 / 10,
            "{file}: {faces} of {given}"
        );
        std::fs::remove_file(&out).unwrap();
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Signed area of every UV triangle of an OBJ with per-corner `vt`, and whether the
/// corners' UVs are split exactly along the seams written by `--seams`.
/// `surfmap flatten INPUT --seams DIR/seams.obj --report DIR/r.json -o DIR/cut.obj`: the
/// run, and the output, seams and report paths.
fn flatten_with_seams(input: &Path, dir: &Path) -> (Output, [std::path::PathBuf; 3]) {
    let paths = ["cut.obj", "seams.obj", "r.json"].map(|name| dir.join(name));
    let [out, seams, report] = &paths;
    let run = flatten(
        input,
        &[
            "--seams",
            seams.to_str().unwrap(),
            "--report",
            report.to_str().unwrap(),
        ],
        out,
    );
    (run, paths)
}

fn check_cut_output(out: &Path, seams: &Path, input: &surfmap::TriMesh) -> f64 {
    let back = read_mesh(out).expect("our own output reads back").mesh;
    assert_eq!(
        back.triangles, input.triangles,
        "the input's faces, in order"
    );
    let Some(surfmap::Uvs::PerCorner { coords, indices }) = &back.uvs else {
        panic!("per-corner UVs expected")
    };
    let mut min = f64::INFINITY;
    for t in indices {
        let [a, b, c] = t.map(|v| coords[v as usize]);
        min = min.min(0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])));
    }
    // The seams as written: every vertex, `l a b` lines; an edge's two faces share the
    // UVs of its ends exactly when it is no seam.
    let text = std::fs::read_to_string(seams).unwrap();
    let mut seam_edges: Vec<[u32; 2]> = text
        .lines()
        .filter_map(|l| l.strip_prefix("l "))
        .map(|l| {
            let v: Vec<u32> = l
                .split_whitespace()
                .map(|x| x.parse::<u32>().unwrap() - 1)
                .collect();
            [v[0].min(v[1]), v[0].max(v[1])]
        })
        .collect();
    seam_edges.sort_unstable();
    assert!(!seam_edges.is_empty());
    let topology = surfmap::Topology::new(input);
    for (e, &[a, b]) in topology.edges.iter().enumerate() {
        let &[f, g] = topology.faces_of_edge(e) else {
            continue;
        };
        let uv = |t: u32, v: u32| {
            let k = input.triangles[t as usize]
                .iter()
                .position(|&w| w == v)
                .unwrap();
            indices[t as usize][k]
        };
        let joined = uv(f, a) == uv(g, a) && uv(f, b) == uv(g, b);
        assert_eq!(
            joined,
            seam_edges.binary_search(&[a, b]).is_err(),
            "edge ({a}, {b})"
        );
    }
    min
}

#[test]
fn closed_and_higher_genus_meshes_are_cut_open_by_default() {
    let Some(data) = shared_data() else { return };
    let dir = temp_dir("flatten-cut");
    for (file, says) in [
        ("sphere.obj", "cut open along seams (closed, genus 0)"),
        (
            "punctured_torus.obj",
            "cut open along seams (genus 1, 1 boundary loop)",
        ),
    ] {
        let (run, [out, seams, report]) = flatten_with_seams(&data.join(file), &dir);
        assert!(
            run.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let summary = String::from_utf8_lossy(&run.stdout);
        assert!(summary.contains(says), "{file}: {summary}");
        let input = read_mesh(&data.join(file)).unwrap().mesh;
        assert!(check_cut_output(&out, &seams, &input) > 0.0, "{file}");
        let r: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
        assert_eq!(r["plan"], says, "{file}");
        assert!(r["seams"]["length"].as_f64().unwrap() > 0.0, "{file}");
        assert_eq!(r["measures"]["charts"], 1, "{file}");
        assert_eq!(r["flipped_triangles"], 0, "{file}");
        // The seams written round-trip through --cut-along: the same cut.
        let again = dir.join("again.obj");
        let seams2 = dir.join("seams2.obj");
        let run = flatten(
            &data.join(file),
            &[
                "--cut-along",
                seams.to_str().unwrap(),
                "--seams",
                seams2.to_str().unwrap(),
            ],
            &again,
        );
        assert!(
            run.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        assert!(String::from_utf8_lossy(&run.stdout).contains("along the given seams"));
        assert_eq!(
            std::fs::read(&seams).unwrap(),
            std::fs::read(&seams2).unwrap()
        );
    }
    // Holes: filled by default, cut open with --cut-holes.
    let holes = data.join("holes.off");
    let run = flatten(&holes, &[], &dir.join("filled.obj"));
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(String::from_utf8_lossy(&run.stderr).contains("filled 6 holes"));
    assert!(min_signed_uv_area(&dir.join("filled.obj")).0 > 0.0);
    let seams = dir.join("hole-seams.obj");
    let run = flatten(
        &holes,
        &["--cut-holes", "--seams", seams.to_str().unwrap()],
        &dir.join("cut-holes.obj"),
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(String::from_utf8_lossy(&run.stdout).contains("(7 boundary loops)"));
    let input = read_mesh(&holes).unwrap().mesh;
    assert!(check_cut_output(&dir.join("cut-holes.obj"), &seams, &input) > 0.0);
    // Bad seams are refused with the reason.
    std::fs::write(dir.join("bad.txt"), "0 1\n2 x\n").unwrap();
    let run = flatten(
        &data.join("sphere.obj"),
        &["--cut-along", dir.join("bad.txt").to_str().unwrap()],
        &dir.join("x.obj"),
    );
    assert_eq!(run.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&run.stderr).contains("bad.txt:2"),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn demo_writes_what_it_says() {
    let dir = temp_dir("demo");
    let text = run_demo(&dir, 20);
    let listed: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("  "))
        .map(str::trim)
        .collect();
    assert!(listed.len() >= 10, "{text}");
    for p in listed {
        let meta = std::fs::metadata(p).unwrap_or_else(|_| panic!("listed {p} missing"));
        assert!(meta.len() > 0, "{p} empty");
    }
    for preset in ["conformal", "balanced"] {
        assert!(min_signed_uv_area(&dir.join(format!("{preset}.obj"))).0 > 0.0);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn invalid_alpha_is_rejected_with_a_reason() {
    let dir = temp_dir("alpha");
    run_demo(&dir, 4);
    let run = flatten(
        &dir.join("surface.obj"),
        &["--alpha", "0,1,1"],
        &dir.join("x.obj"),
    );
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("α"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn face_scans_with_open_eyes_and_mouth_flatten_with_fill_holes() {
    let Some(data) = shared_data() else { return };
    let dir = temp_dir("fill-holes");
    for (file, extra) in [
        ("faces/ict/ict_neutral.obj", vec![]),
        ("faces/flame/flame_template.ply", vec!["--keep-largest"]),
    ] {
        let out = dir.join("face.obj");
        let options: Vec<&str> = extra.iter().copied().chain(["--fill-holes"]).collect();
        let run = flatten(&data.join(file), &options, &out);
        assert!(
            run.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let back = read_mesh(&out).unwrap().mesh;
        // The output is the input surface (holes open again), with a valid map.
        let input = read_mesh(&data.join(file)).unwrap().mesh;
        if extra.is_empty() {
            assert_eq!(back.positions.len(), input.positions.len(), "{file}");
            assert_eq!(back.triangles, input.triangles, "{file}");
        }
        assert!(min_signed_uv_area(&out).0 > 0.0, "{file}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn normalize_and_uv_as_positions_write_the_flat_unit_layout() {
    let dir = temp_dir("normalize");
    run_demo(&dir, 8);
    let out = dir.join("flat.obj");
    let run = flatten(
        &dir.join("surface.obj"),
        &["--normalize", "--uv-as-positions", "--quiet"],
        &out,
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(run.stdout.is_empty(), "--quiet prints nothing");
    let flat = read_mesh(&out).unwrap().mesh;
    let uv = flat.vertex_uvs().unwrap();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for (p, t) in flat.positions.iter().zip(uv) {
        assert_eq!(p[2], 0.0);
        assert_eq!([p[0], p[1]], *t, "positions are the UVs");
        for k in 0..2 {
            lo[k] = lo[k].min(t[k]);
            hi[k] = hi[k].max(t[k]);
        }
    }
    // Fits [0,1]²: starts at the origin, the longer side spans exactly 1 (aspect kept).
    assert!(lo[0].abs() < 1e-12 && lo[1].abs() < 1e-12, "{lo:?}");
    assert!((hi[0].max(hi[1]) - 1.0).abs() < 1e-12, "{hi:?}");
    assert!(min_signed_uv_area(&out).0 > 0.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn multilevel_start_reaches_the_single_level_minimum_on_a_real_scan() {
    let Some(data) = shared_data() else { return };
    let dir = temp_dir("multilevel");
    let input = data.join("faces/face_bff.obj");
    let mut energies = Vec::new();
    for (name, options) in [
        ("single", vec!["--multilevel", "off"]),
        (
            "multi",
            vec!["--multilevel", "on", "--coarse-vertices", "2000"],
        ),
    ] {
        let out = dir.join(format!("{name}.obj"));
        let report = dir.join(format!("{name}.json"));
        let mut options: Vec<&str> = options;
        let report_arg = report.to_str().unwrap().to_string();
        options.extend(["--report", &report_arg]);
        let run = flatten(&input, &options, &out);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let stdout = String::from_utf8_lossy(&run.stdout);
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        assert_eq!(r["converged"], true, "{name}");
        assert_eq!(r["flipped_triangles"], 0, "{name}");
        assert!(min_signed_uv_area(&out).0 > 0.0, "{name}");
        if name == "multi" {
            assert_eq!(r["start"], "multilevel");
            assert!(
                stdout.contains("multilevel (2000 coarse vertices"),
                "{stdout}"
            );
            let m = &r["multilevel"];
            assert_eq!(m["abandoned"], serde_json::Value::Null);
            assert_eq!(m["coarse_vertices"], 2000);
            assert_eq!(
                m["prolongation"]["inserted"].as_u64().unwrap() + 2000,
                r["vertices"].as_u64().unwrap()
            );
        } else {
            assert_eq!(r["multilevel"], serde_json::Value::Null);
        }
        energies.push(r["energy"].as_f64().unwrap());
    }
    assert!(
        (energies[0] - energies[1]).abs() <= 1e-9 * energies[0],
        "{energies:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_explicit_start_is_honoured_and_its_failure_explained() {
    let Some(data) = shared_data() else { return };
    let dir = temp_dir("explicit-start");
    let out = dir.join("out.obj");
    // Auto multilevel (camelhead has 22.7k faces) yields to an explicit --start.
    let run = flatten(&data.join("camelhead.off"), &["--start", "lscm"], &out);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("start lscm"), "{stdout}");
    // LSCM flips triangles on three_peaks: forced, that is an error naming the remedy.
    let run = flatten(&data.join("three_peaks.off"), &["--start", "lscm"], &out);
    assert_eq!(run.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("LSCM start flips") && stderr.contains("--start auto"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_failed_write_is_reported_once_and_contradictory_flags_are_refused() {
    let dir = temp_dir("write-fail");
    run_demo(&dir, 4);
    let out = dir.join("no-such-folder").join("x.obj");
    let run = flatten(&dir.join("surface.obj"), &["--quiet"], &out);
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(err.matches("cannot write").count(), 1, "{err}");
    assert!(err.contains("no-such-folder"), "{err}");
    // The library's checks, worded as flags.
    for (flags, says) in [
        (vec!["--tolerance", "0"], "--tolerance must be positive"),
        (
            vec!["--coarse-vertices", "3"],
            "--coarse-vertices must be at least 16",
        ),
        (
            vec!["--start", "lscm", "--multilevel", "on"],
            "needs --start auto",
        ),
        (
            vec!["--energy", "sd", "--from-alpha", "1,1,1"],
            "needs --energy litke",
        ),
    ] {
        let run = flatten(&dir.join("surface.obj"), &flags, &dir.join("y.obj"));
        assert_eq!(run.status.code(), Some(1), "{flags:?}");
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(err.contains(says), "{flags:?}: {err}");
        assert!(
            !err.contains("FlattenOptions") && !err.contains("CoarseLevel"),
            "{err}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The mean symmetric Dirichlet distortion (isometry 1) of an OBJ with per-corner `vt`,
/// measured here from the file.
fn mean_sd_of(path: &Path) -> f64 {
    let mesh = read_mesh(path).expect("our own output reads back").mesh;
    let Some(surfmap::Uvs::PerCorner { coords, indices }) = &mesh.uvs else {
        panic!("per-corner UVs expected")
    };
    let corners: Vec<[[f64; 2]; 3]> = indices
        .iter()
        .map(|t| t.map(|v| coords[v as usize]))
        .collect();
    let r = surfmap::distortion_report(
        &mesh.positions,
        &mesh.triangles,
        &corners,
        &surfmap::MeasureOptions::default(),
    )
    .unwrap();
    assert_eq!((r.charts, r.flipped_triangles), (1, 0));
    assert!(!r.boundary_overlap.self_intersecting);
    r.symmetric_dirichlet / 4.0
}

#[test]
fn max_distortion_cuts_a_cone_until_the_bound_holds_and_says_when_it_cannot() {
    let dir = temp_dir("flatten-max-distortion");
    let input = dir.join("cone.obj");
    let cone = surfmap::mesh::generate::cone(1.0, 3.0, 12, 48);
    surfmap::write_obj(&input, &cone, None).unwrap();
    let (out, seams, report) = (
        dir.join("out.obj"),
        dir.join("seams.obj"),
        dir.join("r.json"),
    );
    let args = [
        "--max-distortion",
        "1.02",
        "--seams",
        seams.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ];
    let run = flatten(&input, &args, &out);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(
        stdout.contains("cut open to lower the distortion") && stdout.contains("≤ 1.02"),
        "{stdout}"
    );
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    let cuts = &r["distortion_cuts"];
    assert_eq!(cuts["met"], true, "{cuts}");
    assert_eq!(r["seams"]["reason"]["kind"], "distortion");
    assert_eq!(r["guarantee"], "bijective");
    let after = cuts["after"].as_f64().unwrap();
    assert!(
        cuts["before"].as_f64().unwrap() > 1.02 && after <= 1.02,
        "{cuts}"
    );
    // The bound holds on the file as written, measured here.
    let written = mean_sd_of(&out);
    assert!((written - after).abs() < 1e-9, "{written} vs {after}");
    assert!(check_cut_output(&out, &seams, &cone) > 0.0);

    // Out of reach (a cut cone is developable, a hemisphere is not: no cut makes its
    // map an isometry): the best map is written, the command fails saying so.
    let cap = dir.join("cap.obj");
    let hemisphere =
        surfmap::mesh::generate::spherical_cap(1.0, std::f64::consts::FRAC_PI_2, 8, 32);
    surfmap::write_obj(&cap, &hemisphere, None).unwrap();
    let run = flatten(
        &cap,
        &["--max-distortion", "1", "--max-cut-rounds", "2"],
        &out,
    );
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("the distortion bound 1 was not met") && stderr.contains("written to"),
        "{stderr}"
    );
    assert!(mean_sd_of(&out) > 1.0);
    let back = read_mesh(&out).unwrap().mesh;
    assert_eq!(back.triangles, hemisphere.triangles);

    // Below an isometry: refused before any work.
    let run = flatten(&input, &["--max-distortion", "0.5"], &out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("--max-distortion must be at least 1"),
        "{stderr}"
    );
}

/// A repeated face is removed by `--repair` (as the refusal says), after which the mesh
/// flattens flip-free with the repeat gone; without the repair it is refused as a repeat.
#[test]
fn a_repeated_face_is_removed_by_repair_and_the_mesh_flattens() {
    let dir = temp_dir("repeated-face");
    let damaged = damaged_inputs(&dir);
    let repeated = damaged.iter().find(|d| d.name == "repeated face").unwrap();
    let out = dir.join("flat.obj");
    let refused = flatten(&repeated.path, &[], &out);
    assert_eq!(refused.status.code(), Some(1));
    let said = String::from_utf8_lossy(&refused.stderr);
    assert!(said.contains("--drop-degenerate (or --repair)"), "{said}");
    for repair in ["--repair", "--drop-degenerate"] {
        let run = flatten(&repeated.path, &[repair], &out);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{repair}: {err}");
        assert!(
            err.contains("dropped 1 degenerate or repeated faces"),
            "{err}"
        );
        let (min_area, faces) = min_signed_uv_area(&out);
        assert!(
            min_area > 0.0,
            "{repair}: a flipped or degenerate UV triangle"
        );
        assert_eq!(faces, 32, "{repair}: the repeat is gone, the rest kept");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Negative numbers work as the help writes them (`--alpha L,A,C`, `--tolerance X`):
/// the answer is the library's reason, not the parser's "use -- -1" tip.
#[test]
fn negative_numbers_in_options_reach_their_checks() {
    let dir = temp_dir("negative-options");
    let input = dir.join("disc.obj");
    surfmap::write_mesh(&input, &surfmap::mesh::generate::bumpy_disc(4, 0.3)).unwrap();
    let out = dir.join("flat.obj");
    for (options, reason) in [
        (
            &["--alpha", "-1,1,1"][..],
            "invalid α: length weight αl = -1 must be > 0",
        ),
        (
            &["--from-alpha", "1,-1,1"][..],
            "invalid α: area weight αa = -1 must be > 0",
        ),
        (
            &["--tolerance", "-1"][..],
            "--tolerance must be positive, got -1",
        ),
        (
            &["--armijo-c", "-0.5"][..],
            "--armijo-c must be in (0, 1), got -0.5",
        ),
        (
            &["--max-distortion", "-2"][..],
            "--max-distortion must be at least 1",
        ),
        (
            &["--weld", "-1"][..],
            "--weld tolerance must be ≥ 0, got -1",
        ),
    ] {
        let run = flatten(&input, options, &out);
        let err = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{options:?}: {err}");
        assert!(err.contains(reason), "{options:?}: {err}");
        assert!(
            !err.contains("-- -1") && !err.contains("unexpected argument"),
            "{err}"
        );
    }
    // A valid negative value is a value: a demo with its bumps turned inward.
    let run = surfmap()
        .args(["demo", "--rings", "6", "--amplitude", "-0.3", "-o"])
        .arg(dir.join("demo"))
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn closed_tentacles_are_cut_along_their_protrusions_and_the_report_says_so() {
    // The failing case of issue 50: refused before ("both initial maps flipped
    // triangles"), now one chart cut along the tentacles.
    use surfmap::mesh::generate::{Tentacles, tentacles};
    let dir = temp_dir("flatten-tentacles");
    let mesh = tentacles(&Tentacles::default());
    let input = dir.join("tentacles.obj");
    surfmap::write_mesh(&input, &mesh).unwrap();
    let (run, [out, seams, report]) = flatten_with_seams(&input, &dir);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    let cuts = r["protrusion_cuts"].as_u64().unwrap();
    let length = r["protrusion_seam_length"].as_f64().unwrap();
    assert!((1..=8).contains(&cuts), "{cuts}");
    assert!(length > 0.0 && r["seams"]["length"].as_f64().unwrap() > length);
    let says = format!(
        "cut open along seams (closed, genus 0), then cut along {cuts} protrusions (seam length {length:.4})"
    );
    assert_eq!(r["plan"], says.as_str());
    assert!(
        String::from_utf8_lossy(&run.stdout).contains(&says),
        "{}",
        String::from_utf8_lossy(&run.stdout)
    );
    assert_eq!(r["measures"]["charts"], 1);
    assert_eq!(r["flipped_triangles"], 0);
    assert_eq!(r["guarantee"], "bijective");
    let input = read_mesh(&input).unwrap().mesh;
    assert!(check_cut_output(&out, &seams, &input) > 0.0);
    std::fs::remove_dir_all(&dir).unwrap();
}
