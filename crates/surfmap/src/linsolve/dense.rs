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
}
