"""Bad input raises the right exception with a message that names the problem and the
remedy; any memory layout and the common dtypes give the same results as the plain
arrays; the remedies the messages name fix the defects they name."""

import os

import numpy as np
import pytest

import surfmap
from conftest import wavy_grid


@pytest.fixture
def grid():
    return wavy_grid(8)


@pytest.mark.parametrize(
    "V_of,needle",
    [
        (lambda V: V.tolist(), "must be a numpy array of shape (n, 3)"),
        (lambda V: V[:, :2], "must have shape (n, 3)"),
        (lambda V: V.ravel(), "got shape (192,)"),
        (lambda V: V[None], "must have shape (n, 3)"),
        (lambda V: V.astype(np.int64), "must hold floats"),
        (lambda V: V.astype(np.complex128), "must hold floats"),
        (lambda V: V.astype(str), "astype(numpy.float64)"),
    ],
)
def test_bad_vertex_arrays_are_value_errors(grid, V_of, needle):
    V, F = grid
    with pytest.raises(ValueError, match="V ") as e:
        surfmap.flatten(V_of(V), F)
    assert needle in str(e.value)
    assert not isinstance(e.value, surfmap.MeshError)


@pytest.mark.parametrize(
    "F_of,needle",
    [
        (lambda F: F.astype(float), "must hold integers"),
        (lambda F: F.astype(bool), "must hold integers"),
        (lambda F: F[:, :2], "must have shape (n, 3)"),
        (lambda F: None, "got a NoneType"),
    ],
)
def test_bad_triangle_arrays_are_value_errors(grid, F_of, needle):
    V, F = grid
    with pytest.raises(ValueError) as e:
        surfmap.inspect(V, F_of(F))
    assert needle in str(e.value) and "F" in str(e.value)


def test_indices_out_of_range_are_mesh_errors(grid):
    V, F = grid
    bad = F.copy()
    bad[5, 1] = len(V)
    with pytest.raises(surfmap.MeshError, match=rf"triangle 5 uses vertex {len(V)} \(corner 1\)"):
        surfmap.flatten(V, bad)
    bad[5, 1] = -1
    with pytest.raises(surfmap.MeshError, match=r"F\[5, 1\] = -1: vertex indices count from 0"):
        surfmap.measure(V, bad, V[:, :2])
    bad[5, 1] = 2**40
    with pytest.raises(surfmap.MeshError, match="must be below the number of vertices"):
        surfmap.inspect(V, bad)
    assert issubclass(surfmap.MeshError, ValueError)


def test_layouts_and_dtypes_give_identical_results(grid):
    V, F = grid
    UV, report = surfmap.flatten(V, F)
    variants = [
        (np.asfortranarray(V), F),
        (V, np.asfortranarray(F)),
        (np.repeat(V, 2, axis=0)[::2], F),  # a strided view
        (V, F.astype(np.int32)),
        (V, F.astype(np.uint32)),
        (V, F.astype(np.uint16)),
    ]
    for W, G in variants:
        UV2, report2 = surfmap.flatten(W, G)
        assert np.array_equal(UV, UV2)
        assert report2["energy"] == report["energy"]
    # float32 positions are widened exactly: the same as the float64 of the same values.
    V32 = V.astype(np.float32)
    assert np.array_equal(surfmap.flatten(V32, F)[0], surfmap.flatten(V32.astype(np.float64), F)[0])
    # Outputs are fresh C-ordered arrays that own their memory.
    assert UV.flags.c_contiguous and UV.flags.writeable and UV.dtype == np.float64


