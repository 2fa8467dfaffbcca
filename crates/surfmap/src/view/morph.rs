//! The page of a glTF morph or rig (`surfmap morph`, `surfmap rig`): the mesh, one
//! slider per morph target (named by `mesh.extras.targetNames`) and the weight
//! animation played, paused and scrubbed. The mesh's base colour texture is shown when
//! the file embeds one.
//!
//! The file is read with the `gltf` crate: the first primitive of the first mesh
//! (the only one in the files surfmap writes), its positions, indices, morph target
//! displacements and texture coordinates, and the first animation of its weights.

use std::path::Path;

use gltf::Gltf;
use gltf::animation::util::ReadOutputs;
use serde_json::{Value, json};

use super::page::{PageData, base64};
use super::surface::add_mesh;
use super::{BuiltPage, PageKind, ViewError};

/// Builds the page of the `.glb` file `path`.
pub(crate) fn build(path: &Path) -> Result<BuiltPage, ViewError> {
    let bytes = std::fs::read(path).map_err(ViewError::io(path))?;
    let gltf = Gltf::from_slice(&bytes).map_err(|e| {
        ViewError::input(
            path,
            format!("not a glTF binary (.glb) surfmap can read: {e}"),
        )
    })?;
    let blob = gltf.blob.as_deref();
    let buffers = |b: gltf::Buffer<'_>| match b.source() {
        gltf::buffer::Source::Bin => blob,
        gltf::buffer::Source::Uri(_) => None,
    };
    let meshes: Vec<gltf::Mesh<'_>> = gltf.meshes().collect();
    let mesh = meshes
        .first()
        .ok_or_else(|| ViewError::input(path, "the file has no mesh"))?;
    let primitive = mesh
        .primitives()
        .next()
        .ok_or_else(|| ViewError::input(path, "the mesh has no primitive"))?;
    let mut notes = vec![];
    let primitives: usize = meshes.iter().map(|m| m.primitives().count()).sum();
    if primitives > 1 {
        notes.push(format!(
            "the file has {primitives} mesh primitives; the first is shown"
        ));
    }
    let reader = primitive.reader(buffers);
    let positions: Vec<[f64; 3]> = reader
        .read_positions()
        .ok_or_else(|| {
            ViewError::input(path, "the mesh has no positions in the file's binary chunk")
        })?
        .map(|p| p.map(f64::from))
        .collect();
    let indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    if primitive.mode() != gltf::mesh::Mode::Triangles || !indices.len().is_multiple_of(3) {
        return Err(ViewError::input(
            path,
            "the primitive is not a list of triangles",
        ));
    }
    let triangles: Vec<[u32; 3]> = indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    crate::mesh::check_indices(&triangles, positions.len())
        .map_err(|e| ViewError::input(path, e.to_string()))?;
    let title = path
        .file_name()
        .map_or("morph".into(), |n| n.to_string_lossy().into_owned());
    let mut page = PageData::new("morph", &title);
    let surface = add_mesh(&mut page, "surface", &positions, &triangles);
    page.set("surface", surface);

    let names = target_names(mesh);
    let mut targets = vec![];
    for (k, (displacements, _, _)) in reader.read_morph_targets().enumerate() {
        let Some(d) = displacements else {
            notes.push(format!("morph target {k} moves no position; left out"));
            continue;
        };
        let d: Vec<[f64; 3]> = d.map(|p| p.map(f64::from)).collect();
        if d.len() != positions.len() {
            return Err(ViewError::input(
                path,
                format!(
                    "morph target {k} has {} displacements for {} vertices",
                    d.len(),
                    positions.len()
                ),
            ));
        }
        let array = format!("target.{k}");
        page.add_points(&array, &d);
        let name = names
            .get(k)
            .cloned()
            .unwrap_or_else(|| format!("target {k}"));
        targets.push(json!({"name": name, "array": array, "index": k}));
    }
    if targets.is_empty() {
        notes.push("the mesh has no morph target: nothing moves".into());
    }
    page.set("targets", json!(targets));
    page.set("animation", animation(&gltf, blob));
    if let Some(st) = reader.read_tex_coords(0) {
        // glTF's t axis points down the image; the page's v points up.
        let uv: Vec<[f64; 2]> = st
            .into_f32()
            .map(|c| [f64::from(c[0]), 1.0 - f64::from(c[1])])
            .collect();
        if let Some(url) = texture(&primitive, blob) {
            page.add_points("uv.coords", &uv);
            page.set("texture", json!(url));
        }
    }
    Ok(BuiltPage {
        kind: PageKind::Morph,
        data: page,
        triangles: triangles.len(),
        notes,
    })
}

