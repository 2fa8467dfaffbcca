//! Least-squares similarity fits: in the plane (the initial alignment of ω_A onto
//! ω_B from paired points, NOTES §2b) and in space (the motion and scale under which
//! the position term compares the two surfaces).

use serde::Serialize;

use crate::linsolve::dense::symmetric_eigen;

/// The map `T(x) = M x + t` of the position term: a similarity, or an affine map near
/// one (`super::solve::PositionMap`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Similarity3 {
    pub matrix: [[f64; 3]; 3],
    pub translation: [f64; 3],
}

impl Similarity3 {
    pub fn identity() -> Self {
        Self {
            matrix: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            translation: [0.0; 3],
        }
    }

    #[inline]
    pub fn apply(&self, x: [f64; 3]) -> [f64; 3] {
        let m = &self.matrix;
        std::array::from_fn(|r| {
            m[r][0] * x[0] + m[r][1] * x[1] + m[r][2] * x[2] + self.translation[r]
        })
    }

    /// The scale `s` of `M = s·R`: `|det M|^(1/3)`.
    pub fn scale(&self) -> f64 {
        let m = &self.matrix;
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        det.abs().cbrt()
    }
}

/// A similarity of the plane, `p ↦ z·p + t` with `z = (c, s)` a complex factor
/// (rotation by `atan2(s, c)`, scale `|z|`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Similarity2 {
    pub z: [f64; 2],
    pub t: [f64; 2],
}

impl Similarity2 {
    pub fn identity() -> Self {
        Self {
            z: [1.0, 0.0],
            t: [0.0, 0.0],
        }
    }

    /// Rotation by `angle` and scaling by `scale` about `centre`, then moved so that
    /// `centre` lands on `target`.
    pub fn about(centre: [f64; 2], angle: f64, scale: f64, target: [f64; 2]) -> Self {
        let z = [scale * angle.cos(), scale * angle.sin()];
        let zc = mul(z, centre);
        Self {
            z,
            t: [target[0] - zc[0], target[1] - zc[1]],
        }
    }

    #[inline]
    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let q = mul(self.z, p);
        [q[0] + self.t[0], q[1] + self.t[1]]
    }

    /// `self ∘ inner`: `p ↦ self(inner(p))`.
    pub fn after(&self, inner: &Similarity2) -> Similarity2 {
        let t = self.apply(inner.t);
        Self {
            z: mul(self.z, inner.z),
            t,
        }
    }

    pub fn angle(&self) -> f64 {
        self.z[1].atan2(self.z[0])
    }

    pub fn scale(&self) -> f64 {
        self.z[0].hypot(self.z[1])
    }
}

#[inline]
fn mul(z: [f64; 2], p: [f64; 2]) -> [f64; 2] {
    [z[0] * p[0] - z[1] * p[1], z[0] * p[1] + z[1] * p[0]]
}

/// The similarity minimizing `Σ |S(pᵢ) − qᵢ|²` (closed form in complex arithmetic:
/// `z = Σ conj(p̃ᵢ) q̃ᵢ / Σ |p̃ᵢ|²` for centred points). `None` with fewer than two
/// distinct source points.
pub fn fit_similarity_2d(p: &[[f64; 2]], q: &[[f64; 2]]) -> Option<Similarity2> {
    let (z, pm, qm) = centred_fit(p, q)?;
    Some(through_means(z, pm, qm))
}

/// The rotation and translation, at the given `scale`, minimizing `Σ |S(pᵢ) − qᵢ|²` over
/// similarities `S(x) = scale·R·x + t` (Procrustes at a fixed scale: in complex
/// arithmetic, `z = scale · c/|c|` with `c = Σ conj(p̃ᵢ) q̃ᵢ` for centred points, and
/// `t = q̄ − z p̄`). `None` with fewer than two pairs, or when `c` vanishes (the source
/// points at one place, or no rotation preferred).
pub fn fit_rotation_2d_at_scale(p: &[[f64; 2]], q: &[[f64; 2]], scale: f64) -> Option<Similarity2> {
    let (free, pm, qm) = centred_fit(p, q)?;
    let norm = free[0].hypot(free[1]);
    if !(norm > 1e-300 && scale.is_finite() && scale > 0.0) {
        return None;
    }
    // The free fit's z is c/Σ|p̃|², so it has c's direction.
    Some(through_means(
        [scale * free[0] / norm, scale * free[1] / norm],
        pm,
        qm,
    ))
}

