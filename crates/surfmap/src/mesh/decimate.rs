//! Topology-preserving decimation of a disc by half-edge collapses, with a replayable
//! history (the coarse level of a multilevel flattening start).
//!
//! A half-edge collapse `u → v` deletes vertex `u`: the one or two faces of edge `uv`
//! are deleted and `u` is replaced by `v` in every other face of its star; `v` keeps
//! its position. Vertex indices and face ids stay the ORIGINAL ones throughout: a face
//! is either deleted or has one corner replaced, so its identity persists, and undoing
//! the collapses in reverse order gives back the input face list exactly.
//!
//! Collapses are taken cheapest first (lazy priority queue with version stamps) by the
//! quadric error of Garland & Heckbert (*Surface simplification using quadric error
//! metrics*, SIGGRAPH 1997): each vertex carries `Q = Σ w·(n·x + d)²` over the planes
//! of its (merged) faces, area-weighted, plus planes through its boundary edges
//! perpendicular to their face (weight `boundary_weight·|e|²`) so the boundary keeps its
//! shape. The cost of `u → v` is `(Q_u + Q_v)(p_v) + length_weight·|p_u − p_v|⁴`; the
//! length term (same units, L⁴) orders collapses by edge length where the surface is
//! flat, which keeps the coarse triangles near uniform in size.
//!
//! A collapse is allowed only if the mesh stays a manifold, consistently oriented disc
//! with sensible triangles (see [`DecimateOptions`] and `can_collapse`):
//! - link condition: the common neighbours of `u` and `v` are exactly the opposite
//!   vertices of the faces of edge `uv` (Dey et al., *Topology preserving edge
//!   contraction*, 1999); with the boundary treated as a virtual vertex this also
//!   means: a boundary vertex only collapses along a boundary edge into its boundary
//!   neighbour, and an interior edge with both ends on the boundary is never collapsed;
//! - the boundary loop keeps at least 4 vertices, and no vertex ends with valence < 3;
//! - no face of `u`'s star turns its 3D normal by more than `max_normal_change_deg` or
//!   drops below the quality floor `4√3·A/Σl² ≥ min_quality` (unless it was already
//!   below and does not get worse).
//!
//! Cost: `O(F log F)` for the topology check, then `O(log F)` per collapse (bounded
//! valence); the vertex–face adjacency is a circular doubly linked list over corners,
//! so the collapse loop does not allocate once its buffers are warm.

use super::{Topology, TriMesh};

/// No vertex / no face.
const NONE: u32 = u32::MAX;

/// Options of [`decimate_with`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DecimateOptions {
    /// Stop when this many (used) vertices are left.
    pub target_vertices: usize,
    /// Largest rotation of a face normal allowed in one collapse, in degrees (default
    /// 60°). A fold is a rotation beyond 90°; 60° keeps a margin against folds while
    /// still letting curved regions (whose normals turn by tens of degrees per coarse
    /// edge) be decimated.
    pub max_normal_change_deg: f64,
    /// Quality floor `4√3·A/(l₁² + l₂² + l₃²)` (1 for an equilateral triangle) for the
    /// faces a collapse changes (default 0.05, about a 3°–3°–174° sliver or a 1:20
    /// isosceles needle). A face already below the floor may change if it does not get
    /// worse.
    pub min_quality: f64,
    /// Weight of the boundary planes relative to the area-weighted face planes
    /// (default 10).
    pub boundary_weight: f64,
    /// Weight of the `|e|⁴` edge-length term of the cost (default 0.01).
    pub length_weight: f64,
}

impl Default for DecimateOptions {
    fn default() -> Self {
        Self {
            target_vertices: 20_000,
            max_normal_change_deg: 60.0,
            min_quality: 0.05,
            boundary_weight: 10.0,
            length_weight: 0.01,
        }
    }
}

/// Why a mesh cannot be decimated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DecimateError {
    #[error("the mesh has no faces: there is nothing to decimate")]
    NoFaces,
    #[error("triangle {triangle} uses vertex {vertex}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        triangle: usize,
        vertex: u32,
        vertices: usize,
    },
    #[error(
        "vertex {vertex} has a NaN or infinite coordinate; fix the exporter or drop it (--drop-unreferenced if no face uses it)"
    )]
    NonFiniteCoordinates { vertex: u32 },
    #[error(
        "triangle {triangle} uses vertex {vertex} twice; remove such faces first (--drop-degenerate)"
    )]
    RepeatedIndexFace { triangle: usize, vertex: u32 },
    #[error(
        "the mesh has {0} connected components; decimation needs one disc (use --keep-largest)"
    )]
    SeveralComponents(usize),
    #[error(
        "the mesh is not manifold ({edges} edges with more than two faces, {vertices} vertices with several fans); repair it first"
    )]
    NonManifold { edges: usize, vertices: usize },
    #[error(
        "the triangles are not consistently oriented ({0} edges are traversed twice in the same direction); use --reorient"
    )]
    InconsistentOrientation(usize),
    #[error("the mesh is closed (no boundary); cut it open into a disc first")]
    Closed,
    #[error(
        "the mesh has {0} boundary loops; decimation needs a disc with exactly one (--fill-holes, or cut)"
    )]
    SeveralBoundaryLoops(usize),
    #[error("the mesh has genus {0}; cut it into a disc first")]
    PositiveGenus(u32),
    #[error("invalid decimation option: {0}")]
    InvalidOption(&'static str),
}

