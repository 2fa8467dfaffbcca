//! # surfmap — variational surface maps
//!
//! Flip-free flattening of disc-like triangle meshes by Newton minimization of an
//! elastic energy (N. Litke, *Variational Methods in Surface Parameterization*, 2005,
//! §2.1/§3.1), distortion measures and pictures, and geometry images for matching
//! (§3.2).
//!
//! The modules follow the data flow: [`mesh`] → [`param`] → [`measure`] / [`render`]
//! → [`raster`]. Nothing downstream is imported upstream.

pub mod fsutil;
pub mod linsolve;
pub mod measure;
pub mod mesh;
pub mod param;
pub mod raster;
pub mod render;
#[doc(hidden)]
pub mod testing;

pub use mesh::{BoundaryLoop, Topology, TriMesh, Uvs};
