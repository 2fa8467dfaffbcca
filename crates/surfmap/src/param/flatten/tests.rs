//! The entry point's behaviour: refusals with their remedies, holes, starts, options.

use super::*;
use crate::energy::{Alpha, Energy};
use crate::mesh::IndexError;
use crate::mesh::generate::{bumpy_disc, grid_disc};
use crate::mesh::repair::{fill_holes, reorient};
use crate::param::count_flipped;

#[test]
fn inconsistent_orientation_is_refused_with_advice_and_reorient_fixes_it() {
    let mut mesh = bumpy_disc(6, 0.3);
    mesh.triangles[40].swap(1, 2);
    let err = flatten(&mesh, &FlattenOptions::default()).unwrap_err();
    assert!(matches!(err, FlattenError::NotADisc(_)), "{err}");
    assert!(err.to_string().contains("repair::reorient"), "{err}");
    let (fixed, flipped) = reorient(&mesh).unwrap();
    assert_eq!(flipped, 1);
    let map = flatten(&fixed, &FlattenOptions::default()).unwrap();
    assert_eq!(map.flipped_triangles, 0);
}

#[test]
fn unreferenced_vertices_are_carried_through() {
    let mut mesh = bumpy_disc(5, 0.3);
    mesh.positions.push([9.0, 9.0, 9.0]);
    let map = flatten(&mesh, &FlattenOptions::default()).unwrap();
    assert_eq!(map.uvs.len(), mesh.positions.len());
    assert_eq!(map.uvs[mesh.positions.len() - 1], [0.0, 0.0]);
    assert_eq!(count_flipped(&map.uvs, &mesh.triangles), 0);
}

#[test]
fn warm_start_reaches_the_same_minimum_with_fewer_newton_iterations() {
    // A cap deep enough that the conformal start squeezes its pole region.
    let mesh = crate::mesh::generate::spherical_cap(1.0, 2.4, 16, 48);
    let cold = flatten(
        &mesh,
        &FlattenOptions {
            warm_start: false,
            ..Default::default()
        },
    )
    .unwrap();
    let warm = flatten(&mesh, &FlattenOptions::default()).unwrap();
    assert!(warm.warm_start_iterations > 0);
    assert!(warm.converged && cold.converged);
    assert!(
        (warm.energy - cold.energy).abs() <= 1e-9 * cold.energy,
        "{} vs {}",
        warm.energy,
        cold.energy
    );
    assert!(
        warm.iterations < cold.iterations,
        "{} vs {}",
        warm.iterations,
        cold.iterations
    );
    assert_eq!(warm.flipped_triangles, 0);
}

#[test]
fn a_given_start_is_used_in_mesh_units_and_checked() {
    let mesh = bumpy_disc(8, 0.4);
    let first = flatten(&mesh, &FlattenOptions::default()).unwrap();
    // Restarting from a converged map (in the mesh's units) needs no iteration.
    let again = flatten(
        &mesh,
        &FlattenOptions::default().with_start(Start::Given(first.uvs.clone())),
    )
    .unwrap();
    assert_eq!(again.start, StartMap::Given);
    assert_eq!(again.start_description(), "given");
    assert!(again.iterations <= 1, "{}", again.iterations);
    assert!((again.energy - first.energy).abs() <= 1e-10 * first.energy);
    // A start with a flipped triangle is refused, not repaired silently.
    let mut folded = first.uvs.clone();
    let t = mesh.triangles[0];
    folded[t[0] as usize] = [
        folded[t[1] as usize][0] + folded[t[2] as usize][0] - folded[t[0] as usize][0],
        folded[t[1] as usize][1] + folded[t[2] as usize][1] - folded[t[0] as usize][1],
    ];
    let err = flatten(
        &mesh,
        &FlattenOptions::default().with_start(Start::Given(folded)),
    )
    .unwrap_err();
    assert!(
        matches!(err, FlattenError::GivenStartFlipped(n) if n >= 1),
        "{err}"
    );
    let err = flatten(
        &mesh,
        &FlattenOptions::default().with_start(Start::Given(vec![[0.0; 2]; 3])),
    )
    .unwrap_err();
    assert!(err.to_string().contains("3 UVs"), "{err}");
}

