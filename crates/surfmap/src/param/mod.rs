//! Flattening (thesis §2.1, §3.1): an initial free-boundary conformal map, then
//! projected Newton minimization of `E = Σ_T area3D(T) · W(a, d)` with flip-free
//! line search and α-continuation.

#[doc(hidden)]
pub mod arap;
pub mod barrier;
#[doc(hidden)]
pub mod element;
pub mod flatten;
pub mod flip_free;
pub mod lscm;
pub mod multilevel;
#[doc(hidden)]
pub mod newton;
pub mod optcuts;
pub mod plan;
pub mod protrusions;
pub mod relief;
pub mod scaffold;
pub mod tutte;

use crate::linsolve::SolveError;
use crate::mesh::{Disc, PositionError};

/// Signed area of a UV triangle, `½ ((b − a) × (c − a))`: positive when `a, b, c` turn
/// counter-clockwise.
#[inline]
pub fn signed_uv_area(uv: [[f64; 2]; 3]) -> f64 {
    let [a, b, c] = uv;
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
}

/// Number of triangles whose UV image is flipped or degenerate (signed area ≤ 0, or not
/// finite). A map is admissible (thesis §2.1.2) when this is 0.
pub fn count_flipped(uvs: &[[f64; 2]], triangles: &[[u32; 3]]) -> usize {
    triangles
        .iter()
        .filter(|t| {
            let area = signed_uv_area(t.map(|v| uvs[v as usize]));
            area.is_nan() || area <= 0.0
        })
        .count()
}

/// A reflected map is as good as any: mirrors `uv` when most triangles are negative.
/// Returns the triangles still flipped or degenerate (0: admissible, §2.1.2).
pub(crate) fn make_admissible(uv: &mut [[f64; 2]], triangles: &[[u32; 3]]) -> usize {
    let negative = triangles
        .iter()
        .filter(|t| signed_uv_area([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]]) < 0.0)
        .count();
    if 2 * negative > triangles.len() {
        uv.iter_mut().for_each(|p| p[1] = -p[1]);
    }
    count_flipped(uv, triangles)
}

/// Why an initial map ([`lscm`], [`tutte`]) could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InitialMapError {
    #[error(transparent)]
    Positions(#[from] PositionError),
    #[error(
        "vertex {vertex} (0-based) is used by no triangle; remove unreferenced vertices first (`repair::drop_unreferenced`)"
    )]
    UnreferencedVertex { vertex: u32 },
    #[error("the boundary loop has zero length (all boundary vertices coincide)")]
    DegenerateBoundary,
    #[error(
        "triangle {triangle} (0-based) is degenerate (zero area or a zero-length edge); remove or repair it"
    )]
    DegenerateTriangle { triangle: usize },
    #[error("expected {expected} boundary UV positions, got {got}")]
    BoundaryUvCount { expected: usize, got: usize },
    #[error("linear solve failed: {0}")]
    Solve(#[from] SolveError),
}

/// Checks what the initial maps need beyond a [`Disc`]: one finite position per vertex
/// ([`Disc::check_positions`]), and every vertex used by a triangle (an unused one would
/// make the systems singular).
pub(crate) fn check_positions(positions: &[[f64; 3]], disc: &Disc) -> Result<(), InitialMapError> {
    disc.check_positions(positions)?;
    match disc.first_unreferenced_vertex() {
        Some(vertex) => Err(InitialMapError::UnreferencedVertex { vertex }),
        None => Ok(()),
    }
}

/// Maps UVs into `[0, 1]²` by one translation and one uniform scale (the aspect ratio
/// is kept): the longer side of the bounding box becomes 1, its lower-left corner the
/// origin. Non-finite UVs are left out of the box (and stay non-finite). See also
/// [`flatten::Flattening::normalized_uvs`].
pub fn normalize_uvs(uvs: &mut [[f64; 2]]) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in uvs.iter().filter(|p| p[0].is_finite() && p[1].is_finite()) {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if lo[0] > hi[0] {
        return; // nothing finite
    }
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f64::MIN_POSITIVE);
    for p in uvs.iter_mut() {
        *p = [(p[0] - lo[0]) / size, (p[1] - lo[1]) / size];
    }
}

/// Real meshes from `shared/data` for tests, read by a minimal OFF/OBJ reader (positions
/// and polygon faces only, fan-triangulated) so these tests do not depend on `mesh::io`.
#[cfg(test)]
pub(crate) mod test_meshes {
    use crate::mesh::TriMesh;

