"""Variational surface maps on numpy arrays.

Flip-free flattening of triangle meshes (N. Litke, *Variational Methods in Surface
Parameterization*, 2005): discs as they are, and with ``cut="auto"`` closed, holed and
higher-genus surfaces cut open along seams (per-corner UVs); distortion measures and
geometry images; batches of mesh files on a thread pool (``flatten_many``) or a cluster
(``surfmap.distributed``); one template registered onto many scans (``register``).

Meshes are numpy arrays: ``V`` (n, 3) floats, one vertex position per row, and ``F``
(m, 3) integers, one counter-clockwise triangle per row. Reports are the dictionaries
the command line writes as JSON. Long computations release the GIL.

>>> import numpy as np, surfmap
>>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0.3], [0, 1, 0]], dtype=float)
>>> F = np.array([[0, 1, 2], [0, 2, 3]])
>>> UV, report = surfmap.flatten(V, F, preset="conformal")
>>> report["flipped_triangles"]
0

Errors: ``ValueError`` for bad arguments, ``MeshError`` (a ``ValueError``) for a mesh
that cannot be used as given (its message names each defect and its repair),
``SolverError`` (a ``RuntimeError``) when a computation fails, ``MatchNotTrusted`` (a
``RuntimeError``) when ``match(..., strict=True)`` made a match whose verdict is not ok,
``OSError`` for files.
"""

import os
import sys
import time
from typing import Any, Callable, Dict, Iterable, List, Optional, Union

from ._surfmap import (
    BATCH_COLUMNS,
    REGISTER_COLUMNS,
    MatchNotTrusted,
    MeshError,
    SolverError,
    __version__,
    _flatten_many,
    _register_many,
    crop,
    flatten,
    flatten_file,
    geometry_images,
    inspect,
    match,
    measure,
    output_names,
    read_mesh,
    register_file,
    repair,
    write_obj,
)

__all__ = [
    "BATCH_COLUMNS",
    "REGISTER_COLUMNS",
    "MatchNotTrusted",
    "MeshError",
    "SolverError",
    "__version__",
    "crop",
    "flatten",
    "flatten_file",
    "flatten_many",
    "geometry_images",
    "inspect",
    "match",
    "measure",
    "output_names",
    "read_mesh",
    "register",
    "register_file",
    "repair",
    "write_obj",
]

Row = Dict[str, Any]


class _ProgressLine:
    """A one-line progress display on a text stream: done/total, failures, rate."""

    def __init__(self, total: int, stream=None, what: str = "meshes") -> None:
        self.total = total
        self.what = what
        self.done = 0
        self.failed = 0
        self.start = time.perf_counter()
        self.stream = stream if stream is not None else sys.stderr

    def __call__(self, row: Row) -> None:
        self.done += 1
        self.failed += row["status"] != "ok"
        rate = self.done / max(time.perf_counter() - self.start, 1e-9)
        name = os.path.basename(row["input"])
        self.stream.write(
            f"\r{self.done}/{self.total} {self.what}, {self.failed} failed, "
            f"{rate:.2f}/s  {name[:40]:<40}"
        )
        self.stream.flush()

    def close(self) -> None:
        self.stream.write("\n")
        self.stream.flush()


def _workers(workers: Optional[int]) -> int:
    """``workers`` checked: a positive integer, or None for one per core (0)."""
    if workers is None:
        return 0
    if not isinstance(workers, int) or isinstance(workers, bool) or workers < 1:
        raise ValueError(
            f"workers must be a positive integer (or None: one per core), got {workers!r}"
        )
    return workers


def _progress(progress: Union[bool, Callable[[Row], None]], total: int, what: str):
    """The callback for ``progress`` (a callable as it is, True a progress line on
    stderr) and the line to close afterwards (or None)."""
    if callable(progress):
        return progress, None
    if progress:
        line = _ProgressLine(total, what=what)
        return line, line
    return None, None


def flatten_many(
    paths: Iterable[Union[str, "os.PathLike[str]"]],
    outdir: Union[str, "os.PathLike[str]"],
    workers: Optional[int] = None,
    progress: Union[bool, Callable[[Row], None]] = False,
    **options: Any,
) -> List[Row]:
    """Flattens many mesh files in parallel into the folder ``outdir``.

    Each mesh is written as ``outdir/NAME.obj`` with its report ``outdir/NAME.json``
    (NAME from ``output_names``); a mesh that cannot be read or flattened is reported
    and skipped, never stopping the batch. ``outdir/summary.csv`` gets one row per
    mesh (columns ``BATCH_COLUMNS``; failures with their reason in ``error``), and the
    same rows are returned as dictionaries, in input order.

    ``workers``: meshes flattened at once, and the threads used in total (None: one
    per core). ``progress``: True draws a progress line on stderr; a callable is called
    with each row as its mesh finishes (from a worker thread). ``options``: the
    keywords of ``flatten`` (``preset``, ``alpha``, ``fill_holes``, ``cut``,
    ``max_distortion``, ``normalize``, …); with ``cut`` the OBJ files have per-corner
    UVs, split along the seams.

    The same as ``surfmap flatten A B … -o OUTDIR/ --jobs WORKERS`` on the command
    line, which writes the same table.

    >>> import tempfile, surfmap
    >>> rows = surfmap.flatten_many(["missing.obj"], tempfile.mkdtemp(), workers=1)
    >>> [(r["status"], r["output"]) for r in rows]
    [('failed', None)]
    """
    paths = [os.fspath(p) for p in paths]
    workers = _workers(workers)
    callback, line = _progress(progress, len(paths), "meshes")
    try:
        return _flatten_many(paths, os.fspath(outdir), workers, callback, **options)
    finally:
        if line is not None:
            line.close()


