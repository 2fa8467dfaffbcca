//! Distortion-driven cutting: while one chart's distortion exceeds a bound, cut it open
//! where the distortion concentrates and flatten again — in the spirit of OptCuts (Li,
//! Kaufman, Kim, Sorkine-Hornung & Sheffer 2018, *OptCuts: joint optimization of surface
//! cuts and parameterization*), with the greedy cut growth of geometry images (Gu,
//! Gortler & Hoppe 2002, §3.2).
//!
//! **The bound.** The distortion is the *mean symmetric Dirichlet distortion*
//!
//! ```text
//! D(φ) = Σ_t A_t · (σ1² + σ2² + σ1⁻² + σ2⁻²)/4  /  Σ_t A_t
//! ```
//!
//! over the input's triangles `t` (3D areas `A_t`, singular values `σ1 ≥ σ2` of the
//! Jacobian), after the UVs are scaled uniformly so the UV area equals the 3D area
//! ([`crate::measure::report`]'s convention, and the referee's `sym_dirichlet_mean` in
//! `../shared/peers/distortion.py`: the same number on the same UVs). `D = 1` exactly
//! for an isometry and `D > 1` for any other map, so a bound below 1 is refused and a
//! bound of 1 is met only by a developable surface. It is the area-weighted *mean*
//! (OptCuts' `E_d ≤ b_d`, there with the isometry at 4), not the maximum: a single
//! sliver triangle can have any distortion, and the mean is what a texture's overall
//! stretch follows. [`DistortionCuts`] also reports the per-round values.
//!
//! **The loop** (`cut_to_bound`, run by [`super::flatten::flatten`]), on the disc the solver flattened (after holes are
//! filled and a closed or higher-genus surface is cut, [`super::plan`]):
//!
//! 1. Measure `D`; stop when `D ≤ bound` (a map already under the bound is returned
//!    unchanged, no cut).
//! 2. Per vertex, `d(v)`: the area-weighted mean of the distortion of its triangles.
//!    Each interior vertex (not on the chart's boundary, not on a filled hole) scores
//!    `(d(v) − 1)·δ(v)`, its excess distortion times its geodesic distance `δ` (along
//!    edges) to the boundary: a cut to it relieves much distortion (it is high there)
//!    over a large region (it is far from where the boundary can relax already). The
//!    best-scoring vertex `v*` is chosen — measured: choosing by `d(v)` alone picks
//!    vertices next to the boundary, and each round grows a seam by one edge.
//! 3. The shortest edge path from `v*` to the chart's boundary (the input's boundary or
//!    a seam) over weights `ℓ(e) / d(e)` (`d(e)`: the mean of its endpoints' `d`, ≥ 1):
//!    short, and through the distorted region. The path is a tree branch hanging off
//!    the boundary, so the chart cut along it stays one disc. With the path counted as
//!    boundary, `δ` is measured again and the next best vertex gets a path too, as long
//!    as it scores at least half the first; at most [`MAX_PATHS_PER_ROUND`] paths per
//!    round (measured on bear, 27k faces, bound 1.05: 6 rounds instead of 21).
//! 4. Split the disc along the paths ([`crate::mesh::cut::open_along`]) and flatten it
//!    again from the previous map: the copies of a split vertex start at its old UV,
//!    moved a little into their own side (`open_slit`), a flip-free and
//!    crossing-free start (the boundary barrier needs one) whose slits open under
//!    Newton.
//!
//! Every round's map is flip-free, and overlap-free unless the bijective mode is off
//! (each solve is a full [`super::flatten`] solve with its guarantee). The loop stops
//! when the bound holds, after [`MaxDistortion::max_rounds`] rounds, when two rounds in
//! a row lower the best `D` by less than 1% of its excess `D − 1`, or when no interior
//! vertex is left; it returns the map with the lowest `D` (which is the last one when
//! the bound is met) and says whether the bound holds. Cost: one flattening per round
//! from a warm start, plus `O(F log F)` for the measure and the path.

