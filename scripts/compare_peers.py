#!/usr/bin/env python3
"""Compare surfmap's flattening with peer tools (libigl SLIM/LSCM/ARAP, CGAL) on the same meshes.

    scripts/compare_peers.py MESH... [--surfmap BIN] [--repeat N] [--json OUT]

For every mesh, in the same run:
  (a) the peers, through the shared harness `run_peers.py` (one subprocess per peer, its
      `--json` output and `--save-uv` OBJs), once per repeat;
  (b) the surfmap CLI, once per repeat and configuration:
        sd         surfmap flatten MESH -o OUT.obj --energy sd --report R.json
        conformal  surfmap flatten MESH -o OUT.obj --preset conformal --report R.json
        balanced   surfmap flatten MESH -o OUT.obj --preset balanced --report R.json
Every output (ours and the peers') is then read back from its OBJ (with `vt`) and scored by
the one referee, `distortion.py` (imported from the peers folder).

Times (medians over --repeat runs):
  proc_s    wall-clock of the whole process. For surfmap: measured here around the CLI call
            (start-up, mesh read, solve, OBJ and report write). For a peer: the worker
            process as timed by run_peers.py (interpreter start, imports, mesh read, method,
            UV write).
  method_s  the tool's own solve time: a peer's `method_s` from run_peers.py's JSON; for
            surfmap the report's `time_total`.

Energies (referee):
  SD        area-weighted mean of (s1^2+s2^2+s1^-2+s2^-2)/4 after the referee's area
            normalization (UV area scaled to the 3D area), ideal 1.
  SD*       the same at the best uniform UV scale: sqrt(a*b)/2, a, b = area-weighted means of
            s1^2+s2^2 and s1^-2+s2^-2. It equals the raw SD energy at any minimizer of the
            raw energy (which SLIM and `--energy sd` both minimize), and is scale-invariant.

Headline per mesh: our `--energy sd` SD vs igl_slim's SD (relative difference, target within
0.1%) and igl_slim's time / ours (target >= 20x), for proc_s and method_s.

The exit status is 0 unless the script itself fails (bad arguments, unreadable mesh, internal
error): a failing tool gives a 'failed: ...' row and a missed target is only reported.

Environment: PEERS_DIR (folder with run_peers.py and distortion.py; default
/work/shared/peers), PEERS_PYTHON (interpreter with numpy + libigl; default
/opt/peers-venv/bin/python, also used to re-run this script if the current python has no
numpy), CGAL_PARAM (CGAL driver; default /opt/peers-bin/cgal_param).
"""
from __future__ import annotations

import os
import sys

PEERS_PY = os.environ.get("PEERS_PYTHON", "/opt/peers-venv/bin/python")

try:
    import numpy as np
except ImportError:  # system python without numpy: re-run under the peers venv
    # (a venv's python is a symlink to the system one, so guard by an env flag, not the path)
    if os.path.exists(PEERS_PY) and not os.environ.get("COMPARE_PEERS_REEXEC"):
        os.environ["COMPARE_PEERS_REEXEC"] = "1"
        os.execv(PEERS_PY, [PEERS_PY, os.path.abspath(__file__)] + sys.argv[1:])
    sys.exit(f"compare_peers.py needs numpy; run it with {PEERS_PY} (set PEERS_PYTHON)")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

PEERS_DIR = os.environ.get("PEERS_DIR", "/work/shared/peers")
CGAL_DEFAULT = os.environ.get("CGAL_PARAM", "/opt/peers-bin/cgal_param")
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# surfmap configurations: name -> extra CLI flags
OURS = {
    "sd": ["--energy", "sd"],
    "conformal": ["--preset", "conformal"],
    "balanced": ["--preset", "balanced"],
}
SLIM = "igl_slim"
SD_TARGET_REL = 1e-3   # our SD within 0.1% of SLIM's
SPEED_TARGET = 20.0    # at least 20x faster than SLIM


