// The video export's long main-thread tasks, traced and attributed (issue 29). Not a test: run
// by hand after `./dev build`,
//   node tests/browser/video-trace.mjs [--secs 4] [--backends webgl2,webgpu] [--over 50] [--save DIR]
// For each back end: the demo song's dance from its lead-in, `--secs` seconds at 1280×720, 30 fps,
// MP4 into a Blob (as the bench does), under a Chromium trace with V8's sampling CPU profiler. Every
// main-thread task of the export over `--over` ms is printed with its wall and CPU time, what ran
// it (timer, message, microtasks, GC), and the functions the profiler found on the stack in it:
// the innermost function of ours (export-video.js, mediabunny.js, the engine's glue odori.js) and
// the innermost function of all (a browser built-in, a WebGL call, garbage collection, "(program)"
// = the browser's own native work), each with its share of the task's samples. Then the same
// summed over all long tasks. `--paused` pauses the page's playback first and `--progress`
// moves a progress bar, as the app's dialog does; without them the page plays on, as it did in
// session 12. `--save DIR` keeps the raw trace (open it in DevTools' Performance panel).
import { mkdirSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { startServer, launch, openDemoDance } from "./harness.mjs";

const arg = (name, dflt) => { const i = process.argv.indexOf(`--${name}`); return i > 0 ? process.argv[i + 1] : dflt; };
const SECS = Number(arg("secs", "4"));
const BACKS = arg("backends", "webgl2").split(",");
const OVER_MS = Number(arg("over", "50"));
const SAVE = arg("save", null);
const PAUSED = process.argv.includes("--paused");
const PROGRESS = process.argv.includes("--progress");
const OURS = /\/(video\/export-video|video\/mediabunny|odori)\.js/;

/** The sampled stacks of the trace's CPU profile on thread (pid, tid): [{ ts, stack: [frames, leaf last] }]. */
function samplesOf(ev, pid, tid) {
  const nodes = new Map();
  const out = [];
  const chunks = ev.filter((e) => e.pid === pid && (e.name === "ProfileChunk" || e.name === "Profile")).sort((a, b) => a.ts - b.ts);
  // The profile's id whose chunks are on our thread (chunks may be on a sampler thread: match the Profile event's tid).
  const profileIds = new Set(ev.filter((e) => e.pid === pid && e.name === "Profile" && e.tid === tid).map((e) => e.id));
  let ts = 0;
  for (const c of chunks) {
    if (c.name === "Profile") { if (profileIds.has(c.id)) ts = c.args.data.startTime; continue; }
    if (!profileIds.has(c.id)) continue;
    const d = c.args.data.cpuProfile || {};
    for (const n of d.nodes || []) nodes.set(n.id, { parent: n.parent, frame: n.callFrame });
    const deltas = c.args.data.timeDeltas || [];
    (d.samples || []).forEach((id, i) => {
      ts += deltas[i] || 0;
      out.push({ ts, id });
    });
  }
  const stackOf = new Map();
  const stack = (id) => {
    if (stackOf.has(id)) return stackOf.get(id);
    const frames = [];
    for (let n = nodes.get(id); n; n = nodes.get(n.parent)) frames.unshift(n.frame);
    stackOf.set(id, frames);
    return frames;
  };
  return out.map((s) => ({ ts: s.ts, stack: stack(s.id) }));
}

const fname = (f) => `${f.functionName || "(anonymous)"}${f.url ? ` ${f.url.split("/").slice(-2).join("/")}:${f.lineNumber + 1}` : ""}`;

function attribute(samples) {
  const ours = new Map(), leaf = new Map();
  for (const s of samples) {
    const frames = s.stack.filter((f) => f.functionName !== "(root)");
    const l = frames[frames.length - 1];
    const o = [...frames].reverse().find((f) => OURS.test(f.url || ""));
    const ln = l ? fname(l) : "(idle)";
    const on = o ? fname(o) : "(none of ours)";
    leaf.set(ln, (leaf.get(ln) || 0) + 1);
    ours.set(on, (ours.get(on) || 0) + 1);
  }
  const top = (m, n) => [...m].sort((a, b) => b[1] - a[1]).slice(0, n).map(([k, v]) => `${k} ${((100 * v) / samples.length).toFixed(0)} %`);
  return { ours: top(ours, 4), leaf: top(leaf, 4), oursMap: ours, leafMap: leaf };
}

/** The trace events directly inside `task` (what ran it and what it ran): names with their ms. */
function inside(ev, main, task) {
  const end = task.ts + task.dur;
  const kinds = new Map();
  for (const e of ev) {
    if (e.pid !== main.pid || e.tid !== main.tid || e.ph !== "X" || e === task || e.ts < task.ts || e.ts >= end) continue;
    if (!/^(Commit|Paint|Layerize|PrePaint|FunctionCall|TimerFire|RunMicrotasks|EventDispatch|MinorGC|MajorGC|V8\.GC_.*|BlinkGC\..*|ThreadState::.*|v8\.callFunction|v8\.run|FireAnimationFrame|GPUTask|ParseHTML|EvaluateScript|v8\.compile|V8\.GCScavenger|V8\.GCFinalizeMC|V8\.GCIncrementalMarking|V8\.GCCompactor)$/.test(e.name)) continue;
    let n = e.name;
    if (e.name === "FunctionCall" && e.args?.data) n = `FunctionCall ${e.args.data.functionName || ""} ${(e.args.data.url || "").split("/").pop()}`.trim();
    kinds.set(n, (kinds.get(n) || 0) + (e.dur || 0) / 1000);
  }
  return [...kinds].sort((a, b) => b[1] - a[1]).slice(0, 5).map(([k, v]) => `${k} ${v.toFixed(0)} ms`);
}

const server = await startServer();
try {
  for (const backend of BACKS) {
    const { browser, page, logs } = await launch(backend);
    try {
      await openDemoDance(page, server, backend);
      await page.evaluate(() => import("/video/export-video.js"));
      await browser.startTracing(page, { categories: ["devtools.timeline", "disabled-by-default-devtools.timeline", "toplevel", "v8", "v8.execute", "blink.user_timing", "disabled-by-default-v8.cpu_profiler", "disabled-by-default-v8.gc"] });
      const r = await page.evaluate(async ({ secs, backend, paused, progress }) => {
        const { exportVideo, danceRange } = await import("/video/export-video.js");
        const { choreo, library, songPlayer, project, exporter } = window.odori;
        choreo.renderDance();
        const grid = project.project.grid();
        const { startSecs } = danceRange(grid.bars, 0, 0, grid.beatsPerBar);
        const endSecs = startSecs + secs;
        const bars = grid.bars.filter((b) => b.endSecs <= endSecs + 1e-3);
        await new Promise((r) => setTimeout(r, 50)); // the dance made above is not the export's work
        let longest = 0;
        const obs = new PerformanceObserver((l) => { for (const e of l.getEntries()) longest = Math.max(longest, e.duration); });
        obs.observe({ type: "longtask" });
        if (paused) window.odori.player.pause();
        const bar = document.body.appendChild(document.createElement("progress"));
        const onProgress = progress ? (p) => { bar.value = p.fraction; } : () => {};
        performance.mark("odori:video-start");
        const t0 = performance.now();
        const res = await exportVideo({ engine: exporter.video.engine, library, clip: choreo.danceId, startSecs, endSecs, bars, sections: project.project.sections(), character: "builtin", width: 1280, height: 720, fps: 30, container: "mp4", song: songPlayer.buffer, backend }, onProgress);
        const wall = (performance.now() - t0) / 1000;
        performance.mark("odori:video-end");
        await new Promise((r) => setTimeout(r, 100));
        obs.disconnect();
        return { wall, longest, frames: res.frames, path: res.path };
      }, { secs: SECS, backend, paused: PAUSED, progress: PROGRESS });
      const buf = await browser.stopTracing();
      if (SAVE) { mkdirSync(SAVE, { recursive: true }); writeFileSync(join(SAVE, `video-trace-${backend}.json`), buf); }
      const ev = JSON.parse(buf.toString()).traceEvents;
      const start = ev.find((e) => e.name === "odori:video-start");
      const end = ev.find((e) => e.name === "odori:video-end");
      if (!start || !end) throw new Error("the trace has no odori:video-start/-end marks");
      const main = { pid: start.pid, tid: start.tid };
      const samples = samplesOf(ev, main.pid, main.tid);
      const tasks = ev.filter((e) => e.pid === main.pid && e.tid === main.tid && e.name === "RunTask" && e.ph === "X" && e.ts + e.dur >= start.ts && e.ts <= end.ts);
      const long = tasks.filter((t) => t.dur > OVER_MS * 1000).sort((a, b) => a.ts - b.ts);
      const busy = tasks.reduce((s, t) => s + t.dur, 0) / 1000;
      console.log(`${backend}: ${r.frames} frames in ${r.wall.toFixed(1)} s (${r.path}); long-task observer: longest ${r.longest.toFixed(0)} ms; trace: ${tasks.length} main-thread tasks, ${busy.toFixed(0)} ms busy of ${((end.ts - start.ts) / 1000).toFixed(0)} ms, ${long.length} over ${OVER_MS} ms, ${samples.length} CPU samples`);
      const all = [];
      for (const t of long) {
        const s = samples.filter((x) => x.ts >= t.ts && x.ts < t.ts + t.dur);
        all.push(...s);
        const a = attribute(s);
        console.log(`  +${((t.ts - start.ts) / 1000).toFixed(0)} ms: ${(t.dur / 1000).toFixed(0)} ms wall, ${((t.tdur ?? 0) / 1000).toFixed(0)} ms CPU; ${inside(ev, main, t).join(", ") || "-"}`);
        console.log(`      ours: ${a.ours.join("; ") || "(no samples)"}`);
        console.log(`      leaf: ${a.leaf.join("; ") || "(no samples)"}`);
      }
      // The long tasks by what ran them (the scheduler's source: the page's frame update, a
      // timer, a message…), with how long each waited in paint and commit.
      const tops = ev.filter((e) => e.pid === main.pid && e.tid === main.tid && e.name === "ThreadControllerImpl::RunTask" && e.ph === "X");
      const paints = ev.filter((e) => e.pid === main.pid && e.tid === main.tid && (e.name === "Commit" || e.name === "Paint") && e.ph === "X");
      const groups = new Map();
      for (const t of long) {
        const src = tops.find((x) => x.ts >= t.ts && x.ts < t.ts + t.dur)?.args?.src_func || "?";
        const pc = paints.filter((x) => x.ts >= t.ts && x.ts < t.ts + t.dur).reduce((s, x) => s + x.dur, 0) / 1000;
        if (!groups.has(src)) groups.set(src, []);
        groups.get(src).push({ wall: t.dur / 1000, cpu: (t.tdur || 0) / 1000, pc });
      }
      const med = (xs) => xs.sort((a, b) => a - b)[xs.length >> 1];
      for (const [src, v] of groups) {
        console.log(`  ${v.length} long tasks run by ${src}: wall median ${med(v.map((x) => x.wall)).toFixed(0)} ms, longest ${Math.max(...v.map((x) => x.wall)).toFixed(0)} ms, ${v.filter((x) => x.wall > 200).length} over 200 ms; CPU at most ${Math.max(...v.map((x) => x.cpu)).toFixed(0)} ms; paint + commit median ${med(v.map((x) => x.pc)).toFixed(0)} ms`);
      }
      if (long.length) {
        const a = attribute(all);
        console.log(`  all ${long.length} long tasks (${(long.reduce((s, t) => s + t.dur, 0) / 1000).toFixed(0)} ms), by our innermost function: ${a.ours.join("; ")}`);
        console.log(`  by innermost function: ${a.leaf.join("; ")}`);
      }
      // Per-function totals over the whole export, to see what each frame costs.
      const exp = samples.filter((x) => x.ts >= start.ts && x.ts <= end.ts);
      const a = attribute(exp);
      console.log(`  whole export (${exp.length} samples) by our innermost function: ${a.ours.join("; ")}`);
      console.log(`  by innermost function: ${a.leaf.join("; ")}`);
    } catch (e) {
      console.log(logs.slice(-20).join("\n"));
      throw e;
    } finally {
      await browser.close().catch(() => {});
    }
  }
} finally {
  server.stop();
}
