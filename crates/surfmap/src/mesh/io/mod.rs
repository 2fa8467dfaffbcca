//! Mesh files in and out: Wavefront OBJ, OFF and PLY (ASCII, binary little and big endian).
//!
//! Reading keeps the file's vertex order and every vertex record (also unreferenced ones), so
//! registered meshes keep their vertex-i ↔ vertex-i correspondence. Polygons are
//! fan-triangulated `(a, b, c), (a, c, d), …`. Faces with repeated indices or zero area are
//! kept (validation reports them); a face with fewer than 3 vertices or an index out of range
//! is a [`ReadError`] naming the line (text) or byte offset (binary).
//!
//! All three readers are hand-written over an in-memory byte slice. `tobj` was measured and
//! rejected because it renumbers vertices per object and drops unreferenced ones (it read
//! `faces/flame/flame_scan.obj` as 47591 instead of 47653 vertices); `ply-rs-bw` is fast enough
//! (igea.ply in 20–40 ms) but reports binary errors by element index, not byte offset.
//!
//! Writers go through `fsutil::write_atomically`; text formats print every `f64` with
//! `{}` (the shortest string that parses back to the same bits), PLY writes doubles.

mod obj;
mod off;
mod ply;

pub use obj::{ObjMaterial, write_obj};
pub use off::write_off;
pub use ply::write_ply;

use std::fmt;
use std::path::{Path, PathBuf};

use super::{TriMesh, Uvs};

/// A mesh file format, chosen by file extension (case-insensitive).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    Obj,
    Off,
    Ply,
}

impl Format {
    /// Every supported format, in the order the error messages list them.
    pub const ALL: [Format; 3] = [Format::Obj, Format::Off, Format::Ply];

    /// The extension without the dot, lower case.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Obj => "obj",
            Format::Off => "off",
            Format::Ply => "ply",
        }
    }

    /// The format named by `path`'s extension (`.obj`, `.off`, `.ply`, any case).
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?;
        Format::ALL
            .into_iter()
            .find(|f| ext.eq_ignore_ascii_case(f.extension()))
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.extension())
    }
}

/// A mesh as read from a file, with what the file said about itself.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshFile {
    pub mesh: TriMesh,
    pub format: Format,
    /// Faces as stored in the file (a quad counts once; `mesh.triangles` has two for it).
    pub stored_faces: usize,
    /// OBJ only: the `map_Kd` texture of the material library, resolved against the `.mtl`'s
    /// folder, when the `.mtl` exists and names one. The image itself is not checked.
    pub texture: Option<PathBuf>,
}

/// Where in a file a problem was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// 1-based line number (text formats and PLY headers).
    Line(usize),
    /// 0-based byte offset from the start of the file (binary PLY bodies).
    Byte(u64),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(n) => write!(f, "line {n}"),
            Location::Byte(n) => write!(f, "byte offset {n}"),
        }
    }
}

