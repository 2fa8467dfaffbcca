//! [`Grid<T>`]: one value per node of the `N × N` grid over ω = `[0,1]²`, `N = 2^k + 1`.
//!
//! Why a type and not a `Vec` with `i · N + j` arithmetic at every use: the size is checked
//! once (a power of two plus one, so levels nest: every other node of level `k` is a node
//! of level `k − 1`), the node ↔ domain correspondence `ξ = (j, i) / (N − 1)` is written
//! once ([`Grid::node`]), and a scalar image, a metric image and a position image are
//! different types. The layout is row-major, node `(i, j)` at index `i · N + j`; row
//! `i = 0` is `ξ₁ = 0`, column `j` goes with `ξ₀`.
//!
//! Cost: a `Vec<T>` of `N²` values plus the size; all accessors are `O(1)`.

use std::ops::{Index, IndexMut};

use super::GridError;
use super::domain::{grid_level, node_position};

/// Values on the nodes of an `N × N` grid over ω = `[0,1]²`, `N = 2^k + 1`; node `(i, j)`
/// (row `i`, column `j`) sits at `ξ = (j, i) / (N − 1)` and is stored at `i · N + j`.
///
/// Constructors accept `3 ≤ N ≤ 4097` ([`grid_level`]); the `2 × 2` grid (`k = 0`) is
/// reached only by [`restrict`](Grid::restrict) or as the coarsest [`Pyramid`](super::Pyramid)
/// level, and every operation is defined on it.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid<T> {
    size: usize,
    data: Vec<T>,
}

impl<T: Clone> Grid<T> {
    /// A grid with every node set to `fill`.
    pub fn new(size: usize, fill: T) -> Result<Self, GridError> {
        grid_level(size)?;
        Ok(Self {
            size,
            data: vec![fill; size * size],
        })
    }
}

impl<T> Grid<T> {
    /// Wraps `data` (`size²` values, node `(i, j)` at `i · size + j`).
    pub fn from_vec(size: usize, data: Vec<T>) -> Result<Self, GridError> {
        grid_level(size)?;
        if data.len() != size * size {
            return Err(GridError::DataLength {
                size,
                len: data.len(),
            });
        }
        Ok(Self { size, data })
    }

    /// A grid with node `(i, j)` set to `f(i, j)`, filled row by row.
    pub fn from_fn(size: usize, mut f: impl FnMut(usize, usize) -> T) -> Result<Self, GridError> {
        grid_level(size)?;
        let data = (0..size * size).map(|k| f(k / size, k % size)).collect();
        Ok(Self { size, data })
    }

    /// For grids this module derives from valid ones (coarser, finer, filtered): `size`
    /// is `2^k + 1` with `0 ≤ k ≤ 12` and `data.len() == size²` by construction.
    pub(crate) fn from_parts(size: usize, data: Vec<T>) -> Self {
        debug_assert!(size >= 2 && (size - 1).is_power_of_two() && data.len() == size * size);
        Self { size, data }
    }

    /// `N`: nodes per side.
    #[inline]
    pub fn size(&self) -> usize {
        self.size
    }

    /// `k` with `N = 2^k + 1`.
    #[inline]
    pub fn level(&self) -> u32 {
        (self.size - 1).trailing_zeros()
    }

    /// Node spacing `h = 1 / (N − 1)` in domain units.
    #[inline]
    pub fn spacing(&self) -> f64 {
        1.0 / (self.size - 1) as f64
    }

    /// `N²`.
    #[inline]
    pub fn num_nodes(&self) -> usize {
        self.data.len()
    }

    /// Domain coordinates `ξ = (j, i) / (N − 1)` of node `(i, j)`.
    #[inline]
    pub fn node(&self, i: usize, j: usize) -> [f64; 2] {
        node_position(self.size, i, j)
    }

    /// The value at node `(i, j)`, or `None` outside the grid.
    #[inline]
    pub fn get(&self, i: usize, j: usize) -> Option<&T> {
        (i < self.size && j < self.size).then(|| &self.data[i * self.size + j])
    }

    /// Row `i` (the nodes `(i, 0..N)`, i.e. `ξ₁ = i / (N − 1)`).
    #[inline]
    pub fn row(&self, i: usize) -> &[T] {
        &self.data[i * self.size..(i + 1) * self.size]
    }

    /// All values, row-major.
    #[inline]
    pub fn as_slice(&self) -> &[T] {
        &self.data
    }

    /// All values, row-major, mutable.
    #[inline]
    pub fn as_mut_slice(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// The values, row-major.
    pub fn into_vec(self) -> Vec<T> {
        self.data
    }

    /// The values, row-major.
    pub fn iter(&self) -> std::slice::Iter<'_, T> {
        self.data.iter()
    }

