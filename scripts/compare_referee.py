#!/usr/bin/env python3
"""Compare `surfmap measure` with the project's referee on the same UV OBJ files.

For every OBJ (with `vt`) given, this runs

  * the referee `shared/peers/distortion.py` (imported; needs numpy), and
  * `surfmap measure --json FILE` and `surfmap measure --csv FILE`,

and prints, per measure, the referee value, ours, and the relative difference
|ours - ref| / max(|ref|, 1) (exact match of counts). The `--csv` columns of the
Shay-Solomon-Stein benchmark are checked against an independent numpy
re-computation of that benchmark's definitions (numpy SVD, law-of-cosines angles).

Conventions mapped: our `symmetric_dirichlet` is libigl's (isometry 4), the
referee's `sym_dirichlet_*` is divided by 4 (isometry 1). Our JSON writes +inf as
null.

Usage:
  python3 scripts/compare_referee.py [--surfmap PATH] [--referee DIR] [--tol 1e-9] FILE.obj ...
Exit status 1 if any difference exceeds --tol.
"""

import argparse
import csv
import io
import json
import math
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))

# (referee key, path in our JSON, factor applied to the referee value)
PAIRS = [
    ("flipped", "flipped_triangles", 1),
    ("degenerate_uv", "degenerate_uv", 1),
    ("degenerate_3d", "degenerate_3d", 1),
    ("charts", "charts", 1),
    ("mirrored_charts", "mirrored_charts", 1),
    ("uv_scale", "uv_scale", 1),
    ("sym_dirichlet_mean", "symmetric_dirichlet", 4),
    ("sym_dirichlet_max", "symmetric_dirichlet_max", 4),
    ("conformal_mean", "conformal_mean", 1),
    ("conformal_max", "conformal_max", 1),
    ("area_min", "area_distortion.min", 1),
    ("area_max", "area_distortion.max", 1),
    ("log_area_mean_abs", "area_distortion.log_mean_abs", 1),
    ("L2_stretch_fwd", "stretch.l2_forward", 1),
    ("L2_stretch_sander", "stretch.l2", 1),
    ("Linf_stretch_sander", "stretch.linf", 1),
    ("thesis_angle_mean", "measures.angle.mean", 1),
    ("thesis_angle_max", "measures.angle.max", 1),
    ("thesis_area_mean", "measures.area.mean", 1),
    ("thesis_area_max", "measures.area.max", 1),
    ("thesis_length_mean", "measures.length.mean", 1),
    ("thesis_length_max", "measures.length.max", 1),
]


def get(d, path):
    for k in path.split("."):
        d = d[k]
    return math.inf if d is None else d


def reldiff(a, b):
    if isinstance(a, bool) or isinstance(b, bool):
        return 0.0 if a == b else math.inf
    if math.isinf(a) or math.isinf(b):
        return 0.0 if a == b else math.inf
    if math.isnan(a) or math.isnan(b):
        return 0.0 if (math.isnan(a) and math.isnan(b)) else math.inf
    return abs(a - b) / max(abs(b), 1.0)


