// Benchmark (issue #16, build item 3): ten hours of motion indexed in headless Chromium the way
// the app does it — the library split over two search workers (www/search-worker.js), the
// index stored in IndexedDB (www/project/index-store.js) — then the page reloaded and the index
// reopened from IndexedDB instead of built. Prints build time, bytes stored, the index's memory
// per hour, search time (top 10, 120-frame query: one from the library, one novel) before and
// after the reopen, and the reopen time. Not a test. Run after `./dev build`:
//   node tests/bench/search-index-10h.mjs            (ODORI_BENCH_HOURS=2 for a shorter run)
//
// The ten hours are made from every real BVH in ../shared/data (indian_13 left out: the novel
// query's source): copy r of each clip is the clip's canonical joint positions replayed at a
// speed of its own (0.8–1.25×, a different factor per copy, linear interpolation), mirrored
// (x → −x) on odd copies, with 2 mm of deterministic noise, so no two copies have the same
// features after normalisation. Each copy is one library clip, as imported files would be.
import { readFileSync, readdirSync } from "node:fs";
import { join } from "node:path";
import { startServer, launch, data } from "../browser/harness.mjs";

const HOURS = Number(process.env.ODORI_BENCH_HOURS || 10);
/** Runs per search: the median of 3 for a short library, one run for ten hours (each takes seconds). */
const REPS = HOURS <= 2 ? 3 : 1;
const ALL = readdirSync(join(data, "mocap"), { withFileTypes: true })
  .filter((d) => d.isDirectory())
  .flatMap((d) => readdirSync(join(data, "mocap", d.name)).filter((f) => f.endsWith(".bvh")).map((f) => `${d.name}/${f.slice(0, -4)}`))
  .sort();

// In-page helpers: two workers speaking the app's protocol, and the exact merge of their answers.
// (Installed through page.evaluate: the page's CSP refuses inline scripts.)
const PAGE_LIB = () => { window.bench = {
  spawn(n) {
    const ws = [];
    let token = 0;
    const pending = new Map();
    for (let k = 0; k < n; k++) {
      const w = new Worker("./search-worker.js", { type: "module" });
      w.onmessage = (ev) => { const m = ev.data; const p = pending.get(m.token); if (!p || m.type === "progress") return; pending.delete(m.token); m.type === "error" ? p.reject(new Error(m.message)) : p.resolve(m); };
      ws.push(w);
    }
    const request = (k, msg, transfer = []) => new Promise((resolve, reject) => { const t = ++token; pending.set(t, { resolve, reject }); ws[k].postMessage({ ...msg, token: t }, transfer); });
    return { ws, request, stop: () => ws.forEach((w) => w.terminate()) };
  },
  async search(pool, mergeOutcomes, order, features, params) {
    const outs = await Promise.all(pool.ws.map((_, k) => pool.request(k, { type: "search", features, params })));
    return mergeOutcomes(outs.map((m) => m.outcome), order, params.maxResults);
  },
}; };

