//! Stanford PLY: ASCII, binary little endian and binary big endian.
//!
//! The `vertex` element must have scalar `x y z` of any type; `s t`, `u v`, `texture_u
//! texture_v` or `texture_s texture_t` become per-vertex UVs; every other property is read
//! and dropped. The `face` element needs a list `vertex_indices` (or `vertex_index`) of any
//! integer count and index type; an optional float list `texcoord` (2 values per corner, the
//! MeshLab convention) becomes per-corner UVs. Other elements are parsed and skipped.
//! Binary errors name the byte offset from the start of the file.

use std::path::Path;

use super::{
    Location, Parsed, ReadError, WriteError, capped, check_writable, fan, parse_f64, parse_i64,
    tokens, write_error,
};
use crate::fsutil::write_atomically;
use crate::mesh::{TriMesh, Uvs};

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &[u8]) -> Option<Scalar> {
        Some(match name {
            b"char" | b"int8" => Scalar::I8,
            b"uchar" | b"uint8" => Scalar::U8,
            b"short" | b"int16" => Scalar::I16,
            b"ushort" | b"uint16" => Scalar::U16,
            b"int" | b"int32" => Scalar::I32,
            b"uint" | b"uint32" => Scalar::U32,
            b"float" | b"float32" => Scalar::F32,
            b"double" | b"float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar {
        name: String,
        ty: Scalar,
    },
    List {
        name: String,
        count: Scalar,
        item: Scalar,
    },
}

impl Property {
    fn name(&self) -> &str {
        match self {
            Property::Scalar { name, .. } | Property::List { name, .. } => name,
        }
    }
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    /// Header line of the `element` statement, for errors about its properties.
    line: usize,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the first body byte.
    body_start: usize,
}

fn parse_header(bytes: &[u8]) -> Result<Header, ReadError> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        line_no += 1;
        let at = Location::Line(line_no);
        let Some(rest) = bytes.get(pos..).filter(|r| !r.is_empty()) else {
            return Err(ReadError::truncated(
                at,
                "a PLY header ending in 'end_header'",
            ));
        };
        let (line, next) = match rest.iter().position(|&b| b == b'\n') {
            Some(n) => (&rest[..n], pos + n + 1),
            None => (rest, bytes.len()),
        };
        pos = next;
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line_no == 1 {
            if line.trim_ascii_end() != b"ply" {
                return Err(ReadError::syntax(at, "'ply' on the first line", line));
            }
            continue;
        }
        let mut toks = tokens(line);
        let Some(keyword) = toks.next() else { continue };
        match keyword {
            b"format" => {
                let name = toks.next().unwrap_or(b"");
                encoding = Some(match name {
                    b"ascii" => Encoding::Ascii,
                    b"binary_little_endian" => Encoding::LittleEndian,
                    b"binary_big_endian" => Encoding::BigEndian,
                    _ => {
                        return Err(ReadError::syntax(
                            at,
                            "ascii, binary_little_endian or binary_big_endian",
                            name,
                        ));
                    }
                });
            }
            b"comment" | b"obj_info" => {}
            b"element" => {
                let name = toks.next().unwrap_or(b"");
                let count_tok = toks.next().unwrap_or(b"");
                let count = parse_i64(count_tok)
                    .and_then(|c| u64::try_from(c).ok())
                    .ok_or_else(|| ReadError::syntax(at, "an element count", count_tok))?;
                if name.is_empty() {
                    return Err(ReadError::syntax(at, "an element name", name));
                }
                elements.push(Element {
                    name: String::from_utf8_lossy(name).into_owned(),
                    count,
                    properties: Vec::new(),
                    line: line_no,
                });
            }
            b"property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(ReadError::syntax(
                        at,
                        "an 'element' before 'property'",
                        line,
                    ));
                };
                let ty = toks.next().unwrap_or(b"");
                let scalar = |t: &[u8]| {
                    Scalar::from_name(t).ok_or_else(|| {
                        ReadError::syntax(at, "a PLY type (char, uchar, short, …, double)", t)
                    })
                };
                let property = if ty == b"list" {
                    let count = scalar(toks.next().unwrap_or(b""))?;
                    let item = scalar(toks.next().unwrap_or(b""))?;
                    if !count.is_integer() {
                        return Err(ReadError::syntax(
                            at,
                            "an integer type for the list length",
                            line,
                        ));
                    }
                    let name = toks.next().unwrap_or(b"");
                    Property::List {
                        name: String::from_utf8_lossy(name).into_owned(),
                        count,
                        item,
                    }
                } else {
                    let ty = scalar(ty)?;
                    let name = toks.next().unwrap_or(b"");
                    Property::Scalar {
                        name: String::from_utf8_lossy(name).into_owned(),
                        ty,
                    }
                };
                element.properties.push(property);
            }
            b"end_header" => {
                let encoding = encoding.ok_or_else(|| {
                    ReadError::syntax(at, "a 'format' line before 'end_header'", keyword)
                })?;
                return Ok(Header {
                    encoding,
                    elements,
                    body_start: pos,
                });
            }
            _ => {
                return Err(ReadError::syntax(
                    at,
                    "a PLY header line (format, element, property, comment, end_header)",
                    line,
                ));
            }
        }
    }
}

