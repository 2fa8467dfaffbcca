#!/usr/bin/env python3
"""Robustness sweep: `surfmap flatten` on every mesh in ../shared/data, once as is, once
with the repairs a user would try (--keep-largest --fill-holes --weld --drop-degenerate)
and once with --repair (every repair without a parameter, non-manifold fixes included).

Every run must end with exit 0 (flattened) or 1 (refused with a reason) — never a panic
(exit 101) or a hang. Prints one line per run and a summary.

    python3 scripts/sweep_flatten.py [--surfmap target/release/surfmap] [--data ../shared/data]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

ap = argparse.ArgumentParser()
ap.add_argument("--surfmap", default="target/release/surfmap")
ap.add_argument("--data", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data"))
args = ap.parse_args()

manifest = json.load(open(os.path.join(args.data, "manifest.json")))
out = os.path.join(tempfile.mkdtemp(), "sweep.obj")
repairs = ["--keep-largest", "--fill-holes", "--weld", "--drop-degenerate"]
modes = {"as is": [], "repaired": repairs, "--repair": ["--repair"]}
bad, ok = [], {m: 0 for m in modes}
for f in manifest["files"]:
    path = os.path.join(args.data, f["file"])
    for mode, extra in modes.items():
        t = time.time()
        r = subprocess.run([args.surfmap, "flatten", path, "-o", out, "--quiet"] + extra,
                           capture_output=True, text=True, timeout=600)
        dt = time.time() - t
        last = r.stderr.strip().splitlines()[-1][:100] if r.stderr.strip() else ""
        print(f"{f['file']:<34} {mode:<9} exit {r.returncode} {dt:6.2f} s  {last}")
        if r.returncode not in (0, 1) or "panicked" in r.stderr:
            bad.append(f["file"])
        elif r.returncode == 0:
            ok[mode] += 1
n = len(manifest["files"])
print(f"\n{n} meshes: {ok['as is']} flattened as is, {ok['repaired']} with those repairs, "
      f"{ok['--repair']} with --repair; "
      f"{len(bad)} runs ended otherwise than flattened-or-refused {bad}")
sys.exit(1 if bad else 0)
