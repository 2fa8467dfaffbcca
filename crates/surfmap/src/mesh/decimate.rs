//! Topology-preserving decimation of a disc by half-edge collapses, with a replayable
//! history (the coarse level of a multilevel flattening start).
//!
//! A half-edge collapse `u → v` deletes vertex `u`: the one or two faces of edge `uv`
//! are deleted and `u` is replaced by `v` in every other face of its star; `v` keeps
//! its position. Vertex indices and face ids stay the ORIGINAL ones throughout: a face
//! is either deleted or has one corner replaced, so its identity persists, and undoing
//! the collapses in reverse order gives back the input face list exactly.
//!
//! Collapses are taken cheapest first by the quadric error of Garland & Heckbert (*Surface simplification using quadric error
//! metrics*, SIGGRAPH 1997): each vertex carries `Q = Σ w·(n·x + d)²` over the planes
//! of its (merged) faces, area-weighted, plus planes through its boundary edges
//! perpendicular to their face (weight `boundary_weight·|e|²`) so the boundary keeps its
//! shape. The cost of `u → v` is `(Q_u + Q_v)(p_v) + length_weight·|p_u − p_v|⁴`; the
//! length term (same units, L⁴) orders collapses by edge length where the surface is
//! flat, which keeps the coarse triangles near uniform in size. Each vertex has one
//! choice (its cheapest allowed target) in a lazy priority queue: a 4-ary heap whose
//! entries are lower bounds, refreshed when popped, with version stamps to drop
//! superseded ones.
//!
//! A collapse is allowed only if the mesh stays a manifold, consistently oriented disc
//! with sensible triangles (see [`DecimateOptions`] and `can_collapse`):
//! - link condition: the common neighbours of `u` and `v` are exactly the opposite
//!   vertices of the faces of edge `uv` (Dey et al., *Topology preserving edge
//!   contraction*, 1999); with the boundary treated as a virtual vertex this also
//!   means: a boundary vertex only collapses along a boundary edge into its boundary
//!   neighbour, and an interior edge with both ends on the boundary is never collapsed;
//! - the boundary loop keeps at least 4 vertices, and no vertex drops below valence 3
//!   (a boundary vertex that starts with valence 2, like a grid corner, keeps it);
//! - no face of `u`'s star turns its 3D normal by more than `max_normal_change_deg` or
//!   drops below the quality floor `4√3·A/Σl² ≥ min_quality` (unless it was already
//!   below and does not get worse).
//!
//! Cost: `O(F log F)` for the disc check ([`Disc::new`], which [`decimate_with`] takes
//! from the caller), then `O(log F)` per collapse (bounded
//! valence). The vertex–face adjacency is a circular doubly linked list over corners
//! and the history is packed (fixed-size [`Collapse`] records plus one flat list of
//! changed faces), so the collapse loop makes no per-collapse allocation (only the
//! amortized growth of its output vectors and the heap). Lionhead subdivided 3×
//! (534k vertices) to 20k: about 1.2 s in release on one core, plus 0.4 s for
//! [`Disc::new`] (`crates/surfmap-bench/examples/decimate_bench.rs`).

