#!/usr/bin/env python3
"""Any mesh in, a valid map out: `surfmap flatten` against xatlas and libigl on closed,
holed and higher-genus meshes, all scored in the same run by the peers' referee
(`../shared/peers/distortion.py`).

* ours:      `surfmap flatten MESH -o OUT.obj --report R.json` (default options: holes
             filled, closed and higher-genus surfaces cut; `--cut-holes` per mesh below).
* ours_sd:   the same with `--energy sd` (symmetric Dirichlet, the energy SLIM minimizes).
* ours@D:    `ours` with `--max-distortion D` (distortion-driven cuts until the mean
             symmetric Dirichlet distortion is at most D); `ours_sd@D` likewise.
* xatlas:    the harness's `xatlas` worker (default chart and pack options) on the mesh
             scaled to area 1e4 (xatlas's float32 epsilons; the metrics are scale-free).
* igl_cut_slim: `igl.cut_to_disk` (plus, for a closed genus-0 surface, which it leaves
             uncut, the shortest edge path between vertex 0 and the vertex farthest from
             it), `igl.cut_mesh`, then the harness's `igl_slim` worker (symmetric
             Dirichlet, harmonic or uniform Tutte start, relative stop 1e-7 over 5
             iterations, at most 500).

Besides the referee's distortion columns it measures, independently of both tools: the
seam length (3D length of the mesh edges whose two faces disagree on a UV) and the
boundary crossings (pairs of UV boundary segments that properly cross; 0 with a flip-free
map means no overlap).

Every method runs in its own process with a timeout (a libigl crash costs one row).
Run it with the peers' interpreter (libigl, xatlas, scipy):

    /opt/peers-venv/bin/python scripts/bench_anymesh.py \
        --surfmap target/release/surfmap ../shared/data/{sphere.obj,bunny.off,...}
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
PEERS = os.environ.get("PEERS_DIR", os.path.join(HERE, "..", "..", "shared", "peers"))
sys.path.insert(0, PEERS)
import distortion as D  # noqa: E402

# Meshes whose holes we open with seams (`--cut-holes`) rather than fill: the same cut
# problem the peers solve (they never fill holes).
CUT_HOLES = {"holes.off", "halftunnel.off", "beetle.off"}


# --------------------------------------------------------------------------- checks
def half_edges(F, C):
    """Per half-edge (face f, corner k): vertices a, b and their UVs."""
    a = F.reshape(-1)
    b = F[:, [1, 2, 0]].reshape(-1)
    ua = C.reshape(-1, 2)
    ub = C[:, [1, 2, 0]].reshape(-1, 2)
    return a, b, ua, ub


def seams(V, F, C):
    """Mesh edges shared by two faces that disagree on a UV of either end: (count, 3D length)."""
    a, b, ua, ub = half_edges(F, C)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    swap = a > b
    ulo = np.where(swap[:, None], ub, ua)
    uhi = np.where(swap[:, None], ua, ub)
    order = np.lexsort((hi, lo))
    lo, hi, ulo, uhi = lo[order], hi[order], ulo[order], uhi[order]
    same = (lo[1:] == lo[:-1]) & (hi[1:] == hi[:-1])
    i = np.nonzero(same)[0]
    scale = max(np.ptp(C.reshape(-1, 2), axis=0).max(), 1e-300)
    differ = (np.abs(ulo[i] - ulo[i + 1]).max(axis=1) > 1e-9 * scale) | (
        np.abs(uhi[i] - uhi[i + 1]).max(axis=1) > 1e-9 * scale)
    e = i[differ]
    length = np.linalg.norm(V[lo[e]] - V[hi[e]], axis=1).sum()
    return int(len(e)), float(length)


def boundary_segments(F, C):
    """UV segments of half-edges without a twin (same two vertices, same two UVs, reversed)."""
    a, b, ua, ub = half_edges(F, C)
    key = {}
    for j in range(len(a)):
        key[(int(a[j]), int(b[j]), *ua[j].tolist(), *ub[j].tolist())] = j
    out = []
    for j in range(len(a)):
        if (int(b[j]), int(a[j]), *ub[j].tolist(), *ua[j].tolist()) not in key:
            out.append((ua[j], ub[j]))
    return np.array(out, dtype=np.float64).reshape(-1, 2, 2)


def crossings(S, block=2048):
    """Pairs of segments that properly cross (strictly opposite orientations both ways)."""
    n = len(S)
    if n < 2:
        return 0
    p, q = S[:, 0], S[:, 1]

    def orient(a, b, c):
        return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])

    count = 0
    for s in range(0, n, block):
        A, B = p[s:s + block, None, :], q[s:s + block, None, :]
        Cc, Dd = p[None, :, :], q[None, :, :]
        d1, d2 = orient(Cc, Dd, A), orient(Cc, Dd, B)
        d3, d4 = orient(A, B, Cc), orient(A, B, Dd)
        hit = (d1 * d2 < 0) & (d3 * d4 < 0)
        rows = np.arange(s, min(s + block, n))[:, None]
        hit &= rows < np.arange(n)[None, :]
        count += int(hit.sum())
    return count


# --------------------------------------------------------------------------- workers
def shortest_path_cut(V, F):
    """Edge path from vertex 0 to the vertex farthest from it (Dijkstra on edge lengths)."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import dijkstra
    E = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)
    w = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    G = sp.coo_matrix((np.r_[w, w], (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])), shape=(len(V),) * 2)
    dist, pred = dijkstra(G.tocsr(), indices=0, return_predecessors=True)
    v = int(np.argmax(np.where(np.isfinite(dist), dist, -1)))
    path = [v]
    while pred[path[-1]] >= 0:
        path.append(int(pred[path[-1]]))
    return path[::-1]


