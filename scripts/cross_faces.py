#!/usr/bin/env python3
"""Faces from two sources matched across: ICT crops (cm, ~9k vertices) against FLAME crops
(metres, ~1.9k vertices), both ways, with no input. There is no dense ground truth across the
two datasets, so the measure is the seven landmarks that both pair builders place by the same
geometric rules (nose tip = most forward vertex, eye corners = the extreme vertices of the eye
openings, mouth corners = the extreme vertices of the mouth opening): the distance from where A's
landmark lands on B to B's landmark, over sqrt(area(B)) and in mm. Also flip / collapse of A's
image on B (as ../shared/match_eval/score.py counts them) and A's matched fraction.

The nose tip and the mouth corners are defined alike in both sets. The eye corners are not quite:
the ICT crops have eye holes (a corner is an end of the hole), the FLAME crops have their eyes
closed over (a corner is an end of the eyelid margin found from the eyeball sphere, about 4 cm
apart against the ICT holes' 2.4 cm), so the two are reported apart.

References (the same as ../shared/match_eval/references.py runs): rigid ICP and non-rigid ICP
(trimesh nricp_amberg) without landmarks. They work in one unit and do not scale, so A is given to
them converted to B's unit (scaled by the power of ten nearest to sqrt(area(B)/area(A)), the
factor `surfmap match` finds by itself; the meshes are given to `surfmap match` as they are).

Usage (pairs from make_pairs.py and scripts/flame_pairs.py):
  /opt/peers-venv/bin/python scripts/cross_faces.py --ict /tmp/surfmap_pairs --flame /tmp/flame_pairs \
      --surfmap target/release/surfmap --out /tmp/cross_faces [--methods surfmap,icp,nricp]
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "shared", "match_eval"))
from common import load_mesh, face_areas, bary_to_points  # noqa: E402

NAMES = ["nose_tip", "eye_inner_l", "eye_outer_l", "eye_inner_r", "eye_outer_r",
         "mouth_corner_l", "mouth_corner_r"]
NOSE_MOUTH = ["nose_tip", "mouth_corner_l", "mouth_corner_r"]
EYES = ["eye_inner_l", "eye_outer_l", "eye_inner_r", "eye_outer_r"]


def faces_of(ict, flame):
    """(name, obj path, {landmark: vertex id}, mm per unit) of every distinct face crop."""
    out = []
    seen = set()
    for root, pairs, mm in ((ict, "identity", 10.0), (flame, "identity", 1000.0)):
        for d in sorted(os.listdir(os.path.join(root, pairs))):
            full = os.path.join(root, pairs, d)
            lm = json.load(open(os.path.join(full, "landmarks.json")))
            a_name, b_name = d.split("_", 1)[1].split("__")
            for side, name in (("A", a_name), ("B", b_name)):
                if name in seen:
                    continue
                # ICT pairs' B sides are remeshed and moved copies: keep A sides only there.
                if root == ict and side == "B":
                    continue
                seen.add(name)
                ids = dict(zip(lm["names"], lm[side]))
                out.append((name, os.path.join(full, f"{side}.obj"), ids, mm))
    return out


class Pair:
    def __init__(self, a, b):
        self.name = f"{a[0]}__{b[0]}"
        self.VA, self.FA = load_mesh(a[1])
        self.VB, self.FB = load_mesh(b[1])
        self.lmA, self.lmB, self.mmB = a[2], b[2], b[3]
        self.areaA = face_areas(self.VA, self.FA).sum()
        self.areaB = face_areas(self.VB, self.FB).sum()
        self.S = np.sqrt(self.areaB)
        self.lm = {"names": NAMES, "A": [a[2][n] for n in NAMES], "B": [b[2][n] for n in NAMES]}


def evaluate(pair, tri, bary):
    import igl
    matched = tri >= 0
    P = np.zeros((len(tri), 3))
    P[matched] = bary_to_points(pair.VB, pair.FB, tri[matched], bary[matched])
    errs = {}
    for n in NAMES:
        a, b = pair.lmA[n], pair.lmB[n]
        errs[n] = float(np.linalg.norm(P[a] - pair.VB[b]) / pair.S) if matched[a] else float("nan")
    fm = matched[pair.FA].all(1)
    Fm = pair.FA[fm]
    nm = np.cross(P[Fm[:, 1]] - P[Fm[:, 0]], P[Fm[:, 2]] - P[Fm[:, 0]])
    nB = igl.per_face_normals(pair.VB, pair.FB, np.array([0.0, 0.0, 1.0]))
    nref = nB[tri[Fm[:, 0]]] + nB[tri[Fm[:, 1]]] + nB[tri[Fm[:, 2]]]
    areaA = face_areas(pair.VA, Fm) * (pair.areaB / pair.areaA)
    amap = 0.5 * np.linalg.norm(nm, axis=1)
    collapsed = amap < 0.01 * areaA
    flipped = (~collapsed) & ((nm * nref).sum(1) < 0)
    vals = [v for v in errs.values() if np.isfinite(v)]
    group = lambda names: [errs[n] for n in names if np.isfinite(errs[n])]
    mean = lambda x: float(np.mean(x)) if x else float("nan")
    return dict(lm_each=errs, lm_mean=mean(vals),
                lm_unmatched=int(sum(not np.isfinite(v) for v in errs.values())),
                lm_mean_mm=mean(vals) * pair.S * pair.mmB,
                nose_mouth=mean(group(NOSE_MOUTH)), eyes=mean(group(EYES)),
                nose_mouth_mm=mean(group(NOSE_MOUTH)) * pair.S * pair.mmB,
                eyes_mm=mean(group(EYES)) * pair.S * pair.mmB,
                flip=float(flipped.mean()) if len(Fm) else float("nan"),
                collapse=float(collapsed.mean()) if len(Fm) else float("nan"),
                matched=float(matched.mean()))


def run_surfmap(pair, a, b, exe, out):
    d = os.path.join(out, pair.name, "surfmap")
    t = time.time()
    r = subprocess.run([exe, "match", a[1], b[1], "-o", d], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(r.stderr)
    pred = np.load(os.path.join(d, "correspondence.npy"))
    tri = np.where(pred[:, 0] >= 0, pred[:, 0], -1).astype(np.int64)
    return tri, pred[:, 1:], time.time() - t, r.stdout.strip().splitlines()[-1]


def run_reference(pair, method):
    import references
    scaled = Pair.__new__(Pair)
    scaled.__dict__.update(pair.__dict__)
    s = 10.0 ** np.round(np.log10(np.sqrt(pair.areaB / pair.areaA)))
    scaled.VA = pair.VA * s
    scaled.areaA = pair.areaA * s * s
    t = time.time()
    if method == "icp":
        tri, bary = references.run_icp(scaled)
    else:
        tri, bary = references.run_nricp(scaled, False)
    return np.asarray(tri, np.int64), np.asarray(bary), time.time() - t, ""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ict", required=True)
    ap.add_argument("--flame", required=True)
    ap.add_argument("--surfmap", default="target/release/surfmap")
    ap.add_argument("--out", default="/tmp/cross_faces")
    ap.add_argument("--methods", default="surfmap,icp,nricp")
    args = ap.parse_args()
    methods = args.methods.split(",")
    faces = faces_of(args.ict, args.flame)
    ict = [f for f in faces if f[0].startswith("ict")]
    flame = [f for f in faces if f[0].startswith("flame")]
    rows = {m: [] for m in methods}
    for a, b in [(x, y) for x in ict for y in flame] + [(y, x) for x in ict for y in flame]:
        pair = Pair(a, b)
        for m in methods:
            try:
                if m == "surfmap":
                    tri, bary, secs, line = run_surfmap(pair, a, b, args.surfmap, args.out)
                else:
                    tri, bary, secs, line = run_reference(pair, m)
                r = evaluate(pair, tri, bary)
            except Exception as e:  # a reference that fails on a pair is reported, not fatal
                print(f"{pair.name} {m}: FAILED {str(e).strip()[:200]}", flush=True)
                continue
            r["seconds"] = secs
            r["direction"] = "ICT→FLAME" if a[0].startswith("ict") else "FLAME→ICT"
            rows[m].append((pair.name, r))
            print(f"{pair.name:40s} {m:8s} nose+mouth {r['nose_mouth']:.4f} ({r['nose_mouth_mm']:.1f} mm) "
                  f"eyes {r['eyes']:.4f} ({r['eyes_mm']:.1f} mm), "
                  f"{r['lm_unmatched']} unmatched, flip {100 * r['flip']:.2f}% "
                  f"collapse {100 * r['collapse']:.2f}% matched {100 * r['matched']:.1f}% "
                  f"{secs:.1f}s", flush=True)
    os.makedirs(args.out, exist_ok=True)
    json.dump(rows, open(os.path.join(args.out, "results.json"), "w"), indent=1)
    print("\n| direction | method | pairs | nose tip + mouth corners / √area(B): mean | median | worst pair | mm | "
          "eye corners / √area(B): mean | mm | landmarks unmatched | flip % (worst pair) | "
          "collapse % (worst pair) | matched A % | s / pair |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for direction in ("ICT→FLAME", "FLAME→ICT"):
        for m in methods:
            rs = [r for _, r in rows[m] if r["direction"] == direction]
            if not rs:
                continue
            mean = lambda k: np.nanmean([r[k] for r in rs])
            print(f"| {direction} | {m} | {len(rs)} | {mean('nose_mouth'):.4f} | "
                  f"{np.nanmedian([r['nose_mouth'] for r in rs]):.4f} | "
                  f"{np.nanmax([r['nose_mouth'] for r in rs]):.4f} | {mean('nose_mouth_mm'):.1f} | "
                  f"{mean('eyes'):.4f} | {mean('eyes_mm'):.1f} | "
                  f"{sum(r['lm_unmatched'] for r in rs)} | {100 * max(r['flip'] for r in rs):.2f} | "
                  f"{100 * max(r['collapse'] for r in rs):.2f} | {100 * mean('matched'):.1f} | "
                  f"{np.median([r['seconds'] for r in rs]):.1f} |")


if __name__ == "__main__":
    main()
