//! Fill-reducing orderings: one AMD ordering of a mesh's vertex graph, shared by every
//! sparse system whose unknowns are per-vertex quantities (the LSCM system, the ARAP
//! Laplacian, the Newton Hessian of a flattening).
//!
//! The matrix of such a system has the pattern of the vertex graph `G = (V, E)` (one
//! unknown per vertex) or of `G ⊗ K_k` (`k` unknowns per vertex, all coupled: every
//! vertex pair `(i, j) ∈ E ∪ diag` gives a dense `k × k` block). Eliminating a vertex's
//! `k` unknowns consecutively in a vertex order `π` gives, for `G ⊗ K_k`, the
//! elimination graphs of `π` on `G` with every node blown up to a `k`-clique: structurally
//! `nnz(L_k) = k² nnz(L_1) − k(k−1)/2 · n`, and the `k` columns of a vertex form one
//! supernode. Pinned unknowns are skipped, which keeps the order a valid one of the
//! reduced system (removing a node from a graph never adds fill).
//!
//! Measured on camelhead (11.4k vertices, `ordering_probe` example): AMD on the vertex
//! graph takes ~3 ms, AMD on the 2-dof Newton system ~4–5 ms of its ~14 ms symbolic phase
//! (the rest: pattern assembly ~4 ms, faer's elimination tree, column counts and
//! supernodes ~5 ms). The expanded vertex order gave *less* fill than AMD on the 2-dof
//! system (1.90M vs 1.96M entries of `L`) and the same numeric factorization time.
//!
//! Not for systems whose `k × k` blocks are sparse: the LSCM matrix couples `u_i` with
//! `v_j` only along the boundary, and there the interleaved order (same fill) breaks
//! faer's supernodes and factorizes 8× slower (61 ms vs 7.6 ms). LSCM keeps its own AMD.

use super::{FIXED, LowerPattern, SolveError, Unknowns};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;

/// From this many vertices on, [`VertexOrdering::fill_reducing`] orders by nested
/// dissection: measured on subdivided lionheads (2-dof Newton pattern, one run, machine
/// loaded): numeric factorization AMD 0.80–0.95 s vs METIS 0.58–0.62 s at 133k vertices
/// (METIS's ordering 0.7 s more, taken once), 0.11–0.12 s for both at 33k.
pub const DISSECTION_MIN_VERTICES: usize = 100_000;

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

    /// The fill-reducing order for a mesh of this size: METIS nested dissection from
    /// [`DISSECTION_MIN_VERTICES`] vertices on ([`Self::nested_dissection`]), AMD below
    /// ([`Self::of_triangles`]), where nested dissection measured no faster.
    pub fn fill_reducing(num_vertices: usize, triangles: &[[u32; 3]]) -> Result<Self, SolveError> {
        if num_vertices >= DISSECTION_MIN_VERTICES {
            Self::nested_dissection(num_vertices, triangles)
        } else {
            Self::of_triangles(num_vertices, triangles)
        }
    }

    /// METIS's nested-dissection ordering (`METIS_NodeND`, multilevel vertex separators
    /// refined by Fiduccia–Mattheyses) of the graph whose nodes are the `num_vertices`
    /// vertices and whose edges are the triangle edges.
    ///
    /// A separator `S` splits the graph into `P₁`, `P₂` with no edge between them;
    /// eliminating `P₁`, `P₂`, then `S` keeps all fill inside `P₁ ∪ S` and `P₂ ∪ S`,
    /// recursively. Planar meshes have separators of `O(√n)` vertices, which bounds the
    /// fill of `L` by `O(n log n)` and the factorization by `O(n^{3/2})` flops; minimum
    /// degree has no such bound. Measured on a 533,713-vertex disc (2-dof Newton
    /// pattern, `ordering_probe` example): `L` has 106M entries instead of AMD's 161M
    /// and factorizes in about half the time; at 133k vertices 22M against 32M; at 33k
    /// the fill is lower but the factorization no faster, hence
    /// [`Self::fill_reducing`]'s threshold. A hand-written breadth-first-level
    /// dissection measured *more* fill than AMD (44M against 32M at 133k): the separators
    /// need METIS's multilevel refinement.
    pub fn nested_dissection(
        num_vertices: usize,
        triangles: &[[u32; 3]],
    ) -> Result<Self, SolveError> {
        let n = num_vertices;
        if n == 0 {
            return Err(SolveError::Empty);
        }
        let (xadj, adjncy) = vertex_adjacency(n, triangles)?;
        // METIS indices are 32-bit signed: n and 2E must fit.
        if n > i32::MAX as usize || adjncy.len() > i32::MAX as usize {
            return Err(SolveError::TooLarge { n });
        }
        let mut xadj: Vec<i32> = xadj.iter().map(|&x| x as i32).collect();
        let mut adjncy: Vec<i32> = adjncy.iter().map(|&x| x as i32).collect();
        let mut nvtxs = n as i32;
        let mut perm = vec![0i32; n];
        let mut iperm = vec![0i32; n];
        let mut options = [0i32; metis_sys::METIS_NOPTIONS as usize];
        // SAFETY: `options` has METIS_NOPTIONS entries, as METIS_SetDefaultOptions writes.
        unsafe { metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr()) };
        // SAFETY: a valid CSR graph of `nvtxs` vertices — `xadj` has `nvtxs + 1`
        // non-decreasing entries from 0 to `adjncy.len()`, every `adjncy` entry is in
        // `0..nvtxs`, no self-loops, symmetric (built so by `vertex_adjacency`); a null
        // vertex-weight pointer is METIS's documented "no weights"; `perm` and `iperm`
        // have `nvtxs` entries. METIS reads the graph and writes only `perm`/`iperm`.
        let status = unsafe {
            metis_sys::METIS_NodeND(
                &mut nvtxs,
                xadj.as_mut_ptr(),
                adjncy.as_mut_ptr(),
                std::ptr::null_mut(),
                options.as_mut_ptr(),
                perm.as_mut_ptr(),
                iperm.as_mut_ptr(),
            )
        };
        if status != metis_sys::rstatus_et_METIS_OK {
            return Err(SolveError::Backend(format!(
                "METIS nested dissection failed (status {status})"
            )));
        }
        // METIS's `perm[new] = old`, as ours.
        Self::from_order(perm.into_iter().map(|p| p as u32).collect())
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
    /// `unknowns` numbers the values `per_vertex · v + c` (component `c` of vertex `v`);
    /// the fixed ones are not unknowns. Vertices are taken in this order, each one's
    /// components consecutively, fixed ones skipped.
    ///
    /// Whether the result is a permutation of the system's unknowns is checked by
    /// [`super::SpdSystem::with_ordering`].
    pub fn expand(&self, per_vertex: usize, unknowns: &Unknowns) -> Result<Ordering, SolveError> {
        let expected = per_vertex * self.order.len();
        if unknowns.len() != expected {
            return Err(SolveError::DimensionMismatch {
                expected,
                got: unknowns.len(),
            });
        }
        let mut forward = Vec::with_capacity(expected);
        for &v in &self.order {
            let base = per_vertex * v as usize;
            forward.extend(
                unknowns.as_slice()[base..base + per_vertex]
                    .iter()
                    .copied()
                    .filter(|&u| u != FIXED),
            );
        }
        Ok(Ordering::Custom(forward))
    }
}

