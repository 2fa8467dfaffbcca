//! Per-triangle energy, gradient and positive semi-definite Hessian (thesis §3.1.2,
//! App. A): the density `W(a, d)` of [`crate::energy`] pulled back to a triangle's UV
//! coordinates.
//!
//! A triangle's map is linear. With the rest triangle in an orthonormal frame of its
//! own plane (2D corners `x1, x2, x3`, `Dm = [x2 − x1, x3 − x1]`) and its UV triangle
//! (`Ds = [u2 − u1, u3 − u1]`), the Jacobian is `J = Ds · Dm⁻¹` and the element energy is
//!
//! ```text
//! E_T = area3D(T) · Ψ(J),   Ψ(J) = W(a, d),   a = ‖J‖²_F = σ1² + σ2²,   d = det(J)² = σ1²σ2²
//! ```
//!
//! (the discrete counterpart of (2.4): `√det g · |T|` is the 3D area). Degrees of
//! freedom are ordered `(u1, v1, u2, v2, u3, v3)`. `J` depends linearly on them through
//! the constant map `∂vec(J)/∂u` (4 × 6), so gradient and Hessian are the pull-backs of
//! `∂Ψ/∂J` and `∂²Ψ/∂J²`.
//!
//! The Hessian of `Ψ` is indefinite away from the minimum (W is polyconvex, not convex).
//! Because `Ψ` is isotropic its 4 × 4 Hessian has a closed-form eigensystem (Smith,
//! De Goes, Kim 2019, *Analytic eigensystems for isotropic distortion energies*), which
//! [`gradient_and_projected_hessian`] uses to clamp negative eigenvalues to zero.

use crate::energy::Density;
use crate::mesh::validate::TriangleShape;
use crate::mesh::{IndexError, check_indices};
use crate::vec3::dot3;
use rayon::prelude::*;
use thiserror::Error;

/// A rest (3D) triangle prepared for the element computations: `Dm⁻¹` in an
/// orthonormal frame of the triangle's plane, and the 3D area.
///
/// The frame is chosen so that `det Dm > 0`; hence `det J > 0` exactly when the UV
/// triangle is counter-clockwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestTriangle {
    /// `Dm⁻¹`, row-major: `dm_inv[row][col]`.
    pub dm_inv: [[f64; 2]; 2],
    /// 3D area `|(p2 − p1) × (p3 − p1)| / 2`.
    pub area: f64,
}

impl RestTriangle {
    /// Builds the rest data of the 3D triangle `(p1, p2, p3)`.
    ///
    /// Frame: `e1 = (p2 − p1)/|p2 − p1|`, `e2 = n × e1` with `n` the unit normal, so
    /// `x1 = (0, 0)`, `x2 = (|p2 − p1|, 0)`, `x3 = ((p3 − p1)·e1, (p3 − p1)·e2)` with
    /// `x3.y = 2·area/|p2 − p1| > 0`.
    ///
    /// Returns `None` for a degenerate triangle: non-finite corners, or an area at
    /// rounding level (`|n| ≤ ε · ℓ²_max`, ℓ the longest edge), including zero.
    pub fn new(p1: [f64; 3], p2: [f64; 3], p3: [f64; 3]) -> Option<Self> {
        // The same test as validation's ([`TriangleShape`]): what it names, this refuses.
        let shape = TriangleShape::new(p1, p2, p3);
        if shape.overflows() || shape.is_flat() {
            return None;
        }
        let (e, f, n_len) = (shape.e, shape.f, shape.normal_length);
        let e_len = dot3(e, e).sqrt();
        // x3 in the frame: x3.x = f·e/|e|, x3.y = |e × f|/|e|.
        let x3x = dot3(f, e) / e_len;
        let x3y = n_len / e_len;
        // Dm = [[e_len, x3x], [0, x3y]]  ⇒  Dm⁻¹ = [[1/e_len, −x3x/(e_len·x3y)], [0, 1/x3y]].
        let dm_inv = [[1.0 / e_len, -x3x / (e_len * x3y)], [0.0, 1.0 / x3y]];
        let area = 0.5 * n_len;
        if !(dm_inv.iter().flatten().all(|v| v.is_finite()) && area.is_finite()) {
            return None;
        }
        Some(Self { dm_inv, area })
    }
}

/// Why the rest triangles of a mesh could not be built.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum RestTriangleError {
    #[error(transparent)]
    Index(#[from] IndexError),
    #[error(
        "{count} face(s) have (nearly) zero area, or corners, lengths or areas that are not finite numbers (0-based face ids, first: {first}); their distortion is undefined — remove or repair them (collapse zero-area faces) before flattening"
    )]
    Degenerate { first: usize, count: usize },
}

