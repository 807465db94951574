// Benchmark: the exact search in wasm in headless Chromium (issue 3: 120-frame query against
// one hour of 60-fps motion, goal < 150 ms). Prints figures; not a test.
// Run after `./dev build`: node tests/bench/search-browser.mjs
import { readFileSync, readdirSync } from "node:fs";
import { join } from "node:path";
import { startServer, launch, data } from "../browser/harness.mjs";

// Two one-hour libraries: the 13 CMU salsa / Indian / martial clips repeated, and every real
// clip (29, as the native bench; fewer copies of the query's source fit in the hour).
const DANCE13 = ["cmu-salsa/salsa_01", "cmu-salsa/salsa_02", "cmu-salsa/salsa_03", "cmu-salsa/salsa_10", "cmu-salsa/salsa_16", "cmu-salsa/salsa_25",
  "cmu-indian/indian_04", "cmu-indian/indian_06", "cmu-indian/indian_07", "cmu-indian/indian_08", "cmu-indian/indian_13",
  "cmu-martial/martial_04", "cmu-martial/martial_07"];
const ALL = readdirSync(join(data, "mocap"), { withFileTypes: true })
  .filter((d) => d.isDirectory())
  .flatMap((d) => readdirSync(join(data, "mocap", d.name)).filter((f) => f.endsWith(".bvh")).map((f) => `${d.name}/${f.slice(0, -4)}`))
  .sort();
const server = await startServer();
const { browser, page } = await launch("webgl2");
try {
  for (const [label, FILES] of [["13 dance/martial clips", DANCE13], [`all ${ALL.length} real clips`, ALL]]) {
  await page.goto(server.url + "?backend=webgl2");
  await page.waitForFunction(() => document.body.dataset.ready === "1");
  for (const f of FILES) {
    const b64 = readFileSync(join(data, "mocap", `${f}.bvh`)).toString("base64");
    await page.evaluate(([name, b64, salsa]) => {
      const bin = atob(b64);
      const bytes = new Uint8Array(bin.length);
      for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
      window.odori.library.importFile(name, bytes, salsa ? { fpsOverride: 60 } : {});
    }, [`${f.split("/")[1]}.bvh`, b64, f.includes("salsa")]);
  }
  const out = await page.evaluate(async () => {
    const { SearchIndex } = await import("./pkg/odori.js");
    const { library } = window.odori;
    const clips = library.clips().filter((c) => c.format === "bvh");
    const feats = clips.map((c) => library.searchFeatures(c.id));
    const perFrame = 63, target = 216000;
    const all = new Float32Array(target * perFrame);
    let at = 0, k = 0;
    while (at < all.length) { const f = feats[k++ % feats.length]; const n = Math.min(f.length, all.length - at); all.set(f.subarray(0, n), at); at += n; }
    const index = new SearchIndex();
    const t0 = performance.now();
    index.addFeatures(1, "hour", all);
    const salsa02 = clips.find((c) => c.name === "salsa_02");
    index.addFromLibrary(library, salsa02.id);
    const tIndex = performance.now() - t0;
    const q = { clipId: salsa02.id, startFrame: 1200, endFrame: 1320 };
    const time = (params) => {
      const runs = [];
      let res;
      for (let r = 0; r < 3; r++) { const t = performance.now(); res = index.search(q, params); runs.push(performance.now() - t); }
      runs.sort((a, b) => a - b);
      return { ms: runs[1], matches: res.matches.length, frames: res.stats.framesSearched };
    };
    return { tIndex, top1: time({ maxResults: 1 }), top10: time({ maxResults: 10 }), feetTop10: time({ preset: "feetOnly", maxResults: 10 }) };
  });
  console.log(`one hour from ${label}: index build (216,000 + clip frames): ${out.tIndex.toFixed(0)} ms`);
  for (const [k, v] of Object.entries(out).filter(([k]) => k !== "tIndex")) {
    console.log(`wasm in Chromium, ${label}, ${k}: ${v.ms.toFixed(1)} ms (median of 3), ${v.matches} matches over ${v.frames} frames`);
  }
  }
} finally {
  await browser.close();
  server.stop();
}
