// Benchmark: what drawing the app's playing demo costs on a machine with no GPU (this machine
// kind: Chromium draws in software, SwiftShader), before and after the drawing budget, on
// WebGL2 and on WebGPU, in one run. For each back end, the app opens (1280×800, as the other
// browser benches), its start-up work is left to finish, then in turn, each for 5 s and twice
// (A B C A B C, so drift in the machine's load falls on all three alike):
//  A. the demo playing with the cap lifted (the app's "drawn in software" box unticked): the
//     rate drawn before this change (the display's, 60 a second, for the 60-fps demo clip);
//  B. the demo playing, capped (what the app does now on a software adapter: 30 a second);
//  C. paused (the page idle: nothing drawn).
// Prints Chromium's CPU seconds per 5 s (all its processes: utime + stime from /proc, split into
// the GPU process, the renderer and the rest), the frames the viewer put on screen per second,
// and capped / lifted. The search's cost beside the drawing is in search-browser.mjs's
// "playing" lines (cap lifted and capped). Prints figures; not a test. Run after `./dev build`:
// node tests/bench/draw-budget.mjs  (ODORI_BENCH_BACKENDS=webgl2 for one back end;
// ODORI_BENCH_VIEWPORT=640x400 for another window size: software drawing's cost per frame
// grows with the canvas's pixels).
import { readFileSync } from "node:fs";
import { startServer, launch, openApp } from "../browser/harness.mjs";
import { descendants } from "./proc.mjs";

const SECS = 5;
const ROUNDS = 2;
const TICK_MS = 1000 / 100; // /proc's clock ticks (USER_HZ 100 on Linux)


/** CPU ms so far of Chromium's processes, by kind: { gpu, renderer, other }. */
function chromiumCpu() {
  const out = { gpu: 0, renderer: 0, other: 0 };
  for (const pid of descendants()) {
    try {
      const cmd = readFileSync(`/proc/${pid}/cmdline`, "utf8");
      if (!cmd.includes("chrom")) continue; // the test server is ours, not Chromium's
      const f = readFileSync(`/proc/${pid}/stat`, "utf8");
      const s = f.slice(f.lastIndexOf(")") + 2).split(" ");
      const ms = (Number(s[11]) + Number(s[12])) * TICK_MS;
      const kind = cmd.includes("--type=gpu-process") ? "gpu" : cmd.includes("--type=renderer") ? "renderer" : "other";
      out[kind] += ms;
    } catch { /* gone */ }
  }
  return out;
}

async function measure(page, mode) {
  await page.evaluate((mode) => {
    const { player } = window.odori;
    const box = document.querySelector("#draw-cap");
    if (mode !== "paused") {
      // The app's own setting, as a person would tick it.
      if (box.checked !== (mode === "capped")) box.click();
      player.play();
    } else {
      player.pause();
    }
  }, mode);
  await new Promise((r) => setTimeout(r, 1000));
  const c0 = chromiumCpu();
  const f0 = await page.evaluate(() => [window.odori.viewer.framesDrawn, performance.now()]);
  await new Promise((r) => setTimeout(r, SECS * 1000));
  const c1 = chromiumCpu();
  const f1 = await page.evaluate(() => [window.odori.viewer.framesDrawn, performance.now()]);
  const secs = (f1[1] - f0[1]) / 1000;
  // Per SECS seconds of wall time (the window may run a little long on a loaded machine).
  const per = (k) => ((c1[k] - c0[k]) / 1000) * (SECS / secs);
  return { gpu: per("gpu"), renderer: per("renderer"), other: per("other"), total: per("gpu") + per("renderer") + per("other"), fps: (f1[0] - f0[0]) / secs };
}

const mean = (v) => v.reduce((a, b) => a + b, 0) / v.length;

const backends = (process.env.ODORI_BENCH_BACKENDS || "webgl2,webgpu").split(",");
const server = await startServer();
try {
  for (const backend of backends) {
    const { browser, page } = await launch(backend);
    try {
      const [w, h] = (process.env.ODORI_BENCH_VIEWPORT || "1280x800").split("x").map(Number);
      await page.setViewportSize({ width: w, height: h });
      await openApp(page, server, backend);
      const canvas = await page.evaluate(() => { const c = document.querySelector("#view"); return `${c.width}×${c.height}`; });
      const info = await page.evaluate(() => window.odori.viewer.adapterInfo);
      // The start-up work after the first pose (the built-in moves, the demo song) is done.
      await page.waitForFunction(() => !document.querySelector("#status").textContent.trim(), null, { timeout: 120000 }).catch(() => {});
      await new Promise((r) => setTimeout(r, 3000));
      const runs = { lifted: [], capped: [], paused: [] };
      for (let r = 0; r < ROUNDS; r++) for (const mode of ["lifted", "capped", "paused"]) runs[mode].push(await measure(page, mode));
      const row = (mode) => {
        const v = runs[mode];
        const m = (k) => mean(v.map((x) => x[k]));
        return { total: m("total"), gpu: m("gpu"), renderer: m("renderer"), other: m("other"), fps: m("fps"), each: v.map((x) => x.total.toFixed(2)).join(", ") };
      };
      const [a, b, c] = [row("lifted"), row("capped"), row("paused")];
      const line = (label, x) => `  ${label.padEnd(36)} ${x.total.toFixed(2).padStart(5)} s CPU per ${SECS} s (GPU process ${x.gpu.toFixed(2)}, renderer ${x.renderer.toFixed(2)}, other ${x.other.toFixed(2)}; runs ${x.each}), ${x.fps.toFixed(1)} frames drawn/s`;
      console.log(`${backend}: adapter ${JSON.stringify(info)}; window ${w}×${h}, canvas ${canvas} px; Chromium's CPU, mean of ${ROUNDS} runs of ${SECS} s each:`);
      console.log(line("demo playing, cap lifted (before)", a));
      console.log(line("demo playing, capped (now)", b));
      console.log(line("paused", c));
      console.log(`  CPU per frame drawn: cap lifted ${((a.total - c.total) / (a.fps * SECS) * 1000).toFixed(1)} ms, capped ${((b.total - c.total) / (b.fps * SECS) * 1000).toFixed(1)} ms (beyond the paused page's)`);
      console.log(`  capped / lifted: ${(b.total / a.total).toFixed(2)}x CPU (GPU process ${(b.gpu / a.gpu).toFixed(2)}x), ${(b.fps / a.fps).toFixed(2)}x frames; CPU saved ${(a.total - b.total).toFixed(2)} s per ${SECS} s (${((a.total - b.total) / SECS).toFixed(2)} cores)`);
    } finally {
      await browser.close();
    }
  }
} finally {
  server.stop();
}
