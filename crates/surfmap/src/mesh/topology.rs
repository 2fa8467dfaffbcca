//! Topology derived once from a triangle list: edges, edge→faces, boundary loops,
//! components, Euler characteristic, genus, manifoldness and orientation.

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
    /// For an orientable mesh, the faces to flip for a consistent orientation (the
    /// smaller side of each component); empty when not orientable.
    pub faces_to_flip_list: Vec<u32>,
}

impl Topology {
    /// Derives the topology of `mesh` in `O(F log F)` (one sort of the half-edges).
    ///
    /// Works on any triangle soup: non-manifold edges, inconsistent orientation and
    /// unreferenced vertices are recorded, never rejected. Precondition: every vertex
    /// index is below `positions.len()` (the readers guarantee it; check meshes built
    /// by hand with [`TriMesh::check_indices`]).
    pub fn new(mesh: &TriMesh) -> Self {
        let nf = mesh.triangles.len();
        let nv = mesh.positions.len();

        // Half-edge h = 3t + k runs from corner k to corner k+1 of triangle t.
        let key = |h: usize| -> u64 {
            let tri = mesh.triangles[h / 3];
            let (a, b) = (tri[h % 3], tri[(h + 1) % 3]);
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            ((lo as u64) << 32) | hi as u64
        };
        let mut order: Vec<u32> = (0..3 * nf as u32).collect();
        let mut keys: Vec<u64> = (0..3 * nf).map(key).collect();
        // Sort half-edges by their undirected edge key.
        order.sort_unstable_by_key(|&h| keys[h as usize]);

        let mut edges = Vec::with_capacity(3 * nf / 2 + 1);
        let mut face_edges = vec![[0u32; 3]; nf];
        let mut edge_face_start = Vec::with_capacity(3 * nf / 2 + 2);
        let mut edge_face_list = Vec::with_capacity(3 * nf);
        let mut i = 0;
        while i < order.len() {
            let k = keys[order[i] as usize];
            let e = edges.len() as u32;
            edges.push([(k >> 32) as u32, k as u32]);
            edge_face_start.push(edge_face_list.len() as u32);
            while i < order.len() && keys[order[i] as usize] == k {
                let h = order[i] as usize;
                face_edges[h / 3][h % 3] = e;
                edge_face_list.push((h / 3) as u32);
                i += 1;
            }
        }
        edge_face_start.push(edge_face_list.len() as u32);
        keys.clear();
        keys.shrink_to_fit();

        let faces_of = |e: usize| {
            &edge_face_list[edge_face_start[e] as usize..edge_face_start[e + 1] as usize]
        };

        // Used vertices.
        let mut used = vec![false; nv];
        for tri in &mesh.triangles {
            for &v in tri {
                if (v as usize) < nv {
                    used[v as usize] = true;
                }
            }
        }
        let num_used_vertices = used.iter().filter(|&&u| u).count();

        // Non-manifold edges; orientation consistency of manifold interior edges.
        let mut non_manifold_edges = Vec::new();
        let mut inconsistent_edges = Vec::new();
        let direction = |t: u32, e: [u32; 2]| -> bool {
            // true when triangle t traverses edge e from e[0] to e[1]
            let tri = mesh.triangles[t as usize];
            (0..3).any(|k| tri[k] == e[0] && tri[(k + 1) % 3] == e[1])
        };
        for (e, &ev) in edges.iter().enumerate() {
            let fs = faces_of(e);
            if fs.len() > 2 {
                non_manifold_edges.push(e as u32);
            } else if fs.len() == 2 && direction(fs[0], ev) == direction(fs[1], ev) {
                inconsistent_edges.push(e as u32);
            }
        }

        // Components: faces sharing a vertex (union-find over vertices).
        let mut uf = UnionFind::new(nv);
        for tri in &mesh.triangles {
            if tri.iter().all(|&v| (v as usize) < nv) {
                uf.union(tri[0], tri[1]);
                uf.union(tri[0], tri[2]);
            }
        }
        let mut root_id = vec![u32::MAX; nv];
        let mut num_components = 0usize;
        let face_component: Vec<u32> = mesh
            .triangles
            .iter()
            .map(|tri| {
                let r = uf.find(tri[0].min(nv.saturating_sub(1) as u32)) as usize;
                if root_id[r] == u32::MAX {
                    root_id[r] = num_components as u32;
                    num_components += 1;
                }
                root_id[r]
            })
            .collect();

        // Orientation: propagate a flip bit across manifold edges (breadth-first).
        let (orientable, faces_to_flip_list) = orient_faces(
            mesh,
            &edges,
            &face_edges,
            &faces_of,
            &direction,
            num_components,
            &face_component,
        );

        let boundary_loops = boundary_loops(mesh, &edges, &faces_of, nv);
        let non_manifold_vertices = non_manifold_vertices(mesh, &edges, &face_edges, &faces_of, nv);

        Topology {
            edges,
            face_edges,
            edge_face_start,
            edge_face_list,
            boundary_loops,
            face_component,
            num_components,
            num_used_vertices,
            non_manifold_edges,
            non_manifold_vertices,
            inconsistent_edges,
            orientable,
            faces_to_flip: orientable.then_some(faces_to_flip_list.len()),
            faces_to_flip_list,
        }
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
    /// For each of `num_vertices` vertices, whether a boundary loop passes through it.
    pub fn on_boundary(&self, num_vertices: usize) -> Vec<bool> {
        let mut on = vec![false; num_vertices];
        for l in &self.boundary_loops {
            l.vertices.iter().for_each(|&v| on[v as usize] = true);
        }
        on
    }
}

/// Boundary loops: connected components of the graph of edges used by exactly one
/// face. Each loop is walked in the direction of its faces' half-edges where that is
/// consistent, so that on an oriented disc the interior lies to the left.
fn boundary_loops<'a>(
    mesh: &TriMesh,
    edges: &[[u32; 2]],
    faces_of: &impl Fn(usize) -> &'a [u32],
    nv: usize,
) -> Vec<BoundaryLoop> {
    // Directed boundary half-edges (from, to) as the owning face traverses them.
    let mut out_start = vec![0u32; nv + 1];
    let mut bedges: Vec<(u32, u32)> = Vec::new();
    for (e, &[a, b]) in edges.iter().enumerate() {
        let fs = faces_of(e);
        if fs.len() == 1 {
            let tri = mesh.triangles[fs[0] as usize];
            let forward = (0..3).any(|k| tri[k] == a && tri[(k + 1) % 3] == b);
            bedges.push(if forward { (a, b) } else { (b, a) });
        }
    }
    if bedges.is_empty() {
        return Vec::new();
    }
    // Undirected adjacency (CSR) over boundary edges, so that loops through
    // non-manifold or inconsistently oriented vertices are still found.
    for &(a, b) in &bedges {
        out_start[a as usize + 1] += 1;
        out_start[b as usize + 1] += 1;
    }
    for v in 0..nv {
        out_start[v + 1] += out_start[v];
    }
    let mut fill = out_start.clone();
    let mut adj = vec![0u32; 2 * bedges.len()]; // boundary edge ids
    for (i, &(a, b)) in bedges.iter().enumerate() {
        for v in [a, b] {
            adj[fill[v as usize] as usize] = i as u32;
            fill[v as usize] += 1;
        }
    }
    let mut used = vec![false; bedges.len()];
    let mut loops = Vec::new();
    for seed in 0..bedges.len() {
        if used[seed] {
            continue;
        }
        // Walk from the seed edge in its face's direction, always continuing with an
        // unused boundary edge at the current vertex; for a simple loop this visits
        // its vertices in order.
        let mut vertices = Vec::new();
        let mut walked = vec![seed as u32];
        used[seed] = true;
        let mut current = bedges[seed].0;
        vertices.push(current);
        let mut next_edge = Some(seed as u32);
        while let Some(ei) = next_edge.take() {
            let (a, b) = bedges[ei as usize];
            current = if a == current { b } else { a };
            let adj_range =
                out_start[current as usize] as usize..out_start[current as usize + 1] as usize;
            for &cand in &adj[adj_range] {
                if !used[cand as usize] {
                    used[cand as usize] = true;
                    next_edge = Some(cand);
                    walked.push(cand);
                    break;
                }
            }
            if next_edge.is_some() {
                vertices.push(current);
            }
        }
        // Sweep any edges of this component the walk did not reach (figure-eight
        // boundaries through non-manifold vertices): they belong to the same loop.
        let mut frontier = walked;
        while let Some(ei) = frontier.pop() {
            let (a, b) = bedges[ei as usize];
            for v in [a, b] {
                let r = out_start[v as usize] as usize..out_start[v as usize + 1] as usize;
                for &cand in &adj[r] {
                    if !used[cand as usize] {
                        used[cand as usize] = true;
                        let (ca, cb) = bedges[cand as usize];
                        vertices.push(if ca == v { cb } else { ca });
                        frontier.push(cand);
                    }
                }
            }
        }
        loops.push(BoundaryLoop { vertices });
    }
    loops
}

