"""surfmap.match: the command line's match, from numpy arrays."""

import json

import numpy as np
import pytest

import surfmap
from conftest import run_cli


def test_match_equals_the_command_line(cli, data, tmp_path):
    a, b = data / "faces" / "ict" / "ict_neutral.obj", data / "faces" / "ict" / "ict_id004.obj"
    run_cli(cli, "match", a, b, "-o", tmp_path, "--size", "129", "--quiet")
    C, report = surfmap.match(*surfmap.read_mesh(a), *surfmap.read_mesh(b), size=129)
    expected = np.load(tmp_path / "correspondence.npy")
    assert C.dtype == expected.dtype and C.shape == expected.shape == (9409, 4)
    assert np.array_equal(C, expected)
    cli_report = json.loads((tmp_path / "match.json").read_text())
    for key in ("matched_vertices_a", "min_det", "flipped_triangles", "collapsed_triangles", "holes_filled_a"):
        assert report[key] == cli_report[key], key
    # The registered faces' vertex i corresponds to vertex i: most matched points lie
    # near B's vertex of the same index.
    VB, FB = surfmap.read_mesh(b)
    ok = C[:, 0] >= 0
    tri = FB[C[ok, 0].astype(int)]
    points = np.einsum("ij,ijk->ik", C[ok, 1:], VB[tri])
    err = np.linalg.norm(points - VB[ok], axis=1) / report["length_unit"]  # ≈ √area
    assert ok.mean() > 0.9 and np.median(err) < 0.05
    # The rim fit turned off: still the command line's table, and a different one.
    off = tmp_path / "off"
    run_cli(cli, "match", a, b, "-o", off, "--size", "129", "--quiet", "--rim-fit-rings", "0")
    C0, report0 = surfmap.match(*surfmap.read_mesh(a), *surfmap.read_mesh(b), size=129, rim_fit_rings=0)
    assert np.array_equal(C0, np.load(off / "correspondence.npy"))
    assert report0["rim_fit"]["holes"] == 0 and report["rim_fit"]["holes"] == 3
    assert not np.array_equal(C0, C)


def test_match_of_a_moved_copy_recovers_the_motion():
    # A disc cut from a 41 × 41 grid over [-1, 1]² (a bump and a saddle), and a moved copy.
    n = 41
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    V = np.c_[x.ravel(), y.ravel(), (0.3 * np.exp(-2 * ((x - 0.3) ** 2 + y**2)) + 0.1 * x * y).ravel()]
    i = np.arange(n * (n - 1)).reshape(n - 1, n)[:, :-1].ravel()
    F = np.r_[np.c_[i, i + 1, i + n + 1], np.c_[i, i + n + 1, i + n]]
    F = F[np.linalg.norm(V[F, :2].mean(1), axis=1) < 0.95]
    used = np.unique(F)
    index = np.full(len(V), -1)
    index[used] = np.arange(len(used))
    V, F = V[used], index[F]
    c, s = np.cos(0.6), np.sin(0.6)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    VB = V @ R.T + [1.0, -2.0, 0.5]
    C, report = surfmap.match(V, F, VB, F, size=129)
    ok = C[:, 0] >= 0
    points = np.einsum("ij,ijk->ik", C[ok, 1:], VB[F[C[ok, 0].astype(int)]])
    err = np.linalg.norm(points - VB[ok], axis=1)
    # The grid's cell is about 2.4 / 128 ≈ 0.019 here; measured: median 0.025, p95 0.047.
    cell = 2.4 / 128
    assert report["min_det"] > 0 and ok.mean() > 0.95 and report["flipped_triangles"] == 0
    assert np.median(err) < 2 * cell and np.percentile(err, 95) < 4 * cell
    # B in units 1000 times smaller (m → mm): read as other units, scaled back for the
    # match, the same correspondence to within rounding.
    C_mm, report_mm = surfmap.match(V, F, VB * 1000.0, F, size=129)
    assert report_mm["scale_b"] == 0.001 and report["scale_b"] == 1.0
    ok_mm = C_mm[:, 0] >= 0
    points_mm = np.einsum("ij,ijk->ik", C_mm[ok_mm, 1:], VB[F[C_mm[ok_mm, 0].astype(int)]])
    err_mm = np.linalg.norm(points_mm - VB[ok_mm], axis=1)
    assert ok_mm.mean() > 0.95 and np.median(err_mm) < 2 * cell


def test_the_budget_caps_the_levels_as_on_the_command_line(cli, tmp_path):
    # A bump against a bent copy of it, on two levels (65², 129²).
    n = 33
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    V = np.c_[x.ravel(), y.ravel(), (0.3 * np.exp(-2 * ((x - 0.3) ** 2 + y**2))).ravel()]
    i = np.arange(n * (n - 1)).reshape(n - 1, n)[:, :-1].ravel()
    F = np.r_[np.c_[i, i + 1, i + n + 1], np.c_[i, i + n + 1, i + n]]
    VB = V + np.c_[np.zeros(len(V)), np.zeros(len(V)), 0.1 * np.sin(np.pi * V[:, 0])]
    levels = lambda report: [(l["size"], l["iterations"], l["stop"]) for l in report["levels"]]
    # The default is the documented 40.
    C, report = surfmap.match(V, F, VB, F, size=129)
    C40, _ = surfmap.match(V, F, VB, F, size=129, budget=40)
    assert np.array_equal(C, C40)
    # 2 finest-level evaluations: 8 at 65², 2 at 129²; no level iterates past its budget,
    # and here it binds; the command line's --budget 2 gives the same table.
    C2, report2 = surfmap.match(V, F, VB, F, size=129, budget=2)
    for size, iterations, _ in levels(report2):
        assert iterations <= 2 * (128 // (size - 1)) ** 2
    assert any(stop == "budget" for *_, stop in levels(report2))
    a, b = tmp_path / "a.obj", tmp_path / "b.obj"
    surfmap.write_obj(str(a), V, F)
    surfmap.write_obj(str(b), VB, F)
    run_cli(cli, "match", a, b, "-o", tmp_path / "out", "--size", "129", "--budget", "2", "--quiet")
    assert np.array_equal(C2, np.load(tmp_path / "out" / "correspondence.npy"))
    # 0: every level runs to its stopping rule.
    _, report0 = surfmap.match(V, F, VB, F, size=129, budget=0)
    assert all(stop != "budget" for *_, stop in levels(report0))


def test_match_errors():
    n = 9
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    V = np.c_[x.ravel(), y.ravel(), 0.1 * np.sin(3 * x.ravel())]
    i = np.arange(n * (n - 1)).reshape(n - 1, n)[:, :-1].ravel()
    F = np.r_[np.c_[i, i + 1, i + n + 1], np.c_[i, i + n + 1, i + n]]
    with pytest.raises(ValueError, match="align must be"):
        surfmap.match(V, F, V, F, size=65, align="sideways")
    with pytest.raises(ValueError, match="missing key 'B'"):
        surfmap.match(V, F, V, F, size=65, landmarks={"names": ["a"], "A": [0]})
    with pytest.raises(ValueError, match="does not exist"):
        surfmap.match(V, F, V, F, size=65, landmarks={"names": ["a"], "A": [0], "B": [10_000]})
    with pytest.raises(ValueError, match="scale_b must be None"):
        surfmap.match(V, F, V, F, size=65, scale_b=-1.0)
    with pytest.raises(ValueError, match="size: grid size 100"):
        surfmap.match(V, F, V, F, size=100)