/// A failure inside the body, turned into a [`ReadError`] by the element reader that knows
/// which record it was reading.
enum BodyError {
    End(Location),
    /// An ASCII token that is not a number of the expected kind.
    Bad(Location, Vec<u8>),
}

/// The element data after the header, read value by value.
trait Body {
    /// Where the next value starts.
    fn at(&mut self) -> Location;
    /// A value of any type, as f64 (exact for every PLY type).
    fn value(&mut self, ty: Scalar) -> Result<f64, BodyError>;
    /// A value of an integer type (the header checks that list lengths have one).
    fn integer(&mut self, ty: Scalar) -> Result<i64, BodyError>;
    /// Skips `n` values of type `ty`.
    fn skip(&mut self, ty: Scalar, n: u64) -> Result<(), BodyError>;
    /// Bytes left, to cap allocations.
    fn remaining(&self) -> usize;
}

struct Binary<'a, const BIG_ENDIAN: bool> {
    bytes: &'a [u8],
    pos: usize,
}

impl<const BIG: bool> Binary<'_, BIG> {
    #[inline]
    fn take<const N: usize>(&mut self) -> Result<[u8; N], BodyError> {
        let end = self.pos + N;
        match self.bytes.get(self.pos..end) {
            Some(b) => {
                self.pos = end;
                let mut out = [0u8; N];
                out.copy_from_slice(b);
                Ok(out)
            }
            None => Err(BodyError::End(Location::Byte(self.pos as u64))),
        }
    }
}

macro_rules! number {
    ($self:ident, $t:ty) => {{
        let b = $self.take::<{ std::mem::size_of::<$t>() }>()?;
        if BIG {
            <$t>::from_be_bytes(b)
        } else {
            <$t>::from_le_bytes(b)
        }
    }};
}

impl<const BIG: bool> Body for Binary<'_, BIG> {
    fn at(&mut self) -> Location {
        Location::Byte(self.pos as u64)
    }

    #[inline]
    fn value(&mut self, ty: Scalar) -> Result<f64, BodyError> {
        Ok(match ty {
            Scalar::F32 => f64::from(number!(self, f32)),
            Scalar::F64 => number!(self, f64),
            _ => self.integer(ty)? as f64,
        })
    }

    #[inline]
    fn integer(&mut self, ty: Scalar) -> Result<i64, BodyError> {
        Ok(match ty {
            Scalar::I8 => i64::from(number!(self, i8)),
            Scalar::U8 => i64::from(number!(self, u8)),
            Scalar::I16 => i64::from(number!(self, i16)),
            Scalar::U16 => i64::from(number!(self, u16)),
            Scalar::I32 => i64::from(number!(self, i32)),
            Scalar::U32 => i64::from(number!(self, u32)),
            // Float indices: taken when they are whole numbers, else an impossible index.
            Scalar::F32 | Scalar::F64 => {
                let x = self.value(ty)?;
                if x.fract() == 0.0 && x.abs() < 9e15 {
                    x as i64
                } else {
                    i64::MIN
                }
            }
        })
    }

    fn skip(&mut self, ty: Scalar, n: u64) -> Result<(), BodyError> {
        let len = (ty.size() as u64).saturating_mul(n);
        if len > self.remaining() as u64 {
            return Err(BodyError::End(self.at()));
        }
        self.pos += len as usize;
        Ok(())
    }

    fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }
}