/// A face deleted by a collapse, with its vertex triple at deletion time (orientation as
/// stored).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct DeletedFace {
    pub face: u32,
    pub vertices: [u32; 3],
}

/// One half-edge collapse `removed → into`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Collapse {
    /// The vertex that disappeared.
    pub removed: u32,
    /// The neighbour it was merged into (which keeps its position).
    pub into: u32,
    /// The faces of edge `removed–into` (1 on the boundary, 2 inside); only the first
    /// `num_deleted` entries are meaningful, see [`Collapse::deleted`].
    pub deleted_faces: [DeletedFace; 2],
    pub num_deleted: u8,
    /// The faces in which `removed` was replaced by `into` are
    /// `Decimation::changed_faces[changed_start..changed_end]`, see
    /// [`Decimation::changed`].
    pub changed_start: u32,
    pub changed_end: u32,
}

impl Collapse {
    /// The 1 or 2 faces deleted by this collapse.
    pub fn deleted(&self) -> &[DeletedFace] {
        &self.deleted_faces[..self.num_deleted as usize]
    }
}

/// The result of [`decimate`]: the coarse face state and the history that leads back to
/// the input.
#[derive(Clone, Debug, PartialEq)]
pub struct Decimation {
    /// The coarse mesh's faces by original face id, in original vertex indices (`None` =
    /// deleted): the face state after the last collapse.
    pub faces: Vec<Option<[u32; 3]>>,
    /// Collapses in the order performed.
    pub collapses: Vec<Collapse>,
    /// Packed lists of changed faces, one range per collapse.
    pub changed_faces: Vec<u32>,
    /// Used vertices left.
    pub num_vertices: usize,
    /// Whether `target_vertices` was reached; `false` when no valid collapse was left.
    pub reached_target: bool,
}

impl Decimation {
    /// Faces in which `c.removed` was replaced by `c.into` (their current triple has
    /// `into`).
    pub fn changed(&self, c: &Collapse) -> &[u32] {
        &self.changed_faces[c.changed_start as usize..c.changed_end as usize]
    }

    /// Undoes collapse `c` on a face state that is the state right after `c`: restores
    /// its deleted faces and puts `removed` back in place of `into` in its changed faces.
    pub fn undo(&self, faces: &mut [Option<[u32; 3]>], c: &Collapse) {
        for d in c.deleted() {
            faces[d.face as usize] = Some(d.vertices);
        }
        for &f in self.changed(c) {
            if let Some(tri) = &mut faces[f as usize] {
                for v in tri.iter_mut().filter(|v| **v == c.into) {
                    *v = c.removed;
                }
            }
        }
    }

    /// Redoes collapse `c` on the face state right before it (the inverse of
    /// [`Decimation::undo`]).
    pub fn redo(&self, faces: &mut [Option<[u32; 3]>], c: &Collapse) {
        for d in c.deleted() {
            faces[d.face as usize] = None;
        }
        for &f in self.changed(c) {
            if let Some(tri) = &mut faces[f as usize] {
                for v in tri.iter_mut().filter(|v| **v == c.removed) {
                    *v = c.into;
                }
            }
        }
    }

    /// The input face list, by undoing every collapse in reverse order.
    pub fn original_faces(&self) -> Vec<Option<[u32; 3]>> {
        let mut faces = self.faces.clone();
        for c in self.collapses.iter().rev() {
            self.undo(&mut faces, c);
        }
        faces
    }

    /// The coarse mesh with compact indices, and the map compact → original vertex
    /// index (the surviving vertices, sorted). Triangles are listed in original face
    /// order; positions are copied from `mesh`.
    pub fn coarse_mesh(&self, mesh: &TriMesh) -> (TriMesh, Vec<u32>) {
        let mut compact = vec![NONE; mesh.positions.len()];
        for tri in self.faces.iter().flatten() {
            for &v in tri {
                compact[v as usize] = 0;
            }
        }
        let mut original = Vec::with_capacity(self.num_vertices);
        for (v, c) in compact.iter_mut().enumerate() {
            if *c == 0 {
                *c = original.len() as u32;
                original.push(v as u32);
            }
        }
        let triangles = self
            .faces
            .iter()
            .flatten()
            .map(|tri| tri.map(|v| compact[v as usize]))
            .collect();
        let positions = original
            .iter()
            .map(|&v| mesh.positions[v as usize])
            .collect();
        (TriMesh::new(positions, triangles), original)
    }
}

/// Decimates the disc `mesh` to `target_vertices` vertices with default options (see
/// [`decimate_with`]).
pub fn decimate(mesh: &TriMesh, target_vertices: usize) -> Result<Decimation, DecimateError> {
    let topology = Topology::new(mesh);
    decimate_with(
        mesh,
        &topology,
        &DecimateOptions {
            target_vertices,
            ..Default::default()
        },
    )
}

