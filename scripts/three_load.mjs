// Loads glTF files with three.js's GLTFLoader (the loader of the three.js viewers) under
// node and prints what a viewer gets: meshes, morph target names, animation clips and
// their tracks. Exits 1 if a file does not load, or has morph targets without names or
// without an animation of their weights.
//
//   node scripts/three_load.mjs FILE.glb...
//
// Images are not decoded (node has no browser image API): textures load as empty
// placeholders through a GLTFLoader plugin; everything else is three.js's own code.
// The package is looked up in GLTF_VALIDATOR_DIR/node_modules (see validate_gltf.sh).
import { readFileSync } from "node:fs";
import { createRequire } from "node:module";
import { join, resolve } from "node:path";
import { pathToFileURL } from "node:url";

const dir = process.env.GLTF_VALIDATOR_DIR;
const require = createRequire(dir ? join(resolve(dir), "package.json") : import.meta.url);
const threeDir = join(require.resolve("three"), "..", "..");
const { Texture } = await import(pathToFileURL(join(threeDir, "build", "three.module.js")));
const { GLTFLoader } = await import(
  pathToFileURL(join(threeDir, "examples", "jsm", "loaders", "GLTFLoader.js"))
);

let failed = 0;
for (const file of process.argv.slice(2)) {
  const buf = readFileSync(file);
  const data = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
  const loader = new GLTFLoader();
  loader.register(() => ({ name: "placeholder_images", loadTexture: () => Promise.resolve(new Texture()) }));
  try {
    const gltf = await loader.parseAsync(data, "");
    const problems = [];
    const meshes = [];
    gltf.scene.traverse((o) => {
      if (!o.isMesh) return;
      const names = Object.keys(o.morphTargetDictionary ?? {});
      meshes.push(`${o.name}: ${o.geometry.attributes.position.count} vertices, targets [${names.join(", ")}]`);
      if ((o.morphTargetInfluences ?? []).length !== names.length) problems.push(`${o.name}: unnamed morph targets`);
      const animated = gltf.animations.some((c) =>
        c.tracks.some((t) => t.name.startsWith(`${o.name}.morphTargetInfluences`)),
      );
      if (names.length > 0 && !animated) problems.push(`${o.name}: no animation of its morph weights`);
    });
    const clips = gltf.animations.map((c) => `"${c.name}" ${c.duration} s, ${c.tracks.length} track(s)`);
    console.log(`${file}: three.js loads ${meshes.join("; ")}; clips ${clips.join("; ") || "none"}`);
    for (const p of problems) console.log(`  problem: ${p}`);
    if (problems.length > 0) failed += 1;
  } catch (e) {
    console.log(`${file}: three.js cannot load it: ${e}`);
    failed += 1;
  }
}
process.exit(failed > 0 ? 1 : 0);
