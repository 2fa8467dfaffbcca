//! One surface prepared for matching (thesis §3.2.1–§3.2.3): flattened with the
//! balanced preset (holes filled for the solve), placed in ω = [0,1]², rasterized into
//! geometry images at the unit-area length scale, every image extended over all of ω,
//! and restricted to every level of the multiscale pyramid.

use super::MatchError;
use super::energy::{B_CHANNELS, LevelA, LevelB, TriangleA, chi, eta, theta};
use super::field::Field;
use crate::mesh::TriMesh;
use crate::param::flatten::{FlattenOptions, flatten};
use crate::raster::extend::harmonic_extension;
use crate::raster::pyramid::Pyramid;
use crate::raster::{FeatureFile, FeatureSource, GeometryImages, GeometryImagesOptions};

/// A surface ready to be matched: its flattening, geometry images and pyramid.
#[derive(Clone, Debug)]
pub struct MatchSurface {
    /// UV per vertex of the input mesh (mesh units).
    pub uvs: Vec<[f64; 2]>,
    /// Holes filled for the flattening.
    pub filled_holes: usize,
    /// Flattening iterations and time (seconds).
    pub flatten_iterations: usize,
    pub flatten_time: f64,
    pub images: GeometryImages,
    /// Names of the features, in the order of the distance maps.
    pub feature_names: Vec<String>,
    /// Per level `k = 0..=K`: `[h, g11, g12, g22, x, y, z]` filtered with σ_k.
    smooth: Pyramid,
    /// Finest signed boundary distance and feature distances.
    boundary_distance: Vec<f64>,
    feature_distance: Vec<Vec<f64>>,
    pub time_images: f64,
}

impl MatchSurface {
    /// Flattens `mesh` (filling holes for the solve when `fill_holes`) and computes its
    /// geometry images on a `size × size` grid, with the distance maps of `features`.
    pub fn new(
        mesh: &TriMesh,
        features: Option<&FeatureFile>,
        size: usize,
        fill_holes: bool,
    ) -> Result<Self, MatchError> {
        let clock = std::time::Instant::now();
        let (solve_mesh, filled_holes) = if fill_holes {
            crate::mesh::repair::fill_holes(mesh)
        } else {
            (mesh.clone(), 0)
        };
        let flat = flatten(&solve_mesh, &FlattenOptions::default())?;
        let mut uvs = flat.uvs;
        uvs.truncate(mesh.num_vertices());
        let flatten_time = clock.elapsed().as_secs_f64();
        let clock = std::time::Instant::now();
        let source = match features {
            Some(f) => FeatureSource::Curves(f),
            None => FeatureSource::None,
        };
        let options = GeometryImagesOptions {
            size,
            pyramid: false,
            ..Default::default()
        };
        let images = GeometryImages::compute(mesh, &uvs, source, None, &options)?;
        let n = size;
        let inside = images.raster.inside_mask();
        let unit = images.length_unit;
        let mut x: [Vec<f64>; 3] = std::array::from_fn(|c| {
            images
                .position
                .iter()
                .map(|p| p[c] / unit)
                .collect::<Vec<f64>>()
        });
        {
            let [x0, x1, x2] = &mut x;
            harmonic_extension(n, &inside, &mut [x0, x1, x2])?;
        }
        let [x0, x1, x2] = x;
        let g = &images.metric_extended;
        let smooth = Pyramid::build(
            n,
            ["h", "g11", "g12", "g22", "x", "y", "z"]
                .map(String::from)
                .to_vec(),
            vec![
                images.mean_curvature_extended.clone(),
                g.iter().map(|v| v[0]).collect(),
                g.iter().map(|v| v[1]).collect(),
                g.iter().map(|v| v[2]).collect(),
                x0,
                x1,
                x2,
            ],
        );
        let feature_names = images.features.iter().map(|f| f.name.clone()).collect();
        // Unreachable nodes (∞) are far from the feature for every purpose here.
        let feature_distance = images
            .features
            .iter()
            .map(|f| {
                f.distance
                    .iter()
                    .map(|&d| if d.is_finite() { d } else { 1e3 })
                    .collect()
            })
            .collect();
        Ok(Self {
            uvs,
            filled_holes,
            flatten_iterations: flat.iterations,
            flatten_time,
            boundary_distance: images.boundary_distance.clone(),
            images,
            feature_names,
            smooth,
            feature_distance,
            time_images: clock.elapsed().as_secs_f64(),
        })
    }

    /// Finest grid size.
    pub fn size(&self) -> usize {
        self.images.size
    }

    /// Number of levels (`K + 1`).
    pub fn num_levels(&self) -> usize {
        self.smooth.levels.len()
    }

    /// Grid size of level `k`.
    pub fn level_size(&self, k: usize) -> usize {
        self.smooth.levels[k].size
    }

    /// `img` (finest grid) sampled at the nodes of level `k` (injection).
    fn inject(&self, img: &[f64], k: usize) -> Vec<f64> {
        let n = self.size();
        let m = self.level_size(k);
        let stride = (n - 1) / (m - 1);
        (0..m * m)
            .map(|q| img[(q / m) * stride * n + (q % m) * stride])
            .collect()
    }

    /// The smoothed images of level `k`: h, metric, position.
    fn smooth_level(&self, k: usize) -> (&[f64], [&[f64]; 3], [&[f64]; 3]) {
        let l = &self.smooth.levels[k].images;
        (&l[0], [&l[1], &l[2], &l[3]], [&l[4], &l[5], &l[6]])
    }

