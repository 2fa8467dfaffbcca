//! Cutting along protrusions: a chart that one initial map cannot embed in floating
//! point is cut open along its protrusions before the solve (issue 50).
//!
//! **Why.** A conformal map (LSCM, thesis §3.1.1) shrinks a thin protrusion
//! exponentially along its length: a tube of radius `ρ` and length `ℓ` maps to a strip
//! whose scale falls by about `e^{−ℓ/ρ}` towards its tip (the tube is conformally a
//! half-infinite cylinder). On a closed body with tentacles 30–50 radii long
//! ([`crate::mesh::generate::tentacles`]), the tips shrink by `e^{−30}`..`e^{−50}`:
//! their UV triangles have areas below `10⁻²⁶` against the chart's 1, below what double
//! precision resolves next to coordinates of order 1, so LSCM flips or degenerates them,
//! and mean-value coordinates (onto a circle, injective in exact arithmetic) crush them
//! the same way. Nothing is wrong with the geometry: the chart is too stretched for one
//! embedding. Shorter protrusions (10–30 radii) still embed, but crushed: the solve
//! keeps much of the crush (mean symmetric Dirichlet distortion 2.8–4.9 on tentacles
//! 12–24 radii long, docs/bench/protrusions.md). Cut open along the protrusion, a tube
//! becomes a strip of width `2πρ`, which maps with bounded scale.
//!
//! **The criterion.** The LSCM start of the disc the solver flattens (after the plan's
//! fill and cut, [`super::plan`]), scaled to the surface's area as the solve scales it,
//! is *admissible* here unless
//!
//! - it is *crushed*: `max_t max_i |ln σ_i(t)| > CRUSHED_START_LOG` (= 10) over its
//!   unflipped triangles `t` (`σ_i`: singular values of the map's Jacobian), a scale
//!   change of `e^{10} ≈ 2·10⁴` in length, `5·10⁸` in area; or
//! - both starts flip: LSCM flips or degenerates a triangle, and so do mean-value
//!   coordinates (the solve's fallback).
//!
//! The bound 10 leaves every mesh of `../shared/data` uncut (their flattenings are byte
//! for byte those from before the check, docs/bench/protrusions.md; the progressive
//! iterations of the solve count none of their starts crushed at 8), while the
//! generated tentacles 12–30 radii long reach 12–33, and the default
//! [`crate::mesh::generate::octopus_disc`] 11.4 (tubes of 12 rows: 9.9). A chart the
//! multilevel
//! start flattens (15k faces and more by default, where LSCM is not computed) is checked
//! only when the solve reports that both starts flip, so large easy meshes pay nothing;
//! a smaller chart's LSCM (and mean-value map, when LSCM flips) is computed once,
//! checked, and handed to the solve as its start (the solve would compute the same
//! maps).
//!
//! **The cut.** While the start is not admissible (at most [`MAX_PROTRUSION_CUTS`]
//! times): of the crushed vertices (one of their triangles has `|ln σ|` above the bound
//! or is flipped), the one farthest from the boundary along edges — a protrusion's tip
//! (the most crushed vertex is often not: measured on tube discs, the scale is least a
//! few rows before the cap, and a cut from there leaves the rest of the tube crushed,
//! 12 cuts for 8 tubes) — then the shortest edge path from it to the chart's boundary
//! (Dijkstra on edge lengths; not through a filled hole's vertices), the chart opened
//! along it ([`crate::mesh::cut::open_along`]; the path hangs off the boundary, so the
//! chart stays one disc), and LSCM again. Cost: one LSCM solve and one Dijkstra per cut.
//! With [`super::plan::Cut::Never`] (a map of one UV per vertex), or a given or explicit
//! start, nothing is checked or cut.
//!
//! If after the cuts both starts still flip, the flattening is refused with
//! [`FlattenError::NoAdmissibleStartAfterCuts`], which names the flips, the cuts and a
//! triangle that flips.

