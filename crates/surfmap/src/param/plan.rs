//! What [`super::flatten`] does with a mesh before the solve, and the way back: a disc is
//! flattened as it is; a disc with holes has them filled for the solve
//! ([`crate::mesh::repair::fill_holes`]; they stay open in the map); any other
//! connected, orientable, manifold surface — closed, with handles, or with holes that
//! are not filled — is cut open into a disc along seams ([`crate::mesh::cut`]), and the
//! map has one UV per corner, split along the seams.
//!
//! [`plan`] says which, and why, without solving (the command line's `inspect` prints
//! it); a mesh no fill or cut can help (coordinates that are not finite or overflow,
//! degenerate or repeated faces, several components, non-manifold, non-orientable or
//! inconsistently oriented) is refused with every blocking defect and its remedy, as
//! [`crate::mesh::validate`] names them.

use super::flatten::{FlattenError, FlattenOptions};
use crate::mesh::cut::{OpenedMesh, fixed_by_cutting, open_along};
use crate::mesh::validate::{DefectKind, blocks_geometry, validate};
use crate::mesh::{Topology, TriMesh};
use serde::Serialize;

/// How a surface that is not a disc is cut open ([`FlattenOptions::cut`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Cut {
    /// Along the cut graph of [`crate::mesh::cut::cut_graph`]: closed surfaces, handles,
    /// and the boundary loops left when holes are not filled.
    #[default]
    Auto,
    /// Along these seams (pairs of vertices joined by an edge, after holes are filled);
    /// the surface cut along them must be a disc.
    Along(Vec<[u32; 2]>),
    /// Never: a mesh that is not a disc (once its holes are filled, if asked) is an
    /// error, and a disc is not cut along protrusions either
    /// ([`super::protrusions`]): the map has one UV per vertex.
    Never,
}

/// Why the surface was cut.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum CutReason {
    /// Along the caller's seams ([`Cut::Along`]).
    Given,
    /// The surface to flatten (holes filled, if asked) has `boundary_loops` boundary
    /// loops (0: closed) and genus `genus`; a disc has one and 0.
    Topology { boundary_loops: usize, genus: u32 },
    /// A disc cut only to bring its distortion under the bound
    /// ([`super::flatten::FlattenOptions::max_distortion`]); a surface cut for its
    /// topology keeps that reason when distortion cuts are added.
    Distortion,
    /// A disc cut only along its protrusions, because no single chart of it could be
    /// embedded in floating point ([`super::protrusions`]; what was cut is in
    /// [`super::flatten::Flattening::protrusion_cuts`]); a surface cut for its topology
    /// keeps that reason when protrusion cuts are added.
    Protrusions,
}

/// What [`super::flatten`] does before the solve (see the module docs).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Plan {
    /// Holes (boundary loops but the longest) filled for the solve.
    pub holes_to_fill: usize,
    /// Why the surface is cut open, if it is.
    pub cut: Option<CutReason>,
}

impl Plan {
    /// Nothing to do: a disc as it is.
    pub fn is_disc_as_is(&self) -> bool {
        self.holes_to_fill == 0 && self.cut.is_none()
    }

    /// For people: `disc as is`, `fill 3 holes`, `cut open along seams (closed, genus 0)`,
    /// `fill 105 holes, then cut open along seams (genus 3, 1 boundary loop)`.
    pub fn describe(&self) -> String {
        let fill = match self.holes_to_fill {
            0 => None,
            1 => Some("fill 1 hole".to_string()),
            n => Some(format!("fill {n} holes")),
        };
        let cut = self.cut.as_ref().map(|reason| match reason {
            CutReason::Given => "cut open along the given seams".to_string(),
            CutReason::Distortion => "cut open to lower the distortion".to_string(),
            CutReason::Protrusions => "cut along protrusions".to_string(),
            CutReason::Topology {
                boundary_loops,
                genus,
            } => format!(
                "cut open along seams ({})",
                topology_words(*boundary_loops, *genus)
            ),
        });
        match (fill, cut) {
            (None, None) => "disc as is".to_string(),
            (Some(f), None) => f,
            (None, Some(c)) => c,
            (Some(f), Some(c)) => format!("{f}, then {c}"),
        }
    }
}

