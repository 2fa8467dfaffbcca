//! Stage 2, **align**: the prepared surfaces → [`Start`], where φ starts (thesis §3.2.4:
//! the "rough alignment"). Both flattenings preserve orientation, so ω_A and ω_B differ
//! by a similarity of the plane. With five or more paired landmarks or features it is
//! their least-squares fit; otherwise the surfaces are aligned in space by trimmed ICP
//! ([`super::rigid`]) and the plane similarity is fitted to the vertex pairs that makes
//! (`shape_alignment`), its candidates scored by the energy's data terms ([`score`]).
//! The same alignment in space measures how far the shapes differ, which sets the
//! position term's weight ([`PositionWeight`]). Last, the rims of filled holes are paired
//! across the surfaces and added to their features ([`holes`]).

pub(crate) mod holes;
pub(crate) mod mouth;
pub(crate) mod score;

use serde::Serialize;

use super::MatchError;
use super::energy::{Betas, epsilon};
use super::options::{
    Align, FEATURES_TO_ALIGN, FeaturesStart, HoleFeatures, MatchOptions, PositionWeight, SearchWhen,
};
use super::prepare::Prepared;
use super::prepare::surface::MatchSurface;
use super::rigid::{RigidAlignment, align_surfaces, align_surfaces_ranked};
use super::similarity::{
    Similarity2, Similarity3, fit_rotation_2d_at_scale, fit_similarity_2d,
    fit_similarity_2d_robust, fit_similarity_3d,
};
use super::solve::SimilaritySearchLog;
use crate::mesh::closest::ClosestPoints;
use crate::raster::FeatureFile;
use holes::add_hole_features;
use score::AlignmentScore;

/// Where φ starts, and the energy's weights.
#[derive(Clone, Debug)]
pub(crate) struct Start {
    /// The plane similarity φ starts from on the coarsest level.
    pub plane: Similarity2,
    /// The position term's map of ℝ³ to start from (ℓ units).
    pub motion: Similarity3,
    /// With features: the second start, from their alignment refined in space (plane
    /// similarity and motion; [`FeatureStarts`]).
    pub in_space: Option<(Similarity2, Similarity3)>,
    /// Whether the similarity search runs on the coarsest level
    /// ([`super::solve::similarity_search`]).
    pub search: bool,
    /// The energy's weights, the position term's set from the shapes' disagreement.
    pub betas: Betas,
    /// The surfaces' RMS distance along B's normals after their rigid alignment (ℓ
    /// units), from which the position weight was set (`None` with a fixed weight).
    pub shape_residual: Option<f64>,
    /// The surfaces' rigid alignment in space (ℓ units), when one was made: what the
    /// verdict compares the correspondence's own similarity with.
    pub pose: Option<Similarity3>,
    pub report: AlignmentReport,
}

