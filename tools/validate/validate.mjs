// Validates cliffmap's exports and prints one JSON summary on stdout.
//
//   node validate.mjs [--max-messages N] PATH...
//
// PATH is a glTF file (.glb, .gltf), a tileset .json file or a directory. A directory
// contributes every glTF file under it and, as entry points, every `*tileset*.json` under it
// (the default pattern of CesiumGS/3d-tiles-validator). From a tileset, external tilesets
// (content URIs ending in .json) are followed and every referenced glTF file is validated.
//
// - glTF: the Khronos glTF validator (npm `gltf-validator`, `validateBytes`), all
//   severities counted (0 error, 1 warning, 2 info, 3 hint).
// - Tileset JSON: the official 3D Tiles 1.1 JSON schemas (schema/, from CesiumGS/3d-tiles,
//   CC BY 4.0) with Ajv (JSON Schema 2020-12), plus checks the schema cannot express, named
//   like CesiumGS/3d-tiles-validator's issues where it has one: the content files exist,
//   the root has `refine`, refine is ADD or REPLACE, a child's geometricError is at most
//   its parent's, asset.version is known, no external tileset cycle; a glTF file under a
//   given directory that no tileset references is a warning (UNREFERENCED_CONTENT).
//   Implicit tiling and other content types are not validated (an info says so).
//
// Output: {"tools": {...}, "files": [{"file", "kind", "numErrors", "numWarnings",
// "numInfos", "numHints", "issues": {CODE: {"severity", "count"}}, "messages": [first N]}],
// "totals": {"gltf", "tilesets", "numErrors", "numWarnings", "numInfos", "numHints"}}.
// Exit status: 0 without errors, 1 with errors, 2 when a path holds nothing to validate or
// on bad usage.
import { existsSync, readFileSync, readdirSync, statSync } from "node:fs";
import { createRequire } from "node:module";
import path from "node:path";
import { fileURLToPath } from "node:url";
import Ajv2020 from "ajv/dist/2020.js";
import gltfValidator from "gltf-validator";

const here = path.dirname(fileURLToPath(import.meta.url));
const require = createRequire(import.meta.url);
const SEVERITY = ["numErrors", "numWarnings", "numInfos", "numHints"];
const [ERROR, WARNING, INFO] = [0, 1, 2];

// ---- arguments
let maxMessages = 10;
const inputs = [];
const argv = process.argv.slice(2);
for (let i = 0; i < argv.length; i++) {
  if (argv[i] === "--max-messages") maxMessages = Number(argv[++i]);
  else if (argv[i].startsWith("--")) usage(`unknown option ${argv[i]}`);
  else inputs.push(argv[i]);
}
if (inputs.length === 0 || !Number.isInteger(maxMessages) || maxMessages < 0) usage("");

function usage(why) {
  if (why) console.error(why);
  console.error("usage: node validate.mjs [--max-messages N] FILE.glb|FILE.gltf|TILESET.json|DIR ...");
  process.exit(2);
}

