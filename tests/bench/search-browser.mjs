// Benchmark: the exact search in wasm in headless Chromium (issues 3, 16: 120-frame query against
// one hour of 60-fps motion, goal top 10 < 150 ms) for (a) a query whose source is in the hour
// (salsa_02) and (b) a novel query (2 s of indian_13, left out of the hour), the fast search
// next to the plain DP (`searchPlain`, every cell) with their ratio. Prints figures; not a test.
// Run after `./dev build`: node tests/bench/search-browser.mjs  (ODORI_BENCH_NO_PLAIN=1 skips the
// plain DP, which takes tens of seconds per query).
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
  const out = await page.evaluate(async (withPlain) => {
    const { SearchIndex } = await import("./pkg/odori.js");
    const { library } = window.odori;
    const all_clips = library.clips().filter((c) => c.format === "bvh");
    // indian_13 is the novel query's source: left out of the hour.
    const held = all_clips.find((c) => c.name === "indian_13");
    const clips = all_clips.filter((c) => c !== held);
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
    // The novel query: its normalised features, from an index that holds only indian_13.
    const side = new SearchIndex();
    side.addFromLibrary(library, held.id);
    const mid = Math.floor(library.searchFeatures(held.id).length / 63 / 2);
    const novel = side.queryFeatures({ clipId: held.id, startFrame: mid, endFrame: mid + 120 });
    const run = (which, params) => (which === "in" ? index.search(q, params) : index.searchFeatures(novel, params));
    const time = (which, params) => {
      const runs = [];
      let res;
      for (let r = 0; r < 3; r++) { const t = performance.now(); res = run(which, params); runs.push(performance.now() - t); }
      runs.sort((a, b) => a - b);
      return { ms: runs[1], matches: res.matches.length, frames: res.stats.framesSearched, best: res.matches[0]?.distance };
    };
    const out = {};
    for (const which of ["in", "novel"]) {
      out[`${which} top1`] = time(which, { maxResults: 1 });
      out[`${which} top10`] = time(which, { maxResults: 10 });
      if (withPlain) {
        const t = performance.now();
        const p = which === "in" ? index.searchPlain(q, { maxResults: 10 }) : index.searchPlainFeatures(novel, { maxResults: 10 });
        out[`${which} top10`].plainMs = performance.now() - t;
        out[`${which} top10`].plainBest = p.matches[0]?.distance;
      }
    }
    out["in feetTop10"] = time("in", { preset: "feetOnly", maxResults: 10 });
    return { tIndex, ...out };
  }, !process.env.ODORI_BENCH_NO_PLAIN);
  console.log(`one hour from ${label}: index build (216,000 + clip frames): ${out.tIndex.toFixed(0)} ms`);
  for (const [k, v] of Object.entries(out).filter(([k]) => k !== "tIndex")) {
    let line = `wasm in Chromium, ${label}, ${k}: fast ${v.ms.toFixed(1)} ms (median of 3), ${v.matches} matches over ${v.frames} frames, best ${v.best?.toFixed(4)}`;
    if (v.plainMs !== undefined) line += `; plain DP ${v.plainMs.toFixed(0)} ms (best ${v.plainBest?.toFixed(4)}), plain / fast = ${(v.plainMs / v.ms).toFixed(1)}x`;
    console.log(line);
  }
  }
} finally {
  await browser.close();
  server.stop();
}
