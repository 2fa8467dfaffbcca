//! glTF 2.0 binary (`.glb`) export of a triangle mesh with morph targets and an
//! animation of their weights: any glTF viewer plays a morph (§5.2) or a blend-shape rig
//! (§5.3) from it.
//!
//! The file holds one scene with one node and one mesh primitive: `POSITION`, `NORMAL`
//! (area-weighted vertex normals), optionally `TEXCOORD_0` with an embedded PNG as the
//! base colour texture, 32-bit indices, and one morph target per key with `POSITION`
//! and `NORMAL` displacements. Target names go in `mesh.extras.targetNames` (the
//! convention Blender and three.js read). The animation samples the weights at the
//! keyframe times given, linearly interpolated. Every accessor carries `min`/`max`
//! where the specification requires them (positions, morph target positions,
//! animation inputs), computed from the `f32` values actually stored.
//!
//! glTF stores a vertex once per distinct (position, texture coordinate) pair, so a mesh
//! with per-corner texture coordinates is split along its texture seams; the morph
//! targets follow the split.
//!
//! The JSON is written with `serde_json` and the binary chunk by hand (GLB container:
//! 12-byte header, a JSON chunk padded with spaces and a BIN chunk padded with zeros,
//! each to a multiple of 4 bytes). The `gltf-json` crate was considered: its typed
//! structures add nothing the tests do not check (they read every file back with the
//! `gltf` crate, and `scripts/validate_gltf.sh` runs the Khronos validator).

use std::path::Path;

use serde_json::{Value, json};

use super::AppError;
use crate::mesh::Uvs;
use crate::vec3::{cross3, norm3, sub3};

/// A named morph target: one displacement per vertex of the mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfTarget {
    pub name: String,
    pub displacements: Vec<[f64; 3]>,
}

/// An animation of the morph weights: at `times[k]` (seconds, increasing) the weights
/// are `weights[k]` (one per target), linear in between.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfAnimation {
    pub name: String,
    pub times: Vec<f64>,
    pub weights: Vec<Vec<f64>>,
}

/// Everything a `.glb` file of ours holds.
#[derive(Clone, Debug, Default)]
pub struct GltfMorphScene {
    pub name: String,
    pub positions: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Texture coordinates (per vertex or per corner) for `texture_png`.
    pub uvs: Option<Uvs>,
    /// An encoded PNG used as the base colour texture (needs `uvs`).
    pub texture_png: Option<Vec<u8>>,
    pub targets: Vec<GltfTarget>,
    pub animation: Option<GltfAnimation>,
}

impl GltfMorphScene {
    /// One target `name` and an animation of its weight `0 → 1` over `seconds`
    /// (the morph of §5.2).
    pub fn morph(
        positions: Vec<[f64; 3]>,
        triangles: Vec<[u32; 3]>,
        name: &str,
        displacements: Vec<[f64; 3]>,
        seconds: f64,
    ) -> Self {
        Self {
            name: name.to_owned(),
            positions,
            triangles,
            targets: vec![GltfTarget {
                name: name.to_owned(),
                displacements,
            }],
            animation: Some(GltfAnimation {
                name: format!("{name} 0 to 1"),
                times: vec![0.0, seconds],
                weights: vec![vec![0.0], vec![1.0]],
            }),
            ..Self::default()
        }
    }

    /// An animation that shows each target in turn: its weight rises `0 → 1` and falls
    /// back over `seconds_per_key`, one key after the other.
    pub fn key_by_key_animation(&self, seconds_per_key: f64) -> GltfAnimation {
        let n = self.targets.len();
        let mut times = vec![0.0];
        let mut weights = vec![vec![0.0; n]];
        for k in 0..n {
            let t0 = k as f64 * seconds_per_key;
            let mut up = vec![0.0; n];
            up[k] = 1.0;
            times.push(t0 + 0.5 * seconds_per_key);
            weights.push(up);
            times.push(t0 + seconds_per_key);
            weights.push(vec![0.0; n]);
        }
        GltfAnimation {
            name: "keys one by one".into(),
            times,
            weights,
        }
    }

