#!/usr/bin/env python3
"""Accuracy and throughput of `surfmap register` on ICT faces whose truth is known
(docs/bench/register.md).

The template is `ict_neutral.obj`; the scans are the other ICT identities and
expressions (registered to it: vertex i ↔ vertex i), each isotropically remeshed (so its
connectivity tells nothing) and moved by a random rigid motion. The truth of template
vertex i on a scan is vertex i of the source file, moved by the same motion. Errors are
in % of the face width (the template's extent along x).

Three steps, each its own Python (the remesher lives in the match_eval venv, surfmap's
Python package in a venv with its wheel):

  # 1. the scans and their truths (pymeshlab, from ../shared/match_eval/make_pairs.py)
  /opt/peers-venv/bin/python scripts/register_eval.py prepare --out /tmp/regeval
  # 2. register them (the command line, --jobs 2), and the same through Dask
  surfmap register ICT/ict_neutral.obj /tmp/regeval/scans -o /tmp/regeval/cli --jobs 2 --keep-matches
  /tmp/regvenv/bin/python scripts/register_eval.py dask --out /tmp/regeval
  # 3. the errors, the models from the registrations and from the truth
  SURFMAP=target/release/surfmap /tmp/regvenv/bin/python scripts/register_eval.py score --out /tmp/regeval
"""

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ICT = os.path.join(REPO, "..", "shared", "data", "faces", "ict")
MATCH_EVAL = os.path.join(REPO, "..", "shared", "match_eval")
SOURCES = ["id000", "id001", "id002", "id003", "id004", "id005",
           "jawopen", "smile_l", "smile_r", "pucker", "blink_l", "browup_l"]


def read_obj(path):
    V, F = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                V.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                F.append([int(x.split("/")[0]) - 1 for x in line.split()[1:4]])
    return np.array(V), np.array(F, dtype=np.int64)


def write_obj(path, V, F):
    with open(path, "w") as f:
        np.savetxt(f, V, fmt="v %.9g %.9g %.9g")
        np.savetxt(f, F + 1, fmt="f %d %d %d")


def face_width():
    V, _ = read_obj(os.path.join(ICT, "ict_neutral.obj"))
    return float(V[:, 0].max() - V[:, 0].min())


def prepare(out, seed):
    sys.path.insert(0, MATCH_EVAL)
    from make_pairs import random_rigid, remesh  # noqa: E402  (the referee's own tools)
    from common import mean_edge_length  # noqa: E402

    rng = np.random.default_rng(seed)
    os.makedirs(os.path.join(out, "scans"), exist_ok=True)
    os.makedirs(os.path.join(out, "truth"), exist_ok=True)
    _, F0 = read_obj(os.path.join(ICT, "ict_neutral.obj"))
    for name in SOURCES:
        V0, F = read_obj(os.path.join(ICT, f"ict_{name}.obj"))
        assert np.array_equal(F, F0)
        VB, FB = remesh(V0, F, mean_edge_length(V0, F))
        S = np.sqrt(0.5 * np.linalg.norm(np.cross(V0[F[:, 1]] - V0[F[:, 0]], V0[F[:, 2]] - V0[F[:, 0]]), axis=1).sum())
        T = random_rigid(rng, S)
        move = lambda P: P @ T[:3, :3].T + T[:3, 3]  # noqa: E731
        write_obj(os.path.join(out, "scans", f"{name}.obj"), move(VB), FB)
        np.save(os.path.join(out, "truth", f"{name}.npy"), move(V0))
        print(f"{name}: {len(VB)} vertices (source {len(V0)})", flush=True)


def dask_run(out, workers):
    import surfmap
    import surfmap.distributed
    from dask.distributed import Client, LocalCluster

    template = os.path.join(ICT, "ict_neutral.obj")
    one_off = surfmap.distributed._check_register(template)
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=None, env={"RAYON_NUM_THREADS": "1"})
    with Client(cluster) as client:
        t0 = time.perf_counter()
        table = surfmap.distributed.register(template, os.path.join(out, "scans"), os.path.join(out, "dask"),
                                             client=client, keep_matches=True)
        seconds = time.perf_counter() - t0
    cluster.close()
    info = dict(scans=len(table), seconds=seconds, per_minute=60 * len(table) / seconds,
                template_one_off_seconds=one_off, workers=workers)
    with open(os.path.join(out, "dask_timing.json"), "w") as f:
        json.dump(info, f, indent=1)
    print(json.dumps(info))


