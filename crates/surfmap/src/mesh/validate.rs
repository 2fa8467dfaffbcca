//! Validation: finds, names and locates every defect that matters for flattening a
//! disc, and says what it means and which repair option fixes it. It is the one verdict
//! on an input: `inspect` lists [`validate`]'s defects, and the flattening refuses a mesh
//! with a blocking one ([`crate::plan`] asks [`blocks_geometry`] before anything is
//! computed), naming the same defects in the same words.
//!
//! Defects are reported, never fixed here; see [`super::repair`] for the opt-in fixes.
//! Each defect says what is wrong ([`Defect::problem`]) and what to do about it in the
//! library's terms ([`Defect::remedy`]: the `repair` function or option that fixes it);
//! the command-line tool words the same remedies as its flags.
//!
//! Vertex and face numbers are 0-based everywhere (vertex 0 is the file's first vertex
//! record; in an OBJ file, whose `f` lines count from 1, vertex `k` is the `(k + 1)`-th
//! `v` line): every list of defects says so under it ([`NUMBERING`], [`list_defects`]).

use super::{Topology, TriMesh};
use crate::vec3::{cross3, dot3, sub3};
use serde::Serialize;
use std::collections::HashMap;

/// The kinds of defect validation looks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DefectKind {
    NonFiniteCoordinates,
    /// Finite coordinates so large that edge lengths or areas overflow.
    OverflowingCoordinates,
    NoFaces,
    RepeatedIndexFaces,
    ZeroAreaFaces,
    /// Faces with the same three vertices as an earlier face (in any order).
    DuplicateFaces,
    UnreferencedVertices,
    DuplicateVertices,
    SeveralComponents,
    NonManifoldEdges,
    NonManifoldVertices,
    InconsistentOrientation,
    NonOrientable,
    ClosedSurface,
    PositiveGenus,
    SeveralBoundaryLoops,
}

/// One defect: its kind, how many elements it affects, the first few of them, what it
/// means for flattening and what to do.
#[derive(Clone, Debug, Serialize)]
pub struct Defect {
    pub kind: DefectKind,
    pub count: usize,
    /// First few offending elements (vertex ids, face ids or vertex pairs, by kind;
    /// 0-based, [`NUMBERING`]).
    pub examples: Vec<Vec<u64>>,
    /// What is wrong, where, and what it means for flattening.
    pub problem: String,
    /// What to do, in library terms (the `mesh::repair` function or the option that
    /// fixes it, or the manual fix); empty when there is nothing to say.
    pub remedy: String,
    /// Whether this defect alone prevents flattening as a disc.
    pub blocks_flattening: bool,
}

impl Defect {
    /// Problem and remedy in one sentence.
    pub fn message(&self) -> String {
        if self.remedy.is_empty() {
            self.problem.clone()
        } else {
            format!("{} {}", self.problem, self.remedy)
        }
    }
}

const EXAMPLES: usize = 5;

/// How the numbers in defect messages count, said under every list of defects
/// ([`list_defects`], `inspect`, the front ends' refusals).
pub const NUMBERING: &str = "vertex and face numbers count from 0 in file order; in an OBJ file vertex k is on the (k + 1)-th v line";

/// Defect messages as an indented list, one `  - message` line each (`message` words a
/// defect), with the [`NUMBERING`] note under it when a message cites vertices or faces.
pub fn list_defects_worded(
    defects: &[Defect],
    mut message: impl FnMut(&Defect) -> String,
) -> String {
    let mut lines: Vec<String> = defects
        .iter()
        .map(|d| format!("  - {}", message(d)))
        .collect();
    if defects.iter().any(|d| !d.examples.is_empty()) {
        lines.push(format!("  ({NUMBERING})"));
    }
    lines.join("\n")
}

/// [`list_defects_worded`] in the library's words ([`Defect::message`]).
pub fn list_defects(defects: &[Defect]) -> String {
    list_defects_worded(defects, Defect::message)
}

