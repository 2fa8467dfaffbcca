//! The columns of the Shay–Solomon–Stein parameterization benchmark ("A dataset and
//! benchmark for mesh parameterization"; code `georgiashay/parameterization_benchmark`,
//! files `benchmark.py` and `utilities/*.py`), recomputed with the benchmark's own
//! conventions, which differ from the rest of the report:
//!
//! * **Scale**: the mesh is scaled to total 3D area 1 and the UVs to total |UV area| 1
//!   (`preprocess.py`). `A_t` and `a_t` below are these normalized 3D and UV triangle
//!   areas (`Σ A_t = Σ a_t = 1`); singular values are those of the normalized map.
//! * **No orientation fix-up**: a triangle is flipped when `det J < 0`; the proportion
//!   reported is `min(p, 1 − p)` (a globally mirrored map scores 0).
//! * **Weights**: sums weighted by the normalized 3D area `A_t`, not means.
//!
//! | column | definition |
//! |---|---|
//! | Faces, Vertices | triangle count, vertex count of the file |
//! | Max Area Distortion | `max_t (a_t/A_t + A_t/a_t) − 2` |
//! | Average Area Discrepancy | `Σ_t |a_t − A_t|` (in `[0, 2]`) |
//! | Min / Max Singular Value | `min_t σ2`, `max_t σ1` |
//! | Proportion Flipped Triangles | `min(p, 1−p)`, `p = #{det J < 0} / #faces` |
//! | Max Angle Distortion | `max_t (σ1/σ2 + σ2/σ1) − 2` |
//! | Average Angle Discrepancy | `Σ_t A_t Σ_corners |θ_3D − θ_UV|` (radians; corner angles from side lengths; a corner of a zero-length side counts 2π) |
//! | Symmetric Dirichlet Energy | `Σ_t A_t (σ1² + σ2² + σ1⁻² + σ2⁻²) / 2` (isometry 2; `utilities/symmetric_dirichlet_energy.py`) |
//!
//! (The benchmark's published code names the two averages "Average Area Error" /
//! "Average Angle Error"; the CSV header uses the paper's names.) Triangles of zero 3D
//! area are left out, as the benchmark drops faces whose Jacobian is NaN.

use serde::Serialize;

use super::jacobian::{signed_singular_values, signed_uv_area, triangle_jacobian};

/// The CSV header, in column order.
pub const BENCHMARK_CSV_HEADER: [&str; 10] = [
    "Faces",
    "Vertices",
    "Max Area Distortion",
    "Average Area Discrepancy",
    "Min Singular Value",
    "Max Singular Value",
    "Proportion Flipped Triangles",
    "Max Angle Distortion",
    "Average Angle Discrepancy",
    "Symmetric Dirichlet Energy",
];

/// One row of the Shay–Solomon–Stein benchmark (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BenchmarkScores {
    pub faces: usize,
    pub vertices: usize,
    pub max_area_distortion: f64,
    pub average_area_discrepancy: f64,
    pub min_singular_value: f64,
    pub max_singular_value: f64,
    pub proportion_flipped_triangles: f64,
    pub max_angle_distortion: f64,
    pub average_angle_discrepancy: f64,
    pub symmetric_dirichlet_energy: f64,
}

impl BenchmarkScores {
    /// The values in [`BENCHMARK_CSV_HEADER`] order, formatted for CSV
    /// (`inf`, `nan` as Python writes them).
    pub fn csv_values(&self) -> [String; 10] {
        let f = |x: f64| {
            if x.is_nan() {
                "nan".to_string()
            } else if x.is_infinite() {
                if x > 0.0 { "inf".into() } else { "-inf".into() }
            } else {
                format!("{x:.17e}")
            }
        };
        [
            self.faces.to_string(),
            self.vertices.to_string(),
            f(self.max_area_distortion),
            f(self.average_area_discrepancy),
            f(self.min_singular_value),
            f(self.max_singular_value),
            f(self.proportion_flipped_triangles),
            f(self.max_angle_distortion),
            f(self.average_angle_discrepancy),
            f(self.symmetric_dirichlet_energy),
        ]
    }
}

/// Corner angles of a triangle from its side lengths (law of cosines, clamped), or
/// `None` if a side has zero length.
fn corner_angles(a: f64, b: f64, c: f64) -> Option<[f64; 3]> {
    if a == 0.0 || b == 0.0 || c == 0.0 {
        return None;
    }
    let ang = |opp: f64, s: f64, t: f64| {
        ((s * s + t * t - opp * opp) / (2.0 * s * t))
            .clamp(-1.0, 1.0)
            .acos()
    };
    Some([ang(a, b, c), ang(b, a, c), ang(c, a, b)])
}

fn dist<const N: usize>(p: [f64; N], q: [f64; N]) -> f64 {
    p.iter()
        .zip(&q)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt()
}

/// Side lengths `(|p1 − p2|, |p2 − p0|, |p0 − p1|)`: side `k` is opposite corner `k`.
fn sides<const N: usize>(p: [[f64; N]; 3]) -> (f64, f64, f64) {
    (dist(p[1], p[2]), dist(p[2], p[0]), dist(p[0], p[1]))
}