use super::flatten::{FlattenError, FlattenOptions, Flattening, Start};
use super::plan::Prepared;
use crate::measure::report::{Measure, triangle_singular_values};
use crate::mesh::cut::{OpenedMesh, open_along};
use crate::mesh::edge_graph::EdgeGraph;
use crate::mesh::{Topology, TriMesh};
use serde::Serialize;
use std::time::Instant;

/// Cut rounds at most, by default ([`MaxDistortion::max_rounds`]).
pub const DEFAULT_MAX_ROUNDS: usize = 30;

/// Paths cut per round at most: the best-scoring one, then every one that scores at
/// least half of it (`NEXT_PATH_SCORE`) once the paths before are part of the boundary.
pub const MAX_PATHS_PER_ROUND: usize = 4;
const NEXT_PATH_SCORE: f64 = 0.5;

/// Rounds in a row whose gain is below [`MIN_GAIN`] of the excess before the loop gives
/// up.
const STALLED_ROUNDS: usize = 2;
/// A round gains when it lowers the best distortion `D` by at least this fraction of
/// `D − 1`.
const MIN_GAIN: f64 = 0.01;

/// A bound on the mean symmetric Dirichlet distortion (module docs) for
/// [`FlattenOptions::max_distortion`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaxDistortion {
    /// The bound on `D` (at least 1: an isometry's `D`).
    pub bound: f64,
    /// Cut rounds (each one to [`MAX_PATHS_PER_ROUND`] paths and one flattening) at most
    /// before the loop stops with the best map.
    pub max_rounds: usize,
}

impl MaxDistortion {
    /// The bound `bound` with at most [`DEFAULT_MAX_ROUNDS`] rounds.
    pub fn new(bound: f64) -> Self {
        Self {
            bound,
            max_rounds: DEFAULT_MAX_ROUNDS,
        }
    }
}

/// Why the cut loop stopped.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "reason")]
pub enum CutStop {
    /// The bound holds.
    Met,
    /// [`MaxDistortion::max_rounds`] rounds were made.
    RoundCap,
    /// Two rounds in a row gained less than 1% of the excess distortion.
    NoProgress,
    /// No interior vertex is left to cut to (every vertex is on the boundary or a
    /// filled hole).
    NoCandidate,
    /// A round's flattening failed (the reason); the best map before it is kept.
    SolveFailed(String),
}

/// One cut round: the path added and the flattening after it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CutRound {
    /// `D` after the round.
    pub distortion: f64,
    /// The vertices (of the mesh with holes filled: the input's first) the round's
    /// paths start from.
    pub from_vertices: Vec<u32>,
    /// Edges and 3D length of the paths.
    pub seam_edges: usize,
    pub seam_length: f64,
    pub iterations: usize,
    /// Seconds for the round (path, split and flattening).
    pub time: f64,
}

/// What the distortion-driven cutting did ([`Flattening::distortion_cuts`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DistortionCuts {
    /// The bound on `D` (module docs).
    pub bound: f64,
    /// `D` of the map without distortion cuts, and of the map returned.
    pub before: f64,
    pub after: f64,
    /// Whether the map returned meets the bound (`after ≤ bound`).
    pub met: bool,
    pub stop: CutStop,
    /// Rounds made, and the round of the map returned (0: no cut kept).
    pub rounds: usize,
    pub best_round: usize,
    /// Seam edges and 3D seam length the returned map has beyond the topological cut.
    pub seam_edges_added: usize,
    pub seam_length_added: f64,
    /// Newton iterations of all rounds' flattenings (the first one included).
    pub total_iterations: usize,
    pub history: Vec<CutRound>,
}

/// The mean symmetric Dirichlet distortion `D` of the map `positions/triangles →
/// corner_uvs` (module docs), and every triangle's `(σ1² + σ2² + σ1⁻² + σ2⁻²)/4` (NaN for
/// triangles of zero 3D area, which are left out as in [`crate::measure::report`]).
pub fn mean_symmetric_dirichlet(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
) -> Result<(f64, Vec<f64>), crate::measure::MeasureError> {
    let sv = triangle_singular_values(positions, triangles, corner_uvs, true)?;
    let (mut sum, mut weight) = (0.0, 0.0);
    let per_triangle = (0..triangles.len())
        .map(|t| {
            if !sv.used[t] {
                return f64::NAN;
            }
            let [s1, s2] = sv.sigma[t];
            let sd = Measure::SymmetricDirichlet.value(s1, s2);
            sum += sv.area3[t] * sd;
            weight += sv.area3[t];
            sd / 4.0
        })
        .collect();
    let mean = if weight > 0.0 {
        sum / weight / 4.0
    } else {
        f64::NAN
    };
    Ok((mean, per_triangle))
}

