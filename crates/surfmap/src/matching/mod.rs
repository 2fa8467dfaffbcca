//! Surface matching (thesis §2.2, §3.2): a smooth, fold-free correspondence
//! `φ_M = x_B ∘ φ ∘ x_A⁻¹` between two disc-like surfaces, found by minimizing the
//! matching energy (2.16) over deformations φ of the parameter plane, coarse to fine.
//!
//! One call runs it all: [`match_meshes`]. Its stages, each a function of its own, a
//! type in and a type out; each imports only the stages before it and the shared pieces
//! below (never the other way):
//!
//! ```text
//!  MatchInput A, B ─┐
//!  Guidance ────────┼─► prepare ──► align ──► solve ──► post ──────► report ──► Match
//!  MatchOptions ────┘   Prepared    Start     Solved    Correspondence  MatchReport
//!                       crop, scale  rigid ICP  multiscale φ  rim fit, folds,  counts, warnings,
//!                       flatten,     / landmarks, NCG per level pinning, fill-in, feature fits
//!                       images       hole pairs                numbering as given
//! ```
//!
//! - [`prepare`]: the meshes as given (and repaired) → both surfaces cut to the part
//!   they share ([`prepare::overlap`]), the guidance renumbered and paired, each surface
//!   flattened and rasterized into geometry images.
//! - `align`: where φ starts — the planes' similarity from landmarks, or from the
//!   surfaces aligned in space by trimmed ICP ([`rigid`]); hole rims paired as features.
//! - `solve`: φ level by level ([`energy`] on a grid [`deformation`], minimized by
//!   preconditioned nonlinear conjugate gradients), with the similarity search and the
//!   two starts on the coarsest level.
//! - `post`: φ → one counterpart per vertex of A, checked for folds in space
//!   ([`folds`]), numbered as the meshes were given.
//! - [`report`]: [`MatchReport`], what `match.json` holds.
//!
//! Shared by the stages: the options ([`MatchOptions`]), the guidance ([`Guidance`]),
//! the similarity fits ([`similarity`]), the rigid alignment ([`rigid`]), the energy
//! ([`energy`]) and φ ([`deformation`]), the fold check ([`folds`]). A [`Match`] writes
//! the match folder ([`folder`]) and draws its pictures ([`pictures`]).

pub mod deformation;
pub mod folder;
pub mod folds;
pub mod guidance;
pub mod options;
pub mod prepare;
pub mod report;
pub mod similarity;

pub(crate) mod align;
pub(crate) mod energy;
pub(crate) mod pictures;
pub(crate) mod post;
pub(crate) mod recover;
pub(crate) mod rigid;
pub(crate) mod solve;

use std::path::{Path, PathBuf};

use crate::mesh::repair::FaceOrigins;
use crate::mesh::{SurfacePoint, TriMesh};

pub use align::{AlignmentReport, FeatureStarts};
pub use deformation::Deformation;
pub use energy::EnergyTerms;
pub use folds::{FoldCheck, check_folds};
pub use guidance::{Guidance, Landmarks};
pub use options::{
    Advanced, Align, FEATURES_TO_ALIGN, FeaturesStart, HoleFeatures, MatchOptions, OptionError,
    POSITION_KAPPA, POSITION_RELIEF, POSITION_RESIDUAL_CAP, POSITION_RESIDUAL_FLOOR,
    PositionWeight, ScaleB, SearchWhen, UNIT_MISMATCH, Weights,
};
pub use report::confidence::{Confidence, Verdict};
pub use report::feature_fit::FeatureFit;
pub use report::{InputMesh, InputNumbering, Inputs, MatchReport};
pub use similarity::{Similarity2, Similarity3};
pub use solve::SimilaritySearchLog;
pub use solve::ncg::{LevelLog, StopReason};

/// Matches surface A onto surface B: every stage of the module documentation, from
/// the meshes as given to the report. `a` and `b` are the meshes (`&TriMesh`) or, when
/// the caller repaired them first, a [`MatchInput`] with the repaired mesh and where its
/// faces came from; the guidance is numbered as the meshes were given, and so are the
/// outputs.
pub fn match_meshes<'m>(
    a: impl Into<MatchInput<'m>>,
    b: impl Into<MatchInput<'m>>,
    guidance: &Guidance,
    options: &MatchOptions,
) -> Result<Match, MatchError> {
    options.validate().map_err(MatchError::Option)?;
    let begin = std::time::Instant::now();
    let mut prepared = prepare::prepare(a.into(), b.into(), guidance, options)?;
    let start = align::align(&mut prepared, options)?;
    let mut attempt = recover::Attempt::run(&prepared, start, options)?;
    // With `Align::None` the user fixed the start (the planes' identity): no other is tried.
    if attempt.report.confidence.verdict != Verdict::Ok
        && options.advanced.recover
        && options.align != Align::None
    {
        attempt = recover::recover(&mut prepared, attempt, options)?;
    }
    let recover::Attempt {
        solved,
        correspondence,
        mut report,
        ..
    } = attempt;
    // Only landmarks that pulled (a feature weight) can be left behind; with weight 0
    // they only placed the start.
    if options.weights.features > 0.0 {
        report
            .confidence
            .doubt_landmarks_left_behind(&report.feature_fit);
    }
    report.seconds_total = begin.elapsed().as_secs_f64();
    let matched = Match {
        correspondence: correspondence.given,
        a_on_b: correspondence.a_on_b,
        report,
        pictures: Pictures {
            mesh_a: prepared.mesh_a,
            mesh_b: prepared.mesh_b,
            points: correspondence.matched,
            a: prepared.a,
            b: prepared.b,
            scale_b: prepared.scale_b,
        },
        solved,
    };
    if options.strict && matched.report.confidence.verdict != Verdict::Ok {
        return Err(MatchError::NotTrusted(Box::new(matched)));
    }
    Ok(matched)
}

