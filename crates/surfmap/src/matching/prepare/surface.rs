//! One surface prepared for matching (thesis §3.2.1–§3.2.3): flattened with the
//! balanced preset (holes filled for the solve), placed in ω = `[0,1]²`, rasterized
//! into geometry images at the unit-area length scale, every image extended over all of
//! ω, and restricted to every level of the multiscale pyramid.

use super::super::MatchError;
use super::super::energy::{B_CHANNELS, FeatureSet, LevelA, LevelB, TriangleA, chi, eta, theta};
use crate::grid::{Grid, Pyramid, harmonic_extension};
use crate::mesh::TriMesh;
use crate::param::flatten::{Cut, FlattenOptions, flatten};
use crate::raster::{
    FeatureCurve, FeatureFile, FeatureSource, GeometryImages, GeometryImagesOptions, SurfaceScale,
};

/// Channels of the smoothed pyramid: mean curvature, metric, position (ℓ units).
const S_H: usize = 0;
const S_G: usize = 1;
const S_X: usize = 4;

/// A surface ready to be matched: its flattening, geometry images and pyramid.
#[derive(Clone, Debug)]
pub struct MatchSurface {
    /// UV per vertex of the input mesh (mesh units).
    pub uvs: Vec<[f64; 2]>,
    /// The input mesh's positions and triangles (holes stay open: the fill is for the
    /// solve only).
    pub positions: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Holes filled for the flattening.
    pub filled_holes: usize,
    /// Flattening iterations and time (seconds).
    pub flatten_iterations: usize,
    pub flatten_time: f64,
    pub images: GeometryImages,
    /// The features' vertex curves on this surface (with their names), in the order of
    /// the distance maps (feature `f` of A is paired with feature `f` of B).
    pub feature_curves: Vec<FeatureCurve>,
    /// The length unit ℓ (mesh units) of every quantity below: shared by both surfaces
    /// of a match, so that their sizes compare.
    pub length_unit: f64,
    /// Per level: `[h, g11, g12, g22, x, y, z]` filtered with σ_k (x in ℓ units), all
    /// extended harmonically over ω.
    smooth: Pyramid<[f64; 7]>,
    /// Finest feature distances (ℓ units; unreachable nodes far away).
    feature_distance: Vec<Grid<f64>>,
    /// The rims of the holes filled for the flattening ([`MatchSurface::hole_rims`]).
    hole_rims: Vec<Vec<u32>>,
    pub time_images: f64,
}

impl MatchSurface {
    /// Flattens `mesh` (filling holes for the solve when `fill_holes`) and computes its
    /// geometry images on a `size × size` grid, with the distance maps of `features`,
    /// in the length unit `length_unit` (mesh units): curvature in `1/ℓ`, metric in
    /// `ℓ²`, positions and distances in `ℓ`.
    pub fn new(
        mesh: &TriMesh,
        features: Option<&FeatureFile>,
        size: usize,
        fill_holes: bool,
        length_unit: f64,
    ) -> Result<Self, MatchError> {
        let clock = std::time::Instant::now();
        // Geometry images need one UV per vertex over a disc: never cut.
        let options = FlattenOptions::default()
            .with_fill_holes(fill_holes)
            .with_cut(Cut::Never);
        let flat = flatten(mesh, &options)?;
        let flatten_time = clock.elapsed().as_secs_f64();
        let clock = std::time::Instant::now();
        let source = match features {
            Some(f) => FeatureSource::Curves(f),
            None => FeatureSource::None,
        };
        let options = GeometryImagesOptions {
            size,
            pyramid: false,
            scale: SurfaceScale::Original,
            ..Default::default()
        };
        let images = GeometryImages::compute(mesh, &flat.uvs, source, None, &options)?;
        let inside = images.raster.inside_mask();
        let unit = length_unit;
        let mut position = images.position.map(|p| p.map(|c| c / unit));
        harmonic_extension(&inside, &mut [&mut position])?;
        let h = images.mean_curvature_extended.as_slice();
        let g = images.metric_extended.as_slice();
        let x = position.as_slice();
        let (hs, gs) = (unit, 1.0 / (unit * unit));
        let finest = Grid::from_fn(size, |i, j| {
            let k = i * size + j;
            [
                h[k] * hs,
                g[k][0] * gs,
                g[k][1] * gs,
                g[k][2] * gs,
                x[k][0],
                x[k][1],
                x[k][2],
            ]
        })?;
        let smooth = Pyramid::new(finest);
        let feature_curves = features.map_or(vec![], |f| f.features.clone());
        let feature_distance = images
            .features
            .iter()
            .map(|f| {
                f.distance
                    .map(|&d| if d.is_finite() { d / unit } else { 1e3 })
            })
            .collect();
        Ok(Self {
            hole_rims: hole_rims(mesh),
            uvs: flat.uvs,
            positions: mesh.positions.clone(),
            triangles: mesh.triangles.clone(),
            filled_holes: flat.holes_filled,
            flatten_iterations: flat.iterations,
            flatten_time,
            images,
            feature_curves,
            length_unit,
            smooth,
            feature_distance,
            time_images: clock.elapsed().as_secs_f64(),
        })
    }

