#!/usr/bin/env python3
"""Where a matcher's misses lie on A: by rings from A's boundary and along the crop.

For every pair of a referee set (`../shared/match_eval` layout: `TRACK/PAIR/{A,B}.obj,
gt.npz`) with a prediction `PREDS/TRACK/PAIR/correspondence.npy` (what
`scripts/bench_match.py --out O` writes under `O/METHOD/`), it prints

  * `p05`: % of A's vertices with a counterpart that lie within 0.05 of it (the referee's
    measure; unmatched counts as a miss);
  * `rings`: the % missed among the vertices 0-1, 2-4, 5-9 and 10+ edge rings from A's
    boundary;
  * `along`: where A has vertices without a counterpart (a partial crop), the mean
    displacement of the prediction from the truth along the axis from that part to the
    rest of A (units of the referee's size `S`), per fifth of A's matched vertices, from
    the side that B lacks to the far side (A's own crop border): negative = pulled back
    towards B's side;
  * `scale`: the similarity scale of A onto the truth and onto the prediction.

It reads the ground truth, so it is a referee's tool: never feed it to a matcher.

Usage:
  /opt/peers-venv/bin/python scripts/match_misses.py --pairs /tmp/flame_s17 \\
      --preds /tmp/ev/s17/surfmap [--only partial]
"""

import argparse
import collections
import os
import sys

import numpy as np

REFEREE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "match_eval")


def rings_from_boundary(faces, n):
    """Edge rings from the boundary of a triangle mesh (0 on the boundary)."""
    edges = np.sort(np.r_[faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]], axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    ring = np.full(n, np.iinfo(np.int64).max)
    boundary = np.unique(unique[count == 1].ravel())
    ring[boundary] = 0
    neighbours = [[] for _ in range(n)]
    for a, b in unique:
        neighbours[a].append(b)
        neighbours[b].append(a)
    queue = collections.deque(boundary)
    while queue:
        v = queue.popleft()
        for w in neighbours[v]:
            if ring[w] > ring[v] + 1:
                ring[w] = ring[v] + 1
                queue.append(w)
    return ring


def similarity_scale(x, y):
    """Scale of the least-squares similarity carrying points `x` onto `y` (Umeyama)."""
    xc, yc = x - x.mean(0), y - y.mean(0)
    u, s, vt = np.linalg.svd(yc.T @ xc)
    d = np.ones(3)
    d[2] = np.sign(np.linalg.det(u @ vt))
    return float((s * d).sum() / (xc**2).sum())


def analyse(pair_dir, prediction, score):
    pair = score.Pair(pair_dir)
    tri, bary, _ = score.parse_prediction(pair, np.load(prediction))
    n = len(pair.VA)
    valid, matched = pair.valid, tri >= 0
    both = valid & matched
    points = score.bary_to_points
    predicted = np.full((n, 3), np.nan)
    predicted[matched] = points(pair.VB, pair.FB, tri[matched], bary[matched])
    truth = np.full((n, 3), np.nan)
    truth[valid] = points(pair.VB, pair.FB, pair.gt_tri[valid], pair.gt_bary[valid])
    error = np.full(n, np.inf)
    error[both] = np.linalg.norm(predicted[both] - truth[both], axis=1) / pair.S
    miss = valid & ~(error <= 0.05)
    ring = rings_from_boundary(pair.FA, n)
    bands = []
    for lo, hi in [(0, 2), (2, 5), (5, 10), (10, None)]:
        band = valid & (ring >= lo) & ((ring < hi) if hi else True)
        bands.append(f"{100 * miss[band].sum() / max(band.sum(), 1):3.0f}")
    along = "-"
    if (~valid).sum() >= 10 and both.sum() >= 50:
        axis = pair.VA[valid].mean(0) - pair.VA[~valid].mean(0)
        axis /= np.linalg.norm(axis)
        t = (pair.VA[both] - pair.VA[both].mean(0)) @ axis
        shift = ((predicted[both] - truth[both]) @ axis) / pair.S
        edges = np.quantile(t, np.linspace(0, 1, 6))
        along = " ".join(
            f"{shift[(t >= lo) & (t <= hi)].mean():+.3f}" for lo, hi in zip(edges[:-1], edges[1:])
        )
    scale = (
        f"{similarity_scale(pair.VA[both], truth[both]):.3f} / "
        f"{similarity_scale(pair.VA[both], predicted[both]):.3f}"
    )
    p05 = 100 * (valid & (error <= 0.05)).sum() / valid.sum()
    return p05, bands, along, scale


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pairs", required=True, help="referee pair set (TRACK/PAIR/...)")
    parser.add_argument("--preds", required=True, help="predictions (TRACK/PAIR/correspondence.npy)")
    parser.add_argument("--only", help="one track")
    parser.add_argument("--referee", default=REFEREE, help="../shared/match_eval")
    args = parser.parse_args()
    sys.path.insert(0, args.referee)
    import score  # the referee's module: Pair, parse_prediction
    from common import bary_to_points

    score.bary_to_points = bary_to_points
    print(f"{'pair':<48} {'p05':>5}  missed % by rings 0-1/2-4/5-9/10+  along the crop (S)"
          "                      scale truth / ours")
    for track in sorted(os.listdir(args.pairs)):
        if args.only and track != args.only:
            continue
        track_dir = os.path.join(args.pairs, track)
        if not os.path.isdir(track_dir):
            continue
        for name in sorted(os.listdir(track_dir)):
            prediction = os.path.join(args.preds, track, name, "correspondence.npy")
            if not os.path.exists(prediction):
                continue
            p05, bands, along, scale = analyse(os.path.join(track_dir, name), prediction, score)
            print(f"{track + '/' + name:<48} {p05:5.1f}  {'/'.join(bands):<34} {along:<42} {scale}")


if __name__ == "__main__":
    main()
