//! A multilevel start's crushed boundary contacts and squeezed triangles relieved by a
//! local solve before the full solve.
//!
//! A multilevel start re-inserts the fine vertices into the coarse map; where the coarse
//! map closes a slit to a sharp tip (the corner of a mouth opened by a seam), the
//! re-inserted boundary vertices of its two sides can only sit a tiny fraction of the
//! barrier's reach `ε` apart ([`super::barrier`]). Such a *crushed* pair costs the
//! barrier `b(d) ≈ −κ ε² ln(d/ε)`, large, and the full barrier solve spends its first
//! iterations opening the tip with steps the contact bound cuts short. Measured on
//! the ICT face id000 opened with seams (BENCHMARKS.md, "Hard discs"): 18 pairs closer
//! than `ε/10`, the closest at `4·10⁻⁴ ε`, around one mouth corner, barrier energy 5.7
//! against the map's 2.5 (1.84 at the minimum), and 17 barrier iterations where the
//! other faces need 3–11.
//!
//! The relief solves the same problem — the elastic energy `Σ_T area(T)·W` (thesis
//! (2.5)) plus the barrier `E_B` — on a patch only: the vertices within
//! [`RELIEF_RINGS`] rings of every vertex of a crushed pair (closer than
//! [`CRUSHED_FRACTION`] of its `ε`) are free, every other vertex is fixed, and the
//! energy is summed over the triangles with a free corner, so each step is as
//! flip-free and crossing-free as the full solve's (the flip-free and contact bounds
//! of [`NewtonSolver`]). Its stopping threshold is the full barrier solve's own,
//! `λ²/2 ≤ 10⁻⁴·E` of the whole map's energy `E`: the patch is relieved as far as the
//! full solve would resolve it, no further.
//!
//! **Hot spots** ([`relieve_hot_spots`]): the same local solve for a multilevel start's
//! squeezed triangles. Re-inserting the fine vertices one at a time can leave a few
//! triangles nearly flat in UV where the coarse map was tight (camelhead subdivided 2×,
//! 363k faces: the two worst triangles held 66 % of the start's energy, 21.1 against
//! 5.35 at the minimum); the full solve's first steps are then cut to 1–10 % of
//! Newton's by the flip-free bound, and it took 22 iterations (21 s). The triangles whose
//! energy density is [`HOT_DENSITY_FACTOR`] times the map's mean or more, and
//! [`RELIEF_RINGS`] rings around them, are solved as a patch first (0.15 s there; the
//! full solve then takes 9 iterations), with the barrier where the map must not overlap.

use super::barrier::BoundaryBarrier;
use super::element::{self, RestTriangle};
use super::newton::{BARRIER_RELATIVE_TOLERANCE, NewtonSettings, NewtonSolver};
use crate::energy::Density;
use crate::linsolve::SolveError;
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// A barrier pair is crushed when its distance is below this fraction of its `ε`.
/// Measured on the 13 ICT faces opened with seams: three starts have such pairs (18, 1
/// and 1 of them), the other ten none (their closest pairs at 0.19–0.71 ε); relieving
/// every pair within `ε` instead made the total Newton work 3.6 % smaller but four
/// faces 3–7 % slower (instruction counts, BENCHMARKS.md "Hard discs").
pub const CRUSHED_FRACTION: f64 = 0.1;

/// Rings of vertices around the crushed pairs or hot triangles that a relief frees.
pub const RELIEF_RINGS: usize = 4;

/// What the crushed-contact relief did (reports).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ContactRelief {
    /// Barrier pairs closer than [`CRUSHED_FRACTION`] of their `ε` at the start.
    pub crushed_pairs: usize,
    #[serde(flatten)]
    pub solve: PatchSolve,
}

