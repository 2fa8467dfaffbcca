//! The library's errors and remedies worded for the command line. The library names its
//! own options and `mesh::repair` functions ("set `FlattenOptions::fill_holes`"); here
//! each becomes the flag that does the same ("use --fill-holes").

use surfmap::FlattenError;
use surfmap::mesh::validate::{Defect, DefectKind};
use surfmap::param::flatten::OptionError;
use surfmap::report::{not_a_disc_message, with_remedy};

/// The remedy of a defect as the flags that apply it, where a flag does.
fn flag_remedy(d: &Defect) -> Option<&'static str> {
    Some(match d.kind {
        // On faces: no flag helps (the library's words say what does).
        DefectKind::NonFiniteCoordinates if d.blocks_flattening => return None,
        DefectKind::NonFiniteCoordinates => "Use --drop-unreferenced to remove them.",
        DefectKind::OverflowingCoordinates => return None,
        DefectKind::RepeatedIndexFaces => "Use --drop-degenerate to remove them.",
        DefectKind::DuplicateFaces => "Use --drop-degenerate (or --repair) to remove the repeats.",
        DefectKind::ZeroAreaFaces => {
            "Use --drop-degenerate to remove them (this may open holes), or fix them in a mesh editor."
        }
        DefectKind::UnreferencedVertices => "Use --drop-unreferenced to remove them.",
        DefectKind::DuplicateVertices => "Use --weld to merge coincident vertices.",
        DefectKind::SeveralComponents => "Use --keep-largest, or --component N to choose one.",
        DefectKind::NonManifoldEdges => {
            "Use --fix-non-manifold to cut them apart into sheets (the faces that continue each \
             other most smoothly stay joined; fins and glued-on sheets come loose), with \
             --keep-largest to drop the loose pieces; or --repair for every repair a raw scan \
             needs."
        }
        DefectKind::NonManifoldVertices => {
            "Use --fix-non-manifold to split each into one copy per fan (or --repair)."
        }
        DefectKind::InconsistentOrientation => "Use --reorient.",
        DefectKind::SeveralBoundaryLoops => {
            "surfmap flatten fills all but the longest for the solve (they stay open in the \
             output), or, with --cut-holes, joins them to the outer boundary by seams."
        }
        DefectKind::ClosedSurface | DefectKind::PositiveGenus => {
            "surfmap flatten cuts it open along seams (or along yours: --cut-along)."
        }
        DefectKind::NoFaces | DefectKind::NonOrientable => {
            return None;
        }
    })
}

/// A defect's problem and remedy, the remedy as flags.
pub fn defect_message(d: &Defect) -> String {
    with_remedy(d, flag_remedy(d))
}

/// A defect that stops `surfmap match`, worded for that command: it fills holes itself
/// (unless `--no-fill-holes`) and cannot cut a closed surface open — the part to match is
/// cut out with `surfmap crop` — while the repairs are the same flags as for flatten.
pub fn match_defect_message(d: &Defect) -> String {
    let remedy = match d.kind {
        DefectKind::SeveralBoundaryLoops => Some(
            "surfmap match fills all but the longest for the solve (the correspondence is \
             reported for the real surface only): leave out --no-fill-holes.",
        ),
        DefectKind::ClosedSurface | DefectKind::PositiveGenus => Some(
            "surfmap match maps discs: cut the part to match out of it with surfmap crop \
             (e.g. the face of a head scan: --center X,Y,Z --radius R), or open it in a mesh \
             editor.",
        ),
        _ => flag_remedy(d),
    };
    with_remedy(d, remedy)
}

/// A numeric option out of range, as the flag that set it.
pub fn option_message(e: &OptionError) -> String {
    match e {
        OptionError::Tolerance(t) => format!("--tolerance must be positive, got {t}"),
        OptionError::ArmijoC(c) => format!("--armijo-c must be in (0, 1), got {c}"),
        OptionError::CoarseVertices(n) => {
            format!("--coarse-vertices must be at least 16, got {n}")
        }
        OptionError::MaxDistortion(d) => format!(
            "--max-distortion must be at least 1 (the mean symmetric Dirichlet distortion of an isometry, the least any map has), got {d}"
        ),
        other => other.to_string(),
    }
}