/// `mesh.extras.targetNames`, the convention Blender and three.js read.
fn target_names(mesh: &gltf::Mesh<'_>) -> Vec<String> {
    mesh.extras()
        .as_ref()
        .and_then(|raw| serde_json::from_str::<Value>(raw.get()).ok())
        .and_then(|v| v.get("targetNames").cloned())
        .and_then(|v| serde_json::from_value(v).ok())
        .unwrap_or_default()
}

/// The first animation of morph weights: `{"name", "times": [...], "weights": [[...]]}`
/// (one weight per target at each time), or `null`.
fn animation(gltf: &Gltf, blob: Option<&[u8]>) -> Value {
    for animation in gltf.animations() {
        for channel in animation.channels() {
            let reader = channel.reader(|b| match b.source() {
                gltf::buffer::Source::Bin => blob,
                gltf::buffer::Source::Uri(_) => None,
            });
            let (Some(inputs), Some(ReadOutputs::MorphTargetWeights(w))) =
                (reader.read_inputs(), reader.read_outputs())
            else {
                continue;
            };
            let times: Vec<f32> = inputs.collect();
            let weights: Vec<f32> = w.into_f32().collect();
            if times.is_empty() || !weights.len().is_multiple_of(times.len()) {
                continue;
            }
            let per = weights.len() / times.len();
            let rows: Vec<&[f32]> = weights.chunks(per).collect();
            return json!({
                "name": animation.name().unwrap_or("animation"),
                "times": times,
                "weights": rows,
                "interpolation": format!("{:?}", channel.sampler().interpolation()),
            });
        }
    }
    Value::Null
}

/// The base colour texture as a `data:` URL, when the file embeds it (PNG or JPEG).
fn texture(primitive: &gltf::Primitive<'_>, blob: Option<&[u8]>) -> Option<String> {
    let info = primitive
        .material()
        .pbr_metallic_roughness()
        .base_color_texture()?;
    let gltf::image::Source::View { view, mime_type } = info.texture().source().source() else {
        return None;
    };
    let bytes = blob?.get(view.offset()..view.offset() + view.length())?;
    Some(format!("data:{mime_type};base64,{}", base64(bytes)))
}

#[cfg(test)]
mod tests {
    use super::super::page::tests::{array, embedded};
    use super::super::{ViewInput, ViewOptions, write_page};
    use super::*;
    use crate::apps::gltf::{GltfMorphScene, GltfTarget, write_glb};

    #[test]
    fn a_rig_page_has_every_target_with_its_name_and_the_animation() {
        let dir = std::env::temp_dir().join(format!("surfmap-view-glb-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mesh = crate::mesh::generate::bumpy_disc(5, 0.2);
        let n = mesh.num_vertices();
        let up: Vec<[f64; 3]> = (0..n).map(|i| [0.0, 0.0, 0.01 * i as f64]).collect();
        let side: Vec<[f64; 3]> = (0..n).map(|i| [0.5, -0.25 * (i % 3) as f64, 0.0]).collect();
        let mut scene = GltfMorphScene {
            name: "rig".into(),
            positions: mesh.positions.clone(),
            triangles: mesh.triangles.clone(),
            targets: vec![
                GltfTarget {
                    name: "smile".into(),
                    displacements: up.clone(),
                },
                GltfTarget {
                    name: "jaw open".into(),
                    displacements: side.clone(),
                },
            ],
            ..GltfMorphScene::default()
        };
        scene.animation = Some(scene.key_by_key_animation(1.0));
        let glb = dir.join("rig.glb");
        write_glb(&glb, &scene).unwrap();
        let input = ViewInput::detect(&glb, &ViewOptions::default()).unwrap();
        assert_eq!(input, ViewInput::Gltf { file: glb.clone() });
        let page = dir.join("rig.html");
        let written = write_page(&input, &page).unwrap();
        assert_eq!(written.kind, PageKind::Morph);
        let doc = embedded(&std::fs::read_to_string(&page).unwrap());
        assert_eq!(doc["targets"][0]["name"], "smile");
        assert_eq!(doc["targets"][1]["name"], "jaw open");
        for (k, d) in [up, side].iter().enumerate() {
            let got = array(&doc, &format!("target.{k}"), f32::from_le_bytes);
            let want: Vec<f32> = d.iter().flatten().map(|&x| x as f32).collect();
            assert_eq!(got, want);
        }
        // Key by key: 1 + 2 keyframes per target, weights one per target.
        assert_eq!(doc["animation"]["times"].as_array().unwrap().len(), 5);
        assert_eq!(doc["animation"]["weights"][1], json!([1.0, 0.0]));
        // Not a glTF: a clear error.
        let bad = dir.join("bad.glb");
        std::fs::write(&bad, b"not a gltf").unwrap();
        let e = write_page(&ViewInput::Gltf { file: bad.clone() }, &page)
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.glb") && e.contains("not a glTF"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