/// ASCII body: whitespace-separated tokens, line numbers counted for errors.
struct Ascii<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Ascii<'a> {
    fn skip_whitespace(&mut self) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    fn token(&mut self) -> Result<(Location, &'a [u8]), BodyError> {
        self.skip_whitespace();
        let start = self.pos;
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        let at = Location::Line(self.line);
        if start == self.pos {
            Err(BodyError::End(at))
        } else {
            Ok((at, &self.bytes[start..self.pos]))
        }
    }
}

impl Body for Ascii<'_> {
    fn at(&mut self) -> Location {
        self.skip_whitespace();
        Location::Line(self.line)
    }

    fn value(&mut self, _ty: Scalar) -> Result<f64, BodyError> {
        let (at, tok) = self.token()?;
        parse_f64(tok).ok_or_else(|| BodyError::Bad(at, tok.to_vec()))
    }

    fn integer(&mut self, ty: Scalar) -> Result<i64, BodyError> {
        let (at, tok) = self.token()?;
        match parse_i64(tok) {
            Some(i) => Ok(i),
            None if !ty.is_integer() => match parse_f64(tok) {
                Some(x) if x.fract() == 0.0 && x.abs() < 9e15 => Ok(x as i64),
                _ => Err(BodyError::Bad(at, tok.to_vec())),
            },
            None => Err(BodyError::Bad(at, tok.to_vec())),
        }
    }

    fn skip(&mut self, _ty: Scalar, n: u64) -> Result<(), BodyError> {
        for _ in 0..n {
            self.token()?;
        }
        Ok(())
    }

    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }
}

/// Turns a body failure into a [`ReadError`] naming the element and record.
fn in_record(element: &Element, record: u64) -> impl Fn(BodyError) -> ReadError + '_ {
    move |e| match e {
        BodyError::End(at) => ReadError::truncated(
            at,
            format!(
                "record {} of {} of element '{}'",
                record + 1,
                element.count,
                element.name
            ),
        ),
        BodyError::Bad(at, tok) => {
            ReadError::syntax(at, format!("a number in element '{}'", element.name), &tok)
        }
    }
}

/// Reads a list length: a non-negative integer.
fn list_len<B: Body>(body: &mut B, count: Scalar) -> Result<(Location, u64), BodyError> {
    let at = body.at();
    let n = body.integer(count)?;
    u64::try_from(n)
        .map(|n| (at, n))
        .map_err(|_| BodyError::Bad(at, n.to_string().into_bytes()))
}

fn skip_element<B: Body>(body: &mut B, element: &Element) -> Result<(), ReadError> {
    if element.properties.is_empty() {
        return Ok(()); // records of no bytes: nothing to skip, however many
    }
    for record in 0..element.count {
        let err = in_record(element, record);
        for p in &element.properties {
            match *p {
                Property::Scalar { ty, .. } => body.skip(ty, 1).map_err(&err)?,
                Property::List { count, item, .. } => {
                    let (_, n) = list_len(body, count).map_err(&err)?;
                    body.skip(item, n).map_err(&err)?;
                }
            }
        }
    }
    Ok(())
}

/// Positions and optional per-vertex UVs.
type VertexData = (Vec<[f64; 3]>, Option<Vec<[f64; 2]>>);

