//! Point location in a flattened triangle mesh: for any point `p` of the plane, the
//! triangle of the flattening that contains it and its barycentric coordinates (a
//! [`SurfacePoint`]), or "outside" — beyond the boundary or inside a hole. Surface
//! matching, texture transfer and morphs map a point of one surface to the other this
//! way, through the flattenings.
//!
//! **Barycentric coordinates** are signed-area ratios. For a UV triangle `(a, b, c)` with
//! edges `e1 = b − a`, `e2 = c − a` and `A = e1 × e2` (twice its signed area; `×` the 2D
//! cross product), and `d = p − a`:
//!
//! ```text
//! λ1 = (d × e2) / A    (area of (a, p, c) over the area of (a, b, c))
//! λ2 = (e1 × d) / A    (area of (a, b, p) over the area of (a, b, c))
//! λ0 = 1 − λ1 − λ2     (area of (p, b, c) over the area of (a, b, c))
//! ```
//!
//! so `p = λ0·a + λ1·b + λ2·c`, and `p` lies in the triangle iff all three are `≥ 0`.
//! Being ratios of signed areas, they do not depend on the orientation (a mirrored
//! flattening is located as well) nor on the triangle's size: the containment test
//! accepts `λm ≥ −1e-12` ([`TOLERANCE`]), so points on a shared edge or vertex, computed
//! in floating point, are always found. The triangle returned is the lowest-index one
//! that contains `p` (all `λ ≥ 0`); failing that (`p` within the tolerance of an edge but
//! in no triangle exactly) the one whose smallest `λ` is largest, with its coordinates
//! clamped to `≥ 0` and renormalized to sum 1.
//!
//! **Data structure**: an adaptive bucket grid. A uniform grid of square cells over the
//! bounding box has about as many cells as triangles; each triangle is listed in the
//! cells its footprint meets (its bounding box padded by the tolerance, then a
//! separating-axis test against its edges, so a long diagonal sliver is not listed all
//! over its box). A cell that still lists more than [`SPLIT_ABOVE`] triangles — where
//! the flattening is denser than average, as after a conformal map, whose triangle
//! areas can vary by 10⁷ — gets a grid of the same kind of its own, down to
//! [`MAX_DEPTH`] levels, unless that would not pay (fans around a vertex) or would
//! exceed a memory budget of [`REFINE_BUDGET`] entries per triangle. On a conformally
//! graded annulus (triangle areas varying by 10⁶) a query at a triangle's centroid
//! finds about 5 triangles listed in its cell instead of about 830 in one uniform grid
//! (the test `crowded_cells_are_refined_and_fans_are_not` prints both).
//!
//! Building costs `O(F)` time and memory for triangles about the size of their cells
//! (long thin triangles add the cells they cross). A query computes one cell per level
//! and the barycentric coordinates of the few triangles listed there, without
//! allocating. Degenerate UV triangles (zero area) cover no point and are left out.

use rayon::prelude::*;

use super::SurfacePoint;

/// Barycentric tolerance of the containment test: `p` is in a triangle when all its
/// barycentric coordinates are `≥ −TOLERANCE` (relative to the triangle: a distance of
/// `TOLERANCE` times the height over an edge).
pub const TOLERANCE: f64 = 1e-12;

/// A grid cell listing more triangles than this is refined by a grid of its own.
pub const SPLIT_ABOVE: usize = 16;

/// Largest number of grid levels, the top grid included.
pub const MAX_DEPTH: u32 = 8;

/// All refinements together may list at most this many entries per triangle, which
/// bounds their memory at `O(F)` whatever the mesh.
pub const REFINE_BUDGET: usize = 16;

/// Grid cells per listed triangle.
const CELLS_PER_TRIANGLE: f64 = 1.0;

/// Why a point locator cannot be built, and what to do about it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LocateError {
    #[error("no triangles were given: there is nothing to locate points in")]
    NoTriangles,
    #[error(
        "triangle {triangle} uses vertex {vertex}, but {num_uvs} UVs were given; pass one UV per vertex of the mesh"
    )]
    VertexOutOfRange {
        triangle: usize,
        vertex: u32,
        num_uvs: usize,
    },
    #[error(
        "the UV of vertex {vertex} (used by triangle {triangle}) is NaN or infinite; the flattening failed, flatten the mesh again"
    )]
    NonFiniteUv { vertex: u32, triangle: usize },
    #[error(
        "every triangle has zero area in the UV plane: the flattening is degenerate, flatten the mesh again"
    )]
    ZeroArea,
    #[error(
        "the locator would need {entries} grid entries, more than 2³² − 1: split the mesh into parts"
    )]
    TooLarge { entries: usize },
}

/// The closest point of the flattened domain to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    /// The closest point as a triangle and barycentric coordinates (`≥ 0`, sum 1).
    pub point: SurfacePoint,
    /// Its UV position.
    pub uv: [f64; 2],
    /// Its distance to the query point (0 when the query is inside the domain).
    pub distance: f64,
}

/// Point location in a flattened (2D, flip-free) triangle mesh; see the
/// [module documentation](self) for the math and the data structure.
///
/// Built once from one UV per vertex and the triangles; answers any number of queries,
/// from any number of threads.
///
/// ```
/// use surfmap::PointLocator;
///
/// // The unit square as two triangles.
/// let uvs = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
/// let triangles = [[0, 1, 2], [0, 2, 3]];
/// let locator = PointLocator::new(&uvs, &triangles)?;
///
/// let p = locator.locate([0.75, 0.25]).unwrap();
/// assert_eq!(p.triangle, 0);
/// let uv = p.interpolate(&uvs, &triangles);
/// assert!((uv[0] - 0.75).abs() < 1e-15 && (uv[1] - 0.25).abs() < 1e-15);
///
/// assert_eq!(locator.locate([1.5, 0.5]), None); // outside
/// let nearest = locator.nearest([1.5, 0.5]).unwrap(); // clamped onto the boundary
/// assert!((nearest.distance - 0.5).abs() < 1e-15);
/// # Ok::<(), surfmap::mesh::locate::LocateError>(())
/// ```
#[derive(Clone, Debug)]
pub struct PointLocator {
    /// Per triangle (by index): its barycentric coordinates as an affine map of `p`.
    affine: Vec<Affine>,
    /// Per triangle: its UV corners.
    corners: Vec<[[f64; 2]; 3]>,
    /// Bounding box of the UVs the triangles use.
    lo: [f64; 2],
    hi: [f64; 2],
    /// The grids; `grids[0]` covers the whole domain (padded), the others one cell each.
    grids: Vec<Grid>,
    /// Every grid's cells, row-major per grid: a range of `entries`, or a finer grid.
    cells: Vec<Cell>,
    /// Triangle indices listed by the leaf cells, ascending within each cell.
    entries: Vec<u32>,
}

