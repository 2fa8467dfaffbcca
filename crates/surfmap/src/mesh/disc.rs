//! A disc, validated once: the input of flattening, its initial maps and decimation.
//!
//! A flattening maps a topological disc: one connected, manifold, consistently oriented
//! surface of genus 0 with exactly one boundary loop (thesis §2.1; a surface with holes
//! or handles needs cuts first). [`Disc::new`] checks that, and the vertex indices and
//! finite coordinates every algorithm relies on, once; [`crate::param::lscm`],
//! [`crate::param::tutte`], [`super::decimate`] and [`crate::flatten`] take the checked
//! [`Disc`] instead of checking again. A mesh that is not a disc gets every defect that
//! blocks it, each with what it means and the repair that fixes it ([`super::validate`]).
//!
//! The disc holds connectivity only (its triangles, topology and boundary loop);
//! positions are passed beside it, so the same disc serves a rescaled copy of the
//! surface. Vertices used by no triangle are allowed (they are harmless, and
//! [`crate::flatten`] puts them aside); the initial maps refuse them.

use super::validate::{Defect, list_defects, validate};
use super::{IndexError, Topology, TriMesh};

/// A mesh checked to be a disc (module docs), with its topology and its boundary loop.
#[derive(Clone, Debug)]
pub struct Disc<'m> {
    triangles: &'m [[u32; 3]],
    num_vertices: usize,
    topology: Topology,
    /// The boundary loop, with the surface on its left.
    boundary: Vec<u32>,
}

/// Why a mesh is not a disc: an index out of range (no topology can be derived), or the
/// defects that block a disc map, each with its remedy.
#[derive(Clone, Debug, thiserror::Error)]
pub enum NotADisc {
    #[error(transparent)]
    Index(#[from] IndexError),
    #[error("the mesh is not a disc:\n{}", list_defects(.0))]
    Defects(Vec<Defect>),
}

/// Positions that do not fit a disc ([`Disc::check_positions`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PositionError {
    #[error(
        "{positions} positions for a disc of {vertices} vertices; give one position per vertex"
    )]
    Count { positions: usize, vertices: usize },
    #[error("position of vertex {vertex} (0-based) is not finite; fix or remove it")]
    NonFinite { vertex: u32 },
}

impl<'m> Disc<'m> {
    /// Checks that `mesh` is a disc (module docs) and derives its topology.
    ///
    /// Cost: `O(F log F)` for [`Topology::new`], plus a full [`validate`] only when a
    /// check fails (to list every defect, not just the first).
    pub fn new(mesh: &'m TriMesh) -> Result<Self, NotADisc> {
        mesh.check_indices()?;
        Self::with_topology(mesh, Topology::new(mesh))
    }

    /// [`Disc::new`] with the topology of `mesh` already derived ([`Topology::new`]).
    ///
    /// A topology of another mesh is caught only when the triangle counts differ.
    pub fn with_topology(mesh: &'m TriMesh, topology: Topology) -> Result<Self, NotADisc> {
        mesh.check_indices()?;
        let belongs = topology.face_edges.len() == mesh.triangles.len();
        if !(belongs
            && mesh.finite_and_proper()
            && topology.is_disc()
            && topology.inconsistent_edges.is_empty())
        {
            let topology = if belongs {
                topology
            } else {
                Topology::new(mesh)
            };
            return Err(NotADisc::Defects(
                validate(mesh, &topology)
                    .into_iter()
                    .filter(|d| d.blocks_flattening)
                    .collect(),
            ));
        }
        let boundary = surface_on_the_left(
            &mesh.triangles,
            mesh.positions.len(),
            &topology.boundary_loops[0].vertices,
        );
        Ok(Self {
            triangles: &mesh.triangles,
            num_vertices: mesh.positions.len(),
            topology,
            boundary,
        })
    }

    /// The triangles (counter-clockwise, consistently oriented).
    pub fn triangles(&self) -> &'m [[u32; 3]] {
        self.triangles
    }

    /// Vertex count of the mesh (including vertices used by no triangle).
    pub fn num_vertices(&self) -> usize {
        self.num_vertices
    }

    /// The boundary loop in order, with the surface on its left (counter-clockwise seen
    /// from the side the triangles face).
    pub fn boundary(&self) -> &[u32] {
        &self.boundary
    }

    /// The derived topology (edges, edge → faces, …).
    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// Checks positions passed beside the disc (its own, or a rescaled copy): one per
    /// vertex, all finite.
    pub fn check_positions(&self, positions: &[[f64; 3]]) -> Result<(), PositionError> {
        if positions.len() != self.num_vertices {
            return Err(PositionError::Count {
                positions: positions.len(),
                vertices: self.num_vertices,
            });
        }
        match positions
            .iter()
            .position(|p| p.iter().any(|x| !x.is_finite()))
        {
            Some(v) => Err(PositionError::NonFinite { vertex: v as u32 }),
            None => Ok(()),
        }
    }

    /// Whether some vertex is used by no triangle.
    pub fn has_unreferenced_vertices(&self) -> bool {
        self.topology.num_used_vertices < self.num_vertices
    }

    /// The first vertex used by no triangle, if any.
    pub fn first_unreferenced_vertex(&self) -> Option<u32> {
        if !self.has_unreferenced_vertices() {
            return None;
        }
        let mut used = vec![false; self.num_vertices];
        for t in self.triangles {
            for &v in t {
                used[v as usize] = true;
            }
        }
        used.iter().position(|&u| !u).map(|v| v as u32)
    }
}