/// Positions and optional per-vertex UVs of the `vertex` element.
fn read_vertices<B: Body>(body: &mut B, element: &Element) -> Result<VertexData, ReadError> {
    let index_of = |name: &str| {
        element
            .properties
            .iter()
            .position(|p| matches!(p, Property::Scalar { name: n, .. } if n == name))
    };
    let at = Location::Line(element.line);
    let [Some(x), Some(y), Some(z)] = ["x", "y", "z"].map(index_of) else {
        let names: Vec<&str> = element.properties.iter().map(Property::name).collect();
        return Err(ReadError::syntax(
            at,
            "scalar properties x, y and z in element 'vertex'",
            names.join(" ").as_bytes(),
        ));
    };
    let uv = [
        ("s", "t"),
        ("u", "v"),
        ("texture_u", "texture_v"),
        ("texture_s", "texture_t"),
    ]
    .into_iter()
    .find_map(|(u, v)| index_of(u).zip(index_of(v)));
    // Slot of each property in the record: 0..3 xyz, 3..5 uv.
    let mut slot = vec![None; element.properties.len()];
    for (k, i) in [x, y, z].into_iter().enumerate() {
        slot[i] = Some(k);
    }
    if let Some((u, v)) = uv {
        slot[u] = Some(3);
        slot[v] = Some(4);
    }
    let cap = capped(element.count, body.remaining(), 3);
    let mut positions = Vec::with_capacity(cap);
    let mut uvs = uv.map(|_| Vec::with_capacity(cap));
    let mut record_values = [0.0f64; 5];
    for record in 0..element.count {
        let err = in_record(element, record);
        for (p, slot) in element.properties.iter().zip(&slot) {
            match *p {
                Property::Scalar { ty, .. } => {
                    let value = body.value(ty).map_err(&err)?;
                    if let Some(s) = *slot {
                        record_values[s] = value;
                    }
                }
                Property::List { count, item, .. } => {
                    let (_, n) = list_len(body, count).map_err(&err)?;
                    body.skip(item, n).map_err(&err)?;
                }
            }
        }
        let [px, py, pz, u, v] = record_values;
        positions.push([px, py, pz]);
        if let Some(uvs) = &mut uvs {
            uvs.push([u, v]);
        }
    }
    Ok((positions, uvs))
}

struct Faces {
    triangles: Vec<[u32; 3]>,
    /// Per-corner UVs from `texcoord` lists: one coordinate per triangle corner.
    corner_uvs: Option<Vec<[f64; 2]>>,
}

fn read_faces<B: Body>(
    body: &mut B,
    element: &Element,
    num_vertices: u64,
) -> Result<Faces, ReadError> {
    let is_list = |p: &&Property, names: &[&str]| matches!(p, Property::List { name, .. } if names.contains(&name.as_str()));
    let Some(index_list) = element
        .properties
        .iter()
        .position(|p| is_list(&p, &["vertex_indices", "vertex_index"]))
    else {
        let names: Vec<&str> = element.properties.iter().map(Property::name).collect();
        return Err(ReadError::syntax(
            Location::Line(element.line),
            "a list property 'vertex_indices' in element 'face'",
            names.join(" ").as_bytes(),
        ));
    };
    let texcoord = element
        .properties
        .iter()
        .position(|p| is_list(&p, &["texcoord"]));
    let num_vertices_usize = usize::try_from(num_vertices).unwrap_or(usize::MAX);
    let mut triangles = Vec::with_capacity(capped(element.count, body.remaining(), 4));
    let mut corner_uvs = texcoord.map(|_| Vec::new());
    let mut corners: Vec<u32> = Vec::new();
    let mut coords: Vec<f64> = Vec::new();
    for record in 0..element.count {
        let err = in_record(element, record);
        corners.clear();
        coords.clear();
        for (k, p) in element.properties.iter().enumerate() {
            match *p {
                Property::Scalar { ty, .. } => body.skip(ty, 1).map_err(&err)?,
                Property::List { count, item, .. } if k == index_list => {
                    let (at, n) = list_len(body, count).map_err(&err)?;
                    if n < 3 {
                        return Err(ReadError::too_small(at, n as usize));
                    }
                    for _ in 0..n {
                        let at = body.at();
                        let index = body.integer(item).map_err(&err)?;
                        match u32::try_from(index) {
                            Ok(i) if u64::from(i) < num_vertices => corners.push(i),
                            _ => {
                                return Err(ReadError::out_of_range(
                                    at,
                                    "vertex",
                                    index,
                                    num_vertices_usize,
                                ));
                            }
                        }
                    }
                }
                Property::List { count, item, .. } if Some(k) == texcoord => {
                    let (_, n) = list_len(body, count).map_err(&err)?;
                    for _ in 0..n {
                        coords.push(body.value(item).map_err(&err)?);
                    }
                }
                Property::List { count, item, .. } => {
                    let (_, n) = list_len(body, count).map_err(&err)?;
                    body.skip(item, n).map_err(&err)?;
                }
            }
        }
        fan(&corners, &mut triangles);
        if let Some(uvs) = &mut corner_uvs {
            if coords.len() == 2 * corners.len() {
                let uv = |c: usize| [coords[2 * c], coords[2 * c + 1]];
                for t in 1..corners.len() - 1 {
                    uvs.extend([uv(0), uv(t), uv(t + 1)]);
                }
            } else {
                corner_uvs = None; // a face without matching texcoords: drop them all
            }
        }
    }
    Ok(Faces {
        triangles,
        corner_uvs,
    })
}