/// Why a mesh file could not be read.
///
/// `path` is empty for [`read_mesh_from_bytes`]; it is then shown as `<bytes>`.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("cannot read {}: {source}", shown(.path))]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "{}: unknown mesh file extension; supported are .obj, .off and .ply (any case)",
        shown(.path)
    )]
    UnknownExtension { path: PathBuf },
    #[error("{}: {at}: expected {expected}, found {found}", shown(.path))]
    Syntax {
        path: PathBuf,
        at: Location,
        expected: String,
        found: String,
    },
    #[error(
        "{}: {at}: {what} index {index} out of range (file has {count} {what} records)",
        shown(.path)
    )]
    IndexOutOfRange {
        path: PathBuf,
        at: Location,
        /// "vertex" or "texture coordinate".
        what: &'static str,
        /// The index as written in the file (1-based or negative in OBJ, 0-based elsewhere).
        index: i64,
        /// How many records of that kind the file has (at that point, for OBJ's relative indices).
        count: usize,
    },
    #[error(
        "{}: {at}: face with {corners} vertices; a face needs at least 3",
        shown(.path)
    )]
    FaceTooSmall {
        path: PathBuf,
        at: Location,
        corners: usize,
    },
    #[error("{}: {at}: the file ends early; expected {expected}", shown(.path))]
    Truncated {
        path: PathBuf,
        at: Location,
        expected: String,
    },
    #[error(
        "{}: {at}: {feature} is not supported; convert the file (e.g. to binary PLY or OBJ)",
        shown(.path)
    )]
    Unsupported {
        path: PathBuf,
        at: Location,
        feature: String,
    },
    #[error(
        "{}: {at}: byte 0x{byte:02x} is not text, but a .{format} file is text: this one holds binary data (another format under a .{format} name, or a damaged file); export the mesh again as text {upper}, or as PLY",
        shown(.path),
        upper = .format.extension().to_uppercase()
    )]
    NotText {
        path: PathBuf,
        at: Location,
        /// The first byte that is not text.
        byte: u8,
        format: Format,
    },
    #[error(
        "{}: {at}: {count} {what} are more than the 4294967295 a mesh can index",
        shown(.path)
    )]
    TooMany {
        path: PathBuf,
        at: Location,
        what: &'static str,
        count: u64,
    },
}

/// Why a mesh could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("cannot write {}: {source}", shown(.path))]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "{}: unknown mesh file extension; supported are .obj, .off and .ply (any case)",
        shown(.path)
    )]
    UnknownExtension { path: PathBuf },
    #[error("{}: the mesh is inconsistent and was not written: {problem}", shown(.path))]
    InvalidMesh { path: PathBuf, problem: String },
}

fn shown(path: &Path) -> String {
    if path.as_os_str().is_empty() {
        "<bytes>".to_owned()
    } else {
        path.display().to_string()
    }
}

impl ReadError {
    /// The location in the file, when the error has one.
    pub fn location(&self) -> Option<Location> {
        match self {
            ReadError::Io { .. } | ReadError::UnknownExtension { .. } => None,
            ReadError::Syntax { at, .. }
            | ReadError::IndexOutOfRange { at, .. }
            | ReadError::FaceTooSmall { at, .. }
            | ReadError::Truncated { at, .. }
            | ReadError::Unsupported { at, .. }
            | ReadError::NotText { at, .. }
            | ReadError::TooMany { at, .. } => Some(*at),
        }
    }

    fn with_path(mut self, file: &Path) -> Self {
        match &mut self {
            ReadError::Io { path, .. }
            | ReadError::UnknownExtension { path }
            | ReadError::Syntax { path, .. }
            | ReadError::IndexOutOfRange { path, .. }
            | ReadError::FaceTooSmall { path, .. }
            | ReadError::Truncated { path, .. }
            | ReadError::Unsupported { path, .. }
            | ReadError::NotText { path, .. }
            | ReadError::TooMany { path, .. } => *path = file.to_path_buf(),
        }
        self
    }

    pub(crate) fn syntax(at: Location, expected: impl Into<String>, found: &[u8]) -> Self {
        ReadError::Syntax {
            path: PathBuf::new(),
            at,
            expected: expected.into(),
            found: describe_token(found),
        }
    }

    pub(crate) fn truncated(at: Location, expected: impl Into<String>) -> Self {
        ReadError::Truncated {
            path: PathBuf::new(),
            at,
            expected: expected.into(),
        }
    }

    pub(crate) fn unsupported(at: Location, feature: impl Into<String>) -> Self {
        ReadError::Unsupported {
            path: PathBuf::new(),
            at,
            feature: feature.into(),
        }
    }

    pub(crate) fn out_of_range(at: Location, what: &'static str, index: i64, count: usize) -> Self {
        ReadError::IndexOutOfRange {
            path: PathBuf::new(),
            at,
            what,
            index,
            count,
        }
    }