def load_referee():
    sys.path.insert(0, PEERS_DIR)
    try:
        import distortion as referee
    except ImportError as e:
        sys.exit(f"cannot import the referee distortion.py from {PEERS_DIR}: {e} (set PEERS_DIR)")
    return referee


D = None  # the referee module, set in main()


# --------------------------------------------------------------------------- #
# Scoring (everything goes through the referee)
# --------------------------------------------------------------------------- #
def best_scale_sd(V, F, uv):
    """sqrt(a*b)/2 = min over c > 0 of the area-weighted mean of (c^2 a_t + b_t / c^2)/4,
    a_t = s1^2 + s2^2, b_t = s1^-2 + s2^-2 (referee's Jacobians and singular values)."""
    J, A = D.jacobians(V, F, uv)
    good = np.isfinite(A) & (A > D.DEGEN_3D_REL * float(np.mean(A)))
    s1, s2 = D.singular_values(J[good])
    w = A[good] / A[good].sum()
    with np.errstate(divide="ignore"):
        a = float(np.sum(w * (s1 ** 2 + s2 ** 2)))
        b = float(np.sum(w * (1.0 / s1 ** 2 + 1.0 / s2 ** 2)))
    return 0.5 * math.sqrt(a * b) if math.isfinite(b) else math.inf


def score_obj(path, n_faces_in):
    """Referee metrics of an OBJ with vt, scored on the mesh stored in that OBJ."""
    V, F, cuv = D.load_mesh(path)
    if cuv is None:
        raise ValueError(f"{path} has no vt on every corner")
    if not np.all(np.isfinite(cuv)):
        raise ValueError("non-finite UVs")
    r = D.distortion(V, F, cuv)
    r["sd_best_scale"] = best_scale_sd(V, F, cuv)
    if F.shape[0] != n_faces_in:
        r["note"] = f"output has {F.shape[0]} faces (input {n_faces_in})"
    return r


def median(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


def tail(text, n=300):
    lines = [ln.strip() for ln in (text or "").strip().splitlines() if ln.strip()]
    return " | ".join(lines[-3:])[-n:]


# --------------------------------------------------------------------------- #
# Runners
# --------------------------------------------------------------------------- #
class PeerRuns:
    """Repeated runs of run_peers.py for one mesh; `once()` is one repeat of all peers."""

    def __init__(self, mesh, peers, work, timeout, extra):
        self.mesh, self.peers, self.work, self.timeout, self.extra = mesh, peers, work, timeout, extra
        self.base = os.path.splitext(os.path.basename(mesh))[0]
        self.uvdir = os.path.join(work, "peers_uv")
        self.acc = {p: {"method": [], "proc": [], "info": None, "error": None} for p in peers}
        self.rep = 0

    def once(self):
        js = os.path.join(self.work, f"peers_rep{self.rep}.json")
        cmd = [PEERS_PY, os.path.join(PEERS_DIR, "run_peers.py"), self.mesh, "--peers", ",".join(self.peers),
               "--json", js, "--timeout", str(self.timeout), "--no-input-uv", "--columns", "brief"] + self.extra
        if self.rep == 0:
            cmd += ["--save-uv", self.uvdir]
        self.rep += 1
        p = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, CGAL_PARAM=CGAL_DEFAULT))
        if p.returncode != 0 or not os.path.exists(js):
            raise RuntimeError(f"run_peers.py failed (exit {p.returncode}): {tail(p.stderr or p.stdout)}")
        with open(js) as fh:
            saved = json.load(fh)
        if saved[0].get("error"):
            raise RuntimeError(f"run_peers.py could not load {self.mesh}: {saved[0]['error']}")
        for row in saved[0]["results"]:
            st = self.acc[row["peer"]]
            if row.get("error"):
                st["error"] = st["error"] or row["error"]
                continue
            st["method"].append(row.get("method_s"))
            st["proc"].append(row.get("process_s"))
            if st["info"] is None:
                st["info"] = row

    def rows(self):
        """One row per peer: median times, the UV OBJ saved by the first repeat."""
        rows = []
        for name in self.peers:
            st = self.acc[name]
            row = {"tool": name, "kind": "peer"}
            info = st["info"] or {}
            for k in ("version", "iterations", "init", "boundary"):
                if info.get(k) is not None:
                    row[k] = info[k]
            row["runs"] = len(st["proc"])
            row["proc_s"] = median(st["proc"])
            row["method_s"] = median(st["method"])
            if st["error"] and not st["proc"]:
                row["error"] = st["error"]
            else:
                if st["error"]:
                    row["note"] = f"some repeats failed: {st['error']}"
                row["uv_obj"] = os.path.join(self.uvdir, f"{self.base}__{name}.obj")
            rows.append(row)
        return rows


