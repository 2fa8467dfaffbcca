//! A page under construction: the data it embeds (a JSON document whose typed arrays are
//! base64 text) and its assembly into one self-contained HTML file around the viewer's
//! own HTML, CSS and JavaScript (`assets/`, embedded in the library with
//! `include_str!`: no network access, no build step, no Node).
//!
//! Arrays are little-endian `Float32Array`, `Uint32Array` or `Int32Array` bytes, base64
//! encoded (RFC 4648, with padding) and listed in the document's `arrays` object by
//! name: `{"type": "f32", "length": n, "b64": "…"}`; the page decodes each once. JSON
//! is placed inside `<script type="application/json">`, so `<` is written `\u003c`
//! (a string in the data cannot close the script element).

use serde_json::{Map, Value, json};

const HTML: &str = include_str!("assets/viewer.html");
const CSS: &str = include_str!("assets/viewer.css");
const JS: &str = include_str!("assets/viewer.js");

/// The embedded document: page metadata (`doc`) and named typed arrays.
#[derive(Debug, Default)]
pub struct PageData {
    pub doc: Map<String, Value>,
    arrays: Map<String, Value>,
    /// Bytes of array data before encoding (for the summary).
    pub array_bytes: usize,
}

/// Element types an array can have in the page.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArrayType {
    F32,
    U32,
    I32,
}

impl ArrayType {
    fn name(self) -> &'static str {
        match self {
            ArrayType::F32 => "f32",
            ArrayType::U32 => "u32",
            ArrayType::I32 => "i32",
        }
    }
}

impl PageData {
    /// A page of `kind` (`flattening`, `match`, `morph`, `table`) titled `title`.
    pub fn new(kind: &str, title: &str) -> Self {
        let mut data = Self::default();
        data.doc.insert("kind".into(), json!(kind));
        data.doc.insert("title".into(), json!(title));
        data.doc.insert(
            "generator".into(),
            json!(concat!("surfmap ", env!("CARGO_PKG_VERSION"))),
        );
        data
    }

    /// Sets a metadata field.
    pub fn set(&mut self, key: &str, value: Value) {
        self.doc.insert(key.into(), value);
    }

    fn add_bytes(&mut self, name: &str, ty: ArrayType, length: usize, bytes: &[u8]) {
        self.array_bytes += bytes.len();
        self.arrays.insert(
            name.into(),
            json!({"type": ty.name(), "length": length, "b64": base64(bytes)}),
        );
    }

    /// `values` as a `Float32Array` named `name`. Infinities are stored as ±`f32::MAX`
    /// and NaN as `nan_as` (the page reads a sentinel, not NaN, from a vertex buffer).
    pub fn add_f32(&mut self, name: &str, values: impl IntoIterator<Item = f64>, nan_as: f32) {
        let mut bytes = vec![];
        let mut n = 0;
        for x in values {
            let v = if x.is_nan() {
                nan_as
            } else {
                (x as f32).clamp(f32::MIN, f32::MAX)
            };
            bytes.extend_from_slice(&v.to_le_bytes());
            n += 1;
        }
        self.add_bytes(name, ArrayType::F32, n, &bytes);
    }

    /// Points of `D` coordinates as a flat `Float32Array`.
    pub fn add_points<const D: usize>(&mut self, name: &str, points: &[[f64; D]]) {
        self.add_f32(name, points.iter().flatten().copied(), 0.0);
    }

    /// `values` as a `Uint32Array`.
    pub fn add_u32(&mut self, name: &str, values: impl IntoIterator<Item = u32>) {
        let bytes: Vec<u8> = values.into_iter().flat_map(u32::to_le_bytes).collect();
        self.add_bytes(name, ArrayType::U32, bytes.len() / 4, &bytes);
    }

    /// `values` as an `Int32Array`.
    pub fn add_i32(&mut self, name: &str, values: impl IntoIterator<Item = i32>) {
        let bytes: Vec<u8> = values.into_iter().flat_map(i32::to_le_bytes).collect();
        self.add_bytes(name, ArrayType::I32, bytes.len() / 4, &bytes);
    }

    /// Triangles as a flat `Uint32Array`.
    pub fn add_triangles(&mut self, name: &str, triangles: &[[u32; 3]]) {
        self.add_u32(name, triangles.iter().flatten().copied());
    }

    /// The JSON document (metadata and arrays).
    pub fn to_json(&self) -> Value {
        let mut doc = self.doc.clone();
        doc.insert("arrays".into(), Value::Object(self.arrays.clone()));
        Value::Object(doc)
    }

