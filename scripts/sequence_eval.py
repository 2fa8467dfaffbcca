#!/usr/bin/env python3
"""Accuracy and jitter of `surfmap register --sequence` on a synthetic ICT sequence whose
truth is known (docs/bench/sequence.md).

The sequence: N frames blending the ICT neutral into an expression linearly
(frame k = (1 − k/(N−1))·neutral + k/(N−1)·expression, vertex by vertex: the ICT crops
are registered, vertex i ↔ vertex i), each frame isotropically remeshed on its own (so
its connectivity tells nothing, as a scanner's would not) and moved by a slowly turning
and drifting head motion (1.5° and 0.35 cm per frame). The truth of template vertex
i on frame k is vertex i of the blend, moved by frame k's motion.

  # 1. the frames and their truths (pymeshlab, from ../shared/match_eval/make_pairs.py)
  /opt/peers-venv/bin/python scripts/sequence_eval.py prepare --out /tmp/seqeval
  # 2. register them as a sequence, every frame from the template, then with the warm
  #    start (each frame from the previous one's registration), and score
  SURFMAP=$CARGO_TARGET_DIR/release/surfmap /opt/peers-venv/bin/python scripts/sequence_eval.py run --out /tmp/seqeval

Scores per frame: the error |registered_i − truth_i| (mean, p95, % of the face width);
the motion error |(y_k,i − y_k−1,i) − (t_k,i − t_k−1,i)| (how far each vertex's step
from the previous frame is from its true step); the jitter of surfmap's summary
(half the rigidly aligned second difference, recomputed here for both runs and for the
truth, whose jitter is the floor a perfect registration would show).
"""

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from register_eval import ICT, MATCH_EVAL, face_width, read_obj, write_obj  # noqa: E402


def motion(k):
    """Frame k's rigid motion: a turn about a tilted axis growing by 1.5° per frame and a
    drift of 0.35 cm per frame (ICT units are cm)."""
    axis = np.array([0.2, 1.0, 0.1])
    axis /= np.linalg.norm(axis)
    ang = np.deg2rad(1.5 * k)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    R = np.eye(3) + np.sin(ang) * K + (1 - np.cos(ang)) * K @ K
    t = np.array([0.3, -0.1, 0.15]) * k
    return lambda P: P @ R.T + t


def prepare(out, frames, expression):
    sys.path.insert(0, MATCH_EVAL)
    from make_pairs import remesh  # noqa: E402  (the referee's own tools)
    from common import mean_edge_length  # noqa: E402

    os.makedirs(os.path.join(out, "frames"), exist_ok=True)
    os.makedirs(os.path.join(out, "truth"), exist_ok=True)
    N0, F = read_obj(os.path.join(ICT, "ict_neutral.obj"))
    E0, F1 = read_obj(os.path.join(ICT, f"ict_{expression}.obj"))
    assert np.array_equal(F, F1)
    for k in range(frames):
        s = k / (frames - 1)
        V0 = (1 - s) * N0 + s * E0
        VB, FB = remesh(V0, F, mean_edge_length(V0, F))
        move = motion(k)
        name = f"frame{k:02d}"
        write_obj(os.path.join(out, "frames", f"{name}.obj"), move(VB), FB)
        np.save(os.path.join(out, "truth", f"{name}.npy"), move(V0))
        print(f"{name}: blend {s:.3f}, {len(VB)} vertices", flush=True)


def rigid_onto(a, b):
    """a carried onto b by the least-squares rigid motion (Kabsch)."""
    ca, cb = a.mean(0), b.mean(0)
    U, _, Vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.sign(np.linalg.det(U @ Vt))
    R = U @ np.diag([1, 1, d]) @ Vt
    return (a - ca) @ R + cb


def jitter(frames):
    """Per frame: mean and p95 of |y_k − ½(T(y_k−1) + T(y_k+1))| (None at the ends)."""
    out = []
    for k in range(len(frames)):
        if k == 0 or k == len(frames) - 1:
            out.append((None, None))
            continue
        mid = 0.5 * (rigid_onto(frames[k - 1], frames[k]) + rigid_onto(frames[k + 1], frames[k]))
        j = np.linalg.norm(frames[k] - mid, axis=1)
        out.append((float(j.mean()), float(np.percentile(j, 95))))
    return out


