//! The one-call flattening (thesis §3.1): checks that the input is a disc, computes the
//! initial map (free-boundary conformal, with an injective fallback, or the multilevel
//! start for large meshes), normalizes scale, runs projected Newton (with optional
//! α-continuation), verifies the result has no flipped triangle, and returns UVs in the
//! mesh's own units.
//!
//! [`FlattenOptions`] says what to minimize ([`Energy`](crate::Energy)), where to start
//! ([`Start`], [`Multilevel`]) and whether holes are filled for the solve; the defaults
//! (balanced α, automatic start, ARAP warm start) suit most meshes.
//!
//! The parts, each importing only those below it: this entry point (the plan — fill,
//! cut — around the solve) → `solve` (one disc: Newton with continuation, the barrier
//! or the scaffold) → `warm_start` (ARAP steps) → `start` (initial maps, the multilevel
//! start) → `result` ([`Flattening`]) → `error` ([`FlattenError`]) → `options`
//! ([`FlattenOptions`]); `settings` ([`FlattenSettings`]: the front ends' names and
//! numbers, the presets) resolves into options. The multilevel start flattens a decimated copy with this entry
//! point, which is handed down to it rather than imported.

mod error;
mod options;
mod result;
mod settings;
mod solve;
mod start;
mod warm_start;

use crate::mesh::{Topology, TriMesh};
use crate::param::optcuts;
use crate::param::plan::{Prepared, map_back, plan_with_topology, prepare};
use crate::param::protrusions::{Protruded, Refuse, cut_protrusions};
use std::time::Instant;

/// Flattens a disc-topology mesh (module docs) with `options`.
///
/// Errors name the problem and the remedy: a mesh that is not a disc gets every defect
/// with the repair that fixes it ([`FlattenError::NotADisc`]).
pub fn flatten(mesh: &TriMesh, options: &FlattenOptions) -> Result<Flattening, FlattenError> {
    flatten_with_progress(mesh, options, &mut |_| {})
}

/// [`flatten`] with a callback receiving every Newton iteration's log entry as it
/// happens (for progress bars; the same entries end up in [`Flattening::log`]).
pub fn flatten_with_progress(
    mesh: &TriMesh,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&IterationLog),
) -> Result<Flattening, FlattenError> {
    let clock = Instant::now();
    options.validate()?;
    mesh.check_indices()?;
    let topology = Topology::new(mesh);
    let mut plan = plan_with_topology(mesh, &topology, options)?;
    if matches!(options.start, Start::Given(_)) && !plan.is_disc_as_is() {
        return Err(match plan.cut {
            None => FlattenError::GivenStartWithFilledHoles(plan.holes_to_fill),
            Some(_) => FlattenError::GivenStartWithCut(plan.describe()),
        });
    }
    // The fill's vertices come after the original ones and the cut's copies after
    // those: mapping back drops them (the holes stay open in the map).
    let (prepared, topology) = if plan.is_disc_as_is() {
        let disc = TriMesh::new(mesh.positions.clone(), mesh.triangles.clone());
        (
            Prepared {
                mesh: disc,
                opened: None,
            },
            Some(topology),
        )
    } else {
        drop(topology);
        (prepare(mesh, &mut plan, options)?, None)
    };
    let time_prepare = clock.elapsed().as_secs_f64();
    let input_faces = mesh.triangles.len();
    let (mut prepared, mut result) =
        solve_prepared(input_faces, prepared, topology, options, progress)?;
    if let Some(bound) = &options.max_distortion {
        let protrusion_cuts = result.protrusion_cuts.take();
        (prepared, result) =
            optcuts::cut_to_bound(input_faces, prepared, result, bound, options, progress)?;
        result.protrusion_cuts = protrusion_cuts;
    }
    // Seams with no topological reason were cut along protrusions or for the
    // distortion bound.
    let reason = plan
        .cut
        .clone()
        .unwrap_or(if result.protrusion_cuts.is_some() {
            CutReason::Protrusions
        } else {
            CutReason::Distortion
        });
    let (uvs, seams) = map_back(mesh, prepared, reason, std::mem::take(&mut result.uvs));
    result.uvs = uvs;
    result.seams = seams;
    result.holes_filled = plan.holes_to_fill;
    result.plan = plan;
    result.time_prepare = time_prepare;
    result.time_total = clock.elapsed().as_secs_f64();
    Ok(result)
}

