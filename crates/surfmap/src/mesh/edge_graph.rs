//! The graph of a mesh's edges weighted by their lengths, and shortest paths over it
//! (the distortion-driven cuts' seam paths, the geodesic crop's ball).

use super::{Topology, TriMesh};
use crate::vec3::{norm3, sub3};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The vertex graph of a mesh's edges with their 3D lengths (CSR).
pub(crate) struct EdgeGraph {
    start: Vec<u32>,
    /// `(neighbour, edge length)`.
    neighbours: Vec<(u32, f64)>,
}

impl EdgeGraph {
    pub(crate) fn new(mesh: &TriMesh, topology: &Topology) -> Self {
        let n = mesh.positions.len();
        let mut start = vec![0u32; n + 1];
        for &[a, b] in &topology.edges {
            start[a as usize + 1] += 1;
            start[b as usize + 1] += 1;
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut neighbours = vec![(0u32, 0f64); start[n] as usize];
        for &[a, b] in &topology.edges {
            let length = norm3(sub3(mesh.positions[a as usize], mesh.positions[b as usize]));
            for (p, q) in [(a, b), (b, a)] {
                neighbours[fill[p as usize] as usize] = (q, length);
                fill[p as usize] += 1;
            }
        }
        Self { start, neighbours }
    }

    /// Dijkstra from `sources` over the edge weights `weight(a, b, length) ≥ 0`,
    /// entering only `passable` vertices, until a vertex where `stop` is true is
    /// settled: distances, parents (`u32::MAX` for none) and that vertex. Distances are
    /// ≥ 0, so their bit patterns order as their values do.
    pub(crate) fn shortest_paths(
        &self,
        sources: &[u32],
        weight: impl Fn(u32, u32, f64) -> f64,
        passable: impl Fn(u32) -> bool,
        stop: impl Fn(u32) -> bool,
    ) -> (Vec<f64>, Vec<u32>, Option<u32>) {
        let n = self.start.len() - 1;
        let mut distance = vec![f64::INFINITY; n];
        let mut parent = vec![u32::MAX; n];
        let mut heap = BinaryHeap::new();
        for &s in sources {
            distance[s as usize] = 0.0;
            heap.push(Reverse((0f64.to_bits(), s)));
        }
        while let Some(Reverse((bits, v))) = heap.pop() {
            let dv = f64::from_bits(bits);
            if dv > distance[v as usize] {
                continue;
            }
            if stop(v) {
                return (distance, parent, Some(v));
            }
            let (lo, hi) = (self.start[v as usize], self.start[v as usize + 1]);
            for &(w, length) in &self.neighbours[lo as usize..hi as usize] {
                if !passable(w) {
                    continue;
                }
                let dw = dv + weight(v, w, length);
                if dw < distance[w as usize] {
                    distance[w as usize] = dw;
                    parent[w as usize] = v;
                    heap.push(Reverse((dw.to_bits(), w)));
                }
            }
        }
        (distance, parent, None)
    }

    /// The shortest path (as [`Self::shortest_paths`]) from `from` to the first vertex
    /// where `stop` is true: its edges, `[low, high]` vertex pairs, from that vertex back
    /// to `from`; `None` when no such vertex is reached.
    pub(crate) fn path_to(
        &self,
        from: u32,
        weight: impl Fn(u32, u32, f64) -> f64,
        passable: impl Fn(u32) -> bool,
        stop: impl Fn(u32) -> bool,
    ) -> Option<Vec<[u32; 2]>> {
        let (_, parent, end) = self.shortest_paths(&[from], weight, passable, stop);
        let mut v = end?;
        let mut path = Vec::new();
        while v != from {
            let p = parent[v as usize];
            path.push([p.min(v), p.max(v)]);
            v = p;
        }
        Some(path)
    }
}