fn read_body<B: Body>(body: &mut B, header: &Header) -> Result<Parsed, ReadError> {
    let num_vertices = header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map_or(0, |e| e.count);
    if num_vertices > u64::from(u32::MAX) {
        return Err(ReadError::too_many(
            Location::Line(1),
            "vertices",
            num_vertices,
        ));
    }
    let mut vertices = None;
    let mut faces = None;
    let mut stored_faces = 0;
    for element in &header.elements {
        match element.name.as_str() {
            "vertex" if vertices.is_none() => vertices = Some(read_vertices(body, element)?),
            "face" if faces.is_none() => {
                faces = Some(read_faces(body, element, num_vertices)?);
                stored_faces = element.count as usize;
            }
            _ => skip_element(body, element)?,
        }
    }
    let (positions, vertex_uvs) = vertices.unwrap_or_default();
    let Faces {
        triangles,
        corner_uvs,
    } = faces.unwrap_or(Faces {
        triangles: Vec::new(),
        corner_uvs: None,
    });
    let uvs = match (vertex_uvs, corner_uvs) {
        (Some(uv), _) => Some(Uvs::PerVertex(uv)),
        (None, Some(coords)) if !triangles.is_empty() => {
            let indices = (0..triangles.len() as u32)
                .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                .collect();
            Some(Uvs::PerCorner { coords, indices })
        }
        _ => None,
    };
    Ok(Parsed {
        mesh: TriMesh {
            positions,
            triangles,
            uvs,
        },
        stored_faces,
        material_libraries: Vec::new(),
        first_material: None,
    })
}

pub(crate) fn parse(bytes: &[u8]) -> Result<Parsed, ReadError> {
    let header = parse_header(bytes)?;
    match header.encoding {
        Encoding::Ascii => {
            let header_lines = bytes[..header.body_start]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            let mut body = Ascii {
                bytes,
                pos: header.body_start,
                line: header_lines + 1,
            };
            read_body(&mut body, &header)
        }
        Encoding::LittleEndian => read_body(
            &mut Binary::<false> {
                bytes,
                pos: header.body_start,
            },
            &header,
        ),
        Encoding::BigEndian => read_body(
            &mut Binary::<true> {
                bytes,
                pos: header.body_start,
            },
            &header,
        ),
    }
}

