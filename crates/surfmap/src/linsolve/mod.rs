//! Sparse linear solves: the only module where `faer` types appear.
//!
//! Two phases, as types (faer's style): [`SpdSystem::new`] fixes the sparsity pattern
//! of a symmetric positive (semi-)definite matrix `A` (lower triangle, CSC) and computes
//! its symbolic Cholesky factorization once (AMD fill-reducing ordering, elimination
//! tree, supernodes). Every later step only refills the values
//! ([`SpdSystem::values_mut`]), refactorizes numerically `A = L Lᵀ`
//! ([`SpdSystem::factorize`]) and solves `L Lᵀ x = b` ([`SpdSystem::solve_in_place`]).
//! This is how the Newton solver (thesis §3.1.2, `H ψ = −∇E`) reuses its analysis.
//!
//! One-shot helpers: [`solve_spd`] (symmetric, Cholesky) and [`solve_general`]
//! (non-symmetric, sparse LU with partial pivoting, e.g. mean-value coordinates).
//!
//! Factorizations run single-threaded (`Par::Seq`): two threads gave no speed-up for
//! ~200k unknowns on the project's 2-core machine (see `DEPENDENCIES.md`).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::LltError;
use faer::linalg::solvers::Solve;
use faer::perm::PermRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMatRef, Triplet};
use faer::{Conj, MatMut, Par, Side};

pub mod dense;
mod ordering;
mod unknowns;
use ordering::inverse_permutation;
pub use ordering::{Ordering, VertexOrdering};
pub use unknowns::{FIXED, Unknowns};

/// What went wrong in a sparse solve, and what to do about it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    #[error("the linear system has no unknowns (dimension 0); build it from a non-empty mesh")]
    Empty,
    #[error(
        "dimension {n} does not fit 32-bit indices, or the pattern has too many entries; split the problem"
    )]
    TooLarge { n: usize },
    #[error(
        "matrix entry ({row}, {col}) is outside the {n}×{n} system; check the assembly indices"
    )]
    IndexOutOfRange { row: u32, col: u32, n: usize },
    #[error("expected a vector of length {expected}, got {got}")]
    DimensionMismatch { expected: usize, got: usize },
    #[error(
        "matrix value #{index} is not finite ({value}); the assembled entries contain NaN or ∞"
    )]
    NonFiniteValue { index: usize, value: f64 },
    #[error("right-hand side entry {index} is not finite ({value})")]
    NonFiniteRhs { index: usize, value: f64 },
    #[error(
        "matrix is not positive definite (non-positive pivot at column {pivot}, still after a diagonal shift of {shift:e}); \
         pin vertices to remove the null space or project the element Hessians to PSD"
    )]
    NotPositiveDefinite { pivot: usize, shift: f64 },
    #[error("matrix is singular (LU pivot {index} vanishes); the system has no unique solution")]
    Singular { index: usize },
    #[error(
        "solve is numerically unreliable: relative residual {residual:e}; the matrix is (nearly) singular"
    )]
    Inaccurate { residual: f64 },
    #[error(
        "the ordering of a {n}-unknown system is not a permutation of 0..{n} (entry #{index} = {value}); \
         build it from the same unknowns as the system"
    )]
    InvalidOrdering { n: usize, index: usize, value: u32 },
    #[error("solve_in_place called before a successful factorize")]
    NotFactorized,
    #[error("sparse solver failed: {0}")]
    Backend(String),
}

/// What [`SpdSystem::factorize`] had to do to succeed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FactorInfo {
    /// Diagonal shift `s` actually factorized (`A + s·I`); 0 when `A` itself was positive definite.
    pub shift: f64,
}

/// First diagonal shift tried, relative to `max |A_ii|`.
const FIRST_RELATIVE_SHIFT: f64 = 1e-12;
/// Growth factor of the shift between attempts.
const SHIFT_GROWTH: f64 = 100.0;
/// Shifted attempts after the unshifted one (relative shifts 1e-12 … 1e-2).
const SHIFT_ATTEMPTS: usize = 6;

/// Symmetric positive (semi-)definite sparse matrix with a fixed pattern, lower triangle
/// stored in CSC, with its symbolic Cholesky factorization computed once and reused for
/// every numeric refactorization.
///
/// The pattern always contains the full diagonal (needed for Cholesky and for the
/// diagonal shift), even when no entry names it.
pub struct SpdSystem {
    n: usize,
    /// CSC of the lower triangle: rows of column `j` are `row_idx[col_ptr[j]..col_ptr[j+1]]`, sorted, `≥ j`.
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    values: Vec<f64>,
    /// Slot of `(j, j)` in `values` (the first entry of column `j`).
    diag_slots: Vec<u32>,
    /// Diagonal saved while a shifted matrix is factorized, restored afterwards.
    saved_diag: Vec<f64>,
    symbolic: SymbolicCholesky<u32>,
    l_values: Vec<f64>,
    factor_scratch: MemBuffer,
    factorized: bool,
}