class OurRuns:
    """Repeated runs of `surfmap flatten` for one mesh; `once()` is one repeat of every configuration."""

    def __init__(self, binary, mesh, work, timeout, configs):
        self.binary, self.mesh, self.work, self.timeout = binary, mesh, work, timeout
        self.acc = {c: {"proc": [], "method": [], "report": None, "error": None, "stdout": ""} for c in configs}

    def paths(self, name):
        return (os.path.join(self.work, f"surfmap_{name}.obj"),
                os.path.join(self.work, f"surfmap_{name}.report.json"))

    def once(self):
        for name, st in self.acc.items():
            if st["error"]:
                continue                      # a configuration that failed once is not retried
            out, rep_path = self.paths(name)
            for f in (out, rep_path):
                if os.path.exists(f):
                    os.remove(f)
            cmd = [self.binary, "flatten", self.mesh, "-o", out, "--report", rep_path] + OURS[name]
            t0 = time.perf_counter()
            try:
                p = subprocess.run(cmd, capture_output=True, text=True, timeout=self.timeout)
            except subprocess.TimeoutExpired:
                st["error"] = f"timeout after {self.timeout:.0f} s"
                continue
            wall = time.perf_counter() - t0
            if p.returncode != 0:
                st["error"] = f"exit {p.returncode}: {tail(p.stderr or p.stdout)}"
                continue
            if not os.path.exists(out):
                st["error"] = f"wrote no {out}"
                continue
            st["proc"].append(wall)
            st["stdout"] = p.stdout.strip()[-500:]
            st["report"] = None
            if os.path.exists(rep_path):
                with open(rep_path) as fh:
                    st["report"] = json.load(fh)
                st["method"].append(_report_time(st["report"]))

    def rows(self):
        rows = []
        for name, st in self.acc.items():
            row = {"tool": f"surfmap {name}", "kind": "ours", "flags": OURS[name], "stdout": st["stdout"],
                   "runs": len(st["proc"]), "proc_s": median(st["proc"]), "method_s": median(st["method"])}
            if st["error"]:
                row["error"] = st["error"]
            report = st["report"]
            if report is not None and not st["error"]:
                row["report"] = {k: v for k, v in report.items() if k != "log"}
                for k in ("iterations", "converged", "flipped_triangles", "symmetric_dirichlet"):
                    if k in report:
                        row["self_" + k] = report[k]
                row["iterations"] = report.get("iterations")
            elif st["proc"] and not st["error"]:
                row["note"] = "no report written"
            if st["proc"] and not st["error"]:
                row["uv_obj"] = self.paths(name)[0]
            rows.append(row)
        return rows


def _report_time(report):
    """Seconds of the solve from surfmap's report (`time_total`, seconds; *_ms in ms)."""
    for k in ("time_total", "time_total_s"):
        v = report.get(k)
        if isinstance(v, (int, float)):
            return float(v)
        if isinstance(v, dict):             # e.g. {"secs":..,"nanos":..}
            if "secs" in v:
                return v["secs"] + v.get("nanos", 0) * 1e-9
    if isinstance(report.get("time_total_ms"), (int, float)):
        return report["time_total_ms"] / 1000.0
    timings = report.get("timings")
    if isinstance(timings, dict):
        return _report_time(timings)
    return None


