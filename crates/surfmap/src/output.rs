//! What a flattening writes, built once for every front end: [`flatten_to_mesh`]
//! flattens a mesh and gives back the mesh to write — the input with its texture
//! coordinates (one per vertex, or per corner, split along the seams, when the surface
//! was cut), or the flat layout itself — with the flattening it came from (seams, solver
//! log) and, on demand, its report ([`FlatMesh::report`]).
//!
//! The command line's `surfmap flatten` (one mesh or a batch) and the Python package's
//! `flatten`, `flatten_file` and `flatten_many` write through it; they only map their
//! arguments, write the files and print.

use std::io;
use std::path::Path;

use crate::measure::MeasureError;
use crate::mesh::{TriMesh, Uvs};
use crate::param::flatten::{
    FlattenError, FlattenOptions, Flattening, IterationLog, Seams, flatten_with_progress,
};
use crate::report::{DefectWording, FlattenReport};

/// How the map is written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UvLayout {
    /// Texture coordinates scaled into `[0, 1]²`, the aspect ratio kept
    /// ([`Flattening::normalized_uvs`]); else in the mesh's length units.
    pub normalize: bool,
    /// The flat mesh itself: positions `(u, v, 0)` (cut open along the seams), for
    /// viewing the layout; else the input's positions and triangles.
    pub uv_as_positions: bool,
}

/// A flattening with the mesh to write.
#[derive(Clone, Debug)]
pub struct FlatMesh {
    /// The mesh flattened, as given.
    pub input: TriMesh,
    pub flattening: Flattening,
    /// The mesh to write ([`UvLayout`]): the input's positions and triangles with their
    /// texture coordinates, or the flat layout with its own.
    pub output: TriMesh,
}

/// Flattens `mesh` with `options` (`progress` sees every Newton iteration, as in
/// [`flatten_with_progress`]) and lays the map out as `layout` asks.
pub fn flatten_to_mesh(
    mesh: TriMesh,
    options: &FlattenOptions,
    layout: UvLayout,
    progress: &mut dyn FnMut(&IterationLog),
) -> Result<FlatMesh, FlattenError> {
    let flattening = flatten_with_progress(&mesh, options, progress)?;
    Ok(FlatMesh::new(mesh, flattening, layout))
}

impl FlatMesh {
    /// The flattening `flattening` of `input`, laid out as `layout` asks.
    pub fn new(input: TriMesh, flattening: Flattening, layout: UvLayout) -> Self {
        let uvs = flattening.texture_coordinates(layout.normalize);
        let output = if !layout.uv_as_positions {
            TriMesh {
                uvs: Some(uvs),
                ..TriMesh::new(input.positions.clone(), input.triangles.clone())
            }
        } else {
            let (coords, triangles) = match uvs {
                Uvs::PerVertex(coords) => (coords, input.triangles.clone()),
                Uvs::PerCorner { coords, indices } => (coords, indices),
            };
            TriMesh {
                positions: coords.iter().map(|p| [p[0], p[1], 0.0]).collect(),
                triangles,
                uvs: Some(Uvs::PerVertex(coords)),
            }
        };
        Self {
            input,
            flattening,
            output,
        }
    }

    /// The seams, when the surface was cut open.
    pub fn seams(&self) -> Option<&Seams> {
        self.flattening.seams.as_ref()
    }

    /// The written texture coordinates as arrays, as an OBJ file's `vt` and `f v/vt`:
    /// the UVs and, per triangle of the output, the UVs of its corners (the triangles
    /// themselves for one UV per vertex).
    pub fn uv_arrays(&self) -> (&[[f64; 2]], &[[u32; 3]]) {
        match &self.output.uvs {
            Some(Uvs::PerCorner { coords, indices }) => (coords, indices),
            Some(Uvs::PerVertex(coords)) => (coords, &self.output.triangles),
            None => unreachable!("a flat mesh has texture coordinates"),
        }
    }

