#!/usr/bin/env python3
"""Accuracy and speed of `surfmap match` on the referee's face pairs.

Runs the surfmap binary on every pair made by ../shared/match_eval/make_pairs.py (without
input, and with the 7 landmarks), scores each prediction with that folder's independent
referee (score.py; the matcher never reads gt.npz) and prints one table row per track in
the layout of match_eval/references.py, so the two tables can be read side by side. The
landmark error is in the pairs' units (index.json), except that metres are shown as mm
(scripts/flame_pairs.py makes such pairs).

    /opt/peers-venv/bin/python scripts/bench_match.py --pairs /tmp/surfmap_pairs \
        --surfmap target/release/surfmap [--only identity,partial] [--out /tmp/surfmap_bench]
"""
import argparse
import json
import os
import subprocess
import time

from match_common import add_common_arguments, selected_pairs

import numpy as np  # noqa: E402
from score import Pair, score  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    add_common_arguments(ap)
    ap.add_argument("--out", default="/tmp/surfmap_bench")
    ap.add_argument("--extra", default="", help="extra arguments for surfmap match")
    args = ap.parse_args()
    rows = []
    for e, d in selected_pairs(args):
        for method, extra in (("surfmap", []), ("surfmap_lm", ["--landmarks", os.path.join(d, "landmarks.json")])):
            out = os.path.join(args.out, method, e["dir"])
            cmd = [args.surfmap, "match", os.path.join(d, "A.obj"), os.path.join(d, "B.obj"), "-o", out, "-q"]
            cmd += extra + args.extra.split()
            t = time.time()
            r = subprocess.run(cmd, capture_output=True, text=True)
            seconds = time.time() - t
            if r.returncode != 0:
                print(f"{e['dir']} {method}: FAILED {r.stderr.strip()}", flush=True)
                continue
            report = json.load(open(os.path.join(out, "match.json")))
            s = score(Pair(d), np.load(os.path.join(out, "correspondence.npy")))
            curve = dict(zip([round(x, 2) for x in s["thresholds"]], s["curve"]))
            # the landmark error in the pairs' units, metres shown as mm
            lm_scale, units = (1000.0, "mm") if e.get("units") == "m" else (1.0, e.get("units", "cm"))
            row = dict(track=e["track"], pair=e["dir"], method=method, units=units, mean=s["mean_err"],
                       p05=s["pct_005"], p02=curve[0.02], p10=s["pct_01"], lm=lm_scale * s["lm_err"],
                       coverA=s["coverage_A"], coverB=s["cover_B"], flip=s["flip"],
                       collapse=s["collapse"], false_match=s["false_match"], seconds=seconds,
                       solve=report["seconds_solve"], min_det=report["min_det"],
                       verdict=report.get("confidence", {}).get("verdict", "-"))
            rows.append(row)
            print(f"{e['dir']:46s} {method:10s} <.02 {row['p02']:.3f} <.05 {row['p05']:.3f} lm {row['lm']:.2f} "
                  f"flip {row['flip']:.4f} coll {row['collapse']:.4f} fm {row['false_match']:.3f} "
                  f"solve {row['solve']:.2f}s total {seconds:.2f}s min det {row['min_det']:.3f} {row['verdict']}", flush=True)
    os.makedirs(args.out, exist_ok=True)
    json.dump(rows, open(os.path.join(args.out, "results.json"), "w"), indent=1)
    print()
    print("| track (pairs, lm units) | method | mean err | % <0.02 | % <0.05 | % <0.10 | lm err | cover A | cover B "
          "| flip | collapse | false match | worst % <0.05 | verdicts ok/doubtful/failed | solve s (median) "
          "| process s (median) |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|")
    for track in ("expression", "identity", "partial", "resolution"):
        for method in ("surfmap", "surfmap_lm"):
            rs = [r for r in rows if r["track"] == track and r["method"] == method]
            if not rs:
                continue
            m = lambda k: float(np.mean([r[k] for r in rs]))  # noqa: E731
            med = lambda k: float(np.median([r[k] for r in rs]))  # noqa: E731
            print(f"| {track} ({len(rs)}, {rs[0]['units']}) | {method} | {m('mean'):.3f} | {100 * m('p02'):.1f} | {100 * m('p05'):.1f} "
                  f"| {100 * m('p10'):.1f} | {m('lm'):.2f} | {100 * m('coverA'):.1f} | {100 * m('coverB'):.1f} "
                  f"| {100 * max(r['flip'] for r in rs):.2f} | {100 * max(r['collapse'] for r in rs):.2f} "
                  f"| {100 * m('false_match'):.1f} | {100 * min(r['p05'] for r in rs):.1f} "
                  f"| {'/'.join(str(sum(r['verdict'] == v for r in rs)) for v in ('ok', 'doubtful', 'failed'))} "
                  f"| {med('solve'):.2f} | {med('seconds'):.2f} |")


if __name__ == "__main__":
    main()