/// The stage (module docs). Pairs the hole rims and adds them to both surfaces'
/// features (so it takes the prepared surfaces mutably).
pub(crate) fn align(p: &mut Prepared<'_>, options: &MatchOptions) -> Result<Start, MatchError> {
    let (fa, fb) = (p.features_a.as_ref(), p.features_b.as_ref());
    let (sa, sb) = (&p.a, &p.b);
    if options.hole_features == HoleFeatures::On {
        let (ha, hb) = (sa.hole_rims().len(), sb.hole_rims().len());
        if ha != hb || ha == 0 {
            return Err(MatchError::Guidance(format!(
                "hole features pair the rims one to one, but A has {ha} filled holes and B has {hb}; \
                 fill or cut the extra holes, or turn hole features off"
            )));
        }
    }
    // UVs are in mesh units and both meshes share ℓ: corresponding lengths match when
    // ω_A is scaled by the ratio of the domain transforms.
    let scale = sb.images.transform.scale / sa.images.transform.scale;
    // With fewer than FEATURES_TO_ALIGN features, `auto` aligns the shapes and the
    // features only guide.
    let features_given = fa.map_or(0, |f| f.features.len());
    let too_few_to_align = (1..FEATURES_TO_ALIGN).contains(&features_given);
    let use_features = match options.align {
        Align::Features => {
            if fa.is_none() {
                return Err(MatchError::Guidance(
                    "alignment from features needs features or landmarks".into(),
                ));
            }
            if features_given < 2 {
                return Err(MatchError::Guidance(
                    "alignment from features needs two or more features or landmarks: one \
                     fixes where A goes but not how it turns; give another, or align with \
                     `auto` (the shapes in space, the feature still guiding the solve)"
                        .into(),
                ));
            }
            true
        }
        Align::Auto => features_given >= FEATURES_TO_ALIGN,
        Align::Shape | Align::None => false,
    };
    // With features, the second start from their alignment refined in space
    // ([`FeatureStarts`]); its ICP also measures the position weight's residual.
    // With two features (no rigid motion in space from their centroids) that second start
    // is the shapes' own alignment.
    let in_space = match features_motion(sa, sb, fa, fb) {
        _ if !(use_features && options.features_start == FeaturesStart::Both) => None,
        Some(start) => shape_alignment(sa, sb, scale, 1, Some(start)).ok(),
        None => shape_alignment(sa, sb, scale, options.tuning.align_rotations.max(1), None).ok(),
    };
    let (s, similarity, alignment, residual) = if use_features {
        let pa = feature_centroids(sa, fa.unwrap());
        let pb = feature_centroids(sb, fb.unwrap());
        let at_one_point =
            || MatchError::Guidance("the features/landmarks of A all lie at one point".into());
        // Two points (`Align::Features` only) fix the size poorly: two mouth corners lie
        // closer together on a closed mouth than on an open one (FLAME template →
        // registered: ×1.26 where the shapes give ×1.07; 42 % within 0.05, 93 % at the
        // size the meshes' units give), so two features keep that size (BENCHMARKS.md,
        // "Few landmarks").
        let (s, left_out) = if pa.len() >= 3 {
            fit_similarity_2d_robust(&pa, &pb).ok_or_else(at_one_point)?
        } else {
            (
                fit_rotation_2d_at_scale(&pa, &pb, scale).ok_or_else(at_one_point)?,
                vec![],
            )
        };
        let names = &fa.unwrap().features;
        let report = AlignmentReport {
            method: "features".into(),
            similarity: s,
            hole_pairs: vec![],
            split_holes: vec![],
            left_out: left_out.iter().map(|&i| names[i].name.clone()).collect(),
            search: None,
            features_in_space: in_space.as_ref().map(|x| FeatureStarts {
                similarity: x.0,
                plane_rms: x.3 * sa.length_unit,
                energy_features: f64::NAN,
                energy_space: f64::NAN,
                kept: false,
            }),
            mouth: None,
        };
        (
            s,
            Similarity3::identity(),
            report,
            in_space.as_ref().map(|x| x.3),
        )
    } else if options.align == Align::None {
        let s = Similarity2::identity();
        let report = AlignmentReport {
            method: "none".into(),
            similarity: s,
            hole_pairs: vec![],
            split_holes: vec![],
            left_out: vec![],
            search: None,
            features_in_space: None,
            mouth: None,
        };
        (s, Similarity3::identity(), report, None)
    } else {
        let (s, motion, mut report, residual) =
            shape_alignment(sa, sb, scale, options.tuning.align_rotations.max(1), None)?;
        if too_few_to_align && options.align == Align::Auto {
            report.method = format!(
                "{} ({features_given} of the {FEATURES_TO_ALIGN} features or landmarks it \
                 takes to align by them; they still guide the solve)",
                report.method
            );
        }
        (s, motion, report, Some(residual))
    };
    // The position term's weight from the surfaces' disagreement in space
    // ([`PositionWeight`]); the shape alignment measured it already.
    // The pose in space: the shapes' alignment, or the features' refined in space, or
    // (measured here when neither ran) the shapes' alignment from the features' motion.
    let known_pose = if use_features {
        in_space.as_ref().map(|x| x.1)
    } else if options.align == Align::None {
        None
    } else {
        Some(similarity)
    };
    let (residual, pose) = match (residual, known_pose) {
        (Some(r), Some(p)) => (Some(r), Some(p)),
        _ => match shape_residual(sa, sb, fa, fb) {
            Some((r, p)) => (residual.or(Some(r)), known_pose.or(Some(p))),
            None => (residual, known_pose),
        },
    };
    let shape_residual = match options.position_weight {
        PositionWeight::Fixed(_) => None,
        PositionWeight::Auto => residual,
    };
    let betas = Betas {
        position: options.position_weight.weight(shape_residual),
        ..options.betas()
    };
    let search = match options.similarity_search {
        SearchWhen::Off => false,
        SearchWhen::Shape => !use_features && options.align != Align::None,
        SearchWhen::Always => true,
    };
    let mut start = Start {
        plane: s,
        motion: similarity,
        in_space: in_space.map(|(s, motion, _, _)| (s, motion)),
        search,
        betas,
        shape_residual,
        pose,
        report: alignment,
    };
    pair_holes(p, &mut start, options)?;
    Ok(start)
}

