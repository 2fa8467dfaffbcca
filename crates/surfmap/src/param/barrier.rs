//! A boundary barrier that keeps a disc map globally injective (Smith & Schaefer 2015,
//! "Bijective parameterization with free boundaries").
//!
//! A locally injective (flip-free) map of a disc is injective exactly when its
//! boundary curve does not cross itself. The barrier adds to the elastic energy
//!
//! ```text
//! E_B(u) = λ · Σ_{v, e} b(d(u_v, u_e)),   b(d) = −κ (d − ε)² ln(d / ε) for d < ε, 0 beyond
//! ```
//!
//! (the clamped log barrier of Li et al. 2020, "Incremental Potential Contact", scaled
//! by `κ` so that `b(ε/2) = 1`; see `profile`)
//! over boundary vertices `v` and boundary edges `e` not incident to `v` (`d`:
//! point–segment distance in the plane). It is zero while every vertex stays `ε` away
//! from every other boundary edge and `+∞` at contact. A boundary edge and the third
//! corner of its own face, when that corner is on the boundary too, are no pair
//! ([`BoundaryBarrier::with_faces`]): the corner cannot reach the edge without turning
//! the face over, which the flip-free step already forbids. For an edge that shares a vertex
//! `w` with a boundary neighbour of `v`, `ε` is at most [`NEAR_FACTOR`] times the start
//! length of the boundary edge `vw`: such a pair is only that close when the boundary
//! folds back at `w` (a seam's tip closing, or opening past a full turn). The
//! line search never steps past the first contact of any boundary vertex with any
//! boundary edge (including the neighbouring ones), a *continuous collision*
//! bound computed like the flip-free bound (a quadratic in the step per pair,
//! [`BoundaryBarrier::max_step`]), so every iterate of a crossing-free start is
//! crossing-free.
//!
//! Newton uses the Gauss–Newton part of each pair's Hessian, `λ b''(d) ∇d ∇dᵀ` with
//! `∇d = c ⊗ n` over the pair's three vertices ([`BoundaryBarrier::for_each_pair_term`]):
//! positive semi-definite, so the direction is still a descent direction. Its couplings
//! of the vertex with the edge's ends are not mesh neighbours: the Newton solver adds
//! them to its sparse pattern when a pair first needs them ([`super::newton`]).
//! Candidate pairs come from a uniform grid over the boundary edges, rebuilt per
//! evaluation in buffers kept between calls.

use std::sync::Mutex;

/// Distance, relative to the mean boundary edge length at the start, below which the
/// barrier acts.
pub const EPSILON_FACTOR: f64 = 0.25;

/// Barrier weight in units of `h²` (`h`: mean boundary edge length at the start; `h²`
/// is about one boundary triangle's energy). A stiff barrier keeps contacts at a stable
/// distance: measured on `holes.off` opened with seams (with the earlier `(ε/d − 1)²`
/// profile and only each vertex's own Hessian block), `λ = h²` left Newton sliding along
/// the contacts for 200 iterations, `100 h²` converged in 29 with the energy 0.3 %
/// higher.
pub const WEIGHT_FACTOR: f64 = 100.0;

/// Cap of `ε`, relative to the start length of the edge between them, for a vertex and
/// an edge incident to its boundary neighbour (see the module docs).
pub const NEAR_FACTOR: f64 = 0.5;

/// The barrier of one disc boundary (see the module docs).
pub struct BoundaryBarrier {
    /// The boundary loop, in order: edge `i` runs from `loop_[i]` to `loop_[i + 1]`.
    loop_: Vec<u32>,
    /// Activation distance `ε` and weight `λ` ([`WEIGHT_FACTOR`]` · h²` for the mean
    /// boundary edge length `h`).
    epsilon: f64,
    weight: f64,
    /// Start length of every boundary edge.
    start_lengths: Vec<f64>,
    /// For every boundary edge, the loop position of the third corner of its face
    /// when that corner is a boundary vertex too (`u32::MAX` otherwise, or when the
    /// faces were not given): that vertex cannot reach the edge without turning the
    /// face over, which the flip-free step already forbids ([`Self::with_faces`]).
    face_corner: Vec<u32>,
    grid: Mutex<Grid>,
}

