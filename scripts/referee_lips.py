#!/usr/bin/env python3
"""Where the referee's ground truth crosses the lips: a diagnostic of ../shared/match_eval.

Evaluation only (it reads `gt.npz` and the registered sources, as the referee does; no
matcher reads them). The referee's ground truth for A's vertex `a` (registered source
vertex `s`) is the closest point of the remeshed B to B0's vertex `s`. Where the lips
touch, that closest point can lie on the *other* lip: B0's vertex is on the upper lip
(by its geodesic distance to the mouth rim's upper and lower arcs on B0's own mesh) but
the closest point of the remeshed B lies on B's lower lip, centimetres away along the
surface. This script finds those vertices, re-projects B0's vertex onto B's faces on
the same lip as on B0 (within 2 cm of B's mouth rim, accepted only when that point is
within `--max-shift` of B0's vertex), and scores every prediction with both ground
truths (the referee's `score()` on a copy of the pair whose ground truth is replaced).

    /opt/peers-venv/bin/python scripts/referee_lips.py --pairs /tmp/surfmap_pairs \
        --pred surfmap=/tmp/bench/surfmap/{track}/{pair}/correspondence.npy \
        --pred nricp_lm=/tmp/refs/{track}/{pair}/nricp_lm.npy

The sides: the mouth rim is the hole loop of B0 with the lowest centroid (ICT frame,
y up), split at its extreme vertices along x into an upper and a lower arc; a point's
side is the arc nearer along the mesh edges (Dijkstra). On B (moved by the pair's rigid
motion, undone here) the mouth loop is the one whose centroid is nearest B0's.
"""
import argparse
import copy
import os
import sys

import numpy as np
import scipy.sparse.csgraph as csgraph

HERE = os.path.dirname(os.path.abspath(__file__))
MATCH_EVAL = os.path.join(HERE, "..", "..", "shared", "match_eval")


def mouth_arcs(V, F, mouth_centroid=None):
    """(upper arc, lower arc) vertex ids of the mouth rim, or None without a mouth.

    Without `mouth_centroid`, the mouth is the hole (not the longest loop) with the lowest
    centroid; with it, the hole whose centroid is nearest (within 1.5 cm)."""
    from common import boundary_loops

    holes = boundary_loops(F)[1:]
    if not holes:
        return None
    cents = [V[l].mean(0) for l in holes]
    if mouth_centroid is None:
        k = int(np.argmin([c[1] for c in cents]))
    else:
        dist = [np.linalg.norm(c - mouth_centroid) for c in cents]
        k = int(np.argmin(dist))
        if dist[k] > 1.5:
            return None
    loop = holes[k]  # ordered along the rim
    i, j = sorted((int(np.argmin(V[loop, 0])), int(np.argmax(V[loop, 0]))))
    arc1 = loop[i : j + 1]
    arc2 = np.concatenate([loop[j:], loop[: i + 1]])
    if V[arc1, 1].mean() < V[arc2, 1].mean():
        arc1, arc2 = arc2, arc1
    return arc1, arc2, V[loop].mean(0)


def arc_distances(V, F, arcs):
    from common import edge_graph

    G = edge_graph(V, F)
    up = csgraph.dijkstra(G, directed=False, indices=arcs[0]).min(0)
    low = csgraph.dijkstra(G, directed=False, indices=arcs[1]).min(0)
    return up, low