/// Decimates the disc `mesh` (with its topology `topology`, from [`Topology::new`]) by
/// half-edge collapses until `options.target_vertices` used vertices are left or no
/// valid collapse remains (then `reached_target` is false). Deterministic.
///
/// Errors: anything but one manifold, consistently oriented disc with finite
/// coordinates and proper triangles, or out-of-range options.
pub fn decimate_with(
    mesh: &TriMesh,
    topology: &Topology,
    options: &DecimateOptions,
) -> Result<Decimation, DecimateError> {
    check_options(options)?;
    check_disc(mesh, topology)?;
    let mut state = State::new(mesh, topology, options);
    let target = options.target_vertices;
    while state.live > target {
        let Some(entry) = state.heap.pop() else { break };
        let u = entry.vertex;
        if entry.stamp != state.stamp[u as usize] || state.head[u as usize] == NONE {
            continue; // superseded by a cheaper entry, or u is gone
        }
        state.queued[u as usize] = f64::INFINITY;
        let v = state.target[u as usize];
        if v == NONE {
            continue; // stuck until its neighbourhood changes
        }
        if state.cost_now[u as usize] > entry.cost {
            // The entry was a lower bound: the cost grew since it was queued.
            state.enqueue(u);
            continue;
        }
        if state.can_collapse(u, v) {
            state.collapse(u, v);
            state.compact_heap();
            continue;
        }
        // The cheap choice is no longer (or was never) valid: the cheapest valid one.
        let best = state.best_valid_target(u);
        state.set_choice(u, best);
        state.enqueue(u);
    }
    Ok(state.finish(target))
}

fn check_options(o: &DecimateOptions) -> Result<(), DecimateError> {
    if !(o.max_normal_change_deg > 0.0 && o.max_normal_change_deg <= 180.0) {
        return Err(DecimateError::InvalidOption(
            "max_normal_change_deg must be in (0, 180]",
        ));
    }
    if !(0.0..1.0).contains(&o.min_quality) {
        return Err(DecimateError::InvalidOption(
            "min_quality must be in [0, 1)",
        ));
    }
    if !(o.boundary_weight >= 0.0 && o.boundary_weight.is_finite()) {
        return Err(DecimateError::InvalidOption(
            "boundary_weight must be finite and ≥ 0",
        ));
    }
    if !(o.length_weight >= 0.0 && o.length_weight.is_finite()) {
        return Err(DecimateError::InvalidOption(
            "length_weight must be finite and ≥ 0",
        ));
    }
    Ok(())
}

/// One manifold, consistently oriented disc with finite coordinates and proper faces.
fn check_disc(mesh: &TriMesh, topology: &Topology) -> Result<(), DecimateError> {
    if mesh.triangles.is_empty() {
        return Err(DecimateError::NoFaces);
    }
    if let Some((t, k)) = mesh.first_invalid_index() {
        return Err(DecimateError::IndexOutOfRange {
            triangle: t,
            vertex: mesh.triangles[t][k],
            vertices: mesh.positions.len(),
        });
    }
    if topology.face_edges.len() != mesh.triangles.len() {
        return Err(DecimateError::InvalidOption(
            "the topology does not belong to this mesh",
        ));
    }
    for (t, &[a, b, c]) in mesh.triangles.iter().enumerate() {
        if a == b || a == c || b == c {
            let vertex = if a == b || a == c { a } else { b };
            return Err(DecimateError::RepeatedIndexFace {
                triangle: t,
                vertex,
            });
        }
        for v in [a, b, c] {
            if mesh.positions[v as usize].iter().any(|x| !x.is_finite()) {
                return Err(DecimateError::NonFiniteCoordinates { vertex: v });
            }
        }
    }
    if topology.num_components != 1 {
        return Err(DecimateError::SeveralComponents(topology.num_components));
    }
    if !topology.is_manifold() {
        return Err(DecimateError::NonManifold {
            edges: topology.non_manifold_edges.len(),
            vertices: topology.non_manifold_vertices.len(),
        });
    }
    if !topology.inconsistent_edges.is_empty() || !topology.orientable {
        return Err(DecimateError::InconsistentOrientation(
            topology.inconsistent_edges.len(),
        ));
    }
    match topology.boundary_loops.len() {
        0 => return Err(DecimateError::Closed),
        1 => {}
        n => return Err(DecimateError::SeveralBoundaryLoops(n)),
    }
    match topology.genus() {
        Some(0) => Ok(()),
        Some(g) => Err(DecimateError::PositiveGenus(g)),
        None => Err(DecimateError::NonManifold {
            edges: topology.non_manifold_edges.len(),
            vertices: topology.non_manifold_vertices.len(),
        }),
    }
}

/// Symmetric quadric `Q(x) = xᵀA x + 2 bᵀx + c`, stored as
/// `[a00, a01, a02, a11, a12, a22, b0, b1, b2, c]`.
#[derive(Clone, Copy, Debug, Default)]
struct Quadric([f64; 10]);

