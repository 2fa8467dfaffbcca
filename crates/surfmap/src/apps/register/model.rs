//! A statistical shape model of registered scans: generalized Procrustes alignment, the
//! mean shape and its principal modes (PCA), all in the template's vertex order.
//!
//! **Generalized Procrustes alignment** (similarity; Gower 1975, Dryden & Mardia ch. 7).
//! Every shape `X_k` (`n` vertices, `n × 3`) is centred and scaled to unit centroid
//! size `‖X_k − x̄_k‖_F = 1`. Starting from the mean `M = X_1`, each shape is rotated onto
//! `M` by the rotation minimizing `‖R X_k − M‖_F` (Horn's closed form,
//! [`crate::matching::similarity::fit_similarity_3d`] without scale), the mean is
//! recomputed as `M = Σ_k R_k X_k / N` and brought back to unit size, until it moves by
//! less than `1e-12` (partial Procrustes: sizes stay 1, the shapes lie on the
//! pre-shape sphere). The aligned shapes and the mean are then multiplied by the mean
//! centroid size of the input, `s̄ = Σ_k ‖X_k − x̄_k‖_F / N`, so the model is in the
//! scans' units.
//!
//! **PCA.** With `d_k = vec(Y_k − M) ∈ ℝ^{3n}` the aligned deviations, the modes are the
//! eigenvectors of the sample covariance `C = Σ_k d_k d_kᵀ / (N − 1)`. `C` is `3n × 3n`
//! but of rank `< N`, so the `N × N` Gram matrix `G_ij = d_i·d_j` is decomposed instead
//! (faer's self-adjoint eigensolver, [`crate::linsolve::dense::symmetric_eigen_n`]):
//! `G u_j = λ_j u_j` gives the mode `φ_j = Σ_k u_jk d_k / √λ_j` (unit length) and its
//! variance `σ_j² = λ_j / (N − 1)` — the same as the SVD of the `N × 3n` matrix of the
//! `d_k`. Modes with `λ_j ≤ 1e-12 · λ_1` are dropped (at most `N − 1` remain). A shape of
//! the model is `M + Σ_j b_j φ_j`; `b_j = ±2σ_j` spans about 95 % of the population
//! along mode `j`.

use crate::linsolve::dense::symmetric_eigen_n;
use crate::matching::similarity::fit_similarity_3d;

/// Shapes aligned by generalized Procrustes ([module documentation](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct Procrustes {
    /// The aligned shapes (input order), at the mean centroid size.
    pub aligned: Vec<Vec<[f64; 3]>>,
    /// Their mean.
    pub mean: Vec<[f64; 3]>,
    /// The mean centroid size `s̄` of the input shapes.
    pub size: f64,
    /// Alignment rounds until the mean settled.
    pub iterations: usize,
}

/// The mean and principal modes of aligned shapes ([module documentation](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeModel {
    pub mean: Vec<[f64; 3]>,
    /// Unit modes `φ_j`, each one `[x, y, z]` per vertex, by decreasing variance.
    pub components: Vec<Vec<[f64; 3]>>,
    /// `σ_j²`, decreasing.
    pub variances: Vec<f64>,
    /// The total variance `tr C` (all modes).
    pub total_variance: f64,
    pub procrustes: Procrustes,
}

impl ShapeModel {
    /// The fraction of the total variance the first `k` modes explain.
    pub fn explained(&self, k: usize) -> f64 {
        let part: f64 = self.variances.iter().take(k).sum();
        if self.total_variance > 0.0 {
            part / self.total_variance
        } else {
            1.0
        }
    }

    /// The fewest modes that explain at least `fraction` of the variance.
    pub fn modes_for(&self, fraction: f64) -> usize {
        (0..=self.variances.len())
            .find(|&k| self.explained(k) >= fraction - 1e-12)
            .unwrap_or(self.variances.len())
    }

    /// The shape `M + b φ_j`.
    pub fn along(&self, j: usize, b: f64) -> Vec<[f64; 3]> {
        self.mean
            .iter()
            .zip(&self.components[j])
            .map(|(m, p)| [m[0] + b * p[0], m[1] + b * p[1], m[2] + b * p[2]])
            .collect()
    }
}

