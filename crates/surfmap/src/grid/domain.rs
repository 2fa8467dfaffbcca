//! The image domain ω = `[0,1]²` and its regular grid (thesis §3.2.1, "rough alignment").
//!
//! A flattening's UVs are placed in ω by a uniform scale and a translation (no rotation,
//! so the aspect ratio and the orientation of the flattening are kept):
//! `ξ = scale · uv + offset`. Its inverse maps every grid node back to the UV plane, and
//! through the rasterized triangle id and barycentric coordinates, to the surface.
//!
//! The grid has `N × N` nodes, `N = 2^k + 1`; node `(i, j)` (row `i`, column `j`) sits
//! at `ξ = (j, i) / (N − 1)` and is stored at index `i · N + j` (row `i = 0` is `ξ_y = 0`).
//! [`grid_level`] checks a size; [`MAX_SIZE`] bounds it.

use serde::{Deserialize, Serialize};

use super::GridError;

/// The similarity `ξ = scale · uv + offset` that places a flattening in ω = `[0,1]²`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DomainTransform {
    pub scale: f64,
    pub offset: [f64; 2],
}

impl DomainTransform {
    /// Fits the bounding box of `uvs` into `[margin, 1 − margin]²`, centred, keeping the
    /// aspect ratio: `scale = (1 − 2·margin) / max(width, height)`.
    pub fn fit(uvs: &[[f64; 2]], margin: f64) -> Result<Self, GridError> {
        if !(0.0..0.5).contains(&margin) {
            return Err(GridError::BadMargin { margin });
        }
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for (v, uv) in uvs.iter().enumerate() {
            if !(uv[0].is_finite() && uv[1].is_finite()) {
                return Err(GridError::NonFiniteUv { vertex: v });
            }
            for k in 0..2 {
                lo[k] = lo[k].min(uv[k]);
                hi[k] = hi[k].max(uv[k]);
            }
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        if uvs.is_empty() || extent.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(GridError::DegenerateDomain);
        }
        let scale = (1.0 - 2.0 * margin) / extent;
        let offset = [
            0.5 - scale * 0.5 * (lo[0] + hi[0]),
            0.5 - scale * 0.5 * (lo[1] + hi[1]),
        ];
        Ok(Self { scale, offset })
    }

    /// `ξ = scale · uv + offset`.
    #[inline]
    pub fn to_domain(&self, uv: [f64; 2]) -> [f64; 2] {
        [
            self.scale * uv[0] + self.offset[0],
            self.scale * uv[1] + self.offset[1],
        ]
    }

    /// `uv = (ξ − offset) / scale`.
    #[inline]
    pub fn to_uv(&self, xi: [f64; 2]) -> [f64; 2] {
        [
            (xi[0] - self.offset[0]) / self.scale,
            (xi[1] - self.offset[1]) / self.scale,
        ]
    }
}

/// Checks that `size = 2^k + 1` with `3 ≤ size ≤ MAX_SIZE` and returns `k`.
///
/// This is the rule for every grid made from data ([`Grid::new`](super::Grid::new) and
/// its siblings, geometry images). The `2 × 2` grid (`k = 0`) exists only as the coarsest
/// level of a hierarchy, reached by restriction (the pyramid's `σ_0 = 1` level).
pub fn grid_level(size: usize) -> Result<u32, GridError> {
    if (3..=MAX_SIZE).contains(&size) && (size - 1).is_power_of_two() {
        Ok((size - 1).trailing_zeros())
    } else {
        Err(GridError::BadSize { size })
    }
}

/// Largest supported grid (memory grows as `size²`; 4097² images take ~130 MB each at f64 ×3).
pub const MAX_SIZE: usize = 4097;

/// Domain coordinates `ξ = (j, i) / (size − 1)` of grid node `(i, j)`.
#[inline]
pub fn node_position(size: usize, i: usize, j: usize) -> [f64; 2] {
    let d = 1.0 / (size - 1) as f64;
    [j as f64 * d, i as f64 * d]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_keeps_aspect_and_centres() {
        let uvs = [[-2.0, 1.0], [2.0, 1.0], [0.0, 3.0]];
        let t = DomainTransform::fit(&uvs, 0.1).unwrap();
        // width 4 > height 2: x spans [0.1, 0.9], y is centred with the same scale.
        assert!((t.scale - 0.2).abs() < 1e-15);
        let a = t.to_domain(uvs[0]);
        let b = t.to_domain(uvs[1]);
        let c = t.to_domain(uvs[2]);
        assert!((a[0] - 0.1).abs() < 1e-15 && (b[0] - 0.9).abs() < 1e-15);
        assert!(((a[1] + c[1]) * 0.5 - 0.5).abs() < 1e-15);
        assert!(((c[1] - a[1]) - 0.4).abs() < 1e-15);
        let back = t.to_uv(c);
        assert!((back[0] - 0.0).abs() < 1e-14 && (back[1] - 3.0).abs() < 1e-14);
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert!(DomainTransform::fit(&[], 0.0).is_err());
        assert!(DomainTransform::fit(&[[1.0, 1.0], [1.0, 1.0]], 0.0).is_err());
        assert!(DomainTransform::fit(&[[f64::NAN, 1.0], [0.0, 0.0]], 0.0).is_err());
        assert!(matches!(
            DomainTransform::fit(&[[0.0, 1.0], [1.0, 0.0]], 0.5),
            Err(GridError::BadMargin { .. })
        ));
        assert_eq!(grid_level(257).unwrap(), 8);
        assert_eq!(grid_level(3).unwrap(), 1);
        assert!(grid_level(256).is_err());
        assert!(grid_level(2).is_err());
        assert!(grid_level(8193).is_err());
    }
}