use super::flatten::FlattenError;
use super::optcuts::Chart;
use super::plan::Prepared;
use crate::mesh::edge_graph::EdgeGraph;
use crate::mesh::{Disc, Topology, TriMesh};
use crate::param::element::{jacobian, rest_triangles};
use crate::param::{lscm, make_admissible, signed_uv_area, tutte};
use serde::Serialize;
use std::time::Instant;

/// A start is crushed when some unflipped triangle's `|ln σ_i|` exceeds this (module
/// docs): at 10 no mesh of `../shared/data` is (they reach at most 8), the tentacles of
/// issue 50 reach 20 and more.
pub(crate) const CRUSHED_START_LOG: f64 = 10.0;

/// Cuts along protrusions at most before the chart is flattened as it is (or refused,
/// if both starts still flip).
pub const MAX_PROTRUSION_CUTS: usize = 64;

/// What the cutting along protrusions did ([`super::flatten::Flattening::protrusion_cuts`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProtrusionCuts {
    /// Paths cut, one per protrusion.
    pub cuts: usize,
    /// Seam edges and their 3D length, beyond the plan's cut.
    pub seam_edges: usize,
    pub seam_length: f64,
    /// The vertices the paths start from (the protrusions' tips; the input's numbering,
    /// the fill's vertices after it).
    pub from_vertices: Vec<u32>,
    /// `max |ln σ|` of the LSCM start over its unflipped triangles, before and after
    /// the cuts.
    pub crush_before: f64,
    pub crush_after: f64,
    /// Triangles the LSCM start flipped or degenerated before and after the cuts.
    pub lscm_flipped_before: usize,
    pub lscm_flipped_after: usize,
    /// Seconds for the checks and cuts.
    pub time: f64,
}

/// Which starts [`cut_protrusions`] refuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Refuse {
    /// Crushed starts, and those where both maps flip (a chart whose solve starts from
    /// LSCM).
    CrushedOrFlipped,
    /// Only those where both maps flip (a chart whose solve starts from the multilevel
    /// start and found no admissible single-level start).
    Flipped,
}

/// The disc to solve after [`cut_protrusions`]: cut open or as it was, what was cut, and
/// its initial maps when computed.
pub(crate) struct Protruded {
    pub(crate) prepared: Prepared,
    pub(crate) cuts: Option<ProtrusionCuts>,
    pub(crate) maps: Option<StartMaps>,
}

/// The initial maps of a disc computed to examine it, as computed (on the positions
/// scaled to unit area, not mirrored): the solve starts from them instead of computing
/// them again (it would compute the same maps).
#[derive(Clone, Debug)]
pub(crate) struct StartMaps {
    pub(crate) lscm: Vec<[f64; 2]>,
    /// Computed only when LSCM flips a triangle (then the solve falls back to it).
    pub(crate) mean_value: Option<Vec<[f64; 2]>>,
}

/// The LSCM start of one disc, examined.
struct Examined {
    maps: StartMaps,
    lscm_flipped: usize,
    /// Triangles mean-value coordinates flip (computed only when LSCM flips).
    mean_value_flipped: usize,
    /// A triangle mean-value coordinates flip, if any.
    mean_value_first: Option<usize>,
    /// `max_i |ln σ_i|` per triangle (infinite where flipped), and its maximum over the
    /// unflipped ones.
    per_triangle: Vec<f64>,
    crush: f64,
}