/// A chart being cut open (here, and along protrusions by [`super::protrusions`]): the
/// disc the solver flattens, and the way back to the mesh the plan prepared (holes
/// filled; its vertices are the input's, then the fill's).
#[derive(Clone)]
pub(crate) struct Chart {
    pub(crate) disc: TriMesh,
    /// For every disc vertex, its vertex in the prepared mesh.
    pub(crate) vertex_of: Vec<u32>,
    /// All seams (topological and added), prepared-mesh vertex pairs, sorted.
    pub(crate) seams: Vec<[u32; 2]>,
    /// Seam edges and length added by cutting the chart.
    pub(crate) added_edges: usize,
    pub(crate) added_length: f64,
    /// Whether the prepared mesh was cut already (for its topology).
    had_cut: bool,
}

impl Chart {
    /// The prepared disc, before any cut of its own.
    pub(crate) fn new(prepared: Prepared) -> Self {
        let had_cut = prepared.opened.is_some();
        let (vertex_of, seams) = match prepared.opened {
            Some(opened) => (opened.original_vertex, opened.seams),
            None => (
                (0..prepared.mesh.positions.len() as u32).collect(),
                Vec::new(),
            ),
        };
        Self {
            disc: prepared.mesh,
            vertex_of,
            seams,
            added_edges: 0,
            added_length: 0.0,
            had_cut,
        }
    }

    /// The chart split along `path` (disc vertex pairs; `topology`: the disc's), and for
    /// every vertex of the new disc its vertex in this one.
    pub(crate) fn split(
        &self,
        topology: &Topology,
        path: &[[u32; 2]],
    ) -> Result<(Chart, Vec<u32>), FlattenError> {
        let opened = open_along(&self.disc, topology, path)?;
        let length = crate::mesh::cut::seam_length(&self.disc.positions, path);
        let mut seams: Vec<[u32; 2]> = path
            .iter()
            .map(|e| {
                let [a, b] = e.map(|v| self.vertex_of[v as usize]);
                [a.min(b), a.max(b)]
            })
            .chain(self.seams.iter().copied())
            .collect();
        seams.sort_unstable();
        seams.dedup();
        let chart = Chart {
            vertex_of: opened
                .original_vertex
                .iter()
                .map(|&v| self.vertex_of[v as usize])
                .collect(),
            disc: opened.mesh,
            seams,
            added_edges: self.added_edges + path.len(),
            added_length: self.added_length + length,
            had_cut: self.had_cut,
        };
        Ok((chart, opened.original_vertex))
    }

    /// Back to what the plan's mapping back reads: the disc, and the cut when there is
    /// one.
    pub(crate) fn into_prepared(self) -> Prepared {
        let opened = (self.had_cut || self.added_edges > 0).then(|| OpenedMesh {
            mesh: TriMesh::default(),
            original_vertex: self.vertex_of,
            seams: self.seams,
        });
        Prepared {
            mesh: self.disc,
            opened,
        }
    }
}