impl Quadric {
    /// `w·(n·x + d)²` for the plane `n·x + d = 0` (`n` a unit normal).
    fn plane(n: [f64; 3], d: f64, w: f64) -> Self {
        Quadric([
            w * n[0] * n[0],
            w * n[0] * n[1],
            w * n[0] * n[2],
            w * n[1] * n[1],
            w * n[1] * n[2],
            w * n[2] * n[2],
            w * d * n[0],
            w * d * n[1],
            w * d * n[2],
            w * d * d,
        ])
    }

    fn add(&mut self, o: &Quadric) {
        for (a, b) in self.0.iter_mut().zip(&o.0) {
            *a += b;
        }
    }

    /// `Q(x)`.
    #[inline]
    fn at(&self, x: [f64; 3]) -> f64 {
        let q = &self.0;
        let [x0, x1, x2] = x;
        x0 * (q[0] * x0 + 2.0 * (q[1] * x1 + q[2] * x2 + q[6]))
            + x1 * (q[3] * x1 + 2.0 * (q[4] * x2 + q[7]))
            + x2 * (q[5] * x2 + 2.0 * q[8])
            + q[9]
    }
}

#[inline]
fn xyz(p: [f64; 4]) -> [f64; 3] {
    [p[0], p[1], p[2]]
}
#[inline]
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
#[inline]
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Twice the area vector `(q − p) × (r − p)` and the quality `4√3·A/Σl²` of triangle
/// `pqr`.
#[inline]
fn normal_and_quality(p: [f64; 3], q: [f64; 3], r: [f64; 3]) -> ([f64; 3], f64) {
    let (e1, e2, e3) = (sub(q, p), sub(r, p), sub(r, q));
    let n = cross(e1, e2);
    let l2 = dot(e1, e1) + dot(e2, e2) + dot(e3, e3);
    let quality = if l2 > 0.0 {
        2.0 * 3f64.sqrt() * dot(n, n).sqrt() / l2
    } else {
        0.0
    };
    (n, quality)
}

/// Priority queue entry: a lower bound `cost` on the cheapest collapse of `vertex` (its
/// current choice is `State::target` at `State::cost_now`), live while `stamp` matches
/// the vertex's stamp. A vertex's cost only gets a new entry when it drops below the
/// queued one; when it grows, the old entry is re-queued at the current cost once it
/// is popped (lazy evaluation), which keeps the heap small.
#[derive(Clone, Copy, Debug)]
struct Entry {
    cost: f64,
    vertex: u32,
    stamp: u32,
}

impl Entry {
    /// Pops first: smaller cost, then smaller vertex (deterministic ties).
    #[inline]
    fn before(&self, o: &Entry) -> bool {
        self.cost < o.cost
            || (self.cost == o.cost && (self.vertex, self.stamp) < (o.vertex, o.stamp))
    }
}

/// A 4-ary min-heap of [`Entry`]: half the depth of a binary heap, and the four
/// children of a node share one or two cache lines, which matters at a million
/// entries (`std`'s `BinaryHeap` spent a third of the decimation time in `pop`).
#[derive(Default)]
struct MinHeap {
    data: Vec<Entry>,
}

impl MinHeap {
    fn from_vec(data: Vec<Entry>) -> Self {
        let mut heap = MinHeap { data };
        heap.rebuild();
        heap
    }

    fn len(&self) -> usize {
        self.data.len()
    }

    fn rebuild(&mut self) {
        let n = self.data.len();
        if n > 1 {
            for i in (0..=(n - 2) / 4).rev() {
                self.sift_down(i);
            }
        }
    }

    fn push(&mut self, e: Entry) {
        let mut i = self.data.len();
        self.data.push(e);
        while i > 0 {
            let parent = (i - 1) / 4;
            if !e.before(&self.data[parent]) {
                break;
            }
            self.data[i] = self.data[parent];
            i = parent;
        }
        self.data[i] = e;
    }

    fn pop(&mut self) -> Option<Entry> {
        let last = self.data.pop()?;
        if self.data.is_empty() {
            return Some(last);
        }
        let top = std::mem::replace(&mut self.data[0], last);
        self.sift_down(0);
        Some(top)
    }

    fn sift_down(&mut self, mut i: usize) {
        let n = self.data.len();
        let e = self.data[i];
        loop {
            let first = 4 * i + 1;
            if first >= n {
                break;
            }
            let mut best = first;
            for c in first + 1..(first + 4).min(n) {
                if self.data[c].before(&self.data[best]) {
                    best = c;
                }
            }
            if !self.data[best].before(&e) {
                break;
            }
            self.data[i] = self.data[best];
            i = best;
        }
        self.data[i] = e;
    }

    fn retain(&mut self, keep: impl Fn(&Entry) -> bool) {
        self.data.retain(keep);
        self.rebuild();
    }
}

