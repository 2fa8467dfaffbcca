//! Cutting a surface open into a disc: the cut graph of a closed surface, a surface with
//! handles or with several boundary loops, and the mesh split along it.
//!
//! A flattening maps a disc (thesis §2.1); the thesis leaves other surfaces to future
//! work (§6.2). Any connected, orientable, manifold surface becomes a disc when it is cut
//! along a *cut graph*: a set of edges that meets every boundary loop and every handle
//! and leaves one simply connected piece. Its edges become *seams*: each seam vertex is
//! split into one copy per wedge of faces between seams, and the flattening gives each
//! copy its own UV (per-corner texture coordinates, [`super::Uvs::PerCorner`]).
//!
//! [`cut_graph`] builds the cut graph by the tree–cotree construction of Eppstein
//! (2003) in the greedy form of Erickson & Whittlesey (2005, *Greedy optimal homotopy
//! and homology generators*), on the surface with every boundary loop capped by a
//! virtual vertex (a cone over the loop, joined to it by zero-length edges):
//!
//! 1. `T`: a shortest-path tree from a root, over edge weights `ℓ(e)·(1 − ½·c(e))`
//!    (3D length `ℓ`, crease `c = (1 − n₁·n₂)/2` of the two face normals: seams prefer
//!    creases, where they are least visible). The root is the longest boundary loop's
//!    virtual vertex, else a vertex chosen among a few far-apart candidates for the
//!    shortest result.
//! 2. `C`: a maximum spanning tree of the dual graph over the edges not in `T`, an edge
//!    `e = uv` weighted by the length of its loop `σ(e) = d(u) + ℓ(e) + d(v)`.
//! 3. The `2g` edges in neither tree each close a loop through the root along `T`: these
//!    are the shortest system of loops through the root that cuts every handle. Every
//!    other boundary loop is joined to the root by its tree path (the shortest path
//!    between it and the root loop). A closed surface of genus 0 has neither: it is cut
//!    along the shortest path between two vertices (approximately) farthest apart.
//!
//! The cut graph is the union of those loops and paths without the virtual edges and the
//! boundary edges. [`open_along`] splits the mesh along any edge set (this one or the
//! caller's seams) and checks that the result is a disc. Cost: `O(F log F)` per root
//! candidate (Dijkstra and a sort); [`open_along`] is `O(F)` with a union–find over
//! triangle corners.

use super::validate::{Defect, DefectKind, validate};
use super::{IndexError, Topology, TriMesh};
use crate::vec3::{cross3, dot3, norm3, sub3};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A mesh cut open into a disc along seams.
#[derive(Clone, Debug, PartialEq)]
pub struct OpenedMesh {
    /// The disc: the input's positions, then one more copy of every seam vertex per
    /// extra wedge; the input's triangles in their order, renumbered onto the copies.
    /// A vertex `v` of the input keeps index `v` for its first copy.
    pub mesh: TriMesh,
    /// For every vertex of [`Self::mesh`], its vertex in the input.
    pub original_vertex: Vec<u32>,
    /// The seams: interior edges of the input that were cut, `[low, high]` vertex
    /// indices, sorted.
    pub seams: Vec<[u32; 2]>,
}

impl OpenedMesh {
    /// Total 3D length of the seams.
    pub fn seam_length(&self, positions: &[[f64; 3]]) -> f64 {
        seam_length(positions, &self.seams)
    }
}

/// Total 3D length of the edges `seams` (vertex pairs into `positions`).
pub fn seam_length(positions: &[[f64; 3]], seams: &[[u32; 2]]) -> f64 {
    seams
        .iter()
        .map(|&[a, b]| norm3(sub3(positions[a as usize], positions[b as usize])))
        .sum()
}