impl std::fmt::Debug for SpdSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpdSystem")
            .field("n", &self.n)
            .field("nnz_lower", &self.values.len())
            .field("nnz_factor", &self.l_values.len())
            .field("factorized", &self.factorized)
            .finish()
    }
}

impl SpdSystem {
    /// Pattern from (row, col) pairs, any triangle, duplicates allowed. Returns the system and, for each
    /// input pair, the index of its slot in `values_mut()` (so callers refill values in O(1) each step:
    /// zero the values, then `values[slot[k]] += v_k`). Pairs with row < col map to the mirrored slot.
    ///
    /// Every slot holds the *sum* of the values scattered into it, and `(i, j)` and `(j, i)`
    /// share one slot: list an off-diagonal entry of the symmetric matrix once (either
    /// triangle), or scatter half of it from each side.
    ///
    /// Cost: O(nnz log(row length)) for the pattern plus faer's symbolic analysis
    /// (AMD ordering, elimination tree, supernodal structure). Same as
    /// [`SpdSystem::with_ordering`] with [`Ordering::Amd`].
    pub fn new(n: usize, entries: &[(u32, u32)]) -> Result<(Self, Vec<u32>), SolveError> {
        Self::with_ordering(n, entries, &Ordering::Amd)
    }

    /// [`SpdSystem::new`] with a given fill-reducing ordering instead of AMD on this
    /// pattern: with [`Ordering::Custom`], faer's symbolic phase skips its AMD and only
    /// computes the elimination tree, column counts and supernodes of `P A Pᵀ`.
    /// The solution of `A x = b` does not depend on the ordering (up to rounding); the
    /// fill of `L` and so the cost of each numeric factorization does.
    ///
    /// An `Ordering::Custom` that is not a permutation of `0..n` is an error
    /// ([`SolveError::InvalidOrdering`]).
    pub fn with_ordering(
        n: usize,
        entries: &[(u32, u32)],
        ordering: &Ordering,
    ) -> Result<(Self, Vec<u32>), SolveError> {
        let LowerPattern {
            col_ptr,
            row_idx,
            slots,
        } = LowerPattern::new(n, entries)?;
        let diag_slots: Vec<u32> = col_ptr[..n].to_vec(); // rows sorted, all ≥ j, (j, j) present
        let pattern = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let inverse;
        let faer_ordering = match ordering {
            Ordering::Amd => SymmetricOrdering::Amd,
            Ordering::Custom(forward) => {
                inverse = inverse_permutation(forward, n)?;
                SymmetricOrdering::Custom(PermRef::new_checked(forward, &inverse, n))
            }
        };
        let symbolic =
            factorize_symbolic_cholesky(pattern, Side::Lower, faer_ordering, symbolic_params())
                .map_err(|e| SolveError::Backend(format!("symbolic Cholesky: {e:?}")))?;
        let l_values = vec![0.0; symbolic.len_val()];
        let factor_scratch = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(parallelism(n), Default::default()),
        )
        .map_err(|e| SolveError::Backend(format!("workspace allocation: {e:?}")))?;
        let nnz = row_idx.len();
        Ok((
            Self {
                n,
                col_ptr,
                row_idx,
                values: vec![0.0; nnz],
                diag_slots,
                saved_diag: vec![0.0; n],
                symbolic,
                l_values,
                factor_scratch,
                factorized: false,
            },
            slots,
        ))
    }

    /// Values of the stored lower triangle, in slot order (see [`SpdSystem::new`]).
    /// Changing them invalidates the last factorization until [`SpdSystem::factorize`].
    pub fn values_mut(&mut self) -> &mut [f64] {
        self.factorized = false;
        &mut self.values
    }

    /// Values of the stored lower triangle, in slot order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Number of unknowns `n` (the matrix is `n × n`).
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Stored entries of the lower triangle (including the full diagonal).
    pub fn nnz_lower(&self) -> usize {
        self.row_idx.len()
    }

    /// Entries of the Cholesky factor `L` (a measure of fill-in).
    pub fn nnz_factor(&self) -> usize {
        self.l_values.len()
    }

    /// The lower-triangle CSC pattern `(col_ptr, row_idx)`: slot `k` of column `j`
    /// (`col_ptr[j] ≤ k < col_ptr[j+1]`) holds `A[row_idx[k], j]`.
    pub fn pattern(&self) -> (&[u32], &[u32]) {
        (&self.col_ptr, &self.row_idx)
    }

    /// `y = A x` with the full symmetric matrix represented by the stored lower triangle.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) -> Result<(), SolveError> {
        check_len(self.n, x.len())?;
        check_len(self.n, y.len())?;
        y.fill(0.0);
        for j in 0..self.n {
            for k in self.col_ptr[j] as usize..self.col_ptr[j + 1] as usize {
                let i = self.row_idx[k] as usize;
                let a = self.values[k];
                y[i] += a * x[j];
                if i != j {
                    y[j] += a * x[i];
                }
            }
        }
        Ok(())
    }

    /// Numeric LLᵀ with the stored symbolic factorization. If faer reports a non-positive pivot, retry
    /// with a diagonal shift (1e-12·max|diag|, growing ×100, a few times); report the shift used.
    ///
    /// The shift is applied to a copy of the diagonal only; `values()` are unchanged afterwards.
    pub fn factorize(&mut self) -> Result<FactorInfo, SolveError> {
        self.factorized = false;
        if let Some((index, &value)) = self.values.iter().enumerate().find(|(_, v)| !v.is_finite())
        {
            return Err(SolveError::NonFiniteValue { index, value });
        }
        let pivot = match self.factorize_numeric() {
            Ok(()) => {
                self.factorized = true;
                return Ok(FactorInfo { shift: 0.0 });
            }
            Err(pivot) => pivot,
        };
        let max_diag = self
            .diag_slots
            .iter()
            .map(|&s| self.values[s as usize].abs())
            .fold(0.0, f64::max);
        if max_diag == 0.0 {
            return Err(SolveError::NotPositiveDefinite { pivot, shift: 0.0 });
        }
        for (j, &s) in self.diag_slots.iter().enumerate() {
            self.saved_diag[j] = self.values[s as usize];
        }
        let mut shift = FIRST_RELATIVE_SHIFT * max_diag;
        let mut last_pivot = pivot;
        for attempt in 0..SHIFT_ATTEMPTS {
            if attempt > 0 {
                shift *= SHIFT_GROWTH;
            }
            for (j, &s) in self.diag_slots.iter().enumerate() {
                self.values[s as usize] = self.saved_diag[j] + shift;
            }
            let result = self.factorize_numeric();
            for (j, &s) in self.diag_slots.iter().enumerate() {
                self.values[s as usize] = self.saved_diag[j];
            }
            match result {
                Ok(()) => {
                    self.factorized = true;
                    return Ok(FactorInfo { shift });
                }
                Err(pivot) => last_pivot = pivot,
            }
        }
        Err(SolveError::NotPositiveDefinite {
            pivot: last_pivot,
            shift,
        })
    }

    /// Numeric LLᵀ without any shift: fails with [`SolveError::NotPositiveDefinite`]
    /// when the matrix is not positive definite. Lets a caller test whether an exact
    /// (unprojected) Hessian is usable before falling back to a projected one.
    pub fn factorize_unshifted(&mut self) -> Result<(), SolveError> {
        self.factorized = false;
        if let Some((index, &value)) = self.values.iter().enumerate().find(|(_, v)| !v.is_finite())
        {
            return Err(SolveError::NonFiniteValue { index, value });
        }
        match self.factorize_numeric() {
            Ok(()) => {
                self.factorized = true;
                Ok(())
            }
            Err(pivot) => Err(SolveError::NotPositiveDefinite { pivot, shift: 0.0 }),
        }
    }

    /// One numeric factorization of the current values; `Err(pivot)` on a non-positive
    /// pivot (index in the permuted order).
    fn factorize_numeric(&mut self) -> Result<(), usize> {
        let a = SparseColMatRef::<'_, u32, f64>::new(
            SymbolicSparseColMatRef::new_checked(
                self.n,
                self.n,
                &self.col_ptr,
                None,
                &self.row_idx,
            ),
            &self.values,
        );
        let stack = MemStack::new(&mut self.factor_scratch);
        match self.symbolic.factorize_numeric_llt::<f64>(
            &mut self.l_values,
            a,
            Side::Lower,
            Default::default(),
            parallelism(self.n),
            stack,
            Default::default(),
        ) {
            Ok(_) => Ok(()),
            Err(LltError::NonPositivePivot { index }) => Err(index),
        }
    }

    /// Solve with the last factorization, in place: `rhs ← (L Lᵀ)⁻¹ rhs`.
    pub fn solve_in_place(&self, rhs: &mut [f64]) -> Result<(), SolveError> {
        if !self.factorized {
            return Err(SolveError::NotFactorized);
        }
        check_len(self.n, rhs.len())?;
        if let Some((index, &value)) = rhs.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(SolveError::NonFiniteRhs { index, value });
        }
        let mut buf = MemBuffer::try_new(self.symbolic.solve_in_place_scratch::<f64>(1, Par::Seq))
            .map_err(|e| SolveError::Backend(format!("workspace allocation: {e:?}")))?;
        let x = MatMut::from_column_major_slice_mut(rhs, self.n, 1);
        LltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            x,
            Par::Seq,
            MemStack::new(&mut buf),
        );
        Ok(())
    }
}

