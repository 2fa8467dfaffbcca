//! End-to-end tests of `surfmap images` on a generated surface (`surfmap demo`): the files
//! named in `images.json` exist, the `.npy` headers carry the announced shapes and the
//! data has the size they imply, features and texture are used, and bad input (unknown
//! vertex id, mask of the wrong size, bad grid size) fails with exit code 1 and a message
//! naming the problem.

mod common;
use common::*;

use std::path::{Path, PathBuf};
use std::process::Output;

use surfmap::render::{RgbImage, save_png};

/// A `width × height` picture of one colour.
fn solid(width: u32, height: u32, c: [u8; 3]) -> RgbImage {
    RgbImage::from_raw(width, height, c.repeat((width * height) as usize)).unwrap()
}

/// `surfmap demo` writes `surface.obj` (no texture coordinates) and `conformal.obj`
/// (the same surface with a flattening as `vt`).
fn demo(dir: &Path) -> (PathBuf, PathBuf) {
    run_demo(dir, 12);
    (dir.join("surface.obj"), dir.join("conformal.obj"))
}

fn run(args: &[&std::ffi::OsStr]) -> Output {
    surfmap().arg("images").args(args).output().unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn writes_every_image_listed_in_images_json() {
    let dir = temp_dir("images-basic");
    let (surface, _) = demo(&dir);
    let out_dir = dir.join("img");
    let features = dir.join("features.json");
    std::fs::write(
        &features,
        r#"{"features": [{"name": "centre", "vertices": [0]},
                         {"name": "arc", "vertices": [5, 6, 7, 8], "closed": false}]}"#,
    )
    .unwrap();
    let out = run(&[
        surface.as_os_str(),
        "-o".as_ref(),
        out_dir.as_os_str(),
        "--size".as_ref(),
        "65".as_ref(),
        "--features".as_ref(),
        features.as_os_str(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("balanced flattening"), "{stdout}");
    assert!(stdout.contains("images.json"), "{stdout}");

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("images.json")).unwrap())
            .unwrap();
    assert_eq!(json["size"], 65);
    assert_eq!(json["features"], serde_json::json!(["centre", "arc"]));
    let images = json["images"].as_array().unwrap();
    let names: Vec<&str> = images.iter().map(|e| e["name"].as_str().unwrap()).collect();
    for want in [
        "mask",
        "position",
        "metric",
        "metric_extended",
        "mean_curvature",
        "mean_curvature_extended",
        "boundary_distance",
        "feature_0",
        "feature_1",
        "feature_distance",
    ] {
        assert!(names.contains(&want), "{want} missing from {names:?}");
    }
    for e in images {
        let npy = out_dir.join(e["npy"].as_str().unwrap());
        let (shape, _) = npy_shape(&npy);
        let listed: Vec<usize> = e["shape"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap() as usize)
            .collect();
        assert_eq!(shape, listed, "{}", npy.display());
        assert_eq!(&shape[..2], &[65, 65]);
        if let Some(png) = e["png"].as_str() {
            assert!(out_dir.join(png).is_file(), "{png}");
        }
    }
    // The pyramid: levels 0..=6 on (2^k + 1)² grids, each listed file present.
    let pyramid = json["pyramid"].as_array().unwrap();
    assert_eq!(pyramid.len(), 7);
    for (k, level) in pyramid.iter().enumerate() {
        let m = (1usize << k) + 1;
        assert_eq!(level["size"], m);
        for e in level["images"].as_array().unwrap() {
            let (shape, elem) = npy_shape(&out_dir.join(e["npy"].as_str().unwrap()));
            assert_eq!((shape, elem), (vec![m, m], 8));
        }
    }
    // The transform maps the flattening into [0, 1]².
    assert!(json["transform"].is_object(), "{}", json["transform"]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn texture_and_feature_mask_through_the_meshs_own_uvs() {
    let dir = temp_dir("images-mask");
    let (_, textured) = demo(&dir);
    let texture = dir.join("texture.png");
    let mut t = solid(8, 8, [200, 40, 40]);
    for y in 0..4 {
        for x in 0..8 {
            t.get_pixel_mut(x, y).0 = [40, 40, 200]; // top half blue
        }
    }
    save_png(&texture, &t).unwrap();
    // Mask of the texture's size: a square region in the middle.
    let mask = dir.join("mask.png");
    let mut m = solid(8, 8, [0, 0, 0]);
    for y in 2..6 {
        for x in 2..6 {
            m.get_pixel_mut(x, y).0 = [255, 0, 0];
        }
    }
    save_png(&mask, &m).unwrap();
    let out_dir = dir.join("img");
    let out = run(&[
        textured.as_os_str(),
        "-o".as_ref(),
        out_dir.as_os_str(),
        "--size".as_ref(),
        "33".as_ref(),
        "--texture".as_ref(),
        texture.as_os_str(),
        "--feature-mask".as_ref(),
        mask.as_os_str(),
        "--no-pyramid".as_ref(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("images.json")).unwrap())
            .unwrap();
    assert_eq!(json["features"], serde_json::json!(["#ff0000"]));
    assert_eq!(json["pyramid"].as_array().unwrap().len(), 0);
    let (shape, elem) = npy_shape(&out_dir.join("texture.npy"));
    assert_eq!((shape, elem), (vec![33, 33, 3], 1));
    // Both texture colours appear in the sampled texture.
    let bytes = std::fs::read(out_dir.join("texture.npy")).unwrap();
    let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let px: Vec<&[u8]> = bytes[10 + hlen..].chunks(3).collect();
    assert!(px.iter().any(|p| p[0] > 150 && p[2] < 100), "red missing");
    assert!(px.iter().any(|p| p[2] > 150 && p[0] < 100), "blue missing");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_fails_with_a_message_naming_the_problem() {
    let dir = temp_dir("images-errors");
    let (surface, textured) = demo(&dir);
    let out_dir = dir.join("img");

    // Unknown vertex id: the message names the feature and the vertex.
    let features = dir.join("bad.json");
    std::fs::write(
        &features,
        r#"{"features": [{"name": "ok", "vertices": [1]}, {"name": "chin", "vertices": [3, 123456]}]}"#,
    )
    .unwrap();
    let out = run(&[
        surface.as_os_str(),
        "-o".as_ref(),
        out_dir.as_os_str(),
        "--features".as_ref(),
        features.as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let e = stderr(&out);
    assert!(
        e.contains("chin") && e.contains("123456") && e.contains("bad.json"),
        "{e}"
    );
    assert!(!out_dir.join("images.json").exists());

    // Empty feature list.
    std::fs::write(&features, r#"{"features": []}"#).unwrap();
    let out = run(&[
        surface.as_os_str(),
        "-o".as_ref(),
        out_dir.as_os_str(),
        "--features".as_ref(),
        features.as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("empty"), "{}", stderr(&out));

    // Mask of the wrong size: the message gives both sizes.
    let texture = dir.join("texture.png");
    save_png(&texture, &solid(8, 4, [90, 90, 90])).unwrap();
    let mask = dir.join("mask.png");
    save_png(&mask, &solid(5, 3, [0, 255, 0])).unwrap();
    let out = run(&[
        textured.as_os_str(),
        "-o".as_ref(),
        out_dir.as_os_str(),
        "--texture".as_ref(),
        texture.as_os_str(),
        "--feature-mask".as_ref(),
        mask.as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let e = stderr(&out);
    assert!(
        e.contains("5×3") && e.contains("8×4") && e.contains("mask.png"),
        "{e}"
    );

    // A mask needs texture coordinates.
    let out = run(&[
        surface.as_os_str(),
        "-o".as_ref(),
        out_dir.as_os_str(),
        "--feature-mask".as_ref(),
        mask.as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("texture coordinates"),
        "{}",
        stderr(&out)
    );

    // Grid size not 2^k + 1.
    let out = run(&[
        surface.as_os_str(),
        "-o".as_ref(),
        out_dir.as_os_str(),
        "--size".as_ref(),
        "100".as_ref(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let e = stderr(&out);
    assert!(e.contains("100") && e.contains("2^k + 1"), "{e}");
    assert!(!out_dir.join("images.json").exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn real_face_if_present() {
    // A small real mesh with its own UVs (MediaPipe canonical face); skipped without data.
    let Some(mesh) = shared_file("faces/mp_canonical.obj") else {
        return;
    };
    let dir = temp_dir("images-face");
    let out = run(&[
        mesh.as_os_str(),
        "-o".as_ref(),
        dir.as_os_str(),
        "--size".as_ref(),
        "65".as_ref(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let (shape, _) = npy_shape(&dir.join("mean_curvature.npy"));
    assert_eq!(shape, vec![65, 65]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn face_with_open_eyes_and_mouth_with_fill_holes() {
    // ICT face crop: 4 boundary loops (outer rim, mouth, two eyes). Without
    // --fill-holes it is refused; with it, the holes stay outside the surface mask.
    let Some(d) = shared_data() else { return };
    let mesh = d.join("faces/ict/ict_neutral.obj");
    let dir = temp_dir("images-ict");
    let size: &std::ffi::OsStr = "65".as_ref();
    let refused = run(&[
        mesh.as_os_str(),
        "-o".as_ref(),
        dir.as_os_str(),
        "--size".as_ref(),
        size,
    ]);
    assert_eq!(refused.status.code(), Some(1));
    assert!(
        stderr(&refused).contains("boundary loops"),
        "{}",
        stderr(&refused)
    );
    let out = run(&[
        mesh.as_os_str(),
        "-o".as_ref(),
        dir.as_os_str(),
        "--size".as_ref(),
        size,
        "--fill-holes".as_ref(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(dir.join("images.json").is_file());
    std::fs::remove_dir_all(&dir).ok();
}

/// With a repair, feature ids are the file's: the demo surface with an unused vertex in
/// front (every id one higher) and `--repair` gives, for the same features (their ids one
/// higher), byte for byte the feature images of the surface itself.
#[test]
fn feature_ids_with_a_repair_are_the_file_s() {
    let dir = temp_dir("images-repair-ids");
    let (surface, _) = demo(&dir);
    let clean = surfmap::read_mesh(&surface).unwrap().mesh;
    let mut text = String::from("v 9 9 9\n");
    for p in &clean.positions {
        text += &format!("v {:?} {:?} {:?}\n", p[0], p[1], p[2]);
    }
    for f in &clean.triangles {
        text += &format!("f {} {} {}\n", f[0] + 2, f[1] + 2, f[2] + 2);
    }
    let shifted = dir.join("shifted.obj");
    std::fs::write(&shifted, text).unwrap();
    let features = |name: &str, offset: u32| {
        let path = dir.join(name);
        let ids = |v: [u32; 4]| format!("{:?}", v.map(|x| x + offset));
        std::fs::write(
            &path,
            format!(
                r#"{{"features": [{{"name": "arc", "vertices": {}}}, {{"name": "spot", "vertices": [{}]}}]}}"#,
                ids([5, 6, 7, 8]),
                40 + offset
            ),
        )
        .unwrap();
        path
    };
    let (plain, moved) = (features("plain.json", 0), features("moved.json", 1));
    for (mesh, f, out, extra) in [
        (&surface, &plain, "clean", None),
        (&shifted, &moved, "shifted", Some("--repair")),
    ] {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            mesh.as_os_str(),
            "-o".as_ref(),
            "--size".as_ref(),
            "65".as_ref(),
            "--no-pyramid".as_ref(),
            "--features".as_ref(),
            f.as_os_str(),
        ];
        let out_dir = dir.join(out);
        args.insert(2, out_dir.as_os_str());
        if let Some(e) = extra {
            args.push(e.as_ref());
        }
        let out = run(&args);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    for name in ["feature_0.npy", "feature_1.npy"] {
        let a = std::fs::read(dir.join("clean").join(name)).unwrap();
        let b = std::fs::read(dir.join("shifted").join(name)).unwrap();
        assert!(a == b, "{name} differs");
    }
    std::fs::remove_dir_all(&dir).ok();
}