/// Computes the benchmark row. Inputs are assumed checked by the caller.
#[allow(clippy::needless_range_loop)]
pub fn benchmark_scores(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    corner_uvs: &[[[f64; 2]; 3]],
) -> BenchmarkScores {
    let n = triangles.len();
    let tri_pos = |t: usize| triangles[t].map(|v| positions[v as usize]);
    let mut total3 = 0.0;
    let mut total_uv = 0.0;
    for t in 0..n {
        let p = tri_pos(t);
        let e1 = crate::vec3::sub3(p[1], p[0]);
        let e2 = crate::vec3::sub3(p[2], p[0]);
        total3 += 0.5 * crate::vec3::norm3(crate::vec3::cross3(e1, e2));
        total_uv += signed_uv_area(corner_uvs[t]).abs();
    }
    // Scale 3D by 1/√total3 and UV by 1/√total_uv: J scales by √(total3/total_uv).
    let (s3, suv) = (1.0 / total3.sqrt(), 1.0 / total_uv.sqrt());
    let jscale = suv / s3;
    let mut out = BenchmarkScores {
        faces: n,
        vertices: positions.len(),
        max_area_distortion: f64::NEG_INFINITY,
        min_singular_value: f64::INFINITY,
        max_singular_value: f64::NEG_INFINITY,
        max_angle_distortion: f64::NEG_INFINITY,
        ..Default::default()
    };
    let mut flipped = 0usize;
    let mut counted = 0usize;
    for t in 0..n {
        let p = tri_pos(t);
        let uv = corner_uvs[t];
        let Some((j, area)) = triangle_jacobian(p, uv) else {
            continue;
        };
        let (s1, s2) = signed_singular_values(j);
        if !(s1.is_finite() && s2.is_finite()) {
            continue;
        }
        counted += 1;
        let (s1, s2n) = (s1 * jscale, s2.abs() * jscale);
        if s2 < 0.0 {
            flipped += 1;
        }
        let a3 = area / total3;
        let auv = signed_uv_area(uv).abs() / total_uv;
        let area_ratio = if auv > 0.0 {
            auv / a3 + a3 / auv
        } else {
            f64::INFINITY
        };
        out.max_area_distortion = out.max_area_distortion.max(area_ratio - 2.0);
        out.average_area_discrepancy += (auv - a3).abs();
        out.min_singular_value = out.min_singular_value.min(s2n);
        out.max_singular_value = out.max_singular_value.max(s1);
        let angle = if s2n > 0.0 && s1 > 0.0 {
            s1 / s2n + s2n / s1
        } else {
            f64::INFINITY
        };
        out.max_angle_distortion = out.max_angle_distortion.max(angle - 2.0);
        let ps = p.map(|q| q.map(|x| x * s3));
        let us = uv.map(|q| q.map(|x| x * suv));
        let (a, b, c) = sides(ps);
        let (d, e, f) = sides(us);
        let err = match (corner_angles(a, b, c), corner_angles(d, e, f)) {
            (Some(x), Some(y)) => (0..3).map(|k| (x[k] - y[k]).abs()).sum::<f64>(),
            _ => 3.0 * std::f64::consts::TAU,
        };
        out.average_angle_discrepancy += a3 * err;
        let inv = |x: f64| {
            if x > 0.0 {
                1.0 / (x * x)
            } else {
                f64::INFINITY
            }
        };
        out.symmetric_dirichlet_energy += 0.5 * a3 * (s1 * s1 + s2n * s2n + inv(s1) + inv(s2n));
    }
    let prop = if counted > 0 {
        flipped as f64 / counted as f64
    } else {
        f64::NAN
    };
    out.proportion_flipped_triangles = prop.min(1.0 - prop);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_triangle_stretched_by_two_along_x() {
        // Normalization scales both to area 1, so the map becomes (√2 x, y/√2) in effect.
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let uv = [[[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]]];
        let s = benchmark_scores(&p, &[[0, 1, 2]], &uv);
        let r2 = 2f64.sqrt();
        assert!((s.max_singular_value - r2).abs() < 1e-12);
        assert!((s.min_singular_value - 1.0 / r2).abs() < 1e-12);
        assert!((s.max_angle_distortion - (2.0 + 0.5 - 2.0)).abs() < 1e-12);
        assert!(s.max_area_distortion.abs() < 1e-12);
        assert!(s.average_area_discrepancy.abs() < 1e-12);
        // Angles: 3D (π/2, π/4, π/4) → UV (π/2, atan(1/2), atan 2).
        let want = (std::f64::consts::FRAC_PI_4 - 0.5f64.atan()).abs()
            + (std::f64::consts::FRAC_PI_4 - 2f64.atan()).abs();
        assert!((s.average_angle_discrepancy - want).abs() < 1e-12);
        assert!((s.symmetric_dirichlet_energy - 0.5 * (2.0 + 0.5 + 0.5 + 2.0)).abs() < 1e-12);
    }

    #[test]
    fn area_discrepancy_of_two_triangles_with_swapped_sizes() {
        // 3D: two triangles of areas 1/2 and 1/2; UV: areas 1/4 and 3/4 (normalized).
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let f = [[0, 1, 2], [0, 2, 3]];
        let uv = [
            [[0.0, 0.0], [1.0, 0.0], [1.0, 0.5]],
            [[0.0, 0.0], [1.0, 0.5], [0.0, 1.5]],
        ];
        let s = benchmark_scores(&p, &f, &uv);
        assert!((s.average_area_discrepancy - 0.5).abs() < 1e-12);
        // max over t of (a/A + A/a) − 2 with a/A ∈ {1/2, 3/2}: 1/2 + 2 − 2 = 0.5.
        assert!((s.max_area_distortion - 0.5).abs() < 1e-12);
        assert_eq!(s.proportion_flipped_triangles, 0.0);
    }
}
