#!/usr/bin/env python3
"""Face pairs with hidden ground truth from the registered FLAME meshes (faces nobody tuned on).

The same layout as ../shared/match_eval/make_pairs.py (whose functions this imports; nothing is
copied): <out>/<track>/<name>/{A.obj, B.obj, gt.npz, landmarks.json} and <out>/index.json, so
`bench_match.py` and match_eval's `references.py` run on them unchanged.

Source: ../shared/data/faces/flame/flame_{template,registered,sample02,lmkfit}.ply, FLAME
topology (vertex i <-> vertex i in all four), metres. Per mesh:

  * the head component (the largest; the two eyeballs are dropped);
  * a FACE crop, one vertex mask for all four, defined on the template: vertices within
    `--radius` (Euclidean) of the nose tip whose normal faces forward (n_z > `--min-nz`); holes
    that this leaves inside the region are filled back (a component of the left-out faces that
    does not reach the neck is put back: the lips' inside stays, up to the mouth loop), then the
    largest face component is kept. The crop must be a disc with the mouth hole: 2 boundary loops, Euler characteristic 0 (checked);
  * the eye regions stay closed as FLAME models them: the eyelids fold into a pocket that lies
    inside the eyeball (~77 template vertices per eye). `--eye-holes` cuts those pockets out
    instead (faces with a vertex inside the template's eyeball sphere), giving 4 loops as on
    the ICT crops; that variant is for diagnosis.

Landmarks (template geometry, carried to the others by the registration): nose tip = most
forward (+z) vertex; mouth corners = min/max-x vertex of the mouth loop; eye corners = the
min/max-|x| vertex of each eyelid margin (head vertices outside the eyeball sphere next to
one inside it, in front of the eyeball's centre). Suffix _l means +x. Units "m": score.py's
lm_err is in metres.

make_pair then cuts its own bands off A and B, remeshes B, moves it rigidly and shuffles.
Tracks: `identity` (all 6 pairs of the 4 meshes, TRACK_CFG["identity"]) and `partial` (4
pairs, TRACK_CFG["partial"]: crops on opposite sides). Everything is seeded (--seed).

    /opt/peers-venv/bin/python scripts/flame_pairs.py --out /tmp/flame_pairs
    /opt/peers-venv/bin/python scripts/flame_pairs.py --table /tmp/flame_bench /tmp/flame_refs

`--table BENCH REFS` builds nothing: it prints, from bench_match.py's results.json in BENCH and
references.py's in REFS, one table per track in the layout of BENCHMARKS.md's matching table
(ours and the references' rows; landmark error in mm; flip and collapse of the worst pair) and
the fraction within 0.05 per pair.
"""
import argparse
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
MATCH_EVAL = os.path.join(HERE, "..", "..", "shared", "match_eval")
sys.path.insert(0, MATCH_EVAL)

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402
import igl  # noqa: E402
from common import (load_mesh, boundary_loops, largest_face_component, compact, edge_graph,  # noqa: E402
                    face_areas, mean_edge_length)
from make_pairs import make_pair, TRACK_CFG  # noqa: E402

FLAME_DIR = os.path.join(HERE, "..", "..", "shared", "data", "faces", "flame")
MESHES = ["template", "registered", "sample02", "lmkfit"]
IDENTITY = [("template", "registered"), ("template", "sample02"), ("template", "lmkfit"),
            ("registered", "sample02"), ("registered", "lmkfit"), ("sample02", "lmkfit")]
PARTIAL = [("template", "registered"), ("registered", "sample02"), ("template", "lmkfit"),
           ("sample02", "lmkfit")]


def face_components(F):
    """Label of the edge-connected face component of every face."""
    TT, _ = igl.triangle_triangle_adjacency(F)
    m = len(F)
    rows, cols = np.repeat(np.arange(m), 3), TT.reshape(-1)
    ok = cols >= 0
    A = sp.coo_matrix((np.ones(ok.sum()), (rows[ok], cols[ok])), shape=(m, m))
    return sp.csgraph.connected_components(A, directed=False)[1]


def head_and_eyes(V, F):
    """Head (largest component) as (V, F, head->file vertex ids) and the eyeballs as (centre, radius)."""
    lab = face_components(F)
    big = np.argmax(np.bincount(lab))
    eyes = []
    for c in range(lab.max() + 1):
        if c == big:
            continue
        E = V[np.unique(F[lab == c])]
        centre = E.mean(0)
        eyes.append((centre, float(np.linalg.norm(E - centre, axis=1).mean())))
    H, FH, h2v = compact(V, F, lab == big)
    return H, FH, h2v, eyes


def inside_eyes(H, eyes):
    """Head vertices inside an eyeball sphere: the eyelid pockets."""
    inside = np.zeros(len(H), bool)
    for c, r in eyes:
        inside |= np.linalg.norm(H - c, axis=1) < r
    return inside


