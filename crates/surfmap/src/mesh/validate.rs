//! Validation: finds, names and locates every defect that matters for flattening a
//! disc, and says what it means and which repair option fixes it.
//!
//! Defects are reported, never fixed here; see [`super::repair`] for the opt-in fixes.
//! Each defect says what is wrong ([`Defect::problem`]) and what to do about it in the
//! library's terms ([`Defect::remedy`]: the `repair` function or option that fixes it);
//! the command-line tool words the same remedies as its flags.

use super::{Topology, TriMesh};
use serde::Serialize;
use std::collections::HashMap;

/// The kinds of defect validation looks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DefectKind {
    NonFiniteCoordinates,
    NoFaces,
    RepeatedIndexFaces,
    ZeroAreaFaces,
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
    /// First few offending elements (vertex ids, face ids or vertex pairs, by kind).
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

/// Triangles that use the same vertex twice.
pub fn repeated_index_faces(mesh: &TriMesh) -> Vec<u32> {
    (0..mesh.triangles.len() as u32)
        .filter(|&t| {
            let [a, b, c] = mesh.triangles[t as usize];
            a == b || b == c || a == c
        })
        .collect()
}

/// Triangles with distinct indices whose area is zero to rounding:
/// `area ≤ 1e-12 · (longest edge)²` (the corners are collinear or coincident).
pub fn zero_area_faces(mesh: &TriMesh) -> Vec<u32> {
    (0..mesh.triangles.len() as u32)
        .filter(|&t| {
            let [a, b, c] = mesh.triangles[t as usize];
            if a == b || b == c || a == c {
                return false;
            }
            let p = mesh.triangle_positions(t as usize);
            let d2 = |x: [f64; 3], y: [f64; 3]| (0..3).map(|k| (x[k] - y[k]).powi(2)).sum::<f64>();
            let longest = d2(p[0], p[1]).max(d2(p[1], p[2])).max(d2(p[2], p[0]));
            let area = mesh.triangle_area(t as usize);
            area.is_finite() && area <= 1e-12 * longest
        })
        .collect()
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
    let mut used = vec![false; mesh.positions.len()];
    for tri in &mesh.triangles {
        for &v in tri {
            used[v as usize] = true;
        }
    }
    (0..used.len() as u32)
        .filter(|&v| !used[v as usize])
        .collect()
}