/// Pairs the hole rims of A and B after `start`'s alignment and adds them to both
/// surfaces' features ([`holes`]), replacing the hole rims an earlier start paired;
/// records the pairs in the start's report.
pub(crate) fn pair_holes(
    p: &mut Prepared<'_>,
    start: &mut Start,
    options: &MatchOptions,
) -> Result<(), MatchError> {
    let given = |f: &Option<FeatureFile>| f.as_ref().map_or(0, |f| f.features.len());
    let guided = given(&p.features_a) + given(&p.features_b) > 0;
    let pair = |p: &mut Prepared<'_>, start: &mut Start| -> Result<(), MatchError> {
        p.a.keep_features(given(&p.features_a));
        p.b.keep_features(given(&p.features_b));
        if options.hole_features != HoleFeatures::Off {
            (start.report.hole_pairs, start.report.split_holes) = add_hole_features(
                &mut p.a,
                &mut p.b,
                &start.plane,
                options.hole_features,
                options.split_ratio(),
            )?;
        }
        Ok(())
    };
    pair(p, start)?;
    // A mouth that opens between the surfaces: the lip arcs lead ([`mouth`]).
    let openings = |p: &Prepared<'_>, start: &Start| {
        mouth::mouth_openings(
            &p.a,
            &p.b,
            &start.report.hole_pairs,
            &start.report.split_holes,
        )
        .map(|(_, o)| o)
    };
    let mut found = openings(p, start);
    // With landmarks or features, only from their alignment refined in space, alone: the
    // features' plane similarity, its scale off by the mouth corners that moved with the
    // jaw, makes the weights below worse ([`mouth`]).
    let mut opens =
        options.advanced.open_mouth && mouth::opens(found) && (!guided || start.in_space.is_some());
    let mut start_in_space = false;
    if opens
        && guided
        && let Some((plane, motion)) = start.in_space.take()
    {
        let plane_start = (start.plane, start.motion);
        (start.plane, start.motion) = (plane, motion);
        pair(p, start)?;
        let refound = openings(p, start);
        if mouth::opens(refound) {
            found = refound;
            start_in_space = true;
            if let Some(f) = start.report.features_in_space.as_mut() {
                f.kept = true;
            }
        } else {
            // The rims paired from the start in space do not show the mouth opening
            // (another hole taken for the mouth, or none): the rule's premise is gone
            // there, so the plane start and its pairing come back, without the rule.
            (start.plane, start.motion) = plane_start;
            start.in_space = Some((plane, motion));
            pair(p, start)?;
            opens = false;
        }
    }
    // From the options each time: a start paired again keeps no earlier change.
    start.betas.features = options.betas().features;
    start.betas.position = options.position_weight.weight(start.shape_residual);
    if opens {
        start.betas.features *= mouth::OPEN_FEATURE_FACTOR;
        if options.position_weight == PositionWeight::Auto {
            start.betas.position = start.betas.position.min(mouth::OPEN_POSITION_WEIGHT);
        }
    }
    start.report.mouth = found.map(|(a, b)| MouthOpening {
        a,
        b,
        opens,
        start_in_space,
        feature_weight: start.betas.features,
    });
    Ok(())
}

