#!/usr/bin/env python3
"""The match's verdict against the referee's score, on good runs and on starts broken on
purpose.

For every referee pair (folders made by ../shared/match_eval/make_pairs.py or
scripts/flame_pairs.py) it runs `surfmap match`:

- `none`: without input; `landmarks`: with the pair's landmarks;
- broken starts, made with wrong landmarks that only place the start (`--align features
  --features-start plane --similarity-search off --beta 1,0.01,0 --free-landmarks`, so
  nothing else of the landmarks reaches the solve): `rot90` and `rot180` (B's landmarks
  turned about their centroid in their plane, each moved to B's nearest vertex),
  `mirrored` (left and right swapped on B), `shifted` (B's landmarks moved by a third of
  their extent), and `unaligned` (`--align none`: the flattenings as placed in ω).

Each output is scored by the referee (score.py: fraction of A within 0.05 of √area(B))
and its verdict read from match.json. It prints every run, then the confusion table of the
verdicts against the score (< 50 %, 50–90 %, ≥ 90 % within 0.05), and writes all rows to
OUT/results.json. The matcher never reads gt.npz; only score.py does.

    /opt/peers-venv/bin/python scripts/verdict_calibration.py --pairs /tmp/pairs7,/tmp/pairs9 \\
        --surfmap target/release/surfmap --out /tmp/verdicts [--modes none,rot90] [--jobs 2]
"""
import argparse
import json
import os
import subprocess
import time
from concurrent.futures import ThreadPoolExecutor

from match_common import HERE  # noqa: F401  (puts ../shared/match_eval on the path)

import numpy as np  # noqa: E402
from common import bary_to_points  # noqa: E402
from score import Pair, parse_prediction, score  # noqa: E402

BROKEN = ("rot90", "rot180", "mirrored", "shifted")
MODES = ("none", "landmarks") + BROKEN + ("unaligned",)
START_ONLY = ["--align", "features", "--features-start", "plane", "--similarity-search", "off",
              "--beta", "1,0.01,0", "--free-landmarks"]


def read_obj_vertices(path):
    return np.array([[float(x) for x in line.split()[1:4]] for line in open(path) if line.startswith("v ")])


def broken_landmarks(pair_dir, mode):
    """The pair's landmarks with B's moved as `mode` says (module docs)."""
    lm = json.load(open(os.path.join(pair_dir, "landmarks.json")))
    vb = read_obj_vertices(os.path.join(pair_dir, "B.obj"))
    names, ids_b = lm["names"], list(lm["B"])
    if mode == "mirrored":
        index = {n: i for i, n in enumerate(names)}
        swapped = []
        for n, b in zip(names, ids_b):
            other = n[:-2] + ("_r" if n.endswith("_l") else "_l") if n[-2:] in ("_l", "_r") else n
            swapped.append(ids_b[index[other]] if other in index else b)
        return {**lm, "B": swapped}
    p = vb[ids_b]
    c = p.mean(0)
    u, s, vt = np.linalg.svd(p - c)
    e1, e2 = vt[0], vt[1]
    if mode == "shifted":
        moved = p + (s[0] / np.sqrt(len(p))) * e1
    else:
        angle = np.radians(90.0 if mode == "rot90" else 180.0)
        x, y = (p - c) @ e1, (p - c) @ e2
        rest = (p - c) - np.outer(x, e1) - np.outer(y, e2)
        xr, yr = np.cos(angle) * x - np.sin(angle) * y, np.sin(angle) * x + np.cos(angle) * y
        moved = c + np.outer(xr, e1) + np.outer(yr, e2) + rest
    nearest = [int(np.argmin(((vb - q) ** 2).sum(1))) for q in moved]
    return {**lm, "B": nearest}


def run_one(args, entry, pair_dir, mode):
    """One `surfmap match` run (module docs), scored."""
    out = os.path.join(args.out, mode, entry["dir"])
    os.makedirs(out, exist_ok=True)
    cmd = [args.surfmap, "match", os.path.join(pair_dir, "A.obj"), os.path.join(pair_dir, "B.obj"), "-o", out, "-q"]
    if mode == "landmarks":
        cmd += ["--landmarks", os.path.join(pair_dir, "landmarks.json")]
    elif mode in BROKEN:
        path = os.path.join(out, "broken_landmarks.json")
        json.dump(broken_landmarks(pair_dir, mode), open(path, "w"))
        cmd += ["--landmarks", path] + START_ONLY
    elif mode == "unaligned":
        cmd += ["--align", "none"]
    cmd += args.extra.split()
    t = time.time()
    r = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.time() - t
    row = dict(pairs=os.path.basename(args_pairs_root(pair_dir)), pair=entry["dir"], track=entry["track"], mode=mode,
               seconds=seconds, exit=r.returncode)
    if r.returncode not in (0, 3):
        row["error"] = r.stderr.strip()[-300:]
        return row
    report = json.load(open(os.path.join(out, "match.json")))
    pred = np.load(os.path.join(out, "correspondence.npy"))
    s = euclidean_score(Pair(pair_dir), pred) if args.euclidean else score(Pair(pair_dir), pred)
    conf = report.get("confidence", {})
    row.update(p05=s["pct_005"], flip=s["flip"], collapse=s["collapse"], false_match=s["false_match"],
               verdict=conf.get("verdict"), reasons=conf.get("reasons", []), measures=conf.get("measures", {}),
               energy=report["energy"], warnings=report["warnings"], recovery=conf.get("recovery"),
               seconds_reported=report.get("seconds"))
    return row


