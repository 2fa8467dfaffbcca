//! The documents a run reports, as serializable data: [`InspectReport`] (a mesh's
//! counts, topology and defects) and [`FlattenReport`] (a flattening with its distortion
//! measures, solver log and its input's defects).
//!
//! They are the JSON of `surfmap inspect --json` and `surfmap flatten --report` and the
//! dictionaries of the Python package's `inspect` and `flatten`, built here once so that
//! every front end reports the same fields. Front ends differ only in how a defect's
//! remedy is worded (the library's option and function names, or the command line's
//! flags): they pass a [`DefectWording`].

use std::path::Path;

use serde::Serialize;

use crate::measure::{DistortionReport, MeasureError, MeasureOptions};
use crate::mesh::validate::{Defect, DefectKind, list_defects_worded, validate};
use crate::param::flatten::{MultilevelReport, StartMap};
use crate::{
    FlattenOptions, Flattening, Guarantee, IterationLog, Seams, StopReason, Topology, TriMesh,
};

/// How a front end words a defect: problem and remedy in one sentence. The library's own
/// wording is [`Defect::message`].
pub type DefectWording = fn(&Defect) -> String;

/// `d`'s problem followed by a front end's own `remedy` (its flag or call), or by the
/// library's remedy when the front end has none for this kind (`None`).
pub fn with_remedy(d: &Defect, remedy: Option<&str>) -> String {
    match remedy {
        Some(remedy) => format!("{} {remedy}", d.problem),
        None => d.message(),
    }
}

/// The message of [`crate::FlattenError::NotADisc`], each defect on its own line
/// worded by `wording`; a remedy already given for an earlier line is not repeated (a
/// closed surface with handles is both closed and of positive genus, and `surfmap
/// match` has one remedy for the two).
pub fn not_a_disc_message(defects: &[Defect], wording: DefectWording) -> String {
    let mut given: Vec<String> = vec![];
    let list = list_defects_worded(defects, |d| {
        let text = wording(d);
        let remedy = text.strip_prefix(d.problem.as_str()).map(str::trim);
        match remedy {
            Some(r) if !r.is_empty() && given.iter().any(|g| g == r) => {
                format!("{} (remedy as above)", d.problem)
            }
            Some(r) if !r.is_empty() => {
                given.push(r.to_string());
                text
            }
            _ => text,
        }
    });
    format!("the mesh cannot be flattened as a disc:\n{list}")
}

/// A defect as reports list it: the library's [`Defect`] with its problem and remedy
/// worded by the front end.
#[derive(Clone, Debug, Serialize)]
pub struct ReportedDefect {
    pub kind: DefectKind,
    pub count: usize,
    /// First few offending elements (vertex ids, face ids or vertex pairs, by kind).
    pub examples: Vec<Vec<u64>>,
    pub message: String,
    pub blocks_flattening: bool,
}

impl ReportedDefect {
    /// `d` with its message worded by `wording`.
    pub fn new(d: &Defect, wording: DefectWording) -> Self {
        Self {
            kind: d.kind,
            count: d.count,
            examples: d.examples.clone(),
            message: wording(d),
            blocks_flattening: d.blocks_flattening,
        }
    }

    /// Every defect of `mesh` (its topology `topo`), worded by `wording`.
    pub fn all(mesh: &TriMesh, topo: &Topology, wording: DefectWording) -> Vec<Self> {
        validate(mesh, topo)
            .iter()
            .map(|d| Self::new(d, wording))
            .collect()
    }
}

