//! What a flattening returns: [`Flattening`] (the UVs, what was done, how the solve
//! went) and its parts ([`StartMap`], [`MultilevelReport`], [`Guarantee`]), and the
//! checked construction of a result from a solved map ([`result_of`]).

use super::error::FlattenError;
use crate::measure::overlap::boundary_crossings;
use crate::mesh::{TriMesh, Uvs};
use crate::param::count_flipped;
use crate::param::newton::{IterationLog, NewtonTimings, StopReason};
use crate::param::optcuts::DistortionCuts;
use crate::param::plan::{Plan, Seams};
use crate::param::protrusions::ProtrusionCuts;
use serde::Serialize;
use std::time::Instant;

/// Which initial map was actually used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StartMap {
    /// Free-boundary least-squares conformal map.
    Lscm,
    /// Mean-value coordinates onto a circle (injective by construction), used because
    /// LSCM flipped or degenerated `lscm_flipped` triangles, or by request.
    MeanValue,
    /// The caller's map ([`Start::Given`](super::Start::Given)).
    Given,
    /// The flattening of a decimated copy, refined vertex by vertex
    /// ([`crate::param::multilevel`]; details in [`Flattening::multilevel`]).
    Multilevel,
}

/// What the multilevel start did (or why it was abandoned).
#[derive(Clone, Debug, Default, Serialize)]
pub struct MultilevelReport {
    pub coarse_vertices: usize,
    pub coarse_faces: usize,
    /// Newton iterations on the coarse mesh.
    pub coarse_iterations: usize,
    /// Whether the coarse mesh was solved with the boundary barrier: because its
    /// unconstrained minimum overlapped itself, or outright where the boundary runs
    /// along itself in 3D (the sides of seams). The bijective mode then solves the full mesh
    /// with the barrier from the start (measured: every ICT face opened with seams
    /// ends in the barrier solve).
    pub coarse_barrier: bool,
    /// α values of the continuation stages solved on the coarse mesh (with a
    /// continuation start; the full mesh then goes straight to the target α).
    pub coarse_continuation: Vec<[f64; 3]>,
    /// Vertices re-inserted, of them placed at their star's kernel centroid, and local
    /// Newton steps taken.
    pub prolongation: crate::param::multilevel::ProlongationStats,
    /// Seconds: decimation, coarse flattening, re-insertion.
    pub time_decimate: f64,
    pub time_coarse: f64,
    pub time_prolongate: f64,
    /// Set when the multilevel start failed and the single-level start was used instead.
    pub abandoned: Option<String>,
    /// The local solve that opened the start's crushed boundary contacts before the
    /// barrier solve, when it had any ([`crate::param::relief`]).
    pub relief: Option<crate::param::relief::ContactRelief>,
    /// The local solve that relieved the start's squeezed triangles before the full
    /// solve, when it had any ([`crate::param::relief::relieve_hot_spots`]).
    pub hot_spots: Option<crate::param::relief::HotSpotRelief>,
}

/// What the result is guaranteed to be (checked on the result, not assumed).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Guarantee {
    /// Flip-free, and the boundary does not cross itself: the map is injective.
    Bijective,
    /// Flip-free, but the boundary crosses itself ([`Flattening::boundary_crossings`]):
    /// locally injective only.
    LocallyInjective,
}

