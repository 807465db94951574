// Shared by the browser tests: the app's server, Debian's headless Chromium on either
// graphics back end, and pixel reading from real screenshots.
import { spawn } from "node:child_process";
import { existsSync, mkdirSync, readFileSync, statSync } from "node:fs";
import { createServer } from "node:http";
import { fileURLToPath } from "node:url";
import { basename, dirname, join } from "node:path";
import { chromium } from "playwright-core";

export const root = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
export const data = join(root, "..", "shared", "data");
export const artifacts = join(root, "tests", "artifacts");
mkdirSync(artifacts, { recursive: true });
if (!existsSync(data)) throw new Error(`../shared/data is missing: the browser tests open real files from it (${data})`);

const BASE_FLAGS = ["--headless", "--no-sandbox", "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-dev-shm-usage", "--autoplay-policy=no-user-gesture-required"];
export const BACKENDS = {
  // WebGL2 needs no flag (SwiftShader through ANGLE); the page is told to use it.
  webgl2: { flags: [], query: "?backend=webgl2" },
  // WebGPU onto a canvas with software Vulkan (see the toolchain guide).
  webgpu: { flags: ["--enable-unsafe-webgpu", "--enable-features=Vulkan", "--use-vulkan=swiftshader", "--use-angle=swiftshader"], query: "?backend=webgpu" },
};

