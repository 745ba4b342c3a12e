// Validates glTF assets with the official Khronos glTF validator (npm package `gltf-validator`).
//
//   npm install --prefix /tmp/gv gltf-validator
//   node assets/validate.mjs                 # every .glb/.gltf in assets/
//   node assets/validate.mjs a.glb b.gltf    # the given files
//
// The package is looked up in the node_modules directory named by GLTF_VALIDATOR_DIR
// (default /tmp/gv/node_modules). Prints one summary line per file (plus its first few messages)
// and exits non-zero if any file has errors or cannot be validated.

import { createRequire } from 'node:module';
import { readFileSync, readdirSync, existsSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const MAX_SHOWN = 5;
const SEVERITY = ['error', 'warning', 'info', 'hint'];

const here = path.dirname(fileURLToPath(import.meta.url));
const modulesDir = path.resolve(process.env.GLTF_VALIDATOR_DIR || '/tmp/gv/node_modules');
const packageDir = path.join(modulesDir, 'gltf-validator');
if (!existsSync(packageDir)) {
  console.error(`gltf-validator not found in ${modulesDir}; install it with ` +
    `'npm install --prefix /tmp/gv gltf-validator' or set GLTF_VALIDATOR_DIR`);
  process.exit(2);
}
const require = createRequire(import.meta.url);
const validator = require(packageDir);

let files = process.argv.slice(2);
if (files.length === 0) {
  files = readdirSync(here)
    .filter((f) => /\.(glb|gltf)$/i.test(f))
    .sort()
    .map((f) => path.join(here, f));
}
if (files.length === 0) {
  console.error(`no .glb/.gltf files given or found in ${here}`);
  process.exit(2);
}

let failed = false;
for (const file of files) {
  let report;
  try {
    const bytes = new Uint8Array(readFileSync(file));
    report = await validator.validateBytes(bytes, {
      uri: path.basename(file),
      maxIssues: 0, // unlimited
      externalResourceFunction: (uri) =>
        new Promise((resolve, reject) => {
          try {
            const target = path.resolve(path.dirname(file), decodeURIComponent(uri));
            resolve(new Uint8Array(readFileSync(target)));
          } catch (e) {
            reject(String(e));
          }
        }),
    });
  } catch (e) {
    console.log(`${file}: FAILED to validate: ${e}`);
    failed = true;
    continue;
  }
  const issues = report.issues;
  const info = report.info || {};
  const status = issues.numErrors > 0 ? 'FAIL' : 'ok';
  console.log(
    `${file}: ${status} errors=${issues.numErrors} warnings=${issues.numWarnings} ` +
      `infos=${issues.numInfos} hints=${issues.numHints}` +
      // The validator counts each mesh once (instancing by several nodes is not multiplied in).
      (info.totalTriangleCount !== undefined ? ` meshTriangles=${info.totalTriangleCount}` : '') +
      (info.drawCallCount !== undefined ? ` drawCalls=${info.drawCallCount}` : ''),
  );
  for (const m of issues.messages.slice(0, MAX_SHOWN)) {
    const where = m.pointer ?? '';
    console.log(`  [${SEVERITY[m.severity] ?? m.severity}] ${m.code} ${where}: ${m.message}`);
  }
  if (issues.messages.length > MAX_SHOWN) {
    console.log(`  ... ${issues.messages.length - MAX_SHOWN} more`);
  }
  if (issues.numErrors > 0) failed = true;
}
process.exit(failed ? 1 : 0);