/// Why a surface could not be cut into a disc.
#[derive(Clone, Debug, thiserror::Error)]
pub enum CutError {
    #[error(transparent)]
    Index(#[from] IndexError),
    /// Defects no cut can fix (several components, non-manifold edges or vertices,
    /// non-orientable or inconsistently oriented faces, degenerate faces, non-finite
    /// coordinates), each with its remedy.
    #[error("the mesh cannot be cut into a disc:\n{}", super::validate::list_defects(.0))]
    Defects(Vec<Defect>),
    #[error(
        "seam {index} ({a}, {b}) is not an edge of the mesh; seams are pairs of vertices joined by an edge (vertex indices from 0)"
    )]
    NotAnEdge { index: usize, a: u32, b: u32 },
    #[error(
        "cut along the seams, the surface is still not a disc: {components} component(s), {boundary_loops} boundary loop(s), genus {genus}; {remedy}"
    )]
    NotADisc {
        components: usize,
        boundary_loops: usize,
        genus: String,
        remedy: &'static str,
    },
}

/// The cut graph of a connected, orientable, manifold surface (module docs): interior
/// edges, as `[low, high]` vertex pairs, sorted, that open the surface into a disc. Empty
/// for a disc.
pub fn cut_graph(mesh: &TriMesh, topology: &Topology) -> Result<Vec<[u32; 2]>, CutError> {
    cut_graph_avoiding(mesh, topology, |_| false)
}

/// [`cut_graph`] with no seam along or through the faces where `avoid` is true (for
/// example the fans that fill holes, [`super::repair::fill_holes`], which are dropped
/// from the map afterwards: a seam that met a filled hole twice would cut off the
/// surface between). Every edge with an endpoint on such a face weighs
/// [`AVOID_FACTOR`] times the whole surface, so no shortest path touches those faces
/// while another way exists, and an edge between two such faces `AVOID_FACTOR` times
/// more, so a path that must touch them runs along their rim, not through them.
pub fn cut_graph_avoiding(
    mesh: &TriMesh,
    topology: &Topology,
    avoid: impl Fn(u32) -> bool,
) -> Result<Vec<[u32; 2]>, CutError> {
    check_cuttable(mesh, topology)?;
    let mut graph = CutProblem::new(mesh, topology);
    let heavy = AVOID_FACTOR * graph.weight.iter().sum::<f64>().max(f64::MIN_POSITIVE);
    let mut touched = vec![false; mesh.positions.len()];
    for (f, tri) in mesh.triangles.iter().enumerate() {
        if avoid(f as u32) {
            tri.iter().for_each(|&v| touched[v as usize] = true);
        }
    }
    for (e, (w, &[a, b])) in graph.weight.iter_mut().zip(&topology.edges).enumerate() {
        if topology.faces_of_edge(e).iter().all(|&f| avoid(f)) {
            // Inside an avoided region (a fill's spokes): a seam through it would enter
            // and leave the region at two places; going along its rim is cheaper.
            *w = heavy * AVOID_FACTOR;
        } else if touched[a as usize] || touched[b as usize] {
            *w = heavy;
        }
    }
    let genus = topology.genus().unwrap_or(0) as usize;
    let edges = if !graph.loops.is_empty() {
        graph.cut_from(graph.loop_node(graph.longest_loop()), None, genus)
    } else if genus == 0 {
        // Closed, genus 0: the path between two vertices (approximately) farthest apart.
        let first = first_used_vertex(mesh);
        let a = graph.farthest(first);
        let b = graph.farthest(a);
        graph.cut_from(a, Some(b), 0)
    } else {
        // Closed with handles: the shortest loop system over a few far-apart roots.
        graph
            .root_candidates(
                first_used_vertex(mesh),
                (ROOT_BUDGET / mesh.triangles.len().max(1)).clamp(4, 32),
            )
            .into_iter()
            .map(|root| graph.cut_from(root, None, genus))
            .min_by(|a, b| graph.length(a).total_cmp(&graph.length(b)))
            .unwrap_or_default()
    };
    let mut seams: Vec<[u32; 2]> = edges
        .into_iter()
        .filter(|&e| topology.faces_of_edge(e as usize).len() == 2)
        .map(|e| topology.edges[e as usize])
        .collect();
    seams.sort_unstable();
    Ok(seams)
}