impl Examined {
    fn of(mesh: &TriMesh) -> Result<Self, FlattenError> {
        let disc = Disc::new(mesh)?;
        let (positions, _) = mesh.unit_area_positions();
        let lscm = lscm::lscm(&positions, &disc)?.uv;
        let mut uv = lscm.clone();
        let lscm_flipped = make_admissible(&mut uv, &mesh.triangles);
        let corners = |uv: &[[f64; 2]], t: &[u32; 3]| t.map(|v| uv[v as usize]);
        // Scaled to unit area, as the solve scales its start.
        let area: f64 = mesh
            .triangles
            .iter()
            .map(|t| signed_uv_area(corners(&uv, t)))
            .sum();
        let s = (1.0 / area).sqrt();
        let rest = rest_triangles(&positions, &mesh.triangles)?;
        let per_triangle: Vec<f64> = mesh
            .triangles
            .iter()
            .zip(&rest)
            .map(|(t, r)| {
                let c = corners(&uv, t).map(|p| [s * p[0], s * p[1]]);
                if signed_uv_area(c).is_nan() || signed_uv_area(c) <= 0.0 {
                    return f64::INFINITY;
                }
                let (s1, s2) = crate::measure::jacobian::signed_singular_values(jacobian(r, &c));
                let crush = s1.ln().abs().max(s2.ln().abs());
                if crush.is_nan() { f64::INFINITY } else { crush }
            })
            .collect();
        let crush = per_triangle
            .iter()
            .filter(|c| c.is_finite())
            .fold(0.0f64, |a, &b| a.max(b));
        let (mut mean_value_flipped, mut mean_value_first, mut mean_value) = (0, None, None);
        if lscm_flipped > 0 {
            let computed = tutte::mean_value(&positions, &disc)?;
            let mut mv = computed.clone();
            mean_value_flipped = make_admissible(&mut mv, &mesh.triangles);
            mean_value_first = mesh.triangles.iter().position(|t| {
                let area = signed_uv_area(corners(&mv, t));
                area.is_nan() || area <= 0.0
            });
            mean_value = Some(computed);
        }
        Ok(Self {
            maps: StartMaps { lscm, mean_value },
            lscm_flipped,
            mean_value_flipped,
            mean_value_first,
            per_triangle,
            crush,
        })
    }

    fn both_flip(&self) -> bool {
        self.lscm_flipped > 0 && self.mean_value_flipped > 0
    }

    fn admissible(&self, refuse: Refuse) -> bool {
        !self.both_flip() && (refuse == Refuse::Flipped || self.crush <= CRUSHED_START_LOG)
    }
}

/// Cuts `prepared` (its first `input_faces` triangles the input's, the rest fill holes)
/// along protrusions until its start is admissible under `refuse` (module docs).
/// Returns it uncut, without a report, when it is admissible already (or has vertices no
/// triangle uses, which the solve leaves out: then it is not examined).
pub(crate) fn cut_protrusions(
    input_faces: usize,
    prepared: Prepared,
    refuse: Refuse,
) -> Result<Protruded, FlattenError> {
    cut_at_most(input_faces, prepared, refuse, MAX_PROTRUSION_CUTS)
}

