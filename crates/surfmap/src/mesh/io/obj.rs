//! Wavefront OBJ: `v`, `vt`, `f` (with `v`, `v/vt`, `v//vn`, `v/vt/vn` corners and negative,
//! relative indices), material library lookup, and the writer (with optional `.mtl`).

use std::path::{Path, PathBuf};

use super::{
    Location, Parsed, ReadError, WriteError, check_writable, content_lines, fan, parse_f64,
    parse_i64, tokens, write_error,
};
use crate::fsutil::write_atomically;
use crate::mesh::{TriMesh, Uvs};

/// A material for [`write_obj`]: its `.mtl` gets `map_Kd TEXTURE`.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjMaterial {
    /// Written verbatim after `map_Kd`; a relative path is relative to the `.mtl`'s folder.
    pub texture: PathBuf,
}

/// Resolves a 1-based or negative OBJ index against the records seen so far.
///
/// Positive `k` means record `k − 1` (it may refer forward; checked at the end of the file),
/// negative `−k` means the k-th most recent record. Returns the 0-based index.
struct IndexResolver {
    what: &'static str,
    /// Largest positive index that was beyond the records known at its line, and that line.
    forward: Option<(i64, usize)>,
}

impl IndexResolver {
    fn new(what: &'static str) -> Self {
        Self {
            what,
            forward: None,
        }
    }

    #[inline]
    fn resolve(&mut self, raw: i64, count: usize, line: usize) -> Result<u32, ReadError> {
        let out_of_range = || ReadError::out_of_range(Location::Line(line), self.what, raw, count);
        let zero_based = if raw > 0 {
            let i = raw - 1;
            if i as u64 >= count as u64 && self.forward.is_none_or(|(m, _)| raw > m) {
                self.forward = Some((raw, line));
            }
            i
        } else if raw < 0 {
            let i = count as i64 + raw;
            if i < 0 {
                return Err(out_of_range());
            }
            i
        } else {
            return Err(out_of_range());
        };
        u32::try_from(zero_based).map_err(|_| out_of_range())
    }

    /// Fails when a forward reference points beyond the final number of records.
    fn finish(&self, count: usize) -> Result<(), ReadError> {
        match self.forward {
            Some((raw, line)) if raw as u64 > count as u64 => Err(ReadError::out_of_range(
                Location::Line(line),
                self.what,
                raw,
                count,
            )),
            _ => Ok(()),
        }
    }
}

