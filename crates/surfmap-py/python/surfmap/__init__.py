"""Variational surface maps on numpy arrays.

Flip-free flattening of triangle meshes (N. Litke, *Variational Methods in Surface
Parameterization*, 2005): discs as they are, and with ``cut="auto"`` closed, holed and
higher-genus surfaces cut open along seams (per-corner UVs); distortion measures and
geometry images; batches of mesh files on a thread pool (``flatten_many``) or a cluster
(``surfmap.distributed``).

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
    MatchNotTrusted,
    MeshError,
    SolverError,
    __version__,
    _flatten_many,
    crop,
    flatten,
    flatten_file,
    geometry_images,
    inspect,
    match,
    measure,
    output_names,
    read_mesh,
    repair,
    write_obj,
)

__all__ = [
    "BATCH_COLUMNS",
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
    "repair",
    "write_obj",
]

Row = Dict[str, Any]


class _ProgressLine:
    """A one-line progress display on a text stream: done/total, failures, rate."""

    def __init__(self, total: int, stream=None) -> None:
        self.total = total
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
            f"\r{self.done}/{self.total} meshes, {self.failed} failed, "
            f"{rate:.2f}/s  {name[:40]:<40}"
        )
        self.stream.flush()

    def close(self) -> None:
        self.stream.write("\n")
        self.stream.flush()


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
    if workers is None:
        workers = 0
    elif not isinstance(workers, int) or isinstance(workers, bool) or workers < 1:
        raise ValueError(
            f"workers must be a positive integer (or None: one per core), got {workers!r}"
        )
    line = None
    if callable(progress):
        callback = progress
    elif progress:
        callback = line = _ProgressLine(len(paths))
    else:
        callback = None
    try:
        return _flatten_many(paths, os.fspath(outdir), workers, callback, **options)
    finally:
        if line is not None:
            line.close()