/// The barycentric coordinates of one triangle as an affine function of `p`:
/// `λ1 = (p − a)·g1`, `λ2 = (p − a)·g2`, `λ0 = 1 − λ1 − λ2` (the cross products of the
/// module documentation, divided by `A` once).
#[derive(Clone, Copy, Debug)]
struct Affine {
    a: [f64; 2],
    g1: [f64; 2],
    g2: [f64; 2],
}

impl Affine {
    /// `None` for a degenerate triangle (zero or non-finite `1/A`).
    fn new([a, b, c]: [[f64; 2]; 3]) -> Option<Self> {
        let e1 = [b[0] - a[0], b[1] - a[1]];
        let e2 = [c[0] - a[0], c[1] - a[1]];
        let inv = 1.0 / (e1[0] * e2[1] - e1[1] * e2[0]);
        let g1 = [e2[1] * inv, -e2[0] * inv];
        let g2 = [-e1[1] * inv, e1[0] * inv];
        [g1, g2]
            .iter()
            .flatten()
            .all(|x| x.is_finite())
            .then_some(Self { a, g1, g2 })
    }

    /// A placeholder for a degenerate triangle (never listed in a cell).
    const NONE: Self = Self {
        a: [f64::NAN; 2],
        g1: [f64::NAN; 2],
        g2: [f64::NAN; 2],
    };

    #[inline(always)]
    fn barycentric(&self, p: [f64; 2]) -> [f64; 3] {
        let d = [p[0] - self.a[0], p[1] - self.a[1]];
        let l1 = d[0] * self.g1[0] + d[1] * self.g1[1];
        let l2 = d[0] * self.g2[0] + d[1] * self.g2[1];
        [1.0 - l1 - l2, l1, l2]
    }
}

/// A uniform grid of `nx × ny` cells of size `size` from `origin`; its cells are
/// `cells[first..first + nx·ny]`, row-major.
#[derive(Clone, Copy, Debug)]
struct Grid {
    origin: [f64; 2],
    size: [f64; 2],
    inv_size: [f64; 2],
    nx: u32,
    ny: u32,
    first: u32,
}

impl Grid {
    /// The cell of `p`, clamped into the grid: `⌊(p − origin) / size⌋` per axis. The
    /// saturating cast truncates, which is the floor for the non-negative values that
    /// are not clamped to 0 anyway. Monotone in each coordinate, so a triangle whose
    /// bounding box contains `p` is listed in `p`'s cell.
    #[inline(always)]
    fn cell_of(&self, p: [f64; 2]) -> [u32; 2] {
        [
            (((p[0] - self.origin[0]) * self.inv_size[0]) as u32).min(self.nx - 1),
            (((p[1] - self.origin[1]) * self.inv_size[1]) as u32).min(self.ny - 1),
        ]
    }

    #[inline(always)]
    fn index(&self, [ix, iy]: [u32; 2]) -> usize {
        self.first as usize + (iy as usize) * (self.nx as usize) + ix as usize
    }

    /// The rectangle `(lo, hi)` of cell `(ix, iy)`.
    fn cell_rect(&self, ix: u32, iy: u32) -> ([f64; 2], [f64; 2]) {
        let lo = [
            self.origin[0] + ix as f64 * self.size[0],
            self.origin[1] + iy as f64 * self.size[1],
        ];
        (lo, [lo[0] + self.size[0], lo[1] + self.size[1]])
    }
}

/// A cell: triangles `entries[start..end]`, or (`end == SUBGRID`) the grid `grids[start]`.
#[derive(Clone, Copy, Debug)]
struct Cell {
    start: u32,
    end: u32,
}

const SUBGRID: u32 = u32::MAX;

impl PointLocator {
    /// Builds the locator for a flattening: `uvs[v]` is the UV of vertex `v`, and
    /// `triangles` index into `uvs`. Only the vertices the triangles use need finite UVs.
    ///
    /// The flattening should be flip-free (an injective map); if triangles overlap,
    /// [`Self::locate`] returns the lowest-index one containing the point.
    pub fn new(uvs: &[[f64; 2]], triangles: &[[u32; 3]]) -> Result<Self, LocateError> {
        Self::with_max_depth(uvs, triangles, MAX_DEPTH)
    }

