//! # surfmap — variational surface maps
//!
//! Flip-free flattening of disc-like triangle meshes by Newton minimization of an
//! elastic energy (N. Litke, *Variational Methods in Surface Parameterization*, 2005,
//! §2.1/§3.1), distortion measures and pictures, and geometry images for matching
//! (§3.2).
//!
//! The modules follow the data flow: [`mesh`] → [`param`] → [`measure`] / [`render`]
//! → [`raster`]. Nothing downstream is imported upstream.
//!
//! ```
//! use surfmap::measure::{MeasureOptions, distortion_report_per_vertex};
//! use surfmap::mesh::generate::bumpy_disc;
//! use surfmap::mesh::io::{read_mesh, write_obj};
//! use surfmap::param::density::{EnergyKind, Litke};
//! use surfmap::param::flatten::{FlattenOptions, flatten};
//! use surfmap::{TriMesh, Uvs};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // A curved disc (in practice: `read_mesh(path)?.mesh`).
//! let mesh = bumpy_disc(12, 0.5);
//! // Flatten with α = (length, area, angle) weights; normalized to sum 1.
//! let options = FlattenOptions {
//!     energy: EnergyKind::Litke(Litke::new(1.0, 1.0, 2.0)?),
//!     ..Default::default()
//! };
//! let map = flatten(&mesh, &options)?;
//! assert!(map.converged);
//! assert_eq!(map.flipped_triangles, 0); // checked on the output, always 0
//!
//! // Score it like any other tool's map.
//! let report = distortion_report_per_vertex(
//!     &mesh.positions,
//!     &mesh.triangles,
//!     &map.uvs,
//!     &MeasureOptions::default(),
//! )?;
//! assert_eq!(report.flipped_triangles, 0);
//! assert!(report.measures.angle.mean >= 1.0);
//!
//! // Write an OBJ with texture coordinates (atomically: temporary file + rename).
//! let out = TriMesh { uvs: Some(Uvs::PerVertex(map.uvs.clone())), ..mesh.clone() };
//! let path = std::env::temp_dir().join(format!("surfmap-doc-{}.obj", std::process::id()));
//! write_obj(&path, &out, None)?;
//! assert_eq!(read_mesh(&path)?.mesh.vertex_uvs().map(<[_]>::len), Some(mesh.positions.len()));
//! std::fs::remove_file(&path)?;
//! # Ok(())
//! # }
//! ```

pub mod fsutil;
pub mod linsolve;
pub mod measure;
pub mod mesh;
pub mod param;
pub mod raster;
pub mod render;
#[doc(hidden)]
pub mod testing;
pub(crate) mod vec3;

pub use mesh::{BoundaryLoop, PointLocator, SurfacePoint, Topology, TriMesh, Uvs};