/// Cuts `mesh` into a disc along its [`cut_graph`] ([`open_along`]).
pub fn cut_to_disc(mesh: &TriMesh) -> Result<OpenedMesh, CutError> {
    mesh.check_indices()?;
    let topology = Topology::new(mesh);
    let seams = cut_graph(mesh, &topology)?;
    open_along(mesh, &topology, &seams)
}

/// Splits `mesh` along `seams` (vertex pairs joined by an edge; boundary edges and
/// repeats are ignored) and checks that the result is a disc.
pub fn open_along(
    mesh: &TriMesh,
    topology: &Topology,
    seams: &[[u32; 2]],
) -> Result<OpenedMesh, CutError> {
    check_cuttable(mesh, topology)?;
    let mut cut = vec![false; topology.edges.len()];
    for (index, &[a, b]) in seams.iter().enumerate() {
        let key = [a.min(b), a.max(b)];
        let e = topology
            .edges
            .binary_search(&key)
            .map_err(|_| CutError::NotAnEdge { index, a, b })?;
        cut[e] = true;
    }
    // Corners 3t + k of one vertex belong to one copy when their faces are joined
    // around it by uncut interior edges.
    let nf = mesh.triangles.len();
    let mut corners = UnionFind::new(3 * nf);
    let corner_of = |t: u32, v: u32| -> u32 {
        let k = mesh.triangles[t as usize]
            .iter()
            .position(|&w| w == v)
            .expect("an edge's vertex is a corner of its faces");
        3 * t + k as u32
    };
    for (e, &[a, b]) in topology.edges.iter().enumerate() {
        let faces = topology.faces_of_edge(e);
        if cut[e] || faces.len() != 2 {
            continue;
        }
        for v in [a, b] {
            corners.union(corner_of(faces[0], v), corner_of(faces[1], v));
        }
    }
    let nv = mesh.positions.len();
    let mut copy_of_class = vec![u32::MAX; 3 * nf];
    let mut first_taken = vec![false; nv];
    let mut original_vertex: Vec<u32> = (0..nv as u32).collect();
    let mut positions = mesh.positions.clone();
    let mut triangles = Vec::with_capacity(nf);
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let mut out = [0u32; 3];
        for (k, &v) in tri.iter().enumerate() {
            let class = corners.find(3 * t as u32 + k as u32) as usize;
            if copy_of_class[class] == u32::MAX {
                copy_of_class[class] = if first_taken[v as usize] {
                    positions.push(mesh.positions[v as usize]);
                    original_vertex.push(v);
                    (positions.len() - 1) as u32
                } else {
                    first_taken[v as usize] = true;
                    v
                };
            }
            out[k] = copy_of_class[class];
        }
        triangles.push(out);
    }
    let mut used_seams: Vec<[u32; 2]> = (0..topology.edges.len())
        .filter(|&e| cut[e] && topology.faces_of_edge(e).len() == 2)
        .map(|e| topology.edges[e])
        .collect();
    used_seams.sort_unstable();
    let opened = TriMesh::new(positions, triangles);
    let result = Topology::new(&opened);
    if !result.is_disc() {
        let boundary_loops = result.boundary_loops.len();
        let genus = result
            .genus()
            .map_or_else(|| "undefined".to_string(), |g| g.to_string());
        let remedy = if result.num_components > 1 {
            "the seams cut off a piece: remove seams so that one piece remains"
        } else if boundary_loops == 0 {
            "the surface is still closed: add at least one seam"
        } else if result.genus().unwrap_or(0) > 0 {
            "handles are left: add seams that cut every handle (around and along it)"
        } else {
            "several boundary loops are left: add seams that join them into one"
        };
        return Err(CutError::NotADisc {
            components: result.num_components,
            boundary_loops,
            genus,
            remedy,
        });
    }
    Ok(OpenedMesh {
        mesh: opened,
        original_vertex,
        seams: used_seams,
    })
}

/// Root candidates tried for a closed surface with handles: as many as fit in about
/// [`ROOT_BUDGET`] face visits, between 4 and 32.
const ROOT_BUDGET: usize = 2_000_000;