    /// Node area of the point on the `(i, j)` position of an `m × m` grid
    /// (trapezoidal rule on ω).
    fn node_weight(m: usize, k: usize) -> f64 {
        let h = 1.0 / (m - 1) as f64;
        let (i, j) = (k / m, k % m);
        let edge = |t: usize| if t == 0 || t == m - 1 { 0.5 } else { 1.0 };
        h * h * edge(i) * edge(j)
    }

    /// A's data at level `k` with cut-off width `eps`; `features` selects and orders
    /// the distance maps (indices into [`Self::feature_names`]).
    pub(crate) fn level_a(&self, k: usize, eps: f64, features: &[usize]) -> LevelA {
        let m = self.level_size(k);
        let (h, g, x) = self.smooth_level(k);
        let sd = self.inject(&self.boundary_distance, k);
        let gm = |q: usize| [g[0][q], g[1][q], g[2][q]];
        let sqrt_det = |v: [f64; 3]| (v[0] * v[2] - v[1] * v[1]).max(0.0).sqrt();
        let weight = (0..m * m)
            .map(|q| Self::node_weight(m, q) * sqrt_det(gm(q)))
            .collect();
        let chi_nodes: Vec<f64> = sd.iter().map(|&s| chi(s, eps).0).collect();
        let dist: Vec<Vec<f64>> = features
            .iter()
            .map(|&f| self.inject(&self.feature_distance[f], k))
            .collect();
        let feature_eta = dist
            .iter()
            .map(|d| d.iter().map(|&s| eta(s, eps).0).collect())
            .collect();
        let hh = 1.0 / (m - 1) as f64;
        let area = 0.5 * hh * hh;
        let mut triangles = Vec::with_capacity(2 * (m - 1) * (m - 1));
        let mut feature_theta = vec![Vec::with_capacity(2 * (m - 1) * (m - 1)); dist.len()];
        for i in 0..m - 1 {
            for j in 0..m - 1 {
                for tri in super::deformation::cell_triangles(m, i, j) {
                    let gt: [f64; 3] = std::array::from_fn(|c| {
                        (g[c][tri[0]] + g[c][tri[1]] + g[c][tri[2]]) / 3.0
                    });
                    let det = gt[0] * gt[2] - gt[1] * gt[1];
                    let g_inv = [gt[2] / det, -gt[1] / det, gt[0] / det];
                    let sd_c = (sd[tri[0]] + sd[tri[1]] + sd[tri[2]]) / 3.0;
                    triangles.push(TriangleA {
                        g_inv,
                        weight: area * det.max(0.0).sqrt(),
                        area,
                        chi: chi(sd_c, eps).0,
                    });
                    for (f, d) in dist.iter().enumerate() {
                        let dc = (d[tri[0]] + d[tri[1]] + d[tri[2]]) / 3.0;
                        feature_theta[f].push(theta(dc, eps).0);
                    }
                }
            }
        }
        LevelA {
            size: m,
            h: h.to_vec(),
            weight,
            chi: chi_nodes,
            x: (0..m * m).map(|q| [x[0][q], x[1][q], x[2][q]]).collect(),
            feature_eta,
            triangles,
            feature_theta,
        }
    }

    /// B's data at level `k`: the metric outside ω_B is scaled by
    /// `soft + (1 − soft)·χ_B^ε` (a "softer" material, thesis §2.2.5).
    pub(crate) fn level_b(&self, k: usize, eps: f64, soft: f64, features: &[usize]) -> LevelB {
        let m = self.level_size(k);
        let (h, g, x) = self.smooth_level(k);
        let sd = self.inject(&self.boundary_distance, k);
        let data: Vec<[f64; B_CHANNELS]> = (0..m * m)
            .map(|q| {
                let c = chi(sd[q], eps).0;
                let f = soft + (1.0 - soft) * c;
                [
                    h[q],
                    sd[q],
                    f * g[0][q],
                    f * g[1][q],
                    f * g[2][q],
                    x[0][q],
                    x[1][q],
                    x[2][q],
                ]
            })
            .collect();
        LevelB {
            field: Field::new(m, data),
            features: features
                .iter()
                .map(|&f| {
                    Field::new(
                        m,
                        self.inject(&self.feature_distance[f], k)
                            .into_iter()
                            .map(|d| [d])
                            .collect(),
                    )
                })
                .collect(),
        }
    }

    /// Finest-level position field (mesh units, extended) and signed boundary distance,
    /// for reading off matched points.
    pub(crate) fn finest_position_and_distance(&self) -> Field<4> {
        let top = self.smooth.levels.last().unwrap();
        let unit = self.images.length_unit;
        let n = self.size();
        Field::new(
            n,
            (0..n * n)
                .map(|q| {
                    [
                        top.images[4][q] * unit,
                        top.images[5][q] * unit,
                        top.images[6][q] * unit,
                        self.boundary_distance[q],
                    ]
                })
                .collect(),
        )
    }

    /// Area centroid and area (in ω) of the surface's inside nodes.
    pub fn domain_centroid_and_area(&self) -> ([f64; 2], f64) {
        let n = self.size();
        let h = 1.0 / (n - 1) as f64;
        let (mut c, mut count) = ([0.0; 2], 0usize);
        for q in 0..n * n {
            if self.images.raster.is_inside(q) {
                let p = super::deformation::node(n, q);
                c[0] += p[0];
                c[1] += p[1];
                count += 1;
            }
        }
        let count = count.max(1) as f64;
        ([c[0] / count, c[1] / count], count * h * h)
    }

    /// Domain position ξ of vertex `v`.
    pub fn vertex_domain_position(&self, v: usize) -> [f64; 2] {
        self.images.transform.to_domain(self.uvs[v])
    }
}