/// Most alternative starts a match that went wrong tries ([`alternatives`]).
pub(crate) const ALTERNATIVES: usize = 6;

/// Other starts than `first` for a match whose verdict was not `ok`: the next distinct
/// poses the rigid alignment in space ended in (`rigid::align_surfaces_ranked`; with
/// landmarks or features, the shapes' own best pose first), each as the plane
/// similarity its vertex pairs give, and `first`'s plane similarity turned by a half
/// and a quarter turn either way about where it puts ω_A's centre (a flattening turned
/// against the other, a start from mislabelled landmarks). At most [`ALTERNATIVES`].
/// Hole rims are not paired ([`pair_holes`] per start).
pub(crate) fn alternatives(p: &Prepared<'_>, first: &Start, options: &MatchOptions) -> Vec<Start> {
    let (sa, sb) = (&p.a, &p.b);
    let scale = sb.images.transform.scale / sa.images.transform.scale;
    let from_shape = first.report.method.starts_with("shape");
    let mut out = vec![];
    let poses = shape_alignments(sa, sb, scale, options.tuning.align_rotations.max(1), 4);
    for (k, (s, motion, mut report, _)) in poses.into_iter().enumerate() {
        if from_shape && k == 0 {
            continue;
        }
        report.method = format!(
            "recovery: pose {} of the alignment in space, {}",
            k + 1,
            report.method
        );
        out.push(Start {
            plane: s,
            motion,
            in_space: None,
            search: options.similarity_search != SearchWhen::Off,
            pose: Some(motion),
            report,
            ..first.clone()
        });
    }
    let (ca, _) = sa.domain_centroid_and_area();
    let centre = first.plane.apply(ca);
    for turn in [0.5, 0.25, -0.25] {
        let angle = turn * std::f64::consts::TAU;
        let plane = Similarity2::about(centre, angle, 1.0, centre).after(&first.plane);
        let mut report = first.report.clone();
        report.method = format!(
            "recovery: {} turned by {:+.0}°",
            report.method,
            angle.to_degrees()
        );
        report.similarity = plane;
        (report.search, report.features_in_space) = (None, None);
        out.push(Start {
            plane,
            in_space: None,
            search: false,
            report,
            ..first.clone()
        });
    }
    out.truncate(ALTERNATIVES);
    out
}

/// The alignment that was used.
#[derive(Clone, Debug, Serialize)]
pub struct AlignmentReport {
    pub method: String,
    pub similarity: Similarity2,
    /// Hole rims paired as features: `(hole of A, hole of B, distance of their centres
    /// in ω after the alignment)`.
    pub hole_pairs: Vec<holes::HolePair>,
    /// The hole pairs (indices into `hole_pairs`) matched as two arcs each, split at
    /// their corners (`holes::split_rim_pair`); the others as one closed curve.
    pub split_holes: Vec<usize>,
    /// Features/landmarks left out of the alignment's similarity fit because the others
    /// disagreed with them ([`fit_similarity_2d_robust`]); they still guide the solve.
    pub left_out: Vec<String>,
    /// The similarity search, when it ran and found a lower energy per matched area
    /// ([`MatchOptions::similarity_search`]); `kept` says whether the solve went on
    /// from it.
    pub search: Option<SimilaritySearchLog>,
    /// With features: the second start from their alignment refined in space, and
    /// which start the solve went on from (`MatchOptions::features_in_space`).
    pub features_in_space: Option<FeatureStarts>,
    /// The mouth's openings when a hole pair was split at its corners, and whether the
    /// weights were changed for a mouth that opens ([`mouth`]).
    pub mouth: Option<MouthOpening>,
}