/// The local solve of a relief (reports).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PatchSolve {
    /// Vertices freed for the local solve.
    pub vertices: usize,
    /// Its Newton iterations.
    pub iterations: usize,
    /// Energy of the patch's triangles (per unit area of the whole surface; with the
    /// barrier's term over the whole boundary when there is one), before and after.
    pub energy_before: f64,
    pub energy_after: f64,
    /// Seconds, finding what to relieve included.
    pub seconds: f64,
}

/// Relieves the crushed barrier pairs of the start `uv` (a flip-free map of the disc
/// `triangles` whose `boundary` loop does not cross itself; `rest`: one rest triangle
/// per triangle, unit-area positions) by a local barrier solve of `density` around
/// them (module docs). `None`, with `uv` untouched, when no pair is crushed or when the
/// patch would hold more than half of the vertices (the full solve is then no dearer).
/// The result is flip-free and crossing-free, with every vertex outside the patch where
/// it was.
pub fn relieve_crushed_contacts<D: Density + ?Sized>(
    uv: &mut [[f64; 2]],
    triangles: &[[u32; 3]],
    rest: &[RestTriangle],
    boundary: &[u32],
    density: &D,
    settings: &NewtonSettings,
) -> Result<Option<ContactRelief>, SolveError> {
    let clock = Instant::now();
    let barrier = BoundaryBarrier::new(boundary, uv).with_faces(triangles);
    let mut free = vec![false; uv.len()];
    let mut crushed_pairs = 0;
    barrier.for_each_pair_within(uv, CRUSHED_FRACTION, |pair| {
        crushed_pairs += 1;
        pair.iter().for_each(|&v| free[v as usize] = true);
    });
    if crushed_pairs == 0 {
        return Ok(None);
    }
    // The full solve's threshold, from the whole map's energy.
    let whole = NewtonSolver::energy_of(rest, triangles)(uv, density) + barrier.energy(uv);
    let tolerance = settings.tolerance.max(BARRIER_RELATIVE_TOLERANCE * whole);
    let solve = solve_patch(
        uv,
        triangles,
        rest,
        free,
        density,
        settings,
        tolerance,
        Some(barrier),
        clock,
    )?;
    Ok(solve.map(|solve| ContactRelief {
        crushed_pairs,
        solve,
    }))
}

/// A triangle is a hot spot of a start when its energy density (energy per unit 3D
/// area) is at least this many times the map's mean. Measured on the multilevel starts
/// of camelhead subdivided 2× (363k faces; full-solve iterations after the relief):
/// none 22, factor 50 12, 10 9, 4 8 (422 triangles, 0.09 s). Lionhead subdivided 3×
/// (1.07M faces) has none at 10: its start was already within 0.2 % of the minimum.
pub const HOT_DENSITY_FACTOR: f64 = 10.0;

/// The patch solve's stopping threshold relative to the whole map's energy: the
/// patch is brought close to its own minimum (a hot spot limits the full solve's steps
/// through the flip-free bound, not through its energy).
const HOT_RELATIVE_TOLERANCE: f64 = 1e-6;

/// What the hot-spot relief did (reports).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct HotSpotRelief {
    /// Triangles at [`HOT_DENSITY_FACTOR`] times the mean energy density or more.
    pub hot_triangles: usize,
    #[serde(flatten)]
    pub solve: PatchSolve,
}

