//! Small dense symmetric eigenproblems (faer's self-adjoint eigensolver), for
//! closed-form fits such as the optimal rotation of a point set (Horn's quaternion
//! method in [`crate::matching::similarity`]).

use faer::{Mat, Side};

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

/// Solves the dense `n × n` system `A X = B` for `m` right-hand sides by LU with partial
/// pivoting (faer): `a` row-major `n × n`, `b` row-major `n × m`, overwritten by `X`.
/// `None` when `A` is singular to working precision (a non-finite solution).
pub fn solve_dense(n: usize, a: &[f64], m: usize, b: &mut [f64]) -> Option<()> {
    use faer::linalg::solvers::Solve;
    assert!(a.len() == n * n && b.len() == n * m, "dense system shapes");
    let matrix = Mat::from_fn(n, n, |i, j| a[i * n + j]);
    let rhs = Mat::from_fn(n, m, |i, j| b[i * m + j]);
    let x = matrix.partial_piv_lu().solve(&rhs);
    for i in 0..n {
        for j in 0..m {
            let v = x[(i, j)];
            if !v.is_finite() {
                return None;
            }
            b[i * m + j] = v;
        }
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn dense_solve_recovers_a_known_solution() {
        // A non-symmetric, well-conditioned 4 × 4 system with two right-hand sides.
        let n = 4;
        let a: Vec<f64> = (0..n * n)
            .map(|k| if k / n == k % n { 5.0 } else { ((k * 7 % 5) as f64 - 2.0) * 0.5 })
            .collect();
        let x = [1.0, -2.0, 0.5, 3.0, 0.0, 1.0, -1.0, 2.0];
        let mut b = vec![0.0; n * 2];
        for i in 0..n {
            for j in 0..2 {
                b[i * 2 + j] = (0..n).map(|k| a[i * n + k] * x[k * 2 + j]).sum();
            }
        }
        solve_dense(n, &a, 2, &mut b).unwrap();
        for (got, want) in b.iter().zip(x) {
            assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        }
        assert!(solve_dense(2, &[1.0, 2.0, 2.0, 4.0], 1, &mut [1.0, 1.0]).is_none());
    }
}