def test_not_a_disc_lists_each_defect_with_a_python_remedy(grid):
    V, F = grid
    # Two copies side by side with a duplicated vertex: two components, duplicates.
    V2 = np.r_[V, V + [2.0, 0, 0], V[:1]]
    F2 = np.r_[F, F + len(V)]
    with pytest.raises(surfmap.MeshError) as e:
        surfmap.flatten(V2, F2)
    kinds = [d["kind"] for d in e.value.defects]
    assert kinds == ["several_components", "several_boundary_loops"]
    message = str(e.value)
    assert message.startswith("the mesh cannot be flattened as a disc:")
    assert "surfmap.repair(V, F, keep_largest=True)" in message
    assert "repair::" not in message and "--" not in message
    # The remedies work: keep one component, drop the stray vertex, flatten.
    W, G, done = surfmap.repair(V2, F2, keep_largest=True, drop_unreferenced=True)
    # The stray vertex (no face uses it) is counted as unreferenced; keeping a component
    # drops the vertices only the other one used, with its faces.
    assert done == {"dropped_faces": len(F), "dropped_unreferenced": 1}
    assert np.array_equal(W, V) and np.array_equal(G, F)
    assert surfmap.inspect(W, G)["disc"]
    assert surfmap.flatten(W, G)[1]["flipped_triangles"] == 0


def test_remedies_fix_what_they_name(data):
    """The repairs the messages name, applied to real meshes with those defects."""
    V, F = surfmap.read_mesh(data / "mask_cone.off")  # duplicates, 2 components, 2 holes
    messages = {d["kind"]: d["message"] for d in surfmap.inspect(V, F)["defects"]}
    assert "surfmap.repair(V, F, weld=0.0)" in messages["duplicate_vertices"]
    assert "surfmap.repair(V, F, keep_largest=True)" in messages["several_components"]
    W, G, done = surfmap.repair(V, F, weld=0.0, keep_largest=True, drop_unreferenced=True)
    assert done["welded"] > 0 and done["dropped_faces"] > 0
    assert surfmap.inspect(W, G)["defects"] == []
    assert surfmap.flatten(W, G)[1]["flipped_triangles"] == 0

    V, F = surfmap.read_mesh(data / "halftunnel.off")  # three boundary loops
    with pytest.raises(surfmap.MeshError, match="pass fill_holes=True to fill"):
        surfmap.flatten(V, F)
    UV, report = surfmap.flatten(V, F, fill_holes=True)
    assert report["holes_filled"] == 2 and report["flipped_triangles"] == 0


def test_fix_non_manifold_makes_the_raw_head_scan_flattenable(data):
    """The FLAME head scan: 11 edges with more than two faces, pinched vertices, hair
    fragments. The messages name fix_non_manifold; the named repairs make it a manifold
    surface that flattens without a flipped triangle."""
    V, F = surfmap.read_mesh(data / "faces" / "flame" / "flame_scan.obj")
    messages = {d["kind"]: d["message"] for d in surfmap.inspect(V, F)["defects"]}
    assert "fix_non_manifold=True" in messages["non_manifold_edges"]
    assert "fix_non_manifold=True" in messages["non_manifold_vertices"]
    W, G, done = surfmap.repair(
        V, F, fix_non_manifold=True, keep_largest=True, drop_unreferenced=True
    )
    assert done["cut_edges"] == 11 and done["split_vertices"] > 0
    assert done["dropped_faces"] > 0  # the pieces cut loose
    # The input's vertices used by no face are counted, not hidden in the dropped pieces.
    unused = len(V) - len(np.unique(F))
    assert unused > 0 and done["dropped_unreferenced"] >= unused
    kinds = [d["kind"] for d in surfmap.inspect(W, G)["defects"]]
    assert "non_manifold_edges" not in kinds and "non_manifold_vertices" not in kinds
    # No face is removed but the loose pieces (fins, hair fragments).
    assert len(G) > 0.99 * len(F)
    UV, report = surfmap.flatten(W, G, fill_holes=True)
    assert report["flipped_triangles"] == 0


