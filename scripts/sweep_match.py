#!/usr/bin/env python3
"""Robustness sweep of `surfmap match`: every mesh in ../shared/data matched onto a moved
copy of itself.

For each mesh A, B is A under a random rotation (20–40° about a random axis) and
translation, with its vertices and faces shuffled, written as OBJ (so B's ids say nothing).
`surfmap match A B -o DIR --quiet` runs as is and, when refused, with `--repair`. Every
run must end with exit 0 (matched) or 1 (refused with a reason) — never a panic (exit
101) or a hang (10 minutes).

For a match the truth is known: A's vertex i belongs at B's copy of it. The sweep reads
`correspondence.npy` (when it has one row per input vertex of A) and reports the fraction
of A's vertices whose image lies within 0.01 and 0.05·√area of their copy (3D distance,
unmatched vertices fail), the matched fraction, `min_det`, the fold counts of
`match.json` (flipped / collapsed image triangles found before they were dropped), and
re-checks the output for folds itself: no face of `A_on_B.obj` may have an image normal
opposite to B's (the referee's test; skipped when B's faces are not consistently oriented
as given). With `--repair` the outputs are numbered as the files given; vertices the repairs
removed are unmatched, and the line also gives the fraction among the others.

    python3 scripts/sweep_match.py [--surfmap target/release/surfmap] [--data ../shared/data]
        [--only NAME,...] [--max-faces N] [--out DIR]      # needs numpy
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import zlib

import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("--surfmap", default="target/release/surfmap")
ap.add_argument("--data", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data"))
ap.add_argument("--only", default="", help="comma-separated substrings of file names")
ap.add_argument("--max-faces", type=int, default=0, help="skip meshes with more faces (0: none)")
ap.add_argument("--out", default="", help="folder for the outputs (default: a temporary one)")
args = ap.parse_args()


def read_obj_like(path):
    """Vertices and triangles (polygons fanned) of an OBJ or OFF file."""
    ext = os.path.splitext(path)[1].lower()
    V, F = [], []
    if ext == ".obj":
        for line in open(path, errors="replace"):
            p = line.split()
            if not p:
                continue
            if p[0] == "v":
                V.append([float(x) for x in p[1:4]])
            elif p[0] == "f":
                ids = [int(x.split("/")[0]) for x in p[1:]]
                ids = [i - 1 if i > 0 else len(V) + i for i in ids]
                for k in range(1, len(ids) - 1):
                    F.append([ids[0], ids[k], ids[k + 1]])
    elif ext == ".off":
        toks = []
        for line in open(path, errors="replace"):
            line = line.split("#")[0]
            toks += line.split()
        assert toks[0].endswith("OFF")
        toks = toks[1:] if toks[0] == "OFF" else [toks[0][3:]] + toks[1:]
        nv, nf = int(toks[0]), int(toks[1])
        k = 3
        for _ in range(nv):
            V.append([float(x) for x in toks[k:k + 3]])
            k += 3
        for _ in range(nf):
            n = int(toks[k])
            ids = [int(x) for x in toks[k + 1:k + 1 + n]]
            k += 1 + n
            for j in range(1, n - 1):
                F.append([ids[0], ids[j], ids[j + 1]])
    else:
        return None
    return np.array(V, float), np.array(F, int).reshape(-1, 3)


def read_ply(path):
    """Vertices and triangles of a binary little-endian PLY (the format of the PLYs
    here); None for another encoding."""
    with open(path, "rb") as fh:
        header = []
        while True:
            line = fh.readline().decode("ascii", "replace").strip()
            header.append(line)
            if line == "end_header":
                break
        body = fh.read()
    fmt = [h for h in header if h.startswith("format")][0].split()[1]
    elements, cur = [], None
    for h in header:
        p = h.split()
        if p[0] == "element":
            cur = [p[1], int(p[2]), []]
            elements.append(cur)
        elif p[0] == "property":
            cur[2].append(p[1:])
    sizes = {"float": "f4", "float32": "f4", "double": "f8", "float64": "f8", "uchar": "u1",
             "uint8": "u1", "char": "i1", "int8": "i1", "short": "i2", "int16": "i2",
             "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4",
             "uint32": "u4"}
    if fmt != "binary_little_endian":
        return None
    off = 0
    V = F = None
    for name, count, props in elements:
        if all(p[0] != "list" for p in props):
            dt = np.dtype([(p[1], "<" + sizes[p[0]]) for p in props])
            arr = np.frombuffer(body, dt, count, off)
            off += dt.itemsize * count
            if name == "vertex":
                V = np.stack([arr["x"], arr["y"], arr["z"]], 1).astype(float)
        else:
            (_, ct, it, pname), = props
            cdt, idt = np.dtype("<" + sizes[ct]), np.dtype("<" + sizes[it])
            faces = []
            for _ in range(count):
                n = int(np.frombuffer(body, cdt, 1, off)[0])
                off += cdt.itemsize
                ids = np.frombuffer(body, idt, n, off)
                off += idt.itemsize * n
                for j in range(1, n - 1):
                    faces.append([ids[0], ids[j], ids[j + 1]])
            F = np.array(faces, int).reshape(-1, 3)
    return V, F


def random_rotation(rng):
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    angle = np.radians(rng.uniform(20, 40))
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def area(V, F):
    return 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1).sum()


manifest = json.load(open(os.path.join(args.data, "manifest.json")))
root = args.out or tempfile.mkdtemp()
os.makedirs(root, exist_ok=True)
bad, rows = [], []
for f in manifest["files"]:
    name = f["file"]
    if args.only and not any(s in name for s in args.only.split(",")):
        continue
    if args.max_faces and f.get("F", 0) > args.max_faces:
        print(f"{name:<34} skipped ({f.get('F')} faces)")
        continue
    path = os.path.join(args.data, name)
    mesh = read_obj_like(path) if not name.endswith(".ply") else read_ply(path)
    if mesh is None:
        print(f"{name:<34} skipped (format this script does not read)")
        continue
    V, F = mesh
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    R = random_rotation(rng)
    t = rng.normal(size=3) * np.sqrt(area(V, F)) * 0.3
    order = rng.permutation(len(V))  # B's vertex j is A's vertex order[j]
    where = np.empty(len(V), int)
    where[order] = np.arange(len(V))
    VB = V[order] @ R.T + t
    FB = where[F][rng.permutation(len(F))]
    tag = os.path.splitext(name.replace("/", "_"))[0]
    b_path = os.path.join(root, tag + "_moved.obj")
    with open(b_path, "w") as fh:
        fh.write("".join(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in VB))
        fh.write("".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in FB))
    out = os.path.join(root, tag)
    for mode, extra in (("as is", []), ("--repair", ["--repair"])):
        start = time.time()
        try:
            r = subprocess.run([args.surfmap, "match", path, b_path, "-o", out, "--quiet"] + extra,
                               capture_output=True, text=True, timeout=600)
        except subprocess.TimeoutExpired:
            print(f"{name:<34} {mode:<8} TIMEOUT")
            bad.append(name)
            break
        dt = time.time() - start
        last = r.stderr.strip().splitlines()[0][:110] if r.stderr.strip() else ""
        if r.returncode not in (0, 1) or "panicked" in r.stderr:
            print(f"{name:<34} {mode:<8} exit {r.returncode} {dt:6.2f} s  {last}")
            bad.append(name)
            break
        if r.returncode == 1:
            print(f"{name:<34} {mode:<8} refused {dt:5.2f} s  {last}")
            continue
        rep = json.load(open(os.path.join(out, "match.json")))
        C = np.load(os.path.join(out, "correspondence.npy"))
        row = dict(file=name, mode=mode, seconds=dt, matched=rep["matched_fraction_a"],
                   min_det=rep["min_det"], flipped_found=rep["flipped_triangles"],
                   collapsed_found=rep["collapsed_triangles"])
        if len(C) == len(V):
            tri = C[:, 0].astype(int)
            m = tri >= 0
            P = np.full((len(V), 3), np.nan)
            P[m] = (VB[FB[tri[m]]] * C[m, 1:4, None]).sum(1)
            err = np.linalg.norm(P - (V @ R.T + t), axis=1) / np.sqrt(area(V, F))
            err[~m] = np.inf
            row["within_001"] = float((err <= 0.01).mean())
            row["within_005"] = float((err <= 0.05).mean())
            removed = (rep.get("input_numbering") or {}).get("removed_vertices_a", 0)
            # The referee's fold test on the faces of A_on_B.obj (A's faces as matched, on
            # the input's vertex numbers), against B's normals — meaningful only when B's
            # faces are consistently oriented as given.
            _, used = read_obj_like(os.path.join(out, "A_on_B.obj"))
            directed = np.concatenate([FB[:, [0, 1]], FB[:, [1, 2]], FB[:, [2, 0]]])
            _, edge, faces_per_edge = np.unique(np.sort(directed, 1), axis=0, return_inverse=True,
                                                return_counts=True)
            manifold = faces_per_edge[edge.ravel()] == 2
            consistent = len(np.unique(directed[manifold], axis=0)) == manifold.sum()
            if consistent and len(used):
                n_img = np.cross(P[used[:, 1]] - P[used[:, 0]], P[used[:, 2]] - P[used[:, 0]])
                NB = np.cross(VB[FB[:, 1]] - VB[FB[:, 0]], VB[FB[:, 2]] - VB[FB[:, 0]])
                NB /= np.maximum(np.linalg.norm(NB, axis=1), 1e-300)[:, None]
                ref = NB[tri[used[:, 0]]] + NB[tri[used[:, 1]]] + NB[tri[used[:, 2]]]
                row["flipped_out"] = int(((n_img * ref).sum(1) < 0).sum())
                folds = f"flipped in A_on_B {row['flipped_out']}"
            else:
                folds = "fold test n/a (B's faces not consistently oriented as given)"
            kept = (f" ({removed} vertices removed by the repairs: of the rest "
                    f"{100 * row['within_005'] * len(V) / (len(V) - removed):5.1f} %)") if removed else ""
            acc = (f"within 0.01 {100 * row['within_001']:5.1f} %  0.05 {100 * row['within_005']:5.1f} %{kept}  "
                   f"{folds}")
        else:
            acc = f"({len(C)} rows for {len(V)} input vertices: repaired A, not scored)"
        rows.append(row)
        print(f"{name:<34} {mode:<8} matched {100 * row['matched']:5.1f} % {dt:6.2f} s  "
              f"min det {row['min_det']:.3g}  {acc}")
        break

json.dump(rows, open(os.path.join(root, "sweep_match.json"), "w"), indent=1)
print(f"\n{len(rows)} meshes matched onto their moved copies; "
      f"{len(bad)} runs ended otherwise than matched-or-refused {bad}; outputs in {root}")
sys.exit(1 if bad else 0)
