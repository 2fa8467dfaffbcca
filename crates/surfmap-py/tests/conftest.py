"""Shared fixtures: the real meshes of the shared data folder, the `surfmap` binary, and
meshes generated in code (so the core tests run anywhere).

Like the Rust tests, tests on real meshes skip with a note when the data folder is
missing, except under CI=true, where they fail: a CI run must not pass by skipping. The
same holds for the command-line binary the equivalence tests compare against.
"""

import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]
IN_CI = os.environ.get("CI") == "true"


def _required(what: str, where: str) -> None:
    if IN_CI:
        pytest.fail(f"{what} not found ({where}); CI=true, so this test fails instead of skipping")
    pytest.skip(f"{what} not found ({where})")


@pytest.fixture(scope="session")
def data() -> pathlib.Path:
    """The shared data folder: $SURFMAP_DATA, else ../shared/data beside the repository."""
    d = pathlib.Path(os.environ.get("SURFMAP_DATA", REPO.parent / "shared" / "data"))
    if not (d / "manifest.json").is_file():
        _required("the shared data folder", f"{d}; set SURFMAP_DATA")
    return d


@pytest.fixture(scope="session")
def cli() -> str:
    """The `surfmap` binary: $SURFMAP_BIN, else the release build of the workspace."""
    candidates = [os.environ.get("SURFMAP_BIN")]
    target = os.environ.get("CARGO_TARGET_DIR", str(REPO / "target"))
    candidates.append(os.path.join(target, "release", "surfmap"))
    candidates.append(shutil.which("surfmap"))
    for c in candidates:
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return c
    _required("the surfmap binary", "set SURFMAP_BIN or build it with cargo build --release")


def run_cli(cli: str, *args: str, ok: bool = True) -> subprocess.CompletedProcess:
    """Runs the command line; with ``ok`` it must succeed."""
    r = subprocess.run([cli, *map(str, args)], capture_output=True, text=True)
    if ok:
        assert r.returncode == 0, r.stderr
    return r


def wavy_grid(n: int = 12, amplitude: float = 0.3):
    """A disc: an n×n grid of the unit square lifted to z = a·sin(3x)·cos(2y)."""
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    V = np.c_[x.ravel(), y.ravel(), amplitude * np.sin(3 * x.ravel()) * np.cos(2 * y.ravel())]
    idx = np.arange(n * n).reshape(n, n)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    F = np.r_[np.c_[a, b, c], np.c_[a, c, d]]
    return V, F


def read_vt(path) -> np.ndarray:
    """The texture coordinates (`vt` lines) of an OBJ file, in order."""
    with open(path) as f:
        return np.array([[float(x) for x in line.split()[1:3]] for line in f if line.startswith("vt ")])


def read_corner_uvs(path):
    """The texture coordinates of an OBJ file per corner: ``(UV, FUV)``, the ``vt`` rows
    and, per face, the (0-based) ``vt`` index of each corner (``f v/vt …``)."""
    UV, FUV = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("vt "):
                UV.append([float(x) for x in line.split()[1:3]])
            elif line.startswith("f "):
                FUV.append([int(c.split("/")[1]) - 1 for c in line.split()[1:]])
    return np.array(UV), np.array(FUV)


def without_times(value, drop=("input",)):
    """A report tree without wall-clock fields (``time*`` keys) and the keys ``drop``."""
    if isinstance(value, dict):
        return {
            k: without_times(v, drop)
            for k, v in value.items()
            if not k.startswith("time") and k not in drop
        }
    if isinstance(value, list):
        return [without_times(v, drop) for v in value]
    return value


def key_paths(value, prefix=""):
    """Every key of a report tree as a path (``measures.angle.mean``); list items share
    one path (``log[].energy``)."""
    out = set()
    if isinstance(value, dict):
        for k, v in value.items():
            out.add(prefix + k)
            out |= key_paths(v, prefix + k + ".")
    elif isinstance(value, list):
        for v in value:
            out |= key_paths(v, prefix.rstrip(".") + "[].")
    return out