impl BoundaryBarrier {
    /// The barrier of the boundary `loop_` (in order) of a map `uv` whose boundary
    /// does not cross itself; `ε` and `λ` are set from its boundary edge lengths.
    pub fn new(loop_: &[u32], uv: &[[f64; 2]]) -> Self {
        let n = loop_.len().max(1);
        let start_lengths: Vec<f64> = (0..loop_.len())
            .map(|i| dist(uv[loop_[i] as usize], uv[loop_[(i + 1) % n] as usize]))
            .collect();
        let h = start_lengths.iter().sum::<f64>() / n as f64;
        Self {
            loop_: loop_.to_vec(),
            epsilon: EPSILON_FACTOR * h,
            weight: WEIGHT_FACTOR * h * h,
            face_corner: vec![u32::MAX; loop_.len()],
            start_lengths,
            grid: Mutex::new(Grid::default()),
        }
    }

    /// Leaves out the pairs of a boundary edge and the third corner of its own face
    /// (`triangles`: the disc's faces): the corner can only reach the edge by turning
    /// that face over, which no flip-free step does, so the barrier adds nothing there
    /// but a force on thin faces at the boundary. Such a corner sits a fraction of an
    /// edge from it where a sliver has all three corners on the boundary (a seam run
    /// through slivers: with these pairs, the contact bound held four of the last nine steps of
    /// the ICT face id002 opened with seams to 4·10⁻³ of the Newton step, BENCHMARKS.md
    /// "Hard discs").
    pub fn with_faces(mut self, triangles: &[[u32; 3]]) -> Self {
        let n = self.loop_.len();
        let mut position = std::collections::HashMap::with_capacity(n);
        for (k, &v) in self.loop_.iter().enumerate() {
            position.insert(v, k);
        }
        for t in triangles {
            for j in 0..3 {
                let (a, b, c) = (t[j], t[(j + 1) % 3], t[(j + 2) % 3]);
                let (Some(&ka), Some(&kb), Some(&kc)) =
                    (position.get(&a), position.get(&b), position.get(&c))
                else {
                    continue;
                };
                // The boundary edge joining a and b (either orientation of the loop).
                let edge = if (ka + 1) % n == kb {
                    ka
                } else if (kb + 1) % n == ka {
                    kb
                } else {
                    continue;
                };
                self.face_corner[edge] = kc as u32;
            }
        }
        self
    }

    fn edge(&self, i: usize) -> (u32, u32) {
        (self.loop_[i], self.loop_[(i + 1) % self.loop_.len()])
    }

    /// The activation distance of loop vertex `k` and edge `i` (edge `i` joins loop
    /// vertices `i` and `i + 1`), or `None` when the edge is incident to `k`.
    fn pair_epsilon(&self, k: usize, i: usize) -> Option<f64> {
        let n = self.loop_.len();
        if i == k || (i + 1) % n == k || self.face_corner[i] == k as u32 {
            return None;
        }
        let cap = if i == (k + 1) % n {
            // Edge (k+1, k+2): joined to k by edge k.
            NEAR_FACTOR * self.start_lengths[k]
        } else if (i + 2) % n == k {
            // Edge (k−2, k−1): joined to k by edge k−1.
            NEAR_FACTOR * self.start_lengths[(i + 1) % n]
        } else {
            f64::INFINITY
        };
        Some(self.epsilon.min(cap))
    }

    /// Calls `f(k, i, ε, d, s, n)` for every penalized pair with `d < ε` (its own
    /// `ε`): loop vertex `k`, edge `i`, distance `d`, closest point parameter `s` on the
    /// edge and the unit direction `n` from that point to the vertex.
    fn for_each_active_pair(
        &self,
        uv: &[[f64; 2]],
        f: impl FnMut(usize, usize, f64, f64, f64, [f64; 2]),
    ) {
        self.for_each_pair_closer_than(uv, 1.0, f);
    }