    /// [`Self::new`] with at most `max_depth` grid levels instead of [`MAX_DEPTH`]
    /// (`1`, or `0`, gives a single uniform grid: for comparisons).
    pub fn with_max_depth(
        uvs: &[[f64; 2]],
        triangles: &[[u32; 3]],
        max_depth: u32,
    ) -> Result<Self, LocateError> {
        if triangles.is_empty() {
            return Err(LocateError::NoTriangles);
        }
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        let mut corners = Vec::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            let mut c = [[0.0; 2]; 3];
            for (m, &v) in tri.iter().enumerate() {
                let uv = *uvs.get(v as usize).ok_or(LocateError::VertexOutOfRange {
                    triangle: t,
                    vertex: v,
                    num_uvs: uvs.len(),
                })?;
                if !(uv[0].is_finite() && uv[1].is_finite()) {
                    return Err(LocateError::NonFiniteUv {
                        vertex: v,
                        triangle: t,
                    });
                }
                for k in 0..2 {
                    lo[k] = lo[k].min(uv[k]);
                    hi[k] = hi[k].max(uv[k]);
                }
                c[m] = uv;
            }
            corners.push(c);
        }
        let affine: Vec<Affine> = corners
            .iter()
            .map(|&c| Affine::new(c).unwrap_or(Affine::NONE))
            .collect();
        // The non-degenerate triangles and their footprints: a point within the
        // tolerance of a triangle is in its padded box and within `pad` of its edges.
        let scale = lo.iter().chain(&hi).fold(0.0f64, |s, x| s.max(x.abs()));
        let mut footprints = vec![Footprint::default(); triangles.len()];
        let mut listed = Vec::with_capacity(triangles.len());
        let mut domain = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for (t, c) in corners.iter().enumerate() {
            if affine[t].a[0].is_nan() {
                continue;
            }
            let mut b = [c[0][0], c[0][1], c[0][0], c[0][1]];
            for p in &c[1..] {
                b = [
                    b[0].min(p[0]),
                    b[1].min(p[1]),
                    b[2].max(p[0]),
                    b[3].max(p[1]),
                ];
            }
            let pad = 1e-10 * ((b[2] - b[0]) + (b[3] - b[1])) + 8.0 * f64::EPSILON * scale;
            let b = [b[0] - pad, b[1] - pad, b[2] + pad, b[3] + pad];
            domain = [
                domain[0].min(b[0]),
                domain[1].min(b[1]),
                domain[2].max(b[2]),
                domain[3].max(b[3]),
            ];
            footprints[t] = Footprint { bbox: b, pad };
            listed.push(t as u32);
        }
        if listed.is_empty() {
            return Err(LocateError::ZeroArea);
        }
        let mut build = Build {
            corners: &corners,
            footprints: &footprints,
            max_depth: max_depth.max(1),
            budget: REFINE_BUDGET * listed.len(),
            grids: Vec::new(),
            cells: Vec::new(),
            entries: Vec::new(),
        };
        build.grid(domain, &listed, 0)?;
        let (grids, cells, entries) = (build.grids, build.cells, build.entries);
        Ok(Self {
            affine,
            corners,
            lo,
            hi,
            grids,
            cells,
            entries,
        })
    }

    /// Heap memory held by the locator, in bytes (about 120–150 per triangle).
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.affine.len() * size_of::<Affine>()
            + self.corners.len() * size_of::<[[f64; 2]; 3]>()
            + self.grids.len() * size_of::<Grid>()
            + self.cells.len() * size_of::<Cell>()
            + self.entries.len() * size_of::<u32>()
    }

    /// Bounding box `(min, max)` of the UVs of the triangles' vertices.
    pub fn bounds(&self) -> ([f64; 2], [f64; 2]) {
        (self.lo, self.hi)
    }

    /// The triangles listed for `p`'s leaf cell (`p` inside the top grid's rectangle).
    #[inline(always)]
    fn candidates(&self, p: [f64; 2]) -> &[u32] {
        let mut grid = &self.grids[0];
        loop {
            let cell = self.cells[grid.index(grid.cell_of(p))];
            if cell.end == SUBGRID {
                grid = &self.grids[cell.start as usize];
            } else {
                return &self.entries[cell.start as usize..cell.end as usize];
            }
        }
    }

    /// Whether `p` lies in the top grid's rectangle (false for NaN).
    #[inline(always)]
    fn in_grid(&self, p: [f64; 2]) -> bool {
        let g = &self.grids[0];
        let hi = [
            g.origin[0] + g.nx as f64 * g.size[0],
            g.origin[1] + g.ny as f64 * g.size[1],
        ];
        p[0] >= g.origin[0] && p[0] <= hi[0] && p[1] >= g.origin[1] && p[1] <= hi[1]
    }

    /// The triangle containing `p` and `p`'s barycentric coordinates in it (`≥ 0`, sum
    /// 1), or `None` when `p` is outside the flattened domain: beyond its boundary,
    /// inside a hole, or not finite. See the [module documentation](self) for the
    /// tolerance and which triangle a point on an edge gets.
    #[inline]
    pub fn locate(&self, p: [f64; 2]) -> Option<SurfacePoint> {
        if !self.in_grid(p) {
            return None;
        }
        let mut best: Option<(u32, [f64; 3], f64)> = None;
        for &t in self.candidates(p) {
            let l = self.affine[t as usize].barycentric(p);
            let min = l[0].min(l[1]).min(l[2]);
            if min >= 0.0 {
                return Some(SurfacePoint {
                    triangle: t,
                    barycentric: l,
                });
            }
            if min >= -TOLERANCE && best.is_none_or(|b| min > b.2) {
                best = Some((t, l, min));
            }
        }
        best.map(|(t, l, _)| SurfacePoint {
            triangle: t,
            barycentric: clamp_barycentric(l),
        })
    }

    /// [`Self::locate`] for every point, in parallel; `result[i]` belongs to `points[i]`.
    pub fn locate_many(&self, points: &[[f64; 2]]) -> Vec<Option<SurfacePoint>> {
        points
            .par_iter()
            .with_min_len(1024)
            .map(|&p| self.locate(p))
            .collect()
    }

    /// The closest point of the flattened domain to `p`, with its distance: `p` itself
    /// (distance 0) when [`Self::locate`] finds it, otherwise `p` clamped onto the
    /// nearest triangle, a point of the domain's boundary. `None` only when `p` is not
    /// finite.
    ///
    /// Searches the top grid's cells in rings around `p`'s cell (clamped to the grid)
    /// until the ring is farther than the best triangle found; the cost grows with the
    /// number of cells closer to `p` than the domain, so it suits points slightly
    /// outside, such as those that rounding or a smooth map pushed over the boundary.
    pub fn nearest(&self, p: [f64; 2]) -> Option<Nearest> {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return None;
        }
        if let Some(point) = self.locate(p) {
            return Some(Nearest {
                point,
                uv: p,
                distance: 0.0,
            });
        }
        let g = &self.grids[0];
        // q: p clamped into the grid. For any point c of the grid,
        // |p − c|² ≥ |p − q|² + |q − c|², and a cell in ring r around q's cell is at
        // least (r − 1) cells from q along one axis.
        let hi = [
            g.origin[0] + g.nx as f64 * g.size[0],
            g.origin[1] + g.ny as f64 * g.size[1],
        ];
        let q = [
            p[0].clamp(g.origin[0], hi[0]),
            p[1].clamp(g.origin[1], hi[1]),
        ];
        let to_grid2 = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
        let step = g.size[0].min(g.size[1]) * (1.0 - 1e-9);
        let [cx, cy] = g.cell_of(q).map(i64::from);
        let (nx, ny) = (i64::from(g.nx), i64::from(g.ny));
        let mut best = Best::NONE;
        let visit = |ix: i64, iy: i64, best: &mut Best| {
            if (0..nx).contains(&ix) && (0..ny).contains(&iy) {
                self.nearest_in_cell(g, ix as u32, iy as u32, p, best);
            }
        };
        for r in 0..nx.max(ny) {
            let gap = (r - 1).max(0) as f64 * step;
            if to_grid2 + gap * gap >= best.distance2 {
                break;
            }
            // The ring: rows cy ± r in full, columns cx ± r between them.
            for ix in (cx - r).max(0)..=(cx + r).min(nx - 1) {
                visit(ix, cy - r, &mut best);
                if r > 0 {
                    visit(ix, cy + r, &mut best);
                }
            }
            for iy in (cy - r + 1).max(0)..=(cy + r - 1).min(ny - 1) {
                visit(cx - r, iy, &mut best);
                if r > 0 {
                    visit(cx + r, iy, &mut best);
                }
            }
        }
        // The domain has a triangle, so the search found one.
        (best.distance2.is_finite()).then(|| Nearest {
            point: best.point,
            uv: best.uv,
            distance: (best.uv[0] - p[0]).hypot(best.uv[1] - p[1]),
        })
    }

    /// Updates `best` with the triangles of cell `(ix, iy)` of `grid` (and of its finer
    /// grids) that may come closer to `p`.
    fn nearest_in_cell(&self, grid: &Grid, ix: u32, iy: u32, p: [f64; 2], best: &mut Best) {
        let (lo, hi) = grid.cell_rect(ix, iy);
        if rect_distance2(p, lo, hi) >= best.distance2 {
            return;
        }
        let cell = self.cells[grid.index([ix, iy])];
        if cell.end == SUBGRID {
            let sub = &self.grids[cell.start as usize];
            for jy in 0..sub.ny {
                for jx in 0..sub.nx {
                    self.nearest_in_cell(sub, jx, jy, p, best);
                }
            }
            return;
        }
        for &t in &self.entries[cell.start as usize..cell.end as usize] {
            let c = self.corners[t as usize];
            for m in 0..3 {
                let n = (m + 1) % 3;
                let (u, e) = (c[m], [c[n][0] - c[m][0], c[n][1] - c[m][1]]);
                let s = (((p[0] - u[0]) * e[0] + (p[1] - u[1]) * e[1])
                    / (e[0] * e[0] + e[1] * e[1]))
                    .clamp(0.0, 1.0);
                let x = [u[0] + s * e[0], u[1] + s * e[1]];
                let d2 = (p[0] - x[0]).powi(2) + (p[1] - x[1]).powi(2);
                if d2 < best.distance2 {
                    let mut barycentric = [0.0; 3];
                    barycentric[m] = 1.0 - s;
                    barycentric[n] = s;
                    *best = Best {
                        distance2: d2,
                        point: SurfacePoint {
                            triangle: t,
                            barycentric,
                        },
                        uv: x,
                    };
                }
            }
        }
    }
}