def face_mask(H, FH, eyes, radius, min_nz, eye_holes):
    """Face mask of the crop on the template head (see the module doc)."""
    nose = int(np.argmax(H[:, 2]))
    N = igl.per_vertex_normals(H, FH)
    keepv = (np.linalg.norm(H - H[nose], axis=1) < radius) & (N[:, 2] > min_nz)
    fm = keepv[FH].all(1)
    # fill holes: a component of the left-out faces that does not reach the neck (the head's lower loop)
    on_rim = np.zeros(len(H), bool)
    on_rim[min(boundary_loops(FH), key=lambda lp: H[lp, 1].mean())] = True
    out = np.where(~fm)[0]
    lab = face_components(FH[out])
    for c in range(lab.max() + 1 if len(out) else 0):
        fs = out[lab == c]
        if not on_rim[FH[fs]].any():
            fm[fs] = True
    if eye_holes:
        fm &= ~inside_eyes(H, eyes)[FH].any(1)
    keep = np.zeros(len(FH), bool)
    keep[np.where(fm)[0][largest_face_component(FH[fm])]] = True
    return keep


def landmarks(H, FH, eyes, mouth):
    """Named template head vertices (see the module doc)."""
    out = {"nose_tip": int(np.argmax(H[:, 2]))}
    inside = inside_eyes(H, eyes)
    G = edge_graph(H, FH)
    G.data[:] = 1.0
    next_to_inside = (G @ inside.astype(float)) > 0
    for c, r in eyes:
        side = "l" if c[0] > 0 else "r"
        near = np.linalg.norm(H - c, axis=1) < 1.5 * r
        margin = np.where(~inside & next_to_inside & near & (H[:, 2] > c[2]))[0]
        ax = np.abs(H[margin, 0])
        out["eye_inner_" + side] = int(margin[np.argmin(ax)])
        out["eye_outer_" + side] = int(margin[np.argmax(ax)])
    out["mouth_corner_l"] = int(mouth[np.argmax(H[mouth, 0])])
    out["mouth_corner_r"] = int(mouth[np.argmin(H[mouth, 0])])
    return out


METHOD_NAMES = {"surfmap": "**surfmap, no input**", "surfmap_lm": "surfmap, landmarks",
                "flat_lm": "landmark-aligned flattening", "icp": "rigid ICP", "nricp": "non-rigid ICP",
                "nricp_lm": "non-rigid ICP + landmarks"}
REFERENCES = ["flat_lm", "icp", "nricp", "nricp_lm"]