    /// [`Self::for_each_active_pair`] for the pairs with `d < reach · ε` (their own `ε`).
    fn for_each_pair_closer_than(
        &self,
        uv: &[[f64; 2]],
        reach: f64,
        mut f: impl FnMut(usize, usize, f64, f64, f64, [f64; 2]),
    ) {
        let eps = reach * self.epsilon;
        let mut grid = self.grid.lock().unwrap_or_else(|e| e.into_inner());
        grid.build(self.loop_.len(), eps, |i| {
            let (a, b) = self.edge(i);
            let (a, b) = (uv[a as usize], uv[b as usize]);
            [
                a[0].min(b[0]) - eps,
                a[1].min(b[1]) - eps,
                a[0].max(b[0]) + eps,
                a[1].max(b[1]) + eps,
            ]
        });
        for (k, &v) in self.loop_.iter().enumerate() {
            let p = uv[v as usize];
            grid.query([p[0], p[1], p[0], p[1]], |i| {
                let Some(eps) = self.pair_epsilon(k, i) else {
                    return;
                };
                let (a, b) = self.edge(i);
                let (a, b) = (uv[a as usize], uv[b as usize]);
                let (d, s, n) = point_segment(p, a, b);
                if d < reach * eps {
                    f(k, i, eps, d, s, n);
                }
            });
        }
    }

    /// `E_B(uv)`; `+∞` at contact.
    pub fn energy(&self, uv: &[[f64; 2]]) -> f64 {
        let mut e = 0.0;
        self.for_each_active_pair(uv, |_, _, eps, d, _, _| {
            e += if d > 0.0 {
                profile(eps, d).0
            } else {
                f64::INFINITY
            };
        });
        self.weight * e
    }

    /// Calls `f(vertices, c, n, f1, f2)` for every penalized pair at positive distance:
    /// the pair's term is `f(d)` with `d = n · (u_v − (1 − s) u_a − s u_b)` to first
    /// order, so its gradient is `f1 · c_i · n` on vertex `vertices[i]` (`c = (1, −(1 −
    /// s), −s)`, vertices `(v, a, b)`) and its Gauss–Newton Hessian is `f2 · (c cᵀ) ⊗ (n
    /// nᵀ)` (`f1 = f'(d)`, `f2 = f''(d) ≥ 0`, weight included).
    pub fn for_each_pair_term(
        &self,
        uv: &[[f64; 2]],
        mut f: impl FnMut([u32; 3], [f64; 3], [f64; 2], f64, f64),
    ) {
        let w = self.weight;
        self.for_each_active_pair(uv, |k, i, eps, d, s, n| {
            if d <= 0.0 {
                return;
            }
            let (_, f1, f2) = profile(eps, d);
            let (a, b) = self.edge(i);
            f(
                [self.loop_[k], a, b],
                [1.0, -(1.0 - s), -s],
                n,
                w * f1,
                w * f2,
            );
        });
    }

    /// Calls `f([v, a, b])` for every pair (vertex `v`, edge `ab`) closer than `reach`
    /// times its `ε`: the pairs that may become active soon (for a sparse pattern
    /// with a margin).
    pub fn for_each_pair_within(&self, uv: &[[f64; 2]], reach: f64, mut f: impl FnMut([u32; 3])) {
        self.for_each_pair_closer_than(uv, reach, |k, i, _, _, _, _| {
            let (a, b) = self.edge(i);
            f([self.loop_[k], a, b]);
        });
    }

    /// Largest `t > 0` such that moving every vertex by `t · dir` brings no boundary
    /// vertex onto a boundary edge it does not end (the first contact along the ray);
    /// `f64::INFINITY` when none occurs. Candidate pairs: the grid over the edges'
    /// swept boxes for steps up to `t_cap`.
    pub fn max_step(&self, uv: &[[f64; 2]], dir: &[[f64; 2]], t_cap: f64) -> f64 {
        let t_cap = if t_cap.is_finite() { t_cap } else { 1e3 };
        let at = |v: u32, t: f64| {
            let (p, d) = (uv[v as usize], dir[v as usize]);
            [p[0] + t * d[0], p[1] + t * d[1]]
        };
        let swept = |v: u32| {
            let (p, q) = (uv[v as usize], at(v, t_cap));
            [
                p[0].min(q[0]),
                p[1].min(q[1]),
                p[0].max(q[0]),
                p[1].max(q[1]),
            ]
        };
        let mut grid = self.grid.lock().unwrap_or_else(|e| e.into_inner());
        grid.build(self.loop_.len(), 0.0, |i| {
            let (a, b) = self.edge(i);
            let (ba, bb) = (swept(a), swept(b));
            [
                ba[0].min(bb[0]),
                ba[1].min(bb[1]),
                ba[2].max(bb[2]),
                ba[3].max(bb[3]),
            ]
        });
        let mut best = f64::INFINITY;
        for &v in &self.loop_ {
            grid.query(swept(v), |i| {
                let (a, b) = self.edge(i);
                if a == v || b == v {
                    return;
                }
                let t = first_contact(
                    [uv[v as usize], uv[a as usize], uv[b as usize]],
                    [dir[v as usize], dir[a as usize], dir[b as usize]],
                );
                best = best.min(t);
            });
        }
        best
    }