/// Rest data of every triangle of a mesh, in triangle order.
///
/// Fails on an out-of-range vertex index or on degenerate triangles (see
/// [`RestTriangle::new`]); the error names the first offender.
pub fn rest_triangles(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<Vec<RestTriangle>, RestTriangleError> {
    check_indices(triangles, positions.len())?;
    let rest: Vec<Option<RestTriangle>> = triangles
        .par_iter()
        .with_min_len(4096)
        .map(|&[a, b, c]| {
            RestTriangle::new(
                positions[a as usize],
                positions[b as usize],
                positions[c as usize],
            )
        })
        .collect();
    let count = rest.iter().filter(|r| r.is_none()).count();
    if count > 0 {
        let first = rest.iter().position(|r| r.is_none()).unwrap_or(0);
        return Err(RestTriangleError::Degenerate { first, count });
    }
    Ok(rest.into_iter().flatten().collect())
}

/// The Jacobian `J = Ds · Dm⁻¹` (row-major) of the map from the rest triangle to the UV
/// triangle `uv = [u1, u2, u3]`; rows are the UV components, columns the rest frame axes.
#[inline]
pub fn jacobian(rest: &RestTriangle, uv: &[[f64; 2]; 3]) -> [[f64; 2]; 2] {
    let ds = [
        [uv[1][0] - uv[0][0], uv[2][0] - uv[0][0]],
        [uv[1][1] - uv[0][1], uv[2][1] - uv[0][1]],
    ];
    let m = &rest.dm_inv;
    [
        [
            ds[0][0] * m[0][0] + ds[0][1] * m[1][0],
            ds[0][0] * m[0][1] + ds[0][1] * m[1][1],
        ],
        [
            ds[1][0] * m[0][0] + ds[1][1] * m[1][0],
            ds[1][0] * m[0][1] + ds[1][1] * m[1][1],
        ],
    ]
}

/// Element energy `area3D · W(a, d)` with `a = ‖J‖²_F`, `d = det(J)²`.
///
/// Returns `f64::INFINITY` when `det J ≤ 0` (flipped or collapsed UV triangle) or the
/// input is not finite: every density here is defined on the admissible set
/// `det J > 0` only (thesis §3.1.3 extends `E` by `+∞` outside it; `W(a, d)` cannot see
/// the orientation, so without this a flipped triangle would look unflipped).
#[inline]
pub fn energy<D: Density + ?Sized>(rest: &RestTriangle, uv: &[[f64; 2]; 3], density: &D) -> f64 {
    let j = jacobian(rest, uv);
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    if !(det > 0.0 && det.is_finite()) {
        return f64::INFINITY;
    }
    let a = j[0][0] * j[0][0] + j[0][1] * j[0][1] + j[1][0] * j[1][0] + j[1][1] * j[1][1];
    let w = density.eval(a, det * det).w;
    rest.area * w
}

/// Element energy and its gradient `∂E_T/∂(u1, v1, u2, v2, u3, v3)`.
///
/// `∂Ψ/∂J = 2·W_a·J + 2·W_d·det J·cof J` (from `∂a/∂J = 2J`, `∂d/∂J = 2 det J·cof J`,
/// `cof J = [[J11, −J10], [−J01, J00]]`), pulled back with `∂J/∂u`. On `det J ≤ 0`
/// returns `f64::INFINITY` and a zero gradient.
#[inline]
pub fn gradient<D: Density + ?Sized>(
    rest: &RestTriangle,
    uv: &[[f64; 2]; 3],
    density: &D,
    out_grad: &mut [f64; 6],
) -> f64 {
    let Some(local) = Local::new(rest, uv, density) else {
        *out_grad = [0.0; 6];
        return f64::INFINITY;
    };
    local.pull_back_gradient(rest, out_grad);
    rest.area * local.w.w
}

/// Element energy, gradient and the Hessian projected to positive semi-definite.
///
/// With `J = U diag(σ1, σ2) Vᵀ` (here `det J > 0`, so `σ2 > 0`), the 4 × 4 Hessian of
/// `Ψ(J) = W(a, d)` has the eigenvectors (Smith, De Goes, Kim 2019, 2D case):
///
/// * twist `U [[0, −1], [1, 0]] Vᵀ/√2`, eigenvalue
///   `(Ψ_σ1 + Ψ_σ2)/(σ1 + σ2) = 2W_a + 2W_d·σ1σ2`;
/// * flip `U [[0, 1], [1, 0]] Vᵀ/√2`, eigenvalue
///   `(Ψ_σ1 − Ψ_σ2)/(σ1 − σ2) = 2W_a − 2W_d·σ1σ2`;
/// * scaling modes `U diag(1, 0) Vᵀ`, `U diag(0, 1) Vᵀ`, coupled by the 2 × 2 Hessian
///   `∂²Ψ/∂σi∂σj` with `Ψ_σi = 2σi(W_a + σj²W_d)`.
///
/// Since `Ψ_σi` is written through `W_a, W_d`, the twist/flip eigenvalues need no
/// division by `σ1 ± σ2`: the equal-σ case (a conformal triangle) is exact. The
/// vectors are built without an explicit SVD: `J = Q·rotation + R·reflection`
/// (conformal plus anticonformal parts, `σ1 = Q + R`, `σ2 = det J/σ1`); `UVᵀ` is the
/// unit rotation, `U diag(1, −1) Vᵀ` the unit reflection, twist and flip their
/// quarter-turns. When `R = 0` (σ1 = σ2) any reflection direction is a valid
/// eigenvector.
///
/// Negative eigenvalues are clamped to 0 (the 2 × 2 scaling block is projected in
/// closed form), and the result is pulled back as `area · Bᵀ H⁺ B` with
/// `B = ∂vec(J)/∂u`. On `det J ≤ 0` returns `f64::INFINITY` and zeros.
#[inline]
pub fn gradient_and_projected_hessian<D: Density + ?Sized>(
    rest: &RestTriangle,
    uv: &[[f64; 2]; 3],
    density: &D,
    out_grad: &mut [f64; 6],
    out_hess: &mut [[f64; 6]; 6],
) -> f64 {
    let Some(local) = Local::new(rest, uv, density) else {
        *out_grad = [0.0; 6];
        *out_hess = [[0.0; 6]; 6];
        return f64::INFINITY;
    };
    local.pull_back_gradient(rest, out_grad);
    let hj = local.eigen_hessian(true);
    pull_back_hessian(rest, &hj, out_hess);
    rest.area * local.w.w
}

/// Element energy, gradient and the exact (unprojected, possibly indefinite) Hessian:
///
/// ```text
/// ∂²Ψ/∂J² = W_aa ∇a∇aᵀ + W_ad (∇a∇dᵀ + ∇d∇aᵀ) + W_dd ∇d∇dᵀ
///         + 2W_a·I + W_d·(2 cof J cof Jᵀ + 2 det J·∂²det J)
/// ```
///
/// with `∇a = 2 vec J`, `∇d = 2 det J·vec cof J`. The Newton solver uses it close to a
/// minimum, where it is positive definite and converges quadratically (falling back to
/// [`gradient_and_projected_hessian`] where its Cholesky fails); the tests check the
/// projection against it. On `det J ≤ 0` returns `f64::INFINITY` and zeros.
pub fn exact_hessian<D: Density + ?Sized>(
    rest: &RestTriangle,
    uv: &[[f64; 2]; 3],
    density: &D,
    out_grad: &mut [f64; 6],
    out_hess: &mut [[f64; 6]; 6],
) -> f64 {
    let Some(local) = Local::new(rest, uv, density) else {
        *out_grad = [0.0; 6];
        *out_hess = [[0.0; 6]; 6];
        return f64::INFINITY;
    };
    local.pull_back_gradient(rest, out_grad);
    let hj = local.exact_hessian_j();
    pull_back_hessian(rest, &hj, out_hess);
    rest.area * local.w.w
}

/// Quantities at one element in `J` space; `vec J = (J00, J01, J10, J11)`.
struct Local {
    f: [f64; 4],
    det: f64,
    w: crate::energy::DensityDerivs,
}

impl Local {
    #[inline(always)]
    fn new<D: Density + ?Sized>(
        rest: &RestTriangle,
        uv: &[[f64; 2]; 3],
        density: &D,
    ) -> Option<Self> {
        let j = jacobian(rest, uv);
        let f = [j[0][0], j[0][1], j[1][0], j[1][1]];
        let det = f[0] * f[3] - f[1] * f[2];
        if !(det > 0.0 && det.is_finite()) {
            return None;
        }
        let a = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] + f[3] * f[3];
        let w = density.eval(a, det * det);
        Some(Self { f, det, w })
    }

    /// `vec cof J = ∂ det J / ∂ vec J`.
    #[inline(always)]
    fn cof(&self) -> [f64; 4] {
        [self.f[3], -self.f[2], -self.f[1], self.f[0]]
    }

    /// `∂Ψ/∂vec J = 2W_a·vec J + 2W_d·det J·vec cof J`.
    #[inline(always)]
    fn stress(&self) -> [f64; 4] {
        let c = self.cof();
        let ka = 2.0 * self.w.w_a;
        let kd = 2.0 * self.w.w_d * self.det;
        [
            ka * self.f[0] + kd * c[0],
            ka * self.f[1] + kd * c[1],
            ka * self.f[2] + kd * c[2],
            ka * self.f[3] + kd * c[3],
        ]
    }

    #[inline(always)]
    fn pull_back_gradient(&self, rest: &RestTriangle, out: &mut [f64; 6]) {
        let p = self.stress();
        let c = column_coefficients(rest);
        for (k, corner) in out.chunks_exact_mut(2).enumerate() {
            for (i, o) in corner.iter_mut().enumerate() {
                *o = rest.area * (p[2 * i] * c[0][k] + p[2 * i + 1] * c[1][k]);
            }
        }
    }

    fn exact_hessian_j(&self) -> [[f64; 4]; 4] {
        let c = self.cof();
        let ga = [
            2.0 * self.f[0],
            2.0 * self.f[1],
            2.0 * self.f[2],
            2.0 * self.f[3],
        ];
        let gd = [
            2.0 * self.det * c[0],
            2.0 * self.det * c[1],
            2.0 * self.det * c[2],
            2.0 * self.det * c[3],
        ];
        let w = &self.w;
        let mut h = [[0.0; 4]; 4];
        for r in 0..4 {
            for s in 0..4 {
                h[r][s] = w.w_aa * ga[r] * ga[s]
                    + w.w_ad * (ga[r] * gd[s] + gd[r] * ga[s])
                    + w.w_dd * gd[r] * gd[s]
                    + 2.0 * w.w_d * c[r] * c[s];
            }
            h[r][r] += 2.0 * w.w_a;
        }
        // ∂²det J: +1 at (J00, J11), −1 at (J01, J10).
        let t = 2.0 * w.w_d * self.det;
        h[0][3] += t;
        h[3][0] += t;
        h[1][2] -= t;
        h[2][1] -= t;
        h
    }

    /// `Σ λk ek ekᵀ` over the analytic eigensystem; with `clamp`, negative eigenvalues
    /// are replaced by 0 (the PSD projection). Without `clamp` it reproduces
    /// [`Self::exact_hessian_j`] (checked in the tests).
    #[inline(always)]
    fn eigen_hessian(&self, clamp: bool) -> [[f64; 4]; 4] {
        let [j00, j01, j10, j11] = self.f;
        // Conformal part E·I + H·R90, anticonformal part F·S + G·S' with
        // S = diag(1, −1), S' = [[0, 1], [1, 0]].
        let e = 0.5 * (j00 + j11);
        let h = 0.5 * (j10 - j01);
        let f = 0.5 * (j00 - j11);
        let g = 0.5 * (j10 + j01);
        let q = (e * e + h * h).sqrt();
        let r = (f * f + g * g).sqrt();
        let s1 = q + r;
        let s2 = self.det / s1;
        let (ce, sh) = (e / q, h / q);
        let (cf, sg) = if r > 0.0 { (f / r, g / r) } else { (1.0, 0.0) };
        let k = std::f64::consts::FRAC_1_SQRT_2;
        // Unit rotation UVᵀ/√2 (= c_hat) and its quarter-turn (twist); unit reflection
        // U S Vᵀ/√2 (= a_hat) and its quarter-turn (flip); all as vec(·).
        let c_hat = [k * ce, -k * sh, k * sh, k * ce];
        let twist = [-k * sh, -k * ce, k * ce, -k * sh];
        let a_hat = [k * cf, k * sg, k * sg, -k * cf];
        let flip = [-k * sg, k * cf, k * cf, k * sg];
        // Scaling modes D1 = U diag(1,0) Vᵀ, D2 = U diag(0,1) Vᵀ.
        let d1: [f64; 4] = std::array::from_fn(|i| k * (c_hat[i] + a_hat[i]));
        let d2: [f64; 4] = std::array::from_fn(|i| k * (c_hat[i] - a_hat[i]));

        let w = &self.w;
        let s1s2 = s1 * s2;
        let mut lambda_twist = 2.0 * w.w_a + 2.0 * w.w_d * s1s2;
        let mut lambda_flip = 2.0 * w.w_a - 2.0 * w.w_d * s1s2;
        // 2×2 Hessian of Ψ(σ1, σ2) = W(σ1² + σ2², σ1²σ2²).
        let (a1, a2) = (2.0 * s1, 2.0 * s2);
        let (dd1, dd2) = (2.0 * s1 * s2 * s2, 2.0 * s2 * s1 * s1);
        let mut p = w.w_aa * a1 * a1
            + 2.0 * w.w_ad * a1 * dd1
            + w.w_dd * dd1 * dd1
            + 2.0 * w.w_a
            + 2.0 * s2 * s2 * w.w_d;
        let mut rr = w.w_aa * a2 * a2
            + 2.0 * w.w_ad * a2 * dd2
            + w.w_dd * dd2 * dd2
            + 2.0 * w.w_a
            + 2.0 * s1 * s1 * w.w_d;
        let mut qq = w.w_aa * a1 * a2
            + w.w_ad * (a1 * dd2 + a2 * dd1)
            + w.w_dd * dd1 * dd2
            + 4.0 * s1s2 * w.w_d;
        if clamp {
            lambda_twist = lambda_twist.max(0.0);
            lambda_flip = lambda_flip.max(0.0);
            (p, qq, rr) = project_psd_2x2(p, qq, rr);
        }
        let mut out = [[0.0; 4]; 4];
        for i in 0..4 {
            for j in i..4 {
                let v = lambda_twist * twist[i] * twist[j]
                    + lambda_flip * flip[i] * flip[j]
                    + p * d1[i] * d1[j]
                    + rr * d2[i] * d2[j]
                    + qq * (d1[i] * d2[j] + d2[i] * d1[j]);
                out[i][j] = v;
                out[j][i] = v;
            }
        }
        out
    }
}