    /// The values, row-major, mutable.
    pub fn iter_mut(&mut self) -> std::slice::IterMut<'_, T> {
        self.data.iter_mut()
    }

    /// The grid of `f(value)` at every node.
    pub fn map<U>(&self, f: impl FnMut(&T) -> U) -> Grid<U> {
        Grid {
            size: self.size,
            data: self.data.iter().map(f).collect(),
        }
    }

    /// Checks that `other` has this grid's size; `what` names it in the error.
    pub fn check_same_size<U>(&self, other: &Grid<U>, what: &'static str) -> Result<(), GridError> {
        if other.size == self.size {
            Ok(())
        } else {
            Err(GridError::SizeMismatch {
                what,
                got: other.size,
                want: self.size,
            })
        }
    }
}

impl<const D: usize> Grid<[f64; D]> {
    /// Component `c` of every value as a scalar grid (e.g. `g11` of a metric grid).
    /// Panics if `c ≥ D`.
    pub fn component(&self, c: usize) -> Grid<f64> {
        assert!(c < D, "component {c} of a {D}-vector");
        self.map(|v| v[c])
    }

    /// All components, node by node (`N² · D` values, C order of an `N × N × D` array).
    #[inline]
    pub fn as_flattened(&self) -> &[f64] {
        self.data.as_flattened()
    }
}

impl<T> Index<(usize, usize)> for Grid<T> {
    type Output = T;
    /// The value at node `(i, j)`; panics outside the grid.
    #[inline]
    fn index(&self, (i, j): (usize, usize)) -> &T {
        assert!(
            j < self.size,
            "column {j} outside the {0}×{0} grid",
            self.size
        );
        &self.data[i * self.size + j]
    }
}

impl<T> IndexMut<(usize, usize)> for Grid<T> {
    #[inline]
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut T {
        assert!(
            j < self.size,
            "column {j} outside the {0}×{0} grid",
            self.size
        );
        &mut self.data[i * self.size + j]
    }
}

impl<'a, T> IntoIterator for &'a Grid<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.data.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_is_row_major_with_xi0_along_the_columns() {
        let g = Grid::from_fn(5, |i, j| 10 * i + j).unwrap();
        assert_eq!((g.size(), g.level(), g.num_nodes()), (5, 2, 25));
        assert_eq!(g.spacing(), 0.25);
        assert_eq!(g[(3, 1)], 31);
        assert_eq!(g.as_slice()[3 * 5 + 1], 31);
        assert_eq!(g.row(2), &[20, 21, 22, 23, 24]);
        assert_eq!(g.node(3, 1), [0.25, 0.75]);
        assert_eq!(g.get(4, 4), Some(&44));
        assert_eq!(g.get(5, 0), None);
        assert_eq!(g.get(0, 5), None);
        let h = g.map(|&v| v as f64 * 0.5);
        assert_eq!(h[(4, 2)], 21.0);
        assert_eq!(
            g.iter().copied().sum::<usize>(),
            (&g).into_iter().sum::<usize>()
        );
        let mut m = g.clone();
        m[(0, 4)] = 7;
        m.iter_mut().for_each(|v| *v += 1);
        m.as_mut_slice()[0] = 0;
        assert_eq!((m[(0, 4)], m[(0, 0)], m[(1, 0)]), (8, 0, 11));
        assert_eq!(m.into_vec().len(), 25);
    }

    #[test]
    fn sizes_other_than_2k_plus_1_are_errors_that_suggest_sizes() {
        for bad in [0, 1, 2, 4, 100, 256, 8193] {
            let err = Grid::new(bad, 0.0).unwrap_err();
            assert_eq!(err, GridError::BadSize { size: bad });
            let msg = err.to_string();
            assert!(
                msg.contains(&bad.to_string()) && msg.contains("257"),
                "{msg}"
            );
        }
        assert!(Grid::new(4097, 0u8).is_ok());
        assert!(matches!(
            Grid::from_vec(3, vec![1.0; 8]),
            Err(GridError::DataLength { size: 3, len: 8 })
        ));
        assert!(Grid::from_fn(6, |i, j| i + j).is_err());
        let a = Grid::new(3, 0.0).unwrap();
        let b = Grid::new(5, false).unwrap();
        assert!(a.check_same_size(&a, "a").is_ok());
        let msg = a.check_same_size(&b, "the mask").unwrap_err().to_string();
        assert!(
            msg.contains("mask") && msg.contains("5×5") && msg.contains("3×3"),
            "{msg}"
        );
    }

    #[test]
    fn components_of_vector_grids() {
        let g = Grid::from_fn(3, |i, j| [i as f64, j as f64, 7.0]).unwrap();
        assert_eq!(g.component(1)[(2, 1)], 1.0);
        assert_eq!(g.as_flattened().len(), 27);
        assert_eq!(&g.as_flattened()[3 * 5..3 * 6], &[1.0, 2.0, 7.0]);
    }

    #[test]
    #[should_panic(expected = "column 3 outside")]
    fn indexing_past_a_row_end_panics_instead_of_wrapping() {
        let g = Grid::new(3, 0.0).unwrap();
        let _ = g[(0, 3)];
    }
}
