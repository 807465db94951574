// Benchmark: the exact search in wasm in headless Chromium (issues 3, 16: 120-frame query against
// one hour of 60-fps motion, goal top 10 < 150 ms) for (a) a query whose source is in the hour
// (salsa_02) and (b) a novel query (2 s of indian_13, left out of the hour). The hour is a
// library of clips: every real clip but indian_13, repeated as separate clips up to 216,000
// frames. Three ways over the same clips:
// - the product's path: the app's SearchClient (www/search/client.js) with one Web Worker per
//   core (navigator.hardwareConcurrency, at most 4), each holding part of the clips, the query
//   sent to all and their answers merged exactly (mergeOutcomes); with two or more workers in
//   two rounds: each worker's probe, then each worker's search from the joined bound;
// - one SearchIndex on the page's thread (one core);
// - the plain DP (`searchPlainFeatures`, every cell) on the page's thread, with the ratio.
// It checks that the workers' merged results equal the one-thread results. Beside each wall
// time it prints CPU time per thread, read from /proc for this run's renderer threads (the
// busiest search worker, all of them, the page's thread): on a shared machine the wall times
// mostly measure the load, while the busiest worker's CPU time is what the product's path takes
// on an idle machine of this kind (the workers run at once, one per core). Prints figures; not
// a test. Run after `./dev build`: node tests/bench/search-browser.mjs  (ODORI_BENCH_NO_PLAIN=1
// skips the plain DP, which takes tens of seconds per query; ODORI_BENCH_BACKEND=webgpu runs the
// page on WebGPU instead of WebGL2).
import { readFileSync, readdirSync } from "node:fs";
import { join } from "node:path";
import { startServer, launch, data } from "../browser/harness.mjs";
import { descendants } from "./proc.mjs";

const ALL = readdirSync(join(data, "mocap"), { withFileTypes: true })
  .filter((d) => d.isDirectory())
  .flatMap((d) => readdirSync(join(data, "mocap", d.name)).filter((f) => f.endsWith(".bvh")).map((f) => `${d.name}/${f.slice(0, -4)}`))
  .sort();
// CPU time per thread of this run's Chromium renderers (descendants of this process), from
// /proc: the machine is shared, so wall times say more about its load than about the search;
// a worker thread's CPU time is what it would take on an idle machine of this kind.
/** Map "pid/tid" → { name, ms } for every thread of this run's renderer processes. */
function threadCpu() {
  const m = new Map();
  for (const pid of descendants()) {
    let cmd = "";
    try { cmd = readFileSync(`/proc/${pid}/cmdline`, "utf8"); } catch { continue; }
    if (!cmd.includes("--type=renderer")) continue;
    let tids = [];
    try { tids = readdirSync(`/proc/${pid}/task`); } catch { continue; }
    for (const tid of tids) {
      try {
        const st = readFileSync(`/proc/${pid}/task/${tid}/stat`, "utf8");
        const name = st.slice(st.indexOf("(") + 1, st.lastIndexOf(")"));
        const f = st.slice(st.lastIndexOf(")") + 2).split(" ");
        m.set(`${pid}/${tid}`, { name, ms: (Number(f[11]) + Number(f[12])) * 10 });
      } catch { /* gone */ }
    }
  }
  return m;
}
/** CPU ms spent between two readings by each worker thread (`"DedicatedWorker"`), or by every
 * other renderer thread (`"page"`: the page's main thread, where the one-thread search runs,
 * plus its few helpers). */
function cpuDelta(a, b, which) {
  const out = [];
  for (const [k, v] of b) if (v.name.startsWith("DedicatedWorker") === (which === "DedicatedWorker")) out.push(v.ms - (a.get(k)?.ms ?? 0));
  return out;
}

