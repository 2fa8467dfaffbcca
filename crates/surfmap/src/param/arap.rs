//! As-rigid-as-possible warm start (Liu et al. 2008; Sorkine & Alexa 2007): cheap
//! local/global iterations that move the initial map toward an isometry before Newton.
//!
//! A free-boundary conformal map squeezes protrusions (areas shrunk by orders of
//! magnitude) and stretches triangles near the boundary; Newton on a barrier energy
//! undoes that slowly (a `1/d` barrier lets a squeezed triangle grow ~20 % per step).
//! One ARAP iteration is a *local* step — the closest rotation `R_T` to each
//! triangle's Jacobian — and a *global* step — the UVs minimizing
//! `Σ_T area(T)·‖J_T(u) − R_T‖²_F`, a linear system whose matrix (the cotangent
//! Laplacian) does not change, so it is factorized once and every iteration costs two
//! triangular solves. The caller uses the global solution only as a search direction,
//! with the flip-free bound and a decrease test on its own energy, so the warm start
//! can never flip a triangle or raise the energy.

use super::element::RestTriangle;
use crate::linsolve::{Ordering, SolveError, SpdSystem, Unknowns, VertexOrdering};

/// The factorized ARAP global step of one mesh.
pub struct ArapStep<'m> {
    triangles: &'m [[u32; 3]],
    rest: &'m [RestTriangle],
    /// Unknown of each vertex; the pinned one (fixes translation) is fixed.
    unknown: Unknowns,
    pinned: u32,
    system: SpdSystem,
}

/// `C[k][c] = ∂J[r][c]/∂u_k[r]`: `J = Σ_k u_k ⊗ C[k]` (corner `k`, rest axis `c`).
#[inline]
fn gradient_coefficients(rest: &RestTriangle) -> [[f64; 2]; 3] {
    let m = &rest.dm_inv;
    [
        [-(m[0][0] + m[1][0]), -(m[0][1] + m[1][1])],
        [m[0][0], m[0][1]],
        [m[1][0], m[1][1]],
    ]
}

impl<'m> ArapStep<'m> {
    /// Assembles and factorizes `K = Σ_T area(T)·C Cᵀ` (the cotangent Laplacian) with
    /// vertex `pinned` held fixed. `ordering`: the mesh's shared vertex ordering (the
    /// pinned vertex skipped), or `None` for AMD on `K`'s own pattern; the result does
    /// not depend on it (up to rounding), only the fill of the factor does.
    pub fn new(
        num_vertices: usize,
        triangles: &'m [[u32; 3]],
        rest: &'m [RestTriangle],
        pinned: u32,
        ordering: Option<&VertexOrdering>,
    ) -> Result<Self, SolveError> {
        let unknown = Unknowns::new(num_vertices, [pinned as usize]);
        let mut entries = Vec::with_capacity(6 * triangles.len());
        let mut values = Vec::with_capacity(6 * triangles.len());
        for (tri, r) in triangles.iter().zip(rest) {
            let c = gradient_coefficients(r);
            for i in 0..3 {
                for j in 0..=i {
                    if let (Some(a), Some(b)) =
                        (unknown.get(tri[i] as usize), unknown.get(tri[j] as usize))
                    {
                        entries.push((a, b));
                        values.push(r.area * (c[i][0] * c[j][0] + c[i][1] * c[j][1]));
                    }
                }
            }
        }
        let ordering = match ordering {
            Some(vertices) => vertices.expand(1, &unknown)?,
            None => Ordering::Amd,
        };
        let (mut system, slots) = SpdSystem::with_ordering(unknown.count(), &entries, &ordering)?;
        let v = system.values_mut();
        for (&s, &x) in slots.iter().zip(&values) {
            v[s as usize] += x;
        }
        system.factorize()?;
        Ok(Self {
            triangles,
            rest,
            unknown,
            pinned,
            system,
        })
    }

