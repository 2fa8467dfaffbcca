"""Flattening a large set of meshes on a cluster: Dask distributed (tested), Ray (recipe).

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

from ._surfmap import BATCH_COLUMNS, _check_flatten_options, flatten_file, output_names

if TYPE_CHECKING:
    import pandas

__all__ = ["flatten_on_dask", "failed_row", "write_table"]

PathLike = Union[str, "os.PathLike[str]"]


def failed_row(path: str, error: str) -> Dict[str, Any]:
    """A row of the batch table for a mesh whose task never returned (a worker that
    died, a cancelled future): every number None, the reason in ``error``."""
    row: Dict[str, Any] = {column: None for column in BATCH_COLUMNS}
    row.update(input=path, status="failed", error=error)
    return row


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
    from dask.distributed import as_completed

    _check_flatten_options(**options)
    paths = [os.fspath(p) for p in paths]
    outdir = os.fspath(outdir)
    os.makedirs(outdir, exist_ok=True)
    names = output_names(paths)
    task = functools.partial(flatten_file, **options)
    futures = client.map(task, paths, [outdir] * len(paths), names, pure=False)
    position = {future.key: i for i, future in enumerate(futures)}
    rows: List[Optional[Dict[str, Any]]] = [None] * len(paths)
    for future in as_completed(futures):
        i = position[future.key]
        try:
            rows[i] = future.result()
        except Exception as e:  # the task itself never raises: the cluster lost it
            rows[i] = failed_row(paths[i], f"task failed on the cluster: {type(e).__name__}: {e}")
    frame = pd.DataFrame(rows, columns=list(BATCH_COLUMNS))
    if table is not None:
        write_table(frame, table)
    return frame
