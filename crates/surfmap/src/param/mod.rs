//! Flattening (thesis §2.1, §3.1): an initial free-boundary conformal map, then
//! projected Newton minimization of `E = Σ_T area3D(T) · W(a, d)` with flip-free
//! line search and α-continuation.

pub mod arap;
pub mod density;
pub mod element;
pub mod flatten;
pub mod flip_free;
pub mod lscm;
pub mod multilevel;
pub mod newton;
pub mod tutte;

use crate::linsolve::SolveError;

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

/// Why an initial map ([`lscm`], [`tutte`]) could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InitialMapError {
    #[error("the mesh has no triangles")]
    NoTriangles,
    #[error("triangle {triangle} uses vertex {vertex}, but there are only {num_vertices} vertices")]
    VertexOutOfRange {
        triangle: usize,
        vertex: u32,
        num_vertices: usize,
    },
    #[error("position of vertex {vertex} is not finite; fix or remove it")]
    NonFinitePosition { vertex: u32 },
    #[error("vertex {vertex} is used by no triangle; remove unreferenced vertices first")]
    UnreferencedVertex { vertex: u32 },
    #[error("the boundary loop has {len} vertices; a disc boundary needs at least 3")]
    BoundaryTooShort { len: usize },
    #[error("boundary entry {index} is vertex {vertex}, which is out of range or repeated")]
    BadBoundaryVertex { index: usize, vertex: u32 },
    #[error(
        "boundary vertices {from} → {to} are not joined by a triangle edge; pass the ordered boundary loop of a disc"
    )]
    BoundaryNotAnEdge { from: u32, to: u32 },
    #[error("the boundary loop has zero length (all boundary vertices coincide)")]
    DegenerateBoundary,
    #[error(
        "triangle {triangle} is degenerate (zero area or a zero-length edge); remove or repair it"
    )]
    DegenerateTriangle { triangle: usize },
    #[error("expected {expected} boundary UV positions, got {got}")]
    BoundaryUvCount { expected: usize, got: usize },
    #[error("linear solve failed: {0}")]
    Solve(#[from] SolveError),
}

/// Checks the common preconditions of the initial maps: indices in range, finite
/// positions, every vertex used, a boundary loop of distinct vertices whose
/// consecutive pairs are triangle edges. Returns whether the loop runs with the
/// triangles' orientation (surface on the left, `true`) or against it.
pub(crate) fn check_disc_input(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    boundary: &[u32],
) -> Result<bool, InitialMapError> {
    let n = positions.len();
    if triangles.is_empty() {
        return Err(InitialMapError::NoTriangles);
    }
    let mut used = vec![false; n];
    for (t, tri) in triangles.iter().enumerate() {
        for &v in tri {
            if v as usize >= n {
                return Err(InitialMapError::VertexOutOfRange {
                    triangle: t,
                    vertex: v,
                    num_vertices: n,
                });
            }
            used[v as usize] = true;
        }
    }
    if let Some(v) = positions
        .iter()
        .position(|p| p.iter().any(|x| !x.is_finite()))
    {
        return Err(InitialMapError::NonFinitePosition { vertex: v as u32 });
    }
    if let Some(v) = used.iter().position(|&u| !u) {
        return Err(InitialMapError::UnreferencedVertex { vertex: v as u32 });
    }
    if boundary.len() < 3 {
        return Err(InitialMapError::BoundaryTooShort {
            len: boundary.len(),
        });
    }
    let mut on_boundary = vec![false; n];
    for (index, &v) in boundary.iter().enumerate() {
        if v as usize >= n || on_boundary[v as usize] {
            return Err(InitialMapError::BadBoundaryVertex { index, vertex: v });
        }
        on_boundary[v as usize] = true;
    }
    // Directed triangle edges between boundary vertices, to check the loop and its direction.
    let mut forward = 0usize;
    let mut edges: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|&(a, b)| on_boundary[a as usize] && on_boundary[b as usize])
        .collect();
    edges.sort_unstable();
    for k in 0..boundary.len() {
        let (a, b) = (boundary[k], boundary[(k + 1) % boundary.len()]);
        let has_forward = edges.binary_search(&(a, b)).is_ok();
        let has_backward = edges.binary_search(&(b, a)).is_ok();
        if !has_forward && !has_backward {
            return Err(InitialMapError::BoundaryNotAnEdge { from: a, to: b });
        }
        if has_forward {
            forward += 1;
        }
    }
    Ok(2 * forward >= boundary.len())
}

