//! What a user tells the matcher besides the two surfaces: landmarks (paired vertices)
//! and feature curves (paired by name), in the numbering of the meshes as given, and
//! their pairing into the feature files the energy's feature term reads (thesis §2.2.4).

use serde::Serialize;

use super::MatchError;
use crate::mesh::TriMesh;
use crate::raster::{FeatureCurve, FeatureFile};

/// Paired landmark points: `a[i]` on A corresponds to `b[i]` on B.
#[derive(Clone, Debug, PartialEq, serde::Deserialize, Serialize)]
pub struct Landmarks {
    pub names: Vec<String>,
    #[serde(rename = "A")]
    pub a: Vec<u32>,
    #[serde(rename = "B")]
    pub b: Vec<u32>,
}

impl Landmarks {
    /// The landmarks renumbered onto repaired meshes: `copies_a[v]` (`copies_b[v]`) is
    /// the repaired vertex of A (B) that stands for input vertex `v`
    /// ([`crate::mesh::repair::FaceOrigins::vertex_copies`]). An id beyond the input
    /// mesh, or whose vertex the repairs removed, is an error naming the landmark.
    pub fn renumbered(
        &self,
        copies_a: &[Option<u32>],
        copies_b: &[Option<u32>],
    ) -> Result<Self, MatchError> {
        let mut out = self.clone();
        for (side, ids, copies) in [("A", &mut out.a, copies_a), ("B", &mut out.b, copies_b)] {
            for (i, v) in ids.iter_mut().enumerate() {
                let name = self.names.get(i).map_or("?", |s| s.as_str());
                let Some(copy) = copies.get(*v as usize) else {
                    return Err(no_such_landmark_vertex(name, side, *v, copies.len()));
                };
                *v = copy.ok_or_else(|| {
                    MatchError::Guidance(format!(
                        "landmark '{name}': vertex {v} of {side} was removed by the repairs \
                         (every face around it went); pick a vertex of the part that is kept"
                    ))
                })?;
            }
        }
        Ok(out)
    }
}

/// A landmark whose vertex id is beyond its surface's `vertices`.
fn no_such_landmark_vertex(name: &str, side: &str, v: u32, vertices: usize) -> MatchError {
    MatchError::Guidance(format!(
        "landmark '{name}': vertex {v} of {side} does not exist ({side} has {vertices} vertices)"
    ))
}

/// Optional user guidance, paired by name between A and B.
#[derive(Clone, Debug, Default)]
pub struct Guidance {
    pub landmarks: Option<Landmarks>,
    pub features_a: Option<FeatureFile>,
    pub features_b: Option<FeatureFile>,
}

impl Guidance {
    /// Every vertex of A and of B the guidance names (feature curves' vertices, then
    /// landmarks), repeats included.
    pub fn vertices(&self) -> (Vec<u32>, Vec<u32>) {
        let curves = |f: &Option<FeatureFile>| -> Vec<u32> {
            f.iter()
                .flat_map(|f| f.features.iter().flat_map(|c| c.vertices.iter().copied()))
                .collect()
        };
        let (mut a, mut b) = (curves(&self.features_a), curves(&self.features_b));
        if let Some(lm) = &self.landmarks {
            a.extend(&lm.a);
            b.extend(&lm.b);
        }
        (a, b)
    }

    /// The guidance renumbered onto repaired or cut meshes (`copies_a[v]`: the vertex
    /// that stands for vertex `v` of A as given; [`Landmarks::renumbered`],
    /// [`FeatureFile::renumbered`]); an id beyond a mesh or whose vertex was removed is
    /// an error naming the landmark or feature.
    pub fn renumbered(
        &self,
        copies_a: &[Option<u32>],
        copies_b: &[Option<u32>],
    ) -> Result<Self, MatchError> {
        let features = |f: &Option<FeatureFile>, copies: &[Option<u32>], side: char| {
            f.as_ref()
                .map(|f| f.renumbered(copies))
                .transpose()
                .map_err(|e| MatchError::Guidance(format!("features of {side}: {e}")))
        };
        Ok(Self {
            landmarks: self
                .landmarks
                .as_ref()
                .map(|lm| lm.renumbered(copies_a, copies_b))
                .transpose()?,
            features_a: features(&self.features_a, copies_a, 'A')?,
            features_b: features(&self.features_b, copies_b, 'B')?,
        })
    }
}

/// Pairs the features of A and B by name (landmarks become point features named
/// `landmark:NAME`); returns both feature files and, for the alignment, the paired
/// domain positions (feature centroids).
pub(crate) fn paired_features(
    a: &TriMesh,
    b: &TriMesh,
    g: &Guidance,
) -> Result<(Option<FeatureFile>, Option<FeatureFile>), MatchError> {
    let mut fa: Vec<FeatureCurve> = g.features_a.as_ref().map_or(vec![], |f| f.features.clone());
    let mut fb: Vec<FeatureCurve> = g.features_b.as_ref().map_or(vec![], |f| f.features.clone());
    for f in &fa {
        if !fb.iter().any(|x| x.name == f.name) {
            return Err(MatchError::Guidance(format!(
                "feature '{}' is given on A but not on B; features are paired by name",
                f.name
            )));
        }
    }
    for f in &fb {
        if !fa.iter().any(|x| x.name == f.name) {
            return Err(MatchError::Guidance(format!(
                "feature '{}' is given on B but not on A; features are paired by name",
                f.name
            )));
        }
    }
    fb.sort_by_key(|f| fa.iter().position(|x| x.name == f.name));
    if let Some(lm) = &g.landmarks {
        if lm.a.len() != lm.b.len() || lm.a.len() != lm.names.len() {
            return Err(MatchError::Guidance(format!(
                "landmarks: {} names, {} ids on A, {} on B; give one id per name on each surface",
                lm.names.len(),
                lm.a.len(),
                lm.b.len()
            )));
        }
        for (i, name) in lm.names.iter().enumerate() {
            for (side, ids, mesh) in [("A", &lm.a, a), ("B", &lm.b, b)] {
                if ids[i] as usize >= mesh.num_vertices() {
                    return Err(no_such_landmark_vertex(
                        name,
                        side,
                        ids[i],
                        mesh.num_vertices(),
                    ));
                }
            }
            fa.push(FeatureCurve {
                name: format!("landmark:{name}"),
                vertices: vec![lm.a[i]],
                closed: false,
            });
            fb.push(FeatureCurve {
                name: format!("landmark:{name}"),
                vertices: vec![lm.b[i]],
                closed: false,
            });
        }
    }
    if fa.is_empty() {
        return Ok((None, None));
    }
    Ok((
        Some(FeatureFile { features: fa }),
        Some(FeatureFile { features: fb }),
    ))
}

/// The landmark pairs among the paired features (point features named `landmark:NAME`,
/// [`paired_features`]): `(vertex of A, vertex of B)`.
pub(crate) fn landmark_pairs(
    fa: Option<&FeatureFile>,
    fb: Option<&FeatureFile>,
) -> Vec<(u32, u32)> {
    let (Some(fa), Some(fb)) = (fa, fb) else {
        return vec![];
    };
    fa.features
        .iter()
        .filter(|f| f.name.starts_with("landmark:") && f.vertices.len() == 1)
        .filter_map(|f| {
            let g = fb.features.iter().find(|g| g.name == f.name)?;
            (g.vertices.len() == 1).then(|| (f.vertices[0], g.vertices[0]))
        })
        .collect()
}
