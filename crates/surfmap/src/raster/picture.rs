//! Colour-mapped pictures of geometry images (like thesis Fig. 3.6, 3.8) and a labelled
//! contact sheet. Grid row `i = 0` (`ξ_y = 0`) is drawn at the bottom of the picture.

use std::path::Path;

/// An 8-bit RGB picture, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Picture {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<[u8; 3]>,
}

/// Colour of nodes outside the surface.
pub const OUTSIDE_GREY: [u8; 3] = [96, 96, 96];

impl Picture {
    pub fn new(width: usize, height: usize, fill: [u8; 3]) -> Self {
        Self {
            width,
            height,
            rgb: vec![fill; width * height],
        }
    }

    /// Maps a `size × size` grid image to a picture, flipping rows so `ξ_y` points up.
    pub fn from_grid(size: usize, colour: impl Fn(usize) -> [u8; 3]) -> Self {
        let mut p = Self::new(size, size, [0, 0, 0]);
        for i in 0..size {
            for j in 0..size {
                p.rgb[(size - 1 - i) * size + j] = colour(i * size + j);
            }
        }
        p
    }

    /// Writes the picture as PNG through `write_atomically`.
    pub fn save_png(&self, path: &Path) -> std::io::Result<()> {
        let bytes: Vec<u8> = self.rgb.iter().flatten().copied().collect();
        let img = image::RgbImage::from_raw(self.width as u32, self.height as u32, bytes)
            .ok_or_else(|| std::io::Error::other("picture buffer has the wrong size"))?;
        crate::fsutil::write_atomically(path, |w| {
            let mut buf = std::io::Cursor::new(Vec::new());
            img.write_to(&mut buf, image::ImageFormat::Png)
                .map_err(std::io::Error::other)?;
            w.write_all(buf.get_ref())
        })
    }

    /// Copies `other` with its top-left corner at `(x, y)`, clipped.
    pub fn blit(&mut self, other: &Picture, x: usize, y: usize) {
        for r in 0..other.height.min(self.height.saturating_sub(y)) {
            for c in 0..other.width.min(self.width.saturating_sub(x)) {
                self.rgb[(y + r) * self.width + x + c] = other.rgb[r * other.width + c];
            }
        }
    }

    /// Nearest-neighbour resize.
    pub fn resized(&self, width: usize, height: usize) -> Picture {
        let mut p = Picture::new(width, height, [0, 0, 0]);
        for r in 0..height {
            for c in 0..width {
                p.rgb[r * width + c] =
                    self.rgb[(r * self.height / height) * self.width + c * self.width / width];
            }
        }
        p
    }

    /// Draws `text` (upper-cased; A–Z, 0–9 and ` .,:=-+()/#σ²`) with a 5×7 font scaled by `scale`.
    pub fn draw_text(&mut self, text: &str, x: usize, y: usize, scale: usize, colour: [u8; 3]) {
        let mut cx = x;
        for ch in text.chars() {
            let g = glyph(ch.to_ascii_uppercase());
            for (row, bits) in g.iter().enumerate() {
                for col in 0..5 {
                    if bits & (0x10 >> col) != 0 {
                        for dy in 0..scale {
                            for dx in 0..scale {
                                let (px, py) = (cx + col * scale + dx, y + row * scale + dy);
                                if px < self.width && py < self.height {
                                    self.rgb[py * self.width + px] = colour;
                                }
                            }
                        }
                    }
                }
            }
            cx += 6 * scale;
        }
    }
}

/// Linear interpolation through colour stops at `t ∈ [0, 1]`.
fn ramp(stops: &[[f64; 3]], t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (stops.len() - 1) as f64;
    let i = (x.floor() as usize).min(stops.len() - 2);
    let f = x - i as f64;
    std::array::from_fn(|c| ((stops[i][c] * (1.0 - f) + stops[i + 1][c] * f) * 255.0).round() as u8)
}

/// Viridis-like sequential map.
pub fn sequential(t: f64) -> [u8; 3] {
    const S: [[f64; 3]; 5] = [
        [0.267, 0.005, 0.329],
        [0.229, 0.322, 0.546],
        [0.128, 0.567, 0.551],
        [0.369, 0.789, 0.383],
        [0.993, 0.906, 0.144],
    ];
    ramp(&S, t)
}

