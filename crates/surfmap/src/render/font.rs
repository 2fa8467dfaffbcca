//! A tiny built-in 5×7 bitmap font (digits, Latin capitals, some punctuation, α σ Σ γ Γ ²)
//! for labels in pictures. Lower-case letters are drawn as capitals; characters
//! without a glyph are drawn as a hollow box.

use image::{Rgb, RgbImage};

/// Glyph cell: 5 columns × 7 rows, drawn with one column of spacing.
pub const GLYPH_W: u32 = 5;
pub const GLYPH_H: u32 = 7;

/// Rows of a glyph, top to bottom; bit 4 is the leftmost column.
fn glyph(c: char) -> [u8; 7] {
    let c = c.to_ascii_uppercase();
    match c {
        ' ' => [0, 0, 0, 0, 0, 0, 0],
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        'A' => [0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'B' => [0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E],
        'C' => [0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E],
        'D' => [0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C],
        'E' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F],
        'F' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10],
        'G' => [0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F],
        'H' => [0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'I' => [0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E],
        'J' => [0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C],
        'K' => [0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11],
        'L' => [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F],
        'M' => [0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11],
        'N' => [0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11],
        'O' => [0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'P' => [0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10],
        'Q' => [0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D],
        'R' => [0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11],
        'S' => [0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E],
        'T' => [0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04],
        'U' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'V' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04],
        'W' => [0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A],
        'X' => [0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11],
        'Y' => [0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04],
        'Z' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F],
        '.' => [0, 0, 0, 0, 0, 0x0C, 0x0C],
        ',' => [0, 0, 0, 0, 0x0C, 0x04, 0x08],
        ':' => [0, 0x0C, 0x0C, 0, 0x0C, 0x0C, 0],
        ';' => [0, 0x0C, 0x0C, 0, 0x0C, 0x04, 0x08],
        '-' => [0, 0, 0, 0x1F, 0, 0, 0],
        '+' => [0, 0x04, 0x04, 0x1F, 0x04, 0x04, 0],
        '=' => [0, 0, 0x1F, 0, 0x1F, 0, 0],
        '/' => [0, 0x01, 0x02, 0x04, 0x08, 0x10, 0],
        '\\' => [0, 0x10, 0x08, 0x04, 0x02, 0x01, 0],
        '*' => [0, 0x04, 0x15, 0x0E, 0x15, 0x04, 0],
        '(' => [0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02],
        ')' => [0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08],
        '[' => [0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E],
        ']' => [0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E],
        '%' => [0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03],
        '|' => [0x04, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04],
        '<' => [0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02],
        '>' => [0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08],
        '_' => [0, 0, 0, 0, 0, 0, 0x1F],
        '\'' => [0x04, 0x04, 0x08, 0, 0, 0, 0],
        '"' => [0x0A, 0x0A, 0, 0, 0, 0, 0],
        '?' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0, 0x04],
        '!' => [0x04, 0x04, 0x04, 0x04, 0x04, 0, 0x04],
        '#' => [0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A],
        '^' => [0x04, 0x0A, 0x11, 0, 0, 0, 0],
        '√' => [0x07, 0x04, 0x04, 0x04, 0x14, 0x0C, 0x04],
        'α' => [0, 0, 0x0D, 0x12, 0x12, 0x12, 0x0D],
        'σ' => [0, 0, 0x0F, 0x12, 0x12, 0x12, 0x0C],
        'Σ' => [0x1F, 0x10, 0x08, 0x04, 0x08, 0x10, 0x1F],
        '²' => [0x0C, 0x02, 0x04, 0x08, 0x0E, 0, 0],
        'Γ' => [0x1F, 0x10, 0x10, 0x10, 0x10, 0x10, 0x10],
        'γ' => [0, 0, 0x11, 0x0A, 0x04, 0x04, 0x04],
        '∞' => [0, 0, 0x0A, 0x15, 0x15, 0x0A, 0],
        _ => [0x1F, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1F],
    }
}

/// Width in pixels of `text` drawn at integer `scale`.
pub fn text_width(text: &str, scale: u32) -> u32 {
    let n = text.chars().count() as u32;
    if n == 0 {
        0
    } else {
        (n * (GLYPH_W + 1) - 1) * scale
    }
}

/// Height in pixels of one line at `scale`.
pub fn text_height(scale: u32) -> u32 {
    GLYPH_H * scale
}

/// Draws `text` with its top-left corner at `(x, y)`; pixels outside the image are
/// clipped.
pub fn draw_text(img: &mut RgbImage, x: i64, y: i64, text: &str, scale: u32, color: [u8; 3]) {
    let scale = scale.max(1) as i64;
    let (w, h) = (img.width() as i64, img.height() as i64);
    for (i, c) in text.chars().enumerate() {
        let rows = glyph(c);
        let gx = x + i as i64 * (GLYPH_W as i64 + 1) * scale;
        for (r, bits) in rows.iter().enumerate() {
            for col in 0..GLYPH_W as i64 {
                if bits & (0x10 >> col) == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let (px, py) = (gx + col * scale + dx, y + r as i64 * scale + dy);
                        if px >= 0 && py >= 0 && px < w && py < h {
                            img.put_pixel(px as u32, py as u32, Rgb(color));
                        }
                    }
                }
            }
        }
    }
}

/// Draws `text` horizontally centred on `cx`.
pub fn draw_text_centered(
    img: &mut RgbImage,
    cx: i64,
    y: i64,
    text: &str,
    scale: u32,
    color: [u8; 3],
) {
    draw_text(
        img,
        cx - text_width(text, scale) as i64 / 2,
        y,
        text,
        scale,
        color,
    );
}