    /// Adds the distance maps of more named vertex curves (e.g. hole rims paired with
    /// the other surface's after the alignment).
    pub fn add_curve_features(&mut self, file: &FeatureFile) -> Result<(), MatchError> {
        let mesh = TriMesh::new(self.positions.clone(), self.triangles.clone());
        let unit = self.length_unit;
        for f in self.images.curve_distances(&mesh, &self.uvs, file)? {
            self.feature_distance.push(
                f.distance
                    .map(|&d| if d.is_finite() { d / unit } else { 1e3 }),
            );
        }
        self.feature_curves.extend(file.features.iter().cloned());
        Ok(())
    }

    /// Keeps the first `n` features (drops those added after them).
    pub(crate) fn keep_features(&mut self, n: usize) {
        self.feature_curves.truncate(n);
        self.feature_distance.truncate(n);
    }

    /// The distance map (finest grid, ℓ units) of feature `f` ([`Self::feature_curves`]).
    pub(crate) fn feature_distance(&self, f: usize) -> &Grid<f64> {
        &self.feature_distance[f]
    }

    /// The rims of the holes filled for the flattening: every boundary loop but the
    /// longest, as closed vertex curves (found from `triangles` when the surface was
    /// made).
    pub fn hole_rims(&self) -> &[Vec<u32>] {
        &self.hole_rims
    }

    /// Finest grid size.
    pub fn size(&self) -> usize {
        self.images.size
    }

    /// Number of levels (`K + 1`).
    pub fn num_levels(&self) -> usize {
        self.smooth.num_levels()
    }

    /// Grid size of level `k`.
    pub fn level_size(&self, k: usize) -> usize {
        self.smooth.level(k).size()
    }

    /// `img` (finest grid) at the nodes of level `k` (injection).
    fn inject(&self, img: &Grid<f64>, k: usize) -> Vec<f64> {
        let n = self.size();
        let m = self.level_size(k);
        let stride = (n - 1) / (m - 1);
        let data = img.as_slice();
        (0..m * m)
            .map(|q| data[(q / m) * stride * n + (q % m) * stride])
            .collect()
    }

    /// Trapezoidal-rule weight of node `q` of an `m × m` grid over ω.
    fn node_weight(m: usize, q: usize) -> f64 {
        let h = 1.0 / (m - 1) as f64;
        let edge = |t: usize| if t == 0 || t == m - 1 { 0.5 } else { 1.0 };
        h * h * edge(q / m) * edge(q % m)
    }