/// Why a model cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error(
        "a shape model needs at least 2 registered scans, got {0}; register more scans (or include the doubtful ones)"
    )]
    TooFew(usize),
    #[error(
        "shape {index} has {got} vertices, the first has {expected}: every registered scan must be in the template's topology"
    )]
    VertexCount {
        index: usize,
        got: usize,
        expected: usize,
    },
    #[error("shape {0} has a coordinate that is not finite, or all its vertices at one point")]
    Degenerate(usize),
    #[error("the eigendecomposition of the shapes' Gram matrix failed")]
    Eigen,
}

fn centred_unit(shape: &[[f64; 3]]) -> Option<(Vec<[f64; 3]>, f64)> {
    let n = shape.len() as f64;
    let mut c = [0.0; 3];
    for p in shape {
        for k in 0..3 {
            c[k] += p[k] / n;
        }
    }
    let centred: Vec<[f64; 3]> = shape
        .iter()
        .map(|p| [p[0] - c[0], p[1] - c[1], p[2] - c[2]])
        .collect();
    let size = norm(&centred);
    (size.is_finite() && size > 0.0)
        .then(|| (centred.iter().map(|p| p.map(|x| x / size)).collect(), size))
}

fn norm(shape: &[[f64; 3]]) -> f64 {
    shape.iter().flatten().map(|x| x * x).sum::<f64>().sqrt()
}

/// Generalized Procrustes alignment of `shapes` (all with the same vertex count).
pub fn procrustes(shapes: &[Vec<[f64; 3]>]) -> Result<Procrustes, ModelError> {
    if shapes.len() < 2 {
        return Err(ModelError::TooFew(shapes.len()));
    }
    let n = shapes[0].len();
    let mut unit = Vec::with_capacity(shapes.len());
    let mut size = 0.0;
    for (index, s) in shapes.iter().enumerate() {
        if s.len() != n {
            return Err(ModelError::VertexCount {
                index,
                got: s.len(),
                expected: n,
            });
        }
        let (u, sz) = centred_unit(s).ok_or(ModelError::Degenerate(index))?;
        unit.push(u);
        size += sz / shapes.len() as f64;
    }
    let weights = vec![1.0; n];
    let mut mean = unit[0].clone();
    let mut iterations = 0;
    for round in 1..=100 {
        iterations = round;
        for u in &mut unit {
            if let Some(r) = fit_similarity_3d(u, &mean, &weights, false) {
                for p in u.iter_mut() {
                    *p = r.apply(*p);
                }
            }
        }
        let mut next = vec![[0.0; 3]; n];
        for u in &unit {
            for (m, p) in next.iter_mut().zip(u) {
                for k in 0..3 {
                    m[k] += p[k] / unit.len() as f64;
                }
            }
        }
        let (next, _) = centred_unit(&next).ok_or(ModelError::Degenerate(0))?;
        let moved: f64 = next
            .iter()
            .zip(&mean)
            .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>())
            .sum::<f64>()
            .sqrt();
        mean = next;
        if moved < 1e-12 {
            break;
        }
    }
    let scaled = |s: &[[f64; 3]]| s.iter().map(|p| p.map(|x| x * size)).collect::<Vec<_>>();
    // The mean of the aligned shapes (the last mean was brought to unit size).
    let aligned: Vec<Vec<[f64; 3]>> = unit.iter().map(|u| scaled(u)).collect();
    let mut mean = vec![[0.0; 3]; n];
    for a in &aligned {
        for (m, p) in mean.iter_mut().zip(a) {
            for k in 0..3 {
                m[k] += p[k] / aligned.len() as f64;
            }
        }
    }
    Ok(Procrustes {
        aligned,
        mean,
        size,
        iterations,
    })
}

