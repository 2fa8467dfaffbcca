"""The package computes what the command line computes: on the same meshes and options,
UVs agree to 1e-12 and the reports have the same fields with the same values. Only
wall-clock times and the input's name differ, and the wording of remedies: the command
line names its flags (--fill-holes), the package its keywords (fill_holes=True)."""

import json

import numpy as np
import pytest

import surfmap
from conftest import key_paths, read_corner_uvs, read_vt, run_cli, wavy_grid, without_times

# (mesh in the shared data folder, the command line's flags, the same as keywords)
CASES = [
    ("nefertiti_small.off", [], {}),
    ("three_peaks.off", [], {}),  # LSCM flips: the mean-value fallback
    ("hemisphere.obj", ["--preset", "conformal"], {"preset": "conformal"}),
    ("hemisphere.obj", ["--alpha", "1,2,3", "--energy", "litke"], {"alpha": (1, 2, 3)}),
    ("nefertiti_small.off", ["--energy", "sd"], {"energy": "sd"}),
    (
        "nefertiti_small.off",
        ["--from-alpha", "0.01,0.01,0.98", "--preset", "area"],
        {"from_alpha": (0.01, 0.01, 0.98), "preset": "area"},
    ),
    ("halftunnel.off", ["--fill-holes"], {"fill_holes": True}),
    (
        "hemisphere.obj",
        ["--multilevel", "on", "--coarse-vertices", "300"],
        {"multilevel": "on", "coarse_vertices": 300},
    ),
    ("three_peaks.off", ["--start", "mean-value"], {"start": "mean_value"}),
]


def compare_with_cli(cli, tmp_path, mesh_path, flags, options):
    obj, rep = tmp_path / "cli.obj", tmp_path / "cli.json"
    run_cli(cli, "flatten", mesh_path, "-o", obj, "--report", rep, "--quiet", *flags)
    cli_report = json.loads(rep.read_text())

    V, F = surfmap.read_mesh(mesh_path)
    if any(k in options for k in ("cut", "seams", "max_distortion")):
        # Per corner: the vt rows and the f v/vt indices of the command line's OBJ.
        UV, FUV, report = surfmap.flatten(V, F, **options)
        cli_uv, cli_fuv = read_corner_uvs(obj)
        assert np.array_equal(FUV, cli_fuv)
    else:
        UV, report = surfmap.flatten(V, F, **options)
        cli_uv = read_vt(obj)
        assert UV.shape == (len(V), 2)

    assert UV.shape == cli_uv.shape
    assert np.abs(UV - cli_uv).max() <= 1e-12
    assert report["input"] is None and cli_report["input"] == str(mesh_path)
    # The same fields, in the same order, with the same values.
    assert key_paths(report) == key_paths(cli_report)
    assert list(report) == list(cli_report)
    drop = ("input", "message")
    assert without_times(report, drop) == without_times(cli_report, drop)
    for d, c in zip(report["input_defects"], cli_report["input_defects"]):
        if d["kind"] == "several_boundary_loops":
            assert "fill_holes=True" in d["message"] and "--cut-holes" in c["message"]
    return report


@pytest.mark.parametrize("name,flags,options", CASES, ids=[f"{c[0]}{''.join(c[1])}" for c in CASES])
def test_flatten_matches_the_command_line(cli, data, tmp_path, name, flags, options):
    report = compare_with_cli(cli, tmp_path, data / name, flags, options)
    assert report["flipped_triangles"] == 0
    if "fill_holes" in options:
        assert report["holes_filled"] == 2
    if "multilevel" in options:
        assert report["start"] == "multilevel"
        assert report["multilevel"]["coarse_vertices"] <= 300


# Cutting: the command line cuts by default; the package with cut="auto" (or seams,
# max_distortion), returning the per-corner UVs the command line's OBJ holds.
CUT_CASES = [
    ("sphere.obj", [], {"cut": "auto"}),  # closed, genus 0
    ("three_holes.off", [], {"cut": "auto"}),  # closed, genus 3
    ("halftunnel.off", [], {"cut": "auto"}),  # holes filled: FUV is F
    ("halftunnel.off", ["--cut-holes"], {"cut": "holes"}),
    ("hemisphere.obj", ["--max-distortion", "1.02"], {"max_distortion": 1.02}),
    (
        "sphere.obj",
        ["--max-distortion", "1.05", "--max-cut-rounds", "3"],
        {"max_distortion": 1.05, "max_cut_rounds": 3},
    ),
]


