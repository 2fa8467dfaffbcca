//! The ARAP warm start: a few as-rigid-as-possible steps that move a start map toward an
//! isometry before Newton ([`crate::param::arap`]), each used only as a search direction
//! and accepted when it keeps the map flip-free (and, with the barrier, free of boundary
//! contact) and lowers the energy minimized first.

use super::error::FlattenError;
use super::start::align_pins;
use crate::energy::Energy;
use crate::linsolve::VertexOrdering;
use crate::mesh::TriMesh;
use crate::param::arap::ArapStep;
use crate::param::barrier::BoundaryBarrier;
use crate::param::element::RestTriangle;
use crate::param::flip_free::max_flip_free_step;
use crate::param::newton::NewtonSolver;

/// ARAP warm-start iterations at most, and the relative energy decrease below which
/// they stop (Newton takes over).
const WARM_START_MAX_ITERATIONS: usize = 30;
const WARM_START_MIN_GAIN: f64 = 0.05;

/// Halvings of an ARAP step before the warm start gives up.
const STEP_HALVINGS: usize = 6;

/// Runs the warm start on `uv` (pinned at `pins`, unit-area units) and re-pins it;
/// returns the steps accepted. The energy decreased is the continuation's first stage
/// when `objective` has one. With `contact` (the barrier solve's boundary) no step may
/// bring the boundary into contact.
pub(super) fn arap_warm_start(
    uv: &mut Vec<[f64; 2]>,
    mesh: &TriMesh,
    rest: &[RestTriangle],
    contact: Option<&[u32]>,
    objective: &Energy,
    (p0, p1): (u32, u32),
    ordering: &VertexOrdering,
) -> Result<usize, FlattenError> {
    let contact =
        contact.map(|boundary| BoundaryBarrier::new(boundary, uv).with_faces(&mesh.triangles));
    let first_energy = match objective.continuation_start() {
        Some(from) => Energy::litke(from),
        None => *objective,
    };
    let arap = ArapStep::new(
        mesh.positions.len(),
        &mesh.triangles,
        rest,
        p0,
        Some(ordering),
    )?;
    let evaluate = NewtonSolver::energy_of(rest, &mesh.triangles);
    let mut energy = evaluate(uv, &first_energy);
    let (mut target, mut direction, mut trial) = (Vec::new(), vec![[0.0; 2]; uv.len()], uv.clone());
    let mut accepted_steps = 0;
    for _ in 0..WARM_START_MAX_ITERATIONS {
        arap.target(uv, &mut target)?;
        for ((d, t), u) in direction.iter_mut().zip(&target).zip(uv.iter()) {
            *d = [t[0] - u[0], t[1] - u[1]];
        }
        let mut bound = max_flip_free_step(uv, &mesh.triangles, &direction);
        if let Some(contact) = &contact {
            bound = bound.min(contact.max_step(uv, &direction, bound.min(1.0)));
        }
        let mut step = 1.0f64.min(0.9 * bound);
        let mut accepted = None;
        for _ in 0..STEP_HALVINGS {
            for ((tr, u), d) in trial.iter_mut().zip(uv.iter()).zip(&direction) {
                *tr = [u[0] + step * d[0], u[1] + step * d[1]];
            }
            let e = evaluate(&trial, &first_energy);
            if e < energy {
                accepted = Some(e);
                break;
            }
            step *= 0.5;
        }
        let Some(e) = accepted else { break };
        let gain = (energy - e) / energy;
        std::mem::swap(uv, &mut trial);
        energy = e;
        accepted_steps += 1;
        if gain < WARM_START_MIN_GAIN {
            break;
        }
    }
    align_pins(uv, p0, p1);
    Ok(accepted_steps)
}