/// Finds every defect of `mesh` (with its topology `topo`).
pub fn validate(mesh: &TriMesh, topo: &Topology) -> Vec<Defect> {
    let mut out = Vec::new();
    let mut push =
        |kind, count: usize, examples: Vec<Vec<u64>>, problem: String, remedy: &str, blocks| {
            if count > 0 {
                out.push(Defect {
                    kind,
                    count,
                    examples,
                    problem,
                    remedy: remedy.to_owned(),
                    blocks_flattening: blocks,
                });
            }
        };
    let one = |v: &[u32]| {
        v.iter()
            .take(EXAMPLES)
            .map(|&x| vec![x as u64])
            .collect::<Vec<_>>()
    };

    let non_finite: Vec<u32> = (0..mesh.positions.len() as u32)
        .filter(|&v| mesh.positions[v as usize].iter().any(|x| !x.is_finite()))
        .collect();
    let ex = one(&non_finite);
    push(
        DefectKind::NonFiniteCoordinates,
        non_finite.len(),
        ex.clone(),
        format!(
            "{} vertices have NaN or infinite coordinates (first: {}); no geometry can be computed from them.",
            non_finite.len(),
            fmt_examples(&ex)
        ),
        "Fix the exporter, or drop them with `repair::drop_unreferenced` if no face uses them.",
        true,
    );
    if mesh.triangles.is_empty() {
        push(
            DefectKind::NoFaces,
            1,
            vec![],
            "the mesh has no faces: there is nothing to flatten (is it a point cloud?)".into(),
            "",
            true,
        );
        return out;
    }

    let repeated = repeated_index_faces(mesh);
    let ex = one(&repeated);
    push(
        DefectKind::RepeatedIndexFaces,
        repeated.len(),
        ex.clone(),
        format!(
            "{} faces use the same vertex twice (first faces: {}); they have no area and no Jacobian.",
            repeated.len(),
            fmt_examples(&ex)
        ),
        "Remove them with `repair::drop_degenerate`.",
        true,
    );
    let zero = zero_area_faces(mesh);
    let ex = one(&zero);
    push(
        DefectKind::ZeroAreaFaces,
        zero.len(),
        ex.clone(),
        format!(
            "{} faces have zero area (collinear corners; first faces: {}); the elastic energy is undefined on them.",
            zero.len(),
            fmt_examples(&ex)
        ),
        "Remove them with `repair::drop_degenerate` (this may open holes), or fix them in a mesh editor.",
        true,
    );

    let unref = unreferenced_vertices(mesh);
    let ex = one(&unref);
    push(
        DefectKind::UnreferencedVertices,
        unref.len(),
        ex.clone(),
        format!(
            "{} vertices are used by no face (first: {}); they are harmless but get no UV.",
            unref.len(),
            fmt_examples(&ex)
        ),
        "Remove them with `repair::drop_unreferenced`.",
        false,
    );
    let dups = duplicate_vertices(mesh);
    let ex: Vec<Vec<u64>> = dups
        .iter()
        .take(EXAMPLES)
        .map(|&(a, b)| vec![a as u64, b as u64])
        .collect();
    push(
        DefectKind::DuplicateVertices,
        dups.len(),
        ex.clone(),
        format!(
            "{} vertices sit exactly on another vertex (pairs: {}); the surface is probably cut there \
             (seams or cracks), which adds boundary loops or components.",
            dups.len(),
            fmt_examples(&ex)
        ),
        "Merge coincident vertices with `repair::weld`.",
        false,
    );

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
        push(
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
    let ex: Vec<Vec<u64>> = topo
        .non_manifold_edges
        .iter()
        .take(EXAMPLES)
        .map(|&e| topo.edges[e as usize].iter().map(|&v| v as u64).collect())
        .collect();
    push(
        DefectKind::NonManifoldEdges,
        topo.non_manifold_edges.len(),
        ex.clone(),
        format!(
            "{} edges are shared by more than two faces (vertex pairs: {}); such a surface cannot be flattened \
             without cutting.",
            topo.non_manifold_edges.len(),
            fmt_examples(&ex)
        ),
        "`repair::fix_non_manifold` cuts them apart into sheets (the faces that continue each \
         other most smoothly stay joined; fins and glued-on sheets come loose); then \
         `repair::keep_component` removes the loose pieces.",
        true,
    );
    let ex = one(&topo.non_manifold_vertices);
    push(
        DefectKind::NonManifoldVertices,
        topo.non_manifold_vertices.len(),
        ex.clone(),
        format!(
            "{} vertices join two or more otherwise separate fans of faces (first: {}); the surface pinches \
             there, so it is not a disc.",
            topo.non_manifold_vertices.len(),
            fmt_examples(&ex)
        ),
        "`repair::fix_non_manifold` splits each into one copy per fan.",
        true,
    );
    if !topo.orientable {
        push(
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
        push(
            DefectKind::InconsistentOrientation,
            topo.inconsistent_edges.len(),
            ex.clone(),
            format!(
                "{} edges are traversed in the same direction by both of their faces (vertex pairs: {}); \
                 {} faces must be flipped for a consistent orientation.",
                topo.inconsistent_edges.len(),
                fmt_examples(&ex),
                topo.faces_to_flip.unwrap_or(0)
            ),
            "Flip them with `repair::reorient`.",
            true,
        );
    }

    let loops = topo.boundary_loops.len();
    if topo.num_components == 1 && topo.is_manifold() && topo.orientable {
        if loops == 0 {
            push(
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
            push(
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
        push(
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
    out
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
}