/// The loop `boundary` of a consistently oriented disc, reversed if its edges run
/// against the triangles (so that the surface lies on its left).
fn surface_on_the_left(triangles: &[[u32; 3]], num_vertices: usize, boundary: &[u32]) -> Vec<u32> {
    let mut next = vec![u32::MAX; num_vertices];
    for (k, &v) in boundary.iter().enumerate() {
        next[v as usize] = boundary[(k + 1) % boundary.len()];
    }
    // A boundary edge a → b belongs to one triangle, which runs along it a → b when the
    // surface is on the left.
    let forward = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|&(a, b)| next[a as usize] == b)
        .count();
    if 2 * forward >= boundary.len() {
        boundary.to_vec()
    } else {
        boundary.iter().rev().copied().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{disc_boundary, grid_disc, octahedron, polar_disc, unit_square};
    use crate::mesh::validate::DefectKind;

    fn kinds(err: NotADisc) -> Vec<DefectKind> {
        match err {
            NotADisc::Defects(d) => d.iter().map(|d| d.kind).collect(),
            NotADisc::Index(e) => panic!("index error {e}"),
        }
    }

    #[test]
    fn a_disc_has_its_boundary_with_the_surface_on_the_left() {
        let mesh = grid_disc(3);
        let disc = Disc::new(&mesh).unwrap();
        assert_eq!(disc.num_vertices(), 16);
        assert_eq!(disc.triangles().len(), 18);
        assert!(!disc.has_unreferenced_vertices());
        // The independent boundary walk of the generator (surface on the left).
        let want = disc_boundary(&mesh.triangles).unwrap();
        let got = disc.boundary();
        assert_eq!(got.len(), want.len());
        let start = got.iter().position(|&v| v == want[0]).unwrap();
        let rotated: Vec<u32> = (0..got.len())
            .map(|k| got[(start + k) % got.len()])
            .collect();
        assert_eq!(rotated, want);
    }

    #[test]
    fn every_blocking_defect_is_listed_with_its_remedy() {
        let octahedron = octahedron();
        assert_eq!(
            kinds(Disc::new(&octahedron).unwrap_err()),
            [DefectKind::ClosedSurface]
        );
        let mut annulus = polar_disc(3, 10);
        annulus.triangles.retain(|t| !t.contains(&0));
        let err = Disc::new(&annulus).unwrap_err();
        let message = err.to_string();
        assert!(
            message.contains("2 boundary loops") && message.contains("fill_holes"),
            "{message}"
        );
        assert_eq!(kinds(err), [DefectKind::SeveralBoundaryLoops]);

        // Two components, one of them with a NaN coordinate: both are listed.
        let mut two = unit_square();
        two.positions
            .extend([[5., 0., 0.], [6., f64::NAN, 0.], [5., 1., 0.]]);
        two.triangles.push([4, 5, 6]);
        let found = kinds(Disc::new(&two).unwrap_err());
        assert!(found.contains(&DefectKind::SeveralComponents), "{found:?}");
        assert!(
            found.contains(&DefectKind::NonFiniteCoordinates),
            "{found:?}"
        );

        let mut flipped = grid_disc(3);
        flipped.triangles[4].swap(1, 2);
        assert_eq!(
            kinds(Disc::new(&flipped).unwrap_err()),
            [DefectKind::InconsistentOrientation]
        );
        let mut repeated = grid_disc(2);
        repeated.triangles[1] = [0, 0, 3];
        assert!(kinds(Disc::new(&repeated).unwrap_err()).contains(&DefectKind::RepeatedIndexFaces));
        assert_eq!(
            kinds(Disc::new(&TriMesh::default()).unwrap_err()),
            [DefectKind::NoFaces]
        );
    }

    #[test]
    fn out_of_range_indices_are_an_index_error() {
        let mut mesh = grid_disc(2);
        mesh.triangles[3][2] = 99;
        assert!(matches!(
            Disc::new(&mesh),
            Err(NotADisc::Index(IndexError {
                triangle: 3,
                corner: 2,
                vertex: 99,
                num_vertices: 9
            }))
        ));
    }

    #[test]
    fn unreferenced_vertices_are_allowed_and_found() {
        let mut mesh = grid_disc(2);
        mesh.positions.push([7.0, 7.0, 7.0]);
        let disc = Disc::new(&mesh).unwrap();
        assert_eq!(disc.first_unreferenced_vertex(), Some(9));
    }

    #[test]
    fn a_reversed_loop_is_turned_around() {
        let mesh = grid_disc(2);
        let good = disc_boundary(&mesh.triangles).unwrap();
        let reversed: Vec<u32> = good.iter().rev().copied().collect();
        assert_eq!(surface_on_the_left(&mesh.triangles, 9, &reversed), good);
        assert_eq!(surface_on_the_left(&mesh.triangles, 9, &good), good);
    }
}
