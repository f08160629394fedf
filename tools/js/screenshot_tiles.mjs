// Serves a cliffmap export-tiles folder on 127.0.0.1 (an ephemeral port), opens its
// index.html in headless Chromium (WebGL through SwiftShader) with ?camera=VIEW, waits until
// every tile is loaded and writes a screenshot.
// Usage: node screenshot_tiles.mjs DIR VIEW_REL_PATH OUT.png WIDTH HEIGHT [MODE]
// (MODE: ?mode= of the page, a texture mode export-tiles wrote; the mode selector is hidden
// for the screenshot.)
// CesiumJS is taken from this folder's node_modules (linked into DIR if DIR has none).
import { createServer } from "node:http";
import { readFile, symlink, access } from "node:fs/promises";
import { extname, join, normalize, dirname } from "node:path";
import { fileURLToPath } from "node:url";
import puppeteer from "puppeteer-core";

const [dir, view, out, w, h, mode] = process.argv.slice(2);
const here = dirname(fileURLToPath(import.meta.url));
try { await access(join(dir, "node_modules")); } catch { await symlink(join(here, "node_modules"), join(dir, "node_modules")); }
const types = { ".html": "text/html", ".js": "text/javascript", ".json": "application/json", ".glb": "model/gltf-binary",
  ".css": "text/css", ".png": "image/png", ".wasm": "application/wasm", ".svg": "image/svg+xml" };
const server = createServer(async (req, res) => {
  const path = normalize(decodeURIComponent(new URL(req.url, "http://x").pathname)).replace(/^(\.\.[/\\])+/, "");
  try {
    const body = await readFile(join(dir, path));
    res.writeHead(200, { "content-type": types[extname(path)] ?? "application/octet-stream" });
    res.end(body);
  } catch { res.writeHead(404); res.end(); }
});
await new Promise((r) => server.listen(0, "127.0.0.1", r));
const port = server.address().port;
const browser = await puppeteer.launch({ executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium", headless: true,
  args: ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--no-sandbox", `--window-size=${w},${h}`] });
let code = 0;
try {
  const page = await browser.newPage();
  await page.setViewport({ width: +w, height: +h, deviceScaleFactor: 1 });
  await page.goto(`http://127.0.0.1:${port}/index.html?camera=${encodeURIComponent(view)}${mode ? `&mode=${mode}` : ""}`);
  await page.waitForFunction("window.cliffmapStarted || window.cliffmapError", { timeout: 180000 });
  const err = await page.evaluate("window.cliffmapError");
  if (err) throw new Error(err);
  await page.evaluate("window.cliffmapReady");
  if (mode && (await page.evaluate("window.cliffmapMode")) !== mode) throw new Error(`the page did not switch to ${mode}`);
  await page.evaluate("document.getElementById('mode').hidden = true");
  await new Promise((r) => setTimeout(r, 500));
  await page.screenshot({ path: out });
} catch (e) { console.error(String(e)); code = 1; }
await browser.close();
server.close();
process.exit(code);
