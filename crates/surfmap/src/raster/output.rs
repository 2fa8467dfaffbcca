//! Writing a [`GeometryImages`] set to a folder: every image as raw `.npy` (numpy-readable)
//! and as a colour-mapped PNG, the pyramid levels, and `images.json` describing the
//! transform, the grid, the units and the files. Every file goes through
//! `write_atomically`.

use std::path::Path;

use serde::Serialize;

use super::RasterError;
use super::images::{GeometryImages, GeometryPyramid, SurfaceScale};
use super::npy::save_npy;
use super::picture::{OUTSIDE_GREY, distance_picture, diverging_picture, metric_picture};
use crate::grid::{DomainTransform, Grid};
use crate::render::{RgbImage, grid_image, save_png};

/// `images.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ImagesManifest {
    pub format: &'static str,
    /// Nodes per side; node `(i, j)` is array element `[i, j]` at `ξ = (j, i)/(size − 1)`.
    pub size: usize,
    /// `ξ = scale · uv + offset` maps flattening UVs into ω = `[0,1]²`.
    pub transform: DomainTransform,
    pub scale: SurfaceScale,
    /// The length unit `ℓ` in mesh units (h in 1/ℓ, g in ℓ², feature distances in ℓ).
    pub length_unit: f64,
    pub images: Vec<ImageEntry>,
    pub features: Vec<String>,
    pub pyramid: Vec<PyramidEntry>,
}

#[derive(Clone, Debug, Serialize)]
pub struct ImageEntry {
    pub name: String,
    pub npy: String,
    pub png: Option<String>,
    pub shape: Vec<usize>,
    pub description: String,
}

#[derive(Clone, Debug, Serialize)]
pub struct PyramidEntry {
    pub level: u32,
    pub size: usize,
    pub sigma: f64,
    pub images: Vec<ImageEntry>,
}

/// Writes every image of `img` into `dir` (created if missing) and returns the manifest,
/// which is also written as `dir/images.json`.
pub fn write_image_set(dir: &Path, img: &GeometryImages) -> Result<ImagesManifest, RasterError> {
    std::fs::create_dir_all(dir)?;
    let n = img.size;
    let mut images = vec![];
    let mut put = |name: &str,
                   shape: Vec<usize>,
                   desc: &str,
                   png: Option<RgbImage>,
                   write: &dyn Fn(&Path) -> std::io::Result<()>|
     -> Result<(), RasterError> {
        let npy = format!("{name}.npy");
        write(&dir.join(&npy))?;
        let png_name = match png {
            Some(p) => {
                let f = format!("{name}.png");
                save_png(&dir.join(&f), &p)?;
                Some(f)
            }
            None => None,
        };
        images.push(ImageEntry {
            name: name.into(),
            npy,
            png: png_name,
            shape,
            description: desc.into(),
        });
        Ok(())
    };
    let inside: Vec<u8> = (0..n * n).map(|k| img.raster.is_inside(k) as u8).collect();
    let outside: Vec<bool> = inside.iter().map(|&b| b == 0).collect();
    put(
        "mask",
        vec![n, n],
        "1 on the surface, 0 outside",
        Some(grid_image(n, n, |k| {
            if inside[k] == 1 { [255; 3] } else { [0; 3] }
        })),
        &|p| save_npy(p, &[n, n], &inside),
    )?;
    put(
        "triangle",
        vec![n, n],
        "triangle id per node, 4294967295 outside",
        None,
        &|p| save_npy(p, &[n, n], img.raster.triangle.as_slice()),
    )?;
    let bary: &[f32] = img.raster.bary.as_slice().as_flattened();
    put(
        "barycentric",
        vec![n, n, 3],
        "barycentric coordinates in that triangle",
        None,
        &|p| save_npy(p, &[n, n, 3], bary),
    )?;
    put(
        "position",
        vec![n, n, 3],
        "3D position (mesh units), NaN outside",
        Some(position_picture(&img.position)),
        &|p| save_npy(p, &[n, n, 3], img.position.as_flattened()),
    )?;
    put(
        "metric",
        vec![n, n, 3],
        "[g11, g12, g22] of g = DxᵀDx (ℓ² per domain unit²), NaN outside",
        Some(metric_picture(n, img.metric.as_slice())),
        &|p| save_npy(p, &[n, n, 3], img.metric.as_flattened()),
    )?;
    put(
        "metric_extended",
        vec![n, n, 3],
        "g harmonically extended to ω",
        Some(metric_picture(n, img.metric_extended.as_slice())),
        &|p| save_npy(p, &[n, n, 3], img.metric_extended.as_flattened()),
    )?;
    put(
        "mean_curvature",
        vec![n, n],
        "signed mean curvature H = (κ1+κ2)/2 in 1/ℓ, NaN outside",
        Some(diverging_picture(n, img.mean_curvature.as_slice())),
        &|p| save_npy(p, &[n, n], img.mean_curvature.as_slice()),
    )?;
    put(
        "mean_curvature_extended",
        vec![n, n],
        "h harmonically extended to ω",
        Some(diverging_picture(n, img.mean_curvature_extended.as_slice())),
        &|p| save_npy(p, &[n, n], img.mean_curvature_extended.as_slice()),
    )?;
    let distance = |d: &Grid<f64>| distance_picture(n, d.as_slice(), Some(&outside));
    put(
        "boundary_distance",
        vec![n, n],
        "signed distance to the domain boundary (domain units), negative inside",
        Some(distance(&img.boundary_distance)),
        &|p| save_npy(p, &[n, n], img.boundary_distance.as_slice()),
    )?;
    for (i, f) in img.features.iter().enumerate() {
        put(
            &format!("feature_{i}"),
            vec![n, n],
            &format!("distance on the surface to feature '{}' (ℓ)", f.name),
            Some(distance(&f.distance)),
            &|p| save_npy(p, &[n, n], f.distance.as_slice()),
        )?;
    }
    if let Some(d) = &img.feature_distance {
        put(
            "feature_distance",
            vec![n, n],
            "distance to the nearest feature (ℓ)",
            Some(distance(d)),
            &|p| save_npy(p, &[n, n], d.as_slice()),
        )?;
    }
    if let Some(t) = &img.texture {
        put(
            "texture",
            vec![n, n, 3],
            "texture colour (RGB), black outside",
            Some(grid_image(n, n, |k| t.as_slice()[k])),
            &|p| save_npy(p, &[n, n, 3], t.as_slice().as_flattened()),
        )?;
    }
    let mut pyramid = vec![];
    if let Some(pyr) = &img.pyramid {
        for (k, (lvl, sigma)) in pyr.mean_curvature.iter().enumerate() {
            let m = lvl.size();
            let mut entries = vec![];
            for (c, name) in GeometryPyramid::NAMES.iter().enumerate() {
                let data = pyr.scalar_level(k, c);
                let base = format!("pyramid_{:02}_{name}", lvl.level());
                let npy = format!("{base}.npy");
                save_npy(&dir.join(&npy), &[m, m], data.as_slice())?;
                let png = if *name == "h" {
                    let f = format!("{base}.png");
                    save_png(&dir.join(&f), &diverging_picture(m, data.as_slice()))?;
                    Some(f)
                } else {
                    None
                };
                entries.push(ImageEntry {
                    name: name.to_string(),
                    npy,
                    png,
                    shape: vec![m, m],
                    description: format!("{name} filtered with σ = {sigma}"),
                });
            }
            pyramid.push(PyramidEntry {
                level: lvl.level(),
                size: m,
                sigma,
                images: entries,
            });
        }
    }
    let manifest = ImagesManifest {
        format: "surfmap geometry images v1",
        size: n,
        transform: img.transform,
        scale: img.scale,
        length_unit: img.length_unit,
        images,
        features: img.features.iter().map(|f| f.name.clone()).collect(),
        pyramid,
    };
    let json = serde_json::to_vec_pretty(&manifest).map_err(std::io::Error::other)?;
    crate::fsutil::write_atomically(&dir.join("images.json"), |w| w.write_all(&json))?;
    Ok(manifest)
}