    fn check(&self) -> Result<(), AppError> {
        let nv = self.positions.len();
        if nv == 0 || self.triangles.is_empty() {
            return Err(AppError::Option(
                "a glTF mesh needs at least one triangle".into(),
            ));
        }
        crate::mesh::check_indices(&self.triangles, nv)?;
        if let Some(v) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|x| x.is_finite()))
        {
            return Err(AppError::Option(format!(
                "vertex {v} has a position that is not finite"
            )));
        }
        for t in &self.targets {
            if t.displacements.len() != nv {
                return Err(AppError::per_vertex(
                    "morph target displacements",
                    t.displacements.len(),
                    nv,
                ));
            }
            if !t.displacements.iter().flatten().all(|x| x.is_finite()) {
                return Err(AppError::Option(format!(
                    "morph target '{}' has a displacement that is not finite",
                    t.name
                )));
            }
        }
        if self.texture_png.is_some() && self.uvs.is_none() {
            return Err(AppError::Option(
                "a texture needs texture coordinates".into(),
            ));
        }
        if let Some(a) = &self.animation {
            let increasing = a.times.windows(2).all(|w| w[0] < w[1]);
            if a.times.is_empty()
                || !increasing
                || !a.times.iter().all(|t| t.is_finite() && *t >= 0.0)
                || a.weights.len() != a.times.len()
                || a.weights.iter().any(|w| w.len() != self.targets.len())
                || self.targets.is_empty()
            {
                return Err(AppError::Option(format!(
                    "animation '{}': needs increasing times ≥ 0 and one weight per target at each time",
                    a.name
                )));
            }
        }
        Ok(())
    }
}

