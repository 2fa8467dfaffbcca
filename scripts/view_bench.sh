#!/usr/bin/env bash
# Page size and time to first frame of `surfmap view` on large inputs: a flattening of
# 150k triangles and a match of two 50k-triangle surfaces (generated height fields,
# flattened and matched by the CLI), each page loaded 5 times in headless Chromium
# (scripts/view_test.mjs --bench). Prints one line per page; docs/bench/viewer.md has
# the figures.
#
#   scripts/view_bench.sh
#
# Needs what scripts/view_test.sh needs (it installs puppeteer-core when missing).
set -euo pipefail
cd "$(dirname "$0")/.."
export VIEW_TEST_DIR="${VIEW_TEST_DIR:-$PWD/target/view-test}"
[ -f "$VIEW_TEST_DIR/node_modules/puppeteer-core/package.json" ] || {
  echo "view_bench: run scripts/view_test.sh once first (it installs puppeteer-core)" >&2
  exit 1
}
cargo build --release --quiet -p surfmap-cli
surfmap="$(realpath "${CARGO_TARGET_DIR:-target}/release/surfmap")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# A height field z = h(x, y) over [-1, 1]², n × n squares (2n² triangles), interior
# vertices jittered so that no two meshes share a vertex.
height_field() { # n seed bump out.obj
  python3 - "$@" <<'PY'
import math, random, sys
n, seed, bump, out = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
rng = random.Random(seed)
with open(out, "w") as f:
    for j in range(n + 1):
        for i in range(n + 1):
            x, y = -1 + 2 * i / n, -1 + 2 * j / n
            if 0 < i < n and 0 < j < n:
                x += 0.6 / n * (rng.random() - 0.5)
                y += 0.6 / n * (rng.random() - 0.5)
            z = bump * math.exp(-(x * x + 2 * y * y)) + 0.1 * math.sin(3 * x) * y
            f.write(f"v {x:.7f} {y:.7f} {z:.7f}\n")
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            b, c, d = a + 1, a + n + 2, a + n + 1
            f.write(f"f {a} {b} {c}\nf {a} {c} {d}\n")
PY
}
(
  cd "$work"
  height_field 274 1 0.5 big.obj        # 150,152 triangles
  height_field 159 2 0.4 a.obj          # 50,562 triangles
  height_field 159 3 0.5 b.obj
  "$surfmap" flatten big.obj -o big_flat.obj --report big_flat.json -q
  "$surfmap" view big_flat.obj -o flattening_150k.html -q
  "$surfmap" match a.obj b.obj -o match_ab -q
  "$surfmap" view match_ab --a a.obj --b b.obj -o match_50k.html -q
)
node scripts/view_test.mjs --bench "$work/flattening_150k.html" "$work/match_50k.html"
