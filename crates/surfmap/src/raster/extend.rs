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

use super::RasterError;

/// Extends `fields` (each `size²` values, read on `inside` nodes) harmonically to the
/// outside nodes, in place. Fails if no node is inside.
pub fn harmonic_extension(
    size: usize,
    inside: &[bool],
    fields: &mut [&mut [f64]],
) -> Result<(), RasterError> {
    let n = size;
    if !inside.iter().any(|&b| b) {
        return Err(RasterError::EmptyDomain);
    }
    let mut unknown = vec![u32::MAX; n * n];
    let mut outside = vec![];
    for k in 0..n * n {
        if !inside[k] {
            unknown[k] = outside.len() as u32;
            outside.push(k);
        }
    }
    if outside.is_empty() {
        return Ok(());
    }
    let m = outside.len();
    let mut triplets: Vec<(u32, u32, f64)> = Vec::with_capacity(5 * m);
    let mut rhs: Vec<Vec<f64>> = vec![vec![0.0; m]; fields.len()];
    for (row, &p) in outside.iter().enumerate() {
        let (i, j) = (p / n, p % n);
        let mut degree = 0.0;
        let mut visit = |q: usize| {
            degree += 1.0;
            if inside[q] {
                for (f, r) in fields.iter().zip(rhs.iter_mut()) {
                    r[row] += f[q];
                }
            } else {
                triplets.push((row as u32, unknown[q], -1.0));
            }
        };
        if j > 0 {
            visit(p - 1);
        }
        if j + 1 < n {
            visit(p + 1);
        }
        if i > 0 {
            visit(p - n);
        }
        if i + 1 < n {
            visit(p + n);
        }
        triplets.push((row as u32, row as u32, degree));
    }
    let mut views: Vec<&mut [f64]> = rhs.iter_mut().map(|r| r.as_mut_slice()).collect();
    solve_spd(m, &triplets, &mut views)?;
    for (f, r) in fields.iter_mut().zip(&rhs) {
        for (row, &p) in outside.iter().enumerate() {
            f[p] = r[row];
        }
    }
    Ok(())
}

/// The one call site of the sparse SPD solver (full symmetric triplets, duplicates summed;
/// each right-hand side is overwritten by its solution).
///
/// TODO(linsolve): switch to `crate::linsolve::solve_spd` once it is merged; until then a
/// Jacobi-preconditioned conjugate gradient (fine for tests, slow on 1025² grids).
#[allow(clippy::needless_range_loop)]
fn solve_spd(
    n: usize,
    triplets: &[(u32, u32, f64)],
    rhs: &mut [&mut [f64]],
) -> Result<(), RasterError> {
    // CSR with summed duplicates.
    let mut sorted: Vec<(u32, u32, f64)> = triplets.to_vec();
    sorted.sort_unstable_by_key(|t| (t.0, t.1));
    let mut start = vec![0usize; n + 1];
    let mut cols: Vec<u32> = Vec::with_capacity(sorted.len());
    let mut vals: Vec<f64> = Vec::with_capacity(sorted.len());
    if let Some(&(r, c, _)) = sorted
        .iter()
        .find(|t| t.0 as usize >= n || t.1 as usize >= n)
    {
        return Err(RasterError::Solve(format!(
            "entry ({r}, {c}) outside {n}×{n}"
        )));
    }
    let mut k = 0;
    for r in 0..n {
        start[r] = cols.len();
        while k < sorted.len() && sorted[k].0 as usize == r {
            let c = sorted[k].1;
            if cols.len() > start[r] && *cols.last().unwrap() == c {
                *vals.last_mut().unwrap() += sorted[k].2;
            } else {
                cols.push(c);
                vals.push(sorted[k].2);
            }
            k += 1;
        }
    }
    start[n] = cols.len();
    let mut diag = vec![0.0; n];
    for r in 0..n {
        for e in start[r]..start[r + 1] {
            if cols[e] as usize == r {
                diag[r] = vals[e];
            }
        }
        if diag[r] <= 0.0 {
            return Err(RasterError::Solve(format!(
                "non-positive diagonal in row {r}"
            )));
        }
    }
    let matvec = |x: &[f64], y: &mut [f64]| {
        for r in 0..n {
            let mut s = 0.0;
            for e in start[r]..start[r + 1] {
                s += vals[e] * x[cols[e] as usize];
            }
            y[r] = s;
        }
    };
    for b in rhs.iter_mut() {
        let bnorm = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        let mut x = vec![0.0; n];
        if bnorm == 0.0 {
            b.copy_from_slice(&x);
            continue;
        }
        let mut r: Vec<f64> = b.to_vec();
        let mut z: Vec<f64> = r.iter().zip(&diag).map(|(r, d)| r / d).collect();
        let mut p = z.clone();
        let mut ap = vec![0.0; n];
        let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let max_iter = 20 * n + 100;
        let mut converged = false;
        for _ in 0..max_iter {
            matvec(&p, &mut ap);
            let alpha = rz / p.iter().zip(&ap).map(|(a, b)| a * b).sum::<f64>();
            for i in 0..n {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
            }
            if r.iter().map(|v| v * v).sum::<f64>().sqrt() <= 1e-13 * bnorm {
                converged = true;
                break;
            }
            for i in 0..n {
                z[i] = r[i] / diag[i];
            }
            let rz_new: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                p[i] = z[i] + beta * p[i];
            }
        }
        if !converged {
            return Err(RasterError::Solve(
                "conjugate gradient did not converge".into(),
            ));
        }
        b.copy_from_slice(&x);
    }
    Ok(())
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
    fn empty_domain_is_an_error() {
        let mut f = vec![0.0; 9];
        assert!(matches!(
            harmonic_extension(3, &[false; 9], &mut [&mut f]),
            Err(RasterError::EmptyDomain)
        ));
    }
}
