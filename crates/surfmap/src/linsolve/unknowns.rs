//! Numbering of a linear system's unknowns when some values are held fixed: the pinned
//! vertices of LSCM and of the ARAP step, the pinned coordinates of Newton (rigid
//! motions), the boundary of a fixed-boundary map. Free values are numbered in order,
//! fixed ones skipped, so a system over the free values is assembled by looking each
//! value up once.

/// The entry of [`Unknowns::as_slice`] for a fixed value.
pub const FIXED: u32 = u32::MAX;

/// `len` values numbered as unknowns `0..count` in order, skipping the fixed ones.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unknowns {
    index: Vec<u32>,
    count: usize,
}

impl Unknowns {
    /// Numbers the values `0..len`, skipping those listed in `fixed` (each `< len`;
    /// repeats are harmless).
    pub fn new(len: usize, fixed: impl IntoIterator<Item = usize>) -> Self {
        let mut index = vec![0u32; len];
        for f in fixed {
            index[f] = FIXED;
        }
        let mut count = 0u32;
        for slot in index.iter_mut().filter(|s| **s != FIXED) {
            *slot = count;
            count += 1;
        }
        Self {
            index,
            count: count as usize,
        }
    }

    /// How many values are unknowns (the system's dimension).
    pub fn count(&self) -> usize {
        self.count
    }

    /// How many values there are, fixed ones included.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// Whether there are no values at all.
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// The unknown of value `i`, or `None` when it is fixed.
    #[inline]
    pub fn get(&self, i: usize) -> Option<u32> {
        let k = self.index[i];
        (k != FIXED).then_some(k)
    }

    /// The unknown of every value, [`FIXED`] for the fixed ones.
    pub fn as_slice(&self) -> &[u32] {
        &self.index
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_values_are_numbered_in_order() {
        let u = Unknowns::new(6, [4, 1, 4]);
        assert_eq!(u.as_slice(), &[0, FIXED, 1, 2, FIXED, 3]);
        assert_eq!((u.count(), u.len()), (4, 6));
        assert_eq!((u.get(3), u.get(4)), (Some(2), None));
        let none_fixed = Unknowns::new(3, []);
        assert_eq!(none_fixed.as_slice(), &[0, 1, 2]);
        assert!(Unknowns::new(0, []).is_empty());
    }
}
