// Checks that the browser path (WebAudio decode + the reference host code of rms.rs in a real
// Chromium) and the native path (symphonia + odori_core::music::envelope) give the same RMS
// envelope and the same bars, within one hop (issue 4). Report tool, not part of `cargo test`.
// Usage: node check.mjs <data dir> <data-relative file> <native example binary>
// Needs playwright-core (resolved from the repository, or the path in ODORI_PLAYWRIGHT) and a
// Chromium (CHROMIUM, default /usr/bin/chromium).
import { createServer } from "node:http";
import { readFileSync, writeFileSync, mkdtempSync } from "node:fs";
import { execFileSync } from "node:child_process";
import { createRequire } from "node:module";
import { join, dirname } from "node:path";
import { tmpdir } from "node:os";
import { fileURLToPath } from "node:url";

const [dataDir, rel, nativeBin] = process.argv.slice(2);
const here = dirname(fileURLToPath(import.meta.url));
const require = createRequire(join(here, "../../../package.json"));
const { chromium } = require(process.env.ODORI_PLAYWRIGHT || "playwright-core");

const server = createServer((req, res) => {
  if (req.url === "/") {
    res.setHeader("content-type", "text/html");
    res.end(readFileSync(join(here, "page.html")));
  } else if (req.url === "/rms.js") {
    res.setHeader("content-type", "text/javascript");
    res.end(readFileSync(join(here, "../../../www/audio/rms.js")));
  } else if (/^\/pkg\/[\w.-]+$/.test(req.url)) {
    // The engine (built into pkg/ by `./dev build`): the page asks it for the envelope's definition.
    res.setHeader("content-type", req.url.endsWith(".wasm") ? "application/wasm" : "text/javascript");
    res.end(readFileSync(join(here, "../../..", req.url)));
  } else if (req.url === "/audio") {
    res.end(readFileSync(join(dataDir, rel)));
  } else {
    res.statusCode = 404;
    res.end();
  }
}).listen(0);
const port = server.address().port;
const browser = await chromium.launch({ executablePath: process.env.CHROMIUM || "/usr/bin/chromium", args: ["--no-sandbox"] });
const page = await browser.newPage();
await page.goto(`http://127.0.0.1:${port}/`);
await page.waitForFunction(() => window.ready === true);
const web = await page.evaluate(() => envelopeOf("/audio", 44100));
const version = browser.version();
await browser.close();
server.close();

const native = JSON.parse(execFileSync(nativeBin, ["dump", rel], { maxBuffer: 1 << 28, env: { ...process.env, ODORI_DATA: dataDir } }).toString());
console.log(`${rel}\nChromium ${version}: ${web.channels} channels, ${web.length} samples, hop ${web.hopSecs}`);
// Decoders may disagree on a lossy file's length (Vorbis end trimming): compare the common
// frames, and report the lag (in frames) at which the full bands agree best.
const common = Math.min(native.bands[0].length, web.bands[0].length);
if (native.bands[0].length !== web.bands[0].length) {
  console.log(`length differs: ${native.bands[0].length} native frames vs ${web.bands[0].length} browser frames; comparing the first ${common}`);
}
const mismatch = (n, w, lag) => {
  let e = 0;
  for (let i = 10; i < common - 10; i++) e += Math.abs(n[i] - (w[i + lag] ?? 0));
  return e;
};
let bestLag = 0;
for (let lag = -5; lag <= 5; lag++) if (mismatch(native.bands[0], web.bands[0], lag) < mismatch(native.bands[0], web.bands[0], bestLag)) bestLag = lag;
console.log(`best alignment lag: ${bestLag} frames`);
let worst = 0;
for (let b = 0; b < native.bands.length; b++) {
  const n = native.bands[b], w = web.bands[b];
  const peak = Math.max(...n);
  let maxRel = 0;
  for (let i = 0; i < common; i++) maxRel = Math.max(maxRel, Math.abs(n[i] - w[i]) / peak);
  worst = Math.max(worst, maxRel);
  console.log(`band ${b}: max |native - browser| = ${(maxRel * 100).toExponential(2)} % of the band's peak`);
}
const dir = mkdtempSync(join(tmpdir(), "odori-webaudio-"));
const webFile = join(dir, "web.json");
writeFileSync(webFile, JSON.stringify({ hopSecs: web.hopSecs, bands: web.bands }));
const gridWeb = JSON.parse(execFileSync(nativeBin, ["analyze", webFile]).toString());
const nativeFile = join(dir, "native.json");
writeFileSync(nativeFile, JSON.stringify(native));
const gridNative = JSON.parse(execFileSync(nativeBin, ["analyze", nativeFile]).toString());
const starts = (g) => g.bars.map((b) => b.startSecs);
const a = starts(gridNative), c = starts(gridWeb);
const barDiff = a.length === c.length ? Math.max(0, ...a.map((t, i) => Math.abs(t - c[i]))) : Infinity;
console.log(`grid from the browser envelope: ${gridWeb.bpm.toFixed(2)} BPM, ${c.length} bars; native: ${gridNative.bpm.toFixed(2)} BPM, ${a.length} bars; worst bar-start difference ${(barDiff * 1000).toFixed(1)} ms (one hop = ${(native.hopSecs * 1000).toFixed(1)} ms)`);
const ok = barDiff <= native.hopSecs + 1e-6 && worst < 1e-2 && bestLag === 0;
console.log(ok ? "OK: same envelope and bars within one hop" : "MISMATCH");
process.exit(ok ? 0 : 1);