    fn fan(face: &[u32], triangles: &mut Vec<[u32; 3]>) {
        for k in 1..face.len().saturating_sub(1) {
            triangles.push([face[0], face[k], face[k + 1]]);
        }
    }

    /// Reads `name` (OFF or OBJ) from the data folder ([`crate::testing::shared_data`]);
    /// `None` (the test returns) only when the folder is missing outside CI.
    pub fn read(name: &str) -> Option<TriMesh> {
        let text = std::fs::read_to_string(crate::testing::shared_data()?.join(name)).ok()?;
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        let num = |t: &str| t.parse::<f64>().ok();
        if name.ends_with(".obj") {
            for line in text.lines() {
                let mut it = line.split_whitespace();
                match it.next() {
                    Some("v") => {
                        let p: Vec<f64> = it.take(3).filter_map(num).collect();
                        positions.push([p[0], p[1], p[2]]);
                    }
                    Some("f") => {
                        let face: Vec<u32> = it
                            .filter_map(|t| t.split('/').next()?.parse::<u32>().ok())
                            .map(|i| i - 1)
                            .collect();
                        fan(&face, &mut triangles);
                    }
                    _ => {}
                }
            }
        } else {
            let mut lines = text
                .lines()
                .map(|l| l.split('#').next().unwrap().trim())
                .filter(|l| !l.is_empty());
            let header = lines.next()?;
            let counts_line = if header.len() > 3 {
                header[3..].trim()
            } else {
                lines.next()?
            };
            let counts: Vec<usize> = counts_line
                .split_whitespace()
                .filter_map(|t| t.parse().ok())
                .collect();
            for _ in 0..counts[0] {
                let p: Vec<f64> = lines
                    .next()?
                    .split_whitespace()
                    .take(3)
                    .filter_map(num)
                    .collect();
                positions.push([p[0], p[1], p[2]]);
            }
            for _ in 0..counts[1] {
                let f: Vec<u32> = lines
                    .next()?
                    .split_whitespace()
                    .filter_map(|t| t.parse().ok())
                    .collect();
                let k = f[0] as usize;
                fan(&f[1..=k], &mut triangles);
            }
        }
        Some(TriMesh::new(positions, triangles))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_area_and_flip_count() {
        assert_eq!(signed_uv_area([[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]]), 1.0);
        assert_eq!(signed_uv_area([[0.0, 0.0], [0.0, 1.0], [2.0, 0.0]]), -1.0);
        let uv = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [2.0, 0.0]];
        // ccw, cw, degenerate (collinear)
        let tris = [[0, 1, 2], [0, 2, 1], [0, 1, 3]];
        assert_eq!(count_flipped(&uv, &tris), 2);
        assert_eq!(
            count_flipped(&[[f64::NAN, 0.0], [1.0, 0.0], [0.0, 1.0]], &[[0, 1, 2]]),
            1
        );
    }

    #[test]
    fn positions_are_checked_against_the_disc() {
        let mesh = crate::mesh::generate::grid_disc(2);
        let disc = Disc::new(&mesh).unwrap();
        assert_eq!(check_positions(&mesh.positions, &disc), Ok(()));
        assert_eq!(
            check_positions(&mesh.positions[..8], &disc),
            Err(InitialMapError::Positions(PositionError::Count {
                positions: 8,
                vertices: 9
            }))
        );
        let mut nan = mesh.positions.clone();
        nan[4][1] = f64::NAN;
        assert_eq!(
            check_positions(&nan, &disc),
            Err(InitialMapError::Positions(PositionError::NonFinite {
                vertex: 4
            }))
        );
        let mut extra = mesh.clone();
        extra.positions.push([0.0; 3]);
        assert_eq!(
            check_positions(&extra.positions, &Disc::new(&extra).unwrap()),
            Err(InitialMapError::UnreferencedVertex { vertex: 9 })
        );
    }

    #[test]
    fn normalized_uvs_fill_the_unit_square_keeping_the_aspect() {
        let mut uv = vec![[-1.0, 2.0], [3.0, 2.0], [1.0, 4.0], [f64::NAN, 0.0]];
        normalize_uvs(&mut uv);
        assert_eq!(&uv[..3], &[[0.0, 0.0], [1.0, 0.0], [0.5, 0.5]]);
        assert!(uv[3][0].is_nan());
        // A single point stays finite.
        let mut one = vec![[5.0, 5.0]];
        normalize_uvs(&mut one);
        assert_eq!(one, vec![[0.0, 0.0]]);
    }
}
