"""Matching with a few of the referee's landmarks: for every pair of a pairs folder
(`../shared/match_eval/make_pairs.py`, `scripts/flame_pairs.py`), `surfmap match` with
subsets of its landmarks (the mouth corners; with the nose tip; with the right inner eye
corner too — those the pair has), scored by `../shared/match_eval/score.py`, for one or
more builds side by side. Prints one row per pair and subset, and the means.

    /opt/peers-venv/bin/python scripts/few_landmarks.py --pairs /tmp/surfmap_pairs \
        --surfmap new=target/release/surfmap --surfmap old=/path/to/old/surfmap --out /tmp/few
"""
import argparse, json, pathlib, subprocess, sys

SUBSETS = {
    "2": ("mouth_corner_l", "mouth_corner_r"),
    "3": ("nose_tip", "mouth_corner_l", "mouth_corner_r"),
    "4": ("nose_tip", "mouth_corner_l", "mouth_corner_r", "eye_inner_r"),
}
HERE = pathlib.Path(__file__).resolve().parent
SCORE = HERE.parent.parent / "shared" / "match_eval" / "score.py"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pairs", required=True, type=pathlib.Path)
    ap.add_argument("--surfmap", action="append", required=True, help="NAME=PATH of a surfmap binary")
    ap.add_argument("--out", required=True, type=pathlib.Path)
    args = ap.parse_args()
    builds = dict(s.split("=", 1) for s in args.surfmap)
    rows = []
    for pair in sorted(p.parent for p in args.pairs.glob("*/*/landmarks.json")):
        lm = json.loads((pair / "landmarks.json").read_text())
        name = f"{pair.parent.name}/{pair.name[:2]}"
        for subset, names in SUBSETS.items():
            keep = [i for i, n in enumerate(lm["names"]) if n in names]
            if not keep:
                continue
            out = args.out / pair.parent.name / pair.name / subset
            out.mkdir(parents=True, exist_ok=True)
            (out / "landmarks.json").write_text(
                json.dumps({k: [lm[k][i] for i in keep] for k in ("names", "A", "B")})
            )
            row = {"pair": name, "subset": subset, "given": len(keep)}
            for build, exe in builds.items():
                d = out / build
                run = subprocess.run(
                    [exe, "match", pair / "A.obj", pair / "B.obj", "-o", d, "-q", "--landmarks", out / "landmarks.json"],
                    capture_output=True, text=True,
                )
                if run.returncode != 0:
                    row[build] = float("nan")
                    print(f"{name} {subset} {build}: {run.stderr.strip()}", file=sys.stderr)
                    continue
                subprocess.run(
                    [sys.executable, SCORE, pair, d / "correspondence.npy", "--json", d / "score.json"],
                    capture_output=True, check=True,
                )
                row[build] = 100 * json.loads((d / "score.json").read_text())["pct_005"]
            rows.append(row)
            print(f"{name:14s} {subset} ({len(keep)} given) " + "  ".join(f"{b} {row[b]:6.2f}" for b in builds), flush=True)
    for subset in SUBSETS:
        sel = [r for r in rows if r["subset"] == subset]
        if sel:
            means = "  ".join(f"{b} {sum(r[b] for r in sel) / len(sel):6.2f} (worst {min(r[b] for r in sel):6.2f})" for b in builds)
            print(f"subset {subset}: {len(sel)} pairs, % within 0.05: {means}")


if __name__ == "__main__":
    main()