/// The mutable mesh during decimation.
struct State {
    /// Position relative to the bounding-box center (quadrics stay well conditioned)
    /// and, in the fourth slot, the vertex's own quadric error `Q_v(p_v)` (one cache
    /// line for what a cost evaluation needs of the target).
    pos: Vec<[f64; 4]>,
    /// Current triple of each face; `[NONE; 3]` once deleted.
    faces: Vec<[u32; 3]>,
    /// Circular doubly linked list of the corners `3f + k` around each vertex.
    next: Vec<u32>,
    prev: Vec<u32>,
    /// A corner of each vertex, `NONE` when the vertex is unused or removed.
    head: Vec<u32>,
    /// Faces around each vertex.
    num_faces: Vec<u32>,
    /// Boundary successor / predecessor (surface on the left), `NONE` inside.
    bnext: Vec<u32>,
    bprev: Vec<u32>,
    loop_len: usize,
    quadric: Vec<Quadric>,
    stamp: Vec<u32>,
    /// Current choice of each vertex (`NONE`: none) and its cost.
    target: Vec<u32>,
    cost_now: Vec<f64>,
    /// Cost of the vertex's live heap entry (∞: none).
    queued: Vec<f64>,
    heap: MinHeap,
    live: usize,
    cos_max_turn: f64,
    min_quality: f64,
    length_weight: f64,
    // History.
    collapses: Vec<Collapse>,
    changed_faces: Vec<u32>,
    // Reused buffers.
    corners: Vec<u32>,
    ring: Vec<u32>,
    candidates: Vec<(f64, u32)>,
    to_requeue: Vec<u32>,
    old_ring: Vec<u32>,
}

impl State {
    fn new(mesh: &TriMesh, topology: &Topology, o: &DecimateOptions) -> Self {
        let nv = mesh.positions.len();
        let nf = mesh.triangles.len();
        let center = match mesh.bounding_box() {
            Some((lo, hi)) => std::array::from_fn(|k| 0.5 * (lo[k] + hi[k])),
            None => [0.0; 3],
        };
        let pos: Vec<[f64; 4]> = mesh
            .positions
            .iter()
            .map(|&p| {
                let [x, y, z] = sub(p, center);
                [x, y, z, 0.0]
            })
            .collect();

        // Corner lists: corner 3f + k belongs to vertex triangles[f][k].
        let mut head = vec![NONE; nv];
        let mut next = vec![NONE; 3 * nf];
        let mut prev = vec![NONE; 3 * nf];
        let mut num_faces = vec![0u32; nv];
        for (f, tri) in mesh.triangles.iter().enumerate() {
            for (k, &v) in tri.iter().enumerate() {
                let c = (3 * f + k) as u32;
                let v = v as usize;
                num_faces[v] += 1;
                if head[v] == NONE {
                    head[v] = c;
                    next[c as usize] = c;
                    prev[c as usize] = c;
                } else {
                    // Insert c before head (at the tail).
                    let h = head[v];
                    let t = prev[h as usize];
                    next[t as usize] = c;
                    prev[c as usize] = t;
                    next[c as usize] = h;
                    prev[h as usize] = c;
                }
            }
        }
        let live = head.iter().filter(|&&h| h != NONE).count();

        // Face quadrics, area-weighted; remember unit normals for the boundary planes.
        let mut quadric = vec![Quadric::default(); nv];
        for tri in &mesh.triangles {
            let [a, b, c] = tri.map(|v| xyz(pos[v as usize]));
            let n = cross(sub(b, a), sub(c, a));
            let len = dot(n, n).sqrt();
            if len > 0.0 {
                let unit = n.map(|x| x / len);
                let q = Quadric::plane(unit, -dot(unit, a), 0.5 * len);
                for &v in tri {
                    quadric[v as usize].add(&q);
                }
            }
        }

        // Boundary loop (oriented with the faces) and boundary planes.
        let mut bnext = vec![NONE; nv];
        let mut bprev = vec![NONE; nv];
        let boundary = &topology.boundary_loops[0].vertices;
        let m = boundary.len();
        for i in 0..m {
            let (a, b) = (boundary[i], boundary[(i + 1) % m]);
            bnext[a as usize] = b;
            bprev[b as usize] = a;
        }
        let mut state = State {
            pos,
            faces: mesh.triangles.clone(),
            next,
            prev,
            head,
            num_faces,
            bnext,
            bprev,
            loop_len: m,
            quadric,
            stamp: vec![0; nv],
            target: vec![NONE; nv],
            cost_now: vec![f64::INFINITY; nv],
            queued: vec![f64::INFINITY; nv],
            heap: MinHeap::default(),
            live,
            cos_max_turn: o.max_normal_change_deg.to_radians().cos(),
            min_quality: o.min_quality,
            length_weight: o.length_weight,
            collapses: Vec::new(),
            changed_faces: Vec::new(),
            corners: Vec::new(),
            ring: Vec::new(),
            candidates: Vec::new(),
            to_requeue: Vec::new(),
            old_ring: Vec::new(),
        };
        for i in 0..m {
            let (a, b) = (boundary[i], boundary[(i + 1) % m]);
            // The face of boundary edge a → b.
            let Some(f) = state.face_with_edge(a, b) else {
                continue;
            };
            let [p, q, r] = state.faces[f as usize].map(|v| state.p(v));
            let n = cross(sub(q, p), sub(r, p));
            let (pa, pb) = (state.p(a), state.p(b));
            let e = sub(pb, pa);
            let m = cross(e, n);
            let len = dot(m, m).sqrt();
            if len > 0.0 {
                let unit = m.map(|x| x / len);
                let q = Quadric::plane(unit, -dot(unit, pa), o.boundary_weight * dot(e, e));
                state.quadric[a as usize].add(&q);
                state.quadric[b as usize].add(&q);
            }
        }

        for v in 0..nv {
            state.pos[v][3] = state.quadric[v].at(state.p(v as u32));
        }
        let mut entries = Vec::with_capacity(live);
        for u in 0..nv as u32 {
            if state.head[u as usize] != NONE
                && let Some((cost, v)) = state.cheapest_target(u)
            {
                state.target[u as usize] = v;
                state.cost_now[u as usize] = cost;
                state.queued[u as usize] = cost;
                entries.push(Entry {
                    cost,
                    vertex: u,
                    stamp: 0,
                });
            }
        }
        state.heap = MinHeap::from_vec(entries);
        state
    }