/// `closed, genus 0`, `genus 1, 1 boundary loop`, `4 boundary loops`.
fn topology_words(boundary_loops: usize, genus: u32) -> String {
    let loops = match boundary_loops {
        0 => "closed".to_string(),
        1 => "1 boundary loop".to_string(),
        n => format!("{n} boundary loops"),
    };
    match (boundary_loops, genus) {
        (0, g) => format!("{loops}, genus {g}"),
        (_, 0) => loops,
        (_, g) => format!("genus {g}, {loops}"),
    }
}

/// What [`super::flatten`] will do with `mesh` under `options` (module docs).
pub fn plan(mesh: &TriMesh, options: &FlattenOptions) -> Result<Plan, FlattenError> {
    mesh.check_indices()?;
    plan_with_topology(mesh, &Topology::new(mesh), options)
}

/// [`plan`] with the topology of `mesh` already derived.
pub(crate) fn plan_with_topology(
    mesh: &TriMesh,
    topology: &Topology,
    options: &FlattenOptions,
) -> Result<Plan, FlattenError> {
    let cuttable = topology.num_components == 1
        && topology.is_manifold()
        && topology.orientable
        && topology.inconsistent_edges.is_empty();
    let loops = topology.boundary_loops.len();
    let holes_to_fill = if options.fill_holes && cuttable && loops > 1 {
        loops - 1
    } else {
        0
    };
    let genus = topology.genus();
    let left = loops - holes_to_fill;
    let is_disc = cuttable && left == 1 && genus == Some(0);
    let cut = match &options.cut {
        _ if !cuttable => None,
        Cut::Along(_) => Some(CutReason::Given),
        Cut::Auto if !is_disc => Some(CutReason::Topology {
            boundary_loops: left,
            genus: genus.unwrap_or(0),
        }),
        Cut::Auto | Cut::Never => None,
    };
    // The geometry first: coordinates and faces no fill or cut can make usable
    // (validation's verdict, the same that `inspect` reports).
    if blocks_geometry(mesh, topology) || !cuttable || (cut.is_none() && !is_disc) {
        // What is left for the caller to fix: everything that blocks a disc, but what
        // the options fill or cut.
        // (A cut or fill that the other defects prevent today counts as fixing: it
        // applies once they are repaired.)
        let fixed = |kind: DefectKind| {
            (options.cut != Cut::Never && fixed_by_cutting(kind))
                || (kind == DefectKind::SeveralBoundaryLoops && options.fill_holes)
        };
        let defects = validate(mesh, topology)
            .into_iter()
            .filter(|d| d.blocks_flattening && !fixed(d.kind))
            .collect();
        return Err(FlattenError::NotADisc(defects));
    }
    Ok(Plan { holes_to_fill, cut })
}

/// The surface handed to the solver, and what maps its result back to the input.
pub(crate) struct Prepared {
    /// The disc to flatten: the input, holes filled (fill vertices and faces after the
    /// input's), cut open (copies of seam vertices after those).
    pub mesh: TriMesh,
    /// The cut, when there is one (its `mesh` moved into [`Self::mesh`]).
    pub opened: Option<OpenedMesh>,
}

/// Fills and cuts `mesh` as `plan` says. With [`Cut::Auto`], if the seams of the filled
/// surface would still cut the surface itself apart (around a filled hole they could not
/// avoid), the holes are cut instead of filled, and `plan` says so.
pub(crate) fn prepare(
    mesh: &TriMesh,
    plan: &mut Plan,
    options: &FlattenOptions,
) -> Result<Prepared, FlattenError> {
    let filled = if plan.holes_to_fill > 0 {
        crate::mesh::repair::fill_holes(mesh).0
    } else {
        TriMesh::new(mesh.positions.clone(), mesh.triangles.clone())
    };
    if plan.cut.is_none() {
        return Ok(Prepared {
            mesh: filled,
            opened: None,
        });
    }
    let topology = Topology::new(&filled);
    // No seam along a filled hole: its faces are dropped from the map.
    let nf = mesh.triangles.len() as u32;
    let seams = match &options.cut {
        Cut::Along(seams) => seams.clone(),
        _ => crate::mesh::cut::cut_graph_avoiding(&filled, &topology, |f| f >= nf)?,
    };
    let mut opened = open_along(&filled, &topology, &seams)?;
    if plan.holes_to_fill > 0 && options.cut == Cut::Auto && !one_piece(&opened.mesh, nf) {
        let topology = Topology::new(mesh);
        *plan = Plan {
            holes_to_fill: 0,
            cut: Some(CutReason::Topology {
                boundary_loops: topology.boundary_loops.len(),
                genus: topology.genus().unwrap_or(0),
            }),
        };
        return prepare(mesh, plan, options);
    }
    let disc = std::mem::take(&mut opened.mesh);
    Ok(Prepared {
        mesh: disc,
        opened: Some(opened),
    })
}

