//! The start of a solve (thesis §3.1.1): the initial map — LSCM with the mean-value
//! fallback, mean-value coordinates, the caller's map, or the multilevel start (the
//! flattening of a decimated copy, re-inserted vertex by vertex) — made admissible
//! (mirrored if reflected, refused if flipped), scaled to the surface's area and pinned
//! against rigid motions.

use super::error::FlattenError;
use super::options::{Bijective, CoarseLevel, FlattenOptions, Multilevel, Start};
use super::result::{Flattening, MultilevelReport, StartMap};
use crate::linsolve::SolveError;
use crate::measure::overlap::boundary_crossings;
use crate::mesh::{Disc, TriMesh};
use crate::param::plan::Cut;
use crate::param::protrusions::StartMaps;
use crate::param::{count_flipped, lscm, make_admissible, signed_uv_area, tutte};
use std::time::Instant;

/// The flattening entry point, handed down to the multilevel start (which flattens a
/// decimated copy with it) so that this module need not import its parent.
pub(super) type FlattenFn = fn(&TriMesh, &FlattenOptions) -> Result<Flattening, FlattenError>;

/// The multilevel start, computed once by the first solve of a disc and reused by the
/// barrier solve when its boundary does not cross itself (its coarse level was solved
/// with the same [`Bijective`] option, so it is overlap-free there).
pub(super) enum SharedStart {
    NotTried,
    /// No coarse level for this mesh size or options.
    None,
    /// The start (`None` when abandoned) and its report.
    Tried(Option<Vec<[f64; 2]>>, Box<MultilevelReport>),
}

/// What the solves of one disc share for their starts: the multilevel start and the
/// initial maps computed before the solve ([`crate::param::protrusions`] computes LSCM,
/// and mean-value coordinates when LSCM flips, to check the start), used instead of
/// computing them again.
pub(super) struct Starts {
    pub(super) multilevel: SharedStart,
    pub(super) maps: Option<StartMaps>,
}

/// The initial map of a solve, before it is checked.
pub(super) struct InitialMap {
    /// One UV per vertex: unit-area units for LSCM and mean-value coordinates, the mesh's
    /// units for a given or multilevel start.
    pub(super) uv: Vec<[f64; 2]>,
    pub(super) map: StartMap,
    /// Triangles LSCM flipped or degenerated (0 when LSCM did not run).
    pub(super) lscm_flipped: usize,
    /// The multilevel start's report, when it was tried.
    pub(super) multilevel: Option<MultilevelReport>,
}

/// The initial map `options.start` asks for on `mesh` (`positions`: scaled to unit
/// area). With the barrier (`barrier`) the start must not cross itself: LSCM and a
/// given map fall back to mean-value coordinates, a multilevel start to LSCM. `starts`:
/// the multilevel start, computed by the first solve that needs it, and the maps
/// computed before the solve.
pub(super) fn initial_map(
    mesh: &TriMesh,
    disc: &Disc,
    positions: &[[f64; 3]],
    options: &FlattenOptions,
    barrier: bool,
    starts: &mut Starts,
    flatten: FlattenFn,
) -> Result<InitialMap, FlattenError> {
    let boundary = disc.boundary();
    let (shared, maps) = (&mut starts.multilevel, starts.maps.as_ref());
    let lscm_or_fallback =
        |fallback: bool| lscm_start(mesh, disc, positions, barrier, fallback, maps);
    let mean_value = || -> Result<_, FlattenError> {
        Ok(InitialMap::plain(
            tutte::mean_value(positions, disc)?,
            StartMap::MeanValue,
        ))
    };
    match &options.start {
        Start::Given(given) => {
            check_given_length(given, mesh)?;
            let mut uv = given.clone();
            if barrier
                && (make_admissible(&mut uv, &mesh.triangles) > 0
                    || boundary_crossings(&uv, boundary) > 0)
            {
                mean_value()
            } else {
                Ok(InitialMap::plain(given.clone(), StartMap::Given))
            }
        }
        Start::MeanValue => mean_value(),
        Start::Lscm => lscm_or_fallback(barrier),
        Start::Auto { multilevel: choice } => {
            if matches!(shared, SharedStart::NotTried) {
                *shared = match choice.coarse_level(mesh.triangles.len()) {
                    Some(coarse) => {
                        let (uv, report) = multilevel_start(mesh, disc, options, coarse, flatten);
                        SharedStart::Tried(uv, Box::new(report))
                    }
                    None => SharedStart::None,
                };
            }
            match shared {
                SharedStart::Tried(Some(uv), report)
                    if !barrier || boundary_crossings(uv, boundary) == 0 =>
                {
                    Ok(InitialMap {
                        multilevel: Some(MultilevelReport::clone(report)),
                        ..InitialMap::plain(uv.clone(), StartMap::Multilevel)
                    })
                }
                SharedStart::Tried(uv, report) => {
                    let mut report = MultilevelReport::clone(report);
                    if uv.is_some() {
                        report.abandoned =
                            Some("its boundary crosses itself (a barrier solve)".into());
                    }
                    Ok(InitialMap {
                        multilevel: Some(report),
                        ..lscm_or_fallback(true)?
                    })
                }
                SharedStart::None | SharedStart::NotTried => lscm_or_fallback(true),
            }
        }
    }
}