/// [`cut_protrusions`] with at most `max_cuts` cuts.
fn cut_at_most(
    input_faces: usize,
    prepared: Prepared,
    refuse: Refuse,
    max_cuts: usize,
) -> Result<Protruded, FlattenError> {
    let clock = Instant::now();
    let mut used = vec![false; prepared.mesh.positions.len()];
    prepared
        .mesh
        .triangles
        .iter()
        .for_each(|t| t.iter().for_each(|&v| used[v as usize] = true));
    if used.contains(&false) {
        return Ok(Protruded {
            prepared,
            cuts: None,
            maps: None,
        });
    }
    let mut examined = Examined::of(&prepared.mesh)?;
    if examined.admissible(refuse) {
        return Ok(Protruded {
            prepared,
            cuts: None,
            maps: Some(examined.maps),
        });
    }
    let mut report = ProtrusionCuts {
        cuts: 0,
        seam_edges: 0,
        seam_length: 0.0,
        from_vertices: Vec::new(),
        crush_before: examined.crush,
        crush_after: examined.crush,
        lscm_flipped_before: examined.lscm_flipped,
        lscm_flipped_after: examined.lscm_flipped,
        time: 0.0,
    };
    let mut chart = Chart::new(prepared);
    while report.cuts < max_cuts && !examined.admissible(refuse) {
        let topology = Topology::new(&chart.disc);
        let Some((from, path)) =
            protrusion_path(&chart.disc, &topology, input_faces, &examined.per_triangle)
        else {
            break;
        };
        report.from_vertices.push(chart.vertex_of[from as usize]);
        chart = chart.split(&topology, &path)?.0;
        report.cuts += 1;
        examined = Examined::of(&chart.disc)?;
    }
    if examined.both_flip() {
        return Err(FlattenError::NoAdmissibleStartAfterCuts {
            cuts: report.cuts,
            lscm: examined.lscm_flipped,
            mean_value: examined.mean_value_flipped,
            triangle: examined.mean_value_first.filter(|&t| t < input_faces),
        });
    }
    report.seam_edges = chart.added_edges;
    report.seam_length = chart.added_length;
    report.crush_after = examined.crush;
    report.lscm_flipped_after = examined.lscm_flipped;
    report.time = clock.elapsed().as_secs_f64();
    let cuts = (report.cuts > 0).then_some(report);
    Ok(Protruded {
        prepared: chart.into_prepared(),
        cuts,
        maps: Some(examined.maps),
    })
}