def score(out, run, width):
    with open(os.path.join(out, run, "summary.json")) as f:
        rows = json.load(f)
    Y = [read_obj(os.path.join(out, run, "registered", f"{r['name']}.obj"))[0] for r in rows]
    T = [np.load(os.path.join(out, "truth", f"{r['name']}.npy")) for r in rows]
    jit = jitter(Y)
    table = []
    for k, r in enumerate(rows):
        e = 100 * np.linalg.norm(Y[k] - T[k], axis=1) / width
        row = dict(name=r["name"], verdict=r["verdict"], seconds=r["seconds"], mean=float(e.mean()),
                   p95=float(np.percentile(e, 95)), started_from=r.get("started_from"))
        if k > 0:
            m = 100 * np.linalg.norm((Y[k] - Y[k - 1]) - (T[k] - T[k - 1]), axis=1) / width
            row.update(step_mean=float(m.mean()), step_p95=float(np.percentile(m, 95)))
        if jit[k][0] is not None:
            row.update(jitter_mean=100 * jit[k][0] / width, jitter_p95=100 * jit[k][1] / width)
            if r.get("jitter_mean") is not None:
                row.update(jitter_mean_surfmap=100 * r["jitter_mean"] / width)
        table.append(row)
    return table


def run(out):
    exe = os.environ.get("SURFMAP", "surfmap")
    template = os.path.join(ICT, "ict_neutral.obj")
    width = face_width()
    result = {}
    for name, extra in [("template", ["--sequence"]), ("warm", ["--sequence", "--warm-start"])]:
        cmd = [exe, "register", template, os.path.join(out, "frames"), "-o", os.path.join(out, name),
               "--jobs", "2", "--no-model", "-q"] + extra
        load = os.getloadavg()[0]
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True)
        seconds = time.perf_counter() - t0
        rows = score(out, name, width)
        result[name] = dict(command=" ".join(cmd), seconds=seconds, load_before=load, frames=rows)
    T = [np.load(os.path.join(out, "truth", f"frame{k:02d}.npy")) for k in range(len(rows))]
    result["truth_jitter"] = [None if m is None else 100 * m / width for m, _ in jitter(T)]
    with open(os.path.join(out, "scores.json"), "w") as f:
        json.dump(result, f, indent=1)
    fmt = lambda x: "-" if x is None else f"{x:.3f}"  # noqa: E731
    for name in ["template", "warm"]:
        r = result[name]
        print(f"## {name}: {r['seconds']:.1f} s (load {r['load_before']:.1f})")
        print("| frame | verdict | from | mean % | p95 % | step mean % | step p95 % | jitter mean % | jitter p95 % | truth jitter % |")
        for k, row in enumerate(r["frames"]):
            print(f"| {row['name']} | {row['verdict']} | {row.get('started_from') or 'template'} | {fmt(row['mean'])} | "
                  f"{fmt(row['p95'])} | {fmt(row.get('step_mean'))} | {fmt(row.get('step_p95'))} | "
                  f"{fmt(row.get('jitter_mean'))} | {fmt(row.get('jitter_p95'))} | {fmt(result['truth_jitter'][k])} |")
        frames = r["frames"]
        avg = lambda key: np.mean([f[key] for f in frames if f.get(key) is not None])  # noqa: E731
        print(f"mean over frames: error {avg('mean'):.3f} / p95 {avg('p95'):.3f}; step {avg('step_mean'):.3f} / "
              f"{avg('step_p95'):.3f}; jitter {avg('jitter_mean'):.3f} / {avg('jitter_p95'):.3f}")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("step", choices=["prepare", "run"])
    p.add_argument("--out", default="/tmp/seqeval")
    p.add_argument("--frames", type=int, default=8)
    p.add_argument("--expression", default="smile_l")
    a = p.parse_args()
    if a.step == "prepare":
        prepare(a.out, a.frames, a.expression)
    else:
        run(a.out)


if __name__ == "__main__":
    main()