def test_a_bow_tie_is_split_into_two_discs(grid):
    V, F = grid
    # A second copy whose corner 0 is glued onto the first copy's last vertex.
    n = len(V)
    V2 = np.r_[V, V[1:] + (V[-1] - V[0])]
    F_second = np.where(F == 0, n - 1, F + n - 1)
    F2 = np.r_[F, F_second]
    kinds = [d["kind"] for d in surfmap.inspect(V2, F2)["defects"]]
    assert "non_manifold_vertices" in kinds
    W, G, done = surfmap.repair(V2, F2, fix_non_manifold=True)
    assert done == {
        "cut_edges": 0,
        "unpaired_faces": 0,
        "dropped_non_manifold_faces": 0,
        "split_vertices": 1,
    }
    assert len(W) == len(V2) + 1 and np.array_equal(W[-1], V[-1])
    assert np.array_equal(W[G], V2[F2])  # the same triangles in space
    W, G, _ = surfmap.repair(W, G, keep_largest=True, drop_unreferenced=True)
    assert surfmap.inspect(W, G)["disc"]


def test_non_finite_positions_are_mesh_errors(grid):
    V, F = grid
    V = V.copy()
    V[3, 2] = np.nan
    with pytest.raises(surfmap.MeshError) as e:
        surfmap.flatten(V, F)
    assert [d["kind"] for d in e.value.defects] == ["non_finite_coordinates"]
    assert e.value.defects[0]["examples"] == [[3]]


def test_damaged_input_gets_one_verdict_from_inspect_and_flatten(grid, tmp_path):
    """The damaged inputs of issue 50: a NaN on a face, coordinates whose areas overflow,
    a face given twice. inspect names the defect that flatten raises for, in the same
    words, and does not call the mesh a disc; the repair the message names makes it
    flattenable; a binary file named .obj is refused as binary."""
    V, F = grid
    nan = V.copy()
    nan[7, 0] = np.nan
    cases = [
        (nan, F, "non_finite_coordinates", "NaN or infinite coordinates (first: 7)"),
        (V * 1e300, F, "overflowing_coordinates", "overflow to infinity"),
        (V, np.r_[F, F[[1]][:, [0, 2, 1]]], "duplicate_faces", f"(repeat and first: ({len(F)}, 1))"),
    ]
    for W, G, kind, words in cases:
        report = surfmap.inspect(W, G)
        assert not report["disc"] and report["flatten"] == "refused", kind
        said = [d for d in report["defects"] if d["kind"] == kind]
        assert said and said[0]["blocks_flattening"] and words in said[0]["message"], report
        with pytest.raises(surfmap.MeshError) as e:
            surfmap.flatten(W, G)
        assert [d["kind"] for d in e.value.defects] == [kind]
        assert words in str(e.value) and "count from 0" in str(e.value)
    W, G, done = surfmap.repair(V, cases[2][1], drop_degenerate=True)
    assert done == {"dropped_degenerate": 1} and np.array_equal(G, F)
    assert surfmap.flatten(W, G)[1]["flipped_triangles"] == 0
    binary = tmp_path / "binary.obj"
    binary.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(surfmap.MeshError, match="byte 0x00 is not text, but a .obj file is text"):
        surfmap.read_mesh(binary)


@pytest.mark.parametrize(
    "options,needle",
    [
        ({"preset": "fast"}, 'unknown preset "fast"; choose one of "conformal", "balanced"'),
        ({"energy": "dirichlet"}, "unknown energy"),
        ({"alpha": (1, -1, 1)}, "alpha"),
        ({"alpha": (1, 2)}, "alpha must be three numbers (length, area, angle weights)"),
        ({"from_alpha": (1, 1, 1), "energy": "mips"}, "from_alpha"),
        ({"tolerance": 0.0}, "tolerance must be positive, got 0"),
        ({"armijo_c": 1.5}, "armijo_c must be in (0, 1)"),
        ({"coarse_vertices": 3}, "coarse_vertices must be at least 16"),
        ({"multilevel": "on", "start": "lscm"}, 'multilevel="on" needs start="auto"'),
    ],
)
def test_bad_options_are_value_errors(grid, options, needle):
    V, F = grid
    with pytest.raises((ValueError, TypeError)) as e:
        surfmap.flatten(V, F, **options)
    assert needle in str(e.value)
    assert not isinstance(e.value, surfmap.MeshError)