/// The lower triangle (with the full diagonal) of a symmetric pattern in CSC, sorted
/// and deduplicated, and the slot of every input pair in it.
pub(crate) struct LowerPattern {
    /// Rows of column `j` are `row_idx[col_ptr[j]..col_ptr[j+1]]`, sorted, `≥ j`, `j` first.
    pub(crate) col_ptr: Vec<u32>,
    pub(crate) row_idx: Vec<u32>,
    /// For each input pair, its slot (an index into `row_idx`).
    pub(crate) slots: Vec<u32>,
}

impl LowerPattern {
    /// From (row, col) pairs, any triangle, duplicates allowed: a counting sort by
    /// column, then a sort and deduplication of each column, O(nnz log(row length)).
    pub(crate) fn new(n: usize, entries: &[(u32, u32)]) -> Result<Self, SolveError> {
        if n == 0 {
            return Err(SolveError::Empty);
        }
        let total = entries.len().checked_add(n);
        if n > u32::MAX as usize || total.is_none_or(|t| t > u32::MAX as usize) {
            return Err(SolveError::TooLarge { n });
        }
        for &(row, col) in entries {
            if row as usize >= n || col as usize >= n {
                return Err(SolveError::IndexOutOfRange { row, col, n });
            }
        }
        let lower = |(r, c): (u32, u32)| if r >= c { (r, c) } else { (c, r) };

        // Counting sort by column (the diagonal once per column, then every entry).
        let mut start = vec![0u32; n + 1];
        for j in 0..n {
            start[j + 1] = 1;
        }
        for &e in entries {
            start[lower(e).1 as usize + 1] += 1;
        }
        for j in 0..n {
            start[j + 1] += start[j];
        }
        let mut fill = start.clone();
        let mut rows = vec![0u32; start[n] as usize];
        for j in 0..n {
            rows[fill[j] as usize] = j as u32;
            fill[j] += 1;
        }
        for &e in entries {
            let (i, j) = lower(e);
            rows[fill[j as usize] as usize] = i;
            fill[j as usize] += 1;
        }
        drop(fill);

        // Sort and deduplicate every column in place, compacting to the front.
        let mut col_ptr = vec![0u32; n + 1];
        let mut write = 0usize;
        for j in 0..n {
            let (s, e) = (start[j] as usize, start[j + 1] as usize);
            rows[s..e].sort_unstable();
            let mut last = u32::MAX;
            for k in s..e {
                let r = rows[k];
                if r != last {
                    rows[write] = r;
                    write += 1;
                    last = r;
                }
            }
            col_ptr[j + 1] = write as u32;
        }
        rows.truncate(write);
        rows.shrink_to_fit();
        let row_idx = rows;

        let column = |j: usize| &row_idx[col_ptr[j] as usize..col_ptr[j + 1] as usize];
        let slots = entries
            .iter()
            .map(|&e| {
                let (i, j) = lower(e);
                let pos = column(j as usize)
                    .binary_search(&i)
                    .expect("every entry was inserted into its column");
                col_ptr[j as usize] + pos as u32
            })
            .collect();
        Ok(Self {
            col_ptr,
            row_idx,
            slots,
        })
    }
}