@pytest.mark.parametrize("name,flags,options", CUT_CASES, ids=[f"{c[0]}{''.join(c[1])}" for c in CUT_CASES])
def test_cutting_matches_the_command_line(cli, data, tmp_path, name, flags, options):
    report = compare_with_cli(cli, tmp_path, data / name, flags, options)
    assert report["flipped_triangles"] == 0
    if "max_distortion" in options:
        assert report["distortion_cuts"]["bound"] == options["max_distortion"]


def test_the_callers_seams_match_the_command_lines_cut_along(cli, data, tmp_path):
    mesh = data / "sphere.obj"
    V, F = surfmap.read_mesh(mesh)
    _, _, first = surfmap.flatten(V, F, cut="auto")
    # The automatic seams given back as the caller's (0-based pairs for --cut-along).
    seams = np.array(first["seams"]["edges"])
    path = tmp_path / "seams.txt"
    path.write_text("".join(f"{a} {b}\n" for a, b in seams))
    report = compare_with_cli(cli, tmp_path, mesh, ["--cut-along", path], {"seams": seams})
    assert report["plan"] == "cut open along the given seams"
    assert report["seams"]["edges"] == first["seams"]["edges"]


def test_flatten_matches_the_command_line_on_a_generated_mesh(cli, tmp_path):
    """Runs without the shared data: a mesh written from arrays, then read by both."""
    V, F = wavy_grid(14)
    path = tmp_path / "wavy.obj"
    surfmap.write_obj(path, V, F)
    compare_with_cli(cli, tmp_path, path, ["--preset", "length"], {"preset": "length"})


def test_normalized_uvs_match_the_command_line(cli, data, tmp_path):
    mesh = data / "nefertiti_small.off"
    run_cli(cli, "flatten", mesh, "-o", tmp_path / "n.obj", "--normalize", "-q")
    UV, _ = surfmap.flatten(*surfmap.read_mesh(mesh), normalize=True)
    assert np.abs(UV - read_vt(tmp_path / "n.obj")).max() <= 1e-12
    assert UV.min() >= 0 and UV.max() == pytest.approx(1.0, abs=1e-12)


def test_inspect_matches_the_command_line(cli, data):
    for name in ["nefertiti_small.off", "mask_cone.off", "halftunnel.off", "moebius.obj", "sphere.obj"]:
        path = data / name
        cli_info = json.loads(run_cli(cli, "inspect", path, "--json").stdout)
        info = surfmap.inspect(*surfmap.read_mesh(path))
        assert list(info) == list(cli_info)
        assert (info["file"], info["format"]) == (None, None)
        # Defects: the same ones; the command line words remedies as its flags.
        assert len(info["defects"]) == len(cli_info["defects"])
        for d, c in zip(info["defects"], cli_info["defects"]):
            same = ("kind", "count", "examples", "blocks_flattening")
            assert {k: d[k] for k in same} == {k: c[k] for k in same}
            if d["kind"] == "several_boundary_loops":
                assert "fill_holes" in d["message"] and "--cut-holes" in c["message"]
        # Arrays hold triangles (a quad of the file is two faces here) and no UVs.
        assert info["faces"] == info["triangles"] == cli_info["triangles"]
        assert info["has_uvs"] is False
        drop = ("file", "format", "faces", "has_uvs", "defects")
        assert without_times(info, drop) == without_times(cli_info, drop), name


def test_measure_matches_the_command_line(cli, data, tmp_path):
    mesh = data / "three_peaks.off"
    V, F = surfmap.read_mesh(mesh)
    UV, _ = surfmap.flatten(V, F)
    surfmap.write_obj(tmp_path / "m.obj", V, F, UV)
    for flags, options in [([], {}), (["--raw", "--no-overlap"], {"normalize": False, "overlap": False})]:
        cli_m = json.loads(run_cli(cli, "measure", tmp_path / "m.obj", "--json", *flags).stdout)
        m = surfmap.measure(V, F, UV, **options)
        assert cli_m.pop("mesh") == str(tmp_path / "m.obj")
        assert m == cli_m