/// Projects the symmetric `[[p, q], [q, r]]` to positive semi-definite (negative
/// eigenvalues set to 0). With eigenvalues `λmin < 0 < λmax` the result is
/// `λmax/(λmax − λmin) · (H − λmin I)` (= `λmax v vᵀ`), no eigenvector needed.
#[inline(always)]
fn project_psd_2x2(p: f64, q: f64, r: f64) -> (f64, f64, f64) {
    let mean = 0.5 * (p + r);
    let half_diff = 0.5 * (p - r);
    let rad = (half_diff * half_diff + q * q).sqrt();
    let (lmin, lmax) = (mean - rad, mean + rad);
    if lmin >= 0.0 {
        (p, q, r)
    } else if lmax <= 0.0 {
        (0.0, 0.0, 0.0)
    } else {
        let s = lmax / (lmax - lmin);
        (s * (p - lmin), s * q, s * (r - lmin))
    }
}

/// Coefficients of `∂J[i][j]/∂(corner k, component i)`: for column `j`,
/// `c[j] = [−(Dm⁻¹[0][j] + Dm⁻¹[1][j]), Dm⁻¹[0][j], Dm⁻¹[1][j]]`.
#[inline(always)]
fn column_coefficients(rest: &RestTriangle) -> [[f64; 3]; 2] {
    let m = &rest.dm_inv;
    [
        [-(m[0][0] + m[1][0]), m[0][0], m[1][0]],
        [-(m[0][1] + m[1][1]), m[0][1], m[1][1]],
    ]
}