/// How open the mouth is on A and on B ([`mouth`]: arc gap over corner distance).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MouthOpening {
    pub a: f64,
    pub b: f64,
    /// A mouth opens between the surfaces (and `--no-open-mouth` was not given; with
    /// landmarks or features, their alignment refined in space exists): features
    /// weighted [`mouth::OPEN_FEATURE_FACTOR`] times more, the automatic position weight
    /// capped at [`mouth::OPEN_POSITION_WEIGHT`].
    pub opens: bool,
    /// With landmarks or features: the solve started from their alignment refined in
    /// space alone, not from their plane similarity too (`features_in_space` then has no
    /// energies: the two starts were not compared).
    pub start_in_space: bool,
    /// The feature weight used (the position weight used is the report's).
    pub feature_weight: f64,
}

impl AlignmentReport {
    /// The plane similarity φ started from on the coarsest level: the alignment's
    /// (`similarity`), or the start the solve went on from instead — the similarity
    /// search's (applied after it) or the features' alignment refined in space — when
    /// that one was kept.
    pub fn start(&self) -> Similarity2 {
        if let Some(f) = &self.features_in_space
            && f.kept
        {
            return f.similarity;
        }
        if let Some(s) = &self.search
            && s.kept
        {
            return s.similarity.after(&self.similarity);
        }
        self.similarity
    }
}

/// The coarsest level solved from two starts when features or landmarks are given.
///
/// The features' similarity of the planes (a least-squares fit of their positions in
/// ω_A and ω_B) trusts a handful of points, and in the flattened domains: where some of
/// them moved with the surface — the mouth corners of a face with its jaw open — it is
/// off in scale (ICT neutral → jaw open: ×1.12 where the vertex pairs below give
/// ×1.036), and the position term, refitted to that start, holds φ there (the chin, the
/// forehead and one ear left unmatched). The second start: the rigid motion of the
/// features' 3D centroids, refined by trimmed ICP over the whole surfaces
/// ([`super::rigid::align_surfaces`]), and the plane similarity of the vertex pairs it
/// makes (as [`Align::Shape`] does). It cannot see a difference in size, which the
/// features can (two ICT identities 5 % apart in size, B remeshed coarser: the features'
/// start ends at energy 1.80, the one from space at 2.79). So both are minimized on the
/// coarsest level, side by side, and the one from space is kept only when it ends with a
/// lower energy and matches at least the same area (the rule of the similarity search).
/// Measured over three runs on the 28 referee pairs with landmarks (BENCHMARKS.md, "Two
/// starts with landmarks"): ICT expression 93.6 / 97.8 → 95.3 / 98.6 % within 0.02 /
/// 0.05, partial 97.4 / 98.1 → 98.0 / 98.5, identity, resolution and the FLAME pairs
/// unchanged or better.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FeatureStarts {
    /// The plane similarity from the alignment in space.
    pub similarity: Similarity2,
    /// Root-mean-square distance (mesh units) between the surfaces along the normals
    /// after that alignment.
    pub plane_rms: f64,
    /// The coarsest level's energy at the end, from the features' start.
    pub energy_features: f64,
    /// The same from the start in space.
    pub energy_space: f64,
    /// Whether the solve went on from the start in space.
    pub kept: bool,
}

/// Domain centroid of every feature of a surface.
fn feature_centroids(s: &MatchSurface, f: &FeatureFile) -> Vec<[f64; 2]> {
    curve_means(f, |v| s.vertex_domain_position(v))
}

/// The mean of `point(v)` over each feature curve's vertices `v`.
fn curve_means<const N: usize>(
    f: &FeatureFile,
    point: impl Fn(usize) -> [f64; N],
) -> Vec<[f64; N]> {
    f.features
        .iter()
        .map(|c| {
            let mut m = [0.0; N];
            for &v in &c.vertices {
                let p = point(v as usize);
                (0..N).for_each(|i| m[i] += p[i]);
            }
            m.map(|x| x / c.vertices.len() as f64)
        })
        .collect()
}

