//! Harmonic extension of surface quantities outside the domain (thesis §2.2.5): on the
//! nodes of ω ∖ ω_A solve the discrete Laplace equation (5-point stencil, grid spacing
//! `h`) with the values on ω_A as Dirichlet data and natural (zero-flux) boundary
//! conditions on ∂ω — the stencil simply omits neighbours beyond the grid's edge:
//!
//! `Σ_{q ~ p} (u_p − u_q) = 0` for every outside node `p`.
//!
//! The discrete maximum principle makes each extended value a convex combination of
//! Dirichlet values with weights that do not depend on the field, so the component-wise
//! extension of `g = [g11, g12, g22]` stays symmetric positive definite (a convex
//! combination of SPD matrices is SPD).

use rayon::prelude::*;

use super::RasterError;
use crate::linsolve::SpdSystem;

/// The factorized Laplace system of one grid size and inside mask: build it once with
/// [`HarmonicExtension::new`] (pattern, symbolic and numeric Cholesky), then extend any
/// number of fields with [`HarmonicExtension::apply`] (two triangular solves each).
///
/// Unknowns are the outside nodes; row `p` is `deg(p) u_p − Σ_{q~p, q outside} u_q =
/// Σ_{q~p, q inside} f_q`, with `deg(p)` the number of grid neighbours of `p` (natural
/// boundary conditions on ∂ω). Every connected outside region touches an inside node,
/// so the matrix is an irreducibly diagonally dominant M-matrix: symmetric positive definite.
#[derive(Debug)]
pub struct HarmonicExtension {
    size: usize,
    /// Grid index of every unknown.
    outside: Vec<u32>,
    /// For every unknown, its up-to-4 inside neighbours (grid indices; `u32::MAX` = none).
    inside_neighbours: Vec<[u32; 4]>,
    system: Option<SpdSystem>,
}

impl HarmonicExtension {
    /// Assembles and factorizes the Laplacian on the outside nodes of `inside`
    /// (`size²` flags). Fails if no node is inside.
    pub fn new(size: usize, inside: &[bool]) -> Result<Self, RasterError> {
        let n = size;
        if inside.len() != n * n {
            return Err(RasterError::BadOption(format!(
                "inside mask has {} entries for a {n}×{n} grid",
                inside.len()
            )));
        }
        if !inside.iter().any(|&b| b) {
            return Err(RasterError::EmptyDomain);
        }
        let mut unknown = vec![u32::MAX; n * n];
        let mut outside = vec![];
        for k in 0..n * n {
            if !inside[k] {
                unknown[k] = outside.len() as u32;
                outside.push(k as u32);
            }
        }
        let m = outside.len();
        if m == 0 {
            return Ok(Self {
                size,
                outside,
                inside_neighbours: vec![],
                system: None,
            });
        }
        // Each off-diagonal pair once (to the right and downwards), plus the diagonal.
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(3 * m);
        let mut off: Vec<usize> = Vec::with_capacity(2 * m);
        let mut degree = vec![0.0; m];
        let mut inside_neighbours = vec![[u32::MAX; 4]; m];
        for (row, &p) in outside.iter().enumerate() {
            let p = p as usize;
            let (i, j) = (p / n, p % n);
            let mut slot = 0;
            for (ok, q) in [
                (j > 0, p.wrapping_sub(1)),
                (j + 1 < n, p + 1),
                (i > 0, p.wrapping_sub(n)),
                (i + 1 < n, p + n),
            ] {
                if !ok {
                    continue;
                }
                degree[row] += 1.0;
                if inside[q] {
                    inside_neighbours[row][slot] = q as u32;
                    slot += 1;
                } else if q > p {
                    off.push(pairs.len());
                    pairs.push((row as u32, unknown[q]));
                }
            }
            pairs.push((row as u32, row as u32));
        }
        let (mut system, slots) = SpdSystem::new(m, &pairs).map_err(solve_error)?;
        let values = system.values_mut();
        values.fill(0.0);
        let mut next_off = off.iter().peekable();
        let mut row = 0usize;
        for (k, &(r, c)) in pairs.iter().enumerate() {
            if next_off.peek() == Some(&&k) {
                next_off.next();
                values[slots[k] as usize] += -1.0;
            } else {
                debug_assert_eq!(r, c);
                values[slots[k] as usize] += degree[row];
                row += 1;
            }
        }
        system.factorize_unshifted().map_err(solve_error)?;
        Ok(Self {
            size,
            outside,
            inside_neighbours,
            system: Some(system),
        })
    }

