#!/usr/bin/env python3
"""Protruding shapes (issue 50): surfmap beside xatlas and libigl (cut + SLIM).

Every input is a closed mesh with long thin protrusions (written by
`cargo run --release -p surfmap-bench --example protrusions -- --save DIR`). Per tool:
the charts of the map, its seam length (half the 3D length of the map's boundary: the
inputs are closed, so every boundary edge is one side of a seam), the flipped triangles
and whether the boundary crosses itself, the referee's distortion
(`../shared/peers/distortion.py`: mean symmetric Dirichlet /4 on the area-normalized
map, 1 for an isometry; area distortion exp(mean |ln s1 s2|) and max s1 s2), and the
time of the method.

- surfmap: `surfmap flatten MESH -o OUT --report R.json` (default options); its time is
  the report's `time_total_s` (the whole library call, reading and writing excluded).
  `--before BIN` runs a build from before the cuts along protrusions the same way.
- xatlas: `Atlas.add_mesh` + `generate` (default chart options; its own charts, LSCM
  per chart and packing), timed around those calls.
- libigl: `igl.cut_to_disk` leaves a closed genus-0 mesh uncut, so the mesh is cut
  along the shortest edge path between two vertices far apart (double Dijkstra sweep,
  scipy), opened with `igl.cut_mesh`, started from a harmonic map onto the circle
  (uniform Tutte if that flips, as `run_peers.py`) and solved by SLIM (symmetric
  Dirichlet) until the energy drops by less than 1e-7 over 5 iterations or 500
  iterations; timed from the cut on.

Usage (the peers' interpreter, see ../shared/peers/README.md):

    /opt/peers-venv/bin/python scripts/protrusion_peers.py --surfmap target/release/surfmap \
        [--before OLD/surfmap] /tmp/protrusions/tentacles_*.obj
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

PEERS = os.environ.get("PEERS_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "shared", "peers"))
sys.path.insert(0, os.path.abspath(PEERS))
import distortion as D  # noqa: E402


def edges_of(F):
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    return e


def boundary_edges(F):
    """Directed edges of F whose reverse is not an edge of F."""
    e = edges_of(F)
    present = set(map(tuple, e.tolist()))
    return [(a, b) for a, b in e.tolist() if (b, a) not in present]


def seam_length(V, F):
    """Half the 3D length of the boundary of the mesh (V, F) (closed inputs: the seams)."""
    b = boundary_edges(F)
    return 0.5 * sum(float(np.linalg.norm(V[a] - V[c])) for a, c in b)


def cross2(a, b):
    return a[0] * b[1] - a[1] * b[0]


def crossings(UV, F):
    """Pairs of non-adjacent boundary edges of the UV mesh that cross (0: no overlap)."""
    b = boundary_edges(F)
    seg = np.array([[UV[a], UV[c]] for a, c in b])
    n = len(seg)
    if n == 0:
        return 0
    lo = seg.min(axis=1)
    hi = seg.max(axis=1)
    count = 0
    for i in range(n):
        cand = np.nonzero(np.all(lo[i + 1:] <= hi[i], axis=1) & np.all(hi[i + 1:] >= lo[i], axis=1))[0] + i + 1
        p, q = seg[i]
        for j in cand:
            if set(b[i]) & set(b[j]):
                continue
            r, s = seg[j]
            d1 = cross2(q - p, r - p)
            d2 = cross2(q - p, s - p)
            d3 = cross2(s - r, p - r)
            d4 = cross2(s - r, q - r)
            if d1 * d2 < 0 and d3 * d4 < 0:
                count += 1
    return count


def scored(V, F, corner_uv, UVm, Fm, Vm):
    d = D.distortion(V, F, corner_uv)
    return {
        "charts": d["charts"],
        "flipped": d["flipped"] + d["degenerate_uv"],
        "crossings": crossings(UVm, Fm),
        "seam": seam_length(Vm, Fm),
        "D": d["sym_dirichlet_mean"],
        "area_avg": math.exp(d["log_area_mean_abs"]),
        "area_max": d["area_max"],
    }


def run_surfmap(binary, path, work):
    out = os.path.join(work, "surfmap.obj")
    report = os.path.join(work, "surfmap.json")
    p = subprocess.run([binary, "flatten", "-q", path, "-o", out, "--report", report],
                       capture_output=True, text=True)
    if p.returncode != 0:
        return {"failed": p.stderr.strip().splitlines()[-1][:120]}
    r = json.load(open(report))
    V, F, cuv = D.load_mesh(out)
    # The written map as its own mesh: one vertex per UV (OBJ `vt`), faces from `f v/t`.
    ft, vt = [], []
    for line in open(out):
        if line.startswith("vt "):
            vt.append([float(x) for x in line.split()[1:3]])
        elif line.startswith("f "):
            ft.append([int(tok.split("/")[1]) - 1 for tok in line.split()[1:]])
    Fm = np.array(ft, dtype=np.int64)
    UVm = np.array(vt)
    Vm = np.zeros((len(vt), 3))
    Vm[Fm.ravel()] = V[F.ravel()]
    row = scored(V, F, cuv, UVm, Fm, Vm)
    cuts = r.get("protrusion_cuts")
    note = f"{r['start']} start, {r['iterations']} iterations" + (
        f", {cuts} protrusion cuts" if cuts is not None else "")
    row.update(time=r["time_total_s"], note=note)
    return row


def run_xatlas(V, F):
    import xatlas
    t0 = time.perf_counter()
    atlas = xatlas.Atlas()
    atlas.add_mesh(V.astype(np.float32), F.astype(np.uint32))
    atlas.generate()
    vmap, idx, uv = atlas.get_mesh(0)
    t = time.perf_counter() - t0
    idx = idx.astype(np.int64)
    uv = uv.astype(np.float64)
    Vm = V[vmap.astype(np.int64)]
    row = scored(Vm, idx, uv[idx], uv, idx, Vm)
    row.update(time=t, note=f"{atlas.chart_count} charts reported")
    return row


def far_path(V, F):
    """Shortest edge path between two vertices far apart (two Dijkstra sweeps)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra
    e = edges_of(F)
    w = np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1)
    n = len(V)
    G = coo_matrix((w, (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    d0 = dijkstra(G, directed=False, indices=0)
    a = int(np.argmax(d0))
    da, pred = dijkstra(G, directed=False, indices=a, return_predecessors=True)
    b = int(np.argmax(da))
    path = [b]
    while path[-1] != a:
        path.append(int(pred[path[-1]]))
    return path


def run_igl(V, F, max_it=500, tol=1e-7, window=5):
    import igl
    sys.path.insert(0, os.path.abspath(PEERS))
    import run_peers as R
    t0 = time.perf_counter()
    cuts = igl.cut_to_disk(F)
    edges = set()
    for c in cuts:
        edges |= {tuple(sorted(p)) for p in zip(c[:-1], c[1:])}
    if not edges:  # a closed genus-0 surface: cut_to_disk leaves it whole
        path = far_path(V, F)
        edges = {tuple(sorted(p)) for p in zip(path[:-1], path[1:])}
    C = np.zeros(F.shape, dtype=bool)
    for f in range(len(F)):
        for j in range(3):
            C[f, j] = tuple(sorted((int(F[f, j]), int(F[f, (j + 1) % 3])))) in edges
    Vc, Fc, _ = igl.cut_mesh(V, F, C)
    bnd = igl.boundary_loop(Fc)
    bnd_uv = igl.map_vertices_to_circle(np.asfortranarray(Vc), bnd.astype(np.int32))
    uv0 = igl.harmonic(Vc, Fc, bnd, np.ascontiguousarray(bnd_uv), 1)
    init = "harmonic"
    if len(igl.flipped_triangles(uv0, Fc)) > 0:
        uv0 = R._tutte_uniform(Vc.shape[0], Fc, bnd, np.asarray(bnd_uv))
        init = "uniform Tutte"
    init_flips = len(igl.flipped_triangles(uv0, Fc))
    data = igl.slim_precompute(np.asfortranarray(Vc), np.asfortranarray(Fc.astype(np.int32)),
                               np.asfortranarray(uv0), igl.SYMMETRIC_DIRICHLET,
                               np.zeros(0, dtype=np.int32), np.asfortranarray(np.zeros((0, 2))), 0.0)
    hist = [R._sd_total(Vc, Fc, uv0)]
    it, uv, check = 0, uv0, 0.0
    while it < max_it:
        uv = igl.slim_solve(data, 1)
        it += 1
        t2 = time.perf_counter()
        e = R._sd_total(Vc, Fc, uv)
        check += time.perf_counter() - t2
        hist.append(e)
        if not np.isfinite(e):
            break
        if len(hist) > window and (hist[-1 - window] - e) <= tol * e:
            break
    t = time.perf_counter() - t0 - check
    uv = np.asarray(uv)[:, :2]
    try:
        row = scored(Vc, Fc, uv, uv, Fc, Vc)
    except ValueError as err:  # non-finite UVs
        return {"failed": f"{err} after {it} SLIM iterations", "time": t}
    row.update(time=t, note=f"{init} start ({init_flips} flipped), {it} SLIM iterations")
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--surfmap", default="target/release/surfmap")
    ap.add_argument("--before", help="a surfmap binary built before the cuts along "
                    "protrusions, run as the tool `before`")
    ap.add_argument("--tools", default="surfmap,xatlas,igl")
    args = ap.parse_args()
    tools = (["before"] if args.before else []) + args.tools.split(",")
    cols = ["charts", "seam", "flipped", "crossings", "D", "area_avg", "area_max", "time"]
    print("| mesh | F | tool | " + " | ".join(cols) + " | note |")
    print("|---|---:|---|" + "---:|" * len(cols) + "---|")
    for path in args.meshes:
        V, F, _ = D.load_mesh(path)
        name = os.path.splitext(os.path.basename(path))[0]
        for tool in tools:
            with tempfile.TemporaryDirectory() as work:
                try:
                    if tool in ("surfmap", "before"):
                        binary = args.surfmap if tool == "surfmap" else args.before
                        row = run_surfmap(binary, path, work)
                    elif tool == "xatlas":
                        row = run_xatlas(V, F)
                    else:
                        row = run_igl(V, F)
                except Exception as err:  # a peer's failure is a row, not the end
                    row = {"failed": f"{type(err).__name__}: {err}"[:120]}
            if "failed" in row:
                print(f"| {name} | {len(F)} | {tool} | " + " | ".join("" for _ in cols) + f" | failed: {row['failed']} |")
                continue
            cells = []
            for c in cols:
                v = row[c]
                cells.append(f"{v:.4g}" if isinstance(v, float) else str(v))
            print(f"| {name} | {len(F)} | {tool} | " + " | ".join(cells) + f" | {row.get('note', '')} |", flush=True)


if __name__ == "__main__":
    main()