/// The similarity of the planes from a rigid alignment of the surfaces in space
/// ([`super::rigid`]): every vertex of A within the trimmed pairs' distance of B is paired
/// with its closest vertex of B, and the least-squares similarity of their domain
/// positions is refitted once without the pairs it explains worst (beyond three times
/// the median residual). Also returns the rigid motion, in ℓ units, as the start of the
/// position term's map. The rigid alignment is searched from many starts, or refined
/// from `refine_from` (an A → B motion in mesh units) alone.
fn shape_alignment(
    sa: &MatchSurface,
    sb: &MatchSurface,
    scale: f64,
    rotations: usize,
    refine_from: Option<Similarity3>,
) -> Result<PlaneStart, MatchError> {
    let starts = if refine_from.is_some() {
        vec![]
    } else {
        rigid_starts(sa, sb, scale, rotations)
    };
    let rigid = align_surfaces(
        (&sa.positions, &sa.triangles),
        (&sb.positions, &sb.triangles),
        &starts,
        refine_from,
    )
    .ok_or_else(|| {
        MatchError::Guidance("cannot align the surfaces in space: too few vertices".into())
    })?;
    plane_from_pose(sa, sb, &rigid)
}

/// [`shape_alignment`] from each of the `count` best distinct poses the rigid alignment
/// ends in (`rigid::align_surfaces_ranked`), those that give a plane similarity.
fn shape_alignments(
    sa: &MatchSurface,
    sb: &MatchSurface,
    scale: f64,
    rotations: usize,
    count: usize,
) -> Vec<PlaneStart> {
    let starts = rigid_starts(sa, sb, scale, rotations);
    align_surfaces_ranked(
        (&sa.positions, &sa.triangles),
        (&sb.positions, &sb.triangles),
        &starts,
        None,
        count,
    )
    .iter()
    .filter_map(|rigid| plane_from_pose(sa, sb, rigid).ok())
    .collect()
}

/// A start from a pose in space: the plane similarity, the motion (ℓ units), the
/// report, and the surfaces' distance along the normals (ℓ units).
type PlaneStart = (Similarity2, Similarity3, AlignmentReport, f64);

/// Extra ICP starts: the rigid motions of the best similarities of the planes (a search
/// over rotations, translations and scales of ω_A scored by the 3D fit, [`score`]); they
/// reach poses that the rotations about the centroids miss when the surfaces overlap
/// only in part.
fn rigid_starts(
    sa: &MatchSurface,
    sb: &MatchSurface,
    scale: f64,
    rotations: usize,
) -> Vec<Similarity3> {
    let unit = sa.length_unit;
    {
        let ks = 5.min(sa.num_levels() - 1);
        let eps = epsilon(ks);
        let level_a = sa.level_a(ks, eps, &[]);
        let level_b = sb.level_b(ks, eps, 1.0, &[]);
        let inside: Vec<bool> = level_a.chi.iter().map(|&c| c == 1.0).collect();
        let (ca, _) = sa.domain_centroid_and_area();
        let (cb, _) = sb.domain_centroid_and_area();
        let search = AlignmentScore::new(&level_a, &level_b, &inside, false);
        let (found, _) = search.search(ca, cb, scale, rotations, 8);
        found
            .iter()
            .filter(|c| c.score.is_finite())
            .map(|c| Similarity3 {
                matrix: c.motion.matrix,
                translation: c.motion.translation.map(|t| t * unit),
            })
            .collect()
    }
}

