//! The full set of geometry images of one flattened surface (thesis §3.2.1–§3.2.4).
//!
//! Units. Positions keep the mesh's units, so every node maps back to the surface. All
//! other quantities use the length unit `ℓ` ([`GeometryImages::length_unit`]): with
//! [`SurfaceScale::UnitArea`] (the default) `ℓ = √(surface area)`, so two surfaces of
//! different size are compared at the same scale (mean curvature has units 1/length, so
//! the weights of the matching energy (2.9) only balance at a common scale); with
//! [`SurfaceScale::Original`], `ℓ` = 1 mesh unit. Mean curvature `h` is in `1/ℓ`, the
//! metric `g` in `ℓ²` per domain unit², feature distances in `ℓ`; the boundary distance
//! is in domain units of ω (it feeds `χ^ε` of (2.14), defined on ω).

use rayon::prelude::*;

use super::RasterError;
use super::boundary::boundary_edges;
use super::boundary_distance::signed_boundary_distance;
use super::curvature::vertex_mean_curvature;
use super::features::{FeatureFile, FeatureSource, colour_name};
use super::metric::triangle_metrics;
use super::rasterize::{OUTSIDE, Rasterization};
use crate::grid::{
    DomainTransform, Grid, HarmonicExtension, MetricPyramid, Pyramid, grid_level, seed_polyline,
    seed_region_boundary, solve_eikonal,
};
use crate::mesh::{TriMesh, Uvs};

/// Which length unit the images use (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceScale {
    /// `ℓ = √(surface area)`.
    #[default]
    UnitArea,
    /// `ℓ` = one mesh unit.
    Original,
}

/// Options for [`GeometryImages::compute`].
#[derive(Clone, Debug, PartialEq)]
pub struct GeometryImagesOptions {
    /// Grid nodes per side, `2^k + 1`.
    pub size: usize,
    /// Free border around the flattening, in domain units (room for the extension).
    pub margin: f64,
    pub scale: SurfaceScale,
    /// Build the Gaussian pyramid of `h` and `g`.
    pub pyramid: bool,
}

impl Default for GeometryImagesOptions {
    fn default() -> Self {
        Self {
            size: 257,
            margin: 1.0 / 32.0,
            scale: SurfaceScale::UnitArea,
            pyramid: true,
        }
    }
}

/// An RGB texture; row 0 is the top of the image (texture `v = 1`).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<[u8; 3]>,
}

impl TextureImage {
    /// Reads a PNG (any colour type; alpha ignored).
    pub fn read(path: &std::path::Path) -> Result<Self, RasterError> {
        let img = image::open(path)
            .map_err(|e| RasterError::Texture(format!("cannot read {}: {e}", path.display())))?
            .to_rgb8();
        Ok(Self {
            width: img.width(),
            height: img.height(),
            rgb: img.pixels().map(|p| p.0).collect(),
        })
    }

    /// Bilinear lookup at texture coordinates `(u, v)`, `v` up, clamped to the edge.
    pub fn sample(&self, uv: [f64; 2]) -> [u8; 3] {
        self.sample_linear(uv).map(|c| c.round() as u8)
    }

