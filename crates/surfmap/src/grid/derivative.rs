//! Finite-difference derivatives at the nodes of a grid (spacing `h = 1/(N − 1)`).
//!
//! * [`gradient`]: `(∂f/∂ξ₀, ∂f/∂ξ₁)` by central differences `(f_{m+1} − f_{m−1}) / 2h`
//!   inside and the second-order one-sided differences `∓(3f_m − 4f_{m±1} + f_{m±2}) / 2h`
//!   on the border nodes, so the result is exact for quadratics everywhere (the `2 × 2` grid
//!   has only `(f₁ − f₀)/h`).
//! * [`laplacian`]: the 5-point stencil `(f_W + f_E + f_S + f_N − 4f) / h²` with natural
//!   (zero-flux) boundary conditions: a neighbour beyond the border is its mirror image
//!   (`f_{−1} = f_1`, `f_N = f_{N−2}`), as in the pyramid's Gaussian filter. Exact for
//!   quadratics inside; the Neumann eigenfunctions `cos(aπξ₀) cos(bπξ₁)` are exact
//!   eigenvectors, border included.
//!
//! Both act component-wise on vector grids. Cost `O(N²)`, one pass, one allocation (the result).

use super::grid::Grid;
use super::value::Vector;

/// `[∂f/∂ξ₀, ∂f/∂ξ₁]` at every node (see the module docs for the stencils).
pub fn gradient<T: Vector>(f: &Grid<T>) -> Grid<[T; 2]> {
    let n = f.size();
    let inv_h = (n - 1) as f64;
    let data = f.as_slice();
    let out = (0..n * n)
        .map(|k| {
            let (i, j) = (k / n, k % n);
            [
                difference(|m| data[i * n + m], j, n, inv_h),
                difference(|m| data[m * n + j], i, n, inv_h),
            ]
        })
        .collect();
    Grid::from_parts(n, out)
}

/// Derivative along one grid line `f(0..n)` at position `m`.
#[inline(always)]
fn difference<T: Vector>(f: impl Fn(usize) -> T, m: usize, n: usize, inv_h: f64) -> T {
    if n == 2 {
        f(1).sub(f(0)).scale(inv_h)
    } else if m == 0 {
        // (−3f₀ + 4f₁ − f₂) / 2h = (4(f₁ − f₀) − (f₂ − f₀)) / 2h
        f(1).sub(f(0))
            .scale(4.0)
            .sub(f(2).sub(f(0)))
            .scale(0.5 * inv_h)
    } else if m == n - 1 {
        // (3f_m − 4f_{m−1} + f_{m−2}) / 2h = (4(f_m − f_{m−1}) − (f_m − f_{m−2})) / 2h
        f(m).sub(f(m - 1))
            .scale(4.0)
            .sub(f(m).sub(f(m - 2)))
            .scale(0.5 * inv_h)
    } else {
        f(m + 1).sub(f(m - 1)).scale(0.5 * inv_h)
    }
}

/// The 5-point Laplacian `Δ_h f` at every node, natural (mirror) boundary conditions.
pub fn laplacian<T: Vector>(f: &Grid<T>) -> Grid<T> {
    let n = f.size();
    let inv_h2 = ((n - 1) * (n - 1)) as f64;
    let data = f.as_slice();
    // Neighbour index along a line, mirrored about the border nodes.
    let below = |m: usize| if m == 0 { 1 } else { m - 1 };
    let above = |m: usize| if m + 1 == n { n - 2 } else { m + 1 };
    let out = (0..n * n)
        .map(|k| {
            let (i, j) = (k / n, k % n);
            let centre = data[k];
            data[i * n + below(j)]
                .add(data[i * n + above(j)])
                .add(data[below(i) * n + j])
                .add(data[above(i) * n + j])
                .add_scaled(-4.0, centre)
                .scale(inv_h2)
        })
        .collect();
    Grid::from_parts(n, out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn quadratic(x: f64, y: f64) -> f64 {
        0.7 - 1.5 * x + 2.0 * y + 3.0 * x * x - 1.25 * x * y + 0.5 * y * y
    }

    #[test]
    fn gradient_is_exact_on_quadratics_border_included() {
        for n in [3, 5, 17] {
            let s = (n - 1) as f64;
            let f = Grid::from_fn(n, |i, j| {
                let (x, y) = (j as f64 / s, i as f64 / s);
                [quadratic(x, y), x * y - y * y]
            })
            .unwrap();
            let g = gradient(&f);
            let scalar = gradient(&f.component(0));
            for i in 0..n {
                for j in 0..n {
                    let [x, y] = f.node(i, j);
                    let exact = [
                        [-1.5 + 6.0 * x - 1.25 * y, y],
                        [2.0 - 1.25 * x + y, x - 2.0 * y],
                    ];
                    for d in 0..2 {
                        for c in 0..2 {
                            assert!(
                                (g[(i, j)][d][c] - exact[d][c]).abs() < 1e-11,
                                "n {n} node {i},{j} ∂{d} component {c}"
                            );
                        }
                        assert_eq!(scalar[(i, j)][d], g[(i, j)][d][0]);
                    }
                }
            }
        }
        // The 2 × 2 grid: one difference per direction.
        let g = gradient(&Grid::from_parts(2, vec![1.0, 2.0, 4.0, 8.0]));
        assert_eq!(
            g.as_slice(),
            &[[1.0, 3.0], [1.0, 6.0], [4.0, 3.0], [4.0, 6.0]]
        );
    }

    #[test]
    fn laplacian_is_exact_on_quadratics_inside() {
        let n = 17;
        let f = Grid::from_fn(n, |i, j| quadratic(j as f64 / 16.0, i as f64 / 16.0)).unwrap();
        let l = laplacian(&f);
        for i in 1..n - 1 {
            for j in 1..n - 1 {
                assert!(
                    (l[(i, j)] - (6.0 + 1.0)).abs() < 1e-9,
                    "{i},{j}: {}",
                    l[(i, j)]
                );
            }
        }
    }

    #[test]
    fn neumann_eigenfunctions_are_exact_eigenvectors() {
        // cos(aπx) cos(bπy) has zero flux on ∂ω; the mirrored stencil maps it to
        // λ_h f with λ_h = (2 cos(aπh) − 2 + 2 cos(bπh) − 2) / h², on every node.
        let n = 33;
        let h = 1.0 / 32.0;
        let (a, b) = (3.0, 2.0);
        let f = Grid::from_fn(n, |i, j| {
            [(a * PI * j as f64 * h).cos() * (b * PI * i as f64 * h).cos(); 2]
        })
        .unwrap();
        let lambda = (2.0 * (a * PI * h).cos() - 2.0 + 2.0 * (b * PI * h).cos() - 2.0) / (h * h);
        let l = laplacian(&f);
        for (v, w) in l.iter().zip(f.iter()) {
            assert!(
                (v[0] - lambda * w[0]).abs() < 1e-9,
                "{} vs {}",
                v[0],
                lambda * w[0]
            );
            assert_eq!(v[0], v[1]);
        }
        // And λ_h → −(a² + b²) π² as the grid refines.
        assert!((lambda / (-(a * a + b * b) * PI * PI) - 1.0).abs() < 0.02);
    }
}