def worker(method, mesh_path, out_path):
    import run_peers as RP
    V, F, _ = D.load_mesh(mesh_path)
    info = {}
    if method == "xatlas":
        area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1).sum()
        Vs = V * (1e4 / area) ** 0.5
        uv, _, Fm, info = RP._worker_py("xatlas", Vs, F, {})
        C = uv[Fm]
    else:  # igl_cut_slim
        import igl
        t0 = time.perf_counter()
        cuts = igl.cut_to_disk(F)
        euler = len(V) - len(np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)) + len(F)
        if not cuts and euler == 2:
            cuts = [shortest_path_cut(V, F)]
        edge_of = {}
        for f in range(len(F)):
            for k in range(3):
                a, b = int(F[f, k]), int(F[f, (k + 1) % 3])
                edge_of.setdefault((min(a, b), max(a, b)), []).append((f, k))
        mask = np.zeros(F.shape, dtype=bool)
        for cut in cuts:
            for a, b in zip(cut[:-1], cut[1:]):
                for f, k in edge_of.get((min(a, b), max(a, b)), []):
                    mask[f, k] = True
        Vn, Fn, _ = igl.cut_mesh(V, F, mask)
        t_cut = time.perf_counter() - t0
        uv, _, _, info = RP._worker_py("igl_slim", np.asarray(Vn), np.asarray(Fn), {})
        info["cut_s"] = t_cut
        info["method_s"] = info["method_s"] + t_cut
        C = np.asarray(uv)[np.asarray(Fn)]
    np.save(out_path, C)
    with open(out_path + ".json", "w") as fh:
        json.dump({k: v for k, v in info.items() if isinstance(v, (int, float, str))}, fh)


# --------------------------------------------------------------------------- driver
def run(cmd, timeout):
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, f"timeout {timeout}s", time.perf_counter() - t0
    if p.returncode != 0:
        return None, (p.stderr.strip().splitlines() or [f"exit {p.returncode}"])[-1][:120], time.perf_counter() - t0
    return p, None, time.perf_counter() - t0


