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

/// Writes named `.npy` streams (each `(name, bytes)`, e.g. from [`write_npy`] into a
/// `Vec`) as an `.npz` file, atomically: a zip archive whose members `NAME.npy` are
/// *stored* (no compression, as `numpy.savez` writes them), each with its CRC-32. Fails
/// for archives beyond 4 GiB (no zip64).
pub fn save_npz(path: &Path, arrays: &[(&str, Vec<u8>)]) -> io::Result<()> {
    let too_big = || io::Error::new(io::ErrorKind::InvalidInput, "npz archive beyond 4 GiB");
    let mut body: Vec<u8> = Vec::new();
    let mut central: Vec<u8> = Vec::new();
    for (name, data) in arrays {
        let file = format!("{name}.npy");
        let offset = u32::try_from(body.len()).map_err(|_| too_big())?;
        let size = u32::try_from(data.len()).map_err(|_| too_big())?;
        let crc = crc32(data);
        // Version 2.0, no flags, stored, time 00:00 of 1980-01-01 (date 0x21).
        let common = |out: &mut Vec<u8>| {
            for v in [20u16, 0, 0, 0, 0x21] {
                out.extend_from_slice(&v.to_le_bytes());
            }
            for v in [crc, size, size] {
                out.extend_from_slice(&v.to_le_bytes());
            }
            out.extend_from_slice(&(file.len() as u16).to_le_bytes());
            out.extend_from_slice(&0u16.to_le_bytes());
        };
        body.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        common(&mut body);
        body.extend_from_slice(file.as_bytes());
        body.extend_from_slice(data);
        central.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
        central.extend_from_slice(&20u16.to_le_bytes());
        common(&mut central);
        // Comment length, disk, internal and external attributes, local header offset.
        for v in [0u16, 0, 0] {
            central.extend_from_slice(&v.to_le_bytes());
        }
        central.extend_from_slice(&0u32.to_le_bytes());
        central.extend_from_slice(&offset.to_le_bytes());
        central.extend_from_slice(file.as_bytes());
    }
    let entries = u16::try_from(arrays.len()).map_err(|_| too_big())?;
    let start = u32::try_from(body.len()).map_err(|_| too_big())?;
    let length = u32::try_from(central.len()).map_err(|_| too_big())?;
    start.checked_add(length).ok_or_else(too_big)?;
    crate::fsutil::write_atomically(path, |w| {
        w.write_all(&body)?;
        w.write_all(&central)?;
        w.write_all(&0x0605_4b50u32.to_le_bytes())?;
        for v in [0u16, 0, entries, entries] {
            w.write_all(&v.to_le_bytes())?;
        }
        w.write_all(&length.to_le_bytes())?;
        w.write_all(&start.to_le_bytes())?;
        w.write_all(&0u16.to_le_bytes())
    })
}

/// CRC-32 (IEEE 802.3, reflected polynomial `0xEDB88320`), as zip stores it.
pub fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &byte in data {
        crc ^= byte as u32;
        for _ in 0..8 {
            crc = (crc >> 1) ^ (0xEDB8_8320 & (crc & 1).wrapping_neg());
        }
    }
    !crc
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

    /// The check value of CRC-32 ("123456789" → 0xCBF43926), and an archive whose
    /// members sit where its central directory says, with their CRCs.
    #[test]
    fn npz_is_a_stored_zip_of_npy_members() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        let mut a = Vec::new();
        write_npy(&mut a, &[2, 2], &[1.0f64, 2.0, 3.0, 4.0]).unwrap();
        let mut b = Vec::new();
        write_npy(&mut b, &[3], &[7u32, 8, 9]).unwrap();
        let dir = std::env::temp_dir().join(format!("surfmap-npz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.npz");
        save_npz(&path, &[("mean", a.clone()), ("ids", b.clone())]).unwrap();
        let z = std::fs::read(&path).unwrap();
        let u16_at = |i: usize| u16::from_le_bytes([z[i], z[i + 1]]) as usize;
        let u32_at = |i: usize| u32::from_le_bytes(z[i..i + 4].try_into().unwrap()) as usize;
        let end = z.len() - 22;
        assert_eq!(u32_at(end), 0x0605_4b50);
        assert_eq!(u16_at(end + 10), 2);
        let mut at = u32_at(end + 16);
        for (name, data) in [("mean.npy", &a), ("ids.npy", &b)] {
            assert_eq!(u32_at(at), 0x0201_4b50);
            assert_eq!(u32_at(at + 16), crc32(data) as usize);
            let name_len = u16_at(at + 28);
            assert_eq!(&z[at + 46..at + 46 + name_len], name.as_bytes());
            let local = u32_at(at + 42);
            assert_eq!(u32_at(local), 0x0403_4b50);
            let start = local + 30 + u16_at(local + 26);
            assert_eq!(&z[start..start + data.len()], data.as_slice());
            at += 46 + name_len;
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