/// faer's symbolic parameters with a lower threshold for the supernodal factorization:
/// faer picks it when the factorization's flops per factor entry exceed 40 × the
/// threshold (default 1), else the simplicial (column by column) one. Our Newton
/// Hessians (a 2×2 block per vertex pair, a planar mesh's AMD fill) stay below 40 up to
/// tens of thousands of vertices, where the supernodal factorization measured faster
/// (`hard_discs`, same run: bunny 0.150 → 0.088 s, three_holes 0.22 → 0.16 s,
/// ict_neutral cut 0.73 → 0.58 s; see BENCHMARKS.md). With 0.25 the supernodal one is
/// used above 10 flops per entry, which leaves only tiny systems simplicial.
fn symbolic_params() -> CholeskySymbolicParams<'static> {
    CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold(0.25),
        ..Default::default()
    }
}

/// Threads for a factorization: one. Measured on this 2-core machine (see
/// BENCHMARKS.md): faer's parallel supernodal factorization was 2.4× slower on 22.7k
/// unknowns and 1.2× slower on 1.07M unknowns than the sequential one.
fn parallelism(_n: usize) -> Par {
    Par::Seq
}

fn check_len(expected: usize, got: usize) -> Result<(), SolveError> {
    if expected == got {
        Ok(())
    } else {
        Err(SolveError::DimensionMismatch { expected, got })
    }
}

/// `max_i |v_i|`, NaN if any entry is NaN.
fn max_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| {
        if x.is_nan() || m.is_nan() {
            f64::NAN
        } else {
            m.max(x.abs())
        }
    })
}

