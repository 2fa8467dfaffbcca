//! Properties of `surfmap::param::flatten` checked against expectations that do not come
//! from the solver itself (thesis §2.1, §3.1, §4.1):
//!
//! 1. developable patches (cylinder, cone) flatten to an isometry under every energy;
//! 2. a k-fold symmetric hemisphere flattens to a k-fold symmetric map;
//! 3. refining the same analytic surface converges (thesis §4.1.3);
//! 4. α-continuation reaches the same minimum as the direct solve (§3.1.3);
//! 5. rigid motions / uniform scaling / vertex permutations of the input act as expected;
//! 6. the initial-map fallback when LSCM flips triangles (three_peaks.off);
//! 7. every output is flip-free, checked with signed areas computed here.
//!
//! Rigid alignment uses a 2D Procrustes fit written here (no reflection: every output is
//! orientation-preserving, so maps can differ only by a rotation and a translation).

use std::f64::consts::{FRAC_PI_2, TAU};

use surfmap::measure::{corner_uvs_from_vertex_uvs, triangle_singular_values};
use surfmap::mesh::TriMesh;
use surfmap::mesh::generate::{bumpy_disc, cylinder_patch, spherical_cap};
use surfmap::param::count_flipped;
use surfmap::{
    Alpha, Disc, Energy, FlattenOptions, Flattening, Multilevel, NewtonSettings, Start, StartMap,
    StopReason, flatten,
};

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------

/// Options with a tighter Newton tolerance than the default (1e-12), so the solver error
/// is far below the tolerances asserted here (Newton converges quadratically, so this
/// costs about one iteration). Not tighter: see
/// `newton_energy_never_increases_at_a_tolerance_below_rounding` for what happens then.
fn options(energy: Energy) -> FlattenOptions {
    FlattenOptions {
        energy,
        newton: NewtonSettings {
            tolerance: 1e-14,
            ..NewtonSettings::default()
        },
        ..FlattenOptions::default()
    }
}

fn litke(alpha: Alpha) -> FlattenOptions {
    options(Energy::litke(alpha))
}

/// Property 7: the result claims no flips, and every UV triangle has positive signed
/// area as computed here (not via the library's `signed_uv_area`).
fn assert_flip_free(mesh: &TriMesh, result: &Flattening, what: &str) {
    assert_eq!(result.flipped_triangles, 0, "{what}: reported flips");
    assert_eq!(
        count_flipped(&result.uvs, &mesh.triangles),
        0,
        "{what}: count_flipped"
    );
    assert_eq!(
        result.uvs.len(),
        mesh.positions.len(),
        "{what}: one UV per vertex"
    );
    let mut min_ratio = f64::INFINITY;
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|v| result.uvs[v as usize]);
        let twice = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        assert!(
            twice.is_finite() && twice > 0.0,
            "{what}: triangle {t} has signed UV area {}",
            0.5 * twice
        );
        min_ratio = min_ratio.min(0.5 * twice / area3(mesh, t));
    }
    assert!(min_ratio > 0.0, "{what}: min UV/3D area ratio {min_ratio}");
}

fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm3(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn area3(mesh: &TriMesh, t: usize) -> f64 {
    let [a, b, c] = mesh.triangles[t].map(|v| mesh.positions[v as usize]);
    let (e1, e2) = (sub3(b, a), sub3(c, a));
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    0.5 * norm3(n)
}

fn dist2(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Best rigid motion (rotation + translation, no reflection, no scaling) taking `from`
/// onto `to` in the least-squares sense (2D Procrustes / Kabsch):
/// centre both sets, then the optimal angle is `atan2(Σ x × y, Σ x · y)` over the
/// centred pairs `(x, y)`.
struct RigidFit {
    /// Rotation angle in radians.
    angle: f64,
    /// Root-mean-square residual after alignment.
    rms: f64,
    /// Largest residual after alignment.
    max: f64,
    /// Root-mean-square distance of `to` from its centroid (a size for relative errors).
    size: f64,
}

fn rigid_fit(from: &[[f64; 2]], to: &[[f64; 2]]) -> RigidFit {
    assert_eq!(from.len(), to.len());
    let n = from.len() as f64;
    let centroid = |p: &[[f64; 2]]| {
        let s = p.iter().fold([0.0, 0.0], |s, q| [s[0] + q[0], s[1] + q[1]]);
        [s[0] / n, s[1] / n]
    };
    let (ca, cb) = (centroid(from), centroid(to));
    let (mut dot, mut cross) = (0.0, 0.0);
    for (a, b) in from.iter().zip(to) {
        let x = [a[0] - ca[0], a[1] - ca[1]];
        let y = [b[0] - cb[0], b[1] - cb[1]];
        dot += x[0] * y[0] + x[1] * y[1];
        cross += x[0] * y[1] - x[1] * y[0];
    }
    let angle = cross.atan2(dot);
    let (c, s) = (angle.cos(), angle.sin());
    let (mut sum_sq, mut max, mut size_sq) = (0.0, 0.0f64, 0.0);
    for (a, b) in from.iter().zip(to) {
        let x = [a[0] - ca[0], a[1] - ca[1]];
        let y = [b[0] - cb[0], b[1] - cb[1]];
        let r = dist2([c * x[0] - s * x[1], s * x[0] + c * x[1]], y);
        sum_sq += r * r;
        max = max.max(r);
        size_sq += y[0] * y[0] + y[1] * y[1];
    }
    RigidFit {
        angle,
        rms: (sum_sq / n).sqrt(),
        max,
        size: (size_sq / n).sqrt(),
    }
}

/// Patch of the cone with apex at the origin, axis +z and half-angle `half_angle`:
/// slant distance `s ∈ [s0, s1]` in `m` steps, azimuth `φ ∈ [0, angle]` in `n` steps;
/// vertex `(i, j)` (azimuth step `i`, slant step `j`) at `s_j (sin β cos φ_i,
/// sin β sin φ_i, cos β)` with index `j·(n + 1) + i`, each quad split along the diagonal
/// `(i, j)–(i + 1, j + 1)`.
///
/// Every quad lies on two generator lines through the apex, so it is a planar
/// trapezoid, and the triangulated patch is exactly developable: at an interior vertex
/// the two wedges on either side of its generator each contribute an angle of π.
fn cone_patch(half_angle: f64, s0: f64, s1: f64, angle: f64, n: usize, m: usize) -> TriMesh {
    let mut positions = Vec::with_capacity((n + 1) * (m + 1));
    for j in 0..=m {
        let s = s0 + (s1 - s0) * j as f64 / m as f64;
        for i in 0..=n {
            let phi = angle * i as f64 / n as f64;
            positions.push([
                s * half_angle.sin() * phi.cos(),
                s * half_angle.sin() * phi.sin(),
                s * half_angle.cos(),
            ]);
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut triangles = Vec::with_capacity(2 * n * m);
    for j in 0..m {
        for i in 0..n {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh::new(positions, triangles)
}

/// Angle sum defect `2π − Σ angles` at interior vertices, max over the mesh (0 for an
/// intrinsically flat mesh): an independent check that the test surfaces are developable.
fn max_angle_defect(mesh: &TriMesh) -> f64 {
    let nv = mesh.positions.len();
    let mut sum = vec![0.0; nv];
    let mut boundary = vec![false; nv];
    let mut edges = std::collections::HashMap::new();
    for tri in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            let (p, q, r) = (
                mesh.positions[tri[k] as usize],
                mesh.positions[tri[(k + 1) % 3] as usize],
                mesh.positions[tri[(k + 2) % 3] as usize],
            );
            let (u, v) = (sub3(q, p), sub3(r, p));
            let cos = (u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) / (norm3(u) * norm3(v));
            sum[tri[k] as usize] += cos.clamp(-1.0, 1.0).acos();
        }
    }
    for (&(a, b), &count) in &edges {
        if count == 1 {
            boundary[a as usize] = true;
            boundary[b as usize] = true;
        }
    }
    (0..nv)
        .filter(|&v| !boundary[v])
        .map(|v| (TAU - sum[v]).abs())
        .fold(0.0, f64::max)
}

/// Mean energy density `Σ area3D·W / Σ area3D` of a map, from the singular values
/// measured by `surfmap::measure` and densities written out here from their
/// definitions (thesis (2.5) with `a = tr C = σ1² + σ2²`, `d = det C = σ1²σ2²`, §2.1.3).
fn mean_density(mesh: &TriMesh, uvs: &[[f64; 2]], energy: Energy) -> f64 {
    let corners = corner_uvs_from_vertex_uvs(&mesh.triangles, uvs).unwrap();
    let sv = triangle_singular_values(&mesh.positions, &mesh.triangles, &corners, false).unwrap();
    let (mut sum, mut area) = (0.0, 0.0);
    for (s, &a3) in sv.sigma.iter().zip(&sv.area3) {
        let (s1, s2) = (s[0], s[1]);
        if s2 <= 0.0 {
            return f64::INFINITY;
        }
        let (a, d) = (s1 * s1 + s2 * s2, s1 * s1 * s2 * s2);
        let w = match energy {
            Energy::Litke { alpha, .. } => {
                let [al, aa, ac] = alpha.alphas();
                al * a + aa * (d + (al / aa + 1.0) / d) + ac * (a * a / d - 4.0)
            }
            Energy::SymmetricDirichlet => s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2),
            Energy::Arap => (s1 - 1.0).powi(2) + (s2 - 1.0).powi(2),
            Energy::Mips => s1 / s2 + s2 / s1,
        };
        sum += a3 * w;
        area += a3;
    }
    sum / area
}

// ---------------------------------------------------------------------------------------
// 1. Developable patches flatten to isometries
// ---------------------------------------------------------------------------------------

fn all_energies() -> Vec<(&'static str, Energy)> {
    vec![
        ("conformal", Energy::litke(Alpha::conformal())),
        ("balanced", Energy::litke(Alpha::balanced())),
        ("area", Energy::litke(Alpha::area())),
        ("length", Energy::litke(Alpha::length())),
        ("symmetric dirichlet", Energy::SymmetricDirichlet),
        ("arap", Energy::Arap),
    ]
}

/// Largest `|σ − 1|` over all triangles and largest relative edge-length error.
fn isometry_errors(mesh: &TriMesh, uvs: &[[f64; 2]]) -> (f64, f64) {
    let corners = corner_uvs_from_vertex_uvs(&mesh.triangles, uvs).unwrap();
    let sv = triangle_singular_values(&mesh.positions, &mesh.triangles, &corners, false).unwrap();
    assert_eq!(sv.uv_scale, 1.0, "no normalization asked for");
    let sigma_err = sv
        .sigma
        .iter()
        .map(|s| (s[0] - 1.0).abs().max((s[1] - 1.0).abs()))
        .fold(0.0, f64::max);
    let mut edge_err = 0.0f64;
    for tri in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
            let l3 = norm3(sub3(mesh.positions[a], mesh.positions[b]));
            let l2 = dist2(uvs[a], uvs[b]);
            edge_err = edge_err.max((l2 - l3).abs() / l3);
        }
    }
    (sigma_err, edge_err)
}

fn check_isometry(name: &str, mesh: &TriMesh) {
    assert!(max_angle_defect(mesh) < 1e-12, "{name} must be developable");
    // LSCM is exact on a developable mesh, so from LSCM the solver has nothing to do;
    // the mean-value start (boundary on a circle) is far from isometric and makes Newton
    // find the isometry itself.
    let auto = Start::Auto {
        multilevel: Multilevel::default(),
    };
    for start in [auto, Start::MeanValue] {
        for (energy_name, energy) in all_energies() {
            let what = format!("{name}, {energy_name}, start {start:?}");
            let result = flatten(mesh, &options(energy).with_start(start.clone())).unwrap();
            assert_flip_free(mesh, &result, &what);
            let (sigma_err, edge_err) = isometry_errors(mesh, &result.uvs);
            println!(
                "{what}: max |σ−1| = {sigma_err:.2e}, max rel. edge error = {edge_err:.2e}, {} iterations, {:?}",
                result.iterations, result.stop_reason
            );
            assert!(sigma_err < 1e-6, "{what}: max |σ − 1| = {sigma_err}");
            assert!(
                edge_err < 1e-6,
                "{what}: max relative edge error = {edge_err}"
            );
            // At an isometry a = 2, d = 1, so the mean density equals W(2, 1).
            let w_iso = match energy {
                Energy::Litke { alpha, .. } => {
                    let [al, aa, _] = alpha.alphas();
                    2.0 * al + aa * (1.0 + al / aa + 1.0)
                }
                Energy::SymmetricDirichlet => 4.0,
                Energy::Arap => 0.0,
                Energy::Mips => 2.0,
            };
            assert!(
                (result.energy - w_iso).abs() < 1e-9 * w_iso.max(1.0),
                "{what}: energy {} vs W(2, 1) = {w_iso}",
                result.energy
            );
        }
    }
}

#[test]
fn cylinder_patch_flattens_to_an_isometry_for_every_energy() {
    // Radius 0.7, 100° of arc, height 1.3: a curved, non-square patch in odd units.
    let mesh = cylinder_patch(0.7, 100f64.to_radians(), 1.3, 14, 9);
    check_isometry("cylinder patch", &mesh);
}

#[test]
fn cone_patch_flattens_to_an_isometry_for_every_energy() {
    // Half-angle 0.5 rad, slant 1..2.5, 150° of azimuth: unrolls to a 72° annular wedge.
    let mesh = cone_patch(0.5, 1.0, 2.5, 150f64.to_radians(), 16, 8);
    check_isometry("cone patch", &mesh);
}

// ---------------------------------------------------------------------------------------
// 2. Rotational symmetry of a symmetric hemisphere
// ---------------------------------------------------------------------------------------

#[test]
fn symmetric_hemisphere_flattens_to_a_symmetric_map() {
    // `spherical_cap` stitches equal rings identically, so rotating every ring by one
    // segment (vertex 1 + (k−1)·S + m ↦ 1 + (k−1)·S + (m+1 mod S), pole fixed) maps the
    // triangulation onto itself: the mesh has exact S-fold symmetry about the pole.
    let (rings, segments) = (8usize, 12usize);
    let mesh = spherical_cap(1.3, FRAC_PI_2, rings, segments);
    let vertex = |k: usize, m: usize| 1 + (k - 1) * segments + m % segments;
    let rotate = |v: usize| {
        if v == 0 {
            0
        } else {
            vertex((v - 1) / segments + 1, (v - 1) % segments + 1)
        }
    };
    // Independent check of the symmetry claim: the rotated triangle set is the same set.
    let canonical = |t: [u32; 3]| {
        let k = (0..3).min_by_key(|&k| t[k]).unwrap();
        [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
    };
    let set: std::collections::HashSet<[u32; 3]> =
        mesh.triangles.iter().map(|&t| canonical(t)).collect();
    for t in &mesh.triangles {
        assert!(set.contains(&canonical(t.map(|v| rotate(v as usize) as u32))));
    }

    for (name, alpha) in [
        ("balanced", Alpha::balanced()),
        ("conformal", Alpha::conformal()),
    ] {
        let result = flatten(&mesh, &litke(alpha)).unwrap();
        assert_flip_free(&mesh, &result, name);
        let uv = &result.uvs;
        let pole = uv[0];
        // Radii about the pole's UV are constant around every ring.
        let mut worst_spread = 0.0f64;
        let mut last_radius = 0.0;
        let mut ring_radius = Vec::new();
        for k in 1..=rings {
            let radii: Vec<f64> = (0..segments)
                .map(|m| dist2(uv[vertex(k, m)], pole))
                .collect();
            let (lo, hi) = radii.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &r| {
                (lo.min(r), hi.max(r))
            });
            let mean = radii.iter().sum::<f64>() / segments as f64;
            let spread = (hi - lo) / mean;
            worst_spread = worst_spread.max(spread);
            assert!(spread < 1e-6, "{name}: ring {k} radius spread {spread:e}");
            assert!(mean > last_radius, "{name}: ring radii must grow outward");
            ring_radius.push(mean);
            last_radius = mean;
        }
        // A radially symmetric conformal map of a sphere cap is a scaled stereographic
        // projection, r ∝ tan(θ/2); the nearly conformal preset (αc = 0.99) must come
        // close (discretization and the 1 % length/area terms make up the rest).
        let stereo_err = (1..=rings)
            .map(|k| {
                let theta = |k: usize| FRAC_PI_2 * k as f64 / rings as f64;
                let want = (theta(k) / 2.0).tan() / (theta(rings) / 2.0).tan();
                (ring_radius[k - 1] / ring_radius[rings - 1] - want).abs() / want
            })
            .fold(0.0, f64::max);
        println!(
            "hemisphere {name}: max rel. deviation of ring radii from stereographic: {stereo_err:.3e}"
        );
        if name == "conformal" {
            assert!(
                stereo_err < 0.02,
                "{name}: not close to stereographic ({stereo_err})"
            );
        }
        // Rotating the mesh by one segment maps the UVs onto themselves up to a rigid
        // motion, and that motion is a rotation by ±2π/S (the sign is the orientation).
        let rotated: Vec<[f64; 2]> = (0..uv.len()).map(|v| uv[rotate(v)]).collect();
        let fit = rigid_fit(uv, &rotated);
        let rel = fit.max / fit.size;
        println!(
            "hemisphere {name}: ring radius spread {worst_spread:.2e}, rotation residual {rel:.2e}, angle {:.12} (2π/S = {:.12})",
            fit.angle,
            TAU / segments as f64
        );
        assert!(rel < 1e-6, "{name}: symmetry residual {rel:e}");
        assert!(
            (fit.angle.abs() - TAU / segments as f64).abs() < 1e-6,
            "{name}: rotation angle {} instead of ±2π/{segments}",
            fit.angle
        );
        // The pole stays the centre: it is the fixed point of that rotation.
        let centre = uv
            .iter()
            .fold([0.0, 0.0], |s, p| [s[0] + p[0], s[1] + p[1]]);
        let centre = [centre[0] / uv.len() as f64, centre[1] / uv.len() as f64];
        assert!(
            dist2(centre, pole) < 1e-6 * fit.size,
            "{name}: pole off centre"
        );
    }
}

// ---------------------------------------------------------------------------------------
// 3. Refinement consistency (thesis §4.1.3)
// ---------------------------------------------------------------------------------------

/// Flattens nested refinements of one analytic surface; `coarse_in_fine(level, v)` is
/// the index in level `level + 1` of vertex `v` of level `level` (the same parameter
/// point). Returns the relative RMS and max differences between consecutive levels at
/// the coarse vertices after the best rigid alignment.
fn refinement_differences(
    name: &str,
    meshes: &[TriMesh],
    energy: Alpha,
    coarse_in_fine: impl Fn(usize, usize) -> usize,
) -> Vec<(f64, f64)> {
    let maps: Vec<Vec<[f64; 2]>> = meshes
        .iter()
        .enumerate()
        .map(|(level, mesh)| {
            let result = flatten(mesh, &litke(energy)).unwrap();
            assert_flip_free(mesh, &result, &format!("{name} level {level}"));
            assert!(
                result.converged,
                "{name} level {level}: {:?}",
                result.stop_reason
            );
            result.uvs
        })
        .collect();
    let mut out = Vec::new();
    for level in 0..meshes.len() - 1 {
        // Independent check of the nesting: the same 3D point.
        let fine_points: Vec<[f64; 2]> = (0..meshes[level].positions.len())
            .map(|v| {
                let w = coarse_in_fine(level, v);
                let d = norm3(sub3(
                    meshes[level].positions[v],
                    meshes[level + 1].positions[w],
                ));
                assert!(
                    d < 1e-12,
                    "{name}: vertex {v} of level {level} is not vertex {w} of the next"
                );
                maps[level + 1][w]
            })
            .collect();
        let fit = rigid_fit(&maps[level], &fine_points);
        out.push((fit.rms / fit.size, fit.max / fit.size));
    }
    out
}

fn report_rates(name: &str, diffs: &[(f64, f64)]) {
    for (k, (rms, max)) in diffs.iter().enumerate() {
        print!(
            "{name}: level {k}→{}: rel. RMS {rms:.3e}, rel. max {max:.3e}",
            k + 1
        );
        if k > 0 {
            let (prev_rms, prev_max) = diffs[k - 1];
            print!(
                ", rate (log2 ratio) RMS {:.2}, max {:.2}",
                (prev_rms / rms).log2(),
                (prev_max / max).log2()
            );
        }
        println!();
    }
    for w in diffs.windows(2) {
        // Mesh width halves per level: first order would halve the difference; ask for
        // clearly better than that (the observed rate is about 2, see the report).
        assert!(
            w[1].0 < 0.4 * w[0].0,
            "{name}: RMS difference does not shrink: {diffs:?}"
        );
        assert!(
            w[1].1 < 0.5 * w[0].1,
            "{name}: max difference does not shrink: {diffs:?}"
        );
    }
}

#[test]
fn refining_a_bumpy_disc_converges() {
    // bumpy_disc(n): ring k (0..=n) has 6k vertices at radius k/n, vertex m of ring k at
    // angle 2πm/6k, index 1 + 3k(k−1) + m; so ring k, vertex m of level n is ring 2k,
    // vertex 2m of level 2n.
    let levels = [6usize, 12, 24, 48];
    let meshes: Vec<TriMesh> = levels.iter().map(|&n| bumpy_disc(n, 0.3)).collect();
    let index = |k: usize, m: usize| if k == 0 { 0 } else { 1 + 3 * k * (k - 1) + m };
    let ring_of = |v: usize| {
        if v == 0 {
            return (0, 0);
        }
        let mut k = 1;
        while index(k + 1, 0) <= v {
            k += 1;
        }
        (k, v - index(k, 0))
    };
    let coarse_in_fine = |_level: usize, v: usize| {
        let (k, m) = ring_of(v);
        index(2 * k, 2 * m)
    };
    let diffs = refinement_differences(
        "bumpy disc, balanced",
        &meshes,
        Alpha::balanced(),
        coarse_in_fine,
    );
    report_rates("bumpy disc, balanced", &diffs);
}

#[test]
fn refining_a_spherical_cap_converges() {
    // spherical_cap(rings, segments): vertex (k, m) at θ = Θk/rings, φ = 2πm/segments,
    // index 1 + (k−1)·segments + m; (k, m) at (r, s) is (2k, 2m) at (2r, 2s).
    let levels = [(4usize, 10usize), (8, 20), (16, 40), (32, 80)];
    let meshes: Vec<TriMesh> = levels
        .iter()
        .map(|&(r, s)| spherical_cap(1.0, 1.2, r, s))
        .collect();
    let coarse_in_fine = |level: usize, v: usize| {
        if v == 0 {
            return 0;
        }
        let s = levels[level].1;
        let (k, m) = ((v - 1) / s + 1, (v - 1) % s);
        1 + (2 * k - 1) * (2 * s) + 2 * m
    };
    let diffs = refinement_differences(
        "spherical cap, length",
        &meshes,
        Alpha::length(),
        coarse_in_fine,
    );
    report_rates("spherical cap, length", &diffs);
}

// ---------------------------------------------------------------------------------------
// Solver behaviour at the rounding floor (found while writing the tests above)
// ---------------------------------------------------------------------------------------

/// Regression (found while writing these tests): with a tolerance below what rounding
/// allows, the iteration used to cycle between two points until the iteration cap, the
/// energy creeping up (the Armijo slack let `e > E` through and step doubling
/// overshot). Now an increase is never accepted, and no measurable decrease means
/// convergence at the rounding floor.
#[test]
fn newton_energy_never_increases_at_a_tolerance_below_rounding() {
    let mesh = spherical_cap(1.0, 1.2, 32, 80);
    let mut opts = litke(Alpha::length());
    opts.newton.tolerance = 1e-18;
    let result = flatten(&mesh, &opts).unwrap();
    assert_flip_free(&mesh, &result, "tight tolerance");
    assert_ne!(
        result.stop_reason,
        StopReason::IterationCap,
        "{} iterations",
        result.iterations
    );
    for w in result.log.windows(2) {
        if w[0].stage == w[1].stage {
            assert!(
                w[1].energy <= w[0].energy,
                "energy increased at iteration {}: {} → {}",
                w[1].iteration,
                w[0].energy,
                w[1].energy
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// 4. Continuation reaches the direct minimum
// ---------------------------------------------------------------------------------------

#[test]
fn continuation_from_conformal_reaches_the_direct_length_minimum() {
    // A cap of 1 rad opening: curved enough that conformal and length-biased maps differ.
    let mesh = spherical_cap(1.0, 1.0, 10, 24);
    let (from, target) = (Alpha::conformal(), Alpha::length());
    let direct = flatten(&mesh, &litke(target)).unwrap();
    let continued = flatten(
        &mesh,
        &options(Energy::litke(target).with_continuation(from).unwrap()),
    )
    .unwrap();
    assert_flip_free(&mesh, &direct, "direct");
    assert_flip_free(&mesh, &continued, "continuation");
    assert!(direct.converged && continued.converged);
    assert!(
        direct.continuation.is_empty(),
        "no stages without a continuation start"
    );

    // Stages: α0 first, the target last, in between points of the segment α0 → α1
    // with increasing blend parameter θ.
    let stages = &continued.continuation;
    println!("continuation stages: {stages:?}");
    assert!(stages.len() >= 2, "{stages:?}");
    let (a0, a1) = (from.alphas(), target.alphas());
    let close = |x: [f64; 3], y: [f64; 3]| (0..3).all(|i| (x[i] - y[i]).abs() < 1e-12);
    assert!(
        close(stages[0], a0),
        "first stage {:?} is not α0 {a0:?}",
        stages[0]
    );
    assert!(
        close(*stages.last().unwrap(), a1),
        "last stage is not α1 {a1:?}"
    );
    let mut last_theta = -1.0;
    for alpha in stages {
        // θ from the length weight, then the whole triple must be the blend at θ.
        let theta = (alpha[0] - a0[0]) / (a1[0] - a0[0]);
        let blend: [f64; 3] = std::array::from_fn(|i| (1.0 - theta) * a0[i] + theta * a1[i]);
        assert!(
            close(*alpha, blend),
            "stage {alpha:?} is not on the segment α0 → α1"
        );
        assert!(theta > last_theta && (0.0..=1.0 + 1e-12).contains(&theta));
        last_theta = theta;
    }

    // Same minimum: energy and map up to a rigid motion.
    let rel_energy = (continued.energy - direct.energy).abs() / direct.energy;
    let fit = rigid_fit(&continued.uvs, &direct.uvs);
    println!(
        "continuation: E = {}, direct E = {}, rel. diff {rel_energy:.2e}; UV max residual {:.2e} (rel.); iterations {} vs {}",
        continued.energy,
        direct.energy,
        fit.max / fit.size,
        continued.iterations,
        direct.iterations
    );
    assert!(rel_energy < 1e-8, "energies differ by {rel_energy:e}");
    assert!(
        fit.max / fit.size < 1e-6,
        "maps differ by {:e}",
        fit.max / fit.size
    );
    // And that minimum really is a different map from the conformal one.
    let conformal = flatten(&mesh, &litke(from)).unwrap();
    let fit_c = rigid_fit(&conformal.uvs, &direct.uvs);
    assert!(
        fit_c.max / fit_c.size > 1e-3,
        "test surface too flat to tell energies apart"
    );
}

// ---------------------------------------------------------------------------------------
// 5. Invariance under rigid motions, scaling and vertex permutations
// ---------------------------------------------------------------------------------------

/// Rotation by `angle` about the unit vector `axis` (Rodrigues), applied to `p`.
fn rotate3(p: [f64; 3], axis: [f64; 3], angle: f64) -> [f64; 3] {
    let (c, s) = (angle.cos(), angle.sin());
    let k_dot_p = axis[0] * p[0] + axis[1] * p[1] + axis[2] * p[2];
    let k_cross_p = [
        axis[1] * p[2] - axis[2] * p[1],
        axis[2] * p[0] - axis[0] * p[2],
        axis[0] * p[1] - axis[1] * p[0],
    ];
    std::array::from_fn(|i| p[i] * c + k_cross_p[i] * s + axis[i] * k_dot_p * (1.0 - c))
}

#[test]
fn rigid_motion_and_scaling_of_the_surface_scale_the_map() {
    let mesh = bumpy_disc(8, 0.35);
    let base = flatten(&mesh, &litke(Alpha::balanced())).unwrap();
    assert_flip_free(&mesh, &base, "base");
    let n = 1.0 / 14f64.sqrt();
    let axis = [n, 2.0 * n, 3.0 * n];
    for scale in [2.5, 1e-3, 40.0] {
        let moved = TriMesh::new(
            mesh.positions
                .iter()
                .map(|&p| {
                    let q = rotate3(p, axis, 0.7);
                    [scale * q[0] + 5.0, scale * q[1] - 3.0, scale * q[2] + 2.0]
                })
                .collect(),
            mesh.triangles.clone(),
        );
        let result = flatten(&moved, &litke(Alpha::balanced())).unwrap();
        assert_flip_free(&moved, &result, &format!("scale {scale}"));
        let scaled: Vec<[f64; 2]> = base
            .uvs
            .iter()
            .map(|p| [scale * p[0], scale * p[1]])
            .collect();
        let fit = rigid_fit(&scaled, &result.uvs);
        let rel_energy = (result.energy - base.energy).abs() / base.energy;
        println!(
            "scale {scale}: UV residual {:.2e} (rel.), energy rel. diff {rel_energy:.2e}",
            fit.max / fit.size
        );
        assert!(
            fit.max / fit.size < 1e-7,
            "scale {scale}: maps differ by {:e}",
            fit.max / fit.size
        );
        assert!(
            rel_energy < 1e-10,
            "scale {scale}: energy per unit area changed by {rel_energy:e}"
        );
    }
}

#[test]
fn permuting_vertices_and_triangles_gives_the_same_map() {
    let mesh = bumpy_disc(8, 0.35);
    let nv = mesh.positions.len();
    // A fixed pseudo-random permutation (xorshift keys, sorted).
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut order: Vec<(u64, usize)> = (0..nv).map(|v| (next(), v)).collect();
    order.sort();
    // new_of_old[v] = position of old vertex v in the new numbering.
    let mut new_of_old = vec![0u32; nv];
    for (new, &(_, old)) in order.iter().enumerate() {
        new_of_old[old] = new as u32;
    }
    let positions: Vec<[f64; 3]> = order.iter().map(|&(_, old)| mesh.positions[old]).collect();
    // Triangles renumbered, each rotated cyclically (same orientation), order shuffled.
    let mut triangles: Vec<(u64, [u32; 3])> = mesh
        .triangles
        .iter()
        .map(|t| {
            let r = (next() % 3) as usize;
            let t = t.map(|v| new_of_old[v as usize]);
            (next(), [t[r], t[(r + 1) % 3], t[(r + 2) % 3]])
        })
        .collect();
    triangles.sort();
    let permuted = TriMesh::new(positions, triangles.into_iter().map(|(_, t)| t).collect());

    let base = flatten(&mesh, &litke(Alpha::balanced())).unwrap();
    let result = flatten(&permuted, &litke(Alpha::balanced())).unwrap();
    assert_flip_free(&mesh, &base, "original order");
    assert_flip_free(&permuted, &result, "permuted");
    let pulled_back: Vec<[f64; 2]> = (0..nv)
        .map(|v| result.uvs[new_of_old[v] as usize])
        .collect();
    let fit = rigid_fit(&pulled_back, &base.uvs);
    let rel_energy = (result.energy - base.energy).abs() / base.energy;
    println!(
        "permutation: UV residual {:.2e} (rel.), energy rel. diff {rel_energy:.2e}",
        fit.max / fit.size
    );
    assert!(
        fit.max / fit.size < 1e-7,
        "maps differ by {:e}",
        fit.max / fit.size
    );
    assert!(rel_energy < 1e-10);
}

// ---------------------------------------------------------------------------------------
// 6. Start-map fallback when LSCM flips triangles
// ---------------------------------------------------------------------------------------

#[test]
fn lscm_flips_on_three_peaks_fall_back_to_mean_value_and_converge() {
    let Some(path) = surfmap::testing::shared_file("three_peaks.off") else {
        return;
    };
    let mesh = surfmap::mesh::io::read_mesh(&path).unwrap().mesh;
    let result = flatten(&mesh, &FlattenOptions::default()).unwrap();
    println!(
        "three_peaks: start {:?}, LSCM flipped {}, {} iterations, {:?}, E = {}",
        result.start, result.lscm_flipped, result.iterations, result.stop_reason, result.energy
    );
    assert_eq!(result.start, StartMap::MeanValue);
    assert!(result.lscm_flipped > 0);
    // LSCM really does flip here: count its non-positive triangles ourselves (either
    // orientation of the whole map is admissible, so count against the majority).
    let disc = Disc::new(&mesh).expect("a disc");
    let lscm = surfmap::param::lscm::lscm(&mesh.positions, &disc).unwrap();
    let (mut positive, mut other) = (0usize, 0usize);
    for tri in &mesh.triangles {
        let [a, b, c] = tri.map(|v| lscm.uv[v as usize]);
        let twice = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        if twice > 0.0 {
            positive += 1
        } else {
            other += 1
        }
    }
    let flipped = positive.min(other);
    println!(
        "three_peaks: LSCM has {flipped} flipped of {} triangles",
        mesh.triangles.len()
    );
    assert_eq!(flipped, result.lscm_flipped);
    assert!(result.converged, "{:?}", result.stop_reason);
    assert_flip_free(&mesh, &result, "three_peaks");
}

// ---------------------------------------------------------------------------------------
// 7. Flip-free outputs on hard inputs
// ---------------------------------------------------------------------------------------

#[test]
fn every_energy_gives_a_flip_free_map_on_hard_surfaces() {
    let surfaces = [
        // Most of a sphere (143° polar opening): large area distortion unavoidable.
        ("deep cap", spherical_cap(1.0, 2.5, 10, 24)),
        // Tall bumps: strongly varying curvature of both signs.
        ("steep bumpy disc", bumpy_disc(8, 1.2)),
    ];
    for (name, mesh) in &surfaces {
        for (energy_name, energy) in all_energies() {
            let what = format!("{name}, {energy_name}");
            let result = flatten(mesh, &options(energy)).unwrap();
            assert_flip_free(mesh, &result, &what);
            let corners = corner_uvs_from_vertex_uvs(&mesh.triangles, &result.uvs).unwrap();
            let sv = triangle_singular_values(&mesh.positions, &mesh.triangles, &corners, false)
                .unwrap();
            let min_s2 = sv.sigma.iter().map(|s| s[1]).fold(f64::INFINITY, f64::min);
            let max_s1 = sv.sigma.iter().map(|s| s[0]).fold(0.0, f64::max);
            println!(
                "{what}: {:?} after {} iterations, E = {:.6}, σ range [{min_s2:.3}, {max_s1:.3}]",
                result.stop_reason, result.iterations, result.energy
            );
            assert!(
                min_s2 > 0.0,
                "{what}: a triangle is flipped per measure ({min_s2})"
            );
            assert!(result.converged, "{what}: {:?}", result.stop_reason);
            // The reported energy is the mean density of the returned map.
            let e = mean_density(mesh, &result.uvs, energy);
            assert!(
                (e - result.energy).abs() < 1e-10 * e.abs().max(1.0),
                "{what}: reported energy {} vs recomputed {e}",
                result.energy
            );
            // And it is a local minimum: small random perturbations (rigid motions
            // included, which must cost nothing) never lower it beyond rounding.
            let size = result
                .uvs
                .iter()
                .map(|p| p[0].abs().max(p[1].abs()))
                .fold(0.0, f64::max);
            let mut state = 0x9e37_79b9_7f4a_7c15u64;
            for trial in 0..4 {
                // ±δ: at a non-stationary point one of the two lowers E to first order.
                let eps = 1e-5 * size;
                let delta: Vec<[f64; 2]> = (0..result.uvs.len())
                    .map(|_| {
                        let mut r = || {
                            state ^= state << 13;
                            state ^= state >> 7;
                            state ^= state << 17;
                            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
                        };
                        [eps * r(), eps * r()]
                    })
                    .collect();
                for sign in [1.0, -1.0] {
                    let perturbed: Vec<[f64; 2]> = result
                        .uvs
                        .iter()
                        .zip(&delta)
                        .map(|(p, d)| [p[0] + sign * d[0], p[1] + sign * d[1]])
                        .collect();
                    let ep = mean_density(mesh, &perturbed, energy);
                    assert!(
                        ep >= e - 1e-12 * e.abs().max(1.0),
                        "{what}: perturbation {trial} lowers E: {ep} < {e}"
                    );
                }
            }
        }
    }
}