    /// Whether any boundary vertex lies on, or any two boundary edges without a common
    /// vertex cross, in `uv` (the map is then not injective).
    pub fn crossings(&self, uv: &[[f64; 2]]) -> usize {
        let segments: Vec<[[f64; 2]; 2]> = (0..self.loop_.len())
            .map(|i| {
                let (a, b) = self.edge(i);
                [uv[a as usize], uv[b as usize]]
            })
            .collect();
        crate::measure::overlap::count_segment_crossings(&segments).0
    }
}

/// First `t > 0` at which point `x[0] + t·d[0]` lies on the segment from `x[1] + t·d[1]`
/// to `x[2] + t·d[2]`, or `f64::INFINITY`. The collinearity condition
/// `(b − a) × (p − a) = 0` is a quadratic in `t`; each root is kept when the point is
/// then within the segment.
fn first_contact(x: [[f64; 2]; 3], d: [[f64; 2]; 3]) -> f64 {
    let sub = |u: [f64; 2], v: [f64; 2]| [u[0] - v[0], u[1] - v[1]];
    let cross = |u: [f64; 2], v: [f64; 2]| u[0] * v[1] - u[1] * v[0];
    let (e0, e1) = (sub(x[2], x[1]), sub(d[2], d[1]));
    let (q0, q1) = (sub(x[0], x[1]), sub(d[0], d[1]));
    // (e0 + t e1) × (q0 + t q1) = c + b t + a t²
    let c = cross(e0, q0);
    let b = cross(e0, q1) + cross(e1, q0);
    let a = cross(e1, q1);
    let mut roots = [f64::INFINITY; 2];
    let scale = (c.abs() + b.abs() + a.abs()).max(f64::MIN_POSITIVE);
    if a.abs() <= 1e-14 * scale {
        if b != 0.0 {
            roots[0] = -c / b;
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            roots = [q / a, if q != 0.0 { c / q } else { f64::INFINITY }];
        }
    }
    if roots[0] > roots[1] {
        roots.swap(0, 1);
    }
    for t in roots {
        if !(t > 0.0 && t.is_finite()) {
            continue;
        }
        let e = [e0[0] + t * e1[0], e0[1] + t * e1[1]];
        let q = [q0[0] + t * q1[0], q0[1] + t * q1[1]];
        let ee = e[0] * e[0] + e[1] * e[1];
        let s = (q[0] * e[0] + q[1] * e[1]) / ee;
        if ee > 0.0 && (0.0..=1.0).contains(&s) {
            return t;
        }
    }
    f64::INFINITY
}

