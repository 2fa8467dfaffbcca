"""Flattening a large set of meshes, or registering a template onto many scans, on a
cluster: Dask distributed (tested), Ray (recipe).

The unit of work is ``surfmap.flatten_file(path, outdir, name, **options)``: it reads
one mesh file, flattens it, writes ``NAME.obj`` and ``NAME.json`` into ``outdir`` and
returns one row of the batch table, never raising for a bad mesh. Any engine that maps a
function over a list can run it; the rows of all meshes make one table (columns
``surfmap.BATCH_COLUMNS``, the same as ``summary.csv`` of ``flatten_many`` and of
``surfmap flatten A B … -o DIR/``), failures listed with their reason.

On a multi-node cluster: install the same surfmap on every worker, and put the meshes
and ``outdir`` on a file system every worker sees (the paths are opened by the workers;
only the rows travel back). A ``LocalCluster`` runs the very same code path on one
machine. Each task uses the cores of its worker for its own parallel loops; with as many
worker threads as cores, set ``RAYON_NUM_THREADS=1`` in the workers' environment to avoid
oversubscription.

Dask distributed::

    import glob
    from dask.distributed import Client
    from surfmap.distributed import flatten_on_dask

    client = Client("tcp://scheduler:8786")   # or Client(LocalCluster(n_workers=2))
    table = flatten_on_dask(client, sorted(glob.glob("/shared/scans/*.ply")),
                            "/shared/flat", table="/shared/flat/summary.parquet",
                            fill_holes=True)
    print(table[table.status == "failed"][["input", "error"]])

Registration (``register``): one task per scan, ``surfmap.register_file`` — the
template is prepared once per worker process and reused by its later tasks; the rows
gather into the table of ``surfmap register`` (``summary.csv`` and ``summary.json`` in
``outdir``)::

    from surfmap.distributed import register
    table = register("/shared/template.obj", "/shared/scans/*.ply", "/shared/reg",
                     client=Client("tcp://scheduler:8786"))
    print(table.groupby("verdict").size())

Ray (the same unit of work; this recipe is not run by the test suite)::

    import glob, pandas, ray, surfmap

    ray.init(address="auto")

    @ray.remote
    def flatten_task(path, outdir, name, options):
        return surfmap.flatten_file(path, outdir, name, **options)

    paths = sorted(glob.glob("/shared/scans/*.ply"))
    options = {"fill_holes": True}
    refs = [flatten_task.remote(p, "/shared/flat", n, options)
            for p, n in zip(paths, surfmap.output_names(paths))]
    table = pandas.DataFrame(ray.get(refs), columns=surfmap.BATCH_COLUMNS)
    table.to_parquet("/shared/flat/summary.parquet", index=False)
"""

import functools
import os
from typing import TYPE_CHECKING, Any, Dict, Iterable, List, Optional, Union

from ._surfmap import (
    BATCH_COLUMNS,
    REGISTER_COLUMNS,
    _check_flatten_options,
    _check_register,
    flatten_file,
    output_names,
    register_file,
)

if TYPE_CHECKING:
    import pandas

__all__ = ["flatten_on_dask", "failed_row", "register", "write_table"]

PathLike = Union[str, "os.PathLike[str]"]


def failed_row(path: str, error: str, columns: Iterable[str] = BATCH_COLUMNS) -> Dict[str, Any]:
    """A row of the batch table (``columns``: ``BATCH_COLUMNS`` or ``REGISTER_COLUMNS``)
    for a mesh whose task never returned (a worker that died, a cancelled future): every
    number None, the reason in ``error``."""
    row: Dict[str, Any] = {column: None for column in columns}
    row.update(input=path, status="failed", error=error)
    return row


def _gather(futures: List[Any], paths: List[str], columns: Iterable[str]) -> List[Dict[str, Any]]:
    """The futures' rows in input order; a task lost on the cluster becomes a failed row."""
    from dask.distributed import as_completed

    position = {future.key: i for i, future in enumerate(futures)}
    rows: List[Optional[Dict[str, Any]]] = [None] * len(paths)
    for future in as_completed(futures):
        i = position[future.key]
        try:
            rows[i] = future.result()
        except Exception as e:  # the task itself never raises: the cluster lost it
            rows[i] = failed_row(paths[i], f"task failed on the cluster: {type(e).__name__}: {e}", columns)
    return rows  # type: ignore[return-value]


