//! Multilevel start for large meshes: flatten a decimated copy, then bring the removed
//! vertices back one at a time, in the reverse order of their collapses, keeping the
//! map flip-free after every insertion (hierarchical parameterization in the manner
//! of Hormann, Labsik & Greiner 2000 and Sander et al. 2002).
//!
//! Undoing the half-edge collapse `v → u` restores `v`'s star: the faces in which `u`
//! had replaced `v`, and the one or two faces of the edge `uv`. `v` is placed
//!
//! 1. at the conformal least-squares position: for each star face `(v, a, b)` (counter-
//!    clockwise), the 3D triangle gives the complex ratio `z = (v − a)/(b − a)` in its
//!    own plane; the UV point that makes the face similar to its 3D shape is
//!    `a' + z·(b' − a')` (primes: UVs), and `v'` is their mean — `v`'s part of the LSCM
//!    energy (§3.1.1) minimized with everything else fixed;
//! 2. if that flips a star face, at the centroid of the star's kernel (the convex
//!    polygon where every star face `(v, a, b)` is counter-clockwise: `v` left of
//!    `a' → b'`), which is non-empty because `u` was inside its own star before the
//!    split;
//! 3. then moved by a few projected-Newton steps on the energy of its star (the same
//!    element energy, gradient and PSD-projected Hessian as the global solver, 2 unknowns),
//!    each step capped below the first flip (star face areas are linear in `v'`); `u`,
//!    whose star shrank, gets the same treatment.
//!
//! After the last insertion, a few Gauss–Seidel sweeps of one such local step per vertex
//! smooth out what one-vertex-at-a-time placement leaves (a few squeezed triangles
//! that would otherwise cost the full-size Newton many barrier-limited iterations; see
//! BENCHMARKS.md for the measured effect). Vertices are coloured so that one colour
//! class runs in parallel.
//!
//! Every insertion is checked (all star faces strictly counter-clockwise) and every
//! local step stays flip-free; a failure is an error, and the caller falls back to the
//! single-level start.
//!
//! Where the map must not overlap itself (the bijective modes), boundary vertices are
//! also kept from crossing the boundary (`BoundaryGuard`): a re-inserted boundary
//! vertex whose edges would cross a current boundary edge is drawn toward the edge its
//! insertion split (which crossed nothing), and a local step (insertion or sweep) of a
//! boundary vertex that would cross is not taken. A vertex that found no crossing-free
//! position when it was inserted gets another try once all vertices are in place
//! (`untangle`); a crossing that still remains is found by the caller, which abandons
//! the start as before. The
//! prolongation needs no linear solve: cost O(faces · (polish steps + sweeps)), plus
//! O(boundary) per placement or step of a boundary vertex when guarded (loops up to
//! [`MAX_GUARDED_BOUNDARY`] vertices).

use super::element::{self, RestTriangle};
use super::signed_uv_area;
use crate::energy::Density;
use crate::measure::overlap::segments_intersect;
use crate::mesh::decimate::Decimation;
use crate::vec3::{cross3, dot3, sub3};

/// Why a prolongation stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProlongationError {
    #[error(
        "re-inserting vertex {vertex}: its star has no admissible position (empty kernel in UV)"
    )]
    EmptyKernel { vertex: u32 },
    #[error("re-inserting vertex {vertex}: a face of its star is degenerate in 3D")]
    DegenerateFace { vertex: u32 },
    #[error("the coarse map gives vertex {vertex} a non-finite UV")]
    NonFiniteCoarseUv { vertex: u32 },
}

/// What the prolongation did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ProlongationStats {
    /// Vertices re-inserted.
    pub inserted: usize,
    /// Of them, placed at the kernel centroid because the conformal position flipped a face.
    pub kernel_fallbacks: usize,
    /// Local Newton steps taken in total.
    pub polish_steps: usize,
    /// Placements and local steps of boundary vertices changed or refused because the
    /// boundary would have crossed itself (see the module docs).
    pub kept_off_the_boundary: usize,
    /// Boundary vertices moved after the re-insertion because their edges still
    /// crossed the boundary (`untangle`).
    pub untangled: usize,
}

/// The boundary loop of the map during the re-insertion: the re-inserted boundary
/// vertices linked between their present neighbours along the fine loop, so that a
/// placement or local step of a boundary vertex can be checked against every current
/// boundary edge (O(boundary) per check, on boundary vertices only). The coarse map is
/// overlap-free (solved with the barrier when it needed one); one-vertex-at-a-time
/// placement can make two sides of a seam, or the rims of a narrow slit, cross where the
/// coarse map had them nearly touching (measured: ICT faces opened with seams, 1–2
/// crossing pairs after the re-insertion, which made the full-size barrier solve start
/// from mean-value coordinates instead).
struct BoundaryGuard {
    /// Position of each vertex in the fine loop (`u32::MAX`: not on the boundary).
    index: Vec<u32>,
    /// The fine loop.
    fine: Vec<u32>,
    /// For each loop position, the previous and next present one (valid for present
    /// positions: those whose vertex has been placed).
    prev: Vec<u32>,
    next: Vec<u32>,
    present: Vec<bool>,
}

/// Longest boundary loop the re-insertion keeps from crossing itself: each check scans
/// the loop, so the sweeps cost `sweeps · n²` edge visits (most rejected by a bounding
/// box). Measured: the prolongation of a 61k-face polar disc with 4,096 boundary
/// vertices 0.056 s unguarded, 0.076 s guarded. Beyond it the loop is not guarded (a
/// start that crosses itself is abandoned, as without the guard).
pub const MAX_GUARDED_BOUNDARY: usize = 4096;

