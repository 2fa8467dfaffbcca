"""A 2-worker Dask LocalCluster (worker processes: the code path of a multi-node cluster)
flattens a folder of meshes, some broken: every good mesh is done, every broken one is
listed with its reason, all in one table written as CSV and Parquet."""

import json
import shutil

import numpy as np
import pytest

import surfmap
import surfmap.distributed
from conftest import read_vt, wavy_grid, without_times

distributed = pytest.importorskip("dask.distributed", reason="pip install surfmap[dask]")
pd = pytest.importorskip("pandas")


@pytest.fixture(scope="module")
def client():
    # Worker processes, one thread each; each solve on one core (two workers, two cores).
    cluster = distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        env={"RAYON_NUM_THREADS": "1"},
    )
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def test_a_folder_on_a_dask_cluster(client, data, tmp_path):
    src = tmp_path / "scans"
    src.mkdir()
    good = []
    for name in ["nefertiti_small.off", "three_peaks.off", "hemisphere.obj"]:
        shutil.copy(data / name, src / name)
        good.append(src / name)
    for n in (6, 9, 12):
        V, F = wavy_grid(n)
        surfmap.write_obj(src / f"wavy{n}.obj", V, F)
        good.append(src / f"wavy{n}.obj")
    broken = {
        src / "truncated.ply": "ply\nformat ascii 1.0\nelement vertex 3\n",
        src / "text.off": "this is not a mesh\n",
        src / "closed.obj": (data / "sphere.obj").read_text(),
    }
    for path, text in broken.items():
        path.write_text(text)
    paths = sorted(src.iterdir())
    out = tmp_path / "flat"

    table = surfmap.distributed.flatten_on_dask(
        client, paths, out, table=out / "summary.csv", preset="conformal"
    )

    assert list(table.columns) == surfmap.BATCH_COLUMNS
    assert table["input"].tolist() == [str(p) for p in paths]
    done = table[table.status == "ok"]
    failed = table[table.status == "failed"]
    assert sorted(done["input"]) == sorted(map(str, good))
    assert sorted(failed["input"]) == sorted(map(str, broken))
    assert failed["error"].str.len().min() > 20
    assert "needs exactly one boundary loop" in failed.set_index("input").loc[str(src / "closed.obj"), "error"]
    # Every good mesh: the flattening and report flatten computes here.
    for row in done.itertuples():
        UV, report = surfmap.flatten(*surfmap.read_mesh(row.input), preset="conformal")
        assert np.abs(read_vt(row.output) - UV).max() <= 1e-12
        with open(row.report) as f:
            assert without_times(json.load(f)) == without_times(report)
        assert row.iterations == report["iterations"]
    # The table on disk is the same table.
    on_disk = pd.read_csv(out / "summary.csv")
    assert on_disk["status"].tolist() == table["status"].tolist()
    assert np.allclose(on_disk["energy"], table["energy"].astype(float), equal_nan=True)
    if _has_parquet():
        surfmap.distributed.write_table(table, out / "summary.parquet")
        back = pd.read_parquet(out / "summary.parquet")
        assert back["input"].tolist() == table["input"].tolist()
        assert back["error"].tolist() == table["error"].tolist()


def _has_parquet() -> bool:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return False
    return True


def test_bad_options_are_caught_before_any_task(client, tmp_path):
    with pytest.raises(ValueError, match='unknown preset "fastest"'):
        surfmap.distributed.flatten_on_dask(client, ["a.obj"], tmp_path, preset="fastest")


def test_a_task_that_raises_is_listed_not_lost(client, data, tmp_path, monkeypatch):
    """flatten_file never raises for a bad mesh, but a task can still fail on the
    cluster (a worker killed, a library bug): it becomes a failed row, the others stay."""
    real = surfmap.flatten_file
    # A lambda is shipped to the workers by value.
    monkeypatch.setattr(
        surfmap.distributed,
        "flatten_file",
        lambda path, outdir, name, **kw: 1 / 0 if "boom" in path else real(path, outdir, name, **kw),
    )
    shutil.copy(data / "nefertiti_small.off", tmp_path / "good.off")
    shutil.copy(data / "nefertiti_small.off", tmp_path / "boom.off")
    table = surfmap.distributed.flatten_on_dask(client, [tmp_path / "good.off", tmp_path / "boom.off"], tmp_path)
    assert table["status"].tolist() == ["ok", "failed"]
    assert table["error"][1] == "task failed on the cluster: ZeroDivisionError: division by zero"