/** Starts the app's static server on a free port; resolves to { url, stop }. */
export function startServer() {
  const bin = join(root, "target", "debug", "xtask");
  return new Promise((resolve, reject) => {
    const proc = spawn(bin, ["serve", "--port", "0"], { cwd: root, stdio: ["ignore", "pipe", "inherit"] });
    let out = "";
    proc.stdout.on("data", (d) => {
      out += d;
      const m = out.match(/http:\/\/localhost:(\d+)\//);
      if (m) resolve({ url: `http://127.0.0.1:${m[1]}/`, stop: () => proc.kill() });
    });
    proc.on("exit", (code) => reject(new Error(`server exited (${code}): ${out}`)));
    setTimeout(() => reject(new Error("server did not start in 20 s")), 20000);
  });
}

/**
 * What a test's code in the page may call, on every page `launch` opens (before the app's
 * scripts; not a <script>, so the page's Content-Security-Policy does not apply):
 * `window.__test.base64(bytes)`, bytes to base64 in slices (a long string of them to Node is far
 * cheaper than a JSON array of numbers), and `window.__test.bytes(base64)`, the way back.
 */
function pageHelpers() {
  window.__test = {
    base64(a) {
      let s = "";
      for (let i = 0; i < a.length; i += 0x8000) s += String.fromCharCode.apply(null, a.subarray(i, i + 0x8000));
      return btoa(s);
    },
    bytes: (b64) => Uint8Array.from(atob(b64), (ch) => ch.charCodeAt(0)),
  };
}

export async function launch(backend) {
  const browser = await chromium.launch({ executablePath: "/usr/bin/chromium", args: [...BASE_FLAGS, ...BACKENDS[backend].flags], headless: true });
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  await page.addInitScript(pageHelpers);
  const logs = [];
  page.on("console", (m) => logs.push(`[${m.type()}] ${m.text()}`));
  page.on("pageerror", (e) => logs.push(`[pageerror] ${e.message}`));
  return { browser, page, logs };
}

/** Opens the app and waits for the first drawn pose. */
export async function openApp(page, server, backend) {
  await page.goto(server.url + BACKENDS[backend].query);
  await page.waitForFunction(() => document.body.dataset.ready, null, { timeout: 60000 });
  const ready = await page.evaluate(() => document.body.dataset.ready);
  if (ready !== "1") throw new Error(`the app did not start: ${await page.textContent("#messages")}`);
}

/**
 * Opens motion files through the page's picker (`files`: paths or playwright file payloads) and
 * answers the import-options dialog the app shows when a BVH file is among them:
 * `options[fileName] = { fps, units }` for the files that need other than their own ("units":
 * metres per file unit as the dialog's values, e.g. "0.01"). Resolves once the dialog is
 * answered, not when the import is done.
 */
export async function importFiles(page, files, options = {}) {
  const list = Array.isArray(files) ? files : [files];
  await page.setInputFiles("#file-input", list);
  const names = list.map((f) => (typeof f === "string" ? basename(f) : f.name));
  if (!names.some((n) => /\.bvh$/i.test(n))) return;
  const dialog = page.locator("#import-options");
  await dialog.waitFor({ state: "visible", timeout: 30000 });
  for (const [name, o] of Object.entries(options)) {
    const row = dialog.locator(`tr[data-file="${name}"]`);
    if (o.fps != null) await row.locator(".import-fps").fill(String(o.fps));
    if (o.units != null) await row.locator(".import-units").selectOption(String(o.units));
  }
  await page.click("#import-go");
  await dialog.waitFor({ state: "hidden", timeout: 10000 });
}

/**
 * The Dance strip's steps the dance tests share. `importSalsaForDance`: opens the CMU salsa_02
 * BVH (at 60 fps) through the picker and waits until the dance library holds its segments and
 * the join costs are built again.
 */
export async function importSalsaForDance(page) {
  await importFiles(page, join(data, "mocap/cmu-salsa/salsa_02.bvh"), { "salsa_02.bvh": { fps: 60 } });
  await page.waitForFunction(() => [...document.querySelectorAll("#messages li")].some((li) => /dance segments/.test(li.textContent)), null, { timeout: 30000 });
  await page.waitForFunction(() => document.querySelector("#dance").dataset.joins === "ready" && window.odori.choreo.lastPrepare?.segments > 558, null, { timeout: 60000 });
}

/** Waits until the dance is not busy and every bar holds a move (after Generate, Another take…). */
export function danceSettled(page, timeout = 60000) {
  return page.waitForFunction(() => !document.querySelector("#dance").dataset.busy && window.odori.choreo.view.every((v) => v.state.kind !== "empty"), null, { timeout });
}

/** Clicks Generate and waits for the dance to settle. */
export async function generateDance(page, timeout = 60000) {
  await page.click("#dance-generate");
  await danceSettled(page, timeout);
}

/** Opens the app on `backend`, waits for the demo song's bars and generates their dance (benches, traces). */
export async function openDemoDance(page, server, backend, timeout = 120000) {
  await page.goto(server.url + BACKENDS[backend].query);
  await page.waitForFunction(() => document.body.dataset.ready === "1", null, { timeout });
  await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8, null, { timeout });
  await generateDance(page, timeout);
}

/**
 * Selects bar `bar` (0-based, as `data-bar`) and returns its candidate chips, left to right, each
 * with the flags the engine's note gives it: [{ text, flags }] (flags null: no note).
 */
export async function candidateChips(page, bar) {
  await page.click(`#dance-bars [data-bar="${bar}"]`);
  await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.candidates) > 0);
  return page.evaluate(() => {
    const ch = window.odori.choreo;
    return [...document.querySelectorAll("#dance-candidates .chip")].map((c, k) => ({ text: c.textContent, flags: ch.candidateNotes.get(ch.candidates[k])?.flags ?? null }));
  });
}

/**
 * Screenshot of the canvas, decoded in the page: { width, height, rgba, save(name) }.
 * Pixels are CSS pixels of the canvas element (device scale 1).
 */
export async function canvasPixels(page, name) {
  const el = await page.$("#view");
  const png = await el.screenshot(name ? { path: join(artifacts, name) } : {});
  return decodeImageInPage(page, png);
}

/**
 * An image file's bytes (PNG, BMP, JPEG: a Buffer) decoded by the browser's own decoders in
 * `page`: { width, height, rgba }. `options` are createImageBitmap's (a texture's exact values:
 * { premultiplyAlpha: "none", colorSpaceConversion: "none" }; none given: the browser's defaults).
 */