#[test]
fn out_of_range_index_is_an_error_not_a_panic() {
    let mut mesh = bumpy_disc(3, 0.3);
    mesh.triangles[2][1] = 10_000;
    let err = flatten(&mesh, &FlattenOptions::default()).unwrap_err();
    assert!(
        matches!(
            err,
            FlattenError::Index(IndexError {
                triangle: 2,
                corner: 1,
                vertex: 10_000,
                ..
            })
        ),
        "{err}"
    );
    // Also with holes to fill (the fill needs the topology, hence valid indices).
    let err = flatten(&mesh, &FlattenOptions::default().with_fill_holes(true)).unwrap_err();
    assert!(matches!(err, FlattenError::Index(_)), "{err}");
}

/// A grid disc with two interior faces' stars removed: three boundary loops.
fn disc_with_two_holes() -> TriMesh {
    let mut mesh = grid_disc(8);
    // Vertices (2, 2) and (5, 4) of the 9×9 grid, index j·9 + i.
    let holes = [2 * 9 + 2, 4 * 9 + 5];
    mesh.triangles
        .retain(|t| !holes.iter().any(|h| t.contains(h)));
    mesh
}

#[test]
fn holes_are_filled_for_the_solve_and_stay_open_in_the_map() {
    let mesh = disc_with_two_holes();
    let never = FlattenOptions::default()
        .with_fill_holes(false)
        .with_cut(Cut::Never);
    let err = flatten(&mesh, &never).unwrap_err();
    assert!(err.to_string().contains("fill_holes"), "{err}");
    let map = flatten(&mesh, &FlattenOptions::default()).unwrap();
    assert_eq!(map.plan.describe(), "fill 2 holes");
    assert!(map.seams.is_none());
    assert_eq!(map.holes_filled, 2);
    assert_eq!(map.uvs.len(), mesh.positions.len());
    assert_eq!(count_flipped(&map.uvs, &mesh.triangles), 0);
    // The same as filling by hand and dropping the fill's vertices.
    let (filled, holes) = fill_holes(&mesh);
    assert_eq!(holes, 2);
    let by_hand = flatten(&filled, &FlattenOptions::default()).unwrap();
    assert_eq!(&by_hand.uvs[..mesh.positions.len()], &map.uvs[..]);
    // A planar grid flattens to an isometry: hole or not, every edge keeps its length.
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let l3 = crate::vec3::norm3(crate::vec3::sub3(mesh.positions[a], mesh.positions[b]));
            let l2 = (map.uvs[a][0] - map.uvs[b][0]).hypot(map.uvs[a][1] - map.uvs[b][1]);
            assert!((l2 - l3).abs() < 1e-6 * l3, "{l2} vs {l3}");
        }
    }
    // Without holes the option changes nothing.
    let plain = grid_disc(4);
    let a = flatten(&plain, &FlattenOptions::default()).unwrap();
    let b = flatten(&plain, &FlattenOptions::default().with_fill_holes(true)).unwrap();
    assert_eq!((a.uvs, b.holes_filled), (b.uvs, 0));
    // A given start has no UVs for the fill.
    let err = flatten(
        &mesh,
        &FlattenOptions::default()
            .with_fill_holes(true)
            .with_start(Start::Given(map.uvs.clone())),
    )
    .unwrap_err();
    assert!(
        matches!(err, FlattenError::GivenStartWithFilledHoles(2)),
        "{err}"
    );
}