/// Weight of an edge to avoid, in units of the whole surface's edge weights.
pub const AVOID_FACTOR: f64 = 1e3;

/// How much cheaper a fully folded edge is than a flat one (see the module docs).
const CREASE_DISCOUNT: f64 = 0.5;

/// The defects that no cut fixes, as [`CutError::Defects`].
fn check_cuttable(mesh: &TriMesh, topology: &Topology) -> Result<(), CutError> {
    mesh.check_indices()?;
    if mesh.finite_and_proper()
        && !mesh.triangles.is_empty()
        && topology.face_edges.len() == mesh.triangles.len()
        && topology.num_components == 1
        && topology.is_manifold()
        && topology.orientable
        && topology.inconsistent_edges.is_empty()
    {
        return Ok(());
    }
    let topology = if topology.face_edges.len() == mesh.triangles.len() {
        topology.clone()
    } else {
        Topology::new(mesh)
    };
    Err(CutError::Defects(
        validate(mesh, &topology)
            .into_iter()
            .filter(|d| d.blocks_flattening && !fixed_by_cutting(d.kind))
            .collect(),
    ))
}

/// The defect kinds a cut removes.
pub fn fixed_by_cutting(kind: DefectKind) -> bool {
    matches!(
        kind,
        DefectKind::ClosedSurface | DefectKind::PositiveGenus | DefectKind::SeveralBoundaryLoops
    )
}

fn first_used_vertex(mesh: &TriMesh) -> u32 {
    mesh.triangles.first().map_or(0, |t| t[0])
}

/// The surface with its boundary loops capped (module docs), as a weighted graph:
/// nodes are the vertices, then one virtual vertex per loop.
struct CutProblem<'a> {
    topology: &'a Topology,
    num_vertices: usize,
    /// Edge weights (real edges).
    weight: Vec<f64>,
    /// Boundary loops as vertex lists.
    loops: Vec<&'a [u32]>,
    /// Offsets of each loop's vertices (and of its edges) in the concatenated lists.
    loop_offset: Vec<usize>,
    /// For each loop edge `i` of loop `h` (vertex `i` to `i + 1`): its edge id.
    loop_edge: Vec<u32>,
    /// For each real boundary edge: its index in the concatenated loop edges.
    boundary_slot: Vec<u32>,
    /// CSR adjacency over nodes: `(neighbour node, link)` where link is an edge id, or
    /// `E + k` for the virtual edge to concatenated loop vertex `k`.
    adjacency_start: Vec<u32>,
    adjacency: Vec<(u32, u32)>,
    /// Loop lengths (3D).
    loop_length: Vec<f64>,
}

/// A shortest-path tree: distance and `(parent node, link)` per node.
struct PathTree {
    distance: Vec<f64>,
    parent: Vec<(u32, u32)>,
}