impl InitialMap {
    fn plain(uv: Vec<[f64; 2]>, map: StartMap) -> Self {
        Self {
            uv,
            map,
            lscm_flipped: 0,
            multilevel: None,
        }
    }

    /// Makes the map admissible (mirrored if most triangles are negative) and refuses
    /// one that still flips a triangle, naming the start that did.
    pub(super) fn check(
        &mut self,
        mesh: &TriMesh,
        options: &FlattenOptions,
    ) -> Result<(), FlattenError> {
        let start_flipped = make_admissible(&mut self.uv, &mesh.triangles);
        if start_flipped > 0 && matches!(self.map, StartMap::Given | StartMap::Multilevel) {
            return Err(FlattenError::GivenStartFlipped(start_flipped));
        }
        if start_flipped > 0 && matches!(options.start, Start::Lscm) {
            return Err(FlattenError::LscmFlipped(start_flipped));
        }
        if start_flipped > 0 {
            return Err(FlattenError::NoAdmissibleStart {
                lscm: self.lscm_flipped,
                mean_value: start_flipped,
            });
        }
        Ok(())
    }

    /// Whether an unconstrained solve from this (admissible) start would end overlapping
    /// itself: its boundary crosses already, or its coarse level needed the barrier
    /// (measured: ICT faces opened with seams, BENCHMARKS.md "Hard discs"; so does one
    /// whose coarse level was solved with the barrier because its boundary runs along
    /// itself: seams). A given start is the user's: it is solved from as given.
    pub(super) fn leads_to_overlap(&self, boundary: &[u32]) -> bool {
        let coarse_overlapped = self.map == StartMap::Multilevel
            && self.multilevel.as_ref().is_some_and(|m| m.coarse_barrier);
        self.map != StartMap::Given
            && (coarse_overlapped || boundary_crossings(&self.uv, boundary) > 0)
    }

    /// Scales the start so its area matches the (unit) surface area — lengths scale by
    /// √(area3D / areaUV), the thesis's "ratio of the surface area versus the area of
    /// the domain" (§3.1.1) taken for lengths; a given or multilevel map is in the mesh's
    /// units and only normalized by `scale` — and pins it: the two boundary vertices
    /// farthest apart, `(p0, p1)` (returned), moved to the origin and onto the u axis.
    pub(super) fn scale_and_pin(
        &mut self,
        mesh: &TriMesh,
        boundary: &[u32],
        scale: f64,
    ) -> (u32, u32) {
        let uv = &mut self.uv;
        let uv_area: f64 = mesh
            .triangles
            .iter()
            .map(|t| signed_uv_area([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]]))
            .sum();
        let s = if matches!(self.map, StartMap::Given | StartMap::Multilevel) {
            1.0 / scale
        } else {
            (1.0 / uv_area).sqrt()
        };
        let (p0, p1) = farthest_pair(uv, boundary);
        uv.iter_mut().for_each(|p| *p = [s * p[0], s * p[1]]);
        align_pins(uv, p0, p1);
        (p0, p1)
    }

    /// Pins the start as [`Self::scale_and_pin`] does, without scaling it (a map in
    /// the solve's normalized units already).
    pub(super) fn pin(&mut self, boundary: &[u32]) -> (u32, u32) {
        let (p0, p1) = farthest_pair(&self.uv, boundary);
        align_pins(&mut self.uv, p0, p1);
        (p0, p1)
    }
}

/// LSCM on the full mesh, made admissible; when it flips a triangle (or, with the
/// barrier, crosses itself) and `fallback`, mean-value coordinates instead. `cached`:
/// either map, when already computed.
fn lscm_start(
    mesh: &TriMesh,
    disc: &Disc,
    positions: &[[f64; 3]],
    barrier: bool,
    fallback: bool,
    cached: Option<&StartMaps>,
) -> Result<InitialMap, FlattenError> {
    let mut uv = match cached {
        Some(maps) => maps.lscm.clone(),
        None => lscm::lscm(positions, disc)?.uv,
    };
    let lscm_flipped = make_admissible(&mut uv, &mesh.triangles);
    // With the barrier, the start must not overlap itself either.
    let usable = lscm_flipped == 0 && (!barrier || boundary_crossings(&uv, disc.boundary()) == 0);
    let (uv, map) = if usable || !fallback {
        (uv, StartMap::Lscm)
    } else {
        let mean_value = match cached.and_then(|maps| maps.mean_value.clone()) {
            Some(uv) => uv,
            None => tutte::mean_value(positions, disc)?,
        };
        (mean_value, StartMap::MeanValue)
    };
    Ok(InitialMap {
        lscm_flipped,
        ..InitialMap::plain(uv, map)
    })
}

