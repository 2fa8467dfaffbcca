#!/usr/bin/env python3
"""Accuracy of blend-shape rigs on real data (issue: applications).

For every expression pair of ../shared/match_eval (A = neutral, B = expression, remeshed,
cropped and moved), `surfmap match` finds A → B and `surfmap rig A B --match …` places the
key on the neutral's connectivity; each key vertex is compared with the true expression
position (the pair's ground truth, read here by the benchmark only — never by the
matcher). Errors are Euclidean, in % of the face width (A's extent across the face, x).
Vertices whose counterpart was cropped away from B have no truth and are not scored;
vertices the match leaves unmatched are scored where the rig put them (moved by the
harmonic extension of the matched displacements). "lips p95": the p95 over A's vertices
within 8 % of the face width (1.5 cm on the ICT crops) of A's mouth rim (the hole loop
with the lowest centroid; y is up in the ICT frame, which A keeps).

    /opt/peers-venv/bin/python scripts/bench_rig.py --pairs /tmp/surfmap_pairs \
        --surfmap target/release/surfmap [--out /tmp/surfmap_rig] [--only jawopen]
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "shared", "match_eval"))

import numpy as np  # noqa: E402
from score import Pair  # noqa: E402


def read_obj_vertices(path):
    v = []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                v.append([float(x) for x in line.split()[1:4]])
    return np.array(v)


def mouth_rim(VA, FA):
    """A's mouth rim: of the boundary loops but the longest (the outer rim), the one whose
    centroid is lowest (y)."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components
    e = np.sort(np.r_[FA[:, [0, 1]], FA[:, [1, 2]], FA[:, [2, 0]]], axis=1)
    u, count = np.unique(e, axis=0, return_counts=True)
    b = u[count == 1]
    n = len(VA)
    g = sp.coo_matrix((np.ones(len(b)), (b[:, 0], b[:, 1])), shape=(n, n))
    _, label = connected_components(g, directed=False)
    on = np.unique(b.ravel())
    loops = [on[label[on] == c] for c in np.unique(label[on])]
    holes = sorted(loops, key=len)[:-1]
    return min(holes, key=lambda lp: VA[lp, 1].mean()) if holes else None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pairs", required=True)
    ap.add_argument("--surfmap", default=os.path.join(HERE, "..", "target", "release", "surfmap"))
    ap.add_argument("--out", default="/tmp/surfmap_rig")
    ap.add_argument("--only", default=None, help="comma-separated substrings of pair names")
    ap.add_argument("--landmarks", action="store_true", help="match with the pair's landmarks.json")
    ap.add_argument("--extra", default="", help="extra arguments for surfmap match (one string)")
    args = ap.parse_args()
    index = json.load(open(os.path.join(args.pairs, "index.json")))
    print("| pair | matched | mean error (% width) | p95 (% width) | max (% width) | lips p95 (% width) |")
    print("|---|---:|---:|---:|---:|---:|")
    means = []
    for e in index:
        if e["track"] != "expression":
            continue
        if args.only and not any(o in e["dir"] for o in args.only.split(",")):
            continue
        d = os.path.join(args.pairs, e["dir"])
        out = os.path.join(args.out, e["dir"])
        a, b = os.path.join(d, "A.obj"), os.path.join(d, "B.obj")
        subprocess.run([args.surfmap, "match", a, b, "-o", os.path.join(out, "match"), "-q"]
                       + (["--landmarks", os.path.join(d, "landmarks.json")] if args.landmarks else [])
                       + args.extra.split(), check=True)
        keys = os.path.join(out, "keys")
        subprocess.run([args.surfmap, "rig", a, b, "--match", os.path.join(out, "match"), "-o",
                        os.path.join(out, "rig.glb"), "--keys-dir", keys, "--names", "key", "-q"], check=True)
        objs = sorted(f for f in os.listdir(keys) if f.endswith(".obj"))
        key = read_obj_vertices(os.path.join(keys, objs[0]))
        pair = Pair(d)
        valid = pair.valid
        fb = pair.FB[pair.gt_tri[valid]]
        truth = np.einsum("ij,ijk->ik", pair.gt_bary[valid], pair.VB[fb])
        width = np.ptp(pair.VA[:, 0])
        err = np.linalg.norm(key[valid] - truth, axis=1) / width * 100
        corr = np.load(os.path.join(out, "match", "correspondence.npy"))
        matched = (corr[:, 0] >= 0).mean()
        means.append(err.mean())
        lips = "–"
        rim = mouth_rim(pair.VA, pair.FA)
        if rim is not None:
            from scipy.spatial import cKDTree
            near = cKDTree(pair.VA[rim]).query(pair.VA[valid])[0] < 0.08 * width
            if near.any():
                lips = f"{np.percentile(err[near], 95):.2f}"
        print(f"| {e['dir']} | {100 * matched:.1f}% | {err.mean():.2f} | {np.percentile(err, 95):.2f} | {err.max():.2f} | {lips} |",
              flush=True)
    print(f"\nmean over the expression pairs: {np.mean(means):.2f}% of the face width")


if __name__ == "__main__":
    main()