def scan_paths(scans: Union[str, "os.PathLike[str]", Iterable[Union[str, "os.PathLike[str]"]]]) -> List[str]:
    """The scan files of ``scans``, as ``surfmap register`` reads them: a list of files
    (kept as given, in order), a folder (its OBJ, OFF and PLY files, sorted) or a glob
    pattern (``"scans/*.ply"``, sorted). A folder or pattern with no mesh file is a
    ``ValueError``."""
    import glob

    if isinstance(scans, (str, os.PathLike)):
        scans = [scans]
    out: List[str] = []
    for s in scans:
        s = os.fspath(s)
        if os.path.isdir(s):
            found = sorted(
                os.path.join(s, n)
                for n in os.listdir(s)
                if n.lower().endswith((".obj", ".off", ".ply")) and os.path.isfile(os.path.join(s, n))
            )
        elif glob.has_magic(s):
            found = sorted(p for p in glob.glob(s) if os.path.isfile(p))
        else:
            found = [s]
        if not found:
            raise ValueError(
                f"no scan in {s}: give mesh files (OBJ, OFF, PLY), a folder holding some, "
                "or a pattern such as 'scans/*.ply'"
            )
        out.extend(found)
    return out


def register(
    template: Union[str, "os.PathLike[str]"],
    scans: Union[str, "os.PathLike[str]", Iterable[Union[str, "os.PathLike[str]"]]],
    outdir: Union[str, "os.PathLike[str]"],
    workers: Optional[int] = None,
    progress: Union[bool, Callable[[Row], None]] = False,
    landmarks_dir: Optional[Union[str, "os.PathLike[str]"]] = None,
    keep_matches: bool = False,
    resume: bool = False,
    size: Optional[int] = None,
    budget: Optional[int] = None,
) -> List[Row]:
    """Registers the template onto every scan, in parallel, into the folder ``outdir``.

    Each scan gets ``outdir/registered/NAME.obj``: the template's triangles and vertex
    order at their places on the scan (vertices without a counterpart continued
    smoothly), and with ``keep_matches`` its match folder ``outdir/matches/NAME/``.
    ``outdir/summary.csv`` and ``summary.json`` get one row per scan (columns
    ``REGISTER_COLUMNS``: ``verdict`` is the match's confidence, ``ok``, ``doubtful`` or
    ``failed``; a scan that cannot be read or matched has ``status == "failed"`` and the
    reason in ``error``, and never stops the others). The same rows are returned as
    dictionaries, in input order.

    ``scans``: files, a folder or a glob pattern (``scan_paths``). ``workers``: scans
    registered at once, and threads used in total (None: one per core). ``progress``:
    True draws a progress line on stderr; a callable gets each row as it finishes.
    ``landmarks_dir``: one ``STEM.json`` per scan (``{"names", "A": template ids, "B":
    scan ids}``). ``resume``: skip the scans an earlier run registered into ``outdir``.
    ``size``, ``budget``: the matches' grid and budget (``surfmap match --size
    --budget``). The template is checked first: one that cannot be matched raises
    ``ValueError``.

    The same as ``surfmap register TEMPLATE SCANS… -o OUTDIR --jobs WORKERS --no-model``
    (``surfmap register --model-only OUTDIR`` builds the shape model of the folder). On a
    cluster: ``surfmap.distributed.register``.

    >>> import os, tempfile, numpy as np, surfmap
    >>> x, y = np.meshgrid(np.linspace(0, 1, 8), np.linspace(0, 1, 8))
    >>> V = np.c_[x.ravel(), y.ravel(), 0.2 * np.sin(3 * x.ravel())]
    >>> F = np.array([[i, i + 1, i + 9] for i in range(56) if i % 8 < 7]
    ...              + [[i, i + 9, i + 8] for i in range(56) if i % 8 < 7])
    >>> d = tempfile.mkdtemp()
    >>> surfmap.write_obj(os.path.join(d, "template.obj"), V, F)
    >>> rows = surfmap.register(os.path.join(d, "template.obj"), ["no/such/scan.obj"], d, workers=1, size=129)
    >>> [(r["name"], r["status"]) for r in rows]
    [('scan', 'failed')]
    """
    paths = scan_paths(scans)
    workers = _workers(workers)
    callback, line = _progress(progress, len(paths), "scans")
    try:
        return _register_many(
            os.fspath(template),
            paths,
            os.fspath(outdir),
            workers,
            callback,
            None if landmarks_dir is None else os.fspath(landmarks_dir),
            keep_matches,
            resume,
            size,
            budget,
        )
    finally:
        if line is not None:
            line.close()