/// One surface given to [`match_meshes`]: the mesh as given (the numbering of the
/// guidance and of the outputs) and, when the caller repaired it, the repaired mesh to
/// match in its place with where each of its faces came from
/// ([`crate::mesh::repair::FaceOrigins`]).
pub struct MatchInput<'m> {
    pub given: &'m TriMesh,
    pub repaired: Option<(TriMesh, FaceOrigins)>,
}

impl<'m> From<&'m TriMesh> for MatchInput<'m> {
    fn from(given: &'m TriMesh) -> Self {
        Self {
            given,
            repaired: None,
        }
    }
}

/// A match of A onto B: everything its outputs need.
#[derive(Debug)]
pub struct Match {
    /// One entry per vertex of A as given: its counterpart on B as given (a triangle of
    /// B and barycentric coordinates), or `None`.
    pub correspondence: Vec<Option<SurfacePoint>>,
    /// A's triangles at their matched points on B, in B's units, numbered as A was given
    /// (unmatched vertices moved by the position term's map; triangles with an unmatched
    /// vertex left out).
    pub a_on_b: TriMesh,
    pub report: MatchReport,
    pictures: Pictures,
    solved: solve::Solved,
}

/// What the pictures are drawn from: the meshes as matched and their correspondence.
#[derive(Debug)]
pub(crate) struct Pictures {
    pub mesh_a: TriMesh,
    pub mesh_b: TriMesh,
    pub points: Vec<Option<SurfacePoint>>,
    pub a: prepare::surface::MatchSurface,
    pub b: prepare::surface::MatchSurface,
    pub scale_b: f64,
}

impl Match {
    /// φ on the finest grid (in ω_A → ω_B).
    pub fn deformation(&self) -> &Deformation {
        &self.solved.deformation
    }

    /// The correspondence as rows `[triangle of B, b0, b1, b2]` (triangle −1 where
    /// unmatched), row-major `(n_A, 4)`: `correspondence.npy`.
    pub fn correspondence_rows(&self) -> Vec<f64> {
        folder::correspondence_rows(&self.correspondence)
    }

    /// The pictures of the match, with their file names: A's checkerboard carried onto
    /// B, the deformed grid, the energy staircase and, with paired features, the
    /// features before and after the solve ([`pictures`]).
    pub fn pictures(&self) -> Vec<(&'static str, image::RgbImage)> {
        pictures::all(&self.pictures, &self.solved)
    }

    /// Writes the match folder into `dir` (created if missing): the files of
    /// [`folder`] and, with `with_pictures`, the pictures — drawn before anything is
    /// written, so an error leaves no partial folder. Returns the paths written.
    pub fn write_folder(
        &self,
        dir: &Path,
        with_pictures: bool,
    ) -> Result<Vec<PathBuf>, MatchError> {
        let drawn = if with_pictures {
            self.pictures()
        } else {
            vec![]
        };
        let mut written = folder::write_match_folder(
            dir,
            &self.solved.deformation,
            &self.correspondence,
            &self.a_on_b,
            &self.report,
        )?;
        for (name, img) in &drawn {
            let path = dir.join(name);
            crate::render::save_png(&path, img)
                .map_err(|e| MatchError::Output(format!("cannot write {}: {e}", path.display())))?;
            written.push(path);
        }
        Ok(written)
    }
}

/// What went wrong while matching, and what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum MatchError {
    /// `surface`: `'A'` or `'B'` when known.
    #[error("cannot flatten {}: {source}", .surface.map_or("the surface".to_string(), |s| format!("surface {s}")))]
    Flatten {
        surface: Option<char>,
        source: crate::param::flatten::FlattenError,
    },
    #[error("geometry images: {0}")]
    Images(#[from] crate::raster::RasterError),
    #[error("grid: {0}")]
    Grid(#[from] crate::grid::GridError),
    #[error("{0}")]
    Guidance(String),
    /// An input surface that cannot be used as given (beyond the flattening's defects).
    #[error("{0}")]
    Input(String),
    #[error("invalid option: {0}")]
    Option(OptionError),
    #[error("{0}")]
    Output(String),
    /// With [`MatchOptions::strict`]: the match was made, but its verdict is not `ok`
    /// (the match is here, to be written or looked at).
    #[error("{}", .0.report.confidence.line())]
    NotTrusted(Box<Match>),
}

impl From<crate::param::flatten::FlattenError> for MatchError {
    fn from(source: crate::param::flatten::FlattenError) -> Self {
        MatchError::Flatten {
            surface: None,
            source,
        }
    }
}

impl MatchError {
    /// Names the surface (`'A'` or `'B'`) a flattening error came from.
    pub(crate) fn of_surface(self, which: char) -> Self {
        match self {
            MatchError::Flatten { source, .. } => MatchError::Flatten {
                surface: Some(which),
                source,
            },
            other => other,
        }
    }
}

#[cfg(test)]
mod tests;