/// Parses OBJ text. UVs are kept as [`Uvs::PerCorner`] when every face gives a `vt` for every
/// corner (and the file has `vt` records); otherwise they are dropped.
pub(crate) fn parse(bytes: &[u8]) -> Result<Parsed, ReadError> {
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut uv_coords: Vec<[f64; 2]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut uv_triangles: Vec<[u32; 3]> = Vec::new();
    let mut every_face_has_uv = true;
    let mut stored_faces = 0usize;
    let mut material_libraries = Vec::new();
    let mut first_material = None;
    let mut vertex_index = IndexResolver::new("vertex");
    let mut uv_index = IndexResolver::new("texture coordinate");
    // Reused per face: no allocation in the loop once they have grown.
    let mut corners: Vec<u32> = Vec::new();
    let mut uv_corners: Vec<u32> = Vec::new();

    for (line_no, line) in content_lines(bytes) {
        let at = Location::Line(line_no);
        let mut toks = tokens(line);
        let Some(keyword) = toks.next() else { continue };
        match keyword {
            b"v" => {
                let mut p = [0.0; 3];
                for (k, name) in ["x", "y", "z"].into_iter().enumerate() {
                    let tok = toks.next().unwrap_or(b"");
                    p[k] = parse_f64(tok).ok_or_else(|| {
                        ReadError::syntax(at, format!("a number for vertex coordinate {name}"), tok)
                    })?;
                }
                // An optional w or a vertex colour may follow: ignored.
                positions.push(p);
            }
            b"vt" => {
                let mut t = [0.0; 2];
                for (k, name) in ["u", "v"].into_iter().enumerate() {
                    let tok = toks.next().unwrap_or(b"");
                    t[k] = match parse_f64(tok) {
                        Some(x) => x,
                        // `vt u` alone is legal: v defaults to 0.
                        None if k == 1 && tok.is_empty() => 0.0,
                        None => {
                            return Err(ReadError::syntax(
                                at,
                                format!("a number for texture coordinate {name}"),
                                tok,
                            ));
                        }
                    };
                }
                uv_coords.push(t);
            }
            b"f" => {
                stored_faces += 1;
                corners.clear();
                uv_corners.clear();
                let mut face_has_uv = true;
                for corner in toks {
                    let mut parts = corner.split(|&b| b == b'/');
                    let v = parts.next().unwrap_or(b"");
                    let raw = parse_i64(v).ok_or_else(|| {
                        ReadError::syntax(at, "a vertex index like 7, 7/2, 7//3 or 7/2/3", corner)
                    })?;
                    corners.push(vertex_index.resolve(raw, positions.len(), line_no)?);
                    match parts.next() {
                        Some(t) if !t.is_empty() => {
                            let raw = parse_i64(t).ok_or_else(|| {
                                ReadError::syntax(at, "a texture coordinate index", corner)
                            })?;
                            uv_corners.push(uv_index.resolve(raw, uv_coords.len(), line_no)?);
                        }
                        _ => face_has_uv = false,
                    }
                    // A normal index may follow; normals are not kept.
                }
                if corners.len() < 3 {
                    return Err(ReadError::too_small(at, corners.len()));
                }
                fan(&corners, &mut triangles);
                if every_face_has_uv && face_has_uv {
                    fan(&uv_corners, &mut uv_triangles);
                } else {
                    every_face_has_uv = false;
                }
            }
            b"mtllib" => {
                // The rest of the line: a file name may contain spaces.
                let rest = line
                    .trim_ascii()
                    .strip_prefix(b"mtllib")
                    .unwrap_or(b"")
                    .trim_ascii();
                if !rest.is_empty() {
                    material_libraries.push(String::from_utf8_lossy(rest).into_owned());
                }
            }
            b"usemtl" if first_material.is_none() => {
                first_material = toks.next().map(|n| String::from_utf8_lossy(n).into_owned());
            }
            // Normals, groups, objects, smoothing, lines, points, free-form data and anything
            // unknown carry nothing a triangle mesh keeps.
            _ => {}
        }
    }
    vertex_index.finish(positions.len())?;
    uv_index.finish(uv_coords.len())?;
    if positions.len() > u32::MAX as usize {
        return Err(ReadError::too_many(
            Location::Line(1),
            "vertices",
            positions.len() as u64,
        ));
    }
    let uvs = (every_face_has_uv && !uv_coords.is_empty() && !triangles.is_empty()).then_some(
        Uvs::PerCorner {
            coords: uv_coords,
            indices: uv_triangles,
        },
    );
    Ok(Parsed {
        mesh: TriMesh {
            positions,
            triangles,
            uvs,
        },
        stored_faces,
        material_libraries,
        first_material,
    })
}

/// The `map_Kd` texture of `material` (or of the first material that has one) in the first
/// existing material library of an OBJ at `obj_path`, resolved against the `.mtl`'s folder.
pub(crate) fn find_texture(
    obj_path: &Path,
    libraries: &[String],
    material: Option<&str>,
) -> Option<PathBuf> {
    let dir = obj_path.parent().unwrap_or(Path::new(""));
    for lib in libraries {
        let mtl_path = dir.join(lib);
        let Ok(text) = std::fs::read(&mtl_path) else {
            continue;
        };
        if let Some(texture) = map_kd(&text, material) {
            let mtl_dir = mtl_path.parent().unwrap_or(Path::new(""));
            return Some(mtl_dir.join(texture));
        }
    }
    None
}