impl BoundaryGuard {
    /// The guard of `boundary` (none when it is longer than [`MAX_GUARDED_BOUNDARY`]),
    /// with the vertices placed in `uv` (finite) present.
    fn new(boundary: &[u32], uv: &[[f64; 2]]) -> Self {
        // (Unguarded also when no boundary vertex is placed yet: nothing to link to.)
        let placed = |v: &u32| uv.get(*v as usize).is_some_and(|p| p[0].is_finite());
        let boundary = if boundary.len() > MAX_GUARDED_BOUNDARY || !boundary.iter().any(placed) {
            &[]
        } else {
            boundary
        };
        let n = boundary.len();
        let mut index = vec![u32::MAX; uv.len()];
        for (k, &v) in boundary.iter().enumerate() {
            index[v as usize] = k as u32;
        }
        let present: Vec<bool> = boundary.iter().map(placed).collect();
        let (mut prev, mut next) = (vec![0u32; n], vec![0u32; n]);
        if let Some(last) = (0..n).rev().find(|&k| present[k]) {
            let mut before = last;
            for k in (0..n).filter(|&k| present[k]) {
                prev[k] = before as u32;
                next[before] = k as u32;
                before = k;
            }
        }
        Self {
            index,
            fine: boundary.to_vec(),
            prev,
            next,
            present,
        }
    }

    /// Loop position of `v`, if it is a boundary vertex.
    fn position(&self, v: u32) -> Option<usize> {
        let k = *self.index.get(v as usize)?;
        (k != u32::MAX).then_some(k as usize)
    }

    /// Links re-inserted vertex `v` (if on the boundary) between its present
    /// neighbours along the loop.
    fn insert(&mut self, v: u32) {
        let Some(k) = self.position(v) else { return };
        if self.present[k] {
            return;
        }
        let n = self.fine.len();
        let mut before = (k + n - 1) % n;
        while !self.present[before] {
            before = (before + n - 1) % n;
        }
        let after = self.next[before] as usize;
        self.present[k] = true;
        (self.prev[k], self.next[k]) = (before as u32, after as u32);
        self.next[before] = k as u32;
        self.prev[after] = k as u32;
    }

    /// The present neighbours of present loop position `k` (previous, next).
    fn neighbours(&self, k: usize) -> (u32, u32) {
        (
            self.fine[self.prev[k] as usize],
            self.fine[self.next[k] as usize],
        )
    }

    /// Whether boundary vertex `v` at `p` makes one of its two boundary edges cross
    /// (or touch) a current boundary edge without a common endpoint; `false` for a
    /// vertex off the boundary (or not yet placed).
    fn crosses(&self, uv: &[[f64; 2]], v: u32, p: [f64; 2]) -> bool {
        let Some(k) = self.position(v).filter(|&k| self.present[k]) else {
            return false;
        };
        let (prev, next) = self.neighbours(k);
        let (a, b) = (uv[prev as usize], uv[next as usize]);
        let (lo, hi) = (
            [p[0].min(a[0]).min(b[0]), p[1].min(a[1]).min(b[1])],
            [p[0].max(a[0]).max(b[0]), p[1].max(a[1]).max(b[1])],
        );
        // Every current boundary edge (x, y) from the one leaving `next` to the one
        // entering `prev`; those sharing an endpoint with an edge of v are skipped for it.
        let mut x = self.next[k] as usize;
        while x != self.prev[k] as usize {
            let y = self.next[x] as usize;
            let (c, d) = (uv[self.fine[x] as usize], uv[self.fine[y] as usize]);
            let outside = c[0].max(d[0]) < lo[0]
                || c[0].min(d[0]) > hi[0]
                || c[1].max(d[1]) < lo[1]
                || c[1].min(d[1]) > hi[1];
            if !outside {
                let (cx, cy) = (self.fine[x], self.fine[y]);
                if (cx != next && cy != next && segments_intersect(p, b, c, d))
                    || (cx != prev && cy != prev && segments_intersect(a, p, c, d))
                {
                    return true;
                }
            }
            x = y;
        }
        false
    }

    /// A position for the just re-inserted boundary vertex `v`, placed at `p` where its
    /// edges cross the boundary, that crosses nothing: `p` drawn toward the point `q` of
    /// the segment between its present neighbours (the boundary edge its insertion
    /// split, which crossed nothing) at the 3D length ratio, `q + s (p − q)` for
    /// `s = ½, ¼, …, 1/64`, else the point of that segment closest to `q` that its star
    /// allows (every face of `star`, rotated to `(v, a, b)`, counter-clockwise, with a
    /// tenth of the admissible interval to spare); `None` if none of these is admissible
    /// and crossing-free.
    fn uncrossed(
        &self,
        positions: &[[f64; 3]],
        uv: &[[f64; 2]],
        star: &[[u32; 3]],
        v: u32,
        p: [f64; 2],
    ) -> Option<[f64; 2]> {
        let k = self.position(v)?;
        let (prev, next) = self.neighbours(k);
        let (a, b) = (uv[prev as usize], uv[next as usize]);
        let length = |x: u32| {
            crate::vec3::norm3(crate::vec3::sub3(
                positions[v as usize],
                positions[x as usize],
            ))
        };
        let (la, lb) = (length(prev), length(next));
        let t0 = if la + lb > 0.0 { la / (la + lb) } else { 0.5 };
        let q = [a[0] + t0 * (b[0] - a[0]), a[1] + t0 * (b[1] - a[1])];
        let usable = |c: [f64; 2]| admissible(uv, star, c) && !self.crosses(uv, v, c);
        let mut s = 1.0;
        for _ in 0..6 {
            s *= 0.5;
            let c = [q[0] + s * (p[0] - q[0]), q[1] + s * (p[1] - q[1])];
            if usable(c) {
                return Some(c);
            }
        }
        // Every star face's area is affine in t along the segment.
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for f in star {
            let (x, y) = (uv[f[1] as usize], uv[f[2] as usize]);
            let area0 = signed_uv_area([a, x, y]);
            let area1 = signed_uv_area([b, x, y]);
            let rate = area1 - area0;
            if rate > 0.0 {
                lo = lo.max(-area0 / rate);
            } else if rate < 0.0 {
                hi = hi.min(-area0 / rate);
            } else if area0 <= 0.0 {
                return None;
            }
        }
        if lo >= hi || lo.is_nan() || hi.is_nan() {
            return None;
        }
        let margin = 0.1 * (hi - lo);
        let t = t0.clamp(lo + margin, hi - margin);
        let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
        usable(p).then_some(p)
    }
}