const server = await startServer();
const { browser, page } = await launch("webgl2");
const line = (s) => console.log(`10-hour index bench: ${s}`);
try {
  await page.goto(server.url + "?backend=webgl2");
  await page.waitForFunction(() => document.body.dataset.ready === "1", null, { timeout: 120000 });
  await page.evaluate(PAGE_LIB);
  for (const f of ALL) {
    const b64 = readFileSync(join(data, "mocap", `${f}.bvh`)).toString("base64");
    await page.evaluate(([name, b64, salsa]) => {
      const bin = atob(b64);
      const bytes = new Uint8Array(bin.length);
      for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
      window.odori.library.importFile(name, bytes, salsa ? { fpsOverride: 60 } : {});
    }, [`${f.split("/")[1]}.bvh`, b64, f.includes("salsa")]);
  }
  const built = await page.evaluate(async ([hours, reps]) => {
    const { SearchIndex } = await import("./pkg/odori.js");
    const { mergeOutcomes } = await import("./search/client.js");
    const { IndexStore } = await import("./project/index-store.js");
    const { library } = window.odori;
    const clips = library.clips().filter((c) => c.format === "bvh" && c.humanoid.kind !== "notHumanoid");
    const held = clips.find((c) => c.name === "indian_13");
    const lib = clips.filter((c) => c !== held);
    // Canonical positions of the real clips (what the app's build starts from; FK).
    let t = performance.now();
    const feats = lib.map((c) => library.searchFeatures(c.id));
    const fkMs = performance.now() - t;
    const fkFrames = feats.reduce((a, f) => a + f.length / 63, 0);
    // Ten hours of distinct copies.
    const target = Math.round(hours * 3600 * 60);
    let seed = 12345;
    const rand = () => { seed = (seed * 1103515245 + 12345) >>> 0; return seed / 4294967296; };
    const copies = [];
    let frames = 0;
    for (let r = 0; frames < target; r++) {
      for (let c = 0; c < feats.length && frames < target; c++) {
        const src = feats[c], n = src.length / 63;
        const speed = 0.8 + 0.45 * ((r * 0.6180339887 + c * 0.137) % 1);
        const m = Math.max(2, Math.min(Math.floor((n - 1) / speed), target - frames));
        const out = new Float32Array(m * 63);
        const mirror = r % 2 === 1 ? -1 : 1;
        for (let i = 0; i < m; i++) {
          const x = i * speed, f0 = Math.min(n - 1, Math.floor(x)), f1 = Math.min(n - 1, f0 + 1), a = x - Math.floor(x);
          for (let j = 0; j < 63; j++) {
            let v = src[f0 * 63 + j] * (1 - a) + src[f1 * 63 + j] * a + (rand() - 0.5) * 0.004;
            if (j % 3 === 0) v *= mirror;
            out[i * 63 + j] = v;
          }
        }
        copies.push({ id: copies.length + 1, name: `${lib[c].name} copy ${r}`, positions: out });
        frames += m;
      }
    }
    // Build: the copies to two workers, balanced by frames (as the app's SearchClient).
    const pool = window.bench.spawn(2);
    const load = [0, 0];
    t = performance.now();
    await Promise.all(copies.map((c) => {
      const k = load[0] <= load[1] ? 0 : 1;
      load[k] += c.positions.length / 63;
      return pool.request(k, { type: "add", id: c.id, name: c.name, positions: c.positions }, [c.positions.buffer]);
    }));
    const buildMs = performance.now() - t;
    const order = copies.map((c) => c.id);
    // Queries: 2 s of a copy in the library, and 2 s of indian_13 (never indexed).
    const inQuery = (await pool.request(0, { type: "queryFeatures", query: { clipId: 1, startFrame: 600, endFrame: 720 } })).features;
    const side = new SearchIndex();
    side.addFromLibrary(library, held.id);
    const mid = Math.floor(side.totalFrames / 2);
    const novel = side.queryFeatures({ clipId: held.id, startFrame: mid, endFrame: mid + 120 });
    const memBefore = (await Promise.all([0, 1].map((k) => pool.request(k, { type: "memory" })))).reduce((a, m) => a + m.heapBytes, 0);
    const timeSearch = async (features) => {
      const ms = [];
      let best;
      for (let i = 0; i < reps; i++) { const t = performance.now(); const o = await window.bench.search(pool, mergeOutcomes, order, features, { maxResults: 10 }); ms.push(performance.now() - t); best = o.matches.map((m) => [m.clipId, m.startFrame, m.endFrame, m.distance]); }
      return { first: ms[0], median: ms.sort((a, b) => a - b)[reps >> 1], best };
    };
    const sIn = await timeSearch(inQuery);
    const sNovel = await timeSearch(novel);
    const memAfter = (await Promise.all([0, 1].map((k) => pool.request(k, { type: "memory" })))).reduce((a, m) => a + m.heapBytes, 0);
    // Store: each worker's part, under the library key of every clip's content key.
    t = performance.now();
    const parts = await Promise.all([0, 1].map((k) => pool.request(k, { type: "toBytes" })));
    const serialiseMs = performance.now() - t;
    const keysInOrder = new Map(parts.flatMap((p) => p.keys.map((key, i) => [p.ids[i], key])));
    const key = SearchIndex.libraryKey(order.map((id) => keysInOrder.get(id)));
    const store = await IndexStore.open();
    t = performance.now();
    const bytes = await store.put(key, parts.map((p) => ({ bytes: p.bytes, keys: p.keys, ids: p.ids, frames: p.frames })));
    const putMs = performance.now() - t;
    pool.stop();
    return { fkMs, fkFrames, clips: copies.length, frames, buildMs, memBefore, memAfter, sIn, sNovel, serialiseMs, putMs, bytes, key, order, inQuery: Array.from(inQuery), novel: Array.from(novel) };
  }, [HOURS, REPS]);
  const hours = built.frames / 60 / 3600;
  line(`${built.clips} clips, ${built.frames} frames = ${hours.toFixed(2)} h at 60 fps, made from ${ALL.length - 1} real clips (see the top of this file)`);
  line(`canonical positions (FK) of the real clips: ${built.fkMs.toFixed(0)} ms for ${built.fkFrames} frames → ${(built.fkMs / built.fkFrames * built.frames / 1000).toFixed(1)} s for ${hours.toFixed(1)} h (the part of a build from clips that the stored index also saves)`);
  line(`build (normalise, boxes, content keys) in 2 workers: ${(built.buildMs / 1000).toFixed(1)} s`);
  line(`memory: the index holds ${(built.memBefore / 1e6).toFixed(0)} MB = ${(built.memBefore / hours / 1e6).toFixed(1)} MB per hour of motion (${(built.memBefore / built.frames).toFixed(0)} bytes per frame: normalised features 252, the distance's lane layout 288, 16-frame bounding boxes 36, the coupled bound's 8-frame boxes 72); ${(built.memAfter / 1e6).toFixed(0)} MB after searching`);
  line(`stored: ${(built.bytes / 1e6).toFixed(0)} MB (${(built.bytes / hours / 1e6).toFixed(1)} MB per hour); serialise ${built.serialiseMs.toFixed(0)} ms, IndexedDB write ${(built.putMs / 1000).toFixed(1)} s`);
  line(`search top 10, 120-frame query, built index: in library ${built.sIn.median.toFixed(0)} ms, novel ${built.sNovel.median.toFixed(0)} ms (${REPS === 1 ? "one run" : "median of 3"}; first ${built.sIn.first.toFixed(0)} / ${built.sNovel.first.toFixed(0)} ms)`);

  // The next visit: a fresh page, the index read from IndexedDB.
  await page.reload();
  await page.waitForFunction(() => document.body.dataset.ready === "1", null, { timeout: 120000 });
  await page.evaluate(PAGE_LIB);
  const reopened = await page.evaluate(async ({ key, order, inQuery, novel, reps }) => {
    const { mergeOutcomes } = await import("./search/client.js");
    const { IndexStore } = await import("./project/index-store.js");
    const t0 = performance.now();
    const pool = window.bench.spawn(2);
    const store = await IndexStore.open();
    const rec = await store.get(key);
    const readMs = performance.now() - t0; // the record's Blob handles: the workers read the bytes
    await Promise.all(rec.parts.map((p, k) => pool.request(k, { type: "reserve", part: k, bytes: p.bytes })));
    await Promise.all(rec.parts.map((p, k) => pool.request(k, { type: "load", part: k, keys: p.keys, ids: p.ids })));
    rec.parts.forEach((p, k) => pool.ws[k].postMessage({ type: "drop", part: k }));
    const reopenMs = performance.now() - t0;
    const timeSearch = async (features) => {
      const ms = [];
      let best;
      for (let i = 0; i < reps; i++) { const t = performance.now(); const o = await window.bench.search(pool, mergeOutcomes, order, features, { maxResults: 10 }); ms.push(performance.now() - t); best = o.matches.map((m) => [m.clipId, m.startFrame, m.endFrame, m.distance]); }
      return { first: ms[0], median: ms.sort((a, b) => a - b)[reps >> 1], best };
    };
    const sIn = await timeSearch(new Float32Array(inQuery));
    const sNovel = await timeSearch(new Float32Array(novel));
    const mem = (await Promise.all([0, 1].map((k) => pool.request(k, { type: "memory" })))).reduce((a, m) => a + m.heapBytes, 0);
    pool.stop();
    return { readMs, reopenMs, sIn, sNovel, mem, bytes: rec.bytes };
  }, { ...built, reps: REPS });
  line(`reopen from IndexedDB: ${(reopened.reopenMs / 1000).toFixed(2)} s (the record ${(reopened.readMs / 1000).toFixed(2)} s; the rest: the workers read its parts, check and decode them) against a build of ${((built.buildMs + built.fkMs / built.fkFrames * built.frames) / 1000).toFixed(1)} s (FK + build): ${((built.buildMs + built.fkMs / built.fkFrames * built.frames) / reopened.reopenMs).toFixed(1)}x`);
  line(`search top 10 after the reopen: in library ${reopened.sIn.median.toFixed(0)} ms, novel ${reopened.sNovel.median.toFixed(0)} ms (the first search, ${reopened.sIn.first.toFixed(0)} ms, also builds the lane layout and the 8-frame boxes, which are not stored); memory ${(reopened.mem / 1e6).toFixed(0)} MB`);
  const same = JSON.stringify(reopened.sIn.best) === JSON.stringify(built.sIn.best) && JSON.stringify(reopened.sNovel.best) === JSON.stringify(built.sNovel.best);
  line(`results after the reopen equal the built index's: ${same ? "yes" : "NO"}`);
  if (!same) process.exitCode = 1;
} finally {
  await browser.close();
  server.stop();
}