/// What a mesh is: counts, bounding box, area, topology and defects.
#[derive(Clone, Debug, Serialize)]
pub struct InspectReport {
    /// The file it was read from (`None` for a mesh given as arrays).
    pub file: Option<String>,
    /// The file's format (`None` for a mesh given as arrays).
    pub format: Option<String>,
    /// Vertex records in the file.
    pub vertices: usize,
    /// Faces as stored (a quad counts once).
    pub faces: usize,
    /// Triangles after fan triangulation.
    pub triangles: usize,
    pub edges: usize,
    pub boundary_loops: usize,
    /// Edge count of each boundary loop, longest first.
    pub boundary_loop_lengths: Vec<usize>,
    pub components: usize,
    pub euler_characteristic: i64,
    pub genus: Option<u32>,
    pub manifold: bool,
    pub orientable: bool,
    /// A disc the flattening maps as it is: one boundary loop, genus 0, manifold and
    /// consistently oriented, with usable geometry (no blocking defect).
    pub disc: bool,
    /// What [`crate::flatten`] does with the mesh by default ([`crate::plan`]): `disc
    /// as is`, `fill N holes`, `cut open along seams (why)`, or `refused` (see the
    /// defects).
    pub flatten: String,
    /// Holes `flatten` fills, and whether it cuts the surface open (default options).
    pub flatten_fills_holes: usize,
    pub flatten_cuts: bool,
    pub has_uvs: bool,
    pub bbox_min: Option<[f64; 3]>,
    pub bbox_max: Option<[f64; 3]>,
    pub area: f64,
    /// Every defect, with what repairs it.
    pub defects: Vec<ReportedDefect>,
}

/// Where an inspected mesh came from: a file (its path, format and stored face count) or
/// arrays (nothing to say: faces are the triangles).
#[derive(Clone, Copy, Debug)]
pub struct MeshSource<'a> {
    pub file: Option<&'a Path>,
    pub format: Option<crate::mesh::io::Format>,
    /// Faces as stored in the file; `None`: the triangles.
    pub stored_faces: Option<usize>,
}

impl MeshSource<'_> {
    /// A mesh given as arrays.
    pub const ARRAYS: MeshSource<'static> = MeshSource {
        file: None,
        format: None,
        stored_faces: None,
    };
}

impl<'a> MeshSource<'a> {
    /// A mesh read from `file` ([`crate::read_mesh`]).
    pub fn file(path: &'a Path, file: &crate::MeshFile) -> Self {
        Self {
            file: Some(path),
            format: Some(file.format),
            stored_faces: Some(file.stored_faces),
        }
    }
}

impl InspectReport {
    /// Inspects `mesh` (from `source`), defects worded by `wording`. Precondition: the
    /// triangles index existing vertices ([`TriMesh::check_indices`]; a mesh read from
    /// a file always does).
    pub fn new(source: MeshSource<'_>, mesh: &TriMesh, wording: DefectWording) -> Self {
        let topo = Topology::new(mesh);
        let mut loop_lengths: Vec<usize> = topo
            .boundary_loops
            .iter()
            .map(|l| l.vertices.len())
            .collect();
        loop_lengths.sort_unstable_by(|a, b| b.cmp(a));
        let bbox = mesh.bounding_box();
        let plan = crate::param::plan::plan_with_topology(mesh, &topo, &FlattenOptions::default());
        Self {
            file: source.file.map(|p| p.display().to_string()),
            format: source.format.map(|f| format!("{f:?}")),
            vertices: mesh.positions.len(),
            faces: source.stored_faces.unwrap_or(mesh.triangles.len()),
            triangles: mesh.triangles.len(),
            edges: topo.edges.len(),
            boundary_loops: topo.boundary_loops.len(),
            boundary_loop_lengths: loop_lengths,
            components: topo.num_components,
            euler_characteristic: topo.euler_characteristic(),
            genus: topo.genus(),
            manifold: topo.is_manifold(),
            orientable: topo.orientable,
            disc: plan.as_ref().is_ok_and(|p| p.is_disc_as_is()),
            flatten: plan
                .as_ref()
                .map_or_else(|_| "refused".to_string(), |p| p.describe()),
            flatten_fills_holes: plan.as_ref().map_or(0, |p| p.holes_to_fill),
            flatten_cuts: plan.as_ref().is_ok_and(|p| p.cut.is_some()),
            has_uvs: mesh.uvs.is_some(),
            bbox_min: bbox.map(|b| b.0),
            bbox_max: bbox.map(|b| b.1),
            area: mesh.area(),
            defects: ReportedDefect::all(mesh, &topo, wording),
        }
    }
}

