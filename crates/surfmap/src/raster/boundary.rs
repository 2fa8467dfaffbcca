//! Boundary edges of a triangle list: edges used by exactly one triangle, kept in that
//! triangle's direction (so the surface lies to their left in a counter-clockwise
//! flattening). Computed by sorting edge keys, `O(F log F)`; no topology needed.

use rayon::prelude::*;

/// Directed boundary edges `[a, b]`.
pub fn boundary_edges(triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut keys: Vec<(u64, u32, u32)> = Vec::with_capacity(3 * triangles.len());
    for tri in triangles {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
            keys.push((key, a, b));
        }
    }
    keys.par_sort_unstable_by_key(|e| e.0);
    let mut out = Vec::new();
    let mut i = 0;
    while i < keys.len() {
        let mut j = i + 1;
        while j < keys.len() && keys[j].0 == keys[i].0 {
            j += 1;
        }
        if j - i == 1 {
            out.push([keys[i].1, keys[i].2]);
        }
        i = j;
    }
    out
}

/// `true` for every vertex on a boundary edge.
pub fn boundary_vertices(num_vertices: usize, triangles: &[[u32; 3]]) -> Vec<bool> {
    let mut on = vec![false; num_vertices];
    for [a, b] in boundary_edges(triangles) {
        on[a as usize] = true;
        on[b as usize] = true;
    }
    on
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_has_four_ccw_boundary_edges() {
        let mut e = boundary_edges(&[[0, 1, 2], [0, 2, 3]]);
        e.sort();
        assert_eq!(e, vec![[0, 1], [1, 2], [2, 3], [3, 0]]);
        assert_eq!(
            boundary_vertices(5, &[[0, 1, 2], [0, 2, 3]]),
            vec![true, true, true, true, false]
        );
    }
}