    /// Number of unknowns (outside nodes).
    pub fn num_unknowns(&self) -> usize {
        self.outside.len()
    }

    /// Overwrites the outside nodes of every field (each `size²` values, read on the
    /// inside nodes) with the harmonic extension of its inside values.
    pub fn apply(&self, fields: &mut [&mut [f64]]) -> Result<(), RasterError> {
        let n = self.size;
        if let Some(f) = fields.iter().find(|f| f.len() != n * n) {
            return Err(RasterError::BadOption(format!(
                "field has {} values for a {n}×{n} grid",
                f.len()
            )));
        }
        let Some(system) = &self.system else {
            return Ok(());
        };
        // The fields are independent right-hand sides of one factorization: solve them in parallel.
        fields.par_iter_mut().try_for_each(|f| {
            let mut rhs: Vec<f64> = self
                .inside_neighbours
                .iter()
                .map(|nb| {
                    nb.iter()
                        .take_while(|&&q| q != u32::MAX)
                        .map(|&q| f[q as usize])
                        .sum()
                })
                .collect();
            if let Some((k, _)) = rhs.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(RasterError::Solve(format!(
                    "a value next to outside node {} is not finite",
                    self.outside[k]
                )));
            }
            system.solve_in_place(&mut rhs).map_err(solve_error)?;
            for (&p, &v) in self.outside.iter().zip(&rhs) {
                f[p as usize] = v;
            }
            Ok(())
        })
    }
}

fn solve_error(e: crate::linsolve::SolveError) -> RasterError {
    RasterError::Solve(e.to_string())
}