    /// A's data at level `k` with cut-off width `eps`; `features` selects and orders
    /// the distance maps (indices into [`Self::feature_curves`]).
    pub(crate) fn level_a(&self, k: usize, eps: f64, features: &[usize]) -> LevelA {
        let s = self.smooth.level(k).as_slice();
        let m = self.level_size(k);
        let sd = self.inject(&self.images.boundary_distance, k);
        let metric = |q: usize| [s[q][S_G], s[q][S_G + 1], s[q][S_G + 2]];
        let sqrt_det = |v: [f64; 3]| (v[0] * v[2] - v[1] * v[1]).max(0.0).sqrt();
        let dist: Vec<Vec<f64>> = features
            .iter()
            .map(|&f| self.inject(&self.feature_distance[f], k))
            .collect();
        let hh = 1.0 / (m - 1) as f64;
        let area = 0.5 * hh * hh;
        let mut triangles = Vec::with_capacity(2 * (m - 1) * (m - 1));
        let mut feature_theta = vec![Vec::with_capacity(2 * (m - 1) * (m - 1)); dist.len()];
        for i in 0..m - 1 {
            for j in 0..m - 1 {
                for tri in super::super::deformation::cell_triangles(m, i, j) {
                    let gt: [f64; 3] = std::array::from_fn(|c| {
                        tri.iter().map(|&q| metric(q)[c]).sum::<f64>() / 3.0
                    });
                    let det = gt[0] * gt[2] - gt[1] * gt[1];
                    let sd_c = tri.iter().map(|&q| sd[q]).sum::<f64>() / 3.0;
                    triangles.push(TriangleA {
                        g_inv: [gt[2] / det, -gt[1] / det, gt[0] / det],
                        weight: area * det.max(0.0).sqrt(),
                        area,
                        chi: chi(sd_c, eps).0,
                    });
                    for (f, d) in dist.iter().enumerate() {
                        let dc = tri.iter().map(|&q| d[q]).sum::<f64>() / 3.0;
                        feature_theta[f].push(theta(dc, eps).0);
                    }
                }
            }
        }
        let feature_eta: Vec<Vec<f64>> = dist
            .iter()
            .map(|d| d.iter().map(|&v| eta(v, eps).0).collect())
            .collect();
        LevelA {
            size: m,
            h: s.iter().map(|v| v[S_H]).collect(),
            weight: (0..m * m)
                .map(|q| Self::node_weight(m, q) * sqrt_det(metric(q)))
                .collect(),
            chi: sd.iter().map(|&d| chi(d, eps).0).collect(),
            x: s.iter().map(|v| [v[S_X], v[S_X + 1], v[S_X + 2]]).collect(),
            eta_set: FeatureSet::nonzero(&feature_eta, m * m),
            feature_eta,
            triangles,
            feature_theta,
        }
    }

    /// B's data at level `k`: the metric outside ω_B is scaled by
    /// `soft + (1 − soft)·χ_B^ε` (a "softer" material, thesis §2.2.5).
    pub(crate) fn level_b(&self, k: usize, eps: f64, soft: f64, features: &[usize]) -> LevelB {
        let s = self.smooth.level(k).as_slice();
        let m = self.level_size(k);
        let sd = self.inject(&self.images.boundary_distance, k);
        let data: Vec<[f64; B_CHANNELS]> = (0..m * m)
            .map(|q| {
                let f = soft + (1.0 - soft) * chi(sd[q], eps).0;
                let v = s[q];
                [
                    v[S_H],
                    sd[q],
                    f * v[S_G],
                    f * v[S_G + 1],
                    f * v[S_G + 2],
                    v[S_X],
                    v[S_X + 1],
                    v[S_X + 2],
                ]
            })
            .collect();
        LevelB::new(
            Grid::from_vec(m, data).expect("level size"),
            features
                .iter()
                .map(|&f| {
                    Grid::from_vec(m, self.inject(&self.feature_distance[f], k))
                        .expect("level size")
                })
                .collect(),
            3.0 * eps,
        )
    }

    /// Finest-level position (mesh units, extended) and signed boundary distance, for
    /// reading off matched points.
    /// Centroid and area (in ω) of the surface's inside nodes.
    pub fn domain_centroid_and_area(&self) -> ([f64; 2], f64) {
        let n = self.size();
        let h = 1.0 / (n - 1) as f64;
        let (mut c, mut count) = ([0.0; 2], 0usize);
        for q in 0..n * n {
            if self.images.raster.is_inside(q) {
                let p = super::super::deformation::node(n, q);
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

/// The rims of the holes that a flattening fills ([`crate::mesh::repair::hole_loops`]),
/// as closed vertex curves.
fn hole_rims(mesh: &TriMesh) -> Vec<Vec<u32>> {
    let topo = crate::mesh::Topology::new(mesh);
    crate::mesh::repair::hole_loops(&topo)
        .into_iter()
        .map(<[u32]>::to_vec)
        .collect()
}