/// The solve of the disc `prepared` (its first `input_faces` triangles the input's;
/// `topology`: its topology, if derived), cut along protrusions first when its start
/// cannot embed it ([`crate::param::protrusions`]; not with a given or explicit start,
/// nor with [`Cut::Never`], whose map must stay one UV per vertex): with the automatic
/// start, a chart solved from
/// LSCM is checked before the solve (and its LSCM map reused by it), one solved from the
/// multilevel start only when the solve finds no admissible single-level start. Returns
/// the disc solved, and the flattening with [`Flattening::protrusion_cuts`].
fn solve_prepared(
    input_faces: usize,
    prepared: Prepared,
    topology: Option<Topology>,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&IterationLog),
) -> Result<(Prepared, Flattening), FlattenError> {
    let (Start::Auto { multilevel }, Cut::Auto | Cut::Along(_)) = (&options.start, &options.cut)
    else {
        let result =
            solve::flatten_used(&prepared.mesh, topology, options, progress, flatten, None)?;
        return Ok((prepared, result));
    };
    if multilevel
        .coarse_level(prepared.mesh.triangles.len())
        .is_none()
    {
        let protruded = cut_protrusions(input_faces, prepared, Refuse::CrushedOrFlipped)?;
        return solve_protruded(protruded, topology, options, progress);
    }
    // The multilevel start does not compute LSCM: a large chart is checked only when no
    // start embeds it (the single-level fallback's error), then cut and solved again.
    match solve::flatten_used(&prepared.mesh, topology, options, progress, flatten, None) {
        Ok(result) => Ok((prepared, result)),
        Err(FlattenError::NoAdmissibleStart { .. }) => {
            let protruded = cut_protrusions(input_faces, prepared, Refuse::Flipped)?;
            solve_protruded(protruded, None, options, progress)
        }
        Err(e) => Err(e),
    }
}

/// The solve of a disc after [`cut_protrusions`] (`topology`: that of the disc before,
/// if derived: used when it was not cut), from its initial maps when computed.
fn solve_protruded(
    protruded: Protruded,
    topology: Option<Topology>,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&IterationLog),
) -> Result<(Prepared, Flattening), FlattenError> {
    let Protruded {
        prepared,
        cuts,
        maps,
    } = protruded;
    let topology = topology.filter(|_| cuts.is_none());
    let mut result =
        solve::flatten_used(&prepared.mesh, topology, options, progress, flatten, maps)?;
    result.protrusion_cuts = cuts;
    Ok((prepared, result))
}

/// The flattening of `mesh`'s vertices used by a triangle (the others at the origin),
/// without the plan: `mesh` must be a disc (`topology`: its topology, if derived). The
/// distortion cuts flatten each round's chart with it.
pub(crate) fn flatten_used(
    mesh: &TriMesh,
    topology: Option<Topology>,
    options: &FlattenOptions,
    progress: &mut dyn FnMut(&IterationLog),
) -> Result<Flattening, FlattenError> {
    solve::flatten_used(mesh, topology, options, progress, flatten, None)
}

pub use crate::param::newton::{IterationLog, NewtonSettings, NewtonTimings, StopReason};
pub use crate::param::optcuts::{CutRound, CutStop, DistortionCuts, MaxDistortion};
pub use crate::param::plan::{Cut, CutReason, Seams};
pub use crate::param::protrusions::ProtrusionCuts;
pub use error::{FlattenError, Remedies};
pub use options::{Bijective, CoarseLevel, FlattenOptions, Multilevel, OptionError, Start};
pub use result::{Flattening, Guarantee, MultilevelReport, StartMap};
pub use settings::{EnergyKind, FlattenSettings, MultilevelKind, Preset, SettingsError, StartKind};

#[cfg(test)]
mod tests;
