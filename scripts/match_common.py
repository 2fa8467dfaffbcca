"""What the matching scripts (bench_match.py, match_noise.py) share: the referee's folder on
the import path (../shared/match_eval, for `score`), the options every one of them takes
(--pairs, --surfmap, --only) and the selection of pairs from the pairs' index.json."""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "shared", "match_eval"))


def add_common_arguments(ap):
    ap.add_argument("--pairs", required=True)
    ap.add_argument("--surfmap", default=os.path.join(HERE, "..", "target", "release", "surfmap"))
    ap.add_argument("--only", default=None, help="comma-separated substrings of pair names")


def selected_pairs(args):
    """Every entry of the pairs' index.json whose name contains one of --only (all without
    it), with the pair's folder."""
    index = json.load(open(os.path.join(args.pairs, "index.json")))
    for e in index:
        if args.only and not any(o in e["dir"] for o in args.only.split(",")):
            continue
        yield e, os.path.join(args.pairs, e["dir"])