    pub(crate) fn too_small(at: Location, corners: usize) -> Self {
        ReadError::FaceTooSmall {
            path: PathBuf::new(),
            at,
            corners,
        }
    }

    pub(crate) fn too_many(at: Location, what: &'static str, count: u64) -> Self {
        ReadError::TooMany {
            path: PathBuf::new(),
            at,
            what,
            count,
        }
    }
}

/// A token quoted for an error message: at most 40 characters, invalid UTF-8 replaced.
fn describe_token(token: &[u8]) -> String {
    if token.is_empty() {
        return "nothing".to_owned();
    }
    let text = String::from_utf8_lossy(&token[..token.len().min(40)]);
    let more = if token.len() > 40 { "…" } else { "" };
    format!("'{text}{more}'")
}

/// What a format parser hands back before the file-level fields are added.
pub(crate) struct Parsed {
    pub mesh: TriMesh,
    pub stored_faces: usize,
    /// OBJ `mtllib` file names, in order.
    pub material_libraries: Vec<String>,
    /// OBJ: the first `usemtl` name.
    pub first_material: Option<String>,
}

/// Reads a mesh file; the format is chosen by the extension (`.obj`, `.off`, `.ply`, any case).
///
/// For OBJ the `map_Kd` texture of the material library is looked up too (see
/// [`MeshFile::texture`]).
pub fn read_mesh(path: &Path) -> Result<MeshFile, ReadError> {
    let format = Format::from_path(path).ok_or_else(|| ReadError::UnknownExtension {
        path: path.to_path_buf(),
    })?;
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let parsed = parse(&bytes, format).map_err(|e| e.with_path(path))?;
    let texture = if format == Format::Obj {
        obj::find_texture(
            path,
            &parsed.material_libraries,
            parsed.first_material.as_deref(),
        )
    } else {
        None
    };
    Ok(MeshFile {
        mesh: parsed.mesh,
        format,
        stored_faces: parsed.stored_faces,
        texture,
    })
}

/// Reads a mesh from bytes in the given format (no texture lookup: `texture` is `None`).
/// Errors carry an empty path, shown as `<bytes>`.
pub fn read_mesh_from_bytes(bytes: &[u8], format: Format) -> Result<MeshFile, ReadError> {
    let parsed = parse(bytes, format)?;
    Ok(MeshFile {
        mesh: parsed.mesh,
        format,
        stored_faces: parsed.stored_faces,
        texture: None,
    })
}

fn parse(bytes: &[u8], format: Format) -> Result<Parsed, ReadError> {
    match format {
        Format::Obj => check_text(bytes, format).and_then(|()| obj::parse(bytes)),
        Format::Off => check_text(bytes, format).and_then(|()| off::parse(bytes)),
        Format::Ply => ply::parse(bytes),
    }
}

/// A text format's bytes must be text: the first control byte other than tab, line
/// breaks, form feed and a DOS end-of-file mark (0x1A) is an error naming it, so that a
/// binary file under a text format's name is refused as such instead of read as a file
/// of unknown lines (an empty mesh).
fn check_text(bytes: &[u8], format: Format) -> Result<(), ReadError> {
    let binary =
        |b: u8| (b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0b | 0x0c | 0x1a)) || b == 0x7f;
    match bytes.iter().position(|&b| binary(b)) {
        None => Ok(()),
        Some(offset) => Err(ReadError::NotText {
            path: PathBuf::new(),
            at: Location::Byte(offset as u64),
            byte: bytes[offset],
            format,
        }),
    }
}

/// Writes a mesh; the format is chosen by the extension. OBJ is written without material.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<(), WriteError> {
    match Format::from_path(path) {
        Some(Format::Obj) => write_obj(path, mesh, None),
        Some(Format::Off) => write_off(path, mesh),
        Some(Format::Ply) => write_ply(path, mesh),
        None => Err(WriteError::UnknownExtension {
            path: path.to_path_buf(),
        }),
    }
}

