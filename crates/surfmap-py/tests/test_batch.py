"""Batches: flatten_many and flatten_file write what flatten computes, list every bad mesh
with its reason without stopping, and give the same table as the command line's batch;
long solves release the GIL."""

import csv
import json
import shutil
import sys
import threading
import time

import numpy as np
import pytest

import surfmap
from conftest import read_corner_uvs, read_vt, run_cli, wavy_grid, without_times

# Every column but the files, the time and the error: what the flattening computed.
NUMBERS = [c for c in surfmap.BATCH_COLUMNS if c not in ("input", "status", "output", "report", "time_s", "error")]


@pytest.fixture
def folder(tmp_path, data):
    """Good meshes (two with the same stem) and broken ones of several kinds."""
    d = tmp_path / "meshes"
    (d / "other").mkdir(parents=True)
    for name in ["nefertiti_small.off", "three_peaks.off", "hemisphere.obj", "halftunnel.off"]:
        shutil.copy(data / name, d / name)
    V, F = wavy_grid(10)
    surfmap.write_obj(d / "other" / "hemisphere.obj", V, F)  # the same stem again
    (d / "garbage.off").write_text("OFF\n3 1 0\n0 0 0\nnot a number\n")
    (d / "empty.obj").write_text("")
    good = [d / "nefertiti_small.off", d / "three_peaks.off", d / "hemisphere.obj", d / "other" / "hemisphere.obj"]
    bad = [d / "garbage.off", d / "empty.obj", d / "halftunnel.off", d / "missing.ply"]
    return good, bad


def read_table(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], [dict(zip(rows[0], r)) for r in rows[1:]]


def test_flatten_many_writes_flattenings_and_lists_failures(folder, tmp_path):
    good, bad = folder
    paths = [good[0], bad[0], good[1], bad[1], good[2], bad[2], good[3], bad[3]]
    out = tmp_path / "out"
    seen = []
    rows = surfmap.flatten_many(paths, out, workers=2, progress=seen.append)

    assert [r["input"] for r in rows] == [str(p) for p in paths]
    assert sorted(r["input"] for r in seen) == sorted(str(p) for p in paths)
    assert [r["status"] for r in rows] == ["ok", "failed"] * 4
    names = surfmap.output_names(paths)
    assert names[4] == "hemisphere" and names[6] == "hemisphere-2"
    for row, path, name in zip(rows, paths, names):
        if row["status"] == "failed":
            assert row["output"] is None and row["energy"] is None
            assert str(path) in row["error"]
            assert not (out / f"{name}.obj").exists()
            continue
        assert row["error"] is None and row["output"] == str(out / f"{name}.obj")
        # What flatten computes, written exactly.
        V, F = surfmap.read_mesh(path)
        UV, report = surfmap.flatten(V, F)
        assert np.abs(read_vt(row["output"]) - UV).max() <= 1e-12
        written = json.loads(open(row["report"]).read())
        assert written["input"] == str(path)
        assert without_times(written) == without_times(report)
        assert row["iterations"] == report["iterations"] and row["energy"] == report["energy"]
        assert row["angle_mean"] == report["measures"]["measures"]["angle"]["mean"]
    errors = {r["input"]: r["error"] for r in rows if r["error"]}
    assert "garbage.off: line 4" in errors[str(bad[0])]
    assert "has no faces" in errors[str(bad[1])]
    assert "pass fill_holes=True" in errors[str(bad[2])]
    assert "cannot read" in errors[str(bad[3])]

    header, table = read_table(out / "summary.csv")
    assert header == surfmap.BATCH_COLUMNS
    assert [t["status"] for t in table] == [r["status"] for r in rows]
    for t, r in zip(table, rows):
        assert t["error"] == (r["error"] or "")
        assert t["energy"] == ("" if r["energy"] is None else repr(r["energy"]))


def test_options_reach_every_mesh(folder, tmp_path):
    good, _ = folder
    rows = surfmap.flatten_many(good[:2], tmp_path, workers=1, preset="conformal", normalize=True)
    for row, path in zip(rows, good):
        UV, report = surfmap.flatten(*surfmap.read_mesh(path), preset="conformal", normalize=True)
        assert np.abs(read_vt(row["output"]) - UV).max() <= 1e-12
        assert row["energy"] == report["energy"]
    row = surfmap.flatten_file(good[1], tmp_path, name="custom", fill_holes=True)
    assert row["output"] == str(tmp_path / "custom.obj") and row["holes_filled"] == 0