/// Where a triangle may hold points within the tolerance: its bounding box
/// `[xmin, ymin, xmax, ymax]` grown by `pad`, and the points within `pad` of the inner
/// side of each edge.
#[derive(Clone, Copy, Debug, Default)]
struct Footprint {
    bbox: [f64; 4],
    pad: f64,
}

/// The grids under construction, and what building them needs.
struct Build<'a> {
    corners: &'a [[[f64; 2]; 3]],
    footprints: &'a [Footprint],
    max_depth: u32,
    /// Entries refinements may still list.
    budget: usize,
    grids: Vec<Grid>,
    cells: Vec<Cell>,
    entries: Vec<u32>,
}

impl Build<'_> {
    /// Whether triangle `t`'s footprint meets the rectangle `[lo, hi]` (its bounding
    /// box is known to): separating-axis test on the triangle's edges, with the
    /// rectangle grown by the pad and the edges moved out by it. Conservative: a point
    /// of the rectangle within the tolerance of the triangle always passes.
    fn overlaps(&self, t: u32, lo: [f64; 2], hi: [f64; 2]) -> bool {
        let c = self.corners[t as usize];
        let pad = self.footprints[t as usize].pad;
        let (lo, hi) = ([lo[0] - pad, lo[1] - pad], [hi[0] + pad, hi[1] + pad]);
        let area2 =
            (c[1][0] - c[0][0]) * (c[2][1] - c[0][1]) - (c[1][1] - c[0][1]) * (c[2][0] - c[0][0]);
        let sign = area2.signum();
        (0..3).all(|m| {
            let (a, b) = (c[m], c[(m + 1) % 3]);
            // Inward normal of edge a → b; the rectangle's corner farthest along it.
            let n = [-(b[1] - a[1]) * sign, (b[0] - a[0]) * sign];
            let x = [
                if n[0] > 0.0 { hi[0] } else { lo[0] },
                if n[1] > 0.0 { hi[1] } else { lo[1] },
            ];
            n[0] * (x[0] - a[0]) + n[1] * (x[1] - a[1]) >= -pad * n[0].hypot(n[1])
        })
    }

    /// Appends a grid over `rect` (`[xmin, ymin, xmax, ymax]`, positive extent) listing
    /// the triangles `tris` (ascending) in the cells they overlap, refining crowded
    /// cells, and returns its index. A refinement (`depth > 0`) is declined (`None`)
    /// when it would not pay — more than half of the triangles per cell on average, as
    /// for a fan around a high-valence vertex, whose triangles all share the cell of the
    /// vertex — or when its entries would exceed the budget left.
    fn grid(
        &mut self,
        rect: [f64; 4],
        tris: &[u32],
        depth: u32,
    ) -> Result<Option<u32>, LocateError> {
        let (w, h) = (rect[2] - rect[0], rect[3] - rect[1]);
        // Square cells, about CELLS_PER_TRIANGLE per triangle; any aspect ratio.
        let cells = (tris.len() as f64 * CELLS_PER_TRIANGLE).ceil().max(1.0);
        let nx = (cells * w / h).sqrt().round().clamp(1.0, cells);
        let ny = (cells / nx).round().max(1.0);
        let (nx, ny) = (nx as u32, ny as u32);
        let size = [w / nx as f64, h / ny as f64];
        let grid = Grid {
            origin: [rect[0], rect[1]],
            size,
            inv_size: [1.0 / size[0], 1.0 / size[1]],
            nx,
            ny,
            first: index_u32(self.cells.len())?,
        };
        let num_cells = nx as usize * ny as usize;

        // Counting sort of (cell, triangle) pairs into CSR order; triangles stay
        // ascending within a cell.
        let for_cells_of = |t: u32, f: &mut dyn FnMut(usize)| {
            let b = self.footprints[t as usize].bbox;
            let [x0, y0] = grid.cell_of([b[0], b[1]]);
            let [x1, y1] = grid.cell_of([b[2], b[3]]);
            let whole = x0 == x1 || y0 == y1;
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let (lo, hi) = grid.cell_rect(x, y);
                    if whole || self.overlaps(t, lo, hi) {
                        f((y * nx + x) as usize);
                    }
                }
            }
        };
        let mut start = vec![0usize; num_cells + 1];
        for &t in tris {
            for_cells_of(t, &mut |c| start[c + 1] += 1);
        }
        for c in 0..num_cells {
            start[c + 1] += start[c];
        }
        let listed = start[num_cells];
        let n = tris.len();
        if depth > 0 && (listed > self.budget || 2 * listed > n * num_cells) {
            return Ok(None);
        }
        let mut fill = start.clone();
        let mut list = vec![0u32; listed];
        for &t in tris {
            for_cells_of(t, &mut |c| {
                list[fill[c]] = t;
                fill[c] += 1;
            });
        }

        if depth > 0 {
            self.budget -= listed;
        }
        let index = index_u32(self.grids.len())?;
        self.grids.push(grid);
        self.cells
            .resize(grid.first as usize + num_cells, Cell { start: 0, end: 0 });
        for c in 0..num_cells {
            let here = &list[start[c]..start[c + 1]];
            let mut cell = None;
            if here.len() > SPLIT_ABOVE && depth + 1 < self.max_depth {
                let (lo, hi) = grid.cell_rect(c as u32 % nx, c as u32 / nx);
                cell = self
                    .grid([lo[0], lo[1], hi[0], hi[1]], here, depth + 1)?
                    .map(|sub| Cell {
                        start: sub,
                        end: SUBGRID,
                    });
            }
            let cell = match cell {
                Some(cell) => cell,
                None => {
                    let begin = index_u32(self.entries.len())?;
                    self.entries.extend_from_slice(here);
                    Cell {
                        start: begin,
                        end: index_u32(self.entries.len())?,
                    }
                }
            };
            self.cells[grid.first as usize + c] = cell;
        }
        Ok(Some(index))
    }
}

