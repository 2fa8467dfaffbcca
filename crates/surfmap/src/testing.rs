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