    #[inline]
    fn p(&self, v: u32) -> [f64; 3] {
        xyz(self.pos[v as usize])
    }

    /// The face that traverses the directed edge `a → b`.
    fn face_with_edge(&self, a: u32, b: u32) -> Option<u32> {
        let h = self.head[a as usize];
        if h == NONE {
            return None;
        }
        let mut c = h;
        loop {
            let (f, k) = ((c / 3) as usize, (c % 3) as usize);
            if self.faces[f][(k + 1) % 3] == b {
                return Some(f as u32);
            }
            c = self.next[c as usize];
            if c == h {
                return None;
            }
        }
    }

    /// Fills `out` with the corners of `u`.
    fn corners_of(&self, u: u32, out: &mut Vec<u32>) {
        out.clear();
        let h = self.head[u as usize];
        if h == NONE {
            return;
        }
        let mut c = h;
        loop {
            out.push(c);
            c = self.next[c as usize];
            if c == h {
                break;
            }
        }
    }

    /// Each neighbour of `u` once: the next vertex of every face of `u`, plus the
    /// boundary predecessor (the one neighbour that only follows `u` in no face).
    fn neighbours_of(&self, u: u32, out: &mut Vec<u32>) {
        out.clear();
        let h = self.head[u as usize];
        if h != NONE {
            let mut c = h;
            loop {
                let (f, k) = ((c / 3) as usize, (c % 3) as usize);
                out.push(self.faces[f][(k + 1) % 3]);
                c = self.next[c as usize];
                if c == h {
                    break;
                }
            }
        }
        if self.bprev[u as usize] != NONE {
            out.push(self.bprev[u as usize]);
        }
    }

    fn is_boundary(&self, v: u32) -> bool {
        self.bnext[v as usize] != NONE
    }

    fn valence(&self, v: u32) -> u32 {
        self.num_faces[v as usize] + self.is_boundary(v) as u32
    }

    /// Cost of the half-edge collapse `u → v`: `(Q_u + Q_v)(p_v) + λ|p_u − p_v|⁴`.
    #[inline]
    fn cost(&self, u: u32, v: u32) -> f64 {
        let (pu, [x, y, z, own]) = (self.p(u), self.pos[v as usize]);
        let pv = [x, y, z];
        let e = sub(pu, pv);
        let l2 = dot(e, e);
        self.quadric[u as usize].at(pv) + own + self.length_weight * l2 * l2
    }

    /// Fills `candidates` with the targets `u` may collapse into by the boundary rules
    /// alone (boundary vertex: its two boundary neighbours while the loop has more than
    /// 4 vertices; interior vertex: every neighbour), with their costs.
    fn candidates_of(&self, u: u32, candidates: &mut Vec<(f64, u32)>, ring: &mut Vec<u32>) {
        candidates.clear();
        if self.is_boundary(u) {
            if self.loop_len > 4 {
                for v in [self.bnext[u as usize], self.bprev[u as usize]] {
                    candidates.push((self.cost(u, v), v));
                }
            }
        } else {
            self.neighbours_of(u, ring);
            for &v in ring.iter() {
                candidates.push((self.cost(u, v), v));
            }
        }
    }

    /// The cheapest target by the boundary rules only (validity is checked on pop).
    fn cheapest_target(&mut self, u: u32) -> Option<(f64, u32)> {
        let (mut candidates, mut ring) = (
            std::mem::take(&mut self.candidates),
            std::mem::take(&mut self.ring),
        );
        self.candidates_of(u, &mut candidates, &mut ring);
        let best = candidates
            .iter()
            .copied()
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        self.candidates = candidates;
        self.ring = ring;
        best
    }