# --------------------------------------------------------------------------- #
# Output
# --------------------------------------------------------------------------- #
COLS = [
    ("tool", "tool", "{}"),
    ("proc_s", "proc_s", "{:.3f}"),
    ("method_s", "method_s", "{:.4f}"),
    ("iterations", "iters", "{}"),
    ("flipped", "flips", "{:d}"),
    ("degenerate_uv", "deg", "{:d}"),
    ("sym_dirichlet_mean", "SD", "{:.6f}"),
    ("sd_best_scale", "SD*", "{:.6f}"),
    ("sym_dirichlet_max", "SD max", "{:.4g}"),
    ("conformal_mean", "s1/s2 mean", "{:.4f}"),
    ("conformal_max", "s1/s2 max", "{:.4g}"),
    ("log_area_mean_abs", "|log s1s2|", "{:.4f}"),
    ("area_min", "s1s2 min", "{:.3g}"),
    ("area_max", "s1s2 max", "{:.3g}"),
]


def fmt(v, spec):
    if v is None:
        return "-"
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    try:
        return spec.format(v)
    except (ValueError, TypeError):
        return str(v)


def table(rows):
    head = [h for _, h, _ in COLS]
    lines = []
    for r in rows:
        if r.get("error"):
            lines.append(("err", [fmt(r.get(k), f) for k, _, f in COLS[:3]] + ["failed: " + " ".join(
                str(r["error"]).split())]))
        else:
            lines.append(("ok", [fmt(r.get(k), f) for k, _, f in COLS]))
    w = [len(h) for h in head]
    for kind, cells in lines:
        n = len(cells) if kind == "ok" else 3
        w[:n] = [max(a, len(c)) for a, c in zip(w[:n], cells[:n])]
    out = ["  ".join(h.ljust(a) for h, a in zip(head, w)), "  ".join("-" * a for a in w)]
    for kind, cells in lines:
        if kind == "ok":
            out.append("  ".join(c.ljust(a) for c, a in zip(cells, w)).rstrip())
        else:
            out.append("  ".join(c.ljust(a) for c, a in zip(cells[:3], w[:3])) + "  " + cells[3])
    return "\n".join(out)


def headline(rows):
    by = {r["tool"]: r for r in rows}
    ours, slim = by.get("surfmap sd"), by.get(SLIM)
    h = {}
    if not ours or not slim or ours.get("error") or slim.get("error") \
            or "sym_dirichlet_mean" not in ours or "sym_dirichlet_mean" not in slim:
        why = "surfmap sd missing/failed" if not ours or ours.get("error") or "sym_dirichlet_mean" not in ours \
            else f"{SLIM} missing/failed"
        return {"available": False, "why": why}
    h["available"] = True
    for key, label in (("sym_dirichlet_mean", "sd"), ("sd_best_scale", "sd_best_scale")):
        a, b = ours[key], slim[key]
        h[f"{label}_ours"], h[f"{label}_slim"] = a, b
        h[f"{label}_rel_diff"] = (a - b) / b
        h[f"{label}_excess_ratio"] = (a - 1.0) / (b - 1.0) if b != 1.0 else None
    h["sd_within_target"] = abs(h["sd_rel_diff"]) <= SD_TARGET_REL
    h["flips_ours"], h["flips_slim"] = ours.get("flipped"), slim.get("flipped")
    for key in ("proc_s", "method_s"):
        a, b = ours.get(key), slim.get(key)
        h[f"speedup_{key}"] = (b / a) if a and b else None
    h["speed_target_met_proc"] = (h["speedup_proc_s"] or 0) >= SPEED_TARGET
    h["speed_target_met_method"] = (h["speedup_method_s"] or 0) >= SPEED_TARGET
    return h