/// Relieves the hot spots of the start `uv` (a flip-free map of `triangles`; `rest`:
/// one rest triangle per triangle, unit-area positions) by a local solve of `density`
/// around them (module docs), with the boundary barrier of `boundary` when it is given
/// (the map must then not cross itself, and stays so). `None`, with `uv` untouched,
/// when there is no hot spot or the patch would hold more than half of the vertices.
/// The result is flip-free, with every vertex outside the patch where it was.
pub fn relieve_hot_spots<D: Density + ?Sized>(
    uv: &mut [[f64; 2]],
    triangles: &[[u32; 3]],
    rest: &[RestTriangle],
    boundary: Option<&[u32]>,
    density: &D,
    settings: &NewtonSettings,
) -> Result<Option<HotSpotRelief>, SolveError> {
    let clock = Instant::now();
    // Per triangle, in parallel (1.45M triangles on camelhead subdivided 3×); summed
    // in order below.
    let energies: Vec<f64> = triangles
        .par_iter()
        .zip(rest)
        .map(|(t, r)| {
            element::energy(
                r,
                &[uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]],
                density,
            )
        })
        .collect();
    let whole: f64 = energies.iter().sum();
    let area: f64 = rest.iter().map(|r| r.area).sum();
    if !(whole.is_finite() && area > 0.0) {
        return Ok(None);
    }
    let hot_density = HOT_DENSITY_FACTOR * whole / area;
    let mut free = vec![false; uv.len()];
    let mut hot_triangles = 0;
    for ((t, r), e) in triangles.iter().zip(rest).zip(&energies) {
        if *e > hot_density * r.area {
            hot_triangles += 1;
            t.iter().for_each(|&v| free[v as usize] = true);
        }
    }
    if hot_triangles == 0 {
        return Ok(None);
    }
    let barrier = boundary.map(|b| BoundaryBarrier::new(b, uv).with_faces(triangles));
    let tolerance = settings.tolerance.max(HOT_RELATIVE_TOLERANCE * whole);
    let solve = solve_patch(
        uv, triangles, rest, free, density, settings, tolerance, barrier, clock,
    )?;
    Ok(solve.map(|solve| HotSpotRelief {
        hot_triangles,
        solve,
    }))
}

