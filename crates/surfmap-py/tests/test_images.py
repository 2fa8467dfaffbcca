"""geometry_images returns the arrays `surfmap images` writes as .npy files: the same
names, dtypes, shapes and values; given UVs are used as they are."""

import json

import numpy as np
import pytest

import surfmap
from conftest import run_cli, wavy_grid


def test_images_match_the_command_line(cli, data, tmp_path):
    mesh = data / "nefertiti_small.off"
    run_cli(cli, "images", mesh, "-o", tmp_path, "--size", "65", "--quiet")
    manifest = json.loads((tmp_path / "images.json").read_text())
    img = surfmap.geometry_images(*surfmap.read_mesh(mesh), size=65)

    assert img["size"] == manifest["size"] == 65
    assert img["transform"] == manifest["transform"]
    assert img["length_unit"] == manifest["length_unit"]
    assert img["scale"] == manifest["scale"]
    assert {e["name"] for e in manifest["images"]} <= set(img)
    for entry in manifest["images"]:
        expected = np.load(tmp_path / entry["npy"])
        got = img[entry["name"]]
        assert got.dtype == expected.dtype and got.shape == expected.shape, entry["name"]
        assert np.array_equal(got, expected, equal_nan=True), entry["name"]
    assert len(img["pyramid"]) == len(manifest["pyramid"])
    for level, entry in zip(img["pyramid"], manifest["pyramid"]):
        assert (level["level"], level["size"], level["sigma"]) == (
            entry["level"],
            entry["size"],
            entry["sigma"],
        )
        for e in entry["images"]:
            assert np.array_equal(level[e["name"]], np.load(tmp_path / e["npy"]), equal_nan=True)


def test_given_uvs_and_features():
    """With the flat grid's own (x, y) as UVs the position image is the identity map
    ξ ↦ (x, y, 0) on the nodes inside, and the metric is the identity up to scale."""
    V, F = wavy_grid(9, amplitude=0.0)
    UV = V[:, :2].copy()
    img = surfmap.geometry_images(
        V,
        F,
        size=33,
        UV=UV,
        pyramid=False,
        features=[{"name": "left edge", "vertices": list(range(0, 81, 9)), "closed": False}],
    )
    assert np.array_equal(img["uv"], UV)
    assert "pyramid" not in img and img["features"] == ["left edge"]
    inside = img["mask"].astype(bool)
    assert inside.sum() > 0.8 * 33 * 33 * (1 - 2 / 32) ** 2
    s, (ox, oy) = img["transform"]["scale"], img["transform"]["offset"]
    j, i = np.meshgrid(np.arange(33), np.arange(33))
    xi = np.stack([j / 32, i / 32], axis=-1)
    expected = (xi - [ox, oy]) / s
    # Barycentric coordinates are float32: positions agree to its precision.
    assert np.abs(img["position"][inside][:, :2] - expected[inside]).max() < 1e-6
    assert np.all(img["position"][inside][:, 2] == 0)
    assert np.all(np.isnan(img["position"][~inside]))
    # Distance to the curve x = 0 along the flat surface, in ℓ = √area = 1: the node's x.
    d = img["feature_0"][inside]
    assert np.abs(d - expected[inside][:, 0]).max() < 0.05
    assert np.array_equal(img["feature_distance"], img["feature_0"], equal_nan=True)


def test_image_errors():
    V, F = wavy_grid(5)
    with pytest.raises(ValueError, match="size"):
        surfmap.geometry_images(V, F, size=100)
    with pytest.raises(ValueError, match="feature 'x': vertex 999 does not exist"):
        surfmap.geometry_images(V, F, size=17, features=[{"name": "x", "vertices": [999]}])
    flipped = V[:, :2].copy()
    flipped[12] = [5.0, 5.0]
    with pytest.raises(surfmap.MeshError, match="flip-free flattening"):
        surfmap.geometry_images(V, F, size=17, UV=flipped)