/// Result of a flattening.
#[derive(Clone, Debug, Serialize)]
pub struct Flattening {
    /// The UVs, in the mesh's length units (an isometry keeps lengths): one per vertex
    /// (vertices used by no triangle at the origin), or, when the surface was cut
    /// ([`Self::seams`]), one per UV vertex of the cut map, indexed per corner by
    /// [`Seams::uv_triangles`]. [`Self::texture_coordinates`] gives either as [`Uvs`].
    pub uvs: Vec<[f64; 2]>,
    /// What was done before the solve: a disc as is, holes filled, or cut open.
    pub plan: Plan,
    /// The seams when the surface was cut open (then [`Self::uvs`] are per UV vertex).
    pub seams: Option<Seams>,
    pub start: StartMap,
    /// Triangles LSCM flipped or degenerated (0 when LSCM was used).
    pub lscm_flipped: usize,
    /// ARAP warm-start steps accepted before Newton.
    pub warm_start_iterations: usize,
    /// Newton iterations, all stages together.
    pub iterations: usize,
    pub converged: bool,
    pub stop_reason: StopReason,
    /// Final energy per unit 3D area (mean density).
    pub energy: f64,
    /// Flipped or degenerate triangles in the output, counted on the output: always 0
    /// for a returned flattening (a non-zero count is an error instead).
    pub flipped_triangles: usize,
    /// Pairs of boundary edges of the solved disc (after filling and cutting) that
    /// cross or touch, checked on the result: 0 means the map is injective.
    pub boundary_crossings: usize,
    /// What the result is guaranteed to be (from the check above).
    pub guarantee: Guarantee,
    /// Whether the boundary barrier was used: with [`Bijective::Always`](super::Bijective::Always), or because
    /// the unconstrained result overlapped ([`Bijective::WhenOverlapping`](super::Bijective::WhenOverlapping); then
    /// [`Self::iterations`] and the log are those of the barrier solve, and the times
    /// include both). From a crushed mean-value start the scaffold iterations
    /// ([`crate::param::scaffold`]) take the barrier solve's place: then the iterations and
    /// the log are theirs and the stop reason is [`StopReason::Stalled`] (or the cap).
    pub barrier: bool,
    /// Holes filled for the solve ([`FlattenOptions::fill_holes`](super::FlattenOptions::fill_holes)).
    pub holes_filled: usize,
    /// α values of the continuation stages actually solved (empty without continuation).
    pub continuation: Vec<[f64; 3]>,
    pub log: Vec<IterationLog>,
    /// Seconds: filling holes and cutting, initial map, Newton (all stages), total.
    pub time_prepare: f64,
    pub time_start: f64,
    pub time_newton: f64,
    pub time_total: f64,
    /// Newton time by phase.
    pub newton_timings: NewtonTimings,
    /// The multilevel start, when it was tried.
    pub multilevel: Option<MultilevelReport>,
    /// Whether the barrier solve started from the last crossing-free iterate of the
    /// unconstrained solve instead of the start map: for a crushed start (the progressive
    /// iterations ran), whose unconstrained solve ended because its boundary crossed
    /// itself. [`Self::start`] is then the map that solve started from.
    pub barrier_resumed: bool,
    /// What the distortion-driven cutting did ([`FlattenOptions::max_distortion`](super::FlattenOptions::max_distortion)):
    /// the distortion before and after, the rounds, the seam length added, whether the
    /// bound holds. The other fields describe the solve of the map returned (the best
    /// one found), [`Self::time_total`] every round.
    pub distortion_cuts: Option<DistortionCuts>,
    /// The cuts along protrusions made because no single chart could be embedded
    /// ([`crate::param::protrusions`]): how many, their seam length, where they start.
    /// `None` when the start was admissible without them.
    pub protrusion_cuts: Option<ProtrusionCuts>,
}

impl Flattening {
    /// The start map for people: `lscm`, `mean-value (LSCM flipped N)`, `given` or
    /// `multilevel (N coarse vertices)` (`…, K crushed boundary contacts relieved` when
    /// [`MultilevelReport::relief`] opened some).
    pub fn start_description(&self) -> String {
        let start = match self.start {
            StartMap::Lscm => "lscm".to_string(),
            StartMap::MeanValue if self.lscm_flipped > 0 => {
                format!("mean-value (LSCM flipped {})", self.lscm_flipped)
            }
            StartMap::MeanValue => "mean-value".to_string(),
            StartMap::Given => "given".to_string(),
            StartMap::Multilevel => match &self.multilevel {
                Some(m) => {
                    let mut what = format!("{} coarse vertices", m.coarse_vertices);
                    if let Some(h) = m.hot_spots {
                        what += &format!(", {} squeezed triangles relieved", h.hot_triangles);
                    }
                    if let Some(r) = m.relief {
                        what +=
                            &format!(", {} crushed boundary contacts relieved", r.crushed_pairs);
                    }
                    format!("multilevel ({what})")
                }
                None => "multilevel".to_string(),
            },
        };
        if self.barrier_resumed {
            format!(
                "{start}, barrier solve from the unconstrained solve's last crossing-free iterate"
            )
        } else {
            start
        }
    }

