//! Small dense problems: symmetric eigenproblems (faer's self-adjoint eigensolver), for
//! closed-form fits such as the optimal rotation of a point set (Horn's quaternion
//! method in [`crate::matching::similarity`]), and square systems (faer's LU with
//! partial pivoting), for radial-basis interpolation (`crate::matching::post::pin`).

use faer::linalg::solvers::Solve;
use faer::{Mat, Side};

/// Solves `M X = R` for the `n × n` matrix with entries `m(i, j)` and the `n × 3`
/// right-hand side `rhs`. `None` when an entry is not finite or the matrix is singular
/// (the solution not finite, or its residual larger than `1e-8 · (|M| |X| + |R|)`).
pub fn solve_square(
    n: usize,
    m: impl Fn(usize, usize) -> f64,
    rhs: &[[f64; 3]],
) -> Option<Vec<[f64; 3]>> {
    let a = Mat::<f64>::from_fn(n, n, &m);
    let r = Mat::<f64>::from_fn(n, 3, |i, c| rhs[i][c]);
    if a.norm_max().is_nan() || r.norm_max().is_nan() || !a.norm_max().is_finite() {
        return None;
    }
    let x = a.partial_piv_lu().solve(&r);
    let residual = &a * &x - &r;
    let scale = a.norm_max() * x.norm_max() * n as f64 + r.norm_max();
    if !x.norm_max().is_finite() || residual.norm_max() > 1e-8 * scale.max(f64::MIN_POSITIVE) {
        return None;
    }
    Some((0..n).map(|i| [x[(i, 0)], x[(i, 1)], x[(i, 2)]]).collect())
}

/// Eigenvalues (non-decreasing) and unit eigenvectors (`vectors[k]` belongs to
/// `values[k]`) of the symmetric `N × N` matrix `m` (only its lower triangle is read).
/// `None` if the matrix has a non-finite entry or the solver fails.
pub fn symmetric_eigen<const N: usize>(m: &[[f64; N]; N]) -> Option<([f64; N], [[f64; N]; N])> {
    if m.iter().flatten().any(|v| !v.is_finite()) {
        return None;
    }
    let a = Mat::<f64>::from_fn(N, N, |i, j| m[i.max(j)][i.min(j)]);
    let evd = a.self_adjoint_eigen(Side::Lower).ok()?;
    let (u, s) = (evd.U(), evd.S());
    let values = std::array::from_fn(|k| s.column_vector()[k]);
    let vectors = std::array::from_fn(|k| std::array::from_fn(|i| u[(i, k)]));
    Some((values, vectors))
}

/// Eigenvalues (non-decreasing) and unit eigenvectors (`vectors[k]` belongs to
/// `values[k]`) of the symmetric `n × n` matrix with entries `m(i, j)` (only `i ≥ j` is
/// read): [`symmetric_eigen`] for a size known at run time (the Gram matrix of a shape
/// model's PCA). `None` if an entry is not finite or the solver fails.
pub fn symmetric_eigen_n(
    n: usize,
    m: impl Fn(usize, usize) -> f64,
) -> Option<(Vec<f64>, Vec<Vec<f64>>)> {
    let a = Mat::<f64>::from_fn(n, n, |i, j| m(i.max(j), i.min(j)));
    if !a.norm_max().is_finite() {
        return None;
    }
    let evd = a.self_adjoint_eigen(Side::Lower).ok()?;
    let (u, s) = (evd.U(), evd.S());
    let values = (0..n).map(|k| s.column_vector()[k]).collect();
    let vectors = (0..n)
        .map(|k| (0..n).map(|i| u[(i, k)]).collect())
        .collect();
    Some((values, vectors))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_solve_recovers_a_known_solution_and_refuses_a_singular_matrix() {
        let m = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let x = [[1.0, -2.0, 0.5], [0.0, 3.0, 1.0], [-1.0, 1.0, 2.0]];
        let rhs: Vec<[f64; 3]> = (0..3)
            .map(|i| std::array::from_fn(|c| (0..3).map(|j| m[i][j] * x[j][c]).sum()))
            .collect();
        let got = solve_square(3, |i, j| m[i][j], &rhs).expect("regular");
        for k in 0..3 {
            for c in 0..3 {
                assert!((got[k][c] - x[k][c]).abs() < 1e-12, "{got:?}");
            }
        }
        assert!(solve_square(2, |_, _| 1.0, &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).is_none());
    }

    #[test]
    fn eigenpairs_satisfy_the_definition() {
        let m = [
            [4.0, 1.0, -2.0, 0.5],
            [1.0, 3.0, 0.0, 1.0],
            [-2.0, 0.0, 5.0, -1.0],
            [0.5, 1.0, -1.0, 2.0],
        ];
        let (values, vectors) = symmetric_eigen(&m).unwrap();
        for k in 0..4 {
            let v = vectors[k];
            let norm: f64 = v.iter().map(|x| x * x).sum();
            assert!((norm - 1.0).abs() < 1e-12);
            for i in 0..4 {
                let mv: f64 = (0..4).map(|j| m[i][j] * v[j]).sum();
                assert!((mv - values[k] * v[i]).abs() < 1e-10);
            }
        }
        assert!(values.windows(2).all(|w| w[0] <= w[1]));
        assert!(symmetric_eigen(&[[f64::NAN]]).is_none());
    }
}