/// The free fit's `z = Σ conj(p̃ᵢ) q̃ᵢ / Σ |p̃ᵢ|²` and the means `p̄`, `q̄` of the first
/// `min(|p|, |q|)` pairs; `None` with fewer than two pairs or the `pᵢ` at one place.
fn centred_fit(p: &[[f64; 2]], q: &[[f64; 2]]) -> Option<([f64; 2], [f64; 2], [f64; 2])> {
    let n = p.len().min(q.len());
    if n < 2 {
        return None;
    }
    let mean = |v: &[[f64; 2]]| {
        let s = v[..n]
            .iter()
            .fold([0.0; 2], |a, x| [a[0] + x[0], a[1] + x[1]]);
        [s[0] / n as f64, s[1] / n as f64]
    };
    let (pm, qm) = (mean(p), mean(q));
    let (mut num, mut den) = ([0.0; 2], 0.0);
    for k in 0..n {
        let a = [p[k][0] - pm[0], p[k][1] - pm[1]];
        let b = [q[k][0] - qm[0], q[k][1] - qm[1]];
        // conj(a)·b
        num[0] += a[0] * b[0] + a[1] * b[1];
        num[1] += a[0] * b[1] - a[1] * b[0];
        den += a[0] * a[0] + a[1] * a[1];
    }
    if den <= 1e-300 {
        return None;
    }
    Some(([num[0] / den, num[1] / den], pm, qm))
}

/// The similarity `x ↦ z x + t` that takes `p̄` to `q̄`.
fn through_means(z: [f64; 2], pm: [f64; 2], qm: [f64; 2]) -> Similarity2 {
    let zp = mul(z, pm);
    Similarity2 {
        z,
        t: [qm[0] - zp[0], qm[1] - zp[1]],
    }
}

/// A landmark is left out of [`fit_similarity_2d_robust`] when the fit of the others
/// predicts it this many times farther off than their own RMS residual...
pub const OUTLIER_RATIO: f64 = 5.0;
/// ...and farther than this (in `ω = [0, 1]²` units: 2 % of the domain's side), so that
/// nearly exact fits drop nothing.
pub const OUTLIER_FLOOR: f64 = 0.02;

/// [`fit_similarity_2d`] that leaves out pairs the others disagree with: while at least
/// four pairs are kept, the pair whose removal leaves the best fit (lowest RMS residual
/// of the others) is dropped if that fit misses it by more than [`OUTLIER_RATIO`] × that
/// RMS and more than [`OUTLIER_FLOOR`]. Flattenings of two crops that differ in shape
/// (a mouth opened into the rim on one side only) can move one landmark by half the
/// domain while the others agree within 1–2 %; one such point pulls the least-squares
/// fit to half the scale (FLAME partial pair, BENCHMARKS.md). Returns the fit and the
/// indices left out (empty when all agree).
pub fn fit_similarity_2d_robust(
    p: &[[f64; 2]],
    q: &[[f64; 2]],
) -> Option<(Similarity2, Vec<usize>)> {
    let n = p.len().min(q.len());
    let mut kept: Vec<usize> = (0..n).collect();
    let fit_of = |idx: &[usize]| {
        let (pk, qk): (Vec<_>, Vec<_>) = idx.iter().map(|&i| (p[i], q[i])).unzip();
        fit_similarity_2d(&pk, &qk)
    };
    let miss = |s: &Similarity2, i: usize| {
        let r = s.apply(p[i]);
        (r[0] - q[i][0]).hypot(r[1] - q[i][1])
    };
    while kept.len() >= 4 {
        let mut best: Option<(f64, usize, Similarity2)> = None;
        for k in 0..kept.len() {
            let others: Vec<usize> = kept.iter().copied().filter(|&j| j != kept[k]).collect();
            let Some(s) = fit_of(&others) else { continue };
            let rms = (others.iter().map(|&j| miss(&s, j).powi(2)).sum::<f64>()
                / others.len() as f64)
                .sqrt();
            if best.is_none_or(|(b, _, _)| rms < b) {
                best = Some((rms, k, s));
            }
        }
        let Some((rms, k, s)) = best else { break };
        let e = miss(&s, kept[k]);
        if e > OUTLIER_RATIO * rms && e > OUTLIER_FLOOR {
            kept.remove(k);
        } else {
            break;
        }
    }
    let dropped = (0..n).filter(|i| !kept.contains(i)).collect();
    fit_of(&kept).map(|s| (s, dropped))
}