    /// The report of this flattening ([`FlattenReport::measure`]: the map measured,
    /// the input's defects worded by `wording`), `file` the input's path if it was read
    /// from one.
    pub fn report(
        &self,
        file: Option<&Path>,
        wording: DefectWording,
    ) -> Result<FlattenReport<'_>, MeasureError> {
        FlattenReport::measure(file, &self.input, &self.flattening, wording)
    }

    /// Writes the seams as an OBJ ([`write_seams`]); `Ok(false)` (nothing written)
    /// when the surface was not cut.
    pub fn write_seams(&self, path: &Path) -> io::Result<bool> {
        let Some(seams) = self.seams() else {
            return Ok(false);
        };
        write_seams(path, &self.input.positions, seams)?;
        Ok(true)
    }
}

/// Writes seams as an OBJ (atomically): every vertex (`positions`, the input's), one
/// `l` line per seam edge (1-based, as OBJ counts).
pub fn write_seams(path: &Path, positions: &[[f64; 3]], seams: &Seams) -> io::Result<()> {
    crate::fsutil::write_atomically(path, |w| {
        writeln!(
            w,
            "# seams of surfmap flatten: {} edges, length {}",
            seams.edges.len(),
            seams.length
        )?;
        for p in positions {
            writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
        }
        for [a, b] in &seams.edges {
            writeln!(w, "l {} {}", a + 1, b + 1)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::mesh::validate::Defect;

    /// A disc keeps its positions and triangles and gets one UV per vertex; normalized,
    /// they fill the unit square.
    #[test]
    fn a_disc_is_written_per_vertex() {
        let mesh = generate::bumpy_disc(6, 0.3);
        let layout = UvLayout {
            normalize: true,
            ..Default::default()
        };
        let flat = flatten_to_mesh(
            mesh.clone(),
            &FlattenOptions::default(),
            layout,
            &mut |_| {},
        )
        .unwrap();
        assert_eq!(flat.output.positions, mesh.positions);
        assert_eq!(flat.output.triangles, mesh.triangles);
        assert!(flat.seams().is_none());
        let (uv, corners) = flat.uv_arrays();
        assert_eq!(uv, &flat.flattening.normalized_uvs()[..]);
        assert_eq!(corners, &mesh.triangles[..]);
        let max = uv.iter().flatten().fold(0.0f64, |m, &x| m.max(x));
        assert!((max - 1.0).abs() < 1e-15, "{max}");
        let report = flat.report(None, Defect::message).unwrap();
        assert_eq!(report.iterations, flat.flattening.iterations);
    }

    /// A closed surface is cut: per-corner UVs whose corners, laid out flat, are the
    /// written positions; every flat triangle keeps its orientation (no flip).
    #[test]
    fn a_cut_surface_is_written_per_corner_or_as_its_layout() {
        let mesh = generate::octahedron();
        let options = FlattenOptions::default();
        let flat =
            flatten_to_mesh(mesh.clone(), &options, UvLayout::default(), &mut |_| {}).unwrap();
        let seams = flat.seams().expect("a closed surface is cut open");
        assert!(!seams.edges.is_empty());
        let (uv, corners) = flat.uv_arrays();
        assert!(uv.len() > mesh.positions.len());
        assert_eq!(corners.len(), mesh.triangles.len());
        assert_eq!(crate::param::count_flipped(uv, corners), 0);
        let layout = UvLayout {
            uv_as_positions: true,
            ..Default::default()
        };
        let flat_layout = FlatMesh::new(mesh.clone(), flat.flattening.clone(), layout);
        assert_eq!(flat_layout.output.triangles, corners);
        for (p, q) in flat_layout.output.positions.iter().zip(uv) {
            assert_eq!(*p, [q[0], q[1], 0.0]);
        }
        // The seams file lists the input's vertices and the seam edges, 1-based.
        let path = std::env::temp_dir().join(format!("surfmap-seams-{}.obj", std::process::id()));
        assert!(flat.write_seams(&path).unwrap());
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(text.lines().filter(|l| l.starts_with("v ")).count(), 6);
        let lines: Vec<[u32; 2]> = text
            .lines()
            .filter_map(|l| l.strip_prefix("l "))
            .map(|l| {
                let v: Vec<u32> = l.split(' ').map(|x| x.parse().unwrap()).collect();
                [v[0] - 1, v[1] - 1]
            })
            .collect();
        assert_eq!(lines, seams.edges);
    }
}
