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
//!
//! Fields are `Grid<f64>` or `Grid<[f64; D]>` ([`Vector`]); every component is one
//! right-hand side of the same factorization.

use rayon::prelude::*;

use super::GridError;
use super::grid::Grid;
use super::value::Vector;
use crate::linsolve::SpdSystem;

/// The factorized Laplace system of one inside mask: build it once with
/// [`HarmonicExtension::new`] (pattern, symbolic and numeric Cholesky), then extend any
/// number of fields with [`HarmonicExtension::apply`] (two triangular solves per component).
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
    /// Assembles and factorizes the Laplacian on the outside nodes of `inside`. Fails if
    /// no node is inside.
    pub fn new(inside: &Grid<bool>) -> Result<Self, GridError> {
        let n = inside.size();
        let size = n;
        let inside = inside.as_slice();
        if !inside.iter().any(|&b| b) {
            return Err(GridError::EmptyMask);
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

    /// Overwrites the outside nodes of every field (read on the inside nodes) with the
    /// harmonic extension of its inside values, component by component. Every field must
    /// have the mask's size and finite values next to the outside nodes.
    pub fn apply<T: Vector>(&self, fields: &mut [&mut Grid<T>]) -> Result<(), GridError> {
        let n = self.size;
        if let Some(f) = fields.iter().find(|f| f.size() != n) {
            return Err(GridError::SizeMismatch {
                what: "the field to extend",
                got: f.size(),
                want: n,
            });
        }
        let Some(system) = &self.system else {
            return Ok(());
        };
        // Every component of every field is an independent right-hand side of one
        // factorization: solve them in parallel, then write them back.
        let jobs: Vec<(usize, usize)> = (0..fields.len())
            .flat_map(|f| (0..T::DIM).map(move |c| (f, c)))
            .collect();
        let solutions = {
            let fields: Vec<&[T]> = fields.iter().map(|f| f.as_slice()).collect();
            jobs.par_iter()
                .map(|&(f, c)| {
                    let f = fields[f];
                    let mut rhs: Vec<f64> = self
                        .inside_neighbours
                        .iter()
                        .map(|nb| {
                            nb.iter()
                                .take_while(|&&q| q != u32::MAX)
                                .map(|&q| f[q as usize].components()[c])
                                .sum()
                        })
                        .collect();
                    if let Some((k, _)) = rhs.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                        return Err(GridError::Solve(format!(
                            "a value next to outside node {} is not finite",
                            self.outside[k]
                        )));
                    }
                    system.solve_in_place(&mut rhs).map_err(solve_error)?;
                    Ok(rhs)
                })
                .collect::<Result<Vec<_>, GridError>>()?
        };
        for (&(f, c), u) in jobs.iter().zip(&solutions) {
            let values = fields[f].as_mut_slice();
            for (&p, &v) in self.outside.iter().zip(u) {
                values[p as usize].components_mut()[c] = v;
            }
        }
        Ok(())
    }
}

fn solve_error(e: crate::linsolve::SolveError) -> GridError {
    GridError::Solve(e.to_string())
}