/// Positions as RGB, each coordinate scaled to its bounding box.
pub fn position_picture(pos: &Grid<[f64; 3]>) -> RgbImage {
    let n = pos.size();
    let pos = pos.as_slice();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in pos.iter().filter(|p| p[0].is_finite()) {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    grid_image(n, n, |k| {
        let p = pos[k];
        if !p[0].is_finite() {
            return OUTSIDE_GREY;
        }
        std::array::from_fn(|c| {
            (255.0 * (p[c] - lo[c]) / (hi[c] - lo[c]).max(1e-300)).round() as u8
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TriMesh;
    use crate::raster::testmesh;
    use crate::raster::{FeatureSource, GeometryImagesOptions};

    #[test]
    fn writes_npy_png_and_manifest() {
        let (x, uv, tris) = testmesh::sphere_cap(6, 2.0, 1.0);
        let mesh = TriMesh::new(x, tris);
        let options = GeometryImagesOptions {
            size: 17,
            ..Default::default()
        };
        let img = GeometryImages::compute(&mesh, &uv, FeatureSource::None, None, &options).unwrap();
        let dir = std::env::temp_dir().join(format!("surfmap-raster-out-{}", std::process::id()));
        let m = write_image_set(&dir, &img).unwrap();
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("images.json")).unwrap()).unwrap();
        assert_eq!(json["size"], 17);
        assert_eq!(m.pyramid.len(), 5);
        for e in &m.images {
            let bytes = std::fs::read(dir.join(&e.npy)).unwrap();
            let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
            let elem = if e.name == "mask" || e.name == "texture" {
                1
            } else if e.name == "triangle" || e.name == "barycentric" {
                4
            } else {
                8
            };
            assert_eq!(
                bytes.len() - 10 - hlen,
                e.shape.iter().product::<usize>() * elem,
                "{}",
                e.name
            );
            if let Some(p) = &e.png {
                let pic = image::open(dir.join(p)).unwrap();
                assert_eq!((pic.width(), pic.height()), (17, 17));
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
