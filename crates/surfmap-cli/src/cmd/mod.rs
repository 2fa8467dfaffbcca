pub mod advice;
pub mod bake;
pub mod batch;
pub mod crop;
pub mod demo;
pub mod flatten;
pub mod images;
pub mod inspect;
pub mod matching;
pub mod matchio;
pub mod measure;
pub mod morph;
pub mod register;
pub mod retarget;
pub mod rig;
pub mod tradeoff;
pub mod transfer;
pub mod view;

use std::path::Path;
use surfmap::mesh::io::{MeshFile, read_mesh};

/// Reads a mesh; the reader's errors already name the file and the position.
pub fn load_mesh(path: &Path) -> anyhow::Result<MeshFile> {
    Ok(read_mesh(path)?)
}

/// Opt-in repairs shared by the commands that read a mesh; each one applied is
/// reported on stderr.
#[derive(clap::Args, Clone, Default)]
pub struct RepairArgs {
    /// Weld vertices closer than TOL (0 = exactly coincident) before anything else.
    #[arg(
        long,
        value_name = "TOL",
        num_args = 0..=1,
        default_missing_value = "0",
        allow_negative_numbers = true
    )]
    pub weld: Option<f64>,
    /// Remove faces with a repeated vertex or zero area, and faces that repeat another
    /// face (the same three vertices).
    #[arg(long)]
    pub drop_degenerate: bool,
    /// Flip faces to make the orientation consistent.
    #[arg(long)]
    pub reorient: bool,
    /// Keep only the largest connected component.
    #[arg(long, conflicts_with = "component")]
    pub keep_largest: bool,
    /// Keep only connected component N (numbered as `inspect` lists them).
    #[arg(long, value_name = "N")]
    pub component: Option<usize>,
    /// Remove vertices no face uses.
    #[arg(long)]
    pub drop_unreferenced: bool,
    /// Make the surface manifold without removing a face: cut every edge shared by more
    /// than two faces apart into sheets (faces paired by how smoothly they continue each
    /// other; a fin is cut loose), and split a vertex that joins separate fans of faces
    /// into one copy per fan. With --keep-largest (or --repair) the loose pieces go.
    #[arg(long)]
    pub fix_non_manifold: bool,
    /// Every repair that needs no parameter, for a raw scan: --drop-degenerate,
    /// --fix-non-manifold, --reorient, --keep-largest (unless --component is given),
    /// --drop-unreferenced. Each one that changes something is reported. A mesh written
    /// is the repaired one (its vertex numbers change when vertices are dropped or
    /// split); vertex ids read or written — landmarks, features, `match`'s
    /// correspondence, `crop`'s --center-vertex and --ids — are the file's.
    #[arg(long)]
    pub repair: bool,
}

impl RepairArgs {
    /// Whether any repair was asked for.
    pub fn asked(&self) -> bool {
        let Self {
            weld,
            drop_degenerate,
            reorient,
            keep_largest,
            component,
            drop_unreferenced,
            fix_non_manifold,
            repair,
        } = self;
        weld.is_some()
            || *drop_degenerate
            || *reorient
            || *keep_largest
            || component.is_some()
            || *drop_unreferenced
            || *fix_non_manifold
            || *repair
    }

    /// [`Self::apply`], and where each face of the result came from in `mesh`
    /// (`None` when no repair was asked for: the mesh is returned as read). The origins
    /// come from repairing a copy whose UVs are tags ([`surfmap::mesh::repair::FaceOrigins`]);
    /// a mesh with UVs of its own is repaired once more to keep them (the repairs are
    /// deterministic: the same faces come out).
    pub fn apply_tracked(
        &self,
        mesh: &surfmap::TriMesh,
        quiet: bool,
    ) -> anyhow::Result<(surfmap::TriMesh, Option<surfmap::mesh::repair::FaceOrigins>)> {
        use anyhow::Context as _;
        use surfmap::mesh::repair::FaceOrigins;
        if !self.asked() {
            return Ok((mesh.clone(), None));
        }
        let mut tagged = self.apply(FaceOrigins::tag(mesh), quiet)?;
        let origins = FaceOrigins::read(&tagged)
            .context("internal error: the repairs lost track of the input's faces")?;
        let repaired = if mesh.uvs.is_some() {
            let own = self.apply(mesh.clone(), true)?;
            anyhow::ensure!(
                own.triangles == tagged.triangles,
                "internal error: the repairs did not repeat themselves"
            );
            own
        } else {
            tagged.uvs = None;
            tagged
        };
        Ok((repaired, Some(origins)))
    }