impl<'a> CutProblem<'a> {
    fn new(mesh: &TriMesh, topology: &'a Topology) -> Self {
        let nv = mesh.positions.len();
        let normal = |t: u32| {
            let [a, b, c] = mesh.triangle_positions(t as usize);
            let n = cross3(sub3(b, a), sub3(c, a));
            let len = norm3(n).max(f64::MIN_POSITIVE);
            n.map(|x| x / len)
        };
        let weight: Vec<f64> = topology
            .edges
            .iter()
            .enumerate()
            .map(|(e, &[a, b])| {
                let length = norm3(sub3(mesh.positions[a as usize], mesh.positions[b as usize]));
                let crease = match topology.faces_of_edge(e) {
                    &[f, g] => 0.5 * (1.0 - dot3(normal(f), normal(g))),
                    _ => 0.0,
                };
                length * (1.0 - CREASE_DISCOUNT * crease.clamp(0.0, 1.0))
            })
            .collect();
        let loops: Vec<&[u32]> = topology
            .boundary_loops
            .iter()
            .map(|l| l.vertices.as_slice())
            .collect();
        let mut loop_offset = vec![0];
        for l in &loops {
            loop_offset.push(loop_offset.last().unwrap() + l.len());
        }
        let total = *loop_offset.last().unwrap();
        let mut loop_edge = Vec::with_capacity(total);
        let mut boundary_slot = vec![u32::MAX; topology.edges.len()];
        let mut loop_length = Vec::with_capacity(loops.len());
        for l in &loops {
            let mut length = 0.0;
            for i in 0..l.len() {
                let (a, b) = (l[i], l[(i + 1) % l.len()]);
                let e = topology
                    .edges
                    .binary_search(&[a.min(b), a.max(b)])
                    .expect("consecutive loop vertices share an edge")
                    as u32;
                boundary_slot[e as usize] = loop_edge.len() as u32;
                loop_edge.push(e);
                length += norm3(sub3(mesh.positions[a as usize], mesh.positions[b as usize]));
            }
            loop_length.push(length);
        }
        // Adjacency: real edges both ways, virtual edges both ways.
        let nodes = nv + loops.len();
        let mut degree = vec![0u32; nodes + 1];
        for &[a, b] in &topology.edges {
            degree[a as usize + 1] += 1;
            degree[b as usize + 1] += 1;
        }
        for (h, l) in loops.iter().enumerate() {
            degree[nv + h + 1] += l.len() as u32;
            for &v in *l {
                degree[v as usize + 1] += 1;
            }
        }
        for i in 0..nodes {
            degree[i + 1] += degree[i];
        }
        let adjacency_start = degree;
        let mut fill = adjacency_start.clone();
        let mut adjacency = vec![(0u32, 0u32); *adjacency_start.last().unwrap() as usize];
        let mut push = |from: u32, to: u32, link: u32| {
            adjacency[fill[from as usize] as usize] = (to, link);
            fill[from as usize] += 1;
        };
        let ne = topology.edges.len() as u32;
        for (e, &[a, b]) in topology.edges.iter().enumerate() {
            push(a, b, e as u32);
            push(b, a, e as u32);
        }
        for (h, l) in loops.iter().enumerate() {
            let node = (nv + h) as u32;
            for (i, &v) in l.iter().enumerate() {
                let link = ne + (loop_offset[h] + i) as u32;
                push(node, v, link);
                push(v, node, link);
            }
        }
        Self {
            topology,
            num_vertices: nv,
            weight,
            loops,
            loop_offset,
            loop_edge,
            boundary_slot,
            adjacency_start,
            adjacency,
            loop_length,
        }
    }

    fn num_nodes(&self) -> usize {
        self.num_vertices + self.loops.len()
    }

    fn loop_node(&self, h: usize) -> u32 {
        (self.num_vertices + h) as u32
    }

    fn longest_loop(&self) -> usize {
        (0..self.loops.len())
            .max_by(|&a, &b| self.loop_length[a].total_cmp(&self.loop_length[b]))
            .unwrap_or(0)
    }

    /// Weight of a link (0 for virtual edges).
    fn link_weight(&self, link: u32) -> f64 {
        self.weight.get(link as usize).copied().unwrap_or(0.0)
    }

    /// Dijkstra from `root`.
    fn shortest_paths(&self, root: u32) -> PathTree {
        let n = self.num_nodes();
        let mut distance = vec![f64::INFINITY; n];
        let mut parent = vec![(u32::MAX, u32::MAX); n];
        let mut heap = BinaryHeap::new();
        distance[root as usize] = 0.0;
        heap.push(Reverse((Ordered(0.0), root)));
        while let Some(Reverse((Ordered(d), u))) = heap.pop() {
            if d > distance[u as usize] {
                continue;
            }
            let range = self.adjacency_start[u as usize] as usize
                ..self.adjacency_start[u as usize + 1] as usize;
            for &(v, link) in &self.adjacency[range] {
                let dv = d + self.link_weight(link);
                if dv < distance[v as usize] {
                    distance[v as usize] = dv;
                    parent[v as usize] = (u, link);
                    heap.push(Reverse((Ordered(dv), v)));
                }
            }
        }
        PathTree { distance, parent }
    }