/// Real meshes from `shared/data` for tests, read by a minimal OFF/OBJ reader (positions
/// and polygon faces only, fan-triangulated) so these tests do not depend on `mesh::io`.
#[cfg(test)]
pub(crate) mod test_meshes {
    use crate::mesh::TriMesh;
    use std::path::PathBuf;

    /// `shared/data` (`$SURFMAP_DATA`, or `../../../shared/data` from the crate, or one
    /// level further up for a worktree under `wt/`), or `None` (with a note) when missing.
    pub fn data_dir() -> Option<PathBuf> {
        let crate_dir = env!("CARGO_MANIFEST_DIR");
        let candidates = [
            std::env::var_os("SURFMAP_DATA").map(PathBuf::from),
            Some(PathBuf::from(format!("{crate_dir}/../../../shared/data"))),
            Some(PathBuf::from(format!(
                "{crate_dir}/../../../../shared/data"
            ))),
        ];
        let found = candidates.into_iter().flatten().find(|d| d.is_dir());
        if found.is_none() {
            eprintln!("note: shared/data not found; skipping real-mesh test");
        }
        found
    }

    fn fan(face: &[u32], triangles: &mut Vec<[u32; 3]>) {
        for k in 1..face.len().saturating_sub(1) {
            triangles.push([face[0], face[k], face[k + 1]]);
        }
    }

    /// Reads `name` (OFF or OBJ) from the data folder.
    pub fn read(name: &str) -> Option<TriMesh> {
        let text = std::fs::read_to_string(data_dir()?.join(name)).ok()?;
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
    fn disc_input_checks() {
        let mesh = crate::mesh::generate::grid_disc(2);
        let boundary = crate::mesh::generate::disc_boundary(&mesh.triangles).unwrap();
        assert_eq!(
            check_disc_input(&mesh.positions, &mesh.triangles, &boundary),
            Ok(true)
        );
        let reversed: Vec<u32> = boundary.iter().rev().copied().collect();
        assert_eq!(
            check_disc_input(&mesh.positions, &mesh.triangles, &reversed),
            Ok(false)
        );
        let mut skipping = boundary.clone();
        skipping.remove(1);
        assert!(matches!(
            check_disc_input(&mesh.positions, &mesh.triangles, &skipping),
            Err(InitialMapError::BoundaryNotAnEdge { .. })
        ));
        let mut extra = mesh.positions.clone();
        extra.push([0.0; 3]);
        assert_eq!(
            check_disc_input(&extra, &mesh.triangles, &boundary),
            Err(InitialMapError::UnreferencedVertex { vertex: 9 })
        );
        let mut nan = mesh.positions.clone();
        nan[4][1] = f64::NAN;
        assert_eq!(
            check_disc_input(&nan, &mesh.triangles, &boundary),
            Err(InitialMapError::NonFinitePosition { vertex: 4 })
        );
        assert!(matches!(
            check_disc_input(&mesh.positions, &mesh.triangles, &[0, 1]),
            Err(InitialMapError::BoundaryTooShort { len: 2 })
        ));
        assert!(matches!(
            check_disc_input(&mesh.positions, &mesh.triangles, &[0, 1, 1]),
            Err(InitialMapError::BadBoundaryVertex {
                index: 2,
                vertex: 1
            })
        ));
    }
}
