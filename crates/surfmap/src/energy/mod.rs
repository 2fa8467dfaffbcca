//! Isotropic energy densities `W(a, d)` and their derivatives (thesis §2.1.5, (2.5)),
//! shared by flattening (§3.1) and by matching's regularization energy (2.7)–(2.8).
//!
//! A density measures the distortion of a symmetric positive definite 2×2 tensor `G`
//! through its two invariants
//!
//! ```text
//! a = tr G,    d = det G
//! ```
//!
//! ([`invariants`]). For flattening, `G = JᵀJ` with `J` the Jacobian of a triangle's map
//! (singular values `σ1 ≥ σ2`), so `a = σ1² + σ2²` (length) and `d = σ1²σ2²` (area;
//! `det G`, not its square root: the thesis's isometry check `W_σ = 0` at `a = 2, d = 1`
//! only holds so). For matching (2.7), `G` is the distortion tensor `g_A⁻¹ Dφᵀ (g_B∘φ) Dφ`
//! of the deformation on the grid; its regularization (2.8) is Litke's density with no
//! angle term, an [`Alpha`] with `αc = 0`.
//!
//! Every density is defined for `a > 0, d > 0` and returns its value with first and
//! second partial derivatives in `(a, d)` ([`Density::eval`]); nothing here knows about
//! triangles, so the same call serves a grid tensor. `param::element` pulls the
//! derivatives back to a triangle's UV coordinates.
//!
//! One file per density: [`litke`] (2.5) with its weights [`Alpha`],
//! [`symmetric_dirichlet`], [`mips`], [`arap`]; [`Energy`] chooses one at run time.

pub mod arap;
pub mod litke;
pub mod mips;
pub mod symmetric_dirichlet;

pub use arap::Arap;
pub use litke::{Alpha, AlphaError};
pub use mips::Mips;
pub use symmetric_dirichlet::SymmetricDirichlet;

/// Value and partial derivatives of a density `W(a, d)` at one point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DensityDerivs {
    /// `W`
    pub w: f64,
    /// `∂W/∂a`
    pub w_a: f64,
    /// `∂W/∂d`
    pub w_d: f64,
    /// `∂²W/∂a²`
    pub w_aa: f64,
    /// `∂²W/∂a∂d`
    pub w_ad: f64,
    /// `∂²W/∂d²`
    pub w_dd: f64,
}

/// An isotropic distortion density `W(a, d)` of the invariants `a = tr G`, `d = det G`
/// of a symmetric positive definite 2×2 tensor `G` (module docs).
///
/// Callers guarantee `a > 0`, `d > 0` (for a triangle: non-degenerate and positively
/// oriented); outside that set the values are meaningless.
pub trait Density: Sync {
    /// `W` and its first and second partial derivatives at `(a, d)`.
    fn eval(&self, a: f64, d: f64) -> DensityDerivs;

    /// `W(a, d)`.
    #[inline]
    fn value(&self, a: f64, d: f64) -> f64 {
        self.eval(a, d).w
    }

    /// `W(a, d)` and its gradient `[∂W/∂a, ∂W/∂d]`: what a first-order method (matching's
    /// nonlinear CG, §3.2.4) needs, by the chain rule `∂W/∂G = W_a·I + W_d·cof G`.
    #[inline]
    fn value_and_gradient(&self, a: f64, d: f64) -> (f64, [f64; 2]) {
        let e = self.eval(a, d);
        (e.w, [e.w_a, e.w_d])
    }

    /// Whether `W → ∞` as `d → 0` (the density itself keeps triangles from
    /// collapsing). For non-barrier densities (ARAP) the flip-free step cap of the
    /// line search is the only protection against flips.
    fn is_barrier(&self) -> bool {
        true
    }
}

/// The invariants `(a, d) = (tr G, det G)` of a symmetric 2×2 tensor
/// `G = [[g11, g12], [g12, g22]]` (the off-diagonal entries are averaged).
#[inline]
pub fn invariants(g: [[f64; 2]; 2]) -> (f64, f64) {
    let off = 0.5 * (g[0][1] + g[1][0]);
    (g[0][0] + g[1][1], g[0][0] * g[1][1] - off * off)
}