/// The similarity `T(x) = s·R·x + t` minimizing `Σ wᵢ |T(pᵢ) − qᵢ|²` (Horn's closed
/// form: the rotation is the unit quaternion of the largest eigenvalue of a 4 × 4
/// symmetric matrix built from the weighted cross-covariance; then
/// `s = Σ wᵢ q̃ᵢ·R p̃ᵢ / Σ wᵢ |p̃ᵢ|²`). With `allow_scale = false`, `s = 1` (a rigid
/// motion). `None` when the weights vanish or the points are degenerate.
pub fn fit_similarity_3d(
    p: &[[f64; 3]],
    q: &[[f64; 3]],
    w: &[f64],
    allow_scale: bool,
) -> Option<Similarity3> {
    let total: f64 = w.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let mut pm = [0.0; 3];
    let mut qm = [0.0; 3];
    for k in 0..p.len() {
        for c in 0..3 {
            pm[c] += w[k] * p[k][c] / total;
            qm[c] += w[k] * q[k][c] / total;
        }
    }
    let mut s = [[0.0; 3]; 3];
    let mut spp = 0.0;
    for k in 0..p.len() {
        if w[k] == 0.0 {
            continue;
        }
        let a: [f64; 3] = std::array::from_fn(|c| p[k][c] - pm[c]);
        let b: [f64; 3] = std::array::from_fn(|c| q[k][c] - qm[c]);
        for r in 0..3 {
            for c in 0..3 {
                s[r][c] += w[k] * a[r] * b[c];
            }
            spp += w[k] * a[r] * a[r];
        }
    }
    if spp.is_nan() || spp <= 0.0 {
        return None;
    }
    let [[sxx, sxy, sxz], [syx, syy, syz], [szx, szy, szz]] = s;
    let n = [
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ];
    let (_, vectors) = symmetric_eigen(&n)?;
    let [q0, qx, qy, qz] = vectors[3];
    let r = [
        [
            q0 * q0 + qx * qx - qy * qy - qz * qz,
            2.0 * (qx * qy - q0 * qz),
            2.0 * (qx * qz + q0 * qy),
        ],
        [
            2.0 * (qx * qy + q0 * qz),
            q0 * q0 - qx * qx + qy * qy - qz * qz,
            2.0 * (qy * qz - q0 * qx),
        ],
        [
            2.0 * (qx * qz - q0 * qy),
            2.0 * (qy * qz + q0 * qx),
            q0 * q0 - qx * qx - qy * qy + qz * qz,
        ],
    ];
    let scale = if allow_scale {
        // Σ w q̃·R p̃ = Σ_ab R_ab S_ba
        let mut num = 0.0;
        for a in 0..3 {
            for b in 0..3 {
                num += r[a][b] * s[b][a];
            }
        }
        (num / spp).max(f64::MIN_POSITIVE)
    } else {
        1.0
    };
    let matrix = r.map(|row| row.map(|v| scale * v));
    let mp: [f64; 3] =
        std::array::from_fn(|a| matrix[a][0] * pm[0] + matrix[a][1] * pm[1] + matrix[a][2] * pm[2]);
    Some(Similarity3 {
        matrix,
        translation: std::array::from_fn(|a| qm[a] - mp[a]),
    })
}

