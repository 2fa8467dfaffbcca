#!/usr/bin/env python3
"""surfmap against MeshMonk, timed side by side on the same referee pairs in one run.

For every selected pair (../shared/match_eval/make_pairs.py layout) and round, times

- `surfmap match A B -o DIR -q` as a whole process (reading the OBJ files, flattening,
  images, solve, post-processing, writing every output): wall clock;
- MeshMonk as the referee's `references.py` runs it (`run_meshmonk`: rigid_register then
  pyramid_register with its defaults, then every moved vertex of A projected onto B to get a
  correspondence), in this process, with the meshes already loaded and MeshMonk imported:
  wall clock of that call alone. This favours MeshMonk (no file reading, no Python start).

The order alternates by round so that a slow spell of the machine hits both. Prints per
pair the medians and the ratio surfmap / MeshMonk, then the median over the pairs, and the
fraction of A within 0.05 of each (the referee's score.py, or straight-line distances with
--euclidean) so that speed is read beside accuracy.

    python scripts/meshmonk_speed.py --pairs /tmp/pairs10 --rounds 3 [--only identity] \
        [--landmarks] [--euclidean]

Needs `pip install meshmonk` (0.3.0) and the referee's requirements.
"""
import argparse
import os
import statistics
import subprocess
import tempfile
import time

import numpy as np

from match_common import add_common_arguments, selected_pairs

from references import run_meshmonk, tribary_array  # noqa: E402  (../shared/match_eval)
from score import Pair, score  # noqa: E402


def surfmap_run(binary, d, out, landmarks):
    cmd = [binary, "match", os.path.join(d, "A.obj"), os.path.join(d, "B.obj"), "-o", out, "-q"]
    if landmarks:
        cmd += ["--landmarks", os.path.join(d, "landmarks.json")]
    t = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if r.returncode not in (0, 3):  # 3: a verdict other than ok with --strict (not used here)
        raise SystemExit(f"surfmap failed on {d}: {r.stderr.strip()[-300:]}")
    return wall, np.load(os.path.join(out, "correspondence.npy"))


def meshmonk_run(pair, landmarks):
    t = time.perf_counter()
    tri, bary = run_meshmonk(pair, landmarks)
    return time.perf_counter() - t, tribary_array(tri, bary)


def euclidean_p05(pair, pred):
    from verdict_calibration import euclidean_score

    return euclidean_score(pair, pred)["pct_005"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_common_arguments(ap)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--landmarks", action="store_true", help="both started from the pair's landmarks")
    ap.add_argument("--euclidean", action="store_true", help="score with straight-line distances (fast)")
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for entry, d in selected_pairs(args):
            pair = Pair(d)
            pair.units = entry["units"]  # MeshMonk's parameters are in mm (references.py scales cm by 10)
            ts, tm = [], []
            for k in range(args.rounds):
                order = ("s", "m") if k % 2 == 0 else ("m", "s")
                for who in order:
                    if who == "s":
                        wall, cs = surfmap_run(args.surfmap, d, os.path.join(tmp, "out"), args.landmarks)
                        ts.append(wall)
                    else:
                        wall, cm = meshmonk_run(pair, args.landmarks)
                        tm.append(wall)
            grade = (lambda p: euclidean_p05(pair, p)) if args.euclidean else (lambda p: score(pair, p)["pct_005"])
            row = dict(pair=entry["dir"], s=statistics.median(ts), m=statistics.median(tm),
                       ps=grade(cs), pm=grade(cm))
            rows.append(row)
            print(f"{row['pair']:45s} surfmap {row['s']:6.2f} s ({100 * row['ps']:5.1f} %)   "
                  f"MeshMonk {row['m']:6.2f} s ({100 * row['pm']:5.1f} %)   ratio {row['s'] / row['m']:.2f}",
                  flush=True)
    med = lambda k: statistics.median(r[k] for r in rows)  # noqa: E731
    print(f"\n{len(rows)} pairs, {args.rounds} rounds, {'with' if args.landmarks else 'without'} landmarks: "
          f"median surfmap {med('s'):.2f} s, MeshMonk {med('m'):.2f} s, "
          f"median ratio surfmap / MeshMonk {statistics.median(r['s'] / r['m'] for r in rows):.2f}; "
          f"mean within 0.05: surfmap {100 * np.mean([r['ps'] for r in rows]):.1f} %, "
          f"MeshMonk {100 * np.mean([r['pm'] for r in rows]):.1f} %")


if __name__ == "__main__":
    main()