    /// The cheapest target whose collapse is valid now.
    fn best_valid_target(&mut self, u: u32) -> Option<(f64, u32)> {
        let (mut candidates, mut ring) = (
            std::mem::take(&mut self.candidates),
            std::mem::take(&mut self.ring),
        );
        self.candidates_of(u, &mut candidates, &mut ring);
        self.ring = ring;
        candidates.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let best = candidates
            .iter()
            .copied()
            .find(|&(_, v)| self.can_collapse(u, v));
        self.candidates = candidates;
        best
    }

    /// Whether the half-edge collapse `u → v` keeps a manifold disc with valence ≥ 3,
    /// turns no face normal beyond the limit and makes no face worse than the quality
    /// floor (module docs).
    fn can_collapse(&mut self, u: u32, v: u32) -> bool {
        let (ub, vb) = (self.is_boundary(u), self.is_boundary(v));
        if ub {
            // Only along a boundary edge, and the loop keeps ≥ 4 vertices.
            let along = self.bnext[u as usize] == v || self.bprev[u as usize] == v;
            if !along || self.loop_len <= 4 {
                return false;
            }
        }
        let mut corners = std::mem::take(&mut self.corners);
        let mut ring = std::mem::take(&mut self.ring);
        let ok = self.check_star(u, v, vb, &mut corners, &mut ring);
        self.corners = corners;
        self.ring = ring;
        ok
    }

    fn check_star(
        &self,
        u: u32,
        v: u32,
        vb: bool,
        corners: &mut Vec<u32>,
        ring: &mut Vec<u32>,
    ) -> bool {
        self.corners_of(u, corners);
        // Faces of edge uv, their opposite vertices; the neighbours of u.
        let mut opposite = [NONE; 2];
        let mut num_shared = 0usize;
        for &c in corners.iter() {
            let tri = self.faces[(c / 3) as usize];
            if tri.contains(&v) {
                if num_shared == 2 {
                    return false;
                }
                opposite[num_shared] = tri[0] ^ tri[1] ^ tri[2] ^ u ^ v;
                num_shared += 1;
            }
        }
        let edge_is_boundary = self.bnext[u as usize] == v || self.bnext[v as usize] == u;
        if num_shared != if edge_is_boundary { 1 } else { 2 } {
            return false;
        }
        // Link condition: N(u) ∩ N(v) = the opposite vertices.
        self.neighbours_of(u, ring);
        let split = ring.len();
        let mut common = 0usize;
        {
            let h = self.head[v as usize];
            let mut c = h;
            loop {
                let (f, k) = ((c / 3) as usize, (c % 3) as usize);
                let x = self.faces[f][(k + 1) % 3];
                if x != u && ring[..split].contains(&x) {
                    common += 1;
                }
                c = self.next[c as usize];
                if c == h {
                    break;
                }
            }
            let x = self.bprev[v as usize];
            if x != NONE && x != u && ring[..split].contains(&x) {
                common += 1;
            }
        }
        if common != num_shared {
            return false;
        }
        // Valence ≥ 3 after the collapse.
        for &o in &opposite[..num_shared] {
            if self.valence(o) < 4 {
                return false;
            }
        }
        let faces_v =
            self.num_faces[v as usize] + self.num_faces[u as usize] - 2 * num_shared as u32;
        if faces_v + (vb as u32) < 3 {
            return false;
        }
        // Geometry of the faces that keep u's corner (u moves to p_v).
        let pv = self.p(v);
        for &c in corners.iter() {
            let (f, k) = ((c / 3) as usize, (c % 3) as usize);
            let tri = self.faces[f];
            if tri.contains(&v) {
                continue;
            }
            let (a, b) = (self.p(tri[(k + 1) % 3]), self.p(tri[(k + 2) % 3]));
            let (n0, q0) = normal_and_quality(self.p(u), a, b);
            let (n1, q1) = normal_and_quality(pv, a, b);
            let (l0, l1) = (dot(n0, n0).sqrt(), dot(n1, n1).sqrt());
            if l1 == 0.0 || dot(n0, n1) < self.cos_max_turn * l0 * l1 {
                return false;
            }
            if q1 < self.min_quality.min(q0) {
                return false;
            }
        }
        true
    }

    fn unlink(&mut self, v: u32, c: u32) {
        let (n, p) = (self.next[c as usize], self.prev[c as usize]);
        if n == c {
            self.head[v as usize] = NONE;
        } else {
            self.next[p as usize] = n;
            self.prev[n as usize] = p;
            if self.head[v as usize] == c {
                self.head[v as usize] = n;
            }
        }
        self.num_faces[v as usize] -= 1;
    }