/// Cuts the flattened disc `prepared` (its flattening `first`) until the distortion of
/// its first `input_faces` triangles (the input's; the rest fill holes) is at most
/// `bound` (module docs). Returns the chart and flattening with the lowest distortion,
/// the report in [`Flattening::distortion_cuts`].
pub(crate) fn cut_to_bound(
    input_faces: usize,
    prepared: Prepared,
    first: Flattening,
    bound: &MaxDistortion,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&super::flatten::IterationLog),
) -> Result<(Prepared, Flattening), FlattenError> {
    let measure = |disc: &TriMesh, uvs: &[[f64; 2]]| -> Result<(f64, Vec<f64>), FlattenError> {
        let triangles = &disc.triangles[..input_faces];
        let corners: Vec<[[f64; 2]; 3]> = triangles
            .iter()
            .map(|t| t.map(|v| uvs[v as usize]))
            .collect();
        mean_symmetric_dirichlet(&disc.positions, triangles, &corners).map_err(FlattenError::from)
    };
    let (before, mut per_triangle) = measure(&prepared.mesh, &first.uvs)?;
    let mut report = DistortionCuts {
        bound: bound.bound,
        before,
        after: before,
        met: before <= bound.bound,
        stop: CutStop::Met,
        rounds: 0,
        best_round: 0,
        seam_edges_added: 0,
        seam_length_added: 0.0,
        total_iterations: first.iterations,
        history: Vec::new(),
    };
    if report.met {
        let mut first = first;
        first.distortion_cuts = Some(report);
        return Ok((prepared, first));
    }
    let mut chart = Chart::new(prepared);
    let mut best = (chart.clone(), first);
    let mut current_uvs = best.1.uvs.clone();
    let mut stalled = 0;
    report.stop = CutStop::RoundCap;
    for round in 1..=bound.max_rounds {
        let round_clock = Instant::now();
        let topology = Topology::new(&chart.disc);
        let paths = cut_paths(&chart.disc, &topology, input_faces, &per_triangle);
        if paths.is_empty() {
            report.stop = CutStop::NoCandidate;
            break;
        }
        let from: Vec<u32> = paths.iter().map(|p| p.0).collect();
        let path: Vec<[u32; 2]> = paths.into_iter().flat_map(|p| p.1).collect();
        let from_vertices = from.iter().map(|&v| chart.vertex_of[v as usize]).collect();
        let length = crate::mesh::cut::seam_length(&chart.disc.positions, &path);
        let (next, old_vertex) = chart.split(&topology, &path)?;
        let warm = open_slit(&next.disc, &old_vertex, &current_uvs);
        chart = next;
        let round_options = FlattenOptions {
            start: Start::Given(warm),
            max_distortion: None,
            ..options.clone()
        };
        let result = match super::flatten::flatten_used(&chart.disc, None, &round_options, progress)
        {
            Ok(result) => result,
            Err(e) => {
                report.stop = CutStop::SolveFailed(e.to_string());
                break;
            }
        };
        let (distortion, values) = measure(&chart.disc, &result.uvs)?;
        report.rounds = round;
        report.total_iterations += result.iterations;
        report.history.push(CutRound {
            distortion,
            from_vertices,
            seam_edges: path.len(),
            seam_length: length,
            iterations: result.iterations,
            time: round_clock.elapsed().as_secs_f64(),
        });
        let best_so_far = report.after;
        current_uvs = result.uvs.clone();
        per_triangle = values;
        if distortion < best_so_far {
            report.after = distortion;
            report.best_round = round;
            best = (chart.clone(), result);
        }
        if distortion <= bound.bound {
            report.stop = CutStop::Met;
            break;
        }
        if best_so_far - distortion < MIN_GAIN * (best_so_far - 1.0) {
            stalled += 1;
            if stalled >= STALLED_ROUNDS {
                report.stop = CutStop::NoProgress;
                break;
            }
        } else {
            stalled = 0;
        }
    }
    let (chart, mut result) = best;
    report.met = report.after <= bound.bound;
    report.seam_edges_added = chart.added_edges;
    report.seam_length_added = chart.added_length;
    result.distortion_cuts = Some(report);
    Ok((chart.into_prepared(), result))
}

