//! A contact sheet: labelled pictures tiled in a grid, each scaled to a square tile.

use image::{Rgb, RgbImage};

use super::font::draw_text;

/// Nearest-neighbour resize: output pixel `(c, r)` takes input pixel
/// `(c · w_in / w, r · h_in / h)`.
pub fn resize_nearest(img: &RgbImage, width: u32, height: u32) -> RgbImage {
    let (iw, ih) = (img.width() as u64, img.height() as u64);
    if iw == 0 || ih == 0 {
        return RgbImage::new(width, height);
    }
    RgbImage::from_fn(width, height, |c, r| {
        let x = c as u64 * iw / width as u64;
        let y = r as u64 * ih / height as u64;
        *img.get_pixel(x as u32, y as u32)
    })
}

/// Tiles `(label, picture)` pairs into a sheet of `columns` columns on white: each
/// picture resized to `tile × tile`, its label (font scale 3) above it.
pub fn contact_sheet(tiles: &[(String, RgbImage)], columns: usize, tile: u32) -> RgbImage {
    let columns = columns.max(1) as u32;
    let rows = (tiles.len() as u32).div_ceil(columns);
    let (pad, label) = (8, 30);
    let mut sheet = RgbImage::from_pixel(
        columns * (tile + pad) + pad,
        rows * (tile + pad + label) + pad,
        Rgb([255, 255, 255]),
    );
    for (i, (name, pic)) in tiles.iter().enumerate() {
        let i = i as u32;
        let (x, y) = (
            pad + (i % columns) * (tile + pad),
            pad + (i / columns) * (tile + pad + label),
        );
        draw_text(&mut sheet, x as i64, y as i64 + 4, name, 3, [20, 20, 20]);
        image::imageops::replace(
            &mut sheet,
            &resize_nearest(pic, tile, tile),
            x as i64,
            (y + label) as i64,
        );
    }
    sheet
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_land_in_their_cells_with_labels_above() {
        let red = RgbImage::from_pixel(3, 3, Rgb([200, 0, 0]));
        let mut quad = RgbImage::from_pixel(2, 2, Rgb([0, 0, 200]));
        quad.put_pixel(1, 0, Rgb([0, 200, 0])); // top-right green
        let s = contact_sheet(&[("H".into(), red), ("G".into(), quad)], 2, 20);
        assert_eq!(s.dimensions(), (2 * 28 + 8, 20 + 8 + 30 + 8));
        // Tile 0 at (8, 38), tile 1 at (36, 38), both 20 × 20.
        assert_eq!(s.get_pixel(8, 38).0, [200, 0, 0]);
        assert_eq!(s.get_pixel(27, 57).0, [200, 0, 0]);
        assert_eq!(s.get_pixel(28, 45).0, [255; 3], "padding between tiles");
        assert_eq!(s.get_pixel(36, 57).0, [0, 0, 200]); // bottom-left of tile 1
        assert_eq!(s.get_pixel(55, 38).0, [0, 200, 0]); // top-right of tile 1
        assert_eq!(s.get_pixel(45, 38).0, [0, 0, 200]);
        assert_eq!(s.get_pixel(46, 38).0, [0, 200, 0]);
        // Labels: ink only in the strip above each tile, starting at its left edge.
        let ink: Vec<(u32, u32)> = s
            .enumerate_pixels()
            .filter(|(_, _, p)| p.0 == [20, 20, 20])
            .map(|(x, y, _)| (x, y))
            .collect();
        assert!(!ink.is_empty());
        assert!(ink.iter().all(|&(_, y)| (12..12 + 21).contains(&y)));
        assert!(ink.iter().any(|&(x, _)| x == 8) && ink.iter().any(|&(x, _)| x == 36));
    }

    #[test]
    fn nearest_resize_picks_the_covering_pixel() {
        let img = RgbImage::from_fn(4, 2, |x, y| Rgb([x as u8, y as u8, 0]));
        let up = resize_nearest(&img, 8, 4);
        assert_eq!(up.get_pixel(7, 3).0, [3, 1, 0]);
        assert_eq!(up.get_pixel(2, 1).0, [1, 0, 0]);
        let down = resize_nearest(&img, 2, 1);
        assert_eq!(down.get_pixel(1, 0).0, [2, 0, 0]);
        assert_eq!(
            resize_nearest(&RgbImage::new(0, 0), 3, 3).dimensions(),
            (3, 3)
        );
    }
}