def test_the_command_line_batch_gives_the_same_table(cli, folder, tmp_path):
    good, bad = folder
    paths = good + bad
    # The command line fills holes by default: bad[2] (three boundary loops) is flattened.
    rows = surfmap.flatten_many(paths, tmp_path / "py", workers=2, fill_holes=True)
    assert [r["status"] for r in rows[len(good):]] == ["failed", "failed", "ok", "failed"]
    r = run_cli(cli, "flatten", *paths, "-o", f"{tmp_path / 'cli'}/", "--jobs", "2", "--quiet", ok=False)
    assert r.returncode == 1 and f"{len(bad) - 1} of {len(paths)} meshes failed" in r.stderr
    header, table = read_table(tmp_path / "cli" / "summary.csv")
    assert header == surfmap.BATCH_COLUMNS
    assert len(table) == len(rows)
    for t, row in zip(table, rows):
        assert t["input"] == row["input"] and t["status"] == row["status"]
        for column in NUMBERS:
            assert same_cell(t[column], row[column]), (column, t[column], row[column])
        if row["status"] == "ok":
            assert read_vt(t["output"]).tolist() == read_vt(row["output"]).tolist()


def same_cell(cell, value):
    """Whether a cell of the command line's summary.csv holds a row's value: empty for
    None, true/false, floats exactly (Rust writes 0.0 as 0), the rest as text."""
    if value is None:
        return cell == ""
    if isinstance(value, bool):
        return cell == str(value).lower()
    if isinstance(value, float):
        return float(cell) == value
    return cell == str(value)


def test_cutting_batches_give_the_command_lines_table(cli, data, tmp_path):
    """cut and max_distortion reach every mesh of a batch: a closed sphere cut open, and
    the distortion columns, the same as the command line's (which cuts by default)."""
    paths = [data / "sphere.obj", data / "hemisphere.obj", data / "nefertiti_small.off"]
    options = {"cut": "auto", "max_distortion": 1.05, "max_cut_rounds": 2}
    rows = surfmap.flatten_many(paths, tmp_path / "py", workers=2, **options)
    flags = ["--max-distortion", "1.05", "--max-cut-rounds", "2"]
    run_cli(cli, "flatten", *paths, "-o", f"{tmp_path / 'cli'}/", "--jobs", "2", "--quiet", *flags)
    header, table = read_table(tmp_path / "cli" / "summary.csv")
    assert header == surfmap.BATCH_COLUMNS
    assert rows[0]["plan"].startswith("cut open along seams (closed, genus 0)")
    assert all(r["distortion_bound"] == 1.05 for r in rows)
    for t, row, path in zip(table, rows, paths):
        assert row["status"] == "ok", row["error"]
        for column in NUMBERS:
            assert same_cell(t[column], row[column]), (column, t[column], row[column])
        UV, FUV, report = surfmap.flatten(*surfmap.read_mesh(path), **options)
        assert row["seam_edges"] == len((report["seams"] or {"edges": []})["edges"])
        for output in (row["output"], t["output"]):
            uv, fuv = read_corner_uvs(output)
            assert np.abs(uv - UV).max() <= 1e-12 and np.array_equal(fuv, FUV)


def test_progress_line(folder, tmp_path, capsys):
    good, bad = folder
    surfmap.flatten_many([good[0], bad[1]], tmp_path, workers=1, progress=True)
    err = capsys.readouterr().err
    assert "2/2 meshes, 1 failed" in err and err.endswith("\n")


def test_a_failing_progress_callback_does_not_lose_the_batch(folder, tmp_path, monkeypatch):
    good, _ = folder
    reported = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: reported.append(u.exc_value))

    def callback(row):
        raise RuntimeError("callback broke")

    rows = surfmap.flatten_many(good[:2], tmp_path, workers=1, progress=callback)
    assert [r["status"] for r in rows] == ["ok", "ok"]
    assert [str(e) for e in reported] == ["callback broke"] * 2


def stamps_inside(call):
    """Runs ``call`` in a thread while this thread records timestamps; returns how many
    fall inside the call, away from its ends by 10% of its length and by three GIL switch
    intervals (the thread may hand the GIL over just before or after ``call``)."""
    span = {}

    def run():
        span["start"] = time.perf_counter()
        call()
        span["end"] = time.perf_counter()

    stamps = []
    worker = threading.Thread(target=run)
    worker.start()
    while worker.is_alive():
        stamps.append(time.perf_counter())
    worker.join()
    margin = max(0.1 * (span["end"] - span["start"]), 3 * sys.getswitchinterval())
    return sum(span["start"] + margin < t < span["end"] - margin for t in stamps)


def test_flatten_releases_the_gil(data):
    """While one thread is inside flatten, another runs Python code: its timestamps fall
    inside the call. The control, a C function that holds the GIL (sorting a list of
    floats), lets none through."""
    # A call long against the margins (about 0.25 s here; the hemisphere's 0.02 s fell inside
    # the 2 x 15 ms margins on a fast machine and let no stamp count).
    V, F = surfmap.read_mesh(data / "faces" / "ict" / "ict_neutral.obj")
    assert stamps_inside(lambda: surfmap.flatten(V, F, multilevel="off", fill_holes=True)) > 100
    floats = np.random.default_rng(1).random(1_000_000).tolist()
    assert stamps_inside(lambda: sorted(floats)) == 0