const server = await startServer();
const BACKEND = process.env.ODORI_BENCH_BACKEND || "webgl2";
const { browser, page } = await launch(BACKEND);
try {
  await page.goto(server.url + `?backend=${BACKEND}`);
  await page.waitForFunction(() => document.body.dataset.ready === "1");
  for (const f of ALL) {
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
    const { SearchClient } = await import("./search/client.js");
    const { library } = window.odori;
    const allClips = library.clips().filter((c) => c.format === "bvh");
    // indian_13 is the novel query's source: left out of the hour.
    const held = allClips.find((c) => c.name === "indian_13");
    const clips = allClips.filter((c) => c !== held);
    // The hour: the clips repeated, each copy its own library clip (ids 1, 2, …), the last cut.
    const perFrame = 63, target = 216000;
    const hour = []; // { id, name, features }
    let frames = 0;
    for (let k = 0; frames < target; k++) {
      const c = clips[k % clips.length];
      const f = library.searchFeatures(c.id);
      const n = Math.min(f.length / perFrame, target - frames);
      hour.push({ id: k + 1, name: `${c.name} copy ${Math.floor(k / clips.length) + 1}`, features: f.subarray(0, n * perFrame) });
      frames += n;
    }
    const byId = new Map(hour.map((h) => [h.id, h]));
    // The app's search client over the hour, through a library-shaped view of it.
    const view = {
      clip: (id) => ({ name: byId.get(id).name, humanoid: { kind: "humanoid" } }),
      searchFeatures: (id) => byId.get(id).features,
    };
    let t0 = performance.now();
    const client = new SearchClient(view);
    for (const h of hour) client.add(h.id);
    const workers = client.workers.length;
    // Wait until every worker has its clips (a message round trip per worker).
    await Promise.all(client.workers.map((w, k) => client.request(k, { type: "queryFeatures", query: { clipId: hour[k].id, startFrame: 0, endFrame: 1 } }).catch(() => null)));
    const tWorkers = performance.now() - t0;
    t0 = performance.now();
    const index = new SearchIndex();
    for (const h of hour) index.addFeatures(h.id, h.name, h.features);
    const tIndex = performance.now() - t0;
    // (a) 2 s of the first salsa_02 copy; (b) 2 s of indian_13 from an index that holds only it.
    const salsa = hour.find((h) => h.name.startsWith("salsa_02 "));
    const q = { clipId: salsa.id, startFrame: 1200, endFrame: 1320 };
    const side = new SearchIndex();
    side.addFromLibrary(library, held.id);
    const mid = Math.floor(library.searchFeatures(held.id).length / perFrame / 2);
    const features = { in: index.queryFeatures(q), novel: side.queryFeatures({ clipId: held.id, startFrame: mid, endFrame: mid + 120 }) };
    // The product's path for given query features: SearchClient.search after its queryFeatures
    // round trip (the same two rounds and the same exact merge).
    const viaWorkers = (feats, params) => client.searchFeatures(feats, params);
    const key = (r) => JSON.stringify(r.matches.map((m) => [m.clipId, m.startFrame, m.endFrame, m.distance]));
    // One search per call from Node (which reads the threads' CPU time between calls).
    window.__searchBench = { key, last: {}, async run(way, which, k) {
      const params = { maxResults: k };
      const t = performance.now();
      const r = way === "workers" ? (which === "in" ? await client.search(q, params) : await viaWorkers(features.novel, params))
        : way === "one" ? index.searchFeatures(features[which], params) : index.searchPlainFeatures(features[which], params);
      const ms = performance.now() - t;
      this.last[way] = key(r);
      return { ms, matches: r.matches.length, best: r.matches[0]?.distance };
    } };
    return { tIndex, tWorkers, workers, clips: hour.length, frames };
  });
  const withPlain = !process.env.ODORI_BENCH_NO_PLAIN;
  const median = (v) => [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)];
  // The app opens playing its demo clip in a loop. With no GPU (this machine kind), Chromium
  // draws it in software (SwiftShader) on the same two cores, about 1.8 cores' worth at 60 fps,
  // so the search is timed twice: with the app's figure paused (the search alone) and playing
  // (what a person on a GPU-less machine gets while the dance plays). The plain DP runs once,
  // paused. Playing is timed twice: with the app's software cap (30 draws a second, what the
  // app does there) and with the cap lifted (the display's rate, as before the cap).
  const measure = async (playing, capped = true) => {
    await page.evaluate(([on, capped]) => {
      const box = document.querySelector("#draw-cap");
      if (!box.closest("label").hidden && box.checked !== capped) box.click();
      on ? window.odori.player.play() : window.odori.player.pause();
    }, [playing, capped]);
    const res = {};
    for (const which of ["in", "novel"]) {
      for (const k of [1, 10]) {
        const row = { workersMs: [], oneMs: [], workersCpu: [], workersCpuSum: [], oneCpu: [] };
        for (let r = 0; r < 3; r++) {
          let c0 = threadCpu();
          const w = await page.evaluate(([which, k]) => window.__searchBench.run("workers", which, k), [which, k]);
          let c1 = threadCpu();
          const dw = cpuDelta(c0, c1, "DedicatedWorker");
          row.workersMs.push(w.ms);
          row.workersCpu.push(Math.max(0, ...dw));
          row.workersCpuSum.push(dw.reduce((a, b) => a + b, 0));
          c0 = threadCpu();
          const o = await page.evaluate(([which, k]) => window.__searchBench.run("one", which, k), [which, k]);
          c1 = threadCpu();
          row.oneMs.push(o.ms);
          row.oneCpu.push(cpuDelta(c0, c1, "page").reduce((a, b) => a + b, 0));
          Object.assign(row, { matches: o.matches, best: o.best });
        }
        row.same = await page.evaluate(() => window.__searchBench.last.workers === window.__searchBench.last.one);
        if (withPlain && !playing && k === 10) {
          const c0 = threadCpu();
          const p = await page.evaluate(([which, k]) => window.__searchBench.run("plain", which, k), [which, k]);
          row.plainCpu = cpuDelta(c0, threadCpu(), "page").reduce((a, b) => a + b, 0);
          row.plainMs = p.ms;
          row.plainSame = await page.evaluate(() => window.__searchBench.last.plain === window.__searchBench.last.one);
        }
        for (const f of ["workersMs", "oneMs", "workersCpu", "workersCpuSum", "oneCpu"]) row[f] = median(row[f]);
        res[`${which} top${k}`] = row;
      }
    }
    return res;
  };
  out.res = { paused: await measure(false), "playing, cap lifted": await measure(true, false), "playing, capped": await measure(true, true) };
  console.log(`one hour of real motion: ${out.frames} frames in ${out.clips} clips (every real clip but indian_13, repeated); one-thread index built in ${out.tIndex.toFixed(0)} ms, ${out.workers} search workers (the app's SearchClient, one per core) loaded in ${out.tWorkers.toFixed(0)} ms`);
  for (const [mode, res] of Object.entries(out.res)) {
    const drawn = await page.evaluate(() => window.odori.viewer.adapterInfo.software ? "drawn in software" : "drawn by the GPU");
    console.log(mode === "paused" ? `the app's figure paused (the search alone, ${BACKEND}):` : `the app's figure ${mode} (${drawn} beside the search, ${BACKEND}):`);
    for (const [k, v] of Object.entries(res)) {
      let line = `wasm in Chromium, ${k}: ${out.workers} workers (the product's path) ${v.workersMs.toFixed(1)} ms wall, busiest worker's CPU ${v.workersCpu.toFixed(0)} ms (all workers ${v.workersCpuSum.toFixed(0)} ms); one thread ${v.oneMs.toFixed(1)} ms wall, CPU ${v.oneCpu.toFixed(0)} ms (medians of 3; CPU from /proc, 10 ms ticks); ${v.matches} matches, best ${v.best?.toFixed(4)}; workers' merged results = one thread's: ${v.same}`;
      if (v.plainMs !== undefined) line += `; plain DP ${v.plainMs.toFixed(0)} ms wall, CPU ${v.plainCpu.toFixed(0)} ms (same results: ${v.plainSame}), plain / workers = ${(v.plainMs / v.workersMs).toFixed(1)}x wall, plain CPU / busiest worker's CPU = ${(v.plainCpu / v.workersCpu).toFixed(1)}x, plain / one thread = ${(v.plainCpu / v.oneCpu).toFixed(1)}x CPU`;
      console.log(line);
    }
  }
  const lifted = out.res["playing, cap lifted"], capped = out.res["playing, capped"];
  console.log(`playing, capped / cap lifted (workers' wall): ${Object.keys(capped).map((k) => `${k} ${(capped[k].workersMs / lifted[k].workersMs).toFixed(2)}x`).join(", ")}`);
} finally {
  await browser.close();
  server.stop();
}
