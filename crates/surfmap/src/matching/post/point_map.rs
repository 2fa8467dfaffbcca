//! Points of A carried onto B through φ: a point of A's parameter domain to φ's image in
//! B's, located on B's surface (snapped onto it from within [`SNAP_CELLS`](super::super::options::SNAP_CELLS) grid cells).

use super::super::MatchError;
use super::super::prepare::surface::MatchSurface;
use super::super::solve::Solved;
use crate::mesh::{PointLocator, SurfacePoint};

/// Maps surface points of A onto B through a match (built once: a point locator over
/// B's parameter domain).
pub(crate) struct PointMap<'a> {
    a: &'a MatchSurface,
    b: &'a MatchSurface,
    solved: &'a Solved,
    locator: PointLocator,
    tolerance: f64,
}

impl<'a> PointMap<'a> {
    /// The map of A onto B that `solved`'s φ makes; points φ carries within `snap_cells`
    /// finest-grid cells of B's surface are snapped onto it ([`SNAP_CELLS`](super::super::options::SNAP_CELLS)).
    pub fn new(
        a: &'a MatchSurface,
        b: &'a MatchSurface,
        solved: &'a Solved,
        snap_cells: f64,
    ) -> Result<Self, MatchError> {
        let locator = PointLocator::new(&b.uvs, &b.triangles)
            .map_err(|e| MatchError::Input(format!("locating points on B: {e}")))?;
        let to_b = b.images.transform;
        let tolerance = snap_cells / (solved.deformation.size - 1) as f64 / to_b.scale;
        Ok(Self {
            a,
            b,
            solved,
            locator,
            tolerance,
        })
    }

    /// The counterpart on B of a point of A's parameter domain `uv` (A's UV units), or
    /// `None` where φ carries it off B's surface. A point that φ puts within
    /// [`SNAP_CELLS`](super::super::options::SNAP_CELLS) grid cells of B's surface is snapped onto it.
    #[cfg(test)]
    pub fn map_uv(&self, uv: [f64; 2]) -> Option<SurfacePoint> {
        self.locate(self.image(uv))
    }

    /// Where φ carries a point of A's parameter domain `uv` (A's UV units), in B's UV
    /// units (anywhere in the plane: off B's surface too).
    pub fn image(&self, uv: [f64; 2]) -> [f64; 2] {
        let xi = self.a.images.transform.to_domain(uv);
        self.b.images.transform.to_uv(self.solved.map_domain(xi))
    }

    /// The point of B's surface at `target` in B's UV, snapped onto it from within
    /// [`SNAP_CELLS`](super::super::options::SNAP_CELLS) grid cells; `None` farther off.
    pub fn locate(&self, target: [f64; 2]) -> Option<SurfacePoint> {
        self.locator.locate(target).or_else(|| {
            self.locator
                .nearest(target)
                .filter(|n| n.distance <= self.tolerance)
                .map(|n| n.point)
        })
    }

    /// The counterpart on B of a point of A's surface (a triangle of A and barycentric
    /// coordinates), or `None`.
    #[cfg(test)]
    pub fn map(&self, p: SurfacePoint) -> Option<SurfacePoint> {
        let a = self.a;
        if p.triangle as usize >= a.triangles.len() {
            return None;
        }
        let [u, v, w] = a.triangles[p.triangle as usize].map(|i| a.uvs[i as usize]);
        let b = p.barycentric;
        self.map_uv(std::array::from_fn(|c| {
            b[0] * u[c] + b[1] * v[c] + b[2] * w[c]
        }))
    }
}