/// The start map of the disc `mesh` cut from the flattened disc with UVs `uvs`
/// (`old_vertex`: every vertex's vertex there): the copies of every split vertex moved a
/// little into their own side (a tenth of the way to the mean of their neighbours, less
/// if that flips a triangle), so the two sides of the new slit neither coincide nor
/// cross — a start the boundary barrier accepts.
fn open_slit(mesh: &TriMesh, old_vertex: &[u32], uvs: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let slit: Vec<[f64; 2]> = old_vertex.iter().map(|&v| uvs[v as usize]).collect();
    let mut copies = vec![0u32; uvs.len()];
    old_vertex.iter().for_each(|&v| copies[v as usize] += 1);
    let split = |v: u32| copies[old_vertex[v as usize] as usize] > 1;
    // Mean of each split vertex's neighbours (each edge counted from both faces).
    let mut sum = vec![[0.0f64; 2]; slit.len()];
    let mut count = vec![0u32; slit.len()];
    for tri in &mesh.triangles {
        for k in 0..3 {
            let v = tri[k];
            if split(v) {
                for w in [tri[(k + 1) % 3], tri[(k + 2) % 3]] {
                    sum[v as usize][0] += slit[w as usize][0];
                    sum[v as usize][1] += slit[w as usize][1];
                    count[v as usize] += 1;
                }
            }
        }
    }
    let mut t = SLIT_OPENING;
    for _ in 0..SLIT_TRIES {
        let trial: Vec<[f64; 2]> = (0..slit.len())
            .map(|v| {
                let p = slit[v];
                if count[v] == 0 {
                    return p;
                }
                let c = sum[v].map(|x| x / count[v] as f64);
                [p[0] + t * (c[0] - p[0]), p[1] + t * (c[1] - p[1])]
            })
            .collect();
        if super::count_flipped(&trial, &mesh.triangles) == 0 {
            return trial;
        }
        t *= 0.25;
    }
    slit
}

/// How far the copies of a slit start into their sides (fraction of the way to their
/// neighbours' mean), and the tries (each a quarter of the last) before the slit is
/// left closed.
const SLIT_OPENING: f64 = 0.1;
const SLIT_TRIES: usize = 4;