/// Checks what a writer relies on: triangle indices in range and UV arrays of matching size.
fn check_writable(path: &Path, mesh: &TriMesh) -> Result<(), WriteError> {
    let invalid = |problem: String| WriteError::InvalidMesh {
        path: path.to_path_buf(),
        problem,
    };
    let nv = mesh.positions.len();
    if nv > u32::MAX as usize {
        return Err(invalid(format!("{nv} vertices cannot be indexed by u32")));
    }
    mesh.check_indices().map_err(|e| invalid(e.to_string()))?;
    match &mesh.uvs {
        None => {}
        Some(Uvs::PerVertex(uv)) if uv.len() != nv => {
            return Err(invalid(format!(
                "{} per-vertex UVs for {nv} vertices",
                uv.len()
            )));
        }
        Some(Uvs::PerVertex(_)) => {}
        Some(Uvs::PerCorner { coords, indices }) => {
            if indices.len() != mesh.triangles.len() {
                return Err(invalid(format!(
                    "{} per-corner UV index triples for {} triangles",
                    indices.len(),
                    mesh.triangles.len()
                )));
            }
            if let Some(t) = indices
                .iter()
                .position(|tri| tri.iter().any(|&i| i as usize >= coords.len()))
            {
                return Err(invalid(format!(
                    "UV triple {t} {:?} uses a coordinate beyond the {} UV coordinates",
                    indices[t],
                    coords.len()
                )));
            }
        }
    }
    Ok(())
}

fn write_error(path: &Path) -> impl FnOnce(std::io::Error) -> WriteError + '_ {
    move |source| WriteError::Io {
        path: path.to_path_buf(),
        source,
    }
}

// ---------------------------------------------------------------------------------------------
// Small byte-level helpers shared by the text parsers.

/// Parses an ASCII decimal float (Rust syntax: also `inf`, `NaN`).
#[inline]
pub(crate) fn parse_f64(token: &[u8]) -> Option<f64> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

/// Parses an ASCII decimal integer with optional sign.
#[inline]
pub(crate) fn parse_i64(token: &[u8]) -> Option<i64> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

/// Whitespace-separated tokens of a line.
#[inline]
pub(crate) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

/// The lines of a text file with 1-based numbers, `\r` and everything from `#` on removed.
pub(crate) fn content_lines(bytes: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    bytes.split(|&b| b == b'\n').enumerate().map(|(i, line)| {
        let line = match line.iter().position(|&b| b == b'#') {
            Some(p) => &line[..p],
            None => line,
        };
        (i + 1, line)
    })
}

/// Fan triangulation of a polygon: `(c0, c1, c2), (c0, c2, c3), …`.
#[inline]
pub(crate) fn fan(corners: &[u32], out: &mut Vec<[u32; 3]>) {
    if let Some((&first, rest)) = corners.split_first() {
        for pair in rest.windows(2) {
            out.push([first, pair[0], pair[1]]);
        }
    }
}