    /// The whole HTML page.
    pub fn html(&self) -> String {
        let title = self
            .doc
            .get("title")
            .and_then(Value::as_str)
            .unwrap_or("surfmap");
        let json = script_safe_json(&self.to_json());
        // Each placeholder appears once in the template; the data goes in last so that
        // nothing inside it is mistaken for a placeholder.
        HTML.replacen("{{TITLE}}", &escape_html(title), 1)
            .replacen("/*{{CSS}}*/", CSS, 1)
            .replacen("/*{{JS}}*/", JS, 1)
            .replacen("{{DATA}}", &json, 1)
    }
}

/// JSON text that can sit inside a `<script>` element: every `<` as `\u003c` (valid
/// JSON, the same string), so no `</script>` or `<!--` can appear in it.
pub fn script_safe_json(value: &Value) -> String {
    serde_json::to_string(value)
        .expect("a serde_json::Value always serializes")
        .replace('<', "\\u003c")
}

/// Text for an HTML element or attribute.
pub fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Standard base64 (RFC 4648 §4) with `=` padding.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        let sextets = [18, 12, 6, 0].map(|s| ALPHABET[(n >> s & 63) as usize] as char);
        let kept = chunk.len() + 1;
        for (k, c) in sextets.into_iter().enumerate() {
            out.push(if k < kept { c } else { '=' });
        }
    }
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Decodes standard padded base64 (the page's `atob`), for the tests.
    pub(crate) fn unbase64(text: &str) -> Vec<u8> {
        let value = |c: u8| -> u32 {
            match c {
                b'A'..=b'Z' => (c - b'A') as u32,
                b'a'..=b'z' => (c - b'a' + 26) as u32,
                b'0'..=b'9' => (c - b'0' + 52) as u32,
                b'+' => 62,
                b'/' => 63,
                _ => panic!("not base64: {c}"),
            }
        };
        let mut out = vec![];
        for quad in text.as_bytes().chunks(4) {
            let pad = quad.iter().filter(|&&c| c == b'=').count();
            let n = quad
                .iter()
                .map(|&c| if c == b'=' { 0 } else { value(c) })
                .fold(0u32, |acc, v| acc << 6 | v);
            let bytes = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
            out.extend_from_slice(&bytes[..3 - pad]);
        }
        out
    }

    /// The array `name` of a page's JSON document, decoded as little-endian 4-byte
    /// values and converted by `f`.
    pub(crate) fn array<T>(doc: &Value, name: &str, f: fn([u8; 4]) -> T) -> Vec<T> {
        let a = &doc["arrays"][name];
        let bytes = unbase64(
            a["b64"]
                .as_str()
                .unwrap_or_else(|| panic!("no array {name}")),
        );
        let values: Vec<T> = bytes
            .chunks_exact(4)
            .map(|c| f(c.try_into().unwrap()))
            .collect();
        assert_eq!(values.len() as u64, a["length"].as_u64().unwrap());
        values
    }

    /// The JSON document embedded in a page.
    pub(crate) fn embedded(html: &str) -> Value {
        let start = html.find("id=\"surfmap-data\">").expect("a data element")
            + "id=\"surfmap-data\">".len();
        let end = start + html[start..].find("</script>").unwrap();
        serde_json::from_str(&html[start..end]).expect("valid JSON")
    }

    #[test]
    fn base64_matches_the_rfc_vectors() {
        // RFC 4648 §10.
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded);
            assert_eq!(unbase64(coded), plain.as_bytes());
        }
        let all: Vec<u8> = (0..=255).collect();
        assert_eq!(unbase64(&base64(&all)), all);
    }

    #[test]
    fn arrays_round_trip_and_the_data_cannot_close_its_script() {
        let mut page = PageData::new("flattening", "a </script> <b>");
        page.add_f32(
            "v",
            [1.5, f64::NAN, f64::INFINITY, -f64::INFINITY, 1e300],
            -1.0,
        );
        page.add_u32("t", [0, 7, u32::MAX]);
        page.add_i32("c", [-1, 3]);
        page.set("note", json!("</script><!-- x"));
        let html = page.html();
        assert_eq!(
            html.matches("</script>").count(),
            2,
            "one per script element"
        );
        assert!(html.contains("<title>a &lt;/script&gt; &lt;b&gt;</title>"));
        let doc = embedded(&html);
        assert_eq!(doc["note"], "</script><!-- x");
        assert_eq!(
            array(&doc, "v", f32::from_le_bytes),
            vec![1.5, -1.0, f32::MAX, f32::MIN, f32::MAX]
        );
        assert_eq!(array(&doc, "t", u32::from_le_bytes), vec![0, 7, u32::MAX]);
        assert_eq!(array(&doc, "c", i32::from_le_bytes), vec![-1, 3]);
        // No placeholder is left, and the viewer's script is in the page.
        assert!(!html.contains("{{") && !html.contains("/*{{"));
        assert!(html.contains("surfmapView"));
    }
}