/// Writes binary little-endian PLY: double `x y z` (plus double `s t` when the mesh has
/// per-vertex UVs) and `list uchar int vertex_indices` (`uint` beyond 2³¹ − 1 vertices).
/// Per-corner UVs that are not per-vertex go to a face list `texcoord` (MeshLab convention).
pub fn write_ply(path: &Path, mesh: &TriMesh) -> Result<(), WriteError> {
    check_writable(path, mesh)?;
    let vertex_uvs = mesh.vertex_uvs();
    let corner_uvs = match &mesh.uvs {
        Some(Uvs::PerCorner { coords, indices }) if vertex_uvs.is_none() => Some((coords, indices)),
        _ => None,
    };
    let index_type = if mesh.positions.len() > i32::MAX as usize {
        "uint"
    } else {
        "int"
    };
    write_atomically(path, |w| {
        write!(
            w,
            "ply\nformat binary_little_endian 1.0\ncomment written by surfmap\n\
             element vertex {}\nproperty double x\nproperty double y\nproperty double z\n",
            mesh.positions.len()
        )?;
        if vertex_uvs.is_some() {
            write!(w, "property double s\nproperty double t\n")?;
        }
        write!(
            w,
            "element face {}\nproperty list uchar {index_type} vertex_indices\n",
            mesh.triangles.len()
        )?;
        if corner_uvs.is_some() {
            writeln!(w, "property list uchar double texcoord")?;
        }
        writeln!(w, "end_header")?;
        for (i, p) in mesh.positions.iter().enumerate() {
            for x in p {
                w.write_all(&x.to_le_bytes())?;
            }
            if let Some(uv) = vertex_uvs {
                w.write_all(&uv[i][0].to_le_bytes())?;
                w.write_all(&uv[i][1].to_le_bytes())?;
            }
        }
        for (t, tri) in mesh.triangles.iter().enumerate() {
            w.write_all(&[3])?;
            for &i in tri {
                w.write_all(&i.to_le_bytes())?;
            }
            if let Some((coords, indices)) = corner_uvs {
                w.write_all(&[6])?;
                for &c in &indices[t] {
                    w.write_all(&coords[c as usize][0].to_le_bytes())?;
                    w.write_all(&coords[c as usize][1].to_le_bytes())?;
                }
            }
        }
        Ok(())
    })
    .map_err(write_error(path))
}

#[cfg(test)]
mod tests {
    use super::super::{Format, MeshFile, read_mesh_from_bytes};
    use super::*;

    /// A malformed input, a check of the error variant, and the place it must name.
    type Case = (Vec<u8>, fn(&ReadError) -> bool, Location);

    fn read(bytes: &[u8]) -> Result<MeshFile, ReadError> {
        read_mesh_from_bytes(bytes, Format::Ply)
    }

    const ASCII_SQUARE: &str = "ply\nformat ascii 1.0\ncomment a square\nobj_info x\n\
        element vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
        element face 1\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