/// The best candidate of a nearest-point search so far.
struct Best {
    distance2: f64,
    point: SurfacePoint,
    uv: [f64; 2],
}

impl Best {
    const NONE: Self = Self {
        distance2: f64::INFINITY,
        point: SurfacePoint {
            triangle: 0,
            barycentric: [0.0; 3],
        },
        uv: [0.0; 2],
    };
}

/// Squared distance from `p` to the rectangle `[lo, hi]`.
#[inline]
fn rect_distance2(p: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> f64 {
    let dx = (lo[0] - p[0]).max(p[0] - hi[0]).max(0.0);
    let dy = (lo[1] - p[1]).max(p[1] - hi[1]).max(0.0);
    dx * dx + dy * dy
}

/// Barycentric coordinates within the tolerance, clamped to `≥ 0` and renormalized.
#[inline]
fn clamp_barycentric(l: [f64; 3]) -> [f64; 3] {
    let l = l.map(|x| x.max(0.0));
    let sum = l[0] + l[1] + l[2];
    l.map(|x| x / sum)
}

/// `n` as a `u32` grid index, or the error that says the grid outgrew them.
fn index_u32(n: usize) -> Result<u32, LocateError> {
    u32::try_from(n)
        .ok()
        .filter(|&i| i != SUBGRID)
        .ok_or(LocateError::TooLarge { entries: n })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;
    use crate::mesh::generate::{bumpy_disc, grid_disc, polar_disc};
    use crate::testing::Rng;
    use std::collections::HashMap;

    /// The planar coordinates of a generated planar mesh.
    fn xy(mesh: &TriMesh) -> Vec<[f64; 2]> {
        mesh.positions.iter().map(|p| [p[0], p[1]]).collect()
    }

    fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }

    /// Barycentric coordinates as the three sub-triangle areas over the whole (each
    /// computed on its own, not as one minus the others).
    fn brute_barycentric(c: [[f64; 2]; 3], p: [f64; 2]) -> [f64; 3] {
        let area = orient(c[0], c[1], c[2]);
        [
            orient(p, c[1], c[2]) / area,
            orient(c[0], p, c[2]) / area,
            orient(c[0], c[1], p) / area,
        ]
    }

    fn corners(uvs: &[[f64; 2]], tri: [u32; 3]) -> [[f64; 2]; 3] {
        tri.map(|v| uvs[v as usize])
    }

    /// Every triangle that contains `p` within the tolerance, by brute force.
    fn brute_containing(uvs: &[[f64; 2]], triangles: &[[u32; 3]], p: [f64; 2]) -> Vec<u32> {
        (0..triangles.len() as u32)
            .filter(|&t| {
                let l = brute_barycentric(corners(uvs, triangles[t as usize]), p);
                l.iter().all(|&x| x >= -TOLERANCE)
            })
            .collect()
    }

    /// Distance from `p` to the closest point of any triangle, by brute force.
    fn brute_distance(uvs: &[[f64; 2]], triangles: &[[u32; 3]], p: [f64; 2]) -> f64 {
        let segment = |a: [f64; 2], b: [f64; 2]| {
            let (ab, ap) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
            let s =
                ((ap[0] * ab[0] + ap[1] * ab[1]) / (ab[0] * ab[0] + ab[1] * ab[1])).clamp(0.0, 1.0);
            (ap[0] - s * ab[0]).hypot(ap[1] - s * ab[1])
        };
        triangles
            .iter()
            .map(|&tri| {
                let c = corners(uvs, tri);
                if brute_barycentric(c, p).iter().all(|&x| x >= 0.0) {
                    0.0
                } else {
                    (0..3)
                        .map(|m| segment(c[m], c[(m + 1) % 3]))
                        .fold(f64::INFINITY, f64::min)
                }
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Checks a located point: coordinates ≥ 0 summing to 1 that reconstruct `p`.
    fn assert_reconstructs(uvs: &[[f64; 2]], triangles: &[[u32; 3]], s: SurfacePoint, p: [f64; 2]) {
        let l = s.barycentric;
        assert!(l.iter().all(|&x| x >= 0.0), "{s:?}");
        assert!((l[0] + l[1] + l[2] - 1.0).abs() < 1e-14, "{s:?}");
        let q = s.interpolate(uvs, triangles);
        let err = (q[0] - p[0]).hypot(q[1] - p[1]);
        assert!(err < 1e-12, "{p:?} reconstructed as {q:?} from {s:?}");
    }

    /// A uniformly random point of triangle `c` whose barycentric coordinates are all at
    /// least `margin`.
    fn random_interior(rng: &mut Rng, margin: f64) -> [f64; 3] {
        let (mut a, mut b) = (rng.uniform(), rng.uniform());
        if a + b > 1.0 {
            (a, b) = (1.0 - a, 1.0 - b);
        }
        let l = [1.0 - a - b, a, b];
        let k = 1.0 - 3.0 * margin;
        l.map(|x| margin + k * x)
    }

    /// A test domain: `(name, uvs, triangles)`.
    type Domain = (&'static str, Vec<[f64; 2]>, Vec<[u32; 3]>);

    fn domains() -> Vec<Domain> {
        let disc = polar_disc(12, 40);
        let grid = grid_disc(16);
        // Very anisotropic: the grid stretched to 1000 × 0.001.
        let thin = xy(&grid)
            .iter()
            .map(|p| [1e3 * p[0], 1e-3 * p[1]])
            .collect();
        // Mirrored (clockwise triangles).
        let mirrored = xy(&disc).iter().map(|p| [-p[0], p[1]]).collect();
        // Graded: r → r³ makes the center triangles ~10⁶ times smaller in area.
        let fine = polar_disc(40, 96);
        let graded = xy(&fine)
            .iter()
            .map(|p| {
                let r2 = p[0] * p[0] + p[1] * p[1];
                [p[0] * r2, p[1] * r2]
            })
            .collect();
        let (spiral_uvs, spiral_tris) = spiral();
        let (annulus_uvs, annulus_tris) = annulus();
        let conformal = conformal_annulus();
        vec![
            ("disc", xy(&disc), disc.triangles.clone()),
            ("grid", xy(&grid), grid.triangles.clone()),
            ("thin grid", thin, grid.triangles.clone()),
            ("mirrored disc", mirrored, disc.triangles),
            ("graded disc", graded, fine.triangles),
            ("spiral", spiral_uvs, spiral_tris),
            ("annulus", annulus_uvs, annulus_tris),
            ("conformal annulus", conformal.0, conformal.1),
            (
                "flattened bumpy disc",
                flattened_bumpy_disc(),
                bumpy_disc(10, 0.4).triangles,
            ),
        ]
    }

    /// A strip rolled up into two turns of a spiral: non-convex, its turns 0.25 apart.
    fn spiral() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let (n, m) = (200usize, 4usize);
        let mut uvs = Vec::new();
        for j in 0..=m {
            for i in 0..=n {
                let (u, v) = (i as f64 / n as f64, j as f64 / m as f64);
                let (theta, r) = (4.0 * std::f64::consts::PI * u, 0.2 + 0.6 * u + 0.05 * v);
                uvs.push([r * theta.cos(), r * theta.sin()]);
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut tris = Vec::new();
        for j in 0..m {
            for i in 0..n {
                tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (uvs, tris)
    }

    /// The unit polar disc without its triangles inside radius 0.4: a hole.
    fn annulus() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let disc = polar_disc(10, 48);
        let uvs = xy(&disc);
        let tris = disc
            .triangles
            .iter()
            .filter(|t| {
                t.iter()
                    .all(|&v| uvs[v as usize][0].hypot(uvs[v as usize][1]) > 0.35)
            })
            .copied()
            .collect();
        (uvs, tris)
    }

    fn flattened_bumpy_disc() -> Vec<[f64; 2]> {
        use crate::param::flatten::{FlattenOptions, flatten};
        let map = flatten(&bumpy_disc(10, 0.4), &FlattenOptions::default()).unwrap();
        assert_eq!(map.flipped_triangles, 0);
        map.uvs
    }

    #[test]
    fn centroids_and_interior_points_are_found_in_their_triangle() {
        let mut rng = Rng(0x5eed);
        for (name, uvs, tris) in domains() {
            let locator = PointLocator::new(&uvs, &tris).unwrap();
            for (t, &tri) in tris.iter().enumerate() {
                let c = corners(&uvs, tri);
                let mut samples = vec![[1.0 / 3.0; 3]];
                samples.extend((0..4).map(|_| random_interior(&mut rng, 1e-6)));
                for l in samples {
                    let p = [0, 1].map(|k| l[0] * c[0][k] + l[1] * c[1][k] + l[2] * c[2][k]);
                    let s = locator
                        .locate(p)
                        .unwrap_or_else(|| panic!("{name}: {p:?} lost"));
                    assert_eq!(s.triangle as usize, t, "{name}: {p:?}");
                    for m in 0..3 {
                        assert!(
                            (s.barycentric[m] - l[m]).abs() < 1e-9,
                            "{name}: {s:?} vs {l:?}"
                        );
                    }
                    assert_reconstructs(&uvs, &tris, s, p);
                }
            }
        }
    }

    #[test]
    fn points_on_edges_and_vertices_are_found() {
        let mut rng = Rng(77);
        for (name, uvs, tris) in domains() {
            let locator = PointLocator::new(&uvs, &tris).unwrap();
            for &tri in &tris {
                for m in 0..3 {
                    let (a, b) = (uvs[tri[m] as usize], uvs[tri[(m + 1) % 3] as usize]);
                    // The vertex itself: found in a triangle that has it as a corner.
                    let s = locator
                        .locate(a)
                        .unwrap_or_else(|| panic!("{name}: vertex {a:?}"));
                    let at = tris[s.triangle as usize].iter().position(|&v| v == tri[m]);
                    assert!(
                        at.is_some_and(|k| s.barycentric[k] > 1.0 - 1e-9),
                        "{name}: {s:?}"
                    );
                    // Points of the edge, rounded as computed.
                    for t in [0.5, rng.uniform(), rng.uniform()] {
                        let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                        let s = locator
                            .locate(p)
                            .unwrap_or_else(|| panic!("{name}: edge {p:?}"));
                        assert_reconstructs(&uvs, &tris, s, p);
                        assert!(brute_containing(&uvs, &tris, p).contains(&s.triangle));
                        assert_eq!(locator.locate(p), Some(s), "deterministic");
                    }
                }
            }
        }
    }

    #[test]
    fn points_outside_and_in_holes_are_not_found() {
        let disc = polar_disc(12, 40);
        let locator = PointLocator::new(&xy(&disc), &disc.triangles).unwrap();
        let mut rng = Rng(3);
        for _ in 0..2000 {
            let angle = rng.range(0.0, std::f64::consts::TAU);
            let r = rng.range(1.0 + 1e-9, 3.0);
            assert_eq!(locator.locate([r * angle.cos(), r * angle.sin()]), None);
        }
        for p in [
            [1e300, 0.0],
            [f64::NAN, 0.0],
            [0.0, f64::INFINITY],
            [-5.0, -5.0],
        ] {
            assert_eq!(locator.locate(p), None, "{p:?}");
        }
        // The annulus: the hole (r < 0.35·cos(π/48), inside its inner polygon) is outside.
        let (uvs, tris) = annulus();
        let locator = PointLocator::new(&uvs, &tris).unwrap();
        for _ in 0..2000 {
            let (angle, r) = (rng.range(0.0, std::f64::consts::TAU), rng.range(0.0, 0.39));
            let p = [r * angle.cos(), r * angle.sin()];
            assert_eq!(locator.locate(p), None, "{p:?} is in the hole");
            let r = rng.range(0.41, 0.99);
            assert!(locator.locate([r * angle.cos(), r * angle.sin()]).is_some());
        }
    }

    /// A uniformly random point of the locator's bounds grown by `margin` times their
    /// size on every side.
    fn random_around(rng: &mut Rng, locator: &PointLocator, margin: f64) -> [f64; 2] {
        let (lo, hi) = locator.bounds();
        [0, 1].map(|k| {
            let grow = margin * (hi[k] - lo[k]);
            rng.range(lo[k] - grow, hi[k] + grow)
        })
    }

    #[test]
    fn locate_many_agrees_with_brute_force() {
        let mut rng = Rng(2024);
        for (name, uvs, tris) in domains() {
            let locator = PointLocator::new(&uvs, &tris).unwrap();
            let points: Vec<[f64; 2]> = (0..10_000)
                .map(|_| random_around(&mut rng, &locator, 0.1))
                .collect();
            let found = locator.locate_many(&points);
            let inside = found.iter().flatten().count();
            assert!(inside > 1000, "{name}: only {inside} points inside");
            for (&p, s) in points.iter().zip(&found) {
                let brute = brute_containing(&uvs, &tris, p);
                match s {
                    None => assert!(brute.is_empty(), "{name}: {p:?} missed, in {brute:?}"),
                    Some(s) => {
                        // Random points do not hit edges: exactly one triangle holds them.
                        assert_eq!(brute, vec![s.triangle], "{name}: {p:?}");
                        assert_reconstructs(&uvs, &tris, *s, p);
                    }
                }
                assert_eq!(*s, locator.locate(p), "serial and parallel agree");
            }
        }
    }

    /// Whether the vertices with non-zero weight lie on the boundary: a boundary edge
    /// (used by one triangle) or an endpoint of one.
    fn on_boundary(tris: &[[u32; 3]], s: &SurfacePoint) -> bool {
        let mut uses: HashMap<(u32, u32), usize> = HashMap::new();
        for t in tris {
            for m in 0..3 {
                let (a, b) = (t[m], t[(m + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let tri = tris[s.triangle as usize];
        let support: Vec<u32> = (0..3)
            .filter(|&m| s.barycentric[m] > 0.0)
            .map(|m| tri[m])
            .collect();
        match support[..] {
            [v] => uses.iter().any(|(e, &n)| n == 1 && (e.0 == v || e.1 == v)),
            [a, b] => uses[&(a.min(b), a.max(b))] == 1,
            _ => false,
        }
    }

    #[test]
    fn nearest_clamps_outside_points_onto_the_boundary() {
        let mut rng = Rng(99);
        for (name, uvs, tris) in domains() {
            let locator = PointLocator::new(&uvs, &tris).unwrap();
            let mut outside = 0;
            for _ in 0..400 {
                let p = random_around(&mut rng, &locator, 0.5);
                let n = locator.nearest(p).unwrap();
                let expected = brute_distance(&uvs, &tris, p);
                assert!(
                    (n.distance - expected).abs() <= 1e-12 * (1.0 + expected),
                    "{name}: {p:?}: {} vs {expected}",
                    n.distance
                );
                assert_reconstructs(&uvs, &tris, n.point, n.uv);
                assert!((n.uv[0] - p[0]).hypot(n.uv[1] - p[1]) == n.distance);
                match locator.locate(p) {
                    Some(s) => assert_eq!((n.point, n.distance), (s, 0.0)),
                    None => {
                        outside += 1;
                        assert!(on_boundary(&tris, &n.point), "{name}: {p:?} → {n:?}");
                    }
                }
            }
            assert!(outside > 50, "{name}: {outside} points outside");
        }
        // Analytic: the unit square, from a side and from a corner.
        let square = grid_disc(3);
        let locator = PointLocator::new(&xy(&square), &square.triangles).unwrap();
        let n = locator.nearest([1.5, 0.25]).unwrap();
        assert!((n.distance - 0.5).abs() < 1e-15 && (n.uv[1] - 0.25).abs() < 1e-15);
        let n = locator.nearest([-3.0, -4.0]).unwrap();
        assert_eq!((n.distance, n.uv), (5.0, [0.0, 0.0]));
        assert_eq!(locator.nearest([f64::NAN, 0.0]), None);
    }

    /// The conformal image of a 64 × 71 grid of squares under `(s, θ) ↦ e^s (cos θ, sin θ)`
    /// for `s ∈ [−7, 0]`: well-shaped triangles whose area shrinks by e¹⁴ ≈ 10⁶ towards
    /// the hole of radius e⁻⁷, as in a conformal flattening with a protrusion.
    fn conformal_annulus() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let (n, m) = (64usize, 71usize);
        let mut uvs = Vec::new();
        for j in 0..=m {
            for i in 0..n {
                let (s, theta) = (
                    -7.0 * j as f64 / m as f64,
                    std::f64::consts::TAU * i as f64 / n as f64,
                );
                uvs.push([s.exp() * theta.cos(), s.exp() * theta.sin()]);
            }
        }
        let id = |i: usize, j: usize| (j * n + i % n) as u32;
        let mut tris = Vec::new();
        for j in 0..m {
            for i in 0..n {
                tris.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
                tris.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            }
        }
        (uvs, tris)
    }

    #[test]
    fn crowded_cells_are_refined_and_fans_are_not() {
        // Queries distributed like the triangles (their centroids): the candidates the
        // refined grids test against those of one uniform grid.
        let (uvs, tris) = conformal_annulus();
        let mean_candidates = |locator: &PointLocator| {
            let total: usize = tris
                .iter()
                .map(|&t| {
                    let c = corners(&uvs, t);
                    let p = [0, 1].map(|k| (c[0][k] + c[1][k] + c[2][k]) / 3.0);
                    locator.candidates(p).len()
                })
                .sum();
            total as f64 / tris.len() as f64
        };
        let refined = PointLocator::new(&uvs, &tris).unwrap();
        let uniform = PointLocator::with_max_depth(&uvs, &tris, 1).unwrap();
        assert_eq!(uniform.grids.len(), 1);
        let (r, u) = (mean_candidates(&refined), mean_candidates(&uniform));
        eprintln!(
            "conformal annulus: {} grids, {} entries for {} triangles; mean candidates {r} (uniform grid {u})",
            refined.grids.len(),
            refined.entries.len(),
            tris.len(),
        );
        assert!(r < SPLIT_ABOVE as f64 && 20.0 * r < u, "{r} vs {u}");
        // A fan of 2000 triangles around one vertex: refining cannot separate them
        // there, and the refinements stay within their budget.
        let fan = polar_disc(1, 2000);
        let uniform = PointLocator::with_max_depth(&xy(&fan), &fan.triangles, 1).unwrap();
        let locator = PointLocator::new(&xy(&fan), &fan.triangles).unwrap();
        eprintln!(
            "fan: {} grids, {} entries (uniform grid {})",
            locator.grids.len(),
            locator.entries.len(),
            uniform.entries.len()
        );
        assert!(locator.entries.len() <= uniform.entries.len() + REFINE_BUDGET * 2000);
        let mut rng = Rng(5);
        for _ in 0..1000 {
            let p = rng.point(0.7);
            let s = locator.locate(p).unwrap();
            assert_eq!(
                brute_containing(&xy(&fan), &fan.triangles, p),
                vec![s.triangle]
            );
        }
    }

    #[test]
    fn bounds_are_the_uvs_of_the_triangles() {
        // Vertex 4 is unused: its (even non-finite) UV does not count.
        let uvs = [
            [0.0, -1.0],
            [2.0, 0.0],
            [1.0, 3.0],
            [0.5, 0.5],
            [f64::NAN, 9.0],
        ];
        let locator = PointLocator::new(&uvs, &[[0, 1, 2], [0, 2, 3]]).unwrap();
        assert_eq!(locator.bounds(), ([0.0, -1.0], [2.0, 3.0]));
    }

    #[test]
    fn degenerate_triangles_are_skipped() {
        // Triangle 1 is a zero-area sliver on the shared edge of triangles 0 and 2.
        let uvs = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.5, 0.5]];
        let tris = [[0, 1, 2], [1, 4, 2], [1, 3, 2]];
        let locator = PointLocator::new(&uvs, &tris).unwrap();
        assert_eq!(locator.locate([0.5, 0.5]).map(|s| s.triangle), Some(0));
        assert_eq!(locator.locate([0.9, 0.9]).map(|s| s.triangle), Some(2));
        assert_eq!(locator.nearest([2.0, 2.0]).unwrap().point.triangle, 2);
    }

    #[test]
    fn bad_input_is_named() {
        let uvs = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert_eq!(
            PointLocator::new(&uvs, &[]).unwrap_err(),
            LocateError::NoTriangles
        );
        let err = PointLocator::new(&uvs, &[[0, 1, 2], [0, 2, 7]]).unwrap_err();
        assert_eq!(
            err,
            LocateError::VertexOutOfRange {
                triangle: 1,
                vertex: 7,
                num_uvs: 3
            }
        );
        assert!(
            err.to_string().contains("triangle 1 uses vertex 7"),
            "{err}"
        );
        let nan = [[0.0, 0.0], [1.0, f64::NAN], [0.0, 1.0]];
        let err = PointLocator::new(&nan, &[[0, 1, 2]]).unwrap_err();
        assert_eq!(
            err,
            LocateError::NonFiniteUv {
                vertex: 1,
                triangle: 0
            }
        );
        assert!(err.to_string().contains("vertex 1"), "{err}");
        let line = [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]];
        let err = PointLocator::new(&line, &[[0, 1, 2], [1, 1, 2]]).unwrap_err();
        assert_eq!(err, LocateError::ZeroArea);
    }
}