/// The vertex graph of a triangle list in compressed rows (`xadj`, `adjncy`): the
/// neighbours of `v` are `adjncy[xadj[v]..xadj[v+1]]`, sorted, without `v` itself and
/// without repeats; symmetric.
fn vertex_adjacency(n: usize, triangles: &[[u32; 3]]) -> Result<(Vec<u32>, Vec<u32>), SolveError> {
    let mut count = vec![0u32; n + 1];
    for t in triangles {
        for &v in t {
            if v as usize >= n {
                return Err(SolveError::IndexOutOfRange { row: v, col: v, n });
            }
            // Each corner sees its two triangle neighbours.
            count[v as usize + 1] += 2;
        }
    }
    for v in 0..n {
        count[v + 1] += count[v];
    }
    let mut fill = count.clone();
    let mut adj = vec![0u32; count[n] as usize];
    for t in triangles {
        for k in 0..3 {
            let v = t[k] as usize;
            for w in [t[(k + 1) % 3], t[(k + 2) % 3]] {
                adj[fill[v] as usize] = w;
                fill[v] += 1;
            }
        }
    }
    drop(fill);
    // Sort and deduplicate each row in place, dropping self-loops (degenerate triangles).
    let mut xadj = vec![0u32; n + 1];
    let mut out = 0usize;
    for v in 0..n {
        let row = &mut adj[count[v] as usize..count[v + 1] as usize];
        row.sort_unstable();
        let mut last = u32::MAX;
        for k in count[v] as usize..count[v + 1] as usize {
            let w = adj[k];
            if w != last && w as usize != v {
                adj[out] = w;
                out += 1;
            }
            last = w;
        }
        xadj[v + 1] = out as u32;
    }
    adj.truncate(out);
    Ok((xadj, adj))
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

#[cfg(test)]
mod tests {
    use super::super::{SpdSystem, solve_spd};
    use super::*;
    use crate::mesh::generate::grid_disc;

    use crate::testing::Rng;

    /// A random SPD matrix on the 2×2-block pattern of a grid mesh (every vertex pair of
    /// a triangle couples all components), with vertex 0 and the `v` of vertex `last`
    /// pinned: `(dof map, triplets)`.
    fn block_system(
        triangles: &[[u32; 3]],
        nv: usize,
        rng: &mut Rng,
    ) -> (Unknowns, Vec<(u32, u32, f64)>) {
        let dof = Unknowns::new(2 * nv, [0, 1, 2 * nv - 1]);
        let mut t = Vec::new();
        let mut diag = vec![0.1; dof.count()];
        for tri in triangles {
            for i in 0..3 {
                for j in 0..i {
                    for (ci, cj) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                        let (a, b) = (
                            dof.get(2 * tri[i] as usize + ci),
                            dof.get(2 * tri[j] as usize + cj),
                        );
                        if let (Some(a), Some(b)) = (a, b) {
                            let w = rng.uniform() - 0.5;
                            t.push((a, b, w));
                            diag[a as usize] += w.abs();
                            diag[b as usize] += w.abs();
                        }
                    }
                }
            }
        }
        t.extend(
            diag.iter()
                .enumerate()
                .map(|(i, &d)| (i as u32, i as u32, d)),
        );
        (dof, t)
    }

    fn solve_with(n: usize, t: &[(u32, u32, f64)], ordering: &Ordering, b: &[f64]) -> Vec<f64> {
        let pairs: Vec<(u32, u32)> = t.iter().map(|&(i, j, _)| (i, j)).collect();
        let (mut sys, slots) = SpdSystem::with_ordering(n, &pairs, ordering).unwrap();
        let values = sys.values_mut();
        for (&(_, _, v), &s) in t.iter().zip(&slots) {
            values[s as usize] += v;
        }
        sys.factorize().unwrap();
        let mut x = b.to_vec();
        sys.solve_in_place(&mut x).unwrap();
        x
    }

    #[test]
    fn expanded_vertex_ordering_solves_like_amd() {
        let mut rng = Rng(17);
        let mesh = grid_disc(7);
        let nv = mesh.num_vertices();
        let (dof, t) = block_system(&mesh.triangles, nv, &mut rng);
        let n = 2 * nv - 3;
        let b: Vec<f64> = (0..n).map(|_| rng.uniform() - 0.5).collect();
        let vertices = VertexOrdering::of_triangles(nv, &mesh.triangles).unwrap();
        let expanded = vertices.expand(2, &dof).unwrap();
        // A reversed identity as a third, arbitrary permutation.
        let reversed = Ordering::Custom((0..n as u32).rev().collect());
        let mut reference = b.clone();
        solve_spd(n, &t, &mut [&mut reference]).unwrap(); // AMD, residual-checked
        for ordering in [Ordering::Amd, expanded, reversed] {
            let x = solve_with(n, &t, &ordering, &b);
            let diff = x
                .iter()
                .zip(&reference)
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max);
            assert!(diff < 1e-10, "{ordering:?}: {diff}");
        }
    }

    #[test]
    fn nested_dissection_is_a_permutation_and_solves_like_amd() {
        // Same system as above, ordered by METIS: the same solution; and a mesh with
        // unused vertices (isolated nodes) and a degenerate triangle (a self-loop) is
        // still ordered completely.
        let mut rng = Rng(5);
        let mesh = grid_disc(9);
        let nv = mesh.num_vertices();
        let (dof, t) = block_system(&mesh.triangles, nv, &mut rng);
        let n = 2 * nv - 3;
        let b: Vec<f64> = (0..n).map(|_| rng.uniform() - 0.5).collect();
        let nd = VertexOrdering::nested_dissection(nv, &mesh.triangles).unwrap();
        let x = solve_with(n, &t, &nd.expand(2, &dof).unwrap(), &b);
        let mut reference = b.clone();
        solve_spd(n, &t, &mut [&mut reference]).unwrap();
        let diff = x
            .iter()
            .zip(&reference)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        assert!(diff < 1e-10, "{diff}");
        let mut triangles = mesh.triangles.clone();
        triangles.push([2, 2, 3]);
        let order = VertexOrdering::nested_dissection(nv + 4, &triangles).unwrap();
        inverse_permutation(order.order(), nv + 4).unwrap();
        assert!(matches!(
            VertexOrdering::nested_dissection(0, &[]),
            Err(SolveError::Empty)
        ));
        assert!(matches!(
            VertexOrdering::nested_dissection(3, &[[0, 1, 3]]),
            Err(SolveError::IndexOutOfRange { .. })
        ));
    }

    #[test]
    fn nested_dissection_beats_minimum_degree_on_a_large_grid() {
        // George (1973): nested dissection of a k×k grid has O(k² log k) fill and
        // O(k³) flops, minimum degree has no such bound; on a 250×250 triangulated grid
        // (63k vertices) METIS's order must give less fill than AMD's (measured 0.91×).
        let mesh = grid_disc(250);
        let nv = mesh.num_vertices();
        let edges: Vec<(u32, u32)> = mesh
            .triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .collect();
        let fill = |order: &VertexOrdering| {
            let (sys, _) =
                SpdSystem::with_ordering(nv, &edges, &Ordering::Custom(order.order().to_vec()))
                    .unwrap();
            sys.nnz_factor()
        };
        let amd = fill(&VertexOrdering::of_triangles(nv, &mesh.triangles).unwrap());
        let nd = fill(&VertexOrdering::nested_dissection(nv, &mesh.triangles).unwrap());
        assert!((nd as f64) < 0.95 * amd as f64, "METIS {nd} vs AMD {amd}");
        // fill_reducing picks AMD below the threshold.
        let chosen = VertexOrdering::fill_reducing(nv, &mesh.triangles).unwrap();
        assert_eq!(
            chosen,
            VertexOrdering::of_triangles(nv, &mesh.triangles).unwrap()
        );
    }

    #[test]
    fn expansion_keeps_each_vertex_together_and_skips_pins() {
        let mesh = grid_disc(4);
        let nv = mesh.num_vertices();
        let vertices = VertexOrdering::of_triangles(nv, &mesh.triangles).unwrap();
        let mut seen = vec![false; nv];
        for &v in vertices.order() {
            assert!(!std::mem::replace(&mut seen[v as usize], true));
        }
        assert!(seen.iter().all(|&s| s));
        // unknown of (v, c) = 2v + c shifted past the pinned u of vertex 3.
        let unknown = Unknowns::new(2 * nv, [6]);
        let Ordering::Custom(forward) = vertices.expand(2, &unknown).unwrap() else {
            panic!("expand gives a custom ordering")
        };
        assert_eq!(forward.len(), 2 * nv - 1);
        let vertex_of = |u: u32| if u >= 6 { u.div_ceil(2) } else { u / 2 };
        let mut k = 0;
        for &v in vertices.order() {
            let count = if v == 3 { 1 } else { 2 };
            for _ in 0..count {
                assert_eq!(vertex_of(forward[k]), v, "position {k}");
                k += 1;
            }
        }
        inverse_permutation(&forward, 2 * nv - 1).unwrap();
        assert!(matches!(
            vertices.expand(2, &Unknowns::new(2 * nv - 1, [6])),
            Err(SolveError::DimensionMismatch { .. })
        ));
    }

    #[test]
    fn vertex_ordering_reduces_fill_of_a_grid_laplacian() {
        // A 30×30 grid numbered row by row: the natural order is banded (fill ≈ 30 per
        // column); minimum degree does clearly better, as well as AMD run inside faer.
        let mesh = grid_disc(29);
        let nv = mesh.num_vertices();
        let pairs: Vec<(u32, u32)> = mesh
            .triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .collect();
        let identity = Ordering::Custom((0..nv as u32).collect());
        let amd = VertexOrdering::of_triangles(nv, &mesh.triangles)
            .unwrap()
            .expand(1, &Unknowns::new(nv, []))
            .unwrap();
        let fill = |o: &Ordering| {
            SpdSystem::with_ordering(nv, &pairs, o)
                .unwrap()
                .0
                .nnz_factor()
        };
        let (banded, minimum_degree) = (fill(&identity), fill(&amd));
        assert!(banded > 25 * nv, "banded fill {banded}");
        assert!(
            3 * minimum_degree < 2 * banded,
            "{minimum_degree} vs {banded}"
        );
        assert!(minimum_degree <= fill(&Ordering::Amd) * 11 / 10);
    }

    #[test]
    fn invalid_orderings_are_errors() {
        let pairs = [(0, 1), (1, 2)];
        for (forward, index, value) in [(vec![0, 1, 1], 2, 1), (vec![2, 0, 3], 2, 3)] {
            assert_eq!(
                SpdSystem::with_ordering(3, &pairs, &Ordering::Custom(forward)).unwrap_err(),
                SolveError::InvalidOrdering { n: 3, index, value }
            );
        }
        assert!(matches!(
            SpdSystem::with_ordering(3, &pairs, &Ordering::Custom(vec![0, 1])),
            Err(SolveError::DimensionMismatch {
                expected: 3,
                got: 2
            })
        ));
        assert!(matches!(
            VertexOrdering::from_order(vec![1, 1]),
            Err(SolveError::InvalidOrdering { .. })
        ));
        assert!(matches!(
            VertexOrdering::of_triangles(3, &[[0, 1, 3]]),
            Err(SolveError::IndexOutOfRange { .. })
        ));
        assert_eq!(VertexOrdering::of_triangles(0, &[]), Err(SolveError::Empty));
    }
}