    /// [`Self::sample`] before rounding: channels in `[0, 255]` as `f64`.
    #[inline]
    pub fn sample_linear(&self, uv: [f64; 2]) -> [f64; 3] {
        let (w, h) = (self.width as usize, self.height as usize);
        let x = (uv[0] * w as f64 - 0.5).clamp(0.0, (w - 1) as f64);
        let y = ((1.0 - uv[1]) * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let p = |x: usize, y: usize| self.rgb[y * w + x];
        std::array::from_fn(|c| {
            let top = p(x0, y0)[c] as f64 * (1.0 - fx) + p(x1, y0)[c] as f64 * fx;
            let bot = p(x0, y1)[c] as f64 * (1.0 - fx) + p(x1, y1)[c] as f64 * fx;
            top * (1.0 - fy) + bot * fy
        })
    }
}

/// The distance map of one named feature.
#[derive(Clone, Debug, PartialEq)]
pub struct FeatureDistance {
    pub name: String,
    /// Distance on the surface in the metric `g` (units `ℓ`); continued outside the
    /// domain with the extended metric; `∞` where unreachable.
    pub distance: Grid<f64>,
}

/// The scale pyramids (thesis §3.2.4) of the extended mean curvature and metric.
#[derive(Clone, Debug, PartialEq)]
pub struct GeometryPyramid {
    /// `h` extended to all of ω, level `k` filtered with `σ_k = 2^−k`.
    pub mean_curvature: Pyramid<f64>,
    /// `[g11, g12, g22]` extended to all of ω, filtered component-wise (SPD on every level).
    pub metric: MetricPyramid,
}

impl GeometryPyramid {
    /// The scalar images of every level, as written to files: `h`, then the metric's components.
    pub const NAMES: [&'static str; 4] = ["h", "g11", "g12", "g22"];

    /// Builds both pyramids (concurrently).
    pub fn new(mean_curvature: Grid<f64>, metric: Grid<[f64; 3]>) -> Self {
        let (mean_curvature, metric) =
            rayon::join(|| Pyramid::new(mean_curvature), || Pyramid::new(metric));
        Self {
            mean_curvature,
            metric,
        }
    }

    /// Level `k` of the image named `NAMES[image]` (`h`, `g11`, `g12`, `g22`).
    pub fn scalar_level(&self, k: usize, image: usize) -> Grid<f64> {
        match image {
            0 => self.mean_curvature.level(k).clone(),
            c => self.metric.level(k).component(c - 1),
        }
    }
}

/// All images of one surface on an `N × N` grid ([`Grid`]: node `(i, j)` at
/// `ξ = (j, i)/(N − 1)`, `N` = [`size`](Self::size)). Values outside the surface are
/// `NaN` unless stated.
#[derive(Clone, Debug)]
pub struct GeometryImages {
    pub size: usize,
    pub transform: DomainTransform,
    pub scale: SurfaceScale,
    /// `ℓ` in mesh units.
    pub length_unit: f64,
    pub raster: Rasterization,
    /// 3D position (mesh units).
    pub position: Grid<[f64; 3]>,
    /// `[g11, g12, g22]` of `g = DxᵀDx` (constant per triangle).
    pub metric: Grid<[f64; 3]>,
    /// Signed mean curvature `h` (interpolated from vertices).
    pub mean_curvature: Grid<f64>,
    /// `g` harmonically extended to all of ω (SPD everywhere).
    pub metric_extended: Grid<[f64; 3]>,
    /// `h` harmonically extended to all of ω.
    pub mean_curvature_extended: Grid<f64>,
    /// Signed distance to ∂ω_A in domain units, negative inside.
    pub boundary_distance: Grid<f64>,
    pub features: Vec<FeatureDistance>,
    /// Distance to the nearest feature (thesis §3.2.2), when there are features.
    pub feature_distance: Option<Grid<f64>>,
    /// Texture colour (black outside), when a texture was given.
    pub texture: Option<Grid<[u8; 3]>>,
    /// Pyramids of the extended `h` and `g`, when requested.
    pub pyramid: Option<GeometryPyramid>,
    /// Wall-clock seconds per stage, in order; entries named "  of which …" break down the
    /// stage before them (its parts ran concurrently, so they do not add up).
    pub timings: Vec<(&'static str, f64)>,
}

impl GeometryImages {
    /// Computes every image of `mesh` flattened to `uvs` (one per vertex, flip-free).
    /// `texture` and mask features are looked up through the mesh's own texture
    /// coordinates `mesh.uvs`.
    pub fn compute(
        mesh: &TriMesh,
        uvs: &[[f64; 2]],
        features: FeatureSource<'_>,
        texture_image: Option<&TextureImage>,
        options: &GeometryImagesOptions,
    ) -> Result<Self, RasterError> {
        let n = options.size;
        grid_level(n)?;
        let mut timings = vec![];
        let mut clock = std::time::Instant::now();
        let mut lap = |name: &'static str, timings: &mut Vec<(&'static str, f64)>| {
            timings.push((name, clock.elapsed().as_secs_f64()));
            clock = std::time::Instant::now();
        };
        if uvs.len() != mesh.num_vertices() {
            return Err(RasterError::UvCount {
                count: uvs.len(),
                num_vertices: mesh.num_vertices(),
            });
        }
        let transform = DomainTransform::fit(uvs, options.margin)?;
        let xi: Vec<[f64; 2]> = uvs.iter().map(|&p| transform.to_domain(p)).collect();
        let raster = Rasterization::new(&xi, &mesh.triangles, n)?;
        lap("rasterize", &mut timings);
        let inside = raster.inside_mask();
        let inside_flags = inside.as_slice();
        if !inside_flags.iter().any(|&b| b) {
            return Err(RasterError::EmptyDomain);
        }
        let length_unit = match options.scale {
            SurfaceScale::Original => 1.0,
            SurfaceScale::UnitArea => mesh.area().sqrt(),
        };
        if !(length_unit.is_finite() && length_unit > 0.0) {
            return Err(RasterError::DegenerateDomain);
        }
        let scaled: Vec<[f64; 3]> = mesh
            .positions
            .iter()
            .map(|p| p.map(|c| c / length_unit))
            .collect();

