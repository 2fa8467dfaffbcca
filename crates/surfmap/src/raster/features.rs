//! Feature sets for matching (thesis §2.2.4, §3.2.2), from two sources:
//!
//! * a JSON file of named vertex curves,
//!   `{"features": [{"name": "left_eye", "vertices": [12, 40, 41], "closed": true}]}`;
//!   consecutive vertices are joined by straight segments in the flattening (a mesh
//!   edge maps to exactly such a segment); one vertex is a point feature;
//! * a PNG mask painted over the mesh's own texture coordinates: every distinct
//!   non-black colour is one region, and the region's boundary is the feature curve
//!   (named by the colour, `#rrggbb`).
//!
//! Names are kept so that matching can pair feature `i` on one surface with feature `i`
//! (or the same name) on the other.

use serde::{Deserialize, Serialize};

use super::RasterError;

/// One named vertex curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeatureCurve {
    pub name: String,
    pub vertices: Vec<u32>,
    #[serde(default)]
    pub closed: bool,
}

/// The JSON feature file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeatureFile {
    pub features: Vec<FeatureCurve>,
}

impl FeatureFile {
    /// Parses and checks the file against a mesh with `num_vertices` vertices: at least
    /// one feature, non-empty unique names, non-empty vertex lists, known vertex ids.
    pub fn parse(json: &str, num_vertices: usize) -> Result<Self, RasterError> {
        let file: FeatureFile =
            serde_json::from_str(json).map_err(|e| RasterError::FeatureFile(e.to_string()))?;
        file.validate(num_vertices)?;
        Ok(file)
    }

    pub fn validate(&self, num_vertices: usize) -> Result<(), RasterError> {
        if self.features.is_empty() {
            return Err(RasterError::FeatureFile(
                "the \"features\" list is empty; give at least one feature".into(),
            ));
        }
        for (i, f) in self.features.iter().enumerate() {
            let err = |problem: String| RasterError::Feature {
                name: f.name.clone(),
                problem,
            };
            if f.name.trim().is_empty() {
                return Err(RasterError::FeatureFile(format!(
                    "feature #{i} has an empty name"
                )));
            }
            if self.features[..i].iter().any(|g| g.name == f.name) {
                return Err(err(
                    "the name is used twice; names pair features across surfaces".into(),
                ));
            }
            if f.vertices.is_empty() {
                return Err(err("the vertex list is empty".into()));
            }
            if let Some(&v) = f.vertices.iter().find(|&&v| v as usize >= num_vertices) {
                return Err(err(format!(
                    "vertex {v} does not exist (the mesh has {num_vertices} vertices, ids 0..{})",
                    num_vertices.saturating_sub(1)
                )));
            }
        }
        Ok(())
    }

    /// The file renumbered onto a repaired mesh: `copies[v]` is the repaired vertex that
    /// stands for input vertex `v` ([`crate::mesh::repair::FaceOrigins::vertex_copies`]);
    /// a vertex the repairs removed is an error naming the feature. Checked against the
    /// input first ([`FeatureFile::validate`] with `copies.len()` vertices).
    pub fn renumbered(&self, copies: &[Option<u32>]) -> Result<Self, RasterError> {
        self.validate(copies.len())?;
        let mut out = self.clone();
        for f in &mut out.features {
            for v in &mut f.vertices {
                *v = copies[*v as usize].ok_or_else(|| RasterError::Feature {
                    name: f.name.clone(),
                    problem: format!(
                        "vertex {v} was removed by the repairs (every face around it went); \
                         pick vertices of the part that is kept"
                    ),
                })?;
            }
        }
        Ok(out)
    }
}

/// An RGB mask painted over texture space; row 0 is the top of the image (texture `v = 1`).
#[derive(Clone, Debug, PartialEq)]
pub struct FeatureMask {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<[u8; 3]>,
}

impl FeatureMask {
    /// Reads a PNG (any colour type; alpha ignored).
    pub fn read_png(path: &std::path::Path) -> Result<Self, RasterError> {
        let img = image::open(path)
            .map_err(|e| {
                RasterError::FeatureFile(format!("cannot read mask {}: {e}", path.display()))
            })?
            .to_rgb8();
        Ok(Self {
            width: img.width(),
            height: img.height(),
            rgb: img.pixels().map(|p| p.0).collect(),
        })
    }

    /// The distinct non-black colours, sorted: one region (feature) each.
    pub fn region_colours(&self) -> Vec<[u8; 3]> {
        let mut c: Vec<[u8; 3]> = self
            .rgb
            .iter()
            .copied()
            .filter(|&c| c != [0, 0, 0])
            .collect();
        c.sort_unstable();
        c.dedup();
        c
    }