/// Local Newton steps per re-inserted vertex.
pub const DEFAULT_POLISH_STEPS: usize = 4;
/// Relaxation sweeps over the full mesh after the re-insertion.
pub const DEFAULT_SWEEPS: usize = 8;

/// Undoes every collapse of `decimation` in reverse order on `faces` (which must be
/// the coarse state, `decimation.faces`), placing each re-inserted vertex in `uv`
/// (module docs). `boundary`: the original mesh's boundary loop, whose vertices are
/// kept from crossing it (empty, or longer than [`MAX_GUARDED_BOUNDARY`]: no such
/// guard). `uv` holds one entry per original vertex; on entry the coarse vertices must
/// be set (a flip-free map of the coarse mesh); on success every vertex is set and the
/// map of the original mesh is flip-free.
pub fn prolongate<D: Density + ?Sized>(
    positions: &[[f64; 3]],
    decimation: &Decimation,
    boundary: &[u32],
    uv: &mut [[f64; 2]],
    density: &D,
    polish_steps: usize,
    sweeps: usize,
) -> Result<ProlongationStats, ProlongationError> {
    let mut guard = BoundaryGuard::new(boundary, uv);
    let mut faces = decimation.faces.clone();
    // Faces around each vertex in the current state (updated by every undo).
    let mut incident: Vec<Vec<u32>> = vec![Vec::new(); uv.len()];
    for (f, tri) in faces.iter().enumerate() {
        for &v in tri.iter().flatten() {
            incident[v as usize].push(f as u32);
        }
    }
    let mut stats = ProlongationStats::default();
    let (mut star, mut rest) = (Vec::with_capacity(16), Vec::with_capacity(16));
    for collapse in decimation.collapses.iter().rev() {
        let (v, u) = (collapse.removed, collapse.into);
        decimation.undo(&mut faces, collapse);
        for &f in decimation.changed(collapse) {
            incident[u as usize].retain(|&g| g != f);
            incident[v as usize].push(f);
        }
        for d in collapse.deleted() {
            for &w in &d.vertices {
                incident[w as usize].push(d.face);
            }
        }
        let into = uv[u as usize];
        if !(into[0].is_finite() && into[1].is_finite()) {
            return Err(ProlongationError::NonFiniteCoarseUv { vertex: u });
        }
        star_of(&faces, &incident[v as usize], v, &mut star);
        let mut p = conformal_position(positions, uv, &star, v)
            .ok_or(ProlongationError::DegenerateFace { vertex: v })?;
        if !admissible(uv, &star, p) {
            p = kernel_centroid(uv, &star).ok_or(ProlongationError::EmptyKernel { vertex: v })?;
            stats.kernel_fallbacks += 1;
        }
        guard.insert(v);
        if guard.crosses(uv, v, p)
            && let Some(q) = guard.uncrossed(positions, uv, &star, v, p)
        {
            p = q;
            stats.kept_off_the_boundary += 1;
        }
        uv[v as usize] = p;
        // Relax the new vertex, then the one it was split from (its star shrank).
        for w in [v, u] {
            star_of(&faces, &incident[w as usize], w, &mut star);
            rest_of(positions, &star, &mut rest)
                .ok_or(ProlongationError::DegenerateFace { vertex: w })?;
            let (p, taken) = polish(uv, &star, &rest, uv[w as usize], density, polish_steps);
            if !admissible(uv, &star, p) {
                return Err(ProlongationError::EmptyKernel { vertex: w });
            }
            if guard.crosses(uv, w, p) && !guard.crosses(uv, w, uv[w as usize]) {
                stats.kept_off_the_boundary += 1;
                continue;
            }
            uv[w as usize] = p;
            stats.polish_steps += taken;
        }
        stats.inserted += 1;
    }
    stats.untangled = untangle(positions, &faces, &incident, uv, &guard, &mut star);
    drop(incident);
    if sweeps > 0 {
        let triangles: Vec<[u32; 3]> = faces.iter().flatten().copied().collect();
        let (steps, refused) = relax(positions, &triangles, uv, density, sweeps, &guard)?;
        stats.polish_steps += steps;
        stats.kept_off_the_boundary += refused;
    }
    Ok(stats)
}

/// Rounds of [`untangle`] at most.
const UNTANGLE_ROUNDS: usize = 4;

