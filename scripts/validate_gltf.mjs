// Runs the Khronos glTF validator (npm package `gltf-validator`) on the files given and
// prints one line per file; exits 1 if any file has an error (or cannot be read), 0
// otherwise. Warnings, infos and hints are counted and listed, not fatal.
//
//   node scripts/validate_gltf.mjs FILE.glb...
//
// The package is looked up in GLTF_VALIDATOR_DIR/node_modules (see validate_gltf.sh).
import { readFileSync } from "node:fs";
import { createRequire } from "node:module";
import { basename, dirname, join, resolve } from "node:path";

const dir = process.env.GLTF_VALIDATOR_DIR;
const require = createRequire(dir ? join(resolve(dir), "package.json") : import.meta.url);
const validator = require("gltf-validator");

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error("usage: node validate_gltf.mjs FILE.glb...");
  process.exit(2);
}
let failed = 0;
for (const file of files) {
  let report;
  try {
    report = await validator.validateBytes(new Uint8Array(readFileSync(file)), {
      uri: basename(file),
      maxIssues: 100,
      externalResourceFunction: (uri) =>
        Promise.resolve(new Uint8Array(readFileSync(join(dirname(file), decodeURIComponent(uri))))),
    });
  } catch (e) {
    console.log(`${file}: cannot be validated: ${e}`);
    failed += 1;
    continue;
  }
  const n = report.issues;
  const info = report.info || {};
  console.log(
    `${file}: ${n.numErrors} errors, ${n.numWarnings} warnings, ${n.numInfos} infos, ${n.numHints} hints` +
      ` (validator ${report.validatorVersion}; ${info.totalVertexCount ?? "?"} vertices,` +
      ` ${info.totalTriangleCount ?? "?"} triangles, morph targets ${info.hasMorphTargets ? "yes" : "no"},` +
      ` textures ${info.hasTextures ? "yes" : "no"}, ${info.animationCount ?? "?"} animations)`,
  );
  for (const m of n.messages) {
    const severity = ["error", "warning", "info", "hint"][m.severity] ?? m.severity;
    console.log(`  ${severity} ${m.code} at ${m.pointer ?? m.offset ?? "?"}: ${m.message}`);
  }
  if (n.numErrors > 0) failed += 1;
}
if (failed > 0) {
  console.log(`${failed} of ${files.length} glTF files failed validation`);
  process.exit(1);
}
console.log(`${files.length} glTF files valid (0 errors)`);