export async function decodeImageInPage(page, buf, options = {}) {
  const { width, height, data } = await page.evaluate(async ({ b64, options }) => {
    // Decoded without fetch(): the page's Content-Security-Policy allows no data: connections.
    const bytes = Uint8Array.from(atob(b64), (ch) => ch.charCodeAt(0));
    const bmp = await createImageBitmap(new Blob([bytes]), options);
    const c = new OffscreenCanvas(bmp.width, bmp.height);
    const g = c.getContext("2d");
    g.drawImage(bmp, 0, 0);
    const img = g.getImageData(0, 0, bmp.width, bmp.height);
    // Back to Node as base64: far cheaper than a JSON array of millions of numbers.
    let bin = "";
    for (let i = 0; i < img.data.length; i += 0x8000) bin += String.fromCharCode.apply(null, img.data.subarray(i, i + 0x8000));
    return { width: img.width, height: img.height, data: btoa(bin) };
  }, { b64: buf.toString("base64"), options });
  return { width, height, rgba: new Uint8Array(Buffer.from(data, "base64")) };
}

/** 32-bit floats sent from the page as base64 (`window.__test.base64` of their bytes). */
export function floatsFromBase64(b64) {
  const b = Buffer.from(b64, "base64");
  return new Float32Array(b.buffer, b.byteOffset, b.length / 4);
}

export function pixel(img, x, y) {
  const i = (Math.round(y) * img.width + Math.round(x)) * 4;
  return [img.rgba[i], img.rgba[i + 1], img.rgba[i + 2]];
}

/** Pixels in a (2r+1)² window around (x, y) matching `pred`. */
export function countNear(img, x, y, r, pred) {
  let n = 0;
  for (let dy = -r; dy <= r; dy++) for (let dx = -r; dx <= r; dx++) {
    const px = x + dx, py = y + dy;
    if (px < 0 || py < 0 || px >= img.width || py >= img.height) continue;
    if (pred(pixel(img, px, py))) n++;
  }
  return n;
}

export function countAll(img, pred) {
  let n = 0;
  for (let i = 0; i < img.rgba.length; i += 4) if (pred([img.rgba[i], img.rgba[i + 1], img.rgba[i + 2]])) n++;
  return n;
}

/** Strongly orange (figure colour 0) / teal (figure colour 1), whatever the shading. */
export const isOrange = ([r, g, b]) => r > 90 && r > g * 1.25 && g > b * 1.2 && r - b > 60;
export const isTeal = ([r, g, b]) => b > 70 && g > 50 && g > r * 1.5 && b > r * 1.6;
/** The first figure's pixels whatever it is drawn on: the built-in body's warm clay, or the first stick figure's orange (not the grey floor nor the background). */
export const isWarmFigure = ([r, g, b]) => r > 80 && r - b > 30 && r >= g;
export const isBackground = ([r, g, b]) => Math.max(r, g, b) < 90 && Math.abs(r - b) < 30;

/**
 * Polls `probe` (sync or async, run in Node) until it returns a truthy value, and returns that
 * value; after `timeoutMs` it throws, naming `what` and the last value seen. Browser tests
 * wait on state with this rather than on fixed sleeps: on a loaded 2-core machine a sleep is
 * either too short (a flake) or far too long.
 */
export async function waitUntil(probe, { what = "condition", timeoutMs = 30000, intervalMs = 50 } = {}) {
  const deadline = Date.now() + timeoutMs;
  let last;
  for (;;) {
    last = await probe();
    if (last) return last;
    if (Date.now() > deadline) throw new Error(`timed out after ${timeoutMs} ms waiting for ${what}; last seen: ${JSON.stringify(last)}`);
    await new Promise((r) => setTimeout(r, intervalMs));
  }
}

/**
 * Screenshots the canvas until `pred(img)` holds (the renderer draws on the next animation
 * frame, whenever the machine gets to it); returns the last image. Throws with `what` on timeout.
 */
