//! Regular grids over the image domain ω = `[0,1]²` (thesis §3.2): the grid type, bilinear
//! sampling with its gradient, finite differences, multigrid transfer, the Gaussian scale
//! pyramid, the anisotropic Eikonal solver and the harmonic extension.
//!
//! Everything here lives on an `N × N` grid, `N = 2^k + 1`: node `(i, j)` (row `i`, column
//! `j`) sits at `ξ = (j, i) / (N − 1)` and is stored at index `i · N + j`. The values are
//! `f64` or `[f64; D]` ([`Vector`]); operations on vector grids act component-wise.
//!
//! One file per concept: [`Grid`] (the container), [`value`] (what a grid may hold),
//! [`domain`] (ω, the similarity that places a flattening in it, valid sizes),
//! [`sample`] (bilinear sampling with gradient, the matcher's inner loop), [`derivative`]
//! (gradient and Laplacian at the nodes), [`multigrid`] (restriction and prolongation),
//! [`pyramid`] (Gaussian filtering as heat semigroup, σ_k = 2^−k), [`eikonal`] (distance
//! in a metric, Hopf–Lax update) and [`extend`] (harmonic extension outside a mask).
//!
//! The module knows nothing of meshes: [`raster`](crate::raster) turns a flattened
//! surface into grids, the matcher samples them.
//!
//! ```
//! use surfmap::grid::{Grid, MetricPyramid, Pyramid};
//!
//! # fn main() -> Result<(), surfmap::grid::GridError> {
//! // f(ξ) = ξ₀ ξ₁ on the 257² grid; node (i, j) sits at ξ = (j, i)/256.
//! let f = Grid::from_fn(257, |i, j| (j * i) as f64 / (256.0 * 256.0))?;
//! let (value, d0, d1) = f.sample_with_gradient([0.3, 0.5]);
//! assert!((value - 0.15).abs() < 1e-12 && (d0 - 0.5).abs() < 1e-12 && (d1 - 0.3).abs() < 1e-12);
//!
//! // A metric image [g11, g12, g22] and its pyramid: 2², 3², 5², …, 257², σ_k = 2^−k.
//! let g = Grid::new(257, [2.0, 0.5, 1.0])?;
//! let pyramid: MetricPyramid = Pyramid::new(g);
//! assert_eq!((pyramid.num_levels(), pyramid.level(3).size(), pyramid.sigma(3)), (9, 9, 0.125));
//! # Ok(())
//! # }
//! ```

pub mod derivative;
pub mod domain;
pub mod eikonal;
pub mod extend;
// The file is named after the concept it holds, like its siblings.
#[allow(clippy::module_inception)]
mod grid;
pub mod multigrid;
pub mod pyramid;
pub mod sample;
pub mod value;

pub use derivative::{gradient, laplacian};
pub use domain::{DomainTransform, MAX_SIZE, grid_level};
pub use eikonal::{seed_polyline, seed_region_boundary, solve_eikonal};
pub use extend::{HarmonicExtension, harmonic_extension};
pub use grid::Grid;
pub use pyramid::{MetricPyramid, Pyramid};
pub use sample::GridPoint;
pub use value::Vector;

/// What went wrong with a grid, and what to do about it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GridError {
    #[error(
        "grid size {size} is not 2^k + 1 between 3 and {max} (try 257, 513 or 1025)",
        max = MAX_SIZE
    )]
    BadSize { size: usize },
    #[error("{len} values given for a {size}×{size} grid, which has {} nodes", size * size)]
    DataLength { size: usize, len: usize },
    #[error("{what} is a {got}×{got} grid but must match the {want}×{want} grid it is used with")]
    SizeMismatch {
        what: &'static str,
        got: usize,
        want: usize,
    },
    #[error("the {size}×{size} grid is the coarsest (k = 0); there is no level to restrict to")]
    NoCoarserLevel { size: usize },
    #[error(
        "prolongating the {size}×{size} grid would exceed the largest supported grid ({max}×{max})",
        max = MAX_SIZE
    )]
    NoFinerLevel { size: usize },
    #[error("margin {margin} must lie in [0, 0.5)")]
    BadMargin { margin: f64 },
    #[error("UV of vertex {vertex} is not finite; the flattening failed")]
    NonFiniteUv { vertex: usize },
    #[error("the flattening has zero extent; nothing to place in the image domain")]
    DegenerateDomain,
    #[error(
        "the inside mask has no node, so there is nothing to extend from (for a rasterized surface: raise the grid size)"
    )]
    EmptyMask,
    #[error("linear solve for the harmonic extension failed: {0}")]
    Solve(String),
    #[error(
        "point {index} of the feature polyline is {point:?}; points must be finite and lie in [−1, 2]² (domain coordinates, ω = [0,1]²)"
    )]
    BadPoint { index: usize, point: [f64; 2] },
    #[error("Eikonal solver did not settle after {pops} updates; the metric is likely degenerate")]
    EikonalStalled { pops: usize },
}