/// The affine map `T(x) = M x + t` of ℝ³ minimizing
///
/// `Σ wᵢ |T(pᵢ) − qᵢ|² + λ̄ ‖M − M₀‖²_F`,   `λ̄ = ridge · tr C / 3`,
///
/// `C = Σ wᵢ p̃ᵢ p̃ᵢᵀ` the weighted covariance of the centred points `p̃ = p − p̄` and `M₀`
/// the linear part of `near` (a similarity fitted to the same pairs,
/// [`fit_similarity_3d`]). Closed form (the normal equations of a ridge regression):
///
/// `M = (Σ wᵢ q̃ᵢ p̃ᵢᵀ + λ̄ M₀)(C + λ̄ I)⁻¹`,   `t = q̄ − M p̄`.
///
/// Along an eigenvector of `C` with eigenvalue `e` the data weigh `e / (e + λ̄)`: where
/// the points spread well (a face's width and height) `M` follows them, where they barely
/// spread (the depth of a shallow crop) it stays at the similarity — an unregularized
/// affine fit there is decided by noise. `ridge = 0` is the least-squares affine map,
/// `ridge → ∞` the similarity. `None` when the weights vanish or `C + λ̄ I` is singular.
pub fn fit_affine_3d_near(
    p: &[[f64; 3]],
    q: &[[f64; 3]],
    w: &[f64],
    near: &Similarity3,
    ridge: f64,
) -> Option<Similarity3> {
    use glam::{DMat3, DVec3};
    let total: f64 = w.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let (mut pm, mut qm) = (DVec3::ZERO, DVec3::ZERO);
    for k in 0..p.len() {
        pm += w[k] * DVec3::from_array(p[k]) / total;
        qm += w[k] * DVec3::from_array(q[k]) / total;
    }
    // glam is column-major: `outer(a, b)` = a bᵀ has columns a·b_j.
    let outer = |a: DVec3, b: DVec3| DMat3::from_cols(a * b.x, a * b.y, a * b.z);
    let (mut c, mut qp) = (DMat3::ZERO, DMat3::ZERO);
    for k in 0..p.len() {
        if w[k] == 0.0 {
            continue;
        }
        let a = DVec3::from_array(p[k]) - pm;
        let b = DVec3::from_array(q[k]) - qm;
        c += outer(a, a) * w[k];
        qp += outer(b, a) * w[k];
    }
    let lambda = ridge * (c.x_axis.x + c.y_axis.y + c.z_axis.z) / 3.0;
    let m0 = DMat3::from_cols_array_2d(&near.matrix).transpose();
    let normal = c + DMat3::from_diagonal(DVec3::splat(lambda));
    let det = normal.determinant();
    if !det.is_finite() || det.abs() <= 1e-300 {
        return None;
    }
    let m = (qp + m0 * lambda) * normal.inverse();
    let t = qm - m * pm;
    m.is_finite().then(|| Similarity3 {
        matrix: m.transpose().to_cols_array_2d(),
        translation: t.to_array(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Rng;

    /// Two points spread 30 % wider on B than the size asked for: the fit at that size
    /// turns and moves A as the points say, centring them on each other, and the free
    /// fit takes their spread as the size instead.
    #[test]
    fn a_fit_at_a_given_scale_keeps_it_and_finds_the_turn() {
        let angle: f64 = 2.4;
        let p = [[0.3, 0.4], [0.7, 0.45]];
        let spread = Similarity2::about([0.5, 0.42], angle, 0.9 * 1.3, [0.55, 0.5]);
        let q = p.map(|x| spread.apply(x));
        let fit = fit_rotation_2d_at_scale(&p, &q, 0.9).unwrap();
        assert!((fit.scale() - 0.9).abs() < 1e-12, "{fit:?}");
        let turn = (fit.angle() - angle).rem_euclid(std::f64::consts::TAU);
        assert!(turn.min(std::f64::consts::TAU - turn) < 1e-12, "{fit:?}");
        let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        let (m, target) = (fit.apply(mid(p[0], p[1])), mid(q[0], q[1]));
        assert!((m[0] - target[0]).hypot(m[1] - target[1]) < 1e-12);
        let free = fit_similarity_2d(&p, &q).unwrap();
        assert!((free.scale() - 0.9 * 1.3).abs() < 1e-12);
        assert!(fit_rotation_2d_at_scale(&[p[0], p[0]], &q, 0.9).is_none());
        assert!(fit_rotation_2d_at_scale(&p, &q, 0.0).is_none());
    }

    #[test]
    fn robust_plane_fit_drops_one_disagreeing_pair_and_nothing_else() {
        let truth = Similarity2::about([0.5, 0.5], 0.3, 0.8, [0.45, 0.55]);
        let p = [
            [0.2, 0.3],
            [0.8, 0.25],
            [0.5, 0.7],
            [0.3, 0.8],
            [0.7, 0.6],
            [0.5, 0.45],
        ];
        // Small noise (≤ 0.004) on every image, as two flattenings give.
        let noise = [0.003, -0.002, 0.004, -0.003, 0.001, -0.004];
        let mut q: Vec<[f64; 2]> = p
            .iter()
            .zip(noise)
            .map(|(&x, e)| {
                let y = truth.apply(x);
                [y[0] + e, y[1] - e]
            })
            .collect();
        let (clean, dropped) = fit_similarity_2d_robust(&p, &q).unwrap();
        assert!(dropped.is_empty(), "{dropped:?}");
        assert_eq!(clean, fit_similarity_2d(&p, &q).unwrap());
        // One image moved by a third of the domain: the plain fit's scale is pulled off
        // by more than 5 %, the robust one drops exactly that pair and recovers the truth.
        q[3] = [q[3][0] + 0.3, q[3][1] - 0.15];
        let plain = fit_similarity_2d(&p, &q).unwrap();
        assert!((plain.scale() / truth.scale() - 1.0).abs() > 0.05);
        let (robust, dropped) = fit_similarity_2d_robust(&p, &q).unwrap();
        assert_eq!(dropped, vec![3]);
        assert!((robust.scale() / truth.scale() - 1.0).abs() < 0.01);
        assert!((robust.angle() - truth.angle()).abs() < 0.01);
        // Three pairs are never thinned (a similarity has four degrees of freedom).
        let (_, dropped) = fit_similarity_2d_robust(&p[..3], &q[..3]).unwrap();
        assert!(dropped.is_empty());
    }

    #[test]
    fn composition_applies_the_inner_similarity_first() {
        let outer = Similarity2::about([0.3, 0.1], 0.7, 1.3, [0.5, -0.2]);
        let inner = Similarity2::about([-0.4, 0.2], -0.4, 0.8, [0.1, 0.9]);
        let both = outer.after(&inner);
        for p in [[0.0, 0.0], [1.0, -2.0], [0.25, 0.75]] {
            let (a, b) = (both.apply(p), outer.apply(inner.apply(p)));
            assert!((a[0] - b[0]).hypot(a[1] - b[1]) < 1e-14, "{a:?} {b:?}");
        }
        assert!((both.angle() - 0.3).abs() < 1e-14 && (both.scale() - 1.04).abs() < 1e-14);
    }

    #[test]
    fn plane_similarity_is_recovered_from_exact_pairs() {
        let truth = Similarity2::about([0.3, 0.4], 2.1, 0.7, [0.6, 0.2]);
        let mut rng = Rng(5);
        let p: Vec<[f64; 2]> = (0..7).map(|_| [rng.uniform(), rng.uniform()]).collect();
        let q: Vec<[f64; 2]> = p.iter().map(|&x| truth.apply(x)).collect();
        let fit = fit_similarity_2d(&p, &q).unwrap();
        assert!((fit.angle() - 2.1).abs() < 1e-12 && (fit.scale() - 0.7).abs() < 1e-12);
        for x in &p {
            let (a, b) = (fit.apply(*x), truth.apply(*x));
            assert!((a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12);
        }
        assert!(fit_similarity_2d(&p[..1], &q[..1]).is_none());
        assert!(fit_similarity_2d(&[[1.0, 1.0]; 3], &q[..3]).is_none());
    }

    #[test]
    fn space_similarity_is_recovered_and_is_optimal() {
        // Rotation about an oblique axis by 1.3 rad, scale 1.4, a translation.
        let truth = oblique_similarity(1.3, 1.4, [0.5, -2.0, 3.0]);
        let mut rng = Rng(9);
        let p: Vec<[f64; 3]> = (0..50)
            .map(|_| [rng.uniform(), rng.uniform(), rng.uniform()])
            .collect();
        let q: Vec<[f64; 3]> = p.iter().map(|&x| truth.apply(x)).collect();
        let w: Vec<f64> = (0..50).map(|_| rng.range(0.5, 2.0)).collect();
        let fit = fit_similarity_3d(&p, &q, &w, true).unwrap();
        for x in &p {
            let (a, b) = (fit.apply(*x), truth.apply(*x));
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() < 1e-9, "{a:?} vs {b:?}");
            }
        }
        // With noise the fit is a stationary point: perturbing it raises the residual.
        let noisy: Vec<[f64; 3]> = q
            .iter()
            .map(|x| x.map(|v| v + rng.range(-0.05, 0.05)))
            .collect();
        let fit = fit_similarity_3d(&p, &noisy, &w, false).unwrap();
        let cost = |t: &Similarity3| squared_misfit(t, &p, &noisy, &w);
        let base = cost(&fit);
        for dt in [[1e-3, 0.0, 0.0], [0.0, -1e-3, 0.0], [0.0, 0.0, 1e-3]] {
            let mut moved = fit;
            for (t, d) in moved.translation.iter_mut().zip(dt) {
                *t += d;
            }
            assert!(cost(&moved) > base);
        }
        // Rigid: the matrix is a rotation.
        let m = fit.matrix;
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        assert!((det - 1.0).abs() < 1e-9);
    }

    /// `Σ wᵢ |T(pᵢ) − qᵢ|²`, the data part of every fit here.
    fn squared_misfit(t: &Similarity3, p: &[[f64; 3]], q: &[[f64; 3]], w: &[f64]) -> f64 {
        p.iter()
            .zip(q)
            .zip(w)
            .map(|((a, b), wi)| {
                let y = t.apply(*a);
                wi * (0..3).map(|c| (y[c] - b[c]).powi(2)).sum::<f64>()
            })
            .sum()
    }

    /// The rotation by `angle` about an oblique axis, scaled by `scale`, then `translation`.
    fn oblique_similarity(angle: f64, scale: f64, translation: [f64; 3]) -> Similarity3 {
        let r = crate::matching::rigid::axis_angle_rotation([0.48, -0.6, 0.64], angle);
        Similarity3 {
            matrix: r.map(|row| row.map(|v| scale * v)),
            translation,
        }
    }

    /// `T ∘ diag(stretch)`.
    fn stretched(t: &Similarity3, stretch: [f64; 3]) -> Similarity3 {
        Similarity3 {
            matrix: t
                .matrix
                .map(|row| std::array::from_fn(|j| row[j] * stretch[j])),
            translation: t.translation,
        }
    }

    #[test]
    fn affine_fit_recovers_an_exact_affine_map_and_keeps_an_exact_similarity() {
        let sim = oblique_similarity(0.7, 0.9, [0.3, -1.0, 2.0]);
        let truth = stretched(&sim, [1.2, 0.9, 1.05]);
        let mut rng = Rng(3);
        let p: Vec<[f64; 3]> = (0..60)
            .map(|_| [rng.uniform(), rng.uniform(), rng.uniform()])
            .collect();
        let w: Vec<f64> = (0..60).map(|_| rng.range(0.5, 2.0)).collect();
        // Without the ridge, exact affine pairs give the affine map back.
        let q: Vec<[f64; 3]> = p.iter().map(|&x| truth.apply(x)).collect();
        let near = fit_similarity_3d(&p, &q, &w, true).unwrap();
        let fit = fit_affine_3d_near(&p, &q, &w, &near, 0.0).unwrap();
        assert!(squared_misfit(&fit, &p, &q, &w) < 1e-20);
        for r in 0..3 {
            for c in 0..3 {
                assert!((fit.matrix[r][c] - truth.matrix[r][c]).abs() < 1e-9);
            }
        }
        // Pairs a similarity explains exactly: any ridge leaves that similarity.
        let q: Vec<[f64; 3]> = p.iter().map(|&x| sim.apply(x)).collect();
        let near = fit_similarity_3d(&p, &q, &w, true).unwrap();
        for ridge in [0.0, 0.3, 1.0, 10.0] {
            let fit = fit_affine_3d_near(&p, &q, &w, &near, ridge).unwrap();
            for r in 0..3 {
                for c in 0..3 {
                    assert!((fit.matrix[r][c] - sim.matrix[r][c]).abs() < 1e-9);
                }
                assert!((fit.translation[r] - sim.translation[r]).abs() < 1e-9);
            }
        }
        assert!(fit_affine_3d_near(&p, &q, &[0.0; 60], &near, 1.0).is_none());
    }

    /// The closed form is the minimizer of its objective (data + ridge): with noisy
    /// pairs, moving any entry of `M` or `t` either way raises it.
    #[test]
    fn affine_fit_minimizes_the_ridge_objective() {
        let truth = stretched(
            &oblique_similarity(0.7, 0.9, [0.3, -1.0, 2.0]),
            [1.15, 1.0, 0.95],
        );
        let mut rng = Rng(11);
        let p: Vec<[f64; 3]> = (0..40)
            .map(|_| [rng.uniform(), rng.uniform(), 0.3 * rng.uniform()])
            .collect();
        let w: Vec<f64> = (0..40).map(|_| rng.range(0.5, 2.0)).collect();
        let q: Vec<[f64; 3]> = p
            .iter()
            .map(|&x| truth.apply(x).map(|v| v + rng.range(-0.05, 0.05)))
            .collect();
        let near = fit_similarity_3d(&p, &q, &w, true).unwrap();
        let ridge = 0.7;
        // λ̄ = ridge · tr C / 3, C the weighted covariance of p.
        let total: f64 = w.iter().sum();
        let mean: [f64; 3] =
            std::array::from_fn(|c| p.iter().zip(&w).map(|(x, wi)| wi * x[c]).sum::<f64>() / total);
        let trace: f64 = p
            .iter()
            .zip(&w)
            .map(|(x, wi)| wi * (0..3).map(|c| (x[c] - mean[c]).powi(2)).sum::<f64>())
            .sum();
        let lambda = ridge * trace / 3.0;
        let objective = |t: &Similarity3| {
            let penalty: f64 = (0..3)
                .flat_map(|r| (0..3).map(move |c| (r, c)))
                .map(|(r, c)| (t.matrix[r][c] - near.matrix[r][c]).powi(2))
                .sum();
            squared_misfit(t, &p, &q, &w) + lambda * penalty
        };
        let fit = fit_affine_3d_near(&p, &q, &w, &near, ridge).unwrap();
        let base = objective(&fit);
        for k in 0..12 {
            for d in [-1e-4, 1e-4] {
                let mut moved = fit;
                if k < 9 {
                    moved.matrix[k / 3][k % 3] += d;
                } else {
                    moved.translation[k - 9] += d;
                }
                assert!(objective(&moved) > base, "entry {k} by {d}");
            }
        }
    }

    /// Points that barely spread in one direction (a shallow crop of a surface): the
    /// plain affine fit's map along it is decided by the noise, the ridge fit's stays
    /// near the similarity, and the ridge fit still follows most of a stretch along the
    /// directions the points do spread in.
    #[test]
    fn ridge_keeps_a_poorly_spread_direction_at_the_similarity() {
        let sim = oblique_similarity(0.7, 0.9, [0.3, -1.0, 2.0]);
        let truth = stretched(&sim, [1.2, 1.0, 1.0]);
        let mut rng = Rng(7);
        let p: Vec<[f64; 3]> = (0..400)
            .map(|_| [rng.uniform(), rng.uniform(), 0.002 * rng.uniform()])
            .collect();
        let w = vec![1.0; p.len()];
        let q: Vec<[f64; 3]> = p
            .iter()
            .map(|&x| truth.apply(x).map(|v| v + rng.range(-0.01, 0.01)))
            .collect();
        let near = fit_similarity_3d(&p, &q, &w, true).unwrap();
        // How much T stretches an axis direction, relative to the similarity's scale.
        let gain = |t: &Similarity3, axis: usize| {
            (0..3)
                .map(|r| t.matrix[r][axis].powi(2))
                .sum::<f64>()
                .sqrt()
                / near.scale()
        };
        // How far T's image of the shallow axis is from the similarity's.
        let off = |t: &Similarity3| {
            (0..3)
                .map(|r| (t.matrix[r][2] - near.matrix[r][2]).powi(2))
                .sum::<f64>()
                .sqrt()
                / near.scale()
        };
        let plain = fit_affine_3d_near(&p, &q, &w, &near, 0.0).unwrap();
        let ridge = fit_affine_3d_near(&p, &q, &w, &near, 1.0).unwrap();
        assert!(off(&plain) > 0.2, "plain fit: {}", off(&plain));
        assert!(off(&ridge) < 0.02, "ridge fit: {}", off(&ridge));
        // The similarity stretches x and y alike; the ridge fit moves the x/y ratio most
        // of the way to the truth's 1.2 (data weight e/(e + λ̄) ≈ 0.6 along x and y).
        let ratio = gain(&ridge, 0) / gain(&ridge, 1);
        assert!(ratio > 1.1 && ratio < 1.2, "x/y gain ratio {ratio}");
        assert!(
            squared_misfit(&ridge, &p, &q, &w) < squared_misfit(&near, &p, &q, &w),
            "the ridge fit explains the pairs better than the similarity"
        );
    }
}