    /// One local/global iteration from `uv`: writes the ARAP global solution into
    /// `target` (the pinned vertex keeps its position).
    pub fn target(&self, uv: &[[f64; 2]], target: &mut Vec<[f64; 2]>) -> Result<(), SolveError> {
        let n = self.system.dim();
        let mut rhs = [vec![0.0; n], vec![0.0; n]];
        let pinned_uv = uv[self.pinned as usize];
        for (tri, r) in self.triangles.iter().zip(self.rest) {
            let corners = [
                uv[tri[0] as usize],
                uv[tri[1] as usize],
                uv[tri[2] as usize],
            ];
            let j = super::element::jacobian(r, &corners);
            // Closest rotation: the normalized conformal part of J.
            let (cs, sn) = (j[0][0] + j[1][1], j[1][0] - j[0][1]);
            let h = cs.hypot(sn);
            let rot = if h > 0.0 {
                [[cs / h, -sn / h], [sn / h, cs / h]]
            } else {
                [[1.0, 0.0], [0.0, 1.0]]
            };
            let c = gradient_coefficients(r);
            for k in 0..3 {
                let v = tri[k] as usize;
                // ∂/∂u_k of area·‖U C − R‖² gives area·(U C Cᵀ − R Cᵀ) for corner k.
                match self.unknown.get(v) {
                    Some(u) => {
                        for row in 0..2 {
                            let rc = rot[row][0] * c[k][0] + rot[row][1] * c[k][1];
                            rhs[row][u as usize] += r.area * rc;
                        }
                    }
                    // The pinned vertex's known value moves to the right-hand side.
                    None => {
                        let p = pinned_uv;
                        for l in 0..3 {
                            if let Some(w) = self.unknown.get(tri[l] as usize) {
                                let kl = r.area * (c[k][0] * c[l][0] + c[k][1] * c[l][1]);
                                rhs[0][w as usize] -= kl * p[0];
                                rhs[1][w as usize] -= kl * p[1];
                            }
                        }
                    }
                }
            }
        }
        for r in rhs.iter_mut() {
            self.system.solve_in_place(r)?;
        }
        target.clear();
        target.extend((0..self.unknown.len()).map(|v| match self.unknown.get(v) {
            Some(u) => [rhs[0][u as usize], rhs[1][u as usize]],
            None => uv[v],
        }));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::param::element::rest_triangles;

    #[test]
    fn global_step_reproduces_an_isometric_map() {
        // A planar grid mapped by a rotation: the local step finds that rotation, and
        // the global step returns the same map (it is the ARAP minimizer).
        let mesh = crate::mesh::generate::grid_disc(6);
        let rest = rest_triangles(&mesh.positions, &mesh.triangles).unwrap();
        let (c, s) = (0.6f64, 0.8f64);
        let uv: Vec<[f64; 2]> = mesh
            .positions
            .iter()
            .map(|p| [c * p[0] - s * p[1] + 3.0, s * p[0] + c * p[1] - 1.0])
            .collect();
        let step = ArapStep::new(uv.len(), &mesh.triangles, &rest, 0, None).unwrap();
        let mut target = Vec::new();
        step.target(&uv, &mut target).unwrap();
        for (a, b) in uv.iter().zip(&target) {
            assert!(
                (a[0] - b[0]).abs() < 1e-10 && (a[1] - b[1]).abs() < 1e-10,
                "{a:?} vs {b:?}"
            );
        }
    }

    #[test]
    fn iterations_move_a_stretched_map_toward_an_isometry() {
        // A planar grid mapped by a non-uniform stretch: ARAP iterations bring every
        // singular value toward 1.
        let mesh = crate::mesh::generate::grid_disc(8);
        let rest = rest_triangles(&mesh.positions, &mesh.triangles).unwrap();
        let mut uv: Vec<[f64; 2]> = mesh
            .positions
            .iter()
            .map(|p| [p[0] * (1.0 + p[0]), 0.3 * p[1]])
            .collect();
        let worst = |uv: &[[f64; 2]]| {
            mesh.triangles
                .iter()
                .zip(&rest)
                .map(|(t, r)| {
                    let j = crate::param::element::jacobian(
                        r,
                        &[uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]],
                    );
                    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
                    (det.ln()).abs()
                })
                .fold(0.0, f64::max)
        };
        let before = worst(&uv);
        let step = ArapStep::new(uv.len(), &mesh.triangles, &rest, 0, None).unwrap();
        let mut target = Vec::new();
        for _ in 0..20 {
            step.target(&uv, &mut target).unwrap();
            uv.clone_from(&target);
        }
        let after = worst(&uv);
        assert!(
            after < 1e-3 && after < before / 100.0,
            "max |log det J| {before} → {after}"
        );
    }

    #[test]
    fn shared_vertex_ordering_does_not_change_the_step() {
        let mesh = crate::mesh::generate::bumpy_disc(6, 0.4);
        let rest = rest_triangles(&mesh.positions, &mesh.triangles).unwrap();
        let uv: Vec<[f64; 2]> = mesh
            .positions
            .iter()
            .map(|p| [p[0] * (1.0 + 0.3 * p[1]), p[1] - 0.2 * p[0] * p[0]])
            .collect();
        let n = uv.len();
        let ordering = VertexOrdering::of_triangles(n, &mesh.triangles).unwrap();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        ArapStep::new(n, &mesh.triangles, &rest, 5, None)
            .unwrap()
            .target(&uv, &mut a)
            .unwrap();
        ArapStep::new(n, &mesh.triangles, &rest, 5, Some(&ordering))
            .unwrap()
            .target(&uv, &mut b)
            .unwrap();
        let diff = crate::testing::max_uv_difference(&a, &b);
        assert!(diff < 1e-9, "{diff}");
        assert!(a.iter().zip(&uv).any(|(p, q)| (p[0] - q[0]).abs() > 1e-3));
        let other = VertexOrdering::of_triangles(n + 1, &mesh.triangles).unwrap();
        assert!(matches!(
            ArapStep::new(n, &mesh.triangles, &rest, 5, Some(&other)),
            Err(SolveError::DimensionMismatch { .. })
        ));
    }
}