export async function canvasPixelsUntil(page, pred, what, name, timeoutMs = 30000) {
  let img;
  await waitUntil(async () => { img = await canvasPixels(page, name); return pred(img); }, { what, timeoutMs, intervalMs: 100 });
  return img;
}

/**
 * A static server for www/ and pkg/ in Node, like `xtask serve` (same paths, types and
 * headers) but on a port the caller may choose again after stopping it, with `overrides`
 * ({ "/main.js": Buffer }) serving other bytes: the offline test uses it to take the origin
 * away and to bring it back with a new build. Resolves to { url, port, stop(), requests }.
 */
export function startStaticServer({ port = 0, overrides = {} } = {}) {
  const types = { html: "text/html; charset=utf-8", js: "text/javascript; charset=utf-8", mjs: "text/javascript; charset=utf-8", css: "text/css; charset=utf-8", wasm: "application/wasm", svg: "image/svg+xml", png: "image/png", json: "application/json", webmanifest: "application/json", ts: "text/plain; charset=utf-8", md: "text/plain; charset=utf-8" };
  const requests = [];
  const sockets = new Set();
  const server = createServer((req, res) => {
    let path = decodeURIComponent(req.url.split(/[?#]/)[0]);
    requests.push(path);
    if (path.endsWith("/")) path += "index.html";
    const file = path.startsWith("/pkg/") ? join(root, "pkg", path.slice(5)) : join(root, "www", path.slice(1));
    const body = overrides[path] ?? (path.split("/").includes("..") || !existsSync(file) || !statSync(file).isFile() ? null : readFileSync(file));
    if (!body) { res.writeHead(404, { "Content-Type": "text/plain" }); res.end(`not found: ${path}\n`); return; }
    res.writeHead(200, { "Content-Type": types[path.split(".").pop()] ?? "application/octet-stream", "Content-Length": body.length, "Cache-Control": "no-cache", "Cross-Origin-Opener-Policy": "same-origin", Connection: "close" });
    res.end(req.method === "HEAD" ? undefined : body);
  });
  server.on("connection", (s) => { sockets.add(s); s.on("close", () => sockets.delete(s)); });
  return new Promise((resolve, reject) => {
    server.once("error", reject);
    server.listen(port, "127.0.0.1", () => {
      const p = server.address().port;
      resolve({
        url: `http://127.0.0.1:${p}/`, port: p, requests,
        // Closes the listener and every open connection: afterwards the origin refuses connections.
        stop: () => new Promise((r) => { for (const s of sockets) s.destroy(); server.close(() => r()); }),
      });
    });
  });
}

const CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-dev-shm-usage"];

/** Our own Chromium process on a profile directory (so a test can kill it), driven over CDP; `console` adds the page's console to `logs`. */
export async function startChromium(profile, backend, { console: withConsole = false } = {}) {
  const proc = spawn("/usr/bin/chromium", [...CHROMIUM_FLAGS, ...BACKENDS[backend].flags, `--user-data-dir=${profile}`, "--remote-debugging-port=0", "about:blank"], { stdio: ["ignore", "ignore", "pipe"], detached: true });
  const ws = await new Promise((resolve, reject) => {
    let err = "";
    proc.stderr.on("data", (d) => {
      err += d;
      const m = err.match(/DevTools listening on (ws:\/\/\S+)/);
      if (m) resolve(m[1]);
    });
    proc.on("exit", (code) => reject(new Error(`chromium exited (${code}): ${err.slice(-2000)}`)));
    setTimeout(() => reject(new Error("chromium did not start in 30 s")), 30000);
  });
  const browser = await chromium.connectOverCDP(ws);
  const context = browser.contexts()[0];
  const page = context.pages()[0] || (await context.newPage());
  const logs = [];
  page.on("pageerror", (e) => logs.push(`[pageerror] ${e.message}`));
  if (withConsole) page.on("console", (m) => logs.push(`[${m.type()}] ${m.text()}`));
  return { proc, browser, context, page, logs };
}