// ---- the 3D Tiles schemas: every file under schema/ gets an absolute $id from its path, so
// the relative $refs between them (./common/..., ../Schema/...) resolve as in the spec.
const SCHEMA_BASE = "https://cliffmap.invalid/3d-tiles/schema/";
// strictSchema: an unknown keyword in a schema is an error. strictTypes/strictTuples off:
// they want every subschema to state its own type, and these schemas inherit
// "type": "object" through $ref (common/rootProperty), as 2020-12 allows.
const ajv = new Ajv2020({ allErrors: true, strictSchema: true, strictTypes: false, strictTuples: false });
// The one format the schemas use (tileset.schemaUri). An IRI reference (RFC 3987): no
// whitespace, control characters or the characters RFC 3987 excludes.
ajv.addFormat("iri-reference", /^[^\s<>"{}|\\^`\u0000-\u001f\u007f]*$/u);
for (const file of walk(path.join(here, "schema")).filter((f) => f.endsWith(".schema.json"))) {
  const schema = JSON.parse(readFileSync(file, "utf8"));
  schema.$id = new URL(path.relative(path.join(here, "schema"), file).split(path.sep).join("/"), SCHEMA_BASE).href;
  ajv.addSchema(schema);
}
const tilesetSchema = ajv.getSchema(new URL("tileset.schema.json", SCHEMA_BASE).href);

// ---- per-file reports
const reports = new Map(); // absolute path -> report

function report(file, kind) {
  let r = reports.get(file);
  if (!r) {
    r = { file, kind, numErrors: 0, numWarnings: 0, numInfos: 0, numHints: 0, issues: {}, messages: [] };
    reports.set(file, r);
  }
  return r;
}

function issue(r, severity, code, pointer, message) {
  r[SEVERITY[severity]]++;
  const e = (r.issues[code] ??= { severity, count: 0 });
  e.count++;
  if (r.messages.length < maxMessages) r.messages.push({ severity, code, pointer, message });
}

function walk(dir) {
  const out = [];
  for (const e of readdirSync(dir, { withFileTypes: true })) {
    const p = path.join(dir, e.name);
    if (e.isDirectory()) out.push(...walk(p));
    else out.push(p);
  }
  return out.sort();
}

// ---- glTF
async function validateGltf(file) {
  const r = report(file, "gltf");
  let bytes;
  try {
    bytes = new Uint8Array(readFileSync(file));
  } catch (e) {
    issue(r, ERROR, "IO_ERROR", "", String(e.message ?? e));
    return;
  }
  const res = await gltfValidator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0, // all of them
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        try {
          resolve(new Uint8Array(readFileSync(path.join(path.dirname(file), decodeURIComponent(uri)))));
        } catch (e) {
          reject(e);
        }
      }),
  });
  for (const m of res.issues.messages) issue(r, m.severity, m.code, m.pointer ?? "", m.message);
}

// ---- tileset JSON
const GLTF = /\.gl(b|tf)$/i;
const gltfs = new Set(); // every glTF file to validate
const referenced = new Set(); // glTF files some tileset references
const tilesetsDone = new Set();

