#!/usr/bin/env python3
"""Two surfmap binaries' matching speed, interleaved on the same pairs in one run.

For every selected pair (../shared/match_eval/make_pairs.py layout) and round, runs
`surfmap match A B -q` with binary `--base` and then `--new` (the order alternates by
round, so a slow spell of the machine hits both), and records the solve time
(`seconds_solve` in match.json) and the whole process's wall time. Prints per pair the
medians of both and their ratio new / base, then the median ratios over the pairs, and
whether the two binaries wrote byte-identical correspondences.

    /opt/peers-venv/bin/python scripts/ab_match_speed.py --pairs /tmp/surfmap_pairs \
        --base /tmp/surfmap_old --new target/release/surfmap --rounds 5 \
        [--only identity/0,partial/00] [--extra '--landmarks {pair}/landmarks.json']

`{pair}` in --extra stands for each pair's folder.
"""
import argparse
import filecmp
import json
import os
import subprocess
import tempfile
import time

import numpy as np

from match_common import selected_pairs


def run(binary, d, out, extra):
    extra = [x.replace("{pair}", d) for x in extra]
    cmd = [binary, "match", os.path.join(d, "A.obj"), os.path.join(d, "B.obj"), "-o", out, "-q"] + extra
    t = time.time()
    subprocess.run(cmd, check=True, capture_output=True)
    wall = time.time() - t
    return json.load(open(os.path.join(out, "match.json")))["seconds_solve"], wall


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pairs", required=True)
    ap.add_argument("--only", default=None, help="comma-separated substrings of pair names")
    ap.add_argument("--base", required=True)
    ap.add_argument("--new", required=True)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--extra", default="", help="extra arguments for surfmap match")
    args = ap.parse_args()
    extra = args.extra.split()
    ratios_solve, ratios_wall, identical = [], [], True
    print(f"{'pair':44s} {'solve base':>10s} {'solve new':>10s} {'ratio':>6s} {'wall base':>10s} {'wall new':>9s} {'ratio':>6s}")
    with tempfile.TemporaryDirectory() as tmp:
        for e, d in selected_pairs(args):
            times = {"base": [], "new": []}
            for r in range(args.rounds):
                order = ("base", "new") if r % 2 == 0 else ("new", "base")
                for which in order:
                    binary = args.base if which == "base" else args.new
                    times[which].append(run(binary, d, os.path.join(tmp, which), extra))
            same = filecmp.cmp(os.path.join(tmp, "base", "correspondence.npy"),
                               os.path.join(tmp, "new", "correspondence.npy"), shallow=False)
            identical &= same
            sb, wb = np.median(times["base"], axis=0)
            sn, wn = np.median(times["new"], axis=0)
            ratios_solve.append(sn / sb)
            ratios_wall.append(wn / wb)
            print(f"{e['dir']:44s} {sb:10.2f} {sn:10.2f} {sn / sb:6.2f} {wb:10.2f} {wn:9.2f} {wn / wb:6.2f}"
                  + ("" if same else "  (outputs differ)"), flush=True)
    print(f"median ratio new / base over {len(ratios_solve)} pairs: solve {np.median(ratios_solve):.3f}, "
          f"wall {np.median(ratios_wall):.3f}; outputs {'byte-identical' if identical else 'DIFFER'}")


if __name__ == "__main__":
    main()