/// Formats a number compactly for labels: 3–4 significant digits, exponent form for
/// very large or small magnitudes, `INF`/`NAN` spelled out.
pub fn format_number(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    format_by_magnitude(x, 1e-3..1e5, 2, &[(100.0, 1), (1.0, 3)], 4)
}

/// At most 4 characters for a non-negative number (tables): `1.00`, `12.3`, `1234`,
/// `1E-3`; non-finite as [`format_number`].
pub fn format_short(x: f64) -> String {
    format_by_magnitude(x, 1e-2..1e4, 0, &[(100.0, 0), (10.0, 1)], 2)
}

/// `x` in upper-case exponent form with `exp_decimals` decimals when `|x|` is non-zero
/// and outside `plain`; otherwise with the decimals of the first `(bound, decimals)` step
/// whose bound `|x|` reaches (steps in decreasing order), `last` decimals below them all.
fn format_by_magnitude(
    x: f64,
    plain: std::ops::Range<f64>,
    exp_decimals: usize,
    steps: &[(f64, usize)],
    last: usize,
) -> String {
    if x.is_nan() {
        return "NAN".into();
    }
    if x.is_infinite() {
        return if x > 0.0 { "INF".into() } else { "-INF".into() };
    }
    let a = x.abs();
    if a != 0.0 && !plain.contains(&a) {
        return format!("{x:.exp_decimals$e}").to_uppercase();
    }
    let decimals = steps
        .iter()
        .find(|(bound, _)| a >= *bound)
        .map_or(last, |s| s.1);
    format!("{x:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_printable_ascii_has_a_distinct_glyph() {
        let missing = glyph('\u{1}');
        for c in (b'!'..=b'~').map(char::from) {
            if c.is_ascii_lowercase() || "@$&`{}~".contains(c) {
                continue;
            }
            assert_ne!(glyph(c), missing, "no glyph for {c:?}");
            assert!(
                glyph(c).iter().all(|r| r & !0x1F == 0),
                "glyph {c:?} wider than 5"
            );
        }
        // Digits are pairwise different.
        for a in '0'..='9' {
            for b in '0'..='9' {
                if a != b {
                    assert_ne!(glyph(a), glyph(b));
                }
            }
        }
    }

    /// Bounding box `[x0, x1) × [y0, y1)` of the pixels of colour `c`.
    fn ink_box(img: &RgbImage, c: [u8; 3]) -> Option<[u32; 4]> {
        img.enumerate_pixels()
            .filter(|(_, _, p)| p.0 == c)
            .fold(None, |b, (x, y, _)| {
                let [x0, y0, x1, y1] = b.unwrap_or([x, y, x + 1, y + 1]);
                Some([x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1)])
            })
    }

    #[test]
    fn text_is_drawn_inside_its_box_and_clipped() {
        let mut img = RgbImage::new(60, 20);
        draw_text(&mut img, 2, 3, "A1", 2, [255, 0, 0]);
        let w = text_width("A1", 2);
        let lit = img.pixels().filter(|p| p.0 == [255, 0, 0]).count();
        let [x0, y0, x1, y1] = ink_box(&img, [255, 0, 0]).unwrap();
        assert!(x0 >= 2 && x1 <= 2 + w && y0 >= 3 && y1 <= 3 + text_height(2));
        assert!(lit > 20);
        // "H" fills its cell's outer columns and all rows, so "HH" inks exactly the box
        // text_width × text_height at the given corner.
        let mut img = RgbImage::new(80, 40);
        draw_text(&mut img, 7, 11, "HH", 3, [0, 255, 0]);
        assert_eq!(
            ink_box(&img, [0, 255, 0]),
            Some([7, 11, 7 + text_width("HH", 3), 11 + text_height(3)])
        );
        // The gap column between the two glyphs stays empty.
        let gap = 7 + 3 * GLYPH_W;
        assert!((11..11 + 21).all(|y| img.get_pixel(gap, y).0 != [0, 255, 0]));
        // Centred text: its box is centred on cx (to a pixel).
        let mut img = RgbImage::new(80, 20);
        draw_text_centered(&mut img, 40, 2, "HIH", 1, [0, 0, 255]);
        let [x0, _, x1, _] = ink_box(&img, [0, 0, 255]).unwrap();
        assert!((x0 + x1) as i64 / 2 - 40 <= 1 && 40 - (x0 + x1) as i64 / 2 <= 1);
        // Far outside: nothing drawn, no panic.
        draw_text(&mut img, -500, 900, "XYZ", 3, [0, 255, 0]);
        assert_eq!(ink_box(&img, [0, 255, 0]), None);
    }

    #[test]
    fn numbers_format_compactly() {
        assert_eq!(format_number(1.0), "1.000");
        assert_eq!(format_number(0.5), "0.5000");
        assert_eq!(format_number(123.456), "123.5");
        assert_eq!(format_number(1.5e-7), "1.50E-7");
        assert_eq!(format_number(f64::INFINITY), "INF");
        assert_eq!(format_number(-2.5e6), "-2.50E6");
        assert_eq!(format_number(0.0), "0");
        assert_eq!(format_short(1.0), "1.00");
        assert_eq!(format_short(12.34), "12.3");
        assert_eq!(format_short(1234.0), "1234");
        assert_eq!(format_short(0.001), "1E-3");
        assert_eq!(format_short(0.0), "0.00");
        assert_eq!(format_short(f64::NAN), "NAN");
    }
}