function validateTileset(file, isExternal, chain = []) {
  if (tilesetsDone.has(file)) return;
  tilesetsDone.add(file);
  const r = report(file, "tileset");
  let json;
  try {
    json = JSON.parse(readFileSync(file, "utf8"));
  } catch (e) {
    issue(r, ERROR, "JSON_PARSE_ERROR", "", String(e.message ?? e));
    return;
  }
  if (!tilesetSchema(json)) {
    for (const e of tilesetSchema.errors) {
      issue(r, ERROR, "SCHEMA_VIOLATION", e.instancePath, `${e.message} (${e.schemaPath}${e.params ? " " + JSON.stringify(e.params) : ""})`);
    }
  }
  const version = json?.asset?.version;
  if (typeof version === "string" && !["0.0", "1.0", "1.1"].includes(version)) {
    issue(r, WARNING, "ASSET_VERSION_UNKNOWN", "/asset/version", `asset.version ${JSON.stringify(version)} is not 0.0, 1.0 or 1.1`);
  }
  const root = json?.root;
  if (root === null || typeof root !== "object") return; // the schema reported it
  if (root.refine === undefined) {
    issue(r, ERROR, "TILE_REFINE_MISSING_IN_ROOT", "/root", `the root tile has no refine (required in ${isExternal ? "an external" : "a"} tileset's root)`);
  }
  const tile = (t, pointer, parentError) => {
    if (t === null || typeof t !== "object") return;
    if (typeof t.geometricError === "number" && typeof parentError === "number" && t.geometricError > parentError) {
      issue(r, WARNING, "TILE_GEOMETRIC_ERRORS_INCONSISTENT", pointer, `geometricError ${t.geometricError} is larger than the parent's ${parentError}`);
    }
    if (typeof t.refine === "string" && t.refine !== "ADD" && t.refine !== "REPLACE") {
      const wrongCase = ["ADD", "REPLACE"].includes(t.refine.toUpperCase());
      issue(r, wrongCase ? WARNING : ERROR, wrongCase ? "TILE_REFINE_WRONG_CASE" : "VALUE_NOT_IN_LIST", `${pointer}/refine`, `refine is ${JSON.stringify(t.refine)}, not ADD or REPLACE`);
    }
    if (t.implicitTiling !== undefined) {
      issue(r, INFO, "IMPLICIT_TILING_NOT_VALIDATED", `${pointer}/implicitTiling`, "implicit tiling is not validated by this tool");
    }
    const contents = [];
    if (t.content) contents.push([t.content, `${pointer}/content`]);
    if (Array.isArray(t.contents)) t.contents.forEach((c, i) => contents.push([c, `${pointer}/contents/${i}`]));
    for (const [c, cp] of contents) {
      if (typeof c?.uri !== "string") continue;
      if (/^[a-z][a-z0-9+.-]*:/i.test(c.uri)) {
        issue(r, INFO, "CONTENT_NOT_LOCAL", `${cp}/uri`, `content ${c.uri} is not a local file and was not validated`);
        continue;
      }
      const target = path.resolve(path.dirname(file), decodeURIComponent(c.uri.split(/[?#]/)[0]));
      if (!existsSync(target)) {
        issue(r, ERROR, "CONTENT_FILE_MISSING", `${cp}/uri`, `content ${c.uri} does not exist (${target})`);
      } else if (GLTF.test(target)) {
        gltfs.add(target);
        referenced.add(target);
      } else if (/\.json$/i.test(target)) {
        if (chain.includes(target) || target === file) {
          issue(r, ERROR, "EXTERNAL_TILESET_CYCLE", `${cp}/uri`, `external tileset ${c.uri} refers back to itself`);
        } else {
          validateTileset(target, true, [...chain, file]);
        }
      } else {
        issue(r, INFO, "CONTENT_TYPE_NOT_VALIDATED", `${cp}/uri`, `content ${c.uri} is not glTF or a tileset and was not validated`);
      }
    }
    if (Array.isArray(t.children)) {
      t.children.forEach((c, i) => tile(c, `${pointer}/children/${i}`, typeof t.geometricError === "number" ? t.geometricError : parentError));
    }
  };
  tile(root, "/root", typeof json.geometricError === "number" ? json.geometricError : undefined);
}

// ---- inputs
const dirGltfs = []; // glTF files found by scanning directories that hold tilesets
let usageError = false;
for (const input of inputs) {
  const abs = path.resolve(input);
  if (!existsSync(abs)) {
    console.error(`${input}: no such file or directory`);
    usageError = true;
    continue;
  }
  if (statSync(abs).isDirectory()) {
    const files = walk(abs);
    const found = files.filter((f) => GLTF.test(f));
    const entries = files.filter((f) => /tileset[^/]*\.json$/i.test(path.basename(f)));
    if (found.length === 0 && entries.length === 0) {
      console.error(`${input}: no .glb/.gltf and no *tileset*.json under it`);
      usageError = true;
    }
    for (const f of found) gltfs.add(f);
    for (const f of entries) validateTileset(f, false);
    if (entries.length > 0) dirGltfs.push(...found);
  } else if (GLTF.test(abs)) {
    gltfs.add(abs);
  } else if (/\.json$/i.test(abs)) {
    validateTileset(abs, false);
  } else {
    console.error(`${input}: neither glTF (.glb, .gltf) nor .json`);
    usageError = true;
  }
}
for (const f of [...gltfs].sort()) await validateGltf(f);
for (const f of dirGltfs) {
  if (!referenced.has(f)) issue(report(f, "gltf"), WARNING, "UNREFERENCED_CONTENT", "", "no validated tileset references this glTF file");
}

// ---- summary
const files = [...reports.values()].sort((a, b) => (a.file < b.file ? -1 : a.file > b.file ? 1 : 0));
const totals = { gltf: 0, tilesets: 0, numErrors: 0, numWarnings: 0, numInfos: 0, numHints: 0 };
for (const r of files) {
  totals[r.kind === "gltf" ? "gltf" : "tilesets"]++;
  for (const k of SEVERITY) totals[k] += r[k];
}
const version = (pkg) => require(`${pkg}/package.json`).version;
const tools = {
  "gltf-validator": gltfValidator.version(),
  ajv: version("ajv"),
  schema: JSON.parse(readFileSync(path.join(here, "schema", "SOURCE.json"), "utf8")),
};
console.log(JSON.stringify({ tools, files, totals }, null, 1));
process.exit(usageError ? 2 : totals.numErrors > 0 ? 1 : 0);