    pub fn apply(
        &self,
        mut mesh: surfmap::TriMesh,
        quiet: bool,
    ) -> anyhow::Result<surfmap::TriMesh> {
        use surfmap::mesh::repair;
        let say = |s: String| {
            if !quiet {
                eprintln!("repair: {s}");
            }
        };
        if let Some(tol) = self.weld {
            if tol.is_nan() || tol < 0.0 {
                anyhow::bail!("--weld tolerance must be ≥ 0, got {tol}");
            }
            let (m, n) = repair::weld(&mesh, tol);
            say(format!("welded {n} vertices (tolerance {tol})"));
            mesh = m;
        }
        // With --repair only the repairs that change something are reported.
        let all = self.repair;
        let say_if = |asked: bool, n: usize, s: String| {
            if asked || n > 0 {
                say(s)
            }
        };
        if self.drop_degenerate || all {
            let (m, n) = repair::drop_degenerate(&mesh);
            say_if(
                self.drop_degenerate,
                n,
                format!("dropped {n} degenerate or repeated faces"),
            );
            mesh = m;
        }
        if all {
            // First, so that the input's unused vertices are counted on their own line
            // (taking one component would drop them silently with the others).
            let (m, n) = repair::drop_unreferenced(&mesh);
            say_if(false, n, format!("dropped {n} unreferenced vertices"));
            mesh = m;
        }
        if self.fix_non_manifold || all {
            let (m, done) = repair::fix_non_manifold(&mesh);
            say_if(
                self.fix_non_manifold,
                done.cut_edges + done.split_vertices,
                format!(
                    "non-manifold: cut {} edges with more than two faces apart into sheets ({} faces left unpaired{}), split {} vertices",
                    done.cut_edges,
                    done.unpaired_faces,
                    match done.dropped_faces {
                        0 => String::new(),
                        n => format!(", {n} removed where the sheets could not be separated"),
                    },
                    done.split_vertices
                ),
            );
            mesh = m;
        }
        if self.reorient || all {
            match repair::reorient(&mesh) {
                Some((m, n)) => {
                    say_if(
                        self.reorient,
                        n,
                        format!("flipped {n} faces for a consistent orientation"),
                    );
                    mesh = m;
                }
                // Under --repair a non-orientable surface is left for the defect report.
                None if !self.reorient => {}
                None => anyhow::bail!(
                    "--reorient: the surface is not orientable (a Möbius-like piece); it cannot be made consistent"
                ),
            }
        }
        if self.keep_largest || self.component.is_some() || all {
            let choice = match self.component {
                Some(i) => repair::ComponentChoice::Index(i),
                None => repair::ComponentChoice::Largest,
            };
            let Some((m, n)) = repair::keep_component(&mesh, choice) else {
                if self.component.is_none() {
                    // No face at all: the defect report says so.
                    return Ok(mesh);
                }
                anyhow::bail!(
                    "--component {}: no such component ({} found)",
                    self.component.unwrap_or(0),
                    surfmap::Topology::new(&mesh).num_components
                )
            };
            say_if(
                self.keep_largest || self.component.is_some(),
                n,
                format!("kept one component, dropped {n} faces of the others"),
            );
            mesh = m;
        }
        if self.drop_unreferenced || all {
            let (m, n) = repair::drop_unreferenced(&mesh);
            say_if(
                self.drop_unreferenced,
                n,
                format!("dropped {n} unreferenced vertices"),
            );
            mesh = m;
        }
        Ok(mesh)
    }
}
