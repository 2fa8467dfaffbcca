#!/usr/bin/env bash
# Validates the glTF files surfmap writes with the Khronos glTF validator (npm package
# gltf-validator): zero errors required; then loads them with three.js's GLTFLoader (npm
# package three), which must find the named morph targets and their animation.
#
#   scripts/validate_gltf.sh            # generate inputs, write every kind of .glb, validate them
#   scripts/validate_gltf.sh FILE.glb…  # validate the given files
#
# Needs node and npm (the validator is installed once into $GLTF_VALIDATOR_DIR, default
# target/gltf-validator) and, without arguments, cargo. Exit status 1 if any file has an
# error.
set -euo pipefail
cd "$(dirname "$0")/.."
VERSION=2.0.0-dev.3.10
THREE_VERSION=0.181.0
export GLTF_VALIDATOR_DIR="${GLTF_VALIDATOR_DIR:-$PWD/target/gltf-validator}"

if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  echo "validate_gltf: node and npm are needed (apt-get install nodejs npm)" >&2
  exit 1
fi
if [ ! -f "$GLTF_VALIDATOR_DIR/node_modules/gltf-validator/package.json" ] ||
  [ ! -f "$GLTF_VALIDATOR_DIR/node_modules/three/package.json" ]; then
  mkdir -p "$GLTF_VALIDATOR_DIR"
  [ -f "$GLTF_VALIDATOR_DIR/package.json" ] || echo '{"private": true}' > "$GLTF_VALIDATOR_DIR/package.json"
  if ! npm install --prefix "$GLTF_VALIDATOR_DIR" --no-audit --no-fund --silent \
    "gltf-validator@$VERSION" "three@$THREE_VERSION"; then
    echo "validate_gltf: could not install gltf-validator@$VERSION and three@$THREE_VERSION with npm" >&2
    exit 1
  fi
fi

check() {
  node scripts/validate_gltf.mjs "$@"
  node scripts/three_load.mjs "$@"
}

if [ $# -gt 0 ]; then
  check "$@"
  exit 0
fi

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cargo run --release --quiet -p surfmap --example apps_inputs -- "$work" >/dev/null
cargo build --release --quiet -p surfmap-cli
surfmap="$(realpath "${CARGO_TARGET_DIR:-target}/release/surfmap")"
(
  cd "$work"
  # A partial match (harmonic extension over the unmatched band), no texture.
  "$surfmap" morph a.obj b.obj --match match_ab -o morph.glb -q
  # A textured scan with texture seams (vertices split per corner UV, PNG embedded).
  "$surfmap" morph scan.obj b.obj --match match_scan_b -o morph_textured.glb -q
  # A rig: two named keys, one through a chain of matches.
  "$surfmap" rig neutral.obj key1.obj key2.obj --match match_n1 --match match_12 \
    --chain --names wide,wider -o rig.glb -q
)
check "$work/morph.glb" "$work/morph_textured.glb" "$work/rig.glb"