#[test]
fn normalized_uvs_fit_the_unit_square() {
    let mesh = bumpy_disc(6, 0.3);
    let map = flatten(&mesh, &FlattenOptions::default()).unwrap();
    let n = map.normalized_uvs();
    let (lo, hi) = n
        .iter()
        .fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        });
    assert_eq!(lo, [0.0, 0.0]);
    assert!((hi[0].max(hi[1]) - 1.0).abs() < 1e-15, "{hi:?}");
    // One translation and one scale: UV edges keep their directions and ratios.
    let s = (n[1][0] - n[0][0]) / (map.uvs[1][0] - map.uvs[0][0]);
    for (p, q) in n.iter().zip(&map.uvs) {
        let d = [p[0] - n[0][0], p[1] - n[0][1]];
        let e = [q[0] - map.uvs[0][0], q[1] - map.uvs[0][1]];
        assert!((d[0] - s * e[0]).abs() < 1e-12 && (d[1] - s * e[1]).abs() < 1e-12);
    }
}

#[test]
fn an_explicit_start_is_single_level_and_options_are_checked() {
    let mesh = bumpy_disc(4, 0.3);
    for (start, used) in [
        (Start::Lscm, StartMap::Lscm),
        (Start::MeanValue, StartMap::MeanValue),
    ] {
        let map = flatten(&mesh, &FlattenOptions::default().with_start(start)).unwrap();
        assert_eq!((map.start, map.multilevel.is_none()), (used, true));
    }
    let always = Start::Auto {
        multilevel: Multilevel::Always(CoarseLevel::with_vertices(30)),
    };
    let map = flatten(&mesh, &FlattenOptions::default().with_start(always)).unwrap();
    assert_eq!(map.start, StartMap::Multilevel);
    assert_eq!(map.multilevel.as_ref().unwrap().coarse_vertices, 30);
    let bad = |o: FlattenOptions| flatten(&mesh, &o).unwrap_err().to_string();
    let mut o = FlattenOptions::default();
    o.newton.tolerance = 0.0;
    assert!(bad(o).contains("tolerance"));
    let mut o = FlattenOptions::default();
    o.newton.armijo_c = 1.0;
    assert!(bad(o).contains("armijo_c"));
    let o = FlattenOptions::default().with_start(Start::Auto {
        multilevel: Multilevel::Auto(CoarseLevel::with_vertices(3)),
    });
    assert!(bad(o).contains("CoarseLevel::vertices must be at least 16, got 3"));
}

#[test]
fn continuation_reaches_the_target_alpha() {
    let mesh = bumpy_disc(5, 0.3);
    let energy = Energy::litke(Alpha::length())
        .with_continuation(Alpha::conformal())
        .unwrap();
    let map = flatten(&mesh, &FlattenOptions::new(energy)).unwrap();
    assert_eq!(map.continuation.first(), Some(&Alpha::conformal().alphas()));
    assert_eq!(map.continuation.last(), Some(&Alpha::length().alphas()));
    let direct = flatten(&mesh, &FlattenOptions::new(Alpha::length())).unwrap();
    assert!(direct.continuation.is_empty());
    assert!((map.energy - direct.energy).abs() <= 1e-9 * direct.energy);
}

#[test]
fn a_disc_with_long_thin_tentacles_converges_in_few_iterations() {
    // Issue 50: eight closed tubes of length ≈ 5.5 diameters on a domed hub; LSCM
    // shrinks their tips by about e^{−11}. 21 Newton iterations when this was written.
    use crate::mesh::generate::{Octopus, octopus_disc};
    let mesh = octopus_disc(&Octopus::default());
    let map = flatten(&mesh, &FlattenOptions::default()).unwrap();
    assert!(map.converged, "{:?}", map.stop_reason);
    assert!(map.iterations <= 40, "{} iterations", map.iterations);
    assert_eq!(map.flipped_triangles, 0);
    assert_eq!(map.boundary_crossings, 0);
}