impl InitialMap {
    /// A local relief of a multilevel start ([`crate::param::relief`]): `relieve` works
    /// on a copy of the UVs and says what it did; the copy is kept and `record`ed in the
    /// multilevel report when it did something. A relief only shortens the solve: should
    /// its linear algebra fail, the full solve starts from the start as it was.
    pub(super) fn relieve<R>(
        &mut self,
        relieve: impl FnOnce(&mut [[f64; 2]]) -> Result<Option<R>, SolveError>,
        record: impl FnOnce(&mut MultilevelReport, R),
    ) {
        let mut relieved = self.uv.clone();
        if let Ok(Some(done)) = relieve(&mut relieved) {
            self.uv = relieved;
            if let Some(report) = self.multilevel.as_mut() {
                record(report, done);
            }
        }
    }
}

/// The multilevel start (see [`crate::param::multilevel`]) in the mesh's units, or `None`
/// (with the reason in the report) when any stage failed. `flatten` flattens the
/// decimated copy.
fn multilevel_start(
    mesh: &TriMesh,
    disc: &Disc,
    options: &FlattenOptions,
    coarse_level: &CoarseLevel,
    flatten: FlattenFn,
) -> (Option<Vec<[f64; 2]>>, MultilevelReport) {
    use crate::mesh::decimate::{DecimateOptions, decimate_with};
    let mut report = MultilevelReport::default();
    let clock = Instant::now();
    let run = |report: &mut MultilevelReport| -> Result<Vec<[f64; 2]>, String> {
        let coarse_size = coarse_level.size_for(mesh.positions.len());
        if mesh.positions.len() < 2 * coarse_size {
            return Err(format!(
                "the mesh has {} vertices, not even twice the {coarse_size} of the coarse level",
                mesh.positions.len(),
            ));
        }
        let decimation = decimate_with(
            &mesh.positions,
            disc,
            &DecimateOptions {
                target_vertices: coarse_size,
                ..Default::default()
            },
        )
        .map_err(|e| format!("decimation: {e}"))?;
        let (coarse, original_of_coarse) = decimation.coarse_mesh(mesh);
        report.coarse_vertices = coarse.positions.len();
        report.coarse_faces = coarse.triangles.len();
        report.time_decimate = clock.elapsed().as_secs_f64();
        let coarse_options = FlattenOptions {
            start: Start::Auto {
                multilevel: Multilevel::Never,
            },
            // Overlap-free on the coarse level unless overlap is allowed, so that a
            // barrier solve can start from it too (the full mesh's solve checks and
            // prevents overlap in any case). Where the boundary runs along itself in 3D
            // (the two sides of a seam) it is solved with the barrier outright: the coarse
            // map then keeps the sides of each slit apart by the barrier's reach (a
            // quarter of a coarse boundary edge), room for the re-inserted vertices
            // between them; without it the coarse mouth of the ICT face id000 opened
            // with seams closed to a slit whose re-inserted lips crossed (the start
            // was abandoned), and id003 / id005 took 11 / 15 fine barrier iterations
            // against 6 / 9 (BENCHMARKS.md, "Hard discs").
            bijective: if options.bijective == Bijective::WhenOverlapping
                && boundary_runs_along_itself(&mesh.positions, disc.boundary())
            {
                Bijective::Always
            } else {
                options.bijective
            },
            max_distortion: None,
            // One UV per coarse vertex: never cut (along protrusions).
            cut: Cut::Never,
            ..options.clone()
        };
        let flat = flatten(&coarse, &coarse_options).map_err(|e| format!("coarse mesh: {e}"))?;
        report.coarse_iterations = flat.iterations;
        report.coarse_barrier = flat.barrier;
        report.coarse_continuation = flat.continuation;
        report.time_coarse = clock.elapsed().as_secs_f64() - report.time_decimate;
        let mut uv = vec![[f64::NAN; 2]; mesh.positions.len()];
        for (c, &v) in original_of_coarse.iter().enumerate() {
            uv[v as usize] = flat.uvs[c];
        }
        report.prolongation = crate::param::multilevel::prolongate(
            &mesh.positions,
            &decimation,
            // Kept from crossing itself where the result must not overlap.
            if options.bijective == Bijective::Off {
                &[]
            } else {
                disc.boundary()
            },
            &mut uv,
            &options.energy,
            coarse_level.polish_steps,
            coarse_level.sweeps,
        )
        .map_err(|e| format!("re-insertion: {e}"))?;
        let flipped = count_flipped(&uv, &mesh.triangles);
        if flipped > 0 {
            return Err(format!("re-insertion left {flipped} flipped triangles"));
        }
        report.time_prolongate =
            clock.elapsed().as_secs_f64() - report.time_decimate - report.time_coarse;
        Ok(uv)
    };
    match run(&mut report) {
        Ok(uv) => (Some(uv), report),
        Err(reason) => {
            report.abandoned = Some(reason);
            (None, report)
        }
    }
}