/// Blue–white–red diverging map, `t ∈ [−1, 1]`.
pub fn diverging(t: f64) -> [u8; 3] {
    const S: [[f64; 3]; 3] = [[0.13, 0.30, 0.75], [0.97, 0.97, 0.97], [0.75, 0.12, 0.15]];
    ramp(&S, 0.5 * (t + 1.0))
}

/// The `q`-quantile of the finite values' magnitudes (robust colour range).
pub fn abs_quantile(values: impl Iterator<Item = f64>, q: f64) -> f64 {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).map(f64::abs).collect();
    if v.is_empty() {
        return 1.0;
    }
    let k = ((v.len() - 1) as f64 * q) as usize;
    let (_, x, _) = v.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
    if *x > 0.0 { *x } else { 1.0 }
}

/// Scalar image with a diverging map symmetric about 0 (range: 98th percentile of |v|);
/// `NaN` nodes grey.
pub fn diverging_picture(size: usize, values: &[f64]) -> Picture {
    let range = abs_quantile(values.iter().copied(), 0.98);
    Picture::from_grid(size, |k| {
        if values[k].is_nan() {
            OUTSIDE_GREY
        } else {
            diverging(values[k] / range)
        }
    })
}

/// Distance image: sequential map over `[0, max]` with dark iso-lines every `max/10`;
/// `NaN`/`∞` grey; `dim` darkens nodes where `dim[k]` is true (e.g. outside the surface).
pub fn distance_picture(size: usize, values: &[f64], dim: Option<&[bool]>) -> Picture {
    let max = values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |a, b| a.max(b.abs()));
    let max = if max > 0.0 { max } else { 1.0 };
    let step = max / 10.0;
    let line = 0.6 * max / size as f64;
    Picture::from_grid(size, |k| {
        let v = values[k];
        if !v.is_finite() {
            return OUTSIDE_GREY;
        }
        let mut c = sequential(v.abs() / max);
        let r = v.abs() % step;
        if r < line || step - r < line {
            c = c.map(|x| x / 3);
        }
        if dim.is_some_and(|d| d[k]) {
            c = c.map(|x| x / 2 + 32);
        }
        c
    })
}

/// Metric `[g11, g12, g22]` as RGB (thesis Fig. 3.6b): `g11`, `g22` scaled by their
/// 98th percentile, `g12` mapped from `[−r, r]`.
pub fn metric_picture(size: usize, g: &[[f64; 3]]) -> Picture {
    let r11 = abs_quantile(g.iter().map(|g| g[0]), 0.98);
    let r12 = abs_quantile(g.iter().map(|g| g[1]), 0.98);
    let r22 = abs_quantile(g.iter().map(|g| g[2]), 0.98);
    Picture::from_grid(size, |k| {
        let [a, b, c] = g[k];
        if a.is_nan() {
            return OUTSIDE_GREY;
        }
        let to = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
        [to(a / r11), to(0.5 + 0.5 * b / r12), to(c / r22)]
    })
}

/// Tiles labelled pictures into a sheet of `columns` columns, each tile `tile × tile`.
pub fn contact_sheet(tiles: &[(String, Picture)], columns: usize, tile: usize) -> Picture {
    let columns = columns.max(1);
    let rows = tiles.len().div_ceil(columns);
    let (pad, label) = (8, 30);
    let mut sheet = Picture::new(
        columns * (tile + pad) + pad,
        rows * (tile + pad + label) + pad,
        [255, 255, 255],
    );
    for (i, (name, pic)) in tiles.iter().enumerate() {
        let (x, y) = (
            pad + (i % columns) * (tile + pad),
            pad + (i / columns) * (tile + pad + label),
        );
        sheet.draw_text(name, x, y + 4, 3, [20, 20, 20]);
        sheet.blit(&pic.resized(tile, tile), x, y + label);
    }
    sheet
}

