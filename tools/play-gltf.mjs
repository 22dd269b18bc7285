// three.js's GLTFLoader and AnimationMixer on an animated voxel export, run on demand (not part of CI):
//   npm install --prefix /tmp/gltf-tools three
//   cd /tmp/gltf-tools && node /path/to/voxel-art/tools/play-gltf.mjs FILE.glb [STEPS]
// A .glb only (Node cannot fetch a .gltf's .bin). Loads the file, plays its first animation and samples it
// at STEPS evenly spaced times over one loop (default: two samples per key), printing at each time which of
// the root's children is shown (scale ≠ 0).
// The exit status is 1 unless exactly one child shows at every sample and each child shows at some time.
import { readFileSync } from 'node:fs';
import { pathToFileURL } from 'node:url';
import { join } from 'node:path';

// The ES module build, the one GLTFLoader itself imports.
const three = join(process.cwd(), 'node_modules', 'three');
const THREE = await import(pathToFileURL(join(three, 'build/three.module.js')).href);
const { GLTFLoader } = await import(pathToFileURL(join(three, 'examples/jsm/loaders/GLTFLoader.js')).href);

const [file, stepsArg] = process.argv.slice(2);
const bytes = readFileSync(file);
const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
const gltf = await new GLTFLoader().parseAsync(buffer, '');
const clip = gltf.animations[0];
if (!clip) {
  console.log(`${file}: no animation`);
  process.exit(1);
}
const root = gltf.scene.children[0];
const frames = root.children;
const keys = clip.tracks[0].times.length;
const steps = Number(stepsArg ?? 2 * (keys - 1));
console.log(`${file}: clip "${clip.name}", ${clip.duration.toFixed(3)} s, ${clip.tracks.length} tracks, ${frames.length} frame nodes`);
const mixer = new THREE.AnimationMixer(gltf.scene);
mixer.clipAction(clip).play();
const seen = new Set();
let ok = true;
const shown = [];
for (let i = 0; i < steps; i++) {
  const t = (i * clip.duration) / steps;
  mixer.setTime(t);
  const visible = frames.filter((node) => node.scale.x !== 0).map((node) => node.name);
  visible.forEach((name) => seen.add(name));
  ok &&= visible.length === 1;
  shown.push(`${t.toFixed(3)}:${visible.join('+') || '-'}`);
}
console.log(shown.join(' '));
ok &&= seen.size === frames.length;
console.log(ok ? `ok: one frame shown at a time, all ${frames.length} in turn` : 'FAILED');
process.exit(ok ? 0 : 1);
