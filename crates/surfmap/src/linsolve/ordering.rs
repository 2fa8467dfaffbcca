//! Fill-reducing orderings: one AMD ordering of a mesh's vertex graph, shared by every
//! sparse system whose unknowns are per-vertex quantities (the LSCM system, the ARAP
//! Laplacian, the Newton Hessian of a flattening).
//!
//! The matrix of such a system has the pattern of the vertex graph `G = (V, E)` (one
//! unknown per vertex) or of `G ⊗ K_k` (`k` unknowns per vertex, all coupled: every
//! vertex pair `(i, j) ∈ E ∪ diag` gives a dense `k × k` block). Eliminating a vertex's
//! `k` unknowns consecutively in a good vertex order `π` gives, for `G ⊗ K_k`, the same
//! elimination graphs as `π` on `G` with every node blown up to a `k`-clique, so
//! `nnz(L_k) = k² nnz(L_1) − k(k−1)/2 · n` (columns of one vertex form a dense
//! triangle). AMD run on the `kn` system itself finds these supervariables too (it
//! detects indistinguishable nodes), so the expanded order mostly costs AMD's time on a
//! `k²`-times larger graph less. Pinned unknowns are simply skipped, which keeps the
//! order a valid one of the reduced system (eliminating a row and column of an SPD
//! matrix never adds fill).

use super::{LowerPattern, SolveError};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;

/// Fill-reducing ordering of an `n × n` system, `forward[new] = old`: unknown
/// `forward[k]` is eliminated `k`-th.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum Ordering {
    /// Approximate minimum degree on the system's own pattern (faer's default).
    #[default]
    Amd,
    /// A given permutation of `0..n`, `forward[new] = old`.
    Custom(Vec<u32>),
}

/// An elimination order of a mesh's vertices, `order[new] = old vertex`: AMD on the
/// vertex graph (triangle edges), computed once and expanded to the unknowns of each
/// per-vertex system with [`VertexOrdering::expand`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VertexOrdering {
    order: Vec<u32>,
}

impl VertexOrdering {
    /// AMD ordering of the graph whose nodes are the `num_vertices` vertices and whose
    /// edges are the triangle edges (vertices in no triangle are isolated nodes).
    /// Cost: O(F) to build the pattern plus AMD on `n` nodes, `≈ 3n` edges.
    pub fn of_triangles(num_vertices: usize, triangles: &[[u32; 3]]) -> Result<Self, SolveError> {
        let edges: Vec<(u32, u32)> = triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .collect();
        Self::of_graph(num_vertices, &edges)
    }

    /// AMD ordering of the graph with `num_vertices` nodes and these edges (either
    /// direction, duplicates and self-loops allowed).
    pub fn of_graph(num_vertices: usize, edges: &[(u32, u32)]) -> Result<Self, SolveError> {
        let n = num_vertices;
        let pattern = LowerPattern::new(n, edges)?;
        let a =
            SymbolicSparseColMatRef::new_checked(n, n, &pattern.col_ptr, None, &pattern.row_idx);
        let mut forward = vec![0u32; n];
        let mut inverse = vec![0u32; n];
        let mut scratch =
            MemBuffer::try_new(amd::order_scratch::<u32>(n, pattern.row_idx.len()))
                .map_err(|e| SolveError::Backend(format!("AMD workspace allocation: {e:?}")))?;
        amd::order(
            &mut forward,
            &mut inverse,
            a,
            amd::Control::default(),
            MemStack::new(&mut scratch),
        )
        .map_err(|e| SolveError::Backend(format!("AMD ordering: {e:?}")))?;
        Ok(Self { order: forward })
    }

    /// A given vertex order (`order[new] = old`), checked to be a permutation.
    pub fn from_order(order: Vec<u32>) -> Result<Self, SolveError> {
        inverse_permutation(&order, order.len())?;
        Ok(Self { order })
    }

    /// The vertices in elimination order.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.order.len()
    }

    /// The ordering of a system with `per_vertex` components per vertex:
    /// `unknown[per_vertex · v + c]` is the unknown of component `c` of vertex `v`, or
    /// `u32::MAX` when that component is not an unknown (pinned). Vertices are taken in
    /// this order, each one's components consecutively, pinned ones skipped.
    ///
    /// Whether the result is a permutation of the system's unknowns is checked by
    /// [`super::SpdSystem::with_ordering`].
    pub fn expand(&self, per_vertex: usize, unknown: &[u32]) -> Result<Ordering, SolveError> {
        let expected = per_vertex * self.order.len();
        if unknown.len() != expected {
            return Err(SolveError::DimensionMismatch {
                expected,
                got: unknown.len(),
            });
        }
        let mut forward = Vec::with_capacity(expected);
        for &v in &self.order {
            let base = per_vertex * v as usize;
            forward.extend(
                unknown[base..base + per_vertex]
                    .iter()
                    .copied()
                    .filter(|&u| u != u32::MAX),
            );
        }
        Ok(Ordering::Custom(forward))
    }
}

/// `inverse[forward[k]] = k`, or [`SolveError::InvalidOrdering`] when `forward` is not
/// a permutation of `0..n` (wrong length, an entry out of range or repeated).
pub(crate) fn inverse_permutation(forward: &[u32], n: usize) -> Result<Vec<u32>, SolveError> {
    if forward.len() != n {
        return Err(SolveError::DimensionMismatch {
            expected: n,
            got: forward.len(),
        });
    }
    let mut inverse = vec![u32::MAX; n];
    for (k, &old) in forward.iter().enumerate() {
        match inverse.get_mut(old as usize) {
            Some(slot) if *slot == u32::MAX => *slot = k as u32,
            _ => {
                return Err(SolveError::InvalidOrdering {
                    n,
                    index: k,
                    value: old,
                });
            }
        }
    }
    Ok(inverse)
}