#[test]
fn an_uncut_tube_disc_resumes_its_barrier_solve_in_few_iterations_at_no_higher_energy() {
    // Issue 50, item 1: tubes of 6 edges around and 20 rows (length ≈ 10.5 diameters),
    // never cut (one UV per vertex, as `match` and Python's default need). The crushed
    // LSCM start's unconstrained solve overlaps, so a barrier solve follows; it starts
    // from that solve's last crossing-free iterate instead of the crushed start again.
    // The reference: the barrier solve from the crushed start itself (`Bijective::Always`,
    // the solve `WhenOverlapping` ran second before the resume: 61 of 81 iterations).
    // A resume happens only after progressive iterations (the start was crushed), so
    // this also covers the progressive phase on a crushed start.
    use crate::mesh::generate::{Octopus, octopus_disc};
    use crate::param::plan::Cut;
    let mesh = octopus_disc(&Octopus {
        width: 6,
        length: 20,
        ..Octopus::default()
    });
    let never = FlattenOptions::default().with_cut(Cut::Never);
    let mut all = 0;
    let map =
        flatten_with_progress(&mesh, &never, &mut |l| all += usize::from(l.iteration > 0)).unwrap();
    assert!(
        map.barrier && map.barrier_resumed,
        "{}",
        map.start_description()
    );
    assert!(
        map.start_description()
            .ends_with("barrier solve from the unconstrained solve's last crossing-free iterate"),
        "{}",
        map.start_description()
    );
    assert!(map.converged, "{:?}", map.stop_reason);
    assert!(map.iterations <= 40, "{} iterations", map.iterations);
    assert!(all <= 60, "{all} iterations in all");
    assert_eq!(map.flipped_triangles, 0);
    assert_eq!(map.boundary_crossings, 0);
    assert!(map.seams.is_none() && map.protrusion_cuts.is_none());
    let reference = flatten(&mesh, &never.clone().with_bijective(Bijective::Always)).unwrap();
    assert!(!reference.barrier_resumed);
    assert!(
        map.iterations < reference.iterations,
        "{} against {}",
        map.iterations,
        reference.iterations
    );
    assert!(
        map.energy <= reference.energy,
        "{} against {}",
        map.energy,
        reference.energy
    );
}

#[test]
fn a_tube_disc_crushed_by_far_more_than_e8_is_de_crushed_before_plain_newton() {
    // Issue 50, item 1: tubes of 8 edges around and 32 rows, never cut (longer than
    // those of octopus:6,8,30,1, whose tips the LSCM start shrinks by e^{-23}). The
    // progressive phase goes on while any triangle is distorted beyond e^8 (the test
    // that starts it). When it also stopped after a step that left more than half of the
    // energy, a step cut short by a flip ended it with the map still crushed, and plain
    // Newton de-crushed it step by step: 89 iterations before the barrier solve, 112 in
    // all (docs/bench/hard_discs.md).
    use crate::mesh::generate::{Octopus, octopus_disc};
    use crate::param::plan::Cut;
    let mesh = octopus_disc(&Octopus {
        arms: 6,
        width: 8,
        length: 32,
        ..Octopus::default()
    });
    let never = FlattenOptions::default().with_cut(Cut::Never);
    let (mut all, mut before_barrier, mut solves) = (0, 0, 0);
    let map = flatten_with_progress(&mesh, &never, &mut |l| {
        if l.iteration == 0 {
            solves += 1;
        } else {
            all += 1;
            // Progressive steps log no iteration 0; the unconstrained solve's is the first
            // and the barrier solve's the second, so this counts every iteration before
            // the barrier solve's Newton iterations.
            before_barrier += usize::from(solves < 2);
        }
    })
    .unwrap();
    assert!(
        map.barrier && map.barrier_resumed,
        "{}",
        map.start_description()
    );
    assert!(map.converged, "{:?}", map.stop_reason);
    assert_eq!(map.flipped_triangles, 0);
    assert_eq!(map.boundary_crossings, 0);
    assert!(all <= 60, "{all} iterations in all");
    assert!(
        before_barrier <= 30,
        "{before_barrier} iterations before the barrier solve"
    );
    let reference = flatten(&mesh, &never.clone().with_bijective(Bijective::Always)).unwrap();
    assert!(
        map.energy <= reference.energy * (1.0 + 1e-5),
        "{} against {}",
        map.energy,
        reference.energy
    );
}