/// Extends `fields` (each `size²` values, read on `inside` nodes) harmonically to the
/// outside nodes, in place: one factorization, one pair of triangular solves per field.
/// Fails if no node is inside.
pub fn harmonic_extension(
    size: usize,
    inside: &[bool],
    fields: &mut [&mut [f64]],
) -> Result<(), RasterError> {
    HarmonicExtension::new(size, inside)?.apply(fields)
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    fn disc_mask(n: usize) -> Vec<bool> {
        (0..n * n)
            .map(|k| {
                let (x, y) = (
                    (k % n) as f64 / (n - 1) as f64,
                    (k / n) as f64 / (n - 1) as f64,
                );
                (x - 0.45).powi(2) + (y - 0.55).powi(2) < 0.09
            })
            .collect()
    }

    #[test]
    fn extension_is_discretely_harmonic_and_keeps_inside_values() {
        let n = 33;
        let inside = disc_mask(n);
        let f0: Vec<f64> = (0..n * n)
            .map(|k| {
                if inside[k] {
                    ((k % n) as f64 * 0.3).sin() + (k / n) as f64 * 0.1
                } else {
                    7.0
                }
            })
            .collect();
        let mut f = f0.clone();
        harmonic_extension(n, &inside, &mut [&mut f]).unwrap();
        let mut max_res = 0.0f64;
        for p in 0..n * n {
            if inside[p] {
                assert_eq!(f[p], f0[p]);
                continue;
            }
            let (i, j) = (p / n, p % n);
            let mut res = 0.0;
            for (ok, q) in [
                (j > 0, p.wrapping_sub(1)),
                (j + 1 < n, p + 1),
                (i > 0, p.wrapping_sub(n)),
                (i + 1 < n, p + n),
            ] {
                if ok {
                    res += f[p] - f[q];
                }
            }
            max_res = max_res.max(res.abs());
        }
        assert!(max_res < 1e-10, "residual {max_res}");
        // Maximum principle: extended values within the range of the inside values.
        let (lo, hi) = (0..n * n)
            .filter(|&k| inside[k])
            .fold((f64::MAX, f64::MIN), |(a, b), k| {
                (a.min(f0[k]), b.max(f0[k]))
            });
        assert!(f.iter().all(|&v| v >= lo - 1e-12 && v <= hi + 1e-12));
    }

    #[test]
    fn band_data_extends_as_constants_under_natural_conditions() {
        // Inside = the band of columns 10..=20, data a(x) = x². Outside, the solution with
        // Dirichlet data a(10) (left) or a(20) (right) and zero flux elsewhere is constant.
        let n = 33;
        let inside: Vec<bool> = (0..n * n).map(|k| (10..=20).contains(&(k % n))).collect();
        let a = |k: usize| ((k % n) as f64).powi(2);
        let mut f: Vec<f64> = (0..n * n)
            .map(|k| if inside[k] { a(k) } else { -5.0 })
            .collect();
        harmonic_extension(n, &inside, &mut [&mut f]).unwrap();
        for k in 0..n * n {
            let exact = a(k).clamp(100.0, 400.0);
            assert!((f[k] - exact).abs() < 1e-9, "{k}: {} vs {exact}", f[k]);
        }
    }

    #[test]
    fn extended_metric_stays_positive_definite() {
        let n = 33;
        let inside = disc_mask(n);
        // Strongly varying SPD metric inside.
        let mut g11 = vec![0.0; n * n];
        let mut g12 = vec![0.0; n * n];
        let mut g22 = vec![0.0; n * n];
        for k in 0..n * n {
            let a = (k % 7) as f64;
            let (s, c) = (a.sin(), a.cos());
            let (l1, l2) = (1.0 + 10.0 * ((k / 5) % 3) as f64, 0.01);
            g11[k] = l1 * c * c + l2 * s * s;
            g12[k] = (l1 - l2) * c * s;
            g22[k] = l1 * s * s + l2 * c * c;
        }
        harmonic_extension(n, &inside, &mut [&mut g11, &mut g12, &mut g22]).unwrap();
        for k in 0..n * n {
            assert!(
                g11[k] > 0.0 && g11[k] * g22[k] - g12[k] * g12[k] > 0.0,
                "node {k}"
            );
        }
    }

    #[test]
    fn one_factorization_serves_many_fields() {
        // Fields extended together through one HarmonicExtension equal fields extended one
        // at a time, and extension is linear: ext(a f + b g) = a ext(f) + b ext(g).
        let n = 17;
        let inside = disc_mask(n);
        let f: Vec<f64> = (0..n * n).map(|k| (k % n) as f64 * 0.1).collect();
        let g: Vec<f64> = (0..n * n).map(|k| ((k / n) as f64).sqrt()).collect();
        let ext = HarmonicExtension::new(n, &inside).unwrap();
        assert_eq!(ext.num_unknowns(), inside.iter().filter(|&&b| !b).count());
        let (mut f1, mut g1) = (f.clone(), g.clone());
        let mut mix: Vec<f64> = f.iter().zip(&g).map(|(a, b)| 2.0 * a - 3.0 * b).collect();
        ext.apply(&mut [&mut f1, &mut g1, &mut mix]).unwrap();
        let mut f2 = f.clone();
        harmonic_extension(n, &inside, &mut [&mut f2]).unwrap();
        for k in 0..n * n {
            assert!((f1[k] - f2[k]).abs() < 1e-12);
            assert!((mix[k] - (2.0 * f1[k] - 3.0 * g1[k])).abs() < 1e-10);
        }
        let mut short = vec![0.0; 5];
        assert!(ext.apply(&mut [&mut short]).is_err());
    }

    #[test]
    fn empty_domain_is_an_error() {
        let mut f = vec![0.0; 9];
        assert!(matches!(
            harmonic_extension(3, &[false; 9], &mut [&mut f]),
            Err(RasterError::EmptyDomain)
        ));
    }
}
