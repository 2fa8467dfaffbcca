//! The library's problems with their remedies worded for Python. The library names its
//! own options and `mesh::repair` functions ("set `FlattenOptions::fill_holes`"); here
//! each becomes the call that does the same from Python (`fill_holes=True`,
//! `surfmap.repair(V, F, weld=0.0)`), as the command line words them as its flags.

use surfmap::FlattenError;
use surfmap::mesh::validate::{Defect, DefectKind};
use surfmap::param::flatten::OptionError;
use surfmap::report::{not_a_disc_message, with_remedy};

/// The remedy of a defect as the Python call that applies it, where one does.
fn python_remedy(d: &Defect) -> Option<&'static str> {
    Some(match d.kind {
        DefectKind::NonFiniteCoordinates if d.blocks_flattening => {
            "Fix the exporter, or remove the faces that use them (rows of F)."
        }
        DefectKind::NonFiniteCoordinates => {
            "Remove them with surfmap.repair(V, F, drop_unreferenced=True)."
        }
        DefectKind::OverflowingCoordinates => {
            "Scale V down (e.g. V / 1e6); the UVs come out in the same unit."
        }
        DefectKind::RepeatedIndexFaces => {
            "Remove them with surfmap.repair(V, F, drop_degenerate=True)."
        }
        DefectKind::DuplicateFaces => {
            "Remove the repeats with surfmap.repair(V, F, drop_degenerate=True)."
        }
        DefectKind::ZeroAreaFaces => {
            "Remove them with surfmap.repair(V, F, drop_degenerate=True) (this may open holes), or fix them in a mesh editor."
        }
        DefectKind::UnreferencedVertices => {
            "Remove them with surfmap.repair(V, F, drop_unreferenced=True)."
        }
        DefectKind::DuplicateVertices => {
            "Merge coincident vertices with surfmap.repair(V, F, weld=0.0)."
        }
        DefectKind::SeveralComponents => {
            "Keep one with surfmap.repair(V, F, keep_largest=True), or component=N to choose one."
        }
        DefectKind::NonManifoldEdges => {
            "Use surfmap.repair(V, F, fix_non_manifold=True, keep_largest=True, \
             drop_unreferenced=True) to cut them apart into sheets (the faces that continue \
             each other most smoothly stay joined; fins and glued-on sheets come loose) and \
             keep the largest piece."
        }
        DefectKind::NonManifoldVertices => {
            "Split each into one copy per fan with surfmap.repair(V, F, fix_non_manifold=True)."
        }
        DefectKind::InconsistentOrientation => {
            "Flip them with surfmap.repair(V, F, reorient=True)."
        }
        DefectKind::SeveralBoundaryLoops => {
            "pass fill_holes=True to fill all but the longest for the flattening (they stay \
             open in the map), or cut=\"holes\" to open them with seams to the outer boundary \
             (per-corner UVs: UV, FUV, report)."
        }
        DefectKind::ClosedSurface | DefectKind::PositiveGenus => {
            "pass cut=\"auto\" to cut it open into a disc along seams (per-corner UVs: UV, FUV, \
             report), or seams=EDGES to cut along your own edges."
        }
        DefectKind::NoFaces | DefectKind::NonOrientable => {
            return None;
        }
    })
}

/// A defect's problem and remedy, the remedy as a Python call.
pub fn defect_message(d: &Defect) -> String {
    with_remedy(d, python_remedy(d))
}

/// A numeric option out of range, as the keyword that set it.
pub fn option_message(e: &OptionError) -> String {
    match e {
        OptionError::Tolerance(t) => format!("tolerance must be positive, got {t}"),
        OptionError::ArmijoC(c) => format!("armijo_c must be in (0, 1), got {c}"),
        OptionError::CoarseVertices(n) => format!("coarse_vertices must be at least 16, got {n}"),
        OptionError::MaxDistortion(d) => format!(
            "max_distortion must be a finite number of at least 1 (the mean symmetric Dirichlet distortion of an isometry, the least any map has), got {d}"
        ),
        other => other.to_string(),
    }
}

/// A defect that stops `match`, worded for it: it fills holes itself (unless
/// `fill_holes=False`) and cannot cut a closed surface open — the part to match is cut
/// out with `surfmap.crop` — while the repairs are the same calls as for `flatten`.
pub fn match_defect_message(d: &Defect) -> String {
    let remedy = match d.kind {
        DefectKind::SeveralBoundaryLoops => Some(
            "match fills all but the longest for the solve (the correspondence is reported \
             for the real surface only): leave fill_holes at True.",
        ),
        DefectKind::ClosedSurface | DefectKind::PositiveGenus => Some(
            "match maps discs: cut the part to match out of it with surfmap.crop(V, F, \
             center=…, radius=…) (e.g. the face of a head scan), or open it in a mesh editor.",
        ),
        _ => python_remedy(d),
    };
    with_remedy(d, remedy)
}

/// A flattening error's message with its remedy as Python calls.
pub fn flatten_error_message(e: &FlattenError) -> String {
    worded_flatten_error(e, defect_message)
}

/// As [`flatten_error_message`], the defects worded by `wording` (`match`:
/// [`match_defect_message`]).
pub fn worded_flatten_error(e: &FlattenError, wording: surfmap::report::DefectWording) -> String {
    match e {
        FlattenError::NotADisc(defects) => not_a_disc_message(defects, wording),
        FlattenError::Degenerate(inner) => {
            format!("{inner}; surfmap.repair(V, F, drop_degenerate=True) removes them")
        }
        FlattenError::LscmFlipped(n) => format!(
            "the LSCM start flips or degenerates {n} triangles; use start=\"auto\" (falls back \
             to mean-value coordinates, injective by construction)"
        ),
        FlattenError::Option(o) => option_message(o),
        e @ (FlattenError::NoAdmissibleStart { .. }
        | FlattenError::NoAdmissibleStartAfterCuts { .. }) => e
            .no_start_worded(
                "cut=\"auto\" or seams=...; the default cut=\"never\" keeps one UV per vertex",
                ("surfmap.repair(V, F, drop_degenerate=True)", "seams=..."),
            )
            .unwrap_or_default(),
        other => other.to_string(),
    }
}
