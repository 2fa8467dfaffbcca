//! Timing of the sparse Cholesky phases in `surfmap::linsolve` on two patterns with
//! ~200k vertices (a `side × side` grid, default side 448):
//!
//! 1. the 5-point grid Laplacian (+ 1e-3·I), one unknown per vertex;
//! 2. the 2-unknowns-per-vertex pattern of the triangulated grid (a 2×2 block for every
//!    pair of vertices sharing a triangle: the pattern of the Newton Hessian), filled
//!    with PSD element matrices `(e_a − e_b)(e_a − e_b)ᵀ ⊗ M`, `M = [[2, ½], [½, 1]]`,
//!    per triangle edge, plus 1e-3·I.
//!
//! Each case: pattern + symbolic factorization once, then three rounds of
//! refill (zero + scatter through slots), numeric factorization and solve.
//!
//! Run: `cargo run --release -p surfmap-bench --example linsolve_bench [side]`

use std::time::Instant;
use surfmap::linsolve::SpdSystem;

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Times every phase for the matrix `Σ_k base[k]·(entry k)` (scaled per round).
fn report(name: &str, n: usize, entries: &[(u32, u32)], base: &[f64]) {
    let t = Instant::now();
    let (mut sys, slots) = SpdSystem::new(n, entries).expect("pattern");
    let symbolic = ms(t);
    println!(
        "{name}: n = {n}, entries = {}, nnz(lower A) = {}, nnz(L) = {}",
        entries.len(),
        sys.nnz_lower(),
        sys.nnz_factor()
    );
    println!("  pattern + symbolic (AMD, supernodes): {symbolic:8.1} ms");
    let b: Vec<f64> = (0..n)
        .map(|i| ((i * 7919) % 101) as f64 / 101.0 - 0.5)
        .collect();
    for round in 0..3 {
        let scale = 1.0 + 0.25 * round as f64;
        let t = Instant::now();
        let v = sys.values_mut();
        v.fill(0.0);
        for (&s, &w) in slots.iter().zip(base) {
            v[s as usize] += scale * w;
        }
        let refill = ms(t);
        let t = Instant::now();
        let info = sys.factorize().expect("SPD");
        let numeric = ms(t);
        let mut x = b.clone();
        let t = Instant::now();
        sys.solve_in_place(&mut x).expect("solve");
        let solve = ms(t);
        let mut ax = vec![0.0; n];
        sys.mul_vec(&x, &mut ax).unwrap();
        let res = ax
            .iter()
            .zip(&b)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!(
            "  round {round}: refill {refill:6.1} ms, numeric {numeric:7.1} ms, solve {solve:6.1} ms, shift {:e}, |Ax-b|max {res:.1e}",
            info.shift
        );
    }
}

fn main() {
    let side: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(448);
    let id = |i: usize, j: usize| (i * side + j) as u32;
    let nv = side * side;

    // 1. Grid Laplacian.
    let (mut entries, mut base) = (Vec::new(), Vec::new());
    for i in 0..side {
        for j in 0..side {
            let p = id(i, j);
            entries.push((p, p));
            base.push(1e-3);
            for (ok, q) in [(i + 1 < side, (i + 1, j)), (j + 1 < side, (i, j + 1))] {
                if ok {
                    let q = id(q.0, q.1);
                    entries.extend([(p, p), (q, q), (q, p)]);
                    base.extend([1.0, 1.0, -1.0]);
                }
            }
        }
    }
    report("grid Laplacian", nv, &entries, &base);

    // 2. Two unknowns per vertex of the triangulated grid.
    let m = [[2.0, 0.5], [0.5, 1.0]];
    let (mut entries, mut base) = (Vec::new(), Vec::new());
    for dof in 0..2 * nv as u32 {
        entries.push((dof, dof));
        base.push(1e-3);
    }
    for i in 0..side - 1 {
        for j in 0..side - 1 {
            let quad = [id(i, j), id(i, j + 1), id(i + 1, j + 1), id(i + 1, j)];
            for tri in [[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]] {
                for k in 0..3 {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    for (r, row) in m.iter().enumerate() {
                        for (s, &w) in row.iter().enumerate() {
                            let (r, s) = (r as u32, s as u32);
                            entries.extend([
                                (2 * a + r, 2 * a + s),
                                (2 * b + r, 2 * b + s),
                                (2 * a + r, 2 * b + s),
                                (2 * b + r, 2 * a + s),
                            ]);
                            base.extend([w, w, -w, -w]);
                        }
                    }
                }
            }
        }
    }
    // Both triangles of an entry pair are listed: halve so the matrix is the intended one.
    for (e, w) in entries.iter().zip(base.iter_mut()) {
        if e.0 != e.1 {
            *w *= 0.5;
        }
    }
    report("2-DOF triangle grid", 2 * nv, &entries, &base);
}
