//! Multi-channel images on the `n × n` grid of one level, sampled bilinearly with
//! the exact gradient of the interpolant at any point of ℝ² (clamped onto ω).
//!
//! Node `(i, j)` (row `i`, column `j`) is stored at `i·n + j` and sits at
//! `ξ = (j, i)/(n − 1)`, as everywhere in the crate.

/// `C` channels per node on an `n × n` grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Field<const C: usize> {
    pub size: usize,
    pub data: Vec<[f64; C]>,
}

/// A sample: values and their derivatives along ξ₀ (x) and ξ₁ (y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample<const C: usize> {
    pub value: [f64; C],
    pub dx: [f64; C],
    pub dy: [f64; C],
}

impl<const C: usize> Field<C> {
    pub fn new(size: usize, data: Vec<[f64; C]>) -> Self {
        assert_eq!(data.len(), size * size, "field data has the wrong length");
        Self { size, data }
    }

    /// Bilinear interpolation at `p` and its gradient. Outside ω the point is clamped
    /// onto ω; the gradient is the clamped function's (zero across a clamped side).
    #[inline]
    pub fn sample(&self, p: [f64; 2]) -> Sample<C> {
        let n = self.size;
        let last = (n - 1) as f64;
        let (gx, cx) = clamp_coordinate(p[0] * last, last);
        let (gy, cy) = clamp_coordinate(p[1] * last, last);
        let j = (gx as usize).min(n - 2);
        let i = (gy as usize).min(n - 2);
        let fx = gx - j as f64;
        let fy = gy - i as f64;
        let k = i * n + j;
        let (v00, v01, v10, v11) = (
            &self.data[k],
            &self.data[k + 1],
            &self.data[k + n],
            &self.data[k + n + 1],
        );
        let mut out = Sample {
            value: [0.0; C],
            dx: [0.0; C],
            dy: [0.0; C],
        };
        let sx = if cx { 0.0 } else { last };
        let sy = if cy { 0.0 } else { last };
        for c in 0..C {
            let bottom = v00[c] + fx * (v01[c] - v00[c]);
            let top = v10[c] + fx * (v11[c] - v10[c]);
            out.value[c] = bottom + fy * (top - bottom);
            out.dx[c] = sx * ((1.0 - fy) * (v01[c] - v00[c]) + fy * (v11[c] - v10[c]));
            out.dy[c] = sy * (top - bottom);
        }
        out
    }

    /// Bilinear interpolation at `p` (clamped onto ω), without the gradient.
    #[inline]
    pub fn value(&self, p: [f64; 2]) -> [f64; C] {
        self.sample(p).value
    }
}

/// Clamps a grid coordinate to `[0, last]`; the flag says whether it was clamped.
#[inline]
fn clamp_coordinate(g: f64, last: f64) -> (f64, bool) {
    if g < 0.0 {
        (0.0, true)
    } else if g > last {
        (last, true)
    } else if g.is_nan() {
        (0.0, true)
    } else {
        (g, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_functions_are_reproduced_with_their_gradient() {
        let n = 9;
        let f = |x: f64, y: f64| [1.0 + 2.0 * x - 3.0 * y + 0.5 * x * y, x];
        let data = (0..n * n)
            .map(|k| f((k % n) as f64 / 8.0, (k / n) as f64 / 8.0))
            .collect();
        let field = Field::<2>::new(n, data);
        for p in [[0.13, 0.77], [0.5, 0.5], [0.999, 0.01], [0.0, 1.0]] {
            let s = field.sample(p);
            let exact = f(p[0], p[1]);
            assert!((s.value[0] - exact[0]).abs() < 1e-12);
            assert!((s.dx[0] - (2.0 + 0.5 * p[1])).abs() < 1e-12, "{p:?}");
            assert!((s.dy[0] - (-3.0 + 0.5 * p[0])).abs() < 1e-12, "{p:?}");
            assert!((s.dx[1] - 1.0).abs() < 1e-12 && s.dy[1].abs() < 1e-12);
        }
        // Outside: clamped value, no gradient across the clamped side.
        let s = field.sample([1.5, 0.25]);
        assert!((s.value[0] - f(1.0, 0.25)[0]).abs() < 1e-12);
        assert_eq!(s.dx[0], 0.0);
        assert!((s.dy[0] - (-3.0 + 0.5)).abs() < 1e-12);
    }
}