/// Accepts a computed solution `x` of `A x = b` given the residual `r = A x − b` and
/// `‖A‖∞`: `x` must be finite, the normwise backward error `‖r‖ / (‖A‖ ‖x‖ + ‖b‖)` at most
/// [`MAX_RELATIVE_RESIDUAL`], and, when the matrix had to be shifted, `‖r‖ ≤ 1e-6 ‖b‖`
/// (a right-hand side outside the range of a singular matrix fails this).
fn check_solution(
    a_norm: f64,
    x: &[f64],
    b: &[f64],
    r: &[f64],
    shifted: bool,
) -> Result<(), SolveError> {
    if x.iter().any(|v| !v.is_finite()) {
        return Err(SolveError::Inaccurate {
            residual: f64::INFINITY,
        });
    }
    let (r_norm, b_norm) = (max_norm(r), max_norm(b));
    let denom = a_norm * max_norm(x) + b_norm;
    let backward = if denom == 0.0 { 0.0 } else { r_norm / denom };
    if backward.is_nan() || backward > MAX_RELATIVE_RESIDUAL {
        return Err(SolveError::Inaccurate { residual: backward });
    }
    if shifted && r_norm > MAX_SHIFTED_RESIDUAL * b_norm {
        return Err(SolveError::Inaccurate {
            residual: r_norm / b_norm,
        });
    }
    Ok(())
}

/// Residual `‖A x − b‖ / ‖b‖` above which a solve of a shifted (singular) matrix is rejected.
const MAX_SHIFTED_RESIDUAL: f64 = 1e-6;

/// Residual above which a one-shot solve reports [`SolveError::Inaccurate`].
const MAX_RELATIVE_RESIDUAL: f64 = 1e-8;

fn check_system(
    n: usize,
    triplets: &[(u32, u32, f64)],
    rhs: &[&mut [f64]],
) -> Result<(), SolveError> {
    if n == 0 {
        return Err(SolveError::Empty);
    }
    if n > u32::MAX as usize {
        return Err(SolveError::TooLarge { n });
    }
    for (index, &(row, col, value)) in triplets.iter().enumerate() {
        if row as usize >= n || col as usize >= n {
            return Err(SolveError::IndexOutOfRange { row, col, n });
        }
        if !value.is_finite() {
            return Err(SolveError::NonFiniteValue { index, value });
        }
    }
    for b in rhs {
        check_len(n, b.len())?;
        if let Some((index, &value)) = b.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(SolveError::NonFiniteRhs { index, value });
        }
    }
    Ok(())
}

/// One-shot: assemble from triplets (duplicates summed), factorize, solve; several right-hand sides.
///
/// The matrix is the symmetric `A` whose entries are given in either triangle: a triplet
/// `(i, j, v)` with `i ≠ j` stands for both `A_ij` and `A_ji` and must be given only once
/// (in one triangle). Each solution is checked by its residual; a shifted factorization
/// whose answer is not accurate to 1e-8 is reported as [`SolveError::Inaccurate`].
pub fn solve_spd(
    n: usize,
    triplets: &[(u32, u32, f64)],
    rhs: &mut [&mut [f64]],
) -> Result<(), SolveError> {
    check_system(n, triplets, rhs)?;
    let pairs: Vec<(u32, u32)> = triplets.iter().map(|&(i, j, _)| (i, j)).collect();
    let (mut system, slots) = SpdSystem::new(n, &pairs)?;
    let values = system.values_mut();
    for (&(_, _, v), &s) in triplets.iter().zip(&slots) {
        values[s as usize] += v;
    }
    let info = system.factorize()?;
    let mut row_abs = vec![0.0; n];
    for &(i, j, v) in triplets {
        row_abs[i as usize] += v.abs();
        if i != j {
            row_abs[j as usize] += v.abs();
        }
    }
    let a_norm = max_norm(&row_abs);
    let mut b = vec![0.0; n];
    let mut r = vec![0.0; n];
    for x in rhs.iter_mut() {
        b.copy_from_slice(x);
        system.solve_in_place(x)?;
        system.mul_vec(x, &mut r)?;
        r.iter_mut().zip(&b).for_each(|(r, b)| *r -= b);
        check_solution(a_norm, x, &b, &r, info.shift > 0.0)?;
    }
    Ok(())
}