/// `out = area · Bᵀ HJ B` with `B[2i + j][2k + i] = c[j][k]` (vec J row-major, DOFs
/// `(u1, v1, u2, v2, u3, v3)`).
#[inline(always)]
fn pull_back_hessian(rest: &RestTriangle, hj: &[[f64; 4]; 4], out: &mut [[f64; 6]; 6]) {
    let c = column_coefficients(rest);
    // G[2i + j][2l + m] = Σ_n HJ[2i + j][2m + n] c[n][l] for column DOF 2l + m, then
    // out[2k + i][2l + m] = area Σ_j c[j][k] G[2i + j][2l + m].
    let mut g = [[0.0; 6]; 4];
    for (row, grow) in hj.iter().zip(g.iter_mut()) {
        for l in 0..3 {
            for m in 0..2 {
                grow[2 * l + m] = row[2 * m] * c[0][l] + row[2 * m + 1] * c[1][l];
            }
        }
    }
    for (k, (&c0k, &c1k)) in c[0].iter().zip(&c[1]).enumerate() {
        let (ck0, ck1) = (rest.area * c0k, rest.area * c1k);
        for i in 0..2 {
            let r = 2 * k + i;
            for col in r..6 {
                let v = ck0 * g[2 * i][col] + ck1 * g[2 * i + 1][col];
                out[r][col] = v;
                out[col][r] = v;
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // matrix indices read best as indices
mod tests {
    use super::*;
    use crate::energy::{Alpha, Arap, Mips, SymmetricDirichlet};
    use crate::vec3::{cross3, sub3};

    use crate::testing::Rng;

    use crate::testing::all_energies as densities;

    fn random_rest(rng: &mut Rng) -> ([[f64; 3]; 3], RestTriangle) {
        loop {
            let p: [[f64; 3]; 3] =
                std::array::from_fn(|_| std::array::from_fn(|_| rng.range(-1.0, 1.0)));
            let n = cross3(sub3(p[1], p[0]), sub3(p[2], p[0]));
            if dot3(n, n).sqrt() > 0.2 {
                return (p, RestTriangle::new(p[0], p[1], p[2]).unwrap());
            }
        }
    }

    fn rot(angle: f64) -> [[f64; 2]; 2] {
        let (s, c) = angle.sin_cos();
        [[c, -s], [s, c]]
    }

    fn mul(a: [[f64; 2]; 2], b: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
        std::array::from_fn(|i| std::array::from_fn(|j| a[i][0] * b[0][j] + a[i][1] * b[1][j]))
    }

    /// Rest corners in the element's own 2D frame, from `Dm = (Dm⁻¹)⁻¹`.
    fn rest_corners(rest: &RestTriangle) -> [[f64; 2]; 3] {
        let m = rest.dm_inv;
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        let dm = [
            [m[1][1] / det, -m[0][1] / det],
            [-m[1][0] / det, m[0][0] / det],
        ];
        [[0.0, 0.0], [dm[0][0], dm[1][0]], [dm[0][1], dm[1][1]]]
    }

    /// UV corners realizing `J = R(φ) diag(σ1, σ2) R(θ)ᵀ` on `rest`, plus a translation.
    fn uv_for(rest: &RestTriangle, s1: f64, s2: f64, phi: f64, theta: f64) -> [[f64; 2]; 3] {
        let rt = rot(theta);
        let j = mul(
            mul(rot(phi), [[s1, 0.0], [0.0, s2]]),
            [[rt[0][0], rt[1][0]], [rt[0][1], rt[1][1]]],
        );
        let x = rest_corners(rest);
        std::array::from_fn(|k| {
            [
                j[0][0] * x[k][0] + j[0][1] * x[k][1] + 0.3,
                j[1][0] * x[k][0] + j[1][1] * x[k][1] - 0.7,
            ]
        })
    }

    /// Singular value pairs: generic, near-degenerate (σ2/σ1 = 1e-3), nearly and
    /// exactly conformal, isometry.
    fn sigma_cases(rng: &mut Rng) -> Vec<(f64, f64)> {
        let s = rng.range(0.4, 2.5);
        vec![
            (s, s * rng.range(0.1, 1.0)),
            (rng.range(0.3, 3.0), rng.range(0.3, 3.0)),
            (s, s * 1e-3),
            (s, s * (1.0 - 1e-9)),
            (s, s),
            (1.0, 1.0),
        ]
    }

    fn max_abs6(h: &[[f64; 6]; 6]) -> f64 {
        h.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()))
    }

    /// Eigenvalues of a symmetric 6×6 matrix by cyclic Jacobi rotations.
    fn sym_eigenvalues(mut a: [[f64; 6]; 6]) -> [f64; 6] {
        for _sweep in 0..100 {
            let off: f64 = (0..6)
                .flat_map(|i| (0..6).filter(move |&j| j != i).map(move |j| (i, j)))
                .map(|(i, j)| a[i][j] * a[i][j])
                .sum();
            if off <= 1e-30 * max_abs6(&a).powi(2) {
                break;
            }
            for p in 0..6 {
                for q in p + 1..6 {
                    if a[p][q] == 0.0 {
                        continue;
                    }
                    let tau = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                    let t = tau.signum() / (tau.abs() + (1.0 + tau * tau).sqrt());
                    let t = if tau == 0.0 { 1.0 } else { t };
                    let c = 1.0 / (1.0 + t * t).sqrt();
                    let s = t * c;
                    for k in 0..6 {
                        let (akp, akq) = (a[k][p], a[k][q]);
                        a[k][p] = c * akp - s * akq;
                        a[k][q] = s * akp + c * akq;
                    }
                    for k in 0..6 {
                        let (apk, aqk) = (a[p][k], a[q][k]);
                        a[p][k] = c * apk - s * aqk;
                        a[q][k] = s * apk + c * aqk;
                    }
                }
            }
        }
        std::array::from_fn(|i| a[i][i])
    }

    #[test]
    fn jacobi_solver_finds_known_eigenvalues() {
        // Q diag(λ) Qᵀ with Q a product of plane rotations.
        let lambda = [3.0, -1.0, 0.5, 0.0, 7.0, -2.5];
        let mut a = [[0.0; 6]; 6];
        for i in 0..6 {
            a[i][i] = lambda[i];
        }
        for (p, q, ang) in [(0, 3, 0.4), (1, 5, 1.1), (2, 4, -0.7), (0, 1, 0.3)] {
            let (s, c) = f64::sin_cos(ang);
            let mut r = [[0.0; 6]; 6];
            for i in 0..6 {
                r[i][i] = 1.0;
            }
            r[p][p] = c;
            r[q][q] = c;
            r[p][q] = -s;
            r[q][p] = s;
            let ra: [[f64; 6]; 6] = std::array::from_fn(|i| {
                std::array::from_fn(|j| (0..6).map(|k| r[i][k] * a[k][j]).sum())
            });
            a = std::array::from_fn(|i| {
                std::array::from_fn(|j| (0..6).map(|k| ra[i][k] * r[j][k]).sum())
            });
        }
        let mut got = sym_eigenvalues(a);
        let mut want = lambda;
        got.sort_by(f64::total_cmp);
        want.sort_by(f64::total_cmp);
        for k in 0..6 {
            assert!((got[k] - want[k]).abs() < 1e-12, "{got:?} vs {want:?}");
        }
    }

    /// The rest frame preserves edge lengths, the angle at corner 1 and the area.
    #[test]
    fn rest_frame_is_isometric() {
        let mut rng = Rng(11);
        for _ in 0..100 {
            let (p, rest) = random_rest(&mut rng);
            let x = rest_corners(&rest);
            let e = sub3(p[1], p[0]);
            let f = sub3(p[2], p[0]);
            let d2 = |a: [f64; 2]| a[0] * a[0] + a[1] * a[1];
            assert!((d2(x[1]) - dot3(e, e)).abs() < 1e-12);
            assert!((d2(x[2]) - dot3(f, f)).abs() < 1e-12);
            assert!((x[1][0] * x[2][0] + x[1][1] * x[2][1] - dot3(e, f)).abs() < 1e-12);
            let n = cross3(e, f);
            assert!((rest.area - 0.5 * dot3(n, n).sqrt()).abs() < 1e-14);
            assert!(x[1][0] * x[2][1] - x[2][0] * x[1][1] > 0.0, "det Dm > 0");
        }
    }

    #[test]
    fn degenerate_rest_triangles_are_rejected() {
        let o = [0.0, 0.0, 0.0];
        assert!(RestTriangle::new(o, [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]).is_none());
        assert!(RestTriangle::new(o, o, [0.0, 1.0, 0.0]).is_none());
        assert!(RestTriangle::new(o, [1.0, 0.0, 0.0], [f64::NAN, 1.0, 0.0]).is_none());
        assert!(RestTriangle::new(o, [1.0, 0.0, 0.0], [0.5, 1e-20, 0.0]).is_none());
        // Small but well-shaped triangles are fine.
        assert!(RestTriangle::new(o, [1e-6, 0.0, 0.0], [0.0, 1e-6, 0.0]).is_some());

        let pos = [o, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [2.0, 0.0, 0.0]];
        assert_eq!(rest_triangles(&pos, &[[0, 1, 2]]).unwrap().len(), 1);
        assert_eq!(
            rest_triangles(&pos, &[[0, 1, 2], [0, 1, 3], [1, 3, 0]]),
            Err(RestTriangleError::Degenerate { first: 1, count: 2 })
        );
        assert!(matches!(
            rest_triangles(&pos, &[[0, 1, 4]]),
            Err(RestTriangleError::Index(IndexError {
                triangle: 0,
                corner: 2,
                vertex: 4,
                num_vertices: 4
            }))
        ));
    }

    /// A planar CCW triangle mapped to its own (x, y) coordinates is an isometry:
    /// J is a rotation with det +1 and E = area · W(2, 1). Mirrored UVs are flipped.
    #[test]
    fn isometric_flattening_has_rotation_jacobian() {
        let p = [[0.2, 0.1, 0.0], [1.5, 0.3, 0.0], [0.4, 1.2, 0.0]];
        let rest = RestTriangle::new(p[0], p[1], p[2]).unwrap();
        let uv = [[0.2, 0.1], [1.5, 0.3], [0.4, 1.2]];
        let j = jacobian(&rest, &uv);
        let jtj = mul([[j[0][0], j[1][0]], [j[0][1], j[1][1]]], j);
        assert!((jtj[0][0] - 1.0).abs() < 1e-14 && (jtj[1][1] - 1.0).abs() < 1e-14);
        assert!(jtj[0][1].abs() < 1e-14);
        assert!((j[0][0] * j[1][1] - j[0][1] * j[1][0] - 1.0).abs() < 1e-14);
        let sd = energy(&rest, &uv, &SymmetricDirichlet);
        assert!((sd - 4.0 * rest.area).abs() < 1e-13);
        let mirrored = [[-0.2, 0.1], [-1.5, 0.3], [-0.4, 1.2]];
        assert_eq!(energy(&rest, &mirrored, &SymmetricDirichlet), f64::INFINITY);
        assert_eq!(energy(&rest, &mirrored, &Arap), f64::INFINITY);
        let (mut g, mut h) = ([1.0; 6], [[1.0; 6]; 6]);
        let e = gradient_and_projected_hessian(&rest, &mirrored, &Mips, &mut g, &mut h);
        assert_eq!(e, f64::INFINITY);
        assert_eq!(g, [0.0; 6]);
        assert_eq!(h, [[0.0; 6]; 6]);
    }

    /// The constructed UVs have the requested singular values (checks the harness and
    /// `jacobian`), and the energy is invariant to rigid motions of the UVs.
    #[test]
    fn energy_is_invariant_to_rigid_motions() {
        let mut rng = Rng(5);
        for (name, density) in densities() {
            for _ in 0..20 {
                let (_, rest) = random_rest(&mut rng);
                let (s1, s2) = (rng.range(0.3, 2.0), rng.range(0.3, 2.0));
                let uv = uv_for(&rest, s1, s2, rng.range(0.0, 6.3), rng.range(0.0, 6.3));
                let j = jacobian(&rest, &uv);
                let a = j.iter().flatten().map(|v| v * v).sum::<f64>();
                assert!((a - (s1 * s1 + s2 * s2)).abs() < 1e-12);
                let e = energy(&rest, &uv, &density);
                let want = rest.area * density.eval(s1 * s1 + s2 * s2, (s1 * s2).powi(2)).w;
                assert!((e - want).abs() <= 1e-11 * (1.0 + want.abs()), "{name}");
                let r = rot(rng.range(0.0, 6.3));
                let t = [rng.range(-5.0, 5.0), rng.range(-5.0, 5.0)];
                let moved: [[f64; 2]; 3] = std::array::from_fn(|k| {
                    [
                        r[0][0] * uv[k][0] + r[0][1] * uv[k][1] + t[0],
                        r[1][0] * uv[k][0] + r[1][1] * uv[k][1] + t[1],
                    ]
                });
                let em = energy(&rest, &moved, &density);
                assert!(
                    (em - e).abs() <= 1e-11 * (1.0 + e.abs()),
                    "{name}: {em} vs {e}"
                );
            }
        }
    }

    /// Gradient vs central differences of `energy`, for every density, at generic,
    /// near-degenerate and (nearly) conformal Jacobians.
    #[test]
    fn gradient_matches_finite_differences() {
        let mut rng = Rng(0xdeadbeef);
        for (name, density) in densities() {
            for _ in 0..10 {
                let (_, rest) = random_rest(&mut rng);
                for (s1, s2) in sigma_cases(&mut rng) {
                    let uv = uv_for(&rest, s1, s2, rng.range(0.0, 6.3), rng.range(0.0, 6.3));
                    let (mut g, mut g2, mut h) = ([0.0; 6], [0.0; 6], [[0.0; 6]; 6]);
                    let e = gradient(&rest, &uv, &density, &mut g);
                    let e2 = gradient_and_projected_hessian(&rest, &uv, &density, &mut g2, &mut h);
                    assert_eq!(e, e2);
                    assert_eq!(g, g2);
                    assert!(e.is_finite());
                    // Step relative to the smallest singular value keeps FD in the
                    // smooth region of the barrier.
                    let step = 1e-6 * s2.min(1.0);
                    let gmax = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    let mut hess = [[0.0; 6]; 6];
                    exact_hessian(&rest, &uv, &density, &mut g2, &mut hess);
                    // FD error budget: truncation ~ step²·E''' (≲ H·step/σ2 here) and
                    // rounding ~ ε·(size of the summed terms)/step; ARAP sums O(a)
                    // terms to a tiny W near the isometry.
                    let terms = e.abs() + rest.area * (1.0 + s1 * s1 + s2 * s2);
                    let tol = 1e-6 * gmax
                        + 1e-4 * max_abs6(&hess) * step / s2.min(1.0)
                        + 1e3 * f64::EPSILON * terms / step;
                    for dof in 0..6 {
                        let mut plus = uv;
                        let mut minus = uv;
                        plus[dof / 2][dof % 2] += step;
                        minus[dof / 2][dof % 2] -= step;
                        let fd = (energy(&rest, &plus, &density) - energy(&rest, &minus, &density))
                            / (2.0 * step);
                        assert!(
                            (g[dof] - fd).abs() <= tol,
                            "{name} σ = ({s1}, {s2}) dof {dof}: {} vs fd {fd}",
                            g[dof]
                        );
                    }
                }
            }
        }
    }

    /// Exact Hessian vs central differences of the gradient.
    #[test]
    fn exact_hessian_matches_finite_differences() {
        let mut rng = Rng(0xfeedface);
        for (name, density) in densities() {
            for _ in 0..6 {
                let (_, rest) = random_rest(&mut rng);
                for (s1, s2) in sigma_cases(&mut rng) {
                    let uv = uv_for(&rest, s1, s2, rng.range(0.0, 6.3), rng.range(0.0, 6.3));
                    let (mut g, mut h) = ([0.0; 6], [[0.0; 6]; 6]);
                    exact_hessian(&rest, &uv, &density, &mut g, &mut h);
                    let hmax = max_abs6(&h);
                    let step = 1e-6 * s2.min(1.0);
                    for dof in 0..6 {
                        let mut plus = uv;
                        let mut minus = uv;
                        plus[dof / 2][dof % 2] += step;
                        minus[dof / 2][dof % 2] -= step;
                        let (mut gp, mut gm) = ([0.0; 6], [0.0; 6]);
                        gradient(&rest, &plus, &density, &mut gp);
                        gradient(&rest, &minus, &density, &mut gm);
                        for r in 0..6 {
                            let fd = (gp[r] - gm[r]) / (2.0 * step);
                            assert!(
                                (h[r][dof] - fd).abs() <= 1e-5 * (hmax + 1e-8),
                                "{name} σ = ({s1}, {s2}) H[{r}][{dof}] = {} vs fd {fd}",
                                h[r][dof]
                            );
                        }
                    }
                }
            }
        }
    }

    /// Without clamping, the analytic eigensystem reassembles the exact J-space
    /// Hessian: the eigenvectors and eigenvalues are right (including σ1 = σ2).
    #[test]
    fn analytic_eigensystem_reproduces_exact_hessian() {
        let mut rng = Rng(1234);
        for (name, density) in densities() {
            for _ in 0..20 {
                let (_, rest) = random_rest(&mut rng);
                for (s1, s2) in sigma_cases(&mut rng) {
                    let uv = uv_for(&rest, s1, s2, rng.range(0.0, 6.3), rng.range(0.0, 6.3));
                    let local = Local::new(&rest, &uv, &density).unwrap();
                    let exact = local.exact_hessian_j();
                    let eig = local.eigen_hessian(false);
                    let scale = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
                    for r in 0..4 {
                        for c in 0..4 {
                            assert!(
                                (exact[r][c] - eig[r][c]).abs() <= 1e-9 * scale,
                                "{name} σ = ({s1}, {s2}) [{r}][{c}]: {} vs {}",
                                exact[r][c],
                                eig[r][c]
                            );
                        }
                    }
                }
            }
        }
    }

    /// The projected Hessian is PSD; where the exact Hessian is already PSD the two
    /// agree; the Litke isometry is such a point.
    #[test]
    fn projected_hessian_is_psd_and_exact_where_exact_is_psd() {
        let mut rng = Rng(777);
        let mut indefinite_seen = 0;
        let mut psd_seen = 0;
        for (name, density) in densities() {
            for _ in 0..30 {
                let (_, rest) = random_rest(&mut rng);
                let mut cases = sigma_cases(&mut rng);
                cases.push((rng.range(2.0, 5.0), rng.range(2.0, 5.0))); // stretched: often indefinite
                for (s1, s2) in cases {
                    let uv = uv_for(&rest, s1, s2, rng.range(0.0, 6.3), rng.range(0.0, 6.3));
                    let (mut g, mut hp, mut he) = ([0.0; 6], [[0.0; 6]; 6], [[0.0; 6]; 6]);
                    gradient_and_projected_hessian(&rest, &uv, &density, &mut g, &mut hp);
                    exact_hessian(&rest, &uv, &density, &mut g, &mut he);
                    let scale = max_abs6(&he).max(max_abs6(&hp));
                    let ep = sym_eigenvalues(hp);
                    let ee = sym_eigenvalues(he);
                    let min_p = ep.iter().cloned().fold(f64::INFINITY, f64::min);
                    let min_e = ee.iter().cloned().fold(f64::INFINITY, f64::min);
                    assert!(
                        min_p >= -1e-9 * scale,
                        "{name} σ = ({s1}, {s2}): λmin {min_p}"
                    );
                    if min_e >= -1e-12 * scale {
                        psd_seen += 1;
                        for r in 0..6 {
                            for c in 0..6 {
                                assert!(
                                    (hp[r][c] - he[r][c]).abs() <= 1e-9 * scale,
                                    "{name} σ = ({s1}, {s2}) PSD exact changed at [{r}][{c}]"
                                );
                            }
                        }
                    } else {
                        indefinite_seen += 1;
                        // Projection only removes the negative part: H⁺ − H is PSD.
                        let diff: [[f64; 6]; 6] =
                            std::array::from_fn(|r| std::array::from_fn(|c| hp[r][c] - he[r][c]));
                        let md = sym_eigenvalues(diff)
                            .iter()
                            .cloned()
                            .fold(f64::INFINITY, f64::min);
                        assert!(md >= -1e-9 * scale, "{name}: H⁺ − H has λ {md}");
                    }
                }
            }
        }
        assert!(
            indefinite_seen > 20 && psd_seen > 20,
            "{indefinite_seen} / {psd_seen}"
        );

        // Litke at the isometry: the exact Hessian is PSD, projection is the identity.
        for w in [
            Alpha::conformal(),
            Alpha::balanced(),
            Alpha::area(),
            Alpha::length(),
        ] {
            let (_, rest) = random_rest(&mut rng);
            let uv = uv_for(&rest, 1.0, 1.0, 0.4, -1.2);
            let (mut g, mut hp, mut he) = ([0.0; 6], [[0.0; 6]; 6], [[0.0; 6]; 6]);
            gradient_and_projected_hessian(&rest, &uv, &w, &mut g, &mut hp);
            let gmax = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(gmax < 1e-12, "isometry is stationary: |g| = {gmax}");
            exact_hessian(&rest, &uv, &w, &mut g, &mut he);
            let min_e = sym_eigenvalues(he)
                .iter()
                .cloned()
                .fold(f64::INFINITY, f64::min);
            assert!(min_e >= -1e-12 * max_abs6(&he));
            for r in 0..6 {
                for c in 0..6 {
                    assert!((hp[r][c] - he[r][c]).abs() <= 1e-12 * max_abs6(&he));
                }
            }
        }
    }

    /// Rotating the UV triangle by R rotates gradient and projected Hessian:
    /// g' = R g, H' = R H Rᵀ with R block-diagonal over the three corners.
    #[test]
    fn projected_hessian_rotates_with_the_uvs() {
        let mut rng = Rng(31337);
        for (name, density) in densities() {
            for _ in 0..10 {
                let (_, rest) = random_rest(&mut rng);
                for (s1, s2) in sigma_cases(&mut rng) {
                    let uv = uv_for(&rest, s1, s2, rng.range(0.0, 6.3), rng.range(0.0, 6.3));
                    let r = rot(rng.range(0.0, 6.3));
                    let rotated: [[f64; 2]; 3] = std::array::from_fn(|k| {
                        [
                            r[0][0] * uv[k][0] + r[0][1] * uv[k][1],
                            r[1][0] * uv[k][0] + r[1][1] * uv[k][1],
                        ]
                    });
                    let (mut g, mut h) = ([0.0; 6], [[0.0; 6]; 6]);
                    let (mut g2, mut h2) = ([0.0; 6], [[0.0; 6]; 6]);
                    gradient_and_projected_hessian(&rest, &uv, &density, &mut g, &mut h);
                    gradient_and_projected_hessian(&rest, &rotated, &density, &mut g2, &mut h2);
                    let rb =
                        |i: usize, j: usize| if i / 2 == j / 2 { r[i % 2][j % 2] } else { 0.0 };
                    let scale = max_abs6(&h);
                    // Natural gradient scale |H|·|uv| (g itself vanishes at a minimum).
                    let extent = uv.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
                    let gmax = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    for i in 0..6 {
                        let gi: f64 = (0..6).map(|k| rb(i, k) * g[k]).sum();
                        let tol = 1e-9 * (gmax + scale * extent);
                        assert!(
                            (g2[i] - gi).abs() <= tol,
                            "{name} g[{i}]: {} vs {gi}",
                            g2[i]
                        );
                        for j in 0..6 {
                            let hij: f64 = (0..6)
                                .flat_map(|k| (0..6).map(move |l| (k, l)))
                                .map(|(k, l)| rb(i, k) * h[k][l] * rb(j, l))
                                .sum();
                            assert!(
                                (h2[i][j] - hij).abs() <= 1e-9 * scale,
                                "{name} σ = ({s1}, {s2}) H[{i}][{j}]: {} vs {hij}",
                                h2[i][j]
                            );
                        }
                    }
                }
            }
        }
    }

    /// Rigid motions are in the kernel of the projected Hessian (translations exactly;
    /// here checked for translations, which every element Hessian must annihilate).
    #[test]
    fn translations_are_in_the_kernel() {
        let mut rng = Rng(4242);
        for (name, density) in densities() {
            let (_, rest) = random_rest(&mut rng);
            let uv = uv_for(&rest, 1.7, 0.6, 0.3, 0.9);
            let (mut g, mut h) = ([0.0; 6], [[0.0; 6]; 6]);
            gradient_and_projected_hessian(&rest, &uv, &density, &mut g, &mut h);
            let scale = max_abs6(&h);
            for comp in 0..2 {
                for r in 0..6 {
                    let v: f64 = (0..3).map(|k| h[r][2 * k + comp]).sum();
                    assert!(v.abs() <= 1e-12 * scale, "{name}: H·t ≠ 0");
                }
                let gs: f64 = (0..3).map(|k| g[2 * k + comp]).sum();
                assert!(gs.abs() <= 1e-12 * (1.0 + g.iter().map(|x| x.abs()).sum::<f64>()));
            }
        }
    }

    /// Continuity at σ1 = σ2, where the reflection direction is arbitrary.
    #[test]
    fn projected_hessian_is_continuous_at_equal_singular_values() {
        let mut rng = Rng(8);
        for (name, density) in densities() {
            let (_, rest) = random_rest(&mut rng);
            let (mut g, mut h0, mut h1) = ([0.0; 6], [[0.0; 6]; 6], [[0.0; 6]; 6]);
            let uv0 = uv_for(&rest, 3.0, 3.0, 0.7, 0.2);
            let uv1 = uv_for(&rest, 3.0, 3.0 * (1.0 - 1e-7), 0.7, 0.2);
            gradient_and_projected_hessian(&rest, &uv0, &density, &mut g, &mut h0);
            gradient_and_projected_hessian(&rest, &uv1, &density, &mut g, &mut h1);
            let scale = max_abs6(&h0);
            for r in 0..6 {
                for c in 0..6 {
                    assert!((h0[r][c] - h1[r][c]).abs() <= 1e-5 * scale, "{name}");
                }
            }
        }
    }
}
