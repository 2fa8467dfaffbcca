//! `surfmap view` end to end on generated inputs (`surfmap::apps::inputs`): a page of
//! each kind written and its embedded data read back, errors for bad paths and for
//! meshes that do not fit a match folder, and `--serve` answering over HTTP. The pages
//! themselves are tested in a browser by `scripts/view_test.sh`.

mod common;
use common::run_in as run;
use common::*;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;

fn fails(dir: &Path, args: &[&str]) -> String {
    let out = surfmap().current_dir(dir).args(args).output().unwrap();
    assert!(!out.status.success(), "surfmap {args:?} should have failed");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The JSON document a page embeds.
fn embedded(page: &Path) -> serde_json::Value {
    let html = std::fs::read_to_string(page).unwrap();
    let start = html.find("id=\"surfmap-data\">").unwrap() + "id=\"surfmap-data\">".len();
    let end = start + html[start..].find("</script>").unwrap();
    serde_json::from_str(&html[start..end]).unwrap()
}

fn at<'a>(doc: &'a serde_json::Value, path: &str) -> &'a serde_json::Value {
    path.split('.').fold(doc, |v, k| &v[k])
}

#[test]
fn pages_of_a_flattening_a_match_a_rig_and_a_batch() {
    let dir = temp_dir("view-pages");
    surfmap::apps::inputs::write_inputs(&dir.join("in"), None, 128);
    run(
        &dir,
        &[
            "flatten",
            "in/scan.obj",
            "-o",
            "flat.obj",
            "--report",
            "flat.json",
            "-q",
        ],
    );
    let out = run(&dir, &["view", "flat.obj", "-o", "flat.html"]);
    assert!(
        out.contains("flattening page") && out.contains("7200 triangles"),
        "{out}"
    );
    let doc = embedded(&dir.join("flat.html"));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("flat.json")).unwrap()).unwrap();
    let numbers = doc["numbers"].as_array().unwrap();
    assert!(numbers.len() >= 10);
    for n in numbers {
        assert_eq!(&n["value"], at(&report, n["path"].as_str().unwrap()), "{n}");
    }
    assert_eq!(doc["report_source"], "flat.json");

    let out = run(&dir, &["view", "in/match_ab", "-o", "match.html"]);
    assert!(out.contains("match page"), "{out}");
    let doc = embedded(&dir.join("match.html"));
    assert_eq!(doc["files"]["a"], "in/a.obj");
    assert!(doc["counts"]["unmatched"].as_u64().unwrap() > 0);

    run(
        &dir,
        &[
            "rig",
            "in/neutral.obj",
            "in/key1.obj",
            "in/key2.obj",
            "--match",
            "in/match_n1",
            "--match",
            "in/match_12",
            "--chain",
            "--names",
            "wide,wider",
            "-o",
            "rig.glb",
            "-q",
        ],
    );
    let out = run(&dir, &["view", "rig.glb", "-o", "rig.html"]);
    assert!(out.contains("morph page"), "{out}");
    let doc = embedded(&dir.join("rig.html"));
    let names: Vec<&str> = doc["targets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["wide", "wider"]);

    run(
        &dir,
        &["flatten", "in/a.obj", "in/b.obj", "-o", "batch/", "-q"],
    );
    let out = run(&dir, &["view", "batch", "-o", "batch.html"]);
    assert!(
        out.contains("table page") && out.contains("2 item pages"),
        "{out}"
    );
    for item in ["a", "b"] {
        let doc = embedded(&dir.join(format!("batch_items/{item}.html")));
        assert_eq!(doc["kind"], "flattening");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_paths_and_meshes_that_do_not_fit_get_clear_errors() {
    let dir = temp_dir("view-errors");
    surfmap::apps::inputs::write_inputs(&dir.join("in"), None, 64);
    let e = fails(&dir, &["view", "missing.obj", "-o", "p.html"]);
    assert!(
        e.contains("missing.obj") && e.contains("no such file"),
        "{e}"
    );
    let e = fails(&dir, &["view", "in/b_height.npy", "-o", "p.html"]);
    assert!(e.contains("not a file the viewer reads"), "{e}");
    std::fs::create_dir_all(dir.join("empty")).unwrap();
    let e = fails(&dir, &["view", "empty", "-o", "p.html"]);
    assert!(e.contains("nothing to view"), "{e}");
    let e = fails(
        &dir,
        &[
            "view",
            "in/match_ab",
            "--a",
            "in/b.obj",
            "--b",
            "in/a.obj",
            "-o",
            "p.html",
        ],
    );
    assert!(e.contains("A and B are swapped"), "{e}");
    let e = fails(
        &dir,
        &["view", "in/a.obj", "--a", "in/b.obj", "-o", "p.html"],
    );
    assert!(e.contains("go with a match folder"), "{e}");
    let e = fails(&dir, &["view", "in/a.obj"]);
    assert!(e.contains("--output"), "{e}");
    assert!(
        !dir.join("p.html").exists(),
        "no page is left behind by a failure"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--serve` prints its address and serves the page at `/`, nothing else.
#[test]
fn serve_answers_on_localhost() {
    let dir = temp_dir("view-serve");
    surfmap::apps::inputs::write_inputs(&dir.join("in"), None, 64);
    let mut child = surfmap()
        .current_dir(&dir)
        .args(["view", "in/a.obj", "-o", "a.html", "--serve", "-q"])
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let address = line
        .split("http://")
        .nth(1)
        .and_then(|s| s.split('/').next())
        .unwrap_or_else(|| panic!("no address in {line:?}"))
        .to_string();
    assert!(address.starts_with("127.0.0.1:"), "{address}");
    let get = |path: &str| {
        let mut s = std::net::TcpStream::connect(&address).unwrap();
        write!(s, "GET {path} HTTP/1.1\r\nHost: localhost\r\n\r\n").unwrap();
        let mut response = String::new();
        s.read_to_string(&mut response).unwrap();
        response
    };
    let page = get("/");
    let served = child.try_wait().unwrap();
    let missing = get("/../in/a.obj");
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(served.is_none(), "the server stopped");
    assert!(
        page.starts_with("HTTP/1.1 200 OK"),
        "{}",
        &page[..page.len().min(200)]
    );
    let body = page.split("\r\n\r\n").nth(1).unwrap();
    assert_eq!(body, std::fs::read_to_string(dir.join("a.html")).unwrap());
    assert!(missing.starts_with("HTTP/1.1 404"), "{missing}");
    std::fs::remove_dir_all(&dir).unwrap();
}