def print_headline(h):
    if not h.get("available"):
        print(f"  headline: n/a ({h['why']})")
        return
    met = "met" if h["sd_within_target"] else "MISSED"
    print(f"  headline SD (referee):  ours {h['sd_ours']:.6f} vs SLIM {h['sd_slim']:.6f}: "
          f"rel diff {100 * h['sd_rel_diff']:+.4f}%  (target |.| <= {100 * SD_TARGET_REL:g}%: {met})"
          + (f"; excess (SD-1) ratio {h['sd_excess_ratio']:.4f}" if h["sd_excess_ratio"] is not None else ""))
    print(f"  headline SD* (best scale): ours {h['sd_best_scale_ours']:.6f} vs SLIM "
          f"{h['sd_best_scale_slim']:.6f}: rel diff {100 * h['sd_best_scale_rel_diff']:+.4f}%")
    for key, label in (("proc_s", "process"), ("method_s", "method")):
        s = h[f"speedup_{key}"]
        if s is None:
            print(f"  headline time ({label}): n/a")
        else:
            ok = "met" if s >= SPEED_TARGET else "MISSED"
            print(f"  headline time ({label}): SLIM/ours = {s:.2f}x  (target >= {SPEED_TARGET:g}x: {ok})")
    print(f"  flips: ours {h['flips_ours']}, SLIM {h['flips_slim']}")


def find_surfmap(arg):
    if arg:
        p = arg if os.path.sep in arg else shutil.which(arg) or arg
        if not (os.path.isfile(p) and os.access(p, os.X_OK)):
            sys.exit(f"--surfmap {arg}: not an executable file")
        return os.path.abspath(p)
    for cand in (os.path.join(REPO, "target", "release", "surfmap"), shutil.which("surfmap")):
        if cand and os.path.isfile(cand) and os.access(cand, os.X_OK):
            return cand
    return None