/// A capacity for `count` records that cannot exceed what `available` bytes could hold.
#[inline]
pub(crate) fn capped(count: u64, available: usize, min_record_bytes: usize) -> usize {
    let most = available / min_record_bytes.max(1);
    usize::try_from(count).map_or(most, |c| c.min(most))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    pub(crate) fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("surfmap-io-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A small mesh with awkward coordinates (not exactly representable in decimal, tiny,
    /// huge, negative zero) so that exact round trips are a real check.
    fn awkward_mesh() -> TriMesh {
        let positions = vec![
            [0.1, 0.2, 0.3],
            [1.0 / 3.0, -2.0 / 7.0, 1e-310],
            [-0.0, 6.02214076e23, std::f64::consts::PI],
            [
                f64::MIN_POSITIVE,
                -1.7976931348623157e308,
                123456789.12345679,
            ],
            [5.0, 0.0, -1e-5], // unreferenced vertex must survive
        ];
        TriMesh::new(positions, vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]])
    }

    fn assert_bits_equal(a: &[[f64; 3]], b: &[[f64; 3]]) {
        assert_eq!(a.len(), b.len());
        for (p, q) in a.iter().zip(b) {
            for k in 0..3 {
                assert_eq!(p[k].to_bits(), q[k].to_bits(), "{p:?} vs {q:?}");
            }
        }
    }

    #[test]
    fn round_trip_positions_faces_and_per_vertex_uvs_all_formats() {
        let dir = temp_dir("roundtrip");
        let mut mesh = awkward_mesh();
        mesh.uvs = Some(Uvs::PerVertex(vec![
            [0.1, 0.7],
            [1.0 / 3.0, 2.0 / 3.0],
            [0.0, 1.0],
            [-0.5, 1e-12],
            [0.25, 0.75],
        ]));
        for format in Format::ALL {
            let path = dir.join(format!("m.{}", format.extension().to_uppercase()));
            write_mesh(&path, &mesh).unwrap();
            let back = read_mesh(&path).unwrap();
            assert_eq!(back.format, format);
            assert_eq!(back.stored_faces, 3);
            assert_bits_equal(&back.mesh.positions, &mesh.positions);
            assert_eq!(back.mesh.triangles, mesh.triangles, "{format}");
            assert_eq!(
                back.mesh.vertex_uvs(),
                mesh.vertex_uvs(),
                "{format}: per-vertex UVs lost"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn round_trip_per_corner_uvs_obj_and_ply() {
        let dir = temp_dir("roundtrip-corner");
        let mut mesh = awkward_mesh();
        let coords = vec![[0.0, 0.0], [1.0, 0.0], [0.1, 0.9], [0.3, 0.3]];
        let indices = vec![[0, 1, 2], [3, 2, 1], [0, 0, 3]];
        mesh.uvs = Some(Uvs::PerCorner {
            coords: coords.clone(),
            indices: indices.clone(),
        });
        // Expected UV of every corner, independent of how a format stores them.
        let corner_uvs = |m: &TriMesh| -> Vec<[f64; 2]> {
            match m.uvs.as_ref().expect("UVs lost") {
                Uvs::PerCorner { coords, indices } => indices
                    .iter()
                    .flat_map(|t| t.iter().map(|&i| coords[i as usize]))
                    .collect(),
                Uvs::PerVertex(uv) => m
                    .triangles
                    .iter()
                    .flat_map(|t| t.iter().map(|&i| uv[i as usize]))
                    .collect(),
            }
        };
        for ext in ["obj", "ply"] {
            let path = dir.join(format!("c.{ext}"));
            write_mesh(&path, &mesh).unwrap();
            let back = read_mesh(&path).unwrap();
            assert_bits_equal(&back.mesh.positions, &mesh.positions);
            assert_eq!(back.mesh.triangles, mesh.triangles);
            assert_eq!(corner_uvs(&back.mesh), corner_uvs(&mesh), "{ext}");
        }
        // OBJ keeps the shared coordinates and their indices exactly.
        let back = read_mesh(&dir.join("c.obj")).unwrap();
        assert_eq!(back.mesh.uvs, Some(Uvs::PerCorner { coords, indices }));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn extension_is_case_insensitive_and_unknown_lists_supported() {
        assert_eq!(Format::from_path(Path::new("a/B.Obj")), Some(Format::Obj));
        assert_eq!(Format::from_path(Path::new("x.PLY")), Some(Format::Ply));
        assert_eq!(Format::from_path(Path::new("x.stl")), None);
        assert_eq!(Format::from_path(Path::new("off")), None);
        let err = read_mesh(Path::new("/nonexistent/mesh.stl")).unwrap_err();
        assert!(matches!(err, ReadError::UnknownExtension { .. }));
        let msg = err.to_string();
        assert!(
            msg.contains(".obj") && msg.contains(".off") && msg.contains(".ply"),
            "{msg}"
        );
        let err = write_mesh(Path::new("/tmp/x.stl"), &TriMesh::default()).unwrap_err();
        assert!(matches!(err, WriteError::UnknownExtension { .. }));
    }

    #[test]
    fn missing_file_is_io_error_with_path() {
        let err = read_mesh(Path::new("/nonexistent-dir/mesh.off")).unwrap_err();
        assert!(matches!(err, ReadError::Io { .. }));
        assert!(err.to_string().contains("/nonexistent-dir/mesh.off"));
    }

    #[test]
    fn parse_errors_from_files_name_the_file() {
        let dir = temp_dir("errpath");
        let path = dir.join("bad.off");
        std::fs::write(&path, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").unwrap();
        let err = read_mesh(&path).unwrap_err();
        let msg = err.to_string();
        assert!(msg.starts_with(&path.display().to_string()), "{msg}");
        assert!(msg.contains("line 6"), "{msg}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn writers_refuse_inconsistent_meshes_without_creating_files() {
        let dir = temp_dir("invalid");
        let bad_index = TriMesh::new(vec![[0.0; 3]; 3], vec![[0, 1, 3]]);
        let mut bad_uv = TriMesh::new(vec![[0.0; 3]; 3], vec![[0, 1, 2]]);
        bad_uv.uvs = Some(Uvs::PerVertex(vec![[0.0; 2]; 2]));
        for format in Format::ALL {
            for mesh in [&bad_index, &bad_uv] {
                let path = dir.join(format!("bad.{format}"));
                let err = write_mesh(&path, mesh).unwrap_err();
                assert!(matches!(err, WriteError::InvalidMesh { .. }), "{err}");
                assert!(!path.exists());
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A binary file under a text format's name is refused as binary, at its first
    /// byte that is not text; a PLY written as binary and renamed `.obj` is the case met
    /// in practice. A DOS end-of-file mark and tabs are text.
    #[test]
    fn binary_data_in_a_text_format_is_refused_by_name() {
        let dir = temp_dir("not-text");
        let ply = dir.join("m.ply");
        write_mesh(&ply, &awkward_mesh()).unwrap();
        let bytes = std::fs::read(&ply).unwrap();
        let first = bytes
            .iter()
            .position(|&b| b < 0x20 && !b"\t\n\r".contains(&b))
            .expect("a binary PLY body");
        for ext in ["obj", "off"] {
            let renamed = dir.join(format!("m.{ext}"));
            std::fs::write(&renamed, &bytes).unwrap();
            let err = read_mesh(&renamed).unwrap_err();
            assert!(
                matches!(err, ReadError::NotText { at: Location::Byte(b), .. } if b == first as u64),
                "{err}"
            );
            let message = err.to_string();
            assert!(
                message.starts_with(&renamed.display().to_string()),
                "{message}"
            );
            assert!(
                message.contains(&format!("a .{ext} file is text")),
                "{message}"
            );
        }
        let dos = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf\t1 2 3\r\n\x1a";
        let m = read_mesh_from_bytes(dos, Format::Obj).unwrap();
        assert_eq!(m.mesh.triangles, [[0, 1, 2]]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn fan_triangulates_polygons() {
        let mut out = Vec::new();
        fan(&[7, 8, 9, 10, 11], &mut out);
        assert_eq!(out, vec![[7, 8, 9], [7, 9, 10], [7, 10, 11]]);
    }

    // ---- robustness: the readers return Ok or Err on any bytes, never panic or hang ----

    fn fuzz_cases() -> u32 {
        std::env::var("SURFMAP_FUZZ_CASES")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(256)
    }

    /// Valid files of every format and feature, the seeds of the mutation tests.
    fn seeds() -> Vec<(Format, Vec<u8>)> {
        let mut ply_be = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\n\
            property float x\nproperty double y\nproperty short z\nproperty uchar red\n\
            property float s\nproperty float t\nelement face 1\nproperty list uchar int vertex_indices\n\
            property list ushort float texcoord\nelement edge 1\nproperty int a\nend_header\n"
            .to_vec();
        for (x, y, z) in [(0.0f32, 0.0f64, 0i16), (1.0, 0.0, 1), (0.0, 1.0, -1)] {
            ply_be.extend(x.to_be_bytes());
            ply_be.extend(y.to_be_bytes());
            ply_be.extend(z.to_be_bytes());
            ply_be.push(200);
            ply_be.extend(0.5f32.to_be_bytes());
            ply_be.extend(0.25f32.to_be_bytes());
        }
        ply_be.push(3);
        for i in 0..3i32 {
            ply_be.extend(i.to_be_bytes());
        }
        ply_be.extend(6u16.to_be_bytes());
        for k in 0..6 {
            ply_be.extend((k as f32).to_be_bytes());
        }
        ply_be.extend(9i32.to_be_bytes());
        let mut ply_le = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty double x\n\
            property double y\nproperty double z\nelement face 1\nproperty list uint uint vertex_index\nend_header\n"
            .to_vec();
        for k in 0..12 {
            ply_le.extend((k as f64 * 0.1).to_le_bytes());
        }
        ply_le.extend(4u32.to_le_bytes());
        for i in 0..4u32 {
            ply_le.extend(i.to_le_bytes());
        }
        vec![
            (
                Format::Obj,
                b"# c\nmtllib a.mtl\no x\nv 0 0 0\nv 1 0 0 1\nv 1 1 0 0.5 0.5 0.5\nv 0 1 0\n\
                  vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\ng g\nusemtl m\ns off\n\
                  f 1/1/1 2/2/1 3/3/1 4/4/1\nf -4/-4 -2/-2 -1/-1\nl 1 2\n"
                    .to_vec(),
            ),
            (
                Format::Obj,
                b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\nf 3 2 1 # back\n".to_vec(),
            ),
            (
                Format::Off,
                b"# head\nCOFF\n4 2 0 # counts\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n\
                  1 1 0 0 0 255 255\n0 1 0 1 1 1 255\n4 0 1 2 3 255 0 0\n3 0 2 3\n"
                    .to_vec(),
            ),
            (
                Format::Off,
                b"STOFF 3 1 0\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n".to_vec(),
            ),
            (
                Format::Ply,
                b"ply\nformat ascii 1.0\ncomment x\nelement vertex 3\nproperty float x\n\
                  property float y\nproperty float z\nproperty float u\nproperty float v\n\
                  element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                  0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n"
                    .to_vec(),
            ),
            (Format::Ply, ply_be),
            (Format::Ply, ply_le),
        ]
    }

    #[test]
    fn seeds_are_valid() {
        for (format, bytes) in seeds() {
            let m = read_mesh_from_bytes(&bytes, format)
                .unwrap_or_else(|e| panic!("{format} seed rejected: {e}"));
            assert!(!m.mesh.triangles.is_empty(), "{format}");
        }
    }

    #[derive(Clone, Debug)]
    enum Mutation {
        Flip(usize, u8),
        Truncate(usize),
        Insert(usize, Vec<u8>),
        Delete(usize, usize),
    }

    fn mutation() -> impl Strategy<Value = Mutation> {
        // Inserted bytes favour the characters that steer the parsers.
        let interesting = prop_oneof![
            any::<u8>(),
            prop::sample::select(b"0123456789-+./ \n\r#eEfvtl".to_vec()),
            Just(0xffu8),
        ];
        prop_oneof![
            (any::<usize>(), 1u8..=255).prop_map(|(i, x)| Mutation::Flip(i, x)),
            any::<usize>().prop_map(Mutation::Truncate),
            (any::<usize>(), prop::collection::vec(interesting, 1..12))
                .prop_map(|(i, b)| Mutation::Insert(i, b)),
            (any::<usize>(), 1usize..8).prop_map(|(i, n)| Mutation::Delete(i, n)),
        ]
    }

    fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
        let n = bytes.len().max(1);
        match m {
            Mutation::Flip(i, x) => {
                if !bytes.is_empty() {
                    let i = i % bytes.len();
                    bytes[i] ^= x;
                }
            }
            Mutation::Truncate(i) => bytes.truncate(i % n),
            Mutation::Insert(i, b) => {
                let i = i % (bytes.len() + 1);
                bytes.splice(i..i, b.iter().copied());
            }
            Mutation::Delete(i, k) => {
                let i = i % n;
                let end = (i + k).min(bytes.len());
                if i < end {
                    bytes.drain(i..end);
                }
            }
        }
    }

    /// Reading must end in Ok or Err; a returned mesh must index only its own vertices.
    fn read_is_total(bytes: &[u8], format: Format) {
        if let Ok(f) = read_mesh_from_bytes(bytes, format) {
            let nv = f.mesh.positions.len();
            assert!(
                f.mesh
                    .triangles
                    .iter()
                    .flatten()
                    .all(|&i| (i as usize) < nv)
            );
            if let Some(Uvs::PerCorner { coords, indices }) = &f.mesh.uvs {
                assert_eq!(indices.len(), f.mesh.triangles.len());
                assert!(
                    indices
                        .iter()
                        .flatten()
                        .all(|&i| (i as usize) < coords.len())
                );
            }
            if let Some(Uvs::PerVertex(uv)) = &f.mesh.uvs {
                assert_eq!(uv.len(), nv);
            }
        }
    }

    /// Small real files of each format from the shared data folder, when it is there
    /// (`None`: skip; under `CI=true` a missing folder fails instead).
    fn real_seeds() -> Option<Vec<(Format, Vec<u8>)>> {
        let dir = crate::testing::shared_data()?;
        let seeds = [
            "nefertiti_small.off",
            "faces/mp_canonical.obj",
            "faces/flame/flame_template.ply",
        ]
        .into_iter()
        .map(|name| {
            let path = dir.join(name);
            let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            (Format::from_path(&path).expect("a mesh extension"), bytes)
        })
        .collect();
        Some(seeds)
    }

    #[test]
    fn mutated_real_files_never_panic() {
        let Some(seeds) = real_seeds() else {
            return;
        };
        let config = ProptestConfig {
            cases: (fuzz_cases() / 16).max(8),
            failure_persistence: None,
            ..ProptestConfig::default()
        };
        let strategy = (0..seeds.len(), prop::collection::vec(mutation(), 1..6));
        proptest::test_runner::TestRunner::new(config)
            .run(&strategy, |(seed, mutations)| {
                let (format, mut bytes) = seeds[seed].clone();
                for m in &mutations {
                    apply(&mut bytes, m);
                }
                read_is_total(&bytes, format);
                Ok(())
            })
            .unwrap();
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: fuzz_cases(), failure_persistence: None, ..ProptestConfig::default() })]

        #[test]
        fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
            for format in Format::ALL {
                read_is_total(&bytes, format);
            }
        }

        #[test]
        fn random_bytes_after_a_valid_header_never_panic(
            seed in 0usize..7,
            tail in prop::collection::vec(any::<u8>(), 0..200),
        ) {
            let (format, mut bytes) = seeds().swap_remove(seed);
            let cut = bytes.len().min(if format == Format::Ply {
                bytes.windows(10).position(|w| w == b"end_header").map_or(0, |p| p + 11)
            } else { 12 });
            bytes.truncate(cut);
            bytes.extend(tail);
            read_is_total(&bytes, format);
        }

        #[test]
        fn mutated_valid_files_never_panic(
            seed in 0usize..7,
            mutations in prop::collection::vec(mutation(), 1..6),
        ) {
            let (format, mut bytes) = seeds().swap_remove(seed);
            for m in &mutations {
                apply(&mut bytes, m);
            }
            read_is_total(&bytes, format);
        }
    }
}