def tables(bench_dir, refs_dir):
    """Print our rows and the references' (landmark error in mm: the pairs are in metres)."""
    ours = json.load(open(os.path.join(bench_dir, "results.json")))
    refs = {r["dir"]: r["scores"] for r in json.load(open(os.path.join(refs_dir, "results.json")))}

    def curve02(s):
        return dict(zip([round(t, 2) for t in s["thresholds"]], s["curve"]))[0.02]

    rows = {}  # (track, method) -> list of per-pair dicts in one vocabulary
    for r in ours:  # bench_match.py already reports the landmark error in mm
        rows.setdefault((r["track"], r["method"]), []).append(dict(
            pair=r["pair"], mean=r["mean"], p02=r["p02"], p05=r["p05"], p10=r["p10"], lm=r["lm"],
            cover=r["coverA"], flip=r["flip"], collapse=r["collapse"], fm=r["false_match"]))
    for d, scores in sorted(refs.items()):
        for m in REFERENCES:
            if m in scores:
                s = scores[m]
                rows.setdefault((d.split("/")[0], m), []).append(dict(
                    pair=d, mean=s["mean_err"], p02=curve02(s), p05=s["pct_005"], p10=s["pct_01"],
                    lm=1000 * s["lm_err"], cover=s["coverage_A"], flip=s["flip"], collapse=s["collapse"],
                    fm=s["false_match"]))
    methods = ["surfmap", "surfmap_lm"] + REFERENCES
    print("| track (pairs) | method | mean err | % <0.02 | % <0.05 | % <0.10 | lm err (mm) | cover A | flip % "
          "| collapse % | false match % |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for track in sorted({t for t, _ in rows}):
        for m in methods:
            rs = rows.get((track, m))
            if not rs:
                continue
            mean = lambda k: float(np.mean([r[k] for r in rs]))  # noqa: E731
            worst = lambda k: 100 * max(r[k] for r in rs)  # noqa: E731
            print(f"| {track} ({len(rs)}) | {METHOD_NAMES[m]} | {mean('mean'):.3f} | {100 * mean('p02'):.1f} "
                  f"| {100 * mean('p05'):.1f} | {100 * mean('p10'):.1f} | {mean('lm'):.2f} | {100 * mean('cover'):.1f} "
                  f"| {worst('flip'):.1f} | {worst('collapse'):.1f} | {100 * mean('fm'):.1f} |")
    print()
    print("| pair | " + " | ".join(METHOD_NAMES[m].strip("*") for m in methods) + " |")
    print("|---|" + "---:|" * len(methods))
    pairs = sorted({r["pair"] for rs in rows.values() for r in rs})
    for p in pairs:
        cells = []
        for m in methods:
            r = [r for (_, mm), rs in rows.items() if mm == m for r in rs if r["pair"] == p]
            cells.append(f"{100 * r[0]['p05']:.1f}" if r else "–")
        print(f"| {p} | " + " | ".join(cells) + " |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="/tmp/flame_pairs")
    ap.add_argument("--flame", default=FLAME_DIR)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--radius", type=float, default=0.10, help="crop radius around the nose tip (m)")
    ap.add_argument("--min-nz", type=float, default=-0.3, help="crop: least z component of the normal")
    ap.add_argument("--eye-holes", action="store_true", help="cut the eyelid pockets out (4 loops)")
    ap.add_argument("--tracks", default="identity,partial")
    ap.add_argument("--mm", action="store_true",
                    help="write the pairs in millimetres (FLAME is in metres): tools whose parameters "
                         "assume mm, such as MeshMonk in references.py, need it; scores do not change")
    ap.add_argument("--table", nargs=2, metavar=("BENCH", "REFS"),
                    help="print the tables from bench_match.py's and references.py's results instead")
    args = ap.parse_args()
    if args.table:
        tables(*args.table)
        return

    heads = {}
    for name in MESHES:
        V, F = load_mesh(os.path.join(args.flame, f"flame_{name}.ply"))
        heads[name] = head_and_eyes(V, F)
    H, FH, h2v, eyes = heads["template"]
    for name in MESHES:
        assert np.array_equal(heads[name][1], FH) and np.array_equal(heads[name][2], h2v), \
            f"flame_{name}.ply is not registered to the template"
    keep = face_mask(H, FH, eyes, args.radius, args.min_nz, args.eye_holes)
    Vc, Fc, c2h = compact(H, FH, keep)
    loops = boundary_loops(Fc)
    chi = len(Vc) - len(np.unique(np.sort(np.r_[Fc[:, [0, 1]], Fc[:, [1, 2]], Fc[:, [2, 0]]], 1), axis=0)) + len(Fc)
    head_mouth = max(boundary_loops(FH), key=lambda lp: H[lp, 1].mean())  # the head's loops: neck, mouth
    h2c = -np.ones(len(H), np.int64)
    h2c[c2h] = np.arange(len(c2h))
    mouth = [lp for lp in loops if set(h2c[head_mouth].tolist()) == set(lp.tolist())]
    want = 4 if args.eye_holes else 2
    print(f"crop: {len(Vc)} V, {len(Fc)} F, boundary loops {[len(lp) for lp in loops]}, Euler characteristic {chi}, "
          f"mouth loop kept: {bool(mouth)}, area {face_areas(Vc, Fc).sum():.4f} m^2, "
          f"mean edge {1000 * mean_edge_length(Vc, Fc):.1f} mm")
    if len(loops) != want or chi != 2 - want or not mouth:
        sys.exit(f"the crop is not a disc with {want - 1} hole(s) including the mouth: change --radius / --min-nz")
    lm0 = {k: int(h2c[v]) for k, v in landmarks(H, FH, eyes, head_mouth).items()}
    assert min(lm0.values()) >= 0, "a landmark fell outside the crop"
    print("landmarks (crop vertex: template position, mm):")
    for k, v in lm0.items():
        print(f"  {k:15s} {v:5d}  " + " ".join(f"{1000 * x:7.1f}" for x in Vc[v]))
    units, scale = ("mm", 1000.0) if args.mm else ("m", 1.0)
    crops = {name: scale * heads[name][0][c2h] for name in MESHES}

    tracks = args.tracks.split(",")
    jobs = [("identity", k, a, b) for k, (a, b) in enumerate(IDENTITY) if "identity" in tracks]
    jobs += [("partial", k, a, b) for k, (a, b) in enumerate(PARTIAL) if "partial" in tracks]
    rng = np.random.default_rng(args.seed)
    index, t0 = [], time.time()
    for track, k, a, b in jobs:
        cfg = dict(TRACK_CFG[track])
        name = f"{k:02d}_flame_{a}__flame_{b}"
        d = os.path.join(args.out, track, name)
        seed = int(rng.integers(2**31))
        info = make_pair(d, crops[a], crops[b], Fc, lm0, cfg, seed, units=units)
        info.update(track=track, name=name, dir=os.path.relpath(d, args.out), A_src=f"flame_{a}.ply",
                    B_src=f"flame_{b}.ply", seed=seed, resolution_factor=1.0, units=units, crop=cfg,
                    face_crop=dict(radius=args.radius, min_nz=args.min_nz, eye_holes=args.eye_holes))
        index.append(info)
        print(f"[{time.time() - t0:5.1f}s] {track}/{name}: nA={info['nA']} nB={info['nB']} "
              f"gt_valid={info['n_gt_valid']} ({100 * info['n_gt_valid'] / info['nA']:.0f}% of A) "
              f"lm={info['n_landmarks']}", flush=True)
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "index.json"), "w") as f:
        json.dump(index, f, indent=1)
    print(f"wrote {len(index)} pairs to {args.out} in {time.time() - t0:.1f}s")


if __name__ == "__main__":
    main()
