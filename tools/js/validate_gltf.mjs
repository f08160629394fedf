// Validates GLB files with the Khronos glTF validator; prints one JSON line per file
// ({"file", "errors", "warnings", "messages": [first error codes]}) and exits 1 if any
// file has errors. Usage: node validate_gltf.mjs FILE.glb [...]
import { readFileSync } from "node:fs";
import validator from "gltf-validator";

let failed = false;
for (const file of process.argv.slice(2)) {
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), { maxIssues: 50 });
  const errors = report.issues.numErrors;
  const messages = report.issues.messages.filter((m) => m.severity === 0).slice(0, 5).map((m) => `${m.code} ${m.pointer ?? ""}: ${m.message}`);
  console.log(JSON.stringify({ file, errors, warnings: report.issues.numWarnings, messages }));
  if (errors > 0) failed = true;
}
process.exit(failed ? 1 : 0);
