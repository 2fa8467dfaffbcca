//! NumPy `.npy` format version 1.0 writer: magic `\x93NUMPY`, version `1 0`, a little-endian
//! `u16` header length, an ASCII dict header (`descr`, `fortran_order`, `shape`) padded
//! with spaces and a newline to a multiple of 64 bytes, then the raw C-order data; and a
//! reader of `float64` arrays (versions 1–3, C order, little or big endian).

use std::io::{self, Write};
use std::path::Path;

/// Element types that can be written.
pub trait NpyElement: Copy {
    const DESCR: &'static str;
    fn write_le(self, w: &mut dyn Write) -> io::Result<()>;
}
impl NpyElement for f64 {
    const DESCR: &'static str = "<f8";
    fn write_le(self, w: &mut dyn Write) -> io::Result<()> {
        w.write_all(&self.to_le_bytes())
    }
}
impl NpyElement for f32 {
    const DESCR: &'static str = "<f4";
    fn write_le(self, w: &mut dyn Write) -> io::Result<()> {
        w.write_all(&self.to_le_bytes())
    }
}
impl NpyElement for u32 {
    const DESCR: &'static str = "<u4";
    fn write_le(self, w: &mut dyn Write) -> io::Result<()> {
        w.write_all(&self.to_le_bytes())
    }
}
impl NpyElement for u8 {
    const DESCR: &'static str = "|u1";
    fn write_le(self, w: &mut dyn Write) -> io::Result<()> {
        w.write_all(&[self])
    }
}

/// The `.npy` header for `shape` and element type `T`.
pub fn npy_header<T: NpyElement>(shape: &[usize]) -> Vec<u8> {
    let dims = match shape {
        [d] => format!("({d},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut dict = format!(
        "{{'descr': '{}', 'fortran_order': False, 'shape': {dims}, }}",
        T::DESCR
    );
    let unpadded = 10 + dict.len() + 1;
    dict.push_str(&" ".repeat(unpadded.next_multiple_of(64) - unpadded));
    dict.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out
}

/// Writes `data` (C order, `shape.iter().product()` elements) as a `.npy` stream.
pub fn write_npy<T: NpyElement>(w: &mut dyn Write, shape: &[usize], data: &[T]) -> io::Result<()> {
    if shape.iter().product::<usize>() != data.len() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("npy shape {shape:?} does not match {} elements", data.len()),
        ));
    }
    w.write_all(&npy_header::<T>(shape))?;
    for &x in data {
        x.write_le(w)?;
    }
    Ok(())
}

/// Writes a `.npy` file atomically.
pub fn save_npy<T: NpyElement>(path: &Path, shape: &[usize], data: &[T]) -> io::Result<()> {
    crate::fsutil::write_atomically(path, |w| write_npy(w, shape, data))
}

/// Reads a `.npy` array of `float64` (`<f8` or `>f8`, C order; versions 1.0, 2.0 and
/// 3.0): its shape and values. Errors say what the file holds instead.
pub fn read_npy_f64(bytes: &[u8]) -> Result<(Vec<usize>, Vec<f64>), String> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err("not a .npy file (no \\x93NUMPY magic)".into());
    }
    let (header_len, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10usize),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(format!("unsupported .npy version {v}")),
    };
    let end = start
        .checked_add(header_len)
        .filter(|&e| e <= bytes.len())
        .ok_or("the .npy header is cut short")?;
    let header =
        std::str::from_utf8(&bytes[start..end]).map_err(|_| "the .npy header is not text")?;
    let value_of = |key: &str| -> Option<&str> {
        let at = header.find(&format!("'{key}'"))? + key.len() + 2;
        let rest = header[at..].trim_start().strip_prefix(':')?.trim_start();
        Some(rest)
    };
    let descr = value_of("descr").ok_or("the .npy header has no 'descr'")?;
    let big_endian = if descr.starts_with("'<f8'") {
        false
    } else if descr.starts_with("'>f8'") {
        true
    } else {
        let shown: String = descr.chars().take_while(|&c| c != ',').collect();
        return Err(format!(
            "the array holds {shown}, expected float64 ('<f8'); save it with .astype(np.float64)"
        ));
    };
    if value_of("fortran_order").is_some_and(|v| v.starts_with("True")) {
        return Err("the array is in Fortran order; save it with np.ascontiguousarray".into());
    }
    let shape_text = value_of("shape").ok_or("the .npy header has no 'shape'")?;
    let inner = shape_text
        .strip_prefix('(')
        .and_then(|s| s.split(')').next())
        .ok_or("the .npy shape is not a tuple")?;
    let shape: Vec<usize> = inner
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().map_err(|_| format!("bad .npy dimension '{s}'")))
        .collect::<Result<_, _>>()?;
    let count = shape
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d))
        .ok_or("the .npy shape is too large")?;
    let data = &bytes[end..];
    if data.len() != count * 8 {
        return Err(format!(
            "the .npy data has {} bytes, but shape {shape:?} of float64 needs {}",
            data.len(),
            count * 8
        ));
    }
    let values = data
        .chunks_exact(8)
        .map(|c| {
            let b: [u8; 8] = c.try_into().expect("8 bytes");
            if big_endian {
                f64::from_be_bytes(b)
            } else {
                f64::from_le_bytes(b)
            }
        })
        .collect();
    Ok((shape, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_aligned_and_parsable() {
        let mut buf = vec![];
        write_npy(&mut buf, &[2, 3], &[1.0f64, 2.0, 3.0, 4.0, 5.0, -0.5]).unwrap();
        assert_eq!(&buf[..8], b"\x93NUMPY\x01\x00");
        let hlen = u16::from_le_bytes([buf[8], buf[9]]) as usize;
        assert_eq!((10 + hlen) % 64, 0);
        let header = std::str::from_utf8(&buf[10..10 + hlen]).unwrap();
        assert!(header.starts_with("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }"));
        assert!(header.ends_with('\n'));
        assert_eq!(buf.len(), 10 + hlen + 6 * 8);
        let last = f64::from_le_bytes(buf[buf.len() - 8..].try_into().unwrap());
        assert_eq!(last, -0.5);
        assert!(npy_header::<u8>(&[7]).windows(4).any(|w| w == b"(7,)"));
        assert!(write_npy(&mut vec![], &[2, 2], &[1u8]).is_err());
    }

    #[test]
    fn written_arrays_read_back_and_wrong_types_are_named() {
        let data = [1.5f64, -2.0, 3.25, f64::NAN, 0.0, 1e300];
        let mut buf = vec![];
        write_npy(&mut buf, &[3, 2], &data).unwrap();
        let (shape, back) = read_npy_f64(&buf).unwrap();
        assert_eq!(shape, vec![3, 2]);
        assert_eq!(back.len(), 6);
        for (a, b) in back.iter().zip(data) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
        let mut one = vec![];
        write_npy(&mut one, &[4], &[1.0f64, 2.0, 3.0, 4.0]).unwrap();
        assert_eq!(read_npy_f64(&one).unwrap().0, vec![4]);
        let mut ints = vec![];
        write_npy(&mut ints, &[2], &[1u32, 2]).unwrap();
        let e = read_npy_f64(&ints).unwrap_err();
        assert!(e.contains("<u4") && e.contains("float64"), "{e}");
        assert!(
            read_npy_f64(&buf[..buf.len() - 3])
                .unwrap_err()
                .contains("bytes")
        );
        assert!(read_npy_f64(b"hello").is_err());
    }
}
