"""Benchmarks of the Python package (figures in BENCHMARKS.md; nothing is asserted).

overhead MESH… [--repeat N] [--rounds R]
    The cost of calling surfmap.flatten(V, F) from Python against the same work called
    from Rust (crates/surfmap-bench/examples/flatten_call.rs: surfmap::flatten, then the report) on a mesh
    in memory. R rounds alternate a Rust process (N calls) and N Python calls, so
    both see the same machine load; prints the median of each side per round, and the
    overhead of the median of medians and of the fastest calls (the least disturbed by
    other jobs on a shared machine). RAYON_NUM_THREADS=1 makes both sides single-threaded.

batch [MESH…] [--workers 1 2] [--rounds R] [--fill-holes]
    Throughput (meshes/s) of a batch: surfmap.flatten_many(paths, outdir, workers=W)
    and the command line's `surfmap flatten MESH… -o DIR/ --jobs W`, each round into a
    fresh folder; with the CPU seconds used and the cores that amounts to (CPU / wall:
    below W when other jobs hold the cores). Default meshes: the disc meshes at the top of the shared data folder.

Run from the repository root with the package installed (pip install ./crates/surfmap-py)
and the release binaries built:
    cargo build --release -p surfmap-cli && cargo build --release -p surfmap-bench --example flatten_call
    python crates/surfmap-py/examples/python_bench.py overhead ../shared/data/nefertiti_small.off
    python crates/surfmap-py/examples/python_bench.py batch --workers 1 2
    python crates/surfmap-py/examples/python_bench.py batch --fill-holes ../shared/data/faces/ict/ict_[!n]*.obj ../shared/data/faces/ict/ict_neutral.obj
"""

import argparse
import os
import pathlib
import resource
import statistics
import subprocess
import tempfile
import time

import surfmap

REPO = pathlib.Path(__file__).resolve().parents[3]
TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "release"
DATA = pathlib.Path(os.environ.get("SURFMAP_DATA", REPO.parent / "shared" / "data"))
DISCS = [
    "nefertiti_small.off",
    "three_peaks.off",
    "hemisphere.obj",
    "nefertiti.off",
    "spothead.obj",
    "maze.obj",
    "mannequin.off",
    "lionhead.off",
    "camelhead.off",
    "mannequin_devil.off",
    "cowhead.obj",
]


def rust_times(mesh, repeat):
    exe = TARGET / "examples" / "flatten_call"
    out = subprocess.run([str(exe), str(mesh), "--repeat", str(repeat)], capture_output=True, text=True, check=True)
    lines = dict(line.split(":", 1) for line in out.stdout.splitlines())
    return tuple([float(t) for t in lines[k].split()] for k in ("times", "flatten", "cpu"))


def python_times(V, F, repeat):
    """Wall and CPU seconds (all threads: time.process_time) of each call."""
    times, cpu = [], []
    for _ in range(repeat):
        clock, cpu_start = time.perf_counter(), time.process_time()
        surfmap.flatten(V, F)
        times.append(time.perf_counter() - clock)
        cpu.append(time.process_time() - cpu_start)
    return times, cpu


def overhead(args):
    print(
        f"{'mesh':<22} {'V':>5} {'F':>5} {'round':>5} {'rust_ms':>8} {'flatten_ms':>10} {'python_ms':>9} "
        f"{'wall':>7} {'rust_cpu_ms':>11} {'python_cpu_ms':>13} {'cpu':>7}"
    )
    for mesh in args.meshes:
        V, F = surfmap.read_mesh(mesh)
        surfmap.flatten(V, F)  # warm: first-call costs (imports, page faults) are not per-call costs
        wall, cpu, fastest = ([], []), ([], []), ([], [])
        for r in range(args.rounds):
            rust, solve, rust_cpu = rust_times(mesh, args.repeat)
            py, py_cpu = python_times(V, F, args.repeat)
            rm, pm = statistics.median(rust), statistics.median(py)
            rc, pc = statistics.median(rust_cpu), statistics.median(py_cpu)
            for pair, values in ((wall, (rm, pm)), (cpu, (rc, pc)), (fastest, (min(rust), min(py)))):
                pair[0].append(values[0])
                pair[1].append(values[1])
            print(
                f"{pathlib.Path(mesh).name:<22} {len(V):>5} {len(F):>5} {r:>5} {1e3 * rm:>8.3f} "
                f"{1e3 * statistics.median(solve):>10.3f} {1e3 * pm:>9.3f} {100 * (pm / rm - 1):>+6.1f}% "
                f"{1e3 * rc:>11.3f} {1e3 * pc:>13.3f} {100 * (pc / rc - 1):>+6.1f}%"
            )
        summary = []
        for label, (rust, py), pick in (
            ("wall, median of medians", wall, statistics.median),
            ("cpu, median of medians", cpu, statistics.median),
            ("fastest wall", fastest, min),
        ):
            r, p = pick(rust), pick(py)
            summary.append(f"{label}: rust {1e3 * r:.3f} ms, python {1e3 * p:.3f} ms ({100 * (p / r - 1):+.1f}%)")
        print(f"{pathlib.Path(mesh).name}: " + "; ".join(summary))


def cpu_seconds():
    """User + system CPU time of this process and its finished children (the CLI)."""
    me, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + children.ru_utime + children.ru_stime


def batch(args):
    paths = [str(p) for p in (args.meshes or [DATA / m for m in DISCS])]
    cli = str(TARGET / "surfmap")
    print(f"{len(paths)} meshes; rounds {args.rounds}")
    print(f"{'engine':<14} {'workers':>7} {'round':>5} {'seconds':>8} {'meshes/s':>9} {'cpu_s':>8} {'cores':>6}")
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            for w in args.workers:
                for engine in ("python", "cli"):
                    out = pathlib.Path(tmp) / f"{engine}-{w}-{r}"
                    clock, cpu = time.perf_counter(), cpu_seconds()
                    if engine == "python":
                        rows = surfmap.flatten_many(paths, out, workers=w, fill_holes=args.fill_holes)
                        failed = [row["input"] for row in rows if row["status"] != "ok"]
                    else:
                        flags = ["--fill-holes"] if args.fill_holes else []
                        p = subprocess.run([cli, "flatten", *paths, "-o", f"{out}/", "--jobs", str(w), "--quiet", *flags])
                        failed = [] if p.returncode == 0 else ["(see stderr)"]
                    seconds, used = time.perf_counter() - clock, cpu_seconds() - cpu
                    assert not failed, failed
                    results.setdefault((engine, w), []).append(seconds)
                    print(f"{engine:<14} {w:>7} {r:>5} {seconds:>8.2f} {len(paths) / seconds:>9.2f} {used:>8.2f} {used / seconds:>6.2f}")
    for (engine, w), s in sorted(results.items()):
        m = statistics.median(s)
        print(f"{engine} workers={w}: median {m:.2f} s, {len(paths) / m:.2f} meshes/s (best {len(paths) / min(s):.2f})")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="what", required=True)
    o = sub.add_parser("overhead")
    o.add_argument("meshes", nargs="+")
    o.add_argument("--repeat", type=int, default=21)
    o.add_argument("--rounds", type=int, default=5)
    b = sub.add_parser("batch")
    b.add_argument("meshes", nargs="*")
    b.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    b.add_argument("--rounds", type=int, default=3)
    b.add_argument("--fill-holes", action="store_true", help="fill_holes=True / --fill-holes for every mesh")
    args = p.parse_args()
    {"overhead": overhead, "batch": batch}[args.what](args)


if __name__ == "__main__":
    main()
