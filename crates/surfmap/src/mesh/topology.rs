//! Topology derived once from a triangle list: edges, edge→faces, boundary loops,
//! components, Euler characteristic, genus, manifoldness and orientation.
//! (Being written by the lead; the public API below is fixed.)

use super::TriMesh;

/// One closed boundary loop: vertex indices in order, oriented so that the surface
/// lies to the left when the triangles are consistently counter-clockwise.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryLoop {
    pub vertices: Vec<u32>,
}

/// Derived topology of a [`TriMesh`].
#[derive(Clone, Debug)]
pub struct Topology {
    /// Unique undirected edges `[min, max]`.
    pub edges: Vec<[u32; 2]>,
    /// `face_edges[t][k]` is the edge from corner `k` to corner `k + 1` of triangle `t`.
    pub face_edges: Vec<[u32; 3]>,
    /// CSR offsets into `edge_face_list`: faces of edge `e` are
    /// `edge_face_list[edge_face_start[e]..edge_face_start[e + 1]]`.
    pub edge_face_start: Vec<u32>,
    pub edge_face_list: Vec<u32>,
    /// Boundary loops (components of the graph of edges used by exactly one face).
    pub boundary_loops: Vec<BoundaryLoop>,
    /// Connected component id of every face (faces sharing a vertex are connected).
    pub face_component: Vec<u32>,
    pub num_components: usize,
    /// Vertices used by at least one triangle.
    pub num_used_vertices: usize,
    /// Edges with more than two incident faces.
    pub non_manifold_edges: Vec<u32>,
    /// Vertices (on manifold edges only) whose incident faces form more than one fan.
    pub non_manifold_vertices: Vec<u32>,
    /// Edges whose two faces traverse them in the same direction.
    pub inconsistent_edges: Vec<u32>,
    /// Whether each component can be consistently oriented.
    pub orientable: bool,
    /// Fewest faces to flip (per component) for a consistent orientation; `None` if not orientable.
    pub faces_to_flip: Option<usize>,
}

impl Topology {
    pub fn new(_mesh: &TriMesh) -> Self {
        unimplemented!("lead is writing this")
    }
    /// `V_used − E + F`.
    pub fn euler_characteristic(&self) -> i64 {
        self.num_used_vertices as i64 - self.edges.len() as i64 + self.face_component.len() as i64
    }
    pub fn faces_of_edge(&self, e: usize) -> &[u32] {
        &self.edge_face_list[self.edge_face_start[e] as usize..self.edge_face_start[e + 1] as usize]
    }
    pub fn is_manifold(&self) -> bool {
        self.non_manifold_edges.is_empty() && self.non_manifold_vertices.is_empty()
    }
    /// Genus from `χ = 2 − 2g − b`, defined only for one orientable manifold component.
    pub fn genus(&self) -> Option<u32> {
        if self.num_components != 1 || !self.orientable || !self.is_manifold() {
            return None;
        }
        let g2 = 2 - self.euler_characteristic() - self.boundary_loops.len() as i64;
        (g2 >= 0 && g2 % 2 == 0).then_some((g2 / 2) as u32)
    }
    /// A disc: one component, manifold, orientable, one boundary loop, genus 0.
    pub fn is_disc(&self) -> bool {
        self.genus() == Some(0) && self.boundary_loops.len() == 1
    }
}
