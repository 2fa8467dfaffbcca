//! Registration of a template onto scans (issue 49; thesis §6.2's correspondences over a
//! set of surfaces): every scan comes out in the template's topology and vertex order.
//!
//! For one scan, [`register_scan`] matches the template A onto the scan B
//! ([`crate::matching::match_meshes`]) and places every template vertex on the scan:
//!
//! - a **matched** vertex `i ∈ M` goes to its counterpart `p_i = φ_M(x_i)` on B;
//! - the template is first carried onto the scan as a whole by the similarity
//!   `S(x) = s·R·x + t` that minimizes `Σ_{i∈M} |S(x_i) − p_i|²` (Horn's closed form,
//!   [`crate::matching::similarity::fit_similarity_3d`]);
//! - an **unmatched** vertex `i ∈ U` (no counterpart: the scan is cropped tighter, has a
//!   hole there, or the fold check dropped it) gets `y_i = S(x_i) + r_i`, where the
//!   residual displacement `r_i = p_i − S(x_i)` known on `M` is extended harmonically
//!   over the template ([`super::morph::harmonic_extension`]):
//!
//! ```text
//! L_UU r_U = −L_UM r_M        (L: the template's cotangent Laplacian)
//! ```
//!
//! Removing the similarity first matters: the cotangent weights are invariant under
//! `S` (angles do not change), so the extension of `r` reproduces a scan that is a
//! moved and scaled copy of the template exactly (`r = 0`), and a rotated scan's
//! unmatched border is not bent towards the template's pose, as extending the raw
//! displacement `p_i − x_i` would do. Among fields that agree with `r_M`, `r_U` has the
//! least Dirichlet energy, so the registered surface joins the matched part without a
//! crease; at the template's own border it levels off (natural boundary condition).
//!
//! **What is prepared once.** [`Template::new`] checks the template as surface A of a
//! match and flattens and rasterizes it once ([`Template::one_off_seconds`]): a bad
//! template is one error before the batch instead of one per scan. The matcher itself
//! rebuilds A's geometry images for every pair, and cannot cheaply be given them: the
//! crop to the part both surfaces share, the length unit `ℓ = (area_A·area_B)^¼` the
//! images are scaled in, and the landmarks as point features all depend on the scan.
//! Sharing them would need `matching::prepare` to accept A's surface prepared for a unit
//! and without a crop (measured in docs/bench/register.md: the cost each scan repeats).
//!
//! Many scans: [`batch`] (one row per scan, files written atomically, resumable). Frames
//! of one moving face: [`sequence`] (each frame from the previous one's result, and the
//! jitter of the registered vertices).

pub mod batch;
pub mod model;
pub mod model_folder;
pub mod sequence;

use std::time::Instant;

use super::AppError;
use super::correspondence::check_correspondence;
use super::morph::harmonic_extension;
use crate::matching::prepare::surface::MatchSurface;
use crate::matching::similarity::{Similarity3, fit_similarity_3d};
use crate::matching::{Guidance, Match, MatchError, MatchOptions, match_meshes};
use crate::mesh::{SurfacePoint, TriMesh};
use crate::vec3::sub3;

/// The template of a registration: the mesh every scan is expressed in, checked once.
#[derive(Clone, Debug)]
pub struct Template {
    pub mesh: TriMesh,
    /// Seconds spent preparing it once ([`Template::new`]): flattening and rasterizing it
    /// as surface A of a match at the options' grid size — about what every scan's match
    /// spends on the template again.
    pub one_off_seconds: f64,
}

impl Template {
    /// Checks `mesh` as surface A of a match with `options`: it has an area, it can be
    /// flattened (holes filled as `options.fill_holes` says) and rasterized into geometry
    /// images on the options' grid. Errors name the defect, as a match would.
    pub fn new(mesh: TriMesh, options: &MatchOptions) -> Result<Self, RegisterError> {
        options.validate().map_err(MatchError::Option)?;
        let clock = Instant::now();
        let area = mesh.area();
        if mesh.triangles.is_empty() || !(area.is_finite() && area > 0.0) {
            return Err(RegisterError::Template(format!(
                "the template has no measurable area ({} triangles, area {area}); give a mesh with faces and finite coordinates",
                mesh.triangles.len()
            )));
        }
        MatchSurface::new(&mesh, None, options.size, options.fill_holes, area.sqrt())
            .map_err(|e| RegisterError::Match(e.of_surface('A')))?;
        Ok(Self {
            mesh,
            one_off_seconds: clock.elapsed().as_secs_f64(),
        })
    }
}

