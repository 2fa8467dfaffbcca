"""Cutting from Python: cut="auto" opens closed and higher-genus surfaces into one disc
and returns per-corner UVs (UV, FUV, report); seams= cuts along the caller's edges;
max_distortion= cuts until the mean symmetric Dirichlet distortion meets its bound.
Checked against independent computations in numpy: the Euler characteristic and
boundary of the cut, every UV triangle's signed area, boundary crossings, and the
distortion recomputed from the triangles' Jacobians."""

import numpy as np
import pytest

import surfmap
from conftest import read_corner_uvs, wavy_grid


def torus(n=24, m=12, R=1.0, r=0.4):
    """A closed torus of genus 1: n × m quads, two triangles each, outward normals."""
    u, v = np.meshgrid(2 * np.pi * np.arange(n) / n, 2 * np.pi * np.arange(m) / m, indexing="ij")
    V = np.c_[((R + r * np.cos(v)) * np.cos(u)).ravel(), ((R + r * np.cos(v)) * np.sin(u)).ravel(), (r * np.sin(v)).ravel()]
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a = (i * m + j).ravel()
    b = (((i + 1) % n) * m + j).ravel()
    c = (((i + 1) % n) * m + (j + 1) % m).ravel()
    d = (i * m + (j + 1) % m).ravel()
    return V, np.r_[np.c_[a, b, c], np.c_[a, c, d]]


def spherical_cap(rings=12, segments=48, angle=np.pi / 2):
    """A cap of the unit sphere around +z, opening `angle` (π/2: a hemisphere): a disc."""
    V = [[0.0, 0.0, 1.0]]
    for i in range(1, rings + 1):
        t = angle * i / rings
        for j in range(segments):
            p = 2 * np.pi * j / segments
            V.append([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
    F = [[0, 1 + j, 1 + (j + 1) % segments] for j in range(segments)]
    for i in range(1, rings):
        for j in range(segments):
            a, b = 1 + (i - 1) * segments + j, 1 + (i - 1) * segments + (j + 1) % segments
            c, d = 1 + i * segments + (j + 1) % segments, 1 + i * segments + j
            F += [[a, d, c], [a, c, b]]
    return np.array(V), np.array(F)


def octahedron():
    V = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [0, 0, -1]], dtype=float)
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1], [5, 2, 1], [5, 3, 2], [5, 4, 3], [5, 1, 4]])
    return V, F


def signed_areas(UV, FUV):
    a, b, c = UV[FUV[:, 0]], UV[FUV[:, 1]], UV[FUV[:, 2]]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def edge_counts(T):
    """Undirected edges of triangles T (sorted pairs) and how many triangles share each."""
    e = np.sort(np.r_[T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]], axis=1)
    return np.unique(e, axis=0, return_counts=True)


def boundary_edges(T):
    edges, counts = edge_counts(T)
    return edges[counts == 1]


def boundary_crossings(UV, FUV):
    """Pairs of boundary edges of the UV mesh without a common endpoint that cross."""
    B = boundary_edges(FUV)
    p, q = UV[B[:, 0]], UV[B[:, 1]]

    def orient(a, b, c):
        return np.sign((b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0]))

    P, Q = p[:, None], q[:, None]
    R, S = p[None, :], q[None, :]
    cross = (orient(P, Q, R) * orient(P, Q, S) < 0) & (orient(R, S, P) * orient(R, S, Q) < 0)
    share = (B[:, None, :, None] == B[None, :, None, :]).any(axis=(2, 3))
    return int((cross & ~share).sum()) // 2


