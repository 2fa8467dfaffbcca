//! Distortion measures of a map surface → UV (thesis §4.1.4): per-triangle singular
//! values of the Jacobian, aggregated into the thesis's and the field's measures, flips
//! and global overlap, plus the Shay–Solomon–Stein benchmark columns.

pub mod benchmark;
pub mod charts;
pub mod jacobian;
pub mod overlap;
pub mod report;

pub use benchmark::{BENCHMARK_CSV_HEADER, BenchmarkScores, benchmark_scores};
pub use overlap::{BoundaryOverlap, boundary_overlap};
pub use report::{
    AreaDistortion, DistortionReport, Measure, MeasureOptions, MinMeanMax, Stretch, ThesisMeasures,
    TriangleSingularValues, corner_uvs_from_indexed, corner_uvs_from_vertex_uvs, distortion_report,
    distortion_report_per_vertex, per_triangle_measure, triangle_singular_values,
};

/// Why a map could not be measured.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeasureError {
    #[error("the mesh has no triangles: nothing to measure")]
    NoTriangles,
    #[error("{uvs} UVs for {vertices} vertices: per-vertex UVs need exactly one UV per vertex")]
    UvCount { uvs: usize, vertices: usize },
    #[error(
        "{uv_triangles} UV triangles for {triangles} triangles: give one UV triangle per mesh triangle"
    )]
    UvIndexCount {
        uv_triangles: usize,
        triangles: usize,
    },
    #[error(transparent)]
    Index(#[from] crate::mesh::IndexError),
    #[error("triangle {triangle} uses UV {index}, but there are only {len} UVs")]
    UvIndexOutOfRange {
        triangle: usize,
        index: u32,
        len: usize,
    },
    #[error(
        "triangle {triangle} has a non-finite UV coordinate (NaN or infinity): fix or drop the UVs"
    )]
    NonFiniteUv { triangle: usize },
}