def sss_benchmark(V, F, C):
    """Independent numpy version of the Shay-Solomon-Stein benchmark columns."""
    P = V[F]
    A3 = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    e1, e2 = C[:, 1] - C[:, 0], C[:, 2] - C[:, 0]
    Auv = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    Vs = V / math.sqrt(A3.sum())
    Cs = C / math.sqrt(Auv.sum())
    a3, auv = A3 / A3.sum(), Auv / Auv.sum()
    # Jacobian in an orthonormal frame of each 3D triangle, by least squares on edges.
    Ps = Vs[F]
    d1, d2 = Ps[:, 1] - Ps[:, 0], Ps[:, 2] - Ps[:, 0]
    n = np.cross(d1, d2)
    x = d1 / np.linalg.norm(d1, axis=1)[:, None]
    y = np.cross(n / np.linalg.norm(n, axis=1)[:, None], x)
    Q = np.stack([np.stack([(d1 * x).sum(1), (d1 * y).sum(1)], 1),
                  np.stack([(d2 * x).sum(1), (d2 * y).sum(1)], 1)], 2)  # columns = local edges
    U = np.stack([Cs[:, 1] - Cs[:, 0], Cs[:, 2] - Cs[:, 0]], 2)
    good = A3 > 0
    J = U[good] @ np.linalg.inv(Q[good])
    sv = np.linalg.svd(J, compute_uv=False)
    det = np.linalg.det(J)
    a3g, auvg = a3[good], auv[good]
    with np.errstate(divide="ignore", invalid="ignore"):
        area_d = np.where(auvg > 0, auvg / a3g + a3g / auvg, np.inf)
        ang_d = np.where(sv[:, 1] > 0, sv[:, 0] / sv[:, 1] + sv[:, 1] / sv[:, 0], np.inf)
        sd = 0.5 * np.sum(a3g * (sv[:, 0] ** 2 + sv[:, 1] ** 2 + 1 / sv[:, 0] ** 2 + 1 / sv[:, 1] ** 2))

    def angles(T):
        a = np.linalg.norm(T[:, 1] - T[:, 2], axis=1)
        b = np.linalg.norm(T[:, 2] - T[:, 0], axis=1)
        c = np.linalg.norm(T[:, 0] - T[:, 1], axis=1)
        ok = (a > 0) & (b > 0) & (c > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            A = np.arccos(np.clip((b * b + c * c - a * a) / (2 * b * c), -1, 1))
            B = np.arccos(np.clip((a * a + c * c - b * b) / (2 * a * c), -1, 1))
            Cc = np.arccos(np.clip((a * a + b * b - c * c) / (2 * a * b), -1, 1))
        return np.stack([A, B, Cc], 1), ok

    am, okm = angles(Ps[good])
    au, oku = angles(Cs[good])
    err = np.where((okm & oku)[:, None], np.abs(am - au), 2 * math.pi).sum(1)
    p = float(np.mean(det < 0))
    return {
        "Faces": F.shape[0],
        "Vertices": V.shape[0],
        "Max Area Distortion": float(np.max(area_d) - 2),
        "Average Area Discrepancy": float(np.sum(np.abs(auvg - a3g))),
        "Min Singular Value": float(np.min(sv[:, 1])),
        "Max Singular Value": float(np.max(sv[:, 0])),
        "Proportion Flipped Triangles": min(p, 1 - p),
        "Max Angle Distortion": float(np.max(ang_d) - 2),
        "Average Angle Discrepancy": float(np.sum(a3g * err)),
        "Symmetric Dirichlet Energy": float(sd),
    }


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--surfmap", default=os.path.join(HERE, "..", "target", "release", "surfmap"))
    ap.add_argument("--referee", default=os.path.join(HERE, "..", "..", "..", "shared", "peers"))
    ap.add_argument("--tol", type=float, default=1e-9)
    a = ap.parse_args(argv)
    sys.path.insert(0, os.path.abspath(a.referee))
    import distortion  # noqa: E402  (the referee)

    worst = 0.0
    for path in a.files:
        V, F, C = distortion.load_mesh(path)
        if C is None:
            print(f"{path}: no per-corner vt, skipped")
            continue
        ref = distortion.distortion(V, F, C)
        ours = json.loads(subprocess.run([a.surfmap, "measure", "--json", path], check=True,
                                         capture_output=True, text=True).stdout)
        rows = list(csv.DictReader(io.StringIO(subprocess.run(
            [a.surfmap, "measure", "--csv", path], check=True, capture_output=True, text=True).stdout)))
        bench_ours = rows[0]
        bench_ref = sss_benchmark(V, F, C)
        print(f"\n=== {os.path.basename(path)}: {F.shape[0]} faces, {ref['charts']} chart(s), "
              f"{ref['flipped']} flipped; overlap: crossings {ours['boundary_overlap']['boundary_crossings']}, "
              f"area fraction {ours['boundary_overlap']['overlap_fraction']:.3g}")
        print(f"  {'measure':<34} {'referee':>14} {'surfmap':>14} {'rel diff':>9}")
        file_worst = 0.0
        for rk, ok, factor in PAIRS:
            r = ref[rk] * factor if not isinstance(ref[rk], bool) else ref[rk]
            o = get(ours, ok)
            d = reldiff(o, r)
            file_worst = max(file_worst, d)
            flag = "" if d <= a.tol else "  <-- DIFFERS"
            print(f"  {rk + (' x4' if factor == 4 else ''):<34} {r:>14.8g} {o:>14.8g} {d:>9.1e}{flag}")
        for k, r in bench_ref.items():
            o = float(bench_ours[k])
            d = reldiff(o, float(r))
            file_worst = max(file_worst, d)
            flag = "" if d <= a.tol else "  <-- DIFFERS"
            print(f"  {'SSS ' + k:<34} {float(r):>14.8g} {o:>14.8g} {d:>9.1e}{flag}")
        print(f"  worst relative difference: {file_worst:.2e}")
        worst = max(worst, file_worst)
    print(f"\nworst over all files: {worst:.2e} (tolerance {a.tol:g})")
    return 0 if worst <= a.tol else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
