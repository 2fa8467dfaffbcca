#!/usr/bin/env python3
"""Robustness sweep: `surfmap flatten` on every mesh in ../shared/data, once as is and once
with the repairs a user would try (--keep-largest --fill-holes --weld --drop-degenerate).

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
bad, ok_plain, ok_repaired = [], 0, 0
for f in manifest["files"]:
    path = os.path.join(args.data, f["file"])
    for extra in ([], repairs):
        t = time.time()
        r = subprocess.run([args.surfmap, "flatten", path, "-o", out, "--quiet"] + extra,
                           capture_output=True, text=True, timeout=600)
        dt = time.time() - t
        last = r.stderr.strip().splitlines()[-1][:100] if r.stderr.strip() else ""
        print(f"{f['file']:<34} {'repaired' if extra else 'as is':<9} exit {r.returncode} {dt:6.2f} s  {last}")
        if r.returncode not in (0, 1) or "panicked" in r.stderr:
            bad.append(f["file"])
        elif r.returncode == 0:
            if extra:
                ok_repaired += 1
            else:
                ok_plain += 1
n = len(manifest["files"])
print(f"\n{n} meshes: {ok_plain} flattened as is, {ok_repaired} with repairs; "
      f"{len(bad)} runs ended otherwise than flattened-or-refused {bad}")
sys.exit(1 if bad else 0)