    /// The real vertex farthest from `from`.
    fn farthest(&self, from: u32) -> u32 {
        let tree = self.shortest_paths(from);
        (0..self.num_vertices)
            .filter(|&v| tree.distance[v].is_finite())
            .max_by(|&a, &b| tree.distance[a].total_cmp(&tree.distance[b]))
            .unwrap_or(from as usize) as u32
    }

    /// `count` far-apart vertices (farthest-point sampling from `first`).
    fn root_candidates(&self, first: u32, count: usize) -> Vec<u32> {
        let mut nearest = vec![f64::INFINITY; self.num_nodes()];
        let mut out = vec![first];
        while out.len() < count {
            let tree = self.shortest_paths(*out.last().unwrap());
            for (n, d) in nearest.iter_mut().zip(&tree.distance) {
                *n = n.min(*d);
            }
            let next = (0..self.num_vertices)
                .filter(|&v| nearest[v].is_finite())
                .max_by(|&a, &b| nearest[a].total_cmp(&nearest[b]));
            match next {
                Some(v) if nearest[v] > 0.0 => out.push(v as u32),
                _ => break,
            }
        }
        out
    }

    /// Total weight of a set of real edges.
    fn length(&self, edges: &[u32]) -> f64 {
        edges.iter().map(|&e| self.weight[e as usize]).sum()
    }

    /// The two faces (real ids, then loop-edge fan faces `F + k`) on either side of a link.
    fn dual(&self, link: u32) -> (u32, u32) {
        let nf = self.topology.face_edges.len() as u32;
        let ne = self.topology.edges.len();
        if (link as usize) < ne {
            match *self.topology.faces_of_edge(link as usize) {
                [f, g] => (f, g),
                [f] => (f, nf + self.boundary_slot[link as usize]),
                _ => unreachable!("a manifold edge has one or two faces"),
            }
        } else {
            // Virtual edge to loop vertex k = offset + i: the fans of loop edges i − 1, i.
            let k = link as usize - ne;
            let h = self.loop_offset.partition_point(|&o| o <= k) - 1;
            let (offset, len) = (self.loop_offset[h], self.loops[h].len());
            let i = k - offset;
            let before = offset + (i + len - 1) % len;
            (nf + before as u32, nf + k as u32)
        }
    }

    /// The real edges of the cut graph for the tree rooted at `root` (module docs):
    /// the `genus`·2 leftover loops, the paths from the other loops, and the path to
    /// `terminal` if given.
    fn cut_from(&self, root: u32, terminal: Option<u32>, genus: usize) -> Vec<u32> {
        let tree = self.shortest_paths(root);
        let ne = self.topology.edges.len();
        let links = ne + self.loop_edge.len();
        let mut in_tree = vec![false; links];
        for &(p, link) in &tree.parent {
            if p != u32::MAX {
                in_tree[link as usize] = true;
            }
        }
        // Dual maximum spanning tree over the links not in T, by loop length.
        let mut candidates: Vec<(f64, u32)> = (0..links as u32)
            .filter(|&l| !in_tree[l as usize])
            .map(|l| {
                let (u, v) = self.endpoints(l);
                let sigma =
                    tree.distance[u as usize] + tree.distance[v as usize] + self.link_weight(l);
                (sigma, l)
            })
            .collect();
        candidates.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let faces = self.topology.face_edges.len() + self.loop_edge.len();
        let mut dual = UnionFind::new(faces);
        let mut leftover = Vec::with_capacity(2 * genus);
        for &(_, l) in &candidates {
            let (f, g) = self.dual(l);
            if !dual.union(f, g) {
                leftover.push(l);
            }
        }
        debug_assert_eq!(leftover.len(), 2 * genus, "2g edges close the handle loops");
        // Union of the loops and paths, walking up T until a node already on the cut.
        let mut on_cut = vec![false; self.num_nodes()];
        on_cut[root as usize] = true;
        let mut edges = Vec::new();
        let mut climb = |mut node: u32, edges: &mut Vec<u32>| {
            while !on_cut[node as usize] {
                on_cut[node as usize] = true;
                let (p, link) = tree.parent[node as usize];
                if p == u32::MAX {
                    break; // unreachable node: not on this component
                }
                if (link as usize) < ne {
                    edges.push(link);
                }
                node = p;
            }
        };
        for &l in &leftover {
            let (u, v) = self.endpoints(l);
            climb(u, &mut edges);
            climb(v, &mut edges);
            if (l as usize) < ne {
                edges.push(l);
            }
        }
        for h in 0..self.loops.len() {
            climb(self.loop_node(h), &mut edges);
        }
        if let Some(t) = terminal {
            climb(t, &mut edges);
        }
        edges.sort_unstable();
        edges.dedup();
        edges
    }

