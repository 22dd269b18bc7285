// Khronos' glTF validator on a .glb/.gltf file, run on demand (not part of CI):
//   npm install --prefix /tmp/gltf-tools gltf-validator
//   cd /tmp/gltf-tools && node /path/to/voxel-art/tools/validate-gltf.mjs FILE.glb [FILE …]
// Prints the counts of errors, warnings, infos and hints, and each error and warning; the exit status is 1
// when any file has an error. Packages are resolved from the current directory.
import { createRequire } from 'node:module';
import { readFileSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';

const require = createRequire(join(process.cwd(), 'package.json'));
const validator = require('gltf-validator');

let failed = false;
for (const file of process.argv.slice(2)) {
  const bytes = new Uint8Array(readFileSync(file));
  const report = await validator.validateBytes(bytes, {
    uri: file,
    maxIssues: 100,
    externalResourceFunction: (uri) =>
      Promise.resolve(new Uint8Array(readFileSync(resolve(dirname(file), decodeURIComponent(uri))))),
  });
  const { numErrors, numWarnings, numInfos, numHints, messages } = report.issues;
  console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos, ${numHints} hints`);
  for (const m of messages.filter((m) => m.severity <= 1)) {
    console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} at ${m.pointer}: ${m.message}`);
  }
  failed ||= numErrors > 0;
}
process.exit(failed ? 1 : 0);