def mean_symmetric_dirichlet(V, F, UV, FUV):
    """Σ_t A_t (σ1² + σ2² + σ1⁻² + σ2⁻²)/4 / Σ_t A_t with the UVs scaled to the 3D area,
    from each triangle's Jacobian in a local orthonormal frame (1 for an isometry)."""
    e1, e2 = V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]
    n = np.cross(e1, e2)
    area3 = 0.5 * np.linalg.norm(n, axis=1)
    x = e1 / np.linalg.norm(e1, axis=1)[:, None]
    y = np.cross(n, x)
    y /= np.linalg.norm(y, axis=1)[:, None]
    P = np.stack([np.c_[(e1 * x).sum(1), (e2 * x).sum(1)], np.c_[(e1 * y).sum(1), (e2 * y).sum(1)]], axis=1)
    k = np.sqrt(area3.sum() / np.abs(signed_areas(UV, FUV)).sum())
    u1, u2 = k * (UV[FUV[:, 1]] - UV[FUV[:, 0]]), k * (UV[FUV[:, 2]] - UV[FUV[:, 0]])
    Q = np.stack([np.c_[u1[:, 0], u2[:, 0]], np.c_[u1[:, 1], u2[:, 1]]], axis=1)
    s = np.linalg.svd(Q @ np.linalg.inv(P), compute_uv=False)
    sd = (s**2).sum(1) + (s**-2.0).sum(1)
    return float((area3 * sd).sum() / area3.sum() / 4)


def check_one_disc(V, F, UV, FUV, report):
    """The cut map is one flip-free, overlap-free disc whose boundary is the seams."""
    assert FUV.shape == F.shape and FUV.dtype == np.int64 and UV.dtype == np.float64
    assert FUV.min() == 0 and FUV.max() == len(UV) - 1
    # Each UV row belongs to one vertex; a vertex has a row per side of the seams.
    owner = np.full(len(UV), -1)
    owner[FUV.ravel()] = F.ravel()
    assert (owner[FUV] == F).all()
    # One disc: χ = V − E + F = 1 and one boundary loop (as many boundary edges as
    # boundary vertices).
    edges, _ = edge_counts(FUV)
    assert len(UV) - len(edges) + len(F) == 1
    B = boundary_edges(FUV)
    assert len(np.unique(B)) == len(B)
    # Flip-free: every UV triangle has positive area; overlap-free: no boundary crossing.
    assert signed_areas(UV, FUV).min() > 0
    assert boundary_crossings(UV, FUV) == 0
    assert report["flipped_triangles"] == 0 and report["guarantee"] == "bijective"
    return B


def test_a_torus_is_cut_into_one_disc():
    V, F = torus()
    UV, FUV, report = surfmap.flatten(V, F, cut="auto")
    B = check_one_disc(V, F, UV, FUV, report)
    assert len(UV) > len(V)
    assert report["plan"] == "cut open along seams (closed, genus 1)"
    # A closed surface's cut boundary is the seams, each seam edge on both sides.
    seams = np.array(report["seams"]["edges"])
    assert seams.shape[1] == 2 and (seams[:, 0] < seams[:, 1]).all()
    owner = np.empty(len(UV), dtype=np.int64)
    owner[FUV.ravel()] = F.ravel()
    sides, counts = np.unique(np.sort(owner[B], axis=1), axis=0, return_counts=True)
    assert (counts == 2).all()
    assert sides.tolist() == seams.tolist()
    length = np.linalg.norm(V[seams[:, 0]] - V[seams[:, 1]], axis=1).sum()
    assert report["seams"]["length"] == pytest.approx(length, rel=1e-12)
    # The report measures the corners returned.
    again = surfmap.measure(V, F, UV, FUV)
    assert again["symmetric_dirichlet"] == report["symmetric_dirichlet"]


def test_the_callers_seams_are_honoured():
    V, F = torus()
    _, _, first = surfmap.flatten(V, F, cut="auto")
    seams = np.array(first["seams"]["edges"])[::-1]  # any order, any direction
    seams = np.c_[seams[:, 1], seams[:, 0]]
    UV, FUV, report = surfmap.flatten(V, F, seams=seams)
    check_one_disc(V, F, UV, FUV, report)
    assert report["plan"] == "cut open along the given seams"
    assert report["seams"]["reason"] == {"kind": "given"}
    assert report["seams"]["edges"] == first["seams"]["edges"]
    # Seams that do not open the torus into a disc: one loop around the tube.
    m = 12
    loop = np.c_[np.arange(m), (np.arange(m) + 1) % m]
    with pytest.raises(ValueError, match="still not a disc"):
        surfmap.flatten(V, F, seams=loop)
    with pytest.raises(ValueError, match=r"seam 0 \(0, 100\) is not an edge"):
        surfmap.flatten(V, F, seams=np.array([[0, 100]]))


