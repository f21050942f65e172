#!/usr/bin/env node
// Validates binary glTF files with the Khronos glTF Validator (npm package gltf-validator, installed globally by
// scripts/install_deps.sh): `node scripts/gltf_validate.js FILE.glb...`. Prints every issue the validator reports
// (errors, warnings, infos, hints) and exits
//   0  when no file has an error or a warning,
//   1  when one has (warnings fail too: vkmesh writes the files itself and has no reason to write anything a
//      viewer might mishandle; infos and hints, such as UNUSED_OBJECT, only inform),
//   2  on a usage or read error,
//   77 when the validator is not installed (the tests skip then; the automake/ctest convention for "skipped").
'use strict';
const fs = require('fs');
const path = require('path');
const { execSync } = require('child_process');

function loadValidator() {
  try {
    return require('gltf-validator');
  } catch (e) {
    // A global install is not on require's path unless NODE_PATH says so: look where npm puts global packages.
    try {
      const root = execSync('npm root -g', { encoding: 'utf8', stdio: ['ignore', 'pipe', 'ignore'] }).trim();
      return require(path.join(root, 'gltf-validator'));
    } catch (e2) {
      return null;
    }
  }
}

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: gltf_validate.js FILE.glb...');
  process.exit(2);
}
const validator = loadValidator();
if (!validator) {
  console.error('gltf-validator is not installed (npm install -g gltf-validator; scripts/install_deps.sh does it)');
  process.exit(77);
}

const severities = ['error', 'warning', 'info', 'hint'];
(async () => {
  let failed = false;
  for (const file of files) {
    let bytes;
    try {
      bytes = new Uint8Array(fs.readFileSync(file));
    } catch (e) {
      console.error(`${file}: cannot read: ${e.message}`);
      process.exit(2);
    }
    const report = await validator.validateBytes(bytes, {
      uri: path.basename(file),
      maxIssues: 0,   // all of them
      // Self-contained .glb files only: an external resource is an error of its own.
      externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri} not allowed`)),
    });
    const issues = report.issues;
    console.log(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ${issues.numInfos} infos, ` +
                `${issues.numHints} hints (glTF Validator ${report.validatorVersion})`);
    for (const m of issues.messages)
      console.log(`  ${severities[m.severity] || m.severity} ${m.code}: ${m.message}${m.pointer ? ' at ' + m.pointer : ''}`);
    if (issues.numErrors > 0 || issues.numWarnings > 0) failed = true;
  }
  process.exit(failed ? 1 : 0);
})().catch((e) => {
  console.error(`gltf_validate.js: ${e && e.stack ? e.stack : e}`);
  process.exit(2);
});