/// The shape model of `shapes`: [`procrustes`], then the PCA of the aligned shapes.
pub fn shape_model(shapes: &[Vec<[f64; 3]>]) -> Result<ShapeModel, ModelError> {
    let procrustes = procrustes(shapes)?;
    let mean = &procrustes.mean;
    let deviations: Vec<Vec<f64>> = procrustes
        .aligned
        .iter()
        .map(|a| {
            a.iter()
                .zip(mean)
                .flat_map(|(p, m)| [p[0] - m[0], p[1] - m[1], p[2] - m[2]])
                .collect()
        })
        .collect();
    let count = deviations.len();
    let dot = |i: usize, j: usize| -> f64 {
        deviations[i]
            .iter()
            .zip(&deviations[j])
            .map(|(a, b)| a * b)
            .sum()
    };
    let gram: Vec<Vec<f64>> = (0..count)
        .map(|i| (0..=i).map(|j| dot(i, j)).collect())
        .collect();
    let (values, vectors) = symmetric_eigen_n(count, |i, j| gram[i][j]).ok_or(ModelError::Eigen)?;
    let trace: f64 = (0..count).map(|i| gram[i][i]).sum();
    let largest = values.iter().copied().fold(0.0, f64::max);
    let mut components = Vec::new();
    let mut variances = Vec::new();
    for k in (0..count).rev() {
        let lambda = values[k];
        if lambda.is_nan() || lambda <= 1e-12 * largest {
            continue;
        }
        let u = &vectors[k];
        let mut phi = vec![0.0; deviations[0].len()];
        for (uk, d) in u.iter().zip(&deviations) {
            for (p, x) in phi.iter_mut().zip(d) {
                *p += uk * x;
            }
        }
        let scale = 1.0 / lambda.sqrt();
        components.push(
            phi.chunks_exact(3)
                .map(|c| [c[0] * scale, c[1] * scale, c[2] * scale])
                .collect(),
        );
        variances.push(lambda / (count - 1) as f64);
    }
    Ok(ShapeModel {
        mean: procrustes.mean.clone(),
        components,
        variances,
        total_variance: trace / (count - 1) as f64,
        procrustes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::bumpy_disc;
    use crate::testing::Rng;

    fn dot(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
            .sum()
    }

    /// Gram–Schmidt of `v` against `basis` (unit, orthogonal), then unit length.
    fn orthonormalize(mut v: Vec<[f64; 3]>, basis: &[Vec<[f64; 3]>]) -> Vec<[f64; 3]> {
        for b in basis {
            let c = dot(&v, b);
            for (p, q) in v.iter_mut().zip(b) {
                for k in 0..3 {
                    p[k] -= c * q[k];
                }
            }
        }
        let n = dot(&v, &v).sqrt();
        v.iter().map(|p| p.map(|x| x / n)).collect()
    }

    /// Shapes built from two known modes (orthogonal to the motions Procrustes removes),
    /// each moved by a random rotation, scale and translation: the model finds the modes
    /// (principal angles below 1°) and their variances — the eigenvalues of the
    /// coefficients' own sample covariance, times the mean scale squared — and two
    /// modes explain (almost) all the variance.
    #[test]
    fn pca_of_shapes_from_known_modes_recovers_them() {
        let base = bumpy_disc(8, 0.3).positions;
        let centroid = base.iter().fold([0.0; 3], |c, p| {
            [0, 1, 2].map(|k| c[k] + p[k] / base.len() as f64)
        });
        let x: Vec<[f64; 3]> = base
            .iter()
            .map(|p| [0, 1, 2].map(|k| p[k] - centroid[k]))
            .collect();
        // The infinitesimal similarities at the base: 3 translations, 3 rotations, scale.
        let mut motions: Vec<Vec<[f64; 3]>> = Vec::new();
        type Field = Box<dyn Fn([f64; 3]) -> [f64; 3]>;
        let fields: Vec<Field> = vec![
            Box::new(|_| [1.0, 0.0, 0.0]),
            Box::new(|_| [0.0, 1.0, 0.0]),
            Box::new(|_| [0.0, 0.0, 1.0]),
            Box::new(|p| [0.0, -p[2], p[1]]),
            Box::new(|p| [p[2], 0.0, -p[0]]),
            Box::new(|p| [-p[1], p[0], 0.0]),
            Box::new(|p| p),
        ];
        for f in &fields {
            let v = orthonormalize(x.iter().map(|&p| f(p)).collect(), &motions);
            motions.push(v);
        }
        let m1 = orthonormalize(
            x.iter()
                .map(|p| [0.0, 0.0, (3.0 * p[0]).sin() * p[1]])
                .collect(),
            &motions,
        );
        let mut with_m1 = motions.clone();
        with_m1.push(m1.clone());
        let m2 = orthonormalize(
            x.iter()
                .map(|p| [0.3 * p[1] * p[1], 0.2 * p[0], (2.0 * p[1]).cos()])
                .collect(),
            &with_m1,
        );
        let mut rng = Rng(12345);
        let mut coefficients = Vec::new();
        let mut shapes = Vec::new();
        let mut scales = Vec::new();
        for _ in 0..30 {
            let gauss = |rng: &mut Rng| {
                // Box–Muller.
                let (u, v) = (rng.uniform().max(1e-300), rng.uniform());
                (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
            };
            let (a, b) = (0.05 * gauss(&mut rng), 0.02 * gauss(&mut rng));
            coefficients.push([a, b]);
            let scale = 0.7 + 0.6 * rng.uniform();
            scales.push(scale);
            let angle = rng.uniform() * 2.0;
            let (s, c) = angle.sin_cos();
            let t = [rng.uniform(), rng.uniform(), rng.uniform()];
            shapes.push(
                x.iter()
                    .zip(m1.iter().zip(&m2))
                    .map(|(p, (u, v))| {
                        let q = [0, 1, 2].map(|k| p[k] + a * u[k] + b * v[k]);
                        // Rotation about (0, 1, 0) by `angle`, then scale and shift.
                        let r = [c * q[0] + s * q[2], q[1], -s * q[0] + c * q[2]];
                        [0, 1, 2].map(|k| scale * r[k] + t[k])
                    })
                    .collect(),
            );
        }
        let mut model = shape_model(&shapes).unwrap();
        assert!(model.variances.len() <= 29);
        // The model lies in the first shape's pose: turn its modes into the base's frame
        // (the rotation of its mean onto the base).
        let turn = fit_similarity_3d(&model.mean, &x, &vec![1.0; x.len()], false).unwrap();
        for c in &mut model.components {
            for p in c.iter_mut() {
                let m = turn.matrix;
                *p = [0, 1, 2].map(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2]);
            }
        }
        // The coefficients' sample covariance and its eigenvalues (closed form, 2 × 2).
        let n = coefficients.len() as f64;
        let mean = [0, 1].map(|k| coefficients.iter().map(|c| c[k]).sum::<f64>() / n);
        let cov = |i: usize, j: usize| {
            coefficients
                .iter()
                .map(|c| (c[i] - mean[i]) * (c[j] - mean[j]))
                .sum::<f64>()
                / (n - 1.0)
        };
        let (p, q, r) = (cov(0, 0), cov(1, 1), cov(0, 1));
        let half = 0.5 * (p + q);
        let root = (0.25 * (p - q).powi(2) + r * r).sqrt();
        // The model is in the mean scale of the shapes (their sizes ∝ their scale).
        let s = scales.iter().sum::<f64>() / n;
        let expected = [(half + root) * s * s, (half - root) * s * s];
        for (k, (got, want)) in model.variances.iter().zip(expected).enumerate() {
            let rel = (got - want).abs() / want;
            assert!(rel < 0.05, "variance {k}: {got} vs {want}");
        }
        assert!(model.explained(2) > 0.99, "{}", model.explained(2));
        assert_eq!(model.modes_for(0.95), 2);
        // Principal angles between span(φ_1, φ_2) and span(m1, m2): the singular values
        // of the 2 × 2 matrix of inner products are their cosines.
        let g = [
            [
                dot(&model.components[0], &m1),
                dot(&model.components[0], &m2),
            ],
            [
                dot(&model.components[1], &m1),
                dot(&model.components[1], &m2),
            ],
        ];
        let gtg = [
            g[0][0] * g[0][0] + g[1][0] * g[1][0],
            g[0][0] * g[0][1] + g[1][0] * g[1][1],
            g[0][1] * g[0][1] + g[1][1] * g[1][1],
        ];
        let half = 0.5 * (gtg[0] + gtg[2]);
        let root = (0.25 * (gtg[0] - gtg[2]).powi(2) + gtg[1] * gtg[1]).sqrt();
        let smallest_cos = (half - root).max(0.0).sqrt();
        let angle = smallest_cos.min(1.0).acos().to_degrees();
        assert!(angle < 1.0, "largest principal angle {angle}°");
        // Each mode is a unit vector.
        for c in &model.components[..2] {
            assert!((dot(c, c) - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn too_few_or_mismatched_shapes_are_refused() {
        let a = bumpy_disc(3, 0.3).positions;
        assert!(matches!(
            shape_model(std::slice::from_ref(&a)),
            Err(ModelError::TooFew(1))
        ));
        let b = bumpy_disc(4, 0.3).positions;
        let err = shape_model(&[a.clone(), b]).unwrap_err();
        assert!(err.to_string().contains("template's topology"), "{err}");
        let mut c = a.clone();
        c[0][0] = f64::NAN;
        assert!(matches!(
            shape_model(&[a, c]),
            Err(ModelError::Degenerate(1))
        ));
    }
}