def score(V, F, C, row):
    m = D.distortion(V, F, C)
    row.update(charts=m["charts"], flip=m["flipped"], sd_mean=m["sym_dirichlet_mean"],
               sd_max=m["sym_dirichlet_max"], conf_mean=m["conformal_mean"], area_log=m["log_area_mean_abs"])
    row["seam_edges"], row["seam_length"] = seams(V, F, C)
    row["crossings"] = crossings(boundary_segments(F, C))
    return row


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="*")
    ap.add_argument("--surfmap", default=os.path.join(HERE, "..", "target", "release", "surfmap"))
    ap.add_argument("--methods", default="ours,ours_sd,xatlas,igl_cut_slim")
    ap.add_argument("--timeout", type=float, default=300)
    ap.add_argument("--json", help="write all rows here")
    ap.add_argument("--worker", nargs=3, metavar=("METHOD", "MESH", "OUT"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        worker(*a.worker)
        return 0
    rows = []
    work = tempfile.mkdtemp(prefix="bench_anymesh_")
    cols = ["mesh", "faces", "method", "time_s", "charts", "flip", "crossings", "seam_length",
            "sd_mean", "sd_max", "conf_mean", "area_log", "note"]
    print("  ".join(f"{c:>12}" for c in cols))
    for path in a.meshes:
        V, F, _ = D.load_mesh(path)
        name = os.path.basename(path)
        for method in a.methods.split(","):
            row = {"mesh": name, "faces": len(F), "method": method, "note": ""}
            if method.split("@")[0] in ("ours", "ours_sd"):
                out, rep = os.path.join(work, "ours.obj"), os.path.join(work, "ours.json")
                for stale in (out, rep):
                    if os.path.exists(stale):
                        os.remove(stale)
                cmd = [a.surfmap, "flatten", path, "-o", out, "--report", rep, "-q"]
                if name in CUT_HOLES:
                    cmd.append("--cut-holes")
                if method.startswith("ours_sd"):
                    cmd += ["--energy", "sd"]
                if "@" in method:
                    # ours@D: distortion-driven cutting to the bound D (the command
                    # fails when D is not met, after writing the best map and report).
                    cmd += ["--max-distortion", method.split("@")[1]]
                p, err, wall = run(cmd, a.timeout)
                if err is not None and "@" in method and os.path.exists(rep):
                    err = None
                if err is None:
                    r = json.load(open(rep))
                    row["time_s"] = r["time_total_s"]
                    row["note"] = f'{r["plan"]}; {r["iterations"]} it; {r["guarantee"]}'
                    c = r.get("distortion_cuts")
                    if c:
                        row["note"] = (f'D {c["before"]:.4f} -> {c["after"]:.4f} '
                                       f'({"met" if c["met"] else "NOT met"}), {c["rounds"]} rounds, '
                                       f'+{c["seam_length_added"]:.4g} seam, {c["total_iterations"]} it; '
                                       f'{r["guarantee"]}')
                    _, _, C = D.load_mesh(out)
                    score(V, F, C, row)
            else:
                out = os.path.join(work, method + ".npy")
                p, err, wall = run([sys.executable, __file__, "--worker", method, path, out], a.timeout)
                if err is None:
                    info = json.load(open(out + ".json"))
                    row["time_s"] = info.get("method_s")
                    if "iterations" in info:
                        row["note"] = f'{info["iterations"]} it, {info.get("init", "")}'
                    score(V, F, np.load(out), row)
            if err is not None:
                row["note"] = "failed: " + err
            rows.append(row)
            fmt = {"time_s": "{:.3f}", "sd_mean": "{:.4f}", "sd_max": "{:.4g}", "conf_mean": "{:.4f}",
                   "area_log": "{:.4f}", "seam_length": "{:.4g}"}
            print("  ".join(f"{fmt.get(c, '{}').format(row[c]) if c in row and row[c] is not None else '-':>12}"
                            for c in cols), flush=True)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
