//! Stage 1, **prepare**: the two meshes as given (and, when the caller repaired them,
//! the repaired ones with where each face came from) → `Prepared`: both surfaces
//! checked for an area, cut down to the part they share ([`overlap`]), B brought to A's
//! units ([`ScaleB`](super::ScaleB)), the guidance renumbered onto the meshes matched
//! and paired into feature files, and each surface flattened and turned into geometry
//! images (`surface`).

pub mod overlap;
pub(crate) mod surface;

use super::guidance::{Guidance, landmark_pairs, paired_features};
use super::options::{HoleFeatures, MatchOptions};
use super::{MatchError, MatchInput};
use crate::mesh::repair::FaceOrigins;
use crate::mesh::validate::{Defect, DefectKind, validate};
use crate::mesh::{Topology, TriMesh};
use crate::raster::FeatureFile;
use overlap::{OverlapCrops, crops_for_match, cut};
use surface::MatchSurface;

/// How the meshes matched relate to the meshes as given, when repairs or the crop
/// changed them.
pub(crate) struct Renumbering {
    /// For every vertex of A as given, its copy in the matched A (`None`: removed).
    pub copies_a: Vec<Option<u32>>,
    /// Where each face of the matched A and B came from in the meshes as given.
    pub origins_a: Option<FaceOrigins>,
    pub origins_b: Option<FaceOrigins>,
}

/// What the later stages work on.
pub(crate) struct Prepared<'m> {
    /// The meshes as given: the numbering of the guidance and of the outputs.
    pub given_a: &'m TriMesh,
    pub given_b: &'m TriMesh,
    /// Whether the caller repaired the meshes before the match.
    pub repaired: bool,
    /// The meshes matched: repaired and cut to their shared part (B in its own units).
    pub mesh_a: TriMesh,
    pub mesh_b: TriMesh,
    /// `None` when the meshes matched are the meshes as given.
    pub renumbering: Option<Renumbering>,
    /// The crop to the shared part, when one was made.
    pub crops: Option<OverlapCrops>,
    /// The landmarks' vertices of A as given (spared by the fold check on the given
    /// meshes when landmarks are pinned).
    pub landmarks_a: Vec<u32>,
    /// The paired features (curves, then landmarks as point features) on the meshes
    /// matched; `None` without guidance.
    pub features_a: Option<FeatureFile>,
    pub features_b: Option<FeatureFile>,
    /// The factor B was multiplied by for the match ([`super::ScaleB`]).
    pub scale_b: f64,
    /// A and B flattened and rasterized (B at `scale_b`).
    pub a: MatchSurface,
    pub b: MatchSurface,
}

impl Prepared<'_> {
    /// The landmark pairs `(vertex of A, vertex of B)` on the meshes matched.
    pub fn landmark_pairs(&self) -> Vec<(u32, u32)> {
        landmark_pairs(self.features_a.as_ref(), self.features_b.as_ref())
    }
}

/// Every vertex of `given` → its copy in `kept` (`origins`: where `kept`'s faces came
/// from; `None`: `kept` is `given`).
fn vertex_copies(
    given: &TriMesh,
    kept: &TriMesh,
    origins: &Option<FaceOrigins>,
) -> Vec<Option<u32>> {
    match origins {
        Some(o) => o.vertex_copies(given, kept),
        None => (0..given.num_vertices() as u32).map(Some).collect(),
    }
}