def corrected_pair(pair, b0_path, max_shift, near=2.0):
    """A copy of `pair` with the lip-crossing ground truth re-projected, and the count."""
    from common import bary_to_points, load_mesh, project_to_mesh

    g = np.load(os.path.join(pair.dir, "gt.npz"))
    src, T = g["A_src_vertex"], g["B_rigid"]
    B0, F0 = load_mesh(b0_path)
    arcs0 = mouth_arcs(B0, F0)
    # B in B0's frame (the pair's rigid motion undone).
    VB = (pair.VB - T[:3, 3]) @ T[:3, :3]
    arcsB = mouth_arcs(VB, pair.FB, arcs0[2]) if arcs0 else None
    out = copy.copy(pair)
    if arcsB is None:
        return out, 0, 0, np.zeros(0)
    up0, low0 = arc_distances(B0, F0, arcs0)
    upB, lowB = arc_distances(VB, pair.FB, arcsB)
    # Side of each B face (mean over its corners) and of each ground-truth point.
    face_up = (upB[pair.FB] - lowB[pair.FB]).mean(1) < 0
    face_near = np.minimum(upB, lowB)[pair.FB].max(1) < near
    valid = pair.valid
    gt_up = (pair.gt_bary * (upB - lowB)[pair.FB[pair.gt_tri]]).sum(1) < 0
    src_up = up0[src] < low0[src]
    src_near = np.minimum(up0, low0)[src] < near
    crossing = np.where(valid & src_near & (gt_up != src_up))[0]
    tri, bary = pair.gt_tri.copy(), pair.gt_bary.copy()
    moved = 0
    for want_up in (True, False):
        ids = crossing[src_up[crossing] == want_up]
        if len(ids) == 0:
            continue
        faces = np.where(face_near & (face_up == want_up))[0]
        t, b, _, d = project_to_mesh(B0[src[ids]], VB, pair.FB[faces])
        ok = d <= max_shift
        tri[ids[ok]] = faces[t[ok]]
        bary[ids[ok]] = b[ok]
        moved += int(ok.sum())
    out.gt_tri, out.gt_bary = tri, bary
    shift = np.linalg.norm(
        bary_to_points(VB, pair.FB, tri[crossing], bary[crossing]) - B0[src[crossing]], axis=1
    )
    return out, len(crossing), moved, shift


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pairs", required=True)
    ap.add_argument("--ict", default=os.path.join(HERE, "..", "..", "shared", "data", "faces", "ict"))
    ap.add_argument("--pred", action="append", required=True, help="LABEL=PATTERN with {track} and {pair}")
    ap.add_argument("--max-shift", type=float, default=0.15, help="cm from B0's vertex, at most")
    args = ap.parse_args()
    sys.path.insert(0, MATCH_EVAL)
    import json

    from score import Pair, score

    preds = [p.split("=", 1) for p in args.pred]
    index = json.load(open(os.path.join(args.pairs, "index.json")))
    rows = {}
    for info in index:
        pair = Pair(os.path.join(args.pairs, info["dir"]))
        fixed, crossing, moved, shift = corrected_pair(
            pair, os.path.join(args.ict, info["B_src"]), args.max_shift
        )
        line = f"{info['dir']}: {crossing} ground-truth points across the lips, {moved} re-projected"
        if crossing:
            line += f" (B0's vertex to the new point: median {np.median(shift):.3f}, max {shift.max():.3f})"
        print(line, flush=True)
        for label, pattern in preds:
            path = pattern.format(track=info["track"], pair=info["name"])
            if not os.path.exists(path):
                continue
            pred = np.load(path)
            before, after = score(pair, pred), score(fixed, pred)
            r = rows.setdefault((info["track"], label), [])
            r.append((before["pct_005"], before["curve"][2], after["pct_005"], after["curve"][2], crossing, moved))
    print()
    print("| track (pairs) | method | % <0.05 referee | % <0.05 lips re-projected | % <0.02 referee | % <0.02 lips re-projected | points re-projected |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for (track, label), r in sorted(rows.items()):
        a = np.array(r)
        print(
            f"| {track} ({len(r)}) | {label} | {100 * a[:, 0].mean():.2f} | {100 * a[:, 2].mean():.2f} | "
            f"{100 * a[:, 1].mean():.2f} | {100 * a[:, 3].mean():.2f} | {int(a[:, 5].sum())} |"
        )


if __name__ == "__main__":
    main()