/// One-shot general sparse solve (LU) for non-symmetric systems such as mean-value coordinates.
///
/// `A` is assembled from triplets `(row, col, value)` with duplicates summed; faer's
/// supernodal LU with partial pivoting (COLAMD ordering) solves `A x = b` for every
/// right-hand side in place. A structurally singular matrix gives [`SolveError::Singular`];
/// a numerically singular one is caught by the residual check ([`SolveError::Inaccurate`]).
pub fn solve_general(
    n: usize,
    triplets: &[(u32, u32, f64)],
    rhs: &mut [&mut [f64]],
) -> Result<(), SolveError> {
    check_system(n, triplets, rhs)?;
    let entries: Vec<Triplet<u32, u32, f64>> = triplets
        .iter()
        .map(|&(i, j, v)| Triplet::new(i, j, v))
        .collect();
    let a = SparseColMat::<u32, f64>::try_new_from_triplets(n, n, &entries)
        .map_err(|e| SolveError::Backend(format!("assembly: {e:?}")))?;
    let lu = a.sp_lu().map_err(|e| match e {
        faer::sparse::linalg::LuError::SymbolicSingular { index } => SolveError::Singular { index },
        faer::sparse::linalg::LuError::Generic(e) => SolveError::Backend(format!("LU: {e:?}")),
    })?;
    let mut row_abs = vec![0.0; n];
    for &(i, _, v) in triplets {
        row_abs[i as usize] += v.abs();
    }
    let a_norm = max_norm(&row_abs);
    let mut r = vec![0.0; n];
    let mut b = vec![0.0; n];
    for x in rhs.iter_mut() {
        b.copy_from_slice(x);
        lu.solve_in_place(MatMut::from_column_major_slice_mut(x, n, 1));
        r.iter_mut().zip(&b).for_each(|(r, b)| *r = -b);
        for &(i, j, v) in triplets {
            r[i as usize] += v * x[j as usize];
        }
        check_solution(a_norm, x, &b, &r, false)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::testing::Rng;

    /// Dense Gaussian elimination with partial pivoting (the independent oracle).
    fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for k in 0..n {
            let p = (k..n)
                .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
                .unwrap();
            a.swap(k, p);
            b.swap(k, p);
            let pivot_row = a[k].clone();
            for i in k + 1..n {
                let f = a[i][k] / pivot_row[k];
                for (aij, akj) in a[i][k..].iter_mut().zip(&pivot_row[k..]) {
                    *aij -= f * akj;
                }
                b[i] -= f * b[k];
            }
        }
        let mut x = vec![0.0; n];
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|j| a[k][j] * x[j]).sum();
            x[k] = (b[k] - s) / a[k][k];
        }
        x
    }

    type Triplets = Vec<(u32, u32, f64)>;
    type Dense = Vec<Vec<f64>>;

    /// A random weighted graph Laplacian plus a positive diagonal, as triplets in both
    /// triangles' mixture (each off-diagonal pair once, randomly in upper or lower),
    /// with some entries split into duplicates.
    fn random_spd(n: usize, edges: usize, rng: &mut Rng) -> (Triplets, Dense) {
        let mut dense = vec![vec![0.0; n]; n];
        let mut t = Vec::new();
        for _ in 0..edges {
            let (i, j) = (rng.below(n), rng.below(n));
            if i == j {
                continue;
            }
            let w = 0.1 + rng.uniform();
            dense[i][j] -= w;
            dense[j][i] -= w;
            dense[i][i] += w;
            dense[j][j] += w;
            let (r, c) = if rng.uniform() < 0.5 { (i, j) } else { (j, i) };
            // split into two duplicates
            t.push((r as u32, c as u32, -0.3 * w));
            t.push((r as u32, c as u32, -0.7 * w));
            t.push((i as u32, i as u32, w));
            t.push((j as u32, j as u32, w));
        }
        for (i, row) in dense.iter_mut().enumerate() {
            let d = 0.05 + rng.uniform();
            row[i] += d;
            t.push((i as u32, i as u32, d));
        }
        (t, dense)
    }

    fn max_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn solve_spd_matches_dense_solve() {
        let mut rng = Rng(7);
        for &n in &[1usize, 2, 5, 30, 80] {
            let (t, dense) = random_spd(n, 3 * n, &mut rng);
            let b1: Vec<f64> = (0..n).map(|_| rng.uniform() - 0.5).collect();
            let b2: Vec<f64> = (0..n).map(|_| rng.uniform() * 3.0).collect();
            let (mut x1, mut x2) = (b1.clone(), b2.clone());
            solve_spd(n, &t, &mut [&mut x1, &mut x2]).unwrap();
            let e1 = dense_solve(dense.clone(), b1);
            let e2 = dense_solve(dense, b2);
            assert!(max_diff(&x1, &e1) < 1e-9, "n={n}: {}", max_diff(&x1, &e1));
            assert!(max_diff(&x2, &e2) < 1e-9, "n={n}");
        }
    }

    #[test]
    fn refactorization_reuses_symbolic_and_is_correct() {
        let mut rng = Rng(11);
        let n = 60;
        let (t, _) = random_spd(n, 200, &mut rng);
        let pairs: Vec<(u32, u32)> = t.iter().map(|&(i, j, _)| (i, j)).collect();
        let (mut sys, slots) = SpdSystem::new(n, &pairs).unwrap();
        let nnz_factor = sys.nnz_factor();
        for round in 0..3 {
            // New values on the same pattern: rescale each triplet differently per round,
            // keep it a Laplacian + positive diagonal by regenerating weights.
            let mut dense = vec![vec![0.0; n]; n];
            let vals = sys.values_mut();
            vals.fill(0.0);
            let mut k = 0;
            while k < t.len() {
                let (i, j, _) = t[k];
                if i != j {
                    // pattern from random_spd: two duplicates then two diagonals
                    let w = 0.1 + rng.uniform() * (round + 1) as f64;
                    let (a, b) = (i as usize, j as usize);
                    for (kk, v) in [(k, -0.5 * w), (k + 1, -0.5 * w), (k + 2, w), (k + 3, w)] {
                        vals[slots[kk] as usize] += v;
                    }
                    dense[a][b] -= w;
                    dense[b][a] -= w;
                    dense[a][a] += w;
                    dense[b][b] += w;
                    k += 4;
                } else {
                    let d = 0.05 + rng.uniform();
                    vals[slots[k] as usize] += d;
                    dense[i as usize][i as usize] += d;
                    k += 1;
                }
            }
            let info = sys.factorize().unwrap();
            assert_eq!(info.shift, 0.0);
            assert_eq!(sys.nnz_factor(), nnz_factor);
            let b: Vec<f64> = (0..n).map(|_| rng.uniform() - 0.5).collect();
            let mut x = b.clone();
            sys.solve_in_place(&mut x).unwrap();
            let expect = dense_solve(dense, b);
            assert!(max_diff(&x, &expect) < 1e-9, "round {round}");
        }
    }

    #[test]
    fn slots_map_duplicates_and_mirrored_entries() {
        // 3×3 pattern with (0,1) and (1,0) given separately, (2,2) twice, (0,2) only upper.
        let pairs = [(0, 1), (1, 0), (2, 2), (2, 2), (0, 2), (1, 1)];
        let (sys, slots) = SpdSystem::new(3, &pairs).unwrap();
        let (col_ptr, row_idx) = sys.pattern();
        let lookup = |s: u32| {
            let s = s as usize;
            let j = (0..3).find(|&j| (col_ptr[j] as usize..col_ptr[j + 1] as usize).contains(&s));
            (row_idx[s], j.unwrap() as u32)
        };
        assert_eq!(slots[0], slots[1]);
        assert_eq!(slots[2], slots[3]);
        assert_eq!(lookup(slots[0]), (1, 0));
        assert_eq!(lookup(slots[2]), (2, 2));
        assert_eq!(lookup(slots[4]), (2, 0));
        assert_eq!(lookup(slots[5]), (1, 1));
        // full diagonal present even for (0,0) which was never named: 3 diag + (1,0) + (2,0)
        assert_eq!(sys.nnz_lower(), 5);
        for (j, w) in col_ptr.windows(2).enumerate() {
            assert_eq!(
                row_idx[w[0] as usize], j as u32,
                "diagonal first in column {j}"
            );
        }
    }

    #[test]
    fn mul_vec_matches_dense() {
        let mut rng = Rng(3);
        let n = 20;
        let (t, dense) = random_spd(n, 50, &mut rng);
        let pairs: Vec<(u32, u32)> = t.iter().map(|&(i, j, _)| (i, j)).collect();
        let (mut sys, slots) = SpdSystem::new(n, &pairs).unwrap();
        for (&(_, _, v), &s) in t.iter().zip(&slots) {
            sys.values_mut()[s as usize] += v;
        }
        let x: Vec<f64> = (0..n).map(|_| rng.uniform()).collect();
        let mut y = vec![0.0; n];
        sys.mul_vec(&x, &mut y).unwrap();
        let expect: Vec<f64> = dense
            .iter()
            .map(|row| row.iter().zip(&x).map(|(a, b)| a * b).sum())
            .collect();
        assert!(max_diff(&y, &expect) < 1e-12);
    }

    #[test]
    fn indefinite_matrix_is_an_error_not_a_panic() {
        // [[1, 2], [2, 1]] has eigenvalues 3 and −1: no small shift helps.
        let t = [(0, 0, 1.0), (1, 1, 1.0), (1, 0, 2.0)];
        let mut b = vec![1.0, 1.0];
        let err = solve_spd(2, &t, &mut [&mut b]).unwrap_err();
        assert!(
            matches!(err, SolveError::NotPositiveDefinite { .. }),
            "{err:?}"
        );
        // all-zero matrix
        let mut b = vec![1.0, 1.0];
        let err = solve_spd(2, &[(0, 1, 0.0)], &mut [&mut b]).unwrap_err();
        assert!(
            matches!(err, SolveError::NotPositiveDefinite { .. }),
            "{err:?}"
        );
    }

    #[test]
    fn singular_psd_laplacian_is_shifted_and_reported() {
        // Path-graph Laplacian: PSD with the constant null space.
        let n = 6;
        let mut pairs = Vec::new();
        let mut vals = Vec::new();
        for i in 0..n - 1 {
            let (a, b) = (i as u32, i as u32 + 1);
            for (p, v) in [((a, a), 1.0), ((b, b), 1.0), ((a, b), -1.0)] {
                pairs.push(p);
                vals.push(v);
            }
        }
        let (mut sys, slots) = SpdSystem::new(n, &pairs).unwrap();
        for (&v, &s) in vals.iter().zip(&slots) {
            sys.values_mut()[s as usize] += v;
        }
        let before = sys.values().to_vec();
        match sys.factorize() {
            Ok(info) => assert!(info.shift > 0.0, "singular matrix factorized without shift"),
            Err(e) => assert!(matches!(e, SolveError::NotPositiveDefinite { .. })),
        }
        assert_eq!(
            sys.values(),
            &before[..],
            "shift must not leak into the values"
        );
        // The one-shot solver must not return a meaningless answer for an inconsistent rhs.
        let t: Vec<(u32, u32, f64)> = pairs
            .iter()
            .zip(&vals)
            .map(|(&(i, j), &v)| (i, j, v))
            .collect();
        let mut b = vec![1.0; n];
        let r = solve_spd(n, &t, &mut [&mut b]);
        assert!(r.is_err(), "{r:?} {b:?}");
        // A consistent right-hand side (orthogonal to the constants) is solved through the shift.
        let b: Vec<f64> = (0..n).map(|i| i as f64 - 2.5).collect();
        let mut x = b.clone();
        solve_spd(n, &t, &mut [&mut x]).unwrap();
        let mut ax = vec![0.0; n];
        for &(i, j, v) in &t {
            ax[i as usize] += v * x[j as usize];
            if i != j {
                ax[j as usize] += v * x[i as usize];
            }
        }
        assert!(max_diff(&ax, &b) < 1e-6, "{ax:?}");
    }

    #[test]
    fn bad_input_is_reported() {
        assert_eq!(SpdSystem::new(0, &[]).unwrap_err(), SolveError::Empty);
        assert!(matches!(
            SpdSystem::new(2, &[(0, 2)]).unwrap_err(),
            SolveError::IndexOutOfRange {
                row: 0,
                col: 2,
                n: 2
            }
        ));
        let (mut sys, _) = SpdSystem::new(2, &[(1, 0)]).unwrap();
        assert_eq!(
            sys.solve_in_place(&mut [0.0, 0.0]),
            Err(SolveError::NotFactorized)
        );
        sys.values_mut().copy_from_slice(&[2.0, 1.0, f64::NAN]);
        assert!(matches!(
            sys.factorize(),
            Err(SolveError::NonFiniteValue { .. })
        ));
        sys.values_mut().copy_from_slice(&[2.0, 1.0, 2.0]);
        sys.factorize().unwrap();
        assert!(matches!(
            sys.solve_in_place(&mut [0.0; 3]),
            Err(SolveError::DimensionMismatch {
                expected: 2,
                got: 3
            })
        ));
        let mut x = [3.0, 3.0];
        sys.solve_in_place(&mut x).unwrap();
        assert!(max_diff(&x, &[1.0, 1.0]) < 1e-14);
        let mut b = vec![1.0];
        assert!(matches!(
            solve_general(2, &[(0, 0, 1.0)], &mut [&mut b]),
            Err(SolveError::DimensionMismatch { .. })
        ));
    }

    #[test]
    fn solve_general_matches_dense_solve() {
        let mut rng = Rng(5);
        for &n in &[1usize, 3, 40] {
            let mut dense = vec![vec![0.0; n]; n];
            let mut t = Vec::new();
            for (i, row) in dense.iter_mut().enumerate() {
                // non-symmetric, diagonally dominant rows; plus a duplicate on the diagonal
                let mut off = 0.0;
                for _ in 0..4 {
                    let j = rng.below(n);
                    if j != i {
                        let v = rng.uniform() - 0.7;
                        row[j] += v;
                        off += v.abs();
                        t.push((i as u32, j as u32, v));
                    }
                }
                row[i] += off + 0.5;
                t.push((i as u32, i as u32, 0.5 * (off + 0.5)));
                t.push((i as u32, i as u32, 0.5 * (off + 0.5)));
            }
            let b: Vec<f64> = (0..n).map(|_| rng.uniform() - 0.5).collect();
            let mut x = b.clone();
            let mut y = b.iter().map(|v| 2.0 * v).collect::<Vec<_>>();
            solve_general(n, &t, &mut [&mut x, &mut y]).unwrap();
            let expect = dense_solve(dense, b);
            assert!(max_diff(&x, &expect) < 1e-10);
            let twice: Vec<f64> = expect.iter().map(|v| 2.0 * v).collect();
            assert!(max_diff(&y, &twice) < 1e-10);
        }
    }

    #[test]
    fn singular_general_matrix_is_an_error() {
        // Rank 1: [[1, 2], [2, 4]]
        let t = [(0, 0, 1.0), (0, 1, 2.0), (1, 0, 2.0), (1, 1, 4.0)];
        let mut b = vec![1.0, 0.0];
        let r = solve_general(2, &t, &mut [&mut b]);
        assert!(r.is_err(), "{r:?} {b:?}");
        // Structurally singular: empty column 1
        let mut b = vec![1.0, 0.0];
        assert!(solve_general(2, &[(0, 0, 1.0), (1, 0, 1.0)], &mut [&mut b]).is_err());
    }
}

#[cfg(test)]
mod send_sync {
    #[test]
    fn spd_system_is_send_and_sync() {
        fn assert_send_sync<T: Send + Sync>() {}
        assert_send_sync::<super::SpdSystem>();
    }
}
