//! Pinning landmarks after the solve: the user says that landmark `k` of A *is*
//! landmark `k` of B, and the feature term (2.11) only pulls toward that (a landmark's
//! distance map is a cone, and the optimum balances it against bending and
//! regularization). When pinning is on ([`super::MatchOptions::pin_landmarks`]), the
//! solved φ is corrected by a smooth bump per landmark so that it carries each landmark
//! of A exactly onto B's:
//!
//! `φ'(ξ) = φ(ξ) + Σ_j c_j G_r(|ξ − a_j|)`,  `G_r(d) = exp(−d² / 2r²)`,
//!
//! with `a_j` A's landmark in the domain and the coefficients `c_j ∈ ℝ²` solving the
//! `n × n` system `Σ_j Ĝ_j(a_k) c_j = b_k − φ(a_k)` (`Ĝ_j`: the grid's P1 interpolant of
//! `G_r(|· − a_j|)`, so that the constraint holds for φ' as the grid represents it;
//! `b_k`: B's landmark). The bump changes `Dφ` by at most `|c| e^{−1/2}/r`, so a width
//! `r` of a few times the largest correction keeps φ' fold-free; `r` starts at
//! `max(6 h, 4 max_k |b_k − φ(a_k)|)` (`h` the grid spacing) and doubles, at most three
//! times, until min det Dφ' > ½ min det Dφ. If no width keeps φ fold-free, φ is left as
//! it was and the report says so.

use super::deformation::{Deformation, node};
use crate::linsolve::dense::solve_dense;

/// What pinning did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Pinning {
    /// Landmarks carried exactly onto B's.
    pub pinned: usize,
    /// Largest correction `|b_k − φ(a_k)|` before pinning (domain units).
    pub largest_correction: f64,
    /// Width `r` of the bumps (domain units); 0 when nothing was pinned.
    pub radius: f64,
}

/// Corrects `phi` so that `phi(sources[k]) = targets[k]` for every landmark (module
/// documentation); returns what it did (nothing pinned if no width keeps φ fold-free or
/// the system is singular, e.g. two landmarks of A at one point).
pub fn pin_landmarks(phi: &mut Deformation, sources: &[[f64; 2]], targets: &[[f64; 2]]) -> Pinning {
    let n = sources.len().min(targets.len());
    let mut report = Pinning::default();
    if n == 0 {
        return report;
    }
    let residual: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let y = phi.apply(sources[k]);
            [targets[k][0] - y[0], targets[k][1] - y[1]]
        })
        .collect();
    report.largest_correction = residual.iter().map(|r| r[0].hypot(r[1])).fold(0.0, f64::max);
    if report.largest_correction == 0.0 {
        report.pinned = n;
        return report;
    }
    let size = phi.size;
    let h = 1.0 / (size - 1) as f64;
    let before = phi.min_jacobian_determinant();
    let mut radius = (6.0 * h).max(4.0 * report.largest_correction);
    for _ in 0..4 {
        if let Some(pinned) = bumped(phi, sources, &residual, radius)
            && pinned.min_jacobian_determinant() > 0.5 * before
        {
            *phi = pinned;
            report.pinned = n;
            report.radius = radius;
            return report;
        }
        radius *= 2.0;
    }
    report
}

/// `phi` plus the bumps of width `radius` that move `phi(sources[k])` by `residual[k]`;
/// `None` when their system is singular.
fn bumped(
    phi: &Deformation,
    sources: &[[f64; 2]],
    residual: &[[f64; 2]],
    radius: f64,
) -> Option<Deformation> {
    let n = sources.len();
    let size = phi.size;
    let bump = |j: usize, x: [f64; 2]| {
        let d2 = (x[0] - sources[j][0]).powi(2) + (x[1] - sources[j][1]).powi(2);
        (-d2 / (2.0 * radius * radius)).exp()
    };
    // Ĝ_j(a_k): the P1 interpolant of bump j at landmark k, read through a deformation
    // whose x displacement holds the bump's node values.
    let mut matrix = vec![0.0; n * n];
    for j in 0..n {
        let field = Deformation {
            size,
            displacement: (0..size * size)
                .map(|k| [bump(j, node(size, k)), 0.0])
                .collect(),
        };
        for k in 0..n {
            matrix[k * n + j] = field.apply(sources[k])[0] - sources[k][0];
        }
    }
    let mut coefficients: Vec<f64> = residual.iter().flat_map(|r| *r).collect();
    solve_dense(n, &matrix, 2, &mut coefficients)?;
    let mut out = phi.clone();
    for (k, u) in out.displacement.iter_mut().enumerate() {
        let x = node(size, k);
        for j in 0..n {
            let g = bump(j, x);
            u[0] += coefficients[2 * j] * g;
            u[1] += coefficients[2 * j + 1] * g;
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn landmarks_land_exactly_and_phi_stays_fold_free() {
        // A smooth φ (a small rotation and shear) and three landmarks whose targets are
        // off by a few grid cells.
        let size = 65;
        let mut phi = Deformation::from_map(size, |p| {
            [0.98 * p[0] + 0.05 * p[1] + 0.01, -0.04 * p[0] + 1.01 * p[1]]
        });
        let sources = [[0.3, 0.4], [0.7, 0.35], [0.5, 0.75]];
        let offsets = [[0.03, -0.02], [-0.025, 0.02], [0.0, 0.035]];
        let targets: Vec<[f64; 2]> = sources
            .iter()
            .zip(offsets)
            .map(|(s, o)| {
                let y = phi.apply(*s);
                [y[0] + o[0], y[1] + o[1]]
            })
            .collect();
        let far = [0.05, 0.95];
        let far_before = phi.apply(far);
        let report = pin_landmarks(&mut phi, &sources, &targets);
        assert_eq!(report.pinned, 3, "{report:?}");
        for (s, t) in sources.iter().zip(&targets) {
            let y = phi.apply(*s);
            assert!((y[0] - t[0]).hypot(y[1] - t[1]) < 1e-12, "{y:?} vs {t:?}");
        }
        assert!(phi.min_jacobian_determinant() > 0.0);
        // The correction is local: far from every landmark φ barely moves.
        let far_after = phi.apply(far);
        let moved = (far_after[0] - far_before[0]).hypot(far_after[1] - far_before[1]);
        assert!(moved < 0.1 * 0.035, "moved {moved}");
    }

    #[test]
    fn a_correction_that_would_fold_is_not_applied() {
        // Two landmarks a cell apart asked to swap places: no smooth bump does that
        // without a fold, so φ is left as it was.
        let size = 33;
        let mut phi = Deformation::identity(size);
        let h = 1.0 / 32.0;
        let sources = [[0.5, 0.5], [0.5 + h, 0.5]];
        let targets = [[0.5 + h, 0.5], [0.5, 0.5]];
        let report = pin_landmarks(&mut phi, &sources, &targets);
        assert_eq!(report.pinned, 0, "{report:?}");
        assert_eq!(phi.displacement, Deformation::identity(size).displacement);
    }
}