/// After the re-insertion: every boundary vertex whose edges still cross the boundary
/// (its placement found no crossing-free position then) is moved to the one
/// [`BoundaryGuard::uncrossed`] finds now that all its neighbours are in place, in up
/// to [`UNTANGLE_ROUNDS`] rounds (a move can free a neighbour's). Returns the vertices
/// moved. Measured: the ICT face id002 opened with seams, where the seam runs through
/// slivers (two boundary vertices 0.006 apart, a seventh of an edge), kept a crossing
/// from its insertion and lost its multilevel start; one move uncrosses it.
fn untangle(
    positions: &[[f64; 3]],
    faces: &[Option<[u32; 3]>],
    incident: &[Vec<u32>],
    uv: &mut [[f64; 2]],
    guard: &BoundaryGuard,
    star: &mut Vec<[u32; 3]>,
) -> usize {
    let mut moved = 0;
    for _ in 0..UNTANGLE_ROUNDS {
        // (The whole loop is in place: one sweep-line test before the O(n²) search.)
        if guard.fine.is_empty()
            || crate::measure::overlap::boundary_crossings(uv, &guard.fine) == 0
        {
            break;
        }
        for &v in &guard.fine {
            if !guard.crosses(uv, v, uv[v as usize]) {
                continue;
            }
            star_of(faces, &incident[v as usize], v, star);
            if let Some(q) = guard.uncrossed(positions, uv, star, v, uv[v as usize]) {
                uv[v as usize] = q;
                moved += 1;
            }
        }
    }
    moved
}

/// `sweeps` Gauss–Seidel sweeps of one local Newton step per vertex over the mesh.
/// Vertices are greedily coloured so that no two of one colour share a face; a colour
/// class is relaxed in parallel (each vertex reads only other colours), the classes
/// one after the other; a step of a boundary vertex that would make the boundary cross
/// itself is not taken (`guard`). Returns the steps taken and those refused.
fn relax<D: Density + ?Sized>(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    uv: &mut [[f64; 2]],
    density: &D,
    sweeps: usize,
    guard: &BoundaryGuard,
) -> Result<(usize, usize), ProlongationError> {
    use rayon::prelude::*;
    let n = uv.len();
    // Stars as CSR: every face once per corner, rotated to start at that corner, with
    // its rest triangle in that corner order.
    let mut offsets = vec![0u32; n + 1];
    for t in triangles {
        for &v in t {
            offsets[v as usize + 1] += 1;
        }
    }
    for v in 0..n {
        offsets[v + 1] += offsets[v];
    }
    let mut fill = offsets.clone();
    let mut star = vec![[0u32; 3]; 3 * triangles.len()];
    for t in triangles {
        for k in 0..3 {
            let v = t[k] as usize;
            star[fill[v] as usize] = [t[k], t[(k + 1) % 3], t[(k + 2) % 3]];
            fill[v] += 1;
        }
    }
    drop(fill);
    let rest: Vec<RestTriangle> = star
        .par_iter()
        .map(|f| {
            RestTriangle::new(
                positions[f[0] as usize],
                positions[f[1] as usize],
                positions[f[2] as usize],
            )
            .ok_or(ProlongationError::DegenerateFace { vertex: f[0] })
        })
        .collect::<Result<_, _>>()?;
    let range = |v: usize| offsets[v] as usize..offsets[v + 1] as usize;
    // Greedy colouring of the vertex graph (neighbours: the star's other corners).
    let mut colour = vec![u8::MAX; n];
    let mut classes: Vec<Vec<u32>> = Vec::new();
    for v in 0..n {
        if offsets[v] == offsets[v + 1] {
            continue;
        }
        let mut used = 0u64;
        for f in &star[range(v)] {
            for &w in &f[1..] {
                let c = colour[w as usize];
                if c < 64 {
                    used |= 1 << c;
                }
            }
        }
        let c = (!used).trailing_zeros() as usize;
        if c >= 64 {
            // Valence beyond 63 neighbours of distinct colours: leave it alone.
            continue;
        }
        colour[v] = c as u8;
        if classes.len() <= c {
            classes.resize_with(c + 1, Vec::new);
        }
        classes[c].push(v as u32);
    }
    let (mut steps, mut refused) = (0, 0);
    let mut moved: Vec<([f64; 2], usize)> = Vec::new();
    for _ in 0..sweeps {
        for class in &classes {
            let current: &[[f64; 2]] = uv;
            class
                .par_iter()
                .with_min_len(256)
                .map(|&v| {
                    let r = range(v as usize);
                    polish(
                        current,
                        &star[r.clone()],
                        &rest[r],
                        current[v as usize],
                        density,
                        1,
                    )
                })
                .collect_into_vec(&mut moved);
            for (&v, &(p, taken)) in class.iter().zip(&moved) {
                if taken == 0 {
                    continue;
                }
                if guard.crosses(uv, v, p) {
                    refused += 1;
                } else {
                    uv[v as usize] = p;
                    steps += taken;
                }
            }
        }
    }
    Ok((steps, refused))
}

/// The current faces around `v` (from its incident face ids), each rotated to
/// `(v, a, b)` (counter-clockwise).
fn star_of(faces: &[Option<[u32; 3]>], incident: &[u32], v: u32, star: &mut Vec<[u32; 3]>) {
    star.clear();
    star.extend(incident.iter().filter_map(|&f| {
        let mut t = faces[f as usize]?;
        while t[0] != v {
            t.rotate_left(1);
        }
        Some(t)
    }));
}

/// Rest triangles of `star` (same corner order); `None` if one is degenerate.
fn rest_of(positions: &[[f64; 3]], star: &[[u32; 3]], rest: &mut Vec<RestTriangle>) -> Option<()> {
    rest.clear();
    for f in star {
        rest.push(RestTriangle::new(
            positions[f[0] as usize],
            positions[f[1] as usize],
            positions[f[2] as usize],
        )?);
    }
    Some(())
}