        let position = raster.sample_vertex_field(&mesh.triangles, &mesh.positions);
        let metric = raster.sample_triangle_field(&triangle_metrics(&scaled, &xi, &mesh.triangles));
        let h_vertex: Vec<[f64; 1]> = vertex_mean_curvature(&scaled, &mesh.triangles)
            .into_iter()
            .map(|h| [h])
            .collect();
        let mean_curvature = raster
            .sample_vertex_field(&mesh.triangles, &h_vertex)
            .map(|v| v[0]);
        lap("sample position, metric, curvature", &mut timings);

        let segments: Vec<[[f64; 2]; 2]> = boundary_edges(&mesh.triangles)
            .iter()
            .map(|e| [xi[e[0] as usize], xi[e[1] as usize]])
            .collect();
        let boundary_distance = signed_boundary_distance(&raster, &segments);
        lap("boundary distance", &mut timings);

        // Texture coordinates of every inside node (for texture and mask lookups).
        let needs_tex = texture_image.is_some() || matches!(features, FeatureSource::Mask(_));
        let tex_uv = if needs_tex {
            Some(node_texture_coordinates(mesh, &raster)?)
        } else {
            None
        };
        let texture = texture_image.map(|t| {
            let tex_uv = tex_uv.as_ref().unwrap();
            let colours = (0..n * n)
                .into_par_iter()
                .map(|k| {
                    if inside_flags[k] {
                        t.sample(tex_uv[k])
                    } else {
                        [0, 0, 0]
                    }
                })
                .collect();
            Grid::from_parts(n, colours)
        });
        lap("texture", &mut timings);

        // Feature seeds (validated first, so bad input fails before any solve).
        let seeds = feature_seeds(
            mesh,
            &xi,
            &raster,
            &metric,
            &inside,
            features,
            texture_image,
            tex_uv.as_deref(),
        )?;

        // Two independent jobs run concurrently: the harmonic extension of h and g (one
        // Cholesky factorization, four right-hand sides: h and g's three components) and
        // the Eikonal solves on the surface, which read g only on the inside nodes, where
        // it needs no extension.
        let mut mean_curvature_extended = mean_curvature.clone();
        let mut metric_extended = metric.clone();
        let (extension, inside_solves) = rayon::join(
            || {
                let t = std::time::Instant::now();
                let ext = HarmonicExtension::new(&inside)?;
                let (h, g) = rayon::join(
                    || ext.apply(&mut [&mut mean_curvature_extended]),
                    || ext.apply(&mut [&mut metric_extended]),
                );
                h.and(g).map(|()| t.elapsed().as_secs_f64())
            },
            || {
                let t = std::time::Instant::now();
                seeds
                    .into_par_iter()
                    .map(|(name, mut d)| {
                        solve_eikonal(&metric, &inside, &mut d)?;
                        Ok((name, d))
                    })
                    .collect::<Result<Vec<_>, RasterError>>()
                    .map(|v| (v, t.elapsed().as_secs_f64()))
            },
        );
        let extension_time = extension?;
        let (on_surface, inside_time) = inside_solves?;
        lap(
            "harmonic extension ‖ feature distances on the surface",
            &mut timings,
        );
        timings.push(("  of which harmonic extension", extension_time));
        timings.push(("  of which feature distances on the surface", inside_time));

