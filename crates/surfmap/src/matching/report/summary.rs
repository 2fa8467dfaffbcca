//! The one-paragraph summary of a match that a command line prints
//! ([`MatchReport::summary`]).

use super::super::options::ScaleB;
use super::MatchReport;

impl MatchReport {
    /// What the match did, in a line (and a second about the numbering of the outputs
    /// when the meshes were repaired or cropped first), without a trailing newline.
    pub fn summary(&self) -> String {
        let report = self;
        let paired = match (
            report.alignment.hole_pairs.len(),
            report.alignment.split_holes.len(),
        ) {
            (0, _) => String::new(),
            (p, 0) => format!(", {p} hole rims paired as features"),
            (p, s) => format!(", {p} hole rims paired as features ({s} split at their corners)"),
        };
        let filled = match (report.holes_filled_a, report.holes_filled_b) {
            (0, 0) => String::new(),
            (a, b) => format!(", holes filled for the solve A {a} B {b}{paired}"),
        };
        let pinned = match report.pinned_landmarks {
            0 => String::new(),
            n => format!(
                ", {n} landmarks matched exactly (φ had left them up to {:.3} of B's units off)",
                report.largest_landmark_miss
            ),
        };
        let searched = match &report.alignment.search {
        None => String::new(),
        Some(s) => format!(
            ", similarity search {:+.2}°, scale {:.3} (energy per matched area {:.4e} → {:.4e}, {} evaluations; {})",
            s.similarity.angle().to_degrees(),
            s.similarity.scale(),
            s.energy_start,
            s.energy_end,
            s.evaluations,
            match (s.kept, s.implausible_size, s.area_ratio_search, s.area_ratio_alignment) {
                (true, ..) => "kept".to_string(),
                (false, true, Some(searched), Some(aligned)) => format!(
                    "not kept: solved from it, the coarsest level matched A at {searched:.2}× its area on B, \
                     from the alignment at {aligned:.2}×"
                ),
                _ => "not kept: solved from it, the coarsest level did not end lower without matching less"
                    .to_string(),
            }
        ),
    };
        let in_space = match &report.alignment.features_in_space {
            None => String::new(),
            Some(_) if report.alignment.mouth.is_some_and(|m| m.start_in_space) => {
                ", the features' alignment refined in space (alone, as the mouth opens)".into()
            }
            Some(f) => format!(
                ", the features' alignment refined in space {} (coarsest level's energy {:.4e} from the features' start, {:.4e} from it)",
                if f.kept { "kept" } else { "not kept" },
                f.energy_features,
                f.energy_space
            ),
        };
        let position = match report.shape_residual {
            Some(sigma) => format!(
                ", position weight {:.3e} (the surfaces {sigma:.4} of √area apart in space, along the normals)",
                report.position_weight
            ),
            None => format!(", position weight {:.3e} (fixed)", report.position_weight),
        };
        let fit = report.rim_fit;
        let rims = match (fit.holes, fit.by_arc_length) {
            (0, _) => String::new(),
            (h, 0) => format!(
                ", {h} hole rims carried onto B's ({} vertices moved)",
                fit.moved
            ),
            (h, l) => format!(
                ", {h} hole rims carried onto B's ({l} by arc length alone; {} vertices moved)",
                fit.moved
            ),
        };
        let left_out = match report.alignment.left_out.as_slice() {
            [] => String::new(),
            names => format!(
                " (left out of its fit, the others disagreeing: {}; they still guide the solve)",
                names.join(", ")
            ),
        };
        let crop_note =
            |side: char, other: char, c: &Option<super::super::prepare::overlap::SurfaceCrop>| {
                c.as_ref().map(|c| {
            format!(
                "{side} cut to the part near {other} ({:.0}% of its area far from {other} left out)",
                100.0 * c.removed_area
            )
        })
            };
        let crop = match &report.overlap_crop {
            Some(c) => format!(
                "{}; --crop-overlap off to match whole, ",
                [crop_note('A', 'B', &c.a), crop_note('B', 'A', &c.b)]
                    .into_iter()
                    .flatten()
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            None => String::new(),
        };
        let scaled = if report.scale_b == 1.0 {
            String::new()
        } else {
            let sizes = report.size_ratio;
            format!(
                "B ×{} for the match ({}; outputs in B's units), ",
                report.scale_b,
                match report.options.scale_b {
                    ScaleB::Auto => format!(
                        "A is {sizes:.3}× B's size (√area): taken for different units; --scale-b 1 to match as given"
                    ),
                    ScaleB::Factor(_) => "--scale-b".into(),
                }
            )
        };
        let mut text = format!(
            "match: {crop}{scaled}{} levels up to {n}², {} iterations, energy {:.4e}, min det Dφ {:.3}, matched {:.1}% of A ({} of {}, {} completed at rims){rims}, {:.1}% of B covered{filled}, {} vertices unmatched for folds ({} flipped, {} collapsed){pinned}, alignment {}{left_out}{in_space}{searched}{position}, {:.2} s",
            report.levels.len(),
            report.iterations,
            report.energy,
            report.min_det,
            100.0 * report.matched_fraction_a,
            report.matched_vertices_a,
            report.vertices_a,
            report.completed_vertices,
            100.0 * report.covered_fraction_b,
            report.dropped_vertices,
            report.flipped_triangles,
            report.collapsed_triangles,
            report.alignment.method,
            report.seconds_total,
            n = report.grid_size,
        );
        text += &format!("\n{}", report.confidence.line());
        if let Some(n) = &report.input_numbering {
            text += &format!(
                "\noutputs numbered as the files given ({} vertices of A, {} triangles of B){}",
                n.vertices_a,
                n.triangles_b,
                match n.removed_vertices_a {
                    0 => String::new(),
                    r => format!(
                        "; {r} vertices of A removed by the {} are unmatched",
                        match (
                            report.repaired,
                            report.overlap_crop.as_ref().is_some_and(|c| c.a.is_some())
                        ) {
                            (true, true) => "repairs and the crop",
                            (false, true) => "crop",
                            _ => "repairs",
                        }
                    ),
                }
            );
        }
        text
    }
}
