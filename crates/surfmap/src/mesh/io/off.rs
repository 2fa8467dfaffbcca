//! Object File Format (Geomview OFF), ASCII: `[ST][C][N]OFF` header, counts line, one vertex
//! per line, one polygon per line (`n i1 … in` plus an optional colour), `#` comments anywhere.

use std::path::Path;

use super::{
    Location, Parsed, ReadError, WriteError, capped, check_writable, content_lines, fan, parse_f64,
    parse_i64, tokens, write_error,
};
use crate::fsutil::write_atomically;
use crate::mesh::{TriMesh, Uvs};

/// The per-vertex fields announced by the header keyword `[ST][C][N]OFF`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Variant {
    /// `ST`: texture coordinates, the last two values of each vertex line.
    texture: bool,
}

/// Reads the header keyword; `4OFF` / `nOFF` (other dimensions) are reported as unsupported.
fn variant(keyword: &[u8], at: Location) -> Result<Variant, ReadError> {
    let expected = "an OFF header keyword (OFF, COFF, NOFF, CNOFF, STOFF, …)";
    let Some(mut prefix) = keyword.strip_suffix(b"OFF") else {
        return Err(ReadError::syntax(at, expected, keyword));
    };
    let texture = prefix.starts_with(b"ST");
    if texture {
        prefix = &prefix[2..];
    }
    for flag in [b'C', b'N'] {
        if prefix.first() == Some(&flag) {
            prefix = &prefix[1..];
        }
    }
    match prefix {
        [] => Ok(Variant { texture }),
        [b'4', ..] | [b'n', ..] => Err(ReadError::unsupported(
            at,
            "OFF with a dimension other than 3 (4OFF / nOFF)",
        )),
        _ => Err(ReadError::syntax(at, expected, keyword)),
    }
}

fn count(token: Option<&[u8]>, what: &str, at: Location) -> Result<u64, ReadError> {
    let token = token.unwrap_or(b"");
    parse_i64(token)
        .and_then(|n| u64::try_from(n).ok())
        .ok_or_else(|| ReadError::syntax(at, format!("the number of {what}"), token))
}

/// Parses ASCII OFF. Extra values after x y z (normals, colours) are ignored; with `ST` the last
/// two values of each vertex line become per-vertex UVs.
pub(crate) fn parse(bytes: &[u8]) -> Result<Parsed, ReadError> {
    let mut lines = content_lines(bytes).filter(|(_, line)| tokens(line).next().is_some());
    let last_line = bytes.split(|&b| b == b'\n').count();
    let eof = Location::Line(last_line);

    let (header_line, header) = lines
        .next()
        .ok_or_else(|| ReadError::truncated(eof, "the OFF header"))?;
    let at = Location::Line(header_line);
    let mut toks = tokens(header);
    let variant = variant(toks.next().unwrap_or(b""), at)?;
    // Counts may follow the keyword on the same line.
    let mut counts = toks.peekable();
    if counts.peek() == Some(&&b"BINARY"[..]) {
        return Err(ReadError::unsupported(at, "binary OFF"));
    }
    let (counts_at, nv, nf) = if counts.peek().is_some() {
        let nv = count(counts.next(), "vertices", at)?;
        (at, nv, count(counts.next(), "faces", at)?)
    } else {
        let (n, line) = lines
            .next()
            .ok_or_else(|| ReadError::truncated(eof, "the counts line 'vertices faces edges'"))?;
        let at = Location::Line(n);
        let mut toks = tokens(line);
        let nv = count(toks.next(), "vertices", at)?;
        (at, nv, count(toks.next(), "faces", at)?)
    };
    if nv > u64::from(u32::MAX) {
        return Err(ReadError::too_many(counts_at, "vertices", nv));
    }
    let num_vertices = nv as usize;

    // Capacities are capped by the file size: a vertex line has at least 6 bytes, a face 8.
    let mut positions = Vec::with_capacity(capped(nv, bytes.len(), 6));
    let mut uvs = Vec::with_capacity(if variant.texture {
        positions.capacity()
    } else {
        0
    });
    for i in 0..num_vertices {
        let (n, line) = lines.next().ok_or_else(|| {
            ReadError::truncated(eof, format!("vertex {} of {num_vertices}", i + 1))
        })?;
        let at = Location::Line(n);
        let mut toks = tokens(line);
        let mut p = [0.0; 3];
        for (k, name) in ["x", "y", "z"].into_iter().enumerate() {
            let tok = toks.next().unwrap_or(b"");
            p[k] = parse_f64(tok).ok_or_else(|| {
                ReadError::syntax(at, format!("a number for vertex coordinate {name}"), tok)
            })?;
        }
        positions.push(p);
        if variant.texture {
            let rest: [Option<&[u8]>; 2] = {
                let mut last = [None, None];
                for t in toks {
                    last = [last[1], Some(t)];
                }
                last
            };
            let uv = match rest {
                [Some(s), Some(t)] => parse_f64(s).zip(parse_f64(t)),
                _ => None,
            };
            let uv = uv.ok_or_else(|| {
                ReadError::syntax(
                    at,
                    "texture coordinates s t at the end of an STOFF vertex",
                    line,
                )
            })?;
            uvs.push([uv.0, uv.1]);
        }
    }

    let mut triangles = Vec::with_capacity(capped(nf, bytes.len(), 8));
    let mut corners: Vec<u32> = Vec::new();
    let mut stored_faces = 0usize;
    while (stored_faces as u64) < nf {
        let (n, line) = lines.next().ok_or_else(|| {
            ReadError::truncated(eof, format!("face {} of {nf}", stored_faces + 1))
        })?;
        let at = Location::Line(n);
        let mut toks = tokens(line);
        let size_tok = toks.next().unwrap_or(b"");
        let size = parse_i64(size_tok)
            .and_then(|s| u64::try_from(s).ok())
            .ok_or_else(|| ReadError::syntax(at, "the number of face vertices", size_tok))?;
        if size < 3 {
            return Err(ReadError::too_small(at, size as usize));
        }
        corners.clear();
        for k in 0..size {
            let tok = toks.next().ok_or_else(|| {
                ReadError::syntax(
                    at,
                    format!("{size} vertex indices after the face size (got {k})"),
                    b"",
                )
            })?;
            let index =
                parse_i64(tok).ok_or_else(|| ReadError::syntax(at, "a vertex index", tok))?;
            match u32::try_from(index) {
                Ok(i) if (i as usize) < num_vertices => corners.push(i),
                _ => {
                    return Err(ReadError::out_of_range(at, "vertex", index, num_vertices));
                }
            }
        }
        // A colour may follow the indices: ignored.
        fan(&corners, &mut triangles);
        stored_faces += 1;
    }
    Ok(Parsed {
        mesh: TriMesh {
            positions,
            triangles,
            uvs: variant.texture.then_some(Uvs::PerVertex(uvs)),
        },
        stored_faces,
        material_libraries: Vec::new(),
        first_material: None,
    })
}

