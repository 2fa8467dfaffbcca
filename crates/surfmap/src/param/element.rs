//! Per-triangle energy, gradient and positive semi-definite Hessian (thesis §3.1.2,
//! App. A; NOTES §1).
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

use super::density::Density;
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
        let e = sub3(p2, p1);
        let f = sub3(p3, p1);
        let g = sub3(p3, p2);
        let n = cross3(e, f);
        let n_len = dot3(n, n).sqrt();
        let l_max2 = dot3(e, e).max(dot3(f, f)).max(dot3(g, g));
        if !(n_len.is_finite() && l_max2.is_finite()) || n_len <= f64::EPSILON * l_max2 {
            return None;
        }
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
    #[error(
        "triangle {triangle} refers to vertex {vertex}, but the mesh has only {num_vertices} vertices; the mesh file is inconsistent"
    )]
    VertexOutOfRange {
        triangle: usize,
        vertex: u32,
        num_vertices: usize,
    },
    #[error(
        "{count} triangle(s) have (nearly) zero area or non-finite corners, the first is triangle {first}; their distortion is undefined — remove or repair them (collapse zero-area triangles) before flattening"
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
    for (t, tri) in triangles.iter().enumerate() {
        if let Some(&v) = tri.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(RestTriangleError::VertexOutOfRange {
                triangle: t,
                vertex: v,
                num_vertices: positions.len(),
            });
        }
    }
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
/// with `∇a = 2 vec J`, `∇d = 2 det J·vec cof J`. For tests and diagnostics; the Newton
/// solver wants [`gradient_and_projected_hessian`]. On `det J ≤ 0` returns
/// `f64::INFINITY` and zeros.
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
    w: super::density::DensityDerivs,
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
        for k in 0..3 {
            for i in 0..2 {
                out[2 * k + i] = rest.area * (p[2 * i] * c[0][k] + p[2 * i + 1] * c[1][k]);
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
    // G[2i + j][(k, m)] = Σ_n HJ[2i + j][2m + n] c[n][l] for column DOF 2l + m, then
    // out[2k + i][2l + m] = area Σ_j c[j][k] G[2i + j][2l + m].
    let mut g = [[0.0; 6]; 4];
    for (row, grow) in hj.iter().zip(g.iter_mut()) {
        for l in 0..3 {
            for m in 0..2 {
                grow[2 * l + m] = row[2 * m] * c[0][l] + row[2 * m + 1] * c[1][l];
            }
        }
    }
    for k in 0..3 {
        for i in 0..2 {
            let r = 2 * k + i;
            let ck0 = rest.area * c[0][k];
            let ck1 = rest.area * c[1][k];
            for col in r..6 {
                let v = ck0 * g[2 * i][col] + ck1 * g[2 * i + 1][col];
                out[r][col] = v;
                out[col][r] = v;
            }
        }
    }
}

#[inline(always)]
fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline(always)]
fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
