//! `surfmap inspect` end to end: agrees with `../shared/data/manifest.json` on every
//! mesh there, names every messy mesh's defects, and uses the documented exit codes.

mod common;
use common::*;

#[test]
fn inspect_json_agrees_with_manifest_on_every_mesh() {
    let Some((dir, files)) = manifest() else {
        return;
    };
    let mut checked = 0;
    for f in &files {
        let name = f["file"].as_str().unwrap();
        let out = surfmap()
            .arg("inspect")
            .arg(dir.join(name))
            .arg("--json")
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        for (ours, theirs) in [
            ("vertices", "V"),
            ("faces", "F"),
            ("boundary_loops", "boundary_loops"),
            ("components", "components"),
            ("euler_characteristic", "euler"),
            ("genus", "genus"),
            ("orientable", "orientable"),
            ("manifold", "manifold"),
        ] {
            assert_eq!(
                r[ours], f[theirs],
                "{name}: {ours} = {} but manifest {theirs} = {}",
                r[ours], f[theirs]
            );
        }
        let mut loops: Vec<u64> = r["boundary_loop_lengths"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect();
        let mut theirs: Vec<u64> = f["boundary_loop_edge_counts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap())
            .collect();
        // The manifest lists the longest ten loops only.
        loops.sort_unstable_by(|a, b| b.cmp(a));
        theirs.sort_unstable_by(|a, b| b.cmp(a));
        loops.truncate(theirs.len());
        assert_eq!(
            loops, theirs,
            "{name}: boundary loop lengths (longest first)"
        );

        // Every defect the manifest records is named.
        let kinds: Vec<&str> = r["defects"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d["kind"].as_str().unwrap())
            .collect();
        let expect = |cond: bool, kind: &str| {
            if cond {
                assert!(
                    kinds.contains(&kind),
                    "{name}: expected defect {kind}, got {kinds:?}"
                );
            }
        };
        expect(f["components"].as_u64().unwrap() > 1, "several_components");
        expect(
            f["nonmanifold_edges"].as_u64().unwrap() > 0,
            "non_manifold_edges",
        );
        expect(
            f["nonmanifold_vertices"].as_u64().unwrap() > 0,
            "non_manifold_vertices",
        );
        expect(
            f["unreferenced_vertices"].as_u64().unwrap() > 0,
            "unreferenced_vertices",
        );
        expect(
            f["duplicate_vertex_positions"].as_u64().unwrap() > 0,
            "duplicate_vertices",
        );
        expect(!f["orientable"].as_bool().unwrap(), "non_orientable");
        expect(
            f["orientable"].as_bool().unwrap()
                && f["faces_to_flip_for_consistency"].as_u64().unwrap() > 0,
            "inconsistent_orientation",
        );
        expect(
            f["boundary_loops"].as_u64().unwrap() > 1,
            "several_boundary_loops",
        );
        expect(f["genus"].as_u64().is_some_and(|g| g > 0), "positive_genus");
        expect(
            f["boundary_loops"] == 0 && f["genus"].is_u64(),
            "closed_surface",
        );
        let is_disc = f["boundary_loops"] == 1 && f["genus"] == 0;
        assert_eq!(r["disc"].as_bool().unwrap(), is_disc, "{name}: disc");
        // What flatten will do: every connected, orientable, manifold mesh is flattened
        // (holes filled, closed surfaces and handles cut open), the others refused.
        let loops = f["boundary_loops"].as_u64().unwrap();
        let cuttable = f["components"] == 1
            && f["genus"].is_u64()
            && f["nonmanifold_vertices"] == 0
            && f["faces_to_flip_for_consistency"] == 0;
        let plan = r["flatten"].as_str().unwrap();
        let holes = |n: u64| format!("fill {} hole{}", n - 1, if n == 2 { "" } else { "s" });
        let handles = |g: u64| format!("cut open along seams (genus {g}, 1 boundary loop)");
        let expected = match (cuttable, loops, f["genus"].as_u64()) {
            (true, 1, Some(0)) => "disc as is".to_string(),
            (true, 0, Some(g)) => format!("cut open along seams (closed, genus {g})"),
            (true, n, Some(0)) => holes(n),
            (true, 1, Some(g)) => handles(g),
            (true, n, Some(g)) => format!("{}, then {}", holes(n), handles(g)),
            _ => "refused".to_string(),
        };
        assert_eq!(plan, expected, "{name}: what flatten will do");
        if is_disc {
            assert!(
                r["defects"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .all(|d| !d["blocks_flattening"].as_bool().unwrap()),
                "{name}: a disc has no blocking defect: {kinds:?}"
            );
        }
        checked += 1;
    }
    assert_eq!(checked, files.len());
}

#[test]
fn messy_mesh_report_locates_defects() {
    let Some(dir) = shared_data() else { return };
    let out = surfmap()
        .arg("inspect")
        .arg(dir.join("beetle_messy.obj"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("47 edges are shared by more than two faces"),
        "{text}"
    );
    assert!(text.contains("--keep-largest"), "{text}");
}

#[test]
fn exit_codes() {
    let dir = temp_dir("exit-codes");
    // Unreadable input: exit 1 with the reason.
    let bad = dir.join("bad.off");
    std::fs::write(&bad, "OFF\n3 1 0\n0 0 0\n1 0 0\n").unwrap();
    let out = surfmap().arg("inspect").arg(&bad).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(!out.stderr.is_empty());
    let out = surfmap()
        .arg("inspect")
        .arg(dir.join("missing.obj"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    // Usage error: exit 2.
    let out = surfmap()
        .arg("inspect")
        .arg("--no-such-flag")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    // --help works on every command.
    for cmd in ["inspect", "flatten"] {
        let out = surfmap().arg(cmd).arg("--help").output().unwrap();
        assert!(out.status.success(), "{cmd} --help");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn closed_stdout_is_not_a_panic() {
    // `surfmap demo | head -1`: the reader goes away; the program must not panic.
    let dir = temp_dir("broken-pipe");
    let mut child = surfmap()
        .arg("demo")
        .arg("-o")
        .arg(&dir)
        .args(["--rings", "6"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// One verdict on damaged input: `inspect` lists the defect that `flatten` refuses the
/// mesh for, in the same words, says the mesh is no disc and that flatten refuses it,
/// and says how its numbers count; a file that is not a mesh is refused by both by name.
#[test]
fn inspect_and_flatten_give_one_verdict_on_damaged_input() {
    let dir = temp_dir("one-verdict");
    for d in damaged_inputs(&dir) {
        let inspect = surfmap().arg("inspect").arg(&d.path).output().unwrap();
        let flatten = surfmap()
            .arg("flatten")
            .arg(&d.path)
            .arg("-o")
            .arg(dir.join("out.obj"))
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&inspect.stdout).into_owned()
            + &String::from_utf8_lossy(&inspect.stderr);
        let refused = String::from_utf8_lossy(&flatten.stderr);
        assert_eq!(flatten.status.code(), Some(1), "{}: {refused}", d.name);
        assert!(
            refused.contains(d.words),
            "{}: flatten said {refused}",
            d.name
        );
        assert!(said.contains(d.words), "{}: inspect said {said}", d.name);
        assert!(!dir.join("out.obj").exists(), "{}", d.name);
        let Some(kind) = d.kind else {
            // Not readable: both stop at reading, with the same error.
            assert_eq!(inspect.status.code(), Some(1), "{}", d.name);
            assert_eq!(said.trim(), refused.trim(), "{}", d.name);
            continue;
        };
        assert!(inspect.status.success(), "{}: {said}", d.name);
        assert!(said.contains(&format!("[{kind}]")), "{}: {said}", d.name);
        assert!(said.contains("  disc       no"), "{}: {said}", d.name);
        assert!(said.contains("  flatten    refused"), "{}: {said}", d.name);
        assert!(!said.contains("defects    none"), "{}: {said}", d.name);
        // A repeat is a repeat: not an orientation or manifold problem.
        assert!(
            !said.contains("inconsistent_orientation") && !said.contains("non_manifold"),
            "{}: {said}",
            d.name
        );
        for text in [&said[..], &refused[..]] {
            assert!(
                text.contains(surfmap::mesh::validate::NUMBERING),
                "{}: {text}",
                d.name
            );
        }
        // The JSON agrees: the same kind, blocking, and no disc.
        let json = surfmap()
            .args(["inspect", "--json"])
            .arg(&d.path)
            .output()
            .unwrap();
        let r: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
        assert_eq!(r["disc"], false, "{}", d.name);
        assert_eq!(r["flatten"], "refused", "{}", d.name);
        assert!(
            r["defects"]
                .as_array()
                .unwrap()
                .iter()
                .any(|x| x["kind"] == kind && x["blocks_flattening"] == true),
            "{}: {r}",
            d.name
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