def write_table(table: "pandas.DataFrame", path: PathLike) -> None:
    """Writes the table as CSV, or as Parquet for a ``.parquet`` path (Parquet needs
    pyarrow or fastparquet installed)."""
    path = os.fspath(path)
    if path.endswith(".parquet"):
        table.to_parquet(path, index=False)
    else:
        table.to_csv(path, index=False)


def flatten_on_dask(
    client: Any,
    paths: Iterable[PathLike],
    outdir: PathLike,
    table: Optional[PathLike] = None,
    **options: Any,
) -> "pandas.DataFrame":
    """Flattens every mesh file of ``paths`` on the Dask cluster of ``client`` into the
    folder ``outdir`` (``NAME.obj`` and ``NAME.json`` per mesh, NAME from
    ``surfmap.output_names``).

    Returns the table of all meshes as a pandas DataFrame in input order (columns
    ``surfmap.BATCH_COLUMNS``): every good mesh with its numbers, every bad one with
    ``status == "failed"`` and the reason in ``error``; a task lost on the cluster is
    listed the same way. With ``table`` (a ``.csv`` or ``.parquet`` path) the table is
    also written there. ``options`` are the keywords of ``surfmap.flatten``, checked
    here before any task starts.
    """
    import pandas as pd

    _check_flatten_options(**options)
    paths = [os.fspath(p) for p in paths]
    outdir = os.fspath(outdir)
    os.makedirs(outdir, exist_ok=True)
    names = output_names(paths)
    task = functools.partial(flatten_file, **options)
    futures = client.map(task, paths, [outdir] * len(paths), names, pure=False)
    rows = _gather(futures, paths, BATCH_COLUMNS)
    frame = pd.DataFrame(rows, columns=list(BATCH_COLUMNS))
    if table is not None:
        write_table(frame, table)
    return frame


def register(
    template: PathLike,
    scans: Union[PathLike, Iterable[PathLike]],
    outdir: PathLike,
    client: Any,
    landmarks_dir: Optional[PathLike] = None,
    keep_matches: bool = False,
    size: Optional[int] = None,
    budget: Optional[int] = None,
    table: Optional[PathLike] = None,
) -> "pandas.DataFrame":
    """Registers the template onto every scan on the Dask cluster of ``client``, one task
    per scan (``surfmap.register_file``), into the folder ``outdir`` (files as
    ``surfmap.register`` writes them; ``scans``: files, a folder or a glob pattern).

    The template is checked here first (a ``ValueError`` if it cannot be matched), and
    prepared once in each worker process, whose later tasks reuse it. Returns the table
    of all scans as a pandas DataFrame in input order (columns
    ``surfmap.REGISTER_COLUMNS``), also written as ``outdir/summary.csv`` and
    ``summary.json`` (and to ``table``, ``.csv`` or ``.parquet``, when given); a bad
    scan, or a task lost on the cluster, is a row with ``status == "failed"`` and the
    reason in ``error``.
    """
    import json

    import pandas as pd

    from . import scan_paths

    template = os.fspath(template)
    _check_register(template, size, budget)
    paths = scan_paths(scans)
    outdir = os.fspath(outdir)
    os.makedirs(outdir, exist_ok=True)
    names = output_names(paths)
    lm = None if landmarks_dir is None else os.fspath(landmarks_dir)
    task = functools.partial(register_file, landmarks_dir=lm, keep_matches=keep_matches, size=size, budget=budget)
    n = len(paths)
    futures = client.map(task, [template] * n, paths, [outdir] * n, names, pure=False)
    rows = _gather(futures, paths, REGISTER_COLUMNS)
    for row, name in zip(rows, names):
        row["name"] = name
    frame = pd.DataFrame(rows, columns=list(REGISTER_COLUMNS))
    # Each file written beside its place and renamed: never seen half written.
    tmp = os.path.join(outdir, f".summary.csv.tmp{os.getpid()}")
    frame.to_csv(tmp, index=False)
    os.replace(tmp, os.path.join(outdir, "summary.csv"))
    tmp = os.path.join(outdir, f".summary.json.tmp{os.getpid()}")
    with open(tmp, "w") as f:
        json.dump(rows, f, indent=2)
    os.replace(tmp, os.path.join(outdir, "summary.json"))
    if table is not None:
        write_table(frame, table)
    return frame