/// Whether the first `faces` triangles of `mesh` (the surface without its fill) are
/// one manifold piece of genus 0.
fn one_piece(mesh: &TriMesh, faces: u32) -> bool {
    let surface = TriMesh::new(
        mesh.positions.clone(),
        mesh.triangles[..faces as usize].to_vec(),
    );
    let topology = Topology::new(&surface);
    topology.num_components == 1 && topology.genus() == Some(0)
}

/// The seams of a cut map and its per-corner UV indexing.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Seams {
    /// Why the surface was cut.
    pub reason: CutReason,
    /// The cut edges, `[low, high]` vertex pairs of the input, sorted.
    pub edges: Vec<[u32; 2]>,
    /// Their total 3D length.
    pub length: f64,
    /// Corner `k` of triangle `t` has UV `Flattening::uvs[uv_triangles[t][k]]`.
    #[serde(skip)]
    pub uv_triangles: Vec<[u32; 3]>,
    /// The input vertex of every UV.
    #[serde(skip)]
    pub vertex_of_uv: Vec<u32>,
}

/// The per-UV coordinates of the prepared disc mapped back to the input: per vertex
/// without a cut (the fill's vertices dropped), or per corner with [`Seams`] (UVs of the
/// fill's vertices and faces dropped).
pub(crate) fn map_back(
    input: &TriMesh,
    prepared: Prepared,
    reason: CutReason,
    uvs: Vec<[f64; 2]>,
) -> (Vec<[f64; 2]>, Option<Seams>) {
    let n = input.positions.len();
    let Some(opened) = prepared.opened else {
        let mut uvs = uvs;
        uvs.truncate(n);
        return (uvs, None);
    };
    let nf = input.triangles.len();
    let mut new_index = vec![u32::MAX; uvs.len()];
    let (mut kept, mut vertex_of_uv) = (Vec::new(), Vec::new());
    let uv_triangles: Vec<[u32; 3]> = prepared.mesh.triangles[..nf]
        .iter()
        .map(|t| {
            t.map(|v| {
                if new_index[v as usize] == u32::MAX {
                    new_index[v as usize] = kept.len() as u32;
                    kept.push(uvs[v as usize]);
                    vertex_of_uv.push(opened.original_vertex[v as usize]);
                }
                new_index[v as usize]
            })
        })
        .collect();
    // Seams of the filled surface that run through a fill are no seams of the input.
    let edges: Vec<[u32; 2]> = opened
        .seams
        .into_iter()
        .filter(|e| e.iter().all(|&v| (v as usize) < n))
        .collect();
    let seams = Seams {
        reason,
        length: crate::mesh::cut::seam_length(&input.positions, &edges),
        edges,
        uv_triangles,
        vertex_of_uv,
    };
    (kept, Some(seams))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::mesh::generate::{grid_disc, octahedron, torus};
    use crate::param::flatten::{Bijective, Guarantee};

    fn with_two_holes() -> TriMesh {
        let mut mesh = grid_disc(8);
        let holes = [2 * 9 + 2, 5 * 9 + 5];
        mesh.triangles
            .retain(|t| !holes.iter().any(|h| t.contains(h)));
        mesh
    }

    #[test]
    fn the_plan_follows_the_topology_and_the_options() {
        let defaults = FlattenOptions::default();
        let described =
            |mesh: &TriMesh, options: &FlattenOptions| plan(mesh, options).map(|p| p.describe());
        assert_eq!(described(&grid_disc(3), &defaults).unwrap(), "disc as is");
        assert_eq!(
            described(&with_two_holes(), &defaults).unwrap(),
            "fill 2 holes"
        );
        let cut_holes = FlattenOptions::default().with_fill_holes(false);
        assert_eq!(
            described(&with_two_holes(), &cut_holes).unwrap(),
            "cut open along seams (3 boundary loops)"
        );
        assert_eq!(
            described(&octahedron(), &defaults).unwrap(),
            "cut open along seams (closed, genus 0)"
        );
        assert_eq!(
            described(&torus(2.0, 0.5, 8, 6), &defaults).unwrap(),
            "cut open along seams (closed, genus 1)"
        );
        let seams = FlattenOptions {
            cut: Cut::Along(vec![[0, 4]]),
            ..Default::default()
        };
        assert_eq!(
            described(&octahedron(), &seams).unwrap(),
            "cut open along the given seams"
        );
        // Never: today's refusal, naming only what is left to fix.
        let never = FlattenOptions {
            cut: Cut::Never,
            ..Default::default()
        };
        let err = plan(&octahedron(), &never).unwrap_err();
        assert!(err.to_string().contains("closed"), "{err}");
        assert_eq!(
            described(&with_two_holes(), &never).unwrap(),
            "fill 2 holes"
        );
        let never_unfilled = FlattenOptions {
            cut: Cut::Never,
            fill_holes: false,
            ..Default::default()
        };
        let err = plan(&with_two_holes(), &never_unfilled).unwrap_err();
        assert!(err.to_string().contains("3 boundary loops"), "{err}");
    }

    /// Flattens with `options`, checks the map: one UV triangle per input triangle,
    /// counter-clockwise (flip-free), every UV a copy of its input vertex, one chart
    /// without overlap, whose boundary does not even touch itself unless
    /// `touching_seams` (the two sides of a seam on a plane, mapped isometrically,
    /// coincide); returns it.
    fn flatten_and_check(
        mesh: &TriMesh,
        options: &FlattenOptions,
        touching_seams: bool,
    ) -> super::super::flatten::Flattening {
        let map = super::super::flatten::flatten(mesh, options).unwrap();
        let corners = map.corner_uvs(&mesh.triangles);
        assert_eq!(corners.len(), mesh.triangles.len());
        assert!(
            corners
                .iter()
                .all(|&c| super::super::signed_uv_area(c) > 0.0)
        );
        let seams = map.seams.as_ref().expect("cut open");
        for (t, uv_tri) in seams.uv_triangles.iter().enumerate() {
            assert_eq!(
                uv_tri.map(|u| seams.vertex_of_uv[u as usize]),
                mesh.triangles[t]
            );
        }
        let (_, charts) = crate::measure::charts::chart_labels(&mesh.triangles, &corners);
        assert_eq!(charts, 1);
        let overlap = crate::measure::overlap::boundary_overlap(&mesh.triangles, &corners);
        assert!(
            overlap.complete && overlap.overlap_area == 0.0,
            "{overlap:?}"
        );
        assert!(touching_seams || !overlap.self_intersecting, "{overlap:?}");
        map
    }

    /// Whether the two faces of every input edge agree on its endpoints' UVs exactly
    /// when the edge is no seam.
    pub(crate) fn seams_split_exactly(mesh: &TriMesh, seams: &Seams) {
        let topology = Topology::new(mesh);
        for (e, &[a, b]) in topology.edges.iter().enumerate() {
            let &[f, g] = topology.faces_of_edge(e) else {
                continue;
            };
            let uv_of = |t: u32, v: u32| {
                let k = mesh.triangles[t as usize]
                    .iter()
                    .position(|&w| w == v)
                    .unwrap();
                seams.uv_triangles[t as usize][k]
            };
            let joined = uv_of(f, a) == uv_of(g, a) && uv_of(f, b) == uv_of(g, b);
            let is_seam = seams.edges.binary_search(&[a, b]).is_ok();
            assert_eq!(joined, !is_seam, "edge ({a}, {b})");
        }
    }

    #[test]
    fn closed_and_higher_genus_surfaces_flatten_to_one_disc() {
        use crate::mesh::generate::{holed_plate, sphere};
        let defaults = FlattenOptions::default();
        for (mesh, genus) in [
            (sphere(3), 0),
            (torus(2.0, 0.7, 40, 16), 1),
            (holed_plate(3, 2), 3),
        ] {
            let map = flatten_and_check(&mesh, &defaults, false);
            let seams = map.seams.as_ref().unwrap();
            assert_eq!(
                seams.reason,
                CutReason::Topology {
                    boundary_loops: 0,
                    genus
                }
            );
            seams_split_exactly(&mesh, seams);
            assert!(map.converged, "genus {genus}: {:?}", map.stop_reason);
            assert!(seams.length > 0.0);
        }
        // Holes and handles: the holes are filled, the handles cut, and no seam runs
        // through a filled hole (the map stays one chart without the fill's faces).
        let mut mesh = holed_plate(2, 3);
        let holes = [0u32, 40];
        mesh.triangles
            .retain(|t| !holes.iter().any(|h| t.contains(h)));
        let topology = Topology::new(&mesh);
        assert_eq!(
            (topology.boundary_loops.len(), topology.genus()),
            (2, Some(2))
        );
        let map = flatten_and_check(&mesh, &defaults, false);
        assert_eq!(
            map.plan.describe(),
            "fill 1 hole, then cut open along seams (genus 2, 1 boundary loop)"
        );
        seams_split_exactly(&mesh, map.seams.as_ref().unwrap());
    }

    #[test]
    fn holes_are_cut_instead_of_filled_on_request() {
        let mut mesh = grid_disc(8);
        let holes = [2 * 9 + 2, 5 * 9 + 5, 6 * 9 + 2];
        mesh.triangles
            .retain(|t| !holes.iter().any(|h| t.contains(h)));
        let cut_holes = FlattenOptions::default().with_fill_holes(false);
        // Without the barrier, a plane cut open is still a plane: the map is an
        // isometry, every UV edge as long as in 3D, the two sides of every seam touch.
        let map = flatten_and_check(
            &mesh,
            &cut_holes.clone().with_bijective(Bijective::Off),
            true,
        );
        let seams = map.seams.as_ref().unwrap();
        assert_eq!(
            seams.reason,
            CutReason::Topology {
                boundary_loops: 4,
                genus: 0
            }
        );
        seams_split_exactly(&mesh, seams);
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let uv = seams.uv_triangles[t];
            for k in 0..3 {
                let (a, b) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
                let l3 =
                    crate::vec3::norm3(crate::vec3::sub3(mesh.positions[a], mesh.positions[b]));
                let (p, q) = (map.uvs[uv[k] as usize], map.uvs[uv[(k + 1) % 3] as usize]);
                let l2 = (p[0] - q[0]).hypot(p[1] - q[1]);
                assert!((l2 - l3).abs() < 1e-6 * l3, "{l2} vs {l3}");
            }
        }
        // By default the touching seam sides are kept apart by the boundary barrier:
        // the boundary does not even touch itself, the energy stays near the isometry's.
        let apart = flatten_and_check(&mesh, &cut_holes, false);
        assert_eq!(
            (apart.guarantee, apart.boundary_crossings),
            (Guarantee::Bijective, 0)
        );
        assert!(apart.barrier && !map.barrier);
        assert!(
            apart.energy < map.energy * 1.05,
            "{} vs {}",
            apart.energy,
            map.energy
        );
        seams_split_exactly(&mesh, apart.seams.as_ref().unwrap());
    }

    #[test]
    fn user_seams_are_honoured() {
        // The octahedron opened along a path pole – equator – equator – pole.
        let mesh = octahedron();
        let given = vec![[4, 0], [0, 2], [2, 5]];
        let options = FlattenOptions::default().with_cut(Cut::Along(given));
        let map = flatten_and_check(&mesh, &options, false);
        let seams = map.seams.as_ref().unwrap();
        assert_eq!(seams.reason, CutReason::Given);
        assert_eq!(seams.edges, vec![[0, 2], [0, 4], [2, 5]]);
        assert!((seams.length - 3.0 * 2f64.sqrt()).abs() < 1e-12);
        seams_split_exactly(&mesh, seams);
        // 6 vertices, the two inner path vertices twice.
        assert_eq!(map.uvs.len(), 8);
        // Seams that leave a handle are refused, naming what is left.
        let t = torus(2.0, 0.5, 12, 6);
        let meridian: Vec<[u32; 2]> = (0..6).map(|j| [j, (j + 1) % 6]).collect();
        let err = super::super::flatten::flatten(
            &t,
            &FlattenOptions::default().with_cut(Cut::Along(meridian)),
        )
        .unwrap_err();
        assert!(err.to_string().contains("2 boundary loop(s)"), "{err}");
    }

    #[test]
    fn what_no_cut_fixes_is_refused_with_only_its_own_defects() {
        let mut mesh = octahedron();
        mesh.triangles[2].swap(1, 2);
        let err = plan(&mesh, &FlattenOptions::default()).unwrap_err();
        let FlattenError::NotADisc(defects) = &err else {
            panic!("{err}")
        };
        assert!(
            defects
                .iter()
                .all(|d| d.kind == DefectKind::InconsistentOrientation),
            "{err}"
        );
    }
}
