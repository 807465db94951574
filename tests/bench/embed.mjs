// Benchmark (issue 12): embedding a dance, side by side with <model-viewer> 4.4.0 measured in
// the same run on the same machine. Prints
//  - bundle sizes, raw and gzip: the player (element + player build: JS + wasm), the full
//    engine (JS + wasm) and model-viewer (its one minified module, three.js inside);
//  - time from element attach to the first drawn pose / frame, on the same GLB
//    (RobotExpressive, 464 KB) in headless Chromium (WebGL2 for both: model-viewer has no
//    WebGPU path; ours also on WebGPU), median of N cold page loads; plus the time from
//    navigation start, which counts model-viewer's script (it carries three.js) and our
//    engine fetch alike; and the same for a `.odori` project (a dance generated on the demo
//    song, and on a song file), for which the player fetches the full engine.
// Not a test. Run after `./dev build`: node tests/bench/embed.mjs [runs]
import { readFileSync, statSync } from "node:fs";
import { join, extname } from "node:path";
import { root, data, launch } from "../browser/harness.mjs";
import { bundleSizes, size } from "./bundle-sizes.mjs";

const RUNS = Number(process.argv[2] || 5);
const MV = join(root, "node_modules", "@google", "model-viewer", "dist", "model-viewer.min.js");
const mvVersion = JSON.parse(readFileSync(join(root, "node_modules", "@google", "model-viewer", "package.json"), "utf8")).version;

const kb = (n) => `${(n / 1024).toFixed(0)} KiB`;
const mb = (n) => `${(n / 1048576).toFixed(2)} MiB`;

const built = bundleSizes(join(root, "pkg"));
const sizes = {
  "odori player (odori/player)": built.player,
  "odori full engine (odori)": built.full,
  [`model-viewer ${mvVersion}`]: size([MV]),
};
console.log("bundle sizes (wasm + JS):");
for (const [k, v] of Object.entries(sizes)) console.log(`  ${k.padEnd(34)} raw ${mb(v.raw).padStart(8)}   gzip ${kb(v.gzip).padStart(8)}`);
const player = sizes["odori player (odori/player)"], fullS = sizes["odori full engine (odori)"], mv = sizes[`model-viewer ${mvVersion}`];
console.log(`  player / full engine (gzip): ${(player.gzip / fullS.gzip).toFixed(2)}; player / model-viewer (gzip): ${(player.gzip / mv.gzip).toFixed(2)}; goal player ≤ 1.0 MB gzip: ${player.gzip <= 1048576 ? "met" : "NOT met"} (${player.gzip} B, ${Math.abs(1048576 - player.gzip)} B ${player.gzip <= 1048576 ? "under" : "over"} 1,048,576 B)`);

// One origin serves both pages, the packages and the GLB.
const GLB = join(data, "gltf", "RobotExpressive.glb");
const PAGES = {
  "/odori.html": `<!doctype html><body style="margin:0"><script type="module">
    import { OdoriPlayer } from "/pkg/player/odori-player.js";
    OdoriPlayer.backend = new URLSearchParams(location.search).get("backend");
    const p = document.createElement("odori-player");
    p.setAttribute("src", "/robot.glb"); p.setAttribute("animation-name", "Dance"); p.setAttribute("loading", "eager");
    p.style.cssText = "width:640px;height:480px;display:block";
    p.addEventListener("firstpose", (e) => { window.result = { attachToFirstMs: e.detail.ms, sinceNavMs: performance.now(), backend: e.detail.backend }; });
    p.addEventListener("error", (e) => { window.result = { error: e.detail.message }; });
    document.body.append(p);
  </script>`,
  // A .odori project (made below through the API): the player fetches the full engine for it.
  ...Object.fromEntries(["demo", "song"].map((k) => [`/project-${k}.html`, `<!doctype html><body style="margin:0"><script type="module">
    import { OdoriPlayer } from "/pkg/player/odori-player.js";
    OdoriPlayer.backend = new URLSearchParams(location.search).get("backend");
    const p = document.createElement("odori-player");
    p.setAttribute("src", "/${k}.odori"); p.setAttribute("loading", "eager");
    p.style.cssText = "width:640px;height:480px;display:block";
    p.addEventListener("firstpose", (e) => { window.result = { attachToFirstMs: e.detail.ms, sinceNavMs: performance.now(), backend: e.detail.backend }; });
    p.addEventListener("error", (e) => { window.result = { error: e.detail.message }; });
    document.body.append(p);
  </script>`])),
  "/maker.html": "<!doctype html><title>maker</title>",
  "/mv.html": `<!doctype html><body style="margin:0"><script type="module">
    import "/mv/model-viewer.min.js";
    await customElements.whenDefined("model-viewer");
    const m = document.createElement("model-viewer");
    m.setAttribute("src", "/robot.glb"); m.setAttribute("animation-name", "Dance"); m.setAttribute("autoplay", ""); m.setAttribute("loading", "eager");
    m.style.cssText = "width:640px;height:480px;display:block";
    const t0 = performance.now();
    // model-viewer has no first-frame event: 'load' fires when the model is ready to render;
    // its first frame is drawn in the next animation frame, so we wait two.
    m.addEventListener("load", () => requestAnimationFrame(() => requestAnimationFrame(() => {
      window.result = { attachToFirstMs: performance.now() - t0, sinceNavMs: performance.now(), backend: "webgl2" };
    })));
    m.addEventListener("error", (e) => { window.result = { error: String(e.detail?.type || "error") }; });
    document.body.append(m);
  </script>`,
};
// localhost is a secure context (WebGPU needs one); nothing listens there: the test serves every request.
const ORIGIN_HOST = "localhost:47123";
const ORIGIN = `http://${ORIGIN_HOST}`;
const external = new Set();
const TYPES = { ".js": "text/javascript", ".wasm": "application/wasm", ".html": "text/html", ".glb": "model/gltf-binary" };