def errors(run_dir, width):
    """Per scan: mean and p95 error (% of face width), all vertices and matched ones."""
    with open(os.path.join(run_dir, "summary.json")) as f:
        rows = json.load(f)
    out = []
    for r in rows:
        if r["status"] != "ok":
            out.append(dict(name=r["name"], status=r["status"], error=r["error"]))
            continue
        V, _ = read_obj(os.path.join(run_dir, "registered", f"{r['name']}.obj"))
        T = np.load(os.path.join(run_dir, "..", "truth", f"{r['name']}.npy"))
        e = 100 * np.linalg.norm(V - T, axis=1) / width
        row = dict(name=r["name"], verdict=r["verdict"], matched=r["matched_fraction"], seconds=r["seconds"],
                   mean=float(e.mean()), p95=float(np.percentile(e, 95)), max=float(e.max()))
        corr = os.path.join(run_dir, "matches", r["name"], "correspondence.npy")
        if os.path.exists(corr):
            m = np.load(corr)[:, 0] >= 0
            row.update(mean_matched=float(e[m].mean()), p95_matched=float(np.percentile(e[m], 95)),
                       mean_extended=float(e[~m].mean()) if (~m).any() else None)
        out.append(row)
    return out


def load_model(d):
    z = np.load(os.path.join(d, "model", "model.npz"))
    with open(os.path.join(d, "model", "model.json")) as f:
        return z["mean"], z["components"], z["variances"], json.load(f)


def compare_models(a, b, k):
    """Principal angles (degrees) between the first k modes of two models, after aligning
    b's mean onto a's (rotation), and both models' explained fractions."""
    ma, ca, _, ja = load_model(a)
    mb, cb, _, jb = load_model(b)
    A, B = ma - ma.mean(0), mb - mb.mean(0)
    U, _, Vt = np.linalg.svd(B.T @ A)
    R = U @ Vt  # B @ R ≈ A
    if np.linalg.det(R) < 0:
        U[:, -1] *= -1
        R = U @ Vt
    Qa = np.linalg.qr(ca[:k].reshape(k, -1).T)[0]
    Qb = np.linalg.qr((cb[:k] @ R).reshape(k, -1).T)[0]
    cos = np.clip(np.linalg.svd(Qa.T @ Qb, compute_uv=False), -1, 1)
    return dict(k=k, angles_deg=[float(x) for x in np.degrees(np.arccos(cos))],
                explained_registered=ja["explained"][:k], explained_truth=jb["explained"][:k],
                total_variance_registered=ja["total_variance"], total_variance_truth=jb["total_variance"],
                mode_cosines=[float(abs((ca[j] * (cb[j] @ R)).sum())) for j in range(k)],
                modes_90_95_99_registered=[ja["modes_90"], ja["modes_95"], ja["modes_99"]],
                modes_90_95_99_truth=[jb["modes_90"], jb["modes_95"], jb["modes_99"]],
                scans_registered=len(ja["scans"]), scans_truth=len(jb["scans"]))


def truth_folder(out, names):
    """A registration folder of the true positions (what a perfect registration gives)."""
    d = os.path.join(out, "truth_reg")
    os.makedirs(os.path.join(d, "registered"), exist_ok=True)
    _, F = read_obj(os.path.join(ICT, "ict_neutral.obj"))
    rows = []
    for n in names:
        p = os.path.join(d, "registered", f"{n}.obj")
        write_obj(p, np.load(os.path.join(out, "truth", f"{n}.npy")), F)
        rows.append(dict(name=n, input=n, status="ok", output=p, verdict="ok", reasons=None, matched_fraction=1.0,
                         extended=0, energy=0.0, seconds=0.0, error=None))
    with open(os.path.join(d, "summary.json"), "w") as f:
        json.dump(rows, f)
    return d


def score(out):
    width = face_width()
    result = dict(face_width_cm=width)
    for run in ("cli", "dask"):
        d = os.path.join(out, run)
        if os.path.exists(os.path.join(d, "summary.json")):
            rows = errors(d, width)
            ok = [r for r in rows if "mean" in r]
            result[run] = dict(rows=rows, mean_of_means=float(np.mean([r["mean"] for r in ok])),
                               mean_p95=float(np.mean([r["p95"] for r in ok])))
    surfmap = os.environ.get("SURFMAP", os.path.join(REPO, "target", "release", "surfmap"))
    cli = os.path.join(out, "cli")
    if os.path.exists(os.path.join(cli, "model", "model.npz")):
        with open(os.path.join(cli, "model", "model.json")) as f:
            names = json.load(f)["scans"]
        t = truth_folder(out, names)
        subprocess.run([surfmap, "register", "--model-only", t, "-q"], check=True)
        result["model"] = compare_models(cli, t, min(3, len(names) - 1))
    with open(os.path.join(out, "score.json"), "w") as f:
        json.dump(result, f, indent=1)
    print(json.dumps(result, indent=1))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("step", choices=["prepare", "dask", "score"])
    ap.add_argument("--out", default="/tmp/regeval")
    ap.add_argument("--seed", type=int, default=49)
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    {"prepare": lambda: prepare(a.out, a.seed), "dask": lambda: dask_run(a.out, a.workers),
     "score": lambda: score(a.out)}[a.step]()


if __name__ == "__main__":
    main()