    /// What was done around the solve, for people: the plan ([`Plan::describe`]),
    /// followed by the cuts along protrusions ([`Self::protrusion_cuts`]) and the
    /// distortion cuts when the map kept some
    /// ([`FlattenOptions::max_distortion`](super::FlattenOptions::max_distortion)):
    /// `disc as is`, `cut open to lower the distortion`, `cut open along seams (closed,
    /// genus 0), then cut along 6 protrusions (seam length 12.3456)`, `cut open along
    /// seams (closed, genus 0), then cut open to lower the distortion`.
    pub fn describe_plan(&self) -> String {
        let plan = (!self.plan.is_disc_as_is()).then(|| self.plan.describe());
        let protrusions = self.protrusion_cuts.as_ref().map(|c| {
            format!(
                "cut along {} protrusion{} (seam length {:.4})",
                c.cuts,
                if c.cuts == 1 { "" } else { "s" },
                c.seam_length
            )
        });
        let distortion = self
            .distortion_cuts
            .as_ref()
            .is_some_and(|c| c.seam_edges_added > 0)
            .then(|| "cut open to lower the distortion".to_string());
        let parts: Vec<String> = [plan, protrusions, distortion]
            .into_iter()
            .flatten()
            .collect();
        if parts.is_empty() {
            self.plan.describe()
        } else {
            parts.join(", then ")
        }
    }

    /// The UVs mapped into `[0, 1]²` with the aspect ratio kept
    /// ([`crate::param::normalize_uvs`]), e.g. for texture coordinates.
    pub fn normalized_uvs(&self) -> Vec<[f64; 2]> {
        let mut uvs = self.uvs.clone();
        crate::param::normalize_uvs(&mut uvs);
        uvs
    }

    /// The texture coordinates of the input mesh: per vertex, or per corner when the
    /// surface was cut; in `[0, 1]²` when `normalized` ([`Self::normalized_uvs`]).
    pub fn texture_coordinates(&self, normalized: bool) -> Uvs {
        let coords = if normalized {
            self.normalized_uvs()
        } else {
            self.uvs.clone()
        };
        match &self.seams {
            None => Uvs::PerVertex(coords),
            Some(seams) => Uvs::PerCorner {
                coords,
                indices: seams.uv_triangles.clone(),
            },
        }
    }

    /// The UV triangle of every input triangle, corner by corner.
    pub fn corner_uvs(&self, triangles: &[[u32; 3]]) -> Vec<[[f64; 2]; 3]> {
        let indices = self.seams.as_ref().map_or(triangles, |s| &s.uv_triangles);
        indices
            .iter()
            .map(|t| t.map(|v| self.uvs[v as usize]))
            .collect()
    }
}

/// What a solve did, for [`result_of`].
pub(super) struct Solved {
    pub(super) start: StartMap,
    pub(super) lscm_flipped: usize,
    pub(super) warm_start_iterations: usize,
    pub(super) iterations: usize,
    pub(super) stop: StopReason,
    pub(super) energy: f64,
    pub(super) barrier: bool,
    pub(super) continuation: Vec<[f64; 3]>,
    pub(super) log: Vec<IterationLog>,
    pub(super) time_start: f64,
    pub(super) time_newton: f64,
    pub(super) newton_timings: NewtonTimings,
    pub(super) multilevel: Option<MultilevelReport>,
    pub(super) barrier_resumed: bool,
}

/// The flattening of the solved map `uv` (normalized units; `scale` back to the
/// mesh's), with its flips and boundary crossings counted on it (`clock`: started with
/// the solve).
pub(super) fn result_of(
    uv: &[[f64; 2]],
    mesh: &TriMesh,
    boundary: &[u32],
    scale: f64,
    clock: Instant,
    solved: Solved,
) -> Result<Flattening, FlattenError> {
    let flipped = count_flipped(uv, &mesh.triangles);
    if flipped > 0 {
        return Err(FlattenError::FlippedResult(flipped));
    }
    let crossings = boundary_crossings(uv, boundary);
    let uvs = uv.iter().map(|p| [p[0] * scale, p[1] * scale]).collect();
    Ok(Flattening {
        uvs,
        plan: Plan {
            holes_to_fill: 0,
            cut: None,
        },
        seams: None,
        start: solved.start,
        lscm_flipped: solved.lscm_flipped,
        warm_start_iterations: solved.warm_start_iterations,
        iterations: solved.iterations,
        converged: solved.stop == StopReason::Converged,
        stop_reason: solved.stop,
        energy: solved.energy,
        flipped_triangles: flipped,
        boundary_crossings: crossings,
        guarantee: if crossings == 0 {
            Guarantee::Bijective
        } else {
            Guarantee::LocallyInjective
        },
        barrier: solved.barrier,
        holes_filled: 0,
        continuation: solved.continuation,
        log: solved.log,
        time_prepare: 0.0,
        time_start: solved.time_start,
        time_newton: solved.time_newton,
        time_total: clock.elapsed().as_secs_f64(),
        newton_timings: solved.newton_timings,
        multilevel: solved.multilevel,
        barrier_resumed: solved.barrier_resumed,
        distortion_cuts: None,
        protrusion_cuts: None,
    })
}