def test_max_distortion_meets_its_bound_on_a_hemisphere():
    V, F = spherical_cap()
    bound = 1.02
    _, one_chart = surfmap.flatten(V, F)
    UV, FUV, report = surfmap.flatten(V, F, max_distortion=bound)
    cuts = report["distortion_cuts"]
    # One chart is above the bound (the test is not vacuous); the cut map is under it.
    assert one_chart["symmetric_dirichlet"] / 4 > bound
    assert cuts["before"] > bound and cuts["met"] and cuts["after"] <= bound
    assert cuts["seam_edges_added"] > 0
    assert report["plan"] == "cut open to lower the distortion"
    # Independently: the distortion of the returned corners, from their Jacobians.
    d = mean_symmetric_dirichlet(V, F, UV, FUV)
    assert d <= bound
    assert d == pytest.approx(cuts["after"], rel=1e-10)
    assert d == pytest.approx(report["symmetric_dirichlet"] / 4, rel=1e-10)
    assert signed_areas(UV, FUV).min() > 0 and boundary_crossings(UV, FUV) == 0
    assert len(boundary_edges(FUV)) == len(boundary_edges(F)) + 2 * cuts["seam_edges_added"]


def test_the_distortion_computation_is_that_of_known_maps():
    """The numpy oracle itself: a flat disc mapped by a similarity has D = 1, stretched
    by 2 along x (√2 and 1/√2 after the area scaling) D = (2 + 1/2 + 1/2 + 2)/4 = 5/4."""
    V, F = wavy_grid(6, amplitude=0.0)
    UV = 3 * V[:, :2]
    assert mean_symmetric_dirichlet(V, F, UV, F) == pytest.approx(1.0, abs=1e-12)
    assert mean_symmetric_dirichlet(V, F, UV * [2, 1], F) == pytest.approx(1.25, abs=1e-12)


def test_the_crossing_count_sees_overlapping_boundaries():
    """The numpy oracle for overlap: two UV triangles whose outlines cross (a star of
    David: 6 crossings), then the same two moved apart (none)."""
    UV = np.array([[0, 0], [2, 0], [1, 1.8], [0, 1.2], [1, -0.6], [2, 1.2]], dtype=float)
    FUV = np.array([[0, 1, 2], [3, 4, 5]])
    assert boundary_crossings(UV, FUV) == 6
    UV[3:] += [10, 0]
    assert boundary_crossings(UV, FUV) == 0


def test_cut_modes_for_holes_and_the_per_vertex_result():
    V, F = wavy_grid(12)
    holes = [2 * 12 + 2, 7 * 12 + 7]
    V, F, _ = surfmap.repair(V, F[~np.isin(F, holes).any(axis=1)], drop_unreferenced=True)
    # Filled (the default of cut="auto"): no seam, one UV per vertex, FUV is F, and the
    # UVs are those of fill_holes=True without cutting.
    UV, FUV, report = surfmap.flatten(V, F, cut="auto")
    UV0, report0 = surfmap.flatten(V, F, fill_holes=True)
    assert report["plan"] == "fill 2 holes" and report["seams"] is None
    assert (FUV == F).all() and np.array_equal(UV, UV0)
    assert report["energy"] == report0["energy"]
    # Opened with seams to the outer boundary.
    for kwargs in [{"cut": "holes"}, {"cut": "auto", "fill_holes": False}]:
        UV, FUV, report = surfmap.flatten(V, F, **kwargs)
        assert report["plan"] == "cut open along seams (3 boundary loops)", kwargs
        assert report["holes_filled"] == 0 and len(report["seams"]["edges"]) > 0
        assert len(UV) > len(V) and signed_areas(UV, FUV).min() > 0
        edges, _ = edge_counts(FUV)
        assert len(UV) - len(edges) + len(F) == 1
    # Without cut, the old behaviour: refused, the message naming both remedies.
    with pytest.raises(surfmap.MeshError, match="fill_holes=True") as err:
        surfmap.flatten(V, F)
    assert 'cut="holes"' in str(err.value)