const PROJECTS = {};
const SONG = join(data, "music", "Kevin_MacLeod_-_Vibe_Ace.hq.ogg");

async function measure(backend, pageName, work) {
  const { browser, page } = await launch(backend);
  try {
    // Anything else (model-viewer may reach for a CDN) fails at once: no internet here, and a
    // hanging request would be counted against it.
    await page.route((url) => url.host !== ORIGIN_HOST, (route) => { external.add(route.request().url()); return route.abort(); });
    await page.route(`${ORIGIN}/**`, (route) => {
      const path = new URL(route.request().url()).pathname;
      let body;
      if (PAGES[path]) body = PAGES[path];
      else if (path === "/robot.glb") body = readFileSync(GLB);
      else if (PROJECTS[path]) body = PROJECTS[path];
      else if (path.startsWith("/audio/")) body = readFileSync(join(root, "www", path));
      else if (path.startsWith("/mv/")) body = readFileSync(MV);
      else if (path.startsWith("/pkg/")) body = readFileSync(join(root, path));
      else return route.fulfill({ status: 404, body: "" });
      return route.fulfill({ status: 200, contentType: TYPES[extname(path)] || "application/octet-stream", body });
    });
    await page.goto(`${ORIGIN}${pageName}?backend=${backend}`);
    if (work) return await work(page);
    await page.waitForFunction(() => window.result, null, { timeout: 120000 });
    return await page.evaluate(() => window.result);
  } finally {
    await browser.close();
  }
}

/** Two projects with a generated dance, made through the API: on the demo song, and on a song file. */
for (const [key, songFile] of [["demo", null], ["song", SONG]]) {
  const b64 = await measure("webgl2", "/maker.html", (page) => page.evaluate(async (songB64) => {
    const engine = await import("/pkg/odori.js");
    await engine.default();
    const { rmsEnvelope } = await import("/audio/rms.js");
    const { bufferFromSamples, decodeSong } = await import("/audio/song-player.js");
    const p = new engine.Project();
    if (songB64) {
      const bytes = Uint8Array.from(atob(songB64), (c) => c.charCodeAt(0));
      const env = await rmsEnvelope(await decodeSong(bytes, "song.ogg"), engine.envelopeDefinition());
      p.setSong("song.ogg", bytes, env.hopSecs, env.bands, undefined);
    } else {
      const demo = engine.DemoSong.render(44100);
      const env = await rmsEnvelope(bufferFromSamples(demo.samples, demo.sampleRateHz), engine.envelopeDefinition());
      p.setSong("Demo song (built-in)", undefined, env.hopSecs, env.bands, undefined);
    }
    p.generate();
    const saved = p.save();
    let bin = "";
    for (let i = 0; i < saved.length; i += 0x8000) bin += String.fromCharCode.apply(null, saved.subarray(i, i + 0x8000));
    return btoa(bin);
  }, songFile ? readFileSync(songFile).toString("base64") : null));
  PROJECTS[`/${key}.odori`] = Buffer.from(b64, "base64");
}

const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };
console.log(`\ntime to the first drawn pose, ${RUNS} cold page loads each, median (GLB ${kb(statSync(GLB).size)}; .odori projects: demo song ${kb(PROJECTS["/demo.odori"].length)}, song file ${kb(PROJECTS["/song.odori"].length)}, whose player also fetches the full engine):`);
const rows = [["odori player", "webgl2", "/odori.html"], [`model-viewer ${mvVersion}`, "webgl2", "/mv.html"], ["odori player", "webgpu", "/odori.html"],
  [`.odori, demo song`, "webgl2", "/project-demo.html"], [`.odori, song file`, "webgl2", "/project-song.html"]];
const results = {};
for (const [label, backend, path] of rows) {
  const rs = [];
  for (let i = 0; i < RUNS; i++) {
    const r = await measure(backend, path);
    if (r.error) throw new Error(`${label} on ${backend}: ${r.error}`);
    rs.push(r);
  }
  const a = median(rs.map((r) => r.attachToFirstMs)), n = median(rs.map((r) => r.sinceNavMs));
  results[`${label} ${backend}`] = a;
  console.log(`  ${label.padEnd(20)} ${backend.padEnd(7)} attach → first pose ${a.toFixed(0).padStart(6)} ms   navigation → first pose ${n.toFixed(0).padStart(6)} ms   (${rs.map((r) => r.attachToFirstMs.toFixed(0)).join(", ")})`);
}
if (external.size) console.log(`  requests to other hosts, refused: ${[...external].join(", ")}`);
const ours = results["odori player webgl2"], theirs = results[`model-viewer ${mvVersion} webgl2`];
console.log(`  odori / model-viewer (attach → first pose, WebGL2): ${(ours / theirs).toFixed(2)}; goal ≤ 1: ${ours <= theirs ? "met" : "NOT met"}`);
