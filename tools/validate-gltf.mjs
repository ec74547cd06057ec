// Validates a .gltf file with the Khronos glTF validator and prints the
// report's issue counts as JSON; exit code 1 when it reports errors.
import { readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import validator from 'gltf-validator';

const path = process.argv[2];
const dir = dirname(path);
const report = await validator.validateBytes(new Uint8Array(readFileSync(path)), {
  uri: path,
  maxIssues: 0,
  externalResourceFunction: (uri) =>
    Promise.resolve(new Uint8Array(readFileSync(join(dir, decodeURIComponent(uri))))),
});
const errors = report.issues.messages.filter((m) => m.severity === 0);
console.log(JSON.stringify({
  file: path,
  errors: report.issues.numErrors,
  warnings: report.issues.numWarnings,
  infos: report.issues.numInfos,
  first_errors: errors.slice(0, 5),
}));
process.exit(report.issues.numErrors > 0 ? 1 : 0);
