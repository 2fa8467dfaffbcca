#!/usr/bin/env bash
# Tests the pages `surfmap view` writes in a real browser: headless Chromium (Debian's
# `chromium`, SwiftShader WebGL) driven by puppeteer-core (npm, pinned) through
# scripts/view_test.mjs. Generates its inputs (the closed-form ones of the apps_inputs
# example, and a flattening, a match, a rig and a batch made with the CLI), writes a page
# of each kind and checks them (see view_test.mjs).
#
#   scripts/view_test.sh                      # the test
#   scripts/view_test.sh --screenshots docs/  # also a screenshot of each page kind
#
# Needs node, npm and cargo; puppeteer-core is installed once into $VIEW_TEST_DIR
# (default target/view-test), Chromium is $CHROMIUM (default /usr/bin/chromium; Debian:
# apt-get install chromium). Exit status 1 if a check fails.
set -euo pipefail
cd "$(dirname "$0")/.."
PUPPETEER_VERSION=24.43.1
export VIEW_TEST_DIR="${VIEW_TEST_DIR:-$PWD/target/view-test}"
export CHROMIUM="${CHROMIUM:-/usr/bin/chromium}"

if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  echo "view_test: node and npm are needed (apt-get install nodejs npm)" >&2
  exit 1
fi
if [ ! -x "$CHROMIUM" ]; then
  echo "view_test: no Chromium at $CHROMIUM (apt-get install chromium, or set CHROMIUM)" >&2
  exit 1
fi
if [ ! -f "$VIEW_TEST_DIR/node_modules/puppeteer-core/package.json" ] ||
  ! grep -q "\"version\": \"$PUPPETEER_VERSION\"" "$VIEW_TEST_DIR/node_modules/puppeteer-core/package.json"; then
  mkdir -p "$VIEW_TEST_DIR"
  [ -f "$VIEW_TEST_DIR/package.json" ] || echo '{"private": true}' > "$VIEW_TEST_DIR/package.json"
  # No browser download: puppeteer-core drives the system's Chromium.
  if ! PUPPETEER_SKIP_DOWNLOAD=1 npm install --prefix "$VIEW_TEST_DIR" --no-audit --no-fund --silent \
    "puppeteer-core@$PUPPETEER_VERSION"; then
    echo "view_test: could not install puppeteer-core@$PUPPETEER_VERSION with npm" >&2
    exit 1
  fi
fi

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cargo run --release --quiet -p surfmap --example apps_inputs -- "$work/in" >/dev/null
cargo build --release --quiet -p surfmap-cli
surfmap="$(realpath "${CARGO_TARGET_DIR:-target}/release/surfmap")"
(
  cd "$work"
  # A flattening cut along a slit (B is a 47 × 47 grid: 24 edges of row 24 from the
  # border inwards), with its report (found beside the mesh as flat.json).
  for c in $(seq 0 23); do echo "$((24 * 48 + c)) $((24 * 48 + c + 1))"; done > slit.txt
  "$surfmap" flatten in/b.obj -o flat.obj --report flat.json --cut-along slit.txt -q
  "$surfmap" view flat.obj -o flat.html -q
  # The generated match (closed form; match.json names a.obj and b.obj) and one made
  # by the CLI, whose surfaces are given.
  "$surfmap" view in/match_ab -o match_generated.html -q
  "$surfmap" match in/a.obj in/b.obj -o match_cli -q
  "$surfmap" view match_cli --a in/a.obj --b in/b.obj -o match_cli.html -q
  # A rig with two named keys.
  "$surfmap" rig in/neutral.obj in/key1.obj in/key2.obj --match in/match_n1 --match in/match_12 \
    --chain --names wide,wider -o rig.glb -q
  "$surfmap" view rig.glb -o rig.html -q
  # A batch of two meshes and its table.
  "$surfmap" flatten in/a.obj in/b.obj -o batch/ -q
  "$surfmap" view batch -o batch.html -q
)
node scripts/view_test.mjs "$work" "$@"