def euclidean_score(pair, pred):
    """The referee's fraction within 0.05 with straight-line instead of geodesic
    distances (`--euclidean`: seconds instead of the heat method's minutes per new pair;
    below 0.05 of √area the two agree closely on these faces). Fold fractions are not
    computed (NaN)."""
    tri, bary, _ = parse_prediction(pair, pred)
    valid, matched = pair.valid, tri >= 0
    err = np.full(len(tri), np.inf)
    mv = matched & valid
    p = bary_to_points(pair.VB, pair.FB, tri[mv], bary[mv])
    g = bary_to_points(pair.VB, pair.FB, pair.gt_tri[mv], pair.gt_bary[mv])
    err[mv] = np.linalg.norm(p - g, axis=1) / pair.S
    return dict(pct_005=float((err[valid] <= 0.05).mean()), flip=float("nan"), collapse=float("nan"),
                false_match=float(matched[~valid].mean()) if (~valid).any() else 0.0)


def args_pairs_root(pair_dir):
    return os.path.dirname(os.path.dirname(pair_dir.rstrip("/")))


def band(p05):
    return "<50" if p05 < 0.5 else ("50-90" if p05 < 0.9 else ">=90")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pairs", required=True, help="comma-separated pair folders (index.json)")
    ap.add_argument("--surfmap", default=os.path.join(HERE, "..", "target", "release", "surfmap"))
    ap.add_argument("--out", default="/tmp/verdicts")
    ap.add_argument("--modes", default=",".join(MODES))
    ap.add_argument("--only", default=None, help="comma-separated substrings of pair names")
    ap.add_argument("--extra", default="", help="extra arguments for surfmap match")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--euclidean", action="store_true", help="straight-line distances (fast; see euclidean_score)")
    args = ap.parse_args()
    jobs = []
    for root in args.pairs.split(","):
        for e in json.load(open(os.path.join(root, "index.json"))):
            if args.only and not any(o in e["dir"] for o in args.only.split(",")):
                continue
            for mode in args.modes.split(","):
                jobs.append((e, os.path.join(root, e["dir"]), mode))
    rows = []
    with ThreadPoolExecutor(args.jobs) as pool:
        for row in pool.map(lambda j: run_one(args, *j), jobs):
            rows.append(row)
            m = row.get("measures", {})
            if "error" in row:
                print(f"{row['pairs']:8s} {row['pair']:46s} {row['mode']:9s} ERROR {row['error']}", flush=True)
                continue
            f = lambda k, d=3: "-" if m.get(k) is None else f"{m[k]:.{d}f}"
            print(f"{row['pairs']:8s} {row['pair']:46s} {row['mode']:9s} <.05 {100 * row['p05']:5.1f} "
                  f"{row['verdict'] or '-':9s} D {f('curvature_disagreement')} Dc {f('coarse_disagreement')} "
                  f"Du {f('unrelated_disagreement')} res {f('residual', 4)} off {f('pose_offset', 4)} "
                  f"ratio {f('residual_ratio', 2)} area {f('area_ratio', 2)} A {f('matched_fraction_a')} "
                  f"{row['seconds']:.1f}s", flush=True)
    os.makedirs(args.out, exist_ok=True)
    json.dump(rows, open(os.path.join(args.out, "results.json"), "w"), indent=1)
    scored = [r for r in rows if "p05" in r]
    print("\n| verdict \\ referee (within 0.05) | < 50 % | 50–90 % | ≥ 90 % |\n|---|---:|---:|---:|")
    for v in ("ok", "doubtful", "failed"):
        counts = [sum(1 for r in scored if r["verdict"] == v and band(r["p05"]) == b) for b in ("<50", "50-90", ">=90")]
        print(f"| {v} | {' | '.join(map(str, counts))} |")
    print(f"\n{len(scored)} runs scored, {len(rows) - len(scored)} failed to run")


if __name__ == "__main__":
    main()
