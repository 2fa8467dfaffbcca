//! Geometry images (thesis §3.2): a flattened surface placed in ω = \[0,1\]² and sampled on
//! a regular `N × N` grid (`N = 2^k + 1`): inside mask, triangle id and barycentric
//! coordinates, 3D position, metric `g`, mean curvature `h`, texture colour, signed
//! distance to the domain boundary, feature distance maps in the metric `g`, harmonic
//! extension of `h` and `g` outside the domain, and a Gaussian scale pyramid.
//!
//! One file per concept: [`domain`] (ω and the grid), [`rasterize`], [`metric`],
//! [`curvature`], [`boundary_distance`], [`eikonal`], [`features`], [`extend`],
//! [`pyramid`], [`npy`], [`picture`]; [`images`] ties them together.

pub mod boundary;
pub mod boundary_distance;
pub mod curvature;
pub mod domain;
pub mod eikonal;
pub mod extend;
pub mod features;
pub mod images;
pub mod metric;
pub mod npy;
pub mod output;
pub mod picture;
pub mod pyramid;
pub mod rasterize;
#[cfg(test)]
pub(crate) mod testmesh;

pub use domain::DomainTransform;
pub use features::{FeatureCurve, FeatureFile, FeatureMask, FeatureSource};
pub use images::{GeometryImages, GeometryImagesOptions, SurfaceScale, TextureImage};
pub use pyramid::{Pyramid, PyramidLevel};
pub use rasterize::Rasterization;

/// What went wrong while building geometry images, and what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum RasterError {
    #[error("grid size {size} is not 2^k + 1 between 3 and {max} (try 257, 513, 1025 or 2049)", max = domain::MAX_SIZE)]
    BadSize { size: usize },
    #[error("invalid option: {0}")]
    BadOption(String),
    #[error("UV of vertex {vertex} is not finite; the flattening failed")]
    NonFiniteUv { vertex: usize },
    #[error("the flattening has zero extent; nothing to rasterize")]
    DegenerateDomain,
    #[error("{count} UVs given for a mesh with {num_vertices} vertices")]
    UvCount { count: usize, num_vertices: usize },
    #[error("triangle {triangle} uses vertex {vertex}, but the mesh has {num_vertices} vertices")]
    BadVertexIndex {
        triangle: usize,
        vertex: usize,
        num_vertices: usize,
    },
    #[error(
        "triangle {triangle} is flipped or degenerate in the flattening (signed area {signed_area:e}); geometry images need a flip-free flattening"
    )]
    FlippedTriangle { triangle: usize, signed_area: f64 },
    #[error("the flattening covers no grid node; raise the grid size")]
    EmptyDomain,
    #[error("feature '{name}': {problem}")]
    Feature { name: String, problem: String },
    #[error("feature file: {0}")]
    FeatureFile(String),
    #[error(
        "feature mask is {got_width}×{got_height} pixels but must be {want_width}×{want_height} (the size of the mesh's texture)"
    )]
    MaskSize {
        got_width: u32,
        got_height: u32,
        want_width: u32,
        want_height: u32,
    },
    #[error("the mesh has no texture coordinates; a feature mask or texture is painted over them")]
    NoTextureCoordinates,
    #[error("texture image: {0}")]
    Texture(String),
    #[error("linear solve for the harmonic extension failed: {0}")]
    Solve(String),
    #[error("Eikonal solver did not settle after {pops} updates; the metric is likely degenerate")]
    EikonalStalled { pops: usize },
    #[error("image I/O: {0}")]
    Io(#[from] std::io::Error),
}