/// All star faces `(v, a, b)` strictly counter-clockwise with `v` at `p`.
fn admissible(uv: &[[f64; 2]], star: &[[u32; 3]], p: [f64; 2]) -> bool {
    star.iter().all(|f| {
        let area = signed_uv_area([p, uv[f[1] as usize], uv[f[2] as usize]]);
        area > 0.0 && area.is_finite()
    })
}

/// The conformal least-squares position of `v` (module docs, step 1); `None` if a star
/// face is degenerate in 3D.
pub(super) fn conformal_position(
    positions: &[[f64; 3]],
    uv: &[[f64; 2]],
    star: &[[u32; 3]],
    v: u32,
) -> Option<[f64; 2]> {
    let pv = positions[v as usize];
    let mut sum = [0.0; 2];
    for f in star {
        let (pa, pb) = (positions[f[1] as usize], positions[f[2] as usize]);
        let e = sub3(pb, pa);
        let g = sub3(pv, pa);
        let e2 = dot3(e, e);
        let n = cross3(e, g);
        let n_len = dot3(n, n).sqrt();
        if !(e2 > 0.0 && n_len > 0.0) {
            return None;
        }
        // z = (v − a)/(b − a) in the face's plane, v to the left of a → b.
        let (zr, zi) = (dot3(g, e) / e2, n_len / e2);
        let (a, b) = (uv[f[1] as usize], uv[f[2] as usize]);
        let d = [b[0] - a[0], b[1] - a[1]];
        sum[0] += a[0] + zr * d[0] - zi * d[1];
        sum[1] += a[1] + zr * d[1] + zi * d[0];
    }
    let k = star.len() as f64;
    Some([sum[0] / k, sum[1] / k])
}

/// Centroid of the kernel of the star: the convex polygon of points `p` with every
/// `(p, a, b)` counter-clockwise, clipped to a box around the ring (an open star, at
/// the boundary, has an unbounded kernel). `None` if the kernel has no area.
fn kernel_centroid(uv: &[[f64; 2]], star: &[[u32; 3]]) -> Option<[f64; 2]> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for f in star {
        for &w in &f[1..] {
            for c in 0..2 {
                lo[c] = lo[c].min(uv[w as usize][c]);
                hi[c] = hi[c].max(uv[w as usize][c]);
            }
        }
    }
    let pad = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let mut poly = vec![
        [lo[0] - pad, lo[1] - pad],
        [hi[0] + pad, lo[1] - pad],
        [hi[0] + pad, hi[1] + pad],
        [lo[0] - pad, hi[1] + pad],
    ];
    let mut next = Vec::with_capacity(poly.len() + star.len());
    for f in star {
        let (a, b) = (uv[f[1] as usize], uv[f[2] as usize]);
        // Keep the side where (p, a, b) is counter-clockwise: left of a → b.
        let side = |p: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        next.clear();
        for k in 0..poly.len() {
            let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
            let (sp, sq) = (side(p), side(q));
            if sp > 0.0 {
                next.push(p);
            }
            if (sp > 0.0) != (sq > 0.0) {
                let t = sp / (sp - sq);
                next.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
            }
        }
        std::mem::swap(&mut poly, &mut next);
        if poly.len() < 3 {
            return None;
        }
    }
    // Area-weighted centroid of the convex polygon.
    let (mut area, mut cx, mut cy) = (0.0, 0.0, 0.0);
    let o = poly[0];
    for k in 1..poly.len() - 1 {
        let (p, q) = (poly[k], poly[k + 1]);
        let a = 0.5 * ((p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]));
        area += a;
        cx += a * (o[0] + p[0] + q[0]) / 3.0;
        cy += a * (o[1] + p[1] + q[1]) / 3.0;
    }
    (area > 0.0 && area.is_finite()).then(|| [cx / area, cy / area])
}