/// Extends `fields` (read on the `inside` nodes) harmonically to the outside nodes, in
/// place: one factorization, one pair of triangular solves per field component. Fails if
/// no node is inside.
pub fn harmonic_extension<T: Vector>(
    inside: &Grid<bool>,
    fields: &mut [&mut Grid<T>],
) -> Result<(), GridError> {
    HarmonicExtension::new(inside)?.apply(fields)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc_mask(n: usize) -> Grid<bool> {
        let s = (n - 1) as f64;
        Grid::from_fn(n, |i, j| {
            let (x, y) = (j as f64 / s, i as f64 / s);
            (x - 0.45).powi(2) + (y - 0.55).powi(2) < 0.09
        })
        .unwrap()
    }

    #[test]
    fn extension_is_discretely_harmonic_and_keeps_inside_values() {
        let n = 33;
        let inside = disc_mask(n);
        let f0 = Grid::from_fn(n, |i, j| {
            if inside[(i, j)] {
                (j as f64 * 0.3).sin() + i as f64 * 0.1
            } else {
                7.0
            }
        })
        .unwrap();
        let mut f = f0.clone();
        harmonic_extension(&inside, &mut [&mut f]).unwrap();
        let mut max_res = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                if inside[(i, j)] {
                    assert_eq!(f[(i, j)], f0[(i, j)]);
                    continue;
                }
                // Σ over the existing grid neighbours of (f_p − f_q).
                let mut res = 0.0;
                for (di, dj) in [(0, -1), (0, 1), (-1, 0), (1, 0)] {
                    let (a, b) = (i as i64 + di, j as i64 + dj);
                    if let Some(&q) = f.get(a as usize, b as usize) {
                        res += f[(i, j)] - q;
                    }
                }
                max_res = max_res.max(res.abs());
            }
        }
        assert!(max_res < 1e-10, "residual {max_res}");
        // Maximum principle: extended values within the range of the inside values.
        let (lo, hi) = f0
            .iter()
            .zip(inside.iter())
            .filter(|(_, b)| **b)
            .fold((f64::MAX, f64::MIN), |(a, b), (&v, _)| (a.min(v), b.max(v)));
        assert!(f.iter().all(|&v| v >= lo - 1e-12 && v <= hi + 1e-12));
    }

    #[test]
    fn band_data_extends_as_constants_under_natural_conditions() {
        // Inside = the band of columns 10..=20, data a(x) = x². Outside, the solution with
        // Dirichlet data a(10) (left) or a(20) (right) and zero flux elsewhere is constant.
        let n = 33;
        let inside = Grid::from_fn(n, |_, j| (10..=20).contains(&j)).unwrap();
        let a = |j: usize| (j as f64).powi(2);
        let mut f = Grid::from_fn(n, |i, j| if inside[(i, j)] { a(j) } else { -5.0 }).unwrap();
        harmonic_extension(&inside, &mut [&mut f]).unwrap();
        for i in 0..n {
            for j in 0..n {
                let exact = a(j).clamp(100.0, 400.0);
                assert!(
                    (f[(i, j)] - exact).abs() < 1e-9,
                    "{i},{j}: {} vs {exact}",
                    f[(i, j)]
                );
            }
        }
    }

    #[test]
    fn extended_metric_stays_positive_definite() {
        let n = 33;
        let inside = disc_mask(n);
        // Strongly varying SPD metric inside.
        let mut g = Grid::from_fn(n, |i, j| {
            let k = i * n + j;
            let a = (k % 7) as f64;
            let (s, c) = (a.sin(), a.cos());
            let (l1, l2) = (1.0 + 10.0 * ((k / 5) % 3) as f64, 0.01);
            [
                l1 * c * c + l2 * s * s,
                (l1 - l2) * c * s,
                l1 * s * s + l2 * c * c,
            ]
        })
        .unwrap();
        harmonic_extension(&inside, &mut [&mut g]).unwrap();
        for (k, m) in g.iter().enumerate() {
            assert!(m[0] > 0.0 && m[0] * m[2] - m[1] * m[1] > 0.0, "node {k}");
        }
    }

    #[test]
    fn one_factorization_serves_many_fields_and_components() {
        // Fields extended together through one HarmonicExtension equal fields extended one
        // at a time, a vector field equals its components extended as scalars (bit for
        // bit), and extension is linear: ext(a f + b g) = a ext(f) + b ext(g).
        let n = 17;
        let inside = disc_mask(n);
        let f = Grid::from_fn(n, |_, j| j as f64 * 0.1).unwrap();
        let g = Grid::from_fn(n, |i, _| (i as f64).sqrt()).unwrap();
        let ext = HarmonicExtension::new(&inside).unwrap();
        assert_eq!(ext.num_unknowns(), inside.iter().filter(|&&b| !b).count());
        let (mut f1, mut g1) = (f.clone(), g.clone());
        let mut mix = Grid::from_fn(n, |i, j| 2.0 * f[(i, j)] - 3.0 * g[(i, j)]).unwrap();
        ext.apply(&mut [&mut f1, &mut g1, &mut mix]).unwrap();
        let mut f2 = f.clone();
        harmonic_extension(&inside, &mut [&mut f2]).unwrap();
        let mut fg = Grid::from_fn(n, |i, j| [f[(i, j)], g[(i, j)]]).unwrap();
        ext.apply(&mut [&mut fg]).unwrap();
        for k in 0..n * n {
            let (f1, g1, mix) = (f1.as_slice()[k], g1.as_slice()[k], mix.as_slice()[k]);
            assert!((f1 - f2.as_slice()[k]).abs() < 1e-12);
            assert!((mix - (2.0 * f1 - 3.0 * g1)).abs() < 1e-10);
            assert_eq!(fg.as_slice()[k], [f1, g1]);
        }
        let mut small = Grid::new(9, 0.0).unwrap();
        assert!(matches!(
            ext.apply(&mut [&mut small]),
            Err(GridError::SizeMismatch {
                got: 9,
                want: 17,
                ..
            })
        ));
        let mut bad = f.clone();
        bad.as_mut_slice().iter_mut().for_each(|v| *v = f64::NAN);
        assert!(matches!(
            ext.apply(&mut [&mut bad]),
            Err(GridError::Solve(_))
        ));
    }

    #[test]
    fn empty_and_full_masks() {
        let mut f = Grid::new(3, 0.0).unwrap();
        assert_eq!(
            harmonic_extension(&Grid::new(3, false).unwrap(), &mut [&mut f]).unwrap_err(),
            GridError::EmptyMask
        );
        // Nothing outside: nothing to do.
        let mut g = Grid::from_fn(3, |i, j| (i * j) as f64).unwrap();
        let before = g.clone();
        harmonic_extension(&Grid::new(3, true).unwrap(), &mut [&mut g]).unwrap();
        assert_eq!(g, before);
    }
}