/// The barrier profile `b(d) = −κ (d − ε)² ln(d / ε)` of Li et al. 2020 (IPC) at
/// distance `0 < d < ε`, with `κ = 1 / ((ε/2)² ln 2)` so that `b(ε/2) = 1`, and its
/// first two derivatives:
///
/// ```text
/// b'(d)  = −κ (2 (d − ε) ln(d/ε) + (d − ε)² / d)
/// b''(d) = −κ (2 ln(d/ε) + 4 (d − ε) / d − (d − ε)² / d²)   > 0 on (0, ε)
/// ```
///
/// `b` is C² at `ε` (value, slope and curvature vanish there) and grows only like
/// `−ln d` at contact, so a Newton step that overshoots toward a contact costs little
/// (a `(ε/d − 1)²` profile, tried first, made steps stall after such overshoots).
fn profile(eps: f64, d: f64) -> (f64, f64, f64) {
    let k = 1.0 / (0.25 * eps * eps * std::f64::consts::LN_2);
    let (l, r) = ((d / eps).ln(), d - eps);
    (
        -k * r * r * l,
        -k * (2.0 * r * l + r * r / d),
        -k * (2.0 * l + 4.0 * r / d - r * r / (d * d)),
    )
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Distance from `p` to segment `ab`, the parameter `s ∈ [0, 1]` of the closest point
/// and the unit vector from it to `p` (zero at contact).
fn point_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> (f64, f64, [f64; 2]) {
    let e = [b[0] - a[0], b[1] - a[1]];
    let ee = e[0] * e[0] + e[1] * e[1];
    let s = if ee > 0.0 {
        (((p[0] - a[0]) * e[0] + (p[1] - a[1]) * e[1]) / ee).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let r = [p[0] - a[0] - s * e[0], p[1] - a[1] - s * e[1]];
    let d = r[0].hypot(r[1]);
    let n = if d > 0.0 {
        [r[0] / d, r[1] / d]
    } else {
        [0.0, 0.0]
    };
    (d, s, n)
}

/// A uniform grid of boxes (compressed rows: the items of cell `c` are
/// `items[start[c]..start[c + 1]]`), its buffers reused between builds.
#[derive(Default)]
struct Grid {
    lo: [f64; 2],
    cell: f64,
    dims: [usize; 2],
    boxes: Vec<[f64; 4]>,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Grid {
    /// Builds the grid of `count` boxes `bbox(i)`, cells no smaller than `min_cell`.
    fn build(&mut self, count: usize, min_cell: f64, bbox: impl Fn(usize) -> [f64; 4]) {
        self.boxes.clear();
        self.boxes.extend((0..count).map(bbox));
        let (mut lo, mut hi, mut extent) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2], 0.0);
        for b in &self.boxes {
            lo = [lo[0].min(b[0]), lo[1].min(b[1])];
            hi = [hi[0].max(b[2]), hi[1].max(b[3])];
            extent += (b[2] - b[0]).max(b[3] - b[1]);
        }
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        if !(span.is_finite() && span > 0.0) {
            // Degenerate or non-finite: one cell holding everything.
            self.lo = [0.0; 2];
            self.cell = f64::INFINITY;
            self.dims = [1, 1];
            self.start.clear();
            self.start.extend([0, count as u32]);
            self.items.clear();
            self.items.extend(0..count as u32);
            return;
        }
        // Cells about an average box, at most ~4 per item in each direction's product.
        let mean = extent / count.max(1) as f64;
        let min_by_count = span / (2.0 * (count as f64).sqrt().max(1.0));
        let cell = mean.max(min_cell).max(min_by_count).max(span * 1e-9);
        self.lo = lo;
        self.cell = cell;
        self.dims = [
            ((hi[0] - lo[0]) / cell) as usize + 1,
            ((hi[1] - lo[1]) / cell) as usize + 1,
        ];
        let cells = self.dims[0] * self.dims[1];
        self.start.clear();
        self.start.resize(cells + 1, 0);
        for i in 0..count {
            let [x0, y0, x1, y1] = self.range(self.boxes[i]);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    self.start[y * self.dims[0] + x + 1] += 1;
                }
            }
        }
        for c in 0..cells {
            self.start[c + 1] += self.start[c];
        }
        self.items.clear();
        self.items.resize(self.start[cells] as usize, 0);
        let mut fill = self.start.clone();
        for i in 0..count {
            let [x0, y0, x1, y1] = self.range(self.boxes[i]);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let c = y * self.dims[0] + x;
                    self.items[fill[c] as usize] = i as u32;
                    fill[c] += 1;
                }
            }
        }
    }

    /// Cell index range `[x0, y0, x1, y1]` of a box, clamped to the grid.
    fn range(&self, b: [f64; 4]) -> [usize; 4] {
        let at = |x: f64, k: usize| {
            let c = ((x - self.lo[k]) / self.cell).floor();
            if c.is_nan() || c < 0.0 {
                0
            } else {
                (c as usize).min(self.dims[k] - 1)
            }
        };
        [at(b[0], 0), at(b[1], 1), at(b[2], 0), at(b[3], 1)]
    }

    /// Calls `f(i)` for every item whose box overlaps `b` (an item may come once per
    /// shared cell).
    fn query(&self, b: [f64; 4], mut f: impl FnMut(usize)) {
        let [x0, y0, x1, y1] = self.range(b);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let c = y * self.dims[0] + x;
                for &i in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                    let bi = self.boxes[i as usize];
                    if bi[0] <= b[2] && b[0] <= bi[2] && bi[1] <= b[3] && b[1] <= bi[3] {
                        f(i as usize);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_contact_is_the_time_the_point_reaches_the_segment() {
        // A point at (0.5, 1) falling at unit speed onto the segment (0,0)–(1,0).
        let x = [[0.5, 1.0], [0.0, 0.0], [1.0, 0.0]];
        let d = [[0.0, -1.0], [0.0, 0.0], [0.0, 0.0]];
        assert!((first_contact(x, d) - 1.0).abs() < 1e-15);
        // The segment rising to meet it halfway.
        let d = [[0.0, -1.0], [0.0, 1.0], [0.0, 1.0]];
        assert!((first_contact(x, d) - 0.5).abs() < 1e-15);
        // Passing beside the segment's end: the line is crossed, the segment is not.
        let x = [[1.5, 1.0], [0.0, 0.0], [1.0, 0.0]];
        let d = [[0.0, -1.0], [0.0, 0.0], [0.0, 0.0]];
        assert_eq!(first_contact(x, d), f64::INFINITY);
        // A rotating segment (quadratic case): the segment (0,0)–(1,0) with its far end
        // moving up at speed 2 sweeps the point (0.5, 0.5) at t = 0.5.
        let x = [[0.5, 0.5], [0.0, 0.0], [1.0, 0.0]];
        let d = [[0.0, 0.0], [0.0, 0.0], [0.0, 2.0]];
        assert!((first_contact(x, d) - 0.5).abs() < 1e-12);
    }

    /// A square boundary loop of side 1 (4·m edges), counter-clockwise.
    fn square(m: usize) -> Vec<[f64; 2]> {
        let mut out = Vec::new();
        for side in 0..4 {
            for j in 0..m {
                let s = j as f64 / m as f64;
                out.push(match side {
                    0 => [s, 0.0],
                    1 => [1.0, s],
                    2 => [1.0 - s, 1.0],
                    _ => [0.0, 1.0 - s],
                });
            }
        }
        out
    }

    #[test]
    fn profile_derivatives_match_finite_differences() {
        let eps = 0.3;
        let (b, b1, b2) = profile(eps, 0.5 * eps);
        assert!((b - 1.0).abs() < 1e-14, "{b}");
        assert!(b1 < 0.0 && b2 > 0.0);
        // Value, slope and curvature vanish at ε: the barrier is C² there.
        let (b, b1, b2) = profile(eps, eps);
        assert_eq!((b, b1), (0.0, 0.0));
        assert!(b2.abs() < 1e-12, "{b2}");
        let h = 1e-6;
        for d in [1e-3, 0.01, 0.05, 0.1, 0.2, 0.29] {
            let (_, b1, b2) = profile(eps, d);
            let fd1 = (profile(eps, d + h).0 - profile(eps, d - h).0) / (2.0 * h);
            let fd2 = (profile(eps, d + h).1 - profile(eps, d - h).1) / (2.0 * h);
            assert!(
                (fd1 - b1).abs() <= 1e-6 * (1.0 + b1.abs()),
                "d {d}: {fd1} vs {b1}"
            );
            assert!(
                (fd2 - b2).abs() <= 1e-6 * (1.0 + b2.abs()),
                "d {d}: {fd2} vs {b2}"
            );
            assert!(b2 > 0.0, "convex: {b2} at {d}");
        }
    }

    #[test]
    fn pair_distance_gradient_is_c_times_n() {
        // d(u_v, u_a, u_b) for a point against a segment, its closest point inside the
        // segment (s = 0.3) and at its end (clamped, s = 0): ∂d/∂u_k = c_k n.
        for (p, a, b) in [
            ([0.3, 0.2], [0.0, 0.0], [1.0, 0.1]),
            ([-0.2, 0.3], [0.0, 0.0], [1.0, 0.1]),
        ] {
            let (_, s, n) = point_segment(p, a, b);
            let c = [1.0, -(1.0 - s), -s];
            let x = [p, a, b];
            let h = 1e-7;
            for k in 0..3 {
                for j in 0..2 {
                    let (mut plus, mut minus) = (x, x);
                    plus[k][j] += h;
                    minus[k][j] -= h;
                    let fd = (point_segment(plus[0], plus[1], plus[2]).0
                        - point_segment(minus[0], minus[1], minus[2]).0)
                        / (2.0 * h);
                    assert!((fd - c[k] * n[j]).abs() < 1e-7, "{fd} vs {}", c[k] * n[j]);
                }
            }
        }
    }

    #[test]
    fn energy_gradient_and_step_bound() {
        let mut uv = square(4);
        let loop_: Vec<u32> = (0..uv.len() as u32).collect();
        let barrier = BoundaryBarrier::new(&loop_, &uv);
        // A square with edges h = 1/4 apart: every non-neighbour pair is ≥ h > ε away.
        assert_eq!(barrier.energy(&uv), 0.0);
        assert_eq!(barrier.crossings(&uv), 0);
        // Pull the middle of the top side (vertex 10) down to 0.04 above the middle of
        // the bottom side (vertex 2): a deep notch, ε-close to the bottom edges.
        uv[10] = [0.5, 0.04];
        let e = barrier.energy(&uv);
        assert!(e > 0.0 && e.is_finite());
        // Gradient by central differences, on every coordinate.
        let mut grad = vec![[0.0; 2]; uv.len()];
        let mut pairs = 0;
        barrier.for_each_pair_term(&uv, |vertices, c, n, f1, f2| {
            assert!(f2 > 0.0, "{f2}");
            pairs += 1;
            for (v, c) in vertices.into_iter().zip(c) {
                grad[v as usize][0] += f1 * c * n[0];
                grad[v as usize][1] += f1 * c * n[1];
            }
        });
        assert!(pairs > 0);
        let step = 1e-7;
        for v in 0..uv.len() {
            for c in 0..2 {
                let (mut plus, mut minus) = (uv.clone(), uv.clone());
                plus[v][c] += step;
                minus[v][c] -= step;
                let fd = (barrier.energy(&plus) - barrier.energy(&minus)) / (2.0 * step);
                assert!(
                    (fd - grad[v][c]).abs() <= 1e-5 * (1.0 + fd.abs()),
                    "vertex {v} coordinate {c}: {fd} vs {}",
                    grad[v][c]
                );
            }
        }
        // Moving vertex 10 straight down at unit speed hits the bottom side at t = 0.04.
        let mut dir = vec![[0.0; 2]; uv.len()];
        dir[10] = [0.0, -1.0];
        let t = barrier.max_step(&uv, &dir, 1.0);
        assert!((t - 0.04).abs() < 1e-12, "{t}");
        // Past it, the boundary crosses itself.
        let mut past = uv.clone();
        past[10] = [0.5, -0.01];
        assert!(barrier.crossings(&past) > 0);
    }

    #[test]
    fn a_boundary_edge_and_its_own_face_corner_are_no_pair() {
        // A disc whose boundary runs out along the bottom and folds back at vertex 1:
        // face (0, 1, 2) is a thin spike, its corner 2 only 0.05 above its boundary edge
        // 0 → 1, well inside ε (0.2).
        let uv = vec![[0.0, 0.0], [1.0, 0.0], [0.5, 0.05], [0.5, 1.0], [0.0, 1.0]];
        let triangles = [[0, 1, 2], [0, 2, 3], [0, 3, 4]];
        let loop_: Vec<u32> = (0..5).collect();
        let plain = BoundaryBarrier::new(&loop_, &uv);
        let with_faces = BoundaryBarrier::new(&loop_, &uv).with_faces(&triangles);
        let pairs = |b: &BoundaryBarrier| {
            let mut found = Vec::new();
            b.for_each_pair_term(&uv, |vertices, _, _, _, _| found.push(vertices));
            found
        };
        // Without the faces the spike's corner is pushed off its own edge; with them
        // no pair is active at all (every other vertex is ≥ 0.45 from every edge).
        assert!(plain.energy(&uv) > 0.0);
        assert_eq!(pairs(&plain), vec![[2, 0, 1]]);
        assert_eq!(with_faces.energy(&uv), 0.0);
        assert!(pairs(&with_faces).is_empty());
        // The step bound still stops the corner at the edge (where the face turns over).
        let mut dir = vec![[0.0; 2]; uv.len()];
        dir[2] = [0.0, -1.0];
        for b in [&plain, &with_faces] {
            let t = b.max_step(&uv, &dir, 1.0);
            assert!((t - 0.05).abs() < 1e-12, "{t}");
        }
    }
}
