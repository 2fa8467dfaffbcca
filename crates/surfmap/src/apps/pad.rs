//! Colour padding beyond a chart's boundary, so that texture filtering never mixes in
//! the background: bilinear lookups near the boundary read texels just outside the
//! chart, and each mipmap level `k` averages `2^k × 2^k` texels, so a coarse level of an
//! unpadded texture shows a dark seam along every chart boundary.
//!
//! **Dilation.** Ring `r = 1, 2, …, rings`: every texel not yet filled that touches
//! (8-neighbourhood) a texel filled before ring `r` gets the mean colour of those
//! neighbours. After `rings` rings every texel within Chebyshev distance `rings` of the
//! chart is filled, and a texel's colour is a mean of colours of the chart near it.
//! Cost: O(texels within the padded band) per ring.
//!
//! **The rest** of the image (farther than `rings` from any chart) gets the mean colour
//! of the chart, so even the coarsest mipmap levels average colours of the surface.

/// What [`pad_colours`] filled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct PadReport {
    /// Texels filled by the dilation rings.
    pub dilated: usize,
    /// Texels beyond the rings, set to the chart's mean colour.
    pub background: usize,
}

/// Pads the colours of a `width × height` image (row-major) outward from the texels
/// marked `filled`: `rings` rings of dilation, then the mean colour everywhere else.
/// `filled` is updated to the texels that hold a chart colour or a dilated one.
/// Nothing happens when no texel is filled.
pub fn pad_colours(
    rgb: &mut [[f64; 3]],
    filled: &mut [bool],
    width: usize,
    height: usize,
    rings: usize,
) -> PadReport {
    assert_eq!(rgb.len(), width * height, "colours do not fit the image");
    assert_eq!(filled.len(), width * height, "mask does not fit the image");
    let count = filled.iter().filter(|&&f| f).count();
    if count == 0 {
        return PadReport {
            dilated: 0,
            background: 0,
        };
    }
    let mut mean = [0.0; 3];
    for (c, _) in rgb.iter().zip(filled.iter()).filter(|(_, f)| **f) {
        for k in 0..3 {
            mean[k] += c[k] / count as f64;
        }
    }
    let neighbours = |i: usize| {
        let (x, y) = ((i % width) as i64, (i / width) as i64);
        (-1i64..=1)
            .flat_map(move |dy| (-1i64..=1).map(move |dx| (x + dx, y + dy)))
            .filter(move |&(nx, ny)| {
                (nx, ny) != (x, y)
                    && (0..width as i64).contains(&nx)
                    && (0..height as i64).contains(&ny)
            })
            .map(move |(nx, ny)| ny as usize * width + nx as usize)
    };
    // The first frontier: unfilled texels touching the chart.
    let mut queued = vec![false; width * height];
    let mut frontier: Vec<usize> = Vec::new();
    for i in 0..width * height {
        if !filled[i] && neighbours(i).any(|j| filled[j]) {
            queued[i] = true;
            frontier.push(i);
        }
    }
    let mut dilated = 0;
    let mut colours: Vec<[f64; 3]> = Vec::new();
    for _ in 0..rings {
        if frontier.is_empty() {
            break;
        }
        // Colours from texels filled before this ring only.
        colours.clear();
        for &i in &frontier {
            let (mut sum, mut n) = ([0.0; 3], 0.0);
            for j in neighbours(i).filter(|&j| filled[j]) {
                for k in 0..3 {
                    sum[k] += rgb[j][k];
                }
                n += 1.0;
            }
            colours.push(sum.map(|s| s / n));
        }
        for (&i, &c) in frontier.iter().zip(&colours) {
            rgb[i] = c;
            filled[i] = true;
        }
        dilated += frontier.len();
        let mut next = Vec::with_capacity(frontier.len() + 8);
        for &i in &frontier {
            for j in neighbours(i) {
                if !filled[j] && !queued[j] {
                    queued[j] = true;
                    next.push(j);
                }
            }
        }
        frontier = next;
    }
    let mut background = 0;
    for (c, f) in rgb.iter_mut().zip(filled.iter()) {
        if !f {
            *c = mean;
            background += 1;
        }
    }
    PadReport {
        dilated,
        background,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rings_fill_the_chebyshev_band_with_nearby_colours() {
        // A 3×3 chart in a 15×11 image, left column red, the rest blue.
        let (w, h) = (15, 11);
        let mut rgb = vec![[0.0; 3]; w * h];
        let mut filled = vec![false; w * h];
        for y in 4..7 {
            for x in 6..9 {
                filled[y * w + x] = true;
                rgb[y * w + x] = if x == 6 {
                    [1.0, 0.0, 0.0]
                } else {
                    [0.0, 0.0, 1.0]
                };
            }
        }
        let chart = filled.clone();
        let report = pad_colours(&mut rgb, &mut filled, w, h, 2);
        // Chebyshev distance ≤ 2 from the chart: a 7×7 square minus the 3×3 chart.
        assert_eq!(report.dilated, 49 - 9);
        assert_eq!(report.background, w * h - 49);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let near = (4..=10).contains(&x) && (2..=8).contains(&y);
                assert_eq!(filled[i], near, "({x}, {y})");
                if chart[i] {
                    continue;
                }
                let c = rgb[i];
                if x <= 4 && near {
                    // Two columns left of the chart: ring 2 averages ring-1 texels of
                    // column 5, which saw only the red column: pure red.
                    assert_eq!(c, [1.0, 0.0, 0.0], "({x}, {y})");
                } else if x >= 9 && near {
                    assert_eq!(c, [0.0, 0.0, 1.0], "({x}, {y})");
                }
                if !near {
                    // The chart's mean: 3 red, 6 blue.
                    assert!((c[0] - 1.0 / 3.0).abs() < 1e-12 && (c[2] - 2.0 / 3.0).abs() < 1e-12);
                }
            }
        }
        // Nothing filled: nothing changes.
        let mut empty = vec![false; 4];
        let mut c = vec![[0.5; 3]; 4];
        assert_eq!(pad_colours(&mut c, &mut empty, 2, 2, 3).dilated, 0);
        assert_eq!(c, vec![[0.5; 3]; 4]);
    }
}