/// The plane similarity of the vertex pairs a rigid pose in space makes ([`shape_alignment`]).
fn plane_from_pose(
    sa: &MatchSurface,
    sb: &MatchSurface,
    rigid: &RigidAlignment,
) -> Result<PlaneStart, MatchError> {
    let unit = sa.length_unit;
    let closest = ClosestPoints::new(&sb.positions);
    let limit = (2.5 * rigid.rms).powi(2);
    let step = (sa.positions.len() / 4000).max(1);
    let mut pa = vec![];
    let mut pb = vec![];
    for v in (0..sa.positions.len()).step_by(step) {
        let (w, d2) = closest.closest(&rigid.motion.apply(sa.positions[v]));
        if d2 <= limit {
            pa.push(sa.vertex_domain_position(v));
            pb.push(sb.vertex_domain_position(w));
        }
    }
    let fail =
        || MatchError::Guidance("the surfaces do not overlap after aligning them in space".into());
    let mut s = fit_similarity_2d(&pa, &pb).ok_or_else(fail)?;
    let residual = |s: &Similarity2, a: &[f64; 2], b: &[f64; 2]| {
        let y = s.apply(*a);
        (y[0] - b[0]).hypot(y[1] - b[1])
    };
    let mut r: Vec<f64> = pa
        .iter()
        .zip(&pb)
        .map(|(a, b)| residual(&s, a, b))
        .collect();
    let mut sorted = r.clone();
    sorted.sort_by(f64::total_cmp);
    let cut = 3.0 * sorted[sorted.len() / 2];
    let keep: Vec<usize> = (0..r.len()).filter(|&i| r[i] <= cut).collect();
    if keep.len() >= 3 {
        let qa: Vec<[f64; 2]> = keep.iter().map(|&i| pa[i]).collect();
        let qb: Vec<[f64; 2]> = keep.iter().map(|&i| pb[i]).collect();
        s = fit_similarity_2d(&qa, &qb).ok_or_else(fail)?;
        r = keep.iter().map(|&i| residual(&s, &pa[i], &pb[i])).collect();
    }
    let motion = Similarity3 {
        matrix: rigid.motion.matrix,
        translation: rigid.motion.translation.map(|t| t / unit),
    };
    let report = AlignmentReport {
        method: format!(
            "shape: trimmed ICP in space (RMS {:.4} mesh units to the closest vertices, {:.4} along the normals), {} vertex pairs, domain residual median {:.4}",
            rigid.rms,
            rigid.plane_rms,
            r.len(),
            {
                let mut x = r.clone();
                x.sort_by(f64::total_cmp);
                x[x.len() / 2]
            }
        ),
        similarity: s,
        hole_pairs: vec![],
        split_holes: vec![],
        left_out: vec![],
        search: None,
        features_in_space: None,
        mouth: None,
    };
    Ok((s, motion, report, rigid.plane_rms / unit))
}

/// The RMS distance (ℓ units) along B's normals between the surfaces after their best
/// rigid alignment in space, and that alignment (ℓ units): trimmed ICP from the rigid
/// motion of the paired features' 3D centroids when there are three or more, else from
/// the usual starts ([`align_surfaces`], either way round); `None` when they cannot be
/// aligned.
fn shape_residual(
    sa: &MatchSurface,
    sb: &MatchSurface,
    fa: Option<&FeatureFile>,
    fb: Option<&FeatureFile>,
) -> Option<(f64, Similarity3)> {
    let start = features_motion(sa, sb, fa, fb);
    let unit = sa.length_unit;
    align_surfaces(
        (&sa.positions, &sa.triangles),
        (&sb.positions, &sb.triangles),
        &[],
        start,
    )
    .map(|rigid| {
        let pose = Similarity3 {
            matrix: rigid.motion.matrix,
            translation: rigid.motion.translation.map(|t| t / unit),
        };
        (rigid.plane_rms / unit, pose)
    })
}

/// The rigid motion (mesh units) that best carries the paired features' 3D centroids of
/// A onto B's, when there are three or more.
fn features_motion(
    sa: &MatchSurface,
    sb: &MatchSurface,
    fa: Option<&FeatureFile>,
    fb: Option<&FeatureFile>,
) -> Option<Similarity3> {
    match (fa, fb) {
        (Some(fa), Some(fb)) if fa.features.len() >= 3 => {
            let pa = curve_means(fa, |v| sa.positions[v]);
            let pb = curve_means(fb, |v| sb.positions[v]);
            fit_similarity_3d(&pa, &pb, &vec![1.0; pa.len()], false)
        }
        _ => None,
    }
}