/// `map_Kd` of the named material in MTL text, else the first `map_Kd` of any material.
/// Options before the file name (`-s 1 1 1`, `-bm 0.5`, …) are skipped: the file name is the
/// last token.
fn map_kd(mtl: &[u8], material: Option<&str>) -> Option<String> {
    let mut current: Option<&[u8]> = None;
    let mut first = None;
    for (_, line) in content_lines(mtl) {
        let mut toks = tokens(line);
        match toks.next() {
            Some(b"newmtl") => current = toks.next(),
            Some(b"map_Kd") => {
                let Some(file) = toks.last() else { continue };
                let file = String::from_utf8_lossy(file).into_owned();
                if material.is_some_and(|m| current == Some(m.as_bytes())) {
                    return Some(file);
                }
                first.get_or_insert(file);
            }
            _ => {}
        }
    }
    first
}

/// Writes OBJ: `v x y z`, `vt u v` (per vertex or per corner), `f a/ta b/tb c/tc` (1-based).
/// With a material, `mtllib STEM.mtl` + `usemtl` are written and `STEM.mtl` beside the OBJ
/// gets `map_Kd TEXTURE`. Every float is printed with `{}`, the shortest round-trip form.
pub fn write_obj(
    path: &Path,
    mesh: &TriMesh,
    material: Option<&ObjMaterial>,
) -> Result<(), WriteError> {
    check_writable(path, mesh)?;
    let material_name = "surfmap_material";
    let mtl_file = match material {
        Some(m) => {
            let stem = path
                .file_stem()
                .map_or_else(|| "mesh".into(), |s| s.to_string_lossy().into_owned());
            let mtl_name = format!("{stem}.mtl");
            let mtl_path = path.with_file_name(&mtl_name);
            write_atomically(&mtl_path, |w| {
                writeln!(w, "# written by surfmap")?;
                writeln!(w, "newmtl {material_name}")?;
                writeln!(w, "Ka 1 1 1\nKd 1 1 1\nKs 0 0 0\nillum 1")?;
                writeln!(w, "map_Kd {}", m.texture.display())
            })
            .map_err(write_error(&mtl_path))?;
            Some(mtl_name)
        }
        None => None,
    };
    write_atomically(path, |w| {
        writeln!(w, "# written by surfmap")?;
        if let Some(mtl) = &mtl_file {
            writeln!(w, "mtllib {mtl}")?;
        }
        for p in &mesh.positions {
            writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
        }
        let uv_triangles: Option<&[[u32; 3]]> = match &mesh.uvs {
            None => None,
            Some(Uvs::PerVertex(uv)) => {
                for t in uv {
                    writeln!(w, "vt {} {}", t[0], t[1])?;
                }
                Some(&mesh.triangles)
            }
            Some(Uvs::PerCorner { coords, indices }) => {
                for t in coords {
                    writeln!(w, "vt {} {}", t[0], t[1])?;
                }
                Some(indices)
            }
        };
        if mtl_file.is_some() {
            writeln!(w, "usemtl {material_name}")?;
        }
        match uv_triangles {
            Some(uvt) => {
                for (v, t) in mesh.triangles.iter().zip(uvt) {
                    writeln!(
                        w,
                        "f {}/{} {}/{} {}/{}",
                        v[0] + 1,
                        t[0] + 1,
                        v[1] + 1,
                        t[1] + 1,
                        v[2] + 1,
                        t[2] + 1
                    )?;
                }
            }
            None => {
                for v in &mesh.triangles {
                    writeln!(w, "f {} {} {}", v[0] + 1, v[1] + 1, v[2] + 1)?;
                }
            }
        }
        Ok(())
    })
    .map_err(write_error(path))
}

#[cfg(test)]
mod tests {
    use super::super::{Format, read_mesh, read_mesh_from_bytes};
    use super::*;

    /// A malformed input, a check of the error variant, and the line it must name.
    type Case = (String, fn(&ReadError) -> bool, usize);

    fn read(text: &str) -> Result<super::super::MeshFile, ReadError> {
        read_mesh_from_bytes(text.as_bytes(), Format::Obj)
    }