fn fmt_examples(ex: &[Vec<u64>]) -> String {
    ex.iter()
        .map(|e| match e.len() {
            1 => e[0].to_string(),
            _ => format!(
                "({})",
                e.iter().map(u64::to_string).collect::<Vec<_>>().join(", ")
            ),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// `1 vertex has` / `3 vertices have`: a count with its noun and verb in agreement.
fn counted(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// The quantities that decide whether a triangle can carry the elastic energy, computed
/// as the flattening's rest triangles compute them
/// ([`crate::param::element::RestTriangle::new`] uses this), so that validation and the
/// solver agree on every triangle.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TriangleShape {
    /// `p2 − p1` and `p3 − p1`.
    pub e: [f64; 3],
    pub f: [f64; 3],
    /// `|e × f|` (twice the area).
    pub normal_length: f64,
    /// The longest edge, squared.
    pub longest_edge_squared: f64,
}

impl TriangleShape {
    #[inline]
    pub(crate) fn new(p1: [f64; 3], p2: [f64; 3], p3: [f64; 3]) -> Self {
        let e = sub3(p2, p1);
        let f = sub3(p3, p1);
        let g = sub3(p3, p2);
        let n = cross3(e, f);
        Self {
            e,
            f,
            normal_length: dot3(n, n).sqrt(),
            longest_edge_squared: dot3(e, e).max(dot3(f, f)).max(dot3(g, g)),
        }
    }

    /// The length or the area is not a finite number: non-finite corners, or finite ones
    /// so large that squares overflow (beyond about 1e77 in size).
    #[inline]
    pub(crate) fn overflows(&self) -> bool {
        !(self.normal_length.is_finite() && self.longest_edge_squared.is_finite())
    }

    /// The area is at rounding level, `|e × f| ≤ ε · ℓ²_max` (zero included): the
    /// corners are collinear or coincident.
    #[inline]
    pub(crate) fn is_flat(&self) -> bool {
        self.normal_length <= f64::EPSILON * self.longest_edge_squared
    }
}

/// Triangles that use the same vertex twice.
pub fn repeated_index_faces(mesh: &TriMesh) -> Vec<u32> {
    (0..mesh.triangles.len() as u32)
        .filter(|&t| {
            let [a, b, c] = mesh.triangles[t as usize];
            a == b || b == c || a == c
        })
        .collect()
}

/// Whether every coordinate of vertex `v` is finite.
fn finite(mesh: &TriMesh, v: u32) -> bool {
    mesh.positions[v as usize].iter().all(|x| x.is_finite())
}

/// The shape of triangle `t` when its vertices are distinct and finite (else `None`:
/// another defect names it).
fn proper_shape(mesh: &TriMesh, t: usize) -> Option<TriangleShape> {
    let [a, b, c] = mesh.triangles[t];
    if a == b || b == c || a == c || ![a, b, c].iter().all(|&v| finite(mesh, v)) {
        return None;
    }
    let p = mesh.triangle_positions(t);
    Some(TriangleShape::new(p[0], p[1], p[2]))
}

/// Triangles with distinct, finite corners whose area is zero to rounding
/// ([`TriangleShape::is_flat`]: the corners are collinear or coincident); the
/// flattening cannot use them.
pub fn zero_area_faces(mesh: &TriMesh) -> Vec<u32> {
    (0..mesh.triangles.len())
        .filter(|&t| proper_shape(mesh, t).is_some_and(|s| !s.overflows() && s.is_flat()))
        .map(|t| t as u32)
        .collect()
}

/// Triangles with distinct, finite corners whose edge lengths or area overflow
/// ([`TriangleShape::overflows`]: coordinates of more than about 1e77).
pub fn overflowing_faces(mesh: &TriMesh) -> Vec<u32> {
    (0..mesh.triangles.len())
        .filter(|&t| proper_shape(mesh, t).is_some_and(|s| s.overflows()))
        .map(|t| t as u32)
        .collect()
}

/// Faces with the same three vertices as an earlier face, in any order or orientation,
/// with that earlier face: `(repeat, first)`.
pub fn duplicate_faces(mesh: &TriMesh) -> Vec<(u32, u32)> {
    let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(mesh.triangles.len());
    let mut out = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let mut key = *tri;
        key.sort_unstable();
        match first.entry(key) {
            std::collections::hash_map::Entry::Occupied(e) => out.push((t as u32, *e.get())),
            std::collections::hash_map::Entry::Vacant(e) => {
                e.insert(t as u32);
            }
        }
    }
    out
}

/// [`duplicate_faces`], searched only where a repeat can hide: a repeated face makes each
/// of its edges either non-manifold, inconsistently oriented (same orientation) or,
/// reversed, the two copies a closed component of their own. So a mesh of more than two
/// faces that is one consistently oriented manifold component has none, and is not
/// searched (the check costs nothing on a clean mesh).
fn duplicate_faces_given(mesh: &TriMesh, topo: &Topology) -> Vec<(u32, u32)> {
    let clean = mesh.triangles.len() > 2
        && topo.num_components == 1
        && topo.non_manifold_edges.is_empty()
        && topo.inconsistent_edges.is_empty();
    if clean {
        Vec::new()
    } else {
        duplicate_faces(mesh)
    }
}

/// Vertices whose position equals (bit for bit) that of an earlier vertex, with the
/// earlier vertex: `(duplicate, first)`.
pub fn duplicate_vertices(mesh: &TriMesh) -> Vec<(u32, u32)> {
    let mut first: HashMap<[u64; 3], u32> = HashMap::with_capacity(mesh.positions.len());
    let mut out = Vec::new();
    for (i, p) in mesh.positions.iter().enumerate() {
        // +0.0 and −0.0 are the same point.
        let key = p.map(|x| if x == 0.0 { 0 } else { x.to_bits() });
        match first.entry(key) {
            std::collections::hash_map::Entry::Occupied(e) => out.push((i as u32, *e.get())),
            std::collections::hash_map::Entry::Vacant(e) => {
                e.insert(i as u32);
            }
        }
    }
    out
}

/// Vertices referenced by no triangle.
pub fn unreferenced_vertices(mesh: &TriMesh) -> Vec<u32> {
    let used = used_vertices(mesh);
    (0..used.len() as u32)
        .filter(|&v| !used[v as usize])
        .collect()
}

fn used_vertices(mesh: &TriMesh) -> Vec<bool> {
    let mut used = vec![false; mesh.positions.len()];
    for tri in &mesh.triangles {
        for &v in tri {
            used[v as usize] = true;
        }
    }
    used
}

/// Collects defects: a kind with a count of 0 is no defect and is left out.
struct Defects(Vec<Defect>);

impl Defects {
    fn push(
        &mut self,
        kind: DefectKind,
        count: usize,
        examples: Vec<Vec<u64>>,
        problem: String,
        remedy: &str,
        blocks_flattening: bool,
    ) {
        if count > 0 {
            self.0.push(Defect {
                kind,
                count,
                examples,
                problem,
                remedy: remedy.to_owned(),
                blocks_flattening,
            });
        }
    }
}

/// The first few of `ids` as examples.
fn one(ids: &[u32]) -> Vec<Vec<u64>> {
    ids.iter().take(EXAMPLES).map(|&x| vec![x as u64]).collect()
}

/// The first few of `pairs` as examples.
fn pairs(pairs: &[(u32, u32)]) -> Vec<Vec<u64>> {
    pairs
        .iter()
        .take(EXAMPLES)
        .map(|&(a, b)| vec![a as u64, b as u64])
        .collect()
}

/// Vertices with a NaN or infinite coordinate: blocking when a face uses one (no
/// geometry can be computed there), harmless otherwise (such a vertex gets no UV).
fn non_finite_coordinates(mesh: &TriMesh, out: &mut Defects) {
    let non_finite: Vec<u32> = (0..mesh.positions.len() as u32)
        .filter(|&v| !finite(mesh, v))
        .collect();
    if non_finite.is_empty() {
        return;
    }
    let used = used_vertices(mesh);
    let (used, unused): (Vec<u32>, Vec<u32>) =
        non_finite.into_iter().partition(|&v| used[v as usize]);
    let ex = one(&used);
    out.push(
        DefectKind::NonFiniteCoordinates,
        used.len(),
        ex.clone(),
        format!(
            "{} NaN or infinite coordinates (first: {}) and {} used by faces; no geometry can \
             be computed there.",
            counted(used.len(), "vertex has", "vertices have"),
            fmt_examples(&ex),
            if used.len() == 1 { "is" } else { "are" },
        ),
        "Fix the exporter, or remove the faces that use them.",
        true,
    );
    if used.is_empty() {
        let ex = one(&unused);
        out.push(
            DefectKind::NonFiniteCoordinates,
            unused.len(),
            ex.clone(),
            format!(
                "{} NaN or infinite coordinates (first: {}) but no face uses {}; {} no UV.",
                counted(unused.len(), "vertex has", "vertices have"),
                fmt_examples(&ex),
                if unused.len() == 1 { "it" } else { "them" },
                if unused.len() == 1 {
                    "it gets"
                } else {
                    "they get"
                },
            ),
            "Remove them with `repair::drop_unreferenced`.",
            false,
        );
    }
}

/// Faces whose lengths or area overflow, and a total area that overflows.
fn overflowing_coordinates(mesh: &TriMesh, out: &mut Defects) {
    let faces = overflowing_faces(mesh);
    let largest = mesh
        .positions
        .iter()
        .flatten()
        .filter(|x| x.is_finite())
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let remedy = "Scale the mesh down (export it in a larger unit, e.g. metres instead of \
                  micrometres); the flattening's UVs come out in the same unit.";
    if !faces.is_empty() {
        let ex = one(&faces);
        out.push(
            DefectKind::OverflowingCoordinates,
            faces.len(),
            ex.clone(),
            format!(
                "{} edge lengths or areas that overflow to infinity (first faces: {}): \
                 coordinates up to {largest:e} are too large to compute with in floating point.",
                counted(faces.len(), "face has", "faces have"),
                fmt_examples(&ex)
            ),
            remedy,
            true,
        );
        return;
    }
    // Each face measurable, their sum not: the unit-area scaling fails.
    let total: f64 = (0..mesh.triangles.len())
        .filter_map(|t| proper_shape(mesh, t))
        .map(|s| 0.5 * s.normal_length)
        .sum();
    if !total.is_finite() && mesh.positions.iter().flatten().all(|x| x.is_finite()) {
        out.push(
            DefectKind::OverflowingCoordinates,
            1,
            vec![],
            format!(
                "the total area overflows to infinity: coordinates up to {largest:e} are too \
                 large to compute with in floating point."
            ),
            remedy,
            true,
        );
    }
}

/// Faces with a repeated vertex, zero area, or repeating another face; returns the
/// repeats (`(repeat, first)`).
fn degenerate_faces(mesh: &TriMesh, topo: &Topology, out: &mut Defects) -> Vec<(u32, u32)> {
    let repeated = repeated_index_faces(mesh);
    let ex = one(&repeated);
    out.push(
        DefectKind::RepeatedIndexFaces,
        repeated.len(),
        ex.clone(),
        format!(
            "{} the same vertex twice (first faces: {}); {} no area and no Jacobian.",
            counted(repeated.len(), "face uses", "faces use"),
            fmt_examples(&ex),
            if repeated.len() == 1 {
                "it has"
            } else {
                "they have"
            },
        ),
        "Remove them with `repair::drop_degenerate`.",
        true,
    );
    let zero = zero_area_faces(mesh);
    let ex = one(&zero);
    out.push(
        DefectKind::ZeroAreaFaces,
        zero.len(),
        ex.clone(),
        format!(
            "{} zero area (collinear corners; first faces: {}); the elastic energy is \
             undefined on them.",
            counted(zero.len(), "face has", "faces have"),
            fmt_examples(&ex)
        ),
        "Remove them with `repair::drop_degenerate` (this may open holes), or fix them in a mesh editor.",
        true,
    );
    let repeats = duplicate_faces_given(mesh, topo);
    let ex = pairs(&repeats);
    out.push(
        DefectKind::DuplicateFaces,
        repeats.len(),
        ex.clone(),
        format!(
            "{} an earlier face with the same three vertices (repeat and first: {}); each \
             repeat lies on its original, which makes the edges around it look non-manifold or \
             inconsistently oriented.",
            counted(repeats.len(), "face repeats", "faces repeat"),
            fmt_examples(&ex)
        ),
        "Remove the repeats with `repair::drop_degenerate`.",
        true,
    );
    repeats
}

/// The geometric defects that stop every flattening, whatever the options: coordinates
/// that are not finite (on a face) or overflow, and faces with a repeated vertex, zero
/// area or repeating another face. Empty for a usable mesh; `O(V + F)` (the search for
/// repeated faces only runs where the topology shows one could hide).
pub fn blocking_geometry(mesh: &TriMesh, topo: &Topology) -> Vec<Defect> {
    let mut out = Defects(Vec::new());
    non_finite_coordinates(mesh, &mut out);
    overflowing_coordinates(mesh, &mut out);
    degenerate_faces(mesh, topo, &mut out);
    out.0.retain(|d| d.blocks_flattening);
    out.0
}

/// Whether the geometry stops every flattening ([`blocking_geometry`] is not empty).
pub fn blocks_geometry(mesh: &TriMesh, topo: &Topology) -> bool {
    !blocking_geometry(mesh, topo).is_empty()
}

/// Finds every defect of `mesh` (with its topology `topo`). Where faces repeat, the
/// defects of the surface itself (components, manifoldness, orientation, boundary,
/// genus) are those of the mesh without the repeats: the repeats are named on their own.
pub fn validate(mesh: &TriMesh, topo: &Topology) -> Vec<Defect> {
    let mut out = Defects(Vec::new());
    non_finite_coordinates(mesh, &mut out);
    if mesh.triangles.is_empty() {
        let problem = if mesh.positions.is_empty() {
            "the mesh has no faces and no vertices: the file holds no mesh (is it another \
             format, or an export that failed?)"
        } else {
            "the mesh has no faces: there is nothing to flatten (is it a point cloud?)"
        };
        out.push(DefectKind::NoFaces, 1, vec![], problem.into(), "", true);
        return out.0;
    }
    overflowing_coordinates(mesh, &mut out);
    let repeats = degenerate_faces(mesh, topo, &mut out);
    let without_repeats;
    let topo = if repeats.is_empty() {
        topo
    } else {
        let mut repeat = vec![false; mesh.triangles.len()];
        for &(t, _) in &repeats {
            repeat[t as usize] = true;
        }
        let kept = (0..mesh.triangles.len()).filter(|&t| !repeat[t]);
        without_repeats = TriMesh::new(
            mesh.positions.clone(),
            kept.map(|t| mesh.triangles[t]).collect(),
        );
        &Topology::new(&without_repeats)
    };

    let unref = unreferenced_vertices(mesh);
    let ex = one(&unref);
    out.push(
        DefectKind::UnreferencedVertices,
        unref.len(),
        ex.clone(),
        format!(
            "{} by no face (first: {}); {} harmless but {} no UV.",
            counted(unref.len(), "vertex is used", "vertices are used"),
            fmt_examples(&ex),
            if unref.len() == 1 {
                "it is"
            } else {
                "they are"
            },
            if unref.len() == 1 { "gets" } else { "get" },
        ),
        "Remove them with `repair::drop_unreferenced`.",
        false,
    );
    let dups = duplicate_vertices(mesh);
    let ex = pairs(&dups);
    out.push(
        DefectKind::DuplicateVertices,
        dups.len(),
        ex.clone(),
        format!(
            "{} exactly on another vertex (pairs: {}); the surface is probably cut there \
             (seams or cracks), which adds boundary loops or components.",
            counted(dups.len(), "vertex sits", "vertices sit"),
            fmt_examples(&ex)
        ),
        "Merge coincident vertices with `repair::weld`.",
        false,
    );
    surface_defects(topo, &mut out);
    out.0
}

/// The defects of the surface's topology: components, manifoldness, orientation,
/// closedness, genus, boundary loops.
fn surface_defects(topo: &Topology, out: &mut Defects) {
    several_components(topo, out);
    non_manifold(topo, out);
    orientation(topo, out);
    not_a_disc_shape(topo, out);
}

/// More than one connected component, the largest listed first.
fn several_components(topo: &Topology, out: &mut Defects) {
    if topo.num_components > 1 {
        let mut sizes = vec![0usize; topo.num_components];
        for &c in &topo.face_component {
            sizes[c as usize] += 1;
        }
        let mut order: Vec<usize> = (0..sizes.len()).collect();
        order.sort_by_key(|&c| std::cmp::Reverse(sizes[c]));
        let listed: Vec<String> = order
            .iter()
            .take(EXAMPLES)
            .map(|&c| format!("#{c}: {} faces", sizes[c]))
            .collect();
        out.push(
            DefectKind::SeveralComponents,
            topo.num_components,
            order
                .iter()
                .take(EXAMPLES)
                .map(|&c| vec![c as u64, sizes[c] as u64])
                .collect(),
            format!(
                "the mesh has {} connected components ({}{}); a flattening maps one piece.",
                topo.num_components,
                listed.join(", "),
                if topo.num_components > EXAMPLES {
                    ", …"
                } else {
                    ""
                }
            ),
            "Keep one with `repair::keep_component` (the largest, or one by number).",
            true,
        );
    }
}

/// Edges with more than two faces and vertices joining separate fans.
fn non_manifold(topo: &Topology, out: &mut Defects) {
    let ex: Vec<Vec<u64>> = topo
        .non_manifold_edges
        .iter()
        .take(EXAMPLES)
        .map(|&e| topo.edges[e as usize].iter().map(|&v| v as u64).collect())
        .collect();
    out.push(
        DefectKind::NonManifoldEdges,
        topo.non_manifold_edges.len(),
        ex.clone(),
        format!(
            "{} shared by more than two faces (vertex pairs: {}); such a surface cannot be \
             flattened without cutting.",
            counted(topo.non_manifold_edges.len(), "edge is", "edges are"),
            fmt_examples(&ex)
        ),
        "`repair::fix_non_manifold` cuts them apart into sheets (the faces that continue each \
         other most smoothly stay joined; fins and glued-on sheets come loose); then \
         `repair::keep_component` removes the loose pieces.",
        true,
    );
    let ex = one(&topo.non_manifold_vertices);
    out.push(
        DefectKind::NonManifoldVertices,
        topo.non_manifold_vertices.len(),
        ex.clone(),
        format!(
            "{} two or more otherwise separate fans of faces (first: {}); the surface pinches \
             there, so it is not a disc.",
            counted(
                topo.non_manifold_vertices.len(),
                "vertex joins",
                "vertices join"
            ),
            fmt_examples(&ex)
        ),
        "`repair::fix_non_manifold` splits each into one copy per fan.",
        true,
    );
}

/// A surface that is not orientable, or faces oriented inconsistently.
fn orientation(topo: &Topology, out: &mut Defects) {
    if !topo.orientable {
        out.push(
            DefectKind::NonOrientable,
            1,
            vec![],
            "the surface is not orientable (like a Möbius strip): no consistent front side exists, so it cannot \
             be flattened without flipping triangles."
                .into(),
            "Cut it into orientable pieces first.",
            true,
        );
    } else if !topo.inconsistent_edges.is_empty() {
        let ex: Vec<Vec<u64>> = topo
            .inconsistent_edges
            .iter()
            .take(EXAMPLES)
            .map(|&e| topo.edges[e as usize].iter().map(|&v| v as u64).collect())
            .collect();
        out.push(
            DefectKind::InconsistentOrientation,
            topo.inconsistent_edges.len(),
            ex.clone(),
            format!(
                "{} traversed in the same direction by both of their faces (vertex pairs: {}); \
                 {} flipped for a consistent orientation.",
                counted(topo.inconsistent_edges.len(), "edge is", "edges are"),
                fmt_examples(&ex),
                counted(
                    topo.faces_to_flip.unwrap_or(0),
                    "face must be",
                    "faces must be"
                )
            ),
            "Flip them with `repair::reorient`.",
            true,
        );
    }
}

/// A clean surface that is not a disc: closed, with handles, or with several boundary
/// loops.
fn not_a_disc_shape(topo: &Topology, out: &mut Defects) {
    let loops = topo.boundary_loops.len();
    if topo.num_components == 1 && topo.is_manifold() && topo.orientable {
        if loops == 0 {
            out.push(
                DefectKind::ClosedSurface,
                1,
                vec![],
                format!(
                    "the surface is closed (no boundary, genus {}); a disc map needs exactly one boundary loop.",
                    topo.genus().map_or("?".into(), |g| g.to_string())
                ),
                "`flatten` cuts it open along seams by default (`FlattenOptions::cut`, `mesh::cut`).",
                true,
            );
        }
        if let Some(g) = topo.genus().filter(|&g| g > 0) {
            out.push(
                DefectKind::PositiveGenus,
                g as usize,
                vec![],
                format!("the surface has genus {g} (handles); a disc has genus 0."),
                "`flatten` cuts every handle open along seams by default (`FlattenOptions::cut`, `mesh::cut`).",
                true,
            );
        }
    }
    if loops > 1 {
        let mut lens: Vec<(usize, usize)> = topo
            .boundary_loops
            .iter()
            .enumerate()
            .map(|(i, l)| (l.vertices.len(), i))
            .collect();
        lens.sort_by_key(|&(n, _)| std::cmp::Reverse(n));
        out.push(
            DefectKind::SeveralBoundaryLoops,
            loops,
            lens.iter()
                .take(EXAMPLES)
                .map(|&(n, i)| vec![i as u64, n as u64])
                .collect(),
            format!(
                "found {loops} boundary loops (edge counts: {}{}); a disc has exactly one. The others are holes \
                 (eyes, mouth, scan gaps):",
                lens.iter()
                    .take(EXAMPLES)
                    .map(|(n, _)| n.to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                if loops > EXAMPLES { ", …" } else { "" }
            ),
            "`flatten` fills all but the longest for the solve by default (`FlattenOptions::fill_holes`, \
             `repair::fill_holes`; they stay open in the map), or, with that off, joins them to the outer \
             boundary by seams (`Cut::Auto`).",
            true,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(m: &TriMesh) -> Vec<DefectKind> {
        validate(m, &Topology::new(m))
            .iter()
            .map(|d| d.kind)
            .collect()
    }

    use crate::mesh::generate::unit_square as square;

    #[test]
    fn clean_disc_has_no_defect() {
        assert!(kinds(&square()).is_empty());
    }

    #[test]
    fn each_defect_is_named() {
        let mut m = square();
        m.positions.push([0.5, 0.5, f64::NAN]);
        assert!(kinds(&m).contains(&DefectKind::NonFiniteCoordinates));
        assert!(kinds(&m).contains(&DefectKind::UnreferencedVertices));

        let mut m = square();
        m.triangles.push([0, 0, 1]);
        assert!(kinds(&m).contains(&DefectKind::RepeatedIndexFaces));

        let mut m = square();
        m.positions.push([2.0, 0.0, 0.0]);
        m.triangles.push([1, 4, 2]); // fine
        m.positions.push([3.0, 0.0, 0.0]);
        m.triangles.push([1, 5, 4]); // collinear: 1, 4, 5 on the x axis
        assert!(kinds(&m).contains(&DefectKind::ZeroAreaFaces));

        let mut m = square();
        m.positions.push([1.0, 0.0, 0.0]);
        let k = kinds(&m);
        assert!(k.contains(&DefectKind::DuplicateVertices));

        let mut m = square();
        m.triangles[1] = [0, 3, 2];
        assert!(kinds(&m).contains(&DefectKind::InconsistentOrientation));

        let mut m = square();
        m.positions
            .extend([[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]]);
        m.triangles.push([4, 5, 6]);
        let k = kinds(&m);
        assert!(k.contains(&DefectKind::SeveralComponents));
    }

    #[test]
    fn messages_say_what_to_do() {
        let mut m = square();
        m.positions
            .extend([[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]]);
        m.triangles.push([4, 5, 6]);
        let d = validate(&m, &Topology::new(&m));
        let comp = d
            .iter()
            .find(|d| d.kind == DefectKind::SeveralComponents)
            .unwrap();
        assert!(comp.remedy.contains("keep_component"), "{}", comp.remedy);
        assert!(
            comp.message().contains("2 connected components"),
            "{}",
            comp.message()
        );
        // Every remedy names the repair in library terms, never a command-line flag.
        let mut m = square();
        m.positions.push([1.0, 0.0, 0.0]);
        m.positions.push([0.5, 0.5, f64::NAN]);
        m.triangles.push([0, 0, 1]);
        m.triangles[1] = [0, 3, 2];
        for d in validate(&m, &Topology::new(&m)) {
            assert!(!d.message().contains("--"), "{}", d.message());
        }
    }

    fn blocking(m: &TriMesh) -> Vec<DefectKind> {
        blocking_geometry(m, &Topology::new(m))
            .iter()
            .map(|d| d.kind)
            .collect()
    }

    /// A NaN coordinate blocks where a face uses it and is harmless where none does;
    /// [`TriMesh::finite_and_proper`] (the disc's check) draws the same line.
    #[test]
    fn non_finite_coordinates_block_only_on_a_face() {
        let mut used = crate::mesh::generate::grid_disc(3);
        used.positions[5][2] = f64::NAN;
        assert_eq!(blocking(&used), [DefectKind::NonFiniteCoordinates]);
        assert!(!used.finite_and_proper());
        let d = &validate(&used, &Topology::new(&used))[0];
        assert!(
            d.blocks_flattening && d.problem.contains("(first: 5)"),
            "{d:?}"
        );
        let mut unused = crate::mesh::generate::grid_disc(3);
        unused.positions.push([f64::INFINITY, 0.0, 0.0]);
        assert!(blocking(&unused).is_empty());
        assert!(unused.finite_and_proper());
        let d = &validate(&unused, &Topology::new(&unused))[0];
        assert_eq!(d.kind, DefectKind::NonFiniteCoordinates);
        assert!(
            !d.blocks_flattening && d.problem.contains("no face uses it"),
            "{d:?}"
        );
    }

    /// Coordinates of 1e300: finite, but every length and area overflows; named as such
    /// (not as zero area), on every face.
    #[test]
    fn overflowing_coordinates_are_named() {
        let mesh = crate::mesh::generate::grid_disc(3);
        let scaled = |k: f64| TriMesh {
            positions: mesh.positions.iter().map(|p| p.map(|x| x * k)).collect(),
            ..mesh.clone()
        };
        let huge = scaled(1e300);
        assert_eq!(blocking(&huge), [DefectKind::OverflowingCoordinates]);
        let d = &blocking_geometry(&huge, &Topology::new(&huge))[0];
        assert_eq!(d.count, huge.triangles.len());
        assert!(d.problem.contains("1e300"), "{}", d.problem);
        assert!(huge.area().is_nan() || huge.area().is_infinite());
        // The area vector's squared length overflows beyond about 1e77: 1e100 is too
        // large as well, 1e70 is not.
        assert_eq!(
            blocking(&scaled(1e100)),
            [DefectKind::OverflowingCoordinates]
        );
        assert!(blocking(&scaled(1e70)).is_empty());
        assert!(scaled(1e70).area().is_finite());
    }

    /// Validation and the solver's rest triangles refuse the same triangles: flat ones
    /// (down to rounding, at any scale) and overflowing ones, and accept the same
    /// slivers.
    #[test]
    fn zero_area_is_what_the_solver_cannot_use() {
        use crate::param::element::RestTriangle;
        let cases: Vec<[[f64; 3]; 3]> = vec![
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1e-17, 0.0]],
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1e-14, 0.0]],
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1e-9, 0.0]],
            [[0.0, 0.0, 0.0], [1e-160, 0.0, 0.0], [0.0, 1e-160, 0.0]],
            [[0.0, 0.0, 0.0], [1e200, 0.0, 0.0], [0.0, 1e200, 0.0]],
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        ];
        for p in cases {
            let m = TriMesh::new(p.to_vec(), vec![[0, 1, 2]]);
            let named = !zero_area_faces(&m).is_empty() || !overflowing_faces(&m).is_empty();
            let refused = RestTriangle::new(p[0], p[1], p[2]).is_none();
            assert_eq!(named, refused, "{p:?}");
        }
    }

    /// A repeated face is named as a repeat, in either orientation, and the surface's
    /// own defects are those of the mesh without it (no non-manifold edge, no
    /// orientation problem, no extra component); [`duplicate_faces`] finds what the
    /// topology-guided search finds.
    #[test]
    fn repeated_faces_are_named_as_repeats() {
        let disc = crate::mesh::generate::grid_disc(4);
        for (t, reversed) in [(0, false), (0, true), (13, false), (13, true)] {
            let mut m = disc.clone();
            let mut repeat = m.triangles[t];
            if reversed {
                repeat.swap(1, 2);
            }
            m.triangles.push(repeat);
            let topo = Topology::new(&m);
            assert_eq!(kinds(&m), [DefectKind::DuplicateFaces], "{t} {reversed}");
            assert_eq!(duplicate_faces_given(&m, &topo), duplicate_faces(&m));
            assert_eq!(
                duplicate_faces(&m),
                [(m.triangles.len() as u32 - 1, t as u32)]
            );
            // Removed by the repair the message names.
            let (fixed, removed) = crate::mesh::repair::drop_degenerate(&m);
            assert_eq!((removed, &fixed.triangles), (1, &disc.triangles));
        }
        // A clean mesh is not searched, and has none.
        let topo = Topology::new(&disc);
        assert!(duplicate_faces_given(&disc, &topo).is_empty());
        assert!(duplicate_faces(&disc).is_empty());
        // Two faces on each other alone (a closed "pillow" of two faces) are found too.
        let pillow = TriMesh::new(disc.positions.clone(), vec![[0, 1, 6], [0, 6, 1]]);
        assert!(kinds(&pillow).contains(&DefectKind::DuplicateFaces));
    }

    /// A list of defects says how its numbers count; one without numbers does not.
    #[test]
    fn defect_lists_say_numbers_count_from_zero() {
        let mut m = square();
        m.triangles.push([0, 0, 1]);
        let listed = list_defects(&validate(&m, &Topology::new(&m)));
        assert!(listed.ends_with(&format!("({NUMBERING})")), "{listed}");
        let empty = TriMesh::new(vec![], vec![]);
        let listed = list_defects(&validate(&empty, &Topology::new(&empty)));
        assert!(
            !listed.contains(NUMBERING) && listed.contains("no vertices"),
            "{listed}"
        );
    }
}