/// A flattening as `surfmap flatten --report` writes it: the solver's result and log,
/// the distortion measures of the map, and the defects of the input.
#[derive(Clone, Debug, Serialize)]
pub struct FlattenReport<'a> {
    /// The file flattened (`None` for a mesh given as arrays).
    pub input: Option<String>,
    pub vertices: usize,
    pub triangles: usize,
    /// What was done before the solve: `disc as is`, `fill N holes`, `cut open along
    /// seams (…)`; then, if kept, `cut open to lower the distortion`
    /// ([`Flattening::describe_plan`]).
    pub plan: String,
    /// The seams when the surface was cut: why, the edges (vertex pairs), their length.
    pub seams: Option<&'a Seams>,
    /// The distortion-driven cutting ([`crate::FlattenOptions::max_distortion`]): bound,
    /// mean symmetric Dirichlet distortion before and after, rounds, seam length added.
    pub distortion_cuts: Option<&'a crate::DistortionCuts>,
    /// Cuts along protrusions made because no single chart could be embedded
    /// ([`crate::param::protrusions`]; 0 when none), their seam length, and the details.
    pub protrusion_cuts: usize,
    pub protrusion_seam_length: f64,
    pub protrusions: Option<&'a crate::ProtrusionCuts>,
    /// Initial map used: `lscm`, `mean_value`, `given` or `multilevel`.
    pub start: StartMap,
    /// The multilevel start's coarse level, re-insertion and timings (when tried).
    pub multilevel: Option<&'a MultilevelReport>,
    pub lscm_flipped_triangles: usize,
    /// ARAP warm-start steps accepted before Newton.
    pub warm_start_iterations: usize,
    pub iterations: usize,
    pub converged: bool,
    pub stop_reason: StopReason,
    /// Final energy per unit 3D area.
    pub energy: f64,
    pub continuation: &'a [[f64; 3]],
    /// Flipped triangles of the output, counted on the output (always 0).
    pub flipped_triangles: usize,
    /// `bijective` (flip-free, boundary crossing-free: injective) or
    /// `locally_injective` (flip-free only), checked on the result.
    pub guarantee: Guarantee,
    /// Whether the boundary barrier was used ([`crate::FlattenOptions::bijective`]).
    pub barrier: bool,
    /// Holes filled for the solve ([`crate::FlattenOptions::fill_holes`]).
    pub holes_filled: usize,
    /// Symmetric Dirichlet energy, area-weighted mean (isometry = 4).
    pub symmetric_dirichlet: f64,
    pub boundary_overlap: serde_json::Value,
    pub measures: DistortionReport,
    pub input_defects: Vec<ReportedDefect>,
    pub time_prepare_s: f64,
    pub time_start_s: f64,
    pub time_newton_s: f64,
    pub time_total_s: f64,
    pub log: &'a [IterationLog],
}

