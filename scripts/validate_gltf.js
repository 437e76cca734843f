// Runs the Khronos glTF validator (npm package gltf-validator) on glTF/GLB files and fails on any error.
// usage: node scripts/validate_gltf.js VALIDATOR_PREFIX FILE...
//   VALIDATOR_PREFIX: the directory `npm install --prefix` put gltf-validator in (scripts/strata.sh validate-gltf).
// Prints one summary line per file (errors, warnings, infos, hints and what the validator counted), then every
// error and warning with its JSON pointer. Exit status 1 when any file has an error, 2 on bad usage.
'use strict';
const fs = require('fs');
const path = require('path');

const [prefix, ...files] = process.argv.slice(2);
if (!prefix || files.length === 0) {
  console.error('usage: node validate_gltf.js VALIDATOR_PREFIX FILE...');
  process.exit(2);
}
const validator = require(path.resolve(prefix, 'node_modules', 'gltf-validator'));

async function main() {
  let failed = false;
  for (const file of files) {
    let report;
    try {
      report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
        uri: path.basename(file),
        maxIssues: 0,  // unlimited: every issue counts
        writeTimestamp: false,
      });
    } catch (e) {
      console.error(`${file}: the validator could not read it: ${e}`);
      failed = true;
      continue;
    }
    const i = report.issues;
    const info = report.info || {};
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} ` +
                `hints (validator ${report.validatorVersion}; ${info.totalVertexCount} vertices, ` +
                `${info.totalTriangleCount} triangles, ${info.animationCount} animation, skins: ${info.hasSkins}, max influences ${info.maxInfluences})`);
    for (const m of i.messages) {
      if (m.severity <= 1) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} at ${m.pointer}: ${m.message}`);
    }
    if (i.numErrors > 0) failed = true;
  }
  process.exit(failed ? 1 : 0);
}

main();