/// A flattening error with its remedy as flags.
pub fn flatten_error(e: FlattenError) -> anyhow::Error {
    match flatten_error_message(&e) {
        Some(message) => anyhow::anyhow!(message),
        None => e.into(),
    }
}

/// The message of a flattening error whose remedy has a flag (`None`: the library's
/// message says it all).
pub fn flatten_error_message(e: &FlattenError) -> Option<String> {
    worded_flatten_error(e, defect_message)
}

/// As [`flatten_error_message`], the defects worded by `wording` (`surfmap match`:
/// [`match_defect_message`]).
pub fn worded_flatten_error(
    e: &FlattenError,
    wording: surfmap::report::DefectWording,
) -> Option<String> {
    Some(match e {
        FlattenError::NotADisc(defects) => not_a_disc_message(defects, wording),
        FlattenError::Degenerate(inner) => {
            format!("{inner}; run with --drop-degenerate or fix the mesh")
        }
        FlattenError::LscmFlipped(n) => format!(
            "the LSCM start flips or degenerates {n} triangles; use --start auto (falls back \
             to mean-value coordinates, injective by construction)"
        ),
        FlattenError::Option(o) => option_message(o),
        e @ (FlattenError::NoAdmissibleStart { .. }
        | FlattenError::NoAdmissibleStartAfterCuts { .. }) => e
            .no_start_worded(
                "`surfmap flatten` does, writing seams; the other commands need one UV per vertex",
                ("--drop-degenerate", "--cut-along"),
            )
            .unwrap_or_default(),
        _ => return None,
    })
}

/// A match error worded as `surfmap match` words it (a flattening's remedies as flags),
/// surfaces A and B called `a` and `b` ("the template", "the scan").
pub fn worded_match_error(e: &surfmap::matching::MatchError, a: &str, b: &str) -> String {
    if let surfmap::matching::MatchError::Flatten { surface, source } = e
        && let Some(message) = worded_flatten_error(source, match_defect_message)
    {
        let which = match surface {
            Some('A') => a,
            Some(_) => b,
            None => "the surface",
        };
        return format!("cannot flatten {which}: {message}");
    }
    crate::source_chain_message(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfmap::TriMesh;
    use surfmap::mesh::validate::validate;

    /// Every defect kind a messy mesh shows is worded with flags that exist, and never
    /// with the library's function names.
    #[test]
    fn remedies_name_flags_not_functions() {
        let mut m = TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.5, 0.5, f64::NAN],
                [5.0, 0.0, 0.0],
                [6.0, 0.0, 0.0],
                [5.0, 1.0, 0.0],
            ],
            vec![[0, 1, 2], [0, 3, 2], [0, 0, 1], [6, 7, 8]],
        );
        m.triangles.push([1, 4, 2]);
        let defects = validate(&m, &surfmap::Topology::new(&m));
        assert!(defects.len() >= 5, "{defects:?}");
        for d in &defects {
            let text = defect_message(d);
            assert!(!text.contains("repair::") && !text.contains('`'), "{text}");
            assert!(text.starts_with(&d.problem), "{text}");
            if flag_remedy(d).is_some() {
                assert!(text.contains(" --"), "{text}");
            }
        }
    }

    /// The refusals of a mesh no start embeds name what to do on the command line.
    #[test]
    fn no_start_refusals_name_flags_not_library_names() {
        let after_cuts = FlattenError::NoAdmissibleStartAfterCuts {
            cuts: 3,
            lscm: 12,
            mean_value: 2,
            triangle: Some(7),
        };
        let text = worded_flatten_error(&after_cuts, defect_message).unwrap();
        assert!(
            text.contains("--drop-degenerate") && text.contains("--cut-along"),
            "{text}"
        );
        assert!(text.contains("after 3 cuts along protrusions") && text.contains("triangle 7"));
        let never = FlattenError::NoAdmissibleStart {
            lscm: 12,
            mean_value: 2,
        };
        let text_never = worded_flatten_error(&never, defect_message).unwrap();
        assert!(
            text_never.contains("`surfmap flatten` does"),
            "{text_never}"
        );
        for t in [&text, &text_never] {
            assert!(!t.contains("::"), "{t}");
        }
        // The library's own wording names its API.
        assert!(after_cuts.to_string().contains("`Cut::Along`"));
        assert!(never.to_string().contains("`Cut::Auto` or `Cut::Along`"));
    }
}
