//! Surface matching (thesis §2.2, §3.2, §4.2): a smooth, fold-free correspondence
//! `φ_M = x_B ∘ φ ∘ x_A⁻¹` between two disc-like surfaces, found by minimizing the
//! matching energy (2.16) over deformations φ of the parameter plane, coarse to fine.
//!
//! Data flow: each surface is flattened and rasterized into geometry images
//! ([`surface`]); the deformation lives on the grid ([`deformation`]); the energy
//! terms and their gradients are in [`energy`]; [`ncg`] minimizes one level;
//! [`solve`] runs the multiscale schedule with the initial alignment
//! ([`similarity`], [`rigid`], [`align`]); [`output`] checks the result for folds in
//! space, maps points and writes the match folder; [`feature_fit`] measures how far φ
//! leaves each paired feature from B's; [`pictures`] draws it.

pub mod align;
pub mod complete;
pub mod deformation;
pub mod energy;
pub mod feature_fit;
pub mod holes;
pub mod ncg;
mod options;
pub mod output;
pub mod overlap;
pub mod pictures;
pub mod pin;
pub mod precondition;
pub mod rigid;
pub mod rim_fit;
pub mod similarity;
pub mod similarity_search;
pub mod solve;
pub mod surface;

pub use deformation::Deformation;
pub use energy::{Betas, EnergyTerms, Similarity3};
pub use feature_fit::FeatureFit;
pub use ncg::{LevelLog, NcgSettings, StopReason};
pub use output::{
    FoldCheck, InputNumbering, MatchReport, PointMap, check_folds, write_match_folder,
};
pub use similarity::Similarity2;
pub use similarity_search::{SearchWhen, SimilaritySearch, SimilaritySearchLog};
pub use solve::{
    Align, AlignmentReport, COARSEST_SOBOLEV_WIDTH, FEATURES_TO_ALIGN, FeatureStarts, Guidance,
    HoleFeatures, Landmarks, MatchOptions, POSITION_AFFINE_RIDGE, POSITION_KAPPA, POSITION_RELIEF,
    POSITION_RESIDUAL_CAP, POSITION_RESIDUAL_FLOOR, PositionMap, PositionWeight,
    RELIEF_MIDDLE_BUDGET, RELIEF_PHASE_FRACTION, ScaleB, SurfaceMatch, UNIT_MISMATCH,
    match_surfaces,
};
pub use surface::MatchSurface;

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
    Option(String),
    #[error("{0}")]
    Output(String),
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