    #[test]
    fn ascii_quad_is_fan_triangulated() {
        let f = read(ASCII_SQUARE.as_bytes()).unwrap();
        assert_eq!(f.stored_faces, 1);
        assert_eq!(f.mesh.positions[2], [1.0, 1.0, 0.0]);
        assert_eq!(f.mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(f.mesh.uvs, None);
    }

    /// Big-endian file with extra vertex properties of mixed types (uchar colour, float
    /// normal, a list), u/v texture coordinates, an int-count uint-index list, a face flag
    /// and an extra element after the faces.
    fn big_endian_file() -> Vec<u8> {
        let mut b = b"ply\r\nformat binary_big_endian 1.0\r\nelement vertex 3\r\n\
            property double x\r\nproperty uchar red\r\nproperty float y\r\nproperty short z\r\n\
            property list uchar ushort extra\r\nproperty float u\r\nproperty float v\r\n\
            element face 1\r\nproperty uchar flags\r\nproperty list int uint vertex_index\r\n\
            element edge 2\r\nproperty int vertex1\r\nproperty list ushort char tags\r\nend_header\r\n"
            .to_vec();
        let verts: [(f64, f32, i16, f32, f32); 3] = [
            (0.1, 0.0, 0, 0.0, 0.0),
            (1.0, -2.5, 7, 1.0, 0.0),
            (-3.25, 1.0, -1, 0.5, 0.75),
        ];
        for (i, (x, y, z, u, v)) in verts.into_iter().enumerate() {
            b.extend(x.to_be_bytes());
            b.push(200);
            b.extend(y.to_be_bytes());
            b.extend(z.to_be_bytes());
            b.push(i as u8); // list of i ushorts
            for k in 0..i as u16 {
                b.extend((1000 + k).to_be_bytes());
            }
            b.extend(u.to_be_bytes());
            b.extend(v.to_be_bytes());
        }
        b.push(1);
        b.extend(3i32.to_be_bytes());
        for i in [2u32, 0, 1] {
            b.extend(i.to_be_bytes());
        }
        for e in 0..2i32 {
            b.extend(e.to_be_bytes());
            b.extend(2u16.to_be_bytes());
            b.extend([1u8, 2]);
        }
        b
    }

    #[test]
    fn big_endian_with_extra_properties_and_elements() {
        let f = read(&big_endian_file()).unwrap();
        assert_eq!(
            f.mesh.positions,
            vec![[0.1, 0.0, 0.0], [1.0, -2.5, 7.0], [-3.25, 1.0, -1.0]]
        );
        assert_eq!(f.mesh.triangles, vec![[2, 0, 1]]);
        assert_eq!(
            f.mesh.uvs,
            Some(Uvs::PerVertex(vec![[0.0, 0.0], [1.0, 0.0], [0.5, 0.75]]))
        );
        assert_eq!(f.stored_faces, 1);
    }

    #[test]
    fn big_endian_truncation_reports_the_byte_offset_of_the_missing_value() {
        let full = big_endian_file();
        // Cut inside the face element's index list: the error is at the first missing index.
        let header_len = full
            .windows(12)
            .position(|w| w == b"end_header\r\n")
            .unwrap()
            + 12;
        let vertex_bytes = 8 + 1 + 4 + 2 + 1 + 4 + 4; // per vertex without list items
        let face_start = header_len + 3 * vertex_bytes + 2 * 3; // 0 + 1 + 2 ushort list items
        let cut = face_start + 1 + 4 + 4; // flags, count, first index
        let err = read(&full[..cut + 2]).unwrap_err();
        assert!(matches!(err, ReadError::Truncated { .. }), "{err}");
        assert_eq!(err.location(), Some(Location::Byte(cut as u64)), "{err}");
        assert!(err.to_string().contains("element 'face'"), "{err}");
    }

    #[test]
    fn little_endian_double_and_texcoord_lists() {
        let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty double x\n\
            property double y\nproperty double z\nelement face 1\n\
            property list uchar uint vertex_indices\nproperty list uchar float texcoord\nend_header\n"
            .to_vec();
        for p in [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0f64],
        ] {
            for x in p {
                b.extend(x.to_le_bytes());
            }
        }
        b.push(4);
        for i in 0..4u32 {
            b.extend(i.to_le_bytes());
        }
        b.push(8);
        for x in [0.0f32, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0] {
            b.extend(x.to_le_bytes());
        }
        let f = read(&b).unwrap();
        assert_eq!(f.mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        let Some(Uvs::PerCorner { coords, indices }) = &f.mesh.uvs else {
            panic!("{:?}", f.mesh.uvs)
        };
        // Corner UVs equal the xy of the corner position, by construction of the file.
        for (tri, uvt) in f.mesh.triangles.iter().zip(indices) {
            for k in 0..3 {
                let p = f.mesh.positions[tri[k] as usize];
                assert_eq!(coords[uvt[k] as usize], [p[0], p[1]]);
            }
        }
    }

    #[test]
    fn element_without_properties_and_huge_count_is_skipped_instantly() {
        let text = ASCII_SQUARE.replace(
            "end_header",
            "element nothing 18446744073709551615\nend_header",
        );
        // u64::MAX does not parse as i64: the count is rejected as a syntax error instead.
        assert!(matches!(
            read(text.as_bytes()),
            Err(ReadError::Syntax { .. })
        ));
        let text = ASCII_SQUARE.replace(
            "end_header",
            "element nothing 9000000000000000000\nend_header",
        );
        assert_eq!(read(text.as_bytes()).unwrap().mesh.triangles.len(), 2);
    }

    #[test]
    fn malformed_inputs_give_the_right_error_and_place() {
        let replace = |from: &str, to: &str| ASCII_SQUARE.replacen(from, to, 1).into_bytes();
        let cases: Vec<Case> = vec![
            (
                replace("4 0 1 2 3", "3 0 1 4"),
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
                Location::Line(16),
            ),
            (
                replace("4 0 1 2 3", "3 0 -1 2"),
                |e| matches!(e, ReadError::IndexOutOfRange { index: -1, .. }),
                Location::Line(16),
            ),
            (
                replace("4 0 1 2 3", "2 0 1"),
                |e| matches!(e, ReadError::FaceTooSmall { corners: 2, .. }),
                Location::Line(16),
            ),
            (
                replace("1 1 0\n", "1 x 0\n"),
                |e| matches!(e, ReadError::Syntax { .. }),
                Location::Line(14),
            ),
            (
                replace("4 0 1 2 3\n", "4 0 1\n"),
                |e| matches!(e, ReadError::Truncated { .. }),
                Location::Line(17),
            ),
            (
                replace("ply", "plx"),
                |e| matches!(e, ReadError::Syntax { .. }),
                Location::Line(1),
            ),
            (
                replace("ascii", "utf8"),
                |e| matches!(e, ReadError::Syntax { .. }),
                Location::Line(2),
            ),
            (
                replace("property float y", "property quad y"),
                |e| matches!(e, ReadError::Syntax { .. }),
                Location::Line(7),
            ),
            (
                replace("property float y", "property float w"),
                |e| matches!(e, ReadError::Syntax { .. }),
                Location::Line(5),
            ),
            (
                replace("vertex_indices", "corners"),
                |e| matches!(e, ReadError::Syntax { .. }),
                Location::Line(9),
            ),
            (
                replace("end_header\n", "bogus\n"),
                |e| matches!(e, ReadError::Syntax { .. }),
                Location::Line(11),
            ),
            (
                b"ply\nformat ascii 1.0\nelement vertex 1\n".to_vec(),
                |e| matches!(e, ReadError::Truncated { .. }),
                Location::Line(4),
            ),
            (
                replace("element vertex 4", "element vertex 5000000000"),
                |e| matches!(e, ReadError::TooMany { .. }),
                Location::Line(1),
            ),
        ];
        for (bytes, is_right, at) in cases {
            let text = String::from_utf8_lossy(&bytes).into_owned();
            let err = read(&bytes).unwrap_err();
            assert!(is_right(&err), "{text}: wrong variant {err:?}");
            assert_eq!(err.location(), Some(at), "{text}: {err}");
        }
    }

    #[test]
    fn binary_index_error_names_the_byte_offset() {
        let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
            property float y\nproperty float z\nelement face 1\n\
            property list uchar int vertex_indices\nend_header\n"
            .to_vec();
        let header_len = b.len();
        b.extend([0u8; 36]);
        b.push(3);
        for i in [0i32, 1, 3] {
            b.extend(i.to_le_bytes());
        }
        let err = read(&b).unwrap_err();
        assert!(
            matches!(
                err,
                ReadError::IndexOutOfRange {
                    index: 3,
                    count: 3,
                    ..
                }
            ),
            "{err}"
        );
        let offset = header_len + 36 + 1 + 8;
        assert_eq!(err.location(), Some(Location::Byte(offset as u64)));
        assert!(err.to_string().contains(&format!("byte offset {offset}")));
    }

    #[test]
    fn huge_list_length_in_binary_fails_without_allocating() {
        let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n\
            property float y\nproperty float z\nproperty list uint float junk\nend_header\n"
            .to_vec();
        b.extend([0u8; 12]);
        b.extend(u32::MAX.to_le_bytes());
        assert!(matches!(read(&b), Err(ReadError::Truncated { .. })));
    }
}
