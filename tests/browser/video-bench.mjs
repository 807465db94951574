// Benchmark of the video export (issue 29); prints figures, asserts nothing.
//   node tests/browser/video-bench.mjs [--secs 60] [--backends webgl2,webgpu] [--stream 60,180] [--before REV]
// For each back end: the demo song's dance, `--secs` seconds (from the lead-in) at 1280×720,
// 30 fps, MP4 into a Blob, as the app's dialog makes it (the page's playback paused, a progress
// bar moved): wall time ÷ video time, the longest main-thread task during the export (a
// PerformanceObserver of long tasks: tasks over 50 ms; the path the frames took is printed
// with it) and its cause (the long animation frame holding it, `long-animation-frame`: the
// scripts that ran in it, by invoker and function, and the rendering step after them), and
// peak memory (the page's JS heap from the DevTools protocol, and the proportional set size of
// every Chromium process, sampled every 250 ms). With `--stream a,b`: 1920×1080 videos of a and
// b seconds written through a stream into a file (the Origin Private File System), peak memory
// of each. With `--before REV` (e.g. 8ed782d, session 12's main): the same export with that
// revision's www/video/export-video.js (served in place of this one) and the page's playback
// left playing, as the app did then: the figures before the fix, with the same engine build.
import { mkdtempSync, readFileSync, readdirSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { execFileSync } from "node:child_process";
import { startServer, startChromium, root, openDemoDance } from "./harness.mjs";

const arg = (name, dflt) => { const i = process.argv.indexOf(`--${name}`); return i > 0 ? process.argv[i + 1] : dflt; };
const SECS = Number(arg("secs", "60"));
const BACKS = arg("backends", "webgl2,webgpu").split(",");
const STREAM = arg("stream", "").split(",").filter(Boolean).map(Number);
const BEFORE = arg("before", null);
const beforeSource = BEFORE ? execFileSync("git", ["show", `${BEFORE}:www/video/export-video.js`], { cwd: root }).toString() : null;

/** PSS (kB) of `pid` and every process below it. */
function treePssKb(pid) {
  let out = "";
  try { out = execFileSync("ps", ["-e", "-o", "pid=,ppid="]).toString(); } catch { return 0; }
  const kids = new Map();
  for (const line of out.trim().split("\n")) {
    const [p, pp] = line.trim().split(/\s+/).map(Number);
    if (!kids.has(pp)) kids.set(pp, []);
    kids.get(pp).push(p);
  }
  let total = 0;
  const stack = [pid];
  while (stack.length) {
    const p = stack.pop();
    try {
      const m = readFileSync(`/proc/${p}/smaps_rollup`, "utf8").match(/^Pss:\s+(\d+)/m);
      if (m) total += Number(m[1]);
    } catch { /* gone */ }
    stack.push(...(kids.get(p) || []));
  }
  return total;
}

async function run(backend, server, jobs) {
  const profile = mkdtempSync(join(tmpdir(), "odori-video-bench-"));
  const { proc, browser, page } = await startChromium(profile, backend);
  const cdp = await page.context().newCDPSession(page);
  await cdp.send("Performance.enable");
  if (beforeSource) await page.route("**/video/export-video.js", (route) => route.fulfill({ contentType: "text/javascript", body: beforeSource }));
  try {
    await openDemoDance(page, server, backend);
    for (const job of jobs) {
      let peakHeap = 0, peakPss = 0, sampling = true;
      const sampler = (async () => {
        while (sampling) {
          const m = await cdp.send("Performance.getMetrics").catch(() => null);
          const heap = m?.metrics.find((x) => x.name === "JSHeapUsedSize")?.value || 0;
          peakHeap = Math.max(peakHeap, heap);
          peakPss = Math.max(peakPss, treePssKb(proc.pid));
          await new Promise((r) => setTimeout(r, 250));
        }
      })();
      const basePss = treePssKb(proc.pid);
      const r = await page.evaluate(async ({ secs, w, h, stream, backend, before }) => {
        const { exportVideo, danceRange } = await import("/video/export-video.js");
        const { choreo, library, songPlayer, project, exporter, player } = window.odori;
        choreo.renderDance();
        const grid = project.project.grid();
        const { startSecs } = danceRange(grid.bars, 0, 0, grid.beatsPerBar);
        const endSecs = startSecs + secs;
        const bars = grid.bars.filter((b) => b.endSecs <= endSecs + 1e-3);
        // The dance made above is the bench's own work, not the export's: observe from the next task.
        await new Promise((r) => setTimeout(r, 50));
        const tasks = [], frames = [];
        const obs = new PerformanceObserver((l) => { for (const e of l.getEntries()) (e.entryType === "longtask" ? tasks : frames).push(e); });
        obs.observe({ type: "longtask" });
        obs.observe({ type: "long-animation-frame" });
        // When the page's frame updates ran (an animation-frame callback of ours runs in each).
        const rafs = [];
        let observing = true;
        const loop = () => { rafs.push(performance.now()); if (observing) requestAnimationFrame(loop); };
        requestAnimationFrame(loop);
        let target = null, fh = null;
        if (stream) {
          const opfs = await navigator.storage.getDirectory();
          fh = await opfs.getFileHandle(`bench-${secs}.mp4`, { create: true });
          target = await fh.createWritable();
        }
        // As the app's dialog does (www/video/video-panel.js): a progress bar and its words
        // moved as frames are encoded, and the page's playback paused (not before the fix).
        const bar = document.body.appendChild(document.createElement("progress"));
        const words = document.body.appendChild(document.createElement("span"));
        const onProgress = (p) => { bar.value = p.fraction; words.textContent = `${Math.floor(p.fraction * 100)} %`; };
        const playing = player.playing;
        if (!before) player.pause();
        const t0 = performance.now();
        const res = await exportVideo({ engine: exporter.video.engine, library, clip: choreo.danceId, startSecs, endSecs, bars, sections: project.project.sections(), character: "builtin", width: w, height: h, fps: 30, container: "mp4", song: songPlayer.buffer, stream: target, backend }, onProgress);
        const wall = (performance.now() - t0) / 1000;
        if (playing && !player.playing) player.play();
        await new Promise((r) => setTimeout(r, 100));
        obs.disconnect();
        observing = false;
        bar.remove();
        words.remove();
        const size = res.blob ? res.blob.size : (await fh.getFile()).size;
        // The longest task, and the cause: the long animation frame it lies in, its scripts and its rendering.
        const top = tasks.reduce((a, e) => (!a || e.duration > a.duration ? e : a), null);
        let cause = "";
        if (top) {
          const name = (x) => `${x.invoker}${x.sourceFunctionName ? ` → ${x.sourceFunctionName}` : ""}${x.sourceURL ? ` (${x.sourceURL.split("/").slice(-2).join("/")})` : ""} ${x.duration.toFixed(0)} ms`;
          // The page's frame update (its rendering step) starts at its frame's renderStart.
          const update = rafs.some((t) => t >= top.startTime && t <= top.startTime + top.duration);
          const f = update ? frames.find((x) => x.renderStart && Math.abs(x.renderStart - top.startTime) < 2) || { scripts: [], renderStart: top.startTime } : null;
          const scripts = f
            ? f.scripts.filter((x) => x.startTime >= f.renderStart - 1)
            : frames.flatMap((x) => x.scripts).filter((x) => x.startTime >= top.startTime - 1 && x.startTime < top.startTime + top.duration);
          const js = scripts.reduce((a, x) => a + x.duration, 0);
          cause = f
            ? `the page's frame update: animation-frame callbacks ${scripts.map(name).join(", ") || "(under 50 ms in all)"}, then style, layout, paint and commit ${(top.duration - js).toFixed(0)} ms`
            : scripts.length ? `scripts: ${scripts.sort((a, b) => b.duration - a.duration).slice(0, 3).map(name).join(", ")}; ${(top.duration - js).toFixed(0)} ms outside them`
              : "no script and no frame update in it (the browser's own work, e.g. garbage collection)";
        }
        const over200 = tasks.filter((e) => e.duration > 200).length;
        return { wall, longest: top ? top.duration : 0, cause, count: tasks.length, over200, frames: res.frames, codecs: `${res.codecs.videoName} + ${res.codecs.audioName}`, size, path: res.path || "main thread, canvas captured in the draw's task" };
      }, { ...job, before: !!BEFORE });
      sampling = false;
      await sampler;
      console.log(`${backend}${BEFORE ? ` (before: ${BEFORE}'s export, playback left playing)` : ""} ${job.w}×${job.h} ${job.secs} s${job.stream ? " (stream)" : " (Blob)"}: ${r.frames} frames in ${r.wall.toFixed(1)} s = ${(r.wall / job.secs).toFixed(2)} × real time; longest main-thread task ${r.longest ? `${r.longest.toFixed(0)} ms` : "< 50 ms"} (${r.count} tasks over 50 ms, ${r.over200} over 200 ms); peak JS heap ${(peakHeap / 2 ** 20).toFixed(0)} MiB; peak Chromium PSS ${(peakPss / 1024).toFixed(0)} MiB (${(basePss / 1024).toFixed(0)} MiB before); ${r.codecs}; ${(r.size / 2 ** 20).toFixed(1)} MiB; ${r.path}`);
      if (r.cause) console.log(`  the longest task: ${r.cause}`);
    }
  } finally {
    await browser.close().catch(() => {});
    try { process.kill(-proc.pid); } catch { /* gone */ }
    rmSync(profile, { recursive: true, force: true });
  }
}

const server = await startServer();
try {
  for (const backend of BACKS) {
    const jobs = [{ secs: SECS, w: 1280, h: 720, stream: false, backend }];
    for (const s of STREAM) jobs.push({ secs: s, w: 1920, h: 1080, stream: true, backend });
    await run(backend, server, jobs);
  }
} finally {
  server.stop();
}