    /// Performs `u → v` (valid by [`State::can_collapse`]), records it and requeues `v`
    /// and its neighbours.
    fn collapse(&mut self, u: u32, v: u32) {
        let mut old_ring = std::mem::take(&mut self.old_ring);
        self.neighbours_of(u, &mut old_ring);
        let mut corners = std::mem::take(&mut self.corners);
        self.corners_of(u, &mut corners);
        let changed_start = self.changed_faces.len() as u32;
        let mut deleted_faces = [DeletedFace::default(); 2];
        let mut num_deleted = 0u8;
        for &c in &corners {
            let (f, k) = ((c / 3) as usize, (c % 3) as usize);
            let tri = self.faces[f];
            if tri.contains(&v) {
                deleted_faces[num_deleted as usize] = DeletedFace {
                    face: f as u32,
                    vertices: tri,
                };
                num_deleted += 1;
                for (j, &w) in tri.iter().enumerate() {
                    self.unlink(w, (3 * f + j) as u32);
                }
                self.faces[f] = [NONE; 3];
            } else {
                self.faces[f][k] = v;
                self.changed_faces.push(f as u32);
            }
        }
        self.corners = corners;
        // Splice u's remaining corners into v's list.
        let (hu, hv) = (self.head[u as usize], self.head[v as usize]);
        if hv == NONE {
            // All of v's faces were deleted (v was a boundary ear): it takes u's list.
            self.head[v as usize] = hu;
        } else if hu != NONE {
            let (tu, tv) = (self.prev[hu as usize], self.prev[hv as usize]);
            self.next[tv as usize] = hu;
            self.prev[hu as usize] = tv;
            self.next[tu as usize] = hv;
            self.prev[hv as usize] = tu;
        }
        self.head[u as usize] = NONE;
        self.num_faces[v as usize] += self.num_faces[u as usize];
        self.num_faces[u as usize] = 0;
        // Boundary loop.
        if self.is_boundary(u) {
            let (n, p) = (self.bnext[u as usize], self.bprev[u as usize]);
            if n == v {
                self.bnext[p as usize] = v;
                self.bprev[v as usize] = p;
            } else {
                self.bprev[n as usize] = v;
                self.bnext[v as usize] = n;
            }
            self.bnext[u as usize] = NONE;
            self.bprev[u as usize] = NONE;
            self.loop_len -= 1;
        }
        let qu = self.quadric[u as usize];
        self.quadric[v as usize].add(&qu);
        self.pos[v as usize][3] = self.quadric[v as usize].at(self.p(v));
        self.stamp[u as usize] += 1;
        self.target[u as usize] = NONE;
        self.queued[u as usize] = f64::INFINITY;
        self.live -= 1;
        self.collapses.push(Collapse {
            removed: u,
            into: v,
            deleted_faces,
            num_deleted,
            changed_start,
            changed_end: self.changed_faces.len() as u32,
        });
        // Requeue v and those of its new ring whose cheapest choice may have changed.
        // A former neighbour of v (not of u) keeps its quadric and its other
        // neighbours, and its cost to v only grew (Q_v grew by the positive
        // semi-definite Q_u), so its queued choice stands unless it was v. Former
        // neighbours of u have v as a new neighbour; stuck vertices (no valid choice
        // when last popped) are retried since their neighbourhood changed.
        let mut ring = std::mem::take(&mut self.ring);
        self.neighbours_of(v, &mut ring);
        let mut to_requeue = std::mem::take(&mut self.to_requeue);
        to_requeue.clear();
        to_requeue.push(v);
        to_requeue.extend(ring.iter().copied().filter(|&w| {
            let t = self.target[w as usize];
            t == v || t == NONE || old_ring.contains(&w)
        }));
        self.old_ring = old_ring;
        self.ring = ring;
        for &w in &to_requeue {
            self.requeue(w);
        }
        self.to_requeue = to_requeue;
    }

    /// Recomputes the cheap choice of `w` and queues it if it got cheaper.
    fn requeue(&mut self, w: u32) {
        let best = self.cheapest_target(w);
        self.set_choice(w, best);
        if self.cost_now[w as usize] < self.queued[w as usize] {
            self.enqueue(w);
        }
    }

    fn set_choice(&mut self, w: u32, choice: Option<(f64, u32)>) {
        let (cost, t) = choice.unwrap_or((f64::INFINITY, NONE));
        self.target[w as usize] = t;
        self.cost_now[w as usize] = cost;
    }

    /// Queues `w` at its current cost (superseding its live entry), if it has a choice.
    fn enqueue(&mut self, w: u32) {
        let cost = self.cost_now[w as usize];
        if self.target[w as usize] == NONE {
            return;
        }
        self.stamp[w as usize] += 1;
        self.queued[w as usize] = cost;
        self.heap.push(Entry {
            cost,
            vertex: w,
            stamp: self.stamp[w as usize],
        });
    }

    /// Drops stale entries when they outnumber the live ones (bounds the heap's memory).
    fn compact_heap(&mut self) {
        if self.heap.len() > 2 * self.live + 1024 {
            let stamp = &self.stamp;
            let head = &self.head;
            self.heap
                .retain(|e| e.stamp == stamp[e.vertex as usize] && head[e.vertex as usize] != NONE);
        }
    }

    fn finish(self, target: usize) -> Decimation {
        let faces = self
            .faces
            .iter()
            .map(|t| (t[0] != NONE).then_some(*t))
            .collect();
        Decimation {
            faces,
            collapses: self.collapses,
            changed_faces: self.changed_faces,
            num_vertices: self.live,
            reached_target: self.live <= target,
        }
    }
}
