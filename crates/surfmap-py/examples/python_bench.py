"""Benchmarks of the Python package (figures in BENCHMARKS.md; nothing is asserted).

overhead MESH… [--repeat N] [--rounds R]
    The cost of calling surfmap.flatten(V, F) from Python against the same work called
    from Rust (examples/flatten_call.rs: surfmap::flatten, then the report) on a mesh
    in memory. R rounds alternate a Rust process (N calls) and N Python calls, so
    both see the same machine load; prints the median of each side per round and the
    overhead of the median of medians.

batch [MESH…] [--workers 1 2] [--rounds R]
    Throughput (meshes/s) of a batch: surfmap.flatten_many(paths, outdir, workers=W)
    and the command line's `surfmap flatten MESH… -o DIR/ --jobs W`, each round into a
    fresh folder. Default meshes: the disc meshes at the top of the shared data folder.

Run from the repository root with the package installed (pip install ./crates/surfmap-py)
and the release binaries built:
    cargo build --release -p surfmap-cli -p surfmap-py --example flatten_call
    python crates/surfmap-py/examples/python_bench.py overhead ../shared/data/nefertiti_small.off
    python crates/surfmap-py/examples/python_bench.py batch --workers 1 2
"""

import argparse
import os
import pathlib
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
    return [float(t) for t in lines["times"].split()], [float(t) for t in lines["flatten"].split()]


def python_times(V, F, repeat):
    times = []
    for _ in range(repeat):
        clock = time.perf_counter()
        surfmap.flatten(V, F)
        times.append(time.perf_counter() - clock)
    return times


def overhead(args):
    print(f"{'mesh':<24} {'V':>6} {'F':>6} {'round':>5} {'rust_ms':>9} {'flatten_ms':>10} {'python_ms':>9} {'overhead':>8}")
    for mesh in args.meshes:
        V, F = surfmap.read_mesh(mesh)
        surfmap.flatten(V, F)  # warm: first-call costs (imports, page faults) are not per-call costs
        rust_medians, py_medians = [], []
        for r in range(args.rounds):
            rust, solve = rust_times(mesh, args.repeat)
            py = python_times(V, F, args.repeat)
            rm, sm, pm = statistics.median(rust), statistics.median(solve), statistics.median(py)
            rust_medians.append(rm)
            py_medians.append(pm)
            print(
                f"{pathlib.Path(mesh).name:<24} {len(V):>6} {len(F):>6} {r:>5} "
                f"{1e3 * rm:>9.3f} {1e3 * sm:>10.3f} {1e3 * pm:>9.3f} {100 * (pm / rm - 1):>7.1f}%"
            )
        rm, pm = statistics.median(rust_medians), statistics.median(py_medians)
        print(f"{pathlib.Path(mesh).name}: median of medians rust {1e3 * rm:.3f} ms, python {1e3 * pm:.3f} ms, overhead {100 * (pm / rm - 1):+.1f}%")


def batch(args):
    paths = [str(p) for p in (args.meshes or [DATA / m for m in DISCS])]
    cli = str(TARGET / "surfmap")
    print(f"{len(paths)} meshes; rounds {args.rounds}")
    print(f"{'engine':<14} {'workers':>7} {'round':>5} {'seconds':>8} {'meshes/s':>9}")
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            for w in args.workers:
                for engine in ("python", "cli"):
                    out = pathlib.Path(tmp) / f"{engine}-{w}-{r}"
                    clock = time.perf_counter()
                    if engine == "python":
                        rows = surfmap.flatten_many(paths, out, workers=w)
                        failed = [row["input"] for row in rows if row["status"] != "ok"]
                    else:
                        p = subprocess.run([cli, "flatten", *paths, "-o", f"{out}/", "--jobs", str(w), "--quiet"])
                        failed = [] if p.returncode == 0 else ["(see stderr)"]
                    seconds = time.perf_counter() - clock
                    assert not failed, failed
                    results.setdefault((engine, w), []).append(seconds)
                    print(f"{engine:<14} {w:>7} {r:>5} {seconds:>8.2f} {len(paths) / seconds:>9.2f}")
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
    args = p.parse_args()
    {"overhead": overhead, "batch": batch}[args.what](args)


if __name__ == "__main__":
    main()