/// Writes ASCII OFF (`STOFF` with `x y z s t` lines when the mesh has per-vertex UVs).
/// Floats are printed with `{}`, the shortest round-trip form; the edge count is written as 0.
pub fn write_off(path: &Path, mesh: &TriMesh) -> Result<(), WriteError> {
    check_writable(path, mesh)?;
    let uvs = mesh.vertex_uvs();
    write_atomically(path, |w| {
        writeln!(w, "{}", if uvs.is_some() { "STOFF" } else { "OFF" })?;
        writeln!(w, "# written by surfmap")?;
        writeln!(w, "{} {} 0", mesh.positions.len(), mesh.triangles.len())?;
        match uvs {
            Some(uv) => {
                for (p, t) in mesh.positions.iter().zip(uv) {
                    writeln!(w, "{} {} {} {} {}", p[0], p[1], p[2], t[0], t[1])?;
                }
            }
            None => {
                for p in &mesh.positions {
                    writeln!(w, "{} {} {}", p[0], p[1], p[2])?;
                }
            }
        }
        for t in &mesh.triangles {
            writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
        }
        Ok(())
    })
    .map_err(write_error(path))
}

#[cfg(test)]
mod tests {
    use super::super::{Format, MeshFile, read_mesh_from_bytes};
    use super::*;

    /// A malformed input, a check of the error variant, and the line it must name.
    type Case = (String, fn(&ReadError) -> bool, usize);

    fn read(text: &str) -> Result<MeshFile, ReadError> {
        read_mesh_from_bytes(text.as_bytes(), Format::Off)
    }

    const SQUARE: &str = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";

