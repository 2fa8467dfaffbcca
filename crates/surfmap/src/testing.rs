//! Deterministic pseudo-random inputs for tests and benchmarks (not for anything that
//! needs statistical quality): xorshift64, so runs repeat exactly.

/// xorshift64 generator of uniform `f64` in `[0, 1)`. Seed must be non-zero.
#[derive(Clone, Debug)]
pub struct Rng(pub u64);

impl Rng {
    /// Next uniform value in `[0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform value in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Uniform index in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        ((self.uniform() * n as f64) as usize).min(n - 1)
    }

    /// A point with both coordinates uniform in `[-r, r)`.
    pub fn point(&mut self, r: f64) -> [f64; 2] {
        [self.range(-r, r), self.range(-r, r)]
    }
}

/// Every energy density with a name: the four Litke presets, symmetric Dirichlet, MIPS
/// and ARAP (tests run each property over all of them).
pub fn all_energies() -> Vec<(&'static str, crate::param::density::EnergyKind)> {
    use crate::param::density::{EnergyKind, Litke};
    vec![
        ("litke conformal", EnergyKind::Litke(Litke::conformal())),
        ("litke balanced", EnergyKind::Litke(Litke::balanced())),
        ("litke area", EnergyKind::Litke(Litke::area())),
        ("litke length", EnergyKind::Litke(Litke::length())),
        ("sym dirichlet", EnergyKind::SymmetricDirichlet),
        ("mips", EnergyKind::Mips),
        ("arap", EnergyKind::Arap),
    ]
}

/// Makes a system's matrix strictly diagonally dominant (so positive definite): every
/// diagonal entry becomes 1 + the sum of |off-diagonal| entries of its row and column.
/// For benchmarks of factorization cost on a given pattern.
pub fn make_diagonally_dominant(sys: &mut crate::linsolve::SpdSystem) {
    let (col_ptr, row_idx) = {
        let (a, b) = sys.pattern();
        (a.to_vec(), b.to_vec())
    };
    let dim = col_ptr.len() - 1;
    let mut rowsum = vec![0.0; dim];
    let v = sys.values_mut();
    for j in 0..dim {
        for k in col_ptr[j] as usize..col_ptr[j + 1] as usize {
            let i = row_idx[k] as usize;
            if i != j {
                rowsum[i] += v[k].abs();
                rowsum[j] += v[k].abs();
            }
        }
    }
    for j in 0..dim {
        v[col_ptr[j] as usize] = rowsum[j] + 1.0;
    }
}