    /// The two nodes a link joins.
    fn endpoints(&self, link: u32) -> (u32, u32) {
        let ne = self.topology.edges.len();
        if (link as usize) < ne {
            let [a, b] = self.topology.edges[link as usize];
            (a, b)
        } else {
            let k = link as usize - ne;
            let h = self.loop_offset.partition_point(|&o| o <= k) - 1;
            let v = self.loops[h][k - self.loop_offset[h]];
            (self.loop_node(h), v)
        }
    }
}

/// `f64` with a total order (for the heap).
#[derive(Clone, Copy, PartialEq)]
struct Ordered(f64);

impl Eq for Ordered {}

impl PartialOrd for Ordered {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ordered {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// Union–find with path halving.
struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
        }
    }

    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let grand = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = grand;
            x = grand;
        }
        x
    }

    /// Joins the sets of `a` and `b`; `false` when they were one set already.
    fn union(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        self.parent[ra.max(rb) as usize] = ra.min(rb);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{grid_disc, holed_plate, octahedron, sphere, torus};

    /// Cuts, then checks the result is a disc whose vertices are copies of the input's,
    /// with every input triangle kept (same corners, up to copies).
    fn cut_and_check(mesh: &TriMesh) -> OpenedMesh {
        let opened = cut_to_disc(mesh).unwrap();
        assert!(Topology::new(&opened.mesh).is_disc());
        assert_eq!(opened.mesh.triangles.len(), mesh.triangles.len());
        for (t, tri) in opened.mesh.triangles.iter().enumerate() {
            assert_eq!(
                tri.map(|v| opened.original_vertex[v as usize]),
                mesh.triangles[t]
            );
        }
        for (v, &o) in opened.original_vertex.iter().enumerate() {
            assert_eq!(opened.mesh.positions[v], mesh.positions[o as usize]);
        }
        opened
    }

    #[test]
    fn a_disc_needs_no_cut() {
        let mesh = grid_disc(4);
        let opened = cut_and_check(&mesh);
        assert!(opened.seams.is_empty());
        assert_eq!(opened.mesh, mesh);
    }

    #[test]
    fn a_sphere_is_cut_along_a_path_between_far_points() {
        let mesh = sphere(3);
        let opened = cut_and_check(&mesh);
        // A simple path: every seam vertex has one or two seam edges, two have one.
        let mut degree = vec![0; mesh.positions.len()];
        for &[a, b] in &opened.seams {
            degree[a as usize] += 1;
            degree[b as usize] += 1;
        }
        assert_eq!(degree.iter().filter(|&&d| d == 1).count(), 2);
        assert!(degree.iter().all(|&d| d <= 2));
        // Between (approximately) antipodal points: about half a great circle, π.
        let length = opened.seam_length(&mesh.positions);
        assert!(length > 0.9 * std::f64::consts::PI, "{length}");
        assert!(length < 1.3 * std::f64::consts::PI, "{length}");
        // Interior path vertices are split in two, the ends are not.
        assert_eq!(
            opened.mesh.positions.len(),
            mesh.positions.len() + opened.seams.len() - 1
        );
    }

    #[test]
    fn a_torus_is_cut_along_two_short_loops() {
        let (big, small) = (2.0, 0.5);
        let mesh = torus(big, small, 48, 16);
        let opened = cut_and_check(&mesh);
        // Shortest loops through one point: a meridian (2πr) and the inner equator
        // (2π(R − r)), as polygons a little shorter.
        let length = opened.seam_length(&mesh.positions);
        let ideal = std::f64::consts::TAU * (small + big - small);
        assert!(
            length > 0.95 * ideal && length < 1.1 * ideal,
            "{length} vs {ideal}"
        );
    }

    #[test]
    fn a_genus_three_surface_is_cut_into_one_disc() {
        let mesh = holed_plate(3, 2);
        assert_eq!(Topology::new(&mesh).genus(), Some(3));
        let opened = cut_and_check(&mesh);
        assert!(!opened.seams.is_empty());
    }

    #[test]
    fn holes_are_joined_by_paths_to_the_outer_loop() {
        // A 9×9 grid with three vertex stars removed: four boundary loops, genus 0.
        let mut mesh = grid_disc(8);
        let holes = [2 * 9 + 2, 5 * 9 + 5, 6 * 9 + 2];
        mesh.triangles
            .retain(|t| !holes.iter().any(|h| t.contains(h)));
        assert_eq!(Topology::new(&mesh).boundary_loops.len(), 4);
        let opened = cut_and_check(&mesh);
        // Each hole is joined by a shortest path to the outer loop (the root) or to a
        // hole on the way: at most its distance to the outer loop, 1, 2 and 1 edges of
        // length 1/8 (planar: no crease discount).
        let length = opened.seam_length(&mesh.positions);
        assert!(opened.seams.len() >= 3);
        assert!(length <= 4.0 / 8.0 + 1e-12, "{length}");
    }

    #[test]
    fn user_seams_are_honoured_and_checked() {
        let mesh = octahedron();
        // A path over three edges from the north pole through the equator to the south.
        let seams = [[4, 0], [0, 2], [2, 5]];
        let opened = open_along(&mesh, &Topology::new(&mesh), &seams).unwrap();
        assert_eq!(opened.seams, vec![[0, 2], [0, 4], [2, 5]]);
        // Two interior path vertices split in two: 6 + 2 vertices.
        assert_eq!(opened.mesh.positions.len(), 8);
        // Not an edge: opposite poles.
        let err = open_along(&mesh, &Topology::new(&mesh), &[[4, 5]]).unwrap_err();
        assert!(
            matches!(
                err,
                CutError::NotAnEdge {
                    index: 0,
                    a: 4,
                    b: 5
                }
            ),
            "{err}"
        );
        // No seam at all: still closed.
        let err = open_along(&mesh, &Topology::new(&mesh), &[]).unwrap_err();
        assert!(err.to_string().contains("add at least one seam"), "{err}");
        // A seam loop cuts the octahedron in two.
        let err = open_along(
            &mesh,
            &Topology::new(&mesh),
            &[[0, 2], [2, 1], [1, 3], [3, 0]],
        )
        .unwrap_err();
        assert!(err.to_string().contains("cut off a piece"), "{err}");
        // A torus cut along one loop only keeps an annulus.
        let t = torus(2.0, 0.5, 12, 6);
        let meridian: Vec<[u32; 2]> = (0..6).map(|j| [j, (j + 1) % 6]).collect();
        let err = open_along(&t, &Topology::new(&t), &meridian).unwrap_err();
        assert!(err.to_string().contains("join them into one"), "{err}");
    }

    #[test]
    fn defects_a_cut_cannot_fix_are_refused_with_their_remedy() {
        let mut mesh = sphere(1);
        mesh.triangles[3].swap(1, 2);
        let err = cut_to_disc(&mesh).unwrap_err();
        assert!(
            matches!(&err, CutError::Defects(d) if d.iter().all(|d| d.kind == DefectKind::InconsistentOrientation)),
            "{err}"
        );
        assert!(err.to_string().contains("reorient"), "{err}");
        let mut two = sphere(1);
        let n = two.positions.len() as u32;
        two.positions
            .extend(sphere(1).positions.iter().map(|p| [p[0] + 3.0, p[1], p[2]]));
        two.triangles
            .extend(sphere(1).triangles.iter().map(|t| t.map(|v| v + n)));
        let err = cut_to_disc(&two).unwrap_err();
        assert!(err.to_string().contains("components"), "{err}");
    }
}