/// The energy a flattening minimizes: one of the densities, and for Litke's an optional
/// continuation start (thesis §3.1.3).
///
/// As a [`Density`] it is its target density (`alpha` for Litke); `from` only tells
/// [`crate::flatten`] where the continuation starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Energy {
    /// Litke's density (2.5) with weights `alpha`. With `from`, the flattening first
    /// minimizes at α = `from`, then moves to `alpha` in steps (continuation, §3.1.3).
    Litke { alpha: Alpha, from: Option<Alpha> },
    /// [`SymmetricDirichlet`].
    SymmetricDirichlet,
    /// [`Mips`] (scale-free: the result is scaled to the surface's area).
    Mips,
    /// [`Arap`] (not a barrier).
    Arap,
}

impl Energy {
    /// Litke's density at `alpha`, no continuation.
    pub fn litke(alpha: Alpha) -> Self {
        Energy::Litke { alpha, from: None }
    }

    /// Litke's density at `alpha`, reached by continuation from `from`.
    pub fn litke_from(from: Alpha, alpha: Alpha) -> Self {
        Energy::Litke {
            alpha,
            from: Some(from),
        }
    }

    /// This energy, reached by continuation from α = `from` (§3.1.3). Continuation
    /// blends Litke's weights, so the energy must be [`Energy::Litke`].
    pub fn with_continuation(self, from: Alpha) -> Result<Self, ContinuationNeedsLitke> {
        match self {
            Energy::Litke { alpha, .. } => Ok(Energy::litke_from(from, alpha)),
            other => Err(ContinuationNeedsLitke(other.name())),
        }
    }

    /// A short name: `litke`, `symmetric Dirichlet`, `MIPS` or `ARAP`.
    pub fn name(&self) -> &'static str {
        match self {
            Energy::Litke { .. } => "litke",
            Energy::SymmetricDirichlet => "symmetric Dirichlet",
            Energy::Mips => "MIPS",
            Energy::Arap => "ARAP",
        }
    }

    /// The continuation start, when there is one.
    pub fn continuation_start(&self) -> Option<Alpha> {
        match self {
            Energy::Litke { from, .. } => *from,
            _ => None,
        }
    }

    /// The same energy without continuation.
    pub fn without_continuation(&self) -> Self {
        match *self {
            Energy::Litke { alpha, .. } => Energy::litke(alpha),
            other => other,
        }
    }
}