use super::{Disc, NotADisc, PositionError, TriMesh};
use crate::vec3::{cross3, dot3, sub3};

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
#[derive(Debug, Clone, thiserror::Error)]
pub enum DecimateError {
    #[error(transparent)]
    NotADisc(#[from] NotADisc),
    #[error(transparent)]
    Positions(#[from] PositionError),
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
/// [`decimate_with`]); an error names every defect when `mesh` is not a disc.
pub fn decimate(mesh: &TriMesh, target_vertices: usize) -> Result<Decimation, DecimateError> {
    let disc = Disc::new(mesh)?;
    decimate_with(
        &mesh.positions,
        &disc,
        &DecimateOptions {
            target_vertices,
            ..Default::default()
        },
    )
}

/// Decimates `disc` with vertex positions `positions` by half-edge collapses until
/// `options.target_vertices` used vertices are left or no valid collapse remains (then
/// `reached_target` is false). Deterministic.
///
/// Errors: positions that do not fit the disc (count, finiteness), or out-of-range
/// options.
pub fn decimate_with(
    positions: &[[f64; 3]],
    disc: &Disc,
    options: &DecimateOptions,
) -> Result<Decimation, DecimateError> {
    check_options(options)?;
    disc.check_positions(positions)?;
    let mut state = State::new(positions, disc, options);
    let target = options.target_vertices;
    while state.live > target {
        let Some(entry) = state.heap.pop() else { break };
        let u = entry.vertex;
        if entry.stamp != state.stamp[u as usize] || state.head[u as usize] == NONE {
            continue; // superseded by a cheaper entry, or u is gone
        }
        state.queued[u as usize] = f64::INFINITY;
        state.refresh_choice(u);
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

/// Twice the area vector `(q − p) × (r − p)` and the quality `4√3·A/Σl²` of triangle
/// `pqr`.
#[inline]
fn normal_and_quality(p: [f64; 3], q: [f64; 3], r: [f64; 3]) -> ([f64; 3], f64) {
    let (e1, e2, e3) = (sub3(q, p), sub3(r, p), sub3(r, q));
    let n = cross3(e1, e2);
    let l2 = dot3(e1, e1) + dot3(e2, e2) + dot3(e3, e3);
    let quality = if l2 > 0.0 {
        2.0 * 3f64.sqrt() * dot3(n, n).sqrt() / l2
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
    old_ring: Vec<u32>,
    scratch: Vec<u32>,
    /// The choice may be worse than recorded (refresh before use).
    dirty: Vec<bool>,
}

impl State {
    fn new(positions: &[[f64; 3]], disc: &Disc, o: &DecimateOptions) -> Self {
        let triangles = disc.triangles();
        let nv = positions.len();
        let nf = triangles.len();
        let center = match super::bounding_box(positions) {
            Some((lo, hi)) => std::array::from_fn(|k| 0.5 * (lo[k] + hi[k])),
            None => [0.0; 3],
        };
        let pos: Vec<[f64; 4]> = positions
            .iter()
            .map(|&p| {
                let [x, y, z] = sub3(p, center);
                [x, y, z, 0.0]
            })
            .collect();

        // Corner lists: corner 3f + k belongs to vertex triangles[f][k].
        let mut head = vec![NONE; nv];
        let mut next = vec![NONE; 3 * nf];
        let mut prev = vec![NONE; 3 * nf];
        let mut num_faces = vec![0u32; nv];
        for (f, tri) in triangles.iter().enumerate() {
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
        for tri in triangles {
            let [a, b, c] = tri.map(|v| xyz(pos[v as usize]));
            let n = cross3(sub3(b, a), sub3(c, a));
            let len = dot3(n, n).sqrt();
            if len > 0.0 {
                let unit = n.map(|x| x / len);
                let q = Quadric::plane(unit, -dot3(unit, a), 0.5 * len);
                for &v in tri {
                    quadric[v as usize].add(&q);
                }
            }
        }

        // Boundary loop (oriented with the faces) and boundary planes.
        let mut bnext = vec![NONE; nv];
        let mut bprev = vec![NONE; nv];
        let boundary = disc.boundary();
        let m = boundary.len();
        for i in 0..m {
            let (a, b) = (boundary[i], boundary[(i + 1) % m]);
            bnext[a as usize] = b;
            bprev[b as usize] = a;
        }
        let mut state = State {
            pos,
            faces: triangles.to_vec(),
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
            old_ring: Vec::new(),
            scratch: Vec::new(),
            dirty: vec![false; nv],
        };
        for i in 0..m {
            let (a, b) = (boundary[i], boundary[(i + 1) % m]);
            // The face of boundary edge a → b.
            let Some(f) = state.face_with_edge(a, b) else {
                continue;
            };
            let [p, q, r] = state.faces[f as usize].map(|v| state.p(v));
            let n = cross3(sub3(q, p), sub3(r, p));
            let (pa, pb) = (state.p(a), state.p(b));
            let e = sub3(pb, pa);
            let m = cross3(e, n);
            let len = dot3(m, m).sqrt();
            if len > 0.0 {
                let unit = m.map(|x| x / len);
                let q = Quadric::plane(unit, -dot3(unit, pa), o.boundary_weight * dot3(e, e));
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
        let e = sub3(pu, pv);
        let l2 = dot3(e, e);
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
            let (l0, l1) = (dot3(n0, n0).sqrt(), dot3(n1, n1).sqrt());
            if l1 == 0.0 || dot3(n0, n1) < self.cos_max_turn * l0 * l1 {
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
        // Update the choices that may have become cheaper now and mark those that may
        // have grown (refreshed when popped; queued entries stay lower bounds). Only a
        // new neighbour can make a choice cheaper: v's (the former neighbours of u)
        // and v for the former neighbours of u. Every other change removes a
        // candidate (u) or raises a cost (to v: Q_v grew by the positive
        // semi-definite Q_u). Stuck vertices (no valid choice when last popped) are
        // retried since their neighbourhood changed.
        let mut ring = std::mem::take(&mut self.ring);
        self.requeue(v, &mut ring);
        for &w in &ring {
            let wi = w as usize;
            if self.target[wi] == NONE {
                let mut scratch = std::mem::take(&mut self.scratch);
                self.requeue(w, &mut scratch);
                self.scratch = scratch;
            } else if !old_ring.contains(&w) {
                // Its cost to v grew: checked when popped (refresh_choice).
            } else if deleted_faces[..num_deleted as usize]
                .iter()
                .any(|d| d.vertices.contains(&w))
            {
                // An opposite vertex: lost u, its cost to v grew.
                if self.target[wi] == u || self.target[wi] == v {
                    self.dirty[wi] = true;
                }
            } else {
                // A former neighbour of u only: v is a new neighbour.
                if self.target[wi] == u {
                    self.dirty[wi] = true;
                    self.target[wi] = NONE;
                    self.cost_now[wi] = f64::INFINITY;
                }
                if self.cheap_allowed(w, v) {
                    let c = self.cost(w, v);
                    if c < self.cost_now[wi] {
                        self.target[wi] = v;
                        self.cost_now[wi] = c;
                        if c < self.queued[wi] {
                            self.enqueue(w);
                        }
                    }
                }
                if self.target[wi] == NONE {
                    // Its only choice was u: find another now.
                    let mut scratch = std::mem::take(&mut self.scratch);
                    self.requeue(w, &mut scratch);
                    self.scratch = scratch;
                }
            }
        }
        self.old_ring = old_ring;
        self.ring = ring;
    }

    /// Whether `w → v` passes the boundary rules (a boundary vertex only along the
    /// boundary, while the loop has more than 4 vertices); `v` must be a neighbour.
    fn cheap_allowed(&self, w: u32, v: u32) -> bool {
        !self.is_boundary(w)
            || (self.loop_len > 4 && (self.bnext[w as usize] == v || self.bprev[w as usize] == v))
    }

    /// Recomputes the cheap choice of `w` exactly (filling `ring` with its
    /// neighbours) and queues it if it got cheaper than its queued entry.
    fn requeue(&mut self, w: u32, ring: &mut Vec<u32>) {
        let mut candidates = std::mem::take(&mut self.candidates);
        self.candidates_of(w, &mut candidates, ring);
        let best = candidates
            .iter()
            .copied()
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        self.candidates = candidates;
        self.set_choice(w, best);
        self.dirty[w as usize] = false;
        if self.cost_now[w as usize] < self.queued[w as usize] {
            self.enqueue(w);
        }
    }

    /// Makes the choice of `u` exact before it is used: recomputed when marked dirty or
    /// when the cost to its target changed (the target absorbed a vertex).
    fn refresh_choice(&mut self, u: u32) {
        let ui = u as usize;
        let t = self.target[ui];
        if !self.dirty[ui] && (t == NONE || self.cost(u, t) == self.cost_now[ui]) {
            return;
        }
        let best = self.cheapest_target(u);
        self.set_choice(u, best);
        self.dirty[ui] = false;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Topology;
    use crate::mesh::generate::{
        bumpy_disc, cylinder_patch, disc_boundary, grid_disc, octahedron, polar_disc,
        spherical_cap, unit_square,
    };
    use crate::mesh::validate::{DefectKind, validate};

    /// The defect kinds of a refusal.
    fn refused(result: Result<Decimation, DecimateError>) -> Vec<DefectKind> {
        match result {
            Err(DecimateError::NotADisc(NotADisc::Defects(d))) => {
                d.iter().map(|d| d.kind).collect()
            }
            other => panic!("expected a refusal with defects, got {other:?}"),
        }
    }

    fn all_some(tris: &[[u32; 3]]) -> Vec<Option<[u32; 3]>> {
        tris.iter().map(|&t| Some(t)).collect()
    }

    fn alive(faces: &[Option<[u32; 3]>]) -> Vec<[u32; 3]> {
        faces.iter().flatten().copied().collect()
    }

    /// Number of distinct neighbours of every vertex.
    fn valences(num_vertices: usize, triangles: &[[u32; 3]]) -> Vec<usize> {
        let mut neighbours = vec![Vec::new(); num_vertices];
        for t in triangles {
            for k in 0..3 {
                for j in 1..3 {
                    let (a, b) = (t[k], t[(k + j) % 3]);
                    if !neighbours[a as usize].contains(&b) {
                        neighbours[a as usize].push(b);
                    }
                }
            }
        }
        neighbours.iter().map(Vec::len).collect()
    }

    /// A face state (original indices) is a manifold, consistently oriented disc with
    /// no degenerate face, and no vertex has dropped below valence 3 (a vertex may keep
    /// a lower valence it had in `input`, e.g. a grid corner).
    fn assert_disc(
        positions: &[[f64; 3]],
        faces: &[Option<[u32; 3]>],
        input: &[[u32; 3]],
        context: &str,
    ) {
        let mesh = TriMesh::new(positions.to_vec(), alive(faces));
        let topo = Topology::new(&mesh);
        assert!(topo.is_disc(), "{context}: not a disc");
        assert!(topo.inconsistent_edges.is_empty(), "{context}: orientation");
        let blocking: Vec<_> = validate(&mesh, &topo)
            .into_iter()
            .filter(|d| {
                d.blocks_flattening
                    && d.kind != crate::mesh::validate::DefectKind::UnreferencedVertices
            })
            .collect();
        assert!(blocking.is_empty(), "{context}: {blocking:?}");
        let before = valences(positions.len(), input);
        for (v, &n) in valences(positions.len(), &mesh.triangles)
            .iter()
            .enumerate()
        {
            assert!(
                n == 0 || n >= before[v].min(3),
                "{context}: vertex {v} has valence {n}"
            );
        }
    }

    fn normal(p: [[f64; 3]; 3]) -> [f64; 3] {
        cross3(sub3(p[1], p[0]), sub3(p[2], p[0]))
    }

    #[test]
    fn coarse_mesh_is_a_disc_and_undo_restores_the_input() {
        let mesh = bumpy_disc(12, 0.5);
        let dec = decimate(&mesh, 60).unwrap();
        assert!(dec.reached_target);
        assert_eq!(dec.num_vertices, 60);
        assert_eq!(dec.collapses.len(), mesh.positions.len() - 60);
        let (coarse, original) = dec.coarse_mesh(&mesh);
        assert_eq!(coarse.positions.len(), 60);
        assert!(original.windows(2).all(|w| w[0] < w[1]));
        for (i, &o) in original.iter().enumerate() {
            assert_eq!(coarse.positions[i], mesh.positions[o as usize]);
        }
        // A disc: V − E + F = 1 and the coarse triangles are the alive faces.
        assert_eq!(coarse.triangles.len(), alive(&dec.faces).len());
        assert_disc(&mesh.positions, &dec.faces, &mesh.triangles, "coarse");
        assert_eq!(
            Topology::new(&coarse).boundary_loops.len(),
            1,
            "compact coarse mesh"
        );
        assert_eq!(dec.original_faces(), all_some(&mesh.triangles));
    }

    #[test]
    fn every_intermediate_state_is_a_disc_and_redo_reaches_the_coarse_state() {
        let mesh = spherical_cap(1.0, 2.0, 6, 16);
        let dec = decimate(&mesh, 8).unwrap();
        let mut faces = all_some(&mesh.triangles);
        for (i, c) in dec.collapses.iter().enumerate() {
            dec.redo(&mut faces, c);
            if i % 4 == 0 || i + 1 == dec.collapses.len() {
                assert_disc(
                    &mesh.positions,
                    &faces,
                    &mesh.triangles,
                    &format!("after collapse {i}"),
                );
            }
        }
        assert_eq!(faces, dec.faces);
        for c in dec.collapses.iter().rev() {
            dec.undo(&mut faces, c);
        }
        assert_eq!(faces, all_some(&mesh.triangles));
    }

    #[test]
    fn the_link_condition_refuses_a_collapse_that_would_pinch() {
        // Triangle u v x with three inner vertices a, b, c (valence 4 each), inside an
        // outer triangle o1 o2 o3: u and v share the neighbour x, which is not opposite
        // to edge uv, so u → v would glue edges ux and vx. Every other rule passes.
        let positions = vec![
            [0., 0., 0.],   // 0 u
            [6., 0., 0.],   // 1 v
            [3., 6., 0.],   // 2 x
            [3., 1., 0.],   // 3 a
            [4., 2.5, 0.],  // 4 b
            [2., 2.5, 0.],  // 5 c
            [-3., -3., 0.], // 6 o1
            [9., -3., 0.],  // 7 o2
            [3., 10., 0.],  // 8 o3
        ];
        let triangles = vec![
            [0, 1, 3],
            [1, 4, 3],
            [1, 2, 4],
            [2, 5, 4],
            [2, 0, 5],
            [0, 3, 5],
            [3, 4, 5],
            [6, 7, 1],
            [6, 1, 0],
            [7, 8, 2],
            [7, 2, 1],
            [8, 6, 0],
            [8, 0, 2],
        ];
        let mesh = TriMesh::new(positions, triangles);
        let topology = Topology::new(&mesh);
        assert!(topology.is_disc());
        let geometry_off = DecimateOptions {
            max_normal_change_deg: 180.0,
            min_quality: 0.0,
            ..Default::default()
        };
        let disc = Disc::with_topology(&mesh, topology).unwrap();
        let mut state = State::new(&mesh.positions, &disc, &geometry_off);
        assert!(!state.can_collapse(0, 1), "u → v breaks the link condition");
        assert!(state.can_collapse(3, 0), "a → u is a valid collapse");
    }

    #[test]
    fn topology_rules_alone_keep_a_disc() {
        // Geometric checks off: only the link condition, the boundary rules and the
        // valence bound stand between the collapses and a broken mesh.
        let options = DecimateOptions {
            target_vertices: 0,
            max_normal_change_deg: 180.0,
            min_quality: 0.0,
            ..Default::default()
        };
        for mesh in [
            bumpy_disc(7, 0.5),
            grid_disc(8),
            spherical_cap(1.0, 2.5, 5, 9),
        ] {
            let dec = decimate_with(&mesh.positions, &Disc::new(&mesh).unwrap(), &options).unwrap();
            let mut faces = all_some(&mesh.triangles);
            for (i, c) in dec.collapses.iter().enumerate() {
                dec.redo(&mut faces, c);
                assert_disc(
                    &mesh.positions,
                    &faces,
                    &mesh.triangles,
                    &format!("after collapse {i}"),
                );
            }
            assert!(dec.num_vertices <= 6, "{} vertices left", dec.num_vertices);
            let boundary = disc_boundary(&alive(&faces)).unwrap();
            assert!(boundary.len() >= 4, "boundary loop of {}", boundary.len());
        }
    }

    #[test]
    fn collapses_respect_the_normal_and_quality_limits() {
        let options = |target_vertices, length_weight| DecimateOptions {
            target_vertices,
            length_weight,
            ..Default::default()
        };
        // Without the length term a flat grid has all costs 0: only the quality floor
        // keeps the collapse order from making slivers.
        for (mesh, options) in [
            (bumpy_disc(10, 0.8), options(20, 0.01)),
            (cylinder_patch(1.0, 3.0, 4.0, 12, 6), options(8, 0.01)),
            (grid_disc(12), options(10, 0.0)),
        ] {
            check_normal_and_quality_limits(&mesh, options);
        }
    }

    fn check_normal_and_quality_limits(mesh: &TriMesh, options: DecimateOptions) {
        let dec = decimate_with(&mesh.positions, &Disc::new(mesh).unwrap(), &options).unwrap();
        let cos_limit = options.max_normal_change_deg.to_radians().cos();
        let mut faces = all_some(&mesh.triangles);
        let tri = |t: [u32; 3]| t.map(|v| mesh.positions[v as usize]);
        for c in &dec.collapses {
            let before: Vec<[u32; 3]> = dec
                .changed(c)
                .iter()
                .map(|&f| faces[f as usize].unwrap())
                .collect();
            dec.redo(&mut faces, c);
            for (k, &f) in dec.changed(c).iter().enumerate() {
                let after = faces[f as usize].unwrap();
                assert!(before[k].contains(&c.removed) && after.contains(&c.into));
                let (n0, n1) = (normal(tri(before[k])), normal(tri(after)));
                let cos = dot3(n0, n1) / (dot3(n0, n0) * dot3(n1, n1)).sqrt();
                assert!(
                    cos >= cos_limit - 1e-12,
                    "normal turned by {}°",
                    cos.acos().to_degrees()
                );
                let (_, q0) = normal_and_quality_ref(tri(before[k]));
                let (_, q1) = normal_and_quality_ref(tri(after));
                assert!(
                    q1 >= options.min_quality.min(q0) - 1e-12,
                    "quality {q0} → {q1}"
                );
            }
        }
    }

    /// Quality `4√3·A/Σl²` from Heron's formula (independent of the module's cross
    /// product form).
    fn normal_and_quality_ref(p: [[f64; 3]; 3]) -> ((), f64) {
        let l: Vec<f64> = (0..3)
            .map(|k| dot3(sub3(p[(k + 1) % 3], p[k]), sub3(p[(k + 1) % 3], p[k])).sqrt())
            .collect();
        let s = 0.5 * (l[0] + l[1] + l[2]);
        let area = (s * (s - l[0]) * (s - l[1]) * (s - l[2])).max(0.0).sqrt();
        (
            (),
            4.0 * 3f64.sqrt() * area / l.iter().map(|x| x * x).sum::<f64>(),
        )
    }

    #[test]
    fn a_flat_grid_decimates_without_flips_and_keeps_its_corners() {
        let mesh = grid_disc(16);
        let dec = decimate(&mesh, 30).unwrap();
        let mut faces = all_some(&mesh.triangles);
        let signed_area = |t: [u32; 3]| {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
        };
        for c in &dec.collapses {
            dec.redo(&mut faces, c);
            for t in faces.iter().flatten() {
                assert!(signed_area(*t) > 0.0, "flipped or degenerate face {t:?}");
            }
        }
        // The boundary planes keep the square: its 4 corners survive, area stays 1.
        let (coarse, original) = dec.coarse_mesh(&mesh);
        for corner in [0u32, 16, 17 * 16, 17 * 17 - 1] {
            assert!(original.contains(&corner), "corner {corner} was removed");
        }
        let area: f64 = alive(&dec.faces).iter().map(|&t| signed_area(t)).sum();
        assert!((area - 1.0).abs() < 1e-12, "area {area}");
        assert_eq!(coarse.positions.len(), 30);
    }

    #[test]
    fn boundary_vertices_only_merge_along_the_boundary() {
        for mesh in [bumpy_disc(8, 0.5), polar_disc(5, 12), grid_disc(9)] {
            let dec = decimate(&mesh, 6).unwrap();
            let mut faces = all_some(&mesh.triangles);
            let mut boundary_collapses = 0;
            for c in &dec.collapses {
                let boundary = disc_boundary(&alive(&faces)).expect("one boundary loop");
                let n = boundary.len();
                if let Some(i) = boundary.iter().position(|&v| v == c.removed) {
                    let (prev, next) = (boundary[(i + n - 1) % n], boundary[(i + 1) % n]);
                    assert!(
                        c.into == prev || c.into == next,
                        "boundary vertex {} into {}",
                        c.removed,
                        c.into
                    );
                    assert_eq!(c.deleted().len(), 1);
                    assert!(n > 4);
                    boundary_collapses += 1;
                } else {
                    assert_eq!(c.deleted().len(), 2);
                }
                dec.redo(&mut faces, c);
            }
            assert!(
                boundary_collapses > 0,
                "the test should exercise boundary collapses"
            );
            assert!(disc_boundary(&alive(&faces)).unwrap().len() >= 4);
        }
    }

    #[test]
    fn stops_when_no_valid_collapse_is_left() {
        let mesh = bumpy_disc(4, 0.3);
        let dec = decimate(&mesh, 0).unwrap();
        assert!(!dec.reached_target);
        assert!(dec.num_vertices >= 4);
        let (coarse, _) = dec.coarse_mesh(&mesh);
        assert_eq!(coarse.positions.len(), dec.num_vertices);
        assert_disc(&mesh.positions, &dec.faces, &mesh.triangles, "minimal");
        // A mesh already at the target is returned unchanged.
        let same = decimate(&mesh, mesh.positions.len()).unwrap();
        assert!(same.collapses.is_empty() && same.reached_target);
        assert_eq!(same.faces, all_some(&mesh.triangles));
    }

    #[test]
    fn decimation_is_deterministic() {
        let mesh = bumpy_disc(10, 0.6);
        assert_eq!(decimate(&mesh, 40).unwrap(), decimate(&mesh, 40).unwrap());
    }

    #[test]
    fn non_disc_input_is_refused_with_the_reason() {
        let octahedron = octahedron();
        assert_eq!(
            refused(decimate(&octahedron, 3)),
            [DefectKind::ClosedSurface]
        );

        // Annulus: a polar disc without its center fan.
        let mut annulus = polar_disc(3, 10);
        annulus.triangles.retain(|t| !t.contains(&0));
        let e = decimate(&annulus, 5).unwrap_err();
        assert!(e.to_string().contains("2 boundary loops"), "{e}");
        assert_eq!(refused(Err(e)), [DefectKind::SeveralBoundaryLoops]);

        let mut two = unit_square();
        two.positions
            .extend([[5., 0., 0.], [6., 0., 0.], [5., 1., 0.]]);
        two.triangles.push([4, 5, 6]);
        assert!(refused(decimate(&two, 3)).contains(&DefectKind::SeveralComponents));

        let mut flipped = grid_disc(3);
        flipped.triangles[4].swap(1, 2);
        assert_eq!(
            refused(decimate(&flipped, 4)),
            [DefectKind::InconsistentOrientation]
        );

        let mut fin = unit_square();
        fin.positions.push([0.5, 0.5, 1.0]);
        fin.triangles.push([0, 2, 4]);
        assert!(refused(decimate(&fin, 3)).contains(&DefectKind::NonManifoldEdges));

        let mut repeated = grid_disc(2);
        repeated.triangles[1] = [0, 0, 3];
        assert!(refused(decimate(&repeated, 4)).contains(&DefectKind::RepeatedIndexFaces));

        let mut nan = grid_disc(2);
        nan.positions[4][2] = f64::NAN;
        assert_eq!(
            refused(decimate(&nan, 4)),
            [DefectKind::NonFiniteCoordinates]
        );

        let mut out_of_range = grid_disc(2);
        out_of_range.triangles[0][2] = 99;
        assert!(matches!(
            decimate(&out_of_range, 4),
            Err(DecimateError::NotADisc(NotADisc::Index(
                crate::mesh::IndexError {
                    triangle: 0,
                    vertex: 99,
                    ..
                }
            )))
        ));

        assert_eq!(
            refused(decimate(&TriMesh::default(), 4)),
            [DefectKind::NoFaces]
        );

        let mesh = grid_disc(2);
        let disc = Disc::new(&mesh).unwrap();
        let bad = DecimateOptions {
            min_quality: 1.5,
            ..Default::default()
        };
        assert!(matches!(
            decimate_with(&mesh.positions, &disc, &bad),
            Err(DecimateError::InvalidOption(_))
        ));
        // Positions that do not fit the disc.
        assert!(matches!(
            decimate_with(&mesh.positions[1..], &disc, &DecimateOptions::default()),
            Err(DecimateError::Positions(PositionError::Count {
                positions: 8,
                vertices: 9
            }))
        ));
        let mut moved = mesh.positions.clone();
        moved[2][0] = f64::INFINITY;
        assert!(matches!(
            decimate_with(&moved, &disc, &DecimateOptions::default()),
            Err(DecimateError::Positions(PositionError::NonFinite {
                vertex: 2
            }))
        ));
    }

    #[test]
    fn quadric_is_the_weighted_squared_plane_distance() {
        // Plane through (1, 2, 3) with normal (2, −1, 2)/3, weight 5.
        let n = [2.0 / 3.0, -1.0 / 3.0, 2.0 / 3.0];
        let d = -dot3(n, [1.0, 2.0, 3.0]);
        let mut q = Quadric::plane(n, d, 5.0);
        for x in [[0.0, 0.0, 0.0], [1.0, 2.0, 3.0], [-4.0, 7.5, 0.25]] {
            let dist = dot3(n, sub3(x, [1.0, 2.0, 3.0]));
            assert!((q.at(x) - 5.0 * dist * dist).abs() < 1e-12 * (1.0 + dist * dist));
        }
        // Sum of two planes: x = 0 and y = 0 (weight 1) measure x² + y².
        q = Quadric::plane([1.0, 0.0, 0.0], 0.0, 1.0);
        q.add(&Quadric::plane([0.0, 1.0, 0.0], 0.0, 1.0));
        assert!((q.at([3.0, 4.0, 9.0]) - 25.0).abs() < 1e-12);
    }

    #[test]
    fn min_heap_pops_in_sorted_order() {
        let mut rng = crate::testing::Rng(0x9e3779b97f4a7c15);
        let entries: Vec<Entry> = (0..500)
            .map(|i| Entry {
                cost: (rng.uniform() * 50.0).floor(),
                vertex: i,
                stamp: 0,
            })
            .collect();
        let mut heap = MinHeap::from_vec(entries[..200].to_vec());
        for e in &entries[200..] {
            heap.push(*e);
        }
        heap.retain(|e| e.vertex % 7 != 3);
        let mut expected: Vec<(f64, u32)> = entries
            .iter()
            .filter(|e| e.vertex % 7 != 3)
            .map(|e| (e.cost, e.vertex))
            .collect();
        expected.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let popped: Vec<(f64, u32)> = std::iter::from_fn(|| heap.pop())
            .map(|e| (e.cost, e.vertex))
            .collect();
        assert_eq!(popped, expected);
    }

    #[test]
    fn real_mesh_decimates_to_a_disc_and_back() {
        let Some(path) = crate::testing::shared_file("camelhead.off") else {
            return;
        };
        let mesh = crate::mesh::io::read_mesh(&path).unwrap().mesh;
        let dec = decimate(&mesh, 1500).unwrap();
        assert!(dec.reached_target);
        assert_eq!(dec.coarse_mesh(&mesh).0.positions.len(), 1500);
        assert_disc(
            &mesh.positions,
            &dec.faces,
            &mesh.triangles,
            "camelhead coarse",
        );
        assert_eq!(dec.original_faces(), all_some(&mesh.triangles));
    }
}