/// 5×7 glyphs, one `u8` per row, bit 4 = leftmost column.
fn glyph(c: char) -> [u8; 7] {
    match c {
        'A' => [14, 17, 17, 31, 17, 17, 17],
        'B' => [30, 17, 17, 30, 17, 17, 30],
        'C' => [14, 17, 16, 16, 16, 17, 14],
        'D' => [30, 17, 17, 17, 17, 17, 30],
        'E' => [31, 16, 16, 30, 16, 16, 31],
        'F' => [31, 16, 16, 30, 16, 16, 16],
        'G' => [14, 17, 16, 23, 17, 17, 15],
        'H' => [17, 17, 17, 31, 17, 17, 17],
        'I' => [14, 4, 4, 4, 4, 4, 14],
        'J' => [7, 2, 2, 2, 2, 18, 12],
        'K' => [17, 18, 20, 24, 20, 18, 17],
        'L' => [16, 16, 16, 16, 16, 16, 31],
        'M' => [17, 27, 21, 21, 17, 17, 17],
        'N' => [17, 17, 25, 21, 19, 17, 17],
        'O' => [14, 17, 17, 17, 17, 17, 14],
        'P' => [30, 17, 17, 30, 16, 16, 16],
        'Q' => [14, 17, 17, 17, 21, 18, 13],
        'R' => [30, 17, 17, 30, 20, 18, 17],
        'S' => [15, 16, 16, 14, 1, 1, 30],
        'T' => [31, 4, 4, 4, 4, 4, 4],
        'U' => [17, 17, 17, 17, 17, 17, 14],
        'V' => [17, 17, 17, 17, 17, 10, 4],
        'W' => [17, 17, 17, 21, 21, 21, 10],
        'X' => [17, 17, 10, 4, 10, 17, 17],
        'Y' => [17, 17, 10, 4, 4, 4, 4],
        'Z' => [31, 1, 2, 4, 8, 16, 31],
        '0' => [14, 17, 19, 21, 25, 17, 14],
        '1' => [4, 12, 4, 4, 4, 4, 14],
        '2' => [14, 17, 1, 2, 4, 8, 31],
        '3' => [31, 2, 4, 2, 1, 17, 14],
        '4' => [2, 6, 10, 18, 31, 2, 2],
        '5' => [31, 16, 30, 1, 1, 17, 14],
        '6' => [6, 8, 16, 30, 17, 17, 14],
        '7' => [31, 1, 2, 4, 8, 8, 8],
        '8' => [14, 17, 17, 14, 17, 17, 14],
        '9' => [14, 17, 17, 15, 1, 2, 12],
        '.' => [0, 0, 0, 0, 0, 12, 12],
        ',' => [0, 0, 0, 0, 12, 4, 8],
        ':' => [0, 12, 12, 0, 12, 12, 0],
        '=' => [0, 0, 31, 0, 31, 0, 0],
        '-' => [0, 0, 0, 31, 0, 0, 0],
        '+' => [0, 4, 4, 31, 4, 4, 0],
        '(' => [2, 4, 8, 8, 8, 4, 2],
        ')' => [8, 4, 2, 2, 2, 4, 8],
        '/' => [0, 1, 2, 4, 8, 16, 0],
        '#' => [10, 10, 31, 10, 31, 10, 10],
        '²' => [12, 2, 4, 8, 14, 0, 0],
        'Σ' | 'σ' => [0, 0, 15, 18, 18, 18, 12],
        _ => [0; 7],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_rows_are_flipped_and_maps_hit_their_ends() {
        let p = Picture::from_grid(3, |k| [k as u8, 0, 0]);
        assert_eq!(p.rgb[0], [6, 0, 0]); // top-left = grid row 2, column 0
        assert_eq!(p.rgb[8], [2, 0, 0]);
        assert_eq!(diverging(0.0), [247, 247, 247]);
        assert_eq!(sequential(1.0), [253, 231, 37]);
        let s = contact_sheet(&[("H".into(), p.clone()), ("G".into(), p)], 2, 20);
        assert_eq!(s.width, 2 * 28 + 8);
        assert!(s.rgb.contains(&[20, 20, 20]));
    }
}
