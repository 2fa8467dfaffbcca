#!/usr/bin/env python3
"""Are two builds' outputs the same? Records a fingerprint of every default output of
`surfmap match` on the referee's pairs (without input and with their landmarks) and of
`surfmap flatten` on the shared meshes, then compares two records file by file.

    python3 scripts/same_outputs.py record --surfmap target/release/surfmap --out /tmp/before \
        --pairs /tmp/pairs7,/tmp/flame7
    python3 scripts/same_outputs.py compare /tmp/before /tmp/after

A fingerprint is the SHA-256 of each output file: `correspondence.npy`, `A_on_B.obj`,
`deformation.npy` and `match.json` of a match folder; the OBJ and the report of a
flattening (an input it refuses: the error it prints). Reports are hashed without their
timings (every key holding `seconds` or `time`), with their numbers rounded to 10
significant digits (parallel sums' last bits vary from run to run), and without the keys
given with `--ignore` (a field a change adds on purpose, e.g. `--ignore confidence`). Needs only the
standard library; the pairs come from ../shared/match_eval/make_pairs.py and
scripts/flame_pairs.py.
"""
import argparse
import hashlib
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "..", "shared", "data")
MATCH_FILES = ("correspondence.npy", "A_on_B.obj", "deformation.npy")


def timeless(value, ignore):
    """The JSON value without timing keys (and the ignored ones), recursively, numbers
    rounded to 10 significant digits: the energies a match reports are sums taken in
    parallel, which differ in their last bits from run to run of one build (measured:
    relative 3e-16), while the outputs themselves are bit for bit the same."""
    if isinstance(value, dict):
        return {k: timeless(v, ignore) for k, v in value.items()
                if "seconds" not in k and "time" not in k and k not in ignore}
    if isinstance(value, list):
        return [timeless(v, ignore) for v in value]
    if isinstance(value, float):
        return float(f"{value:.10g}")
    return value


def digest(data):
    return hashlib.sha256(data).hexdigest()


def json_digest(path, ignore):
    """The digest of a report as `timeless` leaves it."""
    with open(path) as f:
        value = timeless(json.load(f), ignore)
    return digest(json.dumps(value, sort_keys=True).encode())


def record_matches(args, ignore):
    out = {}
    for pairs in args.pairs.split(","):
        index = json.load(open(os.path.join(pairs, "index.json")))
        for e in index:
            d = os.path.join(pairs, e["dir"])
            for mode, extra in (("none", []), ("landmarks", ["--landmarks", os.path.join(d, "landmarks.json")])):
                key = f"match/{os.path.basename(pairs.rstrip('/'))}/{e['dir']}/{mode}"
                folder = os.path.join(args.out, key)
                cmd = [args.surfmap, "match", os.path.join(d, "A.obj"), os.path.join(d, "B.obj"),
                       "-o", folder, "-q"] + extra
                r = subprocess.run(cmd, capture_output=True, text=True)
                if r.returncode != 0:
                    out[key] = {"error": r.stderr.strip()}
                else:
                    out[key] = {name: digest(open(os.path.join(folder, name), "rb").read()) for name in MATCH_FILES}
                    out[key]["match.json"] = json_digest(os.path.join(folder, "match.json"), ignore)
                print(key, "error" if "error" in out[key] else "ok", flush=True)
    return out


def record_flattenings(args, ignore):
    manifest = json.load(open(os.path.join(DATA, "manifest.json")))
    out = {}
    for f in manifest["files"]:
        name = f["file"]
        if args.skip_large and f.get("F", 0) > 120_000:
            continue
        key = f"flatten/{name}"
        folder = os.path.join(args.out, "flatten")
        os.makedirs(folder, exist_ok=True)
        stem = name.replace("/", "_")
        obj, report = os.path.join(folder, stem + ".obj"), os.path.join(folder, stem + ".json")
        for p in (obj, report):
            if os.path.exists(p):
                os.remove(p)
        r = subprocess.run([args.surfmap, "flatten", os.path.join(DATA, name), "-o", obj, "--report", report, "-q"],
                           capture_output=True, text=True)
        if r.returncode != 0:
            out[key] = {"error": digest(r.stderr.encode()), "message": r.stderr.strip()[:300]}
        else:
            out[key] = {"obj": digest(open(obj, "rb").read()), "report": json_digest(report, ignore)}
        print(key, "refused" if "error" in out[key] else "ok", flush=True)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    rec = sub.add_parser("record")
    rec.add_argument("--surfmap", default=os.path.join(HERE, "..", "target", "release", "surfmap"))
    rec.add_argument("--out", required=True)
    rec.add_argument("--pairs", default="", help="comma-separated folders of referee pairs (index.json)")
    rec.add_argument("--no-flatten", action="store_true")
    rec.add_argument("--skip-large", action="store_true", help="leave out meshes of more than 120k faces")
    rec.add_argument("--ignore", default="", help="comma-separated report keys left out of the fingerprint")
    cmp = sub.add_parser("compare")
    cmp.add_argument("before")
    cmp.add_argument("after")
    args = ap.parse_args()
    if args.command == "record":
        ignore = set(filter(None, args.ignore.split(",")))
        os.makedirs(args.out, exist_ok=True)
        fingerprints = {}
        if args.pairs:
            fingerprints.update(record_matches(args, ignore))
        if not args.no_flatten:
            fingerprints.update(record_flattenings(args, ignore))
        with open(os.path.join(args.out, "fingerprints.json"), "w") as f:
            json.dump(fingerprints, f, indent=1, sort_keys=True)
        print(f"{len(fingerprints)} outputs recorded in {args.out}/fingerprints.json")
        return
    before = json.load(open(os.path.join(args.before, "fingerprints.json")))
    after = json.load(open(os.path.join(args.after, "fingerprints.json")))
    differ = only = 0
    for key in sorted(set(before) | set(after)):
        b, a = before.get(key), after.get(key)
        if b == a:
            continue
        if b is None or a is None:
            only += 1
            print(f"{key}: only in {'after' if b is None else 'before'}")
            continue
        differ += 1
        files = sorted(k for k in set(b) | set(a) if b.get(k) != a.get(k))
        print(f"{key}: differs in {', '.join(files)}")
    same = len(set(before) & set(after)) - differ
    print(f"{same} outputs identical, {differ} differ, {only} recorded on one side only")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
