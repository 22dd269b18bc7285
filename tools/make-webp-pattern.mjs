// Makes the WebP test pattern (our own image): tests/data/webp-pattern.png and its lossy WebP twin
// webp-pattern-lossy.webp (libwebp through sharp, quality 75), which the EXT_texture_webp test compares.
//   npm install --prefix /tmp/gltf-tools sharp
//   cd /tmp/gltf-tools && node /path/to/voxel-art/tools/make-webp-pattern.mjs /path/to/voxel-art
// The pattern: 64 × 64, four colour quadrants with a soft gradient, a white disc and a dark stripe.
import { createRequire } from 'node:module';
import { join } from 'node:path';

const sharp = createRequire(join(process.cwd(), 'package.json'))('sharp');
const repo = process.argv[2] ?? '.';
const size = 64;
const rgb = Buffer.alloc(size * size * 3);
const quadrants = [[220, 60, 50], [60, 170, 80], [50, 90, 200], [230, 190, 40]];
for (let y = 0; y < size; y++) {
  for (let x = 0; x < size; x++) {
    const q = quadrants[(y < size / 2 ? 0 : 2) + (x < size / 2 ? 0 : 1)];
    const shade = 0.75 + 0.25 * (x + y) / (2 * size);
    let c = q.map((v) => Math.round(v * shade));
    if ((x - 40) ** 2 + (y - 24) ** 2 < 64) c = [250, 250, 250];
    if (Math.abs(x - y) < 2) c = [30, 30, 40];
    rgb.set(c, (y * size + x) * 3);
  }
}
const image = () => sharp(rgb, { raw: { width: size, height: size, channels: 3 } });
const dir = join(repo, 'crates', 'voxel-core', 'tests', 'data');
await image().png().toFile(join(dir, 'webp-pattern.png'));
await image().webp({ quality: 75 }).toFile(join(dir, 'webp-pattern-lossy.webp'));
console.log(`wrote ${dir}/webp-pattern.png and webp-pattern-lossy.webp`);
