//! Applications of flattenings and correspondences (thesis ch. 5): texture baking
//! (§5.1, fig. 5.2), transfer of attributes, texture coordinates and texture images
//! through a correspondence, 3D morphs (§5.2, fig. 5.3), blend-shape rigs by composed
//! correspondences (§5.3, figs. 5.4–5.5) and their glTF 2.0 export.
//!
//! **A correspondence** from a surface A to a surface B is plain data,
//! `&[Option<SurfacePoint>]`: one entry per vertex of A, the point of B it corresponds
//! to (a triangle of B and barycentric coordinates), or `None` where A has no
//! counterpart on B (partial matches, thesis §2.2.5). It is what a surface match
//! hands out (`φ_M = x_B ∘ φ ∘ x_A⁻¹` of §5.2 sampled at A's vertices) and what a match
//! folder stores on disk ([`match_folder`]). [`correspondence`] checks one against its
//! meshes, carries points that are not vertices through it (piecewise-linear in a
//! [`Chart`] of B), composes two of them and measures how far two maps are apart.
//!
//! One file per concept:
//!
//! | file | what it computes |
//! |---|---|
//! | [`correspondence`] | checks, [`Chart`], pushing points through a map, composition `φ_BC ∘ φ_AB`, map distances |
//! | [`transfer`] | per-vertex values, labels, landmarks, texture coordinates and texture images carried from B to A |
//! | [`texture`] | texture images in and out, bilinear sampling |
//! | [`bake`] | texture baking: an old texture rendered into a new parameter domain |
//! | [`pad`] | colour padding beyond a chart's boundary (no mipmap seams) |
//! | [`morph`] | morph targets `φ_M(x) − x` with a harmonic extension over unmatched vertices |
//! | [`rig`] | blend-shape keys re-expressed on the neutral's connectivity |
//! | [`retarget`] | a rig's keys carried onto a new neutral through a match (displacement transfer) |
//! | [`register`] | a template registered onto many scans: placed in its topology, a table per batch |
//! | [`stills`] | a sheet of morph stills from one fixed view (figs. 5.3, 5.5) |
//! | [`gltf`] | glTF 2.0 binary (`.glb`) with morph targets and a weight animation |
//! | [`match_folder`] | `DIR/correspondence.npy` + `DIR/match.json` in and out |

pub mod bake;
pub mod correspondence;
pub mod gltf;
#[doc(hidden)]
pub mod inputs;
pub mod match_folder;
pub mod morph;
pub mod pad;
pub mod register;
pub mod retarget;
pub mod rig;
pub mod stills;
pub mod texture;
pub mod transfer;

pub use bake::{BakeOptions, BakedTexture, bake_texture, bake_vertex_colors};
pub use correspondence::{Chart, MapDistance, compare_maps, compose, push_point};
pub use morph::{MorphTarget, morph_frame, morph_target};
pub use rig::{RigKey, rig_key};
pub use texture::Texture;
pub use transfer::{
    transfer_labels, transfer_scalars, transfer_texture, transfer_uvs, transfer_values,
};

use crate::linsolve::SolveError;
use crate::mesh::IndexError;
use crate::mesh::locate::LocateError;

/// What went wrong in an application, and what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum AppError {
    #[error(
        "the correspondence has {got} entries but surface A has {expected} vertices; it belongs to another mesh (one entry per vertex of A)"
    )]
    CorrespondenceLength { got: usize, expected: usize },
    #[error(
        "the correspondence maps vertex {vertex} of A to triangle {triangle} of B, but B has only {num_triangles} triangles; it belongs to another mesh B"
    )]
    CorrespondenceTriangle {
        vertex: usize,
        triangle: u32,
        num_triangles: usize,
    },
    #[error(
        "the correspondence maps vertex {vertex} of A to barycentric coordinates {barycentric:?}, which are not a point of the triangle (each ≥ 0, sum 1)"
    )]
    CorrespondenceBarycentric {
        vertex: usize,
        barycentric: [f64; 3],
    },
    #[error("{what}: {got} values given for {expected} {per}; pass one per {per_one}")]
    Length {
        what: &'static str,
        got: usize,
        expected: usize,
        per: &'static str,
        per_one: &'static str,
    },
    #[error(
        "no vertex of A has a counterpart on B: the correspondence is empty, match the surfaces again"
    )]
    NothingMatched,
    #[error(
        "vertex {vertex} of A lies in a part of the mesh where no vertex is matched, so its displacement cannot be extended from matched ones; drop that part (e.g. --keep-largest) or match it"
    )]
    UnanchoredPart { vertex: usize },
    #[error("texture: {0}")]
    Texture(String),
    #[error("invalid option: {0}")]
    Option(String),
    #[error(transparent)]
    Index(#[from] IndexError),
    #[error("chart: {0}")]
    Locate(#[from] LocateError),
    #[error("linear solve: {0}")]
    Solve(#[from] SolveError),
    #[error(transparent)]
    Flatten(#[from] crate::param::flatten::FlattenError),
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {problem}")]
    File { path: String, problem: String },
}

impl AppError {
    pub(crate) fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> AppError + '_ {
        move |source| AppError::Io {
            path: path.display().to_string(),
            source,
        }
    }

    pub(crate) fn file(path: &std::path::Path, problem: impl Into<String>) -> AppError {
        AppError::File {
            path: path.display().to_string(),
            problem: problem.into(),
        }
    }

    /// `got` per-vertex values where `expected` are needed.
    pub(crate) fn per_vertex(what: &'static str, got: usize, expected: usize) -> AppError {
        AppError::Length {
            what,
            got,
            expected,
            per: "vertices",
            per_one: "vertex",
        }
    }
}