def test_a_closed_surface_without_cut_says_how_to_cut_it():
    V, F = octahedron()
    with pytest.raises(surfmap.MeshError, match='pass cut="auto"') as err:
        surfmap.flatten(V, F)
    assert [d["kind"] for d in err.value.defects] == ["closed_surface"]
    UV, FUV, report = surfmap.flatten(V, F, cut="auto", normalize=True)
    check_one_disc(V, F, UV, FUV, report)
    assert UV.min() >= 0 and UV.max() == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize(
    "kwargs,message",
    [
        ({"cut": "never", "max_distortion": 1.1}, 'max_distortion cuts the surface open, but cut="never"'),
        ({"cut": "never", "seams": np.array([[0, 1]])}, 'seams cuts the surface open, but cut="never"'),
        ({"cut": "holes", "fill_holes": True}, 'fill_holes=True fills the holes that cut="holes" opens'),
        ({"cut": "always"}, 'unknown cut "always"; choose one of "never", "auto", "holes"'),
        ({"max_distortion": 0.9}, "max_distortion must be a finite number of at least 1"),
        ({"seams": np.array([0, 1])}, r"seams must have shape \(n, 2\)"),
        ({"seams": np.array([[0, -1]])}, r"seams\[0, 1\] = -1: vertex indices count from 0"),
    ],
)
def test_contradictory_or_bad_cut_options_are_value_errors(kwargs, message):
    V, F = octahedron()
    with pytest.raises(ValueError, match=message):
        surfmap.flatten(V, F, **kwargs)


def test_write_obj_and_measure_take_per_corner_uvs(tmp_path):
    V, F = torus(12, 6)
    UV, FUV, report = surfmap.flatten(V, F, cut="auto")
    path = tmp_path / "torus.obj"
    surfmap.write_obj(path, V, F, UV, FUV)
    vt, fuv = read_corner_uvs(path)
    assert np.array_equal(vt, UV) and np.array_equal(fuv, FUV)
    assert np.array_equal(surfmap.read_mesh(path)[1], F)
    m = surfmap.measure(V, F, UV, FUV)
    assert m["flipped_triangles"] == 0 and m["charts"] == 1
    assert m["symmetric_dirichlet"] == report["symmetric_dirichlet"]
    with pytest.raises(ValueError, match=r"FUV\[0, 0\] = 9999: UV indices count from 0"):
        surfmap.measure(V, F, UV, np.where(FUV == FUV[0, 0], 9999, FUV))
    with pytest.raises(ValueError, match="FUV has 3 rows but F has"):
        surfmap.write_obj(path, V, F, UV, FUV[:3])
    with pytest.raises(ValueError, match="give UV too"):
        surfmap.write_obj(path, V, F, FUV=FUV)


def test_flatten_file_cuts_and_writes_per_corner_uvs(tmp_path):
    V, F = torus(12, 6)
    surfmap.write_obj(tmp_path / "torus.obj", V, F)
    refused = surfmap.flatten_file(tmp_path / "torus.obj", tmp_path / "out")
    assert refused["status"] == "failed" and 'cut="auto"' in refused["error"]
    row = surfmap.flatten_file(tmp_path / "torus.obj", tmp_path / "out", cut="auto")
    UV, FUV, report = surfmap.flatten(V, F, cut="auto")
    assert row["status"] == "ok" and row["plan"] == report["plan"]
    assert row["seam_edges"] == len(report["seams"]["edges"])
    assert row["seam_length"] == report["seams"]["length"]
    vt, fuv = read_corner_uvs(row["output"])
    assert np.abs(vt - UV).max() <= 1e-12 and np.array_equal(fuv, FUV)