/// Vertices all of whose edges are manifold but whose incident faces form more than
/// one fan (faces connected through edges containing the vertex): a "bow-tie".
/// Vertices on non-manifold edges are reported with those edges instead.
fn non_manifold_vertices<'a>(
    mesh: &TriMesh,
    edges: &[[u32; 2]],
    face_edges: &[[u32; 3]],
    faces_of: &impl Fn(usize) -> &'a [u32],
    nv: usize,
) -> Vec<u32> {
    let mut touches_nm = vec![false; nv];
    for (e, &[a, b]) in edges.iter().enumerate() {
        if faces_of(e).len() > 2 {
            touches_nm[a as usize] = true;
            touches_nm[b as usize] = true;
        }
    }
    // Incident faces per vertex (CSR).
    let mut start = vec![0u32; nv + 1];
    for tri in &mesh.triangles {
        for &v in tri {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut incident = vec![0u32; start[nv] as usize];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &v in tri {
            incident[fill[v as usize] as usize] = t as u32;
            fill[v as usize] += 1;
        }
    }
    let mut seen = Vec::new();
    let mut stack = Vec::new();
    (0..nv)
        .filter(|&v| {
            let around = &incident[start[v] as usize..start[v + 1] as usize];
            !touches_nm[v]
                && around.len() > 1
                && several_fans(
                    mesh, face_edges, faces_of, around, v as u32, &mut seen, &mut stack,
                )
        })
        .map(|v| v as u32)
        .collect()
}

/// Whether the faces `around` vertex `v` split into two or more edge-connected fans.
fn several_fans<'a>(
    mesh: &TriMesh,
    face_edges: &[[u32; 3]],
    faces_of: &impl Fn(usize) -> &'a [u32],
    around: &[u32],
    v: u32,
    seen: &mut Vec<bool>,
    stack: &mut Vec<usize>,
) -> bool {
    seen.clear();
    seen.resize(around.len(), false);
    stack.clear();
    stack.push(0);
    seen[0] = true;
    while let Some(i) = stack.pop() {
        let t = around[i] as usize;
        let tri = mesh.triangles[t];
        for k in 0..3 {
            if tri[k] != v && tri[(k + 1) % 3] != v {
                continue; // edge opposite v
            }
            for &u in faces_of(face_edges[t][k] as usize) {
                if let Some(j) = around.iter().position(|&x| x == u)
                    && !seen[j]
                {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
    }
    seen.iter().any(|s| !s)
}

/// Breadth-first propagation of orientation across manifold edges. Returns whether
/// every component is orientable and, if so, the fewest faces to flip (per component
/// the smaller side of the two-colouring), in increasing order.
fn orient_faces<'a>(
    mesh: &TriMesh,
    edges: &[[u32; 2]],
    face_edges: &[[u32; 3]],
    faces_of: &impl Fn(usize) -> &'a [u32],
    direction: &impl Fn(u32, [u32; 2]) -> bool,
    num_components: usize,
    face_component: &[u32],
) -> (bool, Vec<u32>) {
    let nf = mesh.triangles.len();
    let mut flip = vec![u8::MAX; nf];
    let mut flipped_count = vec![0usize; num_components];
    let mut comp_size = vec![0usize; num_components];
    let mut orientable = true;
    let mut queue = std::collections::VecDeque::new();
    for seed in 0..nf {
        if flip[seed] != u8::MAX {
            continue;
        }
        flip[seed] = 0;
        queue.push_back(seed);
        while let Some(t) = queue.pop_front() {
            comp_size[face_component[t] as usize] += 1;
            flipped_count[face_component[t] as usize] += flip[t] as usize;
            for &e in &face_edges[t] {
                let e = e as usize;
                let fs = faces_of(e);
                if fs.len() != 2 {
                    continue;
                }
                let other = if fs[0] as usize == t { fs[1] } else { fs[0] } as usize;
                if other == t {
                    continue;
                }
                let same_dir = direction(t as u32, edges[e]) == direction(other as u32, edges[e]);
                // Consistent neighbours traverse the shared edge in opposite directions.
                let want = flip[t] ^ same_dir as u8;
                if flip[other] == u8::MAX {
                    flip[other] = want;
                    queue.push_back(other);
                } else if flip[other] != want {
                    orientable = false;
                }
            }
        }
    }
    if !orientable {
        return (false, Vec::new());
    }
    // In each component keep the majority colour and flip the others.
    let keep_colour: Vec<u8> = (0..num_components)
        .map(|c| u8::from(2 * flipped_count[c] > comp_size[c]))
        .collect();
    let list = (0..nf as u32)
        .filter(|&t| flip[t as usize] != keep_colour[face_component[t as usize] as usize])
        .collect();
    (true, list)
}

/// Disjoint sets over vertex ids, path halving, union by size.
struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }
    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = p;
            x = p;
        }
        x
    }
    fn union(&mut self, a: u32, b: u32) {
        let (mut ra, mut rb) = (self.find(a), self.find(b));
        if ra == rb {
            return;
        }
        if self.size[ra as usize] < self.size[rb as usize] {
            std::mem::swap(&mut ra, &mut rb);
        }
        self.parent[rb as usize] = ra;
        self.size[ra as usize] += self.size[rb as usize];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(tris: &[[u32; 3]], nv: usize) -> TriMesh {
        TriMesh::new(
            (0..nv).map(|i| [i as f64, (i * i) as f64, 0.0]).collect(),
            tris.to_vec(),
        )
    }

    /// An n×n grid of quads split into triangles: a disc with V − E + F = 1.
    fn grid(n: u32) -> TriMesh {
        let mut tris = Vec::new();
        let id = |i: u32, j: u32| i * (n + 1) + j;
        for i in 0..n {
            for j in 0..n {
                tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        mesh(&tris, ((n + 1) * (n + 1)) as usize)
    }

    #[test]
    fn grid_is_a_disc_with_one_ordered_loop() {
        let m = grid(4);
        let t = Topology::new(&m);
        assert_eq!(t.edges.len(), 4 * 5 * 2 + 16);
        assert_eq!(t.euler_characteristic(), 1);
        assert_eq!(t.boundary_loops.len(), 1);
        assert!(t.is_disc());
        let lp = &t.boundary_loops[0].vertices;
        assert_eq!(lp.len(), 16);
        // consecutive loop vertices share a boundary edge
        for k in 0..lp.len() {
            let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
            let e = t
                .edges
                .iter()
                .position(|&e| e == [a.min(b), a.max(b)])
                .expect("edge");
            assert_eq!(t.faces_of_edge(e).len(), 1);
        }
    }

    #[test]
    fn tetrahedron_is_closed_genus_zero() {
        let m = mesh(&[[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], 4);
        let t = Topology::new(&m);
        assert_eq!(t.euler_characteristic(), 2);
        assert!(t.boundary_loops.is_empty());
        assert_eq!(t.genus(), Some(0));
        assert!(t.orientable && t.inconsistent_edges.is_empty());
        assert!(!t.is_disc());
    }

    #[test]
    fn flipped_face_is_found_and_counted() {
        let mut m = grid(3);
        let tri = &mut m.triangles[4];
        tri.swap(1, 2);
        let t = Topology::new(&m);
        assert_eq!(t.inconsistent_edges.len(), 3);
        assert!(t.orientable);
        assert_eq!(t.faces_to_flip, Some(1));
    }

    #[test]
    fn bowtie_vertex_and_fin_edge() {
        // Two triangles sharing only vertex 0.
        let m = mesh(&[[0, 1, 2], [0, 3, 4]], 5);
        let t = Topology::new(&m);
        assert_eq!(t.non_manifold_vertices, vec![0]);
        assert_eq!(t.num_components, 1);
        assert_eq!(t.genus(), None);
        // Three triangles on one edge.
        let m = mesh(&[[0, 1, 2], [1, 0, 3], [0, 1, 4]], 5);
        let t = Topology::new(&m);
        assert_eq!(t.non_manifold_edges.len(), 1);
        assert!(t.non_manifold_vertices.is_empty());
    }

    #[test]
    fn moebius_strip_is_not_orientable() {
        // A strip of 5 quads whose ends are glued with a half twist.
        let n = 5u32;
        let mut tris = Vec::new();
        for i in 0..n {
            let (a, b) = (2 * i, 2 * i + 1);
            let (c, d) = if i + 1 == n {
                (1, 0)
            } else {
                (2 * i + 2, 2 * i + 3)
            };
            tris.push([a, c, b]);
            tris.push([b, c, d]);
        }
        let t = Topology::new(&mesh(&tris, 2 * n as usize));
        assert!(!t.orientable);
        assert_eq!(t.faces_to_flip, None);
        assert_eq!(t.boundary_loops.len(), 1);
        assert_eq!(t.euler_characteristic(), 0);
    }

    #[test]
    fn components_and_unreferenced_vertices() {
        let m = mesh(&[[0, 1, 2], [3, 4, 5]], 7);
        let t = Topology::new(&m);
        assert_eq!(t.num_components, 2);
        assert_eq!(t.num_used_vertices, 6);
        assert_eq!(t.euler_characteristic(), 2);
        assert_eq!(t.boundary_loops.len(), 2);
    }
}