/// The stage (module docs).
pub(crate) fn prepare<'m>(
    a: MatchInput<'m>,
    b: MatchInput<'m>,
    guidance: &Guidance,
    options: &MatchOptions,
) -> Result<Prepared<'m>, MatchError> {
    let repaired = a.repaired.is_some() || b.repaired.is_some();
    let (mesh_a, origins_a) = a
        .repaired
        .map_or((a.given.clone(), None), |(m, o)| (m, Some(o)));
    let (mesh_b, origins_b) = b
        .repaired
        .map_or((b.given.clone(), None), |(m, o)| (m, Some(o)));
    // The crop to the part the surfaces share, sparing every vertex the guidance names
    // (in the repaired meshes' numbering). Not with hole features `On`: a cut could take
    // away holes the user pairs.
    let crops = if options.crop_overlap && options.hole_features != HoleFeatures::On {
        let (ids_a, ids_b) = guidance.vertices();
        let copies_a = vertex_copies(a.given, &mesh_a, &origins_a);
        let copies_b = vertex_copies(b.given, &mesh_b, &origins_b);
        let on_repaired = |ids: Vec<u32>, copies: &[Option<u32>]| -> Vec<u32> {
            ids.into_iter()
                .filter_map(|v| copies.get(v as usize).copied().flatten())
                .collect()
        };
        crops_for_match(
            &mesh_a,
            &mesh_b,
            &on_repaired(ids_a, &copies_a),
            &on_repaired(ids_b, &copies_b),
            options.scale_b,
        )
    } else {
        None
    };
    let (mesh_a, origins_a) = cut(mesh_a, origins_a, crops.as_ref().and_then(|c| c.a.as_ref()));
    let (mesh_b, origins_b) = cut(mesh_b, origins_b, crops.as_ref().and_then(|c| c.b.as_ref()));
    let renumbering = (origins_a.is_some() || origins_b.is_some()).then(|| Renumbering {
        copies_a: vertex_copies(a.given, &mesh_a, &origins_a),
        origins_a,
        origins_b,
    });
    let on_matched = match &renumbering {
        None => guidance.clone(),
        Some(r) => {
            let copies_b = vertex_copies(b.given, &mesh_b, &r.origins_b);
            guidance.renumbered(&r.copies_a, &copies_b)?
        }
    };
    let (area_a, area_b) = (
        measurable_area(&mesh_a, 'A')?,
        measurable_area(&mesh_b, 'B')?,
    );
    let scale_b = options.scale_b.factor(area_a, area_b);
    if !(scale_b.is_finite() && scale_b > 0.0) {
        return Err(MatchError::Input(format!(
            "B's scale factor must be finite and positive, got {scale_b}"
        )));
    }
    let scaled_b;
    let matched_b = if scale_b == 1.0 {
        &mesh_b
    } else {
        let mut m = mesh_b.clone();
        for p in &mut m.positions {
            *p = p.map(|c| c * scale_b);
        }
        scaled_b = m;
        &scaled_b
    };
    let (features_a, features_b) = paired_features(&mesh_a, matched_b, &on_matched)?;
    let unit = shared_length_unit(area_a, matched_b.area());
    if !(unit.is_finite() && unit > 0.0) {
        // Both areas were checked above: only B's scaling can get here.
        return Err(MatchError::Input(format!(
            "B scaled by {scale_b:e} has no finite area; give B a smaller scale"
        )));
    }
    let surface = |mesh: &TriMesh, features: &Option<FeatureFile>| {
        MatchSurface::new(
            mesh,
            features.as_ref(),
            options.size,
            options.fill_holes,
            unit,
        )
    };
    let (sa, sb) = rayon::join(
        || surface(&mesh_a, &features_a),
        || surface(matched_b, &features_b),
    );
    Ok(Prepared {
        given_a: a.given,
        given_b: b.given,
        repaired,
        a: sa.map_err(|e| e.of_surface('A'))?,
        b: sb.map_err(|e| e.of_surface('B'))?,
        mesh_a,
        mesh_b,
        renumbering,
        crops,
        landmarks_a: guidance
            .landmarks
            .as_ref()
            .map_or(vec![], |lm| lm.a.clone()),
        features_a,
        features_b,
        scale_b,
    })
}

/// The one length unit ℓ of both surfaces (mesh units): the geometric mean of their
/// `√area`, `ℓ = (area_A · area_B)^¼`, so that the energy's balance (NOTES §2: curvature
/// in `1/ℓ`, metric in `ℓ²`) does not depend on the units and the surfaces' relative size
/// is kept.
pub(crate) fn shared_length_unit(area_a: f64, area_b: f64) -> f64 {
    (area_a * area_b).sqrt().sqrt()
}

/// Refuses a surface whose area is zero or not finite (no faces, NaN coordinates, only
/// degenerate faces, coordinates so large that the area overflows) before anything is
/// computed: by the defects the flattening would name, with their remedies
/// ([`validate`]), else by its size. Returns the area.
fn measurable_area(mesh: &TriMesh, which: char) -> Result<f64, MatchError> {
    let area = mesh.area();
    if area.is_finite() && area > 0.0 {
        return Ok(area);
    }
    let defects: Vec<Defect> = validate(mesh, &Topology::new(mesh))
        .into_iter()
        .filter(|d| {
            matches!(
                d.kind,
                DefectKind::NonFiniteCoordinates
                    | DefectKind::NoFaces
                    | DefectKind::RepeatedIndexFaces
                    | DefectKind::ZeroAreaFaces
            )
        })
        .collect();
    if defects.is_empty() {
        let largest = mesh
            .positions
            .iter()
            .flatten()
            .fold(0.0f64, |m, c| m.max(c.abs()));
        return Err(MatchError::Input(format!(
            "surface {which}'s area is {area} (coordinates up to {largest:e} in size): it cannot \
             be measured in floating point; scale the surface to a smaller unit first"
        )));
    }
    Err(MatchError::Flatten {
        surface: Some(which),
        source: crate::param::flatten::FlattenError::NotADisc(defects),
    })
}
