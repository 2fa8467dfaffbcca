//! UV charts of a map: faces joined across a mesh edge whose two endpoints carry the
//! same UVs in both faces. A single-disc map is one chart; an atlas has several.
//! Used to decide orientation per chart: a chart mirrored as a whole is a valid chart,
//! not a set of flipped triangles (the referee `distortion.py` does the same).

/// One side of a UV triangle: its vertex pair (smaller first), the UVs at those two
/// vertices (bit patterns, in the same order), and which face and corner it comes from.
/// Two faces are glued in UV along a side exactly when both keys are equal.
#[derive(Clone, Copy, Debug)]
pub struct UvSide {
    pub vertices: [u32; 2],
    pub uv_bits: [u64; 4],
    pub face: u32,
    /// The side runs from corner `corner` to corner `corner + 1` of `face`.
    pub corner: u8,
}

impl UvSide {
    /// Same vertices and same UVs: the two faces are glued along this side.
    pub fn same_side(&self, other: &UvSide) -> bool {
        self.vertices == other.vertices && self.uv_bits == other.uv_bits
    }
}

/// Every side of every UV triangle, sorted so that glued sides are adjacent.
pub fn sorted_uv_sides(triangles: &[[u32; 3]], corner_uvs: &[[[f64; 2]; 3]]) -> Vec<UvSide> {
    let mut sides = Vec::with_capacity(3 * triangles.len());
    for (t, (tri, uv)) in triangles.iter().zip(corner_uvs).enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let (ua, ub) = (uv[k], uv[(k + 1) % 3]);
            let (lo, hi, ulo, uhi) = if a <= b {
                (a, b, ua, ub)
            } else {
                (b, a, ub, ua)
            };
            sides.push(UvSide {
                vertices: [lo, hi],
                uv_bits: [
                    ulo[0].to_bits(),
                    ulo[1].to_bits(),
                    uhi[0].to_bits(),
                    uhi[1].to_bits(),
                ],
                face: t as u32,
                corner: k as u8,
            });
        }
    }
    sides.sort_unstable_by_key(|s| (s.vertices, s.uv_bits));
    sides
}

/// Chart label `0..k` of every face, and the number of charts `k`.
#[allow(clippy::needless_range_loop)]
pub fn chart_labels(triangles: &[[u32; 3]], corner_uvs: &[[[f64; 2]; 3]]) -> (Vec<u32>, usize) {
    let n = triangles.len();
    let sides = sorted_uv_sides(triangles, corner_uvs);
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for w in sides.windows(2) {
        if w[0].same_side(&w[1]) {
            let (ra, rb) = (find(&mut parent, w[0].face), find(&mut parent, w[1].face));
            if ra != rb {
                parent[ra as usize] = rb;
            }
        }
    }
    let mut label_of_root = vec![u32::MAX; n];
    let mut labels = vec![0u32; n];
    let mut k = 0u32;
    for t in 0..n {
        let r = find(&mut parent, t as u32) as usize;
        if label_of_root[r] == u32::MAX {
            label_of_root[r] = k;
            k += 1;
        }
        labels[t] = label_of_root[r];
    }
    (labels, k as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seam_splits_charts_and_shared_uvs_join_them() {
        let tris = [[0, 1, 2], [2, 1, 3], [4, 5, 6]];
        let a = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let joined = [
            a,
            [[0.0, 1.0], [1.0, 0.0], [1.0, 1.0]],
            [[9.0, 9.0], [10.0, 9.0], [9.0, 10.0]],
        ];
        let (l, k) = chart_labels(&tris, &joined);
        assert_eq!(k, 2);
        assert_eq!(l[0], l[1]);
        assert_ne!(l[0], l[2]);
        let seam = [a, [[5.0, 1.0], [6.0, 0.0], [6.0, 1.0]], joined[2]];
        assert_eq!(chart_labels(&tris, &seam).1, 3);
    }
}
