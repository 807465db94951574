// What a change of the dance costs the page's frames with a character chosen: Generate with
// Xbot chosen while the dance plays on it, in headless Chromium, with the viewer's whole-dance
// retargeting done between frames (`prepareBodies`, the app's way) and, as the control in the
// same run, inside the draw that first needs it (`viewer.deferRetarget = false`, how it was).
// Prints per back end and mode, over the Generates: the longest `viewer.draw` call (what one
// animation frame's callback spends drawing), the longest gap between animation frames, the
// long tasks (PerformanceObserver "longtask", > 50 ms) and the longest `prepareBodies` task.
// Figures, not a test: run by hand after `./dev build`,
//   node tests/browser/retarget-trace.mjs webgl2 webgpu [generates]
// (wall times: on a loaded machine a task is also the thread waiting).
import { join } from "node:path";
import { startServer, launch, openApp, waitUntil, data } from "./harness.mjs";

const backends = process.argv.slice(2).filter((a) => !/^\d+$/.test(a));
const generates = Number(process.argv.slice(2).find((a) => /^\d+$/.test(a)) ?? 3);
const server = await startServer();
const fmt = (v) => v.toFixed(1);
try {
  for (const backend of backends.length ? backends : ["webgl2", "webgpu"]) {
    const { browser, page } = await launch(backend);
    try {
      await openApp(page, server, backend);
      await page.waitForFunction(() => Number(document.querySelector("#dance").dataset.bars) > 8 && document.body.dataset.project === "ready", null, { timeout: 120000 });
      await page.waitForFunction(() => document.querySelector("#dance").dataset.joins === "ready", null, { timeout: 120000 });
      await page.click("#dance-generate");
      await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy, null, { timeout: 120000 });
      const n = await page.evaluate(() => window.odori.library.size);
      await page.setInputFiles("#file-input", join(data, "gltf/Xbot.glb"));
      await page.waitForFunction((n) => window.odori.library.size > n, n, { timeout: 60000 });
      const charId = await page.evaluate(() => {
        window.odori.exporter.refreshCharacters();
        return Number([...document.querySelectorAll("#character option")].find((o) => o.textContent === "Xbot.glb").value);
      });
      await page.selectOption("#character", String(charId));
      await page.click("#dance-play");
      await waitUntil(() => page.evaluate(() => window.odori.viewer.bodiesPending === 0 && window.odori.viewer.lastDrawn()[0]?.body === "character"), { what: "the dance on Xbot", timeoutMs: 60000 });
      // Probes: each draw call's time, the gaps between animation frames, long tasks, and each
      // `prepareBodies` call's time.
      await page.evaluate(() => {
        const { viewer } = window.odori;
        const probe = (window.__probe = { draws: [], gaps: [], long: [], prepares: [], on: false });
        const draw = viewer.draw.bind(viewer);
        viewer.draw = (...a) => { const t = performance.now(); try { return draw(...a); } finally { if (probe.on) probe.draws.push(performance.now() - t); } };
        const prepare = viewer.prepareBodies.bind(viewer);
        viewer.prepareBodies = (...a) => { const t = performance.now(); try { return prepare(...a); } finally { if (probe.on) probe.prepares.push(performance.now() - t); } };
        let last = null;
        const tick = (now) => { if (probe.on && last != null) probe.gaps.push(now - last); last = now; requestAnimationFrame(tick); };
        requestAnimationFrame(tick);
        new PerformanceObserver((list) => { if (probe.on) for (const e of list.getEntries()) probe.long.push(e.duration); }).observe({ type: "longtask" });
      });
      // The draws' own noise on this machine: 2 s of the dance playing on Xbot, no edit.
      await page.evaluate(() => Object.assign(window.__probe, { draws: [], gaps: [], long: [], prepares: [], on: true }));
      await page.waitForTimeout(2000);
      const idle = await page.evaluate(() => { const p = window.__probe; p.on = false; const s = p.draws.slice().sort((a, b) => a - b); return { n: s.length, median: s[s.length >> 1] ?? 0, max: s.at(-1) ?? 0, gap: Math.max(0, ...p.gaps), long: p.long.length }; });
      console.log(`${backend} no edit (2 s of play): ${idle.n} draws, median ${fmt(idle.median)} ms, longest ${fmt(idle.max)} ms; longest frame gap ${fmt(idle.gap)} ms; ${idle.long} long tasks`);
      for (const defer of [false, true]) {
        const rows = [];
        for (let g = 0; g < generates; g++) {
          await page.evaluate((defer) => { window.odori.viewer.deferRetarget = defer; Object.assign(window.__probe, { draws: [], gaps: [], long: [], prepares: [], on: true }); }, defer);
          await page.click("#dance-generate");
          await page.waitForFunction(() => !document.querySelector("#dance").dataset.busy, null, { timeout: 120000 });
          await waitUntil(() => page.evaluate(() => window.odori.viewer.bodiesPending === 0 && window.odori.viewer.lastDrawn()[0]?.body === "character"), { what: "the new dance on Xbot", timeoutMs: 60000 });
          await page.waitForTimeout(500);
          rows.push(await page.evaluate(() => {
            const p = window.__probe;
            p.on = false;
            const max = (a) => (a.length ? Math.max(...a) : 0);
            return { draw: max(p.draws), gap: max(p.gaps), long: p.long.map((d) => Math.round(d)), prepare: max(p.prepares), drawing: window.odori.viewer.lastDrawn()[0].body };
          }));
        }
        const worst = (k) => Math.max(...rows.map((r) => r[k]));
        const median = (k) => rows.map((r) => r[k]).sort((a, b) => a - b)[rows.length >> 1];
        const mode = defer ? "between frames (prepareBodies)" : "control: in the draw       ";
        console.log(`${backend} ${mode}: over ${rows.length} Generates with Xbot: longest draw ${fmt(worst("draw"))} ms (median over Generates ${fmt(median("draw"))}) [${rows.map((r) => fmt(r.draw)).join(", ")}], longest frame gap ${fmt(worst("gap"))} ms (median ${fmt(median("gap"))}), longest prepareBodies ${fmt(worst("prepare"))} ms, long tasks ${JSON.stringify(rows.map((r) => r.long))}`);
      }
    } finally {
      await browser.close();
    }
  }
} finally {
  server.stop();
}