    #[test]
    fn quads_and_pentagons_are_fan_triangulated_and_counted_once() {
        let f = read(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 1 0\n\
             f 1 2 3 4\nf 1 2 3 4 5\n",
        )
        .unwrap();
        assert_eq!(f.stored_faces, 2);
        assert_eq!(
            f.mesh.triangles,
            vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 3], [0, 3, 4]]
        );
        assert_eq!(f.mesh.uvs, None);
    }

    #[test]
    fn all_corner_forms_and_extra_vertex_values() {
        let f = read(
            "v 0 0 0 1\nv 1 0 0 0.1 0.2 0.3\nv 0 1 0\nvt 0.5 0.5\nvt 1 0 0\nvt 0\nvn 0 0 1\n\
             f 1/1/1 2/2/1 3/3/1\nf 1//1 2//1 3//1\n",
        )
        .unwrap();
        assert_eq!(f.mesh.positions[1], [1.0, 0.0, 0.0]);
        assert_eq!(f.mesh.triangles, vec![[0, 1, 2], [0, 1, 2]]);
        // The second face has no vt: UVs are dropped rather than half-kept.
        assert_eq!(f.mesh.uvs, None);

        let f =
            read("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 0.5\nvt 1 0\nvt 0\nf 1/3 2/2 3/1\n").unwrap();
        assert_eq!(
            f.mesh.uvs,
            Some(Uvs::PerCorner {
                coords: vec![[0.5, 0.5], [1.0, 0.0], [0.0, 0.0]],
                indices: vec![[2, 1, 0]],
            })
        );
    }

    #[test]
    fn negative_indices_are_relative_to_the_records_so_far() {
        let f = read(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf -3/-3 -2/-2 -1/-1\n\
             v 1 1 0\nvt 1 1\nf -4/-4 -2/-2 -1/-1\n",
        )
        .unwrap();
        assert_eq!(f.mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        match f.mesh.uvs {
            Some(Uvs::PerCorner { indices, .. }) => {
                assert_eq!(indices, vec![[0, 1, 2], [0, 2, 3]])
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn tolerated_lines_comments_and_crlf() {
        let f = read(
            "# comment\r\nmtllib my lib.mtl\r\no obj\r\ng group\r\ns 1\r\nusemtl skin\r\n\
             v 0 0 0 # inline comment\r\nv 1 0 0\r\nv 0 1 0\r\nl 1 2\r\np 1\r\ncstype bezier\r\n\
             \r\n   \r\nf 1 2 3\r\n",
        )
        .unwrap();
        assert_eq!(f.mesh.positions.len(), 3);
        assert_eq!(f.mesh.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn repeated_index_and_degenerate_faces_are_kept() {
        let f = read("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 1 2\nf 1 2 3\n").unwrap();
        assert_eq!(f.mesh.triangles, vec![[0, 0, 1], [0, 1, 2]]);
    }

    #[test]
    fn unreferenced_vertices_and_order_are_kept() {
        let f = read("v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 4 2 3\n").unwrap();
        assert_eq!(f.mesh.positions.len(), 4);
        assert_eq!(f.mesh.positions[0], [9.0, 9.0, 9.0]);
        assert_eq!(f.mesh.triangles, vec![[3, 1, 2]]);
    }

    #[test]
    fn forward_references_are_allowed_if_the_vertex_comes_later() {
        let f = read("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
        assert_eq!(f.mesh.triangles, vec![[0, 1, 2]]);
        let err = read("f 1 2 5\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap_err();
        assert!(
            matches!(
                err,
                ReadError::IndexOutOfRange {
                    at: Location::Line(1),
                    index: 5,
                    count: 3,
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn malformed_inputs_name_the_line() {
        let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let cases: Vec<Case> = vec![
            (
                format!("{base}f 1 2 4\n"),
                |e| {
                    matches!(
                        e,
                        ReadError::IndexOutOfRange {
                            index: 4,
                            count: 3,
                            what: "vertex",
                            ..
                        }
                    )
                },
                4,
            ),
            (
                format!("{base}f 1 2 0\n"),
                |e| matches!(e, ReadError::IndexOutOfRange { index: 0, .. }),
                4,
            ),
            (
                format!("{base}f 1 -4 3\n"),
                |e| matches!(e, ReadError::IndexOutOfRange { index: -4, .. }),
                4,
            ),
            (
                format!("{base}f 1 2\n"),
                |e| matches!(e, ReadError::FaceTooSmall { corners: 2, .. }),
                4,
            ),
            (
                format!("{base}f\n"),
                |e| matches!(e, ReadError::FaceTooSmall { corners: 0, .. }),
                4,
            ),
            (
                format!("{base}f 1 x 3\n"),
                |e| matches!(e, ReadError::Syntax { .. }),
                4,
            ),
            (
                format!("{base}f 1/a 2 3\n"),
                |e| matches!(e, ReadError::Syntax { .. }),
                4,
            ),
            (
                format!("{base}vt 0 0\nf 1/1 2/2 3/1\n"),
                |e| {
                    matches!(
                        e,
                        ReadError::IndexOutOfRange {
                            what: "texture coordinate",
                            index: 2,
                            ..
                        }
                    )
                },
                5,
            ),
            (
                "v 0 0\n".into(),
                |e| matches!(e, ReadError::Syntax { .. }),
                1,
            ),
            (
                "\n\nv 0 zero 0\n".into(),
                |e| matches!(e, ReadError::Syntax { .. }),
                3,
            ),
            (
                format!("{base}f 1 2 99999999999\n"),
                |e| matches!(e, ReadError::IndexOutOfRange { .. }),
                4,
            ),
        ];
        for (text, is_right, line) in cases {
            let err = read(&text).unwrap_err();
            assert!(is_right(&err), "{text:?}: wrong variant {err:?}");
            assert_eq!(
                err.location(),
                Some(Location::Line(line)),
                "{text:?}: {err}"
            );
            assert!(err.to_string().contains(&format!("line {line}")), "{err}");
        }
        let msg = read(&format!("{base}f 1 2 9001\n"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            msg,
            "<bytes>: line 4: vertex index 9001 out of range (file has 3 vertex records)"
        );
    }

    #[test]
    fn texture_is_found_through_mtllib_and_usemtl() {
        let dir = super::super::tests::temp_dir("obj-texture");
        std::fs::create_dir_all(dir.join("mats")).unwrap();
        std::fs::write(
            dir.join("mats/lib.mtl"),
            "newmtl a\nmap_Kd a.png\nnewmtl b\nmap_Kd -s 1 1 1 b.png\n",
        )
        .unwrap();
        let obj = "mtllib missing.mtl\nmtllib mats/lib.mtl\nusemtl b\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        std::fs::write(dir.join("m.obj"), obj).unwrap();
        let f = read_mesh(&dir.join("m.obj")).unwrap();
        assert_eq!(f.texture, Some(dir.join("mats").join("b.png")));
        // Without usemtl: the first map_Kd. Without an existing .mtl: None.
        std::fs::write(dir.join("n.obj"), obj.replace("usemtl b\n", "")).unwrap();
        let f = read_mesh(&dir.join("n.obj")).unwrap();
        assert_eq!(f.texture, Some(dir.join("mats").join("a.png")));
        std::fs::write(dir.join("o.obj"), obj.replace("mtllib mats/lib.mtl\n", "")).unwrap();
        assert_eq!(read_mesh(&dir.join("o.obj")).unwrap().texture, None);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn written_material_round_trips_to_the_texture() {
        let dir = super::super::tests::temp_dir("obj-material");
        let mut mesh = TriMesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        );
        mesh.uvs = Some(Uvs::PerVertex(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]));
        let material = ObjMaterial {
            texture: PathBuf::from("checker.png"),
        };
        write_obj(&dir.join("flat.obj"), &mesh, Some(&material)).unwrap();
        let mtl = std::fs::read_to_string(dir.join("flat.mtl")).unwrap();
        assert!(mtl.contains("map_Kd checker.png"), "{mtl}");
        let f = read_mesh(&dir.join("flat.obj")).unwrap();
        assert_eq!(f.texture, Some(dir.join("checker.png")));
        assert_eq!(f.mesh.vertex_uvs(), mesh.vertex_uvs());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
