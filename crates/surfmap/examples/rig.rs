//! A blend-shape rig (thesis §5.3): a generated neutral "face" and two expression keys,
//! each key a surface of its own triangulation, re-expressed on the neutral's
//! connectivity through a correspondence neutral → key, and written as one glTF binary
//! (`.glb`) with a named morph target per key and an animation showing them in turn.
//!
//! The correspondences here are known in closed form (all three surfaces are built over
//! the same unit disc); with scanned keys they come from `surfmap::matching::match_meshes`
//! (its `Match::correspondence`), or from `surfmap match` folders as `surfmap rig` reads.
//!
//! `cargo run --release -p surfmap --example rig`

use surfmap::apps::gltf::{GltfMorphScene, GltfTarget, write_glb};
use surfmap::apps::rig_key;
use surfmap::{PointLocator, SurfacePoint, TriMesh};

/// A pose: the point of the surface over parameter `(x, y)` of the unit disc.
type Pose = fn(f64, f64) -> [f64; 3];

/// The neutral: a dome with a nose-like bump.
fn neutral(x: f64, y: f64) -> [f64; 3] {
    let nose = 0.25 * (-20.0 * (x * x + (y - 0.1).powi(2))).exp();
    [x, y, 0.4 * (1.0 - x * x - y * y) + nose]
}

/// "smile": the mouth region (below the nose) widens and its corners rise.
fn smile(x: f64, y: f64) -> [f64; 3] {
    let [_, _, z] = neutral(x, y);
    let mouth = (-12.0 * (y + 0.4).powi(2)).exp() * (1.0 - x * x);
    [
        x * (1.0 + 0.1 * mouth),
        y + 0.12 * mouth * x * x,
        z + 0.05 * mouth,
    ]
}

/// "brows up": the band above the nose moves up and forward.
fn brows_up(x: f64, y: f64) -> [f64; 3] {
    let [_, _, z] = neutral(x, y);
    let brows = (-15.0 * (y - 0.5).powi(2)).exp();
    [x, y + 0.08 * brows, z + 0.04 * brows]
}

/// `pose` sampled on a polar grid of the disc (`rings` circles of `segments` vertices):
/// the mesh, and each vertex's parameter `(x, y)`.
fn build(pose: Pose, rings: usize, segments: usize) -> (TriMesh, Vec<[f64; 2]>) {
    let disc = surfmap::mesh::generate::polar_disc(rings, segments);
    let params: Vec<[f64; 2]> = disc.positions.iter().map(|p| [p[0], p[1]]).collect();
    let positions = params.iter().map(|&[x, y]| pose(x, y)).collect();
    (TriMesh::new(positions, disc.triangles), params)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // Three triangulations: each key is meshed differently from the neutral.
    let (face, face_params) = build(neutral, 30, 96);
    let keys: [(&str, Pose, usize, usize); 2] =
        [("smile", smile, 24, 80), ("brows_up", brows_up, 36, 110)];

    let mut targets = vec![];
    for (name, pose, rings, segments) in keys {
        let (key, key_params) = build(pose, rings, segments);
        // The correspondence neutral → key: for each neutral vertex, the point of the
        // key (triangle + barycentric coordinates) with the same disc parameter; None
        // where the key's polygon does not reach (at the rim): those vertices get a
        // harmonic extension of their neighbours' displacements.
        let locator = PointLocator::new(&key_params, &key.triangles)?;
        let map: Vec<Option<SurfacePoint>> = locator.locate_many(&face_params);
        let rig = rig_key(name, &face, &map, &key)?;

        // Check: the key on the neutral's connectivity against the pose in closed form.
        let on_face = rig.mesh(&face);
        let error = on_face
            .positions
            .iter()
            .zip(&face_params)
            .map(|(p, &[x, y])| {
                let t = pose(x, y);
                (0..3).map(|k| (p[k] - t[k]).powi(2)).sum::<f64>().sqrt()
            })
            .fold(0.0, f64::max);
        println!(
            "key {name}: {} triangles of its own; {} of {} neutral vertices matched, {} extended; largest error {error:.4}",
            key.num_triangles(),
            rig.target.matched,
            face.num_vertices(),
            rig.target.extended.len()
        );
        targets.push(GltfTarget {
            name: name.to_owned(),
            displacements: rig.target.displacements,
        });
    }

    // The glTF scene: the neutral's mesh, one morph target per key, and an animation
    // raising each key's weight 0 → 1 → 0 in turn (1 s per key).
    let mut scene = GltfMorphScene {
        name: "rig".into(),
        positions: face.positions.clone(),
        triangles: face.triangles.clone(),
        targets,
        ..GltfMorphScene::default()
    };
    scene.animation = Some(scene.key_by_key_animation(1.0));

    let dir = std::env::temp_dir().join(format!("surfmap-rig-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("rig.glb");
    let bytes = write_glb(&path, &scene)?; // atomic: temporary file, then rename
    let head = std::fs::read(&path)?;
    assert!(head.starts_with(b"glTF") && head.len() == bytes);
    println!(
        "wrote {} ({bytes} bytes, {} vertices, {} morph targets: {})",
        path.display(),
        scene.positions.len(),
        scene.targets.len(),
        scene
            .targets
            .iter()
            .map(|t| t.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}
