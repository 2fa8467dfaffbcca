//! Helpers for tests, examples and benchmarks (not part of the library's API): the
//! shared data folder of real meshes, deterministic pseudo-random inputs (xorshift64,
//! so runs repeat exactly; not for anything that needs statistical quality), and the
//! list of energies the property tests run over.

use std::path::PathBuf;

/// The environment variable that names the shared data folder (real meshes, several
/// without a licence, so never copied into the repository).
pub const DATA_ENV: &str = "SURFMAP_DATA";

/// The shared data folder: `$SURFMAP_DATA`, else `../shared/data` beside the repository
/// (`CARGO_MANIFEST_DIR/../../../shared/data`), recognized by its `manifest.json`.
///
/// When it is missing, tests on real meshes skip with a note (`None`), except under
/// `CI=true`, where this panics: a CI run must not pass by skipping them.
pub fn shared_data() -> Option<PathBuf> {
    let dir = std::env::var_os(DATA_ENV).map_or_else(
        || PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data")),
        PathBuf::from,
    );
    if dir.join("manifest.json").is_file() {
        return Some(dir);
    }
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    assert!(
        !ci,
        "the shared data folder {} (with manifest.json) is missing; CI=true, so tests on real \
         meshes fail instead of skipping: set {DATA_ENV} to the folder",
        dir.display()
    );
    eprintln!(
        "note: shared data folder {} not found (set {DATA_ENV}); skipping a test on real meshes",
        dir.display()
    );
    None
}

/// A file of the shared data folder ([`shared_data`]), or `None` (skip) as there.
pub fn shared_file(name: &str) -> Option<PathBuf> {
    Some(shared_data()?.join(name))
}

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

/// The largest coordinate difference `max_i max(|p_i.u − q_i.u|, |p_i.v − q_i.v|)` of two
/// lists of UVs of the same length.
pub fn max_uv_difference(p: &[[f64; 2]], q: &[[f64; 2]]) -> f64 {
    assert_eq!(p.len(), q.len(), "UV lists of different lengths");
    p.iter()
        .zip(q)
        .map(|(p, q)| (p[0] - q[0]).abs().max((p[1] - q[1]).abs()))
        .fold(0.0, f64::max)
}

/// Every energy density with a name: the four Litke presets, Litke without the angle
/// term (matching's regularization (2.8)), symmetric Dirichlet, MIPS and ARAP (tests
/// run each property over all of them).
pub fn all_energies() -> Vec<(&'static str, crate::energy::Energy)> {
    use crate::energy::{Alpha, Energy};
    vec![
        ("litke conformal", Energy::litke(Alpha::conformal())),
        ("litke balanced", Energy::litke(Alpha::balanced())),
        ("litke area", Energy::litke(Alpha::area())),
        ("litke length", Energy::litke(Alpha::length())),
        (
            "litke no angle",
            Energy::litke(Alpha::new(1.0, 1.0, 0.0).expect("valid weights")),
        ),
        ("sym dirichlet", Energy::SymmetricDirichlet),
        ("mips", Energy::Mips),
        ("arap", Energy::Arap),
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

/// The faces of `mesh` whose three vertices `keep`, with the vertices renumbered;
/// also the new index of every old vertex (`None`: removed).
pub fn crop(
    mesh: &crate::TriMesh,
    keep: impl Fn([f64; 3]) -> bool,
) -> (crate::TriMesh, Vec<Option<u32>>) {
    let mut index = vec![None; mesh.num_vertices()];
    let mut positions = vec![];
    for (v, &p) in mesh.positions.iter().enumerate() {
        if keep(p) {
            index[v] = Some(positions.len() as u32);
            positions.push(p);
        }
    }
    let triangles = mesh
        .triangles
        .iter()
        .filter_map(|t| {
            let [a, b, c] = t.map(|v| index[v as usize]);
            Some([a?, b?, c?])
        })
        .collect();
    (crate::TriMesh::new(positions, triangles), index)
}
