// Runs the Khronos glTF validator (npm gltf-validator, validateBytes) on glTF/GLB files and
// prints one JSON object per file on its own line:
//   {"file", "errors", "warnings", "infos", "hints", "messages": [{"code", "severity", "pointer"}]}
// severity: 0 error, 1 warning, 2 info, 3 hint. Used by tests/io/gltf_test.cpp.
// Usage: node gltf_validate.mjs <node_modules folder> <file>...
import { readFile } from 'node:fs/promises';
import { createRequire } from 'node:module';
import path from 'node:path';

const [nodeModules, ...files] = process.argv.slice(2);
if (!nodeModules || files.length === 0) {
  console.error('usage: node gltf_validate.mjs <node_modules folder> <file>...');
  process.exit(2);
}
const require = createRequire(path.join(path.resolve(nodeModules), 'noop.js'));
const validator = require('gltf-validator');

for (const file of files) {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,  // no cap
    // a file we write is self-contained: any external reference is a bug
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}`)),
  });
  const messages = report.issues.messages.map((m) => ({
    code: m.code, severity: m.severity, pointer: m.pointer ?? m.offset ?? null, message: m.message,
  }));
  console.log(JSON.stringify({
    file,
    errors: report.issues.numErrors,
    warnings: report.issues.numWarnings,
    infos: report.issues.numInfos,
    hints: report.issues.numHints,
    messages,
  }));
}