def test_unknown_batch_options_are_value_errors(tmp_path):
    with pytest.raises(ValueError, match='unknown option "tolerence"; the flattening options are .*tolerance'):
        surfmap.flatten_file("x.obj", tmp_path, tolerence=1e-9)
    with pytest.raises(ValueError, match="option max_iters"):
        surfmap.flatten_many(["x.obj"], tmp_path, max_iters="many")
    with pytest.raises(ValueError, match="workers must be a positive integer"):
        surfmap.flatten_many(["x.obj"], tmp_path, workers=0)


def test_uv_arrays_are_checked(grid):
    V, F = grid
    with pytest.raises(ValueError, match="UV has 10 rows but the mesh has 64 vertices"):
        surfmap.measure(V, F, V[:10, :2])
    with pytest.raises(ValueError, match=r"UV must have shape \(n, 2\)"):
        surfmap.write_obj("x.obj", V, F, UV=V)


def test_file_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="no_such.obj"):
        surfmap.read_mesh(tmp_path / "no_such.obj")
    with pytest.raises(ValueError, match="unknown mesh file extension"):
        surfmap.read_mesh(tmp_path / "mesh.stl")
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n")
    with pytest.raises(surfmap.MeshError, match="bad.off: line 5"):
        surfmap.read_mesh(bad)
    V, F = wavy_grid(3)
    with pytest.raises(OSError, match="cannot write"):
        surfmap.write_obj(tmp_path / "missing_dir" / "m.obj", V, F)
    # A failed write leaves nothing behind.
    assert os.listdir(tmp_path) == ["bad.off"]


def test_a_closed_surface_is_refused_unless_cut(data):
    """Without cut, flatten returns one UV per vertex, so it never cuts: a closed surface
    is refused with the keyword that cuts it (not the command line's flag); with it, the
    surface is cut open as the command line cuts it."""
    V, F = surfmap.read_mesh(data / "sphere.obj")
    assert surfmap.inspect(V, F)["flatten_cuts"]  # what `surfmap flatten` would do
    with pytest.raises(surfmap.MeshError) as e:
        surfmap.flatten(V, F)
    assert [d["kind"] for d in e.value.defects] == ["closed_surface"]
    assert 'pass cut="auto"' in str(e.value) and "--" not in str(e.value)
    UV, FUV, report = surfmap.flatten(V, F, cut="auto")
    assert report["plan"] == "cut open along seams (closed, genus 0)" and FUV.shape == F.shape


def test_crop_cuts_the_scan_to_its_face_and_refuses_bad_requests(data):
    """The repaired FLAME scan cut to 10 cm around its nose tip (the vertex farthest
    forward): a disc of input vertices, all within the radius, the tip among them;
    the geodesic ball of the same radius is a part of it. Bad radius or an empty ball:
    ValueError naming the problem."""
    V, F = surfmap.read_mesh(data / "faces" / "flame" / "flame_scan.obj")
    V, F, _ = surfmap.repair(
        V, F, fix_non_manifold=True, keep_largest=True, drop_unreferenced=True
    )
    tip = V[np.argmax(V[:, 2])]
    W, G, ids = surfmap.crop(V, F, center=tip, radius=0.1)
    assert np.array_equal(W, V[ids]) and np.all(np.diff(ids) > 0)
    assert np.all(np.linalg.norm(W - tip, axis=1) <= 0.1)
    assert surfmap.inspect(W, G)["disc"]
    Wg, Gg, ids_g = surfmap.crop(V, F, center=tip, radius=0.1, geodesic=True)
    assert set(ids_g) <= set(ids) and len(Gg) < len(G)
    with pytest.raises(ValueError, match="finite and positive"):
        surfmap.crop(V, F, center=tip, radius=0.0)
    with pytest.raises(ValueError, match="give a larger radius"):
        surfmap.crop(V, F, center=tip + [1.0, 0, 0], radius=0.01)