/// The local solve of both reliefs: the vertices marked in `free` and [`RELIEF_RINGS`]
/// rings around them are free, every other vertex is pinned, and the energy (with
/// `barrier`'s term when given) is summed over the triangles with a free corner,
/// minimized to `tolerance` (`clock`: since the relief began). `None`, with `uv`
/// untouched, when the patch would hold more than half of the vertices (the full solve
/// is then no dearer).
#[allow(clippy::too_many_arguments)]
fn solve_patch<D: Density + ?Sized>(
    uv: &mut [[f64; 2]],
    triangles: &[[u32; 3]],
    rest: &[RestTriangle],
    mut free: Vec<bool>,
    density: &D,
    settings: &NewtonSettings,
    tolerance: f64,
    barrier: Option<BoundaryBarrier>,
    clock: Instant,
) -> Result<Option<PatchSolve>, SolveError> {
    let n = uv.len();
    let mut ring = free.clone();
    for _ in 0..RELIEF_RINGS {
        for t in triangles {
            if t.iter().any(|&v| free[v as usize]) {
                t.iter().for_each(|&v| ring[v as usize] = true);
            }
        }
        free.copy_from_slice(&ring);
    }
    let vertices = free.iter().filter(|&&f| f).count();
    if 2 * vertices > n {
        return Ok(None);
    }
    let (patch, patch_rest): (Vec<[u32; 3]>, Vec<RestTriangle>) = triangles
        .iter()
        .zip(rest)
        .filter(|(t, _)| t.iter().any(|&v| free[v as usize]))
        .map(|(t, r)| (*t, *r))
        .unzip();
    let pins: Vec<(u32, usize)> = (0..n as u32)
        .filter(|&v| !free[v as usize])
        .flat_map(|v| [(v, 0), (v, 1)])
        .collect();
    let local = NewtonSettings {
        tolerance,
        ..*settings
    };
    let mut solver = NewtonSolver::new(n, &patch, patch_rest, &pins, None)?;
    let barrier_start = barrier.as_ref().map_or(0.0, |b| b.energy(uv));
    let energy_before = solver.energy(uv, density) + barrier_start;
    if let Some(barrier) = barrier {
        solver.set_barrier(barrier);
    }
    let (_, iterations, energy_after) =
        solver.minimize(uv, density, &local, 0, clock, &mut |_| {})?;
    Ok(Some(PatchSolve {
        vertices,
        iterations,
        energy_before,
        energy_after,
        seconds: clock.elapsed().as_secs_f64(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::{Alpha, Energy};
    use crate::measure::overlap::boundary_crossings;
    use crate::mesh::{Disc, TriMesh};
    use crate::param::count_flipped;
    use crate::param::element::rest_triangles;

    /// A flat U, 7 × 3 units, `m` cells per unit, whose slot (x in [3, 4], y > 1) is
    /// squeezed in the start map to a gap of `gap`: the left part stretched so that its
    /// inner side lies at x = 4 − gap (x' = x · x₁(y)/3 for x ≤ 3, the slot's floor
    /// compressed between x₁(y) and 4, with x₁ = 3 + (1 − gap) · min(y, 1)). The map
    /// is increasing in x on every row, so no triangle turns over.
    fn squeezed_u(m: u32, gap: f64) -> (TriMesh, Vec<[f64; 2]>) {
        let (w, h) = (7 * m + 1, 3 * m + 1);
        let at = |i: u32, j: u32| j * w + i;
        let in_slot = |i: u32, j: u32| i >= 3 * m && i < 4 * m && j >= m;
        let mut triangles = Vec::new();
        for j in 0..h - 1 {
            for i in 0..w - 1 {
                if in_slot(i, j) {
                    continue;
                }
                triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        let xy = |v: u32| {
            let (i, j) = (v % w, v / w);
            (f64::from(i) / f64::from(m), f64::from(j) / f64::from(m))
        };
        let positions: Vec<[f64; 3]> = (0..w * h)
            .map(|v| {
                let (x, y) = xy(v);
                [x, y, 0.0]
            })
            .collect();
        let uv: Vec<[f64; 2]> = (0..w * h)
            .map(|v| {
                let (x, y) = xy(v);
                let x1 = 3.0 + (1.0 - gap) * y.min(1.0);
                let u = if x <= 3.0 {
                    x * x1 / 3.0
                } else if x <= 4.0 {
                    x1 + (x - 3.0) * (4.0 - x1)
                } else {
                    x
                };
                [u, y]
            })
            .collect();
        // The slot's inner vertices (strictly between its sides, above its floor) are
        // not referenced: drop them.
        let kept: Vec<u32> = (0..w * h)
            .filter(|&v| !(v % w > 3 * m && v % w < 4 * m && v / w > m))
            .collect();
        let mut index = vec![u32::MAX; (w * h) as usize];
        for (k, &v) in kept.iter().enumerate() {
            index[v as usize] = k as u32;
        }
        let triangles = triangles
            .iter()
            .map(|t| t.map(|v| index[v as usize]))
            .collect();
        let positions = kept.iter().map(|&v| positions[v as usize]).collect();
        let uv = kept.iter().map(|&v| uv[v as usize]).collect();
        (TriMesh::new(positions, triangles), uv)
    }

    #[test]
    fn a_crushed_slit_is_opened_locally_flip_free_and_crossing_free() {
        let (mesh, start) = squeezed_u(6, 1e-3);
        let disc = Disc::new(&mesh).expect("a U is a disc");
        let boundary = disc.boundary();
        let rest = rest_triangles(&mesh.positions, &mesh.triangles).unwrap();
        let energy = Energy::litke(Alpha::balanced());
        assert_eq!(count_flipped(&start, &mesh.triangles), 0);
        assert_eq!(boundary_crossings(&start, boundary), 0);
        let mut uv = start.clone();
        let relief = relieve_crushed_contacts(
            &mut uv,
            &mesh.triangles,
            &rest,
            boundary,
            &energy,
            &NewtonSettings::default(),
        )
        .unwrap()
        .expect("the slit's sides are crushed together");
        assert!(relief.crushed_pairs > 10, "{relief:?}");
        assert!(2 * relief.solve.vertices < uv.len(), "{relief:?}");
        assert!(
            relief.solve.energy_after < 0.1 * relief.solve.energy_before,
            "{relief:?}"
        );
        assert_eq!(count_flipped(&uv, &mesh.triangles), 0);
        assert_eq!(boundary_crossings(&uv, boundary), 0);
        // No pair is crushed any more, measured as the full solve will measure it: with
        // a barrier built on the relieved map.
        let after = BoundaryBarrier::new(boundary, &uv).with_faces(&mesh.triangles);
        let mut still = 0;
        after.for_each_pair_within(&uv, CRUSHED_FRACTION, |_| still += 1);
        assert_eq!(still, 0);
        // Only the patch moved: the far ends of the U stay where they were.
        let moved = |v: usize| (uv[v][0] - start[v][0]).hypot(uv[v][1] - start[v][1]) > 0.0;
        let far = (0..uv.len())
            .filter(|&v| mesh.positions[v][0] < 1.0 || mesh.positions[v][0] > 6.0)
            .collect::<Vec<_>>();
        assert!(!far.is_empty() && far.iter().all(|&v| !moved(v)));
        assert!((0..uv.len()).any(moved));
    }

    #[test]
    fn a_start_without_crushed_pairs_is_left_alone() {
        // The same U with its slot squeezed to 0.02 (ε is a quarter of the mean
        // boundary edge, about 0.04): pairs within ε, none crushed.
        let (mesh, start) = squeezed_u(6, 0.02);
        let disc = Disc::new(&mesh).unwrap();
        let rest = rest_triangles(&mesh.positions, &mesh.triangles).unwrap();
        let barrier = BoundaryBarrier::new(disc.boundary(), &start).with_faces(&mesh.triangles);
        let mut within = 0;
        barrier.for_each_pair_within(&start, 1.0, |_| within += 1);
        assert!(within > 10, "{within} pairs within ε");
        let mut uv = start.clone();
        let relief = relieve_crushed_contacts(
            &mut uv,
            &mesh.triangles,
            &rest,
            disc.boundary(),
            &Energy::litke(Alpha::balanced()),
            &NewtonSettings::default(),
        )
        .unwrap();
        assert_eq!(relief, None);
        assert_eq!(uv, start);
    }

    /// The flat U (its identity map: an isometry, uniform energy density) with one
    /// interior vertex pushed towards a neighbour until 0.1 % short of the first flip,
    /// and that vertex.
    fn u_with_a_squeezed_vertex() -> (TriMesh, Vec<[f64; 2]>, usize) {
        let (mesh, _) = squeezed_u(6, 1.0);
        let mut uv: Vec<[f64; 2]> = mesh.positions.iter().map(|p| [p[0], p[1]]).collect();
        let near = |v: usize, x: f64, y: f64| (uv[v][0] - x).hypot(uv[v][1] - y);
        let v = (0..uv.len())
            .min_by(|&a, &b| near(a, 1.5, 1.5).total_cmp(&near(b, 1.5, 1.5)))
            .unwrap();
        let a = mesh.triangles.iter().find(|t| t[0] as usize == v).unwrap()[1] as usize;
        let mut direction = vec![[0.0; 2]; uv.len()];
        direction[v] = [uv[a][0] - uv[v][0], uv[a][1] - uv[v][1]];
        let t = crate::param::flip_free::max_flip_free_step(&uv, &mesh.triangles, &direction);
        let t = 0.999 * t.min(1.0);
        uv[v] = [
            uv[v][0] + t * direction[v][0],
            uv[v][1] + t * direction[v][1],
        ];
        (mesh, uv, v)
    }

    #[test]
    fn a_squeezed_triangle_is_relieved_locally_and_the_full_solve_then_needs_fewer_iterations() {
        let (mesh, start, squeezed) = u_with_a_squeezed_vertex();
        let (positions, _) = mesh.unit_area_positions();
        let scale = (mesh.area()).sqrt();
        let start: Vec<[f64; 2]> = start.iter().map(|p| [p[0] / scale, p[1] / scale]).collect();
        let rest = rest_triangles(&positions, &mesh.triangles).unwrap();
        let energy = Energy::litke(Alpha::balanced());
        assert_eq!(count_flipped(&start, &mesh.triangles), 0);
        let density = |uv: &[[f64; 2]]| -> (f64, f64) {
            let e: Vec<f64> = mesh
                .triangles
                .iter()
                .zip(&rest)
                .map(|(t, r)| {
                    let c = [uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]];
                    element::energy(r, &c, &energy) / r.area
                })
                .collect();
            let whole = NewtonSolver::energy_of(&rest, &mesh.triangles)(uv, &energy);
            (e.iter().copied().fold(0.0, f64::max), whole)
        };
        let (worst, whole) = density(&start);
        assert!(
            worst > 100.0 * whole,
            "the squeeze makes a hot spot: {worst} vs {whole}"
        );
        let mut uv = start.clone();
        let relief = relieve_hot_spots(
            &mut uv,
            &mesh.triangles,
            &rest,
            None,
            &energy,
            &NewtonSettings::default(),
        )
        .unwrap()
        .expect("a hot spot");
        assert!(
            relief.hot_triangles >= 1 && 2 * relief.solve.vertices < uv.len(),
            "{relief:?}"
        );
        assert!(
            relief.solve.energy_after < relief.solve.energy_before,
            "{relief:?}"
        );
        assert_eq!(count_flipped(&uv, &mesh.triangles), 0);
        // No hot spot is left, and only the patch moved: the U's far ends stay.
        let (worst, whole) = density(&uv);
        assert!(worst < HOT_DENSITY_FACTOR * whole, "{worst} vs {whole}");
        let moved = |v: usize| (uv[v][0] - start[v][0]).hypot(uv[v][1] - start[v][1]) > 0.0;
        assert!(moved(squeezed));
        let far: Vec<usize> = (0..uv.len())
            .filter(|&v| mesh.positions[v][0] > 5.0)
            .collect();
        assert!(!far.is_empty() && far.iter().all(|&v| !moved(v)));
        // The full solve from each start: the relieved one converges in less than half
        // the squeezed one's iterations, to the same minimum.
        let boundary = Disc::new(&mesh).unwrap().boundary().to_vec();
        let (p0, p1) = (boundary[0], boundary[boundary.len() / 2]);
        let solve = |from: &[[f64; 2]]| {
            let mut solver = NewtonSolver::new(
                from.len(),
                &mesh.triangles,
                rest.clone(),
                &[(p0, 0), (p0, 1), (p1, 1)],
                None,
            )
            .unwrap();
            let mut uv = from.to_vec();
            let (stop, iterations, energy_end) = solver
                .minimize(
                    &mut uv,
                    &energy,
                    &NewtonSettings::default(),
                    0,
                    Instant::now(),
                    &mut |_| {},
                )
                .unwrap();
            assert_eq!(stop, super::super::newton::StopReason::Converged);
            (iterations, energy_end)
        };
        let (it_squeezed, e_squeezed) = solve(&start);
        let (it_relieved, e_relieved) = solve(&uv);
        // (14 against 3 iterations when written.)
        assert!(
            2 * it_relieved < it_squeezed,
            "{it_relieved} vs {it_squeezed}"
        );
        assert!((e_squeezed - e_relieved).abs() <= 1e-9 * e_squeezed);
    }

    #[test]
    fn a_start_without_hot_spots_is_left_alone() {
        // The U's identity map: every triangle at the same energy density.
        let (mesh, _) = squeezed_u(6, 1.0);
        let start: Vec<[f64; 2]> = mesh.positions.iter().map(|p| [p[0], p[1]]).collect();
        let rest = rest_triangles(&mesh.positions, &mesh.triangles).unwrap();
        let mut uv = start.clone();
        let relief = relieve_hot_spots(
            &mut uv,
            &mesh.triangles,
            &rest,
            None,
            &Energy::litke(Alpha::balanced()),
            &NewtonSettings::default(),
        )
        .unwrap();
        assert_eq!(relief, None);
        assert_eq!(uv, start);
    }
}