/// The template's vertices placed on a scan ([`place_on_scan`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    /// One position per template vertex (template order), in the scan's units and frame.
    pub positions: Vec<[f64; 3]>,
    /// Template vertices with a counterpart on the scan (placed on it).
    pub matched: usize,
    /// Template vertices without a counterpart, placed by the harmonic extension.
    pub extended: Vec<u32>,
    /// The similarity template → scan fitted on the matched vertices.
    pub similarity: Similarity3,
}

impl Placement {
    /// Matched template vertices over all template vertices.
    pub fn matched_fraction(&self) -> f64 {
        self.matched as f64 / self.positions.len().max(1) as f64
    }
}

/// A scan registered: the template's vertices placed on it, and the match behind them.
#[derive(Debug)]
pub struct Registered {
    pub placement: Placement,
    /// The match template → scan (its report holds the verdict).
    pub matched_with: Match,
}

impl Registered {
    /// The registered scan as a mesh: the template's triangles at the placed positions.
    pub fn mesh(&self, template: &Template) -> TriMesh {
        TriMesh::new(
            self.placement.positions.clone(),
            template.mesh.triangles.clone(),
        )
    }
}

/// Registers `template` onto `scan` (see the [module documentation](self)). The guidance
/// is numbered as the meshes are: landmarks' `A` ids are template vertices, `B` ids scan
/// vertices. With `options.strict` a match whose verdict is not `ok` is an error
/// ([`MatchError::NotTrusted`]); without, the verdict is in the match's report.
pub fn register_scan(
    template: &Template,
    scan: &TriMesh,
    guidance: &Guidance,
    options: &MatchOptions,
) -> Result<Registered, RegisterError> {
    let matched_with = match_meshes(&template.mesh, scan, guidance, options)?;
    let placement = place_on_scan(&template.mesh, scan, &matched_with.correspondence)?;
    Ok(Registered {
        placement,
        matched_with,
    })
}

/// The vertices of `template` placed on `scan` through the correspondence template →
/// scan (one entry per template vertex: a point of the scan, or `None`): matched ones on
/// their points, the others by the similarity and the harmonic extension of the residual
/// (module documentation).
pub fn place_on_scan(
    template: &TriMesh,
    scan: &TriMesh,
    correspondence: &[Option<SurfacePoint>],
) -> Result<Placement, RegisterError> {
    let x = &template.positions;
    check_correspondence(correspondence, x.len(), scan.triangles.len())?;
    crate::mesh::check_indices(&scan.triangles, scan.positions.len()).map_err(AppError::from)?;
    let points: Vec<Option<[f64; 3]>> = correspondence
        .iter()
        .map(|p| p.map(|p| p.position(&scan.positions, &scan.triangles)))
        .collect();
    let (from, to): (Vec<[f64; 3]>, Vec<[f64; 3]>) = points
        .iter()
        .zip(x)
        .filter_map(|(p, x)| p.map(|p| (*x, p)))
        .unzip();
    if from.is_empty() {
        return Err(RegisterError::Extend(AppError::NothingMatched));
    }
    // Fewer than three matched points (or all on a line) fix no rotation: translate.
    let similarity = fit_similarity_3d(&from, &to, &vec![1.0; from.len()], true)
        .filter(|s| s.scale().is_finite() && s.scale() > 0.0)
        .unwrap_or_else(|| {
            let n = from.len() as f64;
            let mut s = Similarity3::identity();
            for (p, q) in from.iter().zip(&to) {
                for c in 0..3 {
                    s.translation[c] += (q[c] - p[c]) / n;
                }
            }
            s
        });
    let moved: Vec<[f64; 3]> = x.iter().map(|&p| similarity.apply(p)).collect();
    let residual: Vec<Option<[f64; 3]>> = points
        .iter()
        .zip(&moved)
        .map(|(p, m)| p.map(|p| sub3(p, *m)))
        .collect();
    let extension = harmonic_extension(x, &template.triangles, &residual)?;
    let positions = moved
        .iter()
        .zip(&extension.values)
        .zip(&points)
        .map(|((m, r), p)| p.unwrap_or([m[0] + r[0], m[1] + r[1], m[2] + r[2]]))
        .collect();
    Ok(Placement {
        positions,
        matched: from.len(),
        extended: extension.extended,
        similarity,
    })
}

/// Why a scan (or the template) could not be registered.
#[derive(Debug, thiserror::Error)]
pub enum RegisterError {
    #[error("{0}")]
    Match(#[from] MatchError),
    #[error("cannot place the unmatched template vertices: {0}")]
    Extend(#[from] AppError),
    #[error("{0}")]
    Template(String),
}

#[cfg(test)]
mod tests;