def main(argv):
    global D
    ap = argparse.ArgumentParser(description="Compare surfmap flatten with peer tools, scored by one referee.")
    ap.add_argument("meshes", nargs="+", metavar="MESH")
    ap.add_argument("--surfmap", help="surfmap binary (default: target/release/surfmap of this repo, "
                                      "else `surfmap` on PATH; without one only the peers run)")
    ap.add_argument("--repeat", type=int, default=1, help="runs per tool; times are medians (default 1)")
    ap.add_argument("--json", help="write all rows and headline ratios here")
    ap.add_argument("--peers", help="comma list of run_peers.py peers (default: igl_slim,igl_lscm,"
                                    "igl_arap, plus cgal_lscm,cgal_arap if the CGAL driver exists)")
    ap.add_argument("--ours", default=",".join(OURS), help=f"surfmap configurations (default {','.join(OURS)})")
    ap.add_argument("--timeout", type=float, default=600.0, help="per tool run, seconds (default 600)")
    ap.add_argument("--keep", help="keep all outputs (UV OBJs, reports, peers' JSON) under this folder")
    ap.add_argument("--peer-args", default="", help="extra arguments for run_peers.py, e.g. '--slim-tol 1e-9'")
    a = ap.parse_args(argv)
    if a.repeat < 1:
        ap.error("--repeat must be >= 1")
    configs = [c.strip() for c in a.ours.split(",") if c.strip()]
    bad = [c for c in configs if c not in OURS]
    if bad:
        ap.error(f"unknown --ours {bad}; choose from {list(OURS)}")
    for m in a.meshes:
        if not os.path.isfile(m):
            ap.error(f"no such mesh: {m}")
    D = load_referee()
    if a.peers:
        peers = [p.strip() for p in a.peers.split(",") if p.strip()]
    else:
        peers = ["igl_slim", "igl_lscm", "igl_arap"]
        if os.path.exists(CGAL_DEFAULT):
            peers += ["cgal_lscm", "cgal_arap"]
    binary = find_surfmap(a.surfmap)
    print(f"peers: {','.join(peers)} (python {PEERS_PY}, CGAL driver "
          f"{CGAL_DEFAULT if os.path.exists(CGAL_DEFAULT) else 'absent'})")
    print(f"surfmap: {binary or 'not found: only the peers run'}; repeat {a.repeat} (median times)")

    results = []
    for mesh in a.meshes:
        mesh = os.path.abspath(mesh)
        V, F, _ = D.load_mesh(mesh)
        info = D.mesh_info(V, F)
        print(f"\n=== {mesh}")
        print(f"    {info['n_vertices']} vertices, {info['n_faces']} faces, boundary loops "
              f"{info['boundary_loops']}, disc {'yes' if info['is_disc'] else 'NO'}")
        base = os.path.splitext(os.path.basename(mesh))[0]
        if a.keep:
            work = os.path.abspath(os.path.join(a.keep, base))
            os.makedirs(work, exist_ok=True)
            ctx = None
        else:
            ctx = tempfile.TemporaryDirectory(prefix=f"compare_{base}_")
            work = ctx.name
        try:
            # ours and the peers alternate, repeat by repeat, so that load from other processes
            # on the machine affects both sides alike
            pr = PeerRuns(mesh, peers, work, a.timeout, a.peer_args.split())
            ours = OurRuns(binary, mesh, work, a.timeout, configs) if binary else None
            for rep in range(a.repeat):
                print(f"    repeat {rep + 1}/{a.repeat}: peers ...", file=sys.stderr, flush=True)
                pr.once()
                if ours:
                    print(f"    repeat {rep + 1}/{a.repeat}: surfmap ...", file=sys.stderr, flush=True)
                    ours.once()
            rows = (ours.rows() if ours else []) + pr.rows()
            for r in rows:
                if r.get("uv_obj") and not r.get("error"):
                    try:
                        r.update(score_obj(r["uv_obj"], info["n_faces"]))
                    except Exception as e:
                        r["error"] = f"scoring failed: {type(e).__name__}: {e}"
                if not a.keep:
                    r.pop("uv_obj", None)
        finally:
            if ctx:
                ctx.cleanup()
        print(table(rows))
        for r in rows:
            extra = []
            if r.get("note"):
                extra.append(r["note"])
            if r["kind"] == "ours" and not r.get("error"):
                if "self_flipped_triangles" in r and r["self_flipped_triangles"] != r.get("flipped"):
                    extra.append(f"self-reported flips {r['self_flipped_triangles']} != referee {r.get('flipped')}")
                if "self_converged" in r:
                    extra.append("converged" if r["self_converged"] else "NOT converged (self-reported)")
            if r["tool"] == SLIM and r.get("init"):
                extra.append(f"init {r['init']}")
            if extra:
                print(f"    {r['tool']}: " + "; ".join(extra))
        h = headline(rows)
        print_headline(h)
        results.append({"mesh": mesh, "info": info, "rows": rows, "headline": h})
        sys.stdout.flush()

    if len(results) > 1:
        print("\n=== summary (surfmap sd vs igl_slim)")
        print(f"{'mesh':24s} {'SD rel diff':>12s} {'speedup proc':>13s} {'speedup method':>15s}  flips ours/slim")
        for res in results:
            h = res["headline"]
            name = os.path.basename(res["mesh"])
            if not h.get("available"):
                print(f"{name:24s} n/a ({h['why']})")
                continue
            sp = h["speedup_proc_s"]
            sm = h["speedup_method_s"]
            print(f"{name:24s} {100 * h['sd_rel_diff']:+11.4f}% {fmt(sp, '{:.2f}x'):>13s} "
                  f"{fmt(sm, '{:.2f}x'):>15s}  {h['flips_ours']}/{h['flips_slim']}")
    if a.json:
        tmp = a.json + ".tmp"
        with open(tmp, "w") as fh:
            json.dump({"repeat": a.repeat, "surfmap": binary, "peers": peers, "meshes": results},
                      fh, indent=1, default=float)
        os.replace(tmp, a.json)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv[1:]))
    except KeyboardInterrupt:
        sys.exit(130)