        // Continue the distances outside the surface with the extended metric.
        let outside = inside.map(|&b| !b);
        let features_out: Vec<FeatureDistance> = on_surface
            .into_par_iter()
            .map(|(name, mut d)| {
                solve_eikonal(&metric_extended, &outside, &mut d)?;
                Ok(FeatureDistance { name, distance: d })
            })
            .collect::<Result<_, RasterError>>()?;
        let feature_distance = (!features_out.is_empty()).then(|| {
            let nearest = (0..n * n)
                .into_par_iter()
                .map(|k| {
                    features_out
                        .iter()
                        .map(|f| f.distance.as_slice()[k])
                        .fold(f64::INFINITY, f64::min)
                })
                .collect();
            Grid::from_parts(n, nearest)
        });
        lap("feature distances outside", &mut timings);
        let pyramid = options.pyramid.then(|| {
            GeometryPyramid::new(mean_curvature_extended.clone(), metric_extended.clone())
        });
        lap("pyramid", &mut timings);
        Ok(Self {
            size: n,
            transform,
            scale: options.scale,
            length_unit,
            raster,
            position,
            metric,
            mean_curvature,
            metric_extended,
            mean_curvature_extended,
            boundary_distance,
            features: features_out,
            feature_distance,
            texture,
            pyramid,
            timings,
        })
    }
}

impl GeometryImages {
    /// Distance maps (in the metric `g`, continued outside the surface with the extended
    /// metric, as [`Self::features`]) of further named vertex curves of `mesh`, whose
    /// flattening `uvs` these images were computed from: lets a caller add features
    /// found after the images (e.g. hole rims paired across two surfaces).
    pub fn curve_distances(
        &self,
        mesh: &TriMesh,
        uvs: &[[f64; 2]],
        file: &FeatureFile,
    ) -> Result<Vec<FeatureDistance>, RasterError> {
        file.validate(mesh.num_vertices())?;
        if uvs.len() != mesh.num_vertices() {
            return Err(RasterError::UvCount {
                count: uvs.len(),
                num_vertices: mesh.num_vertices(),
            });
        }
        let n = self.size;
        let inside = self.raster.inside_mask();
        let outside = inside.map(|&b| !b);
        file.features
            .par_iter()
            .map(|f| {
                let pts: Vec<[f64; 2]> = f
                    .vertices
                    .iter()
                    .map(|&v| self.transform.to_domain(uvs[v as usize]))
                    .collect();
                let mut d = Grid::new(n, f64::INFINITY)?;
                seed_polyline(&self.metric, &inside, &pts, f.closed, &mut d)?;
                solve_eikonal(&self.metric, &inside, &mut d)?;
                solve_eikonal(&self.metric_extended, &outside, &mut d)?;
                Ok(FeatureDistance {
                    name: f.name.clone(),
                    distance: d,
                })
            })
            .collect()
    }
}

/// Initial values of every feature's distance map (`0`-ish near the feature, `∞`
/// elsewhere), on the inside nodes, with the feature's name; validates the features.
#[allow(clippy::too_many_arguments)]
fn feature_seeds(
    mesh: &TriMesh,
    xi: &[[f64; 2]],
    raster: &Rasterization,
    metric: &Grid<[f64; 3]>,
    inside: &Grid<bool>,
    features: FeatureSource<'_>,
    texture_image: Option<&TextureImage>,
    tex_uv: Option<&[[f64; 2]]>,
) -> Result<Vec<(String, Grid<f64>)>, RasterError> {
    let n = raster.size();
    let mut seeds: Vec<(String, Grid<f64>)> = vec![];
    match features {
        FeatureSource::None => {}
        FeatureSource::Curves(file) => {
            file.validate(mesh.num_vertices())?;
            for f in &file.features {
                let pts: Vec<[f64; 2]> = f.vertices.iter().map(|&v| xi[v as usize]).collect();
                let mut d = Grid::new(n, f64::INFINITY)?;
                seed_polyline(metric, inside, &pts, f.closed, &mut d)?;
                seeds.push((f.name.clone(), d));
            }
        }
        FeatureSource::Mask(mask) => {
            mask.validate(texture_image.map(|t| (t.width, t.height)))?;
            let tex_uv = tex_uv.ok_or(RasterError::NoTextureCoordinates)?;
            let labels = Grid::from_fn(n, |i, j| {
                let k = i * n + j;
                if inside[(i, j)] {
                    mask.lookup(tex_uv[k])
                } else {
                    [0, 0, 0]
                }
            })?;
            for c in mask.region_colours() {
                let region = labels.map(|&l| l == c);
                let mut d = Grid::new(n, f64::INFINITY)?;
                seed_region_boundary(metric, inside, &region, &mut d)?;
                seeds.push((colour_name(c), d));
            }
        }
    }
    if let Some((name, _)) = seeds.iter().find(|(_, d)| !d.iter().any(|v| v.is_finite())) {
        return Err(RasterError::Feature {
            name: name.clone(),
            problem: "it covers no grid node inside the surface; raise the grid size".into(),
        });
    }
    Ok(seeds)
}

/// Corner `k` of triangle `t` in the mesh's own texture coordinates.
fn node_texture_coordinates(
    mesh: &TriMesh,
    raster: &Rasterization,
) -> Result<Vec<[f64; 2]>, RasterError> {
    let corner = |t: usize, k: usize| -> Option<[f64; 2]> {
        match mesh.uvs.as_ref()? {
            Uvs::PerVertex(uv) => uv.get(mesh.triangles[t][k] as usize).copied(),
            Uvs::PerCorner { coords, indices } => {
                coords.get(*indices.get(t)?.get(k)? as usize).copied()
            }
        }
    };
    if mesh.uvs.is_none() {
        return Err(RasterError::NoTextureCoordinates);
    }
    // Validate once per triangle so the per-node loop cannot fail.
    for t in 0..mesh.num_triangles() {
        for k in 0..3 {
            if corner(t, k).is_none() {
                return Err(RasterError::NoTextureCoordinates);
            }
        }
    }
    Ok(raster
        .triangle
        .as_slice()
        .par_iter()
        .zip(raster.bary.as_slice().par_iter())
        .map(|(&t, b)| {
            if t == OUTSIDE {
                return [f64::NAN; 2];
            }
            let c = [0, 1, 2].map(|k| corner(t as usize, k).unwrap());
            std::array::from_fn(|d| {
                b[0] as f64 * c[0][d] + b[1] as f64 * c[1][d] + b[2] as f64 * c[2][d]
            })
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::features::{FeatureCurve, FeatureFile, FeatureMask};
    use crate::raster::testmesh;

    fn images(
        (x, uv, tris): testmesh::TestMesh,
        size: usize,
        features: FeatureSource<'_>,
    ) -> GeometryImages {
        let mesh = TriMesh::new(x, tris);
        let options = GeometryImagesOptions {
            size,
            margin: 0.05,
            scale: SurfaceScale::Original,
            pyramid: false,
        };
        GeometryImages::compute(&mesh, &uv, features, None, &options).unwrap()
    }

    /// Largest `f(node)` over the nodes `(i, j)` on the surface.
    fn max_inside_error(img: &GeometryImages, f: impl Fn((usize, usize)) -> f64) -> f64 {
        let n = img.size;
        (0..n * n)
            .filter(|&k| img.raster.is_inside(k))
            .map(|k| f((k / n, k % n)))
            .fold(0.0, f64::max)
    }

    #[test]
    fn rasterized_mean_curvature_matches_sphere_cylinder_plane() {
        let r = 2.0;
        let mut errs = vec![];
        for (m, size) in [(8, 65), (16, 129), (32, 257)] {
            let img = images(testmesh::sphere_cap(m, r, 1.0), size, FeatureSource::None);
            errs.push(max_inside_error(&img, |ij| {
                (img.mean_curvature[ij] - 1.0 / r).abs()
            }));
        }
        assert!(
            errs[1] < errs[0] && errs[2] < errs[1] && errs[2] < 2e-3,
            "sphere {errs:?}"
        );

        let img = images(testmesh::cylinder_patch(16, 1.5), 129, FeatureSource::None);
        let e = max_inside_error(&img, |ij| (img.mean_curvature[ij] - 1.0 / 3.0).abs());
        assert!(e < 1e-6, "cylinder {e}");

        let img = images(
            testmesh::grid(8, 1.0, |u, v| [u, v, 0.3 * u - 0.2 * v]),
            65,
            FeatureSource::None,
        );
        let e = max_inside_error(&img, |ij| img.mean_curvature[ij].abs());
        assert!(e < 1e-6, "plane {e}");
        // Outside the surface the raw images are NaN, the extended ones finite.
        assert!(!img.raster.is_inside(0) && img.mean_curvature[(0, 0)].is_nan());
        assert!(img.mean_curvature_extended.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn metric_of_the_orthographic_sphere_parameterization() {
        // uv = (u, v), z = √(R² − u² − v²): g_uv = I + (u, v)(u, v)ᵀ / z²; ξ = s·uv + o
        // scales it by 1/s².
        let r = 2.0;
        let mut errs = vec![];
        for m in [8, 16, 32] {
            let img = images(testmesh::sphere_cap(m, r, 1.0), 129, FeatureSource::None);
            let s2 = img.transform.scale.powi(2);
            errs.push(max_inside_error(&img, |ij| {
                let [u, v, z] = img.position[ij];
                let exact = [
                    (1.0 + u * u / (z * z)) / s2,
                    u * v / (z * z) / s2,
                    (1.0 + v * v / (z * z)) / s2,
                ];
                (0..3)
                    .map(|c| (img.metric[ij][c] - exact[c]).abs() * s2)
                    .fold(0.0, f64::max)
            }));
        }
        assert!(
            errs[1] < 0.65 * errs[0] && errs[2] < 0.65 * errs[1] && errs[2] < 0.08,
            "{errs:?}"
        );
        // The isometric cylinder parameterization has g = I / s²; the inscribed mesh's
        // chords shorten the curved direction by O(h²): the error drops fourfold per halving.
        let mut errs = vec![];
        for m in [8, 16] {
            let img = images(testmesh::cylinder_patch(m, 1.5), 65, FeatureSource::None);
            let s2 = img.transform.scale.powi(2);
            errs.push(max_inside_error(&img, |ij| {
                let g = img.metric[ij];
                (g[0] * s2 - 1.0)
                    .abs()
                    .max(g[1].abs() * s2)
                    .max((g[2] * s2 - 1.0).abs())
            }));
        }
        assert!(errs[1] < 0.3 * errs[0] && errs[1] < 1e-3, "{errs:?}");
    }

    #[test]
    fn feature_distance_is_geodesic_distance_on_a_sphere_cap() {
        // Point feature at the pole; geodesic distance R·acos(z/R).
        let r = 2.0;
        let mut errs = vec![];
        for (m, size) in [(8, 65), (16, 129), (32, 257)] {
            let pole = ((m / 2) * (m + 1) + m / 2) as u32;
            let file = FeatureFile {
                features: vec![FeatureCurve {
                    name: "pole".into(),
                    vertices: vec![pole],
                    closed: false,
                }],
            };
            let img = images(
                testmesh::sphere_cap(m, r, 1.0),
                size,
                FeatureSource::Curves(&file),
            );
            let d = &img.features[0].distance;
            assert_eq!(img.feature_distance.as_ref().unwrap(), d);
            errs.push(max_inside_error(&img, |ij| {
                let exact = r * (img.position[ij][2] / r).clamp(-1.0, 1.0).acos();
                (d[ij] - exact).abs() / r
            }));
            assert!(d.iter().all(|v| v.is_finite()));
        }
        assert!(
            errs[1] < 0.6 * errs[0] && errs[2] < 0.6 * errs[1] && errs[2] < 0.015,
            "{errs:?}"
        );
    }

    #[test]
    fn extension_is_continuous_across_the_boundary() {
        let mut jumps = vec![];
        for size in [65, 129, 257] {
            // A surface with varying mean curvature.
            let surface = testmesh::grid(16, 1.0, |u, v| {
                [u, v, 0.4 * (u * u - v * v) + 0.3 * u * u * u]
            });
            let img = images(surface, size, FeatureSource::None);
            let n = size;
            let mut jump = 0.0f64;
            for p in 0..n * n {
                if img.raster.is_inside(p) {
                    continue;
                }
                for q in [p.wrapping_sub(1), p + 1, p.wrapping_sub(n), p + n] {
                    if q < n * n && img.raster.is_inside(q) && (q % n).abs_diff(p % n) <= 1 {
                        let (ext, h) = (&img.mean_curvature_extended, &img.mean_curvature);
                        jump = jump.max((ext.as_slice()[p] - h.as_slice()[q]).abs());
                    }
                }
            }
            jumps.push(jump);
        }
        assert!(
            jumps[1] < 0.7 * jumps[0] && jumps[2] < 0.7 * jumps[1] && jumps[2] < 0.05,
            "{jumps:?}"
        );
    }

    #[test]
    fn mask_features_and_texture_use_the_mesh_texture_coordinates() {
        // Plane grid over [−1, 1]² with texture coordinates (u + 1)/2, (v + 1)/2.
        let (x, uv, tris) = testmesh::grid(8, 1.0, |u, v| [u, v, 0.0]);
        let mut mesh = TriMesh::new(x, tris);
        mesh.uvs = Some(Uvs::PerVertex(
            uv.iter()
                .map(|p| [(p[0] + 1.0) / 2.0, (p[1] + 1.0) / 2.0])
                .collect(),
        ));
        // Left half of the texture red.
        let (w, h) = (16u32, 16u32);
        let rgb: Vec<[u8; 3]> = (0..w * h)
            .map(|k| if k % w < 8 { [255, 0, 0] } else { [0, 0, 0] })
            .collect();
        let mask = FeatureMask {
            width: w,
            height: h,
            rgb: rgb.clone(),
        };
        let tex = TextureImage {
            width: w,
            height: h,
            rgb,
        };
        let options = GeometryImagesOptions {
            size: 65,
            margin: 0.05,
            scale: SurfaceScale::Original,
            pyramid: true,
        };
        let img =
            GeometryImages::compute(&mesh, &uv, FeatureSource::Mask(&mask), Some(&tex), &options)
                .unwrap();
        assert_eq!(img.features.len(), 1);
        assert_eq!(img.features[0].name, "#ff0000");
        // The feature is the line u = 0: distance |u| on the plane.
        let e = max_inside_error(&img, |ij| {
            (img.features[0].distance[ij] - img.position[ij][0].abs()).abs()
        });
        assert!(e < 0.04, "{e}");
        let t = img.texture.as_ref().unwrap();
        let k = 32 * 65 + 10; // u < 0
        assert!(img.raster.is_inside(k) && t.as_slice()[k] == [255, 0, 0]);
        let p = img.pyramid.as_ref().unwrap();
        assert_eq!(p.mean_curvature.num_levels(), 7);
        assert_eq!(p.metric.num_levels(), 7);
        assert_eq!(p.mean_curvature.finest(), &img.mean_curvature_extended);
        assert_eq!(p.metric.finest(), &img.metric_extended);
        assert_eq!(p.scalar_level(3, 2), p.metric.level(3).component(1));
        // Wrong mask size, no texture coordinates.
        let small = FeatureMask {
            width: 8,
            height: 16,
            rgb: vec![[255, 0, 0]; 128],
        };
        let err = GeometryImages::compute(
            &mesh,
            &uv,
            FeatureSource::Mask(&small),
            Some(&tex),
            &options,
        )
        .unwrap_err();
        assert!(matches!(err, RasterError::MaskSize { .. }), "{err}");
        mesh.uvs = None;
        let err = GeometryImages::compute(&mesh, &uv, FeatureSource::Mask(&mask), None, &options)
            .unwrap_err();
        assert!(matches!(err, RasterError::NoTextureCoordinates), "{err}");
    }

    #[test]
    fn unit_area_scale_normalizes_h() {
        let r = 2.0;
        let (x, uv, tris) = testmesh::sphere_cap(16, r, 1.0);
        let mesh = TriMesh::new(x, tris);
        let options = GeometryImagesOptions {
            size: 65,
            pyramid: false,
            ..Default::default()
        };
        let img = GeometryImages::compute(&mesh, &uv, FeatureSource::None, None, &options).unwrap();
        assert!((img.length_unit - mesh.area().sqrt()).abs() < 1e-12);
        let e = max_inside_error(&img, |ij| {
            (img.mean_curvature[ij] - img.length_unit / r).abs()
        });
        assert!(e < 0.01, "{e}");
        assert!(
            GeometryImages::compute(&mesh, &uv[1..], FeatureSource::None, None, &options).is_err()
        );
    }
}