/// Area-weighted vertex normals (unit; `[0, 0, 1]` where undefined).
pub fn vertex_normals(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<[f64; 3]> {
    let mut n = vec![[0.0; 3]; positions.len()];
    for t in triangles {
        let p = t.map(|v| positions[v as usize]);
        let c = cross3(sub3(p[1], p[0]), sub3(p[2], p[0]));
        for &v in t {
            for k in 0..3 {
                n[v as usize][k] += c[k];
            }
        }
    }
    n.iter()
        .map(|v| {
            let l = norm3(*v);
            if l > 0.0 && l.is_finite() {
                v.map(|x| x / l)
            } else {
                [0.0, 0.0, 1.0]
            }
        })
        .collect()
}

/// The binary chunk under construction: bufferViews appended 4-byte aligned.
struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.data.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.data.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    /// A float accessor of `D` components per element, with min/max when asked.
    fn floats<const D: usize>(
        &mut self,
        values: &[[f32; D]],
        target: Option<u32>,
        bounds: bool,
    ) -> usize {
        let bytes: Vec<u8> = values
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let view = self.view(&bytes, target);
        let kind = match D {
            1 => "SCALAR",
            2 => "VEC2",
            3 => "VEC3",
            _ => "VEC4",
        };
        let mut a =
            json!({"bufferView": view, "componentType": 5126, "count": values.len(), "type": kind});
        if bounds {
            let mut lo = [f32::INFINITY; D];
            let mut hi = [f32::NEG_INFINITY; D];
            for v in values {
                for k in 0..D {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
            a["min"] = json!(lo.map(f64::from).to_vec());
            a["max"] = json!(hi.map(f64::from).to_vec());
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }
}

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// The `.glb` bytes of a scene.
pub fn glb_bytes(scene: &GltfMorphScene) -> Result<Vec<u8>, AppError> {
    scene.check()?;
    // glTF vertices: one per distinct (vertex, texture coordinate) pair.
    let (source, indices, uv_of): (Vec<u32>, Vec<u32>, Option<Vec<[f64; 2]>>) = match &scene.uvs {
        None => (
            (0..scene.positions.len() as u32).collect(),
            scene.triangles.iter().flatten().copied().collect(),
            None,
        ),
        Some(uvs) => {
            let corners = super::texture::corner_uvs(uvs, &scene.triangles)?;
            let mut map = std::collections::HashMap::new();
            let mut source = vec![];
            let mut uv = vec![];
            let mut indices = Vec::with_capacity(3 * scene.triangles.len());
            for (tri, c) in scene.triangles.iter().zip(&corners) {
                for k in 0..3 {
                    let key = (tri[k], c[k][0].to_bits(), c[k][1].to_bits());
                    let id = *map.entry(key).or_insert_with(|| {
                        source.push(tri[k]);
                        uv.push(c[k]);
                        source.len() as u32 - 1
                    });
                    indices.push(id);
                }
            }
            (source, indices, Some(uv))
        }
    };
    let expand = |values: &[[f64; 3]]| -> Vec<[f32; 3]> {
        source
            .iter()
            .map(|&v| values[v as usize].map(|x| x as f32))
            .collect()
    };
    let normals = vertex_normals(&scene.positions, &scene.triangles);

    let mut bin = Bin {
        data: vec![],
        views: vec![],
        accessors: vec![],
    };
    let position = bin.floats(&expand(&scene.positions), Some(ARRAY_BUFFER), true);
    let normal = bin.floats(&expand(&normals), Some(ARRAY_BUFFER), false);
    let mut attributes = json!({"POSITION": position, "NORMAL": normal});
    if let Some(uv) = &uv_of {
        // glTF's t axis points down the image: t = 1 − v.
        let st: Vec<[f32; 2]> = uv
            .iter()
            .map(|p| [p[0] as f32, (1.0 - p[1]) as f32])
            .collect();
        attributes["TEXCOORD_0"] = json!(bin.floats(&st, Some(ARRAY_BUFFER), false));
    }
    let index_bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
    let index_view = bin.view(&index_bytes, Some(ELEMENT_ARRAY_BUFFER));
    bin.accessors.push(json!({
        "bufferView": index_view, "componentType": 5125, "count": indices.len(), "type": "SCALAR"
    }));
    let index_accessor = bin.accessors.len() - 1;
    let mut targets = vec![];
    for t in &scene.targets {
        let moved: Vec<[f64; 3]> = scene
            .positions
            .iter()
            .zip(&t.displacements)
            .map(|(p, d)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
            .collect();
        let moved_normals = vertex_normals(&moved, &scene.triangles);
        let normal_delta: Vec<[f64; 3]> = moved_normals
            .iter()
            .zip(&normals)
            .map(|(a, b)| sub3(*a, *b))
            .collect();
        let p = bin.floats(&expand(&t.displacements), Some(ARRAY_BUFFER), true);
        let n = bin.floats(&expand(&normal_delta), Some(ARRAY_BUFFER), false);
        targets.push(json!({"POSITION": p, "NORMAL": n}));
    }

    let mut primitive =
        json!({"attributes": attributes, "indices": index_accessor, "mode": 4, "material": 0});
    if !targets.is_empty() {
        primitive["targets"] = json!(targets);
    }
    let mut mesh = json!({"name": scene.name, "primitives": [primitive]});
    if !scene.targets.is_empty() {
        mesh["weights"] = json!(vec![0.0; scene.targets.len()]);
        mesh["extras"] = json!({"targetNames": scene.targets.iter().map(|t| t.name.clone()).collect::<Vec<_>>()});
    }
    let mut pbr = json!({"baseColorFactor": [0.85, 0.85, 0.85, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8});
    let mut root = json!({
        "asset": {"version": "2.0", "generator": concat!("surfmap ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": scene.name, "mesh": 0}],
        "meshes": [mesh],
    });
    if let Some(png) = &scene.texture_png {
        let view = bin.view(png, None);
        root["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
        root["samplers"] =
            json!([{"magFilter": 9729, "minFilter": 9987, "wrapS": 33071, "wrapT": 33071}]);
        root["textures"] = json!([{"sampler": 0, "source": 0}]);
        pbr = json!({"baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 0.8});
    }
    root["materials"] =
        json!([{"name": "surface", "pbrMetallicRoughness": pbr, "doubleSided": true}]);
    if let Some(a) = &scene.animation {
        let times: Vec<[f32; 1]> = a.times.iter().map(|&t| [t as f32]).collect();
        let weights: Vec<[f32; 1]> = a.weights.iter().flatten().map(|&w| [w as f32]).collect();
        let input = bin.floats(&times, None, true);
        let output = bin.floats(&weights, None, false);
        root["animations"] = json!([{
            "name": a.name,
            "samplers": [{"input": input, "output": output, "interpolation": "LINEAR"}],
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
        }]);
    }
    root["bufferViews"] = json!(bin.views);
    root["accessors"] = json!(bin.accessors);
    root["buffers"] = json!([{"byteLength": bin.data.len()}]);

    let mut json_bytes = serde_json::to_vec(&root).map_err(|e| AppError::Option(e.to_string()))?;
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    let mut data = bin.data;
    while !data.len().is_multiple_of(4) {
        data.push(0);
    }
    let total = 12 + 8 + json_bytes.len() + 8 + data.len();
    let total = u32::try_from(total).map_err(|_| {
        AppError::Option(format!(
            "the glTF file would be {total} bytes, more than a GLB can hold (4 GiB)"
        ))
    })?;
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total.to_le_bytes());
    out.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json_bytes);
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&data);
    Ok(out)
}

/// Writes a scene as `.glb`, atomically (temporary file + rename).
pub fn write_glb(path: &Path, scene: &GltfMorphScene) -> Result<usize, AppError> {
    let bytes = glb_bytes(scene)?;
    crate::fsutil::write_atomically(path, |w| w.write_all(&bytes)).map_err(AppError::io(path))?;
    Ok(bytes.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::bumpy_disc;

    fn read(bytes: &[u8]) -> (gltf::Document, Vec<u8>) {
        let g = gltf::Gltf::from_slice(bytes).expect("a valid glTF");
        let blob = g.blob.clone().expect("a BIN chunk");
        (g.document, blob)
    }

    #[test]
    fn morph_reads_back_with_bounds_targets_and_animation() {
        let mesh = bumpy_disc(6, 0.3);
        let d: Vec<[f64; 3]> = mesh
            .positions
            .iter()
            .map(|p| [0.1 * p[1], 0.0, 0.5 - p[0]])
            .collect();
        let scene = GltfMorphScene::morph(
            mesh.positions.clone(),
            mesh.triangles.clone(),
            "A to B",
            d.clone(),
            2.0,
        );
        let bytes = glb_bytes(&scene).unwrap();
        assert_eq!(&bytes[..4], b"glTF");
        assert_eq!(
            u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
            bytes.len()
        );
        assert_eq!(bytes.len() % 4, 0);
        let (doc, blob) = read(&bytes);
        let m = doc.meshes().next().unwrap();
        let names: Vec<String> = serde_json::from_str::<Value>(m.extras().as_ref().unwrap().get())
            .unwrap()["targetNames"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().to_owned())
            .collect();
        assert_eq!(names, vec!["A to B"]);
        assert_eq!(m.weights(), Some(&[0.0f32][..]));
        let prim = m.primitives().next().unwrap();
        assert_eq!(prim.morph_targets().count(), 1);
        let reader = prim.reader(|_| Some(&blob));
        let pos: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        assert_eq!(pos.len(), mesh.num_vertices());
        for (p, q) in pos.iter().zip(&mesh.positions) {
            for k in 0..3 {
                assert_eq!(p[k], q[k] as f32);
            }
        }
        let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        assert_eq!(
            idx,
            mesh.triangles.iter().flatten().copied().collect::<Vec<_>>()
        );
        // min/max of POSITION and of the target are the exact bounds of the stored data.
        let bounds = |a: gltf::Accessor| {
            let (lo, hi) = (a.min().unwrap(), a.max().unwrap());
            let f = |v: &Value| -> Vec<f32> {
                v.as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap() as f32)
                    .collect()
            };
            (f(&lo), f(&hi))
        };
        let (lo, hi) = bounds(prim.get(&gltf::Semantic::Positions).unwrap());
        for k in 0..3 {
            assert_eq!(
                lo[k],
                pos.iter().map(|p| p[k]).fold(f32::INFINITY, f32::min)
            );
            assert_eq!(
                hi[k],
                pos.iter().map(|p| p[k]).fold(f32::NEG_INFINITY, f32::max)
            );
        }
        let target = prim.morph_targets().next().unwrap();
        let (lo, hi) = bounds(target.positions().unwrap());
        let disp: Vec<[f32; 3]> = reader
            .read_morph_targets()
            .next()
            .unwrap()
            .0
            .unwrap()
            .collect();
        for (p, q) in disp.iter().zip(&d) {
            for k in 0..3 {
                assert_eq!(p[k], q[k] as f32);
                assert!(lo[k] <= p[k] && p[k] <= hi[k]);
            }
        }
        // The animation: weights 0 → 1 on node 0 over [0, 2] s, linear.
        let anim = doc.animations().next().unwrap();
        let channel = anim.channels().next().unwrap();
        assert_eq!(channel.target().node().index(), 0);
        assert_eq!(
            channel.target().property(),
            gltf::animation::Property::MorphTargetWeights
        );
        assert_eq!(
            channel.sampler().interpolation(),
            gltf::animation::Interpolation::Linear
        );
        let r = channel.reader(|_| Some(&blob));
        let times: Vec<f32> = r.read_inputs().unwrap().collect();
        assert_eq!(times, vec![0.0, 2.0]);
        let weights: Vec<f32> = match r.read_outputs().unwrap() {
            gltf::animation::util::ReadOutputs::MorphTargetWeights(w) => w.into_f32().collect(),
            _ => panic!("not weights"),
        };
        assert_eq!(weights, vec![0.0, 1.0]);
        let input = channel.sampler().input();
        assert!(input.min().is_some() && input.max().is_some());
    }

    #[test]
    fn per_corner_uvs_split_vertices_and_targets_follow() {
        // Two triangles sharing an edge whose texture coordinates differ on each side:
        // 4 vertices become 6 glTF vertices; each keeps its position and displacement.
        let positions = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let triangles = vec![[0, 1, 2], [0, 2, 3]];
        let uvs = Uvs::PerCorner {
            coords: vec![
                [0.0, 0.0],
                [0.5, 0.0],
                [0.5, 0.5],
                [0.6, 0.0],
                [0.9, 0.5],
                [0.6, 0.5],
            ],
            indices: vec![[0, 1, 2], [3, 4, 5]],
        };
        let png = {
            let mut buf = Vec::new();
            image::RgbImage::from_pixel(4, 4, image::Rgb([200, 100, 50]))
                .write_to(&mut std::io::Cursor::new(&mut buf), image::ImageFormat::Png)
                .unwrap();
            buf
        };
        let disp: Vec<[f64; 3]> = (0..4).map(|i| [0.0, 0.0, i as f64]).collect();
        let mut scene = GltfMorphScene {
            name: "quad".into(),
            positions: positions.clone(),
            triangles,
            uvs: Some(uvs),
            texture_png: Some(png),
            targets: vec![
                GltfTarget {
                    name: "up".into(),
                    displacements: disp.clone(),
                },
                GltfTarget {
                    name: "down".into(),
                    displacements: disp.iter().map(|d| d.map(|x| -x)).collect(),
                },
            ],
            animation: None,
        };
        scene.animation = Some(scene.key_by_key_animation(1.0));
        let bytes = glb_bytes(&scene).unwrap();
        let (doc, blob) = read(&bytes);
        let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|_| Some(&blob));
        let pos: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        let st: Vec<[f32; 2]> = reader.read_tex_coords(0).unwrap().into_f32().collect();
        assert_eq!(pos.len(), 6);
        let targets: Vec<Vec<[f32; 3]>> = reader
            .read_morph_targets()
            .map(|(p, _, _)| p.unwrap().collect())
            .collect();
        assert_eq!(targets.len(), 2);
        for (i, p) in pos.iter().enumerate() {
            // Find the source vertex by position; its displacement is (0, 0, index).
            let v = positions
                .iter()
                .position(|q| q.map(|x| x as f32) == *p)
                .unwrap();
            assert_eq!(targets[0][i], [0.0, 0.0, v as f32]);
            assert_eq!(targets[1][i], [0.0, 0.0, -(v as f32)]);
        }
        assert!(st.contains(&[0.9, 0.5]) && st.contains(&[0.5, 1.0]));
        assert_eq!(doc.images().count(), 1);
        let mat = doc.materials().next().unwrap();
        assert!(mat.pbr_metallic_roughness().base_color_texture().is_some());
        // Key-by-key animation: 1 + 2 keyframes per target.
        let anim = doc.animations().next().unwrap();
        let r = anim.channels().next().unwrap().reader(|_| Some(&blob));
        assert_eq!(r.read_inputs().unwrap().count(), 5);
    }

    #[test]
    fn inconsistent_scenes_are_refused() {
        let mesh = bumpy_disc(2, 0.1);
        let mut s = GltfMorphScene::morph(
            mesh.positions.clone(),
            mesh.triangles.clone(),
            "x",
            vec![[0.0; 3]; 3],
            1.0,
        );
        assert!(matches!(glb_bytes(&s), Err(AppError::Length { .. })));
        s.targets[0].displacements = vec![[0.0; 3]; mesh.num_vertices()];
        s.animation.as_mut().unwrap().times = vec![1.0, 0.5];
        assert!(glb_bytes(&s).is_err());
        s.animation = None;
        s.triangles.push([0, 1, 999]);
        assert!(matches!(glb_bytes(&s), Err(AppError::Index(_))));
    }
}