/// The path of one cut (module docs): among the vertices of `disc` neither on its
/// boundary nor on a filled hole, the crushed one (a triangle's `|ln σ|` above
/// [`CRUSHED_START_LOG`] or flipped; `per_triangle`: `|ln σ|` of every triangle, the
/// ones from `input_faces` on filling holes) farthest from the boundary, and its
/// shortest edge path (disc vertex pairs) to the boundary. `None` when no such vertex
/// reaches the boundary.
fn protrusion_path(
    disc: &TriMesh,
    topology: &Topology,
    input_faces: usize,
    per_triangle: &[f64],
) -> Option<(u32, Vec<[u32; 2]>)> {
    let n = disc.positions.len();
    let mut crush = vec![0.0f64; n];
    let mut blocked = vec![false; n];
    for (t, tri) in disc.triangles.iter().enumerate() {
        for &v in tri {
            if t >= input_faces {
                blocked[v as usize] = true;
            } else {
                crush[v as usize] = crush[v as usize].max(per_triangle[t]);
            }
        }
    }
    let on_boundary = topology.on_boundary(n);
    let graph = EdgeGraph::new(disc, topology);
    let passable = |v: u32| !blocked[v as usize] || on_boundary[v as usize];
    let boundary: Vec<u32> = (0..n as u32).filter(|&v| on_boundary[v as usize]).collect();
    let (reach, _, _) = graph.shortest_paths(&boundary, |_, _, l| l, passable, |_| false);
    let crushed = |v: usize| crush[v] > CRUSHED_START_LOG;
    let from = (0..n)
        .filter(|&v| !blocked[v] && !on_boundary[v] && reach[v].is_finite())
        .max_by(|&a, &b| {
            crushed(a)
                .cmp(&crushed(b))
                .then(reach[a].total_cmp(&reach[b]))
                .then(crush[a].total_cmp(&crush[b]))
        })? as u32;
    let path = graph.path_to(from, |_, _, l| l, passable, |v| on_boundary[v as usize])?;
    Some((from, path))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{Octopus, Tentacles, octopus_disc, sphere, tentacles};
    use crate::param::flatten::{CutReason, FlattenOptions, Flattening, flatten};

    /// One chart (one disc after the cuts), flip-free and overlap-free, cut open, the
    /// UVs split exactly along the reported seams; returns the map's mean symmetric
    /// Dirichlet distortion `D` (1 for an isometry).
    fn check_one_chart(mesh: &TriMesh, map: &Flattening) -> f64 {
        assert!(map.seams.is_some(), "cut open");
        crate::param::optcuts::tests::one_chart(mesh, map).symmetric_dirichlet / 4.0
    }

    /// The disc the plan makes of `mesh` with the default options.
    fn topologically_cut(mesh: &TriMesh) -> Prepared {
        let options = FlattenOptions::default();
        let mut plan = crate::param::plan::plan(mesh, &options).unwrap();
        crate::param::plan::prepare(mesh, &mut plan, &options).unwrap()
    }

    #[test]
    fn closed_tentacles_are_cut_along_their_protrusions_into_one_chart() {
        let mesh = tentacles(&Tentacles::default());
        // The failing case: after the topological cut, both starts flip (the flattening
        // was refused: "both initial maps flipped triangles").
        let examined = Examined::of(&topologically_cut(&mesh).mesh).unwrap();
        assert!(
            examined.both_flip(),
            "flips {} / {}",
            examined.lscm_flipped,
            examined.mean_value_flipped
        );
        let map = flatten(&mesh, &FlattenOptions::default()).unwrap();
        let distortion = check_one_chart(&mesh, &map);
        let cuts = map.protrusion_cuts.as_ref().expect("cut along protrusions");
        // The topological cut of a closed genus-0 surface opens one path between two far
        // tips; the other tentacles get one cut each, at most.
        assert!((1..=8).contains(&cuts.cuts), "{cuts:?}");
        assert!(cuts.crush_after <= CRUSHED_START_LOG, "{cuts:?}");
        let seams = map.seams.as_ref().unwrap();
        assert_eq!(
            seams.reason,
            CutReason::Topology {
                boundary_loops: 0,
                genus: 0
            }
        );
        assert!(seams.length > cuts.seam_length && cuts.seam_length > 0.0);
        assert!(
            map.describe_plan().starts_with(&format!(
                "cut open along seams (closed, genus 0), then cut along {} protrusions (seam length ",
                cuts.cuts
            )),
            "{}",
            map.describe_plan()
        );
        assert!(distortion < 1.5, "D = {distortion}");
        // With a distortion bound, too (issue 50: refused the same way before).
        let bounded = flatten(&mesh, &FlattenOptions::default().with_max_distortion(1.5)).unwrap();
        check_one_chart(&mesh, &bounded);
        assert!(bounded.protrusion_cuts.is_some());
    }

    #[test]
    fn tube_discs_are_cut_along_their_tubes() {
        // Tubes 60 rows long on the octopus disc: tips shrunk by about e^{−47}; both
        // starts flip (refused before).
        let mesh = octopus_disc(&Octopus {
            length: 60,
            ..Default::default()
        });
        assert!(Examined::of(&mesh).unwrap().both_flip());
        // Never cut: refused as before, naming protrusions as a cause.
        let never = FlattenOptions::default().with_cut(crate::param::plan::Cut::Never);
        let err = flatten(&mesh, &never).unwrap_err();
        assert!(
            matches!(err, FlattenError::NoAdmissibleStart { .. }),
            "{err}"
        );
        assert!(err.to_string().contains("protrusions"), "{err}");
        let map = flatten(&mesh, &FlattenOptions::default()).unwrap();
        check_one_chart(&mesh, &map);
        let cuts = map.protrusion_cuts.as_ref().expect("cut along protrusions");
        // Every tube is cut first from its end: its tip (one of the 8 vertices farthest
        // from the hub's centre) or a vertex of its last row, which the arm numbers
        // just before the tip (the far side of the tube can be farther from the
        // boundary than the tip); short cuts near the hub may follow.
        let mut by_distance: Vec<u32> = (0..mesh.positions.len() as u32).collect();
        let radius = |v: &u32| crate::vec3::norm3(mesh.positions[*v as usize]);
        by_distance.sort_by(|a, b| radius(b).total_cmp(&radius(a)));
        for tip in &by_distance[..8] {
            let end = tip - 8..=*tip;
            assert!(
                cuts.from_vertices[..8].iter().any(|v| end.contains(v)),
                "{tip}: {cuts:?}"
            );
        }
        assert!((8..=16).contains(&cuts.cuts), "{cuts:?}");
        let seams = map.seams.as_ref().unwrap();
        assert_eq!(seams.reason, CutReason::Protrusions);
        assert!((seams.length - cuts.seam_length).abs() < 1e-12);
        assert!(
            map.describe_plan()
                .starts_with(&format!("cut along {} protrusions", cuts.cuts)),
            "{}",
            map.describe_plan()
        );
    }

    #[test]
    fn a_chart_the_multilevel_start_flattens_is_cut_only_when_no_start_embeds_it() {
        use crate::param::flatten::{CoarseLevel, Multilevel, Start};
        let options = FlattenOptions {
            start: Start::Auto {
                multilevel: Multilevel::Always(CoarseLevel::default()),
            },
            ..Default::default()
        };
        let mesh = tentacles(&Tentacles::default());
        // The multilevel start embeds the tentacles (its coarse level is not crushed):
        // no check, no cut.
        let map = flatten(&mesh, &options).unwrap();
        check_one_chart(&mesh, &map);
        assert_eq!(map.start, crate::param::flatten::StartMap::Multilevel);
        assert!(map.protrusion_cuts.is_none());
        // Had it failed, the single-level starts would have been cut until they no
        // longer both flip: the same tips first, and no more cuts than for a crush.
        let prepared = topologically_cut(&mesh);
        let faces = prepared.mesh.triangles.len();
        let flipped = cut_protrusions(faces, prepared, Refuse::Flipped).unwrap();
        let crushed =
            cut_protrusions(faces, topologically_cut(&mesh), Refuse::CrushedOrFlipped).unwrap();
        let (flipped, crushed) = (flipped.cuts.unwrap(), crushed.cuts.unwrap());
        assert!(
            flipped.cuts >= 1 && flipped.cuts <= crushed.cuts,
            "{flipped:?}"
        );
        assert_eq!(
            flipped.from_vertices[..],
            crushed.from_vertices[..flipped.cuts]
        );
    }

    #[test]
    fn easy_meshes_are_not_cut_and_keep_their_map() {
        // Tubes 10 rows long: tips shrunk by e^{−8.4}, below the bound (the default
        // octopus, 14 rows, reaches e^{−11.4} and is cut).
        let short = octopus_disc(&Octopus {
            length: 10,
            ..Default::default()
        });
        for mesh in [sphere(3), short] {
            let map = flatten(&mesh, &FlattenOptions::default()).unwrap();
            assert!(map.protrusion_cuts.is_none());
            assert!(!map.describe_plan().contains("protrusion"));
        }
    }

    #[test]
    fn a_start_the_cuts_do_not_make_admissible_is_refused_naming_what_flips() {
        // The tentacles with a single cut allowed: five crushed tentacles are left, both
        // starts still flip, and the error says how many triangles and after what.
        let prepared = topologically_cut(&tentacles(&Tentacles::default()));
        let faces = prepared.mesh.triangles.len();
        let Err(e) = cut_at_most(faces, prepared, Refuse::CrushedOrFlipped, 1) else {
            panic!("one cut made the start admissible");
        };
        let FlattenError::NoAdmissibleStartAfterCuts {
            cuts,
            lscm,
            mean_value,
            triangle,
        } = e
        else {
            panic!("{e}")
        };
        assert_eq!(cuts, 1);
        assert!(lscm > 0 && mean_value > 0);
        let t = triangle.expect("an input triangle flips");
        let message = e.to_string();
        for part in [
            "after 1 cut along a protrusion".to_string(),
            format!("LSCM flips or degenerates {lscm} triangles"),
            format!("mean-value coordinates {mean_value}"),
            format!("triangle {t}"),
            "nearly coincident vertices".to_string(),
            "Cut::Along".to_string(),
        ] {
            assert!(message.contains(&part), "{part}: {message}");
        }
    }
}