    /// Colour of the pixel containing texture coordinates `(u, v)` (`v` up), clamped.
    #[inline]
    pub fn lookup(&self, uv: [f64; 2]) -> [u8; 3] {
        let x = (uv[0] * self.width as f64)
            .floor()
            .clamp(0.0, self.width as f64 - 1.0) as usize;
        let y = ((1.0 - uv[1]) * self.height as f64)
            .floor()
            .clamp(0.0, self.height as f64 - 1.0) as usize;
        self.rgb[y * self.width as usize + x]
    }

    /// Checks the mask size against the texture's, when there is one, and that it has regions.
    pub fn validate(&self, texture_size: Option<(u32, u32)>) -> Result<(), RasterError> {
        if let Some((w, h)) = texture_size
            && (w, h) != (self.width, self.height)
        {
            {
                return Err(RasterError::MaskSize {
                    got_width: self.width,
                    got_height: self.height,
                    want_width: w,
                    want_height: h,
                });
            }
        }
        if self.width == 0
            || self.height == 0
            || self.rgb.len() != (self.width * self.height) as usize
        {
            return Err(RasterError::FeatureFile(
                "the feature mask has no pixels".into(),
            ));
        }
        if self.region_colours().is_empty() {
            return Err(RasterError::FeatureFile(
                "the feature mask is all black: paint each feature region in its own colour".into(),
            ));
        }
        Ok(())
    }
}

/// Name of the feature of a mask region.
pub fn colour_name(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// Where features come from.
#[derive(Clone, Copy, Debug, Default)]
pub enum FeatureSource<'a> {
    #[default]
    None,
    Curves(&'a FeatureFile),
    Mask(&'a FeatureMask),
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ids move to their copies; a removed vertex or one beyond the input is refused
    /// with the feature's name.
    #[test]
    fn renumbering_onto_a_repaired_mesh() {
        let file = FeatureFile::parse(
            r#"{"features": [{"name": "brow", "vertices": [0, 2]}, {"name": "lip", "vertices": [3]}]}"#,
            4,
        )
        .unwrap();
        let moved = file.renumbered(&[Some(5), None, Some(1), Some(0)]).unwrap();
        assert_eq!(moved.features[0].vertices, vec![5, 1]);
        assert_eq!(moved.features[1].vertices, vec![0]);
        let err = file
            .renumbered(&[Some(5), None, Some(1), None])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("lip") && err.contains("vertex 3 was removed"),
            "{err}"
        );
        let err = file.renumbered(&[Some(0); 3]).unwrap_err().to_string();
        assert!(err.contains("vertex 3 does not exist"), "{err}");
    }

    #[test]
    fn parses_and_validates() {
        let ok = r#"{"features": [{"name": "left_eye", "vertices": [1, 2, 3], "closed": true},
                                  {"name": "nose", "vertices": [4]}]}"#;
        let f = FeatureFile::parse(ok, 5).unwrap();
        assert_eq!(f.features[1].name, "nose");
        assert!(!f.features[1].closed && f.features[0].closed);
        let e = FeatureFile::parse(ok, 4).unwrap_err().to_string();
        assert!(e.contains("nose") && e.contains("vertex 4"), "{e}");
        let e =
            FeatureFile::parse(r#"{"features": [{"name": "a", "vertices": []}]}"#, 4).unwrap_err();
        assert!(e.to_string().contains("empty"), "{e}");
        assert!(FeatureFile::parse(r#"{"features": []}"#, 4).is_err());
        assert!(
            FeatureFile::parse(
                r#"{"features": [{"name": "a", "vertices": [1]}, {"name": "a", "vertices": [2]}]}"#,
                4
            )
            .is_err()
        );
        assert!(FeatureFile::parse(r#"{"feature": []}"#, 4).is_err());
    }

    #[test]
    fn mask_regions_lookup_and_size() {
        let m = FeatureMask {
            width: 2,
            height: 2,
            rgb: vec![[255, 0, 0], [0, 0, 0], [0, 0, 0], [0, 255, 0]],
        };
        assert_eq!(m.region_colours(), vec![[0, 255, 0], [255, 0, 0]]);
        assert_eq!(m.lookup([0.1, 0.9]), [255, 0, 0]); // top-left
        assert_eq!(m.lookup([0.9, 0.1]), [0, 255, 0]); // bottom-right
        assert!(m.validate(Some((2, 2))).is_ok());
        assert!(matches!(
            m.validate(Some((4, 2))),
            Err(RasterError::MaskSize { .. })
        ));
        let black = FeatureMask {
            width: 1,
            height: 1,
            rgb: vec![[0, 0, 0]],
        };
        assert!(black.validate(None).is_err());
        assert_eq!(colour_name([255, 0, 16]), "#ff0010");
    }
}