impl<'a> FlattenReport<'a> {
    /// The report of `r`, the flattening of `mesh` (read from `input`, if from a file):
    /// measures the map ([`crate::distortion_report`] on its corner UVs, default
    /// options) and lists the input's defects worded by `wording`.
    pub fn measure(
        input: Option<&Path>,
        mesh: &TriMesh,
        r: &'a Flattening,
        wording: DefectWording,
    ) -> Result<Self, MeasureError> {
        let measures = crate::distortion_report(
            &mesh.positions,
            &mesh.triangles,
            &r.corner_uvs(&mesh.triangles),
            &MeasureOptions::default(),
        )?;
        let defects = ReportedDefect::all(mesh, &Topology::new(mesh), wording);
        Ok(Self {
            input: input.map(|p| p.display().to_string()),
            vertices: mesh.positions.len(),
            triangles: mesh.triangles.len(),
            plan: r.describe_plan(),
            seams: r.seams.as_ref(),
            distortion_cuts: r.distortion_cuts.as_ref(),
            protrusion_cuts: r.protrusion_cuts.as_ref().map_or(0, |c| c.cuts),
            protrusion_seam_length: r.protrusion_cuts.as_ref().map_or(0.0, |c| c.seam_length),
            protrusions: r.protrusion_cuts.as_ref(),
            start: r.start,
            multilevel: r.multilevel.as_ref(),
            lscm_flipped_triangles: r.lscm_flipped,
            warm_start_iterations: r.warm_start_iterations,
            iterations: r.iterations,
            converged: r.converged,
            stop_reason: r.stop_reason,
            energy: r.energy,
            continuation: &r.continuation,
            flipped_triangles: measures.flipped_triangles,
            guarantee: r.guarantee,
            barrier: r.barrier,
            holes_filled: r.holes_filled,
            symmetric_dirichlet: measures.symmetric_dirichlet,
            boundary_overlap: serde_json::to_value(&measures.boundary_overlap).unwrap_or_default(),
            measures,
            input_defects: defects,
            time_prepare_s: r.time_prepare,
            time_start_s: r.time_start,
            time_newton_s: r.time_newton,
            time_total_s: r.time_total,
            log: &r.log,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::{FlattenOptions, flatten};

    #[test]
    fn a_remedy_is_given_once() {
        // A torus is closed and has a handle: two defects; worded with one remedy for
        // both, it is said once.
        let torus = generate::torus(2.0, 0.5, 12, 8);
        let defects: Vec<Defect> = validate(&torus, &Topology::new(&torus))
            .into_iter()
            .filter(|d| d.blocks_flattening)
            .collect();
        assert_eq!(defects.len(), 2, "{defects:?}");
        let same: DefectWording = |d| with_remedy(d, Some("Cut it open."));
        let message = not_a_disc_message(&defects, same);
        assert_eq!(message.matches("Cut it open.").count(), 1, "{message}");
        assert_eq!(
            message.matches("(remedy as above)").count(),
            defects.len() - 1,
            "{message}"
        );
        // Different remedies are all given.
        let own: DefectWording = |d| d.message();
        let message = not_a_disc_message(&defects, own);
        for d in &defects {
            assert!(message.contains(&d.message()), "{message}");
        }
    }

    /// The front ends' wording of a non-disc mesh is the library's message when they
    /// word each defect as the library does, and their remedy replaces the library's.
    #[test]
    fn not_a_disc_messages_reword_only_the_remedies() {
        let two = crate::mesh::generate::unit_square();
        let mut both = two.clone();
        both.positions
            .extend(two.positions.iter().map(|p| [p[0] + 3.0, p[1], p[2]]));
        both.triangles
            .extend(two.triangles.iter().map(|t| t.map(|i| i + 4)));
        let Err(crate::FlattenError::NotADisc(defects)) =
            flatten(&both, &FlattenOptions::default())
        else {
            panic!("two squares are not a disc");
        };
        let library = crate::FlattenError::NotADisc(defects.clone()).to_string();
        assert_eq!(not_a_disc_message(&defects, Defect::message), library);
        let worded = |d: &Defect| with_remedy(d, Some("Use --flag."));
        let message = not_a_disc_message(&defects, worded);
        assert_eq!(message.matches("Use --flag.").count(), defects.len());
        assert!(!message.contains(&defects[0].remedy));
        assert_eq!(with_remedy(&defects[0], None), defects[0].message());
    }

    /// The report repeats the flattening's own numbers and measures the map it
    /// describes: an independent measurement of the same UVs gives the same values.
    #[test]
    fn flatten_report_describes_its_flattening() {
        let mesh = generate::bumpy_disc(8, 0.3);
        let r = flatten(&mesh, &FlattenOptions::default()).unwrap();
        let report = FlattenReport::measure(None, &mesh, &r, Defect::message).unwrap();
        assert_eq!(report.input, None);
        assert_eq!(report.vertices, mesh.num_vertices());
        assert_eq!(report.triangles, mesh.num_triangles());
        assert_eq!(report.iterations, r.iterations);
        assert_eq!(report.energy, r.energy);
        assert_eq!(report.log.len(), r.log.len());
        assert_eq!(report.flipped_triangles, 0);
        assert!(report.input_defects.is_empty());
        let again = crate::distortion_report_per_vertex(
            &mesh.positions,
            &mesh.triangles,
            &r.uvs,
            &MeasureOptions::default(),
        )
        .unwrap();
        assert_eq!(report.symmetric_dirichlet, again.symmetric_dirichlet);
        assert_eq!(report.measures.measures.angle, again.measures.angle);
        let json = serde_json::to_value(&report).unwrap();
        assert_eq!(json["input"], serde_json::Value::Null);
        assert_eq!(json["boundary_overlap"]["self_intersecting"], false);
        assert_eq!(json["plan"], "disc as is");
        assert_eq!(json["seams"], serde_json::Value::Null);
        assert_eq!(json["guarantee"], "bijective");
    }

    /// A surface cut open is measured on its per-corner UVs: the same numbers as a
    /// measurement of the corners, and the seams are reported.
    #[test]
    fn flatten_report_of_a_cut_surface_measures_its_corners() {
        let mesh = generate::sphere(1);
        let r = flatten(&mesh, &FlattenOptions::default()).unwrap();
        let seams = r.seams.as_ref().expect("a sphere is cut open");
        let report = FlattenReport::measure(None, &mesh, &r, Defect::message).unwrap();
        assert_eq!(report.plan, "cut open along seams (closed, genus 0)");
        assert_eq!(report.seams.map(|s| s.edges.len()), Some(seams.edges.len()));
        assert_eq!(report.flipped_triangles, 0);
        let again = crate::distortion_report(
            &mesh.positions,
            &mesh.triangles,
            &r.corner_uvs(&mesh.triangles),
            &MeasureOptions::default(),
        )
        .unwrap();
        assert_eq!(report.symmetric_dirichlet, again.symmetric_dirichlet);
        assert!(report.symmetric_dirichlet.is_finite());
    }

    /// Counts and topology of a known surface (a square of two triangles and a closed
    /// octahedron), and defects worded by the front end's function.
    #[test]
    fn inspect_report_counts_and_words_defects() {
        let square = generate::unit_square();
        let r = InspectReport::new(MeshSource::ARRAYS, &square, Defect::message);
        assert_eq!((r.vertices, r.faces, r.triangles, r.edges), (4, 2, 2, 5));
        assert_eq!((r.boundary_loops, r.components), (1, 1));
        assert_eq!(r.boundary_loop_lengths, vec![4]);
        assert_eq!(r.euler_characteristic, 1);
        assert!(r.disc && r.manifold && r.orientable && !r.has_uvs);
        assert_eq!(r.area, 1.0);
        assert_eq!(r.bbox_max, Some([1.0, 1.0, 0.0]));
        assert!(r.defects.is_empty() && r.file.is_none() && r.format.is_none());
        assert_eq!(r.flatten, "disc as is");
        assert_eq!((r.flatten_fills_holes, r.flatten_cuts), (0, false));

        let closed = generate::octahedron();
        let r = InspectReport::new(MeshSource::ARRAYS, &closed, |d| format!("[{:?}]", d.kind));
        assert_eq!((r.vertices, r.edges, r.euler_characteristic), (6, 12, 2));
        assert_eq!(r.genus, Some(0));
        assert!(!r.disc);
        let closed_surface = r
            .defects
            .iter()
            .find(|d| d.kind == DefectKind::ClosedSurface)
            .expect("a closed surface is reported");
        assert_eq!(closed_surface.message, "[ClosedSurface]");
        assert!(closed_surface.blocks_flattening);
        // Blocking the disc map as it is, but `flatten` cuts it open.
        assert_eq!(r.flatten, "cut open along seams (closed, genus 0)");
        assert_eq!((r.flatten_fills_holes, r.flatten_cuts), (0, true));

        let handles = generate::holed_plate(2, 1);
        let r = InspectReport::new(MeshSource::ARRAYS, &handles, Defect::message);
        assert!(r.flatten.starts_with("cut open along seams") && r.flatten.contains("genus 2"));
        assert_eq!((r.flatten_fills_holes, r.flatten_cuts), (0, true));
        let mut two = generate::unit_square();
        two.positions.extend(
            generate::unit_square()
                .positions
                .iter()
                .map(|p| [p[0] + 3.0, p[1], p[2]]),
        );
        two.triangles.extend([[4, 5, 6], [4, 6, 7]]);
        let r = InspectReport::new(MeshSource::ARRAYS, &two, Defect::message);
        assert_eq!(r.flatten, "refused");
        assert_eq!((r.flatten_fills_holes, r.flatten_cuts), (0, false));
    }
}
