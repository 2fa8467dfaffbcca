//! NumPy `.npy` format version 1.0 writer: magic `\x93NUMPY`, version `1 0`, a little-endian
//! `u16` header length, an ASCII dict header (`descr`, `fortran_order`, `shape`) padded
//! with spaces and a newline to a multiple of 64 bytes, then the raw C-order data.

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
}