/// Whether the boundary runs along itself in 3D: a boundary edge whose reverse, from
/// the same point to the same point, is a boundary edge too (the two sides of a seam
/// edge, split into copies by [`crate::mesh::cut::open_along`] or by whoever cut the
/// mesh). A single point where the boundary touches itself (beetle.off: two loops meet
/// at one vertex) is not a seam.
fn boundary_runs_along_itself(positions: &[[f64; 3]], boundary: &[u32]) -> bool {
    let n = boundary.len();
    let at = |k: usize| positions[boundary[k % n] as usize].map(f64::to_bits);
    let edges: std::collections::HashSet<_> = (0..n).map(|k| (at(k), at(k + 1))).collect();
    (0..n).any(|k| edges.contains(&(at(k + 1), at(k))))
}

/// A given start has one UV per vertex of `mesh`.
pub(super) fn check_given_length(given: &[[f64; 2]], mesh: &TriMesh) -> Result<(), FlattenError> {
    if given.len() == mesh.positions.len() {
        Ok(())
    } else {
        Err(FlattenError::GivenStartLength {
            uvs: given.len(),
            vertices: mesh.positions.len(),
        })
    }
}

/// Moves `p0` to the origin and rotates `p1` onto the positive u axis (a rigid motion:
/// the energy does not change), so pinning `p0` and the v coordinate of `p1` removes
/// exactly the rigid motions.
pub(super) fn align_pins(uv: &mut [[f64; 2]], p0: u32, p1: u32) {
    let origin = uv[p0 as usize];
    let (dx, dy) = (
        uv[p1 as usize][0] - origin[0],
        uv[p1 as usize][1] - origin[1],
    );
    let len = dx.hypot(dy).max(f64::MIN_POSITIVE);
    let (c, sn) = (dx / len, dy / len);
    for p in uv.iter_mut() {
        let (x, y) = (p[0] - origin[0], p[1] - origin[1]);
        *p = [c * x + sn * y, -sn * x + c * y];
    }
}

/// The two loop vertices farthest apart (approximately: farthest from the loop's
/// first vertex, then farthest from that), deterministic for a given map.
fn farthest_pair(uv: &[[f64; 2]], boundary: &[u32]) -> (u32, u32) {
    let far = |from: u32| -> u32 {
        let o = uv[from as usize];
        *boundary
            .iter()
            .max_by(|&&a, &&b| {
                let da = (uv[a as usize][0] - o[0]).hypot(uv[a as usize][1] - o[1]);
                let db = (uv[b as usize][0] - o[0]).hypot(uv[b as usize][1] - o[1]);
                da.total_cmp(&db)
            })
            .expect("a disc has a boundary")
    };
    let a = far(boundary[0]);
    let b = far(a);
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::grid_disc;

    #[test]
    fn a_boundary_running_along_itself_is_a_seam_and_a_touching_point_is_not() {
        // A torus cut into a disc: every seam edge is on the boundary twice, reversed.
        let torus = crate::mesh::generate::torus(2.0, 0.5, 12, 8);
        let opened = crate::mesh::cut::cut_to_disc(&torus).unwrap();
        let disc = Disc::new(&opened.mesh).unwrap();
        assert!(boundary_runs_along_itself(
            &opened.mesh.positions,
            disc.boundary()
        ));
        // A plain disc does not.
        let plain = grid_disc(6);
        let disc = Disc::new(&plain).unwrap();
        assert!(!boundary_runs_along_itself(
            &plain.positions,
            disc.boundary()
        ));
        // Nor a loop that passes one point twice (a pinch, like where two of
        // beetle.off's loops meet at a vertex).
        let p = |x: f64, y: f64| [x, y, 0.0];
        let positions = [
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(2.0, -1.0),
            p(2.0, 1.0),
            p(1.0, 0.0),
            p(0.0, 1.0),
        ];
        assert!(!boundary_runs_along_itself(&positions, &[0, 1, 2, 3, 4, 5]));
        // ... but the same edge walked back is: 0 → 1 → 2 → 3 (= 1) → 4 (= 0).
        let positions = [
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(2.0, 1.0),
            p(1.0, 0.0),
            p(0.0, 0.0),
        ];
        assert!(boundary_runs_along_itself(&positions, &[0, 1, 2, 3, 4]));
    }
}