    #[test]
    fn every_header_variant_reads_the_same_geometry() {
        let plain = read(&format!("OFF\n4 1 0\n{SQUARE}4 0 1 2 3\n")).unwrap();
        assert_eq!(plain.mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(plain.stored_faces, 1);
        let cases = [
            "COFF\n4 1 0\n0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n1 1 0 0 0 1 1\n0 1 0 1 1 1 1\n4 0 1 2 3\n",
            "NOFF\n4 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n4 0 1 2 3\n",
            "CNOFF\n4 1 0\n0 0 0 0 0 1 9 9 9\n1 0 0 0 0 1 9 9 9\n1 1 0 0 0 1 9 9 9\n0 1 0 0 0 1 9 9 9\n4 0 1 2 3\n",
            "OFF 4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n",
        ];
        for text in cases {
            let f = read(text).unwrap_or_else(|e| panic!("{text}: {e}"));
            assert_eq!(f.mesh.positions, plain.mesh.positions, "{text}");
            assert_eq!(f.mesh.triangles, plain.mesh.triangles, "{text}");
            assert_eq!(f.mesh.uvs, None);
        }
        let st = read("STOFF\n3 1 0\n0 0 0 0.5 0.25\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n").unwrap();
        assert_eq!(
            st.mesh.uvs,
            Some(Uvs::PerVertex(vec![[0.5, 0.25], [1.0, 0.0], [0.0, 1.0]]))
        );
    }

    #[test]
    fn comments_blank_lines_and_face_colours() {
        let f = read(
            "# leading comment\n\nOFF # keyword\n# between\n4 2 0\n\n0 0 0 # v0\n1 0 0\n# mid\n\
             1 1 0\n0 1 0\n3 0 1 2 255 0 0\n\n3 0 2 3 0.1 0.2 0.3 1.0 # coloured\n",
        )
        .unwrap();
        assert_eq!(f.mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(f.mesh.positions.len(), 4);
    }

    #[test]
    fn hexagon_and_mixed_sizes() {
        let f =
            read("OFF\n6 2 0\n0 0 0\n1 0 0\n2 1 0\n1 2 0\n0 2 0\n-1 1 0\n6 0 1 2 3 4 5\n3 5 4 0\n")
                .unwrap();
        assert_eq!(f.stored_faces, 2);
        assert_eq!(
            f.mesh.triangles,
            vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5], [5, 4, 0]]
        );
    }

    #[test]
    fn degenerate_faces_are_kept() {
        let f = read("OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 0 1\n").unwrap();
        assert_eq!(f.mesh.triangles, vec![[0, 0, 1]]);
    }

    #[test]
    fn malformed_inputs_name_the_line() {
        let cases: Vec<Case> = vec![
            (
                format!("OFF\n4 1 0\n{SQUARE}3 0 1 4\n"),
                |e| {
                    matches!(
                        e,
                        ReadError::IndexOutOfRange {
                            index: 4,
                            count: 4,
                            ..
                        }
                    )
                },
                7,
            ),
            (
                format!("OFF\n4 1 0\n{SQUARE}3 0 -1 2\n"),
                |e| matches!(e, ReadError::IndexOutOfRange { index: -1, .. }),
                7,
            ),
            (
                format!("OFF\n4 1 0\n{SQUARE}2 0 1\n"),
                |e| matches!(e, ReadError::FaceTooSmall { corners: 2, .. }),
                7,
            ),
            (
                format!("OFF\n4 1 0\n{SQUARE}4 0 1 2\n"),
                |e| matches!(e, ReadError::Syntax { .. }),
                7,
            ),
            (
                format!("OFF\n4 2 0\n{SQUARE}3 0 1 2\n"),
                |e| matches!(e, ReadError::Truncated { .. }),
                8,
            ),
            (
                "OFF\n4 1 0\n0 0 0\n1 0\n".into(),
                |e| matches!(e, ReadError::Syntax { .. }),
                4,
            ),
            (
                "OFF\n4 1 0\n0 0 0\n".into(),
                |e| matches!(e, ReadError::Truncated { .. }),
                4,
            ),
            ("PLY\n".into(), |e| matches!(e, ReadError::Syntax { .. }), 1),
            (
                "\n# only a comment\n4OFF\n".into(),
                |e| matches!(e, ReadError::Unsupported { .. }),
                3,
            ),
            (
                "OFF BINARY\n".into(),
                |e| matches!(e, ReadError::Unsupported { .. }),
                1,
            ),
            (
                "OFF\n-4 1 0\n".into(),
                |e| matches!(e, ReadError::Syntax { .. }),
                2,
            ),
            (
                "OFF\n99999999999 1 0\n".into(),
                |e| matches!(e, ReadError::TooMany { .. }),
                2,
            ),
            ("".into(), |e| matches!(e, ReadError::Truncated { .. }), 1),
        ];
        for (text, is_right, line) in cases {
            let err = read(&text).unwrap_err();
            assert!(is_right(&err), "{text:?}: wrong variant {err:?}");
            assert_eq!(
                err.location(),
                Some(Location::Line(line)),
                "{text:?}: {err}"
            );
        }
    }

    #[test]
    fn huge_counts_with_little_data_fail_fast_without_allocating_them() {
        let err = read("OFF\n4000000000 4000000000 0\n0 0 0\n").unwrap_err();
        assert!(matches!(err, ReadError::Truncated { .. }), "{err}");
    }
}
