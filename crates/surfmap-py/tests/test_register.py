"""One template registered onto a folder of scans, on a thread pool (`surfmap.register`)
and on a 2-worker Dask LocalCluster (`surfmap.distributed.register`): the scans are the
template's surface warped, sampled by other grids and moved, so the truth of every
registered vertex is known; broken scans are rows with their reason."""

import json
import math

import numpy as np
import pytest

import surfmap
import surfmap.distributed

SIZE = 129  # the matches' grid: small, for speed


def height(x, y):
    """A surface with features to match: waves and one bump off the centre."""
    return 0.25 * np.sin(3 * x) * np.cos(2 * y) + 0.2 * np.exp(-((x - 0.3) ** 2 + (y - 0.65) ** 2) / 0.02)


def grid(n):
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    V = np.c_[x.ravel(), y.ravel(), height(x.ravel(), y.ravel())]
    idx = np.arange(n * n).reshape(n, n)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    return V, np.r_[np.c_[a, b, c], np.c_[a, c, d]]


def warp(V, k):
    """A smooth non-rigid change of the surface, then a rigid motion (scan k)."""
    x, y, z = V.T
    W = np.c_[x + 0.03 * np.sin(2 * y + k), y + 0.02 * x * y, z + 0.05 * x * (1 - y)]
    a = 0.3 + 0.2 * k
    R = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    return W @ R.T + np.array([0.5 * k, -1.0, 0.2])


@pytest.fixture(scope="module")
def scans(tmp_path_factory):
    root = tmp_path_factory.mktemp("register")
    src = root / "scans"
    src.mkdir()
    V, F = grid(21)
    surfmap.write_obj(root / "template.obj", V, F)
    truth = {}
    for k, n in enumerate([28, 33]):
        W, G = grid(n)
        surfmap.write_obj(src / f"scan{k}.obj", warp(W, k), G)
        truth[f"scan{k}"] = warp(V, k)  # the template's vertices, warped and moved
    # Broken scans: no surface (three triangles on one edge), a NaN coordinate, an empty file.
    (src / "fin.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n")
    (src / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")
    (src / "empty.obj").write_text("")
    return root, truth


def registered(row):
    V, _ = surfmap.read_mesh(row["output"])
    return V


def check_table(rows, truth, root):
    by_name = {r["name"]: r for r in rows}
    assert sorted(by_name) == ["empty", "fin", "nan", "scan0", "scan1"]
    _, F = surfmap.read_mesh(root / "template.obj")
    for name, T in truth.items():
        row = by_name[name]
        assert row["status"] == "ok", row
        assert row["verdict"] in ("ok", "doubtful", "failed")
        V = registered(row)
        assert V.shape == T.shape
        assert np.array_equal(surfmap.read_mesh(row["output"])[1], F)
        err = np.linalg.norm(V - T, axis=1)
        # Within 3 % of the surface's width (√2) on average, 8 % at the 95th percentile.
        assert err.mean() < 0.03 * math.sqrt(2), (name, err.mean())
        assert np.percentile(err, 95) < 0.08 * math.sqrt(2), (name, np.percentile(err, 95))
    for name, words in [("fin", "edge"), ("nan", "nan"), ("empty", "no ")]:
        row = by_name[name]
        assert row["status"] == "failed" and row["output"] is None
        assert words in row["error"].lower(), row["error"]


def test_register_on_a_thread_pool(scans, tmp_path):
    root, truth = scans
    seen = []
    rows = surfmap.register(root / "template.obj", root / "scans", tmp_path, workers=2, progress=seen.append, size=SIZE)
    assert [r["name"] for r in rows] == ["empty", "fin", "nan", "scan0", "scan1"]
    assert sorted(r["name"] for r in seen) == sorted(r["name"] for r in rows)
    assert list(rows[0]) == surfmap.REGISTER_COLUMNS
    check_table(rows, truth, root)
    with open(tmp_path / "summary.json") as f:
        assert json.load(f) == rows
    assert (tmp_path / "summary.csv").read_text().splitlines()[0] == ",".join(surfmap.REGISTER_COLUMNS)
    # A rerun with resume keeps the rows of the scans done (their times included).
    again = surfmap.register(root / "template.obj", str(root / "scans" / "scan*.obj"), tmp_path, workers=1, resume=True, size=SIZE)
    assert again == [r for r in rows if r["name"].startswith("scan")]


def test_a_bad_template_is_refused_before_any_scan(scans, tmp_path):
    root, _ = scans
    with pytest.raises(ValueError, match="template"):
        surfmap.register(root / "scans" / "fin.obj", root / "scans" / "scan0.obj", tmp_path)
    with pytest.raises(ValueError, match="no scan in"):
        surfmap.register(root / "template.obj", str(root / "scans" / "*.ply"), tmp_path)


def test_register_on_a_dask_cluster(scans, tmp_path):
    distributed = pytest.importorskip("dask.distributed", reason="pip install surfmap[dask]")
    pytest.importorskip("pandas")
    root, truth = scans
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, env={"RAYON_NUM_THREADS": "1"}
    )
    with distributed.Client(cluster) as client:
        table = surfmap.distributed.register(root / "template.obj", root / "scans", tmp_path, client=client, size=SIZE)
    cluster.close()
    assert list(table.columns) == surfmap.REGISTER_COLUMNS
    rows = table.to_dict("records")
    rows = [{k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in r.items()} for r in rows]
    check_table(rows, truth, root)
    # The same registrations as on the thread pool (one process, same options).
    local = surfmap.register(root / "template.obj", root / "scans", tmp_path / "local", workers=1, size=SIZE)
    for r, l in zip(rows, local):
        assert (r["name"], r["status"], r["verdict"]) == (l["name"], l["status"], l["verdict"])
        if r["status"] == "ok":
            assert np.abs(registered(r) - registered(l)).max() < 1e-9
    with open(tmp_path / "summary.json") as f:
        assert [r["name"] for r in json.load(f)] == [r["name"] for r in rows]
