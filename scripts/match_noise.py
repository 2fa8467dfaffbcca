#!/usr/bin/env python3
"""How much of a matching result is rounding noise: runs `surfmap match` on each referee pair
with B.obj as made (seed 0) and with B's coordinates multiplied by (1 + 1e-12 N(0,1)) (seeds
1, 2, ...), scores every run with ../shared/match_eval/score.py and prints the fraction within
0.05 (and the false matches: A vertices without a counterpart matched anyway) per run, per pair
and per track.

    /opt/peers-venv/bin/python scripts/match_noise.py --pairs /tmp/surfmap_pairs \\
        --surfmap target/release/surfmap [--seeds 3] [--landmarks] [--only partial] \\
        [--extra "--position-weight 1000"]
"""
import argparse
import os
import subprocess

from match_common import add_common_arguments, selected_pairs

import numpy as np  # noqa: E402
from score import Pair, score  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    add_common_arguments(ap)
    ap.add_argument("--out", default="/tmp/surfmap_noise_runs")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--landmarks", action="store_true")
    ap.add_argument("--extra", default="", help="more `surfmap match` options, space-separated")
    args = ap.parse_args()
    tracks, false = {}, {}
    for e, d in selected_pairs(args):
        runs, fm = [], []
        for seed in range(args.seeds):
            work = os.path.join(args.out, e["dir"], str(seed))
            os.makedirs(work, exist_ok=True)
            rng = np.random.default_rng(seed)
            lines = []
            for line in open(os.path.join(d, "B.obj")).read().splitlines():
                if line.startswith("v ") and seed > 0:
                    x = np.array([float(t) for t in line.split()[1:4]])
                    x = x * (1 + 1e-12 * rng.standard_normal(3))
                    line = "v %.17g %.17g %.17g" % tuple(x)
                lines.append(line)
            open(os.path.join(work, "B.obj"), "w").write("\n".join(lines) + "\n")
            cmd = [args.surfmap, "match", os.path.join(d, "A.obj"), os.path.join(work, "B.obj"),
                   "-o", os.path.join(work, "out"), "--quiet"]
            if args.landmarks:
                cmd += ["--landmarks", os.path.join(d, "landmarks.json")]
            cmd += args.extra.split()
            subprocess.run(cmd, check=True, capture_output=True)
            s = score(Pair(d), np.load(os.path.join(work, "out", "correspondence.npy")))
            runs.append(s["pct_005"])
            fm.append(s["false_match"])
        tracks.setdefault(e["track"], []).append(runs)
        false.setdefault(e["track"], []).append(fm)
        print(f"{e['dir']:48s} " + " ".join(f"{100 * r:.1f}" for r in runs)
              + f"  spread {100 * (max(runs) - min(runs)):.1f}"
              + "  false match " + " ".join(f"{100 * r:.1f}" for r in fm), flush=True)
    for track, rs in tracks.items():
        a, f = 100 * np.array(rs), 100 * np.array(false[track])
        print(f"{track:12s} per run " + " / ".join(f"{m:.1f}" for m in a.mean(0))
              + f"  mean {a.mean():.1f}  largest spread on a pair {(a.max(1) - a.min(1)).max():.1f}"
              + f"  false match mean {f.mean():.2f} (per run " + " / ".join(f"{m:.2f}" for m in f.mean(0)) + ")")


if __name__ == "__main__":
    main()