/// The paths of one round (module docs, steps 2–3): for each, the interior vertex of
/// `disc` it starts from and its edges (disc vertex pairs) to the boundary. The
/// distortion is `per_triangle` on the first `input_faces` triangles; the others fill
/// holes, and no path touches their vertices. Empty when no interior vertex can reach
/// the boundary.
fn cut_paths(
    disc: &TriMesh,
    topology: &Topology,
    input_faces: usize,
    per_triangle: &[f64],
) -> Vec<(u32, Vec<[u32; 2]>)> {
    let n = disc.positions.len();
    // Per-vertex distortion, and the vertices no path may use (on a filled hole).
    let (mut sum, mut weight) = (vec![0.0; n], vec![0.0; n]);
    let mut blocked = vec![false; n];
    for (t, tri) in disc.triangles.iter().enumerate() {
        if t >= input_faces {
            tri.iter().for_each(|&v| blocked[v as usize] = true);
            continue;
        }
        let d = per_triangle[t];
        if d.is_finite() {
            let area = disc.triangle_area(t);
            for &v in tri {
                sum[v as usize] += area * d;
                weight[v as usize] += area;
            }
        }
    }
    let distortion: Vec<f64> = (0..n)
        .map(|v| {
            if weight[v] > 0.0 {
                sum[v] / weight[v]
            } else {
                1.0
            }
        })
        .collect();
    let mut on_boundary = topology.on_boundary(n);
    let graph = EdgeGraph::new(disc, topology);
    let candidate = |v: usize| !blocked[v] && weight[v] > 0.0;
    let mut paths = Vec::new();
    let mut first_score = f64::NAN;
    while paths.len() < MAX_PATHS_PER_ROUND {
        // A path may run through unblocked vertices and end on the boundary (which
        // includes the paths already chosen).
        let passable = |v: u32| !blocked[v as usize] || on_boundary[v as usize];
        let boundary: Vec<u32> = (0..n as u32).filter(|&v| on_boundary[v as usize]).collect();
        let (reach, _, _) = graph.shortest_paths(&boundary, |_, _, l| l, passable, |_| false);
        let score = |v: usize| (distortion[v] - 1.0) * reach[v];
        let Some(from) = (0..n)
            .filter(|&v| candidate(v) && !on_boundary[v] && reach[v].is_finite())
            .max_by(|&a, &b| score(a).total_cmp(&score(b)))
        else {
            break;
        };
        if paths.is_empty() {
            first_score = score(from);
        } else if score(from) < NEXT_PATH_SCORE * first_score {
            break;
        }
        let Some(path) = graph.path_to(
            from as u32,
            |a, b, length| length / (0.5 * (distortion[a as usize] + distortion[b as usize])),
            passable,
            |v| on_boundary[v as usize],
        ) else {
            break;
        };
        for e in &path {
            e.iter().for_each(|&v| on_boundary[v as usize] = true);
        }
        paths.push((from as u32, path));
    }
    paths
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::measure::{DistortionReport, MeasureOptions, distortion_report};
    use crate::mesh::generate::{bumpy_disc, cone, sphere, spherical_cap};
    use crate::param::flatten::{CutReason, Guarantee, OptionError, flatten};

    /// Checks what every cut map must be: one UV triangle per input triangle, all
    /// counter-clockwise, one chart whose boundary does not even touch itself, the
    /// input's UV per corner split exactly along the reported seams; returns the
    /// measures of the written corners.
    pub(crate) fn one_chart(mesh: &TriMesh, map: &Flattening) -> DistortionReport {
        let corners = map.corner_uvs(&mesh.triangles);
        assert!(
            corners
                .iter()
                .all(|&c| super::super::signed_uv_area(c) > 0.0)
        );
        assert_eq!(map.guarantee, Guarantee::Bijective);
        let measured = distortion_report(
            &mesh.positions,
            &mesh.triangles,
            &corners,
            &MeasureOptions::default(),
        )
        .unwrap();
        assert_eq!(measured.charts, 1);
        assert_eq!(measured.flipped_triangles, 0);
        assert!(
            !measured.boundary_overlap.self_intersecting,
            "{:?}",
            measured.boundary_overlap
        );
        if let Some(seams) = &map.seams {
            crate::param::plan::tests::seams_split_exactly(mesh, seams);
        }
        measured
    }

    /// [`one_chart`], and the reported `D` the one an independent measurement of the
    /// written corners gives.
    fn check(mesh: &TriMesh, map: &Flattening) -> DistortionCuts {
        let measured = one_chart(mesh, map);
        let cuts = map.distortion_cuts.clone().expect("a distortion report");
        let d = measured.symmetric_dirichlet / 4.0;
        assert!((cuts.after - d).abs() <= 1e-12 * d, "{} vs {d}", cuts.after);
        cuts
    }

    #[test]
    fn a_cone_is_cut_from_its_apex_and_unrolls_nearly_isometrically() {
        // All the curvature of a cone sits at its apex (vertex 0): cut along a path from
        // the apex to the rim it is developable, so D falls to (nearly) 1.
        let (radius, height) = (1.0, 3.0);
        let mesh = cone(radius, height, 12, 48);
        let one_chart = flatten(&mesh, &FlattenOptions::default()).unwrap();
        let corners = one_chart.corner_uvs(&mesh.triangles);
        let (d0, _) = mean_symmetric_dirichlet(&mesh.positions, &mesh.triangles, &corners).unwrap();
        let map = flatten(&mesh, &FlattenOptions::default().with_max_distortion(1.01)).unwrap();
        let cuts = check(&mesh, &map);
        assert_eq!(cuts.before, d0);
        assert!(d0 > 1.1, "{d0}");
        assert!(cuts.met && cuts.stop == CutStop::Met, "{cuts:?}");
        assert!(cuts.after <= 1.01);
        let seams = map.seams.as_ref().unwrap();
        assert_eq!(seams.reason, CutReason::Distortion);
        assert_eq!(map.describe_plan(), "cut open to lower the distortion");
        assert_eq!(seams.edges.len(), cuts.seam_edges_added);
        assert!((seams.length - cuts.seam_length_added).abs() < 1e-12);
        // One round, one cut: along a generator from the apex to the rim (the shortest
        // path from the apex, the vertex farthest from the rim), the slant height long.
        // The cone unrolls onto its sector: an isometry, D = 1.
        assert_eq!(cuts.rounds, 1);
        assert!(seams.edges.iter().any(|e| e[0] == 0), "{:?}", seams.edges);
        assert_eq!(seams.edges.len(), 12);
        let slant = radius.hypot(height);
        assert!(
            (seams.length - slant).abs() < 1e-12,
            "{} vs {slant}",
            seams.length
        );
        assert!(cuts.after < 1.0 + 1e-9, "{}", cuts.after);
    }

    #[test]
    fn a_hemisphere_gets_cuts_until_the_bound_holds() {
        let mesh = spherical_cap(1.0, std::f64::consts::FRAC_PI_2, 12, 48);
        let bound = 1.02;
        let map = flatten(&mesh, &FlattenOptions::default().with_max_distortion(bound)).unwrap();
        let cuts = check(&mesh, &map);
        assert!(cuts.before > bound, "{cuts:?}");
        assert!(
            cuts.met && cuts.after <= bound && cuts.rounds >= 1,
            "{cuts:?}"
        );
        assert_eq!(cuts.best_round, cuts.rounds);
    }

    #[test]
    fn a_map_under_the_bound_is_returned_unchanged() {
        let mesh = bumpy_disc(8, 0.2);
        let plain = flatten(&mesh, &FlattenOptions::default()).unwrap();
        let map = flatten(&mesh, &FlattenOptions::default().with_max_distortion(1.5)).unwrap();
        let cuts = check(&mesh, &map);
        assert!(cuts.before < 1.5 && cuts.met, "{cuts:?}");
        assert_eq!((cuts.rounds, cuts.seam_edges_added), (0, 0));
        assert!(map.seams.is_none());
        assert_eq!(map.describe_plan(), "disc as is");
        assert_eq!(map.uvs, plain.uvs);
        assert_eq!(map.iterations, plain.iterations);
    }

    #[test]
    fn an_unreachable_bound_stops_with_the_best_map_and_says_so() {
        // A sphere, cut to a disc first: no cut makes it developable, D = 1 is out of reach.
        let mesh = sphere(3);
        let mut options = FlattenOptions::default().with_max_distortion(1.0);
        options.max_distortion.as_mut().unwrap().max_rounds = 4;
        let plain = flatten(&mesh, &FlattenOptions::default()).unwrap();
        let map = flatten(&mesh, &options).unwrap();
        let cuts = check(&mesh, &map);
        assert!(!cuts.met, "{cuts:?}");
        assert!(
            matches!(cuts.stop, CutStop::RoundCap | CutStop::NoProgress),
            "{cuts:?}"
        );
        assert!(cuts.rounds <= 4 && cuts.after < cuts.before, "{cuts:?}");
        assert_eq!(cuts.history.len(), cuts.rounds);
        assert_eq!(
            cuts.after,
            cuts.history[cuts.best_round - 1].distortion,
            "the best round's map is returned"
        );
        // The topological cut is kept, the distortion cuts come on top of it.
        let seams = map.seams.as_ref().unwrap();
        let topological = plain.seams.as_ref().unwrap();
        assert_eq!(seams.reason, topological.reason);
        assert_eq!(
            map.describe_plan(),
            "cut open along seams (closed, genus 0), then cut open to lower the distortion"
        );
        assert!(
            topological
                .edges
                .iter()
                .all(|e| seams.edges.binary_search(e).is_ok())
        );
        assert!(
            (seams.length - topological.length - cuts.seam_length_added).abs() < 1e-9,
            "{} vs {} + {}",
            seams.length,
            topological.length,
            cuts.seam_length_added
        );
        // Below an isometry's D there is nothing to try.
        let err = flatten(&mesh, &FlattenOptions::default().with_max_distortion(0.9)).unwrap_err();
        assert!(
            matches!(err, FlattenError::Option(OptionError::MaxDistortion(b)) if b == 0.9),
            "{err}"
        );
        assert!(err.to_string().contains("at least 1"), "{err}");
    }

    #[test]
    fn the_mean_distortion_is_that_of_an_affine_stretch() {
        // One triangle stretched by 2 along x: σ = (2, 1), (4 + 1 + 1/4 + 1)/4 before the
        // area normalization scales both by 1/√2: (2 + 1/2 + 1/2 + 2)/4 = 5/4.
        let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let corners = [[[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]]];
        let (d, per) = mean_symmetric_dirichlet(&positions, &[[0, 1, 2]], &corners).unwrap();
        assert!(
            (d - 1.25).abs() < 1e-14 && (per[0] - 1.25).abs() < 1e-14,
            "{d}"
        );
    }
}