/// Up to `steps` projected-Newton steps on the star energy `Σ area·W(J)` of a vertex
/// at `p`, the other vertices fixed at `uv`; `star` lists its faces rotated to
/// `(v, a, b)` and `rest` their rest triangles (same corner order). Returns the new
/// position and the steps taken; every step stays below the first flip.
fn polish<D: Density + ?Sized>(
    uv: &[[f64; 2]],
    star: &[[u32; 3]],
    rest: &[RestTriangle],
    p: [f64; 2],
    density: &D,
    steps: usize,
) -> ([f64; 2], usize) {
    let energy_at = |uv: &[[f64; 2]], p: [f64; 2]| -> f64 {
        star.iter()
            .zip(rest)
            .map(|(f, r)| element::energy(r, &[p, uv[f[1] as usize], uv[f[2] as usize]], density))
            .sum()
    };
    let mut p = p;
    let mut taken = 0;
    for _ in 0..steps {
        // Gradient and Hessian of v's corner (the first one of every face).
        let (mut g, mut h) = ([0.0; 2], [[0.0; 2]; 2]);
        let mut star_energy = 0.0;
        for (f, r) in star.iter().zip(rest) {
            let corners = [p, uv[f[1] as usize], uv[f[2] as usize]];
            let (mut eg, mut eh) = ([0.0; 6], [[0.0; 6]; 6]);
            star_energy +=
                element::gradient_and_projected_hessian(r, &corners, density, &mut eg, &mut eh);
            g[0] += eg[0];
            g[1] += eg[1];
            for i in 0..2 {
                for j in 0..2 {
                    h[i][j] += eh[i][j];
                }
            }
        }
        // The star energy at `p`, from the same pass: the element energies that
        // `energy_at` sums, in the same order, so bit for bit its value.
        let energy = star_energy;
        let det = h[0][0] * h[1][1] - h[0][1] * h[1][0];
        if !(det > 0.0 && det.is_finite()) {
            break;
        }
        let d = [
            -(h[1][1] * g[0] - h[0][1] * g[1]) / det,
            -(-h[1][0] * g[0] + h[0][0] * g[1]) / det,
        ];
        let decrement = -(g[0] * d[0] + g[1] * d[1]);
        if decrement.is_nan() || decrement <= 1e-14 * energy.abs() {
            break;
        }
        // Star face areas are linear in v: the first flip along d is at
        // min over shrinking faces of area / shrink rate.
        let mut t_max = f64::INFINITY;
        for f in star {
            let (a, b) = (uv[f[1] as usize], uv[f[2] as usize]);
            let area = signed_uv_area([p, a, b]);
            let rate = 0.5 * (d[0] * (a[1] - b[1]) - d[1] * (a[0] - b[0]));
            if rate < 0.0 {
                t_max = t_max.min(area / -rate);
            }
        }
        let mut t = 1.0f64.min(0.9 * t_max);
        let mut accepted = false;
        for _ in 0..30 {
            let q = [p[0] + t * d[0], p[1] + t * d[1]];
            let e = energy_at(uv, q);
            if e.is_finite() && e <= energy - 1e-4 * t * decrement {
                p = q;
                accepted = true;
                break;
            }
            t *= 0.5;
        }
        if !accepted {
            break;
        }
        taken += 1;
    }
    (p, taken)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::{Alpha, Energy};
    use crate::mesh::generate::{bumpy_disc, spherical_cap};
    use crate::param::count_flipped;
    use crate::param::flatten::{
        CoarseLevel, FlattenOptions, Multilevel, Start, StartMap, flatten,
    };

    fn multilevel(choice: Multilevel) -> Start {
        Start::Auto { multilevel: choice }
    }

    /// A ring of `k` vertices around vertex 0 (counter-clockwise faces `(0, i, i+1)`).
    fn fan(ring: &[[f64; 2]]) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let mut uv = vec![[f64::NAN; 2]];
        uv.extend_from_slice(ring);
        let k = ring.len() as u32;
        let star = (0..k).map(|i| [0, 1 + i, 1 + (i + 1) % k]).collect();
        (uv, star)
    }

    #[test]
    fn the_boundary_guard_links_insertions_and_sees_crossings() {
        // A square with a notch in its top side reaching down to (1.5, 0.1), boundary
        // loop 0 → 4 → 1 → 2 → 6 → 3; vertex 4 (on the bottom side) not placed yet.
        let nan = [f64::NAN; 2];
        let uv = vec![
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [0.0, 1.0],
            nan,
            [0.5, 0.5],
            [1.5, 0.1],
        ];
        let mut guard = BoundaryGuard::new(&[0, 4, 1, 2, 6, 3], &uv);
        // Not yet placed, or off the boundary: never crossing.
        assert!(!guard.crosses(&uv, 4, [1.5, 0.3]));
        assert!(!guard.crosses(&uv, 5, [1.5, 5.0]));
        guard.insert(4);
        assert_eq!(guard.neighbours(1), (0, 1));
        assert_eq!(guard.neighbours(2), (4, 2));
        // Below the notch, or outside the square: nothing crossed.
        assert!(!guard.crosses(&uv, 4, [1.5, 0.05]));
        assert!(!guard.crosses(&uv, 4, [1.0, -0.5]));
        // Above the notch's tip: its edge (4, 1) crosses the notch's side (2, 6).
        assert!(guard.crosses(&uv, 4, [1.5, 0.3]));
        // Moving a placed vertex: 6 pulled below the bottom side crosses (0, 4)/(4, 1)
        // only once 4 is placed (as it now is), and its own neighbours are skipped.
        let mut moved = uv.clone();
        moved[4] = [1.0, 0.0];
        assert!(guard.crosses(&moved, 6, [1.5, -0.2]));
        assert!(!guard.crosses(&moved, 6, [1.5, 0.5]));
        // With no boundary (the guard off) nothing is ever crossing.
        let off = BoundaryGuard::new(&[], &uv);
        assert!(!off.crosses(&uv, 6, [1.5, -0.2]));
        // Nor when none of the loop is placed yet (nothing to link an insertion to).
        let mut unplaced = BoundaryGuard::new(&[4], &uv);
        unplaced.insert(4);
        assert!(!unplaced.crosses(&moved, 4, [1.5, 0.3]));
    }

    #[test]
    fn untangling_moves_a_crossing_boundary_vertex_back_between_its_neighbours() {
        // A U of 3×3 unit squares without the middle column's top two: its arms' inner
        // sides at x = 1 and x = 2. Vertex (1, 2) of the left arm is pulled across the
        // gap to (2.5, 2), into the right arm: its faces only grow (its kernel is open
        // outward), but its boundary edges cross the right arm's inner side.
        let at = |x: u32, y: u32| y * 4 + x;
        let mut faces = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                if i == 1 && j > 0 {
                    continue;
                }
                faces.push(Some([at(i, j), at(i + 1, j), at(i + 1, j + 1)]));
                faces.push(Some([at(i, j), at(i + 1, j + 1), at(i, j + 1)]));
            }
        }
        let positions: Vec<[f64; 3]> = (0..16)
            .map(|v| [(v % 4) as f64, (v / 4) as f64, 0.0])
            .collect();
        let mut uv: Vec<[f64; 2]> = positions.iter().map(|p| [p[0], p[1]]).collect();
        let boundary = [
            at(0, 0),
            at(1, 0),
            at(2, 0),
            at(3, 0),
            at(3, 1),
            at(3, 2),
            at(3, 3),
            at(2, 3),
            at(2, 2),
            at(2, 1),
            at(1, 1),
            at(1, 2),
            at(1, 3),
            at(0, 3),
            at(0, 2),
            at(0, 1),
        ];
        let mut incident = vec![Vec::new(); 16];
        for (f, t) in faces.iter().enumerate() {
            for &v in t.iter().flatten() {
                incident[v as usize].push(f as u32);
            }
        }
        let pulled = at(1, 2) as usize;
        uv[pulled] = [2.5, 2.0];
        let guard = BoundaryGuard::new(&boundary, &uv);
        let mut star = Vec::new();
        star_of(&faces, &incident[pulled], pulled as u32, &mut star);
        assert!(admissible(&uv, &star, uv[pulled]));
        assert!(crate::measure::overlap::boundary_crossings(&uv, &boundary) > 0);
        let moved = untangle(&positions, &faces, &incident, &mut uv, &guard, &mut star);
        // Every vertex whose edges crossed is drawn toward the midpoint of its loop
        // neighbours until it crosses nothing, in loop order: first (2, 1), the right
        // arm's inner corner (its side was crossed: an eighth of the way back suffices),
        // then the pulled vertex itself, halfway back from (1, 2) to (1.75, 2). Nothing
        // crosses any more, every face stays counter-clockwise, nothing else moved.
        assert_eq!(moved, 2);
        assert_eq!(uv[at(2, 1) as usize], [1.5625, 1.4375]);
        assert_eq!(uv[pulled], [1.75, 2.0]);
        assert_eq!(
            crate::measure::overlap::boundary_crossings(&uv, &boundary),
            0
        );
        for t in faces.iter().flatten() {
            assert!(signed_uv_area(t.map(|v| uv[v as usize])) > 0.0, "{t:?}");
        }
        for v in (0..16).filter(|&v| v != pulled && v != at(2, 1) as usize) {
            assert_eq!(uv[v], [positions[v][0], positions[v][1]]);
        }
        // Nothing crossing: nothing to do.
        assert_eq!(
            untangle(&positions, &faces, &incident, &mut uv, &guard, &mut star),
            0
        );
    }

    #[test]
    fn conformal_position_reproduces_a_similarity() {
        // Planar 3D star; UVs are a rotated, scaled, shifted copy: v's conformal
        // least-squares position is the same similarity applied to v.
        let ring3: Vec<[f64; 3]> = [
            [1.0, 0.1],
            [0.4, 0.9],
            [-0.8, 0.7],
            [-0.9, -0.5],
            [0.3, -1.0],
        ]
        .iter()
        .map(|p| [p[0], p[1], 0.0])
        .collect();
        let v3 = [0.05, -0.1, 0.0];
        let (c, s, t) = (0.6 * 1.7, 0.8 * 1.7, [3.0, -2.0]);
        let sim = |p: [f64; 3]| [c * p[0] - s * p[1] + t[0], s * p[0] + c * p[1] + t[1]];
        let (mut uv, star) = fan(&ring3.iter().map(|&p| sim(p)).collect::<Vec<_>>());
        let mut positions = vec![v3];
        positions.extend_from_slice(&ring3);
        let p = conformal_position(&positions, &uv, &star, 0).unwrap();
        let expected = sim(v3);
        assert!((p[0] - expected[0]).abs() < 1e-12 && (p[1] - expected[1]).abs() < 1e-12);
        uv[0] = p;
        assert!(admissible(&uv, &star, p));
    }

    #[test]
    fn kernel_centroid_is_inside_a_non_convex_star() {
        // A star-shaped but non-convex ring (a four-pointed star): its kernel is the
        // small square-like region around the origin.
        let ring = [
            [2.0, 0.0],
            [0.2, 0.2],
            [0.0, 2.0],
            [-0.2, 0.2],
            [-2.0, 0.0],
            [-0.2, -0.2],
            [0.0, -2.0],
            [0.2, -0.2],
        ];
        let (uv, star) = fan(&ring);
        let p = kernel_centroid(&uv, &star).unwrap();
        assert!(admissible(&uv, &star, p), "{p:?}");
        // By symmetry the kernel's centroid is the origin.
        assert!(p[0].abs() < 1e-12 && p[1].abs() < 1e-12, "{p:?}");
        // A ring that winds the wrong way has no kernel.
        let reversed: Vec<[f64; 2]> = ring.iter().rev().copied().collect();
        let (uv, star) = fan(&reversed);
        assert_eq!(kernel_centroid(&uv, &star), None);
    }

    #[test]
    fn polishing_lowers_the_star_energy_and_keeps_it_flip_free() {
        let ring = [
            [1.0, 0.0],
            [0.5, 0.8],
            [-0.5, 0.8],
            [-1.0, 0.0],
            [-0.5, -0.8],
            [0.5, -0.8],
        ];
        let (mut uv, star) = fan(&ring);
        let mut positions = vec![[0.0, 0.0, 0.0]];
        positions.extend(ring.iter().map(|p| [p[0], p[1], 0.0]));
        // Start far off-centre (still admissible): the optimum for this symmetric
        // planar star is the centre (the identity map).
        uv[0] = [0.6, 0.1];
        let density = Alpha::balanced();
        let before: f64 = star_energy(&positions, &uv, &star, &density);
        let mut rest = Vec::new();
        rest_of(&positions, &star, &mut rest).unwrap();
        let (p, taken) = polish(&uv, &star, &rest, uv[0], &density, 20);
        uv[0] = p;
        let after = star_energy(&positions, &uv, &star, &density);
        assert!(taken > 0 && after < before);
        assert!(
            uv[0][0].abs() < 1e-6 && uv[0][1].abs() < 1e-6,
            "{:?}",
            uv[0]
        );
        assert!(admissible(&uv, &star, uv[0]));
    }

    #[test]
    fn the_gradient_pass_returns_the_element_energies_bit_for_bit() {
        // `polish` takes its start energy from the gradient pass instead of an energy
        // pass; that keeps its steps (and every multilevel start) bit-identical only if
        // both give the same value for every element. A bumpy star, a sheared map, and
        // the four presets' densities.
        let ring = [
            [1.0, 0.1],
            [0.4, 0.9],
            [-0.6, 0.7],
            [-1.1, -0.1],
            [-0.4, -0.9],
            [0.7, -0.6],
        ];
        let (mut uv, star) = fan(&ring);
        for (k, p) in uv.iter_mut().enumerate().skip(1) {
            *p = [1.3 * p[0] + 0.4 * p[1], 0.7 * p[1] + 0.05 * k as f64];
        }
        uv[0] = [0.2, -0.1];
        let mut positions = vec![[0.0, 0.0, 0.3]];
        positions.extend(
            ring.iter()
                .enumerate()
                .map(|(k, p)| [p[0], p[1], 0.1 * (k as f64).sin()]),
        );
        let mut rest = Vec::new();
        rest_of(&positions, &star, &mut rest).unwrap();
        for alpha in [
            Alpha::conformal(),
            Alpha::balanced(),
            Alpha::area(),
            Alpha::length(),
        ] {
            let density = Energy::litke(alpha);
            for (f, r) in star.iter().zip(&rest) {
                let corners = [uv[0], uv[f[1] as usize], uv[f[2] as usize]];
                let (mut g, mut h) = ([0.0; 6], [[0.0; 6]; 6]);
                let from_gradient =
                    element::gradient_and_projected_hessian(r, &corners, &density, &mut g, &mut h);
                let alone = element::energy(r, &corners, &density);
                assert!(alone.is_finite() && alone > 0.0);
                assert_eq!(from_gradient.to_bits(), alone.to_bits(), "{alpha:?}");
            }
        }
    }

    fn star_energy(
        positions: &[[f64; 3]],
        uv: &[[f64; 2]],
        star: &[[u32; 3]],
        density: &Alpha,
    ) -> f64 {
        star.iter()
            .map(|f| {
                let r = RestTriangle::new(
                    positions[f[0] as usize],
                    positions[f[1] as usize],
                    positions[f[2] as usize],
                )
                .unwrap();
                element::energy(
                    &r,
                    &[uv[f[0] as usize], uv[f[1] as usize], uv[f[2] as usize]],
                    density,
                )
            })
            .sum()
    }

    #[test]
    fn a_coarse_level_that_is_not_coarser_is_abandoned_with_the_reason() {
        let mesh = bumpy_disc(6, 0.3);
        let r = flatten(
            &mesh,
            &FlattenOptions::default().with_start(multilevel(Multilevel::Always(
                CoarseLevel::with_vertices(mesh.positions.len()),
            ))),
        )
        .unwrap();
        assert_ne!(r.start, StartMap::Multilevel);
        let reason = r.multilevel.unwrap().abandoned.unwrap();
        assert!(reason.contains("not even twice"), "{reason}");
        assert_eq!(r.flipped_triangles, 0);
    }

    #[test]
    fn continuation_runs_on_the_coarse_level_and_reaches_the_same_minimum() {
        let mesh = bumpy_disc(20, 0.4);
        let options = |choice| {
            FlattenOptions::new(Energy::litke_from(Alpha::conformal(), Alpha::balanced()))
                .with_start(multilevel(choice))
        };
        let single = flatten(&mesh, &options(Multilevel::Never)).unwrap();
        let multi = flatten(&mesh, &options(Multilevel::Always(CoarseLevel::default()))).unwrap();
        assert_eq!(multi.start, StartMap::Multilevel);
        let report = multi.multilevel.unwrap();
        assert_eq!(
            report.coarse_continuation.last(),
            single.continuation.last(),
            "both end at the target α"
        );
        assert!(report.coarse_continuation.len() >= 2);
        assert!((multi.energy - single.energy).abs() <= 1e-9 * single.energy);
        assert_eq!(multi.flipped_triangles, 0);
    }

    #[test]
    fn multilevel_flattening_reaches_the_single_level_minimum() {
        for mesh in [bumpy_disc(24, 0.4), spherical_cap(1.0, 1.6, 20, 60)] {
            for energy in [
                Energy::litke(Alpha::balanced()),
                Energy::litke(Alpha::conformal()),
                Energy::SymmetricDirichlet,
            ] {
                let single = flatten(
                    &mesh,
                    &FlattenOptions::new(energy).with_start(multilevel(Multilevel::Never)),
                )
                .unwrap();
                let multi = flatten(
                    &mesh,
                    &FlattenOptions::new(energy).with_start(multilevel(Multilevel::Always(
                        CoarseLevel::with_vertices(mesh.positions.len() / 8),
                    ))),
                )
                .unwrap();
                let report = multi.multilevel.as_ref().unwrap();
                assert_eq!(report.abandoned, None);
                assert_eq!(multi.start, StartMap::Multilevel);
                assert!(report.coarse_vertices <= mesh.positions.len() / 4);
                assert_eq!(
                    report.prolongation.inserted + report.coarse_vertices,
                    mesh.positions.len()
                );
                assert!(multi.converged && single.converged);
                assert_eq!(count_flipped(&multi.uvs, &mesh.triangles), 0);
                assert!(
                    (multi.energy - single.energy).abs() <= 1e-9 * single.energy,
                    "{energy:?}: {} vs {}",
                    multi.energy,
                    single.energy
                );
            }
        }
    }
}