/// Continuation (§3.1.3) was asked of an energy other than Litke's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "continuation blends Litke's α weights; it needs the Litke energy (`Energy::Litke`) as the target, not {0}"
)]
pub struct ContinuationNeedsLitke(pub &'static str);

impl Default for Energy {
    /// Litke's density with balanced weights ([`Alpha::balanced`]), no continuation.
    fn default() -> Self {
        Energy::litke(Alpha::balanced())
    }
}

impl From<Alpha> for Energy {
    fn from(alpha: Alpha) -> Self {
        Energy::litke(alpha)
    }
}

impl Density for Energy {
    #[inline]
    fn eval(&self, a: f64, d: f64) -> DensityDerivs {
        match self {
            Energy::Litke { alpha, .. } => alpha.eval(a, d),
            Energy::SymmetricDirichlet => SymmetricDirichlet.eval(a, d),
            Energy::Mips => Mips.eval(a, d),
            Energy::Arap => Arap.eval(a, d),
        }
    }

    fn is_barrier(&self) -> bool {
        !matches!(self, Energy::Arap)
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // matrix indices read best as indices
mod tests {
    use super::*;

    use crate::testing::Rng;

    use crate::testing::all_energies as all_densities;

    fn assert_close(got: f64, want: f64, rel: f64, what: &str) {
        let tol = rel * (1.0 + want.abs().max(got.abs()));
        assert!(
            (got - want).abs() <= tol,
            "{what}: got {got}, want {want} (tol {tol})"
        );
    }

    /// `got` against the central difference `fd = (f(x + h) − f(x − h)) / 2h` of a
    /// function of size `f`: relative tolerance `rel`, plus the rounding error of the
    /// difference itself, a few `ε·|f|/h` (it dominates where `W` is huge, near `d = 0`).
    fn assert_fd(got: f64, fd: f64, f: f64, h: f64, rel: f64, what: &str) {
        let rounding = 4.0 * f64::EPSILON * f.abs() / h;
        let tol = rel * (1.0 + fd.abs().max(got.abs())) + rounding;
        assert!(
            (got - fd).abs() <= tol,
            "{what}: got {got}, finite difference {fd} (tol {tol})"
        );
    }

    /// First and second derivatives in (a, d) against central differences of `w`
    /// and of the first derivatives, at random singular values.
    #[test]
    fn derivatives_match_finite_differences() {
        let mut rng = Rng(0x9e3779b97f4a7c15);
        for (name, density) in all_densities() {
            for _ in 0..200 {
                let s1 = rng.range(0.2, 3.0);
                let s2 = s1 * rng.range(0.05, 1.0);
                let (a, d) = (s1 * s1 + s2 * s2, s1 * s1 * s2 * s2);
                let f = density.eval(a, d);
                let ha = 1e-6 * a;
                let hd = 1e-6 * d;
                let (pa, ma) = (density.eval(a + ha, d), density.eval(a - ha, d));
                let (pd, md) = (density.eval(a, d + hd), density.eval(a, d - hd));
                let tag = format!("{name} at σ = ({s1}, {s2})");
                assert_fd(
                    f.w_a,
                    (pa.w - ma.w) / (2.0 * ha),
                    f.w,
                    ha,
                    1e-6,
                    &format!("W_a {tag}"),
                );
                assert_fd(
                    f.w_d,
                    (pd.w - md.w) / (2.0 * hd),
                    f.w,
                    hd,
                    1e-6,
                    &format!("W_d {tag}"),
                );
                let scale_a = f.w_aa.abs() + (f.w_a.abs() / a);
                let scale_d = f.w_dd.abs() + (f.w_d.abs() / d);
                let fd_aa = (pa.w_a - ma.w_a) / (2.0 * ha);
                let fd_dd = (pd.w_d - md.w_d) / (2.0 * hd);
                let fd_ad = (pd.w_a - md.w_a) / (2.0 * hd);
                let fd_da = (pa.w_d - ma.w_d) / (2.0 * ha);
                assert!(
                    (f.w_aa - fd_aa).abs() <= 1e-6 * (1.0 + scale_a),
                    "W_aa {tag}"
                );
                assert!(
                    (f.w_dd - fd_dd).abs() <= 1e-6 * (1.0 + scale_d),
                    "W_dd {tag}"
                );
                let scale_ad = f.w_ad.abs() + f.w_a.abs() / d + f.w_d.abs() / a;
                assert!(
                    (f.w_ad - fd_ad).abs() <= 1e-6 * (1.0 + scale_ad),
                    "W_ad {tag}"
                );
                assert!(
                    (f.w_ad - fd_da).abs() <= 1e-6 * (1.0 + scale_ad),
                    "W_da {tag}"
                );
            }
        }
    }

    /// Each density against its definition in singular values.
    #[test]
    fn values_match_singular_value_definitions() {
        let mut rng = Rng(42);
        for _ in 0..100 {
            let (s1, s2) = (rng.range(0.1, 4.0), rng.range(0.1, 4.0));
            let (a, d) = (s1 * s1 + s2 * s2, s1 * s1 * s2 * s2);
            let sd = s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2);
            assert_close(SymmetricDirichlet.eval(a, d).w, sd, 1e-12, "SD");
            assert_close(Mips.eval(a, d).w, s1 / s2 + s2 / s1, 1e-12, "MIPS");
            let arap = (s1 - 1.0).powi(2) + (s2 - 1.0).powi(2);
            assert!((Arap.eval(a, d).w - arap).abs() < 1e-12 * (1.0 + a), "ARAP");
            let [l, ar, c] = Alpha::balanced().alphas();
            let litke = l * a
                + ar * (s1 * s1 * s2 * s2 + (l / ar + 1.0) / (s1 * s1 * s2 * s2))
                + c * (s1 / s2 - s2 / s1).powi(2);
            assert_close(Alpha::balanced().eval(a, d).w, litke, 1e-12, "Litke");
        }
    }

    #[test]
    fn isometry_values() {
        assert_eq!(SymmetricDirichlet.eval(2.0, 1.0).w, 4.0);
        assert_eq!(Mips.eval(2.0, 1.0).w, 2.0);
        assert_eq!(Arap.eval(2.0, 1.0).w, 0.0);
        // Litke at the isometry: αl·2 + αa·(1 + αl/αa + 1) + 0 = 3αl + 2αa.
        let w = Alpha::balanced();
        let [l, a, _] = w.alphas();
        assert!((w.eval(2.0, 1.0).w - (3.0 * l + 2.0 * a)).abs() < 1e-15);
    }

    /// `invariants(JᵀJ)` are `‖J‖²_F` and `det(J)²` (what the triangle code computes
    /// from `J` directly), and `∂W/∂G = W_a·I + W_d·cof G` (the chain rule quoted by
    /// [`Density::value_and_gradient`]) against central differences in the entries of G.
    #[test]
    fn tensor_invariants_and_the_tensor_gradient() {
        let mut rng = Rng(5);
        for (name, density) in all_densities() {
            for _ in 0..50 {
                // J = R(θ)·diag(σ1, σ2) with σ in [0.3, 2]: moderate distortion.
                let (s1, s2, th) = (
                    rng.range(0.3, 2.0),
                    rng.range(0.3, 2.0),
                    rng.range(0.0, 6.3),
                );
                let (co, si) = (th.cos(), th.sin());
                let j = [[co * s1, -si * s2], [si * s1, co * s2]];
                let g = [
                    [
                        j[0][0] * j[0][0] + j[1][0] * j[1][0],
                        j[0][0] * j[0][1] + j[1][0] * j[1][1],
                    ],
                    [
                        j[0][0] * j[0][1] + j[1][0] * j[1][1],
                        j[0][1] * j[0][1] + j[1][1] * j[1][1],
                    ],
                ];
                let (a, d) = invariants(g);
                let frob = j.iter().flatten().map(|x| x * x).sum::<f64>();
                let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
                assert_close(a, frob, 1e-14, "a");
                assert_close(d, det * det, 1e-12, "d");
                let (_, [w_a, w_d]) = density.value_and_gradient(a, d);
                // cof G = [[g22, −g12], [−g12, g11]]; perturb G symmetrically per entry.
                let analytic = [w_a + w_d * g[1][1], -w_d * g[0][1], w_a + w_d * g[0][0]];
                let w_at = |g: [[f64; 2]; 2]| {
                    let (a, d) = invariants(g);
                    density.value(a, d)
                };
                let h = 1e-6;
                for (k, (r, c)) in [(0usize, 0usize), (0, 1), (1, 1)].into_iter().enumerate() {
                    let (mut gp, mut gm) = (g, g);
                    gp[r][c] += h;
                    gm[r][c] -= h;
                    if r != c {
                        gp[c][r] += h;
                        gm[c][r] -= h;
                    }
                    // A symmetric off-diagonal perturbation moves two entries.
                    let fd = (w_at(gp) - w_at(gm)) / (2.0 * h) / if r != c { 2.0 } else { 1.0 };
                    let what = format!("{name}: ∂W/∂G[{r}][{c}]");
                    assert_fd(analytic[k], fd, w_at(g), h, 1e-6, &what);
                }
            }
        }
    }

    #[test]
    fn continuation_needs_the_litke_energy() {
        let from = Alpha::conformal();
        assert_eq!(
            Energy::litke(Alpha::length()).with_continuation(from),
            Ok(Energy::litke_from(from, Alpha::length()))
        );
        let err = Energy::SymmetricDirichlet
            .with_continuation(from)
            .unwrap_err();
        assert!(err.to_string().contains("symmetric Dirichlet"), "{err}");
        assert_eq!(
            Energy::litke_from(from, Alpha::length()).continuation_start(),
            Some(from)
        );
        assert_eq!(
            Energy::litke_from(from, Alpha::length()).without_continuation(),
            Energy::litke(Alpha::length())
        );
        assert_eq!(Energy::default(), Energy::litke(Alpha::balanced()));
    }
}
