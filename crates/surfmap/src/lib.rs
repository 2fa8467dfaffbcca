//! # surfmap — variational surface maps
//!
//! Flip-free flattening of disc-like triangle meshes by Newton minimization of an
//! elastic energy (N. Litke, *Variational Methods in Surface Parameterization*, 2005,
//! §2.1/§3.1), distortion measures and pictures, geometry images (§3.2), fold-free
//! matching of two surfaces through them (§2.2, §3.2) and its applications (ch. 5).
//!
//! ## A complete run: read → flatten → measure → write
//!
//! ```
//! use surfmap::{Alpha, FlattenOptions, MeasureOptions, TriMesh, Uvs};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let dir = std::env::temp_dir().join(format!("surfmap-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! // A curved disc written to a file first, so that reading it is real (in practice:
//! // a scan as OBJ, OFF or PLY).
//! let input = dir.join("surface.ply");
//! surfmap::write_mesh(&input, &surfmap::mesh::generate::bumpy_disc(12, 0.5))?;
//!
//! // Read.
//! let mesh = surfmap::read_mesh(&input)?.mesh;
//!
//! // Flatten with Litke's energy, α = (length, area, angle) weights (normalized to sum 1).
//! let options = FlattenOptions::new(Alpha::new(1.0, 1.0, 2.0)?);
//! let map = surfmap::flatten(&mesh, &options)?;
//! assert!(map.converged);
//! assert_eq!(map.flipped_triangles, 0); // counted on the output: always 0
//! println!(
//!     "start {}, {} Newton iterations, energy {:.5}",
//!     map.start_description(),
//!     map.iterations,
//!     map.energy
//! );
//!
//! // Measure: the thesis's angle, area and length distortion, flips, overlap.
//! let report = surfmap::distortion_report_per_vertex(
//!     &mesh.positions,
//!     &mesh.triangles,
//!     &map.uvs,
//!     &MeasureOptions::default(),
//! )?;
//! assert_eq!(report.flipped_triangles, 0);
//! assert!(report.measures.angle.mean >= 1.0);
//!
//! // Write an OBJ with texture coordinates in [0, 1]² (atomically: temporary file + rename).
//! let output = dir.join("flat.obj");
//! let flat = TriMesh { uvs: Some(Uvs::PerVertex(map.normalized_uvs())), ..mesh };
//! surfmap::write_mesh(&output, &flat)?;
//! assert_eq!(surfmap::read_mesh(&output)?.mesh.vertex_uvs().map(<[_]>::len), Some(flat.num_vertices()));
//!
//! // Locate any point of the parameter domain on the surface: a triangle and
//! // barycentric coordinates, or None outside the map.
//! let locator = surfmap::PointLocator::new(&map.uvs, &flat.triangles)?;
//! let hit = locator.locate(map.uvs[0]).expect("a vertex's own UV lies on the map");
//! let p = hit.position(&flat.positions, &flat.triangles);
//! assert!((0..3).all(|k| (p[k] - flat.positions[0][k]).abs() < 1e-9)); // back at vertex 0
//! assert!(locator.locate([1e9, 1e9]).is_none());
//! std::fs::remove_dir_all(&dir)?;
//! # Ok(())
//! # }
//! ```
//!
//! A mesh that is not a disc gets an error listing every defect with the repair that
//! fixes it ([`FlattenError::NotADisc`], [`mesh::repair`]); holes (eyes, mouth) can be
//! filled for the solve with [`FlattenOptions::fill_holes`]. `examples/library.rs`
//! builds a mesh from arrays, fills its holes, reads the whole report, locates points
//! and matches the surface onto a moved copy (`matching::match_meshes`).
//!
//! ## Modules
//!
//! The modules follow the data flow; each uses only those above it (nothing downstream
//! is imported upstream):
//!
//! | module | what it holds |
//! |---|---|
//! | [`mesh`] | [`TriMesh`], [`Topology`], the validated [`Disc`], file io, validation, repairs, decimation, generated test surfaces |
//! | [`energy`] | the densities `W(a, d)` (Litke's (2.5) with weights [`Alpha`], symmetric Dirichlet, MIPS, ARAP), shared by flattening and matching |
//! | [`param`] | flattening: initial maps (LSCM, mean-value), per-triangle elements, projected Newton, the multilevel start, [`flatten`] |
//! | [`measure`] | distortion measures of any map, flips, global overlap |
//! | [`render`] | PNG pictures: UV layouts, checkerboard renders, plots |
//! | [`grid`] | regular `2^k + 1` grids over ω = `[0,1]²`: [`grid::Grid`], bilinear sampling with gradient, finite differences, restriction/prolongation, the typed Gaussian pyramid, Eikonal distances, harmonic extension |
//! | [`raster`] | geometry images: a flattened surface rasterized onto a grid (§3.2) |
//! | [`matching`] | surface matching: alignment in space, the matching energy (2.16) over deformations of the grid, the multiscale solve, fold checks, point maps, the match folder |
//! | [`apps`] | thesis ch. 5 on matches and maps: transfer, baking, morphs, rigs, glTF |
//! | [`report`] | the documents of a run: [`InspectReport`], [`FlattenReport`] (the CLI's JSON, the Python package's dictionaries) |
//! | [`output`] | what a flattening writes: [`flatten_to_mesh`] gives the mesh to write (per-vertex or per-corner UVs, or the flat layout), its seams and its report, for every front end |
//! | [`view`] | one self-contained interactive HTML page of a flattening, a match, a morph or rig, or a folder of results |
//! | [`batch`] | many mesh files on a thread pool, one bad mesh never stopping the rest, and their summary table |
//!
//! Internal building blocks are public for benchmarks and probes but hidden from these
//! docs and not part of the API: the sparse solver (`linsolve`, the only place `faer`
//! appears), the Newton solver and its per-triangle elements (`param::newton`,
//! `param::element`), the ARAP warm start (`param::arap`), file-system helpers
//! (`fsutil`) and test helpers (`testing`).

pub mod apps;
pub mod batch;
pub mod energy;
#[doc(hidden)]
pub mod fsutil;
pub mod grid;
#[doc(hidden)]
pub mod linsolve;
pub mod matching;
pub mod measure;
pub mod mesh;
pub mod output;
pub mod param;
pub mod raster;
pub mod render;
pub mod report;
#[doc(hidden)]
pub mod testing;
pub(crate) mod vec3;
pub mod view;

pub use energy::{Alpha, Energy};
pub use measure::{
    DistortionReport, MeasureError, MeasureOptions, distortion_report, distortion_report_per_vertex,
};
pub use mesh::io::{MeshFile, read_mesh, write_mesh, write_obj};
pub use mesh::{
    BoundaryLoop, Disc, IndexError, NotADisc, PointLocator, SurfacePoint, Topology, TriMesh, Uvs,
};
pub use output::{FlatMesh, UvLayout, flatten_to_mesh};
pub use param::flatten::{
    Bijective, CoarseLevel, Cut, CutStop, DistortionCuts, EnergyKind, FlattenError, FlattenOptions,
    FlattenSettings, Flattening, Guarantee, IterationLog, MaxDistortion, Multilevel,
    MultilevelKind, NewtonSettings, Preset, ProtrusionCuts, Seams, SettingsError, Start, StartKind,
    StartMap, StopReason, flatten, flatten_with_progress,
};
pub use param::normalize_uvs;
pub use param::plan::{Plan, plan};
pub use raster::{GeometryImages, GeometryImagesOptions};
pub use report::{FlattenReport, InspectReport};
